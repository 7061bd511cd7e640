"""The URDF text of a serial chain held as a Pinocchio model.

A leg read out of a closure model (:meth:`pkm_pin.Mechanism.from_closure_model`) is a
Pinocchio model, not a URDF file; written back as URDF text it is a leg like any other:
:mod:`pkm_pin.sensitivity` names and perturbs its parameters (joint origins and axes)
and :meth:`pkm_pin.leg.Leg.from_urdf` rebuilds it.

Each joint ``j`` becomes a URDF joint of the same name whose parent link is the body of
its parent joint (``"<parent joint>_link"``, ``root`` for the universe) and whose
``<origin>`` is the joint placement (xyz [m], roll-pitch-yaw [rad]); revolute and
prismatic joints about any axis (Pinocchio's ``RX``… and ``…Unaligned`` models) keep
their axis and position limits within :data:`~pkm_pin.urdf.MAX_COORDINATE` (a joint
unlimited, or with Pinocchio's default ±1.8e308, is written without a range,
which :func:`pkm_pin.urdf.joints_without_range` reads back as unlimited), unbounded
revolutes are ``continuous``. The tip frame
becomes a link of its name, fixed to its joint's body at the frame's placement.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from lxml import etree

from ..errors import InputError
from ..urdf import MAX_COORDINATE

__all__ = ["chain_urdf"]

_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def chain_urdf(model: pin.Model, tip: str, name: str = "chain") -> str:
    """URDF text of the serial chain ``model`` from its root to the frame ``tip``.

    Raises:
        InputError: a joint is not a revolute, continuous or prismatic joint.
    """
    robot = etree.Element("robot", name=name)
    etree.SubElement(robot, "link", name="root")
    for j in range(1, model.njoints):
        etree.SubElement(robot, "link", name=_link(model, j))
        kind, axis = _kind(model, j)
        joint = etree.SubElement(robot, "joint", name=model.names[j], type=kind)
        etree.SubElement(joint, "parent", link=_link(model, model.parents[j]))
        etree.SubElement(joint, "child", link=_link(model, j))
        _origin(joint, model.jointPlacements[j])
        etree.SubElement(joint, "axis", xyz=" ".join(repr(float(a)) for a in axis))
        if kind != "continuous":  # a range only where it is finite (else: unlimited)
            iq = model.joints[j].idx_q
            lower, upper = model.lowerPositionLimit[iq], model.upperPositionLimit[iq]
            limit = etree.SubElement(joint, "limit", effort="100.0", velocity="10.0")
            if max(abs(lower), abs(upper)) <= MAX_COORDINATE:  # Pinocchio's "none": ±1.8e308
                limit.set("lower", repr(float(lower)))
                limit.set("upper", repr(float(upper)))
    frame = model.frames[model.getFrameId(tip)]
    etree.SubElement(robot, "link", name=tip)
    fixed = etree.SubElement(robot, "joint", name=f"{tip}_fixed", type="fixed")
    etree.SubElement(fixed, "parent", link=_link(model, frame.parentJoint))
    etree.SubElement(fixed, "child", link=tip)
    _origin(fixed, frame.placement)
    return etree.tostring(robot, pretty_print=True, xml_declaration=True,
                          encoding="UTF-8").decode()


def _link(model: pin.Model, j: int) -> str:
    return "root" if j == 0 else f"{model.names[j]}_link"


def _kind(model: pin.Model, j: int) -> tuple[str, tuple]:
    """URDF joint type and axis of joint ``j``."""
    joint = model.joints[j]
    short = joint.shortname().removeprefix("JointModel")
    for prefix, kind in (("RUB", "continuous"), ("R", "revolute"), ("P", "prismatic")):
        if short in (prefix + "X", prefix + "Y", prefix + "Z"):
            return kind, _AXES[short[-1]]
    unaligned = {"RevoluteUnaligned": "revolute", "PrismaticUnaligned": "prismatic",
                 "RevoluteUnboundedUnaligned": "continuous"}
    if short in unaligned:
        return unaligned[short], tuple(np.asarray(joint.extract().axis, float))
    raise InputError(f"joint {model.names[j]!r} is a {short} joint: a leg written as URDF "
                     "has revolute, continuous and prismatic joints")


def _origin(element, placement: pin.SE3) -> None:
    etree.SubElement(element, "origin",
                     xyz=" ".join(repr(float(x)) for x in placement.translation),
                     rpy=" ".join(repr(float(x)) for x in pin.rpy.matrixToRpy(placement.rotation)))
