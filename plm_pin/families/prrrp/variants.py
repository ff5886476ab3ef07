"""Variants of the 2-PRRRP presets built in memory (not registered)."""

from __future__ import annotations

import math

from ...description.loader import description_from_text
from ...description.writer import urdf_text
from ...exceptions import InvalidInput
from ...loading import mechanism_from_description
from ...mechanism import Mechanism
from ...models.registry import PRESETS
from .builder import build_2prrrp, rod_scaled

__all__ = ["symmetric_variant"]


def symmetric_variant(
    rod_length: float = 0.240, *, base: str = "harada2015_asymmetric", name: str | None = None
) -> Mechanism:
    """A 2-PRRRP like the preset ``base`` but with every rod ``rod_length`` [m] long.

    Rod masses and inertias scale from the 2011 rod (Table 1) as in the 2015 preset; the
    other parameters are the preset's. Built in memory, not registered.
    """
    if base not in PRESETS or PRESETS[base].builder is not build_2prrrp:
        raise InvalidInput(f"base must be a 2-PRRRP preset, got {base!r}")
    if not (math.isfinite(rod_length) and rod_length > 0.0):
        raise InvalidInput(f"rod_length must be a positive length [m], got {rod_length!r}")
    preset = PRESETS[base]
    params = dict(preset.parameters)
    scaled = rod_scaled(rod_length, 0.140, 0.026, 9.84e-5)
    params.update(
        rod_lengths=(rod_length,) * 4,
        rod_masses=(scaled[0],) * 4,
        rod_inertias=(scaled[1],) * 4,
    )
    label = name or f"{base}_symmetric_{round(rod_length * 1000)}mm"
    robot, sidecar = preset.builder(name=label, source=f"{preset.source}; all rods {rod_length} m", **params)
    description = description_from_text(urdf_text(robot), sidecar.to_yaml())
    return mechanism_from_description(description, label)
