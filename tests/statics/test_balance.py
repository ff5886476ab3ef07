"""The balance's QR factorisation against SVD and least-squares references; the internal basis convention."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import null_space
from scipy.optimize import linprog

from plm_pin.statics import static_balance, static_forces
from plm_pin.statics.balance import balance_factors, closure_factors, oriented_internal_basis
from tests.conftest import preset


def _random_case(rng, m, nv, n_act, rank=None):
    """A closure Jacobian (m, nv) of the given rank and the actuated velocities."""
    rank = m if rank is None else rank
    J = rng.normal(size=(m, rank)) @ rng.normal(size=(rank, nv))
    act = np.sort(rng.choice(nv, size=n_act, replace=False))
    return J, act


class _Mech:
    """The attributes balance_factors reads from a mechanism."""

    name = "random"
    closure_tol = 1e-12  # an exact description

    def __init__(self, mobility):
        self.mobility = mobility


CASES = [(6, 9, 4), (24, 30, 8), (5, 8, 3), (3, 7, 4)]  # (m, nv, n_act): redundant, square and rich


@pytest.mark.parametrize(("m", "nv", "n_act"), CASES)
@pytest.mark.parametrize("rank_drop", [0, 1])
def test_factors_match_svd_pseudo_inverses_on_random_balances(m, nv, n_act, rank_drop, rng):
    """N spans null(J) (scipy), lambda_map is pinv(J^T), P tau is pinv(Pi B) Pi tau; QR and SVD paths."""
    for _ in range(5):
        J, act = _random_case(rng, m, nv, n_act, m - rank_drop)
        N, lambda_map = closure_factors(J)
        reference = null_space(J, rcond=1e-10)
        np.testing.assert_allclose(N.T @ N, np.eye(N.shape[1]), atol=1e-13)
        np.testing.assert_allclose(N @ N.T, reference @ reference.T, atol=1e-12)
        np.testing.assert_allclose(lambda_map, np.linalg.pinv(J.T, rcond=1e-10), atol=1e-10)
        Pi = reference @ reference.T  # projector on the feasible motions, from scipy's SVD
        B = np.zeros((nv, n_act))
        B[act, np.arange(n_act)] = 1.0
        A = Pi @ B
        if np.linalg.matrix_rank(A.T @ A) < min(n_act, reference.shape[1]):
            continue  # a direct singularity of the random draw: not a well-posed case
        tau_held = B @ rng.normal(size=n_act) + J.T @ rng.normal(size=m)  # a load the actuators hold
        f = balance_factors(_Mech(nv - m), J, act, tau_held, 1e-8)
        f_ref = np.linalg.pinv(A, rcond=1e-10) @ (Pi @ tau_held)  # minimum norm of Pi (B f - tau) = 0
        np.testing.assert_allclose(f.P @ tau_held, f_ref, atol=1e-10 * max(1.0, np.max(np.abs(f_ref))))
        G_ref = null_space(A, rcond=1e-10)  # internal forces: B f balanced by the closures alone
        np.testing.assert_allclose(f.G @ f.G.T, G_ref @ G_ref.T, atol=1e-11)
        np.testing.assert_allclose(f.C, f.N[act], atol=0.0)
        gram = f.C.T @ f.C  # C's columns orthogonal, of decreasing norm
        np.testing.assert_allclose(gram - np.diag(np.diag(gram)), 0.0, atol=1e-12)
        assert np.all(np.diff(np.diag(gram)) <= 1e-12)


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_8pss"])
def test_min_norm_forces_equal_the_lp_free_least_squares_and_hold_the_load(name, rng):
    """f_p is the minimum-norm f with B f + J^T lam = tau (lstsq on the full balance, f weighted alone)."""
    mech = preset(name)
    bal = static_balance(mech, mech.q_ref, rng.normal(size=6))
    n_act, m = mech.n_actuators, bal.J_phi.shape[0]
    B = np.zeros((mech.nv, n_act))
    B[bal.actuated_v, np.arange(n_act)] = 1.0
    # minimum norm of f alone: lambda eliminated by the projector of scipy's null space of J_phi
    Z = null_space(bal.J_phi)
    f_ref = np.linalg.lstsq(Z.T @ B, Z.T @ bal.tau, rcond=None)[0]
    np.testing.assert_allclose(bal.f_particular, f_ref, atol=1e-9 * np.max(np.abs(f_ref)))
    # every balancing allocation is f_p + G y: an LP over (f, lam) finds the same range of f . g
    g = bal.internal_basis[:, 0]
    A_eq = np.hstack([B, bal.J_phi.T])
    for sign in (1.0, -1.0):
        c = np.concatenate([sign * g, np.zeros(m)])
        cap = 10.0 * np.max(np.abs(f_ref))
        bounds = [(-cap, cap)] * n_act + [(None, None)] * m
        lp = linprog(c, A_eq=A_eq, b_eq=bal.tau, bounds=bounds, method="highs")
        assert lp.status == 0
        f = lp.x[:n_act]
        residual = f - bal.f_particular
        np.testing.assert_allclose(
            residual, bal.internal_basis @ (bal.internal_basis.T @ residual), atol=1e-9 * cap
        )


def test_the_internal_basis_does_not_depend_on_the_basis_it_is_computed_from(rng):
    """Any orthonormal basis of the same space, rotated or reflected, gives the same oriented basis."""
    for n, k in [(4, 1), (8, 2), (9, 3), (6, 4)]:
        G0 = np.linalg.qr(rng.normal(size=(n, k)))[0]
        G = oriented_internal_basis(G0)
        for _ in range(5):
            R = np.linalg.qr(rng.normal(size=(k, k)))[0]  # any rotation or reflection
            np.testing.assert_allclose(oriented_internal_basis(G0 @ R), G, atol=1e-13)
        np.testing.assert_allclose(G.T @ G, np.eye(k), atol=1e-14)
        np.testing.assert_allclose(G @ G.T, G0 @ G0.T, atol=1e-14)


def test_the_internal_basis_is_pivoted_gram_schmidt_on_the_actuators(rng):
    """Column j: the normalised projection of the actuator with the largest remaining share, positive."""
    for n, k in [(4, 1), (8, 2), (9, 3)]:
        G = oriented_internal_basis(np.linalg.qr(rng.normal(size=(n, k)))[0])
        Pi = G @ G.T
        done = np.zeros((n, 0))
        for j in range(k):
            remaining = Pi - done @ done.T  # projector on the internal space left
            shares = np.linalg.norm(remaining, axis=0)
            p = int(np.argmax(shares))
            expected = remaining[:, p] / shares[p]
            np.testing.assert_allclose(G[:, j], expected, atol=1e-13)
            assert G[p, j] > 0.0
            done = np.column_stack([done, expected])


def test_ties_take_the_first_actuator():
    """Equal shares (a symmetric pose) pick the first actuator in order, not the one round-off favours."""
    g = np.array([0.5, -0.5, 0.5, -0.5])[:, None]
    np.testing.assert_array_equal(oriented_internal_basis(g), g)
    np.testing.assert_array_equal(oriented_internal_basis(-g), g)
    G = np.array([[1.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, -1.0]]).T / np.sqrt(2.0)
    np.testing.assert_allclose(oriented_internal_basis(G[:, ::-1]), G, atol=1e-15)


def test_3d4m_internal_force_has_its_largest_entry_positive_and_the_plate_reading_is_unchanged():
    """On the 3D4M the one internal force is a unit vector whose largest entry is positive."""
    mech = preset("harada2011_3d4m")
    g = static_balance(mech, mech.q_ref).internal_basis[:, 0]
    assert g[np.argmax(np.abs(g))] > 0.0
    assert np.linalg.norm(g) == pytest.approx(1.0, abs=1e-15)
    # the coordinate of a prescribed plate preload reads back in the same basis
    sol = static_forces(mech, mech.q_ref, gravity=False, internal={"plate": -2.0})
    np.testing.assert_allclose(sol.f_c, sol.internal[0] * g, atol=1e-12)
