"""Square solves by LU and determinant signs, against numpy's solve and det."""

import numpy as np
import pytest

from plm_pin import _linalg


@pytest.mark.parametrize("n", [1, 2, 5, 9, 20])
def test_solve_and_factors_match_numpy(n):
    rng = np.random.default_rng(n)
    for _ in range(20):
        A = rng.standard_normal((n, n))
        b, B = rng.standard_normal(n), rng.standard_normal((n, 3))
        np.testing.assert_allclose(_linalg.lu_solve(A, b), np.linalg.solve(A, b), rtol=1e-10, atol=1e-12)
        lu = _linalg.LU(A)
        np.testing.assert_allclose(lu.solve(B), np.linalg.solve(A, B), rtol=1e-10, atol=1e-12)
        assert _linalg.det_sign(A) == np.sign(np.linalg.det(A))


def test_a_permuted_identity_has_the_sign_of_its_permutation():
    """A transposition flips the sign, a 3-cycle keeps it (independent of any factorisation)."""
    assert _linalg.det_sign(np.eye(4)[[1, 0, 2, 3]]) == -1.0
    assert _linalg.det_sign(np.eye(4)[[1, 2, 0, 3]]) == 1.0
    assert _linalg.det_sign(-np.eye(3)) == -1.0


def test_singular_matrices_raise_as_numpy_does_and_have_sign_zero():
    A = np.array([[1.0, 2.0], [2.0, 4.0]])
    with pytest.raises(np.linalg.LinAlgError):
        _linalg.lu_solve(A, np.ones(2))
    with pytest.raises(np.linalg.LinAlgError):
        _linalg.LU(A).solve(np.ones(2))
    assert _linalg.det_sign(A) == 0.0
    assert _linalg.det_sign(np.zeros((3, 3))) == 0.0


def test_empty_systems():
    assert _linalg.lu_solve(np.zeros((0, 0)), np.zeros(0)).shape == (0,)
    assert _linalg.LU(np.zeros((0, 0))).solve(np.zeros((0, 2))).shape == (0, 2)
    assert _linalg.det_sign(np.zeros((0, 0))) == 1.0
