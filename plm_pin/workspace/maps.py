r"""Manipulability and singularity maps over slices of the workspace.

A *slice* fixes every task coordinate but one (a sweep, e.g. :math:`w(\theta)` at fixed
x, y as in Harada 2011 Fig. 6) or two (a map, e.g. an x-y grid at fixed :math:`\theta`).
At every grid pose the inverse kinematics is solved by continuation: each point starts
from its solved neighbours (extrapolated along the grid line), so the working mode of
the first solved point (the *seed*) is kept throughout; a point the continuation cannot
solve in that working mode is marked unreachable (``reachable`` False, metrics NaN)
instead of raising. "Reachable" therefore means reachable in the seed's working mode
through the grid, which is what a mechanism moving continuously can do.

The metrics are those of :func:`plm_pin.workspace.manipulability` and
:func:`plm_pin.kinematics.classify` (the singularity margins), computed in batches. The
keyword ``metrics`` names the ones to compute (default all of
:data:`~plm_pin.workspace.manipulability.POSE_METRICS`); the others are not computed, their
arrays hold NaN and :meth:`WorkspaceSlice.metric` refuses them. A manipulability map without
the margins skips the eigenvalues of the closure Jacobian, of :math:`C` and of :math:`T^{-1}`,
about half of the metrics' cost.

Cost (``make bench``): on trees of one-axis joints and free-flyers with point closures
and a task of translations plus a planar yaw or all three angles (the 2-PRRRP tables, the
n-PSS), 2-D grids are solved a row at a time by one batched Newton over the row, both
sides of the seed's row together (on the compiled kernels, else
:mod:`plm_pin.workspace._batch`'s numpy forward kinematics from the model's joint placements),
in one process, after the seed's row (walked point by point by the compiled Newton, its
modes and metrics in one batch); the points the rows miss are filled point by point.
Other mechanisms go point by point (one Newton step per pose, exact Jacobians, metrics in
batches); their grids of 20,000 poses or more are split in bands of rows solved in parallel
processes (``workers``, default all CPUs), then joined across the band borders.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._text import short
from ..core.mechanism import Mechanism, require_task
from ..exceptions import InvalidInput
from ..kinematics.collisions import collision_free
from ..kinematics.jacobians import check_square_task
from ..kinematics.limits import within_limits
from ..results import Result, unit
from ._continuation import base_pose, solve_poses
from .manipulability import POSE_METRICS, W_UNIT


@dataclass(frozen=True)
class WorkspaceSlice(Result):
    r"""Metrics over a 1-D sweep or a 2-D map of task poses (``ij`` indexing).

    ``a[i, j]`` belongs to the pose whose coordinate ``axes[0]`` is ``values[0][i]`` and
    ``axes[1]`` is ``values[1][j]``, the others being those of ``pose``. Unreachable
    points hold NaN (and 0 in ``mode``), and so do the metrics not in ``metrics`` everywhere.

    Attributes:
        axes: the varied task coordinates, among the task's (``x y z rx ry rz``).
        values: their grid values [m or rad], one array per axis.
        pose: the task pose supplying the fixed coordinates [m, rad], shape (n_task,).
        dofs: names of the task coordinates.
        reachable: solved in the working mode, shape ``shape``.
        manipulability: :math:`w = \sqrt{\det(J_{ce}^T J_{ce})}` (Harada 2011 eq. (13)) [product of
            the column units of J_ce, m/rad for linear actuators and an x-y-theta task]; 0 at a
            direct singularity, inf at an inverse one.
        condition_number: :math:`\sigma_{max}/\sigma_{min}` of J_ce [-].
        constraint_margin: normalised smallest closure singular value at the generic rank [-].
        inverse_margin: :math:`\sigma_{min}(T)/\sigma_{max}(J_x)`, :math:`T = J_x N` (type 1) [-].
        direct_margin: :math:`\sigma_{min}(C)`, :math:`C = S_a N` (type 2) [-].
        actuators: actuator positions [m or rad], shape ``shape + (n_act,)``.
        q: configurations, shape ``shape + (nq,)``.
        mode: working mode of each point (one sign per square leg), shape ``shape + (n_legs,)``.
        working_mode: the seed's working mode, kept over the slice (None when nothing was reached).
        metrics: the metrics computed, in the order of
            :data:`~plm_pin.workspace.manipulability.POSE_METRICS` (the others are NaN).
    """

    axes: tuple[str, ...]
    values: tuple[np.ndarray, ...] = field(metadata=unit("m, rad"))
    pose: np.ndarray = field(metadata=unit("m, rad"))
    dofs: tuple[str, ...]
    reachable: np.ndarray
    manipulability: np.ndarray = field(metadata=unit(W_UNIT))
    condition_number: np.ndarray = field(metadata=unit("-"))
    constraint_margin: np.ndarray = field(metadata=unit("-"))
    inverse_margin: np.ndarray = field(metadata=unit("-"))
    direct_margin: np.ndarray = field(metadata=unit("-"))
    actuators: np.ndarray = field(metadata=unit("m, rad"))
    q: np.ndarray = field(metadata=unit("m, rad"))
    mode: np.ndarray
    working_mode: tuple[int, ...] | None
    metrics: tuple[str, ...] = POSE_METRICS
    _SKIPPED = ("q",)
    _NONFINITE_AS_TEXT = (*POSE_METRICS, "actuators")

    def __post_init__(self) -> None:
        shape = tuple(len(v) for v in self.values)
        if len(self.axes) != len(self.values) or self.reachable.shape != shape:
            raise InvalidInput(f"slice arrays of shape {self.reachable.shape} do not match the axes {shape}")
        for name in (*POSE_METRICS, "reachable", "actuators", "q", "mode"):
            arr = getattr(self, name)
            if arr.shape[: len(shape)] != shape:
                raise InvalidInput(f"{name} has shape {arr.shape}, expected {shape} first")
            arr.setflags(write=False)

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape, one entry per varied coordinate."""
        return self.reachable.shape

    @property
    def reachable_fraction(self) -> float:
        """Fraction of the grid reached [-]."""
        return float(np.mean(self.reachable))

    def within_limits(self, mech: Mechanism) -> np.ndarray:
        """Reached points whose configuration keeps every joint inside its position limits, shape ``shape``.

        Apart from :attr:`reachable` (the loops close there): a reached point may need a passive
        joint beyond its range (see :mod:`plm_pin.kinematics.limits`).
        """
        return np.asarray(self.reachable & within_limits(mech, self.q))

    def collision_free(self, mech: Mechanism, ignore: Sequence[tuple[str, str]] = ()) -> np.ndarray:
        """Reached points where no two non-adjacent bodies touch, shape ``shape``.

        See :mod:`plm_pin.kinematics.collisions` (``ignore``: more body-name pairs left out).
        """
        return np.asarray(self.reachable & collision_free(mech, self.q, ignore))

    def poses(self) -> np.ndarray:
        """Task pose of every grid point [m, rad], shape ``shape + (n_task,)``."""
        return _grid_poses(self.pose, self.dofs, self.axes, self.values)

    def metric(self, name: str) -> np.ndarray:
        """One of :data:`plm_pin.workspace.manipulability.POSE_METRICS` by name, shape ``shape``.

        Raises:
            InvalidInput: an unknown name, or a metric the slice was computed without.
        """
        if name not in POSE_METRICS:
            raise InvalidInput(f"unknown metric {name!r}; metrics are {list(POSE_METRICS)}")
        if name not in self.metrics:
            raise InvalidInput(
                f"metric {name!r} was not computed (metrics={list(self.metrics)}); include it in the "
                "map's metrics"
            )
        return np.asarray(getattr(self, name))


def _grid_poses(
    pose: np.ndarray, dofs: tuple[str, ...], axes: tuple[str, ...], values: tuple[np.ndarray, ...]
) -> np.ndarray:
    shape = tuple(len(v) for v in values)
    out = np.broadcast_to(pose, (*shape, len(dofs))).copy()
    grids = np.meshgrid(*values, indexing="ij")
    for axis, g in zip(axes, grids, strict=True):
        out[..., dofs.index(axis)] = g
    return out


def _check_axes(
    mech: Mechanism, axes: Sequence[str], values: Sequence[ArrayLike]
) -> tuple[tuple[str, ...], tuple[np.ndarray, ...]]:
    task = require_task(mech)
    dofs = tuple(task.dofs)
    check_square_task(task.size, mech.mobility, "manipulability maps need", mech.name)
    for a in axes:
        if a not in dofs:
            raise InvalidInput(f"unknown task coordinate {a!r}; the task's coordinates are {list(dofs)}")
    if len(set(axes)) != len(axes):
        raise InvalidInput(f"the varied coordinates must differ, got {list(axes)}")
    arrays = []
    for a, v in zip(axes, values, strict=True):
        arr = np.asarray(v, dtype=float)
        if arr.ndim != 1 or arr.size == 0:
            raise InvalidInput(f"values of {a!r} must be a non-empty 1-D array, got shape {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise InvalidInput(f"values of {a!r} hold non-finite entries")
        arrays.append(arr)
    return dofs, tuple(arrays)


def _check_metrics(metrics: Sequence[str] | None) -> tuple[str, ...]:
    """The names of ``metrics`` in the order of :data:`POSE_METRICS` (None: all; a string: that one).

    Raises:
        InvalidInput: not a sequence of strings, or an unknown name.
    """
    if metrics is None:
        return POSE_METRICS
    names = (metrics,) if isinstance(metrics, str) else metrics
    if not isinstance(names, Sequence):
        raise InvalidInput(
            f"metrics must be a list of names among {list(POSE_METRICS)}, got {short(metrics)}"
        )
    for name in names:
        if name not in POSE_METRICS:
            raise InvalidInput(f"metrics: unknown metric {short(name)}; choose among {list(POSE_METRICS)}")
    return tuple(name for name in POSE_METRICS if name in names)


def _slice(
    mech: Mechanism,
    axes: tuple[str, ...],
    values: Sequence[ArrayLike],
    pose: ArrayLike | None,
    guess: ArrayLike | None,
    mode: tuple[int, ...] | None,
    tol: float | None,
    workers: int | None,
    metrics: Sequence[str] | None,
) -> WorkspaceSlice:
    names = _check_metrics(metrics)
    dofs, arrays = _check_axes(mech, axes, values)
    base = base_pose(mech, pose, guess)
    shape = tuple(len(a) for a in arrays)
    poses = _grid_poses(base, dofs, axes, arrays)
    tol = mech.closure_tol if tol is None else tol
    state, target = solve_poses(mech, poses, guess, mode=mode, tol=tol, workers=workers, names=names)
    reached = state.reached.reshape(shape)
    columns = {
        name: state.metrics.get(name, np.full(state.reached.size, np.nan)).reshape(shape)
        for name in POSE_METRICS
    }
    q = state.q.reshape(*shape, -1)
    return WorkspaceSlice(
        axes=axes,
        values=arrays,
        pose=base,
        dofs=dofs,
        reachable=reached,
        manipulability=columns["manipulability"],
        condition_number=columns["condition_number"],
        constraint_margin=columns["constraint_margin"],
        inverse_margin=columns["inverse_margin"],
        direct_margin=columns["direct_margin"],
        actuators=mech.actuator_positions(q),
        q=q,
        mode=np.where(reached[..., None], state.mode.reshape(*shape, -1), 0).astype(np.int8),
        working_mode=target,
        metrics=names,
    )


def workspace_map(
    mech: Mechanism,
    axes: tuple[str, str],
    values: tuple[ArrayLike, ArrayLike],
    pose: ArrayLike | None = None,
    *,
    guess: ArrayLike | None = None,
    mode: tuple[int, ...] | None = None,
    tol: float | None = None,
    workers: int | None = None,
    metrics: Sequence[str] | None = None,
) -> WorkspaceSlice:
    """Manipulability, condition number, singularity margins and reachability over a 2-D grid.

    Args:
        mech: the mechanism (its task must have as many coordinates as it has DOF).
        axes: the two varied task coordinates, e.g. ``("x", "y")``.
        values: their grid values [m or rad], two 1-D arrays.
        pose: task pose giving the fixed coordinates (default: the guess's pose) [m, rad].
        guess: configuration the seed is solved from (default: the reference configuration).
        mode: working mode to keep (default: the one the seed is solved in from ``guess``).
        tol: inverse-kinematics residual tolerance [m, rad] (default: the mechanism's ``closure_tol``).
        workers: processes to use (default: all CPUs for grids of 20,000 poses or more, else 1);
            unused where the rows are solved in batches (one process is faster there).
        metrics: the metrics to compute, among
            :data:`~plm_pin.workspace.manipulability.POSE_METRICS` (default all; a string names
            one). The others are not computed and hold NaN: ``metrics=("manipulability",)``
            skips the singularity margins' eigenvalues, about half of the metrics' cost.

    Returns:
        The map, arrays of shape ``(len(values[0]), len(values[1]))``.

    Raises:
        InvalidInput: unknown or repeated axes, malformed values or pose, a task whose size
            differs from the mechanism's DOF, or an unknown metric.
    """
    if len(axes) != 2 or len(values) != 2:
        raise InvalidInput(f"a map varies two task coordinates; got axes {list(axes)}")
    return _slice(mech, tuple(axes), values, pose, guess, mode, tol, workers, metrics)


def workspace_grid(
    mech: Mechanism,
    axes: Sequence[str],
    values: Sequence[ArrayLike],
    pose: ArrayLike | None = None,
    *,
    guess: ArrayLike | None = None,
    mode: tuple[int, ...] | None = None,
    tol: float | None = None,
    metrics: Sequence[str] | None = None,
) -> WorkspaceSlice:
    """The metrics of :func:`workspace_map` over a grid of any number of task coordinates.

    The continuation walks the whole grid from its seed in one process, in a fixed order,
    so the result depends only on the arguments (the design sweeps of :mod:`plm_pin.sweep`
    rely on it).

    Args:
        mech: the mechanism.
        axes: the varied task coordinates, e.g. ``("x", "y", "rz")``.
        values: their grid values [m or rad], one 1-D array per axis.
        pose: task pose giving the fixed coordinates (default: the guess's pose) [m, rad].
        guess: configuration the seed is solved from (default: the reference configuration).
        mode: working mode to keep (default: the seed's).
        tol: inverse-kinematics residual tolerance [m, rad] (default: the mechanism's ``closure_tol``).
        metrics: the metrics to compute (default all; see :func:`workspace_map`).

    Returns:
        The grid, arrays of shape ``tuple(len(v) for v in values)``.

    Raises:
        InvalidInput: see :func:`workspace_map`.
    """
    if len(axes) < 1 or len(axes) != len(values):
        raise InvalidInput(f"give one array of values per varied coordinate; got axes {list(axes)}")
    return _slice(mech, tuple(axes), values, pose, guess, mode, tol, 1, metrics)


def workspace_sweep(
    mech: Mechanism,
    axis: str,
    values: ArrayLike,
    pose: ArrayLike | None = None,
    *,
    guess: ArrayLike | None = None,
    mode: tuple[int, ...] | None = None,
    tol: float | None = None,
    metrics: Sequence[str] | None = None,
) -> WorkspaceSlice:
    """The metrics of :func:`workspace_map` along one task coordinate, the others fixed.

    Args:
        mech: the mechanism.
        axis: the varied task coordinate, e.g. ``"rz"`` for Harada 2011 Fig. 6.
        values: its values [m or rad], 1-D.
        pose: task pose giving the fixed coordinates (default: the guess's pose) [m, rad].
        guess: configuration the seed is solved from (default: the reference configuration).
        mode: working mode to keep (default: the seed's).
        tol: inverse-kinematics residual tolerance [m, rad] (default: the mechanism's ``closure_tol``).
        metrics: the metrics to compute (default all; see :func:`workspace_map`).

    Returns:
        The sweep, arrays of shape ``(len(values),)``.

    Raises:
        InvalidInput: see :func:`workspace_map`.
    """
    return _slice(mech, (axis,), (values,), pose, guess, mode, tol, 1, metrics)
