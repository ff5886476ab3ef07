"""The closure rank at the largest gap of the singular values (plm_pin/core/rank.py) and its uses."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import plm_pin
from plm_pin.core.rank import numerical_rank, rank_by_gap
from plm_pin.exceptions import InvalidInput
from plm_pin.tolerances import RANK_RTOL
from plm_pin.warnings import AmbiguousRankWarning


def _with_singular_values(s: list[float], shape: tuple[int, int], seed: int = 0) -> np.ndarray:
    """A matrix of the given shape whose singular values are ``s`` (random orthogonal factors)."""
    rng = np.random.default_rng(seed)
    U = np.linalg.qr(rng.normal(size=(shape[0], shape[0])))[0]
    V = np.linalg.qr(rng.normal(size=(shape[1], shape[1])))[0]
    S = np.zeros(shape)
    S[np.arange(len(s)), np.arange(len(s))] = s
    return U @ S @ V.T


@pytest.mark.parametrize(
    ("s", "floor", "rank"),
    [
        ([2.0, 0.3, 1e-16, 1e-17], 1e-12, 2),  # exact: round-off zeros
        ([2.0, 0.3, 0.1, 3e-7, 3e-8], 1e-12, 3),  # rounded data: the gap 0.1 | 3e-7, not 3e-8 | floor
        ([2.0, 0.3, 0.1, 3e-7, 3e-8], 1e-5, 3),  # the same, the dependent rows below the stated floor
        ([2.0, 0.3, 1e-10, 1e-16], 1e-12, 2),  # a value near the floor is no row
        ([2.0, 0.3, 1e-3, 1e-16], 1e-12, 3),  # above the ceiling: a row, however small its neighbours
        ([1e-3, 1e-17], 1e-12, 1),  # a matrix of small entries is judged against 1, not s_max
        ([5e-13, 1e-17], 1e-12, 0),
    ],
)
def test_rank_by_gap_on_known_singular_values(s, floor, rank):
    """The rank cut at the largest ratio between the ceiling and the floor, on constructed spectra."""
    gap = rank_by_gap(_with_singular_values(s, (6, 7)), floor)
    assert gap.rank == rank
    values = [*s, 0.0]
    assert gap.above == pytest.approx(values[rank - 1], rel=1e-6) if rank else math.isnan(gap.above)
    assert gap.below == pytest.approx(values[rank], rel=1e-6, abs=1e-15)


def test_a_fixed_relative_tolerance_counts_rounded_dependent_rows():
    """The case the gap rule exists for: 1e-9 of s_max counts rows at 3e-7 independent."""
    M = _with_singular_values([2.0, 0.3, 0.1, 3e-7, 3e-8], (6, 7))
    assert numerical_rank(M, RANK_RTOL, floor=1.0) == 5
    assert rank_by_gap(M, 1e-12).rank == 3


def test_rank_gap_reports_its_ratio_and_clearness():
    """The ratio is the two singular values' quotient; below RANK_GAP_MIN the cut is not clear."""
    clear = rank_by_gap(_with_singular_values([1.0, 0.5, 1e-8], (3, 4)), 1e-12)
    assert clear.ratio == pytest.approx(0.5 / 1e-8, rel=1e-6) and clear.clear
    murky = rank_by_gap(_with_singular_values([1.0, 1e-2, 1e-3, 1e-5], (4, 4)), 1e-7)
    assert not murky.clear and murky.ratio < 1e3
    assert clear.to_dict()["rank"] == 2 and rank_by_gap(np.zeros((2, 3)), 1e-12).to_dict()["ratio"] is None


def test_exact_presets_keep_their_mobility():
    """Every shipped preset's mobility is its registry DOF (the gap rule changes no exact answer)."""
    from plm_pin.models.registry import PRESETS

    for name, preset in PRESETS.items():
        mech = plm_pin.load(name)
        assert mech.mobility == preset.dof, name
        assert mech.rank_gap.clear and mech.closure_tol == 1e-12, name


def test_a_fixed_mobility_sets_the_rank():
    """``load(..., mobility=)`` fixes the closure rank; a value outside [0, nv] is refused."""
    mech = plm_pin.load("fourbar", mobility=1)
    assert mech.mobility == 1 and mech.rank_gap.fixed and mech.summary()["rank_gap"]["fixed"]
    with pytest.raises(InvalidInput, match=r"mobility must be an integer in \[0, 3\]"):
        plm_pin.load("fourbar", mobility=7)


def test_an_unclear_gap_warns():
    """A closure tolerance above an independent row (the four-bar's 0.18): the doubtful mobility is warned."""
    mech = plm_pin.load("fourbar", closure_tol=0.3)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", AmbiguousRankWarning)
        assert mech.mobility == 2  # the row at 0.18 taken for a dependent one
    (warning,) = caught
    assert "no clear-cut gap" in str(warning.message) and "mobility 2 is in doubt" in str(warning.message)
    with warnings.catch_warnings():
        warnings.simplefilter("error", AmbiguousRankWarning)
        assert plm_pin.load("fourbar").mobility == 1  # exact: no warning
