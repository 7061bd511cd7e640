"""Screw analysis of an assembled mechanism — seed 000, sections 3 and 4 (Michalková &
Guldan; the source papers are listed in docs/references.md).

Everything is derived from one Jacobian per leg (its columns are the joint twists):

* **Mobility** (§3): leg ``i``'s constraint wrenches ``W_i`` are reciprocal to all its
  joint twists; the mechanism's constraint system is their union; the platform twist
  system is the reciprocal of that union, and its dimension is the (instantaneous)
  degree of freedom.
* **Actuation** (§4.1): for each actuated joint, the wrench reciprocal to every other
  joint twist of its leg that does work on the platform twist system: the actuation
  wrench ``ζ``. Multiplying the leg's velocity equation by it removes the passive rates:
  ``ζᵀ Δ t = (ζ ∘ $_a) q̇_a``. Stacked: ``A Δ t = B q̇_a`` with the rows of ``A`` the
  actuation wrenches and ``B = diag(ζ_i ∘ $_a,i)`` (eq. 43–45).
* **Singularities** (§4.2): type I when ``B`` is singular, type II when ``A Δ`` is
  singular on the platform twist system, type III both; a constraint singularity when
  the constraint system loses rank (the platform gains a motion).

Conventions: twists ``(ω; v_O)`` and wrenches ``(f; m_O)`` axis-first about the world
origin. Every rank and singularity decision is made on unit-homogenised screws about the
platform's centre (the pose's origin; moment parts divided by the mechanism's
characteristic length, then rows normalised), so the same mechanism in millimetres or
metres, or moved anywhere in the world, gives the same DOF, indices and classes. Actuation
wrenches are scaled to a unit force (or, for a pure moment, a unit moment) and signed so
that ``B_ii >= 0``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from . import engine, screws
from .assembly import checked_twists
from .errors import InputError, PkmError, SingularityError
from .output_maps import OutputMaps
from .screws import from_homogenised, homogenised_about
from .tolerances import CLOSENESS_SINGULAR_TOL, ROTATION_COUNT_TOL, SPAN_RTOL
from .transmission import (
    Transmission,
    constraint_transmission,
    leg_points,
    transmission_indices,
)
from .twists import joint_lines

#: Dimensionless threshold below which a closeness index counts as singular (alias of
#: :data:`pkm_pin.tolerances.CLOSENESS_SINGULAR_TOL`).
SINGULAR_TOL = CLOSENESS_SINGULAR_TOL


@dataclass
class LegScrews:
    """Screws of one leg at one configuration (all axis-first, world origin).

    Attributes:
        jacobian: 6 × nv Jacobian (columns: joint twists).
        constraint_wrenches: basis of the wrenches reciprocal to every joint twist.
    """

    jacobian: np.ndarray
    constraint_wrenches: np.ndarray


class Analysis(OutputMaps):
    """The screw analysis of a mechanism at one assembly, whichever backend reads it:
    the one result type of :meth:`Mechanism.analyze` (docs/indices.md defines each
    number once).

    ``Analysis(assembly, **options)`` analyses an :class:`~pkm_pin.assembly.Assembly`
    with the backend that made it: the per-leg engine (:class:`LegsAnalysis`) where it
    has a per-leg view, the general elimination of the tree (:class:`TreeAnalysis`,
    ``assembly.mechanism.analyze``) where it has not. Both answer the same names:

    * the motion: ``q`` (the tree's configuration), ``mobility``, ``dof``, ``idle_dof``,
      ``output_dof``, ``translations``, ``motion_type``, ``grubler``,
      ``redundant_constraints``, ``platform_twists``, ``constraint_wrenches``;
    * the actuation: ``A`` (= ``actuation_wrenches``), ``B`` of ``A Δ t = B q̇_a``,
      ``actuated_twists``, ``joint_twists``;
    * the singularities: ``indices`` (``type_I``, ``type_II``, ``condition_A``),
      ``motion_indices`` (``forward``, ``inverse``), ``singularity``,
      ``constraint_singular``;
    * the maps and studies: ``forward_velocity``, ``inverse_velocity``, ``joint_rates``,
      ``transmission``,
      the statics and ellipsoids of :class:`~pkm_pin.output_maps.OutputMaps`;
    * where they come from: ``mechanism``, ``assembly``, ``rtol``, ``singular_tol``,
      ``length``, ``centre`` (= ``reference_point``, the point every decision is
      homogenised about).

    ``joint_rates(q̇_a)`` gives the rates of every joint of the tree. What only legs have
    (``legs``, ``leg_constraint_wrenches``, and ``passive_rates``: each leg's joint rates
    for a platform twist) a general analysis refuses with the reason.

    Conventions: twists ``(ω; v_O)`` and wrenches ``(f; m_O)`` axis-first about the
    world origin.
    """

    def __new__(cls, assembly=None, *args, **kwargs):
        if cls is Analysis:
            cls = TreeAnalysis if getattr(assembly, "leg_q", ()) is None else LegsAnalysis
        return super().__new__(cls)


class LegsAnalysis(Analysis):
    """The per-leg engine's :class:`Analysis`: mobility, Jacobians and singularity
    classes of a base–legs–platform mechanism at an assembly with a per-leg view.

    The screw algebra is the analysis engine (:mod:`pkm_pin.engine`) at one pose: the
    same compiled code that :meth:`Mechanism.sweep` runs over many poses.

    Args:
        assembly: The assembled configuration (see :meth:`Mechanism.assemble`).
        rtol: Relative tolerance of rank decisions (see :mod:`pkm_pin.screws`).
        singular_tol: Threshold of the dimensionless closeness indices (default
            :data:`SINGULAR_TOL`): below it the configuration is singular and the
            velocity maps refuse to answer.
    """

    def __init__(self, assembly, rtol: float = screws.RTOL, singular_tol: float = SINGULAR_TOL):
        if rtol is not screws.RTOL or singular_tol is not SINGULAR_TOL:
            for name, value in (("rtol", rtol), ("singular_tol", singular_tol)):
                if not (isinstance(value, (int, float)) and np.isfinite(value)
                        and 0 < value < 1):
                    raise InputError(f"{name} must be a finite positive number below 1, "
                                     f"got {value!r}")
        self.assembly = assembly
        self.mechanism = mech = assembly.mechanism
        self.rtol = rtol
        self.singular_tol = singular_tol
        self.length = mech.characteristic_length
        #: (nv × 6) joint twists of every leg, one after the other.
        self.joint_twists = assembly.joint_twists
        if self.joint_twists is None:  # not verified by the solver's pass: check it
            self.joint_twists = checked_twists(assembly)
        layout = mech.engine_layout if rtol == screws.RTOL else layout_of(mech, rtol)
        #: The platform's centre [m]: screws are homogenised about it for every decision.
        self.centre = assembly.pose.translation.copy()
        self._results = engine.analyse(self.joint_twists[None], layout,
                                       centres=self.centre[None])

    @property
    def reference_point(self) -> np.ndarray:
        """The point every decision is homogenised about [m]: :attr:`centre`."""
        return self.centre

    @property
    def actuated_prismatic(self) -> np.ndarray:
        """Whether each actuated joint is prismatic (its rate in m/s)."""
        return self._actuated_prismatic

    # ------------------------------------------------ hooks of OutputMaps
    @property
    def _twist_dim(self) -> int:
        return self.dof

    @property
    def _platform_h(self) -> np.ndarray:
        return self._results.platform[0, :self.dof]

    @property
    def _actuation_h(self) -> np.ndarray:
        return self._results.A_h[0]

    @property
    def _actuated_prismatic(self) -> np.ndarray:
        return ~(np.linalg.norm(self.actuated_twists[:, :3], axis=1) > 0)

    @cached_property
    def legs(self) -> list[LegScrews]:
        """Per leg: its Jacobian and its constraint wrenches."""
        r, offs = self._results, self.mechanism.leg_frames.coords
        W = self._to_origin(r.leg_constraints[0].reshape(-1, 6)).reshape(-1, 6, 6)
        return [LegScrews(self.joint_twists[a:b].T, W[k, :r.leg_dims[0, k]])
                for k, (a, b) in enumerate(zip(offs[:-1], offs[1:]))]

    # ------------------------------------------------------------------ mobility
    @property
    def leg_constraint_wrenches(self) -> list[np.ndarray]:
        """Per leg, a basis of its constraint wrench system (k_i × 6)."""
        return [ls.constraint_wrenches for ls in self.legs]

    @cached_property
    def constraint_wrenches(self) -> np.ndarray:
        """Basis of the mechanism's constraint wrench system (union over the legs, eq. 37)."""
        r = self._results
        return self._to_origin(r.constraints[0, :6 - r.dof[0]])

    @cached_property
    def platform_twists(self) -> np.ndarray:
        """Basis (dof × 6) of the platform's twist system: reciprocal of the constraints.

        Orthonormal once written about :attr:`centre` with the linear parts divided by
        the characteristic length."""
        return self._to_origin(self._results.platform[0, :self.dof])

    @property
    def dof(self) -> int:
        """Instantaneous degree of freedom of the platform."""
        return int(self._results.dof[0])

    @property
    def output_dof(self) -> int:
        """Dimension of the platform's twist system: :attr:`dof`. (A general linkage's
        analysis has both: its ``dof`` counts every motion of its tree, idle ones
        included, its ``output_dof`` the output's.)"""
        return self.dof

    @cached_property
    def mobility(self):
        """The mobility of the mechanism's whole tree at this assembly
        (:meth:`Mechanism.mobility`, a :class:`~pkm_pin.linkage.Mobility`: the idle
        motions in words, the ranks compared with nearby configurations, the actuators
        that can be driven independently, Grübler's count of the tree; cached)."""
        return self.mechanism.mobility(self.assembly)

    @property
    def idle_dof(self) -> int:
        """Motions of the tree left with every actuated joint locked
        (:attr:`mobility`'s ``idle_dof``: a leg spinning about its own axis)."""
        return self.mobility.idle_dof

    @property
    def translations(self) -> int:
        """Dimension of the pure translations (couples) in the platform twist system."""
        return int(self._results.translations[0])

    @property
    def motion_type(self) -> str:
        """``"3T"``, ``"2T1R"``, ``"1T2R"``, ``"3R"``, ``"3T3R"``…, ``"1H"`` for a helical
        motion; ``"0"`` when rigid (:func:`pkm_pin.screws.motion_type`)."""
        return screws.motion_type(self._about_centre(self.platform_twists), self.translations,
                                  self.length)

    @property
    def grubler(self) -> int:
        """Grübler–Kutzbach count of the mechanism (see :attr:`Mechanism.grubler`)."""
        return self.mechanism.grubler

    @property
    def redundant_constraints(self) -> int:
        """Σ rank(leg constraints) − rank(union): the constraints counted more than once.

        ``dof = grubler + redundant_constraints`` when no leg has an idle motion.
        """
        return int(self._results.redundant[0])

    # ----------------------------------------------------------------- actuation
    @property
    def actuation_wrenches(self) -> np.ndarray:
        """Actuation wrenches (n × 6), one per actuated joint, in actuated-coordinate order.

        For each actuated joint: the member of the reciprocal of the other joint twists
        of its leg that does the most work on the platform twists (orthogonal to the
        leg's constraint wrenches (see :func:`pkm_pin.engine.stages.actuation_wrench`);
        a unit force, or a unit moment when it is a couple; signed so that
        ``B_ii >= 0``."""
        return self._results.A[0]

    @property
    def A(self) -> np.ndarray:
        """Parallel Jacobian (n × 6): rows are the actuation wrenches; ``A Δ t = B q̇_a``."""
        return self._results.A[0]

    @property
    def B(self) -> np.ndarray:
        """Serial Jacobian (n × n, diagonal): ``B_ii = ζ_i ∘ $_a,i``."""
        b = self._results.B[0]
        out = np.zeros((b.shape[0], b.shape[0]))
        out.flat[::b.shape[0] + 1] = b
        return out

    @property
    def actuated_twists(self) -> np.ndarray:
        """Twists (n × 6) of the actuated joints, in actuated-coordinate order."""
        return self.joint_twists[self.mechanism.engine_layout.act_col]

    # ------------------------------------------------------------- singularities
    @cached_property
    def indices(self) -> dict[str, float]:
        """Dimensionless closeness indices (0 at the singularity, unit-invariant).

        * ``type_II``: smallest singular value of ``A Δ`` on the platform twist system
          (rows of A unit-homogenised, platform basis orthonormal); 0 when the platform
          has more degrees of freedom than actuators.
        * ``type_I``: smallest ``|ζ_i ∘ $_a,i|`` of unit-homogenised screws.
        * ``condition_A``: condition number of that ``A Δ`` (inf when singular).
        """
        r = self._results
        return {"type_I": float(r.type_I[0]), "type_II": float(r.type_II[0]),
                "condition_A": float(r.condition[0])}

    @property
    def q(self) -> np.ndarray:
        """The configuration of the mechanism's tree at this analysis
        (:attr:`~pkm_pin.assembly.Assembly.q`), as a general analysis's ``q``."""
        return self.assembly.q

    @cached_property
    def motion_indices(self) -> dict[str, float]:
        """The general elimination's ``forward`` and ``inverse`` indices
        (:func:`pkm_pin.screws.motion_indices`, docs/indices.md) of this machine's motions:
        the pairs (actuated rates, platform twist) with the twist in the platform twist
        system and ``A Δ t = B q̇_a``, rates over :attr:`Mechanism.actuated_scales`,
        twists homogenised about :attr:`centre`. The same numbers as the general
        elimination of the machine's tree (those do not depend on the representatives
        of ``A``); not part of :attr:`indices`, which the engine computes for every pose
        of a sweep."""
        L, centre = self.length, self.centre
        T = screws.homogenised_about(self.platform_twists, centre, L)
        P_h = np.linalg.qr(T.T)[0].T if len(T) else np.zeros((0, 6))
        A_h = screws.homogenised_about(self.A, centre, L) if len(self.A) else np.zeros((0, 6))
        norms = np.linalg.norm(A_h, axis=1)
        norms = np.where(norms > 0, norms, 1.0)
        rates = np.diag(self.B) * self.mechanism.actuated_scales / (L * norms)
        # row i: L |A_h,i| (A_h,i / |A_h,i|) Δ t_h = B_ii s_i q̇'_i, t_h = P_hᵀ y
        S = np.hstack([(A_h / norms[:, None]) @ screws.DELTA @ P_h.T, -np.diag(rates)])
        rank, _, _, Vt = screws.svd_rank(S, self.rtol)
        N, d = Vt[rank:].T, P_h.shape[0]
        _, _, forward, inverse = screws.motion_indices(N[d:], P_h.T @ N[:d], self.rtol)
        return {"forward": forward, "inverse": inverse}

    @property
    def singularity(self) -> str:
        """``"none"``, ``"I"`` (B singular), ``"II"`` (A Δ singular), or ``"III"`` (both)."""
        r = self._results
        return classify(float(r.type_I[0]), float(r.type_II[0]), self.singular_tol)

    @cached_property
    def constraint_singular(self) -> bool:
        """Whether the constraint system has lost rank compared with the home assembly."""
        if self._is_home:
            return False
        home = self.mechanism.home_analysis
        return self.constraint_wrenches.shape[0] < home.constraint_wrenches.shape[0]

    @property
    def _is_home(self) -> bool:
        """Whether this is the analysis of the mechanism's home assembly (the reference
        of the constraint singularities: compared with nothing)."""
        return self.assembly is self.mechanism.__dict__.get("home_assembly")

    # ---------------------------------------------------------------- velocities
    def _check_twist(self, twist) -> np.ndarray:
        t = screws.as_screws(twist, "twist")
        if t.shape[0] != 1:
            raise InputError(f"twist must have shape (6,), got {np.shape(twist)}")
        return t[0]

    def _admissible(self, t: np.ndarray) -> bool:
        """Whether ``t`` lies in the platform twist system (decided about :attr:`centre`)."""
        return screws.contains(self._about_centre(self.platform_twists),
                               self._about_centre(t), self.length)

    def forward_velocity(self, qdot_actuated) -> np.ndarray:
        """Platform twist (6,) axis-first about the world origin from the actuated rates.

        Solves ``A Δ t = B q̇_a`` on the platform twist system.

        Raises:
            SingularityError: at or near a type II singularity (index below
                ``singular_tol``), or when the actuators do not control every DOF.
        """
        qd = self.mechanism.check_actuated(qdot_actuated, "qdot_actuated")
        if self.indices["type_II"] < self.singular_tol:
            raise SingularityError(
                f"forward velocity undefined: type II closeness index "
                f"{self.indices['type_II']:.3g} < {self.singular_tol:g} (the platform is "
                f"not controlled by the {self.mechanism.n_actuated} actuators here)",
                "forward", self.indices["type_II"])
        A_P = self.A @ screws.DELTA @ self.platform_twists.T
        x, *_ = np.linalg.lstsq(A_P, self.B @ qd, rcond=None)
        if A_P.shape[0] > A_P.shape[1]:
            resid = np.linalg.norm(A_P @ x - self.B @ qd)
            if resid > 1e-9 * max(1.0, np.linalg.norm(self.B @ qd)):
                raise InputError("these actuated rates are incompatible (redundant actuation)")
        return x @ self.platform_twists

    def inverse_velocity(self, twist) -> np.ndarray:
        """Actuated rates producing the platform twist ``twist`` (axis-first, world origin).

        Raises:
            InputError: the twist is outside the platform twist system.
            SingularityError: at or near a type I singularity.
        """
        t = self._check_twist(twist)
        if not self._admissible(t):
            raise InputError(
                f"twist {np.round(t, 6)} is not a motion of the platform here "
                f"(motion type {self.motion_type}); project it onto platform_twists first"
            )
        if self.indices["type_I"] < self.singular_tol:
            raise SingularityError(
                f"inverse velocity undefined: type I closeness index "
                f"{self.indices['type_I']:.3g} < {self.singular_tol:g}",
                "inverse", self.indices["type_I"])
        return (self.A @ screws.DELTA @ t) / np.diag(self.B)

    # -------------------------------------------------------------- transmission
    @cached_property
    def transmission(self) -> Transmission:
        """Motion/force transmission indices ITI, OTI, LTI and CTI
        (:mod:`pkm_pin.transmission`; Wang, Wu & Liu 2010): dimensionless, in [0, 1],
        invariant under units and rigid motions, 0 at type I (ITI), type II (OTI) and
        constraint (CTI) singularities."""
        mech, L = self.mechanism, self.length
        lay = mech.engine_layout
        A, J = self._about_centre(self.A), self._about_centre(self.joint_twists)
        lines = self._about_centre(joint_lines(mech, self.assembly.leg_q, self.joint_twists))
        P = screws.dehomogenise(self._results.platform[0, :self.dof], L)
        p_in, p_out = leg_points(A, lines, lay.coords, lay.act_col, lay.act_leg, L)
        iti, oti = transmission_indices(A, J[lay.act_col], P, p_in, p_out, L, self.rtol)
        C = [self._about_centre(ls.constraint_wrenches).reshape(-1, 6) for ls in self.legs]
        points = [leg_points(c[:1], lines, lay.coords, [lay.coords[k] - 1], [k], L)[1][0]
                  if len(c) else np.zeros(3) for k, c in enumerate(C)]
        generic = None if self._is_home else mech.home_analysis.constraint_wrenches.shape[0]
        leg_cti = constraint_transmission(A, C, points, L, self.rtol, generic)
        return Transmission.of(iti, oti, leg_cti, lay.act_leg, [leg.name for leg in mech.legs])

    def joint_rates(self, qdot_actuated) -> np.ndarray:
        """Velocity ``v`` (nv,) of the mechanism's whole tree (``mechanism.model.tree``,
        the order of :attr:`q`) for the actuated rates [rad/s or m/s]: the general
        elimination's at this configuration (:meth:`TreeAnalysis.joint_rates`), so both
        analyses of one machine give the same rates."""
        return self._tree_analysis.joint_rates(qdot_actuated)

    @cached_property
    def _tree_analysis(self) -> TreeAnalysis:
        """The general elimination at this configuration (made once, for
        :meth:`joint_rates`)."""
        return self.mechanism.general.analyze(self.q, nearby=0)

    def passive_rates(self, twist) -> list[np.ndarray]:
        """Every leg's joint rates (all joints, velocity order) for a platform twist."""
        t = self._check_twist(twist)
        if not self._admissible(t):
            raise InputError(f"twist {np.round(t, 6)} is not a motion of the platform here")
        out = []
        for leg, ls in zip(self.mechanism.legs, self.legs):
            qd, *_ = np.linalg.lstsq(ls.jacobian, t, rcond=None)
            out.append(qd)
        return out


@dataclass(frozen=True)
class Mobility:
    """Mobility of a linkage at a configuration (:meth:`Linkage.mobility`).

    Attributes:
        dof: ``nv − rank J_c``: dimension of the tree's motions the closures allow.
        redundant_constraints: ``rows − rank J_c``: closure rows counted more than once.
        idle_dof: Dimension of the motions left when every actuated joint is locked.
        idle_motions: One sentence per idle motion (a basis of them).
        independent_actuators: The actuated joints that can be driven independently
            (the first maximal independent set, in actuated order).
        grubler: Grübler–Kutzbach count ``Σ joint nv − Σ closure rows``.
        rank: ``rank J_c`` here.
        generic_dof, generic_idle_dof: ``dof`` and ``idle_dof`` at generic
            configurations: the largest ranks of ``J_c`` and of ``J_c`` with the
            actuated rows among this configuration and
            :data:`~pkm_pin.tolerances.NEARBY_SAMPLES` nearby ones on the closure
            manifold (a step along the allowed motions, and off the representation
            singularities, projected back by the tree solver; seeded); ``None``: not
            sampled (``nearby=0``).
        singular: Whether a rank here is below the generic one (``None``: not decided).
        representation: Representation singularities here, one sentence each (three
            revolutes at a gimbal lock, a joint exactly at a limit).
    """

    dof: int
    redundant_constraints: int
    idle_dof: int
    idle_motions: tuple
    independent_actuators: tuple
    grubler: int
    rank: int | None = None
    generic_dof: int | None = None
    generic_idle_dof: int | None = None
    singular: bool | None = None
    representation: tuple = ()

    @property
    def singular_words(self) -> str:
        """One sentence on a singular configuration (its ranks against the generic ones
        and the representation singularities); ``""`` when it is not singular."""
        if not self.singular:
            return ""
        nv = self.dof + self.rank
        locked, generic_locked = nv - self.idle_dof, nv - self.generic_idle_dof
        text = (f"singular configuration: DOF {self.dof}, idle DOF {self.idle_dof} here, "
                f"{self.generic_dof} and {self.generic_idle_dof} at nearby configurations "
                f"on the closure manifold (closure Jacobian rank {self.rank}, generic "
                f"{nv - self.generic_dof}; with the actuated joints locked {locked}, "
                f"generic {generic_locked})")
        if self.representation:
            text += "; representation singularity: " + "; ".join(self.representation)
        return text


@dataclass(frozen=True, eq=False, init=False)
class TreeAnalysis(Analysis):
    """The general elimination's :class:`Analysis`: the output frame of a mechanism read
    over its whole tree at one configuration (:meth:`pkm_pin.linkage.Linkage.analyze`;
    ``TreeAnalysis(assembly, **options)`` is ``assembly.mechanism.analyze(assembly,
    **options)``).

    Screws are axis-first about the world origin; ``reference_point`` [m] is the point
    they are homogenised about for every decision (output origin or world origin).

    Attributes:
        q: The configuration analysed.
        mobility: The :class:`Mobility` (``dof``, ``idle_dof`` … are also attributes).
        output_dof: Dimension of the output frame's twist system.
        translations: Pure translations among them (motion type ``"2T1R"`` …).
        platform_twists: (output_dof × 6) basis of the output twists, orthonormal once
            homogenised about ``reference_point``.
        constraint_wrenches: ((6 − output_dof) × 6) basis of the wrenches reciprocal to
            them, orthonormal once homogenised about ``reference_point``.
        A: (actuated × 6) actuation wrenches (unit force, or unit moment).
        B: (actuated × actuated) diagonal, ``A Δ t = B q̇_a`` for every admissible ``t``.
        indices: ``type_I``, ``type_II``, ``condition_A`` (seed 000's), ``forward``,
            ``inverse`` (module docstring).
        singularity: ``"none"``, ``"I"``, ``"II"`` or ``"III"``.
        constraint_singular: Whether ``dof`` or ``output_dof`` differs from the generic
            analysis given (``None`` without one).
        mechanism: The general backend that analysed it
            (:class:`~pkm_pin.linkage.Linkage`).
        rtol: Relative tolerance of its rank decisions.
        about: ``"output"`` or ``"world"``: where :attr:`reference_point` is.
    """

    q: np.ndarray = field(repr=False)
    mobility: Mobility
    output_dof: int
    translations: int
    platform_twists: np.ndarray = field(repr=False)
    constraint_wrenches: np.ndarray = field(repr=False)
    A: np.ndarray = field(repr=False)
    B: np.ndarray = field(repr=False)
    indices: dict
    singularity: str
    constraint_singular: bool | None
    reference_point: np.ndarray = field(repr=False)
    length: float
    singular_tol: float
    _maps: tuple = field(repr=False)
    #: Whether each actuated joint is prismatic (its rate in m/s).
    actuated_prismatic: np.ndarray = field(repr=False)
    mechanism: object = field(repr=False)
    rtol: float = field(repr=False)
    about: str = field(repr=False)
    #: Kinematic redundancy: independent actuators beyond the output's directions of
    #: motion (:func:`pkm_pin.linkage.kinematic_redundancy`); where positive, the type I
    #: and inverse indices are 0 and the class I at every configuration.
    redundancy: int = 0
    #: Under-actuation: independent output motions with every actuated joint locked at a
    #: configuration whose ranks are the generic ones
    #: (:func:`pkm_pin.linkage.uncontrolled_output`; 0 where class II does not hold or
    #: the ranks were not compared); where positive, class II holds nearby too.
    underactuation: int = 0

    def __init__(self, assembly, **options):
        done = assembly.mechanism.analyze(assembly, **options)
        self.__dict__.update(done.__dict__)
        self.__dict__["assembly"] = assembly

    @classmethod
    def of_values(cls, **values) -> TreeAnalysis:
        """The analysis with every field given (no checks: what
        :meth:`~pkm_pin.linkage.Linkage.analyze` computed)."""
        out = object.__new__(cls)
        out.__dict__.update(values)
        return out

    # ------------------------------------------------ the names only legs had
    @cached_property
    def assembly(self):
        """The :class:`~pkm_pin.assembly.Assembly` analysed (of the general backend)."""
        return self.mechanism.assembly_at(self.q)

    @property
    def actuation_wrenches(self) -> np.ndarray:
        """Actuation wrenches (n × 6), one per actuated joint: the rows of :attr:`A`."""
        return self.A

    @cached_property
    def joint_twists(self) -> np.ndarray:
        """(nv × 6) row k: the axis-first twist ``(ω; v_O)`` about the world origin of
        the tree's velocity coordinate k (per unit rate)."""
        return self.mechanism.model.kinematics(self.q).joint_twists

    @property
    def actuated_twists(self) -> np.ndarray:
        """Twists (n × 6) of the actuated joints, in actuated-coordinate order."""
        return self.joint_twists[list(self.mechanism.model.actuated_v)]

    @cached_property
    def transmission(self):
        """Motion/force transmission indices ITI, OTI, LTI and CTI of the actuators'
        sides of the loops (:meth:`pkm_pin.linkage.Linkage.transmission`)."""
        return self.mechanism.transmission(
            self.q, analysis=self if self.about == "output" else None)

    @property
    def legs(self):
        """Refused: a mechanism read over its tree has no legs."""
        raise _no_legs("legs")

    @property
    def leg_constraint_wrenches(self):
        """Refused: a mechanism read over its tree has no legs."""
        raise _no_legs("leg_constraint_wrenches")

    # ------------------------------------------------ hooks of OutputMaps
    @property
    def centre(self) -> np.ndarray:
        """The point every decision is homogenised about (:attr:`reference_point`)."""
        return self.reference_point

    @property
    def motion_indices(self) -> dict[str, float]:
        """The ``forward`` and ``inverse`` indices (:func:`pkm_pin.screws.motion_indices`),
        as :attr:`pkm_pin.analysis.Analysis.motion_indices` names them."""
        return {"forward": self.indices["forward"], "inverse": self.indices["inverse"]}

    @property
    def _twist_dim(self) -> int:
        return self.output_dof

    @property
    def _actuated_prismatic(self) -> np.ndarray:
        return self.actuated_prismatic

    @property
    def _closeness(self) -> tuple[float, float]:
        """Seed 000's indices and the generalised ones together, as :attr:`singularity`
        reads them."""
        idx = self.indices
        return (float(np.nanmin([idx["type_I"], idx["inverse"]])),
                float(np.nanmin([idx["type_II"], idx["forward"]])))

    @property
    def dof(self) -> int:
        """``nv − rank J_c`` (:attr:`Mobility.dof`)."""
        return self.mobility.dof

    @property
    def idle_dof(self) -> int:
        """:attr:`Mobility.idle_dof`."""
        return self.mobility.idle_dof

    @property
    def redundant_constraints(self) -> int:
        """:attr:`Mobility.redundant_constraints`."""
        return self.mobility.redundant_constraints

    @property
    def grubler(self) -> int:
        """Grübler–Kutzbach count of the tree and its closures (:attr:`Mobility.grubler`;
        a per-leg :class:`~pkm_pin.analysis.Analysis` answers the same name)."""
        return self.mobility.grubler

    @property
    def motion_type(self) -> str:
        """``"3T"``, ``"1T2R"``, ``"3T3R"`` … of the output; ``"0"`` when it is rigid."""
        t, r = self.translations, self.output_dof - self.translations
        return (f"{t}T" if t else "") + (f"{r}R" if r else "") or "0"

    # ------------------------------------------------------------- velocities
    def _contains(self, t: np.ndarray) -> bool:
        P = homogenised_about(self.platform_twists, self.reference_point, self.length)
        th = homogenised_about(t[None], self.reference_point, self.length)[0]
        out = th - (th @ P.T) @ P if P.size else th
        return np.linalg.norm(out) <= SPAN_RTOL * max(np.linalg.norm(th), 1e-300)

    def passive_rates(self, twist):
        """Refused: each leg's joint rates for an output twist need legs
        (:meth:`joint_rates` of :meth:`inverse_velocity` gives the tree's)."""
        raise _no_legs("passive_rates",
                       "joint_rates(inverse_velocity(twist)) gives the tree's joint rates")

    def joint_rates(self, qdot_actuated) -> np.ndarray:
        """Velocity ``v`` (nv,) of the whole tree for the actuated rates [rad/s or m/s]
        (internal motions that move neither the actuators nor the output: none).

        Raises:
            SingularityError: the actuators do not determine the motion (type II).
            InputError: wrong length, or rates incompatible with redundant actuation.
        """
        Xr, Yr, M, U, act = self._maps
        qd = screws.as_vector(qdot_actuated, Xr.shape[0], "qdot_actuated")
        if self.indices["forward"] < self.singular_tol:
            raise SingularityError(
                f"forward velocity undefined: forward index {self.indices['forward']:.3g} "
                f"< {self.singular_tol:g} (the actuators do not determine the motion)",
                "forward", self.indices["forward"])
        rhs = qd / U[act]
        z, *_ = np.linalg.lstsq(Xr, rhs, rcond=None)
        if np.linalg.norm(Xr @ z - rhs) > 1e-9 * max(1.0, np.linalg.norm(rhs)):
            raise InputError("these actuated rates are incompatible (redundant actuation)")
        return U * (M @ z)

    def forward_velocity(self, qdot_actuated) -> np.ndarray:
        """Output twist (6,) axis-first about the world origin from the actuated rates."""
        Xr, Yr, M, U, act = self._maps
        v = self.joint_rates(qdot_actuated)
        return from_homogenised(Yr @ np.linalg.lstsq(Xr, v[act] / U[act], rcond=None)[0],
                                self.reference_point, self.length)[0]

    def inverse_velocity(self, twist) -> np.ndarray:
        """Actuated rates producing the output twist ``twist`` (axis-first, world origin).

        Raises:
            InputError: the twist is not a motion of the output here.
            SingularityError: an actuator moves without moving the output (type I).
        """
        t = screws.as_vector(twist, 6, "twist", noun="components")
        if not self._contains(t):
            raise InputError(f"twist {np.round(t, 6)} is not a motion of the output here "
                             f"(motion type {self.motion_type})")
        if self.indices["inverse"] < self.singular_tol:
            raise SingularityError(
                f"inverse velocity undefined: inverse index {self.indices['inverse']:.3g} "
                f"< {self.singular_tol:g}", "inverse", self.indices["inverse"])
        Xr, Yr, M, U, act = self._maps
        th = homogenised_about(t[None], self.reference_point, self.length)[0]
        z, *_ = np.linalg.lstsq(Yr, th, rcond=None)
        return U[act] * (Xr @ z)



#: The general backend's name of :class:`TreeAnalysis`.
LinkageAnalysis = TreeAnalysis


def _no_legs(name: str, instead: str = "") -> PkmError:
    """Why a general analysis has no ``name`` (``instead``: what answers instead)."""
    return PkmError(f"{name}: this analysis is the general elimination over the tree, "
                    "which reads no legs; " + (f"{instead}; " if instead else "")
                    + "where a base–legs–platform machine is detected in the model, "
                    "mech.legs_mechanism.analyze(...) reads it per leg")


def classify(type_I, type_II, tol: float = SINGULAR_TOL):
    """Singularity class(es) from closeness indices: ``"none"``, ``"I"``, ``"II"``, ``"III"``.

    Works on scalars (returns a str) and on arrays (returns an array of str)."""
    if isinstance(type_I, float) and isinstance(type_II, float):
        return _CLASS_NAMES[(type_I < tol) + 2 * (type_II < tol)]
    code = (np.asarray(type_I) < tol).astype(np.int8) + 2 * (np.asarray(type_II) < tol)
    out = _CLASSES[code]
    return str(out) if out.ndim == 0 else out


_CLASS_NAMES = ("none", "I", "II", "III")  # by (type I) + 2 (type II)
_CLASSES = np.array(_CLASS_NAMES)


def layout_of(mechanism, rtol: float = screws.RTOL, reference=None) -> engine.Layout:
    """The engine's :class:`~pkm_pin.engine.Layout` of a mechanism (legs one after the
    other; ``reference``: platform basis for the carried determinant, homogenised about
    its pose's centre)."""
    offs = mechanism.leg_frames.coords
    legs = mechanism.legs
    groups = np.array([offs[i] + np.array(g) for i, leg in enumerate(legs)
                       for g in leg.spherical_groups], dtype=np.int64).reshape(-1, 3)
    act_col = np.concatenate([offs[i] + np.atleast_1d(leg.actuated_v)
                              for i, leg in enumerate(legs)]).astype(np.int64)
    act_leg = np.concatenate([np.full(len(np.atleast_1d(leg.actuated_v)), i)
                              for i, leg in enumerate(legs)]).astype(np.int64)
    ref = np.zeros((0, 6)) if reference is None else np.ascontiguousarray(reference, float)
    return engine.Layout(offs, groups, act_col, act_leg, ref,
                         float(mechanism.characteristic_length), float(rtol),
                         ROTATION_COUNT_TOL)

