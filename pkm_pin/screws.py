"""Screw algebra in axis-first (Plücker) coordinates — seed 000, sections 1–2 (Michalková &
Guldan; the source papers are listed in docs/references.md).

Conventions (the papers'):

* A screw is ``$ = (s; s0)``: the direction part ``s`` first, then the moment part
  ``s0``, both about the **world origin** unless a name says otherwise.
* A twist is ``(ω; v_O)``: angular velocity [rad/s], then the velocity [m/s] of the body
  point that coincides with the origin. A wrench is ``(f; m_O)``: force [N], then the
  moment [N m] about the origin.
* A line through ``r`` along unit ``s`` is ``(s; r × s)``; a screw of pitch ``h`` is
  ``(s; r × s + h s)``; a couple (pitch infinite) is ``(0; s)``.
* Reciprocal product ``a ∘ b = a[:3]·b[3:] + a[3:]·b[:3] = aᵀ Δ b`` with
  ``Δ = [[0, I], [I, 0]]`` (:data:`DELTA`). A twist and a wrench are reciprocal when the
  wrench does no work on the twist.
* Arrays of screws have shape ``(6,)`` or ``(k, 6)``, one screw per row.

Pinocchio's ``Motion`` and its Jacobians are linear-first ``(v; ω)``:
:func:`from_pinocchio` and :func:`to_pinocchio` are the only place in pkm_pin where the
two orders are swapped. (Pinocchio's ``Force`` is ``(f; τ)``, already the axis-first
order of a wrench.)

Rank decisions (:func:`rank`, :func:`basis`, :func:`reciprocal`, ...) are made on a
*unit-homogenised* copy: the moment part is divided by a characteristic length ``length``
[m], then every row is scaled to unit norm, and singular values below ``rtol`` times the
largest are taken as zero. The same geometry expressed in millimetres with ``length`` in
millimetres gives the same ranks. When ``length`` is omitted it is estimated from the
screws themselves (:func:`characteristic_length`), which is also unit-invariant.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
from numba import njit
from numba.extending import register_jitable

from .errors import InputError
from .tolerances import HELICAL_PITCH_RTOL, RANK_RTOL, SPAN_RTOL, ZERO_SCREW_RTOL

#: Matrix of the reciprocal product: ``a ∘ b = a @ DELTA @ b``.
DELTA = np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]])
DELTA.setflags(write=False)

#: Default relative tolerance of rank decisions (on unit-homogenised, row-normalised
#: screws, relative to the largest singular value); alias of
#: :data:`pkm_pin.tolerances.RANK_RTOL`.
RTOL = RANK_RTOL

_SWAP = np.r_[3:6, 0:3]
_FLOAT = np.dtype(float)


# --------------------------------------------------------------------------- checks
def as_float_array(x, name: str = "value") -> np.ndarray:
    """``x`` as a float array, or an :class:`InputError` saying it is not numeric."""
    try:
        return np.asarray(x, dtype=float)
    except (TypeError, ValueError) as e:
        raise InputError(f"{name} must be numbers, got {type(x).__name__} {x!r:.60}") from e


def as_fraction(value, name: str) -> float:
    """``value`` as a float in (0, 1) — a relative tolerance or a dimensionless
    threshold — or an :class:`InputError` naming ``name``."""
    if type(value) is float and 0.0 < value < 1.0:  # the common case (nan fails it)
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) \
            or not (np.isfinite(value) and 0 < value < 1):
        raise InputError(f"{name} must be a number between 0 and 1 (exclusive), got {value!r}")
    return float(value)


def as_vector(x, n: int, name: str = "vector", what: str = "", noun: str = "values"
              ) -> np.ndarray:
    """``x`` as a finite float array of shape (n,), or an :class:`InputError` naming
    ``name`` (and ``what`` the n values are, when given)."""
    # an exact float64 vector (the solvers' own arrays) skips the conversion
    a = x if type(x) is np.ndarray and x.dtype is _FLOAT else as_float_array(x, name)
    if a.shape != (n,):
        detail = f" ({what})" if what else ""
        raise InputError(f"{name} must have {n} {noun}{detail}, got shape {a.shape}")
    # a·a finite ⇒ every entry finite (the cheap test); otherwise the exact one (a·a
    # also overflows for finite entries beyond ~1e154)
    if not math.isfinite(a.dot(a)) and not np.isfinite(a).all():
        raise InputError(f"{name} must be finite, got {a}")
    return a


def is_vector(x, n: int) -> bool:
    """Whether ``x`` already is what :func:`as_vector` returns for it (a finite float64
    array of shape (n,)): the callers' fast path, which skips making their messages."""
    return type(x) is np.ndarray and x.dtype is _FLOAT and x.shape == (n,) \
        and math.isfinite(x.dot(x))


def as_vector3(x, name: str = "vector") -> np.ndarray:
    """Return ``x`` as a finite float array of shape (3,), or raise :class:`InputError`."""
    return as_vector(x, 3, name, noun="components")


def as_screws(S, name: str = "screws") -> np.ndarray:
    """Return ``S`` as a finite float array of shape (k, 6); accepts (6,) or (k, 6)."""
    a = as_float_array(S, name)
    if a.ndim == 1 and a.shape[0] == 6:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 6:
        raise InputError(
            f"{name} must have shape (6,) or (k, 6) (one screw per row), got {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name} must be finite (found NaN or inf)")
    return a


def _unit(direction, name: str = "direction") -> np.ndarray:
    d = as_vector3(direction, name)
    n = np.linalg.norm(d)
    if n == 0.0:
        raise InputError(f"{name} must be a non-zero vector")
    return d / n


# --------------------------------------------------------------------- constructors
def line(point, direction) -> np.ndarray:
    """Unit line screw (pitch 0) through ``point`` along ``direction``: ``(s; r × s)``.

    >>> line([1, 0, 0], [0, 0, 2])
    array([ 0.,  0.,  1.,  0., -1.,  0.])
    """
    s = _unit(direction)
    r = as_vector3(point, "point")
    return np.concatenate([s, np.cross(r, s)])


def couple(direction) -> np.ndarray:
    """Unit couple (pitch infinite) ``(0; s)``: a pure translation or a pure moment.

    >>> couple([0, 3, 0])
    array([0., 0., 0., 0., 1., 0.])
    """
    return np.concatenate([np.zeros(3), _unit(direction)])


def screw(point, direction, pitch: float) -> np.ndarray:
    """Unit screw ``(s; r × s + h s)`` of pitch ``h`` [m/rad]; ``inf`` pitch gives a couple."""
    h = float(pitch)
    if np.isinf(h):
        return couple(direction)
    if np.isnan(h):
        raise InputError("pitch must be a number or inf, got NaN")
    s = _unit(direction)
    return np.concatenate([s, np.cross(as_vector3(point, "point"), s) + h * s])


# ------------------------------------------------------------------------- products
def reciprocal_product(a, b) -> np.ndarray | float:
    """Reciprocal product ``a ∘ b = a[:3]·b[3:] + a[3:]·b[:3]`` (broadcasts over rows).

    For a twist and a wrench it is the instantaneous power of the wrench on the twist.
    """
    a = as_float_array(a, "a")
    b = as_float_array(b, "b")
    if a.ndim == 0 or b.ndim == 0 or a.shape[-1] != 6 or b.shape[-1] != 6:
        raise InputError(f"screws must have 6 coordinates, got shapes {a.shape} and {b.shape}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise InputError("screws must be finite (found NaN or inf)")
    out = np.sum(a[..., :3] * b[..., 3:] + a[..., 3:] * b[..., :3], axis=-1)
    return float(out) if np.ndim(out) == 0 else out


def pitch(s, length: float = 1.0, rtol: float = RTOL) -> np.ndarray | float:
    """Pitch ``h = s·s0 / s·s`` [m/rad]; ``inf`` for a couple (``|s|`` negligible).

    ``|s|`` is negligible when ``|s| · length <= rtol · |s0|``; ``length`` [m] is a
    characteristic length of the problem.
    """
    S = as_screws(s)
    w, v = S[:, :3], S[:, 3:]
    ww = np.einsum("ij,ij->i", w, w)
    is_couple = np.sqrt(ww) * length <= rtol * np.linalg.norm(v, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.where(is_couple, np.inf, np.einsum("ij,ij->i", w, v) / np.where(is_couple, 1, ww))
    return float(h[0]) if np.ndim(s) == 1 else h


def axis(s, length: float = 1.0, rtol: float = RTOL) -> tuple[np.ndarray, np.ndarray]:
    """Axis of a single screw: (point of the axis nearest the origin, unit direction).

    For a couple the axis has no location: the parallel line through the origin is
    returned (point = 0). A zero screw raises :class:`InputError`.
    """
    S = as_screws(s)
    if S.shape[0] != 1:
        raise InputError(f"axis() takes one screw, got {S.shape[0]}")
    w, v = S[0, :3], S[0, 3:]
    if np.linalg.norm(w) * length <= rtol * np.linalg.norm(v):
        if not np.any(v):
            raise InputError("the zero screw has no axis")
        return np.zeros(3), v / np.linalg.norm(v)
    if not np.any(w):
        raise InputError("the zero screw has no axis")
    return np.cross(w, v) / w.dot(w), w / np.linalg.norm(w)



def axis_point_nearest(S, point) -> np.ndarray:
    """The point of the axis of each screw ``S`` (…, 6) nearest to ``point`` (…, 3)
    [m]: the foot ``a × b / |a|²`` of the axis moved along ``a``; ``point`` itself for
    a couple (``a = 0``: its axis has no location)."""
    S = np.asarray(S, dtype=float)
    p = np.broadcast_to(np.asarray(point, dtype=float), S.shape[:-1] + (3,))
    a = S[..., :3]
    aa = np.einsum("...i,...i->...", a, a)
    safe = np.where(aa > 0, aa, 1.0)[..., None]
    foot = cross(a, S[..., 3:]) / safe
    along = np.einsum("...i,...i->...", p - foot, a)[..., None] / safe
    return np.where((aa > 0)[..., None], foot + along * a, p)

# -------------------------------------------------------------------- linear algebra
def characteristic_length(S) -> float:
    """A length [m] that scales with the geometry of ``S``, for homogenising.

    The median distance from the origin of the axes of the rows of ``S`` that are not
    couples (rows whose direction part is below 1e-12 of the row norm count as couples).
    Round-off distances (below 1e-12) do not count; 1.0 when no distance is left.
    Scaling the geometry by ``k`` scales the result by ``k``.
    """
    S = as_screws(S)
    w, v = S[:, :3], S[:, 3:]
    ww = np.einsum("ij,ij->i", w, w)
    keep = ww > (1e-12) ** 2 * np.einsum("ij,ij->i", S, S)
    if not np.any(keep):
        return 1.0
    d = np.linalg.norm(cross(w[keep], v[keep]), axis=1) / ww[keep]
    d = d[d > 1e-12]
    return float(np.median(d)) if d.size else 1.0


def cross(a, b) -> np.ndarray:
    """``a × b`` over the last axis (length 3), broadcast like ``numpy.cross`` (same
    numbers; about three times faster on the small stacks of this package)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def about(S, point) -> np.ndarray:
    """Screws ``S`` (..., k, 6) given about the world origin written about ``point``
    (..., 3) [m], twists and wrenches alike: ``(a; b) → (a; b + a × point)`` (the
    velocity, or the moment, at the point). A copy."""
    S = np.array(S, dtype=float, copy=True)
    p = np.asarray(point, dtype=float)[..., None, :] if S.ndim > 1 else np.asarray(point, float)
    S[..., 3:] += cross(S[..., :3], p)
    return S


def from_point(S, point) -> np.ndarray:
    """Inverse of :func:`about`: screws given about ``point`` written about the world
    origin, ``(a; b) → (a; b − a × point)``. A copy."""
    return about(S, -np.asarray(point, dtype=float))


def homogenise(S, length: float) -> np.ndarray:
    """Copy of screws ``S`` (…, 6) with the moment part divided by ``length`` [m]
    (twists and wrenches alike): dimensionless, and reciprocity is kept up to the factor
    ``1 / length``."""
    H = np.array(S, dtype=float, copy=True)
    H[..., 3:] /= length
    return H


def dehomogenise(H, length: float) -> np.ndarray:
    """Copy of homogenised screws ``H`` (…, 6) back in world units (the moment part
    times ``length``)."""
    S = np.array(H, dtype=float, copy=True)
    S[..., 3:] *= length
    return S


def homogenised_about(S: np.ndarray, p: np.ndarray, length: float) -> np.ndarray:
    """Screws ``S`` (rows, world origin) about the point ``p``, moment part / ``length``:
    ``(a; b) → (a; (b + a × p) / length)`` (the velocity, or moment, at ``p``)."""
    return homogenise(about(np.atleast_2d(S), p), length)


def from_homogenised(H: np.ndarray, p: np.ndarray, length: float) -> np.ndarray:
    """Inverse of :func:`homogenised_about`: world-origin screws (rows)."""
    H = np.atleast_2d(H)
    if H.shape[0] == 0:
        return np.zeros((0, 6))
    return from_point(dehomogenise(H, length), p)


#: Rows whose homogenised norm is below this fraction of the largest are zero screws
#: (alias of :data:`pkm_pin.tolerances.ZERO_SCREW_RTOL`).
_ZERO_ROW = ZERO_SCREW_RTOL


def normalised_rows(S, length: float) -> np.ndarray:
    """Homogenised rows (k × 6) scaled to unit norm; (numerically) zero rows dropped."""
    S = np.atleast_2d(np.asarray(S, dtype=float))
    H = homogenise(S, length)
    n = np.linalg.norm(H, axis=1)
    keep = n > _ZERO_ROW * n.max() if n.size else n > 0
    return H[keep] / n[keep, None]


def _length(S: np.ndarray, length: float | None) -> float:
    if length is None:
        return characteristic_length(S)
    L = float(length)
    if not (np.isfinite(L) and L > 0):
        raise InputError(f"characteristic length must be a positive number, got {length}")
    return L


def motion_indices(X: np.ndarray, Y: np.ndarray, rtol: float):
    """The forward and inverse indices of a machine's motions (docs/indices.md): with the
    columns of ``X`` (actuated rates, dimensionless: rad, or m over the characteristic
    length) and ``Y`` (the output's homogenised twists) spanning its motions, those that
    move neither removed (rank of ``(X; Y)`` by :func:`svd_rank`), ``forward = min |X z|
    / |(X; Y) z|`` (0: the output moves with the actuators locked) and ``inverse = min
    |Y z| / |(X; Y) z|`` (0: an actuator moves without moving the output): the smallest
    singular values of the two blocks of an orthonormal basis of the motions. They do
    not depend on the basis, so the general elimination (its null space) and the
    per-leg engine (its platform twists and ``A Δ t = B q̇``) give the same numbers.

    Returns:
        ``(m, Vt, forward, inverse)``: the number of motions kept, the right singular
        vectors of ``(X; Y)`` (its first ``m`` rows span them) and the two indices (1
        when no motion is left).
    """
    n = X.shape[0]
    S = np.vstack([X, Y])
    if S.shape[1] == 0:
        return 0, np.eye(0), 1.0, 1.0
    m, _, _, Vt = svd_rank(S, rtol)
    if m == 0:
        return 0, Vt, 1.0, 1.0
    Q, _ = np.linalg.qr(S @ Vt[:m].T)
    cx = np.linalg.svd(Q[:n], compute_uv=False) if n else np.zeros(0)
    cy = np.linalg.svd(Q[n:], compute_uv=False)
    forward = float(cx[m - 1]) if n >= m else 0.0
    inverse = float(cy[m - 1]) if Y.shape[0] >= m else 0.0
    return m, Vt, forward, inverse


def svd_rank(H, rtol: float) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """``(rank, U, sv, Vt)``: numpy's SVD of the m × n matrix ``H`` (full matrices) and
    its rank, the number of singular values above ``rtol`` times the largest. The one
    rank rule of the numpy code (the compiled engine applies the same rule to its Jacobi
    SVD, :mod:`pkm_pin.engine.linalg`). ``H`` without rows or columns has rank 0,
    ``U = I_m``, no singular values and ``Vt = I_n``."""
    H = np.asarray(H, dtype=float)
    m, n = H.shape
    if m == 0 or n == 0:
        return 0, np.eye(m), np.zeros(0), np.eye(n)
    U, sv, Vt = np.linalg.svd(H, full_matrices=True)
    return (int(np.sum(sv > rtol * sv[0])) if sv[0] > 0 else 0), U, sv, Vt


def rank(S, length: float | None = None, rtol: float = RTOL) -> int:
    """Number of linearly independent screws among the rows of ``S``."""
    S = as_screws(S)
    L = _length(S, length)
    return svd_rank(normalised_rows(S, L).reshape(-1, 6), rtol)[0]


def basis(S, length: float | None = None, rtol: float = RTOL) -> np.ndarray:
    """Independent rows (rank × 6) spanning the same screw system as ``S``.

    The rows are orthonormal in the homogenised coordinates ``(s; s0/length)``.
    """
    S = as_screws(S)
    L = _length(S, length)
    r, _, _, Vt = svd_rank(normalised_rows(S, L).reshape(-1, 6), rtol)
    return dehomogenise(Vt[:r], L)


def reciprocal(S, length: float | None = None, rtol: float = RTOL) -> np.ndarray:
    """Basis ((6 − rank) × 6) of every screw reciprocal to all rows of ``S``.

    Empty ``S`` (shape (0, 6)) gives 6 rows. Twists of a joint system give its
    constraint wrenches and vice versa (seed 000, eq. 11 and 23).
    """
    S = as_screws(S)
    L = _length(S, length)
    H = normalised_rows(S, L)
    # a_h Δ b_h = (a Δ b) / L for homogenised a_h, b_h: reciprocity is preserved.
    r, _, _, Vt = svd_rank(H.reshape(-1, 6) @ DELTA, rtol)
    return dehomogenise(Vt[r:], L)


def union(*systems, length: float | None = None, rtol: float = RTOL) -> np.ndarray:
    """Basis of the screw system spanned by all the given systems together (eq. 34, 37)."""
    stacked = np.vstack([as_screws(S) for S in systems]) if systems else np.zeros((0, 6))
    return basis(stacked, length, rtol)


def intersection(*systems, length: float | None = None, rtol: float = RTOL) -> np.ndarray:
    """Basis of the screws common to all the given systems (eq. 35, 36).

    Computed as the reciprocal of the union of the reciprocals.
    """
    if not systems:
        return np.eye(6)
    arrays = [as_screws(S) for S in systems]
    L = _length(np.vstack(arrays), length)
    recips = [reciprocal(S, L, rtol) for S in arrays]
    return reciprocal(np.vstack(recips), L, rtol)


def contains(S, x, length: float | None = None,
             rtol: float = SPAN_RTOL) -> np.ndarray | bool:
    """Whether each row of ``x`` lies in the span of ``S`` (relative tolerance ``rtol``)."""
    S = as_screws(S)
    X = as_screws(x, "x")
    L = _length(np.vstack([S, X]), length)
    B = normalised_rows(basis(S, L), L) if S.shape[0] else np.zeros((0, 6))
    H = homogenise(X, L)
    n = np.linalg.norm(H, axis=1)
    resid = H - (H @ B.T) @ B if B.shape[0] else H
    out = np.linalg.norm(resid, axis=1) <= rtol * np.where(n > 0, n, 1.0)
    return bool(out[0]) if np.ndim(x) == 1 else out


# ------------------------------------------------------------------ transformations
def adjoint(placement: pin.SE3) -> np.ndarray:
    """6×6 matrix mapping axis-first screw coordinates from frame b to frame a.

    ``placement`` is ``aMb``. For a twist ``(ω; v)`` and a wrench ``(f; m)`` alike:
    ``ω_a = R ω_b``, ``v_a = R v_b + p × R ω_b``.
    """
    if not isinstance(placement, pin.SE3):
        raise InputError(f"placement must be a pinocchio.SE3, got {type(placement).__name__}")
    R, p = placement.rotation, placement.translation
    X = np.zeros((6, 6))
    X[:3, :3] = R
    X[3:, 3:] = R
    X[3:, :3] = pin.skew(p) @ R
    return X


def transform(S, placement: pin.SE3) -> np.ndarray:
    """Coordinates of screws ``S`` (given in frame b) in frame a, ``placement = aMb``."""
    arr = as_float_array(S, "screws")
    out = as_screws(S) @ adjoint(placement).T
    return out[0] if arr.ndim == 1 else out


def from_pinocchio(x) -> np.ndarray:
    """Pinocchio motion coordinates ``(v; ω)`` → axis-first twist ``(ω; v)``.

    Works on a 6-vector, a ``pin.Motion``, and on a 6×n Jacobian (the rows are swapped;
    the result is still 6×n). A ``pin.Force`` is ``(f; τ)``: force first, which is
    already the axis-first order of a wrench, so it is returned unchanged. This,
    :func:`world_twist_rows` (its compiled form for Jacobians), :func:`probe_tip` (a
    probe's placement read from its columns) and :func:`to_pinocchio` are the only place
    where the two orders meet.
    """
    if isinstance(x, pin.Force):
        return x.vector.copy()
    if isinstance(x, pin.Motion):
        x = x.vector
    a = as_float_array(x, "x")
    if a.shape[0] != 6:
        raise InputError(f"expected 6 rows in Pinocchio order (v; w), got shape {a.shape}")
    return a[_SWAP].copy()


@register_jitable
def probe_tip(Jt, c, tip):
    """The world placement ``tip`` (4 × 4) of the frame of a
    :class:`~pkm_pin.twists.TreePass` probe (a spherical joint at rest) whose columns of
    Pinocchio's WORLD Jacobian ``Jt`` start at ``c``: three unit rotations in
    Pinocchio's order ``(v; ω) = (p × r_a; r_a)``, ``r_a`` the columns of the rotation,
    ``p = ½ Σ_a r_a × (p × r_a)``. Compiled code; with :func:`world_twist_rows`, the
    compiled reading of Pinocchio's ``(v; ω)``."""
    p0 = p1 = p2 = 0.0
    for a in range(3):
        r0, r1, r2 = Jt[3, c + a], Jt[4, c + a], Jt[5, c + a]
        v0, v1, v2 = Jt[0, c + a], Jt[1, c + a], Jt[2, c + a]
        tip[0, a], tip[1, a], tip[2, a] = r0, r1, r2
        p0 += 0.5 * (r1 * v2 - r2 * v1)
        p1 += 0.5 * (r2 * v0 - r0 * v2)
        p2 += 0.5 * (r0 * v1 - r1 * v0)
    tip[0, 3], tip[1, 3], tip[2, 3] = p0, p1, p2
    tip[3, 0], tip[3, 1], tip[3, 2], tip[3, 3] = 0.0, 0.0, 0.0, 1.0


@njit(cache=True, nogil=True)
def world_twist_rows(Jp, base, out):
    """Compiled :func:`from_pinocchio` of a Jacobian, moved to the world: ``out`` (nv ×
    6) receives the axis-first twists ``(R ω; R v + p × R ω)`` (rows) of the columns
    ``(v; ω)`` of ``Jp`` (6 × nv, Pinocchio WORLD frame of a chain whose root stands at
    ``base = (R, p)`` in the world, a 4×4 placement)."""
    px, py, pz = base[0, 3], base[1, 3], base[2, 3]
    for c in range(Jp.shape[1]):
        v0, v1, v2 = Jp[0, c], Jp[1, c], Jp[2, c]
        w0, w1, w2 = Jp[3, c], Jp[4, c], Jp[5, c]
        a0 = base[0, 0] * w0 + base[0, 1] * w1 + base[0, 2] * w2
        a1 = base[1, 0] * w0 + base[1, 1] * w1 + base[1, 2] * w2
        a2 = base[2, 0] * w0 + base[2, 1] * w1 + base[2, 2] * w2
        out[c, 0], out[c, 1], out[c, 2] = a0, a1, a2
        out[c, 3] = base[0, 0] * v0 + base[0, 1] * v1 + base[0, 2] * v2 + py * a2 - pz * a1
        out[c, 4] = base[1, 0] * v0 + base[1, 1] * v1 + base[1, 2] * v2 + pz * a0 - px * a2
        out[c, 5] = base[2, 0] * v0 + base[2, 1] * v1 + base[2, 2] * v2 + px * a1 - py * a0


def to_pinocchio(x) -> np.ndarray:
    """Axis-first twist ``(ω; v)`` → Pinocchio motion coordinates ``(v; ω)`` (vector or
    6×n). Wrenches need no conversion: ``pin.Force(wrench[:3], wrench[3:])``."""
    a = as_float_array(x, "x")
    if a.shape[0] != 6:
        raise InputError(f"expected 6 rows in axis-first order (w; v), got shape {a.shape}")
    return a[_SWAP].copy()


def exp(twist) -> pin.SE3:
    """Rigid displacement ``exp`` of an axis-first twist (ω; v_O) held for unit time.

    The result is the world-frame displacement ``D`` such that a body at ``M`` moves to
    ``D * M`` (a spatial twist about the world origin).
    """
    t = as_screws(twist, "twist")
    if t.shape[0] != 1:
        raise InputError(f"exp takes one twist of shape (6,), got {np.shape(twist)}")
    t = t[0]
    return pin.exp6(pin.Motion(to_pinocchio(t)))


def log(displacement: pin.SE3) -> np.ndarray:
    """Axis-first twist (ω; v_O) whose :func:`exp` is the world displacement given."""
    return from_pinocchio(pin.log6(displacement).vector)


def motion_type(twists, translations: int, length: float) -> str:
    """Name of a twist system (rows, axis-first): ``"3T"``, ``"2T1R"``, ``"3R"``… from
    its ``translations`` pure translations and the other ``r`` directions, ``"0"`` when
    empty.

    With one direction besides the translations (r = 1), the twist system may be
    *helical*: its rotation ``(ω; v)`` has a pitch ``h = ω·v / |ω|²`` that no translation
    of the system cancels (they are all normal to ω). It is named ``"H"`` then (a
    Bennett linkage's coupler: ``"1H"``), decided on ``|h| / length`` above
    :data:`~pkm_pin.tolerances.HELICAL_PITCH_RTOL` and the translations' component
    along ω below it. With r ≥ 2 the directions are counted as rotations.
    """
    P = np.atleast_2d(np.asarray(twists, dtype=float)).reshape(-1, 6)
    t, r = int(translations), P.shape[0] - int(translations)
    name = f"{t}T" if t else ""
    if r == 1 and P.shape[0]:
        _, sv, Vt = np.linalg.svd(P[:, :3].T, full_matrices=True)  # combos: ω-parts
        rot = Vt[0] @ P  # the combination with the largest rotation
        w, v = rot[:3], rot[3:]
        trans = Vt[1:] @ P  # ω ≈ 0: the translations
        pitch = abs(w @ v) / (w @ w) / length
        axis = w / np.linalg.norm(w)
        along = np.linalg.norm(np.linalg.lstsq(trans[:, 3:].T, axis, rcond=None)[0]
                               @ trans[:, 3:]) if t else 0.0
        if pitch > HELICAL_PITCH_RTOL and along < HELICAL_PITCH_RTOL:
            return name + "1H"
    return name + (f"{r}R" if r else "") or "0"
