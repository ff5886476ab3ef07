"""Joint position limits (plm_pin/kinematics/limits.py): missing ones, and limits as reachability."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.exceptions import JointLimitExceeded
from plm_pin.kinematics import forward_kinematics, inverse_kinematics
from plm_pin.warnings import MissingLimitsWarning
from plm_pin.workspace import workspace_map
from tests import textbook as tb
from tests.conftest import INTEROP

ISO3D = INTEROP / "5bar_linkage_iso3d"


@pytest.mark.skipif(not ISO3D.is_dir(), reason="example-parallel-robots corpus absent")
def test_missing_limits_are_unlimited_and_fk_finds_both_planar_modes():
    """5bar_linkage_iso3d: one warning names the 5 limitless joints; FK finds both in-plane assemblies.

    The two in-plane assemblies of a five-bar are mirror images across the line of its two
    elbows: the closure point is at the same distance from each elbow in both.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mech = plm_pin.load(ISO3D)
    limits = [str(w.message) for w in caught if issubclass(w.category, MissingLimitsWarning)]
    assert limits == [
        f"{ISO3D / 'robot.urdf'}: 5 joint(s) have no position limits (lower = upper = 0 in the URDF) and "
        "are treated as unlimited (continuous): ['free2', 'mot2', 'mot1', 'free1', 'freeortho']"
    ]
    assert np.all(np.isinf(mech.model.upperPositionLimit))
    found = forward_kinematics(mech, mech.actuator_positions(mech.q_ref))
    data = mech.model.createData()
    point, elbows, planar = mech.model.getFrameId("closedloop3D_1A"), ("free1", "free2"), []
    for sol in found:
        pin.framesForwardKinematics(mech.model, data, sol.q)
        if abs(sol.q[mech.model.joints[mech.model.getJointId("freeortho")].idx_q]) < 1e-9:
            E = [data.oMi[mech.model.getJointId(j)].translation.copy() for j in elbows]
            planar.append((data.oMf[point].translation.copy(), E))
    assert len(planar) == 2
    (P1, E), (P2, E2) = planar
    np.testing.assert_allclose(E, E2, atol=1e-12)  # the motors fix the elbows
    assert np.linalg.norm(P1 - P2) > 1e-3
    for e in E:
        assert np.linalg.norm(P1 - e) == pytest.approx(np.linalg.norm(P2 - e), abs=1e-12)


def _outside(angle: float, lo: float, hi: float) -> float:
    """Distance of the angle, shifted by the nearest multiple of 2 pi, to [lo, hi] (by hand)."""
    return min(max(lo - a, a - hi, 0.0) for a in (angle + 2 * math.pi * k for k in range(-2, 3)))


@pytest.fixture(scope="module")
def limited(tmp_path_factory):
    """The 3-RRR with leg 1's elbow limited to [psi_ref - 0.02, psi_ref + 2] [rad]."""
    theta = tb.rrr_ik(tb.RRR_POSE, (1, 1, 1))
    psi = tb.rrr_elbows(tb.RRR_POSE, theta)[1]
    lo, hi = psi - 0.02, psi + 2.0
    return tb.three_rrr(tmp_path_factory.mktemp("rrr"), elbow_limits=(lo, hi)), (lo, hi)


def test_ik_reports_passive_limits_apart(limited):
    """IK at poses where the closed-form elbow angle leaves its range reports it, and refuses on request."""
    mech, (lo, hi) = limited
    beyond = []
    for dx in ([0.0, 0.0, 0.0], [0.03, 0.0, 0.0], [-0.03, 0.0, 0.0], [0.0, 0.03, 0.0], [0.0, -0.03, 0.0]):
        pose = tuple(np.array(tb.RRR_POSE) + dx)
        psi = tb.rrr_elbows(pose, tb.rrr_ik(pose, (1, 1, 1)))[1]
        sol = inverse_kinematics(mech, pose)
        np.testing.assert_allclose(sol.actuators, tb.rrr_ik(pose, (1, 1, 1)), atol=1e-12)
        expected = _outside(psi, lo, hi)
        if expected > 1e-9:
            beyond.append(pose)
            assert sol.limit_violations == {"e1": pytest.approx(expected, abs=1e-12)}
            with pytest.raises(
                JointLimitExceeded, match=r"closes the loops only with joints outside their limits: e1 by "
            ):
                inverse_kinematics(mech, pose, respect_limits=True)
        else:
            assert sol.within_limits
    assert 0 < len(beyond) < 5  # both cases were met


def test_map_marks_poses_beyond_passive_limits_apart_from_reachability(limited):
    """On an x-y map the within-limits mask is the closed-form elbow condition at the reached points."""
    mech, (lo, hi) = limited
    xs, ys = np.linspace(-0.05, 0.08, 7), np.linspace(-0.06, 0.05, 6)
    grid = workspace_map(mech, ("x", "y"), (xs, ys), tb.RRR_POSE)
    mask = grid.within_limits(mech)
    assert grid.reachable.all()
    for i, x in enumerate(xs):
        for j, y in enumerate(ys):
            pose = (x, y, tb.RRR_POSE[2])
            psi = tb.rrr_elbows(pose, tb.rrr_ik(pose, (1, 1, 1)))[1]
            assert mask[i, j] == (_outside(psi, lo, hi) <= 1e-9)
    assert 0 < mask.sum() < mask.size
