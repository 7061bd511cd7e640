"""Compiled general elimination of a linkage's analysis (issue 24).

:meth:`pkm_pin.linkage.Linkage.analyze` at one configuration takes the closure
Jacobian, the null space of its dimensionless columns, the output twist system, the
actuation wrenches ``A``, ``B``, the type I/II indices and the general forward and
inverse indices through some fifteen small SVDs. In numpy each one costs its Python
wrapper (~5 µs) plus the arrays around it, ~1 ms a pose. :func:`analysis_core` does
the same algebra in one numba-compiled call: the closure and output Jacobians from
the compiled tree (:func:`pkm_pin.tree_kernel.closure_rows`, no Pinocchio ``Data``),
then each step of :mod:`pkm_pin.linkage`'s numpy path (``_numpy_core``) in the same
order with the same LAPACK routines (``gesdd`` SVDs, ``geqrf`` QR) and the same rank
rule (:func:`pkm_pin.screws.svd_rank`: singular values above ``rtol`` times the
largest). Where only singular values are read (the rotations of the twist system,
the type II index, the forward and inverse indices), and for the least-norm step of
each actuation wrench (whose result does not depend on the bases it is computed in),
a one-sided Jacobi SVD (:func:`pkm_pin.engine.linalg.jacobi`) replaces LAPACK's SVD and
least-squares solve: the same numbers to round-off, without LAPACK's fixed cost.

It is an accelerator, not a second definition: ``tests/test_general_kernel.py``
compares every field with the numpy path's to 1e-9 at random assembled configurations
(bases through the projectors onto their spans). :data:`ENABLED` switches it off; trees
that :func:`pkm_pin.tree_kernel.tree_kernel` does not represent (mimic joints) take the
numpy path. The kernel runs as plain Python until its machine code is ready
(:class:`~pkm_pin.compiling.SameTypes` with ``plain``: a one-off analysis on a fresh
installation does not wait for numba).

Conventions are :mod:`pkm_pin.linkage`'s: screws axis-first, twists ``(ω; v_O)`` and
wrenches ``(f; m_O)`` about the world origin, homogenised ``(a; (b + a × p) / L)``
about ``p`` (the output frame's origin, or the world origin) for every decision;
columns per velocity coordinate times :attr:`ClosureModel.velocity_units`.
"""

from __future__ import annotations

import functools
import math
import weakref
from typing import NamedTuple

import numpy as np
from numba import njit
from numba.extending import register_jitable

from . import screws
from .compiling import SameTypes
from .engine.linalg import JACOBI_TOL, jacobi, largest
from .model.closure_model import sparse_basis
from .tolerances import GIMBAL_LOCK_RTOL, JOINT_LIMIT_SLACK, ROTATION_COUNT_TOL
from .tree_kernel import (
    PRISMATIC,
    TreeKernel,
    closure_rows,
    tree_kernel,
    tree_placements,
    tree_twists,
    workspace,
)

#: Whether :meth:`Linkage.analyze` may use this module (False: the numpy path
#: everywhere, for comparisons and diagnosis).
ENABLED = True

#: Beyond this many closure rows, an actuation row with every closure stacked is found
#: in the null space of the closure rows (:func:`_actuation_all`), not from the stacked
#: rows (the same wrench; below it, the stacked rows are the smaller problem).
REDUCE_ROWS = 6


class Layout(NamedTuple):
    """What the compiled analysis reads of one closure model, made once per model.

    ``loop_rows[k]``: 1 at the closure rows of the loops whose tree path contains
    actuated joint ``k`` (:func:`pkm_pin.linkage._loops_of_actuators`);
    ``out_support``: 1 at the velocity coordinates that move the output frame."""

    kernel: TreeKernel
    out_support: np.ndarray  # (nv,)
    loop_rows: np.ndarray  # (na, n_rows)
    act_v: np.ndarray  # (na,)
    units: np.ndarray  # (nv,)
    length: float
    point_output: bool
    act_translating: np.ndarray  # (na,) bool: the actuated joint is prismatic
    triples: np.ndarray  # (m, 3) revolute triples that may lock (:func:`revolute_triples`)


class Core(NamedTuple):
    """The numbers of one analysis (both paths), before the result objects are made.

    ``kin``: the kinematics (:class:`~pkm_pin.model.closure_model.TreeKinematics`, or
    :class:`LazyKinematics`); ``ns``: the null space (``NullSpace`` or
    :class:`CompiledNullSpace`); ``p``: the point screws are homogenised about;
    ``d``: the output DOF; ``twists``, ``wrenches``: the output twist and constraint
    wrench bases (world origin, orthonormal once homogenised about ``p``);
    ``A`` (na × 6), ``B`` (na × na); ``Xr``, ``Yr``, ``M``: the reduced maps of
    :class:`~pkm_pin.linkage.LinkageAnalysis`."""

    kin: object
    ns: object
    p: np.ndarray
    d: int
    rotations: int
    twists: np.ndarray
    wrenches: np.ndarray
    A: np.ndarray
    B: np.ndarray
    type_I: float
    type_II: float
    condition: float
    Xr: np.ndarray
    Yr: np.ndarray
    M: np.ndarray
    forward: float
    inverse: float
    translating: np.ndarray  # (na,) whether each actuated joint translates (prismatic)
    #: (m,) whether each of :func:`revolute_triples` is at a gimbal lock (``None``:
    #: not decided here, :func:`pkm_pin.linkage._representation` decides)
    locked: np.ndarray | None = None
    #: whether a coordinate may be at a limit (``False``: none is within
    #: :data:`~pkm_pin.tolerances.JOINT_LIMIT_SLACK` of one; ``None``: not decided here)
    near_limit: bool | None = None


class LazyKinematics:
    """``q`` now; the Pinocchio :class:`~pkm_pin.model.closure_model.TreeKinematics` at
    ``q`` made on first use of any other attribute (idle motions described in words,
    gimbal locks tested: rarely per pose)."""

    def __init__(self, model, q: np.ndarray):
        self.q = q
        self._model = model
        self._kin = None

    def __getattr__(self, name: str):
        if name.startswith("__") or name in ("_kin", "_model"):
            raise AttributeError(name)
        if self._kin is None:
            self._kin = self._model.kinematics(self.q)
        return getattr(self._kin, name)


class CompiledNullSpace:
    """:class:`~pkm_pin.model.closure_model.NullSpace`'s attributes and methods from the
    compiled call (``idle`` and ``rank_x`` precomputed at ``rtol``)."""

    def __init__(self, rank, N, X, Y_world, units, rtol, rank_x, idle_span):
        self.rank, self.N, self.X, self.Y_world, self.units = rank, N, X, Y_world, units
        self._rtol, self._rank_x, self._idle_span = rtol, rank_x, idle_span

    def idle(self, rtol: float) -> np.ndarray:
        """As ``NullSpace.idle``."""
        if rtol != self._rtol:
            rank_x, _, _, Vt = screws.svd_rank(self.X, rtol)
            return sparse_basis(self.N @ Vt[rank_x:].T)
        return sparse_basis(self._idle_span)

    def rank_x(self, rtol: float) -> int:
        """As ``NullSpace.rank_x``."""
        return self._rank_x if rtol == self._rtol else screws.svd_rank(self.X, rtol)[0]


@functools.lru_cache(maxsize=64)
def revolute_triples(model) -> np.ndarray:
    """(m × 3) joint indices ``(p, j, c)`` of three consecutive revolute joints of the
    tree (``p`` the parent of ``j``, ``j`` of ``c``; 1-DOF joints counted in radians)
    whose axes meet at one point (``j`` and ``c`` placed without offset: three
    revolutes standing for a spherical joint): where a gimbal lock, a representation
    singularity, can occur (axes that meet elsewhere make a real singularity of the
    linkage, not one of its description). Read-only; cached per model."""
    tree, U = model.tree, model.velocity_units
    tiny = 1e-12 * model.length

    def revolute(j):
        joint = tree.joints[j]
        return j > 0 and joint.nq == joint.nv == 1 and U[joint.idx_v] == 1.0

    def centred(j):
        return np.linalg.norm(tree.jointPlacements[j].translation) <= tiny

    out = [(tree.parents[tree.parents[c]], tree.parents[c], c) for c in range(1, tree.njoints)
           if revolute(c) and revolute(tree.parents[c])
           and revolute(tree.parents[tree.parents[c]])
           and centred(c) and centred(tree.parents[c])]
    triples = np.array(out, dtype=int).reshape(-1, 3)
    triples.setflags(write=False)
    return triples


_LAYOUTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def layout(model, loops: tuple) -> Layout | None:
    """The :class:`Layout` of ``model`` (``loops``: the closures of each actuated
    joint's loops), made once per model; ``None`` when its tree is not compiled."""
    if model in _LAYOUTS:
        return _LAYOUTS[model]
    k = tree_kernel(model)
    out = None
    if k is not None:
        plan = model._plan
        out_support = plan.support[-1].astype(float)
        loop_rows = np.zeros((len(loops), plan.n_rows))
        for a, chosen in enumerate(loops):
            for c in chosen:
                loop_rows[a, plan.slices[c]] = 1.0
        joints = [model.tree.getJointId(name) for name in model.actuated]
        out = Layout(k, out_support, loop_rows, np.array(plan.act_v, np.int64),
                     np.array(model.velocity_units, float), float(model.length),
                     bool(model.output_point),
                     np.array([k.kind[j] == PRISMATIC for j in joints], dtype=bool),
                     np.ascontiguousarray(revolute_triples(model), dtype=np.int64))
    _LAYOUTS[model] = out
    return out


def analysis_core(model, loops: tuple, q: np.ndarray, about_output: bool,
                  rtol: float) -> Core | None:
    """The :class:`Core` of the analysis of ``model`` at the checked configuration
    ``q`` (compiled), or ``None`` where this module does not apply (:data:`ENABLED`
    off, a tree the compiled kernel does not represent)."""
    lay = layout(model, loops) if ENABLED else None
    if lay is None:
        return None
    q = np.ascontiguousarray(q, dtype=float)
    (rank, N, X, Yw, rank_x, idle_span, p, d, rotations, twists, wrenches, A, B, type_I,
     type_II, cond, Xr, Yr, M, forward, inverse, locked,
     near_limit) = _ANALYSE(lay, q, bool(about_output), float(rtol))
    ns = CompiledNullSpace(rank, N, X, Yw, model.velocity_units, rtol, rank_x, idle_span)
    return Core(LazyKinematics(model, q), ns, p, d, rotations, twists, wrenches, A,
                np.diag(B), type_I, type_II, cond, Xr, Yr, M, forward, inverse,
                lay.act_translating.copy(), locked, near_limit)


# ============================================================ compiled algebra
@register_jitable
def _svd_rank(H, rtol):
    """:func:`pkm_pin.screws.svd_rank`: ``(rank, U, sv, Vt)``, full matrices."""
    m, n = H.shape
    if m == 0 or n == 0:
        return 0, np.eye(m), np.zeros(0), np.eye(n)
    U, sv, Vt = np.linalg.svd(np.ascontiguousarray(H), True)
    U, Vt = np.ascontiguousarray(U), np.ascontiguousarray(Vt)
    rank = 0
    if sv[0] > 0:
        for s in sv:
            if s > rtol * sv[0]:
                rank += 1
    return rank, U, sv, Vt


@register_jitable
def _singular_values(H):
    """The ``min(m, n)`` singular values of ``H`` (m × n), largest first (none without
    rows or columns): a one-sided Jacobi SVD (:func:`pkm_pin.engine.linalg.jacobi`) of
    ``H`` or ``Hᵀ``, whichever has fewer columns (accurate to round-off, as LAPACK's)."""
    m, n = H.shape
    if m == 0 or n == 0:
        return np.zeros(0)
    X = np.ascontiguousarray(H) if n <= m else np.ascontiguousarray(H.T)
    r, c = X.shape
    V, W, sv = np.eye(c), np.empty((r, c)), np.empty(c)
    jacobi(X, r, c, W, V, sv, JACOBI_TOL)  # values only: no polishing of the bases
    return -np.sort(-sv)


@register_jitable
def _jacobi_sorted(H):
    """One-sided Jacobi SVD of ``H`` (m × n, :func:`pkm_pin.engine.linalg.jacobi`):
    ``(sv, V, W)`` with ``H V = W``, ``|W_j| = sv[j]``, columns sorted by ``sv``
    descending (as LAPACK's ``Vt.T`` and ``U Σ``, up to the bases of repeated values)."""
    m, n = H.shape
    V, W, sv = np.eye(n), np.empty((m, n)), np.empty(n)
    if n == 0:
        return sv, V, W
    X = np.ascontiguousarray(H)
    if m > 0:
        jacobi(X, m, n, W, V, sv)
    else:
        sv[:] = 0.0
    order = np.argsort(-sv, kind="mergesort")
    return sv[order], np.ascontiguousarray(V[:, order]), np.ascontiguousarray(W[:, order])


@register_jitable
def _rank_of(sv, rtol):
    """:func:`pkm_pin.screws.svd_rank`'s rule on singular values sorted descending."""
    rank = 0
    if sv.shape[0] and sv[0] > 0:
        for s in sv:
            if s > rtol * sv[0]:
                rank += 1
    return rank


@register_jitable
def _householder(A, first):
    """``(Q₂, R)``: ``A = Q R`` (m × n, m ≥ n) by Householder reflections, ``R`` upper
    triangular (m × n), ``Q₂`` the columns ``first …`` of the orthogonal ``Q`` (from
    ``n``: an orthonormal basis of the complement of ``A``'s columns, from 0 the first
    ``n`` a basis of them, where ``A`` has full rank)."""
    m, n = A.shape
    R, refl, vvs = A.copy(), np.zeros((n, m)), np.zeros(n)
    for k in range(min(m - 1, n)):
        s = 0.0
        for i in range(k, m):
            s += R[i, k] * R[i, k]
        if s == 0.0:
            continue
        alpha = -math.sqrt(s) if R[k, k] >= 0.0 else math.sqrt(s)
        vv = 0.0
        for i in range(k, m):
            refl[k, i] = R[i, k]
        refl[k, k] -= alpha
        for i in range(k, m):
            vv += refl[k, i] * refl[k, i]
        vvs[k] = vv
        for j in range(k, n):
            f = 0.0
            for i in range(k, m):
                f += refl[k, i] * R[i, j]
            f *= 2.0 / vv
            for i in range(k, m):
                R[i, j] -= f * refl[k, i]
    Q2 = np.zeros((m, m - first))
    for j in range(m - first):
        Q2[first + j, j] = 1.0
    for k in range(min(m - 1, n) - 1, -1, -1):  # Q₂ = H₀ H₁ … E: the last one first
        if vvs[k] == 0.0:
            continue
        for j in range(m - first):
            f = 0.0
            for i in range(k, m):
                f += refl[k, i] * Q2[i, j]
            f *= 2.0 / vvs[k]
            for i in range(k, m):
                Q2[i, j] -= f * refl[k, i]
    return Q2, R


@register_jitable
def _surely_full_rank(R, n, rtol):
    """Whether the leading ``n × n`` upper triangle of ``R`` (the QR factor of a matrix
    with ``n`` columns) certainly has every singular value above ``rtol`` times the
    largest (:func:`pkm_pin.screws.svd_rank`'s full rank): ``1 / |R⁻¹|_F > rtol |R|_F``
    bounds ``σ_min > rtol σ_max`` from the safe side (``False``: not decided here)."""
    fro = 0.0
    for i in range(n):
        if R[i, i] == 0.0:
            return False
        for j in range(i, n):
            fro += R[i, j] * R[i, j]
    inv, x = 0.0, np.empty(n)
    for c in range(n):  # column c of R⁻¹ by back substitution
        for i in range(n - 1, -1, -1):
            s = 1.0 if i == c else 0.0
            for j in range(i + 1, n):
                s -= R[i, j] * x[j]
            x[i] = s / R[i, i]
            inv += x[i] * x[i]
    return inv > 0.0 and 1.0 / math.sqrt(inv) > rtol * math.sqrt(fro)


@register_jitable
def _mm(A, B):
    """``A B`` (small matrices, any sizes, no BLAS call)."""
    out = np.zeros((A.shape[0], B.shape[1]))
    for i in range(A.shape[0]):
        for j in range(B.shape[1]):
            s = 0.0
            for k in range(A.shape[1]):
                s += A[i, k] * B[k, j]
            out[i, j] = s
    return out


@register_jitable
def _mv(A, x):
    """``A x`` (small matrix, vector)."""
    out = np.zeros(A.shape[0])
    for i in range(A.shape[0]):
        s = 0.0
        for k in range(A.shape[1]):
            s += A[i, k] * x[k]
        out[i] = s
    return out


@register_jitable
def _norm(x):
    s = 0.0
    for v in x:
        s += v * v
    return math.sqrt(s)


@register_jitable
def _homogenised_rows(S, p, L):
    """:func:`pkm_pin.screws.homogenised_about` of the rows of ``S`` (k × 6)."""
    H = S.copy()
    for i in range(S.shape[0]):
        a0, a1, a2 = S[i, 0], S[i, 1], S[i, 2]
        H[i, 3] = (S[i, 3] + a1 * p[2] - a2 * p[1]) / L
        H[i, 4] = (S[i, 4] + a2 * p[0] - a0 * p[2]) / L
        H[i, 5] = (S[i, 5] + a0 * p[1] - a1 * p[0]) / L
    return H


@register_jitable
def _swap_halves(S):
    """``S Δ`` (columns ``(a; b)`` → ``(b; a)``) of rows ``S`` (k × 6)."""
    out = np.empty_like(S)
    out[:, :3] = S[:, 3:]
    out[:, 3:] = S[:, :3]
    return out


@register_jitable
def _jacobians(lay, q):
    """Closure Jacobian (n_rows × nv), output Jacobian (6 × nv, axis-first, world
    origin; a point's ``(0; v_p)``), the joint twists (6 × nv) and the output
    placement (4 × 4), as :class:`~pkm_pin.model.closure_model.TreeKinematics`."""
    k = lay.kernel
    nv, n = k.nv, k.rows[k.rows.shape[0] - 1]
    ws = workspace(k)
    e, Jc = np.empty(n), np.empty((n, nv))
    norms, oMo = np.empty(k.ckind.shape[0]), np.empty((4, 4))
    closure_rows(k, q, ws, e, Jc, norms, oMo)
    S = ws.S.copy()
    Jo = np.empty((6, nv))
    for c in range(nv):
        for r in range(6):
            Jo[r, c] = S[r, c] * lay.out_support[c]
        if lay.point_output:  # the origin's velocity v_O + ω × p
            wx, wy, wz = Jo[0, c], Jo[1, c], Jo[2, c]
            px, py, pz = oMo[0, 3], oMo[1, 3], oMo[2, 3]
            Jo[3, c] += wy * pz - wz * py
            Jo[4, c] += wz * px - wx * pz
            Jo[5, c] += wx * py - wy * px
            Jo[0, c], Jo[1, c], Jo[2, c] = 0.0, 0.0, 0.0
    return Jc, Jo, S, oMo, ws.oMi


@register_jitable
def _gimbal_locked(triples, iv, S, oMi, L):
    """``linkage._representation``'s gimbal-lock test of each revolute triple ``(p, j,
    c)``: the unit homogenised twists of ``p`` and ``c`` about ``j``'s origin agree up
    to sign (:data:`~pkm_pin.tolerances.GIMBAL_LOCK_RTOL`) while ``j``'s does not."""
    m = triples.shape[0]
    out = np.zeros(m, np.bool_)
    T = np.empty((3, 6))
    for t in range(m):
        j = triples[t, 1]
        centre = np.array([oMi[j, 0, 3], oMi[j, 1, 3], oMi[j, 2, 3]])
        for a in range(3):
            T[a] = np.ascontiguousarray(S[:, iv[triples[t, a]]])
        H = _homogenised_rows(T, centre, L)
        for a in range(3):
            H[a] /= _norm(H[a])
        out[t] = _apart(H[0], H[2]) <= GIMBAL_LOCK_RTOL < _apart(H[1], H[0])
    return out


@register_jitable
def _near_limit(lower, upper, q):
    """Whether a coordinate is within :data:`~pkm_pin.tolerances.JOINT_LIMIT_SLACK` of
    its limit (``linkage._at_limits``'s test, before it names the joints)."""
    for i in range(q.shape[0]):
        if abs(q[i] - lower[i]) <= JOINT_LIMIT_SLACK \
                or abs(q[i] - upper[i]) <= JOINT_LIMIT_SLACK:
            return True
    return False


@register_jitable
def _apart(a, b):
    """``min(|a − b|, |a + b|)``."""
    return min(_norm(a - b), _norm(a + b))


@register_jitable
def _null_space(Jc, Jo, units, act_v, rtol):
    """``NullSpace``: rank, ``N``, ``X``, ``Y_world``; then the rank of ``X`` and the
    orthonormal span of the idle motions (``NullSpace.idle`` before its sparse basis)."""
    nv = Jc.shape[1]
    H = Jc.copy()
    for c in range(nv):
        H[:, c] *= units[c]
    rank, N = _kernel_basis(H, rtol)
    X = np.empty((act_v.shape[0], N.shape[1]))
    for a in range(act_v.shape[0]):
        X[a] = N[act_v[a]]
    UN = N.copy()
    for c in range(nv):
        UN[c] *= units[c]
    Yw = _mm(Jo, UN)
    if _surely_full_column_rank(X, rtol):  # no idle motion
        return rank, N, X, Yw, X.shape[1], np.zeros((nv, 0))
    sv, Vx, _ = _jacobi_sorted(X)
    rank_x = _rank_of(sv, rtol)
    idle = _mm(N, np.ascontiguousarray(Vx[:, rank_x:]))
    return rank, N, X, Yw, rank_x, idle


@register_jitable
def _surely_full_column_rank(A, rtol):
    """Whether ``A`` (m × n, m ≥ n ≥ 1) surely has rank ``n`` by :func:`_svd_rank`'s
    rule (:func:`_surely_full_rank` of its QR factor; ``False``: not decided here)."""
    m, n = A.shape
    if n == 0 or m < n:
        return False
    _, R = _householder(np.ascontiguousarray(A), m)
    return _surely_full_rank(R, n, rtol)


@register_jitable
def _kernel_basis(H, rtol):
    """``(rank, N)``: the rank of ``H`` (:func:`_svd_rank`'s rule) and an orthonormal
    basis ``N`` of its null space. Where ``H`` (r × c, r ≤ c) surely has full row rank
    (:func:`_surely_full_rank`), the last columns of the QR factor ``Q`` of ``Hᵀ``
    (the generic case, a few µs); else LAPACK's SVD."""
    r, c = H.shape
    if r <= c:
        Q2, R = _householder(np.ascontiguousarray(H.T), r)
        if _surely_full_rank(R, r, rtol):
            return r, Q2
    rank, _, _, Vt = _svd_rank(H, rtol)
    return rank, np.ascontiguousarray(Vt[rank:].T)


@register_jitable
def _twist_system(Yw, p, L, rtol):
    """Homogenised output twists ``Y_h`` (6 × dof), the output DOF ``d``, the
    orthonormal twist basis ``P_h`` (d × 6), its rotations and the reciprocal wrench
    basis ``C_h`` ((6 − d) × 6)."""
    Yh = np.ascontiguousarray(_homogenised_rows(np.ascontiguousarray(Yw.T), p, L).T)
    if Yh.shape[1] == 6:  # six motions: surely spanning every twist, no wrench left
        _, R = _householder(Yh, 6)
        if _surely_full_rank(R, 6, rtol):
            P_h = np.eye(6)  # an orthonormal basis of all twists
            return Yh, 6, 3, P_h, np.zeros((0, 6))
    d, Uy, _, _ = _svd_rank(Yh, rtol)
    P_h = np.ascontiguousarray(Uy[:, :d].T)
    rotations = 0
    for s in _singular_values(P_h[:, :3]):
        if s > ROTATION_COUNT_TOL:
            rotations += 1
    _, _, _, Vc = _svd_rank(_swap_halves(P_h), rtol)
    return Yh, d, rotations, P_h, np.ascontiguousarray(Vc[d:])


@register_jitable
def _stacked(Jc, units, mask, Ho):
    """``G``: the closure rows where ``mask`` (times the units), then ``H_o``."""
    n = 0
    for r in range(mask.shape[0]):
        if mask[r] > 0:
            n += 1
    nv = Jc.shape[1]
    G = np.empty((n + 6, nv))
    i = 0
    for r in range(mask.shape[0]):
        if mask[r] > 0:
            for c in range(nv):
                G[i, c] = Jc[r, c] * units[c]
            i += 1
    G[n:] = Ho
    return G


@register_jitable
def _actuation_row(G, col, rtol):
    """``linkage._actuation_row``: the homogenised ζ with ``β = 1`` orthogonal to the
    admissible ζ with β = 0, and whether there is one. The admissible ``w`` span the
    left null space of the other columns (:func:`_left_null`)."""
    m = G.shape[0]
    W = _left_null(G, col, rtol)
    g = np.ascontiguousarray(G[:, col])
    b = _mv(W, g)
    if _norm(b) <= rtol * max(_norm(g), 1e-300):
        return np.zeros(6), False
    ZT = np.ascontiguousarray(_swap_halves(W[:, m - 6:]).T)  # 6 × rows of W
    return _least_wrench(ZT, b, rtol)


@register_jitable
def _least_wrench(ZT, b, rtol):
    """The least ζ = ``Zᵀ y`` with ``β = bᵀ y = 1``, and whether it is not zero (zero:
    the closures alone hold the actuated rate, no wrench on the output carries it)."""
    y0 = b / np.sum(b * b)
    zeta = _least_on_plane(ZT, b, y0, rtol)
    return zeta, _norm(zeta) > rtol * _norm(y0)


@register_jitable
def _left_null(G, col, rtol):
    """Orthonormal rows spanning the ``w`` with ``w G_j = 0`` for every column ``j`` but
    ``col`` (:func:`_svd_rank`'s rank rule). Columns of zeros are left out (they hold
    nothing); where the other columns (m × k, k ≤ m) surely have full rank
    (:func:`_surely_full_rank`), the last ``m − k`` columns of their QR factor ``Q``;
    else LAPACK's SVD."""
    m, nv = G.shape
    keep = np.zeros(nv, np.bool_)
    k = 0
    for c in range(nv):
        if c != col:
            for r in range(m):
                if G[r, c] != 0.0:
                    keep[c] = True
                    k += 1
                    break
    others = np.empty((m, k))
    i = 0
    for c in range(nv):
        if keep[c]:
            others[:, i] = G[:, c]
            i += 1
    if k <= m:
        Q2, R = _householder(others, k)
        if _surely_full_rank(R, k, rtol):
            return np.ascontiguousarray(Q2.T)
    rank, Ul, _, _ = _svd_rank(others, rtol)
    return np.ascontiguousarray(Ul[:, rank:].T)


@register_jitable
def _actuation_all(x_a, Yh, rtol):
    """:func:`_actuation_row` with every closure stacked, in the null space ``N`` of
    the closure rows: ``w_c J_c + w_o H_o = β e_a`` has a ``w_c`` exactly when
    ``(β e_a − w_o H_o) N = 0``, i.e. ``Y_hᵀ w_o = β x_a`` (``Y_h = H_o N`` the
    homogenised output twists, ``x_a = N[a]`` the actuated rates of the motions), so the
    admissible ``(w_o, β)`` are the null space of ``(Y_hᵀ | −x_a)`` (dof × 7) and the
    least ζ with β = 1 is the same (to round-off). Used where more than 6 closure
    rows are stacked (:data:`REDUCE_ROWS`): there the QR of the stacked rows costs more
    than this dof × 7 system."""
    dof = Yh.shape[1]
    K = np.empty((dof, 7))
    for j in range(dof):
        for r in range(6):
            K[j, r] = Yh[r, j]
        K[j, 6] = -x_a[j]
    rank, Wt = _kernel_basis(K, rtol)
    W = np.ascontiguousarray(Wt.T)  # rows (w_o; β), orthonormal
    b = np.ascontiguousarray(W[:, 6])
    if _norm(b) <= rtol:
        return np.zeros(6), False
    ZT = np.ascontiguousarray(_swap_halves(np.ascontiguousarray(W[:, :6])).T)
    return _least_wrench(ZT, b, rtol)


@register_jitable
def _least_on_plane(ZT, b, y0, rtol):
    """The least ``Zᵀ y`` over ``y`` with ``bᵀ y = 1`` (``y0`` one of them): ``Zᵀ y0``
    less its projection on the range of ``Zᵀ (I − b bᵀ / bᵀb)`` — numpy's
    ``lstsq(Zᵀ N_b, −Zᵀ y0, rcond=rtol)`` with ``N_b`` an orthonormal basis of ``b⊥``:
    the same range and nonzero singular values, from a one-sided Jacobi SVD
    (:func:`pkm_pin.engine.linalg.jacobi`), those ≤ ``rtol`` times the largest dropped.
    The result does not depend on the basis ``N_b`` (the least point of an affine set)."""
    rows, nb = ZT.shape
    r0 = _mv(ZT, y0)
    if nb == 1:  # b⊥ = {0}
        return r0
    Zb = _mv(ZT, b)
    bb = np.sum(b * b)
    Ap = ZT.copy()
    for i in range(rows):
        for j in range(nb):
            Ap[i, j] -= Zb[i] * b[j] / bb
    V, W, sv = np.eye(nb), np.empty((rows, nb)), np.empty(nb)
    jacobi(Ap, rows, nb, W, V, sv)
    top = largest(sv, nb)
    for j in range(nb):
        if sv[j] > rtol * top:
            c = 0.0
            for i in range(rows):
                c += W[i, j] * r0[i]
            c /= sv[j] * sv[j]
            for i in range(rows):
                r0[i] -= c * W[i, j]
    return r0


@register_jitable
def _scaled_wrench(zeta, p, L, unit, rtol):
    """``linkage._scaled_wrench``: the world wrench (unit force, or unit moment) and
    ``B`` from the homogenised ζ."""
    f, m_p = zeta[:3].copy(), zeta[3:] * L
    nf, nm = _norm(f), _norm(m_p)
    s = nf if nf * L > rtol * nm else nm
    w = np.empty(6)
    w[:3] = f / s
    w[3] = (m_p[0] + f[1] * -p[2] - f[2] * -p[1]) / s
    w[4] = (m_p[1] + f[2] * -p[0] - f[0] * -p[2]) / s
    w[5] = (m_p[2] + f[0] * -p[1] - f[1] * -p[0]) / s
    return w, L / unit / s


@register_jitable
def _actuation(lay, Jc, Jo, S, p, rtol, X, Yh):
    """``linkage._actuation``: ``A`` (na × 6, world origin), the diagonal of ``B`` and
    the type I index (every closure stacked, beyond :data:`REDUCE_ROWS` rows: in the
    null space, :func:`_actuation_all`, from its ``X`` and ``Y_h``)."""
    L, units, act_v = lay.length, lay.units, lay.act_v
    Ho = np.ascontiguousarray(_homogenised_rows(np.ascontiguousarray(Jo.T), p, L).T)
    for c in range(Ho.shape[1]):
        Ho[:, c] *= units[c]
    na = act_v.shape[0]
    every = np.ones(Jc.shape[0])
    A, B, type_I = np.zeros((na, 6)), np.zeros(na), np.inf
    for k in range(na):
        col = act_v[k]
        rows = lay.loop_rows[k]
        if np.all(rows > 0) and rows.shape[0] > REDUCE_ROWS:
            zeta, ok = _actuation_all(X[k], Yh, rtol)
        else:
            zeta, ok = _actuation_row(_stacked(Jc, units, rows, Ho), col, rtol)
        if not ok and not np.all(rows > 0):
            if every.shape[0] > REDUCE_ROWS:
                zeta, ok = _actuation_all(X[k], Yh, rtol)
            else:
                zeta, ok = _actuation_row(_stacked(Jc, units, every, Ho), col, rtol)
        if not ok:
            type_I = 0.0
            continue
        w, b = _scaled_wrench(zeta, p, L, units[col], rtol)
        A[k], B[k] = w, b
        twist = _homogenised_rows(np.ascontiguousarray(S[:, col]).reshape(1, 6), p, L)[0]
        a_h = _homogenised_rows(w.reshape(1, 6), p, L)[0]
        type_I = min(type_I, abs(b) / (L * _norm(a_h) * _norm(twist)))
    return A, B, type_I


@register_jitable
def _transmission(A, P_h, d, p, L):
    """``linkage._transmission`` (nan, nan where an actuation wrench is zero)."""
    n = A.shape[0]
    A_n = _homogenised_rows(A, p, L)
    for i in range(n):
        norm = _norm(A_n[i])
        if not norm > 0:
            return np.nan, np.nan
        A_n[i] /= norm
    if n == 0 or d == 0:
        return 0.0, np.inf
    sv = _singular_values(_mm(A_n, np.ascontiguousarray(_swap_halves(P_h).T)))
    t2 = sv[d - 1] if d <= n else 0.0
    return t2, (sv[0] / t2 if t2 > 0 else np.inf)


@register_jitable
def _generalised(N, X, Yh, rtol):
    """``linkage._generalised``: ``X_r``, ``Y_r``, ``M``, the forward and inverse
    indices."""
    n, dof = X.shape
    if dof == 0:
        return X.copy(), Yh.copy(), N.copy(), 1.0, 1.0
    S = np.empty((n + 6, dof))
    S[:n], S[n:] = X, Yh
    full = False
    if n + 6 >= dof:
        Q, R = _householder(S, 0)
        full = _surely_full_rank(R, dof, rtol)
    if full:  # every motion moves an actuator or the output
        m, Xr, Yr, M = dof, X.copy(), Yh.copy(), N.copy()
        Q = np.ascontiguousarray(Q[:, :m])  # an orthonormal basis of the columns of S
    else:
        sv, Vs, Ws = _jacobi_sorted(S)
        m = _rank_of(sv, rtol)
        V = np.ascontiguousarray(Vs[:, :m])
        M, Xr, Yr = _mm(N, V), _mm(X, V), _mm(Yh, V)
        if m == 0:
            return Xr, Yr, M, 1.0, 1.0
        Q = np.empty((n + 6, m))  # an orthonormal basis of the columns of (X_r; Y_r)
        for j in range(m):
            Q[:, j] = Ws[:, j] / sv[j]
    cx = _singular_values(Q[:n])
    cy = _singular_values(Q[n:])
    forward = cx[m - 1] if n >= m else 0.0
    inverse = cy[m - 1] if Yr.shape[0] >= m else 0.0
    return Xr, Yr, M, forward, inverse


@register_jitable
def _world(H, p, L):
    """:func:`pkm_pin.screws.from_homogenised` of the rows of ``H``."""
    S = H.copy()
    for i in range(H.shape[0]):
        a0, a1, a2 = H[i, 0], H[i, 1], H[i, 2]
        b0, b1, b2 = H[i, 3] * L, H[i, 4] * L, H[i, 5] * L
        S[i, 3] = b0 + a1 * -p[2] - a2 * -p[1]
        S[i, 4] = b1 + a2 * -p[0] - a0 * -p[2]
        S[i, 5] = b2 + a0 * -p[1] - a1 * -p[0]
    return S


@njit(cache=True, nogil=True)
def analyse_pose(lay, q, about_output, rtol):
    """The numbers of :func:`analysis_core` at ``q`` (compiled), in its order."""
    Jc, Jo, S, oMo, oMi = _jacobians(lay, q)
    L = lay.length
    locked = _gimbal_locked(lay.triples, lay.kernel.iv, S, oMi, L)
    near_limit = _near_limit(lay.kernel.lower, lay.kernel.upper, q)
    p = np.zeros(3)
    if about_output:
        p[0], p[1], p[2] = oMo[0, 3], oMo[1, 3], oMo[2, 3]
    rank, N, X, Yw, rank_x, idle = _null_space(Jc, Jo, lay.units, lay.act_v, rtol)
    Yh, d, rotations, P_h, C_h = _twist_system(Yw, p, L, rtol)
    A, B, type_I = _actuation(lay, Jc, Jo, S, p, rtol, X, Yh)
    type_II, cond = _transmission(A, P_h, d, p, L)
    Xr, Yr, M, forward, inverse = _generalised(N, X, Yh, rtol)
    return (rank, N, X, Yw, rank_x, idle, p, d, rotations, _world(P_h, p, L),
            _world(C_h, p, L), A, B, type_I, type_II, cond, Xr, Yr, M, forward, inverse,
            locked, near_limit)


def representation_flags(model, q: np.ndarray):
    """``(locked, near_limit)`` of :class:`Core` at the checked configuration ``q``
    without an analysis (for :func:`pkm_pin.linkage._representation` after a solve), or
    ``None`` where this module does not apply."""
    k = tree_kernel(model) if ENABLED else None
    if k is None:
        return None
    triples = revolute_triples(model)
    if not len(triples) and not _finite_limits(model, k):  # nothing to flag
        return _NO_LOCKS, False
    q = np.ascontiguousarray(q, dtype=float)
    locked, near = _FLAGS(k, np.ascontiguousarray(triples, dtype=np.int64), q,
                          float(model.length))
    return locked, bool(near)


_NO_LOCKS = np.zeros(0, np.bool_)
_NO_LOCKS.flags.writeable = False


def _finite_limits(model, k) -> bool:
    """Whether a coordinate of the compiled tree ``k`` of ``model`` has a finite limit
    (kept on the model, as :func:`~pkm_pin.tree_kernel.tree_kernel`)."""
    cached = model.__dict__.get("_finite_limits")
    if cached is None:
        cached = bool(np.isfinite(k.lower).any() or np.isfinite(k.upper).any())
        object.__setattr__(model, "_finite_limits", cached)
    return cached


@njit(cache=True, nogil=True)
def flags_at(k, triples, q, L):
    """The gimbal locks (:func:`_gimbal_locked`) and joint-limit proximity
    (:func:`_near_limit`) at ``q`` from the compiled tree ``k`` alone."""
    near = _near_limit(k.lower, k.upper, q)
    if triples.shape[0] == 0:  # no gimbal to lock: no tree pass
        return np.zeros(0, np.bool_), near
    oMi = np.empty((k.parent.shape[0], 4, 4))
    S = np.zeros((6, k.nv))
    tree_placements(k.parent, k.place, k.kind, k.axis, k.rate, k.iq, q, oMi)
    tree_twists(k.kind, k.iv, k.rate, k.axis, oMi, S)
    return _gimbal_locked(triples, k.iv, S, oMi, L), near


_FLAGS = SameTypes(flags_at, key=0, plain=True)


#: :func:`analyse_pose` as :func:`analysis_core` calls it: a model's layout is typed
#: once, later calls go straight to the machine code (:class:`SameTypes`); plain
#: Python until the code is ready.
_ANALYSE = SameTypes(analyse_pose, key=0, plain=True)
