"""Skeleton drawings put the joints where the paper's closed forms put them."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import re

import numpy as np
import pytest

from analyses._harada2011_paper import pair_position, slider_positions
from plm_pin.exceptions import InvalidInput
from plm_pin.kinematics import inverse_kinematics
from plm_pin.viz import plot_skeletons
from tests.conftest import preset

L, RT = 0.14, 0.05  # Harada 2011 Table 1: rod length, half plate length [m]


def _points(ax) -> np.ndarray:
    return np.array([p for line in ax.get_lines() for p in line.get_xydata()])


def test_snapshots_draw_the_papers_joints():
    """Each snapshot has the plate ends L_i (eq. (1)) and the sliders at (c_i, 0) (eq. (2), (M.42))."""
    mech = preset("harada2011_3d4m")
    poses = [(0.0, 0.08, -0.35), (0.03, 0.09, -0.2)]
    qs = [inverse_kinematics(mech, p).q for p in poses]
    ax = plot_skeletons(mech, qs, title="two poses")
    drawn = _points(ax)
    for pose in poses:
        expected = [pair_position(pose, i, RT) for i in (1, 3)]
        expected += [(c, 0.0) for c in slider_positions(pose, L, RT, (1, 2, 3, 4))]
        for point in expected:
            assert np.min(np.linalg.norm(drawn - point, axis=1)) < 1e-9
    assert ax.get_title() == "two poses" and ax.get_xlabel() == "x [m]"
    squares = np.array([p for line in ax.get_lines() if line.get_marker() == "s" for p in line.get_xydata()])
    expected = [(c, 0.0) for pose in poses for c in slider_positions(pose, L, RT, (1, 2, 3, 4))]
    np.testing.assert_allclose(np.sort(squares[:, 0]), np.sort([p[0] for p in expected]), atol=1e-9)
    np.testing.assert_allclose(squares[:, 1], 0.0, atol=1e-12)


def test_later_snapshots_are_darker():
    """Colours run from light grey (first configuration) to black (last)."""
    mech = preset("harada2011_3d4m")
    ax = plot_skeletons(mech, [mech.q_ref, mech.q_ref, mech.q_ref])
    links = [line for line in ax.get_lines() if line.get_linewidth() < 5]  # segments, squares; not rails
    shades = sorted({float(line.get_color()) for line in links}, reverse=True)
    assert shades == pytest.approx([0.75, 0.375, 0.0])


@pytest.mark.parametrize(
    ("qs", "plane", "message"),
    [
        ([], "xy", "qs is empty"),
        ([[0.0, 1.0]], "xy", "qs[0] must have shape"),
        ([np.full(9, np.nan)], "xy", "qs[0] has non-finite entries"),
        (None, "xw", "plane 'xw' is not one of ['xy', 'xz', 'yz']"),
    ],
)
def test_bad_input_is_refused(qs, plane, message):
    """Empty, wrong-sized or non-finite configurations and unknown planes raise InvalidInput."""
    mech = preset("harada2011_3d4m")
    with pytest.raises(InvalidInput, match=re.escape(message)):
        plot_skeletons(mech, [mech.q_ref] if qs is None else qs, plane=plane)


def test_rails_are_drawn_once_on_the_base_along_each_stroke():
    """3D4M: one wide band per slider over three snapshots, from lower to upper limit along x at y = 0."""
    mech = preset("harada2011_3d4m")
    ax = plot_skeletons(mech, [mech.q_ref, mech.q_ref, mech.q_ref])
    bands = [line.get_xydata() for line in ax.get_lines() if line.get_linewidth() >= 5]
    assert len(bands) == len(mech.actuators)
    for band, act in zip(bands, mech.actuators, strict=True):
        k = mech.model.joints[mech.model.getJointId(act.joint)].idx_q
        lower, upper = mech.model.lowerPositionLimit[k], mech.model.upperPositionLimit[k]
        np.testing.assert_allclose(sorted(band[:, 0]), [lower, upper], atol=1e-12)  # the slider x is q
        np.testing.assert_allclose(band[:, 1], 0.0, atol=1e-12)


def test_platform_outline_closes_through_the_attachment_points():
    """6-PSS, projected on xy: a closed outline whose corners are the six platform closure frames."""
    import pinocchio as pin

    mech = preset("zhao2011_6pss")
    ax = plot_skeletons(mech, mech.q_ref)
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.q_ref)
    corners = np.array(
        [data.oMf[mech.model.getFrameId(f"platform_p{k}")].translation[:2] for k in range(2, 8)]
    )
    lines = [line for line in ax.get_lines() if line.get_linestyle() != "None"]  # not the squares
    rings = [line.get_xydata() for line in lines if len(line.get_xydata()) == 7]
    assert len(rings) == 1
    ring = rings[0]
    np.testing.assert_allclose(ring[0], ring[-1], atol=1e-15)  # closed
    np.testing.assert_allclose(np.sort(ring[:-1], axis=0), np.sort(corners, axis=0), atol=1e-9)


def test_no_rail_without_a_finite_stroke():
    """A slider at Pinocchio's default limits (+-max double) has no rail; an inclined one spans its limits."""
    import pinocchio as pin

    from plm_pin.viz.skeleton import prismatic_rails

    model = pin.Model()
    model.addJoint(0, pin.JointModelPX(), pin.SE3.Identity(), "free_slider")
    axis = np.array([0.6, 0.8, 0.0])
    placement = pin.SE3(np.eye(3), np.array([0.1, 0.2, 0.3]))
    model.addJoint(
        0,
        pin.JointModelPrismaticUnaligned(axis),
        placement,
        "inclined",
        np.zeros(1),
        np.zeros(1),
        np.array([-0.5]),
        np.array([1.5]),
    )
    rails = prismatic_rails(model)
    assert [r.joint for r in rails] == ["inclined"]
    np.testing.assert_allclose(rails[0].start, placement.translation - 0.5 * axis, atol=1e-15)
    np.testing.assert_allclose(rails[0].end, placement.translation + 1.5 * axis, atol=1e-15)
    assert rails[0].length == pytest.approx(2.0, abs=1e-15)
