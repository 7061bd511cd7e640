"""Descriptions of mechanisms: one kinematic tree plus closures (:mod:`.closure_model`).

Readers of other formats (Extended URDF + YAML closures, MJCF ``<equality>``) are to
produce the same :class:`ClosureModel`.
"""

from .closure_model import (
    KINDS,
    PLATFORM,
    PLATFORM_JOINT,
    Closure,
    ClosureModel,
    TreeFrameNotFound,
    TreeJointNotFound,
    configuration,
    from_mechanism,
    velocity_units,
)

__all__ = [
    "Closure",
    "ClosureModel",
    "KINDS",
    "PLATFORM",
    "PLATFORM_JOINT",
    "TreeFrameNotFound",
    "TreeJointNotFound",
    "configuration",
    "from_mechanism",
    "velocity_units",
]
