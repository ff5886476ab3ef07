"""Text hygiene: no control characters in sources, docstrings or docs; a CHANGELOG that reads."""

from __future__ import annotations

import ast
import os
import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TEXT_SUFFIXES = {".py", ".md", ".yaml", ".yml", ".toml", ".json", ".urdf", ".j2", ".css", ".ipynb", ".txt"}
"""The committed text files checked (by suffix); the Makefile is checked on its own, tabs allowed."""
SKIPPED_FOLDERS = {".git", ".venv", "_build", "reports", "build", "dist", "jupyter_execute", "node_modules"}
CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f]")
"""Control characters but newline and tab: a TAB, BEL or BS in a docstring is a lost backslash."""
CHANGELOG_LINE = 150
"""[characters] the longest CHANGELOG line: one short line per change."""


def _text_files() -> list[Path]:
    """The checkout's text files, walked without entering skipped or hidden folders (.venv, .git)."""
    found = []
    for folder, subfolders, files in os.walk(REPO):
        subfolders[:] = [d for d in subfolders if d not in SKIPPED_FOLDERS and (d == ".ci" or d[0] != ".")]
        found += [Path(folder) / f for f in files if Path(f).suffix in TEXT_SUFFIXES]
    return sorted(found)


def _control_characters(text: str, *, tabs: bool) -> list[str]:
    """``line:column 0xNN`` of each control character (tabs too unless ``tabs``) in ``text``."""
    found = []
    for number, line in enumerate(text.splitlines(), 1):
        for match in CONTROL.finditer(line if tabs else line.replace("\t", "\x0b")):
            found.append(f"{number}:{match.start() + 1} {ord(line[match.start()]):#04x}")
    return found


def test_control_character_scan_finds_what_it_looks_for():
    """The scan reports a BEL and, where tabs are not allowed, a TAB; it passes plain text and newlines."""
    assert _control_characters("\\alpha\n\\times", tabs=False) == []
    assert _control_characters(":math:`\x07lpha`\nw \times v", tabs=False) == ["1:8 0x07", "2:3 0x09"]
    assert _control_characters("a\tb", tabs=True) == []


def test_no_control_characters_in_text_files():
    """No committed source, docs or data file holds a control character but newline (tabs: Makefile only)."""
    files = _text_files()
    assert len(files) > 100  # the walk found the checkout
    bad = {
        str(p.relative_to(REPO)): found
        for p in files
        if (found := _control_characters(p.read_text(encoding="utf-8"), tabs=False))
    }
    makefile = REPO / "Makefile"
    if found := _control_characters(makefile.read_text(encoding="utf-8"), tabs=True):
        bad["Makefile"] = found
    assert bad == {}


def test_no_control_characters_in_docstrings():
    r"""No docstring holds a control character once Python reads it (``"\times"`` not raw is a TAB)."""
    bad = []
    for path in _text_files():
        if path.suffix != ".py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
                doc = ast.get_docstring(node, clean=False)
                if doc and _control_characters(doc, tabs=False):
                    bad.append(f"{path.relative_to(REPO)}:{getattr(node, 'lineno', 1)}")
    assert bad == []


def test_changelog_has_one_short_line_per_change():
    """Every CHANGELOG line fits CHANGELOG_LINE characters; entries are single "- " lines, no continuation."""
    lines = (REPO / "CHANGELOG.md").read_text(encoding="utf-8").splitlines()
    assert [n for n, line in enumerate(lines, 1) if len(line) > CHANGELOG_LINE] == []
    allowed = re.compile(r"^(# .+|## .+|### .+|- \S.*|\S.*|)$")  # headings, entries, prose, blank lines
    assert [n for n, line in enumerate(lines, 1) if not allowed.match(line)] == []


def test_changelog_releases_the_current_version():
    """An Unreleased section on top, then the release of plm_pin.__version__ with its date."""
    from plm_pin import __version__

    headings = re.findall(r"^## (.+)$", (REPO / "CHANGELOG.md").read_text(encoding="utf-8"), flags=re.M)
    assert headings[0] == "Unreleased"
    assert re.fullmatch(rf"{re.escape(__version__)} \u2014 \d{{4}}-\d{{2}}-\d{{2}}", headings[1]), headings[1]
