"""Writing reports: one folder per study, swapped in whole, and the index written last.

A report's ``report.html`` and ``results.json`` are written into a hidden temporary folder
inside the output folder, then renamed over the old report folder (which is first moved
aside, then deleted), so a failed or interrupted run leaves the previous report as it was.
Every path written is checked to lie inside the output folder.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .._io import atomic_write_text
from ..exceptions import InvalidInput
from ._private import FOLDER, software_versions
from .content import FORMAT, Scene, StudyResult
from .render import render_index, render_report

BUNDLE = "meshcat.min.js"
"""meshcat's JavaScript bundle, written once in the output folder and loaded by every report's scenes."""

REPORT = "report.html"
RESULTS = "results.json"
INDEX = "index.html"


def output_folder(out: str | Path) -> Path:
    """The output folder, created if missing, as an absolute path.

    Raises:
        InvalidInput: when ``out`` exists and is not a folder.
    """
    path = Path(out)
    if path.exists() and not path.is_dir():
        raise InvalidInput(f"--out {out}: is not a folder")
    path.mkdir(parents=True, exist_ok=True)
    return path.resolve()


def inside(root: Path, name: str) -> Path:
    """``root / name`` for a report folder name, refused unless it is a plain name inside ``root``.

    Raises:
        InvalidInput: a name with separators, dots or other characters (e.g. ``../x``), a path
            resolving outside ``root``, or an existing symbolic link.
    """
    if not FOLDER.fullmatch(name):
        raise InvalidInput(
            f"report folder {name!r} is not a plain name (letters, digits, '_', '-'); nothing is "
            f"written outside {root}"
        )
    path = root / name
    if path.is_symlink() or not path.resolve().is_relative_to(root.resolve()):
        raise InvalidInput(f"report folder {path} is a link or lies outside {root}; it is not replaced")
    return path


def write_report(result: StudyResult, out: str | Path) -> Path:
    """Write one report (``report.html``, ``results.json``, ``scene-N.html``) into ``out/<result.folder>``.

    The page is rendered before anything is written; the files go to a temporary folder
    that then replaces the old report folder whole. Each meshcat scene is a page of its own
    beside the report, loaded lazily by it, and all of them load the one copy of meshcat's
    JavaScript written in ``out`` (:data:`BUNDLE`), instead of carrying 0.85 MB each.

    Returns:
        The path of ``report.html``.

    Raises:
        InvalidInput: ``out`` is not a folder, or the report folder would not lie inside it.
    """
    root = output_folder(out)
    final = inside(root, result.folder)
    scenes = [b for s in result.sections for b in s.blocks if isinstance(b, Scene)]
    files = {id(scene): f"scene-{k}.html" for k, scene in enumerate(scenes, 1)}
    page = render_report(result, files)
    scene_pages = {files[id(scene)]: _scene_page(scene) for scene in scenes}
    data = json.dumps(result.to_dict(), indent=1, allow_nan=False)
    tmp = Path(tempfile.mkdtemp(dir=root, prefix=f".{result.folder}.", suffix=".tmp"))
    try:
        (tmp / RESULTS).write_text(data, encoding="utf-8")
        (tmp / REPORT).write_text(page, encoding="utf-8")
        for name, text in scene_pages.items():
            (tmp / name).write_text(text, encoding="utf-8")
        for f in tmp.iterdir():
            f.chmod(0o644)
        tmp.chmod(0o755)  # mkdtemp makes it owner-only
        if scenes:
            _write_bundle(root / BUNDLE)
        _replace_folder(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return final / REPORT


def _scene_page(scene: Scene) -> str:
    """A scene's page as written beside its report: meshcat's bundle loaded from :data:`BUNDLE`."""
    from ..viz.meshcat_view import share_bundle

    return share_bundle(scene.html, f"../{BUNDLE}")


def _write_bundle(path: Path) -> None:
    """Write meshcat's bundle at ``path`` (atomically), unless the same bundle is there already."""
    from ..viz.meshcat_view import meshcat_bundle

    bundle = meshcat_bundle()
    if path.is_symlink() or not path.is_file() or path.read_text(encoding="utf-8") != bundle:
        if path.is_symlink():
            path.unlink()
        atomic_write_text(path, bundle)
        path.chmod(0o644)


def _replace_folder(new: Path, final: Path) -> None:
    """Put the folder ``new`` at ``final``: the old one is renamed aside first, then deleted."""
    if not final.exists():
        os.rename(new, final)
        return
    old = Path(tempfile.mkdtemp(dir=final.parent, prefix=f".{final.name}.", suffix=".old"))
    os.rename(final, old / final.name)
    try:
        os.rename(new, final)
    except BaseException:
        os.rename(old / final.name, final)  # put the good report back
        old.rmdir()
        raise
    shutil.rmtree(old, ignore_errors=True)


def _entry(folder: Path) -> dict[str, Any] | None:
    """An index entry from a report folder's results.json; None when it is not one of ours."""
    try:
        data = json.loads((folder / RESULTS).read_text(encoding="utf-8"))
        if not isinstance(data, Mapping) or data.get("format") != FORMAT:
            return None
        return {
            "folder": folder.name,
            "title": str(data["title"]),
            "summary": str(data["summary"]),
            "mechanisms": [str(m["name"]) for m in data["mechanisms"]],
            "rows": int(data["agreement"]["rows"]),
            "agree": int(data["agreement"]["agree"]),
            "paper_inconsistent": int(data["agreement"].get("paper_inconsistent", 0)),
            "generated": str(data["generated"]),
        }
    except (OSError, ValueError, KeyError, TypeError):
        return None


def write_index(out: str | Path) -> Path:
    """Write ``out/index.html`` linking every report folder in ``out`` (atomically); returns its path."""
    root = output_folder(out)
    entries = [
        e
        for folder in sorted(root.iterdir())
        if FOLDER.fullmatch(folder.name) and folder.is_dir() and not folder.is_symlink()
        if (e := _entry(folder)) is not None
    ]
    path = root / INDEX
    atomic_write_text(path, render_index(entries, software_versions()))
    return path
