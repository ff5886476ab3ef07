"""The published JSON Schemas agree with ``plm-pin check`` and the sweep reader (plm_pin/schemas/)."""

from __future__ import annotations

import copy
import re
import shutil
from pathlib import Path
from typing import Any

import jsonschema
import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from plm_pin import DescriptionError, InvalidInput
from plm_pin.cli import app
from plm_pin.description import parse_sidecar
from plm_pin.models import urdf_folder
from plm_pin.schemas import load_schema, schema_path
from plm_pin.sweep.config import KEYS, spec_from_config

FOURBAR = yaml.safe_load((urdf_folder() / "fourbar.plm.yaml").read_text())


def _changed(base: dict[str, Any], changes: dict[str, Any]) -> dict[str, Any]:
    """A copy of ``base`` with top-level keys replaced (None removes a key)."""
    data = copy.deepcopy(base)
    for key, value in changes.items():
        if value is None:
            data.pop(key, None)
        else:
            data[key] = value
    return data


def _fourbar(**changes: Any) -> dict[str, Any]:
    """The four-bar's sidecar with top-level keys replaced (None removes a key)."""
    return _changed(FOURBAR, changes)


def _closure(**item: Any) -> dict[str, Any]:
    return _fourbar(closures=[{"name": "coupler_rocker", "frames": ["coupler_tip", "rocker_tip"], **item}])


def _actuator(**item: Any) -> dict[str, Any]:
    return _fourbar(actuation=[{"joint": "crank_pivot", **item}])


SIDECARS = [
    ("the shipped four-bar", _fourbar(), True),
    ("no name, source or gravity", _fourbar(name=None, source=None, gravity=None), True),
    ("gravity along -z", _fourbar(gravity=[0.0, 0.0, -9.81]), True),
    (
        "actuator with limits, lead and inertias",
        _actuator(limits=[-5, 5], lead=0.01, rotor_inertia=1e-4, screw_inertia=0),
        True,
    ),
    ("actuator limits null", _actuator(limits=None), True),
    ("revolute closure with its axis", _closure(type="revolute", axis=[0, 0, 1]), True),
    ("no end effector", _fourbar(end_effector=None), True),
    ("no format", _fourbar(format=None), False),
    ("another format", _fourbar(format="plm-pin/2"), False),
    ("an unknown top-level key", _fourbar(colour="red"), False),
    ("closures not a list", _fourbar(closures={"a": 1}), False),
    ("closure type misspelt", _closure(type="spherical"), False),
    ("closure without a type", _closure(), False),
    ("closure with one frame", _fourbar(closures=[{"frames": ["coupler_tip"], "type": "point"}]), False),
    ("revolute closure without axis", _closure(type="revolute"), False),
    ("point closure with an axis", _closure(type="point", axis=[0, 0, 1]), False),
    ("axis of two numbers", _closure(type="revolute", axis=[0, 1]), False),
    ("closure with an unknown key", _closure(type="point", stiffness_typo=3), False),
    ("actuator without a joint", _fourbar(actuation=[{"limits": [-1, 1]}]), False),
    ("limits of three numbers", _actuator(limits=[-1, 0, 1]), False),
    ("limits as text", _actuator(limits="big"), False),
    ("negative lead", _actuator(lead=-0.01), False),
    ("zero lead", _actuator(lead=0), False),
    ("negative rotor inertia", _actuator(rotor_inertia=-1.0), False),
    ("actuator with an unknown key", _actuator(gear=3), False),
    ("gravity of two numbers", _fourbar(gravity=[0.0, -9.81]), False),
    ("gravity as text", _fourbar(gravity="down"), False),
    ("task direction unknown", _fourbar(end_effector={"frame": "rocker", "task": ["yaw"]}), False),
    ("task direction repeated", _fourbar(end_effector={"frame": "rocker", "task": ["rz", "rz"]}), False),
    ("task empty", _fourbar(end_effector={"frame": "rocker", "task": []}), False),
    ("end effector without frame", _fourbar(end_effector={"task": ["rz"]}), False),
    ("joint task: the rocker's joint", _fourbar(end_effector={"joints": ["rocker_pivot"]}), True),
    ("joint task and a frame", _fourbar(end_effector={"joints": ["rocker_pivot"], "frame": "rocker"}), False),
    ("joint task empty", _fourbar(end_effector={"joints": []}), False),
    ("joint task repeated", _fourbar(end_effector={"joints": ["rocker_pivot", "rocker_pivot"]}), False),
    ("joint task not a list", _fourbar(end_effector={"joints": "rocker_pivot"}), False),
    ("reference value as text", _fourbar(reference={"crank_pivot": "up"}), False),
    (
        "compliance: a drive and a joint spring",
        _fourbar(compliance={"actuators": {"crank_pivot": 100.0}, "joints": {"rocker_pivot": 5.0}}),
        True,
    ),
    (
        "compliance: a beam link by its section",
        _fourbar(
            compliance={
                "links": [
                    {
                        "link": "coupler",
                        "tip": "coupler_tip",
                        "E": 2.1e11,
                        "G": 8.1e10,
                        "A": 1e-4,
                        "Iy": 8e-10,
                        "Iz": 8e-10,
                        "J": 1.4e-9,
                    }
                ]
            }
        ),
        True,
    ),
    (
        "compliance: a beam link by its tip compliance",
        _fourbar(
            compliance={
                "links": [{"link": "coupler", "tip": "coupler_tip", "compliance": np.eye(6).tolist()}]
            }
        ),
        True,
    ),
    (
        "compliance: a negative drive stiffness",
        _fourbar(compliance={"actuators": {"crank_pivot": -1.0}}),
        False,
    ),
    ("compliance: an unknown key", _fourbar(compliance={"dampers": {}}), False),
    (
        "compliance: a beam without its torsion constant",
        _fourbar(
            compliance={
                "links": [
                    {
                        k: v
                        for k, v in {
                            "link": "coupler",
                            "tip": "coupler_tip",
                            "E": 2.1e11,
                            "G": 8.1e10,
                            "A": 1e-4,
                            "Iy": 8e-10,
                            "Iz": 8e-10,
                            "J": 1.4e-9,
                        }.items()
                        if k != "J"
                    }
                ]
            }
        ),
        False,
    ),
    (
        "compliance: a 5x5 tip compliance",
        _fourbar(
            compliance={
                "links": [{"link": "coupler", "tip": "coupler_tip", "compliance": np.eye(5).tolist()}]
            }
        ),
        False,
    ),
    ("name as a number", _fourbar(name=3), False),
    (
        "self-collision: a body pair ignored",
        _fourbar(self_collision={"ignore": [["crank", "coupler"]]}),
        True,
    ),
    (
        "self-collision: a pair of three bodies",
        _fourbar(self_collision={"ignore": [["crank", "coupler", "rocker"]]}),
        False,
    ),
    ("self-collision: an unknown key", _fourbar(self_collision={"ignore": [], "margin": 0.01}), False),
    ("closure tolerance stated", _fourbar(closure_tolerance=1e-6), True),
    ("closure tolerance zero", _fourbar(closure_tolerance=0.0), False),
    ("closure tolerance negative", _fourbar(closure_tolerance=-1e-6), False),
    ("mobility fixed", _fourbar(mobility=1), True),
    ("mobility negative", _fourbar(mobility=-1), False),
    ("mobility not an integer", _fourbar(mobility=1.5), False),
]
"""(case, sidecar, valid): each checked by the schema, by the parser and by ``plm-pin check``."""


def _schema_accepts(schema: dict[str, Any], data: Any) -> bool:
    try:
        jsonschema.validate(data, schema, cls=jsonschema.Draft202012Validator)
    except jsonschema.ValidationError:
        return False
    return True


def test_schemas_are_valid_draft_2020_12():
    """The files are themselves valid JSON Schemas (draft 2020-12)."""
    for name in ("sidecar", "sweep", "optimize"):
        jsonschema.Draft202012Validator.check_schema(load_schema(name))


@pytest.mark.parametrize(("case", "data", "valid"), SIDECARS, ids=[c for c, _, _ in SIDECARS])
def test_sidecar_schema_and_plm_pin_check_agree(case, data, valid, tmp_path):
    """The schema, parse_sidecar and `plm-pin check` on the four-bar give the same verdict."""
    assert _schema_accepts(load_schema("sidecar"), data) is valid, case
    try:
        parse_sidecar(data, "fourbar.plm.yaml")
        parsed = True
    except DescriptionError:
        parsed = False
    assert parsed is valid, case
    shutil.copy(urdf_folder() / "fourbar.urdf", tmp_path / "fourbar.urdf")
    (tmp_path / "fourbar.plm.yaml").write_text(yaml.safe_dump(data))
    result = CliRunner().invoke(app, ["check", str(tmp_path / "fourbar.urdf")])
    assert (result.exit_code == 0) is valid, result.output


def _valid_keys(data: dict[str, Any]) -> list[str]:
    """The keys parse_sidecar accepts where ``data`` has an unknown one, from its error message."""
    with pytest.raises(DescriptionError) as info:
        parse_sidecar(data, "x.plm.yaml")
    found = re.search(r"valid keys are \[(.*?)\]", str(info.value))
    assert found, str(info.value)
    return sorted(k.strip(" '") for k in found.group(1).split(","))


def test_sidecar_schema_lists_the_keys_the_parser_accepts():
    """Top-level, closure, actuator, end-effector and self-collision keys: schema and parser agree."""
    schema = load_schema("sidecar")
    defs = schema["$defs"]
    assert sorted(schema["properties"]) == _valid_keys(_fourbar(zzz=1))
    assert sorted(defs["closure"]["properties"]) == _valid_keys(_closure(type="point", zzz=1))
    assert sorted(defs["actuator"]["properties"]) == _valid_keys(_actuator(zzz=1))
    ee = _fourbar(end_effector={"frame": "rocker", "task": ["rz"], "zzz": 1})
    assert sorted(defs["end_effector"]["properties"]) == _valid_keys(ee)
    sc = _fourbar(self_collision={"ignore": [], "zzz": 1})
    assert sorted(defs["self_collision"]["properties"]) == _valid_keys(sc)


SWEEP = yaml.safe_load(
    (Path(__file__).resolve().parents[2] / "analyses/sweeps/harada2011_ratio.yaml").read_text()
)


def _sweep(**changes: Any) -> dict[str, Any]:
    """The example sweep configuration with top-level keys replaced (None removes a key)."""
    return _changed(SWEEP, changes)


SWEEPS = [
    ("the shipped example", _sweep(), True),
    ("no format, options", _sweep(format=None, options=None), True),
    ("samples instead of a grid", _sweep(parameters=[{"half_plate": 0.05}, {"half_plate": 0.07}]), True),
    ("values with a unit", _sweep(poses={"rz": {"values": [-10, 10], "unit": "deg"}}), True),
    ("a chunk", _sweep(chunk=64), True),
    ("no metrics", _sweep(metrics=None), False),
    ("no mechanism", _sweep(mechanism=None), False),
    ("an unknown key", _sweep(colour="red"), False),
    ("another format", _sweep(format="plm-pin-sweep/9"), False),
    ("chunk zero", _sweep(chunk=0), False),
    ("chunk as text", _sweep(chunk="big"), False),
    ("unknown unit", _sweep(poses={"rz": {"values": [0.1], "unit": "grad"}}), False),
    ("linspace and values", _sweep(poses={"rz": {"linspace": [0, 1, 3], "values": [1]}}), False),
    ("linspace of two numbers", _sweep(poses={"rz": {"linspace": [0, 1]}}), False),
    ("linspace count as a float", _sweep(poses={"rz": {"linspace": [0, 1, 2.5]}}), False),
    ("options not a mapping", _sweep(options=[1, 2]), False),
]
"""(case, configuration, valid): each checked by the schema and by the sweep reader."""


@pytest.mark.parametrize(("case", "data", "valid"), SWEEPS, ids=[c for c, _, _ in SWEEPS])
def test_sweep_schema_and_reader_agree(case, data, valid):
    """The schema and plm_pin.sweep.config give the same verdict on each configuration."""
    assert _schema_accepts(load_schema("sweep"), data) is valid, case
    try:
        spec_from_config(data, "sweep.yaml")
        read = True
    except InvalidInput:
        read = False
    assert read is valid, case


def test_sweep_schema_lists_the_reader_keys():
    """The schema's top-level keys are plm_pin.sweep.config.KEYS."""
    assert sorted(load_schema("sweep")["properties"]) == sorted(KEYS)


def test_unknown_schema_names_the_choices():
    """schema_path of an unknown name raises InvalidInput listing the schemas."""
    with pytest.raises(
        InvalidInput, match=r"unknown schema 'x'; schemas are \['optimize', 'sidecar', 'sweep'\]"
    ):
        schema_path("x")
