"""The closure model (pkm_pin.model): one tree plus closures, and its agreement with the
per-leg screw reading of the same mechanisms (DESIGN.md, "One velocity picture, two
readings of it").

Numbers asserted for the shipped mechanisms (tree of the legs plus a free-flyer
platform, one weld per leg), at home and at nearby assemblies:

=================  ====  ====  ========  =========  ===  ====
mechanism           nv   rows  mobility  redundant  dof  idle
=================  ====  ====  ========  =========  ===  ====
rpr3, rrr3           15    18         3          6    3     0
stewart (6-UPS)      42    36         6          0    6     0
delta                18    18         3          3    3     0
upu3, rps3, prs3     21    18         3          0    3     0
agile_eye            15    18         3          6    3     0
orthoglide(_quasi)   18    18         3          3    3     0
=================  ====  ====  ========  =========  ===  ====

No mechanism has an idle (internal) motion: at a regular pose every leg's joint twists
are independent (3 planar twists of an RPR/RRR leg; U-P-S: 2 + 1 + 3 = 6 twists that
span the 6 screws, the spin of a leg about its axis is not a joint motion since the U
has 2 rotations; U-P-U, R-P-S and P-R-S: 5; the agile eye's R-R-R: 3 concurrent
rotations; the delta's and the Orthoglide's R-(Pa)-R legs: 4
with each parallelogram one coordinate), so a motion of the tree with the platform at
rest moves no joint. Hence mobility = dof, and redundant = mobility − Grübler count
(the planar ones: their 3 out-of-plane constraints counted by 3 legs; the agile eye:
its 3 translation constraints counted by 3 legs; delta and
Orthoglide: the 3 rotation constraints counted twice over), equal to
``Analysis.redundant_constraints``. With the actuated rates held at zero no motion is
left (the poses are regular).
"""

from __future__ import annotations

import functools
import pickle
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest
from helpers import shipped_mechanisms

import pkm_pin
from pkm_pin import screws
from pkm_pin.builders import MECHANISMS
from pkm_pin.errors import FrameNotFound, InputError, JointNotFound
from pkm_pin.model import (
    PLATFORM,
    Closure,
    ClosureModel,
    TreeFrameNotFound,
    TreeJointNotFound,
    configuration,
)

mechanism = shipped_mechanisms()

#: name: (mobility, redundant closure rows, dof of the platform, idle motions)
EXPECTED = {
    "rpr3": (3, 6, 3, 0),
    "rrr3": (3, 6, 3, 0),
    "stewart": (6, 0, 6, 0),
    "delta": (3, 3, 3, 0),
    "upu3": (3, 0, 3, 0),
    "rps3": (3, 0, 3, 0),
    "prs3": (3, 0, 3, 0),
    "agile_eye": (3, 6, 3, 0),
    "orthoglide": (3, 3, 3, 0),
    "orthoglide_quasi": (3, 3, 3, 0),
}
NAMES = sorted(MECHANISMS)

#: Step of the central differences, and their tolerance relative to the Jacobian's size.
FD_STEP = 1e-6
FD_RTOL = 1e-7


@functools.lru_cache(maxsize=None)
def assemblies(name: str) -> tuple:
    """Home and two nearby assemblies of mechanism ``name`` (forward kinematics from
    home, actuated coordinates moved by ~2 % of their unit)."""
    mech = mechanism(name)
    home = mech.home_assembly
    rng = np.random.default_rng(15)
    out = [home]
    for _ in range(2):
        dq = 0.02 * mech.actuated_scales * rng.normal(size=mech.n_actuated)
        out.append(mech.forward_kinematics(home.q_actuated + dq, home))
    return tuple(out)


def homogenised_projector(T: np.ndarray, length: float) -> np.ndarray:
    """Orthogonal projector (6 × 6) onto the span of the twists ``T`` (rows, world
    origin) in the coordinates ``(ω; v / length)``."""
    H = np.array(T, dtype=float).reshape(-1, 6)
    H[:, 3:] /= length
    if H.shape[0] == 0:
        return np.zeros((6, 6))
    U, sv, _ = np.linalg.svd(H.T, full_matrices=False)
    U = U[:, sv > 1e-9 * sv[0]]
    return U @ U.T


def fd_closure_jacobian(cm: ClosureModel, q: np.ndarray) -> np.ndarray:
    """Central differences of ``closure_residual`` along each velocity coordinate, the
    steps taken with ``pin.integrate``."""
    cols = []
    for k in range(cm.nv):
        dv = np.zeros(cm.nv)
        dv[k] = FD_STEP
        plus = cm.closure_residual(pin.integrate(cm.tree, q, dv))
        minus = cm.closure_residual(pin.integrate(cm.tree, q, -dv))
        cols.append((plus - minus) / (2 * FD_STEP))
    return np.array(cols).T


def output_placement(cm: ClosureModel, q: np.ndarray) -> pin.SE3:
    """World placement of the output frame at ``q`` (plain Pinocchio)."""
    data = cm.tree.createData()
    pin.framesForwardKinematics(cm.tree, data, q)
    return data.oMf[cm.tree.getFrameId(cm.output)].copy()


def fd_output_jacobian(cm: ClosureModel, q: np.ndarray) -> np.ndarray:
    """Central differences of the output placement: column k is
    ``log(M(q + h e_k) M(q − h e_k)⁻¹) / 2h``, axis-first (``screws.log``)."""
    cols = []
    for k in range(cm.nv):
        dv = np.zeros(cm.nv)
        dv[k] = FD_STEP
        plus = output_placement(cm, pin.integrate(cm.tree, q, dv))
        minus = output_placement(cm, pin.integrate(cm.tree, q, -dv))
        cols.append(screws.log(plus * minus.inverse()) / (2 * FD_STEP))
    return np.array(cols).T


def assert_fd_close(J: np.ndarray, fd: np.ndarray) -> None:
    assert J.shape == fd.shape
    np.testing.assert_allclose(J, fd, rtol=0, atol=FD_RTOL * max(1.0, np.abs(fd).max()))


def locked_mobility(cm: ClosureModel, q: np.ndarray) -> int:
    """Dimension of the tree's motions allowed by the closures with every actuated rate
    zero (numpy SVD of ``J_c`` stacked with the actuated rows of the identity, columns
    in :attr:`ClosureModel.velocity_units`)."""
    idx = [cm.tree.joints[cm.tree.getJointId(a)].idx_v for a in cm.actuated]
    H = np.vstack([cm.closure_jacobian(q), np.eye(cm.nv)[idx]]) * cm.velocity_units
    sv = np.linalg.svd(H, compute_uv=False)
    return cm.nv - int(np.sum(sv > 1e-9 * sv[0]))


def moved(mech, M: pin.SE3):
    """``mech`` with every leg base and the home pose moved by the rigid transform ``M``."""
    legs = [replace(leg, base=M * leg.base) for leg in mech.legs]
    return pkm_pin.Mechanism(legs, mech.anchors, name=mech.name, home=M * mech.home,
                             home_q=mech.home_q, description=mech.description)


# ------------------------------------------------------------------------ the tree
@pytest.mark.parametrize("name", NAMES)
def test_tree_of_a_mechanism(name):
    """The tree holds every leg plus a free-flyer platform, one weld per leg to it."""
    mech = mechanism(name)
    cm = mech.closure_model
    assert cm is mech.closure_model and isinstance(cm, ClosureModel)
    assert cm.nq == sum(leg.nq for leg in mech.legs) + 7
    assert cm.nv == sum(leg.nv for leg in mech.legs) + 6
    assert [c.kind for c in cm.closures] == ["weld"] * len(mech.legs)
    assert [c.frame_a for c in cm.closures] == [f"{leg.name}/{leg.tip}" for leg in mech.legs]
    assert {c.frame_b for c in cm.closures} == {PLATFORM} and cm.output == PLATFORM
    assert all(c.placement_b == a for c, a in zip(cm.closures, mech.anchors))
    assert cm.actuated == tuple(mech.actuated_names)
    assert cm.n_rows == 6 * len(mech.legs) and cm.length == mech.characteristic_length
    for leg in mech.legs:  # the legs' own models keep their names
        assert leg.model.existFrame(leg.tip) and not leg.model.existFrame(f"{leg.name}/{leg.tip}")


@pytest.mark.parametrize("name", NAMES)
def test_residual_vanishes_at_assemblies(name):
    """The closure residual of an assembly's configuration is ~0, and not once perturbed."""
    mech = mechanism(name)
    cm = mech.closure_model
    rng = np.random.default_rng(1)
    for assembly in assemblies(name):
        q = configuration(mech, assembly)
        assert np.abs(cm.closure_residual(q)).max() <= 1e-10
        q_off = pin.integrate(cm.tree, q, 1e-3 * rng.normal(size=cm.nv))
        assert np.abs(cm.closure_residual(q_off)).max() > 1e-5


@pytest.mark.parametrize("name", NAMES)
def test_jacobians_match_finite_differences(name):
    """closure_jacobian and output_jacobian equal central differences (pin.integrate
    steps) at an assembly and at a configuration off the closures."""
    mech = mechanism(name)
    cm = mech.closure_model
    q = configuration(mech, assemblies(name)[1])
    q_off = pin.integrate(cm.tree, q, 0.05 * np.random.default_rng(2).normal(size=cm.nv))
    for x in (q, q_off):
        assert_fd_close(cm.closure_jacobian(x), fd_closure_jacobian(cm, x))
        assert_fd_close(cm.output_jacobian(x), fd_output_jacobian(cm, x))


# ------------------------------------------------------------ the two readings agree
@pytest.mark.parametrize("name", NAMES)
def test_output_twists_equal_platform_twists(name):
    """The output twists allowed by the closures span the platform twist system of the
    per-leg screw analysis; mobility, redundancy and idle motions are the numbers of the
    module docstring."""
    mech = mechanism(name)
    cm = mech.closure_model
    mobility, redundant, dof, idle = EXPECTED[name]
    L = mech.characteristic_length
    for assembly in assemblies(name):
        q = configuration(mech, assembly)
        an = mech.analyze(assembly)
        T = cm.output_twists(q)
        assert (cm.mobility(q), cm.redundant_constraints(q), an.dof, len(T)) == (
            mobility, redundant, dof, dof)
        assert cm.mobility(q) - len(T) == idle
        assert locked_mobility(cm, q) == 0  # regular poses: locked actuators, rigid
        assert redundant == an.redundant_constraints
        assert mobility == mech.grubler + redundant  # Grübler–Kutzbach, corrected
        np.testing.assert_allclose(homogenised_projector(T, L),
                                   homogenised_projector(an.platform_twists, L), atol=1e-8)
        H = T.copy()
        H[:, 3:] /= L
        np.testing.assert_allclose(H @ H.T, np.eye(len(T)), atol=1e-12)


def _without_length(mech) -> bool:
    """Whether no leg has a length (every joint and tip frame at its leg's base, no
    prismatic joint: the agile eye written with its frames at the centre), so that the
    mechanism's only length, where its centre is, says nothing of its size."""
    return all(np.allclose([p.translation for p in leg.model.jointPlacements], 0.0)
               and not np.any(leg.model.frames[leg.tip_id].placement.translation)
               and not leg._prismatic_joints for leg in mech.legs)


@pytest.mark.parametrize("name", NAMES)
def test_unit_invariance(name):
    """The mechanism in millimetres has the same dimensionless closure Jacobian, the
    same mobility and redundancy, and the same homogenised output span about the
    platform's origin; its unit of
    length is 1000 times larger (the same fallback 1 for a mechanism without length)."""
    mech, mm = mechanism(name), mechanism(name, 1000.0)
    if _without_length(mech):
        # nothing to scale: the unit of length is the fallback 1 in either model
        assert mm.characteristic_length == mech.characteristic_length == 1.0
    else:
        assert mm.characteristic_length == pytest.approx(1000 * mech.characteristic_length)
    cm, cm_mm = mech.closure_model, mm.closure_model
    for assembly in assemblies(name)[:2]:
        pose = pin.SE3(assembly.pose.rotation, 1000.0 * assembly.pose.translation)
        q, q_mm = configuration(mech, assembly), configuration(mm, mm.assemble(pose))
        np.testing.assert_allclose(cm_mm.closure_jacobian(q_mm) * cm_mm.velocity_units,
                                   cm.closure_jacobian(q) * cm.velocity_units, atol=1e-8)
        assert cm_mm.mobility(q_mm) == cm.mobility(q)
        assert cm_mm.redundant_constraints(q_mm) == cm.redundant_constraints(q)
        # spans about the platform's origin (the world origin is no point of the mechanism)
        about, about_mm = (pin.SE3(np.eye(3), -p.translation) for p in (assembly.pose, pose))
        np.testing.assert_allclose(
            homogenised_projector(screws.transform(cm_mm.output_twists(q_mm), about_mm),
                                  mm.characteristic_length),
            homogenised_projector(screws.transform(cm.output_twists(q), about),
                                  mech.characteristic_length), atol=1e-8)


@pytest.mark.parametrize("name", NAMES)
def test_frame_invariance(name):
    """Moving every leg base and the home pose by one rigid transform (100 m away, turned)
    leaves the closure Jacobian, mobility and redundancy unchanged and moves the output
    span with the mechanism."""
    mech = mechanism(name)
    M = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.5, 1.1), np.array([100.0, -40.0, 25.0]))
    far = moved(mech, M)
    cm, cm_far = mech.closure_model, far.closure_model
    for assembly in assemblies(name)[:2]:
        q = configuration(mech, assembly)
        q_far = configuration(far, far.assemble(M * assembly.pose))
        np.testing.assert_allclose(cm_far.closure_jacobian(q_far), cm.closure_jacobian(q),
                                   atol=1e-8)
        assert cm_far.mobility(q_far) == cm.mobility(q)
        assert cm_far.redundant_constraints(q_far) == cm.redundant_constraints(q)
        L = mech.characteristic_length
        np.testing.assert_allclose(
            homogenised_projector(cm_far.output_twists(q_far), L),
            homogenised_projector(screws.transform(cm.output_twists(q), M), L), atol=1e-7)


# ------------------------------------------------------------- other closure kinds
def constraint_frames(seed: int) -> tuple[pin.SE3, pin.SE3]:
    """A random placement and the same frame turned about its z axis."""
    rng = np.random.default_rng(seed)
    P = pin.SE3(pin.rpy.rpyToMatrix(*rng.uniform(-1, 1, 3)), rng.uniform(-0.3, 0.3, 3))
    return P, P * pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, 0.7), np.zeros(3))


@pytest.mark.parametrize("kind", ["weld", "point", "revolute"])
def test_closure_kinds_on_a_welded_mechanism(kind):
    """Point and revolute closures between frames a weld keeps together vanish where
    their definition says (same point; same point and z axis), and every kind's Jacobian
    matches finite differences."""
    mech = mechanism("stewart")
    welds = mech.closure_model
    P, P_turned = constraint_frames(3)
    closures = tuple(Closure(kind, c.frame_a, c.frame_b, P, c.placement_b * P_turned, c.name)
                     for c in welds.closures)
    cm = ClosureModel(welds.tree, closures, welds.actuated, PLATFORM, "stewart",
                      welds.length)
    assert cm.n_rows == 6 * {"weld": 6, "point": 3, "revolute": 5}[kind]
    q = configuration(mech, assemblies("stewart")[1])
    r = np.abs(cm.closure_residual(q)).max()
    assert (r <= 1e-10) == (kind != "weld")
    q_off = pin.integrate(cm.tree, q, 0.05 * np.random.default_rng(4).normal(size=cm.nv))
    for x in (q, q_off):
        assert_fd_close(cm.closure_jacobian(x), fd_closure_jacobian(cm, x))


def five_bar(kind: str, spin: bool = False) -> ClosureModel:
    """A planar five-bar (xy plane): two R-R branches from (0, 0) and (1.5, 0) with unit
    links, their ends joined by a ``kind`` closure; output: the end of branch A.
    ``spin``: an extra revolute at that end that carries nothing (an idle motion)."""
    tree = pin.Model()
    for branch, x in (("A", 0.0), ("B", 1.5)):
        j1 = tree.addJoint(0, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([x, 0.0, 0.0])),
                           f"{branch}1")
        j2 = tree.addJoint(j1, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([1.0, 0, 0])),
                           f"{branch}2")
        tree.addBodyFrame(f"{branch}_end", j2, pin.SE3(np.eye(3), np.array([1.0, 0, 0])),
                          tree.addJointFrame(j2))
        if spin and branch == "A":
            tree.addJoint(j2, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([1.0, 0, 0])),
                          "spin")
    return ClosureModel(tree, (Closure(kind, "A_end", "B_end", name="loop"),), ("A1", "B1"),
                        "A_end", "five-bar")


def assembled(cm: ClosureModel, q: np.ndarray) -> np.ndarray:
    """Gauss–Newton on the closure residual (least-norm steps) from ``q``."""
    for _ in range(30):
        r = cm.closure_residual(q)
        if np.abs(r).max() <= 1e-13:
            break
        q = pin.integrate(cm.tree, q, -np.linalg.pinv(cm.closure_jacobian(q)) @ r)
    return q


@pytest.mark.parametrize("kind, mobility, redundant",
                         [("point", 2, 1), ("revolute", 2, 3), ("weld", 1, 3)])
@pytest.mark.parametrize("spin", [False, True])
def test_five_bar(kind, mobility, redundant, spin):
    """A general linkage (two branches, one closure): a point or revolute closure is a
    pin joint in the plane (2 independent rows, mobility 2), a weld also fixes the
    relative angle (3 rows, mobility 1); the other rows are redundant; an idle spin joint
    adds one to the mobility and nothing to the planar output twists."""
    cm = five_bar(kind, spin)
    q0 = np.array([np.pi / 2, -np.pi / 4] + [0.3] * spin + [np.pi / 2, np.pi / 4])
    q = assembled(cm, q0)
    assert np.abs(cm.closure_residual(q)).max() <= 1e-10
    assert_fd_close(cm.closure_jacobian(q), fd_closure_jacobian(cm, q))
    assert_fd_close(cm.output_jacobian(q), fd_output_jacobian(cm, q))
    assert cm.mobility(q) == mobility + spin
    assert cm.redundant_constraints(q) == redundant
    T = cm.output_twists(q)
    assert len(T) == mobility  # the spin is idle: it does not move the output
    np.testing.assert_allclose(T[:, [0, 1, 5]], 0.0, atol=1e-12)  # (0, 0, ω_z; v_x, v_y, 0)


# --------------------------------------------------------------------- the object
def test_pickle_and_threads():
    """A closure model pickles with its mechanism, and threads sharing it get the
    serial results (every call makes its own Pinocchio data)."""
    mech = mechanism("stewart")
    cm = mech.closure_model
    qs = [configuration(mech, a) for a in assemblies("stewart")] * 3
    serial = [cm.output_twists(q) for q in qs]
    with ThreadPoolExecutor(2) as pool:
        threaded = list(pool.map(cm.output_twists, qs))
    for a, b in zip(serial, threaded):
        np.testing.assert_array_equal(a, b)
    copy = pickle.loads(pickle.dumps(mech)).closure_model
    np.testing.assert_array_equal(copy.closure_jacobian(qs[1]), cm.closure_jacobian(qs[1]))
    assert not copy.velocity_units.flags.writeable
    with pytest.raises(AttributeError):
        cm.output = "elsewhere"


def test_tree_is_a_private_copy():
    """Changing the model a closure model was made from does not change the model."""
    cm = five_bar("point")
    tree = pin.Model(cm.tree)
    copy = ClosureModel(tree, cm.closures, cm.actuated, cm.output)
    tree.jointPlacements[2] = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.0]))
    q = np.array([0.1, 0.2, 0.3, 0.4])
    np.testing.assert_array_equal(copy.closure_residual(q), cm.closure_residual(q))


def test_bad_input():
    """Wrong closure kinds, frame and joint names, sizes and lengths raise InputError
    subclasses that say what is wrong."""
    mech = mechanism("rpr3")
    cm = mech.closure_model
    with pytest.raises(InputError, match="unknown kind 'ball'.*'point', 'revolute', 'weld'"):
        Closure("ball", "A/tip", PLATFORM)
    with pytest.raises(InputError, match="placement_b must be a finite pinocchio.SE3"):
        Closure("weld", "A/tip", PLATFORM, pin.SE3.Identity(), np.eye(4))
    with pytest.raises(TreeFrameNotFound, match="frame 'A/nope' is not .*'A/tip'") as e:
        ClosureModel(cm.tree, (Closure("weld", "A/nope", PLATFORM),), (), PLATFORM)
    assert isinstance(e.value, InputError) and isinstance(e.value, FrameNotFound)
    with pytest.raises(TreeFrameNotFound, match="frame 'tool'"):
        ClosureModel(cm.tree, cm.closures, (), "tool")
    with pytest.raises(TreeJointNotFound, match="joint 'A1' is not .*'A/A1'") as e:
        ClosureModel(cm.tree, cm.closures, ("A1",), PLATFORM)
    assert isinstance(e.value, InputError) and isinstance(e.value, JointNotFound)
    with pytest.raises(InputError, match="length must be a positive number"):
        ClosureModel(cm.tree, cm.closures, (), PLATFORM, length=-1.0)
    with pytest.raises(InputError, match="closures must be Closure objects"):
        ClosureModel(cm.tree, ("weld",), (), PLATFORM)
    for method in (cm.closure_residual, cm.closure_jacobian, cm.output_jacobian,
                   cm.mobility, cm.output_twists):
        with pytest.raises(InputError, match=f"must have {cm.nq} values"):
            method(np.zeros(cm.nq - 1))
    other = mechanism("rrr3").home_assembly
    with pytest.raises(InputError):
        configuration(mechanism("stewart"), other)


def test_origins_are_pinocchios_forward_kinematics():
    """ClosureModel.origins: every joint's world origin and the output placement equal
    a fresh Data's framesForwardKinematics, to the last bit, at two configurations in
    turn (the working data is reused)."""
    from pathlib import Path

    from pkm_pin import load_mechanism

    loops = Path(__file__).resolve().parents[1] / "models" / "loops"
    model = load_mechanism(loops / "cassie_knee.urdf", backend="general").model
    rng = np.random.default_rng(3)
    for _ in range(2):
        q = rng.uniform(-1.0, 1.0, model.nq)
        data = model.tree.createData()
        pin.framesForwardKinematics(model.tree, data, q)
        P, oMo = model.origins(q)
        assert P.shape == (model.tree.njoints - 1, 3)
        assert np.array_equal(P, np.array([data.oMi[j].translation
                                           for j in range(1, model.tree.njoints)]))
        assert np.array_equal(oMo.homogeneous,
                              data.oMf[model.tree.getFrameId(model.output)].homogeneous)
