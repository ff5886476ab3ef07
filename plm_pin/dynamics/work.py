r"""Work done by each actuator, :math:`W_i = \int |P_i|\,dt`, by two independent quadratures.

- :func:`adaptive_trapezoid_work` is Zhao 2011's rule (eqs. (30)-(34)): the composite
  trapezoid on :math:`2^n` equal intervals, doubled until two successive values differ by at
  most ``tol`` for every actuator; it reports the final exponent :math:`n_1` (the paper's
  ``n1``, an exponent, not a gear ratio). It needs the power at any time, so it takes a
  function (see :func:`power_along`).
- :func:`spline_work` integrates :math:`|P|` of a cubic spline through samples exactly:
  the spline's roots split the interval where the power changes sign, and each piece is
  integrated by the spline's antiderivative. Its error is that of the interpolation
  (fourth order in the sample step), and it does not smear the kinks of :math:`|P|`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import count, positive
from .._lazy import lazy_module
from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput
from ..results import Result, unit
from ..tolerances import ZHAO_WORK_TOL
from .inverse_dynamics import inverse_dynamics
from .trajectory import Profile, task_trajectory

interpolate = lazy_module("scipy.interpolate")  # CubicSpline


@dataclass(frozen=True)
class AdaptiveWork(Result):
    """Result of the adaptive trapezoid rule.

    Attributes:
        work: work of each actuator [J], shape (n_act,).
        n1: the exponent reached: ``2**n1`` intervals.
        change: the last change of the work between ``2**(n1-1)`` and ``2**n1`` intervals [J].
    """

    work: np.ndarray = field(metadata=unit("J"))
    n1: int
    change: np.ndarray = field(metadata=unit("J"))
    _DERIVED = ("intervals",)

    @property
    def intervals(self) -> int:
        """Number of intervals of the last rule, ``2**n1``."""
        return 2**self.n1


def adaptive_trapezoid_work(
    power_at: Callable[[np.ndarray], np.ndarray],
    ts: float,
    te: float,
    *,
    tol: float = ZHAO_WORK_TOL,
    n_max: int = 16,
) -> AdaptiveWork:
    """Zhao 2011 eqs. (30)-(34): trapezoid on ``2**n`` intervals, ``n = 1, 2, ...`` until converged.

    Args:
        power_at: ``times (k,) -> power (k, n_act)`` [W].
        ts: start time [s].
        te: end time [s].
        tol: the largest change allowed between successive rules, for every actuator [J].
        n_max: the largest exponent tried.

    Raises:
        InvalidInput: ``te <= ts``, a non-positive tolerance, or no convergence by ``2**n_max``
            intervals (the message gives the last change).
    """
    if not (np.isfinite(ts) and np.isfinite(te) and te > ts):
        raise InvalidInput(f"need finite ts < te, got ts = {ts}, te = {te}")
    tol, n_max = positive(tol, "tol", "J"), count(n_max, "n_max", minimum=1)
    previous = change = None
    for n in range(1, n_max + 1):
        t = np.linspace(ts, te, 2**n + 1)
        work = np.trapezoid(np.abs(np.asarray(power_at(t), dtype=float)), t, axis=0)
        if previous is not None:
            change = np.abs(work - previous)
            if np.all(change <= tol):
                return AdaptiveWork(work, n, change)
        previous = work
    last = "" if change is None else f"; the last change was {np.max(change):.6g} J"
    raise InvalidInput(f"the trapezoid rule did not converge to {tol} J with 2**{n_max} intervals{last}")


def spline_work(t: ArrayLike, power: ArrayLike) -> np.ndarray:
    r"""Exact :math:`\int |P|\,dt` of the cubic spline through power samples, per actuator [J].

    Args:
        t: increasing sample times [s], shape (n,), n >= 4.
        power: power samples [W], shape (n,) or (n, n_act).

    Returns:
        The work of each column [J], shape (n_act,) (one entry for 1-D power).
    """
    tt = np.asarray(t, dtype=float)
    P = np.asarray(power, dtype=float)
    if tt.ndim != 1 or tt.shape[0] < 4 or P.shape[0] != tt.shape[0] or not np.all(np.diff(tt) > 0):
        raise InvalidInput(
            f"need >= 4 increasing times and one power row per time, got {tt.shape}, {P.shape}"
        )
    if not (np.all(np.isfinite(tt)) and np.all(np.isfinite(P))):
        raise InvalidInput("times and power must be finite")
    columns = P.reshape(tt.shape[0], -1).T
    out = np.empty(columns.shape[0])
    for k, column in enumerate(columns):
        spline = interpolate.CubicSpline(tt, column)
        roots = spline.roots(extrapolate=False)
        edges = np.unique(np.concatenate([[tt[0]], roots, [tt[-1]]]))
        antiderivative = spline.antiderivative()
        out[k] = float(np.sum(np.abs(np.diff(antiderivative(edges)))))
    return out


def power_along(
    mech: Mechanism, profile: Profile | ArrayLike, *, guess: ArrayLike | None = None, **options: Any
) -> Callable[[np.ndarray], np.ndarray]:
    """``times -> actuator power`` along a task profile: trajectory then inverse dynamics at those times.

    Args:
        mech: the mechanism.
        profile: a task profile ``t -> (x, xd, xdd)`` (see :mod:`~plm_pin.dynamics.trajectory`).
        guess: starting configuration for the inverse kinematics.
        options: inverse-dynamics options (allocation, wrench, gravity); see
            :func:`~plm_pin.dynamics.inverse_dynamics.inverse_dynamics`.
    """
    id_options: Mapping[str, Any] = dict(options)

    def power_at(times: np.ndarray) -> np.ndarray:
        traj = task_trajectory(mech, profile, times, guess=guess)
        return inverse_dynamics(mech, traj, **id_options).power

    return power_at
