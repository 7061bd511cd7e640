"""Timing helper shared by the benchmark scripts."""

from __future__ import annotations

import time


def best_of_each(fns: dict, repeat: int) -> dict:
    """Smallest wall time [s] of each callable over ``repeat`` rounds, each round
    calling every callable once (interleaved: a noisy spell of the machine slows a
    figure and its references alike)."""
    best = dict.fromkeys(fns, float("inf"))
    for _ in range(repeat):
        for key, fn in fns.items():
            t = time.perf_counter()
            fn()
            best[key] = min(best[key], time.perf_counter() - t)
    return best
