"""An inverse (type 1) singularity is flagged alike by classify, manipulability and task_space_dynamics.

The four-bar's rocker extremes (crank and coupler collinear) are placed by the law of cosines; just off them
the values are checked against the four-bar's hand-derived velocity ratios and kinetic energy.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from plm_pin import InvalidInput, SingularConfiguration
from plm_pin.dynamics import task_space_dynamics
from plm_pin.kinematics import classify, inverse_kinematics
from plm_pin.warnings import IllConditionedWarning
from plm_pin.workspace import manipulability
from tests.conftest import preset

A, B, C, D = 0.10, 0.25, 0.20, 0.30  # crank, coupler, rocker, ground of the fourbar preset [m]
RHO = 2.0  # mass per length of its bars [kg/m]


def extremes() -> list[tuple[float, float]]:
    """(crank angle, rocker angle) [rad] of the rocker's two extremes, upper branch, by the law of cosines.

    Crank and coupler are collinear, the coupler tip at |OB| = b + a (extended) or b - a (folded) from O.
    """
    out = []
    for ob, flip in ((B + A, 0.0), (B - A, math.pi)):
        beta = math.acos((ob**2 + D**2 - C**2) / (2 * ob * D))
        tip = ob * np.array([math.cos(beta), math.sin(beta)])
        out.append((beta + flip, math.atan2(tip[1], tip[0] - D)))
    return out


def angles(q: np.ndarray) -> tuple[float, float, float]:
    """Absolute angles of crank, coupler and rocker [rad] from the tree configuration."""
    return q[0], q[0] + q[1], q[2]


def crank_per_rocker(q: np.ndarray) -> float:
    """J_ce of the four-bar, crank rate per rocker rate, from the loop a e2 + b e3 = d + c e4 [rad/rad]."""
    t2, t3, t4 = angles(q)
    return C * math.sin(t4 - t3) / (A * math.sin(t2 - t3))


def task_inertia(q: np.ndarray) -> float:
    """M_x = 2 T at unit rocker rate [kg m^2]: bars of mass RHO L, inertia m L^2 / 12 about their centres."""
    t2, t3, t4 = angles(q)
    w2 = crank_per_rocker(q)
    w3 = A * math.sin(t4 - t2) / (B * math.sin(t3 - t4)) * w2
    m_a, m_b, m_c = RHO * A, RHO * B, RHO * C
    e2, e3 = np.array([math.cos(t2), math.sin(t2)]), np.array([math.cos(t3), math.sin(t3)])
    perp = np.array([[0.0, -1.0], [1.0, 0.0]])
    v_g = w2 * A * perp @ e2 + w3 * (B / 2) * perp @ e3  # coupler centre
    return m_a * A**2 / 3 * w2**2 + m_b * float(v_g @ v_g) + m_b * B**2 / 12 * w3**2 + m_c * C**2 / 3 * 1.0**2


@pytest.fixture(scope="module")
def fourbar():
    """The fourbar preset (the dimensions above are its builder's defaults)."""
    return preset("fourbar")


def at_crank(mech, theta: float) -> np.ndarray:
    """The assembled upper-branch configuration with the crank at ``theta``."""
    return mech.assemble(mech.q_ref, fixed={"crank_pivot": theta}).q


@pytest.mark.parametrize("extreme", [0, 1])
def test_exact_singular_pose_is_flagged_by_every_analysis(fourbar, extreme):
    """At the closed-form extreme: classify says inverse, w is inf and flagged, M_x is refused."""
    theta, rocker = extremes()[extreme]
    q = at_crank(fourbar, theta)
    assert q[2] == pytest.approx(rocker, abs=1e-9)  # the closed form is the same pose
    assert classify(fourbar, q).kinds == ("inverse",)
    result = manipulability(fourbar, q)
    assert result.inverse_singular and math.isinf(result.w) and result.J_ce is None
    with pytest.raises(SingularConfiguration, match=r"^fourbar: inverse-kinematics \(type 1\) singular"):
        manipulability(fourbar, q, raise_if_singular=True)
    with pytest.raises(
        SingularConfiguration,
        match=r"^fourbar: inverse-kinematics \(type 1\) singular configuration: inverse margin \S+ at or "
        r"below the tolerance 1e-06 \(as plm_pin.kinematics.classify decides\); "
        r"S and M_x are undefined there$",
    ):
        task_space_dynamics(fourbar, q)


@pytest.mark.parametrize("extreme", [0, 1])
def test_pose_solved_at_the_extreme_rocker_angle_is_flagged_as_classify_flags_it(fourbar, extreme):
    """IK at the extreme rocker angle lands at the fold: the analyses agree with classify, no w = 1e9.

    The crank lands within 1e-5 rad of the closed-form extreme, so the pose is the fold by hand.
    Newton converges linearly there and stops in the sqrt(closure tolerance) band around the fold,
    where the inverse margin (about 1e-6) sits on either side of the singularity tolerance
    depending on round-off (the kernel and Pinocchio paths land on different sides). Either way
    manipulability and task_space_dynamics must say what classify says: flagged, or the
    hand-derived values.
    """
    theta, rocker = extremes()[extreme]
    q = inverse_kinematics(fourbar, [rocker], at_crank(fourbar, theta + 0.02)).q
    assert fourbar.actuator_positions(q)[0] == pytest.approx(theta, abs=1e-5)  # the fold, by hand
    report = classify(fourbar, q)
    assert report.inverse_margin < 1e-5  # in the band, whichever side of the tolerance
    result = manipulability(fourbar, q)
    if report.kinds == ("inverse",):
        assert result.inverse_singular
        with pytest.raises(SingularConfiguration):
            task_space_dynamics(fourbar, q)
    else:
        assert report.kinds == ()
        assert not result.inverse_singular
        assert result.w == pytest.approx(abs(crank_per_rocker(q)), rel=1e-8)
        with pytest.warns(IllConditionedWarning):
            tsd = task_space_dynamics(fourbar, q)
        assert tsd.M_x[0, 0] == pytest.approx(task_inertia(q), rel=1e-8)


@pytest.mark.parametrize("extreme", [0, 1])
@pytest.mark.parametrize("delta", [-1e-2, 1e-2, 1e-4])
def test_just_off_the_singularity_values_are_the_hand_derived_ones(fourbar, extreme, delta):
    """Off the fold by delta in crank angle: w = |J_ce| and M_x from the kinetic energy, by hand."""
    theta, _ = extremes()[extreme]
    q = at_crank(fourbar, theta + delta)
    report = classify(fourbar, q)
    assert report.kinds == ()
    result = manipulability(fourbar, q)
    assert not result.inverse_singular
    assert result.w == pytest.approx(abs(crank_per_rocker(q)), rel=1e-8)
    with pytest.warns(IllConditionedWarning) if report.inverse_margin < 1e-3 else _no_warning():
        tsd = task_space_dynamics(fourbar, q)
    assert tsd.M_x[0, 0] == pytest.approx(task_inertia(q), rel=1e-8)


class _no_warning:
    """A context manager that does nothing (the regular case of the warning check)."""

    def __enter__(self) -> None:
        return None

    def __exit__(self, *args: object) -> None:
        return None


@pytest.mark.parametrize("tol", [-1.0, float("nan"), "1e-6", None, float("inf")])
def test_singularity_tolerance_must_be_a_finite_nonnegative_number(fourbar, tol):
    """Manipulability and task_space_dynamics refuse a singularity_tol that is not a number >= 0."""
    for call in (manipulability, task_space_dynamics):
        with pytest.raises(InvalidInput, match=r"^singularity_tol must be a finite number >= 0, got "):
            call(fourbar, fourbar.q_ref, singularity_tol=tol)


def test_raise_if_singular_must_be_a_boolean(fourbar):
    """manipulability(raise_if_singular="no") is refused: a string would count as true."""
    with pytest.raises(InvalidInput, match=r"^raise_if_singular must be True or False, got 'no'$"):
        manipulability(fourbar, fourbar.q_ref, raise_if_singular="no")
