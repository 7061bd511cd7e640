"""A leg: one serial chain from a URDF, its joint twists, tip placement and inverse kinematics.

Conventions: twists are axis-first ``(ω; v_O)`` about the **world** origin
(see :mod:`pkm_pin.screws`); placements are ``pinocchio.SE3`` in the world frame, the
leg's ``base`` placement included; SI units and radians.

The joint twists are the columns of Pinocchio's spatial (``WORLD``) frame Jacobian of
the tip: column ``k`` is the twist of the tip produced by a unit rate of the ``k``-th
velocity coordinate. A mimic pair (a parallelogram written as a revolute plus a
mimicking revolute) therefore contributes one column: the combined twist of the pair.

Pinocchio data (:attr:`Leg.data`) is working state private to each thread: several
threads may use one leg (one mechanism) at once, and a pickled leg carries none. Every
method runs its own Pinocchio pass for the configuration it is given.
"""

from __future__ import annotations

import os
import threading
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
import pinocchio as pin

from . import screws, solve, urdf
from .compiling import prefer_compiled
from .engine.stages import spherical_lines
from .errors import FrameNotFound, InputError, JointNotFound
from .serial import SerialChain
from .solve import LegSolution, closure_error
from .tolerances import (
    CLOSURE_TOL,
    JOINT_LIMIT_SLACK,
    SPHERICAL_AXES_SIN,
    SPHERICAL_OFFSET_RTOL,
)

__all__ = ["Leg", "LegSolution", "pose_error"]


@dataclass(eq=False)
class Leg(SerialChain):
    """One serial chain of a parallel mechanism (or a serial robot on its own).

    Build it with :meth:`from_urdf` or :meth:`from_example_robot_data`. The Pinocchio
    model holds only the chain from the URDF root to ``tip``: joints of other branches
    are locked at their neutral value.

    Attributes:
        model: Pinocchio model of the chain (mimic joints honoured).
        tip: Name of the frame of the chain fixed to the platform (or end effector).
        actuated: Names of the actuated joints, in the order of the actuated coordinates.
        base: Placement of the URDF root in the world.
        name: Name of the leg.
        source: Where the URDF came from (file path or a string label).
        xml: The URDF text (for the geometric parameters of :mod:`pkm_pin.sensitivity`).
        tip_id: Pinocchio frame index of :attr:`tip` (set from the model).
    """

    model: pin.Model
    tip: str
    actuated: tuple[str, ...] = ()
    base: pin.SE3 = field(default_factory=pin.SE3.Identity)
    name: str = "leg"
    source: str = "<model>"
    xml: str | None = field(default=None, repr=False)
    tip_id: int = field(init=False, repr=False)
    #: Per-thread working state: ``_local.data`` is the thread's Pinocchio data.
    _local: threading.local = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.model.existFrame(self.tip):
            raise FrameNotFound(self.tip, self._frame_names(), f"leg {self.name!r}")
        self.tip_id = self.model.getFrameId(self.tip)
        self._local = threading.local()
        self.actuated = tuple(self.actuated)
        for a in self.actuated:
            if a not in self.joint_names:
                raise JointNotFound(a, self.joint_names, f"the chain of leg {self.name!r}")
        if len(set(self.actuated)) != len(self.actuated):
            raise InputError(f"leg {self.name!r}: an actuated joint is listed twice")
        if not isinstance(self.base, pin.SE3):
            raise InputError(f"leg {self.name!r}: base must be a pinocchio.SE3")
        for j in range(1, self.model.njoints):
            jm = self.model.joints[j]
            if jm.nv > 1:
                raise InputError(
                    f"leg {self.name!r}: joint {self.model.names[j]!r} is a "
                    f"{jm.shortname().removeprefix('JointModel')} joint ({jm.nv} DOF): a "
                    "leg's joints move along one coordinate each (revolute, continuous, "
                    "prismatic; a spherical joint as three revolutes). A floating body is "
                    "the platform (pkm_pin.Mechanism) or a tree with closures "
                    "(pkm_pin.load_mechanism of an Extended URDF)")

    # ------------------------------------------------------------------ builders
    @classmethod
    def from_urdf(
        cls,
        source: str | os.PathLike,
        tip: str,
        actuated=(),
        base: pin.SE3 | None = None,
        name: str | None = None,
    ) -> Leg:
        """Leg from a URDF file path or XML text.

        Args:
            source: Path of a ``.urdf`` file, or the URDF text itself.
            tip: Link or frame of the URDF fixed to the platform / end effector.
            actuated: Names of the actuated joints (movable joints of the chain).
            base: Placement of the URDF root in the world (identity by default).
            name: Leg name (default: the robot name of the URDF).

        Raises:
            UrdfError: missing file, malformed XML or structure, unbuildable model.
            FrameNotFound: ``tip`` is not a link or frame of the URDF.
            JointNotFound: an actuated name is not a movable joint from root to tip.
        """
        src = urdf.read(source)
        full = urdf.build_model(src)
        name = name if name is not None else src.robot.name or "leg"
        if isinstance(actuated, str):
            actuated = (actuated,)
        if not full.existFrame(tip):
            raise FrameNotFound(tip, _frame_names(full), f"the URDF {src.label}")
        model = _chain_model(full, tip)
        for a in actuated:
            if not model.existJointName(a) or model.joints[model.getJointId(a)].nv == 0:
                chain = _movable_joint_names(model)
                raise JointNotFound(a, chain, f"the chain from the root to {tip!r} in {src.label}")
        return cls(
            model=model,
            tip=tip,
            actuated=tuple(actuated),
            base=base if base is not None else pin.SE3.Identity(),
            name=name,
            source=src.label,
            xml=src.xml,
        )

    @classmethod
    def from_example_robot_data(
        cls,
        robot: str,
        tip: str | None = None,
        actuated=None,
        base: pin.SE3 | None = None,
        name: str | None = None,
    ) -> Leg:
        """Leg from a robot of the example-robot-data package (``"ur5"``, ``"panda"``…).

        ``tip`` defaults to the robot's flange frame; ``actuated`` to every joint of the
        chain (a serial robot).
        """
        path = urdf.example_robot_path(robot)
        if tip is None:
            if robot not in urdf.EXAMPLE_ROBOTS:
                raise InputError(f"give the tip frame of {robot!r}")
            tip = urdf.EXAMPLE_ROBOTS[robot][1]
        leg = cls.from_urdf(path, tip, () if actuated is None else actuated, base, name or robot)
        return leg if actuated is not None else replace(leg, actuated=tuple(leg.joint_names))

    def _frame_names(self) -> list[str]:
        return _frame_names(self.model)

    # --------------------------------------------------------------- properties
    @cached_property
    def joint_names(self) -> list[str]:
        """Movable joints of the chain (mimicking joints excluded), in velocity order."""
        return _movable_joint_names(self.model)

    @property
    def nq(self) -> int:
        """Dimension of the configuration vector."""
        return self.model.nq

    @property
    def nv(self) -> int:
        """Number of velocity coordinates (the leg's joint twists)."""
        return self.model.nv

    @cached_property
    def actuated_v(self) -> np.ndarray:
        """Velocity indices of the actuated joints, in :attr:`actuated` order."""
        return np.array([self.model.joints[self.model.getJointId(a)].idx_v for a in self.actuated],
                        dtype=int)

    @cached_property
    def passive_v(self) -> np.ndarray:
        """Velocity indices of the passive (not actuated) coordinates."""
        return np.setdiff1d(np.arange(self.nv), self.actuated_v)

    @cached_property
    def actuated_q(self) -> np.ndarray:
        """Configuration indices of the actuated joints (1-DOF joints)."""
        out = []
        for a in self.actuated:
            j = self.model.joints[self.model.getJointId(a)]
            if j.nq != 1:
                raise InputError(f"actuated joint {a!r} of leg {self.name!r} is not a 1-DOF joint")
            out.append(j.idx_q)
        return np.array(out, dtype=int)

    @property
    def lower(self) -> np.ndarray:
        """Lower joint limits (configuration space)."""
        return self.model.lowerPositionLimit

    @property
    def upper(self) -> np.ndarray:
        """Upper joint limits (configuration space)."""
        return self.model.upperPositionLimit

    @cached_property
    def characteristic_length(self) -> float:
        """Sum of the offsets between consecutive joint frames up to the tip [m]
        (:attr:`offset_length`).

        The unit of length for the leg's relative tolerances; 1.0 for a chain with no
        offset at all. For each prismatic joint with finite limits,
        ``(|lower| + |upper|) / 2`` is added.
        """
        return self.offset_length if self.offset_length > 0 else 1.0

    @cached_property
    def offset_length(self) -> float:
        """:attr:`characteristic_length` without the 1.0 of a chain with no offset (0.0
        then): a mechanism averages the legs that have a length
        (:attr:`pkm_pin.Mechanism.characteristic_length`)."""
        L = sum(np.linalg.norm(self.model.jointPlacements[j].translation)
                for j in range(1, self.model.njoints))
        L += np.linalg.norm(self.model.frames[self.tip_id].placement.translation)
        for j in self._prismatic_joints:
            iq = self.model.joints[j].idx_q
            lo, up = self.lower[iq], self.upper[iq]
            if np.isfinite(lo) and np.isfinite(up):
                L += 0.5 * (abs(lo) + abs(up))
        return float(L)

    @cached_property
    def reach(self) -> tuple[float, float]:
        """``(r_min, r_max)``: bounds of the distance between the root's origin and the
        tip frame's origin over every configuration within the limits (the triangle
        inequality over the offsets on the path to the tip, a prismatic joint adding its
        stroke; with one prismatic joint whose stroke keeps a sign, ``r_min`` is that
        stroke's least length less every offset). ``(0, inf)`` when a joint on the path
        is not a revolute, continuous, spherical or bounded prismatic joint (a mimic
        joint, a free flyer …): no bound is claimed. A pose whose tip target lies
        outside them cannot be reached, whatever a solver would do."""
        m = self.model
        path = [j for j in m.supports[m.frames[self.tip_id].parentJoint] if j > 0]
        offsets = float(np.linalg.norm(m.frames[self.tip_id].placement.translation))
        strokes = []
        for j in path:
            offsets += float(np.linalg.norm(m.jointPlacements[j].translation))
            name = m.joints[j].shortname()
            if j in self._prismatic_joints:
                lo, up = self.lower[m.joints[j].idx_q], self.upper[m.joints[j].idx_q]
                if not (np.isfinite(lo) and np.isfinite(up)):
                    return 0.0, np.inf
                strokes.append((0.0 if lo <= 0.0 <= up else min(abs(lo), abs(up)),
                                max(abs(lo), abs(up))))
            elif "Mimic" in name or not name.startswith(("JointModelR", "JointModelSpherical")):
                return 0.0, np.inf
        r_max = offsets + sum(hi for _, hi in strokes)
        r_min = max(0.0, strokes[0][0] - offsets) if len(strokes) == 1 else 0.0
        return float(r_min), float(r_max)

    @cached_property
    def _prismatic_joints(self) -> list[int]:
        """Joint indices of the 1-DOF prismatic joints of the chain (aligned or not;
        mimicking joints excluded)."""
        m = self.model
        return [j for j in range(1, m.njoints)
                if m.joints[j].nq == 1 and m.joints[j].nv == 1
                and "P" in m.joints[j].shortname().replace("Mimic", "")]

    # ------------------------------------------------------------ configurations
    def neutral(self) -> np.ndarray:
        """Neutral configuration, moved inside the joint limits where it lies outside."""
        return self.clip(pin.neutral(self.model))

    @cached_property
    def _bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Limits used for projection: those of 1-DOF joints (revolute, prismatic);
        unbounded for the others (continuous joints, free flyers)."""
        lo = np.full(self.nq, -np.inf)
        up = np.full(self.nq, np.inf)
        for j in range(1, self.model.njoints):
            jm = self.model.joints[j]
            if jm.nq == 1 and jm.nv == 1:
                lo[jm.idx_q] = self.model.lowerPositionLimit[jm.idx_q]
                up[jm.idx_q] = self.model.upperPositionLimit[jm.idx_q]
        return lo, up

    def clip(self, q: np.ndarray) -> np.ndarray:
        """Project ``q`` onto the joint limits of the 1-DOF joints."""
        return np.clip(q, *self._bounds)

    def within_limits(self, q: np.ndarray, tol: float = JOINT_LIMIT_SLACK) -> bool:
        """Whether ``q`` respects the joint limits (with absolute slack ``tol``)."""
        lo, up = self._bounds
        return bool(np.all(q >= lo - tol) and np.all(q <= up + tol))

    def at_a_limit(self, q: np.ndarray) -> bool:
        """Whether a joint of ``q`` sits exactly at a bound of its limits (where
        :meth:`clip` puts a joint that a solver's step would take beyond it)."""
        lo, up = self._bounds
        return bool(np.any((q <= lo) | (q >= up)))

    def random_configuration(self, rng: np.random.Generator) -> np.ndarray:
        """A configuration drawn uniformly inside the limits (infinite limits: ±π)."""
        lo, up = self._bounds
        q = rng.uniform(np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(up), up, np.pi))
        return pin.normalize(self.model, q) if self.model.nq != self.model.nv else q

    def check_q(self, q, name: str = "q") -> np.ndarray:
        """``q`` as a finite float array of shape (nq,), or a specific :class:`InputError`."""
        return screws.as_vector(q, self.nq, f"{name} of leg {self.name!r}",
                                f"joints {self.joint_names}")

    # ---------------------------------------------------------------- kinematics
    @property
    def data(self) -> pin.Data:
        """Pinocchio data of :attr:`model` private to the calling thread (made on the
        thread's first use). Methods that fill it return it: read it before the next
        Pinocchio call on this leg."""
        local = self._local
        try:
            return local.data
        except AttributeError:
            local.data = self.model.createData()
            return local.data

    def _jacobian_pass(self, q: np.ndarray) -> pin.Data:
        """The calling thread's data after one pass at ``q``: joint placements and
        Jacobians, and the tip frame's placement."""
        data = self.data
        pin.computeJointJacobians(self.model, data, q)
        pin.updateFramePlacement(self.model, data, self.tip_id)
        return data

    def _world_jacobian(self, data: pin.Data) -> np.ndarray:
        """The tip's 6×nv axis-first world Jacobian from ``data`` filled by
        :meth:`_jacobian_pass`."""
        J = pin.getFrameJacobian(self.model, data, self.tip_id, pin.WORLD).reshape(6, -1)
        rows = np.empty((self.nv, 6))
        screws.world_twist_rows(J, self.base.homogeneous, rows)
        return rows.T

    def tip_placement(self, q) -> pin.SE3:
        """World placement of the tip frame (base placement included)."""
        q = self.check_q(q)
        data = self.data
        pin.framesForwardKinematics(self.model, data, q)
        return self.base * data.oMf[self.tip_id]

    def kinematics(self, q) -> tuple[pin.SE3, np.ndarray]:
        """Tip placement and the 6×nv axis-first world Jacobian, from one Pinocchio pass."""
        data = self._jacobian_pass(self.check_q(q))
        return self.base * data.oMf[self.tip_id], self._world_jacobian(data)

    def jacobian(self, q) -> np.ndarray:
        """Spatial Jacobian, 6×nv, axis-first: column k is the twist (ω; v_O) of joint k."""
        return self.kinematics(q)[1]

    def joint_twists(self, q) -> np.ndarray:
        """Joint twists (nv × 6), axis-first, about the world origin (rows of Jᵀ)."""
        return self.jacobian(q).T

    def joint_origins(self, q) -> np.ndarray:
        """World positions of the joint frames of the chain at ``q``, (njoints − 1) × 3."""
        q = self.check_q(q)
        data = self.data
        pin.forwardKinematics(self.model, data, q)
        return np.array([(self.base * data.oMi[j]).translation
                         for j in range(1, self.model.njoints)])

    @cached_property
    def spherical_groups(self) -> list[tuple[int, int, int]]:
        """Velocity indices of runs of three revolutes that form a spherical joint.

        Three consecutive 1-DOF revolute joints whose frames coincide (zero offsets
        between them: concurrent axes) are a spherical joint written with three
        coordinates when they are also

        * passive (none actuated, none mimic-coupled): an actuated revolute among
          concurrent ones is a joint of its own (the agile eye's base revolutes), and
          replacing its twist would change the actuation wrench;
        * independent: consecutive axes are not parallel (the angle between consecutive
          axes is fixed by the joint placement), so the three axes span space away from
          the gimbal lock.

        Such a spherical joint loses rank only through its parametrisation (the gimbal
        lock); the analysis replaces its twists by three orthogonal lines through the
        centre. Other concurrent revolutes keep their own twists.
        """
        m = self.model
        coupled = {m.joints[j].idx_v for j in range(1, m.njoints) if m.joints[j].nv == 0}
        actuated = set(np.atleast_1d(self.actuated_v).tolist())
        axes = self._joint_axes()
        rev = []
        for j in range(1, m.njoints):
            jm = m.joints[j]
            short = jm.shortname()
            rev.append(jm.nv == 1 and short.startswith("JointModelR") and "UB" not in short
                       and jm.idx_v not in coupled and jm.idx_v not in actuated)
        L = self.characteristic_length
        groups, j = [], 1
        while j + 2 < m.njoints:
            trio = (j, j + 1, j + 2)
            if all(rev[k - 1] for k in trio) and all(
                m.parents[k] == k - 1
                and np.linalg.norm(m.jointPlacements[k].translation) <= SPHERICAL_OFFSET_RTOL * L
                and np.linalg.norm(np.cross(axes[k - 1], m.jointPlacements[k].rotation
                                            @ axes[k])) > SPHERICAL_AXES_SIN
                for k in trio[1:]
            ):
                groups.append(tuple(m.joints[k].idx_v for k in trio))
                j += 3
            else:
                j += 1
        return groups

    def _joint_axes(self) -> dict[int, np.ndarray]:
        """Axis (unit, in the joint's own frame) of every 1-DOF joint, from its motion
        subspace in Pinocchio (the angular part for a revolute)."""
        m = self.model
        data = m.createData()
        pin.computeJointJacobians(m, data, pin.neutral(m))
        axes = {}
        for j in range(1, m.njoints):
            jm = m.joints[j]
            if jm.nv == 1:
                S = np.reshape(pin.getJointJacobian(m, data, j, pin.LOCAL), (6, -1))[:, jm.idx_v]
                w = screws.from_pinocchio(S)[:3]
                axes[j] = w / np.linalg.norm(w) if np.linalg.norm(w) > 0 else w
        return axes

    def motion_twists(self, q) -> np.ndarray:
        """Joint twists (nv × 6) with spherical groups replaced by 3 orthogonal lines.

        Same span as :meth:`joint_twists` away from the gimbal lock of the spherical
        groups; at the gimbal lock the true (3-dimensional) span of the spherical joint.
        """
        return self.screws(q)[1]

    def screws(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Jacobian (6 × nv) and motion twists (nv × 6, see :meth:`motion_twists`) at
        ``q`` from a single Pinocchio pass."""
        data = self._jacobian_pass(self.check_q(q))
        J = self._world_jacobian(data)
        T = np.empty((self.nv, 6))
        groups = np.array(self.spherical_groups, dtype=np.int64).reshape(-1, 3)
        spherical_lines(np.ascontiguousarray(J.T), groups, T, np.empty((3, 3)), np.empty(3),
                        np.empty(3))
        return J, T

    # -------------------------------------------------------------------- pickle
    def __getstate__(self) -> dict:
        """The description only: no Pinocchio data, no cached values. A model with
        mimic joints travels as its URDF text and is built again on unpickling:
        Pinocchio 4.1 unpickles ``JointModelMimic`` into a model that crashes the first
        kinematics pass (a segmentation fault: every process-pool or Dask sweep of a
        Delta died of it)."""
        state = {k: v for k, v in self.__dict__.items()
                 if k != "_local"
                 and not isinstance(getattr(type(self), k, None), cached_property)}
        if self.xml is not None and self.has_mimic:
            state["model"] = None
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        if self.model is None:  # built again from the URDF text (see __getstate__)
            self.model = _chain_model(urdf.build_model(urdf.read(self.xml)), self.tip)
        self._local = threading.local()

    # ----------------------------------------------------------------------- IK
    def solve(
        self,
        target: pin.SE3,
        q0=None,
        *,
        tol: float = CLOSURE_TOL,
        max_iter: int = 100,
        restarts: int = 24,
        seed: int = 0,
        compiled: bool | None = None,
    ) -> LegSolution:
        """Joint configuration placing the tip at ``target`` (world), inside the limits.

        The closure solver of :mod:`pkm_pin.solve` with mask LEGS: damped
        (Levenberg–Marquardt) Newton on the residual :func:`pkm_pin.solve.closure_error`
        (world rotation vector [rad] and tip displacement / the characteristic length;
        damping :func:`pkm_pin.tolerances.damping`), dimensionless unknowns, each step
        projected onto the joint limits, warm started from ``q0`` (default: neutral). If
        it stalls above ``tol`` (a local minimum, a limit), it restarts from
        :func:`pkm_pin.solve.start_configurations` (the neutral configuration, the middle
        of the limits and ``restarts`` configurations drawn with ``seed``) and returns
        the best result found. It never raises for an unreachable target: check
        :attr:`LegSolution.converged`.

        ``compiled``: the compiled driver (:func:`pkm_pin.solve.solve_from`) when the
        chain has a kernel, its result evaluated again (and a near miss polished) by
        Pinocchio; else the Python driver (Pinocchio). Default (None): compiled once the
        compiled solver is ready or has been asked for repeatedly
        (:func:`pkm_pin.compiling.prefer_compiled`: a one-off solve does not wait for its
        compilation).
        """
        if not isinstance(target, pin.SE3):
            raise InputError(f"the target of leg {self.name!r} must be a pinocchio.SE3")
        if not (np.all(np.isfinite(target.translation)) and np.all(np.isfinite(target.rotation))):
            raise InputError(f"the target of leg {self.name!r} must be finite, got\n{target}")
        warm = self.neutral() if q0 is None else self.clip(self.check_q(q0, "q0"))
        if compiled is None:
            compiled = self.kernel is not None and prefer_compiled(solve.solve_from)
        best = solve.solve_leg(self, target, warm, tol=tol, max_iter=max_iter,
                               compiled=compiled)
        if best.converged:
            return best
        starts = solve.start_configurations(self, None, restarts, seed)
        if q0 is None:
            starts = starts[1:]  # the neutral configuration was the first attempt
        sol = solve.solve_leg(self, target, starts, tol=tol, max_iter=max_iter,
                              compiled=compiled)
        sol.iterations += best.iterations
        if sol.residual < best.residual:
            return sol
        best.iterations = sol.iterations
        return best

    @cached_property
    def kernel(self):
        """Compiled kinematics of the chain (:mod:`pkm_pin.kernels`), or None."""
        from .kernels import chain_kernel

        return chain_kernel(self)

    @cached_property
    def has_mimic(self) -> bool:
        """Whether a joint of the chain mimics another (a parallelogram written as a
        revolute and its mimicking revolute; cached)."""
        return any(j.shortname() == "JointModelMimic" for j in self.model.joints)

    @cached_property
    def _velocity_units(self) -> np.ndarray:
        """Unit of each velocity coordinate: the characteristic length for a prismatic
        joint, 1 rad otherwise (the closure solver's unknowns are the increments divided
        by it; the compiled kernel takes the same array)."""
        units = np.ones(self.nv)
        for j in self._prismatic_joints:
            units[self.model.joints[j].idx_v] = self.characteristic_length
        return units


# ---------------------------------------------------------------------- helpers
def pose_error(current: pin.SE3, target: pin.SE3, length: float) -> float:
    """Relative distance between two placements: the norm of the closure residual
    :func:`pkm_pin.solve.closure_error` (world rotation vector of ``R_target R_currentᵀ``
    [rad], displacement divided by ``length`` [m]), the residual of :meth:`Leg.solve`."""
    return float(closure_error(current.homogeneous, target.homogeneous, length, np.empty(6)))


def _frame_names(model: pin.Model) -> list[str]:
    return [f.name for f in model.frames if f.type != pin.FrameType.JOINT and f.name != "universe"]


def _movable_joint_names(model: pin.Model) -> list[str]:
    return [model.names[j] for j in range(1, model.njoints) if model.joints[j].nv > 0]


def _joint_of_v(model: pin.Model, idx_v: int) -> int:
    for j in range(1, model.njoints):
        if model.joints[j].nv > 0 and model.joints[j].idx_v == idx_v:
            return j
    raise InputError(f"no joint has velocity index {idx_v}")


def _chain_model(full: pin.Model, tip: str) -> pin.Model:
    """The chain from the root to ``tip``: joints of other branches locked at neutral."""
    parent = full.frames[full.getFrameId(tip)].parentJoint
    chain = set(full.supports[parent])
    # a mimicking joint on the chain (nv = 0) needs its primary joint, wherever it is
    for j in list(chain):
        if j > 0 and full.joints[j].nv == 0 and full.joints[j].nq == 0:
            chain.add(_joint_of_v(full, full.joints[j].idx_v))
    lock = [j for j in range(1, full.njoints) if j not in chain]
    if not lock:
        return full
    q_ref = pin.neutral(full)
    q_ref = np.clip(q_ref, full.lowerPositionLimit, full.upperPositionLimit)
    return pin.buildReducedModel(full, lock, q_ref)
