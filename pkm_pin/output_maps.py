"""Statics, ellipsoids and singular directions of the output, written once for every
analysis (:class:`pkm_pin.Analysis` of the per-leg engine and
:class:`pkm_pin.linkage.LinkageAnalysis` of the general elimination).

Both analyses end in the same objects: the actuation wrenches ``A`` (n × 6) and the
diagonal ``B`` of ``A Δ t = B q̇_a`` for every admissible output twist ``t``, a basis of
the output's twist system and of the constraint wrenches reciprocal to it, a centre
(the point every decision is homogenised about) and a characteristic length ``L``.
Everything here is derived from those alone, so the same machine gives the same
efforts, ellipsoids and singular directions whichever backend analysed it.

Conventions: twists ``(ω; v_O)`` and wrenches ``(f; m_O)`` axis-first about the world
origin [rad/s, m/s, N, N m]; homogenised screws are written about the centre with the
moment part divided by ``L``.

Virtual work gives the statics: for every admissible ``t``, ``τ · q̇_a = w ∘ t``.
Writing ``w = Aᵀ λ + Cᵀ μ`` (actuation and constraint wrenches) and using
``A Δ t = B q̇_a``, ``C Δ t = 0`` gives ``τ = B λ``.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from . import screws
from .errors import InputError, SingularityError
from .tolerances import RANK_RTOL
from .transmission import Ellipsoid

__all__ = ["OutputMaps"]


class OutputMaps:
    """Mixin of an analysis that has ``A``, ``B``, ``platform_twists``,
    ``constraint_wrenches`` (world origin), ``centre`` [m], ``length`` [m], ``indices``
    (with ``type_I`` and ``type_II``), ``singular_tol``, and the hooks
    :attr:`_twist_dim`, :attr:`_actuated_prismatic` (and, where the analysis has its
    own, :attr:`_platform_h`, :attr:`_actuation_h`, :attr:`_closeness`)."""

    # ------------------------------------------------------------------ hooks
    @property
    def _twist_dim(self) -> int:
        """Dimension of the output's twist system."""
        raise NotImplementedError

    @property
    def _platform_h(self) -> np.ndarray:
        """The output twist basis homogenised about the centre, orthonormal rows."""
        return screws.homogenise(self._about_centre(self.platform_twists), self.length)

    @property
    def _actuation_h(self) -> np.ndarray:
        """The actuation wrenches homogenised about the centre, rows of unit norm (zero
        rows kept at zero)."""
        H = screws.homogenise(self._about_centre(self.A), self.length)
        n = np.linalg.norm(H, axis=1)
        return H / np.where(n > 0, n, 1.0)[:, None]

    @property
    def _actuated_prismatic(self) -> np.ndarray:
        """Whether each actuated joint is prismatic (its rate in m/s)."""
        raise NotImplementedError

    @property
    def _closeness(self) -> tuple[float, float]:
        """The closeness to a type I and to a type II singularity (dimensionless, 0 at
        the singularity; nan when undefined, read as singular)."""
        return self.indices["type_I"], self.indices["type_II"]

    # ------------------------------------------------------------- frames
    def _to_origin(self, H: np.ndarray) -> np.ndarray:
        """Screws homogenised about :attr:`centre` in world units about the world
        origin."""
        return screws.from_point(screws.dehomogenise(H, self.length), self.centre)

    def _about_centre(self, S: np.ndarray) -> np.ndarray:
        """Screws about the world origin written about :attr:`centre`."""
        return screws.about(S, self.centre)

    def _controlled(self, what: str) -> None:
        """Refuse ``what`` at a type II singularity (an index below ``singular_tol``,
        or undefined)."""
        t2 = self._closeness[1]
        if not t2 >= self.singular_tol:
            raise SingularityError(
                f"{what} undefined: type II closeness index {t2:.3g} < "
                f"{self.singular_tol:g} (the actuators cannot balance every wrench here)",
                "forward", t2)

    # ------------------------------------------------------------ actuation
    @property
    def full_jacobian(self) -> np.ndarray:
        """Actuation rows stacked on constraint rows: ``[A; C] Δ t = [B q̇_a; 0]``."""
        return np.vstack([self.A, self.constraint_wrenches])

    @cached_property
    def uncontrolled_twist(self) -> np.ndarray | None:
        """At a type II/III singularity, the output twist the locked actuators allow
        (unit once homogenised, axis-first); ``None`` elsewhere."""
        if self._closeness[1] >= self.singular_tol or self._twist_dim == 0:
            return None
        P = self._platform_h
        _, _, Vt = np.linalg.svd(self._actuation_h @ screws.DELTA @ P.T, full_matrices=True)
        return self._to_origin(Vt[-1] @ P)

    @cached_property
    def unresisted_wrench(self) -> np.ndarray | None:
        """At a type II/III singularity, an output wrench that no combination of
        actuation and constraint wrenches balances with bounded efforts; ``None``
        elsewhere. Where the rows ``[A; C]`` (unit, homogenised about :attr:`centre`)
        lose rank: the direction they miss (the last right singular vector, its singular
        value well apart from the others'). Where they keep it and the singularity is in
        ``B`` instead (``A Δ t = B q̇_a`` with ``B`` unbounded, as a linkage's generalised
        forward index reads it): the actuation wrench of ``B``'s largest singular
        direction, its part off the constraint wrenches (unique, never decided by the
        order of equal singular values)."""
        if self._closeness[1] >= self.singular_tol:
            return None
        H = screws.normalised_rows(self._about_centre(self.full_jacobian), self.length)
        _, s, Vt = np.linalg.svd(H, full_matrices=True)
        B = np.atleast_2d(np.asarray(self.B, dtype=float))
        if s[-1] < 1e-3 * s[0] or not B.size or not np.isfinite(B).all():
            return self._to_origin(Vt[-1])
        U, _, _ = np.linalg.svd(B)
        n = B.shape[0]
        w = U[:, 0] @ H[:n]  # the actuation wrench needing unbounded effort
        C = H[n:]
        if C.size:
            rank, _, _, Ct = screws.svd_rank(C, RANK_RTOL)
            w = w - (w @ Ct[:rank].T) @ Ct[:rank]
        return self._to_origin(w / max(float(np.linalg.norm(w)), 1e-300))

    @cached_property
    def lost_actuated_rates(self) -> np.ndarray | None:
        """At a type I/III singularity, actuated rates that move no output twist."""
        if self._closeness[0] >= self.singular_tol:
            return None
        e = np.zeros(self.A.shape[0])
        e[int(np.argmin(np.abs(np.diag(self.B))))] = 1.0
        return e

    # -------------------------------------------------------------- statics
    def _balance(self, wrench) -> tuple[np.ndarray, np.ndarray]:
        """``(λ, μ)`` with ``wrench = Aᵀ λ + Cᵀ μ`` (C: ``constraint_wrenches``),
        solved on rows homogenised about :attr:`centre`."""
        w = screws.as_vector(wrench, 6, "wrench", noun="components")
        self._controlled("actuator efforts")
        L = self.length
        rows = screws.homogenise(self._about_centre(self.full_jacobian), L)
        rhs = screws.homogenise(self._about_centre(w), L)
        x, *_ = np.linalg.lstsq(rows.T, rhs, rcond=None)
        if np.linalg.norm(rows.T @ x - rhs) > 1e-9 * max(np.linalg.norm(rhs), 1e-300):
            raise InputError("this wrench is not balanced by the actuation and constraint "
                             "wrenches (fewer actuators than degrees of freedom)")
        n = self.A.shape[0]
        return x[:n], x[n:]

    def actuator_efforts(self, wrench) -> np.ndarray:
        """Actuator efforts ``τ`` (n,) [N for a prismatic, N m for a revolute actuator]
        with which the mechanism applies the wrench ``wrench`` (axis-first ``(f; m_O)``
        about the world origin [N, N m]) to the output.

        Virtual work (module docstring): ``τ = B λ`` with ``w = Aᵀ λ + Cᵀ μ``. To hold
        an external load ``w_ext`` (a payload's weight:
        :func:`pkm_pin.transmission.payload_wrench`), pass ``−w_ext``. With redundant
        actuation, the minimum-norm ``(λ, μ)`` (homogenised).

        Raises:
            SingularityError: at or near a type II singularity.
            InputError: the wrench cannot be balanced (fewer actuators than DOF).
        """
        lam, _ = self._balance(wrench)
        return np.diag(self.B) * lam

    def constraint_forces(self, wrench) -> np.ndarray:
        """Magnitudes ``μ`` of the part of ``wrench`` carried by the constraints:
        ``wrench = Aᵀ λ + Cᵀ μ`` with ``C`` = ``constraint_wrenches`` (rows of unit
        norm once written about :attr:`centre` with moments divided by the
        characteristic length, so ``μ`` is in newtons); the wrench they carry is
        ``μ @ constraint_wrenches``. Same conventions and errors as
        :meth:`actuator_efforts`."""
        return self._balance(wrench)[1]

    # ----------------------------------------------------------- ellipsoids
    def _velocity_map(self) -> tuple[np.ndarray, np.ndarray]:
        """``K`` (d × n) with ``x = K q̇_h`` (x: coordinates of the output twist on the
        orthonormal homogenised basis ``P_h`` about the centre; ``q̇_h``: actuated rates,
        prismatic ones divided by L), and ``P_h``."""
        n, d, L = self.A.shape[0], self._twist_dim, self.length
        if n != d:
            raise InputError(f"ellipsoids need as many actuators as degrees of freedom "
                             f"of the output (here {n} actuators, {d} DOF)")
        self._controlled("ellipsoids")
        P_h = self._platform_h
        A_h = screws.homogenise(self._about_centre(self.A), L)
        D = np.diag(self.B) * np.where(self._actuated_prismatic, L, 1.0) / L
        return np.linalg.solve(A_h @ screws.DELTA @ P_h.T, np.diag(D)), P_h

    def velocity_ellipsoid(self) -> Ellipsoid:
        """Output twists reached by actuated rates of unit norm.

        Homogenised units, so that the answer does not depend on units or frame:
        actuated rates as revolute [rad/s] and prismatic [m/s] divided by the
        characteristic length L; twists about the centre as ``(ω; v_c / L)`` [1/s].
        Semi-axes are the singular values of that map (largest first), axes the twists
        (about the world origin) along them.

        Raises:
            InputError: actuators and DOF differ. SingularityError: type II.
        """
        K, P_h = self._velocity_map()
        U, sv, _ = np.linalg.svd(K)
        return Ellipsoid(sv, self._to_origin(U.T @ P_h), np.array(self.centre, float),
                         self.length)

    def force_ellipsoid(self) -> Ellipsoid:
        """Output wrenches produced by actuator efforts of unit norm (the dual of
        :meth:`velocity_ellipsoid`: same principal directions, semi-axes inverted).

        Homogenised units: efforts as prismatic [N] and revolute [N m] divided by L;
        wrenches about the centre as ``(f; m_c / L)`` [N], each axis the wrench (about
        the world origin) that does work only on its twist axis (modulo the constraint
        wrenches, which the structure carries). Semi-axes largest first (inf at a
        type I singularity).

        Raises:
            InputError: actuators and DOF differ. SingularityError: type II.
        """
        K, P_h = self._velocity_map()
        U, sv, _ = np.linalg.svd(K)
        with np.errstate(divide="ignore"):
            semi = 1.0 / sv[::-1]
        W_h = (U.T @ P_h)[::-1] @ screws.DELTA
        return Ellipsoid(semi, self._to_origin(W_h), np.array(self.centre, float),
                         self.length)
