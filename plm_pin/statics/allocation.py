r"""Redundant actuator-force allocation: which balancing forces to apply, as a small QP.

Every balancing allocation is :math:`f_c = f_p + G y` (:mod:`plm_pin.statics.balance`), so the
problem is posed in the internal-force coordinates :math:`y` (as many as the redundancy):

- ``"norm"``: minimise :math:`\tfrac12 f_c^T W f_c` (weighted minimum norm; :math:`W = I` by
  default), i.e. :math:`\min \tfrac12 y^T G^T W G y + y^T G^T W f_p`;
- ``"max"``: minimise the largest weighted force :math:`\max_i w_i |f_{c,i}|` (then, among
  the minimisers, the weighted minimum norm, so the answer is unique);

subject to actuator box limits and any linear conditions on other forces (a link's axial
force, for preloads such as "every rod in compression by at least F"). The internal
coordinates can also be prescribed outright (Harada 2011's :math:`f_i`, eqs. (20)-(22)).

Without inequalities the norm problem is solved in closed form (its KKT system); with them,
ProxSuite's dense QP solves it and an active-set polish (the KKT system of the constraints
ProxSuite found active) brings the answer to round-off. The minimum peak is a linear
programme, solved by HiGHS (:func:`solve_lp`, through its own Python package ``highspy``)
before its minimum-norm tie-break. When no allocation meets the inequalities, a second QP
finds the least-violating one (minimum sum of squared violations) and
:class:`~plm_pin.exceptions.AllocationInfeasible` carries it.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import dataclass, field

import highspy
import numpy as np
import proxsuite

from .._arguments import nonfinite_indices, real_numbers
from .._linalg import lu_solve
from ..exceptions import AllocationInfeasible, InvalidInput, PlmError
from ..results import Result, unit
from ..tolerances import FEASIBILITY_RTOL, QP_EPS, QP_INFEASIBILITY_EPS

OBJECTIVES = ("norm", "max")
"""Allocation objectives: weighted minimum norm, or minimum largest force."""

_THREAD = threading.local()
"""Per-thread solver state (:func:`_highs`)."""


@dataclass(frozen=True)
class Inequalities:
    r"""Linear inequalities :math:`lo \le a + D y \le hi` on the internal coordinates.

    Attributes:
        names: one name per row (an actuator limit or a condition), for messages.
        offset: :math:`a`, the constrained quantities at :math:`y = 0`, shape (p,).
        D: their change per internal coordinate, shape (p, k).
        lower: lower bounds, ``-inf`` where none, shape (p,).
        upper: upper bounds, ``+inf`` where none, shape (p,).
    """

    names: tuple[str, ...]
    offset: np.ndarray
    D: np.ndarray
    lower: np.ndarray
    upper: np.ndarray

    def violation(self, y: np.ndarray) -> np.ndarray:
        """By how much each row is exceeded at ``y`` (zero when met), shape (p,)."""
        v = self.offset + self.D @ y
        return np.maximum(np.maximum(self.lower - v, v - self.upper), 0.0)


@dataclass(frozen=True)
class Allocation(Result):
    """Result of an allocation.

    Attributes:
        f_c: actuator forces [N] or torques [N m], shape (n_act,).
        y: internal-force coordinates in the balance's internal basis, shape (k,).
        active: names of the inequality rows at their bounds.
    """

    f_c: np.ndarray = field(metadata=unit("N, N m"))
    y: np.ndarray = field(metadata=unit("N, N m"))
    active: tuple[str, ...]


def check_weights(weights: object, n: int) -> np.ndarray:
    """Weights as an SPD matrix (n, n): None -> identity, a vector -> its diagonal.

    Raises:
        InvalidInput: wrong shape, non-finite, not symmetric positive definite.
    """
    if weights is None:
        return np.eye(n)
    W = np.asarray(real_numbers(weights, "weights"), dtype=float)
    if W.shape not in ((n,), (n, n)):
        raise InvalidInput(
            f"weights must be {n} positive numbers or an ({n}, {n}) SPD matrix, got shape {W.shape}"
        )
    if not np.all(np.isfinite(W)):
        raise InvalidInput(f"weights has non-finite entries at indices {nonfinite_indices(W)}")
    if W.shape == (n,):
        W = np.diag(W)
    if not np.allclose(W, W.T) or np.linalg.eigvalsh(W)[0] <= 0.0:
        raise InvalidInput("weights must be symmetric positive definite")
    return W


def allocate(
    f_p: np.ndarray,
    G: np.ndarray,
    ineq: Inequalities,
    *,
    weights: np.ndarray,
    objective: str = "norm",
    internal: np.ndarray | None = None,
    actuator_names: Sequence[str] = (),
) -> Allocation:
    r"""Choose :math:`f_c = f_p + G y` by ``objective`` under ``ineq``.

    Args:
        f_p: minimum-norm balancing forces, shape (n_act,).
        G: orthonormal internal-force basis, shape (n_act, k).
        ineq: inequalities on :math:`y` (actuator limits and conditions).
        weights: SPD weight matrix (n_act, n_act) (see :func:`check_weights`).
        objective: one of :data:`OBJECTIVES`.
        internal: prescribed :math:`y` (shape (k,)), or None to optimise it.
        actuator_names: names for messages (``f_c[i]`` when empty).

    Raises:
        InvalidInput: unknown objective, wrong-sized ``internal``.
        AllocationInfeasible: no allocation meets ``ineq``; carries the least-violating one.
    """
    if objective not in OBJECTIVES:
        raise InvalidInput(f"objective {objective!r} is not one of {list(OBJECTIVES)}")
    k = G.shape[1]
    if internal is None and objective == "norm" and not ineq.names:  # nothing to check: the KKT system
        return min_norm(f_p, G, weights)
    names = tuple(actuator_names) or tuple(f"f_c[{i}]" for i in range(f_p.shape[0]))
    scale = max(float(np.max(np.abs(f_p), initial=0.0)), float(np.max(np.abs(ineq.offset), initial=0.0)), 1.0)
    tol = FEASIBILITY_RTOL * scale
    y: np.ndarray | None
    if internal is not None:
        y = np.asarray(internal, dtype=float)
        if y.shape != (k,):
            raise InvalidInput(
                f"internal must be {k} finite numbers (one per internal force), got shape {y.shape}"
            )
        if not np.all(np.isfinite(y)):
            raise InvalidInput(f"internal has non-finite entries at indices {nonfinite_indices(y)}")
    elif k == 0:
        y = np.zeros(0)
    else:
        solve = _min_norm if objective == "norm" else _min_max
        y = solve(f_p, G, weights, ineq, tol)
        if y is None or np.max(ineq.violation(y), initial=0.0) > tol:
            # No answer within the inequalities: decide by the least violation whether there is
            # one (ProxSuite's own infeasibility detection is unreliable on these small problems).
            least = _least_violating(G.shape[1], ineq, tol)
            if np.max(ineq.violation(least), initial=0.0) <= tol:
                raise PlmError("ProxSuite did not solve a feasible allocation problem")
            y = least
    if np.max(ineq.violation(y), initial=0.0) > tol:
        _raise_infeasible(f_p, G, ineq, names, tol, y)
    f_c = f_p + G @ y
    v = ineq.offset + ineq.D @ y
    active = tuple(
        n
        for n, vi, lo, hi in zip(ineq.names, v, ineq.lower, ineq.upper, strict=True)
        if abs(vi - lo) <= tol or abs(vi - hi) <= tol
    )
    return Allocation(f_c, y, active)


def min_norm(f_p: np.ndarray, G: np.ndarray, weights: np.ndarray) -> Allocation:
    """The weighted minimum norm without inequalities (its KKT system): the allocation of a linear rule."""
    y = _unconstrained(f_p, G, weights) if G.shape[1] else np.zeros(0)
    return Allocation(f_p + G @ y, y, ())


def _unconstrained(f_p: np.ndarray, G: np.ndarray, W: np.ndarray) -> np.ndarray:
    """Internal coordinates of the weighted minimum norm without inequalities (its KKT system)."""
    WG = W @ G
    if G.shape[1] == 1:  # one internal force (3D4M): a scalar
        return np.array([-(WG[:, 0] @ f_p) / (G[:, 0] @ WG[:, 0])])
    return lu_solve(G.T @ WG, -(WG.T @ f_p))


def _min_norm(
    f_p: np.ndarray, G: np.ndarray, W: np.ndarray, ineq: Inequalities, tol: float
) -> np.ndarray | None:
    y0 = _unconstrained(f_p, G, W)
    if np.max(ineq.violation(y0), initial=0.0) <= tol:
        return y0  # the unconstrained minimiser already meets every inequality
    if G.shape[1] == 1:
        return _clipped(y0, ineq)
    return solve_qp(G.T @ W @ G, G.T @ W @ f_p, ineq, tol)


def _clipped(y0: np.ndarray, ineq: Inequalities) -> np.ndarray:
    """One internal force: the convex quadratic's minimiser ``y0`` clipped into the feasible interval.

    Each row bounds y to an interval; their intersection is the feasible set, and the
    minimiser of a convex quadratic over an interval is its free minimiser clipped into it.
    An intersection emptied by rounding alone (a single point, as at the minimum peak) gives
    the middle of the crossed ends; the caller checks the answer's violation either way.
    """
    d = ineq.D[:, 0]
    moving = d != 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (ineq.lower[moving] - ineq.offset[moving]) / d[moving]
        b = (ineq.upper[moving] - ineq.offset[moving]) / d[moving]
    lo = float(np.max(np.minimum(a, b), initial=-np.inf))
    hi = float(np.min(np.maximum(a, b), initial=np.inf))
    if lo > hi:
        return np.array([0.5 * (lo + hi)])
    return np.array([min(max(float(y0[0]), lo), hi)])


def _min_max(
    f_p: np.ndarray, G: np.ndarray, W: np.ndarray, ineq: Inequalities, tol: float
) -> np.ndarray | None:
    """Minimise t subject to |w_i f_i| <= t (a linear programme), then the weighted norm at that t."""
    n, k = G.shape
    w = np.sqrt(np.diag(W))
    # z = (y, t): rows  w_i (f_p + G y)_i - t <= 0  and  w_i (f_p + G y)_i + t >= 0
    D = np.vstack(
        [np.hstack([w[:, None] * G, -np.ones((n, 1))]), np.hstack([w[:, None] * G, np.ones((n, 1))])]
    )
    rows = Inequalities(
        ("max",) * 2 * n,
        np.concatenate([w * f_p, w * f_p]),
        D,
        np.concatenate([np.full(n, -np.inf), np.zeros(n)]),
        np.concatenate([np.zeros(n), np.full(n, np.inf)]),
    )
    c = np.zeros(k + 1)
    c[-1] = 1.0
    z = solve_lp(c, _stack(rows, _extend(ineq, 1)), "the minimum-peak programme")
    if z is None:
        return None
    t = float(np.max(np.abs(w * (f_p + G @ z[:k]))))  # the peak of the LP's vertex
    capped = Inequalities(("max",) * n, w * f_p, w[:, None] * G, np.full(n, -t), np.full(n, t))
    return _min_norm(f_p, G, W, _stack(capped, ineq), tol)


def _extend(ineq: Inequalities, extra: int) -> Inequalities:
    """The same inequalities on ``(y, extra variables)``."""
    D = np.hstack([ineq.D, np.zeros((ineq.D.shape[0], extra))])
    return Inequalities(ineq.names, ineq.offset, D, ineq.lower, ineq.upper)


def _stack(a: Inequalities, b: Inequalities) -> Inequalities:
    return Inequalities(
        a.names + b.names,
        np.concatenate([a.offset, b.offset]),
        np.vstack([a.D, b.D]),
        np.concatenate([a.lower, b.lower]),
        np.concatenate([a.upper, b.upper]),
    )


def solve_lp(
    c: np.ndarray,
    ineq: Inequalities,
    what: str,
    bounds: Sequence[tuple[float | None, float | None]] | None = None,
) -> np.ndarray | None:
    """Solve ``min c^T z`` s.t. ``lower <= offset + D z <= upper`` (and ``bounds`` on z) with HiGHS.

    ``bounds`` are (lower, upper) per variable, None where unbounded (default: all free).
    The rows go to HiGHS as they are (ranged rows, dense row-wise), through this thread's
    solver (:func:`_highs`). Returns None when the programme is infeasible.

    Raises:
        PlmError: HiGHS found it unbounded or did not solve it (``what`` names it).
    """
    p, n = ineq.D.shape
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = n, p
    lp.col_cost_ = c
    if bounds is None:
        lp.col_lower_, lp.col_upper_ = np.full(n, -np.inf), np.full(n, np.inf)
    else:
        lp.col_lower_ = np.array([-np.inf if lo is None else lo for lo, _ in bounds])
        lp.col_upper_ = np.array([np.inf if hi is None else hi for _, hi in bounds])
    lp.row_lower_, lp.row_upper_ = ineq.lower - ineq.offset, ineq.upper - ineq.offset
    lp.a_matrix_.format_ = highspy.MatrixFormat.kRowwise
    lp.a_matrix_.start_ = np.arange(0, p * n + 1, n, dtype=np.int32)
    lp.a_matrix_.index_ = np.tile(np.arange(n, dtype=np.int32), p)
    lp.a_matrix_.value_ = ineq.D.ravel()
    highs = _highs()
    highs.passModel(lp)
    highs.run()
    status = highs.getModelStatus()
    if status == highspy.HighsModelStatus.kInfeasible:
        return None
    if status != highspy.HighsModelStatus.kOptimal:
        raise PlmError(f"HiGHS did not solve {what}: {highs.modelStatusToString(status)}")
    return np.array(highs.getSolution().col_value)


class _SilentHighs(highspy.Highs):
    """A HiGHS solver that prints nothing, not even the banner of the first solver in a process.

    ``highspy.Highs()`` prints that banner to stdout when it enables its Python callbacks, before
    any option can be set (HiGHS issues #1702, #2749); these programmes use no callback, so they stay off.
    """

    def enableCallbacks(self) -> None:
        """Leave HiGHS's callbacks off (nothing here subscribes to one)."""


def new_highs() -> highspy.Highs:
    """A HiGHS solver as plm_pin's linear programmes use it: silent, banner included, without presolve.

    Presolve is off: on programmes of a few columns it costs more than it saves.
    """
    highs = _SilentHighs()
    highs.setOptionValue("output_flag", False)
    highs.setOptionValue("presolve", "off")
    return highs


def _highs() -> highspy.Highs:
    """This thread's solver (:func:`new_highs`, made on first use).

    One per thread: a sweep calls the statics from several threads, and a HiGHS instance
    holds its model.
    """
    highs: highspy.Highs | None = getattr(_THREAD, "highs", None)
    if highs is None:
        highs = _THREAD.highs = new_highs()
    return highs


def solve_qp(H: np.ndarray, g: np.ndarray, ineq: Inequalities, tol: float) -> np.ndarray | None:
    """Solve ``min 1/2 y^T H y + g^T y`` s.t. ``lower <= offset + D y <= upper`` with ProxSuite, polished.

    The answer is polished on its active set (see the module docstring). Returns None when
    ProxSuite does not report the problem solved.
    """
    n = g.shape[0]
    p = ineq.D.shape[0]
    qp = proxsuite.proxqp.dense.QP(n, 0, p)
    qp.settings.eps_abs = QP_EPS
    qp.settings.eps_rel = 0.0
    qp.settings.verbose = False
    qp.settings.max_iter = 1_000  # these problems converge in tens of iterations; never hang
    # ProxSuite's default infeasibility thresholds (1e-4) misjudge these small problems as
    # infeasible; infeasibility is decided here by the violation of the answer instead.
    qp.settings.eps_primal_inf = QP_INFEASIBILITY_EPS
    qp.settings.eps_dual_inf = QP_INFEASIBILITY_EPS
    lower = np.where(np.isfinite(ineq.lower), ineq.lower - ineq.offset, -1e20)
    upper = np.where(np.isfinite(ineq.upper), ineq.upper - ineq.offset, 1e20)
    qp.init(H, g, None, None, ineq.D, lower, upper)
    qp.solve()
    if qp.results.info.status != proxsuite.proxqp.QPSolverOutput.PROXQP_SOLVED:
        return None
    y = np.array(qp.results.x)
    return _polish(H, g, ineq, y, np.array(qp.results.z), tol)


def _polish(
    H: np.ndarray, g: np.ndarray, ineq: Inequalities, y: np.ndarray, z: np.ndarray, tol: float
) -> np.ndarray:
    """Re-solve the KKT system of the active rows exactly; keep it when feasible and no worse."""
    v = ineq.offset + ineq.D @ y
    at_lower = np.abs(v - ineq.lower) <= 1e3 * tol
    at_upper = np.abs(v - ineq.upper) <= 1e3 * tol
    active = np.flatnonzero((at_lower | at_upper) & (np.abs(z) > 0.0))
    n = y.shape[0]
    Da = ineq.D[active]
    rhs = np.where(at_lower[active], ineq.lower[active], ineq.upper[active]) - ineq.offset[active]
    K = np.zeros((n + active.size, n + active.size))
    K[:n, :n] = H
    K[:n, n:] = Da.T
    K[n:, :n] = Da
    b = np.concatenate([-g, rhs])
    try:
        sol = lu_solve(K, b)
    except np.linalg.LinAlgError:  # a degenerate active set: the least-squares solution
        sol = np.linalg.lstsq(K, b, rcond=None)[0]
    y_pol = sol[:n]
    objective = 0.5 * y @ H @ y + g @ y
    polished = 0.5 * y_pol @ H @ y_pol + g @ y_pol
    ok = np.max(ineq.violation(y_pol), initial=0.0) <= tol and polished <= objective + tol * (
        1.0 + abs(objective)
    )
    return y_pol if ok else y


def _least_violating(k: int, ineq: Inequalities, tol: float) -> np.ndarray:
    """Internal coordinates minimising the sum of squared violations of ``ineq`` (always feasible)."""
    # solved in units of the largest bound or offset (u = y / scale, the same minimiser), so that
    # ProxSuite's absolute tolerances are relative ones (a min_compression of 1e9 N)
    values = np.concatenate([ineq.lower, ineq.upper, ineq.offset])
    scale = float(np.max(np.abs(values[np.isfinite(values)]), initial=1.0))
    offset, lower, upper = ineq.offset / scale, ineq.lower / scale, ineq.upper / scale
    # variables (u, s): min 1/2 |s|^2 with lower - s <= offset + D u <= upper + s, s >= 0
    p = ineq.D.shape[0]
    lo_rows = Inequalities(ineq.names, offset, np.hstack([ineq.D, np.eye(p)]), lower, np.full(p, np.inf))
    hi_rows = Inequalities(ineq.names, offset, np.hstack([ineq.D, -np.eye(p)]), np.full(p, -np.inf), upper)
    pos = Inequalities(
        ("s",) * p, np.zeros(p), np.hstack([np.zeros((p, k)), np.eye(p)]), np.zeros(p), np.full(p, np.inf)
    )
    H = np.zeros((k + p, k + p))
    H[k:, k:] = np.eye(p)
    H[:k, :k] = 1e-12 * np.eye(k)  # a unique u among equally violating ones
    z = solve_qp(H, np.zeros(k + p), _stack(_stack(lo_rows, hi_rows), pos), tol / scale)
    if z is None:
        raise PlmError("ProxSuite did not solve the least-violation problem")
    return scale * z[:k]


def _raise_infeasible(
    f_p: np.ndarray, G: np.ndarray, ineq: Inequalities, names: tuple[str, ...], tol: float, y: np.ndarray
) -> None:
    """Raise AllocationInfeasible with the allocation ``y`` (the least-violating one, or the only one)."""
    f_c = f_p + G @ y
    over = ineq.violation(y)
    violated = {n: float(o) for n, o in zip(ineq.names, over, strict=True) if o > tol}
    v = ineq.offset + ineq.D @ y
    at_limit = [
        n
        for n, vi, lo, hi in zip(ineq.names, v, ineq.lower, ineq.upper, strict=True)
        if vi <= lo + tol or vi >= hi - tol
    ]
    saturated = [n for n in names if n in at_limit]
    shown = ", ".join(f"{n} by {o:.6g}" for n, o in violated.items())
    raise AllocationInfeasible(
        f"no actuator forces balance the load within the limits and conditions; the least-violating "
        f"allocation {np.round(f_c, 9).tolist()} exceeds {shown}; saturated actuators: {saturated}",
        f_c,
        saturated,
        violated,
    )
