"""Tests of pkm_pin.urdf and Leg.from_urdf / from_example_robot_data: sources, errors.

Every malformed URDF gives its own :class:`UrdfError` whose message names the file and
what is wrong; a missing tip gives :class:`FrameNotFound` listing the frames; a bad
actuated name gives :class:`JointNotFound` listing the movable joints of the chain.
"""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest

from pkm_pin import FrameNotFound, JointNotFound, Leg, PkmError, UrdfError, urdf

_LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'

#: A small valid URDF: a revolute R1 about y, a mimicking revolute R2, a fixed tip, and
#: a side branch (joint "side", link "arm2") off the base.
GOOD = f"""<?xml version="1.0"?>
<robot name="para">
  <link name="base"/>
  <link name="rod"/>
  <link name="plate"/>
  <link name="tip"/>
  <link name="arm2"/>
  <joint name="R1" type="revolute">
    <parent link="base"/><child link="rod"/><axis xyz="0 1 0"/>{_LIMIT}
  </joint>
  <joint name="R2" type="revolute">
    <parent link="rod"/><child link="plate"/><origin xyz="1 0 0"/><axis xyz="0 1 0"/>{_LIMIT}
    <mimic joint="R1" multiplier="-1" offset="0"/>
  </joint>
  <joint name="T" type="fixed">
    <parent link="plate"/><child link="tip"/><origin xyz="0.5 0 0"/>
  </joint>
  <joint name="side" type="prismatic">
    <parent link="base"/><child link="arm2"/><axis xyz="0 0 1"/>{_LIMIT}
  </joint>
</robot>
"""


def _bad(old: str, new: str) -> str:
    assert old in GOOD
    return GOOD.replace(old, new, 1)


# ----------------------------------------------------------------------- sources
def test_source_may_be_xml_text_str_path_or_pathlib(tmp_path):
    """The same URDF as XML text, a str path and a pathlib.Path gives the same leg."""
    path = tmp_path / "para.urdf"
    path.write_text(GOOD)
    legs = [Leg.from_urdf(GOOD, "tip", ["R1"]), Leg.from_urdf(str(path), "tip", ["R1"]),
            Leg.from_urdf(path, "tip", ["R1"])]
    for leg in legs:
        assert leg.joint_names == ["R1"]
        assert leg.tip_placement([0.4]).isApprox(legs[0].tip_placement([0.4]), 1e-15)
    assert legs[0].source == "<string: robot 'para'>"
    assert legs[1].source == str(path)
    assert legs[0].name == "para"


def test_xml_text_with_leading_whitespace_is_text():
    """XML text with leading blank lines is read as text, not as a path."""
    leg = Leg.from_urdf("\n\n   " + GOOD.split("\n", 1)[1], "tip")
    assert leg.nv == 1


def test_read_returns_text_label_and_directory(tmp_path):
    """urdf.read gives the text, a label naming the file and its folder."""
    path = tmp_path / "para.urdf"
    path.write_text(GOOD)
    src = urdf.read(path)
    assert src.xml == GOOD
    assert src.label == str(path)
    assert src.directory == tmp_path
    assert src.robot.name == "para"
    assert urdf.read(GOOD).directory is None


def test_build_model_honours_mimic():
    """build_model turns the mimicking revolute into no extra coordinate."""
    model = urdf.build_model(urdf.read(GOOD))
    assert model.existJointName("R2")
    # R1 and the prismatic side branch are the coordinates; R2 follows R1
    assert model.nv == 2


def test_name_argument_overrides_robot_name():
    """Leg.from_urdf(name=...) names the leg."""
    assert Leg.from_urdf(GOOD, "tip", name="left").name == "left"


def test_fixed_joint_frame_may_be_the_tip():
    """A fixed joint's frame name is a valid tip, placed like its child link."""
    by_joint = Leg.from_urdf(GOOD, "T")
    by_link = Leg.from_urdf(GOOD, "tip")
    assert by_joint.tip_placement([0.3]).isApprox(by_link.tip_placement([0.3]), 1e-15)


def test_side_branch_is_locked_out_of_the_chain():
    """Joints of branches other than root→tip are not coordinates of the leg."""
    leg = Leg.from_urdf(GOOD, "tip")
    assert leg.joint_names == ["R1"]
    side = Leg.from_urdf(GOOD, "arm2", ["side"])
    assert side.joint_names == ["side"]
    np.testing.assert_allclose(side.jacobian([0.2])[:, 0], [0, 0, 0, 0, 0, 1], atol=1e-15)


# ------------------------------------------------------------------- UrdfError
def test_missing_file_names_the_path(tmp_path):
    """A missing file raises UrdfError naming the path."""
    missing = tmp_path / "nope" / "robot.urdf"
    with pytest.raises(UrdfError, match="no such file") as info:
        Leg.from_urdf(missing, "tip")
    assert str(missing) in str(info.value)
    assert info.value.source == str(missing)


def test_relative_missing_path_says_where_it_was_looked_for():
    """A missing relative path mentions the working folder it was taken from."""
    with pytest.raises(UrdfError, match="relative paths"):
        Leg.from_urdf("no_such_robot_here.urdf", "tip")


def test_malformed_xml_mentions_line():
    """Malformed XML raises UrdfError giving the line of the error."""
    text = GOOD.replace("</joint>", "</joint", 1)
    bad_line = next(i for i, ln in enumerate(text.splitlines(), 1) if "</joint" in ln)
    with pytest.raises(UrdfError, match="malformed XML") as info:
        Leg.from_urdf(text, "tip")
    lines = [int(n) for n in re.findall(r"line (\d+)", str(info.value))]
    assert lines and all(bad_line <= n <= bad_line + 1 for n in lines)


def test_malformed_xml_in_file_names_file_and_line(tmp_path):
    """Malformed XML in a file names the file and the line."""
    path = tmp_path / "broken.urdf"
    path.write_text(GOOD.replace('<link name="rod"/>', '<link name="rod">'))
    with pytest.raises(UrdfError, match=r"line \d+") as info:
        Leg.from_urdf(path, "tip")
    assert str(path) in str(info.value)


@pytest.mark.parametrize(
    "text, pattern",
    [
        (_bad('<child link="rod"/>', '<child link="rodd"/>'), r"'R1'.*'rodd'"),
        (_bad('<parent link="plate"/>', '<parent link="plates"/>'), r"'T'.*'plates'"),
        (_bad('mimic joint="R1"', 'mimic joint="R9"'), r"'R2'.*mimics 'R9'"),
        (_bad('mimic joint="R1"', 'mimic joint="T"'), r"'R2'.*mimics 'T'"),
        (_bad('<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>'), r"'R1'.*zero axis"),
        (_bad('<axis xyz="0 1 0"/>', '<axis xyz="0 1"/>'), r"'R1' axis"),
        (_bad('<axis xyz="0 1 0"/>', '<axis xyz="0 nan 1"/>'), r"'R1' axis"),
        (_bad('<origin xyz="1 0 0"/>', '<origin xyz="1 0 x"/>'), r"'R2' origin"),
        (_bad(_LIMIT, _LIMIT.replace('lower="-1" upper="1"', 'lower="1" upper="-1"')),
         r"'R1'.*lower=1.0 > upper=-1.0"),
        (_bad(_LIMIT, ""), r"'R1'.*no <limit>"),
        (_bad('<link name="arm2"/>', '<link name="arm2"/><link name="rod"/>'),
         r"link names must be unique.*'rod'"),
        (_bad('name="T"', 'name="R1"'), r"joint names must be unique.*'R1'"),
        (_bad('<link name="arm2"/>', '<link name="arm2"/><link name="stray"/>'),
         r"one root.*'base'.*'stray'"),
        (_bad('type="fixed"', 'type="hinge"'), r"'T' has type 'hinge'"),
        (_bad("</robot>", '<joint name="extra" type="fixed"><parent link="arm2"/>'
                          '<child link="rod"/></joint></robot>'),
         r"'rod' is the child of two joints"),
        ("<robt name='x'><link name='a'/></robt>", r"<robot>"),
        ("<robot name='x'></robot>", r"no <link>"),
    ],
    ids=["missing-child-link", "missing-parent-link", "mimic-unknown", "mimic-fixed",
         "zero-axis", "short-axis", "nan-axis", "bad-origin", "lower-above-upper",
         "no-limit", "duplicate-link", "duplicate-joint", "two-roots", "bad-type",
         "two-parents", "not-robot", "no-link"],
)
def test_malformed_urdf_gives_specific_urdf_error(text, pattern):
    """Each structural mistake gets a UrdfError whose message names the culprit."""
    with pytest.raises(UrdfError) as info:
        Leg.from_urdf(text, "tip")
    assert re.search(pattern, str(info.value)), str(info.value)
    assert str(info.value).startswith("URDF <string")


def test_missing_link_error_lists_existing_links():
    """A joint naming a missing link lists the links that exist."""
    with pytest.raises(UrdfError) as info:
        Leg.from_urdf(_bad('<child link="rod"/>', '<child link="rodd"/>'), "tip")
    for link in ("base", "rod", "plate", "tip", "arm2"):
        assert repr(link) in str(info.value)


def test_loop_is_reported():
    """Joints forming a loop (and hence no single root) raise UrdfError."""
    loop = _bad("</robot>", """<joint name="back" type="fixed">
    <parent link="tip"/><child link="base"/></joint></robot>""")
    with pytest.raises(UrdfError, match="(loop|root)"):
        Leg.from_urdf(loop, "tip")


def test_urdf_error_is_a_pkm_error_and_chains_parser_error():
    """UrdfError is a PkmError; the XML parser's error is kept as its cause."""
    with pytest.raises(UrdfError) as info:
        Leg.from_urdf(GOOD.replace("</joint>", "</joint", 1), "tip")
    assert isinstance(info.value, PkmError)
    assert info.value.__cause__ is not None


# --------------------------------------------------------------- FrameNotFound
def test_unknown_tip_raises_frame_not_found_listing_frames():
    """A tip that is not a link or frame raises FrameNotFound listing existing frames."""
    with pytest.raises(FrameNotFound) as info:
        Leg.from_urdf(GOOD, "tool0")
    err = info.value
    assert err.name == "tool0"
    assert {"base", "rod", "plate", "tip", "arm2"} <= set(err.frames)
    message = str(err)
    assert "'tool0'" in message
    for link in ("base", "rod", "plate", "tip", "arm2"):
        assert repr(link) in message
    assert isinstance(err, PkmError) and isinstance(err, KeyError)


def test_unknown_tip_of_example_robot(ur5):
    """An unknown tip of an example robot lists that robot's frames."""
    with pytest.raises(FrameNotFound, match="tool0"):
        Leg.from_example_robot_data("ur5", "tool_99")


# --------------------------------------------------------------- JointNotFound
@pytest.mark.parametrize(
    "actuated, tip",
    [("T", "tip"), ("nope", "tip"), ("side", "tip"), ("R2", "tip"), ("R1", "arm2")],
    ids=["fixed-joint", "nonexistent", "other-branch", "mimicking-joint", "not-on-chain"],
)
def test_bad_actuated_name_raises_joint_not_found(actuated, tip):
    """An actuated name that is not a movable joint of root→tip raises JointNotFound
    listing the movable joints of the chain."""
    with pytest.raises(JointNotFound) as info:
        Leg.from_urdf(GOOD, tip, [actuated])
    err = info.value
    assert err.name == actuated
    expected = ["R1"] if tip == "tip" else ["side"]
    assert err.joints == expected
    assert repr(actuated) in str(err) and repr(expected[0]) in str(err)
    assert isinstance(err, PkmError)


def test_panda_finger_joint_is_not_on_the_arm_chain():
    """Actuating panda_finger_joint1 with tip panda_link8 raises JointNotFound."""
    path = urdf.example_robot_path("panda")
    with pytest.raises(JointNotFound) as info:
        Leg.from_urdf(path, "panda_link8", ["panda_joint1", "panda_finger_joint1"])
    assert info.value.name == "panda_finger_joint1"
    assert info.value.joints == [f"panda_joint{i}" for i in range(1, 8)]
    with pytest.raises(JointNotFound):
        Leg.from_example_robot_data("panda", "panda_link8", actuated=["panda_finger_joint1"])


def test_actuated_joint_listed_twice_is_rejected():
    """An actuated joint listed twice is an error, not a silent duplicate."""
    with pytest.raises(PkmError, match="twice"):
        Leg.from_urdf(GOOD, "tip", ["R1", "R1"])


# ----------------------------------------------------------- example-robot-data
def test_example_robot_data_ur5_and_panda(ur5, panda):
    """from_example_robot_data loads UR5 (tool0) and Panda (panda_link8) with every joint
    actuated and finite limits."""
    assert ur5.source.endswith("ur5_robot.urdf")
    assert panda.source.endswith("panda.urdf")
    assert ur5.actuated == tuple(ur5.joint_names) and len(ur5.actuated) == 6
    assert panda.actuated == tuple(panda.joint_names) and len(panda.actuated) == 7
    for leg in (ur5, panda):
        assert np.all(np.isfinite(leg.lower)) and np.all(leg.lower < leg.upper)


def test_example_robot_data_with_actuated_subset_and_base():
    """from_example_robot_data takes an actuated subset and a base placement."""
    base = pin.SE3(np.eye(3), np.array([0.0, 0.0, 1.0]))
    leg = Leg.from_example_robot_data("ur5", actuated=["elbow_joint"], base=base)
    assert leg.actuated == ("elbow_joint",)
    np.testing.assert_array_equal(leg.actuated_v, [2])
    plain = Leg.from_example_robot_data("ur5")
    q = np.full(6, 0.3)
    assert leg.tip_placement(q).isApprox(base * plain.tip_placement(q), 1e-14)


def test_example_robot_path_of_unknown_name_lists_known_names():
    """An unknown example robot name raises UrdfError listing the known names."""
    with pytest.raises(UrdfError, match="ur5") as info:
        Leg.from_example_robot_data("r2d2")
    assert "panda" in str(info.value)


def test_example_robot_by_relative_path_needs_a_tip():
    """A robot given by its relative .urdf path loads with an explicit tip."""
    leg = Leg.from_example_robot_data("ur_description/urdf/ur5_robot.urdf", "tool0")
    assert leg.nv == 6
    with pytest.raises(PkmError):
        Leg.from_example_robot_data("ur_description/urdf/ur5_robot.urdf")
