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

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput, SingularConfiguration
from . import closures as _closures
from .task import Task

if TYPE_CHECKING:
    from ..mechanism import Mechanism


@dataclass(frozen=True)
class ClosedChainJacobians:
    """Jacobians of a closed chain at one configuration.

    Attributes:
        J_phi: closure Jacobian, shape (m, nv).
        J_x: task Jacobian (world-aligned twist rows), shape (n_task, nv).
        N: orthonormal basis of the feasible velocities, shape (nv, mobility).
        closure_singular_values: singular values of ``J_phi``, descending.
        T: task rates per feasible motion ``J_x N``, shape (n_task, mobility).
        C: actuator rates per feasible motion ``S_a N``, shape (n_act, mobility).
    """

    J_phi: np.ndarray
    J_x: np.ndarray
    N: np.ndarray
    closure_singular_values: np.ndarray
    T: np.ndarray
    C: np.ndarray

    @property
    def S(self) -> np.ndarray:
        r"""Velocity map :math:`v = S \dot x`, shape (nv, n_task).

        Raises:
            SingularConfiguration: when :math:`T` is singular (inverse-kinematics singularity).
        """
        return self.N @ self._T_inverse()

    @property
    def J_ce(self) -> np.ndarray:
        r"""Actuator Jacobian :math:`\dot c = J_{ce} \dot x`, shape (n_act, n_task).

        Raises:
            SingularConfiguration: when :math:`T` is singular (inverse-kinematics singularity).
        """
        return self.C @ self._T_inverse()

    def _T_inverse(self) -> np.ndarray:
        if self.T.shape[0] != self.T.shape[1]:
            raise InvalidInput(
                f"the task has {self.T.shape[0]} coordinates but the mechanism has {self.T.shape[1]} DOF; "
                "S and J_ce need as many task coordinates as DOF"
            )
        s = np.linalg.svd(self.T, compute_uv=False)
        if s[-1] <= 1e-12 * s[0]:
            raise SingularConfiguration(
                f"inverse-kinematics (type 1) singular: the task Jacobian on the feasible motions has "
                f"singular values {s.tolist()}"
            )
        return np.linalg.inv(self.T)


def closed_chain_jacobians(mech: Mechanism, q: Any) -> ClosedChainJacobians:
    """Compute :class:`ClosedChainJacobians` at ``q`` (need not be assembled, but should be).

    The null-space dimension is the mechanism's generic mobility, so at a constraint
    singularity the extra near-null direction is left out of :math:`N` and shows in
    ``closure_singular_values``.

    Raises:
        InvalidInput: on a malformed ``q`` or a mechanism without a task.
    """
    qa = mech.check_q(q)
    task = require_task(mech)
    model, data = mech.model, mech.data
    pin.computeJointJacobians(model, data, qa)
    pin.updateFramePlacements(model, data)
    J_phi = _closures.jacobian_from_data(model, data, mech.closures)
    J_x = task.jacobian_from_data(model, data)
    mobility = mech.mobility
    if J_phi.shape[0]:
        _, s, Vt = np.linalg.svd(J_phi)
        N = Vt[mech.nv - mobility :].T
    else:
        s = np.zeros(0)
        N = np.eye(mech.nv)
    return ClosedChainJacobians(J_phi, J_x, N, s, J_x @ N, N[mech.actuated_v_indices])


def require_task(mech: Mechanism) -> Task:
    """The mechanism's compiled task, or a clear error when it has none."""
    if mech.task_compiled is None:
        raise InvalidInput(f"{mech.name} has no end-effector task; add 'end_effector' to its sidecar")
    return mech.task_compiled
