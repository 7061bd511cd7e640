"""Recursive "screw reduction" of an open serial chain (seed 002), by hand — plain numpy.

Seed 002: anon., Polish, 1987, see docs/references.md.

Part of the independent witness :mod:`pkm_pin.formulas`: imports nothing from
``pkm_pin`` and nothing from Pinocchio.

Seed 002's notions, as used here
--------------------------------
* Every link ``i`` has a local frame whose origin is the **pole** ``A_i`` of the pair
  joining it to link ``i-1`` (the point common to both links of the pair). Link poses
  are 4x4 homogeneous ("projective") transforms ``T_0i = T_01 T_12 ... T_{i-1,i}``; the
  rotation-only part is the paper's collineation ``K_0i`` (:func:`collineation`).
* The kinematic **motor** of link ``i`` at its pole is ``M_Ai = w_0i + eps v_Ai``
  (angular velocity, velocity of the pole; ``eps`` the Clifford dual unit,
  ``eps^2 = 0``). Moved to the world origin it is the axis-first twist ``(w; v_O)`` with
  ``v_O = v_A + w x (O - A) = v_A - w x A``.
* The kinematic **screw** (skretnik) is ``S = w (1 + mu eps)`` with the **parameter**
  ``mu = w.v / |w|^2`` (the pitch [m/rad], the same for every pole), its axis the line
  ``p = x0 + lambda w/|w|``.
* Propagation pole to pole (15), (19): ``v_B = v_A + B_AB w``, ``a_B = a_A + B_AB eps +
  V_AB w`` with ``B_AB w = w x AB`` (:func:`pole_matrix`, (16)) and ``V_AB w = w x
  (v_B - v_A)`` ((20)); across a prismatic pair the relative velocity ``v_rel = qd e``
  and, for accelerations, the Coriolis ``2 w x v_rel`` and the relative acceleration
  ``qdd e`` are added ((40), (43)).

Conventions: screws axis-first ``(s; s0)`` about the world origin, twists ``(w; v_O)``;
SI units, radians; all vectors are returned in world (base) coordinates.

Chain description
-----------------
A chain is a sequence of :class:`ChainJoint` (or ``(kind, offset, axis)`` tuples):
``kind`` is ``'R'`` or ``'P'``; ``offset`` is the fixed 4x4 transform from the previous
joint frame (after that joint's motion; the base frame for the first joint) to this
joint's frame before its motion; ``axis`` is the unit joint axis in this joint frame,
through its origin. The joint motion is ``Rot(axis, q)`` [rad] or ``Trans(axis q)`` [m],
so ``T_0i = T_0,i-1 @ offset_i @ motion_i(q_i)`` and link ``i``'s pole is the origin
of ``T_0i``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Sequence

import numpy as np


@dataclass(frozen=True)
class ChainJoint:
    """One pair of an open serial chain.

    Attributes:
        kind: ``'R'`` (revolute, q in rad) or ``'P'`` (prismatic, q in m).
        offset: (4, 4) fixed transform previous joint frame -> this joint frame.
        axis: (3,) unit axis in this joint frame.
        name: Optional label used by :func:`reduction_graph`.
    """

    kind: str
    offset: np.ndarray
    axis: np.ndarray
    name: str = ""


@dataclass
class LinkState:
    """Kinematic state of one link, all vectors in world coordinates.

    Attributes:
        index: 1-based link number (link 0 is the base).
        kind: Kind of the pair joining it to its predecessor.
        pose: (4, 4) ``T_0i``.
        pole: (3,) pole ``A_i`` (origin of ``T_0i``) [m].
        w: Angular velocity ``w_0i`` [rad/s].
        eps: Angular acceleration [rad/s^2].
        v_pole: Velocity of the pole [m/s].
        a_pole: Classical acceleration of the pole [m/s^2].
        axis: Joint axis in world coordinates (unit).
        motor: Axis-first twist ``(w; v_O)`` about the world origin.
    """

    index: int
    kind: str
    pose: np.ndarray
    pole: np.ndarray
    w: np.ndarray
    eps: np.ndarray
    v_pole: np.ndarray
    a_pole: np.ndarray
    axis: np.ndarray
    motor: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.motor = np.concatenate([self.w, self.v_pole - np.cross(self.w, self.pole)])


def _skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix ``[v]x``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues rotation about unit ``axis`` by ``angle`` [rad]."""
    k = _skew(axis)
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * k @ k


def joint_motion(kind: str, axis: Sequence[float], q: float) -> np.ndarray:
    """4x4 motion of a pair: ``Rot(axis, q)`` for ``'R'``, ``Trans(q axis)`` for ``'P'``.

    Args:
        kind: ``'R'`` or ``'P'``.
        axis: (3,) unit axis in the joint frame.
        q: Joint coordinate [rad or m].

    Returns:
        (4, 4) homogeneous transform.
    """
    a = np.asarray(axis, dtype=float)
    out = np.eye(4)
    if kind == "R":
        out[:3, :3] = _rotation(a, q)
    elif kind == "P":
        out[:3, 3] = q * a
    else:
        raise ValueError(f"joint kind must be 'R' or 'P', got {kind!r}")
    return out


def collineation(T: np.ndarray) -> np.ndarray:
    """Seed 002's collineation ``K``: the 4x4 transform with its translation zeroed."""
    K = np.array(T, dtype=float, copy=True)
    K[:3, 3] = 0.0
    return K


def pole_matrix(r: Sequence[float]) -> np.ndarray:
    """Seed 002's matrix (16) of a relative position ``r = (x, y, z)``.

    Returns:
        ``[[0, z, -y], [-z, 0, x], [y, -x, 0]]`` so that ``pole_matrix(r) @ w = w x r``.
        With ``r`` a relative velocity it is the matrix ``V`` of (20)/(44).
    """
    x, y, z = np.asarray(r, dtype=float)
    return np.array([[0.0, z, -y], [-z, 0.0, x], [y, -x, 0.0]])


def _as_joints(chain: Iterable) -> list[ChainJoint]:
    """Normalise a chain given as ChainJoint objects or (kind, offset, axis) tuples."""
    out = []
    for j in chain:
        if not isinstance(j, ChainJoint):
            j = ChainJoint(*j)
        out.append(j)
    return out


def chain_kinematics(chain: Sequence, q: Sequence[float], qd: Sequence[float],
                     qdd: Sequence[float]) -> list[LinkState]:
    """Positions, velocities and accelerations of every link by pole-to-pole reduction.

    For pair ``i`` with world axis ``e`` at joint point ``c`` (origin of
    ``T_0,i-1 @ offset_i``) and ``r = (new pole) - A_{i-1}``:

    * revolute: ``A_i = c``, ``w_i = w + qd e``, ``eps_i = eps + qdd e + w x (qd e)``,
      ``v_i = v + w x r``, ``a_i = a + eps x r + w x (w x r)``;
    * prismatic: ``A_i = c + q e``, ``w_i = w``, ``eps_i = eps``,
      ``v_i = v + w x r + qd e``, ``a_i = a + eps x r + w x (w x r) + 2 w x (qd e) + qdd e``.

    Args:
        chain: Sequence of :class:`ChainJoint` or ``(kind, offset, axis)``.
        q, qd, qdd: Joint positions, rates and accelerations (rad or m, per second...).

    Returns:
        One :class:`LinkState` per joint (links 1..n); the base is at rest at identity.
    """
    joints = _as_joints(chain)
    T = np.eye(4)
    pole, w, eps, v, a = (np.zeros(3) for _ in range(5))
    states = []
    for i, j in enumerate(joints):
        frame = T @ np.asarray(j.offset, dtype=float)
        e = frame[:3, :3] @ np.asarray(j.axis, dtype=float)
        T = frame @ joint_motion(j.kind, j.axis, q[i])
        new_pole = T[:3, 3].copy()
        r = new_pole - pole
        v_new = v + pole_matrix(r) @ w
        a_new = a + pole_matrix(r) @ eps + pole_matrix(v_new - v) @ w
        if j.kind == "R":
            eps = eps + qdd[i] * e + np.cross(w, qd[i] * e)
            w = w + qd[i] * e
        else:
            v_rel = qd[i] * e
            a_new = a_new + 2.0 * np.cross(w, v_rel) + qdd[i] * e
            v_new = v_new + v_rel
        pole, v, a = new_pole, v_new, a_new
        states.append(LinkState(i + 1, j.kind, T.copy(), pole.copy(), w.copy(), eps.copy(),
                                v.copy(), a.copy(), e))
    return states


def point_velocity(link_state: LinkState, point_world: Sequence[float]) -> np.ndarray:
    """Velocity (15) of a point of the link: ``v_P = v_A + B_AP w`` = ``v_A + w x AP``.

    Args:
        link_state: State of the link carrying the point.
        point_world: (3,) current world position of the point [m].

    Returns:
        (3,) velocity [m/s].
    """
    r = np.asarray(point_world, dtype=float) - link_state.pole
    return link_state.v_pole + pole_matrix(r) @ link_state.w


def point_acceleration(link_state: LinkState, point_world: Sequence[float]) -> np.ndarray:
    """Classical acceleration (19) of a point of the link.

    ``a_P = a_A + B_AP eps + V_AP w`` = ``a_A + eps x AP + w x (w x AP)``.

    Args:
        link_state: State of the link carrying the point.
        point_world: (3,) current world position of the point [m].

    Returns:
        (3,) acceleration [m/s^2].
    """
    r = np.asarray(point_world, dtype=float) - link_state.pole
    v_rel = pole_matrix(r) @ link_state.w
    return link_state.a_pole + pole_matrix(r) @ link_state.eps + pole_matrix(v_rel) @ link_state.w


def link_screw(twist: Sequence[float], tol: float = 1e-12
               ) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Instantaneous screw axis and parameter (pitch) of an axis-first twist.

    Args:
        twist: ``(w; v_O)`` about the world origin.
        tol: Norms below this count as zero.

    Returns:
        ``(point, direction, pitch)``: the axis point nearest the origin
        ``w x v_O / |w|^2`` [m], the unit direction ``w/|w|`` and ``mu = w.v_O/|w|^2``
        [m/rad]. For a pure translation: ``(0, v/|v|, inf)`` (axis at infinity; any
        parallel line). ``None`` when the body is at rest.
    """
    t = np.asarray(twist, dtype=float)
    w, v = t[:3], t[3:]
    nw = float(np.linalg.norm(w))
    if nw <= tol:
        nv = float(np.linalg.norm(v))
        if nv <= tol:
            return None
        return np.zeros(3), v / nv, float("inf")
    return np.cross(w, v) / nw**2, w / nw, float(w @ v) / nw**2


def reduction_graph(chain: Sequence, states: Sequence[LinkState] | None = None) -> str:
    """Graph of the recursive reduction (seed 002, Figs. 4, 5, 7) as Graphviz DOT text.

    Nodes: per link ``i`` the angular velocity ``w_0i`` and the pole velocity ``v_Ai``
    (together the motor ``M_Ai``), the screw ``S_i = w_0i(1 + mu_i eps)``, and for a
    prismatic pair the relative velocity ``v_rel,i``. Solid edges carry the transforms
    (``T_{i-1,i}``, the collineation ``K``, the pole matrix ``B_{A(i-1)A(i)}``); dashed
    edges (motor -> screw) carry the parameter ``mu_i``, as in the paper.

    Args:
        chain: The chain (see :func:`chain_kinematics`).
        states: Optional states from :func:`chain_kinematics` to print numbers.

    Returns:
        DOT source text (no graphviz package needed).
    """
    joints = _as_joints(chain)
    lines = ["digraph screw_reduction {", "  rankdir=LR;", "  node [shape=box];",
             '  w0 [label="w_00 = 0 (base)"];', '  v0 [label="v_A0 = 0 (base)"];']
    for i, j in enumerate(joints, start=1):
        name = f" {j.name}" if j.name else ""
        mu = ""
        if states is not None:
            scr = link_screw(states[i - 1].motor)
            mu = " = ?" if scr is None else f" = {scr[2]:.6g}"
            w_lbl = np.array2string(states[i - 1].w, precision=4)
            v_lbl = np.array2string(states[i - 1].v_pole, precision=4)
        else:
            w_lbl = v_lbl = ""
        lines.append(f'  w{i} [label="w_0{i}{name} {w_lbl}"];')
        lines.append(f'  v{i} [label="v_A{i} {v_lbl}"];')
        lines.append(f'  S{i} [shape=ellipse, label="S_{i} = w_0{i}(1 + mu_{i} eps)"];')
        k_lbl = f"K_0{i}: + qd_{i} e_{i}" if j.kind == "R" else f"K_0{i}: unchanged (P)"
        lines.append(f'  w{i - 1} -> w{i} [label="{k_lbl}"];')
        lines.append(f'  v{i - 1} -> v{i} [label="T_{i - 1},{i}"];')
        lines.append(f'  w{i - 1} -> v{i} [label="B_A{i - 1}A{i}"];')
        if j.kind == "P":
            lines.append(f'  vrel{i} [label="v_rel{i} = qd_{i} e_{i}"];')
            lines.append(f"  vrel{i} -> v{i};")
        lines.append(f'  w{i} -> S{i} [style=dashed, label="mu_{i}{mu}"];')
        lines.append(f"  v{i} -> S{i} [style=dashed];")
    lines.append("}")
    return "\n".join(lines) + "\n"
