"""Joint twists from Pinocchio: the one Pinocchio pass per configuration.

The columns of Pinocchio's WORLD Jacobian of a leg's tip frame are its joint twists
(linear-first ``(v; ω)``, about the origin of the leg's URDF root frame); they become
axis-first twists ``(ω; v_O)`` about the world origin through
:func:`pkm_pin.screws.world_twist_rows` (the leg's base placement applied). Rows of the
legs one after the other are the input of the analysis engine (:mod:`pkm_pin.engine`).

* :func:`joint_twists` — one configuration (an :class:`~pkm_pin.Analysis`);
* :func:`sweep_pass` — many configurations of a sweep, with the closure check of every
  leg against its target placement (Pinocchio's tip placement confirms the compiled
  leg solver's solution).
"""

from __future__ import annotations

import io
import threading
from contextlib import contextmanager
from itertools import repeat
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numba import njit

from . import screws
from .compiling import SameTypes, prefer_compiled
from .kernels import _compose, pose_error
from .screws import probe_tip, world_twist_rows

#: The calling thread's scratch buffer of :func:`_scratch`.
_SCRATCH = threading.local()


@contextmanager
def _scratch(size: int):
    """A byte buffer of at least ``size`` bytes, at position 0, that the calling thread
    reuses from one sweep block to the next, for Pinocchio's arrays as they come.

    A fresh buffer per block (0.7 MB for 256 poses of a 6-UPS) may be new memory from
    the system each time, depending on the allocator's history in the process: ~700
    page faults per 1000-pose sweep, 0.5–1 µs a pose (measured). Arrays read from the
    buffer must be dropped inside the ``with`` block; a buffer still exported then (an
    exception) is not reused."""
    buf = getattr(_SCRATCH, "buf", None)
    if buf is None or _SCRATCH.size < size:
        buf, _SCRATCH.size = io.BytesIO(bytes(size)), size
    _SCRATCH.buf = None  # taken (a nested use makes its own)
    buf.seek(0)
    try:
        yield buf
    finally:
        try:
            buf.write(b"")  # raises while an array still reads the buffer
        except BufferError:
            pass
        else:
            _SCRATCH.buf = buf


class LegFrames(NamedTuple):
    """The constant frames of a base–legs–platform mechanism, as arrays.

    Attributes:
        bases: (legs, 4, 4) placement of each leg's URDF root in the world.
        anchors: (legs, 4, 4) placement of each leg's tip frame in the platform frame.
        coords: (legs + 1,) offsets of the legs' velocity coordinates (and twist rows).
        lengths: (legs,) characteristic length of each leg [m].
    """

    bases: np.ndarray
    anchors: np.ndarray
    coords: np.ndarray
    lengths: np.ndarray


def leg_frames(mechanism) -> LegFrames:
    """The :class:`LegFrames` of a mechanism."""
    legs = mechanism.legs
    return LegFrames(np.stack([leg.base.homogeneous for leg in legs]),
                     np.stack([a.homogeneous for a in mechanism.anchors]),
                     np.r_[0, np.cumsum([leg.nv for leg in legs])].astype(np.int64),
                     np.array([leg.characteristic_length for leg in legs], dtype=float))


def leg_jacobian(leg, q: np.ndarray, data=None) -> np.ndarray:
    """Pinocchio's WORLD Jacobian (6 × nv, ``(v; ω)``, URDF root frame) of the leg's tip
    at ``q``, from one pass (``data``: default the calling thread's ``leg.data``)."""
    model = leg.model
    if data is None:
        data = leg.data
    J = pin.computeJointJacobians(model, data, q)
    if model.nvExtended != model.nv:  # mimic joints have their own columns in data.J
        J = pin.getFrameJacobian(model, data, leg.tip_id, pin.WORLD)
    return J


def joint_twists(mechanism, leg_q) -> np.ndarray:
    """The joint twists of every leg at one configuration (nv × 6 rows, axis-first, about
    the world origin; legs one after the other)."""
    out = np.empty((sum(leg.nv for leg in mechanism.legs), 6))
    row = 0
    for leg, q in zip(mechanism.legs, leg_q):
        q = np.asarray(q, dtype=float)
        world_twist_rows(leg_jacobian(leg, q), leg.base.homogeneous, out[row:row + leg.nv])
        row += leg.nv
    return out


def has_mimic(mechanism) -> bool:
    """Whether a leg of ``mechanism`` has a joint mimicking another (then
    :func:`joint_lines` differ from :func:`joint_twists`)."""
    return any(leg.has_mimic for leg in mechanism.legs)


def joint_lines(mechanism, leg_q, J: np.ndarray) -> np.ndarray:
    """The twist of the joint that owns each velocity coordinate, alone (nv × 6 rows,
    axis-first, world origin): where joints mimic another (a Delta's parallelogram,
    written ``R2 … R5 = −R2``), the coordinate's column of :func:`joint_twists` is the
    sum of all their twists (there a translation), while the transmission indices need
    the line of the joint where the force reaches the actuated link (the elbow).
    ``J`` (:func:`joint_twists` at ``leg_q``) is returned as it is when no leg has a
    mimic joint."""
    legs = mechanism.legs
    if not has_mimic(mechanism):
        return J
    out = np.array(J, dtype=float, copy=True)
    row = 0
    for leg, q in zip(legs, leg_q):
        if leg.has_mimic:
            model, data = leg.model, leg.data  # the thread's data
            pin.computeJointJacobians(model, data, np.asarray(q, dtype=float))
            for j in range(1, model.njoints):
                joint = model.joints[j]
                if joint.nv == 1:  # the owner of its coordinate (mimics have none)
                    col = np.reshape(pin.getJointJacobian(model, data, j, pin.WORLD),
                                     (6, -1))[:, joint.idx_v]
                    out[row + joint.idx_v] = screws.transform(screws.from_pinocchio(col),
                                                              leg.base)
        row += leg.nv
    return out


def verified_twists(mechanism, leg_q, pose: np.ndarray, flat=None
                    ) -> tuple[np.ndarray, np.ndarray, float]:
    """The joint twists at one configuration (as :func:`joint_twists`) and each leg's
    closure error against the platform pose (4×4): :func:`pkm_pin.kernels.pose_error`
    of Pinocchio's tip placement from ``pose · anchor``, from the same single pass:
    :class:`TreePass` (every leg in one Pinocchio call) when the mechanism has no
    mimic joint, else one pass per leg. ``flat``: the legs' configurations already
    concatenated (saves a copy).

    Returns ``(J, errors, worst)``: (nv, 6) rows, (legs,) errors and the largest (nan
    when one is)."""
    tree_pass = mechanism.tree_pass
    if tree_pass is not None:
        return tree_pass.run(np.concatenate(leg_q) if flat is None else flat, pose)
    legs = mechanism.legs
    f = mechanism.leg_frames
    # Pinocchio's Jacobian and tip placement of each leg, one after the other, copied
    # as they come into one byte buffer (as in _leg_pass), read by pose_outputs
    buf = io.BytesIO()
    write, place = buf.write, pin.updateFramePlacement
    for leg, q in zip(legs, leg_q):
        write(leg_jacobian(leg, np.asarray(q, dtype=float)))
        write(place(leg.model, leg.data, leg.tip_id).homogeneous)
    flat = np.frombuffer(buf.getbuffer(), dtype=np.float64)
    if flat.shape[0] != 6 * f.coords[-1] + 16 * len(legs):
        raise RuntimeError("Pinocchio's Jacobians and placements do not add up to the legs'")
    J = np.empty((f.coords[-1], 6))
    errors = np.empty(len(legs))
    # a one-off call on a fresh installation runs the source (no 7 s compilation)
    outputs = pose_outputs if prefer_compiled(pose_outputs) else pose_outputs.py_func
    worst = outputs(flat, f.bases, f.anchors, f.coords, f.lengths, pose, J, errors)
    return J, errors, worst


@njit(cache=True, nogil=True)
def pose_outputs(flat, bases, anchors, coords, lengths, pose, J_out, errors):
    """:func:`verified_twists` in compiled code. ``flat`` holds, leg after leg,
    Pinocchio's WORLD Jacobian (6 × nv, C order) and tip placement (4 × 4) in the leg's
    root frame. ``J_out`` (nv × 6) receives the axis-first world twists, ``errors[k]``
    leg k's :func:`~pkm_pin.kernels.pose_error` from ``pose · anchors[k]``; returns the
    largest error (nan if one is nan)."""
    worst = 0.0
    tip = np.empty((4, 4))
    target = np.empty((4, 4))
    e = np.empty(6)
    o = 0
    for k in range(coords.shape[0] - 1):
        c0, c1 = coords[k], coords[k + 1]
        nv = c1 - c0
        Jp = flat[o:o + 6 * nv].reshape(6, nv)
        H = flat[o + 6 * nv:o + 6 * nv + 16].reshape(4, 4)
        o += 6 * nv + 16
        _compose(bases[k], H, tip)
        _compose(pose, anchors[k], target)
        errors[k] = pose_error(tip, target, lengths[k], e)
        if errors[k] > worst or errors[k] != errors[k]:  # a nan stays the worst
            worst = errors[k]
        world_twist_rows(Jp, bases[k], J_out[c0:c1])
    return worst


class TreePass:
    """Pinocchio's pass over every leg of a mechanism at one configuration, in one call.

    The tree is :attr:`Mechanism.closure_model`'s without the platform (each leg under
    the universe at its base placement, so the columns of the tree's WORLD joint
    Jacobian are the joint twists about the world origin) with one more joint per leg:
    a spherical joint at the leg's tip frame, held at rest, that moves nothing (a
    *probe*). Its three columns of the WORLD Jacobian are the unit rotations about the
    tip frame's axes, ``(v; ω) = (p × r_a; r_a)``, where ``r_a`` are the columns of the
    tip's rotation and ``p`` its origin (``p = ½ Σ_a r_a × (p × r_a)``). One
    ``computeJointJacobians`` thus gives the joint twists and every tip placement,
    where reading each placement back costs as much as the pass.

    For mechanisms without mimic joints (whose tree Jacobian has one column per
    velocity coordinate). ``Data`` per thread, as :attr:`Leg.data`; safe to use from
    several threads.
    """

    def __init__(self, mechanism):
        from .model.closure_model import PLATFORM_JOINT

        full = mechanism.closure_model.tree  # the legs alone: the platform's joint locked
        tree = pin.buildReducedModel(full, [full.getJointId(PLATFORM_JOINT)], pin.neutral(full))
        legs = mechanism.legs
        nq, nv = sum(leg.nq for leg in legs), sum(leg.nv for leg in legs)
        for leg in legs:
            tip = tree.frames[tree.getFrameId(f"{leg.name}/{leg.tip}")]
            tree.addJoint(tip.parentJoint, pin.JointModelSpherical(), tip.placement,
                          f"{leg.name}/{leg.tip}/probe")
        self.tree = tree
        #: velocity column of each leg's probe
        self.probes = np.array([tree.joints[j].idx_v
                                for j in range(tree.njoints - len(legs), tree.njoints)],
                               dtype=np.int64)
        #: the probes, at rest (their motion is not read)
        self.rest_q = pin.neutral(tree)[nq:]
        self.frames = mechanism.leg_frames
        self.nv, self.shape = nv, (6, tree.nv)
        if nv != self.frames.coords[-1]:
            raise ValueError("the tree's legs do not have the mechanism's coordinates")
        self._local = threading.local()

    def __getstate__(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k != "_local"}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._local = threading.local()

    def _data(self) -> pin.Data:
        """The calling thread's ``Data`` of the tree."""
        try:
            return self._local.data
        except AttributeError:
            self._local.data = self.tree.createData()
            return self._local.data

    def _check(self, Jt: np.ndarray) -> None:
        """Pinocchio's Jacobian is read by compiled code that trusts its type
        (:class:`~pkm_pin.compiling.SameTypes`)."""
        if Jt.shape != self.shape or Jt.dtype != np.float64 or not Jt.flags.c_contiguous:
            raise RuntimeError(f"Pinocchio's Jacobian has shape {Jt.shape}, type {Jt.dtype}: "
                               f"expected C-ordered float64 {self.shape}")

    def run(self, Q: np.ndarray, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """:func:`verified_twists` at the legs' configurations ``Q`` (concatenated)."""
        Jt = pin.computeJointJacobians(self.tree, self._data(),
                                       np.concatenate((Q, self.rest_q)))
        self._check(Jt)
        J = np.empty((self.nv, 6))
        errors = np.empty(len(self.probes))
        f = self.frames
        worst = _tree_outputs(self.probes, Jt, f.anchors, f.lengths, pose, J, errors)
        return J, errors, worst

    def many(self, Qs, targets: np.ndarray, idx: np.ndarray, tol: float, out=None
             ) -> tuple[np.ndarray, np.ndarray]:
        """:func:`sweep_pass`: one call per pose.

        Pinocchio returns a new array per call; each is copied at once into the
        thread's scratch buffer (:func:`_scratch`) and freed, so the allocator recycles
        its memory (as :func:`_leg_pass`)."""
        M = len(idx)
        rows = np.empty((M, self.tree.nq))
        c = 0
        for Q in Qs:
            rows[:, c:c + Q.shape[1]] = Q[idx]
            c += Q.shape[1]
        rows[:, c:] = self.rest_q
        data, tree, jacobians = self._data(), self.tree, pin.computeJointJacobians
        J = np.empty((M, self.nv, 6)) if out is None else out[:M]
        bad = np.zeros(M, bool)
        size = 8 * M * 6 * self.shape[1]
        with _scratch(size) as buf:
            if M:
                Jt = jacobians(tree, data, rows[0])
                self._check(Jt)
                buf.write(Jt)
                buf.writelines(map(jacobians, repeat(tree), repeat(data), rows[1:]))
            if buf.tell() != size:
                raise RuntimeError("Pinocchio's Jacobians do not add up to the poses'")
            Jt = np.frombuffer(buf.getbuffer(), dtype=np.float64, count=size // 8)
            tree_outputs_many(self.probes, Jt.reshape(M, 6, self.shape[1]), targets,
                              np.asarray(idx, dtype=np.int64), self.frames.lengths,
                              float(tol), J, bad)
            del Jt  # the buffer is read: free for the next block
        return J, bad


@njit(cache=True, nogil=True)
def tree_outputs(probes, Jt, anchors, lengths, pose, J_out, errors):
    """:meth:`TreePass.run` in compiled code: ``J_out`` (nv × 6) receives the axis-first
    twists of the first nv columns of the tree's WORLD Jacobian ``Jt`` (6 × nv_tree);
    ``errors[k]`` is leg k's :func:`~pkm_pin.kernels.pose_error` from ``pose ·
    anchors[k]`` of its tip placement (:func:`probe_tip`, its probe's columns from
    ``probes[k]``). Returns the largest error (nan if one is)."""
    world_twist_rows(Jt[:, :J_out.shape[0]], np.eye(4), J_out)
    worst = 0.0
    tip = np.empty((4, 4))
    target = np.empty((4, 4))
    e = np.empty(6)
    for k in range(probes.shape[0]):
        probe_tip(Jt, probes[k], tip)
        _compose(pose, anchors[k], target)
        errors[k] = pose_error(tip, target, lengths[k], e)
        if errors[k] > worst or errors[k] != errors[k]:  # a nan stays the worst
            worst = errors[k]
    return worst


@njit(cache=True, nogil=True)
def tree_outputs_many(probes, Jt, targets, idx, lengths, tol, J_out, bad):
    """:meth:`TreePass.many` in compiled code: for each pose ``m`` (``Jt[m]``, the tree's
    WORLD Jacobian at pose ``idx[m]``), ``J_out[m]`` receives the joint twists as
    :func:`tree_outputs`, and ``bad[m]`` is set when a leg's tip misses its target
    ``targets[k, idx[m]]`` by more than ``tol`` (:func:`~pkm_pin.kernels.pose_error`, or
    nan)."""
    I4 = np.eye(4)
    tip = np.empty((4, 4))
    e = np.empty(6)
    nv = J_out.shape[1]
    for m in range(Jt.shape[0]):
        world_twist_rows(Jt[m, :, :nv], I4, J_out[m])
        for k in range(probes.shape[0]):
            probe_tip(Jt[m], probes[k], tip)
            if not pose_error(tip, targets[k, idx[m]], lengths[k], e) <= tol:
                bad[m] = True


#: :func:`tree_outputs` as :meth:`TreePass.run` calls it (its arguments keep their types)
_tree_outputs = SameTypes(tree_outputs, key=0, plain=True)


def sweep_pass(mechanism, Qs, targets, idx, tol: float, out=None):
    """Pinocchio's pass at the poses ``idx`` (increasing) of a sweep: one call per pose
    on the legs' tree (:meth:`TreePass.many`) when no leg has mimic joints, else one
    pass per leg and pose.

    Args:
        Qs: Per leg, the (N, nq) configurations.
        targets: (legs, N, 4, 4) world placements each leg's tip must reach.
        idx: Indices of the poses to evaluate.
        tol: Closure tolerance (as :func:`pkm_pin.leg.pose_error`).
        out: An (at least M, nv, 6) array to write the joint twists in (its first M
            rows, returned), so that a sweep's blocks reuse one array; default: a new one.

    Returns:
        ``(J, bad)``: the (M, nv, 6) joint twists of the legs one after the other, and
        (M,) whether a leg's tip (Pinocchio's placement) misses its target by more than
        ``tol``.
    """
    M = len(idx)
    nv = sum(leg.nv for leg in mechanism.legs)
    if out is not None and (out.shape[0] < M or out.shape[1:] != (nv, 6)):
        raise ValueError(f"out of shape {out.shape}: expected at least ({M}, {nv}, 6)")
    if mechanism.tree_pass is not None:
        return mechanism.tree_pass.many(Qs, targets, idx, tol, out)
    J = np.empty((M, nv, 6)) if out is None else out[:M]
    bad = np.zeros(M, bool)
    row = 0
    for k, (leg, Q) in enumerate(zip(mechanism.legs, Qs)):
        with _scratch(8 * M * (6 * leg.nv + 16)) as buf:
            Jp, H = _leg_pass(leg, list(np.ascontiguousarray(Q[idx], dtype=float)), buf)
            leg_outputs(H, Jp, leg.base.homogeneous, targets[k], idx,
                        float(leg.characteristic_length), tol, J, row, bad)
            del Jp, H  # the buffer is read: free for the next leg
        row += leg.nv
    return J, bad


def _leg_pass(leg, rows: list, buf: io.BytesIO) -> tuple[np.ndarray, np.ndarray]:
    """Pinocchio's WORLD Jacobians (M, 6, nv) and tip placements (M, 4, 4) of one leg at
    the configurations ``rows``: views of ``buf`` (:func:`_scratch`, from its position
    0).

    Pinocchio returns a new array per call; each is copied at once into the byte buffer
    and freed, so the allocator recycles its memory: 2–3 µs per 6-UPS pose cheaper than
    assigning into numpy rows or stacking a list (measured). Pinocchio's arrays must be
    C-ordered float64 of the expected shapes: checked on the first pose, and the number
    of bytes at the end."""
    model, data, tip = leg.model, leg.data, leg.tip_id
    M, nj = len(rows), 6 * leg.nv
    if M:
        first = (leg_jacobian(leg, rows[0]), pin.updateFramePlacement(model, data, tip).homogeneous)
        for a, shape in zip(first, ((6, leg.nv), (4, 4))):
            if a.dtype != np.float64 or a.shape != shape or not a.flags.c_contiguous:
                raise RuntimeError(f"leg {leg.name!r}: Pinocchio returned an array of shape "
                                   f"{a.shape}, type {a.dtype}; expected C-ordered float64 "
                                   f"{shape}")
    write, place = buf.write, pin.updateFramePlacement
    if model.nvExtended == model.nv:
        # computeJointJacobians returns the chain's WORLD Jacobian: every joint of a
        # leg's chain supports its tip
        jacobians = pin.computeJointJacobians
        for q in rows:
            write(jacobians(model, data, q))
            write(place(model, data, tip).homogeneous)
    else:
        for q in rows:
            write(leg_jacobian(leg, q))
            write(place(model, data, tip).homogeneous)
    if buf.tell() != 8 * M * (nj + 16):
        raise RuntimeError(f"leg {leg.name!r}: Pinocchio's arrays do not add up to "
                           f"{M} Jacobians and placements")
    B = np.frombuffer(buf.getbuffer(), dtype=np.float64, count=M * (nj + 16))
    B = B.reshape(M, nj + 16)
    return B[:, :nj].reshape(M, 6, leg.nv), B[:, nj:].reshape(M, 4, 4)


@njit(cache=True, nogil=True)
def leg_outputs(H, Jp, base, targets, idx, length, tol, J_out, c0, bad):
    """Post-process one leg's Pinocchio pass over the poses ``idx``.

    Args:
        H: (M, 4, 4) tip placements from Pinocchio (URDF root frame).
        Jp: (M, 6, nv) Pinocchio WORLD Jacobians (root frame).
        base: root placement in the world (4×4).
        targets: (N, 4, 4) world placements the tip must reach (pose · anchor).
        J_out: (M, nv_total, 6) receives the axis-first twists in rows c0:c0+nv.
        bad: (M,) set where the closure error exceeds ``tol`` (or is nan):
            :func:`~pkm_pin.kernels.pose_error`, the residual of every solver.
    """
    M = H.shape[0]
    nv = Jp.shape[2]
    tip = np.empty((4, 4))
    e = np.empty(6)
    for j in range(M):
        _compose(base, H[j], tip)  # tip in the world
        if not pose_error(tip, targets[idx[j]], length, e) <= tol:
            bad[j] = True
        world_twist_rows(Jp[j], base, J_out[j, c0:c0 + nv])
