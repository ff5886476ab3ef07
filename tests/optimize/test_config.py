"""The optimisation configuration: the JSON Schema and the reader agree; the CLI writes the designs."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import jsonschema
import pandas as pd
import pytest
import yaml
from typer.testing import CliRunner

from plm_pin import InvalidInput
from plm_pin.cli import app
from plm_pin.optimize.config import problem_from_config
from plm_pin.schemas import load_schema

EXAMPLE = Path(__file__).resolve().parents[2] / "analyses/sweeps/fivebar_optimize.yaml"


def _config(**changes: Any) -> dict[str, Any]:
    data = yaml.safe_load(EXAMPLE.read_text())
    for key, value in changes.items():
        if value is None:
            data.pop(key)
        else:
            data[key] = value
    return copy.deepcopy(data)


CASES = [
    ("the shipped example", _config(), True),
    ("no format, search or constraints", _config(format=None, search=None, constraints=None), True),
    ("no variables", _config(variables=None), False),
    ("an unknown key", _config(speed=3), False),
    ("an unknown constraint", _config(constraints={"fast": 1}), False),
    ("an unknown objective", _config(objectives=["speed"]), False),
    ("bounds of three numbers", _config(variables={"distal": [0.1, 0.2, 0.3]}), False),
    ("an unknown search method", _config(search={"method": "annealing"}), False),
    ("an unknown unit", _config(variables={"distal": {"bounds": [1, 2], "unit": "ft"}}), False),
]


@pytest.mark.parametrize(("case", "data", "valid"), CASES, ids=[c for c, _, _ in CASES])
def test_schema_and_reader_agree(case: str, data: dict[str, Any], valid: bool) -> None:
    """The JSON Schema and problem_from_config accept and refuse the same configurations."""
    try:
        jsonschema.validate(data, load_schema("optimize"), cls=jsonschema.Draft202012Validator)
        accepted = True
    except jsonschema.ValidationError:
        accepted = False
    assert accepted is valid, case
    try:
        problem_from_config(data, "example.yaml")
        read = True
    except InvalidInput:
        read = False
    assert read is valid, case


def test_units_convert_the_bounds() -> None:
    """``unit: mm`` divides the bounds by 1000."""
    problem, _ = problem_from_config(_config())
    assert problem.bounds[0] == pytest.approx((0.06, 0.3), rel=1e-15)


def test_cli_writes_every_design_and_the_summary(tmp_path: Path) -> None:
    """`plm-pin optimize` writes designs.csv (every design) and summary.json (best and start)."""
    result = CliRunner().invoke(app, ["optimize", str(EXAMPLE), "--out", str(tmp_path / "run")])
    assert result.exit_code == 0, result.output
    table = pd.read_csv(tmp_path / "run" / "designs.csv")
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["designs"] == len(table) > 1
    best = table.loc[table["score"].idxmin()]
    assert summary["best"]["parameters"]["proximal"] == pytest.approx(best["proximal"])
    again = CliRunner().invoke(app, ["optimize", str(EXAMPLE), "--out", str(tmp_path / "run")])
    assert again.exit_code == 0 and "0 computed now" in again.output


def test_cli_report_lists_the_start_and_best_designs_of_the_table(tmp_path: Path) -> None:
    """The report's designs table holds the start design and the best design of designs.csv."""
    result = CliRunner().invoke(app, ["optimize", str(EXAMPLE), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    report = json.loads((tmp_path / "optimization" / "results.json").read_text())
    (table,) = [b for s in report["sections"] for b in s["blocks"] if b.get("title") == "Designs"]
    rows = {row[0]: row for row in table["rows"]}
    designs = pd.read_csv(tmp_path / "designs.csv")
    best = designs.loc[designs["score"].idxmin()]
    assert rows["start"][1:3] == [0.15, 0.2]  # the preset's proximal and distal
    assert rows["best 1"][1:3] == pytest.approx([best["proximal"], best["distal"]], rel=1e-12)


def test_a_description_path_is_read_beside_the_configuration_file(tmp_path: Path, monkeypatch) -> None:
    """``mechanism: m/arm.urdf`` names the file beside the configuration, wherever the command runs."""
    from plm_pin.legs import planar
    from plm_pin.optimize.config import load_config as load_optimization
    from plm_pin.sweep.config import load_config as load_sweep

    ring = [(0.3, 0.0), (-0.15, 0.26), (-0.15, -0.26)]
    urdf = planar(
        "RPR", ring, [(0.1 * x / 0.3, 0.1 * y / 0.3) for x, y in ring], folder=tmp_path / "m", name="arm"
    )
    poses = {"x": {"linspace": [-0.01, 0.01, 2]}, "y": {"linspace": [-0.01, 0.01, 2]}}
    optimization = {"mechanism": "m/arm.urdf", "variables": {"pivot2.x": [-0.2, -0.1]}, "poses": poses}
    sweep = {"mechanism": "m/arm.urdf", "poses": poses, "metrics": ["reachable"]}
    (tmp_path / "opt.yaml").write_text(yaml.safe_dump(optimization))
    (tmp_path / "sweep.yaml").write_text(yaml.safe_dump(sweep))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    problem, _ = load_optimization(tmp_path / "opt.yaml")
    spec, _ = load_sweep(tmp_path / "sweep.yaml")
    import plm_pin

    assert problem.spec.build(0).nq == spec.build(0).nq == plm_pin.load(urdf).nq
    assert not Path("m/arm.urdf").exists() and urdf == tmp_path / "m" / "arm.urdf"
