"""Small dense linear algebra for the stages of the engine.

Plain Python functions, compiled by numba inside the engine's loop
(``register_jitable``): callable and testable from Python as they are.

numpy's per-call overhead dominates on 6 × 6 problems (one SVD costs ~27 µs), so the
engine factorises its screw systems here, one pose at a time:

* :func:`jacobi` — one-sided Jacobi SVD of an ``m × n`` matrix (``n ≤ 6`` columns):
  the right singular basis ``V`` and the singular values, accurate to round-off
  (relative to the largest), so rank decisions ``σ > rtol · σ_max`` are those of
  ``numpy.linalg.svd``. ``V`` is updated in place: the previous pose's basis is a warm
  start that leaves few rotations along a path of poses.
* :func:`descending` — the order of the singular values.
* :func:`lu`, :func:`lu_column` — the LU factors of a square matrix (partial
  pivoting), its determinant and a column of its inverse;
  :func:`certainly_invertible` certifies from them that the matrix has full rank
  without an SVD.
"""

from __future__ import annotations

import math

from numba.extending import register_jitable

#: Jacobi stops after a sweep in which every pair of columns had a cosine below this:
#: the convergence is quadratic, so the column norms are then the singular values to
#: round-off.
JACOBI_TOL = 1e-10
#: A pair of columns whose cosine is below this is already orthogonal (not rotated) …
JACOBI_SKIP = 1e-15
#: … and so is a pair whose inner product is below this fraction of ``‖X‖_F²``: columns
#: at round-off level (the null space of a rank-deficient X) are never orthogonal in
#: relative terms, yet their inner products move the singular values by about this
#: fraction of σ_max only.
JACOBI_FLOOR = 1e-15
#: See :func:`certainly_invertible`.
CERTIFY_MARGIN = 10.0
#: A rotation whose ``ρ = c / (b − a)`` is below ``SMALL_ANGLE^(−1/2)`` (1e-5) takes
#: ``tan θ = ρ (1 − ρ²)`` and ``cos θ = 1 − t²/2``, exact to round-off, without the
#: square roots and divisions of the general formula (the rotations of a warm start's
#: later sweeps).
SMALL_ANGLE = 1e10
#: Upper bound on the Jacobi sweeps (6 columns converge in 3–6 from a cold start).
JACOBI_SWEEPS = 60


@register_jitable
def jacobi(X, m, n, W, V, sv, skip=JACOBI_SKIP):
    """One-sided Jacobi SVD of the leading ``m × n`` block of ``X``.

    Computes ``W = X V`` with orthogonal columns: ``X = W Vᵀ``, ``W_j = σ_j u_j``.
    ``V`` (``n × n``, in/out) must be orthogonal on entry (identity, or the previous
    pose's basis as a warm start). On exit ``sv[j] = |W_j|`` (not sorted: use
    :func:`descending`). ``W``: at least ``m × n``. ``skip``: a pair of columns whose
    cosine is below it is left as it is (:data:`JACOBI_SKIP`: ``V`` orthogonalises
    to round-off, for bases; :data:`JACOBI_TOL` where only the singular values are read
    and ``V`` is a warm start, which spares the polishing rotations).
    """
    for a in range(m):
        for b in range(n):
            s = 0.0
            for k in range(n):
                s += X[a, k] * V[k, b]
            W[a, b] = s
    floor = 0.0
    for a in range(m):
        for b in range(n):
            floor += X[a, b] * X[a, b]
    floor *= JACOBI_FLOOR
    for _ in range(JACOBI_SWEEPS):
        rotated = False
        for p in range(n - 1):
            for q in range(p + 1, n):
                a = 0.0
                b = 0.0
                c = 0.0
                for r in range(m):
                    a += W[r, p] * W[r, p]
                    b += W[r, q] * W[r, q]
                    c += W[r, p] * W[r, q]
                cc = c * c
                if cc <= skip * skip * a * b or abs(c) <= floor:
                    continue
                if cc > JACOBI_TOL * JACOBI_TOL * a * b:
                    rotated = True
                # tan θ of the rotation that makes the pair orthogonal, the smaller root
                # of t² + 2ζt − 1 = 0 (ζ = (b − a) / 2c), written without dividing by c
                h = b - a
                if cc * SMALL_ANGLE < h * h:  # ρ = c / h below 1e-5: the series of t
                    rho = c / h  # and cos θ to round-off (next terms 2ρ⁵, 3t⁴/8)
                    t = rho * (1.0 - rho * rho)
                    cs = 1.0 - 0.5 * t * t
                else:
                    t = 2.0 * c / (abs(h) + math.sqrt(h * h + 4.0 * cc))
                    if h < 0.0:
                        t = -t
                    cs = 1.0 / math.sqrt(1.0 + t * t)
                sn = cs * t
                for r in range(m):
                    x, y = W[r, p], W[r, q]
                    W[r, p] = cs * x - sn * y
                    W[r, q] = sn * x + cs * y
                for r in range(n):
                    x, y = V[r, p], V[r, q]
                    V[r, p] = cs * x - sn * y
                    V[r, q] = sn * x + cs * y
        if not rotated:
            break
    for j in range(n):
        s = 0.0
        for r in range(m):
            s += W[r, j] * W[r, j]
        sv[j] = math.sqrt(s)


@register_jitable
def descending(sv, n, order):
    """``order[:n]``: the indices of ``sv[:n]`` by decreasing value (ties keep their
    order, so a basis read in that order moves continuously along a path)."""
    for j in range(n):
        order[j] = j
    for j in range(1, n):
        x = order[j]
        k = j - 1
        while k >= 0 and sv[order[k]] < sv[x]:
            order[k + 1] = order[k]
            k -= 1
        order[k + 1] = x


@register_jitable
def largest(sv, n):
    """``max(sv[:n])`` (0 for n = 0)."""
    top = 0.0
    for j in range(n):
        top = max(top, sv[j])
    return top


@register_jitable
def reset(V, n):
    """``V[:n, :n] = I``."""
    for a in range(n):
        for b in range(n):
            V[a, b] = 1.0 if a == b else 0.0


@register_jitable
def lu(X, n, LU, perm):
    """LU factors of the leading ``n × n`` block of ``X`` with partial pivoting, in
    ``LU``: the unit lower factor below the diagonal, the upper factor above it and the
    reciprocals of its diagonal on it (:func:`lu_column` multiplies by them); row
    ``perm[i]`` of ``X`` is row ``i`` of ``L U``. Returns the determinant of ``X`` (0
    when a pivot is zero, and the factors are then incomplete)."""
    for r in range(n):
        perm[r] = r
        for c in range(n):
            LU[r, c] = X[r, c]
    d = 1.0
    for j in range(n):
        p = j  # partial pivoting: the largest |LU[r, j]|, r ≥ j
        big = abs(LU[j, j])
        for r in range(j + 1, n):
            if abs(LU[r, j]) > big:
                p = r
                big = abs(LU[r, j])
        if big == 0.0:
            return 0.0
        if p != j:
            for c in range(n):
                LU[j, c], LU[p, c] = LU[p, c], LU[j, c]
            perm[j], perm[p] = perm[p], perm[j]
            d = -d
        d *= LU[j, j]
        f = 1.0 / LU[j, j]
        LU[j, j] = f
        for r in range(j + 1, n):
            g = LU[r, j] * f
            LU[r, j] = g
            for c in range(j + 1, n):
                LU[r, c] -= g * LU[j, c]
    return d


@register_jitable
def lu_column(LU, perm, n, col, x):
    """``x``: column ``col`` of ``X⁻¹`` from the factors of :func:`lu` (the solution of
    ``X x = e_col``)."""
    start = 0  # L y = P e_col: y is zero above the row that e_col moved to
    for i in range(n):
        x[i] = 0.0
        if perm[i] == col:
            start = i
    x[start] = 1.0
    for i in range(start + 1, n):
        s = 0.0
        for k in range(start, i):
            s -= LU[i, k] * x[k]
        x[i] = s
    for i in range(n - 1, -1, -1):  # U x = y
        s = x[i]
        for k in range(i + 1, n):
            s -= LU[i, k] * x[k]
        x[i] = s * LU[i, i]


@register_jitable
def certainly_invertible(X, n, LU, perm, rtol):
    """The factors of :func:`lu` of ``X`` in ``LU`` and ``perm``, and whether ``σ_min /
    σ_max > rtol`` is certain without an SVD. With ``σ_i ≤ σ_max ≤ ‖X‖_F`` and ``Π σ_i
    = |det X|``, ``σ_min / σ_max ≥ |det X| / σ_max^n ≥ |det X| / ‖X‖_F^n``, asked to
    exceed ``rtol`` by a factor :data:`CERTIFY_MARGIN` (which covers the round-off of the
    determinant). A matrix the bound does not certify is left to :func:`jacobi`; a
    certified rank is the one the SVD would give."""
    d = lu(X, n, LU, perm)
    if d == 0.0:
        return False
    f = 0.0
    for r in range(n):
        for c in range(n):
            f += X[r, c] * X[r, c]
    bound = rtol * CERTIFY_MARGIN
    bound *= bound
    for _ in range(n):
        bound *= f
    return d * d >= bound
