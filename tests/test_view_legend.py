"""Tests of the views' explanations (issue 25, item 8): the legend and title over the
page, the default camera and the grid, for mechanisms, linkages and workspace clouds."""

from __future__ import annotations

import html
import re
from pathlib import Path

import numpy as np
import pytest
from test_view import chromium, page_commands

from pkm_pin import load_mechanism
from pkm_pin.builders import MECHANISMS, rpr3_type2_pose
from pkm_pin.scene import (
    ACTUATED_SCREW_COLOUR,
    ACTUATION_WRENCH_COLOUR,
    CAMERA_ELEVATION,
    CAMERA_FOV,
    CONSTRAINT_WRENCH_COLOUR,
    LEG_COLOURS,
    LEGEND_TEXT,
    PASSIVE_SCREW_COLOUR,
    PLATFORM_COLOUR,
    SINGULARITY_WORDS,
    grid_cell,
)
from pkm_pin.view import view
from pkm_pin.view_linkage import CLOSURE_COLOUR, GROUND_COLOUR, IDLE_COLOUR, OUTPUT_AXIS_COLOURS

MODELS = Path(__file__).resolve().parents[1] / "models"


@pytest.fixture(scope="module")
def stewart():
    return load_mechanism(MODELS / "mechanisms" / "stewart.toml")


@pytest.fixture(scope="module")
def rps3():
    return MECHANISMS["rps3"]().build()


@pytest.fixture(scope="module")
def ankle():
    return load_mechanism(MODELS / "loops" / "ankle.urdf")


def legend_kinds_in_page(text: str) -> list[str]:
    """The kinds of the legend rows of a page's overlay, in order."""
    return re.findall(r'<tr data-kind="([^"]+)"', text)


def object_colours(scene) -> dict[str, int]:
    """Material colour of each object of the scene (meshcat path → 0xRRGGBB)."""
    out = {}
    for c in page_commands(scene.to_html()):
        if c["type"] == "set_object" and "materials" in c["object"]:
            out[c["path"]] = int(c["object"]["materials"][0]["color"])
    return out


# -------------------------------------------------------------------------- legend
def test_legend_lists_exactly_the_kinds_drawn(stewart, rps3):
    """The 3-RPS has constraint wrenches and its legend says so; the 6-UPS has none and
    its legend has no such entry; screws and wrenches left out leave their entries out."""
    with_c, without = view(rps3), view(stewart)
    assert with_c.children("wrenches/constraint")
    assert not without.children("wrenches/constraint")
    assert with_c.legend_kinds() == ["legs", "platform", "actuated_axis", "passive_axis",
                                     "actuation_wrench", "constraint_wrench", "grid"]
    assert without.legend_kinds() == ["legs", "platform", "actuated_axis", "passive_axis",
                                      "actuation_wrench", "grid"]
    bare = view(rps3, show_screws=False, show_wrenches=False)
    assert bare.legend_kinds() == ["legs", "platform", "grid"]
    for scene in (with_c, without, bare):
        assert legend_kinds_in_page(scene.to_html()) == scene.legend_kinds()


def test_legend_colours_are_the_painters_constants(rps3):
    """Each legend entry's colours are the painter's constants, and objects of the scene
    are drawn in each of them."""
    scene = view(rps3)
    colours = {e.kind: e.colours for e in scene.legend}
    assert colours == {
        "legs": LEG_COLOURS[:len(rps3.legs)], "platform": (PLATFORM_COLOUR,),
        "actuated_axis": (ACTUATED_SCREW_COLOUR,), "passive_axis": (PASSIVE_SCREW_COLOUR,),
        "actuation_wrench": (ACTUATION_WRENCH_COLOUR,),
        "constraint_wrench": (CONSTRAINT_WRENCH_COLOUR,), "grid": ()}
    drawn = object_colours(scene)
    root = f"/meshcat/{scene.root}"
    assert {drawn[p] for p in drawn if p.startswith(f"{root}/wrenches/actuation/")} == \
        {ACTUATION_WRENCH_COLOUR}
    assert {drawn[p] for p in drawn if p.startswith(f"{root}/wrenches/constraint/")} == \
        {CONSTRAINT_WRENCH_COLOUR}
    assert {drawn[p] for p in drawn if p.startswith(f"{root}/platform/")} == {PLATFORM_COLOUR}
    page = scene.to_html()
    for e in scene.legend:
        for c in e.colours:
            assert f"background:#{c:06x}" in page


def test_linkage_legend_names_closures_idle_axes_and_output(ankle):
    """The ankle's legend has its loop closures, idle axes, output frame and axes, in
    the colours view_linkage draws them with."""
    scene = view(ankle)
    colours = {e.kind: e.colours for e in scene.legend}
    assert colours["closure"] == (CLOSURE_COLOUR,)
    assert colours["idle"] == (IDLE_COLOUR,)
    assert colours["output"] == (PLATFORM_COLOUR,)
    assert colours["output_axes"] == OUTPUT_AXIS_COLOURS
    assert colours["ground"] == (GROUND_COLOUR,)
    assert colours["actuated_joint"] == (ACTUATED_SCREW_COLOUR,)
    assert set(colours) <= set(LEGEND_TEXT) | {"grid"}
    drawn = object_colours(scene)
    root = f"/meshcat/{scene.root}"
    assert {drawn[p] for p in drawn if p.startswith(f"{root}/idle/")} == {IDLE_COLOUR}
    assert {drawn[p] for p in drawn if p.startswith(f"{root}/closures/")} == {CLOSURE_COLOUR}


def test_workspace_cloud_legend_lists_the_kinds_drawn():
    """A workspace cloud's legend has one entry per kind drawn, in its KIND_COLOURS, and
    the home marker; its page shows them."""
    from test_workspace import DELTA_BOX

    from pkm_pin.view import HOME_COLOUR, workspace_cloud
    from pkm_pin.workspace import KIND_COLOURS

    delta = MECHANISMS["delta"]().build()
    ws = delta.workspace(bounds=DELTA_BOX, n=6, kinds=["reachable", "singularity-free"])
    rec = workspace_cloud(ws)
    assert [e.kind for e in rec.legend] == ["reachable", "singularity-free", "home"]
    assert [e.colours for e in rec.legend] == [
        (int(KIND_COLOURS["reachable"][1:], 16),), (int(KIND_COLOURS["singularity-free"][1:], 16),),
        (HOME_COLOUR,)]
    assert legend_kinds_in_page(rec.static_html()) == ["reachable", "singularity-free", "home"]
    assert rec.title_lines[0] == "workspace of Delta"


# --------------------------------------------------------------------------- title
def test_title_has_name_pose_dof_motion_type_and_class(rps3):
    """The title names the mechanism, its pose (short numbers, in millimetres too), DOF,
    motion type and singularity class; at a type II pose it says so and that the scene
    is animated."""
    scene = view(rps3)
    a = scene.analysis
    assert scene.title_lines[0] == rps3.name
    assert "xyz (0, 0, 1)" in scene.title_lines[1] and "rpy (0°, 0°, 0°)" in scene.title_lines[1]
    assert f"{a.dof} DOF" in scene.title and a.motion_type in scene.title
    assert f"singularity: {SINGULARITY_WORDS[a.singularity]}" in scene.title
    page = scene.to_html()
    assert f"<title>pkm_pin: {html.escape(scene.title)}</title>" in page
    assert all(html.escape(line) in page for line in scene.title_lines)

    mm = view(MECHANISMS["rps3"](scale=1000.0).build())
    assert "xyz (0, 0, 1000)" in mm.title_lines[1]  # no 1e+03

    rpr3 = MECHANISMS["rpr3"]().build()
    singular = view(rpr3, rpr3_type2_pose())
    assert singular.analysis.singularity in ("II", "III")
    assert "type II" in singular.title or "type III" in singular.title
    assert "animated" in singular.title


def test_linkage_title_names_the_output_frame(ankle):
    """A linkage's title names its output frame and pose, DOF, idle DOF, the output's
    motion type and the singularity class."""
    scene = view(ankle)
    a = scene.analysis
    assert scene.title_lines[0] == ankle.name
    assert f"output frame {ankle.output} at xyz" in scene.title
    assert f"{a.dof} DOF, {a.idle_dof} idle" in scene.title
    assert f"output motion {a.motion_type}" in scene.title
    assert f"singularity: {SINGULARITY_WORDS[a.singularity]}" in scene.title


# -------------------------------------------------------------------------- camera
def mechanism_points(mech, assembly) -> np.ndarray:
    """Bases, joint origins and tips of the legs."""
    pts = []
    for leg, q in zip(mech.legs, assembly.leg_q):
        pts += [leg.base.translation[None], leg.joint_origins(q),
                leg.tip_placement(q).translation[None]]
    return np.vstack(pts)


def check_camera(scene, points: np.ndarray) -> None:
    """The scene's camera looks at its box's centre from outside the box, sees every
    point, is above the ground at an angle, and is what the page sets."""
    cam = scene.camera
    lo, hi = cam["box"]
    assert np.all(points >= lo - 1e-9) and np.all(points <= hi + 1e-9)
    np.testing.assert_allclose(cam["target"], 0.5 * (lo + hi), atol=1e-12)
    assert np.any((cam["position"] < lo) | (cam["position"] > hi)), "camera inside the box"
    offset = cam["position"] - cam["target"]
    distance = np.linalg.norm(offset)
    d = offset / distance
    elevation = np.degrees(np.arcsin(d[2]))
    assert CAMERA_ELEVATION[0] - 1e-9 <= elevation <= CAMERA_ELEVATION[1] + 1e-9
    right = np.cross(d, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, d)
    Q = points - cam["target"]
    depth = distance - Q @ d
    assert np.all(depth > 0)
    t = np.tan(np.radians(CAMERA_FOV / 2))
    assert np.all(np.abs(Q @ up) / depth < t) and np.all(np.abs(Q @ right) / depth < t)
    commands = page_commands(scene.to_html())
    root = [c for c in commands if c["type"] == "set_transform"
            and c["path"] == f"/meshcat/{scene.root}"]
    shift = np.array(root[-1]["matrix"], dtype=float).reshape(4, 4).T[:3, 3]
    np.testing.assert_allclose(shift, -cam["target"], atol=1e-12)  # target at the origin
    position = [c["value"] for c in commands if c["type"] == "set_property"
                and c["path"] == "/Cameras/default/rotated/<object>"
                and c["property"] == "position"][-1]
    np.testing.assert_allclose([position[0], -position[2], position[1]], offset, atol=1e-12)


@pytest.mark.parametrize("key", ["stewart", "rps3"])
def test_camera_looks_at_the_box_centre_from_outside(key, stewart, rps3):
    """The default camera looks at the centre of the drawing's bounding box from outside
    it, obliquely, and sees every joint of the mechanism."""
    mech = {"stewart": stewart, "rps3": rps3}[key]
    scene = view(mech)
    points = mechanism_points(mech, scene.assembly)
    check_camera(scene, points)
    assert np.linalg.norm(scene.camera["position"] - scene.camera["target"]) > np.ptp(
        points, axis=0).max() / 2  # farther than half the drawing's extent


def test_camera_and_grid_of_a_hanging_linkage():
    """Cassie's knee hangs below its origin: the camera frames it from above the ground
    plane, and the grid lies under it, not through it, at the drawing's scale."""
    link = load_mechanism(MODELS / "loops" / "cassie_knee.urdf")
    scene = view(link)
    kin = link.model.kinematics(scene.assembly.q)
    joints = np.array([kin.joint_placements[j].translation
                       for j in range(1, link.model.tree.njoints)])
    check_camera(scene, joints)
    grid = [c for c in page_commands(scene.to_html())
            if c["type"] == "set_transform" and c["path"] == "/Grid"][-1]
    G = np.array(grid["matrix"], dtype=float).reshape(4, 4).T
    height = G[2, 3] + scene.camera["target"][2]
    assert height == pytest.approx(joints[:, 2].min())
    assert [e for e in scene.legend if e.kind == "grid"][0].note.endswith(
        f"z = {joints[:, 2].min():.3g}")
    lo, hi = scene.camera["box"]
    width = 20.0 * G[0, 0]  # meshcat's grid is 20 units wide
    assert 0.5 * np.linalg.norm(hi - lo) < width < 6.0 * np.linalg.norm(hi - lo)


CORPUS = Path(__file__).resolve().parent / "data"


@pytest.mark.parametrize("path", ["ankles/g1_ankle/g1_ankle.xml",
                                  "gepetto/battobot_6d/robot.urdf",
                                  "menagerie/agility_cassie/cassie.xml"])
def test_wrenches_whose_axis_lies_metres_away_leave_the_camera_on_the_mechanism(path):
    """Published files whose actuation wrenches are near-couples (the G1's 2R ankle:
    axes 14 m away from a 25 cm ankle; battobot's and Cassie's legs: 26 m): the box the
    camera frames with the wrenches drawn is at most 25 % larger than without them, and
    each wrench drawn as a couple points along its moment about the output (1e-9)."""
    link = load_mechanism(CORPUS / path)
    bare, full = view(link, show_wrenches=False), view(link)
    size = [np.ptp(np.array(s.camera["box"]), axis=0).max() for s in (bare, full)]
    assert size[1] <= 1.25 * size[0]
    moves = {c["path"]: np.array(c["matrix"], dtype=float).reshape(4, 4).T
             for c in page_commands(full.to_html()) if c["type"] == "set_transform"}
    root = f"/meshcat/{full.root}/wrenches/actuation"
    subs = full.submechanisms or ((link, full.analysis),)
    kin = link.model.kinematics(full.assembly.q)
    couples = 0
    for sub, an in subs:
        c = kin.frame_placements[link.model.tree.getFrameId(sub.output)].translation
        for name, w in zip(sub.actuated, an.A):
            if f"{root}/{name}/tail" not in moves:
                continue
            couples += 1
            m = w[3:] - np.cross(c, w[:3])
            u = moves[f"{root}/{name}"][:3, 1]  # the arrow's y axis
            assert np.allclose(u, m / np.linalg.norm(m), atol=1e-9), name
    assert couples >= 1


def test_grid_cell_is_a_round_fraction_of_the_drawing():
    """grid_cell: 1, 2 or 5 times a power of ten, 1/40 to 1/16 of the extent, scaling
    with it."""
    assert (grid_cell(1.6), grid_cell(2.2), grid_cell(5.0), grid_cell(16.0)) == (
        0.1, 0.1, 0.2, 1.0)
    for extent in (0.37, 1.0, 2.9, 47.0, 1234.5):
        cell = grid_cell(extent)
        assert extent / 40 < cell <= extent / 16 * (1 + 1e-12)
        assert grid_cell(1000.0 * extent) == pytest.approx(1000.0 * cell)


# ---------------------------------------------------------------------- in Chromium
def test_chromium_shows_the_legend_and_title(rps3, tmp_path):
    """The page rendered by headless Chromium holds the title and legend in its DOM,
    and the overlay is drawn: a screenshot has the light title box top left and the
    legend box bottom left, with dark text in them."""
    from PIL import Image

    scene = view(rps3)
    path = tmp_path / "rps3.html"
    scene.to_html(path)
    run = chromium("--dump-dom", path.as_uri(), tmp_path=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    dom = run.stdout
    assert 'id="pkm-overlay"' in dom and 'id="pkm-legend"' in dom
    for e in scene.legend:
        assert f">{html.escape(e.label)}<" in dom, f"{e.label!r} missing from the DOM"
    assert html.escape(scene.title_lines[-1]) in dom
    png = tmp_path / "shot.png"
    chromium(f"--screenshot={png}", path.as_uri(), tmp_path=tmp_path)
    image = np.asarray(Image.open(png).convert("RGB")).astype(int)
    assert image.shape[:2] == (600, 800)
    for box in (image[14:60, 14:200], image[-100:-14, 14:200]):  # title, legend
        assert np.mean(box.min(axis=2) > 235) > 0.6, "no light box"
        assert np.sum(box.max(axis=2) < 90) > 50, "no dark text"


def test_live_viewer_gets_the_legend_as_a_card(rps3):
    """A live viewer, whose page takes no HTML, gets the title and legend as an image
    card on the camera; the static page has the HTML overlay instead, without the card."""
    import base64

    import meshcat
    import umsgpack

    from pkm_pin.scene import LEGEND_CARD_PATH, SceneRecorder

    live = meshcat.Visualizer(window=SceneRecorder())
    scene = view(rps3, visualizer=live)
    card = live.window.node(LEGEND_CARD_PATH)
    assert card is not None and card.object is not None
    obj = umsgpack.unpackb(card.object)["object"]
    url = obj["images"][0]["url"]
    assert url.startswith("data:image/png;base64,")
    png = base64.b64decode(url.split(",", 1)[1])
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5000
    assert obj["materials"][0]["depthTest"] is False
    page = scene.to_html()
    assert 'id="pkm-legend"' in page
    assert not any(c["path"].startswith(LEGEND_CARD_PATH) for c in page_commands(page))
    assert view(rps3).recorder.node(LEGEND_CARD_PATH) is None  # no live viewer: no card


def test_second_view_into_a_live_viewer_keeps_its_camera(rps3, stewart, tmp_path):
    """Two views drawn one after the other into one live viewer (every command replayed
    in order, as meshcat's page receives them): the viewer's camera ends where the
    second view put it, with the second legend card on it; the camera object is never
    replaced (meshcat's page fails on a second replacement and leaves the camera at
    the origin, looking at the grid edge-on)."""
    import base64
    import json

    import meshcat
    import umsgpack

    from pkm_pin.scene import _PAGE, LEGEND_CARD_PATH

    class Log:
        def __init__(self):
            self.commands = []

        def send(self, command):
            self.commands.append(umsgpack.packb(command.lower()))

    log = Log()
    live = meshcat.Visualizer(window=log)
    view(rps3, visualizer=live)
    second = view(stewart, visualizer=live)
    decoded = [umsgpack.unpackb(c) for c in log.commands]
    assert not any(c["type"] == "set_object" and c["path"].startswith("/Cameras/default/rotated")
                   and not c["path"].startswith(LEGEND_CARD_PATH) for c in decoded)
    viewer_js = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
    calls = "\n".join(f'pkmRun("{base64.b64encode(c).decode("ascii")}");'
                      for c in log.commands)
    probe = """<script>setTimeout(function () {
      var c = viewer.camera, card = null;
      c.traverse(function (o) { if (o.isMesh) card = o; });
      var d = document.createElement("pre"); d.id = "probe";
      d.textContent = JSON.stringify({position: c.position.toArray(), fov: c.fov,
                                      card: card !== null});
      document.body.appendChild(d); }, 300);</script></body>"""
    page = _PAGE.format(title="live", viewer_js=viewer_js.read_text("utf-8"), commands=calls,
                        overlay="").replace("</body>", probe)
    path = tmp_path / "live.html"
    path.write_text(page, encoding="utf-8")
    run = chromium("--dump-dom", path.as_uri(), tmp_path=tmp_path)
    found = re.search(r'<pre id="probe">([^<]*)</pre>', run.stdout)
    assert found, run.stderr[-2000:]
    state = json.loads(html.unescape(found.group(1)))
    offset = second.camera["position"] - second.camera["target"]
    np.testing.assert_allclose(state["position"], [offset[0], offset[2], -offset[1]], rtol=1e-6)
    assert state["fov"] == CAMERA_FOV and state["card"]


def test_cli_view_titles_the_page_with_the_file_read(tmp_path, capsys):
    """pkm-pin view of a Gepetto file (its robot is named 'onshape', like every Onshape
    export): the page's title names the file after the robot, then the output, 12 DOF, 6
    idle, 3T3R and class; view() without a source keeps the bare name."""
    from pkm_pin.cli import main

    path = CORPUS / "gepetto" / "wl16_like" / "robot.urdf"
    page = tmp_path / "wl16.html"
    assert main(["view", str(path), "--html", str(page)]) == 0
    capsys.readouterr()
    title = re.search(r"<title>([^<]*)</title>", page.read_text()).group(1)
    assert title.startswith(f"pkm_pin: onshape ({path}) — output frame foot at xyz")
    assert title.endswith("12 DOF, 6 idle, output motion 3T3R, singularity: none")
    assert f'<div class="pkm-name">onshape ({html.escape(str(path))})</div>' in page.read_text()
    assert view(load_mechanism(path), show_wrenches=False).title_lines[0] == "onshape"
