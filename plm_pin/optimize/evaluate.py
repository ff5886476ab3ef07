"""One design evaluated down the constraint hierarchy (:func:`evaluate_design`), and its score.

The mechanism of the design is built and its metrics computed by the sweep's own code
(:class:`plm_pin.sweep.metrics.PointEvaluation`, each analysis once); the constraints are
checked in the order of :attr:`Problem.levels` and the evaluation stops at the first one the
design violates. Its *score*, which a single-objective search minimises, is the weighted sum
of the objectives (each ``sign * value``) for a feasible design; for a design stopped at level
``k`` of ``L`` it is ``PENALTY * (L - k + violation / 2)``, ``violation`` clipped to 1: any
design that passes more levels scores lower, and among those stopped at one level the smaller
violation wins. A feasible design whose objectives cannot be computed (NaN) scores
``PENALTY / 2``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..core.mechanism import Mechanism
from ..sweep.metrics import METRICS, PointEvaluation
from .problem import CONSTRAINTS, REDUCTIONS, Problem, variable_metrics

PENALTY = 1e9
"""Score unit of the infeasible designs [objective units]: feasible objectives must stay below it."""


@dataclass(frozen=True)
class DesignEvaluation:
    """One evaluated design.

    Attributes:
        x: the design variables' values.
        violations: level name -> relative violation (0: met; NaN: not evaluated, the design
            stopped before).
        measures: constraint name -> the number compared with its limit (NaN: not evaluated).
        objectives: objective name -> value (NaN unless the design is feasible).
        failed: the level the design violates ("" when feasible).
        error: the message of the builder or analysis that raised ("" when none did).
    """

    x: tuple[float, ...]
    violations: dict[str, float]
    measures: dict[str, float]
    objectives: dict[str, float]
    failed: str = ""
    error: str = ""

    @property
    def feasible(self) -> bool:
        """Whether the design meets every constraint."""
        return not self.failed

    def constraint_violation(self, problem: Problem) -> float:
        """0 when feasible, else ``L - k + violation / 2`` for a design stopped at level ``k`` of ``L``."""
        if self.feasible:
            return 0.0
        levels = problem.levels
        v = self.violations[self.failed]
        return len(levels) - levels.index(self.failed) + 0.5 * min(1.0, v if math.isfinite(v) else 1.0)

    def signed(self, problem: Problem) -> np.ndarray:
        """``sign * value`` of every objective (each minimised); ``PENALTY`` where infeasible or NaN."""
        values = np.array([o.sign * self.objectives[o.name] for o in problem.objectives])
        if not self.feasible:
            return np.full(values.shape, PENALTY * (1.0 + self.constraint_violation(problem)))
        return np.where(np.isnan(values), PENALTY / 2, values)

    def score(self, problem: Problem) -> float:
        """What a single-objective search minimises (see the module docstring)."""
        if not self.feasible:
            return PENALTY * self.constraint_violation(problem)
        total = sum(o.weight * o.sign * self.objectives[o.name] for o in problem.objectives)
        return PENALTY / 2 if math.isnan(total) else float(total)


def moving_mass(mech: Mechanism) -> float:
    """Mass of every body that moves [kg] (the fixed base is merged into the universe by Pinocchio)."""
    return float(sum(inertia.mass for inertia in mech.model.inertias[1:]))


def evaluate_design(problem: Problem, x: Sequence[float]) -> DesignEvaluation:
    """Evaluate the design ``x`` down the constraint hierarchy, then its objectives if it is feasible."""
    xs = tuple(float(v) for v in x)
    violations = dict.fromkeys(problem.levels, math.nan)
    measures = dict.fromkeys(problem.constraints, math.nan)
    objectives = {o.name: math.nan for o in problem.objectives}

    def stop(level: str, violation: float, error: str = "") -> DesignEvaluation:
        violations[level] = violation
        return DesignEvaluation(xs, violations, measures, objectives, level, error)

    outside = max(
        max(0.0, v.lower - xi, xi - v.upper) / (v.upper - v.lower)
        for v, xi in zip(problem.variables, xs, strict=True)
    )
    if outside > 0.0:
        return stop("bounds", outside)
    violations["bounds"] = 0.0
    spec = problem.design_spec(xs)
    try:
        mech = spec.build(0)
        ev = PointEvaluation(spec.pose_grid(), mech)
    except Exception as exc:  # the builder refuses these dimensions: the design is infeasible
        return stop("build", 1.0, f"{type(exc).__name__}: {exc}")
    violations["build"] = 0.0
    values: dict[str, np.ndarray] = {}

    def need(metric: str) -> None:
        if not any(v.name in values for v in METRICS[metric].variables):
            values.update(METRICS[metric].compute(ev))

    for name, limit in problem.constraints.items():
        constraint = CONSTRAINTS[name]
        try:
            need(constraint.metric)
        except Exception as exc:  # an analysis that fails on this design: it does not meet the level
            return stop(name, 1.0, f"{type(exc).__name__}: {exc}")
        measures[name] = constraint.measure(values)
        violation = constraint.violation(measures[name], limit)
        if violation > 0.0:
            return stop(name, violation)
        violations[name] = 0.0
    by_variable = variable_metrics()
    for o in problem.objectives:
        if o.reduce == "sum":
            objectives[o.name] = moving_mass(mech)
            continue
        need(by_variable[o.variable])
        data = np.asarray(values[o.variable], dtype=float)
        if o.reduce == "area":
            objectives[o.name] = float(np.mean(data)) * problem.measure()
        else:
            objectives[o.name] = REDUCTIONS[o.reduce](data)
    return DesignEvaluation(xs, violations, measures, objectives)
