"""What the colours and marks of a meshcat scene mean: the scene's palette and a legend drawn over its page.

The legend is plain HTML (a ``<div>`` fixed in the page's lower left corner, above the
3-D canvas) inserted in meshcat's page: in the static pages of reports and
:meth:`~plm_pin.viz.MeshcatViewer.static_html` it lists what the scene draws; the page a
live server serves lists every mark a viewer can draw. No JavaScript, no import of meshcat.
"""

from __future__ import annotations

import html
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from ..exceptions import InvalidInput

RGBA = tuple[float, float, float, float]

CLOSED_COLOR: RGBA = (0.1, 0.7, 0.2, 1.0)
"""RGBA of the markers of a closure that holds."""

OPEN_COLOR: RGBA = (1.0, 0.0, 1.0, 1.0)
"""RGBA of the markers of a closure that does not hold."""

SINGULAR_COLORS: Mapping[str, RGBA] = {
    "constraint": (0.95, 0.8, 0.1, 1.0),
    "inverse": (1.0, 0.5, 0.0, 1.0),
    "direct": (0.85, 0.1, 0.1, 1.0),
}
"""RGBA of the mechanism at a singularity, by kind (the first kind found wins), and of singular points."""

SKELETON_COLOR: RGBA = (0.45, 0.5, 0.6, 1.0)
"""RGBA of the rods and balls drawn for a mechanism without visual geometry."""

VIRTUAL_COLOR: RGBA = (0.55, 0.55, 0.55, 0.6)
"""RGBA of the dashed lines from the base origin to the joints on the base (not links)."""

RAIL_COLOR: RGBA = (0.3, 0.3, 0.35, 0.5)
"""RGBA of the rails: the stroke of each prismatic joint between its limits."""

PLATFORM_COLOR: RGBA = (0.1, 0.35, 0.8, 1.0)
"""RGBA of the closed polygon through a platform's attachment points."""

WORKSPACE_COLOR: RGBA = (0.0, 0.6, 0.6, 1.0)
"""RGBA of the points of a workspace slice's boundary."""

FORCE_COLOR = 0x1F5FBF
"""Colour of force arrows (0xRRGGBB)."""

ELLIPSE_COLOR = 0x2E8B57
"""Colour of the inspector's velocity ellipse (0xRRGGBB), drawn at :data:`ELLIPSE_OPACITY`."""

ELLIPSE_OPACITY = 0.35
"""Opacity of the inspector's velocity ellipse [-]."""

STIFFNESS_COLOR = 0x8A2BE2
"""Colour of the inspector's smallest-stiffness axis (0xRRGGBB)."""

ELEMENT_ID = "plm-pin-legend"
"""``id`` of the legend's ``<div>`` in a page."""


@dataclass(frozen=True)
class LegendEntry:
    """One line of a legend: a swatch drawn as ``mark`` in ``color``, then ``label``.

    Attributes:
        label: what the mark means.
        color: RGBA in [0, 1].
        mark: the swatch's shape, one of :data:`MARKS`.
    """

    label: str
    color: RGBA
    mark: str


MARKS = ("ball", "rod", "dashed", "band", "outline", "arrow", "dot")
"""Swatch shapes of :class:`LegendEntry`."""


def _hex(rgb: int, alpha: float = 1.0) -> RGBA:
    return ((rgb >> 16 & 255) / 255, (rgb >> 8 & 255) / 255, (rgb & 255) / 255, alpha)


ENTRIES: Mapping[str, LegendEntry] = {
    "direct": LegendEntry("direct singularity (type 2)", SINGULAR_COLORS["direct"], "band"),
    "inverse": LegendEntry("inverse singularity (type 1)", SINGULAR_COLORS["inverse"], "band"),
    "constraint": LegendEntry("constraint singularity", SINGULAR_COLORS["constraint"], "band"),
    "closed": LegendEntry("closure holds", CLOSED_COLOR, "ball"),
    "open": LegendEntry("closure open", OPEN_COLOR, "ball"),
    "link": LegendEntry("link", SKELETON_COLOR, "rod"),
    "virtual": LegendEntry("base to joint (no link)", VIRTUAL_COLOR, "dashed"),
    "rail": LegendEntry("rail: prismatic stroke", RAIL_COLOR, "rod"),
    "platform": LegendEntry("platform", PLATFORM_COLOR, "outline"),
    "force": LegendEntry("force", _hex(FORCE_COLOR), "arrow"),
    "workspace": LegendEntry("workspace boundary", WORKSPACE_COLOR, "dot"),
    "ellipse": LegendEntry("velocity ellipse", _hex(ELLIPSE_COLOR, ELLIPSE_OPACITY), "band"),
    "stiffness": LegendEntry("softest axis (smallest stiffness)", _hex(STIFFNESS_COLOR), "rod"),
}
"""Every mark a :class:`~plm_pin.viz.MeshcatViewer` or the live inspector draws, by key; singular
kinds colour the mechanism and the singular points alike."""

_SWATCH = {
    "ball": "width:10px;height:10px;border-radius:50%;background:{c}",
    "rod": "width:18px;height:4px;background:{c}",
    "dashed": "width:18px;height:0;border-top:2px dashed {c}",
    "band": "width:18px;height:10px;background:{c}",
    "outline": "width:14px;height:8px;border:2px solid {c}",
    "arrow": "width:0;height:0;border-left:14px solid {c};border-top:5px solid transparent;"
    "border-bottom:5px solid transparent",
    "dot": "width:5px;height:5px;background:{c}",
}

_STYLE = (
    "position:fixed;left:8px;bottom:8px;z-index:10;margin:0;padding:6px 8px;list-style:none;"
    "font:12px/1.5 sans-serif;color:#111;background:rgba(255,255,255,0.85);border-radius:4px;"
    "pointer-events:none"
)


def _css(color: RGBA) -> str:
    r, g, b, a = (float(v) for v in color)
    return f"rgba({round(255 * r)},{round(255 * g)},{round(255 * b)},{a:.3g})"


def legend_html(entries: Sequence[LegendEntry]) -> str:
    """The legend as one ``<ul id="plm-pin-legend">`` fixed over the page's lower left corner.

    Args:
        entries: its lines, in order (e.g. values of :data:`ENTRIES`).

    Raises:
        InvalidInput: an entry whose mark is not one of :data:`MARKS`.
    """
    rows = []
    for entry in entries:
        if entry.mark not in _SWATCH:
            raise InvalidInput(
                f"legend entry {entry.label!r}: mark {entry.mark!r} is not one of {list(MARKS)}"
            )
        swatch = _SWATCH[entry.mark].format(c=_css(entry.color))
        rows.append(
            '<li style="display:flex;align-items:center;gap:6px">'
            f'<span style="display:inline-block;{swatch}"></span>{html.escape(entry.label)}</li>'
        )
    return f'<ul id="{ELEMENT_ID}" style="{_STYLE}">{"".join(rows)}</ul>'


def with_legend(page: str, entries: Sequence[LegendEntry]) -> str:
    """``page`` (meshcat's HTML) with :func:`legend_html` of ``entries`` before its last ``</body>``.

    No entries: ``page`` unchanged.

    Raises:
        InvalidInput: a page without ``</body>``.
    """
    if not entries:
        return page
    end = page.rfind("</body>")
    if end < 0:
        raise InvalidInput("page: no </body> to put the legend before; give meshcat's HTML page")
    return page[:end] + legend_html(entries) + page[end:]
