r"""Yoshikawa manipulability and condition number of the actuator Jacobian :math:`J_{ce}`.

Harada 2011 eqs. (12)-(13): with :math:`\dot c = J_{ce} \dot x`
(:attr:`plm_pin.kinematics.ClosedChainJacobians.J_ce`, the paper's
:math:`J_c^{-1} J_e`),

.. math:: w = \sqrt{\det(J_{ce}^T J_{ce})} = \prod_i \sigma_i(J_{ce}),
          \qquad \kappa = \sigma_{max}(J_{ce}) / \sigma_{min}(J_{ce}).

For any mechanism, :math:`J_{ce} = C T^{-1}` with :math:`T = J_x N` and :math:`C = S_a N`,
so :math:`w = \sqrt{\det(C^T C)} / |\det T|`: it vanishes at a direct (type 2)
singularity (:math:`C` loses rank) and is infinite at an inverse (type 1) one (:math:`T`
loses rank), and neither it nor :math:`\kappa` depends on the basis :math:`N`.

Units: the column ``j`` of :math:`J_{ce}` is in actuator units per unit of task coordinate
``j`` (m/m, m/rad for linear actuators and an x-y-theta task), so :math:`w` carries the
product of the column units (m/rad for Harada's tables) and :math:`\kappa` depends on the
unit of length whenever the task mixes translations and rotations.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import check_tolerance, flag
from ..core.mechanism import Mechanism, require_task
from ..exceptions import SingularConfiguration
from ..kinematics.inverse import inverse_kinematics
from ..kinematics.jacobians import (
    INVERSE_RTOL,
    ClosedChainJacobians,
    check_square_task,
    closed_chain_jacobians,
    feasible_motions,
    times_T_inverse,
)
from ..kinematics.singularity import SINGULARITY_TOL, constraint_margins, direct_margins, inverse_margins
from ..results import Result, unit

W_UNIT = "product of the column units of J_ce (m/rad for linear actuators and an x-y-theta task)"
"""Unit of the manipulability w."""

POSE_METRICS: tuple[str, ...] = (
    "manipulability",
    "condition_number",
    "constraint_margin",
    "inverse_margin",
    "direct_margin",
)
"""Names of the per-pose metrics of workspace maps, in this order."""

MARGIN_METRICS: tuple[str, ...] = ("constraint_margin", "inverse_margin", "direct_margin")
"""The singularity margins of :data:`POSE_METRICS`, as :data:`plm_pin.kinematics.singularity.KINDS`."""


def manipulability_unit(mech: Mechanism) -> str:
    r"""SI unit of :math:`w` for ``mech``: the product of the column units of :math:`J_{ce}`.

    Column ``j`` is in actuator units (m for prismatic, rad for revolute actuators) per unit
    of task coordinate ``j`` (m for ``x y z``, rad for ``rx ry rz``), so :math:`w` is in
    :math:`a^k / \prod_j t_j` (e.g. m/rad for linear actuators and an x-y-theta task, ``-``
    for a four-bar's crank angle per rocker angle). With actuators of both kinds the rows of
    :math:`J_{ce}` mix units and :math:`w` has none: :data:`W_UNIT` is returned.

    Raises:
        InvalidInput: a mechanism without a task.
    """
    task = require_task(mech)
    kinds = {a.kind for a in mech.actuators}
    if len(kinds) != 1:
        return W_UNIT
    powers = {"m": 0, "rad": 0}
    powers["m" if kinds == {"prismatic"} else "rad"] += len(task.dofs)
    for dof in task.dofs:
        powers["rad" if dof.startswith("r") else "m"] -= 1

    def product(sign: int) -> str:
        parts = [s if abs(p) == 1 else f"{s}^{abs(p)}" for s, p in powers.items() if p * sign > 0]
        return " ".join(parts)

    above, below = product(1), product(-1)
    if not below:
        return above or "-"
    return f"{above or '1'}/{below if ' ' not in below else f'({below})'}"


@dataclass(frozen=True)
class Manipulability(Result):
    r"""Manipulability of a mechanism at one configuration (Harada 2011 eq. (13)).

    Attributes:
        w: :math:`\sqrt{\det(J_{ce}^T J_{ce})}` [product of the column units of J_ce: m/rad
            for linear actuators and an x-y-theta task]; 0 at a direct singularity, inf at
            an inverse one.
        condition_number: :math:`\sigma_{max} / \sigma_{min}` of J_ce [-] (depends on the unit
            of length when the task mixes translations and rotations); inf at a singularity.
        singular_values: singular values of J_ce, descending [actuator units per task unit],
            shape (n_task,); NaN at an inverse singularity, where J_ce is undefined.
        J_ce: actuator Jacobian, shape (n_act, n_task); None at an inverse singularity.
        inverse_singular: whether :math:`T = J_x N` is singular (J_ce undefined).
    """

    w: float = field(metadata=unit(W_UNIT))
    condition_number: float = field(metadata=unit("-"))
    singular_values: np.ndarray
    J_ce: np.ndarray | None
    inverse_singular: bool = field(metadata=unit("-"))
    _NONFINITE_AS_TEXT = ("w", "condition_number", "singular_values")

    @property
    def inverse_condition(self) -> float:
        r""":math:`1 / \kappa` in [0, 1]: 0 at a singularity, 1 when isotropic [-]."""
        return 0.0 if not np.isfinite(self.condition_number) else 1.0 / self.condition_number


def manipulability_from_jacobians(
    jac: ClosedChainJacobians, singularity_tol: float = INVERSE_RTOL
) -> Manipulability:
    """Manipulability from Jacobians already computed (see :func:`manipulability`).

    ``singularity_tol`` is the inverse margin at or below which :math:`T` counts as singular [-].
    """
    check_square_task(jac.T.shape[0], jac.T.shape[1], "manipulability needs")
    J_ce, s, w, cond, singular = _manipulability_values(jac.T, jac.C, jac.J_x, singularity_tol)
    return Manipulability(float(w), float(cond), s, None if singular else J_ce, bool(singular))


def _manipulability_values(
    T: np.ndarray, C: np.ndarray, J_x: np.ndarray, rtol: float = INVERSE_RTOL
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r""":math:`J_{ce} = C T^{-1}`, its singular values, :math:`w` and :math:`\kappa`, batched.

    Args:
        T: shape (..., k, k).
        C: shape (..., n_act, k).
        J_x: task Jacobians, shape (..., k, nv) (the scale of :math:`T`'s singularity test).
        rtol: inverse margin at or below which :math:`T` counts as singular [-].

    Returns:
        ``J_ce`` (..., n_act, k) and its singular values (..., k) (NaN where :math:`T` is
        singular), ``w`` and ``condition_number`` (...) (inf there), and the singular mask (...).
    """
    J_ce, singular = times_T_inverse(C, T, J_x, rtol)
    if singular.any():  # NaN blocks: SVD of zeros there, then NaN
        s = np.linalg.svd(np.where(singular[..., None, None], 0.0, J_ce), compute_uv=False)
        s[singular] = np.nan
        w = np.where(singular, np.inf, s.prod(axis=-1))
    else:
        s = np.linalg.svd(J_ce, compute_uv=False)
        w = s.prod(axis=-1)
    s_min = s[..., -1]
    if s_min.min() > 0.0:  # False on NaN
        cond = s[..., 0] / s_min
    else:  # inf where J_ce is singular or undefined
        cond = np.divide(s[..., 0], s_min, out=np.full(s_min.shape, np.inf), where=s_min > 0.0)
    return J_ce, s, w, cond, singular


def manipulability(
    mech: Mechanism,
    q: ArrayLike,
    *,
    raise_if_singular: bool = False,
    singularity_tol: float = SINGULARITY_TOL,
) -> Manipulability:
    """Yoshikawa manipulability and condition number of :math:`J_{ce}` at configuration ``q``.

    Args:
        mech: the mechanism (its task must have as many coordinates as it has DOF).
        q: assembled configuration, shape (nq,).
        raise_if_singular: raise at an inverse (type 1) singularity instead of returning
            ``w = inf`` flagged ``inverse_singular``.
        singularity_tol: inverse margin at or below which ``q`` counts as inverse-singular [-]
            (the tolerance of :func:`plm_pin.kinematics.classify`, so that both agree; a finite
            number >= 0).

    Returns:
        The manipulability.

    Raises:
        SingularConfiguration: when ``raise_if_singular`` and :math:`T` is singular.
        InvalidInput: malformed ``q``, ``raise_if_singular`` or ``singularity_tol``, no task, or a
            task size different from the DOF.
    """
    flag(raise_if_singular, "raise_if_singular")
    tol = check_tolerance(singularity_tol, "singularity_tol")
    jac = closed_chain_jacobians(mech, q)
    result = manipulability_from_jacobians(jac, tol)
    if raise_if_singular and result.inverse_singular:
        margin = float(inverse_margins(jac.T, jac.J_x))
        raise SingularConfiguration(
            f"{mech.name}: inverse-kinematics (type 1) singular configuration: inverse margin {margin:.3g} "
            f"at or below the tolerance {tol:.3g}; J_ce is undefined"
        )
    return result


def manipulability_at(
    mech: Mechanism,
    x: ArrayLike,
    guess: ArrayLike | None = None,
    *,
    mode: tuple[int, ...] | None = None,
    raise_if_singular: bool = False,
) -> Manipulability:
    """Manipulability at task pose ``x`` [m, rad]: inverse kinematics, then :func:`manipulability`.

    Args:
        mech: the mechanism.
        x: task coordinates [m, rad], shape (n_task,).
        guess: starting configuration of the inverse kinematics (default: reference).
        mode: working mode to use (default: the guess's).
        raise_if_singular: see :func:`manipulability`.

    Raises:
        PoseUnreachable: when ``x`` cannot be reached.
    """
    sol = inverse_kinematics(mech, x, guess, mode=mode)
    return manipulability(mech, sol.q, raise_if_singular=raise_if_singular)


def batch_metrics(
    J_phi: np.ndarray,
    J_x: np.ndarray,
    actuated_v: np.ndarray,
    mobility: int,
    basis: np.ndarray | None = None,
    names: Sequence[str] = POSE_METRICS,
) -> dict[str, np.ndarray]:
    """Manipulability, condition number and singularity margins of a batch of configurations.

    The batched counterpart of :func:`manipulability` and
    :func:`plm_pin.kinematics.classify`, from the closure and task Jacobians.

    Args:
        J_phi: closure Jacobians, shape (b, m, nv).
        J_x: task Jacobians, shape (b, n_task, nv).
        actuated_v: velocity indices of the actuators, shape (n_act,).
        mobility: DOF of the mechanism (= n_task).
        basis: an orthonormal basis of the feasible motions already at hand, shape (b, nv,
            mobility) (default: from the SVD of ``J_phi``); the values do not depend on it.
        names: the metrics to compute, among :data:`POSE_METRICS` (default: all).

    Returns:
        ``{name: (b,) array}`` for every name of ``names``.
    """
    if basis is None:
        _, s_phi, T, C = feasible_motions(J_phi, J_x, actuated_v, mobility)
    else:
        s_phi = np.linalg.svd(J_phi, compute_uv=False)
        T, C = J_x @ basis, basis[..., actuated_v, :]
    values = {}
    if "manipulability" in names or "condition_number" in names:
        _, _, values["manipulability"], values["condition_number"], _ = _manipulability_values(T, C, J_x)
    if "constraint_margin" in names:
        values["constraint_margin"] = constraint_margins(s_phi, J_phi.shape[-1] - mobility)
    if "inverse_margin" in names:
        values["inverse_margin"] = inverse_margins(T, J_x)
    if "direct_margin" in names:
        values["direct_margin"] = direct_margins(C)
    return {name: values[name] for name in names}
