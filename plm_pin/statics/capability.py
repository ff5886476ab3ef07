r"""Force capability: the largest wrench a mechanism holds within its actuator limits.

Loads enter the balance linearly, so the balancing forces for gravity plus a load
:math:`\alpha d` are :math:`f_c = f_g + \alpha f_d + G y`, with :math:`f_g` and :math:`f_d`
the minimum-norm forces for gravity and for the unit load :math:`d`, and :math:`G y` any
internal force. The capability along :math:`d` is the linear programme

.. math:: \max \alpha \quad \text{s.t.} \quad l \le f_g + \alpha f_d + G y \le u,

solved by HiGHS (:func:`~plm_pin.statics.allocation.solve_lp`). A redundant mechanism
chooses :math:`y` to relieve the most loaded actuator, so its capability is never below that
of the same mechanism with an actuator removed. A planar section of the capability set
(the *wrench polygon*) is traced by one such programme per direction of the plane: the set
is convex, so its boundary points along rays from the origin trace it exactly.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import count, load_arguments
from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput, PlmError
from ..results import Result, unit
from ..tolerances import FEASIBILITY_RTOL
from .allocation import Inequalities, allocate, solve_lp
from .balance import Load, load_on_frame, static_balance
from .forces import actuator_limits


@dataclass(frozen=True)
class Capability(Result):
    """Largest load along one direction.

    Attributes:
        direction: the unit load as given (6 values, or one per task coordinate) [N, N m].
        alpha: the largest multiple of ``direction`` held (``inf`` when the structure alone
            holds it, e.g. an out-of-plane force on a planar mechanism).
        f_c: actuator forces at that load [N, N m], shape (n_act,) (NaN when ``alpha`` is inf).
        saturated: actuators at a limit there.
    """

    direction: np.ndarray = field(metadata=unit("N, N m"))
    alpha: float = field(metadata=unit("-"))
    f_c: np.ndarray = field(metadata=unit("N, N m"))
    saturated: tuple[str, ...]


def force_capability(
    mech: Mechanism,
    q: ArrayLike,
    direction: ArrayLike,
    frame: str | None = None,
    *,
    gravity: bool = True,
    limits: Any = "description",
) -> Capability:
    r"""Largest :math:`\alpha \ge 0` such that the mechanism holds the wrench :math:`\alpha d` at ``q``.

    Args:
        mech: the mechanism.
        q: an assembled configuration, shape (nq,).
        direction: the load :math:`d` applied to ``frame`` (see
            :func:`~plm_pin.statics.balance.load_on_frame`); its scale sets the unit of ``alpha``.
        frame: frame the load acts on; default the task frame.
        gravity: the weight of the bodies is held too.
        limits: actuator effort limits (``"description"`` or an (n_act, 2) array); every
            actuator needs finite limits.

    Raises:
        InvalidInput: a malformed or zero direction, or actuators without finite limits.
        AllocationInfeasible: the limits do not even hold gravity (``alpha = 0`` is infeasible).
        SingularConfiguration: the load cannot be resisted at ``q``.
    """
    load_arguments(direction, frame, limits, mech.n_actuators, "direction")
    bounds = _finite_limits(mech, limits, "force capability")
    load = load_on_frame(mech, direction, frame)
    if not np.any(load.wrench if isinstance(load, Load) else load.forces):
        raise InvalidInput(f"direction must be a nonzero load (it sets the unit of alpha), got {direction!r}")
    with_load = static_balance(mech, q, direction, frame, gravity=gravity)
    base = static_balance(mech, q, gravity=gravity) if gravity else None
    f_g = base.f_particular if base is not None else np.zeros(mech.n_actuators)
    f_d = with_load.f_particular - f_g  # (n_act,) forces per unit load (the balance is linear)
    G = with_load.internal_basis  # (n_act, k)
    names = tuple(a.joint for a in mech.actuators)
    scale = max(float(np.max(np.abs(bounds))), 1.0)
    tol = FEASIBILITY_RTOL * scale
    k = G.shape[1]
    # the part of f_d the internal forces cannot cancel; none left: the structure holds the load
    f_d_out = f_d - G @ (G.T @ f_d)
    if np.max(np.abs(f_d_out), initial=0.0) <= tol:
        _check_gravity_held(f_g, G, bounds, names)
        return Capability(np.asarray(direction, dtype=float), float("inf"), np.full(len(names), np.nan), ())
    # variables (y, alpha): max alpha, bounds <= f_g + G y + alpha f_d, alpha >= 0
    rows = Inequalities(names, f_g, np.hstack([G, f_d[:, None]]), bounds[:, 0], bounds[:, 1])
    c = np.zeros(k + 1)
    c[-1] = -1.0
    z = solve_lp(c, rows, "the force-capability programme", [(None, None)] * k + [(0.0, None)])
    if z is None:  # alpha = 0 is infeasible: the limits do not hold gravity
        raise _unheld(mech, f_g, G, bounds, "the force-capability programme")
    alpha = float(z[-1])
    f_c = f_g + G @ z[:k] + alpha * f_d
    saturated = tuple(
        n
        for n, f, (lo, hi) in zip(names, f_c, bounds, strict=True)
        if f <= lo + 1e3 * tol or f >= hi - 1e3 * tol
    )
    return Capability(np.asarray(direction, dtype=float), alpha, f_c, saturated)


def _finite_limits(mech: Mechanism, limits: ArrayLike | None, what: str) -> np.ndarray:
    """The actuator limits, shape (n_act, 2); refused unless every one is finite."""
    bounds = actuator_limits(mech, limits)
    if not np.isfinite(bounds).all():
        unbounded = [a.joint for a, b in zip(mech.actuators, bounds, strict=True) if not np.isfinite(b).all()]
        raise InvalidInput(
            f"{what} needs finite effort limits on every actuator; {unbounded} have none "
            "(add 'limits' to the sidecar's actuation or pass limits=...)"
        )
    return bounds


@dataclass(frozen=True)
class InternalRange(Result):
    r"""The internal forces the actuator limits admit under one load.

    The balancing forces are :math:`f_c = f_p + G y` (:math:`f_p` of minimum norm, :math:`G`
    the orthonormal internal basis of :attr:`StaticBalance.internal_basis`); the admissible
    :math:`y` form the polytope :math:`l \le f_p + G y \le u`. Its extent along each basis
    vector is :attr:`lower` .. :attr:`upper`.

    Attributes:
        lower: smallest admissible coordinate along each internal-force direction, shape (k,) [N, N m].
        upper: largest admissible coordinate along each internal-force direction, shape (k,) [N, N m].
        f_lower: actuator forces at each lower end, shape (k, n_act) [N, N m].
        f_upper: actuator forces at each upper end, shape (k, n_act) [N, N m].
        internal_basis: the basis :math:`G` the coordinates refer to, shape (n_act, k).
    """

    lower: np.ndarray = field(metadata=unit("N, N m"))
    upper: np.ndarray = field(metadata=unit("N, N m"))
    f_lower: np.ndarray = field(metadata=unit("N, N m"))
    f_upper: np.ndarray = field(metadata=unit("N, N m"))
    internal_basis: np.ndarray = field(metadata=unit("-"))


def internal_force_range(
    mech: Mechanism,
    q: ArrayLike,
    wrench: ArrayLike | None = None,
    frame: str | None = None,
    *,
    gravity: bool = True,
    limits: Any = "description",
) -> InternalRange:
    r"""How far each internal force can go while the actuators hold the load within their limits.

    One linear programme per bound: :math:`\min / \max\ y_k` s.t.
    :math:`l \le f_p + G y \le u` (the other coordinates free), solved by HiGHS as in
    :func:`force_capability`. Multiply a direction's
    :class:`~plm_pin.statics.InternalDirection` readings (link axial forces, guide forces) by a
    coordinate to read the preload it stands for.

    Args:
        mech: a redundantly actuated mechanism.
        q: an assembled configuration, shape (nq,).
        wrench: load applied to ``frame`` (see :func:`~plm_pin.statics.balance.load_on_frame`);
            default none.
        frame: frame the load acts on; default the task frame.
        gravity: the weight of the bodies is held too.
        limits: actuator effort limits (``"description"`` or an (n_act, 2) array); every
            actuator needs finite limits.

    Raises:
        InvalidInput: no redundancy (no internal force), a malformed load, or actuators
            without finite limits.
        AllocationInfeasible: the limits do not hold the load at all.
        SingularConfiguration: the load cannot be resisted at ``q``.
    """
    bounds = _finite_limits(mech, limits, "the internal-force range")
    if wrench is None:
        balance = static_balance(mech, q, gravity=gravity)
    else:
        balance = static_balance(mech, q, wrench, frame, gravity=gravity)
    G = balance.internal_basis  # (n_act, k)
    k = G.shape[1]
    if k == 0:
        raise InvalidInput(f"{mech.name} has no internal forces (redundancy {mech.redundancy})")
    names = tuple(a.joint for a in mech.actuators)
    f_p = balance.f_particular
    rows = Inequalities(names, f_p, G, bounds[:, 0], bounds[:, 1])
    ends = np.empty((2, k))
    f_lower, f_upper = np.empty((k, len(names))), np.empty((k, len(names)))
    for side, sign in enumerate((1.0, -1.0)):  # minimise y_k, then -y_k
        for i in range(k):
            y = solve_lp(sign * np.eye(k)[i], rows, "the internal-force range programme")
            if y is None:  # no internal force holds the load within the limits
                raise _unheld(mech, f_p, G, bounds, "the internal-force range programme")
            ends[side, i] = y[i]
            (f_lower if side == 0 else f_upper)[i] = f_p + G @ y
    return InternalRange(ends[0], ends[1], f_lower, f_upper, G.copy())


def _check_gravity_held(f_g: np.ndarray, G: np.ndarray, bounds: np.ndarray, names: tuple[str, ...]) -> None:
    """Raise AllocationInfeasible when no internal force brings the gravity forces within the limits."""
    ineq = Inequalities(names, f_g, G, bounds[:, 0], bounds[:, 1])
    allocate(f_g, G, ineq, weights=np.eye(len(names)), actuator_names=names)


def _unheld(mech: Mechanism, f_p: np.ndarray, G: np.ndarray, bounds: np.ndarray, what: str) -> PlmError:
    """After HiGHS found ``what`` infeasible: raise AllocationInfeasible with the least-violating forces.

    Returns the error to raise when the allocation holds the load after all (a solver disagreement).
    """
    _check_gravity_held(f_p, G, bounds, tuple(a.joint for a in mech.actuators))
    return PlmError(f"{mech.name}: HiGHS found {what} infeasible, yet the limits hold the load")


def wrench_polygon(
    mech: Mechanism,
    q: ArrayLike,
    d1: Any,
    d2: Any,
    frame: str | None = None,
    *,
    n: int = 72,
    gravity: bool = True,
    limits: Any = "description",
) -> np.ndarray:
    r"""Boundary of the loads :math:`a d_1 + b d_2` the mechanism holds, traced along ``n`` rays.

    Args:
        mech: the mechanism.
        q: an assembled configuration.
        d1: first load direction (as for :func:`force_capability`).
        d2: second load direction.
        frame: frame the loads act on; default the task frame.
        n: number of rays (at least 8).
        gravity: hold the bodies' weight too.
        limits: actuator effort limits.

    Returns:
        ``(n, 2)`` coordinates :math:`(a, b)` of the boundary, counter-clockwise from :math:`d_1`
        (``inf`` along rays the structure holds without actuator force).
    """
    n = count(n, "n", minimum=8)
    a = np.asarray(d1, dtype=float)
    b = np.asarray(d2, dtype=float)
    if a.shape != b.shape:
        raise InvalidInput(f"d1 and d2 must have the same shape, got {a.shape} and {b.shape}")
    out = np.empty((int(n), 2))
    for i, phi in enumerate(np.linspace(0.0, 2.0 * np.pi, int(n), endpoint=False)):
        u = np.array([np.cos(phi), np.sin(phi)])
        cap = force_capability(mech, q, u[0] * a + u[1] * b, frame, gravity=gravity, limits=limits)
        out[i] = cap.alpha * u
    return out
