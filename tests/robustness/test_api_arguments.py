"""Wrong argument types and values at the API are one InvalidInput naming the argument, never a traceback."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from plm_pin.dynamics import inverse_dynamics, simulate
from plm_pin.dynamics.trajectory import sampled_profile, task_trajectory
from plm_pin.exceptions import AllocationInfeasible, InvalidInput
from plm_pin.kinematics import forward_kinematics, inverse_kinematics, task_pose
from plm_pin.statics import force_capability, static_forces
from tests.conftest import preset
from tests.robustness.conftest import budget


@functools.cache
def trajectory():
    """A short task trajectory of the 3D4M (seven samples from the reference pose)."""
    m = preset("harada2011_3d4m")
    x0 = task_pose(m, m.q_ref)
    t = np.linspace(0.0, 0.06, 7)
    xs = x0 + np.outer(t, [0.1, 0.0, 0.0])
    return task_trajectory(m, sampled_profile(t, xs), t)


def with_nan(field: str, index: int):
    """The trajectory with one entry of ``field`` at sample ``index`` set to NaN."""
    from dataclasses import replace

    traj = trajectory()
    values = np.array(getattr(traj, field), dtype=float)
    values.reshape(len(values), -1)[index, 0] = np.nan
    return replace(traj, **{field: values})


def calls() -> dict[str, Callable[..., Any]]:
    """The functions under test, bound to the mechanism they act on (by short name)."""
    m, fb = preset("harada2011_3d4m"), preset("fourbar")
    x = task_pose(m, m.q_ref)
    c = m.actuator_positions(m.q_ref)
    return {
        "inverse_kinematics": lambda **kw: inverse_kinematics(m, x, **kw),
        "forward_kinematics": lambda **kw: forward_kinematics(m, c, **kw),
        "static_forces": lambda **kw: static_forces(m, m.q_ref, **kw),
        "force_capability": lambda **kw: force_capability(m, m.q_ref, **{"direction": [0.0, 1.0, 0.0], **kw}),
        "inverse_dynamics": lambda **kw: inverse_dynamics(
            m, kw.pop("trajectory") if "trajectory" in kw else trajectory(), **kw
        ),
        "simulate": lambda **kw: simulate(fb, fb.q_ref, **{"duration": 0.01, "dt": 0.01, **kw}),
    }


INF = math.inf
CASES = [
    # (function, arguments, message start)
    (
        "inverse_kinematics",
        {"mode": 3},
        "mode must be None or a sequence of signs (+1 or -1), one per leg; got 3",
    ),
    ("inverse_kinematics", {"mode": "+-+-"}, "mode must be None or a sequence of signs"),
    ("inverse_kinematics", {"mode": 2.5}, "mode must be None or a sequence of signs"),
    ("inverse_kinematics", {"mode": {1: 1}}, "mode must be None or a sequence of signs"),
    (
        "inverse_kinematics",
        {"mode": (1, "a", 1, 1)},
        "mode must hold signs (+1 or -1), one per leg; got (1, 'a', 1, 1)",
    ),
    ("inverse_kinematics", {"mode": (True, 1, 1, 1)}, "mode must hold signs"),
    ("inverse_kinematics", {"mode": (1, 0.5, 1, 1)}, "mode must hold signs"),
    (
        "inverse_kinematics",
        {"mode": (1, 2, 1, -1)},
        "mode must hold 4 signs (+1 or -1), one per leg; got (1, 2, 1, -1)",
    ),
    ("inverse_kinematics", {"tol": "a"}, "tol must be a positive finite number, got 'a'"),
    ("inverse_kinematics", {"tol": 0}, "tol must be a positive finite number, got 0"),
    ("inverse_kinematics", {"tol": 0.0}, "tol must be a positive finite number, got 0.0"),
    ("inverse_kinematics", {"tol": -1e-9}, "tol must be a positive finite number, got -1e-09"),
    ("inverse_kinematics", {"tol": math.nan}, "tol must be a positive finite number, got nan"),
    ("inverse_kinematics", {"tol": INF}, "tol must be a positive finite number, got inf"),
    ("inverse_kinematics", {"tol": -1.0}, "tol must be a positive finite number, got -1.0"),
    ("inverse_kinematics", {"tol": [1e-9]}, "tol must be a positive finite number, got [1e-09]"),
    ("inverse_kinematics", {"tol": True}, "tol must be a positive finite number, got True"),
    ("inverse_kinematics", {"tol": 1j}, "tol must be a positive finite number, got 1j"),
    ("forward_kinematics", {"starts": 2.5}, "starts must be a whole number >= 0, got 2.5"),
    ("forward_kinematics", {"starts": -1}, "starts must be a whole number >= 0, got -1"),
    ("forward_kinematics", {"starts": "3"}, "starts must be a whole number >= 0, got '3'"),
    ("forward_kinematics", {"starts": None}, "starts must be a whole number >= 0, got None"),
    ("forward_kinematics", {"starts": True}, "starts must be a whole number >= 0, got True"),
    ("forward_kinematics", {"seed": 1.5}, "seed must be a whole number >= 0, got 1.5"),
    ("forward_kinematics", {"tol": "a"}, "tol must be a positive finite number, got 'a'"),
    ("forward_kinematics", {"tol": 0}, "tol must be a positive finite number, got 0"),
    ("static_forces", {"frame": 3}, "frame must be a frame name (a string) or None, got 3"),
    (
        "static_forces",
        {"frame": 3, "wrench": [0.0] * 6},
        "frame must be a frame name (a string) or None, got 3",
    ),
    ("static_forces", {"frame": ["plate"]}, "frame must be a frame name (a string) or None, got ['plate']"),
    ("static_forces", {"frame": b"plate"}, "frame must be a frame name (a string) or None, got b'plate'"),
    (
        "static_forces",
        {"wrench": [1j, 0, 0]},
        "wrench must be real numbers (array-like), got complex numbers",
    ),
    (
        "static_forces",
        {"wrench": np.zeros(3, complex)},
        "wrench must be real numbers (array-like), got complex",
    ),
    ("static_forces", {"wrench": "abc"}, "wrench must be real numbers (array-like), got 'abc'"),
    ("static_forces", {"wrench": {"fx": 1.0}}, "wrench must be real numbers (array-like), got {'fx': 1.0}"),
    ("static_forces", {"wrench": [object()] * 3}, "wrench must be real numbers (array-like), got [<object"),
    ("static_forces", {"wrench": [[1, 2], [3]]}, "wrench must be real numbers (array-like): "),
    (
        "static_forces",
        {"limits": {"slider1": (0, 1)}},
        "limits must be 'description', None or an (4, 2) array",
    ),
    ("static_forces", {"limits": b"description"}, "limits must be 'description', None or an (4, 2) array"),
    (
        "static_forces",
        {"limits": [(INF, INF)] * 4},
        "limits must have lower <= upper, lower < +inf and upper > -inf",
    ),
    ("static_forces", {"limits": [(-INF, -INF)] * 4}, "limits must have lower <= upper, lower < +inf"),
    (
        "static_forces",
        {"limits": [(1j, 2)] * 4},
        "limits must be real numbers (array-like), got complex numbers",
    ),
    ("static_forces", {"limits": [(0, 1)] * 3}, "limits must be 'description', None or an (4, 2) array"),
    (
        "static_forces",
        {"limits": [(0, "a")] * 4},
        "limits must be real numbers (array-like), got [(0, 'a'), ",
    ),
    (
        "force_capability",
        {"direction": [1j, 0, 0]},
        "direction must be real numbers (array-like), got complex numbers",
    ),
    ("force_capability", {"frame": 2}, "frame must be a frame name (a string) or None, got 2"),
    ("force_capability", {"limits": {"a": 1}}, "limits must be 'description', None or an (4, 2) array"),
    ("inverse_dynamics", {"trajectory": None}, "trajectory must be a JointTrajectory (see plm_pin.dynamics"),
    ("inverse_dynamics", {"trajectory": 3}, "trajectory must be a JointTrajectory"),
    ("inverse_dynamics", {"trajectory": {"q": []}}, "trajectory must be a JointTrajectory"),
    ("inverse_dynamics", {"trajectory": np.zeros((3, 9))}, "trajectory must be a JointTrajectory"),
    (
        "inverse_dynamics",
        {"wrench": [1j, 0, 0]},
        "wrench must be real numbers (array-like), got complex numbers",
    ),
    ("inverse_dynamics", {"frame": 0}, "frame must be a frame name (a string) or None, got 0"),
    ("inverse_dynamics", {"limits": {"a": 1}}, "limits must be 'description', None or an (4, 2) array"),
    (
        "simulate",
        {"duration": 1e9, "dt": 1e-9},
        "duration / dt = 1e+18 output samples; at most 1e+07 are kept",
    ),
    (
        "simulate",
        {"duration": 1e8, "dt": 1e-3},
        "duration / dt = 1e+11 output samples; at most 1e+07 are kept",
    ),
    ("simulate", {"duration": 1.0, "dt": 0.0}, "dt must be a positive finite number, got 0.0"),
    ("simulate", {"duration": 1.0, "dt": -0.1}, "dt must be a positive finite number, got -0.1"),
    ("simulate", {"duration": "1", "dt": 0.1}, "duration must be a positive finite number, got '1'"),
    ("simulate", {"duration": INF, "dt": 0.1}, "duration must be a positive finite number, got inf"),
    ("simulate", {"duration": 1.0, "dt": math.nan}, "dt must be a positive finite number, got nan"),
    ("simulate", {"wrench": [1j]}, "wrench must be real numbers (array-like), got complex numbers"),
    (
        "simulate",
        {"wrench": [0.0], "frame": 1},
        "frame must be a frame name (a string) or None, got 1",
    ),
]


@pytest.mark.parametrize(
    ("function", "arguments", "message"), CASES, ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)]
)
def test_a_wrong_argument_is_one_invalid_input_naming_it(function, arguments, message):
    """Each bad argument raises InvalidInput whose message starts by naming the argument and what it takes."""
    with pytest.raises(InvalidInput) as err:
        calls()[function](**arguments)
    assert str(err.value).startswith(message), str(err.value)


@pytest.mark.parametrize("field", ["t", "q", "v", "a"])
@pytest.mark.parametrize("index", [0, 3, 6])
def test_a_trajectory_holding_nan_is_refused_naming_the_sample(field, index):
    """NaN anywhere in a trajectory is refused by inverse_dynamics naming the field and the sample."""
    with pytest.raises(InvalidInput, match=rf"^trajectory\.{field} holds NaN or inf at sample {index}$"):
        inverse_dynamics(preset("harada2011_3d4m"), with_nan(field, index))


not_positive = st.one_of(
    st.floats(max_value=0.0),
    st.just(math.nan),
    st.just(math.inf),
    st.text(max_size=5),
    st.booleans(),
    st.complex_numbers(),
    st.lists(st.floats(), max_size=2),
)


@budget
@given(value=not_positive, function=st.sampled_from(["inverse_kinematics", "forward_kinematics"]))
def test_any_tolerance_that_is_not_a_positive_number_is_refused(value, function):
    """Any tol that is not a finite number > 0 (zero gave "misses by 0 m") is one InvalidInput naming tol.

    None is the default: the mechanism's closure tolerance.
    """
    with pytest.raises(InvalidInput, match=r"^tol must be a positive finite number, got "):
        calls()[function](tol=value)


@budget
@given(
    value=st.one_of(
        st.floats().filter(lambda v: not (math.isfinite(v) and v.is_integer())),
        st.integers(max_value=-1),
        st.text(max_size=4),
        st.none(),
        st.booleans(),
    )
)
def test_any_start_count_that_is_not_a_whole_number_is_refused(value):
    """forward_kinematics(starts=...) takes a whole number >= 0 only."""
    with pytest.raises(InvalidInput, match=r"^starts must be a whole number >= 0, got "):
        calls()["forward_kinematics"](starts=value)


@pytest.mark.parametrize("preload", [1e3, 1e6, 1e9])
def test_an_infeasible_min_compression_of_any_size_is_allocation_infeasible(preload):
    """A compression preload the limits cannot give raises AllocationInfeasible, whatever its size."""
    with pytest.raises(AllocationInfeasible, match="no actuator forces balance the load within the limits"):
        static_forces(preset("harada2011_3d4m"), preset("harada2011_3d4m").q_ref, min_compression=preload)
