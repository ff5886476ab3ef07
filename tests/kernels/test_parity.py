"""The compiled kernels against Pinocchio (the oracle): placements, rows, Jacobians, Newton answers.

On every preset and every loadable corpus robot at random configurations, and on a model
holding every supported joint type with every closure type and both kinds of frame task.
"""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.core import closures as C
from plm_pin.core.assembly import assemble, newton
from plm_pin.core.task import TaskTarget, compile_task
from plm_pin.description.sidecar import ClosureSpec
from plm_pin.exceptions import ClosureNotSatisfied
from plm_pin.kernels import Kernel, kernel_of, kernels_enabled
from plm_pin.kernels.arrays import JOINT_KINDS, jacobian_pattern, unsupported_joints
from plm_pin.kernels.linear import lu_factor, lu_solve
from plm_pin.kinematics import forward_kinematics, inverse_kinematics
from plm_pin.models import preset_names
from plm_pin.warnings import KernelFallbackWarning
from tests.conftest import INTEROP, load_corpus, preset

TOL = 1e-12

CORPUS = sorted(p.name for p in INTEROP.iterdir() if p.is_dir()) if INTEROP.is_dir() else []


def _mechanism(name: str) -> plm_pin.Mechanism:
    if name in CORPUS:
        try:
            return load_corpus(INTEROP / name)
        except plm_pin.exceptions.PlmError as exc:
            pytest.skip(f"{name} does not load: {exc}")
    return preset(name)


def _pinocchio_rows(model, closures, q, target):
    data = model.createData()
    r = C.residual(model, data, closures, q)
    J = C.jacobian(model, data, closures, q)
    if target is not None:
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        r = np.concatenate([r, target.residual(data)])
        J = np.vstack([J, target.jacobian(model, data)])
    return r, J


def _check_rows(kernel: Kernel, model, closures, q, target) -> None:
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    oR, op, fR, fp = kernel.placements(q)
    for j in range(model.njoints):
        np.testing.assert_allclose(oR[j], data.oMi[j].rotation, atol=TOL)
        np.testing.assert_allclose(op[j], data.oMi[j].translation, atol=TOL)
    for i, f in enumerate(kernel.frame_ids):
        np.testing.assert_allclose(fR[i], data.oMf[f].rotation, atol=TOL)
        np.testing.assert_allclose(fp[i], data.oMf[f].translation, atol=TOL)
    r, J = kernel.rows(q, target)
    r_pin, J_pin = _pinocchio_rows(model, closures, q, target)
    np.testing.assert_allclose(r, r_pin, atol=TOL)
    np.testing.assert_allclose(J, J_pin, atol=TOL)
    _check_square_solve(kernel, J_pin, r_pin)


def _check_square_solve(kernel: Kernel, J: np.ndarray, r: np.ndarray) -> None:
    """The kernel's pattern holds every nonzero of Pinocchio's Jacobian, and its LU solves as LAPACK does."""
    pattern = jacobian_pattern(kernel.arrays)
    assert pattern.shape == J.shape
    assert not J[~pattern].any()
    live = J.any(axis=1)
    if live.sum() != J.shape[1] or np.linalg.cond(J[live]) > 1e8:
        return
    F, X = np.empty(J.shape), np.empty((J.shape[1], 1))
    pivots, step = np.empty(J.shape[1], np.int64), np.empty(J.shape[0], np.int64)
    assert lu_factor(J, kernel.elimination, F, pivots, step)
    lu_solve(F, kernel.elimination, pivots, step, r[:, None].copy(), X)
    np.testing.assert_allclose(
        X[:, 0], np.linalg.solve(J[live], r[live]), rtol=1e-9, atol=1e-9 * np.abs(X).max()
    )


@pytest.mark.parametrize("name", [*preset_names(), *CORPUS])
def test_rows_and_placements_match_pinocchio(name, rng):
    mech = _mechanism(name)
    kernel = kernel_of(mech)
    assert kernel is not None
    task = mech.task_compiled
    for _ in range(5):
        q = pin.integrate(mech.model, mech.q_ref, rng.normal(scale=0.3, size=mech.nv))
        target = None
        if task is not None:
            data = mech.model.createData()
            pin.framesForwardKinematics(mech.model, data, q)
            target = TaskTarget(task, task.pose_from_data(data) + rng.normal(scale=0.05, size=task.size))
        _check_rows(kernel, mech.model, mech.closures, q, target)


@pytest.mark.parametrize("name", [*preset_names(), *CORPUS])
def test_newton_matches_pinocchio_newton(name, rng):
    """IK (task fixed, all columns free) and FK (actuators fixed), polished or not: same answer or stall."""
    mech = _mechanism(name)
    kernel = kernel_of(mech)
    assert kernel is not None
    model, task = mech.model, mech.task_compiled
    data = model.createData()
    n = mech.n_closure_rows + (task.size if task is not None else 0)
    for _ in range(3):
        q = pin.integrate(model, mech.q_ref, rng.normal(scale=0.05, size=mech.nv))
        cases = [(mech.passive_v_indices, None)]
        if task is not None and task.size >= mech.mobility:
            pin.framesForwardKinematics(model, data, q)
            x = task.pose_from_data(data)
            cases.append((None, TaskTarget(task, x)))
        for (free, target), polish in itertools.product(cases, (True, False)):
            got = kernel.newton(mech.q_ref, free, mech.closure_tol, target, polish)
            r, A = np.empty(n), np.empty((n, mech.nv))
            want = newton(
                model,
                data,
                mech.closures,
                mech.q_ref,
                free,
                r,
                A,
                tol=mech.closure_tol,
                extra=target,
                polish=polish,
            )
            assert (got is None) == (want is None)
            if got is not None and want is not None:
                np.testing.assert_allclose(got[0], want[0], atol=1e-10)
                assert np.max(np.abs(got[1]), initial=0.0) <= mech.closure_tol
                if task is not None:
                    pin.framesForwardKinematics(model, data, got[0])
                    np.testing.assert_allclose(got[2], task.pose_from_data(data), atol=TOL)


@pytest.mark.parametrize("name", [*preset_names(), *CORPUS])
def test_levenberg_marquardt_matches_pinocchio_assemble(name, rng):
    """The compiled assembly takes Pinocchio's Levenberg-Marquardt steps: same answer, or both fail.

    From far starts (0.5 rad off the reference) to reachable targets (IK: a configuration's own
    pose; FK: the actuators fixed), and to a target pushed out of reach.
    """
    mech = _mechanism(name)
    kernel = kernel_of(mech)
    assert kernel is not None
    model, task = mech.model, mech.task_compiled
    data = model.createData()
    everything = np.arange(mech.nv)
    for _ in range(2):
        q = pin.integrate(model, mech.q_ref, rng.normal(scale=0.3, size=mech.nv))
        start = pin.integrate(model, mech.q_ref, rng.normal(scale=0.5, size=mech.nv))
        cases = [(mech.passive_v_indices, None)]
        if task is not None and task.size >= mech.mobility:
            pin.framesForwardKinematics(model, data, q)
            x = task.pose_from_data(data)
            cases += [(None, TaskTarget(task, x)), (None, TaskTarget(task, x + 10.0))]
        for free, target in cases:
            q_got, r_got, closed = kernel.assemble(start, free, mech.closure_tol, target, max_iterations=60)
            try:
                want = assemble(
                    model, data, mech.closures, start, everything if free is None else free,
                    tol=mech.closure_tol, max_iterations=60, extra=target,
                ).q  # fmt: skip
            except ClosureNotSatisfied:
                want = None
            assert closed == (want is not None)
            if closed and want is not None:
                np.testing.assert_allclose(q_got, want, atol=1e-9)
                assert np.max(np.abs(r_got), initial=0.0) <= mech.closure_tol


def _every_joint_model() -> pin.Model:
    """A tree with every supported joint type in a chain (and a branch), with a frame on each body."""
    model = pin.Model()
    rng = np.random.default_rng(3)

    def place() -> pin.SE3:
        return pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(scale=0.3, size=3))

    axis = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    joints = [
        pin.JointModelFreeFlyer(),
        pin.JointModelSpherical(),
        pin.JointModelPlanar(),
        pin.JointModelUniversal(np.array([0.0, 0.0, 1.0]), np.array([0.6, 0.8, 0.0])),
        pin.JointModelRUBY(),
        pin.JointModelRevoluteUnaligned(axis),
        pin.JointModelPrismaticUnaligned(axis[::-1].copy()),
        pin.JointModelRX(),
        pin.JointModelPY(),
        pin.JointModelRZ(),
        pin.JointModelPZ(),
    ]
    parent = 0
    for i, joint in enumerate(joints):
        jid = model.addJoint(parent if i != 9 else 3, joint, place(), f"j{i}")
        model.appendBodyToJoint(jid, pin.Inertia.Random(), pin.SE3.Identity())
        model.addFrame(pin.Frame(f"f{i}", jid, place(), pin.FrameType.OP_FRAME))
        parent = jid
    assert not unsupported_joints(model) and {j.shortname() for j in model.joints[1:]} <= set(JOINT_KINDS)
    return model


EVERY_CLOSURE = [
    ClosureSpec("p", ("f10", "f4"), "point"),
    ClosureSpec("r", ("f2", "f9"), "revolute", (0.0, 0.6, 0.8)),
    ClosureSpec("w", ("f5", "f8"), "weld"),
    ClosureSpec("t", ("f1", "f7"), "twist", (0.0, 0.0, 1.0)),
]
"""One closure of every type between frames of :func:`_every_joint_model`."""


@pytest.mark.parametrize("dofs", [("x", "y", "z", "rx", "ry", "rz"), ("x", "y", "rz"), ("z", "ry", "rx"), ()])
def test_every_joint_and_closure_type(dofs, rng):
    model = _every_joint_model()
    closures = C.compile_closures(model, EVERY_CLOSURE)
    task = compile_task(model, "f6", dofs) if dofs else None
    kernel = Kernel.build(model, closures, task)
    data = model.createData()
    for _ in range(5):
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
        target = None
        if task is not None:
            pin.framesForwardKinematics(model, data, q)
            target = TaskTarget(task, task.pose_from_data(data) + rng.normal(scale=0.1, size=task.size))
        _check_rows(kernel, model, closures, q, target)
        v = rng.normal(scale=0.7, size=model.nv)
        moved = kernel.integrate(q, v)
        pin.framesForwardKinematics(model, data, moved)
        placed = [M.copy() for M in data.oMi]
        pin.framesForwardKinematics(model, data, pin.integrate(model, q, v))
        for a, b in zip(placed, data.oMi, strict=True):  # the same placements (quaternion signs aside)
            np.testing.assert_allclose(a.homogeneous, b.homogeneous, atol=TOL)


def test_batched_newton_puts_quaternions_and_pairs_back_to_unit_norm(rng):
    """A start whose quaternions and (cos, sin) pairs are off unit norm (an extrapolated one) is normalised.

    The start is a configuration with every quaternion and pair scaled by 1.3, the target its own
    task pose: once normalised it is a solution, so it passes with no Newton iteration and comes
    back as the configuration. Read as it is, each scaled pair would place its joint by a scaled
    rotation, far from the target.
    """
    model = _every_joint_model()
    task = compile_task(model, "f8", ("x", "y", "z", "rx", "ry", "rz"))  # every joint type up to PY
    kernel = Kernel.build(model, (), task)
    data = model.createData()
    unit = {"JointModelFreeFlyer": (3, 7), "JointModelSpherical": (0, 4), "JointModelPlanar": (2, 4)}
    unit["JointModelRUBY"] = (0, 2)
    for _ in range(5):
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
        pin.framesForwardKinematics(model, data, q)
        x = task.pose_from_data(data)
        start = q.copy()
        for joint in model.joints[1:]:
            a, b = unit.get(joint.shortname(), (0, 0))
            start[joint.idx_q + a : joint.idx_q + b] *= 1.3
        R_star = data.oMf[task.frame_id].rotation[None]
        got, ok, _, _ = kernel.newton_modes((), start[None], x[None], R_star, 1e-12, max_iterations=0)
        assert ok[0]
        np.testing.assert_allclose(got[0], q, rtol=0.0, atol=1e-15)


def test_unsupported_joint_falls_back_with_one_warning(monkeypatch):
    """Without a joint type the kernels take the Pinocchio path, say so once, and answer the same."""
    mech = preset("fivebar")
    x = forward_kinematics(mech, mech.actuator_positions(mech.q_ref), all_modes=False)[0].x + 0.01
    with_kernel = inverse_kinematics(mech, x)
    fresh = plm_pin.load("fivebar")
    monkeypatch.delitem(JOINT_KINDS, "JointModelRZ")
    with pytest.warns(KernelFallbackWarning, match="JointModelRZ"):
        assert kernel_of(fresh) is None
    with warnings.catch_warnings():
        warnings.simplefilter("error", KernelFallbackWarning)
        assert kernel_of(fresh) is None  # said once
        without = inverse_kinematics(fresh, x)
    np.testing.assert_allclose(without.q, with_kernel.q, atol=1e-10)


def test_switch_turns_the_kernels_off(monkeypatch):
    mech = preset("harada2011_3d4m")
    assert kernel_of(mech) is not None
    monkeypatch.setenv("PLM_PIN_KERNELS", "0")
    assert kernel_of(mech) is None


@pytest.mark.parametrize(
    ("value", "on"), [(None, True), ("0", False), (" 0\n", False), ("1", True), ("", True)]
)
def test_switch_is_read_at_each_call(monkeypatch, value, on):
    mech = preset("harada2011_3d4m")
    if value is None:
        monkeypatch.delenv("PLM_PIN_KERNELS", raising=False)
    else:
        monkeypatch.setenv("PLM_PIN_KERNELS", value)
    assert (kernel_of(mech) is not None) is on
    assert kernels_enabled() is on
    monkeypatch.setenv("PLM_PIN_KERNELS", "1" if not on else "0")  # flipped: the next call sees it
    assert (kernel_of(mech) is not None) is not on


def test_working_modes_with_sign_rows_past_the_ik_jacobian_stay_off_the_kernels():
    """A corpus five-bar whose working mode reads platform rows past ``[J_phi; J_x]``.

    The compiled modes read only the IK Jacobian: the kernel refuses these legs (a ValueError,
    not a read past its rows), and the maps' batches leave them to the Pinocchio path.
    """
    from plm_pin.workspace._continuation import IKEvaluator, _batch_kernel

    mech = _mechanism("5bar_linkage_iso3d")
    ev = IKEvaluator.from_mechanism(mech)
    assert ev.kernel is not None and not ev.modes_in_ik and _batch_kernel(ev) is None
    x = np.zeros((1, ev.task.size))
    with pytest.raises(ValueError, match="sign rows past the IK Jacobian"):
        ev.kernel.newton_modes(ev.legs, mech.q_ref[None], x, np.eye(3)[None], 1e-10)
