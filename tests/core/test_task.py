"""Task coordinates, their Jacobian and task targets (plm_pin/core/task.py).

Oracles: the presets' reference poses (their builders' parameters), finite differences, and
the fixed-axis angle-rate relation omega = [R_z R_y x, R_z y, z] rpy_dot written inline.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from plm_pin import InvalidInput
from plm_pin.core.task import TaskTarget, check_task_vector, compile_task, rpy_rates, wrap_angle
from plm_pin.kinematics import task_pose
from plm_pin.models import PRESETS, preset_names
from tests.conftest import fd_jacobian, preset
from tests.core.conftest import random_q


@pytest.mark.parametrize(
    "name", ["harada2011_3d4m", "harada2011_3d3m", "harada2015_asymmetric", "enferadi2017_star_triangle"]
)
def test_reference_task_pose_is_the_presets_reference_pose(name):
    """The task pose of the reference configuration is the pose the preset was built around."""
    expected = PRESETS[name].parameters["reference_pose"]
    np.testing.assert_allclose(task_pose(preset(name), preset(name).q_ref), expected, atol=1e-12)


@pytest.mark.parametrize("name", ["zhao2011_8pss", "zhao2011_6pss"])
def test_pss_reference_task_pose_is_home(name):
    """The n-PSS reference task pose is the home pose (0, 0, 1.744 m, level)."""
    np.testing.assert_allclose(
        task_pose(preset(name), preset(name).q_ref), (0, 0, 1.744, 0, 0, 0), atol=1e-12
    )


def test_star_triangle_task_angle_is_the_star_line_3_angle():
    """For the star-triangle, rz is phi, the angle of star line 3 (pivot1 = phi - pi/2)."""
    mech = preset("enferadi2017_star_triangle")
    q = mech.q_ref.copy()
    assert task_pose(mech, q)[2] == pytest.approx(
        math.pi / 2 + q[mech.model.joints[mech.model.getJointId("pivot1")].idx_q]
    )


@pytest.mark.parametrize("name", preset_names())
def test_task_jacobian_matches_finite_differences(name, rng):
    """The task Jacobian is the task frame's world twist: FD of its position and log3 of its rotation."""
    mech = preset(name)
    task = mech.task_compiled
    fid = task.frame_id
    data = mech.model.createData()

    def placement_vector(q):
        pin.framesForwardKinematics(mech.model, data, q)
        return data.oMf[fid].translation.copy(), data.oMf[fid].rotation.copy()

    for _ in range(2):
        q = random_q(mech, rng)
        pin.computeJointJacobians(mech.model, data, q)
        pin.updateFramePlacements(mech.model, data)
        J = task.jacobian_from_data(mech.model, data)
        eps = 1e-6
        for k in range(mech.nv):
            dv = np.zeros(mech.nv)
            dv[k] = eps
            p1, R1 = placement_vector(pin.integrate(mech.model, q, dv))
            p0, R0 = placement_vector(pin.integrate(mech.model, q, -dv))
            twist = np.concatenate([(p1 - p0) / (2 * eps), pin.log3(R1 @ R0.T) / (2 * eps)])
            np.testing.assert_allclose(J[:, k], twist[list(task.rows)], atol=1e-8)


@pytest.mark.parametrize("name", ["harada2011_3d4m", "fivebar", "fourbar", "enferadi2017_star_triangle"])
def test_planar_task_coordinates_differentiate_to_the_task_jacobian(name, rng):
    """For planar tasks the Jacobian is the derivative of the task coordinates (rz rate = omega_z)."""
    mech = preset(name)
    q = random_q(mech, rng, 0.2)
    data = mech.model.createData()
    pin.computeJointJacobians(mech.model, data, q)
    pin.updateFramePlacements(mech.model, data)
    J = mech.task_compiled.jacobian_from_data(mech.model, data)
    np.testing.assert_allclose(J, fd_jacobian(lambda qq: task_pose(mech, qq), mech.model, q), atol=1e-8)


@pytest.mark.parametrize("name", preset_names())
def test_task_target_jacobian_matches_finite_differences(name, rng):
    """TaskTarget residual Jacobians (position rows, wrapped angles or log3) equal finite differences."""
    mech = preset(name)
    task = mech.task_compiled
    data = mech.model.createData()
    x = task_pose(mech, mech.q_ref) + rng.normal(scale=0.05, size=task.size)
    target = TaskTarget(task, x)

    def residual(q):
        pin.framesForwardKinematics(mech.model, data, q)
        return target.residual(data)

    for _ in range(2):
        q = random_q(mech, rng, 0.2)
        pin.computeJointJacobians(mech.model, data, q)
        pin.updateFramePlacements(mech.model, data)
        np.testing.assert_allclose(
            target.jacobian(mech.model, data), fd_jacobian(residual, mech.model, q), atol=1e-8
        )


def test_task_target_residual_is_the_pose_error():
    """The residual is p - p* and log3(R R*^T): a target turned 0.1 rad about an axis gives -0.1 axis."""
    mech = preset("zhao2011_8pss")
    task = mech.task_compiled
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.q_ref)
    M = data.oMf[task.frame_id]
    axis = np.array([1.0, -2.0, 2.0]) / 3.0
    R_target = pin.exp3(0.1 * axis) @ M.rotation
    x = np.concatenate([M.translation + np.array([0.01, 0.0, -0.02]), pin.rpy.matrixToRpy(R_target)])
    np.testing.assert_allclose(
        TaskTarget(task, x).residual(data), [-0.01, 0.0, 0.02, *(-0.1 * axis)], atol=1e-12
    )


def test_planar_target_wraps_the_angle():
    """A planar target at theta + 2 pi minus a tiny step gives a residual of that tiny step, not ~2 pi."""
    mech = preset("harada2011_3d4m")
    task = mech.task_compiled
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.q_ref)
    x = task_pose(mech, mech.q_ref) + np.array([0.0, 0.0, 2 * math.pi - 1e-3])
    np.testing.assert_allclose(TaskTarget(task, x).residual(data), [0.0, 0.0, 1e-3], atol=1e-12)


def test_rpy_rates_invert_the_fixed_axis_relation():
    """With omega = [R_z R_y e_x, R_z e_y, e_z] rpy_dot (R = R_z R_y R_x), rpy_rates gives rpy_dot back."""
    rng = np.random.default_rng(3)
    for _ in range(5):
        r, p, y = rng.uniform(-1.2, 1.2, 3)
        Rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
        Ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
        E = np.column_stack([Rz @ Ry @ [1, 0, 0], Rz @ [0, 1, 0], [0, 0, 1]])
        rates = rng.normal(size=3)
        np.testing.assert_allclose(rpy_rates(np.array([r, p, y]), E @ rates), rates, atol=1e-12)


def test_wrap_angle_maps_to_minus_pi_exclusive_pi_inclusive():
    """Angles are wrapped to (-pi, pi]: pi and -pi both give pi, 3 pi / 2 gives -pi / 2."""
    np.testing.assert_allclose(
        wrap_angle(np.array([0.0, math.pi, -math.pi, 1.5 * math.pi, -7.0])),
        [0.0, math.pi, math.pi, -0.5 * math.pi, -7.0 + 2 * math.pi],
        atol=1e-15,
    )


def test_compile_task_selects_rows_in_order():
    """A task [x, y, rz] selects rows (0, 1, 5): linear (0, 1), angular (2,)."""
    mech = preset("harada2011_3d4m")
    task = compile_task(mech.model, "plate_center", ("x", "y", "rz"))
    assert task.rows == (0, 1, 5)
    assert task.linear == (0, 1)
    assert task.angular == (2,)
    assert task.size == 3


@pytest.mark.parametrize(
    ("x", "message"),
    [
        ([1.0, float("nan")], r"^x has non-finite entries at indices \[1\]$"),
        ([1.0, 2.0, 3.0], r"^x must have shape \(2,\), got \(3,\)$"),
        ("ab", r"^x must be 2 numbers: could not convert string to float: 'ab'$"),
        ([1.0, [2.0, 3.0]], r"^x must be 2 numbers: setting an array element with a sequence"),
    ],
)
def test_check_task_vector_refuses_bad_input(x, message):
    """Non-numbers, NaN and wrongly shaped task vectors raise InvalidInput saying why."""
    with pytest.raises(InvalidInput, match=message):
        check_task_vector(x, 2)


def test_task_target_on_unordered_rows_fills_a_given_buffer(rng):
    """Rows (z, x, rz, rx): residual = wrapped pose error, Jacobian = finite differences, into ``out``."""
    mech = preset("zhao2011_8pss")
    task = compile_task(
        mech.model, mech.model.frames[mech.task_compiled.frame_id].name, ("z", "x", "rz", "rx")
    )
    data = mech.model.createData()
    q = random_q(mech, rng, 0.05)
    pin.framesForwardKinematics(mech.model, data, q)
    M = data.oMf[task.frame_id]
    rpy = pin.rpy.matrixToRpy(M.rotation)
    x = np.array([M.translation[2] - 0.01, M.translation[0] + 0.02, rpy[2] - 2 * math.pi + 0.03, rpy[0]])
    target = TaskTarget(task, x)
    r = np.full(6, np.nan)
    assert target.residual(data, r[1:5]).base is r
    np.testing.assert_allclose(r[1:5], [0.01, -0.02, -0.03, 0.0], atol=1e-12)

    def residual(qq):
        pin.framesForwardKinematics(mech.model, data, qq)
        return target.residual(data)

    pin.computeJointJacobians(mech.model, data, q)
    pin.updateFramePlacements(mech.model, data)
    A = np.full((6, mech.nv), np.nan)
    assert target.jacobian(mech.model, data, A[1:5]).base is A
    np.testing.assert_allclose(A[1:5], fd_jacobian(residual, mech.model, q), atol=1e-8)
    assert np.isnan(A[[0, 5]]).all()
