"""Sweep configuration files: the YAML format, units, the committed example, and bad files refused."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from plm_pin import InvalidInput, Mechanism
from plm_pin.sweep import load_config, make_spec
from plm_pin.sweep.config import spec_from_config

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = REPO / "analyses" / "sweeps" / "harada2011_ratio.yaml"


def _config(**changes):
    config = {
        "mechanism": "harada2011_3d4m",
        "parameters": {"half_plate": {"linspace": [0.03, 0.05, 3]}},
        "poses": {"y": {"values": [80, 90], "unit": "mm"}, "rz": {"linspace": [-10, 10, 3], "unit": "deg"}},
        "metrics": ["manipulability"],
    }
    config.update(changes)
    return config


def test_config_values_and_units_become_the_api_spec():
    """linspace, values, mm and deg in a config give the spec of the same sweep through the API."""
    spec, chunk = spec_from_config(_config(chunk=500))
    api = make_spec(
        "harada2011_3d4m",
        {"half_plate": np.linspace(0.03, 0.05, 3)},
        {"y": [0.08, 0.09], "rz": np.radians([-10.0, 0.0, 10.0])},
        ["manipulability"],
    )
    assert chunk == 500 and spec.key() == api.key()
    assert spec.values[1].tolist() == pytest.approx([-math.pi / 18, 0.0, math.pi / 18], abs=1e-16)


def test_the_committed_example_is_a_valid_sweep():
    """analyses/sweeps/harada2011_ratio.yaml: the 3D3M / 3D4M ratio study of the README."""
    spec, chunk = load_config(EXAMPLE)
    assert spec.label == "harada2011_3d4m" and chunk is None
    assert spec.parameters.names == ("legs", "half_plate") and spec.parameters.shape == (2, 5)
    assert spec.axes == ("x", "y", "rz") and spec.n_poses == 12 * 81
    assert 0.14 / spec.parameters.values[1][2] == pytest.approx(4.0)  # l : 2 r_t = 2 : 1 among them


def test_builder_by_module_and_name():
    """mechanism: module:function imports a builder; its parameters are then the ones checked."""
    spec, _ = spec_from_config(
        _config(mechanism="tests.sweep.conftest:fragile_2prrrp", metrics=["reachable"], poses={"y": [0.08]})
    )
    assert spec.label == "tests.sweep.conftest:fragile_2prrrp"


def test_description_path_without_parameters_is_loaded_once_to_be_shipped(tmp_path):
    """mechanism: PATH of a URDF with its sidecar: one point, its Mechanism held by the spec (shipped)."""
    from tests import textbook as tb

    mech = tb.stewart(tmp_path)
    config = _config(mechanism=mech.source, parameters=None, poses={"x": [0.0]}, pose=list(tb.STEWART_POSE))
    spec, _ = spec_from_config(config)
    assert spec.label == mech.source and spec.n_points == 1 and spec.built is not None
    assert isinstance(spec.built, Mechanism) and spec.built.nq == mech.nq


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        (
            {"kind": "grid"},
            "unknown key(s) ['kind']; keys are ['format', 'mechanism', 'base', 'parameters', "
            "'poses', 'pose', 'metrics', 'options', 'chunk']",
        ),
        ({"format": "plm-pin-sweep/0"}, "format 'plm-pin-sweep/0' is not 'plm-pin-sweep/1'"),
        ({"metrics": None}, "metrics must be a non-empty list among"),
        (
            {"poses": {"y": {"linspace": [0, 1]}}},
            "poses.y: linspace takes [start, stop, number of values >= 1], got [0, 1]",
        ),
        (
            {"poses": {"rz": {"values": [1], "unit": "grad"}}},
            "poses.rz: unknown unit 'grad'; units are ['deg', 'rad', 'mm', 'm']",
        ),
        (
            {"parameters": {"half_plate": {"linspace": [0.03, 0.05, 0]}}},
            "parameters.half_plate: linspace takes",
        ),
        (
            {"mechanism": "nowhere.module:builder"},
            "mechanism 'nowhere.module:builder': cannot import the builder",
        ),
        ({"chunk": 0}, "chunk must be a positive number of poses per task, got 0"),
    ],
)
def test_bad_configs_are_refused_naming_the_file_and_the_problem(changes, message):
    """Each malformed entry raises InvalidInput starting with the source and saying what is wrong."""
    with pytest.raises(InvalidInput) as err:
        spec_from_config(_config(**changes), "study.yaml")
    assert str(err.value).startswith(f"study.yaml: {message}")


def test_missing_key_unreadable_and_invalid_yaml(tmp_path):
    """A missing key, a missing file and broken YAML each give one clear message."""
    config = _config()
    del config["poses"]
    with pytest.raises(InvalidInput, match=r"^<config>: missing key 'poses'$"):
        spec_from_config(config)
    with pytest.raises(InvalidInput, match="cannot read the sweep configuration"):
        load_config(tmp_path / "none.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("mechanism: [unclosed\n")
    with pytest.raises(InvalidInput, match=r"bad.yaml: not valid YAML \("):
        load_config(bad)
