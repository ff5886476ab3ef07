"""The checkpoint store of an optimisation: one Parquet file per evaluated generation, and a manifest.

Layout of a store folder (the lock and the manifest as a sweep's, :mod:`plm_pin.sweep.store`)::

    manifest.json                               the problem's canonical description, its key, the search
    generations/generation-00000.parquet        one row per design of a generation (00000: the start design)
    generations/generation-00000.parquet.sha256 the SHA-256 of that file's bytes
    .lock, .lock.owner                          held while the optimisation runs

A row holds the design's variables, the violation of every level of the constraint hierarchy
(``violation:<level>``, NaN when not evaluated), the measure compared with every constraint's
limit (``measure:<constraint>``), the objectives (``objective:<name>``), the level it fails
(``failed``, empty when feasible) and the error of the builder or analysis that raised.
Floats are stored bit for bit, so a resumed search replays the stored designs exactly.
"""

from __future__ import annotations

import hashlib
import json
import warnings
from pathlib import Path
from typing import Any

from .._io import atomic_path, atomic_write_text
from ..exceptions import InvalidInput
from ..sweep.store import check_manifest, lock_folder, unlock_folder
from ..warnings import CorruptChunkWarning
from .evaluate import DesignEvaluation
from .problem import FORMAT, Problem

GENERATIONS = "generations"
DIGEST_SUFFIX = ".sha256"


def generation_name(generation: int) -> str:
    """File name of a generation."""
    return f"generation-{generation:05d}.parquet"


def to_row(problem: Problem, generation: int, design: int, ev: DesignEvaluation) -> dict[str, Any]:
    """The stored row of an evaluated design."""
    row: dict[str, Any] = {"generation": generation, "design": design}
    row.update(zip(problem.names, ev.x, strict=True))
    row.update({f"violation:{k}": v for k, v in ev.violations.items()})
    row.update({f"measure:{k}": v for k, v in ev.measures.items()})
    row.update({f"objective:{k}": v for k, v in ev.objectives.items()})
    row.update(failed=ev.failed, error=ev.error, score=ev.score(problem))
    return row


def from_row(problem: Problem, row: dict[str, Any]) -> DesignEvaluation:
    """The evaluated design a stored row holds."""
    return DesignEvaluation(
        tuple(float(row[n]) for n in problem.names),
        {k: float(row[f"violation:{k}"]) for k in problem.levels},
        {k: float(row[f"measure:{k}"]) for k in problem.constraints},
        {o.name: float(row[f"objective:{o.name}"]) for o in problem.objectives},
        str(row["failed"]),
        str(row["error"]),
    )


class OptimizeStore:
    """Checkpoints of one optimisation in a folder (created if needed), locked while open.

    Attributes:
        root: the folder.
        key: the problem's key.
    """

    def __init__(self, root: str | Path, problem: Problem, search: dict[str, Any]) -> None:
        """Open the store of ``problem`` searched by ``search`` (method and settings) in ``root``.

        Raises:
            StoreLocked: another process holds the folder.
            StoreMismatch: ``root`` holds another optimisation (problem or search settings differ).
            InvalidInput: ``root`` is a file, or its manifest is unreadable.
        """
        self.root = Path(root)
        self.problem = problem
        if self.root.exists() and not self.root.is_dir():
            raise InvalidInput(f"checkpoint folder {self.root} is a file; give a folder")
        self.generations = self.root / GENERATIONS
        self.generations.mkdir(parents=True, exist_ok=True)
        spec = {**problem.to_dict(), "search": search}
        self.key = hashlib.sha256(json.dumps(spec, sort_keys=True, allow_nan=False).encode()).hexdigest()
        self._lock: Any = lock_folder(self.root, "optimisation")
        try:
            document = {"format": FORMAT, "key": self.key, "spec": spec, "source": problem.spec.source}
            check_manifest(self.root, document, "optimisation")
        except BaseException:
            self.close()
            raise
        for stale in self.generations.glob(".*.tmp"):
            stale.unlink(missing_ok=True)

    def close(self) -> None:
        """Release the folder's lock (idempotent)."""
        if self._lock is not None:
            unlock_folder(self.root, self._lock)
            self._lock = None

    def __enter__(self) -> OptimizeStore:
        """The store itself; its lock is released on leaving the block."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Release the lock."""
        self.close()

    def load(self) -> dict[int, list[dict[str, Any]]]:
        """The stored generations: number -> rows (files whose hash does not match are skipped, warned)."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        out = {}
        for path in sorted(self.generations.glob("generation-*.parquet")):
            data = path.read_bytes()
            digest = path.with_name(path.name + DIGEST_SUFFIX)
            expected = digest.read_text(encoding="ascii").strip() if digest.is_file() else "missing"
            if hashlib.sha256(data).hexdigest() != expected:
                warnings.warn(
                    f"{path}: its SHA-256 is not the one recorded; its designs are evaluated again",
                    CorruptChunkWarning,
                    stacklevel=2,
                )
                continue
            out[int(path.stem.split("-")[1])] = pq.read_table(pa.BufferReader(data)).to_pylist()
        return out

    def write(self, generation: int, rows: list[dict[str, Any]]) -> Path:
        """Write a generation's rows atomically; returns its path."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        path = self.generations / generation_name(generation)
        with atomic_path(path) as tmp:
            pq.write_table(pa.Table.from_pylist(rows), tmp)
            digest = hashlib.sha256(tmp.read_bytes()).hexdigest()
            atomic_write_text(path.with_name(path.name + DIGEST_SUFFIX), digest + "\n")
        return path
