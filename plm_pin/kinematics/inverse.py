"""Inverse kinematics: task pose -> assembled configuration, with working modes."""

from __future__ import annotations

import functools
import itertools
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import count, flag, positive, signs
from ..core import closures as _closures
from ..core.assembly import LM_MAX_ITERATIONS, assemble, newton
from ..core.closures import Closure, compile_closures
from ..core.closures import closure_rows as _closure_rows
from ..core.mechanism import Mechanism, require_task
from ..core.task import TaskTarget, check_task_vector
from ..exceptions import ClosureNotSatisfied, InvalidInput, JointLimitExceeded, PoseUnreachable
from ..kernels import kernel_of
from ..results import Result, unit
from ..tolerances import BRANCH_TOL
from .forward import same_assembly
from .limits import limit_violations, wrap_into_limits
from .starts import random_starts
from .working_mode import working_mode


@dataclass(frozen=True)
class IKSolution(Result):
    """One inverse-kinematics solution.

    The actuator positions and the working mode are derived from ``q`` when first read (the
    mode costs a Pinocchio pass and a sign per leg block, which a caller that only wants
    ``q`` does not pay).

    Attributes:
        q: assembled configuration placing the task frame at ``x``, shape (nq,).
        x: the task coordinates asked for [m, rad], shape (n_task,).
        residual_norm: largest absolute residual of closures and task [m, rad].
        limit_violations: joints outside their position limits at ``q``, with by how much
            [m or rad] (revolute angles are first shifted by 2 pi into their limits where they fit).
    """

    q: np.ndarray = field(metadata=unit("m, rad"))
    x: np.ndarray = field(metadata=unit("m, rad"))
    residual_norm: float = field(metadata=unit("m, rad"))
    limit_violations: Mapping[str, float] = field(metadata=unit("m, rad"))
    _mech: Mechanism = field(repr=False, compare=False)
    _DERIVED = ("actuators", "mode")
    _SKIPPED = ("_mech",)

    @functools.cached_property
    def actuators(self) -> np.ndarray:
        """Actuator positions [m, rad], shape (n_act,)."""
        return self._mech.actuator_positions(self.q)

    @functools.cached_property
    def mode(self) -> tuple[int, ...]:
        """Working mode, one sign per square leg block (0: leg at an actuator singularity)."""
        return working_mode(self._mech, self.q)

    @property
    def within_limits(self) -> bool:
        """Whether every joint respects its position limits."""
        return not self.limit_violations


def _solve(
    mech: Mechanism,
    target: TaskTarget,
    guess: np.ndarray,
    free: np.ndarray,
    tol: float,
    closures: tuple[Closure, ...] | None = None,
) -> np.ndarray:
    """Newton from ``guess`` (:func:`plm_pin.core.assembly.newton`; on the kernels for all closures), else LM.

    Raises:
        ClosureNotSatisfied: when neither reaches ``tol``.
    """
    all_free = free.size == mech.nv
    kernel = kernel_of(mech) if closures is None else None
    ws = mech._thread_workspace()
    chosen = mech.closures if closures is None else closures
    fast: tuple[Any, ...] | None
    if kernel is not None:
        fast = kernel.newton(guess, None if all_free else free, tol, target)
    else:
        if closures is None:
            r, A = ws.residual, ws.jacobian
        else:
            n = _closure_rows(chosen) + target.size
            r, A = np.empty(n), np.empty((n, mech.nv))
        fast = newton(
            mech.model, ws.data, chosen, guess, None if all_free else free, r, A, tol=tol, extra=target
        )
    if fast is not None:
        return fast[0]
    return assemble(
        mech.model,
        ws.data,
        chosen,
        guess,
        free,
        tol=tol,
        max_iterations=60,
        extra=target,
    ).q


def _solution(mech: Mechanism, target: TaskTarget, q: np.ndarray) -> IKSolution:
    """The solution at ``q``, its residual from one Pinocchio pass."""
    ws = mech._thread_workspace()
    pin.framesForwardKinematics(mech.model, ws.data, q)
    r_phi, _ = ws.closure_rows
    r_x, _ = ws.task_rows
    _closures.residual_from_placements(ws.data, mech.closures, r_phi)
    target.residual(ws.data, r_x)
    return _solution_from_residual(mech, target.x, q, ws.residual)


def _solution_from_residual(mech: Mechanism, x: np.ndarray, q: np.ndarray, r: np.ndarray) -> IKSolution:
    """The solution at ``q`` for the task coordinates ``x``, whose stacked residual (closures, task) is ``r``.

    Revolute angles are shifted by 2 pi into their limits where they fit (the same
    placements, the same mode); a configuration inside every limit is kept as it is.
    """
    model = mech.model
    if (model.lowerPositionLimit <= q).all() and (q <= model.upperPositionLimit).all():
        q, violations = np.array(q), {}  # nothing to shift, nothing outside
    else:
        q = wrap_into_limits(mech, q)
        violations = limit_violations(mech, q)
    q.setflags(write=False)
    residual_norm = float(abs(r).max()) if r.size else 0.0
    return IKSolution(q, x.copy(), residual_norm, violations, mech)


def check_mode(mech: Mechanism, mode: object) -> tuple[int, ...] | None:
    """``mode`` as a tuple if it is None or a working mode of ``mech``: one sign (+1 or -1) per square leg.

    Raises:
        InvalidInput: naming ``mode``, the number of signs wanted and what it got.
    """
    signed = signs(mode, "mode")
    if signed is not None:
        n_square = sum(leg.square for leg in mech.legs)
        if len(signed) != n_square or any(m not in (-1, 1) for m in signed):
            raise InvalidInput(f"mode must hold {n_square} signs (+1 or -1), one per leg; got {mode!r}")
    return signed


def inverse_kinematics(
    mech: Mechanism,
    x: ArrayLike,
    guess: ArrayLike | None = None,
    *,
    mode: tuple[int, ...] | None = None,
    tol: float | None = None,
    explain: bool = True,
    respect_limits: bool = False,
) -> IKSolution:
    """Solve the inverse kinematics at task coordinates ``x``.

    Newton on the closures plus the task rows from ``guess`` (Cholesky steps of the normal
    equations, Levenberg-Marquardt only when Newton stalls); the solution is the one in the
    guess's basin, normally its working mode. With ``mode`` the working mode is imposed: the
    solution from the guess is returned when its signs match, otherwise all modes are
    enumerated and the matching one returned.

    Args:
        mech: the mechanism (its task gives the meaning of ``x``).
        x: task coordinates [m, rad], shape (n_task,).
        guess: starting configuration (default: the reference configuration).
        mode: working mode to return, one sign per square leg (see :attr:`IKSolution.mode`).
        tol: largest residual accepted [m, rad] (default: the mechanism's ``closure_tol``).
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
    mode = signs(mode, "mode")
    tol = mech.closure_tol if tol is None else positive(tol, "tol")
    flag(explain, "explain"), flag(respect_limits, "respect_limits")
    task = require_task(mech)
    n_task = task.size
    if n_task < mech.mobility:
        raise InvalidInput(
            f"{mech.name}: the task has {n_task} coordinates but the mechanism has {mech.mobility} DOF: "
            "a pose does not determine the configuration; give a task with as many coordinates as DOF"
        )
    xa = check_task_vector(x, n_task)
    q0 = mech.q_ref if guess is None else mech.check_q(guess, "guess")
    if mode is None:  # the guess's basin, on the kernels first: no TaskTarget to build when they solve it
        kernel = kernel_of(mech)
        if kernel is not None:
            solved = kernel.solve_pose(q0, tol, task, xa)
            if solved is not None:
                return _within_limits(mech, _kernel_solution(mech, xa, solved), respect_limits)
        target = TaskTarget(task, xa)
        solution = _from_guess(mech, target, q0, tol, newton_tried=kernel is not None)
        if solution is not None:
            return _within_limits(mech, solution, respect_limits)
        if not explain:
            raise PoseUnreachable(f"{mech.name}: pose {xa.tolist()} could not be solved from this guess")
        raise _unreachable(mech, target, q0, tol)
    check_mode(mech, mode)
    first = _from_guess(mech, TaskTarget(task, xa), q0, tol)
    if first is not None and first.mode == tuple(mode):
        return _within_limits(mech, first, respect_limits)
    for sol in working_modes(mech, xa, guess=guess, tol=tol):
        if sol.mode == tuple(mode):
            return _within_limits(mech, sol, respect_limits)
    raise PoseUnreachable(
        f"{mech.name}: no inverse-kinematics solution in working mode {tuple(mode)} at x = {xa.tolist()}"
    )


def _within_limits(mech: Mechanism, sol: IKSolution, respect_limits: bool) -> IKSolution:
    """``sol``, refused with ``respect_limits`` when it puts joints outside their limits."""
    if respect_limits and sol.limit_violations:
        raise JointLimitExceeded(
            f"{mech.name}: pose {sol.x.tolist()} closes the loops only with joints outside their limits: "
            + ", ".join(f"{k} by {v:.3g}" for k, v in sol.limit_violations.items()),
            dict(sol.limit_violations),
            sol.q,
        )
    return sol


def _kernel_solution(
    mech: Mechanism, x: np.ndarray, solved: tuple[np.ndarray, np.ndarray, np.ndarray, float, bool]
) -> IKSolution:
    """The solution from :meth:`~plm_pin.kernels.Kernel.solve`'s answer for the task coordinates ``x``.

    The kernels give the residual norm and whether the solution is within limits.
    """
    q, r, _, residual_norm, inside = solved
    if inside:  # nothing to shift, nothing outside
        q.setflags(write=False)
        return IKSolution(q, x.copy(), residual_norm, {}, mech)
    return _solution_from_residual(mech, x, q, r)


def _from_guess(
    mech: Mechanism, target: TaskTarget, q0: np.ndarray, tol: float, newton_tried: bool = False
) -> IKSolution | None:
    """The solution in the basin of the (checked) configuration ``q0``, or None.

    Newton first (on the compiled kernels where :func:`~plm_pin.kernels.kernel_of` serves the
    mechanism), unless ``newton_tried`` says the kernels' Newton already stalled from ``q0``;
    its last pass gives the residual of the solution. Levenberg-Marquardt when Newton stalls
    (on the kernels too).
    """
    ws = mech._thread_workspace()
    kernel = kernel_of(mech)
    if not newton_tried:
        if kernel is not None:
            solved = kernel.solve(q0, None, tol, target)
            if solved is not None:
                return _kernel_solution(mech, target.x, solved)
        else:
            fast = newton(
                mech.model, ws.data, mech.closures, q0, None, ws.residual, ws.jacobian, tol=tol, extra=target
            )
            if fast is not None:
                return _solution_from_residual(mech, target.x, fast[0], ws.residual)
    if kernel is not None:
        q, r, closed = kernel.assemble(q0, None, tol, target, max_iterations=LM_MAX_ITERATIONS)
        return _solution_from_residual(mech, target.x, q, r) if closed else None
    try:
        q = assemble(
            mech.model,
            ws.data,
            mech.closures,
            q0,
            np.arange(mech.nv),
            tol=tol,
            max_iterations=LM_MAX_ITERATIONS,
            extra=target,
        ).q
    except ClosureNotSatisfied:
        return None
    return _solution(mech, target, q)


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
    x: ArrayLike,
    guess: ArrayLike | None = None,
    *,
    tol: float | None = None,
    starts_per_leg: int = 12,
    seed: int = 0,
) -> list[IKSolution]:
    """Every inverse-kinematics solution (working mode) at task coordinates ``x``.

    The legs are independent once the task frame is placed (:mod:`plm_pin.core.legs`):
    each leg's branches are found by Newton from random starts on that leg's joints alone,
    and the working modes are all their combinations.

    Args:
        mech: the mechanism.
        x: task coordinates [m, rad], shape (n_task,).
        guess: configuration to start from (default: reference).
        tol: residual tolerance [m, rad] (default: the mechanism's ``closure_tol``).
        starts_per_leg: random starts per leg.
        seed: random seed (results are deterministic for a given seed).

    Returns:
        The solutions, sorted by working mode.

    Raises:
        PoseUnreachable: when some leg cannot reach.
        InvalidInput: malformed inputs, ``starts_per_leg`` not a whole number >= 1 or ``seed`` not
            one >= 0.
    """
    starts_per_leg, seed = count(starts_per_leg, "starts_per_leg", minimum=1), count(seed, "seed")
    first = inverse_kinematics(mech, x, guess, tol=tol)
    tol = mech.closure_tol if tol is None else tol
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
        if sol.residual_norm <= max(tol, BRANCH_TOL):
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
