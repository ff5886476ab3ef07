"""Design sweeps: metrics over builder parameters times task poses, local or on Dask, checkpointed.

:func:`sweep` runs one: ``from plm_pin.sweep import sweep``, then
``sweep("harada2011_3d4m", parameters=..., poses=..., metrics=[...])``, or over the poses of a
Mechanism as it is, ``sweep(plm_pin.load("robot.urdf"), poses=...)``.
Its optional dependencies (``pip install 'plm-pin[sweep]'``: dask, distributed, xarray,
pyarrow) are imported only when a sweep runs.
"""

from __future__ import annotations

from .config import load_config
from .metrics import METRICS, OPTIONS, Metric, Option, Variable
from .result import ChunkFailure, PointFailure, SweepResult
from .run import run_spec, sweep
from .spec import ParameterSpace, SweepSpec, make_spec

__all__ = [
    "METRICS",
    "OPTIONS",
    "ChunkFailure",
    "Metric",
    "Option",
    "ParameterSpace",
    "PointFailure",
    "SweepResult",
    "SweepSpec",
    "Variable",
    "load_config",
    "make_spec",
    "run_spec",
    "sweep",
]
