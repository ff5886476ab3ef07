"""The command line never prints a traceback for bad input or a failing disk: one `error:` line, exit 1."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest
import yaml

from plm_pin.report import writer
from plm_pin.sweep import store as store_module
from tests.robustness.conftest import fourbar_files, fourbar_sidecar, one_line_error, run_cli

DRIVES = [
    (1e300, 0.0, 1e-300),
    (0.0, 1e300, 1e-300),
    (1e10, 0.0, 1e-160),
    (1e308, 1e308, 1.0),
    (1.0, 0.0, 1e-200),
]
"""(rotor_inertia, screw_inertia, lead) whose reflected inertia overflows a float."""


def overflowing(tmp_path: Path, rotor: float, screw: float, lead: float) -> Path:
    """The four-bar with a drive whose reflected inertia overflows."""
    data = fourbar_sidecar()
    data["actuation"][0].update({"rotor_inertia": rotor, "screw_inertia": screw, "lead": lead})
    return fourbar_files(tmp_path, sidecar=yaml.safe_dump(data))


@pytest.mark.parametrize("command", ["info", "check", "report"])
@pytest.mark.parametrize(("rotor", "screw", "lead"), DRIVES)
def test_an_overflowing_reflected_inertia_is_one_line(tmp_path, command, rotor, screw, lead):
    """The issue's OverflowError (rotor_inertia 1e300, lead 1e-300) in info, check and report: one line."""
    urdf = overflowing(tmp_path / "d", rotor, screw, lead)
    args = [command, str(urdf)] + (["--out", str(tmp_path / "out")] if command == "report" else [])
    line = one_line_error(run_cli(*args))
    assert (
        "actuation[0] (actuator 'crank_pivot': the reflected inertia (rotor_inertia + screw_inertia)" in line
    )
    assert "overflows a float" in line


@pytest.mark.parametrize("below", ["sub", "sub/deeper", "a/b/c"])
def test_report_out_below_a_file_is_one_line(tmp_path, below):
    """`report --out afile/sub`: the file in the way is named, no traceback."""
    (tmp_path / "afile").write_text("x")
    out = tmp_path / "afile" / below
    line = one_line_error(run_cli("report", "fourbar", "--out", str(out)))
    assert line.startswith(f"error: {tmp_path / 'afile'}") or line.startswith(f"error: {out}")
    assert "Not a directory" in line or "File exists" in line


FAULTS = [
    (errno.ENOSPC, "No space left on device"),
    (errno.EACCES, "Permission denied"),
    (errno.EROFS, "Read-only file system"),
    (errno.EDQUOT, "Disk quota exceeded"),
    (errno.EIO, "Input/output error"),
]
"""Operating-system errors a full, read-only or failing output disk raises."""


def failing(code: int, where: str):
    """A stand-in for a file-system call that fails with ``code`` on ``where``."""

    def fail(*args, **kwargs):
        raise OSError(code, os.strerror(code), where)

    return fail


@pytest.mark.parametrize(("code", "text"), FAULTS[:3])
def test_a_report_onto_a_failing_disk_is_one_line(tmp_path, monkeypatch, code, text):
    """A disk that fails while the report folder is made (full, read-only, ...) gives one line, exit 1."""
    monkeypatch.setattr(writer.tempfile, "mkdtemp", failing(code, str(tmp_path / "out")))
    line = one_line_error(run_cli("report", "fourbar", "--out", str(tmp_path / "out")))
    assert line == f"error: {tmp_path / 'out'}: {text}"


@pytest.mark.parametrize(("code", "text"), FAULTS[:2])
def test_a_report_whose_files_cannot_be_written_is_one_line(tmp_path, monkeypatch, code, text):
    """A write failing midway (a full disk) leaves no debris and gives one line."""
    real = Path.write_text

    def write_text(self, *args, **kwargs):
        if self.name == "report.html":
            raise OSError(code, os.strerror(code), str(self))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", write_text)
    out = tmp_path / "out"
    line = one_line_error(run_cli("report", "fourbar", "--out", str(out)))
    assert line.startswith(f"error: {out}/.overview-fourbar.") and line.endswith(f"report.html: {text}")
    assert sorted(p.name for p in out.iterdir()) == []


@pytest.mark.parametrize("target", ["afile/page.html", "afile/sub/page.html"])
def test_view_html_below_a_file_is_one_line(tmp_path, target):
    """`view --html` onto a path through an existing file names it, no traceback."""
    (tmp_path / "afile").write_text("x")
    line = one_line_error(run_cli("view", "fourbar", "--html", str(tmp_path / target)))
    assert line.startswith(f"error: {tmp_path / 'afile'}")


@pytest.mark.parametrize(("code", "text"), FAULTS[:3])
def test_view_html_onto_a_failing_disk_is_one_line(tmp_path, monkeypatch, code, text):
    """A static page that cannot be written (full or read-only disk) gives one line."""
    from plm_pin.viz import meshcat_view

    monkeypatch.setattr(meshcat_view, "atomic_write_text", failing(code, str(tmp_path / "page.html")))
    line = one_line_error(run_cli("view", "fourbar", "--html", str(tmp_path / "page.html")))
    assert line == f"error: {tmp_path / 'page.html'}: {text}"


SWEEP = """\
mechanism: harada2011_3d4m
parameters:
  legs: [[1, 2, 4]]
poses:
  y: [0.08]
  rz: [0.0, 0.1]
pose: [0.0, 0.08, 0.0]
metrics: [manipulability]
"""

MANIFESTS = {
    "binary": b"\x00\xff\xfe garbage",
    "truncated JSON": b'{"key": "abc", "spe',
    "a list": b"[]",
    "null": b"null",
    "a string": b'"key"',
    "no spec": b'{"key": "abc"}',
    "a numeric key": b'{"key": 1, "spec": {}}',
    "a list spec": b'{"key": "abc", "spec": []}',
    "empty": b"",
}


@pytest.mark.parametrize("case", sorted(MANIFESTS))
def test_sweep_onto_a_garbage_manifest_is_one_line(tmp_path, case):
    """A manifest.json that is not ours is refused in one line that says how to go on."""
    config = tmp_path / "sweep.yaml"
    config.write_text(SWEEP)
    out = tmp_path / "out"
    out.mkdir()
    (out / "manifest.json").write_bytes(MANIFESTS[case])
    line = one_line_error(run_cli("sweep", str(config), "--out", str(out)))
    assert line.startswith(f"error: {out / 'manifest.json'}: not a plm_pin sweep manifest (")
    assert line.endswith("); give another folder, or delete it to start again")


@pytest.mark.parametrize(("code", "text"), FAULTS)
def test_sweep_onto_a_read_only_or_full_out_is_one_line(tmp_path, monkeypatch, code, text):
    """A --out that cannot be created or written gives one line naming it, exit 1."""
    config = tmp_path / "sweep.yaml"
    config.write_text(SWEEP)
    out = tmp_path / "out"
    real = Path.mkdir

    def mkdir(self, *args, **kwargs):
        if self.is_relative_to(out):
            raise OSError(code, os.strerror(code), str(self))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Path, "mkdir", mkdir)
    line = one_line_error(run_cli("sweep", str(config), "--out", str(out)))
    assert line == f"error: {out / 'chunks'}: {text}"


def test_sweep_whose_checkpoint_cannot_be_written_is_one_line(tmp_path, monkeypatch):
    """A disk filling up while chunks are written gives one line (the finished chunks stay)."""
    config = tmp_path / "sweep.yaml"
    config.write_text(SWEEP)
    monkeypatch.setattr(store_module, "atomic_path", failing(errno.ENOSPC, str(tmp_path / "out" / "chunks")))
    line = one_line_error(run_cli("sweep", str(config), "--out", str(tmp_path / "out")))
    assert line == f"error: {tmp_path / 'out' / 'chunks'}: No space left on device"


def test_sweep_onto_a_folder_in_use_is_one_line_naming_the_holder(tmp_path):
    """A second `plm-pin sweep` on a locked --out says which process holds it."""
    from plm_pin.sweep import load_config
    from plm_pin.sweep.store import SweepStore

    config = tmp_path / "sweep.yaml"
    config.write_text(SWEEP)
    out = tmp_path / "out"
    with SweepStore(out, load_config(config)[0]):
        line = one_line_error(run_cli("sweep", str(config), "--out", str(out)))
    assert line.startswith(f"error: {out} is in use by another sweep (process {os.getpid()} on ")
