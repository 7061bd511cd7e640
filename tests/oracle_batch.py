"""The screw algebra of an analysis, batched over many poses (stacked linear algebra).

One call handles N assemblies of one mechanism at once: every rank decision and every
null space is a stacked ``numpy.linalg.svd`` over arrays of shape ``(N, k, 6)`` instead
of a Python loop of small SVDs. Screw systems whose dimension varies from pose to pose
are held as ``(N, 6, 6)`` arrays whose unused rows are zero (masked).

All work is done in homogenised coordinates: the moment part of every screw (twists
and wrenches alike) is divided by the mechanism's characteristic length ``L``; this
keeps reciprocity (``a_h Δ b_h = (a Δ b) / L``) and makes every decision unit-invariant.
Conventions: axis-first screws ``(ω; v_O)``, ``(f; m_O)`` about the world origin.
:class:`~pkm_pin.analysis.Analysis` is this computation for N = 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkm_pin.screws import DELTA, RTOL

#: ω-part singular values below this (rows orthonormal in homogenised coordinates)
#: are zero when counting rotations in the platform twist system.
ROTATION_TOL = 1e-7


def homogenise(S: np.ndarray, length: float) -> np.ndarray:
    """Copy of ``S`` (…, 6) with the moment part divided by ``length``."""
    H = np.array(S, dtype=float, copy=True)
    H[..., 3:] /= length
    return H


def dehomogenise(H: np.ndarray, length: float) -> np.ndarray:
    """Copy of ``H`` (…, 6) with the moment part multiplied by ``length``."""
    S = np.array(H, dtype=float, copy=True)
    S[..., 3:] *= length
    return S


def unit_rows(H: np.ndarray) -> np.ndarray:
    """Rows scaled to unit norm; rows below 1e-12 of the largest of their stack → 0."""
    n = np.linalg.norm(H, axis=-1, keepdims=True)
    big = n.max(axis=-2, keepdims=True) if H.shape[-2] else n
    keep = n > 1e-12 * big
    return np.where(keep, H / np.where(keep, n, 1.0), 0.0)


def span_and_null(H: np.ndarray, rtol: float = RTOL) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Masked orthonormal bases of the row span and of the null space of stacks of rows.

    Args:
        H: (N, k, 6) homogenised screws (rows are normalised here).

    Returns:
        ``(span, null, rank)``: span (N, 6, 6) with rows ``≥ rank`` zeroed, null
        (N, 6, 6) with rows ``< rank`` zeroed (orthonormal basis of the vectors x with
        ``H x = 0``), and the ranks (N,).
    """
    N = H.shape[0]
    if H.shape[1] == 0:
        return np.zeros((N, 6, 6)), np.broadcast_to(np.eye(6), (N, 6, 6)).copy(), np.zeros(N, int)
    _, sv, Vt = np.linalg.svd(unit_rows(H), full_matrices=True)
    top = sv[:, :1]
    rank = np.sum(sv > rtol * np.where(top > 0, top, np.inf), axis=1)
    rows = np.arange(6)[None, :, None]
    span = np.where(rows < rank[:, None, None], Vt, 0.0)
    null = np.where(rows >= rank[:, None, None], Vt, 0.0)
    return span, null, rank


def reciprocal(H: np.ndarray, rtol: float = RTOL) -> tuple[np.ndarray, np.ndarray]:
    """Masked basis (N, 6, 6) of the screws reciprocal to every row of ``H`` (N, k, 6),
    homogenised, and its dimension (N,)."""
    _, null, rank = span_and_null(H @ DELTA, rtol)
    return null, 6 - rank


@dataclass
class BatchScrews:
    """Screw analysis of N assemblies (arrays indexed by pose first).

    Attributes:
        length: Characteristic length used for homogenising [m].
        leg_constraints: Per leg, masked homogenised constraint wrenches (N, 6, 6).
        leg_constraint_dim: Per leg, their dimension (N,).
        constraints: Masked homogenised basis of the union (N, 6, 6).
        platform: Masked homogenised orthonormal basis of the platform twists (N, 6, 6).
        dof: (N,) platform degrees of freedom.
        translations: (N,) dimension of the pure translations among the platform twists.
        redundant: (N,) redundant constraints.
        A: (N, n, 6) actuation wrenches (unit force or unit moment, world units).
        B: (N, n) diagonal of B.
        actuated_twists: (N, n, 6) twists of the actuated joints (world units).
        type_I, type_II, condition: (N,) dimensionless closeness indices.
        M: (N, n, 6) ``A_h Δ P_hᵀ`` with unit-norm rows of A_h (masked columns).
    """

    length: float
    leg_constraints: list
    leg_constraint_dim: list
    constraints: np.ndarray
    constraint_dim: np.ndarray
    platform: np.ndarray
    dof: np.ndarray
    translations: np.ndarray
    redundant: np.ndarray
    A: np.ndarray
    B: np.ndarray
    actuated_twists: np.ndarray
    type_I: np.ndarray
    type_II: np.ndarray
    condition: np.ndarray
    M: np.ndarray


def analyse(jacobians, twists, actuated_v, length: float, rtol: float = RTOL) -> BatchScrews:
    """Mobility, actuation and singularity indices of N assemblies.

    Args:
        jacobians: Per leg, (N, 6, nv_i) axis-first world Jacobians.
        twists: Per leg, (N, nv_i, 6) motion twists (spherical groups replaced).
        actuated_v: Per leg, the velocity indices of its actuated joints.
        length: Characteristic length of the mechanism [m].
        rtol: Relative tolerance of the rank decisions.
    """
    L = float(length)
    Th = [homogenise(T, L) for T in twists]
    leg_W, leg_dim = zip(*[reciprocal(T, rtol) for T in Th]) if Th else ((), ())
    N = Th[0].shape[0]
    stacked = np.concatenate(leg_W, axis=1)
    span, null, rank_c = span_and_null(stacked, rtol)
    constraints = span
    platform = null @ DELTA  # right singular vectors of (W Δ) are those of W times Δ
    dof = 6 - rank_c
    sv_w = np.linalg.svd(platform[:, :, :3], compute_uv=False)
    translations = dof - np.sum(sv_w > ROTATION_TOL, axis=1)
    redundant = np.sum(np.stack(leg_dim), axis=0) - rank_c

    A_h, B, a_list = [], [], []
    for T, J, ks in zip(Th, jacobians, actuated_v):
        for k in ks:
            R, _ = reciprocal(np.delete(T, k, axis=1), rtol)
            M = platform @ DELTA @ np.swapaxes(R, 1, 2)
            _, _, Vt = np.linalg.svd(M)
            w = np.einsum("ni,nij->nj", Vt[:, 0], R)
            a = J[:, :, k]
            a_list.append(a)
            A_h.append(w)
    n = len(A_h)
    if n:
        A_h = np.stack(A_h, axis=1)
        actuated = np.stack(a_list, axis=1)
    else:
        A_h, actuated = np.zeros((N, 0, 6)), np.zeros((N, 0, 6))
    A = dehomogenise(A_h, L)
    f = np.linalg.norm(A[..., :3], axis=-1, keepdims=True)
    m = np.linalg.norm(A[..., 3:], axis=-1, keepdims=True)
    A = A / np.where(f * L > rtol * m, f, np.where(m > 0, m, 1.0))
    B = np.sum(A[..., :3] * actuated[..., 3:] + A[..., 3:] * actuated[..., :3], axis=-1)
    biggest = np.take_along_axis(A, np.argmax(np.abs(A), axis=-1)[..., None], axis=-1)[..., 0]
    flip = (B < 0) | ((B == 0) & (biggest < 0))
    A = np.where(flip[..., None], -A, A)
    B = np.where(flip, -B, B)

    Ahu = unit_rows(homogenise(A, L))
    Thu = unit_rows(homogenise(actuated, L))
    type_I = (np.min(np.abs(np.sum(Ahu[..., :3] * Thu[..., 3:] + Ahu[..., 3:] * Thu[..., :3],
                                   axis=-1)), axis=1) if n else np.full(N, np.inf))
    M = Ahu @ DELTA @ np.swapaxes(platform, 1, 2)
    sv = np.linalg.svd(M, compute_uv=False) if n else np.zeros((N, 1))
    idx = np.clip(dof - 1, 0, sv.shape[1] - 1)
    type_II = np.where((dof <= n) & (dof > 0), np.take_along_axis(sv, idx[:, None], 1)[:, 0], 0.0)
    with np.errstate(divide="ignore"):
        condition = np.where(type_II > 0, sv[:, 0] / np.where(type_II > 0, type_II, 1), np.inf)
    return BatchScrews(L, list(leg_W), list(leg_dim), constraints, rank_c, platform, dof,
                       translations, redundant, A, B, actuated, type_I, type_II, condition, M)
