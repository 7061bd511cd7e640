"""The warm forward-kinematics path's shortcuts (issue 24's speed on PlaCo's 5-bar) give
what the general code gives: same starts, same flags, same solutions, same errors."""

from pathlib import Path

import numpy as np
import pytest

from pkm_pin import InputError, general_kernel, load_mechanism, solve
from pkm_pin.linkage import LinkageAssembly

FIVE_BAR = (Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "planar_2dof"
            / "robot.urdf")


@pytest.fixture(scope="module")
def link():
    return load_mechanism(FIVE_BAR)


def test_unlimited_tree_warm_start_is_a_copy_of_the_guess(link):
    model = link.model
    lo, up = solve.tree_limits(model)
    assert not np.isfinite(lo).any() and not np.isfinite(up).any()  # the shortcut applies
    warm = np.array([0.1, -0.2, 0.3, -0.4])
    first = next(solve.iter_tree_starts(model, warm))
    assert first is not warm and np.array_equal(first, np.clip(warm, lo, up))


def test_representation_flags_without_triples_or_limits_match_the_compiled_pass(link):
    model = link.model
    q = link.assemble(np.zeros(model.nq)).q
    locked, near = general_kernel.representation_flags(model, q)
    k = general_kernel.tree_kernel(model)
    locked_k, near_k = general_kernel.flags_at(
        k, np.zeros((0, 3), np.int64), np.ascontiguousarray(q), float(model.length))
    assert locked.shape == locked_k.shape == (0,) and near is bool(near_k) is False


def test_warm_forward_kinematics_matches_the_pinocchio_driver_to_1e10(link):
    from pkm_pin import tree_kernel
    model = link.model
    home = link.assemble(np.zeros(model.nq))
    targets = home.q_actuated + np.random.default_rng(3).uniform(-0.3, 0.3, (10, 2))
    runs = []
    for enabled in (True, False):
        tree_kernel.ENABLED = enabled
        try:
            prev, out = home, []
            for qa in targets:
                prev = link.forward_kinematics(qa, prev, starts=0, tol=1e-10)
                assert isinstance(prev, LinkageAssembly)
                assert np.allclose(prev.q_actuated, qa, rtol=0, atol=1e-10)
                assert max(prev.closure_residuals.values()) <= 1e-10
                out.append(np.r_[prev.q, prev.output_pose.translation])
            runs.append(np.array(out))
        finally:
            tree_kernel.ENABLED = True
    assert np.abs(runs[0] - runs[1]).max() <= 1e-10


def test_tree_solution_fields_and_equality(link):
    model = link.model
    home = link.assemble(np.zeros(model.nq))
    sol = solve.solve_tree(model, home.q, targets=home.q_actuated + 0.05, tol=1e-10)
    assert sol.converged and sol.iterations >= 1 and sol.residual <= 1e-10
    assert sol.output_placement is not None and sol.closure_norms is not None
    again = solve.TreeSolution(sol.q, sol.residual, sol.closure, sol.actuated, sol.pose,
                               sol.iterations, sol.converged, sol.closure_norms,
                               sol.output_placement)
    assert sol == again and type(sol) is solve.TreeSolution


@pytest.mark.parametrize("bad", [[0.0, np.nan], [np.inf, 0.0], [0.0, 0.0, 0.0], "ab"])
def test_checks_still_refuse_bad_actuated_values(link, bad):
    arr = np.array(bad, dtype=float) if not isinstance(bad, str) else bad
    with pytest.raises(InputError, match="q_actuated"):
        link.forward_kinematics(arr, starts=0)


def test_check_q_returns_a_ready_vector_and_refuses_a_non_finite_one(link):
    model = link.model
    q = np.zeros(model.nq)
    assert model.check_q(q) is q
    assert np.array_equal(model.check_q([0, 0, 0, 0]), q)
    with pytest.raises(InputError, match="finite"):
        model.check_q(np.array([0.0, np.nan, 0.0, 0.0]))
    with pytest.raises(InputError, match="finite"):
        model.check_q(np.array([0.0, 0.0, -np.inf, 0.0]))
    with pytest.raises(InputError, match="4 values"):
        model.check_q(np.zeros(5))
