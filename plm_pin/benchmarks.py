"""Benchmarks: cost per call of the core paths, written as a Markdown table.

Run with ``make bench`` (or ``python -m plm_pin.benchmarks --out reports/bench``). A
benchmark measures; correctness is asserted by the test suite, never here. Besides the
cost per call of loading, closures, assembly, kinematics and manipulability for every
preset, it records the wall time of a 10^5-pose manipulability map of
``harada2011_3d4m`` and, as a reproduction note, the 3D3M's singular angle of Harada
2011 Fig. 6.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import os
import platform
import tempfile
import time
import timeit
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin

from .analysis import manipulability, singular_points_along, workspace_map
from .description.writer import write_description
from .kinematics import (
    classify,
    closed_chain_jacobians,
    forward_kinematics,
    inverse_kinematics,
    task_pose,
)
from .loading import load
from .models.registry import PRESETS, preset_names

MAP_SHAPE = (317, 316)
"""Grid of the manipulability-map benchmark: 100,172 poses."""


def _per_call(fn: Callable[[], object], min_time: float = 0.2) -> float:
    """Best-of-5 time per call [s], with the repeat count chosen to last ``min_time``."""
    timer = timeit.Timer(fn)
    number, _ = timer.autorange()
    number = max(1, int(number * min_time / 0.2))
    return min(timer.repeat(repeat=5, number=number)) / number


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
                forward_kinematics, mech, c, q, all_modes=True
            ),
            "closed_chain_jacobians": functools.partial(closed_chain_jacobians, mech, q),
            "manipulability": functools.partial(manipulability, mech, q),
            "classify": functools.partial(classify, mech, q),
        }
        for case, fn in cases.items():
            rows.append({"mechanism": name, "case": case, "seconds_per_call": _per_call(fn)})
    rows.append(map_benchmark())
    return rows


def map_benchmark(shape: tuple[int, int] = MAP_SHAPE, workers: int | None = None) -> dict[str, object]:
    """Wall time of one manipulability map of ``harada2011_3d4m`` over an x-y grid at theta = -20 deg.

    x in [-0.1, 0.1] m, y in [0.01, 0.12] m (all reachable), ``workers`` processes
    (default: all CPUs). One run, not best of 5: the map takes seconds.
    """
    mech = load("harada2011_3d4m")
    values = (np.linspace(-0.1, 0.1, shape[0]), np.linspace(0.01, 0.12, shape[1]))
    used = workers if workers is not None else (os.cpu_count() or 1)
    start = time.perf_counter()
    result = workspace_map(mech, ("x", "y"), values, (0.0, 0.08, math.radians(-20.0)), workers=used)
    seconds = time.perf_counter() - start
    n = shape[0] * shape[1]
    return {
        "mechanism": "harada2011_3d4m",
        "case": (
            f"workspace_map x-y {shape[0]} x {shape[1]} = {n} poses at theta = -20 deg "
            f"({100 * result.reachable_fraction:.0f}% reachable, {used} process(es), "
            f"{seconds / n * 1e6:.0f} us/pose, wall time)"
        ),
        "seconds_per_call": seconds,
    }


def fig6_note() -> str:
    """Harada 2011 Fig. 6: the 3D3M's type-4 singular angle at the y where eq. (11.4) gives 28.7 deg.

    The table with l : 2 r_t = 2 : 1 (r_t = l / 4) is built, written and loaded; the angle
    is located by root finding along theta (:func:`plm_pin.analysis.singular_points_along`).
    """
    params = {**PRESETS["harada2011_3d3m"].parameters}
    l = float(params["rod_lengths"][0])
    rt = l / 4.0
    params["half_plate"] = rt
    robot, sidecar = PRESETS["harada2011_3d3m"].builder(
        name="fig6_3d3m", source="Harada 2011 Fig. 6", **params
    )
    with tempfile.TemporaryDirectory() as folder:
        write_description(robot, sidecar, folder, "fig6_3d3m")
        mech = load(Path(folder) / "fig6_3d3m.urdf")
    y = (l + rt) * math.sin(math.radians(28.7))
    points = singular_points_along(mech, "rz", np.radians(np.linspace(-80.0, 80.0, 65)), (0.0, y, 0.0))
    angles = ", ".join(f"{math.degrees(p.parameter):.2f} deg ({p.kind})" for p in points)
    return (
        f"Harada 2011 Fig. 6 (l = {l:.3f} m, r_t = l/4 = {rt:.4f} m): at y = {y:.6f} m = {y / l:.4f} l "
        f"(where eq. (11.4) gives 28.7 deg), the 3D3M's singular angle found numerically: {angles}."
    )


def _fmt(seconds: float) -> str:
    return f"{seconds * 1e6:.1f} us" if seconds < 1e-3 else f"{seconds * 1e3:.2f} ms"


def write(rows: list[dict[str, object]], out: Path, notes: tuple[str, ...] = ()) -> Path:
    """Write ``results.md`` (table, then ``notes``) and ``results.json`` (rows) into ``out``.

    Returns:
        The Markdown path.
    """
    out.mkdir(parents=True, exist_ok=True)
    lines = [
        "# plm_pin benchmarks",
        "",
        f"Machine: {platform.machine()}, Python {platform.python_version()}, "
        f"Pinocchio {pin.__version__}. Best of 5 repeats.",
        "",
        "| mechanism | case | time per call |",
        "|---|---|---|",
    ]
    lines += [f"| {r['mechanism']} | {r['case']} | {_fmt(float(r['seconds_per_call']))} |" for r in rows]  # type: ignore[arg-type]
    if notes:
        lines += ["", "## Notes", "", *(f"- {n}" for n in notes)]
    md = out / "results.md"
    md.write_text("\n".join(lines) + "\n")
    (out / "results.json").write_text(json.dumps(rows, indent=2))
    return md


def main() -> None:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("reports/bench"), help="output folder")
    args = parser.parse_args()
    md = write(run(), args.out, (fig6_note(),))
    print(md.read_text())


if __name__ == "__main__":
    main()
