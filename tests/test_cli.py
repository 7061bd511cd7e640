"""The command-line interface `pkm-pin`: every sub-command, its errors and its help."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pinocchio as pin
import pytest
from helpers import MECHANISM_DIR, one_error_line

from pkm_pin import load_mechanism
from pkm_pin.builders import DESCRIPTIONS
from pkm_pin.cli import main


def test_analyze_default_prints_the_3rpr_report(capsys):
    """With no file, analyze reports the 3-RPR of seed 000 (Michalková & Guldan, see
    docs/references.md): 3 DOF 2T1R and a tiny cross-check error."""
    assert main(["analyze"]) == 0
    out = capsys.readouterr().out
    assert "3-RPR" in out
    assert "DOF                3  (idle DOF 0; output motion 2T1R; singularity none)" in out
    assert "singularity        none" in out
    assert "cross-check" in out


def test_analyze_json_has_the_documented_keys(capsys):
    """--json prints one object with dof, motion_type, grubler, A, B, singularity, indices."""
    assert main(["analyze", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    for key in ("dof", "motion_type", "grubler", "A", "B", "singularity",
                "constraint_singular", "indices", "crosscheck_max_error"):
        assert key in report
    assert report["dof"] == 3 and report["motion_type"] == "2T1R" and report["grubler"] == -3
    assert len(report["A"]) == 3 and len(report["B"]) == 3
    assert report["crosscheck_max_error"] < 1e-9


def test_analyze_at_a_given_pose(capsys):
    """--pose moves the platform; the report shows that pose."""
    assert main(["analyze", "--json"]) == 0
    home = json.loads(capsys.readouterr().out)["pose"]
    x, y, z = home["xyz"]
    r, p, yaw = home["rpy"]
    assert main(["analyze", "--json", "--pose", str(x + 0.05), str(y), str(z), str(r),
                 str(p + 0.02), str(yaw)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["pose"]["xyz"][0] == pytest.approx(x + 0.05)
    assert report["dof"] == 3


def test_user_mistakes_give_one_line_and_status_2(tmp_path):
    """A missing file is one error line on stderr, exit status 2, no traceback."""
    proc = subprocess.run([sys.executable, "-m", "pkm_pin.cli", "analyze",
                           str(tmp_path / "missing.toml")], capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.startswith("pkm-pin: error:")
    assert "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


# ----------------------------------------------------------------------- helpers
RPR3_TOML = MECHANISM_DIR / "rpr3.toml"


# --------------------------------------------------------------------------- help
@pytest.mark.parametrize("command", ["list", "analyze", "check", "fk", "ik", "map", "view",
                                     "dynamics"])
def test_every_command_has_help(command, capsys):
    """'pkm-pin COMMAND --help' prints a usage and exits with 0."""
    assert main([command, "--help"]) == 0
    assert capsys.readouterr().out.startswith(f"usage: pkm-pin {command}")


def test_usage_errors_are_one_line(capsys):
    """A wrong number of --pose values is one error line naming --help, status 2."""
    assert main(["analyze", "--pose", "1", "2"]) == 2
    assert "--help" in one_error_line(capsys)


def test_no_command_is_a_usage_error(capsys):
    """pkm-pin without a command is one error line, status 2."""
    assert main([]) == 2
    one_error_line(capsys)


# --------------------------------------------------------------------------- list
def test_list_names_every_shipped_model_with_its_description(capsys):
    """list prints every builder name and every models/mechanisms file with a description."""
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name, description in DESCRIPTIONS.items():
        assert any(line.split()[0] == name and description in line for line in out.splitlines())
    for path in RPR3_TOML.parent.glob("*.toml"):
        assert path.stem in out


# ------------------------------------------------------------------------ analyze
def test_analyze_accepts_a_shipped_model_name(capsys):
    """'analyze stewart' builds the shipped Gough–Stewart: 6 DOF, 3T3R, words for the twists."""
    assert main(["analyze", "stewart", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["dof"] == 6 and report["motion_type"] == "3T3R"
    assert report["motion_basis"][0]["words"] == "pure translation along (1, 0, 0)"


def test_analyze_accepts_a_file_path(capsys):
    """A mechanism file path gives the same report as the shipped name."""
    assert main(["analyze", str(RPR3_TOML), "--json"]) == 0
    by_path = json.loads(capsys.readouterr().out)
    assert main(["analyze", "rpr3", "--json"]) == 0
    by_name = json.loads(capsys.readouterr().out)
    assert np.allclose(by_path["A"], by_name["A"])


def test_analyze_writes_markdown(tmp_path, capsys):
    """--markdown FILE writes the Markdown report and --plots links the images in it."""
    md = tmp_path / "r.md"
    assert main(["analyze", "--markdown", str(md), "--plots", "m_singularity.png"]) == 0
    text = md.read_text()
    assert text.startswith("# 3-RPR") and "## Cross-check" in text
    assert "![m_singularity](m_singularity.png)" in text
    assert str(md) in capsys.readouterr().out


def test_unknown_model_lists_the_shipped_ones(capsys):
    """An unknown name is one line that lists the shipped models."""
    assert main(["analyze", "no_such_model"]) == 2
    line = one_error_line(capsys)
    assert "stewart" in line and "pkm-pin list" in line


def test_nan_pose_is_refused(capsys):
    """--pose with NaN is one line saying the pose must be finite."""
    assert main(["analyze", "--pose", "nan", "0", "0", "0", "0", "0"]) == 2
    assert "finite" in one_error_line(capsys)


# -------------------------------------------------------------------------- check
def test_check_a_shipped_file_is_fine(capsys):
    """check on a shipped file reports load, assembly, analysis and exits with 0."""
    assert main(["check", str(RPR3_TOML)]) == 0
    out = capsys.readouterr().out
    assert out.count("ok    ") >= 3 and out.strip().endswith("fine")


def test_check_reports_a_broken_file_in_one_line(tmp_path, capsys):
    """A wrong key of a leg is one error line naming the file and the key, status 2."""
    text = RPR3_TOML.read_text().replace('tip = "tip"', 'tip = "no_such_link"', 1)
    text = text.replace('"../urdf/', f'"{RPR3_TOML.parent.parent}/urdf/')
    path = tmp_path / "broken.toml"
    path.write_text(text)
    assert main(["check", str(path)]) == 2
    line = one_error_line(capsys)
    assert str(path) in line and "tip" in line and "no_such_link" in line


def test_check_warns_about_missing_actuators(tmp_path, capsys):
    """A leg without actuator leaves 2 actuators for 3 DOF: a warning and status 1."""
    text = RPR3_TOML.read_text().replace('actuated = ["A1"]', "actuated = []")
    text = text.replace('name = "3-RPR (seed 000)"', 'name = "under-actuated RPR"')
    text = text.replace('"../urdf/', f'"{RPR3_TOML.parent.parent}/urdf/')
    path = tmp_path / "under.toml"
    path.write_text(text)
    assert main(["check", str(path)]) == 1
    out = capsys.readouterr().out
    assert "warn  2 actuated joints for 3 DOF" in out


# --------------------------------------------------------------------- fk and ik
def test_ik_then_fk_round_trip(capsys):
    """ik at a pose then fk of those coordinates gives the pose back."""
    pose = ["0.85", "0", "0.62", "0", "0.55", "0"]
    assert main(["ik", "rpr3", "--pose", *pose, "--json"]) == 0
    q = json.loads(capsys.readouterr().out)["q_actuated"]
    assert len(q) == 3
    assert main(["fk", "rpr3", *map(str, q), "--json"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert found["pose"]["xyz"] == pytest.approx([0.85, 0.0, 0.62], abs=1e-9)
    assert found["pose"]["rpy"] == pytest.approx([0.0, 0.55, 0.0], abs=1e-9)
    # the whole tree's configuration, as a general linkage's fk gives it: legs, then the
    # platform's free flyer (its position is the pose's)
    mech = load_mechanism(MECHANISM_DIR / "rpr3.toml")
    assert len(found["q"]) == mech.model.tree.nq
    assert found["q"][-7:-4] == pytest.approx([0.85, 0.0, 0.62], abs=1e-9)
    assert np.concatenate(list(found["leg_q"].values())).tolist() == found["q"][:-7]


def test_ik_all_lists_the_home_working_mode_first(capsys):
    """ik --all at home lists every working mode, the home one first."""
    assert main(["ik", "rrr3", "--all", "--json"]) == 0
    modes = json.loads(capsys.readouterr().out)["q_actuated"]
    assert main(["ik", "rrr3", "--json"]) == 0
    home = json.loads(capsys.readouterr().out)["q_actuated"]
    assert len(modes) >= 2 and modes[0] == pytest.approx(home)


def test_fk_all_prints_modes(capsys):
    """fk --all prints one line per assembly mode found, the continuation first."""
    assert main(["fk", "stewart", *["1.2"] * 6, "--all", "--starts", "2"]) == 0
    out = capsys.readouterr().out
    assert "mode 1     xyz [0, 0, 1.0276" in out


def test_fk_wrong_count_names_the_actuated_joints(capsys):
    """fk with too few coordinates is one line naming the actuated joints."""
    assert main(["fk", "rpr3", "0.7", "-1.5"]) == 2
    assert "A/A1, B/B0, C/C1" in one_error_line(capsys)


# ---------------------------------------------------------------------------- map
def test_map_writes_npz_and_pngs_with_a_progress_bar(tmp_path, capsys):
    """map writes PREFIX.npz with every sweep array on the grid and the two PNG maps."""
    prefix = tmp_path / "m"
    assert main(["map", "rpr3", "--plane", "xz", "--range", "0.6", "1.0", "0.4", "0.8",
                 "--n", "5", "--fixed", "pitch=0.55", "--out", str(prefix)]) == 0
    captured = capsys.readouterr()
    assert "sweep" in captured.err and "/25" in captured.err  # the progress bar
    data = np.load(tmp_path / "m.npz")
    for key in ("ok", "dof", "singularity", "type_I", "type_II", "condition", "det",
                "q_actuated", "poses", "u", "v", "labels"):
        assert key in data
    assert data["ok"].shape == (5, 5) and data["q_actuated"].shape == (5, 5, 3)
    assert data["ok"].all() and np.all(data["poses"][..., 4] == 0.55)
    assert data["u"] == pytest.approx(np.linspace(0.6, 1.0, 5))
    assert (tmp_path / "m_singularity.png").is_file()
    assert (tmp_path / "m_conditioning.png").is_file()


def test_map_refuses_a_fixed_varied_coordinate(capsys):
    """--fixed of a coordinate of the plane is one error line."""
    assert main(["map", "rpr3", "--plane", "xz", "--fixed", "x=1", "--quiet"]) == 2
    assert "varied" in one_error_line(capsys)


# --------------------------------------------------------------------------- view
def test_view_writes_a_self_contained_page(tmp_path, capsys):
    """view --html writes the meshcat page of the mechanism and opens no browser."""
    page = tmp_path / "v.html"
    assert main(["view", "rpr3", "--html", str(page)]) == 0
    assert page.stat().st_size > 10_000 and "MeshCat" in page.read_text()


def test_a_urdf_refused_by_urdfdom_is_still_one_line(tmp_path):
    """A leg URDF whose <limit> lacks velocity gives one stderr line (fails until
    pkm_pin/urdf.py build_model() silences urdfdom's C++ 'Error: ...' lines on fd 2)."""
    root = RPR3_TOML.parents[1]
    urdf = (root / "urdf" / "rpr_leg_a.urdf").read_text()
    (tmp_path / "a.urdf").write_text(urdf.replace('velocity="10.0" lower="0.2"', 'lower="0.2"'))
    text = RPR3_TOML.read_text().replace('"../urdf/rpr_leg_a.urdf"', f'"{tmp_path / "a.urdf"}"')
    (tmp_path / "m.toml").write_text(text.replace('"../urdf/', f'"{root / "urdf"}/'))
    proc = subprocess.run([sys.executable, "-m", "pkm_pin.cli", "check", str(tmp_path / "m.toml")],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.startswith("pkm-pin: error:")
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr


def test_first_analyze_on_a_fresh_installation_compiles_nothing_long(tmp_path):
    """README's first command with an empty numba cache: no compilation long enough to
    be announced (> 2 s): the single pose runs the engine's and the closure check's
    source as plain Python (issue 15, item 5). Not a timing test: it checks what runs."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    out = subprocess.run([sys.executable, "-m", "pkm_pin.cli", "analyze"], env=env,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "DOF                3" in out.stdout
    assert "compiling" not in out.stderr, out.stderr


# ----------------------------------------------------------------------- dynamics
CASSIE_LIKE = MECHANISM_DIR.parents[1] / "tests" / "data" / "gepetto" / "cassie_like" / \
    "robot.urdf"


def test_dynamics_on_a_file_with_inertias(tmp_path, capsys):
    """'pkm-pin dynamics' on Gepetto's Cassie-like leg (its own inertias): exit 0, the
    JSON numbers per actuator, PREFIX.npz with t, q, v, a, efforts of the right shapes,
    and the four PNGs."""
    prefix = tmp_path / "leg"
    assert main(["dynamics", str(CASSIE_LIKE), "--samples", "31", "--json",
                 "--out", str(prefix)]) == 0
    data = json.loads(capsys.readouterr().out)
    actuated = data["actuated"]
    assert len(actuated) == 5 and data["samples"] == 31 and data["duration"] == 2.0
    for name in actuated:
        s = data["actuators"][name]
        for key in ("peak_effort", "rms_effort", "peak_speed", "peak_power", "energy",
                    "net_energy"):
            assert np.isfinite(s[key])
        assert 0 < s["rms_effort"] <= s["peak_effort"]
        assert s["peak_speed"] == pytest.approx(0.1 * 2 * np.pi / 2.0)  # 0.1 rad sine, 2 s
    arrays = np.load(prefix.with_name("leg.npz"))
    assert arrays["t"].shape == (31,) and arrays["efforts"].shape == (31, 5)
    assert arrays["q"].shape[0] == arrays["v"].shape[0] == arrays["a"].shape[0] == 31
    assert list(arrays["actuated"]) == actuated
    for tag in ("efforts", "speeds", "powers", "torque_speed"):
        png = tmp_path / f"leg_{tag}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and str(png) in data["files"]


def test_dynamics_text_table_and_csv_trajectory(tmp_path, capsys):
    """A CSV motion (columns in another order) gives a text table with one row per
    actuator, the massless bodies named in one line; --duration with it is refused."""
    names = ["motor_hip1", "motor_hip2", "motor_tigh", "motor_knee", "motor_ankle"]
    t = np.linspace(0, 1, 11)
    rows = [",".join(["t"] + names[::-1])]
    rows += [",".join(f"{x:.9g}" for x in [ti] + [0.05 * np.sin(np.pi * ti)] * 5) for ti in t]
    csv = tmp_path / "motion.csv"
    csv.write_text("\n".join(rows) + "\n")
    assert main(["dynamics", str(CASSIE_LIKE), "--trajectory", str(csv), "--samples",
                 "21"]) == 0
    out = capsys.readouterr().out
    assert "cubic spline (clamped) through 11 samples" in out
    assert "massless   8 bodies have no mass in the file" in out
    for name in names:
        assert sum(line.startswith(name + " ") for line in out.splitlines()) == 1
    assert main(["dynamics", str(CASSIE_LIKE), "--trajectory", str(csv), "--duration",
                 "3"]) == 2
    assert "--duration" in one_error_line(capsys)


def test_dynamics_csv_of_output_coordinates(tmp_path, capsys):
    """A CSV of the foot's x and z over time (the Cassie-like leg's output moves in 5
    dimensions: y, roll, pitch held at home): exit 0, the motion described as the
    output's; the hip motors, which only the held coordinates move, stay still (peak
    speed at round-off) and the npz's q follows the CSV's z at its knots."""
    t = np.linspace(0, 1, 11)
    z = -0.09961938 + 0.01 * np.sin(np.pi * t)
    x = -0.2479085 + 0.005 * np.sin(np.pi * t)
    csv = tmp_path / "foot.csv"
    csv.write_text("t,z,x\n" + "\n".join(f"{a:.9g},{b:.9g},{c:.9g}" for a, b, c in
                                          zip(t, z, x)) + "\n")
    prefix = tmp_path / "foot"
    assert main(["dynamics", str(CASSIE_LIKE), "--trajectory", str(csv), "--samples", "11",
                 "--json", "--out", str(prefix)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["motion"].startswith("output x, z: cubic spline (clamped) through 11")
    assert data["actuators"]["motor_hip1"]["peak_speed"] < 1e-9
    assert data["actuators"]["motor_knee"]["peak_speed"] > 0.05
    arrays = np.load(prefix.with_name("foot.npz"))
    from pkm_pin import load_mechanism
    from pkm_pin.solve import pose_coordinates

    link = load_mechanism(CASSIE_LIKE)
    tree = link.model.tree
    data_ = tree.createData()
    for q, zk in zip(arrays["q"], z):
        pin.framesForwardKinematics(tree, data_, q)
        assert abs(pose_coordinates(data_.oMf[tree.getFrameId(link.model.output)])[2] - zk) \
            < 1e-10


def test_dynamics_refuses_a_file_without_masses(capsys):
    """A file with no mass on any body (models/loops/four_bar.urdf, the built-in 3-RPR):
    exit 2, one line naming the bodies; with a payload it runs and says the efforts are
    the payload's."""
    four_bar = MECHANISM_DIR.parent / "loops" / "four_bar.urdf"
    assert main(["dynamics", str(four_bar)]) == 2
    line = one_error_line(capsys)
    assert "no mass on any body (crank, coupler, rocker)" in line
    assert main(["dynamics", str(four_bar), "--payload", "0", "0", "0", "0", "0", "2",
                 "--samples", "5"]) == 0
    assert "note       no body of" in capsys.readouterr().out
    assert main(["dynamics"]) == 2  # the built-in 3-RPR has no inertias either
    assert "3-RPR (seed 000) has no mass on any body (A/A0_link" in one_error_line(capsys)


def test_scientific_negative_values_in_every_numeric_option(capsys):
    """Values such as -7e-17 (as --json prints them) are numbers, not options, in every
    option taking numbers (argparse's own rule reads only -12 and -1.5 as numbers);
    analyze --q with them gives the same assembly as with the plain spelling."""
    from pathlib import Path

    from pkm_pin.cli import build_parser

    parser = build_parser()
    cases = [(["fk", "m", "-7e-17", "-1E+0"], "q", [-7e-17, -1.0]),
             (["analyze", "m", "--q", "-7e-17", "-.5"], "q", [-7e-17, -0.5]),
             (["ik", "m", "--pose", "-1e-3", "0", "-2.5E-2", "-0.", "1e1", "-3e-1"], "pose",
              [-1e-3, 0.0, -2.5e-2, 0.0, 10.0, -0.3]),
             (["map", "m", "--range", "-1e-3", "2e-3", "-5E-1", "-.5e1"], "range",
              [-1e-3, 2e-3, -0.5, -5.0]),
             (["workspace", "m", "--coords", "x", "--range", "-2e-2", "-1e-2"], "range",
              [-2e-2, -1e-2]),
             (["dynamics", "m", "--payload", "0", "0", "-9.81e1", "-1e-3", "0", "0"],
              "payload", [0.0, 0.0, -98.1, -1e-3, 0.0, 0.0])]
    for argv, name, values in cases:
        assert getattr(parser.parse_args(argv), name) == values, argv
    path = str(Path(__file__).resolve().parents[1] / "models" / "loops" / "five_bar.urdf")
    outs = []
    for q in (["-7e-17", "-1E-3"], ["0", "-0.001"]):
        assert main(["analyze", path, "--q", *q, "--json"]) == 0
        outs.append(json.loads(capsys.readouterr().out))
    assert outs[0]["q_actuated"] == pytest.approx([0.0, -1e-3], abs=1e-12)
    assert np.allclose(outs[0]["q"], outs[1]["q"], atol=1e-12)
    assert main(["analyze", path, "--q", "-7e-17", "-x1"]) == 2  # still an error
