r"""Task coordinates, their Jacobian, and task targets for solvers.

A task is either the pose of an end-effector frame (:class:`FrameTask`) or the positions of
output joints (:class:`JointTask`, for a linkage without an end effector: a gripper finger,
a knee four-bar).

Frame tasks: coordinates ``x`` are the selected entries of ``(p, rpy)``: the frame origin in
the world [m] and its roll-pitch-yaw angles [rad] with :math:`R = R_z(r_z) R_y(r_y) R_x(r_x)`
(``pin.rpy``; for a planar task ``rz`` is the plate angle). Task *velocities* are the
selected entries of the frame's world-aligned twist :math:`(v, \omega)`; for a planar task
:math:`\omega_z = \dot r_z`, for spatial rotations :math:`\omega` differs from
:math:`\dot{rpy}` (use :func:`rpy_rates`).

Joint tasks: coordinates are the output joints' positions [m] or [rad] (a revolute angle
wrapped to (-pi, pi]), their velocities the joints' velocities: the Jacobian selects
columns of the identity and the acceleration drift is zero.
"""

from __future__ import annotations

import abc
import functools
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .._arguments import as_vector
from ..description.sidecar import TASK_DOFS, TaskSpec
from ..exceptions import DescriptionError

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
TWO_PI = 2.0 * math.pi


def wrap_angle(a: np.ndarray | float) -> np.ndarray:
    """Angle(s) wrapped to (-pi, pi] [rad]."""
    return np.asarray(np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2.0 * np.pi))


class Task(abc.ABC):
    """A compiled task: coordinates ``x(q)``, their Jacobian and acceleration drift.

    Attributes:
        dofs: the coordinates' names (directions of a frame task, joints of a joint task).
    """

    dofs: tuple[str, ...]

    @property
    def size(self) -> int:
        """Number of task coordinates."""
        return len(self.dofs)

    @property
    @abc.abstractmethod
    def angles(self) -> list[int]:
        """Indices of the coordinates that are angles [rad] (to wrap or unwrap)."""

    @abc.abstractmethod
    def pose_from_data(self, data: pin.Data) -> np.ndarray:
        """Task coordinates from the placements already in ``data``, shape (n_task,)."""

    @abc.abstractmethod
    def jacobian_from_data(
        self, model: pin.Model, data: pin.Data, out: np.ndarray | None = None
    ) -> np.ndarray:
        """Task Jacobian from joint Jacobians in ``data``, shape (n_task, nv); into ``out`` when given."""

    @abc.abstractmethod
    def drift_from_data(self, model: pin.Model, data: pin.Data) -> np.ndarray:
        r"""Task acceleration drift :math:`\dot J_x v` from the kinematics of ``(q, v, 0)`` in ``data``."""


@dataclass(frozen=True)
class FrameTask(Task):
    """A compiled frame task: frame index and selected rows of ``(p, rpy)`` / ``(v, omega)``.

    Attributes:
        frame_id: Pinocchio frame index.
        rows: selected rows among ``x y z rx ry rz`` (0..5).
        dofs: their names.
    """

    frame_id: int
    rows: tuple[int, ...]
    dofs: tuple[str, ...]

    @property
    def angles(self) -> list[int]:
        """Indices of the rotation coordinates (``rx ry rz``) among the task's."""
        return [k for k, r in enumerate(self.rows) if r >= 3]

    @functools.cached_property
    def linear(self) -> tuple[int, ...]:
        """Selected translation rows (0..2)."""
        return tuple(r for r in self.rows if r < 3)

    @functools.cached_property
    def angular(self) -> tuple[int, ...]:
        """Selected rotation rows (0..2, i.e. rx ry rz)."""
        return tuple(r - 3 for r in self.rows if r >= 3)

    @functools.cached_property
    def selectors(self) -> tuple[slice | list[int], slice | list[int], slice | list[int]]:
        """Indices of :attr:`rows` in a 6-vector, of :attr:`linear` and of :attr:`angular` in 3-vectors.

        Slices where the rows are consecutive (the usual case): they index faster than lists.
        """
        return _selector(self.rows), _selector(self.linear), _selector(self.angular)

    def pose_from_data(self, data: pin.Data) -> np.ndarray:
        """Task coordinates from frame placements already in ``data``, shape (n_task,)."""
        M = data.oMf[self.frame_id]
        full = np.concatenate([M.translation, pin.rpy.matrixToRpy(M.rotation)])
        return full[self.selectors[0]]

    def jacobian_from_data(
        self, model: pin.Model, data: pin.Data, out: np.ndarray | None = None
    ) -> np.ndarray:
        """Task Jacobian (world-aligned twist rows) from joint Jacobians in ``data``, shape (n_task, nv).

        Written into ``out`` (shape (n_task, nv)) when given.
        """
        J = pin.getFrameJacobian(model, data, self.frame_id, _LWA)[self.selectors[0]]
        if out is None:
            return J
        out[:] = J
        return out

    def drift_from_data(self, model: pin.Model, data: pin.Data) -> np.ndarray:
        r"""Task acceleration drift :math:`\dot J_x v`, shape (n_task,).

        ``data`` must hold the kinematics of ``(q, v, 0)`` (``pin.forwardKinematics`` with zero
        acceleration, then ``pin.updateFramePlacements``): the classical acceleration of the
        frame origin and the angular acceleration, world-aligned, of the selected rows.
        """
        acc = pin.getFrameClassicalAcceleration(model, data, self.frame_id, _LWA)
        return acc.vector[self.selectors[0]]


def _selector(rows: tuple[int, ...]) -> slice | list[int]:
    if rows and rows == tuple(range(rows[0], rows[-1] + 1)):
        return slice(rows[0], rows[-1] + 1)
    return list(rows)


@dataclass(frozen=True, eq=False)
class JointTask(Task):
    """A compiled joint task: the positions of output joints (one-DOF revolute or prismatic).

    Attributes:
        joint_ids: Pinocchio joint indices.
        v_indices: their velocity indices.
        revolute: whether each joint is revolute (angle [rad]) or prismatic (position [m]).
        axes: each joint's axis in its own frame, shape (3,) each.
        placements: each joint's placement in its parent joint's frame (``model.jointPlacements``).
        dofs: the joint names.
    """

    joint_ids: tuple[int, ...]
    v_indices: tuple[int, ...]
    revolute: tuple[bool, ...]
    axes: tuple[np.ndarray, ...]
    placements: tuple[pin.SE3, ...]
    dofs: tuple[str, ...]

    @property
    def angles(self) -> list[int]:
        """Indices of the revolute joints among the task's."""
        return [k for k, r in enumerate(self.revolute) if r]

    def pose_from_data(self, data: pin.Data) -> np.ndarray:
        """Joint positions [m, rad] from the joint placements ``data.liMi``, shape (n_task,).

        The joint's own motion is its placement relative to its parent with the fixed
        placement taken out; a revolute angle is wrapped to (-pi, pi].
        """
        out = np.empty(self.size)
        for k, (jid, axis, M0) in enumerate(zip(self.joint_ids, self.axes, self.placements, strict=True)):
            M = M0.actInv(data.liMi[jid])
            out[k] = float(pin.log3(M.rotation) @ axis) if self.revolute[k] else float(M.translation @ axis)
        return out

    def jacobian_from_data(
        self, model: pin.Model, data: pin.Data, out: np.ndarray | None = None
    ) -> np.ndarray:
        """Rows of the identity at the output joints' velocity indices, shape (n_task, nv)."""
        J = np.zeros((self.size, model.nv)) if out is None else out
        J[:] = 0.0
        J[np.arange(self.size), list(self.v_indices)] = 1.0
        return J

    def drift_from_data(self, model: pin.Model, data: pin.Data) -> np.ndarray:
        """Zero: a joint's acceleration is its entry of the tree acceleration, shape (n_task,)."""
        return np.zeros(self.size)


def compile_task(model: pin.Model, frame: str, dofs: tuple[str, ...]) -> FrameTask:
    """Compile a frame task (directions ``dofs`` of ``frame``) against a model."""
    return FrameTask(model.getFrameId(frame), tuple(TASK_DOFS.index(d) for d in dofs), dofs)


def compile_joint_task(model: pin.Model, joints: tuple[str, ...]) -> JointTask:
    """Compile a joint task (the positions of ``joints``) against a model.

    Raises:
        DescriptionError: when a joint is missing or is not a one-DOF revolute or prismatic joint.
    """
    data = model.createData()
    q0 = pin.neutral(model)
    pin.computeJointJacobians(model, data, q0)
    ids, vs, rev, axes, placements = [], [], [], [], []
    for name in joints:
        if not model.existJointName(name):
            raise DescriptionError(
                f"end_effector.joints: no joint {name!r}; joints are {list(model.names)[1:]}"
            )
        jid = model.getJointId(name)
        joint = model.joints[jid]
        short = joint.shortname()
        if joint.nv != 1 or not short.startswith(("JointModelR", "JointModelP")):
            raise DescriptionError(
                f"end_effector.joints: joint {name!r} ({short}) is not a one-DOF revolute or prismatic "
                "joint; a joint task takes such joints only"
            )
        S = pin.getJointJacobian(model, data, jid, pin.ReferenceFrame.LOCAL)[:, joint.idx_v]
        revolute = short.startswith("JointModelR")
        ids.append(jid)
        vs.append(joint.idx_v)
        rev.append(revolute)
        axes.append(np.array(S[3:] if revolute else S[:3]))
        placements.append(model.jointPlacements[jid].copy())
    return JointTask(tuple(ids), tuple(vs), tuple(rev), tuple(axes), tuple(placements), tuple(joints))


def compile_task_spec(model: pin.Model, spec: TaskSpec) -> Task:
    """Compile a sidecar task (a frame's directions, or output joints) against a model."""
    if spec.frame is None:
        return compile_joint_task(model, spec.dofs)
    return compile_task(model, spec.frame, spec.dofs)


class TaskTarget:
    r"""Residual rows that pin the task frame at given task coordinates.

    Translation rows: :math:`p - p^*`. Rotation rows: with all three angles selected,
    :math:`\log_3(R R^{*T})` (no representation singularity); otherwise the wrapped
    difference of the selected roll-pitch-yaw angles. Jacobians are exact.
    """

    def __init__(self, task: Task, x: np.ndarray) -> None:
        """Target ``x`` (task coordinates, shape (n_task,)) for ``task``."""
        self.task = task
        self.x = np.asarray(x, dtype=float)
        self._joints = task if isinstance(task, JointTask) else None
        if not isinstance(task, FrameTask):
            return
        self.frame_task = task
        _, self._lin, self._ang = task.selectors
        self._n_lin = nl = len(task.linear)
        self._x_lin, self._x_ang = self.x[:nl], self.x[nl:]
        self._R: np.ndarray | None = None  # target rotation, when all three angles are selected
        self._angle = task.angular[0] if len(task.angular) == 1 else None  # the one angle selected
        self._x_angle = float(self._x_ang[0]) if self._angle is not None else 0.0
        if len(task.angular) == 3:
            rpy = np.empty(3)
            rpy[self._ang] = self._x_ang
            self._R = pin.rpy.rpyToMatrix(rpy)

    @property
    def size(self) -> int:
        """Number of residual rows."""
        return self.task.size

    def residual(self, data: pin.Data, out: np.ndarray | None = None) -> np.ndarray:
        """Residual from placements in ``data``, shape (n_task,); written into ``out`` when given.

        For a joint task: the joint positions minus the target, revolute angles wrapped.
        """
        r = np.empty(self.size) if out is None else out
        if self._joints is not None:
            d = self._joints.pose_from_data(data) - self.x
            r[:] = np.where(self._joints.revolute, wrap_angle(d), d)
            return r
        M = data.oMf[self.frame_task.frame_id]
        nl = self._n_lin
        r[:nl] = M.translation[self._lin] - self._x_lin
        if self._R is not None:
            r[nl:] = pin.log3(M.rotation @ self._R.T)
        elif self._angle is not None:  # wrap_angle in Python floats (the same operations)
            a = float(pin.rpy.matrixToRpy(M.rotation)[self._angle]) - self._x_angle
            r[nl] = math.pi - (math.pi - a) % TWO_PI
        elif nl < r.size:
            r[nl:] = wrap_angle(pin.rpy.matrixToRpy(M.rotation)[self._ang] - self._x_ang)
        return r

    def jacobian(self, model: pin.Model, data: pin.Data, out: np.ndarray | None = None) -> np.ndarray:
        """Exact Jacobian of :meth:`residual` from joint Jacobians in ``data``, shape (n_task, nv).

        Written into ``out`` (shape (n_task, nv)) when given.
        """
        if self._joints is not None:
            return self._joints.jacobian_from_data(model, data, out)
        J = pin.getFrameJacobian(model, data, self.frame_task.frame_id, _LWA)
        A = np.empty((self.size, model.nv)) if out is None else out
        nl = self._n_lin
        A[:nl] = J[self._lin]
        if nl < A.shape[0]:
            R = data.oMf[self.frame_task.frame_id].rotation
            if self._R is not None:
                E = R @ self._R.T
                A[nl:] = pin.Jlog3(E) @ E.T @ J[3:]
            else:
                rpy = pin.rpy.matrixToRpy(R)
                A[nl:] = (pin.rpy.computeRpyJacobianInverse(rpy, pin.ReferenceFrame.WORLD) @ J[3:])[self._ang]
        return A


def rpy_rates(rpy: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Roll-pitch-yaw rates [rad/s] from a world angular velocity [rad/s], shape (3,)."""
    return np.asarray(
        pin.rpy.computeRpyJacobianInverse(np.asarray(rpy, float), pin.ReferenceFrame.WORLD) @ omega
    )


def check_task_vector(x: object, size: int, name: str = "x") -> np.ndarray:
    """Return ``x`` as a float array of shape (size,); refuse non-numbers, wrong shapes, non-finite values."""
    return as_vector(x, size, name)
