"""Task-space dynamics against Harada 2011's closed forms, a hand derivation and pin.constraintDynamics.

The hand derivation below (any rod lengths, masses and working modes) is written from the
paper's set-up without plm_pin; it is shared with ``test_decoupling.py``.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

from plm_pin import ClosureNotSatisfied, InvalidInput, SingularConfiguration
from plm_pin.core.mechanism import Mechanism
from plm_pin.description.sidecar import TaskSpec
from plm_pin.dynamics import inverse_dynamics, task_trajectory
from plm_pin.dynamics.task_space import task_space_dynamics, task_units
from plm_pin.kinematics import closed_chain_jacobians
from plm_pin.models import PRESETS
from tests.conftest import preset, prrrp_paper_configuration

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

PRRRP = ("harada2011_3d4m", "harada2011_3d3m", "harada2015_asymmetric")

POSES = [(0.0, 0.08, 0.0), (0.012, 0.09, 0.25), (-0.03, 0.06, -0.35), (0.02, 0.11, 0.1)]
"""Plate poses (x [m], y [m], theta [rad]) inside the workspace of every 2-PRRRP preset."""


# ------------------------------------------------------------------ hand derivation
def lagrange_inertia_and_gravity(params: Mapping[str, Any], pose: Any) -> tuple[np.ndarray, np.ndarray]:
    r"""M(x) [kg, kg m, kg m^2] and G(x) [N, N m] of a 2-PRRRP in (x, y, theta), by hand.

    Harada 2011 section 5.2 set-up, any rod lengths, masses and working modes. Leg ``i``
    joins slider ``i`` (mass m_m, at c_i on the x axis) to the plate pair
    P = (x + s cos(theta), y + s sin(theta)), s = -r_t (legs 1, 2) or +r_t (legs 3, 4), with a
    uniform rod (length l, mass m_l, inertia I_l about its centre: (M.16), (M.21)). With
    d = sqrt(l^2 - P_y^2), k = P_y / d and sigma the sign of eq. (2) (c = P_x + sigma d):
    c_dot = P_x_dot - sigma k P_y_dot, phi_dot = -P_y_dot / (sigma d), and the rod centre moves at
    ((c_dot + P_x_dot) / 2, P_y_dot / 2). The leg's kinetic energy is 1/2 P_dot^T A P_dot with

    A = [[m_m + m_l, -sigma k (m_m + m_l / 2)],
         [-sigma k (m_m + m_l / 2), k^2 (m_m + m_l / 4) + m_l / 4 + I_l / d^2]],

    its potential energy m_l g P_y / 2. With J_P = dP/d(x, y, theta) and the plate's
    1/2 m_t |p_dot|^2 + 1/2 I_t theta_dot^2 + m_t g y ((M.22), (M.24)):
    M = diag(m_t, m_t, I_t) + sum J_P^T A J_P and G = (0, m_t g, 0) + sum (m_l g / 2) dP_y/dx.
    """
    _, y, theta = pose
    rt, mm, grav = params["half_plate"], params["slider_mass"], params["gravity"]
    M = np.diag([params["plate_mass"], params["plate_mass"], params["plate_inertia"]])
    G = np.array([0.0, params["plate_mass"] * grav, 0.0])
    for i in params.get("legs", (1, 2, 3, 4)):
        s = -rt if i in (1, 2) else rt
        sigma = params["working_modes"][i - 1]
        l, ml, Il = params["rod_lengths"][i - 1], params["rod_masses"][i - 1], params["rod_inertias"][i - 1]
        Py = y + s * math.sin(theta)
        d = math.sqrt(l * l - Py * Py)
        k = Py / d
        A = np.array(
            [
                [mm + ml, -sigma * k * (mm + ml / 2)],
                [-sigma * k * (mm + ml / 2), k * k * (mm + ml / 4) + ml / 4 + Il / d**2],
            ]
        )
        JP = np.array([[1.0, 0.0, -s * math.sin(theta)], [0.0, 1.0, s * math.cos(theta)]])
        M += JP.T @ A @ JP
        G += ml * grav / 2 * JP[1]
    return M, G


def lagrange_velocity_terms(
    params: Mapping[str, Any], pose: Any, xd: np.ndarray, eps: float = 1e-6
) -> np.ndarray:
    """Velocity terms M_dot xd - 1/2 d(xd^T M xd)/dx [N, N m] of eq. (25), by central differences of M(x)."""
    dM = []
    for k in range(3):
        step = np.zeros(3)
        step[k] = eps
        plus = lagrange_inertia_and_gravity(params, np.asarray(pose) + step)[0]
        minus = lagrange_inertia_and_gravity(params, np.asarray(pose) - step)[0]
        dM.append((plus - minus) / (2 * eps))
    M_dot = sum(dM[k] * xd[k] for k in range(3))
    return M_dot @ xd - 0.5 * np.array([xd @ dM[i] @ xd for i in range(3)])


def paper_configuration(name: str, pose: Any) -> np.ndarray:
    """Configuration of a 2-PRRRP preset at ``pose`` from the paper's eqs. (2)-(3) (no plm_pin IK)."""
    p = PRESETS[name].parameters
    return prrrp_paper_configuration(
        preset(name), pose, p["rod_lengths"], p["half_plate"], p["working_modes"]
    )


# ------------------------------------------------------------------ Harada 2011 closed forms
def _harada2011_symbols() -> tuple[float, float, float, float, float, float, float]:
    """l, r_t, m_m, m_l, I_l, m_t, g of (M.36)-(M.37), read from the preset (equal rods)."""
    p = PRESETS["harada2011_3d4m"].parameters
    return (
        p["rod_lengths"][0],
        p["half_plate"],
        p["slider_mass"],
        p["rod_masses"][0],
        p["rod_inertias"][0],
        p["plate_mass"],
        p["gravity"],
    )


def _m31_m32(y: float, theta: float) -> tuple[float, float]:
    """m_yy (M.31) and m_y-theta (M.32) as printed, OCR read: "1^2" is l^2, "I_l" the rod inertia."""
    l, rt, mm, ml, Il, mt, _ = _harada2011_symbols()
    s2 = math.sin(theta) ** 2
    den = (l**2 - rt**2 * s2) ** 2 - 2 * (l**2 + rt**2 * s2) * y**2 + y**4
    m_yy = (
        (l**2 - rt**2 * s2) * (4 * Il + l**2 * (ml + mt) + (4 * mm - mt) * rt**2 * s2)
        - (4 * Il + l**2 * (ml - 4 * mm + 2 * mt) - 2 * (4 * mm - mt) * rt**2 * s2) * y**2
        + (-4 * mm + mt) * y**4
    ) / den
    m_yt = (4 * Il + l**2 * (ml + 4 * mm)) * rt**2 * math.sin(2 * theta) * y / den
    return m_yy, m_yt


def _m33_m35(y: float, theta: float) -> tuple[float, float, float]:
    """h_y1, h_y2, h_y3 (M.33)-(M.35), coefficients of y_dot theta_dot, y_dot^2 and theta_dot^2.

    OCR read: "2 I_l^2" in (M.33) and "l^2", "l_1", "m_1", "mm" in (M.34)-(M.35) are 2 l^2,
    l^2, I_l, m_l and m_m (the common factor is that of (M.32)).
    """
    l, rt, mm, ml, Il, _, _ = _harada2011_symbols()
    B = 4 * Il + l**2 * (ml + 4 * mm)
    c2, c4, c6 = math.cos(2 * theta), math.cos(4 * theta), math.cos(6 * theta)
    u = 2 * l**2 - rt**2 + rt**2 * c2  # 2 (l^2 - r_t^2 sin^2)
    w = 2 * l**2 + rt**2 - rt**2 * c2  # 2 (l^2 + r_t^2 sin^2)
    D = (l**2 - rt**2 * math.sin(theta) ** 2) ** 2 - 2 * (l**2 + rt**2 * math.sin(theta) ** 2) * y**2 + y**4
    h1 = B * rt**2 * math.sin(2 * theta) * (u**2 + 4 * w * y**2 - 12 * y**4) / (4 * D**2)
    h2 = (
        2
        * B
        * y
        * (
            8 * l**4
            + 8 * l**2 * rt**2
            - 9 * rt**4
            + (-8 * l**2 * rt**2 + 12 * rt**4) * c2
            - 3 * rt**4 * c4
            - 8 * u * y**2
            + 8 * y**4
        )
        / (u**2 - 4 * w * y**2 + 4 * y**4) ** 2
    )
    h3 = (
        2
        * B
        * rt**2
        * y
        * (
            -16 * l**4
            + 56 * l**2 * rt**2
            - 26 * rt**4
            + (48 * l**4 - 64 * l**2 * rt**2 + 33 * rt**4) * c2
            + 8 * l**2 * rt**2 * c4
            - 6 * rt**4 * c4
            - rt**4 * c6
            - 8 * (-4 * l**2 - 7 * rt**2 + 4 * (3 * l**2 + 2 * rt**2) * c2 - rt**2 * c4) * y**2
            + 16 * (-1 + 3 * c2) * y**4
        )
        / (2 * u**2 - 8 * w * y**2 + 8 * y**4) ** 2
    )
    return h1, h2, h3


@pytest.mark.parametrize("pose", POSES)
def test_3d4m_x_row_and_gravity_match_harada_eq26_and_m30(pose):
    """m_xx = 4 m_l + 4 m_m + m_t, m_xy = m_x-theta = 0 (eq. (26)) and g = (0, (2 m_l + m_t) g, 0) (M.30)."""
    _, _, mm, ml, _, mt, g = _harada2011_symbols()
    dyn = task_space_dynamics(preset("harada2011_3d4m"), paper_configuration("harada2011_3d4m", pose))
    assert dyn.M_x[0] == pytest.approx([4 * ml + 4 * mm + mt, 0.0, 0.0], abs=1e-12)
    assert dyn.g_x == pytest.approx([0.0, (2 * ml + mt) * g, 0.0], abs=1e-12)  # holds against -y gravity
    assert np.all(dyn.h_x == 0.0)  # at rest


@pytest.mark.parametrize("pose", POSES)
def test_3d4m_myy_and_mytheta_match_harada_m31_m32(pose):
    """m_yy and m_y-theta equal the paper's (M.31)-(M.32); the rod inertia is about its centre in both."""
    dyn = task_space_dynamics(preset("harada2011_3d4m"), paper_configuration("harada2011_3d4m", pose))
    m_yy, m_yt = _m31_m32(pose[1], pose[2])
    assert dyn.M_x[1, 1] == pytest.approx(m_yy, rel=1e-12)
    assert dyn.M_x[1, 2] == pytest.approx(m_yt, rel=1e-10, abs=1e-15)
    assert dyn.M_x[2, 1] == dyn.M_x[1, 2]


@pytest.mark.parametrize("pose", POSES)
def test_3d4m_velocity_terms_match_harada_m33_m35(pose, rng):
    """h_x = 0 and h_y = h_y1 y_dot theta_dot + h_y2 y_dot^2 + h_y3 theta_dot^2 ((M.33)-(M.35), eq. (27))."""
    xd = rng.normal(size=3) * np.array([0.3, 0.3, 2.0])
    dyn = task_space_dynamics(
        preset("harada2011_3d4m"), paper_configuration("harada2011_3d4m", pose), xdot=xd
    )
    h1, h2, h3 = _m33_m35(pose[1], pose[2])
    h_y = h1 * xd[1] * xd[2] + h2 * xd[1] ** 2 + h3 * xd[2] ** 2
    assert dyn.h_x[0] == pytest.approx(0.0, abs=1e-12)
    assert dyn.h_x[1] == pytest.approx(h_y, rel=1e-9, abs=1e-13)


@pytest.mark.parametrize("name", PRRRP)
@pytest.mark.parametrize("pose", POSES)
def test_prrrp_inertia_and_gravity_match_hand_lagrange(name, pose):
    """M_x and g_x of every 2-PRRRP preset (equal, asymmetric, three legs) equal the hand derivation."""
    M, G = lagrange_inertia_and_gravity(PRESETS[name].parameters, pose)
    dyn = task_space_dynamics(preset(name), paper_configuration(name, pose))
    np.testing.assert_allclose(dyn.M_x, M, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(dyn.g_x, G, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("name", PRRRP)
@pytest.mark.parametrize("pose", POSES)
def test_prrrp_velocity_terms_match_christoffel_symbols(name, pose, rng):
    """h_x equals Lagrange's velocity terms from finite differences of the hand M(x)."""
    xd = rng.normal(size=3) * np.array([0.3, 0.3, 2.0])
    dyn = task_space_dynamics(preset(name), paper_configuration(name, pose), xdot=xd)
    expected = lagrange_velocity_terms(PRESETS[name].parameters, pose, xd)
    np.testing.assert_allclose(dyn.h_x, expected, rtol=1e-7, atol=1e-8 * np.max(np.abs(expected)))


# ------------------------------------------------------------------ a second engine route
def _pinocchio_acceleration(mech: Mechanism, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Tree acceleration from ``pin.constraintDynamics`` with one CONTACT_3D per point closure."""
    model = mech.model
    cms = pin.StdVec_RigidConstraintModel()
    for c in mech.closures:
        fa, fb = (model.frames[i] for i in c.frame_ids)
        cms.append(
            pin.RigidConstraintModel(
                pin.ContactType.CONTACT_3D,
                model,
                fa.parentJoint,
                fa.placement,
                fb.parentJoint,
                fb.placement,
                _LWA,
            )
        )
    cds = pin.StdVec_RigidConstraintData()
    for cm in cms:
        cds.append(cm.createData())
    data = model.createData()
    pin.initConstraintDynamics(model, data, cms, cds)
    return np.array(
        pin.constraintDynamics(model, data, q, v, tau, cms, cds, pin.ProximalSettings(1e-14, 1e-12, 50))
    )


@pytest.mark.parametrize(
    "name",
    ["fivebar", "harada2011_3d4m", "harada2015_asymmetric", "enferadi2017_star_triangle", "zhao2011_6pss"],
)
def test_equation_of_motion_matches_pinocchio_constraint_dynamics(name, rng):
    """M_x xdd + h_x + g_x = S^T tau, xdd from pin.constraintDynamics (spatial, armature, redundant rows)."""
    mech = preset(name)
    q = mech.q_ref
    dyn = task_space_dynamics(mech, q, xdot=0.3 * rng.normal(size=len(mech.task.dofs)))
    tau = 5.0 * rng.normal(size=mech.nv)
    a = _pinocchio_acceleration(mech, q, dyn.v, tau)
    data = mech.model.createData()
    pin.forwardKinematics(mech.model, data, q, dyn.v, a)
    pin.updateFramePlacements(mech.model, data)
    task = mech.task_compiled
    # classical acceleration of the frame origin and angular acceleration: the twist-row derivatives
    xdd = pin.getFrameClassicalAcceleration(mech.model, data, task.frame_id, _LWA).vector[list(task.rows)]
    f_x = dyn.S.T @ tau
    np.testing.assert_allclose(dyn.force(xdd), f_x, rtol=1e-9, atol=1e-9 * np.max(np.abs(f_x)))
    np.testing.assert_allclose(dyn.acceleration(f_x), xdd, rtol=1e-9, atol=1e-9 * np.max(np.abs(xdd)))


def test_inverse_dynamics_forces_reach_the_task_force_along_a_trajectory():
    """Along a task trajectory, J_ce^T f_c of plm_pin's inverse dynamics is M_x xdd + h_x + g_x.

    A cross-module check (RNEA with the trajectory's accelerations, then the statics balance),
    not an independent route for h_x: that is the Lagrange and constraint-dynamics tests' job.
    """
    mech = preset("harada2011_3d4m")

    def profile(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        w = 2 * math.pi
        x = np.array([0.02 * math.sin(w * t), 0.08 + 0.01 * math.cos(w * t), 0.2 * math.sin(w * t)])
        xd = np.array([0.02 * w * math.cos(w * t), -0.01 * w * math.sin(w * t), 0.2 * w * math.cos(w * t)])
        xdd = -(w**2) * (x - np.array([0.0, 0.08, 0.0]))
        return x, xd, xdd

    traj = task_trajectory(mech, profile, np.linspace(0.0, 0.5, 6))
    f_c = inverse_dynamics(mech, traj).f_c
    for k in range(traj.n_samples):
        dyn = task_space_dynamics(mech, traj.q[k], traj.v[k])
        J_ce = closed_chain_jacobians(mech, traj.q[k]).J_ce
        np.testing.assert_allclose(J_ce.T @ f_c[k], dyn.force(traj.xdd[k]), rtol=1e-9, atol=1e-10)


def test_actuator_forces_reach_the_task_through_J_ce(rng):
    """With forces on the actuated joints only, f_x = S^T tau = J_ce^T f_c (Harada's J_ce, eq. (12))."""
    mech = preset("harada2011_3d4m")
    q = paper_configuration("harada2011_3d4m", POSES[1])
    f_c = rng.normal(size=mech.n_actuators)
    tau = np.zeros(mech.nv)
    tau[mech.actuated_v_indices] = f_c
    dyn = task_space_dynamics(mech, q)
    np.testing.assert_allclose(dyn.S.T @ tau, closed_chain_jacobians(mech, q).J_ce.T @ f_c, rtol=1e-12)


def test_armature_adds_the_reflected_inertia_through_J_ce():
    """The 6-PSS's screw armature adds J_ce^T diag(reflected inertia) J_ce to M_x (pin.crba holds it)."""
    mech = preset("zhao2011_6pss")
    bare = mech.model.copy()
    bare.armature[:] = 0.0
    no_armature = Mechanism(bare, mech.sidecar, name="bare_6pss")
    q = mech.q_ref
    reflected = np.array([a.reflected_inertia for a in mech.actuators])
    assert np.all(reflected > 400.0)  # (2 pi / 0.05 m)^2 (10.5e-4 + 248e-4) kg m^2 = 408.2 kg
    J_ce = closed_chain_jacobians(mech, q).J_ce
    added = task_space_dynamics(mech, q).M_x - task_space_dynamics(no_armature, q).M_x
    np.testing.assert_allclose(added, J_ce.T @ np.diag(reflected) @ J_ce, rtol=1e-10, atol=1e-9)


def test_tree_velocity_and_task_velocity_give_the_same_terms(rng):
    """The tree velocity S xdot gives the terms of xdot, read back as J_x v; at rest h_x = 0."""
    mech = preset("harada2015_asymmetric")
    q = paper_configuration("harada2015_asymmetric", POSES[2])
    xd = rng.normal(size=3)
    by_task = task_space_dynamics(mech, q, xdot=xd)
    by_tree = task_space_dynamics(mech, q, by_task.v)
    np.testing.assert_allclose(by_tree.h_x, by_task.h_x, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(by_tree.xdot, xd, rtol=1e-12, atol=1e-14)
    assert np.all(task_space_dynamics(mech, q).h_x == 0.0)
    with pytest.raises(ValueError):
        by_task.M_x[0, 0] = 1.0  # read-only


def test_to_dict_is_json_with_units():
    """to_dict gives plain data with the SI units of M_x (row-major) and of the force rows."""
    dyn = task_space_dynamics(preset("harada2011_3d4m"), preset("harada2011_3d4m").q_ref)
    data = json.loads(json.dumps(dyn.to_dict()))
    assert data["units"]["M_x"] == ["kg", "kg", "kg m", "kg", "kg", "kg m", "kg m", "kg m", "kg m^2"]
    assert data["units"]["g_x"] == ["N", "N", "N m"]
    assert task_units(("x", "y", "z", "rx", "ry", "rz"))[1] == ("N", "N", "N", "N m", "N m", "N m")
    assert data["M_x"][0][0] == pytest.approx(dyn.M_x[0, 0])


# ------------------------------------------------------------------ refusals
def test_refuses_a_mechanism_without_task_or_with_a_short_task():
    """No task, or fewer task coordinates than DOF, is refused with the existing messages."""
    mech = preset("harada2011_3d4m")
    no_task = Mechanism(mech.model, dataclasses.replace(mech.sidecar, task=None), name="no_task")
    with pytest.raises(InvalidInput, match="no_task has no end-effector task"):
        task_space_dynamics(no_task, mech.q_ref)
    short = Mechanism(
        mech.model, dataclasses.replace(mech.sidecar, task=TaskSpec("plate_center", ("x", "y"))), name="short"
    )
    with pytest.raises(InvalidInput, match="short: the task has 2 coordinates but the mechanism has 3 DOF"):
        task_space_dynamics(short, mech.q_ref)


def test_refuses_bad_states():
    """Open loops, an infeasible v, v with xdot, and malformed vectors are refused by name."""
    mech = preset("harada2011_3d4m")
    q = mech.q_ref
    open_q = q.copy()
    open_q[0] += 1e-3  # slider 1 moved alone
    with pytest.raises(
        ClosureNotSatisfied, match=r"q is not assembled: closure 'rod2_plate_left' is open by 0\.001"
    ):
        task_space_dynamics(mech, open_q)
    v = np.zeros(mech.nv)
    v[0] = 1.0
    with pytest.raises(InvalidInput, match="v is not a feasible velocity"):
        task_space_dynamics(mech, q, v)
    with pytest.raises(InvalidInput, match="not both"):
        task_space_dynamics(mech, q, np.zeros(mech.nv), xdot=np.zeros(3))
    with pytest.raises(InvalidInput, match=r"xdot must have shape \(3,\)"):
        task_space_dynamics(mech, q, xdot=np.zeros(2))
    with pytest.raises(InvalidInput, match="xddot has non-finite entries"):
        task_space_dynamics(mech, q).force([0.0, np.nan, 0.0])


def test_refuses_an_inverse_kinematics_singularity():
    """With every rod vertical (y = l, theta = 0) S is undefined: SingularConfiguration."""
    q = paper_configuration("harada2011_3d4m", (0.0, 0.140, 0.0))
    with pytest.raises(SingularConfiguration, match="inverse-kinematics"):
        task_space_dynamics(preset("harada2011_3d4m"), q)
