"""Compiled inverse kinematics of output-driven motions (issue 26).

:class:`pkm_pin.trajectory._OutputDriver` solves, per sample, the closure rows and the
rows of some output pose coordinates ``c = (x, y, z, roll, pitch, yaw)`` (the output
frame's origin, world [m]; ``R = Rz(yaw) Ry(pitch) Rx(roll)``, Pinocchio's
``matrixToRpy``), each divided by its unit (:func:`pkm_pin.solve.coordinate_scales`),
the angle errors wrapped to (−π, π]. Its Python loop (the reference) costs one
Pinocchio pass and ~0.5 ms of Python per Newton step. This module runs the same damped
Newton (Levenberg–Marquardt) loop compiled on :mod:`pkm_pin.tree_kernel`'s rows: the
closure rows :func:`~pkm_pin.tree_kernel.closure_rows`, then the coordinate rows with
their Jacobian ``K = [J_p; E(rpy)⁻¹ J_ω]`` (``J_p`` the origin's world velocity
``v_O + ω × p``, ``E`` Pinocchio's WORLD rpy Jacobian). The same steps as the reference
(every column free, :func:`~pkm_pin.newton.lm_damping`, step at most
:data:`~pkm_pin.newton.TREE_MAX_STEP`, clipped to the limits), at most ``max_iter``
evaluations, stopping at ``r ≤ tol``; tests compare both drivers' configurations.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba.extending import register_jitable

from .compiling import SameTypes
from .newton import lm_damping
from .tree_kernel import (
    _relative_columns,
    closure_rows,
    newton_step,
    stepped_within,
    workspace,
)


@register_jitable
def matrix_to_rpy(R, out):
    """``out ← (roll, pitch, yaw)`` of ``R`` as Pinocchio's ``rpy.matrixToRpy`` (Eigen's
    ``eulerAngles(2, 1, 0)`` brought to pitch in [−π/2, π/2]): yaw from the first column,
    roll from yaw and the other two (defined up to pitch = ±π/2 itself)."""
    y = math.atan2(R[1, 0], R[0, 0])
    p = math.atan2(-R[2, 0], math.sqrt(R[2, 1] * R[2, 1] + R[2, 2] * R[2, 2]))
    sy, cy = math.sin(y), math.cos(y)
    r = math.atan2(sy * R[0, 2] - cy * R[1, 2], cy * R[1, 1] - sy * R[0, 1])
    out[0], out[1], out[2] = r, p, y


@register_jitable
def output_rows(k, ws, oMo, sel, target, scales, n0, e, H, c):
    """The coordinate rows ``sel`` (indices into x, y, z, roll, pitch, yaw) from row
    ``n0``: ``e = (c − target) / scale`` (angles wrapped), ``H = K / scale`` per unit of
    each velocity coordinate; ``c`` (6,) receives the coordinates. Needs
    :func:`closure_rows` evaluated at the same ``q`` (``ws.S``, ``oMo``). Returns the
    rows' largest magnitude."""
    W = ws.W
    _relative_columns(k.iv, k.kind, k.parent, 0, k.fjoint[k.fjoint.shape[0] - 1], ws.S, W)
    px, py, pz = oMo[0, 3], oMo[1, 3], oMo[2, 3]
    c[0], c[1], c[2] = px, py, pz
    rpy = c[3:]
    matrix_to_rpy(oMo, rpy)
    sp, cp = math.sin(rpy[1]), math.cos(rpy[1])
    sy, cy = math.sin(rpy[2]), math.cos(rpy[2])
    cpi = 1.0 / cp
    tp = sp * cpi
    Ei = ((cy * cpi, sy * cpi, 0.0), (-sy, cy, 0.0), (cy * tp, sy * tp, 1.0))
    worst = 0.0
    for a in range(sel.shape[0]):
        s, r = sel[a], n0 + a
        d = c[s] - target[a]
        if s >= 3:
            d = (d + math.pi) % (2.0 * math.pi) - math.pi
        e[r] = d / scales[a]
        worst = max(worst, abs(e[r]))
        for col in range(k.nv):
            wx, wy, wz = W[0, col], W[1, col], W[2, col]
            if s == 0:
                h = W[3, col] + wy * pz - wz * py
            elif s == 1:
                h = W[4, col] + wz * px - wx * pz
            elif s == 2:
                h = W[5, col] + wx * py - wy * px
            else:
                row = Ei[s - 3]
                h = row[0] * wx + row[1] * wy + row[2] * wz
            H[r, col] = h / scales[a]
    return worst


@njit(cache=True, nogil=True)
def solve_output_kernel(k, q, sel, target, scales, lower, upper, tol, max_iter, info):
    """The output driver's damped Newton (module docstring) from ``q`` (solved in
    place), every velocity coordinate free, ``lower``/``upper`` the limits the steps are
    clipped to; ``info`` receives ``(r, evaluations)``."""
    units, kind, iq, iv, nv, nq = k.units, k.kind, k.iq, k.iv, k.nv, k.nq
    n0 = k.rows[k.rows.shape[0] - 1]
    m = n0 + sel.shape[0]
    ws = workspace(k)
    H, e, Hf = np.empty((m, nv)), np.empty(m), np.empty((m, nv))
    N, g, inv, dx = np.empty((nv, nv)), np.empty(nv), np.empty(nv), np.empty(nv)
    q_new, dv, c = np.empty(nq), np.empty(nv), np.empty(6)
    norms, oMo = np.empty(k.ckind.shape[0]), np.empty((4, 4))
    r, it = np.inf, 0
    for it in range(max_iter):
        closure = closure_rows(k, q, ws, e, H, norms, oMo)
        r = max(closure, output_rows(k, ws, oMo, sel, target, scales, n0, e, H, c))
        if r <= tol:
            break
        for row in range(m):
            for b in range(nv):
                Hf[row, b] = H[row, b] * units[b]
        if not newton_step(Hf, e, m, nv, lm_damping(r), N, g, inv, dx):
            break
        for a in range(nv):
            dv[a] = units[a] * dx[a]
        if not stepped_within(kind, iq, iv, nq, q, dv, lower, upper, q_new):
            break
        for a in range(nq):
            q[a] = q_new[a]
    info[0], info[1] = r, it + 1


#: :func:`solve_output_kernel` typed once per kernel (:class:`SameTypes`).
SOLVE_OUTPUT = SameTypes(solve_output_kernel, 0)


@njit(cache=True, nogil=True)
def output_rows_compiled(k, q, sel, target, scales, e, H, c):
    """The closure rows then :func:`output_rows` at ``q`` into ``e``, ``H`` (for tests
    and one-off evaluations); returns the largest row."""
    ws, norms, oMo = workspace(k), np.empty(k.ckind.shape[0]), np.empty((4, 4))
    closure = closure_rows(k, q, ws, e, H, norms, oMo)
    n0 = k.rows[k.rows.shape[0] - 1]
    return max(closure, output_rows(k, ws, oMo, sel, target, scales, n0, e, H, c))
