"""Numerical rank: how closure and leg Jacobians are judged full or deficient."""

import numpy as np

from ..tolerances import RANK_RTOL


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
