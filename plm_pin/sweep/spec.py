"""What a design sweep computes, checked in full before any work starts: :class:`SweepSpec`.

A sweep varies the parameters of a mechanism builder (a grid, or a list of samples) and,
at every parameter point, evaluates metrics over a grid of task poses; or it evaluates them
over the poses of one :class:`~plm_pin.Mechanism` given as it is (e.g. from :func:`plm_pin.load`).
The spec holds everything that decides the numbers, normalised (SI units, radians, floats
as given), so that its :meth:`SweepSpec.key` identifies the results: a checkpoint store
refuses another sweep's spec (:mod:`plm_pin.sweep.store`). The mechanism enters the key by
its label and by the :func:`mechanism_digest` of its first parameter point, so a resumed
sweep whose mechanism (file, builder or object) changed is refused. How the work is split
and where it runs is not part of it (results do not depend on it).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import mapping, real_numbers
from .._text import short
from .._version import __version__
from ..core.mechanism import Mechanism
from ..description.sidecar import TASK_DOFS
from ..exceptions import InvalidInput, PlmError
from ..loading import build_mechanism, resolve_builder
from ..models.registry import Builder, builder_parameters
from .metrics import METRICS, PoseGrid, Variable, check_options, grid_metrics

Scalar = float | int | str
Value = Scalar | tuple[Scalar, ...]
"""A builder-parameter value: a number, a name, or a tuple of them (e.g. ``rod_lengths``)."""

ParametersArg = Mapping[str, Sequence[Any]] | Sequence[Mapping[str, Any]] | None
"""Varied builder parameters as given: a grid ``{name: values}`` or samples ``[{name: value}, ...]``."""

PosesArg = Mapping[str, ArrayLike] | None
"""The pose grid as given: ``{task coordinate: values}`` [m, rad]."""

RESERVED = ("sample", "failed")
"""Names of the result that no parameter may take."""

FORMAT = "plm-pin-sweep/1"
"""Format of a sweep's canonical description (and of its checkpoint manifest)."""


def _scalar(where: str, v: Any) -> Scalar:
    if isinstance(v, (bool, np.bool_)):
        raise InvalidInput(f"{where}: {short(v)} is a boolean; give a number, a name or a list of them")
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        if not math.isfinite(v):
            raise InvalidInput(f"{where} holds a non-finite value {short(float(v))}")
        return float(v)
    if isinstance(v, str):
        return v
    raise InvalidInput(f"{where}: {short(v)} is not a number, a name or a list of them")


def normalise_value(where: str, v: Any) -> Value:
    """A builder-parameter value checked and normalised: numbers finite, lists made tuples.

    Raises:
        InvalidInput: a non-finite number, an empty list, or another type.
    """
    if isinstance(v, (list, tuple, np.ndarray)):
        items = list(np.asarray(v).tolist()) if isinstance(v, np.ndarray) else list(v)
        if not items:
            raise InvalidInput(f"{where}: an empty list is not a parameter value")
        return tuple(_scalar(where, item) for item in items)
    return _scalar(where, v)


def mechanism_digest(mech: Mechanism) -> str:
    """SHA-256 of what decides a mechanism's results: its Pinocchio model and its sidecar.

    The model is taken as Pinocchio serialises it (``model.saveToString()``: every joint,
    inertia, frame and limit to the last bit), once its idle gauges are in it; the sidecar as
    canonical JSON. Equal mechanisms loaded in different processes get equal digests; a
    Pinocchio upgrade may change them (a resumed sweep is then refused, never mixed).
    """
    mech.idle_gauges  # noqa: B018 - the model is final (gauge frames added) before it is hashed
    h = hashlib.sha256(mech.model.saveToString().encode())
    h.update(json.dumps(mech.sidecar.to_dict(), sort_keys=True, allow_nan=False).encode())
    return h.hexdigest()


def value_label(v: Value) -> str:
    """Text naming a value in a result's coordinate (tuples as ``(0.24, 0.17)``)."""
    if isinstance(v, tuple):
        return "(" + ", ".join(str(x) for x in v) + ")"
    return str(v)


@dataclass(frozen=True)
class ParameterSpace:
    """The builder parameters a sweep varies: a grid (Cartesian product) or a list of samples.

    Attributes:
        names: the varied parameters, in the order given.
        values: grid: one tuple of values per name; samples: one tuple per sample, aligned with ``names``.
        samples: whether the space is a list of samples (dimension ``sample``) rather than a grid.
    """

    names: tuple[str, ...]
    values: tuple[tuple[Value, ...], ...]
    samples: bool = False

    @property
    def shape(self) -> tuple[int, ...]:
        """Points along each dimension (``()`` when nothing is varied: one point)."""
        return (len(self.values),) if self.samples else tuple(len(v) for v in self.values)

    @property
    def dims(self) -> tuple[str, ...]:
        """Dimension names of the result: the parameters of a grid, or ``("sample",)``."""
        return ("sample",) if self.samples else self.names

    @property
    def size(self) -> int:
        """Number of parameter points."""
        return math.prod(self.shape)

    def point(self, index: int) -> dict[str, Value]:
        """The parameters of the point with flat (row-major) ``index``."""
        if self.samples:
            return dict(zip(self.names, self.values[index], strict=True))
        at = np.unravel_index(index, self.shape) if self.shape else ()
        return {name: self.values[k][int(i)] for k, (name, i) in enumerate(zip(self.names, at, strict=True))}

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON (tuples as lists)."""

        def plain(v: Value) -> object:
            return list(v) if isinstance(v, tuple) else v

        if self.samples:
            return {
                "samples": [{n: plain(v) for n, v in zip(self.names, s, strict=True)} for s in self.values]
            }
        return {"grid": {n: [plain(v) for v in vs] for n, vs in zip(self.names, self.values, strict=True)}}


def _parameter_space(parameters: ParametersArg, valid: tuple[str, ...], label: str) -> ParameterSpace:
    def check_name(name: Any) -> str:
        if name not in valid:
            raise InvalidInput(
                f"unknown parameter {short(name)} of {label}; its parameters are {list(valid)}"
            )
        return str(name)

    if parameters is None:
        return ParameterSpace((), ())
    if isinstance(parameters, Mapping):
        names = tuple(check_name(n) for n in parameters)
        values = []
        for name in names:
            raw = parameters[name]
            if isinstance(raw, (str, bytes)) or not isinstance(raw, (Sequence, np.ndarray)):
                raise InvalidInput(f"parameter {short(name)}: give a list of values, got {short(raw)}")
            if len(raw) == 0:
                raise InvalidInput(f"parameter {short(name)} has no values: an empty grid")
            values.append(tuple(normalise_value(f"parameter {short(name)}", v) for v in raw))
        return ParameterSpace(names, tuple(values))
    if isinstance(parameters, Sequence) and not isinstance(parameters, (str, bytes)):
        if not parameters:
            raise InvalidInput("parameters: the list of samples is empty")
        if not all(isinstance(s, Mapping) for s in parameters):
            raise InvalidInput(
                "parameters: give a mapping name -> values (a grid) or a list of mappings (samples)"
            )
        names = tuple(check_name(n) for n in parameters[0])
        rows = []
        for i, sample in enumerate(parameters):
            if tuple(sample) != names:
                raise InvalidInput(
                    f"parameters: sample {i} sets {list(sample)}; every sample must set {list(names)}, "
                    "in order"
                )
            rows.append(
                tuple(normalise_value(f"parameter {short(n)} of sample {i}", sample[n]) for n in names)
            )
        return ParameterSpace(names, tuple(rows), samples=True)
    raise InvalidInput(
        "parameters must be a mapping name -> values (a grid) or a list of mappings (samples), "
        f"got {short(parameters)}"
    )


def _pose_axes(poses: PosesArg) -> tuple[tuple[str, ...], tuple[np.ndarray, ...]]:
    if not isinstance(poses, Mapping) or not poses:
        raise InvalidInput(
            f"poses must map task coordinates among {list(TASK_DOFS)} to their values, got {short(poses)}"
        )
    axes, values = [], []
    for axis, raw in poses.items():
        if axis not in TASK_DOFS:
            raise InvalidInput(
                f"poses: unknown task coordinate {short(axis)}; coordinates are {list(TASK_DOFS)}"
            )
        try:
            arr = np.array(raw, dtype=float)
        except (TypeError, ValueError):
            raise InvalidInput(f"poses: values of {short(axis)} must be numbers, got {short(raw)}") from None
        if arr.ndim != 1 or arr.size == 0:
            raise InvalidInput(
                f"poses: values of {short(axis)} must be a non-empty 1-D list, got shape {arr.shape}"
            )
        if not np.all(np.isfinite(arr)):
            raise InvalidInput(
                f"poses: values of {short(axis)} hold non-finite entries {arr[~np.isfinite(arr)].tolist()}"
            )
        arr.setflags(write=False)
        axes.append(str(axis))
        values.append(arr)
    return tuple(axes), tuple(values)


@dataclass(frozen=True)
class SweepSpec:
    """A design sweep, checked and normalised (build one with :func:`make_spec`).

    Attributes:
        mechanism: the preset name, the builder callable, the description path, or the
            :class:`~plm_pin.Mechanism` itself.
        label: the preset name, the builder's ``module:qualname``, the path, or the
            Mechanism's name.
        base: fixed builder parameters given on top of the preset's (SI units).
        parameters: the varied builder parameters.
        axes: the pose grid's task coordinates, in order.
        values: their values [m or rad], one read-only array per axis.
        pose: task pose giving the other coordinates [m, rad], or None (each variant's
            reference pose).
        metrics: the metrics asked for, in order.
        options: every option of those metrics, defaults filled in.
        digest: :func:`mechanism_digest` of the first parameter point's mechanism (None when
            it cannot be built: that point fails).
        built: the mechanism of the only parameter point, held by the spec and shipped with it
            to the workers, never built there: the Mechanism given, or the one a single-point
            sweep built on the client for its checks. None for sweeps of several points (each
            worker builds its own points, see :mod:`plm_pin.sweep.execution`).
        source: the first point's provenance (:attr:`plm_pin.Mechanism.source`: a paper, or the
            file it was loaded from), recorded with the results; not part of :meth:`key`.
    """

    mechanism: str | Builder | Mechanism
    label: str
    base: Mapping[str, Value]
    parameters: ParameterSpace
    axes: tuple[str, ...]
    values: tuple[np.ndarray, ...]
    pose: tuple[float, ...] | None
    metrics: tuple[str, ...]
    options: Mapping[str, Any] = field(default_factory=dict)
    digest: str | None = None
    built: Mechanism | None = field(default=None, compare=False, repr=False)
    source: str = field(default="", compare=False)

    @property
    def pose_shape(self) -> tuple[int, ...]:
        """Points along each pose axis."""
        return tuple(len(v) for v in self.values)

    @property
    def n_poses(self) -> int:
        """Poses per parameter point."""
        return math.prod(self.pose_shape)

    @property
    def n_points(self) -> int:
        """Parameter points."""
        return self.parameters.size

    @property
    def reduced_over(self) -> tuple[str, ...]:
        """Pose axes the reduced metrics run over (the option ``over``, default all)."""
        over = self.options.get("over")
        return self.axes if over is None else tuple(over)

    def pose_grid(self) -> PoseGrid:
        """The pose grid and options every parameter point's metrics share."""
        return PoseGrid(
            self.axes, self.values, self.pose, self.reduced_over, self.options, grid_metrics(self.metrics)
        )

    def variables(self) -> tuple[Variable, ...]:
        """The result variables of the metrics, in order."""
        return tuple(v for m in self.metrics for v in METRICS[m].variables)

    def variable_axes(self, variable: Variable) -> tuple[str, ...]:
        """The pose axes a variable keeps."""
        if variable.axes == "reduced":
            return tuple(a for a in self.axes if a not in self.reduced_over)
        if variable.axes == "line":
            return tuple(a for a in self.axes if a != self.options["rotation_axis"])
        return self.axes

    def variable_shape(self, variable: Variable) -> tuple[int, ...]:
        """Shape of a variable at one parameter point."""
        return tuple(len(self.values[self.axes.index(a)]) for a in self.variable_axes(variable))

    def point_parameters(self, index: int) -> dict[str, Value]:
        """Builder parameters of a parameter point: ``base`` and its values (preset defaults aside)."""
        return {**self.base, **self.parameters.point(index)}

    def build(self, index: int) -> Mechanism:
        """The mechanism at a parameter point: :attr:`built`, else :func:`plm_pin.build_mechanism`."""
        if self.built is not None:
            return self.built
        assert not isinstance(self.mechanism, Mechanism)  # make_spec sets built for a Mechanism
        stem = self.label.rsplit(":", 1)[-1]
        return build_mechanism(self.mechanism, self.point_parameters(index), name=f"{stem}_p{index}")

    def to_dict(self) -> dict[str, object]:
        """Canonical plain data: everything that decides the results, nothing about how they are computed."""
        options = {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.options.items()}
        if isinstance(options.get("wrenches"), list):
            options["wrenches"] = [list(w) for w in options["wrenches"]]
        return {
            "format": FORMAT,
            "plm_pin": __version__,
            "mechanism": self.label,
            "digest": self.digest,
            "base": {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.base.items()},
            "parameters": self.parameters.to_dict(),
            "poses": {a: v.tolist() for a, v in zip(self.axes, self.values, strict=True)},
            "pose": None if self.pose is None else list(self.pose),
            "metrics": list(self.metrics),
            "options": options,
        }

    def key(self) -> str:
        """SHA-256 of :meth:`to_dict` as canonical JSON: equal keys, equal results."""
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"), allow_nan=False)
        return hashlib.sha256(text.encode()).hexdigest()


def make_spec(
    mechanism: str | Builder | Mechanism,
    parameters: ParametersArg = None,
    poses: PosesArg = None,
    metrics: Sequence[str] = ("manipulability",),
    *,
    base: Mapping[str, Any] | None = None,
    pose: Sequence[float] | None = None,
    options: Mapping[str, Any] | None = None,
) -> SweepSpec:
    """Check a sweep's arguments and normalise them (see :func:`plm_pin.sweep.sweep` for their meaning).

    The mechanism at the first parameter point is built to check the pose axes, the fixed
    pose and the wrenches against its task, and to take its :func:`mechanism_digest`; if it
    cannot be built, that point is reported by the sweep like any other failure. A
    single-point sweep keeps that mechanism (:attr:`SweepSpec.built`) rather than building
    it again.

    Raises:
        InvalidInput: an unknown preset, parameter, metric, option or task coordinate (the
            message lists the valid ones), an empty grid, a non-finite value, a value of
            the wrong shape, or parameters (or ``base``) given with a Mechanism.
    """
    if isinstance(mechanism, Mechanism):
        if parameters or base:
            raise InvalidInput(
                f"parameters and base are builder parameters; {mechanism.name} is a Mechanism, which has "
                "none: sweep its poses alone, or give its preset, builder or description path to vary them"
            )
        valid: tuple[str, ...] = ()
        label = mechanism.name
    else:
        builder, _, label = resolve_builder(mechanism)
        valid = builder_parameters(builder)
    fixed = {}
    for name, v in mapping(base or {}, "base", "builder parameter names to values").items():
        if name not in valid:
            raise InvalidInput(
                f"unknown parameter {short(name)} of {label}; its parameters are {list(valid)}"
            )
        fixed[str(name)] = normalise_value(f"base parameter {short(name)}", v)
    space = _parameter_space(parameters, valid, label)
    both = [n for n in space.names if n in fixed]
    if both:
        raise InvalidInput(f"parameters {both} are both varied and fixed (base); give each once")
    if isinstance(metrics, str) or not isinstance(metrics, Sequence) or not metrics:
        raise InvalidInput(f"metrics must be a non-empty list among {list(METRICS)}, got {short(metrics)}")
    for m in metrics:
        if not isinstance(m, str) or m not in METRICS:
            raise InvalidInput(f"unknown metric {short(m)}; metrics are {list(METRICS)}")
    if len(set(metrics)) != len(metrics):
        raise InvalidInput(f"metrics are repeated: {list(metrics)}")
    axes, values = _pose_axes(poses)
    taken = {*axes, *(v.name for m in metrics for v in METRICS[m].variables), *RESERVED}
    clash = [n for n in space.names if n in taken]
    if clash:
        raise InvalidInput(
            f"parameters {clash} share their names with pose axes or result variables {sorted(taken)}; "
            "they would be ambiguous dimensions of the result"
        )
    fixed_pose = None
    if pose is not None:
        arr = np.asarray(real_numbers(pose, "pose"), dtype=float)
        if arr.ndim != 1 or not np.all(np.isfinite(arr)):
            raise InvalidInput(
                f"pose must be a 1-D list of finite task coordinates [m, rad], got {short(pose)}"
            )
        fixed_pose = tuple(float(v) for v in arr)
    checked = check_options(tuple(metrics), dict(mapping(options or {}, "options", "option names to values")))
    held = mechanism if isinstance(mechanism, Mechanism) else None
    spec = SweepSpec(
        mechanism, label, fixed, space, axes, values, fixed_pose, tuple(metrics), checked, built=held
    )
    _check_axes_options(spec)
    first = _first_point(spec)
    if first is None:
        return spec
    _check_against(spec, first)
    return dataclasses.replace(
        spec,
        digest=mechanism_digest(first),
        built=first if spec.n_points == 1 else None,
        source=first.source,
    )


def _check_axes_options(spec: SweepSpec) -> None:
    options = spec.options
    if "rotation_axis" in options:
        axis = options["rotation_axis"]
        if axis not in spec.axes:
            raise InvalidInput(
                f"the orientation range turns {axis!r} (option rotation_axis), which the poses do not vary; "
                f"pose axes are {list(spec.axes)}"
            )
        ts = spec.values[spec.axes.index(axis)]
        if ts.size < 2 or np.any(np.diff(ts) <= 0.0):
            raise InvalidInput(
                f"poses: values of the rotation axis {short(axis)} must increase, at least 2 of them"
            )
    over = options.get("over")
    if over is not None:
        unknown = [a for a in over if a not in spec.axes]
        if unknown or len(set(over)) != len(over):
            raise InvalidInput(
                f"option 'over' must name distinct pose axes among {list(spec.axes)}, got {list(over)}"
            )


def _first_point(spec: SweepSpec) -> Mechanism | None:
    """The mechanism of the first parameter point, or None when it cannot be built."""
    try:
        return spec.build(0)
    except PlmError:
        return None  # reported as that point's failure
    except (TypeError, ValueError):
        return None


def _check_against(spec: SweepSpec, mech: Mechanism) -> None:
    """Check the pose axes, the fixed pose and the wrenches against ``mech``'s task."""
    dofs = mech.sidecar.task.dofs if mech.sidecar.task is not None else ()
    unknown = [a for a in spec.axes if a not in dofs]
    if unknown:
        raise InvalidInput(
            f"poses: {mech.name} has no task coordinate {unknown}; its task coordinates are {list(dofs)}"
        )
    if spec.pose is not None and len(spec.pose) != len(dofs):
        raise InvalidInput(f"pose must hold {len(dofs)} task coordinates {list(dofs)}, got {list(spec.pose)}")
    for w in spec.options.get("wrenches") or ():
        if len(w) not in (6, len(dofs)):
            raise InvalidInput(
                "option 'wrenches': each wrench holds 6 values or one per task coordinate "
                f"{list(dofs)}, got {list(w)}"
            )
