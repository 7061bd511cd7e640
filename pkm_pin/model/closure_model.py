"""The closure model: every mechanism as one kinematic tree plus closures.

A :class:`ClosureModel` is the general description of a closed-loop mechanism
(DESIGN.md, "One closure model"): one Pinocchio model (``tree``), the loops closed by
:class:`Closure` s between pairs of frames of that tree, the actuated joints and the
output frame whose motion is analysed. A base–legs–platform :class:`~pkm_pin.Mechanism`
is the legs appended under the universe at their base placements plus the platform as a
free-flyer body, each leg tip welded to it (:func:`from_mechanism`).

Velocity picture: ``J_c v = 0`` (:meth:`ClosureModel.closure_jacobian`) and ``t = J_o v``
(:meth:`ClosureModel.output_jacobian`), ``v`` the tree's velocity (Pinocchio's tangent
space: the velocity a step of ``pin.integrate`` is taken along; a free flyer's rates are
its body-frame ``(v; ω)``). The mobility is the dimension of the null space of ``J_c``;
the output twists the closures allow are ``J_o`` times that null space.

Conventions:

* Twists are axis-first ``(ω; v_O)`` [rad/s; m/s] about the **world origin**, as in
  :mod:`pkm_pin.screws`; Pinocchio's ``(v; ω)`` is converted only by
  :func:`pkm_pin.screws.from_pinocchio` / :func:`~pkm_pin.screws.to_pinocchio`.
* Closure ``c`` relates its constraint frames ``C_a = frame_a * placement_a`` and
  ``C_b = frame_b * placement_b`` through ``M = C_a⁻¹ C_b`` (``C_b`` seen from
  ``C_a``); every residual is expressed in ``C_a``, so it does not change when the whole
  mechanism is moved in the world. Its rows, dimensionless (``L`` the characteristic
  length :attr:`ClosureModel.length` [m]):

  - ``"weld"`` (6): ``log6(M)`` axis-first, ``(θ [rad]; ρ / L)``: ``θ`` the rotation
    vector of ``M``, ``ρ`` the linear part of the logarithm (``M``'s translation to
    first order);
  - ``"point"`` (3): the position of ``C_b``'s origin in ``C_a``, divided by ``L``;
  - ``"revolute"`` (5): the point rows, then the x and y components (in ``C_a``) of
    ``C_b``'s z axis: the revolute axis is the z axis of both constraint frames;
  - ``"coupling"`` (1): a linear coupling of two joint coordinates (an MJCF ``<joint>``
    equality): ``(q_a − c₁ q_b − c₀) / u_a``, ``q_a`` the coordinate of ``frame_a``'s
    parent joint, ``q_b`` that of ``frame_b``'s (0 when ``frame_b`` is on the universe:
    ``q_a = c₀``), ``(c₀, c₁)`` = :attr:`Closure.coef`, ``u_a`` joint a's velocity unit
    (``L`` for a prismatic joint, 1 for a revolute): its Jacobian row has ``1 / u_a`` in
    ``q_a``'s column and ``−c₁ / u_a`` in ``q_b``'s. Both joints move along one
    coordinate (revolute, prismatic); the placements are not used.

* :meth:`ClosureModel.closure_jacobian` is ``d residual / dv`` (one column per velocity
  coordinate), built from Pinocchio's ``LOCAL`` frame Jacobians of ``frame_a`` and
  ``frame_b`` and the relative placement ``M`` (body velocity of ``C_b`` relative to
  ``C_a`` in ``C_b``, then ``Jlog6`` for welds): frame-invariant by construction.
* Rank decisions (:meth:`~ClosureModel.mobility`, :meth:`~ClosureModel.output_twists`)
  are unit- and frame-invariant: the columns of ``J_c`` are the rates of dimensionless
  coordinates (a coordinate whose motion is a pure translation is counted in lengths
  ``L``, :attr:`ClosureModel.velocity_units`); output twists are homogenised (linear
  part / ``L``) about the output frame's origin, in its axes; singular values below
  ``rtol`` (:data:`pkm_pin.tolerances.RANK_RTOL`) times the largest are zero.

The description is immutable (the tree is a private copy; do not modify it). Every
method runs one Pinocchio pass: :meth:`ClosureModel.kinematics` in a ``pin.Data`` of its
own (kept by the :class:`TreeKinematics` it returns), the others in a working ``Data``
per thread that no result refers to: safe to call from several threads. The index lists
of that pass (frames, support columns, rows of each closure kind, actuated coordinates)
are made once, at construction (:class:`_Plan`); the closure rows of all closures are
computed together (vectorised over closures).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .. import screws
from ..errors import InputError, TreeFrameNotFound, TreeJointNotFound, _cut
from ..tolerances import RANK_RTOL, SPARSE_ZERO_RTOL, ZERO_SCREW_RTOL

if TYPE_CHECKING:  # pragma: no cover
    from ..assembly import Assembly
    from ..mechanism import Mechanism

#: Rows constrained by each closure kind.
KINDS = {"weld": 6, "point": 3, "revolute": 5, "coupling": 1}

#: The closure kind that couples two joint coordinates (not two frames' placements).
COUPLING = "coupling"

#: Name of the platform's body frame and free-flyer joint in :func:`from_mechanism`.
PLATFORM = "platform"
PLATFORM_JOINT = "platform_joint"


@dataclass(frozen=True)
class Closure:
    """One loop closure between two frames of the tree.

    Attributes:
        kind: ``"weld"`` (6 rows: same placement), ``"point"`` (3 rows: same point),
            ``"revolute"`` (5 rows: same point and same z axis) or ``"coupling"`` (1 row:
            ``q_a = c₀ + c₁ q_b``, the coordinates of the two frames' parent joints).
        frame_a: Frame of the tree carrying the first constraint frame (a coupling: a
            frame of the coupled joint ``a``, e.g. its joint frame).
        frame_b: Frame of the tree carrying the second constraint frame (a coupling: a
            frame of joint ``b``; a frame of the universe for ``q_a = c₀``).
        placement_a: Constraint frame ``C_a`` in ``frame_a`` (not used by a coupling).
        placement_b: Constraint frame ``C_b`` in ``frame_b`` (not used by a coupling).
        name: Name of the closure (for messages).
        coef: ``(c₀, c₁)`` of a coupling [c₀ in joint a's unit, rad or m; c₁ in joint a's
            unit per joint b's]; ignored by the other kinds.
    """

    kind: str
    frame_a: str
    frame_b: str
    placement_a: pin.SE3 = field(default_factory=pin.SE3.Identity)
    placement_b: pin.SE3 = field(default_factory=pin.SE3.Identity)
    name: str = ""
    coef: tuple[float, float] = (0.0, 1.0)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InputError(f"closure {self.name!r}: unknown kind {self.kind!r}; "
                             f"the kinds are {sorted(KINDS)}")
        try:
            coef = tuple(float(c) for c in self.coef)
        except (TypeError, ValueError) as e:
            raise InputError(f"closure {self.name!r}: coef must be two numbers (c0, c1), "
                             f"got {self.coef!r}") from e
        if len(coef) != 2 or not np.isfinite(coef).all():
            raise InputError(f"closure {self.name!r}: coef must be two finite numbers "
                             f"(c0, c1), got {self.coef!r}")
        object.__setattr__(self, "coef", coef)
        for key in ("frame_a", "frame_b"):
            if not isinstance(getattr(self, key), str):
                raise InputError(f"closure {self.name!r}: {key} must be a frame name (str)")
        for key in ("placement_a", "placement_b"):
            value = getattr(self, key)
            if not isinstance(value, pin.SE3) or not np.isfinite(value.homogeneous).all():
                raise InputError(f"closure {self.name!r}: {key} must be a finite pinocchio.SE3")

    @property
    def dim(self) -> int:
        """Number of rows the closure constrains (6, 3, 5 or 1)."""
        return KINDS[self.kind]

    @property
    def joins_frames(self) -> bool:
        """Whether the closure holds two frames together (a loop of bodies): every kind
        but a coupling of joint coordinates."""
        return self.kind != COUPLING


@dataclass(frozen=True, eq=False)
class ClosureModel:
    """A mechanism as one kinematic tree plus closures (see the module docstring).

    Attributes:
        tree: The Pinocchio model of the tree (copied: the description is immutable).
        closures: The loop closures.
        actuated: Names of the actuated joints of the tree, in actuated-coordinate order.
        output: Name of the output frame (the platform).
        name: Name of the mechanism.
        length: Characteristic length [m] of the residuals and rank decisions; default:
            the sum of the offsets between the tree's joints (not the root placements)
            and of the closures' placements, 1.0 when that is zero.
        output_point: The output is a **point**, the output frame's origin (legs meeting
            at a pin, a point "platform"): its rotation is not analysed, the output
            Jacobian's columns are pure translations ``(0; v_p)``
            (:meth:`output_jacobian`), and its pose is its position.
        reference: Reference configuration of the tree (nq,), the one assembly starts
            from (a file's ``q = 0`` or MJCF ``qpos0``; it need not satisfy the
            closures); default ``pinocchio.neutral(tree)``. Read-only.
        actuator_matches: What the file named as actuators and which joints each name
            picked, ``((identifier, (joint, ...)), ...)`` in the file's order (an Extended
            URDF's ``name_mot`` entries, an MJCF's actuators); empty for a model made in
            code. Reports may list it.
        notes: Sentences a reader adds about how it read the file (e.g. a free joint at
            the root held as the base); reports print them.
        output_named: Whether the output was named (by the caller, or by the file)
            rather than taken from a reader's fallback (a frame called ``effector``, the
            last body): :func:`pkm_pin.io.load_mechanism` chooses a designer's output
            (:mod:`pkm_pin.output_choice`) where it was not.
        springs: Joints the file gives a spring and no actuator (an MJCF joint's
            ``stiffness``: Cassie's shin and heel springs): they stay joints of the
            analysis (their motions are idle), and the default output is chosen as if
            they were held (:mod:`pkm_pin.output_choice`), so that it is the body the
            motors move, not a link above the springs.
    """

    tree: pin.Model = field(repr=False)
    closures: tuple[Closure, ...]
    actuated: tuple[str, ...]
    output: str
    name: str = ""
    length: float | None = None
    reference: np.ndarray | None = field(default=None, repr=False)
    output_point: bool = False
    actuator_matches: tuple = ()
    notes: tuple[str, ...] = ()
    output_named: bool = True
    springs: tuple[str, ...] = ()
    _frame_ids: dict = field(init=False, repr=False)
    _units: np.ndarray = field(init=False, repr=False)
    _plan: _Plan = field(init=False, repr=False)
    _local: threading.local = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.tree, pin.Model):
            raise InputError(f"tree must be a pinocchio.Model, got {type(self.tree).__name__}")
        tree = pin.Model(self.tree)
        closures = tuple(self.closures)
        for c in closures:
            if not isinstance(c, Closure):
                raise InputError(f"closures must be Closure objects, got {type(c).__name__}")
        if isinstance(self.actuated, str):
            raise InputError("actuated must be a sequence of joint names, not one string")
        set_ = object.__setattr__
        set_(self, "tree", tree)
        set_(self, "closures", closures)
        set_(self, "actuated", tuple(self.actuated))
        matches = self.actuator_matches
        try:
            matches = tuple((str(k), tuple(str(j) for j in v)) for k, v in (
                matches.items() if isinstance(matches, dict) else matches))
        except (TypeError, ValueError) as e:
            raise InputError("actuator_matches must be pairs (identifier, joint names), got "
                             f"{type(matches).__name__}") from e
        set_(self, "actuator_matches", matches)
        set_(self, "notes", tuple(str(n) for n in self.notes))
        set_(self, "springs", _springs(tree, self.springs, self.actuated))
        set_(self, "_frame_ids", _frame_ids(tree, closures, self.output, self.name))
        _check_closures_join_two_bodies(tree, closures, self.name)
        _check_couplings(tree, closures, self.name)
        _check_actuated(tree, self.actuated, self.name)
        set_(self, "length", _length(tree, closures, self.length))
        reference = pin.neutral(tree) if self.reference is None else screws.as_vector(
            self.reference, tree.nq, f"the reference configuration of {self.name or 'the tree'}",
            "the tree's configuration vector").copy()
        reference.setflags(write=False)
        set_(self, "reference", reference)
        units = velocity_units(tree, self.length)
        units.setflags(write=False)
        set_(self, "_units", units)
        set_(self, "_plan", _Plan(self))
        set_(self, "_local", threading.local())

    def __getstate__(self) -> dict:
        """Pickle: the description (not the per-thread working data, nor the compiled
        tree of :func:`pkm_pin.tree_kernel.tree_kernel`, made again on first use)."""
        return {k: v for k, v in self.__dict__.items() if k not in ("_local", "_tree_kernel")}

    def __setstate__(self, state: dict) -> None:
        """Unpickle: the description as pickled, its arrays read-only again."""
        self.__dict__.update(state)
        self.__dict__["_local"] = threading.local()
        self._units.setflags(write=False)
        self.reference.setflags(write=False)

    # ------------------------------------------------------------------- sizes
    @property
    def nq(self) -> int:
        """Size of the tree's configuration vector."""
        return self.tree.nq

    @property
    def nv(self) -> int:
        """Number of the tree's velocity coordinates (columns of the Jacobians)."""
        return self.tree.nv

    @property
    def n_rows(self) -> int:
        """Number of closure rows (the sum of the closures' :attr:`Closure.dim`)."""
        return self._plan.n_rows

    @cached_property
    def translating(self) -> np.ndarray:
        """Whether each velocity coordinate is a length (its motion a pure translation:
        :func:`translating_coordinates`), not an angle; read-only. Decide an actuated
        joint's unit from this, not from :attr:`velocity_units` (``L`` may be 1)."""
        out = translating_coordinates(self.tree)
        out.setflags(write=False)
        return out

    @property
    def velocity_units(self) -> np.ndarray:
        """Unit of each velocity coordinate (read-only): :attr:`length` [m] for a
        coordinate whose motion is a pure translation (prismatic joints, the linear rates
        of a free flyer), 1 [rad] for the others. ``J_c * velocity_units`` is the
        dimensionless matrix whose rank is decided."""
        return self._units

    @property
    def actuated_v(self) -> tuple[int, ...]:
        """Velocity index of each actuated joint (its first coordinate)."""
        return self._plan.act_v_tuple

    def actuated_values(self, q) -> np.ndarray:
        """Values [rad or m] of the actuated joints at ``q``: the coordinate of a 1-DOF
        joint, the angle ``atan2(sin, cos)`` of a continuous (unbounded) revolute; an
        :class:`InputError` for an actuated joint with several degrees of freedom."""
        return self._plan.actuated_values(self.check_q(q), self)

    def check_q(self, q) -> np.ndarray:
        """``q`` as a finite array of shape (nq,), or an :class:`InputError`."""
        if screws.is_vector(q, self.tree.nq):
            return q
        return screws.as_vector(q, self.nq, f"the configuration of {self.name or 'the tree'}",
                                "the tree's configuration vector")

    # ---------------------------------------------------------------- residuals
    def closure_residual(self, q) -> np.ndarray:
        """Stacked residuals of every closure at ``q`` (dimensionless, module docstring)."""
        return self._pass(self.check_q(q), self._work_data())[0]

    def closure_jacobian(self, q) -> np.ndarray:
        """``d closure_residual / dv`` (n_rows × nv) at ``q``, ``v`` the tree's velocity."""
        return self._pass(self.check_q(q), self._work_data())[1]

    def output_jacobian(self, q) -> np.ndarray:
        """6 × nv: column k is the axis-first twist ``(ω; v_O)`` of the output frame,
        about the world origin, for a unit rate of velocity coordinate k; with
        :attr:`output_point`, the translation ``(0; v_p)`` at the velocity of its origin."""
        return self._pass(self.check_q(q), self._work_data())[2]

    # ----------------------------------------------------------------- mobility
    def mobility(self, q, rtol: float = RANK_RTOL) -> int:
        """Dimension of the tree's motions allowed by the closures at ``q``:
        ``nv − rank J_c`` (rank decided on ``J_c * velocity_units``)."""
        rank, _ = _rank_and_null(self.closure_jacobian(q) * self._units, rtol)
        return self.nv - rank

    def redundant_constraints(self, q, rtol: float = RANK_RTOL) -> int:
        """Closure rows that are dependent at ``q``: ``n_rows − rank J_c``."""
        rank, _ = _rank_and_null(self.closure_jacobian(q) * self._units, rtol)
        return self.n_rows - rank

    def output_twists(self, q, rtol: float = RANK_RTOL) -> np.ndarray:
        """Basis (k × 6, one twist per row, axis-first about the world origin) of the
        output frame's twists allowed by the closures at ``q``: the span of ``J_o N``, N
        a basis of the null space of ``J_c``.

        Its dimension is decided on twists homogenised about the output frame's origin;
        the rows returned are orthonormal once their linear parts are divided by
        :attr:`length` (as :attr:`pkm_pin.Analysis.platform_twists`).
        """
        _, Jc, Jo, oMo = self._pass(self.check_q(q), self._work_data())
        _, N = _rank_and_null(Jc * self._units, rtol)
        T = (Jo @ (self._units[:, None] * N)).T
        return _orthonormal_span(T, oMo, self.length, rtol)

    def origins(self, q) -> tuple[np.ndarray, pin.SE3]:
        """``(P, oMo)``: the world origins of the tree's joints (njoints − 1 × 3, the
        universe left out) and the output frame's placement at ``q``; one forward pass
        in this thread's working data (a ``Data`` of a large tree costs milliseconds to
        make: a humanoid's 130 coordinates, 3–40 ms)."""
        q = self.check_q(q)
        tree, data = self.tree, self._work_data()
        pin.forwardKinematics(tree, data, q)
        oMo = pin.updateFramePlacement(tree, data, self.frame_id(self.output))
        P = np.array([data.oMi[j].translation for j in range(1, tree.njoints)]).reshape(-1, 3)
        return P, pin.SE3(oMo)

    def kinematics(self, q) -> TreeKinematics:
        """Everything first-order at ``q`` from one Pinocchio pass (:class:`TreeKinematics`)."""
        q = self.check_q(q)
        return TreeKinematics(self, q, self.tree.createData())

    def frame_id(self, name: str) -> int:
        """Index in :attr:`tree` of a frame the closures or the output name (resolved once,
        when the model was made: a name an MJCF body shares with a joint names one frame
        here)."""
        try:
            return self._frame_ids[name]
        except KeyError:
            raise TreeFrameNotFound(str(name), list(self._frame_ids), "the frames the "
                                    "closures and the output name") from None

    def closure_rates(self, kin: TreeKinematics, motions: np.ndarray) -> np.ndarray:
        """The closure rows' rates (:meth:`closure_residual` rows × n) when the closures'
        frames move by the world twists ``motions`` (2C × 6 × n, axis-first ``(ω; v_O)``:
        each closure's ``frame_a``, then each closure's ``frame_b``) at the configuration
        of ``kin``: closure-Jacobian columns of motions that are not joints' (a geometric
        error's virtual twist). Coupling rows, which no frame motion changes, are 0."""
        motions = np.asarray(motions, dtype=float)
        n = motions.shape[-1]
        if motions.shape != (2 * len(self.closures), 6, n):
            raise InputError(f"motions must be (2C, 6, n) = ({2 * len(self.closures)}, 6, n), "
                             f"got {motions.shape}")
        plan = self._plan
        H = np.array([kin.frame_placements[f].homogeneous for f in plan.frames[:-1]])
        J = np.concatenate([motions, np.zeros((1, 6, n))])
        rates = plan._closure_rows(H.reshape(-1, 4, 4), J)[1]
        if plan.couplings is not None:
            rates[plan.couplings[0]] = 0.0
        return rates

    def closure_slices(self) -> tuple[slice, ...]:
        """Rows of each closure in :meth:`closure_residual` (closure order)."""
        return self._plan.slices

    def closure_norms(self, residual: np.ndarray) -> np.ndarray:
        """Norm of each closure's rows of ``residual`` (closure order)."""
        return self._plan.closure_norms(residual)

    # ---------------------------------------------------------- Pinocchio passes
    def _work_data(self) -> pin.Data:
        """This thread's working ``Data`` (never referred to by a result)."""
        data = getattr(self._local, "data", None)
        if data is None:
            data = self._local.data = self.tree.createData()
        return data

    def _pass(self, q: np.ndarray, data: pin.Data) -> tuple:
        """One Pinocchio pass at ``q`` in ``data``: ``(residual, closure Jacobian, output
        Jacobian, output placement)``, new arrays."""
        pin.computeJointJacobians(self.tree, data, q)
        pin.updateFramePlacements(self.tree, data)
        return self._plan.evaluate(data, self, q)


class _Plan:
    """The index lists and constants of a :class:`ClosureModel`'s one-pass kinematics,
    made once at construction.

    ``frames``: frame ids ``[frame_a of each closure, frame_b of each closure, output]``;
    ``placements`` (2C × 4 × 4): the constraint frames in them; ``support`` (2C + 1 ×
    nv): 1 where a velocity coordinate moves that frame (its joint's supporting joints);
    ``rows``: per kind, the closures of that kind and their rows in the stacked residual.
    Without mimicking joints, ``data.J`` (every joint's world twist) times ``support``
    is a frame's world Jacobian; with them, ``getFrameJacobian`` is called per frame.
    """

    def __init__(self, model: ClosureModel):
        tree, closures = model.tree, model.closures
        ids = model._frame_ids
        C = len(closures)
        self.C, self.nv, self.length = C, tree.nv, model.length
        self.frames = [ids[c.frame_a] for c in closures] + [ids[c.frame_b] for c in closures]
        self.frames.append(ids[model.output])
        self.placements = np.array([c.placement_a.homogeneous for c in closures]
                                   + [c.placement_b.homogeneous for c in closures]
                                   ).reshape(2 * C, 4, 4)
        self.support = np.array([_support(tree, tree.frames[f].parentJoint)
                                 for f in self.frames])
        self.relative = self.support[C:2 * C] - self.support[:C]
        self.mimic = any(tree.joints[j].shortname() == "JointModelMimic"
                         for j in range(1, tree.njoints))
        self.point_output = model.output_point
        ends = np.cumsum([0] + [c.dim for c in closures])
        self.slices = tuple(slice(int(a), int(b)) for a, b in zip(ends[:-1], ends[1:]))
        self.starts = ends[:-1]
        self.n_rows = int(ends[-1])
        self.rows = {kind: _kind_rows(closures, ends, kind) for kind in KINDS}
        self.couplings = _coupling_plan(tree, closures, model.velocity_units)
        self.all_points = C > 0 and all(c.kind == "point" for c in closures)
        self.placed = any(not c.placement_a.isIdentity() or not c.placement_b.isIdentity()
                          for c in closures)
        joints = [tree.joints[tree.getJointId(a)] for a in model.actuated]
        self.act_v = np.array([j.idx_v for j in joints], dtype=int)
        self.act_v_tuple = tuple(int(j.idx_v) for j in joints)
        self.act_q = np.array([j.idx_q for j in joints], dtype=int)
        self.act_ok = all(j.nv == 1 and j.nq in (1, 2) for j in joints)
        self.act_plain = all(j.nv == 1 and j.nq == 1 for j in joints)
        self.limits = _position_limits(tree)
        self.act_scales = model.velocity_units[self.act_v]
        self.act_rows = np.zeros((len(joints), tree.nv))  # d(q_a / s_a) / dv
        self.act_rows[np.arange(len(joints)), self.act_v] = 1.0 / self.act_scales

    def actuated_values(self, q: np.ndarray, model: ClosureModel) -> np.ndarray:
        """The actuated joints' values (:meth:`ClosureModel.actuated_values`)."""
        if self.act_plain:
            return q[self.act_q]
        if not self.act_ok:
            for name in model.actuated:
                joint = model.tree.joints[model.tree.getJointId(name)]
                if joint.nv != 1 or joint.nq not in (1, 2):
                    raise InputError(f"actuated joint {name!r} has {joint.nv} degrees of "
                                     "freedom and no single actuated value")
        out = np.empty(len(self.act_q))
        for k, (i, name) in enumerate(zip(self.act_q, model.actuated)):
            nq = model.tree.joints[model.tree.getJointId(name)].nq
            out[k] = q[i] if nq == 1 else np.arctan2(q[i + 1], q[i])
        return out

    def closure_norms(self, residual: np.ndarray) -> np.ndarray:
        """Norm of each closure's rows of ``residual``."""
        if self.C == 0:
            return np.zeros(0)
        return np.sqrt(np.add.reduceat(residual * residual, self.starts))

    def world_jacobians(self, data: pin.Data, model: ClosureModel) -> np.ndarray:
        """(2C + 1) × 6 × nv axis-first world Jacobians ``(ω; v_O)`` of the frames."""
        if not self.mimic:
            return screws.from_pinocchio(_six_by(data.J, self.nv))[None] \
                * self.support[:, None, :]
        return np.array([screws.from_pinocchio(_six_by(pin.getFrameJacobian(
            model.tree, data, f, pin.WORLD), self.nv)) for f in self.frames])

    def evaluate(self, data: pin.Data, model: ClosureModel, q: np.ndarray) -> tuple:
        """``(residual, closure Jacobian, output Jacobian, output placement)`` at ``q``
        from a ``data`` after ``computeJointJacobians`` and ``updateFramePlacements``."""
        oMf = data.oMf
        H = np.array([oMf[f].homogeneous for f in self.frames])
        J = self.world_jacobians(data, model)
        residual, jacobian = self._closure_rows(H[:-1], J)
        self._coupling_rows(q, residual, jacobian)
        oMo = pin.SE3(H[-1])
        Jo = J[-1]
        if self.point_output:  # the origin's velocity v_O + ω × p
            Jo = np.vstack([np.zeros((3, self.nv)), Jo[3:] - _skew(H[-1:, :3, 3])[0] @ Jo[:3]])
        return residual, jacobian, Jo, oMo

    def _closure_rows(self, H: np.ndarray, J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual and Jacobian rows of every closure (module docstring), vectorised
        (``J``: the frames' world Jacobians, (2C + 1) × 6 × n: the joints' columns, or
        any other motions of the frames, e.g. a geometric error's virtual twists):
        ``M = C_a⁻¹ C_b``, the relative motion's velocity at ``C_b``'s origin ``p_b``,
        ``V = v_O + ω × p_b`` (world axes), in ``C_a`` axes for point and revolute rows,
        in ``C_b`` axes (the body twist) for a weld's ``Jlog6``."""
        C, L, n = self.C, self.length, J.shape[-1]
        residual, jacobian = np.empty(self.n_rows), np.empty((self.n_rows, n))
        if C == 0:
            return residual, jacobian
        Cw = H @ self.placements if self.placed else H
        Ra_T, pa, Rb, pb = Cw[:C, :3, :3].transpose(0, 2, 1), Cw[:C, :3, 3], Cw[C:, :3, :3], \
            Cw[C:, :3, 3]
        W = J[C:2 * C, :3] - J[:C, :3]  # relative angular velocity (world)
        V = J[C:2 * C, 3:] - J[:C, 3:] - _skew(pb) @ W  # v_O + ω × p_b
        if self.all_points:  # the common case, without index lists
            d = np.einsum("cij,cj->ci", Ra_T, pb - pa)
            return d.reshape(-1) / L, (Ra_T @ V).reshape(-1, n) / L
        index, rows = self.rows[COUPLING]
        if index.size:  # filled by _coupling_rows
            jacobian[rows[:, 0]] = 0.0
        for kind in ("point", "revolute"):
            index, rows = self.rows[kind]
            if index.size:
                d = np.einsum("cij,cj->ci", Ra_T[index], pb[index] - pa[index]) / L
                rate = Ra_T[index] @ V[index] / L
                residual[rows[:, :3]] = d
                jacobian[rows[:, :3]] = rate
        index, rows = self.rows["revolute"]
        if index.size:  # x, y of C_b's z axis in C_a: d(R_aᵀ z_b) = R_aᵀ (ω_rel × z_b)
            zb = Rb[index, :, 2]
            residual[rows[:, 3:]] = np.einsum("cij,cj->ci", Ra_T[index], zb)[:, :2]
            jacobian[rows[:, 3:]] = -(Ra_T[index] @ _skew(zb) @ W[index])[:, :2]
        index, rows = self.rows["weld"]
        for k, c in enumerate(index):
            M = pin.SE3(Cw[c][:3, :3].T @ Cw[C + c][:3, :3],
                        Cw[c][:3, :3].T @ (pb[c] - pa[c]))
            Rb_T = Rb[c].T
            nu = screws.to_pinocchio(np.vstack([Rb_T @ W[c], Rb_T @ V[c]]))  # body twist in C_b
            log = screws.from_pinocchio(pin.log6(M))  # (θ; ρ)
            rates = screws.from_pinocchio(pin.Jlog6(M) @ nu)
            residual[rows[k]] = np.r_[log[:3], log[3:] / L]
            jacobian[rows[k]] = np.vstack([rates[:3], rates[3:] / L])
        return residual, jacobian


    def _coupling_rows(self, q: np.ndarray, residual: np.ndarray, jacobian: np.ndarray
                       ) -> None:
        """The coupling rows (module docstring) into ``residual`` and ``jacobian``, in
        place (their other entries of ``jacobian`` already zero)."""
        plan = self.couplings
        if plan is None:
            return
        rows, qa, qb, va, vb, c0, c1, inv_u = plan
        residual[rows] = (q[qa] - c1 * np.where(qb >= 0, q[qb], 0.0) - c0) * inv_u
        jacobian[rows, va] = inv_u
        has_b = vb >= 0
        jacobian[rows[has_b], vb[has_b]] -= c1[has_b] * inv_u[has_b]


def _coupling_plan(tree: pin.Model, closures: tuple, units: np.ndarray) -> tuple | None:
    """Index arrays of the coupling closures: ``(rows, q index of a, of b, v index of a,
    of b, c0, c1, 1 / u_a)`` (b's indices −1 on the universe), or None without any."""
    ends = np.cumsum([0] + [c.dim for c in closures])
    picked = [(ends[i], c) for i, c in enumerate(closures) if c.kind == COUPLING]
    if not picked:
        return None
    cols: list = [[] for _ in range(8)]
    for row, c in picked:
        ja, jb = (tree.frames[tree.getFrameId(f)].parentJoint for f in (c.frame_a, c.frame_b))
        a = tree.joints[ja]
        b = tree.joints[jb] if jb > 0 else None
        for k, value in enumerate((row, a.idx_q, -1 if b is None else b.idx_q, a.idx_v,
                                   -1 if b is None else b.idx_v, c.coef[0], c.coef[1],
                                   1.0 / units[a.idx_v])):
            cols[k].append(value)
    return tuple(np.array(x, dtype=int) for x in cols[:5]) + tuple(
        np.array(x, dtype=float) for x in cols[5:])


#: Pinocchio's default "no limit" (the largest float) and anything beyond it.
_NO_LIMIT = 0.5 * np.finfo(float).max


def _position_limits(tree: pin.Model) -> tuple[np.ndarray, np.ndarray]:
    """Read-only lower and upper limits (nq,) of :func:`pkm_pin.solve.tree_limits`."""
    lo, up = np.full(tree.nq, -np.inf), np.full(tree.nq, np.inf)
    for j in range(1, tree.njoints):
        joint = tree.joints[j]
        if joint.nq == 1 and joint.nv == 1:
            i = joint.idx_q
            a, b = tree.lowerPositionLimit[i], tree.upperPositionLimit[i]
            if max(abs(a), abs(b)) < _NO_LIMIT and a < b:
                lo[i], up[i] = a, b
    lo.setflags(write=False)
    up.setflags(write=False)
    return lo, up


def _skew(p: np.ndarray) -> np.ndarray:
    """(k × 3 × 3) cross-product matrices ``[p]×`` of the rows of ``p`` (k × 3)."""
    S = np.zeros((len(p), 3, 3))
    S[:, 0, 1], S[:, 0, 2], S[:, 1, 2] = -p[:, 2], p[:, 1], -p[:, 0]
    S[:, 1, 0], S[:, 2, 0], S[:, 2, 1] = p[:, 2], -p[:, 1], p[:, 0]
    return S


def _support(tree: pin.Model, j: int) -> np.ndarray:
    """1.0 at the velocity coordinates of the joints supporting joint ``j``."""
    mask = np.zeros(tree.nv)
    for k in tree.supports[j][1:]:
        joint = tree.joints[k]
        mask[joint.idx_v:joint.idx_v + joint.nv] = 1.0
    return mask


def _kind_rows(closures: tuple, ends: np.ndarray, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the closures of ``kind`` and their rows (k × dim) in the residual."""
    index = [i for i, c in enumerate(closures) if c.kind == kind]
    rows = np.array([np.arange(ends[i], ends[i + 1]) for i in index], dtype=int)
    return np.array(index, dtype=int), rows.reshape(len(index), KINDS[kind])


class TreeKinematics:
    """The first-order kinematics of a :class:`ClosureModel` at one configuration, from
    one Pinocchio pass in a ``pin.Data`` of its own (:meth:`ClosureModel.kinematics`);
    the attributes after ``output_placement`` are read from that pass when first asked
    for.

    Attributes:
        q: The configuration (nq,).
        residual: :meth:`ClosureModel.closure_residual` (dimensionless).
        closure_jacobian: :meth:`ClosureModel.closure_jacobian` (n_rows × nv).
        output_jacobian: :meth:`ClosureModel.output_jacobian` (6 × nv, axis-first
            ``(ω; v_O)`` about the world origin).
        output_placement: World placement of the output frame.
        joint_twists: (nv × 6) row k: the axis-first twist ``(ω; v_O)`` [per unit rate]
            about the world origin of velocity coordinate k's joint motion (the child
            body relative to the parent body; a mimicking joint's motion is not in it).
        body_jacobians: Per joint j (index 0 the universe), 6 × nv: column k the world
            twist (axis-first, world origin) of joint j's child body per unit rate of
            velocity coordinate k (mimicking joints included).
        joint_placements: World placement of every joint (``data.oMi``, index 0 the
            universe).
        frame_placements: World placement of every frame (``data.oMf``).
    """

    def __init__(self, model: ClosureModel, q: np.ndarray, data: pin.Data):
        self.q = q
        self._tree, self._data, self._mimic = model.tree, data, model._plan.mimic
        (self.residual, self.closure_jacobian, self.output_jacobian,
         self.output_placement) = model._pass(q, data)

    @cached_property
    def joint_twists(self) -> np.ndarray:
        if not self._mimic:  # data.J: every coordinate's world twist
            return screws.from_pinocchio(_six_by(self._data.J, self._tree.nv)).T.copy()
        twists = np.zeros((self._tree.nv, 6))
        for j, J in enumerate(self.body_jacobians):
            joint = self._tree.joints[j]
            if j and joint.shortname() != "JointModelMimic":
                cols = slice(joint.idx_v, joint.idx_v + joint.nv)
                twists[cols] = J[:, cols].T
        return twists

    @cached_property
    def body_jacobians(self) -> tuple:
        tree, data = self._tree, self._data
        return (np.zeros((6, tree.nv)),) + tuple(
            screws.from_pinocchio(_six_by(pin.getJointJacobian(tree, data, j, pin.WORLD),
                                          tree.nv))
            for j in range(1, tree.njoints))

    @cached_property
    def joint_placements(self) -> tuple:
        return tuple(M.copy() for M in self._data.oMi)

    @cached_property
    def frame_placements(self) -> tuple:
        return tuple(M.copy() for M in self._data.oMf)


# ------------------------------------------------------------------ rank decisions
def _rank_and_null(H: np.ndarray, rtol: float) -> tuple[int, np.ndarray]:
    """Rank of the dimensionless ``H`` (singular values above ``rtol`` times the
    largest) and an orthonormal basis (columns) of its null space."""
    rank, _, _, Vt = screws.svd_rank(H, rtol)
    return rank, Vt[rank:].T


def _orthonormal_span(T: np.ndarray, oMo: pin.SE3, length: float, rtol: float) -> np.ndarray:
    """Rows spanning the twists ``T`` (rows, world origin): the dimension decided on
    twists homogenised about the output frame ``oMo`` in its axes; the rows returned
    orthonormal in the world-origin homogenised coordinates."""
    if T.shape[0] == 0:
        return np.zeros((0, 6))
    local = screws.homogenise(screws.transform(T, oMo.inverse()), length)
    _, sv, Vt = np.linalg.svd(local, full_matrices=False)
    rank = int(np.sum(sv > rtol * sv[0])) if sv[0] > 0 else 0
    if rank == 0:
        return np.zeros((0, 6))
    basis = screws.dehomogenise(Vt[:rank], length)
    world = screws.homogenise(screws.transform(basis, oMo).reshape(rank, 6), length)
    return screws.dehomogenise(np.linalg.qr(world.T)[0].T, length)


class NullSpace:
    """The motions the closures allow at one configuration (dimensionless columns).

    Attributes: ``N`` (nv × dof) orthonormal null-space basis of ``J_c U``; ``rank``;
    ``X`` (actuated × dof) actuated rates; ``Y_world`` (6 × dof) output twists about the
    world origin per unit of the null coordinates."""

    def __init__(self, model: ClosureModel, kin: TreeKinematics, rtol: float):
        U = model.velocity_units
        self.rank, self.N = _rank_and_null(kin.closure_jacobian * U, rtol)
        self.X = self.N[list(model.actuated_v)]
        self.Y_world = kin.output_jacobian @ (U[:, None] * self.N)
        self.units = U

    def idle(self, rtol: float) -> np.ndarray:
        """(nv × k) basis of the idle motions (dimensionless unit columns): the allowed
        motions that leave every actuated joint still, each moving few joints
        (:func:`sparse_basis` of the orthonormal one)."""
        rank_x, _, _, Vt = screws.svd_rank(self.X, rtol)
        return sparse_basis(self.N @ Vt[rank_x:].T)

    def rank_x(self, rtol: float) -> int:
        """Rank of the actuated rates over the allowed motions."""
        return screws.svd_rank(self.X, rtol)[0]


def sparse_basis(K: np.ndarray) -> np.ndarray:
    """A basis of the column space of ``K`` (n × k, independent columns) whose columns
    move few coordinates: unit columns, each the sparsest vector found with a given
    coordinate moving (an L1 minimisation: least ``Σ |x_i|`` over ``x = K c`` with
    ``x_p = 1``, a linear program per coordinate ``p``, coordinates whose rows of ``K``
    are parallel tried once), taken greedily, fewest moving coordinates first, while
    independent of those taken; entries below :data:`~pkm_pin.tolerances.SPARSE_ZERO_RTOL`
    of a column's largest are zero. Motions with disjoint sets of coordinates (the
    spins of separate rods) come out one by one. Ordered by first moving coordinate,
    its largest entry positive. Spans the column space of ``K`` (to the zeroed
    entries). When the reduced row echelon form (:func:`_echelon`) already has disjoint
    columns, it is the answer (no linear program)."""
    n, k = K.shape
    if k == 0:
        return np.zeros((n, 0))
    if k == 1:
        return _unit_columns(K)
    echelon = _echelon(K)
    moving = np.abs(echelon) > 0
    if moving.sum(axis=1).max() <= 1:  # disjoint motions: each one is already sparsest
        B = _unit_columns(echelon)
        first = [int(np.flatnonzero(B[:, j])[0]) for j in range(k)]
        return B[:, np.argsort(first, kind="stable")]
    from scipy.optimize import linprog

    scale = np.abs(K).max()
    rows = K / scale
    norms = np.linalg.norm(rows, axis=1)
    tried: list[np.ndarray] = []
    found = []
    A_ub = np.block([[rows, -np.eye(n)], [-rows, -np.eye(n)]])
    cost = np.r_[np.zeros(k), np.ones(n)]
    bounds = [(None, None)] * k + [(0, None)] * n
    for p in np.argsort(-norms, kind="stable"):
        if norms[p] <= SPARSE_ZERO_RTOL * norms.max():
            break
        u = rows[p] / norms[p]
        if any(abs(abs(u @ t) - 1.0) <= SPARSE_ZERO_RTOL for t in tried):
            continue
        tried.append(u)
        res = linprog(cost, A_ub=A_ub, b_ub=np.zeros(2 * n),
                      A_eq=np.r_[rows[p], np.zeros(n)][None], b_eq=[1.0], bounds=bounds,
                      method="highs")
        if res.status != 0:
            continue
        x = rows @ res.x[:k]
        x[np.abs(x) <= SPARSE_ZERO_RTOL * np.abs(x).max()] = 0.0
        found.append((int(np.count_nonzero(x)), float(np.abs(x).sum() / np.abs(x).max()),
                      int(p), x))
    found.sort(key=lambda f: f[:3])
    chosen: list[np.ndarray] = []
    for *_, x in found:
        trial = np.array(chosen + [x])
        if np.linalg.matrix_rank(trial, tol=SPARSE_ZERO_RTOL * np.abs(trial).max()) \
                == len(chosen) + 1:
            chosen.append(x)
        if len(chosen) == k:
            break
    if len(chosen) < k:  # not expected: complete with the orthogonal remainder of K
        Q = np.linalg.qr(np.array(chosen).T)[0] if chosen else np.zeros((n, 0))
        rest = K - Q @ (Q.T @ K)
        chosen += list(np.linalg.svd(rest, full_matrices=False)[0][:, :k - len(chosen)].T)
    B = _unit_columns(np.array(chosen).T)
    first = [int(np.flatnonzero(B[:, j])[0]) for j in range(k)]
    return B[:, np.argsort(first, kind="stable")]


def _echelon(K: np.ndarray) -> np.ndarray:
    """Columns spanning those of ``K`` (n × k): the reduced row echelon form of ``Kᵀ``
    by complete pivoting (each column 1 at its pivot coordinate, 0 at the others'),
    entries below :data:`~pkm_pin.tolerances.SPARSE_ZERO_RTOL` of a column's largest
    set to zero."""
    R = np.array(K.T, dtype=float)
    k = R.shape[0]
    for i in range(k):
        sub = np.abs(R[i:])
        r, c = np.unravel_index(np.argmax(sub), sub.shape)
        R[[i, i + r]] = R[[i + r, i]]
        R[i] /= R[i, c]
        for j in range(k):
            if j != i:
                R[j] -= R[j, c] * R[i]
                R[j, c] = 0.0
    for row in R:
        row[np.abs(row) <= SPARSE_ZERO_RTOL * np.abs(row).max()] = 0.0
    return R.T


def _unit_columns(B: np.ndarray) -> np.ndarray:
    """Columns of ``B`` scaled to unit norm, each one's largest entry positive."""
    B = np.array(B, dtype=float)
    for j in range(B.shape[1]):
        big = B[np.argmax(np.abs(B[:, j])), j]
        B[:, j] /= np.linalg.norm(B[:, j]) * np.sign(big)
    return B


def pose_rows(model: ClosureModel, kin: TreeKinematics) -> np.ndarray:
    """Rows (d × 6) selecting the components of the output pose error that the output
    can realise: an orthonormal basis of its twist system, homogenised, in its own axes
    and about its origin (the identity when d = 6)."""
    ns = NullSpace(model, kin, RANK_RTOL)
    M = kin.output_placement  # a point's error is in world axes (solve.pose_error_rows)
    M = pin.SE3(np.eye(3), M.translation) if model.output_point else M
    local = screws.homogenise(screws.transform(ns.Y_world.T, M.inverse()), model.length)
    rank, _, _, Vt = screws.svd_rank(local, RANK_RTOL)
    return np.eye(6) if rank == 6 else Vt[:rank]


# ------------------------------------------------------------------- validation
def velocity_units(tree: pin.Model, length: float) -> np.ndarray:
    """Unit of each velocity coordinate of ``tree``: ``length`` for a coordinate whose
    motion is a pure translation (:func:`translating_coordinates`), 1.0 otherwise."""
    return np.where(translating_coordinates(tree), float(length), 1.0)


def translating_coordinates(tree: pin.Model) -> np.ndarray:
    """Whether each velocity coordinate's motion (joint motion subspace, at the neutral
    configuration) is a pure translation (a prismatic joint, a free flyer's linear
    rates): counted in lengths, not radians; mimicking joints have no coordinate of
    their own."""
    data = tree.createData()
    pin.computeJointJacobians(tree, data, pin.neutral(tree))
    out = np.zeros(tree.nv, bool)
    for j in range(1, tree.njoints):
        joint = tree.joints[j]
        if joint.nv == 0 or joint.shortname() == "JointModelMimic":
            continue
        cols = slice(joint.idx_v, joint.idx_v + joint.nv)
        # (6, nv) even for nv = 1, which Pinocchio's binding returns as a (6,) vector
        J = _six_by(pin.getJointJacobian(tree, data, j, pin.LOCAL), tree.nv)
        S = screws.from_pinocchio(J[:, cols])
        size = np.linalg.norm(S, axis=0)
        out[cols] = np.linalg.norm(S[:3], axis=0) <= ZERO_SCREW_RTOL * size
    return out


def _frame_names(tree: pin.Model) -> list[str]:
    return [f.name for f in tree.frames]


def _frame_ids(tree: pin.Model, closures: tuple, output: str, name: str) -> dict:
    """Frame index of every frame the closures and the output name, or a
    :class:`TreeFrameNotFound`."""
    where = f"the tree of {name!r}" if name else "the tree"
    ids = {}
    needed = [output] + [f for c in closures for f in (c.frame_a, c.frame_b)]
    for frame in needed:
        if not isinstance(frame, str) or not tree.existFrame(frame):
            raise TreeFrameNotFound(str(frame), _frame_names(tree), where)
        ids[frame] = tree.getFrameId(frame)
    return ids


def _check_closures_join_two_bodies(tree: pin.Model, closures: tuple, name: str) -> None:
    """Raise :class:`InputError` for a closure whose two frames are on one body (the same
    frame, or two frames of one joint): their relative placement never changes, so the
    closure either constrains nothing or can never hold."""
    for c in closures:
        a, b = (tree.frames[tree.getFrameId(f)] for f in (c.frame_a, c.frame_b))
        if a.parentJoint == b.parentJoint:
            what = (f"frame {c.frame_a!r} to itself" if c.frame_a == c.frame_b else
                    f"{c.frame_a!r} and {c.frame_b!r}, two frames of one body "
                    f"(joint {tree.names[a.parentJoint]!r})")
            raise InputError(f"closure {c.name!r} of {name or 'the tree'} joins {what}: it "
                             "constrains nothing (or can never hold); remove it, or name "
                             "frames of two different bodies")


def _check_couplings(tree: pin.Model, closures: tuple, name: str) -> None:
    """Raise :class:`InputError` for a coupling whose joint ``a`` is the universe or a
    joint of more than one coordinate (or of one coordinate stored as two, an unbounded
    revolute), or whose joint ``b`` is such a joint."""
    for c in closures:
        if c.kind != COUPLING:
            continue
        for key, frame in (("frame_a", c.frame_a), ("frame_b", c.frame_b)):
            j = tree.frames[tree.getFrameId(frame)].parentJoint
            if j == 0 and key == "frame_b":
                continue
            joint = tree.joints[j]
            if j == 0 or joint.nq != 1 or joint.nv != 1:
                what = "the base" if j == 0 else (
                    f"joint {tree.names[j]!r} ({joint.shortname().removeprefix('JointModel')}"
                    f", {joint.nq} coordinates)")
                raise InputError(f"coupling {c.name!r} of {name or 'the tree'}: {key} "
                                 f"{frame!r} is on {what}; a coupling relates two joints "
                                 "of one coordinate each (revolute or prismatic)")


def duplicate_closures(closures) -> list[tuple[str, str]]:
    """Pairs ``(closure, earlier closure)`` that join the same two frames with the same
    kind and constraint frames (either way round): each one's rows repeat the other's
    and are counted as redundant."""
    seen, out = {}, []
    for c in closures:
        ends = ((c.frame_a, _key(c.placement_a)), (c.frame_b, _key(c.placement_b)))
        key = (c.kind, frozenset(ends)) if c.kind != COUPLING else (
            c.kind, ends, c.coef)
        if key in seen:
            out.append((c.name, seen[key]))
        else:
            seen[key] = c.name
    return out


def _key(M: pin.SE3) -> tuple:
    """A placement as a hashable key (rounded to 1e-12)."""
    return tuple(np.round(M.homogeneous[:3].ravel(), 12))


def _check_actuated(tree: pin.Model, actuated: tuple, name: str) -> None:
    """Raise :class:`TreeJointNotFound` for a name that is not a movable joint."""
    movable = [tree.names[j] for j in range(1, tree.njoints) if tree.joints[j].nv > 0]
    for a in actuated:
        if a not in movable:
            raise TreeJointNotFound(str(a), movable, f"the tree of {name!r}" if name else
                                    "the tree")
    if len(set(actuated)) != len(actuated):
        raise InputError(f"an actuated joint is listed twice in {actuated}")


def _springs(tree: pin.Model, springs, actuated: tuple) -> tuple[str, ...]:
    """``springs`` checked: names of one-coordinate joints of ``tree`` that no actuator
    drives."""
    out = tuple(str(n) for n in springs)
    for name in out:
        if not tree.existJointName(name):
            raise InputError(f"springs: no joint {_cut(name)} in the tree")
        if tree.joints[tree.getJointId(name)].nv != 1 or name in actuated:
            raise InputError(f"springs: joint {_cut(name)} must have one coordinate and "
                             "no actuator")
    return out


def _six_by(J, nv: int) -> np.ndarray:
    """A Jacobian read from Pinocchio as (6, nv): its bindings return a one-column matrix
    as a vector (a tree with one velocity coordinate)."""
    return np.reshape(J, (6, nv))


def default_length(tree: pin.Model, closures: tuple) -> float:
    """The default characteristic length [m] of a :class:`ClosureModel`: the offsets
    between consecutive joints of the tree plus the closures' frame offsets (1.0 when
    there are none). :class:`pkm_pin.linkage.Linkage` replaces it by the legs' length
    (:func:`pkm_pin.model.structure.legs_length`) where a platform structure is
    detected."""
    L = sum(np.linalg.norm(tree.jointPlacements[j].translation)
            for j in range(1, tree.njoints) if tree.parents[j] != 0)
    L += sum(np.linalg.norm(p.translation) for c in closures
             for p in (c.placement_a, c.placement_b))
    return float(L) if L > 0 else 1.0


def _length(tree: pin.Model, closures: tuple, length) -> float:
    """The characteristic length given, or the default of :class:`ClosureModel`."""
    if length is None:
        return default_length(tree, closures)
    if isinstance(length, bool) or not isinstance(length, (int, float)) \
            or not (np.isfinite(length) and length > 0):
        raise InputError(f"length must be a positive number [m], got {length!r}")
    return float(length)


# ------------------------------------------------------------- base–legs–platform
def from_mechanism(mech: Mechanism) -> ClosureModel:
    """The base–legs–platform mechanism ``mech`` as one tree plus closures.

    Every leg's model is appended under the universe at the leg's base placement, its
    joint and frame names prefixed ``"legname/"``; then the platform, a free-flyer joint
    :data:`PLATFORM_JOINT` carrying the body frame :data:`PLATFORM`. One weld per leg
    (named after the leg) between its tip frame and the platform frame at
    ``mech.anchors[i]``. Actuated: each leg's actuated joints as ``"leg/joint"``; output:
    :data:`PLATFORM`; length: ``mech.characteristic_length``. The configuration layout
    is the legs' configurations in order, then the platform's (:func:`configuration`).
    """
    tree = pin.Model()
    tree.name = mech.name
    for leg in mech.legs:
        tree = pin.appendModel(tree, _prefixed(leg.model, leg.name), 0, leg.base)
    joint = tree.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), PLATFORM_JOINT)
    tree.addBodyFrame(PLATFORM, joint, pin.SE3.Identity(), tree.addJointFrame(joint))
    closures = tuple(Closure("weld", f"{leg.name}/{leg.tip}", PLATFORM, pin.SE3.Identity(),
                             anchor, name=leg.name)
                     for leg, anchor in zip(mech.legs, mech.anchors))
    actuated = tuple(f"{leg.name}/{a}" for leg in mech.legs for a in leg.actuated)
    return ClosureModel(tree, closures, actuated, PLATFORM, mech.name,
                        length=mech.characteristic_length)


def _prefixed(model: pin.Model, prefix: str) -> pin.Model:
    """A copy of ``model`` with every joint and frame name prefixed ``"prefix/"``."""
    out = pin.Model(model)
    for j in range(1, out.njoints):
        out.names[j] = f"{prefix}/{out.names[j]}"
    for frame in out.frames:
        frame.name = f"{prefix}/{frame.name}"
    return out


def configuration(mech: Mechanism, assembly: Assembly) -> np.ndarray:
    """The configuration of :func:`from_mechanism`'s tree at ``assembly``: the legs'
    configurations, then the platform's free flyer ``(x, y, z, qx, qy, qz, qw)``
    (Pinocchio's layout) from ``assembly.pose``."""
    leg_q = list(assembly.leg_q)
    if len(leg_q) != len(mech.legs):
        raise InputError(f"the assembly has {len(leg_q)} leg configurations for "
                         f"{len(mech.legs)} legs of {mech.name!r}")
    qs = [leg.check_q(q, "assembly.leg_q") for leg, q in zip(mech.legs, leg_q)]
    return np.concatenate(qs + [pin.SE3ToXYZQUAT(assembly.pose)])

