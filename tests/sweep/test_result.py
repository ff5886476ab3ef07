"""Sweep results: dimensions, coordinates and units of the Dataset, samples, JSON, failures."""

from __future__ import annotations

import json
import math

import numpy as np

from plm_pin import load
from plm_pin.models import PRESETS
from plm_pin.sweep import sweep
from tests.sweep.conftest import FIG6_RT, THETAS, small


def test_dataset_dimensions_coordinates_and_units():
    """Parameters then pose axes as dimensions; pose values in m / rad; every variable has units."""
    result = sweep(**small())
    ds = result.dataset
    assert dict(ds.sizes) == {"legs": 2, "half_plate": 2, "y": 3, "rz": 33}
    assert ds.legs.values.tolist() == ["(1, 2, 4)", "(1, 2, 3, 4)"]
    assert ds.half_plate.values.tolist() == [FIG6_RT, 0.05]
    np.testing.assert_array_equal(ds.rz.values, THETAS)
    assert (ds.y.attrs["units"], ds.rz.attrs["units"]) == ("m", "rad")
    assert ds.manipulability.dims == ("legs", "half_plate", "y", "rz")
    assert ds.min_manipulability.dims == ds.orientation_lower.dims == ("legs", "half_plate", "y")
    for name, var in ds.data_vars.items():
        assert var.attrs["units"] and var.attrs["description"], name
    assert ds.orientation_lower.attrs["units"] == "rad"
    assert ds.orientation_lower_end.attrs["flag_meanings"].split() == [
        "constraint",
        "inverse",
        "direct",
        "boundary",
        "grid",
        "unreachable",
    ]
    assert ds.attrs["key"] == result.key and json.loads(ds.attrs["spec"])["mechanism"] == "harada2011_3d4m"
    assert not ds.failed.any()


def test_samples_give_one_dimension_with_each_parameter_as_a_coordinate():
    """A list of samples (e.g. rod-length sets) is dimension 'sample', each parameter a coordinate on it."""
    rods = [[0.24, 0.17, 0.17, 0.24], [0.24, 0.24, 0.24, 0.24]]
    ds = sweep(
        "harada2015_asymmetric",
        [{"rod_lengths": rods[0], "half_plate": 0.05}, {"rod_lengths": rods[1], "half_plate": 0.06}],
        {"y": [0.1], "rz": [0.0, 0.1]},
        ["manipulability", "reachable_fraction"],
    ).dataset
    assert ds.manipulability.dims == ("sample", "y", "rz") and ds.reachable_fraction.dims == ("sample",)
    assert ds.rod_lengths.dims == ("sample",)
    assert ds.rod_lengths.values.tolist() == ["(0.24, 0.17, 0.17, 0.24)", "(0.24, 0.24, 0.24, 0.24)"]
    assert ds.half_plate.values.tolist() == [0.05, 0.06]
    assert ds.reachable_fraction.values.tolist() == [1.0, 1.0]


def test_to_dict_is_json_ready():
    """The result's summary and data go through strict JSON (NaN and inf as strings)."""
    result = sweep(**small(metrics=["manipulability"], options={}))
    data = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    assert data["key"] == result.key and data["failures"] == [] and data["loaded"] == 0
    assert data["spec"] == result.spec.to_dict() and data["computed"] == [list(c) for c in result.computed]
    assert data["store"] is None and data["elapsed"] == result.elapsed
    w = data["dataset"]["data_vars"]["manipulability"]
    assert w["attrs"]["units"].startswith("product of the column units of J_ce")
    assert "nan" in json.dumps(w["data"])  # unreached poses


def test_a_loaded_mechanism_reduced_over_every_axis_gives_one_number_the_brute_force_count():
    """A loaded mechanism, reachable_fraction over every pose axis: one number, the brute-force share.

    The share counts, pose by pose, where every leg of Harada 2011 eq. (2) has a real root (|L_y| <= l).
    """
    mech = load("harada2011_3d4m")
    parameters = PRESETS["harada2011_3d4m"].parameters
    l, rt = parameters["rod_lengths"][0], parameters["half_plate"]
    ys, thetas = [0.02, 0.08, 0.12, 0.15], np.radians([-60.0, -20.0, 0.0, 35.0, 70.0])
    poses = {"y": ys, "rz": thetas}
    ds = sweep(mech, poses=poses, pose=(0.0, 0.08, 0.0), metrics=["reachable_fraction"]).dataset
    assert ds.reachable_fraction.dims == () and ds.failed.dims == ()
    # L_y = y +- r_t sin(theta) for the two pairs
    reached = [abs(y) + rt * abs(math.sin(t)) < l for y in ys for t in thetas]
    assert 0 < sum(reached) < len(reached)  # the box holds poses of both kinds
    assert float(ds.reachable_fraction) == sum(reached) / len(reached)
