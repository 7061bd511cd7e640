"""Reading mechanism files: TOML legs, Extended URDF, MJCF (one loader for every format).

:func:`load_mechanism` reads a file by its suffix and returns a
:class:`~pkm_pin.mechanism.Mechanism` (legs fixed to a platform: the per-leg screw
engine) or a :class:`~pkm_pin.linkage.Linkage` (the general elimination), or either for
any file with ``backend=``.

Mechanism files are TOML (read with the standard library)::

    name = "3-RPR (seed 000)"
    length_unit = "m"                               # optional: "mm" for a model in mm
    closure = "weld"                                # optional: legs at a pin, see below
    [[legs]]
    name = "A"
    urdf = "../urdf/rpr_leg_a.urdf"                 # relative to this file
    tip = "tip"                                     # link/frame fixed to the platform
    actuated = ["A1"]                               # joint names
    base = { xyz = [0, 0, 0], rpy = [0, 0, 0] }     # leg root in the world
    anchor = { xyz = [0, 0, 0], rpy = [0, 0, 0] }   # tip frame in the platform frame
    home_q = [0.0, 1.2, 0.3]                        # optional: leg configuration at home
    [home]                                          # a pose where the mechanism assembles
    xyz = [0.0, 0.0, 0.0]
    rpy = [0.0, 0.0, 0.0]

``home_q`` (optional) selects the working mode (e.g. elbow up/down) of each leg at home;
without it the leg's inverse kinematics starts from its neutral configuration.

``closure = "spherical"`` or ``"revolute"`` joins the legs' tips at a pin instead of a
platform (:mod:`pkm_pin.model.pinned`; no ``[home]``: ``home_q`` is where assembly
starts); ``load_mechanism`` then returns a :class:`~pkm_pin.linkage.Linkage`.
``length_unit`` only labels lengths in reports: nothing is converted.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin

from .assembly import placement
from .errors import (
    AssemblyError,
    FrameNotFound,
    InputError,
    JointNotFound,
    MechanismFileError,
    PkmError,
    UrdfError,
)
from .leg import Leg
from .linkage import Linkage
from .mechanism import Mechanism
from .urdf import MAX_COORDINATE, LimitExceeded, read_bounded

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["BACKENDS", "FORMATS", "load_mechanism"]


# --------------------------------------------------------------------- TOML files
_LEG_KEYS = {"name", "urdf", "tip", "actuated", "base", "anchor", "home_q"}
_TOP_KEYS = {"name", "description", "legs", "home", "closure", "length_unit"}
#: Largest mechanism file read [bytes], refused before it is read whole: the shipped
#: ones are 1–4 kB (legs, paths, poses); like the closures file's limit
#: (:data:`pkm_pin.model.extended_urdf.MAX_CLOSURES_BYTES`), it bounds the parse's time
#: and memory.
MAX_MECHANISM_BYTES = 1_000_000

#: Values of the top-level ``closure`` key: a rigid platform, or a pin.
_CLOSURES = ("weld", "spherical", "revolute")
_POSE_KEYS = {"xyz", "rpy"}


#: Backends of :func:`load_mechanism`.
BACKENDS = ("legs", "general")


def load_mechanism(path: str | os.PathLike, *, closures: str | os.PathLike | None = None,
                   output: str | None = None, point: bool | None = None,
                   backend: str | None = None):
    """Read a mechanism file: a :class:`Mechanism` whatever the file, whose
    :attr:`~Mechanism.backend` is chosen by its suffix:

    * ``.toml``: our format (this module's docstring): legs fixed to a platform are read
      by the per-leg engine (``"legs"``); legs meeting at a pin (``closure =
      "spherical"`` or ``"revolute"``, :mod:`pkm_pin.model.pinned`) by the general
      elimination (``"general"``, :class:`~pkm_pin.linkage.Linkage`);
    * ``.urdf``: Extended URDF, the URDF tree plus its closures file (YAML or TOML with
      the keys of Gepetto's example-parallel-robots; beside the URDF, or ``closures``),
      :func:`pkm_pin.model.read_extended_urdf`;
    * ``.xml`` / ``.mjcf``: MJCF with ``<equality>`` closures,
      :func:`pkm_pin.model.read_mjcf` (a tree without closures when it has none).

    An Extended URDF or MJCF file is read per leg (``"legs"``) where a
    base–legs–platform machine is detected in it and its legs take the actuated values
    in the file's order (so that the same machine has the same indices whatever file
    describes it, docs/indices.md), by the general elimination (``"general"``)
    otherwise (multi-loop legs, a point output, coupled chains …).

    Args:
        closures: The closures file of a URDF (default: found beside it).
        output: For a :class:`~pkm_pin.linkage.Linkage`, the frame whose motion is
            analysed (default: the file's).
        point: For a :class:`~pkm_pin.linkage.Linkage`, analyse the output frame's origin
            as a point (``True``) or as a body (``False``; default: the file's).
        backend: ``None`` (default): as above. ``"legs"``: the per-leg screw
            engine of a base–legs–platform machine, a :class:`Mechanism`, also for an
            Extended URDF or MJCF file in which that structure is detected
            (:meth:`Mechanism.from_closure_model`: the same machine written as TOML legs
            gives the same numbers); a file without it is refused with the reason.
            ``"general"``: the general elimination (:attr:`Mechanism.general`),
            for every file (TOML legs through their :attr:`Mechanism.closure_model`).

    Raises:
        MechanismFileError: the file is missing or wrong; the message names the file,
            the entry (leg, key, closure) and how to fix it.
    """
    if backend not in (None,) + BACKENDS:
        raise InputError(f"backend={backend!r}: write one of {', '.join(map(repr, BACKENDS))} "
                         "or leave it out")
    path = Path(path)
    label = str(path)
    mech = _with_backend(_load_file(path, label, closures, output, point), backend, label)
    return Mechanism.of_linkage(mech, description=_description(path)) \
        if isinstance(mech, Linkage) else mech


def _description(path: Path) -> str:
    """The one-line description of a file read by the general backend."""
    return f"read from {path.name}"


def _load_file(path: Path, label: str, closures, output, point):
    """:func:`load_mechanism` of the file's own kind."""
    try:
        exists = path.is_file()
    except OSError as e:  # e.g. a name too long for the file system
        raise MechanismFileError(label[:80], "", f"not a usable file name: {e.strerror}") from e
    if not exists:
        raise MechanismFileError(label, "", "no such file")
    suffix = path.suffix.lower()
    if suffix in (".urdf", ".xml", ".mjcf"):
        return _linkage_file(path, suffix, closures, output, point)
    if suffix != ".toml":
        raise MechanismFileError(label, "", _unread_format(suffix))
    if closures is not None:
        raise MechanismFileError(label, "", "closures= names the closures file of a .urdf; "
                                 "a TOML mechanism file holds its own closures")
    mech = _load_toml(path)
    if isinstance(mech, Mechanism):
        return mech if output is None and point is None else \
            other_output(mech, output, point, label)
    try:
        return type(mech)(mech.model, output=output, point=point)
    except InputError as e:
        raise MechanismFileError(label, "output", str(e)) from e


def general_reading(mech: Mechanism, output: str | None = None,
                    point: bool | None = None) -> Linkage:
    """The general elimination (:class:`~pkm_pin.linkage.Linkage`) of a platform
    mechanism (:attr:`Mechanism.general`: its model's tree assembled from its home), with
    another output frame or a point if asked."""
    if output is None and point is None:
        return mech.general
    return Linkage(mech.general.model, output=output, point=point)


def other_output(mech: Mechanism, output: str | None, point: bool | None,
                 label: str = "") -> Linkage:
    """A platform mechanism read with another output (a frame of its
    :attr:`~Mechanism.closure_model`'s tree: ``"<leg>/<link>"``, ``"platform"``) or its
    platform's origin as a point: :func:`general_reading`, which analyses any frame as a
    body or a point."""
    try:
        return general_reading(mech, output, point)
    except InputError as e:
        raise MechanismFileError(label or mech.name, "output", f"{e} (a platform mechanism "
                                 "is read with another output through its legs-and-"
                                 "platform tree)") from e


#: The formats :func:`load_mechanism` reads, in words (for messages).
FORMATS = ("a .toml mechanism file (legs, or legs meeting at a pin), an Extended URDF "
           "(.urdf with its .yaml/.toml closures file beside it) or an MJCF file (.xml, "
           ".mjcf)")


def _unread_format(suffix: str) -> str:
    """Why a file of this suffix is not read, and what to give instead."""
    if suffix in (".yaml", ".yml"):
        return ("is a closures file: give the .urdf it belongs to (the closures file is "
                "found beside it, or pass it with closures= / --closures)")
    if suffix == ".sdf":
        why = ("its closures are not read yet" if getattr(pin, "WITH_SDFORMAT", False) else
               "the installed Pinocchio has no SDFormat support (pinocchio.WITH_SDFORMAT)")
        return f"SDF is not read ({why}); give {FORMATS}"
    return f"unknown suffix {suffix or '(none)'!r}: pkm_pin reads {FORMATS}"


def _linkage_file(path: Path, suffix: str, closures, output, point):
    """The :class:`~pkm_pin.linkage.Linkage` of an Extended URDF or an MJCF file.

    Its output: ``output=``, else the file's (a closures file's ``output`` key, an MJCF
    ``<custom><text name="pkm_pin:output" data="FRAME"/>``), else the body the
    mechanism exists to move (:func:`pkm_pin.output_choice.designer_output`: at the
    assembly from the reference, kept as :attr:`Linkage.home_assembly`; the readers'
    default when it does not assemble)."""
    from .closure_gaps import reconcile
    from .model import read_extended_urdf, read_mjcf
    from .output_choice import designer_output

    label = str(path)
    try:
        if suffix == ".urdf":
            model = read_extended_urdf(path, closures, output=output)
        else:
            if closures is not None:
                raise MechanismFileError(label, "", "an MJCF file holds its closures "
                                         "(<equality>): closures= is for a .urdf")
            model = read_mjcf(path, output=output)
        link = Linkage(reconcile(model), point=point)
        return link if model.output_named else designer_output(link)
    except MechanismFileError:
        raise
    except (FrameNotFound, JointNotFound) as e:
        raise MechanismFileError(label, "output" if isinstance(e, FrameNotFound) else
                                 "actuated joints", str(e)) from e
    except InputError as e:
        raise MechanismFileError(label, "", str(e)) from e


def _with_backend(mech, backend: str | None, label: str):
    """``mech`` (a :class:`Mechanism` or a :class:`~pkm_pin.linkage.Linkage`) read
    through the ``backend`` of :func:`load_mechanism`."""
    if backend is None and isinstance(mech, Linkage):
        return _detected(mech, label)
    if backend is None or (backend == "legs") == isinstance(mech, Mechanism):
        return mech
    if backend == "general":
        return general_reading(mech)
    try:
        return Mechanism.from_closure_model(
            mech.model, mech.assemble().q,
            description=f"base–legs–platform machine detected in {Path(label).name}")
    except AssemblyError as e:
        raise MechanismFileError(label, "", f"does not assemble from its reference, so its "
                                 f"legs cannot be read: {e}") from e
    except InputError as e:
        raise MechanismFileError(label, "", f"{e}; analyse it with the general backend "
                                 "(the default for this file)") from e


def _detected(link: Linkage, label: str):
    """The default reading of a linkage read from a file: the per-leg engine where a
    base–legs–platform machine is detected in it and its legs take the actuated values
    in the file's order (so that a vector of actuated values means the same to both
    readings), its indices then those of the same machine written as TOML legs
    (docs/indices.md); else the general elimination, ``link`` itself."""
    if not link.model.closures or link.platform_structure[0] is None:
        return link  # a serial tree is not a base–legs–platform machine
    try:
        legs = _with_backend(link, "legs", label)
    except (PkmError, ValueError, RuntimeError):  # e.g. it does not assemble from its
        return link  # reference: the general elimination reads it, and says why
    same = legs.actuated_names == list(link.actuated)
    return legs if same else link


def _load_toml(path: Path):
    """:func:`load_mechanism` for a TOML file."""
    label = str(path)
    try:
        doc = tomllib.loads(read_bounded(path, MAX_MECHANISM_BYTES, "mechanism file"))
    except LimitExceeded as e:
        raise MechanismFileError(label, "", f"{e.reason} (a mechanism file is a few kB)"
                                 ) from e
    except (tomllib.TOMLDecodeError, RecursionError) as e:  # RecursionError: deep nesting
        raise MechanismFileError(label, "", f"not valid TOML: {e}") from e
    except (OSError, UnicodeDecodeError) as e:
        raise MechanismFileError(label, "", f"cannot be read: {e}") from e
    _unknown(doc, _TOP_KEYS, label, "")
    name = _typed(doc, "name", str, label, "", default=path.stem)
    description = _typed(doc, "description", str, label, "", default="")
    legs_doc = doc.get("legs")
    if not isinstance(legs_doc, list) or not legs_doc:
        raise MechanismFileError(label, "legs", "needs at least one [[legs]] table")
    legs, anchors, home_q = [], [], []
    for i, entry in enumerate(legs_doc):
        leg, anchor, q = _load_leg(entry, i, path)
        legs.append(leg)
        anchors.append(anchor)
        home_q.append(q)
    closure = _typed(doc, "closure", str, label, "", default="weld")
    if closure not in _CLOSURES:
        raise MechanismFileError(label, "closure", f"unknown closure {closure!r}: write one of "
                                 f"{', '.join(repr(c) for c in _CLOSURES)}")
    if closure != "weld":
        return _pinned(legs, anchors, home_q, closure, name, doc, label)
    home = _pose_table(doc.get("home", {}), label, "home")
    try:
        return Mechanism(legs, anchors, name=name, home=home,
                         home_q=home_q if any(q is not None for q in home_q) else None,
                         description=description,
                         length_unit=_typed(doc, "length_unit", str, label, "", default="m"))
    except InputError as e:
        raise MechanismFileError(label, "", str(e)) from e


def _pinned(legs, anchors, home_q, closure: str, name: str, doc: dict, label: str):
    """The :class:`~pkm_pin.linkage.Linkage` of legs meeting at a pin
    (:func:`pkm_pin.model.pinned.pinned_legs`)."""
    from .model.pinned import pinned_legs

    if "home" in doc:
        raise MechanismFileError(label, "home", f"legs meeting at a {closure} pin have no "
                                 "platform pose: remove [home] and give each leg's home_q "
                                 "(the configuration assembly starts from)")
    try:
        return Linkage(pinned_legs(legs, anchors, closure, name=name, home_q=home_q))
    except InputError as e:
        raise MechanismFileError(label, "closure", str(e)) from e


def _load_leg(entry, i: int, path: Path):
    label = str(path)
    if not isinstance(entry, dict):
        raise MechanismFileError(label, f"legs[{i}]", "must be a table")
    leg_name = entry.get("name", f"leg{i}")
    where = f"leg {leg_name!r} (legs[{i}])"
    _unknown(entry, _LEG_KEYS, label, where)
    leg_name = _typed(entry, "name", str, label, where, default=f"leg{i}")
    urdf_rel = _typed(entry, "urdf", str, label, where)
    tip = _typed(entry, "tip", str, label, where)
    actuated = entry.get("actuated", [])
    if not (isinstance(actuated, list) and all(isinstance(a, str) for a in actuated)):
        raise MechanismFileError(label, f"{where}.actuated", "must be a list of joint names")
    base = _pose_table(entry.get("base", {}), label, f"{where}.base")
    anchor = _pose_table(entry.get("anchor", {}), label, f"{where}.anchor")
    urdf_path = (path.parent / urdf_rel).resolve()
    try:
        leg = Leg.from_urdf(urdf_path, tip, actuated, base, leg_name)
    except (FrameNotFound, JointNotFound) as e:
        key = "tip" if isinstance(e, FrameNotFound) else "actuated"
        raise MechanismFileError(label, f"{where}.{key}", str(e)) from e
    except UrdfError as e:
        raise MechanismFileError(label, f"{where}.urdf", str(e)) from e
    except PkmError as e:
        raise MechanismFileError(label, where, str(e)) from e
    q = None
    if "home_q" in entry:
        q = _numbers(entry["home_q"], leg.nq, label, f"{where}.home_q")
    return leg, anchor, q


def _unknown(table: dict, allowed: set, label: str, where: str) -> None:
    extra = sorted(set(table) - allowed)
    if extra:
        raise MechanismFileError(
            label, where or "top level",
            f"unknown key(s) {extra}; the allowed keys are {sorted(allowed)}",
        )


def _typed(table: dict, key: str, kind: type, label: str, where: str, default=None):
    if key not in table:
        if default is None:
            raise MechanismFileError(label, f"{where}.{key}" if where else key, "is missing")
        return default
    value = table[key]
    if not isinstance(value, kind):
        raise MechanismFileError(
            label, f"{where}.{key}" if where else key,
            f"must be a {kind.__name__}, got {type(value).__name__} {value!r}",
        )
    return value


def _numbers(value, n: int, label: str, where: str) -> np.ndarray:
    if not (isinstance(value, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                            for v in value)):
        raise MechanismFileError(label, where, f"must be a list of {n} numbers, got {value!r}")
    if len(value) != n:
        raise MechanismFileError(label, where, f"must have {n} numbers, got {len(value)}")
    a = np.array(value, dtype=float)
    if not np.all(np.isfinite(a)):
        raise MechanismFileError(label, where, f"must be finite, got {value!r}")
    if np.abs(a).max(initial=0.0) > MAX_COORDINATE:  # 1e154 overflowed the solvers' norms
        big = a[np.argmax(np.abs(a))]
        raise MechanismFileError(label, where, f"has {big:g}, beyond ±{MAX_COORDINATE:g} "
                                 "(m or rad): a mechanism is not a thousand kilometres wide")
    return a


def _pose_table(table, label: str, where: str) -> pin.SE3:
    if not isinstance(table, dict):
        raise MechanismFileError(label, where, "must be a table { xyz = [...], rpy = [...] }")
    _unknown(table, _POSE_KEYS, label, where)
    xyz = _numbers(table.get("xyz", [0.0, 0.0, 0.0]), 3, label, f"{where}.xyz")
    rpy = _numbers(table.get("rpy", [0.0, 0.0, 0.0]), 3, label, f"{where}.rpy")
    return placement(xyz, rpy)

