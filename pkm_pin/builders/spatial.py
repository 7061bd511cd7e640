"""Spatial parallel mechanisms: 6-UPS Gough–Stewart, Delta, 3-UPU (Tsai), 3-RPS, 3-PRS,
agile eye (spherical 3-RRR).

Every length is multiplied by ``scale`` (``scale=1000`` builds the same mechanism in
millimetres); angles are in radians. The legs of the symmetric mechanisms stand at
azimuths 0°, 120°, 240° about the world z axis; the base lies in the plane z = 0.

At home, every leg has its base-side joint angles at 0 and its spherical groups (three
concurrent revolutes x, y, z) at 0, far from their gimbal lock (middle angle ±π/2): the
leg's base frame is turned so that its z axis points along the leg at home (the 3-PRS's
along its actuator, the rod turned by a fixed offset of its R joint).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from ..errors import InputError
from .design import LegDesign, MechanismDesign, frame_with_z
from .urdf_writer import JointSpec, chain_urdf

_X, _Y, _Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
_HALF_PI = 0.5 * math.pi
_AZIMUTHS = np.radians([0.0, 120.0, 240.0])


def _spherical(prefix: str = "S", xyz=(0.0, 0.0, 0.0)) -> list[JointSpec]:
    """Three concurrent revolutes about x, y, z (a spherical joint) at ``xyz`` in the
    previous joint's frame; the middle one limited to ±π/2 (its gimbal lock)."""
    return [
        JointSpec(f"{prefix}1", "revolute", xyz=xyz, axis=_X, lower=-math.pi, upper=math.pi),
        JointSpec(f"{prefix}2", "revolute", axis=_Y, lower=-_HALF_PI, upper=_HALF_PI),
        JointSpec(f"{prefix}3", "revolute", axis=_Z, lower=-math.pi, upper=math.pi),
    ]


def _ring(radius: float, azimuths) -> np.ndarray:
    a = np.asarray(azimuths, dtype=float)
    return radius * np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)])


def _tangent(azimuth: float) -> np.ndarray:
    return np.array([-math.sin(azimuth), math.cos(azimuth), 0.0])


# ==================================================================== Gough–Stewart
def stewart_default_points(scale: float = 1.0, base_radius: float = 1.0,
                           platform_radius: float = 0.5,
                           half_angle_deg: float = 15.0) -> tuple[np.ndarray, np.ndarray]:
    """Base (world) and platform (platform frame) points of the classic 6-6 layout.

    Base points at 0°, 120°, 240° ± ``half_angle_deg``, platform points at 60°, 180°,
    300° ± ``half_angle_deg``; each base point is paired with the nearest platform point
    (base 15° with platform 45°, base 105° with platform 75°, …), so neighbouring legs
    cross over in a zigzag. Rows are the legs, in order.
    """
    h = half_angle_deg
    base = np.radians([h, 120 - h, 120 + h, 240 - h, 240 + h, 360 - h])
    plat = np.radians([60 - h, 60 + h, 180 - h, 180 + h, 300 - h, 300 + h])
    return _ring(scale * base_radius, base), _ring(scale * platform_radius, plat)


def stewart(
    base_points=None,
    platform_points=None,
    scale: float = 1.0,
    *,
    home: pin.SE3 | None = None,
    height: float = 1.0,
    base_radius: float = 1.0,
    platform_radius: float = 0.5,
    stroke: tuple[float, float] = (0.3, 2.0),
    name: str = "6-UPS Gough–Stewart",
    description: str = "Gough–Stewart platform, 6-UPS, classic 6-6 layout; prismatic actuators",
    slug: str = "stewart",
    urdf_file: str = "ups_leg.urdf",
) -> MechanismDesign:
    """6-UPS Gough–Stewart platform (also the 6-SPS ℓ-coordinate body of seed 003,
    Demidov 2025, see docs/references.md).

    Leg URDF (shared by the six legs): ``U1`` revolute about x then ``U2`` about y at the
    base point, ``P`` prismatic along z (actuated; its value is the leg length), then a
    spherical joint ``S1``, ``S2``, ``S3`` (about x, y, z, concurrent) at the platform
    point, tip frame ``tip`` at the sphere centre. Each leg's base frame sits at its base
    point with its z axis along the leg at home (the smallest rotation taking world z
    there): at home ``U1 = U2 = 0``, ``P`` = leg length, ``S = 0``.

    Args:
        base_points: 6×3 base points in the world [m] (multiplied by ``scale``); default
            :func:`stewart_default_points`.
        platform_points: 6×3 platform points in the platform frame (multiplied by
            ``scale``); given together with ``base_points``.
        scale: Multiplies every length.
        home: Platform placement at home (its translation multiplied by ``scale``);
            default: ``height`` above the origin, not rotated.
        height: Home height of the platform frame (before scaling) when ``home`` is None.
        base_radius: Base radius of the default layout.
        platform_radius: Platform radius of the default layout.
        stroke: Prismatic limits as fractions: ``[stroke[0] · shortest home length,
            stroke[1] · longest home length]``.
        name: Mechanism name.
        description: One line.
        slug: File stem of the mechanism file.
        urdf_file: File name of the leg URDF (change it for a second geometry whose
            stroke differs).
    """
    if (base_points is None) != (platform_points is None):
        raise InputError("give both base_points and platform_points, or neither")
    if base_points is None:
        base, plat = stewart_default_points(scale, base_radius, platform_radius)
    else:
        base = scale * np.asarray(base_points, dtype=float)
        plat = scale * np.asarray(platform_points, dtype=float)
        if base.shape != (6, 3) or plat.shape != (6, 3):
            raise InputError(f"base_points and platform_points must be 6×3, got "
                             f"{base.shape} and {plat.shape}")
    if home is None:
        home = pin.SE3(np.eye(3), np.array([0.0, 0.0, scale * height]))
    else:
        home = pin.SE3(home.rotation, scale * home.translation)
    ends = np.array([home.act(p) for p in plat])
    lengths = np.linalg.norm(ends - base, axis=1)
    if np.any(lengths <= 0):
        raise InputError("a leg has zero length at home")
    joints = [
        JointSpec("U1", "revolute", axis=_X, lower=-_HALF_PI, upper=_HALF_PI),
        JointSpec("U2", "revolute", axis=_Y, lower=-_HALF_PI, upper=_HALF_PI),
        JointSpec("P", "prismatic", axis=_Z, lower=stroke[0] * lengths.min(),
                  upper=stroke[1] * lengths.max()),
        *_spherical("S"),
    ]
    xml = chain_urdf("ups_leg", joints, tip="tip")
    legs, home_q = [], []
    for i in range(6):
        leg_base = frame_with_z(base[i], ends[i] - base[i])
        q = np.array([0.0, 0.0, lengths[i], 0.0, 0.0, 0.0])
        legs.append(LegDesign.assembled(str(i + 1), xml, "tip", ("P",), leg_base, q, home,
                                        urdf_file))
        home_q.append(q)
    return MechanismDesign(name=name, description=description, legs=legs, home=home,
                           home_q=home_q, slug=slug)


# ============================================================================ Delta
def delta(
    scale: float = 1.0,
    *,
    base_radius: float = 0.2,
    platform_radius: float = 0.05,
    upper_arm: float = 0.3,
    forearm: float = 0.8,
    home_arm_angle: float = 0.4,
) -> MechanismDesign:
    """Delta robot: three legs R-(spatial parallelogram)-R at 0°, 120°, 240° about z.

    Leg URDF (``delta_leg.urdf``, shared): ``R1`` actuated revolute about u (the
    tangent to the base circle, leg frame y) at the base radius; upper arm of length
    ``upper_arm`` to the elbow; the parallelogram written with mimic joints: ``R2``
    (about u) and ``R3`` (about n, perpendicular to u and to the forearm at home,
    concurrent with R2) at the elbow, forearm of length ``forearm``, ``R4`` about n
    mimicking R3 ×(−1), ``R5`` about u mimicking R2 ×(−1) (the platform-side bar keeps
    the elbow bar's orientation), then ``R6``, a free revolute about u (the spin of the
    bar that the ball joints allow); tip frame ``tip`` at the platform bar. Velocity
    coordinates: R1, R2, R3, R6 (nv = 4).

    Home: platform horizontal, below the base, centred on the z axis; ``R1 =
    home_arm_angle`` (arms turned downwards), ``R2 = R3 = 0`` and R6 cancelling the
    turn of the bar about u (``R6 = −(R1 + forearm pitch)``: the tip frames have the
    platform's orientation turned by the leg's azimuth). For the defaults the
    forearm is 58° below horizontal and at 99° to the upper arm: far from the
    stretched/folded type I and the coplanar-forearm type II singularities. Expected
    mobility 3T with 3 redundant constraints (couples normal to each u).
    """
    Rb, rp = scale * base_radius, scale * platform_radius
    la, lf = scale * upper_arm, scale * forearm
    q1 = home_arm_angle
    # leg frame: x radial, y = u tangent, z up; elbow E, platform point P
    E = np.array([Rb + la * math.cos(q1), 0.0, -la * math.sin(q1)])
    dx = rp - E[0]
    if abs(dx) >= lf:
        raise InputError("the forearm is too short for this base/platform/upper arm")
    dz = -math.sqrt(lf * lf - dx * dx)
    h = -(E[2] + dz)  # platform depth below the base plane
    d_local = pin.rpy.rpyToMatrix(0.0, q1, 0.0).T @ np.array([dx, 0.0, dz])  # in R1's frame
    beta = math.atan2(-d_local[2], d_local[0])  # R_y(beta) x = forearm direction
    joints = [
        JointSpec("R1", "revolute", axis=_Y, lower=-_HALF_PI, upper=_HALF_PI),
        JointSpec("R2", "revolute", xyz=(la, 0.0, 0.0), rpy=(0.0, beta, 0.0), axis=_Y,
                  lower=-_HALF_PI, upper=_HALF_PI),
        JointSpec("R3", "revolute", axis=_Z, lower=-_HALF_PI, upper=_HALF_PI),
        JointSpec("R4", "revolute", xyz=(lf, 0.0, 0.0), axis=_Z, lower=-_HALF_PI,
                  upper=_HALF_PI, mimic=("R3", -1.0, 0.0)),
        JointSpec("R5", "revolute", axis=_Y, lower=-_HALF_PI, upper=_HALF_PI,
                  mimic=("R2", -1.0, 0.0)),
        JointSpec("R6", "revolute", axis=_Y, lower=-math.pi, upper=math.pi),
    ]
    xml = chain_urdf("delta_leg", joints, tip="tip")
    home = pin.SE3(np.eye(3), np.array([0.0, 0.0, -h]))
    q = _delta_q(xml, {"R1": q1, "R6": -(q1 + beta)})
    legs, home_q = three_arms(xml, q, home, Rb, "delta_leg.urdf")
    return MechanismDesign(
        name="Delta",
        description="Delta robot (3 R-Pa-R legs); actuated base revolutes; 3T",
        legs=legs, home=home, home_q=home_q, slug="delta")


def three_arms(xml: str, q: np.ndarray, home: pin.SE3, radius: float, urdf_file: str,
               actuated: tuple[str, ...] = ("R1",)
               ) -> tuple[list[LegDesign], list[np.ndarray]]:
    """Three legs (the URDF ``xml``, tip ``tip``, ``actuated`` joints: a Delta's ``R1``)
    at azimuths 0°, 120°, 240° on the base circle of ``radius``, each assembled at
    ``home`` with joint values ``q``: ``(legs, home_q)``."""
    legs, home_q = [], []
    for i, phi in enumerate(_AZIMUTHS):
        Rz = pin.rpy.rpyToMatrix(0.0, 0.0, phi)
        base = pin.SE3(Rz, Rz @ np.array([radius, 0.0, 0.0]))
        legs.append(LegDesign.assembled(str(i + 1), xml, "tip", actuated, base, q, home,
                                        urdf_file))
        home_q.append(q.copy())
    return legs, home_q


def _delta_q(xml: str, values: dict[str, float]) -> np.ndarray:
    """Configuration vector of the Delta leg with the given joints set, the others 0."""
    from ..leg import Leg

    leg = Leg.from_urdf(xml, "tip")
    q = np.zeros(leg.nq)
    for joint, value in values.items():
        q[leg.model.joints[leg.model.getJointId(joint)].idx_q] = value
    return q


# ============================================================================ 3-UPU
def _three_legs(scale, base_radius, platform_radius, height):
    """Base frames (z along the leg at home, x tangent), leg lengths, home."""
    home = pin.SE3(np.eye(3), np.array([0.0, 0.0, scale * height]))
    base = _ring(scale * base_radius, _AZIMUTHS)
    ends = [home.act(p) for p in _ring(scale * platform_radius, _AZIMUTHS)]
    frames = [frame_with_z(base[i], ends[i] - base[i], _tangent(_AZIMUTHS[i])) for i in range(3)]
    lengths = [float(np.linalg.norm(ends[i] - base[i])) for i in range(3)]
    return frames, lengths, home


def upu3(
    scale: float = 1.0,
    *,
    base_radius: float = 1.0,
    platform_radius: float = 0.4,
    height: float = 0.8,
    stroke: tuple[float, float] = (0.3, 2.0),
) -> MechanismDesign:
    """3-UPU translational parallel mechanism (Tsai); prismatic joints actuated.

    Leg URDF (``upu_leg.urdf``, shared): base universal joint ``U1`` (about x: the
    tangent to the base circle) then ``U2`` (about y, perpendicular), ``P`` prismatic
    along z (the leg; actuated), platform universal joint ``U3`` (about y, parallel to
    U2) then ``U4`` (about x, parallel to U1 at home and, with the platform not rotating,
    always), tip frame ``tip`` at the platform point. The leg's constraint is one couple,
    normal to both U axes. Base frames: x tangent, z along the leg at home; at home every
    revolute is at 0 and ``P`` is the leg length (1.0 for the defaults; stroke
    ``[0.3, 2.0]`` times it). Expected mobility 3T (Grübler 3).
    """
    frames, lengths, home = _three_legs(scale, base_radius, platform_radius, height)
    joints = [
        JointSpec("U1", "revolute", axis=_X, lower=-_HALF_PI, upper=_HALF_PI),
        JointSpec("U2", "revolute", axis=_Y, lower=-_HALF_PI, upper=_HALF_PI),
        JointSpec("P", "prismatic", axis=_Z, lower=stroke[0] * lengths[0],
                  upper=stroke[1] * lengths[0]),
        JointSpec("U3", "revolute", axis=_Y, lower=-_HALF_PI, upper=_HALF_PI),
        JointSpec("U4", "revolute", axis=_X, lower=-_HALF_PI, upper=_HALF_PI),
    ]
    xml = chain_urdf("upu_leg", joints, tip="tip")
    legs, home_q = [], []
    for i in range(3):
        q = np.array([0.0, 0.0, lengths[i], 0.0, 0.0])
        legs.append(LegDesign.assembled(str(i + 1), xml, "tip", ("P",), frames[i], q, home,
                                        "upu_leg.urdf"))
        home_q.append(q)
    return MechanismDesign(
        name="3-UPU (Tsai)",
        description="3-UPU translational parallel mechanism (Tsai); prismatic actuators; 3T",
        legs=legs, home=home, home_q=home_q, slug="upu3")


def upu3_constraint_singular_pose(scale: float = 1.0, **geometry) -> pin.SE3:
    """Pose of :func:`upu3` where the three legs' constraint couples are dependent.

    The platform is lowered (not rotated) into the base plane, centred: each leg's
    constraint couple, normal to its two U axes, is then horizontal (the legs are
    horizontal and radial), so the three couples span only the horizontal plane and
    the platform gains a rotation about z (a constraint singularity). Reachable with
    the default limits: legs of length ``base_radius − platform_radius`` = 0.6 ≥ 0.3,
    U1 = −0.93 rad.
    """
    del geometry  # the pose does not depend on the radii
    return pin.SE3(np.eye(3), np.zeros(3) * scale)


# ============================================================================ 3-RPS
def rps3(
    scale: float = 1.0,
    *,
    base_radius: float = 1.0,
    platform_radius: float = 0.5,
    height: float = 1.0,
    stroke: tuple[float, float] = (0.3, 2.0),
) -> MechanismDesign:
    """3-RPS parallel mechanism; prismatic joints actuated; 3 DOF (1T2R).

    Leg URDF (``rps_leg.urdf``, shared): ``R`` revolute about x (the tangent to the base
    circle) at the base point, ``P`` prismatic along z (the leg; actuated), spherical
    joint ``S1``, ``S2``, ``S3`` (about x, y, z) at the platform point, tip frame
    ``tip`` at the sphere centre. Base frames: x tangent, z along the leg at home; at
    home ``R = 0``, ``P`` = leg length (√1.25 for the defaults), ``S = 0``. The leg's
    constraint is a force through the sphere centre parallel to R.
    """
    frames, lengths, home = _three_legs(scale, base_radius, platform_radius, height)
    joints = [
        JointSpec("R", "revolute", axis=_X, lower=-_HALF_PI, upper=_HALF_PI),
        JointSpec("P", "prismatic", axis=_Z, lower=stroke[0] * lengths[0],
                  upper=stroke[1] * lengths[0]),
        *_spherical("S"),
    ]
    xml = chain_urdf("rps_leg", joints, tip="tip")
    legs, home_q = [], []
    for i in range(3):
        q = np.array([0.0, lengths[i], 0.0, 0.0, 0.0])
        legs.append(LegDesign.assembled(str(i + 1), xml, "tip", ("P",), frames[i], q, home,
                                        "rps_leg.urdf"))
        home_q.append(q)
    return MechanismDesign(
        name="3-RPS",
        description="3-RPS parallel mechanism; prismatic actuators; 1T2R",
        legs=legs, home=home, home_q=home_q, slug="rps3")


# ============================================================================ 3-PRS
def prs3(
    scale: float = 1.0,
    *,
    base_radius: float = 1.0,
    platform_radius: float = 0.4,
    leg_length: float = 1.0,
    height: float = 1.0,
    tilt: float = 0.0,
    stroke: tuple[float, float] = (0.0, 1.0),
) -> MechanismDesign:
    """3-PRS parallel mechanism: actuated prismatic joints on the base; 3 DOF (1T2R,
    driven by z, roll, pitch; x, y, yaw are parasitic).

    Leg URDF (``prs_leg.urdf``, shared): ``P`` prismatic along the leg frame's z (the
    actuator: vertical, or leaning by ``tilt`` towards the centre) from the base point at
    ``base_radius``; ``R`` revolute about the leg frame's y (the tangent to the base
    circle) at the slider; a rod of ``leg_length`` to the spherical joint ``S1``, ``S2``,
    ``S3`` (about x, y, z of the rod frame, concurrent) at ``platform_radius`` on the
    platform; tip frame ``tip`` at the sphere centre. Leg frames: x radial (outwards), y
    tangent, z the actuator axis (turned about y by ``tilt``). The leg's constraint is a
    force through the sphere centre parallel to R.

    Home: platform horizontal, centred, at ``height``; ``R = 0`` with the rod inclined in
    the radial plane from the slider to the sphere centre, ``S = 0``; ``P`` = the
    slider's travel from the base point (0.2 for the defaults: rod at 36.9° from the
    vertical, a 3-4-5 triangle), within ``stroke`` (limits of ``P`` [m], multiplied by
    ``scale``). The slider is below the sphere centre (the rod points upwards).
    """
    Rb, rp, rod, h = (scale * v for v in (base_radius, platform_radius, leg_length, height))
    a = np.array([-math.sin(tilt), 0.0, math.cos(tilt)])  # actuator axis, leg frame
    centre = np.array([rp - Rb, 0.0, h])  # sphere centre from the base point, leg frame
    # |s a − centre| = rod, the slider below the sphere: the smaller root
    b = a @ centre
    disc = b * b - (centre @ centre - rod * rod)
    if disc < 0:
        raise InputError("the rod is too short to reach the platform at this height")
    s0 = b - math.sqrt(disc)
    lower, upper = scale * stroke[0], scale * stroke[1]
    if not lower <= s0 <= upper:
        raise InputError(f"the slider's home travel {s0:.6g} is outside the stroke "
                         f"[{lower:.6g}, {upper:.6g}]")
    d = (centre - s0 * a) / rod  # rod direction, leg frame
    d_local = pin.rpy.rpyToMatrix(0.0, -tilt, 0.0).T @ d  # in P's frame (z = actuator)
    beta = math.atan2(d_local[0], d_local[2])  # R_y(beta) z = rod direction
    joints = [
        JointSpec("P", "prismatic", rpy=(0.0, -tilt, 0.0), axis=_Z, lower=lower, upper=upper),
        JointSpec("R", "revolute", rpy=(0.0, beta, 0.0), axis=_Y, lower=-_HALF_PI,
                  upper=_HALF_PI),
        *_spherical("S", xyz=(0.0, 0.0, rod)),
    ]
    xml = chain_urdf("prs_leg", joints, tip="tip")
    home = pin.SE3(np.eye(3), np.array([0.0, 0.0, h]))
    legs, home_q = three_arms(xml, np.array([s0, 0.0, 0.0, 0.0, 0.0]), home, Rb,
                              "prs_leg.urdf", ("P",))
    return MechanismDesign(
        name="3-PRS",
        description="3-PRS parallel mechanism; prismatic actuators on the base; 1T2R",
        legs=legs, home=home, home_q=home_q, slug="prs3")


# ========================================================================== agile eye
def agile_eye(scale: float = 1.0, *, centred: bool = True, radius: float = 0.1,
              centre: tuple[float, float, float] = (0.0, 0.0, 0.5)) -> MechanismDesign:
    """Agile eye (Gosselin's spherical 3-RRR): three R-R-R legs whose nine joint axes
    all pass through one centre, actuated base revolutes; 3R.

    Leg i's axes at home are ``(u, v, w) = (e_i, e_{i+1}, e_{i+2})`` (cyclic): the base
    axes are the world axes, the platform axes too, and every proximal and distal link
    spans 90°: the isotropic home (A's rows: unit couples along the base axes, B = I).
    The platform frame is at the centre with the world's orientation; ``home_q = 0``.

    ``centred=True`` writes every joint frame at the centre (zero offsets between the
    three revolutes: the natural way, and three concurrent revolutes that are *not* a
    spherical joint since one is actuated); ``centred=False`` puts joint k's frame at
    ``radius`` along its axis (the same lines). Both describe the same mechanism.
    """
    c = scale * np.asarray(centre, dtype=float)
    r = 0.0 if centred else scale * radius
    legs, home_q = [], []
    home = pin.SE3(np.eye(3), c)
    for i in range(3):
        u, v, w = (np.eye(3)[(i + k) % 3] for k in range(3))
        joints = [JointSpec("R1", "revolute", xyz=tuple(r * u), axis=tuple(u)),
                  JointSpec("R2", "revolute", xyz=tuple(r * (v - u)), axis=tuple(v)),
                  JointSpec("R3", "revolute", xyz=tuple(r * (w - v)), axis=tuple(w))]
        name = f"agile_eye_leg{i + 1}" + ("" if centred else "_offset")
        xml = chain_urdf(name, joints, tip="tip", tip_xyz=tuple(-r * w))
        q = np.zeros(3)
        legs.append(LegDesign.assembled(str(i + 1), xml, "tip", ("R1",), pin.SE3(np.eye(3), c),
                                        q, home, f"{name}.urdf"))
        home_q.append(q)
    return MechanismDesign(
        name="Agile eye" + ("" if centred else " (offset frames)"),
        description="Spherical 3-RRR (agile eye): nine revolute axes through one centre; "
        "actuated base revolutes; 3R", legs=legs, home=home, home_q=home_q,
        slug="agile_eye" + ("" if centred else "_offset"))
