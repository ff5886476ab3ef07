"""Design sweeps: metrics over builder parameters times task poses, local or on Dask, checkpointed.

:func:`sweep` runs one: ``from plm_pin.sweep import sweep``, then
``sweep("harada2011_3d4m", parameters=..., poses=..., metrics=[...])``, or over the poses of a
Mechanism as it is, ``sweep(plm_pin.load("robot.urdf"), poses=...)``.
Its optional dependencies (``pip install 'plm-pin[sweep]'``: dask, distributed, xarray,
pyarrow) are imported only when a sweep runs.
"""

from __future__ import annotations

from .config import load_config, spec_from_config
from .execution import DEFAULT_CHUNK, Chunk, ChunkValues, evaluate_chunk, plan_chunks
from .metrics import METRICS, OPTIONS, Metric, Option, Variable
from .result import ChunkFailure, PointFailure, SweepResult, build_dataset
from .run import run_spec, sweep
from .spec import ParameterSpace, SweepSpec, make_spec, mechanism_digest
from .store import SweepStore

__all__ = [
    "DEFAULT_CHUNK",
    "METRICS",
    "OPTIONS",
    "Chunk",
    "ChunkFailure",
    "ChunkValues",
    "Metric",
    "Option",
    "ParameterSpace",
    "PointFailure",
    "SweepResult",
    "SweepSpec",
    "SweepStore",
    "Variable",
    "build_dataset",
    "evaluate_chunk",
    "load_config",
    "make_spec",
    "mechanism_digest",
    "plan_chunks",
    "run_spec",
    "spec_from_config",
    "sweep",
]
