"""Idle mobilities (plm_pin/core/idle.py) on textbook robots built in the tests.

A 6-SPS Stewart platform (ball joints at the base: three revolutes, the last along the strut)
lets each strut spin about its own axis: 12 DOF of which 6 idle. Held, every analysis runs on
the 6 effective DOF, and agrees with the 6-UPS closed forms of tests/textbook.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from plm_pin import InvalidInput
from plm_pin.cli import app
from plm_pin.core.closures import compile_closures
from plm_pin.core.closures import jacobian as closure_jacobian
from plm_pin.kinematics import (
    classify,
    closed_chain_jacobians,
    forward_kinematics,
    inverse_kinematics,
    same_assembly,
)
from plm_pin.workspace import manipulability
from tests import textbook as tb
from tests.conftest import ball_joint_body

POSES = [np.array(tb.STEWART_POSE) + d for d in (np.zeros(6), [0.03, 0.02, -0.05, 0.04, -0.03, 0.06])]


@pytest.fixture(scope="module")
def stewarts(tmp_path_factory):
    """The 6-UPS and the 6-SPS Stewart platforms."""
    folder = tmp_path_factory.mktemp("stewart")
    return tb.stewart(folder), tb.stewart(folder, spherical_base=True, name="stewart_sps")


def test_strut_spins_are_idle_and_held(stewarts):
    """6-SPS: the cut closures leave 12 DOF; 6 are strut spins, each held by its strut-axis revolute."""
    ups, sps = stewarts
    assert (ups.mobility, ups.idle_mobility) == (6, 0)
    assert (sps.mobility, sps.idle_mobility) == (6, 6)
    assert sorted(g.joint for g in sps.idle_gauges) == [f"u{k}c" for k in range(6)]
    cut = compile_closures(sps.model, sps.sidecar.closures)
    J = closure_jacobian(sps.model, sps.model.createData(), cut, sps.q_ref)
    s = np.linalg.svd(J, compute_uv=False)
    assert sps.nv - int(np.sum(s > 1e-9 * s[0])) == 12
    assert sps.summary()["idle_joints"] == [g.joint for g in sps.idle_gauges]


def test_ik_and_actuator_jacobian_match_the_closed_form_with_idle_spins(stewarts):
    """IK leg lengths and J_ce equal |p + R P_k - B_k| and [e_k, R P_k x e_k], with and without idle spins."""
    for mech in stewarts:
        for x in POSES:
            sol = inverse_kinematics(mech, x)
            L, J = tb.stewart_legs(tuple(x))
            np.testing.assert_allclose(sol.actuators, L, atol=1e-12)
            np.testing.assert_allclose(closed_chain_jacobians(mech, sol.q).J_ce, J, atol=1e-10)


def test_fk_classify_and_manipulability_run_on_the_effective_dof(stewarts):
    """6-SPS: FK of the IK's leg lengths finds the IK assembly; classify and manipulability answer."""
    _, sps = stewarts
    sol = inverse_kinematics(sps, POSES[1])
    found = forward_kinematics(sps, sol.actuators, sol.q, all_modes=False)
    assert same_assembly(sps, found[0].q, sol.q)
    assert not classify(sps, sol.q).singular
    _, J = tb.stewart_legs(tuple(POSES[1]))
    w = manipulability(sps, sol.q)
    assert w.w == pytest.approx(abs(np.linalg.det(J)), rel=1e-10)  # square J_ce: sqrt(det(J^T J)) = |det J|
    assert w.condition_number == pytest.approx(np.linalg.cond(J), rel=1e-8)


def test_pendulum_on_a_ball_joint_is_not_idle(tmp_path):
    """A body on a ball joint with its centre of mass off the centre is a real mobility, not an idle one."""
    mech = ball_joint_body(tmp_path, {"type": "point"})
    assert (mech.mobility, mech.idle_mobility) == (3, 0)


def test_task_smaller_than_the_mobility_is_refused(tmp_path):
    """3-RRR with task [x, y]: IK and classify refuse, `plm-pin check` fails with the reason."""
    mech = tb.three_rrr(tmp_path, ("x", "y"), name="rrr_xy")
    message = (
        "rrr_xy: the task has 2 coordinates but the mechanism has 3 DOF: a pose does not determine the "
        "configuration; give a task with as many coordinates as DOF"
    )
    with pytest.raises(InvalidInput, match=f"^{message}$"):
        inverse_kinematics(mech, [0.0, 0.0])
    with pytest.raises(
        InvalidInput, match=r"^rrr_xy: the task has 2 coordinates but the mechanism has 3 DOF"
    ):
        classify(mech, mech.q_ref)
    result = CliRunner().invoke(app, ["check", str(tmp_path / "rrr_xy.urdf")])
    assert result.exit_code == 1
    assert result.stderr == (
        "error: the task ['x', 'y'] has 2 coordinates but the mechanism has 3 DOF: a pose does not "
        "determine the configuration, so IK, FK, the Jacobians and manipulability are undefined; either a "
        "closure is missing, or the task lacks coordinates (add the missing coordinates to "
        "end_effector.task)\n"
    )


def test_check_explains_idle_mobilities(stewarts, tmp_path):
    """`plm-pin check` on the 6-SPS says mobility 6 with 6 idle, names the held joints, and passes."""
    _, sps = stewarts
    tb.stewart(tmp_path, spherical_base=True, name="sps")
    result = CliRunner().invoke(app, ["check", str(tmp_path / "sps.urdf")])
    assert result.exit_code == 0, result.output
    held = [g.joint for g in sps.idle_gauges]
    lines = result.stdout.splitlines()
    assert lines[0] == (
        f"note: mobility 6, 6 idle: 6 motion(s) move nothing else (a strut spinning about its own axis, "
        f"a half-revolute pair turning together); joint(s) {held} are held at their reference values and "
        "every analysis runs on the 6 effective DOF"
    )
    assert lines[-1].startswith("ok: sps: 6 closures, 6 actuators, mobility 6, 6 idle,")
