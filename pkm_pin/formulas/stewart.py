"""Gough-Stewart (6-UPS / 6-SPS) l-coordinate body of seed 003, by hand — plain numpy.

Seed 003: Demidov 2025, see docs/references.md.

Part of the independent witness :mod:`pkm_pin.formulas`: imports nothing from
``pkm_pin`` and nothing from Pinocchio.

Conventions
-----------
* Screws are axis-first ``(s; s0)`` about the world origin. A twist (or small finite
  displacement screw) is ``(w; v_O)``: rotation [rad/s or rad] first, then the velocity
  (displacement) [m/s or m] of the body point at the origin. Seed 003 writes the same
  thing as ``Phi = phi + chi S`` and its solution as ``(x, y, z | x0, y0, z0)``.
* Leg line ``E_i = (e_i; b_i x e_i)``: unit direction ``e_i`` from the base point
  ``B_i`` towards the platform point ``A_i``, moment about the origin.
* Reciprocal product ``a o b = a[:3].b[3:] + a[3:].b[:3]``. The rate of a leg length is
  ``dl_i = E_i o t = e_i . v_O + (b_i x e_i) . w`` (= ``e_i . v_{A_i}``).
* SI units, radians.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

#: The Plucker matrix of E1..E6 printed in seed 003 (rows ``(x, y, z | x0, y0, z0)``,
#: direction first: already axis-first in this package's sense).
SEED003_LINES = np.array([
    [0, 0, 1, 0, 1, 0],
    [0, 0, 1, -1, 0, 0],
    [0, 0, 1, 0, -1, 0],
    [1, 0, 0, 0, 0, 0],
    [0, 1, 0, 0, 0, 0],
    [0, -1, 0, 0, 0, -1],
], dtype=float)
SEED003_LINES.setflags(write=False)

#: Seed 003's one-step example: dl1 = dl4 = 0.1 m, the others 0 (the paper's list of
#: zero increments names dl4 twice; dl4 = 0.1 is meant).
SEED003_DL = np.array([0.1, 0.0, 0.0, 0.1, 0.0, 0.0])
SEED003_DL.setflags(write=False)

#: The small twist solving the seed-003 system for :data:`SEED003_DL`, axis-first
#: ``(w; v_O)``. The paper prints ``y0 = 0.1``; the system itself (row 5: ``y0 = dl5 =
#: 0``) and the text ("O moves 0.1 m along x and 0.05 m along z") give ``y0 = 0``.
SEED003_TWIST = np.array([0.05, 0.05, 0.0, 0.1, 0.0, 0.05])
SEED003_TWIST.setflags(write=False)


def _delta(screws: np.ndarray) -> np.ndarray:
    """Swap the two halves of axis-first screws (multiply by Delta)."""
    return np.concatenate([screws[..., 3:], screws[..., :3]], axis=-1)


def _skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix ``[v]x`` with ``[v]x u = v x u``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def leg_lengths(base_points: np.ndarray, platform_points_world: np.ndarray) -> np.ndarray:
    """Leg lengths ``|A_i - B_i|``.

    Args:
        base_points: (6, 3) base points ``B_i`` [m].
        platform_points_world: (6, 3) platform points ``A_i`` in world coordinates [m].

    Returns:
        (6,) lengths [m].
    """
    return np.linalg.norm(np.asarray(platform_points_world, float)
                          - np.asarray(base_points, float), axis=1)


def leg_lines(base_points: np.ndarray, platform_points_world: np.ndarray) -> np.ndarray:
    """Unit Plucker lines of the legs, axis-first ``(e_i; B_i x e_i)``.

    Args:
        base_points: (n, 3) base points ``B_i`` [m].
        platform_points_world: (n, 3) platform points ``A_i`` (world) [m].

    Returns:
        (n, 6) rows; ``e_i`` is the unit vector from ``B_i`` to ``A_i``.
    """
    b = np.asarray(base_points, dtype=float)
    d = np.asarray(platform_points_world, dtype=float) - b
    e = d / np.linalg.norm(d, axis=1, keepdims=True)
    return np.hstack([e, np.cross(b, e)])


def inverse_jacobian(base_points: np.ndarray, platform_points_world: np.ndarray) -> np.ndarray:
    """Matrix ``J`` with ``dl = J @ t`` for the axis-first platform twist ``t = (w; v_O)``.

    ``J = lines @ Delta``: row i is ``(B_i x e_i, e_i)``.

    Args:
        base_points: (n, 3) base points [m].
        platform_points_world: (n, 3) platform points (world) [m].

    Returns:
        (n, 6) matrix [m/rad | 1].
    """
    return _delta(leg_lines(base_points, platform_points_world))


def screw_step(lines: np.ndarray, dl: Sequence[float]) -> np.ndarray:
    """Solve seed 003's system ``E_i o Phi = dl_i`` for the small twist ``Phi``.

    Args:
        lines: (6, 6) axis-first unit leg lines ``E_i``.
        dl: (6,) leg-length increments [m].

    Returns:
        ``Phi = (w; v_O)`` axis-first: small rotation [rad], displacement of the body
        point at the origin [m].

    Raises:
        numpy.linalg.LinAlgError: When the lines are linearly dependent (singular).
    """
    return np.linalg.solve(_delta(np.asarray(lines, dtype=float)),
                           np.asarray(dl, dtype=float))


def rodrigues(w: np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector ``w`` (axis * angle [rad]).

    Args:
        w: (3,) rotation vector.

    Returns:
        (3, 3) rotation ``I + sin t/t [w] + (1 - cos t)/t^2 [w]^2``.
    """
    w = np.asarray(w, dtype=float)
    t = float(np.linalg.norm(w))
    k = _skew(w)
    if t < 1e-8:
        return np.eye(3) + k + 0.5 * k @ k
    return np.eye(3) + np.sin(t) / t * k + (1.0 - np.cos(t)) / t**2 * k @ k


def twist_exponential(twist: Sequence[float]) -> np.ndarray:
    """Rigid displacement generated by a constant unit-time twist (screw motion).

    Args:
        twist: Axis-first ``(w; v_O)`` [rad, m].

    Returns:
        (4, 4) homogeneous transform ``[[R, p], [0, 1]]`` with ``R = rodrigues(w)`` and
        ``p = V v_O``, ``V = I + (1-cos t)/t^2 [w] + (t - sin t)/t^3 [w]^2``; it maps a
        body point's initial world position to its final one.
    """
    t_ = np.asarray(twist, dtype=float)
    w, v = t_[:3], t_[3:]
    t = float(np.linalg.norm(w))
    k = _skew(w)
    if t < 1e-8:
        V = np.eye(3) + 0.5 * k + k @ k / 6.0
    else:
        V = np.eye(3) + (1.0 - np.cos(t)) / t**2 * k + (t - np.sin(t)) / t**3 * k @ k
    out = np.eye(4)
    out[:3, :3] = rodrigues(w)
    out[:3, 3] = V @ v
    return out


def move_points(points: np.ndarray, twist: Sequence[float], linear: bool = False) -> np.ndarray:
    """Move body points by a small twist.

    Args:
        points: (n, 3) world points of the body [m].
        twist: Axis-first ``(w; v_O)`` [rad, m].
        linear: If True, seed 003's first-order update ``A + (v_O + w x A)`` (the
            "moment of the screw reduced to A"); otherwise the exact screw motion
            :func:`twist_exponential`.

    Returns:
        (n, 3) moved points [m].
    """
    p = np.asarray(points, dtype=float)
    t_ = np.asarray(twist, dtype=float)
    if linear:
        return p + t_[3:] + np.cross(t_[:3], p)
    g = twist_exponential(t_)
    return p @ g[:3, :3].T + g[:3, 3]


def seed003_geometry() -> tuple[np.ndarray, np.ndarray]:
    """Base and platform points of seed 003's example, derived from the printed lines.

    The body is the unit sphere about the origin, all legs have l = 1 m. From
    ``E_i = (e_i; A_i x e_i)`` with ``|A_i| = 1`` each ``A_i`` is fixed up to the two
    sphere intersections; the text's point motions (A1, A4 move by 0.1 m along x and z,
    the others by 0.1 m along x) pick one. The result is consistent with every printed
    line and with the printed residuals (0.0045 m and 0.005 m): the six legs meet the
    body in three points, two legs each, ``A1 = A4 = (-1,0,0)``, ``A2 = A5 = (0,-1,0)``,
    ``A3 = A6 = (1,0,0)``, and ``B_i = A_i - e_i``.

    Returns:
        ``(base_points, platform_points)``, each (6, 3) [m], world coordinates.
    """
    platform = np.array([[-1, 0, 0], [0, -1, 0], [1, 0, 0],
                         [-1, 0, 0], [0, -1, 0], [1, 0, 0]], dtype=float)
    base = platform - SEED003_LINES[:, :3]
    return base, platform


def forward_position_continuation(base_points: np.ndarray, platform_points_world: np.ndarray,
                                  l_target: Sequence[float], n_steps: int,
                                  linear: bool = False, eps: float = 1e-6,
                                  max_inertia_steps: int = 100) -> np.ndarray:
    """Seed 003's forward position algorithm (Euler polyline with "motion by inertia").

    The leg lengths go from their current values to ``l_target`` in ``n_steps`` equal
    increments; at each step the small twist is :func:`screw_step` and the platform is
    moved by it. When ``|det|`` of the line matrix is below ``eps`` the last twist is
    repeated until it grows above ``eps`` ("motion by inertia"), after which the
    increments are re-aimed at the target from the reached lengths.

    Args:
        base_points: (6, 3) base points [m].
        platform_points_world: (6, 3) initial platform points (world) [m].
        l_target: (6,) target lengths [m].
        n_steps: Number of steps ``N`` (the error shrinks as ``N`` grows).
        linear: Use the paper's first-order point update (see :func:`move_points`).
        eps: Singularity threshold on ``|det(lines)|``.
        max_inertia_steps: Give up after this many inertia moves in a row.

    Returns:
        (6, 3) final platform points [m].

    Raises:
        numpy.linalg.LinAlgError: Singular at the start, or inertia did not escape.
    """
    pts = np.asarray(platform_points_world, dtype=float).copy()
    target = np.asarray(l_target, dtype=float)
    dl = (target - leg_lengths(base_points, pts)) / n_steps
    last = None
    for k in range(n_steps):
        lines = leg_lines(base_points, pts)
        inertia = 0
        while abs(np.linalg.det(lines)) < eps:
            if last is None or inertia >= max_inertia_steps:
                raise np.linalg.LinAlgError("singular leg lines; inertia cannot help")
            pts = move_points(pts, last, linear)
            lines = leg_lines(base_points, pts)
            inertia += 1
        if inertia:
            dl = (target - leg_lengths(base_points, pts)) / (n_steps - k)
        last = screw_step(lines, dl)
        pts = move_points(pts, last, linear)
    return pts


def axis_angle_twist(axis: Sequence[float], angle: float, point: Sequence[float],
                     translation: Sequence[float]) -> np.ndarray:
    """Axis-first small displacement: rotation ``angle`` about a line through ``point``
    along unit ``axis``, plus a translation.

    This is the right side ``L dPsi + chi dr`` of seed 003's inverse-problem system,
    whose moment part is ``dPsi (O_c x L) + dr`` =
    ``dPsi (eta Lz - zeta Ly, zeta Lx - xi Lz, xi Ly - eta Lx) + dr``.

    Args:
        axis: Unit axis ``L``.
        angle: ``dPsi`` [rad].
        point: ``O_c = (xi, eta, zeta)`` on the axis [m].
        translation: ``dr`` [m].

    Returns:
        (6,) ``(dPsi L; dPsi O_c x L + dr)``.
    """
    L = np.asarray(axis, dtype=float)
    return np.concatenate([angle * L, angle * np.cross(point, L) + np.asarray(translation)])


def quaternion_from_rotation(R: np.ndarray) -> np.ndarray:
    """Unit quaternion ``(d0, d1, d2, d3)`` of a rotation matrix (seed 003, corrected).

    ``d0 = sqrt(1 + a11 + a22 + a33)/2`` (the paper omits the ``1 +``),
    ``d1 = (a32 - a23)/(4 d0)`` (the paper prints ``a33``), ``d2 = (a13 - a31)/(4 d0)``,
    ``d3 = (a21 - a12)/(4 d0)``; the sign is chosen with ``d0 >= 0``. Valid while the
    rotation angle is not close to pi (``d0`` not small); a largest-component branch
    is used otherwise.

    Args:
        R: (3, 3) rotation matrix ``a_ij``.

    Returns:
        (4,) ``cos(delta/2), M sin(delta/2)``.
    """
    a = np.asarray(R, dtype=float)
    tr = a[0, 0] + a[1, 1] + a[2, 2]
    if 1.0 + tr > 1e-6:
        d0 = 0.5 * np.sqrt(1.0 + tr)
        q = np.array([d0, (a[2, 1] - a[1, 2]) / (4 * d0), (a[0, 2] - a[2, 0]) / (4 * d0),
                      (a[1, 0] - a[0, 1]) / (4 * d0)])
    else:
        i = int(np.argmax(np.diag(a)))
        j, k = (i + 1) % 3, (i + 2) % 3
        di = 0.5 * np.sqrt(1.0 + a[i, i] - a[j, j] - a[k, k])
        q = np.zeros(4)
        q[0] = (a[k, j] - a[j, k]) / (4 * di)
        q[1 + i] = di
        q[1 + j] = (a[j, i] + a[i, j]) / (4 * di)
        q[1 + k] = (a[k, i] + a[i, k]) / (4 * di)
        if q[0] < 0:
            q = -q
    return q


def quaternion_multiply(p: Sequence[float], q: Sequence[float]) -> np.ndarray:
    """Hamilton product ``p q`` (scalar first); the system printed in seed 003 for
    ``Delta = Theta Gamma`` is exactly this product."""
    p0, p1, p2, p3 = p
    q0, q1, q2, q3 = q
    return np.array([
        p0 * q0 - p1 * q1 - p2 * q2 - p3 * q3,
        p0 * q1 + p1 * q0 + p2 * q3 - p3 * q2,
        p0 * q2 - p1 * q3 + p2 * q0 + p3 * q1,
        p0 * q3 + p1 * q2 - p2 * q1 + p3 * q0,
    ])


def relative_rotation(R_start: np.ndarray, R_target: np.ndarray) -> tuple[np.ndarray, float]:
    """Axis ``L`` and angle ``Psi`` taking ``R_start`` to ``R_target`` (seed 003).

    Solves ``Delta = Theta Gamma`` for ``Theta = cos(Psi/2) + L sin(Psi/2)`` with
    ``Gamma``, ``Delta`` the quaternions of ``R_start``, ``R_target``; then
    ``R_target = rot(L, Psi) R_start`` (rotation expressed in the world frame).

    Args:
        R_start: (3, 3) initial orientation.
        R_target: (3, 3) required orientation.

    Returns:
        ``(L, Psi)``: unit axis (world), angle in [0, pi] [rad]; ``L = (1,0,0)`` when
        ``Psi = 0``.
    """
    g = quaternion_from_rotation(R_start)
    d = quaternion_from_rotation(R_target)
    g_inv = np.array([g[0], -g[1], -g[2], -g[3]])
    th = quaternion_multiply(d, g_inv)
    if th[0] < 0:
        th = -th
    s = float(np.linalg.norm(th[1:]))
    psi = 2.0 * np.arctan2(s, th[0])
    axis = th[1:] / s if s > 1e-15 else np.array([1.0, 0.0, 0.0])
    return axis, float(psi)
