"""A base–legs–platform structure, detected in any closure model.

Whatever file describes a parallel machine — TOML legs welded to a free platform, an
Extended URDF whose tree runs through one leg to the platform and closes the other legs
on it with point closures, an MJCF with ``<equality>`` welds — the machine is the same:
legs, each a serial chain from the base to the one output body (the platform). This
module finds that structure in a :class:`~pkm_pin.model.ClosureModel` so that every such
file gets the per-leg screw engine of seed 000 (:class:`pkm_pin.Mechanism`), with the
same numbers whatever tree describes it.

The rule (:func:`detect_platform`):

* the **platform** is the body carrying the output frame (a body, not a point output);
  it hangs either on a free-flyer joint under the base (no leg in the tree: every leg is
  closed on it), or at the end of a chain of one-coordinate joints from the base (that
  chain is a leg: the *tree leg*, its tip the output frame);
* every closure joins a frame on the platform to a frame of one **closure leg**: the
  chain of one-coordinate joints from the base to that frame; a weld fixes the leg's tip
  to the platform, a point closure is a spherical joint there and a revolute closure a
  revolute joint about the constraint frames' common z axis;
* legs share no joint, and every movable joint of the tree is on a leg (or is the
  platform's free flyer): a joint on no leg, a closure between two legs or from the
  platform to itself (refused by the closure model), a joint of several coordinates on
  a leg (a ball joint), a coupling of two joints' coordinates (an MJCF ``<joint>``
  equality: no leg holds it), or mimicking joints leave the model to the general
  elimination, with the reason.

The structure only names joints and frames: the legs' Pinocchio models are built from it
by :meth:`pkm_pin.Mechanism.from_closure_model`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .closure_model import COUPLING, Closure, ClosureModel

__all__ = ["PlatformLeg", "PlatformStructure", "detect_platform", "legs_length"]


@dataclass(frozen=True)
class PlatformLeg:
    """One leg of a detected platform structure.

    Attributes:
        name: The leg's name: the common prefix of its joints' names (``"leg2"`` for
            ``leg2_U1``, ``leg2_P``…), else its leg-side frame (``"tree"`` for the leg
            the tree carries the platform on).
        joints: Tree joint indices from the base to the leg's end, one coordinate each.
        kind: ``"tree"`` (the platform is the leg's last body), or the kind of the
            closure joining the leg to the platform: ``"weld"``, ``"point"``,
            ``"revolute"``.
        frame: The leg-side frame of the closure (the output frame for the tree leg).
        placement: The constraint frame in :attr:`frame` (identity for the tree leg).
        platform_frame: The platform-side frame of the closure (the output frame for
            the tree leg).
        platform_placement: The constraint frame in :attr:`platform_frame`.
    """

    name: str
    joints: tuple[int, ...]
    kind: str
    frame: str
    placement: pin.SE3
    platform_frame: str
    platform_placement: pin.SE3


@dataclass(frozen=True)
class PlatformStructure:
    """A base–legs–platform machine found in a closure model (module docstring).

    Attributes:
        platform_joint: Tree joint carrying the platform body.
        free_flyer: Whether that joint is a free flyer under the base (else it is the
            last joint of the tree leg).
        legs: The legs, in the order of their first actuated joint in the model's
            actuated list (so the mechanism's actuated coordinates keep the file's
            order).
    """

    platform_joint: int
    free_flyer: bool
    legs: tuple[PlatformLeg, ...]


def detect_platform(model: ClosureModel) -> tuple[PlatformStructure | None, str]:
    """The platform structure of ``model``, or ``None`` and the reason in words.

    Returns:
        ``(structure, "")`` where the rule of the module docstring holds, else
        ``(None, reason)``: ``reason`` says which joint, closure or frame breaks it.
    """
    tree = model.tree
    if model.output_point:
        return None, "the output is a point, not a platform body"
    if any(tree.joints[j].shortname() == "JointModelMimic" for j in range(1, tree.njoints)):
        return None, "the tree has mimicking joints"
    platform = tree.frames[tree.getFrameId(model.output)].parentJoint
    if platform == 0:
        return None, f"the output frame {model.output!r} is fixed to the base"
    free_flyer = (tree.joints[platform].shortname() == "JointModelFreeFlyer"
                  and tree.parents[platform] == 0)
    legs, used = [], set()
    if not free_flyer:
        chain, reason = _chain(tree, platform, "the platform")
        if reason:
            return None, reason
        legs.append(PlatformLeg(_leg_name(tree, chain, "tree"), chain, "tree", model.output,
                                pin.SE3.Identity(),
                                model.output, pin.SE3.Identity()))
        used |= set(chain)
    for closure in model.closures:
        if closure.kind == COUPLING:
            return None, (f"closure {closure.name!r} couples the coordinates of two joints "
                          f"({closure.frame_a!r}, {closure.frame_b!r}; a joint equality), "
                          "which no leg of a base–legs–platform machine holds")
        leg, reason = _closure_leg(tree, closure, platform, model.output)
        if reason:
            return None, reason
        shared = used & set(leg.joints)
        if shared:
            return None, (f"closure {closure.name!r} closes a chain that shares joint "
                          f"{tree.names[min(shared)]!r} with another leg")
        used |= set(leg.joints)
        legs.append(leg)
    movable = {j for j in range(1, tree.njoints) if tree.joints[j].nv > 0}
    free = movable - used - ({platform} if free_flyer else set())
    if free:
        return None, f"joint {tree.names[min(free)]!r} is on no leg between base and platform"
    order, reason = _actuated_order(model, legs)
    if reason:
        return None, reason
    return PlatformStructure(platform, free_flyer, tuple(legs[i] for i in order)), ""


def _chain(tree: pin.Model, joint: int, what: str) -> tuple[tuple[int, ...], str]:
    """The joints from the base to ``joint`` (its support), if each moves along one
    coordinate; else ``((), reason)``."""
    chain = tuple(int(j) for j in tree.supports[joint] if j > 0)
    for j in chain:
        if tree.joints[j].nv != 1:
            kind = tree.joints[j].shortname().removeprefix("JointModel")
            return (), (f"joint {tree.names[j]!r} on the chain to {what} is a {kind} joint "
                        f"({tree.joints[j].nv} coordinates), not a one-coordinate joint")
    return chain, ""


def _closure_leg(tree: pin.Model, closure: Closure, platform: int, output: str
                 ) -> tuple[PlatformLeg | None, str]:
    """The leg closed on the platform by ``closure``, or ``(None, reason)``."""
    sides = [(closure.frame_a, closure.placement_a), (closure.frame_b, closure.placement_b)]
    parents = [tree.frames[tree.getFrameId(f)].parentJoint for f, _ in sides]
    on_platform = [p == platform for p in parents]
    if not any(on_platform):  # (both on it: refused by ClosureModel)
        return None, (f"closure {closure.name!r} joins {closure.frame_a!r} to "
                      f"{closure.frame_b!r}, neither on the platform (the body of the "
                      f"output frame {output!r})")
    (frame, placement), (pframe, pplacement) = sides if on_platform[1] else sides[::-1]
    leg_joint = parents[1] if on_platform[0] else parents[0]
    if platform in tree.supports[leg_joint]:
        return None, f"closure {closure.name!r} closes a chain carried by the platform"
    chain, reason = _chain(tree, leg_joint, repr(frame)) if leg_joint else ((), "")
    if reason:
        return None, reason
    name = _leg_name(tree, chain, frame)
    return PlatformLeg(name, chain, closure.kind, frame, placement, pframe, pplacement), ""


def _actuated_order(model: ClosureModel, legs: list) -> tuple[list[int], str]:
    """Leg order that keeps the model's actuated order (legs without actuated joints
    last), or a reason where the file interleaves one leg's actuated joints with
    another's."""
    tree = model.tree
    rank = {name: k for k, name in enumerate(model.actuated)}
    firsts = []
    for leg in legs:
        mine = sorted(rank[tree.names[j]] for j in leg.joints if tree.names[j] in rank)
        firsts.append(mine[0] if mine else len(rank) + len(firsts))
    order = sorted(range(len(legs)), key=firsts.__getitem__)
    seen = [rank[tree.names[j]] for i in order for j in legs[i].joints
            if tree.names[j] in rank]
    if seen != sorted(seen):
        return [], ("the actuated joints are listed in an order that interleaves the legs "
                    "(list each leg's actuated joints together, in chain order)")
    return order, ""


def _leg_name(tree: pin.Model, chain: tuple[int, ...], default: str) -> str:
    """A leg's name: the common prefix of its joints' names (``"leg2"`` for
    ``leg2_U1``, ``leg2_P``, …) when it is at least two characters, else ``default``."""
    names = [tree.names[j] for j in chain]
    prefix = os.path.commonprefix(names).rstrip("_-/ .") if len(names) > 1 else ""
    return prefix if len(prefix) >= 2 else default


def legs_length(model: ClosureModel, structure: PlatformStructure) -> float:
    """The characteristic length [m] of the machine's legs: the mean over the legs of
    :attr:`pkm_pin.leg.Leg.characteristic_length` of the legs that
    :meth:`pkm_pin.Mechanism.from_closure_model` builds (the offsets between consecutive
    joints from the second on, the offset of the closure's constraint frame from the
    leg's last joint, half the range of each prismatic joint with finite limits; legs
    with none are left out), read from the tree without building them. The same
    machine written as TOML legs or as any tree plus closures gets the same length,
    hence the same homogenised indices."""
    tree = model.tree
    lengths = []
    for leg in structure.legs:
        L = sum(float(np.linalg.norm(tree.jointPlacements[j].translation))
                for j in leg.joints[1:])
        if leg.kind != "tree":
            frame = tree.frames[tree.getFrameId(leg.frame)]
            L += float(np.linalg.norm((frame.placement * leg.placement).translation))
        for j in leg.joints:
            joint = tree.joints[j]
            if joint.nq == joint.nv == 1 and "P" in joint.shortname():  # prismatic
                lo = tree.lowerPositionLimit[joint.idx_q]
                up = tree.upperPositionLimit[joint.idx_q]
                if np.isfinite(lo) and np.isfinite(up):
                    L += 0.5 * (abs(lo) + abs(up))
        if L > 0:
            lengths.append(L)
    return float(np.mean(lengths)) if lengths else 1.0
