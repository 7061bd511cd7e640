"""Dynamic design indices of a closed-loop mechanism (issue 26, item 5): the
actuator-space inertia, its eigenvalues and condition, the apparent inertia at the
output, and the gravity efforts over a workspace slice.

Written on the :class:`~pkm_pin.model.ClosureModel` (``q`` in its tree's order; the
actuated coordinates in its ``actuated`` order). docs/dynamics.md, "Dynamic design
indices", states the definitions and what is checked.

* ``G`` (nv × n) maps the actuated rates to the tree's rates, ``v = G q̇_a``: column k is
  :func:`pkm_pin.dynamics.motion_from_actuated` of the k-th unit rate (the elimination
  of the passive rates, ``[J; S] v = [0; q̇_a]``). Where idle motions (``N``: tree
  motions with every actuator still and the closures satisfied, e.g. a rod spinning
  about its axis) leave ``v`` undetermined, ``G`` is taken **M-orthogonal to them**,
  ``G = G₀ − N (NᵀMN)⁺ NᵀM G₀``: by Kelvin's theorem the motion with given actuated rates
  and free idle joints is the one of least kinetic energy, so ``G`` gives the inertia
  the actuators feel.
* **Actuator-space inertia** ``Λ = Gᵀ M G`` (n × n; ``M`` the tree's joint-space inertia,
  ``crba``): ``T = ½ q̇_aᵀ Λ q̇_a``. Units kg m² between revolute actuators, kg between
  prismatic ones, kg m across. Its eigenvalues and condition are taken on the
  **scaled** ``Λ̃ = Uₐ Λ Uₐ`` (``Uₐ`` the characteristic length ``L`` for a prismatic
  actuator, 1 for a revolute; every entry in kg m²): dimensionless condition
  ``κ = λ_max(Λ̃) / λ_min(Λ̃)``, unchanged by a change of unit of length; for actuators
  all of one kind it is the condition of ``Λ`` itself.
* **Apparent inertia at the output** ``Λ_x``: the output's twist is ``t = J_x q̇_a``,
  ``J_x = J_o G`` with ``t = (ω; v_P)`` **about the output frame's origin P, world axes**
  (6 × n), or ``v_P`` alone for a point output (3 × n). ``Λ_x = (J_x Λ⁻¹ J_xᵀ)⁺``, the
  pseudo-inverse taken on homogenised twists ``(ω; v_P / L)`` (so the choice is
  unit-free) and mapped back: ``Λ_x = D (D J_x Λ⁻¹ J_xᵀ D)⁺ D``, ``D = diag(1, 1, 1, 1/L,
  1/L, 1/L)``. Then ``T = ½ tᵀ Λ_x t`` for every twist the actuators can give (also when
  the output has fewer than six degrees of freedom, where ``Λ_x`` is zero on the twists
  it cannot make); with six independent actuators ``Λ_x = J_x⁻ᵀ Λ J_x⁻¹``. Blocks
  ``[[kg m², kg m], [kg m, kg]]`` in the order ``(ω; v)``; for a point output kg.
* **Gravity efforts**: the static efforts ``τ_g(q)`` that hold the mechanism under
  gravity (:func:`pkm_pin.dynamics.inverse_dynamics` at ``v = a = 0``), over a set of
  configurations (a workspace slice: from :meth:`Linkage.sweep` or a Mechanism's
  poses).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from . import dynamics, screws
from .errors import InputError, PkmError
from .model.closure_model import ClosureModel
from .tolerances import RANK_RTOL

GRAVITY = dynamics.GRAVITY


@dataclass(frozen=True)
class DynamicIndices:
    """The dynamic indices at one configuration (:func:`dynamic_indices`).

    Attributes:
        inertia: (n, n) ``Λ = Gᵀ M G`` [kg m², kg m, kg], ``actuated`` order.
        scaled_inertia: (n, n) ``Uₐ Λ Uₐ`` [kg m²].
        eigenvalues: (n,) ascending eigenvalues of :attr:`scaled_inertia` [kg m²] (of
            :attr:`inertia` itself when every actuator is revolute).
        condition: ``λ_max / λ_min`` of :attr:`scaled_inertia` (inf when singular).
        G: (nv, n) actuated rates → the tree's rates (M-orthogonal to idle motions).
        idle_motions: number of idle motions eliminated.
        output_inertia: (6, 6) ``Λ_x`` about the output's origin, world axes, ``(ω; v)``
            order; (3, 3) [kg] for a point output.
        output_jacobian: (6, n) or (3, n) ``J_x``: the output twist (about its origin)
            per unit actuated rate.
        actuated: names; units: ``"rad"`` or ``"m"`` per actuator; length: ``L`` [m].
    """

    inertia: np.ndarray
    scaled_inertia: np.ndarray
    eigenvalues: np.ndarray
    condition: float
    G: np.ndarray
    idle_motions: int
    output_inertia: np.ndarray
    output_jacobian: np.ndarray
    actuated: tuple
    units: tuple
    length: float

    def summary(self) -> dict:
        """JSON-ready: ``actuated``, ``units``, ``inertia`` (nested lists),
        ``eigenvalues`` [kg m²], ``condition`` (None when infinite), ``idle_motions``,
        ``output_inertia``, ``length``."""
        return {"actuated": list(self.actuated), "units": list(self.units),
                "inertia": self.inertia.tolist(), "eigenvalues": self.eigenvalues.tolist(),
                "condition": self.condition if np.isfinite(self.condition) else None,
                "idle_motions": self.idle_motions,
                "output_inertia": self.output_inertia.tolist(), "length": self.length}


def mass_matrix(model: ClosureModel, q) -> np.ndarray:
    """The tree's joint-space inertia ``M(q)`` (nv × nv, symmetric; ``crba`` in its WORLD
    convention, which Pinocchio 4.1 gets right with mimic joints on a reused Data)."""
    q = model.check_q(q)
    tree = model.tree
    M = pin.crba(tree, tree.createData(), q, pin.Convention.WORLD)
    return np.triu(M) + np.triu(M, 1).T


def actuated_map(model: ClosureModel, q, M: np.ndarray | None = None
                 ) -> tuple[np.ndarray, int]:
    """``(G, k)``: ``v = G q̇_a`` (nv × n, module docstring; M-orthogonal to the ``k``
    idle motions).

    Raises:
        SingularityError: at or near a type II singularity.
        InconsistentMotion: more actuators than degrees of freedom (or type I).
    """
    q = model.check_q(q)
    n = len(model.actuated)
    G = np.column_stack([dynamics.motion_from_actuated(model, q, e, np.zeros(n))[0]
                         for e in np.eye(n)]) if n else np.zeros((model.nv, 0))
    N = idle_motions(model, q)
    if N.shape[1] == 0:
        return G, 0
    M = mass_matrix(model, q) if M is None else M
    G = G - N @ (np.linalg.pinv(N.T @ M @ N, rcond=RANK_RTOL, hermitian=True) @ (N.T @ M @ G))
    return G, N.shape[1]


def idle_motions(model: ClosureModel, q) -> np.ndarray:
    """(nv, k) the idle motions at ``q``: the null space of ``[J_c U; S]`` (rank at
    :data:`RANK_RTOL` on dimensionless rows and coordinates), as physical velocities."""
    U = model.velocity_units
    act = list(model.actuated_v)
    Jc = model.closure_jacobian(q)
    H = np.zeros((len(Jc) + len(act), model.nv))
    H[:len(Jc)] = Jc * U
    H[len(Jc) + np.arange(len(act)), act] = 1.0
    rank, _, _, Vt = screws.svd_rank(H, RANK_RTOL)
    return U[:, None] * Vt[rank:].T


def actuator_units(model: ClosureModel) -> np.ndarray:
    """``Uₐ``: :attr:`ClosureModel.length` for a prismatic actuator, 1 for a revolute."""
    return model.velocity_units[list(model.actuated_v)].astype(float)


def dynamic_indices(model: ClosureModel, q) -> DynamicIndices:
    """Actuator-space inertia, its eigenvalues and condition, and the apparent inertia at
    the output, at the assembled configuration ``q`` (module docstring)."""
    q = model.check_q(q)
    M = mass_matrix(model, q)
    G, k = actuated_map(model, q, M)
    Lam = G.T @ M @ G
    Lam = 0.5 * (Lam + Lam.T)
    ua = actuator_units(model)
    scaled = ua[:, None] * Lam * ua
    ev = np.linalg.eigvalsh(scaled) if len(ua) else np.zeros(0)
    cond = float(ev[-1] / ev[0]) if len(ev) and ev[0] > 0 else float("inf")
    Jx, Lx = _output_inertia(model, q, G, Lam)
    return DynamicIndices(
        inertia=Lam, scaled_inertia=scaled, eigenvalues=ev, condition=cond, G=G,
        idle_motions=k, output_inertia=Lx, output_jacobian=Jx,
        actuated=tuple(model.actuated), units=_units(model, q), length=float(model.length))


def _units(model: ClosureModel, q: np.ndarray) -> tuple[str, ...]:
    """``"m"`` for an actuator whose joint translates (no rotation in its twist),
    ``"rad"`` otherwise."""
    twists = model.kinematics(q).joint_twists
    return tuple("m" if np.linalg.norm(twists[i, :3]) == 0.0 else "rad"
                 for i in model.actuated_v)


def _output_inertia(model: ClosureModel, q, G: np.ndarray, Lam: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """``(J_x, Λ_x)`` (module docstring)."""
    kin = model.kinematics(q)
    T = kin.output_jacobian @ G  # axis-first (ω; v_O) about the world origin
    p = kin.output_placement.translation
    if model.output_point:
        Jx = T[3:]
        D = np.ones(3)
    else:
        Jx = T.copy()
        Jx[3:] += np.cross(T[:3].T, p).T  # v_P = v_O + ω × p
        D = np.r_[np.ones(3), np.full(3, 1.0 / model.length)]
    Li = np.linalg.pinv(Lam, rcond=RANK_RTOL, hermitian=True)
    B = (D[:, None] * Jx) @ Li @ (D[:, None] * Jx).T
    Lx = D[:, None] * np.linalg.pinv(0.5 * (B + B.T), rcond=RANK_RTOL, hermitian=True) * D
    return Jx, 0.5 * (Lx + Lx.T)


# ------------------------------------------------------------ gravity over a slice
@dataclass(frozen=True)
class GravityMap:
    """Gravity efforts over configurations (:func:`gravity_efforts`), one row each.

    Attributes:
        q: (N, nq) the configurations (nan rows: not assembled).
        efforts: (N, n) static efforts holding the mechanism under gravity (plus the
            wrench, if given) [N m or N], nan where not computed.
        ok: (N,) whether the row was computed.
        reasons: (index, message) of every row not computed (not assembled, singular,
            an idle motion that gravity drives).
        condition: (N,) :attr:`DynamicIndices.condition` when asked for (else nan).
        actuated: names.
    """

    q: np.ndarray
    efforts: np.ndarray
    ok: np.ndarray
    reasons: list
    condition: np.ndarray
    actuated: tuple

    @property
    def peak(self) -> np.ndarray:
        """(n,) the largest ``|τ_g|`` of each actuator over the computed rows."""
        if not self.ok.any():
            return np.full(len(self.actuated), np.nan)
        return np.abs(self.efforts[self.ok]).max(axis=0)


def gravity_efforts(model: ClosureModel, configurations, *, gravity=GRAVITY, wrench=None,
                    condition: bool = False) -> GravityMap:
    """The static efforts under gravity at each configuration (rows of
    ``configurations``, (N, nq); nan rows, as a sweep leaves where it did not assemble,
    are skipped), optionally with the actuator-inertia condition
    (:func:`dynamic_indices`). ``wrench`` as :func:`pkm_pin.dynamics.inverse_dynamics`."""
    Q = screws.as_float_array(configurations, "configurations")
    if Q.ndim != 2 or Q.shape[1] != model.nq:
        raise InputError(f"configurations must have shape (N, {model.nq}) (the tree's "
                         f"configuration per row), got {Q.shape}")
    n, N = len(model.actuated), len(Q)
    eff, ok = np.full((N, n), np.nan), np.zeros(N, bool)
    cond, reasons = np.full(N, np.nan), []
    zero = np.zeros(model.nv)
    for i, q in enumerate(Q):
        if not np.isfinite(q).all():
            reasons.append((i, "not assembled"))
            continue
        try:
            eff[i] = dynamics.inverse_dynamics(model, q, zero, zero, gravity=gravity,
                                               wrench=wrench).efforts
            if condition:
                cond[i] = dynamic_indices(model, q).condition
        except PkmError as e:
            reasons.append((i, str(e)))
            continue
        ok[i] = True
    return GravityMap(q=Q, efforts=eff, ok=ok, reasons=reasons, condition=cond,
                      actuated=tuple(model.actuated))
