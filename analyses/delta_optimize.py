"""A Clavel Delta's base radius, arms and rods chosen by optimisation for a cube workspace.

The Delta of the preset ``delta`` (plm_pin.legs.delta: arm pivots on a 0.20 m circle, arms
0.30 m, parallelogram rods 0.60 m, platform points on a 0.05 m circle) must move its platform
over a cube of 0.2 m side centred 0.5 m below the base. :func:`plm_pin.optimize.run_problem`
chooses the pivots' circle radius R, the arm length l_a and the rod length l_b for the largest
global conditioning index (GCI: the mean of 1 / condition number of the Jacobian over the
cube; the task is positions only, so the index has no mixed units), under the hierarchy: the
whole cube reached in the working mode (elbows out). The preset's design is the start design.
The search runs on the cube's corners, edge and face middles and centre (3 x 3 x 3 positions);
the optimum and the start design are then evaluated on 5 x 5 x 5 positions for the table. The
builder is :func:`plm_pin.legs.delta.build_delta` behind a function of three numbers (its
pivots are points, so the radius is a parameter of that function). Every number it states is
computed here.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from plm_pin.legs import parts
from plm_pin.legs.delta import build_delta
from plm_pin.models import PRESETS
from plm_pin.optimize import evaluate_design, make_problem, run_problem
from plm_pin.report import Column, StudyContext
from plm_pin.report.optimization import add_optimization

TITLE = "A Clavel Delta's base radius, arms and rods chosen by optimisation for a cube workspace"
SUMMARY = (
    "plm_pin.optimize over a Delta's pivot radius, arm and rod lengths (differential evolution): the "
    "largest GCI over a 0.2 m cube, beside the preset's design."
)

CENTRE_Z = -0.5
"""Height of the cube's centre [m] (the preset's reference pose)."""

CUBE = {
    "x": np.linspace(-0.1, 0.1, 5),
    "y": np.linspace(-0.1, 0.1, 5),
    "z": np.linspace(CENTRE_Z - 0.1, CENTRE_Z + 0.1, 5),
}
"""The required cube of platform positions [m]."""

SEARCH_CUBE = {axis: values[::2] for axis, values in CUBE.items()}
"""The cube's corners, edge and face middles and centre (3 x 3 x 3 positions): the search's [m]."""

ANGLES = (0.0, 120.0, 240.0)
"""Directions of the arm pivots and of the platform points about the vertical [deg]."""

VARIABLES = {"base_radius": [0.10, 0.30], "arm": [0.20, 0.40], "forearm": [0.40, 0.80]}
"""R, l_a and l_b [m]."""

CONSTRAINTS = {"reach": 1.0}
"""The constraint hierarchy (the GCI itself keeps the optimum away from singularities)."""

SEARCH: dict[str, Any] = {"generations": 12, "population": 6, "seed": 1985, "tol": 0.0}
"""Differential evolution settings (seeded: the report is reproducible; tol 0: every generation, the GCI
is flat along the ridge of the optimum; the convergence figure shows the last generations' plateau)."""


def build_delta_radius(
    *,
    base_radius: float = 0.20,
    arm: float = 0.30,
    forearm: float = 0.60,
    name: str = "delta",
    source: str = "",
) -> parts.Built:
    """The preset ``delta``, its arm pivots on a circle of ``base_radius`` [m], its arm and rods given [m]."""
    base = tuple(
        (base_radius * math.cos(math.radians(a)), base_radius * math.sin(math.radians(a)), 0.0)
        for a in ANGLES
    )
    preset = dict(PRESETS["delta"].parameters)
    return build_delta(
        **{**preset, "base": base, "arm": arm, "forearm": forearm, "name": name, "source": source}
    )


def run(ctx: StudyContext) -> None:
    """Fill the report."""
    ctx.load("delta")
    search, problem = (
        make_problem(build_delta_radius, VARIABLES, cube, ["gci"], constraints=CONSTRAINTS)
        for cube in (SEARCH_CUBE, CUBE)
    )
    ctx.step("differential evolution over R, l_a and l_b, on 3 x 3 x 3 positions")
    result = run_problem(search, **SEARCH)
    ctx.step("the optimum and the preset's design on 5 x 5 x 5 positions")
    best, start = evaluate_design(problem, result.best.x), evaluate_design(problem, result.start.x)
    r, la, lb = best.x
    at_bounds = [
        f"{v.name} ({'lower' if x - v.lower < v.upper - x else 'upper'})"
        for v, x in zip(problem.variables, best.x, strict=True)
        if min(x - v.lower, v.upper - x) < 1e-3
    ]
    section = ctx.section("The optimum beside the preset's design")
    section.text(
        f"The optimum has R = {r * 1e3:.1f} mm, l_a = {la * 1e3:.1f} mm and l_b = {lb * 1e3:.1f} mm; on the "
        f"5 x 5 x 5 cube it is {best.failed or 'feasible'} with GCI {best.objectives['gci']:.4f} (on the "
        f"search's 3 x 3 x 3 positions {result.best.objectives['gci']:.4f}), against "
        f"{start.objectives['gci']:.4f} for the preset's R = 200 mm, l_a = 300 mm, l_b = 600 mm. "
        + (
            f"Within 1 mm of its bound, which holds the optimum back: {', '.join(at_bounds)}."
            if at_bounds
            else "No variable is within 1 mm of its bounds."
        )
    )
    section.table(
        "The optimum and the preset's design on the 5 x 5 x 5 cube",
        [Column("design"), Column("R", "m"), Column("l_a", "m"), Column("l_b", "m"), Column("GCI"),
         Column("verdict")],
        [
            [name, *e.x, e.objectives["gci"] if e.feasible else None, e.failed or "feasible"]
            for name, e in (("optimum", best), ("preset", start))
        ],
        id="full-cube",
        note="GCI: the mean over the cube's positions of 1 / cond(J), J the Jacobian from the arm angles to "
        "the platform position.",
    )  # fmt: skip
    add_optimization(ctx, result)
