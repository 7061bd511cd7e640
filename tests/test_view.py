"""Tests of pkm_pin.view: the meshcat scene, its static HTML page, and that page drawn
by a real headless Chromium."""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest
import umsgpack

from pkm_pin import InputError, Leg, Mechanism
from pkm_pin.builders import MECHANISMS, rpr3_type2_pose
from pkm_pin.view import (
    LEG_COLOURS,
    PLATFORM_COLOUR,
    SceneRecorder,
    node_name,
    view,
)

CHROMIUM_FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--window-size=800,600",
    "--virtual-time-budget=5000",
]


@pytest.fixture(scope="module")
def rpr3():
    return MECHANISMS["rpr3"]().build()


@pytest.fixture(scope="module")
def page(rpr3, tmp_path_factory):
    """The 3-RPR at home written as a static page: (scene, path)."""
    path = tmp_path_factory.mktemp("view") / "rpr3.html"
    return view(rpr3, html=path), path


def page_commands(text: str) -> list[dict]:
    """The meshcat commands embedded in a page, decoded."""
    import base64

    return [umsgpack.unpackb(base64.b64decode(b))
            for b in re.findall(r'pkmRun\("([A-Za-z0-9+/=]+)"\);', text)]


def chromium(*args: str, tmp_path) -> subprocess.CompletedProcess:
    exe = shutil.which("chromium")
    if exe is None:
        pytest.fail("Debian's chromium is not installed: run `bash .ci/install-system-deps` "
                    "(as root) before the tests", pytrace=False)
    return subprocess.run([exe, *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'profile'}", *args],
                          capture_output=True, text=True, timeout=120)


def hue_of(colour: int) -> float:
    import colorsys

    r, g, b = ((colour >> s) & 0xFF for s in (16, 8, 0))
    return 360.0 * colorsys.rgb_to_hsv(r / 255, g / 255, b / 255)[0]


# ------------------------------------------------------------------------ the page
def test_page_is_self_contained(page):
    """The page loads no script or style from the network."""
    _, path = page
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>")
    assert not re.search(r"<script[^>]*\bsrc\s*=", text)
    assert not re.search(r"<link[^>]*\bhref\s*=\s*[\"']https?:", text)
    assert "MeshCat.Viewer" in text and "handle_command_bytearray" in text
    assert len(text) > 500_000  # three.js and the viewer are inlined


def test_page_holds_the_mechanism_nodes(page, rpr3):
    """Every leg, the platform, each joint screw and each wrench is drawn in the page."""
    scene, path = page
    commands = page_commands(path.read_text(encoding="utf-8"))
    objects = {c["path"] for c in commands if c["type"] == "set_object"}
    root = f"/meshcat/pkm/{node_name(rpr3.name)}"
    assert root == "/meshcat/pkm/3-RPR_seed_000"
    for leg in rpr3.legs:
        assert any(p.startswith(f"{root}/legs/{leg.name}/visuals/") for p in objects)
        for joint in leg.joint_names:
            assert f"{root}/screws/{leg.name}/{joint}" in objects
    assert f"{root}/platform/body" in objects
    for name in ("A.A1", "B.B0", "C.C1"):
        assert f"{root}/wrenches/actuation/{name}/head" in objects
    assert not any(c["type"] == "set_animation" for c in commands)
    assert sorted(p.removeprefix("/meshcat/") for p in objects if p.startswith(root)) == \
        sorted(scene.paths())


# ---------------------------------------------------------------------- in Chromium
def test_chromium_draws_the_mechanism(page, rpr3, tmp_path):
    """Headless Chromium renders the page: the legs' and platform's colours fill many
    pixels of the screenshot, not only the grey background."""
    from PIL import Image

    _, path = page
    png = tmp_path / "shot.png"
    run = chromium(f"--screenshot={png}", path.as_uri(), tmp_path=tmp_path)
    assert png.is_file(), f"chromium wrote no screenshot:\n{run.stderr[-2000:]}"
    image = Image.open(png).convert("RGB")
    assert image.size == (800, 600)
    rgb = np.asarray(image).reshape(-1, 3)
    assert len(np.unique(rgb, axis=0)) > 500, "the screenshot has almost no colours: blank?"
    hsv = np.asarray(image.convert("HSV")).reshape(-1, 3).astype(float)
    hue = hsv[:, 0] * 360.0 / 255.0
    coloured = (hsv[:, 1] > 0.35 * 255) & (hsv[:, 2] > 0.2 * 255)
    assert coloured.mean() > 0.02, f"only {coloured.mean():.2%} coloured pixels"

    def pixels_of(colour):
        return int(np.sum(coloured & (np.abs((hue - hue_of(colour) + 180) % 360 - 180) < 12)))

    legs = [pixels_of(c) for c in LEG_COLOURS[:len(rpr3.legs)]]
    assert min(legs) > 500, f"leg pixels {legs}"
    assert pixels_of(PLATFORM_COLOUR) > 1000


def test_chromium_loads_the_scene_tree(page, rpr3, tmp_path):
    """The viewer running in Chromium holds the mechanism's nodes (its scene menu)."""
    _, path = page
    run = chromium("--dump-dom", path.as_uri(), tmp_path=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    titles = re.findall(r'class="title">([^<]*)<', run.stdout)
    assert "meshcat" in titles, "the viewer did not build its scene tree"
    tree = titles[titles.index("meshcat"):]
    for name in ("pkm", node_name(rpr3.name), "legs", "A", "B", "C", "platform", "body",
                 "screws", "wrenches", "actuation", "constraint"):
        assert name in tree, f"{name!r} missing from the browser's scene tree"


# ------------------------------------------------------------------------ the scene
@pytest.mark.parametrize("key", sorted(MECHANISMS))
def test_every_shipped_mechanism_is_drawn(key):
    """At home every leg, every joint screw, every actuation and constraint wrench and
    the platform of each shipped mechanism get their node."""
    mech = MECHANISMS[key]().build()
    scene = view(mech)
    analysis = scene.analysis
    assert scene.children("legs") == [node_name(leg.name) for leg in mech.legs]
    for leg in mech.legs:
        assert len(scene.children(f"screws/{node_name(leg.name)}")) == leg.nv
        assert scene.children(f"legs/{node_name(leg.name)}/visuals")
    assert len(scene.children("wrenches/actuation")) == mech.n_actuated
    assert len(scene.children("wrenches/constraint")) == analysis.constraint_wrenches.shape[0]
    assert "body" in scene.children("platform")
    assert not scene.animated and scene.recorder.animation is None


def test_type_ii_pose_is_animated(rpr3):
    """At the 3-RPR's type II singularity the platform and legs move along the
    uncontrolled twist; at home nothing is animated."""
    home = view(rpr3)
    assert not home.animated
    scene = view(rpr3, rpr3_type2_pose())
    assert scene.analysis.singularity in ("II", "III")
    assert scene.animated and scene.recorder.animation is not None
    clips = {a["path"]: a["clip"] for a in umsgpack.unpackb(scene.recorder.animation)["animations"]}
    platform = clips[f"/meshcat/{scene.root}/platform"]
    positions = next(t for t in platform["tracks"] if t["name"] == ".position")
    xyz = np.array([k["value"] for k in positions["keys"]])
    assert len(xyz) > 10 and np.ptp(xyz, axis=0).max() > 1e-3 * rpr3.characteristic_length
    assert any("/legs/A/visuals/" in p for p in clips)


def test_animation_frames_keep_the_legs_closed(rpr3):
    """Each animation frame's platform pose is reached by the legs drawn in it: the
    first-order motion along the uncontrolled twist, legs re-assembled."""
    scene = view(rpr3, rpr3_type2_pose())
    clips = {a["path"]: a["clip"] for a in umsgpack.unpackb(scene.recorder.animation)["animations"]}
    root = f"/meshcat/{scene.root}"
    platform = {t["name"]: t["keys"] for t in clips[f"{root}/platform"]["tracks"]}
    # the tip sphere (A2_link_0) of leg A sits on anchor A at every frame
    tip = {t["name"]: t["keys"] for t in clips[f"{root}/legs/A/visuals/A2_link_0"]["tracks"]}
    import pinocchio as pin

    base = rpr3.legs[0].base
    for kp, kq, tp in zip(platform[".position"], platform[".quaternion"], tip[".position"]):
        x, y, z, w = kq["value"]
        pose = pin.SE3(pin.Quaternion(w, x, y, z).matrix(), np.array(kp["value"]))
        anchor = (pose * rpr3.anchors[0]).translation
        assert np.allclose(base * np.array(tp["value"]), anchor, atol=1e-5)


def test_leg_without_visuals_gets_spheres(rpr3):
    """A leg whose URDF has no visual is drawn with a sphere per joint and its links."""
    legs = [Leg.from_urdf(re.sub(r"<visual>.*?</visual>", "", leg.xml, flags=re.S),
                          leg.tip, leg.actuated, leg.base, leg.name) for leg in rpr3.legs]
    bare = Mechanism(legs, rpr3.anchors, name="bare", home=rpr3.home, home_q=rpr3.home_q)
    scene = view(bare)
    for leg in legs:
        assert scene.children(f"legs/{leg.name}/visuals") == []
        assert len(scene.children(f"legs/{leg.name}/joints")) == leg.model.njoints + 1
        assert scene.children(f"legs/{leg.name}/links")


def test_urdf_meshes_are_embedded(ur5):
    """A leg whose URDF visuals are meshes (``package://`` paths, UR5) is drawn from those
    meshes, carried inside the scene."""
    q = ur5.neutral() + 0.3
    arm = Mechanism([ur5], name="ur5 arm", home=ur5.tip_placement(q), home_q=[q])
    scene = view(arm, show_wrenches=False)
    visuals = scene.children(f"legs/{ur5.name}/visuals")
    assert len(visuals) >= 6
    node = scene.recorder.node(f"/meshcat/{scene.root}/legs/{ur5.name}/visuals/{visuals[0]}")
    assert len(node.object) > 10_000  # the mesh data itself


def test_missing_mesh_warns_and_draws_spheres(rpr3):
    """A URDF visual whose mesh file cannot be found gives a warning, and the leg is
    drawn with spheres and links instead."""
    leg = rpr3.legs[0]
    xml = leg.xml.replace('<sphere radius="0.09"/>', '<mesh filename="package://nowhere/x.stl"/>')
    legs = [Leg.from_urdf(xml, leg.tip, leg.actuated, leg.base, leg.name), *rpr3.legs[1:]]
    mech = Mechanism(legs, rpr3.anchors, name="missing mesh", home=rpr3.home,
                     home_q=rpr3.home_q)
    with pytest.warns(UserWarning, match="cannot be loaded"):
        scene = view(mech)
    assert scene.children(f"legs/{leg.name}/joints")
    assert scene.children(f"legs/{leg.name}/visuals") == []


def test_options_leave_out_screws_and_wrenches(rpr3):
    """show_screws=False and show_wrenches=False draw neither."""
    scene = view(rpr3, show_screws=False, show_wrenches=False)
    assert scene.children("screws") == [] and scene.children("wrenches") == []
    assert scene.children("legs")


def test_live_visualizer_receives_the_scene(rpr3):
    """A visualizer given to view() receives every command (here an in-memory one)."""
    import meshcat

    live = meshcat.Visualizer(window=SceneRecorder())
    scene = view(rpr3, visualizer=live)
    assert live.window.commands() == scene.recorder.commands()


def test_wrong_inputs_raise(rpr3):
    """Something other than a mechanism, or another mechanism's assembly, is refused."""
    with pytest.raises(InputError, match="Mechanism"):
        view("rpr3")
    other = MECHANISMS["rpr3"]().build()
    with pytest.raises(InputError, match="another mechanism"):
        view(rpr3, other.home_assembly)


def test_cli_view_writes_the_page(tmp_path, capsys):
    """``pkm-pin view rpr3 --pose … --html FILE`` writes the page of that pose."""
    from pkm_pin.cli import main

    out = tmp_path / "page.html"
    pose = rpr3_type2_pose()
    import pinocchio as pin

    numbers = [repr(float(x)) for x in (*pose.translation, *pin.rpy.matrixToRpy(pose.rotation))]
    assert main(["view", "rpr3", "--html", str(out), "--pose", *numbers]) == 0
    assert str(out) in capsys.readouterr().out
    commands = page_commands(out.read_text(encoding="utf-8"))
    assert any(c["type"] == "set_animation" for c in commands)


def test_grid_and_axes_follow_the_models_scale(tmp_path):
    """meshcat's grid and axes are drawn at a power of ten of the characteristic length:
    the same 3-RPR in millimetres gets them 1000 times larger (issue 17, item 7)."""
    from pkm_pin.builders import MECHANISMS
    from pkm_pin.view import grid_scale

    assert (grid_scale(1.0), grid_scale(2.3), grid_scale(2300.0), grid_scale(0.3)) == (
        1.0, 1.0, 1000.0, 0.1)
    scales = []
    for scale in (1.0, 1000.0):
        mech = MECHANISMS["rpr3"](scale=scale).build()
        path = tmp_path / f"rpr3_{scale:g}.html"
        view(mech, html=path)
        grid = [c for c in page_commands(path.read_text(encoding="utf-8"))
                if c["type"] == "set_transform" and c["path"] == "/Grid"]
        M = np.array(grid[-1]["matrix"], dtype=float).reshape(4, 4)
        scales.append(np.linalg.norm(M[:3, 0]))
    assert scales[1] == pytest.approx(1000.0 * scales[0])
