"""Report folder names: which names a report folder may have, and a safe name piece from any text."""

from __future__ import annotations

import re

_SLUG = re.compile(r"[^A-Za-z0-9_-]+")

FOLDER = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*")
"""A report folder name: letters, digits, ``_`` and ``-``, not starting with ``-`` or ``_``."""


def slug(text: str) -> str:
    """A folder-name piece from any text (a mechanism name from a user file): ``[A-Za-z0-9_-]`` only."""
    return _SLUG.sub("_", text).strip("_-") or "mechanism"
