"""Writing URDF text from yourdfpy objects, and a small API for serial chains.

URDFs are built as :class:`yourdfpy.Robot` objects (links, joints, limits, mimics,
simple visuals) and serialised with yourdfpy's writer, never pasted together as strings.

yourdfpy 0.0.60's writer has two problems worked around here:

* ``URDF._write_joint`` does not write the ``<mimic>`` element (nor ``<calibration>`` /
  ``<safety_controller>``): :class:`_Writer` adds the mimic back;
* ``URDF.write_xml_string`` returns bytes without pretty printing and passes its keyword
  arguments positionally: :func:`robot_to_xml` serialises the element tree itself.

Conventions: origins are URDF ``xyz`` [m] and ``rpy`` [rad] (fixed axes X, Y, Z, i.e.
``R = Rz(yaw) Ry(pitch) Rx(roll)``); axes are in the joint frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import yourdfpy
from lxml import etree

from ..errors import InputError

#: Effort [N or N m] and velocity [m/s or rad/s] limits written on every movable joint
#: (URDF requires them; the kinematic analysis does not use them).
EFFORT, VELOCITY = 100.0, 10.0

_JOINT_TYPES = ("revolute", "prismatic", "fixed", "continuous")


@dataclass(frozen=True)
class JointSpec:
    """One joint of a serial chain.

    Attributes:
        name: Joint name.
        type: ``"revolute"``, ``"prismatic"``, ``"continuous"`` or ``"fixed"``.
        xyz: Origin of the joint frame in the previous joint's frame [m].
        rpy: Orientation of the joint frame (URDF roll, pitch, yaw) [rad].
        axis: Joint axis in the joint frame.
        lower: Lower limit [rad or m].
        upper: Upper limit [rad or m].
        mimic: ``(joint, multiplier, offset)``: this joint follows ``joint`` as
            ``q = multiplier * q_joint + offset``; None for an independent joint.
    """

    name: str
    type: str = "revolute"
    xyz: Sequence[float] = (0.0, 0.0, 0.0)
    rpy: Sequence[float] = (0.0, 0.0, 0.0)
    axis: Sequence[float] = (0.0, 0.0, 1.0)
    lower: float = -math.pi
    upper: float = math.pi
    mimic: tuple[str, float, float] | None = None

    def __post_init__(self) -> None:
        if self.type not in _JOINT_TYPES:
            raise InputError(f"joint {self.name!r}: type must be one of {_JOINT_TYPES}, "
                             f"got {self.type!r}")
        if self.type in ("revolute", "prismatic") and not self.lower <= self.upper:
            raise InputError(f"joint {self.name!r}: lower limit {self.lower} > upper {self.upper}")


def origin_matrix(xyz: Sequence[float] = (0.0, 0.0, 0.0),
                  rpy: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """4×4 homogeneous matrix of a URDF origin ``xyz`` [m], ``rpy`` [rad]."""
    T = np.eye(4)
    T[:3, :3] = pin.rpy.rpyToMatrix(*map(float, rpy))
    T[:3, 3] = np.asarray(xyz, dtype=float)
    return T


class _Writer(yourdfpy.URDF):
    """yourdfpy's URDF writer, with the ``<mimic>`` element that it leaves out."""

    def _write_joint(self, xml_parent, joint):
        super()._write_joint(xml_parent, joint)
        if joint.mimic is not None:
            self._write_mimic(xml_parent[-1], joint.mimic)


def robot_to_xml(robot: yourdfpy.Robot) -> str:
    """URDF text (pretty printed, with an XML declaration) of a yourdfpy robot."""
    writer = _Writer(robot=robot, build_scene_graph=False, load_meshes=False)
    tree = writer.write_xml()
    return etree.tostring(tree, xml_declaration=True, encoding="UTF-8",
                          pretty_print=True).decode()


# ------------------------------------------------------------------------ visuals
def _visual_size(joints: Sequence[JointSpec], tip_xyz: Sequence[float]) -> float:
    """Length that sets the radii of the visuals: largest offset or prismatic stroke."""
    sizes = [np.linalg.norm(j.xyz) for j in joints] + [np.linalg.norm(tip_xyz)]
    sizes += [max(abs(j.lower), abs(j.upper)) for j in joints if j.type == "prismatic"]
    size = max(sizes, default=0.0)
    return float(size) if size > 0 else 1.0


def _bar(offset: np.ndarray, radius: float) -> yourdfpy.Visual | None:
    """Cylinder from the link origin to ``offset`` (link frame), or None if too short."""
    length = float(np.linalg.norm(offset))
    if length <= 1e-9 * radius:
        return None
    z = offset / length
    # rotation taking +z to z (about the axis z0 × z)
    c = np.cross([0.0, 0.0, 1.0], z)
    angle = math.atan2(np.linalg.norm(c), z[2])
    R = pin.exp3(c / np.linalg.norm(c) * angle) if np.linalg.norm(c) > 1e-12 else (
        np.eye(3) if z[2] > 0 else np.diag([1.0, -1.0, -1.0]))
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = 0.5 * offset
    return yourdfpy.Visual(origin=T, geometry=yourdfpy.Geometry(
        cylinder=yourdfpy.Cylinder(radius=radius, length=length)))


def _ball(radius: float) -> yourdfpy.Visual:
    return yourdfpy.Visual(origin=np.eye(4), geometry=yourdfpy.Geometry(
        sphere=yourdfpy.Sphere(radius=radius)))


# -------------------------------------------------------------------------- chain
def chain_robot(
    robot_name: str,
    joints: Sequence[JointSpec],
    tip: str = "tip",
    link_prefix: str = "",
    tip_xyz: Sequence[float] = (0.0, 0.0, 0.0),
    tip_rpy: Sequence[float] = (0.0, 0.0, 0.0),
    visuals: bool = True,
) -> yourdfpy.Robot:
    """yourdfpy robot of a serial chain: ``base`` → joints … → fixed joint → ``tip``.

    The root link is ``<link_prefix>base``; joint ``J`` moves the link
    ``<link_prefix>J_link``; the last link carries the frame ``tip`` through a fixed
    joint ``<tip>_fixed`` of origin ``tip_xyz``, ``tip_rpy``. With ``visuals``, every
    link has a sphere at its joint and a cylinder along the offset to the next joint.
    """
    if not joints:
        raise InputError(f"chain {robot_name!r}: give at least one joint")
    names = [j.name for j in joints]
    if len(set(names)) != len(names) or f"{tip}_fixed" in names:
        raise InputError(f"chain {robot_name!r}: joint names must be unique, got {names}")
    link_names = [f"{link_prefix}base"] + [f"{link_prefix}{n}_link" for n in names] + [tip]
    radius = 0.02 * _visual_size(joints, tip_xyz)
    offsets = [np.asarray(j.xyz, dtype=float) for j in joints[1:]]
    offsets.append(np.asarray(tip_xyz, dtype=float))
    links = [yourdfpy.Link(name=link_names[0])]
    for k, link_name in enumerate(link_names[1:-1]):
        shapes = []
        if visuals:
            shapes = [_ball(1.5 * radius), _bar(offsets[k], radius)]
        links.append(yourdfpy.Link(name=link_name, visuals=[v for v in shapes if v is not None]))
    links.append(yourdfpy.Link(name=tip))
    urdf_joints = []
    for k, j in enumerate(joints):
        limit = None
        if j.type != "fixed":
            limit = yourdfpy.Limit(effort=EFFORT, velocity=VELOCITY,
                                   lower=float(j.lower) if j.type != "continuous" else None,
                                   upper=float(j.upper) if j.type != "continuous" else None)
        mimic = None if j.mimic is None else yourdfpy.Mimic(
            joint=j.mimic[0], multiplier=float(j.mimic[1]), offset=float(j.mimic[2]))
        axis = None if j.type == "fixed" else np.asarray(j.axis, dtype=float)
        urdf_joints.append(yourdfpy.Joint(
            name=j.name, type=j.type, parent=link_names[k], child=link_names[k + 1],
            origin=origin_matrix(j.xyz, j.rpy), axis=axis, limit=limit, mimic=mimic))
    urdf_joints.append(yourdfpy.Joint(
        name=f"{tip}_fixed", type="fixed", parent=link_names[-2], child=tip,
        origin=origin_matrix(tip_xyz, tip_rpy)))
    return yourdfpy.Robot(name=robot_name, links=links, joints=urdf_joints)


def chain_urdf(
    robot_name: str,
    joints: Sequence[JointSpec],
    tip: str = "tip",
    link_prefix: str = "",
    tip_xyz: Sequence[float] = (0.0, 0.0, 0.0),
    tip_rpy: Sequence[float] = (0.0, 0.0, 0.0),
    visuals: bool = True,
) -> str:
    """URDF text of a serial chain (see :func:`chain_robot`).

    >>> xml = chain_urdf("rp", [JointSpec("R", axis=(0, 1, 0)),
    ...                         JointSpec("P", "prismatic", axis=(1, 0, 0), lower=0.2, upper=3)])
    >>> xml.count("<joint ")
    3
    """
    return robot_to_xml(chain_robot(robot_name, joints, tip, link_prefix, tip_xyz, tip_rpy,
                                    visuals))
