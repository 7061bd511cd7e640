"""MJCF as people write it (issue 25 item 1): ``<joint>`` equalities as coupling closures,
actuators on fixed tendons, joint positions from default classes; the numbers against
hand derivations, finite differences and the compiled tree kernel."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkm_pin
from pkm_pin import dynamics, screws, tree_kernel
from pkm_pin.cli import main
from pkm_pin.errors import InputError
from pkm_pin.model import Closure, ClosureModel, read_mjcf
from pkm_pin.model.structure import detect_platform
from pkm_pin.solve import solve_tree

GRIPPER = """<mujoco model="gripper">
  <compiler angle="radian"/>
  <worldbody>
    <body name="palm">
      <body name="left" pos="0.02 0 0.05">
        <joint name="left" type="hinge" axis="0 1 0" range="-1 1"/>
        <body name="left_tip" pos="0 0 {r}"/>
      </body>
      <body name="right" pos="-0.02 0 0.05">
        <joint name="right" type="hinge" axis="0 1 0" range="-1 1"/>
        <body name="right_tip" pos="0 0 {r}"/>
      </body>
    </body>
  </worldbody>
  <custom><text name="pkm_pin:output" data="left_tip"/></custom>
  <tendon>
    <fixed name="grip"><joint joint="left" coef="0.5"/><joint joint="right" coef="-0.5"/></fixed>
  </tendon>
  <equality><joint name="mirror" joint1="right" joint2="left" polycoef="0 -1 0 0 0"/></equality>
  <actuator><position name="close" tendon="grip" kp="10"/></actuator>
</mujoco>
"""

#: Two jaws sliding along x, the right one geared to the left: q_r = 0.01 − 2 q_l.
JAW = """<mujoco model="jaw">
  <compiler angle="radian"/>
  <worldbody>
    <body name="palm">
      <body name="carriage" pos="0 0 0.1">
        <joint name="lift" type="slide" axis="0 0 1"/>
        <body name="jaw_l" pos="-0.05 0 0.02">
          <joint name="jaw_l" type="slide" axis="1 0 0"/>
        </body>
        <body name="jaw_r" pos="0.05 0 0.02">
          <joint name="jaw_r" type="slide" axis="1 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
  <custom><text name="pkm_pin:output" data="jaw_r"/></custom>
  <equality>
    <joint name="gear" joint1="jaw_r" joint2="jaw_l" polycoef="0.01 -2"/>
    <joint name="hold" joint1="lift" polycoef="0.03"/>
  </equality>
  <actuator><motor name="m" joint="jaw_l"/></actuator>
</mujoco>
"""

#: A four-bar (crank at ref 0.2) closed by a connect; {extra} more equalities.
FOUR_BAR = """<mujoco model="loop">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base">
      <body name="crank" pos="0 0 0" axisangle="0 0 1 1.0">
        <joint name="crank_joint" type="hinge" axis="0 0 1" ref="0.2"/>
        <body name="coupler" pos="0.03 0 0" axisangle="0 0 1 -0.6">
          <joint name="coupler_joint" type="hinge" axis="0 0 1"/>
        </body>
      </body>
      <body name="rocker" pos="0.1 0 0" axisangle="0 0 1 1.4">
        <joint name="rocker_joint" type="hinge" axis="0 0 1"/>
      </body>
    </body>
  </worldbody>
  <equality>
    <connect name="c" body1="coupler" body2="rocker" anchor="0.09 0 0"/>{extra}
  </equality>
  <actuator><motor name="m" joint="crank_joint"/></actuator>
</mujoco>
"""


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _fd_jacobian(model: ClosureModel, q: np.ndarray, h: float = 1e-7) -> np.ndarray:
    """Central differences of the closure residual along each velocity coordinate."""
    cols = []
    for k in range(model.nv):
        dv = np.zeros(model.nv)
        dv[k] = h
        plus = model.closure_residual(pin.integrate(model.tree, q, dv))
        minus = model.closure_residual(pin.integrate(model.tree, q, -dv))
        cols.append((plus - minus) / (2 * h))
    return np.array(cols).T


# ------------------------------------------------------------------------ gripper
def test_gripper_fingers_coupled_and_driven_through_a_fixed_tendon(tmp_path):
    """Two fingers mirrored by a joint equality, closed by a position actuator on a
    fixed tendon ``0.5 left − 0.5 right``: on the coupling ``right = −left`` the tendon
    moves as ``1·left``, so ``left`` is the actuated joint (a note says so); one DOF,
    nothing idle; A and B as derived by hand for a finger of length r turning about
    its hinge."""
    r = 0.04
    link = pkm_pin.load_mechanism(_write(tmp_path, "g.xml", GRIPPER.format(r=r)))
    model = link.model
    (c,) = model.closures
    assert (c.kind, c.name, c.coef, c.dim) == ("coupling", "mirror", (0.0, -1.0), 1)
    assert model.actuated == ("left",)
    assert model.actuator_matches == (("close", ("left",)),)
    assert any("tendon grip (length 0.5·left − 0.5·right; on the joint couplings it "
               "moves as 1·left): left is its actuated joint" in n for n in model.notes)
    q = np.array([0.3, -0.3])
    assert np.allclose(model.closure_residual(q), 0.0, atol=1e-15)
    assert np.allclose(model.closure_jacobian(q), [[1.0, 1.0]])
    mob = link.mobility(q)
    assert (mob.dof, mob.idle_dof, mob.redundant_constraints) == (1, 0, 0)
    an = link.analyze(q)
    # the tip moves along u = (cos q, 0, −sin q) at r per unit rate; homogenised
    # orthogonality about the tip gives f = u and the couple L² ω / r, so B = r + L²/r
    L, s = model.length, np.sin(0.3)
    u = np.array([np.cos(0.3), 0.0, -s])
    p = np.array([0.02 + r * s, 0.0, 0.05 + r * np.cos(0.3)])
    m_p = np.array([0.0, L * L / r, 0.0])
    assert np.allclose(an.A, [np.r_[u, m_p + np.cross(p, u)]], atol=1e-9)
    assert an.B.shape == (1, 1) and an.B[0, 0] == pytest.approx(r + L * L / r, rel=1e-9)
    # A Δ t = B q̇ along the allowed motion (left +1, right −1)
    t = model.kinematics(q).output_jacobian @ np.array([1.0, -1.0])
    assert an.A @ screws.DELTA @ t == pytest.approx(an.B[0, 0], rel=1e-12)


def test_gripper_assembles_and_analyses_from_the_cli(tmp_path, capsys):
    """The gripper file assembles from its reference (both fingers at 0) and the CLI
    prints its JSON report with the tendon's note."""
    path = _write(tmp_path, "g.xml", GRIPPER.format(r=0.04))
    link = pkm_pin.load_mechanism(path)
    a = link.forward_kinematics([0.2])
    assert np.allclose(a.q, [0.2, -0.2], atol=1e-10)
    assert main(["analyze", str(path), "--json"]) == 0
    out = capsys.readouterr().out
    assert '"dof": 1' in out and "left is its actuated joint" in out


# ------------------------------------------------------------------ parallel jaw
def test_parallel_jaw_coupling_rows_and_mobility(tmp_path):
    """Slides geared by ``polycoef="0.01 -2"`` and a lift held by a one-joint equality
    (``lift = 0.03``): the rows are ``(q_r + 2 q_l − 0.01) / L`` and ``(lift − 0.03) / L``
    (prismatic coordinates counted in lengths L), their Jacobian equals central
    differences, one DOF; A is a unit force along −x through the right jaw's origin,
    B = 2 (the jaw moves at −2 per unit rate of the left one)."""
    link = pkm_pin.load_mechanism(_write(tmp_path, "jaw.xml", JAW))
    model = link.model
    assert [(c.kind, c.coef) for c in model.closures] == [("coupling", (0.01, -2.0)),
                                                          ("coupling", (0.03, 0.0))]
    L = model.length
    rng = np.random.default_rng(4)
    for _ in range(5):
        q = rng.uniform(-0.05, 0.05, 3)  # lift, jaw_l, jaw_r
        assert np.allclose(model.closure_residual(q),
                           [(q[2] + 2 * q[1] - 0.01) / L, (q[0] - 0.03) / L], atol=1e-15)
        J = model.closure_jacobian(q)
        assert np.allclose(J, [[0.0, 2 / L, 1 / L], [1 / L, 0.0, 0.0]], atol=1e-15)
        assert np.allclose(J, _fd_jacobian(model, q), atol=1e-8)
    a = link.forward_kinematics([0.004])
    assert np.allclose(a.q, [0.03, 0.004, 0.002], atol=1e-12)
    mob = link.mobility(a.q)
    assert (mob.dof, mob.idle_dof, mob.redundant_constraints) == (1, 0, 0)
    an = link.analyze(a)
    p = model.kinematics(a.q).output_placement.translation
    f = np.array([-1.0, 0.0, 0.0])
    assert np.allclose(an.A, [np.r_[f, np.cross(p, f)]], atol=1e-12)
    assert an.B.shape == (1, 1) and an.B[0, 0] == pytest.approx(2.0, rel=1e-12)
    assert an.motion_type == "1T"
    # inverse kinematics: the right jaw at x = 0.05 − 0.008 needs q_l = (0.01 + 0.008) / 2
    ik = link.inverse_kinematics(pin.SE3(np.eye(3), np.array([0.042, 0.0, 0.15])))
    assert ik.q_actuated == pytest.approx([0.009], abs=1e-12)


def test_coupling_rows_of_the_compiled_kernel_equal_the_closure_model(tmp_path):
    """The compiled tree kernel's coupling rows and its solver equal the Pinocchio
    path (a coupling to another joint, and one to the base)."""
    model = read_mjcf(_write(tmp_path, "jaw.xml", JAW))
    kern = tree_kernel.tree_kernel(model)
    assert kern is not None
    q = np.array([0.01, -0.02, 0.03])
    e, H = np.empty(model.n_rows), np.empty((model.n_rows, model.nv))
    norms, oMo = np.empty(2), np.empty((4, 4))
    worst = tree_kernel.closure_rows_compiled(kern, q, e, H, norms, oMo)
    assert np.allclose(e, model.closure_residual(q), atol=1e-15)
    assert np.allclose(H, model.closure_jacobian(q), atol=1e-15)
    assert worst == pytest.approx(np.abs(model.closure_residual(q)).max(), rel=1e-12)
    compiled = solve_tree(model, q, compiled=True)
    plain = solve_tree(model, q, compiled=False)
    assert compiled.converged and plain.converged
    assert np.allclose(compiled.q, plain.q, atol=1e-10)


def test_coupling_dynamics_rows(tmp_path):
    """Dynamics: a coupling's physical row is ``(1, −c₁)`` in its joints' columns (its
    unit the joint's: metres here), its second derivative ``a_r − c₁ a_l`` with no
    drift."""
    model = read_mjcf(_write(tmp_path, "jaw.xml", JAW))
    q = np.array([0.03, 0.004, 0.002])
    v = np.array([0.0, 0.1, -0.2])
    a = np.array([0.0, 0.5, 0.7])
    J, rdd, drift = dynamics.closure_acceleration(model, q, v, a)
    assert np.allclose(J, [[0.0, 2.0, 1.0], [1.0, 0.0, 0.0]], atol=1e-14)
    assert np.allclose(rdd, [0.7 + 2 * 0.5, 0.0], atol=1e-14)
    assert np.allclose(drift, 0.0, atol=1e-14)
    assert np.allclose(dynamics.row_units(model), model.length)


# ---------------------------------------------------------------------- four-bar
def test_four_bar_held_by_a_joint_equality_is_rigid(tmp_path):
    """A four-bar whose crank a one-joint equality holds (MuJoCo: ``q − qpos0 = c₀``,
    so crank = ref 0.2 + 0.1) has DOF 0 and assembles with the crank at 0.3."""
    text = FOUR_BAR.format(extra='\n    <joint name="lock" joint1="crank_joint" '
                                 'polycoef="0.1"/>')
    link = pkm_pin.load_mechanism(_write(tmp_path, "rigid.xml", text))
    lock = link.model.closures[1]
    assert (lock.kind, lock.coef) == ("coupling", (pytest.approx(0.3), 0.0))
    a = link.assemble()
    assert a.q[0] == pytest.approx(0.3, abs=1e-10)
    assert np.abs(link.model.closure_residual(a.q)).max() < 1e-10
    mob = link.mobility(a.q)
    assert (mob.dof, mob.idle_dof) == (0, 0)


def test_four_bar_with_a_crank_rocker_gear_is_rigid(tmp_path):
    """A linear crank–rocker coupling fights the four-bar's own (non-linear) relation:
    DOF 0 where it assembles; the coupling row's Jacobian equals central differences."""
    text = FOUR_BAR.format(extra='\n    <joint joint1="rocker_joint" joint2="crank_joint" '
                                 'polycoef="0 1.5"/>')
    link = pkm_pin.load_mechanism(_write(tmp_path, "gear.xml", text))
    model = link.model
    q = np.array([0.25, 0.1, -0.05])
    assert np.allclose(model.closure_jacobian(q), _fd_jacobian(model, q), atol=1e-7)
    assert model.closure_residual(q)[-1] == pytest.approx(-0.05 - 1.5 * (0.25 - 0.2),
                                                           rel=1e-12)
    a = link.assemble()
    assert link.mobility(a.q).dof == 0


def test_inactive_equalities_are_ignored_with_a_note(tmp_path):
    """``active="false"``: the equality is skipped and the model's notes say so."""
    text = FOUR_BAR.format(extra='\n    <joint joint1="crank_joint" active="false"/>')
    model = read_mjcf(_write(tmp_path, "idle.xml", text))
    assert [c.kind for c in model.closures] == ["point"]
    assert 'joint[0] is inactive in the file (active="false"): ignored' in model.notes


def test_one_joint_tendon_drives_its_joint(tmp_path):
    """A fixed tendon over one joint drives that joint."""
    text = FOUR_BAR.format(extra="").replace(
        '<actuator><motor name="m" joint="crank_joint"/>',
        '<tendon><fixed name="t"><joint joint="crank_joint" coef="2"/></fixed></tendon>'
        '<actuator><motor name="m" tendon="t"/>')
    model = read_mjcf(_write(tmp_path, "t.xml", text))
    assert model.actuated == ("crank_joint",)
    assert "motor[0] 'm' drives fixed tendon t (length 2·crank_joint): crank_joint is its " \
        "actuated joint" in model.notes


def test_a_tendon_that_the_couplings_hold_still_is_refused(tmp_path):
    """A tendon whose length does not change on the couplings moves nothing."""
    text = GRIPPER.format(r=0.04).replace('coef="-0.5"', 'coef="0.5"')
    with pytest.raises(pkm_pin.errors.ClosureFileError, match="does not change on the "
                       "file's joint couplings: it moves nothing"):
        read_mjcf(_write(tmp_path, "g.xml", text))


# ------------------------------------------------------------------ guards, others
def test_structure_detection_refuses_a_coupling(tmp_path):
    """The platform-structure detection leaves a coupled model to the general
    elimination, with the reason."""
    model = read_mjcf(_write(tmp_path, "g.xml", GRIPPER.format(r=0.04)))
    structure, reason = detect_platform(model)
    assert structure is None
    assert "closure 'mirror' couples the coordinates of two joints" in reason


def test_a_coupling_of_a_ball_joint_is_refused():
    """A coupling names joints of one coordinate."""
    tree = pin.Model()
    j = tree.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    tree.addJointFrame(j)
    k = tree.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "hinge")
    tree.addJointFrame(k)
    with pytest.raises(InputError, match="joint 'ball' .*a coupling relates two joints of "
                       "one coordinate each"):
        ClosureModel(tree, (Closure("coupling", "ball", "hinge", coef=(0, 1)),), (), "hinge")
    with pytest.raises(InputError, match="coef must be two finite numbers"):
        Closure("coupling", "hinge", "ball", coef=(0.0, np.inf))


def test_joint_position_from_a_default_class(tmp_path):
    """A joint whose ``pos`` comes from its default class (``class=`` or a body's
    ``childclass``, nested defaults inherit) gets the tree of the same file with the
    position written inline (Pinocchio 4.1 leaves it out)."""
    body = ('<body name="b{k}" pos="0 0.05 0"{cc}><joint name="j{k}"{attr} axis="1 0 0"/>'
            '</body>')
    defaults = ('<default><default class="outer"><joint pos="0 -0.018 0.0065"/>'
                '<default class="inner"><joint damping="1"/></default></default></default>')
    frame = ('<mujoco model="d">{d}<worldbody><body name="a">{b}</body></worldbody>'
             '</mujoco>')
    by_class = frame.format(d=defaults, b="".join([
        body.format(k=1, cc="", attr=' class="outer"'),
        body.format(k=2, cc=' childclass="inner"', attr=""),
        body.format(k=3, cc="", attr=' class="inner" pos="0 0 0.01"')]))
    inline = frame.format(d="", b="".join([
        body.format(k=1, cc="", attr=' pos="0 -0.018 0.0065"'),
        body.format(k=2, cc="", attr=' pos="0 -0.018 0.0065"'),
        body.format(k=3, cc="", attr=' pos="0 0 0.01"')]))
    a = read_mjcf(_write(tmp_path, "class.xml", by_class)).tree
    b = read_mjcf(_write(tmp_path, "inline.xml", inline)).tree
    for j in range(1, a.njoints):
        assert np.allclose(a.jointPlacements[j].homogeneous, b.jointPlacements[j].homogeneous)
    assert np.allclose(a.jointPlacements[1].translation, [0.0, 0.032, 0.0065])


def test_a_one_joint_tendon_on_an_unknown_joint_names_the_joint(tmp_path):
    """A fixed tendon over a joint Pinocchio's model lacks: the actuator's error names
    that joint (not a differential)."""
    text = FOUR_BAR.format(extra="").replace(
        '<actuator><motor name="m" joint="crank_joint"/>',
        '<tendon><fixed name="t"><joint joint="ghost"/></fixed></tendon>'
        '<actuator><motor name="m" tendon="t"/>')
    with pytest.raises(pkm_pin.errors.ClosureFileError, match="joint 'ghost' is not a joint "
                       "of Pinocchio's model"):
        read_mjcf(_write(tmp_path, "t.xml", text))


def test_limits_of_a_joint_with_a_ref_are_its_range(tmp_path):
    """MuJoCo's ``range`` bounds ``qpos``, the coordinate Pinocchio's tree uses (the body
    at its ``pos`` when ``q = ref``): the tree's limits are the range, not Pinocchio's
    ``range − ref``."""
    text = ('<mujoco model="r"><compiler angle="radian"/><worldbody><body name="a">'
            '<body name="b" pos="0 0.05 0"><joint name="h" axis="0 0 1" range="-0.5 0.7" '
            'ref="0.2"/><body name="t" pos="0.1 0 0"/></body>'
            '<body name="c" pos="0 0.05 0"><joint name="s" type="slide" axis="1 0 0" '
            'range="-0.5 0.7" ref="0.2"/></body>'
            '<body name="d"><joint name="free_h" axis="0 0 1" ref="0.3"/></body>'
            '</body></worldbody></mujoco>')
    model = read_mjcf(_write(tmp_path, "r.xml", text))
    tree = model.tree
    assert np.allclose(tree.lowerPositionLimit[:2], -0.5)
    assert np.allclose(tree.upperPositionLimit[:2], 0.7)
    assert tree.upperPositionLimit[2] > 1e300  # no range: no limit
    assert np.allclose(model.reference, [0.2, 0.2, 0.3])
    data = tree.createData()
    pin.framesForwardKinematics(tree, data, model.reference)
    assert np.allclose(data.oMf[tree.getFrameId("t")].translation, [0.1, 0.05, 0.0])


SPRING_COUPLED = """<mujoco model="spring_coupled">
  <worldbody>
    <body name="a"><joint name="j1" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/>
      <body name="b" pos="0.1 0 0"><joint name="j2" axis="0 0 1" stiffness="1"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/>
        <body name="c" pos="0.1 0 0"><joint name="j3" axis="0 0 1" stiffness="1"/>
          <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/>
          <body name="d" pos="0.1 0 0"><joint name="j4" axis="0 0 1" stiffness="1"/>
            <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/></body></body></body>
    </body>
  </worldbody>
  <equality><joint joint1="j2" joint2="j1" polycoef="0 1 0 0 0"/>
    <joint joint1="j3" joint2="j2" polycoef="0 0.5 0 0 0"/></equality>
  <actuator><position joint="j1"/></actuator>
</mujoco>
"""


def test_a_spring_joint_coupled_to_a_motor_is_not_a_free_spring(tmp_path):
    """Springs tied to the motor by joint equalities, directly (j2) or through another
    (j3), move with it: not listed as springs (Menagerie's stretch_3 arm joints were);
    j4, free, is, and the analysis agrees: one idle motion, body d's spin about j4's
    axis (through (0.3, 0, 0) at home)."""
    model = read_mjcf(_write(tmp_path, "s.xml", SPRING_COUPLED))
    assert model.springs == ("j4",)
    assert any(n.startswith("j4: a spring") for n in model.notes)
    mob = pkm_pin.load_mechanism(tmp_path / "s.xml").mobility()
    assert mob.idle_dof == 1
    assert mob.idle_motions[0].startswith("d spins about the line through (0.3, 0, 0)")


ROLLING = """<mujoco model="rolling_joint">
  <worldbody>
    <body name="p1">
      <joint name="a" axis="0 0 1" pos="-0.013 0 0"/>
      <joint name="b" axis="0 0 1"/>
      <geom type="box" size="0.01 0.01 0.005"/>
    </body>
  </worldbody>
  {equality}
  <actuator><motor joint="{motor}"/></actuator>
</mujoco>
"""


@pytest.mark.parametrize("equality,motor,where", [
    ('<equality><joint joint1="a" joint2="b"/></equality>', "b", "equality/joint[0] joint1"),
    ("", "b", "actuator/motor[0]")])
def test_a_joint_merged_into_a_composite_names_the_fix(tmp_path, equality, motor, where):
    """Two hinges in one body (IIT SoftFoot's rolling contacts): Pinocchio's MJCF parser
    makes them one composite joint, so a coupling or an actuator on either cannot be
    read; the error names the composite and the fix (one body per joint)."""
    from pkm_pin.errors import ClosureFileError

    path = _write(tmp_path, "r.xml", ROLLING.format(equality=equality, motor=motor))
    with pytest.raises(ClosureFileError) as info:
        read_mjcf(path)
    assert info.value.where == where
    assert "one composite joint ('Composite_a')" in str(info.value)
    assert "give each of that body's joints its own body" in str(info.value)
