"""Descriptions that would be answered wrongly are refused: self-closures, detached cycles, limits, mimics."""

from __future__ import annotations

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from plm_pin import load
from plm_pin.exceptions import DescriptionError
from plm_pin.loading import erd_names
from tests.robustness.conftest import (
    budget,
    fourbar_files,
    fourbar_sidecar,
    fourbar_urdf,
    one_line_error,
    run_cli,
)

JOINTS = ("crank_pivot", "coupler_pivot", "rocker_pivot")
FRAMES = (
    "base",
    "crank",
    "coupler",
    "rocker",
    "coupler_tip",
    "rocker_tip",
    "crank_pivot",
    "rocker_tip_fixed",
)
RIGID = {  # frames that move with one body once fixed joints are merged (Pinocchio's parent joint)
    "base": "universe",
    "crank": "crank_pivot",
    "crank_pivot": "crank_pivot",
    "coupler": "coupler_pivot",
    "coupler_tip": "coupler_pivot",
    "rocker": "rocker_pivot",
    "rocker_tip": "rocker_pivot",
    "rocker_tip_fixed": "rocker_pivot",
}
"""The body each frame of the four-bar moves with, read off the URDF by hand."""


def sidecar_text(**closure: object) -> str:
    """The four-bar sidecar with its closure changed."""
    data = fourbar_sidecar()
    data["closures"][0].update(closure)
    return yaml.safe_dump(data, sort_keys=False)


@pytest.mark.parametrize("frame", FRAMES)
@pytest.mark.parametrize("kind", ["point", "weld"])
def test_a_closure_of_a_frame_with_itself_is_refused(tmp_path, frame, kind):
    """A closure joining a frame to itself constrains nothing: refused by the sidecar reader."""
    urdf = fourbar_files(tmp_path, sidecar=sidecar_text(frames=[frame, frame], type=kind))
    with pytest.raises(
        DescriptionError, match=rf"closures\[0\] \(coupler_rocker\): joins frame '{frame}' to itself"
    ):
        load(urdf)


@pytest.mark.parametrize(
    ("first", "second"),
    [(a, b) for a in FRAMES for b in FRAMES if a < b and RIGID[a] == RIGID[b]],
)
def test_a_closure_between_two_frames_of_one_body_is_refused(tmp_path, first, second):
    """Two frames rigidly joined (one body after fixed joints merge) make no loop: refused naming the body."""
    urdf = fourbar_files(tmp_path, sidecar=sidecar_text(frames=[first, second]))
    with pytest.raises(
        DescriptionError, match=rf"two frames of one rigid body \(both move with joint '{RIGID[first]}'\)"
    ):
        load(urdf)


def test_plm_pin_check_refuses_a_self_closure_in_one_line(tmp_path):
    """The issue's case: `check` used to say "mobility 3, redundancy -2"; now it fails in one line."""
    urdf = fourbar_files(tmp_path, sidecar=sidecar_text(frames=["rocker_tip", "rocker_tip"]))
    assert "joins frame 'rocker_tip' to itself" in one_line_error(run_cli("check", str(urdf)))


def detached_cycle(n: int, kind: str) -> str:
    """The four-bar URDF plus ``n`` links joined in a ring by ``kind`` joints, hanging from nothing."""
    links = "".join(f'  <link name="ring{i}"/>\n' for i in range(n))
    limit = (
        '<axis xyz="0 0 1"/><limit effort="1" velocity="1" lower="-1" upper="1"/>' if kind != "fixed" else ""
    )
    joints = "".join(
        f'  <joint name="ring_joint{i}" type="{kind}"><parent link="ring{i}"/>'
        f'<child link="ring{(i + 1) % n}"/>{limit}</joint>\n'
        for i in range(n)
    )
    return fourbar_urdf().replace("</robot>", links + joints + "</robot>")


@pytest.mark.parametrize("n", [1, 2, 3, 7])
@pytest.mark.parametrize("kind", ["fixed", "revolute"])
def test_a_cycle_of_joints_detached_from_the_root_is_refused(tmp_path, n, kind):
    """Links in a ring of joints have one parent each but never reach the root: refused, not dropped."""
    urdf = fourbar_files(tmp_path, urdf=detached_cycle(n, kind))
    rings = [f"ring{i}" for i in range(n)]
    with pytest.raises(
        DescriptionError, match=r"do not hang from the root link 'base': their joints form a cycle"
    ) as err:
        load(urdf)
    assert all(name in str(err.value) for name in rings[:8])


@budget
@given(
    joint=st.sampled_from(JOINTS),
    lower=st.floats(-10.0, 10.0),
    gap=st.floats(1e-9, 10.0),
)
def test_joint_limits_with_lower_above_upper_are_refused(tmp_path_factory, joint, lower, gap):
    """A position limit with lower > upper (by any amount) is refused naming the joint."""
    upper = lower - gap
    if not upper < lower:  # the gap vanished in rounding
        return
    old = '<limit effort="1000.0" velocity="100.0" lower="-6.283185307179586" upper="6.283185307179586"/>'
    text = fourbar_urdf().split(f'<joint name="{joint}"', 1)
    text[1] = text[1].replace(
        old, f'<limit effort="1000.0" velocity="100.0" lower="{lower!r}" upper="{upper!r}"/>', 1
    )
    urdf = fourbar_files(tmp_path_factory.mktemp("l"), urdf=f'<joint name="{joint}"'.join(text))
    with pytest.raises(
        DescriptionError, match=rf"joint '{joint}': <limit lower=.* upper=.*> has lower > upper"
    ):
        load(urdf, validate=False)


@pytest.mark.parametrize("joint", JOINTS)
@pytest.mark.parametrize(("attribute", "value"), [("effort", "-1"), ("effort", "-1e-9"), ("velocity", "-5")])
def test_a_negative_effort_or_velocity_names_its_joint(tmp_path, joint, attribute, value):
    """A negative URDF effort or velocity is refused naming the joint and the unit."""
    text = fourbar_urdf().split(f'<joint name="{joint}"', 1)
    text[1] = text[1].replace(
        f'{attribute}="{"1000.0" if attribute == "effort" else "100.0"}"', f'{attribute}="{value}"', 1
    )
    urdf = fourbar_files(tmp_path, urdf=f'<joint name="{joint}"'.join(text))
    with pytest.raises(
        DescriptionError, match=rf"joint '{joint}': <limit {attribute}='{value}'> must be >= 0 \["
    ):
        load(urdf, validate=False)


NAMES_NO_JOINT = r"<mimic joint=.*> must name another moving joint"
BAD_NUMBER = r"<mimic (multiplier|offset)=.* must hold 1 finite"
MIMICS = {
    "no joint attribute": ("<mimic multiplier='1'/>", NAMES_NO_JOINT),
    "an unknown joint": ("<mimic joint='nope'/>", NAMES_NO_JOINT),
    "itself": ("<mimic joint='coupler_pivot'/>", NAMES_NO_JOINT),
    "a fixed joint": ("<mimic joint='rocker_tip_fixed'/>", NAMES_NO_JOINT),
    "an empty name": ("<mimic joint=''/>", NAMES_NO_JOINT),
    "a NaN multiplier": ("<mimic joint='crank_pivot' multiplier='nan'/>", BAD_NUMBER),
    "a text offset": ("<mimic joint='crank_pivot' offset='x'/>", BAD_NUMBER),
}
"""Bad ``<mimic>`` elements on the coupler joint, and the message each gets."""


@pytest.mark.parametrize("case", sorted(MIMICS))
def test_a_bad_mimic_is_refused_before_pinocchio(tmp_path, case, capfd):
    """A mimic naming no other moving joint, or with a bad number, is refused naming the joint; no stderr."""
    mimic, message = MIMICS[case]
    text = fourbar_urdf().replace(
        '<joint name="coupler_pivot" type="revolute">',
        f'<joint name="coupler_pivot" type="revolute">{mimic}',
        1,
    )
    urdf = fourbar_files(tmp_path, urdf=text)
    with pytest.raises(DescriptionError, match=rf"joint 'coupler_pivot': {message}"):
        load(urdf, validate=False)
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize("axis", ["0 0 0", "0 0 1e-12", "1e-300 0 0", "1e-10 1e-10 1e-10"])
def test_a_near_zero_axis_is_refused_naming_the_joint(tmp_path, axis):
    """A moving joint's axis shorter than 1e-9 is refused as such, not blamed on the reference guess."""
    text = fourbar_urdf().replace('<axis xyz="0.0 0.0 1.0"/>', f'<axis xyz="{axis}"/>', 1)
    urdf = fourbar_files(tmp_path, urdf=text)
    with pytest.raises(
        DescriptionError,
        match=rf"joint 'crank_pivot': <axis xyz='{axis}'> must be non-zero \(norm at least 1e-09\)",
    ):
        load(urdf)


@pytest.mark.parametrize("pattern", ["*", "ur*", "?r5", "[u]r5", "**/ur5", "ur5*", "*_robot", "../*"])
def test_erd_names_are_names_not_patterns(pattern):
    """`erd:` takes a robot name only; glob characters match nothing and the message lists the names."""
    assert pattern not in erd_names()
    with pytest.raises(DescriptionError, match=r"unknown example-robot-data robot .*; available are \["):
        load(f"erd:{pattern}")


def test_plm_pin_info_erd_star_fails_in_one_line():
    """The issue's case: `plm-pin info 'erd:*'` is an unknown robot, not the first file a glob finds."""
    assert "unknown example-robot-data robot '*'" in one_line_error(run_cli("info", "erd:*"))
