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
* ``<equality><joint>``: a coupling closure (``kind="coupling"``, one row) when linear:
  MuJoCo's ``q₁ − q₁₀ = c₀ + c₁ (q₂ − q₂₀)`` (``polycoef``, ``q₁₀``, ``q₂₀`` the
  joints' ``qpos0``) is ``q₁ = (c₀ + q₁₀ − c₁ q₂₀) + c₁ q₂``, the closure's ``frame_a`` /
  ``frame_b`` the two joints' frames (the universe's without ``joint2``: ``q₁ = c₀ +
  q₁₀``); a non-zero ``c₂``, ``c₃`` or ``c₄`` is refused in a sentence naming the
  equality.
* ``active="false"`` equalities are skipped, each with a note (:attr:`ClosureModel.notes`);
  ``tendon``, ``flex`` and ``distance`` equalities are refused with an error.
* Actuated joints, one per ``<actuator>`` child in file order (MuJoCo's ``ctrl``
  order): its ``joint`` (or ``jointinparent``); or, for ``tendon=`` on a fixed tendon,
  the joint the tendon's length moves with on the file's linear joint couplings
  (:func:`_tendon_joint`, with a note). A spatial tendon, a tendon over independent
  joints, and ``site``/``body``/slider-crank transmissions are refused by name.
* Reference: Pinocchio's ``referenceConfigurations["qpos0"]`` (the joints' ``ref``), else
  the neutral configuration; joint limits are MuJoCo's ``range`` of ``qpos``
  (:func:`_limits_in_qpos`).
* Output frame: ``output=`` if given, else the one the file names in
  ``<custom><text name="pkm_pin:output" data="FRAME"/>``, else a body named
  ``effector``, else the last body.
* A free joint of a body directly under ``<worldbody>`` (a floating base) is removed:
  that body is the base, the mechanism is analysed relative to it, and the model says so
  in its ``notes``; its coordinates are removed from every ``<key>`` of the file's size
  (:func:`_drop_from_keyframes`).
* Frame names are made distinct (MuJoCo names bodies, joints and sites in separate name
  spaces; Pinocchio's frames share one): a body keeps its name, a joint or site frame of
  the same name gets the suffix ``_joint`` / ``_site`` (joint names are unchanged).

An MJCF without ``<equality>`` is a tree: its model has no closures and is analysed as a
serial (or branching) chain.

Pinocchio 4.1's parser is worked around where it is wrong: it keeps only the first body
under ``<worldbody>`` (the others, and sites on the world, are dropped), so the children of
``<worldbody>`` are wrapped in one joint-less body (:data:`WORLD_BODY`, a frame fixed to
the universe) in a temporary copy of the file; it takes no joint ``pos`` from a default
class, so the copy has it written on the joint (:func:`_inline_default_joint_pos`); it
gives every constraint an empty name (the
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

from ..errors import ClosureFileError, _clip, _cut, _is_file, _listing
from ..urdf import (
    MAX_BYTES,
    MAX_COORDINATE,
    MAX_LINKS,
    MAX_XML_DEPTH,
    MAX_XML_ELEMENTS,
    LimitExceeded,
    _captured_stderr,
    check_xml_limits,
    read_bounded,
)
from .closure_model import Closure, ClosureModel

#: Name of the joint-less body that wraps the children of ``<worldbody>``.
WORLD_BODY = "mjcf_worldbody"

#: Deepest chain of ``<include>`` (a scene including a robot including its parts: 2).
MAX_INCLUDE_DEPTH = 8

#: Attributes checked as numbers (finite, within ±:data:`~pkm_pin.urdf.MAX_COORDINATE`)
#: on every element: positions, orientations, axes, joint ranges and references.
_NUMERIC = ("pos", "quat", "axisangle", "euler", "xyaxes", "zaxis", "axis", "range", "ref",
            "anchor", "relpose", "fromto")
#: How many numbers each of them holds (MuJoCo's XML reference): Pinocchio 4.1 reads an
#: empty or short list as uninitialised memory (``pos=""`` gave positions of 1e300 and
#: an SVD that did not converge; found by the fuzz suite), so the count is checked too.
_COUNTS = {"pos": 3, "quat": 4, "axisangle": 4, "euler": 3, "xyaxes": 6, "zaxis": 3,
           "axis": 3, "range": 2, "ref": 1, "anchor": 3, "relpose": 7, "fromto": 6}

#: MJCF elements that make bodies Pinocchio 4.1's parser ignores (the model would lose
#: them without a word): refused by name.
_NOT_EXPANDED = {"attach": "attaches a sub-model", "replicate": "repeats its bodies",
                 "composite": "generates bodies", "flexcomp": "generates a flex",
                 "model": "declares a sub-model to attach"}

#: Equality elements that are not loop closures, and why each is refused.
_NOT_CLOSURES = {"tendon": "couples tendon lengths, not joints nor bodies",
                 "flex": "holds a deformable flex", "flexvert": "holds a deformable flex",
                 "flexstrain": "holds a deformable flex",
                 "distance": "is a geom distance (removed from MuJoCo in 2.2.2)"}


def read_mjcf(path: str | os.PathLike, *, output: str | None = None) -> ClosureModel:
    """The closure model of an MJCF file (module docstring).

    Raises:
        ClosureFileError: a missing or malformed file, an equality naming an unknown body
            or site, an actuator on something other than a joint; the message names the
            file, the element and how to fix it.
    """
    path = Path(path)
    label = _clip(str(path))
    root, rewritten = _parse(path)
    held = _hold_free_roots(root)
    placed = _inline_default_joint_pos(root)
    tree = _build_tree(path, root, rewritten or bool(held) or placed)
    renamed = _distinct_frame_names(tree)
    reference = (np.array(tree.referenceConfigurations["qpos0"])
                 if "qpos0" in tree.referenceConfigurations else pin.neutral(tree))
    _limits_in_qpos(tree, reference)
    closures, notes = _closures(label, root, tree, reference, renamed)
    actuated, matches, drive_notes = _actuated(label, root, tree, closures)
    named = output if output is not None else _named_output(root)
    out = named if named is not None else _output_frame(tree)
    notes = tuple(f"{body} has a free joint in the file: it is held as the base, the "
                  "mechanism analysed relative to it" for body in held) + notes + drive_notes
    springs = _springs(root, tree, actuated)
    if springs:
        notes += (f"{', '.join(springs)}: a spring (stiffness) and no actuator in the file "
                  "(pkm_pin models no spring): where they move with every motor locked, "
                  "those are idle motions, and the default output is chosen as if they "
                  "were held",)
    return ClosureModel(tree, closures, actuated, out, name=root.get("model", path.stem),
                        reference=reference, actuator_matches=matches, notes=notes,
                        output_named=named is not None, springs=springs)


# ------------------------------------------------------------------------------ tree
def parse_mjcf(path: str | os.PathLike) -> ET.Element:
    """The XML root of an MJCF file as :func:`read_mjcf` reads it: within the limits of
    ``docs/reliability.md``, its ``<include>`` files inlined, its ``<worldbody>`` sections
    merged (for what the file says beyond the tree, e.g. a ``<custom>`` text).

    Raises:
        ClosureFileError: as :func:`read_mjcf`.
    """
    return _parse(Path(path))[0]


def _parse(path: Path) -> tuple[ET.Element, bool]:
    """The file's XML root with its ``<include>`` files inlined and its ``<worldbody>``
    sections merged (MuJoCo's rules), checked within the limits of ``docs/reliability.md``;
    and whether anything was inlined or merged (then Pinocchio reads a rewritten copy).

    Raises:
        ClosureFileError: a missing, too large, too deep or malformed file, a wrong include
            or a number out of range.
    """
    label = _clip(str(path))
    if not _is_file(path):
        raise ClosureFileError(label, "", "no such MJCF file; check the path")
    budget = [MAX_BYTES]
    root = _parse_file(path, label, budget)
    if root.tag != "mujoco":
        raise ClosureFileError(label, "", f"the root element is <{_cut(root.tag)[1:-1]}>, an "
                               "MJCF's must be <mujoco>")
    included = _inline_includes(path, root, budget)
    merged = _merge_worldbodies(root)
    if included:
        _check_inlined_size(label, root)
    if root.find("worldbody") is None:
        raise ClosureFileError(label, "worldbody", "is missing; an MJCF needs a <worldbody>")
    for section, tag, what in (("worldbody", "body", "bodies"),
                               ("equality", "equality/*", "equality constraints"),
                               ("actuator", "actuator/*", "actuators")):
        count = sum(1 for _ in root.iterfind(f".//{tag}" if tag == "body" else tag))
        if count > MAX_LINKS:
            raise ClosureFileError(label, section, f"{count} {what}, more than the "
                                   f"{MAX_LINKS} pkm_pin reads")
    for el in root.iter():
        if el.tag in _NOT_EXPANDED and (el.tag != "model" or el.get("file") is not None):
            raise ClosureFileError(label, f"<{el.tag}>", f"{_NOT_EXPANDED[el.tag]}, which "
                                   "Pinocchio's MJCF parser ignores; write the bodies out "
                                   "(MuJoCo's compiled model, mj_saveLastXML, has them)")
    _check_numbers(label, root)
    return root, bool(included or merged)


def _parse_file(path: Path, label: str, budget: list) -> ET.Element:
    """One XML file's root, read within ``budget[0]`` bytes (decreased by its size) and
    the XML limits."""
    try:
        data = read_bounded(path, budget[0], "MJCF (with its included files)", binary=True)
        check_xml_limits(data)
    except LimitExceeded as e:
        reason = e.reason if budget[0] == MAX_BYTES else (
            f"with its included files, the model is more than {MAX_BYTES / 1e6:g} MB, the "
            "most pkm_pin reads")
        raise ClosureFileError(label, "", reason) from e
    except OSError as e:
        raise ClosureFileError(label, "", f"cannot be read: {e}") from e
    budget[0] -= len(data)
    try:
        return ET.fromstring(data)
    except ET.ParseError as e:
        line, col = e.position
        raise ClosureFileError(label, "", f"malformed XML at line {line}, column {col}: "
                               f"{e}") from e


def _inline_includes(main: Path, root: ET.Element, budget: list) -> list[Path]:
    """Replace every ``<include file=…>`` under ``root``, in place, by the children of the
    included file's ``<mujoco>`` root, as MuJoCo does: the path is relative to the main
    file's folder (MuJoCo's rule, even in an included file), a file is included at most
    once, includes nest. Refused: a file outside the main file's folder (after links are
    resolved), a cycle, a second include of a file, nesting deeper than
    :data:`MAX_INCLUDE_DEPTH`, a file that is not ``<mujoco>``. Returns the files
    inlined."""
    start = main.resolve()
    folder = start.parent
    seen: list[Path] = []
    labels = {start: _clip(str(main))}  # errors name the main file as it was given

    def shown(p: Path) -> str:
        return str(p.relative_to(folder)) if p.is_relative_to(folder) else str(p)

    def load(el: ET.Element, including: Path, chain: tuple) -> ET.Element:
        label, name = labels[including], el.get("file")
        where = f"include {_cut(name)}" if name is not None else "include"
        if not name:
            raise ClosureFileError(label, where, "has no file attribute")
        if len(chain) > MAX_INCLUDE_DEPTH:
            raise ClosureFileError(label, where, f"includes nested more than "
                                   f"{MAX_INCLUDE_DEPTH} deep")
        try:
            target = (folder / name).resolve()
        except (OSError, ValueError, RuntimeError) as e:
            raise ClosureFileError(label, where, f"not a usable path ({e})") from e
        if not target.is_relative_to(folder):
            raise ClosureFileError(label, where, f"{_cut(str(target))} is outside the "
                                   f"model's folder {_cut(str(folder))}; pkm_pin includes "
                                   "files of that folder only (paths are relative to the "
                                   "main file, as in MuJoCo)")
        if target in chain:
            cycle = " → ".join(shown(p) for p in chain[chain.index(target):] + (target,))
            raise ClosureFileError(label, where, f"includes itself ({_cut(cycle)[1:-1]}); "
                                   "remove the include")
        if target in seen:
            raise ClosureFileError(label, where, f"{shown(target)} is included twice; MuJoCo "
                                   "includes a file at most once")
        if not _is_file(target):
            raise ClosureFileError(label, where, f"no such file {_cut(str(target))} (paths "
                                   "are relative to the main file's folder, as in MuJoCo)")
        seen.append(target)
        labels[target] = _clip(str(target))
        sub = _parse_file(target, labels[target], budget)
        if sub.tag != "mujoco":
            raise ClosureFileError(labels[target], "", f"the root element is "
                                   f"<{_cut(sub.tag)[1:-1]}>; an included MJCF's must be "
                                   "<mujoco>")
        expand(sub, target, chain + (target,))
        return sub

    def expand(top: ET.Element, file: Path, chain: tuple) -> None:
        stack = [top]
        while stack:
            el = stack.pop()
            i = 0
            while i < len(el):
                child = el[i]
                if child.tag == "include":
                    children = list(load(child, file, chain))
                    el[i:i + 1] = children
                    i += len(children)
                else:
                    stack.append(child)
                    i += 1

    expand(root, start, (start,))
    return seen


def _merge_worldbodies(root: ET.Element) -> bool:
    """Merge repeated top-level sections as MuJoCo does, where Pinocchio 4.1 does not
    (returns whether it did):

    * every ``<worldbody>`` after the first moves its children into the first (Pinocchio
      builds the tree once per ``<worldbody>``: a scene that includes its robot and adds
      a floor has two);
    * every ``<default>`` after the first moves its classes into the first, and its
      element defaults (``<geom>``, ``<joint>`` … of the main class) into the first's,
      attributes given later winning (Pinocchio keeps one ``<default>``, then fails on
      a ``class=`` of the other: Menagerie's aloha scene adds its own)."""
    worlds = root.findall("worldbody")
    for world in worlds[1:]:
        worlds[0].extend(list(world))
        root.remove(world)
    defaults = root.findall("default")
    for default in defaults[1:]:
        for child in list(default):
            same = defaults[0].find(child.tag) if child.tag != "default" else None
            if same is None:
                defaults[0].append(child)
            else:
                same.attrib.update(child.attrib)
        root.remove(default)
    return len(worlds) > 1 or len(defaults) > 1


def _check_inlined_size(label: str, root: ET.Element) -> None:
    """The depth and element count of the model with its includes inlined."""
    stack, count = [(root, 1)], 0
    while stack:
        el, depth = stack.pop()
        count += 1
        if depth > MAX_XML_DEPTH:
            raise ClosureFileError(label, "include", f"with its included files, elements "
                                   f"nested more than {MAX_XML_DEPTH} deep (<{el.tag}>)")
        if count > MAX_XML_ELEMENTS:
            raise ClosureFileError(label, "include", f"with its included files, more than "
                                   f"{MAX_XML_ELEMENTS} XML elements")
        stack.extend((c, depth + 1) for c in el)


def _check_numbers(label: str, root: ET.Element) -> None:
    """Every attribute of :data:`_NUMERIC` numbers, finite, within ±MAX_COORDINATE; joint
    axes and quaternions of non-zero length; joint ranges with lower ≤ upper. The error
    names the element, the attribute and the value."""
    counts: dict = {}
    equalities = {el for equality in root.iter("equality") for el in equality}
    for el in root.iter():
        i = counts[el.tag] = counts.get(el.tag, -1) + 1
        keys = [k for k in _NUMERIC if k in el.attrib]
        if not keys:
            continue
        where = f"{el.tag}[{i}]" + (f" {_cut(el.get('name'))}" if el.get("name") else "")
        for key in keys:
            text = el.get(key)
            try:
                values = np.array([float(t) for t in text.split()])
            except ValueError as e:
                raise ClosureFileError(label, f"{where} {key}", f"must be numbers, got "
                                       f"{_cut(text)}") from e
            if values.size != _COUNTS[key] and el not in equalities:  # (_closures: those)
                raise ClosureFileError(label, f"{where} {key}", f"must be {_COUNTS[key]} finite "
                                       f"numbers, got {_cut(text)}")
            if not np.all(np.abs(values) <= MAX_COORDINATE):
                bad = values[~(np.abs(values) <= MAX_COORDINATE)][0]
                raise ClosureFileError(label, f"{where} {key}", f"has {bad:g}; numbers must "
                                       f"be finite and within ±{MAX_COORDINATE:g} (m, rad or "
                                       "degrees)")
            if key == "quat" or (key == "axis" and el.tag == "joint"):
                if not np.any(values):
                    raise ClosureFileError(label, f"{where} {key}", f"has zero length "
                                           f"({_cut(text)}); give a non-zero {key}")
            if key == "range" and el.tag == "joint" and values[0] > values[1]:
                raise ClosureFileError(label, f"{where} range", f"has lower {values[0]:g} > "
                                       f"upper {values[1]:g}")


def _hold_free_roots(root: ET.Element) -> list[str]:
    """Remove the free joints (``<freejoint/>``, ``<joint type="free">``) of the bodies
    directly under ``<worldbody>``, in place: a floating base (a humanoid's pelvis, a
    robot dropped on a floor) is held, and the closed loops are analysed relative to it.
    Returns the names of the bodies so held."""
    held, removed, slots = [], [], _joint_slots(root)
    for world in root.findall("worldbody"):
        for body in world.findall("body"):
            free = [c for c in body if c.tag == "freejoint"
                    or (c.tag == "joint" and c.get("type") == "free")]
            for joint in free:
                body.remove(joint)
                removed.append(joint)
            if free:
                held.append(body.get("name", "the root body"))
    if held:
        _drop_from_keyframes(root, slots, removed)
    return held


#: Coordinates (qpos, qvel) of MuJoCo's joint types; ``hinge`` is the default type.
_JOINT_SIZES = {"free": (7, 6), "ball": (4, 3), "slide": (1, 1), "hinge": (1, 1)}


def _joint_slots(root: ET.Element) -> list:
    """``[(element, nq, nv)]`` for every joint of the tree in MuJoCo's ``qpos`` order:
    bodies depth first (through ``<frame>``), each body's joints in the file's order
    before its children's."""
    slots: list = []

    def walk(el: ET.Element) -> None:
        for child in el:
            if child.tag == "freejoint":
                slots.append((child, 7, 6))
            elif child.tag == "joint":
                slots.append((child, *_JOINT_SIZES.get(child.get("type", "hinge"), (1, 1))))
        for child in el:
            if child.tag in ("body", "frame"):
                walk(child)

    for world in root.findall("worldbody"):
        walk(world)
    return slots


def _drop_from_keyframes(root: ET.Element, slots: list, removed: list) -> None:
    """Remove the ``removed`` (held) free joints' entries from every ``<key>``'s ``qpos``
    and ``qvel`` (a keyframe of the floating robot, e.g. Menagerie Cassie's ``home``; Pinocchio
    refuses one whose size is not the model's), in place. ``slots``: :func:`_joint_slots`
    before the free joints were removed. A key whose size is not the file's is left to
    Pinocchio's own error."""
    for attr, size in (("qpos", 1), ("qvel", 2)):
        total = sum(s[size] for s in slots)
        keep, start = [], 0
        for el, *n in slots:  # n: (nq, nv)
            if not any(el is r for r in removed):
                keep.extend(range(start, start + n[size - 1]))
            start += n[size - 1]
        for keys in root.findall("keyframe"):
            for key in keys.findall("key"):
                values = (key.get(attr) or "").split()
                if len(values) == total:
                    key.set(attr, " ".join(values[i] for i in keep))


def _inline_default_joint_pos(root: ET.Element, attribute: str = "pos") -> bool:
    """Write on every ``<joint>`` without ``attribute`` (``pos``) the value its default
    class gives, in place (MuJoCo's rules: the joint's ``class``, else the nearest
    ``childclass`` of its bodies, else ``main``; a nested ``<default>`` inherits its
    parent's). Pinocchio 4.1 takes a joint's type, axis, range and ref from its class but
    not its position (Menagerie's Robotiq 2F-85 puts its fingers' follower joints there:
    without it the joint axis passes through the loop's pin). Returns whether a joint
    was changed."""
    defaults: dict = {}

    def walk(el: ET.Element, inherited: dict) -> None:
        own = dict(inherited)
        joint = el.find("joint")
        if joint is not None and joint.get(attribute) is not None:
            own[attribute] = joint.get(attribute)
        defaults[el.get("class", "main")] = own
        for child in el.findall("default"):
            walk(child, own)

    for top in root.findall("default"):
        walk(top, {})
    if not any(attribute in d for d in defaults.values()):
        return False
    changed = False
    stack = [(body, "main") for body in root.findall("worldbody")]
    while stack:
        el, cls = stack.pop()
        cls = el.get("childclass", cls)
        for child in el:
            if child.tag == "joint" and child.get(attribute) is None:
                value = defaults.get(child.get("class", cls), {}).get(attribute)
                if value is not None:
                    child.set(attribute, value)
                    changed = True
            elif child.tag in ("body", "frame"):
                stack.append((child, cls))
    return changed


def _springs(root: ET.Element, tree: pin.Model, actuated: tuple) -> tuple[str, ...]:
    """The joints the file gives a spring (``stiffness`` > 0, its own or its class's)
    and no actuator, in tree order (:attr:`ClosureModel.springs`)."""
    _inline_default_joint_pos(root, "stiffness")
    stiff = set()
    for joint in root.iter("joint"):
        try:
            k = float(joint.get("stiffness", "0"))
        except ValueError:
            continue
        if k > 0 and joint.get("name") and joint.get("name") not in actuated:
            stiff.add(joint.get("name"))
    driven = _coupled_to(root, set(actuated))
    return tuple(tree.names[j] for j in range(1, tree.njoints)
                 if tree.names[j] in stiff - driven and tree.joints[j].nv == 1)


def _coupled_to(root: ET.Element, joints: set) -> set:
    """The joints that the file's active ``<equality><joint>`` couplings tie to any of
    ``joints``, directly or through other couplings (those included): a spring joint
    among them moves with its motor, not with the motors locked."""
    edges: dict = {}
    for equality in root.findall("equality"):
        for el in equality.findall("joint"):
            a, b = el.get("joint1"), el.get("joint2")
            if el.get("active", "true").lower() == "false" or not a or not b:
                continue
            edges.setdefault(a, set()).add(b)
            edges.setdefault(b, set()).add(a)
    seen, stack = set(joints), list(joints)
    while stack:
        for other in edges.get(stack.pop(), ()):
            if other not in seen:
                seen.add(other)
                stack.append(other)
    return seen


def _build_tree(path: Path, root: ET.Element, rewritten: bool = False) -> pin.Model:
    """Pinocchio's tree of the file, with the children of ``<worldbody>`` wrapped in one
    body when Pinocchio would drop some (several bodies, or sites on the world); from a
    temporary copy of ``root`` when it was ``rewritten`` (includes inlined) or wrapped."""
    world = root.find("worldbody")
    children = list(world)
    needs_wrap = sum(c.tag == "body" for c in children) > 1 or any(
        c.tag in ("site", "frame") for c in children)
    if not needs_wrap and not rewritten:
        return _pinocchio_model(str(path), str(path))
    wrapper = ET.Element("body", {"name": WORLD_BODY})
    if needs_wrap:
        for c in children:
            world.remove(c)
            wrapper.append(c)
        world.append(wrapper)
    with tempfile.TemporaryDirectory() as folder:
        copy = Path(folder) / path.name
        ET.ElementTree(root).write(copy)
        model = _pinocchio_model(str(copy), str(path))
    if needs_wrap:
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


def _limits_in_qpos(tree: pin.Model, qpos0: np.ndarray) -> None:
    """Shift the finite position limits of every one-coordinate joint by its ``qpos0``
    (its ``ref``), in place. MuJoCo's ``range`` bounds ``qpos``; Pinocchio 4.1 places
    the body so that its ``q`` is ``qpos`` (the body at its ``pos`` when ``q = ref``) but
    stores ``range − ref`` as the limits."""
    lower, upper = tree.lowerPositionLimit.copy(), tree.upperPositionLimit.copy()
    for j in range(1, tree.njoints):
        joint = tree.joints[j]
        i = joint.idx_q
        if joint.nq != 1 or joint.nv != 1 or qpos0[i] == 0.0:
            continue
        for limits in (lower, upper):
            if abs(limits[i]) < 1e300:  # Pinocchio's "no limit" is the largest float
                limits[i] += qpos0[i]
    tree.lowerPositionLimit, tree.upperPositionLimit = lower, upper


def _pinocchio_model(filename: str, label: str) -> pin.Model:
    with _captured_stderr():
        try:
            return pin.buildModelFromMJCF(filename)
        except Exception as e:  # Pinocchio raises RuntimeError/ValueError with C++ text
            hint = ("" if "unordered_map::at" not in str(e) else
                    " (a name it looked up is not defined: most often a class= that no "
                    "<default class=...> defines, or a mesh, material or texture not in "
                    "<asset>; check the names the file refers to)")
            raise ClosureFileError(label, "", f"Pinocchio cannot build a model: {e}{hint}"
                                   ) from e


# -------------------------------------------------------------------------- closures
def _closures(label: str, root: ET.Element, tree: pin.Model, q: np.ndarray,
              renamed: dict) -> tuple[tuple, tuple[str, ...]]:
    """One :class:`Closure` per active ``connect`` / ``weld`` / ``joint`` of
    ``<equality>``, and a note per inactive one (``active="false"``: skipped)."""
    data = tree.createData()
    pin.framesForwardKinematics(tree, data, q)
    out, notes, counts = [], [], {}
    composites = _composites(root, tree)
    for equality in root.findall("equality"):
        for el in equality:
            i = counts[el.tag] = counts.get(el.tag, -1) + 1
            where = f"equality/{el.tag}[{i}]" + (f" {_cut(el.get('name'))}" if el.get("name")
                                                 else "")
            if el.tag in _NOT_CLOSURES:
                raise ClosureFileError(label, where, f"{_NOT_CLOSURES[el.tag]}; pkm_pin reads "
                                       "<connect>, <weld> and linear <joint> equalities: "
                                       "remove it")
            if el.tag not in ("connect", "weld", "joint"):
                raise ClosureFileError(label, where, "unknown equality element")
            if el.get("active", "true") == "false":
                notes.append(f"{where[len('equality/'):]} is inactive in the file "
                             "(active=\"false\"): ignored")
                continue
            name = el.get("name") or f"{el.tag}{i}"
            if el.tag == "joint":
                out.append(_coupling(label, where, el, name, tree, q, composites))
            else:
                out.append(_closure(label, where, el, name, tree, data, renamed))
    return tuple(out), tuple(notes)


#: MuJoCo's default ``polycoef`` of a ``<joint>`` equality (``q1 = q2``).
_POLYCOEF = (0.0, 1.0, 0.0, 0.0, 0.0)


def _coupling(label: str, where: str, el: ET.Element, name: str, tree: pin.Model,
              q: np.ndarray, composites: dict | None = None) -> Closure:
    """The coupling closure of one ``<joint>`` equality. MuJoCo's meaning: ``y − y₀ =
    c₀ + c₁ (x − x₀) + … + c₄ (x − x₀)⁴``, ``y`` joint1, ``x`` joint2, ``y₀``, ``x₀``
    their ``qpos0`` (without joint2, ``y − y₀ = c₀``); linear (``c₂ = c₃ = c₄ = 0``),
    it is ``y = (c₀ + y₀ − c₁ x₀) + c₁ x``."""
    text = el.get("polycoef")
    try:
        given = [float(t) for t in text.split()] if text is not None else []
    except ValueError as e:
        raise ClosureFileError(label, f"{where} polycoef", f"must be numbers, got "
                               f"{_cut(text)}") from e
    if len(given) > 5 or not np.all(np.abs(given) <= MAX_COORDINATE):
        raise ClosureFileError(label, f"{where} polycoef", f"must be at most 5 finite "
                               f"numbers, got {_cut(text)}")
    coef = np.array(given + list(_POLYCOEF[len(given):]))
    j1 = _coupled_joint(label, f"{where} joint1", el.get("joint1"), tree, composites)
    j2 = _coupled_joint(label, f"{where} joint2", el.get("joint2"), tree, composites) \
        if el.get("joint2") is not None else 0
    if j2 and np.any(coef[2:] != 0):
        degree = int(np.flatnonzero(coef)[-1])
        raise ClosureFileError(label, where, f"couples {_cut(tree.names[j1])} to "
                               f"{_cut(tree.names[j2])} by a polynomial of degree {degree} "
                               f"(polycoef {_cut(text)}); pkm_pin reads linear couplings "
                               "only (c2 = c3 = c4 = 0): a gear ratio, not a cam")
    y0 = q[tree.joints[j1].idx_q]
    c1 = float(coef[1]) if j2 else 0.0
    x0 = q[tree.joints[j2].idx_q] if j2 else 0.0
    return Closure("coupling", _joint_frame(tree, j1), _joint_frame(tree, j2),
                   name=name, coef=(float(coef[0] + y0 - c1 * x0), c1))


def _coupled_joint(label: str, where: str, joint: str | None, tree: pin.Model,
                   composites: dict | None = None) -> int:
    """The tree's joint ``joint`` of a ``<joint>`` equality: one coordinate (hinge or
    slide). ``composites``: :func:`_composites`."""
    if joint is None:
        raise ClosureFileError(label, where, "is missing")
    single = [tree.names[j] for j in range(1, tree.njoints)
              if tree.joints[j].nq == 1 and tree.joints[j].nv == 1]
    if joint not in single:
        raise ClosureFileError(label, where, _composite_words(composites or {}, joint) or (
            f"{_cut(joint)} is not a hinge or slide joint of Pinocchio's model; such "
            f"joints: {_listing(single)}"))
    return tree.getJointId(joint)


def _composites(root: ET.Element, tree: pin.Model) -> dict:
    """``{joint: composite}``: the file's joints that Pinocchio's MJCF parser merged
    into a composite joint (the joints of one body with several, MuJoCo's way of writing
    a rolling contact or a planar base), with the composite's name in the tree
    (``Composite_`` + the body's first joint)."""
    out = {}
    for body in root.iter("body"):
        names = [j.get("name") for j in body.findall("joint") if j.get("name")]
        if len(names) > 1 and tree.existJointName(f"Composite_{names[0]}"):
            out.update({n: f"Composite_{names[0]}" for n in names})
    return out


def _composite_words(composites: dict, joint: str) -> str:
    """Why ``joint`` of the file is no joint of the tree when it was merged into a
    composite joint (:func:`_composites`), with the fix; ``""`` otherwise."""
    if joint not in composites:
        return ""
    return (f"{_cut(joint)} is one of several joints of one body, which Pinocchio's MJCF "
            f"parser merges into one composite joint ({_cut(composites[joint])}): an "
            "actuator or a joint equality needs a joint of its own; give each of that "
            "body's joints its own body (massless ones nested in order, the last with the "
            "geometry)")


def _joint_frame(tree: pin.Model, j: int) -> str:
    """The name of joint ``j``'s frame (renamed or not; the universe's for 0)."""
    if j == 0:
        return tree.frames[0].name
    return next(f.name for f in tree.frames
                if f.parentJoint == j and f.type == pin.FrameType.JOINT)


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
        raise ClosureFileError(label, where, f"{_cut(name)} is not a {what} of the model; its "
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
                               f"{_cut(text)}") from e
    if values.shape != (n,) or not np.isfinite(values).all():
        raise ClosureFileError(label, f"{where} {key}", f"must be {n} finite numbers, got "
                               f"{_cut(text)}")
    return values


# ------------------------------------------------------------------ motors and output
#: Actuator transmissions other than joints and tendons, refused by name.
_TRANSMISSIONS = {"site": "a site (a force or moment at a point)",
                  "body": "a body (adhesion)",
                  "cranksite": "a slider-crank", "slidersite": "a slider-crank",
                  "refsite": "a site"}


def _actuated(label: str, root: ET.Element, tree: pin.Model, closures: tuple
              ) -> tuple[tuple[str, ...], tuple, tuple[str, ...]]:
    """The joints of the ``<actuator>`` elements, in file order, each actuator's (name,
    or its element, and joint), and notes on actuators through tendons. A ``joint=``
    (or ``jointinparent=``) actuator drives that joint; a ``tendon=`` actuator on a
    fixed tendon drives the joint its length moves with (:func:`_tendon_joint`)."""
    movable = [tree.names[j] for j in range(1, tree.njoints) if tree.joints[j].nv > 0]
    tendons = _tendons(root)
    out, matches, notes = [], [], []
    for actuators in root.findall("actuator"):
        for i, el in enumerate(actuators):
            where = f"actuator/{el.tag}[{i}]" + (f" {_cut(el.get('name'))}" if el.get("name")
                                                 else "")
            joint = el.get("joint", el.get("jointinparent"))
            if joint is None and el.get("tendon") is not None:
                joint, note = _tendon_joint(label, where, el.get("tendon"), tendons, tree,
                                            closures)
                notes.append(note)
            if joint is None:
                how = next((_TRANSMISSIONS[k] for k in _TRANSMISSIONS if el.get(k)), None)
                raise ClosureFileError(label, where, f"drives {how or 'no joint'}; pkm_pin "
                                       "reads actuators on joints and on fixed tendons")
            if joint not in movable:
                raise ClosureFileError(label, where, _composite_words(
                    _composites(root, tree), joint) or (
                    f"joint {_cut(joint)} is not a joint of Pinocchio's model; joints: "
                    f"{_listing(movable)}"))
            matches.append((el.get("name") or f"actuator/{el.tag}[{i}]", (joint,)))
            if joint not in out:
                out.append(joint)
    return tuple(out), tuple(matches), tuple(notes)


def _tendons(root: ET.Element) -> dict:
    """``{name: ("fixed", ((joint, coef), ...)) or ("spatial", ())}`` of ``<tendon>``."""
    out: dict = {}
    for section in root.findall("tendon"):
        for el in section:
            if el.get("name") is None:
                continue
            joints = tuple((j.get("joint"), j.get("coef", "1")) for j in el.findall("joint"))
            out[el.get("name")] = (el.tag, joints if el.tag == "fixed" else ())
    return out


def _tendon_joint(label: str, where: str, tendon: str, tendons: dict, tree: pin.Model,
                  closures: tuple) -> tuple[str, str]:
    """The joint an actuator on the fixed tendon ``tendon`` drives, and a note saying so.

    The tendon's length is ``Σ cᵢ qᵢ``. One joint: that joint (the actuated coordinate
    is the joint's; the tendon's length is ``c q``). Several: where the file's linear
    joint couplings make every one of them move with one of them, ``q``, (``q̇ᵢ = rᵢ
    q̇``), the length moves as ``(Σ cᵢ rᵢ) q̇`` and that joint, the first in the tendon
    that works, is the actuated one; otherwise (independent joints: a differential) it is
    refused, since pkm_pin's actuated coordinates are joints, one velocity each.
    """
    kind, joints = tendons.get(tendon, (None, ()))
    if kind is None:
        raise ClosureFileError(label, f"{where} tendon", f"{_cut(tendon)} is not a tendon "
                               f"of the file; its tendons: {_listing(sorted(tendons))}")
    if kind != "fixed":
        raise ClosureFileError(label, where, f"drives the {kind} tendon {_cut(tendon)} (a "
                               "cable routed through sites, its length a function of the "
                               "bodies' poses); pkm_pin reads actuators on joints and on "
                               "fixed tendons")
    try:
        terms = [(j, float(c)) for j, c in joints]
    except ValueError as e:
        raise ClosureFileError(label, f"tendon {_cut(tendon)}", "a coef is not a "
                               "number") from e
    terms = [(j, c) for j, c in terms if c != 0.0]
    if not terms or any(j is None for j, _ in terms):
        raise ClosureFileError(label, f"tendon {_cut(tendon)}", "has no joint with a "
                               "non-zero coef (or a <joint> without joint=)")
    length = " ".join(f"{'−' if c < 0 else '+'} {abs(c):g}·{j}" for j, c in terms
                      ).removeprefix("+ ")
    for joint, _ in terms:
        rates = {joint: 1.0} if len(terms) == 1 else _coupled_rates(tree, closures, joint)
        if all(j in rates for j, _ in terms):
            k = sum(c * rates[j] for j, c in terms)
            if abs(k) <= 1e-12 * max(abs(c) for _, c in terms):
                raise ClosureFileError(label, where, f"drives fixed tendon {_cut(tendon)} "
                                       f"whose length {_cut(length)[1:-1]} does not change "
                                       "on the file's joint couplings: it moves nothing; "
                                       "check the coefs' signs")
            moves = "" if len(terms) == 1 else (
                f"; on the joint couplings it moves as {k:g}·{joint}")
            return joint, (f"{where[len('actuator/'):]} drives fixed tendon {tendon} "
                           f"(length {length}{moves}): {joint} is its actuated joint")
    raise ClosureFileError(label, where, f"drives fixed tendon {_cut(tendon)} (length "
                           f"{_cut(length)[1:-1]}) over joints that no linear <joint> "
                           "equality ties to one of them, a differential of several "
                           "independent joints; pkm_pin's actuated coordinates are joints "
                           "(one velocity each): actuate one joint, or couple them with "
                           "<joint> equalities")


def _coupled_rates(tree: pin.Model, closures: tuple, joint: str) -> dict:
    """``{joint name: rᵢ}``: the joints the coupling closures tie to ``joint`` (itself
    included, r = 1), with their rates per unit rate of ``joint`` (a graph walk over
    the couplings, each ``q_a = c₀ + c₁ q_b`` both ways, ``c₁ ≠ 0`` to go from a to b)."""
    if not tree.existJointName(joint):
        return {}
    edges: dict = {}
    for c in closures:
        if c.kind != "coupling":
            continue
        a, b = (tree.names[tree.frames[tree.getFrameId(f)].parentJoint]
                for f in (c.frame_a, c.frame_b))
        if b == tree.names[0]:
            edges.setdefault(a, []).append((None, 0.0))
            continue
        edges.setdefault(b, []).append((a, c.coef[1]))  # q̇_a = c₁ q̇_b
        if c.coef[1] != 0.0:
            edges.setdefault(a, []).append((b, 1.0 / c.coef[1]))
    rates, stack = {joint: 1.0}, [joint]
    while stack:
        j = stack.pop()
        for other, r in edges.get(j, ()):
            if other is not None and other not in rates:
                rates[other] = rates[j] * r
                stack.append(other)
    return rates


#: The ``<custom><text name=...>`` whose ``data`` names the output frame of an MJCF file.
OUTPUT_KEY = "pkm_pin:output"


def _named_output(root: ET.Element) -> str | None:
    """The output frame the file names, ``<custom><text name="pkm_pin:output"
    data="FRAME"/></custom>`` (MuJoCo's element for user text; in the file or a file it
    includes), or None."""
    for text in root.iter("text"):
        if text.get("name") == OUTPUT_KEY and text.get("data"):
            return text.get("data").strip()
    return None


def _output_frame(tree: pin.Model) -> str:
    """A body named ``effector``, else the last body of the tree."""
    bodies = [f.name for f in tree.frames if f.type == pin.FrameType.BODY
              and f.name != WORLD_BODY]
    if "effector" in bodies:
        return "effector"
    return bodies[-1] if bodies else tree.frames[0].name
