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
  aligned; a coupling's row ``q_a − c₁ q_b − c₀`` [joint a's unit, rad or m] has
  ``J = (1, −c₁)`` in the two joints' columns and ``J̇ = 0``: its λ [N m or N] is the
  generalized force ``+λ`` on joint a and ``−c₁ λ`` on joint b.
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

Compiled path: where :mod:`pkm_pin.tree_kernel` represents the tree, one numba kernel
(:func:`inverse_dynamics_kernel`) does a sample's whole work — closure rows, the bodies'
world velocities and accelerations, ``rnea`` in world axes, the closures' second
derivative, the checks, the balance, the type II test — for one call
(:func:`inverse_dynamics`) or N samples (:func:`inverse_dynamics_batch`); a sample it
declines goes through the Python path below, which raises the error with its message or
returns (docs/dynamics.md, "The compiled path"). The balance (:func:`_balance`): where
``A`` has full row rank, the ``L D Lᵀ`` of ``A Aᵀ`` gives the minimum-norm solution and
the condition from the extreme eigenvalues of ``A Aᵀ``, each certified to
:data:`EIG_RTOL` (power and inverse iterations warm-started from the previous samples,
Temple's bound or a shifted ``L D Lᵀ`` as certificate), with a condition certified far
below the type II threshold; elsewhere (the first sample of a call, idle motions,
rank-deficient or ill-conditioned ``A``, and the sample after an SVD one out of the
Cholesky route's reach) a warm-started Jacobi SVD with iterative refinement and the
type II test on its vectors. :func:`motion_kernel` is
:func:`motion_from_actuated` compiled the same way (:func:`actuated_motion`).

Gravity is set per call on a private copy of the tree kept per thread (Pinocchio reads
the gravity from the ``Model``, not the ``Data``): the shared model is never modified
and threads do not share working data.
"""

from __future__ import annotations

import math
import threading
import weakref
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numba import njit
from numba.extending import register_jitable

from . import screws
from .compiling import PLAIN_CALLS, prefer_compiled
from .engine.linalg import JACOBI_TOL, jacobi, largest
from .errors import (
    InconsistentMotion,
    InertiaError,
    InputError,
    PkmError,
    SingularityError,
)
from .model.closure_model import KINDS, ClosureModel, TreeKinematics
from .newton import ldl_solve
from .tolerances import (
    ASSEMBLY_CHECK_RTOL,
    CLOSENESS_SINGULAR_TOL,
    EFFORT_BALANCE_RTOL,
    MOTION_CONSISTENCY_RTOL,
    RANK_RTOL,
)
from .tree_kernel import _nv_of, _relative_columns, closure_rows, log6_jlog6, workspace

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
        codes = {"point": 0, "revolute": 1, "weld": 2, "coupling": 3}
        self.kind_codes = np.array([codes[c.kind] for c in model.closures], dtype=np.int64)
        self.first_rows = np.array(ends[:-1], dtype=np.int64)
        units = np.ones(self.n_rows)
        L = model.length
        for kind in ("point", "revolute"):
            units[self.rows[kind][:, :3].ravel()] = L
        units[self.rows["weld"][:, 3:].ravel()] = L
        for i, r in zip(self.kinds["coupling"], self.rows["coupling"][:, 0]):
            units[r] = model.velocity_units[tree.joints[self.joints[i]].idx_v]
        units.setflags(write=False)
        self.row_units = units
        #: a coupling's physical Jacobian row (nv,), by closure index
        self.coupling_rows = {}
        for i in self.kinds["coupling"]:
            row = np.zeros(tree.nv)
            ja, jb = self.joints[i], self.joints[C + i]
            row[tree.joints[ja].idx_v] = 1.0
            if jb > 0:
                row[tree.joints[jb].idx_v] -= model.closures[i].coef[1]
            self.coupling_rows[i] = row
        self.act_v = np.array(model.actuated_v, dtype=int)
        self.names = velocity_names(tree)
        #: per joint: mass, centre of mass (joint frame), rotational inertia by rows
        self.body = np.array([np.r_[I.mass, I.lever, I.inertia.ravel()]
                              for I in tree.inertias])
        self.armature = np.array(tree.armature, dtype=float)

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


def velocity_names(tree: pin.Model) -> list[str]:
    """Name of the joint of each velocity coordinate."""
    names = [""] * tree.nv
    for j in range(1, tree.njoints):
        joint = tree.joints[j]
        for k in range(joint.idx_v, joint.idx_v + joint.nv):
            names[k] = tree.names[j]
    return names


# ------------------------------------------------------ closure second derivative
def _second_derivative(work: _Work, a: np.ndarray, Hj: np.ndarray, VA: np.ndarray
                       ) -> np.ndarray:
    """``J a + J̇ v`` of every closure row (physical units) from the world placements
    ``Hj`` (2C × 4 × 4) of the ends' joints and their local spatial velocities and
    accelerations ``VA`` (2C × 2 × 6, Pinocchio's linear-first ``(v; ω)``): the
    compiled :func:`closure_second_derivative` (its plain-Python source for the first
    calls of a process, :func:`pkm_pin.compiling.prefer_compiled`), then ``Jlog6`` for
    the welds; a coupling's is ``a_a − c₁ a_b`` (``a`` the tree's acceleration the
    pass was made with)."""
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
    for i, r in zip(work.kinds["coupling"], work.rows["coupling"][:, 0]):
        out[r] = work.coupling_rows[i] @ a
    return out


@register_jitable
def _x3(a, b):
    """``a × b`` as a tuple (no allocation; ``a``, ``b`` arrays or tuples)."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@register_jitable
def _p3(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@register_jitable
def _m3(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


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
    2 weld, 3 coupling (left to the caller); rows from ``first[i]``), point and
    revolute rows into ``out``; for a weld
    ``ν̇`` (axis-first, ``C_b`` axes) into ``nud[i]`` and ``M = C_a⁻¹ C_b`` (3 × 4)
    into ``Mh[i]``, for the caller's ``Jlog6``."""
    C = kind.shape[0]
    for i in range(C):
        if kind[i] == 3:
            continue
        _closure_dd(_end(Hj, VA, local, i), _end(Hj, VA, local, C + i), kind[i], first[i],
                    out, nud[i], Mh[i])


@register_jitable
def _closure_dd(end_a, end_b, kind, r0, out, nud, Mh):
    """One closure's second derivative from its ends' world quantities ``(p, ṗ, p̈, ω,
    ω̇, R)`` (:func:`_end`, :func:`_end_world`): point and revolute rows into ``out``
    from row ``r0``; a weld's ``ν̇`` into ``nud`` (6) and ``M`` into ``Mh`` (3 × 4).
    Written on tuples (:func:`_x3`): no allocation."""
    pa, pda, pdda, wa, dwa, Ra = end_a
    pb, pdb, pddb, wb, dwb, Rb = end_b
    d, dd, Wr, Wrd = _m3(pb, pa), _m3(pdb, pda), _m3(wb, wa), _m3(dwb, dwa)
    U = _m3(dd, _x3(wa, d))                    # velocity at p_b, relative motion
    Ud = _m3(_m3(_m3(pddb, pdda), _x3(dwa, d)), _x3(wa, dd))
    if kind < 2:  # d/dt (R_aᵀ U) = R_aᵀ (U̇ − ω_a × U)
        y = _m3(Ud, _x3(wa, U))
        for r in range(3):
            out[r0 + r] = _transposed(Ra, y, r)
        if kind == 1:  # d/dt R_aᵀ (W × z_b)
            zb = (Rb[0, 2], Rb[1, 2], Rb[2, 2])
            x = _m3(_p3(_x3(Wrd, zb), _x3(Wr, _x3(wb, zb))), _x3(wa, _x3(Wr, zb)))
            out[r0 + 3] = _transposed(Ra, x, 0)
            out[r0 + 4] = _transposed(Ra, x, 1)
    else:  # ν = (R_bᵀ W; R_bᵀ U): ν̇ = (R_bᵀ (Ẇ − ω_b × W); R_bᵀ (U̇ − ω_b × U))
        x1, x2 = _m3(Wrd, _x3(wb, Wr)), _m3(Ud, _x3(wb, U))
        for r in range(3):
            nud[r] = _transposed(Rb, x1, r)
            nud[3 + r] = _transposed(Rb, x2, r)
            Mh[r, 3] = _transposed(Ra, d, r)
            for k in range(3):
                Mh[r, k] = Ra[0, r] * Rb[0, k] + Ra[1, r] * Rb[1, k] + Ra[2, r] * Rb[2, k]


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
    rdd = _second_derivative(work, a, *_end_motions(work, work.data, None))
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
    v, a, _ = actuated_motion(model, q, qd_actuated, qdd_actuated)
    return v, a


def actuated_motion(model: ClosureModel, q, qd_actuated, qdd_actuated
                    ) -> tuple[np.ndarray, np.ndarray, bool]:
    """:func:`motion_from_actuated` and whether the compiled kernel
    (:func:`motion_kernel`) gave it, which certifies that ``[J; S]`` has full column
    rank: no idle motion (the caller can skip looking for one). Same errors."""
    q = model.check_q(q)
    n = len(model.actuated)
    qd = screws.as_vector(qd_actuated, n, "qd_actuated", ", ".join(model.actuated))
    qdd = screws.as_vector(qdd_actuated, n, "qdd_actuated", ", ".join(model.actuated))
    kern = _compiled(model, kernel=motion_kernel)
    if kern is not None:
        work = _work(model)
        v, a, info = np.empty(model.nv), np.empty(model.nv), np.zeros(1)
        cons = np.array([ASSEMBLY_CHECK_RTOL, MOTION_CERTIFY_RTOL, MOTION_CONSISTENCY_RTOL])
        motion_kernel(kern, q, qd, qdd, work.row_units, cons, v, a, info)
        if info[0] == _OK:
            return v, a, True
    v, a = _motion_python(model, q, qd, qdd)
    return v, a, False


def _motion_python(model: ClosureModel, q, qd, qdd) -> tuple[np.ndarray, np.ndarray]:
    """:func:`motion_from_actuated` by Pinocchio passes and numpy (checked arguments)."""
    n = len(model.actuated)
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
    drift = _second_derivative(work, np.zeros(model.nv),
                               *_end_motions(work, work.data, None))
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
    M = pin.crba(work.tree, work.data, q, pin.Convention.WORLD)  # LOCAL on a reused Data is
    # wrong with mimic joints in Pinocchio 4.1 (the Delta TOML: off by 0.5)
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
                f"or an under-actuated mechanism (fewer independent actuators "
                f"({len(model.actuated)}) than the output's degrees of freedom: springs or "
                "passive joints without a motor, at every pose; `pkm-pin analyze` says "
                "which); its motion is not determined by the actuated rates",
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
    _work(model, masses=True)  # the masses checked first (once per model and thread)
    kern = _compiled(model)
    if kern is not None:  # the compiled kernel on one sample; Python where it declines
        out = _run_kernel(model, kern, _work(model), q[None], v[None], a[None], g,
                          None if w is None else w[None], tol)
        if out[-1][0, 0] == _OK:
            return _one_result(model, *(x[0] for x in out))
    return _python_path(model, q, v, a, g, w, tol)


def _one_result(model: ClosureModel, T, X, XW, RDD, DRIFT, INFO) -> InverseDynamics:
    """:class:`InverseDynamics` of one kernel sample."""
    na, nr = len(model.actuated), X.shape[0] - len(model.actuated)
    return InverseDynamics(
        efforts=X[:na], actuated=tuple(model.actuated), closure_forces=X[na:],
        redundant_rows=int(na + nr - INFO[3]), payload_efforts=XW[:na],
        payload_closure_forces=XW[na:], tree_efforts=T, acceleration_residual=RDD,
        drift=DRIFT, balance_residual=float(INFO[1]), condition=float(INFO[2]))


def _python_path(model: ClosureModel, q, v, a, g, w, tol) -> InverseDynamics:
    """:func:`inverse_dynamics` by Pinocchio passes and numpy (checked arguments): every
    error with its message."""
    work = _work(model)
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
    rdd = _second_derivative(work, a, *_end_motions(work, data, g))
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


# ================================================================ compiled path
# One numba kernel per batch of samples: the closure rows and the joints' world twists
# of :mod:`pkm_pin.tree_kernel`, the bodies' world velocities and accelerations, the
# closures' second derivative, the consistency checks, the balance's SVD and solve, and
# the type II test. Pinocchio's ``rnea`` gives the tree efforts. A sample the kernel
# does not pass (a check fails, a singular or unbalanced system, an idle motion) is
# handed to the Python path above, which raises the error with its message, or returns.

#: Status of a kernel sample.
_OK, _TO_PYTHON = 0, 1


@register_jitable(inline="always")
def _body_motions(k, S, v, a, Vb, Ab, sv):
    """World twists ``Vb`` (nj × 6) and spatial accelerations ``Ab`` (axis-first, about
    the world origin) of every joint's body: ``V_j = V_p + S_j v_j``, ``A_j = A_p + S_j
    a_j + V_j × S_j v_j`` (``S`` the joints' world twists, ``sv`` work (6))."""
    for r in range(6):
        Vb[0, r], Ab[0, r] = 0.0, 0.0
    for j in range(1, k.parent.shape[0]):
        p, c0 = k.parent[j], k.iv[j]
        for r in range(6):
            s_v, s_a = 0.0, 0.0
            for c in range(c0, c0 + _nv_of(k.kind[j])):
                s_v += S[r, c] * v[c]
                s_a += S[r, c] * a[c]
            sv[r] = s_v
            Vb[j, r] = Vb[p, r] + s_v
            Ab[j, r] = Ab[p, r] + s_a
        w0, w1, w2, u0, u1, u2 = Vb[j, 0], Vb[j, 1], Vb[j, 2], Vb[j, 3], Vb[j, 4], Vb[j, 5]
        Ab[j, 0] += w1 * sv[2] - w2 * sv[1]
        Ab[j, 1] += w2 * sv[0] - w0 * sv[2]
        Ab[j, 2] += w0 * sv[1] - w1 * sv[0]
        Ab[j, 3] += w1 * sv[5] - w2 * sv[4] + u1 * sv[2] - u2 * sv[1]
        Ab[j, 4] += w2 * sv[3] - w0 * sv[5] + u2 * sv[0] - u0 * sv[2]
        Ab[j, 5] += w0 * sv[4] - w1 * sv[3] + u0 * sv[1] - u1 * sv[0]


@register_jitable
def _end_world(F, e, j, Vb, Ab):
    """:func:`_end`'s quantities (tuples, the rotation a view) of constraint frame ``e``
    (world placement ``F[e]``) on joint ``j``'s body from its world twist and spatial
    acceleration: ``ṗ = v_O + ω × p``, ``p̈ = a_O + ω̇ × p + ω × ṗ``."""
    p = (F[e, 0, 3], F[e, 1, 3], F[e, 2, 3])
    w, vo = (Vb[j, 0], Vb[j, 1], Vb[j, 2]), (Vb[j, 3], Vb[j, 4], Vb[j, 5])
    dw, ao = (Ab[j, 0], Ab[j, 1], Ab[j, 2]), (Ab[j, 3], Ab[j, 4], Ab[j, 5])
    pd = _p3(vo, _x3(w, p))
    pdd = _p3(_p3(ao, _x3(dw, p)), _x3(w, pd))
    return p, pd, pdd, w, dw, F[e, :3, :3]


@register_jitable
def _weld_rows(Mh, nud, r0, out, lg, Jl, w3, A3, Cm, R, p):
    """``Jlog6(M) ν̇`` into a weld's rows ``(θ; ρ)`` (Pinocchio's ``(v; ω)`` Jlog6;
    ``R`` (3 × 3), ``p`` (3): work)."""
    for a in range(3):
        p[a] = Mh[a, 3]
        for b in range(3):
            R[a, b] = Mh[a, b]
    log6_jlog6(R, p, lg, Jl, w3, A3, Cm)
    for a in range(3):
        ang, lin = 0.0, 0.0
        for b in range(3):
            ang += Jl[3 + a, b] * nud[3 + b] + Jl[3 + a, 3 + b] * nud[b]
            lin += Jl[a, b] * nud[3 + b] + Jl[a, 3 + b] * nud[b]
        out[r0 + a], out[r0 + 3 + a] = ang, lin


@register_jitable(inline="always")
def _second_derivative_world(k, ws, Vb, Ab, H, a, row_units, rdd, nud, Mh, lg, Jl, A3):
    """Every closure's ``J a + J̇ v`` (physical) from the bodies' motions; a coupling's
    (linear in q) is ``J a`` from its dimensionless row of ``H``."""
    C = k.ckind.shape[0]
    for c in range(C):
        if k.ckind[c] == 3:  # a coupling: J is constant, J a + J̇ v = J a
            r0 = k.rows[c]
            s = 0.0
            for col in range(H.shape[1]):
                s += H[r0, col] * a[col]
            rdd[r0] = row_units[r0] * s
            continue
        ea = _end_world(ws.F, c, k.fjoint[c], Vb, Ab)
        eb = _end_world(ws.F, C + c, k.fjoint[C + c], Vb, Ab)
        _closure_dd(ea, eb, k.ckind[c], k.rows[c], rdd, nud, Mh)
        if k.ckind[c] == 2:
            _weld_rows(Mh, nud, k.rows[c], rdd, lg, Jl, ws.w, A3, ws.Cm, ws.Rrel, ws.prel)


@register_jitable(inline="always")
def _output_columns(k, ws, point, Jo):
    """The output Jacobian (6 × nv, axis-first, world origin; a point output: ``(0;
    v_p)``) from the joints' twists."""
    _relative_columns(k.iv, k.kind, k.parent, 0, k.fjoint[2 * k.ckind.shape[0]], ws.S, Jo)
    if point:
        o = 2 * k.ckind.shape[0]
        px, py, pz = ws.F[o, 0, 3], ws.F[o, 1, 3], ws.F[o, 2, 3]
        for c in range(Jo.shape[1]):
            wx, wy, wz = Jo[0, c], Jo[1, c], Jo[2, c]
            Jo[3, c] += wy * pz - wz * py
            Jo[4, c] += wz * px - wx * pz
            Jo[5, c] += wx * py - wy * px
            Jo[0, c], Jo[1, c], Jo[2, c] = 0.0, 0.0, 0.0


@register_jitable
def _consistent(H, U, rows, v, a, rdd, gscale, tol, drift, Hu):
    """The checks of :func:`_check_rows` with ``‖J_c U‖₂`` bounded below by its
    Frobenius norm over √min(m, n) (stricter: a sample at the limit goes to Python);
    on the way ``J̇ v = (J a + J̇ v) − s ∘ (J_c a)`` into ``drift`` (physical rows) and
    the dimensionless ``Hu = J_c U`` (the balance's)."""
    m, n = H.shape
    fro, jv, nv_, na_, r2, d2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for i in range(m):
        s, sa = 0.0, 0.0
        for c in range(n):
            x = H[i, c] * U[c]
            Hu[i, c] = x
            fro += x * x
            s += H[i, c] * v[c]
            sa += H[i, c] * a[c]
        drift[i] = rdd[i] - rows[i] * sa
        jv += s * s
        r = rdd[i] / rows[i]
        r2 += r * r
        d = r - sa
        d2 += d * d
    for c in range(n):
        nv_ += (v[c] / U[c]) ** 2
        na_ += (a[c] / U[c]) ** 2
    size = math.sqrt(fro / max(1, min(m, n)))
    ev, ea = math.sqrt(jv), math.sqrt(r2)
    ok_v = ev == 0.0 or ev <= tol * size * math.sqrt(nv_)
    ok_a = ea == 0.0 or ea <= tol * (size * math.sqrt(na_) + math.sqrt(d2) + gscale)
    return ok_v and ok_a


@register_jitable
def _type_two(V, sv, small, Jo, U, F, o, length, close, t):
    """Whether a left singular vector of the balance matrix (column ``j`` of ``V``)
    whose singular value is below ``small`` moves the output (homogenised about its
    origin, > ``close``)."""
    nv = V.shape[0]
    px, py, pz = F[o, 0, 3], F[o, 1, 3], F[o, 2, 3]
    for j in range(nv):
        if sv[j] >= small:
            continue
        for r in range(6):
            s = 0.0
            for c in range(nv):
                s += Jo[r, c] * U[c] * V[c, j]
            t[r] = s
        hx = (t[3] + t[1] * pz - t[2] * py) / length
        hy = (t[4] + t[2] * px - t[0] * pz) / length
        hz = (t[5] + t[0] * py - t[1] * px) / length
        if math.sqrt(t[0] ** 2 + t[1] ** 2 + t[2] ** 2 + hx * hx + hy * hy + hz * hz) > close:
            return True
    return False


@register_jitable(inline="always")
def _right_side(k, Jo, tau, w, has_w, point, b, bw):
    """``b = U (τ_tree − J_oᵀ Δ w)`` and its payload part ``bw`` (for a point output
    only the force acts, on the point's velocity)."""
    U = k.units
    for c in range(b.shape[0]):
        bw[c] = 0.0
        if has_w:
            if point:
                s = Jo[3, c] * w[0] + Jo[4, c] * w[1] + Jo[5, c] * w[2]
            else:
                s = Jo[0, c] * w[3] + Jo[1, c] * w[4] + Jo[2, c] * w[5] \
                    + Jo[3, c] * w[0] + Jo[4, c] * w[1] + Jo[5, c] * w[2]
            bw[c] = -U[c] * s
        b[c] = U[c] * tau[c] + bw[c]


@register_jitable
def _pinv_add(At, Wj, V, sv, thr, rhs, y, r):
    """``y += A⁺ rhs`` with ``Aᵀ = W Vᵀ`` (``A⁺ = Σ_j W_j V_jᵀ / σ_j²`` over ``σ_j >
    thr``); ``r``: work (nv)."""
    m, nv = At.shape
    for j in range(nv):
        if sv[j] > thr:
            c = 0.0
            for i in range(nv):
                c += V[i, j] * rhs[i]
            c /= sv[j] * sv[j]
            for i in range(m):
                y[i] += Wj[i, j] * c


@register_jitable
def _residual(At, y, b, r) -> float:
    """``r = b − A y`` (``A = Atᵀ``); returns ``‖r‖``."""
    m, nv = At.shape
    out = 0.0
    for c in range(nv):
        s = 0.0
        for i in range(m):
            s += At[i, c] * y[i]
        r[c] = b[c] - s
        out += r[c] * r[c]
    return math.sqrt(out)


@register_jitable
def _norm(x) -> float:
    """``‖x‖₂`` of a vector (no allocation)."""
    s = 0.0
    for i in range(x.shape[0]):
        s += x[i] * x[i]
    return math.sqrt(s)


@register_jitable
def _gram(act, Hu, G) -> tuple:
    """``G = A Aᵀ = S Sᵀ + Huᵀ Hu`` (nv × nv, both triangles) of the balance matrix ``A
    = [Sᵀ, −Huᵀ]`` (``Hu = J_c U``, the dimensionless closure rows), summed row by row
    (a closure's row is zero outside its loop's joints). Returns ``(max |A|, ‖G‖_F²)``."""
    nr, nv = Hu.shape
    for c in range(nv):
        for d in range(nv):
            G[c, d] = 0.0
    for i in range(act.shape[0]):
        G[act[i], act[i]] += 1.0
    amax = 1.0 if act.shape[0] else 0.0
    for i in range(nr):
        for c in range(nv):
            h = Hu[i, c]
            if h != 0.0:
                amax = max(amax, abs(h))
                for d in range(c + 1):
                    G[c, d] += h * Hu[i, d]
    fro = 0.0
    for c in range(nv):
        fro += G[c, c] * G[c, c]
        for d in range(c):
            G[d, c] = G[c, d]
            fro += 2.0 * G[c, d] * G[c, d]
    return amax, fro


@register_jitable
def _shifted_ldl(G, sign, shift, L, inv) -> bool:
    """``L D Lᵀ`` of ``sign G − shift I`` (``G`` symmetric, both triangles) in ``L``'s
    lower triangle as :func:`pkm_pin.newton.ldl` writes it (unit factor below the
    diagonal, ``D`` on it; :func:`~pkm_pin.newton.ldl_solve` reads it), the products
    ``L D`` of each row in the upper triangle (work: half the multiplications), ``inv =
    1 / D``. Returns whether that matrix is positive definite (Sylvester)."""
    n = G.shape[0]
    for j in range(n):
        d = sign * G[j, j] - shift
        for k in range(j):
            w = L[j, k] * L[k, k]
            L[k, j] = w
            d -= w * L[j, k]
        if not 0.0 < d < np.inf:
            return False
        L[j, j] = d
        f = 1.0 / d
        inv[j] = f
        for i in range(j + 1, n):
            t = sign * G[i, j]
            for k in range(j):
                t -= L[i, k] * L[k, j]
            L[i, j] = t * f
    return True


@register_jitable
def _times_transpose(act, Hu, z, x):
    """``x = Aᵀ z`` (``A = [Sᵀ, −Huᵀ]``)."""
    na, nr, nv = act.shape[0], Hu.shape[0], Hu.shape[1]
    for i in range(na):
        x[i] = z[act[i]]
    for i in range(nr):
        s = 0.0
        for c in range(nv):
            s -= Hu[i, c] * z[c]
        x[na + i] = s


@register_jitable
def _residual_of(act, Hu, x, rhs, r) -> float:
    """``r = rhs − A x`` (``A = [Sᵀ, −Huᵀ]``); returns ``‖r‖``."""
    na, nr, nv = act.shape[0], Hu.shape[0], Hu.shape[1]
    for c in range(nv):
        s = rhs[c]
        for i in range(nr):
            s += Hu[i, c] * x[na + i]
        r[c] = s
    for i in range(na):
        r[act[i]] -= x[i]
    return _norm(r)


@register_jitable
def _min_norm(act, Hu, L, inv, rhs, x, r, z) -> float:
    """The minimum-norm solution ``x = Aᵀ G⁻¹ rhs`` of ``A x = rhs`` (``A`` of full row
    rank, ``G = A Aᵀ`` factored in ``L``, ``inv``; ``x`` in the row space of ``A``).
    Its relative error is ``~eps κ(G)``, ``κ(G) = κ(A)²``, which :func:`_balance_cholesky`
    bounds (below 1e-11: no refinement step). Returns ``‖rhs − A x‖`` (``r`` the
    residual)."""
    ldl_solve(L, L.shape[0], inv, rhs, z)
    _times_transpose(act, Hu, z, x)
    return _residual_of(act, Hu, x, rhs, r)


#: Power and inverse iterations of :func:`_largest_eigenvalue`,
#: :func:`_smallest_eigenvalue` before they give up (the Jacobi SVD then).
EIG_STEPS = 40
#: Relative width of the interval in which :func:`_largest_eigenvalue` and
#: :func:`_smallest_eigenvalue` certify the extreme eigenvalues of ``A Aᵀ``.
EIG_RTOL = 3e-10
#: Relative error of the balance's condition the Cholesky route must certify (else the
#: Jacobi SVD): the certified intervals plus the round-off of ``A Aᵀ`` (:func:`_balance`).
CONDITION_RTOL = 1e-9
#: Samples whose certificate came at the first try before :func:`_certified` tries one
#: iteration fewer.
EIG_PATIENCE = 16


@register_jitable
def _certified(step, plan, which):
    """Book-keeping of an iteration certified at ``step``: ``plan[which]`` is the step
    of the first certificate attempt (the previous sample's need), ``plan[2 + which]``
    counts the samples certified at that first try; after :data:`EIG_PATIENCE` of them
    the next sample tries one step earlier."""
    if step > plan[which]:
        plan[which], plan[2 + which] = step, 0
        return
    plan[2 + which] += 1
    if plan[2 + which] >= EIG_PATIENCE and plan[which] > 1:
        plan[which], plan[2 + which] = plan[which] - 1, 0


@register_jitable
def _largest_eigenvalue(G, fro, u, z, L, inv, delta, plan) -> float:
    """``λ_max(G)`` of the symmetric positive definite ``G`` (``fro = ‖G‖_F²``) by power
    iteration from the unit ``u`` (a warm start, updated): the Rayleigh quotient ``ρ =
    uᵀ G u ≤ λ_max`` rises to it, and from step ``plan[0]`` (:func:`_certified`) each
    step tries to certify ``λ_max < (1 + delta) ρ`` (:func:`_below`). Returns ``ρ``, or
    −1 when no certificate came within :data:`EIG_STEPS`."""
    n = G.shape[0]
    for step in range(1, EIG_STEPS + 1):
        for i in range(n):
            z[i] = 0.0
        for j in range(n):  # z = G u by rows of the symmetric G
            t = u[j]
            for i in range(n):
                z[i] += G[j, i] * t
        rho, nz = 0.0, 0.0
        for i in range(n):
            rho += u[i] * z[i]
            nz += z[i] * z[i]
        if not 0.0 < nz < np.inf:
            return -1.0
        eps2 = 0.0
        for i in range(n):
            eps2 += (z[i] - rho * u[i]) ** 2
        f = 1.0 / math.sqrt(nz)
        for i in range(n):
            u[i] = z[i] * f
        if step >= plan[0] and _below(G, fro, rho, eps2, (1.0 + delta) * rho, L, inv):
            _certified(step, plan, 0)
            return rho
    return -1.0


@register_jitable
def _below(G, fro, rho, eps2, top, L, inv) -> bool:
    """Whether ``λ_max(G) < top`` is certain, from a Rayleigh quotient ``ρ`` with its
    residual ``ε² = ‖G u − ρ u‖²``: Temple's inequality ``λ_max ≤ ρ + ε² / (ρ − β)``
    where ``β ≥ λ₂`` (the second largest; ``λ₂² ≤ ‖G‖_F² − λ_max² ≤ ‖G‖_F² − ρ²``) is
    below ``ρ`` (plus the round-off of ``ρ`` and ``ε``); else ``top I − G`` positive
    definite (:func:`_shifted_ldl`)."""
    n = G.shape[0]
    off = 8.0 * n * 2.2e-16 * math.sqrt(fro)  # the round-off of ρ, ε² and β
    gap = rho - math.sqrt(max(fro - rho * rho, 0.0)) - off
    if gap > 0.0 and rho + eps2 / gap + off < top:
        return True
    return _shifted_ldl(G, -1.0, -top, L, inv)


@register_jitable
def _smallest_eigenvalue(G, LG, invG, u, z, L, inv, delta, plan) -> float:
    """``λ_min(G)`` by inverse iteration with ``G``'s factors (``LG``, ``invG``) from the
    unit ``u`` (warm start, updated), and from step ``plan[1]`` the Rayleigh quotient
    ``ρ = uᵀ G u ≥ λ_min`` of the new vector (whose error is that of the input times
    ``(λ_min / λ₂)²``) with the certificate ``λ_min > (1 − delta) ρ``: ``G − (1 − delta)
    ρ I`` positive definite. Returns ``ρ``, or −1."""
    n = G.shape[0]
    for step in range(1, EIG_STEPS + 1):
        ldl_solve(LG, n, invG, u, z)
        nz = _norm(z)
        if not 0.0 < nz < np.inf:
            return -1.0
        for i in range(n):
            u[i] = z[i] / nz
        if step < plan[1]:
            continue
        rho = 0.0
        for i in range(n):
            t = 0.0
            for j in range(n):
                t += G[i, j] * u[j]
            rho += u[i] * t
        if rho > 0.0 and _shifted_ldl(G, 1.0, (1.0 - delta) * rho, L, inv):
            _certified(step, plan, 1)
            return rho
    return -1.0


#: :func:`_extrapolate` predicts where the last step of the vector is below this.
EXTRAPOLATE_BELOW = 0.1


@register_jitable
def _extrapolate(u, prev, w):
    """The warm start of an eigenvector along a path of samples: ``u`` (the last
    sample's vector) ← ``2 u − prev`` (``prev``: the one before), normalised, where the
    step ``|u − prev|`` is below :data:`EXTRAPOLATE_BELOW` (an error ``O(h²)`` rather
    than ``O(h)``); then ``prev`` ← the last vector (``w``: work)."""
    n = u.shape[0]
    d2 = 0.0
    for i in range(n):
        w[i] = u[i]
        d2 += (u[i] - prev[i]) ** 2
    if d2 < EXTRAPOLATE_BELOW ** 2:
        for i in range(n):
            u[i] = 2.0 * u[i] - prev[i]
        f = 1.0 / _norm(u)
        for i in range(n):
            u[i] *= f
    for i in range(n):
        prev[i] = w[i]


@register_jitable
def _within_reach(nr, nv, kappa) -> bool:
    """Whether the Cholesky route certifies the condition of a balance whose ``G = A
    Aᵀ`` (``nr`` closure rows, ``nv`` velocity coordinates) has the condition ``kappa``
    (``κ(A)²``): the round-off of ``G``, ``(nr + 4) nv eps κ(G)``, plus the certified
    widths within :data:`CONDITION_RTOL` (:func:`_balance_cholesky`)."""
    return 2.0 * EIG_RTOL + (nr + 4) * nv * 2.2e-16 * kappa <= 2.0 * CONDITION_RTOL


@register_jitable(inline="always")
def _balance_cholesky(act, s, has_w):
    """The balance by the Cholesky (``L D Lᵀ``) factors of ``G = A Aᵀ`` where ``A`` has
    full row rank with a certified condition: the minimum-norm solutions of ``b`` and
    ``bw`` (:func:`_min_norm`), ``σ_max² = λ_max(G)`` and ``σ_min² = λ_min(G)`` certified
    (:func:`_largest_eigenvalue`, :func:`_smallest_eigenvalue`, warm-started with the
    previous samples' vectors, :func:`_extrapolate`). Returns ``(ok, σ_max, σ_min,
    relative residual)``; not ok: a factorisation fails, an iteration gives up, or the
    round-off of ``G`` (``(n_rows + 4) nv eps κ(G)``, ``κ(G) = κ(A)²``) with the
    certified widths exceeds :data:`CONDITION_RTOL`."""
    nv, nr = s.G.shape[0], s.H.shape[0]
    amax, fro = _gram(act, s.Hu, s.G)
    if not _shifted_ldl(s.G, 1.0, 0.0, s.LG, s.invG):
        return False, 0.0, 0.0, 0.0
    _extrapolate(s.umax, s.pmax, s.z)
    _extrapolate(s.umin, s.pmin, s.z)
    lmax = _largest_eigenvalue(s.G, fro, s.umax, s.z, s.L, s.inv, EIG_RTOL, s.plan)
    if lmax < 0.0:
        return False, 0.0, 0.0, 0.0
    lmin = _smallest_eigenvalue(s.G, s.LG, s.invG, s.umin, s.z, s.L, s.inv, EIG_RTOL,
                                s.plan)
    if lmin <= 0.0 or not _within_reach(nr, nv, lmax / lmin):
        return False, 0.0, 0.0, 0.0
    res = _min_norm(act, s.Hu, s.LG, s.invG, s.b, s.y, s.rv, s.z)
    if has_w:
        _min_norm(act, s.Hu, s.LG, s.invG, s.bw, s.yw, s.rv, s.z)
    else:
        s.yw[:] = 0.0
    scale = max(_norm(s.b), amax * _norm(s.y), 1e-300)
    return True, math.sqrt(lmax), math.sqrt(lmin), res / scale


@register_jitable(inline="always")
def _balance(k, s, cons, has_w):
    """The balance ``A x = b`` (and ``bw``) of one sample: by :func:`_balance_cholesky`
    once a previous sample of the batch has given warm vectors and ``A`` can have full
    row rank, else (or where it declines) by :func:`_balance_svd`, whose basis then
    gives the warm vectors. Along a path the previous sample predicts the route: after
    an SVD sample whose ``A`` is rank-deficient or too ill-conditioned for the Cholesky
    route (:func:`_within_reach`: near a type II singularity, say) the next sample takes
    the SVD at once (no Cholesky attempt bound to be declined); the route comes back
    after an SVD sample within reach. Returns ``(rank, σ_max, σ_min kept, relative
    residual, svd)``: ``svd`` whether ``s.V``, ``s.sv`` hold this sample's SVD (the type
    II test reads it; the Cholesky route certifies ``σ_min / σ_max`` far above
    :data:`CLOSENESS_SINGULAR_TOL`)."""
    nv, na, nr = s.G.shape[0], k.act_v.shape[0], s.H.shape[0]
    if s.warm[0] and na + nr >= nv:
        ok, smax, smin, res = _balance_cholesky(k.act_v, s, has_w)
        if ok:
            return nv, smax, smin, res, False
    rank, smax, smin, res = _balance_svd(k, s.H, s.At, s.Wj, s.V, s.sv, s.b, s.bw, s.y,
                                         s.yw, s.rv, cons, has_w)
    hi, lo = 0, 0
    for j in range(nv):
        if s.sv[j] > s.sv[hi]:
            hi = j
        if s.sv[j] < s.sv[lo]:
            lo = j
    for i in range(nv):
        s.umax[i], s.umin[i] = s.V[i, hi], s.V[i, lo]
        s.pmax[i], s.pmin[i] = s.V[i, hi], s.V[i, lo]
    s.warm[0] = 1 if rank == nv and _within_reach(nr, nv, (smax / smin) ** 2) else 0
    return rank, smax, smin, res, True


@register_jitable
def _balance_svd(k, H, At, Wj, V, sv, b, bw, y, yw, r, cons, has_w):
    """The balance ``A x = b``, ``A = [Sᵀ, −(J_c U)ᵀ]`` (nv × (na + nr)), by the
    one-sided Jacobi SVD of ``Aᵀ = W Vᵀ`` (:func:`pkm_pin.engine.linalg.jacobi`; ``V``:
    the previous sample's basis, a warm start): ``A = V Σ (W Σ⁻¹)ᵀ``, the truncated
    solution ``y = Σ_j W_j (V_jᵀ b) / σ_j²`` over ``σ_j > RANK_RTOL σ_max``, then two
    steps of iterative refinement (``y += A⁺ (b − A y)``): the Jacobi sweeps stop at
    cosines below :data:`~pkm_pin.engine.linalg.JACOBI_TOL` and leave the null columns
    at ~1e-12, which a condition of 10³ would carry into the solution;
    ``yw`` the same of ``bw``. Returns ``(rank, σ_max, σ_min kept, relative
    residual)``. The general route (:func:`_balance`): any rank."""
    U, act = k.units, k.act_v
    nv, nr, na = H.shape[1], H.shape[0], act.shape[0]
    At[:, :] = 0.0
    for i in range(na):
        At[i, act[i]] = 1.0
    for i in range(nr):
        for c in range(nv):
            At[na + i, c] = -H[i, c] * U[c]
    jacobi(At, na + nr, nv, Wj, V, sv, JACOBI_TOL)
    smax = largest(sv, nv)
    thr = cons[1] * smax
    rank, smin = 0, np.inf
    for j in range(nv):
        if sv[j] > thr:
            rank += 1
            smin = min(smin, sv[j])
    yw[:] = 0.0
    for rhs, x in ((b, y), (bw, yw)):
        if x is yw and not has_w:  # no payload: its part is zero
            break
        x[:] = 0.0
        _pinv_add(At, Wj, V, sv, thr, rhs, x, r)
        for _ in range(2):
            _residual(At, x, rhs, r)
            _pinv_add(At, Wj, V, sv, thr, r, x, r)
    res = _residual(At, y, b, r)
    amax = 0.0
    for i in range(At.shape[0]):
        for c in range(nv):
            amax = max(amax, abs(At[i, c]))
    scale = max(_norm(b), amax * _norm(y), 1e-300)
    return rank, smax, smin, res / scale


@register_jitable(inline="always")
def _rnea_world(k, oMi, S, Vb, Ab, a, body, armature, g, Fb, tau):
    """``rnea(q, v, a)`` with gravity ``g`` from the bodies' world twists and spatial
    accelerations: per body (``body[j]`` = mass, centre of mass in the joint frame, its
    rotational inertia by rows) ``f = m (a_c − g)``, ``n_O = I ω̇ + ω × I ω + c × f``
    (world, about the world origin; ``a_c`` the centre of mass's acceleration), summed
    from the leaves (``Fb``: (nj, 6) work), then ``τ_k = S_kᵀ (n_O; f) + armature_k a_k``."""
    nj = k.parent.shape[0]
    for j in range(nj):
        for r in range(6):
            Fb[j, r] = 0.0
    for j in range(1, nj):
        m = body[j, 0]
        c = (oMi[j, 0, 3] + oMi[j, 0, 0] * body[j, 1] + oMi[j, 0, 1] * body[j, 2]
             + oMi[j, 0, 2] * body[j, 3],
             oMi[j, 1, 3] + oMi[j, 1, 0] * body[j, 1] + oMi[j, 1, 1] * body[j, 2]
             + oMi[j, 1, 2] * body[j, 3],
             oMi[j, 2, 3] + oMi[j, 2, 0] * body[j, 1] + oMi[j, 2, 1] * body[j, 2]
             + oMi[j, 2, 2] * body[j, 3])
        w, vo = (Vb[j, 0], Vb[j, 1], Vb[j, 2]), (Vb[j, 3], Vb[j, 4], Vb[j, 5])
        dw, ao = (Ab[j, 0], Ab[j, 1], Ab[j, 2]), (Ab[j, 3], Ab[j, 4], Ab[j, 5])
        vc = _p3(vo, _x3(w, c))
        ac = _m3(_p3(_p3(ao, _x3(dw, c)), _x3(w, vc)), g)
        f = (m * ac[0], m * ac[1], m * ac[2])
        # body frame: I (R_jᵀ ω̇) and I (R_jᵀ ω), then back to world axes
        bd = (_transposed(oMi[j], dw, 0), _transposed(oMi[j], dw, 1),
              _transposed(oMi[j], dw, 2))
        bw = (_transposed(oMi[j], w, 0), _transposed(oMi[j], w, 1),
              _transposed(oMi[j], w, 2))
        for r in range(3):
            s1, s2 = 0.0, 0.0
            for t in range(3):
                s1 += body[j, 4 + 3 * r + t] * bd[t]
                s2 += body[j, 4 + 3 * r + t] * bw[t]
            Fb[0, r], Fb[0, 3 + r] = s1, s2  # row 0 (the universe) as work
        Id = (oMi[j, 0, 0] * Fb[0, 0] + oMi[j, 0, 1] * Fb[0, 1] + oMi[j, 0, 2] * Fb[0, 2],
              oMi[j, 1, 0] * Fb[0, 0] + oMi[j, 1, 1] * Fb[0, 1] + oMi[j, 1, 2] * Fb[0, 2],
              oMi[j, 2, 0] * Fb[0, 0] + oMi[j, 2, 1] * Fb[0, 1] + oMi[j, 2, 2] * Fb[0, 2])
        Iw = (oMi[j, 0, 0] * Fb[0, 3] + oMi[j, 0, 1] * Fb[0, 4] + oMi[j, 0, 2] * Fb[0, 5],
              oMi[j, 1, 0] * Fb[0, 3] + oMi[j, 1, 1] * Fb[0, 4] + oMi[j, 1, 2] * Fb[0, 5],
              oMi[j, 2, 0] * Fb[0, 3] + oMi[j, 2, 1] * Fb[0, 4] + oMi[j, 2, 2] * Fb[0, 5])
        n = _p3(_p3(Id, _x3(w, Iw)), _x3(c, f))
        for r in range(3):
            Fb[j, r] += f[r]
            Fb[j, 3 + r] += n[r]
    for j in range(nj - 1, 0, -1):
        p = k.parent[j]
        if p > 0:
            for r in range(6):
                Fb[p, r] += Fb[j, r]
        c0 = k.iv[j]
        for col in range(c0, c0 + _nv_of(k.kind[j])):
            tau[col] = S[0, col] * Fb[j, 3] + S[1, col] * Fb[j, 4] + S[2, col] * Fb[j, 5] \
                + S[3, col] * Fb[j, 0] + S[4, col] * Fb[j, 1] + S[5, col] * Fb[j, 2] \
                + armature[col] * a[col]


class _Scratch(NamedTuple):
    """Work arrays of :func:`_samples` (made by :func:`_scratch` once per kernel call)."""

    e: np.ndarray  # (nr,) closure rows …
    H: np.ndarray  # (nr, nv) … and their Jacobian (dimensionless)
    norms: np.ndarray  # (C,)
    oMo: np.ndarray  # (4, 4)
    Vb: np.ndarray  # (nj, 6) bodies' world twists …
    Ab: np.ndarray  # (nj, 6) … and spatial accelerations
    Fb: np.ndarray  # (nj, 6) rnea's forces
    s6: np.ndarray  # (6,)
    nud: np.ndarray  # (6,)
    Mh: np.ndarray  # (3, 4)
    lg: np.ndarray  # (6,)
    Jl: np.ndarray  # (6, 6)
    A3: np.ndarray  # (3, 3)
    Jo: np.ndarray  # (6, nv) output Jacobian
    b: np.ndarray  # (nv,) right sides
    bw: np.ndarray  # (nv,)
    y: np.ndarray  # (m,) solutions (m = na + nr)
    yw: np.ndarray  # (m,)
    rv: np.ndarray  # (nv,)
    At: np.ndarray  # (m, nv) Jacobi SVD: Aᵀ …
    Wj: np.ndarray  # (m, nv) … A V …
    V: np.ndarray  # (nv, nv) … its basis (warm start) …
    sv: np.ndarray  # (nv,) … and singular values
    Hu: np.ndarray  # (nr, nv) Cholesky route: J_c U …
    G: np.ndarray  # (nv, nv) … A Aᵀ …
    LG: np.ndarray  # (nv, nv) … its factors …
    invG: np.ndarray  # (nv,)
    L: np.ndarray  # (nv, nv) … a certificate's factors …
    inv: np.ndarray  # (nv,)
    z: np.ndarray  # (nv,)
    umax: np.ndarray  # (nv,) … and the warm eigenvectors
    umin: np.ndarray  # (nv,)
    pmax: np.ndarray  # (nv,) … the ones before (:func:`_extrapolate`)
    pmin: np.ndarray  # (nv,)
    warm: np.ndarray  # (1,) whether umax, umin hold a previous sample's vectors (and
    # its balance was within the Cholesky route's reach, :func:`_balance`)
    plan: np.ndarray  # (4,) the iterations' first certificate steps (:func:`_certified`)


@register_jitable
def _scratch(k) -> _Scratch:
    """:class:`_Scratch` for the tree kernel ``k`` (no warm vectors yet)."""
    nv, nr, C = k.nv, k.rows[-1], k.ckind.shape[0]
    nj, m = k.parent.shape[0], k.act_v.shape[0] + k.rows[-1]
    return _Scratch(
        np.empty(nr), np.empty((nr, nv)), np.empty(C), np.empty((4, 4)), np.empty((nj, 6)),
        np.empty((nj, 6)), np.empty((nj, 6)), np.empty(6), np.zeros(6), np.zeros((3, 4)),
        np.empty(6), np.empty((6, 6)), np.empty((3, 3)), np.empty((6, nv)), np.empty(nv),
        np.empty(nv), np.empty(m), np.empty(m), np.empty(nv), np.empty((m, nv)),
        np.empty((m, nv)), np.eye(nv), np.empty(nv), np.empty((nr, nv)), np.empty((nv, nv)),
        np.empty((nv, nv)), np.empty(nv), np.empty((nv, nv)), np.empty(nv), np.empty(nv),
        np.empty(nv), np.empty(nv), np.empty(nv), np.empty(nv), np.zeros(1, np.int64),
        np.array([2, 2, 0, 0]))


@njit(cache=True, nogil=True)
def inverse_dynamics_kernel(k, Q, V_, A, body, armature, g, W, has_w, point, row_units, cons,
                            T, X, XW, RDD, DRIFT, INFO):
    """Inverse dynamics of the samples ``Q, V_, A`` (rows; ``W`` the wrenches when
    ``has_w``) on the tree kernel ``k`` (``body``, ``armature``: the tree's inertias,
    :class:`_Work`; gravity ``g``): per sample ``rnea`` into ``T``, the efforts then
    closure forces ``X`` (physical), the payload's part ``XW``, ``J a + J̇ v`` (``RDD``)
    and ``J̇ v`` (``DRIFT``), ``INFO`` = (status, balance residual, condition, rank,
    1 where the balance took the Jacobi SVD, 0 the LDLᵀ route of :func:`_balance`);
    status :data:`_TO_PYTHON` where a check does not pass. ``cons``: the assembly,
    rank, closeness and balance tolerances, the consistency tolerance and ``|g| / L``.
    Makes the work arrays, then :func:`_samples` runs the samples."""
    _samples(k, workspace(k), _scratch(k), Q, V_, A, body, armature, g, W, has_w, point,
             row_units, cons, T, X, XW, RDD, DRIFT, INFO)


# numba counts references to every array a compiled function passes to another one (two
# atomic operations per array and call: ~15 ns): the tree kernel, the workspace and the
# work arrays are ~70 arrays, passed to a dozen functions per sample, which cost more
# than the arithmetic. The sample loop allocates nothing and is compiled without
# reference counting (numba's ``_nrt`` option; its caller keeps the arrays alive).
# A call also passes each array of a named tuple member by member (~8 scalars per
# array): the functions that take the tree kernel or the work arrays whole (``k``,
# ``ws``, ``s``: ~500 scalars a call) are inlined into the loop (``inline="always"``,
# numba's own inlining: LLVM leaves functions of that size as calls).
@njit(cache=True, nogil=True, _nrt=False)
def _samples(k, ws, s, Q, V_, A, body, armature, g, W, has_w, point, row_units, cons, T, X,
             XW, RDD, DRIFT, INFO):
    """The loop of :func:`inverse_dynamics_kernel` (``ws``: the tree kernel's
    :func:`~pkm_pin.tree_kernel.workspace`, ``s``: :func:`_scratch`)."""
    nr, C, na = k.rows[-1], k.ckind.shape[0], k.act_v.shape[0]
    for i in range(Q.shape[0]):
        info = INFO[i]
        info[0] = _TO_PYTHON
        closure_rows(k, Q[i], ws, s.e, s.H, s.norms, s.oMo)
        if _norm(s.e) > cons[0]:
            continue
        _body_motions(k, ws.S, V_[i], A[i], s.Vb, s.Ab, s.s6)
        _rnea_world(k, ws.oMi, ws.S, s.Vb, s.Ab, A[i], body, armature, g, s.Fb, T[i])
        _second_derivative_world(k, ws, s.Vb, s.Ab, s.H, A[i], row_units, RDD[i], s.nud,
                                 s.Mh, s.lg, s.Jl, s.A3)
        if not _consistent(s.H, k.units, row_units, V_[i], A[i], RDD[i], cons[5], cons[4],
                           DRIFT[i], s.Hu):
            continue
        _output_columns(k, ws, point, s.Jo)
        _right_side(k, s.Jo, T[i], W[i], has_w, point, s.b, s.bw)
        rank, smax, smin, info[1], svd = _balance(k, s, cons, has_w)
        info[2], info[3] = smax / smin if rank else np.inf, rank
        for r in range(na + nr):
            unit = k.units[k.act_v[r]] if r < na else row_units[r - na]
            X[i, r], XW[i, r] = s.y[r] / unit, s.yw[r] / unit
        info[4] = svd
        if svd and _type_two(s.V, s.sv, cons[2] * smax, s.Jo, k.units, ws.F, 2 * C,
                             k.length, cons[2], s.s6):
            continue
        if info[1] <= cons[3]:
            info[0] = _OK


#: :func:`motion_kernel` solves ``M = [J; S]`` (dimensionless) where ``MᵀM −
#: MOTION_CERTIFY_RTOL ‖MᵀM‖_F I`` is positive definite: a condition below 1e5, far from
#: the type II threshold (:data:`CLOSENESS_SINGULAR_TOL`), and full column rank (no idle
#: motion); other samples go to the Python path, which decides.
MOTION_CERTIFY_RTOL = 1e-10


@njit(cache=True, nogil=True)
def motion_kernel(k, q, qd, qdd, row_units, cons, v, a, info):
    """:func:`motion_from_actuated` at one sample on the tree kernel ``k``: ``v``, ``a``
    and ``info[0]`` = :data:`_OK`, or :data:`_TO_PYTHON` where a check does not pass
    (``cons``: the assembly tolerance, :data:`MOTION_CERTIFY_RTOL`, the consistency
    tolerance). Makes the work arrays, then :func:`_motion_sample`."""
    _motion_sample(k, workspace(k), _scratch(k), q, qd, qdd, row_units, cons, v, a, info)


@njit(cache=True, nogil=True, _nrt=False)
def _motion_sample(k, ws, s, q, qd, qdd, row_units, cons, v, a, info):
    """The work of :func:`motion_kernel` (no allocation: see :func:`_samples`). With
    ``M = [J_c U; S]`` (dimensionless) of full column rank, certified by ``MᵀM = G``
    (:func:`_gram`, the balance's ``A Aᵀ``) minus ``cons[1] ‖G‖_F I`` being positive
    definite, ``v`` and ``a`` are the unique solutions of ``M x = rhs``
    (:func:`_full_rank_solve`); ``J̇ v`` from the bodies' motions at ``a = 0``."""
    info[0] = _TO_PYTHON
    nv, nr, na = k.nv, k.rows[-1], k.act_v.shape[0]
    closure_rows(k, q, ws, s.e, s.H, s.norms, s.oMo)
    if _norm(s.e) > cons[0]:
        return
    U = k.units
    for i in range(nr):
        for c in range(nv):
            s.Hu[i, c] = s.H[i, c] * U[c]
    _, fro = _gram(k.act_v, s.Hu, s.G)
    if not (_shifted_ldl(s.G, 1.0, cons[1] * math.sqrt(fro), s.L, s.inv)
            and _shifted_ldl(s.G, 1.0, 0.0, s.LG, s.invG)):
        return
    rhs = s.y  # (nr + na): closure rows, then actuated rows
    for r in range(nr):
        rhs[r] = 0.0
    for r in range(na):
        rhs[nr + r] = qd[r] / U[k.act_v[r]]
    if not _full_rank_solve(k.act_v, s.Hu, s.LG, s.invG, rhs, s.yw, s.z, s.rv, cons[2]):
        return
    for c in range(nv):
        v[c] = U[c] * s.rv[c]
        s.b[c] = 0.0
    _body_motions(k, ws.S, v, s.b, s.Vb, s.Ab, s.s6)
    _second_derivative_world(k, ws, s.Vb, s.Ab, s.H, s.b, row_units, s.e, s.nud, s.Mh,
                             s.lg, s.Jl, s.A3)  # J̇ v (physical) into e
    for r in range(nr):
        rhs[r] = -s.e[r] / row_units[r]
    for r in range(na):
        rhs[nr + r] = qdd[r] / U[k.act_v[r]]
    if not _full_rank_solve(k.act_v, s.Hu, s.LG, s.invG, rhs, s.yw, s.z, s.rv, cons[2]):
        return
    for c in range(nv):
        a[c] = U[c] * s.rv[c]
    info[0] = _OK


@register_jitable
def _full_rank_solve(act, Hu, LG, invG, rhs, r, z, x, tol) -> bool:
    """``x`` (nv) with ``M x = rhs``, ``M = [Hu; S]`` of full column rank, ``MᵀM`` factored
    in ``LG``, ``invG``: the normal equations and one step of iterative refinement
    (their ``eps κ(M)²`` down to ``eps κ(M)``); ``r``: the residual (nr + na), ``z``:
    work (nv). False where ``‖M x − rhs‖`` exceeds ``tol ‖rhs‖`` (rates the closures do
    not allow: the Python path raises)."""
    nr, nv, na = Hu.shape[0], Hu.shape[1], act.shape[0]
    for c in range(nv):
        x[c] = 0.0
    for r_ in range(nr + na):
        r[r_] = rhs[r_]
    for _ in range(2):  # x += (MᵀM)⁻¹ Mᵀ r, r = rhs − M x
        for c in range(nv):
            z[c] = 0.0
        for i in range(nr):
            for c in range(nv):
                z[c] += Hu[i, c] * r[i]
        for i in range(na):
            z[act[i]] += r[nr + i]
        ldl_solve(LG, nv, invG, z, z)
        for c in range(nv):
            x[c] += z[c]
        for i in range(nr):
            t = rhs[i]
            for c in range(nv):
                t -= Hu[i, c] * x[c]
            r[i] = t
        for i in range(na):
            r[nr + i] = rhs[nr + i] - x[act[i]]
    return _norm(r) <= tol * max(_norm(rhs), 1e-300)


def _compiled(model: ClosureModel, many: bool = False, kernel=None):
    """The tree kernel of ``model`` when the compiled path applies (joints
    :mod:`pkm_pin.tree_kernel` represents, the kernel ready, asked for often enough
    (:func:`~pkm_pin.compiling.prefer_compiled`) or ``many`` samples at once), else
    ``None``."""
    from . import tree_kernel

    if not tree_kernel.ENABLED:
        return None
    kern = tree_kernel.tree_kernel(model)
    kernel = inverse_dynamics_kernel if kernel is None else kernel
    if kern is None or not (prefer_compiled(kernel) or many):
        return None
    return kern


def _run_kernel(model: ClosureModel, kern, work: _Work, Q, V, A, g, W, tol) -> tuple:
    """:func:`inverse_dynamics_kernel` on the samples: ``(T, X, XW, RDD, DRIFT,
    INFO)``."""
    N, nv, nr, na = Q.shape[0], model.nv, work.n_rows, len(work.act_v)
    Q, V, A, g = (np.ascontiguousarray(x, dtype=np.float64) for x in (Q, V, A, g))
    T = np.empty((N, nv))
    has_w = W is not None
    W = np.ascontiguousarray(W, dtype=float) if has_w else np.zeros((N, 6))
    cons = np.array([ASSEMBLY_CHECK_RTOL, RANK_RTOL, CLOSENESS_SINGULAR_TOL,
                     EFFORT_BALANCE_RTOL, min(float(tol), 1e300),
                     float(np.linalg.norm(g)) / model.length])
    X, XW = np.zeros((N, na + nr)), np.zeros((N, na + nr))
    RDD, DRIFT, INFO = np.zeros((N, nr)), np.zeros((N, nr)), np.zeros((N, 5))
    inverse_dynamics_kernel(kern, Q, V, A, work.body, work.armature, g, W, has_w,
                            bool(model.output_point), work.row_units, cons, T, X, XW, RDD,
                            DRIFT, INFO)
    return T, X, XW, RDD, DRIFT, INFO


@dataclass(frozen=True)
class InverseDynamicsBatch:
    """:class:`InverseDynamics` of N samples (:func:`inverse_dynamics_batch`): the same
    attributes with a leading sample axis (``redundant_rows``, ``balance_residual`` and
    ``condition``: (N,)); ``compiled``: (N,) whether each sample went through the
    compiled kernel (else the Python path)."""

    efforts: np.ndarray
    actuated: tuple
    closure_forces: np.ndarray
    redundant_rows: np.ndarray
    payload_efforts: np.ndarray
    payload_closure_forces: np.ndarray
    tree_efforts: np.ndarray
    acceleration_residual: np.ndarray
    drift: np.ndarray
    balance_residual: np.ndarray
    condition: np.ndarray
    compiled: np.ndarray

    def __len__(self) -> int:
        return self.efforts.shape[0]

    def __getitem__(self, i: int) -> InverseDynamics:
        return InverseDynamics(
            efforts=self.efforts[i], actuated=self.actuated,
            closure_forces=self.closure_forces[i],
            redundant_rows=int(self.redundant_rows[i]),
            payload_efforts=self.payload_efforts[i],
            payload_closure_forces=self.payload_closure_forces[i],
            tree_efforts=self.tree_efforts[i],
            acceleration_residual=self.acceleration_residual[i], drift=self.drift[i],
            balance_residual=float(self.balance_residual[i]),
            condition=float(self.condition[i]))


def inverse_dynamics_batch(model: ClosureModel, Q, V, A, *, gravity=GRAVITY, wrenches=None,
                           tol: float = MOTION_CONSISTENCY_RTOL) -> InverseDynamicsBatch:
    """:func:`inverse_dynamics` of N samples at once (rows of ``Q`` (N, nq), ``V``, ``A``
    (N, nv); ``wrenches`` None or (N, 6), axis-first about the world origin): the same
    numbers (tests: 1e-10 relative), at a fraction of the cost of N calls. The shapes are
    checked once, Pinocchio's ``rnea`` gives each sample's tree efforts, and one compiled
    kernel (:func:`inverse_dynamics_kernel`: the closure rows and joint twists of
    :mod:`pkm_pin.tree_kernel`, the bodies' world accelerations ``A_j = A_p + S_j a_j +
    V_j × S_j v_j``, the closures' second derivative, the checks, the balance's SVD)
    does the rest. Samples the kernel does not pass (a check fails, a singular or
    unbalanced balance) and models it cannot represent (mimic joints) go through
    :func:`inverse_dynamics`, which raises its error (message prefixed with the sample
    index, attribute ``sample``) or returns.

    Raises:
        As :func:`inverse_dynamics`, for the first sample that fails.
    """
    Q, V, A, W = _batch_arrays(model, Q, V, A, wrenches)
    g = screws.as_vector3(gravity, "gravity")
    work, N = _work(model, masses=True), Q.shape[0]
    na, nr = len(work.act_v), work.n_rows
    kern = _compiled(model, many=N >= PLAIN_CALLS)
    if kern is not None:
        T, X, XW, RDD, DRIFT, INFO = _run_kernel(model, kern, work, Q, V, A, g, W, tol)
    else:
        T, X, XW = np.zeros((N, model.nv)), np.zeros((N, na + nr)), np.zeros((N, na + nr))
        RDD, DRIFT, INFO = np.zeros((N, nr)), np.zeros((N, nr)), np.zeros((N, 5))
        INFO[:, 0] = _TO_PYTHON
    for i in np.flatnonzero(INFO[:, 0] != _OK):
        try:
            r = _python_path(model, model.check_q(Q[i]), V[i], A[i], g,
                             None if W is None else W[i], tol)
        except PkmError as e:
            e.sample = int(i)
            if e.args and isinstance(e.args[0], str):
                e.args = (f"sample {i}: {e.args[0]}",) + e.args[1:]
            raise
        X[i] = np.r_[r.efforts, r.closure_forces]
        XW[i] = np.r_[r.payload_efforts, r.payload_closure_forces]
        T[i], RDD[i], DRIFT[i] = r.tree_efforts, r.acceleration_residual, r.drift
        INFO[i, 1:4] = r.balance_residual, r.condition, na + nr - r.redundant_rows
    return InverseDynamicsBatch(
        efforts=X[:, :na], actuated=tuple(model.actuated), closure_forces=X[:, na:],
        redundant_rows=(na + nr - INFO[:, 3]).astype(int), payload_efforts=XW[:, :na],
        payload_closure_forces=XW[:, na:], tree_efforts=T, acceleration_residual=RDD,
        drift=DRIFT, balance_residual=INFO[:, 1].copy(), condition=INFO[:, 2].copy(),
        compiled=INFO[:, 0] == _OK)


def _batch_arrays(model: ClosureModel, Q, V, A, wrenches) -> tuple:
    """The samples as C-contiguous float arrays of the right shapes, or an InputError."""
    Q = screws.as_float_array(Q, "Q")
    V = screws.as_float_array(V, "V")
    A = screws.as_float_array(A, "A")
    N = Q.shape[0] if Q.ndim == 2 else -1
    for name, X, n in (("Q", Q, model.nq), ("V", V, model.nv), ("A", A, model.nv)):
        if X.ndim != 2 or X.shape != (N, n):
            raise InputError(f"{name} must have shape (N, {n}) with N = {N} the samples of "
                             f"Q, got {X.shape}")
        if not np.isfinite(X).all():
            raise InputError(f"{name} must be finite")
    W = None
    if wrenches is not None:
        W = screws.as_float_array(wrenches, "wrenches")
        if W.shape != (N, 6) or not np.isfinite(W).all():
            raise InputError(f"wrenches must be finite, shape ({N}, 6), got {W.shape}")
    return (np.ascontiguousarray(Q), np.ascontiguousarray(V), np.ascontiguousarray(A),
            None if W is None else np.ascontiguousarray(W))
