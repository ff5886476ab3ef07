"""The example-parallel-robots corpus and its sidecar reader (plm_pin/description/interop.py)."""

from __future__ import annotations

import functools
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

import plm_pin
from plm_pin import ClosureNotSatisfied, DescriptionError
from plm_pin.core.mechanism import Mechanism
from plm_pin.description import read_description
from plm_pin.description.interop import parse_epr_sidecar
from plm_pin.warnings import MissingLimitsWarning, MissingMeshWarning

CORPUS = Path(__file__).parents[2].parent / "shared/interop/example-parallel-robots"
if not CORPUS.is_dir():
    pytest.skip(f"example-parallel-robots corpus absent ({CORPUS})", allow_module_level=True)

FOLDERS = sorted(p.name for p in CORPUS.iterdir() if (p / "robot.yaml").is_file())
NOT_ASSEMBLING = "kangaroo_like"
LOADABLE = [f for f in FOLDERS if f != NOT_ASSEMBLING]


def _robot_yaml(folder: str) -> dict:
    return yaml.safe_load((CORPUS / folder / "robot.yaml").read_text())


def _missing_meshes(folder: str) -> set[str]:
    """Mesh references of the URDF whose file is absent from the folder, found by plain text search."""
    text = (CORPUS / folder / "robot.urdf").read_text()
    names = set(re.findall(r'<mesh filename="([^"]+)"', text))
    return {n for n in names if not (CORPUS / folder / n.removeprefix("package:///")).is_file()}


@functools.cache
def _load(folder: str) -> tuple[Mechanism, tuple[warnings.WarningMessage, ...]]:
    """Load a corpus folder once, recording every warning."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mech = plm_pin.load(CORPUS / folder)
    return mech, tuple(caught)


def test_corpus_has_the_expected_folders():
    """The corpus holds the ten example-parallel-robots folders this module relies on."""
    assert len(FOLDERS) == 10
    assert NOT_ASSEMBLING in FOLDERS
    assert "5bar_linkage_iso3d" in FOLDERS


@pytest.mark.parametrize("folder", LOADABLE)
def test_folder_loads_with_closed_loops(folder):
    """Every folder but kangaroo_like loads and its reference configuration closes to 1e-12."""
    mech, _ = _load(folder)
    assert mech.name == folder
    assert np.max(np.abs(mech.closure_residual(mech.q_ref))) <= 1e-12


@pytest.mark.parametrize("folder", LOADABLE)
def test_closures_follow_robot_yaml(folder):
    """Closures are the robot.yaml pairs in order, '3d' typed point and '6d' typed weld, then idle gauges."""
    mech, _ = _load(folder)
    raw = _robot_yaml(folder)
    expected_type = {"3d": "point", "6d": "weld"}
    gauges = mech.closures[len(raw["type"]) :]
    assert [c.name for c in gauges] == [f"idle:{g.joint}" for g in mech.idle_gauges]
    assert [c.frames for c in mech.sidecar.closures] == [tuple(p) for p in raw["closed_loop"]]
    assert [c.type for c in mech.sidecar.closures] == [expected_type[t] for t in raw["type"]]
    assert [c.name for c in mech.sidecar.closures] == [f"loop{k + 1}" for k in range(len(raw["type"]))]


@pytest.mark.parametrize("folder", LOADABLE)
def test_actuators_are_name_mot_in_order(folder):
    """The actuated joints are robot.yaml's name_mot, in the same order, unbounded."""
    mech, _ = _load(folder)
    assert [a.joint for a in mech.actuators] == _robot_yaml(folder)["name_mot"]
    assert all(a.limits is None for a in mech.actuators)


@pytest.mark.parametrize("folder", LOADABLE)
def test_missing_meshes_warn_exactly_once(folder):
    """A folder lacking its meshes warns once, naming the count; a complete folder does not warn."""
    _, caught = _load(folder)
    missing = _missing_meshes(folder)
    mesh_warnings = [w for w in caught if issubclass(w.category, MissingMeshWarning)]
    if not missing:
        assert mesh_warnings == []
        return
    assert len(mesh_warnings) == 1
    msg = str(mesh_warnings[0].message)
    assert f"{len(missing)} mesh file(s) missing, loading without those visuals: " in msg
    assert msg.startswith(str(CORPUS / folder / "robot.urdf"))


def test_folders_with_meshes_are_the_complete_ones():
    """5bar_linkage and robot_delta carry all their meshes; the other folders lack them all."""
    complete = [f for f in FOLDERS if not _missing_meshes(f)]
    assert complete == ["5bar_linkage", "robot_delta"]


def test_iso3d_five_bar_has_two_dof_and_no_redundancy():
    """The point-closed five-bar has mobility 2 (any five-bar has 2 DOF); its 2 motors are not redundant."""
    mech, _ = _load("5bar_linkage_iso3d")
    assert mech.mobility == 2
    assert mech.n_actuators == 2
    assert mech.redundancy == 0


def test_kangaroo_does_not_assemble_from_zero():
    """kangaroo_like raises ClosureNotSatisfied naming the neutral guess, the worst loop and the fix."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MissingMeshWarning)
        warnings.simplefilter("ignore", MissingLimitsWarning)
        with pytest.raises(ClosureNotSatisfied) as info:
            plm_pin.load(CORPUS / NOT_ASSEMBLING)
    exc = info.value
    msg = str(exc)
    assert msg.startswith(
        "kangaroo_like: the closures cannot be assembled from the reference guess (neutral configuration): "
        "residual "
    )
    assert (
        f"m/rad above the closure tolerance 1e-12, worst closure {exc.worst_closure!r}. Give a "
        "configuration close to an assembled one" in msg
    )
    assert msg.endswith("in the sidecar's 'reference', or check that the closure frames can meet.")
    assert re.fullmatch(r"loop([1-9]|1[01])", exc.worst_closure)
    assert exc.residual_norm > exc.tolerance


def test_robot_urdf_path_reads_the_folder():
    """Giving robot.urdf of a folder reads it with robot.yaml, as the folder itself does."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MissingMeshWarning)
        by_file = read_description(CORPUS / "5bar_linkage_iso3d" / "robot.urdf")
        by_folder = read_description(CORPUS / "5bar_linkage_iso3d")
    assert by_file == by_folder
    assert by_file.convention == "example-parallel-robots"
    assert by_file.sidecar.name == "5bar_linkage_iso3d"


# -------------------------------------------------------------- parse errors


def _epr_error(data) -> str:
    with pytest.raises(DescriptionError) as info:
        parse_epr_sidecar(data, "robot.yaml")
    return str(info.value)


def _valid_epr() -> dict:
    return {"closed_loop": [["a", "b"]], "type": ["3d"], "name_mot": ["m1", "m2"]}


def test_epr_sidecar_translates_types_and_motors():
    """A valid robot.yaml gives point/weld closures named loop<k> and unbounded actuators."""
    data = {"closed_loop": [["a", "b"], ["c", "d"]], "type": ["3d", "6d"], "name_mot": ["m1", "m2"]}
    side = parse_epr_sidecar(data, "robot.yaml", name="demo")
    assert [(c.name, c.frames, c.type) for c in side.closures] == [
        ("loop1", ("a", "b"), "point"),
        ("loop2", ("c", "d"), "weld"),
    ]
    assert [a.joint for a in side.actuation] == ["m1", "m2"]
    assert side.name == "demo"
    assert side.task is None


@pytest.mark.parametrize("key", ["closed_loop", "type", "name_mot"])
def test_epr_missing_key_is_named(key):
    """A robot.yaml lacking a key names it and the three keys it needs."""
    data = _valid_epr()
    del data[key]
    assert _epr_error(data) == f"robot.yaml: robot.yaml lacks {key!r}; it needs closed_loop, type, name_mot"


def test_epr_mismatched_lengths_are_refused():
    """closed_loop and type of different lengths are refused with both counts."""
    data = _valid_epr()
    data["type"] = ["3d", "6d"]
    assert _epr_error(data) == "robot.yaml: closed_loop has 1 pairs but type has 2 entries"


def test_epr_bad_type_lists_the_valid_ones():
    """An unknown constraint type such as '4d' is named, with 3d and 6d listed."""
    data = _valid_epr()
    data["type"] = ["4d"]
    assert _epr_error(data) == "robot.yaml: type[0]: invalid constraint type '4d'; valid are ['3d', '6d']"


def test_epr_bad_pair_and_motor_are_refused():
    """A closed_loop entry that is not a pair of names, or a non-string motor, is refused."""
    data = _valid_epr()
    data["closed_loop"] = [["a"]]
    assert _epr_error(data) == "robot.yaml: closed_loop[0] must be a pair of frame names, got ['a']"
    data = _valid_epr()
    data["name_mot"] = ["m1", 3]
    assert _epr_error(data) == "robot.yaml: name_mot[1] must be a joint name, got 3"


def test_epr_non_mapping_and_non_lists_are_refused():
    """A robot.yaml that is not a mapping, or whose entries are not lists, is refused."""
    assert _epr_error(["closed_loop"]) == "robot.yaml: robot.yaml must be a YAML mapping"
    data = _valid_epr()
    data["name_mot"] = "m1"
    assert _epr_error(data) == "robot.yaml: closed_loop, type and name_mot must be lists"


def test_epr_motor_listed_twice_is_refused():
    """A joint listed twice in name_mot is refused, as in a plm-pin sidecar (no double-counted actuator)."""
    data = _valid_epr()
    data["name_mot"] = ["m1", "m2", "m1"]
    assert _epr_error(data) == "robot.yaml: name_mot: joint(s) ['m1'] actuated twice"
