"""Quasi-orthogonal Orthoglide of seed 001, eq. (2)-(16), by hand.

Seed 001: Pashkevich & Gomolitsky 2007, see docs/references.md.

This module is part of the independent witness :mod:`pkm_pin.formulas`: it imports
nothing from ``pkm_pin`` and nothing from Pinocchio. Plain numpy, SI units, radians.

Model (2)/(5): the platform point ``p`` is at distance ``L_i`` from the point ``g_i`` of
leg ``i`` on its actuator axis, ``|p - g_i|^2 = L_i^2``, with (legs in the order x, y, z)::

    g_x = (rho_x cos phi_x,           0,                 rho_x sin phi_x + dd_x)
    g_y = (rho_y sin phi_y + dd_y,    rho_y cos phi_y,   0)
    g_z = (0,                         rho_z sin phi_z + dd_z, rho_z cos phi_z)

i.e. ``g_i = rho_i u_i + dd_i o_i`` with the tilted actuator axis ``u_i`` (rows of
:func:`actuator_axes`) and the offset direction ``o_i`` (rows of :data:`OFFSETS`).

Extension (not in the paper): the tool offset ``e``. The paper puts it into the tool
transform; here each leg's parallelogram ends at ``C_i = p + e n_i`` (``n_i`` the
nominal axis, rows of :data:`NOMINAL`), so every formula holds with ``g_i`` replaced
by ``g_i - e n_i``. With ``e = 0`` (the default) the formulas are the paper's.

Differential relations (16), derived from (2): ``A dp = B_rho drho = B_L dL =
B_phi dphi = B_d dd`` with rows of ``A`` the vectors ``p - g_i`` and the diagonal
matrices ``B_rho = (p - g_i).u_i``, ``B_L = L_i``, ``B_phi = rho_i (p - g_i).du_i/dphi_i``,
``B_d = (p - g_i).o_i``. The printed ``B_rho`` and ``B_phi`` carry slips
(:func:`b_rho_printed`, :func:`b_phi_printed`; see ``docs/errata.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Nominal actuator axes ``n_i`` (rows: legs x, y, z).
NOMINAL = np.eye(3)
#: Offset directions ``o_i`` of ``dd_i`` (rows): z for leg x, x for leg y, y for leg z.
OFFSETS = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


@dataclass(frozen=True)
class OrthoglideParameters:
    """Geometric parameters of the quasi-orthogonal model (2).

    Attributes:
        L: Parallelogram lengths ``(L_x, L_y, L_z)`` [m].
        phi: Axis tilts ``(phi_x, phi_y, phi_z)`` [rad].
        dd: Axis offsets ``(dd_x, dd_y, dd_z)`` [m].
        e: Tool offset [m] (extension, see the module docstring).
    """

    L: tuple = (1.0, 1.0, 1.0)
    phi: tuple = (0.0, 0.0, 0.0)
    dd: tuple = (0.0, 0.0, 0.0)
    e: float = 0.0


def actuator_axes(phi) -> np.ndarray:
    """Unit actuator axes ``u_i`` (rows): ``u_x = (cos phi_x, 0, sin phi_x)``, etc."""
    c, s = np.cos(np.asarray(phi, dtype=float)), np.sin(np.asarray(phi, dtype=float))
    return np.array([[c[0], 0.0, s[0]], [s[1], c[1], 0.0], [0.0, s[2], c[2]]])


def axis_derivatives(phi) -> np.ndarray:
    """``du_i / dphi_i`` (rows)."""
    c, s = np.cos(np.asarray(phi, dtype=float)), np.sin(np.asarray(phi, dtype=float))
    return np.array([[-s[0], 0.0, c[0]], [c[1], -s[1], 0.0], [0.0, c[2], -s[2]]])


def carriage_points(rho, params: OrthoglideParameters) -> np.ndarray:
    """Points ``g_i`` (rows) of eq. (5), minus ``e n_i`` (zero for the paper's model)."""
    rho = np.asarray(rho, dtype=float)
    return (rho[:, None] * actuator_axes(params.phi)
            + np.asarray(params.dd, dtype=float)[:, None] * OFFSETS - params.e * NOMINAL)


def residuals(p, rho, params: OrthoglideParameters) -> np.ndarray:
    """Left minus right sides of (2): ``|p - g_i|^2 - L_i^2`` [m^2]."""
    d = np.asarray(p, dtype=float) - carriage_points(rho, params)
    return np.einsum("ij,ij->i", d, d) - np.asarray(params.L, dtype=float) ** 2


# ------------------------------------------------------------------ inverse, (3)-(4)
def inverse_kinematics(p, params: OrthoglideParameters, signs=(1, 1, 1)) -> np.ndarray:
    """Actuated coordinates of eq. (3) for the configuration indices ``signs``.

    ``rho_i = c_i.u_i + s_i sqrt(L_i^2 - |c_i|^2 + (c_i.u_i)^2)`` with
    ``c_i = p - dd_i o_i + e n_i``. Raises ``ValueError`` when ``p`` is out of reach of
    a leg (negative discriminant).
    """
    p = np.asarray(p, dtype=float)
    c = p[None, :] - np.asarray(params.dd, dtype=float)[:, None] * OFFSETS + params.e * NOMINAL
    cu = np.einsum("ij,ij->i", c, actuator_axes(params.phi))
    disc = np.asarray(params.L, dtype=float) ** 2 - np.einsum("ij,ij->i", c, c) + cu ** 2
    if np.any(disc < 0):
        raise ValueError(f"point {p} is out of reach (discriminants {disc})")
    return cu + np.asarray(signs, dtype=float) * np.sqrt(disc)


def inverse_kinematics_all(p, params: OrthoglideParameters) -> dict:
    """All 8 solutions of (3): ``{(s_x, s_y, s_z): rho}``."""
    signs = [(a, b, c) for a in (1, -1) for b in (1, -1) for c in (1, -1)]
    return {s: inverse_kinematics(p, params, s) for s in signs}


def configuration_signs(p, rho, params: OrthoglideParameters) -> tuple:
    """Configuration indices ``s_i`` of a solution: ``sign(rho_i - c_i.u_i) = -sign(B_rho,ii)``.

    This is the corrected (4); it equals the printed ``sign(rho_i - p_i)`` only for the
    orthogonal machine (``phi = dd = 0``, ``e = 0``).
    """
    return tuple(int(v) for v in -np.sign(np.diag(b_rho(p, rho, params))))


def configuration_signs_printed(p, rho) -> tuple:
    """The printed (4): ``s_i = sign(rho_i - p_i)`` (x, y, z components of ``p``)."""
    return tuple(int(v) for v in np.sign(np.asarray(rho, dtype=float) - np.asarray(p, dtype=float)))


# ----------------------------------------------------------------- forward, (6)-(14)
def forward_line(rho, params: OrthoglideParameters) -> tuple[np.ndarray, np.ndarray]:
    """Direction ``k = n1 x n2`` (9) and particular point ``p0 = mu1 n1 + mu2 n2`` (11)-(13)."""
    g = carriage_points(rho, params)
    L2 = np.asarray(params.L, dtype=float) ** 2
    gg = np.einsum("ij,ij->i", g, g)
    n1, n2 = -2.0 * (g[0] - g[1]), -2.0 * (g[1] - g[2])
    xi1, xi2 = (L2[0] - L2[1]) - (gg[0] - gg[1]), (L2[1] - L2[2]) - (gg[1] - gg[2])
    a11, a12, a22 = n1 @ n1, n1 @ n2, n2 @ n2
    det = a11 * a22 - a12 * a12
    mu1 = (xi1 * a22 - xi2 * a12) / det
    mu2 = (a11 * xi2 - a12 * xi1) / det
    return np.cross(n1, n2), mu1 * n1 + mu2 * n2


def p0_printed_14(rho, params: OrthoglideParameters) -> np.ndarray:
    """``p0`` as printed in (14): ``xi1`` and ``xi2`` factored out of ``mu1``, ``mu2`` (a slip)."""
    g = carriage_points(rho, params)
    L2 = np.asarray(params.L, dtype=float) ** 2
    gg = np.einsum("ij,ij->i", g, g)
    n1, n2 = -2.0 * (g[0] - g[1]), -2.0 * (g[1] - g[2])
    xi1, xi2 = (L2[0] - L2[1]) - (gg[0] - gg[1]), (L2[1] - L2[2]) - (gg[1] - gg[2])
    a11, a12, a22 = n1 @ n1, n1 @ n2, n2 @ n2
    det = a11 * a22 - a12 * a12
    return (a22 - a12) / det * xi1 * n1 + (a11 - a12) / det * xi2 * n2


def quadratic_coefficients(rho, params: OrthoglideParameters) -> tuple[float, float, float]:
    """The paper's ``A t^2 + B t + C = 0``: the SUM of the three equations (5) on the line.

    ``A = 3 k^2``, ``B = 2 k.(3 p0 - sum g_i)``,
    ``C = 3 p0^2 + sum g_i^2 - 2 (sum g_i).p0 - sum L_i^2``.
    """
    k, p0 = forward_line(rho, params)
    g = carriage_points(rho, params)
    gs = g.sum(axis=0)
    A = 3.0 * (k @ k)
    B = 2.0 * k @ (3.0 * p0 - gs)
    C = 3.0 * (p0 @ p0) + np.einsum("ij,ij->", g, g) - 2.0 * gs @ p0 - np.sum(
        np.asarray(params.L, dtype=float) ** 2)
    return float(A), float(B), float(C)


def forward_kinematics(rho, params: OrthoglideParameters, m: int = 1) -> np.ndarray:
    """Platform point for the branch index ``m = +-1``: ``t = (-B + m sqrt(B^2 - 4AC)) / 2A``.

    ``m`` equals ``sign(det A)`` of the Jacobian (16) at the solution
    (:func:`branch_index`). Raises ``ValueError`` when the spheres do not meet.
    """
    A, B, C = quadratic_coefficients(rho, params)
    disc = B * B - 4.0 * A * C
    if disc < 0:
        raise ValueError(f"no assembly for rho = {rho} (discriminant {disc:.3g})")
    t = (-B + m * np.sqrt(disc)) / (2.0 * A)
    k, p0 = forward_line(rho, params)
    return k * t + p0


def forward_kinematics_both(rho, params: OrthoglideParameters) -> dict:
    """Both solutions of the forward problem: ``{m: p}`` for ``m = +1, -1``."""
    return {m: forward_kinematics(rho, params, m) for m in (1, -1)}


def branch_index(p, rho, params: OrthoglideParameters) -> int:
    """``m = sign(det A)``."""
    return int(np.sign(np.linalg.det(jacobian_a(p, rho, params))))


# ----------------------------------------------------------------- differential, (16)
def jacobian_a(p, rho, params: OrthoglideParameters) -> np.ndarray:
    """Parallel Jacobian ``A`` of (16): rows ``p - g_i`` [m]."""
    return np.asarray(p, dtype=float)[None, :] - carriage_points(rho, params)


def b_rho(p, rho, params: OrthoglideParameters) -> np.ndarray:
    """Serial Jacobian ``B_rho = diag((p - g_i).u_i)`` [m] (derived from (2))."""
    return np.diag(np.einsum("ij,ij->i", jacobian_a(p, rho, params), actuator_axes(params.phi)))


def b_l(params: OrthoglideParameters) -> np.ndarray:
    """``B_L = diag(L_i)`` [m] (as printed)."""
    return np.diag(np.asarray(params.L, dtype=float))


def b_phi(p, rho, params: OrthoglideParameters) -> np.ndarray:
    """``B_phi = diag(rho_i (p - g_i).du_i/dphi_i)`` [m^2/rad] (derived from (2))."""
    d = np.einsum("ij,ij->i", jacobian_a(p, rho, params), axis_derivatives(params.phi))
    return np.diag(np.asarray(rho, dtype=float) * d)


def b_d(p, rho, params: OrthoglideParameters) -> np.ndarray:
    """``B_d = diag((p - g_i).o_i)`` [m] (as printed)."""
    return np.diag(np.einsum("ij,ij->i", jacobian_a(p, rho, params), OFFSETS))


def b_rho_printed(p, rho, params: OrthoglideParameters) -> np.ndarray:
    """``B_rho`` as printed: e.g. ``p_x + p_z sin phi_x - rho_x - dd_x sin phi_x`` (``e = 0``)."""
    p = np.asarray(p, dtype=float)
    rho, phi, dd = (np.asarray(v, dtype=float) for v in (rho, params.phi, params.dd))
    own, other = p[[0, 1, 2]], p[[2, 0, 1]]
    return np.diag(own + other * np.sin(phi) - rho - dd * np.sin(phi))


def b_phi_printed(p, rho, params: OrthoglideParameters) -> np.ndarray:
    """``B_phi`` (printed ``B_alpha``): e.g. ``rho_x (p_x sin phi_x - p_z cos phi_x +
    dd_x cos phi_x)`` (``e = 0``)."""
    p = np.asarray(p, dtype=float)
    rho, phi, dd = (np.asarray(v, dtype=float) for v in (rho, params.phi, params.dd))
    own, other = p[[0, 1, 2]], p[[2, 0, 1]]
    return np.diag(rho * (own * np.sin(phi) - other * np.cos(phi) + dd * np.cos(phi)))


def forward_velocity(p, rho, rho_dot, params: OrthoglideParameters) -> np.ndarray:
    """Platform velocity ``dp/dt = A^-1 B_rho drho/dt`` [m/s]."""
    return np.linalg.solve(jacobian_a(p, rho, params), b_rho(p, rho, params) @ rho_dot)


def sensitivities(p, rho, params: OrthoglideParameters) -> dict:
    """``dp / d(parameter)``: ``{"rho": A^-1 B_rho, "L": A^-1 B_L, "phi": A^-1 B_phi,
    "dd": A^-1 B_d}`` (3x3 each, column i for leg i's parameter)."""
    A = jacobian_a(p, rho, params)
    return {
        "rho": np.linalg.solve(A, b_rho(p, rho, params)),
        "L": np.linalg.solve(A, b_l(params)),
        "phi": np.linalg.solve(A, b_phi(p, rho, params)),
        "dd": np.linalg.solve(A, b_d(p, rho, params)),
    }
