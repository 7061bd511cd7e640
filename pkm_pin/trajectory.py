"""Motions given as actuated values over time, and the efforts, speeds and powers each
actuator needs along them (issue 26, items 2 and 3; docs/dynamics.md, "Trajectories").

A motion is the actuated values ``q_a(t)`` (in the model's :attr:`~ClosureModel.actuated`
order): samples ``(t, q_a)`` (arrays, or a CSV file with the header
``t,<actuated names…>``) splined by :class:`SplineMotion`, or the default
:class:`SineMotion` (:func:`default_motion`); or the output's pose coordinates over
time, all or some of x, y, z, roll, pitch, yaw (:class:`OutputMotion`,
:func:`pose_motion` from poses, a CSV with the header ``t,<coordinates…>``): ``q`` by
inverse kinematics on the closure and coordinate rows, ``v, a`` from ``[J; K] v = [0;
ċ]``, ``[J; K] a = [−J̇ v; c̈ − κ(q, v)]`` (``K`` the coordinates' rates,
:class:`_OutputCoordinates`). At each time of an actuated motion:

* ``q``: the whole tree by forward kinematics (:func:`pkm_pin.solve.solve_tree` with the
  actuated targets, to :data:`~pkm_pin.tolerances.CLOSURE_TOL`, or :data:`FK_ACCEPT_RTOL`
  where the Newton converges slowly), warm-started from the previous sample moved by its
  own velocity and acceleration (``q ⊕ (v dt + a dt²/2)``: the branch is continued);
* ``v, a``: :func:`pkm_pin.dynamics.motion_from_actuated` from the spline's ``q̇_a, q̈_a``
  (``[J; S] v = [0; q̇_a]``, ``[J; S] a = [−J̇ v; q̈_a]``); along idle motions (the tree's
  motions with every actuator still, e.g. a rod spinning about its axis) the velocity is
  the minimum-norm one and the acceleration the one the idle joints' own dynamics give
  (:func:`pkm_pin.dynamics.idle_acceleration`);
* the efforts: :func:`pkm_pin.dynamics.inverse_dynamics` with the gravity asked for
  (default ``(0, 0, −9.81)``) and the payload wrench.

Decisions:

* **Spline**: scipy's ``CubicSpline``, **clamped** (``q̇_a = 0`` at both ends) by default:
  a motion given for motor sizing starts and ends at rest, and a clamped spline keeps the
  accelerations of the start and the stop (a natural spline sets ``q̈_a = 0`` there and
  lets the motion start with a speed: the peak efforts at start-up are lost).
  ``bc_type="natural"``, ``"not-a-knot"`` or ``"periodic"`` are accepted for data that
  are a piece of a longer motion. The acceleration is continuous (C²) in every case.
* **Default motion**: each actuator ``q_a,k(t) = q_a,k(home) + A_k sin(2π t / T + 2π k /
  n)`` over ``T = 2 s`` (one period; phases spread over the actuators so the output
  moves in every direction the actuators give): ``A_k = 0.1 rad`` for a revolute,
  ``0.1 L`` for a prismatic (``L`` the model's characteristic length), reduced to 10 %
  of the joint's range and half the distance from home to its nearer limit when those
  are finite and smaller.
* **Payload**: a wrench ``(f; m)`` at the output frame's origin, world axes, constant in
  the world (a payload of mass ``m``: ``(m g; 0)``); at each sample it is given to
  :func:`~pkm_pin.dynamics.inverse_dynamics` about the world origin, ``(f; m + p × f)``.
* **Energy**: trapezoidal rule on the samples: ``energy = ∫ |P| dt`` (what the motor
  delivers when braking is not recovered: the sizing number) and ``net_energy = ∫ P dt``
  (the change of the mechanism's kinetic and potential energy minus the payload's work).
  RMS effort ``sqrt(∫ τ² dt / (t_end − t_0))`` (time-weighted), peaks ``max |·|`` over
  the samples.
* **Masses**: the file's inertias only, never invented ones. :func:`study` refuses a
  model with no mass on any body unless a payload is given (its efforts would be zero:
  :class:`~pkm_pin.errors.InputError` naming the bodies); a payload on a massless model
  gives the payload's efforts, said in :attr:`TrajectoryStudy.notes`. Bodies without mass
  in a model with some are listed in :attr:`TrajectoryStudy.massless_bodies`.
"""

from __future__ import annotations

import csv
import io
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from . import dynamics, screws
from .closure_gaps import loop_size
from .dynamics import body_names
from .errors import (
    ForwardKinematicsError,
    InconsistentMotion,
    InputError,
    PkmError,
    SingularityError,
)
from .model.closure_model import ClosureModel
from .output_driver import OutputCoordinates, OutputDriver, coordinate_errors_of  # noqa: F401
from .solve import (
    POSE_COORDINATES,
    iter_tree_starts,
    pose_coordinates,
    solve_tree,
    solve_tree_starts,
    tree_limits,
)
from .tolerances import CLOSURE_TOL, MOTION_CONSISTENCY_RTOL, RANK_RTOL

#: Duration [s] of the default motion.
DEFAULT_DURATION = 2.0
#: Samples of a study (uniform in time, both ends included).
DEFAULT_SAMPLES = 201
#: Amplitude of the default motion: this many rad (revolute) or characteristic lengths
#: (prismatic; without limits, of the size of its loops,
#: :func:`pkm_pin.closure_gaps.loop_size`).
DEFAULT_AMPLITUDE = 0.1
#: ... at most this fraction of the joint's range,
DEFAULT_RANGE_FRACTION = 0.1
#: ... and at most this fraction of the distance from home to the nearer limit.
DEFAULT_MARGIN_FRACTION = 0.5
#: Largest CSV file read [bytes], and rows.
CSV_MAX_BYTES = 20_000_000
CSV_MAX_ROWS = 1_000_000
#: A sample's forward kinematics that stops above CLOSURE_TOL (slow, linear convergence
#: near a constraint singularity) is kept when its relative residual is below this (100×
#: below what :func:`pkm_pin.dynamics.inverse_dynamics` accepts).
FK_ACCEPT_RTOL = 1e-10
#: Boundary conditions of :class:`SplineMotion` (scipy's names).
SPLINE_BC = ("clamped", "natural", "not-a-knot", "periodic")


# ------------------------------------------------------------------- motions
class SplineMotion:
    """Actuated values over time from samples, a C² cubic spline per actuator.

    Args:
        t: (N,) strictly increasing times [s], N ≥ 2.
        q_actuated: (N, n) actuated values [rad or m] (the model's actuated order).
        names: Names of the n actuated joints (for messages).
        bc_type: ``"clamped"`` (default: at rest at both ends), ``"natural"``,
            ``"not-a-knot"`` or ``"periodic"`` (the first and last rows must then be
            equal), module docstring.
    """

    #: What the motion's values drive: the actuated joints (an :class:`OutputMotion`:
    #: "output").
    driven = "actuated"

    def __init__(self, t, q_actuated, names=(), bc_type: str = "clamped"):
        from scipy.interpolate import CubicSpline

        t = screws.as_float_array(t, "t").ravel()
        Q = screws.as_float_array(q_actuated, "q_actuated")
        if Q.ndim == 1:
            Q = Q[:, None]
        if Q.ndim != 2 or Q.shape[0] != t.size:
            raise InputError(f"q_actuated must have one row per time ({t.size}), got shape "
                             f"{Q.shape}")
        if t.size < 2:
            raise InputError(f"a motion needs at least 2 samples, got {t.size}")
        if not (np.isfinite(t).all() and np.isfinite(Q).all()):
            raise InputError("the motion's times and values must be finite")
        if not np.all(np.diff(t) > 0):
            k = int(np.argmin(np.diff(t)))
            raise InputError(f"the times must increase strictly: t[{k}] = {t[k]:g}, "
                             f"t[{k + 1}] = {t[k + 1]:g}")
        if bc_type not in SPLINE_BC:
            raise InputError(f"bc_type must be one of {', '.join(SPLINE_BC)}, got {bc_type!r}")
        if bc_type == "periodic" and not np.allclose(Q[0], Q[-1], rtol=0, atol=1e-12):
            raise InputError("a periodic spline needs equal first and last values")
        self.t, self.q_actuated, self.bc_type = t, Q, bc_type
        self.names = tuple(names)
        self.spline = CubicSpline(t, Q, axis=0, bc_type=bc_type)

    @property
    def start(self) -> float:
        return float(self.t[0])

    @property
    def stop(self) -> float:
        return float(self.t[-1])

    def __call__(self, times) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(q_a, q̇_a, q̈_a)`` at ``times``, each (len(times), n)."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        s = self.spline
        return s(times), s(times, 1), s(times, 2)

    def describe(self) -> str:
        return (f"cubic spline ({self.bc_type}) through {self.t.size} samples, "
                f"t in [{self.start:g}, {self.stop:g}] s")


@dataclass(frozen=True)
class SineMotion:
    """``q_a(t) = centre + amplitude sin(2π t / duration + phase)`` per actuator (the
    default motion, :func:`default_motion`); exact derivatives."""

    centre: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    duration: float = DEFAULT_DURATION

    start = 0.0

    @property
    def stop(self) -> float:
        return float(self.duration)

    def __call__(self, times) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        times = np.atleast_1d(np.asarray(times, dtype=float))
        w = 2 * np.pi / self.duration
        arg = w * times[:, None] + self.phase
        A = self.amplitude
        return (self.centre + A * np.sin(arg), A * w * np.cos(arg),
                -A * w ** 2 * np.sin(arg))

    def describe(self) -> str:
        return (f"default: each actuator a sine about home over {self.duration:g} s, "
                "amplitudes " + ", ".join(f"{a:.3g}" for a in self.amplitude))


def default_motion(model: ClosureModel, q0, duration: float = DEFAULT_DURATION
                   ) -> SineMotion:
    """The default motion about the assembled ``q0`` (module docstring): one period of a
    sine per actuator, phases ``2π k / n``, amplitude 0.1 rad or 0.1 L (a length without
    limits: 0.1 of its loops' size, :func:`pkm_pin.closure_gaps.loop_size`), at most 10 % of
    the joint's range and half the distance to its nearer limit (0: an actuator whose
    home is at a limit stays there)."""
    duration = float(duration)
    if not (np.isfinite(duration) and duration > 0):
        raise InputError(f"the duration must be a positive number of seconds, got {duration}")
    q0 = model.check_q(q0)
    centre = np.asarray(model.actuated_values(q0), dtype=float)
    lo, up = tree_limits(model)
    tree = model.tree
    amp = np.empty(len(model.actuated))
    for k, name in enumerate(model.actuated):
        joint = tree.joints[tree.getJointId(name)]
        scale = 1.0
        if model.translating[joint.idx_v]:  # a length: L; without limits, its loops' size
            bounded = joint.nq == 1 and np.isfinite([lo[joint.idx_q], up[joint.idx_q]]).all()
            scale = model.length if bounded else loop_size(model, q0, name)
        A = DEFAULT_AMPLITUDE * scale
        if joint.nq == 1:
            i = joint.idx_q
            if np.isfinite(lo[i]) and np.isfinite(up[i]):
                A = min(A, DEFAULT_RANGE_FRACTION * (up[i] - lo[i]))
            margin = min(q0[i] - lo[i], up[i] - q0[i])
            if margin <= 0:  # home at (or beyond) a limit: a sine about it leaves the range
                A = 0.0
            elif margin < np.inf:
                A = min(A, DEFAULT_MARGIN_FRACTION * margin)
        amp[k] = A
    n = len(amp)
    return SineMotion(centre, amp, 2 * np.pi * np.arange(n) / max(n, 1), duration)


def read_csv(path, names) -> SplineMotion:
    """The motion of a CSV file, splined (clamped): a header ``t`` then either the
    actuated joints' names (``names``, in any order: a :class:`SplineMotion` of the
    actuated values [rad or m]) or some of the output's coordinates x, y, z [m], roll,
    pitch, yaw [rad] (an :class:`OutputMotion`, the others held by the mechanism), then
    one row of numbers per sample [s; …]. Blank lines and lines starting with ``#``
    are skipped."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > CSV_MAX_BYTES:
            raise InputError(f"{path}: {size} bytes, more than the {CSV_MAX_BYTES} read")
        text = path.read_text()
    except UnicodeDecodeError as e:
        raise InputError(f"{path}: not a text file ({e.reason})") from e
    except OSError as e:
        raise InputError(f"cannot read {path}: {e.strerror or e}") from e
    lines = [(n, line) for n, line in enumerate(text.splitlines(), 1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise InputError(f"{path}: empty; give a header t,{','.join(names)} and rows")
    rows = list(csv.reader(io.StringIO("\n".join(line for _, line in lines))))
    header = [h.strip() for h in rows[0]]
    names = tuple(names)
    expected = "t," + ",".join(names)
    actuated = sorted(header[1:]) == sorted(names)
    output = bool(header[1:]) and all(h in POSE_COORDINATES for h in header[1:])
    if not header or header[0] != "t" or not (actuated or output) \
            or len(set(header)) != len(header):
        shown = ",".join(header)[:200]
        raise InputError(f"{path}: the header must be {expected} (the actuated joints in any "
                         f"order) or t and some of {','.join(POSE_COORDINATES)} (output "
                         f"coordinates), got {shown!r}")
    if len(rows) - 1 > CSV_MAX_ROWS:
        raise InputError(f"{path}: more than {CSV_MAX_ROWS} rows")
    data = np.empty((len(rows) - 1, len(header)))
    for k, row in enumerate(rows[1:]):
        line = lines[k + 1][0]
        if len(row) != len(header):
            raise InputError(f"{path}:{line}: {len(row)} values for {len(header)} columns")
        for c, text in enumerate(row):
            try:
                data[k, c] = float(text)
            except ValueError as e:
                raise InputError(f"{path}:{line}: {text.strip()[:40]!r} is not a number") from e
    try:
        if not actuated:
            return OutputMotion(data[:, 0], data[:, 1:], header[1:])
        return SplineMotion(data[:, 0], data[:, [header.index(n) for n in names]], names)
    except InputError as e:
        raise InputError(f"{path}: {e}") from e


# ------------------------------------------------------ motions of the output
class OutputMotion(SplineMotion):
    """Output pose coordinates over time, a C² cubic spline per coordinate.

    ``coordinates``: some of x, y, z [m] (the output frame's origin, world) and roll,
    pitch, yaw [rad] (``R = Rz(yaw) Ry(pitch) Rx(roll)``, world), the others held by the
    mechanism (:func:`motion_states`: the parasitic motions of a lower-mobility machine
    follow its closures; with fewer coordinates than the output's degrees of freedom,
    the first others in the order x, y, z, roll, pitch, yaw that complete an independent
    set are held at their values at the start configuration). Stored in that order;
    angles unwrapped along time (a yaw through ±π stays continuous).
    """

    driven = "output"

    def __init__(self, t, values, coordinates=POSE_COORDINATES, bc_type: str = "clamped"):
        coordinates = tuple(coordinates)
        unknown = [c for c in coordinates if c not in POSE_COORDINATES]
        if not coordinates or unknown or len(set(coordinates)) != len(coordinates):
            raise InputError(f"output coordinates must be distinct names among "
                             f"{', '.join(POSE_COORDINATES)}, got {', '.join(coordinates)}")
        V = screws.as_float_array(values, "values")
        V = V[:, None] if V.ndim == 1 else V
        if V.ndim != 2 or V.shape[1] != len(coordinates):
            raise InputError(f"values must have one column per coordinate "
                             f"({', '.join(coordinates)}), got shape {V.shape}")
        order = sorted(range(len(coordinates)),
                       key=lambda k: POSE_COORDINATES.index(coordinates[k]))
        V, coordinates = V[:, order].copy(), tuple(coordinates[k] for k in order)
        angles = [k for k, c in enumerate(coordinates) if c in POSE_COORDINATES[3:]]
        if angles and np.isfinite(V).all():
            V[:, angles] = np.unwrap(V[:, angles], axis=0)
        super().__init__(t, V, coordinates, bc_type)
        self.coordinates = coordinates

    def describe(self) -> str:
        return (f"output {', '.join(self.coordinates)}: cubic spline ({self.bc_type}) "
                f"through {self.t.size} samples, t in [{self.start:g}, {self.stop:g}] s")


def pose_motion(t, poses, coordinates=POSE_COORDINATES, bc_type: str = "clamped"
                ) -> OutputMotion:
    """An :class:`OutputMotion` from output poses over time: ``poses`` a sequence of
    ``pinocchio.SE3`` (world placements of the output frame), an (N, 4, 4) array of
    homogeneous matrices, or an (N, 6) array of x, y, z, roll, pitch, yaw; only
    ``coordinates`` of them are followed (default all six; a 3-DOF machine: its own
    three, the others are what its closures impose)."""
    if len(poses) and isinstance(poses[0], pin.SE3):
        C = np.array([pose_coordinates(p) for p in poses])
    else:
        P = screws.as_float_array(poses, "poses")
        if P.ndim == 3 and P.shape[1:] == (4, 4):
            C = np.array([pose_coordinates(pin.SE3(M)) for M in P])
        elif P.ndim == 2 and P.shape[1] == 6:
            C = P
        else:
            raise InputError(f"poses must be SE3s, (N, 4, 4) or (N, 6) x, y, z, roll, "
                             f"pitch, yaw, got shape {P.shape}")
    idx = [POSE_COORDINATES.index(c) for c in coordinates if c in POSE_COORDINATES]
    if len(idx) != len(tuple(coordinates)):
        raise InputError(f"coordinates must be among {', '.join(POSE_COORDINATES)}")
    return OutputMotion(t, C[:, idx], tuple(coordinates), bc_type)


#: The output frame's coordinates and rates (:mod:`pkm_pin.output_driver`).
_OutputCoordinates = OutputCoordinates


class _OutputDriver(OutputDriver):
    """:class:`pkm_pin.output_driver.OutputDriver` of an :class:`OutputMotion`'s
    coordinates (the others held at ``q0``), with the velocity system of its rows."""

    def __init__(self, model: ClosureModel, motion: OutputMotion, q0: np.ndarray):
        super().__init__(model, motion.coordinates, q0)

    def system(self, q) -> "_ActuatedSystem":
        c, K = self.oc.rates(q)
        return _ActuatedSystem(self.model, q, K[self.rows] / self.oc.scales[self.rows, None])


# ------------------------------------------------------------ the mechanism
def closure_model_of(mech) -> tuple[ClosureModel, np.ndarray]:
    """The closure model whose dynamics a mechanism's study uses, and its assembled home
    configuration: a :class:`~pkm_pin.Mechanism` detected in a file: its
    ``source_model`` (the file's tree, with the file's inertias); a TOML mechanism: its
    ``closure_model`` (legs and platform, the inertias of the legs' URDFs); a
    :class:`~pkm_pin.linkage.Linkage`: its ``model``; a :class:`ClosureModel`: itself,
    assembled from its reference."""
    if isinstance(mech, ClosureModel):
        sol, _ = solve_tree_starts(mech, iter_tree_starts(mech, None, count=16))
        if not sol.converged:
            raise ForwardKinematicsError(f"{mech.name or 'the model'} does not assemble "
                                         f"from its reference (residual {sol.residual:.3g})")
        return mech, sol.q
    if isinstance(getattr(mech, "model", None), ClosureModel) \
            and hasattr(mech, "tree_configuration"):  # any mechanism
        return mech.model, mech.tree_configuration()
    raise InputError(f"a mechanism, linkage or closure model is needed, got "
                     f"{type(mech).__name__}")


def massless_bodies(model: ClosureModel) -> list[str]:
    """The bodies (:func:`~pkm_pin.dynamics.body_names`) whose mass in the model is
    zero (the masses checked first: :func:`~pkm_pin.dynamics.check_inertias`)."""
    dynamics.check_inertias(model)
    tree = model.tree
    return [n for j, n in zip(range(1, tree.njoints), body_names(model))
            if not tree.inertias[j].mass > 0]


def _at_time(e: Exception, t: float) -> Exception:
    """``e`` with its message prefixed by the sample's time (its attributes kept)."""
    if e.args and isinstance(e.args[0], str):
        e.args = (f"at t = {t:g} s: {e.args[0]}",) + e.args[1:]
    return e


def _at_sample(e: Exception, times) -> Exception:
    """An error of :func:`dynamics.inverse_dynamics_batch` (``e.sample``, its message
    prefixed ``sample i: ``) with the sample's time instead."""
    i = getattr(e, "sample", None)
    if i is None:
        return e
    prefix = f"sample {i}: "
    if e.args and isinstance(e.args[0], str) and e.args[0].startswith(prefix):
        e.args = (e.args[0][len(prefix):],) + e.args[1:]
    return _at_time(e, times[i])


# ------------------------------------------------------------------ results
@dataclass(frozen=True)
class TrajectoryStudy:
    """Efforts, speeds and powers of each actuator along a motion (:func:`study`).

    Arrays over the N samples (``n`` actuators in :attr:`actuated` order, the tree's
    ``nq``/``nv``):

    Attributes:
        t: (N,) times [s].
        q, v, a: (N, nq), (N, nv), (N, nv) the tree's consistent motion.
        q_actuated, speeds, accelerations: (N, n) actuated values, rates, accelerations.
        efforts: (N, n) [N m or N]; powers: (N, n) ``efforts × speeds`` [W].
        payload_efforts: (N, n) the part of :attr:`efforts` due to the payload.
        actuated: Actuated joint names; units: ``"rad"`` or ``"m"`` per actuator.
        gravity, payload: As given (payload ``(f; m)`` at the output origin, or None).
        motion: What the motion is (one line).
        massless_bodies: Bodies with no mass in the model.
        notes: Lines the reader must see (a massless model, idle motions).
        timing: Seconds per sample of each stage (``kinematics``: forward kinematics,
            ``motion``: ``v, a``, ``dynamics``) and ``total`` seconds.
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    q_actuated: np.ndarray
    speeds: np.ndarray
    accelerations: np.ndarray
    efforts: np.ndarray
    payload_efforts: np.ndarray
    actuated: tuple
    units: tuple
    gravity: np.ndarray
    payload: np.ndarray | None
    motion: str
    massless_bodies: tuple = ()
    notes: tuple = ()
    timing: dict = field(default_factory=dict)

    @property
    def powers(self) -> np.ndarray:
        """(N, n) mechanical power of each actuator ``τ q̇_a`` [W] (positive: the
        actuator gives energy to the mechanism)."""
        return self.efforts * self.speeds

    @property
    def effort_units(self) -> tuple:
        return tuple("N m" if u == "rad" else "N" for u in self.units)

    @property
    def speed_units(self) -> tuple:
        return tuple(f"{u}/s" for u in self.units)

    def summary(self) -> dict:
        """Per actuator: ``peak_effort`` ``max |τ|``, ``rms_effort`` ``sqrt(∫ τ² dt / T)``,
        ``peak_speed`` ``max |q̇_a|``, ``peak_power`` ``max |P|``, ``energy`` ``∫ |P| dt``
        and ``net_energy`` ``∫ P dt`` [J] (trapezoidal rule on the samples), and the
        units."""
        t, tau, P = self.t, self.efforts, self.powers
        T = float(t[-1] - t[0])
        out = {}
        for k, name in enumerate(self.actuated):
            out[name] = {
                "peak_effort": float(np.abs(tau[:, k]).max()),
                "rms_effort": float(np.sqrt(trapezoid(tau[:, k] ** 2, t) / T)),
                "peak_speed": float(np.abs(self.speeds[:, k]).max()),
                "peak_power": float(np.abs(P[:, k]).max()),
                "energy": float(trapezoid(np.abs(P[:, k]), t)),
                "net_energy": float(trapezoid(P[:, k], t)),
                "effort_unit": self.effort_units[k], "speed_unit": self.speed_units[k],
            }
        return out


def trapezoid(y: np.ndarray, t: np.ndarray) -> float:
    """``∫ y dt`` by the trapezoidal rule on the samples."""
    y, t = np.asarray(y, float), np.asarray(t, float)
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(t)))


# ---------------------------------------------------------------- the study
def motion_states(model: ClosureModel, motion, times, q0, *, gravity=dynamics.GRAVITY,
                  tol: float = CLOSURE_TOL) -> tuple:
    """The consistent ``(q, v, a)`` of the tree (each (N, nq / nv)) and the actuated
    ``(q_a, q̇_a, q̈_a)`` (each (N, n)) at ``times`` along ``motion`` (a callable
    ``times -> (q_a, q̇_a, q̈_a)``: :class:`SplineMotion`, :class:`SineMotion`; or an
    :class:`OutputMotion` of output coordinates: inverse kinematics and
    ``[J; K] (v, a)``), the first sample's position solved from ``q0`` (module
    docstring; ``gravity`` sets the idle joints' accelerations).

    Raises:
        ForwardKinematicsError: a sample's forward kinematics does not converge (the motion
            leaves the workspace), with its time.
        SingularityError, InconsistentMotion: as :func:`dynamics.motion_from_actuated`,
            the message with the sample's time.
    """
    times = np.asarray(times, dtype=float).ravel()
    if getattr(motion, "driven", "actuated") == "output":
        return _output_states(model, motion, times, q0, gravity, tol)
    Qa, Qd, Qdd = motion(times)
    n = len(model.actuated)
    if Qa.shape != (times.size, n):
        raise InputError(f"the motion gives {Qa.shape[-1]} actuated values, the model has "
                         f"{n} ({', '.join(model.actuated)})")
    N = times.size
    q, v, a = np.empty((N, model.nq)), np.empty((N, model.nv)), np.empty((N, model.nv))
    clock = {"kinematics": 0.0, "motion": 0.0}
    guess = model.check_q(q0)
    for i, ti in enumerate(times):
        t0 = time.perf_counter()
        if i > 0:
            dt = ti - times[i - 1]
            guess = pin.integrate(model.tree, q[i - 1], v[i - 1] * dt + 0.5 * a[i - 1] * dt * dt)
        q[i] = _forward_kinematics(model, guess, q[i - 1] if i else guess, Qa[i], ti, tol)
        t1 = time.perf_counter()
        try:  # the compiled kernel where it certifies no idle motion, else numpy
            vi, ai, determined = dynamics.actuated_motion(model, q[i], Qd[i], Qdd[i])
            if not determined:
                system = _ActuatedSystem(model, q[i])
                rhs = Qdd[i] / system.units[system.act]
                vi, ai = _carry_idle(model, system, q[i], vi, ai,
                                     (v[i - 1], a[i - 1], ti - times[i - 1]) if i else None,
                                     lambda _: rhs, gravity)
        except PkmError as e:  # SingularityError, InconsistentMotion
            raise _at_time(e, ti)
        v[i], a[i] = vi, ai
        clock["kinematics"] += t1 - t0
        clock["motion"] += time.perf_counter() - t1
    return (q, v, a, Qa, Qd, Qdd), clock


def _forward_kinematics(model: ClosureModel, guess, previous, qa, ti: float, tol: float):
    """One sample's forward kinematics from ``guess`` (then restarts about
    ``previous``); a :class:`ForwardKinematicsError` with its time when it does not
    close."""
    sol = solve_tree(model, guess, targets=qa, tol=tol)
    if not sol.converged and sol.residual > FK_ACCEPT_RTOL:
        sol = solve_tree(model, sol.q, targets=qa, tol=tol, max_iter=400)
    if not sol.converged and sol.residual > FK_ACCEPT_RTOL:
        starts = iter_tree_starts(model, previous, count=16)
        sol, _ = solve_tree_starts(model, starts, targets=qa, tol=tol, nearest=previous)
    if not sol.converged and sol.residual > FK_ACCEPT_RTOL:
        values = ", ".join(f"{x:.6g}" for x in qa)
        raise ForwardKinematicsError(
            f"at t = {ti:g} s the forward kinematics of {model.name or 'the model'} "
            f"does not converge (actuated {values}; relative residual "
            f"{sol.residual:.3g}): the motion leaves the workspace or crosses a "
            "singularity")
    return sol.q


def _carry_idle(model: ClosureModel, system, q, v, a, previous, driven_rhs, gravity):
    """``(v, a)`` with the idle motions' part set by their own dynamics: at rest at the
    first sample (``previous`` None) with :func:`dynamics.idle_acceleration`; later a
    Heun step from ``previous = (v, a, dt)`` of the sample before (``driven_rhs(v)``:
    the driven rows' right-hand side of the acceleration at velocity ``v``)."""
    if system.idle is None:
        return v, a
    if previous is None:
        return v, dynamics.idle_acceleration(model, q, v, a, gravity=gravity,
                                             idle=system.idle)
    v_prev, a_prev, dt = previous
    v0 = v
    with np.errstate(over="ignore", invalid="ignore"):
        for pred in (v_prev + a_prev * dt, None):
            if pred is None:
                pred = v_prev + 0.5 * (a_prev + a) * dt
            v = system.carry(v0, pred)
            if not np.isfinite(v).all():
                break
            a = dynamics.idle_acceleration(model, q, v, system.acceleration(
                v, driven_rhs(v)), gravity=gravity, idle=system.idle)
        _check_idle_step(model, system, v, dt)
    return v, a


#: The most an idle motion may move a joint in one sample (rad, or the characteristic
#: length for a translation) before its carried dynamics is refused as running away: 16
#: turns between two samples follow nothing (a rod spinning about its own axis reaches
#: 4.6 rad a sample in the tests; Robotiq's 2F-85 fingers pass 100 at 0.25 s on their way
#: to 1e31 rad/s, then nan).
IDLE_STEP_MAX = 100.0


def _check_idle_step(model: ClosureModel, system, v: np.ndarray, dt: float) -> None:
    """An :class:`InconsistentMotion` (``kind="idle"``) when the idle motions' velocity
    carried by :func:`_carry_idle` is not finite or moves a joint by more than
    :data:`IDLE_STEP_MAX` in one sample: the explicit steps no longer follow their own
    dynamics (no spring nor damper is modelled; Robotiq's 2F-85 fingers under gravity),
    and the rest of the motion would be numbers without meaning (the velocities grew to
    1e31 rad/s, then nan, before this check)."""
    idle = np.abs(system.idle).max(axis=1) > 1e-9 * np.abs(system.idle).max()
    step = np.abs(v / model.velocity_units) * dt
    if np.isfinite(step[idle]).all() and not (step[idle] > IDLE_STEP_MAX).any():
        return
    joints = tuple(dict.fromkeys(n for n, k in zip(dynamics.velocity_names(model.tree),
                                                   idle) if k))
    worst = float(np.nanmax(np.where(np.isfinite(step), step, np.inf)[idle]))
    raise InconsistentMotion(
        f"the idle motions ({', '.join(joints[:8])}{' …' if len(joints) > 8 else ''} move "
        "with every actuator locked) move too fast for the samples to follow: one sample "
        f"moves them by {'more than any bound' if not np.isfinite(worst) else f'{worst:.3g}'}"
        f" (rad, or L for a translation; at most {IDLE_STEP_MAX:g}): their own dynamics, "
        "followed without springs or dampers (a file's stiffness is not modelled), "
        "diverges or is faster than the samples; actuate or lock those joints (a closures "
        "file's name_mot, an MJCF actuator), or, for a fast but bounded motion, sample it "
        "finer (--samples)", kind="idle", joints=joints)


def _output_states(model: ClosureModel, motion, times, q0, gravity, tol) -> tuple:
    """:func:`motion_states` of an :class:`OutputMotion`: per sample the inverse
    kinematics on the closure and coordinate rows (warm-started as the forward
    kinematics), ``[J; K] v = [0; ċ]``, ``[J; K] a = [−J̇ v; c̈ − κ(q, v)]``
    (:class:`_OutputCoordinates`), the idle motions as for actuated motions."""
    q0 = model.check_q(q0)
    driver = _OutputDriver(model, motion, q0)
    C, Cd, Cdd = driver.targets(*motion(times))
    N, s = times.size, driver.oc.scales[driver.rows]
    q, v, a = np.empty((N, model.nq)), np.empty((N, model.nv)), np.empty((N, model.nv))
    clock, guess = {"kinematics": 0.0, "motion": 0.0}, q0
    for i, ti in enumerate(times):
        t0 = time.perf_counter()
        if i > 0:
            dt = ti - times[i - 1]
            guess = pin.integrate(model.tree, q[i - 1], v[i - 1] * dt + 0.5 * a[i - 1] * dt * dt)
        q[i], r = driver.position(guess, C[i], tol)
        if r > FK_ACCEPT_RTOL:
            values = ", ".join(f"{n} {x:.6g}" for n, x in zip(driver.names, C[i]))
            raise ForwardKinematicsError(
                f"at t = {ti:g} s the inverse kinematics of {model.name or 'the model'} "
                f"does not converge ({values}; residual {r:.3g}): the motion leaves the "
                "workspace or crosses a singularity")
        t1 = time.perf_counter()
        try:
            system = driver.system(q[i])
            _check_drives(model, system, driver.names)
            rhs_v = np.r_[np.zeros(len(system.rows)), Cd[i] / s]
            vi = system.solve(rhs_v)
            ai = system.acceleration(vi, driver.rhs(q[i], vi, Cdd[i]))
            vi, ai = _carry_idle(model, system, q[i], vi, ai,
                                 (v[i - 1], a[i - 1], ti - times[i - 1]) if i else None,
                                 lambda vel, qi=q[i], c=Cdd[i]: driver.rhs(qi, vel, c),
                                 gravity)
        except PkmError as e:
            raise _at_time(e, ti)
        v[i], a[i] = vi, ai
        clock["kinematics"] += t1 - t0
        clock["motion"] += time.perf_counter() - t1
    act = list(model.actuated_v)
    Qa = np.array([model.actuated_values(x) for x in q]).reshape(N, len(act))
    return (q, v, a, Qa, v[:, act].copy(), a[:, act].copy()), clock


def _check_drives(model: ClosureModel, system, names) -> None:
    """A :class:`SingularityError` when the actuators can move with the output
    coordinates still (a motion of ``[J; K]``'s null space that moves one): a type I
    singularity, or coordinates that do not fix the mechanism's motion."""
    if system.idle is None:
        return
    moved = np.abs(system.null[system.act]).max(initial=0.0)
    if moved > 1e-6:
        raise SingularityError(
            f"{model.name or 'the model'}: with the output coordinates "
            f"{', '.join(names)} still an actuator can move: a type I singularity, or a "
            "mechanism with more degrees of freedom than its output's; give its motion as "
            "actuated values", kind="type I", index=0.0)


class _ActuatedSystem:
    """``[J; D]`` at ``q`` (dimensionless rows and coordinates; ``D`` the driven rows:
    the actuated coordinates ``S``, or ``driven`` (k × nv, dimensionless coordinate per
    unit of each velocity coordinate), the output's coordinates), its SVD and the idle
    motions (its null space: ``idle``, (nv, k) physical directions, or None)."""

    def __init__(self, model: ClosureModel, q: np.ndarray, driven=None):
        self.model, self.q = model, q
        self.units, self.rows = model.velocity_units, dynamics.row_units(model)
        zero = np.zeros(model.nv)
        J, _, _ = dynamics.closure_acceleration(model, q, zero, zero)
        self.act = list(model.actuated_v)
        if driven is None:
            driven = np.zeros((len(self.act), model.nv))
            driven[np.arange(len(self.act)), self.act] = 1.0 / self.units[self.act]
        self.H = H = np.vstack([J / self.rows[:, None], driven]) * self.units
        self.rank, self.Us, self.sv, self.Vt = screws.svd_rank(H, RANK_RTOL)
        self.null = self.Vt[self.rank:].T
        self.idle = self.units[:, None] * self.null if self.rank < model.nv else None

    def carry(self, v: np.ndarray, v_pred: np.ndarray) -> np.ndarray:
        """``v`` (minimum-norm, from the driven rates) plus the idle part of
        ``v_pred`` (the previous sample's velocity stepped by the idle dynamics)."""
        N, U = self.null, self.units
        return v + U * (N @ (N.T @ ((v_pred - v) / U)))

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """The minimum-norm physical ``x`` of ``[J; D] x = rhs`` (dimensionless rows)."""
        r = self.rank
        return self.units * (self.Vt[:r].T @ ((self.Us[:, :r].T @ rhs) / self.sv[:r]))

    def acceleration(self, v: np.ndarray, driven_rhs: np.ndarray) -> np.ndarray:
        """The minimum-norm (dimensionless) ``a`` of ``[J; D] a = [−J̇ v; driven_rhs]``
        (``driven_rhs``: dimensionless, e.g. ``q̈_a / s_a``)."""
        model = self.model
        _, _, drift = dynamics.closure_acceleration(model, self.q, v, np.zeros(model.nv))
        return self.solve(np.r_[-drift / self.rows, driven_rhs])


def _inverse_dynamics(model: ClosureModel, q, v, a, g, w) -> dynamics.InverseDynamics:
    """:func:`dynamics.inverse_dynamics`; when its consistency check refuses the motion,
    the motion is accepted if its closure residuals are at round-off of the norms
    (``|J v| ≤ tol ‖J‖ ‖v‖``, ``|J a + J̇ v| ≤ tol (‖J‖ ‖a‖ + |J̇ v| + |g| / L)``, rows
    and coordinates dimensionless, ``tol`` :data:`MOTION_CONSISTENCY_RTOL`): the check
    of :mod:`~pkm_pin.dynamics` scales each row by its own entries, too strict when a
    joint moves without entering the closure rows at all (a rod spinning about its
    axis, its column of ``J`` at round-off)."""
    try:
        return dynamics.inverse_dynamics(model, q, v, a, gravity=g, wrench=w)
    except InconsistentMotion as e:
        if e.kind not in ("velocity", "acceleration"):
            raise
        units, rows = model.velocity_units, dynamics.row_units(model)
        J, rdd, drift = dynamics.closure_acceleration(model, q, v, a)
        Jd = J / rows[:, None] * units
        norm = float(np.linalg.norm(Jd, 2))
        rv = float(np.linalg.norm(Jd @ (v / units)))
        ra = float(np.linalg.norm(rdd / rows))
        if rv > MOTION_CONSISTENCY_RTOL * norm * np.linalg.norm(v / units) or \
                ra > MOTION_CONSISTENCY_RTOL * (norm * np.linalg.norm(a / units)
                                                + np.linalg.norm(drift / rows)
                                                + np.linalg.norm(g) / model.length):
            raise
        return dynamics.inverse_dynamics(model, q, v, a, gravity=g, wrench=w, tol=np.inf)


def _mass_notes(model: ClosureModel, massless: list, payload) -> list[str]:
    """Notes on the model's masses; an :class:`InputError` (naming the bodies) when no
    body has a mass and no payload is given: its efforts would all be zero."""
    if len(massless) < len(body_names(model)):
        return []
    listing = ", ".join(massless[:8]) + (f" and {len(massless) - 8} more"
                                         if len(massless) > 8 else "")
    if payload is None:
        raise InputError(
            f"{model.name or 'the model'} has no mass on any body ({listing}): its "
            "efforts would all be zero; give the bodies their inertias in the file "
            "(URDF <inertial>, MJCF <inertial>/geoms), or a payload to size the "
            "actuators for the payload alone")
    return [f"no body of {model.name or 'the model'} has a mass: the efforts are the "
            "payload's alone (no inertia, no gravity of the links)"]


def _sample_times(motion, samples: int, times) -> np.ndarray:
    """The times of a study: ``times`` (checked increasing), or ``samples`` uniform over
    the motion, both ends included."""
    if times is None:
        samples = int(samples)
        if samples < 2:
            raise InputError(f"samples must be at least 2, got {samples}")
        return np.linspace(motion.start, motion.stop, samples)
    times = screws.as_float_array(times, "times").ravel()
    if times.size < 2 or not np.all(np.diff(times) > 0):
        raise InputError("times must be at least 2 increasing values")
    return times


def _efforts_along(model: ClosureModel, times, q, v, a, g, f) -> tuple:
    """The actuated efforts at each sample (N × actuated), and the part the payload ``f``
    (force and moment at the output's origin, world axes) adds, by
    :func:`dynamics.inverse_dynamics_batch` (one compiled pass over the samples); where it
    refuses a sample's motion as inconsistent, sample by sample with the normwise check
    of :func:`_inverse_dynamics`. Errors carry the sample's time."""
    N, n = times.size, len(model.actuated)
    W = None
    if f is not None:  # the payload's wrench about the world origin
        out, data = model.tree.getFrameId(model.output), model.tree.createData()
        W = np.empty((N, 6))
        for i in range(N):
            pin.framesForwardKinematics(model.tree, data, q[i])
            W[i] = screws.from_point(np.r_[f[:3], f[3:]], data.oMf[out].translation)
    try:
        b = dynamics.inverse_dynamics_batch(model, q, v, a, gravity=g, wrenches=W)
        return b.efforts, b.payload_efforts
    except InconsistentMotion as e:
        if e.kind not in ("velocity", "acceleration"):
            raise _at_sample(e, times)
    except PkmError as e:
        raise _at_sample(e, times)
    efforts, from_payload = np.empty((N, n)), np.zeros((N, n))
    for i in range(N):
        try:
            r = _inverse_dynamics(model, q[i], v[i], a[i], g, None if W is None else W[i])
        except PkmError as e:
            raise _at_time(e, times[i])
        efforts[i], from_payload[i] = r.efforts, r.payload_efforts
    return efforts, from_payload


def study(mech, motion=None, *, samples: int = DEFAULT_SAMPLES, times=None,
          duration: float = DEFAULT_DURATION, gravity=dynamics.GRAVITY, payload=None,
          q0=None) -> TrajectoryStudy:
    """Efforts, speeds and powers of each actuator along a motion.

    Args:
        mech: A :class:`~pkm_pin.Mechanism`, :class:`~pkm_pin.linkage.Linkage` or
            :class:`ClosureModel` (:func:`closure_model_of`).
        motion: A :class:`SplineMotion`, :class:`SineMotion` (or any callable ``times ->
            (q_a, q̇_a, q̈_a)`` with ``start``/``stop``), an :class:`OutputMotion` (output
            coordinates over time, :func:`pose_motion`), a CSV path (:func:`read_csv`:
            actuated or output columns), or ``None``: :func:`default_motion` over
            ``duration``.
        samples: Number of times, uniform over the motion (both ends), ≥ 2.
        times: The times instead (increasing).
        gravity: [m/s²], world axes.
        payload: ``(fx, fy, fz, mx, my, mz)`` [N, N m] applied to the output frame at its
            origin, world axes (module docstring), or None.
        q0: A configuration of the tree to start the forward kinematics from (default
            the mechanism's home).

    Raises:
        InputError: bad arguments; a model with no mass on any body and no payload
            (naming the bodies).
        ForwardKinematicsError, SingularityError, InconsistentMotion: as :func:`motion_states`
            and :func:`pkm_pin.dynamics.inverse_dynamics`, with the sample's time.
    """
    start_clock = time.perf_counter()
    model, home = closure_model_of(mech)
    q0 = home if q0 is None else model.check_q(q0)
    g = screws.as_vector3(gravity, "gravity")
    f = None if payload is None else screws.as_vector(payload, 6, "payload",
                                                         "fx, fy, fz, mx, my, mz")
    massless = massless_bodies(model)
    notes = _mass_notes(model, massless, f)
    if motion is None:
        motion = default_motion(model, q0, duration)
    elif isinstance(motion, (str, Path)):
        motion = read_csv(motion, model.actuated)
    times = _sample_times(motion, samples, times)
    (q, v, a, Qa, Qd, Qdd), clock = motion_states(model, motion, times, q0, gravity=g)
    N = times.size
    t0 = time.perf_counter()
    efforts, from_payload = _efforts_along(model, times, q, v, a, g, f)
    clock["dynamics"] = time.perf_counter() - t0
    timing = {k: x / N for k, x in clock.items()}
    timing["total"] = time.perf_counter() - start_clock
    tree = model.tree
    units = tuple("m" if model.translating[tree.joints[tree.getJointId(j)].idx_v]
                  else "rad" for j in model.actuated)
    return TrajectoryStudy(
        t=times, q=q, v=v, a=a, q_actuated=Qa, speeds=Qd, accelerations=Qdd,
        efforts=efforts, payload_efforts=from_payload, actuated=tuple(model.actuated),
        units=units, gravity=g, payload=f, motion=motion.describe() if hasattr(
            motion, "describe") else type(motion).__name__,
        massless_bodies=tuple(massless), notes=tuple(notes), timing=timing)
