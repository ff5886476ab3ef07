"""The registry of named presets (papers' mechanisms and test linkages) built by the families' builders."""

from .registry import PRESETS, Preset, preset_names, urdf_folder

__all__ = [
    "PRESETS",
    "Preset",
    "preset_names",
    "urdf_folder",
]
