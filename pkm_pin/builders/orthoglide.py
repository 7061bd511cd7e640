"""Orthoglide of seed 001: three P-R-Pa-R legs on (quasi-)orthogonal linear actuators.

Seed 001: Pashkevich & Gomolitsky 2007, see docs/references.md.

Every leg is written in its own *leg frame* ``(n_i, a_i, o_i)``: ``x`` along the nominal
actuator axis ``n_i``, ``z`` along the offset direction ``o_i`` of ``dd_i``, ``y = z × x``.
The three leg frames are the cyclic permutations of the world axes (leg x: the world
frame; leg y: ``(e_y, e_z, e_x)``; leg z: ``(e_z, e_x, e_y)``), so that in its frame every
leg has the form of the paper's leg x: ``g = (ρ cos φ, 0, ρ sin φ + dd)`` (seed 001, eq. 5).

Leg URDF (one file per leg and geometry; joint names as in the issue):

* ``P`` — actuated prismatic, origin ``(0, 0, dd)``, axis ``(cos φ, 0, sin φ)`` (the axis
  tilt is in the joint axis, the carriage keeps the nominal orientation), value ``ρ``;
* ``R1`` — revolute about the leg frame's ``z`` at the carriage point ``g`` (``rpy = (0, 0,
  π)``: its ``x`` points back towards the platform);
* ``Pa1`` / ``Pa2`` — the parallelogram: ``Pa1`` revolute about ``y`` at ``g``, ``Pa2``
  revolute about ``y`` at distance ``L`` along the bar (``origin.x = L``), mimicking
  ``Pa1`` with multiplier −1: the coupler keeps the carriage's orientation turned by R1;
* ``R2`` — revolute about ``z`` (parallel to R1) at the bar's end ``C``;
* tip frame ``tip`` at ``C``.

So ``|C − g| = L`` and each leg lets the platform turn only about its ``R`` axis: it
constrains two rotations (two couples), the three legs together all three: 3T with 3
redundant constraints (Grübler 6(1 − 3) + 3·4 = 0). The anchor of leg ``i`` puts ``C_i``
at ``e n_i`` from the tool point ``p`` (platform origin): ``|p + e n_i − g_i| = L_i``.
Working mode: carriages on the positive half-axes beyond the platform (``s_i = +1`` in
eq. 3), bars pointing from the carriage back towards the platform. For the nominal
machine the home ``p = 0`` is the isotropic point: bars along the axes, ``ρ_i = L + e``.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from ..errors import InputError
from .design import LegDesign, MechanismDesign
from .urdf_writer import JointSpec, chain_urdf

#: Leg names, in the order of the paper's legs (x, y, z).
LEG_NAMES = ("legx", "legy", "legz")
#: Rotation of each leg frame in the world (columns: n_i, z × n_i, o_i).
LEG_ROTATIONS = (
    np.eye(3),
    np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
    np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]),
)
#: Quasi-orthogonal geometry shipped as ``orthoglide_quasi`` (before scaling).
QUASI = {"L": (1.01, 0.99, 1.005), "phi": (0.02, -0.015, 0.01), "dd": (0.01, -0.02, 0.015)}


def _triple(value, name: str) -> np.ndarray:
    a = np.broadcast_to(np.asarray(value, dtype=float), (3,)).copy()
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name} must be finite, got {value}")
    return a


def orthoglide_leg_urdf(L: float, phi: float, dd: float, stroke: tuple[float, float],
                        angle_limit: float = 0.5 * math.pi, robot_name: str = "orthoglide_leg"
                        ) -> str:
    """URDF text of one P-R-Pa-R leg in its leg frame (see the module docstring)."""
    lim = float(angle_limit)
    joints = [
        JointSpec("P", "prismatic", xyz=(0.0, 0.0, dd), axis=(math.cos(phi), 0.0, math.sin(phi)),
                  lower=stroke[0], upper=stroke[1]),
        JointSpec("R1", "revolute", rpy=(0.0, 0.0, math.pi), axis=(0.0, 0.0, 1.0),
                  lower=-lim, upper=lim),
        JointSpec("Pa1", "revolute", axis=(0.0, 1.0, 0.0), lower=-lim, upper=lim),
        JointSpec("Pa2", "revolute", xyz=(L, 0.0, 0.0), axis=(0.0, 1.0, 0.0), lower=-lim,
                  upper=lim, mimic=("Pa1", -1.0, 0.0)),
        JointSpec("R2", "revolute", axis=(0.0, 0.0, 1.0), lower=-lim, upper=lim),
    ]
    return chain_urdf(robot_name, joints, tip="tip")


def _leg_home(L: float, phi: float, dd: float, c_local: np.ndarray) -> np.ndarray:
    """Joint values ``(ρ, R1, Pa1, R2)`` placing the bar's end at ``c_local`` (leg frame),
    carriage beyond the platform (``s = +1``), ``R2 = −R1`` (tip frame unturned)."""
    u = np.array([math.cos(phi), 0.0, math.sin(phi)])
    c = c_local - np.array([0.0, 0.0, dd])
    cu = float(c @ u)
    disc = L * L - float(c @ c) + cu * cu
    if disc <= 0:
        raise InputError(f"the home point is out of reach of a leg (L = {L})")
    rho = cu + math.sqrt(disc)
    d = c_local - (np.array([0.0, 0.0, dd]) + rho * u)   # bar from g to C, leg frame
    d_r1 = np.array([-d[0], -d[1], d[2]])                # in R1's frame (yaw π)
    theta = math.atan2(d_r1[1], d_r1[0])
    beta = math.asin(max(-1.0, min(1.0, -d_r1[2] / L)))
    return np.array([rho, theta, beta, -theta])


def orthoglide(
    scale: float = 1.0,
    *,
    L=1.0,
    phi=0.0,
    dd=0.0,
    e: float = 0.1,
    home=(0.0, 0.0, 0.0),
    stroke: tuple[float, float] = (-0.5, 0.5),
    angle_limit: float = 0.5 * math.pi,
    name: str = "Orthoglide",
    slug: str = "orthoglide",
    description: str = "Orthoglide (3 P-R-Pa-R legs, orthogonal linear actuators); 3T",
) -> MechanismDesign:
    """Orthoglide design from the paper's named parameters (defaults: nominal machine).

    Args:
        scale: Multiplies every length (``L``, ``dd``, ``e``, ``home``, ``stroke``).
        L: Parallelogram lengths ``L_i`` (one value or three) [m].
        phi: Actuator axis tilts ``φ_i`` [rad].
        dd: Actuator axis offsets ``Δd_i`` [m].
        e: Tool offset: distance from the platform point to each bar's end [m].
        home: Platform point at home [m]; the platform is not rotated.
        stroke: Prismatic limits relative to the home value of ``ρ_i``, as multiples of
            ``L_i`` (``ρ ∈ ρ_home + stroke · L``).
        angle_limit: Limits ``±angle_limit`` of the revolutes [rad].
        name: Mechanism name.
        slug: File stem; URDF files are ``<slug>_<leg>.urdf``.
        description: One line.
    """
    Ls, phis, dds = _triple(L, "L") * scale, _triple(phi, "phi"), _triple(dd, "dd") * scale
    if np.any(Ls <= 0):
        raise InputError(f"leg lengths must be positive, got {Ls}")
    e = float(e) * scale
    p_home = np.asarray(home, dtype=float) * scale
    home_pose = pin.SE3(np.eye(3), p_home)
    legs, home_q = [], []
    for i, leg_name in enumerate(LEG_NAMES):
        Rl = LEG_ROTATIONS[i]
        c_local = Rl.T @ (p_home + e * Rl[:, 0])
        q4 = _leg_home(Ls[i], phis[i], dds[i], c_local)
        lo, up = q4[0] + stroke[0] * Ls[i], q4[0] + stroke[1] * Ls[i]
        xml = orthoglide_leg_urdf(float(Ls[i]), float(phis[i]), float(dds[i]), (lo, up),
                                  angle_limit, robot_name=f"{slug}_{leg_name}")
        q = q4  # configuration vector: P, R1, Pa1, R2 (Pa2 mimics Pa1)
        legs.append(LegDesign.assembled(leg_name, xml, "tip", ("P",), pin.SE3(Rl, np.zeros(3)),
                                        q, home_pose, f"{slug}_{leg_name}.urdf"))
        home_q.append(q)
    return MechanismDesign(name=name, description=description, legs=legs, home=home_pose,
                           home_q=home_q, slug=slug)


def orthoglide_quasi(scale: float = 1.0, **geometry) -> MechanismDesign:
    """Quasi-orthogonal Orthoglide: :func:`orthoglide` with :data:`QUASI` (tilted, offset
    axes and unequal legs) unless overridden."""
    params = {**QUASI, "name": "Orthoglide (quasi-orthogonal)", "slug": "orthoglide_quasi",
              "description": "Orthoglide with tilted/offset actuator axes and unequal legs "
                             "(seed 001 model); 3T"}
    params.update(geometry)
    return orthoglide(scale, **params)
