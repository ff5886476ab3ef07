"""Forward kinematics: every assembly mode (plm_pin/kinematics/forward.py).

Oracle: the 2-PRRRP sub-mechanism solution, intersection of two circles centred on the
stator, of Harada 2011 eqs. (6)-(8) and Harada 2015 eqs. (3)-(4), written inline.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from plm_pin import InvalidInput, PoseUnreachable
from plm_pin.kinematics import forward_kinematics, inverse_kinematics, same_assembly, task_pose
from tests.conftest import preset

RT = 0.05  # r_t [m]


def circles(c0: float, r0: float, c1: float, r1: float) -> list[np.ndarray]:
    """Harada 2011 eq. (6) / 2015 eq. (4): the points at r0 from (c0, 0) and r1 from (c1, 0), [+] then [-].

    x = c0 + l cos(phi), cos(phi) = (r0^2 + d^2 - r1^2) / (2 r0 d), d = c1 - c0 (signed), y = +-l sin(phi).
    """
    d = c1 - c0
    x = c0 + (r0**2 + d**2 - r1**2) / (2 * d)
    h2 = r0**2 - (x - c0) ** 2
    if h2 < 0:
        return []
    return [np.array([x, math.sqrt(h2)]), np.array([x, -math.sqrt(h2)])]


def circle_and_point(p: np.ndarray, r: float, c: float, l: float) -> list[np.ndarray]:
    """The points at r from p and at l from (c, 0): the 3D3M's right pair given its left pair."""
    d = np.array([c, 0.0]) - p
    dist = float(np.linalg.norm(d))
    a = (r**2 - l**2 + dist**2) / (2 * dist)
    h2 = r**2 - a**2
    if h2 < 0:
        return []
    mid = p + a * d / dist
    n = np.array([-d[1], d[0]]) / dist
    return [mid + math.sqrt(h2) * n, mid - math.sqrt(h2) * n]


def plate_pose(p_left: np.ndarray, p_right: np.ndarray) -> np.ndarray:
    """Harada 2011 eq. (8) / 2015 eq. (3): centre at the midpoint, theta = atan2(q_R - q_L, p_R - p_L)."""
    mid = (p_left + p_right) / 2
    return np.array([mid[0], mid[1], math.atan2(*(p_right - p_left)[::-1])])


def _same_pose(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    d = a - b
    d[2] = (d[2] + math.pi) % (2 * math.pi) - math.pi
    return bool(np.max(np.abs(d)) <= tol)


def _assert_same_sets(found: list[np.ndarray], expected: list[np.ndarray], tol: float = 1e-12) -> None:
    assert len(found) == len(expected), f"{len(found)} FK solutions, closed form has {len(expected)}"
    for e in expected:
        assert sum(_same_pose(f, e, tol) for f in found) == 1, f"closed-form pose {e} found {found}"


ACTUATOR_POSES = [(0.0, 0.08, -0.35), (0.02, 0.1, 0.3), (-0.03, 0.05, 0.0), (0.01, 0.07, -0.5)]


@pytest.mark.parametrize("pose", ACTUATOR_POSES)
def test_3d3m_fk_is_the_four_circle_intersections(pose):
    """The 3D3M's assemblies: 2 left pairs of eq. (6) times 2 right pairs at 2 r_t from each, eq. (8)."""
    mech = preset("harada2011_3d3m")
    c1, c2, c4 = inverse_kinematics(mech, pose).actuators  # any actuator positions with assemblies
    l = 0.14
    expected = []
    for p_left in circles(c1, l, c2, l):
        for p_right in circle_and_point(p_left, 2 * RT, c4, l):
            expected.append(plate_pose(p_left, p_right))
    assert len(expected) == 4
    _assert_same_sets([s.x for s in forward_kinematics(mech, [c1, c2, c4])], expected)


@pytest.mark.parametrize("pose", ACTUATOR_POSES)
@pytest.mark.parametrize(
    ("name", "lengths"),
    [("harada2015_asymmetric", (0.24, 0.17, 0.17, 0.24)), ("harada2011_3d4m", (0.14,) * 4)],
)
def test_4_motor_fk_is_the_mirror_pair_of_eq4(name, lengths, pose):
    """Four motors: of the 2 x 2 sub-mechanism solutions of eq. (4) only [++] and its mirror [--] fit.

    Each PRRRP sub-mechanism has two assemblies, its pair above or below the stator (eq. (4)), so
    there are four candidate plates; the plate's length |p_R - p_L| = 2 r_t holds for [++] (the
    actuators come from an IK pose above the stator) and for its mirror image [--], but for
    [+-] and [-+] only when a pair lies on the stator, a non-generic case. So the redundant
    tables have exactly two assembly modes at generic actuator positions.
    """
    mech = preset(name)
    c = inverse_kinematics(mech, pose).actuators
    left = circles(c[0], lengths[0], c[1], lengths[1])
    right = circles(c[2], lengths[2], c[3], lengths[3])
    plates = {}
    for (i, p_left), (j, p_right) in itertools.product(enumerate(left), enumerate(right)):
        plates["+-"[i] + "+-"[j]] = (p_left, p_right)
    spans = {k: float(np.linalg.norm(pr - pl)) for k, (pl, pr) in plates.items()}
    assert abs(spans["++"] - 2 * RT) < 1e-12 and abs(spans["--"] - 2 * RT) < 1e-12
    assert abs(spans["+-"] - 2 * RT) > 1e-3 and abs(spans["-+"] - 2 * RT) > 1e-3
    expected = [plate_pose(*plates["++"]), plate_pose(*plates["--"])]
    _assert_same_sets([s.x for s in forward_kinematics(mech, c)], expected)
    assert _same_pose(expected[0], np.array(pose), 1e-12)


def test_fk_of_equal_rods_uses_eq7():
    """Equal rods: eqs. (7)-(8) put the pairs above the sliders' midpoints, at sqrt(l^2 - (c2 - c1)^2 / 4)."""
    mech = preset("harada2011_3d4m")
    l = 0.14
    # sliders 1, 2 anywhere; sliders 3, 4 placed so that the right pair is 2 r_t away at 0.1 rad
    c1, c2 = -0.15, -0.02
    left = np.array([(c1 + c2) / 2, math.sqrt(l**2 - ((c2 - c1) / 2) ** 2)])
    right = left + 2 * RT * np.array([math.cos(0.1), math.sin(0.1)])
    c3, c4 = right[0] - math.sqrt(l**2 - right[1] ** 2), right[0] + math.sqrt(l**2 - right[1] ** 2)
    p1 = np.array([(c2 + c1) / 2, math.sqrt(l**2 - ((c2 - c1) / 2) ** 2)])  # eq. (7)
    p2 = np.array([(c3 + c4) / 2, math.sqrt(l**2 - ((c4 - c3) / 2) ** 2)])
    expected = np.array(
        [(p1[0] + p2[0]) / 2, (p1[1] + p2[1]) / 2, math.atan((p2[1] - p1[1]) / (p2[0] - p1[0]))]
    )
    found = forward_kinematics(mech, [c1, c2, c3, c4])
    assert len(found) == 2
    assert sum(_same_pose(s.x, expected, 1e-12) for s in found) == 1
    mirror = expected * np.array([1.0, -1.0, -1.0])
    assert sum(_same_pose(s.x, mirror, 1e-12) for s in found) == 1


def test_fk_from_a_guess_alone_returns_its_assembly():
    """With all_modes=False the guess's own assembly is returned, and no other."""
    mech = preset("harada2011_3d3m")
    ik = inverse_kinematics(mech, (0.01, 0.09, -0.2))
    found = forward_kinematics(mech, ik.actuators, ik.q, all_modes=False)
    assert len(found) == 1
    assert same_assembly(mech, found[0].q, ik.q)
    assert found[0].residual_norm <= 1e-12


def test_fk_solutions_are_closed_and_distinct():
    """Every FK solution closes the loops to 1e-12, keeps the actuators, and no two are the same assembly."""
    mech = preset("zhao2011_6pss")
    c = inverse_kinematics(mech, (0.02, -0.01, 1.72, 0.02, 0.03, -0.01)).actuators
    found = forward_kinematics(mech, c, starts=24)
    for s in found:
        assert np.max(np.abs(mech.closure_residual(s.q))) <= 1e-12
        np.testing.assert_allclose(mech.actuator_positions(s.q), c, atol=1e-12)
        np.testing.assert_allclose(task_pose(mech, s.q), s.x, atol=1e-15)
    for a, b in itertools.combinations(found, 2):
        assert not same_assembly(mech, a.q, b.q)


def test_same_assembly_ignores_full_turns():
    """Two configurations whose revolute angles differ by 2 pi are the same assembly; a mirror one is not."""
    mech = preset("harada2011_3d4m")
    q = mech.q_ref.copy()
    j = mech.model.joints[mech.model.getJointId("rod2_pivot")]
    q[j.idx_q] += 2 * math.pi
    assert same_assembly(mech, q, mech.q_ref)
    mirror = forward_kinematics(mech, mech.actuator_positions(mech.q_ref))
    assert sum(not same_assembly(mech, s.q, mech.q_ref) for s in mirror) == 1


def test_actuators_without_assembly_raise_pose_unreachable():
    """Sliders too far apart for the rods (|c2 - c1| > l1 + l2): PoseUnreachable, proven or with residual."""
    mech = preset("harada2011_3d4m")
    with pytest.raises(
        PoseUnreachable,
        match=r"^harada2011_3d4m: no assembly with actuators at \[-0\.3, 0\.0, 0\.05, 0\.1\]: the closures "
        r"have no real solution \(none of the 8 complex roots is real and closes every loop\)$",
    ):
        forward_kinematics(mech, [-0.3, 0.0, 0.05, 0.1])
    with pytest.raises(
        PoseUnreachable,
        match=r"^harada2011_3d4m: no assembly with actuators at \[-0\.3, 0\.0, 0\.05, 0\.1\]: the loops "
        r"cannot be closed \(smallest residual [0-9.e-]+ m/rad over 1 starts\)$",
    ):
        forward_kinematics(mech, [-0.3, 0.0, 0.05, 0.1], all_modes=False)


@pytest.mark.parametrize(
    ("actuators", "message"),
    [
        ([0.0, 0.1, float("nan"), 0.2], r"^actuators has non-finite entries at indices \[2\]$"),
        ([0.0, 0.1, 0.2], r"^actuators must have shape \(4,\), got \(3,\)$"),
        ([[0.0, 0.1, 0.2, 0.3]], r"^actuators must have shape \(4,\), got \(1, 4\)$"),
    ],
)
def test_bad_actuators_are_refused(actuators, message):
    """NaN or wrongly shaped actuator positions raise InvalidInput saying what is wrong."""
    with pytest.raises(InvalidInput, match=message):
        forward_kinematics(preset("harada2011_3d4m"), actuators)


def test_bad_fk_guess_is_refused():
    """A NaN or wrongly shaped FK guess raises InvalidInput naming the guess."""
    mech = preset("harada2011_3d4m")
    c = mech.actuator_positions(mech.q_ref)
    with pytest.raises(InvalidInput, match=r"^guess must have shape \(9,\), got \(10,\)$"):
        forward_kinematics(mech, c, np.zeros(10))
    bad = mech.q_ref.copy()
    bad[0] = np.inf
    with pytest.raises(InvalidInput, match=r"^guess has non-finite entries at indices \[0\]$"):
        forward_kinematics(mech, c, bad)
