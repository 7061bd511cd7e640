"""Motion/force transmission indices of parallel mechanisms (Wang, Wu & Liu 2010; Liu et
al. 2014), on arrays of screws: one definition for :class:`~pkm_pin.Analysis`,
:meth:`~pkm_pin.Mechanism.sweep` and the general linkages.

References (docs/indices.md): J. Wang, C. Wu, X.-J. Liu, "Performance evaluation of
parallel manipulators: motion/force transmissibility and its index", Mech. Mach. Theory
45 (2010) 1462–1476; X.-J. Liu, C. Wu, J. Wang, I. Bonev, "Motion/force
constrainability analysis of lower-mobility parallel manipulators", ASME J. Mech. Robot.
6 (2014) 011002; the pressure angle of Takeda & Funabashi (1995).

**Power coefficient.** A unit transmission wrench ``$_T`` (pitch ``h_T``) acting at a
point ``P`` of its axis on a body whose unit twist is ``$`` (pitch ``h``, axis at the
distance ``d`` and angle ``θ`` from the wrench's) develops the power ``$_T ∘ $ = (h_T +
h) cos θ − d sin θ``; the paper normalises it by its largest value over the wrench
directions, ``|$_T ∘ $|_max = √((h_T + h)² + d_max²)``, with ``d_max`` the potential
largest distance. We take the wrench's *application point* ``P`` as what fixes the
potential: ``d_max`` is the distance from ``P`` to the twist's axis, so that with
``u = v_P + h_T ω`` (the velocity of ``P`` plus ``h_T ω``)

    ``λ = |$_T ∘ $| / |$_T ∘ $|_max = |f · u| / (|f| |u|)``        (:func:`power_coefficient`)

— the cosine of the pressure angle at ``P`` for a pure force. A couple ``(0; m)`` gives
``|m · ω| / (|m| |ω|)``. ``λ`` is dimensionless, in [0, 1], does not depend on the scale
of either screw, on the units or on the frame, and is 0 exactly when the wrench does no
work on the twist (0 also when no direction of the wrench could: ``u = 0``).

**Indices** (per actuator ``i``, with ``$_Ti`` its actuation wrench, the row ``A_i``):

* ``ITI_i = λ($_Ti, $_Ii; P_in)``: against the twist ``$_Ii`` of the actuated joint, at
  the point where the force reaches the actuated link — the point of the wrench axis
  nearest to the axis of the first rotation joint after the actuator in its leg (the
  elbow of a five-bar, :func:`leg_points`). 0 exactly at a type I singularity
  (``B_ii = A_i ∘ $_Ii = 0``); 1 for a prismatic actuator pushing along its wrench.
* ``OTI_i = λ($_Ti, $_Oi; P_out)``: against the output twist ``$_Oi``, the platform
  twist when every other actuator is locked (reciprocal to every other ``A_j`` among
  the platform twists, :func:`output_twists`), at the point where the force reaches the
  platform (nearest to the leg's last rotation joint; the output point of a linkage).
  0 exactly at a type II singularity.
* ``LTI = min_i min(ITI_i, OTI_i)`` (local transmission index; ≥ 0.7: good transmission).
* ``CTI``: for a leg ``k`` with constraint wrenches ``C_k``, the twists ``R_k``
  reciprocal to every actuation wrench and to the other legs' constraints (what the
  platform could do without leg ``k``'s constraints): with one constraint wrench and
  one freed twist, ``λ(c, r; P_out)`` (Liu et al.'s constraint transmission index);
  otherwise the smallest singular value of ``Ĉ_k Δ R̂_kᵀ`` with both bases orthonormal
  once homogenised about the platform centre (the same index generalised to
  subspaces: 0 when a freed twist escapes the leg's constraints). A leg whose
  constraints cannot be lost alone (no freed twist, or no constraint) counts 1.
  :func:`constraint_transmission`.

Screws are rows, axis-first (:mod:`pkm_pin.screws`): twists ``(ω; v)``, wrenches
``(f; m)``, all about one common point (any: the indices do not depend on it; about the
platform centre keeps the numbers well conditioned).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import screws
from .errors import InputError
from .screws import DELTA, as_vector3
from .tolerances import RANK_RTOL

#: Relative size below which a screw part counts as zero when deciding couples and
#: translations and below which ``|u|`` counts as zero (no direction can do work).
ZERO_RTOL = 1e-12
#: ``|sin θ|`` between a wrench axis and a joint axis below which the two are parallel
#: (no unique nearest point): the next candidate joint is used (:func:`leg_points`);
#: also the sine of the principal angle below which a freed twist counts as one of the
#: motions free with every wrench (:func:`constraint_transmission`).
PARALLEL_SIN = 1e-6
#: LTI at or above this value: good transmission (Wang et al. 2010).
GOOD_LTI = 0.7


def _dot(a, b):
    return np.einsum("...k,...k->...", a, b)


def _cross(a, b):
    """``a × b`` over the last axis (broadcasting; faster than ``numpy.cross``)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def power_coefficient(wrench, twist, point, length: float) -> np.ndarray:
    """Power coefficient ``λ = |$_T ∘ $| / |$_T ∘ $|_max`` (module docstring).

    Args:
        wrench: (..., 6) wrenches ``(f; m)`` about a common point (any scale).
        twist: (..., 6) twists ``(ω; v)`` about the same point (any scale).
        point: (..., 3) application point of each wrench [m], same frame; projected onto
            the wrench's axis first (ignored for a couple).
        length: Characteristic length [m]: a wrench is a couple when ``|f| · length ≤
            1e-12 |m|``, a twist a translation when ``|ω| · length ≤ 1e-12 |v|``.

    Returns:
        (...) values in [0, 1].
    """
    W, T = np.asarray(wrench, float), np.asarray(twist, float)
    P = np.asarray(point, float)
    f, m, w, v = W[..., :3], W[..., 3:], T[..., :3], T[..., 3:]
    fn, mn = np.linalg.norm(f, axis=-1), np.linalg.norm(m, axis=-1)
    wn = np.linalg.norm(w, axis=-1)
    couple = fn * length <= ZERO_RTOL * mn
    ff = np.where(couple, 1.0, fn * fn)[..., None]
    P = screws.axis_point_nearest(W, P)  # onto the axis (not used for a couple)
    h = (_dot(f, m) / ff[..., 0])[..., None]
    u = v + _cross(w, P) + h * w
    un = np.linalg.norm(u, axis=-1)
    scale_u = np.linalg.norm(v, axis=-1) + wn * (length + np.linalg.norm(P, axis=-1))
    num = np.where(couple, np.abs(_dot(m, w)), np.abs(_dot(f, u)))
    den = np.where(couple, mn * wn, fn * un)
    dead = np.where(couple, wn * length <= ZERO_RTOL * np.linalg.norm(v, axis=-1),
                    un <= ZERO_RTOL * scale_u)
    dead |= (fn == 0) & (mn == 0)
    out = np.where(dead | (den == 0), 0.0, num / np.where(den == 0, 1.0, den))
    return np.clip(out, 0.0, 1.0)


def nearest_point(wrench, twist) -> tuple[np.ndarray, np.ndarray]:
    """The point of each wrench's axis nearest to each twist's axis, and ``|sin θ|``
    between the two axes (0 when the twist is a translation or the wrench a couple: no
    point; the point returned is then the wrench axis point nearest the origin).

    Args:
        wrench: (..., 6) wrenches ``(f; m)``; twist: (..., 6) twists ``(ω; v)``.

    Returns:
        ((..., 3) points [m], (...) sines).
    """
    W, T = np.asarray(wrench, float), np.asarray(twist, float)
    f, m, w, v = W[..., :3], W[..., 3:], T[..., :3], T[..., 3:]
    ff, ww = _dot(f, f), _dot(w, w)
    ok_f, ok_w = ff > 0, ww > 0
    d1 = f / np.sqrt(np.where(ok_f, ff, 1.0))[..., None]
    d2 = w / np.sqrt(np.where(ok_w, ww, 1.0))[..., None]
    p1 = _cross(f, m) / np.where(ok_f, ff, 1.0)[..., None]
    p2 = _cross(w, v) / np.where(ok_w, ww, 1.0)[..., None]
    n = _cross(d1, d2)
    nn = _dot(n, n)
    s = _dot(_cross(p2 - p1, d2), n) / np.where(nn > 0, nn, 1.0)
    sin = np.where(ok_f & ok_w, np.sqrt(nn), 0.0)
    return p1 + np.where(sin > 0, s, 0.0)[..., None] * d1, sin


def _is_rotation(T: np.ndarray, length: float) -> np.ndarray:
    return (np.linalg.norm(T[..., :3], axis=-1) * length
            > ZERO_RTOL * np.linalg.norm(T[..., 3:], axis=-1))


def leg_points(A, J, coords, act_col, act_leg, length: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """Application points of the actuation wrenches: on the actuated link and on the
    platform (module docstring).

    The input point is the point of ``A_i``'s axis nearest to the axis of the first
    rotation joint after the actuated one in its leg that is not parallel to it; the
    output point the one nearest to the leg's last such joint. A leg without one uses
    the point of the wrench axis nearest to the origin of the coordinates.

    Args:
        A: (..., n, 6) actuation wrenches; J: (..., nv, 6) joint twists of every leg, one
            leg after the other in chain order (base to tip), about the same point.
        coords: (legs + 1,) row offsets of the legs in ``J``; act_col: (n,) row of each
            actuated joint; act_leg: (n,) its leg.
        length: Characteristic length [m].

    Returns:
        ((..., n, 3) input points, (..., n, 3) output points).
    """
    A, J = np.asarray(A, float), np.asarray(J, float)
    batch = A.shape[:-2]
    p_in = np.empty(batch + (A.shape[-2], 3))
    p_out = np.empty_like(p_in)
    for a in range(A.shape[-2]):
        W = A[..., a, :]
        p0 = screws.axis_point_nearest(W, np.zeros(3))  # the fallback
        end = int(coords[int(act_leg[a]) + 1])
        rows = range(int(act_col[a]) + 1, end)
        for out, order in ((p_in, rows), (p_out, reversed(rows))):
            out[..., a, :] = p0
            found = np.zeros(batch, bool)
            for r in order:
                T = J[..., r, :]
                p, sin = nearest_point(W, T)
                take = ~found & _is_rotation(T, length) & (sin > PARALLEL_SIN)
                out[..., a, :] = np.where(take[..., None], p, out[..., a, :])
                found |= take
    return p_in, p_out


def output_twists(A, platform, length: float, rtol: float = RANK_RTOL) -> np.ndarray:
    """Output twist of each actuator: the platform twist when every other actuator is
    locked (reciprocal to every other row of ``A`` among the rows of ``platform``).

    Args:
        A: (..., n, 6) actuation wrenches; platform: (..., d, 6) a basis of the platform
            twists; both about the same point, world units.
        length: Characteristic length [m] (homogenising for the rank decisions).
        rtol: Relative tolerance of the rank decisions.

    Returns:
        (..., n, 6) twists (unit once homogenised). A zero row when locking the others
        leaves more than one twist (the others dependent, or fewer actuators than
        degrees of freedom: that space holds a twist on which ``A_i`` does no work, so
        the OTI is 0); nan rows when it leaves none (redundant actuation).
    """
    A, P = np.asarray(A, float), np.asarray(platform, float)
    n, d = A.shape[-2], P.shape[-2]
    Ah = screws.homogenise(A, length)
    Ah = Ah / np.maximum(np.linalg.norm(Ah, axis=-1, keepdims=True), 1e-300)
    Ph = screws.homogenise(P, length)
    Q = np.linalg.qr(np.swapaxes(Ph, -1, -2))[0]  # (..., 6, d) orthonormal columns
    M = Ah @ DELTA @ Q  # (..., n, d)
    if n == d and n > 1:
        return _adjugate_twists(M, Q, length, rtol)
    out = np.full(A.shape, np.nan)
    for i in range(n):
        others = np.delete(M, i, axis=-2)
        if others.shape[-2] == 0:
            X = np.broadcast_to(np.eye(d), M.shape[:-2] + (d, d))
            null = np.full(M.shape[:-2], d)
        else:
            _, sv, Vt = np.linalg.svd(others, full_matrices=True)
            big = sv[..., :1] if sv.shape[-1] else np.zeros(M.shape[:-2] + (1,))
            rank = np.sum(sv > rtol * big, axis=-1)
            null = d - rank
            X = np.swapaxes(Vt, -1, -2)  # columns: right singular vectors
        x = X[..., :, -1]  # the last right singular vector
        t = screws.dehomogenise(np.einsum("...kd,...d->...k", Q, x), length)
        t = np.where((null == 1)[..., None], t, np.where((null > 1)[..., None], 0.0, np.nan))
        out[..., i, :] = t
    return out


def _adjugate_twists(M, Q, length: float, rtol: float) -> np.ndarray:
    """:func:`output_twists` for as many actuators as DOF: column ``i`` of the adjugate
    of ``M`` (reciprocal to every other row, continuous through singularities) from one
    SVD, ``adj M = det(U Vᵀ) V diag(Π_{j≠k} σ_j) Uᵀ``; zero where two singular values
    vanish (the others then leave more than one twist)."""
    U, sv, Vt = np.linalg.svd(M)
    n = sv.shape[-1]
    big = np.maximum(sv[..., :1], 1e-300)
    r = sv / big
    prod = np.stack([np.prod(np.delete(r, k, axis=-1), axis=-1) for k in range(n)], -1)
    sign = np.linalg.det(U) * np.linalg.det(Vt)
    adj = np.einsum("...kd,...k,...ik->...id", Vt, prod, U) * sign[..., None, None]
    adj = np.where((r[..., -2] <= rtol)[..., None, None], 0.0, adj)
    T = np.einsum("...ed,...id->...ie", Q, adj)  # row i: column i of adj, as a twist
    T = T / np.maximum(np.linalg.norm(T, axis=-1, keepdims=True), 1e-300)
    return screws.dehomogenise(T, length)


def transmission_indices(A, input_twists, platform, input_points, output_points,
                         length: float, rtol: float = RANK_RTOL
                         ) -> tuple[np.ndarray, np.ndarray]:
    """ITI and OTI of every actuator (module docstring).

    Args:
        A: (..., n, 6) actuation wrenches (rows of A); input_twists: (..., n, 6) the
            twists of the actuated joints; platform: (..., d, 6) a basis of the platform
            (output) twists; all about one common point, world units.
        input_points, output_points: (..., n, 3) application points of each wrench on
            the actuated link and on the platform (:func:`leg_points`; for a linkage
            with a point output, the output point).
        length: Characteristic length [m]; rtol: relative tolerance of rank decisions.

    Returns:
        ((..., n) ITI, (..., n) OTI): OTI is 0 where locking the other actuators leaves
        several twists (type II, or too few actuators), nan where it leaves none
        (redundant actuation).
    """
    A = np.asarray(A, float)
    iti = power_coefficient(A, input_twists, input_points, length)
    T = output_twists(A, platform, length, rtol)
    oti = power_coefficient(A, np.nan_to_num(T), output_points, length)
    oti = np.where(np.isnan(T[..., 0]), np.nan, oti)
    return iti, oti


def local_transmission_index(iti, oti) -> np.ndarray:
    """``LTI = min_i min(ITI_i, OTI_i)`` over the last axis (nan when there are no
    actuators; the nan OTIs of redundant actuation are skipped)."""
    both = np.concatenate([np.asarray(iti, float), np.asarray(oti, float)], axis=-1)
    if both.shape[-1] == 0:
        return np.full(both.shape[:-1], np.nan)
    low = np.where(np.isnan(both), np.inf, both).min(axis=-1)
    return np.where(np.isinf(low), np.nan, low)


def _orthonormal_rows(H: np.ndarray, rtol: float) -> tuple[np.ndarray, np.ndarray]:
    """An orthonormal basis of the span of the (homogenised) rows of each ``H`` (...,
    m, 6), rank by ``rtol`` relative to the largest singular value once every row that
    is not negligible (``|row| > 1e-12 max |row|``) has unit norm.

    Returns:
        ((..., 6, 6) rows: the basis first, zero rows after it; (...) ranks).
    """
    batch = H.shape[:-2]
    if H.shape[-2] == 0:
        return np.zeros(batch + (6, 6)), np.zeros(batch, int)
    n = np.linalg.norm(H, axis=-1)
    keep = n > ZERO_RTOL * n.max(axis=-1, keepdims=True)
    Hn = np.where(keep[..., None], H / np.where(keep, n, 1.0)[..., None], 0.0)
    _, sv, Vt = np.linalg.svd(Hn, full_matrices=False)  # (..., min(m, 6), 6)
    rank = np.sum(sv > rtol * sv[..., :1], axis=-1)
    if Vt.shape[-2] < 6:
        Vt = np.concatenate([Vt, np.zeros(batch + (6 - Vt.shape[-2], 6))], axis=-2)
    return _first_rows(Vt, 0, rank), rank


def _first_rows(V: np.ndarray, start, stop) -> np.ndarray:
    """``V`` (..., 6, 6) with the rows outside ``start:stop`` (per matrix) zeroed."""
    r = np.arange(V.shape[-2])
    keep = (r >= np.asarray(start)[..., None]) & (r < np.asarray(stop)[..., None])
    return np.where(keep[..., None], V, 0.0)


def _reciprocal_rows(Wh: np.ndarray, rtol: float) -> tuple[np.ndarray, np.ndarray]:
    """An orthonormal basis of the homogenised twists reciprocal to the homogenised
    wrench rows ``Wh`` (..., m, 6) (zero rows allowed; all six twists when every row is
    zero), as ((..., 6, 6) rows, zero rows after the basis; (...) dimensions)."""
    batch = Wh.shape[:-2]
    if Wh.shape[-2] == 0:
        return np.broadcast_to(np.eye(6), batch + (6, 6)).copy(), np.full(batch, 6)
    _, sv, Vt = np.linalg.svd(Wh @ DELTA, full_matrices=Wh.shape[-2] < 6)
    rank = np.sum(sv > rtol * sv[..., :1], axis=-1)
    return _shift_up(Vt, rank), 6 - rank


def _shift_up(V: np.ndarray, by: np.ndarray) -> np.ndarray:
    """Rows ``by:`` of each ``V`` (..., 6, 6) moved to the top (zeros below)."""
    r = np.arange(V.shape[-2])
    src = np.minimum(r + np.asarray(by)[..., None], V.shape[-2] - 1)
    out = np.take_along_axis(V, src[..., None], axis=-2)
    return np.where((r + np.asarray(by)[..., None] < V.shape[-2])[..., None], out, 0.0)


def constraint_transmissions(A, leg_constraints, output_points, length: float,
                             rtol: float = RANK_RTOL, generic_rank: int | None = None
                             ) -> np.ndarray:
    """Constraint transmission index of every leg at N poses (module docstring;
    :func:`constraint_transmission` is this at one pose).

    The twists ``R_k`` freed by removing leg ``k``'s constraints are those reciprocal to
    every actuation wrench and to the other legs' constraints. While the union of the
    constraints keeps its ``generic_rank`` (no constraint singularity), the twists
    reciprocal to *every* wrench are left out of ``R_k``: they are the uncontrolled
    motions of a type II singularity, which the OTI reports, not a constraint that
    fails. Every span is decided on orthonormal rows (each leg's constraints first,
    then their union), rank by ``rtol`` relative to the largest singular value.

    Args:
        A: (N, n, 6) actuation wrenches; leg_constraints: (N, legs, K, 6) each leg's
            constraint wrenches (any spanning rows, zero rows as padding);
            output_points: (N, legs, 3) the point where each leg's constraint forces
            reach the platform; all about one common point per pose (the platform
            centre: the rank decisions homogenise about it), world units.
        length: Characteristic length [m]; rtol: relative tolerance of rank decisions.
        generic_rank: Rank of the union of the constraints away from constraint
            singularities (the home pose's); default: each pose's own.

    Returns:
        (N, legs) values in [0, 1]; 1 for a leg without constraints or whose
        constraints cannot be lost alone.
    """
    A = np.asarray(A, float)
    C = np.asarray(leg_constraints, float)
    N, legs = C.shape[0], C.shape[1]
    out = np.ones((N, legs))
    if not N or not legs:
        return out
    OA, r_a = _orthonormal_rows(screws.homogenise(A, length), rtol)
    OC, dims = _orthonormal_rows(screws.homogenise(C, length), rtol)  # (N, legs, 6, 6)
    # the rows beyond every pose's rank are zero: left out of the products below
    if not dims.any():
        return out
    OA, OC = OA[:, :int(r_a.max(initial=0))], OC[:, :, :int(dims.max())]
    union, r_u = _orthonormal_rows(OC.reshape(N, -1, 6), rtol)
    free, _ = _reciprocal_rows(np.concatenate([OA, union], axis=-2), rtol)
    if generic_rank is not None:  # a constraint singularity: keep every freed twist
        free = np.where((r_u < generic_rank)[:, None, None], 0.0, free)
    P = np.asarray(output_points, float).reshape(N, legs, 3)
    rows = np.arange(N)
    for k in range(legs):
        rest = np.concatenate([OA] + [OC[:, j] for j in range(legs) if j != k], axis=-2)
        basis, r_rest = _orthonormal_rows(rest, rtol)
        R, _ = _reciprocal_rows(basis[:, :int(r_rest.max(initial=0))], rtol)
        # leave out the motions free with every wrench: the rows are orthonormal, the
        # singular values of the rest are the sines of the principal angles
        _, sv, Vt = np.linalg.svd(R - (R @ np.swapaxes(free, -1, -2)) @ free)
        n_r = np.sum(sv > PARALLEL_SIN, axis=-1)
        R = _first_rows(Vt, 0, n_r)
        m = dims[:, k]
        s = np.linalg.svd(OC[:, k] @ DELTA @ np.swapaxes(R, -1, -2), compute_uv=False)
        value = np.where(n_r <= m, s[rows, np.clip(n_r - 1, 0, s.shape[-1] - 1)], 0.0)
        single = (m == 1) & (n_r == 1)
        if single.any():  # one wrench, one twist: the power coefficient at the point
            w = screws.dehomogenise(OC[single, k, 0], length)
            t = screws.dehomogenise(R[single, 0], length)
            value[single] = power_coefficient(w, t, P[single, k], length)
        out[:, k] = np.where((m == 0) | (n_r == 0), 1.0, value)
    return np.clip(out, 0.0, 1.0)


def _padded_legs(leg_constraints) -> np.ndarray:
    """Per-leg (k, 6) rows as one (1, legs, K, 6) array, zero rows as padding."""
    Cs = [np.asarray(c, float).reshape(-1, 6) for c in leg_constraints]
    C = np.zeros((1, len(Cs), max([len(c) for c in Cs] + [1]), 6))
    for k, c in enumerate(Cs):
        C[0, k, :len(c)] = c
    return C


def constraint_rank(leg_constraints, length: float, rtol: float = RANK_RTOL) -> int:
    """Rank of the union of the legs' constraint wrenches, decided as
    :func:`constraint_transmissions` decides it (each leg's rows orthonormalised once
    homogenised, then their union): the ``generic_rank`` to pass for poses compared
    with this one.

    Args:
        leg_constraints: per leg, (k, 6) its constraint wrenches about one common point,
            world units; length: characteristic length [m]; rtol: relative tolerance.
    """
    C = _padded_legs(leg_constraints)
    if not C.shape[1]:
        return 0
    OC, dims = _orthonormal_rows(screws.homogenise(C, length), rtol)
    if not dims.any():
        return 0
    return int(_orthonormal_rows(OC.reshape(1, -1, 6), rtol)[1][0])


def constraint_transmission(A, leg_constraints, output_points, length: float,
                            rtol: float = RANK_RTOL, generic_rank: int | None = None
                            ) -> np.ndarray:
    """Constraint transmission index of every leg at one pose:
    :func:`constraint_transmissions` of that pose.

    Args:
        A: (n, 6) actuation wrenches; leg_constraints: per leg, (k, 6) a basis of its
            constraint wrenches; output_points: per leg, (3,) the point where its
            constraint forces reach the platform; all about one common point (the
            platform centre), world units.
        length, rtol, generic_rank: As :func:`constraint_transmissions`.

    Returns:
        (legs,) values in [0, 1].
    """
    A = np.asarray(A, float).reshape(-1, 6)
    C = _padded_legs(leg_constraints)
    P = np.asarray(output_points, float).reshape(1, C.shape[1], 3)
    return constraint_transmissions(A[None], C, P, length, rtol, generic_rank)[0]


@dataclass(frozen=True)
class Transmission:
    """Motion/force transmission indices at one pose (module docstring).

    Attributes:
        iti: (n,) input transmission index of each actuator.
        oti: (n,) output transmission index of each actuator (nan: redundant actuation).
        lti: ``min(ITI, OTI)`` over the actuators.
        leg_cti: (legs,) constraint transmission index of each leg.
        cti: Its minimum (1 without constraints that a leg could lose).
        legs: (n,) the leg of each actuator (0-based).
        leg_names: Names of the legs.
    """

    iti: np.ndarray
    oti: np.ndarray
    lti: float
    leg_cti: np.ndarray
    cti: float
    legs: np.ndarray
    leg_names: tuple

    @classmethod
    def of(cls, iti, oti, leg_cti, legs, leg_names) -> Transmission:
        """The indices with ``lti`` (:func:`local_transmission_index`) and ``cti`` (the
        smallest leg's; 1 without legs) derived from the others."""
        leg_cti = np.asarray(leg_cti, float)
        return cls(iti, oti, float(local_transmission_index(iti, oti)), leg_cti,
                   float(leg_cti.min()) if len(leg_cti) else 1.0, np.asarray(legs, int),
                   tuple(leg_names))

    @property
    def good(self) -> bool:
        """Whether ``LTI`` and ``CTI`` are at least :data:`GOOD_LTI` (a ``CTI`` of nan,
        not defined, is not held against it)."""
        return bool(self.lti >= GOOD_LTI and (np.isnan(self.cti) or self.cti >= GOOD_LTI))

    @property
    def worst(self) -> str:
        """The weakest index in words, e.g. ``"leg 2 transmits poorly: ITI 0.12"``
        (``"transmits well"`` when every index is at least :data:`GOOD_LTI`)."""
        cands = [(v, "ITI", int(self.legs[i])) for i, v in enumerate(self.iti)]
        cands += [(v, "OTI", int(self.legs[i])) for i, v in enumerate(self.oti)
                  if np.isfinite(v)]
        cands += [(v, "CTI", k) for k, v in enumerate(self.leg_cti)]
        if not cands:
            return "no actuators"
        value, name, leg = min(cands, key=lambda c: c[0])
        label = self.leg_names[leg] if leg < len(self.leg_names) else str(leg + 1)
        word = "transmits well" if value >= GOOD_LTI else "transmits poorly"
        return f"leg {label} {word}: {name} {value:.2f}"


def sweep_lti(A, platform_h, dof, J, centres, layout, lines=None) -> np.ndarray:
    """LTI at N poses from the engine's arrays (:class:`pkm_pin.engine.Results`).

    Args:
        A: (N, n, 6) actuation wrenches about the world origin; platform_h: (N, 6, 6)
            homogenised platform bases about the centres (rows beyond ``dof`` unused);
            dof: (N,); J: (N, nv, 6) joint twists about the world origin; centres:
            (N, 3); layout: the mechanism's :class:`~pkm_pin.engine.Layout`; lines:
            (N, nv, 6) the twists of the joints owning each coordinate
            (:func:`pkm_pin.twists.joint_lines`; default ``J``), where the wrenches act.

    Returns:
        (N,) LTI (nan without actuators).
    """
    L, rtol = float(layout.length), float(layout.rtol)
    out = np.full(len(A), np.nan)
    if A.shape[1] == 0 or not len(A):
        return out
    Ac, Jc = screws.about(A, centres), screws.about(J, centres)
    Lc = Jc if lines is None else screws.about(lines, centres)
    for d in np.unique(dof):
        i = np.flatnonzero(dof == d)
        P = screws.dehomogenise(platform_h[i, :d], L)
        p_in, p_out = leg_points(Ac[i], Lc[i], layout.coords, layout.act_col,
                                 layout.act_leg, L)
        iti, oti = transmission_indices(Ac[i], Jc[i][:, layout.act_col], P, p_in, p_out,
                                        L, rtol)
        out[i] = local_transmission_index(iti, oti)
    return out


def sweep_cti(A, leg_constraints, leg_dims, J, centres, layout, generic_rank: int
              ) -> np.ndarray:
    """CTI (the smallest leg's) at N poses from the engine's arrays, as
    :attr:`pkm_pin.Analysis.transmission` computes it at each pose.

    Args:
        A: (N, n, 6) actuation wrenches about the world origin; leg_constraints:
            (N, legs, 6, 6) each leg's homogenised orthonormal constraint basis about
            the centres; leg_dims: (N, legs) their dimensions; J: (N, nv, 6) the joint
            lines (:func:`pkm_pin.twists.joint_lines`: where the constraint wrenches
            act) about the world origin; centres: (N, 3); layout: the mechanism's
            :class:`~pkm_pin.engine.Layout`; generic_rank: the home pose's rank of the
            union of the constraints (6 − home DOF).

    Returns:
        (N,) CTI (1 for a mechanism whose legs have no constraint to lose).
    """
    L, rtol = float(layout.length), float(layout.rtol)
    N, legs = len(A), len(layout.coords) - 1
    if not N or not legs or not np.any(leg_dims):
        return np.ones(N)
    C = screws.dehomogenise(leg_constraints, L)  # world units about the centres
    Ac, Jc = screws.about(A, centres), screws.about(J, centres)
    points = np.zeros((N, legs, 3))
    for k in range(legs):
        if np.any(leg_dims[:, k] == 1):  # the point is used for one wrench only
            points[:, k] = leg_points(C[:, k, :1], Jc, layout.coords,
                                      [layout.coords[k] - 1], [k], L)[1][:, 0]
    return constraint_transmissions(Ac, C, points, L, rtol, generic_rank).min(axis=1)


@dataclass(frozen=True)
class Ellipsoid:
    """Velocity or force ellipsoid of the platform at one pose (see
    :meth:`pkm_pin.Analysis.velocity_ellipsoid`).

    Attributes:
        semi_axes: (d,) semi-axes, largest first (dimensionless: homogenised units).
        axes: (d, 6) principal axes: twists ``(ω; v_O)`` (velocity) or wrenches
            ``(f; m_O)`` (force) about the world origin, each of unit norm once written
            about ``centre`` with its moment part divided by ``length``.
        centre: (3,) the platform centre [m]; length: the characteristic length L [m].
    """

    semi_axes: np.ndarray
    axes: np.ndarray
    centre: np.ndarray
    length: float


def payload_wrench(mass: float, centre_of_mass, g=(0.0, 0.0, -9.81)) -> np.ndarray:
    """The gravity wrench ``(m g; c × m g)`` of a payload on the platform, axis-first about
    the world origin [N, N m].

    Args:
        mass: Payload mass [kg]; centre_of_mass: (3,) its centre of mass in the world
            [m]; g: (3,) gravity [m/s²] (default 9.81 m/s² along −z).

    To find the efforts that hold it: ``analysis.actuator_efforts(-payload_wrench(...))``
    (the actuators must apply the opposite wrench).
    """
    m = float(mass)
    if not (np.isfinite(m) and m >= 0):
        raise InputError(f"mass must be a finite non-negative number [kg], got {mass!r}")
    f = m * as_vector3(g, "g")
    return np.concatenate([f, _cross(as_vector3(centre_of_mass, "centre_of_mass"), f)])


def worst_efforts(mech, poses, wrench) -> dict:
    """The largest actuator efforts over a set of poses, for one wrench the actuators
    apply to the platform (``−payload_wrench(...)`` to hold a payload; a callable
    ``wrench(pose)`` for a load that depends on the pose): each pose assembled from the
    previous one (order them along a path) and :meth:`Analysis.actuator_efforts`.

    Returns:
        ``{"efforts": (N, n) τ [N or N m] (nan where the pose does not assemble or is
        type II), "worst": (n,) max |τ_i| over the poses, "pose_index": (n,) where,
        "failures": [(index, reason)]}``.
    """
    from .assembly import as_pose
    from .errors import PkmError

    poses = [as_pose(p) for p in poses]
    n = mech.n_actuated
    tau = np.full((len(poses), n), np.nan)
    failures, guess = [], None
    for i, pose in enumerate(poses):
        try:
            a = mech.assemble(pose, guess)
            w = wrench(pose) if callable(wrench) else wrench
            tau[i] = mech.analyze(a).actuator_efforts(w)
            guess = a
        except PkmError as e:
            failures.append((i, str(e)))
    mag = np.where(np.isnan(tau), -np.inf, np.abs(tau))
    idx = np.argmax(mag, axis=0) if len(poses) else np.zeros(n, int)
    worst = np.array([mag[k, a] if len(poses) else np.nan for a, k in enumerate(idx)])
    return {"efforts": tau, "worst": np.where(np.isinf(worst), np.nan, worst),
            "pose_index": idx, "failures": failures}
