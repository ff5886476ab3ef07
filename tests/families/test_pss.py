"""Zhao 2011 8-PSS and 6-PSS presets (plm_pin/families/pss) against the paper's tables and equations."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from analyses._zhao2011_paper import zhao2011_trajectory
from plm_pin.description import write_description
from plm_pin.kinematics import closed_chain_jacobians
from plm_pin.models import PRESETS
from tests.conftest import preset
from tests.families.conftest import body_inertia

# Zhao 2011, transcribed here again (not imported from plm_pin) so the model is checked
# against the paper rather than against itself.
TABLE1_B = np.array(  # guide points B_i [m], columns 1..8 of Table 1
    [
        [0.4, 0.4, -0.4, -0.4, 0.4, -0.4, -2.0, -2.0],
        [-0.4, 0.4, 0.4, -0.4, -2.0, -2.0, -0.4, 0.4],
        [0.0, 0.0, 0.0, 0.0, 1.5, 1.5, 1.5, 1.5],
    ]
).T  # (8, 3)
TABLE2_A = np.array(  # platform joints a_i in O'-uvw [m], columns 1..8 of Table 2
    [
        [0.4, 0.4, -0.4, -0.4, 0.4, -0.4, -0.681, -0.681],
        [-0.4, 0.4, 0.4, -0.4, -0.681, -0.681, -0.4, 0.4],
        [-0.166, -0.166, -0.166, -0.166, -0.0375, -0.0375, -0.0375, -0.0375],
    ]
).T  # (8, 3)
# lead screws 1-4 "vertical to the ground", 5-6 and 7-8 "parallel with the ground", orthogonal
GUIDE_E = np.array([[0, 0, 1]] * 4 + [[0, 1, 0]] * 2 + [[1, 0, 0]] * 2, dtype=float)  # (8, 3)
TABLE3_L = 1.0  # strut length [m], all legs
TABLE4_STRUT, TABLE4_SLIDER = 20.0, 50.0  # [kg]
PLATFORM_MASS, PLATFORM_I = 200.0, np.diag([17.333, 17.333, 33.333])  # section "Simulation"
STRUT_I = np.diag([1.279, 1.279, 0.005])  # section "Simulation", strut frame, z along the strut
# the tree's strut: transverse moments as printed, axial 0 (an S-S strut's spin is idle, never driven)
TREE_STRUT_I = np.diag([STRUT_I[0, 0], STRUT_I[1, 1], 0.0])
ARMATURE = (2 * math.pi / 0.05) ** 2 * (10.5e-4 + 248e-4)  # eq. (19): lead 0.05 m/rev, I_L + I_C + I_M

LEGS = {"zhao2011_8pss": (1, 2, 3, 4, 5, 6, 7, 8), "zhao2011_6pss": (2, 3, 4, 5, 6, 7)}
HOME = np.array([0.0, 0.0, 1.744, 0.0, 0.0, 0.0])
T_EQ35 = math.sqrt(2 * math.pi * 0.2 / 9.8)  # eq. (35): T = sqrt(2 pi S / a_max) [s]


def _rot(phi):
    """R = Rz(phi_z) Ry(phi_y) Rx(phi_x): rotations about the fixed x, then y, then z axes."""
    (cx, cy, cz), (sx, sy, sz) = np.cos(phi), np.sin(phi)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def _eq35(t):
    """Platform pose of eq. (35) at time t [s]."""
    u = t / T_EQ35
    x0 = np.array([-0.1, -0.1, 1.644, -0.1, -0.1, -0.1])
    return x0 + 0.2 * (u - np.sin(2 * np.pi * u) / (2 * np.pi))


def _strut_length_ik(pose, legs):
    """Slider q_i from |p + R a_i - B_i - q_i e_i| = l_i, the root below the platform joint."""
    R = _rot(pose[3:])
    out = {}
    for i in legs:
        d = pose[:3] + R @ TABLE2_A[i - 1] - TABLE1_B[i - 1]
        s = GUIDE_E[i - 1] @ d
        out[i] = s - math.sqrt(TABLE3_L**2 - d @ d + s * s)
    return out


def _jacobian_eq6a(pose, legs):
    """Eq. (6a): row i = [w_i^T, (a_i x w_i)^T] / (w_i^T e_i), with a_i = R a_i' (world)."""
    R = _rot(pose[3:])
    q = _strut_length_ik(pose, legs)
    rows = []
    for i in legs:
        a = R @ TABLE2_A[i - 1]
        e = GUIDE_E[i - 1]
        w = (pose[:3] + a - TABLE1_B[i - 1] - q[i] * e) / TABLE3_L
        rows.append(np.r_[w, np.cross(a, w)] / (w @ e))
    return np.array(rows)  # (n_legs, 6)


def _placements(mech, q):
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    return data


@pytest.mark.parametrize("name", sorted(LEGS))
def test_masses_and_inertias_match_tables_3_4_and_the_text(name):
    """Sliders 50 kg; struts 20 kg, 1.279 transverse, 0 axial (idle spin) at l/2; platform 200 kg, 17.333.."""
    mech = preset(name)
    for i in LEGS[name]:
        assert body_inertia(mech, f"slider{i}").mass == pytest.approx(TABLE4_SLIDER, abs=1e-15)
        assert body_inertia(mech, f"u{i}a").mass == 0.0  # the universal joint's cross is massless
        strut = body_inertia(mech, f"u{i}b")
        assert strut.mass == pytest.approx(TABLE4_STRUT, abs=1e-15)
        np.testing.assert_allclose(strut.lever, [0.0, 0.0, TABLE3_L / 2], atol=1e-15)
        np.testing.assert_allclose(strut.inertia, TREE_STRUT_I, atol=1e-15)
    platform = body_inertia(mech, "platform_floating")
    assert platform.mass == pytest.approx(PLATFORM_MASS, abs=1e-15)
    np.testing.assert_allclose(platform.lever, 0.0, atol=1e-15)
    np.testing.assert_allclose(platform.inertia, PLATFORM_I, atol=1e-15)
    total = TABLE4_SLIDER * len(LEGS[name]) + TABLE4_STRUT * len(LEGS[name]) + PLATFORM_MASS
    assert sum(body.mass for body in mech.model.inertias) == pytest.approx(total, abs=1e-12)


@pytest.mark.parametrize("name", sorted(LEGS))
def test_slider_armature_is_the_reflected_screw_and_rotor_inertia(name):
    """Armature = (2 pi / p)^2 (I_L + I_C + I_M) on each slider (eqs. (5), (18)-(19)), zero elsewhere."""
    mech = preset(name)
    # (2 pi / 0.05)^2 = 15791.3670 rad^2/m^2; x (10.5e-4 + 248e-4 = 0.02585 kg m^2) = 408.2068380 kg
    expected = 408.2068380
    sliders = [mech.model.joints[mech.model.getJointId(f"slider{i}")].idx_v for i in LEGS[name]]
    np.testing.assert_allclose(mech.model.armature[sliders], expected, atol=1e-6)
    others = np.setdiff1d(np.arange(mech.nv), sliders)
    np.testing.assert_array_equal(mech.model.armature[others], 0.0)
    assert [a.lead for a in mech.actuators] == [0.05] * len(LEGS[name])


@pytest.mark.parametrize("name", sorted(LEGS))
def test_slider_guides_are_table_1_points_along_the_stated_axes(name):
    """Slider i moves from B_i (Table 1) along +z (1-4), +y (5-6) or +x (7-8), read from the model."""
    mech = preset(name)
    data = mech.model.createData()
    pin.computeJointJacobians(mech.model, data, mech.q_ref)
    for i in LEGS[name]:
        jid = mech.model.getJointId(f"slider{i}")
        assert mech.model.parents[jid] == 0  # mounted on the base
        np.testing.assert_allclose(mech.model.jointPlacements[jid].translation, TABLE1_B[i - 1], atol=1e-15)
        J = pin.getJointJacobian(mech.model, data, jid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        column = J[:, mech.model.joints[jid].idx_v]
        np.testing.assert_allclose(column, np.r_[GUIDE_E[i - 1], 0.0, 0.0, 0.0], atol=1e-15)


@pytest.mark.parametrize("name", sorted(LEGS))
def test_struts_have_table_3_length_at_the_reference(name):
    """|p_tip - p_slider| = l_i = 1 m at q_ref, and each platform joint sits at Table 2's a_i."""
    mech = preset(name)
    data = _placements(mech, mech.q_ref)
    platform = data.oMi[mech.model.getJointId("platform_floating")]
    for i in LEGS[name]:
        tip = data.oMf[mech.model.getFrameId(f"strut{i}_tip")].translation
        slider = data.oMi[mech.model.getJointId(f"slider{i}")].translation
        assert np.linalg.norm(tip - slider) == pytest.approx(TABLE3_L, abs=1e-12)
        joint = data.oMf[mech.model.getFrameId(f"platform_p{i}")]
        np.testing.assert_allclose(platform.actInv(joint).translation, TABLE2_A[i - 1], atol=1e-15)


@pytest.mark.parametrize(("name", "redundancy"), [("zhao2011_8pss", 2), ("zhao2011_6pss", 0)])
def test_mobility_six_and_actuation_redundancy(name, redundancy):
    """Free-flyer + 3 DOF per leg, 3 closure rows per leg: mobility 6, redundancy 2 (8-PSS) or 0."""
    mech = preset(name)
    n = len(LEGS[name])
    assert (mech.nq, mech.nv, mech.n_closure_rows) == (7 + 3 * n, 6 + 3 * n, 3 * n)
    assert (mech.mobility, mech.redundancy) == (6, redundancy)
    assert [a.joint for a in mech.actuators] == [f"slider{i}" for i in LEGS[name]]


@pytest.mark.parametrize("name", sorted(LEGS))
def test_reference_is_closed_at_the_home_pose(name):
    """The closed-form reference closes every loop to 1e-12 with the platform at (0, 0, 1.744 m), level."""
    mech = preset(name)
    assert np.max(np.abs(mech.closure_residual(mech.reference_guess()))) <= 1e-12
    assert np.max(np.abs(mech.closure_residual(mech.q_ref))) <= 1e-12
    frame = _placements(mech, mech.q_ref).oMf[mech.task_frame_id]
    np.testing.assert_allclose(frame.translation, HOME[:3], atol=1e-12)
    np.testing.assert_allclose(frame.rotation, np.eye(3), atol=1e-12)
    q = _strut_length_ik(HOME, LEGS[name])
    np.testing.assert_allclose(mech.actuator_positions(mech.q_ref), [q[i] for i in LEGS[name]], atol=1e-12)


def test_builder_closes_the_loops_at_a_tilted_home_pose(tmp_path):
    """Built at the eq. (35) start pose (all angles -0.1 rad), the closed-form reference is closed."""
    start = _eq35(0.0)
    robot, sidecar = PRESETS["zhao2011_8pss"].builder(
        **{**PRESETS["zhao2011_8pss"].parameters, "home_pose": tuple(start)}, name="tilted"
    )
    write_description(robot, sidecar, tmp_path, "tilted")
    mech = plm_pin.load(tmp_path / "tilted.urdf")
    q = mech.reference_guess()
    assert np.max(np.abs(mech.closure_residual(q))) <= 1e-12
    frame = _placements(mech, q).oMf[mech.task_frame_id]
    np.testing.assert_allclose(frame.translation, start[:3], atol=1e-15)
    np.testing.assert_allclose(frame.rotation, _rot(start[3:]), atol=1e-15)
    sliders = _strut_length_ik(start, range(1, 9))
    np.testing.assert_allclose(mech.actuator_positions(q), [sliders[i] for i in range(1, 9)], atol=1e-12)


@pytest.mark.parametrize("name", sorted(LEGS))
def test_sliders_from_the_strut_length_equation_place_the_platform_on_eq_35(name):
    """Sliders fixed at the strut-length solution of an eq. (35) pose put the platform there to 1e-9."""
    mech = preset(name)
    legs = LEGS[name]
    fid = mech.task_frame_id
    for end in (0.0, T_EQ35):  # from the midpoint (home) to each end, each step from the last
        q = mech.q_ref
        for t in np.linspace(T_EQ35 / 2, end, 6)[1:]:
            pose = _eq35(t)
            sliders = _strut_length_ik(pose, legs)
            q = mech.assemble(q, fixed={f"slider{i}": sliders[i] for i in legs}).q
            frame = _placements(mech, q).oMf[fid]
            np.testing.assert_allclose(frame.translation, pose[:3], atol=1e-9)
            assert np.linalg.norm(pin.log3(_rot(pose[3:]).T @ frame.rotation)) <= 1e-9
            np.testing.assert_allclose(mech.actuator_positions(q), [sliders[i] for i in legs], atol=1e-15)


def test_eq_6a_jacobian_has_rank_6_and_the_6pss_subset_is_regular():
    """At home J of eq. (6a) has rank 6; legs 2-7 equal the 6-PSS preset's J_ce; legs 1-6 are singular."""
    J = _jacobian_eq6a(HOME, range(1, 9))
    s = np.linalg.svd(J, compute_uv=False)
    assert np.sum(s > 1e-9 * s[0]) == 6
    J6 = _jacobian_eq6a(HOME, (2, 3, 4, 5, 6, 7))
    J_ce = closed_chain_jacobians(preset("zhao2011_6pss"), preset("zhao2011_6pss").q_ref).J_ce
    np.testing.assert_allclose(J_ce, J6, atol=1e-12)  # eq. (6a) vs the closed-chain null space
    s6 = np.linalg.svd(J6, compute_uv=False)
    assert s6[0] / s6[-1] < 5.0
    s_bad = np.linalg.svd(_jacobian_eq6a(HOME, (1, 2, 3, 4, 5, 6)), compute_uv=False)
    assert s_bad[-1] < 1e-12 * s_bad[0]  # four vertical legs span only z, rx, ry


@pytest.mark.parametrize("name", sorted(LEGS))
@pytest.mark.parametrize("t", [0.0, 0.3 * T_EQ35])
def test_closure_null_space_maps_platform_twist_to_sliders_by_eq_6a(name, t):
    """Every closed-chain velocity satisfies qdot = J [v; omega] of eq. (6a) (twist at O', world axes)."""
    mech = preset(name)
    legs = LEGS[name]
    pose = _eq35(t)
    sliders = _strut_length_ik(pose, legs)
    q = mech.assemble(mech.q_ref, fixed={f"slider{i}": sliders[i] for i in legs}).q
    _, s, Vt = np.linalg.svd(mech.closure_jacobian(q))
    N = Vt[np.sum(s > 1e-9 * s[0]) :].T  # (nv, 6): closed-chain velocities
    assert N.shape[1] == 6
    ff = mech.model.joints[mech.model.getJointId("platform_floating")].idx_v
    R = _rot(pose[3:])
    twist = np.vstack([R @ N[ff : ff + 3], R @ N[ff + 3 : ff + 6]])  # free-flyer: local -> world axes
    np.testing.assert_allclose(N[mech.actuated_v_indices], _jacobian_eq6a(pose, legs) @ twist, atol=1e-10)


def test_trajectory_helper_follows_eq_35():
    """zhao2011_trajectory: X0 at t = 0, home at T/2, X0 + 0.2 at T, rest to rest, peak a_max = 9.8."""
    assert T_EQ35 == pytest.approx(0.358090, abs=1e-6)
    for t in (0.0, 0.2 * T_EQ35, T_EQ35 / 2, T_EQ35):
        np.testing.assert_allclose(zhao2011_trajectory(t)[0], _eq35(t), atol=1e-15)
    np.testing.assert_allclose(zhao2011_trajectory(T_EQ35 / 2)[0], HOME, atol=1e-15)
    for t in (0.0, T_EQ35):
        _, rate, acc = zhao2011_trajectory(t)
        np.testing.assert_allclose(rate, 0.0, atol=1e-15)
        np.testing.assert_allclose(acc, 0.0, atol=1e-12)
    np.testing.assert_allclose(zhao2011_trajectory(T_EQ35 / 2)[1], 2 * 0.2 / T_EQ35, rtol=1e-15)
    np.testing.assert_allclose(zhao2011_trajectory(T_EQ35 / 4)[2], 9.8, rtol=1e-15)


def _paper_kinetic_energy(mech, q, v, legs):
    """Kinetic energy of the paper's S-S legs from the platform twist and slider rates alone [J].

    Eqs. (6b), (9): strut i has its centre at (C_i + A_i) / 2 and the angular velocity
    w_i x (v_A - v_C) / l, normal to it; sliders carry the reflected armature of eq. (19).
    """
    data = _placements(mech, q)
    j = mech.model.joints[mech.model.getJointId("platform_floating")]
    M = data.oMi[mech.model.getJointId("platform_floating")]
    R, p = M.rotation, M.translation
    v_p, w_p = R @ v[j.idx_v : j.idx_v + 3], R @ v[j.idx_v + 3 : j.idx_v + 6]  # free-flyer: local -> world
    energy = 0.5 * PLATFORM_MASS * v_p @ v_p + 0.5 * w_p @ (R @ PLATFORM_I @ R.T) @ w_p
    for i in legs:
        slider = mech.model.joints[mech.model.getJointId(f"slider{i}")]
        qi, qdi = q[slider.idx_q], v[slider.idx_v]
        C, v_C = TABLE1_B[i - 1] + qi * GUIDE_E[i - 1], qdi * GUIDE_E[i - 1]
        r = R @ TABLE2_A[i - 1]
        A, v_A = p + r, v_p + np.cross(w_p, r)
        w = (A - C) / TABLE3_L
        omega = np.cross(w, v_A - v_C) / TABLE3_L
        v_G = 0.5 * (v_C + v_A)
        energy += 0.5 * (TABLE4_SLIDER + ARMATURE) * qdi**2
        energy += 0.5 * TABLE4_STRUT * v_G @ v_G + 0.5 * STRUT_I[0, 0] * omega @ omega
    return energy


@pytest.mark.parametrize("name", sorted(LEGS))
@pytest.mark.parametrize("t", [0.0, 0.3 * T_EQ35, 0.8 * T_EQ35])
def test_kinetic_energy_is_the_paper_s_s_model_exactly(name, t, rng):
    """1/2 v^T M v of the tree equals the paper's S-S energy (strut omega normal to it) for any feasible v.

    The universal joint slaves each strut's spin to its swing; with the strut's axial moment at
    0 that spin costs nothing, as in an S-S strut that transmits no axial torque. With the printed
    0.005 kg m^2 the energy would exceed the paper's by 1/2 0.005 (omega . w)^2 per strut.
    """
    mech = preset(name)
    legs = LEGS[name]
    sliders = _strut_length_ik(_eq35(t), legs)
    q = mech.assemble(mech.q_ref, fixed={f"slider{i}": sliders[i] for i in legs}).q
    N = closed_chain_jacobians(mech, q).N  # (nv, 6) feasible velocities
    M = pin.crba(mech.model, mech.model.createData(), q)  # armature included
    spins = []
    for _ in range(3):
        v = N @ rng.normal(size=6)
        tree = 0.5 * v @ M @ v
        assert tree == pytest.approx(_paper_kinetic_energy(mech, q, v, legs), rel=1e-12)
        data = mech.model.createData()
        pin.forwardKinematics(mech.model, data, q, v)
        for i in legs:
            jid = mech.model.getJointId(f"u{i}b")
            spins.append(abs(data.v[jid].angular[2]))  # strut frame: z along the strut
    assert 0.5 * STRUT_I[2, 2] * max(spins) ** 2 > 1e-9 * tree  # the spin the axial 0.005 would cost is seen


def test_builder_refuses_unequal_transverse_strut_moments():
    """Dropping the idle spin is exact only for an axisymmetric strut: unequal transverse moments refused."""
    params = dict(PRESETS["zhao2011_8pss"].parameters)
    params["strut_inertia"] = (1.279, 1.0, 0.005)
    with pytest.raises(
        plm_pin.InvalidInput, match=r"^strut_inertia \(1\.279, 1\.0, 0\.005\): the transverse moments"
    ):
        PRESETS["zhao2011_8pss"].builder(name="zhao", **params)
