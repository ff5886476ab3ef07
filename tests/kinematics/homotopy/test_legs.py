"""Legs reduced to distances (U-P-S legs) aimed in closed form from the platform pose.

Oracles: the leg lengths |p + R b - a| of a random platform pose, written here from the
base and platform points, and Pinocchio's closure residual of the aimed configuration.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.kinematics.homotopy import prepared
from plm_pin.kinematics.homotopy.polynomial import aim_legs
from tests.conftest import preset

from .test_complete_fk import _general_stewart


def _random_pose_with_lengths(mech: plm_pin.Mechanism, rng: np.random.Generator) -> np.ndarray:
    """q_ref with the platform moved at random and each strut at |p + R b_i - a_i|."""
    model, data = mech.model, mech.model.createData()
    q = mech.q_ref.copy()
    platform = model.joints[model.getJointId("platform_floating")]
    dv = np.zeros(model.nv)
    dv[platform.idx_v : platform.idx_v + 6] = np.r_[rng.uniform(-0.05, 0.05, 3), rng.uniform(-0.2, 0.2, 3)]
    q = pin.integrate(model, q, dv)
    pin.forwardKinematics(model, data, q)
    M = data.oMi[platform.id]
    for n in range(1, 7):
        a = data.oMi[model.getJointId(f"u{n}a")].translation
        b = model.frames[model.getFrameId(f"platform_p{n}")].placement.translation
        q[model.joints[model.getJointId(f"extend{n}")].idx_q] = np.linalg.norm(
            M.translation + M.rotation @ b - a
        )
    return q


@pytest.mark.parametrize("kernels", ["1", "0"])
@pytest.mark.parametrize("which", ["stewart_6ups", "general"])
def test_aimed_legs_close_every_loop_at_random_platform_poses(which, kernels, tmp_path, monkeypatch):
    """At 20 random platform poses the aimed legs close every loop to 1e-12, with no Newton.

    The placements come from the compiled kernels, or from Pinocchio with the kernels off.
    """
    monkeypatch.setenv("PLM_PIN_KERNELS", kernels)
    mech = _general_stewart(tmp_path) if which == "general" else preset(which)
    form, _ = prepared(mech)
    assert len(form.legs) == 6
    rng = np.random.default_rng(7)
    qs = np.array([_random_pose_with_lengths(mech, rng) for _ in range(20)])
    assert (
        min(np.abs(mech.closure_residual(q)).max() for q in qs) > 1e-3
    )  # the legs' joints are not there yet
    aimed, done = aim_legs(form, mech, qs)
    assert done
    for q, before in zip(aimed, qs, strict=True):
        assert np.abs(mech.closure_residual(q)).max() < 1e-12
        off_legs = np.ones(mech.model.nq, dtype=bool)
        for leg in form.legs:
            for iq, nq in zip(leg.q_index, leg.nq, strict=True):
                off_legs[iq : iq + nq] = False
        np.testing.assert_array_equal(q[off_legs], before[off_legs])  # only the legs' joints moved


def test_aim_pairs_recovers_the_turns_and_its_mirror_also_aims():
    """For random axes and angles, one pair is the angles (mod 2 pi); both turn v onto w (exp3 rotations)."""
    from plm_pin.kinematics.homotopy.polynomial import aim_pairs

    rng = np.random.default_rng(3)
    m = 50
    u1, u2 = (x / np.linalg.norm(x, axis=1)[:, None] for x in rng.normal(size=(2, m, 3)))
    theta = rng.uniform(-np.pi, np.pi, (m, 2))
    v = rng.normal(size=(m, 3))
    w = np.array([pin.exp3(u1[i] * theta[i, 0]) @ pin.exp3(u2[i] * theta[i, 1]) @ v[i] for i in range(m)])
    pairs = aim_pairs(u1, u2, v, w)
    for i in range(m):
        gap = np.angle(np.exp(1j * (pairs[:, i] - theta[i])))  # wrapped to (-pi, pi]
        assert np.abs(gap).max(axis=1).min() < 1e-9
        for t1, t2 in pairs[:, i]:
            np.testing.assert_allclose(pin.exp3(u1[i] * t1) @ pin.exp3(u2[i] * t2) @ v[i], w[i], atol=1e-12)
