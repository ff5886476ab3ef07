"""Sweep specs: bad input refused before any work with messages naming the valid choices; keys."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from plm_pin import InvalidInput
from plm_pin.families.prrrp import build_2prrrp
from plm_pin.models.registry import builder_parameters
from plm_pin.sweep import METRICS, OPTIONS, make_spec, sweep
from tests.sweep.conftest import small

PARAMS = list(builder_parameters(build_2prrrp))


def _refusal(**changes) -> str:
    """The message of the InvalidInput that make_spec raises for the small sweep with ``changes``."""
    kwargs = small(**changes)
    with pytest.raises(InvalidInput) as err:
        make_spec(
            kwargs.pop("mechanism"),
            kwargs.pop("parameters"),
            kwargs.pop("poses"),
            kwargs.pop("metrics"),
            **kwargs,
        )
    return str(err.value)


def _refused(message: str, **changes) -> None:
    assert _refusal(**changes) == message


def test_unknown_parameter_lists_the_builders_parameters():
    """A misspelt parameter is refused with every parameter of the builder."""
    _refused(
        f"unknown parameter 'rod_length' of harada2011_3d4m; its parameters are {PARAMS}",
        parameters={"rod_length": [0.1, 0.2]},
    )
    _refused(
        f"unknown parameter 'plate' of harada2011_3d4m; its parameters are {PARAMS}", base={"plate": 0.1}
    )


def test_unknown_metric_and_option_list_the_valid_ones():
    """Unknown metrics and options, and options no chosen metric uses, are refused by name."""
    _refused(
        f"unknown metric 'rigidity'; metrics are {list(METRICS)}", metrics=["manipulability", "rigidity"]
    )
    _refused(f"unknown option 'tolerance'; options are {sorted(OPTIONS)}", options={"tolerance": 1e-9})
    _refused(
        "option 'wrenches' is used by the metrics ['peak_force', 'preload'], none of which is asked for; the "
        "options of ['manipulability'] are ['ik_tol']",
        metrics=["manipulability"],
        options={"wrenches": [[0, 1, 0]]},
    )
    _refused("metrics are repeated: ['manipulability', 'manipulability']", metrics=["manipulability"] * 2)


def test_empty_grids_are_refused():
    """An empty parameter list, an empty list of samples and an empty pose axis are each refused."""
    _refused("parameter 'half_plate' has no values: an empty grid", parameters={"half_plate": []})
    _refused("parameters: the list of samples is empty", parameters=[])
    _refused(
        "poses: values of 'y' must be a non-empty 1-D list, got shape (0,)", poses={"y": [], "rz": [0.0]}
    )
    with pytest.raises(InvalidInput, match="poses must map task coordinates"):
        make_spec("harada2011_3d4m", None, {}, ["manipulability"])


def test_non_finite_values_are_refused():
    """NaN or inf in a parameter, a base value, a tuple value, a pose axis or the fixed pose are refused."""
    _refused(
        "parameter 'half_plate' holds a non-finite value nan", parameters={"half_plate": [0.05, math.nan]}
    )
    _refused(
        "parameter 'rod_lengths' holds a non-finite value inf",
        parameters={"rod_lengths": [[0.14, 0.14, 0.14, math.inf]]},
    )
    _refused("base parameter 'gravity' holds a non-finite value nan", base={"gravity": math.nan})
    _refused("poses: values of 'rz' hold non-finite entries [inf]", poses={"y": [0.08], "rz": [0.0, np.inf]})
    with pytest.raises(InvalidInput, match=re.escape("pose must be a 1-D list of finite task coordinates")):
        make_spec("harada2011_3d4m", None, {"y": [0.08]}, ["manipulability"], pose=[0.0, math.nan, 0.0])


def test_task_coordinates_are_checked_against_the_mechanism():
    """A pose axis outside x..rz, one the planar task lacks, and a bad rotation axis are refused."""
    _refused(
        "poses: unknown task coordinate 'theta'; coordinates are ['x', 'y', 'z', 'rx', 'ry', 'rz']",
        poses={"theta": [0.0]},
    )
    _refused(
        "poses: harada2011_3d4m_p0 has no task coordinate ['z']; its task coordinates are ['x', 'y', 'rz']",
        poses={"z": [0.0], "rz": [0.0, 0.1]},
    )
    _refused(
        "the orientation range turns 'rz' (option rotation_axis), which the poses do not vary; pose axes are "
        "['y']",
        poses={"y": [0.05]},
        options={},
    )
    _refused("pose must hold 3 task coordinates ['x', 'y', 'rz'], got [0.0, 0.08]", pose=(0.0, 0.08))


def test_other_malformed_arguments_are_refused():
    """Varied and fixed at once, a bad value type, misaligned samples, bad wrenches are refused by name."""
    _refused(
        "parameters ['half_plate'] are both varied and fixed (base); give each once",
        base={"half_plate": 0.05},
    )
    _refused(
        "parameter 'half_plate': True is a boolean; give a number, a name or a list of them",
        parameters={"half_plate": [True]},
    )
    _refused(
        "parameters: sample 1 sets ['legs']; every sample must set ['half_plate'], in order",
        parameters=[{"half_plate": 0.05}, {"legs": [1, 2, 4]}],
    )
    _refused(
        "option 'wrenches': each wrench holds 6 values or one per task coordinate ['x', 'y', 'rz'], "
        "got [1.0, 0.0]",
        metrics=["peak_force"],
        options={"wrenches": [[1.0, 0.0]]},
    )
    with pytest.raises(InvalidInput, match=r"unknown preset 'harada'; presets are \["):
        make_spec("harada", None, {"y": [0.08]})


def test_bad_input_starts_no_work(tmp_path):
    """A refused sweep writes no checkpoint folder."""
    store = tmp_path / "store"
    with pytest.raises(InvalidInput, match="unknown metric"):
        sweep(**small(metrics=["w"]), store=store)
    with pytest.raises(InvalidInput, match="chunk must be a positive number of poses per task, got 0"):
        sweep(**small(), store=store, chunk=0)
    with pytest.raises(InvalidInput, match="workers must be a positive number of processes, got 0"):
        sweep(**small(), store=store, workers=0)
    assert not store.exists()


def test_key_identifies_what_decides_the_results():
    """Equal arguments give equal keys; a changed value, metric or option changes it."""
    base = make_spec("harada2011_3d4m", {"half_plate": [0.05]}, {"y": [0.08]}, ["manipulability"])
    same = make_spec("harada2011_3d4m", {"half_plate": np.array([0.05])}, {"y": (0.08,)}, ("manipulability",))
    assert base.key() == same.key() and len(base.key()) == 64
    others = [
        make_spec("harada2011_3d4m", {"half_plate": [0.0500001]}, {"y": [0.08]}, ["manipulability"]),
        make_spec("harada2011_3d4m", {"half_plate": [0.05]}, {"y": [0.08]}, ["condition_number"]),
        make_spec("harada2011_3d3m", {"half_plate": [0.05]}, {"y": [0.08]}, ["manipulability"]),
        make_spec(
            "harada2011_3d4m",
            {"half_plate": [0.05]},
            {"y": [0.08]},
            ["manipulability"],
            options={"ik_tol": 1e-10},
        ),
    ]
    assert len({base.key(), *(o.key() for o in others)}) == 5


def test_samples_and_grids_enumerate_points_row_major():
    """A grid's flat index runs row-major over its parameters; samples keep their order."""
    grid = make_spec(
        "harada2011_3d4m", {"legs": [[1, 2, 4], [1, 2, 3, 4]], "half_plate": [0.03, 0.05]}, {"y": [0.08]}
    )
    assert grid.parameters.shape == (2, 2) and grid.parameters.dims == ("legs", "half_plate")
    assert grid.parameters.point(1) == {"legs": (1, 2, 4), "half_plate": 0.05}
    samples = make_spec("harada2011_3d4m", [{"half_plate": 0.03}, {"half_plate": 0.05}], {"y": [0.08]})
    assert samples.parameters.dims == ("sample",) and samples.parameters.point(1) == {"half_plate": 0.05}
    none = make_spec("harada2011_3d4m", None, {"y": [0.08]})
    assert none.n_points == 1 and none.parameters.point(0) == {}


def test_a_huge_option_value_is_quoted_short():
    """An option's bad value is quoted cut short: a million-entry list does not fill the message."""
    message = _refusal(options={"ik_tol": ["x"] * 1_000_000})
    assert message.startswith("option 'ik_tol' must be a positive finite number, got ['x', 'x', ")
    assert len(message) < 200
