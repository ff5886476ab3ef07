"""Workspace maps and sweeps: reachability, working mode, metrics against Harada 2011 eqs. (2)-(4)."""

from __future__ import annotations

import json
import math
import pickle

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from analyses import _harada2011_paper as paper
from plm_pin.exceptions import InvalidInput
from plm_pin.kinematics import classify, inverse_kinematics, task_pose
from plm_pin.kinematics.working_mode import working_mode
from plm_pin.warnings import ReferenceWarning
from plm_pin.workspace import (
    POSE_METRICS,
    _continuation,
    manipulability,
    workspace_grid,
    workspace_map,
    workspace_sweep,
)
from plm_pin.workspace._batch import BatchKinematics
from plm_pin.workspace._continuation import IKEvaluator
from tests.conftest import preset
from tests.kinematics.homotopy.rpr import rpr_files

L, RT = 0.140, 0.05  # Harada 2011 Table 1
THETA = math.radians(-20.0)


def test_map_matches_paper_inverse_kinematics_and_J_ce():
    """Over an x-y grid, actuators follow eq. (2) with the (M.5) signs and w follows eqs. (4), (13)."""
    mech = preset("harada2011_3d4m")
    xs, ys = np.linspace(-0.06, 0.06, 9), np.linspace(0.03, 0.11, 7)
    result = workspace_map(mech, ("x", "y"), (xs, ys), (0.0, 0.08, THETA))
    assert result.reachable.all()
    for i, x in enumerate(xs):
        for j, y in enumerate(ys):
            pose = (x, y, THETA)
            c = paper.slider_positions(pose, L, RT, (1, 2, 3, 4))
            np.testing.assert_allclose(result.actuators[i, j], c, atol=1e-10)
            J = paper.J_ce(pose, c, L, RT, (1, 2, 3, 4))
            assert result.manipulability[i, j] == pytest.approx(math.sqrt(np.linalg.det(J.T @ J)), rel=1e-9)
            assert result.condition_number[i, j] == pytest.approx(np.linalg.cond(J), rel=1e-8)


def _reachable_eq2(y: float, theta: float) -> bool:
    """Both plate pairs within reach of their rods: |y -/+ rt sin(theta)| <= l (eq. (2) real)."""
    return abs(y - RT * math.sin(theta)) <= L and abs(y + RT * math.sin(theta)) <= L


def test_reachable_mask_matches_eq2_and_unreachable_points_are_nan():
    """A y-theta grid crossing the top of the workspace: mask = eq. (2) real; NaN where unreachable."""
    mech = preset("harada2011_3d4m")
    ys = 0.052 + 0.01 * np.arange(15)  # 0.052 to 0.192 m
    thetas = np.radians(np.linspace(-42.5, 42.5, 18))  # 5 deg steps
    expected = np.array([[_reachable_eq2(y, t) for t in thetas] for y in ys])
    # no grid point within 1 mm of the boundary, where "reachable" would hinge on the tolerance
    margin = np.array(
        [[L - max(abs(y - RT * math.sin(t)), abs(y + RT * math.sin(t))) for t in thetas] for y in ys]
    )
    assert np.min(np.abs(margin)) > 1e-3
    result = workspace_map(mech, ("y", "rz"), (ys, thetas), (0.0, 0.08, 0.0))
    assert 0 < expected.sum() < expected.size
    np.testing.assert_array_equal(result.reachable, expected)
    for name in (
        "manipulability",
        "condition_number",
        "direct_margin",
        "inverse_margin",
        "constraint_margin",
    ):
        values = result.metric(name)
        assert np.all(np.isnan(values[~expected])) and np.all(np.isfinite(values[expected]))
    assert np.all(np.isnan(result.q[~expected])) and np.all(np.isnan(result.actuators[~expected]))
    assert result.reachable_fraction == pytest.approx(expected.mean())


def test_working_mode_is_kept_and_recorded():
    """Every reached point keeps the seed's working mode, the reference's (kinematics.working_mode)."""
    mech = preset("harada2011_3d4m")
    result = workspace_map(
        mech, ("x", "rz"), (np.linspace(-0.05, 0.05, 8), np.radians(np.linspace(-35, 35, 9)))
    )
    assert result.working_mode == working_mode(mech, mech.q_ref)
    assert np.all(result.mode[result.reachable] == np.array(result.working_mode))
    for i, j in [(0, 0), (3, 4), (7, 8)]:
        assert working_mode(mech, result.q[i, j]) == result.working_mode
    # the same branch as eq. (2) with the (M.5) signs everywhere
    poses = result.poses()
    for i, j in np.ndindex(result.shape):
        c = paper.slider_positions(poses[i, j], L, RT, (1, 2, 3, 4))
        np.testing.assert_allclose(result.actuators[i, j], c, atol=1e-10)


def test_mode_argument_selects_another_branch():
    """mode= with leg 4 flipped gives slider 4 on the other side of its pair (eq. (2) other sign)."""
    mech = preset("harada2011_3d3m")
    base = working_mode(mech, mech.q_ref)
    flipped = (*base[:-1], -base[-1])
    thetas = np.radians(np.linspace(-30, 30, 7))
    result = workspace_sweep(mech, "rz", thetas, (0.0, 0.07, 0.0), mode=flipped)
    assert result.working_mode == flipped and result.reachable.all()
    signs = {**paper.PAPER_SIGNS, 4: -paper.PAPER_SIGNS[4]}
    for k, t in enumerate(thetas):
        c = paper.slider_positions((0.0, 0.07, t), L, RT, (1, 2, 4), signs)
        np.testing.assert_allclose(result.actuators[k], c, atol=1e-10)


def test_margins_match_classify_and_w_matches_manipulability():
    """The batched metrics equal kinematics.classify and analysis.manipulability at the map's points."""
    mech = preset("harada2011_3d4m")
    result = workspace_map(mech, ("x", "y"), (np.linspace(-0.04, 0.04, 5), np.linspace(0.04, 0.1, 4)))
    for i, j in [(0, 0), (2, 1), (4, 3)]:
        report = classify(mech, result.q[i, j])
        assert result.constraint_margin[i, j] == pytest.approx(report.constraint_margin, rel=1e-9)
        assert result.inverse_margin[i, j] == pytest.approx(report.inverse_margin, rel=1e-9)
        assert result.direct_margin[i, j] == pytest.approx(report.direct_margin, rel=1e-9)
        assert result.manipulability[i, j] == pytest.approx(manipulability(mech, result.q[i, j]).w, rel=1e-9)


@pytest.mark.parametrize("name", ["fivebar", "zhao2011_8pss", "enferadi2017_star_triangle"])
def test_other_mechanisms_map_consistently(name):
    """Maps of a five-bar, the spatial 8-PSS and the star-triangle agree with the single-pose functions."""
    mech = preset(name)
    x0 = task_pose(mech, mech.q_ref)
    dofs = mech.task.dofs
    axes = ("x", "y")
    values = tuple(x0[dofs.index(a)] + np.linspace(-0.02, 0.02, 4) for a in axes)
    result = workspace_map(mech, axes, values)
    assert result.reachable.all()
    for i, j in [(0, 0), (3, 3)]:
        q = result.q[i, j]
        np.testing.assert_allclose(task_pose(mech, q), result.poses()[i, j], atol=1e-11)
        assert np.max(np.abs(mech.closure_residual(q))) <= 1e-12
        assert result.manipulability[i, j] == pytest.approx(manipulability(mech, q).w, rel=1e-9)


def test_parallel_workers_give_the_same_map():
    """Bands solved in two processes and joined give the map of one process."""
    mech = preset("harada2011_3d4m")
    values = (np.linspace(-0.08, 0.08, 24), np.linspace(0.02, 0.17, 20))
    one = workspace_map(mech, ("x", "y"), values, workers=1)
    two = workspace_map(mech, ("x", "y"), values, workers=2)
    assert 0 < one.reachable.sum() < one.reachable.size
    np.testing.assert_array_equal(one.reachable, two.reachable)
    np.testing.assert_allclose(one.manipulability, two.manipulability, rtol=1e-9, equal_nan=True)
    np.testing.assert_allclose(one.actuators, two.actuators, atol=1e-11, equal_nan=True)


MAP_CASES = [("harada2011_3d4m", (0.09, 0.08)), ("zhao2011_8pss", (0.03, 0.03))]
"""Presets and the half-widths in x and y [m] of a 15 x 15 grid about their reference pose."""


def _grid_about_reference(mech, half_width: tuple[float, float]) -> tuple[np.ndarray, ...]:
    """15 values of x and of y centred on the reference pose's, ``half_width`` either side."""
    x0 = task_pose(mech, mech.q_ref)
    dofs = mech.task.dofs
    return tuple(
        x0[dofs.index(a)] + np.linspace(-h, h, 15) for a, h in zip(("x", "y"), half_width, strict=True)
    )


@pytest.mark.parametrize(("name", "half_width"), MAP_CASES)
def test_map_on_the_kernels_equals_the_pinocchio_path(name, half_width, monkeypatch):
    """The compiled path (seed row, batched rows, metrics) and the Pinocchio/numpy path give one map.

    On the 3D4M the grid runs past the reach of the rods, so the edges are filled point by point.
    """
    mech = preset(name)
    values = _grid_about_reference(mech, half_width)
    compiled = workspace_map(mech, ("x", "y"), values, workers=1)
    monkeypatch.setenv("PLM_PIN_KERNELS", "0")
    plain = workspace_map(mech, ("x", "y"), values, workers=1)
    assert compiled.reachable.any() and (name != "harada2011_3d4m" or not compiled.reachable.all())
    np.testing.assert_array_equal(compiled.reachable, plain.reachable)
    np.testing.assert_array_equal(compiled.mode, plain.mode)
    for metric in (
        "manipulability",
        "condition_number",
        "constraint_margin",
        "inverse_margin",
        "direct_margin",
    ):
        np.testing.assert_allclose(compiled.metric(metric), plain.metric(metric), rtol=1e-8, equal_nan=True)
    np.testing.assert_allclose(compiled.actuators, plain.actuators, atol=1e-11, equal_nan=True)


LINES = [
    ("harada2011_3d3m", "rz", np.radians(np.linspace(-85.0, 85.0, 69)), 0.1),
    ("zhao2011_8pss", "z", np.linspace(-0.8, 0.8, 69), None),
]
"""Sweeps past the reach: preset, axis, values about the reference pose's (the 3D3M: absolute), y [m]."""


@pytest.mark.parametrize(("name", "axis", "line", "y"), LINES)
def test_line_walked_on_the_kernels_equals_the_pinocchio_path(name, axis, line, y, monkeypatch):
    """A sweep past the reach, walked from its seed by one compiled call per side.

    It equals the point-by-point Pinocchio path: reachable set, modes, configurations and metrics
    (the 8-PSS: a free-flyer, its extrapolated quaternions put back to unit norm).
    """
    mech = preset(name)
    x0 = task_pose(mech, mech.q_ref)
    values = line if y is not None else x0[mech.task.dofs.index(axis)] + line
    if y is not None:
        x0[mech.task.dofs.index("y")] = y
    walked = []
    walk = _continuation._walk_seed_row
    monkeypatch.setattr(_continuation, "_walk_seed_row", lambda *a: walked.append(walk(*a)))
    compiled = workspace_sweep(mech, axis, values, x0)
    assert walked
    monkeypatch.setenv("PLM_PIN_KERNELS", "0")
    plain = workspace_sweep(mech, axis, values, x0)
    assert 0.2 < compiled.reachable_fraction < 1.0  # the walk stops at the edge
    np.testing.assert_array_equal(compiled.reachable, plain.reachable)
    np.testing.assert_array_equal(compiled.mode, plain.mode)
    np.testing.assert_allclose(compiled.q, plain.q, rtol=0.0, atol=1e-10)
    for metric in POSE_METRICS:
        np.testing.assert_allclose(compiled.metric(metric), plain.metric(metric), rtol=1e-8, equal_nan=True)


def test_3d_grid_solved_point_by_point_on_the_kernels_equals_the_pinocchio_path(monkeypatch):
    """A Delta's x-y-z grid, past its reach, solved point by point: the kernels' Jacobians and modes agree.

    A three-axis grid is not walked by rows: every point is solved by Newton from its
    neighbours, its IK Jacobian and working mode read by the kernels (one compiled call at the
    solution) or from Pinocchio's data.
    """
    mech = preset("delta")
    x0 = task_pose(mech, mech.q_ref)
    values = tuple(x0[i] + np.linspace(-0.5, 0.5, 6) for i in range(3))
    compiled = workspace_grid(mech, ("x", "y", "z"), values)
    monkeypatch.setenv("PLM_PIN_KERNELS", "0")
    plain = workspace_grid(mech, ("x", "y", "z"), values)
    assert 0.2 < compiled.reachable_fraction < 1.0
    np.testing.assert_array_equal(compiled.reachable, plain.reachable)
    np.testing.assert_array_equal(compiled.mode, plain.mode)
    np.testing.assert_allclose(compiled.q, plain.q, rtol=0.0, atol=1e-11)
    for metric in POSE_METRICS:
        np.testing.assert_allclose(compiled.metric(metric), plain.metric(metric), rtol=1e-8, equal_nan=True)


def test_map_of_a_user_mechanism_with_kernel_only_joints_walks_rows_on_the_kernels(tmp_path, monkeypatch):
    """A 3-RPR of one's own with continuous pivots walks its rows on the kernels; the Pinocchio path agrees.

    Continuous joints ((cos, sin) pairs) are outside the numpy batch evaluator, so the kernels
    walk the rows alone; the map equals the point-by-point Pinocchio one. The grid runs near a
    direct singularity, where solutions converged to the same residual tolerance from other
    starts differ by the tolerance times the condition number: the metrics are compared at
    condition numbers below 1e3.
    """
    base = np.array([[0.0, 0.0], [1.0, 0.0], [0.3, 0.9]])
    plate = np.array([[0.0, 0.0], [0.45, 0.05], [0.15, 0.35]])
    with pytest.warns(ReferenceWarning, match="moved it away"):  # no reference given: the loader picks one
        mech = plm_pin.load(rpr_files(tmp_path, base, plate))
    ev = IKEvaluator.from_mechanism(mech)
    assert ev.kernel is not None and BatchKinematics.from_parts(ev.model, ev.closures, ev.task) is None
    walked = []
    walk = _continuation._walk_rows
    monkeypatch.setattr(_continuation, "_walk_rows", lambda *a: walked.append(walk(*a)))
    x0 = task_pose(mech, mech.q_ref)
    values = (x0[0] + np.linspace(-1.0, 1.0, 25), x0[1] + np.linspace(-1.0, 1.0, 21))
    compiled = workspace_map(mech, ("x", "y"), values, workers=1)
    assert walked
    monkeypatch.setenv("PLM_PIN_KERNELS", "0")
    plain = workspace_map(mech, ("x", "y"), values, workers=1)
    assert compiled.reachable.all() and plain.reachable.all()
    np.testing.assert_array_equal(compiled.mode, plain.mode)
    np.testing.assert_allclose(compiled.q, plain.q, rtol=0.0, atol=1e-9)
    assert plain.condition_number.max() > 1e3  # near the singularity
    well = plain.condition_number < 1e3
    for metric in POSE_METRICS:
        np.testing.assert_allclose(compiled.metric(metric)[well], plain.metric(metric)[well], rtol=1e-9)


SUBSETS = (
    ("manipulability",),
    ("condition_number", "direct_margin"),
    ("constraint_margin",),
    ("inverse_margin",),
    ("manipulability", "inverse_margin"),
    (),
)


@pytest.mark.parametrize(("name", "half_width"), MAP_CASES)
@pytest.mark.parametrize("kernels", [True, False])
def test_a_map_of_some_metrics_equals_the_full_map_on_them(name, half_width, kernels, monkeypatch):
    """Each subset of the metrics gives the all-five map's values on its columns and NaN elsewhere.

    On either path (compiled, numpy); a pose may pass the acceptance tests of a subset and not
    those of all five, so a value may come from the Gram eigenvalues in one map and the SVD in
    the other: equal to round-off.
    """
    if not kernels:
        monkeypatch.setenv("PLM_PIN_KERNELS", "0")
    mech = preset(name)
    values = _grid_about_reference(mech, half_width)
    full = workspace_map(mech, ("x", "y"), values, workers=1)
    assert full.metrics == POSE_METRICS and full.reachable.any()
    for subset in SUBSETS:
        part = workspace_map(mech, ("x", "y"), values, workers=1, metrics=list(reversed(subset)))
        assert part.metrics == subset  # in the order of POSE_METRICS
        np.testing.assert_array_equal(part.reachable, full.reachable)
        np.testing.assert_array_equal(part.q, full.q)
        for metric in POSE_METRICS:
            if metric in subset:
                np.testing.assert_allclose(
                    part.metric(metric), full.metric(metric), rtol=1e-11, equal_nan=True, err_msg=metric
                )
            else:
                assert np.isnan(getattr(part, metric)).all()
                with pytest.raises(InvalidInput, match=rf"metric '{metric}' was not computed"):
                    part.metric(metric)


def test_unknown_metrics_are_refused_and_one_name_is_a_subset():
    """A bad name is refused with the valid choices; a string names one metric."""
    mech = preset("harada2011_3d4m")
    xs, ys = np.linspace(-0.02, 0.02, 3), np.linspace(0.06, 0.08, 3)
    with pytest.raises(InvalidInput, match=r"metrics: unknown metric 'w'; choose among \['manipulability', "):
        workspace_map(mech, ("x", "y"), (xs, ys), metrics=("manipulability", "w"))
    with pytest.raises(InvalidInput, match=r"metrics: unknown metric 3; choose among"):
        workspace_sweep(mech, "x", xs, metrics=[3])
    with pytest.raises(InvalidInput, match=r"metrics must be a list of names among"):
        workspace_grid(mech, ("x",), (xs,), metrics=7)
    one = workspace_sweep(mech, "x", xs, metrics="direct_margin")
    assert one.metrics == ("direct_margin",) and np.isfinite(one.direct_margin).all()
    assert np.isnan(one.manipulability).all()


def test_three_axis_grid_follows_the_papers_inverse_kinematics_and_the_2d_map():
    """An x-y-theta grid: actuators follow eq. (2) with the (M.5) signs; its theta slice is the x-y map."""
    mech = preset("harada2011_3d4m")
    xs, ys, ths = np.linspace(-0.03, 0.03, 4), np.linspace(0.05, 0.1, 5), np.radians([-30.0, -20.0, 0.0])
    grid = workspace_grid(mech, ("x", "y", "rz"), (xs, ys, ths))
    assert grid.shape == (4, 5, 3) and grid.reachable.all() and grid.q.shape == (4, 5, 3, mech.nq)
    for i, j, k in np.ndindex(grid.shape):
        c = paper.slider_positions((xs[i], ys[j], ths[k]), L, RT, (1, 2, 3, 4))
        np.testing.assert_allclose(grid.actuators[i, j, k], c, atol=1e-11)
    flat = workspace_map(mech, ("x", "y"), (xs, ys), (0.0, 0.08, ths[1]))
    np.testing.assert_allclose(grid.manipulability[:, :, 1], flat.manipulability, rtol=1e-10)
    assert grid.working_mode == flat.working_mode == working_mode(mech, mech.q_ref)
    with pytest.raises(InvalidInput, match=r"give one array of values per varied coordinate; got axes"):
        workspace_grid(mech, ("x",), (xs, ys))


def test_nothing_reachable_gives_an_empty_map():
    """A slice entirely out of reach is returned unreachable everywhere instead of raising."""
    mech = preset("harada2011_3d4m")
    result = workspace_map(mech, ("x", "y"), (np.linspace(-0.05, 0.05, 3), np.linspace(0.25, 0.3, 3)))
    assert not result.reachable.any() and result.working_mode is None
    assert np.all(np.isnan(result.manipulability))
    data = json.loads(json.dumps(result.to_dict(), allow_nan=False))  # NaN and inf as text
    assert data["manipulability"] == [["nan"] * 3] * 3 and data["working_mode"] is None


def test_sweep_shapes_and_json():
    """A sweep has 1-D arrays along its axis and serialises to JSON."""
    mech = preset("harada2011_3d3m")
    thetas = np.radians(np.linspace(-60, 60, 13))
    result = workspace_sweep(mech, "rz", thetas)
    assert result.shape == (13,) and result.actuators.shape == (13, 3) and result.q.shape == (13, mech.nq)
    data = json.loads(json.dumps(result.to_dict()))
    assert data["axes"] == ["rz"] and len(data["manipulability"]) == 13
    assert list(data) == [
        *("axes", "values", "pose", "dofs", "reachable", "manipulability", "condition_number"),
        *("constraint_margin", "inverse_margin", "direct_margin", "actuators", "mode", "working_mode"),
        "metrics",
    ]  # q left out
    assert data["metrics"] == list(POSE_METRICS)
    with pytest.raises(ValueError):
        result.manipulability[0] = 1.0  # read-only


def test_bad_input_messages():
    """Unknown or repeated axes, a wrong pose and a wrong metric name are refused by name."""
    mech = preset("harada2011_3d4m")
    v = np.linspace(0, 0.01, 2)
    with pytest.raises(
        InvalidInput, match=r"unknown task coordinate 'z'; the task's coordinates are \['x', 'y', 'rz'\]"
    ):
        workspace_map(mech, ("x", "z"), (v, v))
    with pytest.raises(InvalidInput, match="the varied coordinates must differ"):
        workspace_map(mech, ("x", "x"), (v, v))
    with pytest.raises(InvalidInput, match="pose must hold 3 finite task coordinates"):
        workspace_sweep(mech, "x", v, pose=(0.0, 0.1))
    with pytest.raises(InvalidInput, match="must be a non-empty 1-D array"):
        workspace_sweep(mech, "x", [])
    with pytest.raises(InvalidInput, match="unknown metric 'w'"):
        workspace_sweep(mech, "x", v).metric("w")


@pytest.mark.parametrize(
    ("name", "axes", "steps"),
    [
        ("harada2011_3d4m", ("x", "rz"), (0.01, 0.05)),
        ("zhao2011_8pss", ("x", "ry"), (0.01, 0.02)),
        ("enferadi2017_star_triangle", ("y", "rz"), (0.005, 0.02)),
    ],
)
def test_continuation_solutions_equal_inverse_kinematics(name, axes, steps):
    """On 3 x 3 maps (planar, spatial), each configuration is inverse_kinematics's (SVD Newton from q_ref)."""
    mech = preset(name)
    x_ref = task_pose(mech, mech.q_ref)
    dofs = mech.task_compiled.dofs
    values = tuple(x_ref[dofs.index(a)] + h * np.arange(-1.0, 2.0) for a, h in zip(axes, steps, strict=True))
    result = workspace_map(mech, axes, values)
    assert result.reachable.all()
    poses = result.poses()
    for i, j in np.ndindex(result.shape):
        sol = inverse_kinematics(mech, poses[i, j], mech.q_ref)
        assert sol.mode == result.working_mode
        gap = pin.difference(mech.model, sol.q, result.q[i, j])
        assert np.max(np.abs(gap)) <= 1e-12


def test_continuation_evaluator_pickles_for_worker_processes():
    """The evaluator survives pickling (spawned workers) and solves a pose to the same configuration."""
    mech = preset("harada2011_3d4m")
    ev = IKEvaluator.from_mechanism(mech)
    copy = pickle.loads(pickle.dumps(ev))
    x = task_pose(mech, mech.q_ref) + np.array([1e-3, -1e-3, 1e-2])
    a, b = ev.solve(x, mech.q_ref, 1e-12), copy.solve(x, mech.q_ref, 1e-12)
    assert a is not None and b is not None
    np.testing.assert_array_equal(a, b)
    assert copy.mode(copy.jacobian()) == working_mode(mech, b)


def test_parallel_bands_of_a_map_the_batched_rows_do_not_take_give_the_same_map(monkeypatch):
    """A star-triangle map solved point by point in one process and in two give the same map.

    Off the kernels, its closures are outside the numpy row batches, so the grid is split into
    bands of rows solved in parallel.
    """
    monkeypatch.setenv("PLM_PIN_KERNELS", "0")
    mech = preset("enferadi2017_star_triangle")
    assert BatchKinematics.from_parts(mech.model, mech.closures, mech.task_compiled) is None
    x0 = task_pose(mech, mech.q_ref)
    values = (x0[0] + np.linspace(-0.02, 0.02, 8), x0[1] + np.linspace(-0.02, 0.02, 5))
    one = workspace_map(mech, ("x", "y"), values, pose=x0, workers=1)
    two = workspace_map(mech, ("x", "y"), values, pose=x0, workers=2)
    assert one.reachable.all()
    np.testing.assert_allclose(one.manipulability, two.manipulability, rtol=1e-9)
    np.testing.assert_allclose(one.actuators, two.actuators, atol=1e-11)
