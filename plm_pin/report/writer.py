"""Writing reports: one folder per study, swapped in whole, and the index written last.

A report's ``report.html`` and ``results.json`` are written into a hidden temporary folder
inside the output folder, then exchanged with the old report folder in one atomic step
(Linux ``renameat2(RENAME_EXCHANGE)``), so a failed or interrupted run leaves the previous
report as it was and the report folder never goes missing. Where that call is not
available the old folder is renamed aside first; a kill between the two renames is undone
by the next run, which puts the old report back. Hidden ``.tmp`` and ``.old`` folders left
by killed runs (their process gone) are removed by the next run.
Every path written is checked to lie inside the output folder.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import errno
import json
import os
import re
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .._io import atomic_write_text
from ..exceptions import InvalidInput
from ..viz.meshcat_view import meshcat_bundle, share_bundle
from .content import FORMAT, Scene, StudyResult
from .folders import FOLDER
from .provenance import software_versions
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


_HIDDEN = re.compile(r"\.(?P<folder>[A-Za-z0-9][A-Za-z0-9_-]*)\.(?P<pid>[0-9]+)\..*\.(?P<kind>tmp|old)")
"""A hidden working folder: ``.<report folder>.<pid of its writer>.<random>.tmp`` (or ``.old``)."""


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs on this machine (a folder of a live writer is never touched)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def recover(root: Path) -> None:
    """Undo what killed runs left in ``root``: put a report moved aside back, remove working folders.

    Only folders whose writing process has ended are touched.
    """
    for folder in sorted(root.iterdir()):
        match = _HIDDEN.fullmatch(folder.name)
        if match is None or not folder.is_dir() or folder.is_symlink() or _alive(int(match["pid"])):
            continue
        name = match["folder"]
        aside = folder / name
        if match["kind"] == "old" and aside.is_dir() and not (root / name).exists():
            os.rename(aside, root / name)  # killed between the two renames: the old report returns
        shutil.rmtree(folder, ignore_errors=True)


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
    recover(root)
    scenes = [b for s in result.sections for b in s.blocks if isinstance(b, Scene)]
    files = {id(scene): f"scene-{k}.html" for k, scene in enumerate(scenes, 1)}
    page = render_report(result, files)
    scene_pages = {files[id(scene)]: _scene_page(scene) for scene in scenes}
    data = json.dumps(result.to_dict(), indent=1, allow_nan=False)
    tmp = Path(tempfile.mkdtemp(dir=root, prefix=f".{result.folder}.{os.getpid()}.", suffix=".tmp"))
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


_AT_FDCWD = -100
_RENAME_EXCHANGE = 2


def _exchange(a: Path, b: Path) -> bool:
    """Swap two existing paths in one atomic step (Linux ``renameat2``); False where not available."""
    libc_name = ctypes.util.find_library("c")
    renameat2 = getattr(ctypes.CDLL(libc_name, use_errno=True), "renameat2", None) if libc_name else None
    if renameat2 is None:
        return False
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):  # kernel or file system without it
        return False
    raise OSError(code, os.strerror(code), str(b))


def _scene_page(scene: Scene) -> str:
    """A scene's page as written beside its report: meshcat's bundle loaded from :data:`BUNDLE`."""
    return share_bundle(scene.html, f"../{BUNDLE}")


def _write_bundle(path: Path) -> None:
    """Write meshcat's bundle at ``path`` (atomically), unless the same bundle is there already."""
    bundle = meshcat_bundle()
    if path.is_symlink() or not path.is_file() or path.read_text(encoding="utf-8") != bundle:
        if path.is_symlink():
            path.unlink()
        atomic_write_text(path, bundle)
        path.chmod(0o644)


def _replace_folder(new: Path, final: Path) -> None:
    """Put the folder ``new`` at ``final`` and delete the old one.

    One atomic exchange where the system offers it; else the old folder is renamed aside
    first (:func:`recover` undoes a kill between the two renames).
    """
    if not final.exists():
        os.rename(new, final)
        return
    if _exchange(new, final):
        shutil.rmtree(new, ignore_errors=True)  # now holds the old report
        return
    old = Path(tempfile.mkdtemp(dir=final.parent, prefix=f".{final.name}.{os.getpid()}.", suffix=".old"))
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
    recover(root)
    entries = [
        e
        for folder in sorted(root.iterdir())
        if FOLDER.fullmatch(folder.name) and folder.is_dir() and not folder.is_symlink()
        if (e := _entry(folder)) is not None
    ]
    path = root / INDEX
    atomic_write_text(path, render_index(entries, software_versions()))
    return path
