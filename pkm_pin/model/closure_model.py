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
    ``C_b``'s z axis: the revolute axis is the z axis of both constraint frames.

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
method makes its own ``pin.Data`` and runs one Pinocchio pass: no hidden state, safe to
call from several threads.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .. import screws
from ..errors import InputError, TreeFrameNotFound, TreeJointNotFound
from ..tolerances import RANK_RTOL, ZERO_SCREW_RTOL

if TYPE_CHECKING:  # pragma: no cover
    from ..assembly import Assembly
    from ..mechanism import Mechanism

#: Rows constrained by each closure kind.
KINDS = {"weld": 6, "point": 3, "revolute": 5}

#: Name of the platform's body frame and free-flyer joint in :func:`from_mechanism`.
PLATFORM = "platform"
PLATFORM_JOINT = "platform_joint"


@dataclass(frozen=True)
class Closure:
    """One loop closure between two frames of the tree.

    Attributes:
        kind: ``"weld"`` (6 rows: same placement), ``"point"`` (3 rows: same point) or
            ``"revolute"`` (5 rows: same point and same z axis).
        frame_a: Frame of the tree carrying the first constraint frame.
        frame_b: Frame of the tree carrying the second constraint frame.
        placement_a: Constraint frame ``C_a`` in ``frame_a``.
        placement_b: Constraint frame ``C_b`` in ``frame_b``.
        name: Name of the closure (for messages).
    """

    kind: str
    frame_a: str
    frame_b: str
    placement_a: pin.SE3 = field(default_factory=pin.SE3.Identity)
    placement_b: pin.SE3 = field(default_factory=pin.SE3.Identity)
    name: str = ""

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InputError(f"closure {self.name!r}: unknown kind {self.kind!r}; "
                             f"the kinds are {sorted(KINDS)}")
        for key in ("frame_a", "frame_b"):
            if not isinstance(getattr(self, key), str):
                raise InputError(f"closure {self.name!r}: {key} must be a frame name (str)")
        for key in ("placement_a", "placement_b"):
            value = getattr(self, key)
            if not isinstance(value, pin.SE3) or not np.isfinite(value.homogeneous).all():
                raise InputError(f"closure {self.name!r}: {key} must be a finite pinocchio.SE3")

    @property
    def dim(self) -> int:
        """Number of rows the closure constrains (6, 3 or 5)."""
        return KINDS[self.kind]


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
    """

    tree: pin.Model = field(repr=False)
    closures: tuple[Closure, ...]
    actuated: tuple[str, ...]
    output: str
    name: str = ""
    length: float | None = None
    reference: np.ndarray | None = field(default=None, repr=False)
    output_point: bool = False
    _frame_ids: dict = field(init=False, repr=False)
    _units: np.ndarray = field(init=False, repr=False)

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
        set_(self, "_frame_ids", _frame_ids(tree, closures, self.output, self.name))
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

    def __setstate__(self, state: dict) -> None:
        """Unpickle: the description as pickled, its arrays read-only again."""
        self.__dict__.update(state)
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
        return sum(c.dim for c in self.closures)

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
        return tuple(self.tree.joints[self.tree.getJointId(a)].idx_v for a in self.actuated)

    def actuated_values(self, q) -> np.ndarray:
        """Values [rad or m] of the actuated joints at ``q``: the coordinate of a 1-DOF
        joint, the angle ``atan2(sin, cos)`` of a continuous (unbounded) revolute; an
        :class:`InputError` for an actuated joint with several degrees of freedom."""
        q = self.check_q(q)
        out = np.empty(len(self.actuated))
        for k, name in enumerate(self.actuated):
            joint = self.tree.joints[self.tree.getJointId(name)]
            if joint.nv != 1 or joint.nq not in (1, 2):
                raise InputError(f"actuated joint {name!r} has {joint.nv} degrees of freedom "
                                 "and no single actuated value")
            i = joint.idx_q
            out[k] = q[i] if joint.nq == 1 else np.arctan2(q[i + 1], q[i])
        return out

    def check_q(self, q) -> np.ndarray:
        """``q`` as a finite array of shape (nq,), or an :class:`InputError`."""
        return screws.as_vector(q, self.nq, f"the configuration of {self.name or 'the tree'}",
                                "the tree's configuration vector")

    # ---------------------------------------------------------------- residuals
    def closure_residual(self, q) -> np.ndarray:
        """Stacked residuals of every closure at ``q`` (dimensionless, module docstring)."""
        data = self._placements(self.check_q(q))
        rows = [_residual(c.kind, self._relative(data, c), self.length) for c in self.closures]
        return np.concatenate(rows) if rows else np.zeros(0)

    def closure_jacobian(self, q) -> np.ndarray:
        """``d closure_residual / dv`` (n_rows × nv) at ``q``, ``v`` the tree's velocity."""
        return self._closure_jacobian(self._jacobians(self.check_q(q)))

    def output_jacobian(self, q) -> np.ndarray:
        """6 × nv: column k is the axis-first twist ``(ω; v_O)`` of the output frame,
        about the world origin, for a unit rate of velocity coordinate k; with
        :attr:`output_point`, the translation ``(0; v_p)`` at the velocity of its origin."""
        return self._output_jacobian(self._jacobians(self.check_q(q)))

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
        data = self._jacobians(self.check_q(q))
        _, N = _rank_and_null(self._closure_jacobian(data) * self._units, rtol)
        T = (self._output_jacobian(data) @ (self._units[:, None] * N)).T
        return _orthonormal_span(T, data.oMf[self._frame_ids[self.output]], self.length, rtol)

    def kinematics(self, q) -> TreeKinematics:
        """Everything first-order at ``q`` from one Pinocchio pass (:class:`TreeKinematics`)."""
        q = self.check_q(q)
        data = self._jacobians(q)
        rows = [_residual(c.kind, self._relative(data, c), self.length) for c in self.closures]
        return TreeKinematics(
            q=q, residual=np.concatenate(rows) if rows else np.zeros(0),
            closure_jacobian=self._closure_jacobian(data),
            output_jacobian=self._output_jacobian(data),
            output_placement=data.oMf[self._frame_ids[self.output]].copy(),
            **_joint_twists(self.tree, data),
            joint_placements=tuple(M.copy() for M in data.oMi),
            frame_placements=tuple(M.copy() for M in data.oMf))

    def closure_slices(self) -> tuple[slice, ...]:
        """Rows of each closure in :meth:`closure_residual` (closure order)."""
        ends = np.cumsum([0] + [c.dim for c in self.closures])
        return tuple(slice(int(a), int(b)) for a, b in zip(ends[:-1], ends[1:]))

    # ---------------------------------------------------------- Pinocchio passes
    def _placements(self, q: np.ndarray) -> pin.Data:
        """A fresh ``Data`` with every frame placement at ``q``."""
        data = self.tree.createData()
        pin.framesForwardKinematics(self.tree, data, q)
        return data

    def _jacobians(self, q: np.ndarray) -> pin.Data:
        """A fresh ``Data`` after one pass at ``q``: joint Jacobians, frame placements."""
        data = self.tree.createData()
        pin.computeJointJacobians(self.tree, data, q)
        pin.updateFramePlacements(self.tree, data)
        return data

    def _relative(self, data: pin.Data, c: Closure) -> pin.SE3:
        """``M = C_a⁻¹ C_b`` of closure ``c`` from placements in ``data``."""
        ids = self._frame_ids
        oMa = data.oMf[ids[c.frame_a]] * c.placement_a
        oMb = data.oMf[ids[c.frame_b]] * c.placement_b
        return oMa.actInv(oMb)

    def _local_twists(self, data: pin.Data, frame: str, placement: pin.SE3) -> np.ndarray:
        """6 × nv axis-first twists of the constraint frame ``frame * placement``, in
        its own axes and about its own origin (from the LOCAL frame Jacobian)."""
        J = pin.getFrameJacobian(self.tree, data, self._frame_ids[frame], pin.LOCAL)
        return screws.adjoint(placement.inverse()) @ screws.from_pinocchio(J)

    def _closure_jacobian(self, data: pin.Data) -> np.ndarray:
        """The closure Jacobian from a ``data`` filled by :meth:`_jacobians`."""
        rows = []
        for c in self.closures:
            M = self._relative(data, c)
            Ta = self._local_twists(data, c.frame_a, c.placement_a)
            Tb = self._local_twists(data, c.frame_b, c.placement_b)
            nu = Tb - screws.adjoint(M.inverse()) @ Ta  # body twist of C_b w.r.t. C_a, in C_b
            rows.append(_residual_rates(c.kind, M, nu, self.length))
        return np.vstack(rows) if rows else np.zeros((0, self.nv))

    def _output_jacobian(self, data: pin.Data) -> np.ndarray:
        """The output Jacobian from a ``data`` filled by :meth:`_jacobians`."""
        fid = self._frame_ids[self.output]
        if self.output_point:  # the origin's velocity: LOCAL_WORLD_ALIGNED's linear rows
            J = pin.getFrameJacobian(self.tree, data, fid, pin.LOCAL_WORLD_ALIGNED)
            return np.vstack([np.zeros((3, self.nv)), J[:3]])
        return screws.from_pinocchio(pin.getFrameJacobian(self.tree, data, fid, pin.WORLD))


@dataclass(frozen=True, eq=False)
class TreeKinematics:
    """The first-order kinematics of a :class:`ClosureModel` at one configuration, from
    one Pinocchio pass (:meth:`ClosureModel.kinematics`).

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

    q: np.ndarray
    residual: np.ndarray
    closure_jacobian: np.ndarray
    output_jacobian: np.ndarray
    output_placement: pin.SE3
    joint_twists: np.ndarray
    body_jacobians: tuple
    joint_placements: tuple
    frame_placements: tuple


def _joint_twists(tree: pin.Model, data: pin.Data) -> dict:
    """``joint_twists`` and ``body_jacobians`` of :class:`TreeKinematics` from a ``data``
    filled by :meth:`ClosureModel._jacobians` (``data.J`` itself is not used: mimicking
    joints share their columns)."""
    bodies = [np.zeros((6, tree.nv))]
    twists = np.zeros((tree.nv, 6))
    for j in range(1, tree.njoints):
        J = screws.from_pinocchio(pin.getJointJacobian(tree, data, j, pin.WORLD))
        bodies.append(J)
        joint = tree.joints[j]
        if joint.shortname() != "JointModelMimic":
            cols = slice(joint.idx_v, joint.idx_v + joint.nv)
            twists[cols] = J[:, cols].T
    return {"joint_twists": twists, "body_jacobians": tuple(bodies)}


# ------------------------------------------------------------------- residuals
def _residual(kind: str, M: pin.SE3, length: float) -> np.ndarray:
    """Rows of one closure's residual from its relative placement ``M = C_a⁻¹ C_b``."""
    point = M.translation / length
    if kind == "point":
        return point
    if kind == "revolute":
        return np.r_[point, M.rotation[:2, 2]]
    r = screws.log(M)  # (θ; ρ) axis-first
    r[3:] /= length
    return r


def _residual_rates(kind: str, M: pin.SE3, nu: np.ndarray, length: float) -> np.ndarray:
    """``d residual / dv`` of one closure: ``nu`` (6 × nv, axis-first) is the body twist
    of ``C_b`` relative to ``C_a``, in ``C_b``, so that ``dM = M [nu]``."""
    point = M.rotation @ nu[3:] / length  # d(p_M) = R_M v
    if kind == "point":
        return point
    if kind == "revolute":
        # d(R_M e_z) = R_M (ω × e_z) = -R_M [e_z]× ω
        axis = -(M.rotation @ pin.skew(np.array([0.0, 0.0, 1.0])))[:2] @ nu[:3]
        return np.vstack([point, axis])
    # d log6(M) = Jlog6(M) nu (Pinocchio order on both sides)
    rates = screws.from_pinocchio(pin.Jlog6(M) @ screws.to_pinocchio(nu))
    rates[3:] /= length
    return rates


# ------------------------------------------------------------------ rank decisions
def _rank_and_null(H: np.ndarray, rtol: float) -> tuple[int, np.ndarray]:
    """Rank of the dimensionless ``H`` (singular values above ``rtol`` times the
    largest) and an orthonormal basis (columns) of its null space."""
    n = H.shape[1]
    if H.shape[0] == 0:
        return 0, np.eye(n)
    _, sv, Vt = np.linalg.svd(H, full_matrices=True)
    rank = int(np.sum(sv > rtol * sv[0])) if sv.size and sv[0] > 0 else 0
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


# ------------------------------------------------------------------- validation
def velocity_units(tree: pin.Model, length: float) -> np.ndarray:
    """Unit of each velocity coordinate of ``tree``: ``length`` for a coordinate whose
    motion (joint motion subspace, at the neutral configuration) is a pure translation,
    1.0 otherwise; mimicking joints have no coordinate of their own."""
    data = tree.createData()
    pin.computeJointJacobians(tree, data, pin.neutral(tree))
    units = np.ones(tree.nv)
    for j in range(1, tree.njoints):
        joint = tree.joints[j]
        if joint.nv == 0 or joint.shortname() == "JointModelMimic":
            continue
        cols = slice(joint.idx_v, joint.idx_v + joint.nv)
        S = screws.from_pinocchio(pin.getJointJacobian(tree, data, j, pin.LOCAL)[:, cols])
        size = np.linalg.norm(S, axis=0)
        units[cols] = np.where(np.linalg.norm(S[:3], axis=0) <= ZERO_SCREW_RTOL * size,
                               length, 1.0)
    return units


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


def _check_actuated(tree: pin.Model, actuated: tuple, name: str) -> None:
    """Raise :class:`TreeJointNotFound` for a name that is not a movable joint."""
    movable = [tree.names[j] for j in range(1, tree.njoints) if tree.joints[j].nv > 0]
    for a in actuated:
        if a not in movable:
            raise TreeJointNotFound(str(a), movable, f"the tree of {name!r}" if name else
                                    "the tree")
    if len(set(actuated)) != len(actuated):
        raise InputError(f"an actuated joint is listed twice in {actuated}")


def _length(tree: pin.Model, closures: tuple, length) -> float:
    """The characteristic length given, or the default of :class:`ClosureModel`."""
    if length is None:
        L = sum(np.linalg.norm(tree.jointPlacements[j].translation)
                for j in range(1, tree.njoints) if tree.parents[j] != 0)
        L += sum(np.linalg.norm(p.translation) for c in closures
                 for p in (c.placement_a, c.placement_b))
        return float(L) if L > 0 else 1.0
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
    ``mech.anchors[i]``. Actuated: ``mech.actuated_names`` (``"leg/joint"``); output:
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
    return ClosureModel(tree, closures, tuple(mech.actuated_names), PLATFORM, mech.name,
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

