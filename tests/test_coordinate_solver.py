"""The compiled pose-coordinate solver (:func:`pkm_pin.solve.solve_coordinates_system`)
against the Python driver (Pinocchio's legs, numpy's SVD): the same completions,
projections and stops, to rounding, on every shipped lower-mobility machine and the
Stewart platform; its coordinate rows against Pinocchio's roll-pitch-yaw."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pkm_pin import load_mechanism
from pkm_pin.position import coordinate_plan
from pkm_pin.solve import (
    CoordinateSystem,
    coordinate_rates,
    coordinate_rows,
    pose_coordinates,
    solve_coordinates,
)

MODELS = Path(__file__).resolve().parents[1] / "models" / "mechanisms"
NAMES = ["rps3", "prs3", "delta", "rpr3", "agile_eye", "orthoglide", "upu3", "stewart"]


@pytest.fixture(scope="module", params=NAMES)
def mech(request):
    return load_mechanism(MODELS / f"{request.param}.toml")


def _same(a, b) -> float:
    """Largest difference of two solutions' poses and leg configurations."""
    return max(float(np.abs(a.pose.homogeneous - b.pose.homogeneous).max()),
               max(float(np.abs(x - y).max()) for x, y in zip(a.leg_q, b.leg_q)))


def test_compiled_completion_is_the_python_drivers(mech):
    """Ten partial poses around home (the mechanism's own independent coordinates, x, y,
    z within ±0.1 L, angles within ±0.15 rad): both drivers reach the same state to
    1e-9, in the same number of steps, with the same closure and coordinate errors."""
    home = mech.home_assembly
    _, rows, _ = coordinate_plan(mech, CoordinateSystem(mech, home.pose, home.leg_q), [])
    rows = np.array(rows)
    rng = np.random.default_rng(7)
    span = np.where(rows < 3, 0.2 * mech.characteristic_length, 0.3)
    for _ in range(10):
        values = pose_coordinates(home.pose)[rows] + (rng.random(rows.size) - 0.5) * span
        a = solve_coordinates(mech, home.pose, home.leg_q, rows, values, compiled=True)
        b = solve_coordinates(mech, home.pose, home.leg_q, rows, values, compiled=False)
        assert a.closure <= 1e-12 and a.coordinates <= 1e-12
        assert _same(a, b) <= 1e-9
        assert a.iterations == b.iterations
        assert a.residuals == pytest.approx(b.residuals, abs=1e-12)
        c = pose_coordinates(a.pose)[rows]
        assert np.abs(c - values).max() <= 1e-9


def test_compiled_projection_is_the_python_drivers(mech):
    """All six coordinates targeted (more than a lower-mobility machine's DOF: the
    nearest pose of its motion, :func:`pkm_pin.position.project_pose`): the same pose
    and the same coordinate error (the distance to the motion) from both drivers."""
    home = mech.home_assembly
    L = mech.characteristic_length
    target = pose_coordinates(home.pose) + np.array([0.01 * L, -0.02 * L, 0.01 * L,
                                                     0.05, -0.03, 0.02])
    a = solve_coordinates(mech, home.pose, home.leg_q, range(6), target, compiled=True)
    b = solve_coordinates(mech, home.pose, home.leg_q, range(6), target, compiled=False)
    assert _same(a, b) <= 1e-9
    assert a.coordinates == pytest.approx(b.coordinates, abs=1e-12)
    assert a.closure <= 1e-12


def test_compiled_stop_against_a_limit_is_the_python_drivers():
    """Beyond a 3-RPS's stroke the step stalls with a leg on its limit: both drivers stop
    at the same state, not closed, with a joint exactly at its bound."""
    mech = load_mechanism(MODELS / "rps3.toml")
    home = mech.home_assembly
    values = [home.pose.translation[2] + 3 * mech.characteristic_length, 0.0, 0.0]
    a = solve_coordinates(mech, home.pose, home.leg_q, [2, 3, 4], values, compiled=True)
    b = solve_coordinates(mech, home.pose, home.leg_q, [2, 3, 4], values, compiled=False)
    assert _same(a, b) <= 1e-9 and a.iterations == b.iterations
    assert a.coordinates == pytest.approx(b.coordinates, rel=1e-9)
    assert a.coordinates > 1e-3
    assert any(leg.at_a_limit(q) for leg, q in zip(mech.legs, a.leg_q))


def test_compiled_closure_rows_are_the_python_drivers(mech):
    """:class:`CoordinateSystem` evaluated by the legs' kernels and by Pinocchio, off
    the closure (the legs moved from home): the same rows, residuals and motions."""
    home = mech.home_assembly
    rng = np.random.default_rng(3)
    leg_q = [q + 0.05 * rng.standard_normal(q.shape) for q in home.leg_q]
    pose = home.pose * pin.exp6(pin.Motion(0.02 * rng.standard_normal(6)))
    a = CoordinateSystem(mech, pose, leg_q, compiled=True)
    b = CoordinateSystem(mech, pose, leg_q, compiled=False)
    assert np.abs(a.A - b.A).max() <= 1e-12
    assert np.abs(a.e - b.e).max() <= 1e-12
    assert a.residuals == pytest.approx(b.residuals, abs=1e-12)
    assert np.abs(a.C - b.C).max() <= 1e-12
    # the same null space (bases may differ by a rotation): projectors agree
    assert np.abs(a.free @ a.free.T - b.free @ b.free.T).max() <= 1e-9


@pytest.mark.parametrize("seed", range(5))
def test_coordinate_rows_are_pinocchios(seed):
    """The compiled coordinates and rates of a random placement (pitch within ±1.4 rad)
    equal :func:`pose_coordinates` (Pinocchio's ``matrixToRpy``) and
    :func:`coordinate_rates` (Pinocchio's inverse RPY Jacobian) to 1e-12; and the
    rates are a finite difference of the coordinates along ξ."""
    rng = np.random.default_rng(seed)
    rpy = rng.uniform([-3.0, -1.4, -3.0], [3.0, 1.4, 3.0])
    M = pin.SE3(pin.rpy.rpyToMatrix(rpy), rng.standard_normal(3))
    L = 0.7
    c, C = np.empty(6), np.empty((6, 6))
    coordinate_rows(M.homogeneous, L, c, C)
    assert c == pytest.approx(pose_coordinates(M), abs=1e-12)
    assert np.abs(C - coordinate_rates(M, L)).max() <= 1e-12
    h = 1e-6
    for k in range(6):
        xi = np.zeros(6)
        xi[k] = h
        moved = pin.exp6(pin.Motion(np.r_[L * xi[3:], xi[:3]]))  # ξ = (ω; v_O / L)
        up = pose_coordinates(moved * M)
        xi[k] = -h
        down = pose_coordinates(pin.exp6(pin.Motion(np.r_[L * xi[3:], xi[:3]])) * M)
        d = (up - down) / (2 * h)
        d[:3] /= L
        assert d == pytest.approx(C[:, k], abs=1e-6)


def test_a_sweep_of_partial_poses_keeps_the_first_plan():
    """A sweep of partial poses makes the coordinates' plan once: its poses are those of
    completions made one by one, each with its own plan, from the same guesses (1e-12),
    and the plan is in each completion's ``info``; a plan for other names is not used."""
    from pkm_pin.position import complete

    mech = load_mechanism(MODELS / "rps3.toml")
    z0 = mech.home.translation[2]
    partial = [dict(z=z0 + dz, roll=r, pitch=0.05) for dz, r in
               [(0.0, 0.0), (0.02, 0.05), (0.04, 0.1), (0.06, 0.15)]]
    swept = mech.sweep(partial)
    previous = None
    for k, coords in enumerate(partial):
        done = complete(mech, coords, previous)
        assert done.info["plan"] == (("z", "roll", "pitch"), (2, 3, 4), (), 3)
        assert np.abs(pose_coordinates(done.pose) - swept.poses[k]).max() <= 1e-12
        previous = done
    # fewer names than the DOF: the plan of (z, roll) holds pitch, not reused for (z,)
    two = complete(mech, dict(z=z0, roll=0.1))
    assert two.info["plan"][2] == (4,)
    one = complete(mech, dict(z=z0 + 0.01), plan=two.info["plan"])
    assert one.info["plan"][0] == ("z",) and len(one.info["held"]) == 2


def test_compiled_completion_takes_strided_values():
    """Target values given as a strided view (every other entry of an array) reach the
    compiled driver as the values they are: the same completion as a plain array's."""
    mech = load_mechanism(MODELS / "rps3.toml")
    home = mech.home_assembly
    c = pose_coordinates(home.pose)
    plain = np.array([c[2] + 0.02, 0.05, -0.03])
    strided = np.zeros(6)
    strided[::2] = plain
    # the plain array first: its call types the machine code that later calls reuse
    b = solve_coordinates(mech, home.pose, home.leg_q, [2, 3, 4], plain, compiled=True)
    a = solve_coordinates(mech, home.pose, home.leg_q, [2, 3, 4], strided[::2], compiled=True)
    assert a.coordinates <= 1e-12 and _same(a, b) == 0.0
