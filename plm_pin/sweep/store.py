"""The checkpoint store of a sweep: one Parquet file per finished chunk, and a manifest naming the sweep.

Layout of a store folder::

    manifest.json                                 the sweep's canonical spec, its key (SHA-256), its source
    chunks/points-0000000-0000039.parquet         one row per parameter point of a finished chunk
    chunks/points-0000000-0000039.parquet.sha256  the SHA-256 of that file's bytes
    .lock, .lock.owner                            held while a sweep runs; who holds it (pid, host)

Every file is written to a temporary name in its folder, then renamed over its final name
(``os.replace``, atomic on POSIX and Windows), so an interrupted sweep leaves finished
chunks whole and at most a temporary file, removed by the next run. A folder whose
manifest names another sweep is refused, never mixed with it. Each Parquet file carries
the key too, and a file whose key, columns or content hash do not match (a flipped bit, a
file from elsewhere, a chunk whose hash was never written) is ignored (with a warning) and
its points computed again. One sweep at a time uses a folder: a second one started on it
is refused, naming the process and host that hold its lock.

In a chunk file, column ``point`` holds the flat parameter index and every result variable
is a fixed-size list column (its values at that point, flattened row-major) of float64,
int8 or bool: floats are stored bit for bit.
"""

from __future__ import annotations

import datetime
import hashlib
import json
import os
import socket
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_path, atomic_write_text
from .._text import short
from ..exceptions import InvalidInput, StoreLocked, StoreMismatch
from ..warnings import CorruptChunkWarning
from ._deps import require
from .execution import ChunkValues
from .spec import FORMAT, SweepSpec

MANIFEST = "manifest.json"
CHUNKS = "chunks"
KEY_METADATA = b"plm_pin_sweep_key"
LOCK = ".lock"
DIGEST_SUFFIX = ".sha256"


def chunk_name(first: int, last: int) -> str:
    """File name of the chunk holding the parameter points ``first`` .. ``last``."""
    return f"points-{first:07d}-{last:07d}.parquet"


def _read_manifest(path: Path) -> tuple[str, dict[str, Any]]:
    """The key and spec a manifest holds.

    Raises:
        InvalidInput: the file is unreadable, not JSON, or not an object with a key and a spec.
    """
    try:
        found = json.loads(path.read_text(encoding="utf-8"))
        problem = "it is not a JSON object with a 'key' and a 'spec'"
    except (OSError, ValueError) as exc:  # unreadable, not UTF-8, not JSON
        found, problem = None, short(str(exc), quote=False)
    if isinstance(found, dict) and isinstance(found.get("key"), str) and isinstance(found.get("spec"), dict):
        return found["key"], found["spec"]
    raise InvalidInput(
        f"{path}: not a plm_pin sweep manifest ({problem}); give another folder, or delete it to start again"
    )


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def lock_folder(root: Path, what: str = "sweep") -> Any:
    """Take the lock of a checkpoint folder (a :class:`filelock.FileLock`), or say who holds it.

    Args:
        root: the folder (it exists).
        what: the kind of run using it, in the message (``"sweep"``, ``"optimisation"``).

    Raises:
        StoreLocked: another process holds the folder (the message names its pid and host).
    """
    filelock = require("filelock")
    lock = filelock.FileLock(root / LOCK, timeout=0)
    owner = root / f"{LOCK}.owner"
    try:
        lock.acquire()
    except filelock.Timeout:
        try:
            holder = json.loads(owner.read_text(encoding="utf-8"))
            who = f"process {holder['pid']} on {holder['host']} since {holder['since']}"
        except (OSError, ValueError, KeyError, TypeError):
            who = "another process"
        raise StoreLocked(
            f"{root} is in use by another {what} ({short(who, quote=False)}): wait for it to end, "
            "or give another folder",
            root,
            who,
        ) from None
    since = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    holder = {"pid": os.getpid(), "host": socket.gethostname(), "since": since}
    atomic_write_text(owner, json.dumps(holder))
    return lock


def unlock_folder(root: Path, lock: Any) -> None:
    """Release a lock taken by :func:`lock_folder`."""
    (root / f"{LOCK}.owner").unlink(missing_ok=True)
    lock.release()


def check_manifest(root: Path, document: dict[str, Any], what: str = "sweep") -> None:
    """Check that ``root``'s manifest names the run ``document`` describes, or write it there.

    Args:
        root: the folder.
        document: the manifest: ``format``, ``key`` (SHA-256 of ``spec``), ``spec``, ...
        what: the kind of run, in the message.

    Raises:
        StoreMismatch: the manifest names another run (the message says which fields differ).
        InvalidInput: the manifest is unreadable.
    """
    manifest = root / MANIFEST
    key = document["key"]
    if manifest.exists():
        found_key, found_spec = _read_manifest(manifest)
        if found_key != key:
            ours = document["spec"]
            fields = tuple(k for k in sorted(set(ours) | set(found_spec)) if ours.get(k) != found_spec.get(k))
            raise StoreMismatch(
                f"{root} holds the checkpoints of another {what} (key {found_key[:12]}, this one "
                f"{key[:12]}; they differ in {short(list(fields))}): give another folder, or delete "
                "it to start again",
                root,
                fields,
            )
    else:
        atomic_write_text(manifest, json.dumps(document, indent=2) + "\n")


class SweepStore:
    """Checkpoints of one sweep in a folder (created if needed), locked while open.

    Use it as a context manager, or call :meth:`close`, to release the folder's lock.

    Attributes:
        root: the folder.
        key: the sweep's key.
    """

    def __init__(self, root: str | Path, spec: SweepSpec) -> None:
        """Open the store of ``spec`` in ``root``, or start one, and lock the folder.

        Raises:
            StoreLocked: another process holds the folder (the message names its pid and host).
            StoreMismatch: ``root`` holds another sweep (the message says which fields differ).
            InvalidInput: ``root`` is a file, or its manifest is unreadable.
        """
        self.root = Path(root)
        self.spec = spec
        self.key = spec.key()
        if self.root.exists() and not self.root.is_dir():
            raise InvalidInput(f"checkpoint folder {self.root} is a file; give a folder")
        self.chunks = self.root / CHUNKS
        self.chunks.mkdir(parents=True, exist_ok=True)
        self._lock = lock_folder(self.root)
        try:
            self._open_manifest()
        except BaseException:
            self.close()
            raise
        for stale in [*self.chunks.glob(".*.tmp"), *self.root.glob(f".{MANIFEST}.*.tmp")]:
            stale.unlink(missing_ok=True)  # left by an interrupted write: never a finished chunk

    def close(self) -> None:
        """Release the folder's lock (idempotent)."""
        if self._lock is not None:
            unlock_folder(self.root, self._lock)
            self._lock = None

    def __enter__(self) -> SweepStore:
        """The store itself; its lock is released on leaving the block."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Release the lock."""
        self.close()

    def _open_manifest(self) -> None:
        """Check the manifest names this sweep, or write it."""
        spec = self.spec
        document = {"format": FORMAT, "key": self.key, "spec": spec.to_dict(), "source": spec.source}
        check_manifest(self.root, document)

    def load(self) -> list[ChunkValues]:
        """Every finished chunk of this sweep (files that do not belong are skipped with a warning)."""
        pq = require("pyarrow.parquet")
        variables = self.spec.variables()
        out = []
        pa = require("pyarrow")
        for path in sorted(self.chunks.glob("points-*.parquet")):
            try:
                data = path.read_bytes()
                digest = path.with_name(path.name + DIGEST_SUFFIX)
                expected = digest.read_text(encoding="ascii").strip() if digest.is_file() else "missing"
                if _digest(data) != expected:
                    raise ValueError(f"its SHA-256 is not the one recorded ({expected[:12]})")
                table = pq.read_table(pa.BufferReader(data))
                key = (table.schema.metadata or {}).get(KEY_METADATA, b"").decode()
                if key != self.key:
                    raise ValueError(f"key {key[:12] or 'missing'} is not this sweep's")
                points = table.column("point").to_numpy().astype(np.int64)
                values = {}
                for v in variables:
                    flat = table.column(v.name).combine_chunks().flatten().to_numpy(zero_copy_only=False)
                    values[v.name] = flat.astype(v.dtype).reshape(len(points), *self.spec.variable_shape(v))
            except Exception as exc:  # any unreadable file is recomputed, never trusted
                warnings.warn(
                    f"{path}: cannot be used ({type(exc).__name__}: {exc}); its points are computed again",
                    CorruptChunkWarning,
                    stacklevel=2,
                )
                continue
            out.append(ChunkValues(points, values, {}))
        return out

    def write(self, chunk: ChunkValues) -> Path:
        """Write a finished chunk atomically; returns its path."""
        pa = require("pyarrow")
        pq = require("pyarrow.parquet")
        columns: dict[str, Any] = {"point": pa.array(chunk.points, type=pa.int64())}
        for v in self.spec.variables():
            arr = np.ascontiguousarray(chunk.values[v.name])
            size = int(np.prod(arr.shape[1:]))
            columns[v.name] = pa.FixedSizeListArray.from_arrays(pa.array(arr.reshape(-1)), size)
        table = pa.table(columns).replace_schema_metadata({KEY_METADATA: self.key.encode()})
        path = self.chunks / chunk_name(int(chunk.points[0]), int(chunk.points[-1]))
        with atomic_path(path) as tmp:
            pq.write_table(table, tmp)
            atomic_write_text(path.with_name(path.name + DIGEST_SUFFIX), _digest(tmp.read_bytes()) + "\n")
        return path
