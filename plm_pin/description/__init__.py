"""Closed-chain descriptions: URDF spanning tree plus closure sidecar, or MJCF, read; URDF written.

A built Mechanism is written as MJCF by :mod:`plm_pin.export`. The names below are imported
from their submodules on first use (the core needs the sidecar's types only).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .loader import Description, read_description
    from .mjcf import MjcfDescription, read_mjcf
    from .sidecar import ActuatorSpec, ClosureSpec, Sidecar, TaskSpec, parse_sidecar
    from .writer import write_description

__all__ = [
    "ActuatorSpec",
    "ClosureSpec",
    "Description",
    "MjcfDescription",
    "Sidecar",
    "TaskSpec",
    "parse_sidecar",
    "read_description",
    "read_mjcf",
    "write_description",
]

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ActuatorSpec": ".sidecar",
        "ClosureSpec": ".sidecar",
        "Description": ".loader",
        "MjcfDescription": ".mjcf",
        "Sidecar": ".sidecar",
        "TaskSpec": ".sidecar",
        "parse_sidecar": ".sidecar",
        "read_description": ".loader",
        "read_mjcf": ".mjcf",
        "write_description": ".writer",
    },
)
