"""Forward kinematics of general closed loops: pkm_pin against PlaCo and a hand-written
Pinocchio loop (issue 24).

1. **PlaCo's planar 5-bar** (``benchmarks/data/planar_2dof``: the dimensions of PlaCo's
   example ``models/planar-2dof``, its ``closing_effector_1/2`` frames as one Extended
   URDF 3D loop, ``motor1``/``motor2`` actuated). 50 motor targets drawn uniformly in
   ±0.3 rad about home (seeded); each solve warm-started from the previous one, to a
   relative closure residual of 1e-10 and the motors to 1e-10 rad:

   * pkm_pin: ``Mechanism.forward_kinematics(q_a, previous, starts=0, tol=1e-10)`` (the
     compiled tree solver, :mod:`pkm_pin.tree_kernel`), and the same loop with the
     Pinocchio driver (``tree_kernel.ENABLED = False``: the path before issue 24);
   * PlaCo: ``RobotWrapper`` + ``KinematicsSolver`` (floating base masked), a hard
     ``RelativePositionTask`` between the two closing frames masked to x, y (as PlaCo's
     own ``kinematics/planar_2dof_joints.py``), a soft joints task on the motors;
     ``solve(True)`` + ``update_kinematics()`` repeated until the two frames are
     1e-10 L apart and the motors within 1e-10 rad of their targets.

   PlaCo 0.10 is built against Pinocchio 3.8 and cannot share pkm_pin's environment
   (Pinocchio 4.1): it runs in a subprocess of the interpreter given by
   ``--placo-python`` or ``$PKM_PIN_PLACO_PYTHON`` (default ``.venv/placo/bin/python``
   under the repository; ``python -m venv .venv/placo && .venv/placo/bin/pip install
   placo``), in the same run, on the same targets. Both solutions are checked with
   pkm_pin's closure residual (:meth:`ClosureModel.closure_residual`) ≤ 1e-10 and
   against each other.

2. **Cassie-like leg** (``models/loops/cassie_knee.urdf``, 3 point loops): forward
   kinematics and assembly along a motor path against the hand-written Pinocchio
   Gauss-Newton loop of ``bench_linkage.py`` (``computeJointJacobians``, frame
   Jacobians, a damped normal-equations solve).

Every ratio printed is measured in this run (best of interleaved rounds).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIVE_BAR = ROOT / "benchmarks" / "data" / "planar_2dof" / "robot.urdf"
N_TARGETS, SPAN, SEED, TOL = 50, 0.3, 0, 1e-10
MOTORS = ("motor1", "motor2")
JOINTS = ("motor1", "passive1", "motor2", "passive2")


# ============================================================ PlaCo (subprocess)
def placo_worker() -> None:
    """Read ``{"targets", "home", "length", "tol"}`` (one JSON line) on stdin, then one
    command a line: ``round`` times one pass over the targets from home and prints its
    seconds per solve; ``result`` prints ``{"q": the joint values of each solution,
    "iterations": PlaCo solves per target}``; end of input ends the worker."""
    import numpy as np
    import placo

    job = json.loads(sys.stdin.readline())
    targets, tol, L = np.array(job["targets"]), job["tol"], job["length"]
    robot = placo.RobotWrapper(str(FIVE_BAR), placo.Flags.ignore_collisions)
    solver = placo.KinematicsSolver(robot)
    solver.mask_fbase(True)
    closing = solver.add_relative_position_task("closing_effector_1", "closing_effector_2",
                                                np.zeros(3))
    closing.configure("closing", "hard", 1.0)
    closing.mask.set_axises("xy")
    joints = solver.add_joints_task()
    joints.configure("joints", "soft", 1.0)

    def run():
        for name, value in zip(JOINTS, job["home"]):
            robot.set_joint(name, value)
        robot.update_kinematics()
        out, iterations = [], []
        t = time.perf_counter()
        for qa in targets:
            joints.set_joints({MOTORS[0]: float(qa[0]), MOTORS[1]: float(qa[1])})
            for it in range(1, 51):
                solver.solve(True)
                robot.update_kinematics()
                d = robot.get_T_world_frame("closing_effector_2")[:3, 3] \
                    - robot.get_T_world_frame("closing_effector_1")[:3, 3]
                if (np.sqrt(d @ d) <= tol * L and abs(robot.get_joint(MOTORS[0]) - qa[0]) <= tol
                        and abs(robot.get_joint(MOTORS[1]) - qa[1]) <= tol):
                    break
            iterations.append(it)
            out.append([robot.get_joint(n) for n in JOINTS])
        return (time.perf_counter() - t) / len(targets), out, iterations

    run()  # warm
    for line in sys.stdin:
        seconds, q, iterations = run()
        reply = {"seconds": seconds} if line.strip() == "round" else {"q": q,
                                                                     "iterations": iterations}
        print(json.dumps(reply), flush=True)


def placo_python(arg: str | None) -> str | None:
    """The interpreter that runs PlaCo, or None when there is none."""
    for cand in (arg, os.environ.get("PKM_PIN_PLACO_PYTHON"),
                 str(ROOT / ".venv" / "placo" / "bin" / "python")):
        if cand and Path(cand).exists():
            return cand
    return None


class PlacoWorker:
    """The PlaCo worker process (:func:`placo_worker`) for one job."""

    def __init__(self, python: str, targets, home, length: float):
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
        self.proc = subprocess.Popen([python, __file__, "--placo-worker"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, env=env)
        self._ask(json.dumps({"targets": targets.tolist(), "home": list(home),
                              "length": length, "tol": TOL}), reply=False)

    def _ask(self, line: str, reply: bool = True):
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        return json.loads(self.proc.stdout.readline()) if reply else None

    def round(self) -> float:
        return self._ask("round")["seconds"]

    def result(self) -> dict:
        return self._ask("result")

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait()


# ============================================================ pkm_pin
def five_bar(placo: str | None, repeat: int) -> dict:
    """Time per solve [s] on the 5-bar: ``{"ours", "pinocchio", "placo" (inf when not
    run)}``."""
    import numpy as np

    from pkm_pin import load_mechanism, tree_kernel

    link = load_mechanism(FIVE_BAR)
    model = link.model
    home = link.assemble(np.zeros(model.nq))
    rng = np.random.default_rng(SEED)
    targets = home.q_actuated + rng.uniform(-SPAN, SPAN, (N_TARGETS, 2))
    names = [model.tree.names[j] for j in range(1, model.tree.njoints)]
    order = [names.index(n) for n in JOINTS]  # PlaCo's joint order → pkm_pin's q

    def ours(enabled: bool = True):
        tree_kernel.ENABLED = enabled
        try:
            prev, out = home, []
            t = time.perf_counter()
            for qa in targets:
                prev = link.forward_kinematics(qa, prev, starts=0, tol=TOL)
                out.append(prev.q)
            return (time.perf_counter() - t) / N_TARGETS, np.array(out)
        finally:
            tree_kernel.ENABLED = True

    worker = None if placo is None else PlacoWorker(placo, targets, home.q[order],
                                                    model.length)
    _, q_ours = ours()  # compile / warm
    _, q_pin = ours(False)
    t_ours = t_pin = t_placo = float("inf")
    for _ in range(repeat):  # interleaved rounds
        t_ours = min(t_ours, ours()[0])
        t_pin = min(t_pin, ours(False)[0])
        if worker is not None:
            t_placo = min(t_placo, worker.round())
    res_ours = max(float(np.linalg.norm(model.closure_residual(q))) for q in q_ours)
    act_ours = float(np.abs(q_ours[:, [model.tree.joints[model.tree.getJointId(m)].idx_q
                                        for m in MOTORS]] - targets).max())
    print(f"PlaCo's planar 5-bar, {N_TARGETS} targets in ±{SPAN} rad, warm-started, "
          f"tol {TOL:g}; time per solve [µs], best of {repeat} interleaved rounds:")
    print(f"  pkm_pin Mechanism.forward_kinematics (compiled tree solver) {1e6 * t_ours:8.1f}"
          f"   closure ≤ {res_ours:.1e}, motors ≤ {act_ours:.1e}")
    print(f"  pkm_pin, Pinocchio driver (before issue 24)              {1e6 * t_pin:8.1f}"
          f"   x{t_pin / t_ours:.1f} the compiled path; same solutions to "
          f"{np.abs(q_pin - q_ours).max():.1e}")
    assert res_ours <= TOL and act_ours <= TOL
    rows = {"ours": t_ours, "pinocchio": t_pin, "placo": t_placo}
    if worker is None:
        print("  PlaCo: no interpreter with placo (--placo-python, $PKM_PIN_PLACO_PYTHON or "
              ".venv/placo); not timed")
        return rows
    p = worker.result()
    worker.close()
    q_placo = np.array(p["q"])[:, np.argsort(order)]
    res_placo = max(float(np.linalg.norm(model.closure_residual(q))) for q in q_placo)
    print(f"  PlaCo KinematicsSolver (solve + update_kinematics until closed) "
          f"{1e6 * t_placo:8.1f}   closure ≤ {res_placo:.1e}, "
          f"{np.mean(p['iterations']):.1f} PlaCo solves a target; same solutions to "
          f"{np.abs(q_placo - q_ours).max():.1e}")
    print(f"  ratio pkm_pin / PlaCo x{t_ours / t_placo:.2f}   (target: at most 1; "
          f"before issue 24 x{t_pin / t_placo:.1f})")
    assert res_placo <= TOL
    return rows


def cassie(repeat: int, n: int = 200) -> dict:
    """Time per pose [s] of the Cassie-like leg: ``{figure: (ours, hand-written,
    Pinocchio driver)}``."""
    from bench_linkage import CASSIE, HandWritten, path_solutions, run_hand, run_ours
    from timing import best_of_each

    from pkm_pin import load_mechanism, tree_kernel

    link = load_mechanism(CASSIE)
    hand = HandWritten(link)
    Q, solutions = path_solutions(link, n)
    print(f"Cassie-like leg ({link.model.nv} joints, {len(link.model.closures)} loops), {n} "
          "poses along a motor path, time per pose [µs]:")
    rows = {}
    for what, label in (("assemble", "assembly (open → closed)"),
                        ("fk", "forward kinematics (warm)")):
        fns = {"ours": lambda: run_ours(link, Q, solutions, what, hand.act_q),
               "hand": lambda: run_hand(hand, Q, solutions, what)}

        def pinocchio_driver():
            tree_kernel.ENABLED = False
            try:
                run_ours(link, Q, solutions, what, hand.act_q)
            finally:
                tree_kernel.ENABLED = True
        fns["before"] = pinocchio_driver
        t = best_of_each(fns, repeat)
        ours, ref, before = t["ours"] / n, t["hand"] / n, t["before"] / n
        rows[what] = (ours, ref, before)
        print(f"  {label:28s} pkm_pin {1e6 * ours:8.1f}   hand-written {1e6 * ref:8.1f}"
              f"   ratio x{ours / ref:5.2f}   (Pinocchio driver {1e6 * before:7.1f}: "
              f"x{before / ref:.2f})")
    return rows


def main(argv=None) -> dict:
    """Run both comparisons (``argv``: the command line's options); returns their
    figures, ``{"five_bar": …, "cassie": …}``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--placo-python", help="interpreter with placo installed")
    parser.add_argument("--no-placo", action="store_true", help="time pkm_pin only")
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--poses", type=int, default=200, help="Cassie-like leg poses")
    parser.add_argument("--placo-worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.placo_worker:
        placo_worker()
        return {}
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    placo = None if args.no_placo else placo_python(args.placo_python)
    return {"five_bar": five_bar(placo, args.repeat), "cassie": cassie(args.repeat, args.poses)}


if __name__ == "__main__":
    main()
