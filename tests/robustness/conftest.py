"""Shared pieces of the robustness suite: copies of the four-bar description, the CLI runner, the budget."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import yaml
from hypothesis import HealthCheck, settings
from typer.testing import CliRunner

from plm_pin.cli import app

REPO = Path(__file__).resolve().parents[2]
URDF = REPO / "urdf"

EXAMPLES = 40
"""Examples each property-based test of this suite tries (hypothesis ``max_examples``)."""

budget = settings(
    max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
"""The settings of every property-based test here: a fixed number of examples, no time limit."""


def fourbar_files(folder: Path, sidecar: str | None = None, urdf: str | None = None) -> Path:
    """Write the shipped four-bar (or the given texts) into ``folder``; returns the URDF path."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "fourbar.urdf"
    if urdf is None:
        shutil.copy(URDF / "fourbar.urdf", path)
    else:
        path.write_text(urdf, encoding="utf-8")
    side = folder / "fourbar.plm.yaml"
    if sidecar is None:
        shutil.copy(URDF / "fourbar.plm.yaml", side)
    else:
        side.write_text(sidecar, encoding="utf-8")
    return path


def fourbar_sidecar() -> dict[str, Any]:
    """The shipped four-bar sidecar as plain data."""
    return yaml.safe_load((URDF / "fourbar.plm.yaml").read_text(encoding="utf-8"))


def fourbar_urdf() -> str:
    """The shipped four-bar URDF text."""
    return (URDF / "fourbar.urdf").read_text(encoding="utf-8")


def run_cli(*args: str) -> Any:
    """Run ``plm-pin ARGS`` in this process; returns click's result (exit_code, stdout, stderr)."""
    return CliRunner().invoke(app, list(args))


def one_line_error(result: Any) -> str:
    """Check a CLI run failed with exit code 1 and one ``error:`` line, no traceback; returns that line."""
    assert result.exit_code == 1, (result.exit_code, result.output, result.exception)
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    assert "Traceback" not in result.output
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("error: ")]
    assert len(errors) == 1, result.stderr
    return errors[0]
