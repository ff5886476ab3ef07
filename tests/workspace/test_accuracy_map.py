"""Accuracy maps (plm_pin/workspace/accuracy.py) against the five-bar's tip error in closed form.

With tolerances on the left motor's position only, the worst-case tip error at each grid pose is
``|dP/dx| t + |dP/dy| t`` with ``dP = A^-1 [(P - E_L) . d, 0]``, ``A = [P - E_L; P - E_R]``: the
elbows from the map's own actuator angles, the geometry from the builder's defaults.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from plm_pin.exceptions import InvalidInput
from plm_pin.kinematics import error_model
from plm_pin.workspace import accuracy_map, accuracy_over, workspace_map
from tests.conftest import preset

BASE, PROXIMAL = 0.2, 0.15  # the five-bar builder's defaults, kept by the preset


def test_fivebar_map_matches_the_closed_form_and_is_nan_where_unreached():
    mech = preset("fivebar")
    model = error_model(mech)
    t = 1e-5
    tol = np.array([t if n in ("left_motor.x", "left_motor.y") else 0.0 for n in model.names])
    xs, ys = np.array([-0.02, 0.02, 0.06]), np.array([0.22, 0.26, 0.6])  # y = 0.6 m is out of reach
    result = accuracy_map(mech, ("x", "y"), (xs, ys), tol)
    grid = workspace_map(mech, ("x", "y"), (xs, ys))
    assert result.reachable.sum() == 6 and not result.reachable[:, 2].any()
    assert np.isnan(result.worst_case[:, 2]).all() and np.isnan(result.rms[:, 2]).all()
    again = accuracy_over(mech, grid, tol)
    np.testing.assert_array_equal(again.worst_case, result.worst_case)
    for i, x in enumerate(xs):
        for j, y in enumerate(ys[:2]):
            a_left, a_right = grid.actuators[i, j]
            E_L = np.array([-BASE / 2 + PROXIMAL * math.cos(a_left), PROXIMAL * math.sin(a_left)])
            E_R = np.array([BASE / 2 + PROXIMAL * math.cos(a_right), PROXIMAL * math.sin(a_right)])
            P = np.array([x, y])
            A = np.array([P - E_L, P - E_R])
            columns = [np.linalg.solve(A, [(P - E_L)[k], 0.0]) for k in range(2)]
            worst = sum(np.abs(c) for c in columns) * t
            rms = np.sqrt(sum(c**2 for c in columns)) * t
            assert result.worst_case[i, j] == pytest.approx(worst, rel=1e-9)
            assert result.rms[i, j] == pytest.approx(rms, rel=1e-9)
            assert result.worst_position[i, j] == pytest.approx(max(worst))
    assert result.units == ("m", "m") and np.isnan(result.worst_angle).all()
    assert result.to_dict()["worst_case"][0][2] == ["nan", "nan"]


def test_accuracy_map_refuses_malformed_tolerances():
    mech = preset("fivebar")
    with pytest.raises(InvalidInput, match="tolerances must be"):
        accuracy_map(mech, ("x", "y"), ([0.0], [0.25]), [1e-5, 1e-5])
