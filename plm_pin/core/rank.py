r"""Numerical rank: how closure and leg Jacobians are judged full or deficient.

Two rules. :func:`numerical_rank` cuts at a fixed relative tolerance (:data:`RANK_RTOL`), for
decisions at arbitrary configurations. :func:`rank_by_gap` decides the rank of a closure
Jacobian where its singular values have their largest gap: an exact description has its
dependent rows at round-off (1e-16 of the largest singular value) and a fixed tolerance would
do, but a CAD export rounded to 6-8 significant digits closes its loops only to 1e-8...1e-5 m,
and its dependent rows then sit at 1e-8...1e-6 of the largest singular value, where a fixed
1e-9 would count them independent.

The gap rule, with :math:`s_0 \ge s_1 \ge \dots` the singular values and
:math:`\bar s = \max(s_0, 1)` (closure Jacobians hold unit axes and lever arms [m]):

- above the ceiling :math:`c\,\bar s` (:data:`RANK_CEILING_RTOL`) a singular value is an
  independent row, whatever its neighbours;
- at or below the floor :math:`f\,\bar s`, :math:`f` the description's closure tolerance (at
  least :data:`~plm_pin.tolerances.ROUND_OFF`), it is zero: a description that closes to
  :math:`f` has its dependent rows there;
- between the two the rank is cut where :math:`s_{r-1} / s_r` is largest (the largest gap in
  log scale), the floor standing for every value below it.

The cut is reported (:class:`RankGap`: the two singular values around it and their ratio);
a ratio below :data:`RANK_GAP_MIN` is no clear-cut decision.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..tolerances import RANK_CEILING_RTOL, RANK_GAP_MIN, RANK_RTOL, ROUND_OFF


def numerical_rank(M: np.ndarray, rtol: float = RANK_RTOL, *, floor: float = 0.0) -> int:
    """Rank of ``M`` by SVD: the singular values above ``rtol * max(s_max, floor)``.

    Args:
        M: the matrix.
        rtol: relative tolerance.
        floor: smallest reference scale, so that a matrix of tiny entries has rank 0
            (1 for closure Jacobians, whose entries are lever arms [m] and unit axes).
    """
    if M.size == 0:
        return 0
    s = np.linalg.svd(M, compute_uv=False)
    return int(np.sum(s > rtol * max(s[0], floor)))


@dataclass(frozen=True)
class RankGap:
    """Where the rank of a matrix was cut among its singular values.

    Attributes:
        rank: the rank.
        above: the smallest singular value counted (NaN for rank 0).
        below: the largest singular value not counted (0 when none is left out).
        fixed: the rank was given (the description's ``mobility``), not decided from the values.
    """

    rank: int
    above: float
    below: float
    fixed: bool = False

    @property
    def ratio(self) -> float:
        """``above / below`` [-]: infinite when nothing is left out or the rest is exactly zero."""
        if math.isnan(self.above):
            return math.inf
        return self.above / self.below if self.below > 0.0 else math.inf

    @property
    def clear(self) -> bool:
        """Whether the cut is clear-cut: a ratio of at least :data:`RANK_GAP_MIN` (or a fixed rank)."""
        return self.fixed or self.ratio >= RANK_GAP_MIN

    def to_dict(self) -> dict[str, float | int | bool]:
        """The gap as plain data (JSON: an infinite ratio is written as None)."""
        ratio = self.ratio
        return {
            "rank": self.rank,
            "above": None if math.isnan(self.above) else self.above,  # type: ignore[dict-item]
            "below": self.below,
            "ratio": None if math.isinf(ratio) else ratio,  # type: ignore[dict-item]
            "fixed": self.fixed,
        }


def gap_of(s: np.ndarray, rank: int, *, fixed: bool = False) -> RankGap:
    """The :class:`RankGap` of a cut after ``rank`` singular values ``s`` (descending)."""
    above = float(s[rank - 1]) if rank > 0 else math.nan
    below = float(s[rank]) if rank < s.size else 0.0
    return RankGap(rank, above, below, fixed)


def rank_by_gap(M: np.ndarray, floor_tol: float) -> RankGap:
    r"""Rank of a closure Jacobian ``M`` at the largest gap of its singular values (see the module).

    Args:
        M: the matrix, shape (m, n).
        floor_tol: the description's closure tolerance [m, rad]: singular values at most
            ``floor_tol * max(s_max, 1)`` are zero.

    Returns:
        The rank and the gap it was cut at.
    """
    if M.size == 0:
        return RankGap(0, math.nan, 0.0)
    return rank_of_singular_values(np.linalg.svd(M, compute_uv=False), floor_tol)


def rank_of_singular_values(s: np.ndarray, floor_tol: float) -> RankGap:
    """:func:`rank_by_gap` from the singular values ``s`` (descending, not empty) of a matrix.

    For a caller that also needs the singular vectors, so that the matrix is decomposed once.
    """
    scale = max(float(s[0]), 1.0)
    floor = max(floor_tol, ROUND_OFF) * scale
    ceiling = max(RANK_CEILING_RTOL * scale, floor)
    sure = int(np.sum(s > ceiling))  # independent whatever the gap
    possible = int(np.sum(s > floor))  # the most that can count
    best, best_ratio = sure, -math.inf
    for r in range(sure, possible + 1):
        upper = float(s[r - 1]) if r > 0 else math.inf
        lower = float(s[r]) if r < possible else floor
        ratio = upper / lower
        if ratio > best_ratio:
            best, best_ratio = r, ratio
    return gap_of(s, best)
