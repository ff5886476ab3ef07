"""The live inspector in the real browser: drag a slider, switch a mode, read what the API gives there.

Headless Chromium, driven as in tests/report/test_browser.py (same fixture and waits): the
page's readouts after a drag are compared with inverse kinematics, manipulability and statics
at the pose the page shows, and the meshcat scene beside it redraws.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from plm_pin.kinematics import classify, inverse_kinematics
from plm_pin.statics import static_forces
from plm_pin.viz import Inspector, inspect
from plm_pin.viz.legend import ENTRIES
from plm_pin.workspace import manipulability
from tests.conftest import preset
from tests.report.test_browser import (
    _check_canvas,
    _console_errors,
    _open,
    _pixels,
    _wait,
    browser,  # noqa: F401 (a fixture)
)

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def table() -> Iterator[Inspector]:
    running = inspect(preset("harada2011_3d4m"))
    yield running
    running.close()


def _settled(driver: Any, inspector: Inspector) -> bool:
    """The page shows the inspector's current state and has no request in flight."""
    shown = driver.execute_script("return state && !busy && !pending ? state.q : null")
    return shown is not None and np.allclose(shown, inspector.state.q, atol=0.0, rtol=0.0)


def _number(driver: Any, element_id: str) -> float:
    return float(driver.execute_script(f"return document.getElementById('{element_id}').textContent"))


def _scene_png(driver: Any, first: bool = True) -> bytes:
    """A screenshot of the scene's canvas; the first time, after checking it draws and has its legend.

    The check hides meshcat's controls, the legend, grid and axes (as the report tests do), and
    they stay hidden: later screenshots compare the mechanism alone.
    """
    from selenium.webdriver.common.by import By

    driver.switch_to.frame(driver.find_element(By.ID, "scene"))
    try:
        if first:
            _check_canvas(driver, "the inspector's scene")
        return driver.find_element(By.TAG_NAME, "canvas").screenshot_as_png
    finally:
        driver.switch_to.default_content()


LEGEND_IN_VIEW = """
const legend = document.querySelector('#legend #plm-pin-legend');
if (!legend) return 'no legend in the panel';
legend.scrollIntoView();
const r = legend.getBoundingClientRect();
if (r.width < 50 || r.height < 20 || r.top < 0 || r.bottom > window.innerHeight) {
    return `legend of ${r.width} x ${r.height} px at (${r.left}, ${r.top}), outside the view`;
}
legend.style.pointerEvents = 'auto';
const top = document.elementFromPoint(r.left + r.width / 2, r.top + r.height / 2);
return legend.contains(top) ? '' : `legend covered by ${top ? top.tagName : 'nothing'}`;
"""
"""Empty when the panel's legend is in view once scrolled to and nothing covers it; else what is wrong."""


def _check_legend(driver: Any, inspector: Inspector) -> None:
    """The panel shows the legend of what the scene draws: singularity colours, closure marks, the ellipse."""
    assert driver.execute_script(LEGEND_IN_VIEW) == ""
    text = driver.execute_script("return document.querySelector('#legend #plm-pin-legend').innerText")
    expected = [ENTRIES[key].label for key in inspector.legend]
    assert text.split("\n") == expected
    for key in ("direct", "inverse", "constraint", "closed", "ellipse"):
        assert ENTRIES[key].label in expected
    driver.execute_script("document.getElementById('panel').scrollTop = 0")


def test_drag_a_slider_and_switch_a_mode(browser, table):  # noqa: F811 (the imported fixture)
    """A drag of the x slider moves the pose; the readouts are the API's there; a mode switch redraws."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    mech = table.state.mech
    mode = table.state.working_mode
    _open(browser, table.url)
    _wait(browser, "the first state", lambda: _settled(browser, table))
    _check_legend(browser, table)
    before_png = _scene_png(browser)
    x0 = float(table.state.x[0])

    slider = browser.find_element(By.ID, "task-x")
    ActionChains(browser).click_and_hold(slider).move_by_offset(25, 0).release().perform()
    _wait(browser, "the drag to move x", lambda: _settled(browser, table) and table.state.x[0] != x0)

    x = np.array(browser.execute_script("return state.x"))
    assert x[0] != pytest.approx(x0)
    sol = inverse_kinematics(mech, x, mech.q_ref, mode=mode)
    np.testing.assert_allclose(browser.execute_script("return state.q"), sol.q, atol=1e-8)
    assert _number(browser, "task-x-value") == pytest.approx(x[0], rel=1e-5, abs=1e-9)
    assert _number(browser, "ro-manipulability") == pytest.approx(manipulability(mech, sol.q).w, rel=1e-5)
    report = classify(mech, sol.q)
    for kind in ("constraint", "inverse", "direct"):
        assert _number(browser, f"ro-margin-{kind}") == pytest.approx(
            getattr(report, f"{kind}_margin"), rel=1e-5
        )
    forces = static_forces(mech, sol.q, np.zeros(3), limits=None).f_c
    for name, f in zip(table.state.actuator_names, forces, strict=True):
        assert _number(browser, f"force-{name}") == pytest.approx(f, rel=1e-5, abs=1e-9)

    other = next(m for m in table.state.working_modes if m != mode)
    Select(browser.find_element(By.ID, "working-mode")).select_by_value(",".join(map(str, other)))
    _wait(
        browser,
        "the working mode to switch",
        lambda: _settled(browser, table) and table.state.working_mode == other,
    )
    switched = inverse_kinematics(mech, x, sol.q, mode=other)
    np.testing.assert_allclose(browser.execute_script("return state.q"), switched.q, atol=1e-8)
    changed = np.max(np.abs(_pixels(_scene_png(browser, first=False)) - _pixels(before_png)), axis=2) > 40
    assert np.count_nonzero(changed) > 100  # the legs moved on screen

    rz = browser.find_element(By.ID, "task-rz")
    ActionChains(browser).click_and_hold(rz).move_by_offset(90, 0).release().perform()
    _wait(browser, "the drag to stop at an edge", lambda: _settled(browser, table) and table.state.stopped)
    assert browser.find_element(By.ID, "stopped").text == f"stopped: {table.state.stopped}"
    assert _console_errors(browser) == []
