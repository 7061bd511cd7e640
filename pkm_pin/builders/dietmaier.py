"""Dietmaier's Stewart–Gough platform: the general 6-6 geometry with 40 real postures.

P. Dietmaier, "The Stewart-Gough platform of general geometry can have 40 real
postures", Advances in Robot Kinematics: Analysis and Control (ARK), Kluwer, 1998,
pp. 7–16. The published data (six digits) are the base points ``a_i`` (world), the
platform points ``b_i`` (platform frame) and the leg lengths ``l_i``; at these lengths
all 40 complex solutions of the forward problem are real (checked by
:func:`pkm_pin.modes.stewart_gough_postures`; see ``tests/test_modes.py``).

Not in :data:`pkm_pin.builders.MECHANISMS` (a test geometry, not a machine): build it
with :func:`dietmaier` and ``.build()``.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from .design import LegDesign, MechanismDesign, frame_with_z
from .spatial import _spherical
from .urdf_writer import JointSpec, chain_urdf

#: Base points ``a_i`` in the world [m] (Dietmaier 1998).
DIETMAIER_BASE = np.array([
    [0.0, 0.0, 0.0],
    [1.107915, 0.0, 0.0],
    [0.549094, 0.756063, 0.0],
    [0.735077, -0.223935, 0.525991],
    [0.514188, -0.526063, -0.368418],
    [0.590473, 0.094733, -0.205018],
])
#: Platform points ``b_i`` in the platform frame [m] (Dietmaier 1998).
DIETMAIER_PLATFORM = np.array([
    [0.0, 0.0, 0.0],
    [0.542805, 0.0, 0.0],
    [0.956919, -0.528915, 0.0],
    [0.665885, -0.353482, 1.402538],
    [0.478359, 1.158742, 0.107672],
    [-0.137087, -0.235121, 0.353913],
])
#: Leg lengths ``l_i`` [m] at which the 40 postures are real (Dietmaier 1998).
DIETMAIER_LENGTHS = np.array([1.0, 0.645275, 1.086284, 1.503439, 1.281933, 0.771071])
#: The home posture: the best-conditioned of the 40 (type II index 0.16), translation
#: [m] and unit quaternion (w, x, y, z) of the platform frame, as computed by
#: :func:`pkm_pin.modes.stewart_gough_postures` (its leg lengths equal
#: :data:`DIETMAIER_LENGTHS` to 1e-15).
DIETMAIER_HOME_TRANSLATION = (0.6361117806578847, 0.7714519603665408, 0.01495577998220024)
DIETMAIER_HOME_QUATERNION = (0.5116908851624843, 0.6634530831683867, -0.008880171196940354,
                             -0.5458237692108209)


def dietmaier_home() -> pin.SE3:
    """The home posture of :func:`dietmaier` (scale 1)."""
    w, x, y, z = DIETMAIER_HOME_QUATERNION
    q = pin.Quaternion(w, x, y, z)
    q.normalize()
    return pin.SE3(q.toRotationMatrix(), np.array(DIETMAIER_HOME_TRANSLATION))


def dietmaier(scale: float = 1.0, *, stroke: tuple[float, float] = (0.1, 3.0)) -> MechanismDesign:
    """Dietmaier's general 6-UPS platform (see the module docstring).

    Leg URDF (``ups_leg_dietmaier.urdf``, shared): ``U1`` revolute about x (±2π), ``U2``
    about y (±π/2) at the base point — together any leg direction —, ``P`` prismatic
    along z (actuated, its value the leg length), then a spherical joint ``S1`` (±2π),
    ``S2`` (±π/2), ``S3`` (±2π) at the platform point (any orientation; the full turns
    either way keep a limit stop away from configurations near ±π), tip frame at the
    sphere centre; each
    leg's base frame has its z axis along the leg at home. The wide joint ranges let
    all 40 postures assemble.

    Args:
        scale: Multiplies every length.
        stroke: Prismatic limits [m] (multiplied by ``scale``).
    """
    base, plat = scale * DIETMAIER_BASE, scale * DIETMAIER_PLATFORM
    h = dietmaier_home()
    home = pin.SE3(h.rotation, scale * h.translation)
    ends = np.array([home.act(p) for p in plat])
    lengths = np.linalg.norm(ends - base, axis=1)
    joints = [
        JointSpec("U1", "revolute", axis=(1.0, 0.0, 0.0), lower=-2 * math.pi,
                  upper=2 * math.pi),
        JointSpec("U2", "revolute", axis=(0.0, 1.0, 0.0), lower=-0.5 * math.pi,
                  upper=0.5 * math.pi),
        JointSpec("P", "prismatic", axis=(0.0, 0.0, 1.0), lower=scale * stroke[0],
                  upper=scale * stroke[1]),
        *_spherical("S"),
    ]
    for k in (3, 5):  # S1, S3: a full turn either way (no limit stop near ±π)
        joints[k] = JointSpec(joints[k].name, "revolute", axis=joints[k].axis,
                              lower=-2 * math.pi, upper=2 * math.pi)
    xml = chain_urdf("ups_leg_dietmaier", joints, tip="tip")
    legs, home_q = [], []
    for i in range(6):
        q = np.array([0.0, 0.0, lengths[i], 0.0, 0.0, 0.0])
        legs.append(LegDesign.assembled(str(i + 1), xml, "tip", ("P",),
                                        frame_with_z(base[i], ends[i] - base[i]), q, home,
                                        "ups_leg_dietmaier.urdf"))
        home_q.append(q)
    return MechanismDesign(
        name="6-UPS Dietmaier", description="Dietmaier's general Stewart–Gough platform "
        "(ARK 1998): 40 real postures at its leg lengths", legs=legs, home=home,
        home_q=home_q, slug="dietmaier")
