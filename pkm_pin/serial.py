"""Serial-chain kinematics of a leg: link twists and screws, point velocities and
accelerations, the serial Jacobian and its singularities (seed 000 §4: Michalková &
Guldan; seed 002 §3–4: the anonymous Polish paper of 1987; see docs/references.md).

Everything here runs through Pinocchio; the hand-written recursive reduction of seed 002
(:mod:`pkm_pin.formulas.serial_reduction`) is the independent witness the tests compare
it with, and is not imported.

Conventions:

* Twists are axis-first ``(ω; v_O)`` [rad/s; m/s] about the **world** origin: ``ω`` is
  the angular velocity of the link, ``v_O`` the velocity of the link point that
  coincides with the world origin (see :mod:`pkm_pin.screws`).
* The leg's :attr:`base` placement is part of every world quantity.
* A *link* is a ``BODY`` frame of the leg's Pinocchio model (a URDF link); a point of a
  link is given in that link's own frame [m]; velocities and accelerations of points are
  returned in world axes [m/s], [m/s²]. Accelerations are *classical* (the second time
  derivative of the point's world position), not Pinocchio's spatial acceleration.
* ``q`` has the leg's ``nq`` values, ``qd`` and ``qdd`` its ``nv`` values [rad/s or
  m/s, rad/s² or m/s²].

:class:`SerialChain` is the base class of :class:`pkm_pin.Leg`; it declares what it
needs from a chain (the abstract members: ``model``, ``base``, ``name``, ``data``,
``characteristic_length``, ``joint_names``, ``check_q``, ``kinematics``). Every method
runs its own Pinocchio pass for the configuration it is given, on the Pinocchio data
of the calling thread, and reads only the data that pass returned.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from . import screws
from .errors import FrameNotFound, InputError, SingularityError
from .tolerances import LINK_TWIST_RTOL, SERIAL_SINGULAR_TOL

#: Default threshold of :meth:`SerialChain.is_serial_singular` and of the singularity
#: check of :meth:`SerialChain.serial_inverse_velocity`, on the dimensionless index of
#: :meth:`SerialChain.serial_singularity_index` (alias of
#: :data:`pkm_pin.tolerances.SERIAL_SINGULAR_TOL`).
SINGULAR_TOL = SERIAL_SINGULAR_TOL

#: Relative tolerance under which a link twist counts as zero (the link at rest) and a
#: twist as outside the span of the Jacobian (:meth:`SerialChain.serial_inverse_velocity`;
#: alias of :data:`pkm_pin.tolerances.LINK_TWIST_RTOL`).
TWIST_RTOL = LINK_TWIST_RTOL


@dataclass(frozen=True)
class LinkScrew:
    """Instantaneous screw axis of a link's motion (seed 002, eqs. (12)–(14)).

    Attributes:
        link: Name of the link (a ``BODY`` frame).
        point: Point of the screw axis nearest the world origin [m], world frame; the
            origin for a pure translation (a couple has no location); ``None`` at rest.
        direction: Unit direction of the axis, world frame: along ``ω`` for a screw
            motion, along ``v`` for a pure translation; ``None`` at rest.
        pitch: Pitch ``h = ω·v_O / ω·ω`` [m/rad] (seed 002's parameter ``μ``); ``inf``
            for a pure translation, ``None`` at rest.
    """

    link: str
    point: np.ndarray | None
    direction: np.ndarray | None
    pitch: float | None

    @property
    def at_rest(self) -> bool:
        """Whether the link does not move (its twist is zero)."""
        return self.pitch is None


class SerialChain(abc.ABC):
    """Link screws, point velocities/accelerations and the serial Jacobian of a chain.

    The base class of :class:`pkm_pin.Leg`. A subclass provides the members declared
    here: the attributes ``model``, ``base``, ``name`` and the abstract properties and
    methods below.
    """

    #: Pinocchio model of the chain.
    model: pin.Model
    #: Placement of the chain's root in the world.
    base: pin.SE3
    #: Name of the chain (in messages).
    name: str

    @property
    @abc.abstractmethod
    def data(self) -> pin.Data:
        """Pinocchio data of :attr:`model` private to the calling thread."""

    @property
    @abc.abstractmethod
    def characteristic_length(self) -> float:
        """Unit of length [m] of the chain's relative tolerances."""

    @property
    @abc.abstractmethod
    def joint_names(self) -> list[str]:
        """Movable joints of the chain, in velocity order."""

    @abc.abstractmethod
    def check_q(self, q, name: str = "q") -> np.ndarray:
        """``q`` as a finite float array of shape (nq,), or an :class:`InputError`."""

    @abc.abstractmethod
    def kinematics(self, q) -> tuple[pin.SE3, np.ndarray]:
        """Tip placement and the 6×nv axis-first world Jacobian at ``q``."""

    # ------------------------------------------------------------------ checks
    def check_v(self, v, name: str = "qd") -> np.ndarray:
        """``v`` as a finite float array of shape (nv,), or a specific :class:`InputError`."""
        a = np.asarray(v, dtype=float)
        nv = self.model.nv
        if a.shape != (nv,):
            raise InputError(
                f"{name} of leg {self.name!r} must have {nv} values (one per velocity "
                f"coordinate, joints {self.joint_names}), got shape {a.shape}"
            )
        if not np.all(np.isfinite(a)):
            raise InputError(f"{name} of leg {self.name!r} must be finite, got {a}")
        return a

    @property
    def link_names(self) -> list[str]:
        """Links of the chain (the ``BODY`` frames of the model), root first."""
        return [f.name for f in self.model.frames if f.type == pin.FrameType.BODY]

    def link_id(self, link: str) -> int:
        """Pinocchio frame index of ``link``, or :class:`FrameNotFound` listing the links."""
        if not isinstance(link, str):
            raise InputError(f"link must be a link name (str), got {type(link).__name__}")
        if not self.model.existFrame(link, pin.FrameType.BODY):
            raise FrameNotFound(link, self.link_names, f"the links of leg {self.name!r}")
        return self.model.getFrameId(link, pin.FrameType.BODY)

    # ----------------------------------------------------------- Pinocchio passes
    def _pass(self, q, qd=None, qdd=None) -> pin.Data:
        """The calling thread's data after forward kinematics at (q, qd, qdd) and every
        frame placement (model world); read it before the next pass."""
        data = self.data
        if qd is None:
            pin.forwardKinematics(self.model, data, q)
        elif qdd is None:
            pin.forwardKinematics(self.model, data, q, qd)
        else:
            pin.forwardKinematics(self.model, data, q, qd, qdd)
        pin.updateFramePlacements(self.model, data)
        return data

    def _twist(self, data: pin.Data, frame_id: int) -> np.ndarray:
        """Axis-first world twist (base included) of a frame in ``data`` returned by
        :meth:`_pass` with qd."""
        v = pin.getFrameVelocity(self.model, data, frame_id, pin.WORLD)
        return screws.adjoint(self.base) @ screws.from_pinocchio(v)

    # -------------------------------------------------------------- placements
    def link_placement(self, link: str, q) -> pin.SE3:
        """World placement of a link's frame (base placement included)."""
        fid = self.link_id(link)
        data = self._pass(self.check_q(q))
        return self.base * data.oMf[fid]

    def point_position(self, link: str, point, q) -> np.ndarray:
        """World position [m] of a point given in the frame of ``link``."""
        p = screws.as_vector3(point, "point")
        return self.link_placement(link, q).act(p)

    # ------------------------------------------------------------------ twists
    def link_twist(self, link: str, q, qd) -> np.ndarray:
        """Twist (ω; v_O) of one link [rad/s; m/s], axis-first, about the world origin."""
        fid = self.link_id(link)
        data = self._pass(self.check_q(q), self.check_v(qd))
        return self._twist(data, fid)

    def link_twists(self, q, qd) -> dict[str, np.ndarray]:
        """Twist (ω; v_O) of every link, axis-first, about the world origin.

        Returns:
            ``{link name: 6-vector}`` in the order of :attr:`link_names` (root first);
            the root link's twist is zero.
        """
        q, qd = self.check_q(q), self.check_v(qd)
        data = self._pass(q, qd)
        return {
            f.name: self._twist(data, i)
            for i, f in enumerate(self.model.frames)
            if f.type == pin.FrameType.BODY
        }

    def _rest_scale(self, q, qd) -> float:
        """Homogenised twist magnitude the chain could reach with ``qd``: the sum over
        the velocity coordinates of ``|qd_k|`` times the norm of the homogenised joint
        twist (columns of the unit-homogenised Jacobian)."""
        J, H, _ = self._tip_jacobian(q)
        return float(np.sum(np.abs(qd) * np.linalg.norm(H, axis=0) / self._column_scales(J)))

    def _screw_of(self, link: str, twist: np.ndarray, scale: float) -> LinkScrew:
        L = self.characteristic_length
        size = np.linalg.norm(twist[:3]) + np.linalg.norm(twist[3:]) / L
        if size <= LINK_TWIST_RTOL * scale or size == 0.0:
            return LinkScrew(link, None, None, None)
        point, direction = screws.axis(twist, length=L)
        return LinkScrew(link, point, direction, float(screws.pitch(twist, length=L)))

    def link_screws(self, q, qd) -> dict[str, LinkScrew]:
        """Instantaneous screw axis and pitch of every link (seed 002, (12)–(14), (30)).

        The axis and pitch are those of the link twist (:meth:`link_twists`), taken with
        :func:`pkm_pin.screws.axis` and :func:`pkm_pin.screws.pitch` at the leg's
        characteristic length. A link is *at rest* (point, direction and pitch ``None``)
        when its homogenised twist ``|ω| + |v_O| / L`` is at most :data:`TWIST_RTOL`
        times the magnitude the joint rates could produce (``Σ |qd_k| |$_k|``,
        homogenised likewise); the root link always is.

        Returns:
            ``{link name: LinkScrew}`` in the order of :attr:`link_names`.
        """
        q, qd = self.check_q(q), self.check_v(qd)
        scale = self._rest_scale(q, qd)
        return {name: self._screw_of(name, t, scale) for name, t in self.link_twists(q, qd).items()}

    # ------------------------------------------------------------------ points
    def point_velocity(self, link: str, point, q, qd) -> np.ndarray:
        """Velocity [m/s], world axes, of a point fixed in ``link`` (given in its frame).

        ``v_P = v_O + ω × P`` with the link twist (ω; v_O) and the world position ``P``
        (seed 002, (15)).
        """
        fid = self.link_id(link)
        p = screws.as_vector3(point, "point")
        data = self._pass(self.check_q(q), self.check_v(qd))
        twist = self._twist(data, fid)
        P = (self.base * data.oMf[fid]).act(p)
        return twist[3:] + np.cross(twist[:3], P)

    def point_acceleration(self, link: str, point, q, qd, qdd) -> np.ndarray:
        """Classical acceleration [m/s²], world axes, of a point fixed in ``link``.

        The second time derivative of the point's world position along the motion with
        rates ``qd`` and accelerations ``qdd``: ``a_P = a_F + ε × r + ω × (ω × r)``,
        with ``a_F`` the classical acceleration of the link frame's origin
        (Pinocchio's ``getFrameClassicalAcceleration`` in ``LOCAL_WORLD_ALIGNED``),
        ``ω``, ``ε`` the link's angular velocity and acceleration and ``r`` the vector
        from the frame origin to the point (seed 002, (19)); the Coriolis term of the
        prismatic pairs (43) is inside ``a_F``.
        """
        fid = self.link_id(link)
        p = screws.as_vector3(point, "point")
        q, qd, qdd = self.check_q(q), self.check_v(qd), self.check_v(qdd, "qdd")
        data = self._pass(q, qd, qdd)
        rf = pin.LOCAL_WORLD_ALIGNED
        a_frame = pin.getFrameClassicalAcceleration(self.model, data, fid, rf)
        v_frame = pin.getFrameVelocity(self.model, data, fid, rf)
        w, eps = v_frame.angular, a_frame.angular
        r = data.oMf[fid].rotation @ p
        a = a_frame.linear + np.cross(eps, r) + np.cross(w, np.cross(w, r))
        return self.base.rotation @ a

    # ------------------------------------------------------- serial velocity map
    def serial_jacobian(self, q) -> np.ndarray:
        """Serial Jacobian ``J`` (6×nv, axis-first, world) of the tip: ``V = J q̇``
        (seed 000, (38)–(42)); column k is the joint twist of velocity coordinate k."""
        return self.kinematics(q)[1]

    def serial_forward_velocity(self, q, qd) -> np.ndarray:
        """Tip twist (ω; v_O) [rad/s; m/s] produced by the joint rates: ``V = J q̇`` (42)."""
        qd = self.check_v(qd)
        return self.serial_jacobian(q) @ qd

    def _column_scales(self, J: np.ndarray) -> np.ndarray:
        """``L`` for translational velocity coordinates (zero angular column of ``J``),
        else 1."""
        L = self.characteristic_length
        translational = np.linalg.norm(J[:3], axis=0) == 0.0
        return np.where(translational, L, 1.0)

    def _homogenise(self, J: np.ndarray, tip: np.ndarray) -> np.ndarray:
        """Dimensionless ``J``: its twists written about the tip point ``tip`` [m] (so the
        decisions do not depend on where the chain stands in the world), linear rows
        divided by ``L``, prismatic columns times ``L``."""
        L = self.characteristic_length
        H = (J * self._column_scales(J)[None, :]).T  # twists as rows
        return screws.homogenise(screws.about(H, tip), L).T  # v_tip = v_O + ω × tip

    def _tip_jacobian(self, q) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(J, H, tip)``: the world Jacobian, its :meth:`_homogenise` d form and the tip
        point, from one pass."""
        M, J = self.kinematics(q)
        return J, self._homogenise(J, M.translation), M.translation

    def serial_singularity_index(self, q) -> float:
        """Dimensionless closeness to a serial singularity (seed 000, (47)–(48)).

        ``σ_k / σ_1`` of the unit-homogenised Jacobian, ``k = min(6, nv)``: the twists
        are written about the tip point (the index does not change when the chain is
        moved in the world), the linear
        rows of ``J`` are divided by the leg's :attr:`characteristic_length` ``L`` and the
        columns of translational coordinates (prismatic joints) multiplied by ``L``, so
        the index is the same for the chain in metres or in millimetres. It is 0 exactly
        where ``det J = 0`` (square ``J``) or ``det(JᵀJ) = 0`` (fewer than 6 joints), or
        where ``J`` has rank below 6 (more than 6 joints), and at most 1.
        """
        sv = np.linalg.svd(self._tip_jacobian(q)[1], compute_uv=False)
        if sv.size == 0 or sv[0] == 0.0:
            return 0.0
        return float(sv[min(6, self.model.nv) - 1] / sv[0])

    def is_serial_singular(self, q, tol: float = SERIAL_SINGULAR_TOL) -> bool:
        """Whether :meth:`serial_singularity_index` is below ``tol`` (dimensionless)."""
        return self.serial_singularity_index(q) < tol

    def serial_inverse_velocity(self, q, twist, tol: float = SERIAL_SINGULAR_TOL) -> np.ndarray:
        """Joint rates producing a tip twist (ω; v_O) (seed 000, (42) solved for q̇).

        * 6 joints: ``q̇ = J⁻¹ V``.
        * More than 6 (redundant): the least-squares solution of least (homogenised) norm,
          ``q̇ = J⁺ V`` computed on the unit-homogenised Jacobian.
        * Fewer than 6: the unique ``q̇`` with ``J q̇ = V`` when ``V`` lies in the span of
          the joint twists.

        Raises:
            SingularityError: ``J`` is singular (:meth:`serial_singularity_index` below
                ``tol``), or the twist is not reachable: the homogenised residual
                ``|J q̇ − V|`` exceeds :data:`TWIST_RTOL` times ``|V|`` (only possible
                with fewer than 6 joints).
            InputError: ``q`` or ``twist`` has a wrong shape or is not finite.
        """
        V = screws.as_screws(twist, "twist")
        if V.shape[0] != 1:
            raise InputError(f"twist must be one 6-vector (ω; v_O), got shape {np.shape(twist)}")
        V = V[0]
        index = self.serial_singularity_index(q)
        if index < tol:
            raise SingularityError(
                f"leg {self.name!r} is at a serial singularity (index {index:.3g} < {tol:g}): "
                "the joint rates of a tip twist are not unique or do not exist",
                kind="serial inverse velocity",
                index=index,
            )
        L = self.characteristic_length
        J, H, tip = self._tip_jacobian(q)
        Vh = screws.homogenise(screws.about(V, tip), L)  # about the tip, as H
        x, *_ = np.linalg.lstsq(H, Vh, rcond=None)
        residual = np.linalg.norm(H @ x - Vh)
        if residual > LINK_TWIST_RTOL * max(np.linalg.norm(Vh), np.finfo(float).tiny):
            raise SingularityError(
                f"the twist {V} is not reachable by leg {self.name!r} at this configuration "
                f"(its {self.model.nv} joint twists leave a relative residual "
                f"{residual / np.linalg.norm(Vh):.3g})",
                kind="serial inverse velocity",
                index=index,
            )
        return x * self._column_scales(J)
