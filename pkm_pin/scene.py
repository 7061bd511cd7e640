"""The meshcat scene of pkm_pin's views: colours and sizes, the in-memory
:class:`SceneRecorder` and its self-contained HTML page, the :class:`Scene`, and the
painter that draws a mechanism's legs, platform, screws, wrenches and animation in it;
the page's title and legend (:func:`overlay_html`, or for a live viewer
:func:`draw_legend_card`) from what the painter noted drawing (:data:`LEGEND_TEXT`), and
the default camera and grid framing the drawing (:func:`frame_view`).

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
from dataclasses import dataclass
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

#: The legend's words for each kind of object a painter draws: kind → (label, what it
#: shows). The order is the legend's; the colours are those the painter drew with
#: (:meth:`_Painter.note`), so they are never written twice.
LEGEND_TEXT = {
    "legs": ("legs", "links and joints, one colour per leg"),
    "ground": ("ground", "bars from the world origin"),
    "links": ("links and joints", "one colour per branch"),
    "actuated_joint": ("actuated joint", "driven by an actuator"),
    "platform": ("platform", "the moving platform and its anchors"),
    "output": ("output frame", "its origin"),
    "output_axes": ("output axes", "x, y, z of the output frame"),
    "closure": ("loop closure", "ring along each closed loop"),
    "idle": ("idle axis", "idle motion: moves with every actuator locked"),
    "actuated_axis": ("actuated joint axis", "screw axis"),
    "passive_axis": ("passive joint axis", "screw axis"),
    "actuation_wrench": ("actuation wrench", "axis of an actuator's wrench on the output; "
                         "double head: a couple (or an axis far beyond the drawing)"),
    "constraint_wrench": ("constraint wrench", "axis of a wrench the constraints exert; "
                          "double head: a couple (or an axis far beyond the drawing)"),
}

#: The singularity classes in words, for the title.
SINGULARITY_WORDS = {"none": "none", "I": "type I (serial)", "II": "type II (parallel)",
                     "III": "type III (serial and parallel)"}

#: Sizes as fractions of the mechanism's characteristic length.
_SIZE = {
    "joint": 0.035, "link": 0.010, "anchor": 0.030, "screw_half": 0.25, "screw": 0.004,
    "arrow": 0.35, "shaft": 0.008, "head": 0.08, "head_radius": 0.025,
}
#: Animation: frames per cycle, frames per second, and the largest displacement along
#: the unit-homogenised uncontrolled twist ([rad], or characteristic lengths).
#: A wrench axis farther than this many drawing lengths from the arrows' centre is drawn
#: as a couple (:meth:`_Painter.arrow`).
FAR_AXIS = 3.0
ANIMATION_FRAMES = 48
ANIMATION_FPS = 24
ANIMATION_AMPLITUDE = 0.12

_E_Y = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class LegendEntry:
    """One line of a scene's legend: a kind of object drawn, in the colours drawn.

    Attributes:
        kind: Key of :data:`LEGEND_TEXT` (or a workspace kind).
        label: What it is, in two or three words.
        note: What it shows, in a few more.
        colours: The colours (0xRRGGBB) it is drawn in, in order of first use.
    """

    kind: str
    label: str
    note: str
    colours: tuple[int, ...]


def css_colour(colour: int) -> str:
    """0xRRGGBB as CSS ``#rrggbb``."""
    return f"#{colour:06x}"


def overlay_html(title_lines, legend) -> str:
    """The page's overlay: the title lines (the first one bold) in the top left corner,
    and the legend, one swatch per colour of each :class:`LegendEntry`, in the bottom
    left one (the corners of a centred drawing are the emptiest). Empty when there is
    neither."""
    title_lines, legend = list(title_lines), list(legend)
    if not title_lines and not legend:
        return ""
    esc = html_lib.escape
    out = ['<div id="pkm-overlay">']
    if title_lines:
        out.append('<div id="pkm-title">')
        out.append(f'<div class="pkm-name">{esc(title_lines[0])}</div>')
        out += [f'<div class="pkm-line">{esc(line)}</div>' for line in title_lines[1:]]
        out.append("</div>")
    if legend:
        out.append('<details id="pkm-legend" open><summary>legend</summary><table>')
        for e in legend:
            swatches = "".join(f'<span class="pkm-swatch" style="background:{css_colour(c)}">'
                               "</span>" for c in e.colours)
            out.append(f'<tr data-kind="{esc(e.kind)}"><td class="pkm-swatches">{swatches}</td>'
                       f'<td><span class="pkm-label">{esc(e.label)}</span> '
                       f'<span class="pkm-note">{esc(e.note)}</span></td></tr>')
        out.append("</table></details>")
    out.append("</div>")
    return "\n".join(out)


#: Where a live viewer gets the legend card (:func:`draw_legend_card`): a child of the
#: default camera, so it stays in the view's top left corner as the camera moves.
LEGEND_CARD_PATH = "/Cameras/default/rotated/<object>/pkm_legend"
#: The width / height of the view the card is placed for.
LEGEND_CARD_ASPECT = 1.5


def legend_png(title_lines, legend, scale: float = 2.0) -> tuple[bytes, int, int]:
    """The title and legend (as :func:`overlay_html` lays them out) drawn as a PNG
    image by matplotlib, ``scale`` pixels per CSS pixel: ``(png, width, height)``, the
    size in CSS pixels."""
    import io

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.image import imsave
    from matplotlib.patches import Rectangle
    from matplotlib.transforms import IdentityTransform

    title_lines, legend = list(title_lines), list(legend)
    line, pad, swatch = 17.0 * scale, 8.0 * scale, 11.0 * scale
    n_swatches = max((len(e.colours) for e in legend), default=0)
    rows = len(title_lines) + len(legend) + (1 if legend else 0)
    height = int(2 * pad + line * rows)
    fig = Figure(figsize=(1000 * scale / 100, height / 100), dpi=100)
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.patch.set_facecolor((1.0, 1.0, 1.0, 0.9))
    pixels = IdentityTransform()
    texts = []
    y = height - pad - 0.75 * line
    for i, text in enumerate(title_lines):
        texts.append(fig.text(pad, y, text, transform=pixels, color="#222222",
                              fontsize=(11.5 if i == 0 else 10) * scale * 0.75,
                              fontweight="bold" if i == 0 else "normal"))
        y -= line
    y -= 0.3 * line
    x_label = pad + n_swatches * (swatch + 2 * scale) + 4 * scale
    for e in legend:
        for k, c in enumerate(e.colours):
            x = x_label - 4 * scale - (len(e.colours) - k) * (swatch + 2 * scale)
            fig.add_artist(Rectangle((x, y - 1 * scale), swatch, swatch, transform=pixels,
                                     facecolor=css_colour(c), edgecolor=(0, 0, 0, 0.35),
                                     linewidth=0.5 * scale))
        label = fig.text(x_label, y, e.label, transform=pixels, color="#222222",
                         fontsize=10 * scale * 0.75)
        texts.append(label)
        right = label.get_window_extent(renderer).x1 + 5 * scale
        texts.append(fig.text(right, y, e.note, transform=pixels, color="#666666",
                              fontsize=9 * scale * 0.75))
        y -= line
    fig.canvas.draw()
    width = min(int(max([t.get_window_extent(renderer).x1 for t in texts], default=0) + pad),
                int(1000 * scale))
    rgba = np.asarray(fig.canvas.buffer_rgba())[:, :width].copy()
    rgba[[0, -1], :] = rgba[:, [0, -1]] = (187, 187, 187, 255)  # a grey border
    out = io.BytesIO()
    imsave(out, rgba, format="png")
    return out.getvalue(), int(round(width / scale)), int(round(height / scale))


def draw_legend_card(vis, title_lines, legend, radius: float) -> None:
    """The title and legend as an image on a card in the default camera's top left
    corner (:data:`LEGEND_CARD_PATH`): what a live meshcat viewer, whose page has no
    room for HTML, shows instead of :func:`overlay_html`. The card is drawn at a tenth
    of ``radius`` in front of the camera, over everything, sized and placed as in a view
    800 pixels high and :data:`LEGEND_CARD_ASPECT` times as wide (a wider view has it
    further right, a narrower one cuts its left side)."""
    g = _meshcat()[1]
    png, width, height = legend_png(title_lines, legend)
    depth = 0.1 * radius
    half = depth * np.tan(np.radians(CAMERA_FOV) / 2)  # half the view's height there
    h = 2 * half * height / 800
    w = h * width / height
    margin = 2 * half * 8 / 800
    texture = g.ImageTexture(image=g.PngImage(png))
    material = g.MeshBasicMaterial(map=texture, transparent=True, depthTest=False,
                                   depthWrite=False, side=0)  # front faces only
    vis[LEGEND_CARD_PATH].set_object(g.Box([w, h, 1e-6 * h]), material)
    # the camera looks along its -z axis, y up
    vis[LEGEND_CARD_PATH].set_transform(_translation(
        [-half * LEGEND_CARD_ASPECT + margin + w / 2, half - margin - h / 2, -depth]))


def _short(x: float) -> str:
    """A number in three significant digits, whole numbers up to 1e6 unabridged
    (``1000``, not ``1e+03``), ``-0`` printed as ``0``."""
    if x == 0 or not np.isfinite(x):
        return "0" if x == 0 else str(x)
    digits = min(max(3, int(np.floor(np.log10(abs(x)))) + 1), 6)
    return f"{x:.{digits}g}"


def pose_words(M: pin.SE3, length: float, point: bool = False) -> str:
    """``xyz (x, y, z) rpy (r°, p°, y°)`` of a placement, short: coordinates below
    1e-6 ``length`` print as 0; ``point``: the position only."""
    p = np.where(np.abs(M.translation) < 1e-6 * length, 0.0, M.translation)
    out = "xyz (" + ", ".join(_short(float(x)) for x in p) + ")"
    if not point:
        rpy = np.degrees(pin.rpy.matrixToRpy(M.rotation))
        rpy = np.where(np.abs(rpy) < 1e-6, 0.0, rpy)
        out += " rpy (" + ", ".join(f"{_short(float(a))}°" for a in rpy) + ")"
    return out


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
        #: Title lines and legend entries of the page (:func:`overlay_html`), when the
        #: drawing sets them (:func:`pkm_pin.view.workspace_cloud` does).
        self.title_lines: tuple[str, ...] = ()
        self.legend: tuple[LegendEntry, ...] = ()

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

    def commands(self, without: tuple[str, ...] = ()) -> list[bytes]:
        """The packed commands that rebuild the scene: objects, properties and
        transforms node by node (parents first), then the animation; ``without``: the
        subtrees at these meshcat paths left out."""
        left_out = []
        for path in without:
            *parent, name = [p for p in path.split("/") if p]
            node = self.node("/".join(parent))
            if node is not None and name in node:
                left_out.append((node, name, node.pop(name)))
        out = []
        try:
            for node in self._tree.walk(self.tree):
                if node.object is not None:
                    out.append(node.object)
                out.extend(node.properties)
                if node.transform is not None:
                    out.append(node.transform)
        finally:
            for node, name, child in left_out:
                node[name] = child
        if self.animation is not None:
            out.append(self.animation)
        return out

    def static_html(self, title: str = "MeshCat", overlay: str | None = None) -> str:
        """A self-contained HTML page of the scene (no server, no network).

        Same page as meshcat's ``static_html()`` (the viewer's ``main.min.js`` inlined,
        then the commands), except that each command is decoded synchronously so that
        they run in order; ``overlay``: HTML drawn over the scene's top left corner;
        default: :func:`overlay_html` of :attr:`title_lines` and :attr:`legend`. A page
        with an overlay leaves out the legend card drawn for a live viewer
        (:data:`LEGEND_CARD_PATH`), which says the same.
        """
        if overlay is None:
            overlay = overlay_html(self.title_lines, self.legend)
        meshcat = _meshcat()[0]
        viewer_js = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
        without = (LEGEND_CARD_PATH,) if overlay else ()
        calls = "\n".join(f'pkmRun("{base64.b64encode(c).decode("ascii")}");'
                          for c in self.commands(without))
        return _PAGE.format(title=html_lib.escape(title), viewer_js=viewer_js.read_text("utf-8"),
                            commands=calls, overlay=overlay)

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
{overlay}
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
#pkm-overlay {{ font: 13px/1.35 system-ui, -apple-system, "Segoe UI", Helvetica, Arial,
  sans-serif; color: #222; }}
#pkm-title, #pkm-legend {{ position: absolute; left: 8px; max-width: 30em; z-index: 10;
  background: rgba(255, 255, 255, 0.86); border: 1px solid #bbb; border-radius: 6px;
  padding: 5px 9px; }}
#pkm-title {{ top: 8px; pointer-events: none; }}
#pkm-legend {{ bottom: 8px; }}
#pkm-title .pkm-name {{ font-weight: 600; font-size: 15px; }}
#pkm-title .pkm-line {{ color: #333; }}
#pkm-legend summary {{ cursor: pointer; color: #555; }}
#pkm-legend table {{ border-collapse: collapse; }}
#pkm-legend td {{ padding: 1px 4px 1px 0; vertical-align: top; }}
#pkm-legend .pkm-swatches {{ white-space: nowrap; text-align: right; }}
#pkm-legend .pkm-swatch {{ display: inline-block; width: 11px; height: 11px;
  margin-left: 1px; border: 1px solid rgba(0, 0, 0, 0.35); border-radius: 2px; }}
#pkm-legend .pkm-note {{ color: #666; font-size: 12px; }}
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
        title_lines: The page's title: the name (and :attr:`source` in brackets), then
            the pose, then DOF, motion type and singularity class (from
            :attr:`analysis`).
        source: The file (or shipped model) the mechanism was read from, when the
            caller gave it (``pkm-pin view``: a Gepetto file's robot is "onshape").
        legend: One :class:`LegendEntry` per kind of object drawn.
        camera: ``{"target": …, "position": …, "box": (lo, hi)}``, the default camera
            in the mechanism's world frame: it looks at the centre of the bounding box
            ``box`` of the drawing's points (joints, ends of screw axes and arrows) from
            outside that box.
    """

    title_lines: tuple[str, ...] = ()
    legend: tuple[LegendEntry, ...] = ()
    camera: dict | None = None
    source: str | None = None

    def __init__(self, visualizer, recorder: SceneRecorder, analysis, root: str):
        self.visualizer = visualizer
        self.recorder = recorder
        self.analysis = analysis
        self.assembly = analysis.assembly
        self.mechanism = analysis.mechanism
        self.root = root
        self.animated = False
        self.title_lines = (self.mechanism.name,)

    @property
    def title(self) -> str:
        """The title lines on one line (the page's ``<title>``)."""
        return " — ".join(self.title_lines)

    def legend_kinds(self) -> list[str]:
        """The kinds of the legend's entries, in order."""
        return [e.kind for e in self.legend]

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
        page = self.recorder.static_html(title=f"pkm_pin: {self.title}",
                                         overlay=overlay_html(self.title_lines, self.legend))
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
    """Scale of meshcat's axes for a mechanism of characteristic length
    ``length``: the power of ten at or below it (1 for a metre-sized model in metres,
    1000 for the same in millimetres, 0.1 for a 30 cm model)."""
    return float(10.0 ** np.floor(np.log10(length)))


def grid_cell(extent: float) -> float:
    """Cell size of the grid under a drawing ``extent`` across: the largest 1, 2 or 5
    times a power of ten at most ``extent / 16``, so that meshcat's grid (40 cells)
    spans 1 to 2.5 times the drawing (its far side stays in front of the camera)."""
    target = extent / 16.0
    power = 10.0 ** np.floor(np.log10(target) + 1e-9)
    return float(max(m * power for m in (1.0, 2.0, 5.0) if m * power <= target * (1 + 1e-12)))


#: The default camera: vertical field of view [deg], the direction it looks from
#: (before the planar adjustment, see :func:`camera_placement`), its least and largest
#: elevation above the ground plane [deg], and the margin around the drawing.
CAMERA_FOV = 50.0
CAMERA_DIRECTION = (1.0, -1.0, 0.7)
CAMERA_ELEVATION = (25.0, 60.0)
CAMERA_MARGIN = 1.1


def camera_placement(P: np.ndarray, length: float, shape: np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray, float]:
    """Where the default camera looks from: ``(centre, offset, radius)``.

    ``centre`` is the centre of the bounding box of the points ``P`` (n × 3), ``radius``
    the largest distance from it to a point (at least ``length / 2``). The camera sits
    at ``centre + offset``, looking at ``centre`` from :data:`CAMERA_DIRECTION`, or,
    when the points ``shape`` (default ``P``) are nearly planar, rather across their
    plane (its normal added to that direction); the elevation is kept within
    :data:`CAMERA_ELEVATION`, so the ground plane is never seen edge-on. The distance
    is the least that shows every point, padded by ``length / 20`` for the markers
    drawn there, within the vertical field of view (:data:`CAMERA_FOV`, narrowed by
    :data:`CAMERA_MARGIN`) in both directions, and at least 1.2 ``radius`` (outside
    the box).
    """
    P = np.asarray(P, dtype=float)
    shape = P if shape is None else np.asarray(shape, dtype=float)
    centre = 0.5 * (P.min(axis=0) + P.max(axis=0))
    radius = max(float(np.max(np.linalg.norm(P - centre, axis=1))), 0.5 * length)
    d = np.array(CAMERA_DIRECTION) / np.linalg.norm(CAMERA_DIRECTION)
    if len(shape) >= 3:
        _, sv, Vt = np.linalg.svd(shape - shape.mean(axis=0))
        if sv[0] > 0 and sv[-1] < 0.15 * sv[0]:  # nearly planar: look across the plane
            normal = Vt[-1] if Vt[-1] @ d >= 0 else -Vt[-1]
            d = normal + d
            d /= np.linalg.norm(d)
    horizontal = d[:2] / np.linalg.norm(d[:2]) if np.linalg.norm(d[:2]) > 1e-6 \
        else np.array(CAMERA_DIRECTION[:2]) / np.linalg.norm(CAMERA_DIRECTION[:2])
    lo, hi = np.radians(CAMERA_ELEVATION)
    elevation = float(np.clip(np.arcsin(np.clip(d[2], -1.0, 1.0)), lo, hi))
    d = np.array([*(np.cos(elevation) * horizontal), np.sin(elevation)])
    right = np.cross(d, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, d)
    t = np.tan(np.radians(CAMERA_FOV) / 2) / CAMERA_MARGIN
    Q = P - centre
    depth = Q @ d  # towards the camera
    reach = np.maximum(np.abs(Q @ up), np.abs(Q @ right)) + 0.05 * length  # + markers
    distance = max(float(np.max(depth + reach / t)), 1.2 * radius)
    return centre, distance * d, radius


def frame_view(vis, root: str, P: np.ndarray, length: float,
               shape: np.ndarray | None = None) -> dict:
    """Light grey background, the drawing under ``vis[root]`` centred, the grid and
    axes scaled to it, and the default camera (:func:`camera_placement` of the points
    ``P``, n × 3, in the drawing's world frame; ``shape``: the points of the body drawn,
    default ``P``).

    meshcat's camera always looks at the viewer's origin, so ``root`` is shifted to put
    the centre of the points' bounding box there; the grid and axes are shifted with it.
    The axes stay at the world origin, scaled by :func:`grid_scale` of ``length``; the
    grid, of :func:`grid_cell` cells, lies in the plane z = 0, or under the drawing when
    its body reaches below (a linkage hanging from its origin), centred under it, its
    lines on multiples of the cell.

    Returns:
        ``target`` and ``position`` of the camera (world frame), ``box`` (lowest and
        highest corner of the points' bounding box), ``radius`` (of
        :func:`camera_placement`), ``grid_cell``, ``grid_height``.
    """
    P = np.asarray(P, dtype=float)
    body = P if shape is None else np.asarray(shape, dtype=float)
    vis["/Background"].set_property("top_color", [0.97, 0.97, 0.97])
    vis["/Background"].set_property("bottom_color", [0.80, 0.80, 0.82])
    centre, offset, radius = camera_placement(P, length, shape=body)
    vis[root].set_transform(_translation(-centre))
    # meshcat's grid: 40 cells of 0.5; its axes: 1 unit long
    cell = grid_cell(2.0 * radius)
    lowest = float(body[:, 2].min())
    height = lowest if lowest < -1e-9 * length else 0.0
    under = [*(np.round(centre[:2] / cell) * cell), height]  # lines on multiples of cell
    vis["/Grid"].set_transform(_translation(under - centre)
                               @ np.diag([2.0 * cell, 2.0 * cell, 2.0 * cell, 1.0]))
    vis["/Axes"].set_transform(_translation(-centre)
                               @ np.diag([*[grid_scale(length)] * 3, 1.0]))
    # The viewer's own camera, set by its properties: a camera object set in its place
    # a second time (a second view drawn into a live viewer) makes meshcat's page fail
    # halfway and leave the camera at the origin, looking at the grid edge-on. The
    # legend card riding on it (draw_legend_card) is drawn anew.
    vis[LEGEND_CARD_PATH].delete()
    camera = vis["/Cameras/default/rotated/<object>"]
    for key, value in (("fov", CAMERA_FOV), ("near", 0.01 * radius), ("far", 200 * radius)):
        camera.set_property(key, float(value))
    # the camera node is rotated so that its y axis (three.js "up") is the world z
    camera.set_property("position", [float(offset[0]), float(offset[2]), float(-offset[1])])
    return {"target": centre, "position": centre + offset, "box": (P.min(axis=0), P.max(axis=0)),
            "radius": radius, "grid_cell": cell, "grid_height": height}


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
        self.noted: dict[str, list[int]] = {}
        self.drawn_points: list[np.ndarray] = []
        self.grid_cell: float | None = None
        self.grid_height = 0.0
        self.radius = self.L

    def size(self, key: str) -> float:
        return _SIZE[key] * self.L

    def centre(self) -> np.ndarray:
        """The point wrench arrows start nearest to: the platform origin."""
        return self.scene.assembly.pose.translation

    def material(self, colour: int, opacity: float = 1.0):
        return self.g.MeshPhongMaterial(color=colour, opacity=opacity,
                                        transparent=opacity < 1.0)

    # ------------------------------------------------------------- legend, title
    def note(self, kind: str, colour: int) -> None:
        """Record that an object of ``kind`` (a key of :data:`LEGEND_TEXT`) was drawn
        in ``colour``: the legend lists what was noted, in those colours."""
        colours = self.noted.setdefault(kind, [])
        if colour not in colours:
            colours.append(colour)

    def legend(self) -> tuple[LegendEntry, ...]:
        """One entry per kind noted, in :data:`LEGEND_TEXT`'s order, then the grid's
        cell size (no swatch: meshcat's colours)."""
        out = [LegendEntry(k, *LEGEND_TEXT[k], tuple(self.noted[k]))
               for k in LEGEND_TEXT if k in self.noted]
        if self.grid_cell is not None:
            out.append(LegendEntry("grid", "grid", f"cells of {self.grid_cell:g}, in the "
                                   f"plane z = {_short(self.grid_height)}", ()))
        return tuple(out)

    def title_lines(self) -> tuple[str, ...]:
        """Name; platform pose; DOF, motion type and singularity class."""
        a = self.scene.analysis
        lines = [self.mech.name,
                 f"platform at {pose_words(self.scene.assembly.pose, self.L)}",
                 f"{a.dof} DOF, motion {a.motion_type}, singularity: "
                 f"{SINGULARITY_WORDS.get(a.singularity, a.singularity)}"]
        if self.scene.animated:
            lines.append("animated: the platform moves along the uncontrolled twist")
        return tuple(lines)

    def finish(self) -> None:
        """The scene's title and legend, from what was drawn; for a live viewer, the
        legend card (:func:`draw_legend_card`)."""
        lines = self.title_lines()
        source = self.scene.source
        if source and source != lines[0]:
            lines = (f"{lines[0]} ({source})", *lines[1:])
        self.scene.title_lines = lines
        self.scene.legend = self.legend()
        if self.scene.recorder.forward is not None:
            draw_legend_card(self.vis, self.scene.title_lines, self.scene.legend, self.radius)

    # ------------------------------------------------------------- view settings
    def frame_points(self) -> np.ndarray:
        """World points that the view must frame: :meth:`mech_points` and the ends of
        the screw axes and wrench arrows drawn so far."""
        return np.vstack([self.mech_points(), *self.drawn_points])

    def settings(self) -> None:
        """The view set up for the drawing (call it last): :func:`frame_view` of
        :meth:`frame_points` (shape: :meth:`mech_points`), the camera kept in
        :attr:`Scene.camera`."""
        body = self.mech_points()
        view = frame_view(self.vis, self.root, self.frame_points(), self.L, shape=body)
        self.grid_cell, self.grid_height = view["grid_cell"], view["grid_height"]
        self.radius = view["radius"]
        self.scene.camera = {k: view[k] for k in ("target", "position", "box")}

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
            self.note("legs", colour)
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
        self.note("platform", PLATFORM_COLOUR)
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
                actuated = k in leg.actuated_v
                colour = ACTUATED_SCREW_COLOUR if actuated else PASSIVE_SCREW_COLOUR
                self.note("actuated_axis" if actuated else "passive_axis", colour)
                node = self.vis[f"{self.root}/screws/{node_name(leg.name)}/{node_name(name)}"]
                node.set_object(self.g.Cylinder(1.0, self.size("screw")), self.material(colour))
                node.set_transform(_segment_matrix(centre - half * u, centre + half * u))
                self.drawn_points.append(np.array([centre - half * u, centre + half * u]))

    # ------------------------------------------------------------------- wrenches
    def wrenches(self) -> None:
        analysis = self.scene.analysis
        for name, w in zip(self.mech.actuated_names, analysis.A):
            self.arrow(f"actuation/{node_name(name.replace('/', '.'))}", w,
                       ACTUATION_WRENCH_COLOUR, "actuation_wrench")
        centre = self.scene.assembly.pose.translation
        basis = readable_basis(analysis.constraint_wrenches, centre, self.L)
        for k, w in enumerate(b.screw for b in basis):
            self.arrow(f"constraint/{k}", w, CONSTRAINT_WRENCH_COLOUR, "constraint_wrench")

    def arrow(self, name: str, wrench: np.ndarray, colour: int, kind: str) -> None:
        """An arrow along a wrench's axis (a double arrow for a couple), noted in the
        legend as ``kind``. A wrench whose axis passes farther than
        :data:`FAR_AXIS` drawing lengths from :meth:`centre` (a near-couple: a 2R ankle's
        actuation wrenches pass metres away) is drawn as the couple it is at this scale,
        a double arrow along its moment about the centre, so that the camera, which
        frames what is drawn, still frames the mechanism."""
        if not np.any(wrench):
            return
        self.note(kind, colour)
        c = self.centre()
        point, u = screws.axis(wrench, length=self.L)
        couple = np.isinf(screws.pitch(wrench, length=self.L))
        length, head = self.size("arrow"), self.size("head")
        tail = None if couple else point + ((c - point) @ u) * u
        if tail is not None and np.linalg.norm(tail - c) > FAR_AXIS * self.L:
            moment = wrench[3:] - np.cross(c, wrench[:3])  # about the centre
            couple, u = True, moment / np.linalg.norm(moment)
        if couple:
            tail = c - 0.5 * length * u
        self.drawn_points.append(np.array([tail, tail + length * u]))
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
