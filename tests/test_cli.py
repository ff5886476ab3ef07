"""The plm-pin command line (plm_pin/cli.py)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from plm_pin.cli import app
from plm_pin.models import PRESETS, urdf_folder

runner = CliRunner()


@pytest.fixture
def fourbar(tmp_path) -> Path:
    """A copy of the fourbar preset in a temporary folder; returns the URDF path."""
    for suffix in (".urdf", ".plm.yaml"):
        shutil.copy(urdf_folder() / f"fourbar{suffix}", tmp_path / f"fourbar{suffix}")
    return tmp_path / "fourbar.urdf"


def _break_closure_type(urdf: Path, bad: str) -> Path:
    """Set the first closure's type to ``bad`` in the sidecar beside ``urdf``; returns the sidecar."""
    sidecar = urdf.with_name("fourbar.plm.yaml")
    data = yaml.safe_load(sidecar.read_text())
    data["closures"][0]["type"] = bad
    sidecar.write_text(yaml.safe_dump(data, sort_keys=False))
    return sidecar


def _assert_clean_failure(result, stderr_line: str) -> None:
    """Exit code 1, nothing on stdout, exactly one 'error:' line on stderr, no traceback."""
    assert result.exit_code == 1, result.output
    assert isinstance(result.exception, SystemExit)
    assert result.stdout == ""
    assert result.stderr == f"error: {stderr_line}\n"
    assert "Traceback" not in result.output


def test_list_shows_every_preset():
    """`list` succeeds and names every preset."""
    result = runner.invoke(app, ["list"])
    assert result.exit_code == 0, result.output
    for name in PRESETS:
        assert name in result.stdout


def test_info_shows_mobility_and_redundancy_of_3d4m():
    """`info harada2011_3d4m` reports mobility 3 and redundancy 1 (four sliders, three DOF)."""
    result = runner.invoke(app, ["info", "harada2011_3d4m"])
    assert result.exit_code == 0, result.output
    rows = {
        cells[0]: cells[1]
        for line in result.stdout.splitlines()
        if len(cells := [c.strip() for c in line.strip("│ ").split("│")]) == 2
    }
    assert rows["mobility"] == "3"
    assert rows["redundancy"] == "1"
    assert rows["task"] == "plate_center: x y rz"


def test_info_json_parses():
    """`info --json fourbar` prints valid JSON with mobility 1 and the crank as actuator."""
    result = runner.invoke(app, ["info", "--json", "fourbar"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["name"] == "fourbar"
    assert summary["mobility"] == 1
    assert summary["redundancy"] == 0
    assert [a["joint"] for a in summary["actuators"]] == ["crank_pivot"]


def test_info_unknown_target_is_one_error_line():
    """`info nonsense` exits 1 with one 'error:' line saying it is neither a preset nor a path."""
    result = runner.invoke(app, ["info", "nonsense"])
    assert result.exit_code == 1
    assert result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("error: 'nonsense' is neither a preset nor an existing path; presets are [")
    assert "Traceback" not in result.output


def test_check_good_description_prints_ok(fourbar):
    """`check` on a valid description prints an ok line with its sizes and mobility."""
    result = runner.invoke(app, ["check", str(fourbar)])
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith(
        "ok: fourbar: 1 closures, 1 actuators, mobility 1, redundancy 0, reference residual "
    )
    assert result.stderr == ""


def test_check_broken_sidecar_names_file_and_bad_type(fourbar):
    """`check` on a sidecar with an invalid closure type exits 1 naming the file and the type."""
    sidecar = _break_closure_type(fourbar, "hinge")
    result = runner.invoke(app, ["check", str(fourbar)])
    _assert_clean_failure(
        result,
        f"{sidecar}: closures[0] (coupler_rocker): invalid closure type 'hinge'; "
        "valid types are ['point', 'revolute', 'weld']",
    )


@pytest.mark.parametrize("bad", ["[/oops]", "[red]hinge", "[bold]"])
def test_check_prints_bracketed_values_verbatim(fourbar, bad):
    """Values that look like rich markup are printed as they are, never interpreted or crashed on."""
    sidecar = _break_closure_type(fourbar, bad)
    result = runner.invoke(app, ["check", str(fourbar)])
    _assert_clean_failure(
        result,
        f"{sidecar}: closures[0] (coupler_rocker): invalid closure type {bad!r}; "
        "valid types are ['point', 'revolute', 'weld']",
    )


def test_info_and_check_print_bracketed_names_verbatim(fourbar):
    """A mechanism and closure named like rich markup appear literally in `check` and `info`."""
    sidecar = fourbar.with_name("fourbar.plm.yaml")
    data = yaml.safe_load(sidecar.read_text())
    data["name"] = "[/weird]"
    data["closures"][0]["name"] = "[bold]loop"
    sidecar.write_text(yaml.safe_dump(data, sort_keys=False))
    checked = runner.invoke(app, ["check", str(fourbar)])
    assert checked.exit_code == 0, checked.output
    assert checked.stdout.startswith("ok: [/weird]: 1 closures")
    shown = runner.invoke(app, ["info", str(fourbar)])
    assert shown.exit_code == 0, shown.output
    assert "[/weird]" in shown.stdout
    assert "closure [bold]loop" in shown.stdout


def test_check_reports_missing_meshes_as_a_warning(fourbar):
    """`check` on a description with a missing mesh succeeds and prints one warning on stderr."""
    text = fourbar.read_text()
    assert text.count('<box size="0.3 0.01 0.004"/>') == 1
    fourbar.write_text(text.replace('<box size="0.3 0.01 0.004"/>', '<mesh filename="base.stl"/>'))
    result = runner.invoke(app, ["check", str(fourbar)])
    assert result.exit_code == 0, result.output
    assert result.stderr == (
        f"warning: {fourbar}: 1 mesh file(s) missing, loading without those visuals: base.stl\n"
    )
    assert result.stdout.startswith("ok: fourbar:")


def test_report_all_writes_every_preset(tmp_path):
    """`report all --out DIR` writes summary.json with one entry per preset, loops closed."""
    out = tmp_path / "reports"
    result = runner.invoke(app, ["report", "all", "--out", str(out)])
    assert result.exit_code == 0, result.output
    rows = json.loads((out / "summary.json").read_text())
    assert [r["name"] for r in rows] == list(PRESETS)
    for r in rows:
        assert r["mobility"] == PRESETS[r["name"]].dof
        assert r["redundancy"] == PRESETS[r["name"]].redundancy
        assert r["reference_residual"] <= 1e-12
        assert len(r["q_ref"]) == r["nq"]
    assert result.stdout.splitlines()[-1] == f"wrote {out / 'summary.json'}"


def test_report_on_broken_description_leaves_summary_untouched(tmp_path, fourbar):
    """`report` on a broken description exits 1 and leaves an existing summary.json byte-identical."""
    out = tmp_path / "reports"
    out.mkdir()
    previous = '[{"name": "earlier run"}]'
    (out / "summary.json").write_text(previous)
    sidecar = _break_closure_type(fourbar, "hinge")
    result = runner.invoke(app, ["report", str(fourbar), "--out", str(out)])
    assert result.exit_code == 1
    assert result.stderr.startswith(f"error: {sidecar}: closures[0] (coupler_rocker): invalid closure type")
    assert (out / "summary.json").read_text() == previous
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]


def test_no_arguments_shows_help():
    """Running with no command prints the usage and lists the commands."""
    result = runner.invoke(app, [])
    for command in ("list", "info", "check", "report"):
        assert command in result.output
