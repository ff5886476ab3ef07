"""plm_pin: analysis of parallel link mechanisms (closed kinematic chains) on Pinocchio."""

import importlib
from typing import Any

from .description.mjcf_writer import export_mjcf
from .exceptions import (
    AllocationInfeasible,
    ClosureNotSatisfied,
    DescriptionError,
    FrameNotFound,
    InvalidInput,
    InverseDynamicsFailed,
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
from .loading import build_mechanism, load
from .mechanism import Mechanism

__version__ = "0.1.0"

__all__ = [
    "AllocationInfeasible",
    "ClosureNotSatisfied",
    "DescriptionError",
    "FrameNotFound",
    "InvalidInput",
    "InverseDynamicsFailed",
    "Mechanism",
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
    "sweep",
]


def __getattr__(name: str) -> Any:
    """``plm_pin.sweep``: the design-sweep package, imported on first use."""
    if name == "sweep":
        return importlib.import_module(".sweep", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
