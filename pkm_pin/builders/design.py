"""Designs of parallel mechanisms: legs (URDF text, base, anchor) and a home pose.

A :class:`MechanismDesign` is what a builder returns: everything needed to build a
:class:`~pkm_pin.mechanism.Mechanism` or to write it to ``models/`` (URDF files and a
TOML mechanism file). Placements are ``pinocchio.SE3`` in the world frame; lengths [m].

The anchor of a leg is the placement of its tip frame in the platform frame. Builders
compute it with :meth:`LegDesign.assembled` from joint values chosen at home, so that
every design assembles at its home pose by construction: ``home * anchor`` equals the
tip placement of the leg at ``home_q``.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..leg import Leg


@dataclass(frozen=True)
class LegDesign:
    """One leg of a design.

    Attributes:
        name: Leg name.
        urdf: URDF text of the leg.
        tip: Frame of the URDF fixed to the platform.
        actuated: Names of the actuated joints.
        base: Placement of the URDF root in the world.
        anchor: Placement of the tip frame in the platform frame.
        urdf_file: File name under ``models/urdf/`` (legs with the same URDF share it).
    """

    name: str
    urdf: str
    tip: str
    actuated: tuple[str, ...]
    base: pin.SE3
    anchor: pin.SE3
    urdf_file: str

    @classmethod
    def assembled(
        cls,
        name: str,
        urdf: str,
        tip: str,
        actuated: Sequence[str],
        base: pin.SE3,
        q_home: np.ndarray,
        home: pin.SE3,
        urdf_file: str,
    ) -> LegDesign:
        """Leg whose anchor makes it assemble at ``home`` with joint values ``q_home``.

        ``anchor = home⁻¹ · tip_placement(q_home)`` (tip placement in the world).
        """
        leg = Leg.from_urdf(urdf, tip, tuple(actuated), base, name)
        q = leg.check_q(q_home, "q_home")
        if not leg.within_limits(q):
            raise InputError(f"leg {name!r}: home joint values {q} are outside the limits "
                             f"[{leg.lower}, {leg.upper}]")
        anchor = home.inverse() * leg.tip_placement(q)
        return cls(name, urdf, tip, tuple(actuated), base, anchor, urdf_file)

    def leg(self) -> Leg:
        """The :class:`~pkm_pin.leg.Leg` of this design."""
        return Leg.from_urdf(self.urdf, self.tip, self.actuated, self.base, self.name)


@dataclass
class MechanismDesign:
    """A parallel mechanism: legs, home pose of the platform and joint values at home.

    Attributes:
        name: Human-readable name, e.g. ``"3-RPR (seed 000)"``.
        description: One line.
        legs: The legs, in order.
        home: Platform placement at home (world).
        home_q: Joint values of each leg at home (``legs[i]`` has ``home_q[i]``).
        slug: File stem of the mechanism file (``models/mechanisms/<slug>.toml``);
            derived from ``name`` when empty.
        closure: How the legs meet: ``"weld"`` (a rigid platform: a
            :class:`~pkm_pin.Mechanism`) or a pin, ``"spherical"`` / ``"revolute"``
            (:mod:`pkm_pin.model.pinned`: a :class:`~pkm_pin.linkage.Linkage`; ``home``
            is then the pin's placement).
    """

    name: str
    description: str
    legs: list[LegDesign]
    home: pin.SE3
    home_q: list[np.ndarray]
    slug: str = field(default="")
    closure: str = "weld"

    def __post_init__(self) -> None:
        if len(self.home_q) != len(self.legs):
            raise InputError(f"{self.name}: {len(self.legs)} legs but {len(self.home_q)} "
                             "home configurations")
        if not self.slug:
            self.slug = re.sub(r"[^a-z0-9]+", "_", self.name.lower()).strip("_")

    def legs_built(self) -> list[Leg]:
        """The legs as :class:`~pkm_pin.leg.Leg` objects (no Mechanism needed)."""
        return [leg.leg() for leg in self.legs]

    def build(self):
        """The :class:`~pkm_pin.mechanism.Mechanism` of this design (read by the general
        backend, :attr:`~pkm_pin.mechanism.Mechanism.general`, when the legs meet at a
        pin)."""
        from ..mechanism import Mechanism

        if self.closure != "weld":
            from ..model.pinned import pinned_legs

            return Mechanism.from_model(
                pinned_legs(self.legs_built(), [leg.anchor for leg in self.legs],
                            self.closure, name=self.name, home_q=self.home_q),
                description=self.description)

        return Mechanism(
            legs=self.legs_built(),
            anchors=[leg.anchor for leg in self.legs],
            name=self.name,
            home=self.home,
            home_q=[np.array(q, dtype=float) for q in self.home_q],
            description=self.description,
        )

    def urdf_files(self) -> dict[str, str]:
        """URDF text of each distinct file name (``urdf_file`` → text)."""
        files: dict[str, str] = {}
        for leg in self.legs:
            if files.setdefault(leg.urdf_file, leg.urdf) != leg.urdf:
                raise InputError(f"{self.name}: two different URDFs are named {leg.urdf_file!r}")
        return files

    def toml(self) -> str:
        """Text of the mechanism file (URDF paths relative to ``models/mechanisms/``).

        Each leg's ``home_q`` is written too: it selects the working mode at home.
        """
        lines = [f"name = {_string(self.name)}", f"description = {_string(self.description)}"]
        if self.closure != "weld":
            lines.append(f"closure = {_string(self.closure)}")
        for leg, q in zip(self.legs, self.home_q):
            lines += [
                "",
                "[[legs]]",
                f"name = {_string(leg.name)}",
                f"urdf = {_string('../urdf/' + leg.urdf_file)}",
                f"tip = {_string(leg.tip)}",
                f"actuated = [{', '.join(_string(a) for a in leg.actuated)}]",
                f"base = {_inline_placement(leg.base)}",
                f"anchor = {_inline_placement(leg.anchor)}",
                f"home_q = {_numbers(q)}",
            ]
        if self.closure != "weld":  # legs meeting at a pin: home_q is the reference
            return "\n".join(lines + [""])
        xyz, rpy = _xyz_rpy(self.home)
        lines += ["", "[home]", f"xyz = {xyz}", f"rpy = {rpy}", ""]
        return "\n".join(lines)

    def write(self, models_dir: str | Path) -> list[Path]:
        """Write the URDFs to ``models_dir/urdf/`` and the TOML to ``models_dir/mechanisms/``
        (``models_dir/pinned/`` for legs meeting at a pin).

        Returns:
            The paths written.
        """
        models_dir = Path(models_dir)
        folder = models_dir / ("mechanisms" if self.closure == "weld" else "pinned")
        (models_dir / "urdf").mkdir(parents=True, exist_ok=True)
        folder.mkdir(parents=True, exist_ok=True)
        written = []
        for file_name, text in self.urdf_files().items():
            path = models_dir / "urdf" / file_name
            path.write_text(text)
            written.append(path)
        path = folder / f"{self.slug}.toml"
        path.write_text(self.toml())
        written.append(path)
        return written


# ------------------------------------------------------------------------ helpers
def _string(text: str) -> str:
    """A TOML basic string (JSON escaping is valid TOML for these characters)."""
    return json.dumps(text, ensure_ascii=False)


def _numbers(values) -> str:
    return "[" + ", ".join(repr(float(v) + 0.0) for v in values) + "]"  # + 0.0: no "-0.0"


def _xyz_rpy(placement: pin.SE3) -> tuple[str, str]:
    rpy = pin.rpy.matrixToRpy(placement.rotation)
    return _numbers(placement.translation), _numbers(rpy)


def _inline_placement(placement: pin.SE3) -> str:
    xyz, rpy = _xyz_rpy(placement)
    return f"{{ xyz = {xyz}, rpy = {rpy} }}"


def placement(xyz: Sequence[float] = (0.0, 0.0, 0.0),
              rpy: Sequence[float] = (0.0, 0.0, 0.0)) -> pin.SE3:
    """``pin.SE3`` from a translation [m] and URDF roll-pitch-yaw angles [rad]."""
    return pin.SE3(pin.rpy.rpyToMatrix(*map(float, rpy)), np.asarray(xyz, dtype=float))


def frame_with_z(origin, z, x_hint=None) -> pin.SE3:
    """Placement at ``origin`` whose z axis is ``z`` (normalised).

    The x axis is ``x_hint`` made orthogonal to ``z`` when given; otherwise the
    rotation is the smallest one taking the world z axis to ``z``.
    """
    z = np.asarray(z, dtype=float)
    z = z / np.linalg.norm(z)
    if x_hint is not None:
        x = np.asarray(x_hint, dtype=float)
        x = x - x.dot(z) * z
        n = np.linalg.norm(x)
        if n < 1e-9:
            raise InputError(f"x_hint {x_hint} is parallel to z {z}")
        x /= n
        R = np.column_stack([x, np.cross(z, x), z])
    else:
        c = np.cross([0.0, 0.0, 1.0], z)
        s, cz = np.linalg.norm(c), z[2]
        if s < 1e-12:
            R = np.eye(3) if cz > 0 else np.diag([1.0, -1.0, -1.0])
        else:
            R = pin.exp3(c / s * np.arctan2(s, cz))
    return pin.SE3(R, np.asarray(origin, dtype=float))
