"""Enferadi 2017 star-triangle preset read back from the built Pinocchio model against section 6."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.models import PRESETS
from tests.conftest import preset, star_triangle_eq5
from tests.families.conftest import body_inertia

NAME = "enferadi2017_star_triangle"
A = 0.5  # side of the base, section 6 [m]
SQ3 = math.sqrt(3.0)


def _star_pose(mech, q):
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    M = data.oMf[mech.model.getFrameId("star")]
    return np.array([M.translation[0], M.translation[1], math.atan2(M.rotation[1, 0], M.rotation[0, 0])])


def test_masses_and_inertias_match_section_6():
    """Sliders m_a = 2 kg, intermediate links m_il = 3 kg and I_il = 37.5, star m_p = 2 kg and I_p = 25."""
    mech = preset(NAME)
    for i in (1, 2, 3):
        assert body_inertia(mech, f"slider{i}").mass == pytest.approx(2.0, abs=1e-15)
    # il1 hangs on pivot1, il2 and il3 on arm2 and arm3; the star on arm1
    for joint in ("pivot1", "arm2", "arm3"):
        il = body_inertia(mech, joint)
        assert il.mass == pytest.approx(3.0, abs=1e-15)
        assert il.inertia[2, 2] == pytest.approx(37.5, rel=1e-14)
        np.testing.assert_allclose(il.lever, 0.0, atol=1e-15)
    star = body_inertia(mech, "arm1")
    assert star.mass == pytest.approx(2.0, abs=1e-15)
    assert star.inertia[2, 2] == pytest.approx(25.0, rel=1e-14)
    np.testing.assert_allclose(star.lever, 0.0, atol=1e-15)


def test_kinetic_energy_is_the_lagrangian_22():
    """At the reference, T = 1/2 (m_a + m_il) |q'|^2 + 1/2 m_p |c'|^2 + 1/2 (I_p + 3 I_il) phi'^2."""
    mech = preset(NAME)
    q = mech.q_ref
    v = np.linalg.svd(mech.closure_jacobian(q))[2][-1]  # a velocity in the closure null space
    v = v / np.linalg.norm(v)
    assert np.max(np.abs(mech.closure_jacobian(q) @ v)) <= 1e-12
    T = 0.5 * v @ pin.crba(mech.model, mech.model.createData(), q) @ v
    h = 1e-7
    qp, qm = pin.integrate(mech.model, q, h * v), pin.integrate(mech.model, q, -h * v)
    qd = (mech.actuator_positions(qp) - mech.actuator_positions(qm)) / (2 * h)
    Xd = (_star_pose(mech, qp) - _star_pose(mech, qm)) / (2 * h)
    expected = 0.5 * 5.0 * qd @ qd + 0.5 * 2.0 * Xd[:2] @ Xd[:2] + 0.5 * (25.0 + 3 * 37.5) * Xd[2] ** 2
    assert T == pytest.approx(expected, rel=1e-7)


def test_rails_are_the_sides_of_the_0_5_m_triangle():
    """Slider joints start at V1, V2, V3 and run along V1->V2, V2->V3, V3->V1 (side 0.5 m)."""
    mech = preset(NAME)
    V = [np.array([0.0, 0.0, 0.0]), np.array([A / 2, A * SQ3 / 2, 0.0]), np.array([A, 0.0, 0.0])]
    for i in range(3):
        jid = mech.model.getJointId(f"slider{i + 1}")
        M = mech.model.jointPlacements[jid]
        joint = mech.model.joints[jid]
        assert joint.shortname() == "JointModelPX"
        start, end = V[i], V[(i + 1) % 3]
        np.testing.assert_allclose(M.translation, start, atol=1e-15)
        np.testing.assert_allclose(M.rotation[:, 0], (end - start) / A, atol=1e-15)
        assert mech.model.lowerPositionLimit[joint.idx_q] == 0.0
        assert mech.model.upperPositionLimit[joint.idx_q] == A


def test_sizes_closures_actuators_task_and_gravity():
    """Tree A: 7 coordinates, two point closures at A_2, A_3, sliders driven, task [x, y, rz], g along -z."""
    mech = preset(NAME)
    assert (mech.nq, mech.nv) == (7, 7)
    assert [(c.name, c.frames, c.type) for c in mech.sidecar.closures] == [
        ("il2_carriage2", ("il2", "carriage2"), "point"),
        ("il3_carriage3", ("il3", "carriage3"), "point"),
    ]
    assert [a.joint for a in mech.actuators] == ["slider1", "slider2", "slider3"]
    assert all(a.limits is None for a in mech.actuators)
    assert mech.sidecar.task is not None
    assert (mech.sidecar.task.frame, mech.sidecar.task.dofs) == ("star", ("x", "y", "rz"))
    np.testing.assert_allclose(mech.model.gravity.linear, [0.0, 0.0, -9.81])


def test_mobility_3_and_no_redundancy():
    """The 3-PRP has 3 DOF and 3 actuators (non-redundant), as load() reports."""
    mech = plm_pin.load(NAME)
    assert (mech.mobility, mech.redundancy, mech.n_actuators) == (3, 0, 3)
    assert (PRESETS[NAME].dof, PRESETS[NAME].actuators) == (3, 3)


def test_reference_is_the_line_start_and_closes():
    """The reference closes to 1e-12 at the vertical line's start C = (a/2, a/2 + a/5), phi = pi/2."""
    mech = preset(NAME)
    assert np.max(np.abs(mech.closure_residual(mech.q_ref))) <= 1e-12
    assert np.max(np.abs(mech.closure_residual(mech.reference_guess()))) <= 1e-12
    np.testing.assert_allclose(_star_pose(mech, mech.q_ref), [0.25, 0.35, math.pi / 2], atol=1e-12)
    # at phi = pi/2: q1 = x/2 + sqrt(3) y/2, q2 = x/2 - sqrt(3) y/2 + a/2, q3 = a - x
    expected = [0.125 + SQ3 * 0.35 / 2, 0.125 - SQ3 * 0.35 / 2 + 0.25, 0.25]
    np.testing.assert_allclose(mech.actuator_positions(mech.q_ref), expected, atol=1e-15)


@pytest.mark.parametrize(
    "pose",
    [
        (0.25, 0.35, math.pi / 2),
        (0.3125, 0.25, math.pi / 2),
        (0.25, 0.15, math.pi / 2),
        (0.18, 0.1, math.pi / 2),
        (0.33, 0.2, math.pi / 2),
        (0.25, 0.2, math.pi / 2 + 0.2),
        (0.2, 0.15, 1.4),
    ],
)
def test_assembly_with_fixed_sliders_reaches_the_paper_pose(pose):
    """Fixing the sliders at the corrected eq. (5)'s values and assembling yields the commanded star pose."""
    mech = preset(NAME)
    q, _ = star_triangle_eq5(pose, A)  # corrected eq. (5)
    fixed = {f"slider{i + 1}": q[i] for i in range(3)}
    start = pin.integrate(mech.model, mech.q_ref, np.full(mech.nv, 0.01))
    asm = mech.assemble(start, fixed=fixed)
    assert asm.residual_norm <= 1e-12
    np.testing.assert_allclose(mech.actuator_positions(asm.q), q, atol=0.0)
    np.testing.assert_allclose(_star_pose(mech, asm.q), pose, atol=1e-10)


def test_builder_refuses_a_reference_outside_the_triangle():
    """A star centre beyond side 2 (rho_2 = (sqrt(3) (a - x) - y) / 2 < 0) is refused, naming the leg."""
    params = {**PRESETS[NAME].parameters, "reference_pose": (0.6, 0.1, math.pi / 2)}
    message = r"leg 2 has q = 0.4634 m \(stroke \[0, 0.5\]\) and rho = -0.1366 m \(must be >= 0\)"
    with pytest.raises(plm_pin.InvalidInput, match=message):
        PRESETS[NAME].builder(name="x", **params)


def test_inverse_kinematics_refuses_the_actuator_singularity():
    """At phi = 0 the star lines are parallel to their rails: the closed form has no solution."""
    from plm_pin.families.star_triangle import star_triangle_inverse_kinematics

    with pytest.raises(plm_pin.InvalidInput, match="sin phi = 0"):
        star_triangle_inverse_kinematics((0.25, 0.2, 0.0), A)
