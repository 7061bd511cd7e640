"""Independent sub-mechanisms of a linkage (issue 25: two legs of six motors each).

A closure model may hold several mechanisms that share only the base: a biped's two
legs, each with its own motors, loops and foot. Read as one mechanism with one output,
the other leg's motors move nothing of that output and the analysis reports a type I
singularity by construction. This module splits such a model and analyses each part on
its own.

**The groups** (:func:`groups`). Nodes: the tree's joints (Pinocchio joints; the
universe is the base and no node). Each joint is linked to its parent joint (what moves
a body moves everything it carries), each closure links the joints carrying its two
frames (a coupling: its two joints), so a closure's whole loop (the tree path between its
frames) and every joint between that loop and the base fall in one group, and so does an
actuated joint with the joints it carries. A **group** is a connected component holding
at least one closure or one actuated joint: two groups share no movable joint, no closure
and no actuator, and move relative to the base independently. A root subtree with neither
closure nor actuator (a free pendulum: idle in the whole) belongs to no group and is held
at the assembled configuration in every sub-mechanism. A floating base (a free joint at
the root carrying everything) makes one group.

**A sub-mechanism** (:func:`submechanisms`) is a :class:`~pkm_pin.linkage.Linkage` over a
:class:`~pkm_pin.model.ClosureModel` whose tree is the whole tree with every joint outside
the group locked at the assembled configuration (:func:`_reduced`, as
``pinocchio.buildReducedModel`` would: the locked bodies become frames of the universe),
with the group's closures and actuated joints (in the whole's actuated order), the whole's
name with ``[k]`` appended, its own characteristic length (the default of the reduced
tree) and the assembled configuration as reference. Its output: the whole's output when it
was named (by the caller or the file) and lies in the group; else the body the group
exists to move (:func:`pkm_pin.output_choice.designer_output`, whose candidates are the
group's bodies: the locked ones hang on the universe), e.g. the right foot for the right
leg.

A model with one group is its own only sub-mechanism (``[link]``).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .model.closure_model import ClosureModel
from .output_choice import designer_output


def groups(model: ClosureModel) -> tuple:
    """The independent groups of ``model`` (module docstring), each a sorted tuple of
    joint ids of the tree, ordered by their first joint (tree order)."""
    tree = model.tree
    parent = list(range(tree.njoints))

    def find(j: int) -> int:
        while parent[j] != j:
            parent[j] = parent[parent[j]]
            j = parent[j]
        return j

    def union(a: int, b: int) -> None:
        if a > 0 and b > 0:
            parent[find(a)] = find(b)

    for j in range(1, tree.njoints):
        union(j, tree.parents[j])
    seeds = {tree.getJointId(name) for name in model.actuated}
    for c in model.closures:
        a, b = (tree.frames[tree.getFrameId(n)].parentJoint for n in (c.frame_a, c.frame_b))
        union(a, b)
        seeds.update(j for j in (a, b) if j > 0)
    roots = {find(j) for j in seeds}
    members: dict = {}
    for j in range(1, tree.njoints):
        if find(j) in roots:
            members.setdefault(find(j), []).append(j)
    return tuple(sorted((tuple(m) for m in members.values()), key=lambda m: m[0]))


def submechanisms(link, q=None) -> list:
    """The independent sub-mechanisms of ``link`` (a :class:`~pkm_pin.linkage.Linkage`)
    at the assembled tree configuration ``q`` (default: its home assembly), in the order
    of :func:`groups`; ``[link]`` when it has one group (module docstring)."""
    model = link.model
    found = groups(model)
    if len(found) <= 1:
        return [link]
    q = link.home_assembly.q if q is None else model.check_q(q)
    return [_sub(link, joints, q, k) for k, joints in enumerate(found)]


def _sub(link, joints: tuple, q: np.ndarray, k: int):
    """The sub-mechanism of the group ``joints`` (joint ids) at ``q``: its tree, closures,
    actuators and output (module docstring)."""
    model = link.model
    tree = model.tree
    keep = set(joints)
    reduced = _reduced(tree, keep, q)
    closures = tuple(c for c in model.closures
                     if tree.frames[tree.getFrameId(c.frame_a)].parentJoint in keep
                     or tree.frames[tree.getFrameId(c.frame_b)].parentJoint in keep)
    actuated = tuple(n for n in model.actuated if tree.getJointId(n) in keep)
    matches = tuple((ident, names) for ident, names in model.actuator_matches
                    if set(names) <= set(actuated))
    out_joint = tree.frames[tree.getFrameId(model.output)].parentJoint
    named = model.output_named and out_joint in keep
    output = model.output if out_joint in keep else _first_body(reduced)
    sub = ClosureModel(reduced, closures, actuated, output,
                       name=f"{model.name or 'linkage'}[{k}]", reference=_restrict(tree,
                                                                                   reduced, q),
                       output_point=model.output_point, actuator_matches=matches,
                       notes=model.notes, output_named=named,
                       springs=tuple(n for n in model.springs if reduced.existJointName(n)))
    one = type(link)(sub)
    return one if named else designer_output(one)


def _reduced(tree: pin.Model, keep: set, q: np.ndarray) -> pin.Model:
    """``tree`` with only the joints ``keep`` (whole root subtrees: no kept joint has a
    locked ancestor), the others held at ``q``: the kept joints with their parents,
    placements, limits, inertias and armature; every frame in the tree's order, a frame of
    a held joint moved to the universe at its placement at ``q`` (a held joint's frame
    becomes a fixed joint's). Built here rather than by ``pinocchio.buildReducedModel``,
    which finds a joint's frame by the joint's name and fails on the Extended URDF
    reader's split spherical joints (their first revolutes have no frame)."""
    data = tree.createData()
    pin.framesForwardKinematics(tree, data, q)
    out = pin.Model()
    out.name = tree.name
    index = {0: 0}
    for j in sorted(keep):
        jm, iq, iv = tree.joints[j], tree.idx_qs[j], tree.idx_vs[j]
        qs, vs = slice(iq, iq + jm.nq), slice(iv, iv + jm.nv)
        index[j] = out.addJoint(
            index[tree.parents[j]], jm, tree.jointPlacements[j], tree.names[j],
            tree.lowerEffortLimit[vs], tree.upperEffortLimit[vs],
            tree.lowerVelocityLimit[vs], tree.upperVelocityLimit[vs],
            tree.lowerPositionLimit[qs], tree.upperPositionLimit[qs],
            tree.positionLimitMargin[qs], tree.lowerDryFrictionLimit[vs],
            tree.upperDryFrictionLimit[vs], tree.damping[vs])
        out.appendBodyToJoint(index[j], tree.inertias[j], pin.SE3.Identity())
        out.armature[out.idx_vs[index[j]]:out.idx_vs[index[j]] + jm.nv] = tree.armature[vs]
    frames = {0: 0}
    for k, f in enumerate(tree.frames):
        if k == 0:
            continue
        if f.parentJoint in index:
            g = pin.Frame(f.name, index[f.parentJoint], frames.get(f.parentFrame, 0),
                          f.placement, f.type, f.inertia)
        else:
            kind = pin.FrameType.FIXED_JOINT if f.type == pin.FrameType.JOINT else f.type
            g = pin.Frame(f.name, 0, frames.get(f.parentFrame, 0), data.oMf[k], kind,
                          f.inertia)
        frames[k] = out.addFrame(g, False)
    return out


def _restrict(tree: pin.Model, reduced: pin.Model, q: np.ndarray) -> np.ndarray:
    """The coordinates of ``reduced``'s joints (by name) taken from ``tree``'s ``q``."""
    out = pin.neutral(reduced)
    for j in range(1, reduced.njoints):
        src = tree.joints[tree.getJointId(reduced.names[j])]
        dst = reduced.joints[j]
        out[dst.idx_q:dst.idx_q + dst.nq] = q[src.idx_q:src.idx_q + src.nq]
    return out


def _first_body(tree: pin.Model) -> str:
    """The first body frame on a movable joint of ``tree`` (a provisional output)."""
    return next(f.name for f in tree.frames
                if f.type == pin.FrameType.BODY and f.parentJoint > 0)


def embed(link, sub, q_sub: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The whole tree's configuration ``q`` with the joints of the sub-mechanism ``sub``
    (of ``link``: :func:`submechanisms`) set from ``q_sub`` (``sub``'s tree
    configuration), by joint name: the inverse of the restriction that gives a
    sub-mechanism its reference."""
    tree, reduced = link.model.tree, sub.model.tree
    out = link.model.check_q(q).copy()
    q_sub = sub.model.check_q(q_sub)
    for j in range(1, reduced.njoints):
        dst = tree.joints[tree.getJointId(reduced.names[j])]
        src = reduced.joints[j]
        out[dst.idx_q:dst.idx_q + dst.nq] = q_sub[src.idx_q:src.idx_q + src.nq]
    return out


def analysed(link, q) -> tuple:
    """``(sub-mechanism, its analysis at its reference assembly)`` of each independent
    sub-mechanism of ``link`` at the assembled ``q`` (:func:`submechanisms`); ``()`` for
    one mechanism."""
    subs = link.submechanisms(q)
    if len(subs) <= 1:
        return ()
    return tuple((sub, sub.analyze(sub.home_assembly)) for sub in subs)
