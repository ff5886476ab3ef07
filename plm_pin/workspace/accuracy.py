"""Accuracy maps: the pose error bound of :mod:`plm_pin.kinematics.accuracy` over a grid of task poses.

The grid is solved as the workspace maps solve theirs (:func:`plm_pin.workspace.workspace_map`:
continuation in one working mode); at every reached pose the bound of
:func:`~plm_pin.kinematics.accuracy.error_bound` is computed for the given tolerances. Unreached
poses and direct singularities (where the bound is unbounded) hold NaN.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..core.mechanism import Mechanism, require_task
from ..exceptions import SingularConfiguration
from ..kinematics.accuracy import error_bound, error_model
from ..results import Result, unit
from .maps import WorkspaceSlice, workspace_map


@dataclass(frozen=True)
class AccuracyMap(Result):
    """Pose error bounds at every reached point of a workspace slice (NaN elsewhere and where singular).

    Attributes:
        axes: the slice's varied task coordinates.
        values: their grid values [m, rad].
        dofs: the task coordinates the bounds are given for.
        units: the unit of each task coordinate, ``"m"`` or ``"rad"``.
        reachable: points reached by the slice, shape ``shape``.
        worst_case: worst-case error of each task coordinate [m, rad], shape ``shape + (n_task,)``.
        rms: standard deviation of each task coordinate's error [m, rad], shape ``shape + (n_task,)``.
        tolerances: the tolerance of each parameter of the error model [m, rad].
    """

    axes: tuple[str, ...]
    values: tuple[np.ndarray, ...] = field(metadata=unit("m, rad"))
    dofs: tuple[str, ...]
    units: tuple[str, ...]
    reachable: np.ndarray
    worst_case: np.ndarray = field(metadata=unit("m, rad"))
    rms: np.ndarray = field(metadata=unit("m, rad"))
    tolerances: np.ndarray = field(metadata=unit("m, rad"))
    _NONFINITE_AS_TEXT = ("worst_case", "rms", "worst_position", "worst_angle")
    _DERIVED = ("worst_position", "worst_angle")

    @property
    def worst_position(self) -> np.ndarray:
        """Largest worst-case error over the task coordinates in m [m], shape ``shape`` (NaN if none)."""
        return self._largest("m")

    @property
    def worst_angle(self) -> np.ndarray:
        """Largest worst-case error over the task coordinates in rad [rad], shape ``shape`` (NaN if none)."""
        return self._largest("rad")

    def _largest(self, symbol: str) -> np.ndarray:
        picked = [k for k, u in enumerate(self.units) if u == symbol]
        if not picked:
            return np.full(self.reachable.shape, np.nan)
        return np.asarray(np.max(self.worst_case[..., picked], axis=-1))


def accuracy_over(mech: Mechanism, grid: WorkspaceSlice, tolerances: ArrayLike) -> AccuracyMap:
    """The pose error bound at the configurations of a workspace slice.

    Args:
        mech: the mechanism the slice was computed for.
        grid: a slice from :func:`plm_pin.workspace.workspace_map` (or ``workspace_grid``).
        tolerances: one per parameter of :func:`plm_pin.kinematics.error_model` [m or rad]
            (:meth:`~plm_pin.kinematics.ErrorModel.tolerances` makes them).

    Returns:
        The bounds, NaN where the slice is unreached or the pose is a direct singularity.

    Raises:
        InvalidInput: malformed tolerances, a mechanism without a task.
    """
    task = require_task(mech)
    shape = grid.reachable.shape
    worst = np.full((*shape, task.size), np.nan)
    rms = np.full((*shape, task.size), np.nan)
    tol = error_model(mech).check(tolerances)
    for index in zip(*np.nonzero(grid.reachable), strict=True):
        try:
            bound = error_bound(mech, grid.q[index], tol)
        except SingularConfiguration:
            continue
        worst[index], rms[index] = bound.worst_case, bound.rms
    units = tuple("rad" if k in task.angles else "m" for k in range(task.size))
    for arr in (worst, rms, tol):
        arr.setflags(write=False)
    return AccuracyMap(grid.axes, grid.values, tuple(task.dofs), units, grid.reachable, worst, rms, tol)


def accuracy_map(
    mech: Mechanism,
    axes: tuple[str, str],
    values: tuple[ArrayLike, ArrayLike],
    tolerances: ArrayLike,
    pose: ArrayLike | None = None,
    *,
    guess: ArrayLike | None = None,
    mode: tuple[int, ...] | None = None,
    tol: float | None = None,
    workers: int | None = None,
) -> AccuracyMap:
    """Worst-case and RMS pose error over a 2-D grid of task poses.

    Args:
        mech: the mechanism (its task must have as many coordinates as it has DOF).
        axes: the two varied task coordinates, e.g. ``("x", "y")``.
        values: their grid values [m or rad], two 1-D arrays.
        tolerances: one per parameter of :func:`plm_pin.kinematics.error_model` [m or rad].
        pose: task pose giving the fixed coordinates (default: the guess's pose) [m, rad].
        guess: configuration the seed is solved from (default: the reference configuration).
        mode: working mode to keep (default: the one the seed is solved in from ``guess``).
        tol: inverse-kinematics residual tolerance [m, rad] (default: the mechanism's ``closure_tol``).
        workers: processes the grid is solved with (see :func:`~plm_pin.workspace.workspace_map`).

    Returns:
        The bounds, arrays of shape ``(len(values[0]), len(values[1]), n_task)``.

    Raises:
        InvalidInput: see :func:`~plm_pin.workspace.workspace_map`, and malformed tolerances.
    """
    grid = workspace_map(mech, axes, values, pose, guess=guess, mode=mode, tol=tol, workers=workers)
    return accuracy_over(mech, grid, tolerances)
