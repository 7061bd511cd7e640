"""Planar 3-RPR ("3-RTR") of seed 000, section 5, written out by hand — plain numpy.

Seed 000: Michalková & Guldan, see docs/references.md.

This module is part of the independent witness :mod:`pkm_pin.formulas`: it imports
nothing from ``pkm_pin`` and nothing from Pinocchio.

Conventions
-----------
* Screws are axis-first ``(s; s0)`` about the world origin: a twist is ``(w; v_O)``
  (angular velocity [rad/s], then the velocity [m/s] of the body point at the origin),
  a wrench is ``(f; m_O)`` (force [N], moment [N m] about the origin). A line through
  ``r`` along ``s`` is ``(s; r x s)``, a couple is ``(0; s)``.
* Reciprocal product ``a o b = a[:3].b[3:] + a[3:].b[:3]``.
* SI units, radians.

Geometry (fixed, shared by the whole project)
---------------------------------------------
The mechanism moves in the xz-plane, ``y`` is the plane normal. Base pivots lie on the
x-axis: ``A0 = (0,0,0)``, ``B0 = (L3,0,0)``, ``C0 = (L3+L6,0,0)``. Leg ``X`` has the
unit direction ``d = (cos a, 0, sin a)`` where ``a`` (alpha, beta, gamma for legs A, B,
C) is measured from ``+x`` towards ``+z``. Each leg is R-P-R: a revolute about ``+y`` at
``X0``, a prismatic along ``d`` whose joint coordinate is the distance ``|X0 X2|``
(``L2``, ``L5``, ``L8`` of (49)), and a revolute about ``+y`` at the platform pivot
``X2 = X0 + length * d``.

Because a positive rotation about ``+y`` turns ``+x`` towards ``-z``, the rate of the
revolute joint at ``X0`` (about ``+y``) is ``-d(angle)/dt``.

Actuated joints (as in the paper): the prismatic joint of leg A [m/s], the revolute at
``B0`` [rad/s], the prismatic joint of leg C [m/s].

Unit screws versus the paper
----------------------------
The paper's prismatic screws (50)-(52) are scaled by the slider lengths ``L1 = |A0A1|``,
``L4 = |B0B1|``, ``L7 = |C0C1|`` instead of being unit couples; this is why ``B`` in (58)
holds ``L1`` and ``L7``. The functions here use UNIT joint screws; the paper's form is
reproduced by :func:`joint_screws_paper` and :func:`velocity_equation_paper`. The two
velocity equations share the same left matrix; they differ only in what the actuated
"rates" mean: the paper's ``v_A1 = (dL2/dt)/L1`` and ``v_C1 = (dL8/dt)/L7``.

The ``L5`` in row 2 of (58) and in ``B`` is the length ``|B0B2|`` (the prismatic joint
coordinate of leg B, a true length, not a screw scaling): the actuation wrench of leg B
is the unit force through ``B2`` along ``n = y x d_B = (sin b, 0, -cos b)``, whose
moment about the origin is ``(0, L5 + L3 cos b, 0)`` and whose reciprocal product with
the unit revolute twist at ``B0`` is ``L5``. Row 2 of (58) is printed with exactly this
sign; the determinant (60) expands exactly (no factor, no sign) to the left side of (61).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

_Y = np.array([0.0, 1.0, 0.0])
#: Indices of (w_y, v_x, v_z) inside an axis-first planar twist (0, w_y, 0 | v_x, 0, v_z).
PLANAR_TWIST_INDEX = (1, 3, 5)


def reciprocal_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Reciprocal product of axis-first screws.

    Args:
        a: Screw(s), shape (6,) or (k, 6).
        b: Screw(s), shape (6,) or (m, 6).

    Returns:
        ``a[:3].b[3:] + a[3:].b[:3]``; a scalar for two single screws, otherwise the
        (k, m) table (or (k,) / (m,)).
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    delta_b = np.concatenate([b[..., 3:], b[..., :3]], axis=-1)
    return a @ delta_b.T


def _line(point: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Axis-first line ``(s; r x s)`` through ``point`` along ``direction``."""
    return np.concatenate([direction, np.cross(point, direction)])


def _direction(angle: float) -> np.ndarray:
    """Unit leg direction ``(cos a, 0, sin a)``; ``a`` from +x towards +z [rad]."""
    return np.array([np.cos(angle), 0.0, np.sin(angle)])


def base_points(L3: float, L6: float) -> np.ndarray:
    """Base pivots ``A0, B0, C0`` on the x-axis.

    Args:
        L3: ``|A0B0|`` [m].
        L6: ``|B0C0|`` [m].

    Returns:
        (3, 3) array, one pivot per row [m].
    """
    return np.array([[0.0, 0.0, 0.0], [L3, 0.0, 0.0], [L3 + L6, 0.0, 0.0]])


def platform_pivots(L3: float, L6: float, angles: Sequence[float],
                    lengths: Sequence[float]) -> np.ndarray:
    """Platform pivots ``X2 = X0 + length * (cos a, 0, sin a)`` of the three legs.

    Args:
        L3: ``|A0B0|`` [m].
        L6: ``|B0C0|`` [m].
        angles: (alpha, beta, gamma) [rad], from +x towards +z.
        lengths: (L2, L5, L8) = ``|X0 X2|`` [m].

    Returns:
        (3, 3) array ``A2, B2, C2`` [m].
    """
    base = base_points(L3, L6)
    return np.array([base[i] + lengths[i] * _direction(angles[i]) for i in range(3)])


def leg_joint_screws(base_point_x: float, angle: float, length: float) -> np.ndarray:
    """Unit joint twists of one R-P-R leg, axis-first, about the world origin.

    Args:
        base_point_x: x-coordinate of the base pivot ``X0 = (x, 0, 0)`` [m].
        angle: Leg angle from +x towards +z [rad].
        length: ``|X0 X2|``, the prismatic joint coordinate [m].

    Returns:
        (3, 6) rows: revolute about +y at ``X0`` = ``(0,1,0 | 0,0,x)``; prismatic
        ``(0,0,0 | cos a, 0, sin a)`` (unit couple); revolute about +y at ``X2`` =
        ``(0,1,0 | -length sin a, 0, x + length cos a)``.
    """
    x0 = np.array([base_point_x, 0.0, 0.0])
    d = _direction(angle)
    x2 = x0 + length * d
    return np.array([_line(x0, _Y), np.concatenate([np.zeros(3), d]), _line(x2, _Y)])


def joint_screws(L3: float, L6: float, angles: Sequence[float],
                 lengths: Sequence[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit joint twists of legs A, B, C (see :func:`leg_joint_screws`).

    Args:
        L3: ``|A0B0|`` [m].
        L6: ``|B0C0|`` [m].
        angles: (alpha, beta, gamma) [rad].
        lengths: (L2, L5, L8) [m].

    Returns:
        Three (3, 6) arrays (R at base, P, R at platform), legs A, B, C.
    """
    xs = base_points(L3, L6)[:, 0]
    return tuple(leg_joint_screws(xs[i], angles[i], lengths[i]) for i in range(3))


def joint_screws_paper(L3: float, L6: float, angles: Sequence[float],
                       lengths: Sequence[float], slider_lengths: Sequence[float],
                       as_printed: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint screws (50)-(52) in the paper's form (prismatic twists scaled by a length).

    Args:
        L3: ``|A0B0|`` [m].
        L6: ``|B0C0|`` [m].
        angles: (alpha, beta, gamma) [rad].
        lengths: (L2, L5, L8) [m].
        slider_lengths: (L1, L4, L7) = ``|A0A1|, |B0B1|, |C0C1|`` [m], the scalings
            of the prismatic screws.
        as_printed: If True, keep the misprint of (52): ``$C2`` with ``-L8 sin(beta)``
            instead of ``-L8 sin(gamma)``.

    Returns:
        Three (3, 6) arrays, as in (50), (51), (52).
    """
    legs = [s.copy() for s in joint_screws(L3, L6, angles, lengths)]
    for leg, scale in zip(legs, slider_lengths):
        leg[1] *= scale
    if as_printed:
        legs[2][2, 3] = -lengths[2] * np.sin(angles[1])
    return tuple(legs)


def constraint_wrenches() -> np.ndarray:
    """Constraint wrench system (54) common to the three legs.

    Returns:
        (3, 6) rows ``(0,1,0|0,0,0)`` (force along y through the origin),
        ``(0,0,0|1,0,0)`` and ``(0,0,0|0,0,1)`` (couples about x and z).
    """
    return np.array([[0, 1, 0, 0, 0, 0], [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 0, 1]], float)


def platform_twists() -> np.ndarray:
    """Twist system (55) of the platform.

    Returns:
        (3, 6) rows: rotation about the y-axis through the origin, translation along
        x, translation along z. ``t3 @ platform_twists()`` turns ``(w_y, v_x, v_z)``
        into the 6-twist ``(0, w_y, 0 | v_x, 0, v_z)`` of (56).
    """
    return np.array([[0, 1, 0, 0, 0, 0], [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 0, 1]], float)


def actuation_wrenches(L3: float, L6: float, angles: Sequence[float],
                       lengths: Sequence[float]) -> np.ndarray:
    """Unit actuation wrenches, each reciprocal to its leg's passive joint twists.

    Leg A (P actuated): unit force along the leg through ``A0`` (coplanar with both
    passive revolute axes). Leg B (R at B0 actuated): unit force through ``B2`` along
    ``n = y x d_B = (sin b, 0, -cos b)`` (perpendicular to the leg: reciprocal to the
    prismatic couple; through B2: reciprocal to the revolute at B2). Leg C: unit force
    along the leg through ``C0``.

    Args:
        L3: ``|A0B0|`` [m].
        L6: ``|B0C0|`` [m].
        angles: (alpha, beta, gamma) [rad].
        lengths: (L2, L5, L8) [m].

    Returns:
        (3, 6) rows, axis-first wrenches ``(f; m_O)`` [N, N m] of unit force.
    """
    base = base_points(L3, L6)
    pivots = platform_pivots(L3, L6, angles, lengths)
    d_b = _direction(angles[1])
    return np.array([
        _line(base[0], _direction(angles[0])),
        _line(pivots[1], np.cross(_Y, d_b)),
        _line(base[2], _direction(angles[2])),
    ])


def actuated_joint_screws(L3: float, L6: float, angles: Sequence[float],
                          lengths: Sequence[float]) -> np.ndarray:
    """Unit twists of the actuated joints: P of leg A, R at B0, P of leg C.

    Returns:
        (3, 6) rows, axis-first.
    """
    legs = joint_screws(L3, L6, angles, lengths)
    return np.array([legs[0][1], legs[1][0], legs[2][1]])


def velocity_equation(L3: float, L6: float, angles: Sequence[float],
                      lengths: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """Input-output velocity equation ``A3 (w_y, v_x, v_z) = B3 rates`` with unit screws.

    Row i is the actuation wrench ``W_i`` of leg i reciprocally multiplied with the
    platform twist ``(0, w_y, 0 | v_x, 0, v_z)``: ``W_i o t = m_y w_y + f_x v_x + f_z v_z``.
    ``B3[i, i] = W_i o $a_i`` with ``$a_i`` the unit twist of the actuated joint.

    Args:
        L3: ``|A0B0|`` [m].
        L6: ``|B0C0|`` [m].
        angles: (alpha, beta, gamma) [rad].
        lengths: (L2, L5, L8) [m].

    Returns:
        ``(A3, B3)``: ``A3`` is the left matrix of (58) (identical to the paper's);
        ``B3 = diag(1, L5, 1)`` acts on (dL2/dt [m/s], w_B0 [rad/s], dL8/dt [m/s]).
    """
    wrenches = actuation_wrenches(L3, L6, angles, lengths)
    twists = platform_twists()
    a3 = reciprocal_product(wrenches, twists)
    b3 = np.diag(np.diag(reciprocal_product(
        wrenches, actuated_joint_screws(L3, L6, angles, lengths))))
    return a3, b3


def velocity_equation_paper(L3: float, L6: float, angles: Sequence[float],
                            lengths: Sequence[float], L1: float,
                            L7: float) -> tuple[np.ndarray, np.ndarray]:
    """Equation (58) exactly as printed.

    Args:
        L3: ``|A0B0|`` [m].
        L6: ``|B0C0|`` [m].
        angles: (alpha, beta, gamma) [rad].
        lengths: (L2, L5, L8) [m]; only ``L5 = |B0B2|`` enters (58).
        L1: ``|A0A1|``, scaling of the paper's prismatic screw of leg A [m].
        L7: ``|C0C1|``, scaling of the paper's prismatic screw of leg C [m].

    Returns:
        ``(A, B)`` with ``A`` the printed left matrix and ``B = diag(L1, L5, L7)``,
        acting on the paper's rates ``(v_A1, w_B0, v_C1)``, where ``v_A1 = (dL2/dt)/L1``
        and ``v_C1 = (dL8/dt)/L7`` [1/s].
    """
    a, b, c = angles
    L5 = lengths[1]
    A = np.array([
        [0.0, np.cos(a), np.sin(a)],
        [L5 + L3 * np.cos(b), np.sin(b), -np.cos(b)],
        [-(L3 + L6) * np.sin(c), np.cos(c), np.sin(c)],
    ])
    return A, np.diag([L1, L5, L7])


def type2_determinant(L3: float, L6: float, angles: Sequence[float],
                      lengths: Sequence[float]) -> float:
    """Determinant (60) of the left matrix of (58); zero at type-2 singularities.

    Args:
        L3: ``|A0B0|`` [m].
        L6: ``|B0C0|`` [m].
        angles: (alpha, beta, gamma) [rad].
        lengths: (L2, L5, L8) [m].

    Returns:
        ``det A3`` [m].
    """
    return float(np.linalg.det(velocity_equation(L3, L6, angles, lengths)[0]))


def singularity_condition_61(L3: float, L6: float, L5: float,
                             angles: Sequence[float]) -> float:
    """Left side of (61): ``L5 sin(a-c) + L6 sin c cos(b-a) + L3 sin a cos(b-c)``.

    Expanding (60) along its first row gives exactly this expression (same sign, no
    factor), so it equals :func:`type2_determinant`.

    Args:
        L3: ``|A0B0|`` [m].
        L6: ``|B0C0|`` [m].
        L5: ``|B0B2|`` [m].
        angles: (alpha, beta, gamma) [rad].

    Returns:
        The value [m].
    """
    a, b, c = angles
    return float(L5 * np.sin(a - c) + L6 * np.sin(c) * np.cos(b - a)
                 + L3 * np.sin(a) * np.cos(b - c))


def forward_velocity(L3: float, L6: float, angles: Sequence[float],
                     lengths: Sequence[float], rates: Sequence[float]) -> np.ndarray:
    """Platform velocity from actuated rates: solve ``A3 t3 = B3 rates``.

    Args:
        L3, L6: Base spacing [m].
        angles: (alpha, beta, gamma) [rad].
        lengths: (L2, L5, L8) [m].
        rates: (dL2/dt [m/s], w_B0 [rad/s] about +y, dL8/dt [m/s]).

    Returns:
        ``(w_y [rad/s], v_x [m/s], v_z [m/s])``, ``v`` of the platform point at the origin.

    Raises:
        numpy.linalg.LinAlgError: At a type-2 singularity.
    """
    a3, b3 = velocity_equation(L3, L6, angles, lengths)
    return np.linalg.solve(a3, b3 @ np.asarray(rates, dtype=float))


def inverse_velocity(L3: float, L6: float, angles: Sequence[float],
                     lengths: Sequence[float], platform_velocity: Sequence[float]) -> np.ndarray:
    """Actuated rates from the platform velocity: solve ``B3 rates = A3 t3``.

    Args:
        L3, L6: Base spacing [m].
        angles: (alpha, beta, gamma) [rad].
        lengths: (L2, L5, L8) [m].
        platform_velocity: ``(w_y, v_x, v_z)`` or the full 6-twist
            ``(0, w_y, 0 | v_x, 0, v_z)`` (axis-first, about the origin).

    Returns:
        (dL2/dt [m/s], w_B0 [rad/s], dL8/dt [m/s]).
    """
    t = np.asarray(platform_velocity, dtype=float)
    if t.shape == (6,):
        t = t[list(PLANAR_TWIST_INDEX)]
    a3, b3 = velocity_equation(L3, L6, angles, lengths)
    return np.linalg.solve(b3, a3 @ t)


def rotation_y(theta: float) -> np.ndarray:
    """Rotation matrix about +y by ``theta`` [rad] (turns +x towards -z)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def inverse_position(L3: float, L6: float, pose: Sequence[float],
                     platform_points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Leg angles and lengths for a platform pose (closed-loop geometry).

    Args:
        L3, L6: Base spacing [m].
        pose: ``(theta, x, z)``: platform rotation about +y [rad] and the world
            position of the platform reference point [m].
        platform_points: (3, 3) or (3, 2) (x, z) coordinates of A2, B2, C2 in the
            platform frame [m].

    Returns:
        ``(angles, lengths)``: (alpha, beta, gamma) [rad] and (L2, L5, L8) [m].
    """
    pts = np.asarray(platform_points, dtype=float)
    if pts.shape == (3, 2):
        pts = np.column_stack([pts[:, 0], np.zeros(3), pts[:, 1]])
    theta, x, z = pose
    world = np.array([x, 0.0, z]) + pts @ rotation_y(theta).T
    legs = world - base_points(L3, L6)
    return np.arctan2(legs[:, 2], legs[:, 0]), np.linalg.norm(legs, axis=1)
