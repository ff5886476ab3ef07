"""The sweep configuration file (YAML) read by ``plm-pin sweep CONFIG.yaml``.

.. code-block:: yaml

    format: plm-pin-sweep/1          # optional; checked when given
    mechanism: harada2011_3d4m       # a preset, a description path, or a builder "package.module:function"
    base: {rod_lengths: [0.14, 0.14, 0.14, 0.14]}   # fixed builder parameters (optional)
    parameters:                      # a grid (mapping) or samples (a list of mappings)
      legs: [[1, 2, 4], [1, 2, 3, 4]]
      half_plate: {linspace: [0.0175, 0.07, 4]}
    poses:                           # the pose grid, task coordinates [m, rad]
      y: {linspace: [0.02, 0.12, 6]}
      rz: {linspace: [-80, 80, 161], unit: deg}
    pose: [0.0, 0.08, 0.0]           # the other coordinates (optional: reference pose)
    metrics: [orientation_range, min_manipulability]
    options: {over: [rz]}            # metric options (optional)
    chunk: 4096                      # poses per task (optional; --chunk overrides)

A list of values is given as a list, or as ``{linspace: [start, stop, num]}`` or
``{values: [...]}``, either with an optional ``unit`` among ``deg`` (converted to rad),
``mm`` (to m), ``rad`` and ``m``. A builder named ``module:function`` is imported: a
configuration file is trusted like code. A description path (a ``.urdf`` with its sidecar, a
``.plm.yaml`` or a folder, relative to the working directory as for ``plm-pin view PATH``)
is swept like :func:`~plm_pin.sweep.sweep` sweeps it: without ``parameters``, the mechanism
is loaded once here and shipped to the workers, which need not have the file.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._text import short
from .._yaml import YamlRefused, load_yaml, read_head
from ..exceptions import InvalidInput
from .spec import FORMAT, SweepSpec, make_spec

KEYS = ("format", "mechanism", "base", "parameters", "poses", "pose", "metrics", "options", "chunk")
"""Keys of a configuration file."""

UNITS = {"deg": math.pi / 180.0, "rad": 1.0, "mm": 1e-3, "m": 1.0}
"""Units a list of values may be given in, and their factor to SI."""


def values_of(where: str, raw: Any) -> Any:
    """A list of values from its YAML form: a list, or ``{linspace: ...}`` / ``{values: ...}`` with a unit."""
    if not isinstance(raw, Mapping):
        return raw
    unknown = [k for k in raw if k not in ("linspace", "values", "unit")]
    if unknown or ("linspace" in raw) == ("values" in raw):
        raise InvalidInput(
            f"{where}: give a list, {{linspace: [start, stop, num]}} or {{values: [...]}} (with an optional "
            f"unit among {list(UNITS)}), got {short(dict(raw))}"
        )
    unit = raw.get("unit", None)
    if unit is not None and (not isinstance(unit, str) or unit not in UNITS):
        raise InvalidInput(f"{where}: unknown unit {short(unit)}; units are {list(UNITS)}")
    if "linspace" in raw:
        spec = raw["linspace"]
        if (
            not isinstance(spec, list)
            or len(spec) != 3
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in spec)
            or not isinstance(spec[2], int)
            or spec[2] < 1
        ):
            raise InvalidInput(
                f"{where}: linspace takes [start, stop, number of values >= 1], got {short(spec)}"
            )
        values: Any = np.linspace(float(spec[0]), float(spec[1]), spec[2]).tolist()
    else:
        values = raw["values"]
    if unit is None or UNITS[unit] == 1.0:
        return values
    try:
        return (np.asarray(values, dtype=float) * UNITS[unit]).tolist()
    except (TypeError, ValueError):
        raise InvalidInput(f"{where}: values in {unit} must be numbers, got {short(values)}") from None


def import_mechanism(raw: Any) -> Any:
    """A configuration's ``mechanism``: a preset name or a path as given, a ``module:function`` imported.

    Raises:
        InvalidInput: not a non-empty string, or a builder that cannot be imported.
    """
    if not isinstance(raw, str) or not raw:
        raise InvalidInput(
            "mechanism must be a preset name, a description path or a builder 'module:function', "
            f"got {short(raw)}"
        )
    if ":" not in raw or Path(raw).exists():
        return raw
    module, _, name = raw.partition(":")
    try:
        builder = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as exc:
        raise InvalidInput(f"mechanism {short(raw)}: cannot import the builder ({exc})") from None
    return builder


def mechanism_beside(config: Any, folder: Path) -> Any:
    """The configuration with a relative description path in ``mechanism`` read from ``folder``.

    A path written in a configuration file names a file beside that file, wherever the command
    runs; a preset name, a builder ``module:function`` or an absolute path is left as it is.
    """
    raw = config.get("mechanism") if isinstance(config, Mapping) else None
    if isinstance(raw, str) and raw and not Path(raw).is_absolute() and (folder / raw).exists():
        return {**config, "mechanism": str(folder / raw)}
    return config


def check_header(config: Any, what: str, keys: Sequence[str], form: str, required: Sequence[str]) -> None:
    """Check the top level of a configuration mapping: a mapping, known keys, its format, required keys.

    Args:
        config: the configuration as read.
        what: what it is, for the messages (``"a sweep configuration"``).
        keys: the keys it may have.
        form: the ``format`` value it must carry when it gives one.
        required: the keys it must have.

    Raises:
        InvalidInput: the first of these it fails, naming the key and the valid choices.
    """
    if not isinstance(config, Mapping):
        raise InvalidInput(f"{what} is a mapping of {list(keys)}, got {type(config).__name__}")
    unknown = [k for k in config if k not in keys]
    if unknown:
        raise InvalidInput(f"unknown key(s) {short(unknown)}; keys are {list(keys)}")
    if "format" in config and config["format"] != form:
        raise InvalidInput(f"format {short(config['format'])} is not {short(form)}")
    for key in required:
        if key not in config:
            raise InvalidInput(f"missing key {short(key)}")


def spec_from_config(config: Any, source: str = "<config>") -> tuple[SweepSpec, int | None]:
    """The sweep a configuration mapping describes, and its ``chunk`` (None when not given).

    Raises:
        InvalidInput: an unknown key, a malformed entry, or anything :func:`~plm_pin.sweep.make_spec` refuses;
            the message starts with ``source``.
    """
    try:
        check_header(config, "a sweep configuration", KEYS, FORMAT, ("mechanism", "poses", "metrics"))
        raw_params = config.get("parameters")
        if isinstance(raw_params, Mapping):
            parameters: Any = {k: values_of(f"parameters.{k}", v) for k, v in raw_params.items()}
        else:
            parameters = raw_params
        poses = config["poses"]
        if isinstance(poses, Mapping):
            poses = {k: values_of(f"poses.{k}", v) for k, v in poses.items()}
        options = config.get("options") or {}
        if not isinstance(options, Mapping):
            raise InvalidInput(f"options must be a mapping, got {short(options)}")
        chunk = config.get("chunk")
        if chunk is not None and (isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 1):
            raise InvalidInput(f"chunk must be a positive number of poses per task, got {short(chunk)}")
        spec = make_spec(
            import_mechanism(config["mechanism"]),
            parameters,
            poses,
            config["metrics"],
            base=config.get("base"),
            pose=config.get("pose"),
            options=options,
        )
    except InvalidInput as exc:
        raise InvalidInput(f"{source}: {exc}") from None
    return spec, chunk


def load_config(path: str | Path) -> tuple[SweepSpec, int | None]:
    """Read a sweep configuration file (see the module docstring).

    Raises:
        InvalidInput: the file is missing, is not YAML, or describes no valid sweep.
    """
    p = Path(path)
    try:
        text = read_head(p)
    except OSError as exc:
        raise InvalidInput(f"{p}: cannot read the sweep configuration ({exc.strerror})") from None
    try:
        config = load_yaml(text)
    except YamlRefused as exc:
        raise InvalidInput(f"{p}: not valid YAML ({exc})") from None
    return spec_from_config(mechanism_beside(config, p.parent), str(p))
