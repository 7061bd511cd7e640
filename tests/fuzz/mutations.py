"""Structure-aware mutations of the real-files corpus, as hypothesis strategies.

Three readers, three corpora:

- **Extended URDF**: every Gepetto folder of ``tests/data/gepetto`` and the shipped
  loop models of ``models/loops`` (a URDF tree and its YAML closures file);
- **MJCF**: Pinocchio's ``closed_chain.xml`` (Cassie) and the shipped ``models/loops``
  MJCF files;
- **TOML**: the shipped mechanism files of ``models/mechanisms`` (their leg URDFs named
  by absolute path, so that a copy loads from a temporary folder).

A case is a dict ``{file name: bytes}`` written into an empty folder, and the name of the
file given to ``pkm-pin analyze``. XML is mutated as a tree (elements dropped,
duplicated, renamed, re-parented, nested deep; attributes dropped, renamed, given
non-finite, huge, empty or wrong values; unknown tags), YAML and TOML as their parsed
data (keys dropped, duplicated, renamed; values swapped, emptied, nested, aliased), then
every file may be cut short or written in a wrong encoding.
"""

from __future__ import annotations

import copy
import json
import math
import re
import xml.etree.ElementTree as ET
from functools import lru_cache
from pathlib import Path

import yaml
from hypothesis import strategies as st

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"
MODELS = ROOT / "models"


# --------------------------------------------------------------------------- corpus
def _urdf_folders() -> list[tuple[Path, Path]]:
    """(URDF, YAML) pairs of the Extended URDF corpus, smallest URDF first."""
    pairs = [(u, u.parent / "robot.yaml") for u in (DATA / "gepetto").rglob("*.urdf")]
    pairs += [(u, u.with_suffix(".yaml")) for u in (MODELS / "loops").glob("*.urdf")]
    return sorted((p for p in pairs if p[1].is_file()), key=lambda p: p[0].stat().st_size)


URDF_CORPUS = _urdf_folders()
MJCF_CORPUS = [DATA / "pinocchio" / "closed_chain.xml", *sorted((MODELS / "loops").glob("*.xml"))]
TOML_CORPUS = sorted((MODELS / "mechanisms").glob("*.toml"))


@lru_cache(maxsize=None)
def _text(path: Path) -> str:
    return path.read_text(encoding="utf-8")


def toml_with_absolute_paths(path: Path) -> str:
    """A shipped mechanism file with its ``../urdf/`` paths made absolute."""
    return _text(path).replace('"../urdf/', f'"{MODELS / "urdf"}/')


# ------------------------------------------------------------------ hostile values
#: Numbers no reader should take as they are.
BAD_NUMBERS = ["nan", "NaN", "inf", "-inf", "1e308", "-1e308", "1e400", "", " ", "1e-320",
               "-0", "0", "1e6", "1e7", "-1", "abc", "0x10", "1,5", "1e", "+", "1 2",
               "1 2 3 4 5 6 7", "9" * 400]
#: Names: empty, long, look-alikes, other kinds of text.
BAD_NAMES = ["", " ", "A", "a" * 5000, "name with spaces", "../x", "é\u0301", "\u202e",
             "null", "0", "<x/>", "*", "mot", "tip", "a\u2028b", "a\x85b", "a\rb", "a\tb"]
UNKNOWN_TAGS = ["include", "xacro:macro", "replicate", "frame", "sensor", "gazebo",
                "transmission", "foo", "body", "joint", "link", "geom", "site", "inertial"]


def _number_text(draw) -> str:
    """A hostile number, a random float (non-finite, huge and tiny included), or a
    plausible one (which the analysis then has to cope with)."""
    kind = draw(st.integers(0, 2))
    if kind == 0:
        return draw(st.sampled_from(BAD_NUMBERS))
    if kind == 1:
        return repr(draw(st.floats(allow_nan=True, allow_infinity=True)))
    return repr(draw(st.floats(-3.0, 3.0)))


# ---------------------------------------------------------------------- XML trees
def _elements_with_parents(root: ET.Element) -> list[tuple[ET.Element, ET.Element]]:
    return [(p, c) for p in root.iter() for c in p]


def _set_attribute(draw, element: ET.Element) -> None:
    """An attribute of ``element`` given a hostile value: a whole value, or one number
    of a list replaced."""
    key = draw(st.sampled_from(sorted(element.attrib)))
    words = element.attrib[key].split()
    if words and draw(st.booleans()):
        words[draw(st.integers(0, len(words) - 1))] = _number_text(draw)
        element.set(key, " ".join(words))
    else:
        element.set(key, draw(st.sampled_from(BAD_NUMBERS + BAD_NAMES) | st.text(max_size=12)))


def _reparent(draw, root: ET.Element, parent: ET.Element, element: ET.Element) -> None:
    """``element`` moved under another element (not its own descendant), or, for a URDF
    joint, its parent and child links swapped."""
    p, c = element.find("parent"), element.find("child")
    if element.tag == "joint" and p is not None and c is not None and draw(st.booleans()):
        a, b = p.get("link"), c.get("link")
        if a is not None and b is not None:
            p.set("link", b)
            c.set("link", a)
            return
    inside = set(element.iter())
    targets = [e for e in root.iter() if e not in inside]
    if targets:
        parent.remove(element)
        draw(st.sampled_from(targets)).append(element)


def _nest(draw, parent: ET.Element, element: ET.Element) -> None:
    """``element`` wrapped in ``depth`` copies of its own tag or of an unknown tag."""
    depth = draw(st.sampled_from([2, 10, 99, 100, 101, 200]))
    tag = element.tag if draw(st.booleans()) else draw(st.sampled_from(UNKNOWN_TAGS))
    index = list(parent).index(element)
    parent.remove(element)
    outer = inner = ET.Element(tag)
    for _ in range(depth - 1):
        inner = ET.SubElement(inner, tag)
    inner.append(element)
    parent.insert(index, outer)


def _mutate_xml_once(draw, root: ET.Element) -> None:
    """One structural mutation of the tree ``root``."""
    pairs = _elements_with_parents(root)
    if not pairs:
        return
    parent, element = draw(st.sampled_from(pairs))
    op = draw(st.sampled_from(["drop", "duplicate", "rename", "drop_attr", "set_attr",
                               "set_attr", "rename_attr", "reparent", "nest", "unknown"]))
    if op == "drop":
        parent.remove(element)
    elif op == "duplicate":
        parent.insert(list(parent).index(element), copy.deepcopy(element))
    elif op == "rename":
        tags = sorted({e.tag for e in root.iter()} | set(UNKNOWN_TAGS))
        element.tag = draw(st.sampled_from(tags))
    elif op == "drop_attr" and element.attrib:
        del element.attrib[draw(st.sampled_from(sorted(element.attrib)))]
    elif op == "set_attr" and element.attrib:
        _set_attribute(draw, element)
    elif op == "rename_attr" and element.attrib:
        old = draw(st.sampled_from(sorted(element.attrib)))
        new = draw(st.sampled_from(["name", "type", "xyz", "rpy", "pos", "quat", "axis",
                                    "range", "link", "joint", "file", "mass", "x"]))
        element.set(new, element.attrib.pop(old))
    elif op == "reparent":
        _reparent(draw, root, parent, element)
    elif op == "nest":
        _nest(draw, parent, element)
    elif op == "unknown":
        attrs = {"name": draw(st.sampled_from(BAD_NAMES))}
        if draw(st.booleans()):
            attrs["file"] = draw(st.sampled_from(["robot.urdf", "m.xml", "../x.xml", "/etc/passwd",
                                                  "missing.xml", ""]))
        element.append(ET.Element(draw(st.sampled_from(UNKNOWN_TAGS)), attrs))


@st.composite
def mutated_xml(draw, text: str) -> str:
    """``text`` (a URDF or an MJCF) with 1–3 structural mutations; sometimes elements
    nested thousands deep (as text: ElementTree recurses to write a tree that deep)."""
    root = ET.fromstring(text)
    for _ in range(draw(st.integers(1, 3))):
        _mutate_xml_once(draw, root)
    out = ET.tostring(root, encoding="unicode")
    if draw(st.integers(0, 9)) == 0:
        tag = draw(st.sampled_from(["body", "link", "x", "worldbody"]))
        depth = draw(st.sampled_from([1000, 20000, 100000]))
        k = out.rfind("</")
        out = out[:k] + f"<{tag}>" * depth + f"</{tag}>" * depth + out[k:]
    return out


# ------------------------------------------------------------------ YAML and TOML data
def _paths(data, prefix=()) -> list[tuple]:
    """Every key/index path into nested dicts and lists."""
    out = []
    items = data.items() if isinstance(data, dict) else enumerate(data) \
        if isinstance(data, list) else ()
    for k, v in items:
        out.append((*prefix, k))
        out.extend(_paths(v, (*prefix, k)))
    return out


def _get(data, path):
    for k in path:
        data = data[k]
    return data


def _hostile_value(draw, old, names: list[str]):
    """A value to put where ``old`` was: a name of the model, a bad name, a hostile
    number, an empty or nested container, or ``old`` of another type."""
    choice = draw(st.sampled_from(["name", "bad_name", "number", "empty", "nest", "type"]))
    if choice == "name" and names:
        return draw(st.sampled_from(names))
    if choice == "bad_name":
        return draw(st.sampled_from(BAD_NAMES))
    if choice == "number":
        return draw(st.floats(allow_nan=True, allow_infinity=True)
                    | st.sampled_from([0, -1, 10**30, 2**64, 1e308]))
    if choice == "empty":
        return draw(st.sampled_from([[], {}, "", None]))
    if choice == "nest":
        value = old
        for _ in range(draw(st.sampled_from([1, 5, 16, 17, 60]))):
            value = [value]
        return value
    return draw(st.sampled_from([str(old), [old], {"x": old}, True, None]))


def _mutate_data_once(draw, data: dict, names: list[str]) -> None:
    """One mutation of parsed YAML/TOML ``data``: a key dropped, renamed or added, an
    entry duplicated or swapped with another, a value replaced."""
    paths = _paths(data)
    if not paths:
        data[draw(st.sampled_from(BAD_NAMES))] = 1
        return
    path = draw(st.sampled_from(paths))
    holder, key = _get(data, path[:-1]), path[-1]
    op = draw(st.sampled_from(["drop", "rename", "duplicate", "swap", "value", "value",
                               "unknown"]))
    if op == "drop":
        del holder[key]
    elif op == "rename" and isinstance(holder, dict):
        new = draw(st.sampled_from(sorted(map(str, data)) + BAD_NAMES + ["name_mot", "urdf"]))
        holder[new] = holder.pop(key)
    elif op == "duplicate" and isinstance(holder, list):
        holder.insert(key, copy.deepcopy(holder[key]))
    elif op == "swap":
        other = draw(st.sampled_from(paths))
        if other[:len(path)] != path and path[:len(other)] != other:
            oholder = _get(data, other[:-1])
            holder[key], oholder[other[-1]] = oholder[other[-1]], holder[key]
    elif op == "unknown" and isinstance(holder, dict):
        holder[draw(st.sampled_from(["extra", "joint_names", "Name_mot", "x"]))] = [1]
    else:
        holder[key] = _hostile_value(draw, holder[key], names)


def _yaml_text(data) -> str:
    return yaml.safe_dump(data, default_flow_style=None, allow_unicode=True, width=10**9)


@st.composite
def mutated_yaml(draw, text: str, names: list[str]) -> str:
    """A closures file with 1–3 data mutations, then maybe a text-level YAML construct
    (a duplicated key line, an anchor and alias, a tag, a deep flow nesting)."""
    data = yaml.safe_load(text) or {}
    for _ in range(draw(st.integers(1, 3))):
        _mutate_data_once(draw, data, names)
    out = _yaml_text(data)
    lines = out.splitlines() or [""]
    i = draw(st.integers(0, len(lines) - 1))
    construct = draw(st.sampled_from(["none", "none", "duplicate_line", "alias", "tag",
                                      "deep", "merge"]))
    if construct == "duplicate_line":
        lines.insert(i, lines[i])
    elif construct == "alias":
        lines[i:i + 1] = ["x: &a [" + ", ".join(["mot1"] * 9) + "]", lines[i], "y: *a",
                          "z: [*a, *a, *a]"]
    elif construct == "tag":
        lines.insert(i, draw(st.sampled_from(["w: !!python/object:os.system ls",
                                              "w: !!binary aGVsbG8=", "w: !custom 1",
                                              "? [a, b]\n: c", "%YAML 1.1", "---", "..."])))
    elif construct == "deep":
        depth = draw(st.sampled_from([15, 16, 17, 100, 10000]))
        lines.insert(i, "deep: " + "[" * depth + "]" * depth)
    elif construct == "merge":
        lines[i:i + 1] = ["base: &b {closed_loop: []}", "<<: *b", lines[i]]
    return "\n".join(lines) + "\n"


def toml_text(data: dict) -> str:
    """A minimal TOML writer: top-level scalars and inline values, arrays of tables as
    ``[[key]]`` sections (what the shipped mechanism files use)."""
    head, sections = [], []
    for key, value in data.items():
        if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for table in value:
                sections.append(f"\n[[{_toml_key(key)}]]")
                sections += [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in table.items()]
        else:
            head.append(f"{_toml_key(key)} = {_toml_value(value)}")
    return "\n".join(head + sections) + "\n"


def _toml_key(key) -> str:
    key = str(key)
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key, ensure_ascii=False)


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf") \
            if math.isinf(value) else repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}"
                                for k, v in value.items()) + " }"
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if value is None:
        return '""'
    return json.dumps(str(value), ensure_ascii=False)


@st.composite
def mutated_toml(draw, text: str) -> str:
    """A mechanism file with 1–3 data mutations, then maybe a duplicated line."""
    data = tomllib.loads(text)
    names = [v for _, v in _flat_strings(data)]
    for _ in range(draw(st.integers(1, 3))):
        _mutate_data_once(draw, data, names)
    out = toml_text(data)
    if draw(st.booleans()):
        lines = out.splitlines()
        i = draw(st.integers(0, len(lines) - 1))
        lines.insert(i, lines[i])
        out = "\n".join(lines) + "\n"
    return out


def _flat_strings(data) -> list[tuple]:
    return [(p, _get(data, p)) for p in _paths(data) if isinstance(_get(data, p), str)]


# --------------------------------------------------------------------- bytes on disk
@st.composite
def on_disk(draw, text: str) -> bytes:
    """``text`` as the bytes of a file: UTF-8 as it is (three times in four), cut short, in a
    wrong encoding, with a BOM, or with invalid or NUL bytes inserted."""
    data = text.encode("utf-8")
    if draw(st.booleans()) or draw(st.booleans()):  # three in four files as they are
        return data
    op = draw(st.sampled_from(["truncate", "utf16", "latin1", "bom", "invalid", "nul"]))
    if op == "truncate":
        return data[:draw(st.integers(0, len(data)))]
    if op == "utf16":
        return text.encode(draw(st.sampled_from(["utf-16", "utf-16-le", "utf-32"])))
    if op == "latin1":
        return (text + "é").encode("latin-1", errors="replace")
    if op == "bom":
        return b"\xef\xbb\xbf" + data
    k = draw(st.integers(0, len(data)))
    junk = b"\x00" if op == "nul" else draw(st.sampled_from([b"\xff\xfe", b"\xc3", b"\x80"]))
    return data[:k] + junk + data[k:]


# -------------------------------------------------------------------------- cases
@lru_cache(maxsize=None)
def joint_names(urdf_text: str) -> list[str]:
    """The joint names of a URDF (what a closures file names)."""
    return [j.get("name", "") for j in ET.fromstring(urdf_text).iter("joint")]


@st.composite
def extended_urdf_case(draw, corpus=None) -> tuple[dict, str]:
    """A Gepetto-style folder: its URDF, its YAML or both mutated."""
    urdf, closures = draw(st.sampled_from(corpus or URDF_CORPUS))
    urdf_text, yaml_text = _text(urdf), _text(closures)
    which = draw(st.sampled_from(["urdf", "urdf", "yaml", "both"]))
    if which != "yaml":
        urdf_text = draw(mutated_xml(urdf_text))
    if which != "urdf":
        yaml_text = draw(mutated_yaml(yaml_text, joint_names(_text(urdf))))
    files = {urdf.name: urdf_text.encode(), "robot.yaml": yaml_text.encode()}
    damaged = urdf.name if which != "yaml" else "robot.yaml"
    files[damaged] = draw(on_disk(files[damaged].decode()))
    if urdf.name != "robot.urdf":  # a shipped loop model: its closures file by stem
        files[urdf.with_suffix(".yaml").name] = files.pop("robot.yaml")
    return files, urdf.name


@st.composite
def mjcf_case(draw, corpus=None) -> tuple[dict, str]:
    """An MJCF file mutated (Pinocchio's Cassie, the shipped loop models)."""
    path = draw(st.sampled_from(corpus or MJCF_CORPUS))
    return {"model.xml": draw(on_disk(draw(mutated_xml(_text(path)))))}, "model.xml"


@st.composite
def toml_case(draw, corpus=None) -> tuple[dict, str]:
    """A shipped mechanism file mutated; sometimes the leg URDF it names is mutated too
    (copied beside it)."""
    path = draw(st.sampled_from(corpus or TOML_CORPUS))
    text = toml_with_absolute_paths(path)
    files = {}
    if draw(st.integers(0, 3)) == 0:
        legs = sorted(set(re.findall(r'urdf = "([^"]+)"', text)))
        leg = draw(st.sampled_from(legs))
        files["leg.urdf"] = draw(on_disk(draw(mutated_xml(Path(leg).read_text()))))
        text = text.replace(f'"{leg}"', '"leg.urdf"', draw(st.sampled_from([1, -1])))
        files["m.toml"] = text.encode()
    else:
        files["m.toml"] = draw(on_disk(draw(mutated_toml(text))))
    return files, "m.toml"
