r"""Task coordinates of the end-effector frame, their Jacobian, and task targets for solvers.

Task coordinates ``x`` are the selected entries of ``(p, rpy)``: the frame origin in the
world [m] and its roll-pitch-yaw angles [rad] with :math:`R = R_z(r_z) R_y(r_y) R_x(r_x)`
(``pin.rpy``; for a planar task ``rz`` is the plate angle). Task *velocities* are the
selected entries of the frame's world-aligned twist :math:`(v, \omega)`; for a planar task
:math:`\omega_z = \dot r_z`, for spatial rotations :math:`\omega` differs from
:math:`\dot{rpy}` (use :func:`rpy_rates`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .._arguments import as_vector
from ..description.sidecar import TASK_DOFS

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
TWO_PI = 2.0 * math.pi


def wrap_angle(a: np.ndarray | float) -> np.ndarray:
    """Angle(s) wrapped to (-pi, pi] [rad]."""
    return np.asarray(np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2.0 * np.pi))


@dataclass(frozen=True)
class Task:
    """A compiled task: frame index and selected rows of ``(p, rpy)`` / ``(v, omega)``.

    Attributes:
        frame_id: Pinocchio frame index.
        rows: selected rows among ``x y z rx ry rz`` (0..5).
        dofs: their names.
    """

    frame_id: int
    rows: tuple[int, ...]
    dofs: tuple[str, ...]

    @property
    def size(self) -> int:
        """Number of task coordinates."""
        return len(self.rows)

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


def compile_task(model: pin.Model, frame: str, dofs: tuple[str, ...]) -> Task:
    """Compile a task spec against a model."""
    return Task(model.getFrameId(frame), tuple(TASK_DOFS.index(d) for d in dofs), dofs)


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
        """Residual from placements in ``data``, shape (n_task,); written into ``out`` when given."""
        M = data.oMf[self.task.frame_id]
        r = np.empty(self.size) if out is None else out
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
        J = pin.getFrameJacobian(model, data, self.task.frame_id, _LWA)
        A = np.empty((self.size, model.nv)) if out is None else out
        nl = self._n_lin
        A[:nl] = J[self._lin]
        if nl < A.shape[0]:
            R = data.oMf[self.task.frame_id].rotation
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
