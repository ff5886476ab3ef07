"""What a report holds: sections of text, tables, paper-vs-plm_pin comparisons, figures and scenes.

A study fills :class:`Section` objects through their methods; every number it shows in a
table, comparison, figure or scene is also kept as data, so that ``results.json`` holds it
(see :meth:`StudyResult.to_dict`). Text is prose: numbers belong in tables.
"""

from __future__ import annotations

import base64
import io
import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from .. import results
from ..exceptions import InvalidInput
from ..tolerances import COMPARISON_RTOL
from ..viz import scene_html
from .animation import Animation

if TYPE_CHECKING:
    from matplotlib.figure import Figure as MplFigure

FORMAT = "plm-pin-report/1"
"""Format tag of ``results.json``."""

Cell = str | int | float | bool | None
"""A table cell: text, a number (NaN and infinities allowed), a yes/no, or empty."""


def strict_json(value: object) -> Any:
    """``value`` as strict JSON for results.json: :func:`plm_pin.results.plain`, non-finite numbers as text.

    Raises:
        InvalidInput: for a value that has no JSON form.
    """
    try:
        return results.plain(value, nonfinite_as_text=True)
    except TypeError as exc:
        raise InvalidInput(f"{exc}: it cannot be written to results.json") from None


def _cell(value: Any, where: str) -> Cell:
    """A cell value as a plain Python value (numpy scalars converted)."""
    if value is None or isinstance(value, (str, bool)):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value)
    raise InvalidInput(f"{where}: a cell must be text, a number, a bool or None, got {value!r}")


def _is_number(value: Cell) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def format_cell(value: Cell, fmt: str = ".4g") -> str:
    """A cell as displayed: numbers by ``fmt`` (integers in full), yes/no, an em dash for None."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return format(value, fmt) if math.isfinite(value) else str(value)
    return value


@dataclass(frozen=True)
class Column:
    """A table column.

    Attributes:
        name: header.
        unit: unit of its numbers, shown in brackets ("N", "m", "deg"); empty when none.
        fmt: format specification of its numbers.
    """

    name: str
    unit: str = ""
    fmt: str = ".4g"

    @property
    def header(self) -> str:
        """The header as shown: ``name [unit]``."""
        return f"{self.name} [{self.unit}]" if self.unit else self.name


@dataclass(frozen=True)
class Text:
    """Prose: Markdown (CommonMark, raw HTML shown as text) or plain text."""

    kind: ClassVar[str] = "text"
    text: str
    markdown: bool = True

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json."""
        return {"kind": self.kind, "text": self.text, "markdown": self.markdown}


@dataclass(frozen=True)
class Table:
    """A table of values with units.

    Attributes:
        title: caption.
        columns: the columns.
        rows: the rows, one cell per column.
        note: a line under the table.
        id: a stable name to look the table up by (:meth:`StudyResult.block`), not shown; "" for none.
    """

    kind: ClassVar[str] = "table"
    title: str
    columns: tuple[Column, ...]
    rows: tuple[tuple[Cell, ...], ...]
    note: str = ""
    id: str = ""

    def __post_init__(self) -> None:
        for k, row in enumerate(self.rows):
            if len(row) != len(self.columns):
                raise InvalidInput(
                    f"table {self.title!r}: row {k} has {len(row)} cells for {len(self.columns)} columns"
                )

    def shown_columns(self) -> list[int]:
        """Indices of the columns holding a cell that is not None or empty text (the others are not shown)."""
        return [
            k
            for k in range(len(self.columns))
            if any(row[k] is not None and row[k] != "" for row in self.rows)
        ] or list(range(len(self.columns)))

    def formatted(self) -> list[list[tuple[str, bool]]]:
        """The rows as displayed: each cell's text and whether it is a number."""
        return [
            [(format_cell(v, c.fmt), _is_number(v)) for v, c in zip(row, self.columns, strict=True)]
            for row in self.rows
        ]

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json: columns with units and the raw rows."""
        return {
            "kind": self.kind,
            "title": self.title,
            "columns": [{"name": c.name, "unit": c.unit} for c in self.columns],
            "rows": strict_json(self.rows),
            "note": self.note,
        }


SOURCES = ("printed", "closed form", "input")
"""Where a comparison's paper value comes from: printed in the paper; a closed form of the paper
re-evaluated by the study; or an input of the study echoed back (not counted as an agreement)."""

PAPER_INCONSISTENT = "paper inconsistent — explained"
"""Verdict of a row whose difference is traced to the paper's own data."""


@dataclass(frozen=True)
class Comparison:
    r"""One row of a paper-vs-plm_pin table.

    Two numbers agree when :math:`|ours - paper| \le atol + rtol\,|paper|`; two texts (or
    yes/no values) when they are equal. A row that does not agree must say why.

    Attributes:
        quantity: what is compared, with the paper's equation, table or figure.
        paper: the paper's value (a number, a text or a yes/no).
        ours: plm_pin's value.
        unit: unit of both numbers.
        explanation: one line saying why they differ (required when they do; optional otherwise).
        rtol: relative tolerance, e.g. the paper's printed precision [-].
        atol: absolute tolerance [unit], needed when the paper's value is zero.
        fmt: format specification of the numbers.
        source: where ``paper`` comes from, among :data:`SOURCES`: ``printed`` in the paper, a
            ``closed form`` of the paper re-evaluated by the study, or an ``input`` of the study
            echoed back (a rod length checked against itself: shown, never counted as agreeing).
        paper_inconsistent: the difference is traced to the paper's own data (its printed values
            do not follow from its printed model), so it is no plm_pin failure; needs an
            ``explanation`` saying where the evidence is.
    """

    quantity: str
    paper: Cell
    ours: Cell
    unit: str = ""
    explanation: str = ""
    rtol: float = COMPARISON_RTOL
    atol: float = 0.0
    fmt: str = ".4g"
    source: str = "printed"
    paper_inconsistent: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "paper", _cell(self.paper, f"comparison {self.quantity!r}, paper"))
        object.__setattr__(self, "ours", _cell(self.ours, f"comparison {self.quantity!r}, ours"))
        if not (self.rtol >= 0.0 and self.atol >= 0.0):
            raise InvalidInput(f"comparison {self.quantity!r}: rtol and atol must be non-negative")
        if self.source not in SOURCES:
            raise InvalidInput(
                f"comparison {self.quantity!r}: source {self.source!r} is not one of {list(SOURCES)}"
            )
        if (not self.agrees or self.paper_inconsistent) and not self.explanation:
            raise InvalidInput(
                f"comparison {self.quantity!r}: paper {format_cell(self.paper, self.fmt)} and ours "
                f"{format_cell(self.ours, self.fmt)} differ; give an explanation"
            )
        if self.paper_inconsistent and (self.agrees or self.source != "printed"):
            raise InvalidInput(
                f"comparison {self.quantity!r}: paper_inconsistent is for a printed value that differs"
            )

    @property
    def counted(self) -> bool:
        """Whether the row counts in the agreement (an input echo does not)."""
        return self.source != "input"

    @property
    def verdict(self) -> str:
        """``agrees``, ``differs``, :data:`PAPER_INCONSISTENT`, or ``input echo``."""
        if not self.counted:
            return "input echo"
        if self.paper_inconsistent:
            return PAPER_INCONSISTENT
        return "agrees" if self.agrees else "differs"

    @property
    def numeric(self) -> bool:
        """Whether both values are numbers."""
        return _is_number(self.paper) and _is_number(self.ours)

    @property
    def relative_difference(self) -> float | None:
        """:math:`|ours - paper| / |paper|` for two numbers with a non-zero paper value, else None."""
        if not self.numeric or self.paper == 0:
            return None
        paper, ours = float(self.paper), float(self.ours)  # type: ignore[arg-type]
        return abs(ours - paper) / abs(paper)

    @property
    def agrees(self) -> bool:
        """Whether the values agree within the tolerances (numbers) or are equal (text, yes/no)."""
        if self.numeric:
            paper, ours = float(self.paper), float(self.ours)  # type: ignore[arg-type]
            return abs(ours - paper) <= self.atol + self.rtol * abs(paper)
        return self.paper == self.ours

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json, with the relative difference and the verdict."""
        return strict_json(
            {
                "quantity": self.quantity,
                "paper": self.paper,
                "ours": self.ours,
                "unit": self.unit,
                "relative_difference": self.relative_difference,
                "agrees": self.agrees,
                "verdict": self.verdict,
                "source": self.source,
                "explanation": self.explanation,
                "rtol": self.rtol,
                "atol": self.atol,
            }
        )


@dataclass(frozen=True)
class Comparisons:
    """A paper-vs-plm_pin table: quantity, paper value, ours, relative difference, explanation.

    Attributes:
        title: caption.
        rows: the rows.
        note: a line under the table.
        id: a stable name to look the table up by (:meth:`StudyResult.block`), not shown; "" for none.
    """

    kind: ClassVar[str] = "comparison"
    title: str
    rows: tuple[Comparison, ...]
    note: str = ""
    id: str = ""

    @property
    def n_agree(self) -> int:
        """Counted rows that agree (input echoes are not counted)."""
        return sum(r.agrees for r in self.rows if r.counted)

    @property
    def n_counted(self) -> int:
        """Rows that count in the agreement: all but the input echoes."""
        return sum(r.counted for r in self.rows)

    @property
    def n_paper_inconsistent(self) -> int:
        """Rows whose difference is traced to the paper's own data."""
        return sum(r.paper_inconsistent for r in self.rows)

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json."""
        return {
            "kind": self.kind,
            "title": self.title,
            "rows": [r.to_dict() for r in self.rows],
            "agree": self.n_agree,
            "total": self.n_counted,
            "paper_inconsistent": self.n_paper_inconsistent,
            "note": self.note,
        }


@dataclass(frozen=True)
class Figure:
    """A matplotlib figure, kept as SVG, with the data it draws.

    Attributes:
        caption: caption.
        svg: the figure as an SVG document ("" when nothing is drawn: the caption says why).
        data: the numbers drawn (for results.json).
    """

    kind: ClassVar[str] = "figure"
    caption: str
    svg: str
    data: Mapping[str, Any]

    @property
    def data_uri(self) -> str:
        """The SVG as a ``data:`` URI, for an ``<img>`` (scripts in it never run)."""
        return "data:image/svg+xml;base64," + base64.b64encode(self.svg.encode()).decode()

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json (the image itself is in the HTML only)."""
        return {"kind": self.kind, "caption": self.caption, "data": strict_json(self.data)}


@dataclass(frozen=True)
class Scene:
    """A static meshcat page (e.g. :func:`plm_pin.viz.scene_html`), shown in an ``<iframe srcdoc>``.

    Attributes:
        caption: caption.
        html: the self-contained page.
        data: the configurations shown (for results.json).
    """

    kind: ClassVar[str] = "scene"
    caption: str
    html: str
    data: Mapping[str, Any]

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json (the page itself is in the HTML only)."""
        return {"kind": self.kind, "caption": self.caption, "data": strict_json(self.data)}


@dataclass(frozen=True)
class Parameter:
    """A named value with its unit.

    Attributes:
        name: name.
        value: value (a number, a text, or a sequence of numbers).
        unit: unit, e.g. "m"; empty when none.
        note: where it comes from or what it means.
    """

    name: str
    value: Any
    unit: str = ""
    note: str = ""

    @property
    def shown(self) -> str:
        """The value as displayed (sequences in parentheses, nested as given)."""

        def text(value: Any) -> str:
            if isinstance(value, (list, tuple, np.ndarray)):
                return "(" + ", ".join(text(v) for v in value) + ")"
            return format_cell(_cell(value, f"parameter {self.name!r}"))

        return text(self.value)

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json."""
        return strict_json({"name": self.name, "value": self.value, "unit": self.unit, "note": self.note})


@dataclass(frozen=True)
class Parameters:
    """A list of parameters (name, value, unit, note)."""

    kind: ClassVar[str] = "parameters"
    title: str
    items: tuple[Parameter, ...]

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json."""
        return {"kind": self.kind, "title": self.title, "items": [p.to_dict() for p in self.items]}


@dataclass(frozen=True)
class Assumptions:
    """A list of assumptions: values chosen where a source is silent, conventions, simplifications."""

    kind: ClassVar[str] = "assumptions"
    title: str
    items: tuple[str, ...]

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json."""
        return {"kind": self.kind, "title": self.title, "items": list(self.items)}


Block = Text | Table | Comparisons | Figure | Scene | Parameters | Assumptions


def figure_svg(fig: MplFigure) -> str:
    """Render a matplotlib figure to SVG (no date, so a rerun gives the same file) and close it.

    Colour meshes are embedded as images (no seams between cells, smaller files).
    """
    import matplotlib.pyplot as plt  # the figure exists, so matplotlib is installed
    from matplotlib.collections import QuadMesh

    for mesh in fig.findobj(QuadMesh):
        mesh.set_rasterized(True)
    buffer = io.StringIO()
    fig.savefig(buffer, format="svg", bbox_inches="tight", dpi=150, metadata={"Date": None})
    plt.close(fig)
    return buffer.getvalue()


@dataclass
class Section:
    """A titled part of a report; a study adds blocks to it in reading order.

    Attributes:
        title: heading.
        blocks: its content.
    """

    title: str
    blocks: list[Block] = field(default_factory=list)

    def text(self, text: str, *, markdown: bool = True) -> Text:
        """Add prose (CommonMark unless ``markdown`` is False; raw HTML is shown as text)."""
        block = Text(text, markdown)
        self.blocks.append(block)
        return block

    def table(
        self,
        title: str,
        columns: Sequence[Column | str],
        rows: Sequence[Sequence[Any]],
        *,
        note: str = "",
        id: str = "",
    ) -> Table:
        """Add a table; a column given as a string has no unit; ``id`` names it for :meth:`StudyResult.block`.

        Raises:
            InvalidInput: a row of the wrong length or a cell that is not text, a number, a bool or None.
        """
        cols = tuple(c if isinstance(c, Column) else Column(c) for c in columns)
        cells = tuple(tuple(_cell(v, f"table {title!r}, row {k}") for v in row) for k, row in enumerate(rows))
        block = Table(title, cols, cells, note, id)
        self.blocks.append(block)
        return block

    def comparison(
        self, title: str, rows: Sequence[Comparison], *, note: str = "", id: str = ""
    ) -> Comparisons:
        """Add a paper-vs-plm_pin table; the relative differences and verdicts are computed.

        ``id`` names it for :meth:`StudyResult.block`.
        """
        block = Comparisons(title, tuple(rows), note, id)
        self.blocks.append(block)
        return block

    def figure(self, fig: MplFigure | None, caption: str, data: Mapping[str, Any]) -> Figure:
        """Add a matplotlib figure (rendered to SVG and closed) with the numbers it draws.

        ``fig`` None (every panel flat, see :func:`plm_pin.viz.plot_panels`): the caption, which
        then says what the panels hold, stands alone and the numbers still go to results.json.

        Raises:
            InvalidInput: ``data`` that has no JSON form.
        """
        strict_json(data)  # refuse data that results.json could not hold, before rendering
        block = Figure(caption, "" if fig is None else figure_svg(fig), data)
        self.blocks.append(block)
        return block

    def scene(self, html: str, caption: str, data: Mapping[str, Any]) -> Scene:
        """Add a static meshcat page with the configurations it shows (``q``, or ``qs`` and ``times``)."""
        strict_json(data)
        block = Scene(caption, html, data)
        self.blocks.append(block)
        return block

    def animation(self, animation: Animation, frames: int = 120) -> Scene:
        """Add a motion as a scene the reader plays in the page (at most ``frames`` configurations)."""
        shown = animation.thinned(frames)
        html = scene_html(shown.mechanism, qs=shown.qs, times=shown.times)
        return self.scene(html, animation.caption, {"qs": shown.qs, "times": shown.times})

    def parameters(self, title: str, items: Sequence[Parameter]) -> Parameters:
        """Add a list of parameters."""
        block = Parameters(title, tuple(items))
        for p in block.items:
            p.shown  # noqa: B018 - refuse values that cannot be shown, now
        self.blocks.append(block)
        return block

    def assumptions(self, title: str, items: Sequence[str]) -> Assumptions:
        """Add a list of assumptions."""
        block = Assumptions(title, tuple(items))
        self.blocks.append(block)
        return block

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json."""
        return {"title": self.title, "blocks": [b.to_dict() for b in self.blocks]}


@dataclass(frozen=True)
class MechanismInfo:
    """A mechanism a study used, as the report describes it.

    Attributes:
        name: mechanism name (from its description: may be anything).
        origin: where it came from: ``preset NAME``, the description's path, or built by the study.
        summary: :meth:`plm_pin.Mechanism.summary`.
        parameters: the preset's parameters (SI units), empty otherwise.
        assumptions: the preset's notes (values chosen where the paper is silent), empty otherwise.
    """

    name: str
    origin: str
    summary: Mapping[str, Any]
    parameters: tuple[Parameter, ...]
    assumptions: tuple[str, ...]

    def to_dict(self) -> dict[str, object]:
        """Plain data for results.json."""
        return strict_json(
            {
                "name": self.name,
                "origin": self.origin,
                "summary": self.summary,
                "parameters": [p.to_dict() for p in self.parameters],
                "assumptions": list(self.assumptions),
            }
        )


@dataclass(frozen=True)
class StudyResult:
    """A study's report, before it is written.

    Attributes:
        study: study name (its module in ``analyses``).
        title: report title.
        summary: one line for the index.
        folder: the report's folder name inside the output folder.
        mechanisms: the mechanisms it used.
        sections: its content, in order.
        warnings: warnings plm_pin emitted while it ran.
        command: the shell command that writes this report again.
        versions: software versions.
        generated: when it ran (ISO 8601, UTC).
        elapsed: how long it ran [s].
    """

    study: str
    title: str
    summary: str
    folder: str
    mechanisms: tuple[MechanismInfo, ...]
    sections: tuple[Section, ...]
    warnings: tuple[str, ...]
    command: str
    versions: Mapping[str, str]
    generated: str
    elapsed: float

    def comparisons(self) -> list[Comparisons]:
        """Every paper-vs-plm_pin table."""
        return [b for s in self.sections for b in s.blocks if isinstance(b, Comparisons)]

    def block(self, id: str) -> Table | Comparisons:
        """The table or paper-vs-plm_pin table named ``id``.

        Raises:
            KeyError: no block of the report has this id.
        """
        for section in self.sections:
            for b in section.blocks:
                if isinstance(b, (Table, Comparisons)) and b.id == id:
                    return b
        raise KeyError(f"no table {id!r} in the report of {self.study!r}")

    def to_dict(self) -> dict[str, object]:
        """The content of ``results.json``: every number shown, with units, and how it was made."""
        rows = [r for c in self.comparisons() for r in c.rows if r.counted]
        return {
            "format": FORMAT,
            "study": self.study,
            "title": self.title,
            "summary": self.summary,
            "folder": self.folder,
            "mechanisms": [m.to_dict() for m in self.mechanisms],
            "sections": [s.to_dict() for s in self.sections],
            "agreement": {
                "rows": len(rows),
                "agree": sum(r.agrees for r in rows),
                "paper_inconsistent": sum(r.paper_inconsistent for r in rows),
            },
            "warnings": list(self.warnings),
            "command": self.command,
            "versions": dict(self.versions),
            "generated": self.generated,
            "elapsed_s": self.elapsed,
        }
