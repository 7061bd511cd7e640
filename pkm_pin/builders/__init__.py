"""Parametric builders of parallel mechanisms: legs written as URDF with yourdfpy.

Each builder returns a :class:`MechanismDesign` (legs with URDF text, base placements
and anchors, a home pose at which it assembles); :data:`MECHANISMS` names them.
Regenerate the committed models with ``python -m pkm_pin.builders``.
"""

from .design import LegDesign, MechanismDesign
from .orthoglide import orthoglide, orthoglide_quasi
from .pinned import delta_point, five_bar
from .planar import (
    rpr3,
    rpr3_type2_pose,
    rpr3_wrench_lines,
    rrr3,
    rrr3_elbow_signs,
    rrr3_stretched_pose,
)
from .spatial import (
    agile_eye,
    delta,
    prs3,
    rps3,
    stewart,
    stewart_default_points,
    upu3,
    upu3_constraint_singular_pose,
)
from .urdf_writer import JointSpec, chain_robot, chain_urdf, robot_to_xml

#: Builder of every mechanism of the project, by registry name (same signature:
#: ``builder(scale=1.0, **geometry) -> MechanismDesign``; ``stewart`` takes its points first).
MECHANISMS = {
    "rpr3": rpr3,
    "rrr3": rrr3,
    "stewart": stewart,
    "delta": delta,
    "upu3": upu3,
    "rps3": rps3,
    "prs3": prs3,
    "agile_eye": agile_eye,
    "orthoglide": orthoglide,
    "orthoglide_quasi": orthoglide_quasi,
}

#: One line per registry entry.
DESCRIPTIONS = {
    "rpr3": "planar 3-RPR of seed 000 (xz-plane), actuated A1 (P), B0 (R), C1 (P)",
    "rrr3": "planar 3-RRR (xy-plane), first revolute of each leg actuated",
    "stewart": "6-UPS Gough–Stewart platform, classic 6-6 layout, prismatic actuators",
    "delta": "Delta robot, parallelograms as mimic joints, 3T with 3 redundant constraints",
    "upu3": "3-UPU translational mechanism (Tsai), prismatic actuators, 3T",
    "rps3": "3-RPS mechanism, prismatic actuators, 1T2R",
    "prs3": "3-PRS mechanism, vertical prismatic actuators on the base, 1T2R",
    "agile_eye": "agile eye (spherical 3-RRR), nine revolute axes through one centre, 3R",
    "orthoglide": "Orthoglide of seed 001, 3 P-R-Pa-R legs on orthogonal prismatic actuators, 3T",
    "orthoglide_quasi": "Orthoglide with tilted/offset actuator axes, unequal legs (seed 001), 3T",
}

__all__ = [
    "DESCRIPTIONS",
    "JointSpec",
    "LegDesign",
    "MECHANISMS",
    "PINNED",
    "delta_point",
    "five_bar",
    "MechanismDesign",
    "agile_eye",
    "chain_robot",
    "chain_urdf",
    "delta",
    "orthoglide",
    "orthoglide_quasi",
    "prs3",
    "robot_to_xml",
    "rpr3",
    "rpr3_type2_pose",
    "rpr3_wrench_lines",
    "rps3",
    "rrr3",
    "rrr3_elbow_signs",
    "rrr3_stretched_pose",
    "stewart",
    "stewart_default_points",
    "upu3",
    "upu3_constraint_singular_pose",
]

#: Builders of the mechanisms whose legs meet at a pin (``models/pinned/``; each builds a
#: :class:`~pkm_pin.linkage.Linkage`).
PINNED = {
    "five_bar": five_bar,
    "delta_point": delta_point,
}
