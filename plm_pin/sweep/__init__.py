"""Design sweeps: metrics over builder parameters times task poses, local or on Dask, checkpointed.

``plm_pin.sweep`` is this package and, called, its :func:`sweep` function:
``plm_pin.sweep("harada2011_3d4m", parameters=..., poses=..., metrics=[...])``, or over the
poses of a Mechanism as it is, ``plm_pin.sweep(plm_pin.load("robot.urdf"), poses=...)``.
Its optional dependencies (``pip install 'plm-pin[sweep]'``: dask, distributed, xarray,
pyarrow) are imported only when a sweep runs.
"""

from __future__ import annotations

import sys
import types
from typing import Any

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


class _CallableModule(types.ModuleType):
    """This package, callable as :func:`sweep` (so that ``plm_pin.sweep(...)`` runs a sweep)."""

    def __call__(self, *args: Any, **kwargs: Any) -> SweepResult:
        return sweep(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
