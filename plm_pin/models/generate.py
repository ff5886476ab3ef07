"""Regenerate the committed preset descriptions: ``python -m plm_pin.models.generate [FOLDER]``."""

from __future__ import annotations

import sys
from pathlib import Path

from ..description.writer import write_description
from .registry import PRESETS, urdf_folder


def generate(folder: Path | None = None) -> list[Path]:
    """Write ``<name>.urdf`` and ``<name>.plm.yaml`` of every preset into ``folder``.

    Returns:
        The files written.
    """
    out = folder if folder is not None else urdf_folder()
    written: list[Path] = []
    for preset in PRESETS.values():
        robot, sidecar = preset.build()
        written.extend(write_description(robot, sidecar, out, preset.name))
    return written


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    args = sys.argv[1:] if argv is None else argv
    folder = Path(args[0]) if args else None
    for path in generate(folder):
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
