"""Closed-chain descriptions: URDF spanning tree plus closure sidecar, or MJCF, read; URDF written.

A built Mechanism is written as MJCF by :mod:`plm_pin.export`.
"""

from .interop import parse_epr_sidecar
from .loader import Description, build_model, build_visual_model, description_from_text, read_description
from .mjcf import MjcfDescription, StateMap, read_mjcf
from .sidecar import ActuatorSpec, ClosureSpec, Sidecar, TaskSpec, parse_sidecar
from .urdf import UrdfSource, read_urdf, read_urdf_text
from .writer import urdf_text, write_description

__all__ = [
    "ActuatorSpec",
    "ClosureSpec",
    "Description",
    "MjcfDescription",
    "Sidecar",
    "StateMap",
    "TaskSpec",
    "UrdfSource",
    "build_model",
    "build_visual_model",
    "description_from_text",
    "parse_epr_sidecar",
    "parse_sidecar",
    "read_description",
    "read_mjcf",
    "read_urdf",
    "read_urdf_text",
    "urdf_text",
    "write_description",
]
