"""Private text helpers for messages: quote a value without ever writing out an unbounded one."""

from __future__ import annotations

import reprlib

_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxdict, _REPR.maxlist, _REPR.maxtuple = 3, 6, 8, 8
_REPR.maxset, _REPR.maxstring, _REPR.maxother, _REPR.maxlong = 8, 60, 60, 40

SHORT = 100
"""Most characters of a value quoted in a message."""


def short(value: object, quote: bool = True) -> str:
    """A bounded text for quoting ``value`` in a message: its ``repr``, cut to :data:`SHORT` characters.

    With ``quote=False`` a string is given as it is (cut likewise), without quotes.

    Nested containers are abbreviated level by level (``reprlib``) without building their
    whole text, so a value standing for a huge structure is quoted in constant time.
    """
    text = value if isinstance(value, str) and not quote else _REPR.repr(value)
    return text if len(text) <= SHORT else text[: SHORT - 5] + "[...]"
