"""Newton and Levenberg-Marquardt assembly (plm_pin/core/assembly.py): the chord iterations.

Oracles: a plain Gauss-Newton written here on Pinocchio's frame placements with a
finite-difference Jacobian (no plm_pin residual or Jacobian code), and for the 3D4M the
benchmark floor (:class:`benchmarks.harness.Floor`, its own residual and Jacobian).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from benchmarks.harness import Floor
from plm_pin.core import assembly
from plm_pin.core.task import TaskTarget
from plm_pin.kinematics import task_pose
from tests.conftest import fd_jacobian, preset, spatial_6r

NON_PLANAR_AND_PLANAR = ["harada2011_3d4m", "zhao2011_8pss"]


def _plain_residual(mech, data, x):
    """Point-closure gaps p_B - p_A, then the task error (p - p*, log3(R R*^T) or the wrapped angle)."""

    def residual(q):
        pin.framesForwardKinematics(mech.model, data, q)
        oMf = data.oMf
        gaps = [oMf[c.frame_ids[1]].translation - oMf[c.frame_ids[0]].translation for c in mech.closures]
        M = oMf[mech.task_compiled.frame_id]
        if mech.task_compiled.dofs == ("x", "y", "rz"):
            angle = np.arctan2(M.rotation[1, 0], M.rotation[0, 0]) - x[2]
            task = [M.translation[0] - x[0], M.translation[1] - x[1], (angle + np.pi) % (2 * np.pi) - np.pi]
        else:
            task = [*(M.translation - x[:3]), *pin.log3(M.rotation @ pin.rpy.rpyToMatrix(x[3:]).T)]
        return np.concatenate([*gaps, task])

    return residual


def _plain_gauss_newton(mech, x, q0):
    """Gauss-Newton with a finite-difference Jacobian, to round-off (an oracle independent of plm_pin)."""
    residual = _plain_residual(mech, mech.model.createData(), x)
    q = q0
    for _ in range(30):
        r = residual(q)
        if np.abs(r).max() < 1e-15:
            break
        J = fd_jacobian(residual, mech.model, q)
        q = pin.integrate(mech.model, q, -np.linalg.lstsq(J, r, rcond=None)[0])
    return q


class _Recording:
    """Task rows recording, per Newton pass, the largest stacked residual and whether a Jacobian was made."""

    def __init__(self, target, stacked):
        self.target, self.stacked, self.passes = target, stacked, []
        self.size = target.size

    def residual(self, data, out):
        self.target.residual(data, out)
        self.passes.append([float(np.abs(self.stacked).max()), False])
        return out

    def jacobian(self, model, data, out):
        self.passes[-1][1] = True
        return self.target.jacobian(model, data, out)


def _newton(mech, x, q0, **options):
    """assembly.newton on closures and task from q0; the configuration and the record of its passes."""
    ws = mech.workspace()
    extra = _Recording(TaskTarget(mech.task_compiled, x), ws.residual)
    found = assembly.newton(
        mech.model,
        ws.data,
        mech.closures,
        q0,
        None,
        ws.residual,
        ws.jacobian,
        tol=1e-12,
        extra=extra,
        **options,
    )
    assert found is not None
    return found[0], extra.passes, ws


def _solve(mech, x, q0):
    return _newton(mech, x, q0)[0]


@pytest.mark.parametrize("name", NON_PLANAR_AND_PLANAR)
@pytest.mark.parametrize("offset", [1e-3, 2e-2])
def test_chord_newton_lands_on_the_plain_gauss_newton_solution(name, offset):
    """From 1e-3 and 2e-2 off q_ref, chord Newton equals an independent Gauss-Newton to 1e-12."""
    mech = preset(name)
    q0 = mech.q_ref
    x = task_pose(mech, q0) + offset
    chord = _solve(mech, x, q0)
    oracle = _plain_gauss_newton(mech, x, q0)
    assert np.abs(pin.difference(mech.model, chord, oracle)).max() < 1e-12
    assert np.abs(_plain_residual(mech, mech.model.createData(), x)(chord)).max() <= 1e-12


@pytest.mark.parametrize("name", NON_PLANAR_AND_PLANAR)
def test_chord_and_full_newton_give_the_same_configuration(name, monkeypatch):
    """With the factorisation refreshed at every step (CHORD_RATIO = 0) Newton ends at the same q to 1e-12."""
    mech = preset(name)
    x = task_pose(mech, mech.q_ref) + 1e-3
    chord = _solve(mech, x, mech.q_ref)
    monkeypatch.setattr(assembly, "CHORD_RATIO", 0.0)
    full = _solve(mech, x, mech.q_ref)
    assert np.abs(pin.difference(mech.model, chord, full)).max() < 1e-12


def test_chord_newton_equals_the_floor_on_the_3d4m():
    """On the 3D4M the chord solution equals the benchmark floor's plain Gauss-Newton to 1e-12."""
    mech = preset("harada2011_3d4m")
    x = task_pose(mech, mech.q_ref) + 1e-3
    floor = Floor(mech).ik(mech.q_ref, x)
    assert np.abs(pin.difference(mech.model, _solve(mech, x, mech.q_ref), floor)).max() < 1e-12


@pytest.mark.parametrize("name", NON_PLANAR_AND_PLANAR)
def test_factorisation_is_kept_only_while_the_residual_contracts_fast(name):
    """A pass reuses the factorisation only after a step that divided the residual by 1 / CHORD_RATIO.

    From 2e-2 off q_ref the first steps contract poorly, so the Jacobian is refreshed more than
    once; near the solution it is reused (fewer Jacobians than passes); the polishing step
    (residual already within tolerance) always reuses it.
    """
    mech = preset(name)
    x = task_pose(mech, mech.q_ref) + 2e-2
    q, passes, _ = _newton(mech, x, mech.q_ref)
    errors = [p[0] for p in passes]
    refreshed = [p[1] for p in passes]
    assert refreshed[0]
    assert 1 < sum(refreshed) < len(refreshed) - 1
    for k in range(1, len(errors) - 1):  # the last pass only checks the residual
        if not refreshed[k] and errors[k] > 1e-12:  # a chord step, not the polishing one
            assert errors[k] < assembly.CHORD_RATIO * errors[k - 1]
    assert np.abs(pin.difference(mech.model, q, _plain_gauss_newton(mech, x, mech.q_ref))).max() < 1e-12


def test_without_polish_every_step_is_a_full_newton_step():
    """polish=False (the maps' continuation) refreshes the Jacobian at every step that is taken."""
    mech = preset("harada2011_3d4m")
    x = task_pose(mech, mech.q_ref) + 1e-3
    _, passes, _ = _newton(mech, x, mech.q_ref, polish=False)
    assert len(passes) > 2
    assert all(p[1] for p in passes[:-1]) and not passes[-1][1]


def test_newton_leaves_the_joint_jacobians_at_the_solution():
    """After a chord solve the data holds joint Jacobians and placements at the returned q (the contract)."""
    mech = preset("zhao2011_8pss")
    x = task_pose(mech, mech.q_ref) + 1e-3
    q, passes, ws = _newton(mech, x, mech.q_ref)
    assert not passes[-2][1]  # the last step was a chord step: the Jacobians were not at q
    fresh = mech.model.createData()
    pin.computeJointJacobians(mech.model, fresh, q)
    pin.updateFramePlacements(mech.model, fresh)
    np.testing.assert_array_equal(ws.data.J, fresh.J)
    for f in range(mech.model.nframes):
        np.testing.assert_array_equal(ws.data.oMf[f].homogeneous, fresh.oMf[f].homogeneous)


@pytest.mark.parametrize(
    ("kind", "fixed"),
    [({"type": "revolute", "axis": [0.0, 0.0, 1.0]}, 1), ({"type": "weld"}, 0), ({"type": "point"}, 3)],
)
def test_chord_newton_closes_revolute_weld_and_point_loops_as_lm_does(tmp_path, kind, fixed):
    """On a spatial 6R loop, chord Newton from a moved assembly lands where Levenberg-Marquardt (SVD) does."""
    mech = spatial_6r(tmp_path, kind)
    step = np.zeros(mech.nv)
    step[:fixed] = 0.05  # the fixed joints move the loop off closure; the others close it again
    start = pin.integrate(mech.model, mech.q_ref, step + 0.01)
    free = np.arange(fixed, mech.nv)
    ws = mech.workspace()
    m = mech.n_closure_rows
    found = assembly.newton(
        mech.model, ws.data, mech.closures, start, free, ws.residual[:m], ws.jacobian[:m], tol=1e-12
    )
    assert found is not None
    lm = assembly.assemble(mech.model, mech.model.createData(), mech.closures, start, free, tol=1e-13)
    assert np.abs(pin.difference(mech.model, found[0], lm.q)).max() < 1e-10
    assert np.abs(mech.closure_residual(found[0])).max() <= 1e-12
