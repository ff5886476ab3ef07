r"""Workspaces: the mutable buffers of kinematic computations, owned by their caller.

A :class:`~plm_pin.Mechanism` is immutable after construction (its cached properties are
computed once, from the mechanism alone) and holds nothing a call leaves behind for the
next one. What a computation writes (a Pinocchio ``Data`` with frame placements and joint
Jacobians, the residual and Jacobian of a Newton solve) lives in a :class:`Workspace`:
hot loops create one per thread with :meth:`plm_pin.Mechanism.workspace` and pass it to
each call, so that nothing is allocated per pose and nothing is shared between threads.

Thread safety: a Mechanism may be shared by threads (and pickled to processes); a
Workspace may not be shared by two threads at once.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin


@dataclass
class Workspace:
    """Pinocchio data and preallocated Newton buffers for one mechanism, one thread at a time.

    Attributes:
        data: Pinocchio data of the mechanism's model.
        residual: stacked residual ``[closures; task]`` [m, rad], shape (m + n_task,).
        jacobian: its Jacobian on the tangent space, shape (m + n_task, nv).
        m: number of closure rows.
    """

    data: pin.Data
    residual: np.ndarray
    jacobian: np.ndarray
    m: int
    _views: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        m = self.m
        self._views = (self.residual[:m], self.residual[m:], self.jacobian[:m], self.jacobian[m:])

    @classmethod
    def create(cls, model: pin.Model, m: int, n_task: int) -> Workspace:
        """A workspace for ``model`` with ``m`` closure rows and ``n_task`` task rows."""
        return cls(model.createData(), np.empty(m + n_task), np.empty((m + n_task, model.nv)), m)

    @property
    def closure_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """Views of the closure part of the residual (m,) and of the Jacobian (m, nv)."""
        return self._views[0], self._views[2]

    @property
    def task_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """Views of the task part of the residual (n_task,) and of the Jacobian (n_task, nv)."""
        return self._views[1], self._views[3]
