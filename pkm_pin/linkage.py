"""General closed-loop linkages: assembly, mobility, output analysis and position problems
of any :class:`~pkm_pin.model.closure_model.ClosureModel` (one Pinocchio tree plus
closures; issue 16).

A :class:`Linkage` wraps one closure model and answers, at a configuration ``q`` of the
whole tree:

* **Assembly and position problems** (:meth:`Linkage.assemble`,
  :meth:`~Linkage.forward_kinematics`, :meth:`~Linkage.inverse_kinematics`,
  :meth:`~Linkage.sweep`): the tree solver :func:`pkm_pin.solve.solve_tree` (damped
  Newton on the dimensionless closure residuals, the damping and stopping rules of the
  per-leg solver), with restarts (:func:`pkm_pin.solve.tree_starts`) and the branch
  nearest the guess.
* **Mobility** (:meth:`Linkage.mobility`): ``dof = nv − rank J_c``, redundant closure
  rows, idle motions (those left with every actuated joint locked: a sparse basis of
  them, :func:`sparse_basis`, each described in words), the actuated joints that can be
  driven independently, and Grübler's count; and whether the configuration is singular:
  the ranks of ``J_c`` and of ``J_c`` with the actuated rows against their generic
  values, the largest at a few nearby configurations on the closure manifold (a random
  step along the allowed motions, projected back by the tree solver, seeded), with the
  representation singularities found (three revolutes standing for a spherical joint at
  a gimbal lock, a joint exactly at a limit).
* **Output analysis** (:meth:`Linkage.analyze` → :class:`LinkageAnalysis`): the output
  frame's twist system, its constraint wrenches, ``A Δ t = B q̇_a``, velocity maps,
  singularity classes and dimensionless indices.

Conventions
-----------
Twists ``(ω; v_O)`` and wrenches ``(f; m_O)`` are axis-first about the **world origin**
[rad/s, m/s; N, N m] (:mod:`pkm_pin.screws`, the only conversion from Pinocchio's
``(v; ω)``); ``v`` is the tree's velocity (Pinocchio's tangent space). Every rank
decision is made on dimensionless matrices: the columns of ``J_c`` are rates of
coordinates counted in radians or in lengths ``L`` (:attr:`ClosureModel.velocity_units`,
``L`` = :attr:`ClosureModel.length`), output twists and wrenches are homogenised
(moment part / ``L``) about a point attached to the mechanism — the output frame's
origin by default (``about="output"``) — and singular values below ``rtol``
(:data:`~pkm_pin.tolerances.RANK_RTOL`) times the largest are zero. The results do not
change with the units (metres or millimetres) nor when the whole mechanism is moved in
the world.

Elimination of the passive rates (``A Δ t = B q̇_a``)
-----------------------------------------------------
Stack the closure rows and the output rows ``t_h = H_o v`` (homogenised output twist)
into ``G`` (columns per dimensionless velocity coordinate). A row vector ``w = (w_c;
w_o)`` with ``w G_j = 0`` for every column ``j`` except actuated joint ``a``'s gives
``ζ ∘ t = L β q̇_a / u_a`` with ``ζ`` the wrench read from ``w_o`` and ``β = w G_a``.
For actuator ``a`` only the closures whose tree path (between their two frames) contains
``a`` are stacked — for :func:`~pkm_pin.model.closure_model.from_mechanism` trees, the
weld of ``a``'s leg — and among the admissible ``ζ`` the one orthogonal (homogenised)
to those with ``β = 0`` is the actuation wrench, scaled to a unit force (a unit moment
for a couple), ``B_aa ≥ 0``. For a base–legs–platform tree this is seed 000's actuation
wrench of the leg (reciprocal to the leg's other joint twists, orthogonal to the leg's
constraint wrenches), so ``A``, ``B`` and the indices equal :class:`pkm_pin.Analysis`'s
(both homogenise about the platform's origin, the default ``about="output"``).

Indices and classes
-------------------
``indices["type_I"]`` (smallest ``|B_aa| / (L |A_a|_h |$_a|_h)``), ``"type_II"``
(smallest singular value of ``A_h Δ P_hᵀ``, unit rows of ``A``, orthonormal output
twists ``P``; 0 with fewer actuators than output DOF) and ``"condition_A"`` are seed
000's. They are blind where the output body lies on a loop path with a 1-DOF output
(``A`` then has no component along the output's own constraints). The general indices
``"forward"`` and ``"inverse"`` come straight from the null space ``N`` of ``J_c``: with
``X`` the actuated rates and ``Y`` the homogenised output twists of the motions
(internal motions that move neither removed), ``forward = min |X z| / |(X; Y) z|`` (0:
the output moves with the actuators locked) and ``inverse = min |Y z| / |(X; Y) z|`` (0:
an actuator moves without moving the output). Class I: ``min(type_I, inverse) <
tol``; II: ``min(type_II, forward) < tol``; III: both. A kinematically redundant
mechanism (more independent actuators than its output has directions of motion: a 7R
arm, a biped read with one foot as the output; :func:`kinematic_redundancy`) moves its
actuators with the output held everywhere: its type I and inverse indices are 0 and its
class I at every configuration, which marks the redundancy, not a singular pose; the
analysis's ``redundancy`` counts those self-motions (at least) and the report says so.
"""

from __future__ import annotations

import contextlib
import copy
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
import pinocchio as pin

from . import dynamics as _dynamics
from . import general_kernel, screws
from .analysis import LinkageAnalysis, Mobility, TreeAnalysis, classify
from .assembly import Assembly, LinkageAssembly, as_pose
from .checkpoint import recording
from .closure_gaps import Diagnosis, diagnose
from .errors import (
    AssemblyError,
    ForwardKinematicsError,
    InputError,
    PkmError,
)
from .model.closure_model import (
    ClosureModel,
    NullSpace,
    TreeKinematics,
    default_length,
    pose_rows,
    sparse_basis,
)
from .model.structure import detect_platform, legs_length
from .screws import from_homogenised, homogenised_about, svd_rank
from .solve import (
    POSE_COORDINATES,
    TreeSolution,
    iter_tree_starts,
    pose_coordinates,
    solve_tree,
    solve_tree_starts,
    tree_starts,
)
from .sweep import SweepResult
from .tolerances import (
    CLOSENESS_SINGULAR_TOL,
    CLOSURE_TOL,
    FK_CONTINUATION_CORRECTION,
    FK_CONTINUATION_MAX_SOLVES,
    FK_CONTINUATION_STEP_ITER,
    FK_FOLD_REACH,
    GIMBAL_LOCK_RTOL,
    JOINT_LIMIT_SLACK,
    MODES_ESTIMATE_FROM,
    MODES_MAX,
    MODES_MAX_BATCHES,
    MODES_PATIENCE,
    NEARBY_SAMPLES,
    NEARBY_STEP,
    RANK_RTOL,
    ROTATION_COUNT_TOL,
    SAME_CONFIGURATION_TOL,
)

__all__ = ["Linkage", "LinkageAnalysis", "LinkageAssembly", "LinkageSweep", "LoopClosureError",
           "Mobility", "sparse_basis"]


class LoopClosureError(AssemblyError):
    """A loop of a linkage does not close (an :class:`AssemblyError` whose ``leg`` is the
    name of the worst closure, or of the actuated or output targets).

    The message names the worst loop and its residual, then (from :attr:`diagnosis`)
    every loop left open with its gap in mm and degrees, the joints held at a limit and a
    hint (:mod:`pkm_pin.closure_gaps`).

    Attributes:
        leg: Name of the loop (closure) that does not close.
        residual: Its residual (dimensionless, as :meth:`ClosureModel.closure_residual`).
        q: The best configuration reached (nq,), or None: ``pkm-pin view`` draws the
            open tree there.
        diagnosis: The :class:`~pkm_pin.closure_gaps.Diagnosis` at :attr:`q`, or None.
        continuation: For a forward kinematics from a guess whose direct solve failed,
            the continuation from the guess along the straight path of actuated values
            (``t``: the fraction of the path where the loops still closed; ``fold``:
            it stopped at a fold, a type II singularity, at ``t_fold``; ``type_ii``: the
            closeness index at the guess and at ``t``; ``q_actuated``: the actuated
            values at ``t``),
            else None. When it ran, the message begins with what it found.
    """

    def __init__(self, loop: str, residual: float, detail: str = "", *, q=None,
                 diagnosis: Diagnosis | None = None, cause: str = ""):
        super().__init__(loop, residual, detail)
        self.q = None if q is None else np.array(q, dtype=float)
        self.diagnosis = diagnosis
        self.continuation = None
        if loop == "output pose":  # the output's targets, not a closure
            head = "the output cannot reach the pose"
        elif loop == "actuated targets":
            head = "the actuated joints cannot all take their values"
        else:
            head = f"loop {loop!r} does not close"
        message = (f"{head}: the best configuration found within the joint limits leaves "
                   f"a relative residual of {self.residual:.3g}")
        message += f" ({detail})" if detail else ""
        words = "" if diagnosis is None else diagnosis.words()
        self.args = ((f"{cause}; " if cause else "") + message
                     + (f"; {words}" if words else ""),)

    def __str__(self) -> str:
        return self.args[0]


@dataclass(eq=False)
class _Continuation:
    """A forward kinematics' continuation from its guess (:meth:`Linkage._continuation`):
    the solution at the target (None: not reached), the fraction ``t`` of the straight
    path of actuated values reached, the assemblies it started from (``origin``; None:
    the guess could not be closed) and last reached (``q``), the solves and iterations
    spent; filled in by :meth:`Linkage._fold_words` on a failure: the type II closeness
    index at ``origin`` and ``q``, the actuated values at ``q``, the fraction of the path
    where that index extrapolates to zero (``t_fold``) and whether it stopped at a
    fold."""

    solution: TreeSolution | None
    t: float
    origin: np.ndarray | None = field(repr=False)
    q: np.ndarray | None = field(repr=False)
    solves: int
    iterations: int
    type_ii: tuple = ()
    q_actuated: np.ndarray | None = field(default=None, repr=False)
    t_fold: float = math.inf
    fold: bool = False


class Linkage:
    """A general closed-loop mechanism (see the module docstring).

    This is the general backend of :class:`pkm_pin.Mechanism` (which every file gives);
    it stands alone on any closure model.

    Args:
        model: The closure model (immutable; kept as :attr:`model`).
        output: Another frame of the tree to analyse instead of ``model.output``.
        point: Analyse the output frame's origin as a point (its translations only,
            :attr:`ClosureModel.output_point`), or as a body (``False``); default: as
            ``model`` says.
        legs: The per-leg reading of a base–legs–platform machine detected in the model
            (a function of the tree configuration returning the legs backend, a
            :class:`pkm_pin.Mechanism`): what :attr:`legs_mechanism` and the
            capabilities that read a machine leg by leg use. :class:`pkm_pin.Mechanism`
            gives it; a linkage made alone has none and refuses those capabilities with
            the reason.
    """

    #: Which backend answers (:attr:`pkm_pin.Mechanism.backend`): the general elimination.
    backend = "general"

    def __init__(self, model: ClosureModel, output: str | None = None,
                 point: bool | None = None, *,
                 legs: Callable[[np.ndarray], object] | None = None):
        if not isinstance(model, ClosureModel):
            raise InputError(f"model must be a ClosureModel, got {type(model).__name__}")
        if output is not None and output != model.output:
            model = replace(model, output=output)
        if point is not None and bool(point) != model.output_point:
            model = replace(model, output_point=bool(point))
        self._model = _machine_length(model)
        self._loops = _loops_of_actuators(model)
        #: ``(rank J_c, rank with the actuated rows)`` at the first configuration whose
        #: nearby ones were sampled (:func:`_mobility`): later configurations with the
        #: same ranks are generic without sampling again.
        self._generic_ranks: tuple[int, int] | None = None
        self._closure_names = tuple(c.name or f"closure {k}"
                                    for k, c in enumerate(model.closures))
        self._legs_reader = legs

    def __repr__(self) -> str:
        return f"Linkage({self.name!r}, actuated={self.actuated}, output={self.output!r})"

    @property
    def model(self) -> ClosureModel:
        """The closure model."""
        return self._model

    def with_legs(self, legs: Callable[[np.ndarray], object]) -> Linkage:
        """This linkage with the per-leg reader ``legs`` (the ``legs`` argument), what it
        has computed kept (its home assembly)."""
        other = copy.copy(self)
        other.__dict__.pop("legs_mechanism", None)
        other._legs_reader = legs
        return other

    @property
    def general(self) -> Linkage:
        """The general reading of this mechanism: itself (:attr:`pkm_pin.Mechanism.general`
        gives the same name on every mechanism)."""
        return self

    @property
    def name(self) -> str:
        """Name of the mechanism."""
        return self._model.name

    @property
    def actuated(self) -> tuple:
        """Names of the actuated joints."""
        return self._model.actuated

    # The names every mechanism answers (a Mechanism has the same).
    def tree_configuration(self, assembly: Assembly | None = None) -> np.ndarray:
        """The configuration of :attr:`model`'s tree at ``assembly`` (default home)."""
        return (self.home_assembly if assembly is None else assembly).q.copy()

    @property
    def closure_model(self) -> ClosureModel:
        """The closure model (:attr:`model`)."""
        return self._model

    @property
    def actuated_names(self) -> list[str]:
        """Names of the actuated joints (:attr:`actuated`), as a list."""
        return list(self._model.actuated)

    @property
    def n_actuated(self) -> int:
        """Number of actuated joints."""
        return len(self._model.actuated)

    @property
    def characteristic_length(self) -> float:
        """The unit of length of every homogenised index [m]: the model's length (the
        legs' where a platform structure is detected: :func:`_machine_length`)."""
        return self._model.length

    @property
    def output(self) -> str:
        """Name of the output frame."""
        return self._model.output

    @cached_property
    def platform_structure(self) -> tuple:
        """``(structure, reason)`` of :func:`pkm_pin.model.structure.detect_platform`: the
        base–legs–platform machine found in the model (the per-leg engine reads it:
        ``load_mechanism(..., backend="legs")``), or ``None`` and why not (cached)."""
        return detect_platform(self._model)

    @cached_property
    def legs_mechanism(self):
        """The per-leg reading of this linkage (:meth:`pkm_pin.Mechanism.from_closure_model`
        at :attr:`home_assembly`, through the ``legs`` reader given): what the
        capabilities that read a machine leg by leg (sensitivity to geometric errors,
        every working mode, the Study homotopy) use (cached).

        Raises:
            InputError: no base–legs–platform structure in the model (the reason), or a
                linkage made alone (no ``legs`` reader: use :class:`pkm_pin.Mechanism`).
        """
        self._check_legs(None)
        return self._legs_reader(self.home_assembly.q)

    def _legs(self, what: str):
        """:attr:`legs_mechanism`, or an :class:`InputError` saying that ``what`` needs
        legs and why this model has none."""
        self._check_legs(what)
        return self.legs_mechanism

    def _check_legs(self, what: str | None) -> None:
        """An :class:`InputError` where there is no per-leg reading: no base–legs–platform
        structure in the model (the reason), or a linkage made alone; ``what``: the
        capability that needs one (None: the reading itself)."""
        structure, reason = self.platform_structure
        name = self.name or "this linkage"
        if structure is None:
            raise InputError(f"{name} is not a base–legs–platform machine: {reason}"
                             if what is None else
                             f"{what} reads a machine leg by leg (legs between the base "
                             f"and one platform), and {name} is not one: {reason}")
        if self._legs_reader is None:
            raise InputError(("" if what is None else f"{what} reads a machine leg by leg: ")
                             + "a Linkage made alone has no per-leg reading; load the file "
                             "with pkm_pin.load_mechanism or use "
                             "pkm_pin.Mechanism.from_model(model)")

    def legs_assembly(self, q=None) -> Assembly:
        """The assembly of :attr:`legs_mechanism` at the tree configuration ``q`` (a
        :class:`Assembly` or q; default home): the same pose, each leg's joints
        from ``q``."""
        mech = self._legs("a per-leg assembly")
        q = self.home_assembly.q if q is None else self._guess_q(q)
        kin = self._model.kinematics(q)
        guess = []
        for leg, chain in zip(mech.structure.legs, mech.legs):
            values = [q[self._model.tree.joints[j].idx_q:self._model.tree.joints[j].idx_q
                        + self._model.tree.joints[j].nq] for j in leg.joints]
            known = np.concatenate(values) if values else np.zeros(0)
            guess.append(np.r_[known, np.zeros(chain.nq - known.size)])
        return mech.assemble(kin.output_placement, guess=guess)

    def sensitivity(self, q=None, parameters=None):
        """Sensitivity of the output pose to geometric errors at ``q`` (a
        :class:`Assembly` or the tree's configuration; default home), actuated
        joints held: a :class:`~pkm_pin.sensitivity.Sensitivity`.

        A base–legs–platform machine is read leg by leg through :attr:`legs_mechanism`
        (:func:`pkm_pin.sensitivity.sensitivity`: the legs' joint origins and axes, bases,
        anchors); any other linkage through its closure Jacobian
        (:func:`pkm_pin.tree_sensitivity.sensitivity`: the tree's joint origins and
        axes, the closures' frames), whose parameters
        (:func:`pkm_pin.tree_sensitivity.parameter_names`) any linkage also answers
        through :meth:`tree_sensitivity`.

        Raises:
            InputError: unknown parameter names.
            SingularityError: the output error is undetermined (type II singularity).
        """
        if self.platform_structure[0] is None:
            return self.tree_sensitivity(q, parameters)
        mech = self._legs("sensitivity to geometric errors")
        return mech.sensitivity(self.legs_assembly(q), parameters)

    def tree_sensitivity(self, q=None, parameters=None):
        """Sensitivity of the output to the geometric errors of the tree and closures
        (:func:`pkm_pin.tree_sensitivity.sensitivity`) at ``q`` (a
        :class:`Assembly` or the tree's configuration; default home)."""
        from .tree_sensitivity import sensitivity

        if q is None:
            q = self.home_assembly
        assembly = q if isinstance(q, Assembly) else self._at(self._guess_q(q))
        return sensitivity(self._model, assembly.q, parameters, assembly=assembly)

    def calibrate(self, samples, parameters, **options):
        """Identify geometric errors from measured output poses or positions after known
        actuations (:func:`pkm_pin.calibration.calibrate`): ``samples`` are pairs
        ``(q_actuated, measured)`` with the actuated values in :attr:`actuated` order,
        ``parameters`` the names :meth:`sensitivity` uses: a base–legs–platform machine's
        legs' (read leg by leg through :attr:`legs_mechanism`), any other linkage's
        tree's (:mod:`pkm_pin.tree_sensitivity`; the calibrated result's ``mechanism``
        is then a :class:`Linkage` of the corrected model)."""
        if self.platform_structure[0] is not None:
            return self._legs("calibration").calibrate(samples, parameters, **options)
        from .calibration import Geometry, calibrate
        from .tree_sensitivity import perturb, select_parameters

        home = self.home_assembly
        geometry = Geometry(
            select=lambda link, names: select_parameters(link.model, names),
            solve=lambda link, qa, guess: link.forward_kinematics(
                qa, guess=(home if guess is None else guess).q),
            sensitivity=lambda link, a, names: link.tree_sensitivity(a, names),
            perturb=lambda link, errors: Linkage(perturb(link.model, errors)))
        return calibrate(self, samples, parameters, geometry=geometry, **options)

    def inverse_kinematics_all(self, pose, *, starts: int = 16, seed: int = 0,
                               patience: int = MODES_PATIENCE, tol: float = CLOSURE_TOL
                               ) -> list[Assembly]:
        """Every working mode at the output ``pose`` (``pin.SE3``), as configurations of
        this tree: for a base–legs–platform machine, one assembly per distinct vector of
        actuated values found leg by leg (:meth:`Mechanism.inverse_kinematics_all` of
        :attr:`legs_mechanism`); for any other linkage, a multistart of the tree solver
        with the output at ``pose`` (:meth:`_inverse_multistart`: batches of ``starts``
        configurations within the joint limits, home's first, stopped after ``patience``
        batches find no new mode; two assemblies are one mode when every joint origin
        and the output agree, as :meth:`forward_kinematics_all` decides), nearest home
        first. A multistart proves nothing: a mode no start falls into is not listed.

        Raises:
            AssemblyError: no start reaches the pose (:class:`LoopClosureError`), or the
                assemblies at the pose do not settle into modes (a continuum).
        """
        if self.platform_structure[0] is not None:
            try:
                mech = self._legs("every working mode of a pose")
            except (InputError, AssemblyError):
                mech = None
            if mech is not None:
                return [self.assemble(mech.source_configuration(a), starts=0)
                        for a in mech.inverse_kinematics_all(pose, starts=starts, seed=seed)]
        return self._inverse_multistart(pose, starts, seed, patience, tol)

    def _inverse_multistart(self, pose, starts: int, seed: int, patience: int,
                            tol: float) -> list[Assembly]:
        """:meth:`inverse_kinematics_all` of a linkage without legs to read: the tree
        solver with the output's pose rows (the components its twist system at home
        moves along, as :meth:`inverse_kinematics`) from batches of starts. Of the
        assemblies that meet those rows, those whose whole output pose is nearest
        ``pose`` are kept (a lower-mobility output meets its rows elsewhere too, with
        other components imposed: another pose, not another working mode; a point
        output by its position alone)."""
        if not isinstance(pose, pin.SE3) or not np.isfinite(pose.homogeneous).all():
            raise InputError(f"pose must be a finite pinocchio.SE3, got {type(pose).__name__}")
        model, home = self._model, self.home_assembly
        rows = pose_rows(model, model.kinematics(home.q))

        def too_many(n: int, tried: int, estimate: float) -> PkmError:
            return AssemblyError("output pose", float("nan"), (
                f"the assemblies of {self.name!r} at this output pose do not settle into "
                f"working modes: {n} distinct ones after {tried} starts, "
                f"{_estimate_words(n, estimate)} (a continuum: the "
                "actuators move with the output held); inverse_kinematics gives the one "
                "nearest a guess"))

        run = self._multistart(
            lambda q0: solve_tree(model, q0, pose=pose, pose_rows=rows, tol=tol), home.q,
            starts, seed, patience, too_many)
        if not run.found:
            raise self._failure(run.best, run.tried, None, "output pose")
        found, L = run.found, model.length
        if model.output_point:  # a point: its position alone
            off = [float(np.linalg.norm(a.output_pose.translation - pose.translation)) / L
                   for a in found]
        else:
            off = [float(np.linalg.norm(screws.homogenise(screws.from_pinocchio(
                pin.log6(pose.actInv(a.output_pose))), L))) for a in found]
        keep = [k for k, e in enumerate(off) if e <= min(off) + SAME_CONFIGURATION_TOL]
        run.found = [run.found[k] for k in keep]
        run.signatures = [run.signatures[k] for k in keep]
        return run.nearest(self._signature(home.q))

    @cached_property
    def home_assembly(self) -> Assembly:
        """The assembly from the model's reference (the file's ``q = 0`` or MJCF
        ``qpos0``: its intended working mode), :meth:`assemble` with no guess (cached)."""
        return self.assemble()

    @cached_property
    def home_analysis(self) -> LinkageAnalysis:
        """The analysis of :attr:`home_assembly` (cached)."""
        return self.analyze(self.home_assembly)

    def submechanisms(self, q=None) -> list:
        """The independent sub-mechanisms (groups of closures and actuators that share no
        movable joint: a biped's two legs) at the assembled tree configuration ``q``
        (default: :attr:`home_assembly`), each a :class:`Linkage` with its own output,
        the other groups' joints locked at ``q``; ``[self]`` for a single mechanism
        (:func:`pkm_pin.submechanisms.submechanisms`)."""
        from .submechanisms import submechanisms

        return submechanisms(self, q)

    @property
    def grubler(self) -> int:
        """Grübler–Kutzbach count ``Σ joint nv − Σ closure rows`` (for comparison with
        :attr:`Mobility.dof`: it ignores redundant rows)."""
        return self._model.nv - self._model.n_rows

    # ---------------------------------------------------------------- inputs
    def check_actuated(self, q_actuated, name: str = "q_actuated") -> np.ndarray:
        """``q_actuated`` as a finite array of one value per actuated joint."""
        if screws.is_vector(q_actuated, len(self.actuated)):
            return q_actuated
        return screws.as_vector(q_actuated, len(self.actuated), name, ", ".join(self.actuated))

    def assembly_at(self, where=None) -> Assembly:
        """What :meth:`pkm_pin.Mechanism.assembly_at` answers, on the tree: the home
        assembly (``None``), a :class:`Assembly` as it is, the assembly nearest
        a configuration of the tree (a 1-D vector of its ``nq`` numbers, ``nq`` ≠ 6:
        :meth:`assemble`), or the assembly whose output reaches a pose
        (:meth:`inverse_kinematics`: ``pin.SE3``, a 4×4 matrix, six numbers x, y, z,
        roll, pitch, yaw, or a partial pose as a mapping)."""
        if where is None:
            return self.home_assembly
        if isinstance(where, Assembly):
            return where
        if isinstance(where, Mapping):
            return self.inverse_kinematics(where)
        if not isinstance(where, pin.SE3):
            shape = np.shape(where)
            if len(shape) == 1 and shape[0] == self._model.nq != 6:
                return self.assemble(where)
            where = as_pose(where)
        return self.inverse_kinematics(where)

    def _guess_q(self, guess) -> np.ndarray | None:
        if guess is None:
            return None
        if isinstance(guess, Assembly):
            return guess.q
        return self._model.check_q(guess)

    # ------------------------------------------------------------ assembly
    def assemble(self, guess=None, *, q_actuated=None, starts: int = 16, seed: int = 0,
                 tol: float = CLOSURE_TOL, max_iter: int = 100,
                 continuation: bool = False) -> Assembly:
        """Close every loop (and, with ``q_actuated``, pin the actuated joints).

        Starts (:func:`pkm_pin.solve.tree_starts`): ``guess`` (a configuration or a
        :class:`Assembly`), ``model.reference``, neutral, the middle of the limits
        and ``starts`` random configurations within the limits (``seed``). A converged
        warm start is kept; otherwise the converged solution nearest ``guess`` (default
        the reference) is. With ``continuation`` (:meth:`forward_kinematics`),
        ``q_actuated`` and a guess whose direct solve fails, the guess's branch is first
        continued along the straight path of actuated values (:meth:`_continuation`);
        when that stops short too, the other starts are tried and the error says how far
        the continuation got and whether a fold (a type II singularity) stopped it
        (:meth:`_fold_words`). A sweep (already a continuation, point to point) does
        without.
        A solution on a representation singularity (three revolutes
        at a gimbal lock, a joint exactly at a limit) whose ranks are below those of
        nearby configurations is not kept: the nearest generic configuration found by
        stepping off it along the allowed motions, keeping the actuated values (any
        values when none were asked for and none of those is generic), is
        (:meth:`_off_representation`; Gepetto's ``wl16_like`` otherwise assembles at
        a gimbal lock with 9 idle DOF instead of 6).

        Raises:
            LoopClosureError: no start closes; the message names the worst loop and its
                residual.
        """
        model = self._model
        warm = self._guess_q(guess)
        targets = None if q_actuated is None else self.check_actuated(q_actuated)
        rows = iter_tree_starts(model, warm, count=int(starts), seed=seed)
        path = None
        if warm is None or targets is None or not continuation:
            sol, iterations = solve_tree_starts(
                model, rows, targets=targets, tol=tol, max_iter=max_iter,
                nearest=model.reference if warm is None else warm)
        else:
            sol = solve_tree(model, next(rows), targets=targets, tol=tol, max_iter=max_iter)
            iterations = sol.iterations
            if not sol.converged:
                path = self._continuation(warm, targets, tol, max_iter)
                iterations += path.iterations
                if path.solution is not None:
                    sol = path.solution
                else:
                    rest, more = solve_tree_starts(model, rows, targets=targets, tol=tol,
                                                   max_iter=max_iter, nearest=warm,
                                                   keep_first=False)
                    iterations += more
                    sol = rest if rest.converged or rest.residual < sol.residual else sol
        if not sol.converged:
            raise self._failure(sol, int(starts) + 3 + (warm is not None), targets,
                                tol=tol, path=path)
        off = self._off_representation(sol.q, targets, seed, tol, max_iter)
        if off is not None:
            sol, iterations = off[0], iterations + off[1]
        return self._assembly(sol, iterations)

    def _continuation(self, warm: np.ndarray, targets: np.ndarray, tol: float,
                      max_iter: int) -> _Continuation:
        """Forward kinematics from the guess ``warm`` by continuation: the actuated
        values moved along the straight path from the guess's own to ``targets`` in
        steps (a fraction of the path: a half first, halved on a failure, doubled on a
        success), each closed by :func:`~pkm_pin.solve.solve_tree` from the last
        assembly reached, at most :data:`~pkm_pin.tolerances.FK_CONTINUATION_MAX_SOLVES`
        solves of at most :data:`~pkm_pin.tolerances.FK_CONTINUATION_STEP_ITER`
        iterations each (a step that needs more is halved). Each step starts from the
        first-order prediction (the tangent of the branch: the least-squares rates of
        the closure and actuated rows, no idle motion) and is kept only when the
        correction to it is at most :data:`~pkm_pin.tolerances.FK_CONTINUATION_CORRECTION`
        of the predicted motion (halved otherwise): a step across a fold onto another
        branch corrects by as much as it moves. A guess whose loops do not close is
        first closed at its own actuated values. The branch of the guess is followed up
        to a fold (a type II singularity), where the steps shrink until the budget is
        spent."""
        model = self._model
        start = _actuated_or_nan(model, warm)
        if not np.isfinite(start).all():
            return _Continuation(None, 0.0, None, None, 0, 0)
        q, solves, iterations = warm, 0, 0
        if float(model.closure_norms(model.kinematics(q).residual).max(initial=0.0)) > tol:
            sol = solve_tree(model, q, targets=start, tol=tol, max_iter=max_iter)
            solves, iterations = 1, sol.iterations
            if not sol.converged:
                return _Continuation(None, 0.0, None, None, solves, iterations)
            q = sol.q
        origin, t, h = q, 0.0, 0.5
        step_iter = min(max_iter, FK_CONTINUATION_STEP_ITER)
        U, rows = model.velocity_units, np.eye(model.nv)[list(model.actuated_v)]
        rhs = np.zeros(model.n_rows + len(start))
        rhs[model.n_rows:] = (targets - start) / U[list(model.actuated_v)]
        tangent = None
        while solves < FK_CONTINUATION_MAX_SOLVES:
            if tangent is None:  # d(v / U)/dt along the branch, no idle motion in it
                H = np.vstack([model.closure_jacobian(q) * U, rows])
                tangent = np.linalg.lstsq(H, rhs, rcond=None)[0]
            s = min(1.0, t + h)
            guess = pin.integrate(model.tree, q, (s - t) * U * tangent)
            sol = solve_tree(model, guess, targets=start + s * (targets - start), tol=tol,
                             max_iter=step_iter)
            solves, iterations = solves + 1, iterations + sol.iterations
            moved = float(np.linalg.norm(pin.difference(model.tree, guess, sol.q) / U))
            if not sol.converged or moved > FK_CONTINUATION_CORRECTION * (s - t) \
                    * float(np.linalg.norm(tangent)):
                h *= 0.5
                continue
            t, q, h, tangent = s, sol.q, 2.0 * h, None
            if t >= 1.0:
                return _Continuation(sol, 1.0, origin, q, solves, iterations)
        return _Continuation(None, t, origin, q, solves, iterations)

    def _fold_words(self, path: _Continuation, targets: np.ndarray) -> str:
        """What the continuation of a failed forward kinematics found (``""``: none ran
        from an assembly): how far along the straight path of actuated values it got and
        the type II closeness index there and at the guess.

        A fold (the guess's branch turns back at a type II singularity between the guess
        and the target) is told from the index: near a fold its square falls linearly
        with the path parameter to zero there, so the line through the squared indices
        at the guess (``t = 0``) and where the continuation stopped (``t``) meets zero at
        the fold (``t_fold``, kept on ``path``). A fold is reported where the index fell
        and ``t_fold`` lies before the target (``≤ 1``) and within
        :data:`~pkm_pin.tolerances.FK_FOLD_REACH` of the path beyond the stop."""
        if path is None or path.origin is None:
            return ""
        model = self._model
        at = [self.analyze(q, nearby=0).indices["type_II"] for q in (path.origin, path.q)]
        path.type_ii = tuple(float(x) for x in at)
        path.q_actuated = _actuated_or_nan(model, path.q)
        start = _actuated_or_nan(model, path.origin)
        s0, s1 = (x * x for x in path.type_ii)
        path.t_fold = path.t + s1 * path.t / (s0 - s1) if s1 < s0 else math.inf
        where = (f"continued from the guess (actuated {np.round(start, 6)}) along the "
                 f"straight path to {np.round(targets, 6)}, the loops close up to "
                 f"{100 * path.t:.3g}% of the way (actuated {np.round(path.q_actuated, 6)}; "
                 f"{path.solves} solves), where the type II closeness index is "
                 f"{_number(at[1])} ({_number(at[0])} at the guess"
                 + ("; undefined: an actuator exerts no wrench on the output, A has a zero "
                    "row" if any(math.isnan(x) for x in at) else "") + ")")
        if path.t > 0.0 and path.t_fold <= min(1.0, path.t + FK_FOLD_REACH):
            path.fold = True
            fold = start + path.t_fold * (targets - start)
            return ("the actuated values lie beyond a fold of the guess's assembly branch "
                    "(a type II singularity between the guess and them, where the branch "
                    f"turns back): {where}; its square falling linearly, the index reaches "
                    f"zero {100 * path.t_fold:.3g}% of the way (actuated "
                    f"{np.round(fold, 6)})")
        return f"{where}; no fold found on the way"

    def _off_representation(self, q: np.ndarray, targets, seed: int, tol: float,
                            max_iter: int):
        """A converged :class:`~pkm_pin.solve.TreeSolution` (and its iterations) at a
        generic configuration near ``q`` when ``q`` sits on a representation singularity
        (:func:`_representation`) whose ranks are below the generic ones; else ``None``.

        The nearby configurations of :func:`_nearby` (along the allowed motions, the
        locked coordinates stepped off and held, projected back) keep the actuated
        values (``targets``, or ``q``'s own); when none is generic and no targets were
        asked for, they may move the actuated joints too. The generic one nearest
        ``q`` is kept."""
        model = self._model
        hold, _ = _representation(model, None, q)
        if not hold:
            return None
        kin = model.kinematics(q)
        ns = NullSpace(model, kin, RANK_RTOL)
        here = _ranks(ns, RANK_RTOL)
        keep = targets if targets is not None else _actuated_or_nan(model, q)
        tries = [keep] if targets is not None or not np.isfinite(keep).all() else [keep, None]
        acted = set(model.actuated_v)
        for k, goal in enumerate(tries):
            held = [i for i in hold if goal is None or i not in acted]
            rng = np.random.default_rng(seed + k)
            found = _nearby(model, q, ns, held, rng, NEARBY_SAMPLES, NEARBY_STEP, goal, tol,
                            max_iter)
            ranked = [(_ranks(NullSpace(model, model.kinematics(s.q), RANK_RTOL),
                              RANK_RTOL), s) for s in found]
            all_ranks = [here] + [r for r, _ in ranked]
            best = (max(r[0] for r in all_ranks), max(r[1] for r in all_ranks))
            good = [s for r, s in ranked if r == best and r != here]
            if good:
                def distance(s):
                    d = pin.difference(model.tree, q, s.q) / model.velocity_units
                    return float(d @ d)
                sol = min(good, key=distance)
                final = solve_tree(model, sol.q, targets=targets, tol=tol, max_iter=max_iter)
                return (final, sum(s.iterations for s in found) + final.iterations) \
                    if final.converged else None
        return None

    def reached(self, error: LoopClosureError) -> Assembly:
        """The best configuration a failed assembly reached (``error.q``) as a
        :class:`Assembly` whose loops do not all close (its ``residual`` is the
        largest closure residual there): what ``pkm-pin view`` draws for a file that does
        not assemble.

        Raises:
            InputError: ``error`` carries no configuration.
        """
        if not isinstance(error, LoopClosureError) or error.q is None:
            raise InputError("reached() takes a LoopClosureError that carries the best "
                             "configuration reached (its q)")
        return self._at(self._model.check_q(error.q))

    def residuals_at(self, q) -> dict:
        """Norm of each closure's residual rows at the tree configuration ``q``, by
        closure name (dimensionless, as :attr:`Assembly.closure_residuals`)."""
        return self._at(self._model.check_q(q)).closure_residuals

    def _at(self, q: np.ndarray) -> Assembly:
        """The configuration ``q`` as a :class:`Assembly` (its ``residual``: the
        largest closure residual there; no solve)."""
        model = self._model
        kin = model.kinematics(q)
        norms = model.closure_norms(kin.residual)
        return Assembly.of_tree(self, q.copy(), float(norms.max(initial=0.0)), 0,
                                dict(zip(self._closure_names, norms.tolist())),
                                _actuated_or_nan(model, q), kin.output_placement)

    def _assembly(self, sol, iterations: int) -> Assembly:
        """The assembly at a converged :class:`~pkm_pin.solve.TreeSolution` (its last
        Pinocchio pass, when it was at ``sol.q``)."""
        model, q = self._model, sol.q
        norms, oMo = sol.closure_norms, sol.output_placement
        if norms is None or oMo is None:
            kin = model.kinematics(q)
            norms, oMo = model.closure_norms(kin.residual), kin.output_placement
        names = dict(zip(self._closure_names, norms.tolist()))
        return Assembly.of_tree(self, q.copy(), float(sol.residual), int(iterations), names,
                                _actuated_or_nan(model, q), oMo)

    def _failure(self, sol, n_starts: int, targets, what: str = "", tol: float = CLOSURE_TOL,
                 path: _Continuation | None = None) -> LoopClosureError:
        """The error for a best solution ``sol`` that did not converge, with its
        :func:`~pkm_pin.closure_gaps.diagnose` (limits lifted only for a plain
        assembly: no targets, no output pose) and what a forward kinematics' continuation
        from its guess found (``path``: :meth:`_fold_words`)."""
        model = self._model
        residual = model.closure_residual(sol.q)
        norms = [float(np.linalg.norm(residual[s])) for s in model.closure_slices()]
        detail = f"{n_starts} starts, {sol.iterations} iterations in the best one"
        found = diagnose(model, sol.q, tol=tol, lift_limits=targets is None and not what)
        cause = self._fold_words(path, targets)
        if path is not None and path.fold and found is not None:
            found = replace(found, hint="")  # not a wrong length: the values are beyond reach
        if found is not None and not found.gaps and (
                not norms or max(norms) <= sol.actuated or max(norms) < sol.pose):
            # every loop closes: the targets are out of reach, not the closures wrong
            found = replace(found, hint="")
        if norms and max(norms) > sol.actuated and max(norms) >= sol.pose:
            k = int(np.argmax(norms))
            error = LoopClosureError(model.closures[k].name or f"closure {k}", norms[k],
                                     detail, q=sol.q, diagnosis=found, cause=cause)
        elif targets is not None and sol.actuated >= sol.pose:
            error = LoopClosureError("actuated targets", sol.actuated,
                                     detail + f"; targets {np.round(targets, 6)}", q=sol.q,
                                     diagnosis=found, cause=cause)
        else:
            error = LoopClosureError(what or "output pose", sol.pose, detail, q=sol.q,
                                     diagnosis=found, cause=cause)
        error.continuation = path
        return error

    # ------------------------------------------------------------- mobility
    def mobility(self, q=None, rtol: float = RANK_RTOL, *, nearby: int = NEARBY_SAMPLES,
                 seed: int = 0) -> Mobility:
        """:class:`Mobility` at the configuration ``q`` (assembled, or a
        :class:`Assembly`; default :attr:`home_assembly`), its ranks compared with
        those at ``nearby`` configurations on the closure manifold (``0``: not compared;
        ``seed``: of their random steps)."""
        q = self.home_assembly.q if q is None else q
        q = q.q if isinstance(q, Assembly) else q
        kin = self._model.kinematics(q)
        return _mobility(self, kin, NullSpace(self._model, kin, rtol), rtol, nearby, seed)

    # ------------------------------------------------------------- analysis
    def analyze(self, q=None, *, about: str = "output", generic: LinkageAnalysis | None = None,
                rtol: float = RANK_RTOL, singular_tol: float = CLOSENESS_SINGULAR_TOL,
                nearby: int = NEARBY_SAMPLES) -> LinkageAnalysis:
        """:class:`LinkageAnalysis` of the output frame at the assembled ``q`` (or a
        :class:`Assembly`; default :attr:`home_assembly`; a pose or partial pose
        of the output: at :meth:`assembly_at` it).

        Args:
            about: ``"output"`` (homogenise about the output frame's origin: frame-
                invariant) or ``"world"`` (about the world origin, as seed 000's
                :class:`pkm_pin.Analysis`).
            generic: An analysis at a generic configuration: a constraint singularity is
                a change of ``dof`` or ``output_dof`` from it (``None``: not decided).
            nearby: How many nearby configurations on the closure manifold give the
                generic ranks of the :class:`Mobility` (``0``: not sampled, as in sweeps
                and workspaces).
        """
        if about not in ("output", "world"):
            raise InputError(f"about must be 'output' or 'world', got {about!r}")
        q = self.home_assembly.q if q is None else q
        if isinstance(q, (Mapping, pin.SE3)) or np.shape(q) in ((4, 4), (6,)) \
                and self._model.nq != 6:
            q = self.assembly_at(q)
        given = q if isinstance(q, Assembly) and q.leg_q is None else None
        q = self._model.check_q(q.q if isinstance(q, Assembly) else q)
        an = _analyse(self, q, about, generic, rtol, singular_tol, nearby)
        if given is not None:  # the assembly analysed is the one given
            an.__dict__["assembly"] = given
        return an

    # ---------------------------------------------------- position problems
    def forward_kinematics(self, q_actuated, guess=None, *, starts: int = 16, seed: int = 0,
                           tol: float = CLOSURE_TOL) -> Assembly:
        """Every joint and the output pose from the actuated values [rad or m]: the
        branch nearest ``guess`` (a configuration or :class:`Assembly`; default
        the reference configuration). Where the direct solve from ``guess`` fails, the
        guess's branch is continued along the straight path of actuated values before
        the other starts are tried (:meth:`assemble`); values beyond a fold of that
        branch (a type II singularity on the way) are refused with its place and the
        type II closeness index (:class:`LoopClosureError`)."""
        return self.assemble(guess, q_actuated=q_actuated, starts=starts, seed=seed, tol=tol,
                             continuation=True)

    def forward_kinematics_all(self, q_actuated, *, starts: int = 32, seed: int = 0,
                               patience: int = MODES_PATIENCE, tol: float = CLOSURE_TOL,
                               method: str = "auto"):
        """Every assembly mode found for the actuated values: a multistart of the tree
        solver from batches of ``starts`` configurations drawn within the joint limits
        (the reference first), stopped after ``patience`` batches in a row find no new
        mode. Two assemblies are the same mode when every joint origin and the output
        pose agree to :data:`~pkm_pin.tolerances.SAME_CONFIGURATION_TOL` (relative to
        the characteristic length): an idle motion (a rod spinning between its spherical
        joints) does not make a new mode.

        ``method``: ``"multistart"`` (above), ``"homotopy"`` (every mode, proven, by the
        Study homotopy of :mod:`pkm_pin.modes`: a machine whose legs are six distance
        constraints, read through :attr:`legs_mechanism`; refused with the reason
        otherwise) or ``"auto"`` (the homotopy where it applies, else the multistart).

        Returns:
            :class:`~pkm_pin.modes.AssemblyModes` of :class:`Assembly`, nearest
            the reference first; ``complete=False`` for a multistart (it proves nothing).

        Raises:
            ForwardKinematicsError: no start closes the loops at these values.
            InputError: ``method="homotopy"`` where it does not apply.
        """
        from time import perf_counter

        from .modes import AssemblyModes, distance_legs

        if method not in ("auto", "homotopy", "multistart"):
            raise InputError(f"method must be 'auto', 'homotopy' or 'multistart', got "
                             f"{method!r}")
        mech = self._homotopy_legs(method, distance_legs)
        if mech is not None:
            modes = mech.forward_kinematics_all(q_actuated, seed=seed, tol=tol,
                                                method="homotopy")
            found = [self.assemble(mech.source_configuration(a), starts=0) for a in modes]
            return AssemblyModes(found, modes.complete, modes.method, modes.counts,
                                 modes.seconds)
        t0 = perf_counter()
        target = self.check_actuated(q_actuated)
        model = self._model

        def too_many(n: int, tried: int, estimate: float) -> PkmError:
            return ForwardKinematicsError(
                f"the assemblies of {self.name!r} at the actuated values "
                f"{np.round(target, 6)} do not settle into modes: {n} distinct ones after "
                f"{tried} starts, {_estimate_words(n, estimate)} (a continuum: see mobility()'s "
                "idle motions; or more modes than a list can hold: each loop that closes "
                "two ways can double them); forward_kinematics gives the one nearest a "
                "guess")

        run = self._multistart(lambda q0: solve_tree(model, q0, targets=target, tol=tol),
                               model.reference, starts, seed, patience, too_many,
                               first=self._refuse_continuum)
        if not run.found:
            raise ForwardKinematicsError(
                f"no assembly of {self.name!r} at the actuated values {np.round(target, 6)}: "
                f"none of {run.tried} starts closed the loops (not proven: a multistart)")
        found = run.nearest(self._signature(model.reference))
        return AssemblyModes(found, False, "multistart",
                             {"starts": run.tried, "batches": run.batches, "modes": len(found)},
                             perf_counter() - t0)

    def _multistart(self, solve: Callable, warm, starts: int, seed: int, patience: int,
                    too_many: Callable, first: Callable | None = None) -> _Multistart:
        """The multistart of :meth:`forward_kinematics_all` and
        :meth:`inverse_kinematics_all`: ``solve(q0)`` (a :class:`TreeSolution`) from
        batches of :func:`~pkm_pin.solve.tree_starts` (``warm`` first, ``starts`` random
        configurations within the limits, seed ``seed + batch``) until ``patience``
        batches in a row find no new assembly; two assemblies are one when every joint
        origin and the output agree (:meth:`_signature`, to
        :data:`~pkm_pin.tolerances.SAME_CONFIGURATION_TOL`). ``first(q)`` checks the
        first assembly found (it may raise); ``too_many(n, tried)`` is the error raised
        after :data:`~pkm_pin.tolerances.MODES_MAX_BATCHES` batches or
        :data:`~pkm_pin.tolerances.MODES_MAX` assemblies (a continuum)."""
        run = _Multistart([], [], 0, 0, None)
        quiet = 0
        while quiet < patience:
            if run.batches >= MODES_MAX_BATCHES or len(run.found) > MODES_MAX:
                raise too_many(len(run.found), run.tried, run.estimate())
            new = False
            for q0 in tree_starts(self._model, None if run.batches else warm, count=starts,
                                  seed=seed + run.batches):
                run.tried += 1
                sol = solve(q0)
                if not sol.converged:
                    if run.best is None or sol.residual < run.best.residual:
                        run.best = sol
                    continue
                sig = self._signature(sol.q)
                seen = next((k for k, s in enumerate(run.signatures)
                             if np.abs(s - sig).max() <= SAME_CONFIGURATION_TOL), None)
                if seen is not None:
                    run.hits[seen] += 1
                    continue
                if not run.found and first is not None:
                    first(sol.q)
                run.signatures.append(sig)
                run.found.append(self._assembly(sol, sol.iterations))
                run.hits.append(1)
                new = True
            run.batches += 1
            if new and run.batches >= MODES_ESTIMATE_FROM and run.estimate() > MODES_MAX:
                raise too_many(len(run.found), run.tried, run.estimate())
            quiet = 0 if new else quiet + 1
        return run

    def _refuse_continuum(self, q) -> None:
        """A :class:`ForwardKinematicsError` where the assembled ``q`` moves with every
        actuated joint locked in a way that moves a joint origin or the output (an
        underactuated mechanism, a gripper's adaptive fingers): its assemblies at these
        actuated values form a continuum, which no list of modes enumerates. Idle
        motions that move nothing (a rod spinning between its spherical joints) pass.
        Decided on the closure Jacobian with the actuated rows added (rates in radians
        and lengths ``L``, rank by :data:`~pkm_pin.tolerances.RANK_RTOL`), each free
        direction's effect on :meth:`_signature` by a central difference."""
        model = self._model
        U = model.velocity_units
        H = model.closure_jacobian(q) * U
        H = np.vstack([H, np.eye(model.nv)[list(model.actuated_v)]])
        rank, _, _, Vt = svd_rank(H, RANK_RTOL)
        moving, h = 0, 1e-6
        for n in Vt[rank:]:
            up = self._signature(pin.integrate(model.tree, q, h * U * n))
            down = self._signature(pin.integrate(model.tree, q, -h * U * n))
            moving += float(np.abs(up - down).max()) / (2 * h) > 1e-3
        if moving:
            raise ForwardKinematicsError(
                f"{self.name!r} still moves with its actuated joints locked ({moving} "
                f"motion{'s' * (moving > 1)} that move its bodies: it is underactuated, "
                "see mobility()): its assemblies at given actuated values form a "
                "continuum, not a list of modes; forward_kinematics gives the one nearest "
                "a guess")

    def _homotopy_legs(self, method: str, distance_legs):
        """The legs the Study homotopy runs on for ``method`` (``None``: use the
        multistart); ``"homotopy"`` where it does not apply is an :class:`InputError`."""
        if method == "multistart" or (method == "auto"
                                      and self.platform_structure[0] is None):
            return None
        try:
            mech = self._legs("the Study homotopy")
        except (InputError, AssemblyError):
            if method == "homotopy":
                raise
            return None
        return mech if method == "homotopy" or distance_legs(mech) is not None else None

    def transmission(self, q=None, *, analysis: LinkageAnalysis | None = None):
        """Motion/force transmission indices of the linkage at ``q`` (a configuration or
        :class:`Assembly`; default :attr:`home_assembly`;
        :mod:`pkm_pin.transmission`, Wang, Wu & Liu 2010): each actuator's side of its
        loops is its "leg". ``analysis``: :meth:`analyze` of the same ``q`` about the
        output, when the caller has made it (not made again).

        The transmission wrench of an actuator is the one its loop passes on to the
        output: reciprocal to every passive freedom of the loop (its passive joints and
        the freedoms its closure leaves: three rotations at a point closure, one at a
        revolute closure) other than the output body's own support joints, and
        orthogonal to the loop's constraint wrenches (:func:`_transmission_wrench`) —
        a four-bar's coupler line, a five-bar's distal link through the pin. It acts on
        the actuated link at the point of its axis nearest to the first revolute child
        of the actuated joint it is not parallel to (ITI), and on the output at the
        output point (a point output) or at the output body's joint nearest to its axis
        (OTI).

        The constraint transmission index (our generalisation of Liu et al. 2014,
        docs/indices.md) is per actuator's side of its loops (the "leg" of
        :func:`_loop_freedoms`; two actuators of one leg share it): its constraint
        wrenches (reciprocal to all of the side's freedoms) against the output twists
        reciprocal to every transmission wrench and to every other side's constraints
        (and to those of the output body's own support joints): the twists the output
        gains when that side's constraints are removed
        (:func:`pkm_pin.transmission.constraint_transmission`, decided about the output
        point, compared with the constraint rank of the reference assembly). For a point
        output only forces through the point count (the point carries no couple). A side
        without constraints, or whose constraints the others impose as well, has CTI 1.

        Returns:
            :class:`~pkm_pin.transmission.Transmission` (``legs``: each actuator's side,
            ``leg_names``: the actuators of each side joined by ``+``).
        """
        from .transmission import Transmission, transmission_indices

        q = self.home_assembly.q if q is None else q
        q = q.q if isinstance(q, Assembly) else self._model.check_q(q)
        model, kin = self._model, self._model.kinematics(q)
        an = analysis
        if an is None:
            an = _analyse(self, q, "output", None, RANK_RTOL, CLOSENESS_SINGULAR_TOL, 0)
        elif not (np.array_equal(an.q, q) and np.allclose(  # compiled or Pinocchio pass
                an.reference_point, kin.output_placement.translation, rtol=0.0,
                atol=1e-12 * model.length)):
            raise InputError("analysis: not this linkage's analysis of q about its output "
                             "(Linkage.analyze(q))")
        tree, J = model.tree, kin.joint_twists
        cols = list(model.actuated_v)
        ids = [tree.getJointId(name) for name in model.actuated]
        out_joint = tree.frames[tree.getFrameId(model.output)].parentJoint
        W = np.array([_transmission_wrench(model, kin, j, self._loops[k], out_joint,
                                           an.reference_point) for k, j in enumerate(ids)]
                     ).reshape(-1, 6)
        W = _or_actuation_wrenches(W, an.A, model.length)
        p_in = np.array([_input_point(tree, J, W[k], j, an.reference_point)
                         for k, j in enumerate(ids)]).reshape(-1, 3)
        p_out = np.array([an.reference_point if model.output_point else
                          _output_point(model, kin, W[k], j, self._loops[k], out_joint)
                          for k, j in enumerate(ids)]).reshape(-1, 3)
        iti, oti = transmission_indices(W, J[cols], an.platform_twists, p_in, p_out,
                                        model.length)
        leg_cti, side_of = self._constraint_transmission(kin, W, an.reference_point)
        names = tuple("+".join(a for a, s in zip(model.actuated, side_of) if s == k)
                      for k in range(len(leg_cti)))
        return Transmission.of(iti, oti, leg_cti, side_of, names)

    def _constraint_transmission(self, kin: TreeKinematics, W: np.ndarray, p: np.ndarray
                                 ) -> tuple[np.ndarray, list]:
        """CTI of each actuator side (:meth:`transmission`) and the side of each actuator,
        from the transmission wrenches ``W`` (world origin), decided about ``p``."""
        from .transmission import constraint_transmission

        C, points, side_of = _side_constraints(self._model, kin, self._loops, p)
        generic = self._generic_constraint_rank()
        value = constraint_transmission(screws.about(W, p), [screws.about(c, p) for c in C],
                                        np.asarray(points) - p, self._model.length,
                                        RANK_RTOL, generic)
        return value[:-1], side_of

    def _generic_constraint_rank(self) -> int | None:
        """Rank of the union of the sides' constraints (and the fixed ones) at the
        reference assembly (:meth:`assemble` without a guess), once; ``None`` (each
        configuration's own) when it does not assemble."""
        if not hasattr(self, "_cti_rank"):
            from .transmission import constraint_rank

            try:
                q = self.assemble().q
            except AssemblyError:
                self._cti_rank = None
                return None
            kin = self._model.kinematics(q)
            p = kin.output_placement.translation
            C, _, _ = _side_constraints(self._model, kin, self._loops, p)
            self._cti_rank = constraint_rank([screws.about(c, p) for c in C],
                                             self._model.length)
        return self._cti_rank

    def _signature(self, q) -> np.ndarray:
        """Every joint origin and the output placement at ``q``, divided by the length:
        what tells two assembly modes apart (idle motions leave it unchanged)."""
        points, oMo = self._model.origins(np.asarray(q, dtype=float))
        return np.concatenate([points.ravel(), oMo.translation, oMo.rotation.ravel()
                               * self._model.length]) / self._model.length

    def inverse_kinematics(self, pose, guess=None, *, starts: int = 16, seed: int = 0,
                           tol: float = CLOSURE_TOL) -> Assembly:
        """The assembly whose output frame reaches ``pose`` (``pin.SE3``, world).

        When the output has 6 DOF the whole pose is targeted. Otherwise the whole pose is
        tried first (least squares on every component: a pose on the output's motion is
        met exactly); where that does not converge, only the components of the pose
        error ``log6(pose⁻¹ · oMo)`` (output axes, ``(θ; ρ / L)``) along the output's
        twist system at the guess (its assembly; homogenised, output axes) are targeted:
        the output reaches the pose as far as it can move towards it, the other
        components are what the mechanism imposes. A point output targets its
        position.

        A partial pose (a mapping of some of x, y, z, roll, pitch, yaw to values, the
        others solved for: :meth:`Mechanism.complete_pose`) is solved leg by leg through
        :attr:`legs_mechanism`; where the model has no legs, on the whole tree
        (:func:`pkm_pin.output_driver.partial_pose`: the loops closed and the given
        coordinates of the output frame met, the others free, nearest the guess).

        Raises:
            LoopClosureError: no start closes the loops and reaches the pose.
        """
        if isinstance(pose, Mapping):
            if self.platform_structure[0] is None:
                return self._partial_pose(pose, guess, starts=starts, seed=seed, tol=tol)
            mech = self._legs("a partial pose")
            return self.assemble(mech.source_configuration(mech.assemble(dict(pose))), starts=0)
        if not isinstance(pose, pin.SE3) or not np.isfinite(pose.homogeneous).all():
            raise InputError(f"pose must be a finite pinocchio.SE3, got {type(pose).__name__}")
        model = self._model
        home = self.assemble(guess, starts=starts, seed=seed, tol=tol)
        rows = pose_rows(model, model.kinematics(home.q))
        iterations = 0
        if len(rows) < 6 and not model.output_point:  # the whole pose first: one on the
            # output's motion is met exactly (the rows chosen at the guess may vanish
            # at another pose of that motion)
            sol, iterations = solve_tree_starts(
                model, iter_tree_starts(model, home.q, count=0), pose=pose, nearest=home.q,
                tol=tol)
            if sol.converged:
                return self._assembly(sol, iterations + home.iterations)
        sol, more = solve_tree_starts(
            model, iter_tree_starts(model, home.q, count=int(starts), seed=seed), pose=pose,
            pose_rows=rows, nearest=home.q, tol=tol)
        iterations += more
        if not sol.converged:
            raise self._failure(sol, starts + 4, None, "output pose")
        return self._assembly(sol, iterations + home.iterations)

    def complete_pose(self, guess=None, **coords) -> pin.SE3:
        """The output frame's full pose at a partial pose (``coords``: some of x, y, z
        [m], roll, pitch, yaw [rad]), the other coordinates solved for nearest ``guess``
        (default home): the output pose of :meth:`inverse_kinematics` of that mapping
        (:meth:`pkm_pin.Mechanism.complete_pose` of a machine read per leg).

        Raises:
            InputError: no coordinate given, or a name that is not one.
            LoopClosureError: the partial pose cannot be reached.
        """
        if not coords:
            raise InputError("complete_pose takes some of x, y, z, roll, pitch, yaw, e.g. "
                             "complete_pose(x=0.1)")
        return self.inverse_kinematics(dict(coords), guess).output_pose

    def _partial_pose(self, pose: Mapping, guess, *, starts: int, seed: int, tol: float
                      ) -> Assembly:
        """A partial output pose on the whole tree (:meth:`inverse_kinematics`)."""
        from .output_driver import partial_pose

        home = self.assemble(guess, starts=starts, seed=seed, tol=tol)
        q, r, steps = partial_pose(self._model, pose, home.q, tol)
        closure = float(np.abs(self._model.closure_residual(q)).max(initial=0.0))
        sol = TreeSolution(q, r, closure, 0.0, r, steps, r <= tol)
        if not sol.converged:
            raise self._failure(sol, 1, None, "partial output pose", tol)
        return self._assembly(sol, home.iterations + steps)

    def workspace(self, coords=None, **options):
        """Reachable, singularity-free and good-transmission (LTI of
        :meth:`transmission` ≥ 0.7) workspaces of the output point or over actuated
        coordinates, on the reference's working mode:
        :func:`pkm_pin.workspace.linkage_workspace`."""
        from .workspace import linkage_workspace

        return linkage_workspace(self, coords, **options)

    def inverse_dynamics(self, q, v, a, *, gravity=(0, 0, -9.81), wrench=None):
        """Actuated efforts and closure forces of the motion ``(q, v, a)`` of the
        model's tree (:func:`pkm_pin.dynamics.inverse_dynamics`)."""
        return _dynamics.inverse_dynamics(self._model, q, v, a, gravity=gravity, wrench=wrench)

    def simulate(self, q0=None, v0=None, duration: float = 1.0, dt: float = 1e-3,
                 **options):
        """Forward dynamics of the model's tree from ``(q0, v0)`` (default: the home
        assembly, at rest): :func:`pkm_pin.simulation.simulate` (``options``:
        ``efforts``, ``controller``, ``gravity``, ``baumgarte``, ``method``,
        ``integrator``)."""
        from . import simulation
        q0 = self.home_assembly.q if q0 is None else q0
        return simulation.simulate(self._model, q0, v0, duration, dt, **options)

    def dynamic_indices(self, q=None):
        """Actuator-space inertia, its eigenvalues and condition, the apparent inertia at
        the output, at ``q`` (default home): :func:`pkm_pin.dynamic_indices.dynamic_indices`."""
        from . import dynamic_indices as _indices
        q = self.home_assembly.q if q is None else q
        return _indices.dynamic_indices(self._model, q)

    def gravity_map(self, q_actuated, guess=None, *, gravity=(0, 0, -9.81), wrench=None,
                    condition: bool = False):
        """Gravity efforts over the rows of ``q_actuated`` (N × actuated), assembled by
        :meth:`sweep` (continuation from ``guess``):
        :func:`pkm_pin.dynamic_indices.gravity_efforts` (``condition``: the actuator
        inertia's condition per row too)."""
        from . import dynamic_indices as _indices
        Q = self.sweep(q_actuated, guess).q
        return _indices.gravity_efforts(self._model, Q, gravity=gravity, wrench=wrench,
                                        condition=condition)

    def sweep(self, q_actuated, guess=None, *, tol: float = CLOSURE_TOL,
              about: str = "output", transmission: bool = False, progress: bool = False,
              rtol: float | None = None, singular_tol: float = CLOSENESS_SINGULAR_TOL,
              chunk_size: int = 2000, checkpoint=None, executor=None) -> LinkageSweep:
        """Forward kinematics and analysis along the rows of ``q_actuated`` (N ×
        actuated), each warm-started from the previous assembly (continuation: the
        branch of ``guess``). A point that does not close from the last good one is solved
        again from ``guess`` (as a per-leg sweep solves a miss again from home: the last
        good point may lie across a fold); one that does not close either is recorded as
        not converged (NaN results) and the next starts again from the last good one. With
        ``transmission``, the ``lti`` and ``cti`` columns too (:meth:`transmission`:
        a few ms a point; nan otherwise).

        Poses instead of actuated values (a sequence of ``pin.SE3`` or of partial poses,
        mappings of some of x, y, z, roll, pitch, yaw, as :meth:`Mechanism.sweep` takes
        them): the output's inverse kinematics at each (:meth:`assembly_at`), warm-started
        from the previous assembly the same way; ``q_actuated`` of the result are then
        the values found.

        The keywords of :meth:`Mechanism.sweep`: ``progress`` (a bar), ``rtol`` and
        ``singular_tol`` (of each analysis), ``checkpoint`` (a
        :class:`~pkm_pin.checkpoint.Checkpoint` or one of its stages, stage ``sweep``:
        the rows are recorded in chunks of ``chunk_size`` in order, an interrupt writes
        them and raises :class:`~pkm_pin.checkpoint.Interrupted`, a resume continues from
        the last row recorded with its configuration: the same arrays, bit for bit).
        ``executor`` is refused: the rows follow one branch, each from the last, so they
        run one after the other in this process."""
        if executor is not None:
            raise InputError("executor: a general sweep follows one branch row after row "
                             "(each row warm-started from the last), so it runs in this "
                             "process; leave executor out")
        if int(chunk_size) < 1:
            raise InputError(f"chunk_size must be a positive integer, got {chunk_size}")
        rtol = RANK_RTOL if rtol is None else screws.as_fraction(rtol, "rtol")
        singular_tol = screws.as_fraction(singular_tol, "singular_tol")
        poses, Q = self._sweep_rows(q_actuated)
        out = _SweepRows(Q, self._model.nq)
        chunks = [np.arange(a, min(a + int(chunk_size), len(Q)))
                  for a in range(0, len(Q), int(chunk_size))]
        stage = _sweep_stage(checkpoint)
        done = [False] * len(chunks)
        if stage is not None:
            fingerprint = Q if poses is None else np.array([_pose_key(p) for p in poses])
            parts = stage.begin(fingerprint, chunks, {
                "tol": tol, "about": about, "transmission": bool(transmission),
                "rtol": rtol, "singular_tol": singular_tol, "guess": self._guess_q(guess)},
                out.fields())
            done = [p is not None for p in parts]
            out.restore(stage)
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=len(Q), unit="row", desc="sweep", leave=False)
            bar.update(sum(len(c) for c, d in zip(chunks, done) if d))
        track = _Track(self, poses, out, self._guess_q(guess), tol, about, transmission,
                       rtol, singular_tol)
        track.run(chunks, done, stage, bar)
        return out.result()

    def _sweep_rows(self, q_actuated) -> tuple:
        """``(poses, Q)`` of :meth:`sweep`'s rows: the poses (None for actuated values)
        and the (N × actuated) values (nan rows for poses, filled as they are solved)."""
        poses = _poses_of(q_actuated)
        if poses is not None:
            return poses, np.full((len(poses), len(self.actuated)), np.nan)
        Q = screws.as_float_array(q_actuated, "q_actuated")
        if Q.ndim != 2 or Q.shape[1] != len(self.actuated):
            raise InputError(f"q_actuated must have shape (N, {len(self.actuated)}) "
                             f"({', '.join(self.actuated)}), or give poses (pin.SE3 or "
                             f"mappings of pose coordinates), got {Q.shape}")
        return None, Q


class _Track:
    """The state of :meth:`Linkage.sweep` along its rows: the configuration the next row
    starts from and the analysis the constraint singularities are compared with (the
    first converged row's)."""

    def __init__(self, link: Linkage, poses, out: _SweepRows, warm, tol, about,
                 transmission, rtol, singular_tol):
        self.link, self.poses, self.out, self.warm = link, poses, out, warm
        self.tol, self.about, self.transmission = tol, about, transmission
        self.rtol, self.singular_tol = rtol, singular_tol
        self.generic = None
        self.start = warm

    def _solve(self, i: int, warm) -> Assembly:
        starts = 0 if warm is not None else 16
        if self.poses is None:
            return self.link.assemble(warm, q_actuated=self.out.qa[i], starts=starts,
                                      tol=self.tol)
        return self.link.inverse_kinematics(self.poses[i], warm, starts=starts, tol=self.tol)

    def row(self, i: int) -> None:
        link, out, warm = self.link, self.out, self.warm
        try:
            a = self._solve(i, warm)
        except AssemblyError as e:
            a = None
            if self.start is not None and warm is not self.start:
                # a miss is solved again from the guess (as a per-leg sweep solves it
                # again from home): the last good row may lie across a fold
                with contextlib.suppress(AssemblyError):
                    a = self._solve(i, self.start)
            if a is None:
                out.failures.append((i, str(e)))
                return
        self.warm = a.q
        an = link.analyze(a.q, about=self.about, generic=self.generic, nearby=0,
                          rtol=self.rtol, singular_tol=self.singular_tol)
        self.generic = self.generic or an
        out.record(i, a, an)
        if self.poses is not None:
            out.qa[i] = a.q_actuated
        if self.transmission:
            tr = link.transmission(a, analysis=an if self.about == "output" else None)
            out.lti[i], out.cti[i] = tr.lti, tr.cti

    def run(self, chunks: list, done: list, stage, bar) -> None:
        """Every row, chunk after chunk (those ``done`` in the checkpoint ``stage``
        skipped, the state carried over them), each chunk recorded in ``stage``; an
        interrupt keeps the chunks recorded (:meth:`Checkpoint.interrupted`)."""
        try:
            with recording(stage):
                for chunk, was_done in zip(chunks, done):
                    if was_done:
                        self.resume_after(chunk)
                        continue
                    for i in chunk:
                        self.row(int(i))
                        if bar is not None:
                            bar.update(1)
                    if stage is not None:
                        stage.record(chunk, self.out.part(chunk))
        finally:
            if bar is not None:
                bar.close()

    def resume_after(self, chunk: np.ndarray) -> None:
        """The state after the recorded rows ``chunk``: its last converged configuration
        (and the first converged row's analysis, analysed again: the same numbers)."""
        ok = chunk[self.out.ok[chunk]]
        if not len(ok):
            return
        if self.generic is None:
            self.generic = self.link.analyze(self.out.q[ok[0]], about=self.about,
                                             nearby=0, rtol=self.rtol,
                                             singular_tol=self.singular_tol)
        self.warm = self.out.q[ok[-1]].copy()


def _sweep_stage(checkpoint):
    """The checkpoint stage of a general sweep: a Checkpoint's ``"sweep"``, or the
    stage given."""
    if checkpoint is None:
        return None
    from .checkpoint import Checkpoint

    return checkpoint.stage("sweep") if isinstance(checkpoint, Checkpoint) else checkpoint


def _pose_key(pose) -> np.ndarray:
    """Numbers that identify a pose of a sweep (a checkpoint's fingerprint): the 4×4
    matrix of a ``pin.SE3``, or a partial pose's six coordinates, nan where not given."""
    if isinstance(pose, pin.SE3):
        return pose.homogeneous.reshape(-1)
    out = np.full(16, np.inf)
    for k, name in enumerate(POSE_COORDINATES):
        if name in pose:
            out[k] = float(pose[name])
    return out


@dataclass
class _Multistart:
    """What :meth:`Linkage._multistart` found: the distinct assemblies and their
    signatures, the starts tried, the batches run, the best solution that did not
    converge (``None`` when every one did)."""

    found: list
    signatures: list
    tried: int
    batches: int
    best: TreeSolution | None
    hits: list = field(default_factory=list)  # per assembly: the starts that found it

    def estimate(self) -> float:
        """How many distinct assemblies the starts would find in all, from how often
        each was found: the bias-corrected Chao1 estimate ``S + f₁(f₁ − 1) / (2 (f₂ +
        1))`` (``S`` found, ``f₁`` of them once, ``f₂`` twice; the bias-corrected form
        of Chao's species-richness estimator): many found only once mean many not found
        yet. A lower bound in expectation."""
        h = np.asarray(self.hits)
        f1, f2 = int((h == 1).sum()), int((h == 2).sum())
        return len(h) + f1 * (f1 - 1) / (2 * (f2 + 1))

    def nearest(self, reference: np.ndarray) -> list:
        """The assemblies found, the one whose signature is nearest ``reference``
        first."""
        order = np.argsort([np.linalg.norm(s - reference) for s in self.signatures],
                           kind="stable")
        return [self.found[k] for k in order]


def _estimate_words(n: int, estimate: float) -> str:
    """The multistart's estimate of the assemblies it would find in all
    (:meth:`_Multistart.estimate`), in words."""
    if estimate > 10 * max(n, 1):
        return "new ones still appearing (most found once: far more remain unseen)"
    return f"new ones still appearing (about {estimate:.0f} in all, from how often each " \
           "was found again)"


def _poses_of(points) -> list | None:
    """``points`` as a list of poses when it is a non-empty sequence of ``pin.SE3`` or
    of mappings (partial poses), else ``None`` (actuated values)."""
    if isinstance(points, (np.ndarray, pin.SE3, Mapping)) or not isinstance(
            points, (list, tuple)) or not points:
        return None
    if all(isinstance(p, (pin.SE3, Mapping)) for p in points):
        return list(points)
    return None


# ====================================================================== structure
def _loops_of_actuators(model: ClosureModel) -> tuple:
    """For each actuated joint, the indices of the closures whose tree path (the joints
    between their two frames) contains it."""
    tree = model.tree
    out = []
    for name in model.actuated:
        j = tree.getJointId(name)
        loops = []
        for k, c in enumerate(model.closures):
            sa = set(tree.supports[tree.frames[tree.getFrameId(c.frame_a)].parentJoint])
            sb = set(tree.supports[tree.frames[tree.getFrameId(c.frame_b)].parentJoint])
            if j in sa ^ sb:
                loops.append(k)
        out.append(tuple(loops))
    return tuple(out)


def _actuated_or_nan(model: ClosureModel, q: np.ndarray) -> np.ndarray:
    """The actuated values at the solver's ``q`` (a checked configuration), NaN where an
    actuated joint has no single value."""
    try:
        return model._plan.actuated_values(q, model)
    except InputError:
        return np.full(len(model.actuated), np.nan)


# ====================================================================== mobility
def _ranks(ns: NullSpace, rtol: float) -> tuple[int, int]:
    """``(rank J_c, rank of J_c with the actuated rows)`` of a :class:`NullSpace`."""
    return ns.rank, ns.rank + ns.rank_x(rtol)


def _mobility(link: Linkage, kin: TreeKinematics, ns: NullSpace, rtol: float,
              nearby: int = NEARBY_SAMPLES, seed: int = 0, locked=None,
              near_limit: bool | None = None) -> Mobility:
    model = link.model
    dof = model.nv - ns.rank
    idle = ns.idle(rtol)
    words: list[str] = []
    for k in range(idle.shape[1]):
        text = describe_motion(model, kin, ns.units * idle[:, k])
        if text in words:  # two motions of the same joints: tell them apart by their rates
            text = describe_motion(model, kin, ns.units * idle[:, k], rates=True)
        words.append(text)
    hold, representation = _representation(model, kin, locked=locked, near_limit=near_limit)
    here = _ranks(ns, rtol)
    generic = singular = None
    known = link._generic_ranks if rtol == RANK_RTOL else None
    if nearby > 0 and known is not None and here == known:
        generic, singular = known, False  # the ranks sampled before: generic
    elif nearby > 0:
        rng = np.random.default_rng(seed)
        found = _nearby(model, kin.q, ns, hold, rng, int(nearby), NEARBY_STEP)
        ranks = [here] + [_ranks(NullSpace(model, model.kinematics(s.q), rtol), rtol)
                          for s in found]
        generic = (max(r[0] for r in ranks), max(r[1] for r in ranks))
        singular = generic != here
        if known is None and rtol == RANK_RTOL:
            link._generic_ranks = generic
    return Mobility(dof, model.n_rows - ns.rank, idle.shape[1], tuple(words),
                    _independent(model, ns.X, rtol, here[1] - here[0]), link.grubler, ns.rank,
                    None if generic is None else model.nv - generic[0],
                    None if generic is None else model.nv - generic[1], singular,
                    tuple(representation))


def _nearby(model: ClosureModel, q: np.ndarray, ns: NullSpace, hold, rng, count: int,
            step: float, targets=None, tol: float = CLOSURE_TOL, max_iter: int = 100
            ) -> list:
    """Converged :class:`~pkm_pin.solve.TreeSolution` s at up to ``count``
    configurations near ``q`` on the closure manifold: a random allowed motion of
    dimensionless size ``step`` (the columns of ``ns.N``), the velocity coordinates
    ``hold`` stepped ``step`` off (into the range of a joint at a limit) and held
    there, projected back onto the closures (and ``targets``) by
    :func:`~pkm_pin.solve.solve_tree`."""
    U, hold = model.velocity_units, list(hold)
    dof = ns.N.shape[1]
    if not dof and not hold:
        return []
    free = None
    if hold:
        free = np.ones(model.nv, bool)
        free[hold] = False
    signs = _inward(model, q, hold)
    out = []
    for _ in range(count):
        dv = np.zeros(model.nv)
        if dof:
            z = rng.normal(size=dof)
            dv = ns.N @ z * (step / np.linalg.norm(z))
        if hold:
            dv[hold] = step * np.where(signs == 0, rng.choice([-1.0, 1.0], len(hold)), signs)
        sol = solve_tree(model, pin.integrate(model.tree, q, U * dv), free, targets, tol=tol,
                         max_iter=max_iter)
        if sol.converged:
            out.append(sol)
    return out


def _inward(model: ClosureModel, q: np.ndarray, coords) -> np.ndarray:
    """For each velocity coordinate of a 1-DOF joint: +1 at its lower limit, −1 at its
    upper limit, 0 elsewhere."""
    from .solve import tree_limits

    lo, up = tree_limits(model)
    tree = model.tree
    out = np.zeros(len(coords))
    idx_q = {tree.joints[j].idx_v: tree.joints[j].idx_q for j in range(1, tree.njoints)
             if tree.joints[j].nq == tree.joints[j].nv == 1}
    for k, i in enumerate(coords):
        if i in idx_q:
            iq = idx_q[i]
            out[k] = 1.0 if q[iq] <= lo[iq] + JOINT_LIMIT_SLACK else (
                -1.0 if q[iq] >= up[iq] - JOINT_LIMIT_SLACK else 0.0)
    return out


def _at_limits(model: ClosureModel, q: np.ndarray) -> list:
    """``(joint, "lower" or "upper", limit)`` of the 1-DOF joints exactly at a finite
    limit of :func:`~pkm_pin.solve.tree_limits` (within
    :data:`~pkm_pin.tolerances.JOINT_LIMIT_SLACK`)."""
    from .solve import tree_limits

    lo, up = tree_limits(model)
    near_lo = np.abs(q - lo) <= JOINT_LIMIT_SLACK
    near_up = np.abs(q - up) <= JOINT_LIMIT_SLACK
    if not (near_lo.any() or near_up.any()):
        return []
    tree, out = model.tree, []
    for j in range(1, tree.njoints):
        joint = tree.joints[j]
        if joint.nq == joint.nv == 1:
            i = joint.idx_q
            if near_lo[i] or near_up[i]:
                out.append((j, "lower" if near_lo[i] else "upper", lo[i] if near_lo[i]
                            else up[i]))
    return out


def _representation(model: ClosureModel, kin: TreeKinematics | None, q=None,
                    locked: np.ndarray | None = None, near_limit: bool | None = None
                    ) -> tuple[list, list]:
    """Representation singularities at ``kin.q`` (or ``q``; ``kin`` made only when
    needed): ``(velocity coordinates, sentences)``.

    * Three consecutive revolute joints
      (:func:`pkm_pin.general_kernel.revolute_triples`) at a gimbal lock: the first and
      third axes lie on one line (their unit homogenised twists about the middle joint
      agree up to sign, :data:`~pkm_pin.tolerances.GIMBAL_LOCK_RTOL`) while the middle
      one is not on it; the middle joint's coordinate.
    * A 1-DOF joint exactly at a finite limit (:func:`_at_limits`; the tree solver clips
      there)."""
    tree = model.tree
    q = kin.q if kin is not None else model.check_q(q)
    coords, words = [], []
    triples = general_kernel.revolute_triples(model)
    if kin is None and locked is None:  # from the compiled tree, if it is
        flags = general_kernel.representation_flags(model, q)
        locked, near_limit = flags if flags is not None else (None, near_limit)
    if len(triples) and locked is None:
        locked = _gimbal_locks(model, kin if kin is not None else model.kinematics(q), triples)
    if len(triples):
        for p, j, c in triples[locked].tolist():
            coords.append(tree.joints[j].idx_v)
            words.append(f"{tree.names[j]} at a gimbal lock (the axes of {tree.names[p]} "
                         f"and {tree.names[c]} coincide)")
    for j, side, limit in _at_limits(model, q) if near_limit is not False else ():
        if tree.joints[j].idx_v not in coords:
            coords.append(tree.joints[j].idx_v)
            words.append(f"{tree.names[j]} at its {side} limit {limit:.6g}")
    return coords, words


def _gimbal_locks(model: ClosureModel, kin: TreeKinematics, triples: np.ndarray
                  ) -> np.ndarray:
    """Whether each revolute triple ``(p, j, c)`` is at a gimbal lock (the test of
    :func:`_representation`)."""
    tree, L = model.tree, model.length
    J = kin.joint_twists
    iv = np.array([tree.joints[k].idx_v for k in range(tree.njoints)])
    centres = np.array([kin.joint_placements[j].translation for j in triples[:, 1]])
    T = screws.homogenise(screws.about(J[iv[triples]], centres), L)  # m × 3 × 6
    T /= np.linalg.norm(T, axis=2)[..., None]

    def apart(a, b):
        return np.minimum(np.linalg.norm(a - b, axis=1), np.linalg.norm(a + b, axis=1))

    return (apart(T[:, 0], T[:, 2]) <= GIMBAL_LOCK_RTOL) \
        & (apart(T[:, 1], T[:, 0]) > GIMBAL_LOCK_RTOL)


def _independent(model: ClosureModel, X: np.ndarray, rtol: float,
                 rank_x: int | None = None) -> tuple:
    """Greedy maximal set of actuated joints whose rates (rows of ``X``) are
    independent over the allowed motions (``rank_x``: the rank of ``X``, if known)."""
    if X.shape[0] and X.shape[0] <= X.shape[1]:
        if rank_x is None:
            rank_x = svd_rank(X, rtol)[0]
        if rank_x == X.shape[0]:  # full row rank: every subset is independent
            return tuple(model.actuated)
    chosen: list[int] = []
    scale = np.linalg.norm(X) if X.size else 0.0
    for k in range(X.shape[0]):
        trial = X[chosen + [k]]
        sv = np.linalg.svd(trial, compute_uv=False)
        if scale > 0 and sv.size and sv[-1] > rtol * max(sv[0], rtol * scale) \
                and np.sum(sv > rtol * sv[0]) == len(chosen) + 1:
            chosen.append(k)
    return tuple(model.actuated[k] for k in chosen)


def _body_twists(model: ClosureModel, kin: TreeKinematics, v: np.ndarray) -> np.ndarray:
    """(njoints × 6) world twist of every joint's child body for the tree velocity v."""
    return np.array([J @ v for J in kin.body_jacobians])


def _body_name(tree: pin.Model, j: int) -> str:
    for f in tree.frames:
        if f.parentJoint == j and f.type == pin.FrameType.BODY:
            return f.name
    return tree.names[j]


def _fmt(p: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in np.where(np.abs(p) < 1e-12, 0.0, p)) + ")"


def describe_motion(model: ClosureModel, kin: TreeKinematics, v: np.ndarray,
                    rates: bool = False) -> str:
    """One sentence describing the tree motion ``v`` (nv,), naming only the joints and
    bodies it moves: the bodies that turn together about one line (through their
    joints' centres when they lie on it) — "rod spins about the line through its joints
    at …" for one body alone — and the joints that move, with the other moving bodies,
    when there are more; else the joints that move and the bodies they move. ``rates``:
    each joint's rate relative to the largest (to tell apart two motions of the same
    joints)."""
    tree, L = model.tree, model.length
    x = v / model.velocity_units
    top = np.abs(x).max(initial=0.0)
    moving, amount = [], []
    for j in range(1, tree.njoints):
        part = x[tree.joints[j].idx_v:tree.joints[j].idx_v + tree.joints[j].nv]
        big = part[np.argmax(np.abs(part))] if part.size else 0.0
        if abs(big) > 1e-9 * top:
            moving.append(tree.names[j])
            amount.append(big / top)
    joints = ", ".join(f"{n} ({a:+.3g})" if rates else n for n, a in zip(moving, amount))
    T = _body_twists(model, kin, v)
    H = screws.homogenise(T, L)
    size = np.linalg.norm(H, axis=1)
    bodies = [j for j in range(1, tree.njoints) if size[j] > 1e-9 * size.max()]
    groups: list[list[int]] = []
    for j in bodies:
        for g in groups:
            if np.linalg.norm(H[j] - H[g[0]]) <= 1e-9 * size.max():
                g.append(j)
                break
        else:
            groups.append([j])
    spin = [g for g in groups if _pure_rotation(T[g[0]], L)]
    if spin:
        g = max(spin, key=lambda g: (len(g), size[g[0]]))
        point, direction = screws.axis(T[g[0]], L)
        on: list = []
        for j in g:
            on += [p for p in _body_points(model, kin, j)
                   if np.linalg.norm(np.cross(p - point, direction)) <= 1e-7 * L
                   and all(np.linalg.norm(p - u) > 1e-9 * L for u in on)]
        where = (" and ".join(_fmt(p) for p in on[:2]) if len(on) >= 2 else
                 f"{_fmt(point)} along {_fmt(direction)}")
        names = [_body_name(tree, j) for j in g]
        who = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]
        verb, own = ("spins", "its") if len(names) == 1 else ("spin", "their")
        through = f"{own} joints at " if len(on) >= 2 else ""
        text = f"{who} {verb} about the line through {through}{where}"
        others = [_body_name(tree, j) for j in bodies if j not in g]
        if len(groups) == 1 and not rates:
            return text
        return (text + f" (joints {joints} move"
                + (f"; bodies {', '.join(others)} move too)" if others else ")"))
    return (f"joints {joints} move (bodies "
            f"{', '.join(_body_name(tree, j) for j in bodies)})")


def _pure_rotation(t: np.ndarray, L: float) -> bool:
    """Whether the twist ``t`` (axis-first) is a rotation of pitch zero."""
    w, vel = t[:3], t[3:]
    return bool(np.linalg.norm(w) > 0 and abs(w @ vel) <= 1e-9 * np.linalg.norm(w) ** 2 * L)


def _loop_freedoms(model: ClosureModel, kin: TreeKinematics, loops, j: int, support: set
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The twists (rows, world origin) of the freedoms of actuator ``j``'s side of the
    loops ``loops`` (its "leg"): the joints on the tree path from the loop's branching
    point to the closure frame on ``j``'s side (those of ``support`` left out) and what
    the closure leaves free (rotations about the point of a point closure, about the
    axis of a revolute one). Returns ``(passive, actuated)``: ``actuated`` is joint
    ``j``'s."""
    rows, is_act, _ = _side_freedoms(model, kin, loops, j, support)
    return rows[~is_act], rows[is_act]


def _side_freedoms(model: ClosureModel, kin: TreeKinematics, loops, j: int, support: set
                   ) -> tuple[np.ndarray, np.ndarray, tuple]:
    """:func:`_loop_freedoms` in chain order: ``(rows, actuated, key)`` with ``rows``
    (m × 6, world origin) loop after loop, each from the branching point to the closure
    (each coordinate's twist of the side's end body) and the closure's freedoms last,
    ``actuated`` (m,) marking joint ``j``'s rows, and ``key`` what identifies the side
    (its loops and joints: two actuators of one leg share it)."""
    tree = model.tree
    if j in support:  # the actuator is on the output body's own chain: that chain is its leg
        return _support_side(model, kin, j, support)
    rows, is_act, joints = [], [], set()
    for c in loops:
        cl = model.closures[c]
        fa, fb = (tree.getFrameId(f) for f in (cl.frame_a, cl.frame_b))
        sa, sb = (set(tree.supports[tree.frames[f].parentJoint]) for f in (fa, fb))
        path = ((sa - sb) if j in sa else (sb - sa)) - support - {0}
        joints |= path
        # each coordinate's motion of the side's end body (the leg's Jacobian columns:
        # a parallelogram's mimicking joints included, as the platform reading has them)
        end = tree.frames[fa if j in sa else fb].parentJoint
        E = kin.body_jacobians[end].T
        for k in sorted(path):
            r = E[tree.joints[k].idx_v:tree.joints[k].idx_v + tree.joints[k].nv]
            rows.extend(r)
            is_act.extend([k == j] * len(r))
        C = kin.frame_placements[fa] * cl.placement_a
        axes = np.eye(3) if cl.kind == "point" else (
            C.rotation[:, 2:] .T if cl.kind == "revolute" else np.zeros((0, 3)))
        rows.extend(screws.line(C.translation, w) for w in axes)  # unit axes
        is_act.extend([False] * len(axes))
    key = (tuple(sorted(loops)), tuple(sorted(joints)))
    return np.array(rows).reshape(-1, 6), np.array(is_act, bool), key


def _support_side(model: ClosureModel, kin: TreeKinematics, j: int, support: set
                  ) -> tuple[np.ndarray, np.ndarray, tuple]:
    """:func:`_side_freedoms` of an actuator ``j`` on the output body's own chain (the
    tree runs through its leg to the output, as an Extended URDF cut open there: the
    platform reading's tree leg): the chain's joints from the base to the output body,
    their twists as the output body sees them."""
    tree = model.tree
    out_joint = tree.frames[tree.getFrameId(model.output)].parentJoint
    E = kin.body_jacobians[out_joint].T
    rows, is_act = [], []
    for k in sorted(support - {0}):
        r = E[tree.joints[k].idx_v:tree.joints[k].idx_v + tree.joints[k].nv]
        rows.extend(r)
        is_act.extend([k == j] * len(r))
    key = ((), tuple(sorted(support - {0})))
    return np.array(rows).reshape(-1, 6), np.array(is_act, bool), key


def _transmission_wrench(model: ClosureModel, kin: TreeKinematics, j: int, loops,
                         out_joint: int, p: np.ndarray, rtol: float = RANK_RTOL
                         ) -> np.ndarray:
    """The wrench actuator ``j``'s loops pass on to the output (:meth:`Linkage.
    transmission`), a unit force or unit couple about the world origin: reciprocal to
    the loops' passive freedoms, orthogonal (homogenised about ``p``) to the wrenches
    reciprocal to all their freedoms; zeros when the actuator's twist depends on them."""
    L = model.length
    # the output body's own support joints carry the output's motion, not the leg's
    support = set() if model.output_point else set(model.tree.supports[out_joint])
    passive, act = _loop_freedoms(model, kin, loops, j, support)

    free = _reciprocal_homogenised(passive, p, L, rtol)
    cons = _reciprocal_homogenised(np.vstack([passive, act]), p, L, rtol)
    W = free - (free @ cons.T) @ cons if len(cons) else free
    _, sv, Vt = np.linalg.svd(W)
    if not len(sv) or sv[0] <= rtol:
        return np.zeros(6)
    zeta = from_homogenised(Vt[0][None], p, L)[0]
    f, m = zeta[:3], zeta[3:]
    s = np.linalg.norm(f) if np.linalg.norm(f) * L > rtol * np.linalg.norm(m) else np.linalg.norm(m)
    return zeta / s


def _or_actuation_wrenches(W: np.ndarray, A: np.ndarray, L: float,
                           rtol: float = RANK_RTOL) -> np.ndarray:
    """The transmission wrenches ``W`` (rows, world origin), each zero row (its side's
    reading attributes no wrench to the actuator: its twist depends on the side's
    passive freedoms, which other loops hold, e.g. a leg's knee and ankle pitch joints
    driven through rods) replaced by the actuator's row of the analysis' ``A`` (the
    wrench it transmits to the output with every other actuator locked), scaled as
    :func:`_transmission_wrench` scales (a unit force, or a unit couple); a zero row of
    ``A`` stays zero. So ITI is 0 only where ``B_ii = A_i ∘ $_i`` is: at a type I
    singularity."""
    W = np.array(W, dtype=float)
    for k, (w, a) in enumerate(zip(W, np.asarray(A, dtype=float).reshape(-1, 6))):
        if np.any(w) or not np.any(a):
            continue
        f, m = np.linalg.norm(a[:3]), np.linalg.norm(a[3:])
        W[k] = a / (f if f * L > rtol * m else m)
    return W


def _reciprocal_homogenised(T: np.ndarray, p: np.ndarray, L: float, rtol: float
                            ) -> np.ndarray:
    """An orthonormal basis (rows, homogenised about ``p``) of the wrenches reciprocal
    to the twists ``T`` (rows, world origin); all six without twists."""
    X = homogenised_about(T, p, L).reshape(-1, 6) @ screws.DELTA
    r, _, _, Vt = svd_rank(X, rtol)
    return Vt[r:]


def _reciprocal_wrenches(T: np.ndarray, p: np.ndarray, L: float, rtol: float = RANK_RTOL
                         ) -> np.ndarray:
    """:func:`_reciprocal_homogenised` in world units about the world origin."""
    return from_homogenised(_reciprocal_homogenised(T, p, L, rtol), p, L).reshape(-1, 6)


def _forces_through(C: np.ndarray, p: np.ndarray, L: float, rtol: float = RANK_RTOL
                    ) -> np.ndarray:
    """The wrenches of the span of ``C`` (rows, world origin) that are forces through
    ``p`` (no moment about it), as rows (world origin)."""
    if not len(C):
        return C
    r, _, _, Vt = svd_rank(homogenised_about(C, p, L), rtol)
    if not r:
        return np.zeros((0, 6))
    B = Vt[:r]  # orthonormal rows spanning C, homogenised about p
    m, _, _, X = svd_rank(B[:, 3:].T, rtol)  # combinations without a moment about p
    F = X[m:] @ B
    F[:, 3:] = 0.0  # zero up to rounding
    return from_homogenised(F, p, L).reshape(-1, 6)


def _constraint_point(c: np.ndarray, rows: np.ndarray, L: float, p: np.ndarray
                      ) -> np.ndarray:
    """Where a side's (single) constraint wrench ``c`` reaches the output: the point of
    its axis nearest to the axis of the side's last rotation freedom that it is not
    parallel to (chain order ``rows``: the rule of
    :func:`pkm_pin.transmission.leg_points`), else its axis point nearest to ``p``."""
    from .transmission import PARALLEL_SIN, ZERO_RTOL, nearest_point

    for T in rows[::-1]:
        if np.linalg.norm(T[:3]) * L <= ZERO_RTOL * np.linalg.norm(T[3:]):
            continue
        point, sin = nearest_point(c, T)
        if sin > PARALLEL_SIN:
            return point
    return screws.axis_point_nearest(c, p)


def _side_constraints(model: ClosureModel, kin: TreeKinematics, loops_of: tuple,
                      p: np.ndarray) -> tuple[list, list, list]:
    """The constraint wrenches of each actuator side (rows, world origin; :meth:`Linkage.
    transmission`), then those never removed as a last entry (the output body's support
    joints' constraints; for a point output the three couples: it carries none), the
    point where each side's constraint reaches the output (the last entry's: ``p``),
    and each actuator's side."""
    tree, L = model.tree, model.length
    out_joint = tree.frames[tree.getFrameId(model.output)].parentJoint
    support = set() if model.output_point else set(tree.supports[out_joint])
    keys, sides, side_of = [], [], []
    for k, name in enumerate(model.actuated):
        rows, _, key = _side_freedoms(model, kin, loops_of[k], tree.getJointId(name),
                                      support)
        if key not in keys:
            keys.append(key)
            sides.append(rows)
        side_of.append(keys.index(key))
    C = [_reciprocal_wrenches(rows, p, L) for rows in sides]
    if model.output_point:
        C = [_forces_through(c, p, L) for c in C] + [np.hstack([np.zeros((3, 3)),
                                                                  np.eye(3)])]
        points = [np.array(p, dtype=float)] * len(C)
    else:
        J = kin.joint_twists
        held = [J[tree.joints[k].idx_v:tree.joints[k].idx_v + tree.joints[k].nv]
                for k in sorted(support - {0})]
        points = [_constraint_point(c[0], rows, L, p) if len(c) else np.array(p, float)
                  for c, rows in zip(C, sides)] + [np.array(p, dtype=float)]
        C = C + [_reciprocal_wrenches(np.vstack(held + [np.zeros((0, 6))]), p, L)]
    return C, points, side_of


def _output_point(model: ClosureModel, kin: TreeKinematics, wrench: np.ndarray, j: int,
                  loops, out_joint: int) -> np.ndarray:
    """Where actuator ``j``'s transmission wrench acts on the output body: the point of
    its axis nearest to the last rotation of its side of the loop (the closure's own
    rotations first: a point closure's point; then the side's joints from the closure
    back) that the wrench axis is not parallel to — the rule of
    :func:`pkm_pin.transmission.leg_points` for a platform's leg; else the output body's
    joint nearest to the wrench axis."""
    from .transmission import PARALLEL_SIN, nearest_point

    support = set(model.tree.supports[out_joint])
    rows, _, _ = _side_freedoms(model, kin, loops, j, support)
    for row in rows[::-1]:
        if np.any(row[:3]):
            p, sin = nearest_point(wrench, row)
            if sin > PARALLEL_SIN:
                return p
    points = _body_points(model, kin, out_joint) or [kin.output_placement.translation]
    return min(points, key=lambda p: _distance_to_axis(wrench, p))


def _distance_to_axis(wrench: np.ndarray, p: np.ndarray) -> float:
    """Distance from the point ``p`` to the axis of ``wrench`` (axis-first, world
    origin); for a couple, 0."""
    return float(np.linalg.norm(p - screws.axis_point_nearest(wrench, p)))


def _input_point(tree: pin.Model, J: np.ndarray, wrench: np.ndarray, j: int,
                 fallback: np.ndarray) -> np.ndarray:
    """Where an actuation wrench acts on the actuated link (joint ``j``'s child body):
    the point of its axis nearest to the axis of the first revolute joint after ``j``
    down the tree (passing prismatic joints, as a 3-RPR leg's slider) that the wrench
    axis is not parallel to — the rule of :func:`pkm_pin.transmission.leg_points` (a
    five-bar's or a Delta's elbow); else the axis point nearest to ``fallback``."""
    from .transmission import PARALLEL_SIN, nearest_point

    for k in range(j + 1, tree.njoints):
        jk = tree.joints[k]
        if j not in tree.supports[k] or jk.nv != 1 or not np.any(J[jk.idx_v, :3]):
            continue
        p, sin = nearest_point(wrench, J[jk.idx_v])
        if sin > PARALLEL_SIN:
            return p
    return screws.axis_point_nearest(wrench, fallback)


def _body_points(model: ClosureModel, kin: TreeKinematics, j: int) -> list:
    """Joint centres on body j: its own joint, its child joints, its closure points."""
    tree = model.tree
    pts = [kin.joint_placements[j].translation]
    pts += [kin.joint_placements[k].translation for k in range(1, tree.njoints)
            if tree.parents[k] == j]
    for c in model.closures:
        for frame, P in ((c.frame_a, c.placement_a), (c.frame_b, c.placement_b)):
            fid = tree.getFrameId(frame)
            if tree.frames[fid].parentJoint == j:
                pts.append((kin.frame_placements[fid] * P).translation)
    unique: list = []
    for p in pts:
        if all(np.linalg.norm(p - u) > 1e-9 * model.length for u in unique):
            unique.append(np.array(p))
    return unique


def _machine_length(model: ClosureModel) -> ClosureModel:
    """``model`` with the characteristic length of the machine it describes: where a
    base–legs–platform structure is detected and the model's length is the tree's
    default, the legs' (:func:`pkm_pin.model.structure.legs_length`, that of the same
    machine written as TOML legs), so that every homogenised index and rank decision is
    the machine's, whatever tree the file wrote. A length given explicitly is kept."""
    structure, _ = detect_platform(model)
    if structure is None or model.length != default_length(model.tree, model.closures):
        return model
    L = legs_length(model, structure)
    return model if L == model.length else replace(model, length=L)


# ====================================================================== analysis
def _analyse(link: Linkage, q: np.ndarray, about: str, generic, rtol: float,
             singular_tol: float, nearby: int = NEARBY_SAMPLES) -> LinkageAnalysis:
    """The analysis at the checked ``q``: its numbers from the compiled path
    (:func:`pkm_pin.general_kernel.analysis_core`) where the tree is compiled, else from
    :func:`_numpy_core`; then the result objects."""
    model = link.model
    core = general_kernel.analysis_core(model, link._loops, q, about == "output", rtol)
    if core is None:
        core = _numpy_core(link, model.kinematics(q), about, rtol)
    mob = _mobility(link, core.kin, core.ns, rtol, nearby, locked=core.locked,
                    near_limit=core.near_limit)
    idx = {"type_I": core.type_I, "type_II": core.type_II, "condition_A": core.condition,
           "forward": core.forward, "inverse": core.inverse}
    singularity = classify(_smaller(core.type_I, core.inverse),
                           _smaller(core.type_II, core.forward), singular_tol)
    redundancy = kinematic_redundancy(len(mob.independent_actuators), model.output_point)
    underactuation = 0  # decided where class II holds at ranks that are the generic ones
    if mob.singular is False and not _smaller(core.type_II, core.forward) >= singular_tol:
        underactuation = uncontrolled_output(core.ns, core.p, model.length, rtol)
    d = core.d
    csing = None if generic is None else bool(mob.dof != generic.dof
                                              or d != generic.output_dof)
    return TreeAnalysis.of_values(
        q=core.kin.q, mobility=mob, output_dof=d, translations=d - core.rotations,
        platform_twists=core.twists, constraint_wrenches=core.wrenches, A=core.A, B=core.B,
        indices=idx, singularity=singularity, constraint_singular=csing,
        reference_point=core.p, length=model.length, singular_tol=singular_tol,
        _maps=(core.Xr, core.Yr, core.M, core.ns.units, list(model.actuated_v)),
        actuated_prismatic=core.translating, mechanism=link, rtol=rtol, about=about,
        redundancy=redundancy, underactuation=underactuation)


def uncontrolled_output(ns: NullSpace, p: np.ndarray, L: float, rtol: float) -> int:
    """How many independent motions of the output the mechanism allows with every
    actuated joint locked (rank of the homogenised output twists, about ``p``, over the
    allowed motions that leave the actuated rates zero; relative to the output twists'
    largest singular value). At a configuration whose ranks are the generic ones
    (:attr:`Mobility.singular` False) these exist at every configuration nearby: an
    under-actuated mechanism (springs, passive joints without a motor), whose class II
    marks that, not a singular pose."""
    rank_x, _, _, Vt = svd_rank(ns.X, rtol)
    if rank_x == ns.X.shape[1]:
        return 0
    Yh = homogenised_about(ns.Y_world.T, p, L).T
    scale = np.linalg.norm(Yh, 2)
    if not scale > 0:
        return 0
    sv = np.linalg.svd(Yh @ Vt[rank_x:].T, compute_uv=False)
    return int(np.sum(sv > rtol * scale))


def kinematic_redundancy(independent: int, output_point: bool) -> int:
    """How many more independent actuators a mechanism has than its output can have
    directions of motion (6 for a body, 3 for a point output): that many self-motions
    (the actuators moving with the output held: class I) at every configuration, at
    least. 0 when
    it has no more (a redundancy the output's rank hides, a planar 4R arm's, is not
    counted: it would need the generic rank of the output twists)."""
    return max(int(independent) - (3 if output_point else 6), 0)


def _number(x: float) -> str:
    """An index in a sentence: ``.3g``, ``"undefined"`` where it is not a number, or
    ``"infinite"``."""
    return f"{x:.3g}" if math.isfinite(x) else ("undefined" if math.isnan(x) else "infinite")


def _smaller(a: float, b: float) -> float:
    """``float(np.nanmin([a, b]))`` without numpy's warning when both are nan."""
    if math.isnan(a):
        return float(b)
    return float(a) if math.isnan(b) else float(min(a, b))


def _numpy_core(link: Linkage, kin: TreeKinematics, about: str,
                rtol: float) -> general_kernel.Core:
    """The numbers of an analysis by numpy from a Pinocchio pass (the reference of the
    compiled :func:`pkm_pin.general_kernel.analysis_core`, and the path of trees it does
    not represent)."""
    model = link.model
    L = model.length
    p = kin.output_placement.translation.copy() if about == "output" else np.zeros(3)
    ns = NullSpace(model, kin, rtol)
    Yh = homogenised_about(ns.Y_world.T, p, L).T  # 6 × dof
    d, Uy, _, _ = svd_rank(Yh, rtol)
    P_h = Uy[:, :d].T
    rotations = int(np.sum(np.linalg.svd(P_h[:, :3], compute_uv=False) > ROTATION_COUNT_TOL))
    _, _, _, Vc = svd_rank(P_h @ screws.DELTA, rtol)
    C_h = Vc[d:]  # homogenised wrenches (f; m_p / L) reciprocal to P
    A, B, type_I = _actuation(model, kin, link._loops, p, rtol)
    A_h = homogenised_about(A, p, L) if len(A) else np.zeros((0, 6))
    norms = np.linalg.norm(A_h, axis=1)
    A_n = A_h / np.where(norms > 0, norms, 1.0)[:, None]
    type_II, cond = _transmission(A_n, P_h, d) if np.all(norms > 0) else (np.nan, np.nan)
    Xr, Yr, M, forward, inverse = _generalised(ns, Yh, rtol)
    translating = np.array([not np.linalg.norm(kin.joint_twists[c][:3]) > 0
                            for c in model.actuated_v], dtype=bool)
    return general_kernel.Core(kin, ns, p, d, rotations, from_homogenised(P_h, p, L),
                               from_homogenised(C_h, p, L), A, B, type_I, type_II, cond,
                               Xr, Yr, M, forward, inverse, translating)


def _transmission(A_n: np.ndarray, P_h: np.ndarray, d: int) -> tuple[float, float]:
    """Seed 000's type II index and condition: singular values of ``A_n Δ P_hᵀ``."""
    n = A_n.shape[0]
    if n == 0 or d == 0:
        return 0.0, np.inf
    sv = np.linalg.svd(A_n @ (P_h @ screws.DELTA).T, compute_uv=False)
    t2 = float(sv[d - 1]) if d <= n else 0.0
    return t2, (float(sv[0] / t2) if t2 > 0 else np.inf)


def _generalised(ns: NullSpace, Yh: np.ndarray, rtol: float):
    """Reduced maps ``X_r``, ``Y_r`` on the motions that move the actuators or the output
    (basis ``M`` of null coordinates), and the forward and inverse indices: the smallest
    singular values of the actuated and output blocks of the orthonormalised ``(X; Y)``."""
    if ns.X.shape[1] == 0 and Yh.shape[1] == 0:
        return ns.X, Yh, ns.N, 1.0, 1.0
    m, Vt, forward, inverse = screws.motion_indices(ns.X, Yh, rtol)
    return ns.X @ Vt[:m].T, Yh @ Vt[:m].T, ns.N @ Vt[:m].T, forward, inverse


def _actuation(model: ClosureModel, kin: TreeKinematics, loops: tuple, p: np.ndarray,
               rtol: float) -> tuple[np.ndarray, np.ndarray, float]:
    """``A`` (n × 6, world origin), ``B`` (n × n diagonal) and the type I index
    (module docstring, "Elimination of the passive rates")."""
    L, U = model.length, model.velocity_units
    H_o = homogenised_about(kin.output_jacobian.T, p, L).T * U
    slices = model.closure_slices()
    n = len(model.actuated)
    A, B, type_I = np.zeros((n, 6)), np.zeros(n), np.inf
    for k, col in enumerate(model.actuated_v):
        for chosen in (loops[k], range(len(model.closures))):
            rows = [np.arange(model.nv)[:0]] + [np.arange(slices[c].start, slices[c].stop)
                                                 for c in chosen]
            G = np.vstack([kin.closure_jacobian[np.concatenate(rows)] * U, H_o])
            zeta = _actuation_row(G, col, rtol)
            if zeta is not None:
                break
        if zeta is None:
            type_I = 0.0
            continue
        A[k], B[k] = _scaled_wrench(zeta, p, L, U[col], rtol)
        twist = homogenised_about(kin.joint_twists[col][None], p, L)[0]
        a_h = homogenised_about(A[k][None], p, L)[0]
        type_I = min(type_I, abs(B[k]) / (L * np.linalg.norm(a_h) * np.linalg.norm(twist)))
    return A, np.diag(B), float(type_I)


def _actuation_row(G: np.ndarray, col: int, rtol: float) -> np.ndarray | None:
    """The homogenised wrench ``ζ_h = (f; m_p / L)`` with ``β = 1`` orthogonal to the
    admissible ζ with β = 0 (``None`` when column ``col`` depends on the others)."""
    others = np.delete(G, col, axis=1)
    rank, Ul, _, _ = svd_rank(others, rtol)
    W = Ul[:, rank:].T
    b = W @ G[:, col]
    if np.linalg.norm(b) <= rtol * max(np.linalg.norm(G[:, col]), 1e-300):
        return None
    Z = W[:, -6:] @ screws.DELTA  # ζ_h read from w_o
    y0 = b / (b @ b)
    _, _, Vb = np.linalg.svd(b[None], full_matrices=True)
    Nb = Vb[1:].T
    z = np.linalg.lstsq(Z.T @ Nb, -Z.T @ y0, rcond=rtol)[0] if Nb.size else np.zeros(0)
    zeta = Z.T @ (y0 + Nb @ z)
    # The closures alone can hold the actuated rate (w_o = 0 with β ≠ 0: the actuator
    # is locked by the loops here): no wrench on the output carries it, as when the
    # column depends on the others.
    if np.linalg.norm(zeta) <= rtol * np.linalg.norm(y0):
        return None
    return zeta


def _scaled_wrench(zeta_h: np.ndarray, p: np.ndarray, L: float, unit: float,
                   rtol: float) -> tuple[np.ndarray, float]:
    """World wrench (unit force, or unit moment for a couple) and ``B`` from the
    homogenised ζ with ``β = 1``: ``ζ ∘ t = (L / u_a) q̇_a``."""
    f, m_p = zeta_h[:3], zeta_h[3:] * L
    s = np.linalg.norm(f) if np.linalg.norm(f) * L > rtol * np.linalg.norm(m_p) \
        else np.linalg.norm(m_p)
    wrench = screws.from_point(np.r_[f, m_p], p) / s  # the moment about the world origin
    return wrench, L / unit / s


# ========================================================================= sweep
#: The results of :meth:`Linkage.sweep`: the one sweep result type
#: (:class:`pkm_pin.sweep.SweepResult`), its points actuated values.
LinkageSweep = SweepResult


class _SweepRows:
    """Preallocated rows of a :class:`LinkageSweep`."""

    _INDICES = ("type_I", "type_II", "condition_A", "forward", "inverse")

    def __init__(self, Q: np.ndarray, nq: int):
        n = self.n = len(Q)
        self.qa = Q
        self.ok = np.zeros(n, bool)
        self.q = np.full((n, nq), np.nan)
        self.poses = np.full((n, 6), np.nan)
        self.dof = np.full(n, -1)
        self.odof = np.full(n, -1)
        self.cls = np.full(n, "", dtype=object)
        self.idx = {k: np.full(n, np.nan) for k in self._INDICES}
        self.lti, self.cti = np.full(n, np.nan), np.full(n, np.nan)
        self.failures: list = []

    def record(self, i: int, a: Assembly, an: LinkageAnalysis) -> None:
        self.ok[i] = True
        self.q[i], self.poses[i] = a.q, pose_coordinates(a.output_pose)
        self.dof[i], self.odof[i], self.cls[i] = an.dof, an.output_dof, an.singularity
        for k in self._INDICES:
            self.idx[k][i] = an.indices[k]

    def fields(self, rows=slice(None)) -> dict:
        """The per-row arrays a checkpoint keeps, of ``rows`` (default all), the classes
        as fixed-width strings (what a checkpoint file holds)."""
        return {"ok": self.ok[rows], "q": self.q[rows], "poses": self.poses[rows],
                "dof": self.dof[rows], "output_dof": self.odof[rows],
                "singularity": self.cls[rows].astype("<U4"), "q_actuated": self.qa[rows],
                "lti": self.lti[rows], "cti": self.cti[rows],
                **{k: v[rows] for k, v in self.idx.items()}}

    def part(self, rows: np.ndarray) -> dict:
        """The checkpoint's part of ``rows`` (failures by position in ``rows``)."""
        where = {int(i): k for k, i in enumerate(rows)}
        part = self.fields(rows)
        part["failures"] = [(where[i], why) for i, why in self.failures if i in where]
        return part

    def restore(self, stage) -> None:
        """The rows recorded in ``stage`` (a resume), copied in."""
        if not stage.done.any():
            return
        d = stage.done
        v = stage.values
        self.ok[d], self.q[d], self.poses[d] = v["ok"][d], v["q"][d], v["poses"][d]
        self.dof[d], self.odof[d], self.qa[d] = v["dof"][d], v["output_dof"][d], \
            v["q_actuated"][d]
        self.cls[d] = v["singularity"][d]
        self.lti[d], self.cti[d] = v["lti"][d], v["cti"][d]
        for k in self._INDICES:
            self.idx[k][d] = v[k][d]
        self.failures = sorted((int(i), why) for i, why in stage.failures.items())

    def result(self) -> SweepResult:
        self.failures.sort()
        idx = self.idx
        return SweepResult(self.poses, self.ok, self.dof, self.cls.astype(str),
                           idx["type_I"], idx["type_II"], idx["condition_A"],
                           np.full(self.n, np.nan), self.qa, self.failures, self.lti,
                           self.cti, self.odof, idx["forward"], idx["inverse"], self.q)
