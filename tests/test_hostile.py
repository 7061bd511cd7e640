"""Hostile files (issue 28): each reader refuses them in one line, in bounded time and memory."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import pytest
from helpers import one_error_line

from pkm_pin.cli import main
from pkm_pin.errors import ClosureFileError, MechanismFileError, UrdfError
from pkm_pin.io import load_mechanism
from pkm_pin.model import read_extended_urdf, read_mjcf
from pkm_pin.model.mjcf import parse_mjcf
from pkm_pin.urdf import read

ROOT = Path(__file__).resolve().parents[1]
LOOPS = ROOT / "models" / "loops"
FIVE_BAR_YAML = ("closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['3d']\n"
                 "name_mot: ['mot1', 'mot2']\n")

#: Runs ``pkm-pin ARGS`` and prints the child's peak RSS [kB] and the seconds main() took.
#: The peak is /proc's VmHWM of the child's own memory: ``ru_maxrss`` keeps the peak of
#: the forked parent (a pytest process grown by the whole suite) across ``exec``.
CHILD = ("import resource, sys, time\nfrom pkm_pin.cli import main\nt = time.perf_counter()\n"
         "rc = main(sys.argv[1:])\ntry:\n"
         "    peak = [int(line.split()[1]) for line in open('/proc/self/status')\n"
         "            if line.startswith('VmHWM:')][0]\n"
         "except (OSError, IndexError):\n"
         "    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n"
         "print(peak, time.perf_counter() - t)\nsys.exit(rc)")


def alias_bomb() -> str:
    """The 544-byte closures file of issue 28: nine levels of nine aliases (9⁹ nodes)."""
    levels = ["&a0 [" + ", ".join(["x"] * 9) + "]"] + [
        f"&a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 9)]
    return FIVE_BAR_YAML + "output: [" + ", ".join(levels) + "]\n"


def five_bar(tmp_path: Path, yaml: str, name: str = "five_bar") -> Path:
    """A copy of models/loops/five_bar.urdf in tmp_path with ``yaml`` beside it."""
    urdf = tmp_path / f"{name}.urdf"
    shutil.copy(LOOPS / "five_bar.urdf", urdf)
    (tmp_path / f"{name}.yaml").write_text(yaml)
    return urdf


def cli(*args: str) -> tuple[subprocess.CompletedProcess, float, float]:
    """``pkm-pin ARGS`` in a subprocess: the process, its peak RSS [MB] and main()'s time [s]."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run([sys.executable, "-c", CHILD, *args], capture_output=True, text=True,
                          timeout=120, env=env)
    rss_kb, seconds = proc.stdout.split()[-2:]
    return proc, float(rss_kb) / 1e3, float(seconds)


def refused(call, error=ClosureFileError) -> tuple[str, float, float]:
    """``call()``'s one-line error message, the seconds it took and its Python peak [MB]."""
    tracemalloc.start()
    t = time.perf_counter()
    try:
        with pytest.raises(error) as info:
            call()
        seconds = time.perf_counter() - t
        peak = tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()
    message = str(info.value)
    assert "\n" not in message
    return message, seconds, peak


def error_line(proc: subprocess.CompletedProcess) -> str:
    """The one ``pkm-pin: error:`` line of a command that exited with 2."""
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert lines[0].startswith("pkm-pin: error: ")
    return lines[0]


# -------------------------------------------------------------------------- YAML
def test_alias_bomb_is_one_line_fast_and_small(tmp_path):
    """The 544-byte alias bomb is refused at its first anchor, naming the line, in well
    under 5 s and 500 MB, through the API and the CLI (exit 2)."""
    urdf = five_bar(tmp_path, alias_bomb())
    assert len((tmp_path / "five_bar.yaml").read_bytes()) <= 544
    message, seconds, peak = refused(lambda: read_extended_urdf(urdf))
    assert "line 4: YAML anchor or alias &a0" in message
    assert seconds < 5 and peak < 500
    proc, rss, seconds = cli("analyze", str(urdf))
    assert "anchor or alias &a0" in error_line(proc) and rss < 500 and seconds < 5


def test_ten_megabyte_value_is_one_line_fast_and_small(tmp_path):
    """A 10 MB value is refused by the file's size before it is parsed; the line echoes
    nothing of it."""
    urdf = five_bar(tmp_path, FIVE_BAR_YAML + "output: '" + "a" * 10_000_000 + "'\n")
    message, seconds, peak = refused(lambda: read_extended_urdf(urdf))
    assert "the closures file is 10.0 MB, more than the 1 MB pkm_pin reads" in message
    assert seconds < 5 and peak < 500 and len(message) < 300
    proc, rss, seconds = cli("analyze", str(urdf))
    assert "10.0 MB" in error_line(proc) and rss < 500 and seconds < 5


def test_a_long_value_is_echoed_cut_to_300_characters(tmp_path):
    """A 500 kB name (within the size limit) is echoed cut to 300 characters with '…'."""
    urdf = five_bar(tmp_path, FIVE_BAR_YAML.replace("'mot2'", "'" + "m" * 500_000 + "'"))
    message, seconds, _ = refused(lambda: read_extended_urdf(urdf))
    echoed = message.split("name_mot[1]: ")[1].split(" matches no movable joint")[0]
    assert len(echoed) == 300 and echoed.endswith("…") and seconds < 5
    proc, _, _ = cli("analyze", str(urdf))
    assert len(error_line(proc)) < 1000


def test_duplicate_key_is_refused_with_its_line(tmp_path):
    """name_mot given twice is an error naming the key and both lines (not the last kept)."""
    urdf = five_bar(tmp_path, FIVE_BAR_YAML + "name_mot: ['mot1']\n")
    message, _, _ = refused(lambda: read_extended_urdf(urdf))
    assert "name_mot: line 4: duplicate key (first given at line 3)" in message
    proc, _, _ = cli("analyze", str(urdf))
    assert "duplicate key" in error_line(proc)


@pytest.mark.parametrize("text,reason", [
    (FIVE_BAR_YAML.replace("name_mot: ['mot1', 'mot2']", "name_mot: &m ['mot1', 'mot2']"),
     "line 3: YAML anchor or alias &m"),
    (FIVE_BAR_YAML + "1: x\n", "a key must be a name"),
    (FIVE_BAR_YAML + "output: " + "[" * 20 + "]" * 20 + "\n", "nested more than 16 deep"),
    (FIVE_BAR_YAML + "output: 2024-01-01\n", "must be a frame name, got datetime.date"),
    (FIVE_BAR_YAML.replace("['mot1', 'mot2']", "[[mot1]]"), "must be a name (string)"),
])
def test_other_yaml_constructs_are_refused(tmp_path, text, reason):
    """Anchors, non-name keys, deep nesting and wrongly typed values are one-line errors."""
    urdf = five_bar(tmp_path, text)
    message, seconds, _ = refused(lambda: read_extended_urdf(urdf))
    assert reason in message and seconds < 5


def test_deeply_nested_toml_closures_file_is_one_line(tmp_path):
    """A TOML closures file nested 100 000 deep is a ClosureFileError, not a RecursionError."""
    urdf = five_bar(tmp_path, FIVE_BAR_YAML)
    toml = tmp_path / "c.toml"
    toml.write_text("closed_loop = " + "[" * 100_000 + "]" * 100_000 + "\ntype = []\n")
    message, seconds, _ = refused(lambda: read_extended_urdf(urdf, toml))
    assert "not valid TOML: arrays or tables nested too deep" in message and seconds < 5


def test_deeply_nested_mechanism_file_is_one_cli_line(tmp_path, capsys):
    """A mechanism TOML nested 100 000 deep: exit 2, one line (no RecursionError)."""
    path = tmp_path / "deep.toml"
    path.write_text("name = " + "[" * 100_000 + "]" * 100_000 + "\n")
    assert main(["analyze", str(path)]) == 2
    assert "not valid TOML: maximum recursion depth exceeded" in one_error_line(capsys)


def test_counts_are_bounded(tmp_path):
    """More than 500 closures in a closures file, or 500 actuators in an MJCF, are refused
    before anything is built from them."""
    urdf = five_bar(tmp_path, "closed_loop: [" + ", ".join(["[a, b]"] * 501) + "]\n"
                    "type: []\nname_mot: []\n")
    message, _, _ = refused(lambda: read_extended_urdf(urdf))
    assert "closed_loop: has 501 entries, more than the 500" in message
    text = (LOOPS / "four_bar.xml").read_text().replace(
        "<actuator>", "<actuator>" + '<motor joint="crank_joint"/>' * 501)
    (tmp_path / "m.xml").write_text(text)
    message, _, _ = refused(lambda: read_mjcf(tmp_path / "m.xml"))
    assert "actuator: 502 actuators, more than the 500 pkm_pin reads" in message


def test_included_files_share_the_size_budget(tmp_path, monkeypatch):
    """The main file and its includes together stay within the MJCF size limit."""
    import pkm_pin.model.mjcf as mjcf

    monkeypatch.setattr(mjcf, "MAX_BYTES", 400)
    (tmp_path / "r.xml").write_text("<mujoco>" + "<!-- padding -->" * 20 + "</mujoco>")
    (tmp_path / "s.xml").write_text('<mujoco><include file="r.xml"/>' + " " * 100
                                    + "</mujoco>")
    message, _, _ = refused(lambda: read_mjcf(tmp_path / "s.xml"))
    assert "with its included files, the model is more than 0.0004 MB" in message


# ----------------------------------------------------------------------- name_mot
def test_name_mot_equal_to_a_joint_picks_it_alone(tmp_path):
    """'mot1' picks joint mot1 alone even when 'mot1_free' contains it; what each
    identifier picked is on the model; a part of names still picks every joint with it."""
    urdf = five_bar(tmp_path, FIVE_BAR_YAML)
    urdf.write_text(urdf.read_text().replace('"free1"', '"mot1_free"'))
    model = read_extended_urdf(urdf)
    assert model.actuated == ("mot1", "mot2")
    assert model.actuator_matches == (("mot1", ("mot1",)), ("mot2", ("mot2",)))
    (tmp_path / "five_bar.yaml").write_text(FIVE_BAR_YAML.replace("'mot1', 'mot2'", "'mot'"))
    model = read_extended_urdf(urdf)
    assert model.actuator_matches == (("mot", ("mot1", "mot1_free", "mot2")),)


def test_actuator_matches_keeps_the_constructor_compatible():
    """ClosureModel without actuator_matches works as before (empty); a mapping is
    accepted; anything else is an InputError."""
    from dataclasses import replace

    from pkm_pin.errors import InputError

    model = read_mjcf(LOOPS / "four_bar.xml")
    bare = type(model)(model.tree, model.closures, model.actuated, model.output)
    assert bare.actuator_matches == ()
    assert replace(bare, actuator_matches={"m": ["crank_joint"]}).actuator_matches == (
        ("m", ("crank_joint",)),)
    with pytest.raises(InputError, match="actuator_matches must be pairs"):
        replace(bare, actuator_matches=3)


@pytest.mark.parametrize("names,where,reason", [
    ("['']", "name_mot[0]", "the empty name '' is part of every joint name"),
    ("['mot1', 'nowhere']", "name_mot[1]", "'nowhere' matches no movable joint"),
    ("['mot1', 'mot']", "name_mot[1]", "'mot' picks joint 'mot1', which name_mot[0] 'mot1' "
     "picked already"),
    ("['mot1', 'mot1']", "name_mot[1]", "which name_mot[0] 'mot1' picked already"),
])
def test_bad_actuator_names_are_named(tmp_path, names, where, reason):
    """The empty identifier, one matching nothing and two picking one joint are errors
    naming the identifiers, through the API and the CLI (exit 2)."""
    urdf = five_bar(tmp_path, FIVE_BAR_YAML.replace("['mot1', 'mot2']", names))
    with pytest.raises(ClosureFileError) as info:
        read_extended_urdf(urdf)
    assert info.value.where == where and reason in str(info.value)


def test_empty_actuator_name_is_one_cli_line(tmp_path, capsys):
    """name_mot: [''] no longer actuates every joint: exit 2, one line naming it."""
    urdf = five_bar(tmp_path, FIVE_BAR_YAML.replace("['mot1', 'mot2']", "['']"))
    assert main(["analyze", str(urdf)]) == 2
    assert "name_mot[0]: the empty name ''" in one_error_line(capsys)


# ---------------------------------------------------------------------------- XML
def test_urdf_coordinate_of_1e308_is_named(tmp_path, capsys):
    """A joint origin of 1e308 is named with its joint and value, not 'residual inf'."""
    urdf = five_bar(tmp_path, FIVE_BAR_YAML)
    text = urdf.read_text()
    assert 'xyz="0.1 0 0"' in text
    urdf.write_text(text.replace('xyz="0.1 0 0"', 'xyz="1e308 0 0"', 1))
    assert main(["analyze", str(urdf)]) == 2
    line = one_error_line(capsys)
    assert "origin xyz has 1e+308, beyond ±1e+06" in line and "joint '" in line


URDF = """<robot name="r">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="{com} 0 0"/><mass value="{mass}"/>
    <inertia ixx="{ixx}" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="{axis}"/><limit lower="{lower}" upper="1" effort="1" velocity="1"/></joint>
</robot>"""
GOOD = {"com": 0.1, "mass": 1, "ixx": 1, "axis": "0 0 1", "lower": -1}


@pytest.mark.parametrize("key,value,reason", [
    ("com", "1e308", "link 'arm' inertial origin xyz has 1e+308, beyond ±1e+06"),
    ("mass", "-1", "link 'arm' has mass -1 < 0"),
    ("ixx", "nan", "link 'arm' inertia ixx must be 1 finite numbers, got 'nan'"),
    ("axis", "0 0 0", "joint 'j' has a zero axis"),
    ("axis", "0 0 inf", "joint 'j' axis must be 3 finite numbers"),
    ("lower", "-1e7", "joint 'j' has limits lower=-1e+07, upper=1, beyond ±1e+06"),
    ("lower", "2", "joint 'j' has limits lower=2.0 > upper=1.0"),
])
def test_urdf_numbers_out_of_range_are_named(key, value, reason):
    """Coordinates beyond ±1e6, negative masses, non-finite inertias, zero axes and bad
    limits are UrdfErrors naming the element and the value."""
    read(URDF.format(**GOOD))
    message, _, _ = refused(lambda: read(URDF.format(**{**GOOD, key: value})), UrdfError)
    assert reason in message


def test_urdf_entity_declaration_is_refused(tmp_path):
    """A DTD entity ('billion laughs') is refused before any parser expands it."""
    entities = "".join(f'<!ENTITY e{i} "&e{i - 1};&e{i - 1};&e{i - 1};">' for i in range(1, 9))
    text = f'<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY e0 "ha">{entities}]>' \
        '<robot name="r"><link name="&e8;"/></robot>'
    message, seconds, _ = refused(lambda: read(text), UrdfError)
    assert "DTD entity declaration <!ENTITY e0>" in message and seconds < 5


def test_mjcf_nested_50000_deep_is_a_clean_error(tmp_path):
    """An MJCF nested 50 000 levels deep is refused in one line (exit 2), no segfault."""
    path = tmp_path / "deep.xml"
    path.write_text("<mujoco><worldbody>" + "<body>" * 50_000 + "</body>" * 50_000
                    + "</worldbody></mujoco>")
    proc, rss, seconds = cli("analyze", str(path))
    assert "elements nested more than 100 deep" in error_line(proc)
    assert rss < 500 and seconds < 5


@pytest.mark.parametrize("old,new,where,reason", [
    ('pos="0.1 0 0"', 'pos="1e308 0 0"', "body[3] 'rocker' pos", "has 1e+308"),
    ('axis="0 0 1"/>\n      </body>\n    </body>', 'axis="0 0 0"/>\n      </body>\n    </body>',
     "joint[2] 'rocker_joint' axis", "has zero length"),
    ('type="hinge" axis="0 0 1"/>\n        <body', 'type="hinge" axis="0 0 1" range="1 -1"/>'
     '\n        <body', "joint[0] 'crank_joint' range", "has lower 1 > upper -1"),
    ('axisangle="0 0 1 1.0471975511966"', 'axisangle="0 0 one 1"', "body[1] 'crank' axisangle",
     "must be numbers"),
])
def test_mjcf_numbers_are_checked(tmp_path, old, new, where, reason):
    """MJCF positions, axes, ranges: finite, within ±1e6, non-zero, lower ≤ upper; the
    error names the element, the attribute and the value."""
    text = (LOOPS / "four_bar.xml").read_text()
    assert old in text
    path = tmp_path / "four_bar.xml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ClosureFileError) as info:
        read_mjcf(path)
    assert info.value.where == where and reason in str(info.value)


def test_xacro_and_unexpanded_mjcf_elements_are_refused_by_name(tmp_path):
    """A xacro macro in a URDF and an MJCF <replicate> (which Pinocchio ignores) are
    refused by name instead of giving a model without those bodies."""
    xacro = '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">' \
        '<xacro:include filename="arm.xacro"/><link name="a"/></robot>'
    message, _, _ = refused(lambda: read(xacro), UrdfError)
    assert "<xacro:include> is a xacro macro" in message
    text = (LOOPS / "four_bar.xml").read_text().replace(
        "<worldbody>", '<worldbody><replicate count="3" offset="0 0 1"><body name="r"/>'
        "</replicate>")
    (tmp_path / "r.xml").write_text(text)
    with pytest.raises(ClosureFileError) as info:
        read_mjcf(tmp_path / "r.xml")
    assert info.value.where == "<replicate>" and "repeats its bodies" in str(info.value)


# ------------------------------------------------------------------------ includes
SCENE = """<mujoco model="{name} scene">
  <include file="{robot}"/>
  <statistic center="0 0 0.1" extent="0.3"/>
  <asset>
    <texture type="2d" name="grid" builtin="checker" rgb1="0.2 0.3 0.4" rgb2="0.1 0.2 0.3"
             width="300" height="300"/>
    <material name="grid" texture="grid" texrepeat="5 5"/>
  </asset>
  <worldbody>
    <light pos="0 0 1.5" dir="0 0 -1" directional="true"/>
    <geom name="floor" size="0 0 0.05" type="plane" material="grid"/>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize("name", ["four_bar", "five_bar"])
def test_menagerie_style_scene_analyses_like_its_robot(tmp_path, name, capsys):
    """A scene.xml including the robot file (in a subfolder too) and adding a floor and a
    light gives the robot's model and the same report (but the model's name)."""
    (tmp_path / "robot").mkdir()
    shutil.copy(LOOPS / f"{name}.xml", tmp_path / "robot" / f"{name}.xml")
    scene = tmp_path / "scene.xml"
    scene.write_text(SCENE.format(name=name, robot=f"robot/{name}.xml"))
    ours, theirs = read_mjcf(scene), read_mjcf(LOOPS / f"{name}.xml")
    assert list(ours.tree.names) == list(theirs.tree.names)
    assert [f.name for f in ours.tree.frames] == [f.name for f in theirs.tree.frames]
    assert (ours.closures, ours.actuated, ours.output) == (theirs.closures, theirs.actuated,
                                                          theirs.output)
    assert ours.actuator_matches == theirs.actuator_matches != ()
    assert main(["analyze", str(scene)]) == 0
    scene_report = capsys.readouterr().out.splitlines()
    assert main(["analyze", str(LOOPS / f"{name}.xml")]) == 0
    robot_report = capsys.readouterr().out.splitlines()
    assert scene_report[0].replace(" scene", "") == robot_report[0]
    assert scene_report[1:] == robot_report[1:]


DEFAULTS_ROBOT = """<mujoco model="robot">
  <default>
    <joint damping="0.1"/>
    <default class="visual"><geom group="2" contype="0" conaffinity="0"/></default>
  </default>
  <worldbody>
    <body name="crank">
      <joint name="j" axis="0 0 1"/>
      <geom class="visual" type="box" size="0.1 0.01 0.01"/>
      <body name="tip" pos="0.2 0 0"><joint name="k" axis="0 0 1" class="{joint_class}"/>
        <geom class="visual" type="box" size="0.1 0.01 0.01"/></body>
    </body>
  </worldbody>
  <actuator><motor joint="j"/><motor joint="k"/></actuator>
</mujoco>
"""
DEFAULTS_SCENE = """<mujoco model="scene">
  <include file="robot.xml"/>
  <default>
    <joint armature="0.01"/>
    <default class="frame"><geom group="1" type="box"/></default>
    <default class="stiff"><joint stiffness="1"/></default>
  </default>
  <worldbody><geom class="frame" size="0.1 0.1 0.1" pos="0 0 -1"/></worldbody>
</mujoco>
"""


def test_a_scene_with_its_own_defaults_reads_like_its_robot(tmp_path):
    """Menagerie's aloha scene adds a second top-level <default> to its robot's: MuJoCo
    merges them (classes of both, the main class's element defaults combined); Pinocchio
    4.1 kept one and failed on a class of the other ('unordered_map::at'). Merged, the
    scene gives the robot's tree, closures and actuators, the robot's joint using the
    scene's class; a class no <default> defines gets a sentence naming the likely cause."""
    (tmp_path / "robot.xml").write_text(DEFAULTS_ROBOT.format(joint_class="stiff"))
    (tmp_path / "scene.xml").write_text(DEFAULTS_SCENE)
    scene = read_mjcf(tmp_path / "scene.xml")
    assert list(scene.tree.names) == ["universe", "j", "k"]
    assert scene.actuated == ("j", "k") and scene.output == "tip"
    root = parse_mjcf(tmp_path / "scene.xml")
    (default,) = root.findall("default")
    assert {d.get("class") for d in default.findall("default")} == {"visual", "frame",
                                                                    "stiff"}
    assert default.find("joint").attrib == {"damping": "0.1", "armature": "0.01"}
    (tmp_path / "alone.xml").write_text(DEFAULTS_ROBOT.format(joint_class="nowhere"))
    with pytest.raises(ClosureFileError, match="a class= that no <default class=...> "
                       "defines"):
        read_mjcf(tmp_path / "alone.xml")


@pytest.mark.parametrize("files,main_file,where,reason", [
    ({"self.xml": '<mujoco><include file="self.xml"/><worldbody/></mujoco>'}, "self.xml",
     "include 'self.xml'", "includes itself (self.xml → self.xml)"),
    ({"a.xml": '<mujoco><include file="b.xml"/></mujoco>',
      "b.xml": '<mujoco><include file="a.xml"/></mujoco>'}, "a.xml", "include 'a.xml'",
     "includes itself (a.xml → b.xml → a.xml)"),
    ({"m/scene.xml": '<mujoco><include file="../robot.xml"/></mujoco>', "robot.xml": "<mujoco/>"},
     "m/scene.xml", "include '../robot.xml'", "is outside the model's folder"),
    ({"s.xml": '<mujoco><include file="r.xml"/><include file="./r.xml"/></mujoco>',
      "r.xml": "<mujoco/>"}, "s.xml", "include './r.xml'", "r.xml is included twice"),
    ({"s.xml": '<mujoco><include file="none.xml"/></mujoco>'}, "s.xml", "include 'none.xml'",
     "no such file"),
    ({"s.xml": '<mujoco><include/></mujoco>'}, "s.xml", "include", "has no file attribute"),
    ({"s.xml": '<mujoco><include file="r.xml"/></mujoco>', "r.xml": "<robot/>"}, "s.xml", "",
     "an included MJCF's must be <mujoco>"),
])
def test_bad_includes_are_one_line_errors(tmp_path, files, main_file, where, reason):
    """Self-inclusion, cycles, an include escaping the folder, a second include of a file,
    a missing file or attribute and a non-MJCF file are one-line errors, fast."""
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    with pytest.raises(ClosureFileError) as info:
        read_mjcf(tmp_path / main_file)
    assert any(info.value.path == str(tmp_path / name) for name in files)
    message, seconds, peak = refused(lambda: read_mjcf(tmp_path / main_file))
    assert where in message and reason in message and seconds < 5 and peak < 500


@pytest.mark.parametrize("case", ["self", "escape"])
def test_bad_includes_exit_2_in_one_line(tmp_path, case):
    """pkm-pin analyze of a self-including MJCF and of one escaping its folder: exit 2,
    one line, under 5 s and 500 MB."""
    (tmp_path / "m").mkdir()
    (tmp_path / "robot.xml").write_text("<mujoco/>")
    path = tmp_path / "m" / "scene.xml"
    path.write_text('<mujoco><include file="%s"/></mujoco>'
                    % ("scene.xml" if case == "self" else "../robot.xml"))
    proc, rss, seconds = cli("analyze", str(path))
    line = error_line(proc)
    assert ("includes itself" if case == "self" else "outside the model's folder") in line
    assert rss < 500 and seconds < 5


def test_include_depth_is_limited(tmp_path):
    """A chain of includes deeper than 8 is refused."""
    for i in range(12):
        (tmp_path / f"f{i}.xml").write_text(f'<mujoco><include file="f{i + 1}.xml"/></mujoco>')
    (tmp_path / "f12.xml").write_text("<mujoco/>")
    message, _, _ = refused(lambda: read_mjcf(tmp_path / "f0.xml"))
    assert "includes nested more than 8 deep" in message


# ------------------------------------------------------------------ mechanism files
def test_two_megabyte_mechanism_file_is_refused_by_its_size(tmp_path, capsys):
    """A mechanism TOML of 2 MB (a shipped file padded with a comment) is refused by its
    size before it is parsed: one line naming the file and the limit, exit 2, fast."""
    path = tmp_path / "big.toml"
    text = (ROOT / "models" / "mechanisms" / "rpr3.toml").read_text()
    path.write_text(text.replace('"../urdf/', f'"{ROOT / "models" / "urdf"}/')
                    + "#" + "x" * 2_000_000 + "\n")
    message, seconds, peak = refused(lambda: load_mechanism(path), MechanismFileError)
    assert "the mechanism file is 2.0 MB, more than the 1 MB pkm_pin reads" in message
    assert seconds < 5 and peak < 500
    assert main(["analyze", str(path)]) == 2
    assert str(path) in one_error_line(capsys)
    path.write_text(text.replace('"../urdf/', f'"{ROOT / "models" / "urdf"}/'))
    assert load_mechanism(path).name == "3-RPR (seed 000)"  # the file unpadded loads


def test_impossible_inertia_in_a_urdf_is_one_cli_line(tmp_path, capsys):
    """A five-bar whose link distal1 has principal moments 1, 1, 3 (no rigid body: I₃ >
    I₁ + I₂): ``pkm-pin dynamics`` exits 2 with one line naming the body and the
    moments (the URDF reader accepts the numbers: each is finite and ≥ 0)."""
    urdf = five_bar(tmp_path, FIVE_BAR_YAML)
    urdf.write_text(urdf.read_text().replace(
        '<link name="distal1"/>',
        '<link name="distal1"><inertial><mass value="0.5"/><inertia ixx="1" ixy="0" '
        'ixz="0" iyy="1" iyz="0" izz="3"/></inertial></link>'))
    assert main(["dynamics", str(urdf), "--samples", "5"]) == 2
    line = one_error_line(capsys)
    assert "body 'distal1': inertia with principal moments 1, 1, 3 kg m²" in line
    assert "triangle inequality" in line
