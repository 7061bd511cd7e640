"""pkm_pin: screw-theory analysis of parallel kinematic machines on top of Pinocchio.

Screw coordinates are axis-first, as in the source papers: twists ``(ω; v_O)`` and
wrenches ``(f; m_O)`` about the world origin (see :mod:`pkm_pin.screws`, the one module
that converts to and from Pinocchio's linear-first order).
"""

from . import screws
from .errors import (
    AssemblyError,
    ForwardKinematicsError,
    FrameNotFound,
    InputError,
    JointNotFound,
    MechanismFileError,
    PkmError,
    SingularityError,
    UrdfError,
)
from .analysis import Analysis
from .leg import Leg, LegSolution
from .mechanism import Assembly, Mechanism, load_mechanism

__version__ = "0.1.0"

__all__ = [
    "Analysis",
    "Assembly",
    "AssemblyError",
    "ForwardKinematicsError",
    "FrameNotFound",
    "InputError",
    "JointNotFound",
    "Leg",
    "LegSolution",
    "Mechanism",
    "MechanismFileError",
    "PkmError",
    "SingularityError",
    "UrdfError",
    "__version__",
    "load_mechanism",
    "screws",
]
