"""Fixtures of the analysis tests: the Fig. 6 tables of Harada 2011 (l : 2 r_t = 2 : 1)."""

from __future__ import annotations

import pytest

import plm_pin
from plm_pin.core.mechanism import Mechanism
from plm_pin.description import write_description
from plm_pin.families.prrrp import build_2prrrp
from plm_pin.models import PRESETS

FIG6_L = 0.140
"""Rod length of the Fig. 6 tables [m] (Table 1)."""

FIG6_RT = FIG6_L / 4.0
"""Half plate length of the Fig. 6 tables [m]: l : 2 r_t = 2 : 1."""


@pytest.fixture(scope="session")
def fig6(tmp_path_factory) -> dict[str, Mechanism]:
    """The 3D3M and 3D4M with r_t = l / 4, built, written to a folder and loaded back."""
    folder = tmp_path_factory.mktemp("fig6")
    out = {}
    for preset, key in (("harada2011_3d3m", "3d3m"), ("harada2011_3d4m", "3d4m")):
        params = {**PRESETS[preset].parameters, "half_plate": FIG6_RT}
        robot, sidecar = build_2prrrp(name=f"fig6_{key}", source="Harada 2011 Fig. 6", **params)
        write_description(robot, sidecar, folder, f"fig6_{key}")
        out[key] = plm_pin.load(folder / f"fig6_{key}.urdf")
    return out
