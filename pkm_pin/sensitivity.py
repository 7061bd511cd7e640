"""Sensitivity of the platform pose to geometric errors of any URDF parameter.

A *parameter* is one component of the geometry of a leg, named
``"<leg>/<what>"``:

* ``"<leg>/<joint>/origin.x"`` … ``.z``, ``.roll``, ``.pitch``, ``.yaw`` — the URDF
  ``<origin>`` of every joint on the chain from the leg's root to its tip (fixed joints,
  e.g. the tip's, included; mimic joints included) [m, rad];
* ``"<leg>/<joint>/axis.rx"``, ``.ry``, ``.rz`` — a small rotation [rad] of the joint's
  ``<axis>`` about the x, y, z axes of the joint frame (the component about an axis
  parallel to the joint axis, which changes nothing, is left out);
* ``"<leg>/base.x"`` … ``.yaw`` — the leg's base placement in the world;
* ``"<leg>/anchor.x"`` … ``.yaw`` — the placement of the leg's tip frame in the platform.

rpy components are the URDF roll, pitch, yaw (``R = Rz(yaw) Ry(pitch) Rx(roll)``); a
parameter error adds to that component (:func:`perturb` applies finite errors by editing
the URDF text, the base or the anchor).

Method (seeds 000, 003: the velocity equations of the legs, with the parameter error as
one more joint). At fixed joint values, an error ``ε`` of a parameter of leg ``i``
displaces the leg's tip by the world twist ``ε ξ`` (the *virtual joint twist*, computed
**analytically** from the joint frames: a translation of an origin is the couple along
the parent frame's axis; a change of an rpy component is the rotation about the
corresponding axis through the frame origin; an axis rotation by ``e_k`` is
``Ad(W_0) (e_k; 0) − Ad(W_q) (e_k; 0)``, ``W_0``, ``W_q`` the joint frame before and after
the joint's own motion; an anchor error is minus the platform twist it would need).
Closure to first order: ``J_i δq_i + ξ = δt`` with ``δq_a = 0``. Every wrench ``ζ``
reciprocal to the passive joint twists of leg ``i`` (its actuation and constraint
wrenches) removes ``δq_i``: ``ζ ∘ δt = ζ ∘ ξ`` for leg ``i``, ``ζ ∘ δt = 0`` for the other
legs. The stacked system has rank 6 away from singularities and is solved by least
squares (homogenised: moments divided by the characteristic length ``L``, rows
normalised).

Overconstrained mechanisms: the system has more rows than 6 and is consistent only for
errors the mechanism can absorb without deformation. For the others (e.g. tilting one
revolute of an Orthoglide leg out of parallel with its mate) the rigid mechanism no
longer assembles; :attr:`Sensitivity.compatibility` gives the relative residual of the
stacked system and :attr:`Sensitivity.incompatible` names them.

Conventions: twists axis-first ``(ω; v_O)`` about the world origin, per unit parameter
error ([rad/m] or [m/m] for a length parameter, [rad/rad], [m/rad] for an angle).
"""

from __future__ import annotations

import fnmatch
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np
import pinocchio as pin
from lxml import etree

from . import screws
from .errors import FrameNotFound, InputError, SingularityError
from .leg import Leg
from .tolerances import COMPATIBILITY_TOL, SENSITIVITY_SINGULAR_TOL

#: Components of a placement (URDF origin, base, anchor).
PLACEMENT_COMPONENTS = ("x", "y", "z", "roll", "pitch", "yaw")
#: Components of a joint axis: small rotations about the joint frame's axes.
AXIS_COMPONENTS = ("rx", "ry", "rz")
# COMPATIBILITY_TOL (relative residual of the stacked system above which a parameter
# error is incompatible with the rigid mechanism) is pkm_pin.tolerances.COMPATIBILITY_TOL.
#: Smallest relative singular value of the stacked wrench system (homogenised, rows
#: normalised) below which the pose error is undetermined (type II singularity); alias
#: of :data:`pkm_pin.tolerances.SENSITIVITY_SINGULAR_TOL`.
SINGULAR_TOL = SENSITIVITY_SINGULAR_TOL


# ================================================================== URDF structure
@dataclass(frozen=True)
class UrdfJoint:
    """One joint of a leg's URDF on the path from the root to the tip."""

    name: str
    type: str
    parent: str
    child: str
    xyz: tuple
    rpy: tuple
    axis: tuple | None


@lru_cache(maxsize=64)
def _chain_of_xml(xml: str, tip: str) -> tuple[UrdfJoint, ...]:
    root = etree.fromstring(xml.encode())
    joints, by_child = {}, {}
    for j in root.findall("joint"):
        name, kind = j.get("name"), j.get("type")
        parent, child = j.find("parent").get("link"), j.find("child").get("link")
        o = j.find("origin")
        xyz = tuple(map(float, (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()))
        rpy = tuple(map(float, (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()))
        a = j.find("axis")
        axis = None
        if kind in ("revolute", "continuous", "prismatic"):
            axis = tuple(map(float, (a.get("xyz") if a is not None else "1 0 0").split()))
        joints[name] = UrdfJoint(name, kind, parent, child, xyz, rpy, axis)
        by_child[child] = name
    link = tip if tip not in joints else joints[tip].child
    path = []
    while link in by_child:
        path.append(joints[by_child[link]])
        link = path[-1].parent
    return tuple(reversed(path))


def urdf_chain(leg) -> tuple[UrdfJoint, ...]:
    """URDF joints of ``leg`` from its root to its tip frame (fixed joints included)."""
    if not getattr(leg, "xml", ""):
        raise InputError(f"leg {leg.name!r} has no URDF text: its parameters are unknown")
    return _chain_of_xml(leg.xml, leg.tip)


# ================================================================ parameter names
def _axis_components(axis) -> list[str]:
    s = np.asarray(axis, dtype=float)
    s = s / np.linalg.norm(s)
    return [c for k, c in enumerate(AXIS_COMPONENTS) if abs(s[k]) < 1.0 - 1e-12]


def leg_parameter_names(leg) -> list[str]:
    """Every parameter of one leg, in canonical order (base, joints root→tip, anchor)."""
    names = [f"{leg.name}/base.{c}" for c in PLACEMENT_COMPONENTS]
    for j in urdf_chain(leg):
        names += [f"{leg.name}/{j.name}/origin.{c}" for c in PLACEMENT_COMPONENTS]
        if j.axis is not None:
            names += [f"{leg.name}/{j.name}/axis.{c}" for c in _axis_components(j.axis)]
    names += [f"{leg.name}/anchor.{c}" for c in PLACEMENT_COMPONENTS]
    return names


def parameter_names(mech) -> list[str]:
    """Every parameter of the mechanism (legs in order)."""
    return [n for leg in mech.legs for n in leg_parameter_names(leg)]


def select_parameters(mech, parameters=None) -> list[str]:
    """Names selected by ``parameters``: None (all), a name, a prefix ending at a ``/``
    or ``.`` boundary (``"legx"``, ``"legx/R1"``, ``"legx/R1/axis"``), a glob
    (``"*/Pa2/origin.x"``), or a sequence of those; pattern order, no repeats.

    Raises:
        InputError: a pattern matches no parameter (the message lists some names).
    """
    every = parameter_names(mech)
    if parameters is None:
        return every
    patterns = [parameters] if isinstance(parameters, str) else list(parameters)
    out, seen = [], set()
    for pat in patterns:
        if not isinstance(pat, str):
            raise InputError(f"parameter patterns are strings, got {pat!r}")
        hits = [n for n in every
                if n == pat or n.startswith(pat + "/") or n.startswith(pat + ".")
                or fnmatch.fnmatchcase(n, pat)]
        if not hits:
            shown = ", ".join(every[:12])
            raise InputError(f"no parameter matches {pat!r}; names look like {shown}, … "
                             f"({len(every)} in all: see pkm_pin.sensitivity.parameter_names)")
        for n in hits:
            if n not in seen:
                seen.add(n)
                out.append(n)
    return out


def _split(mech, name: str):
    """``(leg index, joint name or "base"/"anchor", kind, component)``."""
    legs = {leg.name: i for i, leg in enumerate(mech.legs)}
    parts = name.split("/")
    if parts[0] not in legs or len(parts) not in (2, 3):
        raise InputError(f"{name!r} is not a parameter name of {mech.name!r}")
    i = legs[parts[0]]
    if len(parts) == 2:
        where, _, comp = parts[1].partition(".")
        if where not in ("base", "anchor") or comp not in PLACEMENT_COMPONENTS:
            raise InputError(f"{name!r} is not a parameter name of {mech.name!r}")
        return i, where, "placement", comp
    joint, (kind, _, comp) = parts[1], parts[2].partition(".")
    chain = {j.name: j for j in urdf_chain(mech.legs[i])}
    ok = (joint in chain and ((kind == "origin" and comp in PLACEMENT_COMPONENTS)
                              or (kind == "axis" and chain[joint].axis is not None
                                  and comp in AXIS_COMPONENTS)))
    if not ok:
        raise InputError(f"{name!r} is not a parameter name of {mech.name!r} (joints on the "
                         f"chain of leg {parts[0]!r}: {list(chain)})")
    return i, joint, kind, comp


# ========================================================== virtual joint twists
def _placement_twist(xyz, rpy, comp: str) -> np.ndarray:
    """Left-perturbation twist (axis-first, parent frame) of a placement per unit of
    one of its xyz / rpy components."""
    k = PLACEMENT_COMPONENTS.index(comp)
    if k < 3:
        return screws.couple(np.eye(3)[k])
    r, p, y = rpy
    Rz, Ry = pin.rpy.rpyToMatrix(0.0, 0.0, y), pin.rpy.rpyToMatrix(0.0, p, 0.0)
    w = (Rz @ Ry @ np.array([1.0, 0.0, 0.0]), Rz @ np.array([0.0, 1.0, 0.0]),
         np.array([0.0, 0.0, 1.0]))[k - 3]
    return screws.line(np.asarray(xyz, dtype=float), w)


def _rpy(M: pin.SE3) -> tuple:
    return tuple(pin.rpy.matrixToRpy(M.rotation))


def _frames_placed(leg, q) -> pin.Data:
    """The calling thread's Pinocchio data of ``leg`` after one pass placing every frame
    at ``q`` (read it before the next Pinocchio call on this leg)."""
    data = leg.data
    pin.framesForwardKinematics(leg.model, data, q)
    return data


def _link_placement(leg, data: pin.Data, link: str) -> pin.SE3:
    """World placement of ``link`` from ``data`` returned by :func:`_frames_placed`."""
    if not leg.model.existFrame(link):
        raise FrameNotFound(link, [f.name for f in leg.model.frames], f"leg {leg.name!r}")
    return leg.base * data.oMf[leg.model.getFrameId(link)]


def virtual_twist(mech, assembly, name: str) -> np.ndarray:
    """World twist (axis-first) of the leg's tip per unit error of parameter ``name``
    at fixed joint values (anchor parameters: minus the platform twist they require)."""
    i = _split(mech, name)[0]
    leg = mech.legs[i]
    data = _frames_placed(leg, leg.check_q(assembly.leg_q[i]))
    return _virtual_twist_placed(mech, assembly, name, data)


def _virtual_twist_placed(mech, assembly, name: str, data: pin.Data) -> np.ndarray:
    """:func:`virtual_twist` from ``data``, the leg's frames placed at its assembly
    configuration by :func:`_frames_placed` (one Pinocchio pass per leg serves all of
    its parameters)."""
    i, where, kind, comp = _split(mech, name)
    leg = mech.legs[i]
    if where == "base":
        return _placement_twist(leg.base.translation, _rpy(leg.base), comp)
    if where == "anchor":
        A = mech.anchors[i]
        return -screws.transform(_placement_twist(A.translation, _rpy(A), comp), assembly.pose)
    j = {jj.name: jj for jj in urdf_chain(leg)}[where]
    F = _link_placement(leg, data, j.parent)
    if kind == "origin":
        return screws.transform(_placement_twist(j.xyz, j.rpy, comp), F)
    e = np.zeros(6)
    e[AXIS_COMPONENTS.index(comp)] = 1.0  # rotation about e_k through the joint origin
    W0 = F * pin.SE3(pin.rpy.rpyToMatrix(*j.rpy), np.asarray(j.xyz, dtype=float))
    Wq = _link_placement(leg, data, j.child)
    return screws.transform(e, W0) - screws.transform(e, Wq)


# ===================================================================== solution
@dataclass
class Sensitivity:
    """Platform pose error per unit parameter error, at one assembly.

    Attributes:
        parameters: Parameter names (columns).
        matrix: 6 × n: column ``k`` is the platform's small displacement twist (axis-first
            ``(ω; v_O)`` about the world origin) per unit error of ``parameters[k]``, at
            fixed actuated coordinates.
        virtual_twists: 6 × n: each parameter's virtual joint twist ``ξ`` (world).
        compatibility: Residual of each column's stacked system relative to the size of
            its virtual twist (homogenised); above :data:`COMPATIBILITY_TOL` the error
            cannot be absorbed by the rigid mechanism.
        assembly: The assembly it was computed at.
    """

    parameters: list[str]
    matrix: np.ndarray
    virtual_twists: np.ndarray
    compatibility: np.ndarray
    assembly: object = field(repr=False)
    tol: float = COMPATIBILITY_TOL

    def column(self, name: str) -> np.ndarray:
        """The column (6,) of one parameter."""
        try:
            return self.matrix[:, self.parameters.index(name)]
        except ValueError as e:
            raise InputError(f"{name!r} is not among the {len(self.parameters)} parameters "
                             "of this sensitivity") from e

    @property
    def incompatible(self) -> list[str]:
        """Parameters whose error the (overconstrained) rigid mechanism cannot absorb."""
        return [n for n, c in zip(self.parameters, self.compatibility) if c > self.tol]

    def point_matrix(self, point=None) -> np.ndarray:
        """6 × n with the linear rows turned into the velocity of ``point`` (default: the
        platform origin): ``(ω; v_O + ω × point)``."""
        p = self.assembly.pose.translation if point is None else screws.as_vector3(point)
        out = self.matrix.copy()
        out[3:] += np.cross(self.matrix[:3].T, p).T
        return out


def _leg_wrench_rows(mech, assembly) -> list[np.ndarray]:
    """Per leg, its actuation and constraint wrenches from the analysis (together they
    span the wrenches reciprocal to the leg's passive joint twists)."""
    an = mech.analyze(assembly)
    ends = np.cumsum([0] + [len(leg.actuated) for leg in mech.legs])
    return [np.vstack([an.A[a:b], w])
            for a, b, w in zip(ends[:-1], ends[1:], an.leg_constraint_wrenches)]


def sensitivity(mech, assembly=None, parameters=None) -> Sensitivity:
    """Platform pose error per unit error of each parameter (see the module docstring).

    Args:
        mech: The :class:`~pkm_pin.mechanism.Mechanism`.
        assembly: Where (default: the home assembly); actuated coordinates held fixed.
        parameters: Names, prefixes or globs (see :func:`select_parameters`); all by default.

    Raises:
        InputError: unknown parameter names or a leg without URDF text.
        SingularityError: the pose error is undetermined (type II singularity).
    """
    if assembly is None:
        assembly = mech.home_assembly
    names = select_parameters(mech, parameters)
    L = mech.characteristic_length
    # every screw about the platform's centre: the rank decision and the compatibility
    # do not depend on where the mechanism stands in the world
    centre = assembly.pose.translation
    W = [screws.about(w, centre) if len(w) else w for w in _leg_wrench_rows(mech, assembly)]
    offs = np.r_[0, np.cumsum([w.shape[0] for w in W])]
    M = np.vstack([w @ screws.DELTA for w in W])  # ζ ∘ t = (ζᵀ Δ) t
    D = np.r_[np.ones(3), np.full(3, L)]          # t = D t_h (homogenised unknown)
    Mh = M * D
    scale = np.linalg.norm(Mh, axis=1)
    scale[scale == 0] = 1.0
    Mh /= scale[:, None]
    U, sv, Vt = np.linalg.svd(Mh, full_matrices=False)
    if sv.size < 6 or sv[-1] < SENSITIVITY_SINGULAR_TOL * sv[0]:
        raise SingularityError(
            "the platform pose error is undetermined here (the legs' actuation and "
            f"constraint wrenches span rank < 6: singular values {sv})", "sensitivity",
            float(sv[-1] / sv[0]) if sv.size else 0.0)
    leg_of = {leg.name: i for i, leg in enumerate(mech.legs)}
    xi = np.zeros((6, len(names)))
    R = np.zeros((M.shape[0], len(names)))
    columns = {}
    for k, name in enumerate(names):
        columns.setdefault(leg_of[name.split("/")[0]], []).append(k)
    for i, ks in columns.items():
        data = _frames_placed(mech.legs[i], assembly.leg_q[i])
        for k in ks:
            xi[:, k] = screws.about(_virtual_twist_placed(mech, assembly, names[k], data),
                                    centre)
            R[offs[i]:offs[i + 1], k] = W[i] @ screws.DELTA @ xi[:, k]
    Rh = R / scale[:, None]
    X = Vt.T @ ((U.T @ Rh) / sv[:, None])
    resid = np.linalg.norm(Mh @ X - Rh, axis=0)
    norm = np.linalg.norm(xi / D[:, None], axis=0)  # |ξ| homogenised bounds every |Rh| row
    compat = np.where(norm > 0, resid / np.where(norm > 0, norm, 1.0), 0.0)
    # twists about the world origin
    X, xi = (screws.from_point((Y * d).T, centre).T for Y, d in ((X, D[:, None]), (xi, 1.0)))
    return Sensitivity(names, X, xi, compat, assembly)


# ================================================================ finite errors
def _placement_with(M: pin.SE3, comp: str, delta: float) -> pin.SE3:
    k = PLACEMENT_COMPONENTS.index(comp)
    xyz, rpy = M.translation.copy(), np.array(_rpy(M))
    if k < 3:
        xyz[k] += delta
    else:
        rpy[k - 3] += delta
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), xyz)


def _numbers(values) -> str:
    return " ".join(repr(float(v) + 0.0) for v in values)


def _edit_xml(xml: str, edits: list[tuple[str, str, str, float]]) -> str:
    root = etree.fromstring(xml.encode())
    for joint, kind, comp, delta in edits:
        j = root.find(f"joint[@name='{joint}']")
        if kind == "origin":
            o = j.find("origin")
            if o is None:
                o = etree.SubElement(j, "origin")
            xyz = np.array(list(map(float, o.get("xyz", "0 0 0").split())))
            rpy = np.array(list(map(float, o.get("rpy", "0 0 0").split())))
            k = PLACEMENT_COMPONENTS.index(comp)
            if k < 3:
                xyz[k] += delta
            else:
                rpy[k - 3] += delta
            o.set("xyz", _numbers(xyz))
            o.set("rpy", _numbers(rpy))
        else:
            a = j.find("axis")
            if a is None:
                a = etree.SubElement(j, "axis", xyz="1 0 0")
            s = np.array(list(map(float, a.get("xyz").split())))
            s = pin.exp3(delta * np.eye(3)[AXIS_COMPONENTS.index(comp)]) @ s
            a.set("xyz", _numbers(s))
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8").decode()


def perturb(mech, errors: Mapping[str, float]):
    """A copy of ``mech`` with finite parameter errors applied.

    Joint origins and axes are edited in the leg's URDF text (origin: the component is
    incremented; axis: rotated by the angle about the joint frame's axis), bases and
    anchors in their placements (xyz incremented, or the rpy component incremented).
    Legs without errors are shared with ``mech``; the copy is of the same class as
    ``mech``.
    """
    per_leg: dict[int, list] = {}
    for name, value in errors.items():
        v = float(value)
        if not math.isfinite(v):
            raise InputError(f"the error of {name!r} must be finite, got {value!r}")
        i, where, kind, comp = _split(mech, name)
        per_leg.setdefault(i, []).append((where, kind, comp, v))
    legs, anchors = list(mech.legs), list(mech.anchors)
    for i, items in per_leg.items():
        leg = mech.legs[i]
        base = leg.base
        edits = []
        for where, kind, comp, v in items:
            if where == "base":
                base = _placement_with(base, comp, v)
            elif where == "anchor":
                anchors[i] = _placement_with(anchors[i], comp, v)
            else:
                edits.append((where, kind, comp, v))
        if edits:
            legs[i] = Leg.from_urdf(_edit_xml(leg.xml, edits), leg.tip, leg.actuated, base,
                                    leg.name)
        elif base is not leg.base:
            legs[i] = replace(leg, base=base)
    return type(mech)(legs, anchors, name=mech.name, home=mech.home, home_q=mech.home_q,
                      description=mech.description)


__all__ = [
    "AXIS_COMPONENTS",
    "COMPATIBILITY_TOL",
    "PLACEMENT_COMPONENTS",
    "Sensitivity",
    "UrdfJoint",
    "leg_parameter_names",
    "parameter_names",
    "perturb",
    "select_parameters",
    "sensitivity",
    "urdf_chain",
    "virtual_twist",
]
