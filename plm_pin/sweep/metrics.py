r"""The metrics a design sweep evaluates: a name, its variables with units, the library call behind it.

Every metric is computed by existing plm_pin analyses at one parameter point (one built
mechanism), over the sweep's pose grid; none re-derives a formula:

- ``reachable``, ``manipulability``, ``condition_number`` and ``singularity`` come from
  :func:`plm_pin.workspace.workspace_grid` (inverse-kinematics continuation over the whole
  pose grid in the working mode of the reference configuration, batched
  :func:`~plm_pin.workspace.manipulability` and :func:`~plm_pin.kinematics.classify` margins);
- ``min_manipulability`` and ``reachable_fraction`` reduce those over the pose axes
  ``over`` (default: all of them);
- ``orientation_range`` runs :func:`plm_pin.workspace.orientation_range` along the rotation
  axis for every combination of the other pose coordinates;
- ``collision_free`` checks them for self-collision
  (:meth:`plm_pin.workspace.WorkspaceSlice.collision_free`);
- ``within_limits`` checks the grid's configurations against the joints' position limits
  (:meth:`plm_pin.workspace.WorkspaceSlice.within_limits`);
- ``peak_force`` and ``preload`` call :func:`plm_pin.statics.static_forces` at every reached
  pose, for every wrench of the set;
- ``accuracy`` calls :func:`plm_pin.workspace.accuracy_over` at the grid's configurations: the
  worst-case pose error for the tolerances ``length_tolerance`` [m] and ``angle_tolerance`` [rad]
  on every geometric parameter (:mod:`plm_pin.kinematics.accuracy`), and its largest over ``over``;
- ``stiffness`` calls :func:`plm_pin.stiffness.stiffness` and
  :func:`plm_pin.stiffness.natural_frequencies` at every reached pose (the mechanism's
  sidecar compliance, gravity and the internal preload ``internal``).

Variables have the dimensions of the parameter space followed by pose axes: all of them
(``"pose"``), those left after reducing over ``over`` (``"reduced"``), or all but the
rotation axis (``"line"``). Unreached poses hold NaN (``-1`` in codes, False in flags).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._text import short
from ..core.mechanism import Mechanism
from ..exceptions import AllocationInfeasible, InvalidInput, SingularConfiguration
from ..kinematics.accuracy import error_model
from ..kinematics.forward import task_pose
from ..kinematics.singularity import KINDS
from ..kinematics.working_mode import guess_mode
from ..results import units
from ..statics import static_forces
from ..statics.allocation import OBJECTIVES
from ..stiffness import StiffnessMap, stiffness_map
from ..stiffness.maps import VARIABLES as STIFFNESS_VARIABLES
from ..tolerances import SINGULARITY_TOL
from ..workspace import WorkspaceSlice, accuracy_over, workspace_grid
from ..workspace.manipulability import MARGIN_METRICS, POSE_METRICS, Manipulability
from ..workspace.orientation import ENDS, RANGE_XTOL, OrientationRange, orientation_range

SINGULARITY_CODES: tuple[str, ...] = ("regular", *KINDS)
"""Meaning of the ``singularity`` codes 0, 1, 2, 3 (-1: unreachable)."""

W_UNIT = units(Manipulability)["w"]
"""Unit of the manipulability w (see :mod:`plm_pin.workspace.manipulability`)."""

RANGE_UNITS = units(OrientationRange)
"""Units of an orientation range's ends (see :mod:`plm_pin.workspace.orientation`)."""

SLICE_UNITS = units(WorkspaceSlice)
"""Units of the per-pose metrics of a workspace slice (see :mod:`plm_pin.workspace.maps`)."""

STIFFNESS_UNITS = units(StiffnessMap)
"""Units of the stiffness-map variables (see :mod:`plm_pin.stiffness.maps`)."""

FORCE_UNIT = "N (N m for revolute actuators)"


@dataclass(frozen=True)
class Variable:
    """One array of a sweep's result.

    Attributes:
        name: variable name in the result.
        unit: its unit, in brackets-free SI notation (``"-"`` when dimensionless).
        description: what it holds, in words.
        axes: which pose axes it keeps: ``"pose"`` (all), ``"reduced"`` (all but the
            option ``over``) or ``"line"`` (all but the option ``rotation_axis``).
        dtype: ``"float64"``, ``"int8"`` (codes) or ``"bool"``.
        flags: meanings of the codes 0, 1, ... (``-1``: unreachable), for ``int8`` codes.
    """

    name: str
    unit: str
    description: str
    axes: str = "pose"
    dtype: str = "float64"
    flags: tuple[str, ...] = ()

    @property
    def fill(self) -> float | int | bool:
        """The value of an unreached pose or a failed parameter point."""
        return {"float64": math.nan, "int8": -1, "bool": False}[self.dtype]


@dataclass(frozen=True)
class Option:
    """A setting of one or more metrics, with its default and check.

    Attributes:
        name: option name.
        default: value when not given (None: computed from the sweep, see ``doc``).
        doc: meaning and unit.
        check: normalises a given value or raises :class:`~plm_pin.exceptions.InvalidInput`.
    """

    name: str
    default: Any
    doc: str
    check: Callable[[str, Any], Any]


def _positive(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < value < math.inf:
        raise InvalidInput(f"option {name!r} must be a positive finite number, got {short(value)}")
    return float(value)


def _finite(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InvalidInput(f"option {name!r} must be a finite number, got {short(value)}")
    return float(value)


def _of_type(kind: type, text: str) -> Callable[[str, Any], Any]:
    """A check that the value is a ``kind`` (described as ``text`` in the message)."""

    def check(name: str, value: Any) -> Any:
        if not isinstance(value, kind):
            raise InvalidInput(f"option {name!r} must be {text}, got {short(value)}")
        return value

    return check


def _names(name: str, value: Any) -> tuple[str, ...] | None:
    if value is None:
        return None
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, Sequence) or not value or not all(isinstance(v, str) for v in value):
        raise InvalidInput(f"option {name!r} must be a non-empty list of names, got {short(value)}")
    return tuple(value)


def _nonnegative(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value < math.inf:
        raise InvalidInput(f"option {name!r} must be a finite number >= 0, got {short(value)}")
    return float(value)


def _objective(name: str, value: Any) -> str:
    if value not in OBJECTIVES:
        raise InvalidInput(f"option {name!r} must be one of {list(OBJECTIVES)}, got {short(value)}")
    return str(value)


def _float_array(value: Any) -> np.ndarray:
    """``value`` as an array of floats; an empty one when it is not numbers (the caller refuses it)."""
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return np.empty(0)


def _wrenches(name: str, value: Any) -> tuple[tuple[float, ...], ...] | None:
    if value is None:
        return None
    arr = _float_array(value)
    if arr.ndim != 2 or arr.shape[0] == 0 or not np.all(np.isfinite(arr)):
        raise InvalidInput(
            f"option {name!r} must be a non-empty list of wrenches (each 6 values, or one per task "
            f"coordinate), all finite, got {short(value)}"
        )
    return tuple(tuple(float(v) for v in row) for row in arr)


def _internal(name: str, value: Any) -> tuple[float, ...] | dict[str, float] | None:
    if value is None:
        return None
    if isinstance(value, Mapping):
        return {str(k): _finite(f"{name}.{k}", v) for k, v in value.items()}
    if isinstance(value, Sequence) and not isinstance(value, str) and value:
        return tuple(_finite(name, v) for v in value)
    raise InvalidInput(
        f"option {name!r} must be internal-force coordinates (a list of numbers) or "
        f"{{link: axial force [N]}}, got {short(value)}"
    )


def _direction(name: str, value: Any) -> tuple[float, ...] | None:
    if value is None:
        return None
    arr = _float_array(value)
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)) or not np.any(arr):
        raise InvalidInput(f"option {name!r} must be a non-zero list of numbers, got {short(value)}")
    return tuple(float(v) for v in arr)


OPTIONS: dict[str, Option] = {
    o.name: o
    for o in (
        Option(
            "ik_tol",
            None,
            "inverse-kinematics residual tolerance [m, rad] (default: the mechanism's closure tolerance)",
            _positive,
        ),
        Option(
            "singularity_tol", SINGULARITY_TOL, "margin at or below which a pose is singular [-]", _positive
        ),
        Option("over", None, "pose axes reduced over (default: all pose axes)", _names),
        Option(
            "rotation_axis",
            "rz",
            "the task coordinate turned by the orientation range",
            _of_type(str, "a task coordinate name"),
        ),
        Option("reference", 0.0, "angle the orientation range must hold [rad]", _finite),
        Option("xtol", RANGE_XTOL, "tolerance on the located ends of the orientation range [rad]", _positive),
        Option(
            "wrenches",
            None,
            "loads applied to the task frame [N, N m]: 6 values or one per task coordinate each "
            "(default: none, gravity alone)",
            _wrenches,
        ),
        Option("gravity", True, "hold the weight of the bodies too", _of_type(bool, "true or false")),
        Option(
            "objective",
            "max",
            "allocation of peak_force: 'max' (least peak) or 'norm' (min norm)",
            _objective,
        ),
        Option("compression", 0.0, "compression every preloaded link must carry [N]", _finite),
        Option("preload_links", None, "hinged links held in compression (default: all of them)", _names),
        Option(
            "internal",
            None,
            "internal preload of the stiffness: coordinates in the internal basis or {link: axial force "
            "[N]} (Harada 2011's f_i on the 3D4M: {plate: -f_i}); default the minimum-norm forces",
            _internal,
        ),
        Option(
            "length_tolerance",
            None,
            "accuracy: tolerance of every placement translation and prismatic actuator offset [m] (required)",
            _nonnegative,
        ),
        Option(
            "angle_tolerance",
            None,
            "accuracy: tolerance of every placement rotation and revolute actuator offset [rad] (required)",
            _nonnegative,
        ),
        Option(
            "compliance_direction",
            None,
            "direction in the task's translation coordinates of compliance_along (default: the first one)",
            _direction,
        ),
    )
}
"""Every option any metric takes, by name."""


@dataclass(frozen=True)
class Metric:
    """A quantity a sweep can evaluate.

    Attributes:
        name: metric name, as given in ``metrics=[...]``.
        summary: its definition in one line.
        variables: the result variables it fills.
        options: names of the :data:`OPTIONS` it uses (``ik_tol`` is used by all).
        compute: the variables' values at one parameter point.
        required: the options among ``options`` that have no default and must be given.
        split: whether its per-pose work divides into shares (:attr:`PointEvaluation.share`):
            independent analyses of each reached pose or line, not the continuation over the grid.
        grid_metrics: the per-pose metrics of :attr:`PointEvaluation.grid` it reads (among
            :data:`~plm_pin.workspace.POSE_METRICS`); the grid computes those the sweep's
            metrics read and no other.
    """

    name: str
    summary: str
    variables: tuple[Variable, ...]
    options: tuple[str, ...]
    compute: Callable[[PointEvaluation], dict[str, np.ndarray]]
    required: tuple[str, ...] = ()
    split: bool = False
    grid_metrics: tuple[str, ...] = ()


@dataclass(frozen=True)
class PoseGrid:
    """What every parameter point's metrics share: the pose grid and the metrics' options.

    Attributes:
        axes: the pose grid's task coordinates, in order.
        values: their values [m or rad], one array per axis.
        pose: task pose giving the other coordinates [m, rad], or None (each variant's
            reference pose).
        reduced_over: pose axes the reduced metrics run over.
        options: every option of the metrics, defaults filled in.
        grid_metrics: the per-pose metrics the grid computes (:func:`grid_metrics` of the sweep's).
    """

    axes: tuple[str, ...]
    values: tuple[np.ndarray, ...]
    pose: tuple[float, ...] | None
    reduced_over: tuple[str, ...]
    options: Mapping[str, Any]
    grid_metrics: tuple[str, ...]


class PointEvaluation:
    """One parameter point: its mechanism and the analyses its metrics share, each computed once.

    Attributes:
        spec: the pose grid and options of the sweep (:meth:`plm_pin.sweep.SweepSpec.pose_grid`).
        mech: the mechanism built at this point.
        mode: the reference configuration's working mode, kept by every analysis (None if
            a leg is singular there: the continuation's seed decides).
        share: ``(k, n)``: this evaluation computes the k-th of n shares of the point. The
            grid's continuation runs whole in every share (so every pose is solved by the same
            calls); the metrics that split (:attr:`Metric.split`) analyse only the reached poses
            or lines whose rank is k modulo n and leave the others at their fill values; the
            others are computed by share 0 alone. ``(0, 1)``: the whole point.
    """

    def __init__(self, spec: PoseGrid, mech: Mechanism, share: tuple[int, int] = (0, 1)) -> None:
        """Prepare the evaluation of the metrics on ``mech`` over ``spec``'s grid (its ``share``)."""
        self.spec = spec
        self.mech = mech
        self.mode = guess_mode(mech, None)
        self.share = share

    def computes(self, metric: Metric) -> bool:
        """Whether this share computes ``metric`` (every share its part of a split one; share 0 the rest)."""
        return metric.split or self.share[0] == 0

    def owned(self, n: int) -> np.ndarray:
        """Which of ``n`` work items (reached poses or lines, in order) this share analyses."""
        k, shares = self.share
        return np.arange(n) % shares == k

    def option(self, name: str) -> Any:
        """A checked option of the sweep (defaults filled in)."""
        return self.spec.options[name]

    @functools.cached_property
    def base(self) -> np.ndarray:
        """Task pose giving the coordinates the pose grid does not vary [m, rad]."""
        if self.spec.pose is not None:
            return np.asarray(self.spec.pose, dtype=float)
        return task_pose(self.mech, self.mech.q_ref)

    @functools.cached_property
    def grid(self) -> WorkspaceSlice:
        """:func:`~plm_pin.workspace.workspace_grid` over the pose grid, computing ``spec.grid_metrics``."""
        spec = self.spec
        return workspace_grid(
            self.mech,
            spec.axes,
            spec.values,
            self.base,
            mode=self.mode,
            tol=self.option("ik_tol"),
            metrics=spec.grid_metrics,
        )

    @functools.cached_property
    def share_grid(self) -> WorkspaceSlice:
        """:attr:`grid` reaching only this share's reached poses (what the split per-pose analyses visit)."""
        grid = self.grid
        if self.share[1] == 1:
            return grid
        reachable = np.zeros_like(grid.reachable)
        reachable.flat[np.flatnonzero(grid.reachable)[self.owned(int(np.count_nonzero(grid.reachable)))]] = (
            True
        )
        return dataclasses.replace(grid, reachable=reachable)

    def over(self) -> tuple[int, ...]:
        """Positions of the pose axes a reduction runs over."""
        return tuple(self.spec.axes.index(a) for a in self.spec.reduced_over)

    def static_peak(self, solve: Callable[[np.ndarray, ArrayLike | None], float]) -> np.ndarray:
        """``max over the wrench set of solve(q, wrench)`` at every reached pose (NaN elsewhere)."""
        grid = self.share_grid
        out = np.full(grid.shape, np.nan)
        wrenches = self.option("wrenches") or (None,)
        for index in zip(*np.nonzero(grid.reachable), strict=True):
            q = grid.q[index]
            out[index] = max(solve(q, w) for w in wrenches)
        return out


def _grid_values(name: str) -> Callable[[PointEvaluation], dict[str, np.ndarray]]:
    return lambda ev: {name: np.asarray(getattr(ev.grid, name))}


def _singularity(ev: PointEvaluation) -> dict[str, np.ndarray]:
    grid = ev.grid
    margins = np.stack([grid.metric(name) for name in MARGIN_METRICS])  # KINDS order
    smallest = np.min(margins, axis=0)
    code = np.where(smallest <= ev.option("singularity_tol"), 1 + np.argmin(margins, axis=0), 0)
    code = np.where(grid.reachable, code, -1).astype(np.int8)
    return {"singularity": code, "singularity_margin": np.where(grid.reachable, smallest, np.nan)}


def _min_manipulability(ev: PointEvaluation) -> dict[str, np.ndarray]:
    w = np.asarray(ev.grid.manipulability)  # NaN where unreached: fmin ignores it
    return {"min_manipulability": np.asarray(np.fmin.reduce(w, axis=ev.over()))}


def _reachable_fraction(ev: PointEvaluation) -> dict[str, np.ndarray]:
    return {"reachable_fraction": np.asarray(np.mean(ev.grid.reachable, axis=ev.over()))}


def _orientation_range(ev: PointEvaluation) -> dict[str, np.ndarray]:
    spec = ev.spec
    axis = ev.option("rotation_axis")
    k = spec.axes.index(axis)
    others = [a for a in spec.axes if a != axis]
    shape = tuple(len(spec.values[spec.axes.index(a)]) for a in others)
    dofs = ev.mech.sidecar.task.dofs if ev.mech.sidecar.task is not None else ()
    out = {
        "orientation_lower": np.full(shape, np.nan),
        "orientation_upper": np.full(shape, np.nan),
        "orientation_halfwidth": np.full(shape, np.nan),
        "orientation_lower_end": np.full(shape, -1, dtype=np.int8),
        "orientation_upper_end": np.full(shape, -1, dtype=np.int8),
    }
    reference = ev.option("reference")
    owned = ev.owned(math.prod(shape))
    for flat, index in enumerate(np.ndindex(*shape)):
        if not owned[flat]:
            continue
        pose = ev.base.copy()
        for a, i in zip(others, index, strict=True):
            pose[dofs.index(a)] = spec.values[spec.axes.index(a)][i]
        r = orientation_range(
            ev.mech,
            axis,
            spec.values[k],
            pose,
            reference=reference,
            xtol=ev.option("xtol"),
            tol=ev.option("singularity_tol"),
            ik_tol=ev.option("ik_tol"),
        )
        out["orientation_lower"][index] = r.lower
        out["orientation_upper"][index] = r.upper
        out["orientation_halfwidth"][index] = min(reference - r.lower, r.upper - reference)
        out["orientation_lower_end"][index] = ENDS.index(r.lower_end)
        out["orientation_upper_end"][index] = ENDS.index(r.upper_end)
    return out


def _peak_force(ev: PointEvaluation) -> dict[str, np.ndarray]:
    def peak(q: np.ndarray, wrench: ArrayLike | None) -> float:
        try:
            options = {"gravity": ev.option("gravity"), "objective": ev.option("objective")}
            sol = static_forces(ev.mech, q, wrench, limits=None, **options)
        except SingularConfiguration:
            return math.inf
        return float(np.max(np.abs(sol.f_c)))

    return {"peak_force": ev.static_peak(peak)}


def _preload(ev: PointEvaluation) -> dict[str, np.ndarray]:
    c = ev.option("compression")
    links = ev.option("preload_links")
    conditions: dict[str, Any] = (
        {"min_compression": c} if links is None else {"link_limits": {n: (-math.inf, -c) for n in links}}
    )

    def needed(q: np.ndarray, wrench: ArrayLike | None) -> float:
        try:
            sol = static_forces(ev.mech, q, wrench, gravity=ev.option("gravity"), limits=None, **conditions)
        except (SingularConfiguration, AllocationInfeasible):
            return math.inf
        return float(np.linalg.norm(sol.internal))

    return {"preload": ev.static_peak(needed)}


def _stiffness(ev: PointEvaluation) -> dict[str, np.ndarray]:
    smap = stiffness_map(
        ev.mech,
        ev.share_grid,
        direction=ev.option("compliance_direction"),
        gravity=ev.option("gravity"),
        internal=ev.option("internal"),
    )
    return {name: np.array(smap.variable(name)) for name in STIFFNESS_VARIABLES}


def _accuracy(ev: PointEvaluation) -> dict[str, np.ndarray]:
    tol = error_model(ev.mech).tolerances(ev.option("length_tolerance"), ev.option("angle_tolerance"))
    amap = accuracy_over(ev.mech, ev.grid, tol)
    position, angle = amap.worst_position, amap.worst_angle  # NaN where unreached: fmax ignores it
    return {
        "position_error": position,
        "angle_error": angle,
        "max_position_error": np.asarray(np.fmax.reduce(position, axis=ev.over())),
        "max_angle_error": np.asarray(np.fmax.reduce(angle, axis=ev.over())),
    }


_W = "Yoshikawa manipulability w = sqrt(det(J_ce^T J_ce)) (Harada 2011 eq. (13)); 0 at a direct singularity"

METRICS: dict[str, Metric] = {
    m.name: m
    for m in (
        Metric(
            "reachable",
            "whether the pose is reached in the reference working mode by continuation over the grid",
            (Variable("reachable", "-", "pose reached in the working mode", dtype="bool"),),
            (),
            _grid_values("reachable"),
        ),
        Metric(
            "manipulability",
            _W,
            (Variable("manipulability", W_UNIT, _W),),
            (),
            _grid_values("manipulability"),
            grid_metrics=("manipulability",),
        ),
        Metric(
            "condition_number",
            "sigma_max / sigma_min of J_ce; inf at a singularity",
            (Variable("condition_number", SLICE_UNITS["condition_number"], "condition number of J_ce"),),
            (),
            _grid_values("condition_number"),
            grid_metrics=("condition_number",),
        ),
        Metric(
            "singularity",
            "singularity type (the kind of the smallest margin when it is at most singularity_tol) "
            "and the smallest of the constraint, inverse and direct margins",
            (
                Variable(
                    "singularity",
                    "-",
                    "0 regular, 1 constraint, 2 inverse (type 1), 3 direct (type 2); -1 unreachable",
                    dtype="int8",
                    flags=SINGULARITY_CODES,
                ),
                Variable(
                    "singularity_margin", "-", "smallest normalised singularity margin sigma_min/sigma_max"
                ),
            ),
            ("singularity_tol",),
            _singularity,
            grid_metrics=MARGIN_METRICS,
        ),
        Metric(
            "min_manipulability",
            "smallest w over the reached poses of the axes 'over' (NaN when none is reached)",
            (Variable("min_manipulability", W_UNIT, "smallest manipulability w", axes="reduced"),),
            ("over",),
            _min_manipulability,
            grid_metrics=("manipulability",),
        ),
        Metric(
            "reachable_fraction",
            "fraction of the poses of the axes 'over' (a box of the workspace) reached in the working mode",
            (Variable("reachable_fraction", "-", "fraction of the pose box reached", axes="reduced"),),
            ("over",),
            _reachable_fraction,
        ),
        Metric(
            "orientation_range",
            "largest interval of the rotation axis holding the reference angle that stays reachable and "
            "non-singular (plm_pin.workspace.orientation_range), ends located to xtol",
            (
                Variable(
                    "orientation_lower",
                    RANGE_UNITS["lower"],
                    "lower end of the singularity-free range",
                    axes="line",
                ),
                Variable(
                    "orientation_upper",
                    RANGE_UNITS["upper"],
                    "upper end of the singularity-free range",
                    axes="line",
                ),
                Variable(
                    "orientation_halfwidth",
                    RANGE_UNITS["reference"],
                    "largest symmetric turn +/- d about the reference within the range",
                    axes="line",
                ),
                Variable(
                    "orientation_lower_end",
                    "-",
                    "what ends the range below: " + ", ".join(f"{i} {e}" for i, e in enumerate(ENDS)),
                    axes="line",
                    dtype="int8",
                    flags=ENDS,
                ),
                Variable(
                    "orientation_upper_end",
                    "-",
                    "what ends the range above (codes as orientation_lower_end)",
                    axes="line",
                    dtype="int8",
                    flags=ENDS,
                ),
            ),
            ("rotation_axis", "reference", "xtol", "singularity_tol"),
            _orientation_range,
            split=True,
        ),
        Metric(
            "peak_force",
            "largest |f_c| over the actuators and the wrench set, static allocation by 'objective' "
            "without limits (plm_pin.statics.static_forces); inf where a load cannot be held",
            (Variable("peak_force", FORCE_UNIT, "static peak actuator force over the wrench set"),),
            ("wrenches", "gravity", "objective"),
            _peak_force,
            split=True,
        ),
        Metric(
            "preload",
            "norm of the internal actuator forces the minimum-norm allocation adds so that the preloaded "
            "links carry at least 'compression', largest over the wrench set; 0 when the load alone does, "
            "inf when no internal force can",
            (Variable("preload", "N", "internal preload needed over the wrench set"),),
            ("wrenches", "gravity", "compression", "preload_links"),
            _preload,
            split=True,
        ),
        Metric(
            "stiffness",
            "Cartesian stiffness with the geometric stiffness of gravity and internal preload "
            "(plm_pin.stiffness, the sidecar's compliance): smallest translational eigen-stiffness, "
            "compliance along a direction, lowest natural frequency (task model); NaN where singular",
            (
                Variable(
                    "min_translational_stiffness",
                    STIFFNESS_UNITS["min_translational_stiffness"],
                    "smallest eigen-stiffness under a pure force",
                ),
                Variable(
                    "compliance_along",
                    STIFFNESS_UNITS["compliance_along"],
                    "displacement per unit force along compliance_direction",
                ),
                Variable(
                    "lowest_frequency",
                    STIFFNESS_UNITS["lowest_frequency"],
                    "lowest natural frequency from M_x and K_x",
                ),
            ),
            ("gravity", "internal", "compliance_direction"),
            _stiffness,
            split=True,
        ),
        Metric(
            "accuracy",
            "worst-case first-order pose error for tolerances length_tolerance / angle_tolerance on "
            "every joint placement, closure frame placement and actuator offset "
            "(plm_pin.kinematics.accuracy), largest over the task coordinates in m and in rad; NaN where "
            "unreached or singular",
            (
                Variable("position_error", "m", "worst-case error of the task's coordinates in m"),
                Variable("angle_error", "rad", "worst-case error of the task's coordinates in rad"),
                Variable(
                    "max_position_error", "m", "largest position_error over the axes 'over'", axes="reduced"
                ),
                Variable(
                    "max_angle_error", "rad", "largest angle_error over the axes 'over'", axes="reduced"
                ),
            ),
            ("length_tolerance", "angle_tolerance", "over"),
            _accuracy,
            required=("length_tolerance", "angle_tolerance"),
        ),
        Metric(
            "within_limits",
            "whether the reached pose keeps every joint inside its URDF position limits (apart from "
            "'reachable': the loops close there, perhaps only with a passive joint beyond its range)",
            (
                Variable(
                    "within_limits", "-", "pose reached with every joint inside its limits", dtype="bool"
                ),
            ),
            (),
            lambda ev: {"within_limits": ev.grid.within_limits(ev.mech)},
        ),
        Metric(
            "collision_free",
            "whether the reached pose is free of self-collision between non-adjacent bodies "
            "(plm_pin.kinematics.collisions, on the description's visual shapes)",
            (Variable("collision_free", "-", "pose reached without self-collision", dtype="bool"),),
            (),
            lambda ev: {"collision_free": ev.grid.collision_free(ev.mech)},
        ),
    )
}
"""Every metric, by name."""


def grid_metrics(metrics: Sequence[str]) -> tuple[str, ...]:
    """The per-pose metrics of the workspace grid that ``metrics`` read, in :data:`POSE_METRICS` order."""
    return tuple(name for name in POSE_METRICS if any(name in METRICS[m].grid_metrics for m in metrics))


def metric_options(metrics: Sequence[str]) -> tuple[str, ...]:
    """Names of the options the given metrics use, ``ik_tol`` first."""
    names = ["ik_tol"]
    for m in metrics:
        names.extend(o for o in METRICS[m].options if o not in names)
    return tuple(names)


def check_options(metrics: Sequence[str], given: Mapping[str, Any]) -> dict[str, Any]:
    """The options of ``metrics``, checked, with the defaults filled in (``over`` left None: all axes).

    Raises:
        InvalidInput: an unknown option, one no chosen metric uses, or a bad value.
    """
    used = metric_options(metrics)
    for m in metrics:
        missing = [o for o in METRICS[m].required if o not in given]
        if missing:
            raise InvalidInput(f"metric {m!r} needs the options {missing} (no default); give them in options")
    for name in given:
        if name not in OPTIONS:
            raise InvalidInput(f"unknown option {name!r}; options are {sorted(OPTIONS)}")
        if name not in used:
            users = [m for m, metric in METRICS.items() if name in metric.options]
            raise InvalidInput(
                f"option {name!r} is used by the metrics {users}, none of which is asked for; "
                f"the options of {list(metrics)} are {list(used)}"
            )
    return {
        name: OPTIONS[name].check(name, given[name]) if name in given else OPTIONS[name].default
        for name in used
    }
