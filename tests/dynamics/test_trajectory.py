"""Trajectories on the closure manifold (plm_pin/dynamics/trajectory.py).

Oracles: the closure residual and drift recomputed from Pinocchio; five-point differences in time
of inverse-kinematics solutions solved independently; the papers' closed forms: Harada 2011 eqs.
(2), (4) and (11.4) (analyses/_harada2011_paper.py), Zhao 2011's strut-length equation and eq. (35),
Enferadi 2017's velocity map at phi = pi/2 and the section 6 ranges of analyses/specs/enferadi2017.md.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pinocchio as pin
import pytest

from analyses import _harada2011_paper as paper
from analyses._enferadi2017_paper import enferadi2017_circle, enferadi2017_line
from analyses._zhao2011_paper import (
    ZHAO2011_TRAJECTORY_A_MAX,
    ZHAO2011_TRAJECTORY_DURATION,
    zhao2011_trajectory,
)
from plm_pin.core import closures
from plm_pin.core.mechanism import Mechanism
from plm_pin.description.sidecar import TaskSpec
from plm_pin.dynamics.trajectory import (
    JointTrajectory,
    actuator_trajectory,
    differentiated_profile,
    sampled_profile,
    task_trajectory,
)
from plm_pin.exceptions import (
    ClosureNotSatisfied,
    InvalidInput,
    PoseUnreachable,
    SingularConfiguration,
    TrajectoryError,
)
from plm_pin.families.pss import pss_inverse_kinematics
from plm_pin.families.star_triangle import star_triangle_inverse_kinematics
from plm_pin.kinematics import closed_chain_jacobians, inverse_kinematics, task_pose, working_modes
from plm_pin.kinematics.singularity import constraint_margins, inverse_margins
from plm_pin.kinematics.working_mode import working_mode
from plm_pin.models import PRESETS
from tests.conftest import preset, spatial_6r
from tests.dynamics.conftest import direct_crossing

ZHAO2011 = PRESETS["zhao2011_8pss"].parameters  # Zhao 2011 Tables 1-3, eq. (19): the preset's parameters

L, RT = 0.140, 0.05  # Harada 2011 Table 1
T_ZHAO = ZHAO2011_TRAJECTORY_DURATION

# amplitude of a sinusoid about the reference pose per preset [m, rad], inside the workspace and
# clear of singularities (the 3D3M's rotation runs against y, away from its eq. (11.4) locus)
AMPLITUDE = {
    "enferadi2017_star_triangle": [0.03, -0.04, 0.2],
    "fivebar": [0.02, -0.01],
    "fourbar": [0.05],
    "harada2011_3d3m": [0.01, 0.01, -0.05],
    "harada2011_3d4m": [0.01, -0.02, 0.15],
    "harada2015_asymmetric": [-0.01, 0.02, -0.15],
    "zhao2011_6pss": [0.03, -0.02, -0.04, 0.03, -0.02, 0.04],
    "zhao2011_8pss": [-0.02, 0.03, 0.04, -0.03, 0.02, 0.05],
}


def wave(x0, amplitude, period: float = 1.0):
    """Profile x0 + A sin(2 pi t / period) with its analytic derivatives."""
    x0, amplitude = np.asarray(x0, float), np.asarray(amplitude, float)
    w = 2.0 * math.pi / period

    def profile(t):
        s, c = math.sin(w * t), math.cos(w * t)
        return x0 + amplitude * s, amplitude * w * c, -amplitude * w * w * s

    return profile


def five_point(f, t: float, h: float):
    """First and second derivatives of f at t by five-point central differences."""
    fm2, fm1, f0, fp1, fp2 = (np.asarray(f(t + j * h), float) for j in (-2, -1, 0, 1, 2))
    return (fm2 - 8 * fm1 + 8 * fp1 - fp2) / (12 * h), (-fm2 + 16 * (fm1 + fp1) - 30 * f0 - fp2) / (
        12 * h * h
    )


def reference_wave(name):
    mech = preset(name)
    return mech, wave(task_pose(mech, mech.q_ref), AMPLITUDE[name])


def zhao_sliders(pose, legs) -> np.ndarray:
    """Slider positions of the strut-length equation (closed form) [m]."""
    ik = pss_inverse_kinematics(
        pose,
        ZHAO2011["guide_points"],
        ZHAO2011["guide_directions"],
        ZHAO2011["platform_points"],
        ZHAO2011["strut_lengths"],
        legs,
    )
    return np.array([ik[i][0] for i in legs])


# ---------------------------------------------------------------- on the closure manifold
@pytest.mark.parametrize("name", sorted(AMPLITUDE))
def test_samples_close_the_loops_at_position_velocity_and_acceleration_level(name):
    """Each sample: phi(q) <= 1e-10, J_phi v = 0, J_phi a + Jdot_phi v = 0, the task frame on the profile."""
    mech, profile = reference_wave(name)
    times = np.linspace(0.0, 1.0, 41)
    tr = task_trajectory(mech, profile, times)
    data = mech.model.createData()
    for k in range(tr.n_samples):
        q, v, a = tr.q[k], tr.v[k], tr.a[k]
        assert np.max(np.abs(mech.closure_residual(q)), initial=0.0) <= 1e-10
        assert tr.residual[k] <= 1e-10
        J = mech.closure_jacobian(q)
        gamma = closures.drift(mech.model, data, mech.closures, q, v)
        scale_v, scale_a = 1.0 + np.max(np.abs(v)), 1.0 + np.max(np.abs(a))
        assert np.max(np.abs(J @ v), initial=0.0) <= 1e-12 * scale_v
        assert np.max(np.abs(J @ a + gamma), initial=0.0) <= 1e-12 * scale_a
        x, xd, xdd = profile(times[k])
        np.testing.assert_allclose(task_pose(mech, q), x, atol=1e-11)
        if not name.startswith("zhao"):  # translations and planar angles: twist rows = coordinate rates
            np.testing.assert_allclose(tr.xd[k], xd, atol=1e-11)
            np.testing.assert_allclose(tr.xdd[k], xdd, atol=1e-10)
    assert tr.max_residual <= 1e-10


@pytest.mark.parametrize(
    "name", ["enferadi2017_star_triangle", "fourbar", "harada2011_3d4m", "zhao2011_6pss", "zhao2011_8pss"]
)
def test_velocity_and_acceleration_are_time_derivatives_of_the_ik_path(name):
    """The v and a equal five-point differences in time of IK solutions at t +- h, t +- 2h, solved apart."""
    mech, profile = reference_wave(name)
    times = np.linspace(0.0, 1.0, 9)
    tr = task_trajectory(mech, profile, times)
    h = 1e-3
    for k in range(0, tr.n_samples, 2):
        q0 = tr.q[k]

        def tangent(t, q0=q0):
            return pin.difference(mech.model, q0, inverse_kinematics(mech, profile(t)[0], q0).q)

        v_fd, a_fd = five_point(tangent, float(times[k]), h)
        np.testing.assert_allclose(tr.v[k], v_fd, atol=1e-9 * (1 + np.max(np.abs(v_fd))))
        np.testing.assert_allclose(tr.a[k], a_fd, atol=2e-8 * (1 + np.max(np.abs(a_fd))))


@pytest.mark.parametrize(
    ("closure", "dofs", "amplitude"),
    [
        ({"type": "revolute", "axis": [0, 0.6, 0.8]}, ("rz",), [0.2]),
        ({"type": "revolute", "axis": [0, 0.6, 0.8]}, ("rx",), [0.2]),
        ({"type": "point"}, ("rx", "ry", "rz"), [0.03, -0.03, 0.05]),
    ],
)
def test_rpy_rates_of_any_angle_selection_on_a_skew_spatial_chain(tmp_path, closure, dofs, amplitude):
    """6R loop turning about skew axes, task = some rpy angles: v and a are time derivatives of IK."""
    base = spatial_6r(tmp_path, closure)
    mech = Mechanism(base.model, dataclasses.replace(base.sidecar, task=TaskSpec("tip", dofs)), name="6r")
    profile = wave(task_pose(mech, mech.q_ref), amplitude)
    times = np.linspace(0.0, 1.0, 5)
    tr = task_trajectory(mech, profile, times)
    for k, t in enumerate(times):
        q0 = tr.q[k]

        def tangent(s, q0=q0):
            return pin.difference(mech.model, q0, inverse_kinematics(mech, profile(s)[0], q0).q)

        v_fd, a_fd = five_point(tangent, float(t), 1e-3)
        np.testing.assert_allclose(tr.v[k], v_fd, atol=1e-8 * (1 + np.max(np.abs(v_fd))))
        np.testing.assert_allclose(tr.a[k], a_fd, atol=2e-8 * (1 + np.max(np.abs(a_fd))))


# ---------------------------------------------------------------- the papers
def test_harada_3d4m_actuator_motion_is_eq2_and_rates_are_eq4():
    """Sliders follow eq. (2), rates J_ce xdot (J_ce = J_c^-1 J_e, eq. (4)), accelerations d2/dt2 of (2)."""
    mech, profile = reference_wave("harada2011_3d4m")
    legs = (1, 2, 3, 4)
    times = np.linspace(0.0, 1.0, 21)
    tr = task_trajectory(mech, profile, times)
    for k, t in enumerate(times):
        x, xd, _ = profile(t)
        c = paper.slider_positions(x, L, RT, legs)
        np.testing.assert_allclose(tr.c[k], c, atol=1e-11)
        np.testing.assert_allclose(tr.cd[k], paper.J_ce(x, c, L, RT, legs) @ xd, atol=1e-11)
        _, cdd = five_point(lambda s: paper.slider_positions(profile(s)[0], L, RT, legs), float(t), 1e-3)
        np.testing.assert_allclose(tr.cdd[k], cdd, atol=2e-8)


def test_zhao_slider_motion_along_eq35_is_the_strut_length_closed_form():
    """Fig. 4: slider positions, rates, accelerations along eq. (35) are the closed-form 8-PSS IK in time."""
    mech = preset("zhao2011_8pss")
    legs = [int(a.joint.removeprefix("slider")) for a in mech.actuators]
    times = np.linspace(0.0, T_ZHAO, 11)
    tr = task_trajectory(mech, zhao2011_trajectory, times)
    for k, t in enumerate(times):
        np.testing.assert_allclose(tr.c[k], zhao_sliders(zhao2011_trajectory(t)[0], legs), atol=1e-11)
        cd, cdd = five_point(lambda s: zhao_sliders(zhao2011_trajectory(s)[0], legs), float(t), 1e-3)
        np.testing.assert_allclose(tr.cd[k], cd, atol=1e-8)
        np.testing.assert_allclose(tr.cdd[k], cdd, atol=5e-8 * ZHAO2011_TRAJECTORY_A_MAX)
    # the spec's table (analyses/specs/zhao2011.md section 2): q_i at the start and end poses
    np.testing.assert_allclose(
        tr.c[0], [0.580153, 0.494156, 0.404128, 0.490058, 0.221715, 0.285388, 0.189031, 0.273655], atol=1e-6
    )
    np.testing.assert_allclose(
        tr.c[-1], [0.619145, 0.691820, 0.763145, 0.690411, 0.500247, 0.442044, 0.516121, 0.476501], atol=1e-6
    )


def test_zhao_rpy_rates_become_the_platform_angular_velocity():
    """xd[3:] and xdd[3:] are the world angular velocity and acceleration of R(t) = Rz Ry Rx of eq. (35)."""
    mech = preset("zhao2011_8pss")
    times = np.linspace(0.0, T_ZHAO, 6)
    tr = task_trajectory(mech, zhao2011_trajectory, times)

    def omega(t, d=1e-5):
        R = [pin.rpy.rpyToMatrix(zhao2011_trajectory(t + s)[0][3:]) for s in (-d, d)]
        return pin.log3(R[1] @ R[0].T) / (2 * d)

    for k, t in enumerate(times):
        np.testing.assert_allclose(tr.xd[k, 3:], omega(t), atol=1e-8)
        np.testing.assert_allclose(tr.xdd[k, 3:], five_point(omega, float(t), 1e-3)[0], atol=1e-7)
        np.testing.assert_allclose(tr.xd[k, :3], zhao2011_trajectory(t)[1][:3], atol=1e-11)
        np.testing.assert_allclose(tr.xdd[k, :3], zhao2011_trajectory(t)[2][:3], atol=1e-10)


@pytest.mark.parametrize(
    ("path", "duration", "ranges"),
    [
        (enferadi2017_line, 8.0, [(0.254904, 0.428109), (0.071891, 0.245096), (0.25, 0.25)]),
        (enferadi2017_circle, 2.0, [(0.279007, 0.404006), (0.095994, 0.220993), (0.1875, 0.3125)]),
    ],
)
def test_enferadi_paths_follow_the_phi_half_pi_velocity_map(path, duration, ranges):
    """Section 6 paths: q of eqs. (4)-(5), qdot = H xdot, qddot = H xddot, H constant at phi = pi/2."""
    mech = preset("enferadi2017_star_triangle")
    times = np.linspace(0.0, duration, 241)  # holds every slider extreme (t = k/3 on the circle)
    tr = task_trajectory(mech, path, times)
    H = np.array([[0.5, math.sqrt(3) / 2], [0.5, -math.sqrt(3) / 2], [-1.0, 0.0]])  # columns x, y; phi fixed
    for k, t in enumerate(times):
        x, xd, xdd = path(t)
        np.testing.assert_allclose(tr.c[k], star_triangle_inverse_kinematics(x, 0.5)[0], atol=1e-12)
        np.testing.assert_allclose(tr.cd[k], H @ xd[:2], atol=1e-12)
        np.testing.assert_allclose(tr.cdd[k], H @ xdd[:2], atol=1e-12)
    # the spec's slider ranges (analyses/specs/enferadi2017.md section 5)
    np.testing.assert_allclose(np.column_stack([tr.c.min(axis=0), tr.c.max(axis=0)]), ranges, atol=1e-6)


@pytest.mark.parametrize(("path", "duration"), [(enferadi2017_line, 8.0), (enferadi2017_circle, 2.0)])
def test_enferadi_profiles_are_the_paper_formulas_with_their_derivatives(path, duration):
    """Section 6 profiles: rates and accelerations are differences of the positions; the spec's extremes."""
    for t in np.linspace(0.0, duration, 7):
        xd, xdd = five_point(lambda s: path(s)[0], float(t), 1e-3)
        np.testing.assert_allclose(path(t)[1], xd, atol=1e-10)
        np.testing.assert_allclose(path(t)[2], xdd, atol=1e-8)
    speed = max(np.linalg.norm(path(t)[1]) for t in np.linspace(0.0, duration, 801))
    accel = max(np.linalg.norm(path(t)[2]) for t in np.linspace(0.0, duration, 801))
    if path is enferadi2017_line:
        np.testing.assert_allclose(path(0.0)[0], [0.25, 0.35, math.pi / 2])
        np.testing.assert_allclose(path(4.0)[0], [0.25, 0.15, math.pi / 2])
        assert (speed, accel) == pytest.approx((0.0785, 0.0617), abs=5e-5)
    else:
        np.testing.assert_allclose(path(0.0)[0], [0.3125, 0.25, math.pi / 2])
        assert (speed, accel) == pytest.approx((0.19635, 0.61685), abs=5e-6)


def test_working_mode_is_imposed_and_kept():
    """With mode given, every sample is in that working mode; sliders take the matching root of eq. (2)."""
    mech, profile = reference_wave("harada2011_3d3m")
    modes = [sol.mode for sol in working_modes(mech, profile(0.0)[0])]
    mode = next(m for m in modes if m != working_mode(mech, mech.q_ref))
    times = np.linspace(0.0, 1.0, 11)
    tr = task_trajectory(mech, profile, times, mode=mode)
    signs = dict(zip((1, 2, 4), (-m for m in mode), strict=True))  # mode = minus the square-root sign
    for k, t in enumerate(times):
        assert working_mode(mech, tr.q[k]) == mode
        np.testing.assert_allclose(
            tr.c[k], paper.slider_positions(profile(t)[0], L, RT, (1, 2, 4), signs), atol=1e-11
        )


# ---------------------------------------------------------------- actuator trajectories
@pytest.mark.parametrize("name", ["harada2011_3d3m", "harada2011_3d4m", "zhao2011_8pss"])
def test_actuator_trajectory_round_trip(name):
    """Task -> c(t) -> actuator_trajectory gives back the task profile (x, twist rates) and q, v, a."""
    mech, profile = reference_wave(name)
    times = np.linspace(0.0, 1.0, 31)
    tr = task_trajectory(mech, profile, times)
    back = actuator_trajectory(mech, sampled_profile(times, tr.c, tr.cd, tr.cdd), times, guess=tr.q[0])
    x = np.array([profile(t)[0] for t in times])
    np.testing.assert_allclose(back.x, x, atol=1e-10)
    for k in range(tr.n_samples):
        np.testing.assert_allclose(pin.difference(mech.model, tr.q[k], back.q[k]), 0.0, atol=1e-10)
    np.testing.assert_allclose(back.v, tr.v, atol=1e-9)
    np.testing.assert_allclose(back.a, tr.a, atol=1e-8 * (1 + np.max(np.abs(tr.a))))
    np.testing.assert_allclose(back.xd, tr.xd, atol=1e-9)
    np.testing.assert_allclose(back.c, tr.c, atol=1e-11)
    assert back.max_residual <= 1e-10


def test_inconsistent_redundant_actuators_stop_with_the_actuator_named():
    """On the 3D4M, a slider rate off the closed-chain motion stops the trajectory; a position off it too."""
    mech, profile = reference_wave("harada2011_3d4m")
    times = np.linspace(0.0, 1.0, 11)
    tr = task_trajectory(mech, profile, times)
    cd = tr.cd.copy()
    cd[5:, 3] += 1e-3  # slider4 (the 4th actuator) from sample 5 on
    with pytest.raises(TrajectoryError) as err:
        actuator_trajectory(mech, sampled_profile(times, tr.c, cd, tr.cdd), times, guess=tr.q[0])
    assert (err.value.index, err.value.partial.n_samples) == (5, 5)
    assert isinstance(err.value.cause, InvalidInput)
    assert "rates are inconsistent: slider4 misses" in str(err.value)
    c = tr.c.copy()
    c[7:, 3] += 1e-3
    with pytest.raises(TrajectoryError) as err:
        actuator_trajectory(mech, sampled_profile(times, c, tr.cd, tr.cdd), times, guess=tr.q[0])
    assert err.value.index == 7
    assert isinstance(err.value.cause, ClosureNotSatisfied)


def test_actuator_trajectory_stops_where_it_crosses_the_type4_singularity():
    """3D3M, x = 0, y = 0.08 m, theta 0 -> -50 deg: stops at the first sample past eq. (11.4)'s -24.9 deg."""
    mech, times, tr, first_past = direct_crossing()  # a direct singularity does not stop the task map
    with pytest.raises(TrajectoryError) as err:
        actuator_trajectory(mech, sampled_profile(times, tr.c, tr.cd, tr.cdd), times, guess=tr.q[0])
    assert err.value.index == first_past
    assert err.value.time == times[first_past]
    assert isinstance(err.value.cause, SingularConfiguration)
    assert "direct (type 2) singularity" in str(err.value)


# ---------------------------------------------------------------- leaving the workspace
def test_leaving_the_workspace_stops_at_the_first_unreachable_sample_with_the_samples_before():
    """3D3M rising in y at theta = 0: every rod misses once y > l (eq. (2)); index, time, cause, partial."""
    mech = preset("harada2011_3d3m")
    y0, rate = 0.0805, 0.1

    def profile(t):
        return np.array([0.0, y0 + rate * t, 0.0]), np.array([0.0, rate, 0.0]), np.zeros(3)

    times = np.linspace(0.0, 1.0, 101)
    first_out = int(np.flatnonzero(y0 + rate * times > L)[0])  # L_y = y for every leg at theta = 0
    with pytest.raises(TrajectoryError) as err:
        task_trajectory(mech, profile, times)
    e = err.value
    assert (e.index, e.time) == (first_out, times[first_out])
    assert isinstance(e.cause, PoseUnreachable)
    assert f"stops at sample {first_out} of 101 (t = {times[first_out]:.9g} s)" in str(e)
    part = e.partial
    assert isinstance(part, JointTrajectory)
    assert part.n_samples == first_out
    np.testing.assert_array_equal(part.t, times[:first_out])
    assert part.max_residual <= 1e-10
    np.testing.assert_allclose(part.x[:, 1], y0 + rate * times[:first_out])
    np.testing.assert_allclose(
        part.c, [paper.slider_positions(x, L, RT, (1, 2, 4)) for x in part.x], atol=1e-10
    )


@pytest.mark.parametrize("name", ["fivebar", "harada2011_3d4m"])
def test_a_sample_stops_exactly_where_its_inverse_margin_reaches_the_tolerance(name):
    """At rest, a sample is kept for a tolerance just below its SVD inverse margin and stops just above."""
    mech = preset(name)
    x = task_pose(mech, mech.q_ref)

    def profile(t):
        return x, np.zeros_like(x), np.zeros_like(x)

    jac = closed_chain_jacobians(mech, mech.q_ref)
    margin = float(inverse_margins(jac.T, jac.J_x))
    assert margin < float(constraint_margins(jac.closure_singular_values, mech.nv - mech.mobility))
    kept = task_trajectory(mech, profile, [0.0], guess=mech.q_ref, singularity_tol=margin * (1.0 - 1e-9))
    assert kept.n_samples == 1
    with pytest.raises(TrajectoryError, match="inverse \\(margin") as err:
        task_trajectory(mech, profile, [0.0], guess=mech.q_ref, singularity_tol=margin * (1.0 + 1e-9))
    assert isinstance(err.value.cause, SingularConfiguration)


# ---------------------------------------------------------------- profiles
def test_differentiated_profile_is_within_its_stated_error_on_eq35():
    """Five-point differences (h = 1 ms) of eq. (35) match its rates to 2e-9 and accelerations to 1e-8."""
    profile = differentiated_profile(lambda t: zhao2011_trajectory(t)[0])
    for t in np.linspace(0.0, T_ZHAO, 13):
        x, xd, xdd = profile(t)
        ref = zhao2011_trajectory(t)
        np.testing.assert_array_equal(x, ref[0])
        np.testing.assert_allclose(xd, ref[1], atol=2e-9)
        np.testing.assert_allclose(xdd, ref[2], atol=1e-8)


def test_task_trajectory_accepts_positions_only_and_samples():
    """Differentiated and spline profiles give the trajectory of eq. (35) to their interpolation error."""
    mech = preset("zhao2011_6pss")
    times = np.linspace(0.0, T_ZHAO, 9)
    exact = task_trajectory(mech, zhao2011_trajectory, times)
    fd = task_trajectory(mech, differentiated_profile(lambda t: zhao2011_trajectory(t)[0]), times)
    np.testing.assert_allclose(fd.a, exact.a, atol=1e-7)
    fine = np.linspace(0.0, T_ZHAO, 201)
    spline = task_trajectory(mech, sampled_profile(fine, [zhao2011_trajectory(t)[0] for t in fine]), times)
    np.testing.assert_allclose(spline.q, exact.q, atol=1e-12)
    np.testing.assert_allclose(spline.v, exact.v, atol=1e-8)
    np.testing.assert_allclose(spline.a, exact.a, atol=5e-6)


def test_sampled_profiles_interpolate_as_documented():
    """Hermite samples are matched exactly, accelerations continuous; the quintic spline fits a sine."""
    t = np.linspace(0.0, 1.0, 11)
    x = np.column_stack([np.sin(t), t**2])
    xd = np.column_stack([np.cos(t), 2 * t])
    xdd = np.column_stack([-np.sin(t), 2 + 0 * t])
    hermite = sampled_profile(t, x, xd, xdd)
    for k in range(t.size):
        np.testing.assert_allclose(np.array(hermite(t[k])), np.stack([x[k], xd[k], xdd[k]]), atol=1e-14)
    eps = 1e-9
    for knot in t[1:-1]:
        np.testing.assert_allclose(hermite(knot - eps)[2], hermite(knot + eps)[2], atol=1e-6)
    spline = sampled_profile(t, np.sin(t))
    for s in np.linspace(0.0, 1.0, 23):
        value, rate, acc = spline(s)
        assert (value[0], rate[0], acc[0]) == pytest.approx(
            (math.sin(s), math.cos(s), -math.sin(s)), abs=5e-5
        )


# ---------------------------------------------------------------- input checks and result object
def test_bad_times_and_profiles_are_refused_with_their_sample_named():
    """Non-increasing or non-finite times, non-finite or misshapen profile values, bad samples are refused."""
    mech, profile = reference_wave("fivebar")
    with pytest.raises(InvalidInput, match=r"strictly increasing: sample 2 \(t = 0.1 s\) follows t = 0.2 s"):
        task_trajectory(mech, profile, [0.0, 0.2, 0.1])
    with pytest.raises(InvalidInput, match=r"times are not finite at samples \[1\]"):
        task_trajectory(mech, profile, [0.0, math.nan, 1.0])
    with pytest.raises(InvalidInput, match="non-empty"):
        task_trajectory(mech, profile, [])

    def nan_late(t):
        x, xd, xdd = profile(t)
        return (x * math.nan, xd, xdd) if t > 0.5 else (x, xd, xdd)

    with pytest.raises(InvalidInput, match=r"profile is not finite at sample 6 \(t = 0.6 s\)"):
        task_trajectory(mech, nan_late, np.linspace(0.0, 1.0, 11))
    with pytest.raises(InvalidInput, match=r"each of shape \(2,\); got shape \(3, 3\)"):
        task_trajectory(mech, wave([0.0, 0.2, 0.0], [0.01, 0.0, 0.0]), [0.0, 0.1])
    with pytest.raises(InvalidInput, match="give both xd and xdd"):
        sampled_profile([0.0, 1.0], [[0.0], [1.0]], xd=[[0.0], [0.0]])
    with pytest.raises(InvalidInput, match="at least 6 samples"):
        sampled_profile([0.0, 1.0, 2.0], [0.0, 1.0, 2.0])
    with pytest.raises(InvalidInput, match=r"x is not finite at samples \[1\]"):
        sampled_profile(np.arange(6.0), [0.0, math.inf, 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(InvalidInput, match=r"^step must be a positive finite number \[s\], got "):
        differentiated_profile(lambda t: t, step=0.0)
    free = Mechanism(
        mech.model, dataclasses.replace(mech.sidecar, actuation=mech.sidecar.actuation[:1]), name="f"
    )
    with pytest.raises(InvalidInput, match="1 actuators cannot drive 2 DOF"):
        actuator_trajectory(free, lambda t: ([0.0], [0.0], [0.0]), [0.0])


def test_result_is_read_only_and_serialisable():
    """Arrays cannot be written, shapes are checked, to_dict survives JSON, fourbar's scalar profile works."""
    mech = preset("fourbar")
    x0 = task_pose(mech, mech.q_ref)[0]

    def scalar(t):
        return x0 + 0.1 * math.sin(t), 0.1 * math.cos(t), -0.1 * math.sin(t)

    tr = task_trajectory(mech, scalar, np.linspace(0.0, 1.0, 5))
    assert tr.q.shape == (5, mech.nq) and tr.x.shape == (5, 1) and tr.c.shape == (5, 1)
    with pytest.raises(ValueError, match="read-only"):
        tr.q[0, 0] = 1.0
    data = json.loads(json.dumps(tr.to_dict()))
    assert data["n_samples"] == 5 and len(data["a"]) == 5
    assert data["max_residual"] == tr.max_residual
    with pytest.raises(InvalidInput, match="t has 5 samples"):
        JointTrajectory(
            *(getattr(tr, f) for f in ("t", "q", "v", "a", "x", "xd", "xdd", "c", "cd", "cdd")),
            tr.residual[:3],
        )
