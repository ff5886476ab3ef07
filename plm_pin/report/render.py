"""HTML of reports and of the index, by jinja2 templates with autoescaping.

Every string from a study or a user's description (names, captions, table cells) is
escaped by jinja2; Markdown text is rendered by markdown-it with raw HTML shown as text;
figures are ``<img>`` of SVG ``data:`` URIs and meshcat scenes ``<iframe sandbox srcdoc>``,
so neither can run code in the report page. jinja2 is imported here only when rendering.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from .content import StudyResult, format_cell

if TYPE_CHECKING:
    import jinja2


@functools.cache
def _environment() -> jinja2.Environment:
    try:
        import jinja2
        from markdown_it import MarkdownIt
    except ImportError as exc:
        raise ImportError(
            "plm_pin.report needs jinja2 and markdown-it-py, which are not installed: "
            "pip install 'plm-pin[report]'"
        ) from exc
    markdown = MarkdownIt("commonmark", {"html": False}).enable("table")
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("plm_pin.report", "templates"),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["markdown"] = lambda text: jinja2.filters.Markup(markdown.render(text))
    env.filters["cell"] = format_cell
    env.filters["relative"] = lambda value: "—" if value is None else f"{value:.2e}"
    return env


def require_renderer() -> None:
    """Check that the report extra (jinja2, markdown-it-py) is installed, before any study runs.

    Raises:
        ImportError: naming ``pip install 'plm-pin[report]'``.
    """
    _environment()


def render_report(result: StudyResult, scene_files: Mapping[int, str] | None = None) -> str:
    """The HTML page of one report.

    Args:
        result: the report.
        scene_files: file name, beside the page, of each scene (by ``id`` of its block), which
            the page then shows with ``<iframe src>`` (lazily loaded); scenes not listed are
            inlined whole in ``<iframe srcdoc>``, so that the page is self-contained.
    """
    files = scene_files or {}
    return (
        _environment()
        .get_template("report.html.j2")
        .render(r=result, scene_file=lambda scene: files.get(id(scene)))
    )


def render_index(entries: Sequence[Mapping[str, Any]], versions: Mapping[str, str]) -> str:
    """The index page: one entry per report (``folder`` and the report's ``results.json`` content)."""
    return _environment().get_template("index.html.j2").render(entries=entries, versions=versions)
