"""plm_pin: analysis of parallel link mechanisms (closed kinematic chains) on Pinocchio."""

from ._version import __version__
from .core.mechanism import Mechanism
from .exceptions import (
    AllocationInfeasible,
    ClosureNotSatisfied,
    DescriptionError,
    FrameNotFound,
    InvalidInput,
    InverseDynamicsFailed,
    JointLimitExceeded,
    NoFeasibleDesign,
    PartialResultError,
    PlmError,
    PoseUnreachable,
    SchedulerUnreachable,
    SimulationFailed,
    SingularConfiguration,
    StoreLocked,
    StoreMismatch,
    TrajectoryError,
    ViewerError,
)
from .export import export_mjcf
from .loading import build_mechanism, load

__all__ = [
    "AllocationInfeasible",
    "ClosureNotSatisfied",
    "DescriptionError",
    "FrameNotFound",
    "InvalidInput",
    "InverseDynamicsFailed",
    "JointLimitExceeded",
    "Mechanism",
    "NoFeasibleDesign",
    "PartialResultError",
    "PlmError",
    "PoseUnreachable",
    "SchedulerUnreachable",
    "SimulationFailed",
    "SingularConfiguration",
    "StoreLocked",
    "StoreMismatch",
    "TrajectoryError",
    "ViewerError",
    "__version__",
    "build_mechanism",
    "export_mjcf",
    "load",
]
