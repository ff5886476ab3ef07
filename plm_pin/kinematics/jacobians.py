r"""Closed-chain Jacobians: the velocity map :math:`S(q)` and the actuator Jacobian :math:`J_{ce}`.

Feasible tree velocities span the null space of :math:`J_\phi`; with an orthonormal basis
:math:`N` (nv x mobility) of it, the task and actuator rates of a feasible motion
:math:`v = N s` are :math:`\dot x = T s` with :math:`T = J_x N` and :math:`\dot c = C s`
with :math:`C = S_a N` (:math:`S_a` selects the actuated velocities). When the task has as
many coordinates as the mechanism has DOF and :math:`T` is invertible,

.. math:: v = S \dot x, \quad S = N T^{-1}, \qquad \dot c = J_{ce} \dot x, \quad J_{ce} = C T^{-1},

which is Harada 2011's :math:`J_{ce} = J_c^{-1} J_e` (eq. (12)) written for any mechanism.
The singular values of :math:`T` and :math:`C` do not depend on the choice of :math:`N`.
"""

from __future__ import annotations

from dataclasses import InitVar, dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._linalg import full_svd, lu_solve
from ..core import closures as _closures
from ..core.checks import check_closed
from ..core.legs import ik_jacobian_from_data
from ..core.mechanism import Mechanism, require_task
from ..exceptions import InvalidInput, SingularConfiguration
from ..results import Result
from ..tolerances import INVERSE_RTOL, RANK_RTOL


@dataclass(frozen=True)
class ClosedChainJacobians(Result):
    """Jacobians of a closed chain at one configuration.

    Attributes:
        J_phi: closure Jacobian, shape (m, nv).
        J_x: task Jacobian (world-aligned twist rows), shape (n_task, nv).
        N: orthonormal basis of the feasible velocities, shape (nv, mobility).
        closure_singular_values: singular values of ``J_phi``, descending.
        T: task rates per feasible motion ``J_x N``, shape (n_task, mobility).
        C: actuator rates per feasible motion ``S_a N``, shape (n_act, mobility).
        closure_pinv: least-norm solver of the closure rows: the pseudo-inverse of ``J_phi``,
            its singular values at most ``RANK_RTOL`` times the largest taken as zero (the rank
            rule of ``numpy.linalg.lstsq`` with ``rcond=RANK_RTOL``), shape (nv, m). Given as
            ``pinv`` by :func:`closed_chain_jacobians` from its SVD; computed when not given.
    """

    J_phi: np.ndarray
    J_x: np.ndarray
    N: np.ndarray
    closure_singular_values: np.ndarray
    T: np.ndarray
    C: np.ndarray
    closure_pinv: np.ndarray = field(init=False, repr=False)
    pinv: InitVar[np.ndarray | None] = None
    _SKIPPED = ("closure_pinv",)

    def __post_init__(self, pinv: np.ndarray | None) -> None:
        if pinv is None:
            pinv = pseudo_inverse(*_closure_svd(self.J_phi))
        object.__setattr__(self, "closure_pinv", pinv)

    @property
    def S(self) -> np.ndarray:
        r"""Velocity map :math:`v = S \dot x`, shape (nv, n_task).

        Raises:
            SingularConfiguration: when :math:`T` is singular (inverse-kinematics singularity).
        """
        return self._times_T_inverse(self.N)

    @property
    def J_ce(self) -> np.ndarray:
        r"""Actuator Jacobian :math:`\dot c = J_{ce} \dot x`, shape (n_act, n_task).

        Raises:
            SingularConfiguration: when :math:`T` is singular (inverse-kinematics singularity).
        """
        return self._times_T_inverse(self.C)

    def _times_T_inverse(self, M: np.ndarray) -> np.ndarray:
        check_square_task(self.T.shape[0], self.T.shape[1], "S and J_ce need")
        out, singular = times_T_inverse(M, self.T, self.J_x)
        if singular:
            s = np.linalg.svd(self.T, compute_uv=False)
            raise SingularConfiguration(
                f"inverse-kinematics (type 1) singular: the task Jacobian on the feasible motions has "
                f"singular values {s.tolist()}"
            )
        return out


def feasible_motions(
    J_phi: np.ndarray, J_x: np.ndarray, actuated_v: np.ndarray, mobility: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""Feasible-motion basis :math:`N`, closure singular values, :math:`T = J_x N` and :math:`C = S_a N`.

    Batched over leading axes (``J_phi`` of shape (..., m, nv), ``J_x`` of shape (..., n_task, nv)),
    so that maps of many configurations are computed at once. :math:`N` spans the right
    singular vectors of the ``mobility`` smallest singular values of :math:`J_\phi` (the
    identity without closures).

    Returns:
        ``N`` (..., nv, mobility), the singular values of ``J_phi`` descending (..., min(m, nv)),
        ``T`` (..., n_task, mobility) and ``C`` (..., n_act, mobility).
    """
    return _motions(_closure_svd(J_phi), J_x, actuated_v, mobility)


def _closure_svd(J_phi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Full SVD ``U, s, Vt`` of ``J_phi`` (..., m, nv); without closure rows ``Vt`` is the identity."""
    if J_phi.shape[-2]:
        U, s, Vt = full_svd(J_phi) if J_phi.ndim == 2 else np.linalg.svd(J_phi)
        return U, s, Vt
    batch, nv = J_phi.shape[:-2], J_phi.shape[-1]
    return np.zeros((*batch, 0, 0)), np.zeros((*batch, 0)), np.broadcast_to(np.eye(nv), (*batch, nv, nv))


def _motions(
    svd: tuple[np.ndarray, np.ndarray, np.ndarray], J_x: np.ndarray, actuated_v: np.ndarray, mobility: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`feasible_motions` from the SVD of ``J_phi``."""
    U, s, Vt = svd
    N = Vt[..., Vt.shape[-1] - mobility :, :].swapaxes(-1, -2) if U.shape[-2] else Vt
    return N, s, J_x @ N, N[..., actuated_v, :]


def pseudo_inverse(U: np.ndarray, s: np.ndarray, Vt: np.ndarray, rtol: float = RANK_RTOL) -> np.ndarray:
    r"""Pseudo-inverse :math:`V_r S_r^{-1} U_r^T` of a matrix from its SVD ``U, s, Vt`` (thin or full).

    The singular values at most ``rtol`` times the largest count as zero, the rule of
    ``numpy.linalg.lstsq(..., rcond=rtol)``, so ``pinv @ b`` is its least-norm solution.

    Args:
        U: left singular vectors, shape (m, k) or (m, m).
        s: singular values, descending, shape (min(m, n),).
        Vt: right singular vectors (transposed), shape (k, n) or (n, n).
        rtol: relative rank tolerance [-].

    Returns:
        The pseudo-inverse, shape (n, m).
    """
    r = int(np.count_nonzero(s > rtol * s[0])) if s.size else 0
    return (Vt[:r].T / s[:r]) @ U[:, :r].T


def times_T_inverse(
    M: np.ndarray, T: np.ndarray, J_x: np.ndarray, rtol: float = INVERSE_RTOL
) -> tuple[np.ndarray, np.ndarray]:
    r""":math:`M T^{-1}` for square :math:`T`, batched over leading axes, and where :math:`T` is singular.

    :math:`T` counts as singular (an inverse-kinematics, type 1, singularity) when
    :math:`\sigma_{min}(T) \le` ``rtol`` :math:`\sigma_{max}(J_x)` (default :data:`INVERSE_RTOL`); the
    product is NaN there.
    The test costs no SVD away from singularities (:func:`inverse_if_regular`); the singular
    values decide only elsewhere.

    Args:
        M: shape (..., r, k).
        T: shape (..., k, k).
        J_x: the task Jacobians :math:`T` restricts, shape (..., k, nv).
        rtol: the inverse margin at or below which :math:`T` counts as singular [-].

    Returns:
        :math:`M T^{-1}` (..., r, k), and the singular mask (...).
    """
    T_inv = inverse_if_regular(T, J_x, rtol)
    if T_inv is not None:
        return M @ T_inv, np.zeros(T.shape[:-2], dtype=bool)
    sT = np.linalg.svd(T, compute_uv=False)
    singular = sT[..., -1] <= rtol * np.linalg.norm(J_x, ord=2, axis=(-2, -1))
    any_singular = bool(singular.any())
    if any_singular:  # invert the identity in their place, then blank them
        T = np.where(singular[..., None, None], np.eye(T.shape[-1]), T)
    out = M @ np.linalg.inv(T)
    if any_singular:
        out[singular] = np.nan
    return out, singular


def inverse_if_regular(T: np.ndarray, J_x: np.ndarray, rtol: float = INVERSE_RTOL) -> np.ndarray | None:
    r""":math:`T^{-1}` (batched) where a bound shows every :math:`T` regular without an SVD, else None.

    Regular means :math:`\sigma_{min}(T) >` ``rtol`` :math:`\sigma_{max}(J_x)`, the inverse margin
    above ``rtol``. :math:`\sigma_{min}(T) \ge 1 / |T^{-1}|_F` and
    :math:`\sigma_{max}(J_x) \le |J_x|_F`, so :math:`T` is regular wherever
    :math:`|J_x|_F |T^{-1}|_F` is below half of 1 / ``rtol`` (the half covers the round-off of
    the computed inverse). None near or at a singularity (or for NaN), where the singular
    values must decide.

    Args:
        T: shape (..., k, k).
        J_x: the task Jacobians :math:`T` restricts, shape (..., k, nv).
        rtol: the inverse margin at or below which :math:`T` counts as singular [-].
    """
    try:  # one LAPACK gesv for a single T: numpy's inv costs more than the solve at this size
        T_inv = lu_solve(T, np.eye(T.shape[-1])) if T.ndim == 2 else np.linalg.inv(T)
    except np.linalg.LinAlgError:  # an exactly singular T
        return None
    bound = (J_x * J_x).sum(axis=(-2, -1)) * (T_inv * T_inv).sum(axis=(-2, -1))  # squared
    return T_inv if bound.max(initial=0.0) * rtol**2 < 0.25 else None  # False on NaN


def closed_chain_jacobians(mech: Mechanism, q: ArrayLike) -> ClosedChainJacobians:
    """Compute :class:`ClosedChainJacobians` at an assembled ``q``.

    The null-space dimension is the mechanism's generic mobility, so at a constraint
    singularity the extra near-null direction is left out of :math:`N` and shows in
    ``closure_singular_values``.

    Raises:
        InvalidInput: on a malformed ``q`` or a mechanism without a task.
        ClosureNotSatisfied: ``q`` is off the closure manifold (residual above
            ``mech.assembled_tol``); assemble it first, ``mech.assemble(q).q``.
    """
    qa = mech.check_q(q)
    model, data = mech.model, mech.data
    pin.computeJointJacobians(model, data, qa)  # the placements of this pass give the closure check
    pin.updateFramePlacements(model, data)
    check_closed(mech, qa, _closures.residual_from_placements(data, mech.closures))
    task = require_task(mech)
    J_phi = _closures.jacobian_from_data(model, data, mech.closures)
    J_x = task.jacobian_from_data(model, data)
    svd = _closure_svd(J_phi)
    N, s, T, C = _motions(svd, J_x, mech.actuated_v_indices, mech.mobility)
    return ClosedChainJacobians(J_phi, J_x, N, s, T, C, pinv=pseudo_inverse(*svd))


def check_square_task(n_task: int, dof: int, needed_by: str, name: str = "") -> None:
    """Refuse a task whose size differs from the DOF.

    Args:
        n_task: number of task coordinates.
        dof: the mechanism's DOF.
        needed_by: what needs them, completing the message (``"manipulability needs"``).
        name: the mechanism's name, to start the message with.

    Raises:
        InvalidInput: when ``n_task != dof``.
    """
    if n_task != dof:
        prefix = f"{name}: " if name else ""
        raise InvalidInput(
            f"{prefix}the task has {n_task} coordinates but the mechanism has {dof} DOF; "
            f"{needed_by} as many task coordinates as DOF"
        )


def ik_jacobian(mech: Mechanism, q: np.ndarray) -> np.ndarray:
    """Stacked Jacobian ``[J_phi; J_x]`` of the inverse-kinematics equations, shape (m + n_task, nv)."""
    task = require_task(mech)
    pin.computeJointJacobians(mech.model, mech.data, q)
    pin.updateFramePlacements(mech.model, mech.data)
    return ik_jacobian_from_data(mech.model, mech.data, mech.closures, task)
