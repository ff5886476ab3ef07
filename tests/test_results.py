"""The result protocol: to_dict made from the fields, units read from their metadata."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

from plm_pin.dynamics import SimulationResult
from plm_pin.results import Result, plain, unit, units
from plm_pin.workspace import OrientationRange


@dataclass(frozen=True)
class _Inner(Result):
    value: float = field(metadata=unit("N"))


@dataclass(frozen=True)
class _Outer(Result):
    name: str
    forces: np.ndarray = field(metadata=unit("N"))
    ratio: float = field(metadata=unit("-"))
    inner: tuple[_Inner, ...]
    by_name: dict[str, np.ndarray]
    hidden: object = None
    _DERIVED = ("doubled",)
    _SKIPPED = ("hidden",)
    _NONFINITE_AS_TEXT = ("ratio",)

    @property
    def doubled(self) -> float:
        return 2.0 * float(self.forces[0])


def test_to_dict_writes_fields_then_derived_as_plain_json():
    """Arrays become lists, nested results their dicts, skipped fields vanish, inf becomes text."""
    r = _Outer("a", np.array([1.5, 2.0]), math.inf, (_Inner(np.float64(3.0)),), {"k": np.eye(2)}, object())
    assert r.to_dict() == {
        "name": "a",
        "forces": [1.5, 2.0],
        "ratio": "inf",
        "inner": [{"value": 3.0}],
        "by_name": {"k": [[1.0, 0.0], [0.0, 1.0]]},
        "doubled": 3.0,
    }
    json.dumps(r.to_dict(), allow_nan=False)


def test_plain_converts_nonfinite_inside_arrays_only_when_asked():
    """Non-finite floats stay numbers by default and become 'nan'/'inf' strings on request."""
    values = np.array([1.0, math.nan, -math.inf])
    assert plain(values)[0] == 1.0 and math.isnan(plain(values)[1])
    assert plain(values, nonfinite_as_text=True) == [1.0, "nan", "-inf"]


def test_plain_writes_paths_as_text_and_nonfinite_inside_nested_to_dicts():
    """A path becomes its text; asked for text, non-finite floats of a nested to_dict() become text too."""
    assert plain(Path("a") / "b") == str(Path("a") / "b")
    inner = _Inner(math.nan)
    assert math.isnan(plain(inner)["value"])
    assert plain([inner], nonfinite_as_text=True) == [{"value": "nan"}]


def test_units_come_from_field_metadata():
    """Only the fields declared with a unit are listed, for a class or an instance alike."""
    assert units(_Outer) == {"forces": "N", "ratio": "-"}
    assert units(_Inner(1.0)) == {"value": "N"}
    assert units(OrientationRange)["lower"] == "rad"
    assert units(SimulationResult)["lam"] == "N, N m"
    with pytest.raises(TypeError):
        units(object())
