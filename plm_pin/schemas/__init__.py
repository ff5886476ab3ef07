"""JSON Schemas of plm_pin's YAML files, for editors to validate and complete them.

- ``plm-pin-sidecar.schema.json``: the closure sidecar ``<name>.plm.yaml`` (format ``plm-pin/1``,
  :mod:`plm_pin.description.sidecar`);
- ``plm-pin-sweep.schema.json``: the sweep configuration of ``plm-pin sweep``
  (format ``plm-pin-sweep/1``, :mod:`plm_pin.sweep.config`);
- ``plm-pin-optimize.schema.json``: the optimisation configuration of ``plm-pin optimize``
  (format ``plm-pin-optimize/1``, :mod:`plm_pin.optimize.config`).

An editor with a YAML language server picks a schema up from a first line such as
``# yaml-language-server: $schema=path/to/plm-pin-sidecar.schema.json``. The schemas check
the structure, types and units' ranges; ``plm-pin check`` also checks what they cannot
(frames and joints exist, ``lower < upper``, values finite) and is the reference.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ..exceptions import InvalidInput

_FOLDER = Path(__file__).resolve().parent
"""Folder holding the schema files (shipped in the wheel)."""

SCHEMAS = {
    "sidecar": "plm-pin-sidecar.schema.json",
    "sweep": "plm-pin-sweep.schema.json",
    "optimize": "plm-pin-optimize.schema.json",
}
"""Schema name -> file name in this package's folder."""


def schema_path(name: str) -> Path:
    """Path of the schema ``name`` (``sidecar`` or ``sweep``).

    Raises:
        InvalidInput: an unknown name (the message lists them).
    """
    if name not in SCHEMAS:
        raise InvalidInput(f"unknown schema {name!r}; schemas are {sorted(SCHEMAS)}")
    return _FOLDER / SCHEMAS[name]


def load_schema(name: str) -> dict[str, Any]:
    """The schema ``name`` (``sidecar`` or ``sweep``) as a JSON object.

    Raises:
        InvalidInput: an unknown name.
    """
    data: dict[str, Any] = json.loads(schema_path(name).read_text(encoding="utf-8"))
    return data


__all__ = ["SCHEMAS", "load_schema", "schema_path"]
