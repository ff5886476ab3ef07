"""Square solves by LU (LAPACK ``getrf`` / ``getrs`` / ``gesv``), the sign of a determinant, an SVD.

``numpy.linalg.solve`` costs about 9 us on a 9 x 9 system (its generalized-ufunc machinery), the
LAPACK driver 2.5 us. Solves here raise ``numpy.linalg.LinAlgError`` on an exactly singular matrix,
as numpy does, so callers keep their fallbacks. A rank or a condition number needs an SVD
(:mod:`plm_pin.core.rank`), not these. scipy is imported on first use.
"""

from __future__ import annotations

import numpy as np

from ._lazy import lazy_module

lapack = lazy_module("scipy.linalg.lapack")  # dgesv, dgetrf, dgetrs, dgesdd


def _singular(info: int, what: str) -> None:
    if info > 0:
        raise np.linalg.LinAlgError(f"Singular matrix: {what} has a zero pivot at row {info - 1}")
    if info < 0:  # a malformed argument: a bug here, not bad input
        raise ValueError(f"LAPACK {what}: illegal value in argument {-info}")


def lu_solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``x`` with ``A x = b`` for a square ``A`` (LAPACK ``gesv``: LU with partial pivoting).

    Args:
        A: a square matrix (n, n).
        b: the right-hand side, (n,) or (n, k).

    Returns:
        The solution, shaped as ``b``.

    Raises:
        numpy.linalg.LinAlgError: ``A`` is exactly singular (a zero pivot).
    """
    if A.shape[0] == 0:
        return np.zeros(np.shape(b))
    _, _, x, info = lapack.dgesv(A, b)
    _singular(info, "gesv")
    return x


class LU:
    """The LU factorisation ``P A = L U`` of a square matrix, to solve several right-hand sides."""

    __slots__ = ("lu", "piv")

    def __init__(self, A: np.ndarray) -> None:
        """Factor ``A`` (n, n) (LAPACK ``getrf``); a singular ``A`` factors, :meth:`solve` raises."""
        if A.shape[0] == 0:
            self.lu, self.piv = np.zeros((0, 0)), np.zeros(0, dtype=np.int32)
        else:
            self.lu, self.piv, info = lapack.dgetrf(A)
            _singular(min(info, 0), "getrf")

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``x`` with ``A x = b``, shaped as ``b`` (LAPACK ``getrs``).

        Raises:
            numpy.linalg.LinAlgError: ``A`` is exactly singular (a zero pivot).
        """
        if self.lu.shape[0] == 0:
            return np.zeros(np.shape(b))
        diagonal = np.diagonal(self.lu)
        if not np.all(diagonal):
            _singular(int(np.flatnonzero(diagonal == 0.0)[0]) + 1, "getrf")
        x, info = lapack.dgetrs(self.lu, self.piv, b)
        _singular(info, "getrs")
        return x

    def det_sign(self) -> float:
        """The sign of ``det A``: +1.0, -1.0, or 0.0 when a pivot is exactly zero."""
        swaps = np.count_nonzero(self.piv != np.arange(self.piv.size))
        return float(np.prod(np.sign(np.diagonal(self.lu)))) * (-1.0 if swaps % 2 else 1.0)


def det_sign(A: np.ndarray) -> float:
    """The sign of ``det A`` for a square ``A`` from its LU factors: +1.0, -1.0, or 0.0 when singular."""
    return LU(A).det_sign()


def thin_svd(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``U, s, Vt`` of ``numpy.linalg.svd(A, full_matrices=False)`` by one LAPACK ``gesdd`` call.

    For the small matrices of a per-sample loop, where numpy's wrapper costs more than the
    factorisation; numpy's (its own driver) where ``gesdd`` does not converge.
    """
    return _svd(A, full_matrices=False)


def full_svd(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``U, s, Vt`` of ``numpy.linalg.svd(A)`` (square ``U`` and ``Vt``), as :func:`thin_svd`."""
    return _svd(A, full_matrices=True)


def _svd(A: np.ndarray, full_matrices: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if A.size:
        U, s, Vt, info = lapack.dgesdd(A, full_matrices=int(full_matrices))
        if info == 0:
            return U, s, Vt
    U, s, Vt = np.linalg.svd(A, full_matrices=full_matrices)
    return U, s, Vt
