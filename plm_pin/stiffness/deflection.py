r"""Deflection under load: the non-linear elastostatic equilibrium of the compliant model.

From the equilibrium at ``q`` (:func:`~plm_pin.stiffness.equilibrium.elastic_state`, springs
at the rest positions that make ``q`` balanced), an extra load is applied and Newton's
method on the Lagrangian finds the new equilibrium:

.. math::

    \begin{bmatrix} H(q, \mu) & -A^T \\ A & 0 \end{bmatrix}
    \begin{bmatrix} \delta v \\ \delta\mu \end{bmatrix}
    = -\begin{bmatrix} r(q, \mu) \\ c(q) \end{bmatrix},

with :math:`r = g - J_w^T w - F_s(q) - A^T \mu` the generalized force residual, :math:`A`
the closure rows and the rigid drives' locks, :math:`c` their residual and :math:`\mu` the
cut-joint and rigid-drive forces. The loads are fixed in the world (dead loads).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import count, optional_name, real_numbers
from .._linalg import lu_solve
from ..core.mechanism import Mechanism, require_frame_task
from ..description.compliance import ComplianceSpec
from ..exceptions import InvalidInput, SingularConfiguration
from ..results import Result, unit
from ..statics import Load, StaticForces
from ..statics.balance import wrench_on_frame
from ..tolerances import DEFLECTION_CLOSURE_TOL, DEFLECTION_RTOL
from .cartesian import condense
from .equilibrium import closure_and_locks, elastic_state, generalized_load, hessian_terms


@dataclass(frozen=True)
class Deflection(Result):
    """The equilibrium reached under an extra load.

    Attributes:
        dofs: task coordinates.
        q: deflected configuration of the compliant model, shape (nq_c,).
        q_rigid: the rigid joints' entries of ``q``, shape (nq,).
        task_displacement: displacement of the task frame, position [m] and world rotation
            vector [rad] rows of the task, shape (n_task,).
        linear_displacement: :math:`K_x^{-1} w` (the linear prediction) [m, rad], shape (n_task,).
        actuator_deflections: change of each drive's joint [m, rad], shape (n_act,).
        joint_deflections: change of each passive spring joint [m, rad], by name.
        link_deflections: tip deflection of each flexible link in its beam frame
            ``(dx, dy, dz, rx, ry, rz)`` [m, rad], by link name.
        f_c: actuator forces at the new equilibrium [N, N m], shape (n_act,).
        lam: cut-joint forces at the new equilibrium [N, N m], shape (m,).
        iterations: Newton iterations used.
    """

    dofs: tuple[str, ...]
    q: np.ndarray = field(metadata=unit("m, rad"))
    q_rigid: np.ndarray = field(metadata=unit("m, rad"))
    task_displacement: np.ndarray = field(metadata=unit("m, rad"))
    linear_displacement: np.ndarray = field(metadata=unit("m, rad"))
    actuator_deflections: np.ndarray = field(metadata=unit("m, rad"))
    joint_deflections: dict[str, float] = field(metadata=unit("m, rad"))
    link_deflections: dict[str, np.ndarray] = field(metadata=unit("m, rad"))
    f_c: np.ndarray = field(metadata=unit("N, N m"))
    lam: np.ndarray = field(metadata=unit("N, N m"))
    iterations: int


def _add(load: Load | None, extra: Load, mech: Mechanism) -> Load:
    if load is None:
        return extra
    if load.frame_id != extra.frame_id:
        raise InvalidInput(
            f"the extra load acts on {extra.frame!r}, the held wrench on {load.frame!r}; use one frame"
        )
    return wrench_on_frame(mech, load.wrench + extra.wrench, load.frame)


def deflection(
    mech: Mechanism,
    q: ArrayLike,
    wrench: ArrayLike,
    frame: str | None = None,
    *,
    gravity: bool = True,
    internal: ArrayLike | Mapping[str, float] | None = None,
    forces: StaticForces | None = None,
    compliance: ComplianceSpec | None = None,
    max_iterations: int = 30,
) -> Deflection:
    """Deflection of the mechanism at ``q`` under an extra ``wrench`` (non-linear, Newton).

    Args:
        mech: the mechanism (with a task).
        q: assembled configuration, the equilibrium before the load, shape (nq,).
        wrench: extra wrench on ``frame`` [N, N m]: 6 values (force, moment) world-aligned
            about the frame origin, or one per task coordinate on the task frame.
        frame: frame the wrench acts on; default the task frame.
        gravity: the equilibrium at ``q`` holds the bodies' weight.
        internal: internal preload at ``q``, as in :func:`~plm_pin.statics.static_forces`.
        forces: the static solution at ``q`` instead of ``gravity`` and ``internal``.
        compliance: the springs; default the sidecar's.
        max_iterations: Newton iteration cap.

    Returns:
        The new equilibrium, its task displacement beside the linear :math:`K_x^{-1} w`.

    Raises:
        InvalidInput: malformed arguments, ``q`` not the configuration of ``forces``, no task,
            no compliance.
        SingularConfiguration: Newton does not converge (the load buckles the mechanism or
            moves it too far), or the state at ``q`` cannot be held.
    """
    task = require_frame_task(mech, "the deflection under a wrench needs")
    max_iterations = count(max_iterations, "max_iterations", minimum=1)
    real_numbers(wrench, "wrench")
    optional_name(frame, "frame")
    state = elastic_state(mech, q, gravity=gravity, internal=internal, forces=forces, compliance=compliance)
    cm = state.compliant
    cmech = cm.mech
    model, data = cmech.model, cmech.data
    extra = wrench_on_frame(
        cmech, wrench, frame if frame is not None else mech.model.frames[task.frame_id].name
    )
    B, T, H, _, _ = condense(state)
    pin.computeJointJacobians(model, data, state.q)
    J_w = pin.getFrameJacobian(model, data, extra.frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
    linear = T @ lu_solve(H, B.T @ (J_w.T @ extra.wrench))
    load = _add(state.load, extra, cmech)
    K_s = cm.stiffness_matrix
    q0, qk = state.q, state.q.copy()
    n_lock = cm.locked.size
    mu = np.concatenate([state.lam, state.spring_forces[cm.locked]])
    F_s0 = state.spring_forces.copy()
    F_s0[cm.locked] = 0.0  # the rigid drives' forces are multipliers
    scale = max(float(np.max(np.abs(state.spring_forces))), float(np.max(np.abs(extra.wrench))), 1.0)
    iterations = 0
    for iterations in range(1, max_iterations + 1):  # noqa: B007 - reported
        dq = pin.difference(model, q0, qk)
        F_s = F_s0 - K_s @ dq
        A = closure_and_locks(cm, qk)
        c = np.concatenate([cmech.closure_residual(qk), dq[cm.locked]])
        r = generalized_load(cmech, qk, load, state.gravity) - F_s - A.T @ mu
        if np.max(np.abs(r)) <= DEFLECTION_RTOL * scale and np.max(np.abs(c), initial=0.0) <= max(
            DEFLECTION_CLOSURE_TOL, cmech.closure_tol
        ):
            break
        terms = hessian_terms(cmech, qk, load, state.gravity, mu[: mu.size - n_lock])
        Hq = K_s + sum(terms.values())
        m = A.shape[0]
        kkt = np.block([[Hq, -A.T], [A, np.zeros((m, m))]])
        step = np.linalg.lstsq(kkt, -np.concatenate([r, c]), rcond=1e-14)[0]
        qk = pin.integrate(model, qk, step[: model.nv])
        mu = mu + step[model.nv :]
    else:
        raise SingularConfiguration(
            f"{mech.name}: the deflection did not converge in {max_iterations} Newton iterations "
            f"(residual {np.max(np.abs(r)):.3g} N): the load may buckle the mechanism or move it too far"
        )
    fid = cmech.model.getFrameId(mech.model.frames[task.frame_id].name)
    M0 = _placement(cmech, q0, fid)
    M1 = _placement(cmech, qk, fid)
    full = np.concatenate([M1.translation - M0.translation, pin.log3(M1.rotation @ M0.rotation.T)])
    dq = pin.difference(model, q0, qk)
    act = np.array([dq[cm.v_index[a.idx_v]] for a in mech.actuators])
    joints = {
        n: float(dq[cm.v_index[mech.model.joints[mech.model.getJointId(n)].idx_v]]) for n in cm.spec.joints
    }
    links = {v.beam.link: dq[v.v_index].copy() for v in cm.links}
    f_c = (F_s0 - K_s @ dq)[cm.v_index[mech.actuated_v_indices]]
    f_c[np.isin(cm.v_index[mech.actuated_v_indices], cm.locked)] = mu[mu.size - n_lock :]
    return Deflection(
        dofs=tuple(task.dofs),
        q=qk,
        q_rigid=cm.drop(qk),
        task_displacement=full[list(task.rows)],
        linear_displacement=linear,
        actuator_deflections=act,
        joint_deflections=joints,
        link_deflections=links,
        f_c=f_c,
        lam=mu[: mu.size - n_lock],
        iterations=iterations,
    )


def _placement(mech: Mechanism, q: np.ndarray, frame_id: int) -> pin.SE3:
    pin.framesForwardKinematics(mech.model, mech.data, q)
    return mech.data.oMf[frame_id].copy()
