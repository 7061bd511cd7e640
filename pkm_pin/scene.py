"""The meshcat scene of pkm_pin's views: colours and sizes, the in-memory
:class:`SceneRecorder` and its self-contained HTML page, the :class:`Scene`, and the
painter that draws a mechanism's legs, platform, screws, wrenches and animation in it.

:func:`pkm_pin.view.view` (mechanisms) and :func:`pkm_pin.view_linkage.view_linkage`
(general linkages) draw with it; its public names are importable from
:mod:`pkm_pin.view` as well. Scene layout and sizes: see :mod:`pkm_pin.view`.
"""

from __future__ import annotations

import base64
import html as html_lib
import os
import re
import tempfile
import warnings
import webbrowser
from pathlib import Path

import numpy as np
import pinocchio as pin

from . import screws
from .errors import AssemblyError, InputError, PkmError
from .report import readable_basis

#: Leg colours (0xRRGGBB), cycled, for legs whose URDF gives no material.
LEG_COLOURS = (0x377EB8, 0x4DAF4A, 0x17BECF, 0xA65628, 0xF781BF, 0xBCBD22)
PLATFORM_COLOUR = 0xFFB000
ACTUATED_SCREW_COLOUR = 0xFF7F00
PASSIVE_SCREW_COLOUR = 0x404040
ACTUATION_WRENCH_COLOUR = 0xE41A1C
CONSTRAINT_WRENCH_COLOUR = 0x984EA3

#: Sizes as fractions of the mechanism's characteristic length.
_SIZE = {
    "joint": 0.035, "link": 0.010, "anchor": 0.030, "screw_half": 0.25, "screw": 0.004,
    "arrow": 0.35, "shaft": 0.008, "head": 0.08, "head_radius": 0.025,
}
#: Animation: frames per cycle, frames per second, and the largest displacement along
#: the unit-homogenised uncontrolled twist ([rad], or characteristic lengths).
ANIMATION_FRAMES = 48
ANIMATION_FPS = 24
ANIMATION_AMPLITUDE = 0.12

_E_Y = np.array([0.0, 1.0, 0.0])


def _meshcat():
    """The meshcat modules, or a :class:`PkmError` that says how to install them."""
    try:
        with warnings.catch_warnings():  # meshcat imports pyzmq's deprecated ioloop
            warnings.simplefilter("ignore", DeprecationWarning)
            import meshcat
        import meshcat.animation
        import meshcat.geometry
        import umsgpack
        from meshcat.servers import tree
    except ImportError as e:
        raise PkmError(
            f"the viewer needs meshcat ({e}); install it with: pip install meshcat"
        ) from e
    return meshcat, meshcat.geometry, meshcat.animation, umsgpack, tree


def node_name(name: str) -> str:
    """A meshcat path element from a name: runs of characters other than letters, digits,
    ``.``, ``_`` and ``-`` become ``_`` (``"3-RPR (seed 000)"`` → ``"3-RPR_seed_000"``)."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("_") or "_"


# ------------------------------------------------------------------ scene recorder
class SceneRecorder:
    """A meshcat "window" that keeps the scene in memory instead of serving it.

    ``meshcat.Visualizer(window=SceneRecorder())`` draws without starting meshcat's
    server. Commands are stored in a scene tree exactly as ``meshcat-server`` stores
    them (one object, properties and transform per node; deleting a node drops its
    subtree), so :meth:`static_html` gives the page that ``Visualizer.static_html()``
    would fetch from the server.

    Args:
        forward: Another window (e.g. ``meshcat.Visualizer().window``, connected to a
            live server) that receives every command too.
    """

    def __init__(self, forward=None):
        _, _, _, self._umsgpack, self._tree = _meshcat()
        self.tree = self._tree.SceneTree()
        self.animation: bytes | None = None
        self.forward = forward

    def send(self, command) -> None:
        """Record one meshcat command (``SetObject``, ``SetTransform``, …)."""
        data = command.lower()
        kind = data["type"]
        path = [p for p in data.get("path", "").split("/") if p]
        packed = self._umsgpack.packb(data)
        if kind == "set_object":
            node = self._tree.find_node(self.tree, path)
            node.object, node.properties = packed, []
        elif kind == "set_transform":
            self._tree.find_node(self.tree, path).transform = packed
        elif kind == "set_property":
            self._tree.find_node(self.tree, path).properties.append(packed)
        elif kind == "set_animation":
            self.animation = packed
        elif kind == "delete":
            if path:
                parent = self._tree.find_node(self.tree, path[:-1])
                parent.pop(path[-1], None)
            else:
                self.tree = self._tree.SceneTree()
                self.animation = None
        if self.forward is not None:
            self.forward.send(command)

    def node(self, path: str):
        """The tree node at a meshcat path (``"/meshcat/pkm/…"``), or None."""
        node = self.tree
        for p in (p for p in path.split("/") if p):
            if p not in node:
                return None
            node = node[p]
        return node

    def commands(self) -> list[bytes]:
        """The packed commands that rebuild the scene: objects, properties and
        transforms node by node (parents first), then the animation."""
        out = []
        for node in self._tree.walk(self.tree):
            if node.object is not None:
                out.append(node.object)
            out.extend(node.properties)
            if node.transform is not None:
                out.append(node.transform)
        if self.animation is not None:
            out.append(self.animation)
        return out

    def static_html(self, title: str = "MeshCat") -> str:
        """A self-contained HTML page of the scene (no server, no network).

        Same page as meshcat's ``static_html()`` (the viewer's ``main.min.js`` inlined,
        then the commands), except that each command is decoded synchronously so that
        they run in order.
        """
        meshcat = _meshcat()[0]
        viewer_js = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
        calls = "\n".join(f'pkmRun("{base64.b64encode(c).decode("ascii")}");'
                          for c in self.commands())
        return _PAGE.format(title=html_lib.escape(title), viewer_js=viewer_js.read_text("utf-8"),
                            commands=calls)

    # a live window has these; the recorder has nothing to open or close
    def close(self) -> None:
        """Nothing to close (no server)."""

    def open(self):
        """Nothing to open: use :meth:`Scene.open`."""
        return self


_PAGE = """<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{title}</title></head>
<body>
<div id="meshcat-pane"></div>
<script>
{viewer_js}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
function pkmRun(b64) {{
  var s = atob(b64), a = new Uint8Array(s.length);
  for (var i = 0; i < s.length; i++) a[i] = s.charCodeAt(i);
  viewer.handle_command_bytearray(a);
}}
{commands}
</script>
<style>
body {{ margin: 0; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
</style>
<script id="embedded-json"></script>
</body>
</html>
"""


# ---------------------------------------------------------------------- the scene
class Scene:
    """A mechanism drawn in a meshcat scene (returned by :func:`pkm_pin.view.view`).

    Attributes:
        mechanism: The mechanism.
        assembly: The assembly drawn.
        analysis: Its :class:`~pkm_pin.analysis.Analysis`.
        visualizer: The ``meshcat.Visualizer`` drawn into.
        recorder: The :class:`SceneRecorder` holding the scene.
        root: Path of the mechanism's subtree, relative to the visualizer
            (``"pkm/<mechanism>"``).
        animated: Whether the scene holds the singularity animation.
    """

    def __init__(self, visualizer, recorder: SceneRecorder, analysis, root: str):
        self.visualizer = visualizer
        self.recorder = recorder
        self.analysis = analysis
        self.assembly = analysis.assembly
        self.mechanism = analysis.mechanism
        self.root = root
        self.animated = False

    def __repr__(self) -> str:
        return f"Scene({self.mechanism.name!r}, root={self.root!r}, animated={self.animated})"

    def _node(self, path: str):
        return self.recorder.node(self.visualizer.path.lower() + "/" + path)

    def children(self, path: str = "") -> list[str]:
        """Names of the child nodes of ``path`` (relative to :attr:`root`)."""
        node = self._node(f"{self.root}/{path}".rstrip("/"))
        return [] if node is None else list(node.keys())

    def paths(self) -> list[str]:
        """Paths (relative to the visualizer) of every node that holds an object."""
        start = self.visualizer.path.lower()
        node = self.recorder.node(start)
        out: list[str] = []

        def walk(n, prefix):
            for name, child in n.items():
                p = f"{prefix}/{name}" if prefix else name
                if child.object is not None:
                    out.append(p.removesuffix("/<object>"))
                walk(child, p)

        if node is not None:
            walk(node, "")
        return out

    def to_html(self, path: str | os.PathLike | None = None) -> str:
        """The self-contained HTML page of the scene; written to ``path`` when given."""
        page = self.recorder.static_html(title=f"pkm_pin: {self.mechanism.name}")
        if path is not None:
            Path(path).write_text(page, encoding="utf-8")
        return page

    def open(self) -> None:
        """Show the scene in a browser: the live viewer when there is one, else the
        static page written to a temporary file."""
        if self.recorder.forward is not None:
            self.visualizer.open()
            return
        _open_page(self.to_html(), "pkm_pin_")


# ------------------------------------------------------------------------ drawing
def _rotation_y_to(u: np.ndarray) -> np.ndarray:
    """A rotation matrix taking the y axis (three.js cylinders' axis) to unit ``u``."""
    return pin.Quaternion.FromTwoVectors(_E_Y, u).matrix()


def _segment_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """4×4 transform of a unit-height y-cylinder stretched from ``a`` to ``b``."""
    d = b - a
    n = float(np.linalg.norm(d))
    T = np.eye(4)
    T[:3, :3] = _rotation_y_to(d / n) @ np.diag([1.0, n, 1.0])
    T[:3, 3] = 0.5 * (a + b)
    return T


def grid_scale(length: float) -> float:
    """Scale of meshcat's grid and axes for a mechanism of characteristic length
    ``length``: the power of ten at or below it (1 for a metre-sized model in metres,
    1000 for the same in millimetres, 0.1 for a 30 cm model)."""
    return float(10.0 ** np.floor(np.log10(length)))


def _open_page(page: str, prefix: str) -> None:
    """The HTML ``page`` written to a temporary file and opened in the browser."""
    fd, name = tempfile.mkstemp(prefix=prefix, suffix=".html")
    os.close(fd)
    Path(name).write_text(page, encoding="utf-8")
    webbrowser.open(Path(name).as_uri(), new=2)


def _translation(p) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = p
    return T


class _Painter:
    """Draws one scene; sizes relative to the mechanism's characteristic length."""

    def __init__(self, scene: Scene):
        _, self.g, self.anim, _, _ = _meshcat()
        self.scene = scene
        self.vis = scene.visualizer
        self.mech = scene.mechanism
        self.L = self.mech.characteristic_length
        self.root = scene.root
        self.legs_drawn: list[dict] = []

    def size(self, key: str) -> float:
        return _SIZE[key] * self.L

    def centre(self) -> np.ndarray:
        """The point wrench arrows start nearest to: the platform origin."""
        return self.scene.assembly.pose.translation

    def material(self, colour: int, opacity: float = 1.0):
        return self.g.MeshPhongMaterial(color=colour, opacity=opacity,
                                        transparent=opacity < 1.0)

    # ------------------------------------------------------------- view settings
    def settings(self) -> None:
        """Light grey background, and the view centred on the mechanism.

        meshcat's camera always looks at the viewer's origin, so the mechanism's subtree
        is shifted to put its centre there; the grid and axes are shifted with it (they
        stay at the mechanism's world origin), and scaled by :func:`grid_scale`.
        """
        vis = self.vis
        vis["/Background"].set_property("top_color", [0.97, 0.97, 0.97])
        vis["/Background"].set_property("bottom_color", [0.80, 0.80, 0.82])
        P = self.mech_points()
        centre = 0.5 * (P.min(axis=0) + P.max(axis=0))
        radius = max(float(np.max(np.linalg.norm(P - centre, axis=1))), 0.5 * self.L)
        vis[self.root].set_transform(_translation(-centre))
        # meshcat's grid (0.5 unit cells) and axes (1 unit) at the model's scale: a power
        # of ten of its characteristic length (a millimetre model gets 1000× larger ones)
        scale = np.diag([*[grid_scale(self.L)] * 3, 1.0])
        for path in ("/Grid", "/Axes"):
            vis[path].set_transform(_translation(-centre) @ scale)
        direction = np.array([1.0, -1.4, 0.9])
        _, sv, Vt = np.linalg.svd(P - P.mean(axis=0))
        if sv[0] > 0 and sv[-1] < 0.15 * sv[0]:  # nearly planar: look along the normal
            normal = Vt[-1] if Vt[-1] @ direction > 0 else -Vt[-1]
            direction = normal + 0.45 * direction / np.linalg.norm(direction)
        offset = 2.7 * radius * direction / np.linalg.norm(direction)
        camera = self.g.PerspectiveCamera(fov=50, aspect=1, near=0.01 * radius,
                                          far=200 * radius)
        vis["/Cameras/default/rotated"].set_object(camera)
        # the camera node is rotated so that its y axis (three.js "up") is the world z
        vis["/Cameras/default/rotated/<object>"].set_property(
            "position", [float(offset[0]), float(offset[2]), float(-offset[1])])

    def mech_points(self) -> np.ndarray:
        """World points that the view must frame: joints, tips and anchors."""
        pts = []
        for leg, q in zip(self.mech.legs, self.scene.assembly.leg_q):
            pts.append(leg.base.translation[None])
            pts.append(leg.joint_origins(q))
            pts.append(leg.tip_placement(q).translation[None])
        return np.vstack(pts)

    # ----------------------------------------------------------------------- legs
    def legs(self) -> None:
        for i, (leg, q) in enumerate(zip(self.mech.legs, self.scene.assembly.leg_q)):
            colour = LEG_COLOURS[i % len(LEG_COLOURS)]
            path = f"{self.root}/legs/{node_name(leg.name)}"
            self.vis[path].set_transform(leg.base.homogeneous)
            drawn = {"leg": leg, "path": path, "viz": self.leg_visuals(leg, path, colour)}
            points = self.leg_points(leg, q)
            drawn["links"] = [k for k in range(len(points) - 1)
                              if np.linalg.norm(points[k + 1] - points[k]) > 1e-9 * self.L]
            for k in drawn["links"]:
                self.vis[f"{path}/links/{k}"].set_object(
                    self.g.Cylinder(1.0, self.size("link")), self.material(colour))
            drawn["spheres"] = drawn["viz"] is None
            if drawn["spheres"]:
                for k in range(len(points)):
                    self.vis[f"{path}/joints/{k}"].set_object(
                        self.g.Sphere(self.size("joint")), self.material(colour))
            self.legs_drawn.append(drawn)
            self.pose_leg(self.vis, drawn, q)

    def leg_visuals(self, leg, path: str, colour: int):
        """Pinocchio's MeshcatVisualizer of the leg's URDF visuals; None when it has none
        or they cannot be loaded (a warning says why; the leg then gets spheres).

        Mesh paths (``package://…`` or relative) are searched in the URDF's folder and
        every folder above it (and in ``ROS_PACKAGE_PATH``, as Pinocchio does).
        """
        if not leg.xml or "<visual" not in leg.xml:
            return None
        from pinocchio.visualize import MeshcatVisualizer

        src = Path(leg.source)
        dirs = [str(d) for d in [src.parent, *src.parent.parents]] if src.is_file() else []
        try:
            geom = pin.buildGeomFromUrdfString(leg.model, leg.xml, pin.GeometryType.VISUAL,
                                               package_dirs=dirs)
        except (RuntimeError, ValueError) as e:
            warnings.warn(f"leg {leg.name!r}: the URDF visuals of {leg.source} cannot be "
                          f"loaded ({e}); drawing spheres and links instead", stacklevel=4)
            return None
        if geom.ngeoms == 0:
            return None
        viz = MeshcatVisualizer(leg.model, None, geom)
        viz.initViewer(viewer=self.vis)
        rgba = None
        if "<material" not in leg.xml:
            rgba = _rgb(colour) + [1.0]
        viz.loadViewerModel(rootNodeName=path, visual_color=rgba)
        return viz

    def leg_points(self, leg, q) -> np.ndarray:
        """Root, joint origins and tip of a leg, in the leg's root frame."""
        data = leg.data  # this thread's
        pin.framesForwardKinematics(leg.model, data, q)
        return np.vstack([np.zeros(3)]
                         + [data.oMi[j].translation for j in range(1, leg.model.njoints)]
                         + [data.oMf[leg.tip_id].translation])

    def pose_leg(self, target, drawn: dict, q) -> None:
        """Place a leg's nodes at ``q`` in ``target`` (the visualizer or an animation
        frame)."""
        leg = drawn["leg"]
        viz = drawn["viz"]
        if viz is not None:
            viewer, viz.viewer = viz.viewer, target
            try:
                viz.display(q)
            finally:
                viz.viewer = viewer
        points = self.leg_points(leg, q)
        animated = target is not self.vis
        for k in drawn["links"]:
            a, b = points[k], points[k + 1]
            node = target[f"{drawn['path']}/links/{k}"]
            if animated:  # animation frames keep position and rotation: scale on its own
                n = float(np.linalg.norm(b - a))
                node.set_transform(_segment_matrix(a, b) @ np.diag([1.0, 1.0 / n, 1.0, 1.0]))
                node.set_property("scale", "vector3", [1.0, n, 1.0])
            else:
                node.set_transform(_segment_matrix(a, b))
        if drawn["spheres"]:
            for k, p in enumerate(points):
                target[f"{drawn['path']}/joints/{k}"].set_transform(_translation(p))

    # ------------------------------------------------------------------ platform
    def platform(self) -> None:
        path = f"{self.root}/platform"
        self.vis[path].set_transform(self.scene.assembly.pose.homogeneous)
        pts = np.array([a.translation for a in self.mech.anchors])
        for leg, p in zip(self.mech.legs, pts):
            self.vis[f"{path}/anchors/{node_name(leg.name)}"].set_object(
                self.g.Sphere(self.size("anchor")), self.material(PLATFORM_COLOUR))
            self.vis[f"{path}/anchors/{node_name(leg.name)}"].set_transform(_translation(p))
        faces = _polygon_faces(pts, 1e-6 * self.L)
        if faces is not None:
            self.vis[f"{path}/body"].set_object(
                self.g.TriangularMeshGeometry(pts, faces), self.material(PLATFORM_COLOUR, 0.55))
        else:  # fewer than 3 anchors or all on a line: a hub and spokes
            self.vis[f"{path}/body"].set_object(self.g.Sphere(2 * self.size("anchor")),
                                                self.material(PLATFORM_COLOUR))
            for k, p in enumerate(pts):
                if np.linalg.norm(p) > 1e-9 * self.L:
                    self.vis[f"{path}/spokes/{k}"].set_object(
                        self.g.Cylinder(1.0, self.size("link")), self.material(PLATFORM_COLOUR))
                    self.vis[f"{path}/spokes/{k}"].set_transform(_segment_matrix(np.zeros(3), p))

    # -------------------------------------------------------------------- screws
    def screws(self) -> None:
        analysis = self.scene.analysis
        half = self.size("screw_half")
        for leg, q, ls in zip(self.mech.legs, self.scene.assembly.leg_q, analysis.legs):
            origins = leg.joint_origins(q)
            names = _velocity_names(leg.model)
            for k, name in enumerate(names):
                twist = ls.jacobian[:, k]
                if not np.any(twist):
                    continue
                joint = _joint_of_column(leg.model, k)
                centre = origins[joint - 1]
                point, u = screws.axis(twist, length=self.L)
                if np.isfinite(screws.pitch(twist, length=self.L)):
                    centre = point + ((centre - point) @ u) * u
                colour = ACTUATED_SCREW_COLOUR if k in leg.actuated_v else PASSIVE_SCREW_COLOUR
                node = self.vis[f"{self.root}/screws/{node_name(leg.name)}/{node_name(name)}"]
                node.set_object(self.g.Cylinder(1.0, self.size("screw")), self.material(colour))
                node.set_transform(_segment_matrix(centre - half * u, centre + half * u))

    # ------------------------------------------------------------------- wrenches
    def wrenches(self) -> None:
        analysis = self.scene.analysis
        for name, w in zip(self.mech.actuated_names, analysis.A):
            self.arrow(f"actuation/{node_name(name.replace('/', '.'))}", w,
                       ACTUATION_WRENCH_COLOUR)
        centre = self.scene.assembly.pose.translation
        basis = readable_basis(analysis.constraint_wrenches, centre, self.L)
        for k, w in enumerate(b.screw for b in basis):
            self.arrow(f"constraint/{k}", w, CONSTRAINT_WRENCH_COLOUR)

    def arrow(self, name: str, wrench: np.ndarray, colour: int) -> None:
        """An arrow along a wrench's axis (a double arrow for a couple)."""
        if not np.any(wrench):
            return
        c = self.centre()
        point, u = screws.axis(wrench, length=self.L)
        couple = np.isinf(screws.pitch(wrench, length=self.L))
        length, head = self.size("arrow"), self.size("head")
        if couple:
            tail = c - 0.5 * length * u
        else:
            tail = point + ((c - point) @ u) * u
        path = f"{self.root}/wrenches/{name}"
        T = np.eye(4)
        T[:3, :3] = _rotation_y_to(u)
        T[:3, 3] = tail
        self.vis[path].set_transform(T)
        start = head if couple else 0.0
        self.vis[f"{path}/shaft"].set_object(
            self.g.Cylinder(length - head - start, self.size("shaft")), self.material(colour))
        self.vis[f"{path}/shaft"].set_transform(
            _translation([0.0, 0.5 * (start + length - head), 0.0]))
        cone = self.g.Cylinder(head, radiusTop=0.0, radiusBottom=self.size("head_radius"))
        self.vis[f"{path}/head"].set_object(cone, self.material(colour))
        self.vis[f"{path}/head"].set_transform(_translation([0.0, length - 0.5 * head, 0.0]))
        if couple:
            back = np.diag([1.0, -1.0, -1.0, 1.0])  # rotated by π about x: points along -y
            back[1, 3] = 0.5 * head
            self.vis[f"{path}/tail"].set_object(cone, self.material(colour))
            self.vis[f"{path}/tail"].set_transform(back)

    # ------------------------------------------------------------------ animation
    def animate(self, twist: np.ndarray) -> None:
        """Platform and legs moving back and forth along ``twist`` (unit-homogenised)."""
        assembly = self.scene.assembly
        animation = self.anim.Animation(default_framerate=ANIMATION_FPS)
        previous = assembly
        for k in range(ANIMATION_FRAMES + 1):
            s = ANIMATION_AMPLITUDE * np.sin(2 * np.pi * k / ANIMATION_FRAMES)
            pose = screws.exp(s * twist) * assembly.pose
            leg_q = self.follow(pose, previous, s * twist)
            previous = leg_q
            frame = animation.at_frame(self.vis, k)
            frame[f"{self.root}/platform"].set_transform(pose.homogeneous)
            for drawn, q in zip(self.legs_drawn, leg_q):
                self.pose_leg(frame, drawn, q)
        self.vis.set_animation(animation, play=True, repetitions=1_000_000)

    def follow(self, pose: pin.SE3, previous, displacement: np.ndarray) -> list[np.ndarray]:
        """Leg configurations at ``pose``: re-assembled from the previous frame, or, when
        a leg cannot reach it, the first-order passive motion from the drawn assembly."""
        try:
            return self.mech.assemble(pose, guess=previous).leg_q
        except AssemblyError:
            rates = self.scene.analysis.passive_rates(displacement)
            return [pin.integrate(leg.model, q, qd)
                    for leg, q, qd in zip(self.mech.legs, self.scene.assembly.leg_q, rates)]


def _velocity_names(model: pin.Model) -> list[str]:
    """One name per velocity coordinate: the joint's, suffixed for multi-DOF joints."""
    names = []
    for j in range(1, model.njoints):
        nv = model.joints[j].nv
        names += [model.names[j]] if nv == 1 else [f"{model.names[j]}_{i}" for i in range(nv)]
    return names


def _joint_of_column(model: pin.Model, k: int) -> int:
    for j in range(1, model.njoints):
        jm = model.joints[j]
        if jm.nv > 0 and jm.idx_v <= k < jm.idx_v + jm.nv:
            return j
    raise InputError(f"no joint has velocity index {k}")


def _polygon_faces(pts: np.ndarray, tol: float) -> np.ndarray | None:
    """Triangles of the convex polygon (planar points) or convex hull through ``pts``;
    None when they span less than a plane."""
    if len(pts) < 3:
        return None
    centred = pts - pts.mean(axis=0)
    _, sv, Vt = np.linalg.svd(centred)
    if sv[1] <= tol:
        return None
    if len(pts) > 3 and sv[2] > tol:
        from scipy.spatial import ConvexHull

        return ConvexHull(pts).simplices.astype(np.uint32)
    xy = centred @ Vt[:2].T
    from scipy.spatial import ConvexHull

    ring = ConvexHull(xy).vertices if len(pts) > 3 else np.arange(3)
    return np.array([[ring[0], ring[i], ring[i + 1]] for i in range(1, len(ring) - 1)],
                    dtype=np.uint32)


def _hex_colour(colour: str) -> int:
    """``"#rrggbb"`` as meshcat's 0xRRGGBB."""
    return int(colour.lstrip("#"), 16)


def _rgb(colour: int) -> list[float]:
    """0xRRGGBB as three fractions."""
    return [((colour >> s) & 0xFF) / 255.0 for s in (16, 8, 0)]
