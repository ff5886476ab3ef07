"""The Harada 2015 study (analyses/harada2015.py): its claims against the paper's text."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def result(report_all):
    """The study's result, from the session's one ``plm-pin report all``."""
    return report_all.study("harada2015")


def test_every_paper_claim_agrees(result):
    """All counted rows agree; the rod lengths, inputs of the study, are echoes not counted as agreements."""
    (table,) = result.comparisons()
    assert table.n_agree == table.n_counted >= 14
    echoes = [r.quantity for r in table.rows if r.verdict == "input echo"]
    assert echoes == [f"rod length l{i} (Fig. 2)" for i in range(1, 5)]


def test_routes_are_the_papers(result):
    """The routes found are the paper's (Sec. V); nine assembly modes (Sec. III)."""
    rows = {r.quantity: r for r in result.comparisons()[0].rows}
    assert (
        rows["singularity-free route [+ +] to [- -] (Fig. 6, Sec. V)"].ours
        == "[+ +] → [+ 0] → [+ -] → [0 -] → [- -]"
    )
    assert rows["working-mode change (Fig. 7, Sec. V)"].ours == "(- + - +) → (- + 0 +) → (- + + +)"
    assert rows["assembly modes of the 2-PRRRP (Sec. III)"].ours == 9


def test_figures_and_animations(result):
    """Graph, both changes with snapshots, and two animations whose times are increasing."""
    figures = [b for s in result.sections for b in s.blocks if b.kind == "figure"]
    scenes = [b for s in result.sections for b in s.blocks if b.kind == "scene"]
    assert len(figures) == 5 and len(scenes) == 2
    for scene in scenes:
        assert len(scene.data["qs"]) == len(scene.data["times"]) > 50
    assert [m.name for m in result.mechanisms] == [
        "harada2015_asymmetric",
        "harada2015_asymmetric_symmetric_240mm",
        "harada2011_3d3m",
    ]
