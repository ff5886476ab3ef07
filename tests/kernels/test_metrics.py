"""The compiled map metrics against the numpy path (QR, LAPACK eigenvalues and SVDs) on random poses."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.core.task import TaskTarget
from plm_pin.kernels import kernel_of
from plm_pin.kinematics import inverse_kinematics, task_pose
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
    _, good = kernel.map_metrics(A, mech.actuated_v_indices, mech.mobility)
    assert good.all()
    for key, value in want.items():
        np.testing.assert_allclose(got[key], value, rtol=1e-9, err_msg=key)
