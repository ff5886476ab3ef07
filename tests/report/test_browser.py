"""The real browser check: reports and meshcat scenes render in headless Chromium without console errors.

Drives Debian's ``chromium`` through its ``chromium-driver`` with selenium (``make test``
installs both when it can). Without them the test fails with the reason; on a machine where
they cannot be installed, ``PLM_PIN_SKIP_BROWSER=1`` skips it on purpose (it then shows as
skipped, with the reason), except on CI (``CI`` set), where it always runs.
"""

from __future__ import annotations

import io
import os
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import plm_pin
from plm_pin.report import study_names
from plm_pin.viz import scene_html

pytestmark = pytest.mark.slow

SKIP = "PLM_PIN_SKIP_BROWSER"
TIMEOUT = 60.0
"""Longest wait for a page, a figure or a 3D canvas [s]."""

PAGE_WEIGHT = 1_000_000
"""Largest report page, its scenes (separate pages, loaded lazily) not counted [bytes]."""

CHROMIUM_ARGS = (
    "--headless=new",
    "--no-sandbox",  # root on CI; the pages are our own local files
    "--disable-dev-shm-usage",
    "--window-size=1280,900",  # the width a report must fit without horizontal scrolling
    "--use-angle=swiftshader",  # software WebGL: no GPU on CI
    "--enable-unsafe-swiftshader",
)


LEGEND_SHOWN = """
const legend = document.getElementById('plm-pin-legend');
if (!legend) return 'no legend';
const r = legend.getBoundingClientRect();
if (r.width < 50 || r.height < 20 || r.left < 0 || r.top < 0 || r.bottom > window.innerHeight) {
    return `legend of ${r.width} x ${r.height} px at (${r.left}, ${r.top}), outside the view`;
}
legend.style.pointerEvents = 'auto';  // hit-test it: what is on top at its centre
const top = document.elementFromPoint(r.left + r.width / 2, r.top + r.height / 2);
legend.style.pointerEvents = 'none';
return legend.contains(top) ? '' : `legend covered by ${top ? top.tagName : 'nothing'}`;
"""
"""Empty when the scene's legend is on screen, in the view and on top of the canvas; else what is wrong."""

HIDE_HELPERS = """
document.querySelectorAll('.dg, #plm-pin-legend').forEach(e => e.style.display = 'none');
for (const path of ['/Grid', '/Axes']) {
    viewer.handle_command({type: 'set_property', path: path, property: 'visible', value: false});
}
"""
"""Hide meshcat's controls, our legend, the floor grid and world axes: what is left on the background is the
mechanism."""


def _executables() -> tuple[str, str]:
    """Paths of chromium and chromedriver; fails (or skips on request) with the reason when missing."""
    found = {name: shutil.which(name) for name in ("chromium", "chromedriver")}
    missing = [name for name, path in found.items() if path is None]
    if missing:
        reason = (
            f"{' and '.join(missing)} not found: the browser check needs Debian's chromium and "
            "chromium-driver (`make test` installs them as root or with passwordless sudo; otherwise "
            "run `sudo apt-get install chromium chromium-driver`)"
        )
        if os.environ.get(SKIP) == "1" and not os.environ.get("CI"):
            pytest.skip(f"{reason}; skipped because {SKIP}=1")
        pytest.fail(f"{reason}; set {SKIP}=1 to skip it on purpose (not on CI)", pytrace=False)
    return found["chromium"] or "", found["chromedriver"] or ""


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """A headless Chromium driven by chromedriver, with its console log kept."""
    chromium, chromedriver = _executables()
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        pytest.fail("selenium is not installed: pip install -e '.[test]'", pytrace=False)
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for arg in CHROMIUM_ARGS:
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(chromedriver), options=options)
    driver.set_page_load_timeout(TIMEOUT)
    driver.set_script_timeout(TIMEOUT)
    try:
        yield driver
    finally:
        driver.quit()


def _wait(driver: Any, what: str, condition: Callable[[], Any]) -> Any:
    """Wait explicitly (selenium's WebDriverWait) until ``condition`` holds, up to :data:`TIMEOUT`.

    Each check waits on the state it tests (a page loaded, an image decoded, pixels inked),
    never on a fixed time, so a loaded machine only makes it wait longer; past the timeout
    it fails saying what it waited for.
    """
    from selenium.common.exceptions import TimeoutException
    from selenium.webdriver.support.ui import WebDriverWait

    try:
        return WebDriverWait(driver, TIMEOUT, poll_frequency=0.25).until(lambda _: condition())
    except TimeoutException:
        pytest.fail(f"timed out after {TIMEOUT:g} s waiting for {what}", pytrace=False)


def _open(driver: Any, url: str) -> None:
    driver.get(url)
    _wait(driver, f"{url} to load", lambda: driver.execute_script("return document.readyState") == "complete")


DECODED_AND_PAINTED = """
const img = arguments[0], done = arguments[arguments.length - 1];
img.decode().then(
    () => requestAnimationFrame(() => requestAnimationFrame(() => done(true))),
    () => done(false),
);
"""
"""Resolve once the image is decoded and two frames have been painted since (false if it cannot decode)."""


def _console_errors(driver: Any) -> list[str]:
    """Console messages of level SEVERE since the last call (errors, uncaught exceptions, failed loads)."""
    return [entry["message"] for entry in driver.get_log("browser") if entry["level"] == "SEVERE"]


def _pixels(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=int)  # (h, w, 3)


def _inked(png: bytes) -> float:
    """Fraction of pixels that are not near-white (a figure drew something)."""
    rgb = _pixels(png)
    return float(np.mean(rgb.min(axis=2) < 200))


def _drawn_on_background(png: bytes) -> tuple[int, float]:
    """Pixels that differ from their row's background, and the background's top-to-bottom change.

    meshcat paints a vertical gradient: each row's median is the background there. A
    rendered scene has a gradient (second value well above 0) and a mechanism on it (first).
    """
    rgb = _pixels(png)
    background = np.median(rgb, axis=1, keepdims=True)  # (h, 1, 3)
    drawn = int(np.sum(np.max(np.abs(rgb - background), axis=2) > 40))
    gradient = float(np.max(np.abs(background[0, 0] - background[-1, 0])))
    return drawn, gradient


def _check_canvas(driver: Any, where: str) -> None:
    """The current frame has a WebGL canvas showing a mechanism on meshcat's background, and the legend."""
    from selenium.webdriver.common.by import By

    canvas = _wait(driver, f"the 3D canvas of {where}", lambda: driver.find_elements(By.TAG_NAME, "canvas"))[
        0
    ]
    assert driver.execute_script(LEGEND_SHOWN) == "", f"{where}: {driver.execute_script(LEGEND_SHOWN)}"
    driver.execute_script(HIDE_HELPERS)
    size = driver.execute_script("return [arguments[0].width, arguments[0].height]", canvas)
    assert min(size) > 100, f"{where}: canvas of {size} pixels"

    def rendered() -> bool:
        drawn, gradient = _drawn_on_background(canvas.screenshot_as_png)
        return drawn > 300 and gradient > 30

    _wait(driver, f"{where} to draw the mechanism (not blank)", rendered)


def _check_report(driver: Any, where: str) -> int:
    """Every figure of the open report is loaded and inked, every scene draws; returns the count of both."""
    from selenium.webdriver.common.by import By

    images = driver.find_elements(By.CSS_SELECTOR, "figure.plot img")
    for k, img in enumerate(images):
        driver.execute_script("arguments[0].scrollIntoView()", img)
        _wait(
            driver,
            f"figure {k} of {where} to load",
            lambda img=img: driver.execute_script(
                "return arguments[0].complete && arguments[0].naturalWidth", img
            ),
        )
        assert driver.execute_async_script(DECODED_AND_PAINTED, img), f"figure {k} of {where} does not decode"
        _wait(
            driver,
            f"figure {k} of {where} to show ink (it stays blank)",
            lambda img=img: _inked(img.screenshot_as_png) > 0.01,
        )
    frames = driver.find_elements(By.CSS_SELECTOR, "iframe.scene")
    for k, frame in enumerate(frames):
        driver.execute_script("arguments[0].scrollIntoView()", frame)
        driver.switch_to.frame(frame)
        try:
            _check_canvas(driver, f"scene {k} of {where}")
        finally:
            driver.switch_to.default_content()
    return len(images) + len(frames)


@pytest.fixture(scope="module")
def reports(report_all) -> Path:
    """The reports of the session's one ``plm-pin report all``: every study, the overview among them."""
    assert report_all.exit_code == 0, report_all.output
    return report_all.out


def _load_time(driver: Any) -> float:
    """Time from navigation start to the end of the page's load event [s] (measured, not asserted)."""
    timing = driver.execute_script("return performance.getEntriesByType('navigation')[0].toJSON()")
    return float(timing["loadEventEnd"] - timing["startTime"]) / 1000.0


def _horizontal_overflow(driver: Any) -> list[str]:
    """The page's width beyond the window, and the elements sticking out of the main column."""
    return driver.execute_script(
        """
        const out = [];
        const doc = document.documentElement;
        if (doc.scrollWidth > window.innerWidth) {
            out.push(`page ${doc.scrollWidth} px > ${window.innerWidth} px`);
        }
        const main = document.querySelector('main');
        if (main) {
            const right = main.getBoundingClientRect().right;
            for (const e of main.querySelectorAll('table, figure, pre, img, iframe')) {
                const r = e.getBoundingClientRect().right;
                const what = (e.querySelector('caption') || e).textContent.slice(0, 60);
                if (r > right + 1) {
                    const tag = e.tagName.toLowerCase();
                    out.push(`${tag} '${what}' ends at ${Math.round(r)} > ${Math.round(right)} px`);
                }
            }
        }
        return out;
        """
    )


def test_reports_render_with_figures_and_3d_scenes(browser, reports, record_property):
    """From index.html each report opens light and fits 1280 px; figures show ink, scenes draw, no error."""
    from selenium.webdriver.common.by import By

    _open(browser, (reports / "index.html").as_uri())
    links = [a.get_attribute("href") for a in browser.find_elements(By.CSS_SELECTOR, "table.index a")]
    pages = [link for link in links if link.endswith("/report.html")]
    assert len(pages) == len(study_names())
    assert _console_errors(browser) == []
    for page in pages:
        path = Path(page.removeprefix("file://"))
        assert path.stat().st_size < PAGE_WEIGHT, f"{path}: {path.stat().st_size} bytes"
        _open(browser, page)
        record_property(f"load time {path.parent.name} [s]", _load_time(browser))
        record_property(f"page weight {path.parent.name} [bytes]", path.stat().st_size)
        assert _horizontal_overflow(browser) == [], page
        assert _check_report(browser, page) >= 3
        assert _console_errors(browser) == [], page


def test_static_meshcat_page_renders(browser, tmp_path):
    """A page of scene_html, opened on its own, draws the mechanism without console errors."""
    page = tmp_path / "scene.html"
    page.write_text(scene_html(plm_pin.load("harada2015_asymmetric")))
    _open(browser, page.as_uri())
    _check_canvas(browser, page.name)
    assert _console_errors(browser) == []
