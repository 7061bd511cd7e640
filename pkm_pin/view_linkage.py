"""Browser preview of a general linkage (:class:`~pkm_pin.linkage.Linkage`): its tree,
its closures, its output frame and its idle motions in a meshcat scene.

:func:`view_linkage` (also reached through :func:`pkm_pin.view.view`) draws, in the
scene and page machinery of :mod:`pkm_pin.scene`:

* the tree as a skeleton: a bar from each joint's parent joint origin to its origin
  (grey from the world origin: the ground), and from a body's joint to the closure and
  output frames it carries; each joint as a ball (several degrees of freedom), a cylinder
  along its axis (revolute) or a cube (prismatic); actuated joints in orange. Bars are
  coloured by branch (the subtree of one joint under the universe);
* each closure: a translucent ring of thick bars along the loop (the tree path between
  its two frames, through their common ancestor) in :data:`CLOSURE_COLOUR`, a marker at
  its constraint frame (a ball for a point closure, a disc across the revolute axis, a
  cube for a weld) and a bar between the two frames when they do not meet;
* the output frame: a ball, and for a body its x, y, z axes (red, green, blue);
* each idle motion (a motion left with every actuated joint locked, see
  :class:`~pkm_pin.linkage.Mobility`): when one body moves, its instantaneous screw axis
  as a bar in :data:`IDLE_COLOUR` spanning the body's joints (the rod's spin axis of an
  S–S rod), else a halo on each joint that moves;
* the joint screw axes (``show_screws``) and the actuation and constraint wrenches on the
  output (``show_wrenches``), as :func:`pkm_pin.view.view` draws them; for a point
  output only the forces among the constraint wrenches.

A linkage of several **independent sub-mechanisms** (:mod:`pkm_pin.submechanisms`: a
biped's legs, which share no movable joint) is drawn as such: its bars coloured one colour
per sub-mechanism (a legend entry each naming its output, DOF, motion type and class),
each sub-mechanism's output frame drawn, and its actuation and constraint wrenches taken
from its own analysis (with its own output) at its own output; the title gives one line
per sub-mechanism instead of the whole's one-output reading (type I by construction: one
leg's motors do not move the other foot).

Title, legend, camera and grid as :func:`pkm_pin.view.view` has them; the title names
the output frame (or point) and its pose, the DOF, the idle DOF, the output's motion type
and the singularity class.

A linkage that does not assemble (a :class:`~pkm_pin.linkage.LoopClosureError` that
carries the best configuration reached, given as ``where`` or raised by the assembly from
the reference) is drawn **open**: the tree, the loops and the output at that
configuration (:meth:`Linkage.reached`), no idle motion nor wrench (nothing is analysed
off the closure manifold) nor screw axis (they would hide the gaps), and for each open
loop (:mod:`pkm_pin.closure_gaps`) a bar and
a line between its two constraint frames in a colour of its own (:data:`GAP_COLOURS`)
with a legend entry giving the gap in mm and degrees; the title says that it does not
assemble and names the worst loop; :attr:`LinkageScene.error` keeps the error.

Scene layout (meshcat paths; ``<m>`` is :func:`~pkm_pin.view.node_name` of the name)::

    pkm/<m>/links/<joint or frame>       skeleton bars
    pkm/<m>/joints/<joint>               joint markers
    pkm/<m>/closures/<closure>/ring/<k>  the loop's ring, marker, gap
    pkm/<m>/gaps/<closure>/bar|line      an open loop's gap (open drawing only)
    pkm/<m>/output/ball, output/x|y|z
    pkm/<m>/idle/<k>/axis, idle/<k>/joints/<joint>
    pkm/<m>/screws/<joint>
    pkm/<m>/wrenches/actuation/<joint>, wrenches/constraint/<k>

Sizes are fractions of the drawing's size (half the diagonal of the box around the
joints, at least :data:`DRAWING_LENGTH_FLOOR` times :attr:`ClosureModel.length`, which
sums every offset of the tree and so exceeds the drawing of a many-jointed leg several
times), so millimetres and metres look the same.
"""

from __future__ import annotations

import os

import numpy as np
import pinocchio as pin

from . import screws
from .assembly import Assembly
from .errors import InputError
from .linkage import Linkage, LoopClosureError, _body_points
from .model.closure_model import NullSpace
from .report import optional, readable_basis
from .scene import (
    ACTUATED_SCREW_COLOUR,
    ACTUATION_WRENCH_COLOUR,
    CONSTRAINT_WRENCH_COLOUR,
    LEG_COLOURS,
    PASSIVE_SCREW_COLOUR,
    PLATFORM_COLOUR,
    SINGULARITY_WORDS,
    LegendEntry,
    Scene,
    SceneRecorder,
    _meshcat,
    _Painter,
    _segment_matrix,
    _translation,
    node_name,
    pose_words,
)
from .submechanisms import analysed, groups
from .tolerances import RANK_RTOL

CLOSURE_COLOUR = 0xE7298A
IDLE_COLOUR = 0x00CC66
GROUND_COLOUR = 0x808080
OUTPUT_AXIS_COLOURS = (0xE41A1C, 0x4DAF4A, 0x377EB8)
#: The drawing's size is at least this share of :attr:`ClosureModel.length`.
DRAWING_LENGTH_FLOOR = 0.1
#: Colours of the open loops' gaps (cycled), none of the other colours of a linkage
#: scene.
GAP_COLOURS = (0xD62728, 0x1F3A93, 0x2CA02C, 0x9467BD, 0x8C564B, 0x4B0082, 0x006D6F,
               0x7B7B00, 0x000000, 0xB8860B)


class LinkageScene(Scene):
    """A linkage drawn in a meshcat scene (returned by :func:`view_linkage`).

    Attributes:
        linkage: The linkage (also :attr:`mechanism`, for the page title).
        assembly: The :class:`~pkm_pin.assembly.Assembly` drawn (for an open
            drawing, :meth:`Linkage.reached`: its loops do not all close).
        analysis: Its :class:`~pkm_pin.linkage.LinkageAnalysis` (None when open).
        idle_motions: The idle motions drawn, in words (none when open).
        error: The :class:`~pkm_pin.linkage.LoopClosureError` of an open drawing, else
            None.
        gaps: The open loops drawn (:class:`~pkm_pin.closure_gaps.Gap`, worst first).
        submechanisms: For a linkage of several independent sub-mechanisms (a biped's
            legs: :meth:`Linkage.submechanisms`), ``(sub-mechanism, its analysis)`` of
            each, drawn each with its own output and wrenches; ``()`` otherwise.
        failed_sections: ``{section: "Type: message"}`` for each optional part that
            failed (:func:`pkm_pin.report.optional`): ``"submechanisms"`` (the whole is
            drawn as one), ``"idle axes"``, ``"gaps"``, ``"screw axes"``, ``"wrenches"``
            (that layer is left out, the rest drawn).
        visualizer, recorder, root, animated: As :class:`pkm_pin.view.Scene`
            (``animated`` is False: nothing is animated).
    """

    def __init__(self, visualizer, recorder: SceneRecorder, link: Linkage,  # noqa: D107
                 assembly: Assembly, analysis, root: str,
                 error: LoopClosureError | None = None):
        self.visualizer = visualizer
        self.recorder = recorder
        self.linkage = self.mechanism = link
        self.assembly = assembly
        self.analysis = analysis
        self.idle_motions = () if analysis is None else tuple(analysis.mobility.idle_motions)
        self.root = root
        self.animated = False
        self.error = error
        self.gaps = () if error is None or error.diagnosis is None else error.diagnosis.gaps
        self.submechanisms = ()
        self.failed_sections = {}


def idle_velocities(link: Linkage, q) -> np.ndarray:
    """A basis (k × nv, rows) of the idle motions at ``q``: the tree velocities the
    closures allow with every actuated joint locked (the basis that
    :attr:`Mobility.idle_motions` describes, same rank decisions)."""
    model = link.model
    ns = NullSpace(model, model.kinematics(q), RANK_RTOL)
    return (ns.units[:, None] * ns.idle(RANK_RTOL)).T


def _assembly(link: Linkage, where) -> Assembly | LoopClosureError:
    """The assembly drawn, or the error of a linkage that does not assemble (when it
    carries the best configuration reached: drawn open)."""
    if isinstance(where, LoopClosureError) and where.q is not None:
        return where
    if where is None:
        try:
            return link.assemble()
        except LoopClosureError as e:
            if e.q is None:
                raise
            return e
    if isinstance(where, Assembly):
        return where
    from .assembly import as_pose

    return link.inverse_kinematics(as_pose(where))


def view_linkage(link: Linkage, where=None, *, visualizer=None,
                 open: bool = False,  # noqa: A002 - the name meshcat and Pinocchio use
                 html: str | os.PathLike | None = None, show_screws: bool = True,
                 show_wrenches: bool = True, source: str | None = None) -> LinkageScene:
    """Draw a linkage in a meshcat scene (see the module docstring).

    Args:
        link: The linkage.
        where: A :class:`~pkm_pin.assembly.Assembly`, or an output pose
            (``pin.SE3``, 4×4 matrix or x, y, z, roll, pitch, yaw: inverse kinematics),
            or a :class:`~pkm_pin.linkage.LoopClosureError` (drawn open at its best
            configuration); default: assembled from the reference configuration, drawn
            open when it does not assemble (see the module docstring).
        visualizer, open, html: As :func:`pkm_pin.view.view`.
        show_screws: Draw the joint screw axes.
        show_wrenches: Draw the actuation and constraint wrenches on the output.
        source: The file the linkage was read from, named in the title
            (:attr:`~pkm_pin.scene.Scene.source`).

    Raises:
        InputError: ``link`` is not a linkage or the pose is malformed.
        LoopClosureError: the inverse kinematics of a pose fails (a pose is not
            drawn open).
    """
    link = getattr(link, "general", link)  # a Mechanism read by the general backend
    if not isinstance(link, Linkage):
        raise InputError(f"view_linkage() takes a pkm_pin Linkage, got {type(link).__name__}")
    assembly = _assembly(link, where)
    error = assembly if isinstance(assembly, LoopClosureError) else None
    if error is not None:
        assembly, analysis = link.reached(error), None
    else:
        analysis = link.analyze(assembly)
    meshcat = _meshcat()[0]
    recorder = SceneRecorder(forward=None if visualizer is None else visualizer.window)
    vis = meshcat.Visualizer(window=recorder)
    if visualizer is not None:
        vis.path = visualizer.path
    scene = LinkageScene(vis, recorder, link, assembly, analysis, f"pkm/{node_name(link.name)}",
                         error)
    scene.source = source
    if error is None:
        scene.submechanisms = optional("submechanisms", lambda: analysed(link, assembly.q),
                                       scene.failed_sections) or ()
    painter = _LinkagePainter(scene)
    painter.tree()
    painter.closures()
    painter.output()
    failed = scene.failed_sections  # an optional layer that fails costs that layer
    if error is None:
        optional("idle axes", painter.idle, failed)
    else:
        optional("gaps", painter.gaps, failed)
    if show_screws and error is None:
        optional("screw axes", painter.screws, failed)
    if show_wrenches and error is None:
        optional("wrenches", painter.wrenches, failed)
    painter.settings()
    painter.finish()
    if html is not None:
        scene.to_html(html)
    if open:
        scene.open()
    return scene


class _LinkagePainter(_Painter):
    """Draws one linkage scene; sizes relative to the drawing's size."""

    def __init__(self, scene: LinkageScene):  # noqa: D107 - no super(): no mechanism
        _, self.g, self.anim, _, _ = _meshcat()
        self.scene = scene
        self.vis = scene.visualizer
        self.mech = scene.linkage
        self.model = scene.linkage.model
        self.tree_ = self.model.tree
        self.kin = self.model.kinematics(scene.assembly.q)
        self.root = scene.root
        self.legs_drawn = []
        self.noted = {}
        self.drawn_points = []
        self.grid_cell = None
        self.grid_height = 0.0
        P = self.mech_points()
        self.L = max(0.5 * float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))),
                     DRAWING_LENGTH_FLOOR * float(self.model.length))
        self.radius = self.L
        self.centre_at = None
        self.group_of = {}
        if scene.submechanisms:
            self.group_of = {j: k for k, g in enumerate(groups(self.model)) for j in g}

    def centre(self) -> np.ndarray:
        """Wrench arrows start nearest to the output frame's origin (a sub-mechanism's
        output while its wrenches are drawn)."""
        if self.centre_at is not None:
            return self.centre_at
        return self.kin.output_placement.translation

    # ------------------------------------------------------------------ geometry
    def frame_point(self, frame: str, placement: pin.SE3 | None = None) -> np.ndarray:
        fid = self.tree_.getFrameId(frame)
        M = self.kin.frame_placements[fid]
        return (M if placement is None else M * placement).translation.copy()

    def joint_origin(self, j: int) -> np.ndarray:
        return self.kin.joint_placements[j].translation.copy()

    def carried_frames(self) -> list[tuple[str, np.ndarray, int]]:
        """(name, world point, parent joint) of each closure frame and the output."""
        out = []
        for c in self.model.closures:
            for frame, P in ((c.frame_a, c.placement_a), (c.frame_b, c.placement_b)):
                if not c.joins_frames:
                    break
                out.append((frame, self.frame_point(frame, P),
                            self.tree_.frames[self.tree_.getFrameId(frame)].parentJoint))
        fid = self.tree_.getFrameId(self.mech.output)
        out.append((self.mech.output, self.frame_point(self.mech.output),
                    self.tree_.frames[fid].parentJoint))
        return out

    def mech_points(self) -> np.ndarray:
        """World points that the view must frame: the joints, the world origin, the
        closure and output frames."""
        pts = [np.zeros(3)] + [self.joint_origin(j) for j in range(1, self.tree_.njoints)]
        return np.vstack(pts + [p for _, p, _ in self.carried_frames()])

    def colour(self, j: int) -> int:
        """Colour of joint ``j``'s branch, or of its sub-mechanism when there are
        several (grey for the universe)."""
        if j == 0:
            return GROUND_COLOUR
        if j in self.group_of:
            return LEG_COLOURS[self.group_of[j] % len(LEG_COLOURS)]
        roots = [k for k in range(1, self.tree_.njoints) if self.tree_.parents[k] == 0]
        return LEG_COLOURS[roots.index(list(self.tree_.supports[j])[1]) % len(LEG_COLOURS)]

    def bar(self, path: str, a, b, colour: int, radius: float, opacity: float = 1.0,
            kind: str | None = None) -> bool:
        """A cylinder from ``a`` to ``b`` (none when they meet), noted in the legend as
        ``kind``; whether it was drawn."""
        if np.linalg.norm(np.asarray(b) - a) <= 1e-9 * self.L:
            return False
        self.vis[path].set_object(self.g.Cylinder(1.0, radius), self.material(colour, opacity))
        self.vis[path].set_transform(_segment_matrix(np.asarray(a), np.asarray(b)))
        self.drawn_points.append(np.array([a, b], dtype=float))
        if kind is not None:
            self.note(kind, colour)
        return True

    def title_lines(self) -> tuple[str, ...]:
        """Name; output frame and its pose; DOF, output motion type, idle DOF and
        singularity class."""
        if self.scene.error is not None:
            return self.open_title_lines()
        if self.scene.submechanisms:
            return self.submechanism_title_lines()
        a = self.scene.analysis
        M = self.kin.output_placement
        what = "point" if self.model.output_point else "frame"
        idle = f", {a.idle_dof} idle" if a.idle_dof else ""
        return (self.mech.name,
                f"output {what} {self.mech.output} at "
                f"{pose_words(M, self.L, point=self.model.output_point)}",
                f"{a.dof} DOF{idle}, output motion {a.motion_type}, singularity: "
                f"{SINGULARITY_WORDS.get(a.singularity, a.singularity)}")

    def submechanism_title_lines(self) -> tuple[str, ...]:
        """Name and how many sub-mechanisms; per sub-mechanism its output and pose, DOF,
        idle DOF, output motion type and singularity class (with its own output)."""
        subs = self.scene.submechanisms
        lines = [self.mech.name,
                 f"{len(subs)} independent sub-mechanisms (no movable joint shared), each "
                 "with its own output"]
        for k, (sub, a) in enumerate(subs):
            M = self.kin.frame_placements[self.tree_.getFrameId(sub.output)]
            idle = f", {a.idle_dof} idle" if a.idle_dof else ""
            lines.append(f"[{k}] {sub.name}: output {sub.output} at "
                         f"{pose_words(M, self.L, point=sub.model.output_point)}; {a.dof} DOF"
                         f"{idle}, output motion {a.motion_type}, singularity: "
                         f"{SINGULARITY_WORDS.get(a.singularity, a.singularity)}")
        return tuple(lines)

    def open_title_lines(self) -> tuple[str, ...]:
        """Name; that it does not assemble and how many loops stay open; the worst."""
        gaps, e = self.scene.gaps, self.scene.error
        worst = f"worst: {gaps[0].words()}" if gaps else f"worst: {e.leg!r}"
        n = len(gaps)
        return (self.mech.name,
                f"does not assemble: {n} loop{'s' * (n != 1)} open at the best "
                f"configuration reached (relative residual {e.residual:.3g})",
                worst)

    def legend(self) -> tuple:
        """The legend of :meth:`_Painter.legend`, then one entry per open loop."""
        out = list(super().legend())
        if self.scene.submechanisms:
            out = [LegendEntry(e.kind, e.label, "one colour per independent sub-mechanism",
                               e.colours) if e.kind == "links" else e for e in out]
            at = next((i for i, e in enumerate(out) if e.kind == "links"), len(out))
            out[at + 1:at + 1] = [
                LegendEntry(f"sub:{sub.name}", f"[{k}] {sub.name}",
                            f"output {sub.output}: {a.dof} DOF, {a.motion_type}, singularity "
                            f"{SINGULARITY_WORDS.get(a.singularity, a.singularity)}",
                            (LEG_COLOURS[k % len(LEG_COLOURS)],))
                for k, (sub, a) in enumerate(self.scene.submechanisms)]
        for k, g in enumerate(self.scene.gaps):
            angle = "" if g.kind == "point" else f", {np.degrees(g.angle):.3g}°"
            out.append(LegendEntry(f"gap:{g.name}", f"gap of {g.name}",
                                   f"open loop: its frames {1e3 * g.distance:.3g} mm{angle} "
                                   "apart", (GAP_COLOURS[k % len(GAP_COLOURS)],)))
        return tuple(out)

    # ----------------------------------------------------------------------- tree
    def tree(self) -> None:
        """Skeleton bars and joint markers."""
        tree, r = self.tree_, self.size("link")
        for j in range(1, tree.njoints):
            parent = tree.parents[j]
            colour = GROUND_COLOUR if parent == 0 else self.colour(parent)
            self.bar(f"{self.root}/links/{node_name(tree.names[j])}", self.joint_origin(parent),
                     self.joint_origin(j), colour, r, kind="ground" if parent == 0 else "links")
            self.joint(j)
        for name, p, j in self.carried_frames():
            self.bar(f"{self.root}/links/{node_name(name)}", self.joint_origin(j), p,
                     self.colour(j), r, kind="ground" if j == 0 else "links")

    def joint(self, j: int) -> None:
        """A joint's marker: cylinder along a revolute axis, cube, or ball."""
        joint, name = self.tree_.joints[j], self.tree_.names[j]
        if joint.nv == 0 or joint.nv == 6:  # mimic or free flyer: no physical joint
            return
        actuated = name in self.mech.actuated
        colour = ACTUATED_SCREW_COLOUR if actuated else self.colour(j)
        self.note("actuated_joint" if actuated else "links", colour)
        node = self.vis[f"{self.root}/joints/{node_name(name)}"]
        c, s = self.joint_origin(j), self.size("joint")
        twist = self.kin.joint_twists[joint.idx_v]
        if joint.nv == 1 and np.linalg.norm(twist[:3]) > 0:
            u = twist[:3] / np.linalg.norm(twist[:3])
            node.set_object(self.g.Cylinder(1.0, s), self.material(colour))
            node.set_transform(_segment_matrix(c - 1.4 * s * u, c + 1.4 * s * u))
        elif joint.nv == 1:
            node.set_object(self.g.Box([2 * s] * 3), self.material(colour))
            node.set_transform(_translation(c))
        else:
            node.set_object(self.g.Sphere(1.2 * s), self.material(colour))
            node.set_transform(_translation(c))

    # ------------------------------------------------------------------- closures
    def loop_points(self, c) -> list[np.ndarray]:
        """Constraint point a, the joints up to the common ancestor and down to b's,
        constraint point b."""
        tree = self.tree_
        ja = tree.frames[tree.getFrameId(c.frame_a)].parentJoint
        jb = tree.frames[tree.getFrameId(c.frame_b)].parentJoint
        sa, sb = list(tree.supports[ja]), list(tree.supports[jb])
        m = next((k for k, (x, y) in enumerate(zip(sa, sb)) if x != y), min(len(sa), len(sb)))
        joints = sa[m - 1:][::-1] + sb[m:]
        return ([self.frame_point(c.frame_a, c.placement_a)]
                + [self.joint_origin(j) for j in joints]
                + [self.frame_point(c.frame_b, c.placement_b)])

    def closures(self) -> None:
        """Each loop's ring, its constraint-frame marker and the gap, if any."""
        for k, c in enumerate(self.model.closures):
            if not c.joins_frames:  # a coupling of joint coordinates: no loop to draw
                continue
            path = f"{self.root}/closures/{node_name(c.name or f'closure_{k}')}"
            self.note("closure", CLOSURE_COLOUR)
            pts = self.loop_points(c)
            for i, (a, b) in enumerate(zip(pts[:-1], pts[1:])):
                self.bar(f"{path}/ring/{i}", a, b, CLOSURE_COLOUR, 2.2 * self.size("link"),
                         opacity=0.45)
            self.vis[f"{path}/line"].set_object(self.g.LineLoop(
                self.g.PointsGeometry(np.array(pts, dtype=np.float32).T),
                self.g.LineBasicMaterial(color=CLOSURE_COLOUR, linewidth=2.0)))
            Ca = self.kin.frame_placements[self.tree_.getFrameId(c.frame_a)] * c.placement_a
            s = 1.6 * self.size("joint")
            marker = self.vis[f"{path}/marker"]
            if c.kind == "revolute":  # a disc across the common z axis
                z = Ca.rotation[:, 2]
                marker.set_object(self.g.Cylinder(1.0, 1.3 * s), self.material(CLOSURE_COLOUR))
                marker.set_transform(_segment_matrix(Ca.translation - 0.15 * s * z,
                                                     Ca.translation + 0.15 * s * z))
            else:
                shape = self.g.Sphere(s) if c.kind == "point" else self.g.Box([1.6 * s] * 3)
                marker.set_object(shape, self.material(CLOSURE_COLOUR, 0.8))
                T = Ca.homogeneous.copy() if c.kind == "weld" else _translation(Ca.translation)
                marker.set_transform(T)
            if self.scene.error is None:  # open: gaps() draws them in their colours
                self.bar(f"{path}/gap", pts[0], pts[-1], CLOSURE_COLOUR, self.size("link"))

    def gaps(self) -> None:
        """Each open loop: a bar and a line between its two constraint frames, in its
        own colour (its legend entry: :meth:`legend`)."""
        for k, g in enumerate(self.scene.gaps):
            colour = GAP_COLOURS[k % len(GAP_COLOURS)]
            path = f"{self.root}/gaps/{node_name(g.name)}"
            self.bar(f"{path}/bar", g.a, g.b, colour, 2.5 * self.size("link"))
            self.vis[f"{path}/line"].set_object(self.g.Line(
                self.g.PointsGeometry(np.array([g.a, g.b], dtype=np.float32).T),
                self.g.LineBasicMaterial(color=colour, linewidth=3.0)))

    # --------------------------------------------------------------------- output
    def output(self) -> None:
        """A ball at the output frame's origin; its axes for a body; the same for each
        sub-mechanism's output other than the whole's (``output/<k>/…``)."""
        self.output_frame(self.kin.output_placement, f"{self.root}/output",
                          self.model.output_point)
        for k, (sub, _) in enumerate(self.scene.submechanisms):
            if sub.output != self.mech.output:
                M = self.kin.frame_placements[self.tree_.getFrameId(sub.output)]
                self.output_frame(M, f"{self.root}/output/{k}", sub.model.output_point)

    def output_frame(self, M: pin.SE3, path: str, point: bool) -> None:
        """One output frame at ``M`` under ``path``: a ball, and its axes for a body."""
        self.note("output", PLATFORM_COLOUR)
        self.vis[f"{path}/ball"].set_object(self.g.Sphere(1.4 * self.size("anchor")),
                                            self.material(PLATFORM_COLOUR))
        self.vis[f"{path}/ball"].set_transform(_translation(M.translation))
        if point:
            return
        for axis, colour, label in zip(M.rotation.T, OUTPUT_AXIS_COLOURS, "xyz"):
            self.bar(f"{path}/{label}", M.translation,
                     M.translation + 0.25 * self.L * axis, colour, self.size("shaft"),
                     kind="output_axes")

    # ---------------------------------------------------------------------- idle
    def idle(self) -> None:
        """Each idle motion: the moving body's screw axis, or halos on moving joints."""
        tree = self.tree_
        for k, v in enumerate(idle_velocities(self.mech, self.scene.assembly.q)):
            path = f"{self.root}/idle/{k}"
            T = np.array([J @ v for J in self.kin.body_jacobians])
            size = np.linalg.norm(screws.homogenise(T, self.model.length), axis=1)
            bodies = [j for j in range(1, tree.njoints) if size[j] > 1e-9 * size.max()]
            if len(bodies) == 1:
                j = bodies[0]
                point, u = screws.axis(T[j], length=self.model.length)
                if np.isinf(screws.pitch(T[j], length=self.model.length)):
                    point = self.joint_origin(j)
                P = np.array(_body_points(self.model, self.kin, j))
                t = (P - point) @ u
                pad = 0.15 * max(float(np.ptp(t)), self.L)
                a, b = point + (t.min() - pad) * u, point + (t.max() + pad) * u
                self.bar(f"{path}/axis", a, b, IDLE_COLOUR, 1.8 * self.size("link"), kind="idle")
                continue
            x = v / self.model.velocity_units
            for j in range(1, tree.njoints):
                sl = slice(tree.joints[j].idx_v, tree.joints[j].idx_v + tree.joints[j].nv)
                if np.abs(x[sl]).max(initial=0.0) > 1e-9 * np.abs(x).max():
                    node = self.vis[f"{path}/joints/{node_name(tree.names[j])}"]
                    node.set_object(self.g.Sphere(2.2 * self.size("joint")),
                                    self.material(IDLE_COLOUR, 0.5))
                    self.note("idle", IDLE_COLOUR)
                    node.set_transform(_translation(self.joint_origin(j)))

    # ------------------------------------------------------------- screws, wrenches
    def screws(self) -> None:
        """The screw axis of every 1-DOF joint, centred at the joint."""
        tree, half = self.tree_, self.size("screw_half")
        for j in range(1, tree.njoints):
            joint = tree.joints[j]
            if joint.nv != 1:
                continue
            twist = self.kin.joint_twists[joint.idx_v]
            point, u = screws.axis(twist, length=self.model.length)
            centre = self.joint_origin(j)
            if np.isfinite(screws.pitch(twist, length=self.model.length)):
                centre = point + ((centre - point) @ u) * u
            actuated = tree.names[j] in self.mech.actuated
            colour = ACTUATED_SCREW_COLOUR if actuated else PASSIVE_SCREW_COLOUR
            self.bar(f"{self.root}/screws/{node_name(tree.names[j])}", centre - half * u,
                     centre + half * u, colour, self.size("screw"),
                     kind="actuated_axis" if actuated else "passive_axis")

    def wrenches(self) -> None:
        """Actuation wrenches (rows of ``A``) and the constraint wrenches on the output
        (a readable basis; forces only for a point output); for several sub-mechanisms,
        each one's on its own output (``constraint/<k>.<i>``)."""
        if not self.scene.submechanisms:
            self.output_wrenches(self.mech, self.scene.analysis, "")
            return
        for k, (sub, a) in enumerate(self.scene.submechanisms):
            self.centre_at = self.kin.frame_placements[
                self.tree_.getFrameId(sub.output)].translation
            self.output_wrenches(sub, a, f"{k}.")
        self.centre_at = None

    def output_wrenches(self, link: Linkage, analysis, tag: str) -> None:
        """The wrenches of one (sub-)mechanism's analysis on its output."""
        for name, w in zip(link.actuated, analysis.A):
            self.arrow(f"actuation/{node_name(name.replace('/', '.'))}", w,
                       ACTUATION_WRENCH_COLOUR, "actuation_wrench")
        basis = readable_basis(analysis.constraint_wrenches, self.centre(), self.model.length)
        for k, b in enumerate(basis):
            if not (link.model.output_point and b.kind == "couple"):
                self.arrow(f"constraint/{tag}{k}", b.screw, CONSTRAINT_WRENCH_COLOUR,
                           "constraint_wrench")
