"""HTML rendering: escaping of every string, embedded figures and scenes (plm_pin/report/render.py)."""

from __future__ import annotations

import base64
from html.parser import HTMLParser

from plm_pin.report import run_study
from plm_pin.report.render import render_report
from tests.report.conftest import make_study

SCENE = "<!DOCTYPE html><html><body><script>var a = \"x\" && 1 < 2;</script>'quoted' &amp;</body></html>"


class _Tags(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict[str, str | None]]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))


def _page() -> str:
    def run(ctx):
        from tests.report.conftest import demo_run

        demo_run(ctx)
        ctx.section("Scene").scene(SCENE, 'A "scene" <caption>', {"q": [0.0]})

    return render_report(run_study(make_study(run)))


def test_strings_from_studies_and_descriptions_are_escaped():
    """Titles, section names, cells and Markdown prose reach the page as text, never as markup."""
    page = _page()
    assert "<script>alert" not in page
    assert "&lt;script&gt;alert('text')&lt;/script&gt;" in page
    assert "<title>Demo &lt;title&gt;</title>" in page
    assert "Numbers &lt;b&gt;bold&lt;/b&gt;" in page
    assert "<td>b &lt;i&gt;</td>" in page
    assert "<em>prose</em>" in page  # Markdown still renders
    assert "<li>&lt;i&gt;gravity&lt;/i&gt; along -y</li>" in page
    assert '<td class="num">(0.24, 0.17)</td><td>m</td><td>Fig. 2</td>' in page


def test_scene_is_a_sandboxed_srcdoc_that_round_trips():
    """The meshcat page sits in <iframe sandbox="allow-scripts" srcdoc>, which decodes to the page exactly."""
    parser = _Tags()
    parser.feed(_page())
    (frame,) = [attrs for tag, attrs in parser.tags if tag == "iframe"]
    assert frame["srcdoc"] == SCENE
    assert frame["sandbox"] == "allow-scripts"
    assert frame["title"] == 'A "scene" <caption>'


def test_figures_are_svg_images():
    """Each figure is an <img> whose data: URI decodes to the SVG."""
    parser = _Tags()
    parser.feed(_page())
    (img,) = [attrs for tag, attrs in parser.tags if tag == "img"]
    prefix = "data:image/svg+xml;base64,"
    assert img["src"].startswith(prefix)
    assert b"<svg" in base64.b64decode(img["src"][len(prefix) :])
    assert img["alt"] == "A line."


def test_page_shows_the_command_and_versions():
    """The regenerate command and the software versions are on the page."""
    result = run_study(make_study(), command="plm-pin report demo --out 'my reports'")
    page = render_report(result)
    assert "plm-pin report demo --out &#39;my reports&#39;" in page
    for name in ("plm_pin", "pinocchio", "proxsuite", "highspy", "numpy", "python"):
        assert f"<th>{name}</th><td>{result.versions[name]}</td>" in page


def test_a_figure_with_nothing_drawn_is_its_caption_alone():
    """Section.figure(None, ...): the caption as a paragraph, no image, and its numbers in results.json."""

    def run(ctx):
        ctx.section("Flat").figure(None, "Torque. Not drawn, being flat to round-off: a: zero.", {"a": [0.0]})

    result = run_study(make_study(run))
    page = render_report(result)
    assert '<p class="flat">Torque. Not drawn, being flat to round-off: a: zero.</p>' in page
    assert "data:image/svg" not in page
    (block,) = result.to_dict()["sections"][0]["blocks"]
    assert block == {
        "kind": "figure",
        "caption": "Torque. Not drawn, being flat to round-off: a: zero.",
        "data": {"a": [0.0]},
    }
