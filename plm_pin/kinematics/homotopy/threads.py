"""Homotopy paths tracked on several threads.

Paths are independent and the compiled trackers release the GIL (``nogil``), so the rows of
a batch of start points are shared among threads: interleaved (row ``k`` on thread
``k mod T``), because path costs vary several-fold. The calling thread tracks its own share
while a pool's threads track the others; the pool is made on first use in each process (a
forked child, such as a sweep's or Dask's worker, makes its own: a parent's pool threads do
not exist there). The number of threads is numba's (``NUMBA_NUM_THREADS``, by default the
cores), at most the cores this process may run on and half the paths; batches of fewer than
:data:`THREADS_MIN_PATHS` paths stay on the calling thread.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np

THREADS_MIN_PATHS = 10
"""Fewest paths in a batch worth a second thread (handing a share to a pool thread costs about
0.05 ms, a path's tracking 0.05 to 0.3 ms). Measured on the 2-core machine: mechanisms of 4 and 6
paths are faster on one thread, of 8 paths equal, of 28 and 40 paths faster on two."""

_POOL: tuple[int, int, ThreadPoolExecutor] | None = None  # (process id, threads, pool)
_POOL_LOCK = threading.Lock()


def _pool(threads: int) -> ThreadPoolExecutor:
    """The process's pool of at least ``threads`` threads (made again in a forked child)."""
    global _POOL
    with _POOL_LOCK:
        if _POOL is None or _POOL[0] != os.getpid() or _POOL[1] < threads:
            if _POOL is not None and _POOL[0] == os.getpid():  # too small: its threads end when idle
                _POOL[2].shutdown(wait=False)
            _POOL = (os.getpid(), threads, ThreadPoolExecutor(threads, thread_name_prefix="plm-pin-paths"))
        return _POOL[2]


def path_threads(n_paths: int) -> int:
    """Threads to track ``n_paths`` paths on: numba's thread count, at most the usable cores."""
    if n_paths < THREADS_MIN_PATHS:
        return 1
    from numba import config

    numba_threads = int(config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]
    return max(1, min(numba_threads, len(os.sched_getaffinity(0)), n_paths // 2))


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

    pool = _pool(k - 1)
    others = [pool.submit(run, i) for i in range(1, k)]
    run(0)
    for future in others:
        future.result()
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
