"""Singularity classification (plm_pin/kinematics/singularity.py).

Oracles: Harada 2011 condition (9) (z_i^T a = 0, a rod normal to the stator), the 3D3M type-4
locus of eq. (11.4) and det J_e33 of eq. (10) / (M.10), Harada 2015's complex singularity
(equal rods on one slider position), all with configurations built inline from eqs. (2)-(3).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import plm_pin
from plm_pin import PoseUnreachable, SingularConfiguration
from plm_pin.core.mechanism import Mechanism
from plm_pin.description import write_description
from plm_pin.families.prrrp import build_2prrrp
from plm_pin.kinematics import classify, closed_chain_jacobians, forward_kinematics, inverse_kinematics
from plm_pin.kinematics.singularity import (
    direct_margins,
    inverse_margins,
    normalised_margin,
    normalised_margins,
)
from plm_pin.models import preset_names
from tests.conftest import preset, prrrp_paper_configuration

RT = 0.05  # r_t [m]


def prrrp_configuration(mech: Mechanism, pose, lengths, signs: dict[int, int]) -> np.ndarray:
    """Configuration of a 2-PRRRP at ``pose`` from eqs. (2)-(3), square-root sign ``signs[i]`` per leg.

    :func:`tests.conftest.prrrp_paper_configuration` (a negative discriminant clipped to zero, the
    rod then pointing straight at its pair's height); the closure is checked here.
    """
    q = prrrp_paper_configuration(mech, pose, lengths, RT, tuple(signs.get(i, 0) for i in (1, 2, 3, 4)))
    assert np.max(np.abs(mech.closure_residual(q))) < 1e-15
    return q


def vertical_pose(length: float, left: bool, theta: float, x: float = 0.0) -> tuple[float, float, float]:
    """Plate pose putting the left (or right) pair at height ``length``: its rods that long are vertical."""
    s = -RT if left else RT
    return (x, length - s * math.sin(theta), theta)


ASYMMETRIC = (0.24, 0.17, 0.17, 0.24)
MODES_2015 = {1: -1, 2: 1, 3: -1, 4: 1}


@pytest.mark.parametrize(
    ("leg", "pose"), [(2, vertical_pose(0.17, True, -0.3)), (3, vertical_pose(0.17, False, 0.3))]
)
def test_vertical_rod_is_an_inverse_singularity(leg, pose):
    """Condition (9): rod i normal to the stator (z_i^T a = 0) makes an inverse singularity, and only that."""
    mech = preset("harada2015_asymmetric")
    q = prrrp_configuration(mech, pose, ASYMMETRIC, MODES_2015)
    z = np.array([math.cos(q[mech.model.joints[mech.model.getJointId(f"rod{leg}_pivot")].idx_q]), 0.0])
    assert abs(z @ np.array([1.0, 0.0])) < 1e-15  # z_i^T a = 0
    report = classify(mech, q)
    assert report.kinds == ("inverse",)
    assert report.inverse_margin < 1e-15
    assert report.constraint_margin > 1e-3 and report.direct_margin > 1e-3


def test_vertical_rod_of_the_3d3m_is_an_inverse_singularity():
    """Condition (9) for the 3D3M: rod 4 vertical is inverse-singular."""
    mech = preset("harada2011_3d3m")
    q = prrrp_configuration(mech, vertical_pose(0.14, False, 0.3), (0.14,) * 4, {1: -1, 2: 1, 4: 1})
    assert classify(mech, q).kinds == ("inverse",)


def type4_angle(y: float, l: float = 0.14) -> float:
    """Eq. (11.4), reference working mode branch: theta = -acos(sqrt((l + r_t)^2 - y^2) / (l + r_t))."""
    return -math.acos(math.sqrt((l + RT) ** 2 - y**2) / (l + RT))


def det_je33(pose, signs, l: float = 0.14) -> float:
    """Determinant of J_e33 of eq. (5) / (M.10), rows [z_i^T, z_i^T R_theta R s_i], legs 1, 2, 4."""
    x, y, theta = pose
    R = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    R_theta = np.array([[0.0, -1.0], [1.0, 0.0]])
    rows = []
    for i, sign in zip((1, 2, 4), signs, strict=True):
        s = np.array([-RT if i in (1, 2) else RT, 0.0])
        L = np.array([x, y]) + R @ s
        c = L[0] + sign * math.sqrt(L[0] ** 2 - L @ L + l**2)
        z = (L - np.array([c, 0.0])) / l
        rows.append([z[0], z[1], z @ R_theta @ R @ s])
    return float(np.linalg.det(np.array(rows)))


@pytest.mark.parametrize(("x", "y"), [(0.0, 0.08), (0.02, 0.08), (0.0, 0.05), (-0.01, 0.1)])
def test_3d3m_type4_locus_is_a_direct_singularity(x, y):
    """On the type-4 locus of eq. (11.4) det J_e33 = 0 and the 3D3M is direct-singular; 0.01 rad off not."""
    mech = preset("harada2011_3d3m")
    theta = type4_angle(y)
    sol = inverse_kinematics(mech, [x, y, theta])
    assert sol.mode == (1, -1, -1)  # the reference working mode: square-root signs (-, +, +)
    assert abs(det_je33((x, y, theta), (-1, 1, 1))) < 1e-15
    report = classify(mech, sol.q)
    assert report.kinds == ("direct",)
    assert report.direct_margin < 1e-14
    for d in (-0.01, 0.01):
        near = classify(mech, inverse_kinematics(mech, [x, y, theta + d]).q)
        assert near.kinds == ()
        assert near.direct_margin > 1e-4


def test_type4_angle_at_y_008_is_minus_24_9_deg():
    """Eq. (11.4) at y = 0.08 m puts type 4 at -24.90 deg, where a scan's direct margin is least."""
    mech = preset("harada2011_3d3m")
    assert math.degrees(type4_angle(0.08)) == pytest.approx(-24.901062, abs=1e-6)
    angles = np.radians(np.arange(-26.0, -23.0, 0.1))
    margins = [classify(mech, inverse_kinematics(mech, [0.0, 0.08, a]).q).direct_margin for a in angles]
    assert abs(math.degrees(angles[int(np.argmin(margins))]) - (-24.9)) < 0.051


def test_redundant_table_is_regular_on_the_3d3m_type4_locus():
    """The 3D4M at the 3D3M's type-4 pose is not direct-singular: the fourth motor removes it."""
    mech = preset("harada2011_3d4m")
    report = classify(mech, inverse_kinematics(mech, [0.0, 0.08, type4_angle(0.08)]).q)
    assert report.kinds == ()
    assert report.direct_margin > 0.01


@pytest.mark.parametrize("name", preset_names())
def test_reference_configurations_are_regular(name):
    """Every preset's reference configuration is regular, its margins well above the tolerance."""
    report = classify(preset(name), preset(name).q_ref)
    assert report.kinds == ()
    assert not report.singular
    assert min(report.constraint_margin, report.inverse_margin, report.direct_margin) > 1e-3


def test_raise_if_singular_names_the_kind():
    """raise_if_singular raises SingularConfiguration whose message names the kind and the margins."""
    mech = preset("harada2011_3d3m")
    q = inverse_kinematics(mech, [0.0, 0.08, type4_angle(0.08)]).q
    with pytest.raises(
        SingularConfiguration,
        match=r"^harada2011_3d3m: configuration is singular \(direct\): margins constraint [0-9.e-]+, "
        r"inverse "
        r"[0-9.e-]+, direct [0-9.e-]+ \(tolerance 1e-06\)$",
    ):
        classify(mech, q, raise_if_singular=True)
    assert classify(mech, mech.q_ref, raise_if_singular=True).kinds == ()


def test_tolerance_is_the_users():
    """A pose 1e-4 rad off the locus is regular at the default tolerance and direct-singular at tol = 1e-3."""
    mech = preset("harada2011_3d3m")
    q = inverse_kinematics(mech, [0.0, 0.08, type4_angle(0.08) + 1e-4]).q
    assert classify(mech, q).kinds == ()
    report = classify(mech, q, tol=1e-3)
    assert report.kinds == ("direct",)
    assert report.to_dict()["kinds"] == ["direct"]


# ----------------------------------------------------- complex (constraint) singularity


def build_table(tmp_path: Path, lengths, legs) -> Mechanism:
    """A 2-PRRRP with the given rods (Harada 2011 masses), written to disk and loaded."""
    robot, sidecar = build_2prrrp(
        name="table",
        rod_lengths=lengths,
        half_plate=RT,
        slider_mass=0.375,
        rod_masses=(0.026,) * 4,
        rod_inertias=(9.84e-5,) * 4,
        plate_mass=0.132,
        plate_inertia=8.54e-4,
        legs=legs,
        reference_pose=(0.0, 0.1, 0.0),
    )
    write_description(robot, sidecar, tmp_path, "table")
    return plm_pin.load(tmp_path / "table.urdf")


EQUAL_12 = (0.24, 0.24, 0.17, 0.24)  # Harada 2015's table with l2 raised to l1


def test_equal_rods_on_one_slider_position_lose_redundancy_not_rank(tmp_path):
    """Equal rods on coincident sliders (Harada 2015's complex singularity), rods not vertical.

    The two circles of eq. (4) coincide, so with sliders 1 and 2 locked the left pair may turn
    on that circle. The whole 4-motor table is still rigid (sliders 3, 4 hold the right pair
    and the plate's length fixes the left one), and J_phi keeps its rank: each cut rod's own
    columns (c_i, phi_i) give an invertible 2 x 2 block of J_phi whenever the rod is not
    normal to the stator. So classify reports no singularity (no "constraint" kind); what is
    lost is the redundancy: rows 1 and 2 of J_ce coincide (same z and s), and the 3-motor
    subset {1, 2, 4} is direct-singular, which the 3-leg table reports as "direct".
    """
    pose = (0.0, 0.1, 0.1)
    table = build_table(tmp_path / "four", EQUAL_12, (1, 2, 3, 4))
    q = prrrp_configuration(table, pose, EQUAL_12, {1: -1, 2: -1, 3: -1, 4: 1})
    c = table.actuator_positions(q)
    assert c[0] == pytest.approx(c[1], abs=1e-15)
    report = classify(table, q)
    assert report.kinds == ()
    assert report.constraint_margin > 1e-2
    J_ce = closed_chain_jacobians(table, q).J_ce
    np.testing.assert_allclose(J_ce[0], J_ce[1], atol=1e-14)
    assert np.linalg.matrix_rank(J_ce) == 3
    assert abs(np.linalg.det(J_ce[[0, 1, 3]])) < 1e-14
    three = build_table(tmp_path / "three", EQUAL_12, (1, 2, 4))
    q3 = prrrp_configuration(three, pose, EQUAL_12, {1: -1, 2: -1, 4: 1})
    assert classify(three, q3).kinds == ("direct",)


def test_equal_vertical_rods_on_one_slider_position_are_constraint_singular(tmp_path):
    """Equal rods coinciding normal to the stator: J_phi loses rank ("constraint"), together with "inverse".

    There the left pair's vertical closure row has no entry left: rod 2's own columns move its
    tip along the stator only, and rod 1, vertical too, moves the pair along the stator only.
    """
    table = build_table(tmp_path, EQUAL_12, (1, 2, 3, 4))
    pose = vertical_pose(0.24, True, -0.8, 0.01)  # right pair at 0.168 m, below l3 = 0.17 m
    q = prrrp_configuration(table, pose, EQUAL_12, {1: -1, 2: 1, 3: -1, 4: 1})
    report = classify(table, q)
    assert "constraint" in report.kinds
    assert report.kinds == ("constraint", "inverse")
    assert report.constraint_margin < 1e-15


def test_asymmetric_rods_cannot_share_a_slider_position():
    """With l1 = 0.24 m and l2 = 0.17 m, |c1 - c2| >= l1 - l2: coincident sliders have no assembly.

    The two circles of eq. (4) are concentric with different radii, hence disjoint; the
    complex singularity cannot occur, which is why Harada 2015 chose asymmetric rods. Likewise
    rods 1 and 2 cannot both be vertical (the pair cannot be at 0.24 m and 0.17 m at once).
    """
    mech = preset("harada2015_asymmetric")
    c = inverse_kinematics(mech, (0.0, 0.1, 0.0)).actuators
    with pytest.raises(PoseUnreachable, match=r"^harada2015_asymmetric: no assembly with actuators at"):
        forward_kinematics(mech, [c[0], c[0], c[2], c[3]])
    rng = np.random.default_rng(7)
    for _ in range(12):
        pose = (rng.uniform(-0.05, 0.05), rng.uniform(0.0, 0.15), rng.uniform(-0.6, 0.6))
        sol = inverse_kinematics(mech, pose, mode=(1, 1, 1, 1))  # sliders 1, 2 on one side: closest
        assert abs(sol.actuators[0] - sol.actuators[1]) >= 0.24 - 0.17 - 1e-12


def test_normalised_margins_of_a_stack_are_inverse_condition_numbers(rng):
    """Batched sigma_min / sigma_max is numpy's 1 / cond per matrix, 0 for a zero matrix, 1 if empty."""
    M = rng.normal(size=(5, 4, 3))
    M[3] = 0.0
    margins = normalised_margins(M)
    for k in (0, 1, 2, 4):
        assert margins[k] == pytest.approx(1.0 / np.linalg.cond(M[k]), rel=1e-12)
        assert normalised_margin(M[k]) == margins[k]
    assert margins[3] == 0.0
    np.testing.assert_array_equal(normalised_margins(np.zeros((2, 0, 3))), [1.0, 1.0])


# ------------------------------------------------ one-DOF chains: the four-bar's rocker extremes

FOURBAR = {"a": 0.10, "b": 0.25, "c": 0.20, "d": 0.30}  # crank, coupler, rocker, ground [m]


def rocker_extreme_crank_angles() -> tuple[float, float]:
    """Crank angles [rad] of the rocker's two extremes, upper branch, by the law of cosines.

    There crank and coupler are collinear, the crank pin at |OB| = b + a (extended) or
    b - a (folded) from the crank pivot O; in triangle O-D-B, c^2 = |OB|^2 + d^2 - 2 |OB| d cos(beta),
    and the crank points along OB (extended) or against it (folded).
    """
    a, b, c, d = FOURBAR["a"], FOURBAR["b"], FOURBAR["c"], FOURBAR["d"]

    def beta(ob: float) -> float:
        return math.acos((ob**2 + d**2 - c**2) / (2 * ob * d))

    return beta(b + a), beta(b - a) + math.pi


def fourbar_margins_by_hand(q: np.ndarray) -> tuple[float, float]:
    """Inverse and direct margins from the four-bar's velocity ratios (loop a e2 + b e3 = d + c e4).

    w3 / w2 = a sin(t4 - t2) / (b sin(t3 - t4)), w4 / w2 = a sin(t2 - t3) / (c sin(t4 - t3)); the feasible
    tree motion is (w2, w3 - w2, w4) (crank, relative coupler, rocker); the task is the rocker angle
    (|J_x| = 1), the actuator the crank (|S_a| = 1).
    """
    t2, t3, t4 = q[0], q[0] + q[1], q[2]
    a, b, c = FOURBAR["a"], FOURBAR["b"], FOURBAR["c"]
    w3 = a * math.sin(t4 - t2) / (b * math.sin(t3 - t4))
    w4 = a * math.sin(t2 - t3) / (c * math.sin(t4 - t3))
    norm = math.sqrt(1.0 + (w3 - 1.0) ** 2 + w4**2)
    return abs(w4) / norm, 1.0 / norm


@pytest.mark.parametrize("extreme", [0, 1])
def test_fourbar_rocker_extremes_are_inverse_singular(extreme):
    """At the closed-form crank angles of the rocker's extremes the 1-DOF four-bar is inverse-singular.

    A 1 x 1 T has sigma_min / sigma_max = 1; the margin relative to |J_x| vanishes there and grows
    away from it as the hand-derived velocity ratio says.
    """
    fb = preset("fourbar")
    theta = rocker_extreme_crank_angles()[extreme]
    q = fb.assemble(fb.q_ref, fixed={"crank_pivot": theta}).q
    report = classify(fb, q)
    assert report.kinds == ("inverse",)
    assert report.inverse_margin < 1e-9
    assert fourbar_margins_by_hand(q)[0] < 1e-9
    for delta in (-0.01, 0.01):
        q_near = fb.assemble(q, fixed={"crank_pivot": theta + delta}).q
        near = classify(fb, q_near)
        assert near.kinds == ()
        inverse, direct = fourbar_margins_by_hand(q_near)
        assert near.inverse_margin == pytest.approx(inverse, rel=1e-9)
        assert near.direct_margin == pytest.approx(direct, rel=1e-9)
        assert near.inverse_margin > 1e-3


def test_fourbar_margins_match_the_velocity_ratios_around_the_crank():
    """Over a crank turn classify's margins are the hand-derived ones, least inverse at the extremes."""
    fb = preset("fourbar")
    angles = np.radians(np.arange(0.0, 360.0, 5.0)) + 1e-3
    q = fb.q_ref
    inverse = []
    for theta in angles:
        q = fb.assemble(q, fixed={"crank_pivot": theta}).q
        report = classify(fb, q)
        by_hand = fourbar_margins_by_hand(q)
        assert (report.inverse_margin, report.direct_margin) == pytest.approx(by_hand, rel=1e-9)
        inverse.append(report.inverse_margin)
    two_least = sorted(angles[np.argsort(inverse)[:2]])
    extremes = sorted(t % (2 * math.pi) for t in rocker_extreme_crank_angles())
    np.testing.assert_allclose(two_least, extremes, atol=math.radians(2.5))


def test_fourbar_task_space_dynamics_refuses_or_warns_at_the_rocker_extreme():
    """task_space_dynamics raises SingularConfiguration at the extreme, warns IllConditioned near it."""
    from plm_pin.dynamics import task_space_dynamics
    from plm_pin.warnings import IllConditionedWarning

    fb = preset("fourbar")
    theta = rocker_extreme_crank_angles()[1]
    q = fb.assemble(fb.q_ref, fixed={"crank_pivot": theta}).q
    with pytest.raises(SingularConfiguration, match=r"^fourbar: inverse-kinematics \(type 1\) singular"):
        task_space_dynamics(fb, q)
    near = fb.assemble(fb.q_ref, fixed={"crank_pivot": 3.7765}).q
    with pytest.warns(
        IllConditionedWarning,
        match=r"^fourbar: near an inverse \(type 1\) singularity: inverse margin 0\.000209 below 1e-03; "
        r"M_x grows as 1/margin\^2 and is inaccurate$",
    ):
        task_space_dynamics(fb, near)


@pytest.mark.parametrize("k", [1, 2, 3, 6])
def test_margins_do_not_depend_on_the_basis_nor_the_scale(k, rng):
    """Any size: margins unchanged by N -> N R (R orthogonal) and by scaling the task; 1 x 1: |T| / |J_x|."""
    nv = k + 4
    N = np.linalg.qr(rng.normal(size=(nv, k)))[0]  # orthonormal feasible motions
    J_x = rng.normal(size=(k, nv))
    S_a = np.eye(nv)[rng.choice(nv, size=k + 1, replace=False)]
    R = np.linalg.qr(rng.normal(size=(k, k)))[0]
    T, C = J_x @ N, S_a @ N
    inverse, direct = float(inverse_margins(T, J_x)), float(direct_margins(C))
    assert inverse == pytest.approx(
        np.linalg.svd(T, compute_uv=False)[-1] / np.linalg.norm(J_x, 2), rel=1e-12
    )
    assert float(inverse_margins(T @ R, J_x)) == pytest.approx(inverse, rel=1e-12)
    assert float(direct_margins(C @ R)) == pytest.approx(direct, rel=1e-12)
    assert float(inverse_margins(1e-3 * T, 1e-3 * J_x)) == pytest.approx(inverse, rel=1e-12)
    assert 0.0 < inverse <= 1.0 and 0.0 < direct <= 1.0
    if k == 1:
        assert inverse == pytest.approx(abs(T[0, 0]) / np.linalg.norm(J_x), rel=1e-12)
        assert normalised_margin(T) == 1.0  # the old ratio, blind for one DOF
