"""The optimisation configuration file (YAML) read by ``plm-pin optimize CONFIG.yaml``.

.. code-block:: yaml

    format: plm-pin-optimize/1       # optional; checked when given
    mechanism: harada2011_3d4m       # a preset, a description path, or a builder "package.module:function"
    base: {reference_pose: [0.0, 0.08, 0.0]}   # fixed builder parameters (optional)
    variables:                       # builder parameter -> [lower, upper] or {bounds, repeat, unit}
      half_plate: [0.02, 0.08]
      rod_lengths: {bounds: [100, 200], unit: mm, repeat: 4}
    poses:                           # the task region, as a sweep's poses
      x: {linspace: [-0.03, 0.03, 20]}
      y: {linspace: [0.06, 0.10, 20]}
    pose: [0.0, 0.08, 0.0]           # the other coordinates (optional)
    constraints: {reach: 1.0, singularity_margin: 0.01}
    objectives: [gci, {name: moving_mass, weight: 0.1}]
    options: {}                      # sweep metric options (optional)
    search: {method: de, generations: 50, population: 10, seed: 0}

Lists of values take the forms of a sweep configuration (:mod:`plm_pin.sweep.config`); a
variable's ``unit`` (``mm``, ``deg``) converts its bounds to SI. A builder named ``module:function``
is imported: a configuration file is trusted like code.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .._text import short
from .._yaml import YamlRefused, load_yaml, read_head
from ..exceptions import InvalidInput
from ..sweep.config import UNITS, check_header, import_mechanism, mechanism_beside, values_of
from .problem import FORMAT, Problem, make_problem
from .search import search_settings

KEYS = (
    "format", "mechanism", "base", "variables", "poses", "pose",
    "constraints", "objectives", "options", "search",
)  # fmt: skip
"""Keys of a configuration file."""

SEARCH = ("method", "generations", "population", "seed", "tol")
"""Keys of its ``search`` entry (the arguments of :func:`~plm_pin.optimize.run_problem`)."""


def _variables(raw: Any) -> Any:
    if not isinstance(raw, Mapping):
        return raw
    out = {}
    for name, v in raw.items():
        if isinstance(v, Mapping) and "unit" in v:
            unit = v["unit"]
            if not isinstance(unit, str) or unit not in UNITS:
                raise InvalidInput(f"variables.{name}: unknown unit {short(unit)}; units are {list(UNITS)}")
            bounds = v.get("bounds")
            if not isinstance(bounds, list) or not all(isinstance(b, (int, float)) for b in bounds):
                raise InvalidInput(f"variables.{name}: bounds must be two numbers, got {short(bounds)}")
            v = {k: x for k, x in v.items() if k != "unit"} | {"bounds": [b * UNITS[unit] for b in bounds]}
        out[name] = v
    return out


def problem_from_config(config: Any, source: str = "<config>") -> tuple[Problem, dict[str, Any]]:
    """The problem a configuration mapping describes, and its search settings (checked, defaults filled in).

    Raises:
        InvalidInput: an unknown key, a malformed entry, or anything :func:`make_problem` refuses;
            the message starts with ``source``.
    """
    try:
        check_header(
            config, "an optimisation configuration", KEYS, FORMAT, ("mechanism", "variables", "poses")
        )
        search = config.get("search") or {}
        if not isinstance(search, Mapping) or any(k not in SEARCH for k in search):
            raise InvalidInput(f"search must be a mapping of {list(SEARCH)}, got {short(search)}")
        poses = config["poses"]
        if isinstance(poses, Mapping):
            poses = {k: values_of(f"poses.{k}", v) for k, v in poses.items()}
        settings = search_settings(**search)
        problem = make_problem(
            import_mechanism(config["mechanism"]),
            _variables(config["variables"]),
            poses,
            config.get("objectives") or ["gci"],
            constraints=config.get("constraints"),
            base=config.get("base"),
            pose=config.get("pose"),
            options=config.get("options"),
        )
    except InvalidInput as exc:
        raise InvalidInput(f"{source}: {exc}") from None
    return problem, settings


def load_config(path: str | Path) -> tuple[Problem, dict[str, Any]]:
    """Read an optimisation configuration file (see the module docstring).

    Raises:
        InvalidInput: the file is missing, is not YAML, or describes no valid optimisation.
    """
    p = Path(path)
    try:
        text = read_head(p)
    except OSError as exc:
        raise InvalidInput(f"{p}: cannot read the optimisation configuration ({exc.strerror})") from None
    try:
        config = load_yaml(text)
    except YamlRefused as exc:
        raise InvalidInput(f"{p}: not valid YAML ({exc})") from None
    return problem_from_config(mechanism_beside(config, p.parent), str(p))
