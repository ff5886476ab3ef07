"""Closed-chain inverse dynamics against independent paths: energy balance, statics, forward simulation."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from scipy.interpolate import CubicSpline

from analyses._enferadi2017_paper import enferadi2017_circle, enferadi2017_line
from analyses._zhao2011_paper import ZHAO2011_TRAJECTORY_DURATION, zhao2011_trajectory
from plm_pin.dynamics import simulate, task_trajectory
from plm_pin.dynamics.inverse_dynamics import inverse_dynamics
from plm_pin.dynamics.work import adaptive_trapezoid_work, power_along, spline_work
from plm_pin.exceptions import AllocationInfeasible, InvalidInput, InverseDynamicsFailed
from plm_pin.statics import static_forces
from tests.conftest import preset
from tests.dynamics.conftest import direct_crossing


def _harada_profile(t):
    """A smooth planar motion of the 3D4M plate around its reference pose."""
    x0 = np.array([0.0, 0.08, np.radians(-20.0)])
    amp = np.array([0.02, 0.01, 0.2])
    w = np.array([2.0, 3.0, 2.5])
    return x0 + amp * np.sin(w * t), amp * w * np.cos(w * t), -amp * w**2 * np.sin(w * t)


def _energy(mech, traj):
    E = []
    for q, v in zip(traj.q, traj.v, strict=True):
        E.append(
            pin.computeKineticEnergy(mech.model, mech.data, q, v)
            + pin.computePotentialEnergy(mech.model, mech.data, q)
        )
    return np.array(E)


@pytest.mark.parametrize(
    ("name", "profile", "duration"),
    [
        ("harada2011_3d4m", _harada_profile, 1.0),
        ("enferadi2017_star_triangle", enferadi2017_circle, 2.0),
        ("zhao2011_8pss", zhao2011_trajectory, ZHAO2011_TRAJECTORY_DURATION),
    ],
)
def test_actuator_power_equals_the_rate_of_energy(name, profile, duration):
    """sum_i f_c,i cdot_i = dE/dt (kinetic + potential from Pinocchio, differentiated along time)."""
    mech = preset(name)
    t = np.linspace(0.0, duration, 401)
    traj = task_trajectory(mech, profile, t)
    idr = inverse_dynamics(mech, traj)
    dEdt = CubicSpline(t, _energy(mech, traj))(t, 1)
    total = idr.power.sum(axis=1)
    inner = slice(10, -10)  # the spline's end conditions are less accurate
    scale = np.max(np.abs(idr.power).sum(axis=1))  # the actuators' powers may cancel in the sum
    np.testing.assert_allclose(total[inner], dEdt[inner], atol=2e-4 * scale)
    assert idr.residual.max() <= 1e-9 * max(np.max(np.abs(idr.f_c)), 1.0)


def test_to_dict_is_strict_json_with_missing_leads_as_text():
    """Actuators without a ball screw have a NaN lead, written as 'nan' (JSON has no NaN)."""
    mech = preset("harada2011_3d4m")
    idr = inverse_dynamics(mech, task_trajectory(mech, _harada_profile, np.linspace(0.0, 1.0, 5)))
    assert np.isnan(idr.leads).all()
    data = json.loads(json.dumps(idr.to_dict(), allow_nan=False))
    assert data["leads"] == ["nan"] * 4 and data["f_c"] == idr.f_c.tolist()


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_8pss"])
def test_term_and_body_shares_add_up_and_gravity_is_statics(name):
    """Shares sum to f_c; the gravity share is the static allocation; at rest only gravity remains."""
    mech = preset(name)
    harada = name.startswith("harada")
    profile = _harada_profile if harada else zhao2011_trajectory
    t = np.linspace(0.0, 1.0 if harada else ZHAO2011_TRAJECTORY_DURATION, 21)
    traj = task_trajectory(mech, profile, t)
    idr = inverse_dynamics(mech, traj)
    assert idr.split_exact
    scale = np.max(np.abs(idr.f_c))
    np.testing.assert_allclose(sum(idr.terms.values()), idr.f_c, atol=1e-10 * scale)
    np.testing.assert_allclose(sum(idr.bodies.values()), idr.f_c, atol=1e-10 * scale)
    for i in (0, 10, 20):
        np.testing.assert_allclose(
            idr.terms["gravity"][i], static_forces(mech, traj.q[i]).f_c, atol=1e-9 * scale
        )
    # inertia share: the minimum-norm forces of M a computed by CRBA (armature on the diagonal)
    M = pin.crba(mech.model, mech.data, traj.q[5])
    inertia_only = inverse_dynamics(mech, traj, gravity=False)
    np.testing.assert_allclose(inertia_only.terms["inertia"][5], idr.terms["inertia"][5], atol=1e-10 * scale)
    assert np.max(np.abs(M @ traj.a[5])) > 0


def test_zhao_rotor_share_is_the_reflected_inertia():
    """The rotor-coupler share on an 8-PSS slider equals the min-norm forces of J_rotor (2 pi / p)^2 cddot."""
    mech = preset("zhao2011_8pss")
    t = np.linspace(0.0, ZHAO2011_TRAJECTORY_DURATION, 31)
    traj = task_trajectory(mech, zhao2011_trajectory, t)
    idr = inverse_dynamics(mech, traj)
    spec = mech.sidecar.actuation[0]
    reflected = spec.rotor_inertia * (2 * np.pi / spec.lead) ** 2  # 391.6 kg (spec, section 5)
    assert reflected == pytest.approx(0.0248 * 15791.367, rel=1e-6)
    # min-norm forces are linear: the rotor share is what the allocation makes of reflected * cddot
    one = inverse_dynamics(mech, traj, groups={"platform": ["platform"]})
    np.testing.assert_allclose(one.bodies["rotor"], idr.bodies["rotor"], atol=1e-9)
    assert np.max(np.abs(idr.bodies["rotor"])) > np.max(np.abs(idr.bodies["screw"]))


def test_round_trip_through_forward_simulation_reproduces_the_path():
    """Enferadi 2017 circle: forces from inverse dynamics, simulated forward, retrace the path to 1e-6 m."""
    mech = preset("enferadi2017_star_triangle")
    t = np.linspace(0.0, 2.0, 801)
    traj = task_trajectory(mech, enferadi2017_circle, t)
    idr = inverse_dynamics(mech, traj)
    forces = CubicSpline(t, idr.f_c)
    run = simulate(
        mech,
        traj.q[0],
        traj.v[0],
        duration=2.0,
        dt=0.05,
        actuator_forces=lambda time, q, v: forces(time),
        method="adaptive",
        rtol=1e-11,
        atol=1e-13,
    )
    expected = np.array([enferadi2017_circle(s)[0] for s in run.t])
    assert np.max(np.abs(run.x - expected)[:, :2]) <= 1e-6


def test_limits_make_the_split_inexact_and_an_infeasible_sample_stops_with_the_samples_before():
    """Bounded allocation adds an 'allocation' share; limits that fail mid-way stop at that sample."""
    mech = preset("harada2011_3d4m")
    t = np.linspace(0.0, 1.0, 41)
    traj = task_trajectory(mech, _harada_profile, t)
    free = inverse_dynamics(mech, traj)
    peak = np.max(np.abs(free.f_c), axis=1)
    bound = 0.5 * (peak.min() + peak.max())
    with pytest.raises(InverseDynamicsFailed, match="stopped at sample") as info:
        inverse_dynamics(mech, traj, limits=[(-bound, bound)] * 4, objective="norm")
    err = info.value
    assert isinstance(err.cause, AllocationInfeasible) and err.cause.saturated
    assert err.partial.n_samples == err.index and err.time == pytest.approx(t[err.index])
    first_over = int(
        np.argmax(np.max(np.abs(inverse_dynamics(mech, traj, objective="max").f_c), axis=1) > bound)
    )
    assert err.index == first_over
    loose = inverse_dynamics(mech, traj, objective="max")
    assert not loose.split_exact
    np.testing.assert_allclose(sum(loose.terms.values()), loose.f_c, atol=1e-12)


def test_spline_and_trapezoid_work_against_a_closed_form():
    """|sin| over [0, 3 pi] integrates to 6: both quadratures get it, the trapezoid with its n1."""
    t = np.linspace(0.0, 3 * np.pi, 200)
    both = np.column_stack([np.sin(t), 2 * np.sin(t)])
    np.testing.assert_allclose(spline_work(t, both), [6.0, 12.0], rtol=1e-6)
    res = adaptive_trapezoid_work(lambda s: np.sin(s)[:, None], 0.0, 3 * np.pi, tol=1e-6)
    assert res.work[0] == pytest.approx(6.0, abs=1e-5)
    grid = np.linspace(0.0, 3 * np.pi, 2 ** (res.n1 - 1) + 1)  # the rule stopped because this one was close
    assert abs(np.trapezoid(np.abs(np.sin(grid)), grid) - res.work[0]) <= 1e-6
    assert res.to_dict() == {
        "work": res.work.tolist(),
        "n1": res.n1,
        "change": res.change.tolist(),
        "intervals": 2**res.n1,
    }
    with pytest.raises(InvalidInput, match="need finite ts < te"):
        adaptive_trapezoid_work(lambda s: s[:, None], 1.0, 0.0)


def test_trapezoid_that_does_not_converge_says_by_how_much():
    """No convergence by 2**n_max intervals: the message gives the tolerance and the last change."""
    t4, t8 = (np.linspace(0.0, 3 * np.pi, k + 1) for k in (4, 8))
    last = abs(np.trapezoid(np.abs(np.sin(t8)), t8) - np.trapezoid(np.abs(np.sin(t4)), t4))
    with pytest.raises(
        InvalidInput,
        match=rf"did not converge to 1e-12 J with 2\*\*3 intervals; the last change was {last:.6g} J",
    ):
        adaptive_trapezoid_work(lambda s: np.sin(s)[:, None], 0.0, 3 * np.pi, tol=1e-12, n_max=3)
    with pytest.raises(InvalidInput, match=r"with 2\*\*1 intervals$"):  # one rule: no change to give
        adaptive_trapezoid_work(lambda s: np.sin(s)[:, None], 0.0, 3 * np.pi, tol=1e-12, n_max=1)


@pytest.mark.slow
def test_zhao_work_by_both_quadratures_agree():
    """Zhao 2011 eqs. (30)-(34): the adaptive trapezoid (tol 1e-3 J) and the spline agree to 0.01 J."""
    mech = preset("zhao2011_8pss")
    power = power_along(mech, zhao2011_trajectory)
    trap = adaptive_trapezoid_work(power, 0.0, ZHAO2011_TRAJECTORY_DURATION, n_max=13)
    t = np.linspace(0.0, ZHAO2011_TRAJECTORY_DURATION, 2049)
    spline = spline_work(t, power(t))
    np.testing.assert_allclose(trap.work, spline, atol=1e-2)
    assert 9 <= trap.n1 <= 13


@pytest.mark.parametrize(
    ("profile", "times", "expected"),
    [
        (
            enferadi2017_line,
            [1.0, 2.0, 4.0],
            [(-0.239237, 0.239237, 0.0), (0.0, 0.0, 0.0), (0.338332, -0.338332, 0.0)],
        ),
        (
            enferadi2017_circle,
            [0.0, 0.25, 0.3, 0.5, 0.75],
            [
                (-2.254403, -2.254403, 3.605675),
                (-3.986470, 0.798263, 2.549597),
                (-4.062266, 1.412056, 2.119362),
                (-3.383317, 3.383317, 0.0),
                (-0.798263, 3.986470, -2.549597),
            ],
        ),
    ],
    ids=["line", "circle"],
)
def test_enferadi_forces_match_the_corrected_lagrange_equations(profile, times, expected):
    """Enferadi 2017 section 6: f_q from the corrected eqs. (25)-(31) (analyses/specs/enferadi2017.md, 5)."""
    mech = preset("enferadi2017_star_triangle")
    grid = np.linspace(0.0, times[-1], round(times[-1] / 0.05) + 1)
    traj = task_trajectory(mech, profile, grid)
    idr = inverse_dynamics(mech, traj)
    for t, f in zip(times, expected, strict=True):
        k = int(np.argmin(np.abs(grid - t)))
        assert grid[k] == pytest.approx(t)
        np.testing.assert_allclose(idr.f_c[k], f, atol=2e-6)  # the spec prints 6 decimals


def test_crossing_a_direct_singularity_stops_at_the_first_sample_past_it():
    """3D3M, theta 0 -> -50 deg at y = 0.08 m: stops past eq. (11.4)'s angle, keeping the samples before."""
    mech, _, traj, first_past = direct_crossing()
    with pytest.raises(InverseDynamicsFailed, match="direct \\(type 2\\) singularity") as info:
        inverse_dynamics(mech, traj)
    assert info.value.index == first_past and info.value.partial.n_samples == first_past


@pytest.mark.parametrize("gravity", [True, False])
def test_body_shares_match_rnea_on_a_model_holding_that_body_alone(gravity):
    """A body's share = min-norm forces of RNEA on a model copy whose only inertia is that body's."""
    from plm_pin.statics import AllocationRule, solve_balance
    from plm_pin.statics.balance import generalized_balance

    mech = preset("harada2011_3d4m")
    t = np.linspace(0.0, 1.0, 6)
    traj = task_trajectory(mech, _harada_profile, t)
    idr = inverse_dynamics(mech, traj, gravity=gravity)
    rule = AllocationRule.checked(mech)
    for j, name in [(2, mech.body_names[1]), (3, mech.body_names[2])]:
        alone = pin.Model(mech.model)
        for k in range(1, alone.njoints):
            if k != j:
                alone.inertias[k] = pin.Inertia.Zero()
        alone.armature = np.zeros(alone.nv)
        data = alone.createData()
        for i in (1, 4):
            q, v, a = traj.q[i], traj.v[i], traj.a[i]
            tau = pin.rnea(alone, data, q, v, a)
            if not gravity:
                tau = tau - pin.computeGeneralizedGravity(alone, data, q)
            expected = solve_balance(mech, generalized_balance(mech, q, tau), rule).f_c
            assert np.abs(expected).max() > 1e-4  # the body does load the actuators
            np.testing.assert_allclose(idr.bodies[name][i], expected, atol=1e-10 * np.abs(expected).max())


def test_a_time_varying_wrench_adds_its_static_allocation_at_each_sample():
    """wrench=t -> w(t): the forces minus the unloaded ones are static_forces' allocation of w(t_i) at q_i."""
    mech = preset("harada2011_3d4m")
    t = np.linspace(0.0, 1.0, 11)
    traj = task_trajectory(mech, _harada_profile, t)

    def wrench(s):
        return [2.0 * s, -1.0, 0.1 * s]  # fx [N], fy [N], mz [N m] on the task frame

    loaded = inverse_dynamics(mech, traj, wrench=wrench, limits=None)
    unloaded = inverse_dynamics(mech, traj, limits=None)
    for i in (0, 5, 10):
        alone = static_forces(mech, traj.q[i], wrench(t[i]), gravity=False, limits=None).f_c
        assert np.abs(alone).max() > 0.1  # the wrench does load the actuators
        np.testing.assert_allclose(loaded.f_c[i] - unloaded.f_c[i], alone, atol=1e-9 * np.abs(alone).max())


def test_result_pickles_with_its_body_split():
    """An InverseDynamics pickles; the lazily computed body split travels as a plain dictionary."""
    import pickle

    mech = preset("harada2011_3d4m")
    traj = task_trajectory(mech, _harada_profile, np.linspace(0.0, 0.5, 6))
    idr = inverse_dynamics(mech, traj)
    back = pickle.loads(pickle.dumps(idr))
    assert set(back.bodies) == set(idr.bodies)
    for name in idr.bodies:
        np.testing.assert_array_equal(back.bodies[name], idr.bodies[name])
