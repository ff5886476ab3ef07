"""Closed-chain descriptions: URDF spanning tree plus closure sidecar, or MJCF, read; URDF written.

A built Mechanism is written as MJCF by :mod:`plm_pin.export`.
"""

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
