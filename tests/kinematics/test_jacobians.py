"""Closed-chain Jacobians S and J_ce (plm_pin/kinematics/jacobians.py).

Oracles: finite differences of the inverse kinematics (re-solved from the same solution), and
the papers' velocity equations written inline: Harada 2011 eq. (4) / (M.9), Enferadi 2017 eqs.
(14)-(17) (corrected, see plm_pin/families/star_triangle/builder.py), Zhao 2011 eq. (6a).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from scipy.linalg import null_space

from plm_pin import InvalidInput, SingularConfiguration
from plm_pin.kinematics import (
    ClosedChainJacobians,
    closed_chain_jacobians,
    inverse_kinematics,
    task_pose,
    working_modes,
)
from plm_pin.kinematics.jacobians import feasible_motions, inverse_if_regular, pseudo_inverse, times_T_inverse
from plm_pin.models import PRESETS, preset_names
from plm_pin.tolerances import INVERSE_RTOL, RANK_RTOL
from tests.conftest import (
    STAR_E,
    ball_joint_body,
    preset,
    prrrp_paper_configuration,
    star_triangle_eq5,
    star_triangle_legs,
)

ZHAO2011 = PRESETS["zhao2011_8pss"].parameters  # Zhao 2011 Tables 1-3, eq. (19): the preset's parameters

EPS = 1e-6

# a pose offset from the reference per preset [m, rad], inside the workspace and regular
OFFSET = {
    "delta": [0.03, -0.02, 0.04],
    "enferadi2017_star_triangle": [0.03, -0.04, 0.2],
    "fivebar": [0.02, -0.01],
    "fourbar": [0.2],
    "harada2011_3d3m": [0.01, 0.01, 0.1],
    "harada2011_3d4m": [0.01, -0.02, 0.15],
    "harada2015_asymmetric": [-0.01, 0.02, -0.15],
    "planar_3rpr": [0.02, -0.01, 0.1],
    "stewart_6ups": [0.03, -0.02, 0.04, 0.03, -0.02, 0.04],
    "zhao2011_6pss": [0.03, -0.02, -0.04, 0.03, -0.02, 0.04],
    "zhao2011_8pss": [-0.02, 0.03, 0.04, -0.03, 0.02, 0.05],
}


def task_twist_fd(mech, x: np.ndarray, k: int) -> np.ndarray:
    """Task velocity (selected world-aligned twist rows) of d x / d x_k, by central differences of (p, R)."""
    task = mech.task_compiled
    n_lin = len(task.linear)

    def placement(xx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p = np.zeros(3)
        p[list(task.linear)] = xx[:n_lin]
        rpy = np.zeros(3)
        rpy[list(task.angular)] = xx[n_lin:]
        return p, pin.rpy.rpyToMatrix(rpy)

    dx = np.zeros(len(x))
    dx[k] = EPS
    (p1, R1), (p0, R0) = placement(x + dx), placement(x - dx)
    twist = np.concatenate([(p1 - p0) / (2 * EPS), pin.log3(R1 @ R0.T) / (2 * EPS)])
    return twist[list(task.rows)]


def ik_differences(mech, q: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Columns k: task twist, tree velocity and actuator rates of IK re-solved at x +- eps e_k from q."""
    twists, dqs, dcs = [], [], []
    for k in range(len(x)):
        dx = np.zeros(len(x))
        dx[k] = EPS
        plus = inverse_kinematics(mech, x + dx, q)
        minus = inverse_kinematics(mech, x - dx, q)
        twists.append(task_twist_fd(mech, x, k))
        dqs.append(pin.difference(mech.model, minus.q, plus.q) / (2 * EPS))
        dcs.append((plus.actuators - minus.actuators) / (2 * EPS))
    return np.column_stack(twists), np.column_stack(dqs), np.column_stack(dcs)


@pytest.mark.parametrize("name", preset_names())
@pytest.mark.parametrize("offset", [False, True])
def test_velocity_map_and_actuator_jacobian_match_finite_differences(name, offset):
    """S and J_ce times the task twist equal finite differences of the IK configuration and actuators."""
    mech = preset(name)
    x = task_pose(mech, mech.q_ref) + (np.array(OFFSET[name]) if offset else 0.0)
    q = inverse_kinematics(mech, x).q
    jac = closed_chain_jacobians(mech, q)
    twist, dq, dc = ik_differences(mech, q, x)
    np.testing.assert_allclose(jac.S @ twist, dq, atol=1e-7)
    np.testing.assert_allclose(jac.J_ce @ twist, dc, atol=1e-7)


@pytest.mark.parametrize("name", preset_names())
def test_velocity_map_is_feasible_and_reproduces_the_task_rates(name):
    """J_phi S = 0 (S keeps the loops closed), J_x S = I, and J_ce is S's actuated rows."""
    mech = preset(name)
    jac = closed_chain_jacobians(mech, mech.q_ref)
    scale = np.max(np.abs(jac.J_phi)) * np.max(np.abs(jac.S))
    np.testing.assert_allclose(jac.J_phi @ jac.S, 0.0, atol=1e-13 * scale)
    np.testing.assert_allclose(jac.J_x @ jac.S, np.eye(jac.J_x.shape[0]), atol=1e-12)
    np.testing.assert_allclose(jac.J_ce, jac.S[mech.actuated_v_indices], atol=1e-14)
    np.testing.assert_allclose(jac.N.T @ jac.N, np.eye(mech.mobility), atol=1e-14)


def test_jacobians_write_their_fields():
    """to_dict writes the six matrices as nested lists (S and J_ce, which may not exist, are left out)."""
    jac = closed_chain_jacobians(preset("harada2011_3d4m"), preset("harada2011_3d4m").q_ref)
    data = jac.to_dict()
    assert list(data) == ["J_phi", "J_x", "N", "closure_singular_values", "T", "C"]
    assert data["T"] == jac.T.tolist() and data["J_phi"] == jac.J_phi.tolist()


RT = 0.05


def harada_jce(pose, legs, lengths, signs) -> np.ndarray:
    """J_c^{-1} J_e of Harada 2011 eq. (4) / (M.9): rows [z_i^T, z_i^T R_theta R s_i] / (z_i^T a).

    z_i = (L_i - c_i a) / l_i with c_i from eq. (2) and sign ``signs[i]``; the task rates are
    (xdot, ydot, thetadot), the paper's Delta p_3 order.
    """
    x, y, theta = pose
    a = np.array([1.0, 0.0])
    R = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    R_theta = np.array([[0.0, -1.0], [1.0, 0.0]])
    J_e, J_c = [], []
    for i, sign in zip(legs, signs, strict=True):
        s = np.array([-RT if i in (1, 2) else RT, 0.0])
        L = np.array([x, y]) + R @ s
        l = lengths[i - 1]
        c = L @ a + sign * math.sqrt((L @ a) ** 2 - L @ L + l**2)
        z = (L - c * a) / l
        J_e.append([z[0], z[1], z @ R_theta @ R @ s])
        J_c.append(z @ a)
    return np.linalg.solve(np.diag(J_c), np.array(J_e))


@pytest.mark.parametrize(
    ("name", "legs", "lengths"),
    [
        ("harada2011_3d4m", (1, 2, 3, 4), (0.14,) * 4),
        ("harada2011_3d3m", (1, 2, 4), (0.14,) * 4),
        ("harada2015_asymmetric", (1, 2, 3, 4), (0.24, 0.17, 0.17, 0.24)),
    ],
)
@pytest.mark.parametrize("pose", [(0.0, 0.08, -0.35), (0.02, 0.1, 0.3), (-0.03, 0.05, 0.0)])
def test_prrrp_actuator_jacobian_is_harada_eq4(name, legs, lengths, pose):
    """In every working mode, J_ce equals J_c^{-1} J_e of eq. (4) with z_i of eqs. (2)-(3)."""
    mech = preset(name)
    for sol in working_modes(mech, pose):
        signs = tuple(-m for m in sol.mode)  # mode = sign(z_i^T a) = minus the square-root sign
        expected = harada_jce(pose, legs, lengths, signs)
        np.testing.assert_allclose(closed_chain_jacobians(mech, sol.q).J_ce, expected, atol=1e-11)


@pytest.mark.parametrize("pose", [(0.25, 0.35, math.pi / 2), (0.2, 0.2, 1.2), (0.3, 0.25, 2.0)])
def test_star_triangle_jacobian_is_enferadi_eqs_15_16(pose):
    """Eq. (17) q_dot = -J^{-1} K X_dot, K of (15), J of (16), X = [phi, x, y], is J_ce up to column order."""
    mech = preset("enferadi2017_star_triangle")
    phi = pose[2]
    _, legs = star_triangle_legs(pose)
    _, rho = star_triangle_eq5(pose)  # eq. (4)
    K = np.empty((3, 3))
    J = np.zeros((3, 3))
    for k, (_, a, s) in enumerate(legs):
        K[k] = [rho[k], *(-(s @ STAR_E))]  # eq. (15), columns (phi, x, y)
        J[k, k] = s @ STAR_E @ a  # eq. (16)
    H = -np.linalg.solve(J, K)  # eq. (17), columns (phi, x, y)
    assert np.allclose(np.diag(J), math.sin(phi))  # J_ii = sin(phi): the spec's closed form
    sol = inverse_kinematics(mech, pose)
    np.testing.assert_allclose(closed_chain_jacobians(mech, sol.q).J_ce, H[:, [1, 2, 0]], atol=1e-12)


def test_star_triangle_jacobian_at_half_pi_is_the_spec_matrix():
    """At phi = pi/2 J_ce is [[1/2, r3/2, -rho_1], [1/2, -r3/2, -rho_2], [-1, 0, -rho_3]], det 3a/4."""
    mech = preset("enferadi2017_star_triangle")
    x, y = 0.27, 0.21
    rho = [(math.sqrt(3) * x - y) / 2, (math.sqrt(3) * (0.5 - x) - y) / 2, y]  # distances to the sides
    expected = np.array(
        [[0.5, math.sqrt(3) / 2, -rho[0]], [0.5, -math.sqrt(3) / 2, -rho[1]], [-1.0, 0.0, -rho[2]]]
    )
    J_ce = closed_chain_jacobians(mech, inverse_kinematics(mech, [x, y, math.pi / 2]).q).J_ce
    np.testing.assert_allclose(J_ce, expected, atol=1e-12)
    assert (
        abs(abs(np.linalg.det(J_ce)) - 3 * 0.5 / 4) < 1e-12
    )  # Viviani: rho_1 + rho_2 + rho_3 = a sqrt(3) / 2


@pytest.mark.parametrize("name", ["zhao2011_8pss", "zhao2011_6pss"])
@pytest.mark.parametrize(
    "pose",
    [
        (0.0, 0.0, 1.744, 0.0, 0.0, 0.0),
        (-0.1, -0.1, 1.644, -0.1, -0.1, -0.1),
        (0.04, -0.03, 1.78, 0.05, 0.02, -0.06),
    ],
)
def test_pss_actuator_jacobian_is_zhao_eq6a(name, pose):
    """J_ce row i is eq. (6a): [w_i^T, (a_i x w_i)^T] / (w_i^T e_i), a_i = R a_i', w_i = (A_i - C_i) / l_i."""
    mech = preset(name)
    legs = [int(a.joint.removeprefix("slider")) for a in mech.actuators]
    p = np.array(pose[:3])
    R = pin.rpy.rpyToMatrix(*pose[3:])
    rows = []
    for i in legs:
        e = np.array(ZHAO2011["guide_directions"][i - 1])
        B = np.array(ZHAO2011["guide_points"][i - 1])
        a_i = R @ np.array(ZHAO2011["platform_points"][i - 1])
        l = ZHAO2011["strut_lengths"][i - 1]
        d = p + a_i - B
        q_i = e @ d - math.sqrt(l**2 - d @ d + (e @ d) ** 2)
        w = (p + a_i - (B + q_i * e)) / l
        rows.append(np.concatenate([w, np.cross(a_i, w)]) / (w @ e))
    sol = inverse_kinematics(mech, pose)
    np.testing.assert_allclose(closed_chain_jacobians(mech, sol.q).J_ce, np.array(rows), atol=1e-12)


def test_jacobians_at_an_inverse_singularity_raise():
    """With rod 2 vertical (z_2^T a = 0, eq. (9)), S and J_ce raise SingularConfiguration naming the type."""
    mech = preset("harada2015_asymmetric")
    lengths = (0.24, 0.17, 0.17, 0.24)
    x, theta = 0.0, -0.3
    y = 0.17 + RT * math.sin(theta)  # L_2y = y - r_t sin(theta) = l_2: rod 2 vertical, the others reach
    q = prrrp_paper_configuration(mech, (x, y, theta), lengths, RT, (-1, 1, -1, 1))
    assert np.max(np.abs(mech.closure_residual(q))) < 1e-15
    jac = closed_chain_jacobians(mech, q)
    with pytest.raises(SingularConfiguration, match=r"^inverse-kinematics \(type 1\) singular"):
        _ = jac.S
    with pytest.raises(SingularConfiguration, match=r"^inverse-kinematics \(type 1\) singular"):
        _ = jac.J_ce


def test_jacobians_need_a_task(tmp_path):
    """A mechanism without an end-effector task cannot give S or J_ce, and says how to add one."""
    mech = ball_joint_body(tmp_path, {"type": "point"})
    with pytest.raises(
        InvalidInput, match=r"^ball has no end-effector task; add 'end_effector' to its sidecar$"
    ):
        closed_chain_jacobians(mech, mech.q_ref)


def test_jacobians_refuse_a_malformed_configuration():
    """A configuration of the wrong size raises InvalidInput."""
    with pytest.raises(InvalidInput, match=r"^q must have shape \(9,\), got \(3,\)$"):
        closed_chain_jacobians(preset("harada2011_3d4m"), [0.0, 0.0, 0.0])


def test_times_T_inverse_is_the_inverse_product_and_blanks_singular_T(rng):
    """Batched M T^-1 equals M @ inv(T) per matrix; a rank-deficient T gives NaN and is flagged."""
    T = rng.normal(size=(4, 3, 3))
    T[2, :, 2] = T[2, :, 0] + T[2, :, 1]  # rank 2
    M = rng.normal(size=(4, 5, 3))
    out, singular = times_T_inverse(M, T, T)  # J_x = T: the scale is T's own norm
    assert singular.tolist() == [False, False, True, False]
    for k in (0, 1, 3):
        np.testing.assert_allclose(out[k], M[k] @ np.linalg.inv(T[k]), rtol=1e-12, atol=1e-12)
    assert np.all(np.isnan(out[2]))


def test_times_T_inverse_scales_a_1x1_T_by_the_task_jacobian():
    """A 1 x 1 T is singular when small against |J_x|, whatever its own ratio sigma_min / sigma_max (= 1)."""
    J_x = np.array([[[0.0, 0.0, 1.0]], [[0.0, 0.0, 1.0]]])
    T = np.array([[[1e-13]], [[0.2]]])
    out, singular = times_T_inverse(np.ones((2, 1, 1)), T, J_x)
    assert singular.tolist() == [True, False]
    assert np.isnan(out[0, 0, 0]) and out[1, 0, 0] == pytest.approx(5.0, rel=1e-15)


def _svd_singular(T: np.ndarray, J_x: np.ndarray) -> bool:
    """The singularity criterion of INVERSE_RTOL, from the singular values (the reference)."""
    return bool(np.linalg.svd(T, compute_uv=False)[-1] <= INVERSE_RTOL * np.linalg.norm(J_x, 2))


def _3d4m_rod2_vertical(d: float) -> np.ndarray:
    """The 3D4M (Harada 2011 eqs. (2)-(3)), plate lowered by d from rod 2 vertical (eq. (9))."""
    mech = preset("harada2011_3d4m")
    theta = -0.3
    y = 0.14 + RT * math.sin(theta) - d  # L_2y = y - r_t sin(theta) = l - d
    return prrrp_paper_configuration(mech, (0.0, y, theta), (0.14,) * 4, RT, (-1, 1, -1, 1))


@pytest.mark.parametrize("d", [0.0, 1e-15, 1e-12, 1e-9, 1e-6, 1e-3])
def test_singular_T_detection_agrees_with_the_svd_criterion_near_an_inverse_singularity(d):
    """Nearing the 3D4M's rod-2-vertical singularity, T is flagged exactly where the SVD criterion says."""
    mech = preset("harada2011_3d4m")
    jac = closed_chain_jacobians(mech, _3d4m_rod2_vertical(d))
    _, singular = times_T_inverse(jac.C, jac.T, jac.J_x)
    assert bool(singular) == _svd_singular(jac.T, jac.J_x)
    assert bool(singular) == (d == 0.0)  # sigma_min(T) grows like sqrt(d): 3e-8 already at d = 1e-15


def test_singular_T_detection_agrees_with_the_svd_criterion_around_its_threshold():
    """T of the singular 3D4M with sigma_min = f INVERSE_RTOL |J_x|: flagged iff f <= 1, single or batched."""
    mech = preset("harada2011_3d4m")
    jac = closed_chain_jacobians(mech, _3d4m_rod2_vertical(0.0))
    U, s, Vt = np.linalg.svd(jac.T)
    factors = [0.0, 1e-3, 0.5, 0.99, 1.01, 2.0, 10.0, 1e3, 1e6, 1e9]
    Ts = []
    for f in factors:
        s_f = s.copy()
        s_f[-1] = f * INVERSE_RTOL * np.linalg.norm(jac.J_x, 2)
        Ts.append(U @ np.diag(s_f) @ Vt)
    expected = [_svd_singular(T, jac.J_x) for T in Ts]
    assert expected == [f <= 1.0 for f in factors]  # the construction is exact to round-off
    for T, flag in zip(Ts, expected, strict=True):
        out, singular = times_T_inverse(jac.C, T, jac.J_x)
        assert bool(singular) == flag
        if not flag:  # the product is C T^-1 to the round-off of T's conditioning
            np.testing.assert_allclose(out @ T, jac.C, atol=1e-13 * np.linalg.cond(T))
    out, singular = times_T_inverse(np.stack([jac.C] * len(Ts)), np.stack(Ts), np.stack([jac.J_x] * len(Ts)))
    assert singular.tolist() == expected
    assert np.isnan(out[singular]).all() and np.isfinite(out[~singular]).all()


def test_feasible_motions_of_a_batch_span_each_null_space(rng):
    """On a stack, N spans scipy's null space of J_phi; T and C have its singular values."""
    mech = preset("zhao2011_8pss")
    jacs = [closed_chain_jacobians(mech, q) for q in _sampled_assemblies(mech, rng, 3)]
    J_phi, J_x = np.stack([j.J_phi for j in jacs]), np.stack([j.J_x for j in jacs])
    N, s, T, C = feasible_motions(J_phi, J_x, mech.actuated_v_indices, mech.mobility)
    for k in range(len(jacs)):  # N is defined up to a rotation: compare basis-free quantities
        Z = null_space(J_phi[k], rcond=1e-9)  # (nv, mobility)
        assert Z.shape[1] == mech.mobility
        np.testing.assert_allclose(N[k] @ N[k].T, Z @ Z.T, atol=1e-12)
        np.testing.assert_allclose(s[k], np.linalg.svd(J_phi[k], compute_uv=False), rtol=1e-12, atol=1e-13)
        for a, b in ((T[k], J_x[k] @ Z), (C[k], Z[mech.actuated_v_indices])):
            sv = np.linalg.svd(a, compute_uv=False)
            np.testing.assert_allclose(sv, np.linalg.svd(b, compute_uv=False), rtol=1e-12)


def _sampled_assemblies(mech, rng, n):
    """``n`` assembled configurations near the reference (the inverse kinematics of perturbed poses)."""
    x = task_pose(mech, mech.q_ref)
    return [inverse_kinematics(mech, x + rng.normal(scale=0.01, size=x.size), mech.q_ref).q for _ in range(n)]


def test_pseudo_inverse_gives_the_least_norm_solution_of_lstsq(rng):
    """The SVD pseudo-inverse solves as lstsq(rcond=RANK_RTOL) on rank-deficient and edge matrices."""
    cases = []
    for m, n, r in ((24, 30, 24), (24, 30, 20), (30, 24, 18), (6, 6, 5), (9, 4, 1)):
        cases.append(rng.normal(size=(m, r)) @ rng.normal(size=(r, n)))
    U, s, Vt = np.linalg.svd(rng.normal(size=(12, 15)), full_matrices=False)
    s[-3:] = s[0] * RANK_RTOL * np.array([10.0, 0.5, 0.0])  # one kept above the rule, two dropped
    cases += [U @ np.diag(s) @ Vt, np.zeros((4, 6))]
    for A in cases:
        b = rng.normal(size=A.shape[0])
        expected = np.linalg.lstsq(A, b, rcond=RANK_RTOL)[0]
        for svd in (np.linalg.svd(A), np.linalg.svd(A, full_matrices=False)):
            got = pseudo_inverse(*svd) @ b
            np.testing.assert_allclose(got, expected, rtol=0.0, atol=1e-12 * max(1.0, np.abs(expected).max()))


def test_closure_pseudo_inverse_is_given_or_computed_the_same():
    """closed_chain_jacobians' pseudo-inverse of J_phi (from its SVD) is the one computed from J_phi alone."""
    for name in ("zhao2011_8pss", "harada2011_3d4m", "fivebar"):
        mech = preset(name)
        jac = closed_chain_jacobians(mech, mech.q_ref)
        rebuilt = ClosedChainJacobians(jac.J_phi, jac.J_x, jac.N, jac.closure_singular_values, jac.T, jac.C)
        np.testing.assert_allclose(jac.closure_pinv, rebuilt.closure_pinv, atol=1e-12)
        np.testing.assert_allclose(jac.closure_pinv, np.linalg.pinv(jac.J_phi, rcond=RANK_RTOL), atol=1e-12)


def test_inverse_by_bound_is_given_only_where_the_svd_criterion_says_regular(rng):
    """inverse_if_regular returns inv(T) only where sigma_min(T) > rtol |J_x| and does so away from it."""
    J_x = rng.normal(size=(6, 30))
    N = np.linalg.qr(rng.normal(size=(30, 6)))[0]
    U, s, Vt = np.linalg.svd(J_x @ N)
    scale = np.linalg.norm(J_x, 2)
    for rtol in (INVERSE_RTOL, 1e-6):
        for f in (0.0, 0.5, 0.99, 1.01, 2.0, 10.0, 1e2, 1e4, 1e6):
            s_f = s.copy()
            s_f[-1] = min(f * rtol * scale, s[-2])
            T = U @ np.diag(s_f) @ Vt
            T_inv = inverse_if_regular(T, J_x, rtol)
            regular = np.linalg.svd(T, compute_uv=False)[-1] > rtol * scale
            if T_inv is not None:
                assert regular
                np.testing.assert_allclose(T_inv @ T, np.eye(6), atol=1e-13 * np.linalg.cond(T))
            if s_f[-1] > 2.0 * rtol * np.linalg.norm(J_x) * math.sqrt(6):  # the bound's slack: sure to pass
                assert T_inv is not None
        T_batch = np.stack([U @ np.diag(s) @ Vt, U @ np.diag(np.r_[s[:-1], 0.0]) @ Vt])
        assert (
            inverse_if_regular(T_batch, np.stack([J_x, J_x]), rtol) is None
        )  # one singular: the SVD decides
