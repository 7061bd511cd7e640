"""Sweep throughput (poses per second) and Dask scaling efficiency per worker.

* a 100×100 slice of the 3-RPR workspace (x, z at the home orientation);
* a 6-D grid (4 values per coordinate, 4096 poses) around the 6-UPS home;
* a 6-D grid of 5 values per coordinate (15625 poses) on a Dask ``distributed``
  LocalCluster with 1 and 2 worker processes (8 chunks of ~2000 poses); scaling
  efficiency = speed-up / workers.

The reference of each ratio is measured in the same run: the serial sweep, and the
per-pose loop ``analyze(assemble(pose, previous))`` on the first 300 poses.
"""

from __future__ import annotations

import itertools
import sys
import time

import numpy as np

from pkm_pin.builders import MECHANISMS
from pkm_pin.compiling import PLAIN_CALLS
from pkm_pin.sweep import pose_array


def warm_up(mech, X: np.ndarray) -> None:
    """Compile or load every numba entry point the timed calls use: a small sweep
    (with a pose out of reach, for the restart path) and a few single poses (the
    single-pose path compiles after :data:`pkm_pin.compiling.PLAIN_CALLS` calls)."""
    far = X[:1].copy()
    far[0, :3] += 100.0 * mech.characteristic_length
    mech.sweep(np.vstack([X[:8], far]))
    for _ in range(PLAIN_CALLS + 2):
        mech.analyze(mech.assemble(mech.home, mech.home_assembly)).singularity  # noqa: B018


def per_pose_rate(mech, X: np.ndarray) -> float:
    """Poses per second of the plain per-pose loop on X (after :func:`warm_up`)."""
    warm_up(mech, X)
    t = time.perf_counter()
    prev = mech.home_assembly
    for x in X:
        try:
            prev = mech.assemble(x, prev)
        except Exception:  # noqa: BLE001 - unreachable poses of the slice
            continue
        mech.analyze(prev).singularity  # noqa: B018 - the work being timed
    return len(X) / (time.perf_counter() - t)


def sweep_rate(mech, X: np.ndarray, **kw) -> tuple[float, object]:
    """Poses per second of ``mech.sweep(X)`` (after :func:`warm_up`) and its result."""
    warm_up(mech, X)
    t = time.perf_counter()
    res = mech.sweep(X, **kw)
    return len(X) / (time.perf_counter() - t), res


def slice_3rpr(n: int = 100) -> tuple[object, np.ndarray]:
    mech = MECHANISMS["rpr3"]().build()
    h = pose_array([mech.home])[0]
    xs = np.linspace(h[0] - 0.6, h[0] + 0.6, n)
    zs = np.linspace(h[2] - 0.4, h[2] + 0.4, n)
    X = np.repeat(h[None], n * n, axis=0)
    X[:, 0] = np.repeat(xs, n)
    X[:, 2] = np.tile(zs, n)
    return mech, X


def grid_stewart(k: int = 4) -> tuple[object, np.ndarray]:
    mech = MECHANISMS["stewart"]().build()
    h = pose_array([mech.home])[0]
    steps = [np.linspace(-0.05, 0.05, k)] * 3 + [np.linspace(-0.08, 0.08, k)] * 3
    X = np.array([h + np.array(d) for d in itertools.product(*steps)])
    return mech, X


def _warm_worker() -> None:
    """Import pkm_pin and load the compiled kernels in this process (a tiny sweep)."""
    mech = MECHANISMS["stewart"]().build()
    mech.sweep(pose_array([mech.home, mech.home]))


def dask_scaling(mech, X: np.ndarray, chunk: int, repeat: int = 3) -> list[tuple[int, float]]:
    """Poses per second with 1 and 2 workers (best of ``repeat`` sweeps on one cluster)."""
    import distributed

    out = []
    for workers in (1, 2):
        with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            client.run(_warm_worker)  # every worker: imports, numba kernels loaded
            ex = client.get_executor(pure=False)  # every round computes (no result reuse)
            rate = max(sweep_rate(mech, X, executor=ex, chunk_size=chunk, progress=False)[0]
                       for _ in range(repeat))
        out.append((workers, rate))
    return out


def main(small: bool = False) -> None:
    n, k = (30, 3) if small else (100, 4)
    mech, X = slice_3rpr(n)
    loop = per_pose_rate(mech, X[:300])
    rate, res = sweep_rate(mech, X, progress=False)
    print(f"3-RPR {n}x{n} slice: {rate:8.0f} poses/s (sweep), {loop:8.0f} poses/s "
          f"(per-pose loop): x{rate / loop:.2f}; {res.ok.sum()} assembled, "
          f"{len(res.failures)} out of reach")
    mech, X = grid_stewart(k)
    loop = per_pose_rate(mech, X[:300])
    rate, res = sweep_rate(mech, X)
    print(f"6-UPS 6-D grid ({len(X)} poses): {rate:8.0f} poses/s (sweep), {loop:8.0f} "
          f"poses/s (per-pose loop): x{rate / loop:.2f}; {res.ok.sum()} assembled")
    # Dask: tasks of thousands of poses (a task of a few ms would time the scheduler)
    mech, X = grid_stewart(k + 1)
    chunk = max(64, len(X) // 8)
    rate = max(sweep_rate(mech, X, progress=False)[0] for _ in range(3))
    scaling = dask_scaling(mech, X, chunk)
    base = scaling[0][1]
    for workers, r in scaling:
        print(f"  Dask LocalCluster, {len(X)} poses, {workers} worker(s), chunks of {chunk}: "
              f"{r:8.0f} poses/s, "
              f"speed-up x{r / base:.2f}, efficiency {r / base / workers:.0%} "
              f"(serial sweep: {rate:.0f} poses/s)")


if __name__ == "__main__":
    main(small="--small" in sys.argv)
