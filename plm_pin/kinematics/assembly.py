"""Projection of a configuration onto the closure manifold (loop assembly)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import pinocchio as pin

from ..exceptions import ClosureNotSatisfied
from .closures import Closure, jacobian_from_data, residual_from_placements


class ExtraRows(Protocol):
    """Residual rows solved together with the closures (for instance a task target)."""

    @property
    def size(self) -> int:
        """Number of rows."""
        ...

    def residual(self, data: pin.Data) -> np.ndarray:
        """Rows from frame placements in ``data``."""
        ...

    def jacobian(self, model: pin.Model, data: pin.Data) -> np.ndarray:
        """Their Jacobian from joint Jacobians and placements in ``data``."""
        ...


@dataclass(frozen=True)
class Assembly:
    """Result of :func:`assemble`.

    Attributes:
        q: the assembled configuration (read-only). # (nq,)
        residual: closure residual at ``q`` [m, rad]. # (m,)
        iterations: Levenberg-Marquardt iterations used.
    """

    q: np.ndarray
    residual: np.ndarray
    iterations: int

    @property
    def residual_norm(self) -> float:
        """Largest absolute closure residual [m or rad]."""
        return float(np.max(np.abs(self.residual))) if self.residual.size else 0.0

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "q": self.q.tolist(),
            "residual_norm": self.residual_norm,
            "iterations": self.iterations,
        }


def assemble(
    model: pin.Model,
    data: pin.Data,
    closures: Sequence[Closure],
    q_guess: np.ndarray,
    free_columns: np.ndarray,
    *,
    tol: float = 1e-12,
    max_iterations: int = 100,
    rcond: float = 1e-10,
    on_failure: Callable[[np.ndarray, np.ndarray], Exception] | None = None,
    extra: ExtraRows | None = None,
) -> Assembly:
    r"""Close the loops from ``q_guess`` by damped Gauss-Newton (Levenberg-Marquardt).

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
        q_guess: starting configuration. # (nq,)
        free_columns: indices of the velocity coordinates allowed to move.
        tol: target largest absolute residual [m, rad].
        max_iterations: iteration cap.
        rcond: relative singular-value cut-off of the step.
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

    q = np.array(q_guess, dtype=float)
    phi = residual_at(q)
    cost = float(phi @ phi)
    mu0 = 1.0
    iterations = 0
    polish = 1  # one more step once within tolerance: quadratic convergence takes it to round-off
    while iterations < max_iterations and phi.size:
        if np.max(np.abs(phi)) <= tol:
            if polish == 0 or np.max(np.abs(phi)) < 1e-15:
                break
            polish -= 1
        iterations += 1
        J = jacobian_at(q)[:, free_columns]
        U, s, Vt = np.linalg.svd(J, full_matrices=False)
        keep = s > rcond * (s[0] if s.size else 0.0)
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
        raise ClosureNotSatisfied(
            f"loops not closed: residual {np.max(np.abs(phi)):.3g} > tolerance {tol:.3g}",
            float(np.max(np.abs(phi))),
            tol,
            q,
            "",
        )
    q.setflags(write=False)
    phi.setflags(write=False)
    return Assembly(q, phi, iterations)
