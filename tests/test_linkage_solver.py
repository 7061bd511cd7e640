"""The tree solver (pkm_pin.solve, tree section) on small closed loops built with the
Pinocchio API: closes loops from open starts, pins actuated values, honours masks and
joint limits, and its pose rows match finite differences."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from linkage_models import four_bar, four_bar_q, spherical_rod

from pkm_pin.solve import (
    lm_damping,
    pose_error_rows,
    solve_tree,
    solve_tree_starts,
    tree_limits,
    tree_starts,
)
from pkm_pin.tolerances import CLOSURE_TOL, damping


def test_closes_an_open_loop_with_the_shared_damping():
    """From the open neutral configuration (gap 0.4 m) the four-bar closes to CLOSURE_TOL,
    and the damping is the per-leg solver's."""
    cm = four_bar()
    assert lm_damping(0.3) == damping(0.3)
    sol = solve_tree(cm, four_bar_q(1.0) + 0.2)
    assert sol.converged and sol.closure <= CLOSURE_TOL
    assert np.linalg.norm(cm.closure_residual(sol.q)) <= CLOSURE_TOL


def test_actuated_targets_and_closed_form():
    """With the crank pinned to 0.9 rad the solution is the closed-form four-bar."""
    cm = four_bar()
    sol = solve_tree(cm, four_bar_q(0.8), targets=np.array([0.9]))
    assert sol.converged and sol.actuated <= CLOSURE_TOL
    np.testing.assert_allclose(sol.q, four_bar_q(0.9), atol=1e-10)


def test_mask_keeps_fixed_coordinates():
    """Coordinates outside the mask do not move: the crank stays at its start."""
    cm = four_bar()
    q0 = four_bar_q(0.5)
    q0[1:] += 0.1
    sol = solve_tree(cm, q0, free=np.array([False, True, True]))
    assert sol.converged
    assert sol.q[0] == q0[0]
    np.testing.assert_allclose(sol.q, four_bar_q(0.5), atol=1e-10)


def test_joint_limits_are_respected():
    """A rocker limited below the open branch's angle ends on the crossed branch,
    inside its limits."""
    cm = four_bar()
    tree = pin.Model(cm.tree)
    q_open = four_bar_q(0.9)
    tree.lowerPositionLimit[:] = [-10, -10, -10]
    tree.upperPositionLimit[:] = [10, 10, q_open[2] - 0.5]
    limited = type(cm)(tree, cm.closures, cm.actuated, cm.output, cm.name)
    lo, up = tree_limits(limited)
    starts = tree_starts(limited, q_open, count=8, seed=1)
    assert np.all(starts >= lo) and np.all(starts <= up)
    sol, _ = solve_tree_starts(limited, starts, targets=np.array([0.9]))
    assert sol.converged and sol.q[2] <= up[2]
    assert abs(sol.q[2] - q_open[2]) > 0.5


def test_starts_are_reproducible():
    """The same seed gives the same starts; the first rows are warm, reference, neutral."""
    cm = spherical_rod()
    a = tree_starts(cm, None, count=4, seed=3)
    np.testing.assert_array_equal(a, tree_starts(cm, None, count=4, seed=3))
    np.testing.assert_array_equal(a[0], cm.reference)
    assert not np.array_equal(a[-1], tree_starts(cm, None, count=4, seed=4)[-1])


def test_pose_rows_match_finite_differences():
    """The output pose error's Jacobian equals central differences along each velocity
    coordinate (steps with pin.integrate)."""
    cm = spherical_rod()
    q = pin.integrate(cm.tree, cm.reference, np.array([0.3, 0.2, -0.1, 0.4, 0.7]))
    target = pin.SE3(pin.rpy.rpyToMatrix(0.1, 0.2, 0.3), np.array([0.1, 0.2, 0.3]))
    e, H = pose_error_rows(cm, cm.kinematics(q), target)
    h = 1e-6
    fd = np.array([(pose_error_rows(cm, cm.kinematics(pin.integrate(cm.tree, q, h * dv)),
                                    target)[0]
                    - pose_error_rows(cm, cm.kinematics(pin.integrate(cm.tree, q, -h * dv)),
                                      target)[0]) / (2 * h) for dv in np.eye(cm.nv)]).T
    np.testing.assert_allclose(H, fd, atol=1e-7)
