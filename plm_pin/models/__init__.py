"""Parametric mechanism builders and the registry of named presets."""

from .classic import build_fivebar, build_fourbar
from .prrrp import build_2prrrp, leg_inverse_kinematics
from .registry import PRESETS, Preset, preset_names, urdf_folder

__all__ = [
    "PRESETS",
    "Preset",
    "build_2prrrp",
    "build_fivebar",
    "build_fourbar",
    "leg_inverse_kinematics",
    "preset_names",
    "urdf_folder",
]
