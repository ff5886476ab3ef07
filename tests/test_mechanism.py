"""The Mechanism model (plm_pin/core/mechanism.py): sizes, mobility, assembly, bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

import plm_pin
import plm_pin.models
from analyses import _harada2011_paper as paper
from plm_pin.models import PRESETS, preset_names
from tests.conftest import preset

# Mobility and redundancy of the seed mechanisms, from the papers' statements (and the
# Chebychev-Grubler count for the classic chains), not from plm_pin.
EXPECTED = {
    "harada2011_3d4m": (3, 1),
    "harada2011_3d3m": (3, 0),
    "harada2015_asymmetric": (3, 1),
    "fourbar": (1, 0),
    "fivebar": (2, 0),
    "enferadi2017_star_triangle": (3, 0),
    "zhao2011_8pss": (6, 2),
    "zhao2011_6pss": (6, 0),
    # Chebychev-Grubler: the planar 3-RPR 3 (x, y, rz), a 6-UPS 6 (six 6-DOF legs on a rigid
    # platform), the Delta 3 (each parallelogram blocks two rotations of the platform)
    "planar_3rpr": (3, 0),
    "stewart_6ups": (6, 0),
    "delta": (3, 0),
}


@pytest.mark.parametrize("name", preset_names())
def test_mobility_and_redundancy_match_the_papers(name):
    """Mobility and redundancy of each preset are those the papers state."""
    mech = preset(name)
    assert (mech.mobility, mech.redundancy) == EXPECTED[name]
    assert (PRESETS[name].dof, PRESETS[name].redundancy) == EXPECTED[name]
    assert mech.n_actuators == PRESETS[name].actuators


@pytest.mark.parametrize("name", preset_names())
def test_reference_configuration_closes_the_loops(name):
    """Every preset's reference configuration closes its loops to 1e-12."""
    mech = preset(name)
    assert np.max(np.abs(mech.closure_residual(mech.q_ref)), initial=0.0) <= 1e-12
    assert not mech.q_ref.flags.writeable


def _plate_pose(mech, q):
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    M = data.oMf[mech.model.getFrameId("plate_center")]
    return np.array([M.translation[0], M.translation[1], math.atan2(M.rotation[1, 0], M.rotation[0, 0])])


@pytest.mark.parametrize("pose", [(0.0, 0.08, -0.35), (0.03, 0.1, 0.2), (-0.05, 0.06, 0.5)])
def test_assembly_with_fixed_sliders_reaches_the_paper_pose(pose):
    """Fixing the 3D4M sliders at eq. (2)'s values and assembling yields the commanded plate pose."""
    mech = preset("harada2011_3d4m")
    c = paper.slider_positions(pose, 0.140, 0.05, (1, 2, 3, 4))  # the signs of (M.5)
    fixed = {f"slider{i + 1}": c[i] for i in range(4)}
    start = pin.integrate(mech.model, mech.q_ref, np.full(mech.nv, 0.01))
    asm = mech.assemble(start, fixed=fixed)
    assert asm.residual_norm <= 1e-12
    np.testing.assert_allclose(mech.actuator_positions(asm.q), c, atol=0.0)
    np.testing.assert_allclose(_plate_pose(mech, asm.q), pose, atol=1e-10)


def test_assembly_keeps_named_joints_where_they_are(rng):
    """Joints named in ``fixed`` keep their guessed values while the loops close."""
    mech = preset("fourbar")
    q = mech.q_ref.copy()
    q[0] += 0.2
    asm = mech.assemble(q, fixed=["crank_pivot"])
    assert asm.q[0] == q[0]
    assert asm.residual_norm <= 1e-12


def test_assembly_failure_is_typed_and_names_the_closure():
    """Actuators that pull the loop apart raise ClosureNotSatisfied naming the worst closure."""
    mech = preset("harada2011_3d4m")
    fixed = {"slider1": -0.5, "slider2": 0.5}
    with pytest.raises(plm_pin.ClosureNotSatisfied, match=r"cannot close the loops.*rod2_plate_left") as info:
        mech.assemble(fixed=fixed)
    assert info.value.worst_closure == "rod2_plate_left"
    assert info.value.residual_norm > 0.1


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        (np.zeros(3), r"guess must have shape \(9,\), got \(3,\)"),
        (np.full(9, np.nan), r"guess has non-finite entries at indices \[0, 1"),
        (np.zeros((9, 1)), r"must have shape \(9,\)"),
    ],
)
def test_bad_configurations_are_refused(bad, message):
    """Wrong-shaped or non-finite configurations raise InvalidInput with a clear message."""
    mech = preset("harada2011_3d4m")
    with pytest.raises(plm_pin.InvalidInput, match=message):
        mech.assemble(bad)
    with pytest.raises(plm_pin.InvalidInput, match=message.replace("guess", "q")):
        mech.closure_residual(bad)


def test_fixing_an_unknown_joint_lists_the_joints():
    """Fixing a joint that does not exist names it and lists the valid joints."""
    mech = preset("fourbar")
    with pytest.raises(plm_pin.InvalidInput, match=r"no joint 'elbow'; joints are \['crank_pivot'"):
        mech.assemble(fixed={"elbow": 0.1})
    with pytest.raises(plm_pin.InvalidInput, match=r"cannot fix joint 'elbow'"):
        mech.assemble(fixed=["elbow"])


def test_summary_reports_sizes_and_closures():
    """The summary lists sizes, closures with their rows, actuators and the task."""
    s = preset("harada2011_3d3m").summary()
    assert (s["nq"], s["nv"], s["closure_rows"]) == (7, 7, 6)
    assert [c["type"] for c in s["closures"]] == ["point", "point"]
    assert [a["joint"] for a in s["actuators"]] == ["slider1", "slider2", "slider4"]
    assert s["task"] == {"frame": "plate_center", "dofs": ["x", "y", "rz"]}


def test_erd_arm_loads_as_an_open_chain():
    """example-robot-data's UR5 loads with no closures, 6 DOF, 6 actuators and no redundancy."""
    mech = plm_pin.load("erd:ur5")
    assert mech.closures == ()
    assert (mech.mobility, mech.redundancy, mech.n_actuators) == (6, 0, 6)
    assert mech.task is not None and len(mech.task.dofs) == 6


def test_unknown_erd_robot_lists_the_choices():
    """An unknown example-robot-data name lists the available robots."""
    with pytest.raises(
        plm_pin.DescriptionError, match=r"unknown example-robot-data robot 'ur55'; available are \[.*'ur5'"
    ):
        plm_pin.load("erd:ur55")


def test_drive_inertia_is_reflected_into_the_armature(tmp_path):
    """A ball-screw drive adds (J_rotor + J_screw) (2 pi / lead)^2 to its joint's armature."""
    import shutil

    for suffix in (".urdf", ".plm.yaml"):
        shutil.copy(Path(plm_pin.models.urdf_folder()) / f"fourbar{suffix}", tmp_path / f"fourbar{suffix}")
    sidecar = tmp_path / "fourbar.plm.yaml"
    data = yaml.safe_load(sidecar.read_text())
    data["actuation"][0].update(lead=0.05, rotor_inertia=2.0e-5, screw_inertia=1.0e-5)
    sidecar.write_text(yaml.safe_dump(data))
    mech = plm_pin.load(tmp_path / "fourbar.urdf")
    # hand value: 3e-5 kg m^2 * (2 pi / 0.05 m)^2 = 3e-5 * 15791.367... = 0.473741...
    expected = 3.0e-5 * (2 * math.pi / 0.05) ** 2
    assert expected == pytest.approx(0.4737410112522892, rel=1e-15)
    assert mech.model.armature[mech.actuators[0].idx_v] == pytest.approx(expected, rel=1e-15)
    assert mech.actuators[0].reflected_inertia == pytest.approx(expected, rel=1e-15)


def test_non_numeric_configuration_is_refused():
    """A configuration holding text is refused with InvalidInput, not numpy's ValueError."""
    mech = preset("fourbar")
    with pytest.raises(plm_pin.InvalidInput, match=r"q must be 3 numbers"):
        mech.closure_residual(["a", "b", "c"])


def test_actuator_positions_of_stacked_configurations(rng):
    """A (2, 2, nq) stack gives each configuration's actuators; a NaN configuration gives NaN."""
    mech = preset("fivebar")
    qs = np.stack(
        [pin.integrate(mech.model, mech.q_ref, rng.normal(scale=0.1, size=mech.nv)) for _ in range(4)]
    )
    qs[3] = np.nan
    out = mech.actuator_positions(qs.reshape(2, 2, mech.nq))
    assert out.shape == (2, 2, mech.n_actuators)
    for k in range(3):
        np.testing.assert_array_equal(out.reshape(4, -1)[k], qs[k, mech.actuated_q_indices])
    assert np.all(np.isnan(out[1, 1]))
    with pytest.raises(
        plm_pin.InvalidInput, match=r"^q must stack configurations of size \d+, got shape \(2, 1\)$"
    ):
        mech.actuator_positions(np.zeros((2, 1)))


def test_closure_errors_are_the_gap_between_the_closure_frames():
    """closure_errors gives each closure's largest coordinate gap, here from planar four-bar geometry."""
    mech = preset("fourbar")
    q = np.array([0.3, -0.2, 1.9])  # crank, coupler (relative), rocker angles [rad]: loop open
    crank, coupler, rocker, ground = 0.10, 0.25, 0.20, 0.30
    tip_coupler = crank * np.array([math.cos(q[0]), math.sin(q[0])]) + coupler * np.array(
        [math.cos(q[0] + q[1]), math.sin(q[0] + q[1])]
    )
    tip_rocker = np.array([ground, 0.0]) + rocker * np.array([math.cos(q[2]), math.sin(q[2])])
    expected = float(np.max(np.abs(tip_rocker - tip_coupler)))
    assert mech.closure_errors(q) == {"coupler_rocker": pytest.approx(expected, abs=1e-15)}


def test_frame_names_hold_the_urdf_links_and_joints():
    """frame_names lists the URDF's links and joints, the sidecar's closure frames among them."""
    names = preset("harada2011_3d4m").frame_names
    for name in ("base", "plate", "plate_center", "rod2_tip", "slider1", "rod1_pivot", "plate_pivot"):
        assert name in names


def test_body_names_are_the_urdf_links_each_joint_carries():
    """body_names: the child link of every URDF joint, in Pinocchio's joint order (the root excluded)."""
    import yourdfpy

    from plm_pin.models import urdf_folder

    mech = preset("zhao2011_8pss")
    urdf = yourdfpy.URDF.load(str(urdf_folder() / "zhao2011_8pss.urdf"), load_meshes=False)
    child = {j.name: j.child for j in urdf.robot.joints}
    assert mech.body_names == tuple(child[name] for name in mech.joint_names)


@pytest.mark.parametrize("dumps", ["pickle", "cloudpickle"])
def test_mechanism_pickles_and_the_copy_computes_the_same(dumps):
    """A pickled Mechanism (pickle, cloudpickle) solves IK and finds mobility and legs like the original."""
    import pickle

    from plm_pin.kinematics import inverse_kinematics, task_pose

    mech = preset("harada2011_3d4m")
    blob = (pickle if dumps == "pickle" else pytest.importorskip("cloudpickle")).dumps(mech)
    copy = pickle.loads(blob)
    x = task_pose(mech, mech.q_ref) + 1e-3
    assert np.array_equal(copy.q_ref, mech.q_ref)
    assert (copy.mobility, copy.legs) == (mech.mobility, mech.legs)
    assert np.array_equal(inverse_kinematics(copy, x).q, inverse_kinematics(mech, x).q)
    assert len(copy.visual_model.geometryObjects) == len(mech.visual_model.geometryObjects) > 0


def test_cached_properties_leave_the_users_scratch_data_alone():
    """Computing mobility and q_ref (they assemble) does not overwrite what the user put in mech.data."""
    mech = plm_pin.load("fivebar")
    q = mech.reference_guess()
    pin.framesForwardKinematics(mech.model, mech.data, q)
    before = [M.translation.copy() for M in mech.data.oMf]
    assert mech.mobility == 2
    mech.closure_jacobian(mech.q_ref)
    assert all(np.array_equal(M.translation, b) for M, b in zip(mech.data.oMf, before, strict=True))


def test_threads_share_a_mechanism_and_get_the_serial_results():
    """Inverse kinematics from 4 threads on one Mechanism equals the serial results (per-thread scratch)."""
    from concurrent.futures import ThreadPoolExecutor

    from plm_pin.kinematics import inverse_kinematics, task_pose

    mech = preset("harada2011_3d4m")
    x0 = task_pose(mech, mech.q_ref)
    targets = [x0 + np.array([0.002 * k, -0.001 * k, 0.01 * k]) for k in range(-6, 6)]
    serial = [inverse_kinematics(mech, x).q for x in targets]
    with ThreadPoolExecutor(4) as pool:
        threaded = list(pool.map(lambda x: inverse_kinematics(mech, x).q, targets * 4))
    assert all(np.array_equal(a, b) for a, b in zip(threaded, serial * 4, strict=True))


def test_workspace_holds_buffers_of_the_stacked_newton_system():
    """mech.workspace() gives fresh data and [closure; task] buffers of the right shapes, not shared."""
    mech = preset("harada2011_3d4m")
    ws, other = mech.workspace(), mech.workspace()
    m, k = mech.n_closure_rows, mech.task_compiled.size
    assert ws.residual.shape == (m + k,) and ws.jacobian.shape == (m + k, mech.nv)
    assert ws.closure_rows[1].shape == (m, mech.nv) and ws.task_rows[0].shape == (k,)
    assert ws.data is not other.data and ws.data is not mech.data


@pytest.mark.slow
def test_mechanism_is_shipped_to_dask_workers_as_it_is():
    """On a 2-worker LocalCluster, a Mechanism sent as an argument solves IK like in this process."""
    from plm_pin.kinematics import inverse_kinematics, task_pose
    from plm_pin.sweep.execution import local_cluster

    mech = preset("harada2011_3d4m")
    x = task_pose(mech, mech.q_ref) + 1e-3
    with local_cluster(2, None) as client:
        remote = client.scatter(mech, broadcast=True)
        futures = [client.submit(inverse_kinematics, remote, x + 1e-4 * k, pure=False) for k in range(4)]
        results = client.gather(futures)
    for k, sol in enumerate(results):
        assert np.array_equal(sol.q, inverse_kinematics(mech, x + 1e-4 * k).q)
