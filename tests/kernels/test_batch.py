"""The kernels' batched Newton and working modes against the numpy batch engine of the workspace maps."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.core.assembly import NEWTON_MAX_ITERATIONS, STALL_RATIO
from plm_pin.kernels import kernel_of
from plm_pin.workspace._batch import BatchKinematics, batch_modes, batch_newton, rpy_matrix
from tests.conftest import preset


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_8pss", "fivebar"])
def test_batch_newton_matches_the_numpy_engine(name, rng):
    mech = preset(name)
    task = mech.task_compiled
    kin = BatchKinematics.from_parts(mech.model, mech.closures, task)
    assert kin is not None
    kernel = kernel_of(mech)
    assert kernel is not None
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.q_ref)
    x0 = task.pose_from_data(data)
    X = x0 + rng.normal(scale=0.01, size=(40, task.size))
    X[-1] += 50.0  # out of reach: both fail
    Q = np.array([pin.integrate(mech.model, mech.q_ref, rng.normal(scale=1e-3, size=mech.nv)) for _ in X])
    R_stars = np.broadcast_to(np.eye(3), (len(X), 3, 3))
    if len(task.angular) == 3:
        R_stars = rpy_matrix(X[:, len(task.linear) :])
    tol = mech.closure_tol
    want = batch_newton(kin, Q, X, tol, NEWTON_MAX_ITERATIONS, STALL_RATIO)
    got = kernel.newton_modes(mech.legs, Q, X, R_stars, tol, NEWTON_MAX_ITERATIONS)
    np.testing.assert_array_equal(got[1], want[1])
    assert got[1].sum() >= len(X) // 2 and not got[1][-1]
    ok = got[1]
    np.testing.assert_allclose(got[0][ok], want[0][ok], atol=1e-9)
    np.testing.assert_allclose(got[2][ok], want[2][ok], atol=1e-9)
    modes = batch_modes(want[2][ok], mech.legs, kin.turns(want[3][ok], mech.legs))
    np.testing.assert_array_equal(got[3][ok], modes)
