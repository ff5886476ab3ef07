"""plm_pin: analysis of parallel link mechanisms (closed kinematic chains) on Pinocchio.

:func:`load`, :func:`build_mechanism` and :func:`export_mjcf` are imported on first use
(their description readers and writers stay off ``import plm_pin``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._lazy import lazy_exports
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

if TYPE_CHECKING:
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

__getattr__, __dir__ = lazy_exports(
    __name__, {"build_mechanism": ".loading", "export_mjcf": ".export", "load": ".loading"}
)
