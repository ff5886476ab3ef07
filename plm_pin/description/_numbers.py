"""Numbers read from description files (sidecars, compliance sections), checked with the culprit named."""

from __future__ import annotations

import math
from typing import Any

from .._text import short
from ..exceptions import DescriptionError


def number(value: Any, where: str, path: str | None) -> float:
    """``value`` as a finite float; YAML 1.1's ``1e3`` (read as a string) is accepted.

    Raises:
        DescriptionError: naming ``where`` and the value (cut to a short quote).
    """
    if isinstance(value, str):  # YAML 1.1 reads 1e3 (no dot) as a string
        try:
            value = float(value)
        except ValueError:
            raise DescriptionError(f"{where} must be a number, got {short(value)}", path) from None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise DescriptionError(f"{where} must be a number, got {short(value)}", path)
    x = float(value)
    if not math.isfinite(x):
        raise DescriptionError(f"{where} must be finite, got {short(value)}", path)
    return x


def positive_number(value: Any, where: str, path: str | None) -> float:
    """``value`` as a finite float > 0 (see :func:`number`).

    Raises:
        DescriptionError: naming ``where`` and the value.
    """
    x = number(value, where, path)
    if x <= 0.0:
        raise DescriptionError(f"{where} must be a positive finite number, got {short(value)}", path)
    return x
