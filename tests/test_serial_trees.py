"""Trees without closures read from published-style files: a plain URDF without a
closures file (a serial arm) and kinematically redundant arms (more independent actuators
than the output's directions of motion)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pkm_pin import load_mechanism
from pkm_pin.cli import main
from pkm_pin.errors import ClosureFileError

LINK = """<body name="l{k}" pos="0 0 0.1" euler="0.3 0.2 0.1">
<joint name="j{k}" axis="{axis}"/><geom type="sphere" size="0.01"/>{inner}</body>"""


def arm_mjcf(n: int) -> str:
    """An nR arm with alternating z / y axes, every joint actuated (MJCF)."""
    inner = ""
    for k in range(n, 0, -1):
        inner = LINK.format(k=k, axis="0 0 1" if k % 2 else "0 1 0", inner=inner)
    motors = "".join(f'<motor joint="j{k}"/>' for k in range(1, n + 1))
    return (f'<mujoco model="arm{n}"><worldbody>{inner}</worldbody>'
            f"<actuator>{motors}</actuator></mujoco>")


@pytest.fixture
def arm(tmp_path):
    def write(n: int) -> Path:
        path = tmp_path / f"arm{n}.xml"
        path.write_text(arm_mjcf(n))
        return path
    return write


Q7 = np.array([0.3, -0.7, 0.4, 1.1, -0.5, 0.8, 0.2])


def test_a_7r_arm_reports_its_redundancy(arm, capsys):
    """Seven actuated revolutes for a body output (six directions): a self-motion at
    every configuration (the output Jacobian's null space, checked here), so the type I
    and inverse indices are 0 by their definitions and the class is I at a generic
    configuration too, which the report explains as a redundancy of 1 (4 for the
    output's origin as a point), not a singular pose. The 6R arm made of its first six
    joints has no redundancy and positive type I and inverse indices there."""
    mech = load_mechanism(arm(7))
    an = mech.analyze(mech.assemble(Q7))
    J = an.joint_twists[list(mech.model.actuated_v)]  # (7, 6): the output's twists
    assert np.linalg.matrix_rank(J.T, tol=1e-9) == 6  # 6 directions, 7 rates: one null
    assert (an.dof, an.output_dof, an.redundancy) == (7, 6, 1)
    assert an.indices["type_I"] == 0.0 and an.indices["inverse"] < 1e-9
    assert an.singularity == "I" and an.indices["forward"] > 0.1
    assert main(["analyze", str(arm(7))]) == 0
    text = capsys.readouterr().out
    assert "kinematically redundant: 7 independent actuators" in text
    assert "at least 1 self-motion" in text and "not a singular pose" in text
    six = load_mechanism(arm(6))
    an6 = six.analyze(six.assemble(Q7[:6]))
    assert an6.redundancy == 0 and an6.singularity == "none"
    assert an6.indices["type_I"] > 1e-3 and an6.indices["inverse"] > 1e-3
    assert main(["analyze", str(arm(6))]) == 0
    assert "redundancy" not in capsys.readouterr().out


def test_the_redundancy_of_a_point_output_counts_three_directions(arm, capsys):
    """The 7R arm's last body origin as a point output: 7 − 3 = 4 self-motions at
    least."""
    assert main(["analyze", str(arm(7)), "--point"]) == 0
    assert "at least 4 self-motions" in capsys.readouterr().out


PLANAR_2R = """<?xml version="1.0"?>
<robot name="planar2r">
  <link name="base"/>
  <link name="upper"/>
  <link name="fore"/>
  <link name="hand"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="wrist_fixed" type="fixed"><parent link="fore"/><child link="hand"/>
    <origin xyz="0.25 0 0"/></joint>
</robot>
"""


def test_a_urdf_read_without_closures_is_its_tree(tmp_path, capsys):
    """A plain URDF has no closures file: refused with a sentence that offers
    `--closures none`; with it, the URDF's tree, every movable joint actuated, with a
    note saying so; the elbow's twist is the closed form's (ω; p × ω), p its axis
    point 0.3 m along the upper arm."""
    urdf = tmp_path / "planar2r.urdf"
    urdf.write_text(PLANAR_2R)
    with pytest.raises(ClosureFileError, match="no closures file beside it.*--closures FILE"
                       ".*--closures none to read the URDF as a tree"):
        load_mechanism(urdf)
    mech = load_mechanism(urdf, closures="none")
    assert mech.actuated == ("shoulder", "elbow") and not mech.model.closures
    assert any("read as a tree without closures" in n for n in mech.model.notes)
    an = mech.analyze(mech.assemble(np.array([0.4, 0.9])))
    assert an.dof == 2 and an.singularity == "none" and an.redundancy == 0
    p = 0.3 * np.array([np.cos(0.4), np.sin(0.4), 0.0])
    omega = np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(an.joint_twists[1], np.r_[omega, np.cross(p, omega)],
                               atol=1e-12)
    assert main(["analyze", str(urdf), "--closures", "none", "--q", "0.4", "0.9"]) == 0
    assert "read as a tree without closures" in capsys.readouterr().out


def test_an_unreachable_pose_is_said_so_not_a_loop_that_does_not_close(tmp_path):
    """The planar 2R (reach 0.55 m) asked for its hand 3 m along y: the error says the
    output cannot reach the pose, with its residual, and gives no hint about closure
    frames (it has none: every loop closes)."""
    import pinocchio as pin

    from pkm_pin.errors import AssemblyError

    urdf = tmp_path / "planar2r.urdf"
    urdf.write_text(PLANAR_2R)
    mech = load_mechanism(urdf, closures="none")
    with pytest.raises(AssemblyError) as info:
        mech.inverse_kinematics(pin.SE3(np.eye(3), np.array([0.0, 3.0, 0.0])))
    text = str(info.value)
    assert text.startswith("the output cannot reach the pose: the best configuration")
    assert "closure frames" not in text and "does not close" not in text


def test_a_tree_whose_zero_is_outside_a_joints_range_starts_inside_it(tmp_path):
    """A joint whose range excludes 0 (Franka Panda's joint 4: [−3.07, −0.07]): read
    without closures, the reference puts it at the middle of its range (a note says
    which), so home respects the limits and the default dynamics motion runs; an
    actuator whose home sits at a limit stays there in the default motion."""
    from pkm_pin.trajectory import default_motion

    urdf = tmp_path / "planar2r.urdf"
    urdf.write_text(PLANAR_2R.replace('<limit lower="-3" upper="3" effort="1" velocity="1"/>'
                                      '</joint>\n  <joint name="wrist_fixed"',
                                      '<limit lower="-3.07" upper="-0.07" effort="1" '
                                      'velocity="1"/></joint>\n  <joint name="wrist_fixed"'))
    mech = load_mechanism(urdf, closures="none")
    np.testing.assert_allclose(mech.model.reference, [0.0, -1.57], atol=1e-15)
    assert any("elbow at the middle of its range" in n for n in mech.model.notes)
    motion = default_motion(mech.model, mech.home_assembly.q)
    assert motion.amplitude.tolist() == pytest.approx([0.1, 0.1])
    at_limit = default_motion(mech.model, np.array([0.0, -0.07]))
    assert at_limit.amplitude[1] == 0.0 and at_limit.amplitude[0] > 0


def test_an_arm_with_a_passive_joint_is_under_actuated_not_singular(arm, tmp_path, capsys):
    """The 6R arm plus a seventh revolute without a motor, its last body as the output
    (the default output is the sixth, which the motors move): with the six motors locked
    the output still turns about j7's axis, at this configuration and every one nearby
    (the ranks are generic): under-actuation 1, which the report tells from a singular
    pose; class II holds (forward index 0). The fully actuated 6R arm has none."""
    path = tmp_path / "passive.xml"
    path.write_text(arm_mjcf(7).replace('<motor joint="j7"/>', ""))
    assert load_mechanism(path).output == "l6"  # the default: the body the motors move
    mech = load_mechanism(path, output="l7")
    an = mech.analyze(mech.assemble(Q7))
    assert mech.actuated == ("j1", "j2", "j3", "j4", "j5", "j6")
    assert an.mobility.singular is False and an.idle_dof == 1
    assert an.underactuation == 1 and an.singularity in ("II", "III")
    assert an.indices["forward"] < 1e-9
    assert main(["analyze", str(path), "--output", "l7"]) == 0
    assert "under-actuated     the output moves with every actuator locked (1 direction)" \
        in capsys.readouterr().out
    six = load_mechanism(arm(6))
    assert six.analyze(six.assemble(Q7[:6])).underactuation == 0


def test_gepetto_disney_like_is_under_actuated_at_home():
    """Gepetto's disney_like (its hip group spins with every motor locked, class III at
    home in the corpus table): under-actuated, one output direction."""
    path = Path(__file__).parent / "data" / "gepetto" / "disney_like" / "robot.urdf"
    mech = load_mechanism(path)
    an = mech.analyze(mech.home_assembly)
    assert an.singularity == "III" and an.underactuation == 1


def test_a_mimic_joint_of_a_tree_follows_its_joint(tmp_path):
    """Read without closures, a URDF <mimic> joint (a gripper's second finger) follows
    its joint, twice its rate here: not actuated, and its body's twist is the closed
    form's, 2 × the elbow's rate about its own axis plus the arm's."""
    text = PLANAR_2R.replace("</robot>", """  <link name="finger"/>
  <joint name="finger_joint" type="revolute"><parent link="hand"/><child link="finger"/>
    <origin xyz="0.05 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
    <mimic joint="elbow" multiplier="2" offset="0"/></joint>
</robot>""")
    urdf = tmp_path / "mimic.urdf"
    urdf.write_text(text)
    mech = load_mechanism(urdf, closures="none", output="finger")
    assert mech.actuated == ("shoulder", "elbow")
    an = mech.analyze(mech.assemble(np.array([0.4, 0.9])))
    assert an.dof == 2 and an.redundancy == 0
    # the finger's angular rate per unit elbow rate: 1 (elbow) + 2 (mimic); axis-first
    kin = mech.model.kinematics(an.q)
    np.testing.assert_allclose(kin.output_jacobian[:3, 1], [0.0, 0.0, 3.0], atol=1e-12)
    np.testing.assert_allclose(kin.output_jacobian[:3, 0], [0.0, 0.0, 1.0], atol=1e-12)
