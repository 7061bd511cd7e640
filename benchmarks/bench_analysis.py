"""Per-pose analysis cost: pkm_pin against hand-written numpy and the Pinocchio-call floor.

For the 6-UPS and the 3-RPR, on the same path of poses around home, it times
  * framework, per pose: assemble (warm-started from the previous pose) + analyze
    (wrenches, A, B, class) in a Python loop;
  * framework, batched: Mechanism.sweep over the same poses (per pose);
  * reference (a): a hand-written per-pose numpy loop of the closed forms
    (pkm_pin.formulas: inverse position, A, B, singular values);
  * reference (b'): (b) plus one pass per leg at the warm start (the previous pose's
    solution), the calls a warm-started assembly needs when Pinocchio evaluates its
    Newton iterations (the sweep evaluates those in compiled code instead);
  * reference (c): one ``computeJointJacobians`` per pose on the legs' tree with a
    probe joint at each tip (pkm_pin.twists.TreePass), the single call from which the
    framework reads every joint twist and tip placement: a lower floor than (b);
  * reference (b): the floor of the Pinocchio calls the legs need at a known solution:
    per leg and pose, the Jacobian and the tip placement (the closure check). The
    cheapest of two call sequences is the floor: ``framesForwardKinematics`` +
    ``computeFrameJacobian`` (placement left inside ``data``), or
    ``computeJointJacobians`` (which returns the chain's WORLD Jacobian) +
    ``updateFramePlacement(...).homogeneous`` (placement read out: what the sweep does),
and prints each figure with its ratio to the references. Targets (issue 15): the
per-pose loop within 1x the hand-written loop for the 6-UPS and 1.5x for the 3-RPR;
the sweep within 3x the Pinocchio floor and 0.3x the hand-written loop. Single poses
and sweeps run the same analysis engine (pkm_pin.engine). The first calls of the
process (numba code compiled or loaded from the cache) are made before timing.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from timing import best_of_each

from pkm_pin import formulas, screws
from pkm_pin.builders import MECHANISMS
from pkm_pin.sweep import pose_array


def path(mech, n: int, size: float = 0.05, seed: int = 0) -> list[pin.SE3]:
    """n poses on a smooth closed path around home inside the platform motions."""
    an = mech.analyze()
    rng = np.random.default_rng(seed)
    a, b = rng.normal(size=(2, an.dof))
    s = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return [screws.exp(size * (np.cos(u) * a + np.sin(u) * b) @ an.platform_twists) * mech.home
            for u in s]




def framework_loop(mech, poses):
    prev = mech.home_assembly
    for pose in poses:
        asm = mech.assemble(pose, prev)
        an = mech.analyze(asm)
        an.A, an.B, an.singularity  # noqa: B018 - the work being timed
        prev = asm


def pinocchio_floor_frames(mech, solutions):
    """Per leg and pose: framesForwardKinematics + computeFrameJacobian (WORLD); the
    tightest Python loop (leg by leg, calls bound to locals)."""
    fk, jacobian, world = pin.framesForwardKinematics, pin.computeFrameJacobian, pin.WORLD
    for k, leg in enumerate(mech.legs):
        model, data, tip = leg.model, leg.data, leg.tip_id
        for leg_q in solutions:
            q = leg_q[k]
            fk(model, data, q)
            jacobian(model, data, q, tip, world)


def pinocchio_floor_joints(mech, solutions):
    """Per leg and pose: computeJointJacobians (returns the chain's WORLD Jacobian) +
    the tip placement read out; the tightest Python loop."""
    jacobians, place = pin.computeJointJacobians, pin.updateFramePlacement
    for k, leg in enumerate(mech.legs):
        model, data, tip = leg.model, leg.data, leg.tip_id
        for leg_q in solutions:
            jacobians(model, data, leg_q[k])
            place(model, data, tip).homogeneous


def tree_rows(mech, solutions) -> list[np.ndarray]:
    """The configurations of the legs' tree with tip probes at the solutions."""
    return [np.concatenate([*leg_q, mech.tree_pass.rest_q]) for leg_q in solutions]


def pinocchio_floor_tree(tree, data, rows):
    """Per pose: one ``computeJointJacobians`` on the legs' tree with a probe at each
    tip (:class:`pkm_pin.twists.TreePass`: the joint twists and the tip placements of
    every leg in one call; mechanisms without mimic joints)."""
    jacobians = pin.computeJointJacobians
    for q in rows:
        jacobians(tree, data, q)


def handwritten_rpr3(mech, poses):
    xs = [leg.base.translation[0] for leg in mech.legs]
    L3, L6 = xs[1] - xs[0], xs[2] - xs[1]
    pts = np.array([a.translation for a in mech.anchors])
    for pose in poses:
        theta = pin.rpy.matrixToRpy(pose.rotation)[1]
        angles, lengths = formulas.rpr3.inverse_position(
            L3, L6, (theta, pose.translation[0], pose.translation[2]), pts)
        a3, b3 = formulas.rpr3.velocity_equation(L3, L6, angles, lengths)
        np.linalg.svd(a3, compute_uv=False)
        np.linalg.det(b3)


def handwritten_stewart(mech, poses):
    base = np.array([leg.base.translation for leg in mech.legs])
    local = np.array([a.translation for a in mech.anchors])
    for pose in poses:
        tips = local @ pose.rotation.T + pose.translation
        lines = formulas.stewart.leg_lines(base, tips)
        np.linalg.norm(tips - base, axis=1)
        np.linalg.svd(lines @ screws.DELTA, compute_uv=False)


HANDWRITTEN = {"rpr3": handwritten_rpr3, "stewart": handwritten_stewart}


def main(n: int = 1000, n_loop: int = 200) -> dict:
    """Figures per pose on ``n`` poses (the slow per-pose loop on the first ``n_loop``)."""
    figures = {}
    for name in ("stewart", "rpr3"):
        mech = MECHANISMS[name]().build()
        poses = path(mech, n)
        X = pose_array(poses)
        solutions, prev = [], mech.home_assembly
        for pose in poses:
            prev = mech.assemble(pose, prev)
            solutions.append(prev.leg_q)
        mech.sweep(X[:10])  # compile / load the kernels
        framework_loop(mech, poses[:20])  # and the single-pose path (compiled after a few)
        framework_loop(mech, poses[:20])
        m = min(n, n_loop)
        # the per-pose loop and the hand-written loop on the same poses, in interleaved
        # rounds (the ratio the target is on)
        t = best_of_each({"loop": lambda: framework_loop(mech, poses[:m]),
                          "hand": lambda: HANDWRITTEN[name](mech, poses[:m])}, repeat=25)
        t_loop, t_hand_loop = t["loop"] / m, t["hand"] / m
        # a Pinocchio-only warm-started assembly also evaluates every leg at its warm
        # start (the previous pose's solution) before the Newton step
        warm = [mech.home_assembly.leg_q] + solutions[:-1]
        rows = tree_rows(mech, solutions)
        tree = mech.tree_pass.tree
        tree_data = tree.createData()  # made once (milliseconds), not timed
        # best of many short runs, taken in interleaved rounds so that a noisy spell of
        # the machine slows the figure and its references alike
        t = best_of_each({
            "sweep": lambda: mech.sweep(X),
            "tenth": lambda: mech.sweep(X[:n // 10]),
            "frames": lambda: pinocchio_floor_frames(mech, solutions),
            "joints": lambda: pinocchio_floor_joints(mech, solutions),
            "warm": lambda: pinocchio_floor_joints(mech, warm + solutions),
            "tree": lambda: pinocchio_floor_tree(tree, tree_data, rows),
            "hand": lambda: HANDWRITTEN[name](mech, poses),
        }, repeat=15)
        t_sweep, t_floor2 = t["sweep"] / n, t["warm"] / n
        t_floor = min(t["frames"], t["joints"]) / n
        t_tree = t["tree"] / n
        t_hand = t["hand"] / n
        figures[name] = (t_loop, t_sweep, t_hand, t_floor, t_tree)
        print(f"\n{mech.name}: {n} poses, time per pose [µs]")
        target = {"stewart": 1.0, "rpr3": 1.5}[name]
        print(f"  framework, per-pose loop   {1e6 * t_loop:9.1f}   "
              f"x{t_loop / t_floor:6.1f} floor   x{t_loop / t_hand_loop:6.2f} hand-written"
              f"   (target: x{target:g} hand-written; {m} poses, interleaved with it)")
        print(f"  framework, batched sweep   {1e6 * t_sweep:9.1f}   "
              f"x{t_sweep / t_floor:6.1f} floor   x{t_sweep / t_hand:6.3f} hand-written"
              f"   (targets: x3 floor, x0.3 hand-written)")
        if n >= 20:  # the cost of one more pose, and the fixed cost of a sweep call
            m10 = n // 10
            marginal = (t["sweep"] - t["tenth"]) / (n - m10)
            fixed = t["sweep"] - n * marginal
            print(f"    of which per pose        {1e6 * marginal:9.1f}   "
                  f"x{marginal / t_floor:6.1f} floor; fixed per call {1e3 * fixed:.2f} ms")
        print(f"  (a) hand-written numpy     {1e6 * t_hand:9.1f}")
        print(f"  (b) Pinocchio-call floor   {1e6 * t_floor:9.1f}   (one pass per leg at the "
              "known solution)")
        print(f"  (b') with the warm start   {1e6 * t_floor2:9.1f}   (+ one pass per leg at the "
              f"warm start, as a Pinocchio-only assembly needs): sweep x{t_sweep / t_floor2:.1f}")
        print(f"  (c) one call per pose      {1e6 * t_tree:9.1f}   (computeJointJacobians on the "
              f"legs' tree with tip probes, what the framework calls): sweep x"
              f"{t_sweep / t_tree:.1f}, per-pose loop x{t_loop / t_tree:.1f}")
    return figures


if __name__ == "__main__":
    main()
