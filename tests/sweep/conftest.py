"""Fixtures of the sweep tests: small Harada 2011 sweeps, a builder that fails on purpose, a Dask cluster."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from plm_pin.families.prrrp import build_2prrrp
from plm_pin.models import PRESETS

FIG6_L = 0.140
"""Rod length of Harada 2011 Fig. 6 and Table 1 [m]."""

FIG6_RT = FIG6_L / 4.0
"""Half plate length of Fig. 6 [m]: l : 2 r_t = 2 : 1."""

FIG6_Y = (FIG6_L + FIG6_RT) * math.sin(math.radians(28.7))
"""The height where eq. (11.4) puts the 3D3M's type-4 singularity at |theta| = 28.7 deg [m] (0.084039 m)."""

THETAS = np.radians(np.linspace(-80.0, 80.0, 33))
"""Plate angles of the small sweeps [rad]: 5 deg samples over Fig. 6's range."""


@pytest.fixture(scope="session")
def cluster():
    """A Dask LocalCluster of 2 single-threaded worker processes on loopback (shared by the sweep tests)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address="127.0.0.1:0"
    ) as local:
        yield local


def small(**changes: Any) -> dict[str, Any]:
    """Arguments of a small sweep: 3D3M and 3D4M, two plate sizes, three heights, 33 angles."""
    kwargs: dict[str, Any] = {
        "mechanism": "harada2011_3d4m",
        "parameters": {"legs": [[1, 2, 4], [1, 2, 3, 4]], "half_plate": [FIG6_RT, 0.05]},
        "poses": {"y": [0.05, FIG6_Y, 0.11], "rz": THETAS},
        "pose": (0.0, 0.08, 0.0),  # x = 0 exactly (the reference pose's x is 0 to round-off only)
        "metrics": ["manipulability", "singularity", "min_manipulability", "orientation_range"],
        "options": {"over": ["rz"]},
    }
    kwargs.update(changes)
    return kwargs


def fragile_2prrrp(
    *, name: str, half_plate: float, legs: tuple[int, ...] = (1, 2, 4), source: str = ""
) -> Any:
    """The Harada 2011 table, refusing plates longer than 0.06 m (a deterministic failure for the tests)."""
    if half_plate > 0.06:
        raise RuntimeError(f"fragile builder refuses half_plate = {half_plate} m")
    params = {**PRESETS["harada2011_3d3m"].parameters, "half_plate": half_plate, "legs": legs}
    return build_2prrrp(name=name, source=source, **params)
