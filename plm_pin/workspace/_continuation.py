r"""Inverse-kinematics continuation over grids of task poses (private helpers of the analysis).

:class:`IKEvaluator` solves the inverse kinematics at one pose by Newton's method on the
closure rows (:mod:`plm_pin.core.closures`) and the task rows
(:class:`plm_pin.core.task.TaskTarget`), from a predicted configuration, and leaves
the exact Jacobians at the solution for the working mode and the metrics. It skips what
the general solver :func:`plm_pin.kinematics.assemble` does for robustness from far away
(SVD of every step, step rejection with damping): continuation starts within a grid step
of the solution, where the Gauss-Newton step through the normal equations converges
quadratically. Every accepted point still satisfies the closures and the task to ``tol``.

:func:`flood` walks a grid from solved points to their neighbours (breadth first),
predicting each configuration by polynomial extrapolation along the line it is reached
on, so that one Newton step usually suffices, and keeping the working mode: a point whose
solution changes the sign of a leg block
(:func:`plm_pin.core.legs.working_mode_from_jacobian`) is not taken from that
neighbour. When the walk ends with unreached stretches left (a leg out of reach between
two reachable arcs, such as the flipped plate of a planar table), :func:`reseed` solves the
inverse kinematics afresh, in the working mode kept, at a few points of each stretch, and
walks on from those it reaches. Points never reached are left unreachable.
"""

from __future__ import annotations

import itertools
import multiprocessing
import os
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import count, positive, real_numbers
from .._lazy import lazy_module
from ..core import closures as _closures
from ..core.assembly import NEWTON_MAX_ITERATIONS, STALL_RATIO, newton
from ..core.legs import Leg, ik_jacobian_from_data, working_mode_from_data
from ..core.mechanism import Mechanism, require_task
from ..core.task import FrameTask, Task, TaskTarget
from ..exceptions import InvalidInput, PoseUnreachable
from ..kernels import Kernel, kernel_of
from ..kinematics.forward import task_pose
from ..kinematics.inverse import check_mode, inverse_kinematics
from ..kinematics.working_mode import start_configuration
from ._batch import (
    BatchKinematics,
    batch_modes,
    batch_newton,
    compiled_square_task_metrics,
    rpy_matrix,
    square_task_metrics,
)
from .manipulability import POSE_METRICS, batch_metrics

ndimage = lazy_module("scipy.ndimage")  # label: the unreached regions of a grid


@dataclass
class IKEvaluator:
    """Newton corrector, Jacobians and working mode of one mechanism, picklable for worker processes.

    Build with :meth:`from_mechanism`. The Pinocchio data is created on first use in each
    process.
    """

    model: pin.Model
    closures: tuple[_closures.Closure, ...]
    task: Task
    legs: tuple[Leg, ...]
    mobility: int
    actuated_v: np.ndarray
    linear_q: bool
    kernel: Kernel | None = None
    _data: pin.Data | None = field(default=None, repr=False)

    @classmethod
    def from_mechanism(cls, mech: Mechanism) -> IKEvaluator:
        """Collect what the continuation needs from ``mech``."""
        model = mech.model
        return cls(
            model=model,
            closures=tuple(mech.closures),
            task=require_task(mech),
            legs=tuple(mech.legs),
            mobility=mech.mobility,
            actuated_v=np.asarray(mech.actuated_v_indices),
            linear_q=all(model.joints[j].nq == model.joints[j].nv for j in range(1, model.njoints)),
            kernel=kernel_of(mech),
        )

    def __post_init__(self) -> None:
        self.m = _closures.closure_rows(self.closures)
        self.n_legs = sum(leg.square for leg in self.legs)
        # the working modes read leg blocks of the IK Jacobian only (no other platform row)
        self.modes_in_ik = all(
            max(leg.sign_rows) < self.m + self.task.size for leg in self.legs if leg.square
        )
        self._r = np.empty(self.m + self.task.size)  # residual [closures; task]
        self._A = np.empty((self.m + self.task.size, self.nv))  # its Jacobian

    def __getstate__(self) -> dict[str, Any]:
        keep = ("model", "closures", "task", "legs", "mobility", "actuated_v", "linear_q", "kernel")
        return {k: self.__dict__[k] for k in keep}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._data = None
        self.__post_init__()

    @property
    def data(self) -> pin.Data:
        """Scratch data of this evaluator (one per process)."""
        if self._data is None:
            self._data = self.model.createData()
        return self._data

    @property
    def nv(self) -> int:
        """Tree velocity size."""
        return int(self.model.nv)

    def solve(self, x: np.ndarray, q0: np.ndarray, tol: float, data: bool = True) -> np.ndarray | None:
        """Configuration at task coordinates ``x`` by Newton from ``q0``, or None.

        :func:`plm_pin.core.assembly.newton` without its polishing step: the attempt
        ends when an iteration does not reduce the residual by the factor
        :data:`~plm_pin.core.assembly.STALL_RATIO`, or after
        :data:`~plm_pin.core.assembly.NEWTON_MAX_ITERATIONS`; on the compiled kernels where
        they serve the mechanism. On success the data holds the joint Jacobians and frame
        placements at the returned configuration (read them with :meth:`jacobian`); on the
        kernels, only if ``data``.
        """
        target = TaskTarget(self.task, x)
        if self.kernel is not None:
            solved = self.kernel.newton(q0, None, tol, target, polish=False)
            if solved is None:
                return None
            if data:
                pin.computeJointJacobians(self.model, self.data, solved[0])
                pin.updateFramePlacements(self.model, self.data)
            return solved[0]
        found = newton(
            self.model,
            self.data,
            self.closures,
            q0,
            None,
            self._r,
            self._A,
            tol=tol,
            extra=target,
            polish=False,
        )
        return None if found is None else found[0]

    def solve_point(
        self, x: np.ndarray, q0: np.ndarray, tol: float
    ) -> tuple[np.ndarray, np.ndarray, Sequence[int]] | None:
        """:meth:`solve`, with the solution's stacked ``[J_phi; J_x]`` and working mode, or None.

        On the compiled kernels (a frame task), the Jacobian and mode come from one more compiled
        call at the solution, with no Pinocchio data; else from the data (:meth:`jacobian`,
        :meth:`mode`).
        """
        kernel = _batch_kernel(self)
        if kernel is None:
            q = self.solve(x, q0, tol)
            if q is None:
                return None
            A = self.jacobian()
            return q, A, self.mode(A)
        q = self.solve(x, q0, tol, data=False)
        if q is None:
            return None
        X = x[None]
        _, ok, A, modes = kernel.newton_modes(self.legs, q[None], X, _target_rotations(self.task, X), tol, 0)
        return (q, A[0], modes[0]) if ok[0] else None

    def ik_jacobians(self, Q: np.ndarray, X: np.ndarray) -> np.ndarray:
        """Stacked ``[J_phi; J_x]`` (B, m + n_task, nv) at configurations ``Q`` (B, nq) of task poses ``X``.

        One compiled call on the kernels (a frame task), else Pinocchio's data per configuration.
        """
        kernel = _batch_kernel(self)
        if kernel is not None:  # no Newton step (none allowed) and any residual accepted
            return kernel.newton_modes(self.legs, Q, X, _target_rotations(self.task, X), np.inf, 0)[2]
        out = np.empty((Q.shape[0], self.m + self.task.size, self.nv))
        for b, q in enumerate(Q):
            pin.computeJointJacobians(self.model, self.data, q)
            pin.updateFramePlacements(self.model, self.data)
            self.jacobian(out[b])
        return out

    def jacobian(self, out: np.ndarray | None = None) -> np.ndarray:
        """Stacked ``[J_phi; J_x]`` (:func:`plm_pin.kinematics.jacobians.ik_jacobian`) left by :meth:`solve`.

        Shape (m + n_task, nv); written into ``out`` when given.
        """
        return ik_jacobian_from_data(self.model, self.data, self.closures, self.task, out)

    def mode(self, A: np.ndarray) -> tuple[int, ...]:
        """Working mode at the configuration of :meth:`solve`, ``A`` its :meth:`jacobian` (not recomputed)."""
        return working_mode_from_data(self.model, self.data, self.closures, self.task, self.legs, ik_rows=A)

    def extrapolate(self, previous: list[np.ndarray]) -> np.ndarray:
        """Next configuration on a line of equally spaced solutions ``previous`` (nearest first)."""
        if len(previous) == 1:
            return previous[0].copy()
        if self.linear_q:
            if len(previous) == 2:
                return np.asarray(2.0 * previous[0] - previous[1])
            return np.asarray(3.0 * previous[0] - 3.0 * previous[1] + previous[2])
        base = previous[0]
        d1 = pin.difference(self.model, base, previous[1])
        if len(previous) == 2:
            return np.asarray(pin.integrate(self.model, base, -d1))
        d2 = pin.difference(self.model, base, previous[2])
        return np.asarray(pin.integrate(self.model, base, -3.0 * d1 + d2))


def compatible(mode: Sequence[int], target: Sequence[int]) -> bool:
    """Whether ``mode`` is the working mode ``target`` (a zero sign, a singular leg, matches either)."""
    return all(m == t or m == 0 or t == 0 for m, t in zip(mode, target, strict=True))


def compatible_rows(modes: np.ndarray, target: np.ndarray) -> np.ndarray:
    """:func:`compatible` for each row of ``modes`` (B, n_legs), as a boolean array (B,)."""
    return np.all((modes == target) | (modes == 0) | (target == 0), axis=1)


BATCH = 1024
"""Points whose Jacobians are buffered before their metrics are computed together."""

Metrics = Callable[[np.ndarray], dict[str, np.ndarray]]
"""Batch metrics: stacked ``[J_phi; J_x]`` (b, m + k, nv) -> ``{name: (b,) array}``."""


@dataclass
class GridState:
    """Solutions and metrics over a flattened grid of shape ``shape`` (row-major).

    Attributes:
        shape: grid shape (any number of axes; a line walked by rows is a grid of one row).
        poses: task coordinates of every point [m, rad], shape (n_points, k).
        q: configurations (NaN where not reached), shape (n_points, nq).
        reached: solved in the working mode, shape (n_points,).
        mode: working mode of each reached point, shape (n_points, n_legs).
        metrics: name -> values (NaN where not reached), each of shape (n_points,).
        tried: per point, bit ``d`` set once it was attempted from its neighbour in direction ``d``.
    """

    shape: tuple[int, ...]
    poses: np.ndarray
    q: np.ndarray
    reached: np.ndarray
    mode: np.ndarray
    metrics: dict[str, np.ndarray]
    tried: np.ndarray
    _pending: list[int] = field(default_factory=list, repr=False)
    _A: np.ndarray | None = field(default=None, repr=False)

    @classmethod
    def empty(cls, ev: IKEvaluator, shape: tuple[int, ...], poses: np.ndarray) -> GridState:
        """A grid with nothing solved."""
        n = int(np.prod(shape))
        return cls(
            shape,
            poses,
            np.full((n, ev.model.nq), np.nan),
            np.zeros(n, dtype=bool),
            np.zeros((n, ev.n_legs), dtype=np.int8),
            {},
            np.zeros(n, dtype=np.uint8),
        )

    def accept(
        self,
        index: int,
        q: np.ndarray,
        A: np.ndarray,
        mode: Sequence[int],
        target_mode: tuple[int, ...] | None,
    ) -> bool:
        """Record the solution at ``index``, its ``[J_phi; J_x]`` and working mode, if the mode fits.

        ``A`` is buffered for the metrics (:meth:`flush`); ``target_mode`` None accepts any mode.
        """
        if target_mode is not None and not compatible(mode, target_mode):
            return False
        if self._A is None:
            self._A = np.empty((BATCH, *A.shape))
        self._A[len(self._pending)] = A
        self.q[index] = q
        self.mode[index] = mode
        self.reached[index] = True
        self._pending.append(index)
        return True

    def accept_batch(
        self,
        index: np.ndarray,
        q: np.ndarray,
        mode: np.ndarray,
        A: np.ndarray,
        metrics: Metrics,
    ) -> None:
        """Record solutions at flat ``index`` with their modes and stacked Jacobians (metrics at once)."""
        if index.size == 0:
            return
        self.q[index] = q
        self.mode[index] = mode
        self.reached[index] = True
        self.record_metrics(index, A, metrics)

    def record_metrics(self, index: np.ndarray, A: np.ndarray, metrics: Metrics) -> None:
        """Record the metrics of the points at flat ``index`` from their stacked Jacobians ``A``."""
        n = self.reached.size
        for name, v in metrics(A).items():
            if name not in self.metrics:
                self.metrics[name] = np.full(n, np.nan)
            self.metrics[name][index] = v

    def flush(self, metrics: Metrics) -> None:
        """Compute the metrics of the buffered points."""
        if not self._pending:
            return
        assert self._A is not None
        values = metrics(self._A[: len(self._pending)])
        n = self.reached.size
        for name, v in values.items():
            if name not in self.metrics:
                self.metrics[name] = np.full(n, np.nan)
            self.metrics[name][self._pending] = v
        self._pending.clear()

    def full(self) -> bool:
        """Whether the buffer must be flushed."""
        return len(self._pending) >= BATCH

    def part(self, band: slice) -> dict[str, Any]:
        """The results over the flat index range ``band`` (to send back from a worker)."""
        return {
            "q": self.q[band],
            "reached": self.reached[band],
            "mode": self.mode[band],
            "tried": self.tried[band],
            "metrics": {name: v[band] for name, v in self.metrics.items()},
        }

    def merge(self, part: dict[str, Any], band: slice) -> None:
        """Copy the results :meth:`part` returned for ``band``."""
        self.q[band] = part["q"]
        self.reached[band] = part["reached"]
        self.mode[band] = part["mode"]
        self.tried[band] |= part["tried"]
        for name, v in part["metrics"].items():
            if name not in self.metrics:
                self.metrics[name] = np.full(self.reached.size, np.nan)
            self.metrics[name][band] = v


def _neighbours(shape: tuple[int, ...]) -> list[int]:
    """Flat index offsets of the 2 * ndim axis neighbours of a row-major grid."""
    strides = [int(np.prod(shape[a + 1 :])) for a in range(len(shape))]
    return [s * sign for s in strides for sign in (1, -1)]


def flood(
    ev: IKEvaluator,
    state: GridState,
    metrics: Metrics,
    target_mode: tuple[int, ...],
    start: Iterable[int],
    tol: float,
    active: np.ndarray | None = None,
) -> None:
    """Solve every point connected to ``start`` through solvable neighbours, breadth first.

    Args:
        ev: the evaluator.
        state: the grid; the points of ``start`` must be reached already.
        metrics: batch metrics of the solved points.
        target_mode: the working mode to keep, one sign per leg.
        start: flat indices to expand from.
        tol: residual tolerance [m, rad].
        active: points that may be solved (default: all).
    """
    shape = state.shape
    coords = np.unravel_index(np.arange(int(np.prod(shape))), shape)
    offsets = _neighbours(shape)
    queue = deque(start)
    reached, tried, q_all = state.reached, state.tried, state.q
    while queue:
        p = queue.popleft()
        for d, off in enumerate(offsets):
            axis = d // 2
            step = 1 if off > 0 else -1
            c = coords[axis][p] + step
            if c < 0 or c >= shape[axis]:
                continue
            n = p + off
            if reached[n] or tried[n] & (1 << d) or (active is not None and not active[n]):
                continue
            tried[n] |= 1 << d
            previous = [q_all[p]]
            for back in (1, 2):
                b = coords[axis][p] - step * back
                if b < 0 or b >= shape[axis] or not reached[p - off * back]:
                    break
                previous.append(q_all[p - off * back])
            found = ev.solve_point(state.poses[n], ev.extrapolate(previous), tol)
            if found is None or not state.accept(n, *found, target_mode):
                continue
            queue.append(n)
            if state.full():
                state.flush(metrics)
    state.flush(metrics)


# ------------------------------------------------------------------ orchestration
PARALLEL_MIN_POINTS = 20_000
"""Grids with fewer poses are solved in the calling process when ``workers`` is None."""

SEED_CANDIDATES = 16
"""Grid points nearest to the guess's pose tried, in turn, as the seed of the continuation."""

RESEED_CANDIDATES = 4
"""Points of each unreached stretch (evenly spread over it) tried as new seeds by :func:`reseed`."""

RESEED_ATTEMPTS = 64
"""Largest number of new seeds :func:`reseed` tries over one grid (bounds its cost on large voids)."""


def _auto_workers(n_points: int, shape: tuple[int, ...], workers: int | None) -> int:
    if workers is None:
        workers = (os.cpu_count() or 1) if n_points >= PARALLEL_MIN_POINTS else 1
    workers = count(workers, "workers", minimum=1)
    if len(shape) < 2:
        return 1
    return max(1, min(workers, shape[0] // 4))


_WORKER: dict[str, Any] = {}


def _init_worker(
    ev: IKEvaluator,
    poses: np.ndarray,
    shape: tuple[int, ...],
    target: tuple[int, ...],
    tol: float,
    names: tuple[str, ...],
) -> None:
    _WORKER.update(ev=ev, poses=poses, shape=shape, target=target, tol=tol, names=names)


def _metrics_for(ev: IKEvaluator, names: tuple[str, ...], kin: BatchKinematics | None = None) -> Metrics:
    """The batch metrics ``names`` (among :data:`POSE_METRICS`) of ``ev``'s mechanism, the cheapest way."""
    arrow = None if kin is None else kin.arrow  # the IK Jacobian's structure, as ``ev``'s has it

    def metrics(A: np.ndarray) -> dict[str, np.ndarray]:
        if not names:
            return {}
        if ev.task.size == ev.mobility and ev.m:
            if ev.kernel is not None:
                return compiled_square_task_metrics(ev.kernel, A, ev.m, ev.actuated_v, ev.mobility, names)
            return square_task_metrics(A, ev.m, ev.actuated_v, ev.mobility, arrow, names)
        return batch_metrics(A[:, : ev.m], A[:, ev.m :], ev.actuated_v, ev.mobility, names=names)

    return metrics


def _band(rows: tuple[int, int], spine: list[tuple[int, np.ndarray]]) -> tuple[slice, dict[str, Any]]:
    """Flood one band of rows from its spine points (in a worker); return the band's results."""
    ev: IKEvaluator = _WORKER["ev"]
    shape: tuple[int, ...] = _WORKER["shape"]
    state = GridState.empty(ev, shape, _WORKER["poses"])
    metrics = _metrics_for(ev, _WORKER["names"])
    start = []
    for index, q in spine:
        found = ev.solve_point(state.poses[index], np.asarray(q), _WORKER["tol"])
        if found is not None and state.accept(index, *found, None):
            start.append(index)
    state.flush(metrics)
    active = np.zeros(state.reached.size, dtype=bool)
    band = slice(rows[0] * shape[1], rows[1] * shape[1])
    active[band] = True
    flood(ev, state, metrics, _WORKER["target"], start, _WORKER["tol"], active)
    return band, state.part(band)


def _solve_grid(
    ev: IKEvaluator,
    state: GridState,
    seed: int,
    target: tuple[int, ...],
    tol: float,
    workers: int,
    names: tuple[str, ...],
) -> None:
    metrics = _metrics_for(ev, names)
    if workers <= 1:
        flood(ev, state, metrics, target, [seed], tol)
        return
    n0, n1 = state.shape
    j0 = seed % n1
    spine_mask = np.zeros(state.reached.size, dtype=bool)
    spine_mask[j0::n1] = True
    flood(ev, state, metrics, target, [seed], tol, spine_mask)
    bands = [(int(b[0]), int(b[-1]) + 1) for b in np.array_split(np.arange(n0), workers)]
    context = multiprocessing.get_context(
        "fork" if "fork" in multiprocessing.get_all_start_methods() else None
    )
    with ProcessPoolExecutor(
        workers,
        mp_context=context,
        initializer=_init_worker,
        initargs=(ev, state.poses, state.shape, target, tol, names),
    ) as pool:
        jobs = []
        for a, b in bands:
            spine = [(i * n1 + j0, state.q[i * n1 + j0]) for i in range(a, b) if state.reached[i * n1 + j0]]
            jobs.append(pool.submit(_band, (a, b), spine))
        for job in jobs:
            band, part = job.result()
            state.merge(part, band)
    # join the bands: expand from the rows on either side of each border
    border: list[int] = []
    for a, b in bands:
        for row in (a, b - 1):
            idx = np.arange(row * n1, (row + 1) * n1)
            border.extend(int(k) for k in idx[state.reached[idx]])
    state.tried[:] = 0
    flood(ev, state, metrics, target, border, tol)


def sweep_rows(
    ev: IKEvaluator,
    kin: BatchKinematics | None,
    state: GridState,
    metrics: Metrics,
    seed: int,
    target_mode: tuple[int, ...],
    tol: float,
) -> None:
    """Solve a 2-D grid row by row with the batched evaluator, then fill what it missed point by point.

    The batched evaluator is the compiled kernel where it serves ``ev`` (``kin`` may then be
    None), else the numpy ``kin``. The seed's row is walked by :func:`_walk_seed_row` on the
    kernels (else by :func:`flood` kept to the row); the rows on either side of it are then solved
    by :func:`_walk_rows`, both sides in the same batches, in this process (two processes,
    one per side, were slower on two cores: the fork and the merge cost more than the second
    side saves). Whatever stays
    unreached next to a reached point is then tried by :func:`flood` from its neighbours.
    """
    n0, n1 = state.shape
    i0 = seed // n1
    if _batch_kernel(ev) is not None:
        _walk_seed_row(ev, state, metrics, seed, target_mode, tol)
    else:
        row = np.zeros(state.reached.size, dtype=bool)
        row[i0 * n1 : (i0 + 1) * n1] = True
        flood(ev, state, metrics, target_mode, [seed], tol, row)
    _walk_rows(ev, kin, state, metrics, i0, target_mode, tol)
    grid = state.reached.reshape(n0, n1)
    edge = np.zeros_like(grid)
    edge[1:] |= ~grid[:-1]
    edge[:-1] |= ~grid[1:]
    edge[:, 1:] |= ~grid[:, :-1]
    edge[:, :-1] |= ~grid[:, 1:]
    border = np.flatnonzero((grid & edge).reshape(-1))
    flood(ev, state, metrics, target_mode, border.tolist(), tol)


def _walk_seed_row(
    ev: IKEvaluator,
    state: GridState,
    metrics: Metrics,
    seed: int,
    target_mode: tuple[int, ...],
    tol: float,
) -> None:
    """The seed's row, outward from the seed on each side: :func:`flood` kept to the row, compiled.

    Each side is one compiled walk (:meth:`~plm_pin.kernels.Kernel.walk_line`): each point
    solved by Newton from its side's line extrapolated (as :func:`flood` does), the side ending
    at its first point that does not converge or falls out of ``target_mode``, where
    :func:`flood` would have stopped; the side's metrics then come in one batch.
    """
    kernel = _batch_kernel(ev)
    assert kernel is not None  # (sweep_rows walks the seed's row so only on the kernels)
    n1 = state.shape[1]
    i0, j0 = divmod(seed, n1)
    row = slice(i0 * n1, (i0 + 1) * n1)  # views: the walk writes into the grid
    poses = state.poses[row]
    R_stars = _target_rotations(ev.task, poses)
    for d, step in ((2, 1), (3, -1)):  # the directions +1 and -1 along the row (see _neighbours)
        index, A = kernel.walk_line(
            ev.legs,
            target_mode,
            poses,
            R_stars,
            state.q[row],
            state.reached[row],
            state.mode[row],
            j0,
            step,
            tol,
        )
        if index.size:
            state.record_metrics(i0 * n1 + index, A, metrics)
        j = j0 + step * (index.size + 1)  # the point where the side stopped
        if 0 <= j < n1:
            state.tried[i0 * n1 + j] |= 1 << d


LAG = 2
"""Batches of :func:`_walk_rows` the second side waits, so that its first rows extrapolate from
the two rows past the seed's row on the first side (as when the sides were walked in turn)."""


def _walk_rows(
    ev: IKEvaluator,
    kin: BatchKinematics | None,
    state: GridState,
    metrics: Metrics,
    i0: int,
    target_mode: tuple[int, ...],
    tol: float,
) -> None:
    """Solve the rows on both sides of row ``i0``, the next row of each side in one batched Newton.

    Each row is predicted per column by polynomial extrapolation from the rows before it on
    its side (as :meth:`IKEvaluator.extrapolate` does along a line) and solved, together
    with the other side's next row, by :func:`~plm_pin.workspace._batch.batch_newton`; a
    point is kept only when it converges to ``tol`` in ``target_mode``. The second side
    starts :data:`LAG` batches late, so that every row gets the prediction it had when the
    sides were walked in turn. A side's walk stops at the grid edge or at a row with no
    solved point before it. On the kernels, each pair of rows is walked by one compiled call
    (:meth:`~plm_pin.kernels.Kernel.walk_rows`: prediction, Newton and working modes), the
    metrics of its points computed on return.
    """
    n0, n1 = state.shape
    kernel = _batch_kernel(ev)
    if kernel is not None:
        for index, A in kernel.walk_rows(
            ev.legs,
            target_mode,
            state.poses,
            _target_rotations(ev.task, state.poses),
            state.q,
            state.reached,
            state.mode,
            n1,
            i0,
            LAG,
            tol,
        ):
            state.record_metrics(index, A, metrics)
        return
    assert kin is not None  # (solve_poses walks on the kernels or on ``kin``)
    Q = state.q.reshape(n0, n1, -1)
    reached = state.reached.reshape(n0, n1)
    poses = state.poses.reshape(n0, n1, -1)
    wanted = np.array(target_mode)
    fronts = {1: i0 + 1, -1: i0 - 1}  # direction -> next row
    for step in itertools.count():
        if not fronts:
            break
        rows, cols, guesses = [], [], []
        for direction, i in list(fronts.items()):
            if direction == -1 and step < LAG:
                continue
            back = [i - direction * k for k in (1, 2, 3) if 0 <= i - direction * k < n0]
            if not 0 <= i < n0 or not reached[back[0]].any():
                del fronts[direction]
                continue
            c = np.flatnonzero(reached[back[0]])  # the columns solved on the row before
            pred = Q0 = Q[back[0], c]
            if len(back) >= 2:
                two = reached[back[1], c][:, None]
                Q1 = Q[back[1], c]
                pred = np.where(two, 2.0 * Q0 - Q1, Q0)
                if len(back) == 3:
                    three = two & reached[back[2], c][:, None]
                    pred = np.where(three, 3.0 * Q0 - 3.0 * Q1 + Q[back[2], c], pred)
            rows.append(np.full(c.size, i))
            cols.append(c)
            guesses.append(pred)
            fronts[direction] = i + direction
        if not rows:
            break
        row, col = np.concatenate(rows), np.concatenate(cols)
        q, ok, A, R = batch_newton(
            kin, np.concatenate(guesses), poses[row, col], tol, NEWTON_MAX_ITERATIONS, STALL_RATIO
        )
        if not ok.all():  # (copies of R, the largest array, only where some point failed)
            A, R, q, row, col = A[ok], R[ok], q[ok], row[ok], col[ok]
        modes = batch_modes(A, ev.legs, kin.turns(R, ev.legs))
        fits = compatible_rows(modes, wanted)
        if not fits.all():
            A, q, modes, row, col = A[fits], q[fits], modes[fits], row[fits], col[fits]
        state.accept_batch(row * n1 + col, q, modes, A, metrics)


def _batch_kernel(ev: IKEvaluator) -> Kernel | None:
    """The compiled kernel that solves ``ev``'s batches and reads their working modes, or None.

    It takes frame tasks whose working modes the IK Jacobian holds (:attr:`IKEvaluator.modes_in_ik`).
    """
    return ev.kernel if isinstance(ev.task, FrameTask) and ev.modes_in_ik else None


def _target_rotations(task: Task, X: np.ndarray) -> np.ndarray:
    """Rotations (B, 3, 3) of targets ``X`` (B, k) of a frame task with all three angles, else I (1, 3, 3)."""
    if not isinstance(task, FrameTask) or len(task.angular) != 3:
        return np.eye(3)[None]
    rpy = np.empty((X.shape[0], 3))
    rpy[:, list(task.angular)] = X[:, len(task.linear) :]
    return rpy_matrix(rpy)


def _seed(
    mech: Mechanism,
    ev: IKEvaluator,
    poses: np.ndarray,
    x_guess: np.ndarray,
    scale: np.ndarray,
    guess: np.ndarray,
    mode: tuple[int, ...] | None,
    tol: float,
) -> tuple[int, np.ndarray] | None:
    """The grid point nearest to the guess's pose that the inverse kinematics reaches.

    The :data:`SEED_CANDIDATES` nearest points are tried by undamped Newton from the guess
    first (:func:`_reseed_solution`: a point out of reach costs under a millisecond), then,
    if none converges, by the general solver (Levenberg-Marquardt after Newton).
    """
    flat = poses.reshape(-1, poses.shape[-1])
    varied = scale > 0.0  # distance over the varied coordinates only, in units of their span
    order = np.argsort(np.sum(((flat - x_guess)[:, varied] / scale[varied]) ** 2, axis=1), kind="stable")
    for index in order[:SEED_CANDIDATES]:
        found = _reseed_solution(mech, ev, flat[index], guess, mode, tol)
        if found is not None:
            return int(index), found
    for index in order[:SEED_CANDIDATES]:
        try:
            q = _seed_solution(mech, flat[index], guess, mode)
        except PoseUnreachable:
            continue
        return int(index), q
    return None


def _seed_solution(
    mech: Mechanism, x: np.ndarray, guess: np.ndarray, mode: tuple[int, ...] | None
) -> np.ndarray:
    """Inverse kinematics at a seed candidate: Newton from the guess, re-solved in ``mode`` if elsewhere.

    A candidate that Newton from the guess cannot reach is skipped (with or without a mode);
    the working modes are enumerated (tens of Newton solves) only when it converges in
    another mode than ``mode``.

    Raises:
        PoseUnreachable: when Newton from the guess does not reach ``x``, or ``x`` has no
            solution in ``mode``.
    """
    sol = inverse_kinematics(mech, x, guess, explain=False)
    if mode is None or sol.mode == tuple(mode):
        return sol.q
    return inverse_kinematics(mech, x, guess, mode=mode).q


RESEED_NEWTON_ITERATIONS = 30
"""Newton iterations a new seed may take from the guess (it starts far: a stretch away)."""


def _reseed_solution(
    mech: Mechanism,
    ev: IKEvaluator,
    x: np.ndarray,
    guess: np.ndarray,
    mode: tuple[int, ...] | None,
    tol: float,
) -> np.ndarray | None:
    """A new seed at ``x``: Newton from ``guess``, re-solved in ``mode`` if it lands in another; or None.

    Undamped Newton only (no Levenberg-Marquardt): a candidate it cannot reach costs well under
    a millisecond, so that stretches with no reachable point stay cheap. The working modes are
    enumerated only when Newton converges in another mode than ``mode``. On the kernels where they
    serve ``ev`` (the same Newton, compiled).
    """
    kernel = _batch_kernel(ev)
    if kernel is not None:
        solved = kernel.newton(
            guess, None, tol, TaskTarget(ev.task, x), max_iterations=RESEED_NEWTON_ITERATIONS
        )
        if solved is None:
            return None
        if mode is None:
            return solved[0]
        X = x[None]
        _, ok, _, modes = kernel.newton_modes(
            ev.legs, solved[0][None], X, _target_rotations(ev.task, X), tol, 0
        )
        if ok[0] and tuple(modes[0]) == tuple(mode):
            return solved[0]
        return _in_mode(mech, x, guess, mode)
    found = newton(
        ev.model,
        ev.data,
        ev.closures,
        guess,
        None,
        ev._r,
        ev._A,
        tol=tol,
        extra=TaskTarget(ev.task, x),
        max_iterations=RESEED_NEWTON_ITERATIONS,
    )
    if found is None:
        return None
    if mode is None or ev.mode(ev.jacobian()) == tuple(mode):
        return found[0]
    return _in_mode(mech, x, guess, mode)


def _in_mode(mech: Mechanism, x: np.ndarray, guess: np.ndarray, mode: tuple[int, ...]) -> np.ndarray | None:
    """Inverse kinematics at ``x`` in working mode ``mode`` from ``guess`` (its modes enumerated), or None."""
    try:
        return inverse_kinematics(mech, x, guess, mode=mode).q
    except PoseUnreachable:
        return None


def base_pose(mech: Mechanism, pose: ArrayLike | None, guess: ArrayLike | None) -> np.ndarray:
    """The task pose giving a slice's fixed coordinates [m, rad]: ``pose`` (checked), else the guess's."""
    task = require_task(mech)
    if pose is None:
        return task_pose(mech, start_configuration(mech, guess))
    base = np.asarray(real_numbers(pose, "pose"), dtype=float)
    if base.shape != (task.size,) or not np.all(np.isfinite(base)):
        raise InvalidInput(
            f"pose must hold {task.size} finite task coordinates {list(task.dofs)}, got {pose!r}"
        )
    return base


def solve_poses(
    mech: Mechanism,
    poses: np.ndarray,
    guess: ArrayLike | None,
    *,
    mode: tuple[int, ...] | None,
    tol: float,
    workers: int | None,
    names: tuple[str, ...] = POSE_METRICS,
) -> tuple[GridState, tuple[int, ...] | None]:
    """Solve a grid of task poses by continuation from the point nearest to the guess's pose.

    Args:
        mech: the mechanism.
        poses: task poses [m, rad], shape ``shape + (n_task,)`` (one or two grid axes).
        guess: configuration the seed is solved from, shape (nq,) (None: the reference).
        mode: working mode to keep (default: the seed's, from ``guess``).
        tol: residual tolerance [m, rad].
        workers: processes (None: all CPUs for large 2-D grids).
        names: the metrics to compute, among :data:`POSE_METRICS` (the others are absent from
            the state's ``metrics``).

    Returns:
        The solved grid, and the working mode kept (None when no point could be seeded).
    """
    tol = positive(tol, "tol", "m, rad")
    mode = check_mode(mech, mode)
    shape = poses.shape[:-1]
    k = poses.shape[-1]
    ev = IKEvaluator.from_mechanism(mech)
    flat = np.ascontiguousarray(poses.reshape(-1, k))
    in_ik = ev.modes_in_ik  # the batched modes read leg blocks of the IK Jacobian only
    compiled = _batch_kernel(ev) is not None
    # the numpy batch engine where the kernels do not serve
    numpy_rows = len(shape) == 2 and in_ik and not compiled
    kin = BatchKinematics.from_parts(ev.model, ev.closures, ev.task) if numpy_rows else None
    # walked by rows: two-axis grids, and on the kernels lines too (as grids of one row)
    rows = kin is not None or (compiled and len(shape) <= 2)
    state = GridState.empty(ev, (1, *shape) if rows and len(shape) == 1 else shape, flat)
    scale = np.ptp(flat, axis=0)
    guess = start_configuration(mech, guess)
    x_guess = task_pose(mech, guess)
    seeded = _seed(mech, ev, flat, x_guess, scale, guess, mode, tol)
    if seeded is None:
        return state, None
    index, q = seeded
    found = ev.solve_point(flat[index], q, tol)
    if found is None or not state.accept(index, *found, None):
        return state, None
    target = tuple(int(s) for s in state.mode[index])
    n_workers = _auto_workers(flat.shape[0], shape, workers)  # checks ``workers`` on either path
    if rows:
        sweep_rows(ev, kin, state, _metrics_for(ev, names, kin), index, target, tol)
    else:
        _solve_grid(ev, state, index, target, tol, n_workers, names)
    reseed(mech, ev, state, _metrics_for(ev, names, kin), target, guess, tol)
    return state, target


def reseed(
    mech: Mechanism,
    ev: IKEvaluator,
    state: GridState,
    metrics: Metrics,
    target_mode: tuple[int, ...],
    guess: np.ndarray,
    tol: float,
) -> None:
    """Seed the continuation again inside the stretches it left unreached, in ``target_mode``.

    The unreached points split into connected stretches (grid-axis neighbours, as
    :func:`flood` walks). In each, up to :data:`RESEED_CANDIDATES` points spread evenly over
    the stretch are solved from ``guess`` in the working mode (:func:`_reseed_solution`); the
    first one reached is flooded from, and the stretches are recomputed. At most
    :data:`RESEED_ATTEMPTS` solves in all. Deterministic: stretches and candidates are taken
    in flat-index order.

    Args:
        mech: the mechanism.
        ev: its evaluator.
        state: the grid after :func:`flood`.
        metrics: batch metrics of the solved points.
        target_mode: the working mode kept (zeros match either sign).
        guess: configuration the new seeds are solved from, shape (nq,).
        tol: residual tolerance [m, rad].
    """
    mode = None if 0 in target_mode else target_mode
    attempted = np.zeros(state.reached.size, dtype=bool)
    budget = RESEED_ATTEMPTS
    while budget > 0 and not state.reached.all():
        labels, count = ndimage.label(~state.reached.reshape(state.shape))
        labels = labels.reshape(-1)
        grown = False
        for stretch in range(1, count + 1):
            members = np.flatnonzero((labels == stretch) & ~attempted)
            if members.size == 0:
                continue
            picks = np.unique(np.linspace(0, members.size - 1, min(RESEED_CANDIDATES, members.size)).round())
            for index in members[picks.astype(int)].tolist():
                if budget == 0:
                    break
                budget -= 1
                attempted[index] = True
                q = _reseed_solution(mech, ev, state.poses[index], guess, mode, tol)
                if q is None:
                    continue
                found = ev.solve_point(state.poses[index], q, tol)
                if found is None or not state.accept(index, *found, target_mode):
                    continue
                flood(ev, state, metrics, target_mode, [index], tol)
                grown = True
                break
            if grown:
                break
        if not grown:
            break
    state.flush(metrics)
