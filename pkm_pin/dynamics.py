"""Closed-loop inverse dynamics of a :class:`~pkm_pin.model.ClosureModel` (issue 26).

Written once on the closure model (one Pinocchio tree plus closures), so every
mechanism — a base–legs–platform machine through :attr:`Mechanism.closure_model`, an
Extended URDF, an MJCF file, a pinned TOML — gets it. docs/dynamics.md derives and
checks what follows.

Equations (``v, a`` the tree's velocity and acceleration in Pinocchio's tangent space,
``τ_tree = rnea(q, v, a)`` with the gravity asked for):

* closures, in **physical units** (not the dimensionless rows of
  :meth:`ClosureModel.closure_residual`): ``φ(q)`` = the point rows [m] (``C_b``'s origin
  in ``C_a``), the revolute axis rows (x, y of ``C_b``'s z in ``C_a``, dimensionless),
  the weld rows ``log6(C_a⁻¹ C_b) = (θ [rad]; ρ [m])``; ``J = dφ/dv`` is
  :meth:`~ClosureModel.closure_jacobian` with its translation rows multiplied by the
  characteristic length (:func:`row_units`). A motion is consistent when ``J v = 0``
  and ``J a + J̇ v = 0`` (:func:`closure_acceleration`);
* balance: ``τ_tree − J_oᵀ Δ w + Jᵀ λ = Sᵀ τ``: ``S`` selects the actuated velocity
  coordinates (``τ`` in :attr:`ClosureModel.actuated` order), ``w = (f; m_O)`` the
  wrench the environment applies to the output frame (axis-first, about the world
  origin; ``J_o`` the output Jacobian, ``Δ`` :data:`pkm_pin.screws.DELTA`), ``λ`` the
  closure forces: **λ is what the closure applies to frame_a's body** (``Jᵀλ`` is the
  generalized force of ``+λ`` on ``frame_a``'s body and ``−λ`` on ``frame_b``'s, so the
  tree's equation of motion reads ``τ_tree = Sᵀτ − Jᵀλ + J_oᵀΔw``). Per closure
  kind, λ is conjugate to its physical rows: a point closure's three rows are the force
  [N] in ``C_a`` axes at ``C_b``'s origin; a weld's six rows ``(moment [N m]; force [N])``
  in ``C_b`` axes at its origin (``Jlog6 = I`` at a closed weld); a revolute's point rows
  as a point's, its two axis rows ``(λ_x, λ_y)`` [N m] the couple ``z_b × (λ_x, λ_y, 0)``
  = ``(−λ_y, λ_x, 0)`` in ``C_a`` axes (at a closed revolute) that keeps the axes
  aligned.
* ``(τ, λ)`` by least squares on the dimensionless system ``[Sᵀ, −(J_c U)ᵀ] (Uₐτ; s λ) =
  U (τ_tree − J_oᵀΔw)`` (``U`` :attr:`ClosureModel.velocity_units`, ``s``
  :func:`row_units`, ``J_c`` the dimensionless closure Jacobian): every unknown and
  equation is in N·m, so the minimum norm taken over redundant closure rows and the
  rank decisions do not depend on units. The truncated SVD (rank at
  :data:`~pkm_pin.tolerances.RANK_RTOL`) gives the minimum-norm solution.

Checks, each a clear error: ``q`` must close the loops, ``J v = 0`` and
``J a + J̇ v = 0`` to :data:`~pkm_pin.tolerances.MOTION_CONSISTENCY_RTOL` (an
:class:`~pkm_pin.errors.InconsistentMotion` with the residual per closure); a motion of
the tree that the closures allow with every actuator still and that moves the output
(a type II singularity, also near one: singular value ratio below
:data:`~pkm_pin.tolerances.CLOSENESS_SINGULAR_TOL`) makes the efforts unbounded: a
:class:`~pkm_pin.errors.SingularityError`; an idle motion (the output still) along which
the motion needs a generalized force that neither an actuator nor a closure gives: an
:class:`~pkm_pin.errors.InconsistentMotion` naming the joints that move in it.

``J̇ v`` comes from Pinocchio: the spatial accelerations of the closures' bodies
(``rnea``'s forward pass, or ``forwardKinematics`` with ``a``) give each closure's
second derivative ``J a + J̇ v`` exactly (the rows' own product rule, below); ``J̇ v`` is
that minus ``J a``. For a weld the second derivative is taken as ``Jlog6(M) ν̇`` (``ν``
the body twist of ``C_b`` relative to ``C_a``): the neglected ``(d/dt Jlog6) ν`` is
``O(|log M| |ν|²)``, zero on a closed weld since ``ad(ν) ν = 0``.

Gravity is set per call on a private copy of the tree kept per thread (Pinocchio reads
the gravity from the ``Model``, not the ``Data``): the shared model is never modified
and threads do not share working data.
"""

from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numba import njit
from numba.extending import register_jitable

from . import screws
from .compiling import prefer_compiled
from .errors import InconsistentMotion, InertiaError, InputError, SingularityError
from .model.closure_model import KINDS, ClosureModel, TreeKinematics
from .tolerances import (
    ASSEMBLY_CHECK_RTOL,
    CLOSENESS_SINGULAR_TOL,
    EFFORT_BALANCE_RTOL,
    MOTION_CONSISTENCY_RTOL,
    RANK_RTOL,
)

#: Default gravity [m/s²] (world z up).
GRAVITY = (0.0, 0.0, -9.81)


@dataclass(frozen=True)
class InverseDynamics:
    """Efforts and closure forces of one sample of a motion (:func:`inverse_dynamics`).

    Attributes:
        efforts: (n_actuated,) effort of each actuated joint [N m for a revolute, N for a
            prismatic], in :attr:`actuated` order, payload included.
        actuated: Names of the actuated joints (the model's order).
        closure_forces: (n_rows,) λ, in the rows of the closures (closure order,
            :meth:`ClosureModel.closure_slices`), physical units (module docstring):
            what each closure applies to its ``frame_a``'s body.
        redundant_rows: Dimension of the family of ``(efforts, closure forces)`` that
            give the same motion: the closure rows that are dependent at ``q``
            (``n_rows − rank J``), plus actuators that the closures alone can balance
            (redundant actuation). When > 0 the minimum-norm solution is returned (on
            the dimensionless unknowns, module docstring).
        payload_efforts: (n_actuated,) the part of :attr:`efforts` due to ``wrench``
            (zeros without one).
        payload_closure_forces: (n_rows,) the part of :attr:`closure_forces` due to it.
        tree_efforts: (nv,) ``rnea(q, v, a)`` of the tree with the gravity asked for.
        acceleration_residual: (n_rows,) ``J a + J̇ v`` [physical units per s²]: the
            closures' second derivative along the motion (small when consistent).
        drift: (n_rows,) ``J̇ v``, physical units.
        balance_residual: relative residual of the least-squares balance (≈ 1e-15
            when every generalized force is balanced).
        condition: ratio of the largest to the smallest nonzero singular value of the
            balance matrix ``[Sᵀ, −(J_c U)ᵀ]`` (large near a type II singularity).
    """

    efforts: np.ndarray
    actuated: tuple
    closure_forces: np.ndarray
    redundant_rows: int
    payload_efforts: np.ndarray
    payload_closure_forces: np.ndarray
    tree_efforts: np.ndarray
    acceleration_residual: np.ndarray
    drift: np.ndarray
    balance_residual: float
    condition: float

    @property
    def redundant(self) -> bool:
        """The closure forces are a minimum-norm choice (redundant closure rows)."""
        return self.redundant_rows > 0


def row_units(model: ClosureModel) -> np.ndarray:
    """(n_rows,) unit of each closure row: the characteristic length [m] for a
    translation row (point rows, a revolute's first three, a weld's last three), 1 for
    the others; ``row_units * closure_residual`` is the residual in physical units and
    ``row_units[:, None] * closure_jacobian`` the physical ``J``."""
    return _work(model).row_units.copy()


# ---------------------------------------------------------------- working state
class _Work:
    """Per thread and model: a private tree copy (gravity set per call), its Data, and
    the index lists of the closures' two ends."""

    def __init__(self, model: ClosureModel):
        tree = model.tree
        self.inertias_checked = False
        self.tree = pin.Model(tree)
        self.data = self.tree.createData()
        self.C = C = len(model.closures)
        frames = [tree.frames[tree.getFrameId(c.frame_a)] for c in model.closures] + \
                 [tree.frames[tree.getFrameId(c.frame_b)] for c in model.closures]
        places = [c.placement_a for c in model.closures] + \
                 [c.placement_b for c in model.closures]
        self.joints = [f.parentJoint for f in frames]
        #: constraint frame of each end in its joint's frame (2C × 4 × 4)
        self.local = np.array([(f.placement * p).homogeneous for f, p in zip(frames, places)]
                              ).reshape(2 * C, 4, 4)
        ends = np.cumsum([0] + [c.dim for c in model.closures])
        self.n_rows = int(ends[-1])
        self.kinds = {k: np.array([i for i, c in enumerate(model.closures) if c.kind == k],
                                  dtype=int) for k in KINDS}
        self.rows = {k: np.array([np.arange(ends[i], ends[i + 1]) for i in idx], dtype=int
                                 ).reshape(len(idx), KINDS[k]) for k, idx in self.kinds.items()}
        codes = {"point": 0, "revolute": 1, "weld": 2}
        self.kind_codes = np.array([codes[c.kind] for c in model.closures], dtype=np.int64)
        self.first_rows = np.array(ends[:-1], dtype=np.int64)
        units = np.ones(self.n_rows)
        L = model.length
        for kind in ("point", "revolute"):
            units[self.rows[kind][:, :3].ravel()] = L
        units[self.rows["weld"][:, 3:].ravel()] = L
        units.setflags(write=False)
        self.row_units = units
        self.act_v = np.array(model.actuated_v, dtype=int)
        self.names = _velocity_names(tree)

    def set_gravity(self, g: np.ndarray) -> None:
        self.tree.gravity = pin.Motion(g, np.zeros(3))


_LOCAL = threading.local()

#: Relative tolerance of the inertia checks (of the sum of the principal moments): what
#: an exporter's rounding of the moments can make of a thin rod or a flat plate.
INERTIA_RTOL = 1e-6


def body_names(model: ClosureModel) -> list[str]:
    """Name of the body of each joint 1 … njoints − 1 of the tree: its first BODY frame
    (the URDF link), else the joint's name."""
    tree = model.tree
    names = [""] * tree.njoints
    for f in tree.frames:
        if f.type == pin.FrameType.BODY and 0 < f.parentJoint and not names[f.parentJoint]:
            names[f.parentJoint] = f.name
    return [names[j] or tree.names[j] for j in range(1, tree.njoints)]


def check_inertias(model: ClosureModel) -> None:
    """Every body's mass and inertia are a rigid body's, where the dynamics reads them.

    A body is massless (mass 0 and a zero inertia: a link the file gives no inertial
    data) or has a finite mass > 0 [kg] and, about its centre of mass, a finite symmetric
    inertia [kg m²] whose principal moments are ≥ 0 and obey the triangle inequality
    ``I₁ + I₂ ≥ I₃`` (both to :data:`INERTIA_RTOL` of their sum). Zero moments stay
    allowed: a point mass and a thin rod are the idealisations of closed-form models.

    Raises:
        InertiaError: naming the body and the value.
    """
    tree = model.tree
    for j, body in zip(range(1, tree.njoints), body_names(model)):
        inertia = tree.inertias[j]
        m, Ic = float(inertia.mass), np.array(inertia.inertia)
        if m == 0.0 and not Ic.any():
            continue  # massless
        if not (np.isfinite(m) and m > 0.0):
            raise InertiaError(body, "mass", m, "must be finite and > 0" + (
                " (a body with an inertia needs a mass)" if m == 0.0 else ""), f"{m:g} kg")
        _check_rotational_inertia(body, Ic)


def _matrix(Ic: np.ndarray) -> str:
    """A 3 × 3 inertia on one line: ``[[…], […], […]] kg m²``."""
    return str([[float(f"{x:.4g}") for x in row] for row in Ic]) + " kg m²"


def _check_rotational_inertia(body: str, Ic: np.ndarray) -> None:
    """The inertia about the centre of mass: finite, symmetric, moments ≥ 0 with the
    triangle inequality (:func:`check_inertias`)."""
    if not np.all(np.isfinite(Ic)):
        raise InertiaError(body, "inertia", Ic, "must be finite", _matrix(Ic))
    scale = max(float(np.abs(Ic).max()), np.finfo(float).tiny)
    if np.abs(Ic - Ic.T).max() > INERTIA_RTOL * scale:
        raise InertiaError(body, "inertia", Ic, "must be symmetric", _matrix(Ic))
    moments = np.linalg.eigvalsh(Ic)  # ascending
    shown = "with principal moments " + ", ".join(f"{x:.4g}" for x in moments) + " kg m²"
    tol = INERTIA_RTOL * float(np.abs(moments).sum())
    if moments[0] < -tol:
        raise InertiaError(body, "inertia", Ic, "must be positive (semi)definite: a "
                           "moment of inertia cannot be negative", shown)
    if moments[0] + moments[1] < moments[2] - tol:
        raise InertiaError(body, "inertia", Ic, "breaks the triangle inequality "
                           "I1 + I2 >= I3 that every rigid body's principal moments obey",
                           shown)


def _work(model: ClosureModel, masses: bool = False) -> _Work:
    """This thread's working state for ``model`` (made once per thread and model);
    ``masses``: the caller reads the masses, checked first (:func:`check_inertias`, once
    per thread and model)."""
    store = getattr(_LOCAL, "store", None)
    if store is None:
        store = _LOCAL.store = weakref.WeakKeyDictionary()
    work = store.get(model)
    if work is None:
        work = store[model] = _Work(model)
    if masses and not work.inertias_checked:
        check_inertias(model)
        work.inertias_checked = True
    return work


def _velocity_names(tree: pin.Model) -> list[str]:
    """Name of the joint of each velocity coordinate."""
    names = [""] * tree.nv
    for j in range(1, tree.njoints):
        joint = tree.joints[j]
        for k in range(joint.idx_v, joint.idx_v + joint.nv):
            names[k] = tree.names[j]
    return names


# ------------------------------------------------------ closure second derivative
def _second_derivative(work: _Work, Hj: np.ndarray, VA: np.ndarray) -> np.ndarray:
    """``J a + J̇ v`` of every closure row (physical units) from the world placements
    ``Hj`` (2C × 4 × 4) of the ends' joints and their local spatial velocities and
    accelerations ``VA`` (2C × 2 × 6, Pinocchio's linear-first ``(v; ω)``): the
    compiled :func:`closure_second_derivative` (its plain-Python source for the first
    calls of a process, :func:`pkm_pin.compiling.prefer_compiled`), then ``Jlog6`` for
    the welds."""
    out = np.empty(work.n_rows)
    if work.C == 0:
        return out
    nud, Mh = np.zeros((work.C, 6)), np.zeros((work.C, 3, 4))
    kernel = closure_second_derivative
    if not prefer_compiled(kernel):
        kernel = kernel.py_func
    kernel(np.ascontiguousarray(Hj), np.ascontiguousarray(VA), work.local, work.kind_codes,
           work.first_rows, out, nud, Mh)
    idx, rows = work.kinds["weld"], work.rows["weld"]
    for k, i in enumerate(idx):  # Jlog6(M) ν̇
        M = pin.SE3(Mh[i, :, :3], Mh[i, :, 3])
        out[rows[k]] = screws.from_pinocchio(pin.Jlog6(M) @ screws.to_pinocchio(nud[i]))
    return out


@register_jitable
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@register_jitable
def _end(Hj, VA, local, e):
    """World quantities of closure end ``e``: its constraint origin ``p``, velocity,
    classical acceleration, the body's angular velocity and acceleration, and the
    constraint frame's rotation."""
    c = local[e, :3, 3]
    w, dw = VA[e, 0, 3:], VA[e, 1, 3:]
    vc = VA[e, 0, :3] + _cross(w, c)              # local velocity of the origin
    acc = VA[e, 1, :3] + _cross(dw, c) + _cross(w, vc)  # its classical acceleration
    p, pd, pdd = np.zeros(3), np.zeros(3), np.zeros(3)
    W, Wd, Rc = np.zeros(3), np.zeros(3), np.zeros((3, 3))
    for r in range(3):
        p[r] = Hj[e, r, 3]
        for k in range(3):
            R = Hj[e, r, k]
            p[r] += R * c[k]
            pd[r] += R * vc[k]
            pdd[r] += R * acc[k]
            W[r] += R * w[k]
            Wd[r] += R * dw[k]
            Rc[r, k] = Hj[e, r, 0] * local[e, 0, k] + Hj[e, r, 1] * local[e, 1, k] \
                + Hj[e, r, 2] * local[e, 2, k]
    return p, pd, pdd, W, Wd, Rc


@register_jitable
def _transposed(R, x, r):
    """``(Rᵀ x)[r]``."""
    return R[0, r] * x[0] + R[1, r] * x[1] + R[2, r] * x[2]


@njit(cache=True, nogil=True)
def closure_second_derivative(Hj, VA, local, kind, first, out, nud, Mh):
    """The closures' second derivative (module docstring): for closure ``i`` (ends
    ``i`` and ``C + i`` of ``Hj``, ``VA``, ``local``; ``kind[i]`` 0 point, 1 revolute,
    2 weld; rows from ``first[i]``), point and revolute rows into ``out``; for a weld
    ``ν̇`` (axis-first, ``C_b`` axes) into ``nud[i]`` and ``M = C_a⁻¹ C_b`` (3 × 4)
    into ``Mh[i]``, for the caller's ``Jlog6``."""
    C = kind.shape[0]
    for i in range(C):
        pa, pda, pdda, wa, dwa, Ra = _end(Hj, VA, local, i)
        pb, pdb, pddb, wb, dwb, Rb = _end(Hj, VA, local, C + i)
        d, dd, Wr, Wrd = pb - pa, pdb - pda, wb - wa, dwb - dwa
        U = dd - _cross(wa, d)                    # velocity at p_b, relative motion
        Ud = pddb - pdda - _cross(dwa, d) - _cross(wa, dd)
        r0 = first[i]
        if kind[i] < 2:  # d/dt (R_aᵀ U) = R_aᵀ (U̇ − ω_a × U)
            y = Ud - _cross(wa, U)
            for r in range(3):
                out[r0 + r] = _transposed(Ra, y, r)
            if kind[i] == 1:  # d/dt R_aᵀ (W × z_b)
                zb = np.array([Rb[0, 2], Rb[1, 2], Rb[2, 2]])
                x = _cross(Wrd, zb) + _cross(Wr, _cross(wb, zb)) \
                    - _cross(wa, _cross(Wr, zb))
                out[r0 + 3] = _transposed(Ra, x, 0)
                out[r0 + 4] = _transposed(Ra, x, 1)
        else:  # ν = (R_bᵀ W; R_bᵀ U): ν̇ = (R_bᵀ (Ẇ − ω_b × W); R_bᵀ (U̇ − ω_b × U))
            x1, x2 = Wrd - _cross(wb, Wr), Ud - _cross(wb, U)
            for r in range(3):
                nud[i, r] = _transposed(Rb, x1, r)
                nud[i, 3 + r] = _transposed(Rb, x2, r)
                Mh[i, r, 3] = _transposed(Ra, d, r)
                for k in range(3):
                    Mh[i, r, k] = Ra[0, r] * Rb[0, k] + Ra[1, r] * Rb[1, k] \
                        + Ra[2, r] * Rb[2, k]


def _end_motions(work: _Work, data: pin.Data, gravity: np.ndarray | None) -> tuple:
    """``(Hj, VA)`` of the ends' joints from ``data``; ``gravity`` given: ``data``
    holds ``rnea``'s ``a_gf`` (the acceleration minus gravity, local) and ``oMi`` from an
    earlier pass at the same ``q``."""
    js, oMi, V = work.joints, data.oMi, data.v
    A = data.a if gravity is None else data.a_gf
    Hj = np.array([oMi[j].homogeneous for j in js]).reshape(-1, 4, 4)
    VA = np.array([(V[j].vector, A[j].vector) for j in js]).reshape(-1, 2, 6)
    if gravity is not None:
        VA[:, 1, :3] += gravity @ Hj[:, :3, :3]  # + R_jᵀ g
    return Hj, VA


def closure_acceleration(model: ClosureModel, q, v, a) -> tuple[np.ndarray, np.ndarray,
                                                                  np.ndarray]:
    """``(J, J a + J̇ v, J̇ v)`` at ``(q, v, a)``: the physical closure Jacobian
    (n_rows × nv, :func:`row_units`) and the closures' second derivative along the
    motion and its drift, from Pinocchio's ``forwardKinematics(q, v, a)`` (module
    docstring)."""
    q, v, a = _check_motion(model, q, v, a)
    work = _work(model)
    kin = TreeKinematics(model, q, work.data)
    J = work.row_units[:, None] * kin.closure_jacobian
    pin.forwardKinematics(work.tree, work.data, q, v, a)
    rdd = _second_derivative(work, *_end_motions(work, work.data, None))
    return J, rdd, rdd - J @ a


def _check_motion(model: ClosureModel, q, v, a) -> tuple:
    q = model.check_q(q)
    what = "the tree's velocity coordinates"
    v = screws.as_vector(v, model.nv, "v", what)
    a = screws.as_vector(a, model.nv, "a", what)
    return q, v, a


def motion_from_actuated(model: ClosureModel, q, qd_actuated, qdd_actuated
                         ) -> tuple[np.ndarray, np.ndarray]:
    """The tree's velocity ``v`` and acceleration ``a`` at the assembled ``q`` for the
    actuated rates and accelerations [rad/s, m/s; /s²] (model.actuated order):
    ``[J; S] v = [0; q̇_a]``, ``[J; S] a = [−J̇ v; q̈_a]`` (the second order kinematics of
    the closures, ``J̇ v`` as in :func:`closure_acceleration`), solved on the
    dimensionless rows; where idle motions leave ``v`` or ``a`` undetermined, the
    minimum-norm (dimensionless) solution, whose idle acceleration need not be the one
    the dynamics gives.

    Raises:
        SingularityError: at or near a type II singularity (the output can move with
            every actuator still).
        InconsistentMotion: actuated rates the closures do not allow (more actuators
            than degrees of freedom, or a type I singularity).
    """
    q = model.check_q(q)
    n = len(model.actuated)
    qd = screws.as_vector(qd_actuated, n, "qd_actuated", ", ".join(model.actuated))
    qdd = screws.as_vector(qdd_actuated, n, "qdd_actuated", ", ".join(model.actuated))
    work = _work(model)
    kin = TreeKinematics(model, q, work.data)
    _check_closed(model, kin.residual)
    Uv = model.velocity_units
    ua = Uv[work.act_v]
    H = np.zeros((work.n_rows + n, model.nv))
    H[:work.n_rows] = kin.closure_jacobian * Uv
    H[work.n_rows + np.arange(n), work.act_v] = 1.0
    rank, Us, sv, Vt = screws.svd_rank(H, RANK_RTOL)
    _check_free(model, kin, Vt, sv, rank)
    pinv = Vt[:rank].T @ (np.diag(1.0 / sv[:rank]) @ Us[:, :rank].T)

    def solve(rhs: np.ndarray, what: str) -> np.ndarray:
        x = pinv @ rhs
        res = float(np.linalg.norm(H @ x - rhs))
        if res > MOTION_CONSISTENCY_RTOL * max(float(np.linalg.norm(rhs)), 1e-300):
            raise InconsistentMotion(
                f"the actuated {what} of {model.name or 'the model'} are not allowed by "
                f"its closures (relative residual {res / np.linalg.norm(rhs):.3g}): more "
                "actuators than degrees of freedom, or a type I singularity",
                kind=what, residual=H @ x - rhs)
        return Uv * x

    zeros = np.zeros(work.n_rows)
    v = solve(np.r_[zeros, qd / ua], "velocity")
    pin.forwardKinematics(work.tree, work.data, q, v, np.zeros(model.nv))
    drift = _second_derivative(work, *_end_motions(work, work.data, None))
    a = solve(np.r_[-drift / work.row_units, qdd / ua], "acceleration")
    return v, a


def idle_acceleration(model: ClosureModel, q, v, a, *, gravity=GRAVITY,
                      idle: np.ndarray | None = None) -> np.ndarray:
    """``a`` (consistent at ``(q, v)``) with its component along the idle motions (tree
    motions the closures allow with every actuator still: ``[J; S] n = 0``, the columns of
    ``N``) set by the idle joints' own dynamics: ``a + N z`` with ``Nᵀ M N z =
    −Nᵀ rnea(q, v, a)``, so that ``Nᵀ rnea(q, v, a + N z) = 0`` (no actuator and no
    closure force acts along an idle motion; a massless idle direction gets ``z = 0``).
    ``a`` itself where there is no idle motion. :func:`motion_from_actuated`'s
    minimum-norm acceleration followed by this one is an acceleration
    :func:`inverse_dynamics` balances (e.g. a rod spinning about its axis, its centre of
    mass off the axis). ``idle``: the (nv, k) idle motions at ``q`` when the caller
    has them (physical velocity directions), else found here (``[J; S]``'s null space
    on dimensionless rows and coordinates, rank at :data:`RANK_RTOL`)."""
    q, v, a = _check_motion(model, q, v, a)
    g = screws.as_vector3(gravity, "gravity")
    work = _work(model, masses=True)
    if idle is None:
        kin = TreeKinematics(model, q, work.data)
        Uv = model.velocity_units
        n = len(work.act_v)
        H = np.zeros((work.n_rows + n, model.nv))
        H[:work.n_rows] = kin.closure_jacobian * Uv
        H[work.n_rows + np.arange(n), work.act_v] = 1.0
        rank, _, _, Vt = screws.svd_rank(H, RANK_RTOL)
        if rank == model.nv:
            return a
        N = Uv[:, None] * Vt[rank:].T
    else:
        N = np.asarray(idle, dtype=float).reshape(model.nv, -1)
        if N.shape[1] == 0:
            return a
    work.set_gravity(g)
    r = pin.rnea(work.tree, work.data, q, v, a).copy()
    M = pin.crba(work.tree, work.data, q)
    M = np.triu(M) + np.triu(M, 1).T
    z = np.linalg.lstsq(N.T @ M @ N, -(N.T @ r), rcond=RANK_RTOL)[0]
    return a + N @ z


def _check_free(model: ClosureModel, kin: TreeKinematics, Vt: np.ndarray, sv: np.ndarray,
                rank: int) -> None:
    """Raise :class:`SingularityError` when a motion of ``[J; S]``'s (near) null space
    moves the output."""
    smax = sv[0] if len(sv) else 0.0
    p = kin.output_placement.translation
    for k in range(model.nv):
        if k < rank and sv[k] >= CLOSENESS_SINGULAR_TOL * smax:
            continue
        t = kin.output_jacobian @ (model.velocity_units * Vt[k])
        if np.linalg.norm(screws.homogenised_about(t, p, model.length)) > \
                CLOSENESS_SINGULAR_TOL:
            index = (sv[k] / smax) if k < len(sv) and smax else 0.0
            raise SingularityError(
                f"{model.name or 'the model'}: with every actuator still the output can "
                f"move: a type II singularity (at or within {CLOSENESS_SINGULAR_TOL:g}), "
                f"or fewer independent actuators ({len(model.actuated)}) than the output's "
                "degrees of freedom; its motion is not determined by the actuated rates",
                kind="type II", index=float(index))


# ------------------------------------------------------------- inverse dynamics
def inverse_dynamics(model: ClosureModel, q, v, a, *, gravity=GRAVITY, wrench=None,
                     tol: float = MOTION_CONSISTENCY_RTOL) -> InverseDynamics:
    """The actuated efforts and closure forces that produce the motion ``(q, v, a)``.

    Args:
        model: The closure model.
        q: Configuration of the tree (nq,), closing the loops.
        v: Velocity (nv,), ``J v = 0``.
        a: Acceleration (nv,), ``J a + J̇ v = 0``.
        gravity: Gravity [m/s²] in world axes.
        wrench: Wrench the environment applies to the output frame, axis-first
            ``(f; m_O)`` about the world origin [N; N m] (a payload of mass ``m`` at
            ``p``: ``(m g; p × m g)``); for a point output only ``f`` acts, at the point.
        tol: Relative tolerance of the consistency checks (``J v``, ``J a + J̇ v``,
            their size relative to the sizes of their terms).

    Returns:
        :class:`InverseDynamics`.

    Raises:
        InputError: wrong shapes, ``q`` does not close the loops.
        InconsistentMotion: ``v`` or ``a`` violates the closures (with the residual
            per closure), or the motion needs an effort along an idle motion that no
            actuator drives (naming the joints moving in it).
        SingularityError: a type II singularity (at or near): an output motion is
            possible with every actuator still, the efforts are unbounded.
    """
    q, v, a = _check_motion(model, q, v, a)
    g = screws.as_vector3(gravity, "gravity")
    w = None if wrench is None else screws.as_vector(wrench, 6, "wrench",
                                                     "axis-first (f; m_O)")
    work = _work(model, masses=True)
    data = work.data
    kin = TreeKinematics(model, q, data)  # computeJointJacobians: oMi, J
    Jc, Jo = kin.closure_jacobian, kin.output_jacobian
    _check_closed(model, kin.residual)
    Uv = model.velocity_units
    JU = Jc * Uv  # dimensionless
    size_J = np.linalg.norm(JU, 2)  # normwise: a joint that no closure row sees (a rod's
    # spin, its column round-off) moves freely without making its rows' own scale tiny
    _check_rows(model, "velocity", JU @ (v / Uv), size_J * np.linalg.norm(v / Uv), tol,
                work.row_units, "v")
    work.set_gravity(g)
    tau_tree = pin.rnea(work.tree, data, q, v, a).copy()
    rdd = _second_derivative(work, *_end_motions(work, data, g))
    J = work.row_units[:, None] * Jc
    Ja = J @ a
    drift = rdd - Ja
    _check_rows(model, "acceleration", rdd / work.row_units,  # gravity/L: its round-off
                size_J * np.linalg.norm(a / Uv) + np.linalg.norm(drift / work.row_units)
                + np.linalg.norm(g) / model.length, tol, work.row_units, "a")
    # balance  [Sᵀ, −(J_c U)ᵀ] x = U (τ_tree − J_oᵀ Δ w)
    na, nr = len(work.act_v), work.n_rows
    A = np.zeros((model.nv, na + nr))
    A[work.act_v, np.arange(na)] = 1.0
    A[:, na:] = -JU.T
    rank, Us, sv, Vt = screws.svd_rank(A, RANK_RTOL)
    _check_singular(model, work, kin, Us, sv, rank)
    b = Uv * tau_tree
    bw = np.zeros(model.nv) if w is None else -Uv * (Jo.T @ (screws.DELTA @ w))
    b = b + bw
    solve = Vt[:rank].T @ (np.diag(1.0 / sv[:rank]) @ Us[:, :rank].T)
    x, xw = solve @ b, solve @ bw
    res = b - A @ x
    scale = max(np.linalg.norm(b), np.abs(A) .max(initial=0.0) * np.linalg.norm(x), 1e-300)
    balance = float(np.linalg.norm(res) / scale)
    if balance > EFFORT_BALANCE_RTOL:
        _unbalanced(model, work, res, balance)
    act_units = Uv[work.act_v]
    return InverseDynamics(
        efforts=x[:na] / act_units, actuated=tuple(model.actuated),
        closure_forces=x[na:] / work.row_units, redundant_rows=na + nr - rank,
        payload_efforts=xw[:na] / act_units, payload_closure_forces=xw[na:] / work.row_units,
        tree_efforts=tau_tree, acceleration_residual=rdd, drift=drift,
        balance_residual=balance,
        condition=float(sv[0] / sv[rank - 1]) if rank else float("inf"))


def _check_closed(model: ClosureModel, residual: np.ndarray) -> None:
    err = float(np.linalg.norm(residual))
    if err > ASSEMBLY_CHECK_RTOL:
        worst = int(np.argmax(model.closure_norms(residual)))
        raise InputError(f"q does not close the loops of {model.name or 'the model'}: "
                         f"relative closure error {err:.3g} (closure "
                         f"{model.closures[worst].name!r} the worst; tolerance "
                         f"{ASSEMBLY_CHECK_RTOL:g}); assemble it first")


def _check_rows(model: ClosureModel, what: str, r: np.ndarray, size: np.ndarray,
                tol: float, units: np.ndarray, arg: str) -> None:
    """An :class:`InconsistentMotion` when the dimensionless closure rows ``r`` exceed
    ``tol`` times the size of their terms (``size``: normwise, ``‖J‖ ‖v‖`` and the
    like)."""
    err, scale = float(np.linalg.norm(r)), float(np.linalg.norm(size))
    if err <= tol * scale or err == 0.0:
        return
    per = model.closure_norms(r * units)
    worst = int(np.argmax(per))
    listing = ", ".join(f"{c.name or i!r}: {x:.3g}" for i, (c, x) in
                        enumerate(zip(model.closures, per)))
    order = "J v" if what == "velocity" else "J a + J̇ v"
    raise InconsistentMotion(
        f"the {what} {arg} is not consistent with the closures of "
        f"{model.name or 'the model'}: {order} has relative size {err / scale:.3g} "
        f"(tolerance {tol:g}); per closure [physical units]: {listing}; closure "
        f"{model.closures[worst].name!r} the worst. Give {arg} with {order} = 0 "
        "(e.g. from the model's forward kinematics or a constrained solve)",
        kind=what, residual=r * units)


def _check_singular(model: ClosureModel, work: _Work, kin: TreeKinematics,
                    Us: np.ndarray, sv: np.ndarray, rank: int) -> None:
    """Raise :class:`SingularityError` when a motion with every actuator still and the
    closures satisfied (a left singular vector of the balance matrix with a singular
    value zero or below CLOSENESS_SINGULAR_TOL × the largest) moves the output."""
    nv = model.nv
    if rank == nv and sv[-1] >= CLOSENESS_SINGULAR_TOL * sv[0]:
        return
    full = np.zeros(nv)
    full[:len(sv)] = sv
    smax = sv[0] if len(sv) else 0.0
    small = [k for k in range(nv) if k >= rank or full[k] < CLOSENESS_SINGULAR_TOL * smax]
    if not small:
        return
    p = kin.output_placement.translation
    U = model.velocity_units
    for k in small:
        t = kin.output_jacobian @ (U * Us[:, k])
        moved = float(np.linalg.norm(screws.homogenised_about(t, p, model.length)))
        if moved > CLOSENESS_SINGULAR_TOL:
            index = full[k] / smax if smax else 0.0
            raise SingularityError(
                f"{model.name or 'the model'}: with every actuator still the output can "
                f"move (singular value ratio {index:.3g} of the balance matrix): a type II "
                f"singularity (at or within {CLOSENESS_SINGULAR_TOL:g}), or fewer "
                f"independent actuators ({len(model.actuated)}) than the output's degrees "
                "of freedom; the actuator efforts are unbounded",
                kind="type II", index=float(index))


def _unbalanced(model: ClosureModel, work: _Work, res: np.ndarray, balance: float) -> None:
    """The unbalanced generalized force ``res`` (dimensionless, along idle motions):
    an :class:`InconsistentMotion` naming the joints that move in it."""
    big = np.abs(res) > 0.1 * np.abs(res).max()
    joints = list(dict.fromkeys(n for n, k in zip(work.names, big) if k))
    raise InconsistentMotion(
        f"the motion of {model.name or 'the model'} needs a generalized force that no "
        f"actuator and no closure gives (relative {balance:.3g}, tolerance "
        f"{EFFORT_BALANCE_RTOL:g}): it lies along an idle motion (the output still, "
        f"every actuator still) of the joints {', '.join(map(repr, joints))}; give an "
        "acceleration of these joints that their own dynamics allows, or actuate one",
        kind="idle", residual=res / model.velocity_units, joints=tuple(joints))
