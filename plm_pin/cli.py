"""The ``plm-pin`` command line: list presets, inspect and check descriptions, write reports, run sweeps."""

from __future__ import annotations

import contextlib
import json
import shlex
import sys
import warnings
import webbrowser
from collections.abc import Callable, Iterator
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

from ._io import atomic_path
from ._version import __version__
from .core.diagnostics import findings, mobility_text
from .core.mechanism import Mechanism
from .exceptions import ClosureNotSatisfied, InvalidInput, PlmError
from .export import export_mjcf
from .kinematics import forward_kinematics, inverse_kinematics, task_pose
from .kinematics.reference import reference_findings, reference_report
from .loading import load
from .models.registry import PRESETS
from .report import Animation, Study, find_study, run_study, study_names, write_index, write_report
from .report.animation import parse_case
from .report.render import require_renderer
from .report.study import compute_animation, studies_hint
from .report.writer import output_folder
from .sweep import load_config, run_spec
from .sweep.execution import DEFAULT_CHUNK
from .viz.meshcat_server import MeshcatServer
from .viz.meshcat_view import MeshcatViewer, SceneStatus
from .warnings import PlmWarning


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
        limits = "unbounded" if a["limits"] is None else f"[{a['limits'][0]:g}, {a['limits'][1]:g}]"
        table.add_row(escape(f"actuator {a['joint']}"), escape(f"{a['kind']}, limits {limits}"))
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


def _actuator_values(mech: Mechanism, assignments: list[str]) -> np.ndarray:
    """Actuator positions from ``joint=value`` words, the others at their reference value."""
    values = mech.actuator_positions(mech.q_ref).copy()
    names = [a.joint for a in mech.actuators]
    for word in assignments:
        joint, sep, text = word.partition("=")
        if not sep or joint not in names:
            raise InvalidInput(f"actuator assignment {word!r}: write JOINT=VALUE with JOINT one of {names}")
        try:
            values[names.index(joint)] = float(text)
        except ValueError:
            raise InvalidInput(f"actuator assignment {word!r}: {text!r} is not a number") from None
    return values


@app.command("fk")
def fk_command(
    target: Annotated[str, typer.Argument(help="preset name, erd:<robot>, .urdf, .plm.yaml or folder")],
    assignments: Annotated[
        list[str] | None,
        typer.Argument(help="actuator positions JOINT=VALUE [m or rad]; the others stay at their reference"),
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
    certificate = "Krawczyk" if modes.method == "homotopy" else "none"
    for i, s in enumerate(modes):
        table.add_row(str(i + 1), *(f"{v:.6f}" for v in s.x), f"{s.residual_norm:.1e}", certificate)
    console.print(table)


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


def _regenerate(study: Study, mechanism: str | None, out: Path) -> str:
    """The shell command that writes this study's report again."""
    chosen = ["--mechanism", mechanism] if mechanism is not None else []
    return shlex.join(["plm-pin", "report", study.name, *chosen, "--out", str(out)])


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
) -> None:
    """Write study reports: per study a self-contained HTML page and results.json, then index.html.

    Each report is written to a temporary folder inside OUT, then swapped in
    whole: a failed or interrupted run leaves the previous report as it was.
    Nothing is written outside OUT.
    """
    require_renderer()  # a missing report extra fails now, not after the studies ran
    try:
        runs = _report_runs(target, mechanism)
        root = output_folder(out)
    except PlmError as exc:
        raise _fail(exc) from None
    for _, chosen in runs:
        if chosen is not None:
            _load(chosen)  # a broken description fails here, with the loader's message
    columns = (SpinnerColumn(), TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn())
    progress = Progress(
        *columns, TimeElapsedColumn(), console=errors, transient=True, disable=not errors.is_terminal
    )
    written, failed = 0, 0
    with progress:
        task = progress.add_task("reports", total=len(runs))
        for study, chosen in runs:
            progress.update(task, description=study.name)
            try:
                result = run_study(
                    study,
                    chosen,
                    command=_regenerate(study, chosen, out),
                    observer=_show_step(progress, task, study.name),
                )
                path = write_report(result, root)
            except PlmError as exc:
                errors.print(f"[bold red]error:[/] {escape(str(exc))}", highlight=False, soft_wrap=True)
                failed += 1
            else:
                written += 1
                console.print(
                    f"wrote {path} ({result.elapsed:.1f} s)", markup=False, highlight=False, soft_wrap=True
                )
            progress.advance(task)
    if written:
        index = write_index(root)
        console.print(f"wrote {index}", markup=False, highlight=False, soft_wrap=True)
    if failed:
        raise typer.Exit(code=1)


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
    joints: dict[str, float | list[float]] = {}
    task: dict[str, float] = {}
    for item in pose:
        name, sep, value = item.partition("=")
        if not sep:
            raise InvalidInput(f"--pose {item!r}: expected NAME=VALUE (or one comma-separated task pose)")
        numbers = _numbers(value, f"--pose {item!r}")
        if name in mech.joint_names:
            joints[name] = numbers[0] if len(numbers) == 1 else numbers
        elif name in dofs and len(numbers) == 1:
            task[name] = numbers[0]
        else:
            raise InvalidInput(
                f"--pose {item!r}: {name!r} is neither a joint nor a task coordinate (one number); "
                f"joints are {list(mech.joint_names)}, task coordinates are {list(dofs)}"
            )
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
        try:
            code = server.wait()
        except KeyboardInterrupt:
            return
    raise _fail(PlmError(f"the meshcat server stopped unexpectedly (exit code {code})"))


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
