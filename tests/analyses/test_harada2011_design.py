"""The design-sweep study (analyses/harada2011_design.py): its numbers against Harada 2011's closed forms."""

from __future__ import annotations

import itertools
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from analyses import _harada2011_paper as paper
from plm_pin.families.prrrp import leg_inverse_kinematics

pytestmark = pytest.mark.slow

L = 0.140


@pytest.fixture(scope="module")
def result(report_all):
    """The study's result, from the session's one ``plm-pin report all``."""
    return report_all.study("harada2011_design")


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
    redundancy = result.block("redundancy")
    assert [row[0] for row in redundancy.rows] == [2.0, 2.8, 4.0, 5.6, 8.0]
    assert all(row[4] >= row[2] for row in redundancy.rows)  # the 3D4M never turns less
    rods = result.block("rod_sets")
    asym = next(row for row in rods.rows if row[0] == "l1 = l4 = 0.24, l2 = l3 = 0.17 m")
    assert asym[5] == "no" and asym[6] == pytest.approx(0.07)
    assert np.isclose(asym[1], next(row for row in rods.rows if row[0].startswith("all 0.17"))[1])


def _carriage_length() -> float:
    """Length along the stator of a carriage box in the committed URDF of the 3D4M [m]."""
    urdf = ET.parse(Path(__file__).parents[2] / "urdf" / "harada2011_3d4m.urdf")
    (link,) = [k for k in urdf.getroot().iter("link") if k.get("name") == "carriage1"]
    return float(link.find("visual/geometry/box").get("size").split()[0])


def _apart(rt: float, y: float, theta: float, legs: tuple[int, ...], length: float) -> bool:
    """Whether eq. (2) reaches the pose and every two sliders are at least a carriage length apart."""
    try:
        ik = leg_inverse_kinematics((0.0, y, theta), (L,) * 4, rt, (-1, 1, -1, 1), legs)
    except ValueError:
        return False
    return all(abs(ik[i][0] - ik[k][0]) >= length for i, k in itertools.combinations(legs, 2))


def test_collision_free_ranges_are_the_carriage_gaps(result):
    """The self-collision half-widths are where the carriages stay a carriage length apart.

    By hand: the 2 deg samples about theta = 0 walked while every two sliders of eq. (2) are at
    least the URDF's carriage length apart on the stator, capped by the singularity-free
    half-width; empty when they are closer at theta = 0.
    """
    length = _carriage_length()
    assert length == pytest.approx(0.03)
    angles = np.radians(np.linspace(-80.0, 80.0, 81))

    def halfwidth(rt, y, legs):
        if not _apart(rt, y, 0.0, legs, length):
            return None
        ends = []
        for step in (1, -1):
            k = 40
            while 0 <= k + step < angles.size and _apart(rt, y, float(angles[k + step]), legs, length):
                k += step
            ends.append(abs(math.degrees(float(angles[k]))))
        return min(ends)

    table = result.block("collision")
    assert len(table.rows) == 15
    wider = touching = 0
    for ratio, y, free3, kept3, free4, kept4 in table.rows:
        three, four = (
            None if (h := halfwidth(L / ratio, y, legs)) is None else min(free, h)
            for free, legs in ((free3, (1, 2, 4)), (free4, (1, 2, 3, 4)))
        )
        assert (kept3 is None, kept4 is None) == (three is None, four is None)
        for kept, expected in ((kept3, three), (kept4, four)):
            if expected is not None:
                assert kept == pytest.approx(expected, abs=1e-9)
        wider += three is not None and four is not None and four > three + 1e-9
        touching += three is not None and four is None
    (text,) = [
        b.text for s in result.sections for b in s.blocks if b.kind == "text" and "Of the 15 rows" in b.text
    ]
    assert f"the 3D4M turns further than the 3D3M at {wider}" in text
    assert (f"and at {touching} the carriage of slider 3" in text) == (touching > 0)
    # the carriages bind: at l : 2 r_t = 2 : 1 and y = 0.084 m the 3D4M stops before its 80 deg
    fig6 = next(row for row in table.rows if row[0] == 4.0 and 0.084 < row[1] < 0.0841)
    assert fig6[4] == pytest.approx(80.0) and fig6[5] < fig6[4]


def test_box_fractions_are_eq_2_with_the_carriage_gaps(result):
    """The box fractions of each rod set are those of eq. (2) and of the carriage gaps.

    Reached: every rod short of normal to the stator (where the sweep stops); collision-free:
    reached with every two carriages at least a carriage length apart.
    """
    length = _carriage_length()
    poses = list(
        itertools.product(
            np.linspace(-0.1, 0.1, 9), np.linspace(0.02, 0.24, 12), np.radians(np.linspace(-60.0, 60.0, 13))
        )
    )
    rods = result.block("rod_sets")
    for row in rods.rows:
        lengths = (
            (0.17,) * 4 if row[0].startswith("all 0.17") else (0.24, *(float(row[0].split()[-2]),) * 2, 0.24)
        )
        reached = free = 0
        for x, y, theta in poses:
            pairs = {i: y + (-0.05 if i in (1, 2) else 0.05) * math.sin(theta) for i in (1, 2, 3, 4)}
            if any(abs(pairs[i]) >= lengths[i - 1] - 1e-9 for i in pairs):
                continue  # out of reach, or a rod normal to the stator (a reach limit)
            ik = leg_inverse_kinematics((x, y, theta), lengths, 0.05, (-1, 1, -1, 1), (1, 2, 3, 4))
            reached += 1
            free += all(abs(ik[i][0] - ik[k][0]) >= length for i, k in itertools.combinations(ik, 2))
        assert row[1] == pytest.approx(reached / len(poses), abs=1e-12)
        assert row[7] == pytest.approx(free / len(poses), abs=1e-12)
