"""Sweep figures: heat maps and line plots of a sweep variable, degrees for radians (no pixel checks)."""

from __future__ import annotations

import numpy as np
import pytest

from plm_pin.exceptions import InvalidInput
from plm_pin.sweep import sweep
from plm_pin.viz import plot_sweep_heatmap, plot_sweep_lines

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
from matplotlib.collections import QuadMesh  # noqa: E402


@pytest.fixture(scope="module")
def ds():
    """A tiny sweep: the 3D3M and 3D4M, two plate sizes, two heights, the orientation range."""
    return sweep(
        "harada2011_3d4m",
        {"legs": [[1, 2, 4], [1, 2, 3, 4]], "half_plate": [0.035, 0.05]},
        {"y": [0.06, 0.09], "rz": np.radians(np.linspace(-60.0, 60.0, 13))},
        ["orientation_range", "manipulability"],
        pose=(0.0, 0.08, 0.0),
    ).dataset


def test_heatmap_shows_radians_in_degrees_and_text_coordinates_as_ticks(ds, close_figures):
    """Half-width over (legs, y): a QuadMesh in degrees, categorical legs ticks, labelled colour bar."""
    data = ds.orientation_halfwidth.sel(half_plate=0.035)
    fig = plot_sweep_heatmap(data, "legs", "y")
    ax = fig.axes[0]
    (mesh,) = [c for c in ax.collections if isinstance(c, QuadMesh)]
    np.testing.assert_allclose(mesh.get_array().reshape(2, 2), np.degrees(data.values.T))
    assert [t.get_text() for t in ax.get_xticklabels()] == ["(1, 2, 4)", "(1, 2, 3, 4)"]
    assert ax.get_ylabel() == "y [m]" and fig.axes[1].get_ylabel() == "orientation_halfwidth [deg]"
    with pytest.raises(InvalidInput, match="a heat map needs a 2-D variable over"):
        plot_sweep_heatmap(ds.orientation_halfwidth, "legs", "y")


def test_heatmap_without_colour_bar_leaves_it_to_the_caller(ds, close_figures):
    """colorbar=False: the figure holds the one axes drawn in, no colour-bar axes."""
    fig = plot_sweep_heatmap(ds.orientation_halfwidth.sel(half_plate=0.035), "legs", "y", colorbar=False)
    assert len(fig.axes) == 1


def test_lines_draw_one_curve_per_hue_value(ds, close_figures):
    """Manipulability against the plate angle, one line per height; the angle axis in degrees."""
    data = ds.manipulability.sel(legs="(1, 2, 4)", half_plate=0.05)
    fig = plot_sweep_lines(data, "rz", "y", label="y = {value} m")
    ax = fig.axes[0]
    assert [line.get_label() for line in ax.get_lines()] == ["y = 0.06 m", "y = 0.09 m"]
    np.testing.assert_allclose(ax.get_lines()[0].get_xdata(), np.linspace(-60.0, 60.0, 13))
    assert ax.get_xlabel() == "rz [deg]"
    with pytest.raises(InvalidInput, match="a line plot needs a variable over"):
        plot_sweep_lines(data, "rz")
