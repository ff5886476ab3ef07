"""Batched kinematics across poses (plm_pin/workspace/_batch.py) against Pinocchio and the serial path."""

from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest

from plm_pin.core import closures as _closures
from plm_pin.core.legs import working_mode_from_data, working_mode_from_jacobian
from plm_pin.core.task import TaskTarget
from plm_pin.kinematics import task_pose
from plm_pin.kinematics.jacobians import ik_jacobian
from plm_pin.tolerances import GRAM_RTOL
from plm_pin.workspace import _continuation, workspace_map
from plm_pin.workspace._batch import (
    BatchKinematics,
    _small_det,
    batch_modes,
    batch_newton,
    log3_and_jacobian,
    square_task_metrics,
)
from plm_pin.workspace.manipulability import POSE_METRICS, batch_metrics
from tests.conftest import preset


def _random_configurations(mech, rng, n, scale=0.5):
    """Configurations spread around the reference (on the manifold of a free-flyer's quaternion)."""
    return np.stack(
        [pin.integrate(mech.model, mech.q_ref, rng.normal(scale=scale, size=mech.nv)) for _ in range(n)]
    )


@pytest.mark.parametrize("name", ["harada2011_3d4m", "zhao2011_8pss"])
def test_batched_residual_and_jacobian_equal_pinocchio_to_1e_13(name):
    """At 40 random configurations, the numpy tree gives Pinocchio's residual, Jacobians and working modes.

    The 3D4M (one-axis joints, planar yaw row) and the 8-PSS (free-flyer platform, log3 rows
    of a 6-D task, passive revolute columns turned for the working mode).
    """
    mech = preset(name)
    kin = BatchKinematics.from_parts(mech.model, mech.closures, mech.task_compiled)
    assert kin is not None
    rng = np.random.default_rng(7)
    Q = _random_configurations(mech, rng, 40, scale=1.5)
    X = task_pose(mech, mech.q_ref) + rng.normal(scale=0.05, size=(40, mech.task_compiled.size))
    e = kin.evaluate(Q, X)
    A = e.ik_jacobian(np.arange(40))
    turns = kin.turns(e.R, mech.legs)
    data = mech.model.createData()
    modes = set()
    for b in range(40):
        pin.computeJointJacobians(mech.model, data, Q[b])
        pin.updateFramePlacements(mech.model, data)
        target = TaskTarget(mech.task_compiled, X[b])
        expected_r = np.concatenate(
            [_closures.residual_from_placements(data, mech.closures), target.residual(data)]
        )
        expected_J = np.vstack(
            [_closures.jacobian(mech.model, data, mech.closures, Q[b]), target.jacobian(mech.model, data)]
        )
        expected_mode = working_mode_from_data(mech.model, data, mech.closures, mech.task_compiled, mech.legs)
        assert np.abs(e.r[b] - expected_r).max() < 1e-13
        assert np.abs(e.J[b] - expected_J).max() < 1e-13
        assert np.abs(A[b] - ik_jacobian(mech, Q[b])).max() < 1e-13
        mode = tuple(batch_modes(A[b : b + 1], mech.legs, [t[b : b + 1] for t in turns])[0])
        assert mode == expected_mode
        modes.add(mode)
    assert len(modes) > 1  # the draws cross working modes
    assert any((t < 0).any() for t in turns) == (name == "zhao2011_8pss")  # spatial legs turn columns


def test_batched_log3_equals_pinocchio_at_small_and_large_angles():
    r"""log3 gives exp3's rotation vector back, Jlog3 the inverse of its right Jacobian, 1e-9 to 3 rad.

    The Jacobian's reference is :math:`J_r(\omega)^{-1}`, :math:`J_r = I - (1 - \cos\theta)/\theta^2
    [\omega]_\times + (\theta - \sin\theta)/\theta^3 [\omega]_\times^2` with its series below
    0.01 rad (pin.Jlog3 itself loses about 4e-10 near 5e-4 rad, where its closed form cancels;
    pin.log3 about 1.5e-14 at 3 rad).
    """
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(12, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.array([1e-9, 1e-6, 5e-5, 9.9e-5, 1.01e-4, 5e-4, 1e-3, 0.1, 0.5, 1.0, 2.0, 3.0])
    E = np.stack([pin.exp3(a * u) for a, u in zip(angles, axes, strict=True)])
    log, J = log3_and_jacobian(E)
    for b, (th, u) in enumerate(zip(angles, axes, strict=True)):
        K = pin.skew(th * u)
        if th > 1e-2:
            c1, c2 = (1.0 - np.cos(th)) / th**2, (th - np.sin(th)) / th**3
        else:
            c1, c2 = 0.5 - th**2 / 24.0 + th**4 / 720.0, 1.0 / 6.0 - th**2 / 120.0 + th**4 / 5040.0
        J_right = np.eye(3) - c1 * K + c2 * K @ K
        assert np.abs(log[b] - th * u).max() < 1e-14
        assert np.abs(log[b] - pin.log3(E[b])).max() < 1e-13
        assert np.abs(J[b] - np.linalg.inv(J_right)).max() < 1e-14


def test_batched_integrate_is_pinocchio_to_first_order():
    """The free-flyer retraction of batched Newton is pin.integrate to O(|dv|^2), with unit quaternions."""
    mech = preset("zhao2011_8pss")
    kin = BatchKinematics.from_parts(mech.model, mech.closures, mech.task_compiled)
    rng = np.random.default_rng(5)
    Q = _random_configurations(mech, rng, 10)
    for h in (1e-3, 1e-5):
        dv = h * rng.normal(size=(10, mech.nv))
        moved = kin.integrate(Q, dv)
        expected = np.stack([pin.integrate(mech.model, q, v) for q, v in zip(Q, dv, strict=True)])
        assert np.abs(moved - expected).max() < 10 * h**2
        assert np.allclose(np.linalg.norm(moved[:, 3:7], axis=1), 1.0, atol=1e-15, rtol=0.0)


def test_batched_newton_modes_and_metrics_match_the_serial_ones():
    """Batched Newton converges to 1e-12; its modes and factorised metrics are the serial ones."""
    mech = preset("harada2011_3d4m")
    kin = BatchKinematics.from_parts(mech.model, mech.closures, mech.task_compiled)
    assert kin is not None
    x0 = task_pose(mech, mech.q_ref)
    X = x0 + np.column_stack([np.linspace(-2e-3, 2e-3, 9), np.linspace(1e-3, -1e-3, 9), np.zeros(9)])
    q, ok, A, _ = batch_newton(kin, np.tile(mech.q_ref, (9, 1)), X, 1e-12, 12, 0.9)
    assert ok.all()
    m = mech.n_closure_rows
    for b in range(9):
        A_serial = ik_jacobian(mech, q[b])
        assert np.abs(A[b] - A_serial).max() < 1e-13
        assert tuple(batch_modes(A[b : b + 1], mech.legs)[0]) == working_mode_from_jacobian(
            A_serial, mech.legs
        )
    fast = square_task_metrics(A, m, mech.actuated_v_indices, mech.mobility)
    svd = batch_metrics(A[:, :m], A[:, m:], mech.actuated_v_indices, mech.mobility)
    for name, values in svd.items():
        assert np.allclose(fast[name], values, rtol=1e-12, atol=0.0), name


def test_small_determinants_equal_lapack(rng):
    """Cofactor determinants (n <= 3, one singular) equal LAPACK's to round-off of Hadamard's bound."""
    for n in range(1, 5):
        M = rng.normal(size=(50, 2, n, n))
        M[0, 0, -1] = M[0, 0, 0]  # singular
        bound = np.prod(np.linalg.norm(M, axis=-2), axis=-1)
        got = _small_det(M)
        assert got.shape == (50, 2)
        assert np.all(np.abs(got - np.linalg.det(M)) <= 10 * np.finfo(float).eps * bound)


def test_block_solve_of_the_8pss_equals_lu_on_pinocchio_jacobians():
    """The 8-PSS IK Jacobian has the arrow structure (Pinocchio's zeros where it says), solved as by LU.

    Closure rows are zero outside the platform's and their own leg's columns, task rows
    outside the platform's; then the block solve equals ``numpy.linalg.solve`` (an LU of the
    whole matrix) to rounding, for the metrics' six right-hand sides and a Newton residual.
    The planar 3D4M (three task rows, the platform not a free body) has no such structure.
    """
    mech = preset("zhao2011_8pss")
    arrow = BatchKinematics.from_parts(mech.model, mech.closures, mech.task_compiled).arrow
    assert arrow is not None and [r.shape for r, _ in arrow.blocks] == [(8, 3)]
    rng = np.random.default_rng(5)
    A = np.stack([ik_jacobian(mech, q) for q in _random_configurations(mech, rng, 12, scale=0.2)])
    allowed = np.zeros(A.shape[1:], dtype=bool)
    allowed[arrow.task_rows[:, None], arrow.hub] = True
    for rows, cols in arrow.blocks:
        allowed[rows[:, :, None], cols[:, None, :]] = True
        allowed[rows.reshape(-1)[:, None], arrow.hub] = True
    assert np.abs(A[:, ~allowed]).max() == 0.0
    b = rng.normal(size=(A.shape[0], A.shape[1], 7))
    expected = np.linalg.solve(A, b)
    assert np.allclose(arrow.solve(A, b), expected, rtol=0.0, atol=1e-12 * np.abs(expected).max())
    planar = preset("harada2011_3d4m")
    assert BatchKinematics.from_parts(planar.model, planar.closures, planar.task_compiled).arrow is None


def test_unsupported_models_fall_back_to_the_generic_path():
    """The star-triangle (a closure the point rows do not take) has no batched evaluator."""
    mech = preset("enferadi2017_star_triangle")
    assert BatchKinematics.from_parts(mech.model, mech.closures, mech.task_compiled) is None


def _point_by_point(monkeypatch) -> None:
    """Maps solved point by point (:func:`~plm_pin.workspace._continuation.flood`) from here on."""
    monkeypatch.setattr(_continuation.BatchKinematics, "from_parts", classmethod(lambda cls, *a: None))
    monkeypatch.setattr(_continuation, "_batch_kernel", lambda ev: None)


@pytest.mark.parametrize(
    ("axes", "span", "shape"),
    [(("x", "y"), (0.05, 0.05), (9, 8)), (("z", "ry"), (0.8, 0.8), (11, 9))],  # the second crosses the edge
)
def test_row_batched_8pss_map_equals_the_point_by_point_map(monkeypatch, axes, span, shape):
    """An 8-PSS map (free-flyer, 6-D task) solved in row batches equals the point-by-point one.

    Inside the workspace the metrics agree to 1e-12; on the grid crossing its edge (poses near
    the boundary, worse conditioned) to 1e-10, the reachable mask and the modes exactly.
    """
    mech = preset("zhao2011_8pss")
    x0 = task_pose(mech, mech.q_ref)
    dofs = mech.task_compiled.dofs
    values = tuple(
        x0[dofs.index(a)] + np.linspace(-h, h, n) for a, h, n in zip(axes, span, shape, strict=True)
    )
    calls = []
    walk = _continuation._walk_rows
    monkeypatch.setattr(_continuation, "_walk_rows", lambda *a: calls.append(1) or walk(*a))
    batched = workspace_map(mech, axes, values, workers=1)
    assert calls  # the rows went through the batch
    _point_by_point(monkeypatch)
    serial = workspace_map(mech, axes, values, workers=1)
    inside = serial.reachable.all()
    assert inside == (axes == ("x", "y")) and serial.reachable.any()
    assert np.array_equal(batched.reachable, serial.reachable)
    assert np.array_equal(batched.mode, serial.mode)
    ok = serial.reachable
    assert np.abs(batched.q[ok] - serial.q[ok]).max() < 1e-11
    for name in POSE_METRICS:
        rtol = 1e-12 if inside else 1e-10
        assert np.allclose(batched.metric(name)[ok], serial.metric(name)[ok], rtol=rtol, atol=0.0), name


def test_row_batched_map_equals_the_point_by_point_map(monkeypatch):
    """A 3D4M map solved row by row in batches equals the generic point-by-point continuation."""
    mech = preset("harada2011_3d4m")
    values = (np.linspace(-0.16, 0.16, 23), np.linspace(0.0, 0.14, 19))  # reaches past the workspace edge
    pose = (0.0, 0.08, math.radians(-20.0))
    batched = workspace_map(mech, ("x", "y"), values, pose, workers=1)
    _point_by_point(monkeypatch)
    serial = workspace_map(mech, ("x", "y"), values, pose, workers=1)
    assert 0.3 < serial.reachable_fraction < 1.0
    assert np.array_equal(batched.reachable, serial.reachable)
    assert np.array_equal(batched.mode, serial.mode)
    ok = serial.reachable
    assert np.abs(batched.q[ok] - serial.q[ok]).max() < 1e-11
    assert np.allclose(batched.manipulability[ok], serial.manipulability[ok], rtol=1e-10, atol=0.0)


WALK_CASES = [
    ("harada2011_3d4m", ("x", "y"), (np.linspace(-0.16, 0.16, 23), np.linspace(0.0, 0.14, 19))),
    ("zhao2011_8pss", ("z", "ry"), (np.linspace(-0.8, 0.8, 11), np.linspace(-0.8, 0.8, 9))),
]
"""Grids reaching past the workspace edge (the 8-PSS's about its reference pose), so that rows fail."""


@pytest.mark.parametrize(("name", "axes", "values"), WALK_CASES)
def test_compiled_row_walk_equals_the_numpy_walk(monkeypatch, name, axes, values):
    """The compiled row walk leaves the grid the numpy walk leaves: reached set, modes, q and metrics.

    Both walks start from the same state (the seed's row solved) and are compared before the
    point-by-point fill, which would otherwise reach what either walk missed.
    """
    mech = preset(name)
    pose = task_pose(mech, mech.q_ref)
    if name == "zhao2011_8pss":
        values = tuple(pose[mech.task_compiled.dofs.index(a)] + v for a, v in zip(axes, values, strict=True))
    walks = []
    walk = _continuation._walk_rows

    def both(ev, kin, state, metrics, i0, target, tol):
        assert kin is None  # the kernels serve: no numpy engine built
        plain = copy.deepcopy(state)
        kin = BatchKinematics.from_parts(ev.model, ev.closures, ev.task)
        walk(dataclasses.replace(ev, kernel=None), kin, plain, metrics, i0, target, tol)
        walk(ev, kin, state, metrics, i0, target, tol)
        walks.append((plain, copy.deepcopy(state)))

    monkeypatch.setattr(_continuation, "_walk_rows", both)
    workspace_map(mech, axes, values, pose, workers=1)
    ((plain, compiled),) = walks
    n1 = len(values[1])
    assert n1 < compiled.reached.sum() < compiled.reached.size  # rows walked, some points failed
    np.testing.assert_array_equal(compiled.reached, plain.reached)
    np.testing.assert_array_equal(compiled.mode, plain.mode)
    ok = plain.reached
    np.testing.assert_allclose(compiled.q[ok], plain.q[ok], rtol=0.0, atol=1e-11)
    assert compiled.metrics.keys() == plain.metrics.keys() == set(POSE_METRICS)
    for metric, v in plain.metrics.items():
        np.testing.assert_allclose(compiled.metrics[metric], v, rtol=1e-10, equal_nan=True, err_msg=metric)


def test_gram_metrics_equal_the_svd_metrics_near_singularities():
    """Over a 3D3M map reaching its workspace edge (cond up to ~4e3), the Gram-eigenvalue metrics equal SVD's.

    The reference is :func:`batch_metrics` with its SVD basis of J_phi (no Newton system, no
    Gram matrix). The bound is that of ``GRAM_RTOL``: eps / GRAM_RTOL ~ 2e-12 relative, times a
    small constant; the poses past it (and the inverse-singular ones) take the SVD path itself.
    """
    mech = preset("harada2011_3d3m")
    values = (np.linspace(-0.16, 0.16, 30), np.linspace(0.0, 0.14, 25))
    result = workspace_map(mech, ("x", "y"), values, (0.0, 0.08, math.radians(-20.0)), workers=1)
    q = result.q[result.reachable]
    A = np.stack([ik_jacobian(mech, qq) for qq in q])
    m, act = mech.n_closure_rows, mech.actuated_v_indices
    fast = square_task_metrics(A, m, act, mech.mobility)
    svd = batch_metrics(A[:, :m], A[:, m:], act, mech.mobility)
    assert svd["condition_number"].max() > 1.0 / math.sqrt(GRAM_RTOL)  # some poses take the SVD path
    for name, values in svd.items():
        assert np.allclose(fast[name], values, rtol=1e-11, atol=0.0), name
    near = np.argmax(svd["condition_number"])
    for name, values in batch_metrics(
        A[near : near + 1, :m], A[near : near + 1, m:], act, mech.mobility
    ).items():
        assert fast[name][near] == values[0], name  # below GRAM_RTOL: the SVD values themselves
