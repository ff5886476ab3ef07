"""The Python examples of the README and of the guide pages taken from it run as written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
GUIDE_PAGES = (
    "kinematics",
    "singularities",
    "statics",
    "stiffness",
    "accuracy",
    "viewer",
    "dynamics",
    "simulation",
    "sweeps",
    "mujoco",
    "cad-and-mujoco",
    "any-robot",
    "legs",
)
"""The docs/guide pages whose examples were the README's (each in a namespace of its own)."""


def _run_python_blocks(page: Path, workdir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every ```python block of ``page`` executes, in order, in one namespace, from ``workdir``.

    The examples write files by relative paths (``viewer.write_html("fivebar.html")``); run from a
    temporary folder, they leave nothing in the checkout.
    """
    monkeypatch.chdir(workdir)
    blocks = re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.S)
    assert blocks, f"{page.name} shows no Python example"
    namespace: dict[str, object] = {}
    for block in blocks:
        exec(compile(block, str(page), "exec"), namespace)


def test_readme_python_blocks_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """Every ```python block of the README executes, in order, in one namespace."""
    _run_python_blocks(README, tmp_path, monkeypatch)


@pytest.mark.parametrize("stem", GUIDE_PAGES)
def test_guide_python_blocks_run(stem: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """Every ```python block of a guide page that holds the README's former examples executes."""
    _run_python_blocks(REPO / "docs" / "guide" / f"{stem}.md", tmp_path, monkeypatch)
