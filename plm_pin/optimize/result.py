"""What an optimisation returns: every evaluated design, the best one, the Pareto front, the convergence."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..exceptions import NoFeasibleDesign
from .evaluate import DesignEvaluation
from .problem import Problem
from .store import to_row

if TYPE_CHECKING:
    import pandas as pd


@dataclass(frozen=True)
class OptimizationResult:
    """The designs an optimisation evaluated, generation by generation.

    Attributes:
        problem: the problem.
        settings: the search: method, generations, population, seed, tol.
        generations: each generation's evaluated designs, in order (0: the start design).
        computed: designs evaluated by this run (the others were replayed from the store).
        elapsed: wall time of the run [s].
        store: the checkpoint folder, or None.
    """

    problem: Problem
    settings: Mapping[str, Any]
    generations: list[list[DesignEvaluation]]
    computed: int
    elapsed: float
    store: Path | None = None

    @property
    def evaluations(self) -> list[DesignEvaluation]:
        """Every evaluated design, in order."""
        return [e for gen in self.generations for e in gen]

    @property
    def start(self) -> DesignEvaluation:
        """The start design."""
        return self.generations[0][0]

    @property
    def best(self) -> DesignEvaluation:
        """The design of least score (:meth:`DesignEvaluation.score`), the first one on a tie."""
        scores = [e.score(self.problem) for e in self.evaluations]
        return self.evaluations[int(np.argmin(scores))]

    def parameters(self, design: DesignEvaluation | None = None) -> dict[str, Any]:
        """The builder parameters a design (default: the best) sets."""
        design = self.best if design is None else design
        return {v.name: v.value(x) for v, x in zip(self.problem.variables, design.x, strict=True)}

    def pareto(self) -> list[DesignEvaluation]:
        """The feasible designs no other feasible design dominates (objectives with their senses)."""
        feasible = [e for e in self.evaluations if e.feasible]
        if not feasible:
            return []
        f = np.array([e.signed(self.problem) for e in feasible])
        keep: list[int] = []
        for i, fi in enumerate(f):
            dominated = np.any(np.all(f <= fi, axis=1) & np.any(f < fi, axis=1))
            duplicate = any(np.array_equal(fi, f[j]) for j in keep)
            if not dominated and not duplicate:
                keep.append(i)
        return [feasible[i] for i in keep]

    def convergence(self) -> np.ndarray:
        """The best score after each generation, shape (generations,)."""
        best = [min(e.score(self.problem) for e in gen) for gen in self.generations]
        return np.minimum.accumulate(np.array(best))

    def table(self) -> pd.DataFrame:
        """Every evaluated design as a row: generation, variables, violations, measures, objectives, score."""
        import pandas as pd

        rows = [
            to_row(self.problem, g, i, e) for g, gen in enumerate(self.generations) for i, e in enumerate(gen)
        ]
        return pd.DataFrame(rows)


def check_feasible(result: OptimizationResult) -> None:
    """Raise :class:`~plm_pin.exceptions.NoFeasibleDesign` when no evaluated design is feasible.

    Raises:
        NoFeasibleDesign: naming the furthest level of the hierarchy a design got to, which none met.
    """
    evaluations = result.evaluations
    if any(e.feasible for e in evaluations):
        return
    levels = result.problem.levels
    deepest = max(levels.index(e.failed) for e in evaluations)
    level = levels[deepest]
    violation = min(e.violations[level] for e in evaluations if e.failed == level)
    limit = result.problem.constraints.get(level)
    what = {"bounds": "the bounds", "build": "the builder (it refused every design's dimensions)"}.get(
        level, f"constraint {level!r} (limit {limit:g})" if limit is not None else level
    )
    errors = sorted({e.error for e in evaluations if e.failed == level and e.error})
    hint = f"; errors: {errors[:3]}" if errors else ""
    raise NoFeasibleDesign(
        f"no design of {len(evaluations)} evaluated met {what}: the smallest violation was "
        f"{violation:.3g} (relative){hint}; relax it, widen the bounds or change the task region",
        level,
        violation if math.isfinite(violation) else math.nan,
        result,
    )
