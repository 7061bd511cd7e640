"""pkm_pin: screw-theory analysis of parallel kinematic machines on top of Pinocchio.

Screw coordinates are axis-first, as in the source papers: twists ``(ω; v_O)`` and
wrenches ``(f; m_O)`` about the world origin (see :mod:`pkm_pin.screws`, the one module
that converts to and from Pinocchio's linear-first order).
"""

from .compiling import install_notice, install_stamp

install_notice()  # a compilation of pkm_pin's numba code that lasts says so on stderr
install_stamp()  # its cached machine code is stale once a module compiled into it changes

from . import position, screws  # noqa: E402
from .analysis import Analysis, LegsAnalysis, TreeAnalysis  # noqa: E402
from .calibration import CalibrationResult, calibrate  # noqa: E402
from .errors import (  # noqa: E402
    AssemblyError,
    ForwardKinematicsError,
    FrameNotFound,
    InputError,
    InvalidAssembly,
    JointNotFound,
    MechanismFileError,
    PkmError,
    SingularityError,
    UrdfError,
)
from .io import load_mechanism  # noqa: E402
from .leg import Leg, LegSolution  # noqa: E402
from .mechanism import Assembly, Mechanism  # noqa: E402
from .sensitivity import Sensitivity  # noqa: E402
from .sweep import SweepResult  # noqa: E402
from .transmission import Transmission  # noqa: E402
from .view import view  # noqa: E402
from .workspace import Workspace  # noqa: E402

__version__ = "0.1.0"

__all__ = [
    "Analysis",
    "Assembly",
    "AssemblyError",
    "CalibrationResult",
    "ForwardKinematicsError",
    "FrameNotFound",
    "InputError",
    "InvalidAssembly",
    "JointNotFound",
    "Leg",
    "LegsAnalysis",
    "LegSolution",
    "Mechanism",
    "MechanismFileError",
    "PkmError",
    "Sensitivity",
    "SingularityError",
    "SweepResult",
    "Transmission",
    "TreeAnalysis",
    "UrdfError",
    "Workspace",
    "__version__",
    "calibrate",
    "load_mechanism",
    "position",
    "screws",
    "view",
]
