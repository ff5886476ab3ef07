"""Private input checks shared by the public API."""

from __future__ import annotations

import numpy as np

from .exceptions import InvalidInput


def as_vector(x: object, size: int, name: str) -> np.ndarray:
    """Return ``x`` as a float array of shape (size,); refuse non-numbers, wrong shapes, non-finite values.

    Raises:
        InvalidInput: naming ``name`` and what is wrong.
    """
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidInput(f"{name} must be {size} numbers: {exc}") from None
    if arr.shape != (size,):
        raise InvalidInput(f"{name} must have shape ({size},), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidInput(
            f"{name} has non-finite entries at indices {np.flatnonzero(~np.isfinite(arr)).tolist()}"
        )
    return arr
