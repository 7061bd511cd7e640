"""Independent witness: the papers' formulas written out by hand in plain numpy.

Nothing here imports ``pkm_pin`` or Pinocchio; the modules are the hand-written check
of the Pinocchio path. Screw coordinates are axis-first ``(s; s0)`` about the world
origin: twists ``(w; v_O)``, wrenches ``(f; m_O)``; reciprocal product
``a o b = a[:3].b[3:] + a[3:].b[:3]``; SI units, radians.

* :mod:`.rpr3` — planar 3-RPR of seed 000 (Michalková & Guldan), section 5.
* :mod:`.stewart` — Gough-Stewart / l-coordinate body of seed 003 (Demidov 2025).
* :mod:`.serial_reduction` — recursive screw reduction of a serial chain, seed 002
  (anon., Polish, 1987).
* :mod:`.orthoglide` — quasi-orthogonal Orthoglide of seed 001 (Pashkevich &
  Gomolitsky 2007).

The seeds are the four source papers; see docs/references.md.
"""

from .rpr3 import (
    actuation_wrenches,
    constraint_wrenches,
    forward_velocity,
    inverse_position,
    inverse_velocity,
    joint_screws,
    joint_screws_paper,
    leg_joint_screws,
    platform_twists,
    reciprocal_product,
    singularity_condition_61,
    type2_determinant,
    velocity_equation,
    velocity_equation_paper,
)
from .serial_reduction import (
    ChainJoint,
    LinkState,
    chain_kinematics,
    link_screw,
    point_acceleration,
    point_velocity,
    reduction_graph,
)
from .stewart import (
    SEED003_LINES,
    SEED003_TWIST,
    axis_angle_twist,
    forward_position_continuation,
    inverse_jacobian,
    leg_lengths,
    leg_lines,
    move_points,
    quaternion_from_rotation,
    quaternion_multiply,
    relative_rotation,
    rodrigues,
    screw_step,
    seed003_geometry,
    twist_exponential,
)

__all__ = [
    "ChainJoint",
    "LinkState",
    "SEED003_LINES",
    "SEED003_TWIST",
    "actuation_wrenches",
    "axis_angle_twist",
    "chain_kinematics",
    "constraint_wrenches",
    "forward_position_continuation",
    "forward_velocity",
    "inverse_jacobian",
    "inverse_position",
    "inverse_velocity",
    "joint_screws",
    "joint_screws_paper",
    "leg_joint_screws",
    "leg_lengths",
    "leg_lines",
    "link_screw",
    "move_points",
    "platform_twists",
    "point_acceleration",
    "point_velocity",
    "quaternion_from_rotation",
    "quaternion_multiply",
    "reciprocal_product",
    "reduction_graph",
    "relative_rotation",
    "rodrigues",
    "screw_step",
    "seed003_geometry",
    "singularity_condition_61",
    "twist_exponential",
    "type2_determinant",
    "velocity_equation",
    "velocity_equation_paper",
]

# Seed 001 (Pashkevich & Gomolitsky 2007) — quasi-orthogonal Orthoglide (module docstring:
# pkm_pin.formulas.orthoglide).
from . import orthoglide  # noqa: E402
from .orthoglide import OrthoglideParameters  # noqa: E402

__all__ += ["OrthoglideParameters", "orthoglide"]
