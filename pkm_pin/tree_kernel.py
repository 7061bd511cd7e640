"""Compiled kinematics and closure solver of a general closure model's tree (issue 24).

The tree solver :func:`pkm_pin.solve.solve_tree` costs one Pinocchio pass and ~70 µs of
Python (small numpy arrays, binding calls) per Newton step on its Pinocchio driver. For
trees whose joints it can represent, this module evaluates the same rows in
numba-compiled code and runs the same damped Newton (Levenberg–Marquardt) loop there,
every constant read from the tree's Pinocchio model (joint placements, joint motions
measured through Pinocchio's own forward kinematics, the closures' frames and
placements, limits, velocity units). It is an accelerator, not a second source of
truth: tests compare its residual, Jacobian and output placement with
:meth:`ClosureModel.closure_residual`, :meth:`~ClosureModel.closure_jacobian` and
Pinocchio's frame placement to 1e-12, and its solutions with the Pinocchio driver's
(the closure norms and output placement of a solve's last evaluation are returned
with the solution). :data:`ENABLED` switches it off.

What it represents (:func:`tree_kernel`; otherwise ``None`` and the Pinocchio driver):
revolute and prismatic joints about any axis (nq = nv = 1), unbounded revolutes
(nq = 2, nv = 1: cos, sin), spherical joints (quaternion, body angular velocity) and
free flyers (position and quaternion, body velocity ``(v; ω)``), as Pinocchio does; no
mimic joints.

Residual rows, exactly :mod:`pkm_pin.model.closure_model`'s (``C_a``, ``C_b`` the two
constraint frames, ``L`` the characteristic length): point ``R_aᵀ (p_b − p_a) / L``;
revolute the point rows and the x, y of ``R_aᵀ z_b``; weld ``log6(C_a⁻¹ C_b)`` axis-first
``(θ; ρ / L)`` with its Jacobian through ``Jlog6`` (Pinocchio's formulas, below).
Columns: per velocity coordinate, from the axis-first world twists ``(ω; v_O)`` of the
joints supporting each frame. Actuated rows ``(q_a − target_a) / s_a``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numba import njit
from numba.extending import register_jitable

from . import screws
from .compiling import SameTypes
from .kernels import log3
from .newton import TREE_MAX_STEP, ldl, ldl_solve, lm_damping, stop_rule
from .tolerances import NEWTON_STALL_RTOL

#: Joint kinds of the compiled tree.
REVOLUTE, PRISMATIC, UNBOUNDED, SPHERICAL, FREE_FLYER = 0, 1, 2, 3, 4
#: Closure kinds of the compiled tree.
POINT, REVOLUTE_CLOSURE, WELD, COUPLING = 0, 1, 2, 3
_CLOSURE_KINDS = {"point": POINT, "revolute": REVOLUTE_CLOSURE, "weld": WELD,
                  "coupling": COUPLING}

#: Whether :func:`pkm_pin.solve.solve_tree` may use this module (False: the Pinocchio
#: driver everywhere, for comparisons and diagnosis).
ENABLED = True


class TreeKernel(NamedTuple):
    """A closure model's tree and closures as the compiled functions take them.

    Joint ``j`` (1 … nj; index 0 the universe) is placed in its parent's frame by
    ``place[j]`` then moved by its motion: a rotation about ``axis[j]`` by ``rate[j]``
    times the coordinate (revolute; unbounded: the angle of ``(cos, sin)``), a
    translation ``rate[j] · q · axis[j]`` (prismatic), the quaternion's rotation
    (spherical) or the free flyer's placement. Frames: the closures' ``frame_a`` (C),
    their ``frame_b`` (C), then the output frame: parent joint ``fjoint`` and constant
    ``fplace`` (the frame's placement times the closure's constraint placement). A
    coupling closure's row is ``(q_a − c₁ q_b − c₀) / u_a`` with ``ccoef[c] = (c₀, c₁,
    1 / u_a)``, ``a`` and ``b`` the parent joints of its two frames (``b`` = 0: no
    ``q_b``).
    """

    parent: np.ndarray  # (nj + 1,) parent joint
    place: np.ndarray  # (nj + 1, 4, 4)
    kind: np.ndarray  # (nj + 1,)
    axis: np.ndarray  # (nj + 1, 3)
    rate: np.ndarray  # (nj + 1,)
    iq: np.ndarray  # (nj + 1,)
    iv: np.ndarray  # (nj + 1,)
    fjoint: np.ndarray  # (2C + 1,)
    fplace: np.ndarray  # (2C + 1, 4, 4)
    ckind: np.ndarray  # (C,)
    rows: np.ndarray  # (C + 1,) first row of each closure
    ccoef: np.ndarray  # (C, 3) a coupling's (c0, c1, 1 / u_a)
    lower: np.ndarray  # (nq,)
    upper: np.ndarray  # (nq,)
    units: np.ndarray  # (nv,)
    act_q: np.ndarray  # (na,)
    act_v: np.ndarray  # (na,)
    act_two: np.ndarray  # (na,) 1 where the actuated joint is (cos, sin)
    act_scales: np.ndarray  # (na,)
    all_free: np.ndarray  # (nv,) True: the mask of every velocity coordinate
    length: float
    nq: int
    nv: int


_SUPPORTED = {"JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned",
              "JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned",
              "JointModelRUBX", "JointModelRUBY", "JointModelRUBZ",
              "JointModelRevoluteUnboundedUnaligned", "JointModelSpherical",
              "JointModelFreeFlyer"}


def tree_kernel(model) -> TreeKernel | None:
    """The compiled description of ``model`` (a :class:`~pkm_pin.model.ClosureModel`),
    made once per model (kept on it), or ``None`` when a joint is not one of the module
    docstring's."""
    cached = model.__dict__.get("_tree_kernel", False)
    if cached is False:
        cached = _build(model)
        object.__setattr__(model, "_tree_kernel", cached)
    return cached


def _one_dof_motion(tree: pin.Model, j: int, data: pin.Data):
    """``(kind, axis, rate)`` of a 1-DOF joint measured through Pinocchio's forward
    kinematics (as :func:`pkm_pin.kernels.chain_kernel`), or ``None``."""
    jm = tree.joints[j]
    probe = 0.1
    q = pin.neutral(tree)
    pin.forwardKinematics(tree, data, q)
    M0 = tree.jointPlacements[j].actInv(data.liMi[j])
    if jm.nq == 1:
        q[jm.idx_q] = probe
    else:
        q[jm.idx_q], q[jm.idx_q + 1] = math.cos(probe), math.sin(probe)
    pin.forwardKinematics(tree, data, q)
    M1 = tree.jointPlacements[j].actInv(data.liMi[j])
    if not np.allclose(M0.homogeneous, np.eye(4), rtol=0.0, atol=1e-12):
        return None
    S = screws.from_pinocchio(pin.log6(M1).vector) / probe
    w, v = S[:3], S[3:]
    nw, nvv = np.linalg.norm(w), np.linalg.norm(v)
    if nw > 1e-12 and nvv <= 1e-12 * max(1.0, nw):
        kind, axis, rate = (REVOLUTE if jm.nq == 1 else UNBOUNDED), w / nw, nw
    elif nw <= 1e-12 and nvv > 0 and jm.nq == 1:
        kind, axis, rate = PRISMATIC, v / nvv, nvv
    else:
        return None
    a = int(np.argmax(np.abs(axis)))
    if np.all(np.abs(np.delete(axis, a)) <= 1e-15):  # along ±e_a: e_a exactly
        sign = 1.0 if axis[a] > 0 else -1.0
        axis = np.zeros(3)
        axis[a] = 1.0
        rate *= sign
    if abs(abs(rate) - 1.0) <= 1e-12:  # Pinocchio's joints: a unit rate
        rate = math.copysign(1.0, rate)
    return kind, axis, rate


def _build(model) -> TreeKernel | None:
    tree = model.tree
    nj = tree.njoints
    parent = np.zeros(nj, np.int64)
    place = np.tile(np.eye(4), (nj, 1, 1))
    kind = np.zeros(nj, np.int64)
    axis = np.zeros((nj, 3))
    rate = np.ones(nj)
    iq = np.zeros(nj, np.int64)
    iv = np.zeros(nj, np.int64)
    data = tree.createData()
    for j in range(1, nj):
        jm = tree.joints[j]
        name = jm.shortname()
        if name not in _SUPPORTED:
            return None
        parent[j] = tree.parents[j]
        place[j] = tree.jointPlacements[j].homogeneous
        iq[j], iv[j] = jm.idx_q, jm.idx_v
        if name == "JointModelSpherical":
            kind[j] = SPHERICAL
        elif name == "JointModelFreeFlyer":
            kind[j] = FREE_FLYER
        else:
            motion = _one_dof_motion(tree, j, data)
            if motion is None:
                return None
            kind[j], axis[j], rate[j] = motion
    closures = model.closures
    C = len(closures)
    ids = model._frame_ids
    names = [c.frame_a for c in closures] + [c.frame_b for c in closures] + [model.output]
    extra = [c.placement_a for c in closures] + [c.placement_b for c in closures] \
        + [pin.SE3.Identity()]
    fjoint = np.array([tree.frames[ids[n]].parentJoint for n in names], np.int64)
    fplace = np.array([(tree.frames[ids[n]].placement * P).homogeneous
                       for n, P in zip(names, extra)]).reshape(2 * C + 1, 4, 4)
    ckind = np.array([_CLOSURE_KINDS[c.kind] for c in closures], np.int64)
    rows = np.cumsum([0] + [c.dim for c in closures]).astype(np.int64)
    ccoef = np.zeros((C, 3))
    for c, cl in enumerate(closures):
        if cl.kind == "coupling":
            ccoef[c] = cl.coef + (1.0 / model.velocity_units[iv[fjoint[c]]],)
    plan = model._plan
    lo, up = plan.limits
    joints = [tree.joints[tree.getJointId(a)] for a in model.actuated]
    act_two = np.array([1 if jm.nq == 2 else 0 for jm in joints], np.int64)
    if not plan.act_ok:
        return None
    return TreeKernel(parent, place, kind, axis, rate, iq, iv, fjoint, fplace, ckind, rows,
                      ccoef, np.array(lo), np.array(up),
                      np.array(model.velocity_units, dtype=float),
                      np.array(plan.act_q, np.int64), np.array(plan.act_v, np.int64), act_two,
                      np.array(plan.act_scales, dtype=float), np.ones(tree.nv, np.bool_),
                      float(model.length),
                      int(tree.nq), int(tree.nv))


# ======================================================== compiled kinematics
@register_jitable
def _quat(x, y, z, w):
    """Eigen's rotation matrix of the quaternion ``(x, y, z, w)`` (9 scalars, by rows)."""
    tx, ty, tz = 2.0 * x, 2.0 * y, 2.0 * z
    twx, twy, twz = tx * w, ty * w, tz * w
    txx, txy, txz = tx * x, ty * x, tz * x
    tyy, tyz, tzz = ty * y, tz * y, tz * z
    return (1.0 - (tyy + tzz), txy - twz, txz + twy, txy + twz, 1.0 - (txx + tzz), tyz - twx,
            txz - twy, tyz + twx, 1.0 - (txx + tyy))


@register_jitable
def _rodrigues(ax, ay, az, c, s):
    """Rotation about the unit axis ``a`` of cosine ``c`` and sine ``s`` (9 scalars)."""
    d = 1.0 - c
    return (c + d * ax * ax, d * ax * ay - s * az, d * ax * az + s * ay,
            d * ay * ax + s * az, c + d * ay * ay, d * ay * az - s * ax,
            d * az * ax - s * ay, d * az * ay + s * ax, c + d * az * az)


@register_jitable
def _load(A, i):
    """The 12 numbers ``(R by rows, p)`` of the rigid transform ``A[i]`` (3-D array)."""
    return (A[i, 0, 0], A[i, 0, 1], A[i, 0, 2], A[i, 1, 0], A[i, 1, 1], A[i, 1, 2],
            A[i, 2, 0], A[i, 2, 1], A[i, 2, 2], A[i, 0, 3], A[i, 1, 3], A[i, 2, 3])


@register_jitable
def _store(T, out, i):
    """``out[i]`` (4 × 4) ← the 12 numbers ``T`` (as :func:`_load`)."""
    out[i, 0, 0], out[i, 0, 1], out[i, 0, 2], out[i, 0, 3] = T[0], T[1], T[2], T[9]
    out[i, 1, 0], out[i, 1, 1], out[i, 1, 2], out[i, 1, 3] = T[3], T[4], T[5], T[10]
    out[i, 2, 0], out[i, 2, 1], out[i, 2, 2], out[i, 2, 3] = T[6], T[7], T[8], T[11]
    out[i, 3, 0], out[i, 3, 1], out[i, 3, 2], out[i, 3, 3] = 0.0, 0.0, 0.0, 1.0


@register_jitable
def _compose(A, B):
    """``A B`` of two rigid transforms given as 12 numbers (:func:`_load`)."""
    return (A[0] * B[0] + A[1] * B[3] + A[2] * B[6], A[0] * B[1] + A[1] * B[4] + A[2] * B[7],
            A[0] * B[2] + A[1] * B[5] + A[2] * B[8], A[3] * B[0] + A[4] * B[3] + A[5] * B[6],
            A[3] * B[1] + A[4] * B[4] + A[5] * B[7], A[3] * B[2] + A[4] * B[5] + A[5] * B[8],
            A[6] * B[0] + A[7] * B[3] + A[8] * B[6], A[6] * B[1] + A[7] * B[4] + A[8] * B[7],
            A[6] * B[2] + A[7] * B[5] + A[8] * B[8],
            A[0] * B[9] + A[1] * B[10] + A[2] * B[11] + A[9],
            A[3] * B[9] + A[4] * B[10] + A[5] * B[11] + A[10],
            A[6] * B[9] + A[7] * B[10] + A[8] * B[11] + A[11])


@register_jitable
def _motion(kj, rate, ax, ay, az, q, i):
    """The motion of a joint of kind ``kj`` (axis ``a``, ``rate``; its coordinates from
    ``q[i]``) as 12 numbers (:func:`_load`)."""
    if kj == REVOLUTE or kj == UNBOUNDED:
        if kj == REVOLUTE:
            t = rate * q[i]
            c, s = math.cos(t), math.sin(t)
        else:
            c, s = q[i], math.copysign(1.0, rate) * q[i + 1]
        return _rodrigues(ax, ay, az, c, s) + (0.0, 0.0, 0.0)
    if kj == PRISMATIC:
        t = rate * q[i]
        return (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, t * ax, t * ay, t * az)
    if kj == SPHERICAL:
        return _quat(q[i], q[i + 1], q[i + 2], q[i + 3]) + (0.0, 0.0, 0.0)
    return _quat(q[i + 3], q[i + 4], q[i + 5], q[i + 6]) + (q[i], q[i + 1], q[i + 2])


# The functions below take the kernel's arrays they read, not the kernel: a call passes
# every array of its arguments member by member, ~150 scalars for the whole kernel (more
# than the work of a small tree). Only closure_rows, once an evaluation, takes it.
@register_jitable
def _coordinate_axis(ax, ay, az):
    """0, 1 or 2 where ``(ax, ay, az)`` is exactly ``e_x``, ``e_y`` or ``e_z`` (the axes
    :func:`_one_dof_motion` snaps), else −1."""
    if ay == 0.0 and az == 0.0 and ax == 1.0:
        return 0
    if ax == 0.0 and az == 0.0 and ay == 1.0:
        return 1
    if ax == 0.0 and ay == 0.0 and az == 1.0:
        return 2
    return -1


@register_jitable
def _rotated(T, e, c, s):
    """``T`` (12 numbers, :func:`_load`) times the rotation of cosine ``c`` and sine
    ``s`` about the coordinate axis ``e``: columns ``a``, ``b`` (``e_a × e_b = e_e``)
    turned, ``(c T_a + s T_b, c T_b − s T_a)``, the third and the translation kept (what
    :func:`_compose` with :func:`_rodrigues` gives, without its products by zeros)."""
    if e == 0:
        return (T[0], c * T[1] + s * T[2], c * T[2] - s * T[1],
                T[3], c * T[4] + s * T[5], c * T[5] - s * T[4],
                T[6], c * T[7] + s * T[8], c * T[8] - s * T[7], T[9], T[10], T[11])
    if e == 1:
        return (c * T[0] - s * T[2], T[1], c * T[2] + s * T[0],
                c * T[3] - s * T[5], T[4], c * T[5] + s * T[3],
                c * T[6] - s * T[8], T[7], c * T[8] + s * T[6], T[9], T[10], T[11])
    return (c * T[0] + s * T[1], c * T[1] - s * T[0], T[2],
            c * T[3] + s * T[4], c * T[4] - s * T[3], T[5],
            c * T[6] + s * T[7], c * T[7] - s * T[6], T[8], T[9], T[10], T[11])


@register_jitable
def tree_placements(parent, place, kind, axis, rate, iq, q, oMi):
    """World placement ``oMi[j]`` (4 × 4) of every joint at ``q`` (the kernel's joint
    arrays)."""
    _store((1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0), oMi, 0)
    for j in range(1, parent.shape[0]):
        kj = kind[j]
        T = _compose(_load(oMi, parent[j]), _load(place, j))
        e = _coordinate_axis(axis[j, 0], axis[j, 1], axis[j, 2])
        if kj == REVOLUTE and e >= 0:
            t = rate[j] * q[iq[j]]
            _store(_rotated(T, e, math.cos(t), math.sin(t)), oMi, j)
        else:
            M = _motion(kj, rate[j], axis[j, 0], axis[j, 1], axis[j, 2], q, iq[j])
            _store(_compose(T, M), oMi, j)


@register_jitable
def frame_placements(fjoint, fplace, oMi, F):
    """World placement ``F[f]`` of the kernel's frames (constraint frames ``C_a`` of
    the closures, ``C_b``, then the output frame)."""
    for f in range(fjoint.shape[0]):
        _store(_compose(_load(oMi, fjoint[f]), _load(fplace, f)), F, f)


@register_jitable
def tree_twists(kind, iv, rate, axis, oMi, S):
    """Column ``c`` of ``S`` (6 × nv): the axis-first world twist ``(ω; v_O)`` of velocity
    coordinate ``c``'s joint motion per unit rate (Pinocchio's ``data.J``, reordered)."""
    for j in range(1, kind.shape[0]):
        kj, c = kind[j], iv[j]
        T = _load(oMi, j)
        px, py, pz = T[9], T[10], T[11]
        if kj == REVOLUTE or kj == UNBOUNDED or kj == PRISMATIC:
            r = rate[j]
            a0, a1, a2 = axis[j, 0], axis[j, 1], axis[j, 2]
            ux = r * (T[0] * a0 + T[1] * a1 + T[2] * a2)
            uy = r * (T[3] * a0 + T[4] * a1 + T[5] * a2)
            uz = r * (T[6] * a0 + T[7] * a1 + T[8] * a2)
            if kj == PRISMATIC:
                S[0, c], S[1, c], S[2, c] = 0.0, 0.0, 0.0
                S[3, c], S[4, c], S[5, c] = ux, uy, uz
            else:
                S[0, c], S[1, c], S[2, c] = ux, uy, uz
                S[3, c], S[4, c], S[5, c] = py * uz - pz * uy, pz * ux - px * uz, \
                    px * uy - py * ux
        else:
            first = c
            if kj == FREE_FLYER:  # linear body rates first
                for b in range(3):
                    S[0, c + b], S[1, c + b], S[2, c + b] = 0.0, 0.0, 0.0
                    S[3, c + b], S[4, c + b], S[5, c + b] = T[b], T[3 + b], T[6 + b]
                first = c + 3
            for b in range(3):
                ux, uy, uz = T[b], T[3 + b], T[6 + b]
                S[0, first + b], S[1, first + b], S[2, first + b] = ux, uy, uz
                S[3, first + b] = py * uz - pz * uy
                S[4, first + b] = pz * ux - px * uz
                S[5, first + b] = px * uy - py * ux


@register_jitable
def _nv_of(kj):
    if kj == SPHERICAL:
        return 3
    if kj == FREE_FLYER:
        return 6
    return 1


@register_jitable
def _relative_columns(iv, kind, parent, ja, jb, S, W):
    """``W`` (6 × nv): the world Jacobian of frame b's joint ``jb`` minus frame a's
    ``ja`` (the columns of the joints supporting each; common ones cancel exactly);
    ``iv``, ``kind``, ``parent``: the kernel's arrays."""
    for r in range(6):
        for c in range(W.shape[1]):
            W[r, c] = 0.0
    j = jb
    while j > 0:
        c0 = iv[j]
        for c in range(c0, c0 + _nv_of(kind[j])):
            for r in range(6):
                W[r, c] += S[r, c]
        j = parent[j]
    j = ja
    while j > 0:
        c0 = iv[j]
        for c in range(c0, c0 + _nv_of(kind[j])):
            for r in range(6):
                W[r, c] -= S[r, c]
        j = parent[j]



@register_jitable
def _add_half_skew(M, x):
    """``M += [x]× / 2`` (3 × 3), ``[x]×`` the cross-product matrix of ``x``
    (``[x]× y = x × y``)."""
    M[0, 1] -= 0.5 * x[2]
    M[0, 2] += 0.5 * x[1]
    M[1, 0] += 0.5 * x[2]
    M[1, 2] -= 0.5 * x[0]
    M[2, 0] -= 0.5 * x[1]
    M[2, 1] += 0.5 * x[0]

@register_jitable
def jlog3(theta, w, J):
    """Pinocchio's ``Jlog3`` (3 × 3) at the rotation vector ``w`` of angle ``theta``."""
    st, ct = math.sin(theta), math.cos(theta)
    if theta < 1.2207031250000000e-04:  # TaylorSeriesExpansion::precision<3>
        alpha = 1.0 / 12.0 + theta * theta / 720.0
        diag = 0.5 * (2.0 - theta * theta / 6.0)
    else:
        st_1mct = st / (1.0 - ct)
        alpha = 1.0 / (theta * theta) - st_1mct / (2.0 * theta)
        diag = 0.5 * (theta * st_1mct)
    for a in range(3):
        for b in range(3):
            J[a, b] = alpha * w[a] * w[b]
        J[a, a] += diag
    _add_half_skew(J, w)


@register_jitable
def log6_jlog6(R, p, out, J, w, A, Cm):
    """Pinocchio's ``log6`` of ``(R, p)`` axis-first into ``out`` (6: ``(θ; ρ)``) and its
    ``Jlog6`` (6 × 6, Pinocchio's order ``(v; ω)`` for both rows and columns); ``w`` (3),
    ``A`` and ``Cm`` (3 × 3): work arrays."""
    log3(R, w)
    t = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    x, y, z = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    t2s = 0.25 * (x * x + y * y + z * z)  # |unskew(R)|², Pinocchio's Taylor argument
    st, ct = math.sin(t), math.cos(t)
    if R[0, 0] + R[1, 1] + R[2, 2] >= 3.0 - 6.0554544523933395e-06:  # precision<2>
        alpha = 1.0 - t2s / 12.0 - t2s * t2s / 720.0
        beta = 1.0 / 12.0 + t2s / 720.0
    else:
        alpha = t * st / (2.0 * (1.0 - ct))
        beta = 1.0 / (t * t) - st / (2.0 * t * (1.0 - ct))
    wp = w[0] * p[0] + w[1] * p[1] + w[2] * p[2]
    cx = w[1] * p[2] - w[2] * p[1]
    cy = w[2] * p[0] - w[0] * p[2]
    cz = w[0] * p[1] - w[1] * p[0]
    out[0], out[1], out[2] = w[0], w[1], w[2]
    out[3] = alpha * p[0] - 0.5 * cx + beta * wp * w[0]
    out[4] = alpha * p[1] - 0.5 * cy + beta * wp * w[1]
    out[5] = alpha * p[2] - 0.5 * cz + beta * wp * w[2]
    jlog3(t, w, A)
    t2 = t * t
    if t < 1.2207031250000000e-04:
        beta = 1.0 / 12.0 + t2 / 720.0
        bdot = 1.0 / 360.0
    else:
        tinv = 1.0 / t
        t2inv = tinv * tinv
        inv22 = 1.0 / (2.0 * (1.0 - ct))
        beta = t2inv - st * tinv * inv22
        bdot = -2.0 * t2inv * t2inv + (1.0 + st * tinv) * t2inv * inv22
    f1, f2 = bdot * wp, t2 * bdot + 2.0 * beta
    for a in range(3):
        v3 = f1 * w[a] - f2 * p[a]
        for b in range(3):
            Cm[a, b] = v3 * w[b] + beta * w[a] * p[b]
        Cm[a, a] += wp * beta
    _add_half_skew(Cm, p)
    for a in range(3):
        for b in range(3):
            J[a, b] = A[a, b]
            J[3 + a, 3 + b] = A[a, b]
            J[3 + a, b] = 0.0
            s = 0.0
            for m in range(3):
                s += Cm[a, m] * A[m, b]
            J[a, 3 + b] = s


class Work(NamedTuple):
    """Work arrays of :func:`closure_rows` (:func:`workspace`)."""

    oMi: np.ndarray  # (nj, 4, 4) joint placements
    F: np.ndarray  # (2C + 1, 4, 4) frame placements
    S: np.ndarray  # (6, nv) joint twists
    W: np.ndarray  # (6, nv) a closure's relative columns
    Rrel: np.ndarray  # (3, 3)  a weld's relative rotation …
    prel: np.ndarray  # (3,)  … and translation
    lg: np.ndarray  # (6,)  its log6
    Jl: np.ndarray  # (6, 6)  its Jlog6
    nu: np.ndarray  # (6,)
    w: np.ndarray  # (3,)
    A: np.ndarray  # (3, 3)
    Cm: np.ndarray  # (3, 3)


@register_jitable
def workspace(k):
    """:class:`Work` for the kernel ``k`` (views into five allocations)."""
    nj, nv = k.parent.shape[0], k.nv
    T3 = np.empty((nj + k.fjoint.shape[0], 4, 4))
    M2 = np.empty((12, nv))
    R3 = np.empty((3, 3, 3))
    v = np.empty(18)
    return Work(T3[:nj], T3[nj:], M2[:6], M2[6:], R3[0], v[0:3], v[6:12], np.empty((6, 6)),
                v[12:18], v[3:6], R3[1], R3[2])


@register_jitable
def about_point(W, px, py, pz):
    """``W[3:] ← v_O + ω × p``: the columns' velocities of the point ``p`` (world), from
    axis-first world twists ``W`` (6 × nv)."""
    for col in range(W.shape[1]):
        wx, wy, wz = W[0, col], W[1, col], W[2, col]
        W[3, col] += wy * pz - wz * py
        W[4, col] += wz * px - wx * pz
        W[5, col] += wx * py - wy * px


@register_jitable
def log6_rows(Fa, Fb, W, ws, iL, r0, e, H):
    """Rows ``r0 … r0 + 5`` of ``e`` and ``H``: ``log6(Fa⁻¹ Fb)`` axis-first ``(θ; ρ / L)``
    (``iL = 1 / L``) and its Jacobian through ``Jlog6`` (Pinocchio's formulas), ``W``
    the relative columns of frame b against frame a, their linear rows about ``p_b``
    (:func:`about_point`): a weld closure's rows, and the output's pose error against a
    fixed target (``Fa`` the target, ``W`` the output's own columns)."""
    Rrel, prel, lg, Jl, nu = ws.Rrel, ws.prel, ws.lg, ws.Jl, ws.nu
    dx, dy, dz = Fb[0, 3] - Fa[0, 3], Fb[1, 3] - Fa[1, 3], Fb[2, 3] - Fa[2, 3]
    for a in range(3):
        for b in range(3):
            Rrel[a, b] = Fa[0, a] * Fb[0, b] + Fa[1, a] * Fb[1, b] + Fa[2, a] * Fb[2, b]
        prel[a] = Fa[0, a] * dx + Fa[1, a] * dy + Fa[2, a] * dz
    log6_jlog6(Rrel, prel, lg, Jl, ws.w, ws.A, ws.Cm)
    for a in range(3):
        e[r0 + a] = lg[a]
        e[r0 + 3 + a] = lg[3 + a] * iL
    for col in range(W.shape[1]):
        for a in range(3):  # body twist in frame b, Pinocchio's (v; ω)
            nu[a] = Fb[0, a] * W[3, col] + Fb[1, a] * W[4, col] + Fb[2, a] * W[5, col]
            nu[3 + a] = Fb[0, a] * W[0, col] + Fb[1, a] * W[1, col] + Fb[2, a] * W[2, col]
        for a in range(3):
            lin, ang = 0.0, 0.0
            for b in range(6):
                lin += Jl[a, b] * nu[b]
                ang += Jl[3 + a, b] * nu[b]
            H[r0 + a, col] = ang
            H[r0 + 3 + a, col] = lin * iL


@register_jitable
def closure_rows(k, q, ws, e, H, norms, oMo):
    """The closure rows at ``q``: residual ``e[:n]`` and Jacobian ``H[:n]`` (per unit of
    each velocity coordinate), each closure's norm in ``norms``, the output frame's
    world placement in ``oMo`` (``ws``: :func:`workspace`). Returns the largest norm."""
    ckind, rows, fjoint = k.ckind, k.rows, k.fjoint
    jiv, jkind, jparent = k.iv, k.kind, k.parent
    C = ckind.shape[0]
    nv = k.nv
    oMi, F, S, W = ws.oMi, ws.F, ws.S, ws.W
    tree_placements(k.parent, k.place, k.kind, k.axis, k.rate, k.iq, q, oMi)
    tree_twists(k.kind, k.iv, k.rate, k.axis, oMi, S)
    frame_placements(k.fjoint, k.fplace, oMi, F)
    for a in range(4):
        for b in range(4):
            oMo[a, b] = F[2 * C, a, b]
    iL = 1.0 / k.length
    worst = 0.0
    for c in range(C):
        ca, cb = c, C + c
        if ckind[c] == COUPLING:
            worst = max(worst, _coupling_row(k, q, c, e, H, norms))
            continue
        _relative_columns(jiv, jkind, jparent, fjoint[c], fjoint[C + c], S, W)
        r0 = rows[c]
        pbx, pby, pbz = F[cb, 0, 3], F[cb, 1, 3], F[cb, 2, 3]
        dx, dy, dz = pbx - F[ca, 0, 3], pby - F[ca, 1, 3], pbz - F[ca, 2, 3]
        about_point(W, pbx, pby, pbz)  # W[:3] relative ω (world), W[3:] about p_b
        kind = ckind[c]
        if kind != WELD:
            for a in range(3):
                e[r0 + a] = (F[ca, 0, a] * dx + F[ca, 1, a] * dy + F[ca, 2, a] * dz) * iL
                for col in range(nv):
                    H[r0 + a, col] = (F[ca, 0, a] * W[3, col] + F[ca, 1, a] * W[4, col]
                                      + F[ca, 2, a] * W[5, col]) * iL
            if kind == REVOLUTE_CLOSURE:
                zx, zy, zz = F[cb, 0, 2], F[cb, 1, 2], F[cb, 2, 2]
                for a in range(2):
                    e[r0 + 3 + a] = F[ca, 0, a] * zx + F[ca, 1, a] * zy + F[ca, 2, a] * zz
                    for col in range(nv):  # R_aᵀ (ω × z_b)
                        wx, wy, wz = W[0, col], W[1, col], W[2, col]
                        H[r0 + 3 + a, col] = (F[ca, 0, a] * (wy * zz - wz * zy)
                                              + F[ca, 1, a] * (wz * zx - wx * zz)
                                              + F[ca, 2, a] * (wx * zy - wy * zx))
        else:
            log6_rows(F[ca], F[cb], W, ws, iL, r0, e, H)
        s = 0.0
        for r in range(r0, rows[c + 1]):
            s += e[r] * e[r]
        norms[c] = math.sqrt(s)
        worst = max(worst, norms[c])
    return worst


@register_jitable
def _coupling_row(k, q, c, e, H, norms):
    """Coupling closure ``c``'s row (class docstring) into ``e``, ``H`` and
    ``norms``; returns its norm."""
    r0, ja, jb = k.rows[c], k.fjoint[c], k.fjoint[k.ckind.shape[0] + c]
    c0, c1, iu = k.ccoef[c, 0], k.ccoef[c, 1], k.ccoef[c, 2]
    qb = q[k.iq[jb]] if jb > 0 else 0.0
    e[r0] = (q[k.iq[ja]] - c1 * qb - c0) * iu
    for col in range(k.nv):
        H[r0, col] = 0.0
    H[r0, k.iv[ja]] = iu
    if jb > 0:
        H[r0, k.iv[jb]] -= c1 * iu
    norms[c] = abs(e[r0])
    return norms[c]


@njit(cache=True, nogil=True)
def closure_rows_compiled(k, q, e, H, norms, oMo):
    """:func:`closure_rows` compiled (for tests and one-off evaluations)."""
    return closure_rows(k, q, workspace(k), e, H, norms, oMo)


@register_jitable
def output_pose_rows(k, ws, target, point, ep, Hp):
    """The output frame's pose error against ``target`` (4 × 4, world) into ``ep`` (6)
    and its Jacobian per unit of each velocity coordinate into ``Hp`` (6 × nv), at the
    placements :func:`closure_rows` left in ``ws`` (the output frame: ``ws.F[2C]``),
    exactly :func:`pkm_pin.solve.pose_error_rows`: ``log6(target⁻¹ · oMo)`` axis-first
    ``(θ; ρ / L)`` with its Jacobian through ``Jlog6``; for a point output (``point``)
    zero rotation rows and ``(p − p_target) / L`` in world axes."""
    C = k.ckind.shape[0]
    F, W = ws.F, ws.W
    o = 2 * C
    nv = k.nv
    _relative_columns(k.iv, k.kind, k.parent, 0, k.fjoint[o], ws.S, W)
    about_point(W, F[o, 0, 3], F[o, 1, 3], F[o, 2, 3])  # W[3:]: the origin's velocity
    iL = 1.0 / k.length
    if point:
        for a in range(3):
            ep[a] = 0.0
            ep[3 + a] = (F[o, a, 3] - target[a, 3]) * iL
            for col in range(nv):
                Hp[a, col] = 0.0
                Hp[3 + a, col] = W[3 + a, col] * iL
        return
    log6_rows(target, F[o], W, ws, iL, 0, ep, Hp)


@njit(cache=True, nogil=True)
def output_pose_rows_compiled(k, q, target, point, ep, Hp):
    """:func:`output_pose_rows` at ``q`` compiled (for tests)."""
    ws = workspace(k)
    C = k.ckind.shape[0]
    n = k.rows[C]
    closure_rows(k, q, ws, np.empty(n), np.empty((n, k.nv)), np.empty(C), np.empty((4, 4)))
    output_pose_rows(k, ws, target, point, ep, Hp)


# ============================================================ the compiled solver
@register_jitable
def _quat_times_exp(q, i, wx, wy, wz):
    """``q[i:i+4] ← q[i:i+4] · exp(ω)`` (quaternions ``(x, y, z, w)``), then Pinocchio's
    first-order normalisation."""
    t = math.sqrt(wx * wx + wy * wy + wz * wz)
    if t < 1e-8:
        f = 0.5 - t * t / 48.0
        cw = 1.0 - t * t / 8.0
    else:
        f = math.sin(0.5 * t) / t
        cw = math.cos(0.5 * t)
    bx, by, bz, bw = f * wx, f * wy, f * wz, cw
    ax, ay, az, aw = q[i], q[i + 1], q[i + 2], q[i + 3]
    x = aw * bx + ax * bw + ay * bz - az * by
    y = aw * by - ax * bz + ay * bw + az * bx
    z = aw * bz + ax * by - ay * bx + az * bw
    w = aw * bw - ax * bx - ay * by - az * bz
    n2 = x * x + y * y + z * z + w * w
    g = (3.0 - n2) * 0.5
    q[i], q[i + 1], q[i + 2], q[i + 3] = g * x, g * y, g * z, g * w


@register_jitable
def tree_integrate(kind, iq, iv, q, dv):
    """``q ← integrate(q, dv)`` (Pinocchio's integration of each joint, in place; the
    kernel's joint arrays)."""
    for j in range(1, kind.shape[0]):
        kj, i, c = kind[j], iq[j], iv[j]
        if kj == REVOLUTE or kj == PRISMATIC:
            q[i] += dv[c]
        elif kj == UNBOUNDED:
            ca, sa = q[i], q[i + 1]
            cb, sb = math.cos(dv[c]), math.sin(dv[c])
            x, y = ca * cb - sa * sb, sa * cb + ca * sb
            g = (3.0 - (x * x + y * y)) * 0.5
            q[i], q[i + 1] = g * x, g * y
        elif kj == SPHERICAL:
            _quat_times_exp(q, i, dv[c], dv[c + 1], dv[c + 2])
        else:  # free flyer: M ← M exp(ν), ν = (v; ω) in the body frame
            wx, wy, wz = dv[c + 3], dv[c + 4], dv[c + 5]
            th2 = wx * wx + wy * wy + wz * wz
            th = math.sqrt(th2)
            if th < 1e-6:
                b = 0.5 - th2 / 24.0
            else:
                h = math.sin(0.5 * th)
                b = 2.0 * h * h / th2
            if th < 1e-2:
                cc = 1.0 / 6.0 - th2 / 120.0 + th2 * th2 / 5040.0
            else:
                cc = (th - math.sin(th)) / (th2 * th)
            vx, vy, vz = dv[c], dv[c + 1], dv[c + 2]
            # J_l(ω) v = v + b ω × v + c ω × (ω × v)
            ux, uy, uz = wy * vz - wz * vy, wz * vx - wx * vz, wx * vy - wy * vx
            tx, ty, tz = wy * uz - wz * uy, wz * ux - wx * uz, wx * uy - wy * ux
            lx, ly, lz = vx + b * ux + cc * tx, vy + b * uy + cc * ty, vz + b * uz + cc * tz
            R = _quat(q[i + 3], q[i + 4], q[i + 5], q[i + 6])
            q[i] += R[0] * lx + R[1] * ly + R[2] * lz
            q[i + 1] += R[3] * lx + R[4] * ly + R[5] * lz
            q[i + 2] += R[6] * lx + R[7] * ly + R[8] * lz
            _quat_times_exp(q, i + 3, wx, wy, wz)


@register_jitable
def _actuated_rows(n0, act_q, act_two, act_scales, act_v, q, targets, e, H):
    """The actuated rows ``(q_a − target_a) / s_a`` from row ``n0`` on; returns their
    largest magnitude."""
    act = 0.0
    for a in range(act_q.shape[0]):
        i = act_q[a]
        value = math.atan2(q[i + 1], q[i]) if act_two[a] else q[i]
        r = n0 + a
        e[r] = (value - targets[a]) / act_scales[a]
        for col in range(H.shape[1]):
            H[r, col] = 0.0
        H[r, act_v[a]] = 1.0 / act_scales[a]
        act = max(act, abs(e[r]))
    return act


@register_jitable
def stepped_within(kind, iq, iv, nq, q, dv, lower, upper, q_new) -> bool:
    """``q_new ← integrate(q, dv)`` (the first ``nq`` coordinates) clipped to the limits
    ``[lower, upper]``; False when a coordinate is not finite (the step to refuse)."""
    for a in range(nq):
        q_new[a] = q[a]
    tree_integrate(kind, iq, iv, q_new, dv)
    finite = True
    for a in range(nq):
        q_new[a] = min(upper[a], max(lower[a], q_new[a]))
        finite = finite and math.isfinite(q_new[a])
    return finite


@register_jitable
def newton_step(Hf, e, m, nf, lam, N, g, inv, dx) -> bool:
    """The damped Newton step ``dx = −(Hfᵀ Hf + λ I)⁻¹ Hfᵀ e`` on the first ``m`` rows and
    ``nf`` columns (``L D Lᵀ`` of the normal equations), shortened to
    :data:`~pkm_pin.newton.TREE_MAX_STEP`; False when they are not positive definite.

    ``Hfᵀ Hf`` and ``Hfᵀ e`` are summed row by row over each row's nonzero columns (a
    closure's rows touch only the joints of its loop: ~7 of a humanoid's 130), in the
    order of the dense sums, which they equal to the last bit."""
    for a in range(nf):
        g[a] = 0.0
        for b in range(a + 1):
            N[a, b] = 0.0
    nz = np.empty(nf, np.int64)
    for row in range(m):
        k = 0
        for a in range(nf):
            if Hf[row, a] != 0.0:
                nz[k] = a
                k += 1
        er = e[row]
        for i in range(k):
            a = nz[i]
            ha = Hf[row, a]
            g[a] += ha * er
            for j in range(i + 1):
                N[a, nz[j]] += ha * Hf[row, nz[j]]
    for a in range(nf):
        N[a, a] += lam
        first = a  # the profile of N's lower triangle, for ldl
        for b in range(a):
            if N[a, b] != 0.0:
                first = b
                break
        nz[a] = first
    if not ldl(N, nf, inv, nz):
        return False
    ldl_solve(N, nf, inv, g, dx)
    big = 0.0
    for a in range(nf):
        dx[a] = -dx[a]
        big = max(big, abs(dx[a]))
    if big > TREE_MAX_STEP:
        f = TREE_MAX_STEP / big
        for a in range(nf):
            dx[a] *= f
    return True


@register_jitable
def _moved(kind, iq, iv, units, q, q_new, dv) -> float:
    """``|difference(q, q_new) / units|²`` of a step (only 1-DOF coordinates are clipped
    to their limits: the others moved by ``dv``)."""
    moved = 0.0
    for j in range(1, kind.shape[0]):
        kj, i, c = kind[j], iq[j], iv[j]
        if kj == REVOLUTE or kj == PRISMATIC:
            d = (q_new[i] - q[i]) / units[c]
            moved += d * d
        else:
            for b in range(c, c + _nv_of(kj)):
                d = dv[b] / units[b]
                moved += d * d
    return moved


@register_jitable
def _selected_rows(P, ep, Hp, n1, e, H):
    """Rows ``n1 …`` of ``e`` and ``H``: ``P ep`` and ``P Hp`` (the targeted components
    of the output pose error); returns their norm."""
    s = 0.0
    for i in range(P.shape[0]):
        x = 0.0
        for a in range(6):
            x += P[i, a] * ep[a]
        e[n1 + i] = x
        s += x * x
        for col in range(H.shape[1]):
            y = 0.0
            for a in range(6):
                y += P[i, a] * Hp[a, col]
            H[n1 + i, col] = y
    return math.sqrt(s)


@njit(cache=True, nogil=True)
def solve_tree_kernel(k, q, free, has_targets, targets, pose, point, P, tol, max_iter, norms,
                      oMo, info):
    """:func:`pkm_pin.solve.solve_tree` compiled: damped Newton on the closure rows (and
    the actuated rows when ``has_targets``; the output pose rows ``P`` (r × 6, no rows:
    none) times :func:`output_pose_rows` against ``pose`` (4 × 4), ``point`` for a point
    output) from ``q`` (solved in
    place), the unknowns the velocity coordinates where ``free`` is true. The same
    steps as the Pinocchio driver (:func:`~pkm_pin.solve.tree_step`): dimensionless
    columns, :func:`lm_damping`, ``L D Lᵀ`` of the normal equations, the step shortened
    to :data:`~pkm_pin.newton.TREE_MAX_STEP`, projected onto the limits; stops on
    :func:`stop_rule`, a non-finite step or a stalled one. ``info`` receives ``(r,
    closure, actuated, iterations, converged, at_q, pose)``; ``norms`` and ``oMo`` the
    last evaluation's closure norms and output placement (at ``q`` when ``at_q``)."""
    units, lower, upper, rows = k.units, k.lower, k.upper, k.rows
    kind, iq, iv = k.kind, k.iq, k.iv
    act_q, act_two, act_scales, act_v = k.act_q, k.act_two, k.act_scales, k.act_v
    nv, nq = k.nv, k.nq
    n0 = rows[rows.shape[0] - 1]
    n1 = n0 + (act_q.shape[0] if has_targets else 0)
    m = n1 + P.shape[0]
    ep, Hp = np.empty(6), np.empty((6, nv))
    ws = workspace(k)
    cols = np.empty(nv, np.int64)
    nf = 0
    for c in range(nv):
        if free[c]:
            cols[nf] = c
            nf += 1
    H, HN, V = np.empty((m, nv)), np.empty((m + nf, nf)), np.empty(m + 3 * nf + nq + nv)
    Hf, N = HN[:m], HN[m:]
    e, g, inv, dx = V[:m], V[m:m + nf], V[m + nf:m + 2 * nf], V[m + 2 * nf:m + 3 * nf]
    q_new, dv = V[m + 3 * nf:m + 3 * nf + nq], V[m + 3 * nf + nq:]
    dv[:] = 0.0
    for a in range(nq):
        q[a] = min(upper[a], max(lower[a], q[a]))
    best, slow, it, at_q = np.inf, 0, 0, True
    closure, act, r, perr = 0.0, 0.0, 0.0, 0.0
    while True:
        closure = closure_rows(k, q, ws, e, H, norms, oMo)
        if has_targets:
            act = _actuated_rows(n0, act_q, act_two, act_scales, act_v, q, targets, e, H)
        if P.shape[0]:
            output_pose_rows(k, ws, pose, point, ep, Hp)
            perr = _selected_rows(P, ep, Hp, n1, e, H)
        r = max(closure, act, perr)
        stop, best, slow = stop_rule(r, tol, it, max_iter, best, slow)
        if stop or nf == 0:
            break
        for row in range(m):
            for b in range(nf):
                Hf[row, b] = H[row, cols[b]] * units[cols[b]]
        if not newton_step(Hf, e, m, nf, lm_damping(r), N, g, inv, dx):
            break
        step = 0.0
        for a in range(nf):
            step += dx[a] * dx[a]
            dv[cols[a]] = units[cols[a]] * dx[a]
        if not stepped_within(kind, iq, iv, nq, q, dv, lower, upper, q_new):
            break
        it += 1
        moved = _moved(kind, iq, iv, units, q, q_new, dv)
        for a in range(nq):
            q[a] = q_new[a]
        if moved < NEWTON_STALL_RTOL * (1.0 + step):
            at_q = False
            break
    info[0], info[1], info[2], info[3] = r, closure, act, it
    info[4] = 1.0 if r <= tol else 0.0
    info[5] = 1.0 if at_q else 0.0
    info[6] = perr


#: :func:`solve_tree_kernel` called by :func:`pkm_pin.solve.solve_tree`: a model's kernel
#: is typed once, later calls go straight to the machine code (:class:`SameTypes`).
SOLVE = SameTypes(solve_tree_kernel, 0)
