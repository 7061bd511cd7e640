"""Browser preview of a mechanism: a meshcat scene and its self-contained HTML page.

:func:`view` draws, in one meshcat scene:

* every leg: its URDF visuals through Pinocchio's ``MeshcatVisualizer``, meshes
  included (a leg whose URDF has no visual, or whose meshes cannot be found, gets a
  sphere at each joint instead, with a warning in the second case), plus thin cylinders
  from joint to joint (the kinematic skeleton, which also shows prismatic joints);
* the platform: a translucent polygon (or convex hull) through the anchors, with a
  sphere at each anchor;
* the joint screw axes (columns of each leg's Jacobian) as thin lines centred at the
  point of the axis nearest to the joint; a prismatic joint (a couple, infinite pitch)
  is drawn along its direction through the joint;
* the actuation wrenches (rows of :attr:`Analysis.A`) and the constraint wrenches (a
  basis of :attr:`Analysis.constraint_wrenches` with the couples split off, see
  :func:`pkm_pin.report.readable_basis`) as arrows of fixed length along the wrench
  axis, starting at the point of the axis nearest to the platform origin; a pure
  couple is a double-headed arrow through the platform origin. Only the axis is
  drawn: arrow lengths are not magnitudes, pitches are not shown;
* at a type II or III singularity, an animation that moves the platform back and forth
  along :attr:`Analysis.uncontrolled_twist` (the legs follow by re-assembly).

The page explains itself: over its top left corner, a title (the mechanism's name; the
platform pose, xyz and roll-pitch-yaw in degrees; DOF, motion type and singularity class,
from the analysis drawn: :attr:`Scene.title_lines`) and a legend with one entry per kind
of object actually drawn, in the colours it was drawn with (:attr:`Scene.legend`; the
painter notes each colour as it draws, so the legend cannot disagree with the picture).
A live viewer's page takes no HTML: it gets the same title and legend as an image card
that rides on the default camera (:func:`pkm_pin.scene.draw_legend_card`).

The default camera looks at the centre of the bounding box of what is drawn (joints,
ends of the screw axes and arrows) obliquely from above (:data:`scene.CAMERA_DIRECTION
<pkm_pin.scene.CAMERA_DIRECTION>`, rather across the plane of a planar mechanism, never
less than 25° above the ground plane), from the least distance that shows every point
(:func:`pkm_pin.scene.camera_placement`, kept in :attr:`Scene.camera`).

Nothing needs a server: by default the commands go to a :class:`SceneRecorder`, an
in-memory stand-in for meshcat's server that keeps the scene tree the way the server
does, and :meth:`Scene.to_html` writes the page that meshcat's ``static_html()`` would
give (three.js and the viewer inlined, every command embedded), which opens from a file
with no network. Pass ``visualizer=meshcat.Visualizer()`` to draw into a live viewer as
well.

Scene layout (meshcat paths under ``/meshcat``; ``<m>`` is :func:`node_name` of the
mechanism name)::

    pkm/<m>                               world frame, shifted (see below)
    pkm/<m>/legs/<leg>                    leg root, placed at leg.base
    pkm/<m>/legs/<leg>/visuals/<geom>     URDF visuals (Pinocchio's MeshcatVisualizer)
    pkm/<m>/legs/<leg>/links/<k>          skeleton cylinders
    pkm/<m>/legs/<leg>/joints/<k>         joint spheres (legs without URDF visuals)
    pkm/<m>/platform                      platform frame, placed at the pose
    pkm/<m>/platform/body, anchors/<leg>
    pkm/<m>/screws/<leg>/<joint>          joint screw axes (world frame)
    pkm/<m>/wrenches/actuation/<leg>.<joint>
    pkm/<m>/wrenches/constraint/<k>

meshcat's camera orbits about the viewer's origin, so ``pkm/<m>`` is translated to bring
the centre of the drawing there; meshcat's axes get the same translation, so they still
mark the mechanism's world origin (scaled by :func:`grid_scale`); its grid is scaled to
the drawing (cells of :func:`pkm_pin.scene.grid_cell`, 1, 2 or 5 × a power of ten, given
in the legend) and lies in the plane z = 0, or under the drawing when it reaches below
(:func:`pkm_pin.scene.frame_view`). Sizes are fractions of
:attr:`Mechanism.characteristic_length`, so a mechanism in millimetres looks the same as
in metres.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .errors import InputError
from .mechanism import Assembly, Mechanism, as_pose
from .scene import (
    ACTUATED_SCREW_COLOUR,
    ACTUATION_WRENCH_COLOUR,
    ANIMATION_AMPLITUDE,
    ANIMATION_FPS,
    ANIMATION_FRAMES,
    CONSTRAINT_WRENCH_COLOUR,
    LEG_COLOURS,
    PASSIVE_SCREW_COLOUR,
    PLATFORM_COLOUR,
    LegendEntry,
    Scene,
    SceneRecorder,
    _hex_colour,
    _meshcat,
    _open_page,
    _Painter,
    _rgb,
    _translation,
    draw_legend_card,
    frame_view,
    grid_scale,
    node_name,
)
from .workspace import KIND_COLOURS

#: The legend's words for the workspace cloud's kinds (colours: ``KIND_COLOURS``) and
#: for its home marker (:data:`HOME_COLOUR`).
WORKSPACE_LEGEND_TEXT = {
    "reachable": ("reachable", "the platform assembles"),
    "singularity-free": ("singularity-free", "reachable, no singularity"),
    "transmission": ("good transmission", "singularity-free, transmission above the "
                     "threshold"),
    "home": ("home", "the home pose"),
}
HOME_COLOUR = 0x000000

#: The scene's names (:mod:`pkm_pin.scene`) are importable from here too.
__all__ = ["ACTUATED_SCREW_COLOUR", "ACTUATION_WRENCH_COLOUR", "ANIMATION_AMPLITUDE",
           "ANIMATION_FPS", "ANIMATION_FRAMES", "CONSTRAINT_WRENCH_COLOUR", "HOME_COLOUR",
           "LEG_COLOURS", "PASSIVE_SCREW_COLOUR", "PLATFORM_COLOUR", "WORKSPACE_LEGEND_TEXT",
           "LegendEntry", "Scene", "SceneRecorder", "grid_scale", "node_name", "view",
           "workspace_cloud"]


def view(
    mech: Mechanism,
    pose_or_assembly=None,
    *,
    visualizer=None,
    open: bool = False,  # noqa: A002 - the name meshcat and Pinocchio use
    html: str | os.PathLike | None = None,
    show_screws: bool = True,
    show_wrenches: bool = True,
    animate_singular: bool = True,
    source: str | None = None,
) -> Scene:
    """Draw a mechanism at a pose or assembly in a meshcat scene (see the module doc).

    Args:
        mech: The mechanism (a :class:`~pkm_pin.linkage.Linkage` is drawn by
            :func:`pkm_pin.view_linkage.view_linkage`).
        pose_or_assembly: An :class:`~pkm_pin.mechanism.Assembly`, or a platform pose
            (``pin.SE3``, 4×4 matrix or x, y, z, roll, pitch, yaw) to assemble at;
            default: the home assembly.
        visualizer: A ``meshcat.Visualizer`` (e.g. connected to a running server) that
            receives the scene too; default: none, nothing is started.
        open: Open the scene in a browser.
        html: Write the self-contained HTML page to this file.
        show_screws: Draw the joint screw axes.
        show_wrenches: Draw the actuation and constraint wrenches.
        animate_singular: At a type II/III singularity, animate the platform along the
            uncontrolled twist.
        source: The file (or shipped model name) the mechanism was read from: named
            in the title after the mechanism's name (:attr:`Scene.source`).

    Raises:
        InputError: ``mech`` is not a mechanism or the pose is malformed.
        AssemblyError: the mechanism does not assemble at the pose given.
    """
    if getattr(mech, "backend", None) == "general":  # pkm_pin.view_linkage
        from .view_linkage import view_linkage

        return view_linkage(mech.general, pose_or_assembly, visualizer=visualizer, open=open,
                            html=html, show_screws=show_screws, show_wrenches=show_wrenches,
                            source=source)
    if not isinstance(mech, Mechanism):
        raise InputError(f"view() takes a pkm_pin.Mechanism or a Linkage, got "
                         f"{type(mech).__name__}")
    analysis = mech.analyze(_assembly_of(mech, pose_or_assembly))
    meshcat = _meshcat()[0]
    recorder = SceneRecorder(forward=None if visualizer is None else visualizer.window)
    vis = meshcat.Visualizer(window=recorder)
    if visualizer is not None:
        vis.path = visualizer.path
    scene = Scene(vis, recorder, analysis, f"pkm/{node_name(mech.name)}")
    scene.source = source
    _paint(scene, analysis, show_screws, show_wrenches, animate_singular)
    if html is not None:
        scene.to_html(html)
    if open:
        scene.open()
    return scene


def _assembly_of(mech: Mechanism, pose_or_assembly) -> Assembly:
    """The assembly :func:`view` draws: home (``None``), an :class:`Assembly` of ``mech``,
    or the assembly at a pose."""
    if pose_or_assembly is None:
        return mech.home_assembly
    if isinstance(pose_or_assembly, Assembly):
        if pose_or_assembly.mechanism not in (mech, mech.__dict__.get("general")):
            raise InputError("the assembly given belongs to another mechanism")
        return mech._per_leg(pose_or_assembly)
    return mech.assemble(as_pose(pose_or_assembly))


def _paint(scene: Scene, analysis, show_screws: bool, show_wrenches: bool,
           animate_singular: bool) -> None:
    """Legs, platform, the screw and wrench layers asked for, the settings, and at a type
    II/III singularity the uncontrolled motion (``scene.animated``)."""
    painter = _Painter(scene)
    painter.legs()
    painter.platform()
    if show_screws:
        painter.screws()
    if show_wrenches:
        painter.wrenches()
    painter.settings()
    if animate_singular and analysis.singularity in ("II", "III") \
            and analysis.uncontrolled_twist is not None:
        painter.animate(analysis.uncontrolled_twist)
        scene.animated = True
    painter.finish()


# --------------------------------------------------------------- workspace cloud
def workspace_cloud(ws, *, html: str | os.PathLike | None = None, visualizer=None,
                    open: bool = False, surfaces: bool = True) -> SceneRecorder:  # noqa: A002
    """A meshcat point cloud of a :class:`~pkm_pin.workspace.Workspace`: one point per
    sample in it, coloured by the smallest kind it belongs to (reachable,
    singularity-free, good transmission), one node per kind
    (``pkm/workspace/<kind>``) so each can be hidden in the viewer's controls. Two
    coordinates are drawn in a plane (the third at 0); the point size is the cell size.
    The page has a title and a legend of the kinds drawn and the home marker
    (:data:`WORKSPACE_LEGEND_TEXT`; ``recorder.title_lines``, ``recorder.legend``), and
    the camera and grid of :func:`pkm_pin.scene.frame_view` on the sampled box.

    With ``surfaces`` and a 3-D grid, each kind's boundary is drawn too, as a
    translucent triangle mesh of its cells' exposed faces
    (:func:`pkm_pin.workspace.voxel_surface`, exact for the cells;
    ``pkm/workspace/<kind>_surface``).

    Returns:
        The :class:`SceneRecorder` holding the scene (``static_html()``); ``html``:
        the page is written there.
    """
    meshcat, g = _meshcat()[:2]
    recorder = SceneRecorder(forward=None if visualizer is None else visualizer.window)
    vis = meshcat.Visualizer(window=recorder)
    P = np.zeros((len(ws.points), 3))
    P[:, :len(ws.coords)] = ws.points
    drawn: dict[str, int] = {}
    span = float(np.max(ws.bounds[:, 1] - ws.bounds[:, 0]))
    size = float(np.min(ws.spacing)) if len(ws.points) else span / 100
    codes, kinds = ws.smallest_kind()
    smallest = codes.ravel()
    root = vis["pkm"]["workspace"]
    corners = np.zeros((2, 3))
    corners[:, :len(ws.coords)] = ws.bounds.T
    framing = frame_view(vis, "pkm/workspace", corners, span)
    for i, k in enumerate(kinds):
        pts = P[smallest == i]
        if not len(pts):
            continue
        colour = np.tile(np.array(_rgb(_hex_colour(KIND_COLOURS[k])))[:, None],
                         (1, len(pts)))
        root[node_name(k)].set_object(g.PointCloud(pts.T.astype(np.float32),
                                                   colour.astype(np.float32), size=size))
        drawn[k] = _hex_colour(KIND_COLOURS[k])
    if surfaces and ws.sampling == "grid" and len(ws.coords) == 3:
        drawn.update(_workspace_surfaces(ws, root, g, kinds))
    home = np.zeros(3)
    home[:len(ws.coords)] = ws.home
    root["home"].set_object(g.Sphere(0.6 * size), g.MeshLambertMaterial(color=HOME_COLOUR))
    root["home"].set_transform(_translation(home))
    drawn["home"] = HOME_COLOUR
    coords = ", ".join(f"{c} [{u}]" for c, u in zip(ws.coords, ws.units))
    recorder.title_lines = (f"workspace of {ws.mechanism}",
                            f"{coords}: {len(ws.points)} {ws.sampling} samples",
                            "each sample in the colour of the smallest set it is in")
    recorder.legend = tuple(LegendEntry(k, *WORKSPACE_LEGEND_TEXT[k], (drawn[k],))
                            for k in WORKSPACE_LEGEND_TEXT if k in drawn)
    if visualizer is not None:
        draw_legend_card(vis, recorder.title_lines, recorder.legend, framing["radius"])
    if html is not None:
        Path(html).write_text(recorder.static_html(title=f"pkm_pin workspace: {ws.mechanism}"),
                              encoding="utf-8")
    if open:
        _open_page(recorder.static_html(), "pkm_pin_ws_")
    return recorder


def _workspace_surfaces(ws, root, g, kinds) -> dict[str, int]:
    """Each kind's voxel boundary mesh under ``root`` (translucent, its cloud's colour;
    the larger kinds more transparent so the smaller ones show through); the colour of
    each kind drawn."""
    from .workspace import voxel_surface

    drawn: dict[str, int] = {}
    for i, k in enumerate(kinds):
        vertices, faces = voxel_surface(ws.masks[k], ws.bounds)
        if not len(faces):
            continue
        drawn[k] = _hex_colour(KIND_COLOURS[k])
        material = g.MeshLambertMaterial(color=_hex_colour(KIND_COLOURS[k]), transparent=True,
                                         opacity=0.25 + 0.2 * i)
        root[node_name(f"{k}_surface")].set_object(
            g.TriangularMeshGeometry(vertices.astype(np.float32),
                                     faces.astype(np.uint32)), material)
    return drawn
