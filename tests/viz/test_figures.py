"""Figure helpers: they return matplotlib Figures with the expected artists (no pixel checks)."""

from __future__ import annotations

import builtins
import math
import subprocess
import sys

import numpy as np
import pytest

from plm_pin.exceptions import InvalidInput
from plm_pin.viz import plot_map, plot_sweep
from plm_pin.workspace import singular_loci, singular_points_along, workspace_map, workspace_sweep
from tests.conftest import preset

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
from matplotlib.collections import PathCollection, QuadMesh  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402


def test_plot_map_has_mesh_colorbar_loci_and_degree_labels(close_figures):
    """A y-theta map: one QuadMesh over the grid, a colour bar, loci markers, theta in degrees."""
    mech = preset("harada2011_3d3m")
    ys = np.linspace(0.01, 0.04, 4)
    thetas = np.radians(np.linspace(-40, 40, 9))
    result = workspace_map(mech, ("y", "rz"), (ys, thetas))
    loci = singular_loci(mech, "rz", thetas, "y", ys[1:3])
    fig = plot_map(result, "manipulability", loci=loci)
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    meshes = [c for c in ax.collections if isinstance(c, QuadMesh)]
    assert len(meshes) == 1 and meshes[0].get_array().size == result.reachable.size
    assert len(fig.axes) == 2  # the map and its colour bar
    assert ax.get_xlabel() == "y [m]" and ax.get_ylabel() == "rz [deg]"
    scatters = [c for c in ax.collections if isinstance(c, PathCollection)]
    assert sum(len(s.get_offsets()) for s in scatters) == len(loci)
    theta_shown = np.concatenate([s.get_offsets()[:, 1] for s in scatters])
    assert np.allclose(sorted(theta_shown), sorted(math.degrees(p.parameter) for p in loci))


def test_plot_map_log_scale_and_existing_axes(close_figures):
    """log=True uses a LogNorm; passing ax draws into that figure."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    mech = preset("harada2011_3d4m")
    result = workspace_map(mech, ("x", "y"), (np.linspace(-0.02, 0.02, 3), np.linspace(0.05, 0.07, 3)))
    fig, ax = plt.subplots()
    out = plot_map(result, "condition_number", ax=ax, log=True, title="kappa")
    assert out is fig and ax.get_title() == "kappa"
    (mesh,) = [c for c in ax.collections if isinstance(c, QuadMesh)]
    assert isinstance(mesh.norm, LogNorm)


def test_plot_sweep_draws_curve_and_singular_lines(close_figures):
    """A theta sweep: one curve in degrees, one dashed line per singular point, labels with units."""
    mech = preset("harada2011_3d3m")
    thetas = np.radians(np.linspace(-60, 60, 25))
    pose = (0.0, 0.03, 0.0)
    result = workspace_sweep(mech, "rz", thetas, pose)
    points = singular_points_along(mech, "rz", thetas, pose)
    fig = plot_sweep(result, singular=points, label="3D3M")
    ax = fig.axes[0]
    curves = [line for line in ax.lines if line.get_linestyle() == "-"]
    dashed = [line for line in ax.lines if line.get_linestyle() == "--"]
    assert len(curves) == 1 and len(dashed) == len(points) == 2
    np.testing.assert_allclose(curves[0].get_xdata(), np.degrees(thetas))
    assert sorted(line.get_xdata()[0] for line in dashed) == pytest.approx(
        sorted(math.degrees(p.parameter) for p in points)
    )
    assert ax.get_xlabel() == "rz [deg]" and ax.get_ylabel() == "manipulability w"
    assert ax.get_legend() is not None


def test_wrong_slice_and_metric_are_refused():
    """plot_map needs a map, plot_sweep a sweep, and the metric must exist."""
    mech = preset("harada2011_3d4m")
    sweep = workspace_sweep(mech, "x", np.linspace(-0.01, 0.01, 3))
    with pytest.raises(InvalidInput, match="plot_map needs a 2-D map"):
        plot_map(sweep)
    with pytest.raises(InvalidInput, match="unknown metric 'w'"):
        plot_sweep(sweep, "w")


def test_missing_matplotlib_gives_a_clear_message(monkeypatch):
    """Without matplotlib the helpers raise ImportError naming the extra to install."""
    real_import = builtins.__import__

    def fake_import(name, *args, **kwargs):
        if name.startswith("matplotlib"):
            raise ImportError("No module named 'matplotlib'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", fake_import)
    mech = preset("harada2011_3d4m")
    sweep = workspace_sweep(mech, "x", np.linspace(-0.01, 0.01, 3))
    with pytest.raises(ImportError, match=r"pip install 'plm-pin\[viz\]'"):
        plot_sweep(sweep)


def test_importing_viz_does_not_import_matplotlib():
    """plm_pin.viz imports matplotlib only when a figure is drawn."""
    code = "import sys, plm_pin.viz; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
