"""The stages of the analysis engine, one pose at a time.

Plain Python functions on numpy arrays, compiled by numba inside the engine's loop
(:func:`~pkm_pin.engine.core.analyse_into`, ``register_jitable``): each can be called
and tested from Python as it is.

Every stage works on *homogenised* screws about the mechanism's **centre** ``p`` (the
platform's origin at the pose analysed): twists ``(ω; v_p)`` and wrenches ``(f; m_p)``,
axis-first, with the moment part divided by the mechanism's characteristic length ``L``
(reciprocity is kept: ``a_h Δ b_h = (a Δ b) / L``). Every rank decision and every index
is therefore invariant under the units (``L`` scales with them) and under a rigid motion
of the whole mechanism (``p`` moves with it; rotations keep every norm), which the world
origin would not give: about a far origin every moment is large and the rows of
:func:`leg_constraints` or :func:`transmission` lose their conditioning. Rank decisions
are ``σ > rtol · σ_max`` on the singular values of rows normalised to unit length
(:func:`~.linalg.jacobi`). Joint twists come in about the world origin and actuation
wrenches go out about it (:func:`shift_twist`, :func:`wrench_about_origin`).

1. :func:`motion_twists` — the joint twists, spherical groups replaced by three lines
   through their centre, about ``p``, homogenised, rows normalised.
2. :func:`leg_constraints` — one leg: the rank of its twist system and an orthonormal
   basis of its reciprocal (the leg's constraint wrenches).
3. :func:`actuation_wrench` — one actuated joint: the wrench reciprocal to every other
   joint twist of its leg and orthogonal to the leg's constraint wrenches.
4. :func:`platform_system` — the union of the constraints and its reciprocal, the
   platform twist system (orthonormal basis), and the number of its rotations.
5. :func:`scale_actuation` — actuation wrenches in world units (unit force, or unit
   moment for a couple), signed so that ``B_ii ≥ 0``; the type I index.
6. :func:`transmission` — the singular values of ``A_h Δ Pᵀ``: type II index and
   condition (:func:`locked_motion_index` where an actuation wrench is not defined);
   and :func:`carried_determinant`.
"""

from __future__ import annotations

import math

from numba.extending import register_jitable

from .linalg import (
    JACOBI_TOL,
    certainly_invertible,
    descending,
    jacobi,
    largest,
    lu,
    lu_column,
    reset,
)


@register_jitable
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


@register_jitable
def group_centre(J, cols, centre, G, b):
    """Centre of three concurrent joint axes (rows ``cols`` of ``J``): the point ``c``
    nearest to the three lines in the least-squares sense,
    ``Σ(|ω|²I − ωωᵀ) c = Σ ω × v_O``."""
    for a in range(3):
        b[a] = 0.0
        for k in range(3):
            G[a, k] = 0.0
    for t in range(3):
        col = cols[t]
        w0, w1, w2 = J[col, 0], J[col, 1], J[col, 2]
        v0, v1, v2 = J[col, 3], J[col, 4], J[col, 5]
        ww = w0 * w0 + w1 * w1 + w2 * w2
        G[0, 0] += ww - w0 * w0
        G[1, 1] += ww - w1 * w1
        G[2, 2] += ww - w2 * w2
        G[0, 1] -= w0 * w1
        G[0, 2] -= w0 * w2
        G[1, 2] -= w1 * w2
        b[0] += w1 * v2 - w2 * v1
        b[1] += w2 * v0 - w0 * v2
        b[2] += w0 * v1 - w1 * v0
    G[1, 0], G[2, 0], G[2, 1] = G[0, 1], G[0, 2], G[1, 2]
    _solve3(G, b, centre)


@register_jitable
def unit_homogeneous(x, L, out):
    """``out = (x[:3]; x[3:] / L)`` scaled to unit norm (zero stays zero); ``out`` may
    be ``x``."""
    s = 0.0
    for k in range(6):
        out[k] = x[k] if k < 3 else x[k] / L
        s += out[k] * out[k]
    if s > 0:
        f = 1.0 / math.sqrt(s)
        for k in range(6):
            out[k] *= f


@register_jitable
def spherical_lines(J, groups, T, G, b, centre):
    """``T`` (nv × 6, world units): the joint twists ``J`` (rows, axis-first) with every
    spherical group (rows of ``groups``) replaced by the three lines through its centre
    (:func:`group_centre`) along the world axes — the true span of a spherical joint,
    also at the gimbal lock of its three revolutes. The one definition of the motion
    twists (:meth:`pkm_pin.Leg.motion_twists` calls it too)."""
    for c in range(J.shape[0]):
        for k in range(6):
            T[c, k] = J[c, k]
    for g in range(groups.shape[0]):
        group_centre(J, groups[g], centre, G, b)
        for t in range(3):  # the line through the centre along e_t: (e_t; c × e_t)
            row = groups[g, t]
            for k in range(6):
                T[row, k] = 0.0
            T[row, t] = 1.0
            T[row, 3 + (t + 2) % 3] = -centre[(t + 1) % 3]
            T[row, 3 + (t + 1) % 3] = centre[(t + 2) % 3]


@register_jitable
def shift_twist(x, p, out):
    """``out``: the twist ``x = (ω; v_O)`` written about the point ``p``: ``(ω; v_O + ω ×
    p)`` (the velocity of the body point at ``p``); ``out`` may be ``x``."""
    w0, w1, w2 = x[0], x[1], x[2]
    out[0], out[1], out[2] = w0, w1, w2
    out[3] = x[3] + w1 * p[2] - w2 * p[1]
    out[4] = x[4] + w2 * p[0] - w0 * p[2]
    out[5] = x[5] + w0 * p[1] - w1 * p[0]


@register_jitable
def wrench_about_origin(x, p, out):
    """``out``: the wrench ``x = (f; m_p)`` given about the point ``p``, written about the
    world origin: ``(f; m_p + p × f)``; ``out`` may be ``x``."""
    f0, f1, f2 = x[0], x[1], x[2]
    out[0], out[1], out[2] = f0, f1, f2
    out[3] = x[3] + p[1] * f2 - p[2] * f1
    out[4] = x[4] + p[2] * f0 - p[0] * f2
    out[5] = x[5] + p[0] * f1 - p[1] * f0


@register_jitable(inline="always")
def motion_twists(J, groups, L, p, T, G, b, centre):
    """Stage 1. ``T`` (nv × 6): the motion twists of :func:`spherical_lines`, written
    about the mechanism's centre ``p`` (:func:`shift_twist`), homogenised, rows of unit
    norm."""
    spherical_lines(J, groups, T, G, b, centre)
    for c in range(J.shape[0]):
        shift_twist(T[c], p, T[c])
        unit_homogeneous(T[c], L, T[c])


#: How :func:`leg_constraints` factorised a leg (read by :func:`actuation_wrench`): the
#: Jacobi SVD of ``X``, or the LU factors of a square ``X``.
WIDE, SQUARE = 0, 1


@register_jitable(inline="always")
def leg_constraints(T, c0, k, rtol, X, W, V, sv, C, m_c, LU, perm):
    """Stage 2. One leg, twists ``T[c0:c0+k]``: the rank of ``X = T_h Δ`` (its rows are
    the reciprocal products with a wrench) and an orthonormal basis of the wrenches
    reciprocal to every joint twist (its null space), written as rows ``C[m_c:]``.

    * ``k == 6`` and a full rank :func:`~.linalg.certainly_invertible` certifies: no
      constraint, the LU factors of ``X`` in ``LU`` and ``perm`` (the decision the SVD
      would take) — ``SQUARE``;
    * otherwise the Jacobi SVD of ``X`` (``W = X V``, k × 6): the constraints are the
      right singular vectors of the singular values ``≤ rtol · σ_max`` — ``WIDE``.

    ``V`` is the leg's singular basis (in/out: a warm start along a path); ``W`` and
    ``sv`` are kept for :func:`actuation_wrench`. Returns ``(rank, m_c + 6 − rank,
    mode)``."""
    for c in range(k):
        for a in range(3):
            X[c, a] = T[c0 + c, 3 + a]
            X[c, 3 + a] = T[c0 + c, a]
    if k == 6 and certainly_invertible(X, 6, LU, perm, rtol):
        return 6, m_c, SQUARE
    jacobi(X, k, 6, W, V, sv)
    threshold = rtol * largest(sv, 6)
    r = 0
    for j in range(6):
        if sv[j] > threshold:
            r += 1
        else:
            for a in range(6):
                C[m_c, a] = V[a, j]
            m_c += 1
    return r, m_c, WIDE


@register_jitable
def actuation_wrench(T, c0, k, ka, r, mode, LU, perm, rtol, X, W, V, sv, C, c_first, c_last,
                     W2, V2, sv2, w):
    """Stage 3. The actuation wrench ``w`` (homogenised, in/out of unit scale) of joint
    ``ka`` (0-based in its leg), defined as the wrench reciprocal to every other joint
    twist of the leg and orthogonal to the leg's constraint wrenches (rows
    ``C[c_first:c_last]``); it is unique up to scale when the joint's twist is
    independent of the others.

    When the leg's twists are independent (``r == k``) it is the minimum-norm solution
    of ``(T_h Δ) w = e_ka``, read from the factorisation of :func:`leg_constraints`
    (``mode``): column ``ka`` of ``X⁻¹`` from its LU factors (``SQUARE``), or ``w = Σ_j
    V_j W[ka, j] / σ_j²`` from ``X = W Vᵀ`` (``WIDE``). Otherwise the reciprocal
    of the other joint twists is computed by a second SVD and its component orthogonal
    to the constraints taken; when the joint's twist depends on the others there is none
    (a type I singularity of the leg) and ``w`` is the first constraint wrench of the
    leg, which does no work on the joint: ``B_ii = 0``.

    Returns whether the joint's twist is independent of the others."""
    if mode == SQUARE:
        lu_column(LU, perm, 6, ka, w)
        return True
    if r == k:
        for a in range(6):
            w[a] = 0.0
        threshold = rtol * largest(sv, 6)
        for j in range(6):
            if sv[j] > threshold:
                f = W[ka, j] / (sv[j] * sv[j])
                for a in range(6):
                    w[a] += V[a, j] * f
        return True
    m = 0  # the other joints' rows of X
    for c in range(k):
        if c != ka:
            for a in range(6):
                X[m, a] = T[c0 + c, (a + 3) % 6]
            m += 1
    reset(V2, 6)
    jacobi(X, m, 6, W2, V2, sv2)
    threshold2 = rtol * largest(sv2, 6)
    best = -1.0
    for j in range(6):
        if sv2[j] > threshold2:
            continue
        # the reciprocal vector V2_j less its components along the constraints
        s2 = 0.0
        for a in range(6):
            x = V2[a, j]
            for i in range(c_first, c_last):
                d = 0.0
                for b in range(6):
                    d += C[i, b] * V2[b, j]
                x -= d * C[i, a]
            s2 += x * x
        if s2 > best:
            best = s2
            for a in range(6):
                w[a] = V2[a, j]
    if best > rtol * rtol:  # project out the constraints from the best candidate
        for i in range(c_first, c_last):
            d = 0.0
            for b in range(6):
                d += C[i, b] * w[b]
            for a in range(6):
                w[a] -= d * C[i, a]
        return True
    for a in range(6):
        w[a] = C[c_first, a] if c_last > c_first else 0.0
    return False


@register_jitable(inline="always")
def platform_system(C, m_c, rtol, rot_tol, W, V, sv, order, constraints, P, Pw, W3, V3, sv3):
    """Stage 4. The union of the constraint wrenches (rows ``C[:m_c]``, homogenised):
    its rank by the Jacobi SVD of ``C`` (``V``: in/out warm start), an orthonormal basis
    of it (rows ``constraints[:rank]``, by decreasing singular value) and of its
    reciprocal, the platform twist system (rows ``P[:6 − rank]``, ``Δ`` times the right
    singular vectors of the small singular values). The number of rotations among the
    platform twists is the rank of their ω parts (absolute threshold ``rot_tol``: the
    rows are orthonormal; ``V3`` in/out warm start). Returns ``(rank, rotations)``."""
    jacobi(C, m_c, 6, W, V, sv)
    threshold = rtol * largest(sv, 6)
    descending(sv, 6, order)
    rank_c = 0
    d = 0
    for jj in range(6):
        j = order[jj]
        if sv[j] > threshold:
            for a in range(6):
                constraints[rank_c, a] = V[a, j]
            rank_c += 1
    for j in range(6):  # in column order: the basis moves continuously along a path
        if not sv[j] > threshold:
            for a in range(3):
                P[d, a] = V[3 + a, j]
                P[d, 3 + a] = V[a, j]
            d += 1
    for j in range(d):
        for a in range(3):
            Pw[j, a] = P[j, a]
    jacobi(Pw, d, 3, W3, V3, sv3)  # V3: in/out warm start
    rotations = 0
    for j in range(3):
        if sv3[j] > rot_tol:
            rotations += 1
    return rank_c, rotations


@register_jitable(inline="always")
def scale_actuation(w, twist, L, rtol, A, a_h, t_h):
    """Stage 5. ``A`` (world units) from the homogenised actuation wrench ``w``: a unit
    force, or a unit moment when it is a couple (force below ``rtol`` of the moment /
    L), signed so that ``B = A ∘ twist ≥ 0`` (at B = 0, the largest entry positive).
    ``a_h``: ``A`` homogenised with unit norm. Returns ``(B, |a_h ∘ t_h|)`` with
    ``t_h`` the joint twist homogenised with unit norm (the joint's type I index)."""
    for a in range(3):
        A[a] = w[a]
        A[3 + a] = w[3 + a] * L
    f = math.sqrt(A[0] ** 2 + A[1] ** 2 + A[2] ** 2)
    m = math.sqrt(A[3] ** 2 + A[4] ** 2 + A[5] ** 2)
    s = f if f * L > rtol * m else (m if m > 0 else 1.0)
    big = 0.0
    for a in range(6):
        A[a] /= s
        if abs(A[a]) > abs(big):
            big = A[a]
    B = 0.0
    for a in range(3):
        B += A[a] * twist[3 + a] + A[3 + a] * twist[a]
    if B < 0 or (B == 0 and big < 0):
        B = -B
        for a in range(6):
            A[a] = -A[a]
    unit_homogeneous(A, L, a_h)
    unit_homogeneous(twist, L, t_h)
    p = 0.0
    for a in range(3):
        p += a_h[a] * t_h[3 + a] + a_h[3 + a] * t_h[a]
    return B, abs(p)


@register_jitable
def reciprocal_products(W, n, T, m, out):
    """``out[a, j] = W_a Δ T_j`` (wrench rows ``W[:n]``, twist rows ``T[:m]``)."""
    for a in range(n):
        for j in range(m):
            s = 0.0
            for k in range(3):
                s += W[a, k] * T[j, 3 + k] + W[a, 3 + k] * T[j, k]
            out[a, j] = s


@register_jitable(inline="always")
def transmission(Ah, n, P, d, M, W, V, sv, order):
    """Stage 6. The singular values of ``M = A_h Δ Pᵀ`` (``n × d``; rows of ``A_h``
    homogenised unit actuation wrenches, rows of ``P`` the orthonormal platform twists):
    returns ``(type_II, condition)`` with ``type_II`` the d-th largest (0 when the
    actuators are fewer than the degrees of freedom) and ``condition = σ_max /
    type_II`` (inf when singular). ``V`` (d × d): in/out warm start."""
    if n == 0 or d == 0:
        return 0.0, math.inf
    reciprocal_products(Ah, n, P, d, M)
    jacobi(M, n, d, W, V, sv, JACOBI_TOL)  # the singular values only
    descending(sv, d, order)
    t2 = sv[order[d - 1]] if d <= n else 0.0
    return t2, (sv[order[0]] / t2 if t2 > 0 else math.inf)


@register_jitable
def locked_motion_index(T, coords, act_col, rtol, P, d, X, W, V, sv, S, R, M, order):
    """Stage 6 where an actuation wrench is not defined (an actuated joint whose twist
    depends on the other joints of its leg: a type I singularity, where :func:`actuation_wrench`
    falls back on a constraint wrench). The type II question is then asked directly:
    which platform twists remain with every actuator locked? Leg ``l`` with its
    actuators locked allows the span of its passive joint twists (rows of ``T``,
    homogenised), whose reciprocal wrenches (rows of ``S``) the platform must respect;
    with ``R`` an orthonormal basis of all of them, the index is the d-th largest
    singular value of ``R Δ Pᵀ`` (0 when they leave a platform twist free; a serial arm,
    every joint actuated, never does). Where every actuation wrench is defined this is
    not used: the index is seed 000's (:func:`transmission`)."""
    m = 0
    for l in range(coords.shape[0] - 1):
        k = 0
        for c in range(coords[l], coords[l + 1]):
            passive = True
            for a in range(act_col.shape[0]):
                if act_col[a] == c:
                    passive = False
            if passive:
                for a in range(6):
                    X[k, a] = T[c, (a + 3) % 6]
                k += 1
        reset(V, 6)
        jacobi(X, k, 6, W, V, sv)  # no passive joint: every wrench is reciprocal
        threshold = rtol * largest(sv, 6)
        for j in range(6):
            if not sv[j] > threshold:
                for a in range(6):
                    S[m, a] = V[a, j]
                m += 1
    reset(V, 6)
    jacobi(S, m, 6, W, V, sv)
    threshold = rtol * largest(sv, 6)
    r = 0
    for j in range(6):
        if sv[j] > threshold:
            for a in range(6):
                R[r, a] = V[a, j]
            r += 1
    if r < d or d == 0:
        return 0.0
    reciprocal_products(R, r, P, d, M)
    reset(V, 6)
    jacobi(M, r, d, W, V, sv, JACOBI_TOL)  # the singular values only
    descending(sv, d, order)
    return sv[order[d - 1]]


@register_jitable(inline="always")
def carried_determinant(Ah, n, P, d, reference, M, P_loc, work, perm):
    """``det(A_h Δ P_locᵀ)`` with ``P_loc`` the reference (home) platform basis
    projected on this pose's platform twists: a signed index whose sign change along a
    path marks a crossed type II singularity. nan when the actuators and the reference
    dimension differ."""
    n_ref = reference.shape[0]
    if n != n_ref or n == 0:
        return math.nan
    for j in range(n_ref):
        for a in range(6):
            P_loc[j, a] = 0.0
        for jj in range(d):
            proj = 0.0
            for a in range(6):
                proj += reference[j, a] * P[jj, a]
            for a in range(6):
                P_loc[j, a] += proj * P[jj, a]
    reciprocal_products(Ah, n, P_loc, n_ref, M)
    return lu(M, n, work, perm)
