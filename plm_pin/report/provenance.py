"""Where a report comes from: the versions of plm_pin (and its git commit) and of the software it ran on."""

from __future__ import annotations

import functools
import platform
import subprocess
from importlib import metadata
from pathlib import Path

from .._version import __version__


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
