""":func:`sweep`: check a design sweep, resume it from its checkpoints, run the rest, label it."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path, PurePath
from typing import TYPE_CHECKING, Any

import numpy as np

from .._text import short
from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput
from ..models.registry import Builder
from ._deps import require
from .execution import DEFAULT_CHUNK, ChunkValues, check_execution, plan_chunks, points_per_chunk, run_chunks
from .result import ChunkFailure, PointFailure, SweepResult, build_dataset
from .spec import ParametersArg, PosesArg, SweepSpec, make_spec
from .store import SweepStore

if TYPE_CHECKING:
    from distributed import Client

Progress = Callable[[int, int], None]
"""Called with (parameter points done, parameter points in all) at the start and after each chunk."""


def _check_storable(spec: SweepSpec) -> None:
    if not isinstance(spec.mechanism, Mechanism) and "<" in spec.label:
        raise InvalidInput(
            f"a checkpointed sweep needs a builder importable by name (module:function); {spec.label} is a "
            "lambda or a local function, whose name does not identify it"
        )


def run_spec(
    spec: SweepSpec,
    *,
    store: str | Path | None = None,
    scheduler: str | Client | None = None,
    workers: int | None = None,
    chunk: int = DEFAULT_CHUNK,
    progress: Progress | None = None,
) -> SweepResult:
    """Run a checked sweep (see :func:`sweep` for the arguments); the store is locked while it runs."""
    start = time.perf_counter()
    require("xarray")
    per_chunk = points_per_chunk(spec, chunk)
    check_execution(scheduler, workers)
    if store is not None and not isinstance(store, (str, PurePath)):
        raise InvalidInput(f"store must be a folder path (a string or a Path) or None, got {short(store)}")
    if progress is not None and not callable(progress):
        raise InvalidInput(f"progress must be a function (done, total) or None, got {short(progress)}")
    if store is None:
        return _run(spec, None, scheduler, workers, per_chunk, progress, start)
    _check_storable(spec)
    require("pyarrow")
    with SweepStore(store, spec) as checkpoints:
        return _run(spec, checkpoints, scheduler, workers, per_chunk, progress, start)


def _run(
    spec: SweepSpec,
    checkpoints: SweepStore | None,
    scheduler: str | Client | None,
    workers: int | None,
    per_chunk: int,
    progress: Progress | None,
    start: float,
) -> SweepResult:
    """Resume ``spec`` from ``checkpoints``, compute the missing chunks, label the result."""
    variables = spec.variables()
    n = spec.n_points
    arrays = {
        v.name: np.full((n, *spec.variable_shape(v)), v.fill, dtype=np.dtype(v.dtype)) for v in variables
    }
    done = np.zeros(n, dtype=bool)
    failed = np.zeros(n, dtype=bool)

    def fill(values: ChunkValues) -> None:
        for name, arr in values.values.items():
            arrays[name][values.points] = arr

    loaded = 0
    for finished in checkpoints.load() if checkpoints is not None else []:
        fresh = ~done[finished.points]
        fill(ChunkValues(finished.points[fresh], {k: v[fresh] for k, v in finished.values.items()}, {}))
        done[finished.points] = True
        loaded += int(fresh.sum())
    finished_points = loaded
    if progress is not None:
        progress(finished_points, n)
    computed: list[tuple[int, int]] = []
    failures: list[ChunkFailure] = []
    chunks = plan_chunks(done, per_chunk)
    local = checkpoints.root if checkpoints is not None else None
    for part, outcome in run_chunks(
        spec, chunks, scheduler=scheduler, workers=workers, local_directory=local
    ):
        if isinstance(outcome, BaseException):
            message = f"{type(outcome).__name__}: {outcome}"
            points = tuple(PointFailure(i, spec.parameters.point(i), message) for i in part.points)
            failures.append(ChunkFailure(part.first, part.last, points))
            failed[list(part.points)] = True
        else:
            fill(outcome)
            if outcome.errors:
                points = tuple(
                    PointFailure(i, spec.parameters.point(i), m) for i, m in outcome.errors.items()
                )
                failures.append(ChunkFailure(part.first, part.last, points))
                failed[list(outcome.errors)] = True
            else:
                if checkpoints is not None:
                    checkpoints.write(outcome)
                computed.append((part.first, part.last))
        finished_points += len(part.points)
        if progress is not None:
            progress(finished_points, n)
    dataset = build_dataset(spec, arrays, failed)
    return SweepResult(
        dataset,
        spec,
        spec.key(),
        tuple(computed),
        loaded,
        tuple(failures),
        None if checkpoints is None else checkpoints.root,
        time.perf_counter() - start,
    )


def sweep(
    mechanism: str | Builder | Mechanism,
    parameters: ParametersArg = None,
    poses: PosesArg = None,
    metrics: Sequence[str] = ("manipulability",),
    *,
    base: Mapping[str, Any] | None = None,
    pose: Sequence[float] | None = None,
    options: Mapping[str, Any] | None = None,
    store: str | Path | None = None,
    scheduler: str | Client | None = None,
    workers: int | None = None,
    chunk: int = DEFAULT_CHUNK,
    progress: Progress | None = None,
) -> SweepResult:
    """Evaluate metrics over a grid of builder parameters times a grid of task poses.

    Every argument is checked before any work starts. At each parameter point the
    mechanism is built (:func:`plm_pin.build_mechanism`), or taken as given, and the
    metrics of :data:`plm_pin.sweep.METRICS` are evaluated over the pose grid in the
    working mode of its reference configuration. Results do not depend on ``chunk``,
    ``workers`` or ``scheduler``: each parameter point is computed by the same calls,
    wherever it runs. A Mechanism given (or a single point's, built here for the checks) is
    shipped to Dask workers pickled with the sweep, never rebuilt there; several points are
    built by the workers (:mod:`plm_pin.sweep.execution` says why, with measurements).

    Args:
        mechanism: a preset name (its builder, with the preset's parameters), a builder
            callable returning ``(robot, sidecar)`` (see :mod:`plm_pin.models`), the path
            of a description (its parameters: joint origins, lengths and masses, see
            :mod:`plm_pin.description.overrides`), or a :class:`~plm_pin.Mechanism` as it
            is (e.g. ``plm_pin.load("robot.urdf")``: its poses only, without ``parameters``
            or ``base``).
        parameters: the builder parameters varied: a mapping ``name -> values`` (their
            grid, row-major in the order given) or a list of mappings (samples, dimension
            ``sample``). A value is a number, a name or a list of them (e.g. ``rod_lengths``).
        poses: the task poses of every point: a mapping ``coordinate -> values`` [m or rad]
            (their grid, e.g. ``{"y": ..., "rz": ...}``).
        metrics: names among :data:`~plm_pin.sweep.METRICS`.
        base: builder parameters fixed for the whole sweep (over the preset's).
        pose: task pose giving the coordinates ``poses`` does not vary [m, rad] (default:
            each variant's reference pose).
        options: metric options (:data:`~plm_pin.sweep.OPTIONS`), e.g. ``{"over": ["rz"]}``.
        store: checkpoint folder: finished chunks are saved there and a re-run with the
            same arguments computes only the missing ones; another sweep's folder is refused.
        scheduler: None (local: in this process when small, else a local cluster of
            ``workers`` processes), a Dask scheduler address ``tcp://host:8786``, or a
            :class:`distributed.Client`.
        workers: processes of the local cluster (default: all CPUs).
        chunk: about how many poses each task evaluates (whole parameter points).
        progress: called with (points done, points in all) as chunks finish.

    Returns:
        The result: ``result.dataset`` is an ``xarray.Dataset`` with units; failed chunks
        are in ``result.failures`` (their points NaN, flagged ``failed``), the rest complete.

    Raises:
        InvalidInput: an unknown preset, parameter, metric, option or task coordinate (the
            message lists the valid ones), an empty grid, a non-finite value, or parameters
            given with a Mechanism.
        StoreMismatch: ``store`` holds another sweep (also when only the mechanism's
            digest differs: a changed description file, builder or Mechanism).
        SchedulerUnreachable: the scheduler does not answer, or has no worker, in time.
        ImportError: the ``sweep`` extra is not installed (``pip install 'plm-pin[sweep]'``).
    """
    spec = make_spec(mechanism, parameters, poses, metrics, base=base, pose=pose, options=options)
    return run_spec(spec, store=store, scheduler=scheduler, workers=workers, chunk=chunk, progress=progress)
