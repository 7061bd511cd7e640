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
  rows, idle motions (those left with every actuated joint locked, described in words),
  the actuated joints that can be driven independently, and Grübler's count.
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
tol``; II: ``min(type_II, forward) < tol``; III: both.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import pinocchio as pin

from . import screws
from .analysis import classify
from .errors import AssemblyError, ForwardKinematicsError, InputError, SingularityError
from .model.closure_model import ClosureModel, TreeKinematics
from .screws import svd_rank
from .solve import iter_tree_starts, solve_tree, solve_tree_starts, tree_starts
from .tolerances import (
    CLOSENESS_SINGULAR_TOL,
    CLOSURE_TOL,
    MODES_PATIENCE,
    RANK_RTOL,
    ROTATION_COUNT_TOL,
    SAME_CONFIGURATION_TOL,
    SPAN_RTOL,
)

__all__ = ["Linkage", "LinkageAnalysis", "LinkageAssembly", "LinkageSweep", "LoopClosureError",
           "Mobility"]


class LoopClosureError(AssemblyError):
    """A loop of a linkage does not close (an :class:`AssemblyError` whose ``leg`` is the
    name of the worst closure, or of the actuated or output targets).

    Attributes:
        leg: Name of the loop (closure) that does not close.
        residual: Its residual (dimensionless, as :meth:`ClosureModel.closure_residual`).
    """

    def __init__(self, loop: str, residual: float, detail: str = ""):
        super().__init__(loop, residual, detail)
        message = (f"loop {loop!r} does not close: the best configuration found within the "
                   f"joint limits leaves a relative residual of {self.residual:.3g}")
        self.args = (message + (f" ({detail})" if detail else ""),)

    def __str__(self) -> str:
        return self.args[0]


@dataclass(frozen=True, eq=False)
class LinkageAssembly:
    """An assembled configuration of a linkage.

    Attributes:
        q: Configuration of the whole tree (nq,), in the tree's joint order.
        residual: Largest residual of the solve (closures, actuated targets, output
            pose target; dimensionless).
        iterations: Newton steps spent, all restarts included.
        closure_residuals: Norm of each closure's residual rows, by closure name.
        q_actuated: Values of the actuated joints [rad or m].
        output_pose: World placement of the output frame.
    """

    q: np.ndarray = field(repr=False)
    residual: float
    iterations: int
    closure_residuals: dict
    q_actuated: np.ndarray
    output_pose: pin.SE3 = field(repr=False)


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
    """

    dof: int
    redundant_constraints: int
    idle_dof: int
    idle_motions: tuple
    independent_actuators: tuple
    grubler: int


def homogenised_about(S: np.ndarray, p: np.ndarray, length: float) -> np.ndarray:
    """Screws ``S`` (rows, world origin) about the point ``p``, moment part / ``length``:
    ``(a; b) → (a; (b + a × p) / length)`` (the velocity, or moment, at ``p``)."""
    return screws.homogenise(screws.about(np.atleast_2d(S), p), length)


def from_homogenised(H: np.ndarray, p: np.ndarray, length: float) -> np.ndarray:
    """Inverse of :func:`homogenised_about`: world-origin screws (rows)."""
    H = np.atleast_2d(H)
    if H.shape[0] == 0:
        return np.zeros((0, 6))
    return screws.from_point(screws.dehomogenise(H, length), p)


class Linkage:
    """A general closed-loop mechanism (see the module docstring).

    Args:
        model: The closure model (immutable; kept as :attr:`model`).
        output: Another frame of the tree to analyse instead of ``model.output``.
        point: Analyse the output frame's origin as a point (its translations only,
            :attr:`ClosureModel.output_point`), or as a body (``False``); default: as
            ``model`` says.
    """

    def __init__(self, model: ClosureModel, output: str | None = None,
                 point: bool | None = None):
        if not isinstance(model, ClosureModel):
            raise InputError(f"model must be a ClosureModel, got {type(model).__name__}")
        if output is not None and output != model.output:
            model = replace(model, output=output)
        if point is not None and bool(point) != model.output_point:
            model = replace(model, output_point=bool(point))
        self._model = model
        self._loops = _loops_of_actuators(model)
        self._closure_names = tuple(c.name or f"closure {k}"
                                    for k, c in enumerate(model.closures))

    def __repr__(self) -> str:
        return f"Linkage({self.name!r}, actuated={self.actuated}, output={self.output!r})"

    @property
    def model(self) -> ClosureModel:
        """The closure model."""
        return self._model

    @property
    def name(self) -> str:
        """Name of the mechanism."""
        return self._model.name

    @property
    def actuated(self) -> tuple:
        """Names of the actuated joints."""
        return self._model.actuated

    @property
    def output(self) -> str:
        """Name of the output frame."""
        return self._model.output

    @property
    def grubler(self) -> int:
        """Grübler–Kutzbach count ``Σ joint nv − Σ closure rows`` (for comparison with
        :attr:`Mobility.dof`: it ignores redundant rows)."""
        return self._model.nv - self._model.n_rows

    # ---------------------------------------------------------------- inputs
    def check_actuated(self, q_actuated, name: str = "q_actuated") -> np.ndarray:
        """``q_actuated`` as a finite array of one value per actuated joint."""
        return screws.as_vector(q_actuated, len(self.actuated), name, ", ".join(self.actuated))

    def _guess_q(self, guess) -> np.ndarray | None:
        if guess is None:
            return None
        if isinstance(guess, LinkageAssembly):
            return guess.q
        return self._model.check_q(guess)

    # ------------------------------------------------------------ assembly
    def assemble(self, guess=None, *, q_actuated=None, starts: int = 16, seed: int = 0,
                 tol: float = CLOSURE_TOL, max_iter: int = 100) -> LinkageAssembly:
        """Close every loop (and, with ``q_actuated``, pin the actuated joints).

        Starts (:func:`pkm_pin.solve.tree_starts`): ``guess`` (a configuration or a
        :class:`LinkageAssembly`), ``model.reference``, neutral, the middle of the limits
        and ``starts`` random configurations within the limits (``seed``). A converged
        warm start is kept; otherwise the converged solution nearest ``guess`` (default
        the reference) is.

        Raises:
            LoopClosureError: no start closes; the message names the worst loop and its
                residual.
        """
        model = self._model
        warm = self._guess_q(guess)
        targets = None if q_actuated is None else self.check_actuated(q_actuated)
        rows = iter_tree_starts(model, warm, count=int(starts), seed=seed)
        sol, iterations = solve_tree_starts(model, rows, targets=targets, tol=tol,
                                            max_iter=max_iter,
                                            nearest=model.reference if warm is None else warm)
        if not sol.converged:
            raise self._failure(sol, int(starts) + 3 + (warm is not None), targets)
        return self._assembly(sol, iterations)

    def _assembly(self, sol, iterations: int) -> LinkageAssembly:
        """The assembly at a converged :class:`~pkm_pin.solve.TreeSolution` (its last
        Pinocchio pass, when it was at ``sol.q``)."""
        model, q = self._model, sol.q
        norms, oMo = sol.closure_norms, sol.output_placement
        if norms is None or oMo is None:
            kin = model.kinematics(q)
            norms, oMo = model.closure_norms(kin.residual), kin.output_placement
        names = dict(zip(self._closure_names, norms.tolist()))
        return LinkageAssembly(q.copy(), float(sol.residual), int(iterations), names,
                               _actuated_or_nan(model, q), oMo)

    def _failure(self, sol, n_starts: int, targets, what: str = "") -> LoopClosureError:
        model = self._model
        residual = model.closure_residual(sol.q)
        norms = [float(np.linalg.norm(residual[s])) for s in model.closure_slices()]
        detail = f"{n_starts} starts, {sol.iterations} iterations in the best one"
        if norms and max(norms) > sol.actuated and max(norms) >= sol.pose:
            k = int(np.argmax(norms))
            return LoopClosureError(model.closures[k].name or f"closure {k}", norms[k], detail)
        if targets is not None and sol.actuated >= sol.pose:
            return LoopClosureError("actuated targets", sol.actuated,
                                    detail + f"; targets {np.round(targets, 6)}")
        return LoopClosureError(what or "output pose", sol.pose, detail)

    # ------------------------------------------------------------- mobility
    def mobility(self, q, rtol: float = RANK_RTOL) -> Mobility:
        """:class:`Mobility` at the configuration ``q`` (assembled)."""
        kin = self._model.kinematics(q)
        return _mobility(self, kin, _NullSpace(self._model, kin, rtol), rtol)

    # ------------------------------------------------------------- analysis
    def analyze(self, q, *, about: str = "output", generic: LinkageAnalysis | None = None,
                rtol: float = RANK_RTOL, singular_tol: float = CLOSENESS_SINGULAR_TOL
                ) -> LinkageAnalysis:
        """:class:`LinkageAnalysis` of the output frame at the assembled ``q`` (or a
        :class:`LinkageAssembly`).

        Args:
            about: ``"output"`` (homogenise about the output frame's origin: frame-
                invariant) or ``"world"`` (about the world origin, as seed 000's
                :class:`pkm_pin.Analysis`).
            generic: An analysis at a generic configuration: a constraint singularity is
                a change of ``dof`` or ``output_dof`` from it (``None``: not decided).
        """
        if about not in ("output", "world"):
            raise InputError(f"about must be 'output' or 'world', got {about!r}")
        q = q.q if isinstance(q, LinkageAssembly) else q
        return _analyse(self, self._model.kinematics(q), about, generic, rtol, singular_tol)

    # ---------------------------------------------------- position problems
    def forward_kinematics(self, q_actuated, guess=None, *, starts: int = 16, seed: int = 0,
                           tol: float = CLOSURE_TOL) -> LinkageAssembly:
        """Every joint and the output pose from the actuated values [rad or m]: the
        branch nearest ``guess`` (a configuration or :class:`LinkageAssembly`; default
        the reference configuration)."""
        return self.assemble(guess, q_actuated=q_actuated, starts=starts, seed=seed, tol=tol)

    def forward_kinematics_all(self, q_actuated, *, starts: int = 32, seed: int = 0,
                               patience: int = MODES_PATIENCE, tol: float = CLOSURE_TOL):
        """Every assembly mode found for the actuated values: a multistart of the tree
        solver from batches of ``starts`` configurations drawn within the joint limits
        (the reference first), stopped after ``patience`` batches in a row find no new
        mode. Two assemblies are the same mode when every joint origin and the output
        pose agree to :data:`~pkm_pin.tolerances.SAME_CONFIGURATION_TOL` (relative to
        the characteristic length): an idle motion (a rod spinning between its spherical
        joints) does not make a new mode.

        Returns:
            :class:`~pkm_pin.modes.AssemblyModes` of :class:`LinkageAssembly`, nearest
            the reference first, ``complete=False`` (a multistart proves nothing).

        Raises:
            ForwardKinematicsError: no start closes the loops at these values.
        """
        from time import perf_counter

        from .modes import AssemblyModes

        t0 = perf_counter()
        target = self.check_actuated(q_actuated)
        model = self._model
        found, signatures, batch, quiet, tried = [], [], 0, 0, 0
        while quiet < patience:
            rows = tree_starts(model, None if batch else model.reference, count=starts,
                               seed=seed + batch)
            new = False
            for q0 in rows:
                tried += 1
                sol = solve_tree(model, q0, targets=target, tol=tol)
                if not sol.converged:
                    continue
                sig = self._signature(sol.q)
                if all(np.max(np.abs(sig - s)) > SAME_CONFIGURATION_TOL for s in signatures):
                    signatures.append(sig)
                    found.append(self._assembly(sol, sol.iterations))
                    new = True
            batch += 1
            quiet = 0 if new else quiet + 1
        if not found:
            raise ForwardKinematicsError(
                f"no assembly of {self.name!r} at the actuated values {np.round(target, 6)}: "
                f"none of {tried} starts closed the loops (not proven: a multistart)")
        ref = self._signature(model.reference)
        found.sort(key=lambda a: float(np.linalg.norm(self._signature(a.q) - ref)))
        return AssemblyModes(found, False, "multistart",
                             {"starts": tried, "batches": batch, "modes": len(found)},
                             perf_counter() - t0)

    def transmission(self, q, *, analysis: LinkageAnalysis | None = None):
        """Motion/force transmission indices of the linkage at ``q`` (a configuration or
        :class:`LinkageAssembly`; :mod:`pkm_pin.transmission`, Wang, Wu & Liu 2010):
        each actuator's side of its loops is its "leg". ``analysis``: :meth:`analyze` of
        the same ``q`` about the output, when the caller has made it (not made again).

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

        q = q.q if isinstance(q, LinkageAssembly) else self._model.check_q(q)
        model, kin = self._model, self._model.kinematics(q)
        an = analysis
        if an is None:
            an = _analyse(self, kin, "output", None, RANK_RTOL, CLOSENESS_SINGULAR_TOL)
        elif not (np.array_equal(an.q, q) and np.array_equal(
                an.reference_point, kin.output_placement.translation)):
            raise InputError("analysis: not this linkage's analysis of q about its output "
                             "(Linkage.analyze(q))")
        tree, J = model.tree, kin.joint_twists
        cols = list(model.actuated_v)
        ids = [tree.getJointId(name) for name in model.actuated]
        out_joint = tree.frames[tree.getFrameId(model.output)].parentJoint
        W = np.array([_transmission_wrench(model, kin, j, self._loops[k], out_joint,
                                           an.reference_point) for k, j in enumerate(ids)]
                     ).reshape(-1, 6)
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
        tree = self._model.tree
        data = tree.createData()
        pin.framesForwardKinematics(tree, data, np.asarray(q, dtype=float))
        oMo = data.oMf[tree.getFrameId(self._model.output)]
        points = [data.oMi[j].translation for j in range(1, tree.njoints)]
        return np.concatenate(points + [oMo.translation, oMo.rotation.ravel()
                                        * self._model.length]) / self._model.length

    def inverse_kinematics(self, pose, guess=None, *, starts: int = 16, seed: int = 0,
                           tol: float = CLOSURE_TOL) -> LinkageAssembly:
        """The assembly whose output frame reaches ``pose`` (``pin.SE3``, world).

        When the output has 6 DOF the whole pose is targeted. Otherwise only the
        components of the pose error ``log6(pose⁻¹ · oMo)`` (output axes, ``(θ; ρ /
        L)``) along the output's twist system at the guess (its assembly; homogenised,
        output axes) are targeted: the output reaches the pose as far as it can move
        towards it, the other components are what the mechanism imposes.

        Raises:
            LoopClosureError: no start closes the loops and reaches the pose.
        """
        if not isinstance(pose, pin.SE3) or not np.isfinite(pose.homogeneous).all():
            raise InputError(f"pose must be a finite pinocchio.SE3, got {type(pose).__name__}")
        model = self._model
        home = self.assemble(guess, starts=starts, seed=seed, tol=tol)
        rows = _pose_rows(model, model.kinematics(home.q))
        sol, iterations = solve_tree_starts(
            model, iter_tree_starts(model, home.q, count=int(starts), seed=seed), pose=pose,
            pose_rows=rows, nearest=home.q, tol=tol)
        if not sol.converged:
            raise self._failure(sol, starts + 4, None, "output pose")
        return self._assembly(sol, iterations + home.iterations)

    def workspace(self, coords=None, **options):
        """Reachable, singularity-free and good-transmission (LTI of
        :meth:`transmission` ≥ 0.7) workspaces of the output point or over actuated
        coordinates, on the reference's working mode:
        :func:`pkm_pin.workspace.linkage_workspace`."""
        from .workspace import linkage_workspace

        return linkage_workspace(self, coords, **options)

    def sweep(self, q_actuated, guess=None, *, tol: float = CLOSURE_TOL,
              about: str = "output", transmission: bool = False) -> LinkageSweep:
        """Forward kinematics and analysis along the rows of ``q_actuated`` (N ×
        actuated), each warm-started from the previous assembly (continuation: the
        branch of ``guess``). A point that does not close is recorded as not converged
        (NaN results) and the next starts again from the last good one. With
        ``transmission``, the ``lti`` and ``cti`` columns too (:meth:`transmission`:
        a few ms a point; nan otherwise)."""
        Q = screws.as_float_array(q_actuated, "q_actuated")
        if Q.ndim != 2 or Q.shape[1] != len(self.actuated):
            raise InputError(f"q_actuated must have shape (N, {len(self.actuated)}) "
                             f"({', '.join(self.actuated)}), got {Q.shape}")
        warm = self._guess_q(guess)
        out = _SweepRows(Q, self._model.nq)
        generic = None
        for i, qa in enumerate(Q):
            try:
                a = self.assemble(warm, q_actuated=qa, starts=0 if warm is not None else 16,
                                  tol=tol)
            except AssemblyError:
                continue
            warm = a.q
            an = self.analyze(a.q, about=about, generic=generic)
            generic = generic or an
            out.record(i, a, an)
            if transmission:
                tr = self.transmission(a, analysis=an if about == "output" else None)
                out.lti[i], out.cti[i] = tr.lti, tr.cti
        return out.result()


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


def _pose_rows(model: ClosureModel, kin: TreeKinematics) -> np.ndarray:
    """Rows (d × 6) selecting the components of the output pose error that the output
    can realise: an orthonormal basis of its twist system, homogenised, in its own axes
    and about its origin (the identity when d = 6)."""
    ns = _NullSpace(model, kin, RANK_RTOL)
    M = kin.output_placement  # a point's error is in world axes (solve.pose_error_rows)
    M = pin.SE3(np.eye(3), M.translation) if model.output_point else M
    local = screws.homogenise(screws.transform(ns.Y_world.T, M.inverse()), model.length)
    rank, _, _, Vt = svd_rank(local, RANK_RTOL)
    return np.eye(6) if rank == 6 else Vt[:rank]


class _NullSpace:
    """The motions the closures allow at one configuration (dimensionless columns).

    Attributes: ``N`` (nv × dof) orthonormal null-space basis of ``J_c U``; ``rank``;
    ``X`` (actuated × dof) actuated rates; ``Y_world`` (6 × dof) output twists about the
    world origin per unit of the null coordinates."""

    def __init__(self, model: ClosureModel, kin: TreeKinematics, rtol: float):
        U = model.velocity_units
        rank, _, _, Vt = svd_rank(kin.closure_jacobian * U, rtol)
        self.rank, self.N = rank, Vt[rank:].T
        self.X = self.N[list(model.actuated_v)]
        self.Y_world = kin.output_jacobian @ (U[:, None] * self.N)
        self.units = U

    def idle(self, rtol: float) -> np.ndarray:
        """(nv × k) orthonormal basis of the idle motions (dimensionless columns): the
        allowed motions that leave every actuated joint still."""
        rank_x, _, _, Vt = svd_rank(self.X, rtol)
        return self.N @ Vt[rank_x:].T


# ====================================================================== mobility
def _mobility(link: Linkage, kin: TreeKinematics, ns: _NullSpace, rtol: float) -> Mobility:
    model = link.model
    dof = model.nv - ns.rank
    idle = ns.idle(rtol)
    words = tuple(describe_motion(model, kin, ns.units * idle[:, k])
                  for k in range(idle.shape[1]))
    return Mobility(dof, model.n_rows - ns.rank, idle.shape[1], words,
                    _independent(model, ns.X, rtol), link.grubler)


def _independent(model: ClosureModel, X: np.ndarray, rtol: float) -> tuple:
    """Greedy maximal set of actuated joints whose rates (rows of ``X``) are
    independent over the allowed motions."""
    if X.shape[0] and X.shape[0] <= X.shape[1]:
        sv = np.linalg.svd(X, compute_uv=False)  # full row rank: every subset is independent
        if sv[-1] > rtol * sv[0]:
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


def describe_motion(model: ClosureModel, kin: TreeKinematics, v: np.ndarray) -> str:
    """One sentence describing the tree motion ``v`` (nv,): the body that moves and the
    line it turns about (through its joints' centres when they lie on it), or the
    joints that move."""
    tree, L = model.tree, model.length
    x = v / model.velocity_units
    moving = [tree.names[j] for j in range(1, tree.njoints)
              if np.abs(x[tree.joints[j].idx_v:tree.joints[j].idx_v + tree.joints[j].nv]).max(
                  initial=0.0) > 1e-9 * np.abs(x).max()]
    T = _body_twists(model, kin, v)
    size = np.linalg.norm(screws.homogenise(T, L), axis=1)
    bodies = [j for j in range(1, tree.njoints) if size[j] > 1e-9 * size.max()]
    if len(bodies) == 1:
        j = bodies[0]
        w, vel = T[j, :3], T[j, 3:]
        if np.linalg.norm(w) > 0 and abs(w @ vel) <= 1e-9 * np.linalg.norm(w) ** 2 * L:
            point, direction = screws.axis(T[j], L)
            on = [p for p in _body_points(model, kin, j)
                  if np.linalg.norm(np.cross(p - point, direction)) <= 1e-7 * L]
            where = (" and ".join(_fmt(p) for p in on[:2]) if len(on) >= 2 else
                     f"{_fmt(point)} along {_fmt(direction)}")
            through = "its joints at " if len(on) >= 2 else ""
            return f"{_body_name(tree, j)} spins about the line through {through}{where}"
    return (f"joints {', '.join(moving)} move (bodies "
            f"{', '.join(_body_name(tree, j) for j in bodies)})")


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


# ====================================================================== analysis
@dataclass(frozen=True, eq=False)
class LinkageAnalysis:
    """The output frame of a linkage at one configuration (:meth:`Linkage.analyze`).

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

    def passive_rates(self, qdot_actuated) -> np.ndarray:
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
        v = self.passive_rates(qdot_actuated)
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


def _analyse(link: Linkage, kin: TreeKinematics, about: str, generic, rtol: float,
             singular_tol: float) -> LinkageAnalysis:
    model = link.model
    L = model.length
    p = kin.output_placement.translation.copy() if about == "output" else np.zeros(3)
    ns = _NullSpace(model, kin, rtol)
    mob = _mobility(link, kin, ns, rtol)
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
    idx = {"type_I": type_I, "type_II": type_II, "condition_A": cond, "forward": forward,
           "inverse": inverse}
    singularity = classify(float(np.nanmin([type_I, inverse])),
                           float(np.nanmin([type_II, forward])), singular_tol)
    csing = None if generic is None else bool(mob.dof != generic.dof
                                              or d != generic.output_dof)
    return LinkageAnalysis(kin.q, mob, d, d - rotations, from_homogenised(P_h, p, L),
                           from_homogenised(C_h, p, L), A, B, idx, singularity, csing, p, L,
                           singular_tol, (Xr, Yr, M, ns.units, list(model.actuated_v)))


def _transmission(A_n: np.ndarray, P_h: np.ndarray, d: int) -> tuple[float, float]:
    """Seed 000's type II index and condition: singular values of ``A_n Δ P_hᵀ``."""
    n = A_n.shape[0]
    if n == 0 or d == 0:
        return 0.0, np.inf
    sv = np.linalg.svd(A_n @ (P_h @ screws.DELTA).T, compute_uv=False)
    t2 = float(sv[d - 1]) if d <= n else 0.0
    return t2, (float(sv[0] / t2) if t2 > 0 else np.inf)


def _generalised(ns: _NullSpace, Yh: np.ndarray, rtol: float):
    """Reduced maps ``X_r``, ``Y_r`` on the motions that move the actuators or the output
    (basis ``M`` of null coordinates), and the forward and inverse indices: the smallest
    singular values of the actuated and output blocks of the orthonormalised ``(X; Y)``."""
    n = ns.X.shape[0]
    S = np.vstack([ns.X, Yh])
    if S.shape[1] == 0:
        return ns.X, Yh, ns.N, 1.0, 1.0
    m, _, _, Vt = svd_rank(S, rtol)
    M = ns.N @ Vt[:m].T
    Xr, Yr = ns.X @ Vt[:m].T, Yh @ Vt[:m].T
    if m == 0:
        return Xr, Yr, M, 1.0, 1.0
    Q, _ = np.linalg.qr(np.vstack([Xr, Yr]))
    cx = np.linalg.svd(Q[:n], compute_uv=False) if n else np.zeros(0)
    cy = np.linalg.svd(Q[n:], compute_uv=False)
    forward = float(cx[m - 1]) if n >= m else 0.0
    inverse = float(cy[m - 1]) if Yr.shape[0] >= m else 0.0
    return Xr, Yr, M, forward, inverse


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
    return Z.T @ (y0 + Nb @ z)


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
@dataclass(frozen=True, eq=False)
class LinkageSweep:
    """Results of :meth:`Linkage.sweep`, one row per actuated point (NaN / ``""`` where
    it did not converge).

    Attributes:
        q_actuated: (N × actuated) the points asked for.
        converged: (N,) whether the point was assembled.
        q: (N × nq) configurations; output_poses: (N × 4 × 4) output placements.
        dof, output_dof: (N,) as :class:`LinkageAnalysis` (-1 where not converged).
        singularity: (N,) class strings; condition: (N,) ``condition_A``;
        forward, inverse: (N,) the general indices.
        lti, cti: (N,) the transmission indices (``sweep(..., transmission=True)``;
            else nan).
    """

    q_actuated: np.ndarray
    converged: np.ndarray
    q: np.ndarray
    output_poses: np.ndarray
    dof: np.ndarray
    output_dof: np.ndarray
    singularity: np.ndarray
    condition: np.ndarray
    forward: np.ndarray
    inverse: np.ndarray
    lti: np.ndarray
    cti: np.ndarray


class _SweepRows:
    """Preallocated rows of a :class:`LinkageSweep`."""

    def __init__(self, Q: np.ndarray, nq: int):
        n = self.n = len(Q)
        self.qa = Q
        self.ok = np.zeros(n, bool)
        self.q = np.full((n, nq), np.nan)
        self.poses = np.full((n, 4, 4), np.nan)
        self.dof = np.full(n, -1)
        self.odof = np.full(n, -1)
        self.cls = np.full(n, "", dtype=object)
        self.cond, self.fwd, self.inv = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
        self.lti, self.cti = np.full(n, np.nan), np.full(n, np.nan)

    def record(self, i: int, a: LinkageAssembly, an: LinkageAnalysis) -> None:
        self.ok[i] = True
        self.q[i], self.poses[i] = a.q, a.output_pose.homogeneous
        self.dof[i], self.odof[i], self.cls[i] = an.dof, an.output_dof, an.singularity
        self.cond[i] = an.indices["condition_A"]
        self.fwd[i], self.inv[i] = an.indices["forward"], an.indices["inverse"]

    def result(self) -> LinkageSweep:
        return LinkageSweep(self.qa, self.ok, self.q, self.poses, self.dof,
                            self.odof, self.cls.astype(str), self.cond, self.fwd, self.inv,
                            self.lti, self.cti)
