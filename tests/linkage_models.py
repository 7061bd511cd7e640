"""Small closed-loop mechanisms built with the Pinocchio Model API, for the linkage tests.

Every builder takes ``scale`` (lengths multiplied: metres → millimetres with 1000) and
``where`` (a rigid placement of the whole mechanism in the world).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pkm_pin.model.closure_model import Closure, ClosureModel

#: Four-bar crank-rocker (Grashof: s + l = 0.9 <= p + q = 1.1, the crank the shortest).
CRANK, COUPLER, ROCKER, GROUND = 0.2, 0.6, 0.5, 0.7


def _xyz(x, y, z=0.0) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([x, y, z], dtype=float))


def four_bar(kind: str = "point", scale: float = 1.0, where: pin.SE3 | None = None,
             actuated=("crank",), output: str = "rocker_body", lengths=None) -> ClosureModel:
    """Planar four-bar in the xy plane of ``where``: crank (RZ at O_A), coupler (RZ at
    the crank's end), rocker (RZ at O_B = (GROUND, 0)); ``kind`` closure between the
    coupler's end and the rocker's end."""
    a, b, c, d = np.array(lengths or (CRANK, COUPLER, ROCKER, GROUND)) * scale
    W = where or pin.SE3.Identity()
    tree = pin.Model()
    j1 = tree.addJoint(0, pin.JointModelRZ(), W, "crank")
    tree.addBodyFrame("crank_body", j1, pin.SE3.Identity(), tree.addJointFrame(j1))
    j2 = tree.addJoint(j1, pin.JointModelRZ(), _xyz(a, 0), "coupler")
    tree.addBodyFrame("coupler_body", j2, pin.SE3.Identity(), tree.addJointFrame(j2))
    tree.addBodyFrame("coupler_end", j2, _xyz(b, 0), tree.addJointFrame(j2))
    j3 = tree.addJoint(0, pin.JointModelRZ(), W * _xyz(d, 0), "rocker")
    tree.addBodyFrame("rocker_body", j3, pin.SE3.Identity(), tree.addJointFrame(j3))
    tree.addBodyFrame("rocker_end", j3, _xyz(c, 0), tree.addJointFrame(j3))
    return ClosureModel(tree, (Closure(kind, "coupler_end", "rocker_end", name="loop"),),
                        actuated, output, "four-bar")


def four_bar_angles(theta2: float, lengths=None) -> tuple[float, float, float]:
    """Closed form (open branch, rocker above the ground line): coupler and rocker
    absolute angles θ3, θ4 and the transmission angle μ (between coupler and rocker)."""
    a, b, c, d = lengths or (CRANK, COUPLER, ROCKER, GROUND)
    C = a * np.array([np.cos(theta2), np.sin(theta2)])
    k = C - np.array([d, 0.0])
    kk = k @ k
    theta4 = np.arctan2(k[1], k[0]) + np.arccos((kk + c * c - b * b) / (2 * c * np.sqrt(kk)))
    D = np.array([d, 0.0]) + c * np.array([np.cos(theta4), np.sin(theta4)])
    theta3 = np.arctan2(*(D - C)[::-1])
    mu = np.arccos((b * b + c * c - kk) / (2 * b * c))
    return theta3, theta4, mu


def four_bar_dead_centre() -> tuple[float, np.ndarray]:
    """The crank angle θ2 of the extended dead centre (crank and coupler collinear:
    |O_A D| = a + b, |O_B D| = c) and the tree configuration there."""
    d, s = GROUND, CRANK + COUPLER
    x = (s * s - ROCKER ** 2 + d * d) / (2 * d)
    D = np.array([x, np.sqrt(s * s - x * x)])
    theta2 = float(np.arctan2(D[1], D[0]))
    return theta2, np.array([theta2, 0.0, np.arctan2(D[1], D[0] - d)])


def four_bar_q(theta2: float) -> np.ndarray:
    """Tree configuration (crank, coupler relative, rocker) of :func:`four_bar_angles`."""
    t3, t4, _ = four_bar_angles(theta2)
    return np.array([theta2, t3 - theta2, t4])


def five_bar(kind: str = "revolute", scale: float = 1.0, where: pin.SE3 | None = None
             ) -> ClosureModel:
    """Planar five-bar: R-R branches from (0, 0) and (1.5, 0), unit links, their ends
    joined by a ``kind`` closure; actuated A1, B1; output: the end of branch A."""
    W = where or pin.SE3.Identity()
    tree = pin.Model()
    for branch, x in (("A", 0.0), ("B", 1.5)):
        j1 = tree.addJoint(0, pin.JointModelRZ(), W * _xyz(x * scale, 0), f"{branch}1")
        j2 = tree.addJoint(j1, pin.JointModelRZ(), _xyz(scale, 0), f"{branch}2")
        tree.addBodyFrame(f"{branch}_end", j2, _xyz(scale, 0), tree.addJointFrame(j2))
    return ClosureModel(tree, (Closure(kind, "A_end", "B_end", name="tip"),), ("A1", "B1"),
                        "A_end", "five-bar")


def five_bar_q(P, elbow_a: float = 1.0, elbow_b: float = -1.0) -> np.ndarray:
    """Configuration (A1, A2, B1, B2) with the common end at ``P`` (unit links)."""
    q = []
    for base, s in ((np.zeros(2), elbow_a), (np.array([1.5, 0.0]), elbow_b)):
        r = np.asarray(P, float) - base
        dist = np.linalg.norm(r)
        t1 = np.arctan2(r[1], r[0]) + s * np.arccos(min(1.0, dist / 2))
        E = base + np.array([np.cos(t1), np.sin(t1)])
        q += [t1, np.arctan2(*(np.asarray(P) - E)[::-1]) - t1]
    return np.array(q)


#: RSSR-like loop: crank (RZ at the origin, arm 0.3), a rod with a spherical joint at
#: the crank's end (length 0.8), point-closed to a rocker (RX at G, arm 0.5).
ROD, ARM, ROCKER_ARM, G = 0.8, 0.3, 0.5, (0.2, 0.9, 0.4)


def spherical_rod(scale: float = 1.0, where: pin.SE3 | None = None) -> ClosureModel:
    """Spatial loop whose rod (spherical at one end, spherical closure at the other)
    has an idle spin about its own axis."""
    W = where or pin.SE3.Identity()
    tree = pin.Model()
    j1 = tree.addJoint(0, pin.JointModelRZ(), W, "crank")
    j2 = tree.addJoint(j1, pin.JointModelSpherical(), _xyz(ARM * scale, 0), "ball")
    tree.addBodyFrame("rod", j2, pin.SE3.Identity(), tree.addJointFrame(j2))
    tree.addBodyFrame("rod_end", j2, _xyz(ROD * scale, 0), tree.addJointFrame(j2))
    j3 = tree.addJoint(0, pin.JointModelRX(), W * _xyz(*(np.array(G) * scale)), "rocker")
    tree.addBodyFrame("rocker_body", j3, pin.SE3.Identity(), tree.addJointFrame(j3))
    tree.addBodyFrame("rocker_end", j3, _xyz(0, ROCKER_ARM * scale), tree.addJointFrame(j3))
    return ClosureModel(tree, (Closure("point", "rod_end", "rocker_end", name="rod_socket"),),
                        ("crank",), "rocker_body", "rssr")
