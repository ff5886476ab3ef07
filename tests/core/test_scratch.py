"""Workspaces and live views of frame placements (plm_pin/core/scratch.py)."""

from __future__ import annotations

import gc
import weakref

import numpy as np
import pinocchio as pin

from plm_pin.core import scratch
from tests.conftest import preset


def test_placement_views_follow_every_update_of_the_data(rng):
    """The views made once show the placements of each later framesForwardKinematics pass, bit for bit."""
    mech = preset("zhao2011_8pss")
    data = mech.model.createData()
    frames = tuple(range(mech.model.nframes))
    translations, rotations = scratch.placement_views(data, frames)
    for _ in range(3):
        q = pin.integrate(mech.model, mech.q_ref, rng.normal(scale=0.3, size=mech.nv))
        pin.framesForwardKinematics(mech.model, data, q)
        for f, t, R in zip(frames, translations, rotations, strict=True):
            np.testing.assert_array_equal(t, data.oMf[f].translation)
            np.testing.assert_array_equal(R, data.oMf[f].rotation)
    assert scratch.placement_views(data, frames)[0] is translations  # made once per data and frames


def test_joint_placement_views_follow_every_pass_and_are_not_the_frames(rng):
    """Views of joint placements (joints=True) show each computeJointJacobians pass, apart from frames."""
    mech = preset("zhao2011_8pss")
    data = mech.model.createData()
    joints = tuple(range(1, mech.model.njoints))
    translations, rotations = scratch.placement_views(data, joints, joints=True)
    for _ in range(3):
        q = pin.integrate(mech.model, mech.q_ref, rng.normal(scale=0.3, size=mech.nv))
        pin.computeJointJacobians(mech.model, data, q)
        for j, t, R in zip(joints, translations, rotations, strict=True):
            np.testing.assert_array_equal(t, data.oMi[j].translation)
            np.testing.assert_array_equal(R, data.oMi[j].rotation)
    assert scratch.placement_views(data, joints, joints=True)[1] is rotations
    assert scratch.placement_views(data, joints)[1] is not rotations  # the frames with those indices


def test_placement_views_are_kept_for_a_bounded_number_of_datas():
    """Views (which keep their data alive) are kept for the last VIEWS_KEPT datas; older datas are freed."""
    mech = preset("harada2011_3d4m")
    first = mech.model.createData()
    scratch.placement_views(first, (1, 2))
    alive = weakref.ref(first)
    del first
    for _ in range(scratch.VIEWS_KEPT):
        scratch.placement_views(mech.model.createData(), (1, 2))
    gc.collect()
    assert alive() is None
    assert len(scratch._VIEWS) <= scratch.VIEWS_KEPT
