"""Sweep execution: chunk plans, results independent of chunk size and executor, failures, schedulers."""

from __future__ import annotations

import concurrent.futures

import numpy as np
import pytest
import xarray as xr

from plm_pin import InvalidInput, SchedulerUnreachable
from plm_pin.sweep import execution, make_spec, sweep
from plm_pin.sweep.execution import plan_chunks
from tests.sweep.conftest import THETAS, fragile_2prrrp, small


@pytest.fixture(scope="module")
def reference():
    """The small sweep in this process, one chunk per parameter point."""
    return sweep(**small(), chunk=1)


def test_chunks_cover_the_missing_points_in_runs():
    """Chunks are runs of consecutive missing points, at most per_chunk long, never across a done point."""
    done = np.array([False, False, False, True, False, True, True, False, False, False, False])
    chunks = plan_chunks(done, 2)
    assert [c.points for c in chunks] == [(0, 1), (2,), (4,), (7, 8), (9, 10)]
    assert [c.points for c in plan_chunks(np.zeros(3, dtype=bool), 10)] == [(0, 1, 2)]
    assert plan_chunks(np.ones(3, dtype=bool), 10) == []


def test_chunk_holds_whole_parameter_points():
    """About `chunk` poses per task, never less than one parameter point (its whole pose grid)."""
    spec = make_spec(**small())
    assert spec.n_poses == 3 * 33
    assert execution.points_per_chunk(spec, 1) == 1
    assert execution.points_per_chunk(spec, 250) == 2
    assert execution.points_per_chunk(spec, 10_000) == 101


def test_results_do_not_depend_on_the_chunk_size(reference):
    """One, two or all parameter points per chunk give bit-identical datasets."""
    for chunk in (200, 10_000):
        other = sweep(**small(), chunk=chunk)
        xr.testing.assert_identical(other.dataset, reference.dataset)
        assert other.complete
    assert [c for c in reference.computed] == [(0, 0), (1, 1), (2, 2), (3, 3)]


def test_a_failing_point_is_reported_with_its_parameters_and_the_rest_completes():
    """The builder refuses one plate size: that chunk fails with its parameters, the other chunks finish."""
    result = sweep(
        fragile_2prrrp,
        {"half_plate": [0.035, 0.05, 0.07, 0.04]},
        {"y": [0.08], "rz": THETAS},
        ["manipulability", "orientation_range"],
        pose=(0.0, 0.08, 0.0),
        chunk=2 * 33,
    )
    assert not result.complete and result.computed == ((0, 1),)
    (failure,) = result.failures
    assert (failure.first, failure.last) == (2, 3)
    (point,) = failure.points
    assert point.index == 2 and point.parameters == {"half_plate": 0.07}
    assert point.message == "RuntimeError: fragile builder refuses half_plate = 0.07 m"
    assert failure.describe() == (
        "chunk of points 2-3: 1 point(s) failed\n  point 2 (half_plate=0.07): RuntimeError: fragile builder "
        "refuses half_plate = 0.07 m"
    )
    assert failure.to_dict() == {
        "first": 2,
        "last": 3,
        "points": [{"index": 2, "parameters": {"half_plate": 0.07}, "message": point.message}],
    }
    ds = result.dataset
    assert ds.failed.values.tolist() == [False, False, True, False]
    assert np.isnan(ds.manipulability.values[2]).all() and np.isfinite(ds.manipulability.values[3]).any()
    assert ds.orientation_lower_end.values[2].tolist() == [-1]


def test_unreachable_scheduler_gives_a_clear_error_without_hanging(monkeypatch):
    """tcp://127.0.0.1:1 refuses connections: SchedulerUnreachable names it and says what to start."""
    monkeypatch.setattr(execution, "CONNECT_TIMEOUT", 2.0)
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        job = pool.submit(sweep, **small(), scheduler="tcp://127.0.0.1:1")
        with pytest.raises(SchedulerUnreachable) as err:
            job.result(timeout=60)  # a hang fails here instead of blocking the suite
    message = str(err.value)
    assert message.startswith("cannot reach the Dask scheduler at 'tcp://127.0.0.1:1' within 2 s (")
    assert "start one with `dask scheduler` and workers with `dask worker tcp://HOST:8786`" in message
    assert err.value.address == "tcp://127.0.0.1:1" and err.value.timeout == 2.0


def test_scheduler_and_workers_are_checked():
    """A scheduler that is no address or client, or workers with a scheduler, are refused."""
    with pytest.raises(
        InvalidInput, match=r"scheduler must be an address tcp://host:port or a distributed\.Client"
    ):
        sweep(**small(), scheduler=3)
    with pytest.raises(InvalidInput, match="workers sizes a local cluster"):
        sweep(**small(), scheduler="tcp://127.0.0.1:1", workers=2)


@pytest.mark.slow
def test_dask_cluster_gives_the_local_results_bit_for_bit(cluster, reference):
    """On a 2-worker LocalCluster, by Client and by address, the dataset equals the in-process one."""
    distributed = pytest.importorskip("distributed")
    with distributed.Client(cluster) as client:
        on_client = sweep(**small(), chunk=1, scheduler=client)
        workers = {w for w in client.run(lambda: 0)}
    assert len(workers) == 2
    xr.testing.assert_identical(on_client.dataset, reference.dataset)
    assert sorted(on_client.computed) == [(0, 0), (1, 1), (2, 2), (3, 3)]
    by_address = sweep(**small(), chunk=200, scheduler=cluster.scheduler_address)
    xr.testing.assert_identical(by_address.dataset, reference.dataset)


@pytest.mark.slow
def test_dask_reports_a_failing_point_and_completes_the_rest(cluster):
    """On the cluster too, the failing chunk is reported with its parameters and the others finish."""
    args = (
        fragile_2prrrp,
        {"half_plate": [0.035, 0.07, 0.05]},
        {"y": [0.08], "rz": THETAS},
        ["manipulability"],
    )
    local = sweep(*args, chunk=1)
    remote = sweep(*args, chunk=1, scheduler=cluster.scheduler_address)
    xr.testing.assert_identical(remote.dataset, local.dataset)
    assert sorted(remote.computed) == [(0, 0), (2, 2)]
    assert [p.parameters for f in remote.failures for p in f.points] == [{"half_plate": 0.07}]


@pytest.mark.slow
def test_local_default_starts_a_cluster_for_large_sweeps_with_the_same_results(
    monkeypatch, reference, tmp_path
):
    """Above IN_PROCESS_MAX poses a local sweep starts a 2-process cluster; its scratch stays in the store."""
    started = []
    real = execution.local_cluster

    def spy(workers, local_directory):
        started.append((workers, local_directory))
        return real(workers, local_directory)

    monkeypatch.setattr(execution, "IN_PROCESS_MAX", 0)
    monkeypatch.setattr(execution, "local_cluster", spy)
    result = sweep(**small(), chunk=1, workers=2, store=tmp_path / "store")
    assert started == [(2, tmp_path / "store")]
    xr.testing.assert_identical(result.dataset, reference.dataset)
    assert sorted(p.name for p in (tmp_path / "store").iterdir()) == [
        ".lock",
        "chunks",
        "manifest.json",
    ]  # .lock: the store lock (filelock)


SPLIT = ["manipulability", "singularity", "min_manipulability", "orientation_range", "peak_force"]
"""Grid metrics (share 0 alone) beside split ones: per line (orientation_range), per pose (peak_force)."""


@pytest.mark.parametrize("shares", [2, 3])
def test_shares_of_a_point_merge_into_the_whole_point_bit_for_bit(shares):
    """Each share computes every n-th line or reached pose; merged, they equal the unsplit point."""
    spec = make_spec(**small(metrics=SPLIT, poses={"y": [0.05, 0.11], "rz": THETAS[::4]}))
    whole = execution.evaluate_chunk(spec, (1,))
    parts = [execution.evaluate_chunk(spec, (1,), (k, shares)) for k in range(shares)]
    assert not any(
        np.array_equal(p.values["peak_force"], whole.values["peak_force"], equal_nan=True) for p in parts
    )
    merged = execution.merge_shares(spec, parts)
    assert merged.values.keys() == whole.values.keys()
    for name, value in whole.values.items():
        np.testing.assert_array_equal(merged.values[name], value, err_msg=name)


def test_only_the_last_incomplete_round_of_one_point_chunks_is_split():
    """3 points on 2 workers: two whole, the third in two shares; complete rounds or no split metric: none."""
    spec = make_spec(**small(metrics=SPLIT))
    chunks = plan_chunks(np.zeros(3, dtype=bool), 1)
    split = execution.split_chunks(spec, chunks, 2)
    assert [(c.points, c.share) for c in split] == [
        ((0,), (0, 1)),
        ((1,), (0, 1)),
        ((2,), (0, 2)),
        ((2,), (1, 2)),
    ]
    assert execution.split_chunks(spec, chunks, 3) == chunks
    assert execution.split_chunks(spec, chunks, 1) == chunks
    grid_only = make_spec(**small(metrics=["manipulability"], options={}))
    assert execution.split_chunks(grid_only, chunks, 2) == chunks


@pytest.mark.slow
def test_three_points_on_two_workers_split_the_third_and_give_the_local_results(cluster):
    """The third point runs as two shares on the 2-worker cluster; the dataset equals the in-process one."""
    args = small(metrics=SPLIT, parameters={"half_plate": [0.03, 0.035, 0.05]})
    local = sweep(**args, chunk=1)
    remote = sweep(**args, chunk=1, scheduler=cluster.scheduler_address)
    xr.testing.assert_identical(remote.dataset, local.dataset)
    assert sorted(remote.computed) == [(0, 0), (1, 1), (2, 2)]
