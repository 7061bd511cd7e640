"""MJCF: a MuJoCo body tree plus its ``<equality>`` loop closures.

:func:`read_mjcf` builds the tree with Pinocchio's MJCF parser (4.1) and reads the
closures, the actuators and the reference configuration from the file itself:

* ``<equality><connect>``: a point closure. Body form (``body1``, ``body2`` — the world when
  omitted —, ``anchor`` in ``body1``): ``C_a`` is ``body1`` at ``anchor``, ``C_b`` the same
  point fixed in ``body2`` at the reference configuration (MuJoCo's rule: the constraint
  holds at ``qpos0``). Site form (``site1``, ``site2``): the two sites' origins.
* ``<equality><weld>``: a weld. Body form: ``C_b`` is ``body2`` at ``anchor`` (in ``body2``),
  ``C_a`` is ``body1`` at ``relpose * anchor`` when ``relpose`` (pos, quat w x y z) has a
  non-zero quaternion, else at the relative pose ``body1⁻¹ body2`` of the reference
  configuration times ``anchor``. Site form: the two sites' frames.
* ``active="false"`` constraints are skipped; ``joint``, ``tendon``, ``flex`` and
  ``distance`` equalities are not loop closures and are refused with an error.
* Actuated joints: the ``joint`` (or ``jointinparent``) attribute of every ``<actuator>``
  child, in file order (MuJoCo's ``ctrl`` order); an actuator on a tendon, site or body is
  an error.
* Reference: Pinocchio's ``referenceConfigurations["qpos0"]`` (the joints' ``ref``), else
  the neutral configuration.
* Output frame: ``output=`` if given, else a body named ``effector``, else the last body.
* Frame names are made distinct (MuJoCo names bodies, joints and sites in separate name
  spaces; Pinocchio's frames share one): a body keeps its name, a joint or site frame of
  the same name gets the suffix ``_joint`` / ``_site`` (joint names are unchanged).

An MJCF without ``<equality>`` is a tree: its model has no closures and is analysed as a
serial (or branching) chain.

Pinocchio 4.1's parser is worked around where it is wrong: it keeps only the first body
under ``<worldbody>`` (the others, and sites on the world, are dropped), so the children of
``<worldbody>`` are wrapped in one joint-less body (:data:`WORLD_BODY`, a frame fixed to
the universe) in a temporary copy of the file; it gives every constraint an empty name (the
``name`` attribute is lost), so the constraints are read here from the XML and only the
tree is taken from Pinocchio (``buildModelAndConstraintsFromMJCF`` gives the same
frames and placements; the tests compare them).
"""

from __future__ import annotations

import os
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ClosureFileError, _listing
from ..urdf import _captured_stderr
from .closure_model import Closure, ClosureModel

#: Name of the joint-less body that wraps the children of ``<worldbody>``.
WORLD_BODY = "mjcf_worldbody"

#: Equality elements that are not loop closures.
_NOT_CLOSURES = ("joint", "tendon", "flex", "flexvert", "distance")


def read_mjcf(path: str | os.PathLike, *, output: str | None = None) -> ClosureModel:
    """The closure model of an MJCF file (module docstring).

    Raises:
        ClosureFileError: a missing or malformed file, an equality naming an unknown body
            or site, an actuator on something other than a joint; the message names the
            file, the element and how to fix it.
    """
    path = Path(path)
    label = str(path)
    root = _parse(path)
    tree = _build_tree(path, root)
    renamed = _distinct_frame_names(tree)
    reference = (np.array(tree.referenceConfigurations["qpos0"])
                 if "qpos0" in tree.referenceConfigurations else pin.neutral(tree))
    closures = _closures(label, root, tree, reference, renamed)
    actuated = _actuated(label, root, tree)
    out = output if output is not None else _output_frame(tree)
    return ClosureModel(tree, closures, actuated, out, name=root.get("model", path.stem),
                        reference=reference)


# ------------------------------------------------------------------------------ tree
def _parse(path: Path) -> ET.Element:
    """The file's XML root, or a :class:`ClosureFileError`."""
    label = str(path)
    if not path.is_file():
        raise ClosureFileError(label, "", "no such MJCF file; check the path")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        line, col = e.position
        raise ClosureFileError(label, "", f"malformed XML at line {line}, column {col}: "
                               f"{e}") from e
    except OSError as e:
        raise ClosureFileError(label, "", f"cannot be read: {e}") from e
    if root.tag != "mujoco":
        raise ClosureFileError(label, "", f"the root element is <{root.tag}>, an MJCF's must "
                               "be <mujoco>")
    if root.find("worldbody") is None:
        raise ClosureFileError(label, "worldbody", "is missing; an MJCF needs a <worldbody>")
    return root


def _build_tree(path: Path, root: ET.Element) -> pin.Model:
    """Pinocchio's tree of the file, with the children of ``<worldbody>`` wrapped in one
    body when Pinocchio would drop some (several bodies, or sites on the world)."""
    world = root.find("worldbody")
    children = list(world)
    needs_wrap = sum(c.tag == "body" for c in children) > 1 or any(
        c.tag in ("site", "frame") for c in children)
    if not needs_wrap:
        return _pinocchio_model(str(path), str(path))
    if root.find(".//include") is not None:
        raise ClosureFileError(str(path), "worldbody", "several bodies under <worldbody> and "
                               "an <include>: Pinocchio keeps only the first body; wrap them "
                               "in one body without joint, or inline the included file")
    wrapper = ET.Element("body", {"name": WORLD_BODY})
    for c in children:
        world.remove(c)
        wrapper.append(c)
    world.append(wrapper)
    with tempfile.TemporaryDirectory() as folder:
        copy = Path(folder) / path.name
        ET.ElementTree(root).write(copy)
        model = _pinocchio_model(str(copy), str(path))
    world.remove(wrapper)
    world.extend(children)
    return model


#: Suffix of a joint or site frame whose name a body also has (MuJoCo's name spaces are
#: per element kind; Pinocchio's frames share one).
_SUFFIX = {pin.FrameType.JOINT: "_joint", pin.FrameType.OP_FRAME: "_site",
           pin.FrameType.FIXED_JOINT: "_fixed", pin.FrameType.SENSOR: "_sensor"}


def _distinct_frame_names(tree: pin.Model) -> dict:
    """Make every frame name of ``tree`` distinct, in place: where a body shares its name
    with a joint or a site (Cassie's ``left-plantar-rod`` is both a body and a joint),
    the body keeps it and the other frames get the suffix of their kind
    (``left-plantar-rod_joint``; joint names, ``tree.names``, are unchanged). Returns the
    new names, ``{(frame type, old name): new name}``."""
    seen: dict = {}
    for frame in tree.frames:
        seen.setdefault(frame.name, []).append(frame.type)
    clashing = {name for name, kinds in seen.items() if len(kinds) > 1}
    renamed: dict = {}
    taken = set(seen)
    for frame in tree.frames:
        if frame.name in clashing and frame.type != pin.FrameType.BODY:
            name = base = frame.name + _SUFFIX.get(frame.type, "_frame")
            k = 1
            while name in taken:
                name, k = f"{base}{k}", k + 1
            taken.add(name)
            renamed[(frame.type, frame.name)] = name
            frame.name = name
    return renamed


def _pinocchio_model(filename: str, label: str) -> pin.Model:
    with _captured_stderr():
        try:
            return pin.buildModelFromMJCF(filename)
        except Exception as e:  # Pinocchio raises RuntimeError/ValueError with C++ text
            raise ClosureFileError(label, "", f"Pinocchio cannot build a model: {e}") from e


# -------------------------------------------------------------------------- closures
def _closures(label: str, root: ET.Element, tree: pin.Model, q: np.ndarray,
              renamed: dict) -> tuple:
    """One :class:`Closure` per active ``connect`` / ``weld`` of ``<equality>``."""
    data = tree.createData()
    pin.framesForwardKinematics(tree, data, q)
    out, counts = [], {}
    for equality in root.findall("equality"):
        for el in equality:
            i = counts[el.tag] = counts.get(el.tag, -1) + 1
            where = f"equality/{el.tag}[{i}]" + (f" {el.get('name')!r}" if el.get("name") else "")
            if el.tag in _NOT_CLOSURES:
                raise ClosureFileError(label, where, "is not a loop closure; pkm_pin reads "
                                       "<connect> and <weld> equalities only: remove it")
            if el.tag not in ("connect", "weld"):
                raise ClosureFileError(label, where, "unknown equality element")
            if el.get("active", "true") == "false":
                continue
            name = el.get("name") or f"{el.tag}{i}"
            out.append(_closure(label, where, el, name, tree, data, renamed))
    return tuple(out)


def _closure(label: str, where: str, el: ET.Element, name: str, tree: pin.Model,
             data: pin.Data, renamed: dict) -> Closure:
    """The closure of one ``connect`` or ``weld`` element."""
    kind = "point" if el.tag == "connect" else "weld"
    if el.get("site1") is not None or el.get("site2") is not None:
        a, b = (_frame(label, f"{where} {k}", el.get(k), tree, pin.FrameType.OP_FRAME,
                       renamed) for k in ("site1", "site2"))
        return Closure(kind, a, b, name=name)
    a = _frame(label, f"{where} body1", el.get("body1"), tree, pin.FrameType.BODY, renamed)
    b = _frame(label, f"{where} body2", el.get("body2", "world"), tree, pin.FrameType.BODY,
               renamed)
    oMa, oMb = (data.oMf[tree.getFrameId(f)] for f in (a, b))
    anchor = pin.SE3(np.eye(3), _floats(label, where, el, "anchor", 3, np.zeros(3)))
    if kind == "point":
        return Closure(kind, a, b, anchor, pin.SE3(np.eye(3), oMb.actInv(oMa * anchor)
                                                     .translation), name=name)
    relpose = _floats(label, where, el, "relpose", 7, np.zeros(7))
    if np.any(relpose[3:] != 0):
        w, x, y, z = relpose[3:]
        aMb = pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), relpose[:3])
    else:
        aMb = oMa.actInv(oMb)
    return Closure(kind, a, b, aMb * anchor, anchor, name=name)


def _frame(label: str, where: str, name: str | None, tree: pin.Model,
           kind: pin.FrameType, renamed: dict) -> str:
    """The tree's frame for the body or site ``name`` (``world``: the universe; a site
    renamed by :func:`_distinct_frame_names`: its new name)."""
    if name is None:
        raise ClosureFileError(label, where, "is missing")
    if name == "world" and kind == pin.FrameType.BODY:
        return tree.frames[0].name
    what = "body" if kind == pin.FrameType.BODY else "site"
    name = renamed.get((kind, name), name)
    names = [f.name for f in tree.frames if f.type == kind and f.name != WORLD_BODY]
    if name not in names:
        raise ClosureFileError(label, where, f"{name!r} is not a {what} of the model; its "
                               f"{what}s: {_listing(names)}")
    return name


def _floats(label: str, where: str, el: ET.Element, key: str, n: int,
            default: np.ndarray) -> np.ndarray:
    text = el.get(key)
    if text is None:
        return default
    try:
        values = np.array([float(t) for t in text.split()])
    except ValueError as e:
        raise ClosureFileError(label, f"{where} {key}", f"must be {n} numbers, got "
                               f"{text!r}") from e
    if values.shape != (n,) or not np.isfinite(values).all():
        raise ClosureFileError(label, f"{where} {key}", f"must be {n} finite numbers, got "
                               f"{text!r}")
    return values


# ------------------------------------------------------------------ motors and output
def _actuated(label: str, root: ET.Element, tree: pin.Model) -> tuple[str, ...]:
    """The joints of the ``<actuator>`` elements, in file order."""
    movable = [tree.names[j] for j in range(1, tree.njoints) if tree.joints[j].nv > 0]
    out = []
    for actuators in root.findall("actuator"):
        for i, el in enumerate(actuators):
            where = f"actuator/{el.tag}[{i}]" + (f" {el.get('name')!r}" if el.get("name")
                                                 else "")
            joint = el.get("joint", el.get("jointinparent"))
            if joint is None:
                raise ClosureFileError(label, where, "drives no joint (a tendon, site or body "
                                       "actuator); pkm_pin needs joint actuators")
            if joint not in movable:
                raise ClosureFileError(label, where, f"joint {joint!r} is not a joint of "
                                       f"Pinocchio's model (a body with several joints is "
                                       f"one composite joint); joints: {_listing(movable)}")
            if joint not in out:
                out.append(joint)
    return tuple(out)


def _output_frame(tree: pin.Model) -> str:
    """A body named ``effector``, else the last body of the tree."""
    bodies = [f.name for f in tree.frames if f.type == pin.FrameType.BODY
              and f.name != WORLD_BODY]
    if "effector" in bodies:
        return "effector"
    return bodies[-1] if bodies else tree.frames[0].name
