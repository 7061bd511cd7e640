"""Compiled kinematics of a leg for the inner loops of the closure solver
(:mod:`pkm_pin.solve`: sweeps, assembly, forward kinematics).

Why this module exists: a Newton iteration of a leg costs about 1 µs of Pinocchio work
but 20–30 µs of Python around it (binding calls, small numpy arrays). For loops over
thousands of poses the leg's kinematics are therefore evaluated here, in numba-compiled
code, as a product of exponentials whose every constant is read from the leg's Pinocchio
model (joint placements, joint motion axes measured through Pinocchio's own forward
kinematics, mimic ratios and offsets, tip frame, limits). The kernel is an accelerator,
not a second source of truth: it is tested against Pinocchio to round-off, and every
configuration it returns to the user is evaluated again by Pinocchio (whose tip
placement gives the reported residual and whose Jacobian gives the joint twists).

Conventions: twists axis-first ``(ω; v_O)`` about the world origin, base placement
included (like :meth:`pkm_pin.Leg.jacobian`); SI units, radians.

Chains the kernel cannot represent (joints with more than one coordinate such as
continuous or free-flyer joints, branches, helical joints) get no kernel:
:func:`chain_kernel` returns ``None`` and callers use the Pinocchio path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numba import njit
from numba.extending import register_jitable

from . import screws

REVOLUTE, PRISMATIC = 0, 1
#: Added to ``kind`` when the joint has a constant factor after its motion (mimic offset).
HAS_POST = 2
#: Added to ``kind`` when the joint's placement in its parent frame is the identity.
AT_PARENT = 4


class Chain(NamedTuple):
    """A serial chain as the compiled functions take it (one argument).

    Joint ``j`` moves its frame by ``parent_j · exp(S_j q[iq_j]) · post_j`` where
    ``S_j`` is a rotation about ``axis_j`` at rate ``rate_j`` (revolute) or a translation
    ``rate_j · axis_j`` (prismatic); mimic joints read the coordinate of their primary
    joint, their ratio is in ``rate_j`` and their offset in ``post_j``; ``iv_j`` is the
    Jacobian column the joint contributes to. ``parent`` … ``nv`` are what
    :func:`_fk` reads; ``lower`` … ``units`` what the closure solver reads.
    """

    parent: np.ndarray  # (nj, 4, 4) joint placements in the parent joint frame
    post: np.ndarray  # (nj, 4, 4) constant factor after the motion (mimic offset)
    kind: np.ndarray  # (nj,) REVOLUTE / PRISMATIC, + HAS_POST, + AT_PARENT
    axis: np.ndarray  # (nj, 3) unit axis in the joint frame (e_a exactly along a frame axis)
    rate: np.ndarray  # (nj,) rad or m per unit of the coordinate (signed)
    iq: np.ndarray  # (nj,) configuration index driving the joint
    iv: np.ndarray  # (nj,) Jacobian column
    tip: np.ndarray  # (4, 4) tip frame in the last joint frame
    base: np.ndarray  # (4, 4) root placement in the world
    nv: int
    lower: np.ndarray  # (nq,)
    upper: np.ndarray  # (nq,)
    length: float  # characteristic length of the leg [m]
    units: np.ndarray  # (nv,) unit of each coordinate: length (prismatic) or 1 rad


class Chains(NamedTuple):
    """Every leg of a mechanism as one argument of the compiled functions: the legs'
    :class:`Chain` arrays one after the other (leg ``i`` owns joints
    ``joints[i]:joints[i+1]`` and coordinates ``coords[i]:coords[i+1]`` of the
    concatenated configuration ``Q``; :func:`chain_of` reads one leg back), the
    platform anchors, the actuated coordinates and their units, the mechanism's length."""

    joints: np.ndarray
    coords: np.ndarray
    parent: np.ndarray
    post: np.ndarray
    kind: np.ndarray
    axis: np.ndarray
    rate: np.ndarray
    iq: np.ndarray
    iv: np.ndarray
    tips: np.ndarray
    bases: np.ndarray
    anchors: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    lengths: np.ndarray
    units: np.ndarray
    actuated: np.ndarray  # global indices of the actuated coordinates in Q
    scales: np.ndarray  # unit of each actuated coordinate
    length: float


@register_jitable
def chain_of(chains, i):
    """Leg ``i`` of :class:`Chains` as a :class:`Chain` (views, no copies)."""
    j0, j1 = chains.joints[i], chains.joints[i + 1]
    c0, c1 = chains.coords[i], chains.coords[i + 1]
    return Chain(chains.parent[j0:j1], chains.post[j0:j1], chains.kind[j0:j1],
                 chains.axis[j0:j1], chains.rate[j0:j1], chains.iq[j0:j1], chains.iv[j0:j1],
                 chains.tips[i], chains.bases[i], c1 - c0, chains.lower[c0:c1],
                 chains.upper[c0:c1], chains.lengths[i], chains.units[c0:c1])


class ChainKernel(Chain):
    """The compiled kinematics of one leg (:func:`chain_kernel`): its :class:`Chain`
    (the same fields) with the calls a leg makes on it (the closure solver takes it in
    :func:`pkm_pin.solve.solve_chain`)."""

    __slots__ = ()

    @property
    def chain(self) -> Chain:
        """The constants as the plain :class:`Chain` the compiled functions take."""
        return Chain(*self)

    def kinematics(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Tip placement (4×4, world) and 6×nv axis-first world Jacobian at ``q``."""
        T = np.empty((4, 4))
        J = np.empty((6, self.nv))
        fk_jacobian(self.chain, np.asarray(q, dtype=float), T, J)
        return T, J


def chain_kernel(leg) -> ChainKernel | None:
    """The kernel of a :class:`~pkm_pin.Leg`, or ``None`` if its chain has a joint the
    kernel does not represent (nq ≠ nv, multi-DOF, helical) or is not a single chain."""
    m = leg.model
    if m.nq != m.nv:
        return None
    data = m.createData()
    nj = m.njoints - 1
    if m.frames[leg.tip_id].parentJoint != nj:
        return None
    parent = np.empty((nj, 4, 4))
    post = np.empty((nj, 4, 4))
    kind = np.empty(nj, np.int64)
    axis = np.empty((nj, 3))
    rate = np.empty(nj)
    iq = np.empty(nj, np.int64)
    iv = np.empty(nj, np.int64)
    probe = 0.1
    for j in range(1, nj + 1):
        jm = m.joints[j]
        mimic = jm.nq == 0 and jm.nv == 0 and "Mimic" in jm.shortname()
        if m.parents[j] != j - 1 or not (mimic or (jm.nq == 1 and jm.nv == 1)):
            return None
        k = j - 1
        parent[k] = m.jointPlacements[j].homogeneous
        iq[k], iv[k] = jm.idx_q, jm.idx_v
        # the joint's own motion, measured through Pinocchio's forward kinematics
        q = np.zeros(m.nq)
        pin.forwardKinematics(m, data, q)
        M0 = m.jointPlacements[j].actInv(data.liMi[j])
        q[jm.idx_q] = probe
        pin.forwardKinematics(m, data, q)
        M1 = m.jointPlacements[j].actInv(data.liMi[j])
        S = screws.from_pinocchio(pin.log6(M1 * M0.inverse()).vector) / probe
        w, v = S[:3], S[3:]  # (ω; v) per unit of the coordinate
        nw, nvv = np.linalg.norm(w), np.linalg.norm(v)
        if nw > 1e-12 and nvv <= 1e-12 * max(1.0, nw):
            kind[k], axis[k], rate[k] = REVOLUTE, w / nw, nw
        elif nw <= 1e-12 and nvv > 0:
            kind[k], axis[k], rate[k] = PRISMATIC, v / nvv, nvv
        else:
            return None  # helical or a joint that does not move
        # an axis along ±e_a to round-off is stored as e_a exactly (the sign goes to the
        # rate: the same motion), which lets _fk turn two columns instead of Rodrigues
        a = int(np.argmax(np.abs(axis[k])))
        if np.all(np.abs(np.delete(axis[k], a)) <= 1e-15):
            sign = 1.0 if axis[k, a] > 0 else -1.0
            axis[k] = 0.0
            axis[k, a] = 1.0
            rate[k] *= sign
        post[k] = M0.homogeneous
        if not np.allclose(post[k], np.eye(4), rtol=0.0, atol=1e-15):
            kind[k] += HAS_POST
        if np.array_equal(parent[k], np.eye(4)):
            kind[k] += AT_PARENT
    lo, up = leg._bounds
    return ChainKernel(parent, post, kind, axis, rate, iq, iv,
                       m.frames[leg.tip_id].placement.homogeneous, leg.base.homogeneous,
                       int(m.nv), lo.copy(), up.copy(), float(leg.characteristic_length),
                       leg._velocity_units.copy())


# =============================================================== compiled functions
@njit(cache=True, nogil=True)
def _compose(A, B, out):
    """out = A · B for 4×4 homogeneous transforms (out may not alias A or B)."""
    for a in range(3):
        for b in range(4):
            s = A[a, 0] * B[0, b] + A[a, 1] * B[1, b] + A[a, 2] * B[2, b]
            if b == 3:
                s += A[a, 3]
            out[a, b] = s
    out[3, 0] = 0.0
    out[3, 1] = 0.0
    out[3, 2] = 0.0
    out[3, 3] = 1.0


@njit(cache=True, nogil=True)
def fk_jacobian(chain, q, T_out, J_out):
    """Tip placement ``T_out`` (4×4, world) and axis-first world Jacobian ``J_out``
    (6×nv, columns ``(ω; v_O)``; a mimic joint adds its twist to its primary's column)
    of the :class:`Chain` at ``q``."""
    _fk(chain, q, T_out, J_out)


@njit(cache=True, nogil=True, inline="always")
def _times(r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz, P):
    """(R, p) · P for a 4×4 homogeneous P, as 12 scalars (kept in registers)."""
    return (r00 * P[0, 0] + r01 * P[1, 0] + r02 * P[2, 0],
            r00 * P[0, 1] + r01 * P[1, 1] + r02 * P[2, 1],
            r00 * P[0, 2] + r01 * P[1, 2] + r02 * P[2, 2],
            r10 * P[0, 0] + r11 * P[1, 0] + r12 * P[2, 0],
            r10 * P[0, 1] + r11 * P[1, 1] + r12 * P[2, 1],
            r10 * P[0, 2] + r11 * P[1, 2] + r12 * P[2, 2],
            r20 * P[0, 0] + r21 * P[1, 0] + r22 * P[2, 0],
            r20 * P[0, 1] + r21 * P[1, 1] + r22 * P[2, 1],
            r20 * P[0, 2] + r21 * P[1, 2] + r22 * P[2, 2],
            px + r00 * P[0, 3] + r01 * P[1, 3] + r02 * P[2, 3],
            py + r10 * P[0, 3] + r11 * P[1, 3] + r12 * P[2, 3],
            pz + r20 * P[0, 3] + r21 * P[1, 3] + r22 * P[2, 3])


@njit(cache=True, nogil=True, inline="always")
def _fk(chain, q, T_out, J_out):
    """:func:`fk_jacobian`. The running placement (R, p) lives in twelve scalars, which
    the compiler keeps in registers (2–3× faster than 4×4 work arrays)."""
    parent, post, kind, axis = chain.parent, chain.post, chain.kind, chain.axis
    rate, iq, iv, tip, base, nv = chain.rate, chain.iq, chain.iv, chain.tip, chain.base, chain.nv
    r00, r01, r02, px = base[0, 0], base[0, 1], base[0, 2], base[0, 3]
    r10, r11, r12, py = base[1, 0], base[1, 1], base[1, 2], base[1, 3]
    r20, r21, r22, pz = base[2, 0], base[2, 1], base[2, 2], base[2, 3]
    for c in range(nv):
        for r in range(6):
            J_out[r, c] = 0.0
    for k in range(kind.shape[0]):
        kk = kind[k]
        if not kk & AT_PARENT:
            r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz = _times(
                r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz, parent[k])
        # twist of the joint, from the frame before its motion
        x, y, z = axis[k, 0], axis[k, 1], axis[k, 2]
        a0 = r00 * x + r01 * y + r02 * z
        a1 = r10 * x + r11 * y + r12 * z
        a2 = r20 * x + r21 * y + r22 * z
        col, g = iv[k], rate[k]
        angle = g * q[iq[k]]
        if kk & 1 == REVOLUTE:
            J_out[0, col] += g * a0
            J_out[1, col] += g * a1
            J_out[2, col] += g * a2
            J_out[3, col] += g * (py * a2 - pz * a1)
            J_out[4, col] += g * (pz * a0 - px * a2)
            J_out[5, col] += g * (px * a1 - py * a0)
            # R ← R · Rot(axis, angle), origin unchanged: about a coordinate axis e_a
            # two columns turn (b = a+1, c = a+2 cyclic: r_b ← c r_b + s r_c,
            # r_c ← c r_c − s r_b); otherwise Rodrigues
            s, c = math.sin(angle), math.cos(angle)
            if x == 0.0 and y == 0.0 and z == 1.0:
                r00, r01 = c * r00 + s * r01, c * r01 - s * r00
                r10, r11 = c * r10 + s * r11, c * r11 - s * r10
                r20, r21 = c * r20 + s * r21, c * r21 - s * r20
            elif x == 1.0 and y == 0.0 and z == 0.0:
                r01, r02 = c * r01 + s * r02, c * r02 - s * r01
                r11, r12 = c * r11 + s * r12, c * r12 - s * r11
                r21, r22 = c * r21 + s * r22, c * r22 - s * r21
            elif x == 0.0 and y == 1.0 and z == 0.0:
                r02, r00 = c * r02 + s * r00, c * r00 - s * r02
                r12, r10 = c * r12 + s * r10, c * r10 - s * r12
                r22, r20 = c * r22 + s * r20, c * r20 - s * r22
            else:
                t = 1.0 - c
                m00, m01, m02 = c + t * x * x, t * x * y - s * z, t * x * z + s * y
                m10, m11, m12 = t * x * y + s * z, c + t * y * y, t * y * z - s * x
                m20, m21, m22 = t * x * z - s * y, t * y * z + s * x, c + t * z * z
                r00, r01, r02, r10, r11, r12, r20, r21, r22 = (
                    r00 * m00 + r01 * m10 + r02 * m20, r00 * m01 + r01 * m11 + r02 * m21,
                    r00 * m02 + r01 * m12 + r02 * m22, r10 * m00 + r11 * m10 + r12 * m20,
                    r10 * m01 + r11 * m11 + r12 * m21, r10 * m02 + r11 * m12 + r12 * m22,
                    r20 * m00 + r21 * m10 + r22 * m20, r20 * m01 + r21 * m11 + r22 * m21,
                    r20 * m02 + r21 * m12 + r22 * m22)
        else:
            J_out[3, col] += g * a0
            J_out[4, col] += g * a1
            J_out[5, col] += g * a2
            px += a0 * angle
            py += a1 * angle
            pz += a2 * angle
        if kk & HAS_POST:
            r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz = _times(
                r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz, post[k])
    (T_out[0, 0], T_out[0, 1], T_out[0, 2], T_out[1, 0], T_out[1, 1], T_out[1, 2],
     T_out[2, 0], T_out[2, 1], T_out[2, 2], T_out[0, 3], T_out[1, 3], T_out[2, 3]) = _times(
        r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz, tip)
    T_out[3, 0], T_out[3, 1], T_out[3, 2], T_out[3, 3] = 0.0, 0.0, 0.0, 1.0


@register_jitable
def log3(R, out):
    """Rotation vector of a rotation matrix, accurate at every angle: θ from
    ``atan2(sin θ, cos θ)``; the axis from the skew part below 90° and from the
    symmetric part ``(R + Rᵀ)/2 − cos θ I = (1 − cos θ) u uᵀ`` above (the skew part
    vanishes at a half turn), its sign from the skew part."""
    x = R[2, 1] - R[1, 2]
    y = R[0, 2] - R[2, 0]
    z = R[1, 0] - R[0, 1]
    s2 = math.sqrt(x * x + y * y + z * z)  # 2 sin θ
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    theta = math.atan2(0.5 * s2, c)
    if c >= 0.0:
        if s2 < 1e-300:
            out[0], out[1], out[2] = 0.0, 0.0, 0.0
            return
        f = theta / s2
        out[0], out[1], out[2] = f * x, f * y, f * z
        return
    i = 0
    for k in range(1, 3):
        if R[k, k] > R[i, i]:
            i = k
    u0 = 0.5 * (R[0, i] + R[i, 0]) - (c if i == 0 else 0.0)
    u1 = 0.5 * (R[1, i] + R[i, 1]) - (c if i == 1 else 0.0)
    u2 = 0.5 * (R[2, i] + R[i, 2]) - (c if i == 2 else 0.0)
    n = math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
    if u0 * x + u1 * y + u2 * z < 0.0:
        n = -n
    out[0], out[1], out[2] = theta * u0 / n, theta * u1 / n, theta * u2 / n


@register_jitable(inline="always")
def pose_error(T, target, length, e):
    """Error ``e`` (6) from ``T`` to ``target`` (4×4 world placements): world rotation
    vector of ``R_target R_Tᵀ`` [rad] and tip displacement ``p_target − p_T`` divided by
    ``length``; returns its norm. The closure residual of every solver
    (:func:`pkm_pin.solve.closure_error`); callable from Python and compiled code."""
    d00 = target[0, 0] * T[0, 0] + target[0, 1] * T[0, 1] + target[0, 2] * T[0, 2]
    d11 = target[1, 0] * T[1, 0] + target[1, 1] * T[1, 1] + target[1, 2] * T[1, 2]
    d22 = target[2, 0] * T[2, 0] + target[2, 1] * T[2, 1] + target[2, 2] * T[2, 2]
    d01 = target[0, 0] * T[1, 0] + target[0, 1] * T[1, 1] + target[0, 2] * T[1, 2]
    d10 = target[1, 0] * T[0, 0] + target[1, 1] * T[0, 1] + target[1, 2] * T[0, 2]
    d02 = target[0, 0] * T[2, 0] + target[0, 1] * T[2, 1] + target[0, 2] * T[2, 2]
    d20 = target[2, 0] * T[0, 0] + target[2, 1] * T[0, 1] + target[2, 2] * T[0, 2]
    d12 = target[1, 0] * T[2, 0] + target[1, 1] * T[2, 1] + target[1, 2] * T[2, 2]
    d21 = target[2, 0] * T[1, 0] + target[2, 1] * T[1, 1] + target[2, 2] * T[1, 2]
    x, y, z = d21 - d12, d02 - d20, d10 - d01
    if x * x + y * y + z * z < 1e-4 and d00 + d11 + d22 > 0.0:
        # small rotation: θu from the skew part 2 sin θ u, to O(θ⁴) relative
        f = 0.5 * (1.0 + (x * x + y * y + z * z) / 24.0)
        e[0], e[1], e[2] = f * x, f * y, f * z
    else:
        Rd = np.array([[d00, d01, d02], [d10, d11, d12], [d20, d21, d22]])
        log3(Rd, e[:3])
    s = 0.0
    for a in range(3):
        e[3 + a] = (target[a, 3] - T[a, 3]) / length
        s += e[a] * e[a] + e[3 + a] * e[3 + a]
    return math.sqrt(s)


@njit(cache=True, nogil=True)
def rpy_placements(X, out):
    """out[i] (4×4) = placement of row i of X = (x, y, z, roll, pitch, yaw), with
    ``R = Rz(yaw) Ry(pitch) Rx(roll)`` as ``pinocchio.rpy.rpyToMatrix``."""
    for i in range(X.shape[0]):
        cr, sr = math.cos(X[i, 3]), math.sin(X[i, 3])
        cp, sp = math.cos(X[i, 4]), math.sin(X[i, 4])
        cy, sy = math.cos(X[i, 5]), math.sin(X[i, 5])
        H = out[i]
        H[0, 0], H[0, 1], H[0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
        H[1, 0], H[1, 1], H[1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
        H[2, 0], H[2, 1], H[2, 2] = -sp, cp * sr, cp * cr
        H[0, 3], H[1, 3], H[2, 3] = X[i, 0], X[i, 1], X[i, 2]
        H[3, 0], H[3, 1], H[3, 2], H[3, 3] = 0.0, 0.0, 0.0, 1.0


@njit(cache=True, nogil=True)
def anchor_targets(poses, anchors, out):
    """out[k, i] = poses[i] · anchors[k] (4×4 homogeneous): where leg k's tip must be."""
    for k in range(anchors.shape[0]):
        A = anchors[k]
        for i in range(poses.shape[0]):
            P = poses[i]
            (out[k, i, 0, 0], out[k, i, 0, 1], out[k, i, 0, 2], out[k, i, 1, 0], out[k, i, 1, 1],
             out[k, i, 1, 2], out[k, i, 2, 0], out[k, i, 2, 1], out[k, i, 2, 2], out[k, i, 0, 3],
             out[k, i, 1, 3], out[k, i, 2, 3]) = _times(
                P[0, 0], P[0, 1], P[0, 2], P[1, 0], P[1, 1], P[1, 2], P[2, 0], P[2, 1], P[2, 2],
                P[0, 3], P[1, 3], P[2, 3], A)
            out[k, i, 3, 0], out[k, i, 3, 1], out[k, i, 3, 2], out[k, i, 3, 3] = 0.0, 0.0, 0.0, 1.0


@njit(cache=True, nogil=True)
def smooth_steps(X, length, out):
    """out[i] = whether pose i continues the path smoothly: ``|d_i − d_{i−1}| ≤ 0.1 |d_i|``
    for the steps ``d_i = X_i − X_{i−1}`` (translations divided by ``length``);
    False for the first two poses."""
    il = 1.0 / length
    for i in range(X.shape[0]):
        if i < 2:
            out[i] = False
            continue
        dd = 0.0
        d1 = 0.0
        for k in range(6):
            u = il if k < 3 else 1.0
            a = (X[i, k] - X[i - 1, k]) * u
            b = (X[i - 1, k] - X[i - 2, k]) * u
            dd += (a - b) * (a - b)
            d1 += a * a
        out[i] = dd <= 0.01 * d1


@njit(cache=True, nogil=True)
def path_steps(X, length, out):
    """out[i] = |X_{i+1} − X_i| (translations divided by ``length``), N − 1 steps."""
    il = 1.0 / length
    for i in range(X.shape[0] - 1):
        s = 0.0
        for k in range(6):
            d = (X[i + 1, k] - X[i, k]) * (il if k < 3 else 1.0)
            s += d * d
        out[i] = math.sqrt(s)


@njit(cache=True, nogil=True)
def is_path(X, length, samples):
    """Whether the rows of X, in their order, already form a path: no step over 3× the
    median step, and the median step at most 2× the median distance from a pose to its
    nearest neighbour (on ``samples`` poses spread over X; a shuffled grid has steps far
    longer than its spacing). Distances: translations divided by ``length``."""
    N = X.shape[0]
    if N < 3:
        return True
    il = 1.0 / length
    Y = X.copy()
    for i in range(N):
        for k in range(3):
            Y[i, k] *= il
    steps = np.empty(N - 1)
    path_steps(X, length, steps)
    median = np.median(steps)
    if steps.max() > 3.0 * median:
        return False
    m = min(samples, N)
    near = np.empty(m)
    for j in range(m):
        i = (j * (N - 1)) // max(m - 1, 1)
        best = np.inf
        for o in range(N):
            d0, d1, d2 = Y[o, 0] - Y[i, 0], Y[o, 1] - Y[i, 1], Y[o, 2] - Y[i, 2]
            d3, d4, d5 = Y[o, 3] - Y[i, 3], Y[o, 4] - Y[i, 4], Y[o, 5] - Y[i, 5]
            s = d0 * d0 + d1 * d1 + d2 * d2 + d3 * d3 + d4 * d4 + d5 * d5
            if s < best and o != i:
                best = s
        near[j] = math.sqrt(best)
    return median <= 2.0 * np.median(near)


# ============================================================== a whole mechanism
@dataclass(frozen=True)
class MechanismKernel:
    """The legs' kernels (``legs``) and their arrays flattened into one
    :class:`Chains` (``chains``; numba takes no lists of arrays), whose fields are
    also attributes of the kernel (``kernel.coords``, ``kernel.anchors`` …)."""

    legs: tuple
    chains: Chains

    def __post_init__(self) -> None:
        # the Chains' fields as plain attributes (a hot path reads them per pose)
        self.__dict__.update(self.chains._asdict())
        c = self.chains.coords
        #: each leg's slice of the concatenated configurations
        self.__dict__["slices"] = tuple(slice(int(a), int(b)) for a, b in zip(c[:-1], c[1:]))


def mechanism_kernel(mech, scales: np.ndarray) -> MechanismKernel | None:
    """Kernel of every leg of ``mech`` (``None`` if one leg has none)."""
    legs = [leg.kernel for leg in mech.legs]  # built once per leg
    if any(k is None for k in legs):
        return None
    joints = np.r_[0, np.cumsum([len(k.kind) for k in legs])].astype(np.int64)
    coords = np.r_[0, np.cumsum([k.nv for k in legs])].astype(np.int64)
    actuated = np.concatenate([coords[i] + np.atleast_1d(leg.actuated_q)
                               for i, leg in enumerate(mech.legs)]).astype(np.int64)
    cat = np.concatenate
    return MechanismKernel(tuple(legs), Chains(
        joints, coords, cat([k.parent for k in legs]), cat([k.post for k in legs]),
        cat([k.kind for k in legs]), cat([k.axis for k in legs]), cat([k.rate for k in legs]),
        cat([k.iq for k in legs]), cat([k.iv for k in legs]),
        np.stack([k.tip for k in legs]), np.stack([k.base for k in legs]),
        np.stack([a.homogeneous for a in mech.anchors]),
        cat([k.lower for k in legs]), cat([k.upper for k in legs]),
        np.array([k.length for k in legs], dtype=float), cat([k.units for k in legs]),
        actuated, np.asarray(scales, dtype=float), float(mech.characteristic_length)))


@njit(cache=True, nogil=True)
def twist_exp(xi, out):
    """4×4 world displacement ``exp`` of an axis-first twist ``(ω; v_O)``."""
    wx, wy, wz = xi[0], xi[1], xi[2]
    th2 = wx * wx + wy * wy + wz * wz
    th = math.sqrt(th2)
    if th < 1e-6:
        a, b = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0
    else:  # (1 − cos θ)/θ² as 2 sin²(θ/2)/θ²: no cancellation
        h = math.sin(0.5 * th)
        a, b = math.sin(th) / th, 2.0 * h * h / th2
    if th < 1e-2:  # (θ − sin θ)/θ³ by its series (the difference cancels)
        c = 1.0 / 6.0 - th2 / 120.0 + th2 * th2 / 5040.0
    else:
        c = (th - math.sin(th)) / (th2 * th)
    W = np.array([[0.0, -wz, wy], [wz, 0.0, -wx], [-wy, wx, 0.0]])
    W2 = W @ W
    for i in range(3):
        for j in range(3):
            d = 1.0 if i == j else 0.0
            out[i, j] = d + a * W[i, j] + b * W2[i, j]
    for i in range(3):
        s = 0.0
        for j in range(3):
            d = 1.0 if i == j else 0.0
            s += (d + b * W[i, j] + c * W2[i, j]) * xi[3 + j]
        out[i, 3] = s
    out[3, 0] = 0.0
    out[3, 1] = 0.0
    out[3, 2] = 0.0
    out[3, 3] = 1.0
