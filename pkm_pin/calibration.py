"""Geometric calibration: identify parameter errors from measured platform poses.

``calibrate(mech, samples, parameters)`` fits the errors of the named parameters (see
:mod:`pkm_pin.sensitivity` for the names) to measurements ``(q_actuated, measured)``:
Gauss–Newton on the sensitivity Jacobian, the model re-solved by the forward kinematics
(:func:`pkm_pin.position.forward_kinematics`) of the perturbed mechanism at every iteration.

Residual of a sample: the small displacement from the model's pose to the measured one,
expressed at the platform origin: ``(L ω; δp)`` [m], ``ω`` the rotation error [rad]
scaled by the characteristic length ``L`` of the mechanism, ``δp`` the position error of
the platform origin. A measurement of 3 numbers is a position only (``δp`` rows alone).

Before fitting, the parameters are sorted out at the start point:

* *incompatible*: errors the rigid (overconstrained) mechanism cannot absorb
  (:attr:`Sensitivity.incompatible`); they cannot be simulated nor fitted;
* *unidentifiable*: columns of the scaled Jacobian that are zero or linear combinations
  of columns of parameters listed before them (relative tolerance ``ident_tol``, the
  pivot threshold of a Gram–Schmidt pass in the order given).

Both are reported and held at zero; only the rest is fitted.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from . import screws
from .assembly import Assembly, as_pose
from .errors import InputError
from .position import forward_kinematics
from .sensitivity import perturb, select_parameters, sensitivity
from .tolerances import CALIBRATION_STEP_TOL, IDENTIFIABILITY_TOL

#: Relative pivot threshold of the identifiability test (scaled Jacobian columns); alias
#: of :data:`pkm_pin.tolerances.IDENTIFIABILITY_TOL`.
IDENT_TOL = IDENTIFIABILITY_TOL


@dataclass
class CalibrationResult:
    """Result of :func:`calibrate`.

    Attributes:
        parameters: The fitted (identifiable) parameters.
        errors: Identified error of each fitted parameter [m or rad].
        std: Standard deviation of each identified error (from the residual variance and
            ``(Jᵀ J)⁻¹`` at the solution) [m or rad].
        unidentifiable: Parameters whose effect is zero or a combination of others'.
        incompatible: Parameters whose error the rigid mechanism cannot absorb.
        residual_before: RMS over the samples of the residual norm before [m].
        residual_after: The same after calibration [m].
        iterations: Gauss–Newton iterations.
        converged: Whether the last step was below ``tol``.
        mechanism: The calibrated mechanism (``geometry.perturb(mech, errors)``).
    """

    parameters: list[str]
    errors: dict[str, float]
    std: dict[str, float]
    unidentifiable: list[str]
    incompatible: list[str]
    residual_before: float
    residual_after: float
    iterations: int
    converged: bool
    mechanism: object = field(repr=False)


def _samples(mech, samples) -> list[tuple[np.ndarray, object]]:
    out = []
    for k, item in enumerate(samples):
        try:
            qa, meas = item
        except (TypeError, ValueError) as e:
            raise InputError(f"samples[{k}] must be a pair (q_actuated, measured pose)") from e
        qa = mech.check_actuated(qa, f"samples[{k}] q_actuated")
        m = np.asarray(meas, dtype=float) if not isinstance(meas, pin.SE3) else None
        if m is not None and m.shape == (3,):
            out.append((qa, screws.as_vector3(m, f"samples[{k}] measured position")))
        else:
            out.append((qa, as_pose(meas)))
    if not out:
        raise InputError("calibration needs at least one sample")
    return out


def _residual(pose: pin.SE3, measured, L: float) -> np.ndarray:
    """``(L ω; δp)`` of the displacement pose → measured, at the platform origin."""
    if isinstance(measured, np.ndarray):
        return measured - pose.translation
    t = screws.log(measured * pose.inverse())
    dp = t[3:] + np.cross(t[:3], pose.translation)
    return np.r_[L * t[:3], dp]


def _jacobian_rows(sens_matrix: np.ndarray, pose: pin.SE3, measured, L: float) -> np.ndarray:
    J = sens_matrix.copy()
    J[3:] += np.cross(J[:3].T, pose.translation).T
    J[:3] *= L
    return J[3:] if isinstance(measured, np.ndarray) else J


def _legs_solve(mech, q_actuated, guess):
    """Forward kinematics of a platform mechanism warm-started from the assembly
    ``guess`` of another (the nominal or an earlier iterate) mechanism."""
    start = None if guess is None else Assembly(mech, guess.pose, [q.copy() for q in guess.leg_q])
    return forward_kinematics(mech, q_actuated, start)


@dataclass(frozen=True)
class Geometry:
    """How :func:`calibrate` reads a mechanism's geometry: four functions of the
    mechanism. ``select(mech, parameters)``: the parameter names (unknown ones refused);
    ``solve(mech, q_actuated, guess)``: the assembly at actuated values (``.pose``: the
    output's world placement), warm-started from ``guess`` (an assembly of the nominal
    or of an earlier iterate, or ``None``); ``sensitivity(mech, assembly, names)``: a
    :class:`~pkm_pin.sensitivity.Sensitivity`; ``perturb(mech, errors)``: the mechanism
    with finite errors added. :data:`LEGS` reads a platform mechanism leg by leg; a
    linkage gives its tree's (:meth:`pkm_pin.linkage.Linkage.calibrate`)."""

    select: Callable
    solve: Callable
    sensitivity: Callable
    perturb: Callable


#: A base–legs–platform mechanism's geometry: :mod:`pkm_pin.sensitivity`'s parameters.
LEGS = Geometry(select_parameters, _legs_solve, sensitivity, perturb)


def _solve_all(geometry: Geometry, mech, samples, guesses):
    """Forward kinematics at every sample, warm-started from ``guesses``."""
    return [geometry.solve(mech, qa, g) for (qa, _), g in zip(samples, guesses)]


def _stack(geometry: Geometry, mech, samples, assemblies, names, L):
    r, J = [], []
    for (qa, meas), a in zip(samples, assemblies):
        r.append(_residual(a.pose, meas, L))
        if names is not None:
            s = geometry.sensitivity(mech, a, names)
            J.append(_jacobian_rows(s.matrix, a.pose, meas, L))
    return np.concatenate(r), (np.vstack(J) if names is not None else None)


def _rms(r: np.ndarray, samples) -> float:
    return float(np.sqrt(np.sum(r * r) / len(samples)))


def identifiable(J: np.ndarray, tol: float = IDENTIFIABILITY_TOL) -> np.ndarray:
    """Boolean mask of the columns of ``J`` kept by a Gram–Schmidt pass in column order:
    a column is kept when its part orthogonal to the kept ones exceeds ``tol`` times its
    norm (columns of zero norm, relative to the largest, are dropped)."""
    norms = np.linalg.norm(J, axis=0)
    big = norms.max() if norms.size else 0.0
    keep = np.zeros(J.shape[1], dtype=bool)
    Q = np.zeros((J.shape[0], 0))
    for k in range(J.shape[1]):
        if norms[k] <= 1e-12 * big or big == 0:
            continue
        v = J[:, k] / norms[k]
        for _ in range(2):  # re-orthogonalise once for accuracy
            v = v - Q @ (Q.T @ v)
        if np.linalg.norm(v) > tol:
            keep[k] = True
            Q = np.column_stack([Q, v / np.linalg.norm(v)])
    return keep


def calibrate(
    mech,
    samples: Sequence,
    parameters,
    *,
    max_iter: int = 20,
    tol: float = CALIBRATION_STEP_TOL,
    ident_tol: float = IDENTIFIABILITY_TOL,
    geometry: Geometry = LEGS,
) -> CalibrationResult:
    """Identify the errors of ``parameters`` from measured platform poses.

    Args:
        mech: The nominal :class:`~pkm_pin.mechanism.Mechanism`.
        samples: Pairs ``(q_actuated, measured)``: the actuated coordinates and the
            measured platform pose (``pin.SE3``, 4×4, 6 numbers) or position (3 numbers).
        parameters: Names, prefixes or globs (:func:`~pkm_pin.sensitivity.select_parameters`).
        max_iter: Gauss–Newton iterations at most.
        tol: Stop when the step, each parameter divided by its column scale, is below
            ``tol`` relative to the characteristic length.
        ident_tol: Pivot threshold of the identifiability test.
        geometry: How the parameters are read (:class:`Geometry`; default :data:`LEGS`).

    Returns:
        A :class:`CalibrationResult`.

    Raises:
        InputError: malformed samples or unknown parameter names.
        ForwardKinematicsError: the model cannot reach a sample's actuated coordinates.
    """
    names = geometry.select(mech, parameters)
    samples = _samples(mech, samples)
    L = mech.characteristic_length
    assemblies = _solve_all(geometry, mech, samples, [None] * len(samples))
    r0, J0 = _stack(geometry, mech, samples, assemblies, names, L)
    incompatible = sorted({n for a in assemblies
                           for n in geometry.sensitivity(mech, a, names).incompatible},
                          key=names.index)
    cand = [k for k, n in enumerate(names) if n not in incompatible]
    keep = identifiable(J0[:, cand], ident_tol)
    fitted = [names[k] for k, ok in zip(cand, keep) if ok]
    unident = [names[k] for k, ok in zip(cand, keep) if not ok]
    x = np.zeros(len(fitted))
    current, r, converged, it = mech, r0, False, 0
    J = J0[:, [names.index(n) for n in fitted]]
    col = np.linalg.norm(J, axis=0) if fitted else np.ones(0)
    col[col == 0] = 1.0
    for it in range(1, max_iter + 1):
        if not fitted:
            converged = True
            break
        dx_s, *_ = np.linalg.lstsq(J / col, r, rcond=None)
        dx = dx_s / col
        x = x + dx
        current = geometry.perturb(mech, dict(zip(fitted, x)))
        assemblies = _solve_all(geometry, current, samples, assemblies)
        r, J = _stack(geometry, current, samples, assemblies, fitted, L)
        if np.linalg.norm(dx_s) <= tol * L:
            converged = True
            break
    m, n = r.size, len(fitted)
    std = np.full(n, np.nan)
    if n and m > n:
        sigma2 = float(r @ r) / (m - n)
        cov = np.linalg.pinv(J.T @ J)
        std = np.sqrt(np.maximum(np.diag(cov), 0.0) * sigma2)
    return CalibrationResult(
        parameters=fitted,
        errors=dict(zip(fitted, map(float, x))),
        std=dict(zip(fitted, map(float, std))),
        unidentifiable=unident,
        incompatible=incompatible,
        residual_before=_rms(r0, samples),
        residual_after=_rms(r, samples),
        iterations=it,
        converged=converged,
        mechanism=current,
    )


__all__ = ["CalibrationResult", "Geometry", "IDENT_TOL", "LEGS", "calibrate", "identifiable"]
