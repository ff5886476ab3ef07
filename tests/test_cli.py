"""The plm-pin command line (plm_pin/cli.py)."""

from __future__ import annotations

import dataclasses
import json
import math
import multiprocessing
import os
import re
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

import plm_pin
from plm_pin import cli
from plm_pin.cli import app
from plm_pin.exceptions import PlmError
from plm_pin.models import PRESETS
from tests.report.numbers import unlisted_numbers

runner = CliRunner()


def _break_closure_type(urdf: Path, bad: str) -> Path:
    """Set the first closure's type to ``bad`` in the sidecar beside ``urdf``; returns the sidecar."""
    sidecar = urdf.with_name("fourbar.plm.yaml")
    data = yaml.safe_load(sidecar.read_text())
    data["closures"][0]["type"] = bad
    sidecar.write_text(yaml.safe_dump(data, sort_keys=False))
    return sidecar


def _assert_clean_failure(result, stderr_line: str) -> None:
    """Exit code 1, nothing on stdout, exactly one 'error:' line on stderr, no traceback."""
    assert result.exit_code == 1, result.output
    assert isinstance(result.exception, SystemExit)
    assert result.stdout == ""
    assert result.stderr == f"error: {stderr_line}\n"
    assert "Traceback" not in result.output


def test_list_shows_every_preset():
    """`list` succeeds and names every preset."""
    result = runner.invoke(app, ["list"])
    assert result.exit_code == 0, result.output
    for name in PRESETS:
        assert name in result.stdout


def test_info_shows_mobility_and_redundancy_of_3d4m():
    """`info harada2011_3d4m` reports mobility 3 and redundancy 1 (four sliders, three DOF)."""
    result = runner.invoke(app, ["info", "harada2011_3d4m"])
    assert result.exit_code == 0, result.output
    rows = {
        cells[0]: cells[1]
        for line in result.stdout.splitlines()
        if len(cells := [c.strip() for c in line.strip("│ ").split("│")]) == 2
    }
    assert rows["mobility"] == "3"
    assert rows["redundancy"] == "1"
    assert rows["task"] == "plate_center: x y rz"


def test_info_json_parses():
    """`info --json fourbar` prints valid JSON with mobility 1 and the crank as actuator."""
    result = runner.invoke(app, ["info", "--json", "fourbar"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["name"] == "fourbar"
    assert summary["mobility"] == 1
    assert summary["redundancy"] == 0
    assert [a["joint"] for a in summary["actuators"]] == ["crank_pivot"]


def test_info_unknown_target_is_one_error_line():
    """`info nonsense` exits 1 with one 'error:' line saying it is neither a preset nor a path."""
    result = runner.invoke(app, ["info", "nonsense"])
    assert result.exit_code == 1
    assert result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("error: 'nonsense' is neither a preset nor an existing path; presets are [")
    assert "Traceback" not in result.output


def test_check_good_description_prints_ok(fourbar):
    """`check` on a valid description prints the reference pose (the sidecar's rocker angle), then ok."""
    result = runner.invoke(app, ["check", str(fourbar)])
    assert result.exit_code == 0, result.output
    note, ok = result.stdout.splitlines()
    rocker = yaml.safe_load(fourbar.with_name("fourbar.plm.yaml").read_text())["reference"]["rocker_pivot"]
    assert note.startswith(f"note: reference: pose rz = {rocker:.6g}; working mode (")
    assert ok.startswith("ok: fourbar: 1 closures, 1 actuators, mobility 1, redundancy 0, reference ")
    assert result.stderr == ""


def test_check_broken_sidecar_names_file_and_bad_type(fourbar):
    """`check` on a sidecar with an invalid closure type exits 1 naming the file and the type."""
    sidecar = _break_closure_type(fourbar, "hinge")
    result = runner.invoke(app, ["check", str(fourbar)])
    _assert_clean_failure(
        result,
        f"{sidecar}: closures[0] (coupler_rocker): invalid closure type 'hinge'; "
        "valid types are ['point', 'revolute', 'weld']",
    )


@pytest.mark.parametrize("bad", ["[/oops]", "[red]hinge", "[bold]"])
def test_check_prints_bracketed_values_verbatim(fourbar, bad):
    """Values that look like rich markup are printed as they are, never interpreted or crashed on."""
    sidecar = _break_closure_type(fourbar, bad)
    result = runner.invoke(app, ["check", str(fourbar)])
    _assert_clean_failure(
        result,
        f"{sidecar}: closures[0] (coupler_rocker): invalid closure type {bad!r}; "
        "valid types are ['point', 'revolute', 'weld']",
    )


def test_info_and_check_print_bracketed_names_verbatim(fourbar):
    """A mechanism and closure named like rich markup appear literally in `check` and `info`."""
    sidecar = fourbar.with_name("fourbar.plm.yaml")
    data = yaml.safe_load(sidecar.read_text())
    data["name"] = "[/weird]"
    data["closures"][0]["name"] = "[bold]loop"
    sidecar.write_text(yaml.safe_dump(data, sort_keys=False))
    checked = runner.invoke(app, ["check", str(fourbar)])
    assert checked.exit_code == 0, checked.output
    assert checked.stdout.splitlines()[-1].startswith("ok: [/weird]: 1 closures")
    shown = runner.invoke(app, ["info", str(fourbar)])
    assert shown.exit_code == 0, shown.output
    assert "[/weird]" in shown.stdout
    assert "closure [bold]loop" in shown.stdout


def test_check_reports_missing_meshes_as_a_warning(fourbar):
    """`check` on a description with a missing mesh succeeds and prints one warning on stderr."""
    text = fourbar.read_text()
    assert text.count('<box size="0.3 0.01 0.004"/>') == 1
    fourbar.write_text(text.replace('<box size="0.3 0.01 0.004"/>', '<mesh filename="base.stl"/>'))
    result = runner.invoke(app, ["check", str(fourbar)])
    assert result.exit_code == 0, result.output
    assert result.stderr == (
        f"warning: {fourbar}: 1 mesh file(s) missing, loading without those visuals: base.stl\n"
    )
    assert result.stdout.splitlines()[-1].startswith("ok: fourbar:")


def _tree(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` with its bytes."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _rename_mechanism(urdf: Path, name: str) -> None:
    sidecar = urdf.with_name(urdf.name.replace(".urdf", ".plm.yaml"))
    data = yaml.safe_load(sidecar.read_text())
    data["name"] = name
    sidecar.write_text(yaml.safe_dump(data, sort_keys=False))


def test_report_on_a_description_runs_the_overview(tmp_path, fourbar):
    """`report PATH` writes overview-<name>/ (page, results.json) and the index, and says so on stdout."""
    out = tmp_path / "reports"
    result = runner.invoke(app, ["report", str(fourbar), "--out", str(out)])
    assert result.exit_code == 0, result.output
    folder = out / "overview-fourbar"
    assert sorted(p.name for p in out.iterdir()) == ["index.html", "meshcat.min.js", "overview-fourbar"]
    names = sorted(p.name for p in folder.iterdir())
    scenes = [n for n in names if re.fullmatch(r"scene-\d+\.html", n)]
    assert scenes and names == ["report.html", "results.json", *scenes]  # scenes share out/meshcat.min.js
    lines = result.stdout.splitlines()
    assert re.fullmatch(rf"wrote {re.escape(str(folder.resolve() / 'report.html'))} \(\d+\.\d s\)", lines[0])
    assert lines[1] == f"wrote {out.resolve() / 'index.html'}"
    data = json.loads((folder / "results.json").read_text())
    assert data["command"] == f"plm-pin report overview --mechanism {fourbar} --out {out}"
    assert data["mechanisms"][0]["origin"] == f"description {fourbar}"
    assert 'href="overview-fourbar/report.html"' in (out / "index.html").read_text()


def test_report_overview_with_mechanism_option_writes_the_same_report(tmp_path, fourbar):
    """`report overview --mechanism PATH` is the long form of `report PATH`."""
    out = tmp_path / "reports"
    result = runner.invoke(app, ["report", "overview", "--mechanism", str(fourbar), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert (out / "overview-fourbar" / "report.html").is_file()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["nope"], "'nope' is neither a study, 'all', a preset nor an existing path; studies are ["),
        (
            ["all", "--mechanism", "fivebar"],
            "--mechanism picks the mechanism of one study; it does not go with 'all'",
        ),
        (["harada2015", "--mechanism", "fivebar"], "study 'harada2015' takes no --mechanism"),
        (
            ["fivebar", "--mechanism", "fourbar"],
            "'fivebar' is a mechanism: give it alone, or as --mechanism of a study",
        ),
    ],
)
def test_report_bad_target_is_one_error_line_and_writes_nothing(tmp_path, args, message):
    """Unknown studies and misplaced --mechanism exit 1 with one line, before creating anything."""
    out = tmp_path / "reports"
    result = runner.invoke(app, ["report", *args, "--out", str(out)])
    assert result.exit_code == 1
    assert result.stdout == ""
    assert result.stderr.startswith(f"error: {message}") and result.stderr.count("\n") == 1
    assert not out.exists()


def test_report_out_that_is_a_file_is_refused(tmp_path):
    """--out naming a file exits 1 and leaves the file alone."""
    target = tmp_path / "reports"
    target.write_text("mine")
    result = runner.invoke(app, ["report", "fourbar", "--out", str(target)])
    _assert_clean_failure(result, f"--out {target}: is not a folder")
    assert target.read_text() == "mine"


def test_report_on_broken_description_leaves_existing_reports_untouched(tmp_path, fourbar):
    """A broken description exits 1 with the loader's message; earlier reports and index stay as they were."""
    out = tmp_path / "reports"
    assert runner.invoke(app, ["report", str(fourbar), "--out", str(out)]).exit_code == 0
    before = _tree(out)
    sidecar = _break_closure_type(fourbar, "hinge")
    result = runner.invoke(app, ["report", str(fourbar), "--out", str(out)])
    _assert_clean_failure(
        result,
        f"{sidecar}: closures[0] (coupler_rocker): invalid closure type 'hinge'; "
        "valid types are ['point', 'revolute', 'weld']",
    )
    assert _tree(out) == before


def test_report_study_failing_midway_keeps_the_old_report(tmp_path, fourbar, monkeypatch):
    """A study raising after some work exits 1 with 'study ... failed'; the previous report is kept."""
    out = tmp_path / "reports"
    assert runner.invoke(app, ["report", str(fourbar), "--out", str(out)]).exit_code == 0
    before = _tree(out)
    real = cli.find_study("overview")

    def failing(ctx):
        ctx.load()
        ctx.section("started").text("half done")
        raise PlmError("the solver gave up")

    monkeypatch.setattr(cli, "find_study", lambda name: dataclasses.replace(real, run=failing))
    result = runner.invoke(app, ["report", str(fourbar), "--out", str(out)])
    assert result.exit_code == 1
    assert result.stderr == "error: study 'overview' failed: the solver gave up\n"
    assert _tree(out) == before


def test_report_escapes_names_from_user_files(tmp_path, fourbar):
    """A mechanism named like a script is shown as text in the report and the index, and slugged in paths."""
    _rename_mechanism(fourbar, "<script>alert(1)</script>")
    out = tmp_path / "reports"
    result = runner.invoke(app, ["report", str(fourbar), "--out", str(out)])
    assert result.exit_code == 0, result.output
    folder = out / "overview-script_alert_1_script"
    for page in (folder / "report.html", out / "index.html"):
        text = page.read_text()
        assert "<script>alert(1)" not in text
        assert "&lt;script&gt;alert(1)&lt;/script&gt;" in text
    assert (
        json.loads((folder / "results.json").read_text())["mechanisms"][0]["name"]
        == "<script>alert(1)</script>"
    )


def test_report_never_writes_outside_out(tmp_path, fourbar):
    """A mechanism named '../x' is written to out/overview-x; nothing appears outside out."""
    _rename_mechanism(fourbar, "../x")
    outside_before = sorted(p.name for p in tmp_path.iterdir())
    out = tmp_path / "reports"
    result = runner.invoke(app, ["report", str(fourbar), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == ["index.html", "meshcat.min.js", "overview-x"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*outside_before, "reports"])


@pytest.mark.slow
def test_report_all_runs_every_study_and_indexes_them(report_all):
    """`report all` writes every study, each number its tables show is in its results.json, all indexed.

    The command is run once for the session (the ``report_all`` fixture of tests/conftest.py).
    """
    out = report_all.out
    assert report_all.exit_code == 0, report_all.output
    studies = cli.study_names()
    assert sorted(report_all.results) == studies  # each study ran once, its result kept
    folders = sorted(p.name for p in out.iterdir() if p.is_dir())
    overview = f"overview-{cli.find_study('overview').mechanism}"
    assert folders == sorted(overview if s == "overview" else s for s in studies)
    index = (out / "index.html").read_text()
    for folder in folders:
        data = json.loads((out / folder / "results.json").read_text())
        assert data["command"] == f"plm-pin report {data['study']} --out {out}"
        assert f'href="{folder}/report.html"' in index
        shown, missing = unlisted_numbers(out / folder)
        assert shown > 20 and missing == [], folder


@pytest.mark.slow
def test_report_studies_in_two_processes_write_what_one_process_writes(tmp_path):
    """--jobs 2: each study's report is written by a worker process, the same tables as in one process.

    A study that fails in a worker comes back as its one-line error; the others are written.
    """
    root = tmp_path / "reports"
    root.mkdir()
    runs = [(cli.find_study("enferadi2017"), None), (cli.find_study("harada2011"), None)]
    runs.append((cli.find_study("overview"), str(tmp_path / "missing.urdf")))
    lines = list(cli._reports_in_processes(runs, root, root, [], cli.StudyCase(), 2))
    written = sorted(line for line, ok in lines if ok)
    assert [ok for _, ok in lines].count(False) == 1, lines
    assert "missing.urdf" in next(line for line, ok in lines if not ok)
    assert [line.split()[1] for line in written] == [
        str(root / "enferadi2017" / "report.html"),
        str(root / "harada2011" / "report.html"),
    ]
    here = cli.run_study(cli.find_study("enferadi2017"), command="plm-pin report enferadi2017 --out x")
    there = json.loads((root / "enferadi2017" / "results.json").read_text())
    assert there["agreement"] == json.loads(json.dumps(here.to_dict()))["agreement"]
    assert there["sections"] == json.loads(json.dumps(here.to_dict()))["sections"]


def test_report_processes_run_blas_and_numba_on_one_thread_each(monkeypatch):
    """Processes spawned for the reports read one BLAS and numba thread; the parent's settings come back."""
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "4")
    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    spawn = multiprocessing.get_context("spawn")
    with cli._one_thread_each(), ProcessPoolExecutor(1, mp_context=spawn) as pool:
        seen = {name: pool.submit(os.getenv, name).result() for name in cli.ONE_THREAD}
    assert seen == dict.fromkeys(cli.ONE_THREAD, "1")
    assert (os.getenv("OPENBLAS_NUM_THREADS"), os.getenv("NUMBA_NUM_THREADS")) == ("4", None)


def test_report_processes_start_the_longest_studies_first(tmp_path):
    """Runs are ordered by the last report's run time in the output folder, unknown studies first."""
    for name, seconds in (("harada2011", 3.0), ("zhao2011", 14.0), ("enferadi2017", 2.0)):
        (tmp_path / name).mkdir()
        (tmp_path / name / "results.json").write_text(json.dumps({"study": name, "elapsed_s": seconds}))
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "results.json").write_text("{")
    runs = [(cli.find_study(n), None) for n in ("enferadi2017", "harada2011", "harada2015", "zhao2011")]
    ordered = [study.name for study, _ in cli._longest_first(runs, tmp_path)]
    assert ordered == ["harada2015", "zhao2011", "harada2011", "enferadi2017"]


def test_no_arguments_shows_help():
    """Running with no command prints the usage and lists the commands."""
    result = runner.invoke(app, [])
    for command in ("list", "info", "check", "report"):
        assert command in result.output


def test_help_texts_point_to_files_that_hold_what_they_promise():
    """Each command's --help names only files of the checkout; sweep and optimize name guide and schema."""
    repo = Path(__file__).resolve().parents[1]
    commands = [c.name or c.callback.__name__ for c in app.registered_commands]
    assert "sweep" in commands
    texts = {}
    for command in commands:
        result = runner.invoke(app, [command, "--help"], terminal_width=400)
        assert result.exit_code == 0, command
        texts[command] = " ".join(result.output.split())
    named = {c: re.findall(r"[\w.-]+(?:/[\w.-]+)+\.(?:md|json|yaml)\b", t) for c, t in texts.items()}  # paths
    assert {c: [f for f in files if not (repo / f).is_file()] for c, files in named.items() if files} == {
        "sweep": [],
        "optimize": [],
    }
    assert [c for c, t in texts.items() if "README" in t] == []
    assert "docs/guide/sweeps.md" in named["sweep"]
    sweeps = (repo / "docs" / "guide" / "sweeps.md").read_text(encoding="utf-8")
    assert (
        "format: plm-pin-sweep/1" in sweeps and "plm-pin-sweep.schema.json" in sweeps
    )  # the format is there
    assert "docs/guide/optimize.md" in named["optimize"]
    guide = (repo / "docs" / "guide" / "optimize.md").read_text(encoding="utf-8")
    assert "format: plm-pin-optimize/1" in guide and "plm-pin-optimize.schema.json" in guide


SWEEP_CONFIG = """\
mechanism: harada2011_3d4m
parameters:
  legs: [[1, 2, 4], [1, 2, 3, 4]]
poses:
  y: [0.06, 0.1]
  rz: {linspace: [-40, 40, 9], unit: deg}
pose: [0.0, 0.08, 0.0]
metrics: [manipulability, orientation_range]
"""


def _sweep_config(tmp_path, text: str = SWEEP_CONFIG) -> Path:
    path = tmp_path / "sweep.yaml"
    path.write_text(text)
    return path


def test_sweep_writes_the_result_and_resumes_from_its_checkpoints(tmp_path):
    """`sweep CONFIG --out DIR` writes DIR/result.nc (the API's dataset); a re-run computes nothing."""
    import xarray as xr

    from plm_pin.sweep import load_config, run_spec

    config, out = _sweep_config(tmp_path), tmp_path / "out"
    result = runner.invoke(app, ["sweep", str(config), "--out", str(out), "--chunk", "18"])
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith(
        f"wrote {out / 'result.nc'}: 2 parameter points x 18 poses; 2 computed now ("
    )
    assert sorted(p.name for p in out.iterdir() if p.name != ".lock") == [
        "chunks",
        "manifest.json",
        "result.nc",
    ]
    assert len(list((out / "chunks").glob("*.parquet"))) == 2
    with xr.open_dataset(out / "result.nc", engine="scipy") as written:
        expected = run_spec(load_config(config)[0]).dataset
        xr.testing.assert_identical(written.load(), expected)
    again = runner.invoke(app, ["sweep", str(config), "--out", str(out)])
    assert again.exit_code == 0, again.output
    assert "; 0 computed now (0 poses/s), 2 from checkpoints (" in again.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "sweep.yaml"]  # nothing outside OUT


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (SWEEP_CONFIG.replace("manipulability,", "rigidity,"), "unknown metric 'rigidity'; metrics are ["),
        (
            SWEEP_CONFIG.replace("legs:", "leg:"),
            "unknown parameter 'leg' of harada2011_3d4m; its parameters are",
        ),
        (
            SWEEP_CONFIG.replace("y: [0.06, 0.1]", "y: []"),
            "poses: values of 'y' must be a non-empty 1-D list",
        ),
        (
            SWEEP_CONFIG.replace("[0.06, 0.1]", "[0.06, .nan]"),
            "poses: values of 'y' hold non-finite entries [nan]",
        ),
    ],
)
def test_sweep_bad_config_is_one_error_line_and_writes_nothing(tmp_path, text, message):
    """A config the spec refuses exits 1 with one error line naming the file, before any work."""
    config, out = _sweep_config(tmp_path, text), tmp_path / "out"
    result = runner.invoke(app, ["sweep", str(config), "--out", str(out)])
    assert result.exit_code == 1 and result.stdout == ""
    assert result.stderr.startswith(f"error: {config}: {message}") and result.stderr.count("\n") == 1
    assert not out.exists()


def test_sweep_refuses_another_sweeps_folder(tmp_path):
    """An OUT holding another sweep's checkpoints is refused in one line; its files are kept."""
    out = tmp_path / "out"
    assert runner.invoke(app, ["sweep", str(_sweep_config(tmp_path)), "--out", str(out)]).exit_code == 0
    other = _sweep_config(tmp_path, SWEEP_CONFIG.replace("[0.06, 0.1]", "[0.06, 0.11]"))
    result = runner.invoke(app, ["sweep", str(other), "--out", str(out)])
    assert result.exit_code == 1
    assert result.stderr.startswith(f"error: {out} holds the checkpoints of another sweep (key ")
    assert "they differ in ['poses']" in result.stderr


def test_sweep_reports_failed_chunks_with_their_parameters(tmp_path):
    """A point the builder refuses is listed with its parameters (exit 1); the rest is written."""
    text = SWEEP_CONFIG.replace("harada2011_3d4m", "tests.sweep.conftest:fragile_2prrrp").replace(
        "legs: [[1, 2, 4], [1, 2, 3, 4]]", "half_plate: [0.05, 0.07]"
    )
    out = tmp_path / "out"
    result = runner.invoke(
        app, ["sweep", str(_sweep_config(tmp_path, text)), "--out", str(out), "--chunk", "1"]
    )
    assert result.exit_code == 1
    assert "1 computed now" in result.stdout and (out / "result.nc").is_file()
    assert result.stderr == (
        "failed: chunk of points 1-1: 1 point(s) failed\n"
        "  point 1 (half_plate=0.07): RuntimeError: fragile builder refuses half_plate = 0.07 m\n"
    )


def test_sweep_unreachable_scheduler_is_one_error_line(tmp_path, monkeypatch):
    """--scheduler tcp://127.0.0.1:1: one line saying the scheduler cannot be reached, exit 1."""
    from plm_pin.sweep import execution

    monkeypatch.setattr(execution, "CONNECT_TIMEOUT", 1.0)
    config, out = _sweep_config(tmp_path), tmp_path / "out"
    result = runner.invoke(app, ["sweep", str(config), "--out", str(out), "--scheduler", "tcp://127.0.0.1:1"])
    assert result.exit_code == 1 and result.stdout == ""
    assert result.stderr.startswith(
        "error: cannot reach the Dask scheduler at 'tcp://127.0.0.1:1' within 1 s"
    )
    assert result.stderr.count("\n") == 1


def test_version_is_the_package_version():
    """`plm-pin --version` prints plm_pin.__version__, which is also the installed distribution's."""
    from importlib.metadata import version

    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0
    assert result.output.strip() == f"plm-pin {plm_pin.__version__}"
    assert version("plm-pin") == plm_pin.__version__


def test_python_dash_m_runs_the_command_line():
    """`python -m plm_pin --version` is the same command."""
    out = subprocess.run(
        [sys.executable, "-m", "plm_pin", "--version"], capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == f"plm-pin {plm_pin.__version__}"


def test_report_without_the_report_extra_is_one_line_naming_it(tmp_path):
    """With jinja2 missing, `plm-pin report fourbar` prints one line with the extra and writes nothing."""
    code = (
        "import sys; sys.modules['jinja2'] = None; sys.argv = ['plm-pin', 'report', 'fourbar', '--out', "
        f"{str(tmp_path / 'out')!r}]; from plm_pin.cli import main; main()"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 1
    assert out.stderr.strip().splitlines() == [
        "error: plm_pin.report needs jinja2 and markdown-it-py, which are not installed: "
        "pip install 'plm-pin[report]'"
    ]
    assert not (tmp_path / "out").exists()


def test_a_missing_module_is_named_with_its_extra():
    """An ImportError of an optional module becomes one line naming the extra that provides it."""
    from plm_pin.cli import missing_extra

    err = ModuleNotFoundError("No module named 'matplotlib'", name="matplotlib")
    assert (
        missing_extra(err)
        == "this command needs matplotlib, which is not installed: pip install 'plm-pin[viz]'"
    )
    own = ImportError("plm_pin.sweep needs dask, which is not installed: pip install 'plm-pin[sweep]'")
    assert missing_extra(own) == str(own)


def test_fk_all_prints_every_certified_mode_of_the_fourbar():
    """`fk fourbar crank_pivot=0.3 --all` says all 2 modes are certified; --json gives the rocker angles."""
    result = runner.invoke(app, ["fk", "fourbar", "crank_pivot=0.3", "--all"])
    assert result.exit_code == 0, result.output
    assert "all 2 assembly modes (certified; 2 complex roots)" in " ".join(result.stdout.split())
    assert result.stdout.count("Krawczyk") == 2
    data = json.loads(runner.invoke(app, ["fk", "fourbar", "crank_pivot=0.3", "--all", "--json"]).stdout)
    assert data["complete"] and data["method"] == "homotopy" and len(data["modes"]) == 2
    mech = plm_pin.load("fourbar")
    from plm_pin.kinematics import forward_kinematics, task_pose

    expected = sorted(float(task_pose(mech, s.q)[0]) for s in forward_kinematics(mech, [0.3]))
    assert sorted(m["x"][0] for m in data["modes"]) == pytest.approx(expected, abs=1e-12)


def test_fk_bad_assignment_is_one_error_line():
    """`fk fourbar crank=1` names the valid actuator joints in one error line."""
    result = runner.invoke(app, ["fk", "fourbar", "crank=1"])
    _assert_clean_failure(
        result, "actuator 'crank=1': 'crank' is not an actuated joint of fourbar, one of ['crank_pivot']"
    )


def _harada_eq2(pose, signs, rod=0.14, half_plate=0.05) -> list[float]:
    """Harada 2011 eq. (2) for the 3D4M, c_i = L_ix + s_i sqrt(l^2 - L_iy^2) (legs 1, 2 on the left)."""
    x, y, theta = pose
    out = []
    for i, sign in enumerate(signs):
        s = -half_plate if i < 2 else half_plate
        Lx, Ly = x + s * math.cos(theta), y + s * math.sin(theta)
        out.append(Lx + sign * math.sqrt(rod**2 - Ly**2))
    return out


@pytest.mark.parametrize("mode", ["+,-,+,-", "-,-,+,+"])
def test_ik_3d4m_gives_harada_eq2_in_the_mode_asked_for(mode):
    """`ik harada2011_3d4m x= y= rz= --mode` prints eq. (2)'s slider positions (signs: minus the mode)."""
    pose = (0.01, 0.08, -0.3)
    args = ["ik", "harada2011_3d4m", "x=0.01", "y=0.08", "rz=-0.3", f"--mode={mode}", "--json"]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    signs = [-1 if w == "+" else 1 for w in mode.split(",")]
    expected = _harada_eq2(pose, signs)
    assert list(data["actuators"].values()) == pytest.approx(expected, abs=1e-12)
    assert [data["q"][f"slider{i}"] for i in (1, 2, 3, 4)] == pytest.approx(expected, abs=1e-12)
    assert data["working_mode"] == [-s for s in signs]
    assert data["closure_residual"] <= 1e-12
    table = runner.invoke(app, args[:-1])
    assert table.exit_code == 0, table.output
    assert re.search(rf"working mode\s*│\s*{re.escape(mode)}\s", table.stdout)
    assert re.search(rf"actuator slider1\s*│\s*{expected[0]:.9g}\s", table.stdout)


def test_ik_fourbar_crank_is_the_circle_intersection():
    """`ik fourbar rz=1.8`: the crank angle puts the crank tip on the coupler circle about the rocker tip."""
    crank, coupler, rocker, ground, theta = 0.10, 0.25, 0.20, 0.30, 1.8
    B = np.array([ground + rocker * math.cos(theta), rocker * math.sin(theta)])  # rocker tip
    d = float(np.linalg.norm(B))
    a = (crank**2 - coupler**2 + d**2) / (2.0 * d)
    h = math.sqrt(crank**2 - a**2)
    perp = np.array([-B[1], B[0]]) / d
    roots = sorted(math.atan2(*(a * B / d + s * h * perp)[::-1]) for s in (-1.0, 1.0))
    found = []
    for mode in ("+", "-"):
        result = runner.invoke(app, ["ik", "fourbar", "rz=1.8", f"--mode={mode}", "--json"])
        assert result.exit_code == 0, result.output
        data = json.loads(result.stdout)
        assert data["q"]["rocker_pivot"] == pytest.approx(theta, abs=1e-12)
        found.append(data["actuators"]["crank_pivot"])
    assert sorted(found) == pytest.approx(roots, abs=1e-12)  # the two modes are the two intersections


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["x=0.01", "y=0.08"],
            "missing task coordinates ['rz']: give every one of ['x', 'y', 'rz'] as NAME=VALUE",
        ),
        (
            ["x=0", "y=0.08", "rz=0", "z=1"],
            "task coordinate 'z=1': 'z' is not a task coordinate of harada2011_3d4m, one of ['x', 'y', 'rz']",
        ),
        (["x=0", "y=0.08", "rz=zero"], "task coordinate 'rz=zero': 'zero' is not a finite number"),
        (["x=0", "y=0.08", "rz=0", "x=1"], "task coordinate 'x=1': 'x' is given twice"),
        (["x=0", "y=0.08", "rz=inf"], "task coordinate 'rz=inf': 'inf' is not a finite number"),
        (["x=0", "y=0.08", "=1"], "task coordinate '=1': write NAME=VALUE, e.g. x=0.1"),
        (
            ["x=0", "y=0.08", "rz=0", "--mode=+,-"],
            "--mode '+,-': give 4 signs (+ or -), comma-separated, one per leg of harada2011_3d4m, "
            "e.g. --mode=+,-,+,-",
        ),
        (
            ["x=0", "y=0.08", "rz=0", "--mode=+,-,+,x"],
            "--mode '+,-,+,x': give 4 signs (+ or -), comma-separated, one per leg of harada2011_3d4m, "
            "e.g. --mode=+,-,+,-",
        ),
        (
            ["x=0", "y=1", "rz=0"],
            "harada2011_3d4m: pose [0.0, 1.0, 0.0] is out of reach of the end-effector chain (slider1): "
            "it misses by 0.858 m/rad",
        ),
    ],
)
def test_ik_bad_input_is_one_error_line(args, message):
    """Unknown, missing or malformed coordinates, bad modes and unreachable poses: one error line each."""
    _assert_clean_failure(runner.invoke(app, ["ik", "harada2011_3d4m", *args]), message)


def _read_map(path: Path) -> tuple[list[str], np.ndarray]:
    lines = path.read_text().splitlines()
    return lines[0].split(","), np.array([[float(v) for v in line.split(",")] for line in lines[1:]])


def test_map_csv_has_a_row_per_pose_with_the_api_metrics(tmp_path):
    """`map --x --y --fixed rz=`: a row per pose (x outer), metrics equal to pointwise IK + manipulability."""
    from plm_pin.kinematics import classify
    from plm_pin.workspace import manipulability_at

    out = tmp_path / "map.csv"
    args = ["map", "harada2011_3d4m", "--x", "-0.02:0.02:3", "--y", "0.06:0.1:4", "--fixed", "rz=-0.3"]
    args += ["--metric", "manipulability,condition_number,direct_margin", "--csv", str(out)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert f"wrote {out}" in result.stdout
    header, rows = _read_map(out)
    assert header == [
        "x [m]",
        "y [m]",
        "rz [rad]",
        "reachable",
        "manipulability [m/rad]",
        "condition_number [-]",
        "direct_margin [-]",
    ]
    assert rows.shape == (12, 7)
    mech = plm_pin.load("harada2011_3d4m")
    from plm_pin.kinematics import inverse_kinematics

    k = 0
    for x in (-0.02, 0.0, 0.02):
        for y in np.linspace(0.06, 0.1, 4):
            pose = (x, y, -0.3)
            assert rows[k, :3] == pytest.approx(pose, abs=1e-15)
            assert rows[k, 3] == 1
            m = manipulability_at(mech, pose, mode=(1, -1, 1, -1))
            q = inverse_kinematics(mech, pose, mode=(1, -1, 1, -1)).q
            assert rows[k, 4:6] == pytest.approx([m.w, m.condition_number], rel=1e-9)
            assert rows[k, 6] == pytest.approx(classify(mech, q).direct_margin, rel=1e-9)
            k += 1
    assert re.search(r"poses\s*│\s*3 x 4 = 12", result.stdout)
    assert re.search(r"working mode\s*│\s*\+,-,\+,-", result.stdout)


def _joint_task_fivebar(folder: Path) -> Path:
    """The fivebar preset with a joint task: its two elbow angles; returns the URDF."""
    from plm_pin.models.registry import urdf_folder

    for suffix in (".urdf", ".plm.yaml"):
        (folder / f"fivebar{suffix}").write_text((urdf_folder() / f"fivebar{suffix}").read_text())
    sidecar = folder / "fivebar.plm.yaml"
    data = yaml.safe_load(sidecar.read_text())
    data["end_effector"] = {"joints": ["left_elbow", "right_elbow"]}
    sidecar.write_text(yaml.safe_dump(data))
    return folder / "fivebar.urdf"


def test_map_over_joint_task_coordinates(tmp_path):
    """`map --over left_elbow=... --over right_elbow=...`: w = |det dc/dx| by central differences of IK."""
    from plm_pin.kinematics import inverse_kinematics

    urdf = _joint_task_fivebar(tmp_path)
    out = tmp_path / "map.csv"
    args = ["map", str(urdf), "--over", "left_elbow=-1.4:-1.2:3", "--over", "right_elbow=1.4:1.5:2"]
    result = runner.invoke(app, [*args, "--csv", str(out)])
    assert result.exit_code == 0, result.output
    header, rows = _read_map(out)
    assert header[:3] == ["left_elbow [rad]", "right_elbow [rad]", "reachable"]
    assert header[3].startswith("manipulability [")
    mech = plm_pin.load(urdf)
    h = 1e-6
    k = 0
    for a in (-1.4, -1.3, -1.2):
        for b in (1.4, 1.5):
            x = np.array([a, b])
            assert rows[k, :2] == pytest.approx(x, abs=1e-15) and rows[k, 2] == 1

            def actuators(x):
                return mech.actuator_positions(inverse_kinematics(mech, x).q)

            jac = np.column_stack(
                [(actuators(x + h * e) - actuators(x - h * e)) / (2 * h) for e in np.eye(2)]
            )
            assert rows[k, 3] == pytest.approx(abs(np.linalg.det(jac)), rel=1e-6)
            k += 1


@pytest.mark.parametrize(
    ("over", "message"),
    [
        (
            ["--over", "left_elbow=-1.4:-1.2:3"],
            "a map varies two task coordinates: give two of "
            "['--over left_elbow=...', '--over right_elbow=...'], got 1",
        ),
        (
            ["--over", "foo=0:1:2", "--over", "left_elbow=0:1:2"],
            "--over 'foo=0:1:2': 'foo' is not a task coordinate of fivebar, "
            "one of ['left_elbow', 'right_elbow']",
        ),
        (
            ["--over", "left_elbow=0:1:2", "--over", "left_elbow=0:1:3"],
            "--over 'left_elbow=0:1:3': 'left_elbow' is given twice",
        ),
        (
            ["--over", "left_elbow 0:1:2"],
            "--over 'left_elbow 0:1:2': write NAME=VALUE, e.g. --over left_elbow=-0.1:0.1:21",
        ),
        (
            ["--over", "left_elbow=1:0:2", "--over", "right_elbow=0:1:2"],
            "--over left_elbow '1:0:2': START must be below STOP; write START:STOP:COUNT "
            "(e.g. --over left_elbow=-0.05:0.05:21)",
        ),
    ],
)
def test_map_over_refuses_bad_words_in_one_line(tmp_path, over, message):
    urdf = _joint_task_fivebar(tmp_path)
    out = tmp_path / "map.csv"
    _assert_clean_failure(runner.invoke(app, ["map", str(urdf), *over, "--csv", str(out)]), message)
    assert not out.exists()


def test_map_refuses_to_overwrite_without_force(tmp_path):
    """An existing CSV is kept (one error line) unless --force; with --force it is replaced."""
    out = tmp_path / "map.csv"
    out.write_text("keep me\n")
    args = ["map", "harada2011_3d4m", "--x", "-0.01:0.01:2", "--y", "0.07:0.09:2", "--csv", str(out)]
    _assert_clean_failure(
        runner.invoke(app, args), f"--csv {out}: the file exists; give --force to overwrite it"
    )
    assert out.read_text() == "keep me\n"
    result = runner.invoke(app, [*args, "--force"])
    assert result.exit_code == 0, result.output
    assert out.read_text().startswith("x [m],y [m],rz [rad],reachable,manipulability [m/rad]\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.csv"]  # no temporary file left beside it


@pytest.mark.parametrize(
    ("ranges", "message"),
    [
        (
            ["--x", "0.02:0.01:5", "--y", "0.06:0.1:4"],
            "--x '0.02:0.01:5': START must be below STOP; write START:STOP:COUNT (e.g. --x -0.05:0.05:21)",
        ),
        (
            ["--x", "-0.02:0.02:1", "--y", "0.06:0.1:4"],
            "--x '-0.02:0.02:1': COUNT must be at least 2; write START:STOP:COUNT (e.g. --x -0.05:0.05:21)",
        ),
        (
            ["--x", "-0.02:0.02:5", "--y", "a:0.1:4"],
            "--y 'a:0.1:4': START and STOP must be finite numbers; write START:STOP:COUNT "
            "(e.g. --y -0.05:0.05:21)",
        ),
        (
            ["--x", "-0.02:0.02:2.5", "--y", "0.06:0.1:4"],
            "--x '-0.02:0.02:2.5': COUNT '2.5' is not a whole number; write START:STOP:COUNT "
            "(e.g. --x -0.05:0.05:21)",
        ),
        (
            ["--x", "-0.02:0.02", "--y", "0.06:0.1:4"],
            "--x '-0.02:0.02': expected 3 fields separated by ':', got 2; write START:STOP:COUNT "
            "(e.g. --x -0.05:0.05:21)",
        ),
        (
            ["--x", "-0.02:0.02:3"],
            "a map varies two task coordinates: give two of ['--x', '--y', '--rz'], got 1",
        ),
        (
            ["--x", "-0.02:0.02:3", "--z", "0:1:2"],
            "--z: harada2011_3d4m's task has no coordinate 'z'; its coordinates are ['x', 'y', 'rz']",
        ),
        (
            ["--x", "-0.02:0.02:3", "--y", "0:1:2", "--metric", "speed"],
            "--metric 'speed': unknown metric; metrics are ['manipulability', 'condition_number', "
            "'constraint_margin', 'inverse_margin', 'direct_margin'] or all",
        ),
    ],
)
def test_map_bad_ranges_are_one_error_line(tmp_path, ranges, message):
    """Ranges with n < 2, a >= b or non-numbers, a missing axis, an unknown metric: one line, no file."""
    out = tmp_path / "map.csv"
    _assert_clean_failure(runner.invoke(app, ["map", "harada2011_3d4m", *ranges, "--csv", str(out)]), message)
    assert list(tmp_path.iterdir()) == []


def test_map_writes_nowhere_but_an_existing_folder(tmp_path):
    """A CSV path in a missing folder is refused; no folder is created."""
    out = tmp_path / "missing" / "map.csv"
    args = ["map", "harada2011_3d4m", "--x", "-0.01:0.01:2", "--y", "0.07:0.09:2", "--csv", str(out)]
    _assert_clean_failure(runner.invoke(app, args), f"--csv {out}: the folder {out.parent} does not exist")
    assert list(tmp_path.iterdir()) == []


def _report_json(out: Path, folder: str) -> dict:
    return json.loads((out / folder / "results.json").read_text())


def _table(data: dict, title: str) -> list[list]:
    """The rows of the first table titled ``title`` in a report's results.json."""
    return next(b["rows"] for s in data["sections"] for b in s["blocks"] if b.get("title") == title)


def test_report_load_pose_and_mode_reach_the_overview_statics(tmp_path):
    """`report 3d4m --load --pose --mode --x --y`: f_c is static_forces at eq. (2)'s q with that wrench."""
    from plm_pin.statics import static_forces
    from tests.conftest import prrrp_paper_configuration

    out = tmp_path / "reports"
    case = ["--load", "3,-2,0.1", "--pose", "x=0.01,y=0.07", "--mode=+,-,+,-"]
    ranges = ["--x", "-0.02:0.02:5", "--y", "0.05:0.09:4"]
    result = runner.invoke(app, ["report", "harada2011_3d4m", *case, *ranges, "--out", str(out)])
    assert result.exit_code == 0, result.output
    data = _report_json(out, "overview-harada2011_3d4m")
    mech = plm_pin.load("harada2011_3d4m")
    pose = (0.01, 0.07, -math.radians(20.0))  # rz stays the reference's, Harada's -20 deg
    q = prrrp_paper_configuration(mech, pose, (0.14,) * 4, 0.05, (-1, 1, -1, 1))  # mode +,-,+,-
    expected = static_forces(mech, q, [3.0, -2.0, 0.1]).f_c
    rows = _table(data, "Actuator forces f_c")
    assert [r[0] for r in rows] == ["slider1", "slider2", "slider3", "slider4"]
    np.testing.assert_allclose([r[2] for r in rows], expected, atol=1e-9)
    assert np.max(np.abs(expected - static_forces(mech, q).f_c)) > 1.0  # the load counts
    figure = next(
        b
        for s in data["sections"]
        for b in s["blocks"]
        if b["kind"] == "figure" and "slice" in b.get("data", {})
    )
    values = figure["data"]["slice"]["values"]
    np.testing.assert_allclose(values[0], np.linspace(-0.02, 0.02, 5), atol=1e-15)
    np.testing.assert_allclose(values[1], np.linspace(0.05, 0.09, 4), atol=1e-15)
    assert figure["data"]["slice"]["working_mode"] == [1, -1, 1, -1]
    assert data["command"].endswith(" ".join([*case, *ranges, "--out", str(out)]))


def test_report_load_on_the_fourbar_rocker_reaches_the_statics(tmp_path):
    """`report fourbar --load 0.5 --pose rz=1.8`: the crank torque is static_forces at that pose and load."""
    from plm_pin.kinematics import inverse_kinematics
    from plm_pin.statics import static_forces

    out = tmp_path / "reports"
    result = runner.invoke(app, ["report", "fourbar", "--load", "0.5", "--pose", "rz=1.8", "--out", str(out)])
    assert result.exit_code == 0, result.output
    rows = _table(_report_json(out, "overview-fourbar"), "Actuator forces f_c")
    mech = plm_pin.load("fourbar")
    q = inverse_kinematics(mech, [1.8]).q
    assert rows[0][2] == pytest.approx(static_forces(mech, q, [0.5]).f_c[0], abs=1e-10)
    assert rows[0][2] != pytest.approx(static_forces(mech, q).f_c[0], abs=1e-3)  # the load counts


def test_report_with_a_pose_loads_and_solves_once(tmp_path, monkeypatch):
    """`report fourbar --pose rz=1.8`: the shell's check loads and solves; the study reuses both."""
    from plm_pin.report import overview, study

    loads, solves = [], []

    def counted_load(*args, **kwargs):
        loads.append(args)
        return plm_pin.load(*args, **kwargs)

    def counted_ik(mech, x, *args, **kwargs):
        solves.append(np.array(x, dtype=float))
        return inverse_kinematics(mech, x, *args, **kwargs)

    from plm_pin.kinematics import inverse_kinematics

    monkeypatch.setattr(study, "load", counted_load)
    monkeypatch.setattr(overview, "inverse_kinematics", counted_ik)
    out = tmp_path / "reports"
    result = runner.invoke(app, ["report", "fourbar", "--pose", "rz=1.8", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert loads == []  # the study got the shell's mechanism
    assert sum(x.shape == (1,) and x[0] == 1.8 for x in solves) == 1


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["harada2011_3d4m", "--load", "3,-2"],
            "--load: give 3 finite numbers, one per task coordinate (fx,fy,mz) [N, N m], got [3.0, -2.0]",
        ),
        (["harada2011_3d4m", "--load", "3,a,1"], "--load: expected comma-separated numbers, got '3,a,1'"),
        (
            ["harada2011_3d4m", "--pose", "q=1"],
            "--pose: 'q' is not a task coordinate of harada2011_3d4m; they are ['x', 'y', 'rz']",
        ),
        (
            ["harada2011_3d4m", "--pose", "x:1"],
            "--pose 'x:1': write NAME=VALUE, e.g. --pose x=0.01,y=0.08",
        ),
        (["harada2011_3d4m", "--pose", "x=1,x=2"], "--pose 'x=2': 'x' is given twice"),
        (
            ["harada2011_3d4m", "--mode=+,x"],
            "--mode '+,x': give one sign (+ or -) per leg, comma-separated, e.g. --mode=+,-",
        ),
        (["harada2011_3d4m", "--mode=+,-"], "--mode must hold 4 signs (+1 or -1), one per leg; got (1, -1)"),
        (
            ["harada2011_3d4m", "--x", "0.1:0:3"],
            "--x '0.1:0:3': START must be below STOP; write START:STOP:COUNT (e.g. --x -0.05:0.05:21)",
        ),
        (
            ["all", "--load", "1,2,3"],
            "--load, --pose, --mode and slice ranges go with the overview of one mechanism "
            "(plm-pin report NAME|PATH ... or plm-pin report overview --mechanism NAME|PATH ...)",
        ),
    ],
)
def test_report_bad_case_options_are_one_error_line(tmp_path, args, message):
    """Malformed or mismatched --load, --pose, --mode, ranges: one error line, nothing written."""
    out = tmp_path / "reports"
    _assert_clean_failure(runner.invoke(app, ["report", *args, "--out", str(out)]), message)
    assert not out.exists()


def test_shell_guide_examples_run(tmp_path, monkeypatch):
    """Every `$ plm-pin ...` line of docs/guide/shell.md runs as written (in an empty folder), exit code 0."""
    import shlex

    page = Path(__file__).resolve().parents[1] / "docs" / "guide" / "shell.md"
    commands = re.findall(r"^\$ plm-pin (.+)$", page.read_text(encoding="utf-8"), flags=re.M)
    assert {c.split()[0] for c in commands} == {"ik", "fk", "accuracy", "map", "report"}
    monkeypatch.chdir(tmp_path)
    for command in commands:
        result = runner.invoke(app, shlex.split(command))
        assert result.exit_code == 0, f"{command}\n{result.output}"
    assert (tmp_path / "xy.csv").is_file() and (tmp_path / "reports" / "index.html").is_file()


def test_report_load_moves_a_horizontal_table(tmp_path):
    """Star triangle, gravity normal to its plane: --load gives J_ce^T f_c = -load; the simulation moves."""
    from plm_pin.kinematics import inverse_kinematics, task_pose

    out = tmp_path / "reports"
    load = np.array([5.0, -1.0, 0.2])
    result = runner.invoke(
        app, ["report", "enferadi2017_star_triangle", "--load", "5,-1,0.2", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    data = _report_json(out, "overview-enferadi2017_star_triangle")
    f_c = np.array([r[2] for r in _table(data, "Actuator forces f_c")])
    mech = plm_pin.load("enferadi2017_star_triangle")
    x0, h = task_pose(mech, mech.q_ref), 1e-6
    J = np.column_stack(  # J_ce by central differences of the inverse kinematics
        [
            (inverse_kinematics(mech, x0 + h * e).actuators - inverse_kinematics(mech, x0 - h * e).actuators)
            / (2 * h)
            for e in np.eye(3)
        ]
    )
    np.testing.assert_allclose(J.T @ f_c, -load, atol=1e-7)  # actuators' work + load's work = 0
    simulation = {r[0]: r[1] for r in _table(data, "Passive simulation")}
    assert simulation["largest joint speed"] > 0.01  # the load moves it (gravity alone does not)


def test_report_one_range_sweeps_that_coordinate(tmp_path):
    """`report fourbar --rz 1.6:1.8:3 --mode=+`: the sweep is over those 3 angles, in that working mode."""
    out = tmp_path / "reports"
    result = runner.invoke(app, ["report", "fourbar", "--rz", "1.6:1.8:3", "--mode=+", "--out", str(out)])
    assert result.exit_code == 0, result.output
    data = _report_json(out, "overview-fourbar")
    sweep = next(
        b["data"]["slice"] for s in data["sections"] for b in s["blocks"] if "slice" in b.get("data", {})
    )
    assert sweep["axes"] == ["rz"] and sweep["working_mode"] == [1]
    np.testing.assert_allclose(sweep["values"][0], [1.6, 1.7, 1.8], atol=1e-15)


def test_help_texts_keep_their_units_in_brackets():
    """Units written in brackets ([m, rad], [s]) reach the help text (rich markup would eat them)."""
    from typer.testing import CliRunner

    from plm_pin.cli import app

    check = " ".join(CliRunner().invoke(app, ["check", "--help"], terminal_width=200).output.split())
    assert "how far the description's loops close [m, rad]" in check
    export = " ".join(CliRunner().invoke(app, ["export", "--help"], terminal_width=200).output.split())
    assert "MuJoCo step [s]" in export


def _elbow(O: np.ndarray, P: np.ndarray, outward: float, proximal: float, distal: float) -> np.ndarray:
    """The five-bar elbow on circles (O, proximal) and (P, distal), on the side ``outward`` (-1 or +1)."""
    d = float(np.linalg.norm(P - O))
    a = (proximal**2 - distal**2 + d**2) / (2 * d)
    h = math.sqrt(proximal**2 - a**2)
    mid = O + a * (P - O) / d
    normal = np.array([-(P - O)[1], (P - O)[0]]) / d
    return max((mid + h * normal, mid - h * normal), key=lambda E: outward * E[0])


def test_accuracy_fivebar_bound_is_the_closed_form_of_the_leg_constraints():
    """`accuracy fivebar x= y= --tol t,0`: each leg keeps the tip on its distal circle, (P - E).(dP - w) = 0.

    ``w`` is the leg tip's displacement by an error at fixed joint angles: a motor or elbow placement
    error moves it by the error (rotated into the parent link), a tip-frame error by the error in the
    distal link's axes; errors along z move nothing in the plane and the angle tolerance is 0.
    """
    base, proximal, distal, t = 0.2, 0.15, 0.2, 2e-5  # the builder's defaults, kept by the preset
    P = np.array([0.03, 0.24])
    result = runner.invoke(app, ["accuracy", "fivebar", "x=0.03", "y=0.24", f"--tol={t},0", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    columns = []
    A = []
    for k, (O, outward) in enumerate(((np.array([-base / 2, 0.0]), -1.0), (np.array([base / 2, 0.0]), 1.0))):
        E = _elbow(O, P, outward, proximal, distal)
        A.append(P - E)
        a, phi = math.atan2(*(E - O)[::-1]), math.atan2(*(P - E)[::-1])
        for rotation in (0.0, a, phi):  # the motor's, the elbow's and the tip frame's placement axes
            for e in np.eye(2):
                w = (
                    np.array(
                        [[math.cos(rotation), -math.sin(rotation)], [math.sin(rotation), math.cos(rotation)]]
                    )
                    @ e
                )
                rhs = np.zeros(2)
                rhs[k] = (P - E) @ w
                columns.append(rhs)
    S = np.linalg.solve(np.array(A), np.array(columns).T)
    assert data["worst_case"] == pytest.approx(np.abs(S).sum(axis=1) * t, rel=1e-8)
    assert data["rms"] == pytest.approx(np.sqrt((S**2).sum(axis=1)) * t, rel=1e-8)
    assert data["length_tolerance"] == t and data["angle_tolerance"] == 0.0
    table = runner.invoke(app, ["accuracy", "fivebar", "x=0.03", "y=0.24", f"--tol={t},0"])
    assert table.exit_code == 0 and "38 parameters" in table.stdout


@pytest.mark.parametrize("tol", ["", "1e-5", "1e-5,-1", "a,b"])
def test_accuracy_refuses_a_malformed_tolerance(tol):
    args = ["accuracy", "fivebar"] + ([f"--tol={tol}"] if tol else [])
    result = runner.invoke(app, args)
    assert result.exit_code == 1
    assert "LENGTH,ANGLE" in result.output


def test_report_over_a_joint_task_slices_those_joints(tmp_path):
    """`report FIVEBAR --over left_elbow=... --over right_elbow=...`: the slice is over those joint values."""
    urdf = _joint_task_fivebar(tmp_path)
    out = tmp_path / "reports"
    args = ["report", str(urdf), "--over", "left_elbow=-1.4:-1.2:3", "--over", "right_elbow=1.4:1.5:2"]
    result = runner.invoke(app, [*args, "--out", str(out)])
    assert result.exit_code == 0, result.output
    data = _report_json(out, "overview-fivebar")
    grid = next(
        b["data"]["slice"] for s in data["sections"] for b in s["blocks"] if "slice" in b.get("data", {})
    )
    assert grid["axes"] == ["left_elbow", "right_elbow"]
    np.testing.assert_allclose(grid["values"][0], [-1.4, -1.3, -1.2], atol=1e-15)
    np.testing.assert_allclose(grid["values"][1], [1.4, 1.5], atol=1e-15)
    assert "--over left_elbow=-1.4:-1.2:3 --over right_elbow=1.4:1.5:2" in json.dumps(data)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["fourbar", "--over", "rz=0:1:2", "--rz", "0:1:3"],
            "--over 'rz=0:1:2': 'rz' is also varied by --rz",
        ),
        (
            ["fourbar", "--over", "crank=0:1:2"],
            "--over crank: 'crank' is not a task coordinate of fourbar; they are ['rz']",
        ),
        (["fourbar", "--over", "rz=1:0:2"], "--over rz '1:0:2': START must be below STOP"),
    ],
)
def test_report_bad_over_is_one_error_line(tmp_path, args, message):
    """A coordinate varied twice, unknown or with a bad range: one error line naming it, nothing written."""
    out = tmp_path / "reports"
    result = runner.invoke(app, ["report", *args, "--out", str(out)])
    assert result.exit_code != 0 and message in result.output
    assert not out.exists()
