"""The closure sidecar: parser, serialiser and actuator data (plm_pin/description/sidecar.py)."""

from __future__ import annotations

import math
import re
import textwrap
from typing import Any

import pytest

from plm_pin import DescriptionError
from plm_pin.description import ActuatorSpec, ClosureSpec, Sidecar, TaskSpec, parse_sidecar
from plm_pin.description.sidecar import read_yaml

FULL = Sidecar(
    closures=(
        ClosureSpec("rod2_plate", ("rod2_tip", "plate_left"), "point"),
        ClosureSpec("hinge", ("a", "b"), "revolute", (0.0, 0.6, 0.8)),
        ClosureSpec("glue", ("c", "d"), "weld"),
    ),
    actuation=(
        ActuatorSpec("slider1", (-50.0, 50.0), 0.05, 0.0248, 0.001),
        ActuatorSpec("slider2", None, 0.01),
        ActuatorSpec("crank"),
    ),
    task=TaskSpec("plate_center", ("x", "y", "rz")),
    gravity=(0.0, -9.8, 0.0),
    reference={"slider1": (-0.1,), "ball": (0.0, 0.0, 0.0, 1.0)},
    name="demo",
    source="Harada 2011, Table 1",
    closure_tolerance=1e-6,
    mobility=3,
)


def _valid() -> dict[str, Any]:
    """A minimal valid sidecar as plain data, one closure and one actuator."""
    return {
        "format": "plm-pin/1",
        "closures": [{"name": "c1", "frames": ["a", "b"], "type": "point"}],
        "actuation": [{"joint": "j1"}],
    }


def _error(data: Any) -> str:
    with pytest.raises(DescriptionError) as info:
        parse_sidecar(data, "robot.plm.yaml")
    return str(info.value)


def test_full_sidecar_round_trips_through_yaml():
    """Sidecar.to_yaml() read back by read_yaml + parse_sidecar gives an equal Sidecar."""
    text = FULL.to_yaml()
    assert parse_sidecar(read_yaml(text, "x.plm.yaml"), "x.plm.yaml") == FULL


def test_minimal_sidecar_round_trips_and_gets_defaults():
    """A sidecar with no task, gravity or reference round-trips and gets the default gravity."""
    side = parse_sidecar(_valid())
    assert side.gravity == (0.0, 0.0, -9.81)
    assert side.task is None
    assert dict(side.reference) == {}
    assert parse_sidecar(read_yaml(side.to_yaml())) == side


def test_revolute_axis_is_normalised():
    """A revolute closure's axis is stored as a unit vector along the given direction."""
    data = _valid()
    data["closures"] = [{"name": "h", "frames": ["a", "b"], "type": "revolute", "axis": [0, 3, 4]}]
    assert parse_sidecar(data).closures[0].axis == pytest.approx((0.0, 0.6, 0.8), abs=1e-15)


def test_task_directions_are_put_in_canonical_order():
    """Task directions are stored in x y z rx ry rz order whatever order the file uses."""
    data = _valid()
    data["end_effector"] = {"frame": "ee", "task": ["rz", "x", "y"]}
    task = parse_sidecar(data).task
    assert task is not None
    assert task.dofs == ("x", "y", "rz")
    assert task.rows() == (0, 1, 5)


def test_unknown_top_level_key_lists_the_valid_keys():
    """An unknown top-level key is named, with every valid key listed."""
    data = _valid()
    data["closure"] = []
    msg = _error(data)
    assert msg.startswith("robot.plm.yaml: sidecar: unknown key(s) ['closure']")
    for key in ("actuation", "closures", "end_effector", "format", "gravity", "name", "reference", "source"):
        assert repr(key) in msg


def test_wrong_format_string_is_refused():
    """A format other than plm-pin/1 (or none) is refused, naming the expected format."""
    data = _valid()
    data["format"] = "plm-pin/2"
    assert "unknown sidecar format 'plm-pin/2'; expected 'plm-pin/1'" in _error(data)
    del data["format"]
    assert "unknown sidecar format None; expected 'plm-pin/1'" in _error(data)


def test_invalid_closure_type_names_it_and_lists_valid_types():
    """An invalid closure type is named with the closure, and point/revolute/weld are listed."""
    data = _valid()
    data["closures"][0]["type"] = "hinge"
    msg = _error(data)
    assert "closures[0] (c1): invalid closure type 'hinge'" in msg
    assert "valid types are ['point', 'revolute', 'weld']" in msg


def test_revolute_closure_without_axis_is_refused():
    """A revolute closure must give its axis."""
    data = _valid()
    data["closures"][0]["type"] = "revolute"
    assert "closures[0] (c1): a revolute closure needs an 'axis'" in _error(data)


def test_zero_axis_is_refused():
    """A revolute closure's axis must be non-zero."""
    data = _valid()
    data["closures"][0].update(type="revolute", axis=[0.0, 0.0, 0.0])
    assert "closures[0].axis must be non-zero, got [0.0, 0.0, 0.0]" in _error(data)


def test_axis_of_wrong_length_is_refused():
    """A revolute axis must have three numbers."""
    data = _valid()
    data["closures"][0].update(type="revolute", axis=[0.0, 1.0])
    assert "closures[0].axis must have 3 numbers, got 2" in _error(data)


def test_axis_on_a_point_closure_is_refused():
    """'axis' is refused on a point (non-revolute) closure."""
    data = _valid()
    data["closures"][0]["axis"] = [0, 0, 1]
    assert "closures[0] (c1): 'axis' is only valid for revolute" in _error(data)


def test_duplicate_closure_names_are_refused():
    """Two closures with the same name are refused, naming it."""
    data = _valid()
    data["closures"].append({"name": "c1", "frames": ["c", "d"], "type": "weld"})
    assert "duplicate closure name(s) ['c1']" in _error(data)


def test_closure_needs_two_frames():
    """A closure with other than two frames is refused."""
    data = _valid()
    data["closures"][0]["frames"] = ["a"]
    assert "closures[0].frames must be a list of two frame names" in _error(data)


def test_joint_actuated_twice_is_refused():
    """The same joint listed twice in actuation is refused."""
    data = _valid()
    data["actuation"].append({"joint": "j1"})
    assert "joint(s) ['j1'] actuated twice" in _error(data)


@pytest.mark.parametrize("limits", [[50.0, -50.0], [10.0, 10.0]])
def test_limits_need_lower_below_upper(limits):
    """Actuator limits with lower >= upper are refused, showing both values."""
    data = _valid()
    data["actuation"][0]["limits"] = limits
    assert f"actuation[0].limits must have lower < upper, got {limits}" in _error(data)


@pytest.mark.parametrize("lead", [-0.01, 0.0])
def test_lead_must_be_positive(lead):
    """A zero or negative ball-screw lead is refused."""
    data = _valid()
    data["actuation"][0]["lead"] = lead
    assert f"actuation[0].lead must be positive [m/rev], got {lead}" in _error(data)


@pytest.mark.parametrize("key", ["rotor_inertia", "screw_inertia"])
def test_negative_inertia_is_refused(key):
    """A negative rotor or screw inertia is refused."""
    data = _valid()
    data["actuation"][0][key] = -1e-4
    assert f"actuation[0].{key} must be >= 0 [kg m^2], got -0.0001" in _error(data)


def test_unknown_actuator_key_is_refused():
    """An unknown key in an actuator entry lists the valid ones."""
    data = _valid()
    data["actuation"][0]["gear_ratio"] = 10
    msg = _error(data)
    assert "actuation[0]: unknown key(s) ['gear_ratio']" in msg
    assert "['joint', 'lead', 'limits', 'rotor_inertia', 'screw_inertia']" in msg


def test_unknown_task_direction_lists_the_valid_ones():
    """An unknown task direction is named, with x y z rx ry rz listed."""
    data = _valid()
    data["end_effector"] = {"frame": "ee", "task": ["x", "theta"]}
    msg = _error(data)
    assert "end_effector.task: unknown direction 'theta'" in msg
    assert "valid are ['x', 'y', 'z', 'rx', 'ry', 'rz']" in msg


def test_repeated_task_direction_is_refused():
    """A task direction given twice is refused."""
    data = _valid()
    data["end_effector"] = {"frame": "ee", "task": ["x", "x"]}
    assert "end_effector.task repeats a direction: ['x', 'x']" in _error(data)


def test_boolean_is_not_a_number():
    """YAML booleans are not accepted where a number is expected."""
    data = _valid()
    data["actuation"][0]["lead"] = True
    assert "actuation[0].lead must be a number, got True" in _error(data)


@pytest.mark.parametrize(
    ("snippet", "where"),
    [
        ("gravity: [0.0, .nan, 0.0]", "gravity[1]"),
        ("gravity: [0.0, 0.0, -.inf]", "gravity[2]"),
        ("actuation: [{joint: j1, lead: .inf}]", "actuation[0].lead"),
        ("actuation: [{joint: j1, limits: [-.inf, 1.0]}]", "actuation[0].limits[0]"),
        ("actuation: [{joint: j1, rotor_inertia: .NaN}]", "actuation[0].rotor_inertia"),
        ("reference: {j1: .nan}", "reference.j1"),
        ("reference: {j1: [0.0, .inf]}", "reference.j1[1]"),
    ],
)
def test_non_finite_numbers_are_refused(snippet, where):
    """.nan and .inf in the YAML are refused wherever a number is read, naming the place."""
    text = f"format: plm-pin/1\n{snippet}\n"
    msg = _error(read_yaml(text, "robot.plm.yaml"))
    assert re.search(rf"{re.escape(where)} must be finite, got -?(nan|inf)", msg), msg


def test_malformed_yaml_gives_line_and_column():
    """Malformed YAML is a DescriptionError naming the file, the line and the column."""
    text = textwrap.dedent(
        """\
        format: plm-pin/1
        closures:
          - name: c1
            frames: [a, b
            type: point
        """
    )
    with pytest.raises(DescriptionError) as info:
        read_yaml(text, "robot.plm.yaml")
    # the unclosed flow list on line 4 runs into "type:" whose colon is line 5, column 9 (LibYAML
    # says "did not find expected ',' or ']'", the pure-Python parser "expected ',' or ']', but got ':'")
    assert str(info.value).startswith("robot.plm.yaml: malformed YAML at line 5, column 9: ")
    assert "expected ',' or ']'" in str(info.value)
    assert info.value.path == "robot.plm.yaml"


def test_yaml_python_tags_are_not_executed():
    """read_yaml is safe: a python/object tag is a YAML error, not an object."""
    with pytest.raises(DescriptionError, match="malformed YAML"):
        read_yaml("!!python/object/apply:os.system ['true']", "evil.yaml")


def test_sidecar_must_be_a_mapping():
    """A YAML list (or scalar) at the top level is refused."""
    assert _error(["format", "plm-pin/1"]) == "robot.plm.yaml: the sidecar must be a YAML mapping"


def test_reflected_inertia_matches_hand_computation():
    """(J_rotor + J_screw) (2 pi / lead)^2: 0.0258 kg m^2 through a 50 mm lead is 407.417 kg."""
    # 2 pi / 0.05 = 125.66370614 rad/m; squared 15791.3670417; times 0.0258 -> 407.41726968
    act = ActuatorSpec("slider1", lead=0.05, rotor_inertia=0.0248, screw_inertia=0.001)
    assert act.reflected_inertia() == pytest.approx(407.41726968, rel=1e-9)
    # a lead of 2 pi cm per turn gives a ratio of exactly 100 rad/m: 3e-4 kg m^2 -> 3 kg
    ratio100 = ActuatorSpec("s", lead=2 * math.pi / 100.0, rotor_inertia=1e-4, screw_inertia=2e-4)
    assert ratio100.reflected_inertia() == pytest.approx(3.0, rel=1e-12)


def test_direct_drive_reflects_the_inertia_unchanged():
    """Without a lead, the armature is the plain sum of rotor and screw inertias."""
    assert ActuatorSpec(
        "crank", rotor_inertia=0.01, screw_inertia=0.002
    ).reflected_inertia() == pytest.approx(0.012)
    assert ActuatorSpec("crank").reflected_inertia() == 0.0


def test_closure_rows_per_type():
    """A point closure has 3 rows, a revolute 5, a weld 6."""
    assert [c.rows for c in FULL.closures] == [3, 5, 6]


def test_non_string_key_is_reported_not_crashed_on():
    """A non-string key beside string keys is named as unknown (no TypeError from sorting)."""
    msg = _error(read_yaml("format: plm-pin/1\n1: x\nfoo: y\n"))
    assert "sidecar: unknown key(s) [1, 'foo']" in msg


def test_joint_task_round_trips_and_refuses_a_frame_beside_it():
    """`end_effector: {joints: [...]}`: a frameless task that round-trips; a frame beside it is refused."""
    side = parse_sidecar({**_valid(), "end_effector": {"joints": ["j1"]}})
    assert side.task == TaskSpec(None, ("j1",))
    assert side.task.joints == ("j1",) and side.task.rows() == ()
    assert parse_sidecar(read_yaml(side.to_yaml())) == side
    message = _error({**_valid(), "end_effector": {"joints": ["j1"], "frame": "tip"}})
    assert (
        "end_effector takes either joints (a joint task) or frame and task (a frame task), not both"
        in message
    )
    assert "end_effector.joints must be a non-empty list" in _error(
        {**_valid(), "end_effector": {"joints": []}}
    )


def test_joint_task_on_a_missing_joint_is_refused(tmp_path):
    """Loading refuses an output joint that does not exist, listing the joints; a real one loads."""
    import shutil

    import yaml

    import plm_pin
    from plm_pin.models import urdf_folder

    shutil.copy(urdf_folder() / "fourbar.urdf", tmp_path)
    data = yaml.safe_load((urdf_folder() / "fourbar.plm.yaml").read_text())
    data["end_effector"] = {"joints": ["rocker"]}
    (tmp_path / "fourbar.plm.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(DescriptionError, match=r"joint 'rocker' not found; joints are \['crank_pivot'"):
        plm_pin.load(tmp_path / "fourbar.urdf")
    data["end_effector"] = {"joints": ["rocker_pivot"]}
    (tmp_path / "fourbar.plm.yaml").write_text(yaml.safe_dump(data))
    assert plm_pin.load(tmp_path / "fourbar.urdf").task_compiled.dofs == ("rocker_pivot",)


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("closure_tolerance", 0.0, "closure_tolerance must be > 0 [m, rad], got 0.0"),
        ("closure_tolerance", "wide", "closure_tolerance must be a number, got 'wide'"),
        ("mobility", -1, "mobility must be an integer >= 0, got -1"),
        ("mobility", 2.5, "mobility must be an integer >= 0, got 2.5"),
        ("mobility", True, "mobility must be an integer >= 0, got True"),
    ],
)
def test_closure_tolerance_and_mobility_are_checked(key, value, message):
    """A closure tolerance must be a positive number, a mobility a non-negative integer."""
    assert message in _error({**_valid(), key: value})
