r"""Batched kinematics across poses: numpy forward kinematics from the Pinocchio model's joint placements.

For trees of one-axis joints about principal axes (``JointModelPX/PY/PZ/RX/RY/RZ``: the
planar tables), with ``point`` closures and a task of translations plus, for a planar
chain, the yaw ``rz``, :class:`BatchKinematics` evaluates the closure-and-task residual and
its exact Jacobian for a whole batch of configurations in a few numpy operations:

.. math:: {}^0M_j = {}^0M_{\lambda(j)}\, M_j^{place}\, M_j(q_j), \qquad
          {}^0M_f = {}^0M_{j(f)}\, M_f^{place},

with the world-aligned Jacobian columns :math:`(a_k \times (p_f - p_k), a_k)` of a
revolute joint :math:`k` supporting frame :math:`f` and :math:`(a_k, 0)` of a prismatic one.
The same quantities as Pinocchio's ``computeJointJacobians`` + ``getFrameJacobian``
(tested to 1e-13), without a Python call per pose: :func:`batch_newton` solves a whole grid
row per call, which is what makes maps cost a few microseconds per pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..kinematics.closures import Closure
from ..kinematics.jacobians import INVERSE_RTOL
from ..kinematics.legs import MODE_RTOL, Leg
from ..kinematics.task import Task, wrap_angle
from .manipulability import batch_metrics

_AXES = {"X": 0, "Y": 1, "Z": 2}


@dataclass(frozen=True)
class BatchKinematics:
    """Batched residual and Jacobian of the inverse-kinematics equations ``[phi(q); x(q) - x*]``.

    Build with :meth:`from_parts` (None when the model is not of the supported kind).

    Attributes:
        parents: parent joint of each joint (universe 0), shape (njoints,).
        place_R: joint placement rotations, shape (njoints, 3, 3).
        place_p: joint placement translations, shape (njoints, 3).
        axis: motion axis (0, 1, 2) of each joint (-1 for the universe).
        revolute: whether each joint is revolute (else prismatic).
        frame_joint: parent joint of each used frame, shape (n_frames,).
        frame_R: frame placement rotations, shape (n_frames, 3, 3).
        frame_p: frame placement translations, shape (n_frames, 3).
        support: ``support[f, k]``: joint k moves frame f, shape (n_frames, nv).
        closure_a: index (in the used frames) of each closure's frame A.
        closure_b: index of each closure's frame B.
        task_frame: index of the task frame in the used frames.
        task_linear: selected translation rows (0..2).
        task_yaw: whether the task holds ``rz``.
    """

    parents: np.ndarray
    place_R: np.ndarray
    place_p: np.ndarray
    axis: np.ndarray
    revolute: np.ndarray
    frame_joint: np.ndarray
    frame_R: np.ndarray
    frame_p: np.ndarray
    support: np.ndarray
    closure_a: np.ndarray
    closure_b: np.ndarray
    task_frame: int
    task_linear: tuple[int, ...]
    task_yaw: bool

    @classmethod
    def from_parts(
        cls, model: pin.Model, closures: tuple[Closure, ...], task: Task
    ) -> BatchKinematics | None:
        """The batched evaluator of a model, or None when a joint, closure or task row is not supported.

        Supported: joints ``JointModelP{X,Y,Z}`` / ``JointModelR{X,Y,Z}`` (one velocity per joint,
        in joint order), ``point`` closures, tasks of ``x y z`` plus ``rz`` when every
        revolute axis is the world z (a planar chain, where the yaw rate is the z angular rate).
        """
        axis, revolute = [-1], [False]
        for j in range(1, model.njoints):
            short = model.joints[j].shortname()
            if short[:-1] not in ("JointModelP", "JointModelR") or short[-1] not in _AXES:
                return None
            if model.joints[j].idx_v != j - 1:
                return None
            axis.append(_AXES[short[-1]])
            revolute.append(short[-2] == "R")
        if any(c.spec.type != "point" for c in closures):
            return None
        dofs = set(task.dofs)
        if not dofs <= {"x", "y", "z", "rz"}:
            return None
        frames = list(dict.fromkeys([f for c in closures for f in c.frame_ids] + [task.frame_id]))
        out = cls(
            parents=np.array(model.parents, dtype=int),
            place_R=np.array([M.rotation for M in model.jointPlacements]),
            place_p=np.array([M.translation for M in model.jointPlacements]),
            axis=np.array(axis),
            revolute=np.array(revolute),
            frame_joint=np.array([model.frames[f].parentJoint for f in frames], dtype=int),
            frame_R=np.array([model.frames[f].placement.rotation for f in frames]),
            frame_p=np.array([model.frames[f].placement.translation for f in frames]),
            support=np.array(
                [
                    [k + 1 in set(model.supports[model.frames[f].parentJoint]) for k in range(model.nv)]
                    for f in frames
                ]
            ),
            closure_a=np.array([frames.index(c.frame_ids[0]) for c in closures], dtype=int),
            closure_b=np.array([frames.index(c.frame_ids[1]) for c in closures], dtype=int),
            task_frame=frames.index(task.frame_id),
            task_linear=task.linear,
            task_yaw="rz" in dofs,
        )
        if out.task_yaw and not all(a == 2 for a, r in zip(axis, revolute, strict=True) if r):
            return None  # the yaw row needs every rotation about z
        if out.task_yaw and not all(np.allclose(R[:, 2], [0.0, 0.0, 1.0]) for R in out.place_R[1:]):
            return None
        return out

    def frames(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Joint axes and origins, frame rotations and origins, all world, for configurations ``q`` (B, nq).

        Returns:
            axes (B, nv, 3), joint origins (B, nv, 3), frame rotations (B, n_frames, 3, 3),
            frame origins (B, n_frames, 3).
        """
        B, nj = q.shape[0], self.parents.size
        R = np.empty((B, nj, 3, 3))
        p = np.empty((B, nj, 3))
        R[:, 0] = np.eye(3)
        p[:, 0] = 0.0
        for j in range(1, nj):
            parent = self.parents[j]
            Rp = R[:, parent] @ self.place_R[j]  # (B, 3, 3)
            pj = p[:, parent] + R[:, parent] @ self.place_p[j]
            value = q[:, j - 1]
            a = self.axis[j]
            if self.revolute[j]:
                c, s = np.cos(value), np.sin(value)
                i1, i2 = (a + 1) % 3, (a + 2) % 3
                # rotation about the axis a: columns i1, i2 turn, column a stays
                R[:, j, :, a] = Rp[:, :, a]
                R[:, j, :, i1] = Rp[:, :, i1] * c[:, None] + Rp[:, :, i2] * s[:, None]
                R[:, j, :, i2] = Rp[:, :, i2] * c[:, None] - Rp[:, :, i1] * s[:, None]
                p[:, j] = pj
            else:
                R[:, j] = Rp
                p[:, j] = pj + Rp[:, :, a] * value[:, None]
        axes = np.stack([R[:, j, :, self.axis[j]] for j in range(1, nj)], axis=1)  # (B, nv, 3)
        Rf = R[:, self.frame_joint] @ self.frame_R  # (B, nf, 3, 3)
        pf = p[:, self.frame_joint] + np.einsum("bfij,fj->bfi", R[:, self.frame_joint], self.frame_p)
        return axes, p[:, 1:], Rf, pf

    def residual_and_jacobian(self, q: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual (B, m + n_task) and Jacobian (B, m + n_task, nv) at ``q`` (B, nq) and targets ``x``.

        Closure rows as :func:`plm_pin.kinematics.closures.residual_from_placements` (three per
        point closure), task rows as :class:`plm_pin.kinematics.task.TaskTarget`.
        """
        axes, origins, Rf, pf = self.frames(q)
        # world-aligned linear velocity of each frame origin per joint: (B, nf, nv, 3)
        lever = pf[:, :, None, :] - origins[:, None, :, :]
        lin = np.where(
            self.revolute[1:, None],
            np.cross(axes[:, None, :, :], lever),
            np.broadcast_to(axes[:, None], lever.shape),
        )
        lin = lin * self.support[None, :, :, None]
        B, nc = q.shape[0], self.closure_a.size
        r_phi = (pf[:, self.closure_b] - pf[:, self.closure_a]).reshape(B, 3 * nc)
        J_phi = np.swapaxes(lin[:, self.closure_b] - lin[:, self.closure_a], -1, -2).reshape(B, 3 * nc, -1)
        t = self.task_frame
        r_x = [pf[:, t, list(self.task_linear)] - x[:, : len(self.task_linear)]]
        J_x = [np.swapaxes(lin[:, t][:, :, list(self.task_linear)], -1, -2)]
        if self.task_yaw:
            yaw = np.arctan2(Rf[:, t, 1, 0], Rf[:, t, 0, 0])
            r_x.append(wrap_angle(yaw - x[:, -1])[:, None])
            J_x.append((axes[:, :, 2] * (self.revolute[1:] * self.support[t]))[:, None, :])
        return np.concatenate([r_phi, *r_x], axis=1), np.concatenate([J_phi, *J_x], axis=1)


def batch_newton(
    kin: BatchKinematics, q0: np.ndarray, x: np.ndarray, tol: float, max_iterations: int, stall: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Newton on every configuration of a batch at once (each stops on its own).

    Args:
        kin: the evaluator.
        q0: starting configurations, shape (B, nq).
        x: task targets, shape (B, n_task).
        tol: residual tolerance [m, rad].
        max_iterations: iteration cap.
        stall: a pose whose residual does not fall below ``stall`` times the previous one fails.

    Returns:
        Configurations (B, nq), which converged (B,), and the stacked Jacobian at each (B, m + k, nv).
    """
    q = q0.copy()
    B = q.shape[0]
    done = np.zeros(B, dtype=bool)
    failed = np.zeros(B, dtype=bool)
    err_prev = np.full(B, np.inf)
    live = np.arange(B)
    J_out: np.ndarray | None = None
    for iteration in range(max_iterations + 1):
        if live.size == 0:
            break
        r, J = kin.residual_and_jacobian(q[live], x[live])
        if J_out is None:
            J_out = np.empty((B, *J.shape[1:]))
        err = np.abs(r).max(axis=1)
        ok = err <= tol
        J_out[live[ok]] = J[ok]
        done[live[ok]] = True
        bad = ~ok & ((err >= stall * err_prev[live]) | (iteration == max_iterations))
        failed[live[bad]] = True
        go = ~ok & ~bad
        if not go.any():
            break
        Jg, rg = J[go], r[go]
        H = np.swapaxes(Jg, 1, 2) @ Jg
        g = np.einsum("bij,bi->bj", Jg, rg)
        try:
            step = np.linalg.solve(H, g[..., None])[..., 0]
        except np.linalg.LinAlgError:  # a singular normal matrix: these poses fail, the others go on
            step = np.stack([_solve_or_nan(h, v) for h, v in zip(H, g, strict=True)])
        idx = live[go]
        err_prev[idx] = err[go]
        q[idx] -= step
        bad_step = ~np.isfinite(step).all(axis=1)
        failed[idx[bad_step]] = True
        live = idx[~bad_step]
    if J_out is None:
        J_out = np.full((B, 0, q.shape[1]), np.nan)
    return q, done & ~failed, J_out


def _solve_or_nan(H: np.ndarray, g: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.solve(H, g)
    except np.linalg.LinAlgError:
        return np.full(g.shape, np.nan)


def batch_modes(A: np.ndarray, legs: tuple[Leg, ...], rtol: float = MODE_RTOL) -> np.ndarray:
    """Working modes of a batch of stacked Jacobians (B, m + k, nv): one sign per square leg, (B, n_legs).

    The batched :func:`plm_pin.kinematics.legs.working_mode_from_jacobian`: the sign of each
    square leg block's determinant, 0 at or below ``rtol`` times Hadamard's bound. The passive
    axes are not turned: in the planar chains this evaluator takes, every revolute axis stays
    along the plane's normal.
    """
    out = []
    for leg in legs:
        if not leg.square:
            continue
        M = A[:, list(leg.sign_rows)][:, :, list(leg.columns)]
        det = np.linalg.det(M)
        bound = np.prod(np.linalg.norm(M, axis=1), axis=-1)
        out.append(np.where(np.abs(det) <= rtol * bound, 0, np.sign(det)).astype(np.int8))
    return np.stack(out, axis=1) if out else np.zeros((A.shape[0], 0), dtype=np.int8)


FACTOR_RCOND = 1e-8
"""Poses whose velocity map is worse conditioned than 1 / FACTOR_RCOND get the SVD path of the metrics."""

GRAM_RTOL = 1e-4
r"""Smallest ratio :math:`\lambda_{min} / \lambda_{max}` of a Gram matrix read for singular values.

A backward-stable symmetric eigensolver perturbs each eigenvalue of :math:`G = M^T M` by
about :math:`\epsilon \lambda_{max}`, so a singular value :math:`\sigma_i = \sqrt{\lambda_i}`
comes out to a relative error of about :math:`\epsilon\, \sigma_{max}^2 / \sigma_i^2`: at most
:math:`2.2 \cdot 10^{-16} / 10^{-4} \approx 2 \cdot 10^{-12}` above this ratio. Poses below it
(near a singularity) get the singular values of the SVD."""


def _squared_singular_values(M: np.ndarray) -> np.ndarray:
    """Squared singular values of ``M`` (..., r, c), descending (..., min(r, c)), from its smaller Gram."""
    G = M @ np.swapaxes(M, -1, -2) if M.shape[-2] <= M.shape[-1] else np.swapaxes(M, -1, -2) @ M
    lam = np.linalg.eigvalsh(G)[..., ::-1][..., : min(M.shape[-2:])]
    return np.maximum(lam, 0.0)


def square_task_metrics(
    A: np.ndarray, m: int, actuated_v: np.ndarray, mobility: int
) -> dict[str, np.ndarray]:
    r"""The map metrics of stacked Jacobians ``A = [J_phi; J_x]`` (B, m + k, nv) from the Newton system.

    Where the task has as many rows as DOF, the velocity map :math:`S` (:math:`J_\phi S = 0`,
    :math:`J_x S = I`) solves the same normal equations as the Newton step,
    :math:`A^T A\, S = J_x^T`. With its QR factors :math:`S = N R` (:math:`N` an orthonormal
    basis of the feasible motions, standing in for the right singular vectors of
    :math:`J_\phi` in :func:`plm_pin.analysis.manipulability.batch_metrics`, whose values do
    not depend on the basis), :math:`T = J_x N = R^{-1}` and :math:`J_{ce} = C T^{-1} = S_a`
    (the actuated rows of :math:`S`), so no inverse is formed:

    .. math:: w = \prod_i \sigma_i(S_a), \quad \kappa = \frac{\sigma_{max}(S_a)}{\sigma_{min}(S_a)},
              \quad \text{inverse margin} = \frac{1}{\sigma_{max}(S)\, \sigma_{max}(J_x)},
              \quad \text{direct margin} = \sigma_{min}(N_a).

    The singular values come from the eigenvalues of the small Gram matrices (``eigvalsh``,
    cheaper than an SVD of each matrix) where that is accurate (:data:`GRAM_RTOL`); poses
    where it is not, where :math:`S` is ill-conditioned (:data:`FACTOR_RCOND`) or where
    :math:`T` is singular get :func:`~plm_pin.analysis.manipulability.batch_metrics` (SVD).

    Args:
        A: stacked Jacobians, shape (B, m + k, nv).
        m: closure rows.
        actuated_v: velocity indices of the actuators.
        mobility: DOF (= k).

    Returns:
        ``{name: (B,) array}`` as :func:`~plm_pin.analysis.manipulability.batch_metrics` returns.
    """
    J_phi, J_x = A[:, :m], A[:, m:]
    H = np.swapaxes(A, 1, 2) @ A
    try:
        S = np.linalg.solve(H, np.swapaxes(J_x, 1, 2))  # (B, nv, k)
    except np.linalg.LinAlgError:
        return batch_metrics(J_phi, J_x, actuated_v, mobility)
    finite = np.isfinite(S).all(axis=(1, 2))
    S[~finite] = 0.0
    N, Rs = np.linalg.qr(S)
    d = np.abs(np.diagonal(Rs, axis1=1, axis2=2))
    good = finite & (d.min(axis=1) > FACTOR_RCOND * d.max(axis=1))
    T_inv = np.linalg.inv(np.where(good[:, None, None], J_x @ N, np.eye(mobility)))
    C = N[:, actuated_v]
    rank = J_phi.shape[-1] - mobility
    s2_ce = _squared_singular_values(C @ T_inv)
    s2_c = _squared_singular_values(C)
    s2_phi = _squared_singular_values(J_phi)[:, [0, rank - 1]]
    s_T_inv = np.sqrt(_squared_singular_values(T_inv)[:, 0])
    s_x = np.sqrt(_squared_singular_values(J_x)[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / (s_T_inv * s_x)
        good &= (
            (inverse > INVERSE_RTOL)
            & (s2_ce[:, -1] > GRAM_RTOL * s2_ce[:, 0])
            & (s2_c[:, -1] > GRAM_RTOL * s2_c[:, 0])
            & (s2_phi[:, 1] > GRAM_RTOL * s2_phi[:, 0])
        )
        s_ce = np.sqrt(s2_ce)
        out = {
            "manipulability": np.prod(s_ce, axis=1),
            "condition_number": s_ce[:, 0] / s_ce[:, -1],
            "constraint_margin": np.sqrt(s2_phi[:, 1] / s2_phi[:, 0]),
            "inverse_margin": inverse,
            "direct_margin": np.sqrt(s2_c[:, -1]),
        }
    if not good.all():
        bad = ~good
        for name, v in batch_metrics(J_phi[bad], J_x[bad], actuated_v, mobility).items():
            out[name][bad] = v
    return out
