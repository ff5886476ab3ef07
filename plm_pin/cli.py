"""The ``plm-pin`` command line: list presets, inspect and check descriptions, write reports."""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from ._io import atomic_write_text
from .exceptions import PlmError
from .loading import load
from .mechanism import Mechanism
from .models.registry import PRESETS
from .warnings import PlmWarning

app = typer.Typer(
    name="plm-pin",
    help="Analyse parallel link mechanisms: closed chains described by a URDF tree plus cut joints.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console()
errors = Console(stderr=True)


def _fail(exc: Exception) -> typer.Exit:
    errors.print(f"[bold red]error:[/] {escape(str(exc))}", markup=True, highlight=False, soft_wrap=True)
    return typer.Exit(code=1)


def _load(target: str | Path) -> Mechanism:
    """Load a mechanism, printing its warnings on stderr and turning errors into exit 1."""
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", PlmWarning)
            mech = load(target)
            mech.summary()  # computes mobility now, inside the error handling
    except PlmError as exc:
        raise _fail(exc) from None
    for w in caught:
        errors.print(f"[yellow]warning:[/] {escape(str(w.message))}", highlight=False, soft_wrap=True)
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


@app.command()
def info(
    target: Annotated[str, typer.Argument(help="preset name, erd:<robot>, .urdf, .plm.yaml or folder")],
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False,
) -> None:
    """Sizes, closures, actuators, task, mobility, redundancy and reference residual."""
    summary = _load(target).summary()
    if as_json:
        console.print_json(json.dumps(summary))
        return
    table = Table(title=escape(summary["name"]), show_header=False)
    table.add_column("item")
    table.add_column("value", overflow="fold")
    table.add_row("source", escape(summary["source"]))
    table.add_row("nq / nv", f"{summary['nq']} / {summary['nv']}")
    for c in summary["closures"]:
        table.add_row(
            escape(f"closure {c['name']}"),
            escape(f"{c['type']} ({c['rows']} rows): {c['frames'][0]} = {c['frames'][1]}"),
        )
    for a in summary["actuators"]:
        limits = "unbounded" if a["limits"] is None else f"[{a['limits'][0]:g}, {a['limits'][1]:g}]"
        table.add_row(escape(f"actuator {a['joint']}"), escape(f"{a['kind']}, limits {limits}"))
    task = summary["task"]
    table.add_row("task", "none" if task is None else escape(f"{task['frame']}: {' '.join(task['dofs'])}"))
    table.add_row("mobility", str(summary["mobility"]))
    red = summary["redundancy"]
    table.add_row("redundancy", f"{red}" + (" (under-actuated)" if red < 0 else ""))
    table.add_row("reference residual", f"{summary['reference_residual']:.3g} m/rad")
    table.add_row("gravity", f"{summary['gravity']} m/s^2")
    console.print(table)


@app.command()
def check(path: Annotated[Path, typer.Argument(help="a .urdf, .plm.yaml or description folder")]) -> None:
    """Validate a description and say exactly what is wrong and where."""
    summary = _load(path).summary()
    console.print(
        f"[green]ok[/]: {escape(summary['name'])}: {len(summary['closures'])} closures, "
        f"{len(summary['actuators'])} actuators, mobility {summary['mobility']}, redundancy "
        f"{summary['redundancy']}, reference residual {summary['reference_residual']:.2g}",
        highlight=False,
        soft_wrap=True,
    )


@app.command()
def report(
    study: Annotated[str, typer.Argument(help="'all' (every preset) or a preset name / description path")],
    out: Annotated[Path, typer.Option("--out", help="output folder")] = Path("reports"),
) -> None:
    """Write the mechanism summaries (the full study reports are planned work)."""
    targets = list(PRESETS) if study == "all" else [study]
    rows = []
    for target in targets:
        mech = _load(target)
        summary = mech.summary()
        summary["q_ref"] = np.asarray(mech.q_ref).tolist()
        rows.append(summary)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "summary.json", json.dumps(rows, indent=2))
    table = Table(title="plm_pin mechanisms")
    for col in ("name", "source", "nv", "closures", "actuators", "mobility", "redundancy", "residual"):
        table.add_column(col, overflow="fold")
    for s in rows:
        table.add_row(
            escape(s["name"]),
            escape(s["source"]),
            str(s["nv"]),
            str(len(s["closures"])),
            str(len(s["actuators"])),
            str(s["mobility"]),
            str(s["redundancy"]),
            f"{s['reference_residual']:.1e}",
        )
    console.print(table)
    console.print(f"wrote {out / 'summary.json'}", markup=False, highlight=False, soft_wrap=True)


if __name__ == "__main__":  # pragma: no cover
    app()
