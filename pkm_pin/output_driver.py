"""Output coordinates on a closure model's tree: the output frame's pose coordinates
``c = (x, y, z, roll, pitch, yaw)`` (position [model length unit], URDF roll, pitch, yaw
[rad] of the output frame, world), their rates and accelerations
(:class:`OutputCoordinates`), and the tree solved for some of them
(:class:`OutputDriver`, :func:`partial_pose`): a motion given by output coordinates
(:mod:`pkm_pin.trajectory`) and a partial output pose of a linkage without legs
(:meth:`Linkage.inverse_kinematics <pkm_pin.linkage.Linkage.inverse_kinematics>`).

Rows are dimensionless: the closure rows as :meth:`ClosureModel.closure_residual`, the
coordinate rows divided by :func:`pkm_pin.solve.coordinate_scales` (the characteristic
length for positions, 1 for angles), angle errors wrapped to (−π, π].
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pinocchio as pin

from . import output_kernel as ok
from . import screws
from . import tree_kernel as tk
from .compiling import prefer_compiled
from .errors import InputError
from .model.closure_model import ClosureModel
from .solve import (
    POSE_COORDINATES,
    coordinate_scales,
    pose_coordinates,
    tree_limits,
    tree_step,
)
from .tolerances import CLOSURE_TOL, RANK_RTOL


class OutputCoordinates:
    """The output frame's pose coordinates on a closure model's tree and their first
    and second derivatives (Pinocchio's frame Jacobian, velocity and accelerations):
    ``c = (p; rpy)``, ``ċ = K v`` with ``K = [J_p; E(rpy)⁻¹ J_ω]`` (``ω = E ṙ``, world),
    ``c̈ = K a + κ(q, v)``, ``κ = (p̈₀; E⁻¹ (ω̇₀ − Ė ṙ))`` where ``p̈₀``, ``ω̇₀`` are the
    origin's classical and the frame's angular acceleration at ``a = 0``."""

    def __init__(self, model: ClosureModel):
        self.model, self.tree = model, model.tree
        self.data = model.tree.createData()
        self.fid = model.tree.getFrameId(model.output)
        self.scales = coordinate_scales(model.length)

    def values(self, q) -> np.ndarray:
        pin.framesForwardKinematics(self.tree, self.data, q)
        return pose_coordinates(self.data.oMf[self.fid])

    def rates(self, q) -> tuple[np.ndarray, np.ndarray]:
        """``(c, K)`` at ``q``, physical units (6,), (6 × nv)."""
        tree, data = self.tree, self.data
        pin.computeJointJacobians(tree, data, q)
        pin.updateFramePlacements(tree, data)
        c = pose_coordinates(data.oMf[self.fid])
        J = pin.getFrameJacobian(tree, data, self.fid, pin.LOCAL_WORLD_ALIGNED)
        K = np.vstack([J[:3], pin.rpy.computeRpyJacobianInverse(c[3:], pin.WORLD) @ J[3:]])
        return c, K

    def drift(self, q, v) -> np.ndarray:
        """``κ(q, v)`` (6,): ``c̈`` at ``a = 0``."""
        tree, data, f = self.tree, self.data, self.fid
        pin.forwardKinematics(tree, data, q, v, np.zeros(tree.nv))
        pin.updateFramePlacements(tree, data)
        rpy = pin.rpy.matrixToRpy(data.oMf[f].rotation)
        w = pin.getFrameVelocity(tree, data, f, pin.LOCAL_WORLD_ALIGNED).angular
        Einv = pin.rpy.computeRpyJacobianInverse(rpy, pin.WORLD)
        rd = Einv @ w
        Ed = pin.rpy.computeRpyJacobianTimeDerivative(rpy, rd, pin.WORLD)
        lin = pin.getFrameClassicalAcceleration(tree, data, f, pin.LOCAL_WORLD_ALIGNED).linear
        ang = pin.getFrameAcceleration(tree, data, f, pin.LOCAL_WORLD_ALIGNED).angular
        return np.r_[lin, Einv @ (ang - Ed @ rd)]


class OutputDriver:
    """The rows of a problem given by output coordinates (``coordinates``, among
    :data:`~pkm_pin.solve.POSE_COORDINATES`): the given ones, then with ``hold`` the held
    ones (as many of the others as make the rows span the output's motion, held at their
    values at ``q0``: a motion of :class:`pkm_pin.trajectory.OutputMotion`), chosen at
    ``q0`` (dimensionless: coordinates divided by
    :func:`pkm_pin.solve.coordinate_scales`, velocity coordinates by the units).
    Without ``hold`` the other coordinates are free (a partial output pose)."""

    def __init__(self, model: ClosureModel, coordinates, q0: np.ndarray, *,
                 hold: bool = True):
        self.model, self.oc = model, OutputCoordinates(model)
        coordinates = tuple(coordinates)
        unknown = [c for c in coordinates if c not in POSE_COORDINATES]
        if unknown or not coordinates or len(set(coordinates)) < len(coordinates):
            raise InputError(f"output coordinates must be distinct names among "
                             f"{', '.join(POSE_COORDINATES)}; got {', '.join(coordinates)}")
        given = [POSE_COORDINATES.index(c) for c in coordinates]
        if model.output_point and max(given) > 2:
            raise InputError(f"the output of {model.name or 'the model'} is a point: give "
                             "x, y, z only")
        c0, K = self.oc.rates(q0)
        U = model.velocity_units
        Jc = model.closure_jacobian(q0) * U
        rank, _, _, Vt = screws.svd_rank(Jc, RANK_RTOL) if Jc.size else (0, 0, 0,
                                                                           np.eye(model.nv))
        G = (K / self.oc.scales[:, None] * U) @ Vt[rank:].T
        top = max(float(np.linalg.norm(G, 2)), 1e-300)

        def rank_of(rows):
            s = np.linalg.svd(G[rows], compute_uv=False) if rows else np.zeros(0)
            return int(np.sum(s > 1e-6 * top))
        if rank_of(given) < len(given):
            raise InputError(
                f"the output coordinates {', '.join(coordinates)} are not independent "
                f"for {model.name or 'the model'} (its output moves in {rank_of(list(range(6)))}"
                " dimensions): give fewer, or others")
        rows, full = list(given), rank_of(list(range(6)))
        for k in range(6 if hold else 0):
            if len(rows) < full and k not in rows and rank_of(rows + [k]) > len(rows):
                rows.append(k)
        self.rows, self.n_given, self.held = np.array(rows), len(given), c0[rows[len(given):]]
        self.names = tuple(POSE_COORDINATES[k] for k in rows)

    def targets(self, C, Cd, Cdd) -> tuple:
        """The targets of every row (given, then held) over the samples."""
        n, h = C.shape[0], len(self.held)
        return (np.c_[C, np.tile(self.held, (n, 1))], np.c_[Cd, np.zeros((n, h))],
                np.c_[Cdd, np.zeros((n, h))])

    def position(self, guess, target, tol: float, compiled: bool | None = None
                 ) -> tuple[np.ndarray, float]:
        """:meth:`position_reference` compiled (:mod:`pkm_pin.output_kernel`) where the
        tree kernel represents the model (``compiled`` True: so; None: when that code is
        ready, :func:`pkm_pin.compiling.prefer_compiled`; False: the Python reference);
        the steps taken are kept in ``iterations``."""
        kern = tk.tree_kernel(self.model) if compiled is not False and tk.ENABLED else None
        if kern is None or not (compiled or prefer_compiled(ok.solve_output_kernel)):
            return self.position_reference(guess, target, tol)
        rows = self.rows.astype(np.int64)
        q, info = np.array(guess, dtype=float), np.empty(2)
        lo, up = tree_limits(self.model)
        ok.SOLVE_OUTPUT(kern, q, rows, np.asarray(target, dtype=float),
                        np.ascontiguousarray(self.oc.scales[rows]), np.asarray(lo, float),
                        np.asarray(up, float), float(tol), 100, info)
        self.iterations = int(info[1])
        return q, float(info[0])

    def position_reference(self, guess, target, tol: float) -> tuple[np.ndarray, float]:
        """Damped Newton (Levenberg–Marquardt as :func:`pkm_pin.solve.solve_tree`:
        damping :func:`~pkm_pin.newton.lm_damping`, steps at most
        :data:`~pkm_pin.newton.TREE_MAX_STEP`, dimensionless) on the closure rows and
        the coordinate rows (angles wrapped) from ``guess``: ``(q, residual)``."""
        model, rows, s = self.model, self.rows, self.oc.scales[self.rows]
        q = guess.copy()
        lo, up = tree_limits(model)
        for self.iterations in range(100):  # the steps taken, kept for an error message
            c, K = self.oc.rates(q)
            e = np.r_[model.closure_residual(q), coordinate_errors_of(c[rows], target, rows) / s]
            r = float(np.abs(e).max(initial=0.0))
            if r <= tol:
                break
            H = np.vstack([model.closure_jacobian(q), K[rows] / s[:, None]])
            q, _ = tree_step(model, q, e, H, None, r, lo, up)
        return q, r

    def rhs(self, q, v, cdd) -> np.ndarray:
        """The dimensionless right-hand side of the coordinate rows of ``[J; K] a``."""
        s = self.oc.scales[self.rows]
        return (cdd - self.oc.drift(q, v)[self.rows]) / s


def coordinate_errors_of(c, target, rows) -> np.ndarray:
    """``c − target`` with the angle rows wrapped to (−π, π]."""
    d = np.asarray(c, float) - target
    angle = np.asarray(rows) >= 3
    d[angle] = (d[angle] + np.pi) % (2 * np.pi) - np.pi
    return d


def partial_pose(model: ClosureModel, values: Mapping, q0, tol: float = CLOSURE_TOL
                 ) -> tuple[np.ndarray, float, int]:
    """``(q, residual, iterations)``: the tree configuration nearest ``q0`` (damped Newton from it,
    :meth:`OutputDriver.position`) that closes the loops and puts the output frame's
    coordinates named in ``values`` (a mapping of some of x, y, z, roll, pitch, yaw to
    values) at those values, the other coordinates free; ``residual``: the largest
    dimensionless row (module docstring), at most ``tol`` when it converged.

    Raises:
        InputError: an unknown coordinate, a value that is not a finite number, or
            coordinates the output cannot move along independently at ``q0``.
    """
    names = tuple(str(k).strip().lower() for k in values)
    try:
        target = np.array([float(v) for v in values.values()])
    except (TypeError, ValueError) as e:
        raise InputError(f"a partial pose maps coordinate names to numbers; got {e}") from e
    if not np.isfinite(target).all():
        raise InputError(f"a partial pose needs finite values; got {dict(zip(names, target))}")
    q0 = model.check_q(q0)
    driver = OutputDriver(model, names, q0, hold=False)
    q, r = driver.position(q0, target, tol)
    return q, r, driver.iterations
