"""Dimensional synthesis: builder parameters meeting a ranked hierarchy of constraints, optimising objectives.

:func:`optimize` runs one: ``from plm_pin.optimize import optimize``, then
``optimize("harada2011_3d4m", {"half_plate": [0.02, 0.08]}, poses={...}, objectives=["gci"],
constraints={"singularity_margin": 0.01})``. A design is a parameter point of a sweep
(:mod:`plm_pin.sweep`), evaluated over the task region by the sweep's metrics. The default
search is SciPy's differential evolution; NSGA-II (Pareto fronts) needs ``pip install
'plm-pin[optimize]'`` (pymoo). Checkpoints and Dask execution need the ``sweep`` extra.
"""

from __future__ import annotations

from .config import load_config
from .evaluate import DesignEvaluation, evaluate_design
from .problem import CONSTRAINTS, OBJECTIVES, Problem, make_problem
from .result import OptimizationResult
from .search import METHODS, optimize, run_problem

__all__ = [
    "CONSTRAINTS",
    "METHODS",
    "OBJECTIVES",
    "DesignEvaluation",
    "OptimizationResult",
    "Problem",
    "evaluate_design",
    "load_config",
    "make_problem",
    "optimize",
    "run_problem",
]
