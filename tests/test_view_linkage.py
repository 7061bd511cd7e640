"""Tests of pkm_pin.view_linkage: a general linkage's meshcat scene (tree, closures,
output, idle motions), its static page, and that page drawn by a headless Chromium."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from test_view import chromium, hue_of, page_commands

from pkm_pin import InputError, load_mechanism
from pkm_pin.view import node_name, view
from pkm_pin.view_linkage import (
    CLOSURE_COLOUR,
    IDLE_COLOUR,
    idle_velocities,
    view_linkage,
)

MODELS = Path(__file__).resolve().parents[1] / "models"
ANKLE = MODELS / "loops" / "ankle.urdf"


@pytest.fixture(scope="module")
def ankle():
    return load_mechanism(ANKLE)


@pytest.fixture(scope="module")
def page(ankle, tmp_path_factory):
    """The ankle at its reference assembly written as a static page: (scene, path)."""
    path = tmp_path_factory.mktemp("view_linkage") / "ankle.html"
    return view(ankle, html=path), path


def test_page_holds_the_tree_closures_output_and_idle_axes(page, ankle):
    """Every joint, every closure's ring and marker, the output axes and one axis per
    idle motion are objects of the page."""
    scene, path = page
    objects = {c["path"] for c in page_commands(path.read_text(encoding="utf-8"))
               if c["type"] == "set_object"}
    root = f"/meshcat/pkm/{node_name(ankle.name)}"
    for joint in ankle.model.tree.names[1:]:
        assert f"{root}/joints/{joint}" in objects
    for c in ankle.model.closures:
        assert f"{root}/closures/{c.name}/marker" in objects
        assert f"{root}/closures/{c.name}/line" in objects
        assert any(p.startswith(f"{root}/closures/{c.name}/ring/") for p in objects)
    for name in ("ball", "x", "y", "z"):
        assert f"{root}/output/{name}" in objects
    assert {f"{root}/idle/0/axis", f"{root}/idle/1/axis"} <= objects
    assert f"{root}/wrenches/actuation/motor_1/head" in objects
    assert sorted(p.removeprefix("/meshcat/") for p in objects if p.startswith(root)) == \
        sorted(scene.paths())
    assert scene.idle_motions == ankle.analyze(ankle.assemble()).mobility.idle_motions


def test_idle_axes_lie_along_the_rods(page, ankle):
    """Each idle axis is drawn along its rod: the line through the rod's two balls."""
    scene, path = page
    commands = page_commands(path.read_text(encoding="utf-8"))
    transforms = {c["path"]: np.array(c["matrix"]).reshape(4, 4).T for c in commands
                  if c["type"] == "set_transform"}
    root = f"/meshcat/pkm/{node_name(ankle.name)}"
    for k, rod_x in enumerate([(-0.05, 0.04), (-0.05, -0.04)]):
        T = transforms[f"{root}/idle/{k}/axis"]
        assert T[:2, 3] == pytest.approx(rod_x, abs=1e-9)  # centre on the rod's line
        axis = T[:3, 1] / np.linalg.norm(T[:3, 1])  # the cylinder's y axis
        assert abs(axis[2]) == pytest.approx(1.0, abs=1e-9)


def test_idle_velocities_leave_the_actuators_still(ankle):
    """The drawn idle motions keep the closures and the actuated joints still."""
    q = ankle.assemble().q
    V = idle_velocities(ankle, q)
    assert V.shape == (2, ankle.model.nv)
    assert np.abs(ankle.model.closure_jacobian(q) @ V.T).max() < 1e-12
    assert np.abs(V[:, list(ankle.model.actuated_v)]).max() < 1e-12


@pytest.mark.parametrize("name", ["loops/four_bar.urdf", "loops/five_bar.xml",
                                  "loops/cassie_knee.urdf", "loops/delta_loops.urdf",
                                  "pinned/five_bar.toml", "pinned/delta_point.toml"])
def test_every_shipped_linkage_is_drawn(name):
    """Each shipped linkage gives a scene with its joints, closures and output."""
    link = load_mechanism(MODELS / name)
    scene = view_linkage(link)
    assert set(scene.children()) >= {"links", "joints", "closures", "output", "wrenches"}
    assert len(scene.children("closures")) == len(link.model.closures)


def test_options_leave_out_screws_and_wrenches(ankle):
    """show_screws / show_wrenches False draw neither."""
    scene = view(ankle, show_screws=False, show_wrenches=False)
    assert "screws" not in scene.children() and "wrenches" not in scene.children()


def test_wrong_inputs_raise(ankle):
    """view_linkage of something else, or a malformed pose, is an InputError."""
    with pytest.raises(InputError, match="Linkage"):
        view_linkage("ankle")
    with pytest.raises(InputError):
        view_linkage(ankle, [0.0, 0.0])


# ---------------------------------------------------------------------- in Chromium
def test_chromium_draws_the_closures_and_idle_axes(page, tmp_path):
    """Headless Chromium renders the page: the closure rings and the idle axes fill
    pixels of their colours."""
    from PIL import Image

    _, path = page
    png = tmp_path / "shot.png"
    run = chromium(f"--screenshot={png}", path.as_uri(), tmp_path=tmp_path)
    assert png.is_file(), f"chromium wrote no screenshot:\n{run.stderr[-2000:]}"
    image = Image.open(png).convert("RGB")
    hsv = np.asarray(image.convert("HSV")).reshape(-1, 3).astype(float)
    hue = hsv[:, 0] * 360.0 / 255.0
    coloured = (hsv[:, 1] > 0.35 * 255) & (hsv[:, 2] > 0.2 * 255)

    def pixels_of(colour):
        return int(np.sum(coloured & (np.abs((hue - hue_of(colour) + 180) % 360 - 180) < 12)))

    assert pixels_of(CLOSURE_COLOUR) > 500, pixels_of(CLOSURE_COLOUR)
    assert pixels_of(IDLE_COLOUR) > 100, pixels_of(IDLE_COLOUR)


def test_chromium_loads_the_scene_tree(page, ankle, tmp_path):
    """The viewer running in Chromium holds the linkage's nodes (its scene menu)."""
    _, path = page
    run = chromium("--dump-dom", path.as_uri(), tmp_path=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    titles = re.findall(r'class="title">([^<]*)<', run.stdout)
    tree = titles[titles.index("meshcat"):]
    for name in ("pkm", node_name(ankle.name), "links", "joints", "closures", "output", "idle",
                 "rod_1_tipCfoot_attach_1"):
        assert name in tree, f"{name!r} missing from the browser's scene tree"


def test_a_coupling_draws_no_loop(tmp_path):
    """Menagerie's Robotiq 2F-85: its two <connect> loops are drawn, its <joint>
    equality (a coupling of two joint coordinates, no loop of bodies) is not."""
    gripper = load_mechanism(Path(__file__).resolve().parent / "data" / "menagerie"
                             / "robotiq_2f85" / "2f85.xml")
    path = tmp_path / "gripper.html"
    view(gripper, html=path)
    objects = {c["path"] for c in page_commands(path.read_text(encoding="utf-8"))
               if c["type"] == "set_object"}
    root = f"/meshcat/pkm/{node_name(gripper.name)}/closures"
    drawn = {p.removeprefix(root + "/").split("/")[0] for p in objects if p.startswith(root)}
    assert drawn == {"connect0", "connect1"}
    assert [c.kind for c in gripper.model.closures] == ["point", "point", "coupling"]


def test_a_failing_layer_leaves_the_rest_of_the_drawing(monkeypatch, tmp_path, capsys):
    """A drawing layer that fails (the wrenches, here an IndexError planted in them) is
    named with its error and left out: the tree, the closures, the output and the idle
    axes are drawn, the page written, exit 0."""
    from pkm_pin.cli import main
    from pkm_pin.view_linkage import _LinkagePainter

    def broken(self):
        raise IndexError("index 0 is out of bounds for axis 0 with size 0")

    monkeypatch.setattr(_LinkagePainter, "wrenches", broken)
    ankle = ANKLE
    scene = view_linkage(load_mechanism(ankle))
    assert scene.failed_sections == {
        "wrenches": "IndexError: index 0 is out of bounds for axis 0 with size 0"}
    kinds = {e.kind for e in scene.legend}
    assert {"closure", "idle", "output"} <= kinds and "actuation_wrench" not in kinds
    page = tmp_path / "ankle.html"
    assert main(["view", str(ankle), "--html", str(page)]) == 0
    out = capsys.readouterr().out
    assert "failed     wrenches: IndexError: index 0" in out and page.stat().st_size > 10_000
