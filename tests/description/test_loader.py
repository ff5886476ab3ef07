"""Reading descriptions from disk and building the model (plm_pin/description/loader.py, writer.py)."""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
import yourdfpy

import plm_pin
from plm_pin import ClosureNotSatisfied, DescriptionError, FrameNotFound, InvalidInput
from plm_pin.description import (
    ActuatorSpec,
    Sidecar,
    parse_sidecar,
    read_description,
    write_description,
)
from plm_pin.description import urdf_parts as u
from plm_pin.description.loader import build_model, description_from_text
from plm_pin.families.classic import build_fourbar

FOURBAR_FRAMES = [
    "universe",
    "base",
    "crank_pivot",
    "crank",
    "coupler_pivot",
    "coupler",
    "coupler_tip_fixed",
    "coupler_tip",
    "rocker_pivot",
    "rocker",
    "rocker_tip_fixed",
    "rocker_tip",
]


def _edit_sidecar(urdf: Path, **changes: Any) -> Path:
    """Rewrite the sidecar beside ``urdf`` with top-level keys replaced; returns its path."""
    path = urdf.with_name(urdf.stem + ".plm.yaml")
    data = yaml.safe_load(path.read_text())
    data.update(changes)
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def _two_body_tree(kind: str) -> yourdfpy.Robot:
    """A base and one body on a joint of the given URDF kind."""
    links = [u.link("base"), u.link("body", 1.0, (0.01, 0.01, 0.01))]
    joints = [u.joint("j", kind, "base", "body")]
    return yourdfpy.Robot(name="two", links=links, joints=joints)


# ------------------------------------------------------------------ paths


def test_urdf_without_sidecar_names_the_expected_file(fourbar):
    """A .urdf with no sidecar beside it names the sidecar it looked for."""
    fourbar.with_name("fourbar.plm.yaml").unlink()
    with pytest.raises(DescriptionError) as info:
        read_description(fourbar)
    assert str(info.value) == (
        f"{fourbar}: no closure sidecar found beside the URDF: expected fourbar.plm.yaml "
        "(format plm-pin/1) or robot.yaml (example-parallel-robots), or closing frames "
        "closing_<name>_1 / closing_<name>_2 (onshape-to-robot)"
    )


def test_sidecar_without_urdf_names_the_expected_file(fourbar):
    """A .plm.yaml with no URDF beside it names the URDF it looked for."""
    fourbar.unlink()
    sidecar = fourbar.with_name("fourbar.plm.yaml")
    with pytest.raises(DescriptionError) as info:
        read_description(sidecar)
    assert str(info.value) == f"{sidecar}: sidecar has no URDF beside it: expected fourbar.urdf"


def test_sidecar_path_reads_the_same_description(fourbar):
    """Giving the .plm.yaml or the .urdf reads the same files."""
    by_urdf = read_description(fourbar)
    by_sidecar = read_description(fourbar.with_name("fourbar.plm.yaml"))
    assert by_sidecar == by_urdf
    assert by_urdf.convention == "plm-pin/1"


def test_folder_with_no_urdf_is_refused(tmp_path):
    """A folder without a URDF says what it expected and what it found."""
    (tmp_path / "notes.txt").write_text("nothing here")
    with pytest.raises(DescriptionError) as info:
        read_description(tmp_path)
    assert str(info.value) == (
        f"{tmp_path}: folder holds neither robot.urdf + robot.yaml (example-parallel-robots) nor "
        "exactly one .urdf file (found [])"
    )


def test_folder_with_two_urdfs_is_refused(fourbar):
    """A folder with two URDFs (and no robot.yaml) is ambiguous and lists both."""
    shutil.copy(fourbar, fourbar.with_name("other.urdf"))
    with pytest.raises(
        DescriptionError, match=r"exactly one \.urdf file \(found \['fourbar.urdf', 'other.urdf'\]\)"
    ):
        read_description(fourbar.parent)


def test_folder_with_one_urdf_reads_it(fourbar):
    """A folder holding exactly one URDF reads that URDF and its sidecar."""
    assert read_description(fourbar.parent).urdf_path == fourbar


def test_nonexistent_path_is_refused(tmp_path):
    """A path that does not exist is a DescriptionError naming it."""
    path = tmp_path / "ghost.urdf"
    with pytest.raises(DescriptionError) as info:
        read_description(path)
    assert str(info.value) == f"{path}: no such file or folder"


def test_load_of_nonexistent_path_lists_presets(tmp_path):
    """plm_pin.load of a missing path says it is neither a preset nor a path, and lists presets."""
    with pytest.raises(DescriptionError) as info:
        plm_pin.load(tmp_path / "ghost.urdf")
    msg = str(info.value)
    assert "is neither a preset nor an existing path; presets are [" in msg
    assert "'fourbar'" in msg
    assert "'erd:<name>'" in msg


def test_unsupported_file_kind_is_refused(tmp_path):
    """An existing file that is neither .urdf nor .plm.yaml is refused, naming the valid kinds."""
    path = tmp_path / "robot.sdf"
    path.write_text("<sdf/>")
    with pytest.raises(DescriptionError) as info:
        read_description(path)
    assert str(info.value) == (
        f"{path}: unsupported file 'robot.sdf'; give a .urdf, a .plm.yaml or a description folder"
    )


def test_sidecar_that_is_not_utf8_is_refused(fourbar):
    """A sidecar that is not UTF-8 text is a DescriptionError naming it."""
    sidecar = fourbar.with_name("fourbar.plm.yaml")
    sidecar.write_bytes(b"format: plm-pin/1\nname: \xff\xfe\n")
    with pytest.raises(
        DescriptionError, match=r"fourbar\.plm\.yaml: not UTF-8 text \(invalid start byte at byte 24\)"
    ):
        read_description(fourbar)


# ----------------------------------------------------------- names in the model


def test_unknown_closure_frame_lists_the_frames(fourbar):
    """A closure naming a missing frame raises FrameNotFound listing the model's frames."""
    sidecar = _edit_sidecar(
        fourbar, closures=[{"name": "c", "frames": ["coupler_tip", "nowhere"], "type": "point"}]
    )
    with pytest.raises(FrameNotFound) as info:
        plm_pin.load(fourbar)
    exc = info.value
    assert exc.name == "nowhere"
    assert exc.kind == "frame"
    assert list(exc.choices) == FOURBAR_FRAMES
    listed = ", ".join(repr(f) for f in FOURBAR_FRAMES)
    assert str(exc) == f"{sidecar}: closure 'c': frame 'nowhere' not found; frames are [{listed}]"
    assert isinstance(exc, DescriptionError)


def test_unknown_end_effector_frame_is_refused(fourbar):
    """An end-effector frame the model lacks raises FrameNotFound at end_effector."""
    _edit_sidecar(fourbar, end_effector={"frame": "tool", "task": ["rz"]})
    with pytest.raises(FrameNotFound, match=r"end_effector: frame 'tool' not found; frames are \['universe'"):
        plm_pin.load(fourbar)


_SAME_NAMES = """<robot name="r"><link name="base"/><link name="a"/><link name="b"/>
<joint name="a" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="j2" type="revolute"><parent link="base"/><child link="b"/><origin xyz="1 0 0"/>
<axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""


@pytest.mark.parametrize(
    ("sidecar", "where"),
    [
        ("closures: [{name: c, frames: [a, b], type: point}]", "closure 'c'"),
        ("end_effector: {frame: a, task: [rz]}", "end_effector"),
    ],
)
def test_a_frame_name_carried_by_a_joint_and_a_link_is_refused(sidecar, where):
    """A sidecar frame naming a joint and a link alike: a DescriptionError (not Pinocchio's ValueError)."""
    description = description_from_text(_SAME_NAMES, f"format: plm-pin/1\n{sidecar}\n")
    with pytest.raises(
        DescriptionError, match=rf"{where}: frame 'a' is ambiguous: 2 frames .*joint, body"
    ) as info:
        build_model(description)
    assert not isinstance(info.value, FrameNotFound)


def test_unknown_actuated_joint_lists_the_joints(fourbar):
    """An actuated joint the model lacks raises FrameNotFound of kind joint listing the joints."""
    sidecar = _edit_sidecar(fourbar, actuation=[{"joint": "crank_motor"}])
    with pytest.raises(FrameNotFound) as info:
        plm_pin.load(fourbar)
    exc = info.value
    assert (exc.name, exc.kind) == ("crank_motor", "joint")
    assert exc.choices == ("crank_pivot", "coupler_pivot", "rocker_pivot")
    assert str(exc) == (
        f"{sidecar}: actuation: joint 'crank_motor' not found; joints are "
        "['crank_pivot', 'coupler_pivot', 'rocker_pivot']"
    )


def test_fixed_joint_cannot_be_actuated(fourbar):
    """A fixed joint (a frame, not a model joint) cannot be actuated."""
    _edit_sidecar(fourbar, actuation=[{"joint": "rocker_tip_fixed"}])
    with pytest.raises(FrameNotFound, match="joint 'rocker_tip_fixed' not found"):
        plm_pin.load(fourbar)


def test_multi_dof_joint_cannot_be_actuated(tmp_path):
    """Actuating a floating (6-DOF) joint is refused, saying only one-DOF joints can be."""
    urdf, sidecar = write_description(
        _two_body_tree("floating"), Sidecar(actuation=(ActuatorSpec("j"),)), tmp_path, "floater"
    )
    with pytest.raises(DescriptionError) as info:
        plm_pin.load(urdf)
    assert str(info.value) == (
        f"{sidecar}: actuated joint 'j' has 6 DOF; "
        "only one-DOF (prismatic or revolute) joints can be actuated"
    )


def test_reference_with_wrong_number_of_values_is_refused(fourbar):
    """A revolute joint's reference with two values is refused, saying it takes one."""
    sidecar = _edit_sidecar(fourbar, reference={"crank_pivot": [1.0, 2.0]})
    with pytest.raises(DescriptionError) as info:
        plm_pin.load(fourbar)
    assert str(info.value) == f"{sidecar}: reference.crank_pivot has 2 value(s); the joint takes 1"


def test_reference_of_unknown_joint_is_refused(fourbar):
    """A reference value for a joint the model lacks raises FrameNotFound of kind joint."""
    _edit_sidecar(fourbar, reference={"crank": 1.0})
    with pytest.raises(
        FrameNotFound, match=r"reference: joint 'crank' not found; joints are \['crank_pivot'"
    ):
        plm_pin.load(fourbar)


def test_continuous_joint_reference_takes_an_angle_or_cos_sin(tmp_path):
    """A continuous joint takes one angle or (cos, sin); three values are refused naming both forms."""
    tree = _two_body_tree("continuous")
    good = Sidecar(actuation=(ActuatorSpec("j"),), reference={"j": (math.pi / 2,)})
    urdf, _ = write_description(tree, good, tmp_path, "spinner")
    q = plm_pin.load(urdf).reference_guess()
    np.testing.assert_allclose(q, [0.0, 1.0], atol=1e-15)  # cos(pi/2), sin(pi/2)
    bad = Sidecar(actuation=(ActuatorSpec("j"),), reference={"j": (1.0, 0.0, 0.0)})
    urdf, sidecar = write_description(tree, bad, tmp_path, "spinner")
    with pytest.raises(DescriptionError) as info:
        plm_pin.load(urdf)
    assert str(info.value) == f"{sidecar}: reference.j has 3 value(s); the joint takes 2 (or one angle [rad])"


def test_joint_with_a_missing_child_link_names_it_and_lists_the_links(fourbar):
    """A joint whose child link does not exist is refused before Pinocchio, naming the link."""
    text = fourbar.read_text().replace('<child link="rocker_tip"/>', '<child link="ghost"/>')
    fourbar.write_text(text)
    with pytest.raises(FrameNotFound) as info:
        plm_pin.load(fourbar)
    assert info.value.name == "ghost"
    assert info.value.kind == "link"
    assert str(info.value).startswith(
        f"{fourbar}: joint 'rocker_tip_fixed' child: link 'ghost' not found; links are ['base', 'crank'"
    )


def test_link_with_two_parents_suggests_a_closure(fourbar):
    """A link that closes a loop inside the URDF is refused with a pointer to the sidecar."""
    text = fourbar.read_text().replace('<child link="rocker_tip"/>', '<child link="coupler_tip"/>')
    fourbar.write_text(text)
    with pytest.raises(
        DescriptionError, match=r"link 'coupler_tip' is the child of two joints .*declare it as a closure"
    ):
        plm_pin.load(fourbar)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            '<mass value="',
            '<mass value="heavy',
            r"link 'crank': <mass value='heavy0.2'> must hold 1 finite number",
        ),
        ('<mass value="', '<mass value="-', r"link 'crank': negative mass -0.2"),
        (
            '<origin xyz="0.1 0.0 0.0"',
            '<origin xyz="0.1 0.0"',
            r"link 'rocker': <origin xyz='0.1 0.0'> must hold 3",
        ),
        (
            '<axis xyz="0.0 0.0 1.0"/>',
            '<axis xyz="0.0 nan 1.0"/>',
            r"joint 'crank_pivot': <axis xyz='0.0 nan 1.0'>",
        ),
    ],
)
def test_bad_numbers_are_refused_not_skipped(fourbar, old, new, message):
    """Non-numeric, non-finite or miscounted numbers are refused (Pinocchio's parser would skip them)."""
    fourbar.write_text(fourbar.read_text().replace(old, new, 1))
    with pytest.raises(DescriptionError, match=message):
        plm_pin.load(fourbar)


def test_pinocchio_rejection_is_a_description_error(fourbar, monkeypatch):
    """Should Pinocchio still reject a checked URDF, its error is wrapped in a plain DescriptionError."""
    import pinocchio

    def refuse(_xml):
        raise RuntimeError("The XML stream does not contain a valid URDF model.")

    monkeypatch.setattr(pinocchio, "buildModelFromXML", refuse)
    with pytest.raises(DescriptionError) as info:
        plm_pin.load(fourbar)
    assert type(info.value) is DescriptionError
    assert str(info.value) == (
        f"{fourbar}: Pinocchio cannot build a model from this URDF: "
        "The XML stream does not contain a valid URDF model."
    )


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda t: t.replace('<inertia ixx="2.5e-06"', "<inertia", 1),
            r"link 'crank': <inertia> lacks \['ixx'\]",
        ),
        (
            lambda t: re.sub(r"<limit [^>]*/>", "", t, count=1),
            r"joint 'crank_pivot': a revolute joint needs <limit",
        ),
        (lambda t: t.replace('<axis xyz="0.0 0.0 1.0"/>', '<axis xyz="0 0 0"/>', 1), r"must be non-zero"),
    ],
)
def test_incomplete_elements_are_refused(fourbar, edit, message):
    """Elements Pinocchio would half-read (missing inertia terms, limits, zero axis) are refused."""
    fourbar.write_text(edit(fourbar.read_text()))
    with pytest.raises(DescriptionError, match=message):
        plm_pin.load(fourbar)


def test_unreachable_closure_names_it_and_suggests_the_reference(fourbar):
    """A four-bar whose rocker pivot is out of reach fails with the closure name and the 'reference' hint."""
    # crank 0.10 + coupler 0.25 reach 0.35 m; the rocker tip stays within 0.20 m of a pivot
    # moved to x = 1.0 m: the tips are always at least 0.45 m apart.
    text = fourbar.read_text()
    pivot = re.compile(r'(<child link="rocker"/>\s*<origin xyz=")0\.3 0\.0 0\.0"')
    assert len(pivot.findall(text)) == 1
    fourbar.write_text(pivot.sub(r'\g<1>1.0 0.0 0.0"', text))
    with pytest.raises(ClosureNotSatisfied) as info:
        plm_pin.load(fourbar)
    exc = info.value
    msg = str(exc)
    assert msg.startswith(
        "fourbar: the closures cannot be assembled from the reference guess (sidecar reference)"
    )
    assert "worst closure 'coupler_rocker'" in msg
    assert "Give a configuration close to an assembled one in the sidecar's 'reference'" in msg
    assert "check that the closure frames can meet" in msg
    assert exc.worst_closure == "coupler_rocker"
    # the gap vector has norm >= 0.45 m in the x-y plane, so its largest component is >= 0.45 / sqrt(2)
    assert exc.residual_norm >= 0.45 / math.sqrt(2)


def test_unreachable_closure_can_be_loaded_without_validation(fourbar):
    """validate=False defers assembly: loading works and q_ref then raises ClosureNotSatisfied."""
    pivot = re.compile(r'(<child link="rocker"/>\s*<origin xyz=")0\.3 0\.0 0\.0"')
    fourbar.write_text(pivot.sub(r'\g<1>1.0 0.0 0.0"', fourbar.read_text()))
    mech = plm_pin.load(fourbar, validate=False)
    with pytest.raises(ClosureNotSatisfied, match="cannot close the loops"):
        mech.q_ref  # noqa: B018


# ------------------------------------------------------------ model contents


def test_gravity_and_armature_come_from_the_sidecar(fourbar):
    """The model's gravity is the sidecar's; a direct drive adds its rotor inertia as armature."""
    _edit_sidecar(
        fourbar, actuation=[{"joint": "crank_pivot", "rotor_inertia": 0.01, "screw_inertia": 0.002}]
    )
    model = build_model(read_description(fourbar))
    np.testing.assert_array_equal(model.gravity.linear, [0.0, -9.81, 0.0])
    np.testing.assert_allclose(model.armature, [0.012, 0.0, 0.0], rtol=1e-15)


def test_description_from_text_matches_the_files(fourbar):
    """description_from_text on the files' texts gives the same sidecar and URDF XML."""
    from_text = description_from_text(fourbar.read_text(), fourbar.with_name("fourbar.plm.yaml").read_text())
    from_files = read_description(fourbar)
    assert from_text.sidecar == from_files.sidecar
    assert from_text.urdf.xml == from_files.urdf.xml


# ------------------------------------------------------------------ writer


@pytest.mark.parametrize("name", ["a/b", "..", "../evil", "x.y", "", "sp ace", "m\u00e9canisme"])
def test_writer_refuses_unsafe_names(tmp_path, name):
    """write_description refuses a name with '/', '..' or other characters, non-ASCII too, writing nothing."""
    robot, sidecar = build_fourbar()
    with pytest.raises(InvalidInput) as info:
        write_description(robot, sidecar, tmp_path / "out", name)
    assert str(info.value) == f"invalid description name {name!r}: use letters, digits, '_' and '-'"
    assert not (tmp_path / "out").exists()


def test_written_description_reads_back_equal(tmp_path):
    """write_description writes <name>.urdf and <name>.plm.yaml; reading them back gives an equal Sidecar."""
    robot, sidecar = build_fourbar(name="bar4", source="test")
    urdf, side = write_description(robot, sidecar, tmp_path / "nested" / "dir", "bar4")
    assert urdf == tmp_path / "nested" / "dir" / "bar4.urdf"
    assert side == tmp_path / "nested" / "dir" / "bar4.plm.yaml"
    assert sorted(p.name for p in urdf.parent.iterdir()) == ["bar4.plm.yaml", "bar4.urdf"]  # no temp files
    description = read_description(urdf)
    assert description.sidecar == sidecar
    assert description.urdf.name == "bar4"
    assert description.urdf_path == urdf
    assert description.sidecar_path == side


def test_written_description_overwrites_in_place(tmp_path):
    """Writing a description twice under one name replaces the files with the new content."""
    robot, sidecar = build_fourbar()
    write_description(robot, sidecar, tmp_path, "bar")
    changed = parse_sidecar({**sidecar.to_dict(), "gravity": [0.0, 0.0, -1.0]})
    write_description(robot, changed, tmp_path, "bar")
    assert read_description(tmp_path / "bar.urdf").sidecar.gravity == (0.0, 0.0, -1.0)
