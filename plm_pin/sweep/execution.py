"""Splitting a sweep into chunks and running them: in this process, on a local Dask cluster, or remotely.

A *chunk* is a run of consecutive parameter points, each with its whole pose grid, so that
every point is computed by the same calls in the same order whichever chunk holds it and
wherever the chunk runs: results do not depend on the chunking or on the executor (the
inverse-kinematics continuation never crosses a chunk boundary). A chunk holds about
``chunk`` poses (:data:`DEFAULT_CHUNK`), never less than one parameter point.

On several workers, chunks of one point that would leave workers idle in the last round
(3 points on 2 workers: the third alone) are split into one *share* per worker thread
(:class:`~plm_pin.sweep.metrics.PointEvaluation`): every share solves the point's whole grid,
the metrics that analyse each reached pose or line independently (orientation ranges, static
forces, stiffness) take every n-th of them, and the shares are merged into the point before
it is reported. The values are those of the whole point, bit for bit.

Execution, by ``scheduler``:

- None: in this process when the work is small (fewer than :data:`IN_PROCESS_MAX` poses,
  one chunk of whole points, or ``workers=1``), else on a :class:`distributed.LocalCluster` of ``workers``
  single-threaded processes (default: all CPUs) bound to 127.0.0.1;
- an address ``tcp://host:8786``: a running Dask scheduler (``dask scheduler``, with
  ``dask worker tcp://host:8786`` on each machine, plm_pin installed there);
- a :class:`distributed.Client`: used as it is.

The spec is scattered once to every worker (``client.scatter(spec, broadcast=True)``).
Where the mechanisms come from:

- one parameter point (a :class:`~plm_pin.Mechanism` given as it is, e.g. from
  ``plm_pin.load("robot.urdf")``, or a builder with nothing varied): the spec holds that
  mechanism (:attr:`~plm_pin.sweep.SweepSpec.built`, built or loaded once on the client), so
  it travels pickled with the spec and is never built or loaded on a worker; a worker
  needs neither the builder nor the description files;
- several parameter points: each worker builds its own points from the builder and the
  parameters, the build being part of the parallel work. Measured on this 2-core machine
  (shared with other work, medians of runs at different loads): a build takes 6-10 ms
  (``harada2011_3d4m``) and 20-145 ms (``zhao2011_8pss``, about 120 ms typically), its
  pickle is 38 kB and 103 kB and costs 0.7-1.4 ms and 2.4-4.1 ms to dump and load.
  Shipping one mechanism is cheaper than building it, but the client builds one after the
  other on one core (on a local cluster, the workers' cores): on a 2-worker LocalCluster,
  12 points built on the client and shipped took 1.1-2.6 times as long (3D4M, 9 and 180
  poses per point) and 2.0-4.1 times as long (8-PSS, 1 and 20 poses) as the same points
  built by the workers, in three runs.

A parameter point that raises is recorded with its message and the chunk goes on; a chunk
whose task fails (a worker lost) is reported whole. Either way the other chunks complete.
"""

from __future__ import annotations

import contextlib
import logging
import os
import shutil
import uuid
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._version import __version__
from ..exceptions import InvalidInput, PlmError, SchedulerUnreachable
from ._deps import require
from .metrics import METRICS, PointEvaluation
from .spec import SweepSpec

if TYPE_CHECKING:
    from distributed import Client

DEFAULT_CHUNK = 4096
"""Poses per chunk (task) by default; a chunk holds whole parameter points."""

IN_PROCESS_MAX = 20_000
"""Local sweeps of fewer poses run in the calling process (no cluster to start)."""

CONNECT_TIMEOUT = 10.0
"""Time allowed to reach a Dask scheduler [s]."""

WORKER_TIMEOUT = 30.0
"""Time allowed for a remote scheduler to have at least one worker [s]."""


@dataclass(frozen=True)
class Chunk:
    """Consecutive parameter points computed by one task.

    Attributes:
        points: their flat indices, increasing.
        share: ``(k, n)``: the k-th of n shares of its one point (``(0, 1)``: whole points).
    """

    points: tuple[int, ...]
    share: tuple[int, int] = (0, 1)

    @property
    def first(self) -> int:
        """First parameter point."""
        return self.points[0]

    @property
    def last(self) -> int:
        """Last parameter point."""
        return self.points[-1]


@dataclass
class ChunkValues:
    """What a chunk computed.

    Attributes:
        points: the parameter points, shape (n,).
        values: variable name -> values, shape ``(n, *variable shape)``.
        errors: point -> ``"Type: message"`` for the points that raised (their values are fill values).
    """

    points: np.ndarray
    values: dict[str, np.ndarray]
    errors: dict[int, str]


def evaluate_point(spec: SweepSpec, index: int, share: tuple[int, int] = (0, 1)) -> dict[str, np.ndarray]:
    """The variables of the sweep at one parameter point (or a share of it): build, run the metrics.

    A variable a share does not compute is left out (its fill values stand).
    """
    ev = PointEvaluation(spec.pose_grid(), spec.build(index), share)
    out: dict[str, np.ndarray] = {}
    for name in spec.metrics:
        if ev.computes(METRICS[name]):
            out.update(METRICS[name].compute(ev))
    return out


def evaluate_chunk(spec: SweepSpec, points: Sequence[int], share: tuple[int, int] = (0, 1)) -> ChunkValues:
    """Evaluate the parameter points of a chunk, in order (the task a worker runs).

    A point that raises gets fill values and its error message; the others go on.
    """
    variables = spec.variables()
    n = len(points)
    values = {
        v.name: np.full((n, *spec.variable_shape(v)), v.fill, dtype=np.dtype(v.dtype)) for v in variables
    }
    errors: dict[int, str] = {}
    for k, index in enumerate(points):
        try:
            point = evaluate_point(spec, int(index), share)
        except Exception as exc:  # reported with the point's parameters; the sweep goes on
            errors[int(index)] = f"{type(exc).__name__}: {exc}"
            continue
        for name, value in point.items():
            values[name][k] = value
    return ChunkValues(np.asarray(points, dtype=np.int64), values, errors)


def merge_shares(spec: SweepSpec, shares: Sequence[ChunkValues]) -> ChunkValues:
    """One point's values from its shares: each entry from the share that computed it.

    A share leaves what it does not compute at the fill value, and an entry its owner computed
    as the fill value (an unreached pose) is the fill value in every share.
    """
    values = {}
    for v in spec.variables():
        merged = shares[0].values[v.name].copy()
        for other in shares[1:]:
            value = other.values[v.name]
            filled = np.isnan(value) if v.dtype == "float64" else value == v.fill
            merged[~filled] = value[~filled]
        values[v.name] = merged
    errors = {p: m for share in reversed(shares) for p, m in share.errors.items()}
    return ChunkValues(shares[0].points, values, errors)


def split_chunks(spec: SweepSpec, chunks: Sequence[Chunk], workers: int) -> list[Chunk]:
    """``chunks`` with the one-point chunks of the last, incomplete round split into ``workers`` shares.

    Nothing is split on one worker, when the rounds are complete, or when no metric splits.
    """
    last = len(chunks) % workers
    if workers == 1 or not last or not any(METRICS[m].split for m in spec.metrics):
        return list(chunks)
    out = list(chunks[: len(chunks) - last])
    for chunk in chunks[len(chunks) - last :]:
        if len(chunk.points) == 1:
            out.extend(Chunk(chunk.points, (k, workers)) for k in range(workers))
        else:
            out.append(chunk)
    return out


def _merged(spec: SweepSpec, outcomes: Iterator[Outcome]) -> Iterator[Outcome]:
    """``outcomes`` with the shares of a point gathered into the point (reported once, when complete).

    A share that fails fails its point (once; the point's other shares are then dropped).
    """
    pending: dict[int, list[ChunkValues]] = {}
    failed: set[int] = set()
    for chunk, outcome in outcomes:
        n = chunk.share[1]
        if n == 1:
            yield chunk, outcome
            continue
        point = chunk.first
        if point in failed:
            continue
        whole = Chunk(chunk.points)
        if isinstance(outcome, BaseException):
            failed.add(point)
            pending.pop(point, None)
            yield whole, outcome
            continue
        parts = pending.setdefault(point, [])
        parts.append(outcome)
        if len(parts) == n:
            del pending[point]
            yield whole, merge_shares(spec, parts)


def points_per_chunk(spec: SweepSpec, chunk: int) -> int:
    """Parameter points per chunk for about ``chunk`` poses per chunk (at least one point).

    Raises:
        InvalidInput: ``chunk`` below 1.
    """
    if isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 1:
        raise InvalidInput(f"chunk must be a positive number of poses per task, got {chunk!r}")
    return max(1, chunk // spec.n_poses)


def plan_chunks(done: np.ndarray, per_chunk: int) -> list[Chunk]:
    """Chunks covering the points not ``done``: runs of consecutive points, ``per_chunk`` at most each."""
    chunks: list[Chunk] = []
    run: list[int] = []
    for index in np.flatnonzero(~done).tolist():
        if run and (index != run[-1] + 1 or len(run) == per_chunk):
            chunks.append(Chunk(tuple(run)))
            run = []
        run.append(index)
    if run:
        chunks.append(Chunk(tuple(run)))
    return chunks


Outcome = tuple[Chunk, "ChunkValues | BaseException"]


def in_process(spec: SweepSpec, chunks: Sequence[Chunk]) -> Iterator[Outcome]:
    """Run the chunks here, one after the other."""
    for chunk in chunks:
        try:
            yield chunk, evaluate_chunk(spec, chunk.points)
        except Exception as exc:  # e.g. MemoryError inside numpy: the chunk is reported, the rest run
            yield chunk, exc


def _plm_pin_version() -> str:
    """plm_pin's version where this runs (checked on every worker)."""
    return __version__


def on_dask(client: Client, spec: SweepSpec, chunks: Sequence[Chunk]) -> Iterator[Outcome]:
    """Run the chunks as tasks of a Dask client, yielding each as it finishes."""
    distributed = require("distributed")
    shared = client.scatter(spec, broadcast=True, hash=False)
    run = uuid.uuid4().hex[:8]
    futures = {
        client.submit(
            evaluate_chunk,
            shared,
            chunk.points,
            chunk.share,
            key=f"plm-pin-sweep-{run}-{chunk.first}-{chunk.share[0]}",
            pure=False,
        ): chunk
        for chunk in split_chunks(spec, chunks, max(1, sum(client.nthreads().values())))
    }

    def outcomes() -> Iterator[Outcome]:
        for future in distributed.as_completed(futures, loop=client.loop):
            chunk = futures[future]
            try:
                yield chunk, future.result()
            except Exception as exc:  # a lost worker, an unpicklable value: reported, the rest go on
                yield chunk, exc
            future.release()

    try:
        yield from _merged(spec, outcomes())
    finally:
        client.cancel(list(futures))


def connect(
    address: str, connect_timeout: float | None = None, worker_timeout: float | None = None
) -> Client:
    """A client of the Dask scheduler at ``address`` with at least one worker running plm_pin.

    Args:
        address: the scheduler, ``tcp://host:port``.
        connect_timeout: time allowed to reach it [s] (default :data:`CONNECT_TIMEOUT`).
        worker_timeout: time allowed for a worker to be there [s] (default :data:`WORKER_TIMEOUT`).

    Raises:
        SchedulerUnreachable: no scheduler answers within ``connect_timeout`` seconds, or it
            has no worker after ``worker_timeout`` seconds.
        PlmError: a worker lacks plm_pin, or runs another version.
    """
    distributed = require("distributed")
    connect_timeout = CONNECT_TIMEOUT if connect_timeout is None else connect_timeout
    worker_timeout = WORKER_TIMEOUT if worker_timeout is None else worker_timeout
    try:
        client = distributed.Client(address, timeout=connect_timeout, set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise SchedulerUnreachable(
            f"cannot reach the Dask scheduler at {address!r} within {connect_timeout:g} s ({exc}); start "
            "one with `dask scheduler` and workers with `dask worker tcp://HOST:8786`, or run without "
            "--scheduler",
            address,
            connect_timeout,
        ) from None
    try:
        client.wait_for_workers(1, timeout=worker_timeout)
    except (TimeoutError, OSError):
        client.close()
        raise SchedulerUnreachable(
            f"the Dask scheduler at {address!r} has no worker after {worker_timeout:g} s; start some with "
            f"`dask worker {address}` on machines where plm_pin is installed",
            address,
            worker_timeout,
        ) from None
    try:
        versions = client.run(_plm_pin_version)
    except Exception as exc:
        client.close()
        raise PlmError(
            f"the workers of {address!r} cannot run plm_pin ({type(exc).__name__}: {exc}); install plm-pin "
            f"{__version__} with the 'sweep' extra on every worker"
        ) from None
    other = {w: v for w, v in versions.items() if v != __version__}
    if other:
        client.close()
        raise PlmError(f"workers of {address!r} run other plm_pin versions {other}; this is {__version__}")
    return client


@contextlib.contextmanager
def local_cluster(workers: int, local_directory: Path | None) -> Iterator[Client]:
    """A client of a LocalCluster of ``workers`` single-threaded processes on 127.0.0.1, closed on exit."""
    distributed = require("distributed")
    scratch = None if local_directory is None else local_directory / "dask-scratch"
    cluster = distributed.LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address="127.0.0.1:0",  # a free port on loopback (None still binds 8787)
        silence_logs=logging.ERROR,
        local_directory=None if scratch is None else str(scratch),
    )
    try:
        with distributed.Client(cluster, set_as_default=False) as client:
            yield client
    finally:
        cluster.close()
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)


def check_execution(scheduler: str | Client | None, workers: int | None) -> None:
    """Check where a sweep is asked to run, before any work.

    Raises:
        InvalidInput: ``workers`` below 1, ``workers`` with a scheduler, or a scheduler that
            is neither an address nor a :class:`distributed.Client`.
    """
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise InvalidInput(f"workers must be a positive number of processes, got {workers!r}")
    if scheduler is not None and workers is not None:
        raise InvalidInput("workers sizes a local cluster; a scheduler's cluster has its own workers")
    if scheduler is not None and not isinstance(scheduler, str):
        distributed = require("distributed")
        if not isinstance(scheduler, distributed.Client):
            raise InvalidInput(
                f"scheduler must be an address tcp://host:port or a distributed.Client, got {scheduler!r}"
            )


def run_chunks(
    spec: SweepSpec,
    chunks: Sequence[Chunk],
    *,
    scheduler: str | Client | None = None,
    workers: int | None = None,
    local_directory: Path | None = None,
) -> Iterator[Outcome]:
    """Run ``chunks`` where ``scheduler`` says (see the module docstring), yielding each as it finishes.

    The arguments are those :func:`check_execution` accepts.

    Raises:
        SchedulerUnreachable: see :func:`connect`.
    """
    if not chunks:
        return
    if scheduler is None:
        n = workers or os.cpu_count() or 1
        if not any(METRICS[m].split for m in spec.metrics):  # whole points: one task each at most
            n = min(n, len(chunks))
        poses = sum(len(c.points) for c in chunks) * spec.n_poses
        if n == 1 or poses < IN_PROCESS_MAX:
            yield from in_process(spec, chunks)
            return
        with local_cluster(n, local_directory) as client:
            yield from on_dask(client, spec, chunks)
    elif isinstance(scheduler, str):
        client = connect(scheduler)
        try:
            yield from on_dask(client, spec, chunks)
        finally:
            client.close()
    else:
        yield from on_dask(scheduler, spec, chunks)
