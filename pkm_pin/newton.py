"""The damped-Newton policy the compiled solvers share (the per-leg and platform solver of
:mod:`pkm_pin.solve`, the tree solver of :mod:`pkm_pin.tree_kernel`): written once.

* :func:`lm_damping`: the Levenberg–Marquardt damping of a relative residual;
* :func:`stop_rule`: when to stop before a step (converged, out of iterations, stalled);
* :func:`ldl`, :func:`ldl_solve`: ``L D Lᵀ`` of the normal equations, no square roots
  (dense, or within a sparse matrix's profile);
* :data:`TREE_MAX_STEP`: the cap on one step of the tree solver.

Plain functions compiled into their callers (``register_jitable``); each can be called
from Python.
"""

from __future__ import annotations

import numpy as np
from numba.extending import register_jitable

__all__ = ["TREE_MAX_STEP", "ldl", "ldl_solve", "lm_damping", "stop_rule"]

#: Largest dimensionless step of the tree solver (infinity norm: rad, or lengths ``L``
#: for translations): a longer Newton step is shortened to it, which keeps a start far
#: from closure (published models open by up to ~1 L) from jumping between branches.
TREE_MAX_STEP = 0.5


@register_jitable
def lm_damping(r):
    """:func:`pkm_pin.tolerances.damping` of the relative residual ``r``, written out for
    the compiled code (numba's cache does not follow tolerances.py; a test checks that
    the two agree)."""
    lam = 1e-10 + 1e-2 * r * r
    return lam


@register_jitable
def stop_rule(r, tol, it, max_iter, best, slow):
    """Newton's stopping rules before a step, ``(stop, best, slow)``: ``r ≤ tol``, ``it ≥
    max_iter``, or :data:`~pkm_pin.tolerances.NEWTON_SLOW_STEPS` (10) evaluations in a
    row whose ``r`` is not below ``1 − NEWTON_SLOW_RTOL`` (1e-3) times the best so far."""
    if r <= tol or it >= max_iter:
        return True, best, slow
    slow = slow + 1 if r > (1.0 - 1e-3) * best else 0
    best = min(best, r)
    return slow >= 10, best, slow


@register_jitable
def ldl(A, n, inv, first=None):
    """``A[:n, :n] = L D Lᵀ`` for the symmetric positive definite ``A``, in place on its
    lower triangle: the unit factor ``L`` below the diagonal, ``D`` on it; ``inv``
    receives ``1 / D``. No square roots (one division per column, off the critical
    path of the substitutions). False if ``A`` is not positive definite.

    ``first`` (optional): the profile of a sparse ``A``, ``first[i]`` the first column
    of row ``i`` of the lower triangle that is not zero (``i`` when none before the
    diagonal). ``L`` keeps that profile (no fill before ``first[i]``), so the sums run
    from the later of the two rows' ``first``: the terms they skip are exact zeros, and
    the factors equal the dense ones to the last bit at a fraction of the cost for the
    normal equations of a tree whose loops are local (a humanoid's legs). Without it
    (compiled away), every sum starts at column 0."""
    for j in range(n):
        fj = 0
        if first is not None:
            fj = first[j]
        d = A[j, j]
        for k in range(fj, j):
            d -= A[j, k] * A[j, k] * A[k, k]
        if not 0.0 < d < np.inf:
            return False
        A[j, j] = d
        f = 1.0 / d
        inv[j] = f
        for i in range(j + 1, n):
            fi = 0
            if first is not None:
                fi = first[i]
                if fi > j:
                    continue
            s = A[i, j]
            for k in range(max(fi, fj), j):
                s -= A[i, k] * A[j, k] * A[k, k]
            A[i, j] = s * f
    return True


@register_jitable
def ldl_solve(A, n, inv, b, x):
    """``x = A⁻¹ b`` from the factors of :func:`ldl` (``x`` may be ``b``)."""
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= A[i, k] * x[k]
        x[i] = s
    for i in range(n):
        x[i] *= inv[i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, n):
            s -= A[k, i] * x[k]
        x[i] = s

