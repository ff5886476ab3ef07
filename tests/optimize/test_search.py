"""plm_pin.optimize: the optimum of a problem solved independently, resume after a kill, infeasibility."""

from __future__ import annotations

import numpy as np
import pytest

from plm_pin import InvalidInput, NoFeasibleDesign
from plm_pin.optimize import make_problem, optimize, run_problem

from .fivebar_closed_form import best_gci, condition_numbers

X = np.linspace(-0.05, 0.05, 5)
Y = np.linspace(0.2, 0.26, 5)
"""The task region of the five-bar: a 5 x 5 grid of tip positions [m]."""

BOUNDS = {"proximal": [0.06, 0.3], "distal": [0.15, 0.35]}


@pytest.mark.slow
def test_differential_evolution_finds_the_brute_force_gci_within_one_percent() -> None:
    """The five-bar's best GCI over its two link lengths, brute-forced on a fine grid in closed form."""
    xx, yy = np.meshgrid(X, Y, indexing="ij")
    p, d, gci = best_gci(0.2, np.linspace(0.06, 0.3, 241), np.linspace(0.15, 0.35, 201), xx, yy)
    assert 0.06 < p < 0.3 and 0.15 < d < 0.35  # an interior optimum
    result = optimize("fivebar", BOUNDS, {"x": X, "y": Y}, ["gci"], generations=40, population=8, seed=1)
    best = result.best
    assert best.feasible
    assert best.objectives["gci"] >= 0.99 * gci
    assert best.objectives["gci"] <= gci * (
        1 + 1e-3
    )  # the brute force's grid is fine: DE cannot beat it by more
    assert result.parameters()["proximal"] == pytest.approx(p, abs=0.01)


def _small(store: object, progress: object = None) -> object:
    problem = make_problem("fivebar", BOUNDS, {"x": X[::2], "y": Y[::2]}, ["gci", "moving_mass"])
    return run_problem(problem, generations=4, population=4, seed=3, store=store, progress=progress)


def test_a_search_killed_after_two_generations_resumes_to_the_same_result(tmp_path: object) -> None:
    """Interrupted after generation 2 then run again on its store: the designs of an uninterrupted run."""
    whole = _small(tmp_path / "whole")  # type: ignore[operator]

    def kill(generation: int, designs: int) -> None:
        if generation == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _small(tmp_path / "killed", kill)  # type: ignore[operator]
    resumed = _small(tmp_path / "killed")  # type: ignore[operator]
    assert resumed.table().equals(whole.table())  # type: ignore[attr-defined]
    first_three = 1 + 2 * 8  # the start design, then two populations of 4 per variable x 2 variables
    assert resumed.computed == whole.computed - first_three  # type: ignore[attr-defined]


def test_no_design_meets_an_impossible_singularity_margin() -> None:
    """A margin above 1 (the largest normalised margin) cannot be met: the error names that constraint."""
    with pytest.raises(NoFeasibleDesign, match="singularity_margin") as info:
        optimize(
            "fivebar",
            BOUNDS,
            {"x": X[::2], "y": Y[::2]},
            constraints={"singularity_margin": 1.5},
            generations=2,
            population=3,
        )
    assert info.value.constraint == "singularity_margin"
    assert len(info.value.partial.evaluations) > 1  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"variables": {"nope": [0.1, 0.2]}}, "unknown parameter 'nope'"),
        ({"variables": {"proximal": [0.3, 0.1]}}, "not below"),
        ({"constraints": {"fast": 1.0}}, "unknown constraint 'fast'"),
        ({"objectives": ["speed"]}, "unknown objective 'speed'"),
        ({"objectives": [{"metric": "manipulability", "reduce": "median"}]}, "reduce 'median'"),
    ],
)
def test_bad_problems_are_refused_naming_the_entry(kwargs: dict, match: str) -> None:
    """Each bad entry gives InvalidInput naming it and the valid choices."""
    args = {"variables": BOUNDS, "objectives": ["gci"], **kwargs}
    with pytest.raises(InvalidInput, match=match):
        make_problem(
            "fivebar",
            args["variables"],
            {"x": X, "y": Y},
            args["objectives"],
            constraints=args.get("constraints"),
        )


def test_moving_mass_is_the_bars_mass() -> None:
    """The five-bar's four moving bars weigh density x (2 proximal + 2 distal)."""
    problem = make_problem("fivebar", BOUNDS, {"x": X[::2], "y": Y[::2]}, ["moving_mass"])
    from plm_pin.optimize import evaluate_design

    ev = evaluate_design(problem, (0.15, 0.2))
    assert ev.objectives["moving_mass"] == pytest.approx(2.0 * (2 * 0.15 + 2 * 0.2), rel=1e-12)


@pytest.mark.slow
def test_nsga2_front_of_gci_and_mass_is_not_dominated_by_the_brute_force_grid() -> None:
    """Front designs' GCI and mass agree with the closed forms; no grid design beats one by 2 % in both."""
    pytest.importorskip("pymoo")
    result = optimize(
        "fivebar",
        BOUNDS,
        {"x": X[::2], "y": Y[::2]},
        ["gci", "moving_mass"],
        method="nsga2",
        generations=15,
        population=8,
        seed=2,
    )
    front = result.pareto()
    assert len(front) >= 3
    xx, yy = np.meshgrid(X[::2], Y[::2], indexing="ij")
    grid = []
    for p in np.linspace(0.06, 0.3, 61):
        for d in np.linspace(0.15, 0.35, 51):
            c = condition_numbers(0.2, p, d, xx, yy)
            if c is not None:
                grid.append((np.mean(1.0 / c), 2.0 * 2.0 * (p + d)))
    grid_values = np.array(grid)
    for design in front:
        p, d = design.x
        c = condition_numbers(0.2, p, d, xx, yy)
        assert c is not None
        assert design.objectives["gci"] == pytest.approx(np.mean(1.0 / c), rel=1e-9)
        assert design.objectives["moving_mass"] == pytest.approx(4.0 * (p + d), rel=1e-12)
        better = (grid_values[:, 0] > 1.02 * design.objectives["gci"]) & (
            grid_values[:, 1] < design.objectives["moving_mass"] / 1.02
        )
        assert not np.any(better), design


@pytest.mark.slow
def test_designs_evaluated_on_two_dask_workers_equal_those_of_one_process() -> None:
    """The same seed on a local cluster of 2 processes evaluates the same designs, bit for bit."""
    pytest.importorskip("distributed")
    here = _small(None)
    there = make_problem("fivebar", BOUNDS, {"x": X[::2], "y": Y[::2]}, ["gci", "moving_mass"])
    cluster = run_problem(there, generations=4, population=4, seed=3, workers=2)
    assert cluster.table().equals(here.table())  # type: ignore[attr-defined]
