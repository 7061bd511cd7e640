"""The closure solver (pkm_pin.solve): every mask on the shipped mechanisms, the compiled
and the Python (Pinocchio) drivers agreeing, the residual against a hand computation,
units, limits, the restart recipe and the stopping rules' constants.

Closures are checked against Pinocchio's tip placements (never against the solver's own
evaluation); random inputs are seeded.
"""

from __future__ import annotations

import inspect
import re

import numpy as np
import pinocchio as pin
import pytest
from helpers import shipped_mechanisms

from pkm_pin import newton, screws, solve, tolerances
from pkm_pin.solve import (
    ACTUATED,
    LEGS,
    PLATFORM,
    closure_error,
    solve_closure,
    solve_leg,
    start_configurations,
)

#: Shipped mechanism ``name`` (``scale``), built once for the module.
mech = shipped_mechanisms()

NAMES = ["stewart", "rpr3", "rps3", "delta"]


def hand_residual(tip: pin.SE3, target: pin.SE3, length: float) -> np.ndarray:
    """The residual by hand (numpy and pin.log3): world rotation vector of
    ``R_target R_tipᵀ`` and tip displacement / length."""
    return np.r_[pin.log3(target.rotation @ tip.rotation.T),
                 (target.translation - tip.translation) / length]


def pinocchio_closure(m, pose: pin.SE3, leg_q) -> np.ndarray:
    """Each leg's |residual| from Pinocchio's tip placement, at the leg's length."""
    return np.array([np.linalg.norm(hand_residual(leg.tip_placement(q), pose * a,
                                                  leg.characteristic_length))
                     for leg, a, q in zip(m.legs, m.anchors, leg_q)])


def nearby(m, seed: int = 0, size: float = 0.03):
    """An assembly reached by forward kinematics from home, actuated coordinates moved
    by ``size`` units (curved motions such as the 3-RPS' included)."""
    rng = np.random.default_rng(seed)
    home = m.home_assembly
    qa = home.q_actuated + rng.uniform(-size, size, m.n_actuated) * m.actuated_scales
    return m.forward_kinematics(qa)


def in_limits(m, leg_q) -> bool:
    return all(np.all(q >= leg.lower) and np.all(q <= leg.upper)
               for leg, q in zip(m.legs, leg_q))


# ----------------------------------------------------------------------- masks
@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("name", NAMES)
def test_mask_legs(name, compiled):
    """Mask LEGS: every leg from its home configuration to an assembled pose nearby;
    Pinocchio closes every leg to 1e-12, inside the limits, the platform not moved."""
    m = mech(name)
    target = nearby(m)
    s = solve_closure(m, target.pose, m.home_assembly.leg_q, LEGS, compiled=compiled)
    assert s.closure <= 1e-12 and s.actuated == 0.0 and 1 <= s.iterations <= 10
    assert s.pose.isApprox(target.pose, 0.0)
    assert np.all(pinocchio_closure(m, target.pose, s.leg_q) <= 1e-12)
    np.testing.assert_allclose(s.residuals, pinocchio_closure(m, target.pose, s.leg_q),
                               rtol=0, atol=1e-15)
    assert in_limits(m, s.leg_q)
    for q, qt in zip(s.leg_q, target.leg_q):
        np.testing.assert_allclose(q, qt, atol=1e-9)


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("name", NAMES)
def test_mask_platform(name, compiled):
    """Mask PLATFORM: legs and platform together from home with every joint moved by up
    to 0.01: an assembly (Pinocchio closes every leg to 1e-12) near home."""
    m = mech(name)
    home = m.home_assembly
    rng = np.random.default_rng(1)
    start = [leg.clip(q + rng.uniform(-0.01, 0.01, q.shape)) for leg, q in
             zip(m.legs, home.leg_q)]
    s = solve_closure(m, home.pose, start, PLATFORM, compiled=compiled)
    assert s.closure <= 1e-12 and s.actuated == 0.0
    assert np.all(pinocchio_closure(m, s.pose, s.leg_q) <= 1e-12)
    assert in_limits(m, s.leg_q)
    L = m.characteristic_length
    assert np.linalg.norm(closure_error(s.pose.homogeneous, home.pose.homogeneous, L,
                                        np.empty(6))) < 0.1


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("name", NAMES)
def test_mask_actuated(name, compiled):
    """Mask ACTUATED: from home to the actuated coordinates of an assembly nearby: that
    assembly's pose to 1e-10 and legs to 1e-9, actuated error ≤ 1e-12, contracting
    Newton steps and a positive Schur ratio."""
    m = mech(name)
    target = nearby(m)
    home = m.home_assembly
    s = solve_closure(m, home.pose, home.leg_q, ACTUATED, target.q_actuated, tol=1e-13,
                      compiled=compiled)
    assert s.closure <= 1e-12 and s.actuated <= 1e-12 and 1 <= s.iterations <= 10
    assert s.contracted and 0.0 < s.schur_ratio <= 1.0
    np.testing.assert_allclose(s.pose.homogeneous, target.pose.homogeneous, atol=1e-10)
    for q, qt in zip(s.leg_q, target.leg_q):
        np.testing.assert_allclose(q, qt, atol=1e-9)
    assert np.all(pinocchio_closure(m, s.pose, s.leg_q) <= 1e-12)
    with pytest.raises(ValueError, match="target"):
        solve_closure(m, home.pose, home.leg_q, ACTUATED)


# --------------------------------------------------------- the two drivers agree
@pytest.mark.parametrize("mask", [LEGS, PLATFORM, ACTUATED])
@pytest.mark.parametrize("name", ["stewart", "orthoglide_quasi"])
def test_compiled_and_python_drivers_agree(name, mask):
    """The same problem through the compiled driver (kernels) and the Python driver
    (Pinocchio): the same iterations, poses and configurations to 1e-12 (mask PLATFORM,
    whose solutions form the mechanism's motion, to 1e-10: the two evaluations differ
    by round-off, which moves the step along the motion through the damping, ≥ 1e-10)."""
    m = mech(name)
    home = m.home_assembly
    target = nearby(m, seed=2)
    rng = np.random.default_rng(3)
    start = [leg.clip(q + rng.uniform(-0.02, 0.02, q.shape)) for leg, q in
             zip(m.legs, home.leg_q)]
    pose = target.pose if mask == LEGS else home.pose
    a = solve_closure(m, pose, start, mask, target.q_actuated, compiled=True)
    b = solve_closure(m, pose, start, mask, target.q_actuated, compiled=False)
    assert a.iterations == b.iterations
    assert a.closure <= 1e-12 and b.closure <= 1e-12
    atol = 1e-10 if mask == PLATFORM else 1e-12
    np.testing.assert_allclose(a.pose.homogeneous, b.pose.homogeneous, rtol=0, atol=atol)
    for qa, qb in zip(a.leg_q, b.leg_q):
        np.testing.assert_allclose(qa, qb, rtol=0, atol=atol)
    assert a.contracted == b.contracted
    # the last step's Schur complement: its smallest eigenvalue along the motion (mask
    # PLATFORM) is the damping of a residual at round-off
    assert a.schur_ratio == pytest.approx(b.schur_ratio, rel=1e-5 if mask == PLATFORM else 1e-9)


@pytest.mark.parametrize("which", ["ur5", "stewart"])
def test_leg_drivers_agree(which, request):
    """solve_leg compiled and in Python: the same configuration (to 1e-12) and
    iterations from the same starts, for UR5 from far starts and a stewart leg."""
    leg = request.getfixturevalue("ur5") if which == "ur5" else mech("stewart").legs[1]
    rng = np.random.default_rng(4)
    for _ in range(3):
        target = leg.tip_placement(leg.random_configuration(rng) if which == "ur5" else
                                   leg.clip(mech("stewart").home_assembly.leg_q[1]
                                            + rng.uniform(-0.1, 0.1, leg.nq)))
        starts = start_configurations(leg, None, 2, seed=5)
        a = solve_leg(leg, target, starts, compiled=True)
        b = solve_leg(leg, target, starts, compiled=False)
        assert a.converged == b.converged and a.iterations == b.iterations
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
        assert a.residual == pytest.approx(b.residual, abs=1e-14)


# ------------------------------------------------------------------- residual
def test_residual_against_a_hand_computation():
    """closure_error is the world rotation vector and the displacement / length (to
    1e-12, rotations up to 3 rad), and its norm."""
    rng = np.random.default_rng(6)
    e = np.empty(6)
    for _ in range(20):
        T = pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3))
        W = pin.SE3(pin.exp3(rng.uniform(-1, 1, 3) * rng.uniform(0, 3)) @ T.rotation,
                    rng.normal(size=3))
        length = rng.uniform(0.1, 2.0)
        r = closure_error(T.homogeneous, W.homogeneous, length, e)
        np.testing.assert_allclose(e, hand_residual(T, W, length), rtol=0, atol=1e-12)
        assert r == pytest.approx(np.linalg.norm(e), rel=1e-14)


@pytest.mark.parametrize("compiled", [True, False])
def test_each_leg_is_measured_at_its_own_length(compiled):
    """The mechanism's residuals use each leg's characteristic length (orthoglide_quasi:
    the legs' lengths differ from the mechanism's): with no step allowed, the residuals
    reported are the hand computation at the legs' lengths."""
    m = mech("orthoglide_quasi")
    lengths = [leg.characteristic_length for leg in m.legs]
    assert max(abs(L - m.characteristic_length) for L in lengths) > 1e-3
    home = m.home_assembly
    pose = screws.exp(np.array([0.0, 0.0, 0.0, 0.01, -0.02, 0.015])) * home.pose
    s = solve_closure(m, pose, home.leg_q, PLATFORM, max_iter=0, compiled=compiled)
    assert s.iterations == 0
    hand = [np.linalg.norm(hand_residual(leg.tip_placement(q), pose * a, L))
            for leg, a, q, L in zip(m.legs, m.anchors, home.leg_q, lengths)]
    np.testing.assert_allclose(s.residuals, hand, rtol=1e-12)
    assert s.closure == pytest.approx(max(hand), rel=1e-12)


# ---------------------------------------------------------------------- units
@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("mask", [LEGS, PLATFORM, ACTUATED])
def test_millimetres_take_the_same_steps(mask, compiled):
    """The 6-UPS in millimetres: the same iterations, residuals (to 1e-9 relative),
    configurations (prismatic ×1000) and pose (translation ×1000) as in metres."""
    m, mm = mech("stewart"), mech("stewart", 1000.0)
    target = nearby(m, seed=7)
    home, home_mm = m.home_assembly, mm.home_assembly
    units = [np.where(leg._velocity_units > 1.0, 1000.0, 1.0) for leg in m.legs]
    scale_a = np.where(m.actuated_scales > 1.0, 1000.0, 1.0)
    pose = target.pose if mask == LEGS else home.pose
    pose_mm = pin.SE3(pose.rotation, 1000.0 * pose.translation)
    rng = np.random.default_rng(8)
    start = [leg.clip(q + rng.uniform(-0.02, 0.02, q.shape)) for leg, q in
             zip(m.legs, home.leg_q)]
    a = solve_closure(m, pose, start, mask, target.q_actuated, compiled=compiled)
    b = solve_closure(mm, pose_mm, [q * u for q, u in zip(start, units)], mask,
                      target.q_actuated * scale_a, compiled=compiled)
    np.testing.assert_allclose(home_mm.q_actuated, home.q_actuated * scale_a, rtol=1e-12)
    assert a.iterations == b.iterations and a.closure <= 1e-12 and b.closure <= 1e-12
    for qa, qb, u in zip(a.leg_q, b.leg_q, units):
        np.testing.assert_allclose(qb, qa * u, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(b.pose.translation, 1000.0 * a.pose.translation, atol=1e-7)
    np.testing.assert_allclose(b.pose.rotation, a.pose.rotation, atol=1e-10)


# --------------------------------------------------------------------- limits
@pytest.mark.parametrize("compiled", [True, False])
def test_limits_are_respected(compiled):
    """Targets out of reach: every configuration returned lies inside the joint limits,
    the residual is large and finite, for one leg (a prismatic stroke ends at its upper
    limit) and for the mechanism (platform 5 m too high, masks LEGS and PLATFORM)."""
    m = mech("rpr3")
    leg, q_home = m.legs[0], m.home_assembly.leg_q[0]
    q_far = q_home.copy()
    q_far[1] = leg.upper[1]
    tip = leg.tip_placement(q_far)
    out = tip.translation - leg.base.translation
    target = pin.SE3(tip.rotation, tip.translation + 0.5 * out / np.linalg.norm(out))
    sol = solve_leg(leg, target, q_home, compiled=compiled)
    assert not sol.converged and 0.1 < sol.residual < np.inf
    assert leg.within_limits(sol.q, 0.0) and sol.q[1] == leg.upper[1]
    s = mech("stewart")
    far = pin.SE3(s.home.rotation, s.home.translation + np.array([0.0, 0.0, 5.0]))
    for mask in (LEGS, PLATFORM):
        r = solve_closure(s, far, s.home_assembly.leg_q, mask, compiled=compiled)
        assert in_limits(s, r.leg_q) and np.isfinite(r.closure)
        if mask == LEGS:
            assert r.closure > 0.1


# ------------------------------------------------------------------- restarts
def test_restart_recipe_is_deterministic(ur5):
    """start_configurations: warm start (projected onto the limits), neutral, middle of
    the limits, then the random starts; the same seed gives the same rows, another seed
    other random rows; every row inside the limits."""
    warm = ur5.neutral() + 100.0
    a = start_configurations(ur5, warm, 5, seed=3)
    b = start_configurations(ur5, warm, 5, seed=3)
    c = start_configurations(ur5, None, 5, seed=4)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (8, ur5.nq) and c.shape == (7, ur5.nq)
    np.testing.assert_array_equal(a[0], ur5.clip(warm))
    np.testing.assert_array_equal(a[1], ur5.neutral())
    np.testing.assert_array_equal(a[2], 0.5 * (ur5.lower + ur5.upper))
    np.testing.assert_array_equal(a[1:3], c[:2])
    assert not np.allclose(a[3:], c[2:])
    assert all(ur5.within_limits(q, 0.0) for q in a)
    rng = np.random.default_rng(3)  # the random rows: Leg.random_configuration, seed 3
    np.testing.assert_array_equal(a[3], ur5.random_configuration(rng))


def test_leg_solve_uses_the_restart_recipe(ur5):
    """Leg.solve from a start that fails within ``max_iter`` goes on through the restarts
    (its iterations count every attempt); the compiled and Python drivers give the
    same result."""
    rng = np.random.default_rng(9)
    target = ur5.tip_placement(ur5.random_configuration(rng))
    bad = ur5.neutral()
    a = ur5.solve(target, bad, max_iter=3, restarts=4, compiled=True)
    b = ur5.solve(target, bad, max_iter=3, restarts=4, compiled=False)
    first = solve_leg(ur5, target, bad, max_iter=3, compiled=False)
    assert not first.converged
    assert a.iterations == b.iterations > first.iterations
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)


# -------------------------------------------------------------- shared constants
def test_stopping_rules_are_those_of_the_tolerances():
    """The compiled stopping rules and damping (pkm_pin.newton, shared by the solvers)
    write out the constants of pkm_pin.tolerances (numba's cache does not follow
    tolerances.py)."""
    source = inspect.getsource(solve) + inspect.getsource(newton)
    slow = re.findall(r"r > \(1\.0 - ([0-9.e+-]+)\) \* best", source)
    steps = re.findall(r"return slow >= (\d+), best, slow", source)
    stall = re.findall(r"step < ([0-9.e+-]+) \* \(1\.0 \+ size\)", source)
    assert len(slow) == 1 and len(steps) == 1 and len(stall) >= 2
    assert float(slow[0]) == tolerances.NEWTON_SLOW_RTOL
    assert int(steps[0]) == tolerances.NEWTON_SLOW_STEPS
    assert all(float(x) == tolerances.NEWTON_STALL_RTOL for x in stall)
    for r in (0.0, 1e-6, 0.3, 2.0):
        assert solve.lm_damping(r) == tolerances.damping(r)


def test_start_configurations_of_unbounded_joints_warn_nothing():
    """A leg whose joints have no limits (Gepetto's 5bar_linkage_iso3d, read per leg:
    its continuous joints): the middle of the limits is the neutral configuration there,
    computed without numpy's 'invalid value' warning (inf + −inf), which would reach the
    terminal of `pkm-pin workspace`."""
    import warnings
    from pathlib import Path

    from pkm_pin import load_mechanism

    path = Path(__file__).parent / "data" / "gepetto" / "5bar_linkage_iso3d" / "robot.urdf"
    leg = next(leg for leg in load_mechanism(path).legs
               if not np.isfinite(leg.model.lowerPositionLimit).any())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        starts = start_configurations(leg, count=3, seed=1)
    assert starts.shape == (5, leg.nq) and np.isfinite(starts).all()
    np.testing.assert_array_equal(starts[0], leg.neutral())  # no warm start: neutral,
    np.testing.assert_array_equal(starts[1], leg.neutral())  # then the middle
