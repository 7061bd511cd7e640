"""Evaluating a mechanism over many poses: ordered warm starts, batched screw algebra,
and any ``concurrent.futures.Executor`` (a Dask ``distributed`` client's executor too).

Poses are processed in chunks. Inside a chunk they are visited in a serpentine order of
their coordinates so that each assembly is warm-started from a neighbour (which keeps
the legs on the working mode of the home assembly); the Pinocchio calls are one leg
solve and one Jacobian per leg and pose; the screw algebra of the whole chunk is one
call of :func:`pkm_pin.batch.analyse`. Results come back in the caller's pose order.
"""

from __future__ import annotations

from concurrent.futures import Executor
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from . import batch
from .analysis import SINGULAR_TOL, classify
from .errors import AssemblyError, InputError
from .screws import as_float_array


@dataclass
class SweepResult:
    """Per-pose results of :meth:`Mechanism.sweep` (arrays in the order of the poses).

    Attributes:
        poses: (N, 6) x, y, z [m], roll, pitch, yaw [rad].
        ok: (N,) whether the pose assembled.
        dof: (N,) platform DOF (−1 where not assembled).
        singularity: (N,) "none", "I", "II", "III" ("" where not assembled).
        type_I, type_II, condition: (N,) dimensionless indices (nan where not assembled).
        det: (N,) signed determinant of ``A Δ`` on the home platform twist basis carried
            to each pose (continuous sign across a slice; nan when not square).
        q_actuated: (N, n) actuated coordinates (nan where not assembled).
        failures: (index, reason) of every pose that did not assemble.
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

    def arrays(self) -> dict[str, np.ndarray]:
        """Every array by name (for ``numpy.savez``)."""
        return {k: getattr(self, k) for k in ("poses", "ok", "dof", "singularity", "type_I",
                                              "type_II", "condition", "det", "q_actuated")}


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
            X = np.array([np.r_[p.translation, pin.rpy.matrixToRpy(p.rotation)] for p in poses])
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


def evaluate_chunk(mech, X: np.ndarray, reference: np.ndarray, rtol: float,
                   singular_tol: float, progress=None, restarts: int = 4) -> dict:
    """Assemble and analyse the poses of one chunk (rows of X, already ordered).

    Module-level so that process-based executors can pickle it."""
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
    out = {"ok": ok, "q_actuated": q_act, "failures": failures,
           "dof": np.full(N, -1), "type_I": np.full(N, np.nan), "type_II": np.full(N, np.nan),
           "condition": np.full(N, np.nan), "det": np.full(N, np.nan)}
    if not solved:
        return out
    Js, Ts = [], []
    for k, leg in enumerate(mech.legs):
        pairs = [leg.screws(asm.leg_q[k]) for asm in solved]
        Js.append(np.stack([J for J, _ in pairs]))
        Ts.append(np.stack([T for _, T in pairs]))
    b = batch.analyse(Js, Ts, [leg.actuated_v for leg in mech.legs],
                      mech.characteristic_length, rtol)
    out["dof"][ok] = b.dof
    out["type_I"][ok] = b.type_I
    out["type_II"][ok] = b.type_II
    out["condition"][ok] = b.condition
    out["det"][ok] = _carried_det(b, reference)
    return out


def _evaluate_copy(mech, *args) -> dict:
    """:func:`evaluate_chunk` on a private deep copy of the mechanism."""
    import copy

    return evaluate_chunk(copy.deepcopy(mech), *args)


def _carried_det(b: batch.BatchScrews, reference: np.ndarray) -> np.ndarray:
    """det(A_h Δ P_locᵀ), P_loc = the home platform basis projected on each pose's."""
    n = b.A.shape[1]
    if reference.shape[0] != n or n == 0:
        return np.full(b.A.shape[0], np.nan)
    P = b.platform  # masked orthonormal rows
    P_loc = reference[None] @ np.swapaxes(P, 1, 2) @ P
    Ahu = batch.unit_rows(batch.homogenise(b.A, b.length))
    return np.linalg.det(Ahu @ batch.DELTA @ np.swapaxes(P_loc, 1, 2))


class SweepMixin:
    """Many-pose evaluation for :class:`~pkm_pin.Mechanism`."""

    def sweep(self, poses, *, executor: Executor | None = None, chunk_size: int = 2000,
              progress: bool = False, rtol: float | None = None,
              singular_tol: float = SINGULAR_TOL) -> SweepResult:
        """Assemble and analyse the mechanism at every pose.

        Args:
            poses: Sequence of ``pin.SE3`` or (N, 6) array of x, y, z, roll, pitch, yaw.
            executor: Any ``concurrent.futures.Executor`` (threads, processes, or a Dask
                ``distributed.Client.get_executor()``); chunks of ``chunk_size`` ordered
                poses are its tasks. ``None``: evaluate here.
            chunk_size: Poses per task (each task warm-starts from the home assembly).
            progress: Show a progress bar on stderr (tqdm).
            rtol: Relative tolerance of rank decisions (default :data:`screws.RTOL`).
            singular_tol: Threshold of the closeness indices.

        Returns:
            A :class:`SweepResult`; poses that do not assemble are recorded in
            ``failures`` and hold nan / −1 / "".
        """
        from .screws import RTOL

        X = pose_array(poses)
        if int(chunk_size) < 1:
            raise InputError(f"chunk_size must be a positive integer, got {chunk_size}")
        rtol = RTOL if rtol is None else rtol
        order = serpentine_order(X)
        reference = batch.homogenise(self.home_analysis.platform_twists, self.characteristic_length)
        chunks = [order[i:i + int(chunk_size)] for i in range(0, len(order), int(chunk_size))]
        bar = _progress_bar(len(X)) if progress else None
        if executor is None:
            tick = bar.update if bar is not None else None
            parts = [evaluate_chunk(self, X[c], reference, rtol, singular_tol, tick)
                     for c in chunks]
        else:
            # each task gets its own copy: Pinocchio Data buffers are not shareable
            # between threads (process and Dask executors copy by pickling anyway)
            futures = [executor.submit(_evaluate_copy, self, X[c], reference, rtol, singular_tol)
                       for c in chunks]
            parts = []
            for c, fut in zip(chunks, futures):
                parts.append(fut.result())
                if bar is not None:
                    bar.update(len(c))
        if bar is not None:
            bar.close()
        return _gather(X, chunks, parts, self.n_actuated, singular_tol)


def _progress_bar(total: int):
    from tqdm import tqdm

    return tqdm(total=total, unit="pose", desc="sweep", leave=False)


def _gather(X, chunks, parts, n, singular_tol) -> SweepResult:
    N = len(X)
    res = {"ok": np.zeros(N, bool), "q_actuated": np.full((N, n), np.nan),
           "dof": np.full(N, -1), "type_I": np.full(N, np.nan), "type_II": np.full(N, np.nan),
           "condition": np.full(N, np.nan), "det": np.full(N, np.nan)}
    failures = []
    for idx, part in zip(chunks, parts):
        for key in res:
            res[key][idx] = part[key]
        failures += [(int(idx[i]), reason) for i, reason in part["failures"]]
    sing = np.where(res["ok"], classify(np.nan_to_num(res["type_I"], nan=np.inf),
                                        np.nan_to_num(res["type_II"], nan=np.inf),
                                        singular_tol), "")
    return SweepResult(X, res["ok"], res["dof"], sing, res["type_I"], res["type_II"],
                       res["condition"], res["det"], res["q_actuated"], sorted(failures))
