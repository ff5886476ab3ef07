"""The ``plm-pin`` command line: presets, checking descriptions, reports, sweeps, optimisation."""

from __future__ import annotations

import contextlib
import csv
import json
import math
import multiprocessing
import os
import shlex
import signal
import sys
import threading
import warnings
import webbrowser
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    SpinnerColumn,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
)
from rich.table import Table
from typer.core import TyperGroup

from ._io import atomic_path, atomic_write_text
from ._version import __version__
from .core.diagnostics import findings, mobility_text
from .core.mechanism import Mechanism, joint_type
from .exceptions import ClosureNotSatisfied, InvalidInput, NoFeasibleDesign, PlmError
from .export import export_mjcf
from .kinematics import error_bound, error_model, forward_kinematics, inverse_kinematics, task_pose
from .kinematics.reference import reference_findings, reference_report
from .loading import load
from .models.registry import PRESETS
from .optimize import OptimizationResult, run_problem
from .optimize import load_config as load_optimize_config
from .report import Animation, Study, StudyCase, find_study, run_study, study_names, write_index, write_report
from .report.animation import parse_case
from .report.optimization import optimization_report
from .report.render import require_renderer
from .report.study import compute_animation, studies_hint
from .report.writer import output_folder
from .sweep import load_config, run_spec
from .sweep.execution import DEFAULT_CHUNK
from .viz.inspect_server import Inspector
from .viz.meshcat_server import MeshcatServer
from .viz.meshcat_view import MeshcatViewer, SceneStatus
from .warnings import PlmWarning
from .workspace import POSE_METRICS, WorkspaceSlice, manipulability_unit, workspace_map


class _Commands(TyperGroup):
    """The command group: an operating-system error (disk full, no permission) is one line, no traceback."""

    def invoke(self, ctx: Any) -> Any:  # a click Context (typer vendors click)
        """Run the command; an ``OSError`` is printed as one line naming the file, with exit code 1."""
        try:
            return super().invoke(ctx)
        except OSError as exc:
            where = f"{exc.filename}: " if exc.filename is not None else ""
            hint = " (a file stands where a folder is needed)" if isinstance(exc, FileExistsError) else ""
            raise _fail(PlmError(f"{where}{exc.strerror or exc}{hint}")) from None


app = typer.Typer(
    cls=_Commands,
    name="plm-pin",
    help="Analyse parallel link mechanisms: closed chains described by a URDF tree plus cut joints.",
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode=None,  # help texts hold units in brackets, [m, rad]: plain text, not rich markup
    pretty_exceptions_enable=False,
)
console = Console()
errors = Console(stderr=True)

EXTRAS = {
    "jinja2": "report",
    "markdown_it": "report",
    "matplotlib": "viz",
    "meshcat": "viz",
    "umsgpack": "viz",
    "dask": "sweep",
    "distributed": "sweep",
    "xarray": "sweep",
    "pyarrow": "sweep",
    "pandas": "sweep",
    "pymoo": "optimize",
    "example_robot_data": "erd",
}
"""The optional extra of plm-pin that provides each optional top-level module."""


def _version(value: bool) -> None:
    if value:
        console.print(f"plm-pin {__version__}", markup=False, highlight=False)
        raise typer.Exit()


@app.callback()
def _options(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_version, is_eager=True, help="print the version and exit"),
    ] = False,
) -> None:
    """Analyse parallel link mechanisms: closed chains described by a URDF tree plus cut joints."""


def missing_extra(exc: ImportError) -> str:
    """One line for a missing optional dependency: the module, and the extra that installs it."""
    message = str(exc)
    if "pip install" in message:  # plm_pin's own message already names the extra
        return message
    module = (exc.name or "").split(".")[0]
    extra = EXTRAS.get(module)
    if extra is None:
        return f"{message} (a dependency of plm-pin is missing: reinstall it)"
    return f"this command needs {module}, which is not installed: pip install 'plm-pin[{extra}]'"


def main() -> None:
    """Entry point of ``plm-pin`` and ``python -m plm_pin``: a missing optional extra is one line."""
    try:
        app()
    except ImportError as exc:
        errors.print(f"[bold red]error:[/] {escape(missing_extra(exc))}", highlight=False, soft_wrap=True)
        sys.exit(1)


def _fail(exc: Exception) -> typer.Exit:
    errors.print(f"[bold red]error:[/] {escape(str(exc))}", markup=True, highlight=False, soft_wrap=True)
    return typer.Exit(code=1)


@contextlib.contextmanager
def _reported() -> Iterator[None]:
    """Print plm_pin's warnings on stderr, and turn its errors into one line and exit 1."""
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", PlmWarning)
            yield
    except PlmError as exc:
        raise _fail(exc) from None
    finally:
        for w in caught:
            errors.print(f"[yellow]warning:[/] {escape(str(w.message))}", highlight=False, soft_wrap=True)


IgnoreOption = Annotated[
    str,
    typer.Option(
        "--ignore",
        help="MJCF elements to drop rather than refuse, comma-separated: "
        "contacts, tendons, joint_equalities, inactive_equalities, actuators",
    ),
]
"""The ``--ignore`` option of the commands that load a mechanism (see ``plm_pin.load``)."""

ClosureTolOption = Annotated[
    float | None,
    typer.Option(
        "--closure-tol",
        help="how far the description's loops close [m, rad] (a CAD export rounded to a few digits); "
        "default: the sidecar's closure_tolerance, else 1e-12",
    ),
]
"""The ``--closure-tol`` option of ``info`` and ``check`` (see ``plm_pin.load``)."""


def _load(target: str | Path, ignore: str = "", closure_tol: float | None = None) -> Mechanism:
    """Load a mechanism, printing its warnings on stderr and turning errors into exit 1."""
    with _reported():
        mech = load(target, ignore=ignore, closure_tol=closure_tol)
        mech.summary()  # computes mobility now, inside the error handling
    return mech


def _preset_rows() -> list[dict[str, Any]]:
    return [
        {
            "name": p.name,
            "paper": p.source,
            "dof": p.dof,
            "actuators": p.actuators,
            "redundancy": p.redundancy,
        }
        for p in PRESETS.values()
    ]


@app.command("list")
def list_presets() -> None:
    """List the presets: name, paper, DOF, actuators, redundancy."""
    table = Table(title="plm_pin presets")
    table.add_column("name", no_wrap=True)  # names are typed back: never folded
    for col in ("paper", "DOF", "actuators", "redundancy"):
        table.add_column(col, overflow="fold")
    for row in _preset_rows():
        table.add_row(
            row["name"], escape(row["paper"]), str(row["dof"]), str(row["actuators"]), str(row["redundancy"])
        )
    console.print(table)


def _rank_gap_text(gap: dict[str, Any]) -> str:
    """The closure rank and the singular values around its cut (:meth:`RankGap.to_dict` data)."""
    if gap["fixed"]:
        return f"rank {gap['rank']} fixed by the description's mobility"
    above = "none" if gap["above"] is None else f"{gap['above']:.3g}"
    ratio = "exact zeros below" if gap["ratio"] is None else f"ratio {gap['ratio']:.3g}"
    return f"rank {gap['rank']}: singular values {above} | {gap['below']:.3g} ({ratio})"


@app.command()
def info(
    target: Annotated[str, typer.Argument(help="preset name, erd:<robot>, .urdf, .plm.yaml or folder")],
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False,
    ignore: IgnoreOption = "",
    closure_tol: ClosureTolOption = None,
) -> None:
    """Sizes, joints, closures, actuators, task, mobility, redundancy, the reference (pose, modes)."""
    mech = _load(target, ignore, closure_tol)
    summary = mech.summary()
    with _reported():
        reference = reference_report(mech)
    summary["reference"] = {
        "q": reference.q.tolist(),
        "pose": reference.pose.tolist(),
        "working_mode": list(reference.working_mode),
        "assembly_mode": reference.assembly_mode,
        "singularity_margins": reference.margins,
    }
    if as_json:
        console.print_json(json.dumps(summary))
        return
    table = Table(title=escape(summary["name"]), show_header=False)
    table.add_column("item")
    table.add_column("value", overflow="fold")
    table.add_row("source", escape(summary["source"]))
    table.add_row("nq / nv", f"{summary['nq']} / {summary['nv']}")
    table.add_row("joints", escape(", ".join(f"{j['name']} ({j['type']})" for j in summary["joints"])))
    for c in summary["closures"]:
        table.add_row(
            escape(f"closure {c['name']}"),
            escape(f"{c['type']} ({c['rows']} rows): {c['frames'][0]} = {c['frames'][1]}"),
        )
    for a in summary["actuators"]:
        unit = "N" if a["kind"] == "prismatic" else "N m"
        limits = "unbounded" if a["limits"] is None else f"[{a['limits'][0]:g}, {a['limits'][1]:g}] {unit}"
        table.add_row(escape(f"actuator {a['joint']}"), escape(f"{a['kind']}, effort limits {limits}"))
    task = summary["task"]
    table.add_row(
        "task",
        "none" if task is None else escape(f"{task['frame'] or 'output joints'}: {' '.join(task['dofs'])}"),
    )
    table.add_row(
        "mobility",
        str(summary["mobility"])
        + (f" ({summary['idle_mobility']} idle held)" if summary["idle_mobility"] else ""),
    )
    red = summary["redundancy"]
    table.add_row("redundancy", f"{red}" + (" (under-actuated)" if red < 0 else ""))
    dofs = mech.task.dofs if mech.task is not None else ()
    table.add_row("reference", escape(reference.describe(dofs)))
    table.add_row("reference residual", f"{summary['reference_residual']:.3g} m/rad")
    table.add_row("closure tolerance", f"{summary['closure_tolerance']:.3g} m/rad")
    table.add_row("rank gap", _rank_gap_text(summary["rank_gap"]))
    table.add_row("gravity", f"{summary['gravity']} m/s^2")
    console.print(table)


@app.command()
def check(
    path: Annotated[Path, typer.Argument(help="a .urdf, .plm.yaml, .xml or description folder")],
    ignore: IgnoreOption = "",
    closure_tol: ClosureTolOption = None,
) -> None:
    """Validate a description and say exactly what is wrong and where (idle DOF, task size, limits)."""
    mech = _load(path, ignore, closure_tol)
    summary = mech.summary()
    with _reported():
        found = tuple(
            sorted((*findings(mech), *reference_findings(mech)), key=lambda f: f.severity != "error")
        )
    for finding in found:
        prefix = "[bold red]error:[/]" if finding.severity == "error" else "[cyan]note:[/]"
        target = errors if finding.severity == "error" else console
        target.print(f"{prefix} {escape(finding.message)}", highlight=False, soft_wrap=True)
    if any(f.severity == "error" for f in found):
        raise typer.Exit(code=1)
    console.print(
        f"[green]ok[/]: {escape(summary['name'])}: {len(mech.sidecar.closures)} closures, "
        f"{len(summary['actuators'])} actuators, mobility {mobility_text(mech)}, redundancy "
        f"{summary['redundancy']}, reference residual {summary['reference_residual']:.2g} "
        f"(closure tolerance {mech.closure_tol:.2g})",
        highlight=False,
        soft_wrap=True,
    )


MODE_SIGNS = {"+": 1, "+1": 1, "1": 1, "-": -1, "-1": -1}
"""The words of a working-mode sign in ``--mode`` (comma-separated, one per square leg)."""


def _named_words(
    words: Sequence[str],
    what: str,
    example: str,
    names: Sequence[str] | None = None,
    kind: str = "a valid name",
) -> dict[str, tuple[str, str]]:
    """``NAME=VALUE`` words as ``{name: (word, value text)}``, in their order: every shell assignment.

    Args:
        words: the words, one assignment each.
        what: the argument or option they come from, which starts every message.
        example: a valid use, quoted where a word is malformed.
        names: the valid names, listed where a word names another (None: any name, checked later).
        kind: what the valid names are, in the message (e.g. ``"a task coordinate of fivebar"``).

    Raises:
        InvalidInput: a word without ``=`` or name, an unknown or repeated name; the message
            names the word.
    """
    out: dict[str, tuple[str, str]] = {}
    for word in words:
        name, sep, text = word.strip().partition("=")
        if not sep or not name:
            raise InvalidInput(f"{what} {word!r}: write NAME=VALUE, e.g. {example}")
        if names is not None and name not in names:
            raise InvalidInput(f"{what} {word!r}: {name!r} is not {kind}, one of {list(names)}")
        if name in out:
            raise InvalidInput(f"{what} {word!r}: {name!r} is given twice")
        out[name] = (word, text)
    return out


def _assignments(
    words: Sequence[str],
    what: str,
    example: str,
    names: Sequence[str] | None = None,
    kind: str = "a valid name",
    *,
    vectors: bool = False,
) -> dict[str, list[float]]:
    """``NAME=VALUE`` words as ``{name: numbers}`` [m, rad].

    Args:
        words: the words, one assignment each.
        what: the argument or option they come from, which starts every message.
        example: a valid use, quoted where a word is malformed.
        names: the valid names (None: any name, checked later).
        kind: what the valid names are, in the message.
        vectors: VALUE may be several comma-separated numbers (a joint with several entries);
            otherwise exactly one.

    Raises:
        InvalidInput: as :func:`_named_words`, or a value that is not a finite number (or
            comma-separated finite numbers).
    """
    out: dict[str, list[float]] = {}
    for name, (word, text) in _named_words(words, what, example, names, kind).items():
        try:
            values = [float(v) for v in (text.split(",") if vectors else [text])]
        except ValueError:
            values = [float("nan")]
        if not np.all(np.isfinite(values)):
            number = "a finite number or finite numbers, comma-separated" if vectors else "a finite number"
            raise InvalidInput(f"{what} {word!r}: {text!r} is not {number}")
        out[name] = values
    return out


def _mode_signs(text: str | None, mech: Mechanism | None = None) -> tuple[int, ...] | None:
    """The working mode ``--mode`` writes as ``+,-,...`` (None: not given).

    Args:
        text: the option's value.
        mech: the mechanism, whose square legs each take a sign (None: counted later).

    Raises:
        InvalidInput: a word that is not a sign, or (with ``mech``) not one sign per square leg.
    """
    if text is None:
        return None
    words = [w.strip() for w in text.split(",")]
    n = sum(leg.square for leg in mech.legs) if mech is not None else len(words)
    if len(words) != n or any(w not in MODE_SIGNS for w in words):
        if mech is None:
            how = "give one sign (+ or -) per leg, comma-separated, e.g. --mode=+,-"
        else:
            example = ",".join("+-"[k % 2] for k in range(n))
            how = (
                f"give {n} signs (+ or -), comma-separated, one per leg of {mech.name}, e.g. --mode={example}"
            )
        raise InvalidInput(f"--mode {text!r}: {how}")
    return tuple(MODE_SIGNS[w] for w in words)


def _actuator_values(mech: Mechanism, assignments: list[str]) -> np.ndarray:
    """Actuator positions from ``JOINT=VALUE`` words, the others at their reference value."""
    values = mech.actuator_positions(mech.q_ref).copy()
    names = [a.joint for a in mech.actuators]
    example = f"{names[0]}=0.1" if names else "JOINT=0.1"
    for joint, number in _assignments(
        assignments, "actuator", example, names, f"an actuated joint of {mech.name}"
    ).items():
        values[names.index(joint)] = number[0]
    return values


@app.command("fk")
def fk_command(
    target: Annotated[str, typer.Argument(help="preset name, erd:<robot>, .urdf, .plm.yaml or folder")],
    assignments: Annotated[
        list[str] | None,
        typer.Argument(help="actuator positions JOINT=VALUE (m or rad); the others stay at their reference"),
    ] = None,
    all_modes: Annotated[
        bool, typer.Option("--all", help="every assembly mode, certified where possible")
    ] = False,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False,
) -> None:
    """Forward kinematics at given actuator positions; with --all every assembly mode and its proof."""
    mech = _load(target)
    with _reported():
        c = _actuator_values(mech, assignments or [])
        modes = forward_kinematics(mech, c, all_modes=all_modes)
    if as_json:
        console.print_json(json.dumps(modes.to_dict(), default=lambda a: np.asarray(a).tolist()))
        return
    task = mech.task.dofs if mech.task is not None else []
    if not all_modes:
        headline = "the reference assembly's mode (use --all for every mode)"
    else:
        headline = modes.headline()
    table = Table(title=escape(f"{mech.name}: {headline}"))
    table.add_column("mode")
    for dof in task:
        table.add_column(dof, justify="right")
    table.add_column("residual", justify="right")
    table.add_column("certificate")
    for i, s in enumerate(modes):
        certificate = "Krawczyk" if s.certified else "none"
        table.add_row(str(i + 1), *(f"{v:.6f}" for v in s.x), f"{s.residual_norm:.1e}", certificate)
    console.print(table)


def _task_dofs(mech: Mechanism, what: str) -> tuple[str, ...]:
    """The task coordinates of ``mech``.

    Raises:
        InvalidInput: a mechanism without a task (``what`` names the option that needs one).
    """
    if mech.task is None:
        raise InvalidInput(f"{what}: {mech.name} has no task (`end_effector` in its sidecar)")
    return tuple(mech.task.dofs)


def _task_units(mech: Mechanism) -> dict[str, str]:
    """The unit of each task coordinate: rad for angles (rotations, revolute output joints), else m."""
    task = mech.task_compiled
    dofs = _task_dofs(mech, "task units")
    angles = task.angles if task is not None else []
    return {d: "rad" if k in angles else "m" for k, d in enumerate(dofs)}


def _task_values(mech: Mechanism, words: list[str], what: str) -> dict[str, float]:
    """Task coordinates from ``NAME=VALUE`` words [m, rad].

    Raises:
        InvalidInput: a malformed word, an unknown or repeated coordinate, a value that is not a
            finite number; the message names the word and the task's coordinates.
    """
    dofs = _task_dofs(mech, what)
    return {
        k: v[0]
        for k, v in _assignments(
            words, what, f"{dofs[0]}=0.1", dofs, f"a task coordinate of {mech.name}"
        ).items()
    }


def _mode_text(mode: tuple[int, ...] | None) -> str:
    """A working mode as ``--mode`` takes it: ``+,-,...`` (0 for a leg at an inverse singularity)."""
    if mode is None:
        return "none"
    return ",".join({1: "+", -1: "-"}.get(int(m), "0") for m in mode) or "none (no square leg)"


def _joint_values(mech: Mechanism, q: np.ndarray) -> dict[str, float | list[float]]:
    """Each joint's configuration entries [m or rad]: one number, or a list for multi-entry joints."""
    out: dict[str, float | list[float]] = {}
    for name in mech.joint_names:
        joint = mech.model.joints[mech.model.getJointId(name)]
        part = [float(v) for v in q[joint.idx_q : joint.idx_q + joint.nq]]
        out[name] = part[0] if len(part) == 1 else part
    return out


_UNITS = {"prismatic": "m", "revolute": "rad"}
"""The unit of a one-axis joint's position, by joint type."""


ModeOption = Annotated[
    str | None,
    typer.Option("--mode", help="working mode: one sign per leg, comma-separated (--mode=+,-,+,-)"),
]


@app.command("ik")
def ik_command(
    target: Annotated[str, typer.Argument(help="preset name, erd:<robot>, .urdf, .plm.yaml or folder")],
    assignments: Annotated[
        list[str] | None,
        typer.Argument(
            help="the task pose NAME=VALUE (m or rad), every task coordinate (e.g. x=0 y=0.08 rz=-0.3)"
        ),
    ] = None,
    mode: ModeOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False,
) -> None:
    """Inverse kinematics at a task pose: joints, actuator positions, working mode, closure residual."""
    mech = _load(target)
    with _reported():
        dofs = _task_dofs(mech, "ik")
        values = _task_values(mech, assignments or [], "task coordinate")
        missing = [d for d in dofs if d not in values]
        if missing:
            raise InvalidInput(
                f"missing task coordinates {missing}: give every one of {list(dofs)} as NAME=VALUE"
            )
        sol = inverse_kinematics(mech, [values[d] for d in dofs], mode=_mode_signs(mode, mech))
        actuators, working = sol.actuators, sol.mode
        closure = float(np.max(np.abs(mech.closure_residual(sol.q)), initial=0.0))
    kinds = {n: joint_type(mech.model, mech.model.getJointId(n)) for n in mech.joint_names}
    for joint, by in sol.limit_violations.items():
        errors.print(
            f"[yellow]warning:[/] joint {escape(joint)} is outside its limits by {by:.3g} "
            f"{_UNITS.get(kinds.get(joint, ''), 'm or rad')}",
            highlight=False,
            soft_wrap=True,
        )
    joints = _joint_values(mech, np.asarray(sol.q))
    names = [a.joint for a in mech.actuators]
    if as_json:
        out = {
            "mechanism": mech.name,
            "x": dict(zip(dofs, sol.x.tolist(), strict=True)),
            "q": joints,
            "actuators": dict(zip(names, actuators.tolist(), strict=True)),
            "working_mode": list(working),
            "closure_residual": closure,
            "residual_norm": sol.residual_norm,
            "limit_violations": dict(sol.limit_violations),
        }
        console.print_json(json.dumps(out))
        return
    units = _task_units(mech)
    table = Table(title=escape(f"{mech.name}: inverse kinematics"), show_header=False)
    table.add_column("item")
    table.add_column("value", justify="right")
    table.add_column("unit")
    for dof, v in zip(dofs, sol.x, strict=True):
        table.add_row(escape(f"task {dof}"), f"{v:.9g}", units[dof])
    for joint, v in joints.items():
        text = f"{v:.9g}" if isinstance(v, float) else ", ".join(f"{e:.9g}" for e in v)
        table.add_row(escape(f"joint {joint}"), text, _UNITS.get(kinds.get(joint, ""), ""))
    for act, v in zip(mech.actuators, actuators, strict=True):
        table.add_row(escape(f"actuator {act.joint}"), f"{v:.9g}", _UNITS.get(act.kind, ""))
    table.add_row("working mode", _mode_text(working), "")
    table.add_row("closure residual", f"{closure:.3g}", "m, rad")
    console.print(table)


def _length_and_angle(text: str) -> tuple[float, float]:
    """``--tol LENGTH,ANGLE`` as two numbers >= 0 [m, rad].

    Raises:
        InvalidInput: not two comma-separated finite numbers >= 0.
    """
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 2 or not all(np.isfinite(v) and v >= 0 for v in values):
        given = f"--tol {text!r}" if text else "--tol is required"
        raise InvalidInput(
            f"{given}: write LENGTH,ANGLE, the tolerance of every placement translation and "
            "prismatic actuator offset [m] and of every placement rotation and revolute actuator offset "
            "[rad], e.g. --tol 1e-5,1e-4"
        )
    return values[0], values[1]


@app.command("accuracy")
def accuracy_command(
    target: Annotated[str, typer.Argument(help="preset name, erd:<robot>, .urdf, .plm.yaml or folder")],
    assignments: Annotated[
        list[str] | None,
        typer.Argument(help="task coordinates NAME=VALUE (m or rad); the others at the reference pose"),
    ] = None,
    tol: Annotated[
        str,
        typer.Option(
            "--tol",
            help="LENGTH,ANGLE: tolerance of every joint and closure-frame placement and actuator offset, "
            "[m] for translations and prismatic actuators, [rad] for rotations and revolute ones",
        ),
    ] = "",
    top: Annotated[int, typer.Option("--top", min=1, help="largest contributions listed per coordinate")] = 3,
    mode: ModeOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False,
) -> None:
    """Pose error bound for manufacturing tolerances: worst case, RMS and the largest contributions."""
    mech = _load(target)
    with _reported():
        length, angle = _length_and_angle(tol)
        dofs = _task_dofs(mech, "accuracy")
        values = _task_values(mech, assignments or [], "task coordinate")
        if values or mode is not None:
            x = task_pose(mech, mech.q_ref)
            for dof, value in values.items():
                x[dofs.index(dof)] = value
            q = np.asarray(inverse_kinematics(mech, x, mode=_mode_signs(mode, mech)).q)
        else:
            q = np.asarray(mech.q_ref)
        model = error_model(mech)
        bound = error_bound(mech, q, model.tolerances(length, angle))
    if as_json:
        out = {
            "mechanism": mech.name,
            "x": dict(zip(dofs, task_pose(mech, q).tolist(), strict=True)),
            **bound.to_dict(),
            "length_tolerance": length,
            "angle_tolerance": angle,
        }
        console.print_json(json.dumps(out))
        return
    units = _task_units(mech)
    pose = ", ".join(f"{d}={v:.6g}" for d, v in zip(dofs, task_pose(mech, q), strict=True))
    title = f"{mech.name} at {pose}: pose error for tolerances {length:g} m, {angle:g} rad"
    table = Table(title=escape(title))
    for col in ("coordinate", "worst case", "rms", "unit", "largest contributions (|S| tol)"):
        table.add_column(col, justify="right" if col in ("worst case", "rms") else "left")
    for k, dof in enumerate(dofs):
        share = ", ".join(f"{name} {value:.3g}" for name, value in bound.contributions(k, top))
        table.add_row(dof, f"{bound.worst_case[k]:.4g}", f"{bound.rms[k]:.4g}", units[dof], escape(share))
    console.print(table)
    opened = int(np.sum(bound.sensitivity.mismatch * bound.tolerances > mech.assembled_tol))
    console.print(
        f"{model.size} parameters: {len(model.joints)} joint placements and {len(model.frames)} closure "
        f"frames x 6 (x y z [m], rx ry rz [rad]), {len(model.actuators)} actuator offsets; {opened} of "
        "them, at their tolerance, open the rigid loops (their effect is a least-squares fit)",
        markup=False,
        highlight=False,
        soft_wrap=True,
    )


AXES = ("x", "y", "z", "rx", "ry", "rz")
"""The task coordinates a slice can vary: options ``--x START:STOP:COUNT`` of ``map`` and ``report``."""


def _axis_option(axis: str) -> Any:
    return typer.Option(
        f"--{axis}",
        help=f"vary {axis} over START:STOP:COUNT, in {'rad' if axis.startswith('r') else 'm'} "
        "(COUNT >= 2 evenly spaced values)",
    )


XOption = Annotated[str | None, _axis_option("x")]
YOption = Annotated[str | None, _axis_option("y")]
ZOption = Annotated[str | None, _axis_option("z")]
RxOption = Annotated[str | None, _axis_option("rx")]
RyOption = Annotated[str | None, _axis_option("ry")]
RzOption = Annotated[str | None, _axis_option("rz")]


def _grid_range(text: str, option: str, joiner: str = " ") -> np.ndarray:
    """The values ``START:STOP:COUNT`` stands for: COUNT evenly spaced from START to STOP.

    ``option`` and ``joiner`` write the example of the message (``--x -0.05:0.05:21``).

    Raises:
        InvalidInput: naming the option, the text and what is wrong with it.
    """
    parts = text.split(":")
    problem = None
    if len(parts) != 3:
        problem = f"expected 3 fields separated by ':', got {len(parts)}"
    else:
        try:
            start, stop = float(parts[0]), float(parts[1])
        except ValueError:
            start = stop = float("nan")
        try:
            count = int(parts[2])
        except ValueError:
            count = 0
            problem = f"COUNT {parts[2]!r} is not a whole number"
        if not (np.isfinite(start) and np.isfinite(stop)):
            problem = "START and STOP must be finite numbers"
        elif start >= stop:
            problem = "START must be below STOP"
        elif problem is None and count < 2:
            problem = "COUNT must be at least 2"
    if problem is not None:
        raise InvalidInput(
            f"{option} {text!r}: {problem}; write START:STOP:COUNT (e.g. {option}{joiner}-0.05:0.05:21)"
        )
    return np.linspace(start, stop, count)


def _slice_ranges(
    mech: Mechanism, given: dict[str, str | None], over: Sequence[str] = ()
) -> dict[str, np.ndarray]:
    """The varied task coordinates and their values, in the task's order (empty when none given).

    Args:
        mech: the mechanism.
        given: the text of each option ``--x`` ... ``--rz`` (None: not given).
        over: ``--over NAME=START:STOP:COUNT`` words, for any task coordinate (a joint task's too).

    Raises:
        InvalidInput: a malformed range, a coordinate given twice, or one the task does not have.
    """
    ranges = {a: _grid_range(text, f"--{a}") for a, text in given.items() if text is not None}
    if over:
        dofs = _task_dofs(mech, "--over")
        words = _named_words(
            over, "--over", f"--over {dofs[0]}=-0.1:0.1:21", dofs, f"a task coordinate of {mech.name}"
        )
        for name, (word, text) in words.items():
            if name in ranges:
                raise InvalidInput(f"--over {word!r}: {name!r} is also varied by --{name}; give it one way")
            ranges[name] = _grid_range(text, f"--over {name}", "=")
    if not ranges:
        return {}
    dofs = _task_dofs(mech, " ".join(f"--{a}" for a in ranges))
    for a in ranges:
        if a not in dofs:
            raise InvalidInput(
                f"--{a}: {mech.name}'s task has no coordinate {a!r}; its coordinates are {list(dofs)}"
            )
    return {d: ranges[d] for d in dofs if d in ranges}


def _csv_target(path: Path, force: bool) -> Path:
    """``path`` checked as the CSV file to write: its folder exists, and it is new unless ``force``.

    Raises:
        InvalidInput: a missing folder, a folder in its place, an existing file without ``force``.
    """
    if not path.parent.is_dir():
        raise InvalidInput(f"--csv {path}: the folder {path.parent} does not exist")
    if path.is_dir():
        raise InvalidInput(f"--csv {path}: a folder stands there; give a file name")
    if path.exists() and not force:
        raise InvalidInput(f"--csv {path}: the file exists; give --force to overwrite it")
    return path


def _metric_names(text: str) -> list[str]:
    """The metrics ``--metric`` asks for: comma-separated names of POSE_METRICS, or ``all``.

    Raises:
        InvalidInput: an unknown name, listing the metrics.
    """
    if text.strip() == "all":
        return list(POSE_METRICS)
    names = [m.strip() for m in text.split(",")]
    for name in names:
        if name not in POSE_METRICS:
            raise InvalidInput(f"--metric {name!r}: unknown metric; metrics are {list(POSE_METRICS)} or all")
    return list(dict.fromkeys(names))


def _write_map_csv(path: Path, mech: Mechanism, grid: WorkspaceSlice, metrics: list[str]) -> None:
    """One row per grid pose: the task coordinates, whether reached, the metrics (nan where not)."""
    units = _task_units(mech)
    metric_units = {name: "-" for name in POSE_METRICS} | {"manipulability": manipulability_unit(mech)}
    header = [
        *(f"{d} [{units[d]}]" for d in grid.dofs),
        "reachable",
        *(f"{m} [{metric_units[m]}]" for m in metrics),
    ]
    poses = grid.poses().reshape(-1, len(grid.dofs))
    reached = grid.reachable.reshape(-1)
    values = [grid.metric(m).reshape(-1) for m in metrics]
    with atomic_path(path) as tmp, tmp.open("w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream)
        writer.writerow(header)
        for k in range(reached.size):
            writer.writerow(
                [*(repr(float(v)) for v in poses[k]), int(reached[k]), *(repr(float(v[k])) for v in values)]
            )


@app.command("map")
def map_command(
    target: Annotated[str, typer.Argument(help="preset name, erd:<robot>, .urdf, .plm.yaml or folder")],
    csv_path: Annotated[Path, typer.Option("--csv", help="the CSV file to write (its folder must exist)")],
    x: XOption = None,
    y: YOption = None,
    z: ZOption = None,
    rx: RxOption = None,
    ry: RyOption = None,
    rz: RzOption = None,
    fixed: Annotated[
        list[str] | None,
        typer.Option(
            "--fixed", help="a fixed task coordinate NAME=VALUE, repeatable (default: the reference's)"
        ),
    ] = None,
    metric: Annotated[
        str,
        typer.Option(
            "--metric", help=f"the metrics computed: comma-separated, among {', '.join(POSE_METRICS)}, or all"
        ),
    ] = "manipulability",
    over: Annotated[
        list[str] | None,
        typer.Option(
            "--over",
            help="vary any task coordinate NAME=START:STOP:COUNT, e.g. a joint of a joint task "
            "(--over elbow=-1:1:21), repeatable",
        ),
    ] = None,
    mode: ModeOption = None,
    force: Annotated[bool, typer.Option("--force", help="overwrite an existing CSV file")] = False,
) -> None:
    """A workspace map over two task coordinates, written as CSV (one row per pose) and summarised."""
    mech = _load(target)
    with _reported():
        ranges = _slice_ranges(mech, {"x": x, "y": y, "z": z, "rx": rx, "ry": ry, "rz": rz}, over or [])
        dofs = _task_dofs(mech, "map")
        if len(ranges) != 2:
            options = [f"--{d}" if d in AXES else f"--over {d}=..." for d in dofs]
            raise InvalidInput(f"a map varies two task coordinates: give two of {options}, got {len(ranges)}")
        values = _task_values(mech, fixed or [], "--fixed")
        both = [d for d in values if d in ranges]
        if both:
            raise InvalidInput(f"--fixed {both[0]}: it is also varied (--{both[0]}); give it one way")
        metrics = _metric_names(metric)
        path = _csv_target(csv_path, force)
        pose = task_pose(mech, mech.q_ref)
        for d, v in values.items():
            pose[dofs.index(d)] = v
        (a, va), (b, vb) = ranges.items()
        grid = workspace_map(mech, (a, b), (va, vb), pose, mode=_mode_signs(mode, mech), metrics=metrics)
    _write_map_csv(path, mech, grid, metrics)
    units = _task_units(mech)
    table = Table(title=escape(f"{mech.name}: workspace map over {a} and {b}"), show_header=False)
    table.add_column("item")
    table.add_column("value", justify="right")
    table.add_column("unit")
    table.add_row("poses", f"{va.size} x {vb.size} = {va.size * vb.size}", "")
    for d in dofs:
        if d not in ranges:
            table.add_row(escape(f"fixed {d}"), f"{grid.pose[dofs.index(d)]:.6g}", units[d])
    table.add_row("reachable fraction", f"{grid.reachable_fraction:.3g}", "-")
    table.add_row("working mode", _mode_text(grid.working_mode), "")
    w_unit = manipulability_unit(mech)
    for m in metrics:
        reached = grid.metric(m)[grid.reachable]
        unit_text = w_unit if m == "manipulability" else "-"
        low, high = (
            (f"{float(np.min(reached)):.4g}", f"{float(np.max(reached)):.4g}") if reached.size else ("-", "-")
        )
        table.add_row(escape(f"{m} min / max"), f"{low} / {high}", escape(unit_text))
    console.print(table)
    console.print(f"wrote {path}", markup=False, highlight=False, soft_wrap=True)


@app.command("export")
def export_command(
    target: Annotated[str, typer.Argument(help="preset name, erd:<robot>, .urdf, .plm.yaml, .xml or folder")],
    mjcf: Annotated[
        Path | None, typer.Option("--mjcf", help="write a MuJoCo model (and its .plm.yaml task) to this .xml")
    ] = None,
    timestep: Annotated[float, typer.Option("--timestep", help="MuJoCo step [s]")] = 1e-3,
    integrator: Annotated[str, typer.Option("--integrator", help="RK4 or implicitfast")] = "RK4",
    ignore: IgnoreOption = "",
) -> None:
    """Write a mechanism for another tool: --mjcf OUT.xml for MuJoCo, loops closed by equalities."""
    if mjcf is None:
        raise _fail(InvalidInput("give a format to export to: --mjcf OUT.xml"))
    mech = _load(target, ignore)
    with _reported():
        error = export_mjcf(mech, mjcf, timestep=timestep, integrator=integrator)
    console.print(f"wrote {mjcf}: {error.describe()}", markup=False, highlight=False, soft_wrap=True)


OVERVIEW = "overview"
"""The study run on a mechanism given instead of a study (``plm-pin report path/to/robot.urdf``)."""


def _report_runs(target: str, mechanism: str | None) -> list[tuple[Study, str | None]]:
    """The studies to run and the mechanism each is asked to study (None: its own).

    Raises:
        InvalidInput: an unknown target, or ``--mechanism`` where it does not apply.
    """
    names = study_names()
    if target == "all":
        if mechanism is not None:
            raise InvalidInput("--mechanism picks the mechanism of one study; it does not go with 'all'")
        return [(find_study(name), None) for name in names]
    if target in names:
        study = find_study(target)
        if mechanism is not None and study.mechanism is None:
            raise InvalidInput(f"study {target!r} takes no --mechanism (it studies the paper's mechanisms)")
        return [(study, mechanism)]
    if target in PRESETS or Path(target).exists():
        if mechanism is not None:
            raise InvalidInput(f"{target!r} is a mechanism: give it alone, or as --mechanism of a study")
        return [(find_study(OVERVIEW), target)]
    raise InvalidInput(
        f"{target!r} is neither a study, 'all', a preset nor an existing path; studies are {names}"
        f"{studies_hint()}"
    )


def _regenerate(study: Study, mechanism: str | None, out: Path, case_words: list[str]) -> str:
    """The shell command that writes this study's report again (``case_words``: its case options)."""
    chosen = ["--mechanism", mechanism] if mechanism is not None else []
    return shlex.join(["plm-pin", "report", study.name, *chosen, *case_words, "--out", str(out)])


def _study_case(
    load_text: str | None,
    pose_text: str | None,
    mode_text: str | None,
    ranges: dict[str, str | None],
    over: Sequence[str] = (),
) -> tuple[StudyCase, list[str]]:
    """The case the ``report`` options ask for, and the options as words (for the regenerate command).

    ``over`` holds ``--over NAME=START:STOP:COUNT`` words: a range of any task coordinate (a
    joint task's too), as ``map`` takes them.

    Raises:
        InvalidInput: malformed numbers, pose items, signs or ranges, a coordinate varied
            twice (names are checked by the study).
    """
    words: list[str] = []
    load_values = None
    if load_text is not None:
        load_values = tuple(_numbers(load_text, "--load"))
        if not np.all(np.isfinite(load_values)):
            raise InvalidInput(f"--load {load_text!r}: the values must be finite numbers [N, N m]")
        words += ["--load", load_text]
    pose = {}
    if pose_text is not None:
        items = _assignments(pose_text.split(","), "--pose", "--pose x=0.01,y=0.08")
        pose = {name: v[0] for name, v in items.items()}
        words += ["--pose", pose_text]
    mode = _mode_signs(mode_text)
    if mode_text is not None:
        words += [f"--mode={mode_text}"]
    values = {}
    for axis, text in ranges.items():
        if text is not None:
            values[axis] = tuple(float(v) for v in _grid_range(text, f"--{axis}"))
            words += [f"--{axis}", text]
    for name, (word, text) in _named_words(over, "--over", "--over elbow=-1:1:21").items():
        if name in values:
            raise InvalidInput(f"--over {word!r}: {name!r} is also varied by --{name}; give it one way")
        values[name] = tuple(float(v) for v in _grid_range(text, f"--over {name}", "="))
        words += ["--over", word]
    return StudyCase(load=load_values, pose=pose, mode=mode, ranges=values), words


def _show_step(progress: Progress, task: TaskID, study: str) -> Callable[[str], None]:
    return lambda step: progress.update(task, description=f"{study}: {step}")


@app.command()
def report(
    target: Annotated[
        str,
        typer.Argument(
            help="a study, 'all' (every study), or a preset / .urdf / .plm.yaml / folder to run the "
            "overview study on"
        ),
    ],
    out: Annotated[Path, typer.Option("--out", help="output folder (created if missing)")] = Path("reports"),
    mechanism: Annotated[
        str | None,
        typer.Option("--mechanism", help="mechanism of a study that takes one (overview): preset or path"),
    ] = None,
    load_text: Annotated[
        str | None,
        typer.Option(
            "--load",
            help="overview: a load, one value per task coordinate, comma-separated: fx,fy,mz (N, N m) on the "
            "task frame (world axes), or a force or torque per output joint of a joint task",
        ),
    ] = None,
    pose_text: Annotated[
        str | None,
        typer.Option(
            "--pose",
            help="overview: the pose to study, NAME=VALUE,... task coordinates (m, rad) (others: reference)",
        ),
    ] = None,
    mode: Annotated[
        str | None,
        typer.Option("--mode", help="overview: the working mode, one sign per leg (--mode=+,-,+,-)"),
    ] = None,
    x: XOption = None,
    y: YOption = None,
    z: ZOption = None,
    rx: RxOption = None,
    ry: RyOption = None,
    rz: RzOption = None,
    over: Annotated[
        list[str] | None,
        typer.Option(
            "--over",
            help="overview: a slice range of any task coordinate NAME=START:STOP:COUNT, e.g. a joint of a "
            "joint task (--over elbow=-1:1:21), repeatable",
        ),
    ] = None,
    jobs: Annotated[
        int | None,
        typer.Option("--jobs", min=1, help="all: studies run at once, each in a process (default: all CPUs)"),
    ] = None,
) -> None:
    """Write study reports: per study a self-contained HTML page and results.json, then index.html.

    Each report is written to a temporary folder inside OUT, then swapped in
    whole: a failed or interrupted run leaves the previous report as it was.
    Nothing is written outside OUT. Several studies run in parallel processes
    (--jobs, default all CPUs), each writing its own report.
    """
    require_renderer()  # a missing report extra fails now, not after the studies ran
    try:
        runs = _report_runs(target, mechanism)
        case, case_words = _study_case(
            load_text, pose_text, mode, {"x": x, "y": y, "z": z, "rx": rx, "ry": ry, "rz": rz}, over or []
        )
        if not case.empty and not all(study.takes_case for study, _ in runs):
            raise InvalidInput(
                "--load, --pose, --mode and slice ranges go with the overview of one mechanism "
                "(plm-pin report NAME|PATH ... or plm-pin report overview --mechanism NAME|PATH ...)"
            )
    except PlmError as exc:
        raise _fail(exc) from None
    loaded: dict[str, Mechanism] = {}  # loaded once: the studies reuse them
    for _, chosen in runs:
        if chosen is not None:
            loaded[chosen] = mech = _load(
                chosen
            )  # a broken description fails here, with the loader's message
            if not case.empty:
                from .report.overview import overview_case

                with _reported():
                    overview_case(mech, case)  # a bad case fails here, in one line; solved once
    try:
        root = output_folder(out)
    except PlmError as exc:
        raise _fail(exc) from None
    columns = (SpinnerColumn(), TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn())
    progress = Progress(
        *columns, TimeElapsedColumn(), console=errors, transient=True, disable=not errors.is_terminal
    )
    written, failed = 0, 0
    workers = min(jobs or _cpus(), len(runs))
    with progress:
        task = progress.add_task("reports", total=len(runs))
        if workers > 1:
            progress.update(task, description=f"{len(runs)} studies in {workers} processes")
            lines = _reports_in_processes(runs, root, out, case_words, case, workers)
        else:
            lines = (
                _study_report(
                    study.name,
                    chosen,
                    root,
                    _regenerate(study, chosen, out, case_words),
                    case if study.takes_case else None,
                    observer=_show_step(progress, task, study.name),
                    loaded=loaded.get(chosen) if chosen is not None else None,
                )
                for study, chosen in runs
            )
        for message, ok in lines:
            if ok:
                written += 1
                console.print(message, markup=False, highlight=False, soft_wrap=True)
            else:
                failed += 1
                errors.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
            progress.advance(task)
    if written:
        index = write_index(root)
        console.print(f"wrote {index}", markup=False, highlight=False, soft_wrap=True)
    if failed:
        raise typer.Exit(code=1)


def _cpus() -> int:
    """The CPUs this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def _study_report(
    name: str,
    chosen: str | None,
    root: Path,
    command: str,
    case: StudyCase | None,
    observer: Callable[[str], None] | None = None,
    loaded: Mechanism | None = None,
) -> tuple[str, bool]:
    """Run study ``name`` and write its report into ``root`` (here, or as a worker process's share).

    ``chosen``, ``command``, ``case``, ``observer`` and ``loaded``: as :func:`run_study` takes them.

    Returns:
        The line to print (where the report went and its time, or the error) and whether it was written.
    """
    try:
        result = run_study(
            find_study(name), chosen, command=command, observer=observer, case=case, loaded=loaded
        )
        path = write_report(result, root)
    except PlmError as exc:
        return str(exc), False
    return f"wrote {path} ({result.elapsed:.1f} s)", True


def _reports_in_processes(
    runs: list[tuple[Study, str | None]],
    root: Path,
    out: Path,
    case_words: list[str],
    case: StudyCase,
    workers: int,
) -> Iterator[tuple[str, bool]]:
    """Run the studies in ``workers`` processes, yielding each one's line as it ends.

    Fresh (spawned) processes: the parent's threads (the progress display) are not copied into
    them. Each writes its own report folder; the writer is safe for concurrent writers.
    """
    context = multiprocessing.get_context("spawn")
    with _one_thread_each(), ProcessPoolExecutor(workers, mp_context=context) as pool:
        jobs = [
            pool.submit(
                _study_report,
                study.name,
                chosen,
                root,
                _regenerate(study, chosen, out, case_words),
                case if study.takes_case else None,
            )
            for study, chosen in _longest_first(runs, root)
        ]
        for job in as_completed(jobs):
            yield job.result()


ONE_THREAD = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")
"""The thread counts of the BLAS libraries and numba, read when they are loaded."""


@contextlib.contextmanager
def _one_thread_each() -> Iterator[None]:
    """Processes spawned in this block run BLAS and numba on one thread each: they share the cores.

    Their small matrices gain nothing from BLAS threads, which fight over the cores with the other
    processes: on 2 cores, ``report all`` took 27 s with them and 21 s without (the Delta
    optimisation study 10 s and 5.3 s).
    """
    saved = {name: os.environ.get(name) for name in ONE_THREAD}
    os.environ.update(dict.fromkeys(ONE_THREAD, "1"))
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _longest_first(runs: list[tuple[Study, str | None]], root: Path) -> list[tuple[Study, str | None]]:
    """``runs`` by the run time of each study's last report in ``root``, longest first (unknown ones first).

    Started first, the long studies do not end alone on one process while the others idle.
    """
    last: dict[str, float] = {}
    for path in root.glob("*/results.json"):
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            last[str(data["study"])] = float(data["elapsed_s"])
        except (OSError, ValueError, KeyError, TypeError):
            continue
    return sorted(runs, key=lambda run: -last.get(run[0].name, math.inf))


def _numbers(text: str, what: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise InvalidInput(f"{what}: expected comma-separated numbers, got {text!r}") from None


def _pose_configuration(mech: Mechanism, pose: list[str]) -> np.ndarray:
    """The configuration asked for by ``--pose``: reference, joints imposed, or a task pose (by IK).

    Raises:
        InvalidInput: malformed items, unknown names, joints mixed with task coordinates.
        PoseUnreachable: a task pose the inverse kinematics cannot reach.
    """
    if not pose:
        return np.array(mech.q_ref)
    dofs = mech.task.dofs if mech.task is not None else ()
    if len(pose) == 1 and "=" not in pose[0]:  # the whole task pose, in the task's order
        if not dofs:
            raise InvalidInput(f"--pose {pose[0]!r}: {mech.name} has no task; give JOINT=VALUE items")
        return np.array(inverse_kinematics(mech, _numbers(pose[0], "--pose")).q)
    names = [*mech.joint_names, *(d for d in dofs if d not in mech.joint_names)]
    kind = f"a joint or task coordinate of {mech.name}"
    items = _assignments(pose, "--pose", f"--pose {names[0]}=0.1", names, kind, vectors=True)
    joints: dict[str, float | list[float]] = {}
    task: dict[str, float] = {}
    for (name, numbers), word in zip(items.items(), pose, strict=True):
        if name in mech.joint_names:
            joints[name] = numbers[0] if len(numbers) == 1 else numbers
        elif len(numbers) == 1:
            task[name] = numbers[0]
        else:
            raise InvalidInput(f"--pose {word!r}: the task coordinate {name!r} takes one number")
    if joints and task:
        raise InvalidInput("--pose mixes joints and task coordinates; give one kind only")
    if task:
        x = task_pose(mech, mech.q_ref)
        for dof, number in task.items():
            x[dofs.index(dof)] = number
        return np.array(inverse_kinematics(mech, x).q)
    try:
        return np.array(mech.assemble(mech.q_ref, fixed=joints).q)
    except ClosureNotSatisfied as exc:
        errors.print(
            f"[yellow]warning:[/] {escape(str(exc))}; showing the closest configuration found",
            highlight=False,
            soft_wrap=True,
        )
        return np.asarray(exc.q, dtype=float)


def _print_status(status: SceneStatus) -> None:
    for name in status.open_closures:
        errors.print(
            f"[yellow]warning:[/] closure {escape(repr(name))} is open (residual "
            f"{status.closure_errors[name]:.3g} m/rad): its markers are magenta",
            highlight=False,
            soft_wrap=True,
        )
    report = status.singularity
    if report is not None and report.singular:
        console.print(
            f"singular configuration ({', '.join(report.kinds)}): margins constraint "
            f"{report.constraint_margin:.3g}, inverse {report.inverse_margin:.3g}, direct "
            f"{report.direct_margin:.3g}; the mechanism is drawn in the colour of the first kind",
            highlight=False,
            soft_wrap=True,
        )


def _animation(spec: str, target: str | None) -> Animation:
    """The motion ``STUDY:CASE``; ``target`` is the mechanism to move, or must be the animation's own."""
    with _reported():
        name, case = parse_case(spec)
        study = find_study(name)
        motion = compute_animation(study, case, target if study.mechanism is not None else None)
        if target is not None and study.mechanism is None and target != motion.mechanism.name:
            raise InvalidInput(
                f"--animate {spec} moves {motion.mechanism.name}, not {target!r}: give that mechanism or none"
            )
    return motion


def _draw(viewer: MeshcatViewer, q: np.ndarray | None, motion: Animation | None) -> SceneStatus:
    """Place the mechanism at ``q``, or play ``motion``."""
    if motion is None:
        return viewer.display(q)
    console.print(
        f"{motion.caption} ({motion.times.size} frames, {motion.times[-1] - motion.times[0]:.3g} s)",
        markup=False,
        highlight=False,
        soft_wrap=True,
    )
    return viewer.animate(motion.qs, motion.times)


@app.command()
def view(
    target: Annotated[
        str | None,
        typer.Argument(
            help="preset name, erd:<robot>, .urdf, .plm.yaml or folder (optional with --animate: the "
            "animation's own mechanism)"
        ),
    ] = None,
    pose: Annotated[
        list[str] | None,
        typer.Option(
            "--pose",
            help="JOINT=VALUE or task coordinate (x y z [m], rx ry rz [rad]) =VALUE, repeatable; or the "
            "whole task pose as x,y,... (default: the reference configuration)",
        ),
    ] = None,
    port: Annotated[
        int | None, typer.Option("--port", help="web port (default: first free from 7000)")
    ] = None,
    zmq_url: Annotated[
        str | None, typer.Option("--zmq-url", help="draw into a running server, tcp://127.0.0.1:PORT")
    ] = None,
    open_browser: Annotated[
        bool, typer.Option("--open/--no-open", help="open the page in a browser")
    ] = False,
    html: Annotated[
        Path | None, typer.Option("--html", help="write a static page to this file instead of serving")
    ] = None,
    animate: Annotated[
        str | None,
        typer.Option(
            "--animate",
            help="STUDY:CASE: play a motion a study computes, e.g. harada2015:assembly, "
            "harada2011:simulation2, enferadi2017:circle, zhao2011:8pss, overview:simulation",
        ),
    ] = None,
    ignore: IgnoreOption = "",
) -> None:
    """Show a mechanism in meshcat (127.0.0.1 only): frames, closure points, singularities highlighted.

    Serves until Ctrl-C, unless --html writes a page that needs no server or --zmq-url draws
    into a server that is already running. With --animate, plays a study's motion instead.
    """
    if animate is None:
        if target is None:
            raise _fail(InvalidInput("give a mechanism (preset, erd:<robot>, .urdf, folder) or --animate"))
        mech, motion = _load(target, ignore), None
    else:
        if pose:
            raise _fail(InvalidInput("--animate plays a motion: it takes no --pose"))
        motion = _animation(animate, target)
        mech = motion.mechanism
    try:
        if html is not None and (port is not None or zmq_url is not None):
            raise InvalidInput(
                "--html writes a page that needs no server: it takes neither --port nor --zmq-url"
            )
        if port is not None and zmq_url is not None:
            raise InvalidInput("--zmq-url draws into a running server: it takes no --port")
        if html is not None and html.is_dir():
            raise InvalidInput(f"--html {html}: is a folder; give a file name")
        q = _pose_configuration(mech, pose or []) if motion is None else None
        if html is not None or zmq_url is not None:
            viewer = MeshcatViewer(mech, static=html is not None, zmq_url=zmq_url)
            _print_status(_draw(viewer, q, motion))
            if html is not None:
                html.parent.mkdir(parents=True, exist_ok=True)
                viewer.write_html(html)
                console.print(f"wrote {html}", markup=False, highlight=False, soft_wrap=True)
                if open_browser:
                    webbrowser.open(html.resolve().as_uri())
            else:
                console.print(f"{mech.name}: {viewer.url}", markup=False, highlight=False, soft_wrap=True)
                if open_browser:
                    viewer.open()
            return
        _ctrl_c_stops()
        server = MeshcatServer(port)
    except PlmError as exc:
        raise _fail(exc) from None
    with server:
        if server.moved:
            errors.print(
                f"[yellow]warning:[/] port {port} is busy; serving on {server.port} instead", highlight=False
            )
        try:
            viewer = MeshcatViewer(mech, server=server)
            _print_status(_draw(viewer, q, motion))
        except PlmError as exc:
            raise _fail(exc) from None
        try:  # from the announcement on, Ctrl-C is the way out
            console.print(f"{mech.name}: {server.web_url}", markup=False, highlight=False, soft_wrap=True)
            console.print(
                f"draw another mechanism into it with: plm-pin view NAME --zmq-url {server.zmq_url}\n"
                "Ctrl-C stops the server",
                markup=False,
                highlight=False,
                soft_wrap=True,
            )
            if open_browser:
                viewer.open()
            code = server.wait()
        except KeyboardInterrupt:
            return
    raise _fail(PlmError(f"the meshcat server stopped unexpectedly (exit code {code})"))


def _ctrl_c_stops() -> None:
    """Make Ctrl-C (SIGINT) raise KeyboardInterrupt here, as the serving commands announce.

    A process started in the background of a script inherits SIGINT ignored, and Python keeps
    it ignored: restored before anything is served, SIGINT (a terminal's Ctrl-C, ``kill -INT``)
    stops the command wherever it was started.
    """
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)


@app.command("inspect")
def inspect_command(
    target: Annotated[str, typer.Argument(help="preset name, erd:<robot>, .urdf, .plm.yaml or folder")],
    port: Annotated[
        int | None, typer.Option("--port", help="port of the control page (default: first free from 7200)")
    ] = None,
    open_browser: Annotated[
        bool, typer.Option("--open/--no-open", help="open the control page in a browser")
    ] = False,
    ignore: IgnoreOption = "",
) -> None:
    """Inspect a mechanism live (127.0.0.1 only): drag its task or actuators, switch modes, read forces.

    Serves a control page beside the meshcat scene until Ctrl-C.
    """
    _ctrl_c_stops()
    mech = _load(target, ignore)
    try:
        inspector = Inspector(mech, port=port, source=target)
    except PlmError as exc:
        raise _fail(exc) from None
    try:
        if port is not None and inspector.address is not None and inspector.address[1] != port:
            errors.print(
                f"[yellow]warning:[/] port {port} is busy; serving on {inspector.address[1]} instead",
                highlight=False,
            )
        console.print(f"{mech.name}: {inspector.url}", markup=False, highlight=False, soft_wrap=True)
        console.print(
            f"meshcat scene: {inspector.viewer.url}\nCtrl-C stops the inspector",
            markup=False,
            highlight=False,
            soft_wrap=True,
        )
        if open_browser:
            inspector.open()
        threading.Event().wait()
    except KeyboardInterrupt:
        pass
    finally:
        inspector.close()


RESULT = "result.nc"
"""File of a sweep's labelled result inside its output folder (netCDF, read with xarray.open_dataset)."""


@app.command("sweep")
def sweep_command(
    config: Annotated[
        Path,
        typer.Argument(
            help="sweep configuration (YAML); format: the user guide's Sweeps page (docs/guide/sweeps.md) "
            "and the JSON Schema plm_pin/schemas/plm-pin-sweep.schema.json"
        ),
    ],
    out: Annotated[Path, typer.Option("--out", help="output folder: checkpoints and the result")],
    scheduler: Annotated[
        str | None,
        typer.Option("--scheduler", help="Dask scheduler tcp://HOST:8786 (default: this machine, all cores)"),
    ] = None,
    chunk: Annotated[
        int | None, typer.Option("--chunk", min=1, help="poses per task (default: the config's, else 4096)")
    ] = None,
    workers: Annotated[
        int | None, typer.Option("--workers", min=1, help="local processes (default: all CPUs)")
    ] = None,
) -> None:
    """Run a design sweep; a re-run with the same configuration computes only the missing chunks.

    Finished chunks are checkpointed in OUT/chunks (Parquet) as they complete, and the
    labelled result is written to OUT/result.nc at the end. A folder holding another
    sweep is refused. Failed chunks are listed with their parameters (exit code 1) and
    the rest is written. Nothing is written outside OUT.
    """
    try:
        spec, config_chunk = load_config(config)
        if out.exists() and not out.is_dir():
            raise InvalidInput(f"--out {out}: is a file; give a folder")
        columns = (SpinnerColumn(), TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn())
        progress = Progress(
            *columns, TimeElapsedColumn(), console=errors, transient=True, disable=not errors.is_terminal
        )
        with progress:
            task = progress.add_task(f"sweep {spec.label}: parameter points", total=spec.n_points)
            result = run_spec(
                spec,
                store=out,
                scheduler=scheduler,
                workers=workers,
                chunk=chunk or config_chunk or DEFAULT_CHUNK,
                progress=lambda done, total: progress.update(task, completed=done, total=total),
            )
        path = out / RESULT
        with atomic_path(path) as tmp:
            result.dataset.to_netcdf(tmp, engine="scipy")
    except (PlmError, ImportError) as exc:
        raise _fail(exc) from None
    console.print(
        f"wrote {path}: {spec.n_points} parameter points x {spec.n_poses} poses; {result.computed_points} "
        f"computed now ({result.poses_per_second():.0f} poses/s), {result.loaded} from checkpoints "
        f"({result.elapsed:.1f} s)",
        markup=False,
        highlight=False,
        soft_wrap=True,
    )
    for failure in result.failures:
        errors.print(f"[bold red]failed:[/] {escape(failure.describe())}", highlight=False, soft_wrap=True)
    if result.failures:
        raise typer.Exit(code=1)


if __name__ == "__main__":  # pragma: no cover
    main()


@app.command("optimize")
def optimize_command(
    config: Annotated[
        Path,
        typer.Argument(
            help="optimisation configuration (YAML); format: the user guide's Design optimisation page "
            "(docs/guide/optimize.md) and the JSON Schema plm_pin/schemas/plm-pin-optimize.schema.json"
        ),
    ],
    out: Annotated[Path, typer.Option("--out", help="output folder: checkpoints and the result")],
    scheduler: Annotated[
        str | None, typer.Option("--scheduler", help="Dask scheduler tcp://HOST:8786 (default: this machine)")
    ] = None,
    workers: Annotated[
        int | None, typer.Option("--workers", min=1, help="local Dask processes (default: this process only)")
    ] = None,
    report: Annotated[
        bool, typer.Option("--report/--no-report", help="write the report page OUT/optimization/report.html")
    ] = True,
) -> None:
    """Choose a mechanism's dimensions; a re-run on the same folder resumes from its checkpoints.

    Every generation is checkpointed in OUT/generations (Parquet) before the search goes on;
    at the end every evaluated design is written to OUT/designs.csv and the best and start
    designs to summary.json in OUT, and the report page (best designs beside the start design,
    constraint verdicts, convergence, Pareto front, a 3D scene of the best design) to
    OUT/optimization/report.html. A folder holding another optimisation is refused. When no
    design meets every constraint, the constraint none met is named (exit code 1) and the
    designs are still written.
    """
    try:
        problem, search = load_optimize_config(config)
        if out.exists() and not out.is_dir():
            raise InvalidInput(f"--out {out}: is a file; give a folder")
        failure = None
        try:
            result = run_problem(problem, **search, store=out, scheduler=scheduler, workers=workers)
        except NoFeasibleDesign as exc:
            assert isinstance(exc.partial, OptimizationResult)
            result, failure = exc.partial, exc
        with atomic_path(out / "designs.csv") as tmp:
            result.table().to_csv(tmp, index=False)
        summary = {
            "mechanism": problem.spec.label,
            "feasible": failure is None,
            "start": {"parameters": result.parameters(result.start), "objectives": result.start.objectives},
            "best": {"parameters": result.parameters(), "objectives": result.best.objectives},
            "designs": len(result.evaluations),
            "computed": result.computed,
        }
        atomic_write_text(out / "summary.json", json.dumps(summary, indent=2, default=float) + "\n")
        if report:
            command = shlex.join(["plm-pin", "optimize", str(config), "--out", str(out)])
            write_report(optimization_report(result, command), out)
    except (PlmError, ImportError) as exc:
        raise _fail(exc) from None
    if failure is not None:
        raise _fail(failure)
    best = ", ".join(f"{k} = {v}" for k, v in result.parameters().items())
    objectives = ", ".join(f"{k} = {v:.6g}" for k, v in result.best.objectives.items())
    console.print(
        f"wrote {out}: {len(result.evaluations)} designs ({result.computed} computed now, "
        f"{result.elapsed:.1f} s); best {best}: {objectives}",
        markup=False,
        highlight=False,
        soft_wrap=True,
    )
