"""Descriptions of mechanisms: one kinematic tree plus closures (:mod:`.closure_model`).

Readers of other formats produce the same :class:`ClosureModel`: Extended URDF (a URDF
plus a YAML closures file, :func:`read_extended_urdf`) and MJCF with ``<equality>``
closures (:func:`read_mjcf`).
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
from .extended_urdf import ClosureSpec, find_closures_file, read_closures_file, read_extended_urdf
from .mjcf import read_mjcf

__all__ = [
    "Closure",
    "ClosureModel",
    "ClosureSpec",
    "KINDS",
    "PLATFORM",
    "PLATFORM_JOINT",
    "TreeFrameNotFound",
    "TreeJointNotFound",
    "configuration",
    "find_closures_file",
    "from_mechanism",
    "read_closures_file",
    "read_extended_urdf",
    "read_mjcf",
    "velocity_units",
]
