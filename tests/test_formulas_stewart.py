"""Tests of the hand-written Gough-Stewart / l-coordinate witness (seed 003) and its errata.

Seed 003: Demidov 2025, see docs/references.md.
"""

from __future__ import annotations

import numpy as np
import pytest

from pkm_pin.formulas import stewart


def _random_hexapod(rng: np.random.Generator):
    """A generic hexapod: base radius 1 m, platform radius 0.5 m, height ~1 m, random jitter."""
    ang_b = np.deg2rad([0, 100, 120, 220, 240, 340]) + rng.normal(0, 0.05, 6)
    ang_p = np.deg2rad([50, 70, 170, 190, 290, 310]) + rng.normal(0, 0.05, 6)
    base = np.column_stack([np.cos(ang_b), np.sin(ang_b), rng.normal(0, 0.02, 6)])
    plat = np.column_stack([0.5 * np.cos(ang_p), 0.5 * np.sin(ang_p), 1.0 + rng.normal(0, .02, 6)])
    return base, plat


def _paper_quaternion(R):
    """Seed 003's quaternion formulas exactly as printed (sqrt(trace)/2, a32 - a33)."""
    d0 = np.sqrt(R[0, 0] + R[1, 1] + R[2, 2]) / 2
    return np.array([d0, (R[2, 1] - R[2, 2]) / (4 * d0), (R[0, 2] - R[2, 0]) / (4 * d0),
                     (R[1, 0] - R[0, 1]) / (4 * d0)])


def test_seed003_twist_solves_the_printed_system():
    """dl1 = dl4 = 0.1 gives (0.05, 0.05, 0 | 0.1, 0, 0.05): y0 = 0, not the printed 0.1."""
    phi = stewart.screw_step(stewart.SEED003_LINES, stewart.SEED003_DL)
    np.testing.assert_allclose(phi, [0.05, 0.05, 0.0, 0.1, 0.0, 0.05], atol=1e-15)
    np.testing.assert_allclose(phi, stewart.SEED003_TWIST, atol=1e-15)
    printed = np.array([0.05, 0.05, 0.0, 0.1, 0.1, 0.05])
    residual = stewart._delta(stewart.SEED003_LINES) @ printed - stewart.SEED003_DL
    np.testing.assert_allclose(residual, [0, 0, 0, 0, 0.1, -0.1], atol=1e-15)


def test_seed003_rotation_angle_and_axis():
    """The twist rotates 0.0707 rad about (0.707, 0.707, 0) and moves O by (0.1, 0, 0.05)."""
    w = stewart.SEED003_TWIST[:3]
    assert np.linalg.norm(w) == pytest.approx(0.0707, abs=5e-5)
    np.testing.assert_allclose(w / np.linalg.norm(w), [0.707, 0.707, 0.0], atol=5e-4)
    np.testing.assert_allclose(stewart.SEED003_TWIST[3:], [0.1, 0.0, 0.05], atol=1e-15)


def test_seed003_geometry_is_consistent_with_the_printed_lines():
    """The derived body (unit sphere, l = 1 m) reproduces all six printed Plucker lines."""
    base, plat = stewart.seed003_geometry()
    np.testing.assert_allclose(stewart.leg_lines(base, plat), stewart.SEED003_LINES, atol=1e-15)
    np.testing.assert_allclose(stewart.leg_lengths(base, plat), np.ones(6), atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(plat, axis=1), np.ones(6), atol=1e-15)
    lines = stewart.SEED003_LINES
    np.testing.assert_allclose(np.sum(lines[:, :3] * lines[:, 3:], axis=1), 0.0)  # true lines


def test_seed003_point_displacements_match_the_text():
    """Reduced to A_i the screw moves A1, A4 by (0.1, 0, 0.1) and A2, A3, A5, A6 by (0.1, 0, 0)."""
    _, plat = stewart.seed003_geometry()
    moved = stewart.move_points(plat, stewart.SEED003_TWIST, linear=True) - plat
    expected = np.array([[0.1, 0, 0.1], [0.1, 0, 0], [0.1, 0, 0],
                         [0.1, 0, 0.1], [0.1, 0, 0], [0.1, 0, 0]])
    np.testing.assert_allclose(moved, expected, atol=1e-15)


def test_seed003_one_step_residuals_match_the_text():
    """One linear step leaves residuals 0.0045 m (l1, l4) and 0.005 m (others), ~5 % of it."""
    base, plat = stewart.seed003_geometry()
    moved = stewart.move_points(plat, stewart.SEED003_TWIST, linear=True)
    resid = stewart.leg_lengths(base, moved) - (1.0 + stewart.SEED003_DL)
    np.testing.assert_allclose(resid[[0, 3]], 0.0045, atol=1e-4)
    np.testing.assert_allclose(resid[[1, 2, 4, 5]], 0.005, atol=1e-4)
    assert np.max(resid) / 0.1 == pytest.approx(0.05, abs=0.005)


def test_inverse_jacobian_matches_finite_differences_of_leg_lengths():
    """dl = J t agrees with central differences of leg lengths under exp(+-h t) platform motions."""
    rng = np.random.default_rng(3)
    h = 1e-6
    for _ in range(10):
        base, plat = _random_hexapod(rng)
        t = rng.normal(size=6)
        J = stewart.inverse_jacobian(base, plat)
        lp = stewart.leg_lengths(base, stewart.move_points(plat, h * t))
        lm = stewart.leg_lengths(base, stewart.move_points(plat, -h * t))
        np.testing.assert_allclose(J @ t, (lp - lm) / (2 * h), atol=1e-8)
        lines = stewart.leg_lines(base, plat)
        np.testing.assert_allclose(np.linalg.norm(lines[:, :3], axis=1), 1.0, atol=1e-15)
        np.testing.assert_allclose(lines[:, 3:], np.cross(plat, lines[:, :3]), atol=1e-14)


def test_screw_step_inverts_the_inverse_jacobian():
    """screw_step returns the twist whose leg-rate image is the requested dl."""
    rng = np.random.default_rng(4)
    base, plat = _random_hexapod(rng)
    dl = rng.normal(size=6)
    t = stewart.screw_step(stewart.leg_lines(base, plat), dl)
    np.testing.assert_allclose(stewart.inverse_jacobian(base, plat) @ t, dl, atol=1e-12)


def test_twist_exponential_is_a_screw_motion():
    """exp of a twist is rigid and moves axis points along the axis by pitch*angle."""
    rng = np.random.default_rng(6)
    w = rng.normal(size=3)
    axis_point = rng.normal(size=3)
    pitch = 0.3
    t = np.concatenate([w, np.cross(axis_point, w) + pitch * w])
    g = stewart.twist_exponential(t)
    R = g[:3, :3]
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
    moved = R @ axis_point + g[:3, 3]
    np.testing.assert_allclose(moved - axis_point, pitch * w, atol=1e-13)


def test_continuation_converges_like_euler():
    """Seed 003's continuation error falls about tenfold when N grows tenfold."""
    base, plat = stewart.seed003_geometry()
    target = 1.0 + stewart.SEED003_DL
    errs = []
    for n in (10, 100):
        pts = stewart.forward_position_continuation(base, plat, target, n)
        errs.append(np.max(np.abs(stewart.leg_lengths(base, pts) - target)))
    assert errs[1] < 2e-4
    assert errs[0] / errs[1] == pytest.approx(10.0, rel=0.2)


def test_continuation_refuses_a_singular_start():
    """Legs all through one point (rank-3 lines) raise LinAlgError at the first step."""
    rng = np.random.default_rng(8)
    dirs = rng.normal(size=(6, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    base, plat = -dirs, 0.5 * dirs
    with pytest.raises(np.linalg.LinAlgError):
        stewart.forward_position_continuation(base, plat, np.full(6, 1.6), 5)


def test_motion_by_inertia_gives_up_when_the_determinant_keeps_falling():
    """If the last twist never lifts |det| above eps, motion by inertia ends in LinAlgError."""
    base, plat = stewart.seed003_geometry()
    target = 1.0 + 5.0 * stewart.SEED003_DL  # |det| falls monotonically from 2 to about 0.88
    pts = stewart.forward_position_continuation(base, plat, target, 50, eps=0.5)
    assert np.max(np.abs(stewart.leg_lengths(base, pts) - target)) < 0.01
    with pytest.raises(np.linalg.LinAlgError, match="inertia"):
        stewart.forward_position_continuation(base, plat, target, 50, eps=1.5,
                                              max_inertia_steps=20)


def test_quaternion_formula_corrected_vs_printed():
    """d0 = sqrt(1 + trace)/2, d1 = (a32 - a23)/(4 d0) are right; the printed forms are not."""
    axis = np.array([0.37, -0.711, 0.6])
    axis /= np.linalg.norm(axis)
    angle = np.deg2rad(18.5)
    R = stewart.rodrigues(angle * axis)
    q = stewart.quaternion_from_rotation(R)
    np.testing.assert_allclose(q, np.r_[np.cos(angle / 2), np.sin(angle / 2) * axis], atol=1e-14)
    qp = _paper_quaternion(R)
    assert abs(np.linalg.norm(qp) - 1.0) > 0.05
    assert abs(qp[1] - q[1]) > 0.1


def test_quaternion_near_half_turn_branch():
    """A rotation by nearly pi still yields the right unit quaternion."""
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    angle = np.pi - 1e-9
    q = stewart.quaternion_from_rotation(stewart.rodrigues(angle * axis))
    np.testing.assert_allclose(q, np.r_[np.cos(angle / 2), np.sin(angle / 2) * axis], atol=1e-8)


def test_printed_quaternion_system_is_the_hamilton_product():
    """Delta = Theta Gamma as printed composes rotations: R(Theta Gamma) = R(Theta) R(Gamma)."""
    rng = np.random.default_rng(9)
    R1 = stewart.rodrigues(rng.normal(size=3))
    R2 = stewart.rodrigues(rng.normal(size=3))
    q = stewart.quaternion_multiply(stewart.quaternion_from_rotation(R1),
                                    stewart.quaternion_from_rotation(R2))
    q12 = stewart.quaternion_from_rotation(R1 @ R2)
    assert min(np.linalg.norm(q - q12), np.linalg.norm(q + q12)) < 1e-13
    L, psi = stewart.relative_rotation(R2, R1 @ R2)
    np.testing.assert_allclose(stewart.rodrigues(psi * L), R1, atol=1e-13)


def test_inverse_problem_right_side_moment_rows():
    """The moment of L dPsi about O is dPsi O_c x L; printed rows 5 and 6 are wrong."""
    oc = np.array([0.3, -0.4, 0.7])
    xi, eta, zeta = oc
    L = np.array([0.36, 0.48, 0.8])
    h = 1e-6

    def origin_displacement(psi):
        """Where the body point at the origin goes under a rotation psi about the line (O_c, L)."""
        return stewart.rodrigues(psi * L) @ (-oc) + oc

    rate = (origin_displacement(h) - origin_displacement(-h)) / (2 * h)
    screw = stewart.axis_angle_twist(L, 1.0, oc, np.zeros(3))
    np.testing.assert_allclose(screw[3:], rate, atol=1e-9)
    correct = np.array([eta * L[2] - zeta * L[1], zeta * L[0] - xi * L[2], xi * L[1] - eta * L[0]])
    np.testing.assert_allclose(rate, correct, atol=1e-9)
    printed5 = xi * L[0] - xi * L[2]
    printed6 = zeta * L[1] - eta * L[0]
    assert abs(printed5 - correct[1]) > 0.1
    assert abs(printed6 - correct[2]) > 0.1
