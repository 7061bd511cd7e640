"""Independent sub-mechanisms (pkm_pin.submechanisms, issue 25): a two-legged robot read
leg by leg. The whole model keeps its single-output reading (type I through the other
leg: tests/test_corpus.py, TWO_LEGS); each leg, analysed with the other held, is a
regular 6-DOF mechanism whose six motors move its own foot."""

from __future__ import annotations

import json
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

import pkm_pin
from pkm_pin import screws
from pkm_pin.cli import main
from pkm_pin.submechanisms import groups

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "gepetto"
FOUR_BAR = ROOT / "models" / "loops" / "four_bar.urdf"

#: Each leg: its actuated joints' suffix and the foot the file hangs on it (battobot's
#: file names the body on the left leg's ankle "foot_right").
LEGS = {
    "digit_like_2legs": (("foot", ("motor_hip_x", "motor_shin2")),
                         ("foot_left", ("motor_hip_x_left", "motor_shin2_left"))),
    "battobot_6d": (("foot_right", ("hipz_left", "motor_knee_left")),
                    ("foot_left", ("hipz_right", "motor_knee_right"))),
}


@lru_cache(maxsize=None)
def _legs(name: str):
    link = pkm_pin.load_mechanism(DATA / name / "robot.urdf")
    a = link.home_assembly
    return link, a, link.submechanisms(a.q)


@pytest.mark.parametrize("name", sorted(LEGS))
def test_each_leg_is_a_regular_six_dof_mechanism_with_its_own_foot(name):
    """Two groups; each has six actuators (its first and last as listed), the foot on its
    own joints as output, DOF 6 with no idle motion, six independent actuators, 3T3R and
    no singularity at home; the whole's 12 DOF are the legs' 6 + 6."""
    link, a, subs = _legs(name)
    assert len(groups(link.model)) == len(subs) == 2
    whole = link.mobility(a.q)
    dofs = []
    for sub, (foot, (first, last)) in zip(subs, LEGS[name]):
        assert len(sub.actuated) == 6 and sub.actuated[0] == first and sub.actuated[-1] == last
        assert sub.output == foot
        tree = sub.model.tree
        assert tree.names[tree.frames[tree.getFrameId(foot)].parentJoint] != "universe"
        an = sub.analyze(sub.home_assembly)
        mob = an.mobility
        assert (an.dof, an.idle_dof, len(mob.independent_actuators)) == (6, 0, 6)
        assert sub.grubler == 6 and an.redundant_constraints == 0
        assert an.motion_type == "3T3R" and an.singularity == "none"
        assert an.indices["inverse"] > 0.03 and an.indices["forward"] > 0.3
        dofs.append(an.dof)
    assert sum(dofs) == whole.dof == 12


@pytest.mark.parametrize("name", sorted(LEGS))
def test_a_leg_reproduces_the_whole_trees_poses_and_motion(name):
    """At the assembled q, each leg's tree holds the whole tree's frames in the same
    order and puts every one (its own and the other leg's, held as frames of the
    universe) where the whole tree does (1e-12); its reference is closed (residual below
    1e-9) and is its home assembly."""
    link, a, subs = _legs(name)
    whole = link.model
    kin = whole.kinematics(a.q)
    for sub in subs:
        m = sub.model
        skin = m.kinematics(m.reference)
        assert [f.name for f in m.tree.frames] == [f.name for f in whole.tree.frames]
        for k, f in enumerate(m.tree.frames):  # the same frames in the same order
            assert np.allclose(skin.frame_placements[k].homogeneous,
                               kin.frame_placements[k].homogeneous, atol=1e-12), f.name
        assert sub.home_assembly.residual < 1e-9
        assert np.abs(m.closure_residual(m.reference)).max() < 1e-9


def test_a_leg_moves_its_foot_as_in_the_whole_model():
    """Forward kinematics of one leg (its hip pitch motor +0.02 rad) gives the foot pose
    the whole model gives with the same motor moved and the other leg's motors kept
    (1e-8 m), and the other leg's foot does not move in the whole."""
    link, a, subs = _legs("digit_like_2legs")
    right = subs[0]
    qa = right.home_assembly.q_actuated.copy()
    qa[2] += 0.02
    leg = right.forward_kinematics(qa)
    qa_whole = a.q_actuated.copy()
    qa_whole[2] += 0.02
    moved = link.forward_kinematics(qa_whole)
    foot = link.model.tree.getFrameId("foot")
    left = link.model.tree.getFrameId("foot_left")
    kin, kin0 = link.model.kinematics(moved.q), link.model.kinematics(a.q)
    assert np.allclose(leg.output_pose.homogeneous, kin.frame_placements[foot].homogeneous,
                       atol=1e-8)
    assert np.allclose(kin.frame_placements[left].homogeneous,
                       kin0.frame_placements[left].homogeneous, atol=1e-10)
    assert np.linalg.norm(leg.output_pose.translation
                          - kin0.frame_placements[foot].translation) > 1e-3


@pytest.mark.parametrize("name,dof,idle", [
    ("digit_like_2legs_6D", 6, 0), ("digit_like_2legs_old", 6, 0),
    ("old/digit_like_2legs", 9, 3)])
def test_the_other_two_legged_files_split_into_regular_legs(name, dof, idle):
    """The other bipeds of the corpus (docs/closed_loops.md's table): two legs of six
    motors, each foot regular at home (old/digit_like_2legs: three spinning rods a leg,
    9 − 3); the legs' DOF add up to the whole's."""
    link = pkm_pin.load_mechanism(DATA / name / "robot.urdf")
    a = link.home_assembly
    subs = link.submechanisms(a.q)
    got = []
    for sub in subs:
        an = sub.analyze(sub.home_assembly)
        got.append((len(sub.actuated), sub.output, an.dof, an.idle_dof, an.singularity))
    assert got == [(6, "foot", dof, idle, "none"), (6, "foot_left", dof, idle, "none")]
    assert 2 * dof == link.mobility(a.q).dof


def test_kangaroo_like_2legs_splits_into_two_legs_like_kangaroo_like():
    """kangaroo_like_2legs (its 26 revolutes named '*spherical*' read as spherical
    joints, generateYAML's convention): each leg has its six linear actuators (the left
    leg's first in the file), its own foot, 20 DOF of which 14 idle spins (rods and
    piston halves with a ball joint at each end), isostatic (Grübler 20), 3T3R, regular;
    the same numbers as the one-leg export kangaroo_like with its corrected closures file
    (tests/test_corpus.py); 20 + 20 = the whole's 40. Its forward index is small (the
    pistons' short strokes move the foot far), not zero."""
    link, a, subs = _legs("kangaroo_like_2legs")
    got = []
    for sub in subs:
        an = sub.analyze(sub.home_assembly)
        got.append((sub.output, sub.actuated[0], an.dof, an.idle_dof,
                    len(an.mobility.independent_actuators), sub.grubler,
                    an.redundant_constraints, an.motion_type, an.singularity))
        assert 5e-3 < an.indices["forward"] < 2e-2 and an.indices["inverse"] > 0.9
    assert got == [("foot", "motor_hip_xy_1_left", 20, 14, 6, 20, 0, "3T3R", "none"),
                   ("foot_2", "motor_hipz", 20, 14, 6, 20, 0, "3T3R", "none")]
    assert link.mobility(a.q).dof == 40


def test_a_single_loop_is_its_own_only_submechanism():
    """The four-bar: one group (its loop and its motor), submechanisms() is [link]."""
    link = pkm_pin.load_mechanism(FOUR_BAR)
    assert len(groups(link.model)) == 1
    assert link.submechanisms() == [link]


def _strict(text: str) -> dict:
    def refuse(c):
        raise ValueError(f"non-strict JSON constant {c}")
    return json.loads(text, parse_constant=refuse)


def test_analyze_json_reports_each_leg_and_stays_strict(capsys):
    """analyze --json: the whole-model keys as before (dof 12, type I through the other
    leg), and ``submechanisms`` with both legs; the four-bar's key is an empty list."""
    assert main(["analyze", str(DATA / "digit_like_2legs/robot.urdf"), "--json"]) == 0
    data = _strict(capsys.readouterr().out)
    assert (data["dof"], data["output"], data["singularity"]) == (12, "foot", "I")
    assert data["failed_sections"] == {}
    subs = data["submechanisms"]
    assert [(s["output"], s["dof"], s["idle_dof"], len(s["actuated"]), s["singularity"],
             s["motion_type"], s["joints"]) for s in subs] == [
        ("foot", 6, 0, 6, "none", "3T3R", 18), ("foot_left", 6, 0, 6, "none", "3T3R", 18)]
    _, _, legs = _legs("digit_like_2legs")
    an = legs[1].analyze(legs[1].home_assembly)
    assert subs[1]["indices"]["inverse"] == pytest.approx(an.indices["inverse"], rel=1e-6)
    assert main(["analyze", str(FOUR_BAR), "--json"]) == 0
    assert _strict(capsys.readouterr().out)["submechanisms"] == []


def test_analyze_text_has_a_block_per_leg_after_the_summary(capsys):
    """The text report: after the DOF line, one block per leg naming its actuators, its
    foot, DOF 6 and class none; no such block for the four-bar."""
    assert main(["analyze", str(DATA / "battobot_6d/robot.urdf")]) == 0
    lines = capsys.readouterr().out.splitlines()
    start = next(i for i, x in enumerate(lines) if x.startswith("sub-mechanisms "))
    dof = next(i for i, x in enumerate(lines) if x.startswith("DOF "))
    assert dof < start and "2 independent" in lines[start]
    block = lines[start + 1:start + 5]
    assert "6 actuators (hipz_left," in block[0] and block[0].endswith("output foot_right")
    assert block[1].strip().startswith("DOF 6 (idle DOF 0; output motion 3T3R; "
                                       "singularity none)")
    assert block[2].endswith("output foot_left")
    assert main(["analyze", str(FOUR_BAR)]) == 0
    assert "sub-mechanisms" not in capsys.readouterr().out


def test_pinocchios_reduced_cassie_splits_into_its_two_legs():
    """closed_chain.xml (no <actuator>, the free pelvis held as the base): two legs of
    13 coordinates and two point loops (rank 5) each, 8 DOF all idle, as the whole's 16
    split in two; with no motor each reads class II, like the whole."""
    link = pkm_pin.load_mechanism(ROOT / "tests" / "data" / "pinocchio" / "closed_chain.xml")
    a = link.home_assembly
    got = []
    for sub in link.submechanisms(a.q):
        an = sub.analyze(sub.home_assembly)
        got.append((sub.model.nv, sub.actuated, sub.output, an.dof, an.idle_dof,
                    an.singularity))
    assert got == [(13, (), "left-foot", 8, 8, "II"), (13, (), "right-foot", 8, 8, "II")]
    assert link.mobility(a.q).dof == 16


# ------------------------------------------------------- fk, check, view per leg
DIGIT2 = str(DATA / "digit_like_2legs/robot.urdf")


def test_fk_of_one_leg_closes_every_loop_and_keeps_the_given_values(capsys):
    """fk --sub 1 with the left leg's six values (hip pitch and knee moved): the whole
    tree closes (every closure residual below 1e-9), the left leg's actuated joints hold
    the given values and the right leg's their reference ones (1e-9); the right foot stays
    where it was (1e-9), the left foot moves by more than 1 cm and is where the whole
    tree puts it; the same as fk of all twelve values (1e-8)."""
    link, a, legs = _legs("digit_like_2legs")
    given = np.array(a.q_actuated[6:]) + [0.0, 0.0, 0.1, -0.05, 0.0, 0.0]
    assert main(["fk", DIGIT2, "--sub", "1", *map(str, given), "--json"]) == 0
    got = _strict(capsys.readouterr().out)
    q = np.array(got["q"])
    model = link.model
    assert np.abs(model.closure_residual(q)).max() < 1e-9
    values = model.actuated_values(q)
    assert np.allclose(values[6:], given, atol=1e-9)
    assert np.allclose(values[:6], a.q_actuated[:6], atol=1e-9)
    subs = got["submechanisms"]
    assert [(s["name"], s["output"], len(s["actuated"])) for s in subs] == [
        ("onshape[0]", "foot", 6), ("onshape[1]", "foot_left", 6)]
    assert np.allclose(subs[1]["q_actuated"], given, atol=1e-9)
    kin, kin0 = model.kinematics(q), model.kinematics(a.q)
    for s, moved in zip(subs, (False, True)):
        fid = model.tree.getFrameId(s["output"])
        assert np.allclose(s["pose"]["xyz"], kin.frame_placements[fid].translation, atol=1e-12)
        shift = np.linalg.norm(kin.frame_placements[fid].translation
                               - kin0.frame_placements[fid].translation)
        assert (shift > 1e-2) if moved else (shift < 1e-9)
    whole = np.concatenate([a.q_actuated[:6], given])
    assert main(["fk", DIGIT2, *map(str, whole), "--json"]) == 0
    assert np.allclose(_strict(capsys.readouterr().out)["q"], q, atol=1e-8)


def test_fk_text_gives_each_legs_foot_and_says_how_to_drive_one(capsys):
    """fk text of the twelve reference values: a block per leg with its six values and
    its foot at the reference pose; six values without --sub, or --sub out of range, or
    --sub on a one-mechanism file: one line naming --sub K and each leg's values."""
    link, a, legs = _legs("digit_like_2legs")
    assert main(["fk", DIGIT2, *map(str, a.q_actuated)]) == 0
    out = capsys.readouterr().out
    assert "sub-mechanisms  2 independent" in out and "fk --sub K" in out
    foot = a.output_pose.translation
    assert "[0] onshape[0]: motor_hip_x, motor_hip_z" in out
    line = next(x for x in out.splitlines() if x.strip().startswith("output foot:"))
    xyz = [float(v) for v in line.split("[")[1].split("]")[0].split(",")]
    assert np.allclose(xyz, foot, atol=1e-6)
    assert main(["fk", DIGIT2, *map(str, a.q_actuated[:6])]) == 2
    err = capsys.readouterr().err
    assert "6 actuated values given, 12 expected" in err and "--sub K" in err
    assert "1: onshape[1] (6 values: motor_hip_x_left," in err and len(err.splitlines()) == 1
    assert main(["fk", DIGIT2, "--sub", "2", "0"]) == 2
    assert "numbered 0 to 1" in capsys.readouterr().err
    assert main(["fk", DIGIT2, "--sub", "0", "0", "0"]) == 2
    assert "2 actuated values given, 6 expected" in capsys.readouterr().err
    assert main(["fk", str(FOUR_BAR), "--sub", "0", "0"]) == 2
    assert "one mechanism" in capsys.readouterr().err


def test_check_judges_each_leg_with_its_own_foot(capsys):
    """check of a biped: a line per leg (its actuators, foot, DOF 6, idle 0, 3T3R, class
    none), the whole's one-output type I as information, no warning, exit 0 and no
    'nan'; Menagerie's Cassie: each leg warned as type III of its own foot (springs)."""
    assert main(["check", DIGIT2]) == 0
    out = capsys.readouterr().out
    legs = [x for x in out.splitlines() if x.startswith("ok    sub-mechanism")]
    assert len(legs) == 2
    assert "[1] onshape[1]: 18 joints, 6 actuated (motor_hip_x_left," in legs[1]
    assert legs[1].endswith("output 'foot_left': DOF 6, idle DOF 0, output motion 3T3R, "
                            "singularity none")
    assert "info  the whole read with the one output 'foot' is type I" in out
    assert "warn" not in out and "nan" not in out and out.rstrip().endswith("fine")
    cassie = ROOT / "tests" / "data" / "menagerie" / "agility_cassie" / "cassie.xml"
    assert main(["check", str(cassie)]) == 1
    warns = [x for x in capsys.readouterr().out.splitlines() if x.startswith("warn")]
    assert [w.split(":")[0] for w in warns] == ["warn  sub-mechanism cassie[0]",
                                                 "warn  sub-mechanism cassie[1]"]
    assert all("type III singularity of its output" in w for w in warns)


def test_view_titles_colours_and_wrenches_per_leg():
    """view of battobot: a title line per leg (its foot, 6 DOF, 3T3R, class none), a
    legend entry per leg in the colour of its bars, both feet drawn, and the twelve
    actuation wrenches, each leg's from its own analysis: each arrow starts on its
    wrench's axis at the point nearest its own foot (1e-9 m), or, for an axis metres
    away, is centred on its own foot along the moment about it (1e-9)."""
    from test_view import page_commands

    from pkm_pin.scene import LEG_COLOURS
    from pkm_pin.view import view

    link, a, legs = _legs("battobot_6d")
    scene = view(link, a)
    assert scene.title_lines[1].startswith("2 independent sub-mechanisms")
    assert scene.title_lines[2].startswith("[0] onshape[0]: output foot_right at xyz")
    assert scene.title_lines[3].endswith("6 DOF, output motion 3T3R, singularity: none")
    entries = {e.kind: e for e in scene.legend}
    assert entries["sub:onshape[1]"].colours == (LEG_COLOURS[1],)
    assert entries["sub:onshape[1]"].note.startswith("output foot_left: 6 DOF")
    commands = page_commands(scene.to_html())
    root = f"/meshcat/{scene.root}"
    colours = {c["path"]: int(c["object"]["materials"][0]["color"]) for c in commands
               if c["type"] == "set_object" and "materials" in c["object"]}
    assert colours[f"{root}/links/knee_right"] == LEG_COLOURS[1]
    assert colours[f"{root}/links/knee_left"] == LEG_COLOURS[0]
    assert f"{root}/output/1/ball" in colours
    moves = {c["path"]: np.array(c["matrix"], dtype=float).reshape(4, 4).T for c in commands
             if c["type"] == "set_transform"}
    tree = link.model.tree
    kin = link.model.kinematics(a.q)
    couples = 0
    for sub, an in scene.submechanisms:
        foot = kin.frame_placements[tree.getFrameId(sub.output)].translation
        for name, w in zip(sub.actuated, an.A):
            point, u = screws.axis(w, length=link.model.length)
            M = moves[f"{root}/wrenches/actuation/{name}"]
            if f"{root}/wrenches/actuation/{name}/tail" in moves:  # axis metres away
                m = w[3:] - np.cross(foot, w[:3])
                u = M[:3, 1]
                assert np.allclose(u, m / np.linalg.norm(m), atol=1e-9), name
                back = foot - M[:3, 3]  # from its tail to its foot: along u
                assert np.linalg.norm(np.cross(back, u)) < 1e-9 and back @ u > 0, name
                couples += 1
                continue
            nearest = point + ((foot - point) @ u) * u
            assert np.linalg.norm(M[:3, 3] - nearest) < 1e-9, name
    assert 0 < couples < 12
    assert len({p.rsplit("/", 1)[0] for p in colours
                if "/wrenches/actuation/" in p}) == 12


def test_markdown_gives_the_summary_and_each_leg_before_the_joint_table(tmp_path, capsys):
    """analyze --markdown of battobot: the summary (DOF 12, class I) and a table row per
    leg (its six actuators, its foot, DOF 6, idle 0, 3T3R, none) come before the
    48-row joint table."""
    md = tmp_path / "b.md"
    assert main(["analyze", str(DATA / "battobot_6d/robot.urdf"), "--markdown", str(md)]) == 0
    capsys.readouterr()
    lines = md.read_text().splitlines()
    summary, table = lines.index("## Summary"), lines.index("## Configuration")
    assert summary < table
    assert "- DOF **12**, idle DOF 0, output motion 3T3R, singularity **I**" in lines[:table]
    rows = [x for x in lines[:table] if x.startswith("| onshape[")]
    assert rows == [
        "| onshape[0] | hipz_left, hipx_left, hipy_left, motor_ankle1_left, motor_ankle2_left, "
        "motor_knee_left | foot_right | 6 | 0 | 3T3R | none |",
        "| onshape[1] | hipz_right, hipx_right, hipy_right, motor_ankle1_right, "
        "motor_ankle2_right, motor_knee_right | foot_left | 6 | 0 | 3T3R | none |"]


def test_a_failing_split_costs_only_the_per_leg_part(monkeypatch, capsys, tmp_path):
    """When the split into legs fails (an error the split raises, here an IndexError
    planted in it), check, fk and view still answer for the whole, each naming the
    section not computed with its error: check warns (exit 1) and keeps the whole's
    class; fk prints the foot pose of the whole's assembly (its JSON records the
    failure); view draws the whole; fk --sub says in one line why it cannot."""
    import pkm_pin.submechanisms as sm

    def broken(link, q=None):
        raise IndexError("index 7 is out of bounds for axis 0 with size 7")

    link, a, _ = _legs("digit_like_2legs")
    monkeypatch.setattr(sm, "submechanisms", broken)
    assert main(["check", DIGIT2]) == 1
    out = capsys.readouterr().out
    assert "warn  sub-mechanisms not computed (IndexError: index 7 is out of bounds" in out
    assert "warn  the reference assembly is a type I singularity" in out
    assert main(["fk", DIGIT2, *map(str, a.q_actuated.tolist()), "--json"]) == 0
    got = _strict(capsys.readouterr().out)
    assert got["submechanisms"] == [] and got["failed_sections"]["submechanisms"].startswith(
        "IndexError")
    assert np.allclose(got["pose"]["xyz"], a.output_pose.translation, atol=1e-9)
    assert main(["fk", DIGIT2, "--sub", "0", *map(str, a.q_actuated[:6].tolist())]) == 2
    assert "the sub-mechanisms of 'onshape' could not be computed (IndexError" in (
        capsys.readouterr().err)
    assert main(["view", DIGIT2, "--html", str(tmp_path / "d.html")]) == 0
    out = capsys.readouterr().out
    assert "failed     submechanisms: IndexError: index 7" in out and "sub [0]" not in out


def test_map_of_one_leg_reads_its_own_foot(tmp_path, capsys):
    """map --sub 1 of digit_like_2legs over the left hip pitch and knee (3 × 3): every
    point assembles and is regular for the left foot (the whole map reads type I at
    each, with a note naming both legs and --sub); each foot pose of the map is the one
    the whole model's fk gives with those two motors set (1e-8 m)."""
    link, a, _ = _legs("digit_like_2legs")
    args = ["--n", "3", "--quiet", "--actuated", "motor_hip_y_left", "motor_knee_left",
            "--range", "-0.3", "-0.1", "-0.05", "0.1"]
    assert main(["map", DIGIT2, "--sub", "1", "--out", str(tmp_path / "left"), *args]) == 0
    capsys.readouterr()
    data = np.load(tmp_path / "left.npz")
    assert str(data["output"]) == "foot_left" and data["converged"].all()
    assert (data["singularity"] == "none").all()
    foot = link.model.tree.getFrameId("foot_left")
    for i, j in ((0, 0), (2, 1), (1, 2)):
        qa = a.q_actuated.copy()
        qa[6:] = data["q_actuated"][i, j]
        whole = link.forward_kinematics(qa, guess=a)
        M = link.model.kinematics(whole.q).frame_placements[foot].homogeneous
        assert np.allclose(data["output_poses"][i, j], M, atol=1e-8)
    right = ["--actuated", "motor_hip_y", "motor_knee", "--range", "-0.1", "0.1", "-0.1",
             "0.1"]
    assert main(["map", DIGIT2, "--out", str(tmp_path / "whole"), "--n", "3", "--quiet",
                 *right]) == 0
    out = capsys.readouterr().out
    assert ("note       2 independent sub-mechanisms (0: onshape[0], output foot; 1: "
            "onshape[1], output foot_left)") in out and "--sub K maps one" in out
    assert "class I 9, class II 0, class III 0" in out
    assert main(["map", str(FOUR_BAR), "--sub", "0", "--out", str(tmp_path / "f")]) == 2
    assert "one mechanism" in capsys.readouterr().err
