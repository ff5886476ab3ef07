"""Private helpers of the report engine: JSON-ready values, folder names, software versions."""

from __future__ import annotations

import dataclasses
import functools
import math
import platform
import re
import subprocess
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..exceptions import InvalidInput

_SLUG = re.compile(r"[^A-Za-z0-9_-]+")

FOLDER = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*")
"""A report folder name: letters, digits, ``_`` and ``-``, not starting with ``-`` or ``_``."""


def plain(value: Any) -> Any:
    """``value`` as strict JSON data: numpy to Python, NaN and infinities as the strings ``nan``, ``inf``.

    Mappings keep their keys (as strings), sequences and arrays become lists, objects with a
    ``to_dict()`` method are converted by it, dataclasses field by field.

    Raises:
        InvalidInput: for a value that has no JSON form.
    """
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, np.integer)) and not isinstance(value, np.bool_):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, (float, np.floating)):
        number = float(value)
        return number if math.isfinite(number) else str(number)
    if isinstance(value, np.ndarray):
        return [plain(v) for v in value.tolist()]
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if hasattr(value, "to_dict"):
        return plain(value.to_dict())
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return plain({f.name: getattr(value, f.name) for f in dataclasses.fields(value)})
    raise InvalidInput(f"{value!r} ({type(value).__name__}) cannot be written to results.json")


def slug(text: str) -> str:
    """A folder-name piece from any text (a mechanism name from a user file): ``[A-Za-z0-9_-]`` only."""
    return _SLUG.sub("_", text).strip("_-") or "mechanism"


def _version(distribution: str) -> str:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return "not installed"


def git_commit() -> str | None:
    """The git commit of the plm_pin checkout this code runs from (``+ changes`` when modified), else None."""
    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        return None
    try:
        run = functools.partial(
            subprocess.run, cwd=root, capture_output=True, text=True, timeout=10, check=True
        )
        commit = run(["git", "rev-parse", "--short=12", "HEAD"]).stdout.strip()
        dirty = run(["git", "status", "--porcelain", "--untracked-files=no"]).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return f"{commit} + changes" if dirty else commit


def software_versions() -> dict[str, str]:
    """Versions of plm_pin (and its git commit in a checkout), its numerical stack, libraries and Python."""
    commit = git_commit()
    return {
        "plm_pin": __version__,
        **({"plm_pin commit": commit} if commit else {}),
        "pinocchio": _version("pin"),
        "proxsuite": _version("proxsuite"),
        "highspy": _version("highspy"),
        "numpy": _version("numpy"),
        "scipy": _version("scipy"),
        "matplotlib": _version("matplotlib"),
        "meshcat": _version("meshcat"),
        "python": platform.python_version(),
    }
