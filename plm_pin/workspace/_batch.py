r"""Batched kinematics across poses: numpy forward kinematics from the Pinocchio model's joint placements.

For trees of one-axis joints about principal axes (``JointModelPX/PY/PZ/RX/RY/RZ``) and
free-flyers (``JointModelFreeFlyer``, the floating platform of the n-PSS), with ``point``
closures and a task of translations plus either the yaw ``rz`` of a planar chain or all
three angles (the :math:`\log_3` rows of :class:`plm_pin.core.task.TaskTarget`),
:class:`BatchKinematics` evaluates the closure-and-task residual and its exact Jacobian for
a whole batch of configurations in a few numpy operations:

.. math:: {}^0M_j = {}^0M_{\lambda(j)}\, M_j^{place}\, M_j(q_j), \qquad
          {}^0M_f = {}^0M_{j(f)}\, M_f^{place},

with the world-aligned Jacobian columns :math:`(a_k \times (p_f - p_k), a_k)` of a
rotation :math:`k` (a revolute, or one of a free-flyer's three, about the columns of its
world rotation) supporting frame :math:`f`, and :math:`(a_k, 0)` of a translation. The same
quantities as Pinocchio's ``computeJointJacobians`` + ``getFrameJacobian`` and the task
rows' :math:`J_{\log_3}` (tested to 1e-13), without a Python call per pose:
:func:`batch_newton` solves a whole grid row per call, which is what makes maps cost a few
microseconds per pose.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ..core.closures import Closure
from ..core.legs import Leg, sign_layout
from ..core.task import FrameTask, Task, wrap_angle
from ..kernels import Kernel
from ..tolerances import BATCH_LOG3_SERIES_ANGLE, FACTOR_RCOND, GRAM_RTOL, INVERSE_RTOL, LEG_SINGULAR_RTOL
from .manipulability import POSE_METRICS, batch_metrics

_AXES = {"X": 0, "Y": 1, "Z": 2}
_REVOLUTE, _PRISMATIC, _FREE_FLYER = 1, 2, 3
_NEAR_PI = np.pi - 1e-3
"""Rotation errors above this angle [rad] are left to the point-by-point path (NaN residual)."""


class Evaluation(NamedTuple):
    """One pass of :meth:`BatchKinematics.evaluate` over a batch of configurations.

    Attributes:
        r: residual ``[phi; x - x*]``, shape (B, m + k).
        J: its Jacobian (the Newton matrix), shape (B, m + k, nv).
        omega: where the task holds log3 rows, the task body's angular velocity rows that
            replace them in :meth:`ik_jacobian` (B, 3, nv); else None.
        R: world rotation of every joint (universe first), shape (B, njoints, 3, 3).
    """

    r: np.ndarray
    J: np.ndarray
    omega: np.ndarray | None
    R: np.ndarray

    def ik_jacobian(self, which: np.ndarray) -> np.ndarray:
        """The inverse-kinematics Jacobian ``[J_phi; J_x]`` at the poses ``which`` (an index or mask array).

        Task twist rows, as :func:`plm_pin.kinematics.jacobians.ik_jacobian`: ``J`` itself unless the
        task holds log3 rows (formed only for the poses asked, as Newton needs ``J`` at the others).
        """
        A = self.J[which]  # a copy (``which`` is an array)
        if self.omega is not None:
            A[:, -3:] = self.omega[which]
        return A


class _Tree(NamedTuple):
    """Constant arrays of :meth:`BatchKinematics.frames`."""

    levels: list[np.ndarray]
    """Joints by depth in the tree (depth 1 first)."""
    one: np.ndarray
    """One-axis joints."""
    K: np.ndarray
    """Skew matrix of each one-axis joint's axis (zero for a prismatic), shape (n_one, 3, 3)."""
    fixed: np.ndarray
    """What a rotation about the axis keeps: :math:`a a^T` (the identity for a prismatic)."""
    turned: np.ndarray
    """What it turns by the cosine: :math:`I - a a^T` (zero for a prismatic)."""
    E: np.ndarray
    """Axis of each prismatic (zero for a revolute), shape (n_one, 3)."""
    free: np.ndarray
    """Free-flyer joints."""


class BlockArrow(NamedTuple):
    r"""The block structure of a square inverse-kinematics matrix whose legs each close on the task body.

    With the task rows depending on the task body's (hub) columns only and each closure on the
    hub and its own leg's columns (as many as its rows), the matrix is, rows and columns
    permuted, :math:`\begin{bmatrix} P & L \\ E & 0 \end{bmatrix}` with :math:`L` block
    diagonal (one square block per leg, 3 x 3 on the 8-PSS), so that :math:`M x = b` is, exactly,

    .. math:: E\, x_{hub} = b_{task}, \qquad L_g\, x_g = b_g - P_g\, x_{hub} \quad \text{per leg } g,

    a k x k solve and one small solve per leg instead of an LU of the whole matrix.

    Attributes:
        hub: the task body's velocity columns (k of them).
        task_rows: the task rows (k of them).
        blocks: per leg block size, the legs' rows and columns, each of shape (n_legs, size).
    """

    hub: np.ndarray
    task_rows: np.ndarray
    blocks: tuple[tuple[np.ndarray, np.ndarray], ...]

    def solve(self, M: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Solutions ``x`` (B, n, r) of ``M x = b`` for matrices of this structure (B, n, n), ``b`` (B, n, r).

        Raises:
            numpy.linalg.LinAlgError: when the task block or a leg block of some pose is singular.
        """
        x = np.empty(b.shape)
        x_hub = np.linalg.solve(M[:, self.task_rows[:, None], self.hub], b[:, self.task_rows])
        x[:, self.hub] = x_hub
        for rows, cols in self.blocks:
            legs = M[:, rows[:, :, None], cols[:, None, :]]  # (B, n_legs, size, size)
            rhs = b[:, rows] - M[:, rows[:, :, None], self.hub] @ x_hub[:, None]
            x[:, cols] = np.linalg.solve(legs, rhs)
        return x


@dataclass(frozen=True)
class BatchKinematics:
    """Batched residual and Jacobian of the inverse-kinematics equations ``[phi(q); x(q) - x*]``.

    Build with :meth:`from_parts` (None when the model is not of the supported kind).

    Attributes:
        parents: parent joint of each joint (universe 0), shape (njoints,).
        place_R: joint placement rotations, shape (njoints, 3, 3).
        place_p: joint placement translations, shape (njoints, 3).
        kind: 1 revolute, 2 prismatic, 3 free-flyer (0 for the universe), shape (njoints,).
        axis: motion axis (0, 1, 2) of each one-axis joint (-1 otherwise).
        idx_q: first configuration index of each joint (-1 for the universe).
        idx_v: first velocity index of each joint (-1 for the universe).
        rotational: whether each velocity column is a rotation (else a translation), shape (nv,).
        frame_joint: parent joint of each used frame, shape (n_frames,).
        frame_R: frame placement rotations, shape (n_frames, 3, 3).
        frame_p: frame placement translations, shape (n_frames, 3).
        support: ``support[f, k]``: velocity column k moves frame f, shape (n_frames, nv).
        closure_a: index (in the used frames) of each closure's frame A.
        closure_b: index of each closure's frame B.
        task_frame: index of the task frame in the used frames.
        task_linear: selected translation rows (0..2).
        task_angular: ``"none"``, ``"yaw"`` (``rz`` of a planar chain) or ``"log3"`` (all three angles).
    """

    parents: np.ndarray
    place_R: np.ndarray
    place_p: np.ndarray
    kind: np.ndarray
    axis: np.ndarray
    idx_q: np.ndarray
    idx_v: np.ndarray
    rotational: np.ndarray
    frame_joint: np.ndarray
    frame_R: np.ndarray
    frame_p: np.ndarray
    support: np.ndarray
    closure_a: np.ndarray
    closure_b: np.ndarray
    task_frame: int
    task_linear: tuple[int, ...]
    task_angular: str

    @classmethod
    def from_parts(
        cls, model: pin.Model, closures: tuple[Closure, ...], task: Task
    ) -> BatchKinematics | None:
        """The batched evaluator of a model, or None when a joint, closure or task row is not supported.

        Supported: joints ``JointModelP{X,Y,Z}`` / ``JointModelR{X,Y,Z}`` and
        ``JointModelFreeFlyer``, ``point`` closures, tasks of ``x y z`` plus either ``rz``
        when every rotation axis is the world z (a planar chain, where the yaw rate is the
        z angular rate) or all of ``rx ry rz``; not joint tasks.
        """
        if not isinstance(task, FrameTask):
            return None
        kind, axis, rotational = [0], [-1], np.zeros(model.nv, dtype=bool)
        for j in range(1, model.njoints):
            short, iv = model.joints[j].shortname(), model.joints[j].idx_v
            if short == "JointModelFreeFlyer":
                kind.append(_FREE_FLYER)
                axis.append(-1)
                rotational[iv + 3 : iv + 6] = True
            elif short[:-1] in ("JointModelP", "JointModelR") and short[-1] in _AXES:
                kind.append(_REVOLUTE if short[-2] == "R" else _PRISMATIC)
                axis.append(_AXES[short[-1]])
                rotational[iv] = short[-2] == "R"
            else:
                return None
        if any(c.spec.type != "point" for c in closures):
            return None
        angular = task.angular
        if angular not in ((), (2,), (0, 1, 2)):
            return None
        frames = list(dict.fromkeys([f for c in closures for f in c.frame_ids] + [task.frame_id]))
        column_joint = np.empty(model.nv, dtype=int)
        for j in range(1, model.njoints):
            column_joint[model.joints[j].idx_v : model.joints[j].idx_v + model.joints[j].nv] = j
        out = cls(
            parents=np.array(model.parents, dtype=int),
            place_R=np.array([M.rotation for M in model.jointPlacements]),
            place_p=np.array([M.translation for M in model.jointPlacements]),
            kind=np.array(kind),
            axis=np.array(axis),
            idx_q=np.array([-1] + [model.joints[j].idx_q for j in range(1, model.njoints)]),
            idx_v=np.array([-1] + [model.joints[j].idx_v for j in range(1, model.njoints)]),
            rotational=rotational,
            frame_joint=np.array([model.frames[f].parentJoint for f in frames], dtype=int),
            frame_R=np.array([model.frames[f].placement.rotation for f in frames]),
            frame_p=np.array([model.frames[f].placement.translation for f in frames]),
            support=np.array(
                [np.isin(column_joint, list(model.supports[model.frames[f].parentJoint])) for f in frames]
            ),
            closure_a=np.array([frames.index(c.frame_ids[0]) for c in closures], dtype=int),
            closure_b=np.array([frames.index(c.frame_ids[1]) for c in closures], dtype=int),
            task_frame=frames.index(task.frame_id),
            task_linear=task.linear,
            task_angular={(): "none", (2,): "yaw", (0, 1, 2): "log3"}[angular],
        )
        if out.task_angular == "yaw":  # the yaw row needs every rotation about the world z
            if any(k != _REVOLUTE or a != 2 for k, a in zip(kind, axis, strict=True) if k in (1, 3)):
                return None
            if not all(np.allclose(R[:, 2], [0.0, 0.0, 1.0]) for R in out.place_R[1:]):
                return None
        return out

    @functools.cached_property
    def _tree(self) -> _Tree:
        """Constant arrays of :meth:`frames`: joints by depth, one-axis joints and their generators."""
        nj = self.parents.size
        depth = np.zeros(nj, dtype=int)
        for j in range(1, nj):
            depth[j] = int(depth[self.parents[j]]) + 1
        one = np.flatnonzero((self.kind == _REVOLUTE) | (self.kind == _PRISMATIC))
        eye = np.eye(3)
        K = np.zeros((one.size, 3, 3))
        fixed = np.broadcast_to(eye, K.shape).copy()
        E = np.zeros((one.size, 3))
        for n, jid in enumerate(one.tolist()):
            a = eye[self.axis[jid]]
            if self.kind[jid] == _REVOLUTE:
                K[n] = pin.skew(a)
                fixed[n] = np.outer(a, a)
            else:
                E[n] = a
        return _Tree(
            [np.flatnonzero(depth == d) for d in range(1, int(depth.max()) + 1)],
            one,
            K,
            fixed,
            eye - fixed,
            E,
            np.flatnonzero(self.kind == _FREE_FLYER),
        )

    def frames(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        r"""Column axes and origins, joint and frame rotations, frame origins (world) at ``q`` (B, nq).

        The joints of one depth in the tree are placed together: each joint's motion
        :math:`M_j(q_j)` (Rodrigues' formula about its axis, a translation along it, or a
        free-flyer's quaternion and translation), then :math:`{}^0M_{\lambda(j)} M_j^{place}
        M_j(q_j)` for the whole depth at once.

        Returns:
            axes (B, nv, 3), column origins (B, nv, 3), joint rotations (B, njoints, 3, 3),
            frame rotations (B, n_frames, 3, 3), frame origins (B, n_frames, 3).
        """
        tree = self._tree
        one, free = tree.one, tree.free
        B, nj, nv = q.shape[0], self.parents.size, self.rotational.size
        motion_R = np.empty((B, nj, 3, 3))
        motion_p = np.empty((B, nj, 3))
        value = q[:, self.idx_q[one]]
        s, c = np.sin(value), np.cos(value)
        # Rodrigues' formula about a principal axis, with entries exactly 1, 0, cos and +-sin
        motion_R[:, one] = tree.fixed + c[..., None, None] * tree.turned + s[..., None, None] * tree.K
        motion_p[:, one] = tree.E * value[..., None]
        for j in free:  # translation, then the quaternion (x, y, z, w)
            iq = self.idx_q[j]
            motion_R[:, j] = quaternion_matrix(q[:, iq + 3 : iq + 7])
            motion_p[:, j] = q[:, iq : iq + 3]
        R = np.empty((B, nj, 3, 3))
        p = np.empty((B, nj, 3))
        placed = np.empty((B, nj, 3, 3))  # parent rotation times placement: the axes of one-axis joints
        R[:, 0] = np.eye(3)
        p[:, 0] = 0.0
        for level in tree.levels:
            R_parent = R[:, self.parents[level]]
            Rp = R_parent @ self.place_R[level]
            placed[:, level] = Rp
            R[:, level] = Rp @ motion_R[:, level]
            p[:, level] = (
                p[:, self.parents[level]]
                + np.einsum("blij,lj->bli", R_parent, self.place_p[level])
                + np.einsum("blij,blj->bli", Rp, motion_p[:, level])
            )
        axes = np.empty((B, nv, 3))
        origins = np.empty((B, nv, 3))
        columns = self.idx_v[one]
        axes[:, columns] = np.swapaxes(placed, 2, 3)[:, one, self.axis[one]]
        origins[:, columns] = p[:, one]
        for j in free:
            iv = self.idx_v[j]
            axes[:, iv : iv + 3] = axes[:, iv + 3 : iv + 6] = np.swapaxes(R[:, j], 1, 2)
            origins[:, iv : iv + 6] = p[:, j, None]
        Rf = R[:, self.frame_joint] @ self.frame_R  # (B, nf, 3, 3)
        pf = p[:, self.frame_joint] + np.einsum("bfij,fj->bfi", R[:, self.frame_joint], self.frame_p)
        return axes, origins, R, Rf, pf

    @functools.cached_property
    def arrow(self) -> BlockArrow | None:
        """The :class:`BlockArrow` structure of the Newton and IK matrices, or None where they have none.

        Read from :attr:`support` (which columns move which frame), so a structural zero, not
        a value that happens to vanish: square matrices (as many task rows as the hub has
        columns) whose closures' non-hub columns fall into disjoint square leg blocks.
        """
        nv, n_closures = self.rotational.size, self.closure_a.size
        k = len(self.task_linear) + {"none": 0, "yaw": 1, "log3": 3}[self.task_angular]
        hub = np.flatnonzero(self.support[self.task_frame])
        if 3 * n_closures + k != nv or hub.size != k:
            return None
        moved = self.support[self.closure_a] | self.support[self.closure_b]
        moved[:, hub] = False
        legs: dict[tuple[int, ...], list[int]] = {}
        for i, row in enumerate(moved):
            legs.setdefault(tuple(np.flatnonzero(row).tolist()), []).append(i)
        cols = [c for leg in legs for c in leg]
        if len(cols) != len(set(cols)) or any(len(leg) != 3 * len(c) for leg, c in legs.items()):
            return None
        by_size: dict[int, list[tuple[list[int], tuple[int, ...]]]] = {}
        for leg, closures in legs.items():
            by_size.setdefault(len(leg), []).append(([3 * i + d for i in closures for d in range(3)], leg))
        return BlockArrow(
            hub,
            3 * n_closures + np.arange(k),
            tuple((np.array([r for r, _ in g]), np.array([c for _, c in g])) for g in by_size.values()),
        )

    @functools.cached_property
    def _pairs(self) -> tuple[np.ndarray, np.ndarray, tuple, tuple, tuple]:
        """The (frame, column) pairs where a velocity column moves a frame, and where each lands in ``J``.

        Returns the pairs' frames and columns, then for the closures' B frames, their A frames
        and the task frame: that frame's pairs and their entries in the flattened Jacobian
        (B, (m + k) * nv), three per pair (rows 3 i .. 3 i + 2 of closure i; the task's
        translation rows), in the order of ``lin[:, pairs].reshape(B, -1)``.
        """
        frame, column = np.nonzero(self.support)
        nv, m = self.rotational.size, 3 * self.closure_a.size

        def placed(frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            pairs = [np.flatnonzero(frame == f) for f in frames]
            at = [((3 * i + np.arange(3)) * nv + column[k, None]).reshape(-1) for i, k in enumerate(pairs)]
            return np.concatenate(pairs), np.concatenate(at)

        task = np.flatnonzero(frame == self.task_frame)
        rows = m + np.arange(len(self.task_linear))
        return (
            frame,
            column,
            placed(self.closure_b),
            placed(self.closure_a),
            (task, (rows * nv + column[task, None]).reshape(-1)),
        )

    def evaluate(self, q: np.ndarray, x: np.ndarray) -> Evaluation:
        """Residual, Newton matrix, IK Jacobian and joint rotations at ``q`` (B, nq) and targets ``x`` (B, k).

        Closure rows as :func:`plm_pin.core.closures.residual_from_placements` (three per
        point closure), task rows as :class:`plm_pin.core.task.TaskTarget` (NaN where a
        log3 rotation error is within 1e-3 rad of pi).
        """
        axes, origins, R, Rf, pf = self.frames(q)
        frame, column, (b_pair, b_at), (a_pair, a_at), (t_pair, t_at) = self._pairs
        B, nv, m = q.shape[0], self.rotational.size, 3 * self.closure_a.size
        t, rows, nl = self.task_frame, list(self.task_linear), len(self.task_linear)
        k = x.shape[1]
        # world-aligned linear velocity of a frame origin per supporting velocity column: (B, P, 3)
        ax = axes[:, column]
        lin = np.where(self.rotational[column, None], _cross(ax, pf[:, frame] - origins[:, column]), ax)
        r = np.empty((B, m + k))
        r[:, :m] = (pf[:, self.closure_b] - pf[:, self.closure_a]).reshape(B, m)
        r[:, m : m + nl] = pf[:, t, rows] - x[:, :nl]
        A = np.zeros((B, m + k, nv))
        flat = A.reshape(B, -1)
        flat[:, b_at] = lin[:, b_pair].reshape(B, -1)
        flat[:, a_at] -= lin[:, a_pair].reshape(B, -1)
        flat[:, t_at] = lin[:, t_pair][:, :, rows].reshape(B, -1)
        omega = np.swapaxes(axes * (self.rotational * self.support[t])[None, :, None], 1, 2)  # (B, 3, nv)
        if self.task_angular == "yaw":
            yaw = np.arctan2(Rf[:, t, 1, 0], Rf[:, t, 0, 0])
            r[:, -1] = wrap_angle(yaw - x[:, -1])
            A[:, -1] = omega[:, 2]
        if self.task_angular != "log3":
            return Evaluation(r, A, None, R)
        E = Rf[:, t] @ np.swapaxes(rpy_matrix(x[:, nl : nl + 3]), 1, 2)
        r[:, m + nl :], J_log = log3_and_jacobian(E)
        A[:, m + nl :] = J_log @ np.swapaxes(E, 1, 2) @ omega
        return Evaluation(r, A, omega, R)

    def integrate(self, q: np.ndarray, dv: np.ndarray) -> np.ndarray:
        r"""Configurations moved by velocity increments ``dv`` (B, nv), as ``pin.integrate`` to first order.

        One-axis joints add their increment; a free-flyer moves its origin by :math:`R\,dv_{lin}`
        and turns its quaternion by :math:`\exp(dv_{ang})` on the right (renormalised).
        """
        out = q.copy()
        one = self.kind[1:] != _FREE_FLYER
        out[:, self.idx_q[1:][one]] += dv[:, self.idx_v[1:][one]]
        for j in np.flatnonzero(self.kind == _FREE_FLYER):
            iq, iv = self.idx_q[j], self.idx_v[j]
            quat = q[:, iq + 3 : iq + 7]
            out[:, iq : iq + 3] += np.einsum("bij,bj->bi", quaternion_matrix(quat), dv[:, iv : iv + 3])
            turned = _quaternion_product(quat, _quaternion_exp(dv[:, iv + 3 : iv + 6]))
            out[:, iq + 3 : iq + 7] = turned / np.linalg.norm(turned, axis=1, keepdims=True)
        return out

    def normalized(self, q: np.ndarray) -> np.ndarray:
        """``q`` (B, nq) with every free-flyer quaternion scaled to unit norm (extrapolated guesses)."""
        out = q.copy()
        for j in np.flatnonzero(self.kind == _FREE_FLYER):
            iq = self.idx_q[j]
            out[:, iq + 3 : iq + 7] /= np.linalg.norm(q[:, iq + 3 : iq + 7], axis=1, keepdims=True)
        return out

    def turns(self, R: np.ndarray, legs: tuple[Leg, ...]) -> list[np.ndarray]:
        """Per square leg, signs (B, n_columns) turning each passive revolute column to its generic side.

        As :func:`plm_pin.core.legs.working_mode_from_data`: a column whose world axis,
        seen from the leg's root joint (rotations ``R`` of :class:`Evaluation`), points away
        from the leg's generic axis is negated.
        """
        square = [leg for leg in legs if leg.square]
        out = [np.ones((R.shape[0], len(leg.columns))) for leg in square]
        axes = [
            (i, k, jid, root, generic) for i, leg in enumerate(square) for k, jid, root, generic in leg.axes
        ]
        if not axes:
            return out
        which, column, jid, root, generic = (np.array(v) for v in zip(*axes, strict=True))
        world = R[:, jid, :, self.axis[jid]]  # (n_axes, B, 3): advanced indices apart go first
        # (R_root^T world) . generic = world . (R_root generic)
        away = np.einsum("abi,bai->ba", world, np.einsum("baij,aj->bai", R[:, root], generic)) < 0.0
        for t in range(len(axes)):
            out[which[t]][away[:, t], column[t]] = -1.0
        return out


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products over the last axis (of length 3), cheaper than ``np.cross`` on small stacks."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def quaternion_matrix(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices (B, 3, 3) of quaternions (B, 4) ``(x, y, z, w)``, normalised."""
    x, y, z, w = quat.T
    s = 2.0 / np.einsum("bi,bi->b", quat, quat)
    out = np.empty((quat.shape[0], 3, 3))
    out[:, 0, 0] = 1.0 - s * (y * y + z * z)
    out[:, 0, 1] = s * (x * y - z * w)
    out[:, 0, 2] = s * (x * z + y * w)
    out[:, 1, 0] = s * (x * y + z * w)
    out[:, 1, 1] = 1.0 - s * (x * x + z * z)
    out[:, 1, 2] = s * (y * z - x * w)
    out[:, 2, 0] = s * (x * z - y * w)
    out[:, 2, 1] = s * (y * z + x * w)
    out[:, 2, 2] = 1.0 - s * (x * x + y * y)
    return out


def _quaternion_exp(w: np.ndarray) -> np.ndarray:
    """Unit quaternions (B, 4) ``(x, y, z, w)`` of rotation vectors ``w`` (B, 3) [rad]."""
    theta = np.linalg.norm(w, axis=1)
    half = 0.5 * np.sinc(theta / (2.0 * np.pi))  # sin(theta / 2) / theta
    return np.concatenate([w * half[:, None], np.cos(0.5 * theta)[:, None]], axis=1)


def _quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products ``a b`` of quaternions (B, 4) ``(x, y, z, w)``."""
    va, wa, vb, wb = a[:, :3], a[:, 3:], b[:, :3], b[:, 3:]
    return np.concatenate(
        [wa * vb + wb * va + _cross(va, vb), wa * wb - np.sum(va * vb, axis=1, keepdims=True)], 1
    )


def rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """``pin.rpy.rpyToMatrix`` of roll-pitch-yaw angles (B, 3) [rad]: :math:`R_z R_y R_x`, shape (B, 3, 3)."""
    cr, cp, cy = np.cos(rpy).T
    sr, sp, sy = np.sin(rpy).T
    out = np.empty((rpy.shape[0], 3, 3))
    out[:, 0, 0] = cy * cp
    out[:, 0, 1] = cy * sp * sr - sy * cr
    out[:, 0, 2] = cy * sp * cr + sy * sr
    out[:, 1, 0] = sy * cp
    out[:, 1, 1] = sy * sp * sr + cy * cr
    out[:, 1, 2] = sy * sp * cr - cy * sr
    out[:, 2, 0] = -sp
    out[:, 2, 1] = cp * sr
    out[:, 2, 2] = cp * cr
    return out


def log3_and_jacobian(E: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""``pin.log3`` and ``pin.Jlog3`` of rotations (B, 3, 3): rotation vectors (B, 3) and (B, 3, 3).

    :math:`\omega = \theta / \sin\theta\; \mathrm{vee}(E - E^T) / 2` and
    :math:`J = I + [\omega]_\times / 2 + (1/\theta^2 - (1 + \cos\theta) / (2 \theta \sin\theta))
    [\omega]_\times^2`, their Taylor series below :data:`BATCH_LOG3_SERIES_ANGLE`; NaN above
    :data:`_NEAR_PI`, where the axis is ill-determined from the skew part.
    """
    v = 0.5 * np.stack([E[:, 2, 1] - E[:, 1, 2], E[:, 0, 2] - E[:, 2, 0], E[:, 1, 0] - E[:, 0, 1]], axis=1)
    s = np.linalg.norm(v, axis=1)
    c = 0.5 * (np.trace(E, axis1=1, axis2=2) - 1.0)
    theta = np.arctan2(s, c)
    small = theta < BATCH_LOG3_SERIES_ANGLE
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # the branch not taken
        factor = np.where(small, 1.0 + theta**2 / 6.0, theta / s)
        coef = np.where(small, 1.0 / 12.0 + theta**2 / 720.0, 1.0 / theta**2 - (1.0 + c) / (2.0 * theta * s))
    factor[theta > _NEAR_PI] = np.nan
    log = factor[:, None] * v
    K = np.zeros((E.shape[0], 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -log[:, 2], log[:, 1], -log[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = log[:, 2], -log[:, 1], log[:, 0]
    return log, np.eye(3) + 0.5 * K + coef[:, None, None] * (K @ K)


def batch_newton(
    kin: BatchKinematics, q0: np.ndarray, x: np.ndarray, tol: float, max_iterations: int, stall: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Newton on every configuration of a batch at once (each stops on its own).

    Args:
        kin: the evaluator.
        q0: starting configurations, shape (B, nq) (free-flyer quaternions are renormalised).
        x: task targets, shape (B, n_task).
        tol: residual tolerance [m, rad].
        max_iterations: iteration cap.
        stall: a pose whose residual does not fall below ``stall`` times the previous one fails.

    Returns:
        Configurations (B, nq), which converged (B,), the inverse-kinematics Jacobian
        ``[J_phi; J_x]`` at each (B, m + k, nv) and the joint rotations there (B, njoints, 3, 3).
    """
    q = kin.normalized(q0)
    B = q.shape[0]
    done = np.zeros(B, dtype=bool)
    failed = np.zeros(B, dtype=bool)
    err_prev = np.full(B, np.inf)
    live = np.arange(B)
    A_out: np.ndarray | None = None
    R_out: np.ndarray | None = None
    for iteration in range(max_iterations + 1):
        if live.size == 0:
            break
        e = kin.evaluate(q[live], x[live])
        r, J, R = e.r, e.J, e.R
        if A_out is None or R_out is None:
            A_out = np.empty((B, *J.shape[1:]))
            R_out = np.empty((B, *R.shape[1:]))
        err = np.abs(r).max(axis=1)
        ok = err <= tol
        A_out[live[ok]] = e.ik_jacobian(ok)
        R_out[live[ok]] = R[ok]
        done[live[ok]] = True
        bad = ~ok & ((err >= stall * err_prev[live]) | (iteration == max_iterations) | np.isnan(err))
        failed[live[bad]] = True
        go = ~ok & ~bad
        if not go.any():
            break
        step = _newton_steps(kin.arrow, J[go], r[go])
        idx = live[go]
        err_prev[idx] = err[go]
        bad_step = ~np.isfinite(step).all(axis=1)
        failed[idx[bad_step]] = True
        q[idx[~bad_step]] = kin.integrate(q[idx[~bad_step]], -step[~bad_step])
        live = idx[~bad_step]
    nv = kin.rotational.size
    if A_out is None or R_out is None:
        A_out = np.full((B, 0, nv), np.nan)
        R_out = np.full((B, kin.parents.size, 3, 3), np.nan)
    return q, done & ~failed, A_out, R_out


def _newton_steps(arrow: BlockArrow | None, J: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Gauss-Newton steps ``(J^T J)^-1 J^T r`` (B, nv); ``J^-1 r`` by blocks where ``J`` has the arrow form.

    A pose whose matrix is singular gets NaN (it fails; the others go on).
    """
    if arrow is not None:
        try:
            return arrow.solve(J, r[..., None])[..., 0]
        except np.linalg.LinAlgError:
            pass
    H = np.swapaxes(J, 1, 2) @ J
    g = np.einsum("bij,bi->bj", J, r)
    try:
        return np.linalg.solve(H, g[..., None])[..., 0]
    except np.linalg.LinAlgError:
        return np.stack([_solve_or_nan(h, v) for h, v in zip(H, g, strict=True)])


def _solve_or_nan(H: np.ndarray, g: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.solve(H, g)
    except np.linalg.LinAlgError:
        return np.full(g.shape, np.nan)


def batch_modes(
    A: np.ndarray,
    legs: tuple[Leg, ...],
    turns: list[np.ndarray] | None = None,
    rtol: float = LEG_SINGULAR_RTOL,
) -> np.ndarray:
    """Working modes of a batch of stacked Jacobians (B, m + k, nv): one sign per square leg, (B, n_legs).

    The batched :func:`plm_pin.core.legs.working_mode_from_jacobian`: the sign of each
    square leg block's determinant, 0 at or below ``rtol`` times Hadamard's bound. ``turns``
    (:meth:`BatchKinematics.turns`) orients the passive revolute columns as
    :func:`~plm_pin.core.legs.working_mode_from_data` does (default: none turned).
    """
    layout = sign_layout(legs)
    out = np.zeros((A.shape[0], layout.n_square), dtype=np.int8)
    for which, rows, cols in layout.blocks:  # the blocks of one size in one call
        n = rows.shape[1]
        M = A[:, rows[:, :, None], cols[:, None, :]]  # (B, n_which, n, n), one gather
        det = _small_det(M)
        if turns is not None:  # negating columns negates the determinant, exactly
            for w, i in enumerate(which):
                for c in range(n):  # cheaper than np.prod on these narrow arrays
                    det[:, w] *= turns[i][:, c]
        bound = np.prod(np.sqrt(np.einsum("bwij,bwij->bwj", M, M)), axis=-1)  # Hadamard's
        out[:, list(which)] = np.where(np.abs(det) <= rtol * bound, 0, np.sign(det))
    return out


def _small_det(M: np.ndarray) -> np.ndarray:
    """Determinants of a stack of square matrices (..., n, n): by cofactors up to 3 x 3, else LAPACK's LU.

    The cofactor sums are exact up to a few round-offs of Hadamard's bound, as the LU's are, and
    save the LAPACK call per matrix on the small leg blocks.
    """
    n = M.shape[-1]
    if n == 1:
        return M[..., 0, 0].copy()
    if n == 2:
        return M[..., 0, 0] * M[..., 1, 1] - M[..., 0, 1] * M[..., 1, 0]
    if n == 3:
        a, b, c = M[..., 0, 0], M[..., 0, 1], M[..., 0, 2]
        d, e, f = M[..., 1, 0], M[..., 1, 1], M[..., 1, 2]
        g, h, i = M[..., 2, 0], M[..., 2, 1], M[..., 2, 2]
        return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return np.linalg.det(M)


def _squared_singular_values(M: np.ndarray) -> np.ndarray:
    """Squared singular values of ``M`` (..., r, c), descending (..., min(r, c)), from its smaller Gram."""
    G = M @ np.swapaxes(M, -1, -2) if M.shape[-2] <= M.shape[-1] else np.swapaxes(M, -1, -2) @ M
    lam = np.linalg.eigvalsh(G)[..., ::-1][..., : min(M.shape[-2:])]
    return np.maximum(lam, 0.0)


def compiled_square_task_metrics(
    kernel: Kernel,
    A: np.ndarray,
    m: int,
    actuated_v: np.ndarray,
    mobility: int,
    names: Sequence[str] = POSE_METRICS,
) -> dict[str, np.ndarray]:
    """:func:`square_task_metrics` pose by pose on the compiled kernel (:meth:`Kernel.map_metrics`).

    The poses that fail its acceptance tests get
    :func:`~plm_pin.workspace.manipulability.batch_metrics` (SVD), as in the numpy path.
    """
    from ..kernels.metrics import METRIC_NAMES

    values, good = kernel.map_metrics(A, actuated_v, mobility, names)
    out = {name: values[:, METRIC_NAMES.index(name)].copy() for name in names}
    if not good.all():
        bad = ~good
        for name, v in batch_metrics(A[bad, :m], A[bad, m:], actuated_v, mobility, names=names).items():
            out[name][bad] = v
    return out


def square_task_metrics(
    A: np.ndarray,
    m: int,
    actuated_v: np.ndarray,
    mobility: int,
    arrow: BlockArrow | None = None,
    names: Sequence[str] = POSE_METRICS,
) -> dict[str, np.ndarray]:
    r"""The map metrics of stacked Jacobians ``A = [J_phi; J_x]`` (B, m + k, nv) from the Newton system.

    Where the task has as many rows as DOF, the velocity map :math:`S` (:math:`J_\phi S = 0`,
    :math:`J_x S = I`) solves the same normal equations as the Newton step,
    :math:`A^T A\, S = J_x^T` (or :math:`A S = [0; I]` itself where :math:`A` is square).
    Its QR factor :math:`N` (:math:`S = N R`) is an orthonormal basis of the feasible
    motions, standing in for the right singular vectors of :math:`J_\phi` in
    :func:`plm_pin.workspace.manipulability.batch_metrics` (whose values do not depend on the
    basis). With :math:`T = J_x N` (formed again from :math:`J_x`: :math:`R^{-1}` would carry
    the rounding of the normal equations) and :math:`C = N_a` (the actuated rows):

    .. math:: J_{ce} = C T^{-1}, \quad w = \prod_i \sigma_i(J_{ce}), \quad
              \kappa = \frac{\sigma_{max}(J_{ce})}{\sigma_{min}(J_{ce})}, \quad
              \text{inverse margin} = \frac{1}{\sigma_{max}(T^{-1})\, \sigma_{max}(J_x)},
              \quad \text{direct margin} = \sigma_{min}(C).

    The singular values come from the eigenvalues of the small Gram matrices (``eigvalsh``,
    cheaper than an SVD of each matrix) where that is accurate (:data:`GRAM_RTOL`); poses
    where it is not, where :math:`S` is ill-conditioned (:data:`FACTOR_RCOND`) or where
    :math:`T` is singular get :func:`~plm_pin.workspace.manipulability.batch_metrics` (SVD).
    Only what ``names`` needs is computed (the constraint margin alone needs no :math:`S`);
    without the inverse margin, :math:`T` is tested with the Frobenius norms, bounds of
    :math:`\sigma_{max}` from above (a pose passing that test passes the exact one).

    Args:
        A: stacked Jacobians, shape (B, m + k, nv).
        m: closure rows.
        actuated_v: velocity indices of the actuators.
        mobility: DOF (= k).
        arrow: the block structure of ``A`` (:attr:`BatchKinematics.arrow`), solved by blocks.
        names: the metrics to compute, among
            :data:`~plm_pin.workspace.manipulability.POSE_METRICS` (default: all).

    Returns:
        ``{name: (B,) array}`` for every name of ``names``, as
        :func:`~plm_pin.workspace.manipulability.batch_metrics` returns.
    """
    J_phi, J_x = A[:, :m], A[:, m:]
    want_ce = "manipulability" in names or "condition_number" in names  # J_ce = C T^-1
    want_t = want_ce or "inverse_margin" in names
    good = np.ones(A.shape[0], dtype=bool)
    out: dict[str, np.ndarray] = {}
    with np.errstate(divide="ignore", invalid="ignore"):
        if want_t or "direct_margin" in names:
            try:
                if A.shape[1] == A.shape[2]:  # as many rows as velocities: A S = [0; I], no normal matrix
                    E = np.broadcast_to(np.eye(A.shape[1])[:, m:], (*A.shape[:2], mobility))
                    S = np.linalg.solve(A, E) if arrow is None else arrow.solve(A, E)
                else:
                    S = np.linalg.solve(np.swapaxes(A, 1, 2) @ A, np.swapaxes(J_x, 1, 2))  # (B, nv, k)
            except np.linalg.LinAlgError:
                return batch_metrics(J_phi, J_x, actuated_v, mobility, names=names)
            finite = np.isfinite(S).all(axis=(1, 2))
            S[~finite] = 0.0
            N, Rs = np.linalg.qr(S)
            d = np.abs(np.diagonal(Rs, axis1=1, axis2=2))
            good = finite & (d.min(axis=1) > FACTOR_RCOND * d.max(axis=1))
            C = N[:, actuated_v]
        if want_t:
            T_inv = np.linalg.inv(np.where(good[:, None, None], J_x @ N, np.eye(mobility)))
            if "inverse_margin" in names:
                s_T_inv = np.sqrt(_squared_singular_values(T_inv)[:, 0])
                s_x = np.sqrt(_squared_singular_values(J_x)[:, 0])
                out["inverse_margin"] = 1.0 / (s_T_inv * s_x)
                good &= out["inverse_margin"] > INVERSE_RTOL
            else:
                good &= (
                    1.0 / (np.linalg.norm(T_inv, axis=(1, 2)) * np.linalg.norm(J_x, axis=(1, 2)))
                    > INVERSE_RTOL
                )
        if want_ce:
            s2_ce = _squared_singular_values(C @ T_inv)
            good &= s2_ce[:, -1] > GRAM_RTOL * s2_ce[:, 0]
            s_ce = np.sqrt(s2_ce)
            out["manipulability"] = np.prod(s_ce, axis=1)
            out["condition_number"] = s_ce[:, 0] / s_ce[:, -1]
        if "direct_margin" in names:
            s2_c = _squared_singular_values(C)
            good &= s2_c[:, -1] > GRAM_RTOL * s2_c[:, 0]
            out["direct_margin"] = np.sqrt(s2_c[:, -1])
        if "constraint_margin" in names:
            s2_phi = _squared_singular_values(J_phi)[:, [0, J_phi.shape[-1] - mobility - 1]]
            good &= s2_phi[:, 1] > GRAM_RTOL * s2_phi[:, 0]
            out["constraint_margin"] = np.sqrt(s2_phi[:, 1] / s2_phi[:, 0])
    out = {name: out[name] for name in names}
    if not good.all():
        bad = ~good
        for name, v in batch_metrics(J_phi[bad], J_x[bad], actuated_v, mobility, names=names).items():
            out[name][bad] = v
    return out
