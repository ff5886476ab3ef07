"""onshape-to-robot closing frames (plm_pin/description/onshape.py): a four-bar against its closed form.

The URDF is written as onshape-to-robot writes one: the CAD pose is the zero configuration,
each frame a dummy link (mass 1e-9, no inertia) hung on its part by a fixed joint
``<frame>_frame``, the closing frames at the mate connector of a mate ``closing_loop``. The
oracle is the planar four-bar's closed form: the coupler tip B is where the circle of radius
``b`` about the crank tip A meets the circle of radius ``c`` about the rocker pivot O4.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import plm_pin
from plm_pin.exceptions import DescriptionError

A_CRANK, B_COUPLER, C_ROCKER, D_GROUND = 0.1, 0.3, 0.25, 0.35  # [m]
THETA2_REF = 1.2  # crank angle of the CAD pose [rad]


def _tip(theta2: float) -> np.ndarray:
    """Closed form: the coupler tip B at crank angle ``theta2``, elbow-up branch (B left of A -> O4)."""
    a = A_CRANK * np.array([math.cos(theta2), math.sin(theta2)])
    o4 = np.array([D_GROUND, 0.0])
    e = float(np.linalg.norm(o4 - a))
    u = (o4 - a) / e
    along = (B_COUPLER**2 - C_ROCKER**2 + e**2) / (2 * e)
    across = math.sqrt(B_COUPLER**2 - along**2)
    return a + along * u + across * np.array([-u[1], u[0]])


def _frame(name: str, parent: str, xyz: tuple[float, float, float], yaw: float) -> str:
    """A frame as onshape-to-robot writes it: a dummy link and a fixed joint ``<name>_frame``."""
    return (
        f'<link name="{name}"><origin xyz="0 0 0" rpy="0 0 0"/><inertial><origin xyz="0 0 0" rpy="0 0 0"/>'
        '<mass value="1e-9"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>'
        f'<joint name="{name}_frame" type="fixed"><origin xyz="{xyz[0]!r} {xyz[1]!r} {xyz[2]!r}" '
        f'rpy="0 0 {yaw!r}"/><parent link="{parent}"/><child link="{name}"/><axis xyz="0 0 0"/></joint>'
    )


def _link(name: str, mass: float, com_x: float) -> str:
    return (
        f'<link name="{name}"><inertial><origin xyz="{com_x} 0 0" rpy="0 0 0"/><mass value="{mass}"/>'
        '<inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>'
    )


def _revolute(name: str, parent: str, child: str, x: float, yaw: float) -> str:
    return (
        f'<joint name="{name}" type="revolute"><origin xyz="{x!r} 0 0" rpy="0 0 {yaw!r}"/>'
        f'<parent link="{parent}"/><child link="{child}"/><axis xyz="0 0 1"/>'
        '<limit effort="10" velocity="10" lower="-3.14" upper="3.14"/>'
        '<joint_properties friction="0.0"/></joint>'
    )


def fourbar_urdf(hinge: bool = False, partner: bool = True) -> str:
    """The four-bar at its CAD pose; ``hinge`` adds the ``_z`` frames of a revolute mate."""
    b = _tip(THETA2_REF)
    a = A_CRANK * np.array([math.cos(THETA2_REF), math.sin(THETA2_REF)])
    theta3 = math.atan2(*(b - a)[::-1])
    theta4 = math.atan2(*(b - np.array([D_GROUND, 0.0]))[::-1])
    frames = [_frame("closing_loop_1", "coupler", (B_COUPLER, 0.0, 0.0), 0.4)]
    if partner:
        frames.append(_frame("closing_loop_2", "rocker", (C_ROCKER, 0.0, 0.0), -0.7))
    if hinge:  # 0.1 m along the mate's z axis, the world z here
        frames.append(_frame("closing_loop_1_z", "coupler", (B_COUPLER, 0.0, 0.1), 0.4))
        frames.append(_frame("closing_loop_2_z", "rocker", (C_ROCKER, 0.0, 0.1), -0.7))
    return (
        '<?xml version="1.0" ?><!-- Generated using onshape-to-robot --><robot name="fourbar">'
        + _link("base", 1.0, 0.0)
        + _link("crank", 0.2, A_CRANK / 2)
        + _link("coupler", 0.3, B_COUPLER / 2)
        + _link("rocker", 0.25, C_ROCKER / 2)
        + "".join(frames)
        + _revolute("crank_joint", "base", "crank", 0.0, THETA2_REF)
        + _revolute("coupler_joint", "crank", "coupler", A_CRANK, theta3 - THETA2_REF)
        + _revolute("rocker_joint", "base", "rocker", D_GROUND, theta4)
        + "</robot>"
    )


def _write(folder: Path, text: str, sidecar: str | None = None) -> Path:
    path = folder / "fourbar.urdf"
    path.write_text(text)
    if sidecar is not None:
        (folder / "fourbar.plm.yaml").write_text(sidecar)
    return path


@pytest.mark.filterwarnings("ignore::plm_pin.warnings.MissingLimitsWarning")
@pytest.mark.parametrize("hinge", [False, True])
def test_closing_frames_close_the_loop_of_the_closed_form(tmp_path: Path, hinge: bool) -> None:
    """No sidecar: the closing frames give the loop; every assembled pose has the closed form's B."""
    mech = plm_pin.load(_write(tmp_path, fourbar_urdf(hinge)))
    assert [(c.name, c.spec.frames, c.spec.type) for c in mech.closures] == [
        ("closing_loop", ("closing_loop_1", "closing_loop_2"), "point"),
        *([("closing_loop_z", ("closing_loop_1_z", "closing_loop_2_z"), "point")] if hinge else []),
    ]
    assert mech.source == "onshape-to-robot closing frames in fourbar.urdf"
    assert (mech.nv, mech.mobility) == (3, 1)
    np.testing.assert_allclose(mech.q_ref, 0.0, atol=1e-12)  # the CAD pose is assembled
    data = mech.model.createData()
    frame = mech.model.getFrameId("closing_loop_2")
    for theta2 in (0.6, 1.0, 1.5, 2.0):
        q = mech.assemble(mech.q_ref, fixed={"crank_joint": theta2 - THETA2_REF}).q
        pin.framesForwardKinematics(mech.model, data, q)
        np.testing.assert_allclose(data.oMf[frame].translation[:2], _tip(theta2), atol=1e-10)
        assert data.oMf[frame].translation[2] == pytest.approx(0.0, abs=1e-12)


def test_sidecar_without_closures_takes_the_closing_frames(tmp_path: Path) -> None:
    """A sidecar giving actuation and task only: the loops are the closing frames'; explicit closures win."""
    side = "format: plm-pin/1\nactuation: [{joint: crank_joint}]\nend_effector: {frame: rocker, task: [rz]}\n"
    mech = plm_pin.load(_write(tmp_path, fourbar_urdf(), side))
    assert [c.name for c in mech.closures] == ["closing_loop"]
    assert (mech.mobility, mech.redundancy) == (1, 0)
    weld = side + "closures: [{name: mine, frames: [closing_loop_1, closing_loop_2], type: weld}]\n"
    (tmp_path / "fourbar.plm.yaml").write_text(weld)
    welded = plm_pin.load(tmp_path / "fourbar.urdf")  # the sidecar says the mate is fastened
    assert [(c.name, c.spec.type) for c in welded.closures] == [("mine", "weld")]
    assert welded.mobility == 0


def test_a_closing_frame_without_partner_is_refused(tmp_path: Path) -> None:
    """closing_loop_1 without closing_loop_2: one error naming the missing frame and the file."""
    path = _write(tmp_path, fourbar_urdf(partner=False))
    with pytest.raises(DescriptionError) as info:
        plm_pin.load(path)
    assert str(info.value) == (
        f"{path}: closing frame 'closing_loop_1' has no partner 'closing_loop_2': onshape-to-robot closes "
        "a loop between the two frames of a closing_<name> mate"
    )


def test_mjcf_connects_between_closing_sites_take_the_mate_name(tmp_path: Path) -> None:
    """onshape-to-robot's MJCF: unnamed connects between closing sites are named after the mate."""
    pytest.importorskip("mujoco")
    a = plm_pin.load(_write(tmp_path, fourbar_urdf(hinge=True)))
    out = tmp_path / "mj" / "fourbar.xml"
    plm_pin.export_mjcf(a, out)
    text = out.read_text()
    for name in ("closing_loop", "closing_loop_z"):
        text = text.replace(f'<connect name="{name}" ', "<connect ")
    out.write_text(text)
    b = plm_pin.load(out)
    assert [(c.name, c.spec.frames) for c in b.closures] == [(c.name, c.spec.frames) for c in a.closures]
    assert (b.mobility, b.closure_rank(b.q_ref)) == (a.mobility, a.closure_rank(a.q_ref)) == (1, 2)


def test_cli_info_reads_an_onshape_urdf(tmp_path: Path) -> None:
    """``plm-pin info robot.urdf`` with closing frames and no sidecar."""
    from typer.testing import CliRunner

    from plm_pin.cli import app

    result = CliRunner().invoke(app, ["info", str(_write(tmp_path, fourbar_urdf()))])
    assert result.exit_code == 0, result.output
    assert "closing_loop_1 = closing_loop_2" in result.output and "mobility" in result.output


def test_mjcf_weld_between_closing_sites_is_a_named_weld(tmp_path: Path) -> None:
    """A fastened mate in onshape-to-robot's MJCF (an unnamed weld of closing sites): weld closing_<name>."""
    pytest.importorskip("mujoco")
    from tests.description.test_mjcf import FLOATING_MJCF

    text = (
        FLOATING_MJCF.replace("coupler_tip", "closing_fix_1")
        .replace("rocker_tip", "closing_fix_2")
        .replace("<connect ", "<weld ")
    )
    path = tmp_path / "fixed.xml"
    path.write_text(text)
    mech = plm_pin.load(path)
    assert [(c.name, c.spec.type, c.spec.frames) for c in mech.closures] == [
        ("closing_fix", "weld", ("closing_fix_1", "closing_fix_2"))
    ]
    # the floating base's 6, and the planar loop's 4 joints (3 hinges, 1 slide) less the weld's 3
    # planar rows (x, y, rz): 1; a point closure would leave 2 (test_mjcf: mobility 8)
    assert mech.mobility == 7


def test_closing_name_pairs_only_the_two_sides_of_one_mate() -> None:
    """closing_<name>_1 / _2 (and their _z frames) pair; other names do not."""
    from plm_pin.description.onshape import closing_name

    assert closing_name("closing_a_1", "closing_a_2") == "closing_a"
    assert closing_name("closing_a_2_z", "closing_a_1_z") == "closing_a_z"
    assert closing_name("closing_a_1", "closing_a_2_z") is None
    assert closing_name("closing_a_1", "closing_b_2") is None
    assert closing_name("closing_a_1", "closing_a_1") is None
    assert closing_name("tip", "pin") is None
