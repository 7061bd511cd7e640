"""One facade (issue 24): every file gives a :class:`pkm_pin.Mechanism`, whose
``backend`` says which engine answers, and both backends answer the same names.

The general backend's answers are its :attr:`Mechanism.general`'s (a Linkage) exactly;
the per-leg backend answers the tree's questions (mobility with generic ranks,
transmission over the tree, sub-mechanisms) through the general elimination of its own
closure model assembled at its home; a per-leg-only name on a model with no legs is refused
with the reason.
"""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkm_pin
from pkm_pin import Mechanism, load_mechanism
from pkm_pin.errors import InputError
from pkm_pin.linkage import Linkage

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
FIVE_BAR = MODELS / "loops" / "five_bar.urdf"
FOUR_BAR = MODELS / "loops" / "four_bar.urdf"
RPR3 = MODELS / "mechanisms" / "rpr3.toml"
STEWART = MODELS / "mechanisms" / "stewart.toml"
SHIPPED = sorted([*MODELS.glob("mechanisms/*.toml"), *MODELS.glob("pinned/*.toml"),
                  *MODELS.glob("loops/*.urdf"), *MODELS.glob("loops/*.xml")])


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_shipped_file_is_a_mechanism(path):
    """One class whatever the file; the backend: per leg for TOML legs and for the
    Extended URDF and MJCF files in which a base–legs–platform machine is detected (the
    legs taking the actuated values in the file's order, named as the file names
    them), the general elimination for the others; the general backend's object behind
    it."""
    mech = load_mechanism(path)
    assert isinstance(mech, Mechanism)
    per_leg = {"delta_loops.urdf", "five_bar.xml", "four_bar.urdf", "four_bar.xml"}
    expected = "legs" if path.parent.name == "mechanisms" or path.name in per_leg \
        else "general"
    assert mech.backend == expected
    if path.suffix != ".toml":
        assert mech.actuated == mech.general.actuated
    assert isinstance(mech.general, Linkage)
    assert mech.name == mech.general.name
    assert repr(mech).startswith("Mechanism(")


def test_general_backend_answers_are_its_linkages():
    """The five-bar: assembly, analysis, FK, mobility, transmission and the actuated
    names are those of mech.general to the last bit."""
    mech = load_mechanism(FIVE_BAR)
    link = mech.general
    a = mech.assemble()
    np.testing.assert_array_equal(a.q, link.assemble().q)
    an, ref = mech.analyze(a.q), link.analyze(a.q)
    np.testing.assert_array_equal(an.A, ref.A)
    np.testing.assert_array_equal(an.B, ref.B)
    assert an.dof == ref.dof == 2
    assert mech.actuated_names == link.actuated_names and mech.n_actuated == 2
    qa = a.q_actuated + 0.05
    np.testing.assert_array_equal(mech.forward_kinematics(qa, guess=a.q).q,
                                  link.forward_kinematics(qa, guess=a.q).q)
    assert mech.mobility(a) == link.mobility(a.q)
    assert mech.submechanisms() == [mech]
    t, r = mech.transmission(a.q), link.transmission(a.q)
    assert t.worst == r.worst


def test_per_leg_backend_answers_the_trees_questions():
    """The TOML Stewart answers mobility (generic ranks), transmission over the tree and
    its sub-mechanisms through its general reading, assembled at its home."""
    mech = load_mechanism(STEWART)
    assert mech.backend == "legs" and mech.legs_mechanism is mech
    home = mech.home_assembly
    mob = mech.mobility(home)
    # 6 × (U 2 + P 1 + S 3) + the platform's 6 = 42 rates, 6 welds = 36 rows: Grübler 6
    assert mob.dof == mech.home_analysis.dof == 6 and mob.idle_dof == 0 and mob.grubler == 6
    assert not mob.singular
    np.testing.assert_allclose(mech.general.home_assembly.q, mech.tree_configuration(home),
                               atol=1e-12)
    assert mech.submechanisms() == [mech]
    structure, _ = mech.platform_structure
    assert structure is not None and len(structure.legs) == 6


def test_from_model_reads_either_backend():
    """Mechanism.from_model: the general backend by default, the per-leg engine on a
    detected machine with backend='legs' (same forward velocity map at home)."""
    source = load_mechanism(FOUR_BAR)
    general = Mechanism.from_model(source.model)
    assert general.backend == "general"
    legs = Mechanism.from_model(source.model, backend="legs", q=source.home_assembly.q)
    assert legs.backend == "legs" and legs.structure is not None
    with pytest.raises(InputError, match="backend='planar'.*'legs', 'general'"):
        Mechanism.from_model(source.model, backend="planar")
    with pytest.raises(InputError, match="takes a pkm_pin.linkage.Linkage"):
        Mechanism.of_linkage(source)


def test_per_leg_names_on_a_model_without_legs_say_why():
    """A per-leg-only name (the compiled leg frames) on the five-bar, whose closures do
    not join one platform, is refused with the structure's reason; a Linkage made alone
    points to the facade."""
    mech = load_mechanism(FIVE_BAR)
    with pytest.raises(InputError, match="not a base–legs–platform machine"):
        mech.leg_frames
    four = load_mechanism(FOUR_BAR)
    alone = Linkage(four.model)
    with pytest.raises(InputError, match="Mechanism.from_model"):
        alone.legs_mechanism
    assert isinstance(four.legs_mechanism, Mechanism)
    assert four.legs_mechanism.backend == "legs"


def test_general_backend_mechanism_pickles():
    """A general-backend mechanism crosses process boundaries (workspaces with jobs)."""
    mech = load_mechanism(FIVE_BAR)
    a = mech.assemble()
    back = pickle.loads(pickle.dumps(mech))
    assert back.backend == "general" and back.name == mech.name
    np.testing.assert_allclose(back.analyze(a.q).A, mech.analyze(a.q).A, atol=1e-12)


def test_the_public_name_is_the_facade():
    """pkm_pin.Mechanism is the class every loader returns."""
    assert pkm_pin.Mechanism is Mechanism
    assert isinstance(load_mechanism(RPR3), pkm_pin.Mechanism)


def test_sub_on_a_platform_machine_is_one_path(tmp_path, capsys):
    """--sub K goes through Mechanism.submechanisms for every mechanism: a platform
    machine is one ([mech]), so --sub 0 on the Stewart is refused in one line saying so,
    by workspace and by dynamics --indices alike (one path, no branch per backend)."""
    from pkm_pin.cli import main

    mech = load_mechanism(STEWART)
    assert mech.submechanisms() == [mech]
    for argv in (["dynamics", str(STEWART), "--indices", "--sub", "0"],
                 ["workspace", str(STEWART), "--sub", "0", "--n", "2", "--quiet",
                  "--out", str(tmp_path / "ws")]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "is one mechanism (no independent sub-mechanisms)" in err[0]


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_mechanism_answers_the_same_names(path):
    """The names both backends share answer without arguments at home (assemble,
    analyze, mobility, transmission, sub-mechanisms, the tree's configuration), and
    agree with each other: the analysis' DOF is the mobility's, the home configuration
    closes the loops, assembling again lands on it."""
    mech = load_mechanism(path)
    a = mech.assemble()
    an = mech.analyze()
    mob = mech.mobility()
    assert an.dof == mob.dof >= 1
    assert mech.transmission() is not None
    assert mech.submechanisms()[0] is mech or len(mech.submechanisms()) > 1
    q = mech.tree_configuration()
    assert np.abs(mech.model.closure_residual(q)).max() < 1e-8
    np.testing.assert_allclose(mech.tree_configuration(a) if mech.backend == "legs" else a.q,
                               q, atol=1e-7)


GRIPPER = ROOT / "tests" / "data" / "menagerie" / "robotiq_2f85" / "2f85.xml"
DISNEY = ROOT / "tests" / "data" / "gepetto" / "disney_like" / "robot.urdf"


def test_every_mode_of_an_underactuated_mechanism_is_refused_in_a_sentence():
    """Robotiq's 2F-85 (one motor, two adaptive fingers: mobility 3, idle 2) has a
    continuum of assemblies at a motor value: forward_kinematics_all says so at once
    (the free directions of the closure Jacobian with the motor locked move its bodies)
    instead of collecting 'modes' for minutes; the disney-like leg, whose hip group spins
    with every motor locked, stops when new assemblies keep appearing; the five-bar
    still finds its two modes."""
    from pkm_pin.errors import ForwardKinematicsError

    gripper = load_mechanism(GRIPPER)
    mob = gripper.mobility()
    assert (mob.dof, mob.idle_dof, gripper.n_actuated) == (3, 2, 1)
    with pytest.raises(ForwardKinematicsError, match="still moves with its actuated joints "
                       "locked \\(2 motions"):
        gripper.forward_kinematics_all(gripper.home_assembly.q_actuated)
    disney = load_mechanism(DISNEY)
    with pytest.raises(ForwardKinematicsError, match="do not settle into modes") as many:
        disney.forward_kinematics_all(disney.home_assembly.q_actuated)
    # a continuum, or more discrete modes than a list holds: the message names both
    assert "idle motions" in str(many.value) and "closes two ways" in str(many.value)
    five = load_mechanism(FIVE_BAR)
    modes = five.forward_kinematics_all(five.home_assembly.q_actuated)
    assert len(modes) == 2 and modes.counts["batches"] <= 10


def test_the_multistart_estimate_is_chao1_bias_corrected():
    """The estimate of the assemblies a multistart would find in all, from how often each
    was found: S + f1 (f1 − 1) / (2 (f2 + 1)), by hand on three cases."""
    from pkm_pin.linkage import _Multistart

    def estimate(hits):
        return _Multistart([], [], 0, 0, None, list(hits)).estimate()

    assert estimate([]) == 0.0
    assert estimate([5, 7, 9]) == 3.0  # each found many times: all seen
    # 28 found, 26 once, 1 twice (kangaroo_like_2legs after 8 batches): 28 + 26·25/4
    assert estimate([1] * 26 + [2] + [4]) == pytest.approx(28 + 26 * 25 / 4)


KANGAROO_2LEGS = ROOT / "tests" / "data" / "gepetto" / "kangaroo_like_2legs" / "robot.urdf"


def test_a_multistart_that_keeps_finding_new_assemblies_stops_early():
    """kangaroo_like_2legs at home: about five new assemblies a batch, almost each found
    once (two legs of twelve closures: hundreds of modes). The multistart refuses after
    the estimate of those still unseen passes MODES_MAX (9 batches of 32 starts + the
    reference), not after 60 batches as before, and its sentence says why. Gepetto's
    battobot_6d (four loops closing two ways each) still lists its 16 modes, each found
    many times."""
    import re

    from pkm_pin.errors import ForwardKinematicsError
    from pkm_pin.tolerances import MODES_ESTIMATE_FROM

    kangaroo = load_mechanism(KANGAROO_2LEGS)
    with pytest.raises(ForwardKinematicsError, match="do not settle into modes") as many:
        kangaroo.forward_kinematics_all(kangaroo.home_assembly.q_actuated,
                                        method="multistart")
    message = " ".join(str(many.value).split())
    found, tried = map(int, re.search(r"(\d+) distinct ones after (\d+) starts",
                                      message).groups())
    assert 32 * MODES_ESTIMATE_FROM < tried <= 32 * (MODES_ESTIMATE_FROM + 4) + 1
    assert 10 <= found < 100
    assert "most found once" in message or "in all, from how often" in message
    batto = load_mechanism(ROOT / "tests" / "data" / "gepetto" / "battobot_6d" / "robot.urdf")
    modes = batto.forward_kinematics_all(batto.home_assembly.q_actuated, method="multistart")
    assert len(modes) == 16 and modes.counts["batches"] < MODES_ESTIMATE_FROM


def test_a_general_backend_mechanism_lists_what_it_answers():
    """dir() of a general-backend mechanism holds the general backend's public names
    (idle motions, partial poses, the tree's sensitivity) besides the facade's."""
    names = dir(load_mechanism(FIVE_BAR))
    for name in ("mobility", "legs_mechanism", "tree_sensitivity", "reached", "with_legs",
                 "analyze", "backend", "general"):
        assert name in names, name


def test_per_leg_description_of_a_general_backend_mechanism():
    """legs, anchors and home of a general-backend mechanism are those of the machine
    detected in its model (the four-bar: two legs, the rocker's home at x = 0.1), and a
    sentence where there is none (the five-bar's output is a point)."""
    four = load_mechanism(FOUR_BAR)
    assert len(four.legs) == len(four.anchors) == 2
    np.testing.assert_allclose(four.home.translation,
                               four.home_assembly.output_pose.translation, atol=1e-12)
    with pytest.raises(InputError, match="the output is a point"):
        load_mechanism(FIVE_BAR).home


def test_builders_give_a_mechanism_for_pinned_legs_too():
    """A design whose legs meet at a pin builds a Mechanism read by the general backend
    (it was a bare Linkage): the five-bar, DOF 2 as before."""
    from pkm_pin.builders.pinned import five_bar

    mech = five_bar().build()
    assert isinstance(mech, Mechanism) and mech.backend == "general"
    assert mech.analyze().dof == 2


# ------------------------------------------- one assembly, one analysis (issue 24, item 2)
PARITY = [MODELS / "mechanisms" / "stewart.toml", MODELS / "mechanisms" / "delta.toml",
          MODELS / "mechanisms" / "rrr3.toml", MODELS / "mechanisms" / "upu3.toml",
          MODELS / "loops" / "delta_loops.urdf", MODELS / "loops" / "four_bar.xml",
          MODELS / "loops" / "five_bar.xml"]


@pytest.mark.parametrize("path", PARITY, ids=lambda p: p.name)
def test_a_per_leg_assembly_answers_the_trees_names(path):
    """A per-leg Assembly answers what a general linkage's assembly does, with the same
    numbers: ``q`` (the whole tree, the model's order), ``output_pose``,
    ``q_actuated``, ``closure_residuals``; and ``q`` read back per leg gives the legs."""
    legs = load_mechanism(path, backend="legs")
    general = load_mechanism(path, backend="general")
    a, g = legs.home_assembly, general.home_assembly
    assert a.q.shape == (legs.model.tree.nq,) == g.q.shape
    # the same tree configuration (legs read off it close the loops the same way)
    assert max(a.closure_residuals.values()) < 1e-12
    assert set(a.closure_residuals) == set(g.closure_residuals)
    np.testing.assert_allclose(a.output_pose.homogeneous, g.output_pose.homogeneous,
                               atol=1e-12)
    np.testing.assert_allclose(np.sort(a.q_actuated), np.sort(g.q_actuated), atol=1e-12)
    back = legs.legs_assembly(a.q)
    for q0, q1 in zip(a.leg_q, back.leg_q):
        np.testing.assert_allclose(q1, q0, atol=1e-10)
    assert a.q is a.q  # computed once


@pytest.mark.parametrize("path", PARITY, ids=lambda p: p.name)
def test_analyze_takes_the_trees_configuration_on_either_backend(path):
    """``analyze(assembly.q)`` is ``analyze(assembly)`` on both backends (one way to name
    a configuration), and a per-leg analysis answers ``output_dof``, ``idle_dof`` and
    ``mobility`` with the general reading's numbers."""
    for backend in ("legs", "general"):
        mech = load_mechanism(path, backend=backend)
        a = mech.assemble()
        an, by_q = mech.analyze(a), mech.analyze(a.q)
        np.testing.assert_allclose(by_q.A, an.A, atol=1e-9)
        assert by_q.indices == pytest.approx(an.indices, abs=1e-9)
    legs = load_mechanism(path, backend="legs").home_analysis
    general = load_mechanism(path, backend="general").home_analysis
    assert legs.output_dof == general.output_dof == legs.dof
    assert legs.idle_dof == general.idle_dof
    assert legs.mobility.dof == general.mobility.dof
    assert legs.mobility.grubler == general.mobility.grubler


def test_a_stewart_assembly_away_from_home_round_trips_through_its_tree():
    """Off home (forward kinematics of longer legs), the TOML Stewart's tree
    configuration gives the same pose and legs back, and the analysis there."""
    mech = load_mechanism(STEWART)
    a = mech.forward_kinematics(mech.home_assembly.q_actuated + 0.02)
    back = mech.assembly_at(a.q)
    np.testing.assert_allclose(back.pose.homogeneous, a.pose.homogeneous, atol=1e-12)
    np.testing.assert_allclose(back.q_actuated, a.q_actuated, atol=1e-12)
    assert mech.analyze(a.q).indices == pytest.approx(mech.analyze(a).indices, abs=1e-9)
    with pytest.raises(InputError):
        mech.legs_assembly(np.zeros(mech.model.tree.nq - 1))


def test_per_leg_reading_takes_the_general_arguments():
    """five_bar.xml is read per leg; it takes what a general-backend mechanism takes:
    assemble(tree configuration that does not close) closes the loops nearest it, and
    forward_kinematics(..., starts=) reaches a target the continuation from home stops
    short of (a fold on the way: the other assembly mode), the motors at the target and
    the loop closed, the same as the general backend's solution from the same starts
    up to the branch (its closure residual and motor values)."""
    from pkm_pin.errors import ForwardKinematicsError

    mech = load_mechanism(MODELS / "loops" / "five_bar.xml")
    assert mech.backend == "legs" and mech.actuated == ("mot1", "mot2")
    near = np.asarray(mech.model.reference) + 0.05
    a = mech.assemble(near)
    assert max(a.closure_residuals.values()) < 1e-12
    assert np.linalg.norm(a.q - near) < 0.1
    np.testing.assert_allclose(a.q, mech.general.assemble(near).q, atol=1e-9)
    target = [1.79, -2.33]
    with pytest.raises(ForwardKinematicsError):
        mech.forward_kinematics(target)
    b = mech.forward_kinematics(target, starts=16)
    np.testing.assert_allclose(b.q_actuated, target, atol=1e-9)
    assert max(b.closure_residuals.values()) < 1e-10
    np.testing.assert_allclose(mech.model.actuated_values(b.q), target, atol=1e-9)
    with pytest.raises(ForwardKinematicsError):  # out of the motors' reach: still refused
        mech.forward_kinematics([1.2, -0.9], starts=4)


@pytest.mark.parametrize("name", ["mechanisms/stewart.toml", "mechanisms/delta.toml",
                                  "mechanisms/rpr3.toml", "loops/five_bar.xml",
                                  "loops/four_bar.urdf", "loops/delta_loops.urdf"])
def test_per_leg_motion_indices_are_the_general_eliminations(name):
    """The per-leg Analysis's forward and inverse indices (from its platform twists and
    A Δ t = B q̇_a) equal the general elimination's of the same tree configuration (from
    the closure Jacobian's null space) to 1e-9, at home and away from it, although A's
    representatives differ on the planar machines; the report of the per-leg reading
    carries all five indices, as the general reading's does."""
    from pkm_pin.report import report_data

    mech = load_mechanism(MODELS / name)
    assert mech.backend == "legs"
    home = mech.home_assembly
    away = mech.forward_kinematics(np.asarray(home.q_actuated) + 0.03)
    for a in (home, away):
        mine = mech.analyze(a).motion_indices
        theirs = mech.general.analyze(mech.tree_configuration(a)).indices
        for key in ("forward", "inverse"):
            assert 0 < mine[key] <= 1
            assert mine[key] == pytest.approx(theirs[key], abs=1e-9), key
    data = report_data(mech, home)
    assert list(data["indices"]) == ["type_I", "type_II", "condition_A", "forward", "inverse"]


def test_one_sweep_result_for_both_backends():
    """Mechanism.sweep (poses, per leg) and the general sweep (actuated values) give the
    one SweepResult: the same fields, each point's output pose (x, y, z, roll, pitch,
    yaw and as a placement), classes and the five indices equal to the analyses' at that
    point (1e-9), nan where one backend does not compute a number, and the failures
    named."""
    from pkm_pin.linkage import LinkageSweep
    from pkm_pin.sweep import SweepResult

    assert LinkageSweep is SweepResult
    five = load_mechanism(FIVE_BAR)  # a point output: read by the general elimination
    home = five.assemble()
    Q = home.q_actuated + np.array([[0.0, 0.0], [0.05, -0.02], [2.5, 0.0]])  # last: apart
    general = five.general.sweep(Q, home)
    assert isinstance(general, SweepResult)
    assert general.ok.tolist() == [True, True, False] and general.converged is general.ok
    assert [i for i, _ in general.failures] == [2] and "loop" in general.failures[0][1]
    for i in (0, 1):
        an = five.general.analyze(general.q[i])
        for key in ("type_I", "type_II", "forward", "inverse"):
            assert getattr(general, key)[i] == pytest.approx(an.indices[key], rel=1e-9)
        pose = five.general.assemble(general.q[i]).output_pose
        np.testing.assert_allclose(general.output_poses[i], pose.homogeneous, atol=1e-12)
        assert general.singularity[i] == an.singularity
    assert np.isnan(general.det).all() and np.isnan(general.poses[2]).all()
    stewart = load_mechanism(STEWART)
    moved = stewart.home * pin.SE3(np.eye(3), np.array([0.0, 0.02, 0.01]))
    legs = stewart.sweep([stewart.home, moved])
    assert isinstance(legs, SweepResult) and legs.q is None
    np.testing.assert_allclose(legs.output_poses[1], moved.homogeneous, atol=1e-12)
    np.testing.assert_array_equal(legs.output_dof, legs.dof)
    assert np.isnan(legs.forward).all() and set(legs.arrays()) >= set(general.arrays()) - {"q"}


def test_general_reading_takes_what_assembly_at_takes():
    """A mechanism read by the general backend (Cassie's knee: multi-loop legs) answers
    assembly_at and analyze as a per-leg one: None is home, a tree configuration is
    assembled nearest it, a pose (SE3 or six numbers) by inverse kinematics of the
    output, a partial pose with the given coordinate met; analyze at a pose equals
    analyze at that assembly."""
    from pkm_pin.linkage import LinkageAssembly

    mech = load_mechanism(MODELS / "loops" / "cassie_knee.urdf")
    assert mech.backend == "general"
    home = mech.home_assembly
    assert mech.assembly_at() is home and mech.assembly_at(home) is home
    at_q = mech.assembly_at(np.asarray(home.q))
    np.testing.assert_allclose(at_q.q, home.q, atol=1e-12)
    moved = home.output_pose * pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.005]))
    at_pose = mech.assembly_at(moved)
    assert isinstance(at_pose, LinkageAssembly) and max(at_pose.closure_residuals.values()) < 1e-10
    six = np.r_[home.output_pose.translation, pin.rpy.matrixToRpy(home.output_pose.rotation)]
    np.testing.assert_allclose(mech.assembly_at(six).output_pose.homogeneous,
                               home.output_pose.homogeneous, atol=1e-9)
    partial = mech.assembly_at({"z": -0.79})
    assert partial.output_pose.translation[2] == pytest.approx(-0.79, abs=1e-10)
    a, b = mech.analyze(moved), mech.analyze(at_pose)
    np.testing.assert_allclose(a.A, b.A, atol=1e-12)
    assert a.indices["type_II"] == pytest.approx(b.indices["type_II"], rel=1e-12)


def test_every_working_mode_of_a_linkage_without_legs():
    """inverse_kinematics_all on the general backend where no legs can be read. The
    five-bar with a point output: each motor's crank reaches the point in two ways, so
    the modes are the four combinations of the two cranks' two angles (the home's
    first), each closing the loop with the point at the target (1e-9). Cassie's knee
    (a 2-DOF foot): every mode reaches the whole foot pose (1e-9), home's first; the
    assemblies that meet the targeted components with another foot pose are not
    listed."""
    five = load_mechanism(FIVE_BAR)
    assert five.backend == "general" and five.model.output_point
    home = five.home_assembly
    modes = five.inverse_kinematics_all(home.output_pose)
    qa = np.array([m.q_actuated for m in modes])
    assert len(modes) == 4 and np.allclose(qa[0], home.q_actuated, atol=1e-9)
    first, second = (np.unique(np.round(qa[:, k], 6)) for k in (0, 1))
    assert len(first) == len(second) == 2
    assert {tuple(np.round(x, 6)) for x in qa} == {(a, b) for a in first for b in second}
    for m in modes:
        assert max(m.closure_residuals.values()) < 1e-10
        np.testing.assert_allclose(m.output_pose.translation, home.output_pose.translation,
                                   atol=1e-9)
    knee = load_mechanism(MODELS / "loops" / "cassie_knee.urdf")
    target = knee.home_assembly.output_pose
    modes = knee.inverse_kinematics_all(target)
    assert len(modes) >= 2
    np.testing.assert_allclose(modes[0].q, knee.home_assembly.q, atol=1e-9)
    for m in modes:
        np.testing.assert_allclose(m.output_pose.homogeneous, target.homogeneous, atol=1e-9)
    assert min(np.abs(a.q_actuated - b.q_actuated).max() for a, b in
               zip(modes, modes[1:])) > 1e-3


SERIAL_ARM = """<mujoco model="arm">
  <worldbody>
    <body name="upper">
      <joint name="shoulder" type="hinge" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>
      <body name="fore" pos="0.3 0 0">
        <joint name="elbow" type="hinge" axis="0 0 1"/>
        <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.02"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="shoulder"/><motor joint="elbow"/></actuator>
</mujoco>
"""


def test_a_serial_tree_is_not_read_per_leg(tmp_path):
    """An MJCF arm without closures: detection sees one 'leg' (the whole tree to the
    output), but a serial tree is not a base–legs–platform machine, so the default
    reading stays the general elimination (2 DOF, the planar 2R arm's motion)."""
    path = tmp_path / "arm.xml"
    path.write_text(SERIAL_ARM)
    arm = load_mechanism(path)
    assert not arm.model.closures and arm.general.platform_structure[0] is not None
    assert arm.backend == "general"
    an = arm.analyze()
    assert an.dof == 2 and an.motion_type == "1T1R"


def test_both_analyses_answer_q_and_motion_indices():
    """The per-leg Analysis gives its tree configuration as q (that of its assembly),
    and the general LinkageAnalysis its forward and inverse indices as motion_indices,
    so code written against one reads the other."""
    legs = load_mechanism(STEWART)
    an = legs.analyze()
    np.testing.assert_array_equal(an.q, legs.home_assembly.q)
    general = legs.general.analyze(an.q)
    np.testing.assert_array_equal(general.q, an.q)
    assert general.motion_indices == {k: general.indices[k] for k in ("forward", "inverse")}
    for key, value in an.motion_indices.items():
        assert value == pytest.approx(general.motion_indices[key], abs=1e-9)


def test_general_sweep_takes_poses_as_the_per_leg_one_does():
    """Linkage.sweep over poses (pin.SE3, or partial poses) as Mechanism.sweep takes
    them: the five-bar's point along a line, each point where asked (1e-9), its
    analysis that of the assembly found and its actuated values recorded; a pose out of
    reach recorded as a failure with its reason; Cassie's knee along partial poses {z}
    reaches the heights asked."""
    five = load_mechanism(FIVE_BAR)
    home = five.home_assembly.output_pose
    line = [home * pin.SE3(np.eye(3), np.array([dx, 0.0, 0.0])) for dx in (0.0, 0.01, 0.02)]
    swept = five.sweep(line + [home * pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.0]))])
    assert swept.ok.tolist() == [True, True, True, False] and swept.failures[0][0] == 3
    for i, pose in enumerate(line):
        np.testing.assert_allclose(swept.poses[i, :3], pose.translation, atol=1e-9)
        an = five.general.analyze(swept.q[i])
        assert swept.forward[i] == pytest.approx(an.indices["forward"], rel=1e-9)
        np.testing.assert_allclose(swept.q_actuated[i], five.model.actuated_values(swept.q[i]),
                                   atol=1e-12)
    assert np.isnan(swept.q_actuated[3]).all()
    knee = load_mechanism(MODELS / "loops" / "cassie_knee.urdf")
    heights = [-0.79, -0.788, -0.786]
    partial = knee.sweep([{"z": z} for z in heights])
    assert partial.ok.all()
    np.testing.assert_allclose(partial.poses[:, 2], heights, atol=1e-9)
