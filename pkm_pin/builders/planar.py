"""Planar parallel mechanisms: the 3-RPR of seed 000 (xz-plane) and a 3-RRR (xy-plane).

Seed 000: Michalková & Guldan, see docs/references.md.

Every length is multiplied by ``scale`` (``scale=1000`` builds the same mechanism in
millimetres); angles are in radians.

Conventions of the 3-RPR (seed 000, §5, the paper's 3-RTR): the mechanism moves in the
xz-plane, y is normal to it. A revolute about +y by ``q`` turns +x into
``(cos q, 0, −sin q)``, so the paper's leg angle (from +x towards +z) is ``α = −q``; the
platform angle ``θ`` below is the rotation about +y of the platform (``rpy = (0, θ, 0)``).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
from scipy.optimize import brentq

from .design import LegDesign, MechanismDesign, placement
from .urdf_writer import JointSpec, chain_urdf

_Y = (0.0, 1.0, 0.0)
_Z = (0.0, 0.0, 1.0)


# =========================================================================== 3-RPR
def _rpr3_geometry(scale, L3, L6, platform_radius):
    """Base pivots (3×3, world) and platform pivots (3×3, platform frame)."""
    base = scale * np.array([[0.0, 0.0, 0.0], [L3, 0.0, 0.0], [L3 + L6, 0.0, 0.0]])
    angles = np.radians([210.0, 90.0, 330.0])  # A2 lower left, B2 top, C2 lower right
    platform = scale * platform_radius * np.column_stack(
        [np.cos(angles), np.zeros(3), np.sin(angles)])
    return base, platform


def _planar_pose(x: float, z: float, theta: float) -> pin.SE3:
    """Platform placement in the xz-plane: centre (x, 0, z), rotation θ about +y."""
    return placement((x, 0.0, z), (0.0, theta, 0.0))


def rpr3(
    scale: float = 1.0,
    *,
    L3: float = 1.0,
    L6: float = 1.0,
    platform_radius: float = 0.4,
    home_xz: tuple[float, float] = (0.8, 0.6),
    home_angle: float = 0.6,
    stroke: tuple[float, float] = (0.2, 3.0),
) -> MechanismDesign:
    """The planar 3-RPR of seed 000 §5 (3-RTR): actuated A1 (P), B0 (R), C1 (P).

    Base pivots on the x axis: A0 = (0, 0, 0), B0 = (L3, 0, 0), C0 = (L3 + L6, 0, 0).
    Each leg: revolute ``X0`` about +y at the base pivot (limits centred on the upward
    direction, ``X0 = −π/2``; the leg angle is ``α = −X0``), prismatic ``X1`` along the
    leg (its value is the distance |X0 X2| [m], limits ``stroke``), revolute ``X2``
    about +y at the platform pivot, tip frame ``tip`` at X2. The platform is an
    equilateral triangle of pivots A2, B2, C2 (circumradius ``platform_radius``) with the
    platform frame at its centroid.

    Home: centre ``(home_xz[0], 0, home_xz[1])``, rotation ``home_angle`` about +y, with
    ``X2 = 0``. It was chosen on a grid as the pose maximising the smaller of the
    relative smallest singular values of the actuation wrench lines (paper's actuation)
    and of the three leg lines (all-prismatic actuation), with the platform above the
    base: both are about 0.18 and 0.22 there (a symmetric pose ``θ = 0`` with the
    platform centred over B0 has the three leg lines concurrent).

    Args:
        scale: Multiplies every length.
        L3: |A0 B0| (before scaling).
        L6: |B0 C0| (before scaling).
        platform_radius: Circumradius of the platform triangle.
        home_xz: Home position (x, z) of the platform centre.
        home_angle: Home rotation of the platform about +y [rad].
        stroke: Limits of the prismatic joints, as lengths (before scaling).
    """
    base, platform = _rpr3_geometry(scale, L3, L6, platform_radius)
    home = _planar_pose(scale * home_xz[0], scale * home_xz[1], home_angle)
    actuated = {"A": "A1", "B": "B0", "C": "C1"}
    legs, home_q = [], []
    for i, X in enumerate("ABC"):
        joints = [
            JointSpec(f"{X}0", "revolute", axis=_Y, lower=-1.5 * math.pi, upper=0.5 * math.pi),
            JointSpec(f"{X}1", "prismatic", axis=(1.0, 0.0, 0.0),
                      lower=scale * stroke[0], upper=scale * stroke[1]),
            JointSpec(f"{X}2", "revolute", axis=_Y, lower=-2 * math.pi, upper=2 * math.pi),
        ]
        xml = chain_urdf(f"rpr_leg_{X.lower()}", joints, tip="tip")
        d = home.act(platform[i]) - base[i]
        q0 = -math.atan2(d[2], d[0])
        q = np.array([q0, np.linalg.norm(d), home_angle - q0])
        legs.append(LegDesign.assembled(X, xml, "tip", (actuated[X],),
                                        pin.SE3(np.eye(3), base[i]), q, home,
                                        f"rpr_leg_{X.lower()}.urdf"))
        home_q.append(q)
    return MechanismDesign(
        name="3-RPR (seed 000)",
        description="Planar 3-RPR (paper: 3-RTR) in the xz-plane; actuated A1 (P), B0 (R), C1 (P)",
        legs=legs, home=home, home_q=home_q, slug="rpr3")


def _line2(point, direction) -> np.ndarray:
    """Planar line coordinates (d_x, d_z, x d_z − z d_x) of a line in the xz-plane."""
    d = np.asarray(direction, dtype=float)[[0, 2]]
    d = d / np.linalg.norm(d)
    p = np.asarray(point, dtype=float)[[0, 2]]
    return np.array([d[0], d[1], p[0] * d[1] - p[1] * d[0]])


def rpr3_wrench_lines(pose: pin.SE3, scale: float = 1.0, *, L3: float = 1.0, L6: float = 1.0,
                      platform_radius: float = 0.4, actuated: str = "PRP") -> np.ndarray:
    """3×3 planar line coordinates ``(d_x, d_z, x d_z − z d_x)`` of the actuation wrenches.

    For an actuated prismatic leg the wrench reciprocal to its passive joints (the two
    revolutes) is the force along the leg line; for the actuated base revolute of leg B
    (passive: prismatic and platform revolute) it is the force through B2 normal to the
    leg. ``actuated="PPP"`` gives the three leg lines. The rows are unit in direction,
    moments divided by ``scale``; the determinant vanishes exactly when the three lines
    are concurrent or parallel (type II singularity).
    """
    base, platform = _rpr3_geometry(scale, L3, L6, platform_radius)
    rows = []
    for i, kind in enumerate(actuated):
        P = pose.act(platform[i])
        d = P - base[i]
        if kind == "R":
            d = np.array([-d[2], 0.0, d[0]])
        row = _line2(P, d)
        row[2] /= scale
        rows.append(row)
    return np.array(rows)


def rpr3_type2_pose(scale: float = 1.0, *, actuated: str = "PRP", **geometry) -> pin.SE3:
    """Platform pose of :func:`rpr3` at a type II singularity (actuation wrenches concurrent).

    How it is found: the platform is translated along +x from home (same height, same
    angle); the determinant of :func:`rpr3_wrench_lines` changes sign before the centre
    has moved by ``L3 + L6`` (between x = 1.8 and 2.0 for the default geometry) and
    ``brentq`` locates the root to machine precision. With the paper's actuation (A1,
    B0, C1) the concurrent lines are leg A, leg C and the normal to leg B at B2 — not
    the three leg lines. With ``actuated="PPP"`` the pose where the three leg lines
    themselves are concurrent (the type II singularity of the all-prismatic 3-RPR) is
    returned. Every leg length stays inside the stroke at both poses (checked by the
    tests).

    Args:
        scale: As for :func:`rpr3`.
        actuated: ``"PRP"`` (the paper's actuation) or ``"PPP"``.
        **geometry: ``L3``, ``L6``, ``platform_radius``, ``home_xz``, ``home_angle`` as
            given to :func:`rpr3`.
    """
    lines = {k: geometry[k] for k in ("L3", "L6", "platform_radius") if k in geometry}
    x, z = geometry.get("home_xz", (0.8, 0.6))
    theta0 = geometry.get("home_angle", 0.6)

    def det(xi: float) -> float:
        pose = _planar_pose(scale * xi, scale * z, theta0)
        return float(np.linalg.det(rpr3_wrench_lines(pose, scale, actuated=actuated, **lines)))

    span = geometry.get("L3", 1.0) + geometry.get("L6", 1.0)
    xs = x + np.linspace(0.0, span, 201)
    values = [det(xi) for xi in xs]
    for k in range(len(xs) - 1):
        if values[k] * values[k + 1] <= 0.0:
            xi = brentq(det, xs[k], xs[k + 1], xtol=1e-15, rtol=1e-15)
            return _planar_pose(scale * xi, scale * z, theta0)
    raise RuntimeError("no type II singularity found along +x from home")  # pragma: no cover


# =========================================================================== 3-RRR
def _rrr3_geometry(scale, base_radius, platform_radius):
    angles = np.radians([90.0, 210.0, 330.0])
    ring = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(3)])
    return scale * base_radius * ring, scale * platform_radius * ring


def _rrr3_leg_q(base: pin.SE3, p, l1, l2, elbow: int) -> np.ndarray:
    """Joint values (R1, R2, R3) placing the leg's R3 at world point ``p`` with elbow
    sign ``elbow``; the tip frame keeps the orientation of the leg's base frame."""
    d = base.actInv(p)
    r = np.linalg.norm(d[:2])
    c2 = (r * r - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    q2 = elbow * math.acos(np.clip(c2, -1.0, 1.0))
    q1 = math.atan2(d[1], d[0]) - math.atan2(l2 * math.sin(q2), l1 + l2 * math.cos(q2))
    return np.array([q1, q2, -(q1 + q2)])


def rrr3(
    scale: float = 1.0,
    *,
    base_radius: float = 1.0,
    platform_radius: float = 0.25,
    links: tuple[float, float] = (0.6, 0.6),
    elbows: tuple[int, int, int] = (1, 1, 1),
) -> MechanismDesign:
    """Planar 3-RRR in the xy-plane (axes +z); the first revolute of each leg actuated.

    Base points on a circle of radius ``base_radius`` at 90°, 210°, 330°; platform
    pivots on a circle of radius ``platform_radius`` at the same angles (platform frame
    at the centre). Leg ``"k"`` has joints ``R1`` (at the base point), ``R2`` (elbow,
    ``links[0]`` further), ``R3`` (platform pivot, ``links[1]`` further) and the tip
    frame at R3. The URDF root of each leg is at its base point, its x axis pointing to
    the centre of the base circle (so R1 is near 0 at home, mid-range).

    Home: platform centred at the origin, not rotated; working mode ``elbows`` (the sign
    of R2 in each leg; all +1: every elbow on the same side). Each leg reaches 0.75 of
    its 1.2 at home (R2 ≈ ±1.79 rad: far from the stretched and folded type I
    singularities); the three distal links are not concurrent (no type II).
    """
    base, platform = _rrr3_geometry(scale, base_radius, platform_radius)
    l1, l2 = scale * links[0], scale * links[1]
    home = pin.SE3.Identity()
    joints = [
        JointSpec("R1", "revolute", axis=_Z, lower=-math.pi, upper=math.pi),
        JointSpec("R2", "revolute", xyz=(l1, 0.0, 0.0), axis=_Z, lower=-math.pi, upper=math.pi),
        JointSpec("R3", "revolute", xyz=(l2, 0.0, 0.0), axis=_Z, lower=-math.pi, upper=math.pi),
    ]
    xml = chain_urdf("rrr_leg", joints, tip="tip")
    legs, home_q = [], []
    for i in range(3):
        inward = math.atan2(-base[i][1], -base[i][0])
        leg_base = placement(base[i], (0.0, 0.0, inward))
        q = _rrr3_leg_q(leg_base, home.act(platform[i]), l1, l2, elbows[i])
        legs.append(LegDesign.assembled(str(i + 1), xml, "tip", ("R1",), leg_base, q, home,
                                        "rrr_leg.urdf"))
        home_q.append(q)
    return MechanismDesign(
        name="3-RRR",
        description="Planar 3-RRR in the xy-plane; first revolute of each leg actuated",
        legs=legs, home=home, home_q=home_q, slug="rrr3")


def rrr3_elbow_signs(home_q) -> tuple[int, ...]:
    """Working mode of a 3-RRR configuration: the sign of R2 in each leg."""
    return tuple(int(np.sign(q[1])) for q in home_q)


def rrr3_stretched_pose(scale: float = 1.0, *, base_radius: float = 1.0,
                        platform_radius: float = 0.25,
                        links: tuple[float, float] = (0.6, 0.6)) -> pin.SE3:
    """Platform pose of :func:`rrr3` where leg 1 is fully stretched (R2 = 0, type I).

    The platform is translated (no rotation) from home along the line from base point 1
    through platform pivot 1 until that distance is ``links[0] + links[1]``; legs 2 and
    3 stay reachable (distances 0.65 of their 1.2 for the defaults).
    """
    base, platform = _rrr3_geometry(scale, base_radius, platform_radius)
    d = platform[0] - base[0]
    target = base[0] + d / np.linalg.norm(d) * scale * (links[0] + links[1])
    return pin.SE3(np.eye(3), target - platform[0])
