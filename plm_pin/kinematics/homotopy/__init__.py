"""Complete forward kinematics: polynomial closures, generic solve, homotopy, interval certificates.

Importing this package does not import numba; the compiled modules (:mod:`.evaluation`,
:mod:`.tracking`, :mod:`.certify`) load it when first used.
"""

from .form import PolynomialForm
from .generic import GenericSolution, cache_folder, generic_solution
from .polynomial import NotPolynomial, polynomial_form
from .solve import HomotopySolve, RealRoot, prepared, solve_homotopy

__all__ = [
    "GenericSolution",
    "HomotopySolve",
    "NotPolynomial",
    "PolynomialForm",
    "RealRoot",
    "cache_folder",
    "generic_solution",
    "polynomial_form",
    "prepared",
    "solve_homotopy",
]
