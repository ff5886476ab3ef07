"""The compiled LU on a symbolic pattern (:mod:`plm_pin.kernels.linear`) against LAPACK's dense solve.

Random matrices on arrow, banded and random patterns, with rows of zeros, with values that make
any candidate row the pivot (so every fill the bound allows happens somewhere), and singular ones.
"""

from __future__ import annotations

import numpy as np
import pytest

from plm_pin.kernels.arrays import Elimination, elimination
from plm_pin.kernels.linear import dense_elimination, lu_factor, lu_solve

ROUND_OFF = 1e-13
"""Backward error accepted, relative to |M| |X| (a few hundred round-offs of a 30 x 30 solve)."""


def _arrow(legs: int, size: int, hub: int) -> np.ndarray:
    """Legs' square blocks around a hub: every leg row touches the hub, task rows the hub only."""
    n = legs * size + hub
    P = np.zeros((n, n), dtype=bool)
    for g in range(legs):
        rows = slice(g * size, (g + 1) * size)
        P[rows, hub + g * size : hub + (g + 1) * size] = True
        P[rows, :hub] = True
    P[legs * size :, :hub] = True
    return P


def _random_pattern(rng: np.random.Generator, n: int, density: float) -> np.ndarray:
    """A random pattern with a nonzero diagonal under a random row permutation (structurally regular)."""
    P = rng.random((n, n)) < density
    P[np.arange(n), np.arange(n)] = True
    return P[rng.permutation(n)]


def _values(rng: np.random.Generator, P: np.ndarray) -> np.ndarray:
    """Values on ``P``, their magnitudes spread over 6 decades: any candidate may win a pivot search."""
    return np.where(P, rng.normal(size=P.shape) * 10.0 ** rng.uniform(-3, 3, size=P.shape), 0.0)


def _solve(M: np.ndarray, e: Elimination, B: np.ndarray) -> np.ndarray | None:
    rows, n = M.shape
    F, pivots, step, X = (
        np.empty((rows, n)),
        np.empty(n, np.int64),
        np.empty(rows, np.int64),
        np.empty((n, B.shape[1])),
    )
    if not lu_factor(M, e, F, pivots, step):
        return None
    lu_solve(F, e, pivots, step, B.copy(), X)
    return X


def _check(M: np.ndarray, e: Elimination, rng: np.random.Generator) -> None:
    B = rng.normal(size=(M.shape[0], 3))
    X = _solve(M, e, B)
    assert X is not None
    live = M.any(axis=1)
    assert np.abs(M @ X - B)[live].max() <= ROUND_OFF * (np.abs(M) @ np.abs(X)).max()
    forward = (
        ROUND_OFF * np.linalg.cond(M[live]) * np.abs(X).max()
    )  # the forward error that backward one allows
    np.testing.assert_allclose(X, np.linalg.solve(M[live], B[live]), rtol=0.0, atol=forward)


PATTERNS = {
    "8-PSS arrow": _arrow(8, 3, 6),
    "planar arrow": _arrow(3, 2, 3),
    "banded": np.abs(np.subtract.outer(np.arange(12), np.arange(12))) <= 2,
    "dense": np.ones((7, 7), dtype=bool),
}


@pytest.mark.parametrize("name", list(PATTERNS))
def test_lu_on_a_pattern_matches_lapack(name, rng):
    P = PATTERNS[name]
    e = elimination(P)
    for _ in range(50):
        _check(_values(rng, P), e, rng)


def test_lu_on_random_patterns_matches_lapack(rng):
    for _ in range(200):
        n = int(rng.integers(1, 16))
        P = _random_pattern(rng, n, rng.uniform(0.05, 0.5))
        e = elimination(P)
        for _ in range(5):
            _check(_values(rng, P), e, rng)


def test_rows_of_zeros_are_left_out(rng):
    """A planar loop's out-of-plane rows: exactly zero, never pivots, their right-hand side not read."""
    P = _arrow(3, 2, 3)
    for _ in range(20):
        M = _values(rng, P)
        zero = rng.integers(0, M.shape[0] + 1, size=3)
        M = np.insert(M, zero, 0.0, axis=0)
        _check(M, elimination(np.insert(P, zero, True, axis=0)), rng)


def test_the_order_puts_legs_before_the_hub():
    e = elimination(PATTERNS["8-PSS arrow"])
    assert sorted(e.order[-6:].tolist()) == list(range(6))
    assert np.diff(e.row_ptr)[:24].max() == 3  # a leg's column: its own 3 rows are the candidates


def test_dense_elimination_matches_the_pattern_one(rng):
    for n in (1, 2, 5, 9):
        M = rng.normal(size=(n, n))
        B = rng.normal(size=(n, 2))
        np.testing.assert_allclose(_solve(M, dense_elimination(n, n), B), np.linalg.solve(M, B), rtol=1e-10)
        np.testing.assert_allclose(
            _solve(M, dense_elimination(n, n), B),
            _solve(M, elimination(np.ones((n, n), bool)), B),
            rtol=1e-12,
        )


def test_singular_matrices_are_reported(rng):
    P = PATTERNS["8-PSS arrow"]
    e = elimination(P)
    M = _values(rng, P)
    M[:, 7] = 0.0  # a leg column of zeros
    assert _solve(M, e, rng.normal(size=(30, 1))) is None
    M = _values(rng, P)
    M[4] = 0.0  # one row fewer than columns
    assert _solve(M, e, rng.normal(size=(30, 1))) is None
