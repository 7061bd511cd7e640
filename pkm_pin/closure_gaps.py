"""Why a linkage does not assemble: the loops left open at the best configuration the
solver reached, the joints held at a limit there, and a hint (issue 25).

:func:`diagnose` reads one configuration ``q`` of a
:class:`~pkm_pin.model.closure_model.ClosureModel`'s tree (the best the assembly found)
and returns a :class:`Diagnosis`:

* each **open loop** (a closure whose residual norm exceeds ``tol`` and
  :data:`GAP_SHARE` of the worst one's) as a
  :class:`Gap`: the distance between the origins of its two constraint frames [m] and,
  for a weld, the rotation angle between them (for a revolute closure the angle between
  their z axes) [rad]; worst first;
* the **joints at a limit**: 1-DOF joints on the open loops' tree paths within
  :data:`~pkm_pin.tolerances.JOINT_LIMIT_SLACK` of a finite limit that
  :func:`~pkm_pin.solve.tree_limits` enforces;
* with joints at a limit, whether the loops **close with those limits lifted**
  (:func:`~pkm_pin.solve.solve_tree` from ``q`` on a copy of the tree without them):
  then only the joints whose value there lies outside their range are kept, each with
  that value;
* a **hint** in words: limits to check when lifting them closes the loops; "the
  orientations (nearly) close but the points stay apart" (a length, a closure frame, or
  a closure kind stricter than the joint it stands for) when a weld or revolute closure
  is open and every open loop's angle is below :data:`ANGLE_CLOSED`; else the closure
  frames, kinds and joint axes to check;
* the reader's **notes** (:attr:`ClosureModel.notes`), last: how the file was read
  where that may be why it does not close (a closure pair the closures file leaves
  out, a revolute named like a spherical joint).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from .solve import solve_tree, tree_limits
from .tolerances import ASSEMBLY_CHECK_RTOL, CLOSURE_TOL, JOINT_LIMIT_SLACK

__all__ = ["ANGLE_CLOSED", "GAP_SHARE", "Diagnosis", "Gap", "LimitHit", "closure_gaps", "diagnose",
           "loop_joints"]

#: The open loops' orientations count as (nearly) closed when each one's angle is below
#: this [rad] (1°).
ANGLE_CLOSED = np.radians(1.0)
#: An open loop is listed when its residual is at least this share of the worst one's
#: (loops the solver left open by rounding only are not).
GAP_SHARE = 1e-3
#: How many open loops a message names (the worst), the others counted.
MESSAGE_LOOPS = 6


@dataclass(frozen=True)
class Gap:
    """One loop left open.

    Attributes:
        name: The closure's name.
        kind: Its kind (``"weld"``, ``"point"``, ``"revolute"``).
        residual: Norm of its residual rows (dimensionless, as
            :meth:`ClosureModel.closure_norms`).
        distance: Distance between the origins of its two constraint frames [m].
        angle: Rotation between them [rad] (weld), between their z axes (revolute);
            0 for a point closure.
        a, b: World positions of the two constraint frames' origins [m].
    """

    name: str
    kind: str
    residual: float
    distance: float
    angle: float
    a: np.ndarray
    b: np.ndarray

    def words(self) -> str:
        """``'name' 81.4 mm, 0.03°`` (the angle left out for a point closure)."""
        angle = "" if self.kind == "point" else f", {np.degrees(self.angle):.3g}°"
        return f"{self.name!r} {1e3 * self.distance:.3g} mm{angle}"


@dataclass(frozen=True)
class LimitHit:
    """A joint at a limit: its name, ``"lower"`` or ``"upper"``, the limit, its range
    ``(lower, upper)`` and, when lifting the limits closes the loops, the value it would
    need (else None) [rad or m]."""

    joint: str
    side: str
    value: float
    limits: tuple[float, float]
    needed: float | None = None

    def words(self) -> str:
        """``leg_shin at its lower limit 0 (range [0, 2.618]; the loops close at -1.471)``."""
        need = "" if self.needed is None else f"; the loops close at {self.needed:.4g}"
        return (f"{self.joint} at its {self.side} limit {self.value:.4g} (range "
                f"[{self.limits[0]:.4g}, {self.limits[1]:.4g}]{need})")


@dataclass(frozen=True)
class Diagnosis:
    """Open loops (worst first), joints at a limit, whether lifting those limits closes
    the loops, a hint (see the module docstring) and the reader's notes on how it read
    the file (:attr:`ClosureModel.notes`: a closure pair the file leaves out, a joint
    named like a spherical joint that stays revolute)."""

    gaps: tuple[Gap, ...]
    at_limits: tuple[LimitHit, ...]
    closes_without_limits: bool
    hint: str
    notes: tuple[str, ...] = ()

    def words(self) -> str:
        """One line: the open loops (the :data:`MESSAGE_LOOPS` worst), the joints at a
        limit, the hint."""
        parts = []
        if self.gaps:
            shown = ", ".join(g.words() for g in self.gaps[:MESSAGE_LOOPS])
            more = len(self.gaps) - MESSAGE_LOOPS
            parts.append(f"open loops: {shown}" + (f" and {more} more" if more > 0 else ""))
        if self.at_limits:
            parts.append("at a limit: " + ", ".join(h.words() for h in self.at_limits))
        if self.hint:
            parts.append(f"hint: {self.hint}")
        if self.notes:
            parts.append("reader notes: " + "; ".join(self.notes))
        return "; ".join(parts)


def closure_gaps(model, q, tol: float = CLOSURE_TOL) -> tuple[Gap, ...]:
    """The closures of ``model`` left open at ``q`` (residual norm above ``tol`` and at
    least :data:`GAP_SHARE` of the worst one's), worst first."""
    kin = model.kinematics(q)
    norms = model.closure_norms(kin.residual)
    tree, out = model.tree, []
    floor = max(tol, GAP_SHARE * float(norms.max(initial=0.0)))
    for c, r in zip(model.closures, norms):
        if not r > floor:
            continue
        A = kin.frame_placements[tree.getFrameId(c.frame_a)] * c.placement_a
        B = kin.frame_placements[tree.getFrameId(c.frame_b)] * c.placement_b
        if c.kind == "weld":
            angle = float(np.linalg.norm(pin.log3(A.rotation.T @ B.rotation)))
        elif c.kind == "revolute":
            cos = float(np.clip(A.rotation[:, 2] @ B.rotation[:, 2], -1.0, 1.0))
            angle = float(np.arccos(cos))
        else:
            angle = 0.0
        out.append(Gap(c.name, c.kind, float(r),
                       float(np.linalg.norm(B.translation - A.translation)), angle,
                       A.translation.copy(), B.translation.copy()))
    return tuple(sorted(out, key=lambda g: -g.residual))


def loop_joints(model, names) -> set[int]:
    """Ids of the joints on the tree paths of the closures called ``names`` (between
    their two frames, through their common ancestor: the joints that move one frame
    relative to the other)."""
    tree, out = model.tree, set()
    for c in model.closures:
        if c.name in names:
            sa, sb = (set(tree.supports[tree.frames[tree.getFrameId(f)].parentJoint])
                      for f in (c.frame_a, c.frame_b))
            out |= sa ^ sb
    return out


def loop_size(model, q, name: str) -> float:
    """The scale of joint ``name``'s motion as a length: the size of the loops through
    it at the configuration ``q`` (the largest distance between the origins of the
    joints on those loops' tree paths, the joint's parent's included), at most the
    characteristic length ``L``; ``L`` when the joint is on no loop. ``L`` sums every
    offset of the tree (7.4 m for Gepetto's two-legged kangaroo, whose pistons' loops
    are 0.06 to 0.13 m across)."""
    L = model.length
    j = model.tree.getJointId(name)
    loops = [c.name for c in model.closures if j in loop_joints(model, [c.name])]
    if not loops:
        return L
    kin = model.kinematics(q)
    joints = sorted(loop_joints(model, loops) | {model.tree.parents[j]})
    points = np.array([kin.joint_placements[i].translation for i in joints])
    size = float(np.max(np.linalg.norm(points[:, None] - points[None], axis=-1)))
    return min(size, L) if size > 0 else L


def _limit_hits(model, q, joints) -> list[tuple[int, str, float]]:
    """``(joint id, side, limit)`` of the 1-DOF joints among ``joints`` at a limit at
    ``q``."""
    lo, up = tree_limits(model)
    tree, out = model.tree, []
    for j in sorted(joints):
        joint = tree.joints[j]
        if joint.nq == joint.nv == 1:
            i = joint.idx_q
            if abs(q[i] - lo[i]) <= JOINT_LIMIT_SLACK:
                out.append((j, "lower", float(lo[i])))
            elif abs(q[i] - up[i]) <= JOINT_LIMIT_SLACK:
                out.append((j, "upper", float(up[i])))
    return out


def _without_limits(model, q, joints, tol: float, max_iter: int):
    """:func:`solve_tree` from ``q`` on ``model`` with the limits of ``joints`` lifted
    (an empty range: none, as :func:`tree_limits` reads it); the solution or None."""
    tree = pin.Model(model.tree)
    for j in joints:
        i = tree.joints[j].idx_q
        tree.lowerPositionLimit[i] = tree.upperPositionLimit[i] = 0.0
    free = replace(model, tree=tree)
    sol = solve_tree(free, q, tol=tol, max_iter=max_iter)
    return sol if sol.converged else None


def _hint(gaps, closes: bool) -> str:
    if closes:
        return ("the loops close with those joints beyond their limits (values above): "
                "check the limits and the axis signs of these joints in the file")
    if any(g.kind != "point" for g in gaps) and all(g.angle < ANGLE_CLOSED for g in gaps):
        return ("the loops' orientations (nearly) close but their points stay apart: a link length "
                "or a closure frame's position disagrees with the loops' other joints, or "
                "a closure is stricter than the joint it stands for (a 6d weld where the "
                "machine has a ball joint: 3d); `pkm-pin view FILE` draws the gaps")
    return ("check the closure frames, their kinds (6d weld, 3d point) and the joints' "
            "axes and limits; `pkm-pin view FILE` draws the gaps")


def diagnose(model, q, *, tol: float = CLOSURE_TOL, lift_limits: bool = True,
             max_iter: int = 100) -> Diagnosis:
    """The :class:`Diagnosis` of ``model`` at ``q`` (the best configuration reached);
    ``lift_limits``: try :func:`solve_tree` with the limits of the joints at a limit
    lifted (one solve)."""
    q = np.asarray(q, dtype=float)
    gaps = closure_gaps(model, q, tol)
    raw = _limit_hits(model, q, loop_joints(model, {g.name for g in gaps}))
    sol = _without_limits(model, q, [j for j, _, _ in raw], tol, max_iter) \
        if raw and gaps and lift_limits else None
    lo, up = tree_limits(model)
    tree, hits = model.tree, []
    for j, side, value in raw:
        i = tree.joints[j].idx_q
        needed = None if sol is None else float(sol.q[i])
        if needed is not None and lo[i] - JOINT_LIMIT_SLACK <= needed <= up[i] + \
                JOINT_LIMIT_SLACK:
            continue  # not what holds the loops open
        hits.append(LimitHit(tree.names[j], side, value, (float(lo[i]), float(up[i])),
                             needed))
    closes = sol is not None
    return Diagnosis(gaps, tuple(hits), closes, _hint(gaps, closes),
                     tuple(getattr(model, "notes", ())))


def reconcile(model, tol: float = CLOSURE_TOL):
    """``model``, or a copy whose closures close exactly where the file's values leave
    redundant closures inconsistent by rounding, with a note saying so.

    A file prints its closures' points to some digits (Menagerie's ToddlerBot: two
    site-form ``connect`` per neck loop, eight digits): where closures are redundant
    (two points standing for a hinge), those digits can leave them inconsistent, a few
    nanometres that no joint closes, and no configuration then closes to ``tol``.
    Decided from the reference: when the closure solver stops at a residual between
    ``tol`` and :data:`~pkm_pin.tolerances.ASSEMBLY_CHECK_RTOL` (relative to the
    length) where its gradient ``J_cᵀ r`` vanishes (the least-squares closure: the
    residual no joint motion reduces), each open closure's ``C_b`` is moved onto its
    ``C_a`` there (a point closure's point; a weld's or revolute's frame) and that
    configuration becomes the reference. Anything else (a closure that closes, or one
    farther open: a wrong file) is left to the assembly and its diagnosis."""
    if not any(c.kind != "coupling" for c in model.closures):
        return model
    sol = solve_tree(model, model.reference, tol=tol, max_iter=200)
    if sol.converged or not sol.closure <= ASSEMBLY_CHECK_RTOL or sol.closure <= tol:
        return model
    kin = model.kinematics(sol.q)
    H = kin.closure_jacobian * model.velocity_units
    r = kin.residual
    if np.linalg.norm(H.T @ r) > 1e-6 * np.linalg.norm(H, 2) * np.linalg.norm(r):
        return model  # not the least-squares closure: a solver's failure, not rounding
    placements = kin.frame_placements
    closures, moved, worst = [], [], 0.0
    for c, rows in zip(model.closures, model.closure_slices()):
        gap = float(np.linalg.norm(r[rows])) if c.kind != "coupling" else 0.0
        if gap <= tol:
            closures.append(c)
            continue
        oMa = placements[model.frame_id(c.frame_a)] * c.placement_a
        oMfb = placements[model.frame_id(c.frame_b)]
        if c.kind == "point":
            new = pin.SE3(c.placement_b.rotation, oMfb.actInv(oMa.translation))
        else:
            new = oMfb.actInv(oMa)
        worst = max(worst, float(np.linalg.norm((oMfb * c.placement_b).translation
                                                - oMa.translation)))
        closures.append(replace(c, placement_b=new))
        moved.append(c.name)
    many = len(moved) > 1
    note = (f"closure{'s' * many} {', '.join(moved[:6])}{' …' if len(moved) > 6 else ''}: "
            f"{'their' if many else 'its'} second frame moved onto the first by at most "
            f"{worst:.3g} m (relative residual {sol.closure:.2g}): the file's values leave "
            "redundant closures inconsistent by rounding, which no joint closes; the "
            "reference is their least-squares closure")
    return replace(model, closures=tuple(closures), reference=sol.q,
                   notes=tuple(model.notes) + (note,))
