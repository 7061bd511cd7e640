"""Reading, validating and building URDF models.

A URDF is first parsed as XML (errors carry line and column), then loaded with
yourdfpy, then checked for the structural mistakes that yourdfpy and Pinocchio let
through or report obscurely (a joint naming a link that does not exist, two parents, a
loop, a mimic of an unknown joint, a zero axis, inverted limits). Only then is the
Pinocchio model built, with mimic joints honoured (a parallelogram is a revolute plus a
mimicking revolute with multiplier −1). Every failure is a :class:`~pkm_pin.UrdfError`.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
import yourdfpy

from .errors import UrdfError, _cut, _listing

_MOVABLE = ("revolute", "continuous", "prismatic", "floating", "planar")
_TYPES = ("fixed",) + _MOVABLE
#: Largest URDF accepted (links; joints likewise): mechanisms and legged robots have tens
#: to a few hundred; beyond, Pinocchio's and urdfdom's recursive parsers exhaust memory
#: (about 1000) or the stack (about 20 000) instead of failing cleanly.
MAX_LINKS = 500
#: Largest URDF text accepted [bytes] (checked before parsing).
MAX_BYTES = 16_000_000
#: Deepest element nesting accepted in an XML model (URDF, MJCF), checked by a streaming
#: pass before any tree is built. A URDF is 4 deep; an MJCF nests one element per body
#: (humanoids and hands: about 20). Pinocchio 4.1's MJCF parser takes time cubic in the
#: depth (0.07 s at 100 levels, 35 s at 600) and recurses on the C stack (50 000 levels:
#: a segfault), so the limit bounds both.
MAX_XML_DEPTH = 100
#: Most XML elements accepted in one model (all its included files together).
MAX_XML_ELEMENTS = 200_000
#: Largest |coordinate| accepted [m] (origins, positions, anchors), and the largest
#: |angle| [rad or deg]: a mechanism is not a thousand kilometres wide; beyond, the
#: residuals and rank decisions lose their meaning (1e308 overflows to inf).
MAX_COORDINATE = 1e6


class LimitExceeded(Exception):
    """An input goes beyond a reader's limit (size, depth, count, range); ``reason`` says
    which. Each reader re-raises it as its own :class:`~pkm_pin.errors.PkmError`."""

    def __init__(self, reason: str):
        self.reason = reason
        super().__init__(reason)


def read_bounded(path: Path, limit: int, what: str, binary: bool = False) -> str | bytes:
    """The text of ``path`` (UTF-8; its bytes if ``binary``), refused before reading it
    whole when it is larger than ``limit`` bytes.

    Raises:
        LimitExceeded: the file is too large.
        OSError, UnicodeDecodeError: as :meth:`Path.read_text`.
    """
    with open(path, "rb") as f:
        size = os.fstat(f.fileno()).st_size  # 0 for a pipe: read up to the limit
        data = f.read((min(size, limit) if size else limit) + 1) if size <= limit else b""
        if size and len(data) == size + 1:  # grew while read: read on, within the limit
            data += f.read(limit + 1 - len(data))
    if size > limit or len(data) > limit:
        shown = f"{size / 1e6:.1f} MB" if size > limit else f"more than {limit / 1e6:g} MB"
        raise LimitExceeded(f"the {what} is {shown}, more than the {limit / 1e6:g} MB "
                            "pkm_pin reads")
    return data if binary else data.decode("utf-8")


def check_xml_limits(xml: str | bytes, limit_depth: int = MAX_XML_DEPTH,
                     limit_elements: int = MAX_XML_ELEMENTS) -> int:
    """Stream through ``xml`` (expat, no tree built) and refuse what the tree builders
    (ElementTree, urdfdom, Pinocchio's MJCF parser) would choke on: nesting deeper than
    ``limit_depth``, more than ``limit_elements`` elements, and DTD entity declarations
    (no URDF or MJCF needs one; they are how "billion laughs" files expand). Malformed XML
    is left to the caller's parser, which reports it with line and column.

    Returns:
        The number of elements.

    Raises:
        LimitExceeded: the limit passed, with the line.
    """
    from xml.parsers import expat

    parser = expat.ParserCreate()
    state = {"depth": 0, "count": 0}

    def start(name, _attrs):
        state["depth"] += 1
        state["count"] += 1
        if state["depth"] > limit_depth:
            raise LimitExceeded(f"elements nested more than {limit_depth} deep (line "
                                f"{parser.CurrentLineNumber}, <{_cut(name)[1:-1]}>)")
        if state["count"] > limit_elements:
            raise LimitExceeded(f"more than {limit_elements} XML elements (line "
                                f"{parser.CurrentLineNumber})")

    def end(_name):
        state["depth"] -= 1

    def entity(name, *_args):
        raise LimitExceeded(f"a DTD entity declaration <!ENTITY {_cut(name)[1:-1]}> (line "
                            f"{parser.CurrentLineNumber}): pkm_pin reads no entities")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.EntityDeclHandler = entity
    try:
        parser.Parse(xml, True)
    except expat.ExpatError:
        pass  # malformed: the caller's parser says where
    return state["count"]


@dataclass(frozen=True)
class UrdfSource:
    """A URDF's text and where it came from.

    Attributes:
        xml: The URDF text.
        label: The file path, or ``"<string: robot NAME>"`` for text given directly.
        directory: Folder that relative mesh paths are resolved against (None for text).
        robot: yourdfpy's parsed robot description.
    """

    xml: str
    label: str
    directory: Path | None
    robot: yourdfpy.Robot


def _looks_like_xml(source: str) -> bool:
    return source.lstrip().startswith("<")


def read(source: str | os.PathLike) -> UrdfSource:
    """Read and validate a URDF given as a file path or as XML text.

    Raises:
        UrdfError: missing file, malformed XML, or a structural mistake; the message
            names the file and what to fix.
    """
    if isinstance(source, str) and not source.strip():
        raise UrdfError("<empty string>", "no URDF given", "pass a file path or the URDF text")
    if isinstance(source, (str, os.PathLike)) and not (
        isinstance(source, str) and _looks_like_xml(source)
    ):
        path = Path(source)
        try:
            exists = path.is_file()
        except OSError as e:  # e.g. a name too long: neither XML nor a usable path
            raise UrdfError(str(path)[:80] + "…", f"neither URDF text nor a usable path "
                            f"({e.strerror})", "give a file path or XML starting with '<'") from e
        if not exists:
            hint = "check the path" + (
                f" (relative paths are taken from {Path.cwd()})" if not path.is_absolute() else ""
            )
            raise UrdfError(str(path), "no such file", hint)
        try:
            xml = read_bounded(path, MAX_BYTES, "URDF")
        except LimitExceeded as e:
            raise UrdfError(str(path), e.reason, "split it or remove meshes inlined") from e
        except (OSError, UnicodeDecodeError) as e:
            raise UrdfError(str(path), f"cannot be read: {e}") from e
        label, directory = str(path), path.parent
    elif isinstance(source, str):
        xml, label, directory = source, "<string>", None
    else:
        raise UrdfError(repr(type(source).__name__), "a URDF source must be a path or XML text")
    if len(xml) > MAX_BYTES:
        raise UrdfError(label, f"the URDF is {len(xml) / 1e6:.1f} MB, more than the "
                        f"{MAX_BYTES / 1e6:g} MB pkm_pin reads",
                        "split it or remove meshes inlined")
    root = _parse_xml(xml, label)
    if label == "<string>":
        label = f"<string: robot {_cut(root.get('name', '?'), 80)}>"
    _check_structure(root, label)
    robot = _load_yourdfpy(xml, label)
    return UrdfSource(xml=xml, label=label, directory=directory, robot=robot)


def _parse_xml(xml: str, label: str) -> ET.Element:
    try:
        check_xml_limits(xml)
    except LimitExceeded as e:
        raise UrdfError(label, e.reason) from e
    try:
        root = ET.fromstring(xml)
    except ET.ParseError as e:
        line, col = e.position
        raise UrdfError(label, f"malformed XML at line {line}, column {col}: {e}") from e
    if root.tag != "robot":
        raise UrdfError(label, f"the root element is <{root.tag}>, a URDF's must be <robot>")
    return root


def _floats(text: str | None, n: int, what: str, label: str,
            bound: float | None = MAX_COORDINATE) -> np.ndarray | None:
    """The ``n`` numbers of ``text`` (None when absent), finite and, unless ``bound`` is
    None, within ±``bound``."""
    if text is None:
        return None
    try:
        values = np.array([float(t) for t in text.split()])
    except ValueError as e:
        raise UrdfError(label, f"{what} must be {n} numbers, got {_cut(text)}") from e
    if values.shape != (n,) or not np.all(np.isfinite(values)):
        raise UrdfError(label, f"{what} must be {n} finite numbers, got {_cut(text)}")
    if bound is not None and np.abs(values).max() > bound:
        big = values[np.argmax(np.abs(values))]
        raise UrdfError(label, f"{what} has {big:g}, beyond ±{bound:g} (m or rad)",
                        "give the value in metres and radians; a mechanism is not "
                        "a thousand kilometres wide")
    return values


def _check_structure(root: ET.Element, label: str) -> None:
    """Check the link/joint tree: names, references, parents, loops, axes, limits."""
    for el in root.iter():
        if isinstance(el.tag, str) and el.tag.startswith("{http://www.ros.org/wiki/xacro}"):
            raise UrdfError(label, f"<xacro:{_cut(el.tag.split('}')[1])[1:-1]}> is a xacro "
                            "macro, which pkm_pin does not expand",
                            "run 'xacro FILE > FILE.urdf' and give the URDF")
    links = [l.get("name") for l in root.findall("link")]
    if not links:
        raise UrdfError(label, "the robot has no <link>")
    if max(len(links), len(root.findall("joint"))) > MAX_LINKS:
        raise UrdfError(label, f"the robot has {len(links)} links and "
                        f"{len(root.findall('joint'))} joints, more than the {MAX_LINKS} "
                        "pkm_pin reads", "model the mechanism with fewer bodies (a leg, "
                        "a linkage), or split the URDF")
    if None in links:
        raise UrdfError(label, "a <link> has no name attribute")
    for link in root.findall("link"):
        _check_link(link, label)
    dup = {n for n in links if links.count(n) > 1}
    if dup:
        raise UrdfError(label, f"link names must be unique; repeated: {_listing(sorted(dup))}")
    link_set = set(links)
    joints = root.findall("joint")
    names = [j.get("name") for j in joints]
    if None in names:
        raise UrdfError(label, "a <joint> has no name attribute")
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise UrdfError(label, f"joint names must be unique; repeated: {_listing(sorted(dup))}")
    parent_of: dict[str, str] = {}
    for j in joints:
        _check_joint(j, link_set, parent_of, label)
    movable = {j.get("name") for j in joints if j.get("type") != "fixed"}
    for j in joints:
        m = j.find("mimic")
        if m is not None and m.get("joint") not in movable:
            raise UrdfError(
                label,
                f"joint {_cut(j.get('name'))} mimics {_cut(m.get('joint'))}, which is not a "
                "movable joint",
                f"movable joints: {_listing(sorted(movable))}",
            )
    roots = [l for l in links if l not in parent_of]
    if len(roots) != 1:
        raise UrdfError(
            label,
            f"the links must form one tree with one root; roots found: {_listing(roots)}",
            "connect every link to the tree with a joint, or remove it",
        )
    for link in links:  # a loop would leave some link without a path to the root
        seen, cur = set(), link
        while cur in parent_of:
            if cur in seen:
                raise UrdfError(label, f"the joints form a loop through link {_cut(cur)}")
            seen.add(cur)
            cur = parent_of[cur]


def _check_link(link: ET.Element, label: str) -> None:
    """Origins (inertial, visual, collision) finite and within range; mass and inertia
    finite, the mass not negative."""
    where = f"link {_cut(link.get('name'))}"
    for part in ("inertial", "visual", "collision"):
        for el in link.findall(part):
            origin = el.find("origin")
            if origin is not None:
                _floats(origin.get("xyz"), 3, f"{where} {part} origin xyz", label)
                _floats(origin.get("rpy"), 3, f"{where} {part} origin rpy", label)
    inertial = link.find("inertial")
    if inertial is None:
        return
    mass = inertial.find("mass")
    if mass is not None and mass.get("value") is not None:
        m = _floats(mass.get("value"), 1, f"{where} mass", label, bound=None)
        if m[0] < 0:
            raise UrdfError(label, f"{where} has mass {m[0]:g} < 0")
    inertia = inertial.find("inertia")
    if inertia is not None:
        for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
            _floats(inertia.get(key), 1, f"{where} inertia {key}", label, bound=None)


def _check_joint(j: ET.Element, link_set: set, parent_of: dict, label: str) -> None:
    name, jtype = j.get("name"), j.get("type")
    where = f"joint {_cut(name)}"
    if jtype not in _TYPES:
        raise UrdfError(label, f"{where} has type {_cut(jtype)}", f"use one of {list(_TYPES)}")
    ends = {}
    for tag in ("parent", "child"):
        el = j.find(tag)
        if el is None or el.get("link") is None:
            raise UrdfError(label, f"{where} has no <{tag} link=...>")
        if el.get("link") not in link_set:
            raise UrdfError(
                label,
                f"{where} names {tag} link {_cut(el.get('link'))}, which does not exist",
                f"links: {_listing(sorted(link_set))}",
            )
        ends[tag] = el.get("link")
    if ends["child"] in parent_of:
        raise UrdfError(label, f"link {_cut(ends['child'])} is the child of two joints")
    parent_of[ends["child"]] = ends["parent"]
    origin = j.find("origin")
    if origin is not None:
        _floats(origin.get("xyz"), 3, f"{where} origin xyz", label)
        _floats(origin.get("rpy"), 3, f"{where} origin rpy", label)
    if jtype in ("revolute", "continuous", "prismatic"):
        ax = j.find("axis")
        if ax is not None and ax.get("xyz") is None:  # urdfdom reads it as a zero axis
            raise UrdfError(label, f"{where} has an <axis> without xyz",
                            'give the axis, e.g. <axis xyz="1 0 0"/>, or no <axis> for x')
        a = _floats(ax.get("xyz") if ax is not None else None, 3, f"{where} axis", label)
        if a is not None and np.linalg.norm(a) == 0:
            raise UrdfError(label, f"{where} has a zero axis", "give a non-zero axis xyz")
    if jtype in ("revolute", "prismatic"):
        lim = j.find("limit")
        if lim is None:
            raise UrdfError(label, f"{where} ({jtype}) has no <limit>", "URDF requires one")
        try:
            lo, up = float(lim.get("lower", 0.0)), float(lim.get("upper", 0.0))
        except ValueError as e:
            raise UrdfError(label, f"{where} has a non-numeric limit") from e
        if not (np.isfinite(lo) and np.isfinite(up)) or lo > up:
            raise UrdfError(label, f"{where} has limits lower={lo} > upper={up}")
        if max(abs(lo), abs(up)) > MAX_COORDINATE:
            raise UrdfError(label, f"{where} has limits lower={lo:g}, upper={up:g}, beyond "
                            f"±{MAX_COORDINATE:g} (m or rad)")
        for key in ("effort", "velocity"):
            if lim.get(key) is None:
                raise UrdfError(label, f"{where} <limit> has no {key} attribute",
                                "URDF requires effort and velocity on every <limit>")


def _load_yourdfpy(xml: str, label: str) -> yourdfpy.Robot:
    logger = logging.getLogger("yourdfpy")
    previous = logger.level
    logger.setLevel(logging.CRITICAL)
    try:
        urdf = yourdfpy.URDF.load(
            io.BytesIO(xml.encode()), build_scene_graph=False, load_meshes=False
        )
    except Exception as e:  # yourdfpy raises many kinds; give one clear error
        raise UrdfError(label, f"yourdfpy cannot load it: {e}") from e
    finally:
        logger.setLevel(previous)
    return urdf.robot


def build_model(src: UrdfSource) -> pin.Model:
    """Pinocchio model of a validated URDF, with mimic joints honoured; a joint whose
    ``<limit>`` gives no range is unlimited (:func:`joints_without_range`).

    What urdfdom prints on the C-level stderr while parsing is captured and, on
    failure, put into the :class:`UrdfError` message (never printed)."""
    with _captured_stderr() as captured:
        try:
            model = free_range(pin.buildModelFromXML(src.xml, mimic=True),
                               joints_without_range(src))
            error = None
        except Exception as e:  # Pinocchio raises RuntimeError/ValueError with C++ text
            model, error = None, e
    if error is not None:
        detail = " ".join(line.strip() for line in captured() if line.strip())
        raise UrdfError(src.label, f"Pinocchio cannot build a model: {error}"
                        + (f" (urdfdom: {detail[:300]})" if detail else "")) from error
    return model


def joints_without_range(src: UrdfSource) -> list[str]:
    """Revolute and prismatic joints of ``src`` whose ``<limit>`` gives neither ``lower``
    nor ``upper``: URDF's default range is then [0, 0] (Pinocchio reads it so), but
    files exported without ranges (Onshape's, Gepetto's ``kangaroo_like``) mean a joint
    that moves; :func:`free_range` reads them as unlimited."""
    return [j.name for j in src.robot.joints if j.type in ("revolute", "prismatic")
            and (j.limit is None or (j.limit.lower is None and j.limit.upper is None))]


def free_range(model: pin.Model, names) -> pin.Model:
    """``model`` with the position range of the joints ``names`` unlimited (in place;
    returned)."""
    for name in names:
        if model.existJointName(name):
            joint = model.joints[model.getJointId(name)]
            for i in range(joint.idx_q, joint.idx_q + joint.nq):
                model.lowerPositionLimit[i] = -np.inf
                model.upperPositionLimit[i] = np.inf
    return model


@contextlib.contextmanager
def _captured_stderr():
    """Redirect file descriptor 2 (C-level stderr) to a temporary file; yields a
    function returning the captured lines."""
    import tempfile

    lines: list[str] = []
    try:
        fd = sys.stderr.fileno()
    except (AttributeError, OSError, ValueError):  # stderr replaced (e.g. by pytest)
        fd = 2
    sys.stderr.flush()
    saved = os.dup(fd)
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), fd)
        try:
            yield lambda: lines
        finally:
            os.dup2(saved, fd)
            os.close(saved)
            tmp.seek(0)
            lines.extend(tmp.read().decode(errors="replace").splitlines())


def example_robot_data_dir() -> Path:
    """Folder ``robots/`` of the installed example-robot-data package.

    The 6.x wheels ship the data under ``cmeel.prefix/share/example-robot-data`` and no
    Python module; older installs ship ``example_robot_data`` with a path helper.
    """
    import site
    import sys

    candidates = []
    try:  # older wheels
        import example_robot_data  # type: ignore

        getter = getattr(example_robot_data, "getModelPath", None)
        if getter is not None:
            candidates.append(Path(getter("ur_description/urdf/ur5_robot.urdf")).parent)
    except ImportError:
        pass
    roots = list(dict.fromkeys(site.getsitepackages() + [site.getusersitepackages()] + sys.path))
    for r in roots:
        candidates.append(Path(r) / "cmeel.prefix" / "share" / "example-robot-data" / "robots")
    candidates.append(Path(sys.prefix) / "share" / "example-robot-data" / "robots")
    for c in candidates:
        if (c / "ur_description").is_dir():
            return c
    raise UrdfError(
        "example-robot-data",
        "the package is not installed",
        "install it with: pip install 'pkm_pin[robots]' (or pip install example-robot-data)",
    )


#: name -> (path inside robots/, default tip frame)
EXAMPLE_ROBOTS = {
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "ur5_limited": ("ur_description/urdf/ur5_joint_limited_robot.urdf", "tool0"),
    "panda": ("panda_description/urdf/panda.urdf", "panda_link8"),
}


def example_robot_path(name: str) -> Path:
    """Path of an example-robot-data URDF: a name of :data:`EXAMPLE_ROBOTS`, or a path
    relative to the package's ``robots/`` folder (e.g. ``"ur_description/urdf/ur10_robot.urdf"``).
    """
    if name in EXAMPLE_ROBOTS:
        relative = EXAMPLE_ROBOTS[name][0]
    elif name.endswith(".urdf"):
        relative = name
    else:
        raise UrdfError(
            f"example-robot-data:{name}",
            "unknown robot name",
            f"known names: {sorted(EXAMPLE_ROBOTS)}, or a path ending in .urdf relative to "
            "the package's robots/ folder",
        )
    path = example_robot_data_dir() / relative
    if not path.is_file():
        raise UrdfError(str(path), "not found in the installed example-robot-data")
    return path
