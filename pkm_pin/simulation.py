"""Forward dynamics of a closed-loop mechanism (issue 26, item 4): a simulation from
actuator efforts, as a feature and as a witness of :mod:`pkm_pin.dynamics`.

Written on the :class:`~pkm_pin.model.ClosureModel` (one Pinocchio tree plus closures),
like the inverse dynamics; ``q, v, a`` in the order of its tree (Pinocchio's tangent
space), efforts in its ``actuated`` order, entering the generalized forces at
:attr:`ClosureModel.actuated_v` (``τ_tree = Sᵀ τ``). docs/dynamics.md, "Forward
dynamics", states the equations and what is checked.

The constrained acceleration at ``(q, v)`` under the efforts ``τ`` solves

    M a + h(q, v) = Sᵀ τ + Jᵀ μ,       J a = −J̇ v − K_d J v − K_p φ(q)

(``μ = −λ``, :mod:`pkm_pin.dynamics`'s closure forces), the second line Baumgarte's
stabilisation of the closures ``φ`` (physical rows, :func:`pkm_pin.dynamics.row_units`):
the drift obeys ``φ̈ + K_d φ̇ + K_p φ = 0``. Two solvers:

* ``"pinocchio"``: ``pin.constraintDynamics`` with every closure a
  ``RigidConstraintModel`` (point: CONTACT_3D, weld: CONTACT_6D, LOCAL; joint placements
  = frame placement · constraint placement) whose Baumgarte corrector has the gains
  ``(K_p, K_d)``; proximal solver to 1e-12. For models whose closures are all points and
  welds and that have no mimic joint (``constraintDynamics`` refuses them).
* ``"kkt"``: our own rows (the closure Jacobian and ``J̇ v`` of
  :func:`pkm_pin.dynamics.closure_acceleration`) in the KKT system, solved by least
  squares on dimensionless unknowns (minimum norm over redundant closure rows: ``a`` is
  unique, ``μ`` is not). Every closure kind, the revolute (5D) one included.

``"auto"`` takes ``"pinocchio"`` where it applies, else ``"kkt"``.

Integration (``integrator``): ``"rk4"`` (default), the classical Runge–Kutta tableau
in the Munthe-Kaas form: the stages at ``q ⊕ θ_i`` (``pin.integrate``), each stage's
velocity brought back to ``q``'s tangent space by the inverse of
``pin.dIntegrate(q, θ_i)`` (the ``dexp⁻¹`` of a free flyer or a spherical joint; the
identity on revolute and prismatic joints), the step ``q ⊕ dt Σ b_i k_i``; fourth order
on every joint. ``v`` is a plain vector (``a = dv/dt`` in Pinocchio's coordinates).
``"semi-implicit"``: symplectic Euler, ``v ← v + dt a``, ``q ← q ⊕ dt v``.

Energy balance: ``E = T + V`` (``T = ½ vᵀ M v``, ``V = −Σ m_j g · c_j``, the gravity
asked for) against the work of the efforts ``W = ∫ τ · q̇_a dt``,
integrated by the same integrator as the state; the report is ``max_k |E_k − E_0 − W_k|``
over ``max_k (T_k + |V_k − V_0| + |W_k|)``. The closure forces do work ``μᵀ J v``, zero
up to the drift.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pinocchio as pin

from . import dynamics, screws
from .errors import InputError, SimulationError
from .model.closure_model import ClosureModel
from .tolerances import ASSEMBLY_CHECK_RTOL, MOTION_CONSISTENCY_RTOL, RANK_RTOL

#: Default gravity [m/s²] (world z up).
GRAVITY = dynamics.GRAVITY
#: Default Baumgarte natural frequency, as a fraction of the step rate: ``ω = 1/(20 dt)``,
#: ``K_p = ω²``, ``K_d = 2ω`` (critically damped; the drift decays in ~ 20 steps).
BAUMGARTE_STEPS = 20.0
#: Largest number of steps of one simulation.
MAX_STEPS = 1_000_000
METHODS = ("auto", "pinocchio", "kkt")
INTEGRATORS = ("rk4", "semi-implicit")


# ------------------------------------------------------------------- controller
@dataclass(frozen=True)
class PD:
    """Joint-space PD control of the actuated joints:
    ``τ = kp (q_a* (t) − q_a) + kd (q̇_a* (t) − q̇_a) + feedforward(t)``.

    Attributes:
        kp: Stiffness, a scalar or one per actuator [N m/rad or N/m].
        kd: Damping, a scalar or one per actuator [N m s/rad or N s/m].
        target: ``q_a*``: an array (n,) (constant) or a callable ``t -> (n,)`` [rad, m].
        target_rate: ``q̇_a*``: a callable ``t -> (n,)``; default: zero for a constant
            target, else the central difference of ``target`` (h = 1e-6 s).
        feedforward: Optional callable ``t -> (n,)`` added to the efforts.
    """

    kp: object
    kd: object
    target: object
    target_rate: Callable | None = None
    feedforward: Callable | None = None

    def __call__(self, t: float, qa: np.ndarray, qda: np.ndarray) -> np.ndarray:
        n = len(qa)
        if callable(self.target):
            qs = np.asarray(self.target(t), dtype=float)
            if self.target_rate is not None:
                qds = np.asarray(self.target_rate(t), dtype=float)
            else:
                h = 1e-6
                qds = (np.asarray(self.target(t + h), float)
                       - np.asarray(self.target(t - h), float)) / (2 * h)
        else:
            qs = np.asarray(self.target, dtype=float)
            qds = np.zeros(n) if self.target_rate is None else \
                np.asarray(self.target_rate(t), dtype=float)
        tau = np.broadcast_to(np.asarray(self.kp, float), (n,)) * (qs - qa) + \
            np.broadcast_to(np.asarray(self.kd, float), (n,)) * (qds - qda)
        if self.feedforward is not None:
            tau = tau + np.asarray(self.feedforward(t), dtype=float)
        return tau


# ----------------------------------------------------------------------- result
@dataclass(frozen=True)
class Simulation:
    """A simulated motion (:func:`simulate`), one row per sample (every step).

    Attributes:
        t: (N,) times [s].
        q, v, a: (N, nq), (N, nv), (N, nv): the tree's configuration, velocity and the
            constrained acceleration at each sample (``a`` the dynamics' own at
            ``(t, q, v)``: :func:`pkm_pin.dynamics.inverse_dynamics` of ``(q, v, a)``
            gives :attr:`efforts` back).
        efforts: (N, n) actuator efforts at each sample [N m or N], ``actuated`` order.
        actuated: Names of the actuated joints.
        closure_forces: (N, n_rows) λ (what each closure applies to its frame_a's body,
            :mod:`pkm_pin.dynamics`' convention), physical units.
        drift: (N,) closure residual norm (dimensionless rows: m / L, rad).
        velocity_drift: (N,) ``‖J_c v‖`` (dimensionless rows) [1/s].
        kinetic, potential, work: (N,) ``T``, ``V`` [J], the work ``W`` [J] of the
            efforts (and of the wrench, if any).
        energy_error: relative energy balance error (module docstring).
        method: ``"pinocchio"`` or ``"kkt"``; integrator: its name.
        baumgarte: ``(K_p, K_d)`` [1/s², 1/s].
        gravity: (3,) [m/s²].
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    efforts: np.ndarray
    actuated: tuple
    closure_forces: np.ndarray
    drift: np.ndarray
    velocity_drift: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    work: np.ndarray
    energy_error: float
    method: str
    integrator: str
    baumgarte: tuple
    gravity: np.ndarray

    @property
    def max_drift(self) -> float:
        """Largest closure residual over the motion (dimensionless rows)."""
        return float(self.drift.max())

    @property
    def energy(self) -> np.ndarray:
        """(N,) ``T + V`` [J]."""
        return self.kinetic + self.potential


# ------------------------------------------------------------------ the solvers
class _Dynamics:
    """The constrained acceleration of one model under one gravity and gains."""

    def __init__(self, model: ClosureModel, gravity: np.ndarray, gains: tuple, method: str):
        self.model = model
        self.tree = pin.Model(model.tree)
        self.tree.gravity = pin.Motion(gravity, np.zeros(3))
        self.data = self.tree.createData()
        self.kp, self.kd = gains
        self.units = dynamics.row_units(model)
        self.act_v = np.array(model.actuated_v, dtype=int)
        self.method = method
        if method == "pinocchio":
            self._init_pinocchio()

    def _init_pinocchio(self) -> None:
        tree = self.tree
        self.cmodels = pin.StdVec_RigidConstraintModel()
        kinds = {"point": pin.ContactType.CONTACT_3D, "weld": pin.ContactType.CONTACT_6D}
        for c in self.model.closures:
            fa, fb = (tree.frames[tree.getFrameId(n)] for n in (c.frame_a, c.frame_b))
            cm = pin.RigidConstraintModel(kinds[c.kind], tree, fa.parentJoint,
                                          fa.placement * c.placement_a, fb.parentJoint,
                                          fb.placement * c.placement_b, pin.LOCAL)
            cm.m_baumgarte_parameters.Kp = self.kp
            cm.m_baumgarte_parameters.Kd = self.kd
            self.cmodels.append(cm)
        self.cdatas = pin.StdVec_RigidConstraintData()
        for cm in self.cmodels:
            self.cdatas.append(cm.createData())
        pin.initConstraintDynamics(tree, self.data, self.cmodels, self.cdatas)
        self.prox = pin.ProximalSettings(1e-14, 1e-12, 200)

    def full(self, tau_a: np.ndarray) -> np.ndarray:
        tau = np.zeros(self.tree.nv)
        np.add.at(tau, self.act_v, tau_a)
        return tau

    def acceleration(self, q: np.ndarray, v: np.ndarray, tau_a: np.ndarray,
                     extra: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(a, λ)`` at ``(q, v)`` under the actuated efforts ``tau_a`` (plus the
        generalized force ``extra``, (nv,), e.g. a wrench's ``J_oᵀ Δ w``)."""
        tau = self.full(tau_a)
        if extra is not None:
            tau = tau + extra
        if self.method == "pinocchio":
            a = pin.constraintDynamics(self.tree, self.data, q, v, tau,
                                       self.cmodels, self.cdatas, self.prox).copy()
            lam = np.concatenate([_pinocchio_force(c, d) for c, d in
                                  zip(self.model.closures, self.cdatas)]
                                 ) if self.cdatas else np.zeros(0)
            return a, lam
        return self._kkt(q, v, tau)

    def _kkt(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> tuple:
        model, nv = self.model, self.tree.nv
        M = pin.crba(self.tree, self.data, q, pin.Convention.WORLD)
        M = np.triu(M) + np.triu(M, 1).T
        h = pin.rnea(self.tree, self.data, q, v, np.zeros(nv))
        J, _, jdv = dynamics.closure_acceleration(model, q, v, np.zeros(nv))
        phi = self.units * model.closure_residual(q)
        U, s = model.velocity_units, self.units
        Jd = J / s[:, None] * U  # dimensionless rows and columns
        nr = len(s)
        K = np.zeros((nv + nr, nv + nr))
        K[:nv, :nv] = Mu = U[:, None] * M * U
        # the closure rows scaled to the inertia (β): the saddle point's closure
        # eigenvalues ~ σ_J² β² / λ_M are then not lost to rcond when masses are large
        beta = max(float(np.abs(np.diag(Mu)).max(initial=0.0)), 1e-300)
        K[:nv, nv:] = -beta * Jd.T
        K[nv:, :nv] = beta * Jd
        rhs = np.r_[U * (tau - h),
                    beta * (-jdv - self.kd * (J @ v) - self.kp * phi) / s]
        x = np.linalg.lstsq(K, rhs, rcond=RANK_RTOL)[0]
        return U * x[:nv], -beta * x[nv:] / s  # μ = −λ


def _pinocchio_force(c, d) -> np.ndarray:
    """λ of one closure from Pinocchio's contact force (a weld's rows moment-first)."""
    f = d.contact_force.vector
    return f[:3].copy() if c.kind == "point" else np.r_[f[3:], f[:3]]


def _method(model: ClosureModel, method: str) -> str:
    if method not in METHODS:
        raise InputError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    mimic = any(j.shortname() == "JointModelMimic" for j in model.tree.joints)
    pin_ok = not mimic and all(c.kind in ("point", "weld") for c in model.closures)
    if method == "pinocchio" and not pin_ok:
        why = "mimic joints" if mimic else "a revolute (5D) closure"
        raise InputError(f"method 'pinocchio': {model.name or 'the model'} has {why}, "
                         "which pin.constraintDynamics has no model for; use method='kkt' "
                         "or 'auto'")
    if method == "auto":
        return "pinocchio" if pin_ok else "kkt"
    return method


def _gains(baumgarte, dt: float) -> tuple[float, float]:
    """``(K_p, K_d)`` from ``baumgarte``: None (default, ``ω = 1/(20 dt)``), a natural
    frequency ω [1/s] (``K_p = ω²``, ``K_d = 2ω``; 0 turns it off) or a pair."""
    if baumgarte is None:
        w = 1.0 / (BAUMGARTE_STEPS * dt)
        return w * w, 2.0 * w
    if np.ndim(baumgarte) == 0:
        w = float(baumgarte)
        if not np.isfinite(w) or w < 0:
            raise InputError(f"baumgarte must be a natural frequency ≥ 0 [1/s] or a pair "
                             f"(Kp, Kd), got {baumgarte!r}")
        return w * w, 2.0 * w
    kp, kd = (float(x) for x in np.asarray(baumgarte, dtype=float).ravel()[:2])
    if np.size(baumgarte) != 2 or not (np.isfinite([kp, kd]).all() and kp >= 0 and kd >= 0):
        raise InputError(f"baumgarte as a pair must be (Kp ≥ 0 [1/s²], Kd ≥ 0 [1/s]), got "
                         f"{baumgarte!r}")
    return kp, kd


# ----------------------------------------------------------------------- checks
def _check_start(model: ClosureModel, q0, v0) -> tuple[np.ndarray, np.ndarray]:
    q = model.check_q(q0)
    v = np.zeros(model.nv) if v0 is None else screws.as_vector(
        v0, model.nv, "v0", "the tree's velocity coordinates")
    err = float(np.linalg.norm(model.closure_residual(q)))
    if err > ASSEMBLY_CHECK_RTOL:
        raise InputError(f"q0 does not close the loops of {model.name or 'the model'} "
                         f"(relative closure error {err:.3g}, tolerance "
                         f"{ASSEMBLY_CHECK_RTOL:g}); assemble it first")
    U = model.velocity_units
    JU = model.closure_jacobian(q) * U
    r = float(np.linalg.norm(JU @ (v / U)))
    if r > MOTION_CONSISTENCY_RTOL * np.linalg.norm(JU, 2) * np.linalg.norm(v / U):
        raise InputError(f"v0 is not consistent with the closures of "
                         f"{model.name or 'the model'} (‖J v0‖ relative {r:.3g}); give a "
                         "velocity from dynamics.motion_from_actuated")
    return q, v


def _effort_function(model: ClosureModel, efforts, controller) -> Callable:
    """``(t, q, v) -> τ_a`` from ``efforts`` (callable or constant) or ``controller``
    (callable ``(t, q_a, q̇_a)``, e.g. :class:`PD`); zero without either."""
    n, act_v = len(model.actuated), np.array(model.actuated_v, dtype=int)
    if efforts is not None and controller is not None:
        raise InputError("give efforts or controller, not both")
    if controller is not None:
        if not callable(controller):
            raise InputError(f"controller must be callable (t, q_a, qd_a) -> efforts, got "
                             f"{type(controller).__name__}")
        return lambda t, q, v: controller(t, model.actuated_values(q), v[act_v])
    if efforts is None:
        return lambda t, q, v: np.zeros(n)
    if callable(efforts):
        return efforts
    const = screws.as_vector(efforts, n, "efforts", ", ".join(model.actuated))
    return lambda t, q, v: const


def _wrench_function(wrench) -> Callable | None:
    if wrench is None or callable(wrench):
        if wrench is None:
            return None

        def checked(t, q, v):
            w = np.asarray(wrench(t, q, v), dtype=float).reshape(-1)
            if w.shape != (6,) or not np.isfinite(w).all():
                raise InputError(f"the wrench at t = {t:.6g} s must be 6 finite numbers "
                                 f"(f; m_O), got {w!r}")
            return w
        return checked
    const = screws.as_vector(wrench, 6, "wrench", "axis-first (f; m_O)")
    return lambda t, q, v: const


def _call(fn: Callable, n: int, t: float, q, v, names) -> np.ndarray:
    tau = np.asarray(fn(t, q, v), dtype=float).reshape(-1)
    if tau.shape != (n,) or not np.isfinite(tau).all():
        raise InputError(f"the efforts at t = {t:.6g} s must be {n} finite numbers "
                         f"({', '.join(names)}), got {tau!r}")
    return tau


def _steps(duration: float, dt: float) -> int:
    duration, dt = float(duration), float(dt)
    if not (np.isfinite(duration) and duration > 0 and np.isfinite(dt) and dt > 0):
        raise InputError(f"duration and dt must be positive [s], got {duration!r}, {dt!r}")
    n = int(round(duration / dt))
    if n < 1 or n > MAX_STEPS:
        raise InputError(f"duration / dt must give 1 … {MAX_STEPS} steps, got "
                         f"{duration / dt:.6g}")
    return n


# ------------------------------------------------------------------ simulation
def simulate(model: ClosureModel, q0, v0=None, duration: float = 1.0, dt: float = 1e-3, *,
             efforts=None, controller=None, gravity=GRAVITY, wrench=None,
             baumgarte=None, method: str = "auto", integrator: str = "rk4") -> Simulation:
    """Simulate the closed-loop dynamics from ``(q0, v0)`` over ``duration`` [s].

    Args:
        model: The closure model (inertias from its tree).
        q0: (nq,) start configuration, closing the loops.
        v0: (nv,) start velocity, consistent with the closures (default rest).
        duration, dt: Length of the motion and the time step [s] (``round(duration/dt)``
            steps; every step is a sample).
        efforts: Actuator efforts: a callable ``(t, q, v) -> (n,)`` or a constant (n,)
            [N m or N], ``model.actuated`` order.
        controller: Instead of ``efforts``: a callable ``(t, q_a, q̇_a) -> (n,)``, e.g.
            :class:`PD`. Neither: the mechanism moves under gravity alone.
        gravity: (3,) [m/s²], world axes.
        wrench: What the environment applies to the output frame, axis-first ``(f;
            m_O)`` about the world origin [N; N m] (:func:`pkm_pin.dynamics.
            inverse_dynamics`' convention; a point output takes ``f`` at the point): a
            constant (6,) or a callable ``(t, q, v) -> (6,)``. Its power ``(J_o v)ᵀ Δ w``
            counts in :attr:`Simulation.work`.
        baumgarte: Drift stabilisation: None (default ``ω = 1/(20 dt)``), a natural
            frequency ω [1/s] (``K_p = ω², K_d = 2ω``; 0: none) or ``(K_p, K_d)``.
        method: ``"auto"``, ``"pinocchio"`` (``pin.constraintDynamics``) or ``"kkt"``
            (our own closure rows), module docstring.
        integrator: ``"rk4"`` or ``"semi-implicit"``.

    Returns:
        :class:`Simulation`.

    Raises:
        InputError: bad arguments, ``q0`` open, ``v0`` inconsistent, efforts of the
            wrong size, no mass on any body.
        SimulationError: a non-finite state.
    """
    dynamics.check_inertias(model)  # the masses forward dynamics reads (InertiaError)
    q, v = _check_start(model, q0, v0)
    if not any(I.mass > 0 for I in model.tree.inertias):
        raise InputError(f"{model.name or 'the model'} has no mass on any body: its "
                         "dynamics is not defined; give the bodies inertias (the file's "
                         "<inertial>)")
    n_steps = _steps(duration, dt)
    if integrator not in INTEGRATORS:
        raise InputError(f"integrator must be one of {', '.join(INTEGRATORS)}, got "
                         f"{integrator!r}")
    g = screws.as_vector3(gravity, "gravity")
    gains = _gains(baumgarte, dt)
    dyn = _Dynamics(model, g, gains, _method(model, method))
    fn = _effort_function(model, efforts, controller)
    n, act_v, names = len(model.actuated), dyn.act_v, model.actuated

    load = _wrench_function(wrench)

    def rates(t, q, v):
        tau = _call(fn, n, t, q, v, names)
        extra, power = None, float(tau @ v[act_v])
        if load is not None:
            w = screws.DELTA @ load(t, q, v)
            Jo = model.output_jacobian(q)
            extra, power = Jo.T @ w, power + float((Jo @ v) @ w)
        a, lam = dyn.acceleration(q, v, tau, extra)
        if not np.isfinite(a).all():
            raise SimulationError(f"non-finite acceleration at t = {t:.6g} s "
                                  f"({model.name or 'the model'}): a singular "
                                  "configuration, or a time step too large")
        return a, power, tau, lam

    rec = _Recorder(n_steps + 1, model, n)
    with np.errstate(all="ignore"):  # a diverging motion: SimulationError, no warning
        _run(model, rates, rec, q, v, n_steps, dt, integrator)
    return rec.result(dyn, g, gains, integrator)


def _run(model, rates, rec, q, v, n_steps, dt, integrator) -> float:
    """The time steps, each sample recorded; the final work."""
    W = 0.0
    for k in range(n_steps + 1):
        t = k * dt
        a, p, tau, lam = rates(t, q, v)
        rec.add(k, t, q, v, a, tau, lam, W)
        if k == n_steps:
            break
        step = _rk4 if integrator == "rk4" else _semi_implicit
        q, v, W = step(model.tree, rates, t, q, v, W, dt, (a, p))
    return W


def _rk4(tree, rates, t, q, v, W, dt, first):
    """One Runge–Kutta–Munthe-Kaas step: the stages' configurations ``q ⊕ θ_i``, each
    stage's velocity taken back to ``q``'s tangent space through ``dIntegrate``
    (``θ̇ = (∂(q ⊕ θ)/∂θ)⁻¹ v``: the ``dexp⁻¹`` of a free flyer or a spherical joint,
    the identity on vector-space joints); ``v`` and ``W`` are plain vectors."""
    a1, p1 = first
    lie = tree.nq != tree.nv

    def back(theta, vs):
        if not lie:
            return vs
        return np.linalg.solve(pin.dIntegrate(tree, q, theta, pin.ArgumentPosition.ARG1), vs)

    th2, v2 = 0.5 * dt * v, v + 0.5 * dt * a1
    a2, p2, *_ = rates(t + 0.5 * dt, pin.integrate(tree, q, th2), v2)
    k2 = back(th2, v2)
    th3, v3 = 0.5 * dt * k2, v + 0.5 * dt * a2
    a3, p3, *_ = rates(t + 0.5 * dt, pin.integrate(tree, q, th3), v3)
    k3 = back(th3, v3)
    th4, v4 = dt * k3, v + dt * a3
    a4, p4, *_ = rates(t + dt, pin.integrate(tree, q, th4), v4)
    k4 = back(th4, v4)
    qn = pin.integrate(tree, q, dt / 6 * (v + 2 * k2 + 2 * k3 + k4))
    return qn, v + dt / 6 * (a1 + 2 * a2 + 2 * a3 + a4), W + dt / 6 * (p1 + 2 * p2 + 2 * p3 + p4)


def _semi_implicit(tree, rates, t, q, v, W, dt, first):
    a, p = first
    vn = v + dt * a
    return pin.integrate(tree, q, dt * vn), vn, W + dt * p


def _energies(tree: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray,
              g: np.ndarray) -> tuple[float, float]:
    """``T = ½ vᵀ M v`` (``crba``) and ``V = −Σ m_j g · c_j`` (the bodies' centres of mass
    from ``forwardKinematics``) [J]: written out because Pinocchio's energy functions
    refuse mimic joints."""
    M = pin.crba(tree, data, q, pin.Convention.WORLD)
    M = np.triu(M) + np.triu(M, 1).T
    pin.forwardKinematics(tree, data, q)
    V = 0.0
    for j in range(1, tree.njoints):
        inertia = tree.inertias[j]
        if inertia.mass > 0:
            V -= inertia.mass * float(g @ (data.oMi[j].act(inertia.lever)))
    return 0.5 * float(v @ M @ v), V


class _Recorder:
    """The arrays of a :class:`Simulation`, filled sample by sample."""

    def __init__(self, N: int, model: ClosureModel, n: int):
        self.model = model
        self.t = np.zeros(N)
        self.q, self.v = np.zeros((N, model.nq)), np.zeros((N, model.nv))
        self.a, self.tau = np.zeros((N, model.nv)), np.zeros((N, n))
        self.lam = np.zeros((N, model.n_rows))
        self.W = np.zeros(N)

    def add(self, k, t, q, v, a, tau, lam, W) -> None:
        if not (np.isfinite(q).all() and np.isfinite(v).all()):
            raise SimulationError(f"non-finite state at t = {t:.6g} s: the time step is too "
                                  "large for this motion")
        self.t[k], self.q[k], self.v[k], self.a[k] = t, q, v, a
        self.tau[k], self.lam[k], self.W[k] = tau, lam, W

    def result(self, dyn: _Dynamics, g, gains, integrator) -> Simulation:
        model, tree, data = self.model, dyn.tree, dyn.data
        N = len(self.t)
        T, V = np.zeros(N), np.zeros(N)
        drift, vdrift = np.zeros(N), np.zeros(N)
        for k in range(N):
            q, v = self.q[k], self.v[k]
            T[k], V[k] = _energies(tree, data, q, v, g)
            drift[k] = np.linalg.norm(model.closure_residual(q))
            vdrift[k] = np.linalg.norm(model.closure_jacobian(q) @ v)
        e = T + V - T[0] - V[0] - self.W
        scale = max(float(np.max(np.abs(T) + np.abs(V - V[0]) + np.abs(self.W))), 1e-300)
        return Simulation(
            t=self.t, q=self.q, v=self.v, a=self.a, efforts=self.tau,
            actuated=tuple(model.actuated), closure_forces=self.lam, drift=drift,
            velocity_drift=vdrift, kinetic=T, potential=V, work=self.W,
            energy_error=float(np.abs(e).max() / scale), method=dyn.method,
            integrator=integrator, baumgarte=tuple(gains), gravity=g)


# ------------------------------------------------------------ replay of a study
def _payload_wrench(model: ClosureModel, payload) -> Callable | None:
    """``(f; m)`` at the output's origin, world axes → ``(f; m + p × f)`` about the world
    origin at each state."""
    if payload is None:
        return None
    fm = screws.as_vector(payload, 6, "payload", "fx, fy, fz, mx, my, mz")

    def wrench(t, q, v):
        p = model.kinematics(q).output_placement.translation
        return np.r_[fm[:3], fm[3:] + np.cross(p, fm[:3])]
    return wrench

@dataclass(frozen=True)
class Replay:
    """A motion given by its samples and efforts, simulated back (:func:`replay`).

    Attributes:
        simulation: The :class:`Simulation` (its times from 0).
        tracking_error: (n,) largest ``|q_a,sim − q_a,ref|`` over the samples [rad or m].
        kp, kd: (n,) the PD gains used.
        bandwidth: the PD's natural frequency [Hz].
    """

    simulation: Simulation
    tracking_error: np.ndarray
    kp: np.ndarray
    kd: np.ndarray
    bandwidth: float


def replay(model: ClosureModel, t, q0, v0, q_actuated, speeds, efforts, *,
           dt: float | None = None, bandwidth: float = 2.0, gravity=GRAVITY, payload=None,
           method: str = "auto") -> Replay:
    """Simulate a motion known by its samples (a trajectory study: times ``t`` (N,), the
    start ``(q0, v0)``, actuated values and rates (N, n), efforts (N, n)) with the
    efforts as feedforward (linear in time between samples) plus a PD on the actuated
    joints towards the samples (cubic Hermite in time), gains below, ``f`` =
    ``bandwidth`` [Hz] (0: feedforward alone). ``dt`` default: a tenth of the samples'
    spacing. ``payload``: ``(f; m)`` on the output at its origin, world axes (as
    :func:`pkm_pin.trajectory.study`'s). The tracking error witnesses that the forward
    dynamics reproduces the motion the inverse dynamics was asked for.

    Decision, gains: one stiffness for every actuator from the smallest eigenvalue
    ``λ_min`` of the scaled actuator inertia ``Λ̃`` at the start,
    ``kp_i = λ_min (2π f)² / Uₐ,i²``, ``kd_i = 2 λ_min (2π f) / Uₐ,i²`` (``Uₐ`` the
    length for a prismatic actuator): the stiffest closed-loop mode stays near ``f``
    where the inertia is smallest (gains on the diagonal of ``Λ`` made Gepetto's 5-bar,
    whose inertia falls 13× along its default motion, too stiff for the step)."""
    from scipy.interpolate import CubicHermiteSpline

    from .dynamic_indices import dynamic_indices

    t = screws.as_float_array(t, "t").reshape(-1)
    n = len(model.actuated)
    Qa, Qd, F = (screws.as_float_array(x, name) for x, name in
                 ((q_actuated, "q_actuated"), (speeds, "speeds"), (efforts, "efforts")))
    for x, name in ((Qa, "q_actuated"), (Qd, "speeds"), (F, "efforts")):
        if x.shape != (len(t), n):
            raise InputError(f"{name} must have shape ({len(t)}, {n}) (one row per time, "
                             f"{', '.join(model.actuated)}), got {x.shape}")
    if len(t) < 2 or not np.all(np.diff(t) > 0):
        raise InputError("t must hold at least 2 strictly increasing times")
    dt = float(np.min(np.diff(t))) / 10.0 if dt is None else float(dt)
    ind = dynamic_indices(model, q0)
    ua = np.where(np.array(ind.units) == "m", model.length, 1.0)
    lam = max(float(ind.eigenvalues[0]), 0.0) / ua ** 2 if n else np.zeros(0)
    w = 2.0 * np.pi * float(bandwidth)
    kp, kd = lam * w * w, 2.0 * lam * w
    ref = CubicHermiteSpline(t, Qa, Qd, axis=0)
    t0 = t[0]
    pd = PD(kp, kd, target=lambda s: ref(s + t0), target_rate=lambda s: ref(s + t0, 1),
            feedforward=lambda s: np.array([np.interp(s + t0, t, F[:, k]) for k in range(n)]))
    sim = simulate(model, q0, v0, t[-1] - t0, dt, controller=pd, gravity=gravity,
                   wrench=_payload_wrench(model, payload), method=method)
    qa = np.array([model.actuated_values(q) for q in sim.q])
    at = np.column_stack([np.interp(t - t0, sim.t, qa[:, k]) for k in range(n)])
    return Replay(simulation=sim, tracking_error=np.abs(at - Qa).max(axis=0), kp=kp, kd=kd,
                  bandwidth=float(bandwidth))
