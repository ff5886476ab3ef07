"""Sensitivity of the task pose to geometric errors, and the error bound (plm_pin/kinematics/accuracy.py).

Oracles: finite differences of the whole pipeline (the model's placements perturbed, the
mechanism rebuilt, the forward kinematics re-solved at the same actuator values; for the
four-bar, the URDF text itself edited and loaded again), and the five-bar's tip error from a
motor-position error derived by hand from its two circle equations.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin import InvalidInput, SingularConfiguration
from plm_pin.core.mechanism import Mechanism
from plm_pin.kinematics import forward_kinematics, task_pose
from plm_pin.kinematics.accuracy import PLACEMENT_ERRORS, error_bound, error_model, sensitivity
from tests import textbook
from tests.conftest import preset

H = 1e-6
"""Finite-difference step [m, rad]."""

ABSORBED = 1e-9
"""Closure mismatch [m, rad per unit] below which an error is absorbed by the rigid loops (FK closes)."""


def _perturbed(mech: Mechanism, name: str, h: float) -> tuple[Mechanism, np.ndarray]:
    """The mechanism with parameter ``name`` moved by ``h``, and the actuator values to hold."""
    c = mech.actuator_positions(mech.q_ref)
    if name.startswith("actuator:"):
        names = [a.joint for a in mech.actuators]
        return mech, c + h * (np.arange(len(c)) == names.index(name.removeprefix("actuator:")))
    model = pin.Model(mech.model)
    target, component = name.rsplit(".", 1)
    d = np.zeros(6)
    d[PLACEMENT_ERRORS.index(component)] = h
    if target.startswith("frame:"):
        fid = model.getFrameId(target.removeprefix("frame:"))
        frame = model.frames[fid]
        M = frame.placement
        frame.placement = pin.SE3(M.rotation @ pin.exp3(d[3:]), M.translation + d[:3])
        model.frames[fid] = frame
    else:
        jid = model.getJointId(target)
        M = model.jointPlacements[jid]
        model.jointPlacements[jid] = pin.SE3(M.rotation @ pin.exp3(d[3:]), M.translation + d[:3])
    return Mechanism(model, mech.sidecar, name=mech.name, idle_gauges=mech.idle_gauges), c


def _task_placement(mech: Mechanism, c: np.ndarray, guess: np.ndarray) -> pin.SE3 | np.ndarray:
    """The task frame's placement (a frame task) or the output joints' positions (a joint task)."""
    q = forward_kinematics(mech, c, guess=guess, all_modes=False)[0].q
    if mech.task_frame_id is None:
        return task_pose(mech, q)
    pin.framesForwardKinematics(mech.model, mech.data, q)
    return pin.SE3(mech.data.oMf[mech.task_frame_id])


def _pipeline_column(mech: Mechanism, name: str) -> np.ndarray:
    """d(task pose)/d(parameter) by central differences of the rebuilt mechanism's forward kinematics."""
    ends = []
    for h in (H, -H):
        moved, c = _perturbed(mech, name, h)
        ends.append(_task_placement(moved, c, mech.q_ref))
    plus, minus = ends
    if isinstance(plus, np.ndarray):
        return (plus - minus) / (2 * H)
    twist = np.concatenate([plus.translation - minus.translation, pin.log3(plus.rotation @ minus.rotation.T)])
    return twist[mech.task_compiled.selectors[0]] / (2 * H)


def _check_against_the_pipeline(mech: Mechanism) -> None:
    sens = sensitivity(mech, mech.q_ref)
    model = error_model(mech)
    assert sens.S.shape == (len(mech.task.dofs), model.size)
    assert model.size == 6 * (mech.model.njoints - 1) + 6 * len(model.frames) + mech.n_actuators
    rng = np.random.default_rng(7)
    absorbed = [k for k in range(model.size) if sens.mismatch[k] < ABSORBED]
    assert any(n.startswith("actuator:") for n in np.array(model.names)[absorbed])
    picked = rng.choice(absorbed, size=min(12, len(absorbed)), replace=False)
    picked = sorted({*picked, model.size - 1})  # an actuator offset always
    for k in picked:
        fd = _pipeline_column(mech, model.names[k])
        scale = max(1.0, float(np.max(np.abs(fd))))
        assert np.allclose(sens.S[:, k], fd, rtol=1e-5, atol=1e-7 * scale), model.names[k]


@pytest.mark.parametrize(
    "name", ["fivebar", "fourbar", "harada2011_3d3m", "enferadi2017_star_triangle", "zhao2011_6pss"]
)
def test_sensitivity_matches_finite_differences_of_the_forward_kinematics(name):
    _check_against_the_pipeline(preset(name))


@pytest.mark.parametrize("build", ["finger", "delta", "stewart"])
def test_sensitivity_of_a_joint_task_a_floating_platform_and_ball_joints(tmp_path, build):
    """The gripper finger (output joint as the task), a Delta on a free-flyer, a Stewart platform."""
    mech = {
        "finger": lambda: textbook.finger(tmp_path),
        "delta": lambda: textbook.delta(tmp_path, parallelogram=False),
        "stewart": lambda: textbook.stewart(tmp_path),
    }[build]()
    _check_against_the_pipeline(mech)


def test_fourbar_urdf_edits_move_the_rocker_as_the_sensitivity_says(fourbar):
    """The URDF text itself edited, loaded again, forward kinematics re-solved at the same crank angle.

    The ground length (rocker pivot's origin x) and the crank pin's offset (coupler pivot's origin y).
    """
    mech = plm_pin.load(fourbar)
    sens = sensitivity(mech, mech.q_ref)
    c = mech.actuator_positions(mech.q_ref)
    text = fourbar.read_text()
    for joint, nominal, edit in (
        ("rocker_pivot", "0.3 0.0 0.0", lambda h: f"{0.3 + h!r} 0.0 0.0"),
        ("coupler_pivot", "0.1 0.0 0.0", lambda h: f"0.1 {h!r} 0.0"),
    ):
        head, tail = text.split(f'<joint name="{joint}"', 1)
        assert f'<origin xyz="{nominal}"' in tail.split("</joint>", 1)[0]
        ends = []
        for h in (1e-5, -1e-5):
            fourbar.write_text(head + f'<joint name="{joint}"' + tail.replace(nominal, edit(h), 1))
            moved = plm_pin.load(fourbar)
            q = forward_kinematics(moved, c, guess=mech.q_ref, all_modes=False)[0].q
            ends.append(task_pose(moved, q)[0])
        fd = (ends[0] - ends[1]) / 2e-5
        column = f"{joint}.{'x' if joint == 'rocker_pivot' else 'y'}"
        assert abs(fd) > 0.1
        assert sens.S[0, sens.names.index(column)] == pytest.approx(fd, rel=1e-6)


def test_fivebar_tip_error_from_a_motor_position_error_in_closed_form():
    r"""Tip P on circles |P - E_L| = |P - E_R| = distal, elbows E = O + proximal (cos a, sin a).

    Moving the left motor O_L by d (actuators held) moves E_L by d, so
    (P - E_L) . (dP - d) = 0 and (P - E_R) . dP = 0: dP = A^-1 [(P - E_L) . d, 0].
    Elbow lengths: the left distal link longer by e gives (P - E_L) . dP = distal e.
    """
    mech = preset("fivebar")
    base, proximal, distal = 0.2, 0.15, 0.2  # the builder's defaults, which the preset keeps
    assert plm_pin.models.PRESETS["fivebar"].parameters == {}
    a_left, a_right = mech.actuator_positions(mech.q_ref)
    O_L, O_R = np.array([-base / 2, 0.0]), np.array([base / 2, 0.0])
    E_L = O_L + proximal * np.array([math.cos(a_left), math.sin(a_left)])
    E_R = O_R + proximal * np.array([math.cos(a_right), math.sin(a_right)])
    P = task_pose(mech, mech.q_ref)
    assert np.linalg.norm(P - E_L) == pytest.approx(distal) and np.linalg.norm(P - E_R) == pytest.approx(
        distal
    )
    A = np.array([P - E_L, P - E_R])
    sens = sensitivity(mech, mech.q_ref)
    for k, axis in enumerate("xy"):
        d = np.eye(2)[k]
        expected = np.linalg.solve(A, [(P - E_L) @ d, 0.0])
        assert sens.S[:, sens.names.index(f"left_motor.{axis}")] == pytest.approx(expected, abs=1e-12)
    # the left tip frame carries the task and closes the loop: the left distal length error
    expected = np.linalg.solve(A, [distal, 0.0])
    assert sens.S[:, sens.names.index("frame:left_tip.x")] == pytest.approx(expected, abs=1e-12)
    # an error along the motor axis (z) moves nothing in the plane, and the point closure cannot absorb it
    k = sens.names.index("left_motor.z")
    assert sens.S[:, k] == pytest.approx([0.0, 0.0], abs=1e-15)
    assert sens.mismatch[k] == pytest.approx(1.0)


def test_the_bound_is_the_interval_and_rms_sum_of_the_sensitivity():
    mech = preset("harada2011_3d3m")
    model = error_model(mech)
    tol = model.tolerances(1e-5, 2e-4)
    assert set(tol) == {1e-5, 2e-4}
    bound = error_bound(mech, mech.q_ref, tol)
    S = bound.sensitivity.S
    rng = np.random.default_rng(3)
    # worst case: attained by the signs of each row, never exceeded by a random error in the box
    for i in range(S.shape[0]):
        signs = np.sign(S[i])
        assert S[i] @ (signs * tol) == pytest.approx(bound.worst_case[i])
    errors = rng.uniform(-1, 1, size=(2000, model.size)) * tol
    assert np.all(np.abs(errors @ S.T) <= bound.worst_case * (1 + 1e-12))
    # rms: the standard deviation of S e over independent errors of standard deviation tol
    samples = rng.standard_normal((20000, model.size)) * tol
    assert np.std(samples @ S.T, axis=0) == pytest.approx(bound.rms, rel=0.03)
    top = bound.contributions(0, 3)
    assert top[0][1] == pytest.approx(np.max(np.abs(S[0]) * tol))
    assert [v for _, v in top] == sorted((v for _, v in top), reverse=True)
    assert bound.sensitivity.largest(1, 1)[0][1] == pytest.approx(np.max(np.abs(S[1])))


def test_bad_tolerances_and_singular_configurations_are_refused():
    mech = preset("fivebar")
    with pytest.raises(InvalidInput, match="tolerances must be"):
        error_bound(mech, mech.q_ref, [1e-5])
    with pytest.raises(InvalidInput, match="length"):
        error_model(mech).tolerances(-1.0, 0.0)
    # a direct singularity: elbows at (-distal, y) and (distal, y), the tip between them, both distal
    # links on one line (built exactly: the elbow angles from the geometry, no solver)
    base, proximal, distal = 0.2, 0.15, 0.2  # the preset's builder defaults
    assert plm_pin.models.PRESETS["fivebar"].parameters == {}
    a_left, a_right = math.acos((base / 2 - distal) / proximal), math.acos((distal - base / 2) / proximal)
    q = np.array(mech.q_ref)
    for joint, value in (
        ("left_motor", a_left),
        ("left_elbow", -a_left),
        ("right_motor", a_right),
        ("right_elbow", math.pi - a_right),
    ):
        mech.set_joint(q, joint, value)
    assert np.abs(mech.closure_residual(q)).max() < 1e-15
    with pytest.raises(SingularConfiguration, match="direct"):
        sensitivity(mech, q)
