"""The closure solver: damped Newton (Levenberg–Marquardt) on the closure residuals of a
mechanism, the unknowns selected by a mask. Every position problem of pkm_pin uses it:
:meth:`Leg.solve`, :meth:`Mechanism.assemble`, forward and inverse kinematics, the
assembly modes, the sweeps (and, through them, sensitivity and calibration).

Residual (the one definition, :func:`closure_error` = :func:`pkm_pin.kernels.pose_error`)
-----------------------------------------------------------------------------------------
Leg ``i``'s tip placement ``T`` (world) against its target ``W = pose · anchor_i``::

    e_i = ( log3(R_W R_Tᵀ) ;  (p_W − p_T) / L_i )

the world rotation vector from the tip's orientation to the target's [rad] and the tip
displacement in units of the **leg's** characteristic length ``L_i``
(:attr:`Leg.characteristic_length`), so dimensionless; ``|e_i|`` is the leg's relative
closure error and ``closure = max_i |e_i|``. Forward kinematics adds one row per actuated
coordinate, ``(target_a − q_a) / s_a`` (``s_a``: :attr:`Mechanism.actuated_scales`);
``actuated = max_a |·|``. The solver stops when ``r = max(closure, actuated) ≤ tol``.

Unknowns and mask
-----------------
Dimensionless unknowns: each leg's joint increments (prismatic ones divided by ``L_i``,
revolute ones in rad; :attr:`Leg._velocity_units`) and the platform twist
``ξ = (ω; v_O / L)`` (axis-first ``(ω; v_O)`` about the world origin as in
:mod:`pkm_pin.screws`, ``L`` the mechanism's characteristic length; the platform moves to
``exp(ξ) · pose``). The same mechanism in millimetres takes the same steps. The mask:

* :data:`LEGS` (a): each leg's joints, the platform fixed; every leg is its own problem
  (:meth:`Leg.solve`, :meth:`Mechanism.assemble`, inverse kinematics, sweeps);
* :data:`PLATFORM` (b): all legs' joints and the platform twist;
* :data:`ACTUATED` (c): (b) plus the actuated rows (forward kinematics, assembly modes).

Step
----
A joint twist ``(ω; v_O)`` moves leg ``i``'s residual by the row ``(ω; (v_O + ω × p_T) /
L_i)``, the platform twist moves its target by ``(ω; (L v' + ω × p_W) / L_i)``: rows
``H_i Δq_i − X_i ξ = e_i``. The normal equations of the masked unknowns get the
Levenberg–Marquardt damping ``λ = damping(r)`` (:func:`pkm_pin.tolerances.damping`,
written out in :func:`lm_damping`) on every unknown; each leg's block is eliminated
(L D Lᵀ of its nv × nv block), then the 6 × 6 Schur complement gives ξ; the joint
increments are projected onto the joint limits.

Stopping rules (:mod:`pkm_pin.tolerances`): ``r ≤ tol``; ``max_iter`` steps;
``NEWTON_SLOW_STEPS`` evaluations in a row not below ``(1 − NEWTON_SLOW_RTOL)`` times the
best ``r`` (a least-squares minimum: out of reach); a step below ``NEWTON_STALL_RTOL``
(stalled at a limit); a step that is not finite or a system not positive definite.

Drivers
-------
The step is written once, as plain functions (``register_jitable``: compiled inside the
drivers, callable from Python as they are). The compiled driver evaluates the legs with
:func:`pkm_pin.kernels._fk` (:func:`solve_from`, :func:`track`, :func:`solve_system`);
the Python driver evaluates them with Pinocchio (legs the kernels cannot represent:
continuous or multi-DOF joints; one-off calls before the compiled code is ready) and runs
:func:`closure_iteration` compiled (:data:`iteration_compiled`) or as Python.

The tree solver of a general closure model (:func:`solve_tree`, below) has two drivers
too: its rows evaluated by Pinocchio, or the whole loop compiled
(:mod:`pkm_pin.tree_kernel`) for trees whose joints the compiled tree represents.

Restarts: :func:`start_configurations` (warm start, neutral, middle of the limits, N random
configurations drawn with a seed).
"""

from __future__ import annotations

import math
import warnings
from collections import namedtuple
from dataclasses import dataclass, fields
from enum import IntEnum

import numpy as np
import pinocchio as pin
from numba import njit
from numba.core.errors import NumbaIRAssumptionWarning
from numba.extending import register_jitable

from . import screws
from .compiling import SameTypes, prefer_compiled
from .engine.linalg import jacobi
from .kernels import _compose, _fk, chain_of, twist_exp
from .kernels import pose_error as closure_error
from .newton import TREE_MAX_STEP, ldl, ldl_solve, lm_damping, stop_rule
from .tolerances import CLOSURE_TOL, NEWTON_STALL_RTOL, RANK_RTOL

# numba's typed IR inlining (register_jitable(inline="always")) trips one of its own
# pedantic checks on the first compilation ("variable '…' is not in scope": the inlined
# variables are not registered in the caller's scope): harmless bookkeeping, not shown.
warnings.filterwarnings("ignore", message=r"variable '.*' is not in scope",
                        category=NumbaIRAssumptionWarning)

__all__ = ["ACTUATED", "LEGS", "PLATFORM", "POSE_COORDINATES", "ClosureSolution",
           "CoordinateSolution", "CoordinateSystem", "LegSolution", "Mask", "closure_error",
           "closure_iteration", "coordinate_errors", "coordinate_rates", "coordinate_scales",
           "pose_coordinates", "solve_chain", "solve_closure", "solve_coordinates",
           "solve_coordinates_system", "solve_from", "solve_kernel", "solve_leg",
           "solve_system", "start_configurations",
           "track"]


class Mask(IntEnum):
    """The unknowns of a solve (see the module docstring)."""

    LEGS = 0  #: (a) each leg's joints, the platform fixed
    PLATFORM = 1  #: (b) every leg's joints and the platform twist
    ACTUATED = 2  #: (c) (b) plus rows pinning the actuated coordinates to targets


LEGS, PLATFORM, ACTUATED = Mask.LEGS, Mask.PLATFORM, Mask.ACTUATED


@dataclass
class LegSolution:
    """Result of :meth:`Leg.solve` / :func:`solve_leg`.

    Attributes:
        q: Joint configuration (inside the joint limits).
        residual: Relative pose error left at ``q``: :func:`closure_error` (world rotation
            vector [rad] and tip displacement / the leg's characteristic length), from
            Pinocchio's tip placement.
        iterations: Newton iterations spent, all restarts included.
        converged: Whether ``residual <= tol``.
    """

    q: np.ndarray
    residual: float
    iterations: int
    converged: bool


@dataclass
class ClosureSolution:
    """Result of :func:`solve_closure`.

    Attributes:
        pose: Platform placement reached (``pin.SE3``, world).
        leg_q: One configuration per leg.
        residuals: (legs,) each leg's :func:`closure_error` at ``pose`` and ``leg_q``.
        closure: Their largest value.
        actuated: Largest scaled actuated error ``|target − q_a| / s_a`` (0 unless the
            mask is :data:`ACTUATED`).
        iterations: Newton steps taken (mask :data:`LEGS`: the most over the legs).
        schur_ratio: λ_min / λ_max of the 6 × 6 Schur complement of the last step (its
            platform system; 0 without a platform step).
        contracted: Whether every step after the first was at most half the previous
            (Newton's quadratic regime: no jump to another branch).
    """

    pose: pin.SE3
    leg_q: list
    residuals: np.ndarray
    closure: float
    actuated: float
    iterations: int
    schur_ratio: float = 0.0
    contracted: bool = True


# =================================================================== the step
@register_jitable
def leg_rows(T, J, units, length, nv, H):
    """Rows of a leg's residual per unit of its dimensionless unknowns: column ``c`` of
    ``H`` (6 × nv) is ``(ω; (v_O + ω × p_T) / length)`` of the joint twist ``J[:, c]``
    (axis-first world Jacobian, per unit of the coordinate) times ``units[c]``; ``p_T``
    is the tip point ``T[:3, 3]`` [m]."""
    il = 1.0 / length
    px, py, pz = T[0, 3], T[1, 3], T[2, 3]
    for c in range(nv):
        u = units[c]
        wx, wy, wz = u * J[0, c], u * J[1, c], u * J[2, c]
        H[0, c], H[1, c], H[2, c] = wx, wy, wz
        H[3, c] = (u * J[3, c] + wy * pz - wz * py) * il
        H[4, c] = (u * J[4, c] + wz * px - wx * pz) * il
        H[5, c] = (u * J[5, c] + wx * py - wy * px) * il


@register_jitable
def platform_rows(W, length, scale, X):
    """``X`` (6 × 6): how the dimensionless platform twist ``ξ = (ω; v_O / scale)`` moves
    a leg's target ``W``: ``(ω; (scale v' + ω × p_W) / length)``, ``length`` the leg's."""
    qx, qy, qz = W[0, 3] / length, W[1, 3] / length, W[2, 3] / length
    f = scale / length
    for a in range(6):
        for b in range(6):
            X[a, b] = 0.0
    for k in range(3):
        X[k, k] = 1.0
        X[3 + k, 3 + k] = f
    X[3, 1], X[3, 2] = qz, -qy
    X[4, 0], X[4, 2] = -qz, qx
    X[5, 0], X[5, 1] = qy, -qx


@register_jitable
def normal_equations(H, e, nv, lam, N, g):
    """Lower triangle of ``N = HᵀH + λ I`` and ``g = Hᵀ e`` for the first ``nv`` columns."""
    for a in range(nv):
        s = 0.0
        for k in range(6):
            s += H[k, a] * e[k]
        g[a] = s
        for b in range(a + 1):
            s = 0.0
            for k in range(6):
                s += H[k, a] * H[k, b]
            N[a, b] = s
        N[a, a] += lam


@register_jitable
def leg_step(T, J, e, r, units, length, nv, H, N, g, dq, inv):
    """One leg's damped Newton step (mask :data:`LEGS`): ``dq`` (dimensionless) from its
    rows at ``T``, ``J`` and its residual ``e`` (norm ``r``). False if the normal
    equations are not positive definite."""
    leg_rows(T, J, units, length, nv, H)
    normal_equations(H, e, nv, lm_damping(r), N, g)
    if not ldl(N, nv, inv):
        return False
    ldl_solve(N, nv, inv, g, dq)
    return True


@register_jitable
def project(q, dq, units, lower, upper):
    """``q ← q + units · dq`` projected onto ``[lower, upper]`` (in place; nq = nv).
    Returns ``(step², size², clipped)``: the squared dimensionless step taken, ``|q /
    units|²`` before it, and whether a limit cut it."""
    step = 0.0
    size = 0.0
    clipped = False
    for a in range(q.shape[0]):
        want = q[a] + units[a] * dq[a]
        new = min(upper[a], max(lower[a], want))
        clipped = clipped or new != want
        iu = 1.0 / units[a]
        d, v = (new - q[a]) * iu, q[a] * iu
        step += d * d
        size += v * v
        q[a] = new
    return step, size, clipped


@register_jitable
def all_finite(x):
    """Whether every entry of the 1-D array ``x`` is finite."""
    for a in range(x.shape[0]):
        if not math.isfinite(x[a]):
            return False
    return True


#: Work arrays of :func:`closure_iteration` (see :func:`system_workspace`).
Work = namedtuple("Work", "Ts Js Ws e H X N G B S S_last rhs inv dq xi")


@register_jitable
def system_workspace(n, mv, ntot):
    """:class:`Work` for ``n`` legs of at most ``mv`` velocity coordinates, ``ntot`` in
    all: the legs' tip placements ``Ts``, Jacobians ``Js`` and targets ``Ws`` (filled by
    the driver), then the step's arrays; ``dq`` (ntot) and ``xi`` (6) receive the step."""
    return Work(np.zeros((n, 4, 4)), np.zeros((n, 6, mv)), np.zeros((n, 4, 4)),
                np.zeros((n, 6)), np.zeros((n, 6, mv)), np.zeros((n, 6, 6)),
                np.zeros((mv, mv)), np.zeros((n, mv, 7)), np.zeros((mv, 6)),
                np.zeros((6, 6)), np.zeros((6, 6)), np.zeros(6), np.zeros(max(mv, 6)),
                np.zeros(ntot), np.zeros(6))


@register_jitable
def _couple(H, X, nv, G, B):
    """``G[:nv, :6] = B = −Hᵀ X``: the coupling of a leg's unknowns with the platform's."""
    for a in range(nv):
        for b in range(6):
            s = 0.0
            for k in range(6):
                s += H[k, a] * X[k, b]
            G[a, b] = -s
            B[a, b] = -s


@register_jitable
def _schur_update(X, e, B, G, nv, S, rhs):
    """``S += XᵀX − Bᵀ N⁻¹ B`` and ``rhs += −Xᵀe − Bᵀ N⁻¹ g`` (``G = N⁻¹ [B | g]``)."""
    for a in range(6):
        s = 0.0
        for k in range(6):
            s += X[k, a] * e[k]
        for k in range(nv):
            s += B[k, a] * G[k, 6]
        rhs[a] -= s
        for b in range(6):
            s = 0.0
            for k in range(6):
                s += X[k, a] * X[k, b]
            for k in range(nv):
                s -= B[k, a] * G[k, b]
            S[a, b] += s


@register_jitable
def system_step(coords, units, platform, act_v, qa, scales, target, lam, ws):
    """The damped least-squares step of the rows in ``ws`` (``H``, ``e``, ``X``) and the
    actuated rows ``(units_v / s_a) Δq'_v = (target_a − qa_a) / s_a``: each leg's block
    eliminated, then the 6 × 6 Schur complement in ξ (with ``platform``). Fills
    ``ws.dq`` (dimensionless joint increments) and ``ws.xi``; False if a block is not
    positive definite."""
    N, G, S, rhs, inv = ws.N, ws.G, ws.S, ws.rhs, ws.inv
    first = 0 if platform else 6  # the columns of G solved: [B | g] or g
    for a in range(6):
        rhs[a] = 0.0
        for b in range(6):
            S[a, b] = 0.0
    for i in range(coords.shape[0] - 1):
        c0, nv = coords[i], coords[i + 1] - coords[i]
        Gi = G[i]
        normal_equations(ws.H[i], ws.e[i], nv, lam, N, Gi[:, 6])
        for a in range(act_v.shape[0]):
            k = act_v[a] - c0
            if 0 <= k < nv:
                w = units[act_v[a]] / scales[a]
                N[k, k] += w * w
                Gi[k, 6] += w * (target[a] - qa[a]) / scales[a]
        if platform:
            _couple(ws.H[i], ws.X[i], nv, Gi, ws.B)
        if not ldl(N, nv, inv):
            return False
        for c in range(first, 7):
            ldl_solve(N, nv, inv, Gi[:, c], Gi[:, c])
        if platform:
            _schur_update(ws.X[i], ws.e[i], ws.B, Gi, nv, S, rhs)
    xi = ws.xi
    for k in range(6):
        xi[k] = 0.0
    if platform:
        for k in range(6):
            S[k, k] += lam
        ws.S_last[:, :] = S
        if not ldl(S, 6, inv):
            return False
        ldl_solve(S, 6, inv, rhs, xi)
    for i in range(coords.shape[0] - 1):
        c0 = coords[i]
        for k in range(coords[i + 1] - c0):
            d = G[i, k, 6]
            if platform:
                for b in range(6):
                    d -= G[i, k, b] * xi[b]
            ws.dq[c0 + k] = d
    return True


@register_jitable
def closure_iteration(coords, lengths, units, length, platform, act_v, qa, scales, target,
                      tol, it, max_iter, best, slow, residual, ws):
    """One iteration of either driver, after it has evaluated the legs into ``ws.Ts``
    (tip placements), ``ws.Js`` (axis-first world Jacobians) and ``ws.Ws`` (targets):
    the residuals (``residual[i]`` = leg i's :func:`closure_error`), the stopping rules
    (:func:`stop_rule` on ``r = max(closure, actuated)``) and, unless they stop, the
    step (:func:`system_step`, damping :func:`lm_damping` of ``r``) in ``ws.dq``,
    ``ws.xi``. Returns ``(stop, closure, actuated, best, slow)``."""
    closure = 0.0
    for i in range(coords.shape[0] - 1):
        c0, c1 = coords[i], coords[i + 1]
        r = closure_error(ws.Ts[i], ws.Ws[i], lengths[i], ws.e[i])
        residual[i] = r
        closure = max(closure, r)
        leg_rows(ws.Ts[i], ws.Js[i], units[c0:c1], lengths[i], c1 - c0, ws.H[i])
        if platform:
            platform_rows(ws.Ws[i], lengths[i], length, ws.X[i])
    act = 0.0
    for a in range(act_v.shape[0]):
        act = max(act, abs(target[a] - qa[a]) / scales[a])
    r = max(closure, act)
    stop, best, slow = stop_rule(r, tol, it, max_iter, best, slow)
    if stop:
        return True, closure, act, best, slow
    ok = system_step(coords, units, platform, act_v, qa, scales, target, lm_damping(r), ws)
    return not ok, closure, act, best, slow


#: :func:`closure_iteration` compiled, for the Python driver once it is ready
#: (:func:`pkm_pin.compiling.prefer_compiled`).
iteration_compiled = njit(cache=True, nogil=True)(closure_iteration)


# ============================================================ compiled drivers
@register_jitable
def leg_workspace(nv):
    """Work arrays of :func:`leg_newton` for legs of at most ``nv`` coordinates: T, J, H,
    e, N, g, dq, inv (``dq`` zero beyond a leg's own coordinates)."""
    return (np.empty((4, 4)), np.empty((6, nv)), np.empty((6, nv)), np.empty(6),
            np.empty((nv, nv)), np.empty(nv), np.zeros(nv), np.empty(nv))


@register_jitable
def leg_newton(chain, target, q, tol, max_iter, trust, ws):
    """Mask :data:`LEGS` for one leg (a :class:`~pkm_pin.kernels.Chain`) in compiled
    code, in place on ``q`` (its tip to ``target``, 4 × 4 world): evaluations by
    :func:`pkm_pin.kernels._fk`, the step :func:`leg_step`, the rules of
    :func:`stop_rule`. Returns ``(residual, iterations)``; the residual is that of the
    returned ``q``. With ``trust > 0`` a step taken from ``r ≤ trust`` (Newton's
    quadratic regime: the next residual is ~r²) and not cut by a limit ends the iteration
    unevaluated, and the residual returned is −r (the caller verifies). The start ``q``
    is projected onto the limits first."""
    T, J, H, e, N, g, dq, inv = ws
    lower, upper, length, units, nv = chain.lower, chain.upper, chain.length, chain.units, chain.nv
    for a in range(q.shape[0]):
        q[a] = min(upper[a], max(lower[a], q[a]))
    it = 0
    best = np.inf
    slow = 0
    while True:
        _fk(chain, q, T, J)
        r = closure_error(T, target, length, e)
        stop, best, slow = stop_rule(r, tol, it, max_iter, best, slow)
        if stop:
            return r, it
        it += 1
        if not leg_step(T, J, e, r, units, length, nv, H, N, g, dq, inv) \
                or not all_finite(dq[:nv]):
            return r, it
        step, size, clipped = project(q, dq, units, lower, upper)
        if step < 1e-30 * (1.0 + size):  # stalled (at a limit or a local minimum)
            _fk(chain, q, T, J)
            return closure_error(T, target, length, e), it
        if r <= trust and not clipped:
            return -r, it


#: :func:`leg_newton` inlined where it is called (numba's IR inlining): :func:`track`
#: calls it once per pose and leg, where a call would cost ~15 % of the sweep's leg solve.
_leg_newton_inlined = njit(inline="always")(leg_newton)


@njit(cache=True, nogil=True)
def solve_from(chain, targets, starts, tol, max_iter, Q, residual, iterations):
    """Each target (M, 4, 4) solved from each of ``starts`` (S, nq) in turn until one
    converges (:func:`leg_newton`; the restarts of :meth:`Leg.solve` and of the sweeps):
    fills ``Q`` (M, nq) and ``residual`` (M,) with the best attempt, ``iterations`` (M,)
    with the steps of all attempts. ``chain``: :attr:`ChainKernel.chain`."""
    ws = leg_workspace(chain.nv)
    q = np.empty(starts.shape[1])
    for i in range(targets.shape[0]):
        residual[i] = np.inf
        iterations[i] = 0
        for s in range(starts.shape[0]):
            q[:] = starts[s]
            r, it = leg_newton(chain, targets[i], q, tol, max_iter, 0.0, ws)
            iterations[i] += it
            if s == 0 or r < residual[i]:
                residual[i] = r
                Q[i] = q
            if r <= tol:
                break


def solve_chain(kernel, target: np.ndarray, q0, tol: float = 1e-12, max_iter: int = 50):
    """:func:`solve_from` for one leg's :class:`~pkm_pin.kernels.ChainKernel`, its tip at
    ``target`` (4×4, world) from ``q0``: ``(q, residual, iterations)``."""
    Q, res, its = np.empty((1, kernel.nv)), np.empty(1), np.zeros(1, np.int64)
    solve_from(kernel.chain, np.ascontiguousarray(target, dtype=float)[None],
               np.array(q0, dtype=float)[None], tol, max_iter, Q, res, its)
    return Q[0], float(res[0]), int(its[0])


@njit(cache=True, nogil=True)
def track(chain, targets, q_start, extrapolate, tol, max_iter, trust, Q, residual):
    """Solve the leg at each target of an ordered path (N, 4, 4) with :func:`leg_newton`,
    warm-started from the previous solution (extrapolated from the previous ones where
    ``extrapolate[i]``: linearly from two, quadratically from three where the path was
    smooth before too). Fills ``Q`` (N, nq) and ``residual`` (N,): the residual reached,
    or −r when the last step was taken from ``r ≤ trust`` and not evaluated (the caller
    verifies). A target that does not converge leaves the warm start unchanged for the
    next one. Returns the number of targets missed (neither converged nor trusted).
    ``chain``: :attr:`ChainKernel.chain`."""
    ws = leg_workspace(chain.nv)
    lower, upper = chain.lower, chain.upper
    nq = q_start.shape[0]
    hist = np.empty((3, nq))  # the last three solutions, newest at row `head`
    for k in range(3):
        hist[k] = q_start
    head = 0
    known = 1  # how many of them are consecutive solutions of this path
    q = np.empty(nq)
    misses = 0
    for i in range(targets.shape[0]):
        q1 = hist[head]
        if extrapolate[i] and i >= 1 and extrapolate[i - 1] and known >= 3:
            q2, q3 = hist[(head + 2) % 3], hist[(head + 1) % 3]
            for a in range(nq):  # quadratic through the last three
                q[a] = min(upper[a], max(lower[a], 3.0 * (q1[a] - q2[a]) + q3[a]))
        elif extrapolate[i] and known >= 2:
            q2 = hist[(head + 2) % 3]
            for a in range(nq):
                q[a] = min(upper[a], max(lower[a], 2.0 * q1[a] - q2[a]))
        else:
            for a in range(nq):
                q[a] = q1[a]
        r, _ = _leg_newton_inlined(chain, targets[i], q, tol, max_iter, trust, ws)
        residual[i] = r
        for a in range(nq):
            Q[i, a] = q[a]
        if r <= tol:  # converged, or trusted (a trusted r is negative)
            head = (head + 1) % 3
            for a in range(nq):
                hist[head, a] = q[a]
            known = known + 1 if i > 0 else 1
        else:
            misses += 1
            known = 0
    return misses


@register_jitable
def _legs_compiled(chains, pose, Q, tol, max_iter, residual):
    """Mask :data:`LEGS` on a mechanism's :class:`~pkm_pin.kernels.Chains`: every leg's
    :func:`leg_newton` for its tip at ``pose · anchor``, warm-started from ``Q``.
    Returns the most iterations of a leg."""
    W = np.empty((4, 4))
    most = 0
    mv = 0
    coords = chains.coords
    for i in range(coords.shape[0] - 1):
        mv = max(mv, coords[i + 1] - coords[i])
    ws = leg_workspace(mv)
    for i in range(coords.shape[0] - 1):
        _compose(pose, chains.anchors[i], W)
        r, it = leg_newton(chain_of(chains, i), W, Q[coords[i]:coords[i + 1]], tol, max_iter,
                           0.0, ws)
        residual[i] = r
        most = max(most, it)
    return most


@register_jitable
def _move(Q, pose, coords, units, lower, upper, length, ws, E, tmp):
    """Apply the step of ``ws`` (compiled driver): each leg's increments projected onto
    its limits, the platform moved to ``exp(ξ) · pose``. Returns ``(step², size²)``
    (dimensionless, as :func:`project`)."""
    step = 0.0
    size = 0.0
    for i in range(coords.shape[0] - 1):
        c0, c1 = coords[i], coords[i + 1]
        s, z, _ = project(Q[c0:c1], ws.dq[c0:c1], units[c0:c1], lower[c0:c1], upper[c0:c1])
        step += s
        size += z
    xi = ws.xi
    for k in range(6):
        step += xi[k] * xi[k]
    for k in range(3, 6):
        xi[k] *= length
    twist_exp(xi, E)
    _compose(E, pose, tmp)
    pose[:, :] = tmp
    return step, size


@njit(cache=True, nogil=True)
def solve_system(chains, mask, pose, Q, target, tol, max_iter, residual, out):
    """The compiled driver on a whole mechanism (its :class:`~pkm_pin.kernels.Chains`,
    :attr:`~pkm_pin.kernels.MechanismKernel.chains`): the mask's unknowns
    solved in place on ``pose`` (4 × 4) and ``Q`` (the legs' configurations one after
    the other; the start projected onto the limits), ``target``: the actuated
    coordinates (mask :data:`ACTUATED`).
    ``residual`` (legs) receives each leg's :func:`closure_error`, ``out`` (closure,
    actuated error, iterations, Schur ratio, contracted) as :class:`ClosureSolution`."""
    coords, units, lower, upper = chains.coords, chains.units, chains.lower, chains.upper
    lengths, length, scales = chains.lengths, chains.length, chains.scales
    n = coords.shape[0] - 1
    if mask == 0:
        most = _legs_compiled(chains, pose, Q, tol, max_iter, residual)
        out[0], out[1], out[2], out[3], out[4] = residual.max(), 0.0, most, 0.0, 1.0
        return
    mv = 0
    for i in range(n):
        mv = max(mv, coords[i + 1] - coords[i])
    ws = system_workspace(n, mv, coords[n])
    n_act = chains.actuated.shape[0] if mask == 2 else 0
    act_v, qa = chains.actuated[:n_act], np.empty(n_act)
    E, tmp = np.empty((4, 4)), np.empty((4, 4))
    for a in range(Q.shape[0]):  # the start, projected onto the limits
        Q[a] = min(upper[a], max(lower[a], Q[a]))
    it, best, slow, stalled, prev, contracted = 0, np.inf, 0, False, np.inf, 1.0
    while True:
        for i in range(n):
            _compose(pose, chains.anchors[i], ws.Ws[i])
            _fk(chain_of(chains, i), Q[coords[i]:coords[i + 1]], ws.Ts[i], ws.Js[i])
        for a in range(n_act):
            qa[a] = Q[act_v[a]]
        stop, closure, act, best, slow = closure_iteration(
            coords, lengths, units, length, True, act_v, qa, scales, target, tol, it,
            it if stalled else max_iter, best, slow, residual, ws)
        if stop or not (all_finite(ws.dq) and all_finite(ws.xi)):
            break
        it += 1
        step, size = _move(Q, pose, coords, units, lower, upper, length, ws, E, tmp)
        stalled = step < 1e-30 * (1.0 + size)
        step = math.sqrt(step)
        if it > 1 and step > 0.5 * prev:
            contracted = 0.0
        prev = step
    ratio = 0.0
    if it > 0:  # λ_min / λ_max of the symmetric positive definite S: its singular values
        sv = np.empty(6)
        jacobi(ws.S_last, 6, 6, np.empty((6, 6)), np.eye(6), sv)
        ratio = sv.min() / sv.max() if sv.max() > 0 else 0.0
    out[0], out[1], out[2], out[3], out[4] = closure, act, it, ratio, contracted


#: :func:`solve_system` as :func:`solve_kernel` calls it (its arguments keep their types)
_solve_system = SameTypes(solve_system, key=0)


# ===================================================== pose-coordinate rows, compiled
@register_jitable
def coordinate_rows(M, length, c, C):
    """The compiled :func:`pose_coordinates` and :func:`coordinate_rates` of a placement
    ``M`` (4 × 4): ``c`` (6) receives x, y, z [m], roll, pitch, yaw [rad] (the closed
    form; away from pitch = ±π/2 it is Pinocchio's ``matrixToRpy`` up to 2π, which the
    wrapped errors and the rates do not see), ``C`` (6 × 6) the scaled coordinate rates
    per unit of ``ξ = (ω; v_O / length)``."""
    px, py, pz = M[0, 3] / length, M[1, 3] / length, M[2, 3] / length
    for k in range(3):
        c[k] = M[k, 3]
    c[4] = math.atan2(-M[2, 0], math.sqrt(M[0, 0] * M[0, 0] + M[1, 0] * M[1, 0]))
    c[5] = math.atan2(M[1, 0], M[0, 0])
    c[3] = math.atan2(M[2, 1], M[2, 2])
    for a in range(6):
        for b in range(6):
            C[a, b] = 0.0
    C[0, 1], C[0, 2], C[1, 0], C[1, 2], C[2, 0], C[2, 1] = pz, -py, -pz, px, py, -px
    C[0, 3] = C[1, 4] = C[2, 5] = 1.0
    cp, tp = math.cos(c[4]), math.tan(c[4])
    sy, cy = math.sin(c[5]), math.cos(c[5])
    C[3, 0], C[3, 1] = cy / cp, sy / cp
    C[4, 0], C[4, 1] = -sy, cy
    C[5, 0], C[5, 1], C[5, 2] = cy * tp, sy * tp, 1.0


@register_jitable
def _coordinate_errors(M, rows, values, length, c, C, d):
    """``d`` ← :func:`coordinate_errors` at ``M`` (``c``, ``C`` filled on the way);
    returns ``max |d|``."""
    coordinate_rows(M, length, c, C)
    worst = 0.0
    for j in range(rows.shape[0]):
        k = rows[j]
        x = values[j] - c[k]
        if k >= 3:
            x = -((-x + np.pi) % (2 * np.pi) - np.pi)
            d[j] = x
        else:
            d[j] = x / length
        worst = max(worst, abs(d[j]))
    return worst


@register_jitable
def _closure_matrix(chains, pose, Q, ws, residual, A):
    """Evaluate the legs (``ws``) at ``pose`` and ``Q`` and fill ``A`` (6 legs × Σ nv +
    6): the rows ``H_i Δq_i − X_i ξ = e_i`` of :class:`CoordinateSystem`. Returns the
    closure (largest leg residual)."""
    coords, lengths, units = chains.coords, chains.lengths, chains.units
    ntot = coords[coords.shape[0] - 1]
    closure = 0.0
    for i in range(coords.shape[0] - 1):
        c0, c1 = coords[i], coords[i + 1]
        _compose(pose, chains.anchors[i], ws.Ws[i])
        _fk(chain_of(chains, i), Q[c0:c1], ws.Ts[i], ws.Js[i])
        r = closure_error(ws.Ts[i], ws.Ws[i], lengths[i], ws.e[i])
        residual[i] = r
        closure = max(closure, r)
        leg_rows(ws.Ts[i], ws.Js[i], units[c0:c1], lengths[i], c1 - c0, ws.H[i])
        platform_rows(ws.Ws[i], lengths[i], chains.length, ws.X[i])
        for a in range(6):
            for b in range(c1 - c0):
                A[6 * i + a, c0 + b] = ws.H[i, a, b]
            for b in range(6):
                A[6 * i + a, ntot + b] = -ws.X[i, a, b]
    return closure


@register_jitable
def coordinate_step(A, e, C, rows, d, lam, rank_rtol, W, V, sv, z):
    """:meth:`CoordinateSystem.step` in compiled code: ``z`` ← the closure rows ``A z =
    e`` solved by the damped pseudo-inverse (rank: singular values above ``rank_rtol``
    times the largest), then the coordinate rows ``C_rows ξ = d`` by damped least squares
    on the null space of ``A``. The SVD is the engine's one-sided Jacobi
    (:func:`pkm_pin.engine.linalg.jacobi`: ``A V = W``, ``W_j = σ_j u_j``), ``V`` (in/out,
    orthogonal) warm-started from the last step's. Returns ``max |C_rows ξ|`` (the
    coordinate change the step makes)."""
    m = A.shape[1]
    ntot = m - 6
    jacobi(A, A.shape[0], m, W, V, sv)
    top = 0.0
    for j in range(m):
        top = max(top, sv[j])
    for a in range(m):
        z[a] = 0.0
    free = np.empty(m, np.int64)
    f = 0
    for j in range(m):
        if top > 0 and sv[j] > rank_rtol * top:
            w = 0.0
            for a in range(e.shape[0]):
                w += W[a, j] * e[a]
            w /= sv[j] * sv[j] + lam
            for a in range(m):
                z[a] += V[a, j] * w
        else:
            free[f] = j
            f += 1
    k = rows.shape[0]
    if k > 0 and f > 0:
        G = np.zeros((k, f))
        rhs = np.empty(k)
        for i in range(k):
            x = d[i]
            for b in range(6):
                x -= C[rows[i], b] * z[ntot + b]
                for j in range(f):
                    G[i, j] += C[rows[i], b] * V[ntot + b, free[j]]
            rhs[i] = x
        N = G.T @ G
        for j in range(f):
            N[j, j] += lam
        y = np.linalg.solve(N, G.T @ rhs)
        for j in range(f):
            for a in range(m):
                z[a] += V[a, free[j]] * y[j]
    worst = 0.0
    for i in range(k):
        x = 0.0
        for b in range(6):
            x += C[rows[i], b] * z[ntot + b]
        worst = max(worst, abs(x))
    return worst


@njit(cache=True, nogil=True)
def solve_coordinates_system(chains, pose, Q, rows, values, rank_rtol, tol, max_iter,
                             residual, out):
    """:func:`solve_coordinates` compiled on a mechanism's
    :class:`~pkm_pin.kernels.Chains` (legs evaluated by :func:`pkm_pin.kernels._fk`): the
    same rows, step (:func:`coordinate_step`), damping and stopping rules, in place on
    ``pose`` (4 × 4) and ``Q`` (the start projected onto the limits). ``residual``
    receives each leg's closure error, ``out`` (closure, coordinates, iterations)."""
    coords, units, lower, upper = chains.coords, chains.units, chains.lower, chains.upper
    n = coords.shape[0] - 1
    ntot = coords[n]
    mv = 0
    for i in range(n):
        mv = max(mv, coords[i + 1] - coords[i])
    ws = system_workspace(n, mv, ntot)
    A = np.zeros((6 * n, ntot + 6))
    e = ws.e[:n].reshape(6 * n)  # a view: filled by each evaluation
    z = np.empty(ntot + 6)
    c, C, d = np.empty(6), np.empty((6, 6)), np.empty(rows.shape[0])
    W, V, sv = np.empty((6 * n, ntot + 6)), np.eye(ntot + 6), np.empty(ntot + 6)
    E, tmp = np.empty((4, 4)), np.empty((4, 4))
    for a in range(ntot):
        Q[a] = min(upper[a], max(lower[a], Q[a]))
    it, best, slow, stalled = 0, np.inf, 0, False
    while True:
        closure = _closure_matrix(chains, pose, Q, ws, residual, A)
        worst = _coordinate_errors(pose, rows, values, chains.length, c, C, d)
        if stalled:
            break
        change = coordinate_step(A, e, C, rows, d, lm_damping(max(closure, worst)),
                                 rank_rtol, W, V, sv, z)
        stop, best, slow = stop_rule(max(closure, change), tol, it, max_iter, best, slow)
        if stop or not all_finite(z):
            break
        it += 1
        ws.dq[:] = z[:ntot]
        ws.xi[:] = z[ntot:]
        step, size = _move(Q, pose, coords, units, lower, upper, chains.length, ws, E, tmp)
        stalled = step < 1e-30 * (1.0 + size)
    out[0], out[1], out[2] = closure, worst, it


#: :func:`solve_coordinates_system` as :func:`solve_coordinates` calls it
_solve_coordinates_system = SameTypes(solve_coordinates_system, key=0)


@njit(cache=True, nogil=True)
def closure_matrix(chains, pose, Q, residual, A, e):
    """:class:`CoordinateSystem`'s rows in compiled code: ``A`` (6 legs × Σ nv + 6) and
    ``e`` (6 legs) at ``pose`` (4 × 4) and ``Q``, ``residual`` each leg's closure error;
    returns the closure."""
    coords = chains.coords
    n = coords.shape[0] - 1
    mv = 0
    for i in range(n):
        mv = max(mv, coords[i + 1] - coords[i])
    ws = system_workspace(n, mv, coords[n])
    closure = _closure_matrix(chains, pose, Q, ws, residual, A)
    for i in range(n):
        for a in range(6):
            e[6 * i + a] = ws.e[i, a]
    return closure


#: :func:`closure_matrix` as :class:`CoordinateSystem` calls it
_closure_matrix_compiled = SameTypes(closure_matrix, key=0)


# =============================================================== Python driver
def _evaluate(legs, anchors, pose, leg_q, ws) -> None:
    """The Python driver's evaluation: one Pinocchio pass per leg (joint Jacobians and
    tip frame) into ``ws.Ts`` (world tip placements) and ``ws.Js`` (axis-first world
    Jacobians), and the targets ``pose · anchor`` into ``ws.Ws``."""
    for i, (leg, anchor, q) in enumerate(zip(legs, anchors, leg_q)):
        data = leg._jacobian_pass(q)
        ws.Ts[i] = (leg.base * data.oMf[leg.tip_id]).homogeneous
        ws.Js[i, :, :leg.nv] = leg._world_jacobian(data)
        ws.Ws[i] = (pose * anchor).homogeneous


def _newton_pinocchio(legs, anchors, pose: pin.SE3, leg_q, mask, target, scales, length,
                      tol, max_iter) -> ClosureSolution:
    """The Python driver: the legs evaluated by Pinocchio, the step of
    :func:`closure_iteration` (compiled once ready), joint increments applied by
    ``pin.integrate`` (any joint) and projected onto the limits. Mask :data:`PLATFORM` or
    :data:`ACTUATED` on the legs together, or :data:`LEGS` for one leg. The starts are
    projected onto the limits first."""
    n = len(legs)
    coords = np.r_[0, np.cumsum([leg.nv for leg in legs])].astype(np.int64)
    lengths = np.array([leg.characteristic_length for leg in legs], dtype=float)
    units = np.concatenate([leg._velocity_units for leg in legs])
    platform = mask != LEGS
    if mask == ACTUATED:
        act_v = np.concatenate([c + leg.actuated_v for c, leg in zip(coords, legs)]
                               ).astype(np.int64)
        target, scales = np.asarray(target, dtype=float), np.asarray(scales, dtype=float)
    else:
        act_v, target, scales = np.empty(0, np.int64), np.empty(0), np.empty(0)
    ws = system_workspace(n, int(max(np.diff(coords))), int(coords[-1]))
    iterate = iteration_compiled if prefer_compiled(iteration_compiled) else closure_iteration
    residual = np.empty(n)
    leg_q = [leg.clip(np.array(q, dtype=float)) for leg, q in zip(legs, leg_q)]
    it, best, slow, stalled, prev, contracted = 0, np.inf, 0, False, np.inf, True
    while True:
        _evaluate(legs, anchors, pose, leg_q, ws)
        qa = np.array([q[k] for leg, q in zip(legs, leg_q) for k in leg.actuated_q]
                      if mask == ACTUATED else [], dtype=float)
        stop, closure, act, best, slow = iterate(
            coords, lengths, units, length, platform, act_v, qa, scales, target, tol, it,
            it if stalled else max_iter, best, slow, residual, ws)
        if stop or not (np.all(np.isfinite(ws.dq)) and np.all(np.isfinite(ws.xi))):
            break
        it += 1
        pose, leg_q, step, size = _apply(legs, pose, leg_q, ws.dq, ws.xi if platform else None,
                                         coords, units, length)
        stalled = step < NEWTON_STALL_RTOL * (1.0 + size)
        contracted = contracted and not (it > 1 and math.sqrt(step) > 0.5 * prev)
        prev = math.sqrt(step)
    ratio = 0.0
    if platform and it > 0:
        sv = np.linalg.svd(ws.S_last, compute_uv=False)
        ratio = float(sv[-1] / sv[0]) if sv[0] > 0 else 0.0
    return ClosureSolution(pose, leg_q, residual.copy(), float(closure), float(act), it,
                           ratio, contracted)


# ==================================================================== the API
def start_configurations(leg, warm=None, count: int = 0, seed: int = 0) -> np.ndarray:
    """The restart recipe: (S, nq) start configurations of ``leg``, in this order: the
    warm start ``warm`` (when given; projected onto the limits), the neutral
    configuration (inside the limits), the middle of the limits (neutral where a limit
    is infinite), and ``count`` configurations drawn uniformly inside the limits by
    ``numpy.random.default_rng(seed)`` (:meth:`Leg.random_configuration`). The same
    arguments give the same starts."""
    lo, up = leg._bounds
    bounded = np.isfinite(lo) & np.isfinite(up)  # inf + (−inf) is nan: add only bounded
    middle = np.where(bounded, 0.5 * (np.where(bounded, lo, 0.0) + np.where(bounded, up, 0.0)),
                      leg.neutral())
    rng = np.random.default_rng(seed)
    rows = [] if warm is None else [leg.clip(np.asarray(warm, dtype=float))]
    rows += [leg.neutral(), middle] + [leg.random_configuration(rng) for _ in range(count)]
    return np.ascontiguousarray(rows, dtype=float)


def solve_leg(leg, target: pin.SE3, starts, *, tol: float = CLOSURE_TOL, max_iter: int = 100,
              compiled: bool = False) -> LegSolution:
    """Mask :data:`LEGS` for one leg: its tip to ``target`` (world), from each row of
    ``starts`` (S, nq) in turn until one converges; the best attempt, its iterations
    those of every attempt. ``compiled``: the compiled driver when the leg has a kernel
    (every configuration it returns is evaluated again by Pinocchio, whose residual is
    reported, and a near miss is polished by the Python driver); else the Python one."""
    starts = np.atleast_2d(np.asarray(starts, dtype=float))
    kernel = leg.kernel if compiled else None
    if kernel is not None:
        Q, res, its = np.empty((1, leg.nq)), np.empty(1), np.zeros(1, np.int64)
        solve_from(kernel.chain, target.homogeneous[None], starts, tol, max_iter, Q,
                   res, its)
        sol = _solve_one(leg, target, Q[0], tol, max_iter if res[0] <= tol else 0)
        sol.iterations += int(its[0])
        return sol
    best, iterations = None, 0
    for q0 in starts:
        sol = _solve_one(leg, target, q0, tol, max_iter)
        iterations += sol.iterations
        if best is None or sol.residual < best.residual:
            best = sol
        if best.converged:
            break
    best.iterations = iterations
    return best


def _solve_one(leg, target: pin.SE3, q0, tol: float, max_iter: int) -> LegSolution:
    """The Python driver for one leg from ``q0``."""
    s = _newton_pinocchio([leg], [pin.SE3.Identity()], target, [q0], LEGS, None, None,
                          leg.characteristic_length, tol, max_iter)
    return LegSolution(s.leg_q[0], s.closure, s.iterations, s.closure <= tol)


def solve_kernel(kernel, mask: Mask, pose: np.ndarray, Q: np.ndarray, target=None, *,
                 tol: float = CLOSURE_TOL, max_iter: int = 50) -> tuple[np.ndarray, np.ndarray]:
    """:func:`solve_system` on a :class:`~pkm_pin.kernels.MechanismKernel`, in place on
    ``pose`` (4 × 4) and ``Q`` (concatenated leg configurations). Returns ``(residual,
    out)``: each leg's closure error and (closure, actuated error, iterations, Schur
    ratio, contracted)."""
    if not (pose.dtype == Q.dtype == np.float64 and pose.ndim == 2 and Q.ndim == 1
            and pose.flags.c_contiguous and Q.flags.c_contiguous):  # solved in place
        raise TypeError("solve_kernel: pose and Q must be C-ordered float64 arrays of "
                        "dimensions 2 and 1")
    residual, out = np.empty(len(kernel.lengths)), np.empty(5)
    # without actuated targets any float array of their length will do (not read)
    target = kernel.scales if target is None else np.ascontiguousarray(target, dtype=float)
    _solve_system(kernel.chains, int(mask), pose, Q, target, float(tol), int(max_iter),
                  residual, out)
    return residual, out


def solve_closure(mech, pose, leg_q, mask: Mask = LEGS, target=None, *,
                  tol: float = CLOSURE_TOL, max_iter: int = 50,
                  compiled: bool | None = None) -> ClosureSolution:
    """The closure solver on a mechanism: the unknowns of ``mask`` from the platform pose
    ``pose`` (``pin.SE3``) and the leg configurations ``leg_q``; ``target``: the actuated
    coordinates (mask :data:`ACTUATED`). ``compiled``: the compiled driver when every
    leg has a kernel (default: when its code is ready,
    :func:`pkm_pin.compiling.prefer_compiled`); else the Python driver (Pinocchio)."""
    if mask == ACTUATED and target is None:
        raise ValueError("mask ACTUATED needs the target actuated coordinates")
    kernel = mech.kernel if compiled is not False else None
    if kernel is not None and (compiled or prefer_compiled(solve_system)):
        M, Q = pose.homogeneous.copy(), np.concatenate(leg_q).astype(float)
        residual, out = solve_kernel(kernel, mask, M, Q, target, tol=tol, max_iter=max_iter)
        c = kernel.coords
        return ClosureSolution(pin.SE3(M), [Q[c[i]:c[i + 1]].copy() for i in range(len(c) - 1)],
                               residual, float(out[0]), float(out[1]), int(out[2]),
                               float(out[3]), bool(out[4] == 1.0))
    L = mech.characteristic_length
    if mask != LEGS:
        return _newton_pinocchio(mech.legs, mech.anchors, pose, leg_q, mask, target,
                                 mech.actuated_scales, L, tol, max_iter)
    sols = [_newton_pinocchio([leg], [pin.SE3.Identity()], pose * anchor, [q], LEGS, None,
                              None, L, tol, max_iter)
            for leg, anchor, q in zip(mech.legs, mech.anchors, leg_q)]
    residuals = np.array([s.closure for s in sols])
    return ClosureSolution(pose, [s.leg_q[0] for s in sols], residuals,
                           float(residuals.max()), 0.0, max(s.iterations for s in sols))


# ============================================================ the tree solver
# The closure solver of a general closed-loop mechanism (pkm_pin.model.ClosureModel):
# one kinematic tree, its closures, optional rows pinning the actuated joints and the
# output frame. Same damping (lm_damping) and stopping rules (stop_rule, the stall test)
# as the per-leg solver above; plain numpy + Pinocchio, one Pinocchio pass a step.



@dataclass(frozen=True)
class TreeSolution:
    """Result of :func:`solve_tree`.

    Attributes:
        q: Configuration of the tree (nq,), inside the limits of its 1-DOF joints.
        residual: ``max(closure, actuated, pose)``: the quantity compared with ``tol``.
        closure: Largest norm of one closure's residual rows (dimensionless, as
            :meth:`ClosureModel.closure_residual`).
        actuated: Largest ``|q_a − target_a| / s_a`` (0 without targets).
        pose: Norm of the (selected) output pose error rows (0 without a pose target).
        iterations: Newton steps taken.
        converged: Whether ``residual <= tol``.
        closure_norms: Norm of each closure's residual rows at ``q`` (None when the
            last evaluation was not at ``q``).
        output_placement: World placement of the output frame at ``q`` (or None, alike).
    """

    q: np.ndarray
    residual: float
    closure: float
    actuated: float
    pose: float
    iterations: int
    converged: bool
    closure_norms: np.ndarray | None = None
    output_placement: pin.SE3 | None = None


def tree_limits(model) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper limits (nq,) of the tree's coordinates that :func:`solve_tree`
    enforces: a 1-DOF joint's (nq = nv = 1) finite position limits; ±inf elsewhere.
    Pinocchio's default "no limit" (the largest float) counts as none, and so does an
    empty range ``lower == upper``: a URDF ``<limit>`` without ``lower``/``upper`` (as
    CAD exporters write, e.g. Gepetto's published models) reads as [0, 0], and a joint
    that may not move would have been written ``fixed``. Read-only arrays, made once
    per model."""
    return model._plan.limits


class _Pass:
    """One evaluation of the tree solver's rows at ``q`` (one Pinocchio pass)."""

    def __init__(self, model, q, targets, pose, pose_rows):
        residual, Jc, Jo, oMo = model._pass(q, model._work_data())
        self.norms, self.output_placement = model.closure_norms(residual), oMo
        e, H = [residual], [Jc]
        closure = float(self.norms.max(initial=0.0))
        actuated = pose_err = 0.0
        if targets is not None:
            plan = model._plan
            ea = (plan.actuated_values(q, model) - targets) / plan.act_scales
            e.append(ea)
            H.append(plan.act_rows)
            actuated = float(np.abs(ea).max(initial=0.0))
        if pose is not None:
            ep, Hp = _pose_error(model, oMo, Jo, pose)
            e.append(pose_rows @ ep)
            H.append(pose_rows @ Hp)
            pose_err = float(np.linalg.norm(e[-1]))
        self.e, self.H = np.concatenate(e), np.vstack(H)
        self.parts = (closure, actuated, pose_err)


def pose_error_rows(model, kin, target: pin.SE3) -> tuple[np.ndarray, np.ndarray]:
    """The output frame's pose error against ``target`` and its Jacobian (per unit of
    v) from ``kin`` (:meth:`ClosureModel.kinematics`): ``log6(target⁻¹ · oMo)``
    axis-first ``(θ [rad]; ρ / L)``, in the target's axes (so frame-invariant), ``L`` =
    :attr:`ClosureModel.length`. For a point output (:attr:`ClosureModel.output_point`)
    the rotation rows are zero and the linear rows the position error ``(p − p_target) /
    L`` in world axes."""
    return _pose_error(model, kin.output_placement, kin.output_jacobian, target)


def _pose_error(model, oMo: pin.SE3, Jo: np.ndarray, target: pin.SE3):
    """:func:`pose_error_rows` from the output placement and Jacobian."""
    if model.output_point:
        e = np.r_[np.zeros(3), oMo.translation - target.translation]
        return e / np.r_[1.0, 1.0, 1.0, [model.length] * 3], Jo / model.length
    M = target.actInv(oMo)
    e = screws.log(M)
    local = screws.adjoint(oMo.inverse()) @ Jo
    H = screws.from_pinocchio(pin.Jlog6(M) @ screws.to_pinocchio(local))
    e[3:] /= model.length
    H[3:] /= model.length
    return e, H


def tree_step(model, q, e, H, free, r, lo, up):
    """One damped Newton step on the free coordinates (``None``: all; columns scaled by
    the velocity units), at most :data:`TREE_MAX_STEP`; returns ``(q_new, dimensionless
    step²)``."""
    units = model.velocity_units if free is None else model.velocity_units[free]
    Hf = (H if free is None else H[:, free]) * units
    N = Hf.T @ Hf
    N.flat[::N.shape[0] + 1] += lm_damping(r)
    dx = -np.linalg.solve(N, Hf.T @ e)
    big = np.abs(dx).max(initial=0.0)
    if big > TREE_MAX_STEP:
        dx *= TREE_MAX_STEP / big
    if free is None:
        dv = units * dx
    else:
        dv = np.zeros(model.nv)
        dv[free] = units * dx
    return np.clip(pin.integrate(model.tree, q, dv), lo, up), float(dx @ dx)


def solve_tree(model, q0, free=None, targets=None, pose: pin.SE3 | None = None, *,
               pose_rows=None, tol: float = CLOSURE_TOL, max_iter: int = 100,
               compiled: bool | None = None) -> TreeSolution:
    """Damped Newton (Levenberg–Marquardt) on a closure model's residual from ``q0``.

    Unknowns: the velocity coordinates selected by the boolean mask ``free`` (nv,;
    default all), in dimensionless units (``v / velocity_units``); a step is integrated
    with ``pin.integrate`` and 1-DOF joints are clipped to their finite limits
    (:func:`tree_limits`). Rows: every closure (:meth:`ClosureModel.closure_residual`);
    with ``targets`` (one value per actuated joint [rad or m]) the rows ``(q_a −
    target_a) / s_a`` (``s_a`` the joint's velocity unit); with ``pose`` the output
    frame's :func:`pose_error_rows`, multiplied by ``pose_rows`` (k × 6, default the
    identity: the components of the pose that are targeted). Damping :func:`lm_damping`
    of ``r = max(closure, actuated, pose)``; stops on :func:`stop_rule` (``r ≤ tol``,
    ``max_iter``, slow progress) or a step below ``NEWTON_STALL_RTOL`` (stalled).

    Drivers: a tree whose joints :mod:`pkm_pin.tree_kernel` represents is solved by its
    compiled loop (the same steps, every row block, closures, actuated and output pose,
    evaluated in compiled code)
    when ``compiled`` is true or, by default, when that code is ready
    (:func:`pkm_pin.compiling.prefer_compiled`: a one-off call on a fresh installation
    does not wait for a compilation); otherwise one Pinocchio pass a step."""
    q = model.check_q(q0).copy()
    pose_rows = _EYE6 if pose_rows is None else np.asarray(pose_rows, float)
    if compiled is not False:
        tk = _TREE_KERNEL or _tree_kernel_module()
        kern = tk.tree_kernel(model) if tk.ENABLED or compiled else None
        if kern is not None and (compiled or prefer_compiled(tk.solve_tree_kernel)):
            return _solve_tree_compiled(tk, kern, q, free, targets, tol, max_iter, pose,
                                        pose_rows, model.output_point)
    free = None if free is None else np.asarray(free, bool)
    if free is not None and free.all():
        free = None
    lo, up = tree_limits(model)
    q = np.clip(q, lo, up)
    best, slow, it, at_q = np.inf, 0, 0, True
    while True:
        ev = _Pass(model, q, targets, pose, pose_rows)
        r = max(ev.parts)
        stop, best, slow = stop_rule(r, tol, it, max_iter, best, slow)
        if stop or (free is not None and not free.any()):
            break
        q_new, step = tree_step(model, q, ev.e, ev.H, free, r, lo, up)
        if not np.all(np.isfinite(q_new)):
            break
        it += 1
        moved = pin.difference(model.tree, q, q_new) / model.velocity_units
        q = q_new
        if float(moved @ moved) < NEWTON_STALL_RTOL * (1.0 + step):
            at_q = False  # the last evaluation is at the previous q
            break
    return TreeSolution(q, r, *ev.parts, it, bool(r <= tol), ev.norms if at_q else None,
                        ev.output_placement if at_q else None)


_NO_TARGETS = np.zeros(0)
_NO_ROWS = np.zeros((0, 6))
_EYE4, _EYE6 = np.eye(4), np.eye(6)
_FLOAT = np.dtype(np.float64)
_TREE_KERNEL = None


def _tree_kernel_module():
    """:mod:`pkm_pin.tree_kernel` (imported on first use: it imports this module)."""
    global _TREE_KERNEL
    from . import tree_kernel

    _TREE_KERNEL = tree_kernel
    return tree_kernel


def _solve_tree_compiled(tk, kern, q, free, targets, tol, max_iter, pose=None,
                         pose_rows=None, point=False) -> TreeSolution:
    """:func:`solve_tree` by :func:`pkm_pin.tree_kernel.solve_tree_kernel` (``q``: a
    checked copy of the start, solved in place)."""
    if free is None:
        free = kern.all_free
    else:
        free = np.ascontiguousarray(free, dtype=np.bool_)
        if free.shape != (kern.nv,):
            raise ValueError(f"free must have one entry per velocity coordinate ({kern.nv})")
    has = targets is not None
    t = targets if type(targets) is np.ndarray and targets.dtype is _FLOAT \
        and targets.flags.c_contiguous else \
        np.ascontiguousarray(targets, dtype=np.float64) if has else _NO_TARGETS
    if has and t.shape != kern.act_q.shape:
        raise ValueError(f"targets must have one value per actuated joint ({len(kern.act_q)})")
    if pose is None:
        target, P = _EYE4, _NO_ROWS
    else:
        target = np.ascontiguousarray(pose.homogeneous, dtype=np.float64)
        P = np.ascontiguousarray(pose_rows, dtype=np.float64)
        if P.ndim != 2 or P.shape[1] != 6:
            raise ValueError("pose_rows must be a (k, 6) array")
    norms, oMo, info = np.empty(kern.ckind.shape[0]), np.empty((4, 4)), np.empty(7)
    tk.SOLVE(kern, q, free, has, t, target, bool(point), P, float(tol), int(max_iter), norms,
             oMo, info)
    r, closure, actuated, iterations, converged, at_q, perr = info.tolist()
    return _tree_solution(q, r, closure, actuated, perr, int(iterations), converged == 1.0,
                          norms if at_q else None, pin.SE3(oMo) if at_q else None)


_TREE_SOLUTION_FIELDS = tuple(f.name for f in fields(TreeSolution))


def _tree_solution(*values) -> TreeSolution:
    """``TreeSolution(*values)`` (every field given) without the frozen dataclass's
    ``__init__``, which sets each field through ``object.__setattr__`` (~1 µs a solve
    of a small tree)."""
    sol = object.__new__(TreeSolution)
    sol.__dict__.update(zip(_TREE_SOLUTION_FIELDS, values))
    return sol


def tree_starts(model, warm=None, count: int = 0, seed: int = 0) -> np.ndarray:
    """Restart configurations (S, nq) of a closure model's tree, in this order: the warm
    start (when given), ``model.reference``, ``pinocchio.neutral``, the middle of the
    limits (the reference where a limit is infinite), and ``count`` configurations drawn
    by ``numpy.random.default_rng(seed)``: each 1-DOF joint uniformly in its finite
    limits (a revolute without limits in [−π, π]), other coordinates as in the
    reference. All clipped to :func:`tree_limits`."""
    return np.array(list(iter_tree_starts(model, warm, count, seed)), dtype=float)


def iter_tree_starts(model, warm=None, count: int = 0, seed: int = 0):
    """The rows of :func:`tree_starts`, made one at a time (a solve that converges from
    the warm start makes none of the others)."""
    lo, up = tree_limits(model)
    if warm is not None:  # np.clip's wrapper costs more than the solve of a small tree
        warm = model.check_q(warm)
        yield np.minimum(np.maximum(warm, lo), up) if _limited(model) else warm.copy()
    ref = np.array(model.reference)
    middle = np.where(np.isfinite(lo), 0.5 * (np.nan_to_num(lo) + np.nan_to_num(up)), ref)
    for row in (ref, pin.neutral(model.tree), middle):
        yield np.clip(row, lo, up)
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield np.clip(_random_tree_q(model, rng, lo, up), lo, up)


def _limited(model) -> bool:
    """Whether a coordinate has a finite limit of :func:`tree_limits` (kept on the
    model: without one, clipping a start is a copy)."""
    cached = model.__dict__.get("_tree_limited")
    if cached is None:
        lo, up = tree_limits(model)
        cached = bool(np.isfinite(lo).any() or np.isfinite(up).any())
        object.__setattr__(model, "_tree_limited", cached)
    return cached


def _random_tree_q(model, rng, lo, up) -> np.ndarray:
    """One random configuration of :func:`tree_starts`."""
    q = np.array(model.reference)
    tree = model.tree
    for j in range(1, tree.njoints):
        joint, i = tree.joints[j], tree.joints[j].idx_q
        if joint.nv != 1:
            continue
        if joint.nq == 1 and np.isfinite(lo[i]):
            q[i] = rng.uniform(lo[i], up[i])
        elif joint.nq == 1 and not model.translating[joint.idx_v]:
            q[i] = rng.uniform(-np.pi, np.pi)
        elif joint.nq == 2:
            a = rng.uniform(-np.pi, np.pi)
            q[i], q[i + 1] = np.cos(a), np.sin(a)
    return q


def solve_tree_starts(model, starts, free=None, targets=None, pose=None, *, pose_rows=None,
                      nearest=None, tol: float = CLOSURE_TOL, max_iter: int = 100,
                      keep_first: bool = True) -> tuple[TreeSolution, int]:
    """:func:`solve_tree` from each row of ``starts`` (an array, or any iterable of
    configurations such as :func:`iter_tree_starts`) in turn. The first start's
    solution is kept when it converges (the branch continued from a warm start; not
    with ``keep_first=False``: the warm start was tried before these rows);
    otherwise every start is solved and, among those that converge, the one nearest
    ``nearest`` (default the first start; distance ``|pin.difference / velocity_units|``)
    is kept; none converging: the smallest residual. Returns ``(solution, total
    iterations)``."""
    if isinstance(starts, np.ndarray):
        starts = np.atleast_2d(starts)
    first = None
    found, total = [], 0
    for k, q0 in enumerate(starts):
        sol = solve_tree(model, q0, free, targets, pose, pose_rows=pose_rows, tol=tol,
                         max_iter=max_iter)
        total += sol.iterations
        found.append(sol)
        if k == 0 and keep_first and sol.converged:
            return sol, total
        if first is None:
            first = q0
    good = [s for s in found if s.converged]
    if not good:
        return min(found, key=lambda s: s.residual), total
    ref = model.check_q(first if nearest is None else nearest)

    def distance(s):
        d = pin.difference(model.tree, ref, s.q) / model.velocity_units
        return float(d @ d)
    return min(good, key=distance), total


# ================================================= pose-coordinate rows (Python driver)
# Partial poses (:func:`pkm_pin.position.complete_pose`) and the projection of a pose
# onto the motion manifold add rows fixing some of the platform's pose coordinates to the
# closure rows. The closure rows are solved exactly and the coordinate rows in the least-
# squares sense on the motions that keep the closure (the null space of the closure rows):
# with as many independent coordinates as the mechanism's DOF the coordinates are reached,
# with more (a full 6-D pose off the manifold) the pose closest to them is found.

#: Pose coordinates of the platform: its origin x, y, z [m] and URDF roll, pitch, yaw
#: [rad] (``R = Rz(yaw) Ry(pitch) Rx(roll)``), the order of a 6-number pose.
POSE_COORDINATES = ("x", "y", "z", "roll", "pitch", "yaw")


def pose_coordinates(pose: pin.SE3) -> np.ndarray:
    """x, y, z [m], roll, pitch, yaw [rad] of a platform placement (world)."""
    return np.concatenate((pose.translation, pin.rpy.matrixToRpy(pose.rotation)))


def coordinate_scales(length: float) -> np.ndarray:
    """Unit of each pose coordinate: ``length`` for x, y, z, 1 rad for the angles."""
    return np.array([length, length, length, 1.0, 1.0, 1.0])


def coordinate_rates(pose: pin.SE3, length: float) -> np.ndarray:
    """(6, 6) rates of the scaled pose coordinates (x, y, z divided by ``length``; roll,
    pitch, yaw [rad]) per unit of the dimensionless platform twist ``ξ = (ω; v_O /
    length)`` of :mod:`pkm_pin.solve` (axis-first, about the world origin): the origin
    moves by ``v_O + ω × p`` and the angles by ``E(rpy)⁻¹ ω`` (world ω; infinite at
    pitch = ±π/2, where roll and yaw are not coordinates)."""
    p = pose.translation / length
    C = np.zeros((6, 6))
    C[:3, :3] = -pin.skew(p)
    C[:3, 3:] = np.eye(3)
    rpy = pin.rpy.matrixToRpy(pose.rotation)
    C[3:, :3] = pin.rpy.computeRpyJacobianInverse(rpy, pin.WORLD)
    return C


def coordinate_errors(pose: pin.SE3, rows, values, length: float) -> np.ndarray:
    """``(values − c_rows(pose)) / scale``: the scaled errors of the targeted coordinates
    (``rows``: indices into :data:`POSE_COORDINATES`), angles wrapped to (−π, π]."""
    rows = np.asarray(rows, dtype=int)
    d = np.asarray(values, dtype=float) - pose_coordinates(pose)[rows]
    angle = rows >= 3
    d[angle] = -((-d[angle] + np.pi) % (2 * np.pi) - np.pi)
    return d / coordinate_scales(length)[rows]


@dataclass
class CoordinateSolution(ClosureSolution):
    """Result of :func:`solve_coordinates`: a :class:`ClosureSolution` and

    Attributes:
        coordinates: Largest scaled error of the targeted coordinates (x, y, z divided by
            the characteristic length, angles in rad) at the pose reached.
    """

    coordinates: float = 0.0


class CoordinateSystem:
    """The closure rows and the pose-coordinate rates of a mechanism at one state: the
    legs evaluated by their kernels (:func:`closure_matrix`) where every leg has one
    (``compiled``: None, when its code is ready), else by Pinocchio (the Python driver's
    evaluation, :func:`closure_iteration` compiled once ready; ``compiled=False``).

    Attributes:
        A: (6 legs, Σ nv + 6) the closure rows per dimensionless unknown ``[Δq; ξ]``
            (``H_i Δq_i − X_i ξ = e_i``, see the module docstring).
        e: (6 legs,) the closure residuals.
        residuals: (legs,) each leg's :func:`closure_error`.
        closure: Their largest value.
        C: (6, Σ nv + 6) the scaled pose-coordinate rates (:func:`coordinate_rates`) per
            dimensionless unknown (zero on the joints).
        free: (Σ nv + 6, k) orthonormal basis of the null space of ``A``: the motions of
            the mechanism (platform motions and the legs' idle motions) to first order.
    """

    def __init__(self, mech, pose: pin.SE3, leg_q: list, ws=None,
                 compiled: bool | None = None):
        legs = mech.legs
        coords = np.asarray(mech.leg_frames.coords, dtype=np.int64)
        n, ntot, L = len(legs), int(coords[-1]), mech.characteristic_length
        self.C = np.zeros((6, ntot + 6))
        self.C[:, ntot:] = coordinate_rates(pose, L)
        kernel = mech.kernel if compiled is not False else None
        if kernel is not None and (compiled or prefer_compiled(closure_matrix)):
            self.A, self.e, self.residuals = np.zeros((6 * n, ntot + 6)), np.empty(6 * n), \
                np.empty(n)
            self.closure = _closure_matrix_compiled(
                kernel.chains, pose.homogeneous, np.concatenate(leg_q).astype(float),
                self.residuals, self.A, self.e)
            self.coords, self.length, self.ws = coords, L, None
            self.units = np.concatenate([leg._velocity_units for leg in legs])
            self._decompose()
            return
        ws = system_workspace(n, int(max(np.diff(coords))), ntot) if ws is None else ws
        _evaluate(legs, mech.anchors, pose, leg_q, ws)
        lengths = np.array([leg.characteristic_length for leg in legs], dtype=float)
        units = np.concatenate([leg._velocity_units for leg in legs])
        iterate = iteration_compiled if prefer_compiled(iteration_compiled) \
            else closure_iteration
        residual = np.empty(n)
        empty_i, empty = np.empty(0, np.int64), np.empty(0)
        # it == max_iter: rows and residuals only, no step
        _, closure, _, _, _ = iterate(coords, lengths, units, L, True, empty_i, empty, empty,
                                      empty, 0.0, 0, 0, np.inf, 0, residual, ws)
        A = np.zeros((6 * n, ntot + 6))
        for i in range(n):
            c0, c1 = coords[i], coords[i + 1]
            A[6 * i:6 * i + 6, c0:c1] = ws.H[i, :, :c1 - c0]
            A[6 * i:6 * i + 6, ntot:] = -ws.X[i]
        self.A, self.e = A, ws.e[:n].reshape(-1).copy()
        self.residuals, self.closure = residual, float(closure)
        self.coords, self.units, self.length, self.ws = coords, units, L, ws
        self._decompose()

    def _decompose(self) -> None:
        """The SVD of :attr:`A`: its row space for the closure step, :attr:`free`."""
        rank, U, s, Vt = screws.svd_rank(self.A, RANK_RTOL)
        self._U, self._s, self._V = U[:, :rank], s[:rank], Vt[:rank].T
        self.free = Vt[rank:].T

    def step(self, rows, d, lam: float) -> np.ndarray:
        """The damped step ``z = [Δq; ξ]``: the closure rows solved exactly (damped
        pseudo-inverse), then the coordinate rows ``C_rows z = d`` in the least-squares
        sense (damping ``lam``) on :attr:`free`."""
        s = self._s
        z = self._V @ (s / (s * s + lam) * (self._U.T @ self.e))
        if len(rows):
            G = self.C[rows] @ self.free
            rhs = d - self.C[rows] @ z
            y = np.linalg.solve(G.T @ G + lam * np.eye(G.shape[1]), G.T @ rhs)
            z = z + self.free @ y
        return z


def _apply(legs, pose: pin.SE3, leg_q: list, dq: np.ndarray, xi, coords, units,
           length: float) -> tuple[pin.SE3, list, float, float]:
    """The step of the Python drivers: each leg moved by ``units · Δq`` (``dq``,
    dimensionless; ``pin.integrate``, projected onto the limits) and, unless ``xi`` is
    ``None``, the platform to ``exp(ξ) · pose``. Returns the new pose and legs, the
    squared dimensionless step taken and the squared size of the legs' coordinates
    before it (``|q / units|²``; ``|q|²`` for a leg whose nq ≠ nv), for the stall test
    ``step < NEWTON_STALL_RTOL · (1 + size)``."""
    step = 0.0 if xi is None else float(xi @ xi)
    new_q, size = [], 0.0
    for i, leg in enumerate(legs):
        u, q = units[coords[i]:coords[i + 1]], leg_q[i]
        new = leg.clip(pin.integrate(leg.model, q, u * dq[coords[i]:coords[i + 1]]))
        d = pin.difference(leg.model, q, new) / u
        step += float(d @ d)
        size += float(q @ q) if leg.nq != leg.nv else float(np.sum((q / u) ** 2))
        new_q.append(new)
    if xi is not None:
        pose = screws.exp(np.concatenate((xi[:3], length * xi[3:]))) * pose
    return pose, new_q, step, size


def solve_coordinates(mech, pose: pin.SE3, leg_q, rows, values, *, tol: float = CLOSURE_TOL,
                      max_iter: int = 50, compiled: bool | None = None) -> CoordinateSolution:
    """The closure solver with rows fixing pose coordinates (Python driver, Pinocchio's
    legs): every leg's joints and the platform from ``pose`` and ``leg_q``, the closure
    of every leg to ``tol`` and the coordinates ``rows`` (indices into
    :data:`POSE_COORDINATES`) to ``values`` [m, rad]. Each step solves the closure rows
    (damped Newton, :func:`lm_damping`) and the coordinate rows by least squares on the
    motions that keep the closure (:class:`CoordinateSystem`): as many independent
    coordinates as the DOF are reached; more are approached as closely as the closure
    allows (the nearest pose of the motion manifold, in scaled coordinates).

    Stops when ``r = max(closure, |C z|∞) ≤ tol`` (``C z``: the coordinate change the
    next step wants, which is the coordinate error when it can be reached), on
    :func:`stop_rule` otherwise, or when a step stalls (a joint limit).

    ``compiled``: the compiled driver (:func:`solve_coordinates_system`) when every leg
    has a kernel (default: when its code is ready,
    :func:`pkm_pin.compiling.prefer_compiled`); else the Python driver, Pinocchio's legs
    (the same steps to rounding: a test)."""
    rows = np.asarray(rows, dtype=int)
    values = np.ascontiguousarray(values, dtype=float)  # as the machine code reads it
    kernel = mech.kernel if compiled is not False else None
    if kernel is not None and (compiled or prefer_compiled(solve_coordinates_system)):
        M, Q = pose.homogeneous.copy(), np.concatenate(leg_q).astype(float)
        residual, out = np.empty(len(kernel.lengths)), np.empty(3)
        _solve_coordinates_system(kernel.chains, M, Q, rows.astype(np.int64), values,
                                  float(RANK_RTOL), float(tol), int(max_iter), residual, out)
        c = kernel.coords
        return CoordinateSolution(pin.SE3(M), [Q[c[i]:c[i + 1]].copy()
                                               for i in range(len(c) - 1)],
                                  residual, float(out[0]), 0.0, int(out[2]),
                                  coordinates=float(out[1]))
    leg_q = [leg.clip(np.array(q, dtype=float)) for leg, q in zip(mech.legs, leg_q)]
    L = mech.characteristic_length
    it, best, slow, ws = 0, np.inf, 0, None
    while True:
        system = CoordinateSystem(mech, pose, leg_q, ws, compiled=False)
        ws = system.ws
        d = coordinate_errors(pose, rows, values, L)
        z = system.step(rows, d, lm_damping(max(system.closure, float(np.abs(d).max(
            initial=0.0)))))
        r = max(system.closure, float(np.abs(system.C[rows] @ z).max(initial=0.0)))
        stop, best, slow = stop_rule(r, tol, it, max_iter, best, slow)
        if stop or not np.all(np.isfinite(z)):
            break
        it += 1
        ntot = int(system.coords[-1])
        pose, leg_q, step, size = _apply(mech.legs, pose, leg_q, z[:ntot], z[ntot:],
                                         system.coords, system.units, L)
        if step < NEWTON_STALL_RTOL * (1.0 + size):
            system = CoordinateSystem(mech, pose, leg_q, ws, compiled=False)
            d = coordinate_errors(pose, rows, values, L)
            break
    return CoordinateSolution(pose, leg_q, system.residuals.copy(), system.closure, 0.0, it,
                              coordinates=float(np.abs(d).max(initial=0.0)))
