"""The default output of a linkage: the body the mechanism exists to move (issue 25).

A closed-loop file often names no output. The readers' fallback (``effector``, else the
last link no closure uses) then lands on a rod or a motor crank of a leg: its analysis
shows idle spins, zero rows of ``A`` and type I–III "singularities" that belong to the
rod, not to the machine. :func:`choose_output` picks, at an assembled configuration, the
body frame a designer would analyse — a leg's foot, an ankle's foot plate, a machine's
platform — by this rule (``docs/closed_loops.md``, "Default output"):

1. **Candidates**: the body frames of the tree (Pinocchio ``BODY`` frames: URDF links,
   MJCF bodies), less the universe and the marker links a closure uses (a body's own
   frame used by a closure, as in MJCF, stays).
2. **Controlled motion**: with ``N`` the motions the closures allow (null space of
   ``J_c``), ``X`` the actuated rates and ``Y`` the frame's homogenised twists over ``N``,
   ``idle_dim`` is the rank of ``Y`` on ``ker X`` (its motions with every motor locked)
   and ``controlled_dim = rank Y − idle_dim``. Springs (:attr:`ClosureModel.springs`)
   are held: ``N`` is restricted to the motions that leave them still, so that a leg's
   foot below Cassie's shin and heel springs counts the motions its motors give it.
   The frame **fits** when ``idle_dim = 0`` and ``rank Y = rank X``: its motion and the
   motors' determine each other, so neither the forward nor the inverse index of the
   analysis is zero by construction. A rod that
   spins about its own axis, a crank that a motor moves alone, a base do not fit.
3. **Order** (:meth:`OutputCandidate.key`): the larger ``controlled_dim``; the smaller
   ``idle_dim``; a body with mass before a massless one (an exporter's intermediate links
   between the revolutes of a spherical joint; only when the file gives masses); not a
   **crank** (every movable joint of its support actuated); not a **rod** (a leaf of the
   tree carrying exactly one closure frame and no link named like an end body, or an
   unactuated zero-length link whose only child is a rod: the cross of a rod end's
   universal joint, :func:`_rod_ends`); the body
   **furthest from the base** (:func:`_depths`: fewest joints from the base through the
   tree and the closures); a frame **named** like an end body (:func:`name_score`); the
   joint's own body frame before links fixed to it; tree order.
4. **Ties**: the other bodies (one frame each) equal to the chosen one on every key but
   the name and the frame are listed (:attr:`OutputChoice.ties`): the two feet of a
   two-legged robot, a motor crank that moves in as many dimensions as the foot.

With an output point (``output_point``), ``Y`` is the velocity of each frame's origin
(3 rows) instead of its twist. Ranks are decided on dimensionless matrices (rad, length
``L`` = :attr:`ClosureModel.length`) with :data:`~pkm_pin.tolerances.RANK_RTOL` times the
largest singular value over all frames.

A mechanism whose independent actuators outnumber six (two legs of six motors each) has
no fitting frame: the frame ranked first then moves with every motor of its own leg and
not with the other leg's, which a single output reports as a type I singularity; each
leg read alone (:mod:`pkm_pin.submechanisms`) has its own foot as output.
"""

from __future__ import annotations

import heapq
import re
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from . import screws
from .assembly import Assembly
from .errors import PkmError
from .model.closure_model import ClosureModel, NullSpace
from .tolerances import RANK_RTOL

#: Names of the end bodies a designer analyses (case-insensitive; exact, then contained).
END_BODY_NAMES = ("end_effector", "effector", "foot", "platform", "plate", "tool", "tcp",
                  "sole")

_SIDE = re.compile(r"^(left|right|l|r)[_-]|[_-](left|right|l|r|\d+)$")


@dataclass(frozen=True)
class OutputCandidate:
    """One body frame judged as an output (:func:`rank_outputs`).

    Attributes:
        frame: The frame's name.
        joint: Name of the joint that carries it.
        motion_dim: Dimension of its motions allowed by the closures (its twists; the
            velocities of its origin for an output point).
        idle_dim: Dimension of its motions with every actuator locked (0: the
            actuators determine its motion).
        controlled_dim: ``motion_dim − idle_dim``: the dimensions of its motion that the
            actuators set.
        fits: ``idle_dim == 0`` and ``motion_dim`` equals the number of independent
            actuators.
        massless: The joint carries no mass while others do (the intermediate links an
            exporter puts between the revolutes of a spherical or universal joint).
        crank: Every movable joint in its support is actuated: the motors move it
            alone (a motor's crank; every body of a serial arm).
        rod: A leaf body of the tree carrying exactly one closure frame and no link
            named like an end body: a two-point link between its joint and a closure;
            or an unactuated zero-length link whose only child is a rod (the cross of
            a rod end's universal joint).
        depth: Its distance from the base (:func:`_depths`: the fewest joints on a
            path through the tree and the closures).
        named: :func:`name_score` (3: an end body's name, 2: the same with a side
            prefix or suffix, 1: a name containing one, 0: neither).
        own: The joint's own body frame (not a link fixed to it).
    """

    frame: str
    joint: str
    motion_dim: int
    idle_dim: int
    controlled_dim: int
    fits: bool
    massless: bool
    crank: bool
    rod: bool
    depth: int
    named: int
    own: bool

    @property
    def determined(self) -> bool:
        """No idle motion (actuators locked) moves it."""
        return self.idle_dim == 0

    def key(self) -> tuple:
        """Sort key of the rule (module docstring), without the tree order."""
        return (-self.controlled_dim, self.idle_dim, self.massless, self.crank, self.rod,
                -self.depth, -self.named, not self.own)

    def tie_key(self) -> tuple:
        """The keys on which ties are judged (all but the name and the frame)."""
        return self.key()[:6]


@dataclass(frozen=True)
class OutputChoice:
    """The default output of a linkage (:func:`choose_output`).

    Attributes:
        frame: The chosen frame.
        ties: Other bodies (one frame each) that fit equally well, in rule order.
        candidates: Every candidate frame, best first.
        independent_actuators: The number of independent actuators (``rank X``).
    """

    frame: str
    ties: tuple
    candidates: tuple
    independent_actuators: int

    @property
    def fits(self) -> bool:
        """Whether the chosen frame fits (module docstring, rule 2)."""
        return bool(self.candidates) and self.candidates[0].fits

    def likely(self) -> tuple:
        """The chosen frame and its ties."""
        return (self.frame,) + self.ties

    def describe(self) -> str:
        """One sentence: the frame chosen, why, and its ties."""
        if not self.candidates:
            return f"output {self.frame}: no body frame to choose from"
        c = self.candidates[0]
        n = self.independent_actuators
        why = (f"its motion space has the dimension of the {n} independent actuators and "
               "no idle motion moves it" if c.fits else
               f"no body fits the {n} independent actuators; the motors set "
               f"{c.controlled_dim} of its {c.motion_dim} motion dimensions"
               + (f", {c.idle_dim} more with them locked" if c.idle_dim else ""))
        tied = f" (equally: {', '.join(self.ties)})" if self.ties else ""
        return (f"output {self.frame} chosen: {why}, {c.depth} joints from the base"
                f"{tied}")


def name_score(name: str) -> int:
    """3 if ``name`` is an end body's name (:data:`END_BODY_NAMES`, case-insensitive), 2
    if it is one less a side prefix or suffix (``left_``, ``_r``, ``_2`` …), 1 if it
    contains one, else 0."""
    low = name.lower()
    if low in END_BODY_NAMES:
        return 3
    if _SIDE.sub("", low) in END_BODY_NAMES:
        return 2
    return 1 if any(n in low for n in END_BODY_NAMES) else 0


def rank_outputs(model: ClosureModel, q, rtol: float = RANK_RTOL) -> tuple:
    """Every candidate body frame of ``model`` at the assembled ``q``, best first
    (:class:`OutputCandidate`, module docstring)."""
    return _judge(model, q, rtol)[0]


def _judge(model: ClosureModel, q, rtol: float) -> tuple:
    """``(rank_outputs, rank X)``."""
    tree = model.tree
    kin = model.kinematics(q)
    ns = NullSpace(model, kin, rtol)
    N, X = ns.N, ns.X
    if model.springs:  # springs held: only the motions that leave every spring still
        springs = [tree.joints[tree.getJointId(n)].idx_v for n in model.springs]
        r_s, _, _, Vs = screws.svd_rank(N[springs], rtol)
        N, X = N @ Vs[r_s:].T, X @ Vs[r_s:].T
    r_x, _, _, Vt = screws.svd_rank(X, rtol)
    idle = Vt[r_x:].T  # null coordinates of the idle motions
    used = {name for c in model.closures if c.joins_frames
            for name in (c.frame_a, c.frame_b)}
    frames = [(k, f) for k, f in enumerate(tree.frames)  # bodies that can move
              if k > 0 and f.type == pin.FrameType.BODY and f.parentJoint > 0
              and (f.name not in used or _own(tree, f))]
    units = ns.units[:, None] * N
    placements = kin.frame_placements
    Y = []
    for k, f in frames:  # (6 or 3) × dof: the frame's motions over the null coordinates
        T = (kin.body_jacobians[f.parentJoint] @ units).T
        H = screws.homogenised_about(T, placements[k].translation, model.length)
        Y.append((H[:, 3:] if model.output_point else H).T)
    scale = max((np.linalg.norm(y, 2) for y in Y if y.size), default=0.0)
    tol = rtol * scale
    massless = _massless(tree)
    depth = _depths(model, massless)
    rods = _rods(model, used)
    actuated = {tree.getJointId(name) for name in model.actuated}
    cranks = {j for j in range(1, tree.njoints)
              if all(i in actuated for i in tree.supports[j][1:] if tree.joints[i].nv > 0)}
    out = []
    for (k, f), y in zip(frames, Y):
        dim = _rank(y, tol)
        idle_dim = _rank(y @ idle, tol) if idle.size else 0
        j = f.parentJoint
        out.append(OutputCandidate(f.name, tree.names[j], dim, idle_dim, dim - idle_dim,
                                   idle_dim == 0 and dim == r_x and r_x > 0, j in massless,
                                   j in cranks, j in rods, depth[j], name_score(f.name),
                                   _own(tree, f)))
    # without an actuator that moves anything every motion is idle: controlled and idle
    # dimensions tell nothing, the body's place in the machine does
    order = sorted(range(len(out)), key=lambda i: (out[i].key()[0 if r_x else 2:], i))
    return tuple(out[i] for i in order), r_x


def choose_output(model: ClosureModel, q, rtol: float = RANK_RTOL) -> OutputChoice:
    """The default output of ``model`` at the assembled ``q`` (module docstring); the
    model's own output when it has no candidate body frame."""
    ranked, r_x = _judge(model, q, rtol)
    if not ranked:
        return OutputChoice(model.output, (), (), r_x)
    best = ranked[0]
    seen, ties = {best.joint}, []
    for c in ranked[1:]:
        if c.tie_key() == best.tie_key() and c.joint not in seen:
            seen.add(c.joint)
            ties.append(c.frame)
    return OutputChoice(best.frame, tuple(ties), ranked, r_x)


def designer_output(link):
    """``link`` (a :class:`~pkm_pin.linkage.Linkage`) analysing the frame of
    :func:`choose_output` at its :attr:`~pkm_pin.linkage.Linkage.home_assembly`, with
    that assembly kept; ``link`` itself when it does not assemble (the assembly error is
    raised again when it is asked for) or when the choice is its own output."""
    try:
        assembly = link.home_assembly
    except (PkmError, np.linalg.LinAlgError):
        return link
    choice = choose_output(link.model, assembly.q)
    if choice.frame == link.output:
        return link
    chosen = type(link)(link.model, output=choice.frame)
    pose = chosen.model.kinematics(assembly.q).output_placement
    chosen.__dict__["home_assembly"] = Assembly.of_tree(  # a cached_property
        chosen, assembly.q, assembly.residual, assembly.iterations,
        assembly.closure_residuals, assembly.q_actuated, pose)
    return chosen


def _own(tree: pin.Model, f: pin.Frame) -> bool:
    """Whether the body frame ``f`` is its joint's own (not a link fixed to it)."""
    return f.parentFrame == 0 or tree.frames[f.parentFrame].type == pin.FrameType.JOINT


def _rank(M: np.ndarray, tol: float) -> int:
    """Singular values of ``M`` above the absolute ``tol``."""
    return int(np.sum(np.linalg.svd(M, compute_uv=False) > tol)) if M.size else 0


def _massless(tree: pin.Model) -> set:
    """Movable joints whose bodies carry no mass, in a tree where some do."""
    masses = [tree.inertias[j].mass for j in range(tree.njoints)]
    heaviest = max(masses[1:], default=0.0)
    if heaviest <= 0:
        return set()
    return {j for j in range(1, tree.njoints) if masses[j] <= 1e-12 * heaviest}


def _depths(model: ClosureModel, massless: set) -> list:
    """Each joint's body's distance from the base: the fewest joints on a path from the
    base through the tree's joints and the closures (a joint of a massless body and a
    weld count 0, a point closure 1). A free-flyer joint under the universe is no path
    when other joints hang on the universe (a free platform held by closures), the base
    itself when it is the only one (a floating base)."""
    tree = model.tree
    edges: dict = {j: [] for j in range(tree.njoints)}
    roots = [j for j in range(1, tree.njoints) if tree.parents[j] == 0]
    for j in range(1, tree.njoints):
        joint = tree.joints[j]
        free = joint.nv == 6 and tree.parents[j] == 0
        if free and len(roots) > 1:
            continue
        w = 0 if (free or joint.nv == 0 or j in massless) else 1
        edges[tree.parents[j]].append((j, w))
        edges[j].append((tree.parents[j], w))
    for c in model.closures:
        if not c.joins_frames:  # a coupling of joint coordinates joins no bodies
            continue
        a, b = (tree.frames[tree.getFrameId(n)].parentJoint for n in (c.frame_a, c.frame_b))
        w = 0 if c.kind == "weld" else 1
        edges[a].append((b, w))
        edges[b].append((a, w))
    far = tree.njoints + len(model.closures) + 1
    dist = [far] * tree.njoints
    dist[0] = 0
    heap = [(0, 0)]
    while heap:
        d, j = heapq.heappop(heap)
        if d > dist[j]:
            continue
        for k, w in edges[j]:
            if d + w < dist[k]:
                dist[k] = d + w
                heapq.heappush(heap, (d + w, k))
    return dist


def _rods(model: ClosureModel, used: set) -> set:
    """Joints whose body is a rod: a leaf of the tree carrying exactly one closure frame
    and no link named like an end body (:func:`name_score` 2 or 3), and the
    intermediate links of its joint (:func:`_rod_ends`)."""
    tree = model.tree
    parents = set(tree.parents[1:])
    ends = [tree.frames[tree.getFrameId(name)].parentJoint
            for c in model.closures if c.joins_frames for name in (c.frame_a, c.frame_b)]
    named = {f.parentJoint for f in tree.frames
             if f.type == pin.FrameType.BODY and (f.name not in used or _own(tree, f))
             and name_score(f.name) >= 2}
    rods = {j for j in set(ends)
            if j > 0 and j not in parents and ends.count(j) == 1 and j not in named}
    return rods | _rod_ends(model, rods, set(ends) | named)


def _rod_ends(model: ClosureModel, rods: set, kept: set) -> set:
    """The intermediate links of a rod's joint (the cross of a universal joint, the
    first revolutes of a spherical one, with or without mass): climbing from each rod,
    a parent whose only child is a rod (or such a link) jointed at the parent's own
    joint origin (zero length: the two axes meet), whose own joint moves and is not
    actuated, carrying no closure frame nor a link named like an end body (``kept``).
    A link of length (a five-bar's distal link carrying its pin's marker link) is no
    such link."""
    tree = model.tree
    actuated = {tree.getJointId(name) for name in model.actuated}
    children: dict = {}
    for j in range(1, tree.njoints):
        children.setdefault(tree.parents[j], []).append(j)
    out: set = set()
    for j in rods:
        p = tree.parents[j]
        while (p > 0 and children.get(p) == [j] and p not in kept and p not in actuated
               and tree.joints[p].nv > 0 and np.linalg.norm(
                   tree.jointPlacements[j].translation) <= 1e-9 * model.length):
            out.add(p)
            j, p = p, tree.parents[p]
    return out
