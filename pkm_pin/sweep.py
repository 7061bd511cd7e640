"""Evaluating a mechanism over many poses: ordered warm starts, batched screw algebra,
and any ``concurrent.futures.Executor`` (a Dask ``distributed`` client's executor too).

Poses are processed in chunks. Inside a chunk they are visited in a serpentine order of
their coordinates so that each assembly is warm-started from a neighbour (which keeps
the legs on the working mode of the home assembly). Results come back in the caller's
pose order.

Per chunk (when every leg has a compiled kernel, :mod:`pkm_pin.kernels`):

1. each leg follows the ordered poses in compiled code (the closure solver,
   :func:`pkm_pin.solve.track`, warm-started from the previous poses, extrapolated along
   smooth paths); a pose a leg misses is solved again in compiled code from the restart
   recipe :func:`pkm_pin.solve.start_configurations` (home, neutral, mid-limits, random
   starts with seed 0), and is recorded as a failure if none converges;
2. one Pinocchio pass per leg and pose at the solution (joint Jacobians and tip frame):
   Pinocchio's tip placement verifies the closure, its Jacobian gives the joint twists;
3. the analysis engine (:mod:`pkm_pin.engine`, the code of a single
   :class:`~pkm_pin.Analysis`) on every assembled pose, its singular bases warm-started
   from pose to pose.

Without kernels (a leg with a continuous or multi-DOF joint) the legs are solved by
:meth:`Leg.solve`; the Pinocchio pass and the engine are the same.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import threading
from concurrent.futures import Executor
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from . import engine
from .analysis import SINGULAR_TOL, classify, layout_of
from .errors import AssemblyError, InputError
from .screws import as_float_array, as_fraction
from .solve import pose_coordinates
from .tolerances import RANK_RTOL, REACH_MARGIN
from .transmission import sweep_cti, sweep_lti
from .twists import has_mimic, joint_lines, joint_twists, sweep_pass


@dataclass
class SweepResult:
    """Per-point results of a sweep, whichever backend ran it (arrays in the order of
    the points): :meth:`Mechanism.sweep` over platform poses (the per-leg engine), and
    :meth:`pkm_pin.linkage.Linkage.sweep` over actuated values (the general
    elimination, also ``LinkageSweep``). Both fill every field; what one backend does
    not compute is nan (``det`` of a general sweep; ``forward`` and ``inverse`` of a
    per-leg one), and a per-leg sweep's ``q`` is ``None`` (its tree configurations are
    not built pose by pose).

    Attributes:
        poses: (N, 6) x, y, z [m], roll, pitch, yaw [rad] of the output (nan where not
            assembled); :attr:`output_poses` as (N, 4, 4) placements.
        ok: (N,) whether the point assembled (:attr:`converged`).
        dof: (N,) DOF (−1 where not assembled): the platform's for a per-leg sweep (its
            ``output_dof`` too), the whole tree's (idle motions included) for a general
            one, as the two analyses' ``dof``.
        singularity: (N,) "none", "I", "II", "III" ("" where not assembled).
        type_I, type_II, condition: (N,) dimensionless indices (nan where not assembled).
        det: (N,) signed determinant of ``A Δ`` on the home platform twist basis carried
            to each pose (continuous sign across a slice; nan when not square).
        q_actuated: (N, n) actuated coordinates (nan where not assembled).
        lti: (N,) local transmission index ``min(ITI, OTI)`` (:mod:`pkm_pin.transmission`;
            nan where not assembled, or when the sweep ran with ``transmission=False``).
        cti: (N,) constraint transmission index (the smallest leg's; 1 when no leg has
            a constraint it could lose; nan as ``lti``).
        failures: (index, reason) of every pose that did not assemble.
        output_dof: (N,) the output's DOF (default ``dof``).
        forward, inverse: (N,) the general indices (:func:`pkm_pin.screws.motion_indices`;
            default nan).
        q: (N, nq) the tree's configurations (a general sweep; default ``None``).
    """

    poses: np.ndarray
    ok: np.ndarray
    dof: np.ndarray
    singularity: np.ndarray
    type_I: np.ndarray
    type_II: np.ndarray
    condition: np.ndarray
    det: np.ndarray
    q_actuated: np.ndarray
    failures: list = field(default_factory=list)
    lti: np.ndarray | None = None
    cti: np.ndarray | None = None
    output_dof: np.ndarray | None = None
    forward: np.ndarray | None = None
    inverse: np.ndarray | None = None
    q: np.ndarray | None = None

    def __post_init__(self):
        for name in ("lti", "cti", "forward", "inverse"):
            if getattr(self, name) is None:
                setattr(self, name, np.full(len(self.ok), np.nan))
        if self.output_dof is None:
            self.output_dof = np.array(self.dof, copy=True)

    @property
    def converged(self) -> np.ndarray:
        """(N,) whether the point assembled (:attr:`ok`)."""
        return self.ok

    @property
    def output_poses(self) -> np.ndarray:
        """(N, 4, 4) the output's placements (nan where not assembled)."""
        out = np.full((len(self.poses), 4, 4), np.nan)
        for i, x in enumerate(self.poses):
            if np.isfinite(x).all():
                out[i] = pin.SE3(pin.rpy.rpyToMatrix(*x[3:]), x[:3]).homogeneous
        return out

    def unordered(self, order: np.ndarray) -> SweepResult:
        """This result of a sweep over ``poses[order]`` given back in the order of
        ``poses`` (a grid walked in a snake so that warm starts hold, reported row by
        row): every per-pose array and the failures' indices permuted back."""
        import dataclasses

        order = np.asarray(order)
        back = np.empty_like(order)
        back[order] = np.arange(len(order))
        out = {}
        for f in dataclasses.fields(self):
            a = getattr(self, f.name)
            if isinstance(a, np.ndarray) and a.ndim >= 1 and a.shape[0] == len(order):
                out[f.name] = a[back]
            elif f.name == "failures":
                out[f.name] = sorted((int(order[i]), r) for i, r in a)
            else:
                out[f.name] = a
        return type(self)(**out)

    def arrays(self) -> dict[str, np.ndarray]:
        """Every array by name (for ``numpy.savez``; ``q`` when recorded)."""
        names = ("poses", "ok", "dof", "output_dof", "singularity", "type_I", "type_II",
                 "condition", "forward", "inverse", "det", "q_actuated", "lti", "cti")
        out = {k: getattr(self, k) for k in names}
        if self.q is not None:
            out["q"] = self.q
        return out


def pose_array(poses) -> np.ndarray:
    """(N, 6) x, y, z, roll, pitch, yaw from a sequence of ``pin.SE3`` or an (N, 6) array."""
    if isinstance(poses, np.ndarray) and poses.ndim == 2 and poses.shape[1] == 6:
        X = poses.astype(float)
    elif isinstance(poses, pin.SE3) or np.ndim(poses) == 0:
        raise InputError(f"poses must be a sequence of poses, got a single value of shape "
                         f"{np.shape(poses)} (wrap a single pose in a list)")
    else:
        poses = list(poses)
        if poses and all(isinstance(p, pin.SE3) for p in poses):
            X = np.array([pose_coordinates(p) for p in poses])
        else:
            X = as_float_array(poses, "poses")
    if X.ndim != 2 or X.shape[1] != 6:
        raise InputError(
            "poses must be a sequence of pinocchio.SE3 or an (N, 6) array of "
            f"x, y, z, roll, pitch, yaw; got shape {np.shape(X)}")
    if not np.all(np.isfinite(X)):
        raise InputError("poses must be finite (found NaN or inf)")
    return X


def serpentine_order(X: np.ndarray) -> np.ndarray:
    """Indices visiting the rows of X so that consecutive rows are neighbours on a grid.

    Lexicographic order on the coordinates that vary, with the direction of each
    inner coordinate reversed on every other value of the outer ones (boustrophedon).
    """
    if len(X) < 2:
        return np.arange(len(X))
    span = X.max(axis=0) - X.min(axis=0)
    cols = [c for c in np.argsort(-span) if span[c] > 0][::-1]  # innermost first
    if not cols:
        return np.arange(len(X))
    keys = np.zeros((len(X), len(cols)))
    for j, c in enumerate(cols):
        _, keys[:, j] = np.unique(np.round(X[:, c] / span[c], 9), return_inverse=True)
    # reverse inner keys on odd outer ranks
    for j in range(len(cols) - 2, -1, -1):
        outer = keys[:, j + 1:].sum(axis=1)
        keys[:, j] = np.where(outer % 2 == 1, -keys[:, j], keys[:, j])
    return np.lexsort(keys.T)


def pose_matrices(X: np.ndarray) -> np.ndarray:
    """(N, 4, 4) homogeneous placements from rows x, y, z, roll, pitch, yaw
    (``R = Rz(yaw) Ry(pitch) Rx(roll)``, as ``pinocchio.rpy.rpyToMatrix``)."""
    from .kernels import rpy_placements

    H = np.empty((len(X), 4, 4))
    rpy_placements(np.ascontiguousarray(X, dtype=float), H)
    return H


def smooth_steps(X: np.ndarray, length: float) -> np.ndarray:
    """(N,) whether pose i continues the path smoothly: the step from i−1 differs from
    the step before by less than a tenth of its size (a grid line, a smooth path), so
    that extrapolating the two previous solutions is a better warm start than the last.
    Translations are divided by ``length``."""
    from . import kernels

    out = np.empty(len(X), bool)
    kernels.smooth_steps(np.ascontiguousarray(X, dtype=float), float(length), out)
    return out


def _steps(X: np.ndarray, length: float) -> np.ndarray:
    """(N − 1,) sizes of the steps between consecutive rows (translations / length)."""
    from .kernels import path_steps

    out = np.empty(max(len(X) - 1, 0))
    path_steps(np.ascontiguousarray(X, dtype=float), float(length), out)
    return out


def visiting_order(X: np.ndarray, length: float) -> np.ndarray:
    """The order of the poses for warm starts (steps: translations divided by ``length``).

    The caller's own order is kept when it is already a path (:func:`kernels.is_path`:
    no step over 3× the median step, and the median step at most 2× the typical
    distance between nearest neighbours: a shuffled grid has steps far longer than its
    spacing). Otherwise :func:`serpentine_order`, unless the caller's order travels
    less."""
    from .kernels import is_path

    X = np.ascontiguousarray(X, dtype=float)
    if is_path(X, float(length), 16):
        return np.arange(len(X))
    serp = serpentine_order(X)
    return np.arange(len(X)) if _steps(X, length).sum() <= _steps(X[serp], length).sum() else serp


def out_of_reach(legs, Ts: np.ndarray, length: float) -> tuple[np.ndarray, list]:
    """``(ok, failures)`` of the poses whose tip targets ``Ts`` (legs × N × 4 × 4,
    world) some leg cannot reach at all: the distance from its base to the target lies
    outside the leg's :attr:`~pkm_pin.leg.Leg.reach` by more than
    :data:`~pkm_pin.tolerances.REACH_MARGIN` of the reach plus the characteristic
    ``length`` (a leg whose joints all meet at one point reaches that point alone, to
    rounding), ``ok`` false and the reason recorded; the other poses ``ok``."""
    ok, failures = np.ones(Ts.shape[1], bool), []
    bounds = []  # per leg: (r_min, r_max, margin), None where no bound is claimed
    for leg in legs:
        r_min, r_max = leg.reach
        bounds.append(None if r_min == 0.0 and not np.isfinite(r_max)
                      else (r_min, r_max, REACH_MARGIN * (r_max + length)))
    if all(b is None for b in bounds):
        return ok, failures
    # one vectorised test of every leg's squared distance first; the messages only
    # where some pose fails it
    base = np.array([leg.base.translation for leg in legs])
    offsets = Ts[:, :, :3, 3] - base[:, None]
    d2 = np.einsum("lni,lni->ln", offsets, offsets)
    lo = np.array([0.0 if b is None else max(b[0] - b[2], 0.0) for b in bounds])
    hi = np.array([np.inf if b is None else b[1] + b[2] for b in bounds])
    if not ((d2 > (hi * hi)[:, None]) | (d2 < (lo * lo)[:, None])).any():
        return ok, failures
    for leg, targets, b in zip(legs, Ts, bounds):
        if b is None:
            continue
        r_min, r_max, margin = b
        d = np.linalg.norm(targets[:, :3, 3] - leg.base.translation, axis=1)
        for i in np.flatnonzero(ok & ((d > r_max + margin) | (d < r_min - margin))):
            failures.append((int(i), f"leg {leg.name!r} cannot reach the pose: its tip "
                             f"would be {d[i]:.6g} from its base, outside its reach "
                             f"[{r_min:.6g}, {r_max:.6g}] (the joint offsets and strokes)"))
            ok[i] = False
    return ok, failures


def evaluate_chunk(mech, X: np.ndarray, reference: np.ndarray, rtol: float,
                   singular_tol: float, progress=None, restarts: int = 4,
                   transmission: bool = False) -> dict:
    """Assemble and analyse the poses of one chunk (rows of X, already ordered); with
    ``transmission``, the LTI and CTI too.

    Module-level so that process-based executors can pickle it."""
    kernel = mech.kernel
    layout = mech.sweep_layout  # cached: the default tolerance and reference
    if rtol != layout.rtol or not np.array_equal(reference, layout.reference):
        layout = layout_of(mech, rtol, reference)
    if kernel is None:
        return _evaluate_chunk_pinocchio(mech, X, layout, progress, restarts, transmission)
    return _evaluate_chunk_compiled(mech, kernel, X, layout, progress, restarts,
                                    transmission)


def _analyse(J, layout, centres, transmission: bool, out: dict, idx, lines=None) -> None:
    """The engine on the assembled poses ``idx`` (joint twists ``J``): fills ``out``'s
    scalar columns, and its ``lti`` and ``cti`` with ``transmission`` (the engine keeps
    A, the platform and leg constraint bases then, and
    :func:`pkm_pin.transmission.sweep_lti` and :func:`~pkm_pin.transmission.sweep_cti`
    run in NumPy; the home pose's constraint rank is 6 − the rows of the reference
    platform basis). ``lines``: the joint lines (:func:`pkm_pin.twists.joint_lines`;
    default ``J``)."""
    r = engine.analyse(J, layout, full=transmission, centres=centres)
    for key in ("dof", "type_I", "type_II", "condition", "det"):
        out[key][idx] = getattr(r, key)
    if transmission:
        lines = J if lines is None else lines
        out["lti"][idx] = sweep_lti(r.A, r.platform, r.dof, J, centres, layout, lines)
        out["cti"][idx] = sweep_cti(r.A, r.leg_constraints, r.leg_dims, lines, centres,
                                    layout, 6 - len(layout.reference))


#: Closure tolerance of the legs in a sweep (relative, as :meth:`Mechanism.assemble`).
SWEEP_TOL = 1e-12
#: A leg's last Newton step taken from a residual below this is not re-evaluated by the
#: compiled solver: Newton's next residual is ~TRUST² ≪ SWEEP_TOL, and Pinocchio's
#: closure check of every pose verifies it (a miss goes through Leg.solve).
TRUST = 1e-7


def _evaluate_chunk_compiled(mech, kernel, X, layout, progress, restarts,
                             transmission: bool = False) -> dict:
    from .kernels import anchor_targets
    from .solve import solve_from, start_configurations, track

    N, n, legs = len(X), mech.n_actuated, mech.legs
    poses = pose_matrices(X)
    along = smooth_steps(X, mech.characteristic_length)
    home = mech.home_assembly
    # 1. legs along the path, compiled; a target a leg misses is solved again from the
    #    restart recipe (home, neutral, mid-limits, random starts)
    Qs = []
    Ts = np.empty((len(legs), N, 4, 4))  # where each leg's tip must be
    anchor_targets(poses, kernel.anchors, Ts)
    ok, failures = out_of_reach(legs, Ts, mech.characteristic_length)  # not solved
    # the runs of consecutive poses between them (slices: no copies), each tracked from
    # home (as a miss is solved again)
    kept = np.flatnonzero(ok)
    cuts = np.flatnonzero(np.diff(kept) > 1) + 1
    runs = [(int(r[0]), int(r[-1]) + 1) for r in np.split(kept, cuts) if len(r)]
    for leg, lk, targets, q_home in zip(legs, kernel.legs, Ts, home.leg_q):
        Q = np.full((N, leg.nq), np.nan)
        res = np.full(N, np.inf)
        misses = 0
        for a, b in runs:
            # a last Newton step taken from a residual below TRUST is checked by Pinocchio
            steps = along[a:b].copy()
            steps[0] = False  # the run's first pose starts from home
            misses += track(lk.chain, targets[a:b], q_home.astype(float), steps,
                            SWEEP_TOL, 50, TRUST, Q[a:b], res[a:b])
        # a miss: neither converged (0 ≤ r ≤ tol) nor trusted (r < 0), as track counts
        miss = np.flatnonzero(~(res <= SWEEP_TOL) & ok) if misses else ()
        if len(miss):
            Qm, rm = np.empty((len(miss), leg.nq)), np.empty(len(miss))
            solve_from(lk.chain, np.ascontiguousarray(targets[miss]),
                       start_configurations(leg, q_home, restarts, seed=0), SWEEP_TOL, 100,
                       Qm, rm, np.zeros(len(miss), np.int64))
            Q[miss] = Qm
            for i, r in zip(miss[rm > SWEEP_TOL], rm[rm > SWEEP_TOL]):
                failures.append((int(i), str(AssemblyError(leg.name, r))))
                ok[i] = False
        Qs.append(Q)
    out = {**_unassembled(N, n), "ok": ok, "failures": failures}
    # 2., 3. by blocks of poses (their arrays stay in the processor's caches): the
    #    Pinocchio pass (closure check and joint twists), then the analysis engine
    own_lines = transmission and has_mimic(mech)  # the owners' own lines (one more pass)
    J_block = np.empty((min(N, BLOCK), sum(leg.nv for leg in legs), 6))  # reused per block
    for start in range(0, N, BLOCK):
        idx = start + np.flatnonzero(ok[start:start + BLOCK])
        Js, idx = _verified(mech, Qs, Ts, poses, idx, restarts, ok, failures, J_block)
        if not len(idx):
            continue
        lines = None
        if own_lines:
            lines = np.stack([joint_lines(mech, [Q[i] for Q in Qs], Js[k])
                              for k, i in enumerate(idx)])
        _analyse(Js, layout, X[idx, :3], transmission, out, idx, lines)
    idx = np.flatnonzero(ok)
    out["q_actuated"][idx] = np.concatenate([Q[idx][:, leg.actuated_q]
                                             for leg, Q in zip(legs, Qs)], axis=1)
    if progress is not None:
        progress(N)
    return out


#: Poses per block of a sweep chunk's Pinocchio pass and analysis: the block's arrays
#: (~0.5 MB for a 6-UPS) stay in the processor's caches (2000 poses at once: 6-UPS 13.1 →
#: 15.1 µs a pose, 3-RPR 5.9 → 6.9).
BLOCK = 256


def _verified(mech, Qs, Ts, poses, idx, restarts, ok, failures, out=None):
    """The Pinocchio pass at the poses ``idx`` (:func:`pkm_pin.twists.sweep_pass`, joint
    twists written in ``out`` when given); a
    closure Pinocchio does not confirm is assembled again by :meth:`Mechanism.assemble`
    (:func:`_assemble_again`), then checked again, or recorded in ``failures`` (``ok``
    cleared). Returns the joint twists and the poses that passed."""
    Js, bad = sweep_pass(mech, Qs, Ts, idx, SWEEP_TOL, out)
    if bad.any():  # a closure Pinocchio does not confirm: Leg.solve from there
        for i in idx[bad]:
            _assemble_again(mech, poses[i], [Q[i] for Q in Qs], restarts, Qs, i, ok,
                            failures)
        rows = np.flatnonzero(bad & ok[idx])  # positions in idx of the poses redone
        Js[rows], bad2 = sweep_pass(mech, Qs, Ts, idx[rows], SWEEP_TOL)
        for i in idx[rows][bad2]:
            failures.append((int(i), "the closure found is not confirmed by Pinocchio"))
            ok[i] = False
    keep = ok[idx]
    return (Js, idx) if keep.all() else (Js[keep], idx[keep])


def _assemble_again(mech, pose, guess, restarts, Qs, i, ok, failures) -> None:
    """:meth:`Mechanism.assemble` of pose i (4×4) from ``guess``: fills ``Qs``, or
    records the failure and clears ``ok[i]``."""
    try:
        asm = mech.assemble(pin.SE3(pose), guess, restarts=restarts)
    except AssemblyError as e:
        failures.append((int(i), str(e)))
        ok[i] = False
        return
    for Q, q in zip(Qs, asm.leg_q):
        Q[i] = q


def _evaluate_chunk_pinocchio(mech, X, layout, progress, restarts,
                              transmission: bool = False) -> dict:
    """:func:`evaluate_chunk` for legs without a compiled kernel."""
    N, n = len(X), mech.n_actuated
    ok = np.zeros(N, bool)
    q_act = np.full((N, n), np.nan)
    failures, solved = [], []
    previous, before = mech.home_assembly, None  # the last two solutions (for extrapolation)
    for i, x in enumerate(X):
        pose = pin.SE3(pin.rpy.rpyToMatrix(*x[3:]), x[:3])
        guess = previous
        if before is not None and np.allclose(x - X[i - 1], X[i - 1] - X[i - 2], rtol=1e-6,
                                              atol=1e-12):
            # equal consecutive steps (a grid line): extrapolate the leg configurations
            guess = [2 * a - b for a, b in zip(previous.leg_q, before.leg_q)]
        try:
            try:
                asm = mech.assemble(pose, guess, restarts=0)
            except AssemblyError:
                asm = mech.assemble(pose, mech.home_assembly, restarts=restarts)
        except AssemblyError as e:
            failures.append((i, str(e)))
        else:
            ok[i] = True
            q_act[i] = asm.q_actuated
            solved.append(asm)
            before = previous if i > 0 and ok[i - 1] else None
            previous = asm
        if progress is not None:
            progress(1)
    out = {**_unassembled(N, n), "ok": ok, "q_actuated": q_act, "failures": failures}
    if not solved:
        return out
    J = [joint_twists(mech, asm.leg_q) if asm.joint_twists is None else asm.joint_twists
         for asm in solved]  # the assembly's verifying pass gave them, when it ran
    lines = np.stack([joint_lines(mech, asm.leg_q, j) for asm, j in zip(solved, J)]
                     ) if transmission and has_mimic(mech) else None
    _analyse(np.stack(J), layout, np.array([asm.pose.translation for asm in solved]),
             transmission, out, ok, lines)
    return out


#: Mechanisms unpickled by :func:`_evaluate_shared`, per (digest, process); the most
#: recent last, at most :data:`_SHARED_MAX` kept.
_SHARED: dict = {}
_SHARED_MAX = 32
_SHARED_LOCK = threading.Lock()


def _evaluate_shared(blob: bytes, digest: str, *args) -> dict:
    """:func:`evaluate_chunk` on the mechanism pickled in ``blob`` (SHA-256 ``digest``).

    Each worker process unpickles it once and its threads share that copy for the next
    chunks of the sweep (each thread evaluates Pinocchio with its own ``Data``, see
    :attr:`pkm_pin.Leg.data`): a task then costs its poses, not a mechanism's
    deserialisation and set-up (~10 ms)."""
    key = (digest, os.getpid())
    with _SHARED_LOCK:
        mech = _SHARED.get(key)
        if mech is None:
            if hashlib.sha256(blob).hexdigest() != digest:
                raise RuntimeError("sweep task: the mechanism's bytes do not match their "
                                   "digest")
            mech = _SHARED[key] = pickle.loads(blob)
            while len(_SHARED) > _SHARED_MAX:
                del _SHARED[next(iter(_SHARED))]
    return evaluate_chunk(mech, *args)


def sweep(mech, poses, *, executor: Executor | None = None, chunk_size: int = 2000,
          progress: bool = False, rtol: float | None = None,
          singular_tol: float = SINGULAR_TOL, transmission: bool = False,
          checkpoint=None) -> SweepResult:
    """Assemble and analyse the mechanism at every pose.

    Args:
        mech: The :class:`~pkm_pin.mechanism.Mechanism`.
        poses: Sequence of ``pin.SE3`` or (N, 6) array of x, y, z, roll, pitch, yaw.
        executor: Any ``concurrent.futures.Executor`` (threads, processes, or a Dask
            ``distributed.Client.get_executor()``); chunks of ``chunk_size`` ordered
            poses are its tasks. ``None``: evaluate here.
        chunk_size: Poses per task (each task warm-starts from the home assembly).
        progress: Show a progress bar on stderr (tqdm).
        rtol: Relative tolerance of rank decisions (default
            :data:`pkm_pin.tolerances.RANK_RTOL`).
        singular_tol: Threshold of the closeness indices.
        transmission: Also compute the local and constraint transmission indices
            ``lti`` and ``cti`` (the engine then keeps every pose's actuation wrenches,
            platform and constraint bases, and the indices run in NumPy over the
            chunk); by default both are nan.
        checkpoint: A :class:`pkm_pin.checkpoint.Checkpoint` (its stage ``"sweep"``)
            or one of its stages: each chunk's results are recorded there as they come
            (written to ``PREFIX.partial.npz``), chunks already done in it are not
            evaluated again, and an interrupt (Ctrl-C, SIGTERM under
            :func:`~pkm_pin.checkpoint.graceful_stop`) writes what is done and raises
            :class:`~pkm_pin.checkpoint.Interrupted`. Chunks are pure tasks: a Dask
            worker lost mid-sweep has its chunk run again elsewhere, with the same
            result.

    Returns:
        A :class:`SweepResult`; poses that do not assemble are recorded in
        ``failures`` and hold nan / −1 / "".
    """
    X = pose_array(poses)
    if int(chunk_size) < 1:
        raise InputError(f"chunk_size must be a positive integer, got {chunk_size}")
    rtol = RANK_RTOL if rtol is None else as_fraction(rtol, "rtol")
    singular_tol = as_fraction(singular_tol, "singular_tol")
    order = visiting_order(X, mech.characteristic_length)
    reference = mech.sweep_layout.reference  # the home platform basis (carried determinant)
    chunks = [order[i:i + int(chunk_size)] for i in range(0, len(order), int(chunk_size))]
    stage = _stage_of(checkpoint)
    parts: list = [None] * len(chunks)
    if stage is not None:
        parts = stage.begin(X, chunks, {"rtol": rtol, "singular_tol": singular_tol,
                                        "transmission": bool(transmission),
                                        "reference": reference},
                             _unassembled(len(X), mech.n_actuated))
    todo = [k for k, p in enumerate(parts) if p is None]
    bar = _progress_bar(len(X)) if progress else None
    if bar is not None and len(todo) < len(chunks):
        bar.update(len(X) - sum(len(chunks[k]) for k in todo))
    from .checkpoint import recording

    with recording(stage):
        if executor is None:
            tick = bar.update if bar is not None else None
            for k in todo:
                parts[k] = evaluate_chunk(mech, X[chunks[k]], reference, rtol,
                                          singular_tol, tick, transmission=transmission)
                if stage is not None:
                    stage.record(chunks[k], parts[k])
        else:
            _run_on(executor, mech, X, chunks, todo, parts, stage, bar, reference, rtol,
                    singular_tol, transmission)
    if bar is not None:
        bar.close()
    return _gather(X, chunks, parts, mech.n_actuated, singular_tol)


def _stage_of(checkpoint):
    """The checkpoint stage of a sweep: a Checkpoint's ``"sweep"``, or the stage given."""
    if checkpoint is None:
        return None
    from .checkpoint import Checkpoint

    return checkpoint.stage("sweep") if isinstance(checkpoint, Checkpoint) else checkpoint


def _run_on(executor, mech, X, chunks, todo, parts, stage, bar, reference, rtol,
            singular_tol, transmission) -> None:
    """The chunks ``todo`` as tasks of ``executor``: ``parts`` filled as they finish
    (recorded in ``stage`` in that order; a stop request is seen within half a
    second). The mechanism is pickled once per sweep and every worker unpickles its own
    copy once (:func:`_evaluate_shared`); bytes also spare Dask the tokenising of the
    object at each submit (~20 ms). A task is pure (its poses in, its arrays out): an
    executor may run it again (Dask does when a worker dies)."""
    from concurrent.futures import FIRST_COMPLETED, wait

    blob = pickle.dumps(mech, protocol=pickle.HIGHEST_PROTOCOL)
    digest = hashlib.sha256(blob).hexdigest()
    futures = {executor.submit(_evaluate_shared, blob, digest, X[chunks[k]], reference, rtol,
                               singular_tol, None, 4, transmission): k for k in todo}
    pending = set(futures)
    try:
        while pending:
            finished, pending = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
            for fut in sorted(finished, key=futures.get):
                k = futures[fut]
                parts[k] = fut.result()
                if bar is not None:
                    bar.update(len(chunks[k]))
                if stage is not None:
                    stage.record(chunks[k], parts[k], check=False)
            if stage is not None:
                stage.cp.poll()
    except BaseException:  # Ctrl-C or a failed chunk: drop the chunks not started
        for fut in pending:
            fut.cancel()
        raise


def _unassembled(N: int, n: int) -> dict:
    """The per-pose arrays of N poses none of which is assembled yet (n actuators):
    ``ok`` False, −1 degrees of freedom, nan elsewhere."""
    nan = np.full(N, np.nan)
    return {"ok": np.zeros(N, bool), "q_actuated": np.full((N, n), np.nan),
            "dof": np.full(N, -1), "type_I": nan, "type_II": nan.copy(),
            "condition": nan.copy(), "det": nan.copy(), "lti": nan.copy(),
            "cti": nan.copy()}


def _progress_bar(total: int):
    from tqdm import tqdm

    return tqdm(total=total, unit="pose", desc="sweep", leave=False)


def _gather(X, chunks, parts, n, singular_tol) -> SweepResult:
    res = _unassembled(len(X), n)
    failures = []
    for idx, part in zip(chunks, parts):
        for key in res:
            res[key][idx] = part[key]
        failures += [(int(idx[i]), reason) for i, reason in part["failures"]]
    # nan (not assembled) compares False: "none", then "" where not ok
    sing = np.where(res["ok"], classify(res["type_I"], res["type_II"], singular_tol), "")
    return SweepResult(X, res["ok"], res["dof"], sing, res["type_I"], res["type_II"],
                       res["condition"], res["det"], res["q_actuated"], sorted(failures),
                       res["lti"], res["cti"])
