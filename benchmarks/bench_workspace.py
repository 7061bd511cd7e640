"""Workspace throughput: the Delta's workspace on a grid of up to 10⁶ poses (100³) on the
local Dask cluster, and scaling per worker.

The Delta's reachable and singularity-free workspaces over x, y, z (its independent
coordinates) in the box x, y ∈ [−0.6, 0.6], z ∈ [−1.3, −0.3] m around home (the one of
tests/test_workspace.py; about 37% of it reachable, the other poses are assembly
failures, the costlier ones), evaluated three ways in the same run: here (serial),
then on a ``dask.distributed.LocalCluster`` with 1 and with 2 worker processes (one
thread each; chunks of ``chunk`` poses). Printed: time, poses/s, the speed-up of 2
workers over 1 and the efficiency (speed-up / workers), and the ratio of Dask with one
worker to the serial run (the scheduling and transfer overhead). The volumes of the
three runs are the same (checked).

Run: ``python benchmarks/bench_workspace.py``: an 80³ grid (512 000 poses, about two
minutes on two cores); ``--full``: 100³ = 10⁶ poses; ``--small``: 20³.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from pkm_pin.builders import MECHANISMS

MECHANISM = "delta"
KINDS = ("reachable", "singularity-free")
#: The box [m]: x, y, z.
BOX = np.array([(-0.6, 0.6), (-0.6, 0.6), (-1.3, -0.3)])


def _warm_worker() -> None:
    """Import pkm_pin and load the compiled kernels in this process (a tiny sweep)."""
    mech = MECHANISMS[MECHANISM]().build()
    mech.workspace(bounds=BOX, n=3, kinds=KINDS)


def timed(mech, n: int, **options) -> tuple[float, object]:
    """Seconds of one workspace of n³ poses, and the workspace."""
    t = time.perf_counter()
    ws = mech.workspace(bounds=BOX, n=n, kinds=KINDS, **options)
    return time.perf_counter() - t, ws


def main(n: int = 80, chunk: int = 20000, workers=(1, 2)) -> dict:
    """Time the serial and Dask runs; returns {label: (seconds, poses/s)}."""
    import distributed

    mech = MECHANISMS[MECHANISM]().build()
    _warm_worker()
    N = n ** 3
    rows = {}
    t, ref = timed(mech, n)
    rows["serial"] = (t, N / t)
    print(f"{mech.name} workspace, {n}^3 = {N} poses, kinds {', '.join(KINDS)}")
    v = ref.volumes["reachable"]
    print(f"  serial                 {t:8.2f} s {N / t:10.0f} poses/s  reachable "
          f"{v.value:.4f} ± {v.error:.2g} {v.unit}")
    for w in workers:
        with distributed.LocalCluster(n_workers=w, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            client.run(_warm_worker)
            ex = client.get_executor(pure=False)
            t, ws = timed(mech, n, executor=ex, chunk_size=chunk)
        for kind in KINDS:
            assert np.array_equal(ws.masks[kind], ref.masks[kind]), kind
        rows[f"dask {w}"] = (t, N / t)
        print(f"  Dask, {w} worker(s)      {t:8.2f} s {N / t:10.0f} poses/s")
    one = rows.get("dask 1")
    if one is not None:
        print(f"  ratio Dask 1 worker / serial: x{rows['serial'][0] / one[0]:.2f} (speed)")
        for w in workers[1:]:
            s = one[0] / rows[f"dask {w}"][0]
            print(f"  speed-up {w} workers / 1 worker: x{s:.2f}, efficiency {s / w:.0%}")
    return rows


if __name__ == "__main__":
    main(n=20 if "--small" in sys.argv else 100 if "--full" in sys.argv else 80)
