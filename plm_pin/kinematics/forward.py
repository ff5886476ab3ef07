"""Forward kinematics: actuator positions -> every assembly mode."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import count, flag, positive
from ..core.assembly import LM_MAX_ITERATIONS, assemble, newton, not_closed
from ..core.mechanism import Mechanism, require_task
from ..core.task import check_task_vector
from ..exceptions import ClosureNotSatisfied, InvalidInput, PoseUnreachable
from ..kernels import kernel_of
from ..results import Result, unit
from ..tolerances import FK_SAME_MODE_TOL, SAME_ASSEMBLY_TOL
from ..warnings import IncompleteSearchWarning
from .starts import random_starts

FK_METHODS = ("auto", "multi-start")
"""Search methods of :func:`forward_kinematics` with ``all_modes``."""


@dataclass(frozen=True)
class FKSolution(Result):
    """One forward-kinematics solution (assembly mode).

    Attributes:
        q: assembled configuration, shape (nq,).
        x: task coordinates of the end-effector frame [m, rad], shape (n_task,).
        residual_norm: largest absolute closure residual [m, rad].
        certified: proven by an interval (Krawczyk) test to be the one root in its box
            (homotopy); False for a root that failed the test or one multi-start found.
    """

    q: np.ndarray = field(metadata=unit("m, rad"))
    x: np.ndarray = field(metadata=unit("m, rad"))
    residual_norm: float = field(metadata=unit("m, rad"))
    certified: bool = field(default=False, metadata=unit("-"))


class FKModes(list[FKSolution]):
    """The assembly modes found by :func:`forward_kinematics`, with how far the search is proven.

    A list of :class:`FKSolution` (sorted by task coordinates) with:

    Attributes:
        method: ``"homotopy"`` (complete search, :mod:`plm_pin.kinematics.homotopy`) or
            ``"multi-start"``.
        complete: whether every assembly mode is proven found (homotopy: every generic path
            ended at its own non-singular root; multi-start: never).
        generic_count: number of complex solutions of the closures at generic actuator values
            (homotopy only, else None).
        certified: real modes proven by an interval (Krawczyk) test, before the polish.
        why_incomplete: what kept the search from being complete ('' when complete).
    """

    method: str = "multi-start"
    complete: bool = False
    generic_count: int | None = None
    certified: int = 0
    why_incomplete: str = "multi-start Newton cannot prove that no assembly mode was missed"

    def headline(self) -> str:
        """One line saying how many modes were found and how far that is proven.

        "all N assembly modes (certified; G complex roots)" when complete, else how many were found
        and why the list is not proven complete.
        """
        if self.complete:
            return f"all {len(self)} assembly modes (certified; {self.generic_count} complex roots)"
        return f"{len(self)} assembly modes found, not proven complete: {self.why_incomplete}"

    def to_dict(self) -> dict[str, Any]:
        """The modes and the search's outcome as JSON-ready data."""
        return {
            "modes": [s.to_dict() for s in self],
            "method": self.method,
            "complete": self.complete,
            "generic_count": self.generic_count,
            "certified": self.certified,
            "why_incomplete": self.why_incomplete,
        }


_FALLBACK_WARNED: set[str] = set()


def _homotopy_modes(mech: Mechanism, c: np.ndarray, tol: float) -> FKModes | None:
    """Every assembly mode by parameter homotopy, or None when the mechanism has no polynomial form."""
    from .homotopy import NotPolynomial, prepared, solve_homotopy
    from .homotopy.polynomial import aim_legs, to_configuration

    try:
        form, _ = prepared(mech)
    except NotPolynomial as exc:
        if mech.name not in _FALLBACK_WARNED:
            _FALLBACK_WARNED.add(mech.name)
            warnings.warn(
                f"{mech.name}: no polynomial form of the closures ({exc}); forward kinematics falls back "
                "to multi-start Newton, which cannot prove that every assembly mode was found",
                IncompleteSearchWarning,
                stacklevel=3,
            )
        return None
    res = solve_homotopy(mech, c)
    free = mech.passive_v_indices
    X = np.array([r.x for r in res.real] + list(res.uncertified)).reshape(-1, form.n)
    certified = [True] * len(res.real) + [False] * len(res.uncertified)  # kept: complete=False
    complete = res.complete
    qs = _with_actuators(mech, to_configuration(form, mech, X, c[form.parameters]), c)
    # the legs reduced to distances: their angles again, in closed form
    if form.eliminated_v.size and len(qs):
        qs, aimed = aim_legs(form, mech, qs, mech._thread_workspace().data)
        if not aimed:  # a leg of another shape: Newton on its joints alone
            qs = np.array([_fit_eliminated(mech, q, form.eliminated_v, tol) for q in qs])
    closed: list[FKSolution] = []
    for q, proven in zip(qs, certified, strict=True):
        try:
            q, residual_norm, x = _close(mech, q, free, tol)
        except ClosureNotSatisfied:  # a root the full model does not close: not a mode, and not proven
            complete = False
            continue
        closed.append(FKSolution(q, x, residual_norm, proven))
    out = FKModes(_distinct_modes(mech, closed))
    out.method, out.complete = "homotopy", complete
    out.generic_count, out.certified = res.generic_count, len(res.real)
    out.why_incomplete = res.why_incomplete() or (
        "" if complete else "a root of the polynomial form does not close the full model's loops"
    )
    return out


def _distinct_modes(mech: Mechanism, solutions: list[FKSolution]) -> list[FKSolution]:
    """The solutions that are no earlier kept solution's mode, in order: every frame origin and the task pose.

    The task poses are compared at once (angles modulo 2 pi), the frame origins only where they
    agree. A half-turn of a symmetric platform can leave every frame origin in place and still turn
    the end effector: the task pose tells the two apart.
    """
    if len(solutions) < 2:
        return solutions
    x = np.array([s.x for s in solutions], dtype=float)
    d = x[None] - x[:, None]  # d[k, j]: solution j's pose less solution k's
    task = mech.task
    if task is not None:
        turns = [i for i, dof in enumerate(task.dofs) if dof.startswith("r")]
        d[..., turns] = (d[..., turns] + np.pi) % (2 * np.pi) - np.pi
    order = np.arange(len(solutions))
    near = np.all(np.abs(d) < FK_SAME_MODE_TOL, axis=2) & (order[:, None] > order)  # k against earlier ones
    kept = np.ones(len(solutions), dtype=bool)
    for k in np.flatnonzero(near.any(axis=1)).tolist():  # in order: the solutions before k are settled
        earlier = np.flatnonzero(near[k, :k] & kept[:k]).tolist()
        kept[k] = not any(same_assembly(mech, solutions[j].q, solutions[k].q) for j in earlier)
    return [s for s, keep in zip(solutions, kept.tolist(), strict=True) if keep]


def _fit_eliminated(mech: Mechanism, q: np.ndarray, columns: np.ndarray, tol: float) -> np.ndarray:
    """Close the loops moving only ``columns`` (the joints of the legs reduced to distances)."""
    try:
        return _close(mech, q, columns, tol)[0]
    except ClosureNotSatisfied:
        pass
    for start in random_starts(mech, np.random.default_rng(0), q, columns, 8):
        try:
            return _close(mech, start, columns, tol)[0]
        except ClosureNotSatisfied:
            continue
    return q  # left to the full polish


def _with_actuators(mech: Mechanism, q: np.ndarray, c: np.ndarray) -> np.ndarray:
    """A copy of ``q`` (nq,), or of each row of ``q`` (N, nq), with the actuated joints at ``c``."""
    out = q.copy()
    simple = vars(mech).get(_ONE_COORDINATE)
    if simple is None:  # the actuated coordinates when every actuated joint has one (read once per mechanism)
        indices = mech.actuated_q_indices
        indices.setflags(write=False)
        one = all(mech.model.nqs[a.joint_id] == 1 for a in mech.actuators)
        simple = vars(mech)[_ONE_COORDINATE] = (indices if one else False,)
    if simple[0] is not False:
        out[..., simple[0]] = c
        return out
    nqs = mech.model.nqs
    for row in out.reshape(-1, out.shape[-1]):
        for a, value in zip(mech.actuators, c, strict=True):
            if nqs[a.joint_id] == 1:
                row[a.idx_q] = value
            else:  # an unbounded revolute: (cos, sin)
                mech.set_joint(row, a.joint, value)
    return out


_ONE_COORDINATE = "_actuators_one_coordinate"
"""Attribute of a mechanism: a 1-tuple of the actuated configuration indices (read-only) when each
actuated joint has one configuration coordinate, else of False."""


def frame_distance(mech: Mechanism, q1: np.ndarray, q2: np.ndarray) -> float:
    """Largest coordinate difference between the frame origins of two configurations [m]."""
    data = mech.data
    pin.framesForwardKinematics(mech.model, data, q1)
    first = np.array([M.translation for M in data.oMf])
    pin.framesForwardKinematics(mech.model, data, q2)
    second = np.array([M.translation for M in data.oMf])
    return float(np.max(np.abs(first - second)))


def same_assembly(mech: Mechanism, q1: np.ndarray, q2: np.ndarray, tol: float = SAME_ASSEMBLY_TOL) -> bool:
    """Whether two configurations put every frame origin at the same place [m].

    Angles equal modulo 2 pi, and the two joint-angle sets of a universal joint that point
    an axisymmetric strut the same way, count as the same assembly.

    Raises:
        InvalidInput: a ``tol`` that is not a positive number [m].
    """
    tol = positive(tol, "tol", "m")
    return frame_distance(mech, q1, q2) < tol


def task_pose(mech: Mechanism, q: ArrayLike) -> np.ndarray:
    """Task coordinates of the end-effector frame at ``q`` [m, rad], shape (n_task,)."""
    task = require_task(mech)
    pin.framesForwardKinematics(mech.model, mech.data, mech.check_q(q))
    return task.pose_from_data(mech.data)


def _close(
    mech: Mechanism, start: np.ndarray, free: np.ndarray, tol: float, newton_tried: bool = False
) -> tuple[np.ndarray, float, np.ndarray]:
    """Close the loops moving the ``free`` columns: Newton first (on the kernels where they serve), else LM.

    ``newton_tried`` says the kernels' Newton already stalled from ``start`` (LM only then).

    Returns:
        The configuration (read-only), its largest closure residual and its task pose
        (empty without a task), from the solver's last pass.

    Raises:
        ClosureNotSatisfied: when neither reaches ``tol``.
    """
    kernel = kernel_of(mech)
    if kernel is not None and not newton_tried:
        solved = kernel.solve(start, free, tol)
        if solved is not None:
            q, _, x, residual_norm, _ = solved
            q.setflags(write=False)
            return q, residual_norm, x
    ws = mech._thread_workspace()
    r_phi, A_phi = ws.closure_rows
    fast = (
        None
        if kernel is not None
        else newton(mech.model, ws.data, mech.closures, start, free, r_phi, A_phi, tol=tol)
    )
    if fast is None and kernel is not None:  # Levenberg-Marquardt, compiled
        q, r, closed = kernel.assemble(start, free, tol, max_iterations=LM_MAX_ITERATIONS)
        if not closed:
            raise not_closed(q, r, tol)
        residual_norm = float(np.abs(r).max()) if r.size else 0.0
        q.setflags(write=False)
        pin.framesForwardKinematics(mech.model, ws.data, q)
    elif fast is None:
        asm = assemble(
            mech.model, ws.data, mech.closures, start, free, tol=tol, max_iterations=LM_MAX_ITERATIONS
        )
        q, residual_norm = asm.q, asm.residual_norm
        pin.framesForwardKinematics(mech.model, ws.data, q)
    else:
        q, residual_norm = fast[0], float(np.abs(r_phi).max()) if r_phi.size else 0.0
        q.setflags(write=False)
    task = mech.task_compiled
    return q, residual_norm, task.pose_from_data(ws.data) if task is not None else np.zeros(0)


def _guess_mode(mech: Mechanism, c: np.ndarray, q0: np.ndarray, free: np.ndarray, tol: float) -> FKModes:
    """The assembly mode in the basin of ``q0`` with the actuators at ``c`` (``all_modes=False``).

    On the kernels first, solving in the start itself (built here, no copy to keep), then
    :func:`_close` from a fresh start when their Newton stalls.

    Raises:
        PoseUnreachable: when the loops cannot be closed from ``q0``.
    """
    kernel = kernel_of(mech)
    solved = None if kernel is None else kernel.solve(_with_actuators(mech, q0, c), free, tol, in_place=True)
    if solved is not None:
        q, _, x, residual_norm, _ = solved
        q.setflags(write=False)
    else:
        try:
            q, residual_norm, x = _close(mech, _with_actuators(mech, q0, c), free, tol, kernel is not None)
        except ClosureNotSatisfied as exc:
            miss: float | None = exc.residual_norm
        else:
            miss = None
        if miss is not None:  # raised here, not in the handler: no chained ClosureNotSatisfied
            raise _no_assembly(mech, c, miss, 1)
    found = FKModes()
    found.append(FKSolution(q, x, residual_norm))
    return found


def _no_assembly(mech: Mechanism, c: np.ndarray, best: float, n_starts: int) -> PoseUnreachable:
    """The error for actuators at ``c``: no start closed the loops (smallest residual ``best``)."""
    return PoseUnreachable(
        f"{mech.name}: no assembly with actuators at {c.tolist()}: the loops cannot be closed "
        f"(smallest residual {best:.3g} m/rad over {n_starts} starts)"
    )


def forward_kinematics(
    mech: Mechanism,
    actuators: ArrayLike,
    guess: ArrayLike | None = None,
    *,
    all_modes: bool = True,
    starts: int = 48,
    seed: int = 0,
    tol: float | None = None,
    method: str = "auto",
) -> FKModes:
    """Assemble the mechanism with its actuators at ``actuators``: every assembly mode found.

    With ``all_modes``, a mechanism whose closures have a polynomial form (revolute,
    prismatic, spherical and free-flyer loop joints, see
    :mod:`plm_pin.kinematics.homotopy`) gets every assembly mode by parameter homotopy,
    each real one certified by an interval test, and ``complete=True`` on the result when
    no path was lost. Other mechanisms (said once by an
    :class:`~plm_pin.warnings.IncompleteSearchWarning`), and ``all_modes=False``, use
    multi-start Newton on the closures with the actuated joints fixed: from ``guess`` (or
    the reference configuration) and, with ``all_modes``, from ``starts`` random
    configurations; solutions are de-duplicated by configuration. Deterministic for a
    given ``seed``.

    Args:
        mech: the mechanism.
        actuators: actuator positions [m, rad], shape (n_act,).
        guess: first starting configuration.
        all_modes: look for every assembly mode (otherwise only the guess's).
        starts: random starts when ``all_modes``.
        seed: random seed.
        tol: closure tolerance [m, rad] (default: the mechanism's ``closure_tol``).
        method: with ``all_modes``, ``"auto"`` (the homotopy where the closures have a
            polynomial form, else multi-start) or ``"multi-start"``.

    Returns:
        The solutions, sorted by task coordinates (the guess's first when not ``all_modes``),
        with the search's outcome (:class:`FKModes`).

    Raises:
        PoseUnreachable: when no start closes the loops (no real assembly), with the
            smallest residual reached.
        InvalidInput: malformed inputs.
    """
    starts, seed = count(starts, "starts"), count(seed, "seed")
    tol = mech.closure_tol if tol is None else positive(tol, "tol")
    flag(all_modes, "all_modes")
    if method not in FK_METHODS:
        raise InvalidInput(f"method must be one of {list(FK_METHODS)}, got {method!r}")
    n_actuators = mech.n_actuators
    c = check_task_vector(actuators, n_actuators, "actuators")
    if mech.mobility > n_actuators:
        raise InvalidInput(
            f"{mech.name} has {mech.mobility} DOF but {n_actuators} actuators: fixing them does not "
            "determine the configuration"
        )
    q0 = mech.q_ref if guess is None else mech.check_q(guess, "guess")
    free = mech.passive_v_indices  # actuators are one-DOF joints
    if not all_modes:
        return _guess_mode(mech, c, q0, free, tol)
    homotopy = _homotopy_modes(mech, c, tol) if method == "auto" else None
    if homotopy is not None and homotopy.complete:
        found = homotopy
        if not found:
            raise PoseUnreachable(
                f"{mech.name}: no assembly with actuators at {c.tolist()}: the closures have no real "
                f"solution (none of the {found.generic_count} complex roots is real and closes every loop)"
            )
        found.sort(key=lambda s: tuple(np.round(s.x, 9)))
        return found
    rng = np.random.default_rng(seed)
    starts_q = [_with_actuators(mech, q0, c)]
    starts_q += [_with_actuators(mech, q, c) for q in random_starts(mech, rng, q0, free, starts)]
    found = FKModes() if homotopy is None else homotopy  # an incomplete homotopy: multi-start adds
    if homotopy is not None:
        homotopy.why_incomplete += "; multi-start Newton added what its starts found"
    best = np.inf
    for start in starts_q:
        try:
            q, residual_norm, x = _close(mech, start, free, tol)
        except ClosureNotSatisfied as exc:
            best = min(best, exc.residual_norm)
            continue
        if found and any(same_assembly(mech, s.q, q) for s in found):
            continue
        found.append(FKSolution(q, x, residual_norm))
    if not found:
        raise _no_assembly(mech, c, best, len(starts_q))
    found.sort(key=lambda s: tuple(np.round(s.x, 9)))
    return found
