"""Per-sample cost of closed-loop inverse dynamics (issue 26): pkm_pin against a
hand-written Pinocchio null-space solve, and the batched path against single calls.

The 3-loop Cassie-like leg (``models/loops/cassie_knee.urdf``: 8 revolutes, three point
closures, two motors; the file has no inertias, so every body gets a seeded random one),
along a closed path of motor values around home: ``q`` by forward kinematics, ``v`` and
``a`` by :func:`pkm_pin.dynamics.motion_from_actuated` (made before timing). Timed, per
sample, best of ``repeat`` runs:

  * ``inverse_dynamics``: :func:`pkm_pin.dynamics.inverse_dynamics` called once per
    sample (its compiled kernel: rnea, the closure Jacobian in physical units, ``J̇ v``,
    the consistency checks of ``J v`` and ``J a + J̇ v``, the balance's SVD with its
    type II / idle checks, efforts and minimum-norm closure forces);
  * hand-written: ``rnea`` on a tree with the gravity set, ``computeJointJacobians`` +
    ``updateFramePlacements``, the two ``LOCAL_WORLD_ALIGNED`` frame Jacobians per point
    closure (their linear rows' difference), the null space ``N`` of ``J`` by numpy's SVD,
    ``τ = lstsq(Nᵀ Sᵀ, Nᵀ τ_tree)`` — no closure forces, no ``J̇ v``, no check;
  * the Python path (the implementation before the kernel: Pinocchio passes and numpy),
    for reference;
  * ``inverse_dynamics_batch`` on the 1000 samples at once.

Prints the times, the ratio inverse_dynamics / hand-written (issue 26's target: ≤ 1),
the ratio single calls / batch (target: ≥ 10) and the largest differences of the
efforts; then ``trajectory.study``'s velocity / acceleration step per sample before
(numpy) and now (compiled), and a whole study of the leg per sample
(:func:`motion_step`).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pinocchio as pin
from timing import best_of_each

from pkm_pin import dynamics as dyn
from pkm_pin import load_mechanism
from pkm_pin.builders.loops import with_random_inertias

CASSIE = Path(__file__).resolve().parents[1] / "models" / "loops" / "cassie_knee.urdf"
GRAVITY = np.array([0.0, 0.0, -9.81])


with_inertias = with_random_inertias  # seeded random inertias on every body


def samples(n: int, size: float = 0.2, rates: list | None = None):
    """The model and n consistent samples ``(q, v, a)`` along sines of the motors
    (``rates``: receives each sample's actuated ``(q̇_a, q̈_a)``)."""
    link = load_mechanism(CASSIE)
    cm = with_inertias(link.model)
    home = link.home_assembly
    t = np.linspace(0.0, 2.0, n, endpoint=False)
    w = np.array([np.pi, 2 * np.pi])
    out, prev = [], home.q
    for s in t:
        qa = home.q_actuated + size * np.sin(w * s)
        q = link.forward_kinematics(qa, prev).q
        qd, qdd = size * w * np.cos(w * s), -size * w ** 2 * np.sin(w * s)
        v, a = dyn.motion_from_actuated(cm, q, qd, qdd)
        out.append((q, v, a))
        if rates is not None:
            rates.append((qd, qdd))
        prev = q
    return cm, out


class HandWritten:
    """rnea + closure Jacobian (point closures) + SVD null space + lstsq."""

    def __init__(self, cm):
        self.tree = pin.Model(cm.tree)
        self.tree.gravity = pin.Motion(GRAVITY, np.zeros(3))
        self.data = self.tree.createData()
        ids = [(self.tree.getFrameId(c.frame_a), self.tree.getFrameId(c.frame_b))
               for c in cm.closures]
        assert all(c.kind == "point" and c.placement_a.isIdentity()
                   and c.placement_b.isIdentity() for c in cm.closures)
        self.ids = ids
        self.S = np.zeros((len(cm.actuated), cm.nv))
        self.S[np.arange(len(cm.actuated)), list(cm.actuated_v)] = 1.0

    def __call__(self, q, v, a):
        tree, data = self.tree, self.data
        tau = pin.rnea(tree, data, q, v, a)
        pin.computeJointJacobians(tree, data, q)
        pin.updateFramePlacements(tree, data)
        J = np.vstack([
            pin.getFrameJacobian(tree, data, fa, pin.LOCAL_WORLD_ALIGNED)[:3]
            - pin.getFrameJacobian(tree, data, fb, pin.LOCAL_WORLD_ALIGNED)[:3]
            for fa, fb in self.ids])
        _, sv, Vt = np.linalg.svd(J)
        rank = int(np.sum(sv > 1e-9 * sv[0]))
        N = Vt[rank:].T
        return np.linalg.lstsq(N.T @ self.S.T, N.T @ tau, rcond=None)[0]


def motion_step(cm, data, rates, repeat: int, n_study: int = 1000) -> dict:
    """Per sample [µs], the velocity / acceleration step of ``trajectory.study``: before
    (numpy ``motion_from_actuated`` and the SVD of ``[J; S]`` that looks for idle
    motions) and now (``actuated_motion``: the compiled kernel, which certifies there is
    none); and a whole study of the leg (default motion, ``n_study`` samples) per
    sample."""
    from pkm_pin import trajectory

    def before():
        for (q, _, _), (qd, qdd) in zip(data, rates):
            dyn._motion_python(cm, q, qd, qdd)
            trajectory._ActuatedSystem(cm, q)

    def now():
        for (q, _, _), (qd, qdd) in zip(data, rates):
            dyn.actuated_motion(cm, q, qd, qdd)

    now()
    best = best_of_each({"before": before, "now": now}, repeat)
    us = {k: x / len(data) * 1e6 for k, x in best.items()}
    q0 = data[0][0]
    trajectory.study(cm, samples=20, q0=q0)
    t = time.perf_counter()
    st = trajectory.study(cm, samples=n_study, q0=q0)
    us["study"] = (time.perf_counter() - t) / n_study * 1e6
    us.update({f"study {k}": x * 1e6 for k, x in st.timing.items() if k != "total"})
    return us


def main(n: int = 1000, single: int = 200, repeat: int = 7) -> dict:
    rates: list = []
    cm, data = samples(n, rates=rates)
    Q, V, A = (np.array([d[k] for d in data]) for k in range(3))
    hand = HandWritten(cm)
    batch = dyn.inverse_dynamics_batch(cm, Q, V, A, gravity=GRAVITY)  # compiles once
    part = data[:single]
    ours = [dyn.inverse_dynamics(cm, q, v, a, gravity=GRAVITY).efforts for q, v, a in part]
    python = [dyn._python_path(cm, q, v, a, GRAVITY, None, dyn.MOTION_CONSISTENCY_RTOL)
              .efforts for q, v, a in part]
    theirs = [hand(q, v, a) for q, v, a in part]
    diff = max(np.abs(x - y).max() / np.abs(y).max() for x, y in zip(ours, theirs))
    diff_batch = max(np.abs(batch.efforts[i] - python[i]).max() / np.abs(python[i]).max()
                     for i in range(single))

    def framework():
        for q, v, a in part:
            dyn.inverse_dynamics(cm, q, v, a, gravity=GRAVITY)

    def python_path():
        for q, v, a in part:
            dyn._python_path(cm, q, v, a, GRAVITY, None, dyn.MOTION_CONSISTENCY_RTOL)

    def reference():
        for q, v, a in part:
            hand(q, v, a)

    def batched():
        dyn.inverse_dynamics_batch(cm, Q, V, A, gravity=GRAVITY)

    best = best_of_each({"single": framework, "hand": reference, "python": python_path,
                         "batch": batched}, repeat)
    us = {k: best[k] / (n if k == "batch" else single) * 1e6 for k in best}
    print(f"Cassie-like leg, inverse dynamics per sample ({single} single calls, a batch "
          f"of {n}; compiled kernel on {int(batch.compiled.sum())}/{n} samples):")
    print(f"  pkm_pin inverse_dynamics (single)   {us['single']:8.1f} us")
    print(f"  hand-written null-space solve       {us['hand']:8.1f} us")
    print(f"  pkm_pin Python path (reference)     {us['python']:8.1f} us")
    print(f"  pkm_pin inverse_dynamics_batch      {us['batch']:8.1f} us")
    print(f"  ratio inverse_dynamics / hand-written   {us['single'] / us['hand']:8.2f}"
          "  (target <= 1)")
    print(f"  ratio single calls / batch              {us['single'] / us['batch']:8.2f}"
          "  (target >= 10)")
    print(f"  ratio Python path / batch               {us['python'] / us['batch']:8.2f}")
    print(f"  largest relative difference of the efforts: single vs hand-written {diff:.1e}, "
          f"batch vs Python path {diff_batch:.1e}")
    step = motion_step(cm, data[:single], rates[:single], max(1, repeat // 2), n)
    print("trajectory.study of the leg, per sample:")
    print(f"  velocity / acceleration step: before {step['before']:8.1f} us (numpy), now "
          f"{step['now']:8.1f} us (compiled kernel), ratio {step['before'] / step['now']:.1f}")
    print(f"  a whole study ({n} samples)         {step['study']:8.1f} us: forward "
          f"kinematics {step['study kinematics']:.1f}, motion {step['study motion']:.1f}, "
          f"dynamics {step['study dynamics']:.1f}")
    return {**us, "diff": diff, "diff_batch": diff_batch,
            **{f"motion {k}": x for k, x in step.items()}}


if __name__ == "__main__":
    main()
