"""Numbers shown in a report page, read back from its HTML, against its results.json."""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser
from pathlib import Path

NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?|nan|inf"
NUMBERS_CELL = re.compile(rf"^[\s(\[]*(?:{NUMBER})(?:[\s,/]+(?:{NUMBER}))*[\s)\]]*$")


class _Cells(HTMLParser):
    """The text of every table cell, outside the software-versions table."""

    def __init__(self) -> None:
        super().__init__()
        self.cells: list[str] = []
        self._skip = 0
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        if tag == "table" and ("class", "versions") in attrs:
            self._skip += 1
        if tag in ("td", "th", "caption") and not self._skip:
            self._cell = []

    def handle_endtag(self, tag):
        if tag == "table" and self._skip:
            self._skip -= 1
        if tag in ("td", "th", "caption") and self._cell is not None:
            self.cells.append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _json_numbers(data) -> list[float]:
    if isinstance(data, bool):
        return []
    if isinstance(data, (int, float)):
        return [float(data)]
    if isinstance(data, str):
        return [float(data)] if data in ("nan", "inf", "-inf") else []
    if isinstance(data, dict):
        return [n for v in data.values() for n in _json_numbers(v)]
    if isinstance(data, list):
        return [n for v in data for n in _json_numbers(v)]
    return []


def _half_last_digit(text: str) -> float:
    """Half a unit of the last digit shown: the rounding a formatted number may carry."""
    mantissa, _, exponent = text.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 0.5 * 10.0 ** (int(exponent or 0) - decimals)


def _shown(value: float, text: str, numbers: list[float]) -> bool:
    if text in ("nan", "inf", "-inf"):
        return any(str(n) == text for n in numbers)
    tol = _half_last_digit(text) * (1 + 1e-9)
    return any(abs(n - value) <= tol for n in numbers)


def unlisted_numbers(folder: Path) -> tuple[int, list[str]]:
    """How many numbers the tables of ``folder/report.html`` show, and those missing from results.json."""
    numbers = _json_numbers(json.loads((folder / "results.json").read_text()))
    parser = _Cells()
    parser.feed((folder / "report.html").read_text())
    shown, missing = 0, []
    for cell in parser.cells:
        if NUMBERS_CELL.match(cell):
            for text in re.findall(NUMBER, cell):
                shown += 1
                if not _shown(float(text), text, numbers):
                    missing.append(f"{text} (in {cell!r})")
    return shown, missing
