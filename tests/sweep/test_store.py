"""Checkpoint stores: resume computes only missing chunks, other sweeps are refused, kills corrupt nothing."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from plm_pin import StoreMismatch
from plm_pin.sweep import make_spec, sweep
from plm_pin.sweep.store import MANIFEST, SweepStore, chunk_name
from plm_pin.warnings import CorruptChunkWarning
from tests.sweep.conftest import small

REPO = Path(__file__).resolve().parents[2]


def _files(store: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted((store / "chunks").glob("points-*.parquet"))}


def test_rerun_loads_every_chunk_and_computes_nothing(tmp_path):
    """A finished sweep run again reads its chunks back bit for bit and computes no chunk."""
    store = tmp_path / "s"
    first = sweep(**small(), chunk=1, store=store)
    assert first.loaded == 0 and first.computed_points == 4
    assert sorted(_files(store)) == [chunk_name(i, i) for i in range(4)]
    manifest = json.loads((store / MANIFEST).read_text())
    assert manifest["key"] == first.key and manifest["spec"]["metrics"] == small()["metrics"]
    again = sweep(**small(), chunk=1, store=store)
    assert again.loaded == 4 and again.computed == ()
    xr.testing.assert_identical(again.dataset, first.dataset)


def test_resume_with_another_chunk_size_fills_only_the_missing_points(tmp_path):
    """With chunks 1 and 3 deleted, a re-run with another chunk size computes exactly points 1 and 3."""
    store = tmp_path / "s"
    full = sweep(**small(), chunk=1, store=store)
    for i in (1, 3):
        (store / "chunks" / chunk_name(i, i)).unlink()
    kept = _files(store)
    resumed = sweep(**small(), chunk=10_000, store=store)
    assert resumed.loaded == 2 and sorted(resumed.computed) == [(1, 1), (3, 3)]
    after = _files(store)
    assert all(after[name] == data for name, data in kept.items())
    xr.testing.assert_identical(resumed.dataset, full.dataset)


def test_another_sweeps_folder_is_refused_naming_the_differences(tmp_path):
    """A store holding other arguments raises StoreMismatch listing the fields that differ; nothing mixes."""
    store = tmp_path / "s"
    sweep(**small(), store=store)
    before = _files(store)
    with pytest.raises(StoreMismatch) as err:
        sweep(**small(metrics=["manipulability"], options={}), store=store)
    message = str(err.value)
    assert message.startswith(f"{store} holds the checkpoints of another sweep (key ")
    assert message.endswith(
        "they differ in ['metrics', 'options']): give another folder, or delete it to start again"
    )
    assert err.value.differences == ("metrics", "options") and err.value.path == store
    assert _files(store) == before


def test_unreadable_or_foreign_chunks_are_recomputed_with_a_warning(tmp_path):
    """A truncated chunk file is ignored with CorruptChunkWarning and its points computed again."""
    store = tmp_path / "s"
    full = sweep(**small(), chunk=1, store=store)
    bad = store / "chunks" / chunk_name(2, 2)
    bad.write_bytes(bad.read_bytes()[:100])
    with pytest.warns(CorruptChunkWarning, match=r"points-0000002-0000002.parquet: cannot be used \("):
        again = sweep(**small(), chunk=1, store=store)
    assert again.computed == ((2, 2),) and again.loaded == 3
    xr.testing.assert_identical(again.dataset, full.dataset)
    spec = make_spec(**small())
    assert len(SweepStore(store, spec).load()) == 4  # rewritten whole


def test_a_write_interrupted_before_its_rename_leaves_no_chunk(tmp_path):
    """A temporary file (a kill during a write) is never read as a chunk and is removed by the next run."""
    store = tmp_path / "s"
    sweep(**small(), chunk=1, store=store)
    (store / "chunks" / chunk_name(0, 0)).unlink()
    stale = store / "chunks" / f".{chunk_name(0, 0)}.abc123.tmp"
    stale.write_bytes(b"half a parquet file")
    again = sweep(**small(), chunk=1, store=store)
    assert again.computed == ((0, 0),) and not stale.exists()


def test_failed_chunks_are_not_checkpointed(tmp_path):
    """A chunk with a failing point is left out of the store, so the next run tries it again."""
    from tests.sweep.conftest import THETAS, fragile_2prrrp

    args = (fragile_2prrrp, {"half_plate": [0.035, 0.07]}, {"y": [0.08], "rz": THETAS}, ["manipulability"])
    first = sweep(*args, chunk=1, store=tmp_path / "s")
    assert first.computed == ((0, 0),) and len(first.failures) == 1
    assert sorted(_files(tmp_path / "s")) == [chunk_name(0, 0)]
    second = sweep(*args, chunk=1, store=tmp_path / "s")
    assert second.loaded == 1 and second.computed == () and second.failures[0].first == 1


SLOW_SWEEP = {
    "mechanism": "harada2011_3d3m",
    "parameters": {"half_plate": np.linspace(0.03, 0.06, 10).tolist()},
    "poses": {"y": np.linspace(0.03, 0.12, 12).tolist(), "rz": np.radians(np.linspace(-80, 80, 33)).tolist()},
    "metrics": ["orientation_range", "manipulability"],
    "pose": [0.0, 0.08, 0.0],
}
"""About 0.4 s per parameter point: slow enough to kill after a few chunks."""


@pytest.mark.slow
def test_killed_sweep_resumes_with_the_missing_chunks_only(tmp_path):
    """SIGKILL after a few checkpoints: finished chunks stay intact, the re-run computes only the others."""
    store = tmp_path / "s"
    code = (
        "import json, sys\nfrom plm_pin.sweep import sweep\n"
        "kw = json.loads(sys.argv[1])\n"
        "sweep(kw.pop('mechanism'), **kw, chunk=1, store=sys.argv[2])\n"
    )
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen([sys.executable, "-c", code, json.dumps(SLOW_SWEEP), str(store)], env=env)
    try:
        deadline = time.monotonic() + 120.0
        while len(list((store / "chunks").glob("points-*.parquet"))) < 3:
            assert proc.poll() is None, "the sweep ended before it could be interrupted"
            assert time.monotonic() < deadline, "no checkpoint appeared"
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    before = _files(store)
    assert 3 <= len(before) < 10
    done = {int(name.split("-")[1]) for name in before}
    kw = dict(SLOW_SWEEP)
    resumed = sweep(kw.pop("mechanism"), **kw, chunk=1, store=store)
    assert resumed.loaded == len(before)
    assert sorted(first for first, _ in resumed.computed) == sorted(set(range(10)) - done)
    after = _files(store)
    assert all(after[name] == data for name, data in before.items())
    assert len(after) == 10
    kw = dict(SLOW_SWEEP)
    uninterrupted = sweep(kw.pop("mechanism"), **kw, chunk=10_000)
    xr.testing.assert_identical(resumed.dataset, uninterrupted.dataset)
