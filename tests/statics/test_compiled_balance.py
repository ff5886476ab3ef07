"""The compiled balance factorisation against the LAPACK path it replaces (statics/_compiled.py)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.kernels import SWITCH, kernels_enabled
from plm_pin.models.registry import preset_names
from plm_pin.statics.balance import assembled_closure_jacobian, balance_factors
from plm_pin.tolerances import STATICS_SINGULAR_RTOL
from tests.conftest import preset

pytestmark = pytest.mark.skipif(not kernels_enabled(), reason="numba not installed")


def _factors(mech, J, tau, monkeypatch, compiled):
    monkeypatch.setenv(SWITCH, "1" if compiled else "0")
    return balance_factors(mech, J, mech.actuated_v_indices, tau, STATICS_SINGULAR_RTOL)


@pytest.mark.parametrize("name", preset_names())
def test_compiled_factors_equal_the_lapack_path_on_every_preset(name, monkeypatch):
    """Force map, closure-force map, internal basis and the projectors N N^T, C C^T agree to round-off."""
    mech = preset(name)
    if not mech.closures or not mech.n_actuators:
        pytest.skip("no closed loop or no actuator")
    q = mech.q_ref
    J = assembled_closure_jacobian(mech, mech.data, q)
    tau = pin.computeGeneralizedGravity(mech.model, mech.data, q).copy() + 1.0  # a generic load
    ours = _factors(mech, J, tau, monkeypatch, True)
    lapack = _factors(mech, J, tau, monkeypatch, False)
    assert ours.N.shape == lapack.N.shape
    np.testing.assert_allclose(ours.N @ ours.N.T, lapack.N @ lapack.N.T, atol=1e-12)
    np.testing.assert_allclose(ours.C @ ours.C.T, lapack.C @ lapack.C.T, atol=1e-12)
    scale = max(1.0, float(np.abs(lapack.P).max()), float(np.abs(lapack.lambda_map).max()))
    np.testing.assert_allclose(ours.P, lapack.P, atol=1e-12 * scale)
    np.testing.assert_allclose(ours.lambda_map, lapack.lambda_map, atol=1e-12 * scale)
    np.testing.assert_allclose(ours.G, lapack.G, atol=1e-12)
    np.testing.assert_allclose(ours.C, ours.N[mech.actuated_v_indices], atol=0.0)


def test_dependent_closure_rows_take_the_lapack_path(monkeypatch):
    """A repeated closure row (rank below the row count): the compiled call declines, the SVD path decides."""
    from plm_pin.statics import _compiled

    mech = preset("harada2011_3d4m")
    q = mech.q_ref
    J = assembled_closure_jacobian(mech, mech.data, q)
    J2 = np.vstack([J, J[:1]])
    tau = pin.computeGeneralizedGravity(mech.model, mech.data, q).copy()
    args = (J2, mech.actuated_v_indices, tau, STATICS_SINGULAR_RTOL, mech.closure_tol, 1e-9, 1e-9)
    assert _compiled.factor(*args)[0] == _compiled.FALLBACK
    ours = _factors(mech, J2, tau, monkeypatch, True)
    single = _factors(mech, J, tau, monkeypatch, False)
    np.testing.assert_allclose(ours.P, single.P, atol=1e-9)  # the same feasible motions and forces
    np.testing.assert_allclose(J2.T @ ours.lambda_map @ tau, J.T @ single.lambda_map @ tau, atol=1e-9)


@pytest.mark.parametrize("name", preset_names())
def test_compiled_closure_rows_equal_pinocchio_frame_jacobians(name):
    """Point closures: the compiled rows and closure decision equal Pinocchio's, bit for bit."""
    from plm_pin.core.closures import BoundClosures
    from plm_pin.core.scratch import placement_views
    from plm_pin.statics import _compiled
    from plm_pin.statics.balance import point_closures

    mech = preset(name)
    points = point_closures(mech) if mech.closures else None
    if points is None:
        pytest.skip("no closure, or closures with rotation rows (the Pinocchio path)")
    model = mech.model
    data = model.createData()
    rng = np.random.default_rng(7)
    for k in range(20):  # the reference pose, then poses off the closure manifold (J is defined there too)
        q = mech.q_ref if k == 0 else pin.integrate(model, mech.q_ref, 0.3 * rng.normal(size=model.nv))
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        bound = BoundClosures(data, mech.closures)
        expected = bound.jacobian(model, np.empty((bound.rows, model.nv)))
        phi = bound.residual(np.empty(bound.rows))
        ours = np.empty_like(expected)
        t = np.concatenate(placement_views(data, points.frames)[0]).reshape(-1, 3)
        tol = mech.assembled_tol
        closed = _compiled.point_closure_rows(
            data.J, t, points.support, points.plus, points.minus, points.axis, tol, ours
        )
        assert ours.tobytes() == expected.tobytes()
        assert closed == (np.abs(phi).max() <= tol)
        assert closed == (k == 0)
