"""What a dimensional synthesis optimises, checked in full before any work: :class:`Problem`.

A *design* is one point of a sweep's parameter space: values of the design variables, each
setting a builder parameter (or all entries of a list parameter, ``repeat``). At a design, the
mechanism is built and evaluated over the *task region* (a pose grid, or the poses of a
trajectory as a grid of one axis) by the sweep's metrics (:mod:`plm_pin.sweep.metrics`).

Constraints form a ranked hierarchy, cheapest first (:data:`CONSTRAINTS`): the builder accepts
the parameters, then the region is reached in the reference working mode, clear of
singularities by a margin, within the joint limits, free of self-collision, with the actuator
forces within a limit under the loads, and stiffer than a minimum. A design is evaluated down
the hierarchy and stopped at the first constraint it violates, so an unreachable design never
pays for its statics. Objectives (:data:`OBJECTIVES`) reduce a sweep variable over the region.
"""

from __future__ import annotations

import dataclasses
import hashlib
import inspect
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._text import short
from .._version import __version__
from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput
from ..loading import resolve_builder
from ..models.registry import Builder, builder_parameters
from ..sweep import METRICS, SweepSpec, make_spec
from ..sweep.spec import PosesArg, Value

FORMAT = "plm-pin-optimize/1"
"""Format of an optimisation's canonical description (and of its checkpoint manifest)."""

REDUCTIONS: dict[str, Callable[[np.ndarray], float]] = {
    "min": lambda a: float(np.nanmin(a)) if np.any(np.isfinite(a)) else math.nan,
    "max": lambda a: float(np.nanmax(a)) if np.any(~np.isnan(a)) else math.nan,
    "mean": lambda a: float(np.nanmean(a)) if np.any(~np.isnan(a)) else math.nan,
    "rms": lambda a: float(np.sqrt(np.nanmean(np.square(a)))) if np.any(~np.isnan(a)) else math.nan,
    "inverse_mean": lambda a: float(np.mean(np.nan_to_num(1.0 / np.asarray(a, dtype=float), nan=0.0))),
}
"""How a variable is reduced over the task region (NaN, the unreached poses, are skipped; ``inverse_mean``
counts them as 0: the global conditioning index of Gosselin and Angeles 1991 on a grid)."""

SENSES = ("min", "max")
"""Whether an objective is minimised or maximised."""


@dataclass(frozen=True)
class Constraint:
    """One level of the constraint hierarchy.

    Attributes:
        name: its name, as given in ``constraints={name: limit}``.
        summary: what it requires, in words (``limit`` is the value given).
        metric: the sweep metric it reads.
        unit: unit of the limit.
        measure: the number the limit is compared with, from the metric's values over the region.
        sense: ``"min"`` when the measure must be at least the limit, ``"max"`` at most.
    """

    name: str
    summary: str
    metric: str
    unit: str
    measure: Callable[[Mapping[str, np.ndarray]], float]
    sense: str

    def violation(self, measure: float, limit: float) -> float:
        """How far ``measure`` misses ``limit``, relative (0: met; NaN and inf count as 1)."""
        if not math.isfinite(measure):
            return 1.0
        gap = limit - measure if self.sense == "min" else measure - limit
        return max(0.0, gap / abs(limit)) if limit != 0.0 else max(0.0, gap)


def _fraction(name: str) -> Callable[[Mapping[str, np.ndarray]], float]:
    return lambda values: float(np.mean(values[name]))


CONSTRAINTS: dict[str, Constraint] = {
    c.name: c
    for c in (
        Constraint("reach", "at least this fraction of the region reached in one working mode", "reachable",
                   "-", _fraction("reachable"), "min"),
        Constraint("singularity_margin", "smallest singularity margin over the region at least this",
                   "singularity", "-", lambda v: REDUCTIONS["min"](v["singularity_margin"]), "min"),
        Constraint("joint_limits", "at least this fraction of the region within the joint limits",
                   "within_limits", "-", _fraction("within_limits"), "min"),
        Constraint("collision", "at least this fraction of the region free of self-collision",
                   "collision_free", "-", _fraction("collision_free"), "min"),
        Constraint("max_force", "peak actuator force over the region and the loads at most this",
                   "peak_force", "N (N m)", lambda v: REDUCTIONS["max"](v["peak_force"]), "max"),
        Constraint("min_stiffness", "smallest translational stiffness over the region at least this",
                   "stiffness", "N/m", lambda v: REDUCTIONS["min"](v["min_translational_stiffness"]), "min"),
    )
}  # fmt: skip
"""The constraints, in the order of the hierarchy (cheapest first); ``bounds`` and ``build`` precede them."""

OBJECTIVES: dict[str, tuple[str, str, str]] = {
    "gci": ("condition_number", "inverse_mean", "max"),
    "min_manipulability": ("manipulability", "min", "max"),
    "workspace": ("reachable", "area", "max"),
    "stiffness": ("min_translational_stiffness", "min", "max"),
    "peak_force": ("peak_force", "max", "min"),
    "rms_force": ("peak_force", "rms", "min"),
    "moving_mass": ("moving_mass", "sum", "min"),
}
"""Named objectives: (sweep variable, reduction, sense). ``workspace`` is the reached fraction of the
region times its measure (area or volume of the varied axes); ``moving_mass`` the mass of every body
that moves [kg]."""


@dataclass(frozen=True)
class DesignVariable:
    """A design variable: a builder parameter varied between bounds.

    Attributes:
        name: the builder parameter it sets.
        lower: lower bound (SI units).
        upper: upper bound.
        repeat: None: the parameter is this number; n: the parameter is a list of n equal entries.
    """

    name: str
    lower: float
    upper: float
    repeat: int | None = None

    def value(self, x: float) -> Value:
        """The builder-parameter value at ``x``."""
        return float(x) if self.repeat is None else (float(x),) * self.repeat


@dataclass(frozen=True)
class Objective:
    """One objective.

    Attributes:
        name: its name (a key of :data:`OBJECTIVES`, or the variable of a custom one).
        variable: the sweep variable it reduces (``moving_mass``: the mechanism's moving mass).
        reduce: a key of :data:`REDUCTIONS` (``sum`` for the moving mass).
        sense: ``"min"`` or ``"max"``.
        weight: its weight in the weighted sum a single-objective search minimises.
    """

    name: str
    variable: str
    reduce: str
    sense: str
    weight: float = 1.0

    @property
    def sign(self) -> float:
        """+1 when minimised, -1 when maximised: the search minimises ``sign * value``."""
        return 1.0 if self.sense == "min" else -1.0


def variable_metrics() -> dict[str, str]:
    """Sweep variable name -> the metric that computes it."""
    return {v.name: m for m, metric in METRICS.items() for v in metric.variables}


@dataclass(frozen=True)
class Problem:
    """A dimensional synthesis, checked (build one with :func:`make_problem`).

    Attributes:
        spec: the sweep evaluating one design: the mechanism, the fixed builder parameters
            (``base``: the starting design), the task region, the metrics the constraints and
            objectives need, and their options.
        variables: the design variables, in order.
        constraints: constraint name -> limit, in the order of the hierarchy.
        objectives: the objectives, in order.
        start: the starting design: each variable's value in ``base``, else the preset's, else the
            builder's default, else mid-bounds (the first entry of a list parameter).
    """

    spec: SweepSpec
    variables: tuple[DesignVariable, ...]
    constraints: Mapping[str, float]
    objectives: tuple[Objective, ...]
    start: tuple[float, ...]

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the design variables."""
        return tuple(v.name for v in self.variables)

    @property
    def bounds(self) -> list[tuple[float, float]]:
        """(lower, upper) of every variable."""
        return [(v.lower, v.upper) for v in self.variables]

    @property
    def levels(self) -> tuple[str, ...]:
        """The constraint hierarchy as evaluated: ``bounds``, ``build``, then the constraints given."""
        return ("bounds", "build", *self.constraints)

    def design_spec(self, x: Sequence[float]) -> SweepSpec:
        """The sweep spec of the design ``x`` (its single point is the design)."""
        params = {v.name: v.value(xi) for v, xi in zip(self.variables, x, strict=True)}
        return dataclasses.replace(self.spec, base={**self.spec.base, **params}, built=None)

    def measure(self) -> float:
        """Measure of the region's varied axes (length, area or volume) [m^k rad^j]."""
        return math.prod(float(np.ptp(v)) or 1.0 for v in self.spec.values)

    def to_dict(self) -> dict[str, object]:
        """Canonical plain data: everything that decides the results."""
        return {
            "format": FORMAT,
            "plm_pin": __version__,
            "sweep": self.spec.to_dict(),
            "variables": [dataclasses.asdict(v) for v in self.variables],
            "constraints": dict(self.constraints),
            "objectives": [dataclasses.asdict(o) for o in self.objectives],
        }

    def key(self) -> str:
        """SHA-256 of :meth:`to_dict` as canonical JSON."""
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"), allow_nan=False)
        return hashlib.sha256(text.encode()).hexdigest()


def _number(where: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InvalidInput(f"{where} must be a finite number, got {short(value)}")
    return float(value)


def _variables(variables: Any, valid: tuple[str, ...], label: str) -> tuple[DesignVariable, ...]:
    if not isinstance(variables, Mapping) or not variables:
        raise InvalidInput(
            "variables must map builder parameters to bounds [lower, upper] or {bounds: [lower, upper], "
            f"repeat: n}}, got {short(variables)}"
        )
    out = []
    for name, raw in variables.items():
        if name not in valid:
            raise InvalidInput(
                f"variables: unknown parameter {short(name)} of {label}; its parameters are {list(valid)}"
            )
        spec = raw if isinstance(raw, Mapping) else {"bounds": raw}
        unknown = [k for k in spec if k not in ("bounds", "repeat")]
        bounds = spec.get("bounds")
        if unknown or not isinstance(bounds, Sequence) or isinstance(bounds, str) or len(bounds) != 2:
            raise InvalidInput(
                f"variables.{name}: give [lower, upper] or {{bounds: [lower, upper], repeat: n}}, "
                f"got {short(raw)}"
            )
        lower, upper = (_number(f"variables.{name} bound", b) for b in bounds)
        if not lower < upper:
            raise InvalidInput(f"variables.{name}: lower bound {lower} is not below upper bound {upper}")
        repeat = spec.get("repeat")
        if repeat is not None and (isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1):
            raise InvalidInput(
                f"variables.{name}: repeat must be a positive number of entries, got {short(repeat)}"
            )
        out.append(DesignVariable(str(name), lower, upper, repeat))
    return tuple(out)


def _constraints(constraints: Any) -> dict[str, float]:
    given = dict(constraints or {})
    for name in given:
        if name not in CONSTRAINTS:
            raise InvalidInput(f"unknown constraint {short(name)}; constraints are {list(CONSTRAINTS)}")
    given.setdefault("reach", 1.0)
    return {name: _number(f"constraint {name!r}", given[name]) for name in CONSTRAINTS if name in given}


def _objective(raw: Any) -> Objective:
    if isinstance(raw, str):
        raw = {"name": raw}
    if not isinstance(raw, Mapping):
        raise InvalidInput(f"an objective is a name among {list(OBJECTIVES)} or a mapping, got {short(raw)}")
    unknown = [k for k in raw if k not in ("name", "metric", "reduce", "sense", "weight")]
    if unknown:
        raise InvalidInput(
            f"objective {short(dict(raw))}: unknown key(s) {unknown}; keys are name, metric, "
            "reduce, sense, weight"
        )
    weight = _number("objective weight", raw.get("weight", 1.0))
    if "metric" in raw:
        variable = raw["metric"]
        if variable not in variable_metrics():
            raise InvalidInput(
                f"objective metric {short(variable)} is no sweep variable; they are "
                f"{sorted(variable_metrics())}"
            )
        reduce, sense = raw.get("reduce", "mean"), raw.get("sense", "max")
        if reduce not in REDUCTIONS:
            raise InvalidInput(f"objective reduce {short(reduce)} is not among {list(REDUCTIONS)}")
        if sense not in SENSES:
            raise InvalidInput(f"objective sense {short(sense)} is not among {list(SENSES)}")
        return Objective(str(raw.get("name", variable)), str(variable), str(reduce), str(sense), weight)
    name = raw.get("name")
    if name not in OBJECTIVES:
        raise InvalidInput(
            f"unknown objective {short(name)}; objectives are {list(OBJECTIVES)}, or give "
            "{metric: <sweep variable>, reduce, sense}"
        )
    variable, reduce, sense = OBJECTIVES[name]
    return Objective(str(name), variable, reduce, raw.get("sense", sense), weight)


def make_problem(
    mechanism: str | Builder,
    variables: Mapping[str, Any],
    poses: PosesArg,
    objectives: Sequence[Any] = ("gci",),
    *,
    constraints: Mapping[str, float] | None = None,
    base: Mapping[str, Any] | None = None,
    pose: Sequence[float] | None = None,
    options: Mapping[str, Any] | None = None,
) -> Problem:
    """Check a dimensional synthesis and normalise it (see :func:`plm_pin.optimize.optimize`).

    Raises:
        InvalidInput: an unknown parameter, constraint, objective, metric or option (the message lists
            the valid ones), bounds not ordered, a Mechanism given as it is (it has no parameters),
            or anything :func:`plm_pin.sweep.make_spec` refuses.
    """
    if isinstance(mechanism, Mechanism):
        raise InvalidInput(
            f"{mechanism.name} is a Mechanism, which has no parameters to optimise: give its preset, builder "
            "or description path"
        )
    if isinstance(objectives, (str, Mapping)) or not isinstance(objectives, Sequence) or not objectives:
        raise InvalidInput(f"objectives must be a non-empty list, got {short(objectives)}")
    checked_objectives = tuple(_objective(o) for o in objectives)
    names = [o.name for o in checked_objectives]
    if len(set(names)) != len(names):
        raise InvalidInput(f"objectives are repeated: {names}")
    checked_constraints = _constraints(constraints)
    by_variable = variable_metrics()
    metrics = [CONSTRAINTS[c].metric for c in checked_constraints]
    metrics += [by_variable[o.variable] for o in checked_objectives if o.variable != "moving_mass"]
    needed = [m for m in METRICS if m in metrics]  # the sweep's order, each once
    spec = make_spec(mechanism, None, poses, needed, base=base, pose=pose, options=options)
    builder, preset, label = resolve_builder(mechanism)
    checked_variables = _variables(variables, builder_parameters(builder), label)
    defaults = {
        n: p.default for n, p in inspect.signature(builder).parameters.items() if p.default is not p.empty
    }
    known = {**defaults, **preset, **spec.base}
    start = []
    for v in checked_variables:
        given = known.get(v.name)
        x = given[0] if isinstance(given, (tuple, list)) and given else given
        ok = isinstance(x, (int, float)) and not isinstance(x, bool)
        start.append(float(x) if ok else 0.5 * (v.lower + v.upper))  # type: ignore[arg-type]
    return Problem(spec, checked_variables, checked_constraints, checked_objectives, tuple(start))
