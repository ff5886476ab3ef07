"""Path continuation: inverse and forward continuation agree, and the redundancy margin."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.kinematics import closed_chain_jacobians
from plm_pin.kinematics.paths import follow_targets, redundancy_margin, track_actuator_path
from tests.conftest import preset

ASYM = "harada2015_asymmetric"


@pytest.fixture(scope="module")
def asym():
    return preset(ASYM)


def test_track_actuator_path_on_the_fivebar_round_trip():
    """Generic continuation: task path -> actuators (IK), actuators -> configurations (FK) agree."""
    mech = preset("fivebar")
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.q_ref)
    task = mech.task_compiled
    start = task.pose_from_data(data)
    assert task.dofs == ("x", "y")
    targets = start + np.outer(np.linspace(0.0, 1.0, 21), [0.02, -0.01])
    qs = follow_targets(mech, mech.q_ref, task_dofs=task.dofs, task_values=targets)
    c = np.array([mech.actuator_positions(q) for q in qs])
    path = track_actuator_path(mech, c, mech.q_ref)
    for q_ik, q_fk in zip(qs, path.q, strict=True):
        np.testing.assert_allclose(q_fk, q_ik, atol=1e-9)
    np.testing.assert_allclose(path.x, targets, atol=1e-10)
    assert path.max_residual <= 1e-10
    assert np.all(path.redundancy_margin == 0.0)  # non-redundant


def test_redundancy_margin_is_the_worst_single_slider_removal(asym):
    """redundancy_margin = min over k of sigma_min of C without row k, the direct margin (2015 reference)."""
    C = closed_chain_jacobians(asym, asym.q_ref).C
    expected = min(np.linalg.svd(np.delete(C, k, 0), compute_uv=False)[-1] for k in range(4))
    assert redundancy_margin(asym, asym.q_ref) == pytest.approx(expected, rel=1e-12)
    assert expected > 1e-3
