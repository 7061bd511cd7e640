"""pkm_pin: screw-theory analysis of parallel kinematic machines on top of Pinocchio.

Screw coordinates are axis-first, as in the source papers: twists ``(ω; v_O)`` and
wrenches ``(f; m_O)`` about the world origin (see :mod:`pkm_pin.screws`, the one module
that converts to and from Pinocchio's linear-first order).
"""

from . import position, screws
from .analysis import Analysis
from .calibration import CalibrationResult, calibrate
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
from .leg import Leg, LegSolution
from .mechanism import Assembly, Mechanism, load_mechanism
from .sensitivity import Sensitivity
from .sweep import SweepResult
from .view import view

__version__ = "0.1.0"

__all__ = [
    "Analysis",
    "Assembly",
    "AssemblyError",
    "CalibrationResult",
    "ForwardKinematicsError",
    "FrameNotFound",
    "InputError",
    "JointNotFound",
    "Leg",
    "LegSolution",
    "Mechanism",
    "MechanismFileError",
    "PkmError",
    "Sensitivity",
    "SingularityError",
    "SweepResult",
    "UrdfError",
    "__version__",
    "calibrate",
    "load_mechanism",
    "position",
    "screws",
    "view",
]
