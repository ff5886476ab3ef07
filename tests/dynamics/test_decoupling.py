"""Decoupling checks: Harada 2011's decoupled x axis, and what the 2015 asymmetric table loses."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from plm_pin import InvalidInput, PoseUnreachable
from plm_pin.dynamics import task_space_dynamics
from plm_pin.dynamics.decoupling import decoupling_check
from plm_pin.models import PRESETS
from plm_pin.tolerances import DECOUPLING_RTOL
from plm_pin.workspace import workspace_map
from tests.conftest import preset
from tests.dynamics.test_task_space import lagrange_inertia_and_gravity

BOX = (np.array([-0.04, 0.04, -0.35]), np.array([0.04, 0.12, 0.35]))
"""Box of plate poses (x [m], y [m], theta [rad]) sampled; it reaches past the 3D3M's workspace."""


def box_sample(n: int, seed: int) -> np.ndarray:
    """``n`` poses drawn uniformly in :data:`BOX`."""
    return np.random.default_rng(seed).uniform(*BOX, size=(n, 3))


def closed_form_range(name: str, poses: np.ndarray, i: int, j: int) -> tuple[float, float]:
    """Smallest and largest M_x[i, j] of the hand Lagrange derivation over ``poses``."""
    values = [lagrange_inertia_and_gravity(PRESETS[name].parameters, p)[0][i, j] for p in poses]
    return min(values), max(values)


def test_3d4m_x_axis_is_decoupled_with_constant_inertia():
    """3D4M: m_xx = 4 m_l + 4 m_m + m_t, m_xy = m_x-theta = 0, g = (0, (2 m_l + m_t) g, 0), h_x = 0."""
    p = PRESETS["harada2011_3d4m"].parameters
    mm, ml, mt, g = p["slider_mass"], p["rod_masses"][0], p["plate_mass"], p["gravity"]
    report = decoupling_check(preset("harada2011_3d4m"), box_sample(30, 1))
    assert report.n_poses + len(report.unreachable) + len(report.singular) == 30
    xx = report.inertia("x", "x")
    assert xx.kind == "constant" and xx.value == pytest.approx(4 * ml + 4 * mm + mt, rel=1e-12)
    assert report.inertia("x", "y").kind == report.inertia("x", "rz").kind == "zero"
    assert report.inertia("rz", "x").kind == "zero"
    assert [report.gravity(d).kind for d in ("x", "y", "rz")] == ["zero", "constant", "zero"]
    assert report.gravity("y").value == pytest.approx((2 * ml + mt) * g, rel=1e-12)
    assert [report.velocity(d).kind for d in ("x", "y", "rz")] == ["zero", "nonzero", "nonzero"]
    yy = report.inertia("y", "y")
    assert yy.kind == "varies"
    assert (yy.minimum, yy.maximum) == pytest.approx(closed_form_range("harada2011_3d4m", report.poses, 1, 1))
    assert report.decoupled() == ("x",)


@pytest.mark.parametrize("name", ["harada2011_3d4m", "harada2011_3d3m", "harada2015_asymmetric"])
def test_x_inertia_is_constant_on_any_one_stator_table(name):
    """m_xx = sum (m_m + m_l) + m_t on every 2-PRRRP: a pure x motion translates every body rigidly."""
    p = PRESETS[name].parameters
    legs = p.get("legs", (1, 2, 3, 4))
    expected = sum(p["slider_mass"] + p["rod_masses"][i - 1] for i in legs) + p["plate_mass"]
    xx = decoupling_check(preset(name), box_sample(12, 2)).inertia("x", "x")
    assert xx.kind == "constant" and xx.value == pytest.approx(expected, rel=1e-12)


def test_asymmetric_table_loses_the_x_decoupling_by_the_hand_derived_couplings():
    r"""Harada 2015 (l1 = l4 = 0.24 m, l2 = l3 = 0.17 m): m_xy, m_x-theta and h_x no longer vanish.

    Hand derivation (``test_task_space.lagrange_inertia_and_gravity``): a pair's legs couple
    x and y by :math:`\sum -\sigma_i k_i (m_m + m_{li}/2)`, :math:`k_i = P_y / \sqrt{l_i^2 - P_y^2}`,
    which cancels between the two legs of a pair (opposite :math:`\sigma`) only when their
    rods are equal. The report's ranges must be those of that closed form over the same
    poses, which exceed the tolerance by orders of magnitude; m_xx and g keep the 2011 form
    (each pair still carries the same rod mass).
    """
    name = "harada2015_asymmetric"
    report = decoupling_check(preset(name), box_sample(30, 3))
    assert report.n_poses >= 25
    for column, j in (("y", 1), ("rz", 2)):
        entry = report.inertia("x", column)
        assert entry.kind == "varies"
        assert (entry.minimum, entry.maximum) == pytest.approx(
            closed_form_range(name, report.poses, 0, j), rel=1e-9
        )
        assert entry.largest > 1e6 * entry.tolerance
    assert report.inertia("x", "x").kind == "constant"
    assert [report.gravity(d).kind for d in ("x", "y", "rz")] == ["zero", "constant", "zero"]
    assert report.velocity("x").kind == "nonzero"
    assert report.decoupled() == ()


def test_asymmetric_table_keeps_m_xy_zero_at_zero_tilt():
    """At theta = 0 both pairs see the same P_y, legs 1, 4 and 2, 3 mirror: m_xy = 0, m_x-theta != 0."""
    name = "harada2015_asymmetric"
    mech = preset(name)
    grid = workspace_map(mech, ("x", "y"), (np.linspace(-0.03, 0.03, 4), np.linspace(0.05, 0.14, 5)))
    report = decoupling_check(mech, grid)
    assert (
        report.n_poses == int(grid.reachable.sum())
        and len(report.unreachable) == grid.reachable.size - report.n_poses
    )
    assert report.inertia("x", "y").kind == "zero"
    xt = report.inertia("x", "rz")
    assert xt.kind == "varies"
    assert (xt.minimum, xt.maximum) == pytest.approx(closed_form_range(name, report.poses, 0, 2), rel=1e-9)


def test_unreachable_and_singular_poses_are_skipped_and_listed():
    """A pose out of reach and one with every rod vertical (y = l) are skipped and reported, not raised."""
    sample = [(0.0, 0.08, 0.0), (0.0, 0.5, 0.0), (0.0, 0.14, 0.0)]
    report = decoupling_check(preset("harada2011_3d4m"), sample)
    assert report.n_poses == 1
    np.testing.assert_array_equal(report.unreachable, [[0.0, 0.5, 0.0]])
    np.testing.assert_array_equal(report.singular, [[0.0, 0.14, 0.0]])
    assert "over 1 poses (1 unreachable and 1 singular skipped)" in report.to_table()


def test_a_velocity_term_is_zero_or_nonzero_never_constant():
    """h_x vanishes at zero velocity, so a non-vanishing row is 'nonzero', not 'constant' nor 'varies'."""
    report = decoupling_check(preset("harada2011_3d4m"), [(0.0, 0.08, 0.1)])
    assert report.velocity("y").kind == "nonzero" and report.velocity("x").kind == "zero"
    assert report.velocity("y").minimum < report.velocity("y").maximum


def test_the_stated_velocities_determine_h_x_at_every_velocity(rng):
    """h_x at v e_i and v (e_i + e_j) fixes the quadratic form: polarised, it gives h_x at any other velocity.

    Gamma_ii = h(e_i), Gamma_ij + Gamma_ji = h(e_i + e_j) - h(e_i) - h(e_j), h(xd) = sum xd_i xd_j Gamma_ij,
    compared with task_space_dynamics at random velocities, on the asymmetric table (no row vanishes).
    """
    mech = preset("harada2015_asymmetric")
    pose = (0.01, 0.1, 0.2)
    report = decoupling_check(mech, [pose], velocity_scale=0.5)
    np.testing.assert_array_equal(
        report.velocities, 0.5 * np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [1, 0, 1], [0, 1, 1]])
    )
    assert "h_x at the 6 task velocities v e_i and v (e_i + e_j), i < j, with v = 0.5 m/s or rad/s" in (
        report.to_table()
    )
    q = report.configurations[0]
    h = {tuple(v): task_space_dynamics(mech, q, xdot=v).h_x for v in report.velocities}
    e = 0.5 * np.eye(3)
    G = np.zeros((3, 3, 3))  # G[i, j] = Gamma_ij (a vector over rows), per unit rate 0.5
    for i in range(3):
        G[i, i] = h[tuple(e[i])]
        for j in range(i + 1, 3):
            G[i, j] = G[j, i] = 0.5 * (h[tuple(e[i] + e[j])] - h[tuple(e[i])] - h[tuple(e[j])])
    for xd in rng.normal(size=(4, 3)):
        c = xd / 0.5
        expected = np.einsum("i,j,ijk->k", c, c, G)
        np.testing.assert_allclose(task_space_dynamics(mech, q, xdot=xd).h_x, expected, rtol=1e-9, atol=1e-12)
    values = np.array(list(h.values()))
    assert (report.velocity("x").minimum, report.velocity("x").maximum) == (
        values[:, 0].min(),
        values[:, 0].max(),
    )


def test_a_range_is_written_with_the_digits_that_tell_its_ends_apart():
    """An entry that varies by less than 4 digits shows more, never 'varies 1.736 .. 1.736'."""
    from plm_pin.dynamics.decoupling import EntryBehaviour

    entry = EntryBehaviour("varies", 1.7360001, 1.7360004, 1e-9, 1.0, "kg")
    assert entry.describe() == "1.7360001 .. 1.7360004 kg"
    assert EntryBehaviour("varies", -2.5, 3.25, 1e-9, 1.0, "N").describe() == "-2.5 .. 3.25 N"


def test_table_and_dict_state_the_tolerances():
    """The table gives values, kinds and the tolerance rule; to_dict is JSON."""
    report = decoupling_check(preset("harada2011_3d4m"), box_sample(5, 4))
    table = report.to_table()
    assert "zero: |value| <= atol + rtol x its Cauchy-Schwarz bound at every pose" in table
    assert f"tol = atol + rtol x largest bound (atol = 0, rtol = {DECOUPLING_RTOL:g})" in table
    assert "1.736 kg" in table and "1.8032 N" in table
    assert table.endswith("decoupled with constant inertia: x")
    data = json.loads(json.dumps(report.to_dict()))
    assert data["M_x"][0][1]["kind"] == "zero" and data["M_x"][0][2]["unit"] == "kg m"
    assert data["decoupled"] == ["x"] and data["rtol"] == DECOUPLING_RTOL
    m_xx = report.inertia("x", "x")
    assert data["M_x"][0][0] == {
        "kind": m_xx.kind,
        "minimum": m_xx.minimum,
        "maximum": m_xx.maximum,
        "tolerance": m_xx.tolerance,
        "ratio": m_xx.ratio,
        "unit": "kg",
    }
    assert data["n_poses"] == report.n_poses and "M_min" not in data and "configurations" not in data


def test_coupling_ratio_is_the_largest_correlation_and_sets_what_rtol_neglects():
    """The ratio is max |m_xy| / sqrt(m_xx m_yy) of the hand derivation; m_xy is zero iff rtol is above it."""
    name = "harada2015_asymmetric"
    poses = box_sample(8, 5)
    report = decoupling_check(preset(name), poses)
    correlations = []
    for pose in report.poses:
        M = lagrange_inertia_and_gravity(PRESETS[name].parameters, pose)[0]
        correlations.append(abs(M[0, 1]) / math.sqrt(M[0, 0] * M[1, 1]))
    ratio = report.inertia("x", "y").ratio
    assert ratio == pytest.approx(max(correlations), rel=1e-9)
    assert 0.01 < ratio < 1.0  # a physical coupling, far from rounding
    assert report.inertia("x", "x").ratio == pytest.approx(1.0)
    assert decoupling_check(preset(name), poses, rtol=1.001 * ratio).inertia("x", "y").kind == "zero"
    assert decoupling_check(preset(name), poses, rtol=0.999 * ratio).inertia("x", "y").kind == "varies"


def test_refuses_bad_samples_and_settings():
    """Empty, malformed, non-finite or wholly unreachable samples and bad settings raise with the reason."""
    mech = preset("harada2011_3d4m")
    with pytest.raises(InvalidInput, match="the sample is empty"):
        decoupling_check(mech, np.zeros((0, 3)))
    with pytest.raises(InvalidInput, match=r"poses must have shape \(k, 3\), got \(2, 2\)"):
        decoupling_check(mech, np.zeros((2, 2)))
    with pytest.raises(InvalidInput, match=r"non-finite entries in rows \[1\]"):
        decoupling_check(mech, [(0.0, 0.08, 0.0), (0.0, math.nan, 0.0)])
    with pytest.raises(PoseUnreachable, match=r"none of the 1 poses could be evaluated \(1 unreachable"):
        decoupling_check(mech, [(0.0, 0.5, 0.0)])
    with pytest.raises(InvalidInput, match=r"^rtol must be a finite number >= 0, got -1.0$"):
        decoupling_check(mech, [(0.0, 0.08, 0.0)], rtol=-1.0)
    with pytest.raises(
        InvalidInput, match=r"^velocity_scale must be a positive finite number \[m/s, rad/s\], got 0$"
    ):
        decoupling_check(mech, [(0.0, 0.08, 0.0)], velocity_scale=0)
    fivebar_grid = workspace_map(preset("fivebar"), ("x", "y"), ([0.0], [0.2]))
    with pytest.raises(InvalidInput, match="does not belong to harada2011_3d4m"):
        decoupling_check(mech, fivebar_grid)
    report = decoupling_check(mech, [(0.0, 0.08, 0.0)])
    with pytest.raises(
        InvalidInput, match=r"unknown task coordinate 'z'; the task's coordinates are \['x', 'y', 'rz'\]"
    ):
        report.inertia("x", "z")
