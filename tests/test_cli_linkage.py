"""The command-line interface on general linkages: .urdf (Extended URDF + closures),
.xml (MJCF) and pinned .toml files; every command, its JSON checked against the Python
API (:class:`pkm_pin.linkage.Linkage`), and its errors."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from helpers import one_error_line

from pkm_pin import load_mechanism
from pkm_pin.builders.loops import four_bar_home
from pkm_pin.cli import main
from pkm_pin.io import general_reading

MODELS = Path(__file__).resolve().parents[1] / "models"
FOUR_BAR = MODELS / "loops" / "four_bar.urdf"
FIVE_BAR_XML = MODELS / "loops" / "five_bar.xml"
ANKLE = MODELS / "loops" / "ankle.urdf"
PINNED = MODELS / "pinned" / "five_bar.toml"
DELTA_POINT = MODELS / "pinned" / "delta_point.toml"
FILES = [FOUR_BAR, FIVE_BAR_XML, ANKLE, PINNED]
#: Actuated values of the fk/ik round trips.
Q_ACTUATED = {FOUR_BAR: [0.3], FIVE_BAR_XML: [0.1, 0.2], ANKLE: [0.1, -0.05],
              PINNED: [2.0, 1.1]}


def _json(capsys, argv) -> dict:
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def _pose_args(pose: dict) -> list[str]:
    return [repr(float(x)) for x in (*pose["xyz"], *pose["rpy"])]


# ------------------------------------------------------------------------ analyze
@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_analyze_json_matches_the_python_api(path, capsys):
    """analyze --json gives the Linkage's DOF, idle DOF, redundant rows, motion type,
    class, indices, A, B and the whole tree's q in Pinocchio's joint order, exactly."""
    report = _json(capsys, ["analyze", str(path), "--json"])
    link = load_mechanism(path)
    assembly = link.assemble()
    an = link.analyze(assembly)
    assert report["q"] == assembly.q.tolist()
    assert len(report["q"]) == link.model.nq
    assert report["joint_names"] == list(link.model.tree.names[1:])
    assert (report["dof"], report["idle_dof"], report["redundant_constraints"]) == \
        (an.dof, an.idle_dof, an.redundant_constraints)
    assert report["motion_type"] == an.motion_type and report["singularity"] == an.singularity
    assert report["grubler"] == link.grubler
    assert report["output"] == link.output and report["actuated"] == list(link.actuated)
    for key, value in an.indices.items():
        if np.isfinite(value):
            assert report["indices"][key] == pytest.approx(value, rel=1e-12, abs=1e-15)
        else:
            assert report["indices"][key] is None
    assert np.allclose(report["A"], an.A) and np.allclose(report["B"], an.B)
    assert len(report["motion_basis"]) == an.output_dof
    for key in ("platform_twists", "constraint_basis", "constraint_singular", "crosscheck",
                "pose", "independent_actuators", "idle_motions", "closures"):
        assert key in report


def test_ankle_reports_two_idle_rod_spins(capsys):
    """The ankle's two S–S rods spin idly: 2 idle DOF, one sentence each, in the JSON
    and in the text."""
    report = _json(capsys, ["analyze", str(ANKLE), "--json"])
    assert report["dof"] == 4 and report["idle_dof"] == 2 and report["motion_type"] == "2R"
    assert [m.split()[:2] for m in report["idle_motions"]] == [["rod_1", "spins"],
                                                              ["rod_2", "spins"]]
    assert main(["analyze", str(ANKLE)]) == 0
    out = capsys.readouterr().out
    assert "idle DOF 2" in out
    assert "rod_1 spins about the line" in out and "rod_2 spins about the line" in out


def test_text_report_names_the_output_and_how_to_choose_another(capsys):
    """The text report says which frame is the output, as a body, and names --output
    and --point."""
    assert main(["analyze", str(FOUR_BAR)]) == 0
    out = capsys.readouterr().out
    line = next(s for s in out.splitlines() if s.startswith("output "))
    assert "rocker, as a body" in line and "--output FRAME" in line and "--point" in line
    assert "DOF                1" in out and "Grübler count      0" in out


def test_output_and_point_options_choose_what_is_analysed(capsys):
    """--output coupler --point analyses the coupler's origin as a point, like the API."""
    report = _json(capsys, ["analyze", str(FOUR_BAR), "--output", "coupler", "--point",
                            "--json"])
    link = load_mechanism(FOUR_BAR, output="coupler", point=True)
    an = link.analyze(link.assemble())
    assert report["output"] == "coupler" and report["output_is_point"] is True
    assert report["motion_type"] == an.motion_type == "1T"
    body = _json(capsys, ["analyze", str(PINNED), "--body", "--json"])
    assert body["output_is_point"] is False


def test_analyze_at_actuated_values(capsys):
    """--q assembles by forward kinematics first; the report is at those values."""
    report = _json(capsys, ["analyze", str(FIVE_BAR_XML), "--q", "0.1", "0.2", "--json"])
    link = load_mechanism(FIVE_BAR_XML)
    assembly = link.forward_kinematics([0.1, 0.2], guess=link.assemble())
    assert report["q_actuated"] == pytest.approx([0.1, 0.2], abs=1e-12)
    assert report["q"] == pytest.approx(assembly.q.tolist(), abs=1e-12)
    for index in ("type_I", "type_II"):
        assert report["indices"][index] == pytest.approx(
            link.analyze(assembly).indices[index], rel=1e-9)


def test_analyze_writes_markdown(tmp_path, capsys):
    """--markdown writes the linkage report (mobility, idle motions, singularity)."""
    md = tmp_path / "ankle.md"
    assert main(["analyze", str(ANKLE), "--markdown", str(md)]) == 0
    text = md.read_text()
    assert text.startswith("# ankle") and "idle degrees of freedom: 2" in text
    assert "rod_1 spins" in text and "## Singularity" in text


def test_platform_analyze_accepts_actuated_values(capsys):
    """--q also works for a platform mechanism: the report is at the home pose when the
    home actuated values are given."""
    home = _json(capsys, ["analyze", "rpr3", "--json"])
    q = _json(capsys, ["ik", "rpr3", "--json"])["q_actuated"]
    report = _json(capsys, ["analyze", "rpr3", "--json", "--q", *map(repr, q)])
    assert report["pose"]["xyz"] == pytest.approx(home["pose"]["xyz"], abs=1e-9)


# -------------------------------------------------------------------------- check
@pytest.mark.parametrize("path", [*FILES, DELTA_POINT], ids=lambda p: p.name)
def test_check_a_linkage_is_fine(path, capsys):
    """check loads, assembles and prints the mobility summary; exit status 0."""
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert out.count("ok    ") == 3 and "mobility: DOF" in out
    assert out.strip().endswith("fine")


def test_check_lists_the_idle_motions(capsys):
    """check of the ankle lists both idle rod spins."""
    assert main(["check", str(ANKLE)]) == 0
    out = capsys.readouterr().out
    assert "idle DOF 2" in out and out.count("info  idle motion") == 2


def test_check_names_the_loop_that_does_not_close(tmp_path, capsys):
    """A coupler too long for the four-bar: one error line naming the file, the loop and
    its residual; exit status 2."""
    urdf = FOUR_BAR.read_text().replace('<origin xyz="0.09 0 0"', '<origin xyz="0.5 0 0"')
    (tmp_path / "four_bar.urdf").write_text(urdf)
    shutil.copy(FOUR_BAR.with_suffix(".yaml"), tmp_path / "four_bar.yaml")
    assert main(["check", str(tmp_path / "four_bar.urdf")]) == 2
    captured = capsys.readouterr()
    assert captured.out.startswith("ok    loads")
    line = captured.err.strip()
    assert len(line.splitlines()) == 1 and line.startswith("pkm-pin: error:")
    assert str(tmp_path / "four_bar.urdf") in line and "coupler_tipCrocker_tip" in line
    assert "residual" in line


# --------------------------------------------------------------------- fk and ik
@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_fk_then_ik_round_trip(path, capsys):
    """fk gives every joint and the output pose, as the API; ik of that pose gives the
    actuated values back."""
    q = Q_ACTUATED[path]
    found = _json(capsys, ["fk", str(path), *map(str, q), "--json"])
    link = load_mechanism(path)
    assembly = link.forward_kinematics(q, guess=link.assemble())
    assert found["q"] == pytest.approx(assembly.q.tolist(), abs=1e-12)
    assert found["q_actuated"] == pytest.approx(q, abs=1e-12)
    assert found["pose"]["xyz"] == pytest.approx(assembly.output_pose.translation, abs=1e-12)
    assert set(found["joints"]) <= set(link.model.tree.names)
    back = _json(capsys, ["ik", str(path), "--pose", *_pose_args(found["pose"]), "--json"])
    assert back["q_actuated"] == pytest.approx(q, abs=1e-7)
    assert len(back["q"]) == link.model.nq
    assert back["pose"]["xyz"] == pytest.approx(found["pose"]["xyz"], abs=1e-9)


def test_fk_stays_on_the_branch_of_the_reference_assembly(capsys):
    """The four-bar's crank at 0.3 from home: the rocker stays on the reference assembly's
    mode (elbow up, its closed form), not on the other assembly mode."""
    found = _json(capsys, ["fk", str(FOUR_BAR), "0.3", "--json"])
    reference = _json(capsys, ["analyze", str(FOUR_BAR), "--json"])
    home = four_bar_home()
    assert reference["joints"]["rocker_joint"][0] == pytest.approx(0.0, abs=1e-12)
    assert found["joints"]["rocker_joint"][0] == pytest.approx(
        four_bar_home(crank_angle=home[0] + 0.3)[2] - home[2], abs=1e-9)


def test_fk_text_lists_every_joint(capsys):
    """fk's text names the output pose and one line per joint."""
    assert main(["fk", str(ANKLE), "0.1", "-0.05"]) == 0
    out = capsys.readouterr().out
    assert "output     foot:" in out
    for joint in ("ankle_X", "ankle_Y", "motor_1", "rod_1_ball", "motor_2", "rod_2_ball"):
        assert f"    {joint}" in out


def test_ik_defaults_to_the_reference_output_pose(capsys):
    """ik without --pose targets the output pose of the reference assembly."""
    link = load_mechanism(PINNED)
    report = _json(capsys, ["ik", str(PINNED), "--json"])
    assert report["q_actuated"] == pytest.approx(link.assemble().q_actuated, abs=1e-7)


def test_fk_all_gives_both_modes_and_wrong_counts_are_refused(capsys):
    """fk --all of a linkage (one path with the platforms'): the four-bar's two assembly
    modes at crank 0.3 (open and crossed: the coupler on either side of the line from
    the crank pin to the rocker pivot), the first the plain fk's, each closing the loop;
    a wrong number of values is one error line."""
    modes = _json(capsys, ["fk", str(FOUR_BAR), "0.3", "--all", "--json"])
    one = _json(capsys, ["fk", str(FOUR_BAR), "0.3", "--json"])
    assert len(modes) == 2 and modes[0]["q"] == pytest.approx(one["q"], abs=1e-9)
    assert all(m["q_actuated"] == [0.3] and m["residual"] < 1e-12 for m in modes)
    link = load_mechanism(FOUR_BAR).general
    for m in modes:  # the loop closes: the closure's residual at q is zero
        assert max(link.residuals_at(np.array(m["q"])).values()) < 1e-12
    assert abs(modes[0]["q"][2] - modes[1]["q"][2]) > 1.0  # two distinct rocker angles
    assert main(["fk", str(FOUR_BAR), "0.3", "--all"]) == 0
    assert capsys.readouterr().out.count("\nmode ") == 2
    assert main(["fk", str(FIVE_BAR_XML), "0.3"]) == 2
    assert "mot1, mot2" in one_error_line(capsys)


# ------------------------------------------------------------------------- errors
def test_missing_closures_file_is_one_line(tmp_path, capsys):
    """A URDF without its closures file: one line naming the file, exit status 2."""
    shutil.copy(FOUR_BAR, tmp_path / "four_bar.urdf")
    for command in (["analyze"], ["check"], ["fk"], ["view"]):
        argv = [*command, str(tmp_path / "four_bar.urdf")] + (["0.1"] if command == ["fk"]
                                                             else [])
        assert main(argv) == 2
        line = one_error_line(capsys)
        assert str(tmp_path / "four_bar.urdf") in line and "closures file" in line
    assert main(["analyze", str(FOUR_BAR), "--closures", str(tmp_path / "no.yaml")]) == 2
    assert "no.yaml" in one_error_line(capsys)


def test_unknown_output_frame_is_one_line(capsys):
    """--output naming no frame: one line naming the file, the entry and the frames."""
    assert main(["analyze", str(FOUR_BAR), "--output", "nope"]) == 2
    line = one_error_line(capsys)
    assert str(FOUR_BAR) in line and "output" in line and "'nope'" in line
    assert "'rocker'" in line
    assert main(["analyze", str(FIVE_BAR_XML), "--output", "nope", "--json"]) == 2
    assert "'nope'" in one_error_line(capsys)


def test_another_output_of_a_platform_mechanism(capsys):
    """--output / --point on a platform mechanism (shipped name or TOML file) read it
    through the general elimination of its legs-and-platform tree, assembled at its home:
    the Delta's platform origin as a point moves as the platform does (3T, same velocity
    map); a leg's link as the output; an unknown frame is one error line naming the
    frames."""
    toml = load_mechanism(MODELS / "mechanisms" / "delta.toml")
    report = _json(capsys, ["analyze", "delta", "--point", "--json"])
    assert report["output_is_point"] and report["motion_type"] == "3T"
    np.testing.assert_allclose(report["pose"]["xyz"], toml.home.translation, atol=1e-12)
    point = load_mechanism(MODELS / "mechanisms" / "delta.toml", point=True)
    np.testing.assert_allclose(point.home_assembly.q, toml.tree_configuration(), atol=1e-12)
    for k in range(3):
        rate = np.eye(3)[k]
        np.testing.assert_allclose(point.home_analysis.forward_velocity(rate),
                                   toml.home_analysis.forward_velocity(rate), atol=1e-9)
    link = _json(capsys, ["analyze", "rpr3", "--output", "A/A1_link", "--json"])
    assert link["output"] == "A/A1_link" and link["dof"] == 3
    assert main(["analyze", str(MODELS / "mechanisms" / "rpr3.toml"), "--output", "x"]) == 2
    line = one_error_line(capsys)
    assert "output" in line and "'x'" in line and "A/A1_link" in line
    assert main(["analyze", "rpr3", "--closures", "c.yaml"]) == 2
    assert "--closures" in one_error_line(capsys)


def test_point_and_body_are_exclusive(capsys):
    """--point and --body together are a usage error (status 2)."""
    assert main(["analyze", str(PINNED), "--point", "--body"]) == 2
    assert "not allowed with" in capsys.readouterr().err


# ---------------------------------------------------------------------------- map
def test_map_of_two_actuated_coordinates(tmp_path, capsys):
    """map over the two motors of the five-bar: npz on the grid (rows v, columns u),
    classes and indices equal to the API's at each assembled q, and two PNGs."""
    prefix = tmp_path / "m"
    assert main(["map", str(FIVE_BAR_XML), "--actuated", "mot1", "mot2", "--range", "-0.6",
                 "-0.2", "0.2", "0.6", "--n", "4", "--out", str(prefix)]) == 0
    out = capsys.readouterr().out
    assert "16 points (snake order)" in out
    data = np.load(tmp_path / "m.npz")
    assert data["converged"].shape == (4, 4) and data["q"].shape == (4, 4, 4)
    assert data["converged"].all()
    assert data["u"] == pytest.approx(np.linspace(-0.6, -0.2, 4))
    assert data["q_actuated"][2, 1] == pytest.approx([data["u"][1], data["v"][2]])
    link = load_mechanism(FIVE_BAR_XML)  # read per leg: a structure is detected in it
    assert link.backend == "legs"
    for j, i in [(0, 0), (1, 3), (3, 2)]:
        an, general = link.analyze(data["q"][j, i]), link.general.analyze(data["q"][j, i])
        assert link.model.actuated_values(data["q"][j, i]) == pytest.approx(
            [data["u"][i], data["v"][j]], abs=1e-9)
        assert data["forward"][j, i] == pytest.approx(general.indices["forward"], rel=1e-9)
        assert data["inverse"][j, i] == pytest.approx(general.indices["inverse"], rel=1e-9)
        for index in ("type_I", "type_II"):
            assert data[index][j, i] == pytest.approx(an.indices[index], rel=1e-9)
        assert data["condition"][j, i] == pytest.approx(an.indices["condition_A"], rel=1e-9)
        assert str(data["singularity"][j, i]) == an.singularity
    assert (tmp_path / "m_singularity.png").is_file() and (tmp_path / "m_indices.png").is_file()


def test_map_of_a_platform_mechanism_over_actuated_coordinates(tmp_path, capsys):
    """map --actuated on the Delta (TOML legs) maps over two of its motors, the third at
    home (it used to be ignored silently): at each assembled grid point the motors hold
    the grid values and the platform pose and type II index are the TOML's forward
    kinematics and analysis; --actuated with --axes is refused."""
    prefix = tmp_path / "d"
    assert main(["map", "delta", "--actuated", "1/R1", "2/R1", "--range", "-0.6", "-0.4",
                 "-0.6", "-0.4", "--n", "3", "--out", str(prefix)]) == 0
    assert "9 points (snake order)" in capsys.readouterr().out
    data = np.load(tmp_path / "d.npz")
    assert data["converged"].all()
    toml = load_mechanism(MODELS / "mechanisms" / "delta.toml")
    home = toml.home_assembly.q_actuated
    for j, i in [(0, 0), (2, 1), (1, 2)]:
        qa = np.array([data["u"][i], data["v"][j], home[2]])
        assert data["q_actuated"][j, i] == pytest.approx(qa, abs=1e-9)
        an = toml.analyze(toml.forward_kinematics(qa))
        assert data["q"][j, i][-7:-4] == pytest.approx(an.assembly.pose.translation, abs=1e-9)
        assert str(data["singularity"][j, i]) == an.singularity
        general = general_reading(toml).analyze(data["q"][j, i])
        assert data["forward"][j, i] == pytest.approx(general.indices["forward"], rel=1e-9)
        assert general.indices["type_II"] == pytest.approx(an.indices["type_II"], rel=1e-9)
    assert main(["map", "delta", "--actuated", "1/R1", "--axes", "x", "y"]) == 2
    assert "one or the other" in one_error_line(capsys)


def test_map_of_one_actuated_coordinate(tmp_path, capsys):
    """The four-bar has one actuator: a line of n points and the index plot."""
    prefix = tmp_path / "f"
    assert main(["map", str(FOUR_BAR), "--actuated", "crank_joint", "--n", "12", "--range",
                 "-1", "1", "--out", str(prefix)]) == 0
    data = np.load(tmp_path / "f.npz")
    assert data["converged"].shape == (12,) and data["converged"].all()
    assert data["q_actuated"][:, 0] == pytest.approx(np.linspace(-1, 1, 12))
    assert (tmp_path / "f_indices.png").is_file()


def test_map_options_of_a_linkage_are_checked(tmp_path, capsys):
    """Dependent pose coordinates (either reading), a wrong --actuated or a wrong number
    of bounds are one error line, before any grid point is solved."""
    out = str(tmp_path / "x")
    assert main(["map", str(FIVE_BAR_XML), "--plane", "xz", "--out", out,
                 "--backend", "general"]) == 2
    assert "x, z are not independent coordinates" in one_error_line(capsys)
    assert main(["map", str(FIVE_BAR_XML), "--plane", "xz", "--out", out]) == 2  # per leg
    assert "x, z are not independent coordinates" in one_error_line(capsys)
    assert main(["map", str(FIVE_BAR_XML), "--actuated", "nope", "--out", out]) == 2
    assert "mot1, mot2" in one_error_line(capsys)
    assert main(["map", str(FIVE_BAR_XML), "--range", "0", "1", "--out", out]) == 2
    assert "4 bounds" in one_error_line(capsys)


def test_map_one_motor_with_the_other_fixed(tmp_path, capsys):
    """--actuated mot2 --fixed mot1=0.2: a line over mot2 at mot1 = 0.2."""
    assert main(["map", str(FIVE_BAR_XML), "--actuated", "mot2", "--fixed", "mot1=0.2",
                 "--range", "-0.3", "0.3", "--n", "5", "--out", str(tmp_path / "l")]) == 0
    data = np.load(tmp_path / "l.npz")
    assert np.all(data["q_actuated"][:, 0] == 0.2)
    assert data["q_actuated"][:, 1] == pytest.approx(np.linspace(-0.3, 0.3, 5))


# --------------------------------------------------------------------------- view
@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_view_writes_the_page(path, tmp_path, capsys):
    """view --html writes the meshcat page of the linkage; idle motions are listed."""
    page = tmp_path / "v.html"
    assert main(["view", str(path), "--html", str(page)]) == 0
    out = capsys.readouterr().out
    assert str(page) in out and page.stat().st_size > 10_000
    assert ("idle       rod_1 spins" in out) == (path == ANKLE)


def test_help_lists_the_linkage_options(capsys):
    """Each command's help shows --output, --point, --body and --closures."""
    for command in ("analyze", "check", "fk", "ik", "map", "view"):
        assert main([command, "--help"]) == 0
        text = capsys.readouterr().out
        for option in ("--output", "--point", "--body", "--closures"):
            assert option in text


def test_mjcf_without_equality_is_a_tree_and_says_so(tmp_path, capsys):
    """An MJCF without <equality> loads as a tree and is analysed as a serial chain; the
    CLI says so (issue 16, bad input)."""
    from pkm_pin.cli import main

    path = tmp_path / "arm.xml"
    path.write_text(
        '<mujoco model="arm"><worldbody><body name="link1"><joint name="j1" type="hinge" '
        'axis="0 0 1"/><geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>'
        '<body name="link2" pos="0.3 0 0"><joint name="j2" type="hinge" axis="0 0 1"/>'
        '<geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.02"/></body></body>'
        '</worldbody><actuator><motor joint="j1"/><motor joint="j2"/></actuator></mujoco>')
    assert main(["analyze", str(path)]) == 0
    out = capsys.readouterr().out
    assert "no closure: a tree, analysed as a serial chain" in out
    assert "DOF                2" in out
    assert main(["check", str(path)]) == 0
    assert "0 closures (none: a tree, analysed as a serial chain)" in capsys.readouterr().out


def test_fk_takes_negative_values_in_scientific_notation(capsys):
    """``fk FILE 0.1 -7e-17``: argparse reads ``-7e-17`` as an option; the values are kept
    in order (found on kangaroo_like_2legs, whose reference holds such values)."""
    assert main(["fk", str(FIVE_BAR_XML), "0.1", "-7e-17", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["q_actuated"] == pytest.approx([0.1, -7e-17], abs=1e-9)


def test_workspace_of_one_submechanism(tmp_path, capsys):
    """pkm-pin workspace BIPED --sub 1: the left leg alone with its own output (the left
    foot, taken as a point): x, z over a 0.1 m square about its home, y held at the
    left foot's home y; the 3 x 3 grid all reachable (volume 0.1², every motor of the
    right leg locked), the same cells as the whole biped read with --output foot_left,
    whose text names the two sub-mechanisms."""
    path = MODELS.parent / "tests" / "data" / "gepetto" / "digit_like_2legs" / "robot.urdf"
    foot = load_mechanism(path, output="foot_left", point=True).home_assembly
    p = foot.output_pose.translation
    box = [f"{v:.17g}" for v in (p[0] - 0.05, p[0] + 0.05, p[2] - 0.05, p[2] + 0.05)]
    common = ["--point", "--coords", "x", "z", "--range", *box, "--n", "3",
              "--kind", "reachable", "--quiet"]
    assert main(["workspace", str(path), "--sub", "1", *common, "--json",
                 "--out", str(tmp_path / "one")]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["mechanism"].endswith("[1]") and data["method"] == "linkage output"
    assert data["fixed"]["y"] == pytest.approx(p[1], abs=1e-12) and p[1] > 0.05
    assert data["home"] == pytest.approx([p[0], p[2]], abs=1e-12)
    assert data["counts"]["reachable"] == 9
    assert data["volumes"]["reachable"]["value"] == pytest.approx(0.01, rel=1e-9)
    assert main(["workspace", str(path), "--output", "foot_left", *common,
                 "--out", str(tmp_path / "whole")]) == 0
    text = capsys.readouterr().out
    assert "2 independent sub-mechanisms" in text and "--sub K" in text
    assert "type I at every pose: the singularity-free workspace is empty for that" in text
    one, whole = (np.load(tmp_path / f"{n}.npz") for n in ("one", "whole"))
    assert np.array_equal(one["mask_reachable"], whole["mask_reachable"])
    assert np.allclose(one["points"], whole["points"], atol=1e-12)
    assert main(["workspace", str(path), "--sub", "2", *common,
                 "--out", str(tmp_path / "bad")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "numbered 0 to 1" in err[0]


def test_map_default_of_a_per_leg_machine_follows_its_motion(tmp_path, capsys):
    """map of a file read per leg with no coordinate given: the four-bar (1 DOF: no
    two pose coordinates) is mapped over its crank, with a note saying so; Gepetto's
    5bar_linkage_iso3d (moving in the xz plane) over x and z, its independent
    coordinates, not x and y (y is a function of x there)."""
    assert main(["map", str(FOUR_BAR), "--n", "3", "--out", str(tmp_path / "f")]) == 0
    out = capsys.readouterr().out
    assert "fewer than 2 independent pose coordinates: mapped over its actuated" in out
    assert "crank_joint in [" in out
    assert np.load(tmp_path / "f.npz")["q_actuated"].shape == (3, 1)
    iso3d = Path(__file__).parent / "data" / "gepetto" / "5bar_linkage_iso3d" / "robot.urdf"
    assert main(["map", str(iso3d), "--n", "2", "--out", str(tmp_path / "g")]) == 0
    assert "slice      x in [" in capsys.readouterr().out
    data = np.load(tmp_path / "g.npz")
    assert [str(a) for a in data["axes"]] == ["x", "z"]


def test_map_of_a_general_mechanism_over_its_output_coordinates(tmp_path, capsys):
    """map --axes x y of the five-bar read over its tree (a point output): the output's
    inverse kinematics at every grid point, walked from home; every point that assembles
    has its output at the grid values (1e-9), the classes and the forward/inverse
    indices are those of analyze at that point's configuration; the singularity and
    indices maps are written; --jobs and --actuated with --axes are refused."""
    path = MODELS / "loops" / "five_bar.urdf"
    out = tmp_path / "m"
    assert main(["map", str(path), "--axes", "x", "y", "--n", "9", "--quiet",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "slice      x in" in text and "assembled" in text
    assert (tmp_path / "m_singularity.png").exists() and (tmp_path / "m_indices.png").exists()
    data = np.load(tmp_path / "m.npz")
    ok = data["ok"]
    assert ok.shape == (9, 9) and 10 < ok.sum() < 81
    U, V = np.meshgrid(data["u"], data["v"])
    np.testing.assert_allclose(data["poses"][ok][:, 0], U[ok], atol=1e-9)
    np.testing.assert_allclose(data["poses"][ok][:, 1], V[ok], atol=1e-9)
    mech = load_mechanism(path)
    for idx in list(zip(*np.nonzero(ok)))[::7]:
        an = mech.analyze(data["q"][idx])
        assert data["singularity"][idx] == an.singularity
        for key in ("forward", "inverse"):
            assert data[key][idx] == pytest.approx(an.indices[key], rel=1e-9, abs=1e-12)
    assert main(["map", str(path), "--axes", "x", "y", "--jobs", "2",
                 "--out", str(out)]) == 2
    assert "follows one branch" in one_error_line(capsys)
    assert main(["map", str(path), "--axes", "x", "y", "--actuated", "mot1",
                 "--out", str(out)]) == 2
    assert "give one or the other" in one_error_line(capsys)
