r"""Transmission of a linkage: how the actuators' motion and force reach the task coordinates.

For a linkage whose task is its output joints (a gripper finger, a knee four-bar) these are
the quantities a designer reads; they hold for a frame task as well.

- **Transmission ratio** :math:`R = \partial x / \partial c`, shape (n_task, n_act): the task
  rates per actuator rate, :math:`R = T C^{-1}` with the feasible-motion blocks of
  :mod:`plm_pin.kinematics.jacobians` (:math:`\dot x = T s`, :math:`\dot c = C s`), that is
  :math:`J_{ce}^{-1}`.
- **Mechanical advantage** :math:`A`, shape (n_task, n_act): the force (or torque) the task
  coordinates deliver per actuator force, read from the static balance (gravity off): the
  actuator forces :math:`F e_k` that hold a unit load :math:`e_k` applied from outside on task
  coordinate :math:`k` give :math:`f_{out} = -F^{-1} f_c`, so :math:`A = -F^{-1}`. An ideal
  linkage loses no power, :math:`f_c^T \dot c = f_{out}^T \dot x`, so :math:`A = R^{-T}`
  (virtual work); the tests check one against the other.
- **Transmission index** of each closure, per task coordinate :math:`k`: the cosine of the
  angle between the force :math:`\lambda` the cut joint carries under the unit load on
  :math:`k` and the velocity :math:`u` of the cut point in the motion :math:`\dot x = e_k`,
  :math:`|\lambda \cdot u| / (|\lambda| |u|)`. For a four-bar cut at the coupler-output
  joint, :math:`\lambda` runs along the (unloaded) coupler and :math:`u` is normal to the
  output link, so the index is :math:`\sin\mu` with :math:`\mu` the transmission angle: 1 is
  the best transmission, 0 a dead centre.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._linalg import lu_solve
from ..core.mechanism import Mechanism, require_task
from ..exceptions import InvalidInput, SingularConfiguration
from ..kinematics.jacobians import check_square_task, closed_chain_jacobians
from ..results import Result, unit
from ..tolerances import DEAD_RTOL
from .balance import static_balance

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class Transmission(Result):
    """Transmission ratio, mechanical advantage and transmission indices at one configuration.

    Attributes:
        q: the configuration, shape (nq,).
        dofs: the task coordinates (rows).
        actuators: the actuated joints (columns).
        ratio: task rates per actuator rate, shape (n_task, n_act) [rad/rad, m/m, rad/m, m/rad].
        mechanical_advantage: task forces delivered per actuator force, shape (n_task, n_act)
            [N m / N m, N / N, ...]; equal to ``inv(ratio).T`` for an ideal linkage.
        transmission_index: per closure, one index in [0, 1] per task coordinate (NaN where the
            cut joint carries no force or does not move), shape (n_task,) each.
    """

    q: np.ndarray = field(metadata=unit("m, rad"))
    dofs: tuple[str, ...]
    actuators: tuple[str, ...]
    ratio: np.ndarray = field(metadata=unit("-"))
    mechanical_advantage: np.ndarray = field(metadata=unit("-"))
    transmission_index: dict[str, np.ndarray] = field(metadata=unit("-"))

    @property
    def worst_index(self) -> float:
        """The smallest transmission index over closures and task coordinates (NaN if none)."""
        values = [v for arr in self.transmission_index.values() for v in arr if np.isfinite(v)]
        return float(min(values)) if values else float("nan")


def transmission(mech: Mechanism, q: ArrayLike) -> Transmission:
    """The linkage's transmission at an assembled ``q`` (see the module docstring).

    Args:
        mech: a mechanism with as many actuators and task coordinates as DOF.
        q: an assembled configuration, shape (nq,).

    Returns:
        The transmission ratio, mechanical advantage and transmission indices.

    Raises:
        InvalidInput: a malformed ``q``, no task, or a task or actuation not square.
        ClosureNotSatisfied: ``q`` is off the closure manifold.
        SingularConfiguration: the actuators cannot drive the task at ``q`` (a dead centre:
            the ratio is infinite) or the task does not move (an inverse singularity).
    """
    task = require_task(mech)
    check_square_task(task.size, mech.mobility, "the transmission needs", mech.name)
    if mech.n_actuators != mech.mobility:
        raise InvalidInput(
            f"{mech.name}: {mech.n_actuators} actuators for {mech.mobility} DOF; the transmission needs "
            "as many actuators as DOF"
        )
    qa = mech.check_q(q)
    jac = closed_chain_jacobians(mech, qa)
    s_C = np.linalg.svd(jac.C, compute_uv=False)
    if s_C[-1] <= DEAD_RTOL * max(float(s_C[0]), 1e-300):
        raise SingularConfiguration(
            f"{mech.name}: the actuators cannot drive the task here (a dead centre, direct singularity): "
            f"the actuator rates per motion have singular values {s_C.tolist()}"
        )
    ratio = lu_solve(jac.C.T, jac.T.T).T  # (n_task, n_act): T C^-1
    S = jac.S  # (nv, n_task); raises at an inverse singularity
    n = task.size
    F = np.empty((mech.n_actuators, n))
    lam = np.empty((n, mech.n_closure_rows))
    for k in range(n):
        balance = static_balance(mech, qa, np.eye(n)[k], gravity=False)
        F[:, k] = balance.f_particular
        lam[k] = balance.closure_forces(balance.f_particular)
    advantage = -np.linalg.inv(F)
    data = mech.model.createData()
    pin.computeJointJacobians(mech.model, data, qa)
    pin.updateFramePlacements(mech.model, data)
    index: dict[str, np.ndarray] = {}
    for c in mech.closures[: len(mech.sidecar.closures)]:  # not the idle gauges
        J_a = pin.getFrameJacobian(mech.model, data, c.frame_ids[0], _LWA)[:3]  # (3, nv)
        out = np.full(n, np.nan)
        for k in range(n):
            force = lam[k, c.rows.start : c.rows.start + 3]
            u = J_a @ S[:, k]
            norm = float(np.linalg.norm(force) * np.linalg.norm(u))
            if norm > 0.0:
                out[k] = abs(float(force @ u)) / norm
        index[c.name] = out
    return Transmission(
        qa.copy(), tuple(task.dofs), tuple(a.joint for a in mech.actuators), ratio, advantage, index
    )
