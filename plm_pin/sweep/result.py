"""The result of a sweep: a labelled xarray Dataset with units, what was computed, and what failed.

Dimensions: the varied parameters (one per parameter of a grid, or ``sample`` for a list
of samples), then the pose axes a variable keeps. Coordinates: the parameter values
(numbers, or text such as ``(1, 2, 4)`` for tuple-valued parameters) and the pose values
[m or rad] with their ``units``. Every variable has ``units`` and ``description``
attributes (codes also ``flag_values`` and ``flag_meanings``); ``failed`` flags the
parameter points that raised. The spec (JSON) and its key are in the dataset's attributes,
with the mechanism's label, digest and source (:class:`~plm_pin.sweep.SweepSpec`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._version import __version__
from ..results import Result, unit
from ._deps import require
from .spec import SweepSpec, Value, value_label

if TYPE_CHECKING:
    import xarray as xr

ANGLES = ("rx", "ry", "rz")


@dataclass(frozen=True)
class PointFailure(Result):
    """A parameter point that could not be evaluated.

    Attributes:
        index: its flat index.
        parameters: its varied parameter values.
        message: ``"Type: message"`` of the error.
    """

    index: int
    parameters: dict[str, Value]
    message: str

    def describe(self) -> str:
        """One line: the parameters and the error."""
        values = ", ".join(f"{k}={value_label(v)}" for k, v in self.parameters.items())
        return f"point {self.index} ({values or 'no varied parameter'}): {self.message}"


@dataclass(frozen=True)
class ChunkFailure(Result):
    """A chunk that did not finish: some of its points raised, or its task was lost.

    Its other points' values are in the result; the chunk is not checkpointed, so a re-run
    computes it again.

    Attributes:
        first: its first parameter point.
        last: its last parameter point.
        points: the points that failed, each with its parameters and message (every point
            of the chunk, with the task's error, when the task itself failed).
    """

    first: int
    last: int
    points: tuple[PointFailure, ...]

    def describe(self) -> str:
        """Lines: the chunk, then each failed point."""
        head = f"chunk of points {self.first}-{self.last}: {len(self.points)} point(s) failed"
        return "\n".join([head, *(f"  {p.describe()}" for p in self.points)])


@dataclass(frozen=True)
class SweepResult(Result):
    """A finished sweep (possibly with failed chunks).

    Attributes:
        dataset: the labelled results (an ``xarray.Dataset``, see the module docstring).
        spec: the sweep.
        key: the spec's key (SHA-256), as in the checkpoint manifest.
        computed: ``(first, last)`` parameter points of each chunk this run computed and
            finished (checkpointed when there is a store), in completion order.
        loaded: parameter points read back from the checkpoint store.
        failures: the chunks that did not finish.
        store: the checkpoint folder, or None.
        elapsed: wall time of the run [s].

    ``to_dict`` writes the dataset as ``xarray.Dataset.to_dict(data="list")`` does, non-finite
    values as strings.
    """

    dataset: xr.Dataset
    spec: SweepSpec
    key: str
    computed: tuple[tuple[int, int], ...]
    loaded: int
    failures: tuple[ChunkFailure, ...]
    store: Path | None
    elapsed: float = field(metadata=unit("s"))
    _NONFINITE_AS_TEXT = ("dataset", "elapsed")

    @property
    def complete(self) -> bool:
        """Whether every parameter point was evaluated."""
        return not self.failures

    @property
    def computed_points(self) -> int:
        """Parameter points this run computed and finished."""
        return sum(last - first + 1 for first, last in self.computed)

    def poses_per_second(self) -> float:
        """Poses evaluated per second of wall time by this run (finished chunks only) [1/s]."""
        n = self.computed_points * self.spec.n_poses
        return n / self.elapsed if self.elapsed > 0.0 else math.inf


def _coordinate(values: tuple[Value, ...]) -> np.ndarray:
    """Numbers as a numeric array; names and tuples as their text labels."""
    if all(isinstance(v, (int, float)) for v in values):
        return np.asarray(values)
    return np.asarray([value_label(v) for v in values], dtype=str)


def build_dataset(spec: SweepSpec, arrays: dict[str, np.ndarray], failed: np.ndarray) -> xr.Dataset:
    """The labelled Dataset of a sweep from its flat arrays ``(n_points, *variable shape)``."""
    xr = require("xarray")
    space = spec.parameters
    dims, shape = space.dims, space.shape
    coords: dict[str, Any] = {}
    described = {"description": "builder parameter (SI units)"}
    if space.samples:
        coords["sample"] = ("sample", np.arange(space.size), {"description": "sample index"})
        for k, name in enumerate(space.names):
            coords[name] = ("sample", _coordinate(tuple(s[k] for s in space.values)), described)
    else:
        for name, values in zip(space.names, space.values, strict=True):
            coords[name] = (name, _coordinate(tuple(values)), described)
    for axis, grid in zip(spec.axes, spec.values, strict=True):
        axis_unit = "rad" if axis in ANGLES else "m"
        coords[axis] = (axis, np.array(grid), {"units": axis_unit, "description": f"task coordinate {axis}"})
    data: dict[str, Any] = {}
    for v in spec.variables():
        attrs: dict[str, Any] = {"units": v.unit, "description": v.description}
        if v.flags:
            attrs["flag_values"] = list(range(len(v.flags)))
            attrs["flag_meanings"] = " ".join(v.flags)
        axes = spec.variable_axes(v)
        data[v.name] = ((*dims, *axes), arrays[v.name].reshape((*shape, *spec.variable_shape(v))), attrs)
    data["failed"] = (dims, failed.reshape(shape), {"units": "-", "description": "the point raised an error"})
    attrs = {
        "title": f"plm_pin design sweep of {spec.label}",
        "mechanism": spec.label,
        "mechanism_digest": spec.digest or "",
        "mechanism_source": spec.source,
        "key": spec.key(),
        "spec": json.dumps(spec.to_dict(), sort_keys=True),
        "plm_pin": __version__,
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)
