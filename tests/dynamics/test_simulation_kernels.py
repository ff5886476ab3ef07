"""The adaptive run's compiled samples against its Python path (kernels switched off): the same samples."""

from __future__ import annotations

import numpy as np
import pytest

from plm_pin.dynamics.simulation import simulate
from plm_pin.kernels import SWITCH, Kernel, kernel_of
from tests.conftest import preset

ROUND_OFF_RTOL = 1e-12
"""Agreement of samples computed by two algorithms in floating point (relative to 1)."""

CONDITIONED_RTOL = 1e-14
"""Agreement of v, a and lambda per squared condition of the closure rows (sigma_1 / sigma_r)^2."""


def _runs(name: str, duration: float, monkeypatch: pytest.MonkeyPatch, **kwargs):
    mech = preset(name)
    monkeypatch.setenv(SWITCH, "0")
    slow = simulate(mech, mech.q_ref, duration=duration, dt=1e-3, **kwargs)
    monkeypatch.setenv(SWITCH, "1")
    assert kernel_of(mech) is not None
    fast = simulate(mech, mech.q_ref, duration=duration, dt=1e-3, **kwargs)
    return mech, slow, fast


@pytest.mark.parametrize(
    ("name", "duration", "solver"),
    [
        ("fourbar", 1.0, "auto"),
        ("fourbar", 0.5, "kkt"),
        ("harada2011_3d4m", 1.0, "auto"),  # crosses constraint singularities: bridged and handed back
        ("zhao2011_6pss", 0.1, "auto"),  # spatial, with a free-flyer platform
    ],
)
def test_compiled_samples_match_the_python_path(name, duration, solver, monkeypatch):
    """q, v, a, lambda, energy, closure distance, drift and pose agree with the Python samples to round-off.

    v, a and lambda near a constraint singularity are sensitive to round-off by the squared
    condition of the closure rows there: their tolerance grows with it.
    """
    mech, slow, fast = _runs(name, duration, monkeypatch, solver=solver)
    assert (len(fast), fast.steps, fast.solver) == (len(slow), slow.steps, slow.solver)
    np.testing.assert_array_equal(fast.t, slow.t)
    for field in ("q", "residual", "closure_drift", "energy", "x"):
        a, b = getattr(fast, field), getattr(slow, field)
        np.testing.assert_allclose(a, b, rtol=0.0, atol=ROUND_OFF_RTOL * max(1.0, float(np.max(np.abs(b)))))
    rank = mech.nv - mech.mobility
    for k in range(len(slow)):
        s = np.linalg.svd(mech.closure_jacobian(slow.q[k]), compute_uv=False)
        tol = ROUND_OFF_RTOL + CONDITIONED_RTOL * (s[0] / s[rank - 1]) ** 2
        for field in ("v", "a", "lam"):
            a, b = getattr(fast, field)[k], getattr(slow, field)[k]
            assert np.max(np.abs(a - b)) <= tol * max(1.0, float(np.max(np.abs(b)))), (field, k)


def test_force_law_and_wrench_runs_take_the_python_path(monkeypatch):
    """A force law or a wrench leaves the samples to the Python path: the same run, kernels on or off."""
    for kwargs in ({"actuator_forces": lambda t, q, v: [0.1 * np.sin(t)]}, {"wrench": [0.5]}):
        _, slow, fast = _runs("fourbar", 0.2, monkeypatch, **kwargs)
        for field in ("q", "v", "a", "lam", "energy"):
            np.testing.assert_array_equal(getattr(fast, field), getattr(slow, field))


def test_samples_handed_back_take_the_python_path(monkeypatch):
    """Every other sample handed back to the Python path (as at a constraint singularity): the same run."""
    compiled = Kernel.samples

    def one_at_a_time(self, states, *args):  # the first state only: the next one is handed back
        return compiled(self, states[:1], *args)

    mech, slow, _ = _runs("fourbar", 0.3, monkeypatch)
    monkeypatch.setattr(Kernel, "samples", one_at_a_time)
    mixed = simulate(mech, mech.q_ref, duration=0.3, dt=1e-3)
    assert (len(mixed), mixed.steps) == (len(slow), slow.steps)
    for field in ("q", "v", "a", "lam", "residual", "closure_drift", "energy", "x"):
        a, b = getattr(mixed, field), getattr(slow, field)
        np.testing.assert_allclose(a, b, rtol=0.0, atol=ROUND_OFF_RTOL * max(1.0, float(np.max(np.abs(b)))))
