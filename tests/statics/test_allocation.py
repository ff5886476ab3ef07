"""Bounded allocation against independent solvers (scipy SLSQP and HiGHS) on the same problems."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog, minimize

from plm_pin.exceptions import AllocationInfeasible
from plm_pin.kinematics import inverse_kinematics
from plm_pin.statics import static_balance, static_forces
from tests.conftest import preset


def _slsqp(balance, W, lower, upper, cap=None):
    """Min 1/2 f^T W f s.t. C^T f = N^T tau, lower <= f <= upper (and |f| <= cap), by SLSQP from f_p.

    Solved in forces scaled by the largest minimum-norm force, so that SLSQP's tolerances are relative.
    Its stopping tolerance is 1e-14, not 1e-16: the SLSQP of SciPy 1.17.1 (installed since) stops
    at the optimum of the 8-PSS min-peak problem with "Positive directional derivative for
    linesearch" below about 1e-15 (its answer already within 1.4e-14 of the optimum); the
    comparison tolerances are unchanged.
    """
    s = max(np.max(np.abs(balance.f_particular)), 1.0)
    A, b = balance.C.T, balance.N.T @ balance.tau / s
    cons = [{"type": "eq", "fun": lambda g: A @ g - b, "jac": lambda g: A}]
    bounds = [(lo / s, hi / s) for lo, hi in zip(lower, upper, strict=True)]
    if cap is not None:
        bounds = [(max(lo, -cap / s), min(hi, cap / s)) for lo, hi in bounds]
    res = minimize(
        lambda g: 0.5 * g @ W @ g,
        balance.f_particular / s,
        jac=lambda g: W @ g,
        constraints=cons,
        bounds=bounds,
        method="SLSQP",
        options={"ftol": 1e-14, "maxiter": 1000},
    )
    assert res.success, res.message
    return res.x * s


CASES = [
    ("harada2011_3d4m", [0.0, 1.0, 0.0], 0.8),
    ("zhao2011_8pss", None, 0.9),
]


@pytest.mark.parametrize(("name", "wrench", "fraction"), CASES)
@pytest.mark.parametrize("weighted", [False, True])
def test_bounded_weighted_min_norm_matches_slsqp(name, wrench, fraction, weighted, rng):
    """Weighted min-norm with limits below the free optimum's peak equals SLSQP's answer to 1e-8."""
    mech = preset(name)
    q = mech.q_ref
    n = mech.n_actuators
    W = np.diag(rng.uniform(0.5, 2.0, n)) if weighted else np.eye(n)
    free = static_forces(mech, q, wrench, weights=W)
    least = np.max(np.abs(static_forces(mech, q, wrench, objective="max").f_c))
    bound = least + fraction * (np.max(np.abs(free.f_c)) - least)
    limits = np.array([[-bound, bound]] * n)
    ours = static_forces(mech, q, wrench, weights=W, limits=limits)
    theirs = _slsqp(static_balance(mech, q, wrench), W, limits[:, 0], limits[:, 1])
    scale = max(np.max(np.abs(theirs)), 1.0)
    np.testing.assert_allclose(ours.f_c, theirs, atol=1e-8 * scale)
    assert ours.saturated


@pytest.mark.parametrize(("name", "wrench", "fraction"), CASES)
def test_min_max_matches_highs_then_slsqp(name, wrench, fraction):
    """The smallest peak force equals HiGHS's LP optimum; the tie-break is the min-norm at that peak."""
    mech = preset(name)
    q = mech.q_ref
    bal = static_balance(mech, q, wrench)
    n = mech.n_actuators
    A, b = bal.C.T, bal.N.T @ bal.tau
    # variables (f, t): min t s.t. A f = b, f - t <= 0, -f - t <= 0
    lp = linprog(
        np.r_[np.zeros(n), 1.0],
        A_ub=np.block([[np.eye(n), -np.ones((n, 1))], [-np.eye(n), -np.ones((n, 1))]]),
        b_ub=np.zeros(2 * n),
        A_eq=np.hstack([A, np.zeros((A.shape[0], 1))]),
        b_eq=b,
        bounds=[(None, None)] * (n + 1),
        method="highs",
    )
    assert lp.status == 0
    ours = static_forces(mech, q, wrench, objective="max")
    scale = max(lp.x[-1], 1.0)
    assert np.max(np.abs(ours.f_c)) == pytest.approx(lp.x[-1], abs=1e-8 * scale)
    theirs = _slsqp(bal, np.eye(n), np.full(n, -np.inf), np.full(n, np.inf), cap=lp.x[-1])
    np.testing.assert_allclose(ours.f_c, theirs, atol=1e-7 * scale)


def test_infeasible_limits_report_the_least_violating_allocation():
    """Limits below the minimum peak raise AllocationInfeasible with SLSQP's least-violating forces."""
    mech = preset("zhao2011_8pss")
    q = mech.q_ref
    least = np.max(np.abs(static_forces(mech, q, objective="max").f_c))
    bound = 0.9 * least
    with pytest.raises(AllocationInfeasible, match="least-violating allocation") as info:
        static_forces(mech, q, limits=[[-bound, bound]] * mech.n_actuators)
    err = info.value
    bal = static_balance(mech, q)
    A, b = bal.C.T, bal.N.T @ bal.tau

    def violation(f):
        return np.maximum(np.abs(f) - bound, 0.0)

    res = minimize(
        lambda f: 0.5 * violation(f) @ violation(f),
        bal.f_particular,
        constraints=[{"type": "eq", "fun": lambda f: A @ f - b}],
        method="SLSQP",
        options={"ftol": 1e-16, "maxiter": 1000},
    )
    ours = 0.5 * violation(err.partial) @ violation(err.partial)
    assert ours == pytest.approx(res.fun, rel=1e-6)
    assert np.max(np.abs(A @ err.partial - b)) <= 1e-9 * least
    assert set(err.saturated) == {
        a.joint for a, f in zip(mech.actuators, err.partial, strict=True) if abs(f) >= bound - 1e-6
    }
    assert err.saturated and set(err.violation) <= {a.joint for a in mech.actuators}


def test_non_redundant_limits_leave_no_choice():
    """On the 3D3M the only balancing forces are checked against the limits and reported when outside."""
    mech = preset("harada2011_3d3m")
    f = static_forces(mech, mech.q_ref, [0.0, 1.0, 0.0], gravity=False).f_c
    bound = 0.5 * np.max(np.abs(f))
    with pytest.raises(AllocationInfeasible) as info:
        static_forces(mech, mech.q_ref, [0.0, 1.0, 0.0], gravity=False, limits=[[-bound, bound]] * 3)
    np.testing.assert_allclose(info.value.partial, f, atol=1e-12)
    worst = mech.actuators[int(np.argmax(np.abs(f)))].joint
    assert worst in info.value.saturated


def test_preload_condition_puts_named_rods_in_compression():
    """link_limits: the 3D4M's rods 2 and 3 held in compression >= 2 N at min norm, as SLSQP finds."""
    mech = preset("harada2011_3d4m")
    q = mech.q_ref
    sol = static_forces(
        mech,
        q,
        [0.0, 1.0, 0.0],
        gravity=False,
        link_limits={"rod2": (-np.inf, -2.0), "rod3": (-np.inf, -2.0)},
    )
    links = sol.link_forces()
    assert links["rod2"].axial <= -2.0 + 1e-9 and links["rod3"].axial <= -2.0 + 1e-9
    assert sol.active  # the preload binds
    # independent: the rod axial force is -f_c / (z . a) per slider (eq. (17)), linear in f_c
    z_a = {i: links[f"rod{i}"].axis[0] for i in (2, 3)}
    bal = static_balance(mech, q, [0.0, 1.0, 0.0], gravity=False)
    A, b = bal.C.T, bal.N.T @ bal.tau
    cons = [{"type": "eq", "fun": lambda f: A @ f - b}] + [
        {"type": "ineq", "fun": lambda f, i=i: f[i - 1] / z_a[i] - 2.0} for i in (2, 3)
    ]
    res = minimize(
        lambda f: 0.5 * f @ f, bal.f_particular, constraints=cons, method="SLSQP", options={"ftol": 1e-16}
    )
    np.testing.assert_allclose(sol.f_c, res.x, atol=1e-8)


def test_every_rod_in_compression_is_infeasible_for_the_3d4m_internal_force():
    """The internal-force direction loads a pair's two rods in opposite senses: all-compression is refused."""
    mech = preset("harada2011_3d4m")
    (direction,) = static_forces(mech, mech.q_ref, gravity=False).internal_directions()
    signs = {k: np.sign(v.axial) for k, v in direction.link_forces.items() if k.startswith("rod")}
    assert signs["rod1"] == -signs["rod2"] and signs["rod3"] == -signs["rod4"]
    with pytest.raises(AllocationInfeasible, match="rod"):
        static_forces(mech, mech.q_ref, [0.0, 1.0, 0.0], gravity=False, min_compression=5.0)


def test_preload_where_proxsuite_stalled_is_the_closed_form_interval():
    """3D4M, pose (0, 0.04 m, 35 deg), f_x = 1 N, every link compressed: the 1-D problem solved exactly.

    ProxSuite's least-violation QP stopped there at 1000 iterations (dual residual 1.07e-11 for a
    tolerance of 1e-11). With one internal force y, each hinged link's axial force is a_l + b_l y
    (b_l from the internal-force direction), and the least |y| keeping all of them <= 0 is 0 clipped to the
    interval those inequalities leave.
    """
    mech = preset("harada2011_3d4m")
    q = inverse_kinematics(mech, [0.0, 0.04, np.radians(35.0)]).q
    sol = static_forces(mech, q, [1.0, 0.0, 0.0], limits=None, min_compression=0.0)
    free = static_forces(mech, q, [1.0, 0.0, 0.0], limits=None)
    (direction,) = free.internal_directions()
    a = {k: v.axial for k, v in free.link_forces().items()}
    b = {k: v.axial for k, v in direction.link_forces.items()}
    lo = max((-a[k] / b[k] for k in a if b[k] < 0.0), default=-np.inf)
    hi = min((-a[k] / b[k] for k in a if b[k] > 0.0), default=np.inf)
    assert lo <= hi
    assert sol.internal[0] == pytest.approx(np.clip(0.0, lo, hi), abs=1e-9)
    assert max(v.axial for v in sol.link_forces().values()) <= 1e-9
