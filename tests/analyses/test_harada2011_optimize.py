"""The optimisation study (analyses/harada2011_optimize.py) against Harada 2011's closed forms."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from analyses import _harada2011_paper as paper
from analyses.harada2011_design import RATIOS, L
from analyses.harada2011_optimize import REGION, SEARCH_REGION, VARIABLES

pytestmark = pytest.mark.slow

LEGS = (1, 2, 3, 4)


def smallest_w(rt: float, l: float, region: dict[str, np.ndarray] = REGION) -> float:
    """Harada 2011 eq. (13) from the paper's J_ce (eqs. (3), (4), (12)), smallest over ``region``."""
    return min(
        float(np.sqrt(np.linalg.det(jce.T @ jce)))
        for pose in itertools.product(*region.values())
        for jce in [paper.leg_matrices(pose, l, rt, LEGS)[3]]
    )


@pytest.fixture(scope="module")
def designs(report_all):
    """The search's start and best designs (its poses), from the session's one ``plm-pin report all``."""
    table = report_all.study("harada2011_optimize").block("optimization-designs")
    return {row[0]: row for row in table.rows}


@pytest.fixture(scope="module")
def full(report_all):
    """The study's table of the optimum and Table 1's design evaluated on the full region."""
    return {row[0]: row for row in report_all.study("harada2011_optimize").block("full-region").rows}


def test_the_paper_design_and_the_optimum_have_the_closed_form_manipulability(designs, full):
    """Table 1's design's and the optimum's smallest w agree with the paper's J_ce to 1e-9 (both regions)."""
    for label in ("start", "best 1"):
        _, rt, l, w = designs[label][:4]
        assert w == pytest.approx(smallest_w(rt, l, SEARCH_REGION), rel=1e-9)
    for label in ("optimum", "Table 1"):
        _, rt, l, w, verdict = full[label]
        assert verdict == "feasible" and w == pytest.approx(smallest_w(rt, l), rel=1e-9)
    assert designs["start"][1:3] == pytest.approx((0.05, 0.14), rel=1e-15)
    assert full["optimum"][1:3] == pytest.approx(designs["best 1"][1:3], rel=1e-15)


def test_the_optimum_beats_table_1_and_the_feasible_ratio_study_designs(full, report_all):
    """No feasible design of the ratio study (l = 0.14 m) has a larger closed-form smallest w."""
    _, rt, _, w, verdict = full["optimum"]
    lower, upper = VARIABLES["half_plate"]
    assert lower <= rt <= upper and verdict == "feasible"
    assert w >= smallest_w(0.05, 0.14)
    grid = report_all.study("harada2011_optimize").block("ratio-grid").rows
    assert [row[0] for row in grid] == list(RATIOS)
    feasible = [smallest_w(L / ratio, L) for ratio, *_, verdict in grid if verdict == "feasible"]
    assert feasible and w >= max(feasible) * (1 - 1e-9)
