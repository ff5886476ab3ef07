"""Homotopy paths tracked on several threads.

Paths are independent and the compiled trackers release the GIL (``nogil``), so the rows of
a batch of start points are shared among threads: interleaved (row ``k`` on thread
``k mod T``), because path costs vary several-fold. Plain threads, started per call (about
0.1 ms, against milliseconds of tracking), so nothing outlives the call: a forked process
(a sweep's or Dask's worker) starts clean. The number of threads is numba's
(``NUMBA_NUM_THREADS``, by default the cores), at most the cores this process may run on;
batches of fewer than :data:`THREADS_MIN_PATHS` paths stay on the calling thread.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable

import numpy as np

THREADS_MIN_PATHS = 4
"""Fewest paths in a batch worth a second thread, two per thread (a thread's start and join cost
about 0.05 ms, a path's tracking 0.1 to 0.5 ms)."""


def path_threads(n_paths: int) -> int:
    """Threads to track ``n_paths`` paths on: numba's thread count, at most the usable cores."""
    if n_paths < THREADS_MIN_PATHS:
        return 1
    from numba import config

    return max(1, min(int(config.NUMBA_NUM_THREADS), len(os.sched_getaffinity(0)), n_paths // 2))


def over_threads(
    track: Callable[..., tuple[np.ndarray, ...]], rows: tuple[np.ndarray, ...], *args: object
) -> tuple[np.ndarray, ...]:
    """``track(*rows, *args)`` with the rows of the arrays ``rows`` (one per path, each) shared among threads.

    :func:`path_threads` threads; ``track`` returns arrays whose first axis runs over the paths,
    put back in path order. An exception on any thread is raised here.
    """
    n = rows[0].shape[0]
    k = path_threads(n)
    if k == 1:
        return track(*rows, *args)
    share = [np.arange(i, n, k) for i in range(k)]
    parts: list[tuple[np.ndarray, ...] | BaseException | None] = [None] * k

    def run(i: int) -> None:
        try:
            parts[i] = track(*(np.ascontiguousarray(r[share[i]]) for r in rows), *args)
        except BaseException as error:  # raised again on the calling thread
            parts[i] = error

    others = [threading.Thread(target=run, args=(i,), daemon=True) for i in range(1, k)]
    for t in others:
        t.start()
    run(0)
    for t in others:
        t.join()
    for part in parts:
        if isinstance(part, BaseException):
            raise part
    first = parts[0]
    assert isinstance(first, tuple)
    out = tuple(np.empty((n, *a.shape[1:]), dtype=a.dtype) for a in first)
    for i, part in enumerate(parts):
        assert isinstance(part, tuple)
        for o, a in zip(out, part, strict=True):
            o[share[i]] = a
    return out
