"""The sweep's reach test on a workspace: the shipped 6-UPS's reachable,
singularity-free and good-transmission workspaces over x, y, z (default box: home ± the
characteristic length), with the test (poses a leg cannot reach refused without a solve,
:func:`pkm_pin.sweep.out_of_reach`) and without it (every pose solved), in the same
run, best of interleaved rounds.

Prints both times, their ratio, the share of the unreachable poses the test refuses,
and whether the reachable masks are the same (they must be).

Then the same for the partial poses of lower-mobility machines (:func:`partial`: the
shipped 3-RPS and 3-PRS over their default coordinates z, roll, pitch, each cell's
parasitic coordinates completed): with and without the completion's limit stop (a
completion whose Newton stops with a joint on its limit is not continued,
``position._against_a_limit``); every mask must be the same. And the same workspaces
with the completion compiled and with its Python driver (:func:`compiled_completion`).
And a workspace of a mechanism read over its tree, the pinned Delta over its point, with
the tree solver's output pose rows compiled and on the Pinocchio driver
(:func:`tree_pose_rows`).

Run: ``python benchmarks/bench_reach.py [n] [rounds]`` (default a 20³ grid, 2 rounds;
the partial poses on a 9³ grid).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from pkm_pin import load_mechanism, position, solve, sweep

STEWART = Path(__file__).resolve().parents[1] / "models" / "mechanisms" / "stewart.toml"
PINNED_DELTA = STEWART.parents[1] / "pinned" / "delta_point.toml"


def with_and_without(module, name: str, off, run, rounds: int) -> tuple[dict, dict]:
    """Best time of ``run()`` with ``module.name`` as it is ("with") and replaced by
    ``off`` ("without"), in interleaved rounds; returns the best times and the last
    result of each."""
    original = getattr(module, name)
    best, last = {"with": np.inf, "without": np.inf}, {}
    for _ in range(rounds):
        for key in ("with", "without"):
            setattr(module, name, original if key == "with" else off)
            try:
                t = time.perf_counter()
                last[key] = run()
                best[key] = min(best[key], time.perf_counter() - t)
            finally:
                setattr(module, name, original)
    return best, last


def main(n: int = 20, rounds: int = 2, name: str = "stewart") -> dict:
    """Time the workspace with and without the reach test; return the figures."""
    mech = load_mechanism(STEWART.with_name(f"{name}.toml"))
    mech.workspace(n=3)  # compile and cache before timing
    original, refused = sweep.out_of_reach, []

    def solve_them_all(legs, Ts, length):
        refused.extend(original(legs, Ts, length)[1])
        return np.ones(Ts.shape[1], bool), []

    def run():
        refused.clear()
        return mech.workspace(n=n)

    best, last = with_and_without(sweep, "out_of_reach", solve_them_all, run, rounds)
    caught = len(refused)  # of the last run, one without the test
    reach_with, reach_without = (last[k].masks["reachable"] for k in ("with", "without"))
    unreachable = int((~reach_without).sum())
    same = bool(np.array_equal(reach_with, reach_without))
    print(f"{name} workspace, {n}^3 poses (x, y, z; transmission and boundary refinement "
          f"included), best of {rounds}:")
    print(f"  without the reach test  {best['without']:8.2f} s")
    ratio = best["with"] / best["without"]
    print(f"  with the reach test     {best['with']:8.2f} s   ratio x{ratio:.2f}")
    print(f"  refused without a solve {caught} poses of the grid and its refinement "
          f"({unreachable} grid poses unreachable); same reachable mask: {same}")
    return {"with": best["with"], "without": best["without"], "same": same,
            "refused": caught}


def workspaces_with_and_without(path, n: int, rounds: int, module, name: str, off,
                                words: tuple[str, str]) -> dict:
    """:func:`with_and_without` on the workspace (n³ cells) of the mechanism in ``path``;
    prints both times (``words``: what "without" and "with" are), their ratio and
    whether every mask is the same; returns the figures."""
    mech = load_mechanism(path)
    mech.workspace(n=2 if mech.backend == "legs" else 3)  # compile and cache first
    best, last = with_and_without(module, name, off, lambda: mech.workspace(n=n), rounds)
    ws, other = last["with"], last["without"]
    same = all(np.array_equal(m, other.masks[k]) for k, m in ws.masks.items())
    ratio = best["with"] / best["without"]
    print(f"{mech.name} workspace over {', '.join(ws.coords)}, {n}^3 cells, best of "
          f"{rounds}: {words[0]} {best['without']:.2f} s, {words[1]} {best['with']:.2f} s, "
          f"ratio x{ratio:.2f}; same masks: {same}")
    return {"with": best["with"], "without": best["without"], "same": same}


def partial(n: int = 9, rounds: int = 1, names=("rps3", "prs3")) -> dict:
    """Time the workspaces over partial poses (each cell's parasitic coordinates
    completed) with and without the completion's limit stop; return {name: figures}."""
    return {name: workspaces_with_and_without(
        STEWART.with_name(f"{name}.toml"), n, rounds, position, "_against_a_limit",
        lambda mech, leg_q: False, ("without the limit stop", "with it"))
        for name in names}


def compiled_completion(n: int = 9, rounds: int = 1, names=("rps3", "prs3")) -> dict:
    """Time the workspaces over partial poses with the completion compiled (the legs'
    kernels, :func:`pkm_pin.solve.solve_coordinates_system`) and with the Python driver
    (Pinocchio's legs, numpy's SVD); return {name: figures}. The masks must be the same,
    the indices equal to rounding."""
    plain = solve.prefer_compiled
    python_only = (solve.solve_coordinates_system, solve.closure_matrix)

    def python_driver(dispatcher):
        return False if dispatcher in python_only else plain(dispatcher)

    return {name: workspaces_with_and_without(
        STEWART.with_name(f"{name}.toml"), n, rounds, solve, "prefer_compiled",
        python_driver, ("Python driver", "compiled")) for name in names}


def tree_pose_rows(n: int = 12, rounds: int = 1) -> dict:
    """Time the pinned Delta's workspace over its output point (a mechanism read over its
    tree: each cell reached by the tree solver with output pose rows, from a neighbour)
    with those rows compiled (:func:`pkm_pin.tree_kernel.output_pose_rows`) and with
    the Pinocchio driver for every solve that has pose rows (the path before); return
    the figures. The masks must be the same."""
    plain = solve.solve_tree

    def pinocchio_for_pose_rows(*args, **kwargs):
        if kwargs.get("pose") is not None or (len(args) > 4 and args[4] is not None):
            kwargs["compiled"] = False
        return plain(*args, **kwargs)

    return workspaces_with_and_without(PINNED_DELTA, n, rounds, solve, "solve_tree",
                                       pinocchio_for_pose_rows,
                                       ("pose rows on the Pinocchio driver", "compiled"))


if __name__ == "__main__":
    args = [int(a) for a in sys.argv[1:3]]
    main(*args)
    partial(rounds=args[1] if len(args) > 1 else 1)
    compiled_completion(rounds=args[1] if len(args) > 1 else 1)
    tree_pose_rows(rounds=args[1] if len(args) > 1 else 1)
