"""Extended URDF: a URDF tree plus a closures file, as in Gepetto's example-parallel-robots.

A closed-loop robot of Gepetto's ``example-parallel-robots`` is a folder with
``robot.urdf`` (the loops cut open: a spanning tree) and ``robot.yaml``::

    closed_loop: [['closedloop1_A', 'closedloop1_B']]   # pairs of frame names
    type: ['6d']                                         # one per pair: 3d/3D or 6d/6D
    name_mot: ['mot1', 'mot2']                           # actuated joints
    joint_name: ['spherical_1']                          # optional: joints to replace,
    joint_type: ['SPHERICAL']                            #   and by what

:func:`read_extended_urdf` turns the pair into a :class:`~pkm_pin.model.ClosureModel`,
following the toolbox's loader (``completeRobotLoader`` in
``example_parallel_robots/loader_tools.py`` and ``ActuationModel`` in
``actuation_model.py``) so that its models load unchanged:

* The URDF is read by Pinocchio's parser with ``<mimic>`` ignored (every joint is its own
  coordinate, as ``RobotWrapper.BuildFromURDF`` does); ``free_flyer=True`` puts a
  free-flyer joint ``root_joint`` under the root link, as the toolbox's ``freeflyer``.
* ``joint_type`` replaces the joint of the same name, at the same placement:
  ``SPHERICAL`` by a spherical joint; ``UJOINT_XY`` (``_YZ``, ``_ZX``; ``CARDAN`` is the
  older ``UJOINT_XY``) by a revolute about the first axis named ``<joint>_X`` followed by
  one about the second named ``<joint>_Y``, which carries the joint's body and frames (any
  two distinct axes are accepted, e.g. ``UJOINT_ZY``); ``FIXED`` locks the joint at
  ``q = 0`` (its frames stay). Children of a replaced universal joint hang on its second
  revolute (the toolbox loses them).
* A file **without a** ``joint_name`` **list** (the key absent or null) follows the
  convention of the toolbox's ``generateYAML``, which writes every joint whose name
  contains ``spherical`` into ``joint_name`` as ``SPHERICAL``: such revolutes are read as
  spherical joints, with a note (:attr:`ClosureModel.notes`); ``joint_name: []`` keeps
  them revolute. (The toolbox's loader converts only what ``joint_name`` lists; Gepetto's
  ``kangaroo_like_2legs`` names 26 ball joints so and assembles only so.) A revolute
  still named like a spherical joint (``sherical_4bar``) and a frame pair of the URDF
  numbered like the file's closure pairs that ``closed_loop`` leaves out (``generateYAML``
  drops loop N when another loop's number starts with N's digits) get a note too; the
  message of a failed assembly ends with the notes.
* Each ``closed_loop`` pair ``[A, B]`` closes frame ``A`` (joint, link or fixed-joint frame:
  Pinocchio's first frame of that name) on frame ``B`` at their own placements: ``3d``/``3D``
  a point closure, ``6d``/``6D`` a weld; the closure is named ``A + "C" + B``.
* ``name_mot`` entries match every movable joint whose name *contains* them (the toolbox's
  ``motname in name``), in the tree's joint order: that is the actuated order. An entry
  equal to a joint's name picks that joint alone; the empty entry, an entry that picks
  nothing and a joint picked by two entries are errors. What each entry picked is
  :attr:`ClosureModel.actuator_matches`.

The YAML is read within bounds (``docs/reliability.md``): at most
:data:`MAX_CLOSURES_BYTES`, no anchors or aliases, no duplicate keys, nesting at most
:data:`MAX_YAML_DEPTH`, at most :data:`MAX_YAML_NODES` values; every value is
type-checked before use and echoed cut to 300 characters.

Deliberate differences: a closure type other than 3d/6d, lists of different lengths, a
frame, joint or motor name that matches nothing are errors (the toolbox falls back to 6D,
truncates, or fails later); keys other than those listed here are errors (typos); the
toolbox's ``simplifyModel`` (three massless revolutes with concurrent axes merged into a
spherical joint) is not applied: the tree keeps the URDF's joints (the same motions);
the URDF's joint limits are kept (the toolbox rebuilds every joint with
``Model.addJoint`` without limits, so its models have none).

Two keys of our own (the toolbox ignores extra keys, so such files still load there):
``output``, the output frame, and ``output_point`` (``true``/``false``, default
``false``): ``true`` analyses the output frame's **origin as a point**
(:attr:`ClosureModel.output_point`: only its translations, e.g. the pin where a five-bar's
distal links meet: motion type ``2T``), ``false`` the frame as a body (translations and
rotations). ``load_mechanism(..., point=)`` overrides it. The same keys are accepted in a
TOML file. ``reference`` is ``q = 0`` of the tree (``pinocchio.neutral``): published
models are usually not closed there (ours in ``models/loops/`` are). The output frame is
``output=`` if given, else the file's ``output``, else a frame named ``effector`` (the
toolbox's robots name their end-effector link so), else the last link (body frame) of the
tree that no closure uses; ``output_point`` applies to whichever frame that is.
"""

from __future__ import annotations

import os
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ClosureFileError, UrdfError, _clip, _cut, _is_file, _listing
from ..urdf import (
    MAX_LINKS,
    LimitExceeded,
    _captured_stderr,
    free_range,
    joints_without_range,
    read,
    read_bounded,
)
from .closure_model import Closure, ClosureModel

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

#: Closure types of the closures file and the :class:`Closure` kind they give.
CLOSURE_TYPES = {"3d": "point", "3D": "point", "6d": "weld", "6D": "weld"}

#: Joint replacements of ``joint_type`` (``UJOINT_`` + two distinct axes of XYZ as well).
JOINT_TYPES = ("SPHERICAL", "FIXED", "CARDAN", "UJOINT_XY", "UJOINT_YZ", "UJOINT_ZX")

#: Keys of a closures file: required, then optional.
REQUIRED_KEYS = ("closed_loop", "type", "name_mot")
OPTIONAL_KEYS = ("joint_name", "joint_type", "output", "output_point")

#: Largest closures file read [bytes]: Gepetto's are under 1 kB; refused before parsing.
MAX_CLOSURES_BYTES = 1_000_000
#: Deepest nesting of YAML lists and mappings (the format needs 3: mapping, list, pair).
MAX_YAML_DEPTH = 16
#: Most YAML nodes (scalars, lists, mappings) in a closures file. Anchors and aliases
#: are refused, so a file's nodes are at most its events and this bounds memory.
MAX_YAML_NODES = 100_000

_REVOLUTE = {"X": pin.JointModelRX, "Y": pin.JointModelRY, "Z": pin.JointModelRZ}

#: Gepetto's ``generateYAML`` (``name_spherical``): the joints whose name contains this
#: are to be spherical joints, and it writes them into ``joint_name`` as ``SPHERICAL``.
SPHERICAL_NAME = "spherical"
#: A revolute named like a spherical joint, misspellings included (``sherical_4bar``).
_SPHERICAL_LIKE = re.compile(r"sp?herical", re.IGNORECASE)


@dataclass(frozen=True)
class ClosureSpec:
    """The validated content of a closures file (names only; nothing checked against a URDF).

    Attributes:
        path: The file.
        closed_loop: Pairs of frame names.
        types: One closure type per pair (``"3d"``, ``"6D"`` …).
        name_mot: Actuated joint names (or parts of names).
        joint_name: Joints to replace.
        joint_type: What replaces each (``"SPHERICAL"``, ``"UJOINT_XY"``, ``"FIXED"`` …).
        output: The output frame, or None.
        output_point: Whether the output is the output frame's origin as a point.
        joint_name_given: Whether the file has a ``joint_name`` list (``[]`` included);
            without one, the revolutes named ``*spherical*`` are spherical joints
            (:data:`SPHERICAL_NAME`).
    """

    path: str
    closed_loop: tuple[tuple[str, str], ...]
    types: tuple[str, ...]
    name_mot: tuple[str, ...]
    joint_name: tuple[str, ...] = ()
    joint_type: tuple[str, ...] = ()
    output: str | None = None
    output_point: bool = False
    joint_name_given: bool = False


# --------------------------------------------------------------------------- entry point
def read_extended_urdf(urdf_path: str | os.PathLike, closures_path: str | os.PathLike | None
                       = None, *, output: str | None = None,
                       free_flyer: bool = False) -> ClosureModel:
    """The closure model of a URDF and its closures file (module docstring).

    Args:
        urdf_path: The URDF file.
        closures_path: The closures file (YAML, or TOML by its ``.toml`` suffix); default:
            :func:`find_closures_file`; ``"none"`` (:data:`NO_CLOSURES`): the URDF's tree
            without closures, every movable joint actuated.
        output: Output frame (overrides the file's ``output`` and the default).
        free_flyer: Put a free-flyer joint ``root_joint`` under the root link.

    Raises:
        ClosureFileError: a missing or wrong file; the message names the file, the entry
            and how to fix it.
    """
    urdf = Path(urdf_path)
    if closures_path is not None and str(closures_path) == NO_CLOSURES:
        return _read_tree(urdf, output, free_flyer)
    path = Path(closures_path) if closures_path is not None else find_closures_file(urdf)
    spec = read_closures_file(path)
    tree, notes = _build_tree(urdf, spec, free_flyer)
    closures = _closures(tree, spec)
    out = output if output is not None else _output_frame(tree, spec)
    actuated, matches = _actuated(tree, spec)
    return ClosureModel(tree, closures, actuated, out, name=tree.name,
                        output_point=spec.output_point, actuator_matches=matches,
                        output_named=output is not None or spec.output is not None,
                        notes=notes + _unused_pair_notes(tree, spec))


def find_closures_file(urdf_path: str | os.PathLike) -> Path:
    """The closures file of ``urdf_path``: the same stem with ``.yaml``, ``.yml`` or
    ``.toml``, else ``robot.yaml`` in the same folder (the toolbox's name)."""
    urdf = Path(urdf_path)
    found = _closures_file_beside(urdf)
    if found is None:
        raise ClosureFileError(_clip(str(urdf)), "", "no closures file beside it (looked for "
                               + ", ".join(_clip(c.name, 80) for c in _candidates(urdf))
                               + "); write one, name it with --closures FILE "
                               "(closures= in Python), or give --closures none to read "
                               "the URDF as a tree without closures (a serial arm)")
    return found


def _candidates(urdf: Path) -> list[Path]:
    """Where :func:`find_closures_file` looks, in order (each path once)."""
    out = [urdf.with_suffix(s) for s in (".yaml", ".yml", ".toml")]
    return out + [p for p in [urdf.parent / "robot.yaml"] if p not in out]


def _closures_file_beside(urdf: Path) -> Path | None:
    """The first of :func:`_candidates` that is a file, or ``None``."""
    return next((c for c in _candidates(urdf) if _is_file(c)), None)


#: The closures "file" that reads a URDF as a tree without closures (``--closures
#: none``): a serial arm, a hand, a legged robot's tree.
NO_CLOSURES = "none"


def _read_tree(urdf: Path, output: str | None, free_flyer: bool) -> ClosureModel:
    """A URDF read without closures (:data:`NO_CLOSURES`): its tree, ``<mimic>`` joints
    following their joint, every other movable joint actuated (a serial arm, a hand, a
    legged robot's tree), with a note saying so."""
    label = _clip(str(urdf))
    tree, notes = _build_tree(urdf, ClosureSpec(label, (), (), (), joint_name_given=True),
                              free_flyer, mimic=True)
    movable = tuple(tree.names[j] for j in range(1, tree.njoints) if tree.joints[j].nv > 0)
    spec = ClosureSpec(label, (), (), movable, joint_name_given=True)
    out = output if output is not None else _output_frame(tree, spec)
    actuated, matches = _actuated(tree, spec)
    note = ("--closures none: read as a tree without closures, every movable joint "
            "actuated (a <mimic> joint follows its joint); a closures file (closed_loop, "
            "type, name_mot; --closures FILE) closes loops and chooses the actuated joints")
    reference, moved = _inside_limits(tree)
    if moved:
        note += (f"; the reference configuration has {', '.join(moved[:6])}"
                 f"{' …' if len(moved) > 6 else ''} at the middle of its range (0 is "
                 "outside it)")
    return ClosureModel(tree, (), actuated, out, name=tree.name, actuator_matches=matches,
                        output_named=output is not None, notes=notes + (note,),
                        reference=reference)


def _inside_limits(tree: pin.Model) -> tuple[np.ndarray, list[str]]:
    """Pinocchio's neutral configuration with each one-coordinate joint whose neutral
    value lies outside its finite limits (Franka Panda's joint 4: [−3.07, −0.07]) moved
    to the middle of its range, and the names of those joints."""
    q = pin.neutral(tree)
    lo, up = tree.lowerPositionLimit, tree.upperPositionLimit
    moved = []
    for j in range(1, tree.njoints):
        joint = tree.joints[j]
        i = joint.idx_q
        if joint.nq == 1 and abs(lo[i]) < 1e300 and abs(up[i]) < 1e300 and lo[i] <= up[i] \
                and not lo[i] <= q[i] <= up[i]:
            q[i] = 0.5 * (lo[i] + up[i])
            moved.append(tree.names[j])
    return q, moved


# ----------------------------------------------------------------------- closures file
def read_closures_file(path: str | os.PathLike) -> ClosureSpec:
    """Read and check a closures file (YAML, or TOML by suffix) without its URDF."""
    path = Path(path)
    label = _clip(str(path))
    if not _is_file(path):
        raise ClosureFileError(label, "", "no such closures file; check the path")
    try:
        text = read_bounded(path, MAX_CLOSURES_BYTES, "closures file")
    except LimitExceeded as e:
        raise ClosureFileError(label, "", e.reason + " (a closures file is a few lines)"
                               ) from e
    except (OSError, UnicodeDecodeError) as e:
        raise ClosureFileError(label, "", f"cannot be read: {e}") from e
    content = _parse(text, label, toml=path.suffix.lower() == ".toml")
    if not isinstance(content, dict):
        raise ClosureFileError(label, "", "must be a mapping with the keys "
                               f"{list(REQUIRED_KEYS)} (optional: {list(OPTIONAL_KEYS)})")
    for key in content:
        if not isinstance(key, str):
            raise ClosureFileError(label, _cut(key), "a key must be a name; the keys are "
                                   f"{list(REQUIRED_KEYS + OPTIONAL_KEYS)}")
    unknown = sorted(set(content) - set(REQUIRED_KEYS) - set(OPTIONAL_KEYS))
    if unknown:
        raise ClosureFileError(label, _cut(unknown[0])[1:-1], "unknown key; the keys are "
                               f"{list(REQUIRED_KEYS + OPTIONAL_KEYS)}")
    for key in REQUIRED_KEYS:
        if key not in content:
            raise ClosureFileError(label, key, "is missing (give [] when there is none)")
    loops = tuple(_pair(p, label, f"closed_loop[{i}]")
                  for i, p in enumerate(_names(content, "closed_loop", label, str_items=False)))
    types = _names(content, "type", label)
    _same_length(label, "closed_loop", loops, "type", types)
    for i, t in enumerate(types):
        if t not in CLOSURE_TYPES:
            raise ClosureFileError(label, f"type[{i}]", f"unknown closure type {_cut(t)}; use "
                                   "'3d' (point contact) or '6d' (weld)")
    names, kinds = _names(content, "joint_name", label), _names(content, "joint_type", label)
    _same_length(label, "joint_name", names, "joint_type", kinds)
    for i, k in enumerate(kinds):
        if _ujoint_axes(k) is None and k not in JOINT_TYPES:
            raise ClosureFileError(label, f"joint_type[{i}]", f"unknown joint type {_cut(k)}; "
                                   f"use one of {list(JOINT_TYPES)} or UJOINT_ + two axes")
    output = content.get("output")
    if output is not None and not isinstance(output, str):
        raise ClosureFileError(label, "output", f"must be a frame name, got {_cut(output)}")
    point = content.get("output_point", False)
    if not isinstance(point, bool):
        raise ClosureFileError(label, "output_point", f"must be true or false, got "
                               f"{_cut(point)}")
    return ClosureSpec(label, loops, types, _names(content, "name_mot", label), names, kinds,
                       output, point, content.get("joint_name") is not None)


def _parse(text: str, label: str, toml: bool):
    """The file's content as Python objects, or a :class:`ClosureFileError`."""
    if toml:
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise ClosureFileError(label, "", f"not valid TOML: {_cut(str(e))[1:-1]}") from e
        except RecursionError as e:  # tomllib recurses once per nested array or table
            raise ClosureFileError(label, "", "not valid TOML: arrays or tables nested too "
                                   "deep; a closures file nests 2 deep") from e
    import yaml

    try:
        _check_yaml_events(text, label)
        return yaml.load(text, Loader=_closures_loader())
    except _DuplicateKey as e:
        raise ClosureFileError(label, e.key, f"line {e.line}: duplicate key (first given at "
                               f"line {e.first}); give each key once") from e
    except yaml.YAMLError as e:
        where = getattr(e, "problem_mark", None)
        at = f" at line {where.line + 1}, column {where.column + 1}" if where else ""
        problem = getattr(e, "problem", None) or str(e).splitlines()[0]
        raise ClosureFileError(label, "", f"not valid YAML{at}: {_cut(problem)[1:-1]}") from e


class _DuplicateKey(Exception):
    def __init__(self, key: str, line: int, first: int):
        self.key, self.line, self.first = key, line, first
        super().__init__(key)


def _check_yaml_events(text: str, label: str) -> None:
    """Stream the YAML events of ``text`` (libyaml when installed; nothing is built) and
    refuse anchors and aliases (an Extended URDF sidecar needs none; nested aliases
    expand exponentially: 544 bytes give 9⁹ nodes), nesting deeper than
    :data:`MAX_YAML_DEPTH` and more than :data:`MAX_YAML_NODES` nodes."""
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    depth = nodes = 0
    for event in yaml.parse(text, Loader=loader):
        if not isinstance(event, yaml.NodeEvent):
            if isinstance(event, yaml.CollectionEndEvent):
                depth -= 1
            continue
        line = event.start_mark.line + 1 if event.start_mark is not None else "?"
        if isinstance(event, yaml.AliasEvent) or event.anchor is not None:
            sign = "*" if isinstance(event, yaml.AliasEvent) else "&"
            raise ClosureFileError(label, "", f"line {line}: YAML anchor or alias "
                                   f"{sign}{_cut(event.anchor)[1:-1]}; a closures file "
                                   "needs none: write the values out")
        nodes += 1
        if nodes > MAX_YAML_NODES:
            raise ClosureFileError(label, "", f"line {line}: more than {MAX_YAML_NODES} YAML "
                                   "values; a closures file has a few")
        if isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > MAX_YAML_DEPTH:
                raise ClosureFileError(label, "", f"line {line}: lists or mappings nested "
                                       f"more than {MAX_YAML_DEPTH} deep")


_LOADER = None


def _closures_loader():
    """PyYAML's safe loader (libyaml's when installed) refusing duplicate keys."""
    global _LOADER
    if _LOADER is None:
        import yaml

        base = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

        class ClosuresLoader(base):  # type: ignore[misc, valid-type]
            def construct_mapping(self, node, deep=False):
                self.flatten_mapping(node)
                first: dict = {}
                for key_node, _ in node.value:
                    key = self.construct_object(key_node, deep=deep)
                    line = key_node.start_mark.line + 1
                    try:
                        tagged = (type(key).__name__, key)  # 1 and true are two keys
                        if tagged in first:
                            raise _DuplicateKey(_cut(key)[1:-1] if isinstance(key, str)
                                                else _cut(key), line, first[tagged])
                        first[tagged] = line
                    except TypeError:  # unhashable: the base class says so
                        break
                return super().construct_mapping(node, deep=deep)

        _LOADER = ClosuresLoader
    return _LOADER


def _names(content: dict, key: str, label: str, str_items: bool = True) -> tuple:
    """``content[key]`` as a tuple (missing or null: empty); items must be strings."""
    value = content.get(key)
    if value is None:
        return ()
    if not isinstance(value, list):
        raise ClosureFileError(label, key, f"must be a list, got {_cut(value)}")
    if len(value) > MAX_LINKS:
        raise ClosureFileError(label, key, f"has {len(value)} entries, more than the "
                               f"{MAX_LINKS} joints pkm_pin reads in a URDF")
    for i, item in enumerate(value):
        if str_items and not isinstance(item, str):
            raise ClosureFileError(label, f"{key}[{i}]", f"must be a name (string), got "
                                   f"{_cut(item)}")
    return tuple(value)


def _pair(value, label: str, where: str) -> tuple[str, str]:
    if not (isinstance(value, list) and len(value) == 2
            and all(isinstance(v, str) for v in value)):
        raise ClosureFileError(label, where, f"must be a pair [frameA, frameB] of frame "
                               f"names, got {_cut(value)}")
    return value[0], value[1]


def _same_length(label: str, key_a: str, a: tuple, key_b: str, b: tuple) -> None:
    if len(a) != len(b):
        raise ClosureFileError(label, key_b, f"has {len(b)} entries but {key_a} has {len(a)};"
                               f" give one {key_b} per {key_a} entry")


def _ujoint_axes(kind: str) -> str | None:
    """The two axes of a universal-joint type (``"XY"`` for ``UJOINT_XY`` and ``CARDAN``)."""
    if kind == "CARDAN":
        return "XY"
    axes = kind[len("UJOINT_"):] if kind.startswith("UJOINT_") else ""
    if len(axes) == 2 and set(axes) <= set("XYZ") and axes[0] != axes[1]:
        return axes
    return None


# -------------------------------------------------------------------------------- tree
def _build_tree(urdf: Path, spec: ClosureSpec, free_flyer: bool, mimic: bool = False
                ) -> tuple[pin.Model, tuple[str, ...]]:
    """Pinocchio's tree of the URDF (``<mimic>`` ignored, as the toolbox does, unless
    ``mimic``), joints replaced as ``spec`` says (or, without a ``joint_name`` list, the
    revolutes named ``*spherical*``), and the reader's notes about those joints."""
    try:
        src = read(urdf)
    except UrdfError as e:
        raise ClosureFileError(e.source, "URDF", e.reason + (f". {e.hint}" if e.hint else "")
                               ) from e
    with _captured_stderr():
        try:
            model = (pin.buildModelFromXML(src.xml, pin.JointModelFreeFlyer(), mimic=mimic)
                     if free_flyer else pin.buildModelFromXML(src.xml, mimic=mimic))
        except Exception as e:  # Pinocchio raises RuntimeError/ValueError with C++ text
            raise ClosureFileError(src.label, "URDF", f"Pinocchio cannot build it: {e}") from e
    free_range(model, joints_without_range(src))
    movable = [model.names[j] for j in range(1, model.njoints) if model.joints[j].nv > 0]
    for i, name in enumerate(spec.joint_name):
        if name not in movable:
            raise ClosureFileError(spec.path, f"joint_name[{i}]", f"{_cut(name)} is not a movable "
                                   f"joint of {src.label}; its joints: {_listing(movable)}")
    kinds, notes = _joint_kinds(model, spec)
    if kinds:
        model = _replace_joints(model, kinds)
    return model, notes


def _joint_kinds(model: pin.Model, spec: ClosureSpec) -> tuple[dict, tuple[str, ...]]:
    """The joints to replace (``joint_name``/``joint_type``; without a ``joint_name`` list,
    each revolute whose name contains :data:`SPHERICAL_NAME` becomes ``SPHERICAL``, the
    convention of Gepetto's ``generateYAML``) and a note for each rule applied or doubt."""
    kinds = dict(zip(spec.joint_name, spec.joint_type))
    revolutes = [model.names[j] for j in range(1, model.njoints)
                 if model.joints[j].nv == 1 and model.joints[j].shortname().startswith(
                     ("JointModelR", "JointModelRevolute"))]
    notes = []
    if not spec.joint_name_given:
        named = [n for n in revolutes if SPHERICAL_NAME in n]
        kinds.update({n: "SPHERICAL" for n in named})
        if named:
            notes.append(f"the revolutes named '*{SPHERICAL_NAME}*' ({len(named)}: "
                         f"{_listing(named)}) are read as spherical joints: the closures "
                         "file has no joint_name list, and Gepetto's generateYAML lists such "
                         "joints there as SPHERICAL (give joint_name: [] to keep them "
                         "revolute)")
    doubtful = [n for n in revolutes if n not in kinds and _SPHERICAL_LIKE.search(n)]
    if doubtful:
        notes.append(f"revolute joint{'s' if len(doubtful) > 1 else ''} "
                     f"{_listing(doubtful)} named like a spherical joint stay"
                     f"{'' if len(doubtful) > 1 else 's'} revolute; if the machine has a ball "
                     "joint there, list it in joint_name with joint_type SPHERICAL")
    return kinds, tuple(notes)


def _replace_joints(model: pin.Model, kinds: dict) -> pin.Model:
    """A copy of ``model`` with the joints named in ``kinds`` replaced (module docstring)."""
    new = pin.Model()
    new.name = model.name
    ids, locked = {0: 0}, []
    for j in range(1, model.njoints):
        parent, name = ids[model.parents[j]], model.names[j]
        kind, place = kinds.get(name), model.jointPlacements[j]
        axes = _ujoint_axes(kind) if kind else None
        if axes:
            first = new.addJoint(parent, _REVOLUTE[axes[0]](), place, f"{name}_{axes[0]}")
            jid = new.addJoint(first, _REVOLUTE[axes[1]](), pin.SE3.Identity(),
                               f"{name}_{axes[1]}")
        elif kind == "SPHERICAL":
            jid = new.addJoint(parent, pin.JointModelSpherical(), place, name)
        else:
            jid = new.addJoint(parent, model.joints[j], place, name, *_limits(model, j))
            if kind == "FIXED":
                locked.append(jid)
        new.appendBodyToJoint(jid, model.inertias[j], pin.SE3.Identity())
        ids[j] = jid
    for f in list(model.frames)[1:]:  # same order: the parent frame indices stay valid
        new.addFrame(pin.Frame(f.name, ids[f.parentJoint], f.parentFrame, f.placement, f.type,
                               f.inertia), False)
    return pin.buildReducedModel(new, locked, pin.neutral(new)) if locked else new


def _limits(model: pin.Model, j: int) -> tuple:
    """Effort, velocity and position limits of joint ``j`` (for ``Model.addJoint``)."""
    joint = model.joints[j]
    v = slice(joint.idx_v, joint.idx_v + joint.nv)
    q = slice(joint.idx_q, joint.idx_q + joint.nq)
    return (model.effortLimit[v], model.velocityLimit[v], model.lowerPositionLimit[q],
            model.upperPositionLimit[q])


# -------------------------------------------------------------------- closures, motors
def _closures(tree: pin.Model, spec: ClosureSpec) -> tuple[Closure, ...]:
    """One closure per ``closed_loop`` pair, at the frames' own placements."""
    frames = [f.name for f in tree.frames]
    for i, pair in enumerate(spec.closed_loop):
        for k, name in enumerate(pair):
            if not tree.existFrame(name):
                raise ClosureFileError(spec.path, f"closed_loop[{i}][{k}]", f"frame {_cut(name)} "
                                       f"is not in the URDF; its frames: {_listing(frames)}")
    return tuple(Closure(CLOSURE_TYPES[t], a, b, name=f"{a}C{b}")
                 for (a, b), t in zip(spec.closed_loop, spec.types))


def _unused_pair_notes(tree: pin.Model, spec: ClosureSpec) -> tuple[str, ...]:
    """A note naming the frame pairs of the URDF numbered like the file's closure pairs
    (``closedloop1_A``/``closedloop1_B`` beside ``closedloop0_A``/``closedloop0_B``)
    that ``closed_loop`` leaves out: Gepetto's ``generateYAML`` drops loop N whenever
    another loop's number starts with N's digits (``closedloop1`` also matches
    ``closedloop10``), so its YAML can miss loops the machine has."""
    names = {f.name for f in tree.frames}
    used = {n for pair in spec.closed_loop for n in pair}
    unused = []
    for a, b in spec.closed_loop:
        ma, mb = _NUMBERED.fullmatch(a), _NUMBERED.fullmatch(b)
        if not (ma and mb and ma[2] == mb[2]):
            continue
        pattern = re.compile(re.escape(ma[1]) + r"(\d+)" + re.escape(ma[3]))
        for name in sorted(names):
            m = pattern.fullmatch(name)
            other = m and mb[1] + m[1] + mb[3]
            if other and other in names and not {name, other} & used \
                    and {name, other} not in [set(u) for u in unused]:
                unused.append(tuple(sorted((name, other))))
    if not unused:
        return ()
    shown = ", ".join(f"{a}/{b}" for a, b in unused[:6])
    return (f"the URDF has closure frames named like the file's pairs that closed_loop "
            f"leaves out ({shown}{' …' if len(unused) > 6 else ''}): Gepetto's generateYAML "
            "drops loop N when another loop's number starts with N; add the pair if the "
            "machine closes that loop",)


#: A frame name with a number: (text before, the first number, text after).
_NUMBERED = re.compile(r"(\D*)(\d+)(.*)")


def _actuated(tree: pin.Model, spec: ClosureSpec) -> tuple[tuple[str, ...], tuple]:
    """The actuated joints (tree order) and what each ``name_mot`` entry picked.

    An entry equal to a movable joint's name picks that joint alone; any other picks
    every movable joint whose name contains it (the toolbox's ``motname in name``). The
    empty entry (a substring of every name), an entry picking nothing, and a joint picked
    by two entries are errors naming them."""
    movable = [tree.names[j] for j in range(1, tree.njoints) if tree.joints[j].nv > 0]
    matches, picked_by = [], {}
    for i, mot in enumerate(spec.name_mot):
        where = f"name_mot[{i}]"
        if not mot.strip():
            raise ClosureFileError(spec.path, where, f"the empty name {_cut(mot)} is part of "
                                   "every joint name; name the actuated joints")
        picked = (mot,) if mot in movable else tuple(n for n in movable if mot in n)
        if not picked:
            raise ClosureFileError(spec.path, where, f"{_cut(mot)} matches no movable joint "
                                   f"of the URDF; its joints: {_listing(movable)}")
        for joint in picked:
            if joint in picked_by:
                k, other = picked_by[joint]
                raise ClosureFileError(spec.path, where, f"{_cut(mot)} picks joint "
                                       f"{_cut(joint)}, which name_mot[{k}] {_cut(other)} "
                                       "picked already; name each actuated joint once (a "
                                       "name equal to a joint's picks that joint alone)")
            picked_by[joint] = (i, mot)
        matches.append((mot, picked))
    return tuple(n for n in movable if n in picked_by), tuple(matches)


def _output_frame(tree: pin.Model, spec: ClosureSpec) -> str:
    """The file's ``output``, else ``effector``, else the last body frame no closure uses."""
    if spec.output is not None:
        if not tree.existFrame(spec.output):
            raise ClosureFileError(spec.path, "output", f"frame {_cut(spec.output)} is not in the "
                                   f"URDF; its frames: {_listing(f.name for f in tree.frames)}")
        return spec.output
    if tree.existFrame("effector"):
        return "effector"
    used = {name for pair in spec.closed_loop for name in pair}
    bodies = [f.name for f in tree.frames if f.type == pin.FrameType.BODY and f.name not in used]
    return bodies[-1] if bodies else tree.frames[0].name
