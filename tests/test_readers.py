"""Readers of closed-loop files: Extended URDF + YAML (Gepetto's layout) and MJCF."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pkm_pin.errors import ClosureFileError, MechanismFileError
from pkm_pin.model import find_closures_file, read_extended_urdf, read_mjcf
from pkm_pin.model.mjcf import WORLD_BODY

ROOT = Path(__file__).resolve().parents[1]
GEPETTO = ROOT / "tests" / "data" / "gepetto"
LOOPS = ROOT / "models" / "loops"


# ------------------------------------------------------------------ published models
def test_gepetto_5bar_loads_unchanged():
    """Gepetto's 5bar_linkage: a 6d weld between two revolute joints' frames, motors by
    name, output 'effector'; open at q = 0; mobility 3 = 2 DOF + the two coaxial closing
    revolutes' idle turn, 3 redundant planar rows."""
    model = read_extended_urdf(GEPETTO / "5bar_linkage" / "robot.urdf")
    (closure,) = model.closures
    assert (closure.kind, closure.name) == ("weld", "closedloop1_ACclosedloop1_B")
    assert model.tree.frames[model.tree.getFrameId("closedloop1_A")].type == pin.FrameType.JOINT
    assert model.actuated == ("mot1", "mot2") and model.output == "effector"
    assert model.nv == 6 and np.abs(model.closure_residual(model.reference)).max() > 0.1
    assert model.mobility(model.reference) == 3
    assert model.redundant_constraints(model.reference) == 3


def test_gepetto_5bar_iso3d_loads_unchanged():
    """Gepetto's 5bar_linkage_iso3d: a 3d point between links on fixed joints; name_mot
    ['mot2', 'mot1'] gives the actuated joints in tree order (the toolbox's ActuationModel);
    nearly closed at q = 0 (CAD export), mobility 2, no redundant row."""
    model = read_extended_urdf(GEPETTO / "5bar_linkage_iso3d" / "robot.urdf")
    (closure,) = model.closures
    assert (closure.kind, closure.frame_a, closure.frame_b) == (
        "point", "closedloop3D_1B", "closedloop3D_1A")
    assert model.actuated == ("mot2", "mot1") and model.output == "effector"
    residual = model.closure_residual(model.reference)
    assert np.abs(residual).max() == pytest.approx(3.727e-3, rel=1e-3)
    assert model.mobility(model.reference) == 2
    assert model.redundant_constraints(model.reference) == 0


def test_free_flyer_adds_root_joint():
    """free_flyer=True puts Pinocchio's 'root_joint' free flyer under the root link."""
    model = read_extended_urdf(GEPETTO / "5bar_linkage" / "robot.urdf", free_flyer=True)
    assert model.tree.names[1] == "root_joint" and model.nv == 12 and model.nq == 13


# ------------------------------------------------------------------------ files & keys
def copy_model(tmp_path: Path, name: str = "five_bar") -> Path:
    """A copy of models/loops/<name>.urdf (without its YAML) in tmp_path."""
    shutil.copy(LOOPS / f"{name}.urdf", tmp_path / f"{name}.urdf")
    return tmp_path / f"{name}.urdf"


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


FIVE_BAR_YAML = ("closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['3d']\n"
                 "name_mot: ['mot1', 'mot2']\n")


def test_closures_file_is_found_beside_the_urdf(tmp_path):
    """Same stem first, then robot.yaml; closures_path names another file; TOML reads alike."""
    urdf = copy_model(tmp_path)
    write(tmp_path / "robot.yaml", FIVE_BAR_YAML)
    assert find_closures_file(urdf) == tmp_path / "robot.yaml"
    write(tmp_path / "five_bar.yaml", FIVE_BAR_YAML.replace("3d", "6D"))
    assert find_closures_file(urdf) == tmp_path / "five_bar.yaml"
    assert read_extended_urdf(urdf).closures[0].kind == "weld"
    assert read_extended_urdf(urdf, tmp_path / "robot.yaml").closures[0].kind == "point"
    toml = write(tmp_path / "c.toml", 'closed_loop = [["closedloop1_A", "closedloop1_B"]]\n'
                 'type = ["3D"]\nname_mot = ["mot1", "mot2"]\noutput = "distal2"\n')
    model = read_extended_urdf(urdf, toml)
    assert model.closures[0].kind == "point" and model.output == "distal2"


def test_output_frame_rules(tmp_path):
    """output= overrides; else 'effector'; else the last link that no closure uses."""
    urdf = copy_model(tmp_path)
    write(tmp_path / "five_bar.yaml", FIVE_BAR_YAML)
    assert read_extended_urdf(urdf).output == "effector"
    assert read_extended_urdf(urdf, output="proximal2").output == "proximal2"
    text = urdf.read_text().replace('"effector"', '"tool"')
    write(urdf, text)
    assert read_extended_urdf(urdf).output == "distal2"


def test_output_point_key(tmp_path):
    """output_point (YAML or TOML, our key) makes the output frame's origin a point; its
    default is false (a body); output= keeps the file's choice."""
    urdf = copy_model(tmp_path)
    write(tmp_path / "five_bar.yaml", FIVE_BAR_YAML)
    assert not read_extended_urdf(urdf).output_point
    write(tmp_path / "five_bar.yaml", FIVE_BAR_YAML + "output_point: true\n")
    assert read_extended_urdf(urdf).output_point
    assert read_extended_urdf(urdf, output="distal2").output_point
    toml = write(tmp_path / "c.toml", 'closed_loop = [["closedloop1_A", "closedloop1_B"]]\n'
                 'type = ["3d"]\nname_mot = ["mot1", "mot2"]\noutput_point = true\n')
    assert read_extended_urdf(urdf, toml).output_point


def test_name_mot_matches_by_substring_in_tree_order(tmp_path):
    """name_mot ['mot'] actuates every joint whose name contains 'mot', in tree order."""
    urdf = copy_model(tmp_path)
    write(tmp_path / "five_bar.yaml", FIVE_BAR_YAML.replace("['mot1', 'mot2']", "['mot']"))
    assert read_extended_urdf(urdf).actuated == ("mot1", "mot2")


def test_joint_replacements(tmp_path):
    """UJOINT_ZY gives <j>_Z then <j>_Y carrying the body and frames; CARDAN is UJOINT_XY;
    SPHERICAL keeps the name (nq 4); FIXED locks the joint at 0 and keeps its frames."""
    urdf = copy_model(tmp_path)
    write(tmp_path / "five_bar.yaml", FIVE_BAR_YAML + "joint_name: ['free1', 'free2']\n"
          "joint_type: ['UJOINT_ZY', 'SPHERICAL']\n")
    model = read_extended_urdf(urdf)
    names = list(model.tree.names)
    assert names[names.index("free1_Z") + 1] == "free1_Y" and "free1" not in names
    assert model.tree.joints[model.tree.getJointId("free2")].nq == 4
    frame = model.tree.frames[model.tree.getFrameId("closedloop1_A")]
    assert frame.parentJoint == model.tree.getJointId("free1_Y")
    write(tmp_path / "five_bar.yaml", FIVE_BAR_YAML + "joint_name: ['free1', 'free2']\n"
          "joint_type: ['CARDAN', 'FIXED']\n")
    model = read_extended_urdf(urdf)
    assert {"free1_X", "free1_Y"} <= set(model.tree.names) and "free2" not in model.tree.names
    assert model.nv == 4 and model.tree.existFrame("closedloop1_B")


def test_revolutes_named_spherical_follow_generate_yaml_without_joint_name(tmp_path):
    """Without a joint_name list a revolute whose name contains 'spherical' is a spherical
    joint (Gepetto's generateYAML writes such joints into joint_name as SPHERICAL), with
    a note; 'joint_name: []' keeps it revolute, without that note; a revolute named like
    a spherical joint otherwise ('sherical') stays revolute, with a note."""
    text = (LOOPS / "five_bar.urdf").read_text()
    assert text.count('"free2"') == 1 and text.count('"free1"') == 1
    text = text.replace('"free2"', '"spherical_free2"').replace('"free1"', '"sherical_1"')
    urdf = write(tmp_path / "five_bar.urdf", text)
    write(tmp_path / "five_bar.yaml", FIVE_BAR_YAML)
    model = read_extended_urdf(urdf)
    tree = model.tree
    assert tree.joints[tree.getJointId("spherical_free2")].nq == 4
    assert tree.joints[tree.getJointId("sherical_1")].nq == 1
    assert len(model.notes) == 2
    assert model.notes[0].startswith("the revolutes named '*spherical*' (1: "
                                     "'spherical_free2') are read as spherical joints")
    assert model.notes[1].startswith("revolute joint 'sherical_1' named like a spherical "
                                     "joint stays revolute")
    write(tmp_path / "five_bar.yaml", FIVE_BAR_YAML + "joint_name: []\njoint_type: []\n")
    model = read_extended_urdf(urdf)
    assert model.tree.joints[model.tree.getJointId("spherical_free2")].nq == 1
    (note,) = model.notes
    assert note.startswith("revolute joints 'sherical_1', 'spherical_free2' named like a "
                           "spherical joint stay revolute")


def test_ankle_model_uses_ujoint_and_spherical():
    """models/loops/ankle: the foot on ankle_X then ankle_Y, both rods on ball joints."""
    model = read_extended_urdf(LOOPS / "ankle.urdf")
    assert [model.tree.names[j] for j in (1, 2)] == ["ankle_X", "ankle_Y"]
    assert model.tree.joints[model.tree.getJointId("rod_1_ball")].shortname() == \
        "JointModelSpherical"


# ------------------------------------------------------------------------- bad input
BAD_YAML = [
    ("type: []\nname_mot: []\n", "closed_loop", "is missing"),
    ("closed_loop: [['nowhere', 'closedloop1_B']]\ntype: ['3d']\nname_mot: ['mot1']\n",
     "closed_loop[0][0]", "'nowhere' is not in the URDF"),
    ("closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['5d']\nname_mot: []\n",
     "type[0]", "unknown closure type '5d'"),
    ("closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['3d', '3d']\nname_mot: []\n",
     "type", "has 2 entries but closed_loop has 1"),
    (FIVE_BAR_YAML + "joint_name: ['free1']\njoint_type: []\n", "joint_type",
     "has 0 entries but joint_name has 1"),
    (FIVE_BAR_YAML.replace("'mot2'", "'motor9'"), "name_mot[1]", "'motor9' matches no"),
    (FIVE_BAR_YAML + "joint_name: ['free1']\njoint_type: ['BALL']\n", "joint_type[0]",
     "unknown joint type 'BALL'"),
    (FIVE_BAR_YAML + "joint_name: ['nojoint']\njoint_type: ['FIXED']\n", "joint_name[0]",
     "'nojoint' is not a movable joint"),
    ("closed_loop: [['a', 'b']\ntype: ['3d']\n", "", "not valid YAML at line"),
    (FIVE_BAR_YAML + "closed_loops: []\n", "closed_loops", "unknown key"),
    ("closed_loop: [['closedloop1_A']]\ntype: ['3d']\nname_mot: []\n", "closed_loop[0]",
     "must be a pair"),
    (FIVE_BAR_YAML + "output: nowhere\n", "output", "'nowhere' is not in the URDF"),
    (FIVE_BAR_YAML + "output_point: 'yes'\n", "output_point", "must be true or false"),
    ("- just\n- a list\n", "", "must be a mapping"),
]


@pytest.mark.parametrize("text,where,reason", BAD_YAML)
def test_bad_closures_file_is_one_line_naming_file_and_entry(tmp_path, text, where, reason):
    """Every mistake in a closures file is a one-line ClosureFileError naming file and entry."""
    urdf = copy_model(tmp_path)
    path = write(tmp_path / "five_bar.yaml", text)
    with pytest.raises(ClosureFileError) as info:
        read_extended_urdf(urdf)
    message = str(info.value)
    assert isinstance(info.value, MechanismFileError) and "\n" not in message
    assert info.value.path == str(path) and info.value.where == where and reason in message


def test_missing_closures_file_and_bad_urdf(tmp_path):
    """No YAML beside the URDF, and malformed URDF XML, are ClosureFileErrors naming the file."""
    urdf = copy_model(tmp_path)
    with pytest.raises(ClosureFileError, match="no closures file beside it") as info:
        read_extended_urdf(urdf)
    assert info.value.path == str(urdf)
    write(tmp_path / "five_bar.yaml", FIVE_BAR_YAML)
    write(urdf, urdf.read_text().replace("</robot>", ""))
    with pytest.raises(ClosureFileError, match="malformed XML at line") as info:
        read_extended_urdf(urdf)
    assert info.value.path == str(urdf) and info.value.where == "URDF"
    with pytest.raises(ClosureFileError, match="no such closures file"):
        read_extended_urdf(urdf, tmp_path / "none.yaml")


# ---------------------------------------------------------------------------- MJCF
MJCF = """<mujoco model="loop">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base">
      <body name="crank" pos="0 0 0" axisangle="0 0 1 1.0">
        <joint name="crank_joint" type="hinge" axis="0 0 1" ref="{ref}"/>
        <body name="coupler" pos="0.03 0 0" axisangle="0 0 1 -0.6">
          <joint name="coupler_joint" type="hinge" axis="0 0 1"/>
          <site name="coupler_tip" pos="0.09 0 0"/>
        </body>
      </body>
      <body name="rocker" pos="0.1 0 0" axisangle="0 0 1 1.4">
        <joint name="rocker_joint" type="hinge" axis="0 0 1"/>
        <site name="rocker_tip" pos="0.07 0 0"/>
      </body>
    </body>
  </worldbody>
  <equality>{equality}</equality>
  <actuator><motor name="m" joint="crank_joint"/></actuator>
</mujoco>
"""
CONNECT = '<connect name="c" body1="coupler" body2="rocker" anchor="0.09 0 0"/>'


def test_mjcf_closures_match_pinocchio_constraint_models(tmp_path):
    """With one root body (Pinocchio parses it), our connect/weld closures are Pinocchio's
    constraint models (which list the points first): same joints, same points and weld
    frames; names kept (Pinocchio's are '')."""
    eq = CONNECT + '<weld body1="coupler" body2="rocker" anchor="0.01 0.02 0"/>' \
        '<connect site1="coupler_tip" site2="rocker_tip"/>'
    path = write(tmp_path / "loop.xml", MJCF.format(ref=0, equality=eq))
    model = read_mjcf(path)
    _, legacy = pin.buildModelAndLegacyConstraintsFromMJCF(str(path))
    assert [c.name for c in legacy] == ["", "", ""]
    assert [c.name for c in model.closures] == ["c", "weld0", "connect1"]
    tree = model.tree
    ours_sorted = sorted(model.closures, key=lambda c: c.kind == "weld")  # Pinocchio: 3D first
    assert [str(c.type) for c in legacy] == ["CONTACT_3D", "CONTACT_3D", "CONTACT_6D"]
    for ours, theirs in zip(ours_sorted, legacy):
        for frame, placement, jid, jplace in (
                (ours.frame_a, ours.placement_a, theirs.joint1_id, theirs.joint1_placement),
                (ours.frame_b, ours.placement_b, theirs.joint2_id, theirs.joint2_placement)):
            f = tree.frames[tree.getFrameId(frame)]
            assert f.parentJoint == jid
            M = f.placement * placement
            if ours.kind == "point":  # a point closure: only the origin matters
                assert np.allclose(M.translation, jplace.translation, atol=1e-12)
            else:
                assert np.allclose(M.homogeneous, jplace.homogeneous, atol=1e-12)
    assert model.actuated == ("crank_joint",) and model.output == "rocker"
    residual = model.closure_residual(model.reference)
    assert np.abs(residual[:9]).max() < 1e-12  # body connect and weld hold at qpos0


def test_mjcf_reference_is_qpos0_and_connect_holds_there(tmp_path):
    """A joint's ref (rad) is the reference; the body connect holds at qpos0, not at 0."""
    path = write(tmp_path / "loop.xml", MJCF.format(ref=0.2, equality=CONNECT))
    model = read_mjcf(path)
    assert model.reference[0] == pytest.approx(0.2)
    assert np.abs(model.closure_residual(model.reference)).max() < 1e-12
    assert np.abs(model.closure_residual(np.zeros(3))).max() > 1e-3
    assert model.mobility(model.reference) == 1


def test_mjcf_weld_relpose(tmp_path):
    """A weld with relpose holds where body2 sits at relpose in body1."""
    eq = '<weld body1="crank" body2="coupler" relpose="0.03 0 0 1 0 0 0"/>'
    model = read_mjcf(write(tmp_path / "w.xml", MJCF.format(ref=0, equality=eq)))
    q = model.reference.copy()
    assert np.abs(model.closure_residual(q)[:3]).max() == pytest.approx(0.6, abs=1e-12)
    q[1] = 0.6  # coupler unrotated in the crank: relpose holds
    assert np.abs(model.closure_residual(q)).max() < 1e-12


def test_mjcf_several_world_bodies_are_kept(tmp_path):
    """Pinocchio 4.1 keeps only the first body under <worldbody>; read_mjcf keeps all
    (our four-bar with its joint-less base body unwrapped)."""
    text = (LOOPS / "four_bar.xml").read_text()
    text = text.replace('<body name="base">', "").replace("    </body>\n  </worldbody>",
                                                           "  </worldbody>")
    path = write(tmp_path / "four_bar.xml", text)
    assert pin.buildModelFromMJCF(str(path)).njoints == 3
    assert pin.buildModelFromMJCF(str(LOOPS / "four_bar.xml")).njoints == 4
    model = read_mjcf(path)
    assert list(model.tree.names) == ["universe", "crank_joint", "coupler_joint",
                                      "rocker_joint"]
    assert model.tree.existFrame(WORLD_BODY)


def test_mjcf_without_equality_is_a_tree(tmp_path):
    """No <equality>: no closures; mobility = nv (a serial/branching chain)."""
    text = MJCF.format(ref=0, equality="").replace("<equality></equality>", "")
    model = read_mjcf(write(tmp_path / "tree.xml", text))
    assert model.closures == () and model.mobility(model.reference) == model.nv == 3


BAD_MJCF = [
    (MJCF.format(ref=0, equality=CONNECT.replace('body2="rocker"', 'body2="ghost"')),
     "equality/connect[0] 'c' body2", "'ghost' is not a body"),
    (MJCF.format(ref=0, equality='<connect site1="coupler_tip" site2="nosite"/>'),
     "equality/connect[0] site2", "'nosite' is not a site"),
    (MJCF.format(ref=0, equality='<joint joint1="crank_joint" joint2="rocker_joint" '
                 'polycoef="0 1 0.5"/>'),
     "equality/joint[0]", "by a polynomial of degree 2 (polycoef '0 1 0.5'); pkm_pin reads "
     "linear couplings only"),
    (MJCF.format(ref=0, equality='<joint joint1="ghost" joint2="rocker_joint"/>'),
     "equality/joint[0] joint1", "'ghost' is not a hinge or slide joint"),
    (MJCF.format(ref=0, equality='<tendon tendon1="t"/>'),
     "equality/tendon[0]", "couples tendon lengths"),
    (MJCF.format(ref=0, equality=CONNECT).replace('joint="crank_joint"', 'tendon="t"'),
     "actuator/motor[0] 'm' tendon", "'t' is not a tendon of the file"),
    (MJCF.format(ref=0, equality=CONNECT).replace('joint="crank_joint"', 'site="coupler_tip"'),
     "actuator/motor[0] 'm'", "drives a site (a force or moment at a point)"),
    (MJCF.format(ref=0, equality=CONNECT).replace('joint="crank_joint"', 'tendon="sp"')
     .replace("<actuator>", '<tendon><spatial name="sp"><site site="coupler_tip"/>'
              '<site site="rocker_tip"/></spatial></tendon><actuator>'),
     "actuator/motor[0] 'm'", "drives the spatial tendon 'sp'"),
    (MJCF.format(ref=0, equality=CONNECT).replace('joint="crank_joint"', 'tendon="diff"')
     .replace("<actuator>", '<tendon><fixed name="diff"><joint joint="crank_joint" coef="1"/>'
              '<joint joint="rocker_joint" coef="1"/></fixed></tendon><actuator>'),
     "actuator/motor[0] 'm'", "a differential of several independent joints"),
    (MJCF.format(ref=0, equality=CONNECT).replace('joint="crank_joint"', 'joint="j9"'),
     "actuator/motor[0] 'm'", "joint 'j9' is not a joint"),
    (MJCF.format(ref=0, equality=CONNECT.replace('anchor="0.09 0 0"', 'anchor="0.09 0"')),
     "equality/connect[0] 'c' anchor", "must be 3 finite numbers"),
    (MJCF.format(ref=0, equality=CONNECT).replace("</mujoco>", ""), "", "malformed XML"),
    ("<robot/>", "", "an MJCF's must be <mujoco>"),
]


@pytest.mark.parametrize("text,where,reason", BAD_MJCF)
def test_bad_mjcf_is_one_line_naming_file_and_element(tmp_path, text, where, reason):
    """Every mistake in an MJCF is a one-line ClosureFileError naming file and element."""
    path = write(tmp_path / "bad.xml", text)
    with pytest.raises(ClosureFileError) as info:
        read_mjcf(path)
    assert "\n" not in str(info.value) and info.value.path == str(path)
    assert info.value.where == where and reason in str(info.value)


def test_missing_mjcf(tmp_path):
    """A missing MJCF file is a ClosureFileError naming it."""
    with pytest.raises(ClosureFileError, match="no such MJCF file"):
        read_mjcf(tmp_path / "none.xml")
