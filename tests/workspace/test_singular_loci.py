"""Singular loci: Harada 2011 eqs. (9), (11.1)-(11.4) and Fig. 6, found numerically by root finding."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from analyses import _harada2011_paper as paper
from plm_pin.exceptions import InvalidInput
from plm_pin.kinematics import closed_chain_jacobians, inverse_kinematics
from plm_pin.kinematics.working_mode import working_mode
from plm_pin.loading import build_mechanism
from plm_pin.workspace import (
    singular_loci,
    singular_points,
    singular_points_along,
    workspace_sweep,
)
from plm_pin.workspace.singular_loci import signed_singularity_function
from tests.conftest import preset, with_rotated_null_basis
from tests.workspace.conftest import FIG6_L, FIG6_RT

L, RT = 0.140, 0.05  # Harada 2011 Table 1
THETAS = np.radians(np.linspace(-85.0, 85.0, 69))  # 2.5 deg samples
TOL = 1e-8  # required agreement with eq. (11) [rad]


def expected_3d3m(y: float, l: float, rt: float, sigma4: int) -> list[tuple[float, str, str]]:
    """(theta, method, equation) of the 3D3M's singular points along theta in (-85, 85) deg at height y.

    ``sigma4`` is the sign of the square root of eq. (2) for leg 4 (+1 in the paper's code (M.5)).
    Eq. (11) is det J_e33 = 0 solved by Mathematica with its +/- signs; which sign is a singular
    point depends on the working mode and on the sign of y:

    - (11.1) theta = asin(y / rt): the left pair on the stator, rods 1 and 2 collinear; any mode.
    - (11.2) theta = asin((y -/+ l) / rt): rods 1 and 2 normal to the stator on one slider
      position (|L_y| = l): the edge of the reachable set, found as a boundary by bisection.
    - (11.3) theta = +/-acos(sqrt(((l - rt)^2 - y^2) / (l - rt)^2)): rod 4 along the plate with its
      slider between the pairs; only with sigma4 = -1 (skipped in the paper's mode, where slider 4
      is beyond its pair), sign + for y > 0.
    - (11.4) theta = +/-acos(sqrt(((l + rt)^2 - y^2) / (l + rt)^2)): rod 4 along the plate with its
      slider beyond its pair; only with sigma4 = +1, sign - for y > 0 (+ for the mirror y < 0).
    - eq. (9) for rod 4 (|y + rt sin theta| = l): the other edge of the reachable set, not in eq. (11).

    Points outside the reachable set of sin(theta) (eq. (2) real for every leg) are left out:
    the continuation cannot reach them in this working mode (e.g. (11.4) at y = 0.12 m).
    """
    lo, hi = paper.reachable_sin_interval(y, l, rt)
    direct = []
    if abs(y) <= rt:
        direct.append((math.asin(y / rt), "11.1"))
    sign_y = 1.0 if y > 0 else -1.0
    if sigma4 > 0:
        direct.append((-sign_y * math.acos(math.sqrt(((l + rt) ** 2 - y**2) / (l + rt) ** 2)), "11.4"))
    elif abs(y) < l - rt:
        direct.append((sign_y * math.acos(math.sqrt(((l - rt) ** 2 - y**2) / (l - rt) ** 2)), "11.3"))
    out = [(t, "sign_change", eq) for t, eq in direct if lo < math.sin(t) < hi]
    limit = math.radians(85.0)
    for s in (lo, hi):
        if abs(s) < 1.0 and abs(math.asin(s)) < limit:
            left = abs(abs(y - rt * s) - l) < 1e-12  # the left pair at |L_y| = l: eq. (11.2)
            out.append((math.asin(s), "boundary", "11.2" if left else "9"))
    return sorted(out)


def _check_against(points, expected) -> None:
    assert len(points) == len(expected), (
        [(math.degrees(p.parameter), p.method) for p in points],
        [(math.degrees(t), m, eq) for t, m, eq in expected],
    )
    for p, (theta, method, eq) in zip(points, expected, strict=True):
        assert p.method == method, eq
        assert abs(p.parameter - theta) < TOL, (eq, p.parameter, theta)
        if method == "sign_change":
            assert p.kind == "direct" and p.report.direct_margin < 1e-12, eq
        else:
            assert "inverse" in p.report.kinds, eq


@pytest.mark.parametrize("y", [0.01, 0.03, 0.06, 0.1, 0.12, -0.03, -0.1])
def test_3d3m_loci_in_the_papers_working_mode(y):
    """Along theta at several y, the 3D3M's singular points are eqs. (11.1), (11.2), (11.4), (9) to 1e-8."""
    mech = preset("harada2011_3d3m")
    mode = working_mode(mech, mech.q_ref)
    points = singular_points_along(mech, "rz", THETAS, (0.0, y, 0.0), mode=mode)
    _check_against(points, expected_3d3m(y, L, RT, +1))


def test_singular_point_on_a_sample_is_found_whatever_the_sign_of_its_round_off():
    """A sample exactly on eq. (11.1) (rt = 0.06 m, y = 0.03 m: theta = 30 deg) is the root it is.

    There the singularity function is round-off (about 1e-20), whose sign the root finder's own
    solve of the sample turns on this grid; the bracket's ends then share a sign. The points
    are eq. (11.1) at 30 deg and eq. (11.4) at -asin(y / (l + rt)), to 1e-8 rad.
    """
    rt, y = 0.06, 0.03
    mech = build_mechanism("harada2011_3d3m", {"half_plate": rt})
    thetas = np.radians(np.linspace(-80.0, 80.0, 33))  # 30 deg is a sample
    points = singular_points_along(mech, "rz", thetas, (0.0, y, 0.0), mode=working_mode(mech, mech.q_ref))
    roots = [p.parameter for p in points if p.method == "sign_change"]
    expected = [-math.asin(y / (L + rt)), math.asin(y / rt)]  # eqs. (11.4), (11.1)
    assert len(roots) == 2 and max(abs(a - b) for a, b in zip(roots, expected, strict=True)) < TOL


@pytest.mark.parametrize("y", [0.02, 0.05, 0.08, -0.04])
def test_3d3m_type3_locus_with_slider4_on_the_other_side(y):
    """With leg 4 in its other branch, eq. (11.3) replaces eq. (11.4), to 1e-8 rad."""
    mech = preset("harada2011_3d3m")
    base = working_mode(mech, mech.q_ref)
    mode = (*base[:-1], -base[-1])
    points = singular_points_along(mech, "rz", THETAS, (0.0, y, 0.0), mode=mode)
    _check_against(points, expected_3d3m(y, L, RT, -1))


def test_fig6_3d3m_w_vanishes_at_28_7_deg_while_3d4m_stays_bounded(fig6):
    """Fig. 6 (l : 2 rt = 2 : 1): where eq. (11.4) gives 28.7 deg, the 3D3M's w is zero, the 3D4M's is not."""
    l, rt = FIG6_L, FIG6_RT
    y = (l + rt) * math.sin(math.radians(28.7))  # eq. (11.4) solved for y
    paper_angle = math.acos(math.sqrt(((l + rt) ** 2 - y**2) / (l + rt) ** 2))
    assert math.degrees(paper_angle) == pytest.approx(28.7, abs=1e-12)
    thetas = np.radians(np.linspace(-80.0, 80.0, 65))
    pose = (0.0, y, 0.0)
    points = singular_points_along(fig6["3d3m"], "rz", thetas, pose)
    assert [(p.method, p.kind) for p in points] == [("sign_change", "direct")]
    found = points[0].parameter
    print(
        f"\nHarada 2011 Fig. 6 (l = {l} m, rt = {rt} m): 3D3M type-4 singular angle "
        f"{math.degrees(found):.2f} deg at y = {y:.6f} m (= {y / l:.4f} l)"
    )
    assert abs(found + paper_angle) < TOL  # the - sign of (11.4) for y > 0
    assert abs(abs(math.degrees(found)) - 28.7) < 0.01
    grid = np.sort(np.append(thetas, found))
    w3 = workspace_sweep(fig6["3d3m"], "rz", grid, pose).manipulability
    w4 = workspace_sweep(fig6["3d4m"], "rz", grid, pose).manipulability
    assert np.all(np.isfinite(w3)) and np.all(np.isfinite(w4))
    at = int(np.flatnonzero(grid == found)[0])
    assert w3[at] < 1e-12 * np.max(w3)  # falls to zero at the singular angle ...
    assert np.min(np.delete(w3, at)) > 0.0  # ... and only there
    assert np.min(w4) > 0.3 * np.max(w4)  # the redundant table stays well away from zero
    assert w4[at] > 0.3 * np.max(w4)
    assert not singular_points_along(fig6["3d4m"], "rz", thetas, pose)


def test_redundant_direct_singularity_found_by_minimising_its_margin():
    """The 3D4M with both pairs on the stator (y = 0, theta = 0): the direct margin is minimised to zero."""
    mech = preset("harada2011_3d4m")
    points = singular_points_along(mech, "y", np.linspace(-0.05, 0.05, 40), (0.01, 0.0, 0.0))
    assert len(points) == 1
    (p,) = points
    assert p.method == "minimum" and p.kind == "direct" and p.reaches_zero
    assert abs(p.parameter) < 1e-9 and p.margin < 1e-9


def test_redundant_minimum_above_zero_is_reported_as_not_reaching_it():
    """At y = 0.02 m the 3D4M's direct margin dips along theta but stays above zero: reaches_zero False."""
    mech = preset("harada2011_3d4m")
    points = singular_points_along(mech, "rz", THETAS, (0.0, 0.02, 0.0))
    assert points and all(p.method == "minimum" and not p.reaches_zero for p in points)
    assert all(p.margin > 1e-4 for p in points)


def test_signed_function_is_basis_independent_with_the_sign_of_det_J_ce(rng):
    """det(T) det(C) is unchanged by N -> N Q (det Q = -1) and has the sign of det J_ce (eq. (12))."""
    mech = preset("harada2011_3d3m")
    pose = (0.01, 0.07, 0.2)
    q = inverse_kinematics(mech, pose, mech.q_ref).q
    jac = closed_chain_jacobians(mech, q)
    other = with_rotated_null_basis(mech, jac, rng)
    g = signed_singularity_function(mech, q)
    assert np.linalg.det(other.T) * np.linalg.det(other.C) == pytest.approx(g, rel=1e-12)
    J = paper.J_ce(pose, paper.slider_positions(pose, L, RT, (1, 2, 4)), L, RT, (1, 2, 4))
    assert np.sign(g) == np.sign(np.linalg.det(J))


def test_signed_function_refuses_redundant_mechanisms():
    """det(C) needs a square C: the 3D4M is refused by name."""
    mech = preset("harada2011_3d4m")
    with pytest.raises(InvalidInput, match=r"harada2011_3d4m: det\(T\) det\(C\) needs as many"):
        signed_singularity_function(mech, mech.q_ref)


def test_singular_loci_over_a_2d_slice_follow_eq_11():
    """Line by line over y, the type-1 and type-4 curves theta(y) of eq. (11) are traced."""
    mech = preset("harada2011_3d3m")
    ys = [0.015, 0.025, 0.035]
    points = singular_loci(mech, "rz", THETAS, "y", ys)
    direct = [p for p in points if p.kind == "direct"]
    assert len(direct) == 2 * len(ys)
    for p in direct:
        y = p.x[1]
        candidates = [math.asin(y / RT), -math.asin(y / (L + RT))]
        assert min(abs(p.parameter - c) for c in candidates) < TOL
    assert json.loads(json.dumps(points[0].to_dict()))["kind"] == "direct"


def test_custom_path_and_bad_samples():
    """A user path (a line in x-y-theta) works; non-increasing samples are refused with a message."""
    mech = preset("harada2011_3d3m")
    y = 0.06
    theta4 = -math.asin(y / (L + RT))

    def path(t: float) -> np.ndarray:
        return np.array([0.01 * t, y, theta4 * t])

    points = singular_points(mech, path, np.linspace(0.5, 1.5, 21))
    assert len(points) == 1 and abs(points[0].parameter - 1.0) < 1e-9
    with pytest.raises(InvalidInput, match="t must be an increasing 1-D array"):
        singular_points(mech, path, [0.0, 0.0, 1.0])


def test_3d3m_flipped_plate_arc_is_reseeded_in_the_same_working_mode():
    """Over a full turn at y = 0.10 m, both arcs of |sin theta| <= (l - y)/r_t are found, with four edges.

    The continuation starts on the upright arc; the flipped-plate arc (around 180 deg) is cut off
    from it by poses no leg reaches, so it must be seeded again, in the same working mode: its
    edges at 180 deg - asin((y - l)/r_t) and its mirror are boundaries too, and the sweep's
    actuators there are eq. (2) with the paper's signs (M.5).
    """
    mech = preset("harada2011_3d3m")
    y = 0.10
    thetas = np.radians(np.linspace(-180.0, 180.0, 721))
    points = singular_points_along(mech, "rz", thetas, (0.0, y, 0.0))
    t1 = math.asin((y - L) / RT)  # eq. (11.2): the left pair at L_y = l
    edges = sorted([t1, -t1, math.pi - t1 - 2 * math.pi, math.pi + t1])  # wrapped to (-pi, pi]
    found = sorted(p.parameter for p in points if p.method == "boundary")
    assert np.allclose(found, edges, atol=TOL, rtol=0.0), (np.degrees(found), np.degrees(edges))
    sweep = workspace_sweep(mech, "rz", thetas, (0.0, y, 0.0))
    s = np.abs(np.sin(thetas))
    inside, outside = s < (L - y) / RT - 1e-9, s > (L - y) / RT + 1e-9
    assert sweep.reachable[inside].all() and not sweep.reachable[outside].any()
    assert set(map(tuple, sweep.mode[sweep.reachable])) == {sweep.working_mode}
    flipped = np.flatnonzero(inside & (np.abs(thetas) > math.pi / 2))
    assert flipped.size > 50
    expected = np.array([paper.slider_positions((0.0, y, thetas[k]), L, RT, (1, 2, 4)) for k in flipped])
    err = np.abs(sweep.actuators[flipped] - expected).max(axis=1)
    assert err.max() < 1e-11, err.max()  # IK residual 1e-12 times the conditioning, as on the upright arc
