"""The compiled map metrics against the numpy path (QR, LAPACK eigenvalues and SVDs) on random poses."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.core.task import TaskTarget
from plm_pin.kernels import kernel_of
from plm_pin.kernels.metrics import METRIC_NAMES
from plm_pin.kinematics import inverse_kinematics, task_pose
from plm_pin.kinematics.jacobians import ik_jacobian
from plm_pin.tolerances import GRAM_RTOL
from plm_pin.workspace import workspace_map
from plm_pin.workspace._batch import compiled_square_task_metrics
from plm_pin.workspace.manipulability import batch_metrics
from tests.conftest import preset


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_8pss", "fivebar"])
def test_compiled_metrics_match_the_svd_metrics(name, rng):
    mech = preset(name)
    kernel = kernel_of(mech)
    assert kernel is not None
    target_task = mech.task_compiled
    x0 = task_pose(mech, mech.q_ref)
    A = []
    for _ in range(20):
        x = x0 + rng.normal(scale=0.005, size=x0.size)
        q = inverse_kinematics(mech, x, mech.q_ref).q
        _, J = kernel.rows(q, TaskTarget(target_task, x))
        data = mech.model.createData()
        pin.computeJointJacobians(mech.model, data, q)
        pin.updateFramePlacements(mech.model, data)
        J_x = pin.getFrameJacobian(mech.model, data, target_task.frame_id, pin.LOCAL_WORLD_ALIGNED)
        A.append(np.vstack([J[: mech.n_closure_rows], J_x[list(target_task.rows)]]))
    A = np.array(A)
    m = mech.n_closure_rows
    got = compiled_square_task_metrics(kernel, A, m, mech.actuated_v_indices, mech.mobility)
    want = batch_metrics(A[:, :m], A[:, m:], mech.actuated_v_indices, mech.mobility)  # SVDs
    _, good = kernel.map_metrics(A, mech.actuated_v_indices, mech.mobility, METRIC_NAMES)
    assert good.all()
    for key, value in want.items():
        np.testing.assert_allclose(got[key], value, rtol=1e-9, err_msg=key)
    for key in METRIC_NAMES:  # each alone: only its stages run, the same values
        alone = compiled_square_task_metrics(kernel, A, m, mech.actuated_v_indices, mech.mobility, (key,))
        assert list(alone) == [key]
        if key in ("manipulability", "condition_number"):  # alone, J_ce = S_a: the same to round-off
            np.testing.assert_allclose(alone[key], got[key], rtol=1e-12, err_msg=key)
        else:
            np.testing.assert_array_equal(alone[key], got[key], err_msg=key)
    both = compiled_square_task_metrics(
        kernel, A, m, mech.actuated_v_indices, mech.mobility, ("manipulability", "condition_number")
    )
    for key, value in both.items():  # the shortcut against the SVDs
        np.testing.assert_allclose(value, want[key], rtol=1e-9, err_msg=key)


def _square_root(rng, n, kind):
    """A random n x n X whose Gram X^T X is full rank, rank-deficient or graded."""
    X = rng.normal(size=(n, n))
    if kind == "deficient":  # rank n // 2, zero eigenvalues hidden by a random rotation
        X[: n - n // 2] = 0.0
        X = X @ np.linalg.qr(rng.normal(size=(n, n)))[0]
    elif kind == "graded":  # columns scaled over eight decades
        X = X * np.logspace(0.0, -8.0, n)
    return X


@pytest.mark.parametrize("kind", ["full", "deficient", "graded"])
def test_gram_eigenvalues_match_lapack(kind, rng):
    """Tridiagonal QL (and Jacobi below it) give LAPACK's eigenvalues to round-off of the matrix norm."""
    from plm_pin.kernels.metrics import _gram_eigenvalues, _tridiagonal_eigenvalues

    eps = np.finfo(float).eps
    for n in range(1, 13):
        for _ in range(20):
            X = _square_root(rng, n, kind)
            P = X.T @ X
            want = np.linalg.eigvalsh(P)[::-1]  # descending
            scale = max(want[0], np.finfo(float).tiny)
            G, d, e = np.full((n + 2, n + 2), np.nan), np.full(n + 2, np.nan), np.full(n + 2, np.nan)
            G[:n, :n] = P
            assert _tridiagonal_eigenvalues(G, n, d, e)
            np.testing.assert_allclose(np.sort(d[:n])[::-1], want, rtol=0.0, atol=50 * n * eps * scale)
            # from X itself (its Gram X X^T has the same eigenvalues; Jacobi for n <= 2), clipped at zero
            got = np.full(n + 2, np.nan)
            assert _gram_eigenvalues(X, np.empty((n + 2, n + 2)), np.empty(n + 2), got) == n
            assert np.all(np.diff(got[:n]) <= 0.0) and np.all(got[:n] >= 0.0)
            np.testing.assert_allclose(got[:n], np.clip(want, 0.0, None), rtol=0.0, atol=50 * n * eps * scale)


def test_tridiagonal_eigenvalues_on_special_matrices(rng):
    """Zero, scaled identity, repeated and widely scaled matrices: LAPACK's values to round-off of |G|."""
    from plm_pin.kernels.metrics import _tridiagonal_eigenvalues

    eps = np.finfo(float).eps
    Q = np.linalg.qr(rng.normal(size=(7, 7)))[0]
    cases = [
        np.zeros((7, 7)),
        3.0 * np.eye(7),
        Q @ np.diag([2.0, 2.0, 2.0, 1.0, 1.0, 0.0, 0.0]) @ Q.T,  # repeated eigenvalues, hidden
        1e100 * (Q @ np.diag(np.arange(7.0)) @ Q.T),
        1e-100 * (Q @ np.diag(np.arange(7.0)) @ Q.T),
    ]
    for P in cases:
        P = (P + P.T) / 2.0
        want = np.linalg.eigvalsh(P)
        G, d, e = P.copy(), np.empty(7), np.empty(7)
        assert _tridiagonal_eigenvalues(G, 7, d, e)
        np.testing.assert_allclose(np.sort(d), want, rtol=0.0, atol=50 * 7 * eps * np.abs(want).max())


def test_the_shortcut_near_singularities_equals_the_svd_metrics():
    """J_ce read off the velocity map (manipulability, condition number alone) over a 3D3M map to its edge.

    As the basis route (tests/workspace/test_batch.py), to 1e-11 of the SVD values: poses past
    the Gram's accuracy, or whose velocity map is ill-conditioned, take the SVD path.
    """
    mech = preset("harada2011_3d3m")
    values = (np.linspace(-0.16, 0.16, 30), np.linspace(0.0, 0.14, 25))
    result = workspace_map(mech, ("x", "y"), values, (0.0, 0.08, math.radians(-20.0)), workers=1)
    A = np.stack([ik_jacobian(mech, q) for q in result.q[result.reachable]])
    m, act = mech.n_closure_rows, mech.actuated_v_indices
    names = ("manipulability", "condition_number")
    kernel = kernel_of(mech)
    fast = compiled_square_task_metrics(kernel, A, m, act, mech.mobility, names)
    svd = batch_metrics(A[:, :m], A[:, m:], act, mech.mobility, names=names)
    assert svd["condition_number"].max() > 1.0 / math.sqrt(GRAM_RTOL)  # some poses take the SVD path
    _, good = kernel.map_metrics(A, act, mech.mobility, names)
    assert good.any() and not good.all()
    for name, value in svd.items():
        np.testing.assert_allclose(fast[name], value, rtol=1e-11, atol=0.0, err_msg=name)
