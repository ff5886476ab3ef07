"""plm_pin.sweep(...): the top-level callable, progress reports, and the run's summary."""

from __future__ import annotations

import subprocess
import sys

import xarray as xr

import plm_pin
from plm_pin.sweep import SweepResult, run_spec
from plm_pin.sweep import sweep as sweep_function
from tests.sweep.conftest import small


def test_plm_pin_sweep_is_the_package_and_calls_its_sweep():
    """plm_pin.sweep is the sweep package, and calling it runs sweep() with the same arguments."""
    kwargs = small(metrics=["manipulability"], options={})
    via_top = plm_pin.sweep(**kwargs)
    direct = sweep_function(**kwargs)
    assert isinstance(via_top, SweepResult) and plm_pin.sweep.sweep is sweep_function
    xr.testing.assert_identical(via_top.dataset, direct.dataset)
    assert "sweep" in plm_pin.__all__


def test_importing_the_sweep_package_needs_no_optional_dependency():
    """`import plm_pin.sweep` imports neither dask, distributed, xarray nor pyarrow (only running does)."""
    heavy = "('dask', 'distributed', 'xarray', 'pyarrow', 'pandas')"
    code = f"import sys, plm_pin.sweep; print(sorted(m for m in {heavy} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_progress_counts_parameter_points_from_the_checkpoints_on(tmp_path):
    """progress(done, total) is called before the first chunk and after each, ending at the total."""
    calls = []
    spec = plm_pin.sweep.make_spec(**small())
    run_spec(spec, chunk=1, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(0, 4), (1, 4), (2, 4), (3, 4), (4, 4)]
    run_spec(spec, chunk=1, store=tmp_path / "s")
    calls.clear()
    again = run_spec(spec, chunk=1, store=tmp_path / "s", progress=lambda d, t: calls.append((d, t)))
    assert calls == [(4, 4)] and again.computed_points == 0 and again.poses_per_second() == 0.0
