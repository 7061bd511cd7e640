"""The compiled sweep path (pkm_pin.fast_analysis) against the numpy reference path.

The sweep's compiled analysis must take the decisions and give the numbers of
``batch.analyse`` (the algorithm of ``Analysis``); near-singular poses are flagged and
handed to the reference. Also its building blocks (QR with column pivoting, Jacobi
singular values, determinant) against numpy.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from test_analysis import mechanism  # built mechanisms, cached per (name, scale)

from pkm_pin import screws
from pkm_pin.analysis import SINGULAR_TOL
from pkm_pin.batch import homogenise
from pkm_pin.builders.planar import rpr3_type2_pose
from pkm_pin.builders.spatial import upu3_constraint_singular_pose
from pkm_pin.fast_analysis import (
    WINDOW,
    _apply_q,
    _det,
    _inverse,
    _qr_core,
    _rank,
    _square_leg,
)
from pkm_pin.kernels import jacobi_sv
from pkm_pin.screws import RTOL
from pkm_pin.sweep import _evaluate_chunk_pinocchio, evaluate_chunk, pose_array


def path(mech, n=40, size=0.25):
    """Poses along a line of the platform twist system through home (both ways)."""
    an = mech.home_analysis
    L = mech.characteristic_length
    c = np.array([1.0, 0.5, -0.3, 0.2, 0.1, 0.4])[: an.dof] @ an.platform_twists
    c /= max(np.linalg.norm(c[:3]), np.linalg.norm(c[3:]) / L)
    return pose_array([screws.exp(s * size * c) * mech.home for s in np.linspace(-1, 1, n)])


def both_paths(mech, X):
    ref = homogenise(mech.home_analysis.platform_twists, mech.characteristic_length)
    fast = evaluate_chunk(mech, X, ref, RTOL, SINGULAR_TOL)
    slow = _evaluate_chunk_pinocchio(mech, X, ref, RTOL, SINGULAR_TOL, None, 4)
    return fast, slow


def assert_same(fast, slow):
    np.testing.assert_array_equal(fast["ok"], slow["ok"])
    ok = fast["ok"]
    np.testing.assert_array_equal(fast["dof"][ok], slow["dof"][ok])
    for key in ("type_I", "type_II", "det"):
        a, b = fast[key][ok], slow[key][ok]
        np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-11, err_msg=key)
    # condition = σ_max / σ_min: σ_min / σ_max is known to an absolute round-off
    np.testing.assert_allclose(1 / fast["condition"][ok], 1 / slow["condition"][ok],
                               rtol=1e-8, atol=1e-14)
    np.testing.assert_allclose(fast["q_actuated"][ok], slow["q_actuated"][ok], atol=1e-9)


@pytest.mark.parametrize("name", ["rpr3", "rrr3", "stewart", "delta", "upu3", "orthoglide",
                                  "orthoglide_quasi"])
def test_compiled_sweep_equals_reference_path(name):
    """Same assemblies, DOF, indices and carried det as the numpy path, pose by pose."""
    mech = mechanism(name)
    fast, slow = both_paths(mech, path(mech))
    assert fast["ok"].sum() >= 30
    assert fast["reference_path"] == 0  # no pose near a rank threshold on this path
    assert_same(fast, slow)


def test_millimetres_give_the_same_sweep(monkeypatch):
    """The Stewart platform in millimetres: same DOF, indices, det (unit-invariant), and
    the compiled legs converge as in metres (no pose falls back to Mechanism.assemble)."""
    import pkm_pin.sweep as sweep_module

    m, mm = mechanism("stewart"), mechanism("stewart", 1000.0)
    X = path(m, n=12)
    Xmm = X.copy()
    Xmm[:, :3] *= 1000.0
    redone = []
    monkeypatch.setattr(sweep_module, "_assemble_again", lambda *a, **k: redone.append(a))
    a, b = m.sweep(X), mm.sweep(Xmm)
    assert not redone
    np.testing.assert_array_equal(a.dof, b.dof)
    np.testing.assert_array_equal(a.singularity, b.singularity)
    for key in ("type_I", "type_II", "condition", "det"):
        np.testing.assert_allclose(getattr(a, key), getattr(b, key), rtol=1e-7, err_msg=key)


def test_near_constraint_singular_poses_go_to_the_reference_path():
    """3-UPU lowered towards its constraint-singular pose: heights giving constraint
    singular values inside the QR ambiguity window are flagged and analysed by
    batch.analyse; the exactly singular pose (4 DOF) is decided by QR. Every pose
    equals the per-pose Analysis."""
    mech = mechanism("upu3")
    L = mech.characteristic_length
    base = upu3_constraint_singular_pose()
    heights = np.array([0.0, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3, 3e-2]) * L
    X = pose_array([pin.SE3(base.rotation, base.translation + [0, 0, h]) for h in heights])
    fast, slow = both_paths(mech, X)
    assert fast["ok"].all()
    assert 1 <= fast["reference_path"] < len(X)  # the window is used, and only there
    assert_same(fast, slow)
    res = mech.sweep(X)
    for i, x in enumerate(X):
        an = mech.analyze(mech.assemble(x))
        assert res.dof[i] == an.dof
        assert res.singularity[i] == an.singularity
        assert res.type_II[i] == pytest.approx(an.indices["type_II"], rel=1e-8, abs=1e-12)
    assert res.dof[0] == 4 and res.dof[-1] == 3


def test_type_II_pose_of_the_rpr3_in_a_sweep():
    """At the 3-RPR type II pose the compiled type II index vanishes (to round-off) and
    the carried det changes sign across it, as in the reference path."""
    mech = mechanism("rpr3")
    P2 = rpr3_type2_pose()
    X = pose_array([pin.SE3(P2.rotation, P2.translation + [dx, 0, 0])
                    for dx in (-0.02, -0.01, 0.0, 0.01, 0.02)])
    fast, slow = both_paths(mech, X)
    ok = fast["ok"]
    assert ok[2]
    assert fast["type_II"][2] < 1e-9
    assert_same(fast, slow)
    d = fast["det"][ok]
    assert d[0] * d[-1] < 0


# ------------------------------------------------------------------ building blocks
def _qrcp(A, Q, perm, ncol):
    """QR with column pivoting of the 6 × ncol A in place, Q formed from the reflectors."""
    V, betas = np.empty((6, 6)), np.empty(6)
    m = _qr_core(A, 6, ncol, perm, V, betas)
    for c in range(6):
        Q[:, c] = np.eye(6)[c]
        _apply_q(V, betas, m, 6, Q[:, c])


def test_qr_with_column_pivoting_factorises():
    """A P = Q R with Q orthogonal, R upper triangular, |R_jj| non-increasing."""
    rng = np.random.default_rng(0)
    for ncol in (1, 3, 6, 9, 18):
        A = rng.normal(size=(6, ncol))
        R = A.copy()
        Q = np.empty((6, 6))
        perm = np.empty(ncol, np.int64)
        _qrcp(R, Q, perm, ncol)
        np.testing.assert_allclose(Q @ Q.T, np.eye(6), atol=1e-14)
        np.testing.assert_allclose(np.tril(R, -1), 0.0, atol=0.0)
        np.testing.assert_allclose(Q @ R, A[:, perm], atol=1e-13)
        d = np.abs(np.diag(R[:, :min(6, ncol)]))
        assert np.all(d[:-1] >= d[1:] - 1e-14)


def test_qr_early_stop_keeps_the_rank_and_the_complement():
    """With ``stop = rtol / WINDOW`` the QR of 9 constraint columns of rank 3 (plus
    round-off) ends after 3 reflectors; the rank read from it, and the span of
    ``Q e_j`` (j ≥ 3), are those of the full factorisation; a rank-4 matrix whose
    4th singular value sits inside the window still goes the whole way (rank −1)."""
    rng = np.random.default_rng(4)
    for noise in (0.0, 1e-15):
        A = rng.normal(size=(6, 3)) @ rng.normal(size=(3, 9)) + noise * rng.normal(size=(6, 9))
        stops = []
        for stop in (0.0, RTOL / WINDOW):
            R = A.copy()
            V, betas, perm = np.empty((6, 6)), np.empty(6), np.empty(9, np.int64)
            m = _qr_core(R, 6, 9, perm, V, betas, stop)
            N = np.empty((6, 3))
            for j in range(3):
                N[:, j] = np.eye(6)[3 + j]
                _apply_q(V, betas, m, 6, N[:, j])
            stops.append((m, _rank(R, 6, RTOL, False), N))
        (m0, r0, N0), (m1, r1, N1) = stops
        assert (m0, m1, r0, r1) == (6, 3, 3, 3)
        np.testing.assert_allclose(N1.T @ A, 0.0, atol=1e-13)
        np.testing.assert_allclose(N1 @ N1.T, N0 @ N0.T, atol=1e-12)  # same complement
    U, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    V9, _ = np.linalg.qr(rng.normal(size=(9, 9)))
    A = U[:, :4] @ np.diag([2.0, 1.0, 0.5, 1e-9]) @ V9[:4]
    R = A.copy()
    V, betas, perm = np.empty((6, 6)), np.empty(6), np.empty(9, np.int64)
    _qr_core(R, 6, 9, perm, V, betas, RTOL / WINDOW)
    assert _rank(R, 6, RTOL, False) == -1


def test_qr_pivot_near_ties_go_to_the_first_column():
    """Unit columns whose norms differ by round-off: the pivots follow the column order
    (not the round-off), so the complement basis ``Q e_j`` (j ≥ rank) of a smoothly
    moving set of constraints moves smoothly; ``unit=True`` (no norm search at step
    0) gives the same factorisation bit for bit."""
    rng = np.random.default_rng(7)
    B, _ = np.linalg.qr(rng.normal(size=(6, 3)))  # three orthonormal constraints
    O, _ = np.linalg.qr(rng.normal(size=(3, 3)))  # the same span, another basis

    def factorise(t, unit):
        G, _ = np.linalg.qr(np.eye(6) + t * np.triu(np.ones((6, 6)), 1))  # moves with t
        A = np.hstack([G @ B, G @ B @ O])
        A *= 1.0 + 1e-14 * np.arange(6)  # later columns longer by round-off only
        R = A.copy()
        V, betas, perm = np.empty((6, 6)), np.empty(6), np.empty(6, np.int64)
        m = _qr_core(R, 6, 6, perm, V, betas, RTOL / WINDOW, unit)
        N = np.empty((6, 3))
        for j in range(3):
            N[:, j] = np.eye(6)[3 + j]
            _apply_q(V, betas, m, 6, N[:, j])
        return perm.copy(), R, N

    p0, R0, N0 = factorise(0.3, False)
    assert p0[0] == 0  # not column 5, the longest by round-off
    p1, R1, N1 = factorise(0.3, True)
    np.testing.assert_array_equal(p0, p1)
    np.testing.assert_array_equal(R0, R1)
    np.testing.assert_array_equal(N0, N1)
    _, _, N2 = factorise(0.3 + 1e-7, True)
    assert np.abs(N2 - N1).max() < 1e-5  # the basis itself moves by O(dt), not its span only


def test_rank_decision_and_its_ambiguity_window():
    """Rank of matrices with chosen singular values; −1 inside the window."""
    rng = np.random.default_rng(1)
    U, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    V, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    for small, expected in ((0.0, 5), (1e-16, 5), (1e-9, -1), (1e-2, 6)):
        A = U @ np.diag([3, 2, 1, 0.5, 0.2, small]) @ V.T
        R = A.copy()
        Q = np.empty((6, 6))
        perm = np.empty(6, np.int64)
        _qrcp(R, Q, perm, 6)
        assert _rank(R, 6, RTOL, False) == expected
        if expected == 5:  # the last column of Q spans the left null space
            np.testing.assert_allclose(Q[:, 5] @ A, 0.0, atol=1e-13)
    assert WINDOW >= 1e3


def test_inverse_and_the_square_leg_certificate():
    """Gauss–Jordan inverse against numpy; False on an exactly singular matrix; a 6-twist
    leg is certified of full rank at σ_min/σ_max = 1e-3 and handed to QR at 1e-6
    (inside the factor-6 slack of the Frobenius bound below rtol · WINDOW = 1e-5)."""
    rng = np.random.default_rng(3)
    Xi, W = np.empty((6, 6)), np.empty((6, 6))
    for n in (1, 3, 6):
        X = rng.normal(size=(6, 6))
        assert _inverse(X, n, Xi, W)
        np.testing.assert_allclose(Xi[:n, :n], np.linalg.inv(X[:n, :n]), rtol=1e-12,
                                   atol=1e-12)
    S = rng.normal(size=(6, 6))
    S[4] = 0.0
    assert not _inverse(S, 6, Xi, W)
    assert not _square_leg(S, Xi, W, RTOL)
    U, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    V, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    assert RTOL * WINDOW == pytest.approx(1e-5)
    for small, certified in ((1e-3, True), (1e-6, False), (1e-12, False)):
        X = U @ np.diag([1.0, 0.9, 0.8, 0.5, 0.3, small]) @ V.T
        assert _square_leg(X, Xi, W, RTOL) is certified
        if certified:
            np.testing.assert_allclose(Xi @ X, np.eye(6), atol=1e-10)


def test_jacobi_singular_values_and_det():
    """One-sided Jacobi (warm-started or not) and elimination match numpy."""
    rng = np.random.default_rng(2)
    V = np.eye(6)
    W = np.empty((6, 6))
    for m, n in ((6, 6), (6, 3), (3, 3), (5, 2)):
        A = rng.normal(size=(m, n))
        sv = np.empty(6)
        k = jacobi_sv(A, m, n, sv, np.eye(n), W)
        np.testing.assert_allclose(sv[:k], np.linalg.svd(A, compute_uv=False), rtol=1e-13)
    # warm start from a previous basis: same values, V stays orthogonal
    A = rng.normal(size=(6, 6))
    sv = np.empty(6)
    jacobi_sv(A, 6, 6, sv, V, W)
    B = A + 1e-3 * rng.normal(size=(6, 6))
    jacobi_sv(B, 6, 6, sv, V, W)
    np.testing.assert_allclose(sv, np.linalg.svd(B, compute_uv=False), rtol=1e-13)
    np.testing.assert_allclose(V.T @ V, np.eye(6), atol=1e-13)
    # clustered and tiny singular values: round-off accuracy relative to the largest
    U, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    Vr, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    chosen = np.array([1.0, 1.0 + 2e-9, 1.0 + 1e-9, 0.5 + 1e-12, 0.5, 1e-6])
    sv = np.empty(6)
    jacobi_sv(U @ np.diag(chosen) @ Vr.T, 6, 6, sv, np.eye(6), W)
    np.testing.assert_allclose(sv, np.sort(chosen)[::-1], rtol=0, atol=1e-14)
    for n in (1, 3, 6):
        A = rng.normal(size=(n, n))
        assert _det(A, n) == pytest.approx(np.linalg.det(A), rel=1e-12)
    assert _det(np.zeros((3, 3)), 3) == 0.0


def test_closures_pinocchio_does_not_confirm_are_solved_again(monkeypatch):
    """With the kernel allowed to stop after a step from a large residual (TRUST = 1e-2),
    Pinocchio's closure check rejects those poses and Mechanism.assemble solves them
    again: the sweep still equals the reference path."""
    import pkm_pin.sweep as sweep_module

    mech = mechanism("stewart")
    X = path(mech, n=8, size=0.6)  # big steps: large predictor residuals
    monkeypatch.setattr(sweep_module, "TRUST", 1e-2)
    redone = []
    original = sweep_module._assemble_again

    def spy(*args, **kwargs):
        redone.append(args[5])
        return original(*args, **kwargs)

    monkeypatch.setattr(sweep_module, "_assemble_again", spy)
    fast, slow = both_paths(mech, X)
    assert len(redone) >= 1  # the safety net was used
    assert fast["ok"].all()
    assert_same(fast, slow)


@pytest.mark.parametrize("name", ["rpr3", "stewart", "delta", "orthoglide_quasi"])
def test_pinocchio_pass_gives_the_legs_twists_and_closure(name):
    """The sweep's Pinocchio pass returns each leg's axis-first world Jacobian (the
    twists ``Leg.jacobian`` gives, base placement included) as rows, and closure errors
    at round-off; a leg configuration moved off its solution is reported."""
    from pkm_pin.sweep import _pinocchio_pass, pose_matrices

    mech = mechanism(name)
    X = path(mech, n=6)
    poses = pose_matrices(X)
    sols = [mech.assemble(pin.SE3(p)).leg_q for p in poses]
    Qs = [np.array([s[k] for s in sols]) for k in range(len(mech.legs))]
    targets = [poses @ a.homogeneous for a in mech.anchors]
    Qs[0][2] += 1e-3  # pose 2: leg 0 no longer closes
    J, bad = _pinocchio_pass(mech, Qs, targets, np.arange(len(X)))
    np.testing.assert_array_equal(bad, np.arange(len(X)) == 2)
    coords = mech._kernel.coords
    for k, leg in enumerate(mech.legs):
        for i in range(len(X)):
            np.testing.assert_allclose(J[i, coords[k]:coords[k + 1]], leg.jacobian(Qs[k][i]).T,
                                       rtol=0, atol=1e-14)
    some = np.array([1, 2, 5])  # a subset of the poses: their rows, in order
    Js, bads = _pinocchio_pass(mech, Qs, targets, some)
    np.testing.assert_array_equal(Js, J[some])
    np.testing.assert_array_equal(bads, bad[some])
