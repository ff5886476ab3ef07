"""PlaCo's closed-loop IK and FK on a planar 2-PRRRP table, run by :mod:`benchmarks.harness` in PlaCo's venv.

PlaCo (pip ``placo``) pins an older Pinocchio than plm_pin, so this script imports neither
plm_pin nor anything but numpy and placo; :func:`benchmarks.harness.placo_benchmark` runs it
with ``.venv-placo/bin/python`` and reads one JSON line. The loops are hard
``RelativePositionTask`` s masked to the plane; IK adds hard planar position and yaw tasks on
the end-effector frame, FK a hard joints task on the sliders. Each solve starts from the
reference configuration and takes the number of QP steps that brings every task to 1e-12.

Usage: ``python placo_ik_fk.py '<json>'`` with keys ``urdf``, ``q_ref`` (joint -> value),
``closures`` (frame pairs), ``frame``, ``x`` (x, y, theta) and ``actuators`` (joint -> value).
"""

from __future__ import annotations

import json
import sys
import timeit
from collections.abc import Callable
from importlib import metadata
from typing import Any

import numpy as np


def _solver(robot: Any, closures: list[list[str]]) -> Any:
    import placo  # only in PlaCo's venv: importing this module elsewhere must work

    solver = placo.KinematicsSolver(robot)
    solver.mask_fbase(True)
    solver.enable_joint_limits(False)
    for a, b in closures:
        task = solver.add_relative_position_task(a, b, np.zeros(3))
        task.configure(f"{a}-{b}", "hard", 1.0)
        task.mask.set_axises("xy")
    return solver


def _gap(robot: Any, closures: list[list[str]]) -> float:
    return max(
        float(np.abs(robot.get_T_world_frame(b)[:2, 3] - robot.get_T_world_frame(a)[:2, 3]).max())
        for a, b in closures
    )


def _steps_and_time(reset: Callable[[], None], step: Callable[[], None], error: Callable[[], float]) -> dict:
    reset()
    steps = 0
    while error() > 1e-12 and steps < 50:
        step()
        steps += 1

    def run() -> None:
        reset()
        for _ in range(steps):
            step()

    timer = timeit.Timer(run)
    number = max(1, timer.autorange()[0] // 2)
    return {"steps": steps, "seconds": min(timer.repeat(7, number)) / number, "error": error()}


def main() -> None:
    """Read the JSON argument, time IK and FK, print one JSON line."""
    import placo

    cfg = json.loads(sys.argv[1])
    robot = placo.RobotWrapper(cfg["urdf"], placo.Flags.ignore_collisions)
    closures = cfg["closures"]

    def reset() -> None:
        for joint, value in cfg["q_ref"].items():
            robot.set_joint(joint, value)
        robot.update_kinematics()

    def joints() -> dict[str, float]:
        return {j: float(robot.get_joint(j)) for j in cfg["q_ref"]}

    x, y, th = cfg["x"]
    R = np.array([[np.cos(th), -np.sin(th), 0.0], [np.sin(th), np.cos(th), 0.0], [0.0, 0.0, 1.0]])
    ik = _solver(robot, closures)
    pos = ik.add_position_task(cfg["frame"], np.array([x, y, 0.0]))
    pos.configure("position", "hard", 1.0)
    pos.mask.set_axises("xy")
    ori = ik.add_orientation_task(cfg["frame"], R)
    ori.configure("yaw", "hard", 1.0)
    ori.mask.set_axises("z")

    def ik_step() -> None:
        ik.solve(True)
        robot.update_kinematics()

    def ik_error() -> float:
        T = robot.get_T_world_frame(cfg["frame"])
        yaw = float(np.arctan2(T[1, 0], T[0, 0]))
        return max(_gap(robot, closures), float(np.abs(T[:2, 3] - [x, y]).max()), abs(yaw - th))

    out: dict[str, Any] = {"placo": metadata.version("placo")}
    out["ik"] = _steps_and_time(reset, ik_step, ik_error)
    out["ik"]["q"] = joints()
    fk = _solver(robot, closures)
    task = fk.add_joints_task()
    task.set_joints(cfg["actuators"])
    task.configure("actuators", "hard", 1.0)

    def fk_step() -> None:
        fk.solve(True)
        robot.update_kinematics()

    def fk_error() -> float:
        return max(
            _gap(robot, closures), max(abs(robot.get_joint(j) - v) for j, v in cfg["actuators"].items())
        )

    out["fk"] = _steps_and_time(reset, fk_step, fk_error)
    out["fk"]["q"] = joints()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
