r"""Compiled square solves that skip structural zeros: an LU with partial pivoting on a symbolic pattern.

The Jacobians the kernels solve with are sparse in a fixed pattern: a leg's closure rows touch
only its own joints and the joints its frames hang from. :func:`.arrays.elimination` reads
that pattern once per kernel. It orders the columns fewest-rows-first (a leg's own joints before the
platform's), then runs the elimination symbolically: at step :math:`j` the rows that may touch
column :math:`j` are the candidates for its pivot, and each of them may afterwards touch every
later column that any of them touches (George and Ng's bound on partial pivoting's fill,
whichever candidate the values make the pivot). :func:`lu_factor` then searches the pivot among
those rows only and updates them on those columns only: on an arrow matrix (the n-PSS, legs'
3 x 3 blocks around a 6-column platform) the factor costs the legs' blocks and the platform's
instead of a dense :math:`n^3/3`, with the loops over the zeros gone as well.

The arithmetic is that of the dense partial-pivoting LU with the columns permuted (an entry
outside the pattern is an exact zero, which the dense LU would subtract as zero): the same
backward stability, whatever the pattern and order, which set the cost and never the accuracy.
A pattern that claims a zero where the matrix has none gives a wrong answer, so patterns come
from the model's structure (which joint moves which frame), never from values.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .arrays import Elimination


@njit(cache=True)
def dense_elimination(rows: int, n: int) -> Elimination:
    """The :class:`Elimination` of a full (rows, n) pattern: columns in order, every row a candidate."""
    order = np.arange(n)
    row_ptr = np.arange(n + 1) * rows
    candidates = np.empty(n * rows, dtype=np.int64)
    col_ptr = np.empty(n + 1, dtype=np.int64)
    cols = np.empty(n * (n - 1) // 2, dtype=np.int64)
    col_ptr[0] = 0
    for j in range(n):
        for i in range(rows):
            candidates[j * rows + i] = i
        col_ptr[j + 1] = col_ptr[j] + n - 1 - j
        for t in range(j + 1, n):
            cols[col_ptr[j] + t - j - 1] = t
    return Elimination(order, row_ptr, candidates, col_ptr, cols)


@njit(cache=True)
def lu_factor(M: np.ndarray, e: Elimination, F: np.ndarray, pivots: np.ndarray, step: np.ndarray) -> bool:
    """Factor ``M`` (rows, n; n nonzero rows) on the pattern ``e`` into ``F``; False if it is singular.

    ``F`` (rows, n) receives a copy of ``M`` turned into the factor in place: pivot row
    ``pivots[j]`` of step ``j`` holds :math:`U`'s row (at the columns ``order[j:]``), every
    other row the multipliers of :math:`L` at the columns of the steps that eliminated it.
    ``step`` (rows,) receives the step at which each row was a pivot (n for a row that was not:
    a row of zeros). False when a step finds no nonzero pivot among its candidates.
    """
    n_rows, n = M.shape
    for i in range(n_rows):
        step[i] = n
        for c in range(n):
            F[i, c] = M[i, c]
    for j in range(n):
        cj = e.order[j]
        p, best = -1, 0.0
        for t in range(e.row_ptr[j], e.row_ptr[j + 1]):
            i = e.rows[t]
            if step[i] == n and abs(F[i, cj]) > best:
                p, best = i, abs(F[i, cj])
        if p < 0:
            return False
        step[p] = j
        pivots[j] = p
        pivot = F[p, cj]
        for t in range(e.row_ptr[j], e.row_ptr[j + 1]):
            i = e.rows[t]
            if step[i] != n or F[i, cj] == 0.0:  # a pivot row, or nothing to eliminate
                continue
            f = F[i, cj] / pivot
            F[i, cj] = f
            for u in range(e.col_ptr[j], e.col_ptr[j + 1]):
                c = e.cols[u]
                F[i, c] -= f * F[p, c]
    return True


@njit(cache=True)
def lu_solve(
    F: np.ndarray, e: Elimination, pivots: np.ndarray, step: np.ndarray, B: np.ndarray, X: np.ndarray
) -> None:
    """Solve ``M X = B`` with the factor of :func:`lu_factor`: ``X`` (n, r) set, ``B`` (rows, r) overwritten.

    Rows of ``B`` at the rows that were no pivot (zero rows of ``M``) are not read.
    """
    n, r = X.shape
    for j in range(n):  # L: each later candidate loses its multiple of the pivot row
        cj, p = e.order[j], pivots[j]
        for t in range(e.row_ptr[j], e.row_ptr[j + 1]):
            i = e.rows[t]
            f = F[i, cj]
            if step[i] > j and f != 0.0:
                for c in range(r):
                    B[i, c] -= f * B[p, c]
    for j in range(n - 1, -1, -1):  # U, from the last step back
        cj, p = e.order[j], pivots[j]
        for c in range(r):
            s = B[p, c]
            for u in range(e.col_ptr[j], e.col_ptr[j + 1]):
                s -= F[p, e.cols[u]] * X[e.cols[u], c]
            X[cj, c] = s / F[p, cj]


@njit(cache=True)
def solve(
    M: np.ndarray,
    e: Elimination,
    F: np.ndarray,
    pivots: np.ndarray,
    step: np.ndarray,
    B: np.ndarray,
    X: np.ndarray,
) -> bool:
    """Solve ``M X = B`` (``M`` with as many nonzero rows as columns) on the pattern ``e``; False if singular.

    :func:`lu_factor` then :func:`lu_solve`: ``B`` is overwritten; ``F`` (>= rows, n),
    ``pivots`` (n,) and ``step`` (>= rows,) are scratch.
    """
    if not lu_factor(M, e, F, pivots, step):
        return False
    lu_solve(F, e, pivots, step, B, X)
    return True
