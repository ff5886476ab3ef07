"""Batched kinematics across poses (plm_pin/analysis/_batch.py) against Pinocchio and the serial path."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from plm_pin.analysis import _continuation, workspace_map
from plm_pin.analysis._batch import (
    GRAM_RTOL,
    BatchKinematics,
    batch_modes,
    batch_newton,
    square_task_metrics,
)
from plm_pin.analysis.manipulability import batch_metrics
from plm_pin.kinematics import closures as _closures
from plm_pin.kinematics import task_pose
from plm_pin.kinematics.legs import ik_jacobian, working_mode_from_jacobian
from plm_pin.kinematics.task import TaskTarget
from tests.conftest import preset


def test_batched_residual_and_jacobian_equal_pinocchio_to_1e_13():
    """At 40 random configurations of the 3D4M, the numpy tree gives Pinocchio's residual and Jacobian."""
    mech = preset("harada2011_3d4m")
    kin = BatchKinematics.from_parts(mech.model, mech.closures, mech.task_compiled)
    assert kin is not None
    rng = np.random.default_rng(7)
    Q = mech.q_ref + rng.normal(scale=0.5, size=(40, mech.nq))
    X = task_pose(mech, mech.q_ref) + rng.normal(scale=0.02, size=(40, 3))
    r, J = kin.residual_and_jacobian(Q, X)
    data = mech.model.createData()
    for b in range(40):
        pin.computeJointJacobians(mech.model, data, Q[b])
        pin.updateFramePlacements(mech.model, data)
        target = TaskTarget(mech.task_compiled, X[b])
        expected_r = np.concatenate(
            [_closures.residual_from_placements(data, mech.closures), target.residual(data)]
        )
        expected_J = np.vstack(
            [_closures.jacobian(mech.model, data, mech.closures, Q[b]), target.jacobian(mech.model, data)]
        )
        assert np.abs(r[b] - expected_r).max() < 1e-13
        assert np.abs(J[b] - expected_J).max() < 1e-13


def test_batched_newton_modes_and_metrics_match_the_serial_ones():
    """Batched Newton converges to 1e-12; its modes and factorised metrics are the serial ones."""
    mech = preset("harada2011_3d4m")
    kin = BatchKinematics.from_parts(mech.model, mech.closures, mech.task_compiled)
    assert kin is not None
    x0 = task_pose(mech, mech.q_ref)
    X = x0 + np.column_stack([np.linspace(-2e-3, 2e-3, 9), np.linspace(1e-3, -1e-3, 9), np.zeros(9)])
    q, ok, A = batch_newton(kin, np.tile(mech.q_ref, (9, 1)), X, 1e-12, 12, 0.9)
    assert ok.all()
    m = mech.n_closure_rows
    for b in range(9):
        A_serial = ik_jacobian(mech, q[b])
        assert np.abs(A[b] - A_serial).max() < 1e-13
        assert tuple(batch_modes(A[b : b + 1], mech.legs)[0]) == working_mode_from_jacobian(
            A_serial, mech.legs
        )
    fast = square_task_metrics(A, m, mech.actuated_v_indices, mech.mobility)
    svd = batch_metrics(A[:, :m], A[:, m:], mech.actuated_v_indices, mech.mobility)
    for name, values in svd.items():
        assert np.allclose(fast[name], values, rtol=1e-12, atol=0.0), name


def test_unsupported_models_fall_back_to_the_generic_path():
    """The 8-PSS (free-flyer platform, 6-D task) has no batched evaluator."""
    mech = preset("zhao2011_8pss")
    assert BatchKinematics.from_parts(mech.model, mech.closures, mech.task_compiled) is None


def test_row_batched_map_equals_the_point_by_point_map(monkeypatch):
    """A 3D4M map solved row by row in batches equals the generic point-by-point continuation."""
    mech = preset("harada2011_3d4m")
    values = (np.linspace(-0.16, 0.16, 23), np.linspace(0.0, 0.14, 19))  # reaches past the workspace edge
    pose = (0.0, 0.08, math.radians(-20.0))
    batched = workspace_map(mech, ("x", "y"), values, pose, workers=1)
    monkeypatch.setattr(_continuation.BatchKinematics, "from_parts", classmethod(lambda cls, *a: None))
    serial = workspace_map(mech, ("x", "y"), values, pose, workers=1)
    assert 0.3 < serial.reachable_fraction < 1.0
    assert np.array_equal(batched.reachable, serial.reachable)
    assert np.array_equal(batched.mode, serial.mode)
    ok = serial.reachable
    assert np.abs(batched.q[ok] - serial.q[ok]).max() < 1e-11
    assert np.allclose(batched.manipulability[ok], serial.manipulability[ok], rtol=1e-10, atol=0.0)


def test_gram_metrics_equal_the_svd_metrics_near_singularities():
    """Over a 3D3M map reaching its workspace edge (cond up to ~4e3), the Gram-eigenvalue metrics equal SVD's.

    The reference is :func:`batch_metrics` with its SVD basis of J_phi (no Newton system, no
    Gram matrix). The bound is that of ``GRAM_RTOL``: eps / GRAM_RTOL ~ 2e-12 relative, times a
    small constant; the poses past it (and the inverse-singular ones) take the SVD path itself.
    """
    mech = preset("harada2011_3d3m")
    values = (np.linspace(-0.16, 0.16, 30), np.linspace(0.0, 0.14, 25))
    result = workspace_map(mech, ("x", "y"), values, (0.0, 0.08, math.radians(-20.0)), workers=1)
    q = result.q[result.reachable]
    A = np.stack([ik_jacobian(mech, qq) for qq in q])
    m, act = mech.n_closure_rows, mech.actuated_v_indices
    fast = square_task_metrics(A, m, act, mech.mobility)
    svd = batch_metrics(A[:, :m], A[:, m:], act, mech.mobility)
    assert svd["condition_number"].max() > 1.0 / math.sqrt(GRAM_RTOL)  # some poses take the SVD path
    for name, values in svd.items():
        assert np.allclose(fast[name], values, rtol=1e-11, atol=0.0), name
    near = np.argmax(svd["condition_number"])
    for name, values in batch_metrics(
        A[near : near + 1, :m], A[near : near + 1, m:], act, mech.mobility
    ).items():
        assert fast[name][near] == values[0], name  # below GRAM_RTOL: the SVD values themselves
