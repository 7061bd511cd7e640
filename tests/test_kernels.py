"""Tests of pkm_pin.kernels: the compiled product-of-exponentials kinematics of a leg.

The kernel is an accelerator, not a second source of truth: every quantity it computes
is checked here against Pinocchio (tip placement and world Jacobian of every leg of
every shipped mechanism and of UR5 / Panda, ``pin.log3``, ``pin.exp6``, the leg's
Pinocchio closure error at the configurations the solvers return) or against finite
differences of the tip placement taken with ``pin.log6``. Seeded random configurations.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest
from helpers import fd_jacobian, random_platform_twist, shipped_mechanisms

from pkm_pin import InputError, Leg, Mechanism, screws
from pkm_pin.builders import MECHANISMS
from pkm_pin.kernels import (
    AT_PARENT,
    HAS_POST,
    PRISMATIC,
    REVOLUTE,
    chain_kernel,
    log3,
    mechanism_kernel,
    pose_error,
    twist_exp,
)
from pkm_pin.leg import pose_error as leg_pose_error
from pkm_pin.position import _actuated_scales
from pkm_pin.solve import ACTUATED, solve_chain, solve_kernel, track

TRUST = 1e-7  # as pkm_pin.sweep.TRUST

#: Shipped mechanism ``name``, built once for the module.
mech = shipped_mechanisms()


def _base() -> pin.SE3:
    """A non-identity base placement (rotation about a skew axis, offset origin)."""
    return pin.SE3(pin.exp3(np.array([0.3, -0.7, 0.5])), np.array([0.4, -1.2, 0.75]))


def _assert_matches_pinocchio(leg: Leg, kernel, q) -> None:
    """Kernel tip placement and Jacobian equal Pinocchio's at ``q`` to 1e-12."""
    T, J = kernel.kinematics(q)
    M, Jp = leg.kinematics(q)
    np.testing.assert_allclose(T, M.homogeneous, rtol=0, atol=1e-12)
    np.testing.assert_allclose(J, Jp, rtol=0, atol=1e-12)
    assert J.shape == (6, leg.nv)


def _near(leg: Leg, q, rng, size: float) -> np.ndarray:
    """``q`` moved by a uniform perturbation of ``size``, projected onto the limits."""
    return np.clip(q + rng.uniform(-size, size, q.shape), leg.lower, leg.upper)


# ---------------------------------------------------------------- kinematics
_LEGS = [(name, i) for name in sorted(MECHANISMS) for i in range(len(mech(name).legs))]


@pytest.mark.parametrize("name,i", _LEGS, ids=[f"{n}-{i}" for n, i in _LEGS])
def test_kernel_matches_pinocchio_on_mechanism_legs(name, i):
    """Every leg of every shipped mechanism: tip and Jacobian equal Pinocchio's to 1e-12."""
    leg = mech(name).legs[i]
    kernel = chain_kernel(leg)
    assert kernel is not None
    assert kernel.nv == leg.nv and len(kernel.kind) == leg.model.njoints - 1
    rng = np.random.default_rng(100 + i)
    for q in [mech(name).home_assembly.leg_q[i]] + [leg.random_configuration(rng)
                                                    for _ in range(4)]:
        _assert_matches_pinocchio(leg, kernel, q)


@pytest.mark.parametrize("robot", ["ur5", "panda"])
def test_kernel_matches_pinocchio_on_serial_robots(robot, request):
    """UR5 and Panda: tip and Jacobian equal Pinocchio's to 1e-12 at random configurations."""
    leg = request.getfixturevalue(robot)
    kernel = chain_kernel(leg)
    assert kernel is not None and kernel.nv == leg.nv
    np.testing.assert_array_equal(kernel.lower, leg.lower)
    np.testing.assert_array_equal(kernel.upper, leg.upper)
    assert kernel.length == leg.characteristic_length
    rng = np.random.default_rng(7)
    for _ in range(8):
        _assert_matches_pinocchio(leg, kernel, leg.random_configuration(rng))


@pytest.mark.parametrize("which", ["ur5", "panda", "stewart", "delta", "orthoglide_quasi",
                                   "rpr3"])
def test_kernel_with_base_placement(which, request):
    """A non-identity base placement is part of the kernel: tip and Jacobian in the world."""
    leg0 = request.getfixturevalue(which) if which in ("ur5", "panda") else mech(which).legs[0]
    leg = dataclasses.replace(leg0, base=_base())
    kernel = chain_kernel(leg)
    np.testing.assert_array_equal(kernel.base, _base().homogeneous)
    rng = np.random.default_rng(11)
    for _ in range(4):
        q = leg.random_configuration(rng)
        _assert_matches_pinocchio(leg, kernel, q)
        # against the leg's own base, everything is moved rigidly by the change of base
        change = _base() * leg0.base.inverse()
        T0, J0 = chain_kernel(leg0).kinematics(q)
        T, J = kernel.kinematics(q)
        np.testing.assert_allclose(T, change.homogeneous @ T0, rtol=0, atol=1e-12)
        np.testing.assert_allclose(J, screws.adjoint(change) @ J0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("which", ["delta", "stewart", "ur5"])
def test_jacobian_against_finite_differences(which, request):
    """Column k of the kernel Jacobian is the world twist of the tip for a change of q_k
    (central differences of Pinocchio's tip placement, log6 of the displacement)."""
    leg = request.getfixturevalue(which) if which == "ur5" else mech(which).legs[0]
    kernel = chain_kernel(leg)
    rng = np.random.default_rng(5)
    h = 1e-6
    if which == "delta":  # a mimic leg: every column is a parallelogram's combined twist
        assert any(leg.model.joints[j].nv == 0 for j in range(1, leg.model.njoints))
    if which == "stewart":
        assert any(kernel.kind & 1 == PRISMATIC)
    for _ in range(3):
        q = leg.random_configuration(rng)
        _, J = kernel.kinematics(q)
        J_fd = fd_jacobian(leg, q, h)  # axis-first, from pin.log6
        for k in range(leg.nv):
            np.testing.assert_allclose(J[:, k], J_fd[:, k], rtol=0, atol=1e-7)


def test_kernel_kinds_of_the_shipped_legs():
    """Joint kinds read from Pinocchio: rpr3 legs are R-P-R with every joint at its parent
    frame; delta legs have mimic joints whose Jacobian column is their primary's."""
    k = chain_kernel(mech("rpr3").legs[0])
    np.testing.assert_array_equal(k.kind & 1, [REVOLUTE, PRISMATIC, REVOLUTE])
    assert np.all(k.kind & AT_PARENT)
    np.testing.assert_allclose(k.rate, 1.0, rtol=0, atol=1e-12)
    leg = mech("delta").legs[0]
    k = chain_kernel(leg)
    mimic = [j - 1 for j in range(1, leg.model.njoints) if leg.model.joints[j].nv == 0]
    assert mimic
    for j in mimic:
        primary = [i for i in range(len(k.kind))
                   if i not in mimic and k.iv[i] == k.iv[j]]
        assert len(primary) == 1 and k.iq[j] == k.iq[primary[0]]


def _mimic_offset_xml() -> str:
    """R-R(mimic, ratio −0.7, offset 0.3)-P-P(mimic, ratio 2, offset 0.1) chain with
    rotated joint origins and a rotated tip frame."""
    def joint(name, jtype, parent, child, xyz, rpy, axis, mimic=None):
        lim = '<limit lower="-2" upper="2" effort="1" velocity="1"/>'
        mim = (f'<mimic joint="{mimic[0]}" multiplier="{mimic[1]}" offset="{mimic[2]}"/>'
               if mimic else "")
        return (f'<joint name="{name}" type="{jtype}"><parent link="{parent}"/>'
                f'<child link="{child}"/><origin xyz="{xyz}" rpy="{rpy}"/>'
                f'<axis xyz="{axis}"/>{lim}{mim}</joint>')
    joints = [
        joint("J1", "revolute", "l0", "l1", "0.1 0.2 0.3", "0.2 0.1 -0.4", "0 0 1"),
        joint("J2", "revolute", "l1", "l2", "0.5 0 0", "0 0.3 0", "0 0.6 0.8",
              ("J1", -0.7, 0.3)),
        joint("J3", "prismatic", "l2", "l3", "0 0.4 0", "0.5 0 0.2", "1 0 0"),
        joint("J4", "prismatic", "l3", "l4", "0 0 0.2", "0 0 0", "0 0 1", ("J3", 2.0, 0.1)),
        joint("J5", "revolute", "l4", "l5", "0.3 0 0", "0.1 0.2 0.3", "1 0 0"),
    ]
    tip = ('<joint name="T" type="fixed"><parent link="l5"/><child link="tip"/>'
           '<origin xyz="0.2 0.1 0" rpy="0.3 0 0.1"/></joint>')
    links = "".join(f'<link name="l{i}"/>' for i in range(6)) + '<link name="tip"/>'
    return f'<?xml version="1.0"?><robot name="mimics">{links}{"".join(joints)}{tip}</robot>'


def test_kernel_mimic_with_offset_and_rotated_origins():
    """Mimic joints with ratio and offset (revolute and prismatic) and rotated joint
    origins: the kernel equals Pinocchio to 1e-12 and the offsets are post factors."""
    leg = Leg.from_urdf(_mimic_offset_xml(), "tip")
    assert leg.nq == leg.nv == 3 and leg.model.njoints == 6
    kernel = chain_kernel(leg)
    assert kernel is not None
    np.testing.assert_array_equal(kernel.kind & HAS_POST != 0,
                                  [False, True, False, True, False])
    np.testing.assert_allclose(kernel.rate, [1.0, 0.7, 1.0, 2.0, 1.0], rtol=0, atol=1e-12)
    rng = np.random.default_rng(3)
    for _ in range(6):
        _assert_matches_pinocchio(leg, kernel, leg.random_configuration(rng))
    leg_b = dataclasses.replace(leg, base=_base())
    _assert_matches_pinocchio(leg_b, chain_kernel(leg_b), leg.random_configuration(rng))


# ------------------------------------------------------------ no kernel
_CONTINUOUS_XML = """<?xml version="1.0"?>
<robot name="wheel">
  <link name="base"/><link name="arm"/><link name="wheel"/><link name="tip"/>
  <joint name="R" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="C" type="continuous"><parent link="arm"/><child link="wheel"/>
    <origin xyz="0.5 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/></joint>
  <joint name="T" type="fixed"><parent link="wheel"/><child link="tip"/>
    <origin xyz="0 0 0.2" rpy="0 0 0"/></joint>
</robot>
"""


def test_no_kernel_for_continuous_joint():
    """A continuous joint (nq = 2, nv = 1) has no kernel: chain_kernel returns None."""
    leg = Leg.from_urdf(_CONTINUOUS_XML, "tip")
    assert (leg.nq, leg.nv) == (3, 2)
    assert chain_kernel(leg) is None


def _continuous_rpr3() -> Mechanism:
    """The shipped 3-RPR with its platform revolutes X2 written as continuous joints."""
    m = mech("rpr3")
    legs, home_q = [], []
    for leg, q in zip(m.legs, m.home_assembly.leg_q):
        x2 = f'<joint name="{leg.name}2" type="revolute">'
        assert x2 in leg.xml
        xml = leg.xml.replace(x2, f'<joint name="{leg.name}2" type="continuous">')
        legs.append(Leg.from_urdf(xml, leg.tip, leg.actuated, leg.base, leg.name))
        home_q.append(np.r_[q[:2], np.cos(q[2]), np.sin(q[2])])
    return Mechanism(legs, m.anchors, name="3-RPR continuous", home=m.home, home_q=home_q)


def test_mechanism_without_kernel_falls_back_to_euler():
    """A mechanism with continuous joints: no mechanism kernel, method='compiled' raises
    InputError, method='auto' solves the forward problem with the Euler continuation."""
    m = _continuous_rpr3()
    assert all(chain_kernel(leg) is None for leg in m.legs)
    assert mechanism_kernel(m, _actuated_scales(m)) is None
    assert m.kernel is None
    home = m.home_assembly
    assert home.residual <= 1e-12
    pose = screws.exp(np.array([0.0, np.radians(2.0), 0.0, 0.02, 0.0, -0.01])) * home.pose
    target = m.assemble(pose)
    with pytest.raises(InputError):
        m.forward_kinematics(target.q_actuated, method="compiled")
    a = m.forward_kinematics(target.q_actuated, method="auto")
    assert a.info["method"] == "euler"
    np.testing.assert_allclose(a.pose.homogeneous, pose.homogeneous, rtol=0, atol=1e-10)
    # the same mechanism with ordinary revolutes takes the compiled path
    b = mech("rpr3").forward_kinematics(target.q_actuated)
    assert b.info["method"] == "compiled"
    np.testing.assert_allclose(b.pose.homogeneous, pose.homogeneous, rtol=0, atol=1e-10)


def test_sweep_without_kernel_equals_the_compiled_sweep():
    """The sweep of the continuous-joint 3-RPR (no kernel: Leg.solve + the engine)
    gives the DOF, indices and actuated coordinates of the compiled sweep of the
    ordinary 3-RPR at the same poses."""
    m, ref = _continuous_rpr3(), mech("rpr3")
    assert m.kernel is None and ref.kernel is not None
    home = ref.home_assembly.pose
    poses = [screws.exp(np.array([0.0, a, 0.0, x, 0.0, z])) * home
             for a in (-0.03, 0.0, 0.03) for x in (-0.02, 0.02) for z in (-0.01, 0.01)]
    a, b = m.sweep(poses), ref.sweep(poses)
    assert a.ok.all() and b.ok.all()
    np.testing.assert_array_equal(a.dof, b.dof)
    np.testing.assert_array_equal(a.singularity, b.singularity)
    for key in ("type_I", "type_II", "condition", "det"):
        np.testing.assert_allclose(getattr(a, key), getattr(b, key), rtol=1e-8, err_msg=key)
    np.testing.assert_allclose(a.q_actuated, b.q_actuated, atol=1e-9)


# ------------------------------------------------------------------ log3
def _random_axis(rng) -> np.ndarray:
    u = rng.normal(size=3)
    return u / np.linalg.norm(u)


def test_log3_random_rotations():
    """log3 equals pin.log3 to 1e-13 for random rotations of angle up to 3 rad."""
    rng = np.random.default_rng(0)
    out = np.empty(3)
    for _ in range(200):
        w = _random_axis(rng) * rng.uniform(0.0, 3.0)
        R = pin.exp3(w)
        log3(R, out)
        np.testing.assert_allclose(out, pin.log3(R), rtol=0, atol=1e-13)
        np.testing.assert_allclose(out, w, rtol=0, atol=1e-13)


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-9, 1e-5, 0.99e-4, 1.01e-4, 1e-3])
def test_log3_small_angles(angle):
    """log3 of small rotations (both sides of the 1e-4 branch) is the rotation vector to
    1e-15 relative (pin.log3 to 1e-13 relative: it is the less accurate at 1e-3)."""
    rng = np.random.default_rng(1)
    out = np.empty(3)
    for _ in range(20):
        w = _random_axis(rng) * angle
        R = pin.exp3(w)
        log3(R, out)
        np.testing.assert_allclose(out, pin.log3(R), rtol=0, atol=1e-13 * max(angle, 1e-300))
        np.testing.assert_allclose(out, w, rtol=0, atol=1e-15 * max(angle, 1e-300))


def test_log3_half_turn_about_coordinate_axes():
    """A half turn (and π − 1e-9) about ±x, ±y, ±z: log3 gives back the rotation."""
    out = np.empty(3)
    for axis in np.vstack([np.eye(3), -np.eye(3)]):
        for angle in (np.pi, np.pi - 1e-9):
            R = pin.exp3(angle * axis)
            log3(R, out)
            np.testing.assert_allclose(pin.exp3(out), R, rtol=0, atol=2e-9)
            assert abs(np.linalg.norm(out) - angle) <= 2e-9


@pytest.mark.parametrize("gap", [0.0, 1e-12, 1e-9, 1e-6, 5e-5, 1.01e-4, 1e-3, 0.1, 1.0])
def test_log3_near_a_half_turn_about_any_axis(gap):
    """Angles π − gap about general axes: the rotation vector to 1e-14 (at exactly π
    either sign of the axis is right: compared through exp3)."""
    rng = np.random.default_rng(13)
    out = np.empty(3)
    for _ in range(20):
        w = _random_axis(rng) * (np.pi - gap)
        R = pin.exp3(w)
        log3(R, out)
        np.testing.assert_allclose(pin.exp3(out), R, rtol=0, atol=1e-14)
        if gap > 0:
            np.testing.assert_allclose(out, w, rtol=0, atol=1e-14 / min(1.0, 1e6 * gap))


# ------------------------------------------------------------------ pose_error
def test_pose_error_zero_at_target():
    """pose_error is exactly zero when T equals the target (e and the returned norm)."""
    rng = np.random.default_rng(2)
    e = np.full(6, np.nan)
    for _ in range(10):
        T = pin.SE3(pin.exp3(_random_axis(rng) * rng.uniform(0, 3)), rng.normal(size=3))
        M = T.homogeneous
        assert pose_error(M, M.copy(), 0.7, e) == 0.0
        np.testing.assert_array_equal(e, np.zeros(6))


@pytest.mark.parametrize("angle,distance", [(1e-4, 1e-4), (1e-6, 3e-5), (0.0, 1e-4),
                                            (1e-4, 0.0), (0.5, 0.2), (2.5, 1.0)])
def test_pose_error_of_a_displacement(angle, distance):
    """T moved by a world rotation vector w (about its own origin) and a translation d:
    e = (w; d / length) (to 1e-6 relative, to round-off for large rotations), norm |e|."""
    rng = np.random.default_rng(4)
    length = 0.8
    e = np.empty(6)
    for _ in range(10):
        T = pin.SE3(pin.exp3(_random_axis(rng) * rng.uniform(0, 3)), rng.normal(size=3))
        w = _random_axis(rng) * angle
        d = _random_axis(rng) * distance
        target = pin.SE3(pin.exp3(w) @ T.rotation, T.translation + d)
        r = pose_error(T.homogeneous, target.homogeneous, length, e)
        expected = np.r_[w, d / length]
        scale = max(np.linalg.norm(expected), 1e-300)
        np.testing.assert_allclose(e, expected, rtol=0, atol=1e-6 * scale)
        if angle >= 0.5:  # the log3 branch: round-off only
            np.testing.assert_allclose(e[:3], w, rtol=0, atol=1e-13)
        assert r == pytest.approx(np.linalg.norm(e), rel=1e-14)


def test_pose_error_of_a_twist():
    """target = exp(ξ) T for a world twist ξ = (ω; v_O): e is (ω; (exp(ξ) p − p) / length)
    to round-off (2e-15), and (ω; (v_O + ω × p) / length) to first order (|ξ| = 1e-7)."""
    rng = np.random.default_rng(6)
    length = 1.3
    e = np.empty(6)
    for size in (1e-4, 1e-7, 0.3):
        for _ in range(10):
            T = pin.SE3(pin.exp3(_random_axis(rng) * rng.uniform(0, 3)), rng.normal(size=3))
            xi = np.r_[_random_axis(rng), _random_axis(rng)] * size
            D = screws.exp(xi)
            pose_error(T.homogeneous, (D * T).homogeneous, length, e)
            p = T.translation
            exact = np.r_[xi[:3], (D.act(p) - p) / length]
            np.testing.assert_allclose(e, exact, rtol=0, atol=2e-15 + 1e-12 * size)
            if size <= 1e-7:
                first = np.r_[xi[:3], (xi[3:] + np.cross(xi[:3], p)) / length]
                np.testing.assert_allclose(e, first, rtol=0,
                                           atol=1e-6 * np.linalg.norm(first))


# ------------------------------------------------------------------ twist_exp
@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-9, 0.9e-8, 2e-6, 1e-5, 1e-4, 1e-3, 0.1, 1.0,
                                   3.0, 5.0])
def test_twist_exp_matches_the_matrix_exponential(angle):
    """twist_exp equals scipy's expm of the 4×4 twist matrix to 2e-15 (pure translations,
    tiny rotations and the range where (1 − cos θ)/θ² cancels included) and
    screws.exp (pin.exp6, itself ~1e-14 off expm near θ = 1e-3) to 5e-14."""
    from scipy.linalg import expm

    rng = np.random.default_rng(8)
    out = np.empty((4, 4))
    for _ in range(20):
        xi = np.r_[_random_axis(rng) * angle, rng.normal(size=3)]
        twist_exp(xi, out)
        X = np.zeros((4, 4))
        X[:3, :3] = pin.skew(xi[:3])
        X[:3, 3] = xi[3:]
        np.testing.assert_allclose(out, expm(X), rtol=0, atol=2e-15 * max(1.0, angle))
        np.testing.assert_allclose(out, screws.exp(xi).homogeneous, rtol=0, atol=5e-14)
        np.testing.assert_allclose(out[:3, :3].T @ out[:3, :3], np.eye(3), rtol=0, atol=1e-14)


def test_twist_exp_pure_rotation_about_a_line():
    """A rotation twist (u; p × u) turns about the line through p: p is fixed."""
    rng = np.random.default_rng(9)
    out = np.empty((4, 4))
    for _ in range(10):
        u, p = _random_axis(rng), rng.normal(size=3)
        xi = screws.line(p, u) * rng.uniform(0.1, 3.0)
        twist_exp(xi, out)
        np.testing.assert_allclose(out[:3, :3] @ p + out[:3, 3], p, rtol=0, atol=1e-14)


# ------------------------------------------------------------------ Newton
@pytest.mark.parametrize("which", ["ur5", "stewart"])
def test_solve_converges_to_reachable_targets(which, request):
    """solve_chain from 0.05 rad away reaches 1e-12 and Pinocchio's tip at the result
    matches the target to 1e-11; the result is inside the joint limits."""
    leg = request.getfixturevalue(which) if which == "ur5" else mech(which).legs[0]
    kernel = chain_kernel(leg)
    L = leg.characteristic_length
    rng = np.random.default_rng(12)
    base_q = None if which == "ur5" else mech(which).home_assembly.leg_q[0]
    for _ in range(10):
        if base_q is None:
            q_true = leg.random_configuration(rng)
        else:
            q_true = _near(leg, base_q, rng, 0.2)
        target, _ = kernel.kinematics(q_true)
        q0 = _near(leg, q_true, rng, 0.05)
        q0_copy = q0.copy()
        q, res, it = solve_chain(kernel, target, q0)
        assert res <= 1e-12 and 1 <= it <= 20
        np.testing.assert_array_equal(q, np.clip(q, leg.lower, leg.upper))
        np.testing.assert_array_equal(q0, q0_copy)  # the start is not modified
        tip = leg.tip_placement(q)
        assert leg_pose_error(tip, pin.SE3(target), L) < 1e-11


def test_solve_respects_limits_for_unreachable_targets():
    """A target outside a prismatic stroke: the solution stays on the limit, the
    residual is the distance left (> 0), never NaN."""
    leg = mech("rpr3").legs[0]
    kernel = chain_kernel(leg)
    q_home = mech("rpr3").home_assembly.leg_q[0]
    q_far = q_home.copy()
    q_far[1] = leg.upper[1]
    T, _ = kernel.kinematics(q_far)
    target = T.copy()
    target[:3, 3] += 0.5 * (T[:3, 3] - leg.base.translation) / np.linalg.norm(
        T[:3, 3] - leg.base.translation)  # 0.5 m further out along the leg
    q, res, _ = solve_chain(kernel, target, q_home)
    assert np.isfinite(res) and res > 0.1
    assert np.all(q >= leg.lower) and np.all(q <= leg.upper)
    assert q[1] == leg.upper[1]


def test_solve_returns_at_once_from_the_solution():
    """From the exact solution the residual is evaluated and no step is taken."""
    leg = mech("stewart").legs[2]
    kernel = chain_kernel(leg)
    q = mech("stewart").home_assembly.leg_q[2]
    T, _ = kernel.kinematics(q)
    q_out, res, it = solve_chain(kernel, T, q)
    assert it == 0 and res == 0.0
    np.testing.assert_array_equal(q_out, q)


# ------------------------------------------------------------------ track
def _stewart_path(n: int = 50):
    """A smooth path of 50 tip targets of a stewart leg: tips at q0 + s dq."""
    leg = mech("stewart").legs[1]
    kernel = chain_kernel(leg)
    q0 = mech("stewart").home_assembly.leg_q[1]
    dq = np.random.default_rng(13).uniform(-0.3, 0.3, leg.nv)
    path = q0 + np.linspace(0.0, 1.0, n)[:, None] * dq
    assert np.all(path >= leg.lower) and np.all(path <= leg.upper)
    targets = np.stack([kernel.kinematics(q)[0] for q in path])
    return leg, kernel, q0, targets


def _track(kernel, q0, targets, extrapolate, tol=1e-12, trust=TRUST):
    n = targets.shape[0]
    Q = np.full((n, kernel.nv), np.nan)
    res = np.full(n, np.nan)
    misses = track(kernel.chain, targets, q0.astype(float),
                   np.asarray(extrapolate, dtype=np.bool_), tol, 50, trust, Q, res)
    # the count returned: targets neither converged nor trusted
    assert misses == np.count_nonzero(~(res <= tol))
    return Q, res


def test_track_follows_a_smooth_path():
    """track with extrapolation: every residual is ≤ 1e-12 or a trusted −r (r ≤ TRUST),
    Pinocchio closes every leg to 1e-12; without extrapolation the same solutions."""
    leg, kernel, q0, targets = _stewart_path()
    L = leg.characteristic_length
    Q, res = _track(kernel, q0, targets, np.ones(len(targets), bool))
    assert np.all((np.abs(res) <= 1e-12) | ((res < 0) & (-res <= TRUST)))
    for q, T in zip(Q, targets):
        assert leg_pose_error(leg.tip_placement(q), pin.SE3(T), L) < 1e-12
        assert leg.within_limits(q, 0.0)
    Q2, res2 = _track(kernel, q0, targets, np.zeros(len(targets), bool))
    assert np.all((np.abs(res2) <= 1e-12) | ((res2 < 0) & (-res2 <= TRUST)))
    np.testing.assert_allclose(Q, Q2, rtol=0, atol=1e-10)
    # without the trust shortcut every residual is evaluated and non-negative
    Q3, res3 = _track(kernel, q0, targets, np.ones(len(targets), bool), trust=0.0)
    assert np.all((res3 >= 0) & (res3 <= 1e-12))
    np.testing.assert_allclose(Q, Q3, rtol=0, atol=1e-10)


def test_track_survives_an_unreachable_target():
    """A target in the middle of the path that cannot be reached (10 m away) is reported
    with a large residual; the path goes on from the last solution."""
    leg, kernel, q0, targets = _stewart_path(20)
    targets = targets.copy()
    targets[10, :3, 3] += 10.0
    Q, res = _track(kernel, q0, targets, np.ones(len(targets), bool))
    assert res[10] > 1.0 and np.count_nonzero(~(res <= 1e-12)) == 1  # one miss counted
    ok = np.delete(np.arange(len(targets)), 10)
    assert np.all((np.abs(res[ok]) <= 1e-12) | ((res[ok] < 0) & (-res[ok] <= TRUST)))
    for i in ok:
        assert leg_pose_error(leg.tip_placement(Q[i]), pin.SE3(targets[i]),
                              leg.characteristic_length) < 1e-12


# ------------------------------------------------------------------ a whole mechanism
def test_mechanism_kernel_layout():
    """mechanism_kernel flattens the legs' kernels: offsets, actuated indices, anchors."""
    m = mech("delta")
    k = m.kernel
    assert k is not None and len(k.legs) == len(m.legs)
    for i, leg in enumerate(m.legs):
        lk = chain_kernel(leg)
        j0, j1 = k.joints[i], k.joints[i + 1]
        np.testing.assert_array_equal(k.kind[j0:j1], lk.kind)
        np.testing.assert_array_equal(k.parent[j0:j1], lk.parent)
        np.testing.assert_array_equal(k.iv[j0:j1], lk.iv)
        assert k.coords[i + 1] - k.coords[i] == leg.nv
        np.testing.assert_array_equal(k.tips[i], lk.tip)
        np.testing.assert_array_equal(k.anchors[i], m.anchors[i].homogeneous)
    Q = np.concatenate(m.home_assembly.leg_q)
    np.testing.assert_array_equal(Q[k.actuated], m.home_assembly.q_actuated)
    np.testing.assert_array_equal(k.scales, _actuated_scales(m))
    assert k.length == m.characteristic_length


@pytest.mark.parametrize("name", ["stewart", "rpr3"])
def test_compiled_actuated_mask_from_home(name):
    """The compiled closure solver (mask ACTUATED) from home to the actuated coordinates
    of a pose 2 cm / 2° away: closure and actuated error ≤ 1e-12, the target pose to
    1e-10, contracting steps."""
    m = mech(name)
    k = m.kernel
    home = m.home_assembly
    rng = np.random.default_rng(14)
    for _ in range(3):
        xi = random_platform_twist(m, m.home_assembly, rng, np.radians(2.0), 0.02)
        target_pose = screws.exp(xi) * home.pose
        target = m.assemble(target_pose)
        pose = home.pose.homogeneous.copy()
        Q = np.concatenate(home.leg_q).astype(float)
        _, out = solve_kernel(k, ACTUATED, pose, Q, target.q_actuated, tol=1e-13, max_iter=50)
        assert out[0] <= 1e-12 and out[1] <= 1e-12
        assert 1 <= out[2] <= 10
        assert 0.0 < out[3] <= 1.0
        assert out[4] == 1.0
        np.testing.assert_allclose(pose, target_pose.homogeneous, rtol=0, atol=1e-10)
        np.testing.assert_allclose(Q, np.concatenate(target.leg_q), rtol=0, atol=1e-9)
        np.testing.assert_allclose(Q[k.actuated], target.q_actuated, rtol=0, atol=1e-12)
        # Pinocchio closes every leg at the returned pose and configurations
        P = pin.SE3(pose)
        for i, (leg, anchor) in enumerate(zip(m.legs, m.anchors)):
            qi = Q[k.coords[i]:k.coords[i + 1]]
            assert leg_pose_error(leg.tip_placement(qi), P * anchor,
                                  m.characteristic_length) < 1e-11


def test_compiled_actuated_mask_at_the_solution_takes_no_step():
    """From an assembled state with its own actuated coordinates: no iteration, out[2] = 0."""
    m = mech("stewart")
    home = m.home_assembly
    pose = home.pose.homogeneous.copy()
    Q = np.concatenate(home.leg_q).astype(float)
    _, out = solve_kernel(m.kernel, ACTUATED, pose, Q, home.q_actuated.copy(), tol=1e-12,
                          max_iter=50)
    assert out[2] == 0 and out[0] <= 1e-12 and out[1] == 0.0
    np.testing.assert_array_equal(pose, home.pose.homogeneous)
