"""The optimisation study (analyses/harada2011_optimize.py) against Harada 2011's closed forms."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from analyses import _harada2011_paper as paper
from analyses.harada2011_design import RATIOS, L
from analyses.harada2011_optimize import REGION, VARIABLES

pytestmark = pytest.mark.slow

LEGS = (1, 2, 3, 4)


def smallest_w(rt: float, l: float) -> float:
    """Harada 2011 eq. (13) from the paper's J_ce (eqs. (3), (4), (12)), smallest over the region."""
    return min(
        float(np.sqrt(np.linalg.det(jce.T @ jce)))
        for pose in itertools.product(*REGION.values())
        for jce in [paper.leg_matrices(pose, l, rt, LEGS)[3]]
    )


@pytest.fixture(scope="module")
def designs(report_all):
    """The study's table of the start and best designs, from the session's one ``plm-pin report all``."""
    table = report_all.study("harada2011_optimize").block("optimization-designs")
    return {row[0]: row for row in table.rows}


def test_the_paper_design_and_the_optimum_have_the_closed_form_manipulability(designs):
    """The smallest w of Table 1's design and of the optimum agree with the paper's J_ce to 1e-9."""
    for label in ("start", "best 1"):
        _, rt, l, w = designs[label][:4]
        assert w == pytest.approx(smallest_w(rt, l), rel=1e-9)
    assert designs["start"][1:3] == pytest.approx((0.05, 0.14), rel=1e-15)


def test_the_optimum_beats_table_1_and_the_feasible_ratio_study_designs(designs, report_all):
    """No feasible design of the ratio study (l = 0.14 m) has a larger closed-form smallest w."""
    _, rt, _, w = designs["best 1"][:4]
    lower, upper = VARIABLES["half_plate"]
    assert lower <= rt <= upper and designs["best 1"][-1] == "feasible"
    assert w >= smallest_w(0.05, 0.14)
    grid = report_all.study("harada2011_optimize").block("ratio-grid").rows
    assert [row[0] for row in grid] == list(RATIOS)
    feasible = [smallest_w(L / ratio, L) for ratio, *_, verdict in grid if verdict == "feasible"]
    assert feasible and w >= max(feasible) * (1 - 1e-9)
