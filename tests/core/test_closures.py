"""Closure residuals and Jacobians (plm_pin/core/closures.py)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.core import closures
from plm_pin.models import preset_names
from tests.conftest import INTEROP, ball_joint_body, fd_jacobian, preset, spatial_6r
from tests.core.conftest import random_q

CLOSURE_KINDS = [{"type": "point"}, {"type": "weld"}, {"type": "revolute", "axis": [0, 0.6, 0.8]}]
"""One closure of each type (a revolute about an oblique axis) on :func:`ball_joint_body`."""


@pytest.mark.parametrize("name", preset_names())
def test_jacobian_matches_finite_differences_on_presets(name, rng):
    """J_phi equals central finite differences of phi at open-loop random configurations."""
    mech = preset(name)
    for _ in range(3):
        q = random_q(mech, rng)
        J = mech.closure_jacobian(q)
        J_fd = fd_jacobian(mech.closure_residual, mech.model, q)
        np.testing.assert_allclose(J, J_fd, atol=1e-8)


@pytest.mark.parametrize("kind", CLOSURE_KINDS)
def test_jacobian_matches_finite_differences_for_every_closure_type(tmp_path, rng, kind):
    """Point, weld and revolute residuals have exact Jacobians, away from closure too."""
    mech = ball_joint_body(tmp_path, kind)
    for _ in range(5):
        q = random_q(mech, rng, scale=1.0)
        np.testing.assert_allclose(
            mech.closure_jacobian(q), fd_jacobian(mech.closure_residual, mech.model, q), atol=1e-8
        )


@pytest.mark.parametrize(
    ("kind", "rows", "mobility"),
    [
        ({"type": "point"}, 3, 3),
        ({"type": "revolute", "axis": [0, 0.6, 0.8]}, 5, 1),
        ({"type": "weld"}, 6, 0),
    ],
)
def test_closure_types_remove_the_right_number_of_freedoms(tmp_path, kind, rows, mobility):
    """A ball-jointed body closed on the world keeps 3, 1 or 0 rotations for point, revolute, weld."""
    mech = ball_joint_body(tmp_path, kind)
    assert mech.n_closure_rows == rows
    assert mech.mobility == mobility


def test_revolute_closure_frees_exactly_the_rotation_about_its_axis(tmp_path):
    """The null space of a spatial revolute closure is the rotation about the given axis."""
    axis = np.array([0.0, 0.6, 0.8])
    mech = ball_joint_body(tmp_path, {"type": "revolute", "axis": axis.tolist()})
    q = mech.q_ref
    J = mech.closure_jacobian(q)
    _, s, Vt = np.linalg.svd(J)
    assert np.sum(s > 1e-9 * s[0]) == 2  # the point rows vanish at the ball centre
    v = Vt[-1]
    data = mech.model.createData()
    pin.computeJointJacobians(mech.model, data, q)
    pin.updateFramePlacements(mech.model, data)
    fid = mech.model.getFrameId("body_tip")
    omega = pin.getFrameJacobian(mech.model, data, fid, pin.ReferenceFrame.LOCAL) @ v
    np.testing.assert_allclose(np.abs(omega[3:] / np.linalg.norm(omega[3:])), axis, atol=1e-12)
    np.testing.assert_allclose(omega[:3], 0.0, atol=1e-12)


def test_revolute_closure_residual_vanishes_after_a_full_half_turn(tmp_path):
    """The revolute residual is zero for any rotation about the axis, 180 deg included."""
    mech = ball_joint_body(tmp_path, {"type": "revolute", "axis": [0, 0, 1]})
    for angle in (0.3, np.pi / 2, np.pi, -2.5):
        q = mech.q_ref.copy()
        q[2] = angle  # the rz joint turns about the closure axis
        assert np.max(np.abs(mech.closure_residual(q))) < 1e-15


def test_interop_fivebar_jacobian_matches_finite_differences(rng):
    """The example-parallel-robots five-bar (6d closure) has an exact closure Jacobian."""
    if not INTEROP.is_dir():
        pytest.skip("interop corpus absent")
    import plm_pin
    from plm_pin.warnings import MissingLimitsWarning

    with pytest.warns(MissingLimitsWarning):  # its URDF gives no position limits
        mech = plm_pin.load(INTEROP / "5bar_linkage")
    q = random_q(mech, rng)
    np.testing.assert_allclose(
        mech.closure_jacobian(q), fd_jacobian(mech.closure_residual, mech.model, q), atol=1e-8
    )


@pytest.mark.parametrize(
    ("kind", "rank"),
    [({"type": "point"}, 3), ({"type": "revolute", "axis": [0.0, 0.0, 1.0]}, 5), ({"type": "weld"}, 6)],
)
def test_spatial_closures_constrain_3_5_6_rows(tmp_path, rng, kind, rank):
    """On a generic spatial 6R loop, point, revolute and weld closures have rank 3, 5 and 6."""
    mech = spatial_6r(tmp_path, kind)
    assert mech.closure_rank(mech.q_ref) == rank
    assert mech.mobility == 6 - rank
    q = random_q(mech, rng)
    np.testing.assert_allclose(
        mech.closure_jacobian(q), fd_jacobian(mech.closure_residual, mech.model, q), atol=1e-8
    )


def test_residual_and_jacobian_fill_a_given_buffer(rng):
    """With ``out``, the residual and Jacobian are written into the caller's buffers, values unchanged."""
    mech = preset("zhao2011_8pss")
    q = pin.integrate(mech.model, mech.q_ref, rng.normal(scale=0.05, size=mech.nv))
    pin.computeJointJacobians(mech.model, mech.data, q)
    pin.updateFramePlacements(mech.model, mech.data)
    m = mech.n_closure_rows
    r, A = np.full(m + 2, np.nan), np.full((m + 2, mech.nv), np.nan)
    assert closures.residual_from_placements(mech.data, mech.closures, r[1:-1]).base is r
    assert closures.jacobian_from_data(mech.model, mech.data, mech.closures, A[1:-1]).base is A
    np.testing.assert_array_equal(r[1:-1], closures.residual_from_placements(mech.data, mech.closures))
    np.testing.assert_array_equal(A[1:-1], closures.jacobian_from_data(mech.model, mech.data, mech.closures))
    assert np.isnan(r[[0, -1]]).all() and np.isnan(A[[0, -1]]).all()


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_8pss"])
def test_point_rows_are_the_frame_gaps_and_jacobian_differences_exactly(name, rng):
    """Point rows from the constant +-1 maps equal p_B - p_A and J_B - J_A from Pinocchio, bit for bit."""
    mech = preset(name)
    data = mech.model.createData()
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    for _ in range(3):
        q = random_q(mech, rng)
        pin.computeJointJacobians(mech.model, data, q)
        pin.updateFramePlacements(mech.model, data)
        gaps = [
            data.oMf[b].translation - data.oMf[a].translation for a, b in (c.frame_ids for c in mech.closures)
        ]
        rows = [
            pin.getFrameJacobian(mech.model, data, b, lwa)[:3]
            - pin.getFrameJacobian(mech.model, data, a, lwa)[:3]
            for a, b in (c.frame_ids for c in mech.closures)
        ]
        np.testing.assert_array_equal(
            closures.residual_from_placements(data, mech.closures), np.concatenate(gaps)
        )
        np.testing.assert_array_equal(
            closures.jacobian_from_data(mech.model, data, mech.closures), np.vstack(rows)
        )


def _drift_fd(mech, jac, q, v, eps=1e-6):
    """d/dt (J(q(t)) v) along q(t) = q (+) t v, by central differences."""
    plus = jac(pin.integrate(mech.model, q, eps * v))
    minus = jac(pin.integrate(mech.model, q, -eps * v))
    return (plus - minus) @ v / (2 * eps)


@pytest.mark.parametrize("kind", CLOSURE_KINDS)
def test_drift_matches_finite_differences_of_the_jacobian(tmp_path, rng, kind):
    """The acceleration drift equals d/dt(J_phi) v for every closure type, off closure too."""
    mech = ball_joint_body(tmp_path, kind)
    for _ in range(5):
        q = random_q(mech, rng, scale=1.0)
        v = rng.normal(size=mech.nv)
        gamma = closures.drift(mech.model, mech.data, mech.closures, q, v)
        np.testing.assert_allclose(gamma, _drift_fd(mech, mech.closure_jacobian, q, v), atol=1e-7)


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_8pss", "enferadi2017_star_triangle"])
def test_drift_matches_finite_differences_on_presets(name, rng):
    """On the presets (point and weld closures), drift == d/dt(J_phi) v at assembled configurations."""
    mech = preset(name)
    q = mech.q_ref
    v = rng.normal(size=mech.nv)
    gamma = closures.drift(mech.model, mech.data, mech.closures, q, v)
    np.testing.assert_allclose(gamma, _drift_fd(mech, mech.closure_jacobian, q, v), atol=1e-7)


def test_task_drift_matches_finite_differences(rng):
    """The task drift equals d/dt(J_x) v (world-aligned twist rows of the task frame)."""
    mech = preset("zhao2011_8pss")
    task = mech.task_compiled

    def jac(q):
        pin.computeJointJacobians(mech.model, mech.data, q)
        pin.updateFramePlacements(mech.model, mech.data)
        return task.jacobian_from_data(mech.model, mech.data).copy()

    q = random_q(mech, rng, scale=0.3)
    v = rng.normal(size=mech.nv)
    pin.forwardKinematics(mech.model, mech.data, q, v, np.zeros(mech.nv))
    pin.updateFramePlacements(mech.model, mech.data)
    gamma = task.drift_from_data(mech.model, mech.data)
    np.testing.assert_allclose(gamma, _drift_fd(mech, jac, q, v), atol=1e-7)


def test_weld_drift_is_finite_and_exact_at_alignment(tmp_path, rng):
    """At an assembled weld (rotation residual 0, where pin.Hlog3 is NaN) the drift stays finite and exact."""
    mech = ball_joint_body(tmp_path, {"type": "weld"})
    q = mech.neutral()
    assert np.max(np.abs(mech.closure_residual(q))) == 0.0  # aligned: log3 of the identity
    v = rng.normal(size=mech.nv)
    gamma = closures.drift(mech.model, mech.data, mech.closures, q, v)
    assert np.all(np.isfinite(gamma))
    np.testing.assert_allclose(gamma, _drift_fd(mech, mech.closure_jacobian, q, v), atol=1e-7)
