"""Inverse kinematics: task pose -> assembled configuration, with working modes."""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from .._checks import positive, signs
from ..exceptions import ClosureNotSatisfied, InvalidInput, JointLimitExceeded, PoseUnreachable
from .assembly import assemble
from .closures import Closure, compile_closures
from .forward import same_assembly
from .jacobians import require_task
from .legs import working_mode
from .limits import limit_violations, wrap_into_limits
from .starts import random_starts
from .task import TaskTarget, check_task_vector

if TYPE_CHECKING:
    from ..mechanism import Mechanism

IK_TOL = 1e-12
"""Default residual tolerance of the inverse kinematics [m, rad]."""


@dataclass(frozen=True)
class IKSolution:
    """One inverse-kinematics solution.

    Attributes:
        q: assembled configuration placing the task frame at ``x``, shape (nq,).
        x: the task coordinates asked for [m, rad], shape (n_task,).
        actuators: actuator positions [m, rad], shape (n_act,).
        mode: working mode, one sign per square leg block (0: leg at an actuator singularity).
        residual_norm: largest absolute residual of closures and task [m, rad].
        limit_violations: joints outside their position limits at ``q``, with by how much
            [m or rad] (revolute angles are first shifted by 2 pi into their limits where they fit).
    """

    q: np.ndarray
    x: np.ndarray
    actuators: np.ndarray
    mode: tuple[int, ...]
    residual_norm: float
    limit_violations: Mapping[str, float] = field(default_factory=dict)

    @property
    def within_limits(self) -> bool:
        """Whether every joint respects its position limits."""
        return not self.limit_violations

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "q": self.q.tolist(),
            "x": self.x.tolist(),
            "actuators": self.actuators.tolist(),
            "mode": list(self.mode),
            "residual_norm": self.residual_norm,
            "limit_violations": dict(self.limit_violations),
        }


def _solve(
    mech: Mechanism,
    target: TaskTarget,
    guess: np.ndarray,
    free: np.ndarray,
    tol: float,
    closures: tuple[Closure, ...] | None = None,
) -> np.ndarray:
    return assemble(
        mech.model,
        mech.data,
        mech.closures if closures is None else closures,
        guess,
        free,
        tol=tol,
        max_iterations=60,
        extra=target,
    ).q


def _solution(mech: Mechanism, target: TaskTarget, q: np.ndarray) -> IKSolution:
    q = wrap_into_limits(mech, q)
    pin.framesForwardKinematics(mech.model, mech.data, q)
    res = np.concatenate([mech.closure_residual(q), target.residual(mech.data)])
    return IKSolution(
        q,
        target.x.copy(),
        mech.actuator_positions(q),
        working_mode(mech, q),
        float(np.max(np.abs(res))),
        limit_violations(mech, q),
    )


def inverse_kinematics(
    mech: Mechanism,
    x: Any,
    guess: Any = None,
    *,
    mode: tuple[int, ...] | None = None,
    tol: float = IK_TOL,
    explain: bool = True,
    respect_limits: bool = False,
) -> IKSolution:
    """Solve the inverse kinematics at task coordinates ``x``.

    Newton (Levenberg-Marquardt) on the closures plus the task rows from ``guess``; the
    solution is the one in the guess's basin, normally its working mode. With ``mode``
    the working mode is imposed: all modes are enumerated and the matching one returned.

    Args:
        mech: the mechanism (its task gives the meaning of ``x``).
        x: task coordinates [m, rad], shape (n_task,).
        guess: starting configuration (default: the reference configuration).
        mode: working mode to return, one sign per square leg (see :attr:`IKSolution.mode`).
        tol: largest residual accepted [m, rad].
        explain: on failure, find which leg misses and by how much (a leg-by-leg solve from
            random starts, about 0.2 s on a 2-PRRRP); False raises at once with a short message.
        respect_limits: raise :class:`~plm_pin.exceptions.JointLimitExceeded` when the solution
            puts a joint outside its position limits (otherwise they are reported in
            :attr:`IKSolution.limit_violations`).

    Returns:
        The solution.

    Raises:
        PoseUnreachable: when no assembly puts the task frame at ``x``; the message names
            the leg that cannot reach and by how much it misses (with ``explain``).
        JointLimitExceeded: with ``respect_limits``, when the loops close at ``x`` only with
            joints outside their limits (a subclass of PoseUnreachable naming them).
        InvalidInput: malformed ``x``, ``guess`` or ``mode``, or a task with fewer coordinates
            than the mechanism has DOF (the pose would not determine the configuration).
    """
    mode, tol = signs(mode, "mode"), positive(tol, "tol")
    task = require_task(mech)
    if task.size < mech.mobility:
        raise InvalidInput(
            f"{mech.name}: the task has {task.size} coordinates but the mechanism has {mech.mobility} DOF: "
            "a pose does not determine the configuration; give a task with as many coordinates as DOF"
        )
    xa = check_task_vector(x, task.size)
    target = TaskTarget(task, xa)
    if mode is not None:
        n_square = sum(leg.square for leg in mech.legs)
        if len(mode) != n_square or any(m not in (-1, 1) for m in mode):
            raise InvalidInput(f"mode must hold {n_square} signs (+1 or -1), one per leg; got {mode!r}")
        for sol in working_modes(mech, xa, guess=guess, tol=tol):
            if sol.mode == tuple(mode):
                return sol
        raise PoseUnreachable(
            f"{mech.name}: no inverse-kinematics solution in working mode {tuple(mode)} at x = {xa.tolist()}"
        )
    q0 = mech.q_ref if guess is None else mech.check_q(guess, "guess")
    try:
        q = _solve(mech, target, q0, np.arange(mech.nv), tol)
    except ClosureNotSatisfied:
        if not explain:
            raise PoseUnreachable(
                f"{mech.name}: pose {xa.tolist()} could not be solved from this guess"
            ) from None
        raise _unreachable(mech, target, q0, tol) from None
    sol = _solution(mech, target, q)
    if respect_limits and sol.limit_violations:
        raise JointLimitExceeded(
            f"{mech.name}: pose {xa.tolist()} closes the loops only with joints outside their limits: "
            + ", ".join(f"{k} by {v:.3g}" for k, v in sol.limit_violations.items()),
            dict(sol.limit_violations),
            sol.q,
        )
    return sol


def _solve_leg(
    mech: Mechanism,
    target: TaskTarget,
    q: np.ndarray,
    columns: tuple[int, ...],
    rng: np.random.Generator,
    tol: float,
    n: int,
    closures: tuple[Closure, ...] | None = None,
) -> tuple[list[np.ndarray], float]:
    """Solutions of one leg block (other joints fixed) from ``n`` random starts, and the best miss.

    ``closures`` (default: all) are the closures solved with the task rows; the miss is the
    largest residual among them.
    """
    found: list[np.ndarray] = []
    best = np.inf
    cols = np.array(columns)
    for start in [q, *random_starts(mech, rng, q, columns, n)]:
        try:
            sol = _solve(mech, target, start, cols, tol, closures)
        except ClosureNotSatisfied as exc:
            best = min(best, exc.residual_norm)
            continue
        best = 0.0
        if not any(same_assembly(mech, s, sol) for s in found):
            found.append(sol)
    return found, best


def working_modes(
    mech: Mechanism,
    x: Any,
    guess: Any = None,
    *,
    tol: float = IK_TOL,
    starts_per_leg: int = 12,
    seed: int = 0,
) -> list[IKSolution]:
    """Every inverse-kinematics solution (working mode) at task coordinates ``x``.

    The legs are independent once the task frame is placed (:mod:`plm_pin.kinematics.legs`):
    each leg's branches are found by Newton from random starts on that leg's joints alone,
    and the working modes are all their combinations.

    Args:
        mech: the mechanism.
        x: task coordinates [m, rad], shape (n_task,).
        guess: configuration to start from (default: reference).
        tol: residual tolerance [m, rad].
        starts_per_leg: random starts per leg.
        seed: random seed (results are deterministic for a given seed).

    Returns:
        The solutions, sorted by working mode.

    Raises:
        PoseUnreachable: when some leg cannot reach.
    """
    first = inverse_kinematics(mech, x, guess, tol=tol)
    task = require_task(mech)
    target = TaskTarget(task, first.x)
    rng = np.random.default_rng(seed)
    branches: list[list[np.ndarray | None]] = []
    for leg in mech.legs:
        if not leg.square:
            branches.append([None])
            continue
        columns = leg.columns + leg.followers
        found, _ = _solve_leg(mech, target, first.q, columns, rng, tol, starts_per_leg)
        branches.append([sol[list(_q_indices(mech, columns))] for sol in found])
    out: dict[tuple[int, ...], IKSolution] = {}
    for combo in itertools.product(*branches):
        q = first.q.copy()
        for leg, values in zip(mech.legs, combo, strict=True):
            if values is not None:
                q[list(_q_indices(mech, leg.columns + leg.followers))] = values
        sol = _solution(mech, target, q)
        if sol.residual_norm <= max(tol, 1e-11):
            out.setdefault(sol.mode, sol)
    return [out[k] for k in sorted(out)]


def _q_indices(mech: Mechanism, columns: tuple[int, ...]) -> list[int]:
    """Configuration indices of the joints owning velocity ``columns``."""
    out: list[int] = []
    for jid in range(1, mech.model.njoints):
        j = mech.model.joints[jid]
        if any(j.idx_v <= c < j.idx_v + j.nv for c in columns):
            out.extend(range(j.idx_q, j.idx_q + j.nq))
    return out


def _unreachable(mech: Mechanism, target: TaskTarget, q0: np.ndarray, tol: float) -> PoseUnreachable:
    """Find which leg misses: place the end-effector chain, then try each leg alone.

    The end-effector chain is the leg holding the task rows; each other leg is solved against
    its own closures only, so the gaps of the legs not yet closed do not count as its miss.
    """
    rng = np.random.default_rng(0)
    n_closure = mech.n_closure_rows
    chain = next(leg for leg in mech.legs if any(r >= n_closure for r in leg.rows))
    misses = {}
    # place the end-effector chain on the task alone (closures ignored)
    q = q0.copy()
    try:
        q = assemble(mech.model, mech.data, (), q0, np.array(chain.columns), tol=tol, extra=target).q
    except ClosureNotSatisfied as exc:
        return PoseUnreachable(
            f"{mech.name}: pose {target.x.tolist()} is out of reach of the end-effector chain "
            f"({chain.label}): it misses by {exc.residual_norm:.3g} m/rad"
        )
    for leg in mech.legs:
        if leg is chain:
            continue
        rows = set(leg.rows)
        own = compile_closures(
            mech.model, [c.spec for c in mech.closures if rows.intersection(range(c.rows.start, c.rows.stop))]
        )
        _, miss = _solve_leg(mech, target, q, leg.columns, rng, tol, 12, own)
        if miss > 0.0:
            misses[leg.label] = miss
    if not misses:
        return PoseUnreachable(f"{mech.name}: pose {target.x.tolist()} could not be solved from this guess")
    worst = max(misses, key=lambda k: misses[k])
    return PoseUnreachable(
        f"{mech.name}: pose {target.x.tolist()} is unreachable: leg {worst} misses by {misses[worst]:.3g} m"
        + (
            f" (also {', '.join(f'{k}: {v:.3g} m' for k, v in misses.items() if k != worst)})"
            if len(misses) > 1
            else ""
        )
    )
