r"""Workspaces: the mutable buffers of kinematic computations, owned by their caller.

A :class:`~plm_pin.Mechanism` is immutable after construction (its cached properties are
computed once, from the mechanism alone) and holds nothing a call leaves behind for the
next one. What a computation writes (a Pinocchio ``Data`` with frame placements and joint
Jacobians, the residual and Jacobian of a Newton solve) lives in a :class:`Workspace`:
hot loops create one per thread with :meth:`plm_pin.Mechanism.workspace` and pass it to
each call, so that nothing is allocated per pose and nothing is shared between threads.

Thread safety: a Mechanism may be shared by threads (and pickled to processes); a
Workspace may not be shared by two threads at once.

:func:`placement_views` gives numpy views of frame placements inside a ``pin.Data``: they
follow every update of the placements, so a solver reads them without a Python call per
frame and pass.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

PlacementViews = tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]
"""Translations (3,) and rotations (3, 3) of some frames, as live views into a ``pin.Data``."""

VIEWS_KEPT = 64
"""Number of Pinocchio datas whose placement views are kept (the one seen first is dropped first)."""

_VIEWS: dict[int, tuple[pin.Data, dict[tuple[bool, tuple[int, ...]], PlacementViews]]] = {}
"""Per Pinocchio data (by id, with the data: the views keep it alive anyway), the views of each frame
(or joint) tuple.

Not a ``WeakKeyDictionary``: ``pin.Data.__eq__`` compares whole contents, which a lookup would call.
"""


def placement_views(data: pin.Data, frames: tuple[int, ...], *, joints: bool = False) -> PlacementViews:
    """Views of ``data.oMf[f].translation`` and ``.rotation`` for each frame ``f`` of ``frames``.

    With ``joints``, of the joint placements ``data.oMi[j]`` for each joint ``j`` of ``frames``.
    Pinocchio 4.1 returns these arrays as views into the placements it stores (a vector
    sized once, when the data is created), and each view keeps the data alive: each pass of
    ``framesForwardKinematics`` or ``updateFramePlacements`` (of ``forwardKinematics`` or
    ``computeJointJacobians`` for joints) shows in them, with no Python call per frame. The
    views are made once per data and frame tuple and kept for the last :data:`VIEWS_KEPT`
    datas seen (older ones are dropped, with the data they hold).
    """
    key = id(data)
    hit = _VIEWS.get(key)
    if hit is None:  # while an entry lives its data does too, so its id is not reused
        if len(_VIEWS) >= VIEWS_KEPT:
            _VIEWS.pop(next(iter(_VIEWS)), None)
        hit = _VIEWS[key] = (data, {})
    per_data = hit[1]
    views = per_data.get((joints, frames))
    if views is None:
        placements = data.oMi if joints else data.oMf
        views = per_data[joints, frames] = (
            tuple(placements[f].translation for f in frames),
            tuple(placements[f].rotation for f in frames),
        )
    return views


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
