"""Inverse kinematics and working modes (plm_pin/kinematics/inverse.py).

Oracles: Harada 2011 eq. (2) / code (M.5) (and Harada 2015 eq. (6), the same formula) for the
2-PRRRP tables, Enferadi 2017 eq. (5) (corrected, see plm_pin/families/star_triangle/builder.py) for the
star-triangle, the strut-length equation of Zhao 2011 for the n-PSS, all written inline; and
the forward kinematics, a different algorithm (closures with the actuators fixed, multi-start).
"""

from __future__ import annotations

import itertools
import math
import re

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plm_pin import InvalidInput, PoseUnreachable
from plm_pin.kinematics import forward_kinematics, inverse_kinematics, same_assembly, task_pose, working_modes
from plm_pin.kinematics.limits import limit_violations, wrap_into_limits
from plm_pin.kinematics.working_mode import working_mode
from plm_pin.models import PRESETS, preset_names
from tests.conftest import preset, star_triangle_eq5

ZHAO2011 = PRESETS["zhao2011_8pss"].parameters  # Zhao 2011 Tables 1-3, eq. (19): the preset's parameters

# Offsets [lo, hi] of the random poses from each preset's reference task pose, per task
# coordinate [m, rad]: inside the workspace and away from singular loci (the 3D3M's type-4
# locus theta = -asin(y / (l + r_t)) of eq. (11.4) is kept at least 2 deg away, the four-bar's
# rocker stays inside its range [1.633, 2.68] rad).
OFFSETS: dict[str, list[tuple[float, float]]] = {
    "delta": [(-0.05, 0.05)] * 3,
    "enferadi2017_star_triangle": [(-0.05, 0.05), (-0.05, 0.05), (-0.3, 0.3)],
    "fivebar": [(-0.03, 0.03)] * 2,
    "fourbar": [(-0.05, 0.5)],
    "harada2011_3d3m": [(-0.02, 0.02), (0.0, 0.02), (-0.05, 0.17)],
    "harada2011_3d4m": [(-0.02, 0.02), (-0.02, 0.02), (-0.2, 0.2)],
    "harada2015_asymmetric": [(-0.02, 0.02), (-0.02, 0.02), (-0.2, 0.2)],
    "planar_3rpr": [(-0.03, 0.03), (-0.03, 0.03), (-0.2, 0.2)],
    "stewart_6ups": [(-0.05, 0.05)] * 3 + [(-0.1, 0.1)] * 3,
    "zhao2011_6pss": [(-0.05, 0.05)] * 6,
    "zhao2011_8pss": [(-0.05, 0.05)] * 6,
}

RT = 0.05  # Harada 2011 Table 1: half plate length r_t [m]
LEFT = (1, 2)  # legs on the plate's left pair, s_i = [-r_t, 0]


def _pose_error(a: np.ndarray, b: np.ndarray, n_lin: int) -> float:
    """Largest difference of two task poses, angles (after the n_lin positions) modulo 2 pi."""
    d = np.asarray(a, dtype=float) - b
    d[n_lin:] = (d[n_lin:] + np.pi) % (2 * np.pi) - np.pi
    return float(np.max(np.abs(d)))


def harada_eq2(pose, legs, lengths, signs) -> np.ndarray:
    """Harada 2011 eq. (2), c_i = L_i^T a +- sqrt((L_i^T a)^2 - L_i^T L_i + l_i^2).

    The printed (L_i^T L_i)^2 is a typo: (M.5) and Harada 2015 eq. (6) have L_i^T L_i.
    """
    x, y, theta = pose
    a = np.array([1.0, 0.0])
    R = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    out = []
    for i, sign in zip(legs, signs, strict=True):
        s = np.array([-RT if i in LEFT else RT, 0.0])
        L = np.array([x, y]) + R @ s
        out.append(L @ a + sign * math.sqrt((L @ a) ** 2 - L @ L + lengths[i - 1] ** 2))
    return np.array(out)


def test_every_preset_has_offsets():
    """The round-trip property test covers every preset."""
    assert set(OFFSETS) == set(preset_names())


@pytest.mark.parametrize("name", preset_names())
@settings(deadline=None, max_examples=8, derandomize=True, database=None)
@given(u=st.lists(st.floats(0.0, 1.0), min_size=6, max_size=6))
def test_ik_then_fk_round_trip(name, u):
    """IK near the reference closes to 1e-12; one FK assembly of its actuators is that pose and q."""
    mech = preset(name)
    x_ref = task_pose(mech, mech.q_ref)
    bounds = np.array(OFFSETS[name])  # (n_task, 2)
    x = x_ref + bounds[:, 0] + np.array(u[: len(x_ref)]) * (bounds[:, 1] - bounds[:, 0])
    ik = inverse_kinematics(mech, x)
    assert ik.residual_norm <= 1e-12
    assert np.max(np.abs(mech.closure_residual(ik.q))) <= 1e-12
    task = mech.task_compiled
    assert task is not None
    n_lin = len(task.linear)
    assert _pose_error(task_pose(mech, ik.q), x, n_lin) <= 1e-12
    solutions = forward_kinematics(mech, ik.actuators)
    errors = [_pose_error(s.x, x, n_lin) for s in solutions]
    best = solutions[int(np.argmin(errors))]
    assert min(errors) <= 1e-12
    assert same_assembly(mech, best.q, ik.q)
    np.testing.assert_allclose(mech.actuator_positions(best.q), ik.actuators, atol=1e-12)


HARADA_POSES = [(0.0, 0.08, -0.35), (0.02, 0.1, 0.3), (-0.03, 0.05, 0.0)]


@pytest.mark.parametrize(
    ("name", "legs", "lengths", "n_modes"),
    [
        ("harada2011_3d4m", (1, 2, 3, 4), (0.140,) * 4, 16),
        ("harada2015_asymmetric", (1, 2, 3, 4), (0.240, 0.170, 0.170, 0.240), 16),
        ("harada2011_3d3m", (1, 2, 4), (0.140,) * 4, 8),
    ],
)
@pytest.mark.parametrize("pose", HARADA_POSES)
def test_harada_working_modes_match_eq2(name, legs, lengths, n_modes, pose):
    """Each sign combination of eq. (2) is exactly one working mode, of mode minus the square-root signs."""
    mech = preset(name)
    solutions = working_modes(mech, pose)
    assert len(solutions) == n_modes
    for signs in itertools.product((-1, 1), repeat=len(legs)):
        c = harada_eq2(pose, legs, lengths, signs)
        hits = [s for s in solutions if np.max(np.abs(s.actuators - c)) <= 1e-12]
        assert len(hits) == 1, f"signs {signs}: {len(hits)} matching solutions"
        assert hits[0].mode == tuple(-s for s in signs)
        assert hits[0].residual_norm <= 1e-12


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_8pss"])
def test_solution_derives_actuators_mode_and_limits_as_from_q(name):
    """Lazily read actuators and mode, and limits checked in one comparison, equal those computed at q."""
    mech = preset(name)
    sol = inverse_kinematics(mech, task_pose(mech, mech.q_ref) + 1e-3)
    assert "mode" not in vars(sol) and "actuators" not in vars(sol)  # nothing derived before it is read
    np.testing.assert_array_equal(sol.actuators, mech.actuator_positions(sol.q))
    assert sol.mode == working_mode(mech, sol.q)
    assert sol.limit_violations == limit_violations(mech, sol.q) == {}
    np.testing.assert_array_equal(wrap_into_limits(mech, sol.q), sol.q)
    assert sol.to_dict()["mode"] == list(sol.mode)


def test_harada_reference_mode_follows_code_m5():
    """IK from the reference guess keeps the (M.5) working mode (- + - +): c_i of eq. (2) with those signs."""
    mech = preset("harada2011_3d4m")
    for pose in HARADA_POSES:
        sol = inverse_kinematics(mech, pose)
        np.testing.assert_allclose(
            sol.actuators, harada_eq2(pose, (1, 2, 3, 4), (0.14,) * 4, (-1, 1, -1, 1)), atol=1e-12
        )
        assert sol.mode == (1, -1, 1, -1)


def test_ik_with_a_mode_returns_that_mode():
    """Asking for a working mode returns the eq. (2) solution with the opposite square-root signs."""
    mech = preset("harada2015_asymmetric")
    pose = (0.01, 0.09, 0.2)
    for mode in [(1, 1, 1, 1), (-1, 1, 1, -1), (1, -1, -1, 1)]:
        sol = inverse_kinematics(mech, pose, mode=mode)
        assert sol.mode == mode
        expected = harada_eq2(pose, (1, 2, 3, 4), (0.24, 0.17, 0.17, 0.24), tuple(-m for m in mode))
        np.testing.assert_allclose(sol.actuators, expected, atol=1e-12)


@pytest.mark.parametrize(
    "pose", [(0.25, 0.35, math.pi / 2), (0.2, 0.2, 1.2), (0.3, 0.25, 2.0), (0.28, 0.12, 1.9)]
)
def test_star_triangle_ik_matches_eq5(pose):
    """The star-triangle has one working mode, and its slider positions and arm lengths are eqs. (4)-(5)."""
    mech = preset("enferadi2017_star_triangle")
    solutions = working_modes(mech, pose)
    assert len(solutions) == 1
    q, rho = star_triangle_eq5(pose)
    np.testing.assert_allclose(solutions[0].actuators, q, atol=1e-12)
    arms = [solutions[0].q[mech.model.joints[mech.model.getJointId(f"arm{i}")].idx_q] for i in (1, 2, 3)]
    np.testing.assert_allclose(arms, rho, atol=1e-12)


@pytest.mark.parametrize("name", ["zhao2011_8pss", "zhao2011_6pss"])
def test_pss_ik_matches_strut_length_equation(name):
    """n-PSS sliders: q_i = e_i^T d_i - sqrt(l_i^2 - |d_i|^2 + (e_i^T d_i)^2), d_i = p + R a_i - B_i."""
    mech = preset(name)
    legs = [int(a.joint.removeprefix("slider")) for a in mech.actuators]
    for pose in [(0.0, 0.0, 1.744, 0.0, 0.0, 0.0), (0.03, -0.04, 1.70, 0.05, -0.03, 0.04)]:
        sol = inverse_kinematics(mech, pose)
        R = pin.rpy.rpyToMatrix(*pose[3:])
        expected = []
        for i in legs:
            e = np.array(ZHAO2011["guide_directions"][i - 1])
            d = (
                np.array(pose[:3])
                + R @ np.array(ZHAO2011["platform_points"][i - 1])
                - np.array(ZHAO2011["guide_points"][i - 1])
            )
            ed = e @ d
            expected.append(ed - math.sqrt(ZHAO2011["strut_lengths"][i - 1] ** 2 - d @ d + ed**2))
        np.testing.assert_allclose(sol.actuators, expected, atol=1e-12)


# ------------------------------------------------------------------------ bad input


def test_unreachable_pose_names_the_legs_and_their_misses():
    """A pose out of reach names the leg missing most and the others, by |L_y| - l (eq. (2) root < 0)."""
    mech = preset("harada2015_asymmetric")
    x, y, theta = 0.0, 0.2, 0.1
    lengths = (0.24, 0.17, 0.17, 0.24)
    miss = {}
    for i in (1, 2, 3, 4):
        Ly = y + (-RT if i in LEFT else RT) * math.sin(theta)
        if abs(Ly) > lengths[i - 1]:
            miss[f"slider{i}"] = abs(Ly) - lengths[i - 1]
    assert set(miss) == {"slider2", "slider3"}  # l2 = l3 = 0.17 m fall short, l1 = l4 = 0.24 m reach
    with pytest.raises(PoseUnreachable) as err:
        inverse_kinematics(mech, [x, y, theta])
    assert str(err.value) == (
        f"harada2015_asymmetric: pose [0.0, 0.2, 0.1] is unreachable: leg slider3 misses by "
        f"{miss['slider3']:.3g} m (also slider2: {miss['slider2']:.3g} m)"
    )


def test_unreachable_pose_without_explanation_raises_a_short_message():
    """explain=False skips the leg-by-leg diagnosis: the same error class, a message without legs."""
    mech = preset("harada2015_asymmetric")
    with pytest.raises(PoseUnreachable) as err:
        inverse_kinematics(mech, [0.0, 0.2, 0.1], explain=False)
    assert str(err.value) == "harada2015_asymmetric: pose [0.0, 0.2, 0.1] could not be solved from this guess"


def test_unreachable_pose_of_the_symmetric_table_lists_both_right_legs():
    """Plate tilted up to the right: both right rods of the 3D4M miss by |L_y| - l, the left ones reach."""
    mech = preset("harada2011_3d4m")
    x, y, theta = 0.0, 0.12, 0.9
    gap = y + RT * math.sin(theta) - 0.14
    with pytest.raises(
        PoseUnreachable, match=rf"leg slider3 misses by {gap:.3g} m \(also slider4: {gap:.3g} m\)$"
    ):
        inverse_kinematics(mech, [x, y, theta])


def test_unreachable_rocker_angle_names_the_crank_leg():
    """A rocker angle out of range blames the crank-coupler leg by its closest gap (max-abs component)."""
    mech = preset("fourbar")
    psi = 1.6  # the rocker of this crank-rocker spans [1.633, 2.68] rad
    B = np.array([0.30 + 0.20 * math.cos(psi), 0.20 * math.sin(psi)])
    # closest approach: crank (0.10) and coupler (0.25) stretched toward B, gap along B
    gap = (np.linalg.norm(B) - 0.35) * B / np.linalg.norm(B)
    with pytest.raises(
        PoseUnreachable, match=rf"is unreachable: leg crank_pivot misses by {np.max(np.abs(gap)):.3g} m$"
    ):
        inverse_kinematics(mech, [psi])


def test_pose_beyond_the_end_effector_chain_says_so():
    """A plate too high for rod 1 itself is reported against the end-effector chain."""
    mech = preset("harada2011_3d4m")
    with pytest.raises(PoseUnreachable, match=r"is out of reach of the end-effector chain \(slider1\)"):
        inverse_kinematics(mech, [0.0, 0.2, 0.0])


@pytest.mark.parametrize(
    ("x", "message"),
    [
        ([0.0, float("nan"), 0.0], r"^x has non-finite entries at indices \[1\]$"),
        ([0.0, 0.08], r"^x must have shape \(3,\), got \(2,\)$"),
        ([[0.0, 0.08, 0.0]], r"^x must have shape \(3,\), got \(1, 3\)$"),
        ([0.0, 0.08, float("inf")], r"^x has non-finite entries at indices \[2\]$"),
    ],
)
def test_bad_pose_is_refused(x, message):
    """A NaN, infinite or wrongly shaped pose raises InvalidInput saying what is wrong."""
    with pytest.raises(InvalidInput, match=message):
        inverse_kinematics(preset("harada2011_3d4m"), x)


def test_bad_guess_is_refused():
    """A NaN or wrongly shaped guess raises InvalidInput naming the guess."""
    mech = preset("harada2011_3d4m")
    bad = mech.q_ref.copy()
    bad[3] = np.nan
    with pytest.raises(InvalidInput, match=r"^guess has non-finite entries at indices \[3\]$"):
        inverse_kinematics(mech, [0.0, 0.08, 0.0], bad)
    with pytest.raises(InvalidInput, match=r"^guess must have shape \(9,\), got \(8,\)$"):
        inverse_kinematics(mech, [0.0, 0.08, 0.0], mech.q_ref[:8])


@pytest.mark.parametrize("mode", [(1, -1, 1), (1, -1, 1, -1, 1), (1, 0, 1, -1), (1, 2, 1, -1)])
def test_bad_mode_is_refused(mode):
    """A working mode of the wrong length or with entries other than +-1 raises InvalidInput."""
    with pytest.raises(
        InvalidInput,
        match=r"^mode must hold 4 signs \(\+1 or -1\), one per leg; got " + re.escape(repr(mode)) + "$",
    ):
        inverse_kinematics(preset("harada2011_3d4m"), [0.0, 0.08, 0.0], mode=mode)


def test_first_call_mode_does_not_depend_on_the_lazily_built_legs(tmp_path):
    """The first IK on a fresh mechanism (fresh process) labels its mode as working_mode does later.

    Every other working mode of the 3D3M at its reference pose is solved from its own
    configuration as guess in a fresh process, where building ``mech.legs`` inside the first
    ``.mode`` used to overwrite the scratch data that the label is read from.
    """
    import subprocess
    import sys

    mech = preset("harada2011_3d3m")
    x = task_pose(mech, mech.q_ref)
    sols = working_modes(mech, x)
    assert len(sols) == 8  # two branches per PRRRP leg
    np.save(tmp_path / "q.npy", np.stack([s.q for s in sols]))
    code = (
        "import numpy as np, plm_pin\n"
        "from plm_pin.kinematics import inverse_kinematics, task_pose\n"
        f"qs = np.load({str(tmp_path / 'q.npy')!r})\n"
        "for q in qs:\n"
        "    mech = plm_pin.load('harada2011_3d3m')\n"
        "    print(inverse_kinematics(mech, task_pose(mech, q), guess=q).mode)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    labels = [tuple(int(s) for s in line.strip("()").split(",")) for line in out.stdout.splitlines()]
    assert labels == [working_mode(mech, s.q) for s in sols]
    assert len(set(labels)) == 8
