"""Sweep metrics against independent paths: Harada 2011's closed forms and direct library calls."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analyses import _harada2011_paper as paper
from plm_pin import build_mechanism
from plm_pin.exceptions import InvalidInput
from plm_pin.kinematics import classify, error_bound, error_model, inverse_kinematics
from plm_pin.statics import static_forces
from plm_pin.sweep import METRICS, sweep
from plm_pin.workspace import POSE_METRICS, manipulability, orientation_range
from tests.sweep.conftest import FIG6_L, FIG6_RT, FIG6_Y, THETAS, small

LEGS = {"(1, 2, 4)": (1, 2, 4), "(1, 2, 3, 4)": (1, 2, 3, 4)}


@pytest.fixture(scope="module")
def result():
    """The small sweep, run once in this process."""
    return sweep(**small())


def _paper_w(pose, rt, legs) -> float:
    """sqrt(det(J_ce^T J_ce)) from eqs. (2), (4), (12), (13) with the (M.5) working modes."""
    J = paper.J_ce(pose, paper.slider_positions(pose, FIG6_L, rt, legs), FIG6_L, rt, legs)
    return float(np.prod(np.linalg.svd(J, compute_uv=False)))


def test_manipulability_is_the_papers_closed_form_at_every_reached_pose(result):
    """At every reached (legs, r_t, y, theta) w is eq. (13) of the paper's J_ce (1e-9: IK tolerance 1e-12)."""
    ds = result.dataset
    checked = 0
    for label, legs in LEGS.items():
        for rt in ds.half_plate.values:
            for y in ds.y.values:
                w = ds.manipulability.sel(legs=label, half_plate=rt, y=y).values
                lo, hi = paper.reachable_sin_interval(y, FIG6_L, rt)
                for theta, ours in zip(ds.rz.values, w, strict=True):
                    inside = lo < math.sin(theta) < hi
                    assert np.isfinite(ours) == inside, (label, rt, y, theta)
                    if inside:
                        assert ours == pytest.approx(_paper_w((0.0, y, theta), rt, legs), rel=1e-9)
                        checked += 1
    assert checked > 200


def test_pose_metrics_equal_direct_calls_on_the_same_variant(result):
    """At sample poses, w and the margins equal manipulability() and classify() after inverse_kinematics."""
    ds = result.dataset
    for label, rt, y, theta in [
        ("(1, 2, 4)", FIG6_RT, FIG6_Y, THETAS[10]),
        ("(1, 2, 3, 4)", 0.05, 0.11, 0.0),
    ]:
        mech = build_mechanism("harada2011_3d4m", {"legs": LEGS[label], "half_plate": rt})
        q = inverse_kinematics(mech, [0.0, y, theta]).q
        at = {"legs": label, "half_plate": rt, "y": y, "rz": theta}
        assert ds.manipulability.sel(at).item() == pytest.approx(manipulability(mech, q).w, rel=1e-12)
        report = classify(mech, q)
        margin = min(report.constraint_margin, report.inverse_margin, report.direct_margin)
        assert ds.singularity_margin.sel(at).item() == pytest.approx(margin, rel=1e-9)
        assert ds.singularity.sel(at).item() == 0


def test_orientation_range_of_the_3d3m_is_eq_11_4_at_the_fig6_geometry(result):
    """At l : 2 r_t = 2 : 1, y = 0.084039 m, the 3D3M's range ends at -28.7 deg (eq. (11.4)), to 2e-9 rad."""
    ds = result.dataset
    at = {"half_plate": FIG6_RT, "y": FIG6_Y}
    paper_angle = -math.acos(math.sqrt(((FIG6_L + FIG6_RT) ** 2 - FIG6_Y**2) / (FIG6_L + FIG6_RT) ** 2))
    assert math.degrees(paper_angle) == pytest.approx(-28.7, abs=1e-12)
    three = ds.sel(legs="(1, 2, 4)", **at)
    assert abs(three.orientation_lower.item() - paper_angle) < 2e-9
    assert three.orientation_lower_end.item() == three.orientation_lower_end.attrs[
        "flag_meanings"
    ].split().index("direct")
    assert three.orientation_halfwidth.item() == pytest.approx(-paper_angle, abs=2e-9)
    four = ds.sel(legs="(1, 2, 3, 4)", **at)  # the fourth motor removes the singularity: the grid's ends
    assert (four.orientation_lower.item(), four.orientation_upper.item()) == (THETAS[0], THETAS[-1])
    mech = build_mechanism("harada2011_3d4m", {"legs": (1, 2, 4), "half_plate": FIG6_RT})
    direct = orientation_range(mech, "rz", THETAS, (0.0, FIG6_Y, 0.0), xtol=1e-9)
    assert three.orientation_lower.item() == direct.lower and three.orientation_upper.item() == direct.upper


def test_singularity_code_is_direct_on_the_eq_11_4_locus():
    """A pose exactly on eq. (11.4) is coded 3 (direct) for the 3D3M and 0 for the 3D4M."""
    theta = -math.radians(28.7)
    out = sweep(
        "harada2011_3d4m",
        {"legs": [[1, 2, 4], [1, 2, 3, 4]]},
        {"y": [FIG6_Y], "rz": [theta, 0.0]},
        ["singularity"],
        base={"half_plate": FIG6_RT},
    ).dataset
    flags = out.singularity.attrs["flag_meanings"].split()
    assert flags == ["regular", "constraint", "inverse", "direct"]
    assert out.singularity.values[:, 0, :].tolist() == [[3, 0], [0, 0]]
    assert out.singularity_margin.values[0, 0, 0] <= 1e-9


def test_reductions_are_the_minimum_and_mean_over_the_axes_asked(result):
    """min_manipulability is w's minimum over rz; reachable_fraction is eq. (9)'s share of the box."""
    ds = result.dataset
    np.testing.assert_array_equal(ds.min_manipulability.values, ds.manipulability.min("rz").values)
    fractions = sweep(**small(metrics=["reachable_fraction"], options={})).dataset.reachable_fraction
    for rt in ds.half_plate.values:
        inside = [
            lo < math.sin(t) < hi
            for y in ds.y.values
            for lo, hi in [paper.reachable_sin_interval(y, FIG6_L, rt)]
            for t in ds.rz.values
        ]
        assert fractions.sel(half_plate=rt).values.tolist() == [np.mean(inside)] * 2


def test_peak_force_of_the_3d3m_is_eq_15_and_redundancy_never_raises_it():
    """No gravity, unit loads: the 3D3M's peak is max |J_ce^-T f_e| (eq. (15)); the 3D4M's is never above."""
    loads = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.01]]
    ds = sweep(
        "harada2011_3d4m",
        {"legs": [[1, 2, 4], [1, 2, 3, 4]]},
        {"y": [0.07, 0.1], "rz": np.radians([-10.0, 0.0, 15.0])},
        ["peak_force"],
        options={"wrenches": loads, "gravity": False},
    ).dataset
    peak = ds.peak_force.values
    for j, y in enumerate(ds.y.values):
        for k, theta in enumerate(ds.rz.values):
            pose = (0.0, y, theta)
            expected = max(
                np.max(np.abs(paper.statics(pose, -np.asarray(f), 0.14, 0.05, (1, 2, 4))[0])) for f in loads
            )
            assert peak[0, j, k] == pytest.approx(expected, rel=1e-10)
    assert np.all(peak[1] <= peak[0] * (1 + 1e-9))
    mech = build_mechanism("harada2011_3d4m")
    q = inverse_kinematics(mech, [0.0, 0.1, 0.0]).q
    direct = max(
        np.max(np.abs(static_forces(mech, q, f, gravity=False, objective="max", limits=None).f_c))
        for f in loads
    )
    assert peak[1, 1, 1] == pytest.approx(direct, rel=1e-12)


def test_plate_preload_is_the_internal_force_of_eq_21_needed_for_the_compression():
    """3D4M, plate compressed by 2 N: the preload is (2 N + its axial force) times |eq. (22)'s mode|."""
    c = 2.0
    poses = [(0.0, 0.08, math.radians(-20.0)), (0.0, 0.08, 0.0), (0.0, 0.08, math.radians(15.0))]
    load = [0.0, -1.0, 0.0]
    ds = sweep(
        "harada2011_3d4m",
        None,
        {"y": [0.08], "rz": [p[2] for p in poses]},
        ["preload"],
        options={"wrenches": [load], "gravity": False, "compression": c, "preload_links": ["plate"]},
    ).dataset
    mech = build_mechanism("harada2011_3d4m")
    for k, pose in enumerate(poses):
        free = static_forces(mech, inverse_kinematics(mech, pose).q, load, gravity=False)
        axial = free.link_forces()["plate"].axial  # of the minimum-norm forces
        z, J_cm, _, _ = paper.leg_matrices(pose, 0.14, 0.05, (1, 2, 3, 4))
        unit = np.linalg.norm(paper.internal_part(pose, z, J_cm, 1.0))
        assert ds.preload.values[0, k] == pytest.approx(max(0.0, c + axial) * unit, rel=1e-8, abs=1e-10)


def test_every_metric_documents_its_variables_and_options():
    """Each metric has a one-line definition, variables with units and descriptions, and known options."""
    from plm_pin.sweep import OPTIONS

    for name, metric in METRICS.items():
        assert metric.name == name and metric.summary
        for v in metric.variables:
            assert v.unit and v.description and v.dtype in ("float64", "int8", "bool")
        assert set(metric.options) <= set(OPTIONS)


def test_the_grid_computes_the_pose_metrics_the_sweep_reads_and_no_other():
    """The union of the pose metrics the asked metrics read, in POSE_METRICS order; none for reach alone."""
    from plm_pin.sweep.metrics import grid_metrics

    assert grid_metrics(["reachable_fraction", "within_limits", "orientation_range"]) == ()
    assert grid_metrics(["condition_number", "min_manipulability", "manipulability"]) == (
        "manipulability",
        "condition_number",
    )
    assert grid_metrics(["singularity"]) == ("constraint_margin", "inverse_margin", "direct_margin")
    for metric in METRICS.values():
        assert set(metric.grid_metrics) <= set(POSE_METRICS), metric.name


def test_stiffness_without_gravity_is_k_j_ce_t_j_ce_of_the_paper():
    """Unloaded and unpreloaded, the 3D4M's K_x is k J_ce^T J_ce with eq. (12)'s J_ce; metrics read it."""
    k = 3.0e5
    xs = np.array([-0.02, 0.0, 0.02])
    ds = sweep(
        "harada2011_3d4m",
        parameters={"actuator_stiffness": [k]},
        poses={"x": xs, "y": [0.08]},
        metrics=["stiffness"],
        options={"gravity": False, "compliance_direction": [0.0, 1.0]},
    ).dataset
    theta = math.radians(-20.0)  # the preset's reference angle, kept by the pose grid
    legs = (1, 2, 3, 4)
    for i, x in enumerate(xs):
        pose = (x, 0.08, theta)
        J = paper.J_ce(pose, paper.slider_positions(pose, 0.14, 0.05, legs), 0.14, 0.05, legs)
        C = np.linalg.inv(k * J.T @ J)
        got = ds.min_translational_stiffness.values[0, i, 0]
        assert got == pytest.approx(1.0 / np.linalg.eigvalsh(C[:2, :2]).max(), rel=1e-9)
        assert ds.compliance_along.values[0, i, 0] == pytest.approx(C[1, 1], rel=1e-9)
        assert np.isfinite(ds.lowest_frequency.values[0, i, 0])


def test_accuracy_is_the_error_bound_at_the_reached_poses_and_needs_its_tolerances():
    """position_error is the largest bound of error_bound() after inverse_kinematics; tolerances required.

    The reduced variable is its largest over the poses.
    """
    xs, ys = [-0.02, 0.03], [0.22, 0.26, 0.6]  # y = 0.6 m is out of reach
    options = {"length_tolerance": 1e-5, "angle_tolerance": 1e-4}
    ds = sweep("fivebar", {"base": [0.2, 0.22]}, {"x": xs, "y": ys}, ["accuracy"], options=options).dataset
    for base in (0.2, 0.22):
        mech = build_mechanism("fivebar", {"base": base})
        tol = error_model(mech).tolerances(1e-5, 1e-4)
        for x in xs:
            for y in ys[:2]:
                q = inverse_kinematics(mech, [x, y]).q
                expected = error_bound(mech, q, tol).worst_case.max()
                at = {"base": base, "x": x, "y": y}
                assert ds.position_error.sel(at).item() == pytest.approx(expected, rel=1e-9)
        assert np.isnan(ds.position_error.sel(base=base, y=0.6)).all()
        assert np.isnan(ds.angle_error.sel(base=base)).all()  # the task has no angle
        worst = np.nanmax(ds.position_error.sel(base=base).values)
        assert ds.max_position_error.sel(base=base).item() == pytest.approx(worst)
    with pytest.raises(InvalidInput, match="needs the options"):
        sweep("fivebar", None, {"x": xs, "y": ys}, ["accuracy"], options={"length_tolerance": 1e-5})
