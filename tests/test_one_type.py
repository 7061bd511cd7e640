"""One result type per concept (issue 24): every mechanism's assemblies are
:class:`pkm_pin.Assembly` and its analyses :class:`pkm_pin.Analysis`, whichever backend
reads it. The per-leg engine and the general elimination answer the same names with the
same numbers for the same machine; an assembly made by one backend is taken by the
other; what only legs have is refused in a sentence."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkm_pin
from pkm_pin import Analysis, Assembly, LegsAnalysis, TreeAnalysis

MODELS = Path(__file__).resolve().parents[1] / "models"
SHIPPED = sorted(str(p.relative_to(MODELS)) for p in
                 [*MODELS.glob("loops/*.urdf"), *MODELS.glob("loops/*.xml"),
                  *MODELS.glob("pinned/*.toml"), *MODELS.glob("mechanisms/*.toml")])

#: The names every analysis answers (Analysis's docstring).
ANALYSIS_NAMES = ("q", "mobility", "dof", "idle_dof", "output_dof", "translations",
                  "motion_type", "grubler", "redundant_constraints", "platform_twists",
                  "constraint_wrenches", "A", "actuation_wrenches", "B", "actuated_twists",
                  "joint_twists", "indices", "motion_indices", "singularity",
                  "constraint_singular", "transmission", "mechanism", "assembly", "rtol",
                  "singular_tol", "length", "centre", "reference_point",
                  "actuated_prismatic")
#: The names every assembly answers.
ASSEMBLY_NAMES = ("mechanism", "pose", "output_pose", "q", "q_actuated", "leg_q",
                  "residual", "iterations", "closure_residuals", "info", "per_leg")


def _load(name: str, backend: str | None = None):
    return pkm_pin.load_mechanism(MODELS / name, backend=backend)


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_mechanism_answers_one_assembly_and_one_analysis_type(name):
    """Home assembly and analysis of every shipped file, read by its default backend and
    by the general one, are an Assembly and an Analysis that answer every name; the
    assembly's q is a configuration of the mechanism's tree whose closures close."""
    for backend in (None, "general"):
        mech = _load(name, backend)
        asm, an = mech.home_assembly, mech.analyze()
        assert type(asm) is Assembly
        assert isinstance(an, Analysis)
        assert isinstance(an, LegsAnalysis if asm.per_leg else TreeAnalysis)
        assert asm.per_leg == (mech.backend == "legs")
        for n in ASSEMBLY_NAMES:
            getattr(asm, n)
        for n in ANALYSIS_NAMES:
            getattr(an, n)
        assert asm.q.shape == (mech.model.tree.nq,)
        assert max(asm.closure_residuals.values(), default=0.0) < 1e-8
        assert asm.output_pose.isApprox(asm.pose)
        np.testing.assert_allclose(an.actuation_wrenches, an.A)
        assert an.actuated_twists.shape == (len(mech.actuated_names), 6)
        np.testing.assert_allclose(an.reference_point, an.centre)


@pytest.mark.parametrize("name", ["mechanisms/stewart.toml", "loops/delta_loops.urdf",
                                  "mechanisms/rpr3.toml"])
def test_both_backends_give_the_same_numbers_under_the_same_names(name):
    """The same machine read per leg and over its tree: actuated twists, A and B up to
    the sign of each row, indices, motion indices and the tree's q agree to 1e-9; the
    actuated values agree exactly as named."""
    legs, general = _load(name, "legs"), _load(name, "general")
    la, ga = legs.analyze(), general.analyze()
    np.testing.assert_allclose(la.q, ga.q, atol=1e-9)
    np.testing.assert_allclose(la.actuated_twists, ga.actuated_twists, atol=1e-9)
    for key in ("type_I", "type_II", "condition_A"):
        assert la.indices[key] == pytest.approx(ga.indices[key], rel=1e-9)
    for key in ("forward", "inverse"):
        assert la.motion_indices[key] == pytest.approx(ga.motion_indices[key], rel=1e-9)
    assert (la.dof, la.output_dof, la.motion_type) == (ga.output_dof, ga.output_dof,
                                                        ga.motion_type)
    np.testing.assert_allclose(legs.home_assembly.q_actuated, general.home_assembly.q_actuated,
                               atol=1e-12)


def test_an_assembly_of_either_backend_is_taken_by_the_other():
    """A general assembly given to a per-leg mechanism is read per leg at its q (pose and
    analysis as the per-leg assembly's there); a per-leg assembly given to the general
    backend is read at its tree configuration; Analysis(assembly) picks the backend that
    made the assembly."""
    mech = _load("loops/delta_loops.urdf")
    assert mech.backend == "legs"
    q_a = mech.home_assembly.q_actuated + np.array([0.05, -0.03, 0.02])
    per_leg = mech.forward_kinematics(q_a)
    general = mech.general.forward_kinematics(q_a, mech.general.assembly_at(per_leg.q))
    assert not general.per_leg and general.mechanism is mech.general
    read = mech.assembly_at(general)
    assert read.per_leg
    assert read.pose.isApprox(per_leg.pose, 1e-9)
    np.testing.assert_allclose(read.q_actuated, q_a, atol=1e-9)
    for key, value in mech.analyze(general).indices.items():
        assert value == pytest.approx(mech.analyze(per_leg).indices[key], rel=1e-7)
    back = mech.general.analyze(per_leg)
    np.testing.assert_allclose(back.q, per_leg.q, atol=1e-12)
    assert type(Analysis(per_leg)) is LegsAnalysis
    assert type(Analysis(general)) is TreeAnalysis
    assert Analysis(general).assembly is general
    assert mech.general.analyze(general).assembly is general
    assert Analysis(general).indices["type_II"] == pytest.approx(back.indices["type_II"],
                                                                 rel=1e-7)
    # a guess of the other backend warm-starts the per-leg solver
    again = mech.forward_kinematics(q_a, guess=general)
    assert again.pose.isApprox(per_leg.pose, 1e-9)


def test_general_assembly_and_analysis_pickle_and_keep_their_numbers():
    """Both result types cross a process boundary (pickle) with their numbers."""
    mech = _load("loops/five_bar.urdf")
    asm, an = mech.home_assembly, mech.analyze()
    asm2, an2 = pickle.loads(pickle.dumps(asm)), pickle.loads(pickle.dumps(an))
    assert type(asm2) is Assembly and type(an2) is TreeAnalysis
    np.testing.assert_array_equal(asm2.q, asm.q)
    assert asm2.iterations == asm.iterations
    assert an2.indices == an.indices
    np.testing.assert_array_equal(an2.forward_velocity([0.1, -0.2]),
                                  an.forward_velocity([0.1, -0.2]))


def test_general_joint_twists_are_the_finite_difference_of_the_output_motion():
    """TreeAnalysis.joint_twists: for a random tree velocity v, the output body's twist
    Σ_k∈support J_k v_k (axis-first, world origin) matches the central difference of its
    placement along v."""
    mech = _load("loops/five_bar.urdf")
    an = mech.analyze()
    model, q = mech.model, an.q
    tree = model.tree
    data = tree.createData()
    frame = tree.getFrameId(model.output)
    rng = np.random.default_rng(5)
    v = rng.normal(size=tree.nv)
    support = [j for j in tree.supports[tree.frames[frame].parentJoint] if j > 0]
    cols = [c for j in support for c in range(tree.joints[j].idx_v,
                                              tree.joints[j].idx_v + tree.joints[j].nv)]
    mask = np.zeros(tree.nv)
    mask[cols] = 1.0
    twist = an.joint_twists.T @ (v * mask)
    h = 1e-6

    def placement(dq):
        pin.framesForwardKinematics(tree, data, pin.integrate(tree, q, dq))
        return data.oMf[frame].copy()

    plus, minus = placement(h * v * mask), placement(-h * v * mask)
    # world twist (ω; v_O) of M(t): log of M+ M-⁻¹ over 2h, linear part about the origin
    m = pin.log6(plus * minus.inverse()).vector / (2 * h)
    fd = np.concatenate([m[3:], m[:3]])
    np.testing.assert_allclose(twist, fd, atol=1e-6 * max(1.0, np.abs(fd).max()))


def test_general_analysis_refuses_what_only_legs_have_in_a_sentence():
    """legs and leg_constraint_wrenches of a mechanism read over its tree: a PkmError
    naming the attribute and where the per-leg reading is."""
    an = _load("loops/five_bar.urdf").analyze()
    for name in ("legs", "leg_constraint_wrenches"):
        with pytest.raises(pkm_pin.PkmError, match=f"{name}: .*reads no legs"):
            getattr(an, name)


def test_a_per_leg_assembly_without_its_view_is_refused_by_the_engine():
    """An Assembly with no per-leg view analysed by the per-leg engine directly
    (LegsAnalysis) says how to read it per leg; one made by hand with neither legs nor
    the tree's q says so when its q is asked for."""
    mech = _load("mechanisms/stewart.toml")
    general = mech.general.home_assembly
    with pytest.raises(pkm_pin.InvalidAssembly, match="no per-leg view"):
        LegsAnalysis(Assembly(mech, general.pose, None))
    with pytest.raises(pkm_pin.InvalidAssembly, match="neither leg configurations"):
        Assembly(mech, general.pose).q  # noqa: B018 - the property raises


@pytest.mark.parametrize("name", ["mechanisms/stewart.toml", "loops/delta_loops.urdf"])
def test_joint_rates_are_the_trees_velocity_for_the_actuated_rates_on_both_backends(name):
    """joint_rates(q̇_a) of either analysis: a velocity of the mechanism's tree that keeps
    every closure (J_c v = 0), moves the actuated joints at q̇_a and the output at
    forward_velocity(q̇_a); the per-leg and the general one agree to 1e-9. A general
    analysis refuses passive_rates (per leg) and says what answers instead."""
    legs, general = _load(name, "legs"), _load(name, "general")
    la, ga = legs.analyze(), general.analyze()
    qd = np.random.default_rng(2).normal(size=la.A.shape[0])
    kin = legs.model.kinematics(la.q)
    for an in (la, ga):
        v = an.joint_rates(qd)
        assert v.shape == (legs.model.tree.nv,)
        np.testing.assert_allclose(kin.closure_jacobian @ v, 0.0, atol=1e-9)
        np.testing.assert_allclose(v[list(legs.model.actuated_v)], qd, atol=1e-9)
        np.testing.assert_allclose(kin.output_jacobian @ v, an.forward_velocity(qd),
                                   atol=1e-9)
    np.testing.assert_allclose(la.joint_rates(qd), ga.joint_rates(qd), atol=1e-9)
    with pytest.raises(pkm_pin.PkmError, match="passive_rates: .*joint_rates"):
        ga.passive_rates(la.forward_velocity(qd))


def test_complete_pose_on_a_general_mechanism():
    """complete_pose on mechanisms read over their tree (the five-bar's point, Cassie's
    knee): the given coordinate is met, the pose is the output pose of the assembly that
    inverse kinematics of the partial pose finds, which closes (forward kinematics at its
    actuated values gives the pose back to 1e-9); no coordinate or a
    wrong name is refused in a sentence."""
    for name, key, step in (("loops/five_bar.urdf", "x", 0.01),
                            ("loops/cassie_knee.urdf", "z", 0.01)):
        mech = _load(name)
        assert mech.backend == "general"
        home = mech.home_assembly
        k = "xyz".index(key)
        given = {key: home.pose.translation[k] + step}
        pose = mech.complete_pose(**given)
        assert pose.translation[k] == pytest.approx(given[key], abs=1e-9)
        asm = mech.inverse_kinematics(given)
        assert asm.pose.isApprox(pose, 1e-12)
        assert max(asm.closure_residuals.values()) < 1e-9
        back = mech.forward_kinematics(asm.q_actuated, asm)
        np.testing.assert_allclose(back.pose.translation, pose.translation, atol=1e-9)
    with pytest.raises(pkm_pin.InputError, match="complete_pose takes some of x"):
        mech.complete_pose()
    with pytest.raises(pkm_pin.InputError, match="x, y, z, roll, pitch, yaw"):
        mech.complete_pose(q=1.0)


def test_inverse_kinematics_meets_a_reachable_pose_of_a_lower_mobility_output():
    """Cassie's knee (a body output with 2 DOF): the inverse kinematics of a full pose on
    the output's motion (completed from z) reaches that pose to 1e-9, not another pose
    where the components along the home twist system happen to vanish (6 mm off before);
    a pose off the motion is still reached as far as the output can move (converged,
    closures closed)."""
    mech = _load("loops/cassie_knee.urdf")
    home = mech.home_assembly
    pose = mech.complete_pose(z=home.pose.translation[2] + 0.01)
    asm = mech.inverse_kinematics(pose)
    np.testing.assert_allclose(asm.pose.translation, pose.translation, atol=1e-9)
    np.testing.assert_allclose(asm.pose.rotation, pose.rotation, atol=1e-9)
    off = pin.SE3(pose.rotation, pose.translation + np.array([0.0, 0.002, 0.0]))
    near = mech.inverse_kinematics(off)
    assert max(near.closure_residuals.values()) < 1e-9
    assert abs(near.pose.translation[1] - off.translation[1]) > 1e-3  # y is not a motion


def test_a_general_sweep_solves_a_miss_again_from_its_guess(monkeypatch):
    """Linkage.sweep: a row that does not close from the last good row is solved again
    from the sweep's guess (a per-leg sweep's rule); the row then holds that solution,
    and a row that closes from neither is a failure. The five-bar's point at y = −0.05
    from x = −0.117 to x = −0.076: the second row closes (from the last good row or,
    failing that, from home) and its loops close."""
    from pkm_pin.errors import AssemblyError
    from pkm_pin.linkage import Linkage

    mech = _load("loops/five_bar.urdf")
    home = mech.home_assembly
    A, B = {"x": -0.11724137931034483, "y": -0.05}, {"x": -0.07586206896551724, "y": -0.05}
    real = mech.sweep([A, B], guess=home)
    assert real.ok.all()
    assert max(mech.general.residuals_at(real.q[1]).values()) < 1e-9
    guesses = []
    ik = Linkage.inverse_kinematics

    def missing_from_a(self, pose, guess=None, **kw):
        guesses.append(guess)
        if len(guesses) == 2:  # row B from row A's configuration
            raise AssemblyError("five_bar", 1.0, "made to miss")
        return ik(self, pose, guess, **kw)

    monkeypatch.setattr(Linkage, "inverse_kinematics", missing_from_a)
    r = mech.sweep([A, B], guess=home)
    assert r.ok.all() and len(guesses) == 3
    np.testing.assert_array_equal(guesses[2], home.q)
    monkeypatch.setattr(Linkage, "inverse_kinematics", ik)
    np.testing.assert_allclose(r.q[1], mech.inverse_kinematics(B, home).q, atol=1e-12)
    far = mech.sweep([A, {"x": 1.0, "y": 1.0}], guess=home)
    assert far.ok.tolist() == [True, False] and far.failures[0][0] == 1
