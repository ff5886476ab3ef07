"""The design-sweep study (analyses/harada2011_design.py): its numbers against Harada 2011's closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analyses import _harada2011_paper as paper
from plm_pin.report import find_study, run_study

pytestmark = pytest.mark.slow

L = 0.140


@pytest.fixture(scope="module")
def result():
    """The study, run once."""
    return run_study(find_study("harada2011_design"))


def _table(result, start: str):
    (table,) = [
        b for s in result.sections for b in s.blocks if b.kind == "table" and b.title.startswith(start)
    ]
    return table


def test_every_paper_claim_agrees(result):
    """Eq. (11.4) at Fig. 6, the 3D4M free of it, the complex singularity of equal rods: all agree."""
    rows = [r for c in result.comparisons() for r in c.rows]
    assert len(rows) == 5 and all(r.agrees for r in rows)


def test_fig6_value_is_eq_11_4(result):
    """At l : 2 r_t = 2 : 1, y = 0.084039 m the 3D3M's range ends at eq. (11.4)'s angle to 1e-9 rad."""
    (row,) = [r for c in result.comparisons() for r in c.rows if r.quantity.startswith("3D3M: |theta|")]
    rt = L / 4.0
    y = (L + rt) * math.sin(math.radians(28.7))
    closed = math.acos(math.sqrt(((L + rt) ** 2 - y**2) / (L + rt) ** 2))
    assert abs(math.radians(row.ours) - closed) < 1e-9


def test_reach_limited_ranges_are_eq_9(result):
    """Where both tables are cut by reach ('equal from y'), the half-width is eq. (9)'s |theta| limit."""
    figures = [b for s in result.sections for b in s.blocks if b.kind == "figure"]
    heat = figures[0].data
    for k, ratio in enumerate(heat["ratio"]):
        rt = L / ratio
        for j, y in enumerate(heat["y"]):
            lo, hi = paper.reachable_sin_interval(y, L, rt)
            limit = math.degrees(min(-math.asin(lo), math.asin(hi), math.radians(80.0)))
            assert heat["3D4M"][k, j] == pytest.approx(limit, abs=1e-6)  # the 3D4M is never singular


def test_tables_answer_the_question(result):
    """The redundancy table covers every ratio; the asymmetric rod set is free of the complex singularity."""
    redundancy = _table(result, "Rotation half-width: the 3D3M at its best height")
    assert [row[0] for row in redundancy.rows] == [2.0, 2.8, 4.0, 5.6, 8.0]
    assert all(row[4] >= row[2] for row in redundancy.rows)  # the 3D4M never turns less
    rods = _table(result, "Rod sets compared")
    asym = next(row for row in rods.rows if row[0] == "l1 = l4 = 0.24, l2 = l3 = 0.17 m")
    assert asym[5] == "no" and asym[6] == pytest.approx(0.07)
    assert np.isclose(asym[1], next(row for row in rods.rows if row[0].startswith("all 0.17"))[1])
