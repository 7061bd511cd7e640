"""Assembly modes: every platform pose for given actuated coordinates.

Two methods, one result (:class:`AssemblyModes`, a list of assemblies with a
``complete`` flag and the counts behind it):

* ``"homotopy"`` — mechanisms whose six legs are distance constraints (6-SPS / 6-UPS /
  6-SPU …: each leg a line between a base point and a platform point, its prismatic
  joint actuated; :func:`distance_legs` recognises them). The forward problem is
  written in Study parameters ``x = (e; g)`` (``e`` the rotation quaternion, the
  translation ``t = 2 g ē / |e|²``) as seven quadrics of P⁷: the six legs
  ``|R b_i + t − a_i|² − l_i² = 0`` multiplied by ``|e|²`` and the Study quadric
  ``e · g = 0`` (:func:`study_quadrics`). Their Bézout number is 2⁷ = 128; a general
  Stewart–Gough platform has 40 finite solutions, the other 88 paths end on the
  exceptional set ``e = 0`` (no rotation). :func:`stewart_gough_postures` tracks the
  128 paths of the total-degree homotopy ``(1 − τ) F + τ γ G`` (start system
  ``x_k² − x_0²``, a random complex ``γ``: the "gamma trick", so that with probability
  one no path meets a singularity for ``τ ∈ (0, 1]``) with a complex predictor
  (Runge–Kutta 4 on the Davidenko equation) and a Newton corrector accepted only while
  it contracts, on a random complex affine chart of P⁷. Every isolated nonsingular
  solution is the end of some path; when every path has reached ``τ = 0`` or the
  exceptional set and the nonsingular ends are distinct, the list of real postures is
  **complete** (``complete=True``). The real postures are then polished by the closure
  solver of the mechanism (:func:`pkm_pin.solve.solve_closure`, mask ACTUATED) and kept
  when their legs assemble inside the joint limits.
* ``"multistart"`` — every other mechanism: the closure solver (mask ACTUATED; compiled
  where the mechanism has kernels) from batches of random starts (platform poses moved
  by random twists of the platform twist system from home, legs at home or at random
  configurations), deduplicated by pose; it stops after ``patience`` batches in a row
  find no new mode. Nothing is proven (``complete=False``).

An unreachable target raises :class:`~pkm_pin.errors.ForwardKinematicsError`.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from . import screws
from .assembly import Assembly
from .errors import AssemblyError, ForwardKinematicsError, InputError
from .leg import pose_error
from .solve import ACTUATED, solve_closure
from .tolerances import (
    CLOSURE_TOL,
    FK_ACCEPT_FLOOR,
    HOMOTOPY_REAL_TOL,
    MODES_PATIENCE,
    SAME_POSE_TOL,
    TARGET_LIMIT_SLACK,
)

__all__ = ["AssemblyModes", "DistanceLegs", "StudySolutions", "assembly_modes",
           "distance_legs", "stewart_gough_postures", "study_quadrics"]


# ======================================================================== result
class AssemblyModes(list):
    """The assembly modes found for one vector of actuated coordinates: a list of
    :class:`~pkm_pin.assembly.Assembly` (sorted by their distance from the home pose,
    nearest first: the same target gives the same order) with what is known about its
    completeness.

    Attributes:
        complete: Whether the list is proven to hold every assembly mode within the
            joint limits (method ``"homotopy"`` with every path tracked to its end).
        method: ``"homotopy"`` or ``"multistart"``.
        counts: What the method saw: homotopy ``paths``, ``finite`` (complex finite
            solutions), ``real``, ``outside_limits`` (real postures whose legs do not
            assemble within the joint limits), ``at_infinity``, ``failed`` (paths not
            tracked to their end); multistart ``starts``, ``batches``, ``converged``.
        seconds: Wall time spent [s].
    """

    def __init__(self, assemblies, complete: bool, method: str, counts: dict,
                 seconds: float = 0.0):
        super().__init__(assemblies)
        self.complete = complete
        self.method = method
        self.counts = dict(counts)
        self.seconds = seconds

    def __repr__(self) -> str:
        return (f"AssemblyModes({len(self)} modes, complete={self.complete}, "
                f"method={self.method!r}, counts={self.counts})")


# ================================================================ distance legs
@dataclass(frozen=True)
class DistanceLegs:
    """Six legs that are distance constraints: leg ``i`` keeps the platform point
    ``platform[i]`` (platform frame) at the distance ``sign[i] q_i + offset[i]`` from the
    base point ``base[i]`` (world), ``q_i`` its actuated prismatic coordinate."""

    base: np.ndarray
    platform: np.ndarray
    sign: np.ndarray
    offset: np.ndarray

    def lengths(self, q_actuated) -> np.ndarray:
        """Leg lengths (distances) for the actuated coordinates [m]."""
        return self.sign * np.asarray(q_actuated, dtype=float) + self.offset


def _skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def _concurrent_point(rows: np.ndarray, length: float):
    """The point common to the lines ``rows`` (axis-first Plücker rows, unit ω), or
    ``None`` when they do not meet (relative to ``length``) or are not independent."""
    w, m = rows[:, :3], rows[:, 3:]
    if np.linalg.matrix_rank(w, tol=1e-6) < len(rows):
        return None
    # m = p × ω  ⇔  [ω]ₓ p = −m
    K = np.vstack([_skew(wi) for wi in w])
    p, *_ = np.linalg.lstsq(K, -m.reshape(-1), rcond=None)
    if np.linalg.norm(K @ p + m.reshape(-1)) > 1e-9 * length:
        return None
    return p


def distance_legs(mech) -> DistanceLegs | None:
    """The distance-constraint description of ``mech`` (see :class:`DistanceLegs`), or
    ``None`` when it is not one.

    A leg qualifies when it has six 1-DOF joints, its only actuated joint is prismatic,
    the revolutes before it (at least two, independent) meet at a base point, those
    after it (at least two, independent) meet at a point of the platform, and the
    prismatic axis is the line through both points. Checked at home and at a second
    configuration of the legs.
    """
    if len(mech.legs) != 6 or mech.n_actuated != 6:
        return None
    home = mech.home_assembly
    L = mech.characteristic_length
    base, plat, sign, offset = [], [], [], []
    for leg, q in zip(mech.legs, home.leg_q):
        found = _leg_line(leg, q, L)
        if found is None:
            return None
        a, b_world, s, d = found
        moved = _leg_line(leg, _nudged(leg, q), L)
        if moved is None or np.linalg.norm(moved[0] - a) > 1e-9 * L \
                or abs(moved[3] - d) > 1e-9 * L or moved[2] != s:
            return None
        base.append(a)
        plat.append(home.pose.actInv(b_world))
        sign.append(s)
        offset.append(d)
    return DistanceLegs(np.array(base), np.array(plat), np.array(sign, float),
                        np.array(offset))


def _nudged(leg, q) -> np.ndarray:
    """A second configuration of ``leg`` inside its limits (deterministic)."""
    lo, up = leg._bounds
    step = np.where(np.isfinite(up - lo), 0.1 * np.minimum(up - lo, 2.0), 0.2)
    out = q + step * np.array([0.37, -0.52, 0.61, -0.43, 0.29, 0.55])[:len(q)]
    return leg.clip(np.where(out > up, q - step * 0.5, out))


def _leg_line(leg, q, L):
    """``(base point, platform point (world), sign, offset)`` of a distance leg at
    ``q``, or ``None`` (see :func:`distance_legs`)."""
    if leg.nq != 6 or leg.nv != 6 or len(np.atleast_1d(leg.actuated_v)) != 1:
        return None
    J = leg.jacobian(q).T  # rows: joint twists (ω; v_O)
    p = int(np.atleast_1d(leg.actuated_v)[0])
    if np.linalg.norm(J[p, :3]) > 1e-12 or abs(np.linalg.norm(J[p, 3:]) - 1.0) > 1e-9:
        return None  # the actuated joint is not a unit prismatic
    before, after = J[:p], J[p + 1:]
    if len(before) < 2 or len(after) < 2:
        return None
    for rows in (before, after):
        if np.any(np.abs(np.linalg.norm(rows[:, :3], axis=1) - 1.0) > 1e-9):
            return None  # not all revolute
    a = _concurrent_point(before, L)
    b = _concurrent_point(after, L)
    if a is None or b is None:
        return None
    u = J[p, 3:]
    d = b - a
    if np.linalg.norm(np.cross(d, u)) > 1e-9 * L:
        return None  # the prismatic axis is not the line a–b
    s = 1.0 if d @ u >= 0 else -1.0
    qa = float(np.atleast_1d(q[leg.actuated_q])[0])
    return a, b, s, float(np.linalg.norm(d) - s * qa)


# ======================================================================= homotopy
def _qmul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Quaternion product (w, x, y, z)."""
    return np.r_[p[0] * q[0] - p[1:] @ q[1:], p[0] * q[1:] + q[0] * p[1:] + np.cross(p[1:], q[1:])]


def _conj(q: np.ndarray) -> np.ndarray:
    return np.r_[q[0], -q[1:]]


def _polarise(f, n: int = 8) -> np.ndarray:
    """The symmetric matrix ``Q`` of a quadratic form ``f(x) = xᵀ Q x`` (exact)."""
    eye = np.eye(n)
    d = [f(eye[j]) for j in range(n)]
    Q = np.diag(d)
    for j in range(n):
        for k in range(j):
            Q[j, k] = Q[k, j] = 0.5 * (f(eye[j] + eye[k]) - d[j] - d[k])
    return Q


def study_quadrics(base, platform, lengths) -> np.ndarray:
    """The seven quadrics (7, 8, 8) of the Stewart–Gough forward problem in Study
    parameters ``x = (e0..e3, g0..g3)``: for each leg ``xᵀ Q_i x = |e|² (|R b_i + t −
    a_i|² − l_i²)`` with ``R`` the rotation of the quaternion ``e / |e|`` and ``t = 2
    vec(g ē) / |e|²``, that is ``(|a|² + |b|² − l²) e·e + 4 g·g + 4 (e b)·g − 2 a·(e b
    ē) − 4 a·(g ē)``; the last is the Study quadric ``e · g``."""
    Q = []
    for a, b, l in zip(np.asarray(base, float), np.asarray(platform, float),
                       np.asarray(lengths, float)):
        bh, c = np.r_[0.0, b], a @ a + b @ b - l * l

        def f(x, a=a, bh=bh, c=c):
            e, g = x[:4], x[4:]
            eb = _qmul(e, bh)
            return (c * (e @ e) + 4.0 * (g @ g) + 4.0 * (eb @ g)
                    - 2.0 * (a @ _qmul(eb, _conj(e))[1:]) - 4.0 * (a @ _qmul(g, _conj(e))[1:]))
        Q.append(_polarise(f))
    S = np.zeros((8, 8))
    S[:4, 4:] = S[4:, :4] = 0.5 * np.eye(4)
    return np.array(Q + [S])


@dataclass
class StudySolutions:
    """Result of :func:`stewart_gough_postures`.

    Attributes:
        poses: The real postures (``pin.SE3``, platform frame in the world), sorted.
        complete: Every path reached ``τ = 0`` or the exceptional set ``e = 0``, and the
            nonsingular ends are distinct: ``poses`` holds every real posture.
        paths: Paths tracked (128).
        finite: Nonsingular finite ends (complex postures included; 40 generically).
        at_infinity: Ends on the exceptional set ``e = 0``.
        singular: Finite ends where the Jacobian is singular (a multiple posture).
        failed: Paths whose step size collapsed before the end.
        steps: Predictor–corrector iterations (all paths at once).
    """

    poses: list
    complete: bool
    paths: int
    finite: int
    at_infinity: int
    singular: int
    failed: int
    steps: int
    solutions: np.ndarray = field(repr=False, default=None)


def _track(Q: np.ndarray, rng, h0: float = 0.02, h_max: float = 0.1,
           max_steps: int = 20000):
    """Track the total-degree homotopy of the quadrics ``Q`` (m, n, n), m = n − 1, on a
    random complex chart. Returns ``(X, tau, chart, steps)``: ends and where each path
    stopped (0 when it reached the target system)."""
    m, n = Q.shape[0], Q.shape[1]
    gamma = np.exp(2j * np.pi * rng.uniform())
    chart = rng.normal(size=n) + 1j * rng.normal(size=n)
    D = np.zeros((m, n, n))
    D[:, 0, 0] = -1.0
    for k in range(m):
        D[k, k + 1, k + 1] = 1.0
    signs = np.array(list(itertools.product([1.0, -1.0], repeat=m)))
    X = np.c_[np.ones(len(signs)), signs].astype(complex)
    X /= (X @ chart)[:, None]
    P = len(X)
    tau, h, active = np.ones(P), np.full(P, h0), np.ones(P, bool)

    def residual(X, t):
        F = np.einsum("pi,kij,pj->pk", X, Q, X)
        G = np.einsum("pi,kij,pj->pk", X, D, X)
        return np.c_[(1 - t)[:, None] * F + (gamma * t)[:, None] * G, X @ chart - 1], F, G

    def jac(X, t):
        J = ((1 - t)[:, None, None] * 2 * np.einsum("kij,pj->pki", Q, X)
             + (gamma * t)[:, None, None] * 2 * np.einsum("kij,pj->pki", D, X))
        return np.concatenate([J, np.broadcast_to(chart, (len(X), 1, n))], axis=1)

    def tangent(X, t):  # dx/dτ = −H_x⁻¹ H_τ
        _, F, G = residual(X, t)
        Ht = np.c_[gamma * G - F, np.zeros(len(X))]
        return -np.linalg.solve(jac(X, t), Ht[..., None])[..., 0]

    steps = 0
    with np.errstate(all="ignore"):
        while active.any() and steps < max_steps:
            steps += 1
            idx = np.nonzero(active)[0]
            Xa, ta = X[idx], tau[idx]
            ha = np.minimum(h[idx], ta)
            k1 = tangent(Xa, ta)
            k2 = tangent(Xa - 0.5 * ha[:, None] * k1, ta - 0.5 * ha)
            k3 = tangent(Xa - 0.5 * ha[:, None] * k2, ta - 0.5 * ha)
            k4 = tangent(Xa - ha[:, None] * k3, ta - ha)
            Y = Xa - (ha / 6)[:, None] * (k1 + 2 * k2 + 2 * k3 + k4)
            tn = ta - ha
            ok = np.ones(len(idx), bool)
            prev = None
            for _ in range(3):  # Newton corrector, accepted only while it contracts
                r, _, _ = residual(Y, tn)
                dY = np.linalg.solve(jac(Y, tn), r[..., None])[..., 0]
                Y = Y - dY
                nd = np.linalg.norm(dY, axis=1) / np.linalg.norm(Y, axis=1)
                ok &= (nd < 0.1) if prev is None else ((nd <= 0.5 * prev) | (nd < 1e-9))
                prev = nd
            ok &= (prev < 1e-7) & np.all(np.isfinite(Y), axis=1)
            good, bad = idx[ok], idx[~ok]
            X[good], tau[good] = Y[ok], tn[ok]
            h[good] = np.minimum(h_max, 1.6 * h[good])
            h[bad] *= 0.5
            active[good[tau[good] <= 0.0]] = False
            active[bad[h[bad] < 1e-13]] = False
    return X, tau, chart, steps


def _newton_end(Q, chart, x, iterations: int = 6):
    """Newton's method on the target quadrics at a path's end: ``(x, condition,
    relative residual)``."""
    for _ in range(iterations):
        F = np.einsum("i,kij,j->k", x, Q, x)
        J = np.vstack([2 * np.einsum("kij,j->ki", Q, x), chart])
        r = np.r_[F, x @ chart - 1]
        try:
            x = x - np.linalg.solve(J, r)
        except np.linalg.LinAlgError:
            break
    F = np.einsum("i,kij,j->k", x, Q, x)
    J = np.vstack([2 * np.einsum("kij,j->ki", Q, x), chart])
    return x, np.linalg.cond(J), float(np.abs(F).max() / max(np.linalg.norm(x) ** 2, 1e-300))


def stewart_gough_postures(base, platform, lengths, *, seed: int = 0) -> StudySolutions:
    """Every real posture of a Stewart–Gough platform (six distance constraints) by
    polynomial homotopy in Study parameters (see the module docstring).

    Args:
        base: (6, 3) base points in the world [m].
        platform: (6, 3) platform points in the platform frame [m].
        lengths: (6,) leg lengths (distances) [m].
        seed: Seed of the random ``γ`` and chart (a second seed is tried when the
            first run is not complete).

    Returns:
        :class:`StudySolutions`. The coordinates are centred on the point clouds and
        scaled by their size before solving (unit- and frame-invariant).
    """
    a = np.asarray(base, float)
    b = np.asarray(platform, float)
    lengths = np.asarray(lengths, float)
    if a.shape != (6, 3) or b.shape != (6, 3) or lengths.shape != (6,):
        raise InputError("base and platform must be 6×3 and lengths 6 numbers")
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    s = max(np.abs(a - ca).max(), np.abs(b - cb).max(), np.abs(lengths).max())
    a_, b_, l_ = (a - ca) / s, (b - cb) / s, lengths / s
    Q = study_quadrics(a_, b_, l_)
    reach = float(np.max(np.linalg.norm(a_, axis=1) + np.linalg.norm(b_, axis=1) + np.abs(l_)))
    best = None
    for attempt in range(3):
        rng = np.random.default_rng([seed, attempt])
        X, tau, chart, steps = _track(Q, rng, h_max=0.1 / (1 + 2 * attempt))
        result = _classify(Q, chart, X, tau, reach, steps)
        if best is None or result.complete:
            best = result
        if result.complete:
            break
    poses = []
    for x in best.solutions:
        e, g = x[:4], x[4:]
        n2 = e @ e
        t = 2.0 * _qmul(g, _conj(e))[1:] / n2
        q = e / math.sqrt(n2)
        R = pin.Quaternion(q[0], q[1], q[2], q[3]).toRotationMatrix()
        # back to the world: p = s t_ + ca + R (·) − R cb
        poses.append(pin.SE3(R, s * t + ca - R @ cb))
    best.poses = _sorted_poses(poses)
    return best


def _classify(Q, chart, X, tau, reach, steps) -> StudySolutions:
    """Sort the path ends: nonsingular finite (real ones kept), exceptional (``e`` ≈
    0 against the reach of the legs), singular, failed."""
    finite, real, at_inf, singular, failed = [], [], 0, 0, 0
    bound = 0.1 * 2.0 / reach  # |e| / |g| ≥ 2 / |t| ≥ 2 / reach for a posture
    for x, t in zip(X, tau):
        ratio = np.linalg.norm(x[:4]) / max(np.linalg.norm(x[4:]), 1e-300)
        if t > 0.0:
            if ratio < bound and t < 1e-3:
                at_inf += 1
            else:
                failed += 1
            continue
        x, cond, res = _newton_end(Q, chart, x)
        ratio = np.linalg.norm(x[:4]) / max(np.linalg.norm(x[4:]), 1e-300)
        if ratio < bound:
            at_inf += 1
            continue
        if not (cond < 1e11 and res < 1e-9):
            singular += 1
            continue
        y = x / x[np.argmax(np.abs(x))]
        if any(np.linalg.norm(y - z) < 1e-8 for z in finite):
            failed += 1  # two paths on one nonsingular end: a path jumped
            continue
        finite.append(y)
        if np.linalg.norm(y.imag) <= HOMOTOPY_REAL_TOL * np.linalg.norm(y.real):
            real.append(y.real)
    complete = failed == 0 and singular == 0 and len(finite) + at_inf == len(X)
    return StudySolutions([], complete, len(X), len(finite), at_inf, singular, failed, steps,
                          np.array(real).reshape(-1, 8))


def _sorted_poses(poses) -> list:
    """Poses in a deterministic order: by x, y, z (rounded to 1e-9), then rotation."""
    def key(p):
        return tuple(np.round(np.r_[p.translation, pin.log3(p.rotation)], 9))
    return sorted(poses, key=key)


# ================================================================ the mechanism
def _actuated_limits(mech):
    lo = np.concatenate([leg._bounds[0][leg.actuated_q] for leg in mech.legs])
    up = np.concatenate([leg._bounds[1][leg.actuated_q] for leg in mech.legs])
    return lo, up


def _check_target(mech, q_actuated) -> np.ndarray:
    """The target as an array, refused (ForwardKinematicsError) outside the limits."""
    target = mech.check_actuated(q_actuated)
    lo, up = _actuated_limits(mech)
    names = mech.actuated_names
    for k in range(len(target)):
        if not (lo[k] - TARGET_LIMIT_SLACK <= target[k] <= up[k] + TARGET_LIMIT_SLACK):
            raise ForwardKinematicsError(
                f"{names[k]} = {target[k]:.6g} is outside its joint limits "
                f"[{lo[k]:.6g}, {up[k]:.6g}]: unreachable")
    return target


def _verified(mech, pose, leg_q, target, tol) -> Assembly | None:
    """The assembly polished by the closure solver (mask ACTUATED) from ``pose`` and
    ``leg_q``, or ``None`` when it does not close, miss the target or break a limit."""
    sol = solve_closure(mech, pose, leg_q, ACTUATED, target, tol=0.1 * tol, max_iter=30)
    if sol.closure > max(tol, FK_ACCEPT_FLOOR) or sol.actuated > max(tol, FK_ACCEPT_FLOOR):
        return None
    if not all(leg.within_limits(q) for leg, q in zip(mech.legs, sol.leg_q)):
        return None
    try:
        a = mech.assemble(sol.pose, sol.leg_q, tol=max(tol, CLOSURE_TOL))
    except AssemblyError:
        return None
    err = np.max(np.abs(a.q_actuated - target) / mech.actuated_scales, initial=0.0)
    if err > max(tol, FK_ACCEPT_FLOOR) or not all(
            leg.within_limits(q) for leg, q in zip(mech.legs, a.leg_q)):
        return None
    return a


def _is_new(mech, found, a) -> bool:
    L = mech.characteristic_length
    return all(pose_error(a.pose, b.pose, L) >= SAME_POSE_TOL for b in found)


def _sorted(mech, found) -> list:
    """Assemblies by their distance from the home pose (nearest first; ties by the
    position and rotation vector): a deterministic order."""
    home, L = mech.home_assembly.pose, mech.characteristic_length

    def key(a):
        p = a.pose
        return (round(pose_error(p, home, L), 9),
                *np.round(np.r_[p.translation, pin.log3(p.rotation)], 9))
    return sorted(found, key=key)


def assembly_modes(mech, q_actuated, *, starts: int = 32, seed: int = 0,
                   tol: float = CLOSURE_TOL, max_iter: int = 100, method: str = "auto",
                   patience: int = MODES_PATIENCE, max_batches: int = 40) -> AssemblyModes:
    """Every assembly mode of ``mech`` at ``q_actuated`` (see the module docstring).

    Args:
        mech: The :class:`~pkm_pin.mechanism.Mechanism`.
        q_actuated: Target actuated coordinates.
        starts: Starts per batch of the multistart.
        seed: Seed of the random starts (and of the homotopy's ``γ`` and chart).
        tol: Closure and scaled actuated tolerance of each mode.
        max_iter: Newton iterations of one start.
        method: ``"auto"`` (homotopy for distance legs, else multistart),
            ``"homotopy"`` or ``"multistart"``.
        patience: The multistart stops after this many batches in a row without a new
            mode.
        max_batches: The most batches of the multistart.

    Raises:
        InputError: bad arguments, or ``method="homotopy"`` for a mechanism whose legs
            are not distance constraints.
        ForwardKinematicsError: no assembly mode (the target is unreachable; proven
            when the homotopy was complete), or a target outside the joint limits.
    """
    t0 = time.perf_counter()
    target = _check_target(mech, q_actuated)
    if not isinstance(starts, (int, np.integer)) or starts < 1:
        raise InputError(f"starts must be a positive integer, got {starts!r}")
    if method not in ("auto", "homotopy", "multistart"):
        raise InputError(f"method must be 'auto', 'homotopy' or 'multistart', got {method!r}")
    geometry = distance_legs(mech) if method != "multistart" else None
    if method == "homotopy" and geometry is None:
        raise InputError(f"{mech.name}: the legs are not six distance constraints "
                         "(SPS/UPS lines with an actuated prismatic); use 'multistart'")
    if geometry is not None:
        modes = _homotopy_modes(mech, geometry, target, seed, tol)
    else:
        modes = _multistart_modes(mech, target, starts, seed, tol, max_iter, patience,
                                  max_batches)
    modes.seconds = time.perf_counter() - t0
    if not modes:
        c = modes.counts
        why = (f"proven: the homotopy tracked all {c['paths']} paths, {c['finite']} finite "
               f"postures, {c['real']} real, {c['outside_limits']} outside the joint limits"
               if modes.complete else
               f"none found from {c.get('starts', 0)} starts in {c.get('batches', 0)} "
               "batches (not proven)")
        raise ForwardKinematicsError(
            f"no assembly mode for {mech.actuated_names} = {np.array2string(target, precision=6)}"
            f": the target is unreachable ({why})")
    return modes


def _homotopy_modes(mech, geometry: DistanceLegs, target, seed, tol) -> AssemblyModes:
    """Assembly modes from :func:`stewart_gough_postures`, each polished and checked
    by the closure solver."""
    lengths = geometry.lengths(target)
    sol = stewart_gough_postures(geometry.base, geometry.platform, lengths, seed=seed)
    found, outside = [], 0
    for pose in sol.poses:
        a = _assemble_anywhere(mech, pose, target, tol)
        if a is None:
            outside += 1
        elif _is_new(mech, found, a):
            found.append(a)
    counts = dict(paths=sol.paths, finite=sol.finite, real=len(sol.poses),
                  outside_limits=outside, at_infinity=sol.at_infinity,
                  singular=sol.singular, failed=sol.failed, steps=sol.steps)
    return AssemblyModes(_sorted(mech, found), sol.complete, "homotopy", counts)


def _assemble_anywhere(mech, pose, target, tol) -> Assembly | None:
    """The legs assembled at ``pose`` (from home, then with restarts) and polished."""
    for guess in (None, mech.home_assembly):
        try:
            a = mech.assemble(pose, guess, tol=1e-9, restarts=48)
        except AssemblyError:
            continue
        out = _verified(mech, a.pose, a.leg_q, target, tol)
        if out is not None:
            return out
    return None


def _random_start(mech, rng, P, home, L):
    """One start of the multistart: a pose moved from home by a random twist of the
    platform twist system (homogenised size up to 1.5) and leg configurations (home
    ones or random ones, alternately)."""
    c = rng.normal(size=P.shape[0]) @ P
    size = max(float(np.linalg.norm(c[:3])), float(np.linalg.norm(c[3:])) / L, 1e-300)
    pose = screws.exp(c * rng.uniform(0.0, 1.5) / size) * home.pose
    if rng.uniform() < 0.5:
        legs = [q.copy() for q in home.leg_q]
    else:
        legs = [leg.random_configuration(rng) for leg in mech.legs]
    return pose, legs


def _multistart_modes(mech, target, starts, seed, tol, max_iter, patience,
                      max_batches) -> AssemblyModes:
    """The multistart of the closure solver (see the module docstring)."""
    rng = np.random.default_rng(seed)
    home = mech.home_assembly
    L = mech.characteristic_length
    P = mech.analyze(home).platform_twists
    compiled = True if mech.kernel is not None else None
    found, idle, batches, converged, tried = [], 0, 0, 0, 0
    first = [(home.pose, [q.copy() for q in home.leg_q])]
    while idle < patience and batches < max_batches:
        batches += 1
        new = False
        batch = first + [_random_start(mech, rng, P, home, L) for _ in range(starts)]
        first = []
        for pose, legs in batch:
            tried += 1
            sol = solve_closure(mech, pose, legs, ACTUATED, target, tol=0.1 * tol,
                                max_iter=max_iter, compiled=compiled)
            if sol.closure > 1e-6 or sol.actuated > 1e-6:
                continue
            converged += 1
            a = _verified(mech, sol.pose, sol.leg_q, target, tol)
            if a is not None and _is_new(mech, found, a):
                found.append(a)
                new = True
        idle = 0 if new else idle + 1
    counts = dict(starts=tried, batches=batches, converged=converged)
    return AssemblyModes(_sorted(mech, found), False, "multistart", counts)
