"""Report content: cells, tables, comparisons, figures (plm_pin/report/content.py)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from plm_pin.exceptions import InvalidInput
from plm_pin.report import Column, Comparison, Section
from plm_pin.report.content import format_cell, strict_json
from plm_pin.report.folders import slug


def test_relative_difference_and_verdict_of_numbers():
    """|ours - paper| / |paper| by hand; agreement within atol + rtol |paper|."""
    row = Comparison("l", 0.240, 0.2403, "m", rtol=2e-3)
    assert row.relative_difference == pytest.approx(0.0003 / 0.240, rel=1e-12)
    assert row.agrees
    assert not Comparison("l", 0.240, 0.2403, "m", rtol=1e-3, explanation="why").agrees
    zero = Comparison("x stays 0", 0.0, 3e-12, "m", atol=1e-9)
    assert zero.relative_difference is None and zero.agrees
    assert Comparison("count", 9, np.int64(9)).relative_difference == 0.0


def test_text_and_yes_no_compare_by_equality():
    """Texts and bools agree when equal; there is no relative difference."""
    assert Comparison("route", "[+ +] → [- -]", "[+ +] → [- -]").agrees
    assert Comparison("singular", True, np.bool_(True)).agrees
    row = Comparison("singular", True, False, explanation="a reason")
    assert not row.agrees and row.relative_difference is None


def test_a_difference_needs_an_explanation():
    """A row that differs without an explanation is refused, naming both values."""
    with pytest.raises(
        InvalidInput, match=r"comparison 'w': paper 0.158 and ours 0.2 differ; give an explanation"
    ):
        Comparison("w", 0.158, 0.2)


def test_comparison_json_has_the_computed_difference():
    """to_dict() carries the values, the relative difference and the verdict."""
    data = Comparison("l", 2.0, 2.5, "m", explanation="e").to_dict()
    assert data["relative_difference"] == 0.25 and data["agrees"] is False and data["unit"] == "m"


def test_table_cells_are_checked_and_formatted():
    """Rows must match the columns; cells are text, numbers, bools or None, shown with their format."""
    section = Section("s")
    table = section.table("t", ["a", Column("b", "m", ".2f")], [("x", np.float64(1.234)), ("y", None)])
    assert table.formatted() == [[("x", False), ("1.23", True)], [("y", False), ("—", False)]]
    assert table.columns[1].header == "b [m]"
    with pytest.raises(InvalidInput, match=r"table 't2': row 0 has 1 cells for 2 columns"):
        section.table("t2", ["a", "b"], [("x",)])
    with pytest.raises(
        InvalidInput, match=r"table 't3', row 0: a cell must be text, a number, a bool or None"
    ):
        section.table("t3", ["a"], [([1, 2],)])


def test_format_cell():
    """Integers in full, floats by format, nan/inf as words, bools as yes/no, None as a dash."""
    assert format_cell(123456789) == "123456789"
    assert format_cell(0.000123456, ".3g") == "0.000123"
    assert format_cell(math.inf) == "inf" and format_cell(math.nan) == "nan"
    assert format_cell(True) == "yes" and format_cell(None) == "—"


def test_strict_json_of_numpy_nonfinite_tuples_and_results():
    """Numpy values, NaN, infinities, tuples and to_dict objects become strict JSON."""
    data = strict_json({"a": np.array([1.0, np.nan]), "b": (np.int32(2), np.inf), "c": Comparison("x", 1, 1)})
    assert data["a"] == [1.0, "nan"] and data["b"] == [2, "inf"]
    json.dumps(data, allow_nan=False)
    with pytest.raises(InvalidInput, match=r"cannot be written to results.json"):
        strict_json({"f": object()})


def test_figure_keeps_svg_and_its_data():
    """A matplotlib figure is kept as SVG (closed afterwards) with its data; bad data is refused first."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.pcolormesh(np.arange(12.0).reshape(3, 4))
    block = Section("s").figure(fig, "cap", {"z": np.arange(3.0)})
    assert block.svg.lstrip().startswith("<?xml") and "<svg" in block.svg
    assert "<image" in block.svg  # the colour mesh is embedded as an image
    assert not plt.fignum_exists(fig.number)
    assert block.data_uri.startswith("data:image/svg+xml;base64,")
    with pytest.raises(InvalidInput):
        Section("s").figure(plt.figure(), "cap", {"bad": object()})
    plt.close("all")


def test_slug_keeps_names_plain():
    """Folder pieces from user names: no dots, slashes or markup survive."""
    assert slug("../x") == "x"
    assert slug("<script>alert(1)</script>") == "script_alert_1_script"
    assert slug("...") == "mechanism"
    assert slug("fivebar") == "fivebar"


def test_sources_and_verdicts_of_comparisons():
    """Printed / closed form / input; an input echo is not counted; a paper inconsistency has its verdict."""
    assert Comparison("w", 1.0, 1.0).source == "printed"
    assert Comparison("f_c, eq. (15)", 0.5, 0.5, source="closed form").verdict == "agrees"
    echo = Comparison("rod length", 0.24, 0.24, "m", source="input")
    assert echo.verdict == "input echo" and not echo.counted
    table5 = Comparison(
        "W_1, Table 5", 99.7, 84.6, "J", explanation="Table 5 is off", paper_inconsistent=True
    )
    assert table5.verdict == "paper inconsistent — explained" and table5.counted
    section = Section("s")
    block = section.comparison("t", [echo, table5, Comparison("n", 1, 1)])
    assert (block.n_agree, block.n_counted, block.n_paper_inconsistent) == (1, 2, 1)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"source": "guessed"}, r"source 'guessed' is not one of \['printed', 'closed form', 'input'\]"),
        ({"paper_inconsistent": True}, "give an explanation"),
        ({"paper_inconsistent": True, "explanation": "x", "source": "closed form"}, "for a printed value"),
    ],
)
def test_bad_sources_and_inconsistencies_are_refused(kwargs, message):
    """An unknown source, a paper inconsistency unexplained or not on a printed value: refused."""
    with pytest.raises(InvalidInput, match=message):
        Comparison("W", 1.0, 2.0, **kwargs)


def test_empty_columns_are_not_shown():
    """A column whose cells are all None or empty text is dropped from the page (kept in the data)."""
    block = Section("s").table("t", ["a", "b", "c"], [(1, None, ""), (2, None, "x")])
    assert block.shown_columns() == [0, 2]
