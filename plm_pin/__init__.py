"""plm_pin: analysis of parallel link mechanisms (closed kinematic chains) on Pinocchio."""

from .exceptions import (
    AllocationInfeasible,
    ClosureNotSatisfied,
    DescriptionError,
    FrameNotFound,
    InvalidInput,
    PlmError,
    PoseUnreachable,
    SimulationFailed,
    SingularConfiguration,
    TrajectoryError,
)
from .loading import build_mechanism, load
from .mechanism import Mechanism

__version__ = "0.1.0"

__all__ = [
    "AllocationInfeasible",
    "ClosureNotSatisfied",
    "DescriptionError",
    "FrameNotFound",
    "InvalidInput",
    "Mechanism",
    "PlmError",
    "PoseUnreachable",
    "SimulationFailed",
    "SingularConfiguration",
    "TrajectoryError",
    "__version__",
    "build_mechanism",
    "load",
]
