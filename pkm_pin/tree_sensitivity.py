"""Sensitivity of a closure model's output to geometric errors: any linkage, any file.

:mod:`pkm_pin.sensitivity` reads a base–legs–platform machine leg by leg (seed 000's
wrenches); this module reads any :class:`~pkm_pin.model.ClosureModel` (a Cassie-like leg,
an ankle, a multi-loop linkage) through its closure Jacobian, so that every mechanism
answers the same question: how far does the output move, actuated joints held, per unit
error of a geometric parameter. Its result is the same
:class:`~pkm_pin.sensitivity.Sensitivity`.

Parameters, named after the tree (the file's own names):

* ``"<joint>/origin.x"`` … ``.z``, ``.roll``, ``.pitch``, ``.yaw`` — the placement of a
  movable joint in the frame of its parent joint (Pinocchio's ``jointPlacements``: a URDF
  joint's ``<origin>``, with fixed joints between it and its parent joint composed in)
  [m, rad]; a free-flyer joint has none (its placement is its coordinates);
* ``"<joint>/axis.rx"``, ``.ry``, ``.rz`` — a small rotation [rad] of a revolute or
  prismatic joint's axis about the joint frame's x, y, z axes (the component about an
  axis parallel to the joint axis, which changes nothing, is left out);
* ``"<closure>/a.x"`` … ``.yaw`` and ``"<closure>/b.x"`` … — the placement of a closure's
  constraint frame on its body (the closure frame ``frame_a`` composed with
  ``placement_a``, in the frame of its parent joint); a point closure has ``x``, ``y``,
  ``z`` only (its orientation constrains nothing).

rpy components are URDF roll, pitch, yaw (``R = Rz(yaw) Ry(pitch) Rx(roll)``); an error
adds to the component (:func:`perturb` applies finite errors).

Method (the closure equations with the error as one more joint, as in
:mod:`pkm_pin.sensitivity`). At fixed joint values an error ``ε`` of a parameter moves
the subtree below its joint, or one closure frame, by the world twist ``ε ξ`` (the
*virtual twist*: a change of an origin component is the couple, or the rotation about
the axis through the frame origin, of :func:`pkm_pin.sensitivity` ``_placement_twist``
mapped by the parent joint's placement; an axis rotation ``e_k`` is
``Ad(W₀)(e_k; 0) − Ad(W_q)(e_k; 0)``, ``W₀`` and ``W_q`` the joint frame before and after
the joint's own motion). Its closure rows ``G ε`` (:meth:`ClosureModel.closure_rates`)
must be absorbed by the passive joints, actuated joints held: ``J_p δq_p = −G ε`` (least
squares in velocity units, minimum norm along idle motions), and the output moves by
``δo = J_o,p δq_p + ξ_o ε`` (``ξ_o``: the virtual twist where the error moves the output
frame itself). The output is undetermined (a type II singularity) when a passive motion
the closures allow moves it: :class:`~pkm_pin.errors.SingularityError`. An
overconstrained linkage absorbs only some errors: ``compatibility`` is the residual of
``J_p δq_p = −G`` relative to the size of the virtual twist (homogenised about the
output origin; per unit of the characteristic length for a length error).

Conventions: twists axis-first ``(ω; v_O)`` about the world origin, per unit error;
closure rows are dimensionless (:meth:`ClosureModel.closure_residual`); passive rates in
velocity units (:attr:`ClosureModel.velocity_units`) for every rank decision, so that
the result does not depend on the unit of length nor on where the mechanism stands.
"""

from __future__ import annotations

import fnmatch
from dataclasses import replace

import numpy as np
import pinocchio as pin

from . import screws
from .errors import InputError, SingularityError
from .model.closure_model import ClosureModel
from .sensitivity import (
    AXIS_COMPONENTS,
    PLACEMENT_COMPONENTS,
    Sensitivity,
    _axis_components,
    _placement_twist,
    _placement_with,
)
from .tolerances import RANK_RTOL, SENSITIVITY_SINGULAR_TOL

#: Size of a homogenised virtual twist below which a parameter moves nothing (its
#: compatibility is read against this floor, not against round-off).
_SMALLEST_ERROR_EFFECT = 1e-6
#: Joint types whose placement is not a parameter (its coordinates already place it).
_NO_ORIGIN = ("JointModelFreeFlyer",)
#: 1-DOF joint types with an axis, and whether it is a rotation axis.
_AXES = {"JointModelRX": (0, True), "JointModelRY": (1, True), "JointModelRZ": (2, True),
         "JointModelRUBX": (0, True), "JointModelRUBY": (1, True), "JointModelRUBZ": (2, True),
         "JointModelPX": (0, False), "JointModelPY": (1, False), "JointModelPZ": (2, False),
         "JointModelRevoluteUnaligned": (None, True),
         "JointModelRevoluteUnboundedUnaligned": (None, True),
         "JointModelPrismaticUnaligned": (None, False)}


def _closure_names(model: ClosureModel) -> list[str]:
    """Each closure's name in parameter names: its own, ``closure K`` when it has none,
    ``NAME#K`` when another closure before it has the same."""
    out = []
    for k, c in enumerate(model.closures):
        name = c.name or f"closure {k}"
        out.append(f"{name}#{k}" if name in out else name)
    return out


def _joint_axis(joint) -> np.ndarray | None:
    """The unit axis of a 1-DOF revolute or prismatic joint in its frame, else ``None``."""
    kind = joint.shortname()
    if kind not in _AXES:
        return None
    k, _ = _AXES[kind]
    if k is not None:
        return np.eye(3)[k]
    axis = np.asarray(joint.extract().axis, dtype=float).reshape(3)
    return axis / np.linalg.norm(axis)


def parameter_names(model: ClosureModel) -> list[str]:
    """Every parameter of ``model`` (module docstring), in canonical order: the joints
    root to leaves (origin, then axis), then the closures (end a, end b)."""
    tree = model.tree
    names = []
    for j in range(1, tree.njoints):
        joint, name = tree.joints[j], tree.names[j]
        if joint.shortname() not in _NO_ORIGIN:
            names += [f"{name}/origin.{c}" for c in PLACEMENT_COMPONENTS]
        axis = _joint_axis(joint)
        if axis is not None:
            names += [f"{name}/axis.{c}" for c in _axis_components(axis)]
    for c, name in zip(model.closures, _closure_names(model)):
        if c.kind == "coupling":
            continue
        comps = PLACEMENT_COMPONENTS[:3] if c.kind == "point" else PLACEMENT_COMPONENTS
        names += [f"{name}/{end}.{x}" for end in "ab" for x in comps]
    return names


def select_parameters(model: ClosureModel, parameters=None) -> list[str]:
    """The parameters named by ``parameters`` (all by default): names, a joint's or a
    closure's name (all of its components), or globs (``"*/origin.z"``), in canonical
    order; an unknown name is an :class:`InputError` naming close ones."""
    every = parameter_names(model)
    if parameters is None:
        return every
    if isinstance(parameters, str):
        parameters = [parameters]
    chosen = set()
    for p in parameters:
        if not isinstance(p, str) or not p:
            raise InputError(f"a parameter is a non-empty name, got {p!r}")
        hit = [n for n in every if n == p or n.startswith(p + "/") or fnmatch.fnmatchcase(n, p)]
        if not hit:
            near = [n for n in every if p.split("/")[0] in n][:6] or every[:6]
            raise InputError(f"{p!r} names no geometric parameter of {model.name or 'the model'}"
                             f" (parameters are <joint>/origin.x…yaw, <joint>/axis.rx…rz, "
                             f"<closure>/a.x…, <closure>/b.x…; e.g. {', '.join(near)})")
        chosen.update(hit)
    return [n for n in every if n in chosen]


def _split(model: ClosureModel, name: str) -> tuple:
    """``(kind, index, comp)``: kind ``"origin"``/``"axis"`` with a joint index, or
    ``"a"``/``"b"`` with a closure index."""
    head, _, tail = name.rpartition("/")
    what, _, comp = tail.partition(".")
    if what in ("origin", "axis"):
        return what, model.tree.getJointId(head), comp
    return what, _closure_names(model).index(head), comp


def _closure_frame(model: ClosureModel, k: int, end: str) -> tuple[int, pin.SE3]:
    """``(parent joint, constraint frame in the parent joint's frame)`` of one end."""
    c = model.closures[k]
    frame = model.tree.frames[model.frame_id(c.frame_a if end == "a" else c.frame_b)]
    return frame.parentJoint, frame.placement * (c.placement_a if end == "a" else c.placement_b)


def _rpy(M: pin.SE3) -> np.ndarray:
    return pin.rpy.matrixToRpy(M.rotation)


def virtual_twists(model: ClosureModel, kin, names: list[str]) -> np.ndarray:
    """6 × n world virtual twists (axis-first, about the origin) of the parameters
    ``names`` at the configuration of ``kin`` (:meth:`ClosureModel.kinematics`)."""
    tree, oMi = model.tree, kin.joint_placements
    out = np.zeros((6, len(names)))
    for k, name in enumerate(names):
        kind, i, comp = _split(model, name)
        if kind == "origin":
            M = tree.jointPlacements[i]
            out[:, k] = screws.transform(_placement_twist(M.translation, _rpy(M), comp),
                                         oMi[tree.parents[i]])
        elif kind == "axis":
            e = np.zeros(6)
            e[AXIS_COMPONENTS.index(comp)] = 1.0
            W0 = oMi[tree.parents[i]] * tree.jointPlacements[i]
            out[:, k] = screws.transform(e, W0) - screws.transform(e, oMi[i])
        else:
            parent, X = _closure_frame(model, i, kind)
            out[:, k] = screws.transform(_placement_twist(X.translation, _rpy(X), comp),
                                         oMi[parent])
    return out


def _moves(model: ClosureModel, names: list[str]) -> np.ndarray:
    """(2C + 1) × n: whether each parameter moves each closure frame (``frame_a`` of every
    closure, then ``frame_b``) and the output frame."""
    tree, C = model.tree, len(model.closures)
    frames = [model.frame_id(c.frame_a) for c in model.closures] \
        + [model.frame_id(c.frame_b) for c in model.closures] + [model.frame_id(model.output)]
    parents = [tree.frames[f].parentJoint for f in frames]
    out = np.zeros((2 * C + 1, len(names)), dtype=bool)
    for k, name in enumerate(names):
        kind, i, _ = _split(model, name)
        if kind in ("origin", "axis"):
            out[:, k] = [i in tree.supports[p] for p in parents]
        else:
            out[i if kind == "a" else C + i, k] = True
    return out


def sensitivity(model: ClosureModel, q, parameters=None, *, assembly=None,
                rtol: float = RANK_RTOL) -> Sensitivity:
    """Output error per unit error of each parameter at the assembled configuration ``q``
    of ``model``'s tree, actuated joints held (module docstring).

    Args:
        model: The closure model.
        q: An assembled configuration (its closures closed).
        parameters: Names, a joint's or closure's name, or globs (:func:`select_parameters`).
        assembly: Kept in the result (:attr:`Sensitivity.assembly`; default: ``None``).
        rtol: Relative tolerance of the rank decision on the passive closure Jacobian.

    Raises:
        InputError: unknown parameter names.
        SingularityError: a passive motion the closures allow moves the output (type II).
    """
    names = select_parameters(model, parameters)
    kin = model.kinematics(q)
    tree, C, L = model.tree, len(model.closures), model.length
    xi = virtual_twists(model, kin, names)
    moves = _moves(model, names)
    G = model.closure_rates(kin, moves[:2 * C, None, :] * xi[None])
    units = model.velocity_units
    passive = np.setdiff1d(np.arange(tree.nv), model.actuated_v)
    Jp = kin.closure_jacobian[:, passive] * units[passive]
    p = kin.output_placement.translation
    Jo = _output_jacobian(model, kin)[:, passive] * units[passive]
    U, sv, Vt = np.linalg.svd(Jp, full_matrices=True) if Jp.size else (
        np.zeros((Jp.shape[0],) * 2), np.zeros(0), np.eye(passive.size))
    rank = int(np.sum(sv > rtol * sv[0])) if sv.size and sv[0] > 0 else 0
    _check_determined(model, Jo, Vt[rank:], p, L)
    inv = Vt[:rank].T / sv[:rank]
    dq = -(inv @ (U[:, :rank].T @ G))                 # passive rates in velocity units
    compat = _compatibility(Jp @ dq + G, xi, names, p, L)
    X = Jo @ dq + moves[-1] * xi
    return Sensitivity(names, X, xi, compat, assembly)


def _compatibility(residual: np.ndarray, xi: np.ndarray, names: list[str], p: np.ndarray,
                   L: float) -> np.ndarray:
    """Each column's closure residual relative to the size of its virtual twist
    (homogenised about the output origin ``p`` with ``L``, per unit of ``L`` for a length
    error: the same in any unit and wherever the mechanism stands), the size floored at
    :data:`_SMALLEST_ERROR_EFFECT` (a joint axis tilted at zero joint value moves nothing:
    its round-off is no incompatibility)."""
    per_l = np.array([L if n.endswith((".x", ".y", ".z")) else 1.0 for n in names])
    X = screws.about(xi.T, p)
    size = np.linalg.norm(np.c_[X[:, :3], X[:, 3:] / L], axis=1) * per_l
    return np.linalg.norm(residual, axis=0) * per_l / np.maximum(size, _SMALLEST_ERROR_EFFECT)


def _output_jacobian(model: ClosureModel, kin) -> np.ndarray:
    """6 × nv world Jacobian (axis-first, about the origin) of the output frame as a body
    (a point output's rotation included: the body carrying the point)."""
    tree = model.tree
    j = tree.frames[model.frame_id(model.output)].parentJoint
    return kin.body_jacobians[j] if tree.nv else np.zeros((6, 0))


def _check_determined(model: ClosureModel, Jo: np.ndarray, N: np.ndarray, p: np.ndarray,
                      L: float) -> None:
    """:class:`SingularityError` when a passive motion in the null space ``N`` of the
    passive closure Jacobian moves the output (its point's velocity for a point output;
    homogenised with ``L`` about the output origin ``p``)."""
    if not N.size:
        return
    T = screws.about((Jo @ N.T).T, p)                     # about the output origin
    if model.output_point:
        T = T[:, 3:] / L
    else:
        T = np.c_[T[:, :3], T[:, 3:] / L]
    worst = float(np.linalg.norm(T, 2)) if T.size else 0.0
    if worst > SENSITIVITY_SINGULAR_TOL ** 0.5:
        raise SingularityError(
            f"the output of {model.name or 'the linkage'} moves with the actuated joints "
            f"held (a passive motion the closures allow moves it by {worst:.3g}): its error "
            "is undetermined here: a type II singularity, or an under-actuated mechanism "
            "(springs or passive joints without a motor, at every pose: `pkm-pin analyze` "
            "says which); choose an output they do not move, or actuate or lock them",
            "sensitivity", worst)


def perturb(model: ClosureModel, errors) -> ClosureModel:
    """A copy of ``model`` with finite parameter errors (``{name: error}``, the
    parameters of :func:`parameter_names`) added to its geometry."""
    tree = pin.Model(model.tree)
    closures = list(model.closures)
    errors = dict(errors)
    select_parameters(model, list(errors))  # every name known, or the error naming it
    for name, value in errors.items():
        value = float(value)
        if not np.isfinite(value):
            raise InputError(f"the error of {name!r} must be finite, got {value!r}")
        kind, i, comp = _split(model, name)
        if kind == "origin":
            tree.jointPlacements[i] = _placement_with(tree.jointPlacements[i], comp, value)
        elif kind == "axis":
            _tilt_axis(tree, i, comp, value)
        else:
            closures[i] = _moved_closure(model, i, kind, comp, value)
    return replace(model, tree=tree, closures=tuple(closures))


def _tilt_axis(tree: pin.Model, j: int, comp: str, angle: float) -> None:
    """Turn joint ``j``'s axis by ``angle`` about its frame's ``comp`` axis, in place: the
    joint frame turns, everything carried by the joint turns back (at zero joint value
    nothing moves)."""
    e = np.zeros(3)
    e[AXIS_COMPONENTS.index(comp)] = angle
    R = pin.SE3(pin.exp3(e), np.zeros(3))
    tree.jointPlacements[j] = tree.jointPlacements[j] * R
    for c in range(1, tree.njoints):
        if tree.parents[c] == j:
            tree.jointPlacements[c] = R.inverse() * tree.jointPlacements[c]
    for f in range(len(tree.frames)):
        if tree.frames[f].parentJoint == j:
            frame = tree.frames[f]
            frame.placement = R.inverse() * frame.placement
            tree.frames[f] = frame
    tree.inertias[j] = tree.inertias[j].se3Action(R.inverse())


def _moved_closure(model: ClosureModel, k: int, end: str, comp: str, value: float):
    """Closure ``k`` with the constraint frame of one end moved by ``value``."""
    c = model.closures[k]
    frame = model.tree.frames[model.frame_id(c.frame_a if end == "a" else c.frame_b)]
    _, X = _closure_frame(model, k, end)
    moved = frame.placement.inverse() * _placement_with(X, comp, value)
    return replace(c, **{f"placement_{end}": moved})
