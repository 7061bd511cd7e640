"""Tests of the hand-written 3-RPR witness (seed 000, section 5) and seed 000 errata.

Seed 000: Michalková & Guldan, see docs/references.md.
"""

from __future__ import annotations

import numpy as np
import pytest

from pkm_pin.formulas import rpr3

L3, L6 = 0.8, 0.7
PLATFORM = np.array([[-0.25, 0.0], [0.05, 0.15], [0.3, -0.05]])  # (x, z) in platform frame


def _random_configuration(rng: np.random.Generator):
    """Random pose well inside the workspace: returns pose, angles, lengths."""
    pose = np.array([rng.uniform(-0.4, 0.4), rng.uniform(0.5, 1.0), rng.uniform(0.6, 1.2)])
    angles, lengths = rpr3.inverse_position(L3, L6, pose, PLATFORM)
    return pose, angles, lengths


def _rp(a, b):
    """Reference reciprocal product, written independently of the module."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a[:3] @ b[3:] + a[3:] @ b[:3]


def test_leg_screws_match_printed_50_51_52():
    """Unit joint screws equal (50)-(52) once the prismatic ones are divided by L1, L4, L7."""
    a, b, c = 0.9, 1.3, 2.1
    L2, L5, L8 = 0.6, 0.75, 0.9
    L1, L4, L7 = 0.3, 0.35, 0.4
    sa, ca, sb, cb, sg, cg = np.sin(a), np.cos(a), np.sin(b), np.cos(b), np.sin(c), np.cos(c)
    printed_a = np.array([[0, 1, 0, 0, 0, 0], [0, 0, 0, L1 * ca, 0, L1 * sa],
                          [0, 1, 0, -L2 * sa, 0, L2 * ca]])
    printed_b = np.array([[0, 1, 0, 0, 0, L3], [0, 0, 0, L4 * cb, 0, L4 * sb],
                          [0, 1, 0, -L5 * sb, 0, L3 + L5 * cb]])
    corrected_c = np.array([[0, 1, 0, 0, 0, L3 + L6], [0, 0, 0, L7 * cg, 0, L7 * sg],
                            [0, 1, 0, -L8 * sg, 0, L3 + L6 + L8 * cg]])
    paper = rpr3.joint_screws_paper(L3, L6, (a, b, c), (L2, L5, L8), (L1, L4, L7))
    np.testing.assert_allclose(paper[0], printed_a, atol=1e-14)
    np.testing.assert_allclose(paper[1], printed_b, atol=1e-14)
    np.testing.assert_allclose(paper[2], corrected_c, atol=1e-14)
    unit = rpr3.joint_screws(L3, L6, (a, b, c), (L2, L5, L8))
    for leg_u, leg_p, scale in zip(unit, paper, (L1, L4, L7)):
        np.testing.assert_allclose(leg_u[1] * scale, leg_p[1], atol=1e-14)
        assert np.linalg.norm(leg_u[1, 3:]) == pytest.approx(1.0, abs=1e-14)
        np.testing.assert_allclose(leg_u[[0, 2]], leg_p[[0, 2]], atol=1e-14)


def test_printed_c2_uses_sin_beta_misprint():
    """Printed $C2 (sin beta) misses C2, so leg C's force is not reciprocal to it."""
    angles, lengths = (0.9, 1.0, 2.8), (0.6, 0.75, 0.9)
    printed = rpr3.joint_screws_paper(L3, L6, angles, lengths, (1, 1, 1), as_printed=True)[2][2]
    fixed = rpr3.joint_screws(L3, L6, angles, lengths)[2][2]
    w_c = rpr3.actuation_wrenches(L3, L6, angles, lengths)[2]
    assert _rp(w_c, fixed) == pytest.approx(0.0, abs=1e-14)
    expected = lengths[2] * np.cos(angles[2]) * (np.sin(angles[2]) - np.sin(angles[1]))
    assert _rp(w_c, printed) == pytest.approx(expected, rel=1e-12)
    assert abs(expected) > 0.1
    c2 = rpr3.platform_pivots(L3, L6, angles, lengths)[2]
    np.testing.assert_allclose(fixed[3:], np.cross(c2, [0, 1, 0]), atol=1e-14)
    assert np.linalg.norm(printed[3:] - np.cross(c2, [0, 1, 0])) > 0.1


def test_constraint_wrenches_54_reciprocal_to_every_joint_screw():
    """(54) is reciprocal to every joint screw of every leg and spans each leg's reciprocal."""
    rng = np.random.default_rng(54)
    W = rpr3.constraint_wrenches()
    for _ in range(20):
        _, angles, lengths = _random_configuration(rng)
        for leg in rpr3.joint_screws(L3, L6, angles, lengths):
            assert np.max(np.abs(rpr3.reciprocal_product(W, leg))) < 1e-14
            assert np.linalg.matrix_rank(leg) == 3
            # reciprocal space of the leg = null space of (leg @ Delta): dimension 3 = span (54)
            delta_leg = np.hstack([leg[:, 3:], leg[:, :3]])
            null = np.linalg.svd(delta_leg)[2][3:]
            assert np.linalg.matrix_rank(np.vstack([null, W]), tol=1e-10) == 3


def test_platform_twists_55_are_the_reciprocal_of_54():
    """(55) is reciprocal to (54) and the mobility (6 - rank of the union) is 3."""
    W = rpr3.constraint_wrenches()
    T = rpr3.platform_twists()
    assert np.max(np.abs(rpr3.reciprocal_product(W, T))) == 0.0
    assert 6 - np.linalg.matrix_rank(W) == 3
    np.testing.assert_array_equal(np.array([0.3, -1.2, 0.7]) @ T, [0, 0.3, 0, -1.2, 0, 0.7])


def test_actuation_wrenches_reciprocal_to_passive_joints():
    """Each actuation wrench annihilates its leg's passive twists and gives B = diag(1, L5, 1)."""
    rng = np.random.default_rng(45)
    for _ in range(20):
        _, angles, lengths = _random_configuration(rng)
        W = rpr3.actuation_wrenches(L3, L6, angles, lengths)
        legs = rpr3.joint_screws(L3, L6, angles, lengths)
        passive = [legs[0][[0, 2]], legs[1][[1, 2]], legs[2][[0, 2]]]
        for w, p in zip(W, passive):
            assert np.max(np.abs([_rp(w, s) for s in p])) < 1e-14
        _, B3 = rpr3.velocity_equation(L3, L6, angles, lengths)
        np.testing.assert_allclose(np.diag(B3), [1.0, lengths[1], 1.0], rtol=1e-13)
        np.testing.assert_allclose(B3 - np.diag(np.diag(B3)), 0.0)


def test_velocity_equation_left_matrix_is_printed_58():
    """The derived left matrix equals (58) as printed, row 2 sign included."""
    rng = np.random.default_rng(58)
    for _ in range(20):
        _, angles, lengths = _random_configuration(rng)
        A3, _ = rpr3.velocity_equation(L3, L6, angles, lengths)
        Ap, Bp = rpr3.velocity_equation_paper(L3, L6, angles, lengths, L1=0.3, L7=0.4)
        np.testing.assert_allclose(A3, Ap, atol=1e-14)
        np.testing.assert_allclose(np.diag(Bp), [0.3, lengths[1], 0.4], rtol=1e-15)


def test_row2_force_orientation_fixes_the_sign_consistently():
    """Flipping leg B's force flips row 2 and B22 together: the printed row-2 sign is right."""
    angles, lengths = (1.0, 1.4, 2.0), (0.7, 0.8, 0.9)
    W = rpr3.actuation_wrenches(L3, L6, angles, lengths)
    b = angles[1]
    np.testing.assert_allclose(W[1], [np.sin(b), 0, -np.cos(b), 0, lengths[1] + L3 * np.cos(b), 0],
                               atol=1e-14)
    r0 = rpr3.joint_screws(L3, L6, angles, lengths)[1][0]
    assert _rp(W[1], r0) == pytest.approx(lengths[1], rel=1e-14)
    assert _rp(-W[1], r0) == pytest.approx(-lengths[1], rel=1e-14)


def test_velocity_equation_matches_finite_differences_of_the_closed_loop():
    """A3 t = B3 qa_dot holds for rates obtained by central differences of the loop geometry."""
    rng = np.random.default_rng(1)
    h = 1e-6
    for _ in range(20):
        pose, angles, lengths = _random_configuration(rng)
        pose_rate = rng.normal(size=3)
        ang_p, len_p = rpr3.inverse_position(L3, L6, pose + h * pose_rate, PLATFORM)
        ang_m, len_m = rpr3.inverse_position(L3, L6, pose - h * pose_rate, PLATFORM)
        dang, dlen = (ang_p - ang_m) / (2 * h), (len_p - len_m) / (2 * h)
        rates = np.array([dlen[0], -dang[1], dlen[2]])  # revolute rate about +y = -d(beta)/dt
        th_dot, x_dot, z_dot = pose_rate
        _, x, z = pose
        t3 = np.array([th_dot, x_dot - th_dot * z, z_dot + th_dot * x])  # v_O = v_P - w x P
        A3, B3 = rpr3.velocity_equation(L3, L6, angles, lengths)
        np.testing.assert_allclose(A3 @ t3, B3 @ rates, atol=1e-7)
        np.testing.assert_allclose(rpr3.forward_velocity(L3, L6, angles, lengths, rates), t3,
                                   atol=1e-6)
        np.testing.assert_allclose(rpr3.inverse_velocity(L3, L6, angles, lengths, t3), rates,
                                   atol=1e-7)
        np.testing.assert_allclose(
            rpr3.inverse_velocity(L3, L6, angles, lengths, t3 @ rpr3.platform_twists()), rates,
            atol=1e-7)
        # the paper's scaled rates satisfy the printed equation
        Ap, Bp = rpr3.velocity_equation_paper(L3, L6, angles, lengths, L1=0.3, L7=0.4)
        paper_rates = rates / np.array([0.3, 1.0, 0.4])
        np.testing.assert_allclose(Ap @ t3, Bp @ paper_rates, atol=1e-7)


def test_l5_in_row2_is_the_length_b0b2():
    """Replacing L5 = |B0B2| by another length in row 2 of (58) breaks the FD check."""
    rng = np.random.default_rng(5)
    pose, angles, lengths = _random_configuration(rng)
    h = 1e-6
    pose_rate = np.array([0.7, 1.0, -0.4])
    ang_p, _ = rpr3.inverse_position(L3, L6, pose + h * pose_rate, PLATFORM)
    ang_m, _ = rpr3.inverse_position(L3, L6, pose - h * pose_rate, PLATFORM)
    w_b0 = -(ang_p[1] - ang_m[1]) / (2 * h)
    t3 = np.array([pose_rate[0], pose_rate[1] - pose_rate[0] * pose[2],
                   pose_rate[2] + pose_rate[0] * pose[1]])
    b = angles[1]

    def row2_residual(L5):
        return (L5 + L3 * np.cos(b)) * t3[0] + np.sin(b) * t3[1] - np.cos(b) * t3[2] - L5 * w_b0

    assert row2_residual(lengths[1]) == pytest.approx(0.0, abs=1e-8)
    assert abs(row2_residual(0.5 * lengths[1])) > 0.05


def test_61_equals_determinant_60_exactly():
    """(61) equals det of (60) with the same sign and no factor, at random configurations."""
    rng = np.random.default_rng(61)
    for _ in range(200):
        angles = rng.uniform(-np.pi, np.pi, size=3)
        lengths = rng.uniform(0.1, 2.0, size=3)
        l3, l6 = rng.uniform(0.1, 2.0, size=2)
        det = rpr3.type2_determinant(l3, l6, angles, lengths)
        expansion = rpr3.singularity_condition_61(l3, l6, lengths[1], angles)
        assert det == pytest.approx(expansion, rel=1e-11, abs=1e-13)


def test_type2_singularity_has_a_platform_twist_with_locked_actuators():
    """Where (61) vanishes, A3 has a null twist and the three actuation forces are dependent."""
    a, b, c = 1.0, 1.5, 2.2
    L5 = -(L6 * np.sin(c) * np.cos(b - a) + L3 * np.sin(a) * np.cos(b - c)) / np.sin(a - c)
    assert L5 > 0
    lengths = (0.7, L5, 0.9)
    assert rpr3.singularity_condition_61(L3, L6, L5, (a, b, c)) == pytest.approx(0.0, abs=1e-14)
    A3, B3 = rpr3.velocity_equation(L3, L6, (a, b, c), lengths)
    sv = np.linalg.svd(A3, compute_uv=False)
    assert sv[-1] < 1e-14 * sv[0]
    assert abs(np.linalg.det(B3)) == pytest.approx(L5, rel=1e-14)  # no type-1 singularity
    W = rpr3.actuation_wrenches(L3, L6, (a, b, c), lengths)
    assert np.linalg.matrix_rank(W, tol=1e-12) == 2


def _printed_section3():
    """Reciprocal systems (26), (29), (32) as printed, with the helical pitch used."""
    h = 0.3
    r26 = np.array([[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0],
                    [0, 0, 0, 0, 1, 0], [1, 0, 0, 0, 0, 1]], float)
    r29 = np.array([[0, 1, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0], [0, 0, 0, 1, 0, 0],
                    [0, 0, 0, 0, 1, 0], [1, 0, 0, 0, 0, 1]], float)
    r32 = np.array([[1, 0, 0, -h, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0],
                    [0, 0, 0, 0, 1, 0], [1, 0, 0, 0, 0, 1]], float)
    return h, r26, r29, r32


def test_r5_misprint_in_26_29_32():
    """Printed $r5 = (1,0,0|0,0,1) fails reciprocity in (29) and (32); (0,0,0|0,0,1) passes."""
    h, r26, r29, r32 = _printed_section3()
    rev, pri, hel = [1, 0, 0, 0, 0, 0], [0, 0, 0, 1, 0, 0], [1, 0, 0, h, 0, 0]
    fixed_r5 = [0, 0, 0, 0, 0, 1]
    assert _rp(r29[4], pri) == 1.0
    assert _rp(r32[4], hel) == pytest.approx(h)
    for twist in (rev, pri, hel):
        assert _rp(fixed_r5, twist) == 0.0
    # (26): the printed r5 happens to be reciprocal to the revolute twist, and spans the same
    # 5-system as the corrected one (it is r1 + the couple), but it is not the "moment about z"
    assert _rp(r26[4], rev) == 0.0
    fixed26 = r26.copy()
    fixed26[4] = fixed_r5
    assert np.linalg.matrix_rank(np.vstack([r26, fixed26])) == 5
    assert np.linalg.norm(r26[4, :3]) == 1.0  # printed r5 has a force part: not a couple
    for sys, twist in ((r29, pri), (r32, hel)):
        fixed = sys.copy()
        fixed[4] = fixed_r5
        assert max(abs(_rp(s, twist)) for s in fixed) < 1e-15
        assert np.linalg.matrix_rank(fixed) == 5


def test_33_first_constrained_twist_disagrees_with_24():
    """(24) on $1^r = (1,0,0|-h,0,0) gives (1,0,0|-1/h,0,0); (33) puts -1/h in the y slot."""
    h = 0.3
    s, s0, hw = np.array([1.0, 0, 0]), np.zeros(3), -h
    from_24 = np.concatenate([s, s0 + s / hw])
    printed = np.array([1.0, 0, 0, 0, -1 / h, 0])
    np.testing.assert_allclose(from_24, [1, 0, 0, -1 / h, 0, 0])
    pitch = lambda x: x[:3] @ x[3:] / (x[:3] @ x[:3])  # noqa: E731
    assert pitch(from_24) == pytest.approx(1 / hw)
    assert pitch(printed) == 0.0
