"""A linkage without an end effector: a four-bar gripper finger whose task is its output joint.

plm_pin/statics/transmission.py and the joint task of plm_pin/core/task.py through IK, FK,
Jacobians, singularities, statics, inverse dynamics and the CLI.

Oracles (tests/textbook.py, from the link lengths alone): Freudenstein's equation for the
output angle, the four-bar's angular velocity ratio a sin(t3 - t2) / (c sin(t3 - t4)), the
law of cosines for the transmission angle, virtual work for the mechanical advantage and
the statics, and a Lagrangian in the output angle (energies from the closed-form positions,
differentiated by finite differences) for the inverse dynamics.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from typer.testing import CliRunner

import plm_pin
from plm_pin import InvalidInput
from plm_pin.cli import app
from plm_pin.dynamics import inverse_dynamics, task_trajectory
from plm_pin.kinematics import (
    classify,
    closed_chain_jacobians,
    forward_kinematics,
    inverse_kinematics,
    task_pose,
)
from plm_pin.statics import JointLoad, static_forces, transmission
from plm_pin.statics.balance import load_on_frame
from tests import textbook as tb

G = 9.81


@pytest.fixture(scope="module")
def finger(tmp_path_factory):
    """The four-bar gripper finger, loaded from its URDF and sidecar."""
    return tb.finger(tmp_path_factory.mktemp("finger"))


def at_crank(mech, theta2):
    """The assembled configuration with the crank at ``theta2`` (the reference's assembly)."""
    return mech.assemble(mech.q_ref, fixed={"drive": theta2}).q


CRANKS = (0.6, 1.2, 2.0, 2.8)


def test_the_task_is_the_output_joint(finger):
    """The sidecar's joint task gives one coordinate, the output angle of Freudenstein's equation."""
    assert finger.task.frame is None and finger.task.dofs == ("finger_pivot",)
    assert finger.mobility == 1 and finger.task_frame_id is None
    for t2 in CRANKS:
        t4, _ = tb.finger_freudenstein(t2)
        assert task_pose(finger, at_crank(finger, t2))[0] == pytest.approx(t4, abs=1e-12)


def test_inverse_and_forward_kinematics_follow_the_closed_forms(finger):
    """IK at an output angle gives the closed-form crank; FK at a crank gives both assemblies."""
    for t4 in (1.1, 1.3, 1.6):
        sol = inverse_kinematics(finger, [t4])
        t2, t3 = tb.finger_from_output(t4)
        assert finger.actuator_positions(sol.q)[0] == pytest.approx(t2, abs=1e-10)
        assert sol.q[1] == pytest.approx(t3 - t2, abs=1e-10)
    outputs = sorted(s.x[0] for s in forward_kinematics(finger, [1.2]))
    expected = sorted(tb.finger_freudenstein(1.2, branch)[0] for branch in (1, -1))
    np.testing.assert_allclose(outputs, expected, atol=1e-10)


def test_joint_task_jacobian_and_pose_match_finite_differences(finger, rng):
    """The task Jacobian selects the output joint's velocity; the pose differentiates to it."""
    task = finger.task_compiled
    data = finger.model.createData()
    for _ in range(3):
        q = pin.integrate(finger.model, finger.q_ref, rng.normal(scale=0.5, size=finger.nv))
        pin.computeJointJacobians(finger.model, data, q)
        J = task.jacobian_from_data(finger.model, data)
        eps = 1e-6
        for k in range(finger.nv):
            dv = np.zeros(finger.nv)
            dv[k] = eps
            plus = task_pose(finger, pin.integrate(finger.model, q, dv))
            minus = task_pose(finger, pin.integrate(finger.model, q, -dv))
            assert J[0, k] == pytest.approx((plus - minus)[0] / (2 * eps), abs=1e-8)
        assert task_pose(finger, q)[0] == pytest.approx(math.remainder(q[2], 2 * math.pi), abs=1e-12)


@pytest.mark.parametrize("t2", CRANKS)
def test_transmission_ratio_is_the_four_bar_velocity_ratio(finger, t2):
    """D theta4 / d theta2 equals a sin(t3 - t2) / (c sin(t3 - t4)) and Freudenstein's derivative."""
    result = transmission(finger, at_crank(finger, t2))
    h = 1e-6
    fd = (tb.finger_freudenstein(t2 + h)[0] - tb.finger_freudenstein(t2 - h)[0]) / (2 * h)
    assert result.ratio[0, 0] == pytest.approx(tb.finger_velocity_ratio(t2), rel=1e-10)
    assert result.ratio[0, 0] == pytest.approx(fd, rel=1e-7)
    jac = closed_chain_jacobians(finger, at_crank(finger, t2))
    assert jac.J_ce[0, 0] == pytest.approx(1.0 / tb.finger_velocity_ratio(t2), rel=1e-10)


@pytest.mark.parametrize("t2", CRANKS)
def test_mechanical_advantage_from_statics_is_the_virtual_work_one(finger, t2):
    """The torque delivered per crank torque, from the static balance, is 1 / (d theta4 / d theta2)."""
    result = transmission(finger, at_crank(finger, t2))
    assert result.mechanical_advantage[0, 0] == pytest.approx(1.0 / tb.finger_velocity_ratio(t2), rel=1e-9)


@pytest.mark.parametrize("t2", CRANKS)
def test_transmission_index_is_the_sine_of_the_transmission_angle(finger, t2):
    """The knuckle's transmission index is sin(mu), mu from the law of cosines."""
    result = transmission(finger, at_crank(finger, t2))
    mu = tb.finger_transmission_angle(t2)
    assert result.transmission_index["knuckle"][0] == pytest.approx(abs(math.sin(mu)), abs=1e-10)
    assert result.worst_index == pytest.approx(abs(math.sin(mu)), abs=1e-10)


def _potential(theta4: float) -> float:
    """Potential energy of the finger's bodies [J] at output angle theta4 (closed form, gravity -y)."""
    return sum(tb.FINGER_BODIES[n][0] * G * p[1] for n, (p, _) in tb.finger_points(theta4).items())


@pytest.mark.parametrize("t2", (0.8, 1.2, 2.2))
def test_static_crank_torque_is_the_virtual_work_of_load_and_weight(finger, t2):
    """Crank torque holding a torque on the finger and the weight: tau = dV/dt2 - f_out d t4/d t2."""
    q = at_crank(finger, t2)
    f_out = 0.05  # [N m] applied from outside on the finger joint
    forces = static_forces(finger, q, [f_out])
    t4, _ = tb.finger_freudenstein(t2)
    ratio = tb.finger_velocity_ratio(t2)
    h = 1e-5
    dV_dt4 = (_potential(t4 + h) - _potential(t4 - h)) / (2 * h)
    expected = (dV_dt4 - f_out) * ratio  # virtual work: tau dt2 = (dV/dt4 - f_out) dt4
    assert forces.f_c[0] == pytest.approx(expected, rel=1e-7)
    load = forces.balance.load
    assert isinstance(load, JointLoad) and load.joints == ("finger_pivot",)
    drives = {k: r.drive[0] for k, r in forces.joint_reactions().items()}
    assert drives["drive"] == pytest.approx(forces.f_c[0], rel=1e-9)
    assert abs(drives["coupler_pivot"]) < 1e-12 and abs(drives["finger_pivot"]) < 1e-12


def test_a_load_on_a_joint_task_takes_one_value_per_output_joint(finger):
    """A joint task's load is one torque per output joint; two values are refused by name."""
    with pytest.raises(InvalidInput, match="wrench"):
        load_on_frame(finger, [1.0, 2.0])
    assert load_on_frame(finger, [0.3]).generalized_force(finger.model).tolist() == [0.0, 0.0, 0.3]


def test_inverse_singularity_where_crank_and_coupler_are_aligned(finger):
    """At the finger's extreme (crank and coupler in line) the output stops: an inverse singularity."""
    a, b, c, d = (tb.FINGER[k] for k in "abcd")
    # |C| = a + b with C = (d + c cos t4, c sin t4): cos t4 = ((a + b)^2 - c^2 - d^2) / (2 c d)
    t4 = math.acos(((a + b) ** 2 - c * c - d * d) / (2 * c * d))
    t2 = math.atan2(c * math.sin(t4), d + c * math.cos(t4))
    q = finger.assemble(finger.q_ref, fixed={"drive": t2, "coupler_pivot": 0.0, "finger_pivot": t4}).q
    report = classify(finger, q)
    assert report.kinds == ("inverse",)
    assert transmission(finger, at_crank(finger, 1.2)).ratio[0, 0] != 0.0
    with pytest.raises(Exception, match="singular"):
        transmission(finger, q)


def _lagrangian_torque(theta4: float, rate: float, accel: float) -> float:
    """Crank torque driving the finger along theta4(t), from a Lagrangian in theta4.

    T = 1/2 I(t4) rate^2 with I = sum m |dp/dt4|^2 + izz (d angle/dt4)^2 from the closed-form
    positions; Q4 = I accel + 1/2 I' rate^2 + V'; the crank supplies tau = Q4 d t4/d t2.
    """

    def inertia(t4: float) -> float:
        h = 1e-6
        plus, minus = tb.finger_points(t4 + h), tb.finger_points(t4 - h)
        total = 0.0
        for name, (m, _, izz) in tb.FINGER_BODIES.items():
            dp = (plus[name][0] - minus[name][0]) / (2 * h)
            da = (plus[name][1] - minus[name][1]) / (2 * h)
            total += m * float(dp @ dp) + izz * da * da
        return total

    h = 1e-4
    dI = (inertia(theta4 + h) - inertia(theta4 - h)) / (2 * h)
    dV = (_potential(theta4 + h) - _potential(theta4 - h)) / (2 * h)
    Q4 = inertia(theta4) * accel + 0.5 * dI * rate * rate + dV
    t2, _ = tb.finger_from_output(theta4)
    return Q4 * tb.finger_velocity_ratio(t2)


def test_inverse_dynamics_along_an_output_trajectory_matches_a_lagrangian(finger):
    """Crank torque along theta4(t) = t4_0 + 0.2 sin(3 t) equals the closed-form Lagrangian's."""
    t4_0 = task_pose(finger, finger.q_ref)[0]

    def profile(t):
        return (
            [t4_0 + 0.2 * math.sin(3 * t)],
            [0.6 * math.cos(3 * t)],
            [-1.8 * math.sin(3 * t)],
        )

    times = np.linspace(0.0, 1.0, 7)
    traj = task_trajectory(finger, profile, times)
    result = inverse_dynamics(finger, traj)
    for k, t in enumerate(times):
        x, xd, xdd = (v[0] for v in profile(t))
        assert result.f_c[k, 0] == pytest.approx(_lagrangian_torque(x, xd, xdd), rel=1e-6)


def test_cli_info_and_check_show_the_joint_task(finger, tmp_path):
    """`plm-pin info` names the output joint as the task; `check` passes with mobility 1."""
    tb.finger(tmp_path)
    info = CliRunner().invoke(app, ["info", str(tmp_path / "finger.urdf")])
    assert info.exit_code == 0, info.output
    assert "output joints: finger_pivot" in info.stdout
    check = CliRunner().invoke(app, ["check", str(tmp_path / "finger.urdf")])
    assert check.exit_code == 0, check.output
    assert "ok: finger: 1 closures, 1 actuators, mobility 1" in check.stdout


def test_prismatic_joint_task_on_the_sliders_is_the_identity_transmission(tmp_path):
    """A 3-PRR whose task is its sliders: IK puts each slider where asked; ratio and advantage are I."""
    import yaml

    tb.three_prr(tmp_path, reference=tb.prr_reference(tb.PRR_POSE))
    sidecar = tmp_path / "prr3.plm.yaml"
    data = yaml.safe_load(sidecar.read_text())
    data["end_effector"] = {"joints": ["slider0", "slider1", "slider2"]}
    sidecar.write_text(yaml.safe_dump(data))
    mech = plm_pin.load(tmp_path / "prr3.urdf")
    sliders = tb.prr_ik(tb.PRR_POSE, (1, 1, 1))
    np.testing.assert_allclose(task_pose(mech, mech.q_ref), sliders, atol=1e-12)
    target = sliders + np.array([0.01, -0.02, 0.015])
    sol = inverse_kinematics(mech, target)
    np.testing.assert_allclose(mech.actuator_positions(sol.q), target, atol=1e-12)
    result = transmission(mech, sol.q)
    np.testing.assert_allclose(result.ratio, np.eye(3), atol=1e-10)
    np.testing.assert_allclose(result.mechanical_advantage, np.eye(3), atol=1e-10)
