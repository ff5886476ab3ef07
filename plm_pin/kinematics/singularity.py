r"""Singularity classification of closed chains at a configuration.

With the feasible motions :math:`v = N s` (:mod:`plm_pin.kinematics.jacobians`):

- **constraint** (complex) singularity: :math:`J_\phi` loses rank below its generic rank,
  so the chain gains a motion (e.g. two equal 2-PRRRP rods on one slider position, both
  normal to the stator; inclined, such coinciding rods keep the rank of :math:`J_\phi`, and
  Harada 2015's complex singularity only makes their two rows of :math:`J_{ce}` equal: a
  redundant table loses its redundancy, a 3-motor one is direct-singular);
- **inverse** (type 1, actuator) singularity: :math:`T = J_x N` loses rank: a motion
  leaves the task frame still while the legs move (Harada 2011 eq. (9), :math:`z_i^T a = 0`);
- **direct** (type 2) singularity: :math:`C = S_a N` loses rank: a motion moves the task
  frame with every actuator locked (Harada 2011 eq. (10), :math:`\det J_e = 0`).

Margins. Each kind is the loss of rank of a map restricted to the feasible motions (or, for
the closure, of its generic rank ``r``); its margin is the smallest singular value that
should be nonzero divided by the norm of the *whole* map it is restricted from, so that
it is scale-aware for every size, a 1 x 1 ``T`` or ``C`` included:

.. math::
    m_{constraint} = \frac{\sigma_r(J_\phi)}{\sigma_1(J_\phi)}, \qquad
    m_{inverse} = \frac{\sigma_{min}(J_x N)}{\sigma_{max}(J_x)}, \qquad
    m_{direct} = \frac{\sigma_{min}(S_a N)}{\sigma_{max}(S_a)} = \sigma_{min}(S_a N).

They lie in [0, 1] and do not depend on the choice of :math:`N` (another orthonormal basis
is :math:`N R` with :math:`R` orthogonal). Since :math:`N` has orthonormal columns and
:math:`S_a` orthonormal rows, the singular values of :math:`C = S_a N` are the cosines of
the principal angles between the feasible motions and the actuated coordinates: the direct
margin is how much the least-seen feasible motion moves the actuators, per unit of joint
speed [m/s, rad/s]. Likewise the inverse margin is the smallest task rate of a unit feasible
motion relative to the largest task rate of any unit tree motion. A ratio
:math:`\sigma_{min}(T) / \sigma_{max}(T)` of the restricted map alone would be 1 for every
1 x 1 matrix, so a one-DOF chain (the four-bar at its rocker's extremes, where the rocker
rate vanishes while the crank turns) would never be found singular. A configuration is
singular of a kind when its margin is at most the tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import check_tolerance, flag
from ..core.mechanism import Mechanism, require_task
from ..exceptions import SingularConfiguration
from ..results import Result, unit
from ..tolerances import SINGULARITY_TOL
from .jacobians import ClosedChainJacobians, check_square_task, closed_chain_jacobians

KINDS: tuple[str, ...] = ("constraint", "inverse", "direct")


def inverse_margins(T: np.ndarray, J_x: np.ndarray) -> np.ndarray:
    r"""Inverse (type 1) margin :math:`\sigma_{min}(T) / \sigma_{max}(J_x)`, batched.

    ``T`` (..., k, k) and ``J_x`` (..., k, nv) give (...). 1 for an empty ``T``; 0 where :math:`J_x` vanishes.
    """
    if min(T.shape[-2:]) == 0:
        return np.ones(T.shape[:-2])
    s_min = np.linalg.svd(T, compute_uv=False)[..., -1]
    return _ratio(s_min, np.linalg.norm(J_x, ord=2, axis=(-2, -1)), 0.0)


def direct_margins(C: np.ndarray) -> np.ndarray:
    r"""Direct (type 2) margin :math:`\sigma_{min}(C)` of :math:`C = S_a N`, (..., n_act, k) -> (...).

    :math:`\sigma_{max}(S_a) = 1`, so this is the margin of the module docstring; the
    smallest of the ``min(n_act, k)`` singular values, i.e. for a redundantly actuated chain
    that of its rank-``k`` part. 1 for an empty ``C``.
    """
    if min(C.shape[-2:]) == 0:
        return np.ones(C.shape[:-2])
    return np.linalg.svd(C, compute_uv=False)[..., -1]


def normalised_margin(M: np.ndarray) -> float:
    r"""Normalised smallest singular value :math:`\sigma_{min} / \sigma_{max}` of ``M`` [-].

    1 for an empty matrix, 0 for a zero matrix.
    """
    return float(normalised_margins(M))


def normalised_margins(M: np.ndarray) -> np.ndarray:
    r""":func:`normalised_margin` of matrices stacked over leading axes, ``M`` (..., r, c) -> (...)."""
    if min(M.shape[-2:]) == 0:
        return np.ones(M.shape[:-2])
    s = np.linalg.svd(M, compute_uv=False)
    return _ratio(s[..., -1], s[..., 0], 0.0)


def constraint_margins(s: np.ndarray, rank: int) -> np.ndarray:
    r"""Constraint margin :math:`\sigma_r / \sigma_1` from closure singular values ``s`` (..., k) -> (...).

    ``rank`` is the generic rank of the closure Jacobian; the margin is 1 without closure
    rows or for a zero Jacobian.
    """
    if rank <= 0 or s.shape[-1] == 0:
        return np.ones(s.shape[:-1])
    return _ratio(s[..., rank - 1], s[..., 0], 1.0)


def _ratio(s_k: np.ndarray, s_1: np.ndarray, at_zero: float) -> np.ndarray:
    """``s_k / s_1`` where ``s_1 > 0``, else ``at_zero``."""
    return np.divide(s_k, s_1, out=np.full(np.shape(s_k), at_zero), where=s_1 > 0.0)


@dataclass(frozen=True)
class SingularityReport(Result):
    r"""Singularity margins of one configuration.

    Attributes:
        constraint_margin: :math:`\sigma_r / \sigma_1` of the closure Jacobian at its generic rank [-].
        inverse_margin: :math:`\sigma_{min}(T) / \sigma_{max}(J_x)`, :math:`T = J_x N` (type 1) [-].
        direct_margin: :math:`\sigma_{min}(C)`, :math:`C = S_a N` (type 2) [-]; for a
            redundantly actuated chain, of its rank-``mobility`` part.
        tol: the tolerance used.
    """

    constraint_margin: float = field(metadata=unit("-"))
    inverse_margin: float = field(metadata=unit("-"))
    direct_margin: float = field(metadata=unit("-"))
    tol: float = field(metadata=unit("-"))
    _DERIVED = ("kinds",)

    @property
    def kinds(self) -> tuple[str, ...]:
        """The kinds of singularity present, among ``constraint``, ``inverse``, ``direct``."""
        margins = (self.constraint_margin, self.inverse_margin, self.direct_margin)
        return tuple(k for k, m in zip(KINDS, margins, strict=True) if m <= self.tol)

    @property
    def singular(self) -> bool:
        """Whether any kind of singularity is present."""
        return bool(self.kinds)


def report_from_jacobians(mech: Mechanism, jac: ClosedChainJacobians, tol: float) -> SingularityReport:
    """Build the report from Jacobians already computed."""
    constraint = float(constraint_margins(jac.closure_singular_values, mech.nv - mech.mobility))
    return SingularityReport(
        constraint, float(inverse_margins(jac.T, jac.J_x)), float(direct_margins(jac.C)), tol
    )


def classify(
    mech: Mechanism, q: ArrayLike, tol: float = SINGULARITY_TOL, *, raise_if_singular: bool = False
) -> SingularityReport:
    """Classify the configuration ``q`` (assembled) as regular or singular, with margins.

    Args:
        mech: the mechanism (needs a task with as many coordinates as DOF).
        q: assembled configuration, shape (nq,).
        tol: margin at or below which a kind counts as singular (a finite number >= 0).
        raise_if_singular: raise instead of returning a singular report.

    Returns:
        The report (check :attr:`SingularityReport.singular` and ``kinds``).

    Raises:
        InvalidInput: a malformed ``q`` or ``tol``.
        ClosureNotSatisfied: ``q`` is off the closure manifold (see
            :func:`plm_pin.kinematics.closed_chain_jacobians`).
        SingularConfiguration: when ``raise_if_singular`` and the configuration is singular;
            the message names the kinds and margins.
        InvalidInput: when the task has not as many coordinates as the mechanism has DOF.
    """
    tol = check_tolerance(tol, "tol")
    flag(raise_if_singular, "raise_if_singular")
    check_square_task(require_task(mech).size, mech.mobility, "singularity classification needs", mech.name)
    report = report_from_jacobians(mech, closed_chain_jacobians(mech, q), tol)
    if raise_if_singular and report.singular:
        raise SingularConfiguration(
            f"{mech.name}: configuration is singular ({', '.join(report.kinds)}): margins constraint "
            f"{report.constraint_margin:.3g}, inverse {report.inverse_margin:.3g}, direct "
            f"{report.direct_margin:.3g} (tolerance {tol:.3g})"
        )
    return report
