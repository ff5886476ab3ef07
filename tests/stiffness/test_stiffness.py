"""Cartesian stiffness, deflection and natural frequencies against independent oracles."""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.description.compliance import ComplianceSpec
from plm_pin.exceptions import InvalidInput, SingularConfiguration
from plm_pin.results import units
from plm_pin.statics import static_forces
from plm_pin.statics.balance import load_on_frame
from plm_pin.stiffness import (
    StiffnessMap,
    Vibration,
    deflection,
    natural_frequencies,
    stiffness,
    stiffness_map,
)
from plm_pin.stiffness.equilibrium import elastic_state, hessian_terms
from plm_pin.stiffness.geometric import TreeDerivatives
from plm_pin.workspace import workspace_map
from tests.conftest import ball_joint_body, fd_jacobian, preset

from .mechanisms import RPR_ROD, cantilever, pendulum, rpr, rpr_points, stewart
from .oracle import compliance_by_equilibria, equilibrium_displacement

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def _drives(mech, k: float) -> ComplianceSpec:
    return ComplianceSpec(actuators={a.joint: k for a in mech.actuators})


@pytest.mark.parametrize("offset", [0.0, 0.3])
@pytest.mark.parametrize(
    "closure", [{"type": "point"}, {"type": "revolute", "axis": [0, 1, 1]}, {"type": "weld"}]
)
def test_closure_force_derivative_matches_finite_differences(tmp_path, closure, offset, rng):
    """-d(J_phi^T lambda)/dq at fixed lambda equals finite differences of the exact closure Jacobian."""
    mech = ball_joint_body(tmp_path, closure)
    model = mech.model
    q = pin.integrate(model, mech.q_ref, rng.normal(scale=offset, size=model.nv))  # closed, then open
    lam = rng.normal(size=mech.n_closure_rows)
    got = hessian_terms(mech, q, None, False, lam)["closures"]
    want = -fd_jacobian(lambda x: mech.closure_jacobian(x).T @ lam, model, q)
    np.testing.assert_allclose(got, want, atol=1e-7 * max(1.0, np.abs(want).max()))


def test_load_and_gravity_derivatives_match_finite_differences(rng):
    """Load (force and moment fixed in the world) and gravity terms of the 8-PSS equal finite differences."""
    mech = preset("zhao2011_8pss")
    model, data = mech.model, mech.data
    q = pin.integrate(model, mech.q_ref, rng.normal(scale=0.05, size=model.nv))
    load = load_on_frame(mech, rng.normal(size=6) * 100.0)

    def generalized(x):
        pin.computeJointJacobians(model, data, x)
        pin.updateFramePlacements(model, data)
        return pin.getFrameJacobian(model, data, load.frame_id, _LWA).T @ load.wrench

    terms = hessian_terms(mech, q, load, True, np.zeros(mech.n_closure_rows))
    np.testing.assert_allclose(terms["load"], -fd_jacobian(generalized, model, q), atol=1e-6)
    g = fd_jacobian(lambda x: pin.computeGeneralizedGravity(model, data, x).copy(), model, q)
    np.testing.assert_allclose(terms["gravity"], g, atol=1e-6)


def test_summed_dead_wrenches_match_finite_differences(rng):
    """Fixed world wrenches on several bodies of the 8-PSS and on the world, summed in one call, are exact.

    Against finite differences of the sum of their generalized forces.
    """
    mech = preset("zhao2011_8pss")
    model, data = mech.model, mech.data
    q = pin.integrate(model, mech.q_ref, rng.normal(scale=0.05, size=model.nv))
    frames = [
        model.getFrameId(n) for n in ("platform_p1", "carriage1", "cross2", "strut3_tip", "strut5", "base")
    ]
    wrenches = rng.normal(size=(len(frames), 6)) * 10.0

    def generalized(x):
        pin.computeJointJacobians(model, data, x)
        pin.updateFramePlacements(model, data)
        return sum(
            pin.getFrameJacobian(model, data, f, _LWA).T @ w for f, w in zip(frames, wrenches, strict=True)
        )

    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    tree = TreeDerivatives(model, data)
    joints = [model.frames[f].parentJoint for f in frames]
    points = np.array([data.oMf[f].translation for f in frames])
    got = tree.dead_wrenches(joints, wrenches[:, :3], wrenches[:, 3:], points)
    assert len(set(joints)) > 3 and 0 in joints
    np.testing.assert_allclose(got, fd_jacobian(generalized, model, q), atol=1e-6)


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_8pss"])
def test_spring_forces_balance_the_loads_at_the_equilibrium(name, rng):
    """The springs carry g(q) - J_w^T w - J_phi^T lambda, computed here with Pinocchio directly."""
    mech = preset(name)
    model, data = mech.model, mech.data
    q = mech.q_ref
    wrench = rng.normal(size=6)
    state = elastic_state(mech, q, wrench)
    load = load_on_frame(mech, wrench)
    g = pin.computeGeneralizedGravity(model, data, q).copy()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J_w = pin.getFrameJacobian(model, data, load.frame_id, _LWA)
    want = g - J_w.T @ load.wrench - mech.closure_jacobian(q).T @ state.lam
    np.testing.assert_allclose(state.spring_forces, want, atol=1e-9 * max(1.0, np.abs(want).max()))


def _griffis_duffy(mech, q, k: float, tensions: np.ndarray) -> np.ndarray:
    """K = sum k j j^T + t/l E^T (I - u u^T) E + t [0, 0; 0, sym(u r^T) - (u.r) I] (hand derivation).

    From the second-order expansion of the leg lengths l_i = |p + R b_i - a_i| with
    R' = exp(dtheta) R: dl = u.e1 + u.e2 + e1^T (I - u u^T) e1 / (2 l), e1 = dp + dtheta x r,
    e2 = dtheta x (dtheta x r) / 2, r = R b_i.
    """
    model, data = mech.model, mech.data
    pin.framesForwardKinematics(model, data, q)
    p = data.oMf[model.getFrameId("platform_center")].translation
    K = np.zeros((6, 6))
    for i in range(6):
        a = data.oMi[model.getJointId(f"leg{i + 1}_ux")].translation
        tip = "leg1_rod" if i == 0 else f"platform_b{i + 1}"
        s = data.oMf[model.getFrameId(tip)].translation
        r, d = s - p, s - a
        ln = np.linalg.norm(d)
        uu = d / ln
        j = np.concatenate([uu, np.cross(r, uu)])
        E = np.hstack([np.eye(3), -pin.skew(r)])
        K += k * np.outer(j, j) + tensions[i] / ln * E.T @ (np.eye(3) - np.outer(uu, uu)) @ E
        K[3:, 3:] += tensions[i] * (0.5 * (np.outer(uu, r) + np.outer(r, uu)) - (uu @ r) * np.eye(3))
    return K


def _leg_jacobian(mech, q) -> np.ndarray:
    model, data = mech.model, mech.data
    pin.framesForwardKinematics(model, data, q)
    p = data.oMf[model.getFrameId("platform_center")].translation
    rows = []
    for i in range(6):
        a = data.oMi[model.getJointId(f"leg{i + 1}_ux")].translation
        s = data.oMf[model.getFrameId("leg1_rod" if i == 0 else f"platform_b{i + 1}")].translation
        uu = (s - a) / np.linalg.norm(s - a)
        rows.append(np.concatenate([uu, np.cross(s - p, uu)]))
    return np.array(rows)


@pytest.mark.parametrize("force", [(0.0, 0.0, 0.0), (300.0, -200.0, -2000.0)])
def test_stewart_gough_matches_griffis_duffy(tmp_path, force):
    """6-UPS with axial leg stiffness: K_x = J^T k J plus the leg-force geometric term; unloaded, loaded."""
    mech = stewart(tmp_path)
    q = mech.q_ref
    k = 2.0e5
    w = np.array([*force, 0.0, 0.0, 0.0])
    J = _leg_jacobian(mech, q)
    tensions = np.linalg.solve(J.T, w)  # leg tensions t with sum t_i j_i = w
    res = stiffness(mech, q, w, gravity=False, compliance=_drives(mech, k))
    want = _griffis_duffy(mech, q, k, tensions)
    np.testing.assert_allclose(res.K_x, want, rtol=0, atol=1e-9 * np.abs(want).max())
    if any(force):
        assert np.abs(want - k * J.T @ J).max() > 1e-3 * np.abs(want).max()  # the geometric term matters here
    assert res.idle == 0


def test_idle_leg_spins_are_left_out(tmp_path):
    """6-SPS (legs free to spin about their axis): five idle motions dropped, K_x still Griffis-Duffy's."""
    mech = stewart(tmp_path, spin=True)
    k = 2.0e5
    res = stiffness(mech, mech.q_ref, gravity=False, compliance=_drives(mech, k))
    want = _griffis_duffy(mech, mech.q_ref, k, np.zeros(6))
    np.testing.assert_allclose(res.K_x, want, rtol=0, atol=1e-9 * np.abs(want).max())
    assert res.idle == 5  # held by the mechanism's gauges
    assert res.unresisted == 0


def test_unsprung_motion_the_task_does_not_see_is_left_out(tmp_path):
    """A flap on a spring-less hinge, no gravity: its swing is left out (unresisted), K_x is the drive's k."""
    k = 40.0
    mech = pendulum(tmp_path, 1.0, 0.2, 1e-3, k, 0.0, flap=True)
    res = stiffness(mech, mech.q_ref, gravity=False)
    np.testing.assert_allclose(res.K_x, [[k]], rtol=1e-12)  # rz of the bar is the hinge angle
    assert (res.idle, res.unresisted) == (0, 1)


def test_preloaded_3d4m_matches_potential_minimisation():
    """3D4M with internal preload f_i = 100 N: K_x equals finite differences of scipy-minimised equilibria."""
    mech = preset("harada2011_3d4m")
    k = 2.0e4
    q = mech.q_ref
    sol = static_forces(mech, q, internal={"plate": -100.0}, limits=None)
    res = stiffness(mech, q, forces=sol, compliance=_drives(mech, k))
    C = compliance_by_equilibria(mech, q, sol.f_c, np.full(4, k), np.array([1.0, 1.0, 0.1]))
    D = np.diag([1.0, 1.0, 10.0])  # rotation rows in N per 0.1 m
    err = np.linalg.norm(D @ (np.linalg.inv(C) - res.K_x) @ D) / np.linalg.norm(D @ res.K_x @ D)
    assert err < 1e-6
    plain = stiffness(mech, q, compliance=_drives(mech, k))
    assert plain.min_translational - res.min_translational > 1e-2 * plain.min_translational  # preload shows


@pytest.mark.slow
def test_8pss_matches_potential_minimisation():
    """8-PSS under gravity: K_x equals finite differences of scipy-minimised equilibria to 1e-6."""
    mech = preset("zhao2011_8pss")
    k = 1.0e6
    q = mech.q_ref
    sol = static_forces(mech, q, limits=None)
    res = stiffness(mech, q, forces=sol, compliance=_drives(mech, k))
    C = compliance_by_equilibria(mech, q, sol.f_c, np.full(8, k), np.array([3000.0] * 3 + [1500.0] * 3))
    err = np.linalg.norm(np.linalg.inv(C) - res.K_x) / np.linalg.norm(res.K_x)
    assert err < 1e-6


def test_contributions_add_up_and_split_the_sources():
    """The per-source shares sum to K_x; without load the geometric shares vanish except gravity's."""
    mech = preset("harada2011_3d4m")
    res = stiffness(mech, mech.q_ref, internal={"plate": -50.0}, compliance=_drives(mech, 1e5))
    np.testing.assert_allclose(sum(res.contributions.values()), res.K_x, atol=1e-9 * np.abs(res.K_x).max())
    assert not res.contributions["load"].any() and not res.contributions["joints"].any()
    assert np.abs(res.contributions["closures"]).max() > 0.0


BEAM = {"E": 2.0e11, "G": 8.0e10, "A": 1.0e-4, "Iy": 2.0e-9, "Iz": 8.0e-10, "J": 1.5e-9, "y_axis": [0, 1, 0]}


def test_cantilever_matches_beam_closed_forms(tmp_path):
    """A flexible link: tip compliance F L^3/3EI in bending, L/EA axially, L/GJ in torsion."""
    L = 0.4
    mech = cantilever(tmp_path, L, compliance={"links": [{"link": "beam", "tip": "beam_tip", **BEAM}]})
    res = stiffness(mech, mech.q_ref, gravity=False)
    E, G, A, Iy, Iz, J = (float(BEAM[k]) for k in ("E", "G", "A", "Iy", "Iz", "J"))
    C = res.C_x
    assert C[0, 0] == pytest.approx(L / (E * A), rel=1e-9)
    assert C[1, 1] == pytest.approx(L**3 / (3 * E * Iz), rel=1e-9)
    assert C[2, 2] == pytest.approx(L**3 / (3 * E * Iy), rel=1e-9)
    assert C[3, 3] == pytest.approx(L / (G * J), rel=1e-9)
    assert C[1, 5] == pytest.approx(L**2 / (2 * E * Iz), rel=1e-9)
    d = deflection(mech, mech.q_ref, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0], gravity=False)
    assert d.task_displacement[1] == pytest.approx(L**3 / (3 * E * Iz), rel=1e-4)
    np.testing.assert_allclose(
        d.link_deflections["beam"][[1, 5]], [L**3 / (3 * E * Iz), L**2 / (2 * E * Iz)], rtol=1e-4
    )


def test_flexible_tip_mass_frequency(tmp_path):
    """A massless cantilever with a tip point mass m vibrates at sqrt(3 E I / (m L^3)) / 2 pi (full model)."""
    L, m = 0.4, 2.0
    mech = cantilever(tmp_path, L, m, compliance={"links": [{"link": "beam", "tip": "beam_tip", **BEAM}]})
    vibration = natural_frequencies(mech, mech.q_ref, model="full", gravity=False)
    soft = min(BEAM["Iy"], BEAM["Iz"])
    assert vibration.lowest == pytest.approx(
        math.sqrt(3 * BEAM["E"] * soft / (m * L**3)) / (2 * math.pi), rel=1e-6
    )
    shape = vibration.task_shapes[:, 0]  # bending in y (about I_z): tip slope / deflection = 3 / (2 L)
    assert shape[5] / shape[1] == pytest.approx(3 / (2 * L), rel=1e-7)  # the 1e-9 kg m^2 tip inertia: ~3e-9
    np.testing.assert_allclose(shape[[0, 2, 3, 4]], 0.0, atol=1e-9)


def test_pendulum_frequency_with_gravity_stiffness(tmp_path):
    """Hanging bar on a torsional drive spring: omega^2 = (k + m g l) / (I + m l^2) (full compliant model)."""
    m, l, I, k, g = 1.5, 0.3, 0.01, 20.0, 9.81
    mech = pendulum(tmp_path, m, l, I, k, g)
    want = math.sqrt((k + m * g * l) / (I + m * l**2)) / (2 * math.pi)
    assert natural_frequencies(mech, mech.q_ref, model="full").lowest == pytest.approx(want, rel=1e-10)
    res = stiffness(mech, mech.q_ref)
    assert res.contributions["gravity"][0, 0] == pytest.approx(m * g * l, rel=1e-10)


def test_stewart_frequencies_from_hand_stiffness(tmp_path):
    """6-UPS with massless legs: the vibrations solve K_GD phi = omega^2 M_platform phi (hand M and K)."""
    mech = stewart(tmp_path, platform_mass=5.0)
    k = 2.0e5
    q = mech.q_ref
    K = _griffis_duffy(mech, q, k, np.zeros(6))
    M = np.zeros((6, 6))
    M[:3, :3] = 5.0 * np.eye(3)
    M[3:, 3:] = np.diag([0.02, 0.03, 0.04])  # platform world-aligned, centre at its COM
    import scipy.linalg

    want = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True)) / (2 * math.pi)
    got = natural_frequencies(mech, q, gravity=False, compliance=_drives(mech, k))
    np.testing.assert_allclose(got.frequencies, want, rtol=1e-9)
    full = natural_frequencies(mech, q, model="full", gravity=False, compliance=_drives(mech, k))
    np.testing.assert_allclose(full.frequencies, want, rtol=1e-9)


def test_deflection_converges_to_linear_for_small_loads():
    """Newton's deflection tends to K_x^-1 w as the load shrinks (relative gap proportional to the load)."""
    mech = preset("harada2011_3d4m")
    spec = _drives(mech, 2e4)
    gaps = []
    for scale in (1.0, 0.1):
        d = deflection(
            mech, mech.q_ref, scale * np.array([1.0, 2.0, 0.1]), internal={"plate": -100.0}, compliance=spec
        )
        gaps.append(
            np.linalg.norm(d.task_displacement - d.linear_displacement)
            / np.linalg.norm(d.linear_displacement)
        )
    assert gaps[1] < 0.2 * gaps[0] and gaps[1] < 1e-3


def test_errors_name_the_problem():
    """No compliance, a stiffness on an unknown drive, an unheld task motion: one clear error each."""
    rigid = preset("fourbar")
    with pytest.raises(InvalidInput, match="has no compliance"):
        stiffness(rigid, rigid.q_ref)
    mech = preset("harada2011_3d4m")
    with pytest.raises(InvalidInput, match="not a drive; drives are"):
        stiffness(mech, mech.q_ref, compliance=ComplianceSpec(actuators={"rod1_pivot": 1e5}))
    with pytest.raises(SingularConfiguration, match="rigid"):
        stiffness(mech, mech.q_ref, compliance=ComplianceSpec(actuators={"slider1": 1e5}))


def test_forces_must_belong_to_q():
    """forces= solved at another configuration, or on another mechanism, than q is refused by name."""
    mech = preset("harada2011_3d4m")
    compliance = _drives(mech, 2.0e4)
    sol = static_forces(mech, mech.q_ref, internal={"plate": -100.0}, limits=None)
    moved = mech.assemble(pin.integrate(mech.model, mech.q_ref, np.full(mech.nv, 0.01))).q
    assert max(mech.closure_errors(moved).values()) < 1e-10  # assembled, only not the forces' q
    with pytest.raises(InvalidInput, match="q is not the configuration forces= were solved at: they differ"):
        stiffness(mech, moved, forces=sol, compliance=compliance)
    with pytest.raises(InvalidInput, match="not the configuration forces= were solved at"):
        elastic_state(mech, moved, forces=sol, compliance=compliance)
    three = preset("harada2011_3d3m")
    with pytest.raises(InvalidInput, match=r"forces= were solved on harada2011_3d3m \(nq = "):
        elastic_state(mech, mech.q_ref, forces=static_forces(three, three.q_ref), compliance=compliance)
    read_back = mech.q_ref + 1e-12  # a q written to a file and read back
    np.testing.assert_array_equal(
        stiffness(mech, read_back, forces=sol, compliance=compliance).K_x,
        stiffness(mech, mech.q_ref, forces=sol, compliance=compliance).K_x,
    )


def test_planar_3rpr_with_flexible_legs_is_drives_in_series_with_rods(tmp_path):
    """3-RPR, rods as beams: K_x = sum k_eff j j^T, 1/k_eff = 1/k + L/EA (two-force legs, unloaded)."""
    k, E, A = 2.0e6, 2.0e11, 1.0e-5
    beam = {"E": E, "G": 8.0e10, "A": A, "Iy": 1.0e-10, "Iz": 1.0e-10, "J": 1.0e-10}
    links = [{"link": f"leg{n}_rod", "tip": f"leg{n}_tip", **beam} for n in (1, 2, 3)]
    mech = rpr(tmp_path, {"actuators": {f"leg{n}_slide": k for n in (1, 2, 3)}, "links": links})
    a, b, p = rpr_points()
    k_eff = 1.0 / (1.0 / k + RPR_ROD / (E * A))
    K = np.zeros((3, 3))
    for i in range(3):
        d = p + b[i] - a[i]
        uu = d / np.linalg.norm(d)
        j = np.array([uu[0], uu[1], b[i][0] * uu[1] - b[i][1] * uu[0]])  # (r x u)_z, r = b_i (world-aligned)
        K += k_eff * np.outer(j, j)
    res = stiffness(mech, mech.q_ref, gravity=False)
    np.testing.assert_allclose(res.K_x, K, rtol=0, atol=1e-8 * np.abs(K).max())
    rigid = stiffness(
        mech,
        mech.q_ref,
        gravity=False,
        compliance=ComplianceSpec(actuators={f"leg{n}_slide": k for n in (1, 2, 3)}),
    )
    assert rigid.min_translational > res.min_translational  # the rods' axial compliance adds in series
    assert np.abs(res.contributions["links"]).max() > 0.0


def test_deflection_matches_potential_minimisation_under_a_large_load():
    """Newton's non-linear deflection of the preloaded 3D4M equals the scipy-minimised equilibrium."""
    mech = preset("harada2011_3d4m")
    k = 2.0e4
    q = mech.q_ref
    sol = static_forces(mech, q, internal={"plate": -100.0}, limits=None)
    w = np.array([40.0, -60.0, 2.0])  # large enough that the response is visibly non-linear
    d = deflection(mech, q, w, forces=sol, compliance=_drives(mech, k))
    want = equilibrium_displacement(mech, q, sol.f_c, np.full(4, k), np.array([w[0], w[1], 0, 0, 0, w[2]]))
    np.testing.assert_allclose(d.task_displacement, want[[0, 1, 5]], rtol=1e-8, atol=1e-12)
    assert np.linalg.norm(d.task_displacement - d.linear_displacement) > 1e-3 * np.linalg.norm(
        d.linear_displacement
    )
    np.testing.assert_allclose(
        d.actuator_deflections, mech.actuator_positions(d.q_rigid) - mech.actuator_positions(q)
    )


def test_stiffness_is_symmetric_under_conservative_loads():
    """Dead forces (and a moment about a fixed axis in the plane) are conservative: K_x is symmetric."""
    eight = preset("zhao2011_8pss")
    res = stiffness(eight, eight.q_ref, [1000.0, -2000.0, 500.0, 0.0, 0.0, 0.0])
    assert np.abs(res.K_x - res.K_x.T).max() <= 1e-12 * np.abs(res.K_x).max()
    four = preset("harada2011_3d4m")
    res = stiffness(four, four.q_ref, [10.0, -20.0, 1.0], internal={"plate": -30.0})
    assert np.abs(res.K_x - res.K_x.T).max() <= 1e-12 * np.abs(res.K_x).max()


ROD = (7.0e10, 2.6e10, 3.2e-5, 4.3e-11, 1.7e-10, 1.17e-10)
"""Aluminium 8 x 4 mm rod section: E, G [Pa], A [m^2], Iy, Iz, J [m^4] (assumed)."""


def test_3d4m_with_flexible_rods_is_drives_and_rods_in_series():
    """Pin-jointed rods carry axial forces only: K_x = sum k_leg j j^T, 1/k_leg = u_x^2 / k + L / EA."""
    from plm_pin.description.compliance import BeamSpec

    mech = preset("harada2011_3d4m")
    k, L = 1.0e6, 0.14
    tips = {1: "plate_pivot", 2: "rod2_tip", 3: "rod3_tip", 4: "rod4_tip"}  # rod 1 carries the plate's joint
    beams = tuple(BeamSpec(f"rod{i}", tips[i], ROD, y_axis=(0.0, 1.0, 0.0)) for i in tips)
    spec = ComplianceSpec(actuators={a.joint: k for a in mech.actuators}, links=beams)
    res = stiffness(mech, mech.q_ref, gravity=False, compliance=spec)
    model, data = mech.model, mech.data
    pin.framesForwardKinematics(model, data, mech.q_ref)
    centre = data.oMf[model.getFrameId("plate_center")].translation
    K = np.zeros((3, 3))
    for i, tip in tips.items():
        s = data.oMf[model.getFrameId(f"rod{i}")].translation
        t = (
            data.oMi[model.getJointId("plate_pivot")].translation
            if i == 1
            else data.oMf[model.getFrameId(tip)].translation
        )
        uu = (t - s) / np.linalg.norm(t - s)
        r = t - centre
        j = np.array([uu[0], uu[1], r[0] * uu[1] - r[1] * uu[0]])
        K += j[:, None] * j[None, :] / (uu[0] ** 2 / k + L / (ROD[0] * ROD[2]))
    np.testing.assert_allclose(res.K_x, K, rtol=0, atol=1e-9 * np.abs(K).max())
    full = natural_frequencies(mech, mech.q_ref, model="full", result=res)
    task = natural_frequencies(mech, mech.q_ref, result=res)
    assert full.lowest < task.lowest  # the rods' out-of-plane bending adds softer vibrations


def test_results_are_strict_json_with_their_units():
    """to_dict writes the fields (the solver's matrices left out), NaN as text; units come from the fields."""
    mech = preset("harada2011_3d4m")
    spec = _drives(mech, 2e4)
    res = stiffness(mech, mech.q_ref, compliance=spec)
    data = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert list(data) == [
        *("dofs", "q", "K_x", "C_x", "translational", "rotational", "contributions", "f_c", "lam"),
        *("idle", "unresisted", "units"),
    ]
    np.testing.assert_array_equal(data["K_x"], res.K_x)
    assert data["translational"]["directions"] == res.translational.directions.tolist()
    assert data["translational"]["unit"] == "N/m" and data["units"]["K_x"][0] == "N/m"
    data = json.loads(json.dumps(res.state.to_dict(), allow_nan=False))
    assert list(data) == ["q", "forces", "load", "gravity", "spring_forces"]  # the compliant model left out
    assert list(data["forces"]["f_c"].values()) == res.f_c.tolist() and data["load"] is None
    vibration = natural_frequencies(mech, mech.q_ref, result=res)
    data = json.loads(json.dumps(vibration.to_dict(), allow_nan=False))
    assert list(data) == ["model", "dofs", "frequencies", "omega", "task_shapes"]
    assert data["frequencies"] == vibration.frequencies.tolist() and units(Vibration)["frequencies"] == "Hz"
    d = deflection(mech, mech.q_ref, [1.0, 2.0, 0.1], compliance=spec)
    data = json.loads(json.dumps(d.to_dict(), allow_nan=False))
    assert data["task_displacement"] == d.task_displacement.tolist() and data["iterations"] == d.iterations
    grid = workspace_map(mech, ("x", "y"), ([0.0], [0.08, 10.0]))  # y = 10 m is out of reach
    smap = stiffness_map(mech, grid, compliance=spec)
    data = json.loads(json.dumps(smap.to_dict(), allow_nan=False))
    assert data["lowest_frequency"][0][1] == "nan"
    assert data["lowest_frequency"][0][0] == pytest.approx(smap.lowest_frequency[0, 0], rel=0)
    assert data["units"] == {
        k: units(StiffnessMap)[k]
        for k in ("min_translational_stiffness", "compliance_along", "lowest_frequency")
    }
