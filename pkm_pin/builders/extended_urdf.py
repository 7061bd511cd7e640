"""A base–legs–platform mechanism written as one Extended URDF (URDF + YAML closures).

:func:`write_extended_urdf` writes the tree the way robot files usually cut a parallel
machine open: the tree runs through the first leg to the platform; every other leg ends
where its spherical joint begins, closed on the platform by a point (``3d``) closure at
the joint's centre, or, for a leg that does not end in a spherical joint, at its tip by
a weld (``6d``). Loaded back with :func:`pkm_pin.load_mechanism`, the file describes
the same machine as the legs it was written from (tests and
``benchmarks/bench_one_core.py`` compare them).

Names: every link and joint of leg ``n`` is prefixed ``"leg<n>_"``; the base link is
``base``, the platform link ``platform``, the platform's constraint frames
``platform_anchor_<n>``. A spherical joint is three revolute joints as the chain's last
movable joints whose axes meet at the tip (offsets after the first one zero).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
from lxml import etree

from ..errors import InputError

__all__ = ["write_extended_urdf"]


def write_extended_urdf(mech, folder: str | Path, name: str = "robot") -> Path:
    """Write ``mech`` (legs built from URDF text) as ``folder/<name>.urdf`` and
    ``folder/<name>.yaml``; returns the URDF's path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    robot = etree.Element("robot", name=mech.name.replace(" ", "_") or "mechanism")
    etree.SubElement(robot, "link", name="base")
    etree.SubElement(robot, "link", name="platform")
    pairs, kinds, motors = [], [], []
    for i, (leg, anchor) in enumerate(zip(mech.legs, mech.anchors)):
        if leg.xml is None:
            raise InputError(f"leg {leg.name!r} has no URDF text to write")
        prefix = f"leg{i + 1}_"
        root, joints = _graft(robot, etree.fromstring(leg.xml.encode()), prefix)
        _fixed(robot, f"{prefix}mount", "base", prefix + root, leg.base)
        motors += [prefix + a for a in leg.actuated]
        anchor_link = f"platform_anchor_{i + 1}"
        if i == 0:
            _fixed(robot, f"{prefix}to_platform", prefix + leg.tip, "platform",
                   anchor.inverse())
            continue
        etree.SubElement(robot, "link", name=anchor_link)
        _fixed(robot, f"{anchor_link}_fixed", "platform", anchor_link, anchor)
        socket = _cut_spherical(robot, joints, prefix + leg.tip, prefix)
        pairs.append([socket or prefix + leg.tip, anchor_link])
        kinds.append("3d" if socket else "6d")
    path = folder / f"{name}.urdf"
    path.write_bytes(etree.tostring(robot, pretty_print=True, xml_declaration=True,
                                    encoding="UTF-8"))
    yaml = (f"# {mech.name}: written by pkm_pin.builders.extended_urdf\n"
            f"closed_loop: {pairs!r}\ntype: {kinds!r}\nname_mot: {motors!r}\n"
            "output: platform\n")
    (folder / f"{name}.yaml").write_text(yaml)
    return path


def _graft(robot, leg_robot, prefix: str) -> tuple[str, list]:
    """Copy a leg's links and joints into ``robot`` with ``prefix`` on every name;
    returns the leg's root link and its joints (in file order)."""
    links = [e.get("name") for e in leg_robot.findall("link")]
    children = set()
    joints = []
    for link in leg_robot.findall("link"):
        link.set("name", prefix + link.get("name"))
        robot.append(link)
    for joint in leg_robot.findall("joint"):
        joint.set("name", prefix + joint.get("name"))
        for tag in ("parent", "child"):
            element = joint.find(tag)
            element.set("link", prefix + element.get("link"))
        children.add(joint.find("child").get("link"))
        mimic = joint.find("mimic")
        if mimic is not None:
            mimic.set("joint", prefix + mimic.get("joint"))
        robot.append(joint)
        joints.append(joint)
    roots = [link for link in links if prefix + link not in children]
    return roots[0], joints


def _cut_spherical(robot, joints: list, tip: str, prefix: str) -> str | None:
    """Remove the spherical joint (three revolutes) ending at link ``tip`` and what
    follows it, leaving a link ``<prefix>socket`` at its centre; ``None`` (nothing
    removed) when the chain does not end so."""
    by_child = {j.find("child").get("link"): j for j in joints}
    path, link = [], tip
    while link in by_child:
        path.append(by_child[link])
        link = by_child[link].find("parent").get("link")
    movable = [j for j in path if j.get("type") != "fixed"]
    if len(movable) < 3 or any(j.get("type") not in ("revolute", "continuous")
                               for j in movable[:3]):
        return None
    first = movable[2]  # the spherical's first revolute (path runs from the tip)
    cut = path[:path.index(first) + 1]
    if any(np.linalg.norm(_xyz(j)) > 0 for j in cut[:-1]):
        return None  # the axes do not meet at the tip
    socket = f"{prefix}socket"
    for joint in cut:
        robot.remove(joint)
        child = robot.find(f"link[@name='{joint.find('child').get('link')}']")
        robot.remove(child)
    etree.SubElement(robot, "link", name=socket)
    origin = first.find("origin")
    placement = pin.SE3(pin.rpy.rpyToMatrix(*_rpy(first)), _xyz(first)) if origin is not None \
        else pin.SE3.Identity()
    _fixed(robot, f"{socket}_fixed", first.find("parent").get("link"), socket, placement)
    return socket


def _fixed(robot, name: str, parent: str, child: str, placement: pin.SE3) -> None:
    """Append a fixed joint ``parent`` → ``child`` at ``placement``."""
    joint = etree.SubElement(robot, "joint", name=name, type="fixed")
    etree.SubElement(joint, "parent", link=parent)
    etree.SubElement(joint, "child", link=child)
    rpy = pin.rpy.matrixToRpy(placement.rotation)
    etree.SubElement(joint, "origin", xyz=" ".join(repr(float(x)) for x in placement.translation),
                     rpy=" ".join(repr(float(x)) for x in rpy))


def _xyz(joint) -> np.ndarray:
    origin = joint.find("origin")
    return np.zeros(3) if origin is None else np.array(
        [float(x) for x in origin.get("xyz", "0 0 0").split()])


def _rpy(joint) -> list[float]:
    origin = joint.find("origin")
    return [0.0] * 3 if origin is None else [
        float(x) for x in origin.get("rpy", "0 0 0").split()]

