"""The analysis engine: N ≥ 1 poses of a mechanism in, full screw analysis out.

:func:`analyse` takes the joint twists of every leg at N assembled configurations
(rows, axis-first, about the world origin: the columns of Pinocchio's WORLD Jacobians
converted by :mod:`pkm_pin.screws`) and the mechanism's :class:`Layout`, and returns a
:class:`Results` of arrays indexed by pose. :class:`~pkm_pin.analysis.Analysis` is one
index of it, :meth:`~pkm_pin.Mechanism.sweep` runs it on chunks of poses: one
computation, whatever the number of poses. The stages are in :mod:`.stages`.

Along a sweep the singular bases of every stage are warm starts for the next pose (they
leave few Jacobi rotations and keep the bases continuous); the first pose starts cold,
so the result at a pose does not depend on the poses before it beyond round-off.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ..compiling import prefer_compiled
from .stages import (
    actuation_wrench,
    carried_determinant,
    leg_constraints,
    motion_twists,
    platform_system,
    scale_actuation,
    transmission,
)


class Layout(NamedTuple):
    """Where each leg's joints sit among the rows of the joint twists, and the
    constants of the rank decisions.

    Attributes:
        coords: (legs + 1,) row offsets: leg ``l`` owns rows ``coords[l]:coords[l+1]``.
        groups: (G, 3) rows of the spherical groups (three concurrent revolutes).
        act_col: (n,) row of each actuated joint, in actuated-coordinate order.
        act_leg: (n,) its leg.
        reference: (n_ref, 6) homogenised platform basis of the reference (home) pose,
            for the carried determinant; (0, 6) for none.
        length: Characteristic length L of the mechanism [m]: moments are divided by it.
        rtol: Relative tolerance of the rank decisions (``σ > rtol · σ_max``).
        rot_tol: Absolute tolerance on the singular values of the ω parts of the
            orthonormal platform twists (counting rotations).
    """

    coords: np.ndarray
    groups: np.ndarray
    act_col: np.ndarray
    act_leg: np.ndarray
    reference: np.ndarray
    length: float
    rtol: float
    rot_tol: float


class Results(NamedTuple):
    """The engine's output for N poses (first axis: the pose).

    Homogenised bases are orthonormal, masked: rows beyond their dimension are zero.

    Attributes:
        dof: (N,) degrees of freedom of the platform (dimension of its twist system).
        translations: (N,) dimension of the pure translations among them.
        redundant: (N,) Σ leg constraint dimensions − rank of their union.
        type_I, type_II, condition, det: (N,) closeness indices and carried determinant.
        independent: (N, n) whether each actuated joint's twist is independent of the
            other joint twists of its leg.
        leg_dims: (N, legs) dimension of each leg's constraint wrench system.
        leg_constraints: (N, legs, 6, 6) their homogenised orthonormal bases.
        constraints: (N, 6, 6) homogenised orthonormal basis of their union (rows).
        platform: (N, 6, 6) homogenised orthonormal basis of the platform twists.
        A: (N, n, 6) actuation wrenches (world units: unit force, or unit moment).
        B: (N, n) diagonal of B, ``B_ii = A_i ∘ $_a,i``.
        A_h: (N, n, 6) the actuation wrenches homogenised, rows of unit norm.
    """

    dof: np.ndarray
    translations: np.ndarray
    redundant: np.ndarray
    type_I: np.ndarray
    type_II: np.ndarray
    condition: np.ndarray
    det: np.ndarray
    independent: np.ndarray
    leg_dims: np.ndarray
    leg_constraints: np.ndarray
    constraints: np.ndarray
    platform: np.ndarray
    A: np.ndarray
    B: np.ndarray
    A_h: np.ndarray


def allocate(N: int, layout: Layout, full: bool = True) -> Results:
    """Output arrays for N poses (:func:`analyse_into` writes every entry, but the
    leg constraint rows beyond each leg's dimension, which stay zero). Without ``full`` the bases and Jacobians are not
    kept (their arrays are empty): sweeps keep the scalars only."""
    legs = len(layout.coords) - 1
    n = len(layout.act_col)
    F = N if full else 0
    e = np.empty
    return Results(
        e(N, np.int64), e(N, np.int64), e(N, np.int64), e(N), e(N), e(N), e(N),
        e((F, n), np.bool_), e((F, legs), np.int64), np.zeros((F, legs, 6, 6)), e((F, 6, 6)),
        e((F, 6, 6)), e((F, n, 6)), e((F, n)), e((F, n, 6)))


def analyse(J: np.ndarray, layout: Layout, full: bool = True) -> Results:
    """Screw analysis of N assembled poses.

    The compiled engine runs for more than one pose, and for one pose when
    :func:`pkm_pin.compiling.prefer_compiled` says so; before that (a one-off analysis on
    a fresh installation) the same code runs as plain Python: milliseconds a pose, the
    same numbers to the last bit.

    Args:
        J: (N, nv, 6) joint twists of every leg one after the other (rows, axis-first,
            world units, about the world origin).
        layout: The mechanism's :class:`Layout`.
        full: Keep the bases and Jacobians (else the scalars only).
    """
    J = np.ascontiguousarray(J, dtype=float)
    if J.ndim != 3 or J.shape[2] != 6 or J.shape[1] != int(layout.coords[-1]):
        raise ValueError(f"joint twists of shape {J.shape}: expected (N, "
                         f"{int(layout.coords[-1])}, 6)")
    out = allocate(len(J), layout, full)
    if len(J) > 1 or prefer_compiled(analyse_into):
        analyse_into(J, layout, out, full)
    else:
        analyse_into.py_func(J, layout, out, full)
    return out


@njit(cache=True, nogil=True)
def analyse_into(J, layout, out, full):
    """:func:`analyse` in compiled code: fills ``out`` (see :func:`allocate`)."""
    N, nv = J.shape[0], J.shape[1]
    coords, act_col, act_leg = layout.coords, layout.act_col, layout.act_leg
    L, rtol = layout.length, layout.rtol
    legs = coords.shape[0] - 1
    n = act_col.shape[0]
    nn = max(n, 1)
    T = np.empty((nv, 6))
    X = np.empty((max(nv, 6), 6))
    W = np.empty((max(6 * legs, nv, nn, 6), 6))
    W2 = np.empty((max(nv, 6), 6))
    V2 = np.empty((6, 6))
    sv = np.empty(6)
    Xi = np.empty((6, 6))
    work6 = np.empty((6, 6))
    sv2 = np.empty(6)
    order = np.empty(6, np.int64)
    C = np.empty((max(6 * legs, 1), 6))
    V_legs = np.zeros((legs, 6, 6))
    for l in range(legs):
        for a in range(6):
            V_legs[l, a, a] = 1.0
    V_union = np.eye(6)
    V_M = np.eye(6)
    W3 = np.empty((6, 3))
    V3 = np.empty((3, 3))
    sv3 = np.empty(3)
    G = np.empty((3, 3))
    gb = np.empty(3)
    centre = np.empty(3)
    wh = np.empty((nn, 6))  # homogenised actuation wrenches of the legs' stage
    ok = np.empty(nn, np.bool_)
    Ah = np.empty((nn, 6))
    A = np.empty(6)
    t_h = np.empty(6)
    B = np.empty(nn)
    cons = np.empty((6, 6))
    P = np.zeros((6, 6))
    Pw = np.empty((6, 3))
    M = np.empty((nn, 6))
    P_loc = np.empty((max(layout.reference.shape[0], 1), 6))
    work = np.empty((nn, nn))
    d_prev = -1
    for i in range(N):
        motion_twists(J[i], layout.groups, L, T, G, gb, centre)
        # legs: constraint wrenches, then the actuation wrench of each actuated joint
        m_c = 0
        for l in range(legs):
            c0, k = coords[l], coords[l + 1] - coords[l]
            first = m_c
            r, m_c, square = leg_constraints(T, c0, k, rtol, X, W, V_legs[l], sv, C, m_c, Xi,
                                             work6)
            if full:
                out.leg_dims[i, l] = m_c - first
                for j in range(m_c - first):
                    for a in range(6):
                        out.leg_constraints[i, l, j, a] = C[first + j, a]
            for a_i in range(n):
                if act_leg[a_i] == l:
                    ok[a_i] = actuation_wrench(T, c0, k, act_col[a_i] - c0, r, square, Xi,
                                               rtol, X, W, V_legs[l], sv, C, first, m_c, W2,
                                               V2, sv2, wh[a_i])
        # union of the constraints, platform twists
        rank_c, rotations = platform_system(C, m_c, rtol, layout.rot_tol, W, V_union, sv,
                                            order, cons, P, Pw, W3, V3, sv3)
        d = 6 - rank_c
        out.dof[i] = d
        out.translations[i] = d - rotations
        out.redundant[i] = m_c - rank_c
        # actuation wrenches in world units, B, type I
        t1 = np.inf
        for a_i in range(n):
            B[a_i], p = scale_actuation(wh[a_i], J[i, act_col[a_i]], L, rtol, A, Ah[a_i],
                                        t_h)
            t1 = min(t1, p)
            if full:
                out.B[i, a_i] = B[a_i]
                out.independent[i, a_i] = ok[a_i]
                for a in range(6):
                    out.A[i, a_i, a] = A[a]
                    out.A_h[i, a_i, a] = Ah[a_i, a]
        out.type_I[i] = t1
        # A_h Δ Pᵀ: type II index, condition, carried determinant
        if d != d_prev:  # a new platform dimension: the warm start is void
            for a in range(6):
                for b in range(6):
                    V_M[a, b] = 1.0 if a == b else 0.0
            d_prev = d
        out.type_II[i], out.condition[i] = transmission(Ah, n, P, d, M, W, V_M, sv, order)
        out.det[i] = carried_determinant(Ah, n, P, d, layout.reference, M, P_loc, work)
        if full:
            for j in range(6):
                for a in range(6):
                    out.constraints[i, j, a] = cons[j, a] if j < rank_c else 0.0
                    out.platform[i, j, a] = P[j, a] if j < d else 0.0
