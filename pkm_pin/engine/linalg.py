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
* :func:`determinant` — Gaussian elimination with partial pivoting.
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
#: Upper bound on the Jacobi sweeps (6 columns converge in 3–6 from a cold start).
JACOBI_SWEEPS = 60


@register_jitable
def jacobi(X, m, n, W, V, sv):
    """One-sided Jacobi SVD of the leading ``m × n`` block of ``X``.

    Computes ``W = X V`` with orthogonal columns: ``X = W Vᵀ``, ``W_j = σ_j u_j``.
    ``V`` (``n × n``, in/out) must be orthogonal on entry (identity, or the previous
    pose's basis as a warm start). On exit ``sv[j] = |W_j|`` (not sorted: use
    :func:`descending`). ``W``: at least ``m × n``.
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
                if cc <= JACOBI_SKIP * JACOBI_SKIP * a * b or abs(c) <= floor:
                    continue
                if cc > JACOBI_TOL * JACOBI_TOL * a * b:
                    rotated = True
                zeta = (b - a) / (2.0 * c)
                t = (1.0 if zeta >= 0 else -1.0) / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
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


@register_jitable(inline="always")
def pivot_row(A, j, n):
    """Partial pivoting: the row ``r ≥ j`` (among the first n) of the largest
    ``|A[r, j]|``."""
    p = j
    for r in range(j + 1, n):
        if abs(A[r, j]) > abs(A[p, j]):
            p = r
    return p


@register_jitable
def inverse(X, n, Xi, work):
    """``Xi = X⁻¹`` for the leading ``n × n`` block (Gauss–Jordan, partial pivoting;
    ``work``: at least ``n × n``). Returns False when a pivot is zero."""
    for r in range(n):
        for c in range(n):
            work[r, c] = X[r, c]
            Xi[r, c] = 1.0 if r == c else 0.0
    for j in range(n):
        p = pivot_row(work, j, n)
        if work[p, j] == 0.0:
            return False
        if p != j:
            for c in range(n):
                work[j, c], work[p, c] = work[p, c], work[j, c]
                Xi[j, c], Xi[p, c] = Xi[p, c], Xi[j, c]
        f = 1.0 / work[j, j]
        for c in range(n):
            work[j, c] *= f
            Xi[j, c] *= f
        for r in range(n):
            if r != j:
                g = work[r, j]
                if g != 0.0:
                    for c in range(n):
                        work[r, c] -= g * work[j, c]
                        Xi[r, c] -= g * Xi[j, c]
    return True


@register_jitable
def certainly_invertible(X, n, Xi, work, rtol):
    """``Xi = X⁻¹`` and whether ``σ_min / σ_max > rtol`` is certain without an SVD:
    ``σ_min / σ_max ≥ 1 / (‖X‖_F ‖X⁻¹‖_F)``, asked to exceed ``rtol`` by a factor
    :data:`CERTIFY_MARGIN` (which covers the round-off of the computed inverse). The
    bound is within a factor n of the ratio, so only matrices near the threshold are
    left to :func:`jacobi`; a certified rank is the one the SVD would give."""
    if not inverse(X, n, Xi, work):
        return False
    a = 0.0
    b = 0.0
    for r in range(n):
        for c in range(n):
            a += X[r, c] * X[r, c]
            b += Xi[r, c] * Xi[r, c]
    return a * b * (rtol * CERTIFY_MARGIN) ** 2 <= 1.0


@register_jitable
def determinant(M, n, work):
    """Determinant of the leading ``n × n`` block of ``M`` (partial pivoting; ``work``:
    at least ``n × n``)."""
    for r in range(n):
        for c in range(n):
            work[r, c] = M[r, c]
    d = 1.0
    for j in range(n):
        p = pivot_row(work, j, n)
        if work[p, j] == 0.0:
            return 0.0
        if p != j:
            for c in range(n):
                work[j, c], work[p, c] = work[p, c], work[j, c]
            d = -d
        d *= work[j, j]
        for r in range(j + 1, n):
            f = work[r, j] / work[j, j]
            for c in range(j, n):
                work[r, c] -= f * work[j, c]
    return d
