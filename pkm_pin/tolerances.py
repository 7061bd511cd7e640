"""Every tolerance and numeric threshold of pkm_pin, in one place.

Each constant says what it is relative to. Unless stated otherwise a tolerance is
dimensionless and unit- and frame-invariant: lengths are divided by a characteristic
length of the mechanism or leg (:attr:`Mechanism.characteristic_length`,
:attr:`Leg.characteristic_length`), moments of screws likewise (the screws are
*homogenised*), prismatic coordinates are counted in characteristic lengths and revolute
ones in radians, and singular values are taken relative to the largest one. The few
absolute slacks (joint limits) say so.

The modules that use them keep their historical names as aliases
(``pkm_pin.screws.RTOL is RANK_RTOL`` …); the table of aliases is at the end of this
module. This module imports nothing from pkm_pin (every module may import it).
"""

from __future__ import annotations

# ================================================================ rank decisions
#: Default relative tolerance of rank decisions on screw systems: singular values of
#: unit-homogenised (moments / characteristic length), row-normalised screws, relative
#: to the largest (``screws.RTOL``).
RANK_RTOL = 1e-9
#: A screw whose homogenised norm is below this fraction of the largest screw of its
#: system is a zero screw (``screws._ZERO_ROW``).
ZERO_SCREW_RTOL = 1e-12
#: Default relative tolerance of :func:`pkm_pin.screws.contains`: the homogenised part of
#: a screw outside the span, relative to the screw's homogenised norm.
SPAN_RTOL = 1e-7
#: Singular values of the ω parts of an orthonormal (homogenised) platform twist basis
#: below this count as zero when counting rotations of the platform twist system.
ROTATION_COUNT_TOL = 1e-7
#: A one-rotation twist system is helical when its rotation's pitch (relative to the
#: characteristic length) is above this and no translation of the system can cancel it
#: (:func:`pkm_pin.screws.motion_type`).
HELICAL_PITCH_RTOL = 1e-7

# ================================================================= singularities
#: Closeness indices (type I, type II, constraint; each a ratio of singular values of
#: homogenised screw matrices) below this are singular (``analysis.SINGULAR_TOL``).
CLOSENESS_SINGULAR_TOL = 1e-7
#: Serial singularity of one chain: the index ``σ_k / σ_1`` of its unit-homogenised
#: Jacobian below this is singular (``serial.SINGULAR_TOL``).
SERIAL_SINGULAR_TOL = 1e-9
#: A link twist whose homogenised size is below this fraction of what the joint rates
#: could produce is zero (link at rest); a twist whose homogenised least-squares residual
#: exceeds this fraction of its size is outside the span of the Jacobian
#: (``serial.TWIST_RTOL``).
LINK_TWIST_RTOL = 1e-9
#: Sensitivity: the smallest singular value of the stacked wrench system (homogenised,
#: rows normalised), relative to the largest, below which the pose error is
#: undetermined (``sensitivity.SINGULAR_TOL``).
SENSITIVITY_SINGULAR_TOL = 1e-9
#: Seed 003's screw step: the six leg lines are dependent when the smallest singular
#: value of their matrix is below this fraction of the largest.
LINES_SINGULAR_TOL = 1e-12
#: Residual of a parameter's stacked sensitivity system relative to the homogenised
#: size of its virtual twist above which the parameter error cannot be absorbed by the
#: rigid (overconstrained) mechanism (``sensitivity.COMPATIBILITY_TOL``; ~1e-15 for
#: compatible errors).
COMPATIBILITY_TOL = 1e-8
#: Calibration: a column of the identification Jacobian is identifiable when its part
#: orthogonal to the columns kept before it exceeds this fraction of its norm
#: (``calibration.IDENT_TOL``).
IDENTIFIABILITY_TOL = 1e-6
#: Calibration stops when its Gauss–Newton step (each parameter times its column scale)
#: is below this times the characteristic length.
CALIBRATION_STEP_TOL = 1e-10

# ================================================================ closure solvers
#: Default closure tolerance of a leg (:meth:`Leg.solve`), of an assembly
#: (:meth:`Mechanism.assemble`) and of forward kinematics: the norm of the closure
#: residual of :mod:`pkm_pin.solve` (world rotation vector from the tip to its target
#: [rad], tip displacement divided by the leg's characteristic length;
#: :func:`pkm_pin.solve.closure_error`).
CLOSURE_TOL = 1e-12
#: Closure tolerance of the legs in a sweep (same measure as :data:`CLOSURE_TOL`;
#: ``sweep.SWEEP_TOL``).
SWEEP_CLOSURE_TOL = CLOSURE_TOL
#: A leg's last Newton step taken from a relative residual below this is not evaluated
#: by the compiled sweep solver: Newton's next residual is ~TRUST² ≪
#: :data:`SWEEP_CLOSURE_TOL`, and Pinocchio's closure check verifies it (``sweep.TRUST``).
NEWTON_TRUST = 1e-7
#: Levenberg–Marquardt damping of the closure solver, added to the normal equations of
#: its dimensionless unknowns (see :func:`damping`): the floor …
DAMPING_FLOOR = 1e-10
#: … and the factor of the squared relative residual.
DAMPING_GAIN = 1e-2
#: A Newton iteration whose residual is above ``(1 − NEWTON_SLOW_RTOL)`` times the best
#: so far is slow; :data:`NEWTON_SLOW_STEPS` slow iterations in a row end the solve (a
#: least-squares minimum: the target is out of reach).
NEWTON_SLOW_RTOL = 1e-3
#: See :data:`NEWTON_SLOW_RTOL` (a count).
NEWTON_SLOW_STEPS = 10
#: A Newton step whose squared norm is below this fraction of ``1 + |q|²`` (dimensionless
#: coordinates) has stalled (at a joint limit or a local minimum).
NEWTON_STALL_RTOL = 1e-30
#: Absolute slack of the joint-limit checks (:meth:`Leg.within_limits`, the compiled
#: forward kinematics' result), in the joint's units [rad or m]: a guard against
#: round-off at a limit, not a relative tolerance.
JOINT_LIMIT_SLACK = 1e-9
#: Absolute slack [rad or m] of the check that target actuated coordinates lie inside
#: their joint limits (forward kinematics).
TARGET_LIMIT_SLACK = 1e-12
#: Three revolute joint frames form a spherical joint when the offsets between them are
#: at most this fraction of the leg's characteristic length.
SPHERICAL_OFFSET_RTOL = 1e-9
#: … and when consecutive axes are not parallel: the sine of their angle is above this.
SPHERICAL_AXES_SIN = 1e-6
#: Gimbal lock of three consecutive revolute joints of a tree (a spherical joint written
#: as three revolutes, issue 24): the first and third joints' homogenised twists (about
#: the middle joint, moments / characteristic length) agree, up to sign, to this.
GIMBAL_LOCK_RTOL = 1e-9
#: Generic rank of a linkage (:meth:`pkm_pin.linkage.Linkage.mobility`): how many
#: configurations near the analysed one, on the closure manifold, are sampled …
NEARBY_SAMPLES = 3
#: … each one this dimensionless step away (radians, or characteristic lengths) along a
#: random motion the closures allow (and off a representation singularity), then
#: projected back onto the closures by the tree solver (seeded: deterministic).
NEARBY_STEP = 0.05
#: An entry of a sparse idle-motion basis vector below this fraction of its largest
#: entry is zero (:func:`pkm_pin.model.closure_model.sparse_basis`).
SPARSE_ZERO_RTOL = 1e-9
#: An assembly made by hand (not by the closure solver) is analysed when every leg closes
#: to this relative pose error (:func:`pkm_pin.assembly.checked_twists`): printed values
#: of about 10 significant digits pass, a leg off by a micrometre per metre does not.
ASSEMBLY_CHECK_RTOL = 1e-8
#: A 4×4 pose is accepted when ``R Rᵀ`` differs from the identity by at most this
#: (absolute, on a dimensionless rotation matrix).
ROTATION_MATRIX_ATOL = 1e-9

#: A leg whose Newton iteration stalls at its type I singularity (its homogenised
#: Jacobian's smallest singular value, relative to the largest, at most
#: ``TYPE_I_STALL_FACTOR · √residual``: Newton converges only like a square root there)
#: or at a joint limit, is accepted by :meth:`Mechanism.assemble` when its relative
#: closure residual (as :data:`CLOSURE_TOL`) is at most this: a pose on the workspace
#: boundary given at 6 significant digits lies up to ~1e-7 outside it. The residual
#: reached is reported (``Assembly.residual``, ``info["boundary"]``).
TYPE_I_CLOSURE_TOL = 1e-6
#: See :data:`TYPE_I_CLOSURE_TOL` (dimensionless factor).
TYPE_I_STALL_FACTOR = 100.0

# ========================================================== partial poses (issue 17)
#: Pose coordinates x, y, z, roll, pitch, yaw are independent coordinates of a mechanism
#: at an assembly when the smallest singular value of their scaled rates (x, y, z
#: divided by the characteristic length, angles in rad) over the mechanism's motions is
#: above this fraction of the largest singular value of all six coordinates' rates.
COORDINATE_INDEPENDENCE_RTOL = 1e-6
#: A full 6-D pose off a lower-mobility mechanism's motion manifold (e.g. printed at 6
#: significant digits) is projected onto it (the nearest pose of the manifold, scaled
#: coordinates) when that pose differs from it by at most this in every coordinate: x, y,
#: z relative to the characteristic length, roll, pitch, yaw in rad. Beyond it the pose
#: is refused (:class:`~pkm_pin.errors.AssemblyError`).
POSE_PROJECTION_TOL = 1e-5

# ====================================================== forward kinematics (seed 003)
#: Largest increment of one Euler continuation step: a fraction of the characteristic
#: length for prismatic coordinates, radians for revolute ones (``position.STEP``).
CONTINUATION_STEP = 0.05
#: Largest step of the compiled predictor–corrector, same units as
#: :data:`CONTINUATION_STEP` (``position.COMPILED_STEP``): its steps are corrected to
#: their intermediate targets and accepted only while Newton's corrections contract.
COMPILED_CONTINUATION_STEP = 0.2
#: Loose relative closure tolerance (as :data:`CLOSURE_TOL`) of the legs, and scaled
#: actuated tolerance, during a continuation (``position.CONTINUATION_TOL``).
CONTINUATION_TOL = 1e-6
#: Type II closeness index below which the Euler continuation moves "by inertia"; the
#: compiled one stops where the closeness of its 6×6 Schur complement falls below it
#: (``position.INERTIA_TOL``).
INERTIA_TOL = 1e-2
#: A continuation whose step (a fraction of the path from start to target) is halved
#: below this has stalled.
CONTINUATION_MIN_STEP = 1e-6
#: Forward kinematics accepts a final assembly whose closure and scaled actuated errors
#: are below ``max(tol, FK_ACCEPT_FLOOR)`` (the floor: what Newton reaches in floating
#: point on ill-conditioned mechanisms).
FK_ACCEPT_FLOOR = 1e-10
#: Closure solves a linkage's forward kinematics may spend continuing from its guess
#: (an assembly) along the straight path of actuated values when the direct solve from
#: the guess fails (:meth:`pkm_pin.linkage.Linkage.assemble`): steps of a fraction of
#: the path, halved on a failure and doubled on a success, each warm-started from the
#: last assembly reached.
FK_CONTINUATION_MAX_SOLVES = 48
#: Newton (Levenberg–Marquardt) iterations one step of that continuation may take; a
#: step that needs more is halved (from the last assembly a short step converges in a
#: few).
FK_CONTINUATION_STEP_ITER = 25
#: A step of that continuation is kept when the Newton correction from its first-order
#: prediction (the branch's tangent times the step) is at most this fraction of the
#: predicted motion (both in the tree's velocity units: radians and characteristic
#: lengths); a larger one (a jump across a fold onto another branch) halves the step.
FK_CONTINUATION_CORRECTION = 0.5
#: That continuation stopped short of its target at a fold of the guess's assembly
#: branch (a type II singularity on the path) when the type II closeness index fell on
#: the way and its square, extrapolated linearly along the path, reaches zero before the
#: target and at most this fraction of the path beyond where it stopped (a fraction of
#: the path from the guess to the target).
FK_FOLD_REACH = 0.05
#: Two assembly modes are the same when their platform poses differ by less than this
#: (:func:`pkm_pin.leg.pose_error` at the characteristic length).
SAME_POSE_TOL = 1e-6
#: Two leg configurations are the same working mode when every coordinate differs by
#: less than this times ``max(1, characteristic length)`` (revolute ones modulo 2π).
SAME_CONFIGURATION_TOL = 1e-7
#: Two actuated-coordinate vectors are the same when they differ by at most this
#: (absolute [rad or m], after the legs' own :data:`SAME_CONFIGURATION_TOL` test).
SAME_ACTUATED_ATOL = 1e-9
#: A nonsingular end of the assembly-mode homotopy (:mod:`pkm_pin.modes`), scaled so its
#: largest Study coordinate is 1, is real when the norm of its imaginary part is at
#: most this fraction of the norm of its real part (the closure solver polishes it next).
HOMOTOPY_REAL_TOL = 1e-6
#: The multistart of :func:`pkm_pin.modes.assembly_modes` stops after this many batches
#: in a row that find no new assembly mode.
MODES_PATIENCE = 5

#: The multistart of a general linkage's :meth:`~pkm_pin.linkage.Linkage.
#: forward_kinematics_all` gives up after this many batches, or this many distinct
#: assemblies (new ones still appearing: a continuum the local check at the first
#: assembly did not see, not a list of modes). Healthy files settle in 6 to 10 batches
#: with 2 to 8 modes.
MODES_MAX_BATCHES = 64

#: The distinct assemblies after which that multistart gives up (see
#: :data:`MODES_MAX_BATCHES`), found or estimated (:data:`MODES_ESTIMATE_FROM`).
MODES_MAX = 256

#: From this many batches on, that multistart also gives up when the assemblies it
#: would find in all, estimated from how often each was found (the bias-corrected Chao1
#: estimate, :meth:`~pkm_pin.linkage._Multistart.estimate`), exceed :data:`MODES_MAX`:
#: Gepetto's kangaroo_like_2legs at home refused after 9 batches (1.3 s), not 60 (6.9 s).
MODES_ESTIMATE_FROM = 8

# ====================================================================== dynamics
#: Inverse dynamics (:mod:`pkm_pin.dynamics`): a velocity with ``J v`` or an
#: acceleration with ``J a + J̇ v`` above this fraction of the size of its terms (the
#: closure rows made dimensionless, each row's ``Σ |J_ij x_j|`` plus ``|J̇ v|``) is
#: inconsistent with the closures.
MOTION_CONSISTENCY_RTOL = 1e-6
#: Inverse dynamics: a least-squares balance of the generalized forces whose residual
#: exceeds this fraction of the right-hand side (or of the size of the solution's
#: terms) needs an effort no actuator gives (along an idle motion).
EFFORT_BALANCE_RTOL = 1e-6

# ======================================================================== reports
#: Components of a unit direction below this are printed as 0; coordinates of points
#: below this times the characteristic length likewise (``report._SNAP``).
DIRECTION_SNAP = 1e-9
#: Largest difference between the Pinocchio path and the hand-written formulas that
#: ``pkm-pin check`` accepts (the cross-checks are relative differences).
CROSSCHECK_TOL = 1e-6


def damping(r: float) -> float:
    """Levenberg–Marquardt damping of the leg solvers for a relative residual ``r``:
    ``DAMPING_FLOOR + DAMPING_GAIN r²``.

    It grows with the error and vanishes at the solution (quadratic convergence kept);
    it tames singular starts (UR5 from neutral: 48/60 first-try vs 5/60 undamped). The
    closure solver (:func:`pkm_pin.newton.lm_damping`) writes the same expression out for
    its compiled code (numba's cache would not see a change made here); a test checks
    that they agree.
    """
    return DAMPING_FLOOR + DAMPING_GAIN * r * r


#: Historical names: ``module.NAME`` is an alias of ``tolerances.VALUE``.
ALIASES = {
    "screws.RTOL": "RANK_RTOL",
    "screws._ZERO_ROW": "ZERO_SCREW_RTOL",
    "analysis.SINGULAR_TOL": "CLOSENESS_SINGULAR_TOL",
    "serial.SINGULAR_TOL": "SERIAL_SINGULAR_TOL",
    "serial.TWIST_RTOL": "LINK_TWIST_RTOL",
    "sensitivity.SINGULAR_TOL": "SENSITIVITY_SINGULAR_TOL",
    "sensitivity.COMPATIBILITY_TOL": "COMPATIBILITY_TOL",
    "calibration.IDENT_TOL": "IDENTIFIABILITY_TOL",
    "sweep.SWEEP_TOL": "SWEEP_CLOSURE_TOL",
    "sweep.TRUST": "NEWTON_TRUST",
    "position.STEP": "CONTINUATION_STEP",
    "position.COMPILED_STEP": "COMPILED_CONTINUATION_STEP",
    "position.CONTINUATION_TOL": "CONTINUATION_TOL",
    "position.INERTIA_TOL": "INERTIA_TOL",
    "report._SNAP": "DIRECTION_SNAP",
}

#: Relative margin of the reach test of a sweep (:func:`pkm_pin.sweep.out_of_reach`): a
#: pose is refused without a solve only when a leg's tip target lies outside its
#: :attr:`~pkm_pin.leg.Leg.reach` by more than this fraction of the reach plus the
#: characteristic length (rounding never refuses a pose the solver would reach).
REACH_MARGIN = 1e-9
