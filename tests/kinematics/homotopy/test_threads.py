"""Paths shared among threads (plm_pin/kinematics/homotopy/threads.py).

Oracles: the rows computed directly (order restored), and the same paths tracked on the
calling thread alone (paths are independent: the split must not change a bit).
"""

from __future__ import annotations

import multiprocessing

import numpy as np
import pytest
from numba import config

from plm_pin.kinematics.homotopy import prepared
from plm_pin.kinematics.homotopy.threads import THREADS_MIN_PATHS, over_threads, path_threads
from plm_pin.kinematics.homotopy.tracking import HANDOFF_GROWTH, track_all
from tests.conftest import preset


@pytest.fixture
def two_threads(monkeypatch):
    """Two threads, whatever this machine's numba default."""
    monkeypatch.setattr(config, "NUMBA_NUM_THREADS", 2)
    monkeypatch.setattr("os.sched_getaffinity", lambda pid: {0, 1})


def test_rows_come_back_in_order(two_threads):
    """Each output row is the one computed from its own input row."""
    X = np.arange(3 * 40, dtype=float).reshape(40, 3)
    doubled, sums = over_threads(lambda A, k: (k * A, A.sum(axis=1)), (X,), 2.0)
    assert path_threads(len(X)) == 2
    assert np.array_equal(doubled, 2.0 * X) and np.array_equal(sums, X.sum(axis=1))


def test_small_batches_stay_on_the_calling_thread(two_threads):
    assert path_threads(THREADS_MIN_PATHS - 1) == 1


def test_an_error_on_a_thread_is_raised_to_the_caller(two_threads):
    def track(A):
        if A[0, 0] == 1.0:  # the second thread's first row
            raise ValueError("lost on thread 2")
        return (A,)

    with pytest.raises(ValueError, match="lost on thread 2"):
        over_threads(track, (np.arange(40.0).reshape(40, 1),))


def test_threaded_paths_equal_one_thread(two_threads):
    """The 8-PSS's 40 generic paths tracked on two threads end bit for bit where one thread ends them."""
    mech = preset("zhao2011_8pss")
    form, gen = prepared(mech)
    p1 = (mech.actuator_positions(mech.q_ref) + 1e-3)[form.parameters].astype(np.complex128)
    zero = np.zeros(form.n, dtype=np.complex128)
    args = (gen.p, zero, p1, zero, form.program, HANDOFF_GROWTH)
    threaded = over_threads(track_all, (gen.x,), *args)
    alone = track_all(gen.x, *args)
    for a, b in zip(threaded, alone, strict=True):
        assert np.array_equal(a, b)


def _shares(_: int) -> list[float]:
    """A child's over_threads result (module level, so a process pool can run it)."""
    X = np.arange(40.0).reshape(40, 1)
    return over_threads(lambda A: (2.0 * A,), (X,))[0].ravel().tolist()


def test_a_forked_child_tracks_after_its_parent_did(two_threads):
    """The parent's pool threads do not exist in a forked child: the child makes its own pool (no hang)."""
    over_threads(lambda A: (A,), (np.zeros((40, 1)),))  # the parent's pool exists now
    with multiprocessing.get_context("fork").Pool(1) as pool:
        got = pool.apply_async(_shares, (0,)).get(timeout=60)
    assert got == (2.0 * np.arange(40.0)).tolist()
