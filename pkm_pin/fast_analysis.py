"""The screw analysis of :mod:`pkm_pin.batch` for many poses, in compiled code.

Same quantities, same conventions and the same decisions as :func:`pkm_pin.batch.analyse`
(axis-first screws about the world origin; moments divided by the characteristic length
``L``; rows normalised; rank decisions ``σ > rtol · σ_max``), computed pose by pose in
numba with cheaper factorisations:

* a leg with six joint twists by the inverse of ``(T_h Δ)ᵀ`` when a bound on its
  condition certifies the rank (no constraint; the actuation wrench is a row of the
  inverse), at half the cost of the QR;
* any other leg's twist system by one Householder QR with column pivoting of ``(T_h Δ)ᵀ``:
  its rank, an orthonormal basis of its reciprocal (the leg's constraint wrenches) and,
  when the leg's twists are independent, the actuation wrench of an actuated joint as
  the minimum-norm solution of ``T_h Δ w = e_k`` (reciprocal to the leg's other joints,
  orthogonal to its constraints: the member of that reciprocal system doing the most
  work on the platform twists, which is how :mod:`pkm_pin.batch` defines it);
* the union of the constraints and the platform twists by the same QR;
* the singular values of ``A_h Δ Pᵀ`` (type II index, condition) by one-sided Jacobi.

QR with column pivoting reveals the rank only up to a bounded factor, so a decision is
taken here only when every pivot ratio is at least 10⁴ away from the threshold; a pose
with a ratio inside that window (a near-singular pose), or with an actuated leg whose
joint twists are dependent, is flagged and the caller evaluates it with
:func:`pkm_pin.batch.analyse`. Tests check the two paths give the same results.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .kernels import jacobi_sv

#: A rank decision is taken by QR only if every pivot ratio is this factor away from
#: its threshold (QR with column pivoting brackets the singular values within 2^6·√6).
WINDOW = 1e4


@njit(cache=True, nogil=True, inline="always")
def _qr_core(A, nrow, ncol, perm, V, betas, stop=0.0, unit=False):
    """Householder QR with column pivoting of the leading nrow × ncol block of ``A`` (in
    place: R in its upper triangle); the reflectors ``I − f_j v_j v_jᵀ`` are kept in
    the columns of ``V`` and ``f_j = 2/(v_jᵀv_j)`` in ``betas`` (0: none); the column
    order in ``perm``.

    The pivot is the first column whose squared norm no later column exceeds by a
    factor 1 + 10⁻¹⁰ (within that factor of the largest): near-ties (the unit columns
    of this module) go to the lowest index rather than to round-off, so that the bases
    built from the factorisation vary continuously along a path of poses (which keeps
    the warm start of :func:`~pkm_pin.kernels.jacobi_sv` valid: one sweep fewer). The
    bounds of pivoted QR on the singular values change by that factor only, far inside
    the window of :data:`WINDOW`.

    ``unit``: the caller's columns all have norm 1 or 0 (normalised twists, orthonormal
    constraints); a unit first column is then the first pivot under that rule, and the
    norms of the others are not computed at step 0 (same factorisation).

    With ``stop > 0`` the factorisation ends at step j when every remaining column is
    shorter than ``stop · |R_00|``: the block left unreduced then has every diagonal
    entry below that bound, so :func:`_rank` reads the same decision from it (for
    ``stop ≤ rtol / WINDOW``), and ``Q e_i`` (i ≥ j) from the j reflectors still spans
    the orthogonal complement of the first j columns.
    Returns the number of reflectors."""
    for c in range(ncol):
        perm[c] = c
    m = min(nrow, ncol)
    top2 = 0.0
    for j in range(m):
        best, p = -1.0, j
        if j == 0 and unit:  # a unit first column is the first pivot: no search
            s = 0.0
            for r in range(nrow):
                s += A[r, 0] * A[r, 0]
            if s > 0.5:
                best = s
        if best < 0.0:
            for c in range(j, ncol):
                s = 0.0
                for r in range(j, nrow):
                    s += A[r, c] * A[r, c]
                if s > best * (1.0 + 1e-10):
                    best, p = s, c
        if j == 0:
            top2 = best * stop * stop
        elif best * (1.0 + 1e-10) <= top2:  # then every remaining column is too
            return j
        if p != j:
            for r in range(nrow):
                A[r, j], A[r, p] = A[r, p], A[r, j]
            perm[j], perm[p] = perm[p], perm[j]
        betas[j] = 0.0
        norm = math.sqrt(best)
        if norm == 0.0:
            continue
        alpha = -norm if A[j, j] >= 0 else norm
        beta = 0.0
        for r in range(j, nrow):
            V[r, j] = A[r, j]
        V[j, j] -= alpha
        for r in range(j, nrow):
            beta += V[r, j] * V[r, j]
        if beta == 0.0:
            continue
        f = 2.0 / beta
        betas[j] = f
        for c in range(j + 1, ncol):
            s = 0.0
            for r in range(j, nrow):
                s += V[r, j] * A[r, c]
            s *= f
            for r in range(j, nrow):
                A[r, c] -= s * V[r, j]
        A[j, j] = alpha
        for r in range(j + 1, nrow):
            A[r, j] = 0.0
    return m


@njit(cache=True, nogil=True, inline="always")
def _apply_q(V, betas, m, nrow, x):
    """x ← Q x with Q = H_0 ⋯ H_{m−1} from :func:`_qr_core`."""
    for j in range(m - 1, -1, -1):
        if betas[j] == 0.0:
            continue
        s = 0.0
        for r in range(j, nrow):
            s += V[r, j] * x[r]
        s *= betas[j]
        for r in range(j, nrow):
            x[r] -= s * V[r, j]


@njit(cache=True, nogil=True, inline="always")
def _rank(R, n, rtol, absolute):
    """Rank from the diagonal of R (first n pivots): ``|R_jj| > rtol · |R_00|`` (or
    ``> rtol`` when ``absolute``); -1 when a ratio lies inside the ambiguity window."""
    if n == 0:
        return 0
    top = abs(R[0, 0])
    if top == 0.0:
        return 0
    scale = 1.0 if absolute else top
    rank = 0
    for j in range(n):
        ratio = abs(R[j, j]) / scale
        if rtol / WINDOW < ratio < rtol * WINDOW:
            return -1
        if ratio > rtol:
            rank += 1
    return rank


@njit(cache=True, nogil=True, inline="always")
def _pivot(A, j, n):
    """Partial pivoting: the row r ≥ j of the largest |A[r, j]| among the first n."""
    p = j
    for r in range(j + 1, n):
        if abs(A[r, j]) > abs(A[p, j]):
            p = r
    return p


@njit(cache=True, nogil=True, inline="always")
def _inverse(X, n, Xi, W):
    """Xi = X⁻¹ for the n × n block of X (Gauss–Jordan, partial pivoting; W: n × n work
    space). Returns False when a pivot is zero."""
    for r in range(n):
        for c in range(n):
            W[r, c] = X[r, c]
            Xi[r, c] = 1.0 if r == c else 0.0
    for j in range(n):
        p = _pivot(W, j, n)
        if W[p, j] == 0.0:
            return False
        if p != j:
            for c in range(n):
                W[j, c], W[p, c] = W[p, c], W[j, c]
                Xi[j, c], Xi[p, c] = Xi[p, c], Xi[j, c]
        f = 1.0 / W[j, j]
        for c in range(n):
            W[j, c] *= f
            Xi[j, c] *= f
        for r in range(n):
            if r != j:
                g = W[r, j]
                if g != 0.0:
                    for c in range(n):
                        W[r, c] -= g * W[j, c]
                        Xi[r, c] -= g * Xi[j, c]
    return True


@njit(cache=True, nogil=True, inline="always")
def _square_leg(X, Xi, W, rtol):
    """A leg with six joint twists: ``Xi = X⁻¹`` and whether X is certainly of full
    rank for the rank decision ``σ_min > rtol · σ_max`` taken outside its ambiguity
    window: ``σ_min / σ_max ≥ 1 / (‖X‖_F ‖X⁻¹‖_F) ≥ rtol · WINDOW`` (the bound is within a
    factor 6 of the ratio, so every leg further than 6 · 10⁻⁵ from a leg singularity is
    certified; the others go to QR)."""
    if not _inverse(X, 6, Xi, W):
        return False
    a = 0.0
    b = 0.0
    for r in range(6):
        for c in range(6):
            a += X[r, c] * X[r, c]
            b += Xi[r, c] * Xi[r, c]
    return a * b * (rtol * WINDOW) ** 2 <= 1.0


@njit(cache=True, nogil=True, inline="always")
def _det(M, n, A=None):
    """Determinant of the leading n × n block (Gaussian elimination, partial pivoting;
    ``A``: optional n × n work space)."""
    if A is None:
        A = np.empty((n, n))
    for r in range(n):
        for c in range(n):
            A[r, c] = M[r, c]
    d = 1.0
    for j in range(n):
        p = _pivot(A, j, n)
        if A[p, j] == 0.0:
            return 0.0
        if p != j:
            for c in range(n):
                A[j, c], A[p, c] = A[p, c], A[j, c]
            d = -d
        d *= A[j, j]
        for r in range(j + 1, n):
            f = A[r, j] / A[j, j]
            for c in range(j, n):
                A[r, c] -= f * A[j, c]
    return d


@njit(cache=True, nogil=True, inline="always")
def _solve3(G, b, x):
    """x = G⁻¹ b for a symmetric 3×3 matrix (adjugate)."""
    c00 = G[1, 1] * G[2, 2] - G[1, 2] * G[2, 1]
    c01 = G[1, 2] * G[2, 0] - G[1, 0] * G[2, 2]
    c02 = G[1, 0] * G[2, 1] - G[1, 1] * G[2, 0]
    c11 = G[0, 0] * G[2, 2] - G[0, 2] * G[2, 0]
    c12 = G[0, 1] * G[2, 0] - G[0, 0] * G[2, 1]
    c22 = G[0, 0] * G[1, 1] - G[0, 1] * G[1, 0]
    f = 1.0 / (G[0, 0] * c00 + G[0, 1] * c01 + G[0, 2] * c02)
    x[0] = (c00 * b[0] + c01 * b[1] + c02 * b[2]) * f
    x[1] = (c01 * b[0] + c11 * b[1] + c12 * b[2]) * f
    x[2] = (c02 * b[0] + c12 * b[1] + c22 * b[2]) * f


@njit(cache=True, nogil=True, inline="always")
def _reciprocal_products(W, n, T, m, out):
    """out[a, j] = W_a Δ T_j (wrench rows W[:n], twist rows T[:m], axis-first)."""
    for a in range(n):
        for j in range(m):
            s = 0.0
            for k in range(3):
                s += W[a, k] * T[j, 3 + k] + W[a, 3 + k] * T[j, k]
            out[a, j] = s


@njit(cache=True, nogil=True, inline="always")
def _homogeneous_unit(x, L, out):
    """(x[:3]; x[3:] / L) scaled to unit norm (zero stays zero)."""
    s = 0.0
    il = 1.0 / L
    for k in range(6):
        out[k] = x[k] if k < 3 else x[k] * il
        s += out[k] * out[k]
    if s > 0:
        f = 1.0 / math.sqrt(s)
        for k in range(6):
            out[k] *= f


@njit(cache=True, nogil=True)
def analyse_poses(J, coords, groups, act_col, act_leg, L, rtol, rot_tol, reference,
                  dof, translations, redundant, type_I, type_II, condition, det, flag):
    """Screw analysis of N assemblies (see the module docstring).

    Args:
        J: (N, nv, 6) axis-first world joint twists (rows) of the legs, one after the
            other (the transposed Jacobians).
        coords: (legs + 1,) column offsets of the legs in J.
        groups: (G, 3) columns of spherical groups (replaced by three lines).
        act_col, act_leg: column and leg of each actuated joint.
        L, rtol, rot_tol: characteristic length, rank tolerance, rotation tolerance.
        reference: (n_ref, 6) homogenised home platform basis (for the carried det).

    Outputs (N,) arrays; ``flag[i]`` is 1 where pose i must be analysed by
    :func:`pkm_pin.batch.analyse` (a rank decision inside the ambiguity window, or an
    actuated leg with dependent joint twists).
    """
    N = J.shape[0]
    n_legs = coords.shape[0] - 1
    n = act_col.shape[0]
    nv = J.shape[1]
    T = np.empty((nv, 6))  # motion twists (rows), homogenised and unit
    X = np.empty((6, nv))
    perm = np.empty(max(6 * n_legs, nv, 6), np.int64)
    C = np.empty((6, 6 * n_legs))  # constraint wrenches (columns)
    Ah = np.empty((max(n, 1), 6))  # homogenised unit actuation wrenches
    A = np.empty(6)
    a_h = np.empty(6)
    y = np.empty(6)
    P = np.empty((6, 6))  # platform twists (rows), homogenised orthonormal
    M = np.empty((max(n, 1), 6))
    sv = np.empty(6)
    Pw = np.empty((6, 6))
    G = np.empty((3, 3))
    gb = np.empty(3)
    ctr = np.empty(3)
    Ploc = np.empty((max(reference.shape[0], 1), 6))
    Wd = np.empty((max(n, 1), max(n, 1)))  # work space of the determinant
    Vh = np.empty((6, 6))  # Householder vectors
    Xi = np.empty((6, 6))  # inverse of a square leg's X, and work space
    Wi = np.empty((6, 6))
    betas = np.empty(6)
    x6 = np.empty(6)
    V = np.eye(6)  # right singular basis of M, carried from pose to pose
    Wk = np.empty((max(n, 6), 6))
    d_prev = -1
    n_ref = reference.shape[0]
    iL = 1.0 / L
    for i in range(N):
        flag[i] = 0
        # ---- motion twists: J columns, spherical groups as three lines through centre
        for c in range(nv):
            for k in range(6):
                T[c, k] = J[i, c, k]
        for g in range(groups.shape[0]):
            # centre c of the three concurrent axes: Σ(|ω|²I − ωωᵀ) c = Σ ω × v
            G[:, :] = 0.0
            gb[:] = 0.0
            for t in range(3):
                col = groups[g, t]
                w0, w1, w2 = J[i, col, 0], J[i, col, 1], J[i, col, 2]
                v0, v1, v2 = J[i, col, 3], J[i, col, 4], J[i, col, 5]
                ww = w0 * w0 + w1 * w1 + w2 * w2
                G[0, 0] += ww - w0 * w0
                G[1, 1] += ww - w1 * w1
                G[2, 2] += ww - w2 * w2
                G[0, 1] -= w0 * w1
                G[0, 2] -= w0 * w2
                G[1, 2] -= w1 * w2
                gb[0] += w1 * v2 - w2 * v1
                gb[1] += w2 * v0 - w0 * v2
                gb[2] += w0 * v1 - w1 * v0
            G[1, 0], G[2, 0], G[2, 1] = G[0, 1], G[0, 2], G[1, 2]
            _solve3(G, gb, ctr)
            for t in range(3):  # the line through the centre along e_t: (e_t; c × e_t)
                row = groups[g, t]
                for k in range(6):
                    T[row, k] = 0.0
                T[row, t] = 1.0
                T[row, 3 + (t + 2) % 3] = -ctr[(t + 1) % 3]
                T[row, 3 + (t + 1) % 3] = ctr[(t + 2) % 3]
        for c in range(nv):  # homogenise and normalise the rows
            s = 0.0
            for k in range(6):
                if k >= 3:
                    T[c, k] *= iL
                s += T[c, k] * T[c, k]
            if s > 0:
                f = 1.0 / math.sqrt(s)
                for k in range(6):
                    T[c, k] *= f
        # ---- per leg: constraints, and actuation wrenches of its actuated joints
        m_c = 0
        leg_dims = 0
        bad = False
        for l in range(n_legs):
            c0, c1 = coords[l], coords[l + 1]
            k = c1 - c0
            for c in range(k):  # columns of (T_h Δ)ᵀ: each twist times Δ (halves swapped)
                for r in range(3):
                    X[r, c] = T[c0 + c, 3 + r]
                    X[3 + r, c] = T[c0 + c, r]
            if k == 6 and _square_leg(X, Xi, Wi, rtol):
                # six independent twists: no constraint; an actuated joint's wrench
                # solves (T_h Δ) w = Xᵀ w = e_k, i.e. w = row k of X⁻¹
                for a_i in range(n):
                    if act_leg[a_i] == l:
                        ka = act_col[a_i] - c0
                        for a in range(6):
                            Ah[a_i, a] = Xi[ka, a]
                continue
            nref = _qr_core(X, 6, k, perm, Vh, betas, 0.0, True)  # unit twist rows
            r = _rank(X, min(6, k), rtol, False)
            if r < 0:
                bad = True
                break
            leg_dims += 6 - r
            for j in range(r, 6):  # the leg's constraints: Q e_j, j ≥ rank
                for a in range(6):
                    x6[a] = 1.0 if a == j else 0.0
                _apply_q(Vh, betas, nref, 6, x6)
                for a in range(6):
                    C[a, m_c] = x6[a]
                m_c += 1
            for a_i in range(n):
                if act_leg[a_i] != l:
                    continue
                if r < k:  # dependent joint twists in an actuated leg
                    bad = True
                    break
                # row k_a of X: the actuated joint; minimum-norm w with (T_h Δ) w = e_k
                ka = act_col[a_i] - c0
                jp = 0
                for j in range(k):
                    if perm[j] == ka:
                        jp = j
                for j in range(jp):
                    y[j] = 0.0
                for j in range(jp, k):  # Rᵀ y = e_jp (forward substitution)
                    s = 1.0 if j == jp else 0.0
                    for t in range(jp, j):
                        s -= X[t, j] * y[t]
                    y[j] = s / X[j, j]
                for j in range(k, 6):
                    y[j] = 0.0
                _apply_q(Vh, betas, nref, 6, y)  # w = Q₁ y
                for a in range(6):
                    Ah[a_i, a] = y[a]
            if bad:
                break
        if bad:
            flag[i] = 1
            continue
        # ---- union of the constraints, platform twists
        nref = 0
        rank_c = 0
        if m_c > 0:
            nref = _qr_core(C, 6, m_c, perm, Vh, betas, rtol / WINDOW, True)
            rank_c = _rank(C, min(6, m_c), rtol, False)
            if rank_c < 0:
                flag[i] = 1
                continue
        d = 6 - rank_c
        for j in range(d):  # t_h = Δ n for n = Q e_(rank+j) ⟂ the constraints
            for a in range(6):
                x6[a] = 1.0 if a == rank_c + j else 0.0
            _apply_q(Vh, betas, nref, 6, x6)
            for a in range(3):
                P[j, a] = x6[3 + a]
                P[j, 3 + a] = x6[a]
        dof[i] = d
        redundant[i] = leg_dims - rank_c
        # rotations among the platform twists: rank of their ω parts
        for j in range(d):
            for a in range(3):
                Pw[a, j] = P[j, a]
            for a in range(3, 6):
                Pw[a, j] = 0.0
        _qr_core(Pw, 3, d, perm, Vh, betas)
        rot = _rank(Pw, min(3, d), rot_tol, True)
        if rot < 0:
            flag[i] = 1
            continue
        translations[i] = d - rot
        # ---- actuation wrenches: world units, unit force (or moment), B ≥ 0
        ti = np.inf
        for a_i in range(n):
            col = act_col[a_i]
            for a in range(3):
                A[a] = Ah[a_i, a]
                A[3 + a] = Ah[a_i, 3 + a] * L
            f = math.sqrt(A[0] ** 2 + A[1] ** 2 + A[2] ** 2)
            mm = math.sqrt(A[3] ** 2 + A[4] ** 2 + A[5] ** 2)
            s = f if f * L > rtol * mm else (mm if mm > 0 else 1.0)
            B = 0.0
            big = 0.0
            f = 1.0 / s
            for a in range(6):
                A[a] *= f
                if abs(A[a]) > abs(big):
                    big = A[a]
            for a in range(3):
                B += A[a] * J[i, col, 3 + a] + A[3 + a] * J[i, col, a]
            if B < 0 or (B == 0 and big < 0):
                for a in range(6):
                    A[a] = -A[a]
            _homogeneous_unit(A, L, Ah[a_i])
            for a in range(6):
                y[a] = J[i, col, a]
            _homogeneous_unit(y, L, a_h)
            s = 0.0
            for a in range(3):
                s += Ah[a_i, a] * a_h[3 + a] + Ah[a_i, 3 + a] * a_h[a]
            ti = min(ti, abs(s))
        type_I[i] = ti
        # ---- M = A_h Δ Pᵀ: type II index and condition
        _reciprocal_products(Ah, n, P, d, M)
        if n > 0 and d > 0:
            if d != d_prev:  # a new platform dimension: start from the identity
                V[:, :] = 0.0
                for a in range(6):
                    V[a, a] = 1.0
                d_prev = d
            if n >= d:
                jacobi_sv(M, n, d, sv, V, Wk)
            else:
                Mt = M[:n, :d].T.copy()
                jacobi_sv(Mt, d, n, sv, np.eye(n), Wk)
            t2 = sv[d - 1] if d <= n else 0.0
            type_II[i] = t2
            condition[i] = sv[0] / t2 if t2 > 0 else np.inf
        else:
            type_II[i] = 0.0
            condition[i] = np.inf
        # ---- det(A_h Δ P_locᵀ), P_loc: the home basis projected on the platform twists
        if n == n_ref and n > 0 and d == 6:  # P spans every twist: P_loc = reference
            _reciprocal_products(Ah, n, reference, n_ref, M)
            det[i] = _det(M, n, Wd)
        elif n == n_ref and n > 0:
            for j in range(n_ref):  # P_loc = reference Pᵀ P
                for a in range(6):
                    Ploc[j, a] = 0.0
                for jj in range(d):
                    proj = 0.0
                    for a in range(6):
                        proj += reference[j, a] * P[jj, a]
                    for a in range(6):
                        Ploc[j, a] += proj * P[jj, a]
            _reciprocal_products(Ah, n, Ploc, n_ref, M)
            det[i] = _det(M, n, Wd)
        else:
            det[i] = np.nan


@njit(cache=True, nogil=True)
def leg_outputs(H, Jp, base, targets, idx, length, tol, J_out, c0, bad):
    """Post-process one leg's Pinocchio pass over poses ``idx``.

    Args:
        H: (M, 4, 4) tip placements from Pinocchio (URDF root frame).
        Jp: (M, 6, nv) Pinocchio WORLD frame Jacobians (linear-first ``(v; ω)``, root
            frame).
        base: root placement (R, p) in the world (4×4); a column becomes the axis-first
            twist about the world origin ``(R ω; R v + p × R ω)`` (as
            :meth:`Leg._world_map`).
        targets: (N, 4, 4) world placements the tip must reach (pose · anchor).
        J_out: (M, nv_total, 6) receives the axis-first twists in rows c0:c0+nv.
        bad: (M,) set where the closure error exceeds ``tol`` (or is nan): sin of the
            rotation angle between tip and target (π beyond 90°) and their distance /
            length, in quadrature.
    """
    M = H.shape[0]
    nv = Jp.shape[2]
    tip = np.empty((3, 4))
    R = np.empty((3, 3))
    il = 1.0 / length
    px, py, pz = base[0, 3], base[1, 3], base[2, 3]
    for j in range(M):
        tgt = targets[idx[j]]
        # tip in the world: base · H
        for a in range(3):
            for b in range(4):
                s = base[a, 3] if b == 3 else 0.0
                for k in range(3):
                    s += base[a, k] * H[j, k, b]
                tip[a, b] = s
        # R = tipᵀ tgt: skew part and trace
        tr = 0.0
        for a in range(3):
            for b in range(3):
                R[a, b] = tip[0, a] * tgt[0, b] + tip[1, a] * tgt[1, b] + tip[2, a] * tgt[2, b]
            tr += R[a, a]
        x = R[2, 1] - R[1, 2]
        y = R[0, 2] - R[2, 0]
        z = R[1, 0] - R[0, 1]
        angle = 0.5 * math.sqrt(x * x + y * y + z * z) if tr >= 1.0 else math.pi
        dx = (tip[0, 3] - tgt[0, 3]) * il
        dy = (tip[1, 3] - tgt[1, 3]) * il
        dz = (tip[2, 3] - tgt[2, 3]) * il
        if not math.sqrt(angle * angle + dx * dx + dy * dy + dz * dz) <= tol:
            bad[j] = True
        for c in range(nv):
            v0, v1, v2 = Jp[j, 0, c], Jp[j, 1, c], Jp[j, 2, c]
            w0, w1, w2 = Jp[j, 3, c], Jp[j, 4, c], Jp[j, 5, c]
            a0 = base[0, 0] * w0 + base[0, 1] * w1 + base[0, 2] * w2
            a1 = base[1, 0] * w0 + base[1, 1] * w1 + base[1, 2] * w2
            a2 = base[2, 0] * w0 + base[2, 1] * w1 + base[2, 2] * w2
            row = J_out[j, c0 + c]
            row[0], row[1], row[2] = a0, a1, a2
            row[3] = base[0, 0] * v0 + base[0, 1] * v1 + base[0, 2] * v2 + py * a2 - pz * a1
            row[4] = base[1, 0] * v0 + base[1, 1] * v1 + base[1, 2] * v2 + pz * a0 - px * a2
            row[5] = base[2, 0] * v0 + base[2, 1] * v1 + base[2, 2] * v2 + px * a1 - py * a0
