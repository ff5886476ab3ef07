"""The live inspector's state function: each change against the API's own answer for the same pose.

Moves are checked against inverse and forward kinematics, the readouts against classify,
manipulability, static_forces and stiffness; the ellipse and the load against finite
differences of the inverse kinematics (velocities and virtual work); the edge a move stops at
against the four-bar's closed-form rocker extreme.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from plm_pin import InvalidInput
from plm_pin.kinematics import classify, forward_kinematics, inverse_kinematics, same_assembly, working_modes
from plm_pin.models import PRESETS
from plm_pin.statics import internal_force_range, static_forces
from plm_pin.stiffness import stiffness
from plm_pin.viz.inspect_state import InspectState, inspect_state, inspect_update
from plm_pin.workspace import manipulability
from tests.conftest import preset
from tests.kinematics.test_singularity import FOURBAR, rocker_extreme_crank_angles


@pytest.fixture(scope="module")
def table() -> InspectState:
    return inspect_state(preset("harada2011_3d4m"))


def _actuators_at(mech, x, guess, mode) -> np.ndarray:
    return inverse_kinematics(mech, x, guess, mode=mode).actuators


def test_first_state_reads_the_api_at_the_reference(table):
    """Pose, modes, margins, manipulability, forces and stiffness are the API's at the reference."""
    mech = table.mech
    q = mech.q_ref
    np.testing.assert_allclose(table.q, q)
    assert set(table.working_modes) == {s.mode for s in working_modes(mech, table.x, guess=q)}
    report = classify(mech, q)
    assert table.margins == pytest.approx(
        {
            "constraint": report.constraint_margin,
            "inverse": report.inverse_margin,
            "direct": report.direct_margin,
        }
    )
    assert table.singular == ()
    m = manipulability(mech, q)
    assert table.manipulability == pytest.approx(m.w)
    assert table.condition_number == pytest.approx(m.condition_number)
    np.testing.assert_allclose(table.forces, static_forces(mech, q, np.zeros(3), limits=None).f_c)
    assert table.stiffness == pytest.approx(stiffness(mech, q).min_translational)
    assert table.closure_residual <= mech.closure_tol
    json.dumps(table.to_dict(), allow_nan=False)  # what the browser panel receives


def test_task_move_is_the_inverse_kinematics_in_the_same_working_mode(table):
    """Moving x and rz gives IK's configuration there, in the working mode it started in."""
    mech = table.mech
    goal = table.x + np.array([0.01, 0.0, 0.1])
    moved = inspect_update(table, {"task": {"x": goal[0], "rz": goal[2]}})
    assert moved.stopped == ""
    np.testing.assert_allclose(moved.x, goal, atol=1e-9)
    assert moved.working_mode == table.working_mode
    sol = inverse_kinematics(mech, goal, table.q, mode=table.working_mode)
    assert same_assembly(mech, moved.q, sol.q)
    np.testing.assert_allclose(moved.actuators, sol.actuators, atol=1e-9)
    assert moved.manipulability == pytest.approx(manipulability(mech, sol.q).w, rel=1e-6)
    np.testing.assert_allclose(table.q, mech.q_ref)  # the old state is unchanged


def test_actuator_move_is_the_forward_kinematics_of_the_same_assembly():
    """A 3D3M slider moved: FK from the old configuration gives the same pose (its assembly mode)."""
    mech = preset("harada2011_3d3m")
    state = inspect_state(mech)
    c = state.actuators.copy()
    c[1] += 0.005
    moved = inspect_update(state, {"actuators": {state.actuator_names[1]: c[1]}})
    assert moved.stopped == ""
    np.testing.assert_allclose(moved.actuators, c, atol=1e-9)
    fk = forward_kinematics(mech, c, state.q, all_modes=False)[0]
    np.testing.assert_allclose(moved.x, fk.x, atol=1e-8)


def test_redundant_actuator_move_holds_as_many_actuators_as_dof(table):
    """On the 3D4M slider1 moves, slider2 and slider3 stay, slider4 follows; the loops hold."""
    c = table.actuators
    moved = inspect_update(table, {"actuators": {"slider1": c[0] + 0.003}})
    assert moved.stopped == ""
    np.testing.assert_allclose(moved.actuators[:3], [c[0] + 0.003, c[1], c[2]], atol=1e-9)
    assert moved.actuators[3] != pytest.approx(c[3])
    assert moved.closure_residual <= table.mech.closure_tol


def test_task_move_stops_at_the_closed_form_rocker_extreme():
    """Dragging the four-bar's rocker below its range stops at the extreme the law of cosines gives."""
    mech = preset("fourbar")
    state = inspect_state(mech)
    a, b, d = FOURBAR["a"], FOURBAR["b"], FOURBAR["d"]
    beta = rocker_extreme_crank_angles()[0]  # crank and coupler extended, |OB| = a + b
    pin_x, pin_y = (a + b) * math.cos(beta), (a + b) * math.sin(beta)
    psi = math.atan2(pin_y, pin_x - d)  # rocker angle, measured at its pivot D = (d, 0)
    moved = inspect_update(state, {"task": {"rz": psi - 0.3}})
    assert moved.stopped.startswith("leaves the workspace") or "inverse" in moved.stopped
    assert moved.x[0] == pytest.approx(psi, abs=1e-4)
    assert moved.q[0] == pytest.approx(beta, abs=2e-2)  # the crank angle flattens at a fold: sqrt error
    assert moved.margins["inverse"] < 1e-2 < state.margins["inverse"]


def test_task_move_stops_at_the_closed_form_direct_singularity():
    """Turning the 3D3M's plate stops at Harada 2011's type-4 locus theta = -asin(y / (l + r_t)) (11.4)."""
    mech = preset("harada2011_3d3m")
    p = PRESETS["harada2011_3d3m"].parameters
    state = inspect_state(mech)
    theta = -math.asin(state.x[1] / (p["rod_lengths"][0] + p["half_plate"]))
    assert theta < state.x[2]  # the locus lies beyond the reference along -rz
    moved = inspect_update(state, {"task": {"rz": theta - 0.2}})
    assert moved.stopped == "reaches a direct singularity"
    assert moved.singular == ("direct",)  # on the locus: the scene is coloured by classify's kinds
    assert moved.x[2] == pytest.approx(theta, abs=1e-4)
    np.testing.assert_allclose(moved.x[:2], state.x[:2], atol=1e-9)
    back = inspect_update(state, {"task": {"rz": theta + 0.05}})  # short of it: moved in full
    assert back.stopped == "" and back.x[2] == pytest.approx(theta + 0.05)


def test_working_mode_switch_changes_the_configuration_not_the_pose(table):
    """Another working mode: IK's configuration in that mode, at the same task pose."""
    mech = table.mech
    other = next(m for m in table.working_modes if m != table.working_mode)
    switched = inspect_update(table, {"working_mode": list(other)})
    assert switched.working_mode == other
    np.testing.assert_allclose(switched.x, table.x, atol=1e-9)
    assert not same_assembly(mech, switched.q, table.q)
    assert same_assembly(mech, switched.q, inverse_kinematics(mech, table.x, table.q, mode=other).q)


def test_assembly_modes_are_forward_kinematics_all_modes(table):
    """find_modes lists FK's assembly modes; choosing another keeps the actuators and moves the platform."""
    mech = table.mech
    found = inspect_update(table, {"find_modes": True})
    fk = forward_kinematics(mech, table.actuators, table.q, all_modes=True)
    assert len(found.assembly_modes) == len(fk) >= 2
    assert same_assembly(mech, found.assembly_modes[found.assembly_index], table.q)
    other = 1 - found.assembly_index
    chosen = inspect_update(found, {"assembly_mode": other})
    np.testing.assert_allclose(chosen.actuators, table.actuators, atol=1e-8)
    assert not np.allclose(chosen.x, table.x, atol=1e-6)


@pytest.mark.parametrize(
    "name, change", [("harada2011_3d4m", {"actuators": {"slider1": 0.012}}), ("fivebar", None)]
)
def test_assembly_modes_are_kept_and_followed_after_a_move(name, change):
    """After a move the modes found are FK's at the new actuator positions, the one shown marked."""
    mech = preset(name)
    found = inspect_update(inspect_state(mech), {"find_modes": True})
    assert len(found.assembly_modes) >= 2
    if change is None:  # move the first actuator a little
        first = mech.actuators[0].joint
        change = {"actuators": {first: float(found.actuators[0]) + 0.05}}
    else:
        change = {"actuators": {k: float(found.actuators[0]) + v for k, v in change["actuators"].items()}}
    moved = inspect_update(found, change)
    assert not moved.stopped
    assert not np.allclose(moved.actuators, found.actuators)
    fk = forward_kinematics(mech, moved.actuators, moved.q, all_modes=True)
    assert len(moved.assembly_modes) == len(fk)
    for sol in fk:
        assert sum(same_assembly(mech, sol.q, m) for m in moved.assembly_modes) == 1
    assert moved.assembly_index is not None
    assert same_assembly(mech, moved.assembly_modes[moved.assembly_index], moved.q)


def test_load_forces_do_virtual_work_against_the_load(table):
    """The forces a load adds do the work the load does on every small IK motion: f . dc = -w . dx."""
    mech = table.mech
    w = np.array([10.0, -5.0, 2.0])
    loaded = inspect_update(table, {"load": w.tolist()})
    extra = loaded.forces - table.forces
    eps = 1e-6
    for k in range(3):
        dx = np.zeros(3)
        dx[k] = eps
        up = _actuators_at(mech, table.x + dx, table.q, table.working_mode)
        down = _actuators_at(mech, table.x - dx, table.q, table.working_mode)
        assert extra @ (up - down) / (2 * eps) == pytest.approx(-w[k], rel=1e-5)


def test_preload_adds_forces_that_balance_nothing(table):
    """A preload adds actuator forces in the null space of J_ce^T, of the size asked (orthonormal basis)."""
    preloaded = inspect_update(table, {"preload": [50.0]})
    extra = preloaded.forces - table.forces
    J_ce = manipulability(table.mech, table.q).J_ce
    np.testing.assert_allclose(J_ce.T @ extra, 0.0, atol=1e-9)
    assert np.linalg.norm(extra) == pytest.approx(50.0)


def test_limits_give_the_internal_force_range_of_statics_and_its_ends_saturate(table):
    """Without limits in the description no range; with limits given, statics' range, whose ends saturate.

    Brute force on the ends: the forces preloaded to an end keep within the limits with one
    at a bound, and a little beyond the end one force passes its bound.
    """
    assert table.internal_range.size == 0 and np.isinf(table.force_limits).all()
    mech, load = table.mech, [3.0, -2.0, 0.5]
    limits = [[-200.0, 150.0], [-120.0, 200.0], [None, 180.0], [-160.0, 90.0]]
    bounds = np.array([[-np.inf if v is None else v for v in pair] for pair in limits])
    partial = inspect_update(table, {"load": load, "limits": limits})
    assert partial.internal_range.size == 0 and any("finite effort limits" in n for n in partial.notes)
    limits[2][0] = -170.0
    bounds[2, 0] = -170.0
    state = inspect_update(table, {"load": load, "limits": limits})
    np.testing.assert_array_equal(state.force_limits, bounds)
    expected = internal_force_range(mech, state.q, load, limits=bounds)
    np.testing.assert_allclose(
        state.internal_range, np.column_stack([expected.lower, expected.upper]), rtol=1e-9
    )
    span = float(np.diff(state.internal_range[0])[0])
    assert span > 0.0
    for end, outward in zip(state.internal_range[0], (-1.0, 1.0), strict=True):
        at = inspect_update(state, {"preload": [float(end)]}).forces
        slack = np.minimum(at - bounds[:, 0], bounds[:, 1] - at)
        assert slack.min() == pytest.approx(0.0, abs=1e-6 * span) and slack.min() > -1e-6 * span
        beyond = inspect_update(state, {"preload": [float(end) + outward * 1e-3 * span]}).forces
        assert np.min(np.minimum(beyond - bounds[:, 0], bounds[:, 1] - beyond)) < 0.0
    back = inspect_update(state, {"limits": None})
    assert back.internal_range.size == 0 and np.isinf(back.force_limits).all()


def test_velocity_ellipse_matches_finite_differences(table):
    """Along each ellipse axis a task step moves the actuators by step / radius (rotation held)."""
    mech = table.mech
    eps = 1e-6
    assert table.ellipse_radii.shape == (2,)
    for radius, axis in zip(table.ellipse_radii, table.ellipse_axes, strict=True):
        dx = np.array([axis[0], axis[1], 0.0]) * eps
        up = _actuators_at(mech, table.x + dx, table.q, table.working_mode)
        down = _actuators_at(mech, table.x - dx, table.q, table.working_mode)
        assert np.linalg.norm(up - down) / (2 * eps) == pytest.approx(1.0 / radius, rel=1e-5)


def test_copy_pose_texts_rebuild_the_pose(table):
    """The python snippet runs and gives the configuration shown; the CLI line names the pose and mode."""
    namespace: dict[str, object] = {}
    exec(table.python_snippet, namespace)
    sol = namespace["sol"]
    assert same_assembly(table.mech, sol.q, table.q)  # type: ignore[attr-defined]
    np.testing.assert_allclose(namespace["q"], table.q, atol=1e-8)
    assert table.cli_line.startswith("plm-pin ik harada2011_3d4m x=")
    assert "--mode=+,-,+,-" in table.cli_line or "--mode=" in table.cli_line


@pytest.mark.parametrize(
    "change, words",
    [
        ({"spin": 1}, "unknown"),
        ({"task": {"q": 1.0}}, "is not one of"),
        ({"actuators": {"slider1": 0.0, "slider2": 0.0, "slider3": 0.0, "slider4": 0.0}}, "at most 3"),
        ({"assembly_mode": 0}, "find_modes"),
        ({"load": [1.0]}, "3 finite numbers"),
        ({"working_mode": [1, 1]}, "mode must hold 4 signs"),
        ({"limits": [[-1.0, 1.0]]}, "one \\[lower, upper\\] pair per actuator \\(4\\)"),
        ({"limits": [["a", 1.0]] * 4}, "numbers or None"),
        ({"limits": [[2.0, 1.0]] * 4}, "lower <= upper"),
    ],
)
def test_bad_changes_are_refused_by_name(table, change, words):
    """Each malformed change raises InvalidInput naming what is wrong."""
    with pytest.raises(InvalidInput, match=words):
        inspect_update(table, change)


def test_preload_without_redundancy_is_refused():
    """The four-bar has no internal force to preload."""
    with pytest.raises(InvalidInput, match="not redundantly actuated"):
        inspect_update(inspect_state(preset("fourbar")), {"preload": [1.0]})
