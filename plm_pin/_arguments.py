"""Private input checks shared by the public API."""

from __future__ import annotations

import math
import numbers
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from ._text import short
from .exceptions import InvalidInput
from .tolerances import MAX_EFFORT

_SHORT = 64
"""Longest vector whose finiteness :func:`as_vector` checks by a Python sum (cheaper than numpy up to it)."""


_FLOAT = np.dtype(float)
"""The float64 dtype (NumPy's native one, a singleton)."""


def nonfinite_indices(arr: np.ndarray) -> list:
    """Indices of the non-finite entries of ``arr``: ints for a vector, tuples for higher ranks."""
    bad = np.argwhere(~np.isfinite(arr))
    return [int(k[0]) if arr.ndim == 1 else tuple(int(i) for i in k) for k in bad]


def as_vector(x: object, size: int, name: str) -> np.ndarray:
    """Return ``x`` as a float array of shape (size,); refuse non-numbers, wrong shapes, non-finite values.

    Raises:
        InvalidInput: naming ``name`` and what is wrong.
    """
    if type(x) is np.ndarray and x.dtype is _FLOAT:  # already a float array: what asarray would return
        arr = x
    else:
        try:
            arr = np.asarray(x, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidInput(f"{name} must be {size} numbers: {exc}") from None
    if arr.shape != (size,):
        raise InvalidInput(f"{name} must have shape ({size},), got {arr.shape}")
    # the sum of a short vector's entries is finite when none is NaN or infinite (a tenth of
    # isfinite().all()'s cost on a few entries); huge finite entries may overflow it: the full check decides
    quick = size <= _SHORT and math.isfinite(sum(arr.tolist()))
    if not quick and not np.isfinite(arr).all():
        raise InvalidInput(f"{name} has non-finite entries at indices {nonfinite_indices(arr)}")
    return arr


def positive(value: object, name: str, unit: str = "") -> float:
    """``value`` as a float if it is a finite real number > 0 (a tolerance, a step, a duration).

    ``unit``, when given, is written in brackets after "number" (e.g. ``"m/rev"``).

    Raises:
        InvalidInput: naming ``name`` and the value (a string, a boolean, NaN, 0 or a negative number).
    """
    if type(value) is float and 0.0 < value < math.inf:  # the common case, without the ABC checks
        return value
    if (
        isinstance(value, bool)
        or not isinstance(value, numbers.Real)
        or not math.isfinite(value)
        or value <= 0
    ):
        shown = f" [{unit}]" if unit else ""
        raise InvalidInput(f"{name} must be a positive finite number{shown}, got {short(value)}")
    return float(value)


def count(value: object, name: str, minimum: int = 0) -> int:
    """``value`` as an int if it is a whole number >= ``minimum`` (not a float, not a boolean).

    Raises:
        InvalidInput: naming ``name`` and the value.
    """
    if type(value) is int and value >= minimum:  # the common case, without the ABC checks
        return value
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise InvalidInput(f"{name} must be a whole number >= {minimum}, got {short(value)}")
    return int(value)


def nonnegative(value: object, name: str, unit: str = "") -> float:
    """``value`` as a float if it is a finite real number >= 0 (a mass, an inertia, a magnitude).

    Args:
        value: the value given.
        name: the argument's name, for the message.
        unit: its SI unit, written in brackets after "number" when given (e.g. ``"kg"``).

    Raises:
        InvalidInput: naming ``name`` and the value (a string, a boolean, NaN, inf or a negative number).
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not (0.0 <= float(value) < math.inf):
        shown = f" [{unit}]" if unit else ""
        raise InvalidInput(f"{name} must be a finite number >= 0{shown}, got {short(value)}")
    return float(value)


def length(value: object, name: str) -> float:
    """``value`` as a float if it is a length: a finite real number > 0 [m].

    Raises:
        InvalidInput: naming ``name``, the value and the valid range.
    """
    if (
        isinstance(value, bool)
        or not isinstance(value, numbers.Real)
        or not math.isfinite(value)
        or value <= 0
    ):
        raise InvalidInput(f"{name} must be a length > 0 [m] (a finite number), got {short(value)}")
    return float(value)


def numbers_of(
    value: object, name: str, size: int, what: str = "finite numbers", check: str = "finite"
) -> np.ndarray:
    """``value`` as a float array of shape (size,): every entry finite, and > 0 or >= 0 as ``check`` says.

    Args:
        value: the sequence given.
        name: the argument's name, for the message.
        size: the number of entries.
        what: what the entries are, for the message (e.g. ``"lengths > 0 [m]"``).
        check: ``"finite"``, ``"positive"`` (> 0) or ``"nonnegative"`` (>= 0).

    Raises:
        InvalidInput: naming ``name``, what it got and which entries are wrong.
    """
    arr = np.asarray(real_numbers(value, name), dtype=float)  # None: NaN of shape (), refused below
    if arr.shape != (size,):
        raise InvalidInput(f"{name} must be {size} {what}, got {short(value)}")
    bad = ~np.isfinite(arr)
    if check == "positive":
        bad |= ~(arr > 0.0)
    elif check == "nonnegative":
        bad |= ~(arr >= 0.0)
    if bad.any():
        raise InvalidInput(
            f"{name} must be {size} {what}, got {short(value)} "
            f"(wrong at indices {np.flatnonzero(bad).tolist()})"
        )
    return arr


def finite_number(value: object, name: str, unit: str = "") -> float:
    """``value`` as a float if it is a finite real number (an angle, a coordinate), not a boolean.

    Raises:
        InvalidInput: naming ``name`` and the value.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        shown = f" [{unit}]" if unit else ""
        raise InvalidInput(f"{name} must be a finite number{shown}, got {short(value)}")
    return float(value)


def finite_array(value: object, name: str, shape: tuple[int, ...], what: str) -> np.ndarray:
    """``value`` as a float array of ``shape`` with finite entries (points, directions, poses).

    Args:
        value: the array-like given.
        name: the argument's name, for the message.
        shape: the shape it must have.
        what: what it holds, for the message (e.g. ``"points [m]"``).

    Raises:
        InvalidInput: naming ``name``, the shape asked and got, or the non-finite entries.
    """
    arr = np.asarray(real_numbers(value, name), dtype=float)  # None: NaN of shape (), refused below
    if arr.shape != shape:
        raise InvalidInput(f"{name} must be an array of shape {shape} of {what}, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise InvalidInput(f"{name} has non-finite entries at indices {nonfinite_indices(arr)}")
    return arr


def optional_positive(value: object, name: str, unit: str) -> float | None:
    """``value`` as a float if it is None or a finite number > 0 (an optional stiffness, say).

    Raises:
        InvalidInput: naming ``name``, the unit and the value.
    """
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not (0.0 < float(value) < math.inf):
        raise InvalidInput(f"{name} must be None or a finite number > 0 [{unit}], got {short(value)}")
    return float(value)


def leg_numbers(value: object, name: str, n: int) -> tuple[int, ...]:
    """``value`` as a sorted tuple if it is a non-empty sequence of distinct whole numbers in 1..n.

    Raises:
        InvalidInput: naming ``name``, the value and the valid numbers.
    """
    numbers_given: list[int] = []
    if isinstance(value, Sequence | np.ndarray) and not isinstance(value, (str, bytes)):
        numbers_given = [
            int(i)
            for i in value
            if isinstance(i, numbers.Integral) and not isinstance(i, bool) and 1 <= int(i) <= n
        ]
        if len(numbers_given) != len(value):  # some entry is not a leg number
            numbers_given = []
    if not numbers_given or len(set(numbers_given)) != len(numbers_given):
        raise InvalidInput(f"{name} must be distinct leg numbers among 1..{n}, got {short(value)}")
    return tuple(sorted(numbers_given))


def flag(value: object, name: str) -> bool:
    """``value`` if it is a boolean (``True`` or ``False``; a NumPy boolean is accepted).

    Raises:
        InvalidInput: naming ``name`` and the value (e.g. the string ``"no"``, which would count as true).
    """
    if value is True or value is False:
        return value
    if not isinstance(value, (bool, np.bool_)):
        raise InvalidInput(f"{name} must be True or False, got {short(value)}")
    return bool(value)


def mapping(value: object, name: str, what: str) -> Mapping:
    """``value`` if it is a mapping (a dict); ``what`` says of what, for the message.

    Raises:
        InvalidInput: naming ``name``, what it got and what it must map.
    """
    if not isinstance(value, Mapping):
        raise InvalidInput(f"{name} must be a mapping of {what}, got {short(value)}")
    return value


def optional_name(value: object, name: str, kind: str = "frame") -> str | None:
    """``value`` if it is None or a name (a string); whether the name exists is checked by the caller.

    Raises:
        InvalidInput: naming ``name`` and the value (e.g. a frame index instead of its name).
    """
    if value is not None and not isinstance(value, str):
        raise InvalidInput(f"{name} must be a {kind} name (a string) or None, got {short(value)}")
    return value


def signs(value: object, name: str) -> tuple[int, ...] | None:
    """``value`` as a tuple if it is None or a sequence of whole numbers, e.g. a working mode of signs.

    Raises:
        InvalidInput: naming ``name`` and the value (a bare number, a string, other entries).
    """
    if value is None:
        return None
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence | np.ndarray):
        raise InvalidInput(
            f"{name} must be None or a sequence of signs (+1 or -1), one per leg; got {short(value)}"
        )
    whole = [isinstance(s, numbers.Real) and not isinstance(s, bool) and float(s).is_integer() for s in value]
    if not all(whole):
        raise InvalidInput(f"{name} must hold signs (+1 or -1), one per leg; got {short(value)}")
    return tuple(int(s) for s in value)  # the caller checks the count and the values


def real_numbers(value: object, name: str) -> object:
    """``value`` unchanged if it is None or holds real numbers only (array-like); the caller checks the shape.

    Raises:
        InvalidInput: naming ``name``: complex numbers, strings, mappings or other objects.
    """
    if value is None:
        return None
    if isinstance(value, (str, bytes, Mapping)):
        raise InvalidInput(f"{name} must be real numbers (array-like), got {short(value)}")
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise InvalidInput(
            f"{name} must be real numbers (array-like): {short(str(exc), quote=False)}"
        ) from None
    if arr.dtype.kind not in "biuf":
        what = "complex numbers" if arr.dtype.kind == "c" else f"{short(value)}"
        raise InvalidInput(f"{name} must be real numbers (array-like), got {what}")
    return value


def effort_limits(value: object, name: str, n: int) -> object:
    """``value`` unchanged if it is a name (``"description"``), None or an (n, 2) array of efforts.

    Each lower bound must be below +inf and each upper bound above -inf (``(inf, inf)`` admits
    no force; it does not mean "unbounded").

    Raises:
        InvalidInput: naming ``name`` and the valid forms.
    """
    valid = f"'description', None or an ({n}, 2) array of [lower, upper] efforts [N, N m]"
    if value is None or isinstance(value, str):  # the caller checks the name
        return value
    if isinstance(value, (bytes, Mapping)):
        raise InvalidInput(f"{name} must be {valid}, got {short(value)}")
    real_numbers(value, name)
    arr = np.asarray(value, dtype=float)
    if arr.shape != (n, 2) or np.isnan(arr).any():
        raise InvalidInput(f"{name} must be {valid}, got {short(value)}")
    if (arr[:, 0] > arr[:, 1]).any() or (arr[:, 0] == np.inf).any() or (arr[:, 1] == -np.inf).any():
        raise InvalidInput(
            f"{name} must have lower <= upper, lower < +inf and upper > -inf for every actuator, got "
            f"{short(arr.tolist())}"
        )
    return value


def physical_effort(value: np.ndarray, name: str) -> np.ndarray:
    """``value`` unchanged if every entry is at most :data:`MAX_EFFORT` in magnitude.

    Raises:
        InvalidInput: naming ``name``, the largest magnitude and the bound.
    """
    largest = float(np.max(np.abs(value), initial=0.0))
    if largest > MAX_EFFORT:
        raise InvalidInput(
            f"{name} reaches {largest:.3g} N (N m), beyond {MAX_EFFORT:.0e}, more than any machine exerts: "
            "not a physical load"
        )
    return value


MAX_SAMPLES = 10_000_000
"""Most samples a simulation or trajectory keeps (``duration / dt``): more would not fit in memory."""


def sample_count(duration: object, dt: object) -> int:
    """The number of output samples ``duration / dt`` + 1, refused beyond :data:`MAX_SAMPLES`.

    Raises:
        InvalidInput: a duration or step that is not a positive finite number, or too many samples.
    """
    d = positive(duration, "duration")
    h = positive(dt, "dt")
    n = d / h
    if n > MAX_SAMPLES:
        raise InvalidInput(
            f"duration / dt = {n:.3g} output samples; at most {MAX_SAMPLES:.0e} are kept: raise dt or "
            "shorten the duration"
        )
    return math.floor(n + 1e-9) + 1


def repeated(names: Iterable[str]) -> list[str]:
    """The names that occur more than once in ``names``, sorted (empty when all are distinct)."""
    return sorted(name for name, n in Counter(names).items() if n > 1)


def load_arguments(
    wrench: object, frame: object, limits: object, n_actuators: int, wrench_name: str = "wrench"
) -> None:
    """Check the types of a wrench, the frame it acts on and the actuator limits (statics and dynamics).

    Raises:
        InvalidInput: naming the argument (``wrench_name`` for the wrench) and its valid forms.
    """
    real_numbers(wrench, wrench_name)
    optional_name(frame, "frame")
    effort_limits(limits, "limits", n_actuators)


# ------------------------------------------------------------ tolerances and results


def check_tolerance(value: object, name: str, *, relative: bool = False) -> float:
    """Return a tolerance as a float; refuse non-numbers, NaN, infinities and negative values.

    Args:
        value: the tolerance given.
        name: the argument's name, for the message.
        relative: a relative tolerance, which must also be below 1.

    Raises:
        InvalidInput: naming ``name`` and the valid range.
    """
    valid = "a finite number in [0, 1)" if relative else "a finite number >= 0"
    if isinstance(value, bool) or not isinstance(value, numbers.Real):  # "1e-6" is text, not a number
        raise InvalidInput(f"{name} must be {valid}, got {short(value)}")
    tol = float(value)
    if not (0.0 <= tol < (1.0 if relative else np.inf)):  # NaN fails every comparison
        raise InvalidInput(f"{name} must be {valid}, got {tol!r}")
    return tol
