"""One result protocol: frozen dataclasses whose fields carry their units, and a ``to_dict`` made from them.

A result is a ``@dataclass(frozen=True)`` deriving from :class:`Result`. Each field that has a
unit declares it once, in its metadata (``lower: float = field(metadata=unit("rad"))``); report tables and the
sweep's xarray attributes read it from there (:func:`units`). :meth:`Result.to_dict` writes every
field as plain JSON data (arrays as nested lists, nested results as their dictionaries), then the
properties named in ``_DERIVED``; fields named in ``_SKIPPED`` (a back-reference to the mechanism,
say) are left out, and non-finite floats of the names in ``_NONFINITE_AS_TEXT`` are written as the
strings ``'inf'``/``'nan'`` (JSON has no such numbers).
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

__all__ = ["Result", "unit", "units"]


def unit(symbol: str) -> dict[str, str]:
    """The metadata of a dataclass field with a unit: ``field(metadata=unit("N"))``.

    Args:
        symbol: the unit in SI notation without brackets, e.g. ``"N"``, ``"m/rad"`` (``"-"``
            when dimensionless).

    Returns:
        ``{"unit": symbol}``.
    """
    return {"unit": symbol}


def units(result: Any) -> dict[str, str]:
    """The units of the fields of a result class or instance that declare one, keyed by field name.

    Args:
        result: a dataclass (class or instance) whose fields were declared with :func:`unit`.

    Returns:
        ``{field name: unit}`` for the fields that have a unit.

    Raises:
        TypeError: ``result`` is not a dataclass.
    """
    return {f.name: f.metadata["unit"] for f in dataclasses.fields(result) if "unit" in f.metadata}


def plain(value: object, nonfinite_as_text: bool = False) -> object:
    """``value`` as JSON data: arrays as lists, results as their ``to_dict()``, paths as text.

    Numpy scalars become Python numbers; mappings keep their keys (as strings), sequences and
    arrays become lists, objects with a ``to_dict()`` method are converted by it and other
    dataclasses field by field.

    Args:
        value: the value to convert.
        nonfinite_as_text: write non-finite floats as the strings ``'inf'``, ``'-inf'``, ``'nan'``
            (in what ``to_dict()`` returns too), so that strict JSON can hold them.

    Returns:
        Plain Python data (dict, list, str, int, float, bool, None).

    Raises:
        TypeError: for a value that has no JSON form (as :func:`json.dumps` would).
    """
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, np.generic):
        return plain(value.item(), nonfinite_as_text)
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        return str(value) if nonfinite_as_text and not math.isfinite(value) else float(value)
    if hasattr(value, "to_dict"):
        data = value.to_dict()
        return plain(data, nonfinite_as_text) if nonfinite_as_text else data
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, np.ndarray):
        return plain(value.tolist(), nonfinite_as_text) if nonfinite_as_text else value.tolist()
    if isinstance(value, Mapping):
        return {str(k): plain(v, nonfinite_as_text) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v, nonfinite_as_text) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {f.name: getattr(value, f.name) for f in dataclasses.fields(value)}
        return plain(fields, nonfinite_as_text)
    raise TypeError(f"{value!r} ({type(value).__name__}) has no JSON form")


class Result:
    """Base of the result dataclasses: :meth:`to_dict` from the fields (see the module docstring)."""

    __dataclass_fields__: ClassVar[dict[str, dataclasses.Field[Any]]]
    _DERIVED: ClassVar[tuple[str, ...]] = ()
    """Properties written after the fields."""
    _SKIPPED: ClassVar[tuple[str, ...]] = ()
    """Fields left out of the dictionary."""
    _NONFINITE_AS_TEXT: ClassVar[tuple[str, ...]] = ()
    """Fields and properties whose non-finite floats are written as text."""

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON: the fields, then the derived properties."""
        names = [f.name for f in dataclasses.fields(self) if f.name not in self._SKIPPED]
        return {n: plain(getattr(self, n), n in self._NONFINITE_AS_TEXT) for n in (*names, *self._DERIVED)}
