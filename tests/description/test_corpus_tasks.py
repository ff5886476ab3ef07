"""The example-parallel-robots corpus analysable: tasks from robot.yaml or the corpus table.

Every corpus robot with an obvious end effector (the five-bars and the planar delta) loads
straight from its folder with a task (plm_pin.description.interop.CORPUS_TASKS); its IK and
FK agree, J_ce equals finite differences of the IK, the static motor torques under gravity
equal finite differences of the potential energy along the motion (virtual work:
f . dc = dU), and its overview report is written to a folder named after it.
"""

from __future__ import annotations

import shutil
import warnings

import numpy as np
import pinocchio as pin
import pytest
import yaml

from plm_pin import kinematics as kin
from plm_pin.core.mechanism import Mechanism
from plm_pin.description.interop import CORPUS_TASKS
from plm_pin.exceptions import DescriptionError
from plm_pin.report import find_study, run_study
from plm_pin.statics import static_forces
from tests.conftest import INTEROP, load_corpus

if not INTEROP.is_dir():
    pytest.skip(f"example-parallel-robots corpus absent ({INTEROP})", allow_module_level=True)

EPS = 1e-6


@pytest.fixture(scope="module")
def robots() -> dict[str, Mechanism]:
    """The corpus robots with a task, loaded from their folders."""
    return {folder: load_corpus(INTEROP / folder) for folder in CORPUS_TASKS}


@pytest.mark.parametrize("folder", list(CORPUS_TASKS))
def test_corpus_robot_has_its_task_and_folder_name(robots, folder):
    """Loaded from its folder, a corpus robot carries its table task and is named after the folder."""
    mech = robots[folder]
    assert mech.task == CORPUS_TASKS[folder]
    assert mech.name == folder
    assert mech.mobility == len(mech.task.dofs) == mech.n_actuators


@pytest.mark.parametrize("folder", list(CORPUS_TASKS))
def test_corpus_ik_fk_jacobian_and_statics(robots, folder):
    """IK -> FK round trip, J_ce against IK finite differences, statics against potential energy."""
    mech = robots[folder]
    x = kin.task_pose(mech, mech.q_ref) + 0.002
    sol = kin.inverse_kinematics(mech, x)
    assert sol.residual_norm <= 1e-12
    found = kin.forward_kinematics(mech, sol.actuators)
    assert any(kin.same_assembly(mech, s.q, sol.q) for s in found)
    J_ce = kin.closed_chain_jacobians(mech, sol.q).J_ce
    data = mech.model.createData()
    dU, dc = [], []
    for k in range(len(x)):
        dx = np.zeros(len(x))
        dx[k] = EPS
        plus, minus = kin.inverse_kinematics(mech, x + dx, sol.q), kin.inverse_kinematics(mech, x - dx, sol.q)
        np.testing.assert_allclose(
            J_ce[:, k], (plus.actuators - minus.actuators) / (2 * EPS), rtol=1e-6, atol=1e-7
        )
        dU.append(
            pin.computePotentialEnergy(mech.model, data, plus.q)
            - pin.computePotentialEnergy(mech.model, data, minus.q)
        )
        dc.append(plus.actuators - minus.actuators)
    f = static_forces(mech, sol.q).f_c
    np.testing.assert_allclose(np.array(dc) @ f, dU, rtol=1e-6, atol=1e-9 * np.max(np.abs(f)))


def test_end_effector_in_robot_yaml_is_read_and_unknown_keys_refused(tmp_path):
    """An end_effector added to robot.yaml gives the task; a misspelt key is refused naming the valid ones."""
    folder = tmp_path / "my_fivebar"
    shutil.copytree(INTEROP / "5bar_linkage_iso3d", folder)
    raw = yaml.safe_load((folder / "robot.yaml").read_text())
    (folder / "robot.yaml").write_text(
        yaml.safe_dump({**raw, "end_effector": {"frame": "part_4", "task": ["x", "z"]}})
    )
    mech = load_corpus(folder)
    assert (mech.name, mech.task.frame, mech.task.dofs) == ("my_fivebar", "part_4", ("x", "z"))
    (folder / "robot.yaml").write_text(yaml.safe_dump({**raw, "end_efector": {"frame": "part_4"}}))
    with pytest.raises(DescriptionError) as info:
        load_corpus(folder)
    assert str(info.value) == (
        f"{folder / 'robot.yaml'}: robot.yaml: unknown key(s) ['end_efector']; valid keys are "
        "['closed_loop', 'type', 'name_mot', 'end_effector']"
    )


def test_robot_urdf_with_its_own_sidecar_is_named_after_the_folder(tmp_path):
    """robot.urdf + robot.plm.yaml (the other route) is named after its folder, not 'robot'."""
    folder = tmp_path / "delta_copy"
    shutil.copytree(INTEROP / "robot_delta", folder)
    sidecar = {
        "format": "plm-pin/1",
        "closures": [{"name": "c1", "frames": ["closedloop1_A", "closedloop1_B"], "type": "weld"}],
        "actuation": [{"joint": "mot1_rod1"}],
    }
    (folder / "robot.plm.yaml").write_text(yaml.safe_dump(sidecar))
    assert load_corpus(folder / "robot.urdf").name == "delta_copy"


@pytest.mark.slow
def test_corpus_overview_reports_do_not_collide(tmp_path):
    """The overview of two corpus robots is written to two folders named after them."""
    folders = set()
    for name in ("5bar_linkage_iso3d", "robot_delta"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = run_study(find_study("overview"), INTEROP / name)
        folders.add(result.folder)
        assert result.folder == f"overview-{name}"
    assert len(folders) == 2
