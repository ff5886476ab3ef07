"""Benchmarks: cost per call of the core paths, written as a Markdown table.

Run with ``make bench`` (or ``python -m benchmarks.harness --out reports/bench``); it lives
in the checkout, not in the installed package. A
benchmark measures; correctness is asserted by the test suite, never here. Besides the
cost per call of loading, closures, assembly, kinematics and manipulability for every
preset, it times the 3D4M's kinematics beside their Pinocchio floor (:class:`Floor`), on the compiled
kernels and on the Pinocchio path, with the kernels' first compile and cache load, and
PlaCo's (in its own venv), the force capability and internal-force range beside theirs
(:func:`capability_floor`, :func:`internal_range_floor`), records the wall time of a
10^5-pose manipulability map of ``harada2011_3d4m`` on one core beside Harada's vectorised
closed form and of an 8-PSS map, the cost and accuracy of closed-chain simulation (the
four-bar, 10 s passive, against MuJoCo's soft ``connect`` constraint on the same four-bar;
Harada 2011's simulation 1), the throughput of a design sweep (:mod:`plm_pin.sweep`) in one
process and on a 2-worker Dask LocalCluster and, as a reproduction note, the 3D3M's singular
angle of Harada 2011 Fig. 6.
"""

from __future__ import annotations

import argparse
import functools
import inspect
import json
import math
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
import timeit
from collections.abc import Callable
from pathlib import Path
from typing import Any

import highspy
import numpy as np
import pinocchio as pin
import proxsuite

# run from the source checkout (make bench): the Zhao 2011 trajectory is the study's, beside it
from analyses._zhao2011_paper import ZHAO2011_TRAJECTORY_DURATION, zhao2011_trajectory
from plm_pin.core.closures import jacobian_from_data as closure_jacobian_from_data
from plm_pin.core.mechanism import Mechanism
from plm_pin.core.task import FrameTask, TaskTarget
from plm_pin.dynamics.inverse_dynamics import inverse_dynamics
from plm_pin.dynamics.simulation import SimulationResult, simulate
from plm_pin.dynamics.trajectory import task_trajectory
from plm_pin.families.classic import build_fourbar
from plm_pin.kernels import SWITCH, kernel_of
from plm_pin.kinematics import (
    classify,
    closed_chain_jacobians,
    forward_kinematics,
    inverse_kinematics,
    task_pose,
)
from plm_pin.loading import build_mechanism, load
from plm_pin.models.registry import PRESETS, preset_names, urdf_folder
from plm_pin.statics import (
    AllocationRule,
    force_capability,
    internal_force_range,
    solve_balance,
    static_balance,
    static_forces,
)
from plm_pin.statics.allocation import new_highs
from plm_pin.statics.balance import wrench_on_frame
from plm_pin.workspace import WorkspaceSlice, manipulability, singular_points_along, workspace_map

MAP_SHAPE = (317, 316)
"""Grid of the manipulability-map benchmark: 100,172 poses."""

MAP_METRICS: tuple[tuple[str, tuple[str, ...] | None], ...] = (
    ("all five metrics", None),
    ("manipulability only", ("manipulability",)),
)
"""The metric selections the map benchmarks time (``workspace_map(metrics=...)``), with their labels."""

SIM_DURATION = 10.0
"""Simulated time of the four-bar comparison [s]."""

SIM_STEP = 1e-3
"""Integration step of the four-bar comparison, both engines [s]."""

SIM_OUTPUT = 1e-2
"""Output (sampling) step of the simulation benchmarks [s]."""

SIM_ROUNDS = 5
"""Alternating runs of plm_pin's default and MuJoCo RK4 whose best gives their cost ratio."""


def _sweep_case(mechanism: str, angles: int, span: float, metrics: list[str]) -> dict[str, Any]:
    """A sweep of 12 plate sizes x 20 heights x ``angles`` plate angles over +/-``span`` deg."""
    return {
        "mechanism": mechanism,
        "parameters": {"half_plate": np.linspace(0.02, 0.07, 12).tolist()},
        "poses": {
            "y": np.linspace(0.03, 0.12, 20).tolist(),
            "rz": np.radians(np.linspace(-span, span, angles)),
        },
        "metrics": metrics,
        "pose": [0.0, 0.08, 0.0],
    }


SWEEP_CASES: dict[str, dict[str, Any]] = {
    "w, singularity, min w (3D4M, 12 plate sizes x 20 heights x 101 angles)": _sweep_case(
        "harada2011_3d4m", 101, 60.0, ["manipulability", "singularity", "min_manipulability"]
    ),
    "orientation range (3D3M, 12 plate sizes x 20 heights x 81 angles)": _sweep_case(
        "harada2011_3d3m", 81, 80.0, ["orientation_range"]
    ),
    "orientation range, 3 points on 2 workers: the third split (3D3M, 3 plate sizes x 20 x 81)": {
        **_sweep_case("harada2011_3d3m", 81, 80.0, ["orientation_range"]),
        "parameters": {"half_plate": [0.03, 0.045, 0.06]},
    },
}
"""The design sweeps timed by :func:`sweep_benchmark` (arguments of :func:`plm_pin.sweep.make_spec`)."""


def _per_call(fn: Callable[[], object], min_time: float = 0.2) -> float:
    """Best-of-5 time per call [s], with the repeat count chosen to last ``min_time``."""
    timer = timeit.Timer(fn)
    number, _ = timer.autorange()
    number = max(1, int(number * min_time / 0.2))
    return min(timer.repeat(repeat=5, number=number)) / number


class Floor:
    r"""The least Python doing a kinematics path's math with Pinocchio calls (the floor of its cost).

    For mechanisms whose closures are all ``point`` and whose task is planar ``(x, y, rz)``
    (the 2-PRRRP tables): one ``computeJointJacobians`` + ``updateFramePlacements`` pass per
    Gauss-Newton iteration, residual from ``oMf``, Jacobian from ``getFrameJacobian``, a
    Cholesky step of the normal equations; the closed-chain Jacobians by one SVD of
    :math:`J_\phi`. No checks, no results objects, no working mode.
    """

    def __init__(self, mech: Mechanism) -> None:
        """Collect the frame pairs, task frame and actuated indices of ``mech``."""
        task = mech.task_compiled
        if (
            not isinstance(task, FrameTask)
            or task.dofs != ("x", "y", "rz")
            or any(c.spec.type != "point" for c in mech.closures)
        ):
            raise ValueError(f"{mech.name}: the floor is written for point closures and an x-y-rz task")
        self.model, self.data = mech.model, mech.model.createData()
        self.pairs = [c.frame_ids for c in mech.closures]
        self.frame = task.frame_id
        self.act_q, self.act_v = mech.actuated_q_indices, mech.actuated_v_indices
        self.free = np.setdiff1d(np.arange(mech.nv), self.act_v)
        self.mobility = mech.mobility

    def _closure(self) -> tuple[np.ndarray, np.ndarray]:
        oMf, lwa = self.data.oMf, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        model, data = self.model, self.data
        r = np.concatenate([oMf[b].translation - oMf[a].translation for a, b in self.pairs])
        J = np.vstack(
            [
                pin.getFrameJacobian(model, data, b, lwa)[:3] - pin.getFrameJacobian(model, data, a, lwa)[:3]
                for a, b in self.pairs
            ]
        )
        return r, J

    def ik(self, q0: np.ndarray, x: np.ndarray, tol: float = 1e-12) -> np.ndarray:
        """Gauss-Newton on closures and task from ``q0`` to ``tol``."""
        model, data, q = self.model, self.data, q0
        for _ in range(30):
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            r_phi, J_phi = self._closure()
            M = data.oMf[self.frame]
            R = M.rotation
            r = np.concatenate([r_phi, M.translation[:2] - x[:2], [math.atan2(R[1, 0], R[0, 0]) - x[2]]])
            if np.abs(r).max() <= tol:
                return q
            J_x = pin.getFrameJacobian(model, data, self.frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            J = np.vstack([J_phi, J_x[[0, 1, 5]]])
            q = pin.integrate(model, q, -np.linalg.solve(J.T @ J, J.T @ r))
        raise RuntimeError("floor IK did not converge")

    def fk(self, q0: np.ndarray, c: np.ndarray, tol: float = 1e-12) -> np.ndarray:
        """Gauss-Newton on the closures with the actuators at ``c``, from ``q0``."""
        model, data = self.model, self.data
        q = q0.copy()
        q[self.act_q] = c
        for _ in range(30):
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            r, J = self._closure()
            if np.abs(r).max() <= tol:
                return q
            Jf = J[:, self.free]
            step = np.zeros(model.nv)
            step[self.free] = -np.linalg.solve(Jf.T @ Jf, Jf.T @ r)
            q = pin.integrate(model, q, step)
        raise RuntimeError("floor FK did not converge")

    def jacobians(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """N, singular values of J_phi, T = J_x N, C = S_a N."""
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        _, J_phi = self._closure()
        J_x = pin.getFrameJacobian(self.model, self.data, self.frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        _, s, Vt = np.linalg.svd(J_phi)
        N = Vt[-self.mobility :].T
        return N, s, J_x[[0, 1, 5]] @ N, N[self.act_v]

    def manipulability(self, q: np.ndarray) -> tuple[float, float]:
        """W and the condition number of J_ce = C T^-1."""
        _, _, T, C = self.jacobians(q)
        sv = np.linalg.svd(np.linalg.solve(T.T, C.T).T, compute_uv=False)
        return float(sv.prod()), float(sv[0] / sv[-1])


def _paired(fn: Callable[[], object], floor: Callable[[], object], rounds: int = 7) -> tuple[float, float]:
    """Best time per call [s] of ``fn`` and of ``floor``, measured in alternation (same load on both)."""
    timers = [timeit.Timer(fn), timeit.Timer(floor)]
    numbers = [max(1, t.autorange()[0] // 2) for t in timers]
    best = [math.inf, math.inf]
    for _ in range(rounds):
        for k, (t, n) in enumerate(zip(timers, numbers, strict=True)):
            best[k] = min(best[k], t.timeit(n) / n)
    return best[0], best[1]


def kinematics_benchmark() -> list[dict[str, object]]:
    """The 3D4M's kinematics paths beside their floor (:class:`Floor`), timed in alternation."""
    mech = load("harada2011_3d4m")
    floor = Floor(mech)
    q = mech.q_ref
    x = task_pose(mech, q) + 1e-3
    c = mech.actuator_positions(inverse_kinematics(mech, x, q).q)  # a consistent set: the 3D4M is redundant
    cases: dict[str, tuple[Callable[[], object], Callable[[], object]]] = {
        "inverse_kinematics (from q_ref, 1e-3 m/rad off)": (
            functools.partial(inverse_kinematics, mech, x, q),
            functools.partial(floor.ik, q, x),
        ),
        "forward_kinematics, one mode (actuators of a pose 1e-3 m/rad off)": (
            functools.partial(forward_kinematics, mech, c, q, all_modes=False),
            functools.partial(floor.fk, q, c),
        ),
        "closed_chain_jacobians": (
            functools.partial(closed_chain_jacobians, mech, q),
            functools.partial(floor.jacobians, q),
        ),
        "manipulability": (
            functools.partial(manipulability, mech, q),
            functools.partial(floor.manipulability, q),
        ),
    }
    rows: list[dict[str, object]] = []
    for case, (fn, low) in cases.items():
        ours, least = _paired(fn, low)
        rows.append(
            {"mechanism": mech.name, "case": case, "seconds_per_call": ours, "floor_seconds_per_call": least}
        )
    return rows


KERNEL_FIRST_CALL = """
import sys, time
from plm_pin import load
from plm_pin.core.task import TaskTarget
from plm_pin.kernels import kernel_of
from plm_pin.kinematics import task_pose
mech = load("harada2011_3d4m")
target = TaskTarget(mech.task_compiled, task_pose(mech, mech.q_ref) + 1e-3)
start = time.perf_counter()
kernel_of(mech).newton(mech.q_ref, None, mech.closure_tol, target)
print(time.perf_counter() - start)
"""
"""Times the first kernel Newton of a fresh process: numba's import and the compile or the cache load."""


def kernel_benchmark() -> list[dict[str, object]]:
    """The compiled kernels on the 3D4M: IK and FK on both paths beside the floor, compile and load times.

    The kernel rows of :func:`kinematics_benchmark` are the public functions; here the same calls
    with ``PLM_PIN_KERNELS=0`` (the Pinocchio path) and the kernel Newton alone, each timed in
    alternation with :class:`Floor`. The first call of a fresh process is timed twice in a
    subprocess with an empty numba cache folder (the compile) and again with it filled (the load).
    """
    mech = load("harada2011_3d4m")
    floor = Floor(mech)
    q = mech.q_ref
    x = task_pose(mech, q) + 1e-3
    c = mech.actuator_positions(inverse_kinematics(mech, x, q).q)
    kernel, task = kernel_of(mech), mech.task_compiled
    assert kernel is not None and task is not None, "the kernels are off (PLM_PIN_KERNELS=0 or no numba)"
    target = TaskTarget(task, x)
    rows: list[dict[str, object]] = []

    def pinocchio_path(fn: Callable[[], object]) -> object:
        os.environ[SWITCH] = "0"
        try:
            return fn()
        finally:
            del os.environ[SWITCH]

    cases: dict[str, tuple[Callable[[], object], Callable[[], object]]] = {
        "kernel Newton alone (IK, from q_ref, 1e-3 m/rad off)": (
            functools.partial(kernel.newton, q, None, mech.closure_tol, target),
            functools.partial(floor.ik, q, x),
        ),
        "inverse_kinematics on the Pinocchio path (PLM_PIN_KERNELS=0)": (
            functools.partial(pinocchio_path, functools.partial(inverse_kinematics, mech, x, q)),
            functools.partial(floor.ik, q, x),
        ),
        "forward_kinematics, one mode, on the Pinocchio path (PLM_PIN_KERNELS=0)": (
            functools.partial(
                pinocchio_path, functools.partial(forward_kinematics, mech, c, q, all_modes=False)
            ),
            functools.partial(floor.fk, q, c),
        ),
    }
    for case, (fn, low) in cases.items():
        ours, least = _paired(fn, low)
        rows.append(
            {"mechanism": mech.name, "case": case, "seconds_per_call": ours, "floor_seconds_per_call": least}
        )
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        for case in (
            "kernels: first call of a process, compiling (empty cache)",
            "kernels: first call, from the disk cache",
        ):
            out = subprocess.run(
                [sys.executable, "-c", KERNEL_FIRST_CALL], env=env, capture_output=True, text=True, check=True
            )
            rows.append(
                {"mechanism": mech.name, "case": case, "seconds_per_call": float(out.stdout.split()[-1])}
            )
    return rows


PLACO_VENV = Path(os.environ.get("PLM_PIN_PLACO_VENV", ".venv-placo"))
"""Virtual environment of PlaCo (pip ``placo`` pins an older Pinocchio than plm_pin's): made on first use."""


def complete_fk_benchmark() -> list[dict[str, object]]:
    """Every assembly mode: certified homotopy beside 48-start multi-start.

    On a 3-RPR with 6 real modes and a general (irregular) 6-UPS Gough-Stewart platform (40 roots).
    The presets' rows (the 6-PUS and 8-PSS: 40 roots) are in :func:`run`.
    """
    import tempfile

    from tests.kinematics.homotopy.rpr import rpr_files  # the test suite's 3-RPR (URDF + sidecar)
    from tests.kinematics.homotopy.test_complete_fk import RPR_BASE, RPR_PLATE, RPR_RHO, _general_stewart

    rows: list[dict[str, object]] = []
    with tempfile.TemporaryDirectory() as folder:
        rpr = load(rpr_files(Path(folder), RPR_BASE, RPR_PLATE))
        stewart = _general_stewart(Path(folder))
        cases = (
            ("3-RPR (6 real modes)", rpr, RPR_RHO),
            ("general 6-UPS Gough-Stewart (40 roots)", stewart, stewart.actuator_positions(stewart.q_ref)),
        )
        for name, mech, c in cases:
            forward_kinematics(mech, c)  # the generic solve, once (cached on disk)
            for case, method in (("48 starts", "multi-start"), ("certified homotopy", "auto")):
                fn = functools.partial(forward_kinematics, mech, c, all_modes=True, method=method)
                rows.append(
                    {
                        "mechanism": name,
                        "case": f"forward_kinematics (all_modes=True, {case})",
                        "seconds_per_call": _per_call(fn),
                    }
                )
    return rows


def _placo_python() -> tuple[Path | None, str]:
    """PlaCo's interpreter, creating its venv when missing; or None and why not."""
    python = PLACO_VENV / "bin" / "python"
    if not python.exists():
        try:
            subprocess.run([sys.executable, "-m", "venv", str(PLACO_VENV)], check=True, capture_output=True)
            subprocess.run(
                [str(python), "-m", "pip", "install", "--quiet", "placo"],
                check=True,
                capture_output=True,
                timeout=900,
            )
        except (OSError, subprocess.SubprocessError) as exc:
            shutil.rmtree(PLACO_VENV, ignore_errors=True)
            return None, f"PlaCo could not be installed in {PLACO_VENV} ({type(exc).__name__}; offline?)"
    return python, ""


def placo_benchmark() -> tuple[list[dict[str, object]], str]:
    """PlaCo's IK and FK on the 3D4M from the same start and targets as :func:`kinematics_benchmark`.

    Runs :mod:`benchmarks.placo_ik_fk` in PlaCo's own venv (:data:`PLACO_VENV`, created with
    pip on first use). Returns its rows and a note (the agreement with plm_pin, or why PlaCo is absent).
    """
    python, why = _placo_python()
    if python is None:
        return [], why
    mech = load("harada2011_3d4m")
    q = mech.q_ref
    x = task_pose(mech, q) + 1e-3
    ik = inverse_kinematics(mech, x, q).q
    fk = forward_kinematics(mech, mech.actuator_positions(ik), q, all_modes=False)[0].q

    def by_joint(config: np.ndarray) -> dict[str, float]:
        return {n: float(config[mech.model.joints[mech.model.getJointId(n)].idx_q]) for n in mech.joint_names}

    cfg = {
        "urdf": str(urdf_folder() / "harada2011_3d4m.urdf"),
        "q_ref": by_joint(q),
        "closures": [list(c.spec.frames) for c in mech.closures],
        "frame": mech.task.frame if mech.task else "",
        "x": x.tolist(),
        # PlaCo's hard equalities must be independent: hold as many sliders as DOF (the 4th follows)
        "actuators": {a.joint: float(ik[a.idx_q]) for a in mech.actuators[: mech.mobility]},
    }
    script = Path(__file__).with_name("placo_ik_fk.py")
    try:
        done = subprocess.run(
            [str(python), str(script), json.dumps(cfg)],
            capture_output=True,
            text=True,
            check=True,
            timeout=600,
        )
        out = json.loads(done.stdout.strip().splitlines()[-1])
    except (OSError, subprocess.SubprocessError, ValueError, IndexError) as exc:
        return [], f"PlaCo run failed: {type(exc).__name__}: {str(exc)[:200]}"
    rows: list[dict[str, object]] = []
    agree = []
    for key, ours in (("ik", ik), ("fk", fk)):
        r = out[key]
        diff = max(abs(r["q"][n] - v) for n, v in by_joint(ours).items())
        agree.append(f"{key.upper()} {diff:.1e}")
        rows.append(
            {
                "mechanism": mech.name,
                "case": f"PlaCo {out['placo']} {key.upper()} ({r['steps']} QP steps to 1e-12, "
                "hard planar loop-closure tasks)",
                "seconds_per_call": float(r["seconds"]),
            }
        )
    return (
        rows,
        f"PlaCo agrees with plm_pin's configurations to {', '.join(agree)} rad/m (max joint difference).",
    )


def harada_closed_form_map(poses: np.ndarray, l: float, rt: float, signs: tuple[int, ...]) -> np.ndarray:
    """Manipulability w of the 3D4M by Harada 2011 eqs. (2), (3), (12), (13), vectorised over poses.

    Args:
        poses: ``(x, y, theta)`` [m, m, rad], shape (n, 3).
        l: rod length [m] (all four equal).
        rt: half plate length [m].
        signs: sign of the square root of eq. (2) per leg (the paper's code (M.5)).

    Returns:
        w per pose [m/rad], shape (n,).
    """
    x, y, th = poses.T
    cos, sin = np.cos(th), np.sin(th)
    rows = []
    for i, sign in enumerate(signs):
        s = -rt if i < 2 else rt
        Lx, Ly = x + s * cos, y + s * sin
        c = Lx + sign * np.sqrt(l * l - Ly * Ly)
        zx, zy = (Lx - c) / l, Ly / l
        rows.append(np.stack([zx, zy, -zx * s * sin + zy * s * cos], axis=-1) / zx[:, None])
    J = np.stack(rows, axis=1)  # (n, 4, 3)
    return np.sqrt(np.linalg.det(np.swapaxes(J, 1, 2) @ J))


def run() -> list[dict[str, object]]:
    """Time loading, closures, assembly, kinematics and manipulability for every preset."""
    rows: list[dict[str, object]] = []
    for name in preset_names():
        mech = load(name)
        q = mech.q_ref
        guess = pin.integrate(mech.model, q, np.full(mech.nv, 1e-3))
        actuated = [a.joint for a in mech.actuators]
        x = task_pose(mech, q) + 1e-3
        c = mech.actuator_positions(q) + 1e-3
        cases: dict[str, Callable[[], object]] = {
            "load": functools.partial(load, name),
            "closure_residual": functools.partial(mech.closure_residual, q),
            "closure_jacobian": functools.partial(mech.closure_jacobian, q),
            "assemble (actuators fixed, 1e-3 rad/m off)": functools.partial(
                mech.assemble, guess, fixed=actuated
            ),
            "inverse_kinematics (from q_ref, 1e-3 m/rad off)": functools.partial(
                inverse_kinematics, mech, x, q
            ),
            "forward_kinematics (all_modes=False, 1e-3 off)": functools.partial(
                forward_kinematics, mech, c, q, all_modes=False
            ),
            "forward_kinematics (all_modes=True, 48 starts)": functools.partial(
                forward_kinematics, mech, c, q, all_modes=True, method="multi-start"
            ),
            "forward_kinematics (all_modes=True, certified homotopy)": functools.partial(
                forward_kinematics, mech, c, q, all_modes=True
            ),
            "closed_chain_jacobians": functools.partial(closed_chain_jacobians, mech, q),
            "manipulability": functools.partial(manipulability, mech, q),
            "classify": functools.partial(classify, mech, q),
            "static_forces (gravity, min-norm)": functools.partial(static_forces, mech, q),
        }
        for case, fn in cases.items():
            rows.append({"mechanism": name, "case": case, "seconds_per_call": _per_call(fn)})
    rows.extend(kinematics_benchmark())
    rows.extend(kernel_benchmark())
    rows.extend(complete_fk_benchmark())
    rows.extend(allocation_benchmark())
    rows.extend(capability_benchmark())
    rows.extend(map_throughput())
    rows.extend(stiffness_benchmark())
    rows.extend(inspect_benchmark())
    rows.extend(import_benchmark())
    return rows


def inspect_benchmark() -> list[dict[str, object]]:
    """Cost of one live-inspector update on the 3D4M (target: 50 ms), state function alone (no drawing).

    A slider step from the reference: the task frame 1 mm along x, or slider 1 by 1 mm; every
    readout (margins, manipulability, ellipse, statics, stiffness) included.
    """
    from plm_pin.viz.inspect_state import inspect_state, inspect_update

    mech = load("harada2011_3d4m")
    state = inspect_state(mech)
    changes = {
        "inspect_update (task x +1 mm, all readouts)": {"task": {"x": float(state.x[0]) + 1e-3}},
        "inspect_update (slider1 +1 mm, all readouts)": {
            "actuators": {"slider1": float(state.actuators[0]) + 1e-3}
        },
    }
    return [
        {
            "mechanism": mech.name,
            "case": case,
            "seconds_per_call": _per_call(functools.partial(inspect_update, state, change)),
        }
        for case, change in changes.items()
    ]


IMPORT_ROUNDS = 9
"""Fresh interpreters per import timed (alternating plm_pin and its floor; the best of each is kept)."""


def _import_seconds(modules: str) -> float:
    """Wall time of ``import <modules>`` in a fresh interpreter (its start-up left out) [s]."""
    code = f"import time; t = time.perf_counter(); import {modules}; print(time.perf_counter() - t)"
    root = str(Path(__file__).resolve().parents[1])  # this checkout's plm_pin
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, (root, os.environ.get("PYTHONPATH"))))}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return float(out.stdout)


def import_benchmark() -> list[dict[str, object]]:
    """``import plm_pin`` beside its floor ``import numpy, pinocchio``, fresh interpreters in alternation."""
    ours, floor = math.inf, math.inf
    for _ in range(IMPORT_ROUNDS):
        ours = min(ours, _import_seconds("plm_pin"))
        floor = min(floor, _import_seconds("numpy, pinocchio"))
    return [
        {
            "mechanism": "-",
            "case": "import plm_pin [floor: import numpy, pinocchio]",
            "seconds_per_call": ours,
            "floor_seconds_per_call": floor,
        }
    ]


def stiffness_benchmark() -> list[dict[str, object]]:
    """Cost per pose of :func:`plm_pin.stiffness.stiffness` beside ``closed_chain_jacobians``.

    Every preset with a compliance in its sidecar, at its reference configuration under gravity.
    """
    from plm_pin.stiffness import stiffness

    rows: list[dict[str, object]] = []
    for name in preset_names():
        mech = load(name)
        if mech.sidecar.compliance is None:
            continue
        call = functools.partial(stiffness, mech, mech.q_ref)
        rows.append(
            {"mechanism": name, "case": "stiffness (gravity, min-norm)", "seconds_per_call": _per_call(call)}
        )
    return rows


def balance_floor(mech: Mechanism, data: pin.Data, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    r"""The floor of a statics or inverse-dynamics sample: ``pin.rnea`` + :math:`J_\phi` + one ProxSuite QP.

    The least Python doing the balance's math with Pinocchio and ProxSuite calls: the
    minimum-norm :math:`(f_c, \lambda)` with :math:`B f_c + J_\phi^T \lambda = \tau` (no split,
    no checks), as an equality-constrained dense QP.
    """
    model = mech.model
    tau = pin.rnea(model, data, q, v, a)
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J = closure_jacobian_from_data(model, data, mech.closures)
    act, n_act = mech.actuated_v_indices, mech.n_actuators
    n = n_act + J.shape[0]
    A = np.zeros((model.nv, n))
    A[act, np.arange(n_act)] = 1.0
    A[:, n_act:] = J.T
    qp = proxsuite.proxqp.dense.QP(n, model.nv, 0)
    qp.init(np.eye(n), np.zeros(n), A, tau, None, None, None)
    qp.solve()
    return np.asarray(qp.results.x)


def allocation_benchmark() -> list[dict[str, object]]:
    """Bounded and min-peak static allocation, trajectory and inverse dynamics per sample (3D4M, 8-PSS).

    The default paths (static forces at one pose, where the factorisation is reused from the
    call before, and along the trajectory, where it is not; inverse dynamics per sample) print
    beside their floor (:func:`balance_floor`), timed in alternation; the default of
    :func:`inverse_dynamics` computes the forces, closure forces, internal coordinates and the
    term split; the body split on request.
    """
    rows: list[dict[str, object]] = []
    profiles: dict[str, tuple[Callable[[float], Any], float]] = {
        "harada2011_3d4m": (_harada_profile, 1.0),
        "zhao2011_8pss": (zhao2011_trajectory, ZHAO2011_TRAJECTORY_DURATION),
    }
    for name, (profile, duration) in profiles.items():
        mech = load(name)
        q = mech.q_ref
        free = np.max(np.abs(static_forces(mech, q).f_c))
        least = np.max(np.abs(static_forces(mech, q, objective="max").f_c))
        bound = [(-(free + least) / 2, (free + least) / 2)] * mech.n_actuators  # the limits bind
        times = np.linspace(0.0, duration, 51)
        traj = task_trajectory(mech, profile, times)
        balance = static_balance(mech, q)
        cases: dict[str, tuple[Callable[[], object], int]] = {
            "static_balance (gravity): B, J_phi, internal basis": (
                functools.partial(static_balance, mech, q),
                1,
            ),
            "solve_balance on it (min-norm)": (
                functools.partial(solve_balance, mech, balance, AllocationRule.checked(mech)),
                1,
            ),
            "solve_balance on it (limits active)": (
                functools.partial(solve_balance, mech, balance, AllocationRule.checked(mech, limits=bound)),
                1,
            ),
            "static_forces (gravity, limits active)": (
                functools.partial(static_forces, mech, q, limits=bound),
                1,
            ),
            "static_forces (gravity, objective='max')": (
                functools.partial(static_forces, mech, q, objective="max"),
                1,
            ),
            "task_trajectory, per sample": (functools.partial(task_trajectory, mech, profile, times), 51),
            "inverse_dynamics and its body split (on request), per sample": (
                functools.partial(_with_bodies, mech, traj),
                51,
            ),
        }
        for case, (fn, per) in cases.items():
            rows.append({"mechanism": name, "case": case, "seconds_per_call": _per_call(fn) / per})
        data = mech.model.createData()
        rest = np.zeros(mech.nv)

        def floor_trajectory(traj: Any = traj, data: pin.Data = data, mech: Mechanism = mech) -> None:
            for qi, vi, ai in zip(traj.q, traj.v, traj.a, strict=True):
                balance_floor(mech, data, qi, vi, ai)

        def statics_along(traj: Any = traj, mech: Mechanism = mech) -> None:
            for qi in traj.q:
                static_forces(mech, qi)

        def floor_along(
            traj: Any = traj, data: pin.Data = data, mech: Mechanism = mech, rest: np.ndarray = rest
        ) -> None:
            for qi in traj.q:
                balance_floor(mech, data, qi, rest, rest)

        floored: dict[str, tuple[Callable[[], object], Callable[[], object], int]] = {
            "static_forces (gravity, min-norm: the default)": (
                functools.partial(static_forces, mech, q),
                functools.partial(balance_floor, mech, data, q, rest, rest),
                1,
            ),
            "static_forces along the trajectory (a new pose each call: no factorisation reused)": (
                statics_along,
                floor_along,
                51,
            ),
            "inverse_dynamics (default: forces, closure forces, term split), per sample": (
                functools.partial(inverse_dynamics, mech, traj),
                floor_trajectory,
                51,
            ),
        }
        for case, (fn, floor, per) in floored.items():
            ours, least = _alternating(fn, floor)
            rows.append(
                {
                    "mechanism": name,
                    "case": f"{case} [{ours / least:.2f}x the floor rnea + J_phi + one ProxSuite QP]",
                    "seconds_per_call": ours / per,
                    "floor_seconds_per_call": least / per,
                }
            )
    return rows


def _reduced_balance(
    mech: Mechanism, data: pin.Data, q: np.ndarray, load: tuple[int, np.ndarray] | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""The balance :math:`B f_c + J_\phi^T \lambda = g(q) - \alpha J_w^T w` reduced by one SVD.

    The SVD of :math:`A = [B\ J_\phi^T]` gives the minimum-norm solutions for gravity and for
    the unit ``load`` (frame index, wrench :math:`w`; zero without one) and the null space, whose
    actuator parts span the internal forces. Returns their actuator parts :math:`f_g`,
    :math:`f_d` (n_act,) and the spanning vectors (n_act, k'), :math:`k' \ge k` (the closure
    forces' own null space adds vectors without an actuator part).
    """
    model = mech.model
    g = pin.computeGeneralizedGravity(model, data, q)
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J = closure_jacobian_from_data(model, data, mech.closures)
    n = mech.n_actuators
    A = np.zeros((model.nv, n + J.shape[0]))
    A[mech.actuated_v_indices, np.arange(n)] = 1.0
    A[:, n:] = J.T
    tau = np.zeros((model.nv, 2))
    tau[:, 0] = g
    if load is not None:
        frame_id, wrench = load
        lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        tau[:, 1] = -pin.getFrameJacobian(model, data, frame_id, lwa).T @ wrench
    U, s, Vt = np.linalg.svd(A)
    r = int(np.sum(s > 1e-9 * s[0]))
    z = Vt[:r].T @ ((U[:, :r].T @ tau) / s[:r, None])  # (n + m, 2) minimum-norm solutions
    return z[:n, 0], z[:n, 1], Vt[r:, :n].T


def _highs_lp(
    highs: highspy.Highs,
    c: np.ndarray,
    D: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    col_lower: np.ndarray,
) -> np.ndarray:
    """``min c^T z`` s.t. ``lower <= D z <= upper``, ``z >= col_lower``: one HiGHS call, rows dense."""
    m, n = D.shape
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = n, m
    lp.col_cost_, lp.col_lower_, lp.col_upper_ = c, col_lower, np.full(n, np.inf)
    lp.row_lower_, lp.row_upper_ = lower, upper
    lp.a_matrix_.format_ = highspy.MatrixFormat.kRowwise
    lp.a_matrix_.start_ = np.arange(0, m * n + 1, n, dtype=np.int32)
    lp.a_matrix_.index_ = np.tile(np.arange(n, dtype=np.int32), m)
    lp.a_matrix_.value_ = D.ravel()
    highs.passModel(lp)
    highs.run()
    return np.array(highs.getSolution().col_value)


def capability_floor(
    mech: Mechanism,
    data: pin.Data,
    highs: highspy.Highs,
    q: np.ndarray,
    frame_id: int,
    wrench: np.ndarray,
    limits: np.ndarray,
) -> float:
    r"""The floor of :func:`~plm_pin.statics.force_capability`: one SVD and one HiGHS LP.

    The least Python doing its math with Pinocchio, numpy and HiGHS calls: the reduced
    balance (:func:`_reduced_balance`), then :math:`\max \alpha` s.t. :math:`l \le f_g + G' y +
    \alpha f_d \le u`, :math:`\alpha \ge 0` (no checks, no saturated actuators, no result
    object). Returns :math:`\alpha`.
    """
    f_g, f_d, G = _reduced_balance(mech, data, q, (frame_id, wrench))
    k = G.shape[1]
    c = np.zeros(k + 1)
    c[-1] = -1.0
    D = np.hstack([G, f_d[:, None]])
    col_lower = np.r_[np.full(k, -np.inf), 0.0]
    return float(_highs_lp(highs, c, D, limits[:, 0] - f_g, limits[:, 1] - f_g, col_lower)[-1])


def internal_range_floor(
    mech: Mechanism, data: pin.Data, highs: highspy.Highs, q: np.ndarray, limits: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    r"""The floor of :func:`~plm_pin.statics.internal_force_range` under gravity: two SVDs and 2k LPs.

    The reduced balance (:func:`_reduced_balance`), a small SVD for an orthonormal basis
    :math:`G` of the internal forces, then :math:`\min / \max y_k` s.t. :math:`l \le f_g + G y
    \le u`, one HiGHS LP each. Returns the (2, k) extents of :math:`G^T f_c` (the coordinates
    plus :math:`G^T f_g`) and the basis (n_act, k).
    """
    f_g, _, spanning = _reduced_balance(mech, data, q)
    U, s, _ = np.linalg.svd(spanning, full_matrices=False)
    G = U[:, s > 1e-9]  # (n_act, k)
    k = G.shape[1]
    ends = np.empty((2, k))
    lower, upper, free = limits[:, 0] - f_g, limits[:, 1] - f_g, np.full(k, -np.inf)
    for side, sign in enumerate((1.0, -1.0)):
        for i in range(k):
            ends[side, i] = _highs_lp(highs, sign * np.eye(k)[i], G, lower, upper, free)[i]
    return ends + G.T @ f_g, G


CAPABILITY_CASES: dict[str, tuple[list[float], float]] = {
    "harada2011_3d4m": ([0.3, -1.0, 0.01], 10.0),
    "zhao2011_8pss": ([0.0, 0.0, -1.0, 0.0, 0.1, 0.0], 6000.0),
}
"""Load direction (task coordinates) and symmetric actuator limit [N] of :func:`capability_benchmark`."""


def capability_benchmark() -> list[dict[str, object]]:
    """Force capability and internal-force range at the reference configuration, beside their floors.

    :func:`capability_floor` and :func:`internal_range_floor`, timed in alternation; gravity held.
    """
    rows: list[dict[str, object]] = []
    for name, (direction, bound) in CAPABILITY_CASES.items():
        mech = load(name)
        q = mech.q_ref
        limits = np.array([[-bound, bound]] * mech.n_actuators)
        data, highs = mech.model.createData(), new_highs()
        task = wrench_on_frame(mech, direction)
        floored: dict[str, tuple[Callable[[], object], Callable[[], object], str]] = {
            "force_capability (gravity, limits)": (
                functools.partial(force_capability, mech, q, direction, limits=limits),
                functools.partial(capability_floor, mech, data, highs, q, task.frame_id, task.wrench, limits),
                "SVD + one HiGHS LP",
            ),
            "internal_force_range (gravity, limits)": (
                functools.partial(internal_force_range, mech, q, limits=limits),
                functools.partial(internal_range_floor, mech, data, highs, q, limits),
                "SVDs + 2k HiGHS LPs",
            ),
        }
        for case, (fn, floor, what) in floored.items():
            ours, least = _alternating(fn, floor)
            rows.append(
                {
                    "mechanism": name,
                    "case": f"{case} [{ours / least:.2f}x the floor {what}]",
                    "seconds_per_call": ours,
                    "floor_seconds_per_call": least,
                }
            )
    return rows


def _with_bodies(mech: Mechanism, traj: Any) -> dict[str, np.ndarray]:
    """Inverse dynamics with its body split read (computed on first access)."""
    return dict(inverse_dynamics(mech, traj).bodies)


def _alternating(
    fn: Callable[[], object], floor: Callable[[], object], rounds: int = 5
) -> tuple[float, float]:
    """Best time per call [s] of ``fn`` and of ``floor``, measured in alternation (same load on both)."""
    best = [math.inf, math.inf]
    for _ in range(rounds):
        for i, f in enumerate((fn, floor)):
            best[i] = min(best[i], _per_call(f, 0.05))
    return best[0], best[1]


def _harada_profile(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A smooth motion of the Harada plate around its reference pose (x, y, theta)."""
    x0 = np.array([0.0, 0.08, math.radians(-20.0)])
    amp = np.array([0.02, 0.01, 0.2])
    w = np.array([2.0, 3.0, 2.5])
    return x0 + amp * np.sin(w * t), amp * w * np.cos(w * t), -amp * w**2 * np.sin(w * t)


def _timed_maps(
    mech: Mechanism, values: tuple[np.ndarray, np.ndarray], pose: tuple[float, ...] | None, stride: int
) -> tuple[dict[str, float], WorkspaceSlice]:
    """Wall time of one x-y map per selection of :data:`MAP_METRICS`, and the last map.

    A small map first (every ``stride``-th value) compiles what the map runs on: the compile is
    not the map's cost (it has its own row).
    """
    workspace_map(mech, ("x", "y"), (values[0][::stride], values[1][::stride]), pose, workers=1)
    seconds = {}
    for label, names in MAP_METRICS:
        start = time.perf_counter()
        result = workspace_map(mech, ("x", "y"), values, pose, workers=1, metrics=names)
        seconds[label] = time.perf_counter() - start
    return seconds, result


def map_throughput(shape: tuple[int, int] = MAP_SHAPE) -> list[dict[str, object]]:
    """Maps on one core: the 3D4M's 10^5 poses beside Harada's closed form, and an 8-PSS map.

    Each map is timed with every metric and with the manipulability alone (:data:`MAP_METRICS`).
    The 3D4M rows' floor is :func:`harada_closed_form_map` over the same poses (numpy,
    vectorised): what a mechanism-specific closed form costs. One run each (wall time).
    """
    mech = load("harada2011_3d4m")
    values = (np.linspace(-0.1, 0.1, shape[0]), np.linspace(0.01, 0.12, shape[1]))
    seconds, result = _timed_maps(mech, values, (0.0, 0.08, math.radians(-20.0)), 40)
    p = PRESETS["harada2011_3d4m"].parameters
    poses = result.poses().reshape(-1, 3)
    start = time.perf_counter()
    harada_closed_form_map(poses, p["rod_lengths"][0], p["half_plate"], (-1, 1, -1, 1))
    closed = time.perf_counter() - start
    n = poses.shape[0]
    rows: list[dict[str, object]] = [
        {
            "mechanism": mech.name,
            "case": f"workspace_map x-y {shape[0]} x {shape[1]} = {n} poses, {label}, 1 process "
            f"({n / t:.0f} poses/s; floor: Harada eqs. (2), (12), (13) vectorised, wall time)",
            "seconds_per_call": t,
            "floor_seconds_per_call": closed,
        }
        for label, t in seconds.items()
    ]
    pss = load("zhao2011_8pss")
    x0 = task_pose(pss, pss.q_ref)
    grid = (np.linspace(x0[0] - 0.05, x0[0] + 0.05, 40), np.linspace(x0[1] - 0.05, x0[1] + 0.05, 40))
    seconds, pss_map = _timed_maps(pss, grid, None, 10)
    rows.extend(
        {
            "mechanism": pss.name,
            "case": f"workspace_map x-y 40 x 40 = 1600 poses, {label}, 1 process ({1600 / t:.0f} poses/s, "
            f"{100 * pss_map.reachable_fraction:.0f}% reachable, wall time)",
            "seconds_per_call": t,
        }
        for label, t in seconds.items()
    )
    return rows


def _peak_kinetic(mech: Mechanism, run: SimulationResult) -> float:
    data = mech.model.createData()
    return max(pin.computeKineticEnergy(mech.model, data, q, v) for q, v in zip(run.q, run.v, strict=True))


def _simulation_row(
    mech: Mechanism, case: str, crank_1s: float | None = None, **kwargs: Any
) -> dict[str, object]:
    """Accuracy and cost of one :func:`simulate` run; energy drift relative to the peak kinetic energy.

    ``crank_1s``: the reference crank angle at 1 s [rad], for the error column (four-bar only).
    """
    start = time.perf_counter()
    run = simulate(mech, mech.q_ref, **kwargs)
    seconds = time.perf_counter() - start
    at_1s = int(np.argmin(np.abs(run.t - 1.0)))
    return {
        "crank_error_1s": None if crank_1s is None else abs(float(run.q[at_1s, 0]) - crank_1s),
        "seconds_per_simulated_second": seconds / float(run.t[-1]),
        "engine": f"plm_pin ({run.solver})",
        "mechanism": mech.name,
        "case": case,
        "max_closure_error": run.max_residual,
        "max_closure_drift_before_projection": float(run.closure_drift.max()),
        "energy_drift": run.energy_drift() / _peak_kinetic(mech, run) if not kwargs.get("wrench") else None,
        "steps": run.steps,
        "seconds_per_step": seconds / run.steps,
        "seconds": seconds,
    }


def fourbar_mjcf(integrator: str = "Euler", solref: float | None = None) -> str:
    """MJCF of the ``fourbar`` preset from its builder parameters, the loop closed by a site ``connect``.

    Bars as in :func:`plm_pin.families.classic.build_fourbar`: mass ``density * L`` at ``L / 2``,
    inertia ``(m r^2 / 2, m L^2 / 12, m L^2 / 12)`` with r = 5 mm; no geoms (no contacts);
    MuJoCo's default solver, ``integrator`` (default Euler) and the constraint's time constant
    ``solref`` [s] (default MuJoCo's 0.02); 1 ms steps.
    """
    defaults = {k: p.default for k, p in inspect.signature(build_fourbar).parameters.items()}
    p = {**defaults, **PRESETS["fourbar"].parameters}

    def inertial(length: float) -> str:
        m = p["density"] * length
        return (
            f'<inertial pos="{length / 2} 0 0" mass="{m}" '
            f'diaginertia="{0.5 * m * 0.005**2} {m * length**2 / 12} {m * length**2 / 12}"/>'
        )

    a, b, c, d = p["crank"], p["coupler"], p["rocker"], p["ground"]
    stiff = "" if solref is None else f' solref="{solref} 1"'
    return f"""<mujoco model="fourbar">
  <option timestep="{SIM_STEP}" integrator="{integrator}" gravity="0 {-p["gravity"]} 0">
    <flag energy="enable"/>
  </option>
  <worldbody>
    <body name="crank">
      <joint name="crank_pivot" type="hinge" axis="0 0 1"/>
      {inertial(a)}
      <body name="coupler" pos="{a} 0 0">
        <joint name="coupler_pivot" type="hinge" axis="0 0 1"/>
        {inertial(b)}
        <site name="coupler_tip" pos="{b} 0 0"/>
      </body>
    </body>
    <body name="rocker" pos="{d} 0 0">
      <joint name="rocker_pivot" type="hinge" axis="0 0 1"/>
      {inertial(c)}
      <site name="rocker_tip" pos="{c} 0 0"/>
    </body>
  </worldbody>
  <equality><connect site1="coupler_tip" site2="rocker_tip"{stiff}/></equality>
</mujoco>
"""


def mujoco_fourbar_row(
    q0: np.ndarray,
    integrator: str = "Euler",
    solref: float | None = None,
    crank_1s: float | None = None,
    output: float = SIM_OUTPUT,
) -> dict[str, object]:
    """The four-bar in MuJoCo from ``q0`` at rest: closure error and energy drift at the output times.

    ``output``: the sampling step [s] (energy and sites computed there, a multiple of :data:`SIM_STEP`).
    """
    softness = "soft connect (defaults)" if solref is None else f"connect solref {solref:g}"
    every = "" if output == SIM_OUTPUT else f", {output * 1e3:g} ms outputs"
    row: dict[str, object] = {
        "engine": "MuJoCo",
        "mechanism": "fourbar",
        "case": f"{SIM_DURATION:g} s passive, {integrator} {SIM_STEP * 1e3:g} ms, {softness}{every}",
    }
    try:
        import mujoco  # optional: pip install mujoco (dev extra)
    except ImportError as exc:
        return {**row, "engine": f"MuJoCo (not available: {exc})"}
    row["engine"] = f"MuJoCo {mujoco.__version__}"
    model = mujoco.MjModel.from_xml_string(fourbar_mjcf(integrator, solref))
    data = mujoco.MjData(model)
    data.qpos[:] = q0
    mujoco.mj_forward(model, data)
    per_sample = round(output / SIM_STEP)
    n_samples = round(SIM_DURATION / output)
    tips = [model.site("coupler_tip").id, model.site("rocker_tip").id]
    energy: list[float] = []
    kinetic: list[float] = []
    gap: list[float] = []
    crank: list[float] = []

    def sample() -> None:
        crank.append(float(data.qpos[0]))
        energy.append(float(data.energy.sum()))
        kinetic.append(float(data.energy[1]))
        gap.append(float(np.linalg.norm(data.site_xpos[tips[0]] - data.site_xpos[tips[1]])))

    sample()
    start = time.perf_counter()
    for _ in range(n_samples):
        mujoco.mj_step(model, data, per_sample)
        mujoco.mj_forward(model, data)  # energy and sites at the sample's state
        sample()
    seconds = time.perf_counter() - start
    steps = n_samples * per_sample
    at_1s = round(1.0 / output)
    return {
        **row,
        "crank_error_1s": None if crank_1s is None else abs(crank[at_1s] - crank_1s),
        "seconds_per_simulated_second": seconds / SIM_DURATION,
        "max_closure_error": max(gap),
        "max_closure_drift_before_projection": None,
        "energy_drift": max(abs(e - energy[0]) for e in energy) / max(kinetic),
        "steps": steps,
        "seconds_per_step": seconds / steps,
        "seconds": seconds,
    }


def simulation_benchmark() -> list[dict[str, object]]:
    """Closed-chain simulation: the four-bar against MuJoCo, and Harada 2011's simulation 1.

    The four-bar runs 10 s passive under gravity from the preset's reference configuration at
    rest, sampled every 10 ms, in plm_pin (the default: one DOP853 run with dense output; RK4 at
    1 ms with both solvers) and in MuJoCo (1 ms: Euler with its defaults, RK4 with the stiffest
    connect that is stable at 1 ms, solref 0.002). Energy drift is relative to the peak kinetic
    energy; the crank error at 1 s is against a DOP853 run at rtol 1e-13 (which matches the
    independent one-coordinate Lagrangian of the tests to 1e-10 rad).
    """
    four = load("fourbar")
    harada = load("harada2011_3d4m")
    p = PRESETS["harada2011_3d4m"].parameters
    f_y = (2 * p["rod_masses"][0] + p["plate_mass"]) * p["gravity"]
    passive = {"duration": SIM_DURATION, "dt": SIM_OUTPUT}
    crank = float(simulate(four, four.q_ref, duration=1.0, dt=1.0, rtol=1e-13, atol=1e-14).q[-1, 0])
    rows = [
        _simulation_row(
            four, f"{SIM_DURATION:g} s passive, default: DOP853 rtol 1e-10, dense output", crank, **passive
        ),
        _simulation_row(
            four, f"{SIM_DURATION:g} s passive, RK4 1 ms", crank, method="fixed", step=SIM_STEP, **passive
        ),
        _simulation_row(
            four,
            f"{SIM_DURATION:g} s passive, RK4 1 ms",
            crank,
            method="fixed",
            step=SIM_STEP,
            solver="kkt",
            **passive,
        ),
        mujoco_fourbar_row(four.q_ref, crank_1s=crank),
        mujoco_fourbar_row(four.q_ref, "RK4", 0.002, crank_1s=crank),
        _simulation_row(
            harada,
            "Harada 2011 simulation 1 (2 s, f_x = 0.2 N), default",
            duration=2.0,
            dt=SIM_OUTPUT,
            wrench=[0.2, f_y, 0.0],
        ),
    ]
    # the ratio to MuJoCo RK4 from the best of SIM_ROUNDS alternating runs of both (one run each
    # swings by 2x on a shared machine)
    rows[0], rows[4] = _best_pair(
        lambda: _simulation_row(four, str(rows[0]["case"]), crank, **passive),
        lambda: mujoco_fourbar_row(four.q_ref, "RK4", 0.002, crank_1s=crank),
        (rows[0], rows[4]),
    )
    _cost_ratios([r for r in rows if r["mechanism"] == "fourbar"], rows[4])
    # every output at 1 ms: the per-sample cost (projection, closure forces, energy) dominates
    fine = _best_pair(
        lambda: _simulation_row(
            four,
            f"{SIM_DURATION:g} s passive, default, {SIM_STEP * 1e3:g} ms outputs",
            crank,
            duration=SIM_DURATION,
            dt=SIM_STEP,
        ),
        lambda: mujoco_fourbar_row(four.q_ref, "RK4", 0.002, crank_1s=crank, output=SIM_STEP),
    )
    _cost_ratios(list(fine), fine[1])
    return [*rows, *fine]


Row = dict[str, object]


def _best_pair(
    ours: Callable[[], Row], theirs: Callable[[], Row], first: tuple[Row, Row] | None = None
) -> tuple[Row, Row]:
    """The fastest of :data:`SIM_ROUNDS` alternating runs of each (``first``: the first round's rows)."""
    best = first or (ours(), theirs())
    for _ in range(SIM_ROUNDS - 1):
        again = (ours(), theirs())
        best = tuple(  # type: ignore[assignment]
            new if float(new.get("seconds", math.inf)) < float(old.get("seconds", math.inf)) else old  # type: ignore[arg-type]
            for new, old in zip(again, best, strict=True)
        )
    return best


def _cost_ratios(rows: list[Row], reference: Row) -> None:
    """Set ``cost_vs_mujoco_rk4``: each row's cost per simulated second over ``reference``'s."""
    base = reference.get("seconds_per_simulated_second")
    for r in rows:
        cost = r.get("seconds_per_simulated_second")
        if isinstance(base, float) and isinstance(cost, float):
            r["cost_vs_mujoco_rk4"] = cost / base


def _simulation_line(r: dict[str, object]) -> str:
    """One Markdown row of the simulation table ("-" where a value is missing or not applicable)."""

    def cell(key: str, fmt: str, scale: float = 1.0) -> str:
        value = r.get(key)
        return "-" if not isinstance(value, (int, float)) else format(scale * value, fmt)

    total = r.get("seconds")
    return (
        f"| {r['engine']} | {r['mechanism']} | {r['case']} | {cell('max_closure_error', '.1e')} "
        f"| {cell('crank_error_1s', '.1e')} | {cell('energy_drift', '.1e')} "
        f"| {cell('seconds_per_step', '.1f', 1e6)} | {cell('seconds_per_simulated_second', '.1f', 1e3)} "
        f"| {cell('cost_vs_mujoco_rk4', '.2f')} | {_fmt(total) if isinstance(total, float) else '-'} "
        f"| {cell('max_closure_drift_before_projection', '.1e')} |"
    )


def fig6_note() -> str:
    """Harada 2011 Fig. 6: the 3D3M's type-4 singular angle at the y where eq. (11.4) gives 28.7 deg.

    The table with l : 2 r_t = 2 : 1 (r_t = l / 4) is built (:func:`plm_pin.build_mechanism`); the angle
    is located by root finding along theta (:func:`plm_pin.workspace.singular_points_along`).
    """
    l = float(PRESETS["harada2011_3d3m"].parameters["rod_lengths"][0])
    rt = l / 4.0
    mech = build_mechanism("harada2011_3d3m", {"half_plate": rt}, name="fig6_3d3m")
    y = (l + rt) * math.sin(math.radians(28.7))
    points = singular_points_along(mech, "rz", np.radians(np.linspace(-80.0, 80.0, 65)), (0.0, y, 0.0))
    angles = ", ".join(f"{math.degrees(p.parameter):.2f} deg ({p.kind})" for p in points)
    return (
        f"Harada 2011 Fig. 6 (l = {l:.3f} m, r_t = l/4 = {rt:.4f} m): at y = {y:.6f} m = {y / l:.4f} l "
        f"(where eq. (11.4) gives 28.7 deg), the 3D3M's singular angle found numerically: {angles}."
    )


def sweep_benchmark(cases: dict[str, dict[str, Any]] | None = None) -> list[dict[str, object]]:
    """Poses per second of design sweeps: in one process, and on a 2-worker Dask LocalCluster.

    The cluster (2 single-threaded processes on 127.0.0.1) is started once; its start-up time
    is reported apart and the sweeps on it are timed without it. Each sweep runs once (wall time),
    after an untimed run of its first two parameter points on the same executor (the imports
    and first calls of a fresh worker, about a second, are not the sweep's cost).
    """
    from plm_pin.sweep import make_spec, run_spec
    from plm_pin.sweep.execution import local_cluster

    rows: list[dict[str, object]] = []
    chosen = cases or SWEEP_CASES
    specs = {case: make_spec(**kwargs) for case, kwargs in chosen.items()}
    warm = {case: make_spec(**_first_points(kwargs, 2)) for case, kwargs in chosen.items()}
    for case, spec in specs.items():
        run_spec(warm[case], workers=1)
        result = run_spec(spec, workers=1)
        rows.append(_sweep_row(case, "1 process", result.elapsed, spec.n_points * spec.n_poses))
    try:
        start = time.perf_counter()
        with local_cluster(2, None) as client:
            startup = time.perf_counter() - start
            for case, spec in specs.items():
                chunk = max(1, spec.n_points * spec.n_poses // 12)  # 12 tasks: both workers busy to the end
                run_spec(warm[case], scheduler=client, chunk=1)  # one point per worker
                result = run_spec(spec, scheduler=client, chunk=chunk)
                rows.append(_sweep_row(case, "2 Dask workers", result.elapsed, spec.n_points * spec.n_poses))
                one = next(r for r in rows if r["case"] == case and r["executor"] == "1 process")
                rows[-1]["speedup"] = float(one["seconds"]) / result.elapsed  # type: ignore[arg-type]
        rows.append(
            {"case": "Dask LocalCluster start-up (2 worker processes)", "executor": "-", "seconds": startup}
        )
    except ImportError as exc:
        rows.append({"case": f"Dask not available: {exc}", "executor": "-", "seconds": None})
    return rows


def _first_points(kwargs: dict[str, Any], n: int) -> dict[str, Any]:
    """A sweep case (arguments of ``make_spec``) cut to the first ``n`` values of each varied parameter."""
    return {**kwargs, "parameters": {k: list(v)[:n] for k, v in kwargs["parameters"].items()}}


OPTIMIZE_CASE = "DE, 1021 designs of the 3D4M (r_t, l) x 20 x 20 poses (x, y): reach + GCI"
"""The optimisation timed by :func:`optimize_benchmark`."""


def optimize_benchmark(workers: tuple[int, ...] = (1, 2)) -> list[dict[str, object]]:
    """Designs of a differential evolution over the 3D4M's plate and rods, in one process and on Dask.

    1 start design, the initial population and 50 generations of 20 each (population 10 per
    variable, ``tol=0``: no early stop),
    each design built and evaluated over a 20 x 20 grid of plate positions (rz = 0). Rows in the
    sweep table's form, ``poses`` counting designs x poses; each run once (wall time). As for the
    sweeps, the local cluster is started first (its start-up has its own row) and its workers
    evaluate two generations untimed (their imports and first calls are not the search's cost).
    """
    from plm_pin.optimize import make_problem, run_problem
    from plm_pin.sweep.execution import local_cluster

    problem = make_problem(
        "harada2011_3d4m",
        {"half_plate": [0.02, 0.07], "rod_lengths": {"bounds": [0.10, 0.20], "repeat": 4}},
        {"x": np.linspace(-0.03, 0.03, 20), "y": np.linspace(0.06, 0.10, 20)},
        ["gci"],
        pose=[0.0, 0.08, 0.0],
    )
    rows: list[dict[str, object]] = []
    for n in workers:
        executor = "1 process" if n == 1 else f"{n} Dask workers"
        try:
            if n == 1:
                run_problem(problem, generations=1, population=10, tol=0.0)
                start = time.perf_counter()
                result = run_problem(problem, generations=50, population=10, tol=0.0)
                seconds = time.perf_counter() - start
            else:
                with local_cluster(n, None) as client:
                    run_problem(problem, generations=1, population=10, tol=0.0, scheduler=client)
                    start = time.perf_counter()
                    result = run_problem(problem, generations=50, population=10, tol=0.0, scheduler=client)
                    seconds = time.perf_counter() - start
        except ImportError as exc:
            rows.append({"case": f"Dask not available: {exc}", "executor": executor, "seconds": None})
            continue
        rows.append(
            _sweep_row(OPTIMIZE_CASE, executor, seconds, len(result.evaluations) * problem.spec.n_poses)
        )
        if n > 1:
            one = next(r for r in rows if r["case"] == OPTIMIZE_CASE and r["executor"] == "1 process")
            rows[-1]["speedup"] = float(one["seconds"]) / seconds  # type: ignore[arg-type]
    return rows


def _sweep_row(case: str, executor: str, seconds: float, poses: int) -> dict[str, object]:
    return {
        "case": case,
        "executor": executor,
        "poses": poses,
        "seconds": seconds,
        "poses_per_second": poses / seconds,
    }


def _sweep_line(r: dict[str, object]) -> str:
    rate = r.get("poses_per_second")
    seconds = r.get("seconds")
    speedup = r.get("speedup")
    return (
        f"| {r['case']} | {r['executor']} | {r.get('poses', '-')} "
        f"| {f'{seconds:.2f}' if isinstance(seconds, float) else '-'} "
        f"| {f'{rate:.0f}' if isinstance(rate, float) else '-'} "
        f"| {f'{speedup:.2f}x' if isinstance(speedup, float) else '-'} |"
    )


def _timing_line(r: dict[str, object]) -> str:
    """One Markdown row of the timing table, with the floor and the ratio where there is a floor."""
    ours = float(r["seconds_per_call"])  # type: ignore[arg-type]
    floor = r.get("floor_seconds_per_call")
    if isinstance(floor, float):
        return f"| {r['mechanism']} | {r['case']} | {_fmt(ours)} | {_fmt(floor)} | {ours / floor:.2f} |"
    return f"| {r['mechanism']} | {r['case']} | {_fmt(ours)} | - | - |"


def _fmt(seconds: float) -> str:
    if seconds >= 1.0:
        return f"{seconds:.2f} s"
    return f"{seconds * 1e6:.1f} us" if seconds < 1e-3 else f"{seconds * 1e3:.2f} ms"


VERSIONS = (("system", "system"), ("python", "Python"), ("pinocchio", "Pinocchio"), ("numpy", "NumPy"))
"""The versions a run records (key of ``machine()``, name printed)."""


def machine() -> dict[str, object]:
    """Where and when the benchmark runs: UTC date, processor, cores, load at the start, versions."""
    cpu = platform.processor() or platform.machine()
    try:
        models = [
            line for line in Path("/proc/cpuinfo").read_text().splitlines() if line.startswith("model name")
        ]
        cpu = models[0].split(":", 1)[1].strip() if models else cpu
    except OSError:
        pass
    return {
        "date": time.strftime("%Y-%m-%d", time.gmtime()),
        "cpu": cpu,
        "cores": os.cpu_count(),
        "load_average": os.getloadavg()[0] if hasattr(os, "getloadavg") else None,
        "system": platform.platform(terse=True),
        "python": platform.python_version(),
        "pinocchio": pin.__version__,
        "numpy": np.__version__,
    }


def machine_line(info: dict[str, object]) -> str:
    """The sentence stating the date and the machine of a run (what the docs page quotes).

    Keys missing from ``info`` are left out; a ``source`` key (a run not timed by this harness,
    e.g. transcribed from an earlier table) is appended as said.
    """
    load = info.get("load_average")
    where = f"{info.get('cpu', 'an unrecorded processor')} ({info.get('cores', '?')} cores"
    where += f", load average {load:.2f} at the start)" if isinstance(load, float) else ")"
    versions = [f"{name} {info[key]}" for key, name in VERSIONS if info.get(key)]
    line = f"Measured on {info['date']} on {where}" + "".join(f", {v}" for v in versions) + "."
    return f"{line} {info['source']}" if info.get("source") else line


def markdown(results: dict[str, Any], level: int = 1, title: str = "plm_pin benchmarks") -> str:
    """The Markdown tables of a run's ``results.json`` content, its date and machine stated first.

    ``level`` is the heading level of the title (1 for ``results.md``, 2 inside the docs page).
    """
    h = "#" * level
    lines = [
        f"{h} {title}",
        "",
        machine_line(results["machine"]),
        "",
        "Times per call are the best of 5 repeats. Floor: the least Python doing the same math with "
        "Pinocchio calls, in the same process (`benchmarks.harness.Floor`), timed in alternation with the "
        "path; ratio: plm_pin's time over the floor's.",
        "",
        "| mechanism | case | time per call | floor | ratio |",
        "|---|---|---|---|---|",
    ]
    lines += [_timing_line(r) for r in results["timings"]]
    if results.get("simulation"):
        lines += [
            "",
            f"{h}# Simulation",
            "",
            f"One run each (wall time), except the four-bar's default and MuJoCo RK4 rows: the best of "
            f"{SIM_ROUNDS} alternating runs of both, whose ratio is the cost column. "
            "Closure error: largest over the samples (for plm_pin after the "
            "projection; the drift the integrator reached before it is in the last column). Energy "
            "drift: largest |E - E0| over the peak kinetic energy.",
            "",
            "| engine | mechanism | case | max closure error [m] | crank error at 1 s [rad] | energy drift "
            "| us per step | ms per simulated s | cost / MuJoCo RK4 | total | drift before projection [m] |",
            "|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        lines += [_simulation_line(r) for r in results["simulation"]]
    if results.get("sweep"):
        lines += [
            "",
            f"{h}# Design sweeps (plm_pin.sweep)",
            "",
            "One run each (wall time), results identical on both executors (tested). The cluster's start-up "
            "is timed apart.",
            "",
            "| sweep | executor | poses | seconds | poses per second | vs 1 process |",
            "|---|---|---|---|---|---|",
        ]
        lines += [_sweep_line(r) for r in results["sweep"]]
    if results.get("notes"):
        lines += ["", f"{h}# Notes", "", *(f"- {n}" for n in results["notes"])]
    return "\n".join(lines) + "\n"


DOCS_TABLE = Path(__file__).resolve().parents[1] / "docs" / "_generated" / "benchmarks.md"
"""The generated tables the docs' benchmark page includes (written by ``make bench``, committed)."""

GENERATED = "<!-- generated by `make bench` (benchmarks/harness.py) from results.json: do not edit -->"
"""First line of the docs' generated tables."""


def write(
    rows: list[dict[str, object]],
    out: Path,
    notes: tuple[str, ...] = (),
    simulation: list[dict[str, object]] | None = None,
    sweep: list[dict[str, object]] | None = None,
    docs: Path | None = None,
    info: dict[str, object] | None = None,
) -> Path:
    """Write ``results.md`` (date and machine, tables, then ``notes``) and ``results.json`` into ``out``.

    ``results.json`` holds ``{"machine", "timings", "simulation", "sweep", "notes"}``; with
    ``docs``, the same tables are written there for the docs' benchmark page.

    Returns:
        The Markdown path.
    """
    results = {
        "machine": info or machine(),
        "timings": rows,
        "simulation": simulation or [],
        "sweep": sweep or [],
        "notes": list(notes),
    }
    out.mkdir(parents=True, exist_ok=True)
    md = out / "results.md"
    md.write_text(markdown(results))
    (out / "results.json").write_text(json.dumps(results, indent=2))
    if docs is not None:
        write_docs(results, docs)
    return md


def write_docs(results: dict[str, Any], docs: Path = DOCS_TABLE) -> None:
    """Write a run's tables for the docs' benchmark page (title one level down, the generator named)."""
    docs.parent.mkdir(parents=True, exist_ok=True)
    docs.write_text(GENERATED + "\n\n" + markdown(results, level=2, title="The latest run"))


def main() -> None:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("reports/bench"), help="output folder")
    parser.add_argument(
        "--docs", type=Path, default=None, help="also write the tables for the docs page here"
    )
    parser.add_argument(
        "--from-json",
        type=Path,
        default=None,
        help="rewrite the tables from a results.json",
    )
    args = parser.parse_args()
    if args.from_json is not None:
        results = json.loads(args.from_json.read_text())
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "results.md").write_text(markdown(results))
        if args.docs is not None:
            write_docs(results, args.docs)
        print(markdown(results))
        return
    info = machine()  # the load average before the benchmark adds its own
    rows = run()
    placo_rows, placo_note = placo_benchmark()
    md = write(
        rows + placo_rows,
        args.out,
        (fig6_note(), placo_note),
        simulation_benchmark(),
        sweep_benchmark() + optimize_benchmark(),
        docs=args.docs,
        info=info,
    )
    print(md.read_text())


if __name__ == "__main__":
    main()
