"""Per-pose cost of a general closed-loop linkage: pkm_pin against a hand-written loop.

The 3-loop Cassie-like leg (``models/loops/cassie_knee.urdf``: 8 revolutes, three point
closures, two motors), along a closed path of motor values around home, each pose
warm-started from the previous one. Three figures per pose:

  * assembly: close every loop from an open configuration (the previous solution with
    the motors moved to the new values; nothing pinned): ``Mechanism.assemble(q_open)``;
  * forward kinematics: motor values → every joint, warm-started from the previous
    solution: ``Mechanism.forward_kinematics(q_a, previous)``;
  * analysis: mobility, idle motions, output twists, A, B, indices, class at the
    solution: ``Mechanism.analyze(q)``;

against the same computed with Pinocchio calls in a hand-written Python loop: a plain
damped Newton on the closure (``computeJointJacobians`` + ``updateFramePlacements``,
``getFrameJacobian``, ``log6``/``Jlog6`` for a weld, the point difference for a point
closure; numpy for the step), and the mobility, output twists and velocity maps from one
numpy SVD of the closure Jacobian (``qa = X Y⁺ t``, ``t = Y X⁺ qa``). Same tolerance
(residual 1e-12 L). Prints the times and their ratios measured in the same run (target:
pkm_pin at most the hand-written loop, ratio ≤ 1; the analysis at most ×1.5), and the
analysis on its numpy path (``general_kernel.ENABLED = False``), the general elimination
before it was compiled.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
from timing import best_of_each

from pkm_pin import general_kernel, load_mechanism

CASSIE = Path(__file__).resolve().parents[1] / "models" / "loops" / "cassie_knee.urdf"


def motor_path(n: int, size: float = 0.2) -> np.ndarray:
    """(n × 2) motor values [rad] on an ellipse around home."""
    s = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([size * np.sin(s), 0.7 * size * np.sin(2 * s + 0.4)])


def path_solutions(link, n: int) -> tuple[np.ndarray, list]:
    """The motor path (:func:`motor_path`) and pkm_pin's solution at each of its points,
    each warm-started from the previous one."""
    Q = motor_path(n)
    solutions, prev = [], link.assemble().q
    for qa in Q:
        prev = link.forward_kinematics(qa, prev, starts=0).q
        solutions.append(prev)
    return Q, solutions



# ============================================================ the hand-written loop
class HandWritten:
    """The closure, Newton and analysis of a closure model with Pinocchio calls and numpy."""

    def __init__(self, link):
        m = link.model
        self.model, self.data = m.tree, m.tree.createData()
        self.L, self.nv = m.length, m.nv
        self.closures = [(m.tree.getFrameId(c.frame_a), m.tree.getFrameId(c.frame_b), c.kind)
                         for c in m.closures]
        self.out = m.tree.getFrameId(m.output)
        self.act_q = [m.tree.joints[m.tree.getJointId(a)].idx_q for a in m.actuated]
        self.act_v = [m.tree.joints[m.tree.getJointId(a)].idx_v for a in m.actuated]

    def closure(self, q):
        """Residual [m, rad] and Jacobian of every closure: one pass at q."""
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        e, J = [], []
        for fa, fb, kind in self.closures:
            if kind == "point":
                e.append(data.oMf[fb].translation - data.oMf[fa].translation)
                J.append(pin.getFrameJacobian(model, data, fb, pin.LOCAL_WORLD_ALIGNED)[:3]
                         - pin.getFrameJacobian(model, data, fa, pin.LOCAL_WORLD_ALIGNED)[:3])
            else:
                M = data.oMf[fa].actInv(data.oMf[fb])
                Ja = pin.getFrameJacobian(model, data, fa, pin.LOCAL)
                Jb = pin.getFrameJacobian(model, data, fb, pin.LOCAL)
                e.append(pin.log6(M).vector)
                J.append(pin.Jlog6(M) @ (Jb - M.inverse().action @ Ja))
        return np.concatenate(e), np.vstack(J)

    def newton(self, q, targets=None, tol: float = 1e-12, max_iter: int = 50):
        """Damped Newton on the closures (and the motors pinned at ``targets``)."""
        n = len(self.act_q)
        for _ in range(max_iter):
            e, J = self.closure(q)
            if targets is not None:
                e = np.r_[e, (q[self.act_q] - targets) * self.L]
                Ja = np.zeros((n, self.nv))
                Ja[np.arange(n), self.act_v] = self.L
                J = np.vstack([J, Ja])
            r = np.linalg.norm(e) / self.L
            if r <= tol:
                return q
            H = J.T @ J + (1e-10 + 1e-2 * r * r) * self.L ** 2 * np.eye(self.nv)
            q = pin.integrate(self.model, q, -np.linalg.solve(H, J.T @ e))
        raise RuntimeError("hand-written Newton did not converge")

    def analyze(self, q, rtol: float = 1e-9):
        """Mobility, idle motions, output twists and velocity maps by SVD."""
        _, J = self.closure(q)
        Jo = pin.getFrameJacobian(self.model, self.data, self.out, pin.LOCAL_WORLD_ALIGNED)
        _, sv, Vt = np.linalg.svd(J)
        rank = int(np.sum(sv > rtol * sv[0]))
        N = Vt[rank:].T
        X, Y = N[self.act_v], Jo @ N
        sx = np.linalg.svd(X, compute_uv=False)
        Uy, sy, _ = np.linalg.svd(Y)
        forward = Y @ np.linalg.pinv(X)  # t = forward qa
        inverse = X @ np.linalg.pinv(Y)  # qa = inverse t
        return {"dof": self.nv - rank, "idle": N.shape[1] - int(np.sum(sx > rtol * sx[0])),
                "twists": Uy[:, :int(np.sum(sy > rtol * sy[0]))], "forward": forward,
                "inverse": inverse, "indices": (sx[-1] / sx[0], sy[-1] / sy[0])}


# =================================================================== the figures
def open_config(q_prev: np.ndarray, targets: np.ndarray, act_q: list) -> np.ndarray:
    """The previous solution with the motors moved to ``targets`` (the loops open)."""
    q = q_prev.copy()
    q[act_q] = targets
    return q


def run_ours(link, Q, solutions, what: str, act_q: list):
    """pkm_pin's figure ``what`` along the path."""
    prev = solutions[-1]
    for k, qa in enumerate(Q):
        if what == "fk":
            prev = link.forward_kinematics(qa, prev, starts=0).q
        elif what == "assemble":
            link.assemble(open_config(solutions[k - 1], qa, act_q), starts=0)
        else:
            link.analyze(solutions[k])


def run_hand(hand, Q, solutions, what: str):
    """The hand-written loop's figure ``what`` along the path."""
    prev = solutions[-1]
    for k, qa in enumerate(Q):
        if what == "fk":
            prev = hand.newton(prev, qa)
        elif what == "assemble":
            hand.newton(open_config(solutions[k - 1], qa, hand.act_q))
        else:
            hand.analyze(solutions[k])


def main(n: int = 200, repeat: int = 5) -> dict:
    """Time per pose [s] of each figure, ``{figure: (pkm_pin, hand-written)}``."""
    link = load_mechanism(CASSIE)
    hand = HandWritten(link)
    Q, solutions = path_solutions(link, n)
    for a, b in zip(solutions, [hand.newton(s, qa) for s, qa in zip(solutions, Q)]):
        assert np.abs(pin.difference(hand.model, a, b)).max() < 1e-9
    rows = {}
    print(f"Cassie-like leg ({link.model.nv} joints, {len(link.model.closures)} loops), "
          f"{n} poses along a motor path, time per pose [µs]:")
    for what, label in (("assemble", "assembly (open → closed)"),
                        ("fk", "forward kinematics (warm)"), ("analyze", "analysis")):
        t = best_of_each({"ours": lambda: run_ours(link, Q, solutions, what, hand.act_q),
                          "hand": lambda: run_hand(hand, Q, solutions, what)}, repeat)
        ours, ref = t["ours"] / n, t["hand"] / n
        rows[what] = (ours, ref)
        print(f"  {label:28s} pkm_pin {1e6 * ours:8.1f}   hand-written {1e6 * ref:8.1f}"
              f"   ratio x{ours / ref:5.2f}")
    total = sum(r[0] for r in rows.values()) / sum(r[1] for r in rows.values())
    print(f"  all three: ratio pkm_pin / hand-written x{total:.2f}   (target: at most 1)")
    rows["analyze_numpy"] = numpy_analysis(link, hand, Q, solutions, repeat)
    return rows


def numpy_analysis(link, hand, Q, solutions, repeat: int) -> tuple:
    """The analysis on its numpy path (``general_kernel.ENABLED = False``: before the
    compiled elimination) against the hand-written loop, timed in the same rounds."""
    n = len(Q)

    def ours():
        general_kernel.ENABLED = False
        try:
            run_ours(link, Q, solutions, "analyze", hand.act_q)
        finally:
            general_kernel.ENABLED = True

    t = best_of_each({"ours": ours, "hand": lambda: run_hand(hand, Q, solutions, "analyze")},
                     repeat)
    ours_t, ref = t["ours"] / n, t["hand"] / n
    print(f"  {'analysis, numpy path':28s} pkm_pin {1e6 * ours_t:8.1f}   hand-written "
          f"{1e6 * ref:8.1f}   ratio x{ours_t / ref:5.2f}   (general_kernel.ENABLED = False)")
    return ours_t, ref


if __name__ == "__main__":
    main()
