"""Position problems (seed 003: Demidov 2025, see docs/references.md): forward kinematics
by screw continuation, assembly modes, iterative inverse kinematics of a serial chain.

Forward position problem (:func:`forward_kinematics`)
------------------------------------------------------
Seed 003's continuation: from a known assembly the actuated coordinates go to the
target in ``N`` equal increments ``Δq``. At each step the screw analysis of the current
assembly (:class:`~pkm_pin.analysis.Analysis`) gives the small platform twist ``t``
solving ``A Δ t = B Δq`` on the platform twist system (the "equilibrium of velocities";
for the 6-SPS body its rows are the Plücker coordinates of the leg lines,
``E_i ∘ t = Δl_i``); the platform moves by ``screws.exp(t) * pose`` and the legs are
re-solved at the new pose (warm start, loose tolerance). That is the Euler polyline of
the paper: its error falls like ``1/N``. For lower-mobility mechanisms whose motion is
curved (3-RPS), ``exp(t)`` leaves the constraint manifold by ``O(|t|²)``; the step is
then projected back by the Newton correction below aimed at the intermediate target.

The Newton corrections are those of the closure solver (:mod:`pkm_pin.solve`): legs
re-closed at the predicted pose (mask LEGS), or with the platform free (PLATFORM) and
aimed at the actuated coordinates (ACTUATED). The final correction is Newton's method on
the closure equations of every leg and the actuated coordinates, unknowns the platform
twist ``t`` and the joint increments ``Δq_i``::

    J_i Δq_i − t = e_i      (e_i: leg i's closure residual towards pose * anchor_i)
    Δq_a = q_target − q_a

Multiplying leg ``i``'s rows by its actuation wrench ``ζ`` (reciprocal to its passive
joint twists) and by its constraint wrenches ``W`` removes the passive increments and
leaves seed 003's system, completed by the constraint error:
``A Δ t = B Δq_a − ζᵀ Δ e`` and ``W Δ t = −W Δ e`` (the ``[A; C]`` system); solving the
full system by least squares is the same Newton step, with the leg increments as a
by-product.

"Motion by inertia": when the type II closeness index falls below ``inertia_tol`` the
platform keeps moving along the last twist (legs re-solved, actuated coordinates left
free) until the index rises above it again; the remaining increments are then re-aimed
at the target from the reached actuated coordinates.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from itertools import product

import numpy as np
import pinocchio as pin

from . import screws
from .analysis import Analysis
from .assembly import Assembly, as_pose
from .compiling import prefer_compiled
from .errors import (
    AssemblyError,
    ForwardKinematicsError,
    InputError,
    PkmError,
    SingularityError,
)
from .modes import AssemblyModes, assembly_modes
from .solve import (
    ACTUATED,
    LEGS,
    PLATFORM,
    POSE_COORDINATES,
    ClosureSolution,
    CoordinateSystem,
    closure_error,
    coordinate_errors,
    pose_coordinates,
    solve_closure,
    solve_coordinates,
    solve_from,
    solve_kernel,
    solve_leg,
    start_configurations,
)
from .tolerances import (
    CLOSURE_TOL,
    COMPILED_CONTINUATION_STEP,
    CONTINUATION_MIN_STEP,
    CONTINUATION_STEP,
    CONTINUATION_TOL,
    COORDINATE_INDEPENDENCE_RTOL,
    FK_ACCEPT_FLOOR,
    INERTIA_TOL,
    JOINT_LIMIT_SLACK,
    LINES_SINGULAR_TOL,
    POSE_PROJECTION_TOL,
    SAME_ACTUATED_ATOL,
    SAME_CONFIGURATION_TOL,
    TARGET_LIMIT_SLACK,
)
from .twists import verified_twists

#: Largest increment of one continuation step (alias of
#: :data:`pkm_pin.tolerances.CONTINUATION_STEP`): fraction of the characteristic length
#: for prismatic coordinates, radians for revolute ones.
STEP = CONTINUATION_STEP
#: Largest step of the compiled predictor–corrector (alias of
#: :data:`pkm_pin.tolerances.COMPILED_CONTINUATION_STEP`, same units as :data:`STEP`).
COMPILED_STEP = COMPILED_CONTINUATION_STEP
# CONTINUATION_TOL and INERTIA_TOL are imported from pkm_pin.tolerances under their names.


# ============================================================ seed 003: one screw step
def screw_step(lines, dl) -> np.ndarray:
    """Small platform twist from seed 003's system ``E_i ∘ Φ = dl_i``.

    Args:
        lines: (6, 6) axis-first Plücker coordinates of the leg lines ``E_i = (e_i;
            b_i × e_i)`` (rows).
        dl: (6,) leg-length increments [m].

    Returns:
        ``Φ = (ω; v_O)`` axis-first about the world origin: small rotation [rad] and
        displacement of the body point at the origin [m].

    Raises:
        InputError: wrong shapes or non-finite values.
        SingularityError: the six lines are linearly dependent.
    """
    E = screws.as_screws(lines, "lines")
    d = np.asarray(dl, dtype=float)
    if E.shape != (6, 6):
        raise InputError(f"lines must be 6×6 (six Plücker rows), got shape {E.shape}")
    if d.shape != (6,) or not np.all(np.isfinite(d)):
        raise InputError(f"dl must be 6 finite numbers, got {d!r}")
    M = E @ screws.DELTA
    sv = np.linalg.svd(M, compute_uv=False)
    if sv[-1] <= LINES_SINGULAR_TOL * sv[0]:
        raise SingularityError(
            f"the six leg lines are linearly dependent (singular values {sv})", "forward",
            float(sv[-1] / sv[0]))
    return np.linalg.solve(M, d)


# ======================================================================= helpers
def _actuated_scales(mech) -> np.ndarray:
    """A copy of :attr:`Mechanism.actuated_scales`: the unit of each actuated
    coordinate (the characteristic length for a prismatic joint, 1 rad for a revolute
    one)."""
    return mech.actuated_scales.copy()


def _progress(mech, q_start: np.ndarray, q_now: np.ndarray, target: np.ndarray) -> float:
    """How far the actuated coordinates got from ``q_start`` to ``target``: ``λ = 1 −
    |target − q_now| / |target − q_start|`` (largest scaled component; 1 at the target,
    0 at the start, negative when it moved away)."""
    scales = _actuated_scales(mech)
    total = float(np.max(np.abs(target - q_start) / scales, initial=0.0))
    if total == 0.0:
        return 1.0
    return 1.0 - float(np.max(np.abs(target - q_now) / scales, initial=0.0)) / total


def _stopped(message: str, reached, lam: float) -> ForwardKinematicsError:
    """A :class:`ForwardKinematicsError` whose ``lam`` attribute is the fraction of the
    way from the start to the target that was reached (:func:`_progress`)."""
    err = ForwardKinematicsError(message, reached)
    err.lam = lam
    return err


def _inertia_needed(inertia_tol: float, step: float, full_step: float) -> float:
    """The type II index below which a continuation step of scaled size ``step`` is not
    trusted: ``inertia_tol`` for a full step (``full_step``: :data:`STEP` or
    :data:`COMPILED_STEP`), proportionally less for a shorter one (the platform moves
    by about step / index, so a small step tolerates a small index)."""
    return inertia_tol * min(1.0, step / full_step)


# ========================================================================= Newton
def _q_actuated_of(mech, leg_q) -> np.ndarray:
    """The actuated coordinates of leg configurations ``leg_q`` (mechanism order)."""
    return np.concatenate([q[leg.actuated_q] for leg, q in zip(mech.legs, leg_q)])


def _assembly_of(mech, state: ClosureSolution) -> Assembly:
    """The assembly of a Newton state (leg configurations copied), with its joint
    twists from one Pinocchio pass: a continuation state closes only to
    :data:`CONTINUATION_TOL`, which the analysis of a hand-made assembly would refuse."""
    leg_q = [q.copy() for q in state.leg_q]
    J, _, worst = verified_twists(mech, leg_q, state.pose.homogeneous)
    return Assembly(mech, state.pose, leg_q, worst, joint_twists=J)


# ================================================================ forward problem
def forward_kinematics(mech, q_actuated, guess=None, *, steps: int | None = None,
                       tol: float = CLOSURE_TOL, inertia_tol: float = INERTIA_TOL,
                       max_newton: int = 50, max_inertia: int = 200,
                       method: str = "auto", starts: int | None = None,
                       seed: int = 0) -> Assembly:
    """Platform pose (an :class:`~pkm_pin.assembly.Assembly`) for the actuated
    coordinates ``q_actuated``, by continuation from ``guess``.

    Two continuations share the same predictor (seed 003's ``A Δ t = B Δq``, which
    is the first Newton step of the closure system from an assembled state):

    * ``method="euler"``: seed 003's algorithm as printed: Euler steps whose legs
      are re-closed at the predicted pose, "motion by inertia" near type II
      singularities, then Newton's method on all closures and actuated coordinates.
      ``info["continuation_error"]`` is the Euler polyline's error.
    * ``method="compiled"``: the same homotopy as a predictor–corrector in compiled
      code (:mod:`pkm_pin.kernels`): each step is corrected by Newton's method on
      the whole closure system to its intermediate actuated coordinates and is
      accepted only in Newton's contracting regime (each correction at most half the
      previous, so no jump to another assembly mode); steps are halved otherwise.
      It stops (``ForwardKinematicsError``) where the closeness of the 6×6 Schur
      complement of the system falls below ``inertia_tol`` (a type II or constraint
      singularity ahead). The result is checked by Pinocchio like the other's.
    * ``method="auto"`` (default): ``"compiled"`` when every leg has a kernel,
      ``"euler"`` (with motion by inertia) where it stops or fails.

    Args:
        mech: The :class:`~pkm_pin.mechanism.Mechanism`.
        q_actuated: Target actuated coordinates (see :attr:`Mechanism.actuated_names`).
        guess: The :class:`Assembly` to start from (default: home), or a pose that
            assembles; its assembly mode is followed.
        steps: Number of continuation steps (default: each step moves every actuated
            coordinate by at most :data:`STEP` of the characteristic length or
            :data:`STEP` rad). Steps that fail to re-assemble are halved.
        tol: Final tolerance on ``|q_a − target|`` (relative to the characteristic
            length for prismatic coordinates, radians otherwise) and on the closure.
        inertia_tol: Type II closeness index below which the platform moves "by
            inertia" along the last twist.
        max_newton: Newton iterations of the final correction.
        max_inertia: Inertia moves allowed in a row.
        starts, seed: As a general-backend mechanism takes them: with ``starts``, a
            target the continuation does not reach is solved from ``starts`` random
            starts too (:meth:`pkm_pin.linkage.Linkage.forward_kinematics` on the tree,
            ``mech.general``, from ``guess``'s branch) and the result read per leg
            (:meth:`Mechanism.legs_assembly`); the continuation's error is raised when
            that fails as well. ``None`` (default): the continuation alone.

    Returns:
        The assembly; its ``info`` holds ``steps`` (accepted continuation steps),
        ``halvings``, ``newton_iterations``, ``residual`` (final scaled actuated
        error), ``continuation_error`` (largest scaled actuated error after the
        continuation, before Newton: the Euler polyline's error), ``inertia``
        (whether motion by inertia was used), ``inertia_steps``, and ``method``
        ("compiled" or "euler").

    Raises:
        InputError: wrong length or non-finite values, a bad guess.
        ForwardKinematicsError: the continuation or the Newton correction failed
            (target out of reach, joint limits, singularity); ``reached`` holds the
            last assembly reached.
    """
    target = mech.check_actuated(q_actuated)
    if steps is not None and (not isinstance(steps, (int, np.integer)) or steps < 1):
        raise InputError(f"steps must be a positive integer, got {steps!r}")
    start = mech.assembly_at(guess)
    try:
        return _continued(mech, target, start, steps, tol, inertia_tol, max_newton,
                          max_inertia, method)
    except (ForwardKinematicsError, AssemblyError):
        if starts is None:
            raise
        found = _tree_multistart(mech, target, start, starts, seed, tol)
        if found is None:
            raise
        return found


def _tree_multistart(mech, target: np.ndarray, start: Assembly, starts: int, seed: int,
                     tol: float) -> Assembly | None:
    """:func:`forward_kinematics` by the tree's multistart (``mech.general``, the actuated
    values in its order, from ``start``'s tree configuration), read per leg; ``None``
    when it fails too."""
    general = mech.general
    values = np.empty(len(target))
    values[[list(general.actuated).index(name) for name in mech.actuated]] = target
    try:
        found = general.forward_kinematics(values, mech.tree_configuration(start),
                                           starts=starts, seed=seed, tol=tol)
    except PkmError:
        return None
    return mech.legs_assembly(found.q)


def _continued(mech, target: np.ndarray, start: Assembly, steps, tol: float,
               inertia_tol: float, max_newton: int, max_inertia: int, method: str) -> Assembly:
    """:func:`forward_kinematics` by continuation from the assembly ``start``."""
    _check_limits(mech, target)
    if method not in ("auto", "compiled", "euler"):
        raise InputError(f"method must be 'auto', 'compiled' or 'euler', got {method!r}")
    if method != "euler":
        kernel = mech.kernel if method == "auto" else _require_kernel(mech)
        if kernel is not None:
            try:
                return _forward_compiled(mech, kernel, target, start, steps, tol,
                                         inertia_tol, max_newton)
            except ForwardKinematicsError:
                if method == "compiled":
                    raise

    return euler_continuation(mech, start, target, steps, tol=tol, inertia_tol=inertia_tol,
                              max_newton=max_newton, max_inertia=max_inertia)


@dataclass
class _Euler:
    """Where seed 003's continuation stands: the assembly reached (``state``), the path
    parameter ``lam`` from the actuated coordinates ``q0`` to the target, the step ``h``
    (a fraction of the path), the counters reported in ``info`` and the remaining budget
    of steps, halvings and inertia moves."""

    state: ClosureSolution
    q0: np.ndarray
    n_total: int
    h: float
    budget: int
    lam: float = 0.0
    accepted: int = 0
    halvings: int = 0
    inertia_steps: int = 0
    last_twist: np.ndarray | None = None
    start: np.ndarray | None = None  #: actuated coordinates of the start assembly
    target: np.ndarray | None = None

    def aim(self, q0: np.ndarray, n_total: int) -> None:
        """Start a new path from ``q0`` in ``n_total`` steps."""
        self.q0, self.n_total, self.lam, self.h = q0, n_total, 0.0, 1.0 / n_total


def _steps_to(mech, q0: np.ndarray, target: np.ndarray) -> int:
    """Continuation steps moving each actuated coordinate by at most :data:`STEP`."""
    scales = _actuated_scales(mech)
    return max(1, math.ceil(float(np.max(np.abs(target - q0) / scales)) / STEP))


def euler_continuation(mech, start: Assembly, target: np.ndarray, steps: int | None = None,
                       *, tol: float = CLOSURE_TOL, inertia_tol: float = INERTIA_TOL,
                       max_newton: int = 50, max_inertia: int = 200) -> Assembly:
    """Seed 003's forward kinematics as printed (``method="euler"`` of
    :func:`forward_kinematics`, which documents the arguments): Euler steps of
    ``A Δ t = B Δq`` whose legs are re-closed at the predicted pose, "motion by inertia"
    where the type II index falls below ``inertia_tol``, then Newton's method on every
    closure and the actuated coordinates (:func:`pkm_pin.solve.solve_closure`)."""
    n_total = _steps_to(mech, start.q_actuated, target) if steps is None else steps
    run = _Euler(ClosureSolution(start.pose, [q.copy() for q in start.leg_q], np.empty(0),
                                 start.residual, np.inf, 0),
                 start.q_actuated, n_total, 1.0 / n_total, 20 * n_total + 200)
    run.start, run.target = start.q_actuated.copy(), target
    while run.lam < 1.0 - 1e-15:
        run.budget -= 1
        if run.budget < 0:
            lam = _progress(mech, run.start, _q_actuated_of(mech, run.state.leg_q), target)
            raise _stopped(
                f"continuation stopped at λ = {lam:.4g} of the way to the target: out of "
                f"its step budget after {run.accepted} steps, {run.halvings} halvings and "
                f"{run.inertia_steps} inertia moves", _assembly_of(mech, run.state), lam)
        an = Analysis(_assembly_of(mech, run.state))
        # seed 003: below eps the platform moves by inertia along its last twist; a
        # start below eps has none, and its first steps are Euler steps halved as needed
        if an.indices["type_II"] < inertia_tol and run.last_twist is not None:
            _move_by_inertia(mech, run, an, inertia_tol, max_inertia)
            run.aim(_q_actuated_of(mech, run.state.leg_q),
                    _steps_to(mech, _q_actuated_of(mech, run.state.leg_q), target))
            continue
        _euler_step(mech, run, an, target)
    return _final_newton(mech, run, target, tol, max_newton)


def _euler_step(mech, run: _Euler, an: Analysis, target: np.ndarray) -> None:
    """One Euler step of the continuation from ``run.state`` (analysed in ``an``):
    accepted (and the next step doubled, up to the planned size) or halved."""
    lam_new = min(1.0, run.lam + run.h)
    q_step = run.q0 + lam_new * (target - run.q0)
    try:
        t = an.forward_velocity((lam_new - run.lam) * (target - run.q0))
    except SingularityError as e:  # pragma: no cover - guarded by inertia_tol
        raise ForwardKinematicsError(str(e), an.assembly) from e
    pose = screws.exp(t) * run.state.pose
    legs = _predict_legs(mech, run.state.leg_q, t, an)
    new = solve_closure(mech, pose, legs, LEGS, tol=CONTINUATION_TOL, max_iter=10)
    if new.closure > CONTINUATION_TOL:
        # off the constraint manifold (curved motion): project back, aiming at q_step
        new = solve_closure(mech, pose, legs, ACTUATED, q_step, tol=CONTINUATION_TOL,
                            max_iter=10)
    if new.closure > CONTINUATION_TOL or not _in_limits(mech, new.leg_q):
        if run.h < CONTINUATION_MIN_STEP:
            lam = _progress(mech, run.start, _q_actuated_of(mech, run.state.leg_q), target)
            why = ("a joint limit" if new.closure <= CONTINUATION_TOL else
                   f"the legs do not re-assemble at the predicted pose: closure error "
                   f"{new.closure:.3g}, type II index {an.indices['type_II']:.3g}")
            raise _stopped(
                f"continuation stalled at λ = {lam:.4g} of the way to the target ({why}); "
                "the target may be out of reach", _assembly_of(mech, run.state), lam)
        run.h *= 0.5
        run.halvings += 1
        return
    run.h = min(2 * run.h, 1.0 / run.n_total)
    run.state, run.last_twist, run.lam = new, t, lam_new
    run.accepted += 1


def _move_by_inertia(mech, run: _Euler, an: Analysis, inertia_tol: float,
                     max_inertia: int) -> None:
    """Seed 003's motion by inertia: the platform keeps moving along the last twist
    (legs re-closed, actuated coordinates free) until the type II index rises above
    ``inertia_tol``; a move that does not re-assemble is halved."""
    L = mech.characteristic_length
    size = max(float(np.linalg.norm(run.last_twist[:3])),
               float(np.linalg.norm(run.last_twist[3:])) / L)
    twist = run.last_twist * (STEP / size)  # inertia moves of bounded size
    index, moves = an.indices["type_II"], 0
    while index < inertia_tol:
        if moves >= max_inertia or run.budget < 0:
            lam = _progress(mech, run.start, _q_actuated_of(mech, run.state.leg_q), run.target)
            raise _stopped(
                f"continuation stopped at λ = {lam:.4g} of the way to the target: motion by "
                f"inertia did not leave the type II singularity after {moves} moves (index "
                f"{index:.3g})", _assembly_of(mech, run.state), lam)
        pose = screws.exp(twist) * run.state.pose
        legs = _predict_legs(mech, run.state.leg_q, twist)
        new = solve_closure(mech, pose, legs, LEGS, tol=CONTINUATION_TOL, max_iter=10)
        if new.closure > CONTINUATION_TOL:
            new = solve_closure(mech, pose, legs, PLATFORM, tol=CONTINUATION_TOL,
                                max_iter=10)
        run.budget -= 1
        if new.closure > CONTINUATION_TOL:
            twist = 0.5 * twist  # a shorter inertia move
            if np.linalg.norm(twist[:3]) + np.linalg.norm(twist[3:]) / L \
                    < CONTINUATION_MIN_STEP * STEP:
                lam = _progress(mech, run.start, _q_actuated_of(mech, run.state.leg_q),
                                run.target)
                raise _stopped(
                    f"continuation stopped at λ = {lam:.4g} of the way to the target: motion "
                    "by inertia left the workspace (the legs no longer assemble: closure "
                    f"error {new.closure:.3g})", _assembly_of(mech, run.state), lam)
            continue
        run.state = new
        moves += 1
        index = Analysis(_assembly_of(mech, run.state)).indices["type_II"]
    run.last_twist = twist
    run.inertia_steps += moves


def _final_newton(mech, run: _Euler, target: np.ndarray, tol: float,
                  max_newton: int) -> Assembly:
    """The final Newton correction on every closure and the actuated coordinates, the
    result assembled and checked against the target and the limits."""
    scales = _actuated_scales(mech)
    qa = _q_actuated_of(mech, run.state.leg_q)
    cont_err = float(np.max(np.abs(qa - target) / scales))
    final = solve_closure(mech, run.state.pose, run.state.leg_q, ACTUATED, target, tol=tol,
                          max_iter=max_newton)
    if final.closure > max(tol, FK_ACCEPT_FLOOR) or final.actuated > tol:
        lam = _progress(mech, run.start, qa, target)
        raise _stopped(
            f"the continuation reached λ = {lam:.4g} of the way to the target, then Newton's "
            f"correction did not converge after {final.iterations} iterations: actuated "
            f"error {final.actuated:.3g}, closure error {final.closure:.3g} (tol {tol:g}); "
            "the target may be out of reach or singular", _assembly_of(mech, final), lam)
    try:
        result = mech.assemble(final.pose, final.leg_q, tol=max(tol, CLOSURE_TOL))
    except AssemblyError as e:
        raise ForwardKinematicsError(f"the final pose does not assemble: {e}",
                                     _assembly_of(mech, final)) from e
    err = float(np.max(np.abs(result.q_actuated - target) / scales))
    if err > max(tol, FK_ACCEPT_FLOOR) or not _in_limits(mech, result.leg_q):
        raise ForwardKinematicsError(
            f"the final assembly misses the target by {err:.3g} (joint limits?)", result)
    result.info.update(steps=run.accepted, halvings=run.halvings,
                       newton_iterations=final.iterations, residual=err,
                       continuation_error=cont_err, inertia=run.inertia_steps > 0,
                       inertia_steps=run.inertia_steps, requested_steps=run.n_total,
                       method="euler")
    return result


# ========================================================== compiled continuation
def _require_kernel(mech):
    """The mechanism's compiled kinematics, or an :class:`InputError` saying why there
    are none."""
    kernel = mech.kernel
    if kernel is None:
        raise InputError(
            f"{mech.name}: a leg has a joint the compiled kinematics do not represent "
            "(continuous, multi-DOF or helical joints); use method='euler'")
    return kernel


def _forward_compiled(mech, kernel, target, start, steps, tol, inertia_tol,
                      max_newton) -> Assembly:
    """Predictor–corrector continuation in compiled code (see
    :func:`forward_kinematics`) with the mechanism's ``kernel``; without ``steps`` the
    whole way is tried first in one step (damped Newton from the start, kept when it
    converges in Newton's contracting regime)."""
    scales = kernel.scales
    pose = start.pose.homogeneous.copy()
    Q = np.concatenate(start.leg_q).astype(float)
    q0 = Q[kernel.actuated].copy()
    span = float(np.max(np.abs(target - q0) / scales, initial=0.0))
    final_tol = 0.1 * min(tol, CLOSURE_TOL)
    if steps is None:
        P, Qn = pose.copy(), Q.copy()
        # contraction judged down to the continuation tolerance (below it round-off
        # steps need not halve), then polished
        _, out = solve_kernel(kernel, ACTUATED, P, Qn, target, tol=CONTINUATION_TOL,
                              max_iter=max_newton)
        if out[0] <= CONTINUATION_TOL and out[1] <= CONTINUATION_TOL and out[4] == 1:
            n_iter = int(out[2])
            _, out = solve_kernel(kernel, ACTUATED, P, Qn, target, tol=final_tol,
                                  max_iter=max_newton)
            try:
                return _compiled_result(mech, kernel, target, P, Qn, tol, dict(
                    steps=1, halvings=0, newton_iterations=n_iter + int(out[2]),
                    continuation_error=0.0, requested_steps=1, direct_newton=True))
            except ForwardKinematicsError:
                pass  # a joint limit: continue instead
        steps = max(1, math.ceil(span / COMPILED_STEP))
    lam, h = 0.0, 1.0 / steps
    accepted = halvings = iterations = 0
    closeness = np.inf
    while lam < 1.0 - 1e-15:
        lam_new = min(1.0, lam + h)
        P, Qn = pose.copy(), Q.copy()
        _, out = solve_kernel(kernel, ACTUATED, P, Qn, q0 + lam_new * (target - q0),
                              tol=CONTINUATION_TOL, max_iter=10)
        iterations += int(out[2])
        ok = out[0] <= CONTINUATION_TOL and out[1] <= CONTINUATION_TOL and out[4] == 1
        if ok:
            closeness = math.sqrt(out[3])
        if not ok or closeness < _inertia_needed(inertia_tol, (lam_new - lam) * span,
                                                 COMPILED_STEP):
            if h < CONTINUATION_MIN_STEP:
                why = (f"near a singularity: Schur closeness {closeness:.3g}" if ok else
                       "Newton's corrections do not contract (a singularity, a joint limit "
                       "or the edge of the workspace ahead)")
                raise _stopped(f"compiled continuation stopped at λ = {lam:.4g} of the way "
                               f"to the target ({why})", _state_of(mech, kernel, pose, Q), lam)
            h *= 0.5
            halvings += 1
            continue
        pose, Q, lam = P, Qn, lam_new
        h = min(2 * h, 1.0 / steps)
        accepted += 1
    cont_err = float(np.max(np.abs(Q[kernel.actuated] - target) / scales, initial=0.0))
    _, out = solve_kernel(kernel, ACTUATED, pose, Q, target, tol=final_tol, max_iter=max_newton)
    iterations += int(out[2])
    return _compiled_result(mech, kernel, target, pose, Q, tol, dict(
        steps=accepted, halvings=halvings, newton_iterations=iterations,
        continuation_error=cont_err, requested_steps=steps, direct_newton=False))


def _compiled_result(mech, kernel, target, pose, Q, tol, info) -> Assembly:
    """The assembly reached by the compiled solver, checked by Pinocchio against the
    target and the limits (a :class:`ForwardKinematicsError` otherwise)."""
    final = _state_of(mech, kernel, pose, Q)
    err = float(np.max(np.abs(final.q_actuated - target) / kernel.scales, initial=0.0))
    inside = bool(np.all(Q >= kernel.lower - JOINT_LIMIT_SLACK)
                  and np.all(Q <= kernel.upper + JOINT_LIMIT_SLACK))
    if final.residual > max(tol, CLOSURE_TOL) or err > max(tol, FK_ACCEPT_FLOOR) or not inside:
        raise _stopped(
            f"the continuation reached the target, but Newton's correction did not converge "
            f"there: actuated error {err:.3g}, closure error {final.residual:.3g} (tol "
            f"{tol:g}){'' if inside else ', outside the joint limits'}", final, 1.0)
    final.info.update(residual=err, inertia=False, inertia_steps=0, method="compiled", **info)
    return final


def _state_of(mech, kernel, pose: np.ndarray, Q: np.ndarray) -> Assembly:
    """Assembly at a 4×4 pose and the legs' configurations concatenated as in
    ``kernel``; its residual is the largest closure error (:func:`pkm_pin.solve.closure_error`)
    evaluated by one Pinocchio pass per leg, whose joint twists it keeps."""
    offs = kernel.coords
    leg_q = [Q[offs[i]:offs[i + 1]].copy() for i in range(len(mech.legs))]
    J, _, worst = verified_twists(mech, leg_q, pose)
    return Assembly(mech, pin.SE3(pose), leg_q, worst, joint_twists=J)


def _predict_legs(mech, leg_q, t, an=None) -> list:
    """Leg configurations moved by the joint rates of the platform twist ``t``."""
    out = []
    for k, (leg, q) in enumerate(zip(mech.legs, leg_q)):
        J = an.legs[k].jacobian if an is not None else leg.jacobian(q)
        dq, *_ = np.linalg.lstsq(J, t, rcond=1e-10)
        out.append(leg.clip(pin.integrate(leg.model, q, dq)))
    return out


def _in_limits(mech, leg_q) -> bool:
    """Whether every leg configuration respects its joint limits."""
    return all(leg.within_limits(q) for leg, q in zip(mech.legs, leg_q))


def _check_limits(mech, target: np.ndarray) -> None:
    """A :class:`ForwardKinematicsError` if a target actuated coordinate lies outside
    its joint limits."""
    k = 0
    names = mech.actuated_names
    for leg in mech.legs:
        lo, up = leg._bounds
        for iq in np.atleast_1d(leg.actuated_q):
            if not (lo[iq] - TARGET_LIMIT_SLACK <= target[k] <= up[iq] + TARGET_LIMIT_SLACK):
                raise ForwardKinematicsError(
                    f"{names[k]} = {target[k]:.6g} is outside its joint limits "
                    f"[{lo[iq]:.6g}, {up[iq]:.6g}]: unreachable")
            k += 1


# ================================================================= assembly modes
def forward_kinematics_all(mech, q_actuated, *, starts: int = 32, seed: int = 0,
                           tol: float = CLOSURE_TOL, max_iter: int = 100,
                           method: str = "auto") -> AssemblyModes:
    """Every assembly mode for ``q_actuated`` (:func:`pkm_pin.modes.assembly_modes`).

    Mechanisms whose six legs are distance constraints (6-SPS, 6-UPS) are solved by
    polynomial homotopy in Study parameters (all real postures, ``complete=True`` when
    every path was tracked to its end); every other mechanism by a multistart of the
    closure solver that stops after :data:`~pkm_pin.tolerances.MODES_PATIENCE` batches
    of ``starts`` starts find nothing new (``complete=False``).

    Args:
        mech: The :class:`~pkm_pin.mechanism.Mechanism`.
        q_actuated: Target actuated coordinates.
        starts: Starts per batch of the multistart.
        seed: Seed of the random starts (and of the homotopy).
        tol: Closure and scaled actuated tolerance of each mode.
        max_iter: Newton iterations of one start.
        method: ``"auto"``, ``"homotopy"`` or ``"multistart"`` (the continuation
            methods ``"compiled"`` and ``"euler"`` of earlier versions mean ``"auto"``).

    Returns:
        An :class:`~pkm_pin.modes.AssemblyModes`: a list of assemblies, each valid
        (closure, actuated coordinates, joint limits), sorted by their distance from
        the home pose, with ``complete``, ``method`` and ``counts``.

    Raises:
        ForwardKinematicsError: no assembly mode (the target is unreachable).
    """
    if method in ("compiled", "euler"):
        method = "auto"
    if not isinstance(starts, (int, np.integer)) or starts < 0:
        raise InputError(f"starts must be a non-negative integer, got {starts!r}")
    return assembly_modes(mech, q_actuated, starts=max(int(starts), 1), seed=seed, tol=tol,
                          max_iter=max_iter, method=method)


# ================================================================ inverse problem
def inverse_kinematics(mech, pose, guess=None) -> Assembly:
    """The assembly at ``pose`` (legs on the working mode of ``guess``, default home):
    ``mech.assemble(pose, guess)``, whose ``q_actuated`` are the actuated coordinates (an
    :class:`Assembly`, as every backend's inverse kinematics gives). ``pose`` may be partial (a
    mapping of independent coordinates, :func:`complete_pose`), and a full pose off a
    lower-mobility mechanism's motion by at most
    :data:`~pkm_pin.tolerances.POSE_PROJECTION_TOL` is projected onto it.

    Raises:
        InputError: a malformed pose.
        AssemblyError: a leg cannot reach the pose within its limits.
        DependentCoordinates, ForwardKinematicsError: a partial pose that is not made of
            independent coordinates, or cannot be completed.
    """
    return mech.assemble(pose, guess)


def inverse_kinematics_all(mech, pose, *, starts: int = 16, seed: int = 0,
                           max_modes: int = 4096) -> list[Assembly]:
    """Every working mode at ``pose``: the distinct actuated-coordinate vectors.

    Each leg is solved (:func:`pkm_pin.solve.solve_leg`) from every start of the
    restart recipe :func:`pkm_pin.solve.start_configurations` (its home configuration,
    neutral, the middle of the limits and ``starts`` random configurations drawn with
    ``seed``); converged solutions inside the limits are deduplicated (revolute
    differences taken modulo 2π) and combined across the legs.

    Returns:
        A list of :class:`Assembly` (``.q_actuated`` gives the vector), one per
        distinct actuated-coordinate vector; the home working mode first when it
        reaches ``pose``.

    Raises:
        AssemblyError: some leg reaches the pose in no configuration.
    """
    pose = complete(mech, pose).pose if isinstance(pose, Mapping) else as_pose(pose)
    per_leg = []
    home_q = mech.leg_starts(None)
    compiled = mech.kernel is not None and prefer_compiled(solve_from)
    for leg, anchor, qh in zip(mech.legs, mech.anchors, home_q):
        want = pose * anchor
        sols, worst = [], np.inf
        for q0 in start_configurations(leg, qh, starts, seed):
            sol = solve_leg(leg, want, q0, compiled=compiled)
            worst = min(worst, sol.residual)
            if not sol.converged or not leg.within_limits(sol.q):
                continue
            if not any(_same_q(leg, sol.q, s) for s, _ in sols):
                sols.append((sol.q, sol.residual))
        if not sols:
            raise AssemblyError(leg.name, worst)
        per_leg.append(sols)
    out, seen = [], []
    for combo in product(*per_leg):
        if len(out) >= max_modes:
            break
        leg_q = [q for q, _ in combo]
        a = Assembly(mech, pose, leg_q, max(r for _, r in combo))
        qa = a.q_actuated
        if any(np.allclose(qa, s, atol=SAME_ACTUATED_ATOL, rtol=0) for s in seen):
            continue
        seen.append(qa)
        out.append(a)
    return out


def _same_q(leg, a, b, tol: float = SAME_CONFIGURATION_TOL) -> bool:
    """Whether two configurations of ``leg`` are the same working mode."""
    d = pin.difference(leg.model, a, b)
    # revolute joints: compare modulo 2π
    d = np.where(np.abs(d) > np.pi, (d + np.pi) % (2 * np.pi) - np.pi, d)
    return bool(np.max(np.abs(d)) < tol * max(1.0, leg.characteristic_length))


# ====================================================== serial chain: iterative IK
@dataclass
class IterativeIKResult:
    """Result of :func:`iterative_ik`.

    Attributes:
        q: Final joint configuration (after the Newton correction).
        q_steps: Configuration after the steps, before the correction.
        angle: Rotation angle [rad] from the start to the target tip orientation.
        axis: Its unit axis (world); zeros when the angle is 0.
        translation: Tip translation from start to target (world) [m].
        steps: Number of steps.
        error_after_steps: (position error [m], orientation error [rad]) after the steps.
        error_after_correction: The same after the Newton correction.
        converged: Whether the correction reached ``tol``.
        path: Joint configurations after each step (start included).
    """

    q: np.ndarray
    q_steps: np.ndarray
    angle: float
    axis: np.ndarray
    translation: np.ndarray
    steps: int
    error_after_steps: tuple
    error_after_correction: tuple
    converged: bool
    path: list = field(default_factory=list)


def _axis_angle(R: np.ndarray) -> tuple[np.ndarray, float]:
    """Unit axis and angle of a rotation matrix from its quaternion (pin.Quaternion)."""
    quat = pin.Quaternion(R)
    quat.normalize()
    v = np.array([quat.x, quat.y, quat.z])
    w = quat.w
    if w < 0:
        v, w = -v, -w
    s = float(np.linalg.norm(v))
    angle = 2.0 * math.atan2(s, w)
    return (v / s if s > 0 else np.zeros(3)), angle


def _tip_error(tip: pin.SE3, target: pin.SE3) -> tuple[float, float]:
    axis, angle = _axis_angle(target.rotation @ tip.rotation.T)
    return float(np.linalg.norm(target.translation - tip.translation)), float(angle)


def iterative_ik(leg, target, q0, *, max_angle_step: float, max_translation_step: float,
                 tol: float = 1e-10, reaim: bool = False, max_iter: int = 100,
                 rcond: float = 1e-6) -> IterativeIKResult:
    """Seed 003's iterative inverse position problem of a serial chain.

    The translation ``r`` of the tip point and the rotation (unit axis ``L``, angle
    ``Ψ``, from the quaternion of ``R_target R_startᵀ``) are split into ``N`` equal
    steps, ``N`` the smallest number keeping every step within ``max_angle_step`` and
    ``max_translation_step``. At each step the joint increments solve the inverse
    velocity problem ``J Δq = (Ψ/N L; r/N + p × Ψ/N L)`` (twist about the world origin,
    ``p`` the tip point) in the least-squares sense (near a singular position: the
    admissible twist closest to the wanted one). With ``reaim`` the remaining
    translation and rotation are recomputed from the reached pose before each step
    (removing the accumulated drift); without it (the paper's worked example) the
    steps follow the first plan and the drift is left to the final Newton correction
    (:meth:`Leg.solve` warm-started from the reached configuration).

    Args:
        leg: The chain (:class:`~pkm_pin.Leg`).
        target: Target tip placement (``pin.SE3``, 4×4 or 6 numbers) in the world.
        q0: Start configuration.
        max_angle_step: Largest rotation per step [rad].
        max_translation_step: Largest tip translation per step [m].
        tol: Relative tolerance of the final correction.
        reaim: Re-aim at the target at every step.

    Raises:
        InputError: bad arguments.
    """
    target = as_pose(target)
    q = leg.check_q(q0, "q0").copy()
    for name, v in (("max_angle_step", max_angle_step),
                    ("max_translation_step", max_translation_step)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise InputError(f"{name} must be a positive number, got {v!r}")
    start = leg.tip_placement(q)
    r = target.translation - start.translation
    axis, angle = _axis_angle(target.rotation @ start.rotation.T)
    n = max(1, math.ceil(max(np.linalg.norm(r) / max_translation_step,
                             angle / max_angle_step) - 1e-12))
    path = [q.copy()]
    step_r, step_w = r / n, axis * angle / n
    for k in range(n):
        tip, J = leg.kinematics(q)
        if reaim:
            rr = target.translation - tip.translation
            ax, an = _axis_angle(target.rotation @ tip.rotation.T)
            step_r, step_w = rr / (n - k), ax * an / (n - k)
        p = tip.translation
        twist = np.r_[step_w, step_r + np.cross(p, step_w)]
        dq, *_ = np.linalg.lstsq(J, twist, rcond=rcond)
        q = pin.integrate(leg.model, q, dq)
        path.append(q.copy())
    q_steps = q.copy()
    err_steps = _tip_error(leg.tip_placement(q_steps), target)
    sol = leg.solve(target, q_steps, tol=tol, max_iter=max_iter, restarts=0)
    err_final = _tip_error(leg.tip_placement(sol.q), target)
    return IterativeIKResult(sol.q, q_steps, float(angle), axis, r, n, err_steps, err_final,
                             sol.converged, path)


# ==================================================================== partial poses
class DependentCoordinates(InputError):
    """Pose coordinates of a partial pose that are not independent coordinates of the
    mechanism (more than its DOF, or one a function of the others, e.g. a parasitic
    motion of a 3-RPS).

    Attributes:
        given: The coordinates given.
        dof: The mechanism's DOF at the start assembly.
        motion_type: Its motion type there (``"1T2R"``…; ``""`` when unknown).
        independent: A set of independent coordinates (the first found in the order x,
            y, z, roll, pitch, yaw).
    """

    def __init__(self, mechanism: str, given, dof: int, motion_type: str, independent,
                 reason: str):
        self.given, self.dof, self.motion_type = tuple(given), dof, motion_type
        self.independent = tuple(independent)
        kind = f" ({motion_type})" if motion_type else ""
        super().__init__(
            f"{', '.join(self.given)} are not independent coordinates of {mechanism!r}: "
            f"{reason}; it has {dof} DOF{kind} here: give at most {dof} independent "
            f"coordinates, e.g. {', '.join(self.independent) or '(none)'} (the others are "
            "solved for)")


class OffMotionManifold(AssemblyError):
    """A full pose that is not one of a lower-mobility mechanism's: the nearest pose of
    its motion manifold differs from it by more than the projection tolerance.

    Attributes:
        distance: That difference (largest coordinate; x, y, z relative to the
            characteristic length, angles in rad).
    """

    def __init__(self, leg: str, residual: float, distance: float, tol: float):
        self.distance = float(distance)
        super().__init__(leg, residual,
                         f"the nearest pose of the mechanism's motion differs from it by "
                         f"{distance:.3g} in a coordinate (x, y, z relative to the "
                         f"characteristic length, angles in rad), more than the {tol:g} "
                         "accepted; give the mechanism's independent coordinates instead "
                         "(a partial pose, Mechanism.complete_pose)")


def partial_pose(coords) -> dict[str, float]:
    """A partial pose checked: ``{name: value}`` with names among
    :data:`~pkm_pin.solve.POSE_COORDINATES` (x, y, z [m], roll, pitch, yaw [rad]) and
    finite values, in that order.

    Raises:
        InputError: an unknown name or a value that is not a finite number.
    """
    if not isinstance(coords, Mapping):
        raise InputError(f"a partial pose is a mapping of coordinate names to values, got "
                         f"{type(coords).__name__}")
    unknown = [str(k) for k in coords if k not in POSE_COORDINATES]
    if unknown:
        raise InputError(f"unknown pose coordinate(s) {', '.join(map(repr, unknown))}: a "
                         f"partial pose names some of {', '.join(POSE_COORDINATES)}")
    out = {}
    for name in POSE_COORDINATES:
        if name in coords:
            v = coords[name]
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
                    or not math.isfinite(float(v)):
                raise InputError(f"pose coordinate {name} must be a finite number, got {v!r}")
            out[name] = float(v)
    return out


def _start_state(mech, guess) -> tuple[pin.SE3, list]:
    """Pose and leg configurations a completion or projection starts from: an
    :class:`Assembly`, a pose (assembled first), leg configurations (at the home pose),
    or ``None`` (the home assembly once known, else the home pose with ``home_q``)."""
    if isinstance(guess, Assembly):
        guess = mech._per_leg(guess)
        return guess.pose, [q.copy() for q in guess.leg_q]
    if guess is None and "home_assembly" not in mech.__dict__:
        starts = mech.leg_starts(None)
        return mech.home, [leg.neutral() if q is None else q
                           for leg, q in zip(mech.legs, starts)]
    if guess is None:
        return _start_state(mech, mech.home_assembly)
    if isinstance(guess, (pin.SE3, Mapping)) or np.shape(guess) in ((6,), (4, 4)):
        return _start_state(mech, mech.assemble(guess))
    starts = mech.leg_starts(guess)
    return mech.home, [leg.neutral() if q is None else q for leg, q in zip(mech.legs, starts)]


def _rank(G: np.ndarray, rows, top: float) -> int:
    """Numerical rank of the coordinate rates ``G[rows]`` relative to ``top``."""
    if not len(rows) or top <= 0:
        return 0
    s = np.linalg.svd(G[list(rows)], compute_uv=False)
    return int(np.sum(s > COORDINATE_INDEPENDENCE_RTOL * top))


def coordinate_plan(mech, system: CoordinateSystem, given) -> tuple[list[int], list[int], int]:
    """The coordinates a completion fixes, from the motions of ``system``: the
    ``given`` names (checked independent) and, when fewer than the DOF, the first of the
    others in the order x, y, z, roll, pitch, yaw that complete an independent set
    (held at the start's values). Returns ``(given rows, held rows, dof)``.

    Raises:
        DependentCoordinates: naming the mechanism's DOF, motion type and a valid set.
    """
    G = system.C @ system.free
    s = np.linalg.svd(G, compute_uv=False)
    top = float(s[0]) if s.size else 0.0
    everything = list(range(6))
    dof = _rank(G, everything, top)
    rows = [POSE_COORDINATES.index(n) for n in given]

    def greedy(start, candidates):
        chosen = list(start)
        for k in candidates:
            if len(chosen) < dof and _rank(G, chosen + [k], top) == len(chosen) + 1:
                chosen.append(k)
        return chosen

    if _rank(G, rows, top) < len(rows):
        independent = [POSE_COORDINATES[k] for k in greedy([], everything)]
        if len(rows) > dof:
            reason = f"{len(rows)} coordinates for {dof} DOF"
        else:
            kept = []
            for k in rows:
                if _rank(G, kept + [k], top) == len(kept):
                    break
                kept.append(k)
            reason = (f"{POSE_COORDINATES[k]} is a function of "
                      f"{', '.join(POSE_COORDINATES[j] for j in kept)}" if kept else
                      f"{POSE_COORDINATES[k]} does not change to first order (a parasitic "
                      "motion)")
        raise DependentCoordinates(mech.name, given, dof, _motion_type(mech), independent,
                                   reason)
    held = greedy(rows, [k for k in everything if k not in rows])[len(rows):]
    return rows, held, dof


def _motion_type(mech) -> str:
    """The home analysis' motion type, ``""`` when it cannot be computed."""
    try:
        return mech.home_analysis.motion_type
    except PkmError:
        return ""


def complete(mech, coords, guess=None, *, tol: float = CLOSURE_TOL,
             max_iter: int = 50, plan=None) -> Assembly:
    """The assembly at a partial pose (see :func:`complete_pose`), its ``info`` holding
    ``given`` (the coordinates given), ``held`` (coordinates held at the guess's values
    because fewer than the DOF were given), ``dof``, ``iterations`` and ``plan``.

    ``plan``: the ``info["plan"]`` of an earlier completion; when it is for the same
    coordinate names, its choice of coordinates (:func:`coordinate_plan`: which are
    held, the DOF) is kept instead of being made again at the guess (a sweep of partial
    poses makes it once: the rows and the SVD at each guess cost a third of a
    completion). The held coordinates still take the guess's values."""
    given = partial_pose(coords)
    pose0, leg_q0 = _start_state(mech, guess)
    if plan is not None and plan[0] == tuple(given):
        rows, held, dof = list(plan[1]), list(plan[2]), plan[3]
    else:
        system = CoordinateSystem(mech, pose0, leg_q0)
        rows, held, dof = coordinate_plan(mech, system, list(given))
    start_values = pose_coordinates(pose0)
    all_rows = rows + held
    values = np.r_[list(given.values()), start_values[held]]
    sol = _complete_from(mech, pose0, leg_q0, all_rows, values, start_values, tol, max_iter)
    asm = _checked_completion(mech, sol, given, tol)
    asm.info.update(given=dict(given), held={POSE_COORDINATES[k]: float(start_values[k])
                                             for k in held},
                    dof=dof, iterations=sol.iterations,
                    plan=(tuple(given), tuple(rows), tuple(held), dof))
    return asm


def _complete_from(mech, pose0, leg_q0, rows, values, start_values, tol, max_iter):
    """:func:`~pkm_pin.solve.solve_coordinates` from the start; where Newton does not
    converge, the same by continuation (the targets moved from the start's values in 4,
    then 16 steps, each warm-started from the last), unless Newton stopped with a joint
    projected onto its limit: the targets lie beyond that limit, which the continuation,
    moving the same targets on the same branch, meets as well (it never completed such a
    pose on the shipped 3-RPS and 3-PRS workspaces and in the tests, where it cost 60 %
    of the time of a workspace over partial poses: ``benchmarks/bench_workspace.py``)."""
    sol = solve_coordinates(mech, pose0, leg_q0, rows, values, tol=tol, max_iter=max_iter)
    if _completed(sol, tol) or _against_a_limit(mech, sol.leg_q):
        return sol
    first = start_values[rows]
    delta = values - first
    delta[np.asarray(rows) >= 3] = (delta[np.asarray(rows) >= 3] + np.pi) % (2 * np.pi) - np.pi
    for steps in (4, 16):
        pose, leg_q, iterations = pose0, leg_q0, sol.iterations
        for k in range(1, steps + 1):
            last = k == steps
            step = solve_coordinates(mech, pose, leg_q, rows, first + k / steps * delta,
                                     tol=tol if last else CONTINUATION_TOL, max_iter=max_iter)
            iterations += step.iterations
            if not _completed(step, tol if last else CONTINUATION_TOL):
                break
            pose, leg_q = step.pose, step.leg_q
        step.iterations = iterations
        if _completed(step, tol):
            return step
    return sol


def _against_a_limit(mech, leg_q) -> bool:
    """Whether a joint of some leg sits exactly at a bound of its limits (where the
    solver's projection puts a joint that a step would take beyond it)."""
    return any(leg.at_a_limit(q) for leg, q in zip(mech.legs, leg_q))


def _completed(sol, tol: float) -> bool:
    return sol.closure <= tol and sol.coordinates <= max(tol, FK_ACCEPT_FLOOR)


def _checked_completion(mech, sol, given: dict, tol: float) -> Assembly:
    """The assembly of a completion, or a :class:`ForwardKinematicsError` saying why
    it is none."""
    reached = _assembly_of(mech, sol)
    inside = _in_limits(mech, sol.leg_q)
    if _completed(sol, tol) and inside:
        return reached
    text = ", ".join(f"{k}={v:g}" for k, v in given.items())
    raise ForwardKinematicsError(
        f"the partial pose {text} cannot be completed on the motion of {mech.name!r} from "
        f"the guess: closure error {sol.closure:.3g}, largest coordinate error "
        f"{sol.coordinates:.3g} (tol {tol:g}){'' if inside else ', outside the joint limits'}"
        " after Newton's method and a continuation (out of the workspace, a joint limit or "
        "a singularity on the way)", reached)


def complete_pose(mech, guess=None, **coords) -> pin.SE3:
    """The full platform pose on the mechanism's motion manifold at a partial pose.

    ``coords``: some of x, y, z [m], roll, pitch, yaw [rad] (URDF roll-pitch-yaw of the
    platform) that are independent coordinates of the mechanism (a 3-RPS: z, roll,
    pitch; the agile eye: roll, pitch, yaw; the Delta: x, y, z; the planar 3-RPR: x, z,
    pitch); the other coordinates (parasitic motions) are solved for: the closure
    solver with rows fixing the given coordinates
    (:func:`pkm_pin.solve.solve_coordinates`), warm-started from ``guess`` (an
    :class:`Assembly`, a pose, or ``None``: home), so the branch of the guess is kept.
    With fewer coordinates than the DOF, the first of the others (order x, y, z, roll,
    pitch, yaw) that complete an independent set are held at the guess's values.

    Raises:
        InputError: an unknown coordinate name or a value that is not finite.
        DependentCoordinates: the coordinates are not independent for this mechanism
            (the message gives its DOF, motion type and a set that is).
        ForwardKinematicsError: no pose of the manifold has these coordinates near the
            guess (the reason and the state reached).
    """
    return complete(mech, coords, guess).pose


def project_pose(mech, pose, guess=None, *, tol: float = POSE_PROJECTION_TOL,
                 closure_tol: float = CLOSURE_TOL) -> Assembly:
    """The assembly at the pose of the mechanism's motion manifold nearest ``pose`` (in
    x, y, z divided by the characteristic length and roll, pitch, yaw [rad]; Newton from
    ``guess``, default home), when it differs from ``pose`` by at most ``tol``
    (:data:`~pkm_pin.tolerances.POSE_PROJECTION_TOL`) in every coordinate: a 6-D pose
    of a lower-mobility mechanism given at printed precision. ``info["projection"]``:
    that difference.

    Raises:
        AssemblyError: the nearest pose is farther (the pose is not one of the
            mechanism's), or none is found.
    """
    pose = as_pose(pose)
    target = pose_coordinates(pose)
    pose0, leg_q0 = _start_state(mech, guess)
    system = CoordinateSystem(mech, pose0, leg_q0)
    G = system.C @ system.free
    top = float(np.linalg.svd(G, compute_uv=False)[0]) if G.size else 0.0
    if _rank(G, range(6), top) == 6 and system.closure <= closure_tol:
        raise AssemblyError(mech.legs[0].name, np.nan, "a mechanism with 6 DOF has no "
                            "lower-dimensional motion to project a pose onto")
    sol = solve_coordinates(mech, pose0, leg_q0, range(6), target, tol=closure_tol)
    distance = float(np.max(np.abs(coordinate_errors(sol.pose, range(6), target,
                                                     mech.characteristic_length))))
    k = int(np.argmax(sol.residuals)) if len(sol.residuals) else 0
    if not (sol.closure <= closure_tol and _in_limits(mech, sol.leg_q)):
        raise AssemblyError(mech.legs[k].name, sol.residuals[k],
                            "and no pose of the mechanism's motion near it was found")
    if not distance <= tol:
        raise OffMotionManifold(mech.legs[k].name, _leg_residual(mech, pose, k, sol.leg_q[k]),
                                distance, tol)
    asm = _assembly_of(mech, sol)
    asm.info.update(projection=distance, projected_from=target.tolist())
    return asm


def _leg_residual(mech, pose: pin.SE3, k: int, q) -> float:
    """Leg ``k``'s relative closure error at ``q`` against ``pose · anchor_k``."""
    leg = mech.legs[k]
    e = np.empty(6)
    return float(closure_error(leg.tip_placement(q).homogeneous,
                               (pose * mech.anchors[k]).homogeneous,
                               leg.characteristic_length, e))
