"""Benchmarks: cost per call of the core paths, written as a Markdown table.

Run with ``make bench`` (or ``python -m plm_pin.benchmarks --out reports/bench``). A
benchmark measures; correctness is asserted by the test suite, never here.
"""

from __future__ import annotations

import argparse
import functools
import json
import platform
import timeit
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin

from .loading import load
from .models.registry import preset_names


def _per_call(fn: Callable[[], object], min_time: float = 0.2) -> float:
    """Best-of-5 time per call [s], with the repeat count chosen to last ``min_time``."""
    timer = timeit.Timer(fn)
    number, _ = timer.autorange()
    number = max(1, int(number * min_time / 0.2))
    return min(timer.repeat(repeat=5, number=number)) / number


def run() -> list[dict[str, object]]:
    """Time loading, closure residual, closure Jacobian and assembly for every preset."""
    rows: list[dict[str, object]] = []
    for name in preset_names():
        mech = load(name)
        q = mech.q_ref
        guess = pin.integrate(mech.model, q, np.full(mech.nv, 1e-3))
        actuated = [a.joint for a in mech.actuators]
        cases: dict[str, Callable[[], object]] = {
            "load": functools.partial(load, name),
            "closure_residual": functools.partial(mech.closure_residual, q),
            "closure_jacobian": functools.partial(mech.closure_jacobian, q),
            "assemble (actuators fixed, 1e-3 rad/m off)": functools.partial(
                mech.assemble, guess, fixed=actuated
            ),
        }
        for case, fn in cases.items():
            rows.append({"mechanism": name, "case": case, "seconds_per_call": _per_call(fn)})
    return rows


def _fmt(seconds: float) -> str:
    return f"{seconds * 1e6:.1f} us" if seconds < 1e-3 else f"{seconds * 1e3:.2f} ms"


def write(rows: list[dict[str, object]], out: Path) -> Path:
    """Write ``results.md`` and ``results.json`` into ``out``; return the Markdown path."""
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
    md = out / "results.md"
    md.write_text("\n".join(lines) + "\n")
    (out / "results.json").write_text(json.dumps(rows, indent=2))
    return md


def main() -> None:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("reports/bench"), help="output folder")
    args = parser.parse_args()
    md = write(run(), args.out)
    print(md.read_text())


if __name__ == "__main__":
    main()
