"""Faults: killed report swaps are undone, sweep folders are locked, flipped checkpoint bits are caught."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import xarray as xr

from plm_pin import StoreLocked
from plm_pin.report import run_study, write_index, write_report
from plm_pin.report.writer import recover
from plm_pin.sweep import make_spec, sweep
from plm_pin.sweep.store import SweepStore, chunk_name
from plm_pin.warnings import CorruptChunkWarning
from tests.report.conftest import make_study
from tests.robustness.conftest import REPO

ENV = {**os.environ, "PYTHONPATH": str(REPO)}

KILLS = {
    "while writing the files": """
        real = Path.write_text
        def write_text(self, *args, **kwargs):
            if self.name == "report.html":
                os.kill(os.getpid(), signal.SIGKILL)
            return real(self, *args, **kwargs)
        Path.write_text = write_text
    """,
    "between the two renames": """
        writer._exchange = lambda a, b: False  # the fallback of systems without renameat2
        real, calls = os.rename, []
        def rename(src, dst):
            calls.append(src)
            if len(calls) == 2:  # the old report moved aside, the new one not yet in place
                os.kill(os.getpid(), signal.SIGKILL)
            return real(src, dst)
        writer.os.rename = rename
    """,
    "after the exchange": """
        real = writer._exchange
        def exchange(a, b):
            done = real(a, b)
            os.kill(os.getpid(), signal.SIGKILL)
            return done
        writer._exchange = exchange
    """,
}
"""Where a run of ``write_report`` is killed (SIGKILL: no handler runs), as code patched in before it."""


def killed_report(out: Path, where: str) -> None:
    """Run write_report of a new demo report into ``out`` in a subprocess killed at ``where``."""
    code = "\n".join(
        [
            "import os, signal, sys",
            "from pathlib import Path",
            "from plm_pin.report import run_study, write_report, writer",
            "from tests.report.conftest import make_study",
            "result = run_study(make_study(lambda ctx: ctx.section('new').text('the new report')))",
            textwrap.dedent(KILLS[where]),
            "write_report(result, sys.argv[1])",
        ]
    )
    done = subprocess.run([sys.executable, "-c", code, str(out)], env=ENV, cwd=REPO, timeout=300, check=False)
    assert done.returncode == -signal.SIGKILL


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` (relative path -> bytes)."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("where", sorted(KILLS))
def test_a_report_run_killed_anywhere_leaves_a_whole_report_after_recovery(tmp_path, where):
    """Killed while writing, between the renames or after the exchange: the next run finds a whole report."""
    out = tmp_path / "out"
    write_report(run_study(make_study()), out)
    old = snapshot(out / "demo")
    killed_report(out, where)
    if where == "after the exchange":  # the atomic step happened: the report folder is never missing
        assert (out / "demo").is_dir() and snapshot(out / "demo") != old
    recover(out)
    assert sorted(p.name for p in out.iterdir()) == ["demo"]  # no .tmp / .old folder left
    report = snapshot(out / "demo")
    assert sorted(report) == ["report.html", "results.json"]
    if where == "after the exchange":
        assert "the new report" in report["report.html"].decode()
    else:
        assert report == old  # the previous report, back in place
    index = write_index(out).read_text()
    assert 'href="demo/report.html"' in index


def test_only_working_folders_of_ended_runs_are_removed(tmp_path):
    """Recovery leaves a live writer's folders and other hidden files alone; a dead writer's go."""
    out = tmp_path / "out"
    out.mkdir()
    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()
    live = [out / f".demo.{os.getpid()}.abc123.tmp", out / f".demo.{os.getppid()}.abc123.old"]
    dead = [out / f".demo.{ended.pid}.abc123.tmp", out / f".demo.{ended.pid}.zz_9.old"]
    others = [out / ".demo.tmp", out / ".hidden", out / f".a.b.{ended.pid}.x.tmp"]
    for folder in live + dead + others:
        folder.mkdir()
    recover(out)
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in live + others)


SWEEP = {
    "mechanism": "harada2011_3d4m",
    "parameters": {"half_plate": [0.035, 0.05, 0.06]},
    "poses": {"y": [0.08], "rz": [0.0, 0.1]},
    "pose": (0.0, 0.08, 0.0),
    "metrics": ["manipulability"],
}


def test_a_second_sweep_on_a_locked_folder_is_refused_naming_the_holder(tmp_path):
    """While one sweep holds the folder, another (here: this process) is refused with its pid and host."""
    store = tmp_path / "s"
    spec = make_spec(**SWEEP)
    code = "\n".join(
        [
            "import sys, time",
            "from plm_pin.sweep import make_spec",
            "from plm_pin.sweep.store import SweepStore",
            f"store = SweepStore(sys.argv[1], make_spec(**{SWEEP!r}))",
            "print('ready', flush=True)",
            "time.sleep(120)",
        ]
    )
    holder = subprocess.Popen(
        [sys.executable, "-c", code, str(store)],
        env=ENV,
        cwd=REPO,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "ready\n"
        in_flight = store / "chunks" / f".{chunk_name(0, 0)}.abc.tmp"
        in_flight.write_bytes(b"the first sweep's chunk being written")
        with pytest.raises(StoreLocked) as err:
            sweep(**SWEEP, store=store)
        message = str(err.value)
        assert message.startswith(
            f"{store} is in use by another sweep (process {holder.pid} on {socket.gethostname()} since "
        )
        assert message.endswith("): wait for it to end, or give another folder")
        assert in_flight.exists()  # the refused run deleted nothing
        holder.send_signal(signal.SIGKILL)
        holder.wait(timeout=30)
    finally:
        if holder.poll() is None:
            holder.kill()
    # a killed holder's lock goes with its process: the folder is free again
    with SweepStore(store, spec):
        with pytest.raises(StoreLocked, match=rf"process {os.getpid()} on "):
            SweepStore(store, spec)
    assert sweep(**SWEEP, store=store).computed_points == 3


def flip(path: Path, position: int, bit: int) -> None:
    """Flip one bit of a file."""
    data = bytearray(path.read_bytes())
    data[position % len(data)] ^= 1 << bit
    path.write_bytes(bytes(data))


@pytest.fixture(scope="module")
def fresh():
    """The sweep's dataset computed without checkpoints."""
    return sweep(**SWEEP).dataset


@pytest.mark.parametrize(("position", "bit"), [(0, 0), (4, 7), (200, 3), (-300, 1), (-9, 5), (-1, 6)])
def test_a_flipped_bit_in_a_checkpoint_is_caught_and_recomputed(tmp_path, fresh, position, bit):
    """Any bit flipped in a chunk file fails its SHA-256: the chunk is recomputed, never served as data."""
    store = tmp_path / "s"
    sweep(**SWEEP, chunk=1, store=store)
    flip(store / "chunks" / chunk_name(1, 1), position, bit)
    with pytest.warns(
        CorruptChunkWarning, match=r"points-0000001-0000001\.parquet: cannot be used \(ValueError: its "
    ):
        again = sweep(**SWEEP, chunk=1, store=store)
    assert again.loaded == 2 and again.computed == ((1, 1),)
    xr.testing.assert_identical(again.dataset, fresh)
    assert sweep(**SWEEP, chunk=1, store=store).loaded == 3  # rewritten with its hash


@pytest.mark.parametrize("damage", ["deleted", "garbage", "another chunk's"])
def test_a_chunk_without_its_right_hash_is_recomputed(tmp_path, fresh, damage):
    """A hash file missing, garbled or belonging to another chunk makes the chunk untrusted."""
    store = tmp_path / "s"
    sweep(**SWEEP, chunk=1, store=store)
    digest = store / "chunks" / f"{chunk_name(2, 2)}.sha256"
    if damage == "deleted":
        digest.unlink()
    elif damage == "garbage":
        digest.write_text("not a hash\n")
    else:
        digest.write_bytes((store / "chunks" / f"{chunk_name(0, 0)}.sha256").read_bytes())
    with pytest.warns(CorruptChunkWarning, match=r"SHA-256 is not the one recorded"):
        again = sweep(**SWEEP, chunk=1, store=store)
    assert again.computed == ((2, 2),)
    xr.testing.assert_identical(again.dataset, fresh)
