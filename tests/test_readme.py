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


def _run_python_blocks(page: Path) -> None:
    """Every ```python block of ``page`` executes, in order, in one namespace."""
    blocks = re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.S)
    assert blocks, f"{page.name} shows no Python example"
    namespace: dict[str, object] = {}
    for block in blocks:
        exec(compile(block, str(page), "exec"), namespace)


def test_readme_python_blocks_run():
    """Every ```python block of the README executes, in order, in one namespace."""
    _run_python_blocks(README)


@pytest.mark.parametrize("stem", GUIDE_PAGES)
def test_guide_python_blocks_run(stem: str):
    """Every ```python block of a guide page that holds the README's former examples executes."""
    _run_python_blocks(REPO / "docs" / "guide" / f"{stem}.md")
