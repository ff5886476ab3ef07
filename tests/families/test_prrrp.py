"""Harada 2-PRRRP presets read back from the built Pinocchio model against the papers' tables."""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import preset
from tests.families.conftest import body_inertia


def _frame_offset(mech, frame):
    return mech.model.frames[mech.model.getFrameId(frame)].placement.translation


@pytest.mark.parametrize("name", ["harada2011_3d4m", "harada2011_3d3m"])
def test_harada2011_masses_inertias_and_lengths_match_table_1(name):
    """Table 1 / (M.36): sliders 0.375 kg, rods 0.140 m 0.026 kg 9.84e-5, plate 0.100 m 0.132 kg 8.54e-4."""
    mech = preset(name)
    legs = (1, 2, 3, 4) if name.endswith("3d4m") else (1, 2, 4)
    for i in legs:
        assert body_inertia(mech, f"slider{i}").mass == pytest.approx(0.375, abs=1e-15)
        rod = body_inertia(mech, f"rod{i}_pivot")
        assert rod.mass == pytest.approx(0.026, abs=1e-15)
        assert rod.inertia[2, 2] == pytest.approx(9.84e-5, rel=1e-12)
        np.testing.assert_allclose(rod.lever, [0.070, 0.0, 0.0], atol=1e-15)
    for i in legs[1:]:
        np.testing.assert_allclose(_frame_offset(mech, f"rod{i}_tip"), [0.140, 0.0, 0.0], atol=1e-15)
    plate_joint = mech.model.getJointId("plate_pivot")
    np.testing.assert_allclose(
        mech.model.jointPlacements[plate_joint].translation, [0.140, 0.0, 0.0], atol=1e-15
    )
    plate = mech.model.inertias[plate_joint]
    assert plate.mass == pytest.approx(0.132, abs=1e-15)
    assert plate.inertia[2, 2] == pytest.approx(8.54e-4, rel=1e-12)
    length = _frame_offset(mech, "plate_right") - _frame_offset(mech, "plate_left")
    np.testing.assert_allclose(length, [0.100, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(plate.lever, [0.050, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(mech.model.gravity.linear, [0.0, -9.8, 0.0])


def test_harada2011_3d3m_has_no_third_leg():
    """The 3D3M is the 3D4M without slider 3 and rod 3 (eq. (5))."""
    mech = preset("harada2011_3d3m")
    assert not mech.model.existJointName("slider3")
    assert not mech.model.existJointName("rod3_pivot")
    assert [a.joint for a in mech.actuators] == ["slider1", "slider2", "slider4"]


def test_harada2015_rod_lengths_are_the_prototypes():
    """Fig. 2 of the 2015 paper: l1 = l4 = 0.240 m, l2 = l3 = 0.170 m."""
    mech = preset("harada2015_asymmetric")
    lengths = [
        mech.model.jointPlacements[mech.model.getJointId("plate_pivot")].translation[0],
        *(_frame_offset(mech, f"rod{i}_tip")[0] for i in (2, 3, 4)),
    ]
    np.testing.assert_allclose(lengths, [0.240, 0.170, 0.170, 0.240], atol=1e-15)


@pytest.mark.parametrize("name", ["harada2011_3d4m", "harada2015_asymmetric"])
def test_reference_working_modes_follow_the_code_m5(name):
    """Slider 1 sits left of the left pair, slider 2 right of it, and so on: modes (- + - +)."""
    mech = preset(name)
    data = mech.model.createData()
    import pinocchio as pin

    pin.framesForwardKinematics(mech.model, data, mech.q_ref)
    left = data.oMf[mech.model.getFrameId("plate_left")].translation[0]
    right = data.oMf[mech.model.getFrameId("plate_right")].translation[0]
    c = mech.actuator_positions(mech.q_ref)
    assert c[0] < left < c[1]
    assert c[2] < right < c[3]
