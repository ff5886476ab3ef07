"""Kinematics of the example-parallel-robots five-bars and delta with a plm-pin task.

Their ``robot.yaml`` names closures and motors but no task, so each folder is copied and given
a plm-pin sidecar ``robot.plm.yaml`` with the same closures (3d -> point, 6d -> weld), the same
motors and an end-effector frame of the URDF with a planar task in the plane the robot moves in
(all its revolute axes are normal to that plane):

- ``5bar_linkage_iso3d``: axes along world y, task [x, z] of frame ``effector``; mobility 2.
- ``5bar_linkage``: axes along world x, task [y, z] of frame ``effector``; mobility 3.
- ``robot_delta``: axes along world x, task [y, z] of frame ``eff``; mobility 5.

Idle freedoms. A ``6d`` (weld) closure joins two bodies that each hang on a revolute coaxial
with the cut joint (``closedloop<k>_A`` and ``closedloop<k>_B``), so those two revolutes turn
together, in series, about one axis: the two small closure bodies (the ``sphere`` links) spin
about the cut joint's axis while every other body stays still. That motion keeps the loops
closed and moves neither the motors nor any link that matters: one idle DOF per weld, which
plm_pin detects and fixes by holding one half-joint of each pair (:mod:`plm_pin.core.idle`).
So ``5bar_linkage`` has mobility 2 with 1 idle (one weld) and ``robot_delta`` 2 with 3 idle
(three welds); the ``point`` closure of ``5bar_linkage_iso3d`` leaves no idle DOF (its
out-of-plane ``freeortho`` revolute is held by the closure's normal row). Tested here: the idle
count against the cut closures alone, IK, FK (the motors now determine the configuration), FK
against a second sidecar that drives one half-joint per weld instead, and J_ce, S against
finite differences of the IK.
"""

from __future__ import annotations

import shutil

import numpy as np
import pinocchio as pin
import pytest
import yaml

from plm_pin.core.closures import compile_closures
from plm_pin.core.closures import jacobian as closure_jacobian
from plm_pin.core.mechanism import Mechanism
from plm_pin.kinematics import (
    closed_chain_jacobians,
    forward_kinematics,
    inverse_kinematics,
    same_assembly,
    task_pose,
)
from tests.conftest import INTEROP, fd_jacobian, load_corpus

if not INTEROP.is_dir():
    pytest.skip(f"example-parallel-robots corpus absent ({INTEROP})", allow_module_level=True)

# folder -> (end-effector frame, planar task, normal of the plane of motion, idle half-joints by weld)
ROBOTS = {
    "5bar_linkage_iso3d": ("effector", ["x", "z"], 1, []),
    "5bar_linkage": ("effector", ["y", "z"], 0, [("closedloop1_A", "closedloop1_B")]),
    "robot_delta": (
        "eff",
        ["y", "z"],
        0,
        [
            ("closedloop1_A", "closedloop1_B"),
            ("closedloop2_A", "closedloop2_B"),
            ("closedloop3_A", "closedloop3_B"),
        ],
    ),
}
EPS = 1e-6


def _sidecar(folder: str, extra_driven: list[str]) -> dict:
    robot = yaml.safe_load((INTEROP / folder / "robot.yaml").read_text())
    frame, task, _, _ = ROBOTS[folder]
    closures = [
        {"name": f"loop{k + 1}", "frames": list(pair), "type": {"3d": "point", "6d": "weld"}[kind]}
        for k, (pair, kind) in enumerate(zip(robot["closed_loop"], robot["type"], strict=True))
    ]
    return {
        "format": "plm-pin/1",
        "closures": closures,
        "actuation": [{"joint": j} for j in [*robot["name_mot"], *extra_driven]],
        "end_effector": {"frame": frame, "task": task},
    }


@pytest.fixture(scope="module")
def robots(tmp_path_factory) -> dict[str, tuple[Mechanism, Mechanism]]:
    """Each robot with its motors, and the same robot with one half-joint per weld also driven."""
    out = {}
    for folder, (_, _, _, welds) in ROBOTS.items():
        dest = tmp_path_factory.mktemp(folder) / folder
        shutil.copytree(INTEROP / folder, dest)
        (dest / "robot.plm.yaml").write_text(yaml.safe_dump(_sidecar(folder, [])))
        shutil.copy(dest / "robot.urdf", dest / "locked.urdf")
        (dest / "locked.plm.yaml").write_text(yaml.safe_dump(_sidecar(folder, [a for a, _ in welds])))
        out[folder] = (load_corpus(dest / "robot.urdf"), load_corpus(dest / "locked.urdf"))
    return out


def _poses(mech: Mechanism) -> list[np.ndarray]:
    x0 = task_pose(mech, mech.q_ref)
    return [x0 + d for d in ([0.0, 0.0], [0.004, -0.003], [-0.003, -0.004], [0.002, 0.004])]


@pytest.mark.parametrize("folder", list(ROBOTS))
def test_mobility_is_the_motors_with_one_idle_spin_per_weld(robots, folder):
    """Mobility 2 plus one idle DOF per weld: the weld's two coaxial half-joints turning together."""
    mech, _ = robots[folder]
    _, _, _, welds = ROBOTS[folder]
    assert mech.n_actuators == 2
    assert (mech.mobility, mech.idle_mobility) == (2, len(welds))
    assert len(mech.closures) == len(mech.sidecar.closures) + len(welds)
    cut = compile_closures(mech.model, mech.sidecar.closures)  # the loops alone, no gauge
    J_cut = closure_jacobian(mech.model, mech.model.createData(), cut, mech.q_ref)
    S_a = np.eye(mech.nv)[mech.actuated_v_indices]
    s = np.linalg.svd(np.vstack([J_cut, S_a]), compute_uv=False)
    assert mech.nv - int(np.sum(s > 1e-9 * s[0])) == len(welds)  # motions with the motors locked
    jac = closed_chain_jacobians(mech, mech.q_ref)
    held = {g.joint for g in mech.idle_gauges}
    for a, b in welds:
        assert len(held & {a, b}) == 1  # one half-joint of each pair is held
        cols = [mech.model.joints[mech.model.getJointId(j)].idx_v for j in (a, b)]
        sub = np.vstack([J_cut, jac.J_x, S_a])[:, cols]  # the pair alone: loops, task, motors
        s = np.linalg.svd(sub, compute_uv=False)
        assert s[1] <= 1e-12 * s[0]  # a combination of the two moves nothing else


@pytest.mark.parametrize("folder", list(ROBOTS))
def test_closure_and_task_jacobians_match_finite_differences(robots, folder, rng):
    """J_phi and the task Jacobian of the three robots equal finite differences."""
    mech, _ = robots[folder]
    q = pin.integrate(mech.model, mech.q_ref, rng.normal(scale=0.2, size=mech.nv))
    np.testing.assert_allclose(
        mech.closure_jacobian(q), fd_jacobian(mech.closure_residual, mech.model, q), atol=1e-8
    )
    q = mech.assemble(q).q  # closed_chain_jacobians refuses open loops
    jac = closed_chain_jacobians(mech, q)
    np.testing.assert_allclose(jac.J_x, fd_jacobian(lambda qq: task_pose(mech, qq), mech.model, q), atol=1e-8)


@pytest.mark.parametrize("folder", list(ROBOTS))
def test_ik_closes_and_keeps_the_plane(robots, folder):
    """IK reaches poses around the reference to 1e-12, and the task frame stays in its plane of motion."""
    mech, _ = robots[folder]
    normal = ROBOTS[folder][2]
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.q_ref)
    height = data.oMf[mech.task_frame_id].translation[normal]
    for x in _poses(mech):
        sol = inverse_kinematics(mech, x)
        assert sol.residual_norm <= 1e-12
        np.testing.assert_allclose(task_pose(mech, sol.q), x, atol=1e-12)
        pin.framesForwardKinematics(mech.model, data, sol.q)
        assert data.oMf[mech.task_frame_id].translation[normal] == pytest.approx(height, abs=1e-12)


def test_delta_keeps_its_effector_orientation(robots):
    """The delta's parallelogram keeps the effector's orientation: the same rotation at every IK pose."""
    mech, _ = robots["robot_delta"]
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, mech.q_ref)
    R0 = data.oMf[mech.task_frame_id].rotation.copy()
    for x in _poses(mech):
        pin.framesForwardKinematics(mech.model, data, inverse_kinematics(mech, x).q)
        np.testing.assert_allclose(data.oMf[mech.task_frame_id].rotation, R0, atol=1e-12)


@pytest.mark.parametrize("folder", list(ROBOTS))
def test_ik_fk_round_trip(robots, folder):
    """One FK assembly of the IK's motor angles is the IK pose and the same assembly (idle DOF held)."""
    mech, _ = robots[folder]
    for x in _poses(mech):
        ik = inverse_kinematics(mech, x)
        found = forward_kinematics(mech, ik.actuators)
        errors = [float(np.max(np.abs(s.x - x))) for s in found]
        assert min(errors) <= 1e-12
        assert same_assembly(mech, found[int(np.argmin(errors))].q, ik.q)


@pytest.mark.parametrize("folder", ["5bar_linkage", "robot_delta"])
def test_ik_fk_round_trip_with_idle_joints_fixed(robots, folder):
    """IK, then FK with the motors and one half-joint per weld driven: one assembly is the IK pose and q."""
    mech, locked = robots[folder]
    assert (locked.mobility, locked.idle_mobility) == (locked.n_actuators, 0)
    for x in _poses(mech):
        ik = inverse_kinematics(mech, x)
        found = forward_kinematics(locked, locked.actuator_positions(ik.q))
        errors = [float(np.max(np.abs(s.x - x))) for s in found]
        assert min(errors) <= 1e-12
        assert same_assembly(locked, found[int(np.argmin(errors))].q, ik.q)


@pytest.mark.parametrize("folder", list(ROBOTS))
def test_actuator_and_velocity_maps_match_finite_differences(robots, folder):
    """J_ce and S (idle DOF held) equal finite differences of the IK re-solved from the same solution."""
    mech, _ = robots[folder]
    for x in _poses(mech)[:2]:
        q = inverse_kinematics(mech, x).q
        jac = closed_chain_jacobians(mech, q)
        J_ce, S = jac.J_ce, jac.S
        np.testing.assert_allclose(J_ce, jac.C @ np.linalg.pinv(jac.T), atol=1e-12)
        for k in range(len(x)):
            dx = np.zeros(len(x))
            dx[k] = EPS
            plus, minus = inverse_kinematics(mech, x + dx, q), inverse_kinematics(mech, x - dx, q)
            np.testing.assert_allclose(J_ce[:, k], (plus.actuators - minus.actuators) / (2 * EPS), atol=1e-7)
            np.testing.assert_allclose(
                S[:, k], pin.difference(mech.model, minus.q, plus.q) / (2 * EPS), atol=1e-7
            )


def _circles(c1: np.ndarray, r1: float, c2: np.ndarray, r2: float) -> list[np.ndarray]:
    """The points at distance r1 from c1 and r2 from c2 in a plane (none, or two)."""
    d = float(np.linalg.norm(c2 - c1))
    along = (r1 * r1 - r2 * r2 + d * d) / (2 * d)
    if r1 * r1 < along * along:
        return []
    e = (c2 - c1) / d
    n = np.array([-e[1], e[0]])
    h = np.sqrt(r1 * r1 - along * along)
    return [c1 + along * e + s * h * n for s in (1.0, -1.0)]


def _turn(v: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _angle(v: np.ndarray) -> float:
    return float(np.arctan2(v[1], v[0]))


def _delta_modes(mech: Mechanism, q: np.ndarray) -> list[np.ndarray]:
    """Every assembly's effector point (y, z) at the motor angles of ``q``, by circle intersections.

    The robot is a five-bar (motor arms to elbows B1, B2, rods to the effector pivot P) with a
    transmission chain: a base link O3-T, a body T-K pinned at the elbow B2 (K) carrying the pivot
    F3, and a rod F3-Q to the effector. So P is where two circles meet (2 ways), T too (2 ways,
    which turns the body T-K and moves F3), and the effector's turn about P puts Q on the circle
    about F3 (2 ways): 8 assemblies. Lengths are read at the reference; the elbows are the motor
    arms' forward kinematics at ``q``.
    """
    data = mech.model.createData()

    def points(config: np.ndarray) -> dict[str, np.ndarray]:
        pin.framesForwardKinematics(mech.model, data, config)
        out = {
            name: data.oMi[mech.model.getJointId(joint)].translation[1:].copy()
            for name, joint in (
                ("O3", "free1_rod3"),
                ("T", "free2_rod3"),
                ("K", "closedloop1_A"),
                ("F3", "free3_rod3"),
                ("B1", "free1_rod1"),
                ("P", "free2_rod1"),
                ("B2", "free1_rod2"),
                ("Q", "closedloop3_A"),
            )
        }
        out["E"] = data.oMf[mech.task_frame_id].translation[1:].copy()
        return out

    ref, now = points(mech.q_ref), points(q)
    np.testing.assert_allclose(ref["K"], ref["B2"], atol=1e-12)  # the body T-K is pinned at the elbow

    def dist(a: str, b: str) -> float:
        return float(np.linalg.norm(ref[a] - ref[b]))

    found = []
    for P in _circles(now["B1"], dist("P", "B1"), now["B2"], dist("P", "B2")):
        for T in _circles(ref["O3"], dist("T", "O3"), now["B2"], dist("T", "K")):
            F3 = T + _turn(ref["F3"] - ref["T"], _angle(now["B2"] - T) - _angle(ref["K"] - ref["T"]))
            for Q in _circles(P, dist("Q", "P"), F3, dist("Q", "F3")):
                turn = _angle(Q - P) - _angle(ref["Q"] - ref["P"])
                found.append(P + _turn(ref["E"] - ref["P"], turn))
    return found


def test_delta_assembly_modes_by_homotopy_are_the_circle_intersections(robots):
    """Homotopy FK of the delta: the 2 x 2 x 2 circle intersections; complete and all certified at every pose.

    (Its generic solve is seeded by the reference assembly: the random start of the offset family
    loses every path on this robot. Two of its roots are ill-conditioned (condition number 1.6e5 at
    the second pose): the Krawczyk box sized from the Newton enclosure certifies them, as a fixed
    width did not.)
    """
    mech, _ = robots["robot_delta"]
    for x in _poses(mech):
        q = inverse_kinematics(mech, x).q
        modes = forward_kinematics(mech, mech.actuator_positions(q), all_modes=True)
        assert (modes.method, modes.generic_count) == ("homotopy", 16)
        assert (modes.complete, modes.certified) == (True, 8)
        expected = sorted(map(tuple, _delta_modes(mech, q)))
        assert len(expected) == 8
        np.testing.assert_allclose(sorted(tuple(s.x) for s in modes), expected, atol=1e-10)
