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
from numba.extending import register_jitable

from ..compiling import SameTypes
from .linalg import reset
from .stages import (
    actuation_wrench,
    carried_determinant,
    leg_constraints,
    locked_motion_index,
    motion_twists,
    platform_system,
    scale_actuation,
    shift_twist,
    transmission,
    wrench_about_origin,
)


class Layout(NamedTuple):
    """Where each leg's joints sit among the rows of the joint twists, and the
    constants of the rank decisions.

    Attributes:
        coords: (legs + 1,) row offsets: leg ``l`` owns rows ``coords[l]:coords[l+1]``.
        groups: (G, 3) rows of the spherical groups (three concurrent revolutes).
        act_col: (n,) row of each actuated joint, in actuated-coordinate order.
        act_leg: (n,) its leg.
        reference: (n_ref, 6) platform basis of the reference (home) pose, homogenised
            about its centre, for the carried determinant; (0, 6) for none.
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


#: Columns of :attr:`Results.counts` …
DOF, TRANSLATIONS, REDUNDANT = 0, 1, 2
#: … and of :attr:`Results.scalars`.
TYPE_I, TYPE_II, CONDITION, DET = 0, 1, 2, 3


class Results(NamedTuple):
    """The engine's output for N poses (first axis: the pose).

    Homogenised bases are about the pose's centre ``p`` (:func:`analyse`'s ``centres``:
    moment parts about ``p`` divided by ``L``), orthonormal, masked: rows beyond their
    dimension are zero.

    Attributes:
        counts: (N, 3) integers, read as the properties :attr:`dof` (degrees of freedom
            of the platform: dimension of its twist system), :attr:`translations`
            (dimension of the pure translations among them) and :attr:`redundant` (Σ
            leg constraint dimensions − rank of their union); columns ``DOF``,
            ``TRANSLATIONS``, ``REDUNDANT``.
        scalars: (N, 4), read as :attr:`type_I`, :attr:`type_II`, :attr:`condition`
            (closeness indices) and :attr:`det` (carried determinant); columns
            ``TYPE_I``, ``TYPE_II``, ``CONDITION``, ``DET``. (Two arrays rather than
            seven: a single pose's analysis allocates and passes every array.)
        independent: (N, n) whether each actuated joint's twist is independent of the
            other joint twists of its leg.
        leg_dims: (N, legs) dimension of each leg's constraint wrench system.
        leg_constraints: (N, legs, 6, 6) their homogenised orthonormal bases.
        constraints: (N, 6, 6) homogenised orthonormal basis of their union (rows).
        platform: (N, 6, 6) homogenised orthonormal basis of the platform twists.
        A: (N, n, 6) actuation wrenches (world units: unit force, or unit moment),
            about the world origin.
        B: (N, n) diagonal of B, ``B_ii = A_i ∘ $_a,i``.
        A_h: (N, n, 6) the actuation wrenches homogenised (about ``p``), rows of unit
            norm.
    """

    counts: np.ndarray
    scalars: np.ndarray
    independent: np.ndarray
    leg_dims: np.ndarray
    leg_constraints: np.ndarray
    constraints: np.ndarray
    platform: np.ndarray
    A: np.ndarray
    B: np.ndarray
    A_h: np.ndarray

    @property
    def dof(self) -> np.ndarray:
        """(N,) degrees of freedom of the platform."""
        return self.counts[:, DOF]

    @property
    def translations(self) -> np.ndarray:
        """(N,) dimension of the pure translations among the platform twists."""
        return self.counts[:, TRANSLATIONS]

    @property
    def redundant(self) -> np.ndarray:
        """(N,) Σ leg constraint dimensions − rank of their union."""
        return self.counts[:, REDUNDANT]

    @property
    def type_I(self) -> np.ndarray:
        """(N,) type I closeness index."""
        return self.scalars[:, TYPE_I]

    @property
    def type_II(self) -> np.ndarray:
        """(N,) type II closeness index."""
        return self.scalars[:, TYPE_II]

    @property
    def condition(self) -> np.ndarray:
        """(N,) condition number of ``A_h Δ Pᵀ``."""
        return self.scalars[:, CONDITION]

    @property
    def det(self) -> np.ndarray:
        """(N,) carried determinant."""
        return self.scalars[:, DET]


def allocate(N: int, layout: Layout, full: bool = True) -> Results:
    """Output arrays for N poses (:func:`analyse_into` writes every entry, but the
    leg constraint rows beyond each leg's dimension, which stay zero). Without
    ``full`` the bases and Jacobians are not kept (their arrays are empty): sweeps keep
    the scalars only."""
    legs = len(layout.coords) - 1
    n = len(layout.act_col)
    F = N if full else 0
    e = np.empty
    return Results(
        e((N, 3), np.int64), e((N, 4)), e((F, n), np.bool_), e((F, legs), np.int64),
        np.zeros((F, legs, 6, 6)), e((F, 6, 6)), e((F, 6, 6)), e((F, n, 6)), e((F, n)),
        e((F, n, 6)))


def analyse(J: np.ndarray, layout: Layout, full: bool = True,
            centres: np.ndarray | None = None) -> Results:
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
        centres: (N, 3) the mechanism's centre at each pose [m] (the platform's origin):
            every screw is homogenised about it (:mod:`.stages`), so the results do not
            depend on where the mechanism stands in the world; default: the world origin.
    """
    J = np.ascontiguousarray(J, dtype=float)
    N = J.shape[0]
    if J.ndim != 3 or J.shape[1:] != (layout.coords[-1], 6):
        raise ValueError(f"joint twists of shape {J.shape}: expected (N, "
                         f"{int(layout.coords[-1])}, 6)")
    centres = np.zeros((N, 3)) if centres is None else np.ascontiguousarray(centres,
                                                                            dtype=float)
    if centres.shape != (N, 3):
        raise ValueError(f"centres of shape {centres.shape}: expected ({N}, 3)")
    out = allocate(N, layout, full)
    if N == 1:  # plain Python until the compiled code is ready (no compilation here)
        _analyse_into(J, centres, layout, out, bool(full))
    else:
        _analyse_many(J, centres, layout, out, bool(full))
    return out


class Workspace(NamedTuple):
    """Work arrays of :func:`analyse_into`, made once per call (see the stages for what
    each holds). ``V_legs``, ``V_union`` and ``V_M`` carry the singular bases of the
    legs, of the union and of ``A_h Δ Pᵀ`` from pose to pose (warm starts).

    :func:`analyse_into` unpacks it into local arrays at once: numba 0.68 miscompiled
    writes through the attributes of this 32-array tuple inside the loop (tested: the
    plain-Python engine and the compiled one agree to the last bit)."""

    T: np.ndarray
    X: np.ndarray
    W: np.ndarray
    W2: np.ndarray
    V2: np.ndarray
    sv: np.ndarray
    sv2: np.ndarray
    order: np.ndarray
    LU: np.ndarray
    perm: np.ndarray
    work6: np.ndarray
    C: np.ndarray
    V_legs: np.ndarray
    V_union: np.ndarray
    V_M: np.ndarray
    W3: np.ndarray
    V3: np.ndarray
    sv3: np.ndarray
    G: np.ndarray
    gb: np.ndarray
    centre: np.ndarray
    wh: np.ndarray
    ok: np.ndarray
    Ah: np.ndarray
    A: np.ndarray
    t_h: np.ndarray
    B: np.ndarray
    cons: np.ndarray
    P: np.ndarray
    Pw: np.ndarray
    M: np.ndarray
    P_loc: np.ndarray
    work: np.ndarray


@register_jitable
def workspace(nv, legs, n, n_ref):
    """The :class:`Workspace` for ``nv`` joint twists, ``legs`` legs, ``n`` actuators
    and a reference basis of ``n_ref`` twists."""
    nn = max(n, 1)
    V_legs = np.zeros((legs, 6, 6))
    for l in range(legs):
        for a in range(6):
            V_legs[l, a, a] = 1.0
    return Workspace(
        np.empty((nv, 6)), np.empty((max(nv, 6), 6)), np.empty((max(6 * legs, nv, nn, 6), 6)),
        np.empty((max(nv, 6), 6)), np.empty((6, 6)), np.empty(6), np.empty(6),
        np.empty(6, np.int64), np.empty((6, 6)), np.empty(6, np.int64), np.empty((6, 6)),
        np.empty((max(6 * legs, 1), 6)), V_legs, np.eye(6), np.eye(6), np.empty((6, 3)),
        np.eye(3), np.empty(3), np.empty((3, 3)), np.empty(3), np.empty(3),
        np.empty((nn, 6)), np.empty(nn, np.bool_), np.empty((nn, 6)), np.empty(6),
        np.empty(6), np.empty(nn), np.empty((6, 6)), np.zeros((6, 6)), np.empty((6, 3)),
        np.empty((nn, 6)), np.empty((max(n_ref, 1), 6)), np.empty((nn, nn)))


@njit(cache=True, nogil=True)
def analyse_into(J, centres, layout, out, full):
    """:func:`analyse` in compiled code: fills ``out`` (see :func:`allocate`)."""
    coords, act_col, act_leg = layout.coords, layout.act_col, layout.act_leg
    L, rtol = layout.length, layout.rtol
    n = act_col.shape[0]
    (T, X, W, W2, V2, sv, sv2, order, LU, perm, work6, C, V_legs, V_union, V_M, W3, V3, sv3, G, gb,
     centre, wh, ok, Ah, A, t_h, B, cons, P, Pw, M, P_loc, work) = workspace(
        J.shape[1], coords.shape[0] - 1, n, layout.reference.shape[0])
    d_prev = -1
    tw = np.empty(6)
    for i in range(J.shape[0]):
        p = centres[i]
        motion_twists(J[i], layout.groups, L, p, T, G, gb, centre)
        # stages 2, 3: each leg's constraint wrenches and its actuation wrenches
        m_c = 0
        for l in range(coords.shape[0] - 1):
            c0, k, first = coords[l], coords[l + 1] - coords[l], m_c
            r, m_c, mode = leg_constraints(T, c0, k, rtol, X, W, V_legs[l], sv, C,
                                           m_c, LU, perm)
            if full:
                out.leg_dims[i, l] = m_c - first
                out.leg_constraints[i, l, :m_c - first] = C[first:m_c]
            for a_i in range(n):
                if act_leg[a_i] != l:
                    continue
                ok[a_i] = actuation_wrench(T, c0, k, act_col[a_i] - c0, r, mode, LU, perm,
                                           rtol, X, W, V_legs[l], sv, C, first, m_c, W2, V2,
                                           sv2, wh[a_i])
        # stage 4: the platform twist system
        rank_c, rotations = platform_system(C, m_c, rtol, layout.rot_tol, W, V_union, sv,
                                            order, cons, P, Pw, W3, V3,
                                            sv3)
        d = 6 - rank_c
        counts = out.counts[i]
        counts[DOF], counts[TRANSLATIONS], counts[REDUNDANT] = d, d - rotations, m_c - rank_c
        # stage 5: actuation wrenches in world units, B, type I
        t1 = np.inf
        for a_i in range(n):
            shift_twist(J[i, act_col[a_i]], p, tw)
            B, index = scale_actuation(wh[a_i], tw, L, rtol, A, Ah[a_i], t_h)
            t1 = min(t1, index)
            if full:
                out.B[i, a_i], out.independent[i, a_i] = B, ok[a_i]
                wrench_about_origin(A, p, out.A[i, a_i])
                out.A_h[i, a_i] = Ah[a_i]
        out.scalars[i, TYPE_I] = t1
        # stage 6: A_h Δ Pᵀ, type II index, condition, carried determinant
        if d != d_prev:  # a new platform dimension: the warm start of V_M is void
            reset(V_M, 6)
            d_prev = d
        out.scalars[i, TYPE_II], out.scalars[i, CONDITION] = transmission(
            Ah, n, P, d, M, W, V_M, sv, order)
        if not ok[:n].all():  # an actuation wrench is not defined: the locked motions
            out.scalars[i, TYPE_II] = locked_motion_index(T, coords, act_col, rtol, P, d, X,
                                                          W, V2, sv2, C, LU, work6, order)
        out.scalars[i, DET] = carried_determinant(Ah, n, P, d, layout.reference, M, P_loc,
                                                  work, perm)
        if full:
            out.constraints[i] = 0.0
            out.constraints[i, :rank_c] = cons[:rank_c]
            out.platform[i] = 0.0
            out.platform[i, :d] = P[:d]


#: :func:`analyse_into` as :func:`analyse` calls it (its arguments keep their types),
#: for one pose (plain Python until compiled) and for several (a sweep's blocks)
_analyse_into = SameTypes(analyse_into, key=2, plain=True)
_analyse_many = SameTypes(analyse_into, key=2)
