"""The Enferadi 2017 study (analyses/enferadi2017.py): forces along both paths and the round trip."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def result(report_all):
    """The study's result, from the session's one ``plm-pin report all``."""
    return report_all.study("enferadi2017")


def test_forces_match_the_corrected_lagrange_equations_and_the_path_is_retraced(result):
    """Both paths: forces at the spec's times to 1e-6 N, direct dynamics back on the path to 1e-6 m."""
    for name in ("line", "circle"):
        rows = result.block(f"{name}_forces").rows
        assert all(r.agrees for r in rows), [r.quantity for r in rows if not r.agrees]
        (trip,) = [r for r in rows if r.quantity.startswith("round trip")]
        assert trip.ours <= 1e-6
    assert len(result.block("line_forces").rows) == 2 * 3 + 1
    assert len(result.block("circle_forces").rows) == 3 * 3 + 1


def test_circle_is_the_paper_s_circle(result):
    """The direct dynamics run on the circle of section 6: centre (a/2, a/2), radius a/8, a = 0.5 m, 2 s."""
    (figure,) = [
        b for s in result.sections if s.title == "Path: circle" for b in s.blocks if b.kind == "figure"
    ]
    x = np.asarray(figure.data["x_direct"])[:, :2]
    np.testing.assert_allclose(np.linalg.norm(x - [0.25, 0.25], axis=1), 0.0625, atol=1e-6)
    assert figure.data["t_direct"][-1] == pytest.approx(2.0)


def test_each_path_is_animated(result):
    """Two scenes, one per path, with increasing times."""
    scenes = [b for s in result.sections for b in s.blocks if b.kind == "scene"]
    assert len(scenes) == 2
    for scene in scenes:
        assert np.all(np.diff(scene.data["times"]) > 0)
