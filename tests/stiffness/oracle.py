"""An independent elastostatic equilibrium: minimise the total potential with scipy subject to the closures.

Only first derivatives (Pinocchio's Jacobians and generalized gravity) are used; nothing of
plm_pin.stiffness. Springs along the actuated joints have rest positions chosen so that the
given configuration balances the given actuator forces.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.optimize import minimize, root

from plm_pin.core.mechanism import Mechanism

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def equilibrium_displacement(
    mech: Mechanism, q0: np.ndarray, f_c: np.ndarray, k: np.ndarray, force: np.ndarray, gravity: bool = True
) -> np.ndarray:
    """Task-frame displacement ``(dp, dtheta)`` (world, 6) under an extra force and moment ``force`` (6,).

    The extra load is a constant world force at the task frame origin and, for the moment,
    the potential ``-m . log3(R R0^T)`` (exact for planar rotations about a fixed axis).
    """
    model, data = mech.model, mech.data
    fid = mech.task_frame_id
    act = mech.actuated_v_indices
    c0 = mech.actuator_positions(q0) + f_c / k  # spring force k (c_rest - c) equals f_c at q0
    pin.framesForwardKinematics(model, data, q0)
    p0 = data.oMf[fid].translation.copy()
    R0 = data.oMf[fid].rotation.copy()
    J_phi0 = mech.closure_jacobian(q0)
    rows = np.flatnonzero(np.abs(J_phi0).max(axis=1) > 1e-12)  # drop the rows planar chains leave empty
    scale_x = 1e-6  # unknowns in micrometres / microradians
    f, m = force[:3], force[3:]

    def q_of(z: np.ndarray) -> np.ndarray:
        return pin.integrate(model, q0, scale_x * z)

    def energy(z: np.ndarray) -> tuple[float, np.ndarray]:
        q = q_of(z)
        c = mech.actuator_positions(q)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        e = 0.5 * np.sum(k * (c - c0) ** 2)
        grad = np.zeros(model.nv)
        grad[act] += k * (c - c0)
        if gravity:
            e += pin.computePotentialEnergy(model, data, q)
            grad += pin.computeGeneralizedGravity(model, data, q)
        pin.framesForwardKinematics(model, data, q)
        pin.computeJointJacobians(model, data, q)
        M = data.oMf[fid]
        theta = pin.log3(M.rotation @ R0.T)
        e -= f @ (M.translation - p0) + m @ theta
        J = pin.getFrameJacobian(model, data, fid, _LWA)
        grad -= J[:3].T @ f + J[3:].T @ (pin.Jlog3(M.rotation @ R0.T).T @ m if np.any(m) else m)
        dint = pin.dIntegrate(model, q0, scale_x * z, pin.ArgumentPosition.ARG1) * scale_x
        return e, grad @ dint

    def closure(z: np.ndarray) -> np.ndarray:
        return mech.closure_residual(q_of(z))[rows] / scale_x

    def closure_jac(z: np.ndarray) -> np.ndarray:
        q = q_of(z)
        return mech.closure_jacobian(q)[rows] @ pin.dIntegrate(
            model, q0, scale_x * z, pin.ArgumentPosition.ARG1
        )

    e0 = energy(np.zeros(model.nv))[0]
    s = 1.0 / (float(np.max(k)) * scale_x**2)  # unit curvature along the drives

    def objective(z: np.ndarray) -> tuple[float, np.ndarray]:
        e, g = energy(z)
        return (e - e0) * s, g * s

    res = minimize(
        objective,
        np.zeros(model.nv),
        jac=True,
        method="SLSQP",
        constraints=[{"type": "eq", "fun": closure, "jac": closure_jac}],
        options={"ftol": 1e-14, "maxiter": 40},
    )
    # polish the minimiser's KKT point (stationary potential on the closures) to machine precision
    z0 = res.x
    mu0 = np.linalg.lstsq(closure_jac(z0).T, -objective(z0)[1], rcond=None)[0]

    def kkt(x: np.ndarray) -> np.ndarray:
        z, mu = x[: model.nv], x[model.nv :]
        return np.concatenate([objective(z)[1] + closure_jac(z).T @ mu, closure(z)])

    sol = root(kkt, np.concatenate([z0, mu0]), method="lm", options={"xtol": 1e-15, "ftol": 1e-15})
    assert sol.success, sol.message
    q = q_of(sol.x[: model.nv])
    pin.framesForwardKinematics(model, data, q)
    M = data.oMf[fid]
    return np.concatenate([M.translation - p0, pin.log3(M.rotation @ R0.T)])


def compliance_by_equilibria(
    mech: Mechanism,
    q0: np.ndarray,
    f_c: np.ndarray,
    k: np.ndarray,
    steps: np.ndarray,
    gravity: bool = True,
) -> np.ndarray:
    """Task compliance from equilibria under small loads: central differences, Richardson-extrapolated.

    Args:
        mech: the mechanism.
        q0: the equilibrium configuration.
        f_c: actuator forces holding it [N].
        k: drive stiffness [N/m].
        steps: load step of each task coordinate [N or N m], shape (n_task,).
        gravity: include the bodies' weight.
    """
    task = mech.task_compiled
    assert task is not None
    rows = list(task.rows)
    n = len(rows)

    def column(j: int, h: float) -> np.ndarray:
        w = np.zeros(6)
        w[rows[j]] = h
        plus = equilibrium_displacement(mech, q0, f_c, k, w, gravity)[rows]
        minus = equilibrium_displacement(mech, q0, f_c, k, -w, gravity)[rows]
        return (plus - minus) / (2 * h)

    C = np.zeros((n, n))
    for j in range(n):
        C[:, j] = (4 * column(j, steps[j] / 2) - column(j, steps[j])) / 3
    return C
