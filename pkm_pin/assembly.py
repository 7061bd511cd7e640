"""Assemblies of a mechanism and the platform poses they are built from.

An :class:`Assembly` is one solution of a mechanism's closure equations, whichever
backend found it: the tree's configuration and the output pose, with one configuration
per leg where the mechanism is read per leg. :func:`placement` and :func:`as_pose` turn the
forms a pose is given in (``pin.SE3``, a 4×4 matrix, x, y, z, roll, pitch, yaw) into a
``pin.SE3``.

This module imports no other module of the mechanism's solvers: position, sensitivity,
sweep and calibration build their results from it without importing
:mod:`pkm_pin.mechanism`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .errors import InputError, InvalidAssembly
from .screws import as_float_array
from .tolerances import ASSEMBLY_CHECK_RTOL, JOINT_LIMIT_SLACK, ROTATION_MATRIX_ATOL

if TYPE_CHECKING:  # pragma: no cover
    pass


def placement(xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0)) -> pin.SE3:
    """``pin.SE3`` from a translation [m] and URDF roll-pitch-yaw angles [rad]."""
    xyz = as_float_array(xyz, "xyz")
    rpy = as_float_array(rpy, "rpy")
    if xyz.shape != (3,) or rpy.shape != (3,):
        raise InputError(f"xyz and rpy must have 3 values each, got {xyz.shape} and {rpy.shape}")
    if not (np.all(np.isfinite(xyz)) and np.all(np.isfinite(rpy))):
        raise InputError(f"xyz and rpy must be finite, got {xyz} and {rpy}")
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), xyz)


def as_pose(pose) -> pin.SE3:
    """A platform pose from a ``pin.SE3``, a 4×4 matrix, or 6 numbers
    (x, y, z, roll, pitch, yaw)."""
    if isinstance(pose, pin.SE3):
        # an SE3 is approximately itself exactly when its entries are finite (a nan
        # compares false, and inf − inf is nan): one Pinocchio call, 10× cheaper
        # than numpy's isfinite on the 4×4 matrix
        if not pose.isApprox(pose):
            raise InputError("the pose must be finite")
        return pose
    a = as_float_array(pose, "pose")
    if a.shape == (6,):
        return placement(a[:3], a[3:])
    if a.shape == (4, 4):
        if not np.all(np.isfinite(a)):
            raise InputError("the pose must be finite")
        R = a[:3, :3]
        if not np.allclose(R @ R.T, np.eye(3), atol=ROTATION_MATRIX_ATOL) or np.linalg.det(R) < 0:
            raise InputError("the 4×4 pose has no rotation matrix in its upper-left block")
        return pin.SE3(R, a[:3, 3])
    raise InputError(
        "a pose is a pinocchio.SE3, a 4×4 homogeneous matrix or 6 numbers "
        f"(x, y, z, roll, pitch, yaw); got shape {a.shape}"
    )


class Assembly:
    """One assembled configuration of a mechanism, whichever backend reads it: the
    configuration of the mechanism's whole Pinocchio tree (:attr:`q`), the output frame's
    placement (:attr:`pose`), and, where the mechanism is read per leg, one configuration
    per leg (:attr:`leg_q`).

    Made by the mechanism (``assemble``, ``forward_kinematics``, ``assembly_at`` …), not
    by hand, except as a guess (``Assembly(mech, pose, leg_q)``, checked before it is
    analysed: :func:`checked_twists`). Not meant to be modified in place.

    Attributes:
        mechanism: What made it: the per-leg :class:`~pkm_pin.Mechanism`, or the general
            backend (:class:`~pkm_pin.linkage.Linkage`, ``mechanism.general``) that solved
            the tree.
        pose: World placement of the output (platform) frame (``pin.SE3``).
        leg_q: The per-leg view: one configuration per leg (legs in mechanism order), or
            ``None`` for an assembly of the general backend (no legs read).
        residual: Largest residual of the solve (closures, targets; dimensionless).
        info: Free-form details from the solver that made it (``"iterations"`` …).
        joint_twists: The legs' joint twists at ``leg_q`` (nv × 6 rows, axis-first,
            world origin), from the Pinocchio pass that verified the closure, or None
            (then the analysis computes them).
    """

    def __init__(self, mechanism, pose: pin.SE3, leg_q: list | None = None,
                 residual: float = 0.0, info: dict | None = None,
                 joint_twists: np.ndarray | None = None):
        self.mechanism = mechanism
        self.pose = pose
        self.leg_q = leg_q
        self.residual = residual
        self.info = {} if info is None else info
        self.joint_twists = joint_twists

    @classmethod
    def of_tree(cls, mechanism, q: np.ndarray, residual: float, iterations: int,
                closure_residuals: dict, q_actuated: np.ndarray, pose: pin.SE3) -> Assembly:
        """An assembly of the general backend ``mechanism`` at the tree configuration
        ``q``, every value given (no per-leg view; one dict update, no checks: ~1 µs of a
        warm forward kinematics)."""
        out = cls.__new__(cls)
        out.__dict__.update(mechanism=mechanism, pose=pose, leg_q=None, residual=residual,
                            info={"iterations": iterations}, joint_twists=None, _tree_q=q,
                            _q_actuated=q_actuated, _closure_residuals=closure_residuals)
        return out

    def __repr__(self) -> str:
        reading = "per leg" if self.leg_q is not None else "general"
        return (f"Assembly({getattr(self.mechanism, 'name', '')!r}, {reading}, "
                f"residual={self.residual:.3g})")

    @property
    def per_leg(self) -> bool:
        """Whether it has a per-leg view (:attr:`leg_q`)."""
        return self.leg_q is not None

    @property
    def q(self) -> np.ndarray:
        """Configuration of the mechanism's whole Pinocchio tree (``mechanism.model.tree``,
        its joint order; for a per-leg one :meth:`Mechanism.tree_configuration`, computed
        from the legs and the pose once, then kept): the order in which the general
        backend and :meth:`Mechanism.inverse_dynamics` take ``q``."""
        q = self.__dict__.get("_tree_q")
        if q is None:
            if self.leg_q is None:
                raise InvalidAssembly("the assembly has neither leg configurations (leg_q) "
                                      "nor the tree's configuration; make it with the "
                                      "mechanism (assemble, assembly_at)")
            q = self.__dict__["_tree_q"] = self.mechanism.tree_configuration(self)
        return q

    @property
    def q_actuated(self) -> np.ndarray:
        """Actuated coordinates [rad or m], in the mechanism's actuated order (per leg:
        legs in mechanism order, each in its ``actuated`` order; general: the model's,
        NaN where an actuated joint has no single value)."""
        q = self.__dict__.get("_q_actuated")
        if q is None:
            q = np.concatenate([q[leg.actuated_q] for leg, q in
                                zip(self.mechanism.legs, self.leg_q)]) \
                if self.leg_q else np.zeros(0)
        return q

    @property
    def output_pose(self) -> pin.SE3:
        """The output (platform) frame's world placement: :attr:`pose`."""
        return self.pose

    @property
    def iterations(self) -> int:
        """Newton steps the solve spent, all restarts included (0: not recorded)."""
        return int(self.info.get("iterations", 0))

    @property
    def closure_residuals(self) -> dict:
        """Norm of each closure's residual rows at :attr:`q`, by closure name (the
        closures of the mechanism's model: a TOML machine's welds, a file's own
        closures; dimensionless)."""
        r = self.__dict__.get("_closure_residuals")
        if r is None:
            r = self.mechanism.general.residuals_at(self.q)
        return r


#: The general backend's name of :class:`Assembly` (one type for both backends).
LinkageAssembly = Assembly


def checked_twists(assembly: Assembly, tol: float = ASSEMBLY_CHECK_RTOL) -> np.ndarray:
    """The joint twists of an assembly that did not come with them (one made by hand, or
    by the Pinocchio path of the solver), after checking that it is one: every leg
    within its joint limits and closing on the platform pose to ``tol`` (relative pose
    error, :func:`pkm_pin.kernels.pose_error`), from the same Pinocchio pass.

    Raises:
        InvalidAssembly: naming the leg (and joint) and how to make a valid assembly.
    """
    from .twists import verified_twists

    mech = assembly.mechanism
    if assembly.leg_q is None:
        raise InvalidAssembly("the assembly has no per-leg view (the general backend made "
                              "it); read it per leg with Mechanism.assembly_at(assembly)")
    leg_q = list(assembly.leg_q)
    if len(leg_q) != len(mech.legs):
        raise InvalidAssembly(f"the assembly has {len(leg_q)} leg configurations for the "
                              f"{len(mech.legs)} legs of {mech.name!r}")
    leg_q = [leg.check_q(q, "assembly.leg_q") for leg, q in zip(mech.legs, leg_q)]
    for leg, q in zip(mech.legs, leg_q):
        if not leg.within_limits(q):
            lo, up = leg._bounds
            k = int(np.argmax((q < lo - JOINT_LIMIT_SLACK) | (q > up + JOINT_LIMIT_SLACK)))
            raise InvalidAssembly(
                f"leg {leg.name!r}: coordinate {k} ({q[k]:.6g}) is outside its joint limits "
                f"[{lo[k]:.6g}, {up[k]:.6g}]; make the assembly with Mechanism.assemble")
    J, errors, worst = verified_twists(mech, leg_q, as_pose(assembly.pose).homogeneous)
    if not worst <= tol:
        k = int(np.nanargmax(np.where(np.isnan(errors), np.inf, errors)))
        raise InvalidAssembly(
            f"leg {mech.legs[k].name!r} does not close on the platform pose (relative pose "
            f"error {errors[k]:.3g} > {tol:g}); make the assembly with "
            "Mechanism.assemble(pose, guess=...)")
    return J


__all__ = ["Assembly", "LinkageAssembly", "as_pose", "checked_twists", "placement"]
