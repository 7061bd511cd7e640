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
