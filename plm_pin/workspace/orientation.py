r"""Singularity-free orientation range: how far the end effector turns from a reference angle.

Along one rotational task coordinate (``rz`` for a planar table), the other coordinates
fixed, the *orientation range* is the largest interval :math:`[\theta_-, \theta_+]` that
holds the reference angle :math:`\theta_0` and over which the mechanism stays reachable in
its working mode and non-singular. Its ends are the singular points and reachable-set
boundaries nearest to :math:`\theta_0` on either side, located by
:func:`plm_pin.workspace.singular_points_along` (Brent root finding of
:math:`\det T \det C` for non-redundant mechanisms, bounded minimisation of the margins for
redundant ones, bisection at a boundary) to ``xtol``. A redundant mechanism's margin
minimum counts only when it reaches zero (at most ``tol``).

The samples ``values`` bracket the search: two singular points between neighbouring
samples may be missed (see :func:`~plm_pin.workspace.singular_points`), and when nothing
ends the range before the first or last sample, that sample is the end (``lower_end`` or
``upper_end`` is ``"grid"``: the range is at least that wide).

The working mode kept is the guess's (the reference configuration's by default,
:func:`~plm_pin.kinematics.guess_mode`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import check_tolerance, finite_number, positive, real_numbers
from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput
from ..kinematics.working_mode import guess_mode, start_configuration
from ..results import Result, unit
from ..tolerances import LOCUS_REFINE_MARGIN, RANGE_XTOL, SINGULARITY_TOL
from .manipulability import MARGIN_METRICS
from .maps import workspace_sweep
from .singular_loci import SingularPoint, line_path, locate_on_solved

ENDS: tuple[str, ...] = ("constraint", "inverse", "direct", "boundary", "grid", "unreachable")
"""What can end an orientation range: a singularity kind, the reachable-set boundary, the samples' end,
or ``"unreachable"`` (the reference angle itself is not reached: the range is NaN)."""


@dataclass(frozen=True)
class OrientationRange(Result):
    """The singularity-free interval of one task coordinate around a reference value.

    Attributes:
        axis: the task coordinate turned (``rx``, ``ry`` or ``rz``; any coordinate works).
        reference: the reference value the interval holds [rad].
        lower: lower end [rad] (NaN when the reference is unreachable).
        upper: upper end [rad] (NaN when the reference is unreachable).
        lower_end: what ends it below, one of :data:`ENDS`.
        upper_end: what ends it above, one of :data:`ENDS`.
        pose: the task pose supplying the other coordinates [m, rad], shape (n_task,).
        points: every singular point and boundary found along the samples, sorted.
    """

    axis: str
    reference: float = field(metadata=unit("rad"))
    lower: float = field(metadata=unit("rad"))
    upper: float = field(metadata=unit("rad"))
    lower_end: str
    upper_end: str
    pose: np.ndarray = field(metadata=unit("m, rad"))
    points: tuple[SingularPoint, ...]
    _DERIVED = ("width",)
    _NONFINITE_AS_TEXT = ("lower", "upper", "width")

    @property
    def width(self) -> float:
        """``upper - lower`` [rad] (NaN when the reference is unreachable)."""
        return self.upper - self.lower


def _ends(point: SingularPoint) -> str | None:
    """What ``point`` ends a range with, or None when it does not (a margin minimum above ``tol``)."""
    if point.method == "boundary":
        return "boundary"
    if point.method == "minimum" and not point.reaches_zero:
        return None
    return point.kind


def orientation_range(
    mech: Mechanism,
    axis: str,
    values: ArrayLike,
    pose: ArrayLike | None = None,
    *,
    reference: float = 0.0,
    guess: ArrayLike | None = None,
    xtol: float = RANGE_XTOL,
    tol: float = SINGULARITY_TOL,
    near: float = LOCUS_REFINE_MARGIN,
    ik_tol: float | None = None,
) -> OrientationRange:
    r"""Largest interval of ``axis`` holding ``reference`` that stays reachable and non-singular.

    Args:
        mech: the mechanism (its task must have as many coordinates as it has DOF).
        axis: the task coordinate turned, e.g. ``"rz"``.
        values: increasing samples of it bracketing the search [rad], shape (n,), n >= 2.
        pose: task pose giving the other coordinates (default: the guess's pose) [m, rad];
            its ``axis`` entry is ignored.
        reference: the value the range must hold, e.g. :math:`\theta = 0` [rad].
        guess: configuration whose working mode is kept (default: the reference configuration).
        xtol: tolerance on the located ends [rad].
        tol: margin at or below which a point is singular.
        near: redundant mechanisms: margin minima below it are refined.
        ik_tol: inverse-kinematics residual tolerance [m, rad] (default: the mechanism's ``closure_tol``).

    Returns:
        The range; NaN ends (``"unreachable"``) when ``reference`` is outside the samples or
        not reached in the working mode.

    Raises:
        InvalidInput: malformed samples or reference, an unknown axis, or a task whose size
            differs from the DOF.
    """
    ts = np.asarray(real_numbers(values, "values"), dtype=float)
    reference = finite_number(reference, "reference", "rad")
    xtol, tol, near = (
        positive(xtol, "xtol", "rad"),
        check_tolerance(tol, "tol"),
        check_tolerance(near, "near"),
    )
    ik_tol = mech.closure_tol if ik_tol is None else positive(ik_tol, "ik_tol", "m, rad")
    if ts.ndim != 1 or ts.size < 2 or not np.all(np.isfinite(ts)) or np.any(np.diff(ts) <= 0.0):
        raise InvalidInput(
            f"values must be an increasing 1-D array of at least 2 finite samples, got {values!r}"
        )
    q0 = start_configuration(mech, guess)
    mode = guess_mode(mech, q0)
    line = workspace_sweep(mech, axis, ts, pose, guess=q0, mode=mode, tol=ik_tol, metrics=MARGIN_METRICS)
    base = line.pose
    nan = math.nan
    unreachable = OrientationRange(axis, float(reference), nan, nan, "unreachable", "unreachable", base, ())
    if not ts[0] <= reference <= ts[-1]:
        return unreachable
    i = int(np.searchsorted(ts, reference, side="right")) - 1
    around = [i] if ts[i] == reference else [i, i + 1]
    if not all(line.reachable[j] for j in around):
        return unreachable
    margins = {
        "direct_margin": line.direct_margin,
        "inverse_margin": line.inverse_margin,
        "constraint_margin": line.constraint_margin,
    }
    assert line.working_mode is not None  # the reference sample was reached
    path = line_path(mech, axis, base, q0)  # the line solved once: its samples seed the search
    found = locate_on_solved(
        mech, path, ts, line.q, line.reachable, margins, line.working_mode, xtol, tol, near, True, ik_tol
    )
    ends = [(p.parameter, end) for p in found if (end := _ends(p)) is not None]
    below = [e for e in ends if e[0] <= reference]
    above = [e for e in ends if e[0] >= reference]
    lower, lower_end = max(below, key=lambda e: e[0]) if below else (float(ts[0]), "grid")
    upper, upper_end = min(above, key=lambda e: e[0]) if above else (float(ts[-1]), "grid")
    return OrientationRange(
        axis, float(reference), float(lower), float(upper), lower_end, upper_end, base, tuple(found)
    )
