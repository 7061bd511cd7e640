"""Mechanisms whose legs meet at a pin (no platform body), written as our TOML.

* :func:`five_bar`: the planar five-bar, two RR legs joined by a revolute pin;
* :func:`delta_point`: a Delta whose "platform" is one point, three R-U-rod legs joined
  by a spherical pin.

Each returns a :class:`~pkm_pin.builders.design.MechanismDesign` with ``closure`` set to
the pin; ``home`` is the pin's placement (the first leg's tip frame at home) and every
anchor the placement of a leg's tip frame in the pin frame (:meth:`LegDesign.assembled`).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from ..errors import InputError
from .design import LegDesign, MechanismDesign
from .spatial import three_arms
from .urdf_writer import JointSpec, chain_urdf

_Z = (0.0, 0.0, 1.0)
_Y = (0.0, 1.0, 0.0)


def elbow_angles(base: np.ndarray, point: np.ndarray, l1: float, l2: float,
                 elbow: int) -> np.ndarray:
    """Joint angles ``(q1, q2)`` of a planar RR leg (axes z, links along x) at ``base``
    whose tip reaches ``point`` (xy-plane); ``elbow = ±1`` picks the sign of ``q2``."""
    d = np.asarray(point, dtype=float)[:2] - np.asarray(base, dtype=float)[:2]
    r = float(np.hypot(*d))
    c2 = (r * r - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    if not -1.0 <= c2 <= 1.0:
        raise InputError(f"the point {point} is out of reach of the RR leg at {base} "
                         f"(links {l1}, {l2})")
    q2 = elbow * math.acos(c2)
    q1 = math.atan2(d[1], d[0]) - math.atan2(l2 * math.sin(q2), l1 + l2 * math.cos(q2))
    return np.array([q1, q2])


def five_bar(scale: float = 1.0, *, half_base: float = 0.1, proximal: float = 0.2,
             distal: float = 0.25, home_xy: tuple[float, float] = (0.0, 0.3)) -> MechanismDesign:
    """Planar five-bar in the xy-plane: legs ``L`` and ``R``, each ``R1`` (actuated,
    about z, at ``(∓half_base, 0, 0)``) – proximal link – ``R2`` (about z) – distal
    link – tip; the tips meet at a revolute pin (axis z). Elbows outward at home (the
    left leg's ``R2 < 0``, the right leg's ``> 0``).

    Singularities in closed form: type I (serial) when a leg is stretched or folded
    (``R2 = 0`` or ``π``); type II (parallel) when the two distal links are aligned
    (the pin on the line through both elbows).
    """
    a, l1, l2 = scale * half_base, scale * proximal, scale * distal
    pin_point = scale * np.array([home_xy[0], home_xy[1], 0.0])
    home = pin.SE3(np.eye(3), pin_point)
    legs, home_q = [], []
    for name, x, elbow in (("L", -a, -1), ("R", a, 1)):
        joints = [JointSpec("R1", "revolute", axis=_Z, lower=-math.pi, upper=math.pi),
                  JointSpec("R2", "revolute", xyz=(l1, 0.0, 0.0), axis=_Z,
                            lower=-math.pi, upper=math.pi)]
        xml = chain_urdf("rr_leg", joints, tip="tip", tip_xyz=(l2, 0.0, 0.0))
        base = pin.SE3(np.eye(3), np.array([x, 0.0, 0.0]))
        q = elbow_angles(base.translation, pin_point, l1, l2, elbow)
        legs.append(LegDesign.assembled(name, xml, "tip", ("R1",), base, q, home,
                                        "rr_leg.urdf"))
        home_q.append(q)
    return MechanismDesign(
        name="Five-bar", description="Planar five-bar: two RR legs joined by a revolute "
        "pin; actuated base revolutes; 2T", legs=legs, home=home, home_q=home_q,
        slug="five_bar", closure="revolute")


def delta_point(scale: float = 1.0, *, base_radius: float = 0.2, upper_arm: float = 0.3,
                rod: float = 0.8, home_arm_angle: float = 0.4) -> MechanismDesign:
    """Delta with a point platform: three legs at azimuths 0°, 120°, 240° about z, each
    ``R1`` (actuated, about the tangent to the base circle, leg frame y) – upper arm
    ``upper_arm`` (radial at ``R1 = 0``) – universal joint ``U1`` (about y) ``U2``
    (about z) – rod ``rod`` – tip; the three rod ends meet at a spherical pin. Home:
    ``R1 = home_arm_angle`` (arms down) and the pin on the z axis.

    Mobility 3T (9 joints − 2 × 3 closure rows); no idle motion (the rods' spins are
    not joints). Type I: a rod aligned with its upper arm; type II: the three rods
    parallel to one plane.
    """
    Rb, la, lr, q1 = scale * base_radius, scale * upper_arm, scale * rod, home_arm_angle
    elbow = np.array([Rb + la * math.cos(q1), 0.0, -la * math.sin(q1)])  # leg frame
    if elbow[0] >= lr:
        raise InputError("the rods are too short to meet on the z axis")
    depth = -elbow[2] + math.sqrt(lr * lr - elbow[0] ** 2)
    pin_point = np.array([0.0, 0.0, -depth])
    home = pin.SE3(np.eye(3), pin_point)
    joints = [JointSpec("R1", "revolute", axis=_Y, lower=-math.pi / 2, upper=math.pi / 2),
              JointSpec("U1", "revolute", xyz=(la, 0.0, 0.0), axis=_Y, lower=-math.pi,
                        upper=math.pi),
              JointSpec("U2", "revolute", axis=_Z, lower=-math.pi / 2, upper=math.pi / 2)]
    xml = chain_urdf("delta_point_leg", joints, tip="tip", tip_xyz=(lr, 0.0, 0.0))
    # the rod from the elbow to the pin, in the arm's frame (turned by R1 about y)
    d = pin.rpy.rpyToMatrix(0.0, q1, 0.0).T @ (np.array([0.0, 0.0, -depth]) - elbow)
    u1 = math.atan2(-d[2], d[0])
    legs, home_q = three_arms(xml, np.array([q1, u1, 0.0]), home, Rb, "delta_point_leg.urdf")
    return MechanismDesign(
        name="Delta (point platform)", description="Delta whose platform is a point: "
        "three R-U-rod legs joined by a spherical pin; actuated base revolutes; 3T",
        legs=legs, home=home, home_q=home_q, slug="delta_point", closure="spherical")
