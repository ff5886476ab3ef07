"""The inspector's Jupyter panel: its widgets call the same state function as the browser page."""

from __future__ import annotations

import numpy as np
import pytest

from plm_pin.viz import Inspector, InspectorPanel, inspect, inspect_update
from tests.conftest import preset


@pytest.fixture(scope="module")
def panel():
    inspector = inspect(preset("harada2011_3d4m"))
    yield inspector.panel()
    inspector.close()


def test_slider_moves_the_state_as_inspect_update_does(panel):
    """Setting the x slider gives the state inspect_update computes from the same change."""
    before = panel.inspector.state
    goal = float(before.x[0]) + 0.004
    expected = inspect_update(before, {"task": {"x": goal}})
    panel.task_sliders["x"].value = goal
    np.testing.assert_allclose(panel.inspector.state.q, expected.q, atol=1e-12)
    assert panel.actuator_sliders["slider1"].value == pytest.approx(expected.actuators[0])
    assert f"{expected.manipulability:.6g}" in panel.readouts.value


def test_mode_selectors_switch_the_configuration(panel):
    """The working-mode selector switches the configuration at the same pose; find modes fills the other."""
    state = panel.inspector.state
    other = next(m for m in state.working_modes if m != state.working_mode)
    panel.working_mode.value = other
    assert panel.inspector.state.working_mode == other
    np.testing.assert_allclose(panel.inspector.state.x, state.x, atol=1e-9)
    panel.find_modes.click()
    assert len(panel.assembly_mode.options) == len(panel.inspector.state.assembly_modes) >= 2


def test_limits_entries_show_the_internal_force_range(panel):
    """Blank limits: no range; finite limits typed in: the range the state function gives for them."""
    fresh = Inspector(preset("harada2011_3d4m"), page=False, server=panel.inspector.viewer.server)
    try:
        _check_limits(fresh.panel())
    finally:
        fresh.close()


def _check_limits(panel: InspectorPanel) -> None:
    assert all(box.value == "" for pair in panel.limits.values() for box in pair)
    for lo, hi in panel.limits.values():
        lo.value, hi.value = "-200", "200"
    state = panel.inspector.state
    np.testing.assert_array_equal(state.force_limits, np.tile([-200.0, 200.0], (4, 1)))
    assert state.internal_range.shape == (1, 2), state.notes
    ((lo, hi),) = state.internal_range
    assert f"{lo:.6g} .. {hi:.6g}" in panel.readouts.value
    panel.limits["slider1"][0].value = "lots"
    assert "is not a number" in panel.error.value
