"""Manipulability: Harada 2011 eq. (13) with J_ce = J_c^-1 J_e of eq. (4), singular cases, basis choice."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from analyses import _harada2011_paper as paper
from plm_pin import build_mechanism
from plm_pin.exceptions import InvalidInput, SingularConfiguration
from plm_pin.kinematics import ClosedChainJacobians, closed_chain_jacobians, inverse_kinematics
from plm_pin.workspace import manipulability, manipulability_at, manipulability_unit
from plm_pin.workspace.manipulability import manipulability_from_jacobians
from tests.conftest import preset, with_rotated_null_basis

L, RT = 0.140, 0.05  # Harada 2011 Table 1
LEGS = {"harada2011_3d4m": (1, 2, 3, 4), "harada2011_3d3m": (1, 2, 4)}
POSES = [
    (0.0, 0.08, math.radians(-20.0)),
    (0.02, 0.06, 0.1),
    (-0.03, 0.1, -0.3),
    (0.05, 0.05, 0.25),
    (-0.01, 0.09, 0.4),
]


@pytest.mark.parametrize("name", sorted(LEGS))
@pytest.mark.parametrize("pose", POSES)
def test_w_is_sqrt_det_of_paper_J_ce(name, pose):
    """Manipulability w = sqrt(det(J_ce^T J_ce)), J_ce = J_c^-1 J_e from eqs. (1)-(4) at the IK solution."""
    mech = preset(name)
    legs = LEGS[name]
    sol = inverse_kinematics(mech, pose, mech.q_ref)
    c = paper.slider_positions(pose, L, RT, legs)
    np.testing.assert_allclose(sol.actuators, c, atol=1e-10)  # the paper's working mode (M.5)
    J = paper.J_ce(pose, c, L, RT, legs)
    result = manipulability(mech, sol.q)
    assert result.J_ce is not None
    np.testing.assert_allclose(result.J_ce, J, rtol=1e-9, atol=1e-11)
    assert result.w == pytest.approx(math.sqrt(np.linalg.det(J.T @ J)), rel=1e-9)
    assert result.condition_number == pytest.approx(np.linalg.cond(J), rel=1e-8)
    assert not result.inverse_singular


def test_non_redundant_w_is_abs_det():
    """For the 3D3M, J_ce is square and w = |det J_ce| (eq. (13) with eq. (5))."""
    mech = preset("harada2011_3d3m")
    pose = (0.01, 0.07, 0.2)
    result = manipulability_at(mech, pose, mech.q_ref)
    J = paper.J_ce(pose, paper.slider_positions(pose, L, RT, (1, 2, 4)), L, RT, (1, 2, 4))
    assert result.w == pytest.approx(abs(np.linalg.det(J)), rel=1e-9)


def test_w_vanishes_at_the_type4_locus():
    """At eq. (11.4) (theta = -acos(sqrt(((l + rt)^2 - y^2)) / (l + rt))) the 3D3M's w is zero."""
    mech = preset("harada2011_3d3m")
    y = 0.06
    theta = -math.acos(math.sqrt(((L + RT) ** 2 - y**2) / (L + RT) ** 2))
    regular = manipulability_at(mech, (0.0, y, 0.0), mech.q_ref)
    singular = manipulability_at(mech, (0.0, y, theta), mech.q_ref)
    assert singular.w <= 1e-12 * regular.w
    assert singular.condition_number > 1e10
    assert singular.inverse_condition < 1e-10


def _fold_configuration():
    """3D3M with both plate pairs at height l (rods vertical): an inverse singularity (eq. (9))."""
    mech = preset("harada2011_3d3m")
    x, theta = 0.01, 0.0
    values = {
        "slider1": x - RT,
        "rod1_pivot": math.pi / 2,
        "plate_pivot": theta - math.pi / 2,
        "slider2": x - RT,
        "rod2_pivot": math.pi / 2,
        "slider4": x + RT,
        "rod4_pivot": math.pi / 2,
    }
    q = mech.neutral()
    for joint, value in values.items():
        q[mech.model.joints[mech.model.getJointId(joint)].idx_q] = value
    assert np.max(np.abs(mech.closure_residual(q))) < 1e-15
    return mech, q


def test_inverse_singularity_gives_infinite_w_or_raises():
    """With rods normal to the stator (z_i^T a = 0), w is inf and flagged, or SingularConfiguration."""
    mech, q = _fold_configuration()
    result = manipulability(mech, q)
    assert result.inverse_singular and result.J_ce is None
    assert math.isinf(result.w) and math.isinf(result.condition_number)
    assert np.all(np.isnan(result.singular_values))
    assert result.inverse_condition == 0.0
    with pytest.raises(SingularConfiguration, match=r"inverse-kinematics \(type 1\) singular"):
        manipulability(mech, q, raise_if_singular=True)


def test_w_and_condition_do_not_depend_on_the_null_space_basis(rng):
    """Replacing N by N Q (Q orthogonal, det -1) leaves w and the condition number unchanged."""
    mech = preset("harada2011_3d4m")
    jac = closed_chain_jacobians(mech, mech.q_ref)
    other = with_rotated_null_basis(mech, jac, rng)
    a, b = manipulability_from_jacobians(jac), manipulability_from_jacobians(other)
    assert b.w == pytest.approx(a.w, rel=1e-12)
    assert b.condition_number == pytest.approx(a.condition_number, rel=1e-10)


def test_task_size_must_equal_dof():
    """A task with fewer coordinates than DOF is refused with a message naming both."""
    jac = ClosedChainJacobians(
        np.zeros((3, 4)), np.zeros((2, 4)), np.eye(4)[:, :3], np.ones(3), np.ones((2, 3)), np.eye(3)
    )
    with pytest.raises(InvalidInput, match="the task has 2 coordinates but the mechanism has 3 DOF"):
        manipulability_from_jacobians(jac)


def test_to_dict_is_json():
    """Regular and singular results serialise to JSON (inf as a string)."""
    mech = preset("harada2011_3d4m")
    regular = manipulability(mech, mech.q_ref).to_dict()
    assert json.loads(json.dumps(regular))["w"] == regular["w"]
    mech3, q = _fold_configuration()
    singular = json.loads(json.dumps(manipulability(mech3, q).to_dict()))
    assert singular["w"] == "inf" and singular["J_ce"] is None


@pytest.mark.parametrize(
    ("name", "expected", "scaled"),
    [
        (
            "harada2011_3d4m",
            "m/rad",
            {
                "rod_lengths": (0.28,) * 4,
                "half_plate": 0.1,
                "reference_pose": (0.0, 0.16, math.radians(-20.0)),
            },
        ),
        ("fivebar", "rad^2/m^2", {"base": 0.4, "proximal": 0.3, "distal": 0.4, "tip": (0.04, 0.5)}),
        ("fourbar", "-", {"crank": 0.2, "coupler": 0.5, "rocker": 0.4, "ground": 0.6}),
    ],
)
def test_manipulability_unit_is_the_power_of_length_w_scales_with(name, expected, scaled):
    """The stated unit m^p rad^r is dimensional analysis: doubling every length multiplies w by 2^p."""
    mech = preset(name)
    unit_text = manipulability_unit(mech)
    assert unit_text == expected
    power = {"m/rad": 1, "rad^2/m^2": -2, "-": 0}[unit_text]
    big = build_mechanism(name, scaled)  # every length doubled, angles kept
    w, w_big = manipulability(mech, mech.q_ref).w, manipulability(big, big.q_ref).w
    assert w_big == pytest.approx(2.0**power * w, rel=1e-6)
