"""Names of motions (issue 17, item 7): a helical motion is "H", not "R".

The Bennett linkage (a spatial 4R loop with a12 = a34 = a, a23 = a41 = b,
α12 = α34 = α, α23 = α41 = β and sin α / a = sin β / b) moves with one degree of
freedom; its coupler turns about a screw whose pitch is not zero, and no translation of
the (one-dimensional) twist system can cancel it.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from pkm_pin import screws
from pkm_pin.linkage import Linkage
from pkm_pin.model.closure_model import Closure, ClosureModel

A, ALPHA = 0.3, math.radians(50.0)
BETA = math.radians(70.0)
B = A * math.sin(BETA) / math.sin(ALPHA)  # Bennett's condition


def _link(a: float, alpha: float) -> pin.SE3:
    """DH link transform Tx(a) Rx(α)."""
    return pin.SE3(pin.rpy.rpyToMatrix(alpha, 0.0, 0.0), np.array([a, 0.0, 0.0]))


def bennett() -> ClosureModel:
    """Joints R1 (ground), R2, R3 in a chain; joint 4 closes on the ground by a revolute
    closure (same point, same z axis). Output: the coupler (the link after R2)."""
    tree = pin.Model()
    parent = 0
    for k, (a, alpha) in enumerate([(0.0, 0.0), (A, ALPHA), (B, BETA)]):
        parent = tree.addJoint(parent, pin.JointModelRZ(), _link(a, alpha), f"R{k + 1}")
        tree.addJointFrame(parent)
        tree.appendBodyToJoint(parent, pin.Inertia.Identity(), pin.SE3.Identity())
        tree.addBodyFrame(f"link{k + 1}", parent, pin.SE3.Identity(), -1)
    tree.addFrame(pin.Frame("joint4", parent, _link(A, ALPHA), pin.FrameType.OP_FRAME))
    tree.addFrame(pin.Frame("ground4", 0, _link(B, BETA).inverse(), pin.FrameType.OP_FRAME))
    loop = Closure("revolute", "joint4", "ground4", name="loop")
    return ClosureModel(tree, (loop,), ("R1",), "link2", "bennett", reference=np.array(
        [0.4, 1.0, -0.4]))


def test_bennett_linkage_moves_with_one_dof_and_three_redundant_closure_rows():
    link = Linkage(bennett())
    a = link.assemble()
    m = link.mobility(a.q)
    assert (m.dof, m.redundant_constraints, link.grubler) == (1, 3, -2)


def test_bennett_coupler_motion_is_helical():
    link = Linkage(bennett())
    a = link.assemble()
    an = link.analyze(a.q)
    L = link.model.length
    # the coupler's twist by finite differences of forward kinematics on the loop
    h = 1e-6
    plus = link.forward_kinematics(a.q_actuated + h, guess=a)
    minus = link.forward_kinematics(a.q_actuated - h, guess=a)
    t = screws.from_pinocchio(pin.log6(plus.output_pose * minus.output_pose.inverse()).vector)
    pitch = (t[:3] @ t[3:]) / (t[:3] @ t[:3])
    assert abs(pitch) > 1e-3 * L  # a screw motion, not a rotation about a line
    np.testing.assert_allclose(an.forward_velocity([2 * h]), t, atol=1e-8)
    assert screws.motion_type(an.platform_twists, an.translations, L) == "1H"


@pytest.mark.parametrize("twists, translations, name", [
    ([[0, 0, 1, 0, 0, 0.1]], 0, "1H"),
    ([[0, 0, 1, 0.5, 0, 0]], 0, "1R"),
    ([[0, 0, 1, 0, 0, 0.1], [0, 0, 0, 0, 0, 1]], 1, "1T1R"),  # cylindrical: pitch cancelled
    ([[0, 0, 1, 0, 0, 0.1], [0, 0, 0, 1, 0, 0]], 1, "1T1H"),
    (np.eye(6)[3:], 3, "3T"),
    (np.zeros((0, 6)), 0, "0"),
])
def test_motion_type_names(twists, translations, name):
    assert screws.motion_type(np.array(twists, dtype=float), translations, 1.0) == name
