"""plm_pin.sweep.sweep(...): a plain typed function, progress reports, and the run's summary."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest
import xarray as xr

import plm_pin
from plm_pin.sweep import SweepResult, run_spec
from plm_pin.sweep import sweep as sweep_function
from tests.sweep.conftest import small


def test_plm_pin_sweep_is_a_plain_package_with_its_sweep_function():
    """plm_pin.sweep is an ordinary module (not callable); plm_pin.sweep.sweep runs the sweep."""
    kwargs = small(metrics=["manipulability"], options={})
    via_top = plm_pin.sweep.sweep(**kwargs)
    direct = run_spec(plm_pin.sweep.make_spec(**kwargs))
    assert isinstance(via_top, SweepResult) and plm_pin.sweep.sweep is sweep_function
    xr.testing.assert_identical(via_top.dataset, direct.dataset)
    assert type(plm_pin.sweep) is type(os) and not callable(plm_pin.sweep)


def _mypy_strict(script):
    """Mypy --strict on one file (plm_pin's own modules followed silently: types read, not checked).

    Its cache is the script's folder's own (a test's tmp_path): a second run there reuses what the
    first read of numpy and plm_pin, and nothing from outside the test.
    """
    cache = script.parent / ".mypy_cache"
    command = [sys.executable, "-m", "mypy", "--strict", "--follow-imports=silent", "--cache-dir", str(cache)]
    return subprocess.run([*command, str(script)], capture_output=True, text=True, cwd=script.parent)


@pytest.mark.slow
def test_mypy_strict_accepts_a_user_script_calling_sweep(tmp_path):
    """Mypy --strict accepts a user script calling sweep(...) and refuses calling the package (~10 s)."""
    script = tmp_path / "user_sweep.py"
    script.write_text(
        textwrap.dedent(
            """\
            import numpy as np

            import plm_pin
            from plm_pin.sweep import SweepResult, sweep

            result: SweepResult = sweep(
                "harada2011_3d4m",
                parameters={"half_plate": [0.035, 0.05]},
                poses={"rz": np.radians([-20.0, 0.0, 20.0])},
                metrics=["manipulability"],
                pose=[0.0, 0.08, 0.0],
            )
            again = plm_pin.sweep.sweep("harada2011_3d4m", poses={"rz": [0.0]})
            complete: bool = result.complete and again.complete
            """
        )
    )
    out = _mypy_strict(script)
    assert out.returncode == 0, out.stdout + out.stderr
    # the same checker refuses calling the package itself, as plm_pin.sweep(...) was written before
    script.write_text('import plm_pin.sweep\n\nplm_pin.sweep("harada2011_3d4m", poses={"rz": [0.0]})\n')
    out = _mypy_strict(script)
    assert out.returncode == 1 and "not callable" in out.stdout, out.stdout


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
