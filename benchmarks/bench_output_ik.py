"""Per-sample cost of output-driven motions (issue 26): the compiled inverse kinematics
(:mod:`pkm_pin.output_kernel`) against the Python reference loop, beside the
actuated-driven motion of the same path, all measured in this run.

Per model, a motion of the output's coordinates (the 5-bar of ``models/loops`` by x, y;
the Gepetto 5-bar by y, z, an idle motion carried by its dynamics; the Cassie-like knee
by z, pitch; the Stewart by its full 6D pose) through ``samples`` times;
:func:`pkm_pin.trajectory.motion_states` per sample [µs], best of ``repeat``:

  * ``actuated``: the same path given by the actuated values it produced (compiled
    forward kinematics and ``actuated_motion``): the reference of the ratios;
  * ``output``: the output-driven states, compiled inverse kinematics (default);
  * ``output, python``: the same with the Python reference loop
    (``tree_kernel.ENABLED`` off during its call only);
  * ``ik`` / ``ik, python``: the inverse-kinematics part of each (the ``kinematics``
    clock of :func:`motion_states`).

Prints the times, ``output / actuated`` and ``python / compiled`` (whole and IK), and
the largest configuration difference of the two drivers.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from pkm_pin import load_mechanism
from pkm_pin import trajectory as tr
from pkm_pin import tree_kernel as tk
from pkm_pin.builders import MECHANISMS
from pkm_pin.builders.loops import with_random_inertias

ROOT = Path(__file__).resolve().parents[1]


def cases():
    """``name -> (closure model, q0, coordinates, offsets (6,) of a sine path)``."""
    out = {}
    for name, path, coords, amp in (
            ("five_bar", ROOT / "models/loops/five_bar.urdf", ("x", "y"),
             [0.01, 0.01, 0, 0, 0, 0]),
            ("5bar_linkage (idle)", ROOT / "tests/data/gepetto/5bar_linkage/robot.urdf",
             ("y", "z"), [0, 0.005, 0.005, 0, 0, 0]),
            ("cassie_knee", ROOT / "models/loops/cassie_knee.urdf", ("z", "pitch"),
             [0, 0, 0.02, 0, 0.1, 0])):
        link = load_mechanism(path)
        cm = link.model if "gepetto" in str(path) else with_random_inertias(link.model)
        out[name] = (cm, link.home_assembly.q, coords, np.array(amp))
    cm, q0 = tr.closure_model_of(MECHANISMS["stewart"]().build())
    out["stewart 6D"] = (cm, q0, tr.POSE_COORDINATES,
                         np.array([0.02, -0.01, 0.03, 0.05, -0.04, 0.1]))
    return out


def motion(cm, q0, coords, amp):
    c0 = tr._OutputCoordinates(cm).values(q0)
    t = np.linspace(0.0, 2.0, 41)
    path = c0 + (0.5 - 0.5 * np.cos(np.pi * t))[:, None] * amp
    if "pitch" in coords and "z" in coords and len(coords) == 2:  # the knee: z rises only
        path[:, 4] = c0[4] + amp[4] * np.sin(np.pi * t)
    idx = [tr.POSE_COORDINATES.index(c) for c in coords]
    return tr.OutputMotion(t, path[:, idx], coords)


def run(cm, q0, m, times, python: bool):
    tk.ENABLED = not python
    try:
        t = time.perf_counter()
        states, clock = tr.motion_states(cm, m, times, q0)
        return time.perf_counter() - t, clock["kinematics"], states
    finally:
        tk.ENABLED = True


def main(samples: int = 200, repeat: int = 3) -> dict:
    times = np.linspace(0.0, 2.0, samples)
    results = {}
    for name, (cm, q0, coords, amp) in cases().items():
        m = motion(cm, q0, coords, amp)
        run(cm, q0, m, times[:3], False)  # compile / load once
        best = {k: np.inf for k in ("actuated", "output", "ik", "output, python",
                                    "ik, python")}
        for _ in range(repeat):
            w, k, (q, *_, Qa, _, _) = run(cm, q0, m, times, False)
            best["output"], best["ik"] = min(best["output"], w), min(best["ik"], k)
            w, k, (qp, *_) = run(cm, q0, m, times, True)
            best["output, python"] = min(best["output, python"], w)
            best["ik, python"] = min(best["ik, python"], k)
            act = tr.SplineMotion(times, Qa)
            t0 = time.perf_counter()
            tr.motion_states(cm, act, times, q0)
            best["actuated"] = min(best["actuated"], time.perf_counter() - t0)
        us = {k: v / samples * 1e6 for k, v in best.items()}
        us["dq"] = float(np.abs(q - qp).max())
        results[name] = us
        print(f"{name:22s} per sample [µs]: actuated {us['actuated']:8.1f} | output "
              f"{us['output']:8.1f} (ik {us['ik']:7.1f}) | python {us['output, python']:8.1f} "
              f"(ik {us['ik, python']:7.1f})")
        print(f"{'':22s} output / actuated {us['output'] / us['actuated']:5.2f}; python / "
              f"compiled: whole {us['output, python'] / us['output']:5.1f}, ik "
              f"{us['ik, python'] / us['ik']:5.1f}; max |Δq| {us['dq']:.1e}")
    return results


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:]))
