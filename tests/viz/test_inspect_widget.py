"""The inspector's Jupyter panel: its widgets call the same state function as the browser page."""

from __future__ import annotations

import numpy as np
import pytest

from plm_pin.viz import inspect, inspect_update
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
