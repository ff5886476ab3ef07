"""The report page of a dimensional synthesis (:mod:`plm_pin.optimize`): sections a study or the CLI adds.

:func:`add_optimization` fills a report with the search (problem and settings), the best
designs beside the start design, where the designs failed in the constraint hierarchy, the
convergence, the Pareto front (two objectives or more), and the best design moving over its
task region (a 3D scene). ``plm-pin optimize --out DIR`` writes it with
:func:`optimization_report`.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..optimize import DesignEvaluation, OptimizationResult
from ..optimize.evaluate import PENALTY
from ..sweep.metrics import PointEvaluation
from .animation import Animation
from .content import Column, StudyResult
from .study import Study, StudyContext, run_study

BEST_SHOWN = 5
"""Distinct feasible designs listed beside the start design."""


def _number(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _design_rows(
    result: OptimizationResult, designs: Sequence[tuple[str, DesignEvaluation]]
) -> list[list[Any]]:
    problem = result.problem
    rows = []
    for label, d in designs:
        row: list[Any] = [label, *d.x]
        row += [_number(d.objectives[o.name]) for o in problem.objectives]
        row += [_number(d.score(problem)), d.failed or "feasible"]
        rows.append(row)
    return rows


def _heading(title: str, text: str) -> str:
    """A section heading: ``title: text``, or ``text`` capitalised."""
    return f"{title}: {text}" if title else text[0].upper() + text[1:]


def best_designs(result: OptimizationResult, count: int = BEST_SHOWN) -> list[DesignEvaluation]:
    """The ``count`` feasible designs of least score, distinct (a design replayed twice counts once)."""
    seen: dict[tuple[float, ...], DesignEvaluation] = {}
    for d in sorted(result.evaluations, key=lambda e: e.score(result.problem)):
        if d.feasible and d.x not in seen:
            seen[d.x] = d
        if len(seen) == count:
            break
    return list(seen.values())


def add_optimization(ctx: StudyContext, result: OptimizationResult, title: str = "") -> None:
    """Add the sections of ``result`` to a report (headings prefixed with ``title`` when given)."""
    from matplotlib.figure import Figure

    problem = result.problem
    names = problem.names
    search = ctx.section(_heading(title, "the problem and the search"))
    search.text(
        f"Mechanism `{problem.spec.label}`; design variables "
        + ", ".join(f"{v.name} in [{v.lower:g}, {v.upper:g}]" for v in problem.variables)
        + "; task region "
        + " x ".join(
            f"{a} {len(v)} values in [{v.min():.4g}, {v.max():.4g}]"
            for a, v in zip(problem.spec.axes, problem.spec.values, strict=True)
        )
        + "; constraints, in the order they are checked: "
        + ", ".join(["bounds", "build", *(f"{k} {v:g}" for k, v in problem.constraints.items())])
        + "; objectives: "
        + ", ".join(f"{o.sense} {o.name} (weight {o.weight:g})" for o in problem.objectives)
        + f". Search: {result.settings['method']}, seed {result.settings['seed']}, "
        f"{len(result.generations) - 1} generations, {len(result.evaluations)} designs "
        f"({result.computed} computed by this run)."
    )
    columns = [Column("design"), *(Column(n) for n in names)]
    columns += [Column(f"{o.name} ({o.sense})") for o in problem.objectives]
    columns += [Column("score (minimised)"), Column("verdict")]
    best = best_designs(result)
    designs = [("start", result.start), *((f"best {k}", d) for k, d in enumerate(best, 1))]
    table = ctx.section(_heading(title, "best designs beside the start design"))
    table.table("Designs", columns, _design_rows(result, designs), id="optimization-designs")
    failed = Counter(e.failed or "feasible" for e in result.evaluations)
    levels = [*problem.levels, "feasible"]
    verdicts = ctx.section(_heading(title, "where the designs stopped in the constraint hierarchy"))
    verdicts.table(
        "Designs by the first level they violate",
        ["level", "designs"],
        [[level, failed.get(level, 0)] for level in levels],
        note="Levels are checked in this order; a design is not evaluated past the first it violates.",
    )
    curve = result.convergence()
    fig = Figure(figsize=(6.0, 3.2))
    ax = fig.subplots()
    feasible = curve < PENALTY / 2
    ax.plot(np.flatnonzero(feasible), curve[feasible], marker="o", markersize=3)
    ax.set_xlabel("generation")
    ax.set_ylabel("best score (weighted objectives)")
    ax.grid(alpha=0.3)
    ctx.section(_heading(title, "convergence")).figure(
        fig,
        "The best score after each generation (generation 0: the start design); generations before the "
        "first feasible design are left out.",
        {"best_score": [_number(float(v)) for v in curve]},
    )
    _design_space(ctx, result, best[0] if best else None, title)
    if len(problem.objectives) >= 2:
        _pareto(ctx, result, title)
    if best:
        _scene(ctx, result, best[0], title)


def _design_space(
    ctx: StudyContext, result: OptimizationResult, best: DesignEvaluation | None, title: str
) -> None:
    """Every evaluated design in its first two variables, marked by the level it stopped at.

    With one variable the designs are plotted against their evaluation order; the best is circled.
    """
    from matplotlib.figure import Figure

    names = result.problem.names
    x = np.array([e.x for e in result.evaluations], dtype=float).reshape(len(result.evaluations), -1)
    second = x[:, 1] if x.shape[1] > 1 else np.arange(len(x), dtype=float)
    fig = Figure(figsize=(5.0, 4.0))
    ax = fig.subplots()
    levels = [*result.problem.levels, "feasible"]
    for k, level in enumerate(levels):
        mask = np.array([(e.failed or "feasible") == level for e in result.evaluations])
        if mask.any():
            ax.scatter(x[mask, 0], second[mask], s=10, color=f"C{k % 10}", label=f"{level} ({mask.sum()})")
    if best is not None:
        bx = best.x[1] if x.shape[1] > 1 else second[result.evaluations.index(best)]
        ax.scatter([best.x[0]], [bx], s=120, facecolors="none", edgecolors="k", label="best")
    ax.set_xlabel(names[0])
    ax.set_ylabel(names[1] if x.shape[1] > 1 else "design number (evaluation order)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ctx.section(_heading(title, "the designs evaluated")).figure(
        fig,
        "Every evaluated design, coloured by the first constraint level it violates (feasible: none), "
        "the best design circled"
        + ("." if x.shape[1] > 1 else "; one variable, so plotted against the evaluation order.")
        + (f" Variables beyond {names[0]} and {names[1]} are not shown." if x.shape[1] > 2 else ""),
        {"x": x.tolist(), "failed": [e.failed for e in result.evaluations]},
    )


def _pareto(ctx: StudyContext, result: OptimizationResult, title: str) -> None:
    from matplotlib.figure import Figure

    first, second = result.problem.objectives[:2]
    feasible = [e for e in result.evaluations if e.feasible]
    front = result.pareto()
    fig = Figure(figsize=(5.0, 4.0))
    ax = fig.subplots()
    ax.scatter(
        [e.objectives[first.name] for e in feasible],
        [e.objectives[second.name] for e in feasible],
        s=8,
        color="0.7",
        label="feasible designs",
    )
    ordered = sorted(front, key=lambda e: e.objectives[first.name])
    ax.plot(
        [e.objectives[first.name] for e in ordered],
        [e.objectives[second.name] for e in ordered],
        marker="o",
        color="C3",
        label="Pareto front",
    )
    ax.set_xlabel(f"{first.name} ({first.sense})")
    ax.set_ylabel(f"{second.name} ({second.sense})")
    ax.legend()
    ctx.section(_heading(title, "Pareto front")).figure(
        fig,
        f"The feasible designs and their non-dominated front in ({first.name}, {second.name}).",
        {"front": [list(e.x) for e in ordered]},
    )


def _scene(ctx: StudyContext, result: OptimizationResult, best: DesignEvaluation, title: str) -> None:
    spec = result.problem.design_spec(best.x)
    mech = spec.build(0)
    grid = PointEvaluation(spec.pose_grid(), mech).grid
    reached = np.asarray(grid.reachable).reshape(-1)
    qs = np.asarray(grid.q).reshape(-1, mech.nq)[reached]
    if len(qs) < 2:
        return
    animation = Animation(
        mech,
        qs,
        np.arange(len(qs), dtype=float) * 0.1,
        f"The best design moving over the {len(qs)} reached poses of its task region, row by row.",
    )
    ctx.load(mech)
    ctx.section(_heading(title, "the best design over its task region")).animation(animation)


def optimization_report(result: OptimizationResult, command: str = "") -> StudyResult:
    """The report of an optimisation on its own (what ``plm-pin optimize`` writes)."""
    study = Study(
        name="optimization",
        title=f"Design optimisation of {result.problem.spec.label}",
        summary="plm_pin.optimize: best designs, constraint verdicts, convergence.",
        mechanism=None,
        run=lambda ctx: add_optimization(ctx, result),
    )
    return run_study(study, command=command)
