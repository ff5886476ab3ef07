"""Projection of a configuration onto the closure manifold (loop assembly)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import pinocchio as pin

from .._lazy import lazy_module
from ..exceptions import ClosureNotSatisfied
from ..results import Result, unit
from ..tolerances import ASSEMBLY_RCOND, CLOSURE_TOL, ROUND_OFF, ROUNDED_DATA_HEADROOM, ROUNDED_DATA_RTOL
from .closures import BoundClosures, Closure, closure_rows, jacobian_from_data, residual_from_placements

lapack = lazy_module("scipy.linalg.lapack")  # dposv: the normal equations of each Newton step

NEWTON_MAX_ITERATIONS = 12
"""Newton iterations allowed before :func:`newton` gives up (and the caller falls back to LM)."""

STALL_RATIO = 0.9
"""A Newton iteration that does not divide the residual by at least 1 / STALL_RATIO ends the attempt."""

LM_MAX_ITERATIONS = 60
"""Levenberg-Marquardt iterations the inverse and forward kinematics allow once Newton stalls."""

CHORD_RATIO = 1e-2
"""A step that divides the residual by at least 1 / CHORD_RATIO lets :func:`newton` keep its factorisation."""


class ExtraRows(Protocol):
    """Residual rows solved together with the closures (for instance a task target)."""

    @property
    def size(self) -> int:
        """Number of rows."""
        ...

    def residual(self, data: pin.Data, out: np.ndarray | None = None) -> np.ndarray:
        """Rows from frame placements in ``data`` (into ``out`` when given)."""
        ...

    def jacobian(self, model: pin.Model, data: pin.Data, out: np.ndarray | None = None) -> np.ndarray:
        """Their Jacobian from joint Jacobians and placements in ``data`` (into ``out`` when given)."""
        ...


def newton(
    model: pin.Model,
    data: pin.Data,
    closures: Sequence[Closure],
    q0: np.ndarray,
    free: np.ndarray | None,
    r: np.ndarray,
    A: np.ndarray,
    *,
    tol: float,
    extra: ExtraRows | None = None,
    polish: bool = True,
    max_iterations: int = NEWTON_MAX_ITERATIONS,
) -> tuple[np.ndarray, int] | None:
    r"""Gauss-Newton on the closures (and ``extra`` rows) from ``q0``, or None when it stalls.

    Each iteration runs ``framesForwardKinematics`` and writes the residual into the
    preallocated ``r``. The step is :math:`\delta = -(A_f^T A_f)^{-1} A_f^T r` over the free
    columns of the exact Jacobian ``A`` (normal equations solved by Cholesky, LAPACK
    ``posv``, once per factorisation for all rows: the zero rows of planar closures do not
    matter). The Jacobian (``computeJointJacobians``) and its factorisation are refreshed
    only when the last step did not divide the residual by at least 1 / :data:`CHORD_RATIO`
    (a simplified, or chord, Newton while convergence is that fast, and for the polishing
    step). No SVD, no damping: the attempt ends (the caller falls back to :func:`assemble`,
    Levenberg-Marquardt) when a step from a fresh factorisation does not divide the residual
    by 1 / :data:`STALL_RATIO`, the normal matrix is not positive definite (the free columns
    are not independent), or :data:`NEWTON_MAX_ITERATIONS` pass.

    Once within ``tol``, one more step is taken (``polish``), which takes the residual to
    round-off, as :func:`assemble` does. Without it every iteration refreshes the Jacobian:
    the last, quadratic, step then leaves the residual far inside ``tol``, where a chord
    step would leave it just inside. On success ``data`` holds the joint Jacobians and
    frame placements at the returned configuration and ``r`` its residual.

    Args:
        model: Pinocchio model.
        data: its data (a workspace's).
        closures: compiled closures.
        q0: starting configuration. # (nq,)
        free: velocity indices allowed to move (None: all).
        r: residual buffer, at least (m + extra rows,); its first m + extra rows are used.
        A: Jacobian buffer, at least (m + extra rows, nv); it holds the last Jacobian factorised.
        tol: target largest absolute residual [m, rad].
        extra: further rows solved with the closures (a task target).
        polish: take the polishing step.
        max_iterations: iteration cap.

    Returns:
        ``(q, iterations)``, or None.
    """
    m = closure_rows(closures)
    n = m + (extra.size if extra is not None else 0)
    r, A = r[:n], A[:n]
    r_phi, A_phi, r_x, A_x = r[:m], A[:m], r[m:], A[m:]
    bound = BoundClosures(data, closures)
    step_map = np.zeros((model.nv, n))  # -(A_f^T A_f)^-1 A_f^T, zero rows at the fixed columns
    factorised = fresh = False  # fresh: the last step came from a factorisation at its start
    q = q0
    err_prev = np.inf
    polished = not polish
    for iteration in range(max_iterations + 1):
        pin.framesForwardKinematics(model, data, q)
        bound.residual(r_phi)
        if extra is not None:
            extra.residual(data, r_x)
        err = float(np.abs(r).max()) if n else 0.0
        if err <= tol:
            if polished or err < ROUND_OFF:
                pin.computeJointJacobians(model, data, q)  # the joint Jacobians at q, for the caller
                return q, iteration
            polished = True
            refresh = not factorised
        elif iteration == max_iterations:
            return None
        elif polish and err < CHORD_RATIO * err_prev:
            refresh = not factorised
        elif err < STALL_RATIO * err_prev or not fresh:
            refresh = True
        else:
            return None
        if refresh:
            pin.computeJointJacobians(model, data, q)  # frame placements already at q
            bound.jacobian(model, A_phi)
            if extra is not None:
                extra.jacobian(model, data, A_x)
            Af = A if free is None else A[:, free]
            _, solution, info = lapack.dposv(Af.T @ Af, Af.T)
            if info != 0:
                return None
            if free is None:
                np.negative(solution, out=step_map)
            else:
                step_map[free] = -solution
            factorised = True
        fresh = refresh
        q = pin.integrate(model, q, step_map @ r)
        err_prev = err
    return None  # pragma: no cover - the loop always returns


@dataclass(frozen=True)
class Assembly(Result):
    """Result of :func:`assemble`.

    Attributes:
        q: the assembled configuration (read-only). # (nq,)
        residual: closure residual at ``q`` [m, rad]. # (m,)
        iterations: Levenberg-Marquardt iterations used.
        tolerance: the largest absolute residual that was accepted [m, rad].
    """

    q: np.ndarray = field(metadata=unit("m, rad"))
    residual: np.ndarray = field(metadata=unit("m, rad"))
    iterations: int
    tolerance: float = field(metadata=unit("m, rad"))
    _SKIPPED = ("residual",)
    _DERIVED = ("residual_norm",)

    @property
    def residual_norm(self) -> float:
        """Largest absolute closure residual [m or rad]."""
        return float(np.max(np.abs(self.residual))) if self.residual.size else 0.0


def assemble(
    model: pin.Model,
    data: pin.Data,
    closures: Sequence[Closure],
    guess: np.ndarray,
    free_columns: np.ndarray,
    *,
    tol: float = CLOSURE_TOL,
    max_iterations: int = 100,
    rcond: float = ASSEMBLY_RCOND,
    on_failure: Callable[[np.ndarray, np.ndarray], Exception] | None = None,
    extra: ExtraRows | None = None,
) -> Assembly:
    r"""Close the loops from ``guess`` by damped Gauss-Newton (Levenberg-Marquardt).

    Only the tangent directions listed in ``free_columns`` move. Each step is the
    minimum-norm damped least-squares step

    .. math:: \delta = -\sum_{\sigma_i > r\sigma_1} \frac{\sigma_i}{\sigma_i^2 + \mu}
              v_i u_i^T \phi, \qquad \mu = \mu_0 \|\phi\|^2,

    so the redundant rows of planar closures (zero singular values) are ignored, and
    convergence is quadratic near a regular solution. Steps that do not reduce
    :math:`\|\phi\|` are rejected and the damping raised.

    Args:
        model: Pinocchio model.
        data: scratch data for ``model``.
        closures: compiled closures.
        guess: starting configuration. # (nq,)
        free_columns: indices of the velocity coordinates allowed to move.
        tol: target largest absolute residual [m, rad].
        max_iterations: iteration cap.
        rcond: relative singular-value cut-off of the step; singular values at most ``tol``
            times ``max(s_max, 1)`` take no part either (below the tolerance a direction cannot be
            told from a dependent row: the inconsistent rows of rounded data sit there).
        on_failure: builds the error raised when ``tol`` is not reached.
        extra: further residual rows (after the closure rows) to drive to zero.

    Returns:
        The assembled configuration and its residual (closure rows, then ``extra`` rows).

    Raises:
        ClosureNotSatisfied: when ``tol`` is not reached.
    """

    def residual_at(q: np.ndarray) -> np.ndarray:
        pin.framesForwardKinematics(model, data, q)
        phi = residual_from_placements(data, closures)
        return phi if extra is None else np.concatenate([phi, extra.residual(data)])

    def jacobian_at(q: np.ndarray) -> np.ndarray:
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        J = jacobian_from_data(model, data, closures)
        return J if extra is None else np.vstack([J, extra.jacobian(model, data)])

    q = np.array(guess, dtype=float)
    phi = residual_at(q)
    cost = float(phi @ phi)
    mu0 = 1.0
    iterations = 0
    polish = 1  # one more step once within tolerance: quadratic convergence takes it to round-off
    while iterations < max_iterations and phi.size:
        if np.max(np.abs(phi)) <= tol:
            if polish == 0 or np.max(np.abs(phi)) < ROUND_OFF:
                break
            polish -= 1
        iterations += 1
        J = jacobian_at(q)[:, free_columns]
        U, s, Vt = np.linalg.svd(J, full_matrices=False)
        keep = s > max(rcond * s[0], tol * max(s[0], 1.0)) if s.size else s > 0.0
        if not np.any(keep):
            break
        accepted = False
        for _ in range(30):
            mu = mu0 * cost
            gain = s[keep] / (s[keep] ** 2 + mu)
            step_free = -(Vt[keep].T @ (gain * (U[:, keep].T @ phi)))
            step = np.zeros(model.nv)
            step[free_columns] = step_free
            q_new = pin.integrate(model, q, step)
            phi_new = residual_at(q_new)
            cost_new = float(phi_new @ phi_new)
            if cost_new < cost:
                q, phi, cost = q_new, phi_new, cost_new
                mu0 = max(mu0 / 10.0, 1e-12)
                accepted = True
                break
            mu0 *= 10.0
        if not accepted:
            break
    if phi.size and np.max(np.abs(phi)) > tol:
        if on_failure is not None:
            raise on_failure(q, phi)
        raise not_closed(q, phi, tol)
    q.setflags(write=False)
    phi.setflags(write=False)
    return Assembly(q, phi, iterations, tol)


def not_closed(q: np.ndarray, phi: np.ndarray, tol: float) -> ClosureNotSatisfied:
    """The error of an assembly that stopped at ``q``, residual ``phi``, above ``tol`` [m, rad]."""
    worst = float(np.max(np.abs(phi)))
    return ClosureNotSatisfied(
        f"loops not closed: residual {worst:.3g} > tolerance {tol:.3g}", worst, tol, q, ""
    )


@dataclass(frozen=True)
class RoundedClosure:
    """Loops that close only to a least-squares residual small against the model: rounded coordinates.

    A description whose anchors were written to 6-8 significant digits (a CAD export) has
    loops that no configuration closes exactly; the Levenberg-Marquardt assembly then stops at
    the least-squares configuration, whose residual is of the order of the rounding.

    Attributes:
        q: the least-squares configuration. # (nq,)
        residual: its largest absolute closure residual [m, rad].
        worst: the closure open the most there.
        size: the model's size, the largest distance of a frame from the origin there [m].
        tolerance: the closure tolerance to load it with: :data:`ROUNDED_DATA_HEADROOM` times
            ``residual``, rounded up to a power of ten [m, rad].
    """

    q: np.ndarray
    residual: float
    worst: str
    size: float
    tolerance: float


def rounded_closure(
    model: pin.Model, closures: Sequence[Closure], guess: np.ndarray, tol: float
) -> RoundedClosure | None:
    """Whether loops that do not close to ``tol`` from ``guess`` are rounded data (:class:`RoundedClosure`).

    Args:
        model: Pinocchio model.
        closures: compiled closures.
        guess: starting configuration. # (nq,)
        tol: the closure tolerance tried [m, rad].

    Returns:
        None when the loops close to ``tol`` or when their least-squares residual is above
        :data:`~plm_pin.tolerances.ROUNDED_DATA_RTOL` times the model's size (open loops, which
        the caller's assembly reports); otherwise the least-squares closure.
    """
    data = model.createData()
    try:
        assemble(model, data, closures, guess, np.arange(model.nv), tol=tol, max_iterations=200)
        return None
    except ClosureNotSatisfied as exc:  # the best configuration Levenberg-Marquardt reached
        q, residual = np.asarray(exc.q), float(exc.residual_norm)
    pin.framesForwardKinematics(model, data, q)
    size = max(float(np.linalg.norm(M.translation)) for M in data.oMf)
    if not residual <= ROUNDED_DATA_RTOL * max(size, 1.0):  # rotation rows [rad] against 1 rad
        return None
    phi = residual_from_placements(data, closures)
    worst = max(closures, key=lambda c: float(np.max(np.abs(phi[c.rows])))).name
    tolerance = 10.0 ** math.ceil(math.log10(ROUNDED_DATA_HEADROOM * residual))
    return RoundedClosure(q, residual, worst, size, tolerance)
