r"""Inverse-kinematics continuation over grids of task poses (private helpers of the analysis).

:class:`IKEvaluator` solves the inverse kinematics at one pose by Newton's method on the
closure and task rows, from a predicted configuration, with the exact Jacobians of
:mod:`plm_pin.kinematics.closures` and :class:`plm_pin.kinematics.task.TaskTarget`, and
leaves the exact Jacobians at the solution for the metrics. It skips what the general
solver :func:`plm_pin.kinematics.assemble` does for robustness from far away (SVD of every
step, step rejection with damping): continuation starts within a grid step of the
solution, where the Gauss-Newton step through the normal equations converges
quadratically. Every accepted point still satisfies the closures and the task to ``tol``.

:func:`flood` walks a grid from solved points to their neighbours (breadth first),
predicting each configuration by polynomial extrapolation along the line it is reached
on, so that one Newton step usually suffices, and keeping the working mode: a point whose
solution changes the sign of a leg block (:func:`plm_pin.kinematics.working_mode`) is not
taken from that neighbour. Points never reached are left unreachable.
"""

from __future__ import annotations

import math
import multiprocessing
import os
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dposv as _posv

from ..exceptions import InvalidInput, PoseUnreachable
from ..kinematics import closures as _closures
from ..kinematics.inverse import inverse_kinematics
from ..kinematics.jacobians import require_task
from ..kinematics.legs import ik_jacobian
from ..kinematics.task import Task
from .manipulability import batch_metrics

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

if TYPE_CHECKING:
    from ..mechanism import Mechanism

MODE_RTOL = 1e-9
"""Zero threshold of a leg block determinant, relative to Hadamard's bound (as in ``working_mode``)."""

NEWTON_MAX_ITERATIONS = 12
"""Newton iterations allowed per continuation step."""

STALL_RATIO = 0.9
"""A Newton iteration that does not divide the residual by at least 1 / STALL_RATIO ends the attempt."""


def _block_index(rows: tuple[int, ...], cols: tuple[int, ...], n_cols: int) -> np.ndarray:
    """Flat indices of the block ``rows x cols`` in a row-major matrix with ``n_cols`` columns."""
    r = np.asarray(rows)[:, None]
    c = np.asarray(cols)[None, :]
    return np.asarray(r * n_cols + c)


def _small_det_sign(M: list[list[float]]) -> int:
    """Sign of the determinant of a 1 x 1 to 3 x 3 matrix, 0 at or below ``MODE_RTOL`` x Hadamard's bound."""
    n = len(M)
    if n == 1:
        det = M[0][0]
        bound = abs(det)
    elif n == 2:
        (a, b), (c, d) = M
        det = a * d - b * c
        bound = math.sqrt((a * a + c * c) * (b * b + d * d))
    else:
        (a, b, c), (d, e, f), (g, h, i) = M
        det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
        bound = math.sqrt((a * a + d * d + g * g) * (b * b + e * e + h * h) * (c * c + f * f + i * i))
    if abs(det) <= MODE_RTOL * bound:
        return 0
    return 1 if det > 0 else -1


@dataclass
class IKEvaluator:
    """Newton corrector and exact Jacobians of one mechanism, picklable for worker processes.

    Build with :meth:`from_mechanism`. The Pinocchio data is created on first use in each
    process. Point closures and the task rows are evaluated inline (the formulas of
    :mod:`plm_pin.kinematics.closures` and :class:`plm_pin.kinematics.task.TaskTarget`,
    checked equal by the tests); other closure types go through
    :mod:`plm_pin.kinematics.closures`.
    """

    model: pin.Model
    closures: tuple[_closures.Closure, ...]
    task: Task
    mobility: int
    actuated_v: np.ndarray
    n_legs: int
    mode_groups: list[tuple[np.ndarray, np.ndarray]]
    linear_q: bool
    _data: pin.Data | None = field(default=None, repr=False)

    @classmethod
    def from_mechanism(cls, mech: Mechanism) -> IKEvaluator:
        """Collect what the continuation needs from ``mech``."""
        task = require_task(mech)
        square = [leg for leg in mech.legs if leg.square]
        by_size: dict[int, list[tuple[int, np.ndarray]]] = {}
        for k, leg in enumerate(square):
            by_size.setdefault(len(leg.rows), []).append((k, _block_index(leg.rows, leg.columns, mech.nv)))
        groups = [
            (np.array([k for k, _ in items]), np.stack([idx for _, idx in items]))
            for _, items in sorted(by_size.items())
        ]
        model = mech.model
        linear = all(model.joints[j].nq == model.joints[j].nv for j in range(1, model.njoints))
        return cls(
            model=model,
            closures=tuple(mech.closures),
            task=task,
            mobility=mech.mobility,
            actuated_v=np.asarray(mech.actuated_v_indices),
            n_legs=len(square),
            mode_groups=groups,
            linear_q=linear,
        )

    def __post_init__(self) -> None:
        self.m = _closures.closure_rows(self.closures)
        self.k = self.task.size
        self._points = all(c.spec.type == "point" for c in self.closures)
        self._pairs = [(c.frame_ids[0], c.frame_ids[1], c.rows.start) for c in self.closures]
        self._lin = list(self.task.linear)
        self._ang = list(self.task.angular)
        nl = len(self._lin)
        self._lin_index: list[int] | slice = slice(0, nl) if self._lin == list(range(nl)) else self._lin
        self._full_rotation = len(self._ang) == 3
        self._nl = len(self._lin)
        self._small_blocks = [
            (leg, idx)
            for legs, index in self.mode_groups
            if index.shape[-1] <= 3
            for leg, idx in zip(legs.tolist(), index.tolist(), strict=True)
        ]
        self._large_groups = [(legs, index) for legs, index in self.mode_groups if index.shape[-1] > 3]
        self._r = np.empty(self.m + self.k)
        self._A = np.empty((self.m + self.k, int(self.model.nv)))

    def __getstate__(self) -> dict[str, Any]:
        keep = ("model", "closures", "task", "mobility", "actuated_v", "n_legs", "mode_groups", "linear_q")
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

    # ------------------------------------------------------------ rows
    def _residual(self, data: pin.Data, x: np.ndarray, R_star: np.ndarray | None) -> float:
        """Fill the residual ``[phi; task - x]`` from placements in ``data``; return its max-norm."""
        r = self._r
        oMf = data.oMf
        if self._points:
            for fa, fb, start in self._pairs:
                r[start : start + 3] = oMf[fb].translation - oMf[fa].translation
        elif self.m:
            r[: self.m] = _closures.residual_from_placements(data, self.closures)
        M = oMf[self.task.frame_id]
        m, nl = self.m, self._nl
        if nl:
            r[m : m + nl] = M.translation[self._lin_index] - x[:nl]
        if self._ang:
            if R_star is not None:
                r[m + nl :] = pin.log3(M.rotation @ R_star.T)
            elif len(self._ang) == 1:  # wrap_angle of one angle, in Python floats
                d = float(pin.rpy.matrixToRpy(M.rotation)[self._ang[0]]) - float(x[nl])
                r[m + nl] = math.pi - (math.pi - d) % (2.0 * math.pi)
            else:
                d = pin.rpy.matrixToRpy(M.rotation)[self._ang] - x[nl:]
                r[m + nl :] = np.pi - np.mod(np.pi - d, 2.0 * np.pi)
        return float(np.abs(r).max())

    def _jacobian(self, data: pin.Data, R_star: np.ndarray | None) -> np.ndarray:
        """Fill the Jacobian of :meth:`_residual` from joint Jacobians in ``data``."""
        model = self.model
        A = self._A
        if self._points:
            for fa, fb, start in self._pairs:
                A[start : start + 3] = (
                    pin.getFrameJacobian(model, data, fb, _LWA)[:3]
                    - pin.getFrameJacobian(model, data, fa, _LWA)[:3]
                )
        elif self.m:
            A[: self.m] = _closures.jacobian_from_data(model, data, self.closures)
        J = pin.getFrameJacobian(model, data, self.task.frame_id, _LWA)
        m, nl = self.m, self._nl
        if nl:
            A[m : m + nl] = J[self._lin_index]
        if self._ang:
            R = data.oMf[self.task.frame_id].rotation
            if R_star is not None:
                E = R @ R_star.T
                A[m + nl :] = pin.Jlog3(E) @ E.T @ J[3:]
            else:
                rpy = pin.rpy.matrixToRpy(R)
                A[m + nl :] = (pin.rpy.computeRpyJacobianInverse(rpy, pin.ReferenceFrame.WORLD) @ J[3:])[
                    self._ang
                ]
        return A

    def residual_and_jacobian(self, q: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residual ``[phi; task - x]`` and its exact Jacobian at ``q`` (copies; for the tests)."""
        R_star = self._rotation(x)
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        self._residual(self.data, x, R_star)
        return self._r.copy(), self._jacobian(self.data, R_star).copy()

    def _rotation(self, x: np.ndarray) -> np.ndarray | None:
        if not self._full_rotation:
            return None
        return np.asarray(pin.rpy.rpyToMatrix(np.asarray(x[self._nl :], dtype=float)))

    # ------------------------------------------------------------ solving
    def solve(self, x: np.ndarray, q0: np.ndarray, tol: float) -> np.ndarray | None:
        """Configuration at task coordinates ``x`` by Newton from ``q0``, or None.

        Gauss-Newton steps through the normal equations (Cholesky); the attempt ends when
        an iteration does not reduce the residual by the factor :data:`STALL_RATIO`, or
        after :data:`NEWTON_MAX_ITERATIONS`. On success the data holds the joint Jacobians
        and frame placements at the returned configuration (read them with :meth:`jacobians`).
        """
        model, data = self.model, self.data
        R_star = self._rotation(x)
        q = q0
        err_prev = np.inf
        for iteration in range(NEWTON_MAX_ITERATIONS + 1):
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            err = self._residual(data, x, R_star)
            if err <= tol:
                return q
            if iteration == NEWTON_MAX_ITERATIONS or not err < STALL_RATIO * err_prev:
                return None
            A = self._jacobian(data, R_star)
            _, step, info = _posv(A.T @ A, A.T @ self._r)
            if info != 0:
                return None
            q = pin.integrate(model, q, -step)
            err_prev = err
        return None  # pragma: no cover - the loop always returns

    def jacobians(self) -> tuple[np.ndarray, np.ndarray]:
        """Closure and task Jacobians from the data left by :meth:`solve`, shapes (m, nv) and (k, nv)."""
        model, data = self.model, self.data
        if self._points:
            J_phi = np.empty((self.m, self.nv))
            for fa, fb, start in self._pairs:
                J_phi[start : start + 3] = (
                    pin.getFrameJacobian(model, data, fb, _LWA)[:3]
                    - pin.getFrameJacobian(model, data, fa, _LWA)[:3]
                )
        else:
            J_phi = _closures.jacobian_from_data(model, data, self.closures)
        J_x = pin.getFrameJacobian(model, data, self.task.frame_id, _LWA)[list(self.task.rows)]
        return J_phi, J_x

    def mode(self, J_phi: np.ndarray, J_x: np.ndarray) -> tuple[int, ...]:
        """Working mode: the sign of each square leg block (0 when singular), one per leg.

        Same rule as :func:`plm_pin.kinematics.working_mode` (zero below ``MODE_RTOL``
        times Hadamard's bound), from Jacobians already computed; blocks up to 3 x 3 in
        Python floats (cheaper than NumPy calls at this size).
        """
        flat = np.concatenate([J_phi.ravel(), J_x.ravel()])
        v = flat.tolist()
        out = [0] * self.n_legs
        for leg, idx in self._small_blocks:
            out[leg] = _small_det_sign([[v[k] for k in row] for row in idx])
        for legs, index in self._large_groups:
            blocks = flat[index]  # (n_blocks, s, s)
            det = np.linalg.det(blocks)
            bound = np.sqrt(np.square(blocks).sum(axis=1)).prod(axis=1)
            signs = np.sign(det) * (np.abs(det) > MODE_RTOL * bound)
            for leg, sign in zip(legs.tolist(), signs.tolist(), strict=True):
                out[leg] = int(sign)
        return tuple(out)

    def mode_of(self, mech: Mechanism, q: np.ndarray) -> tuple[int, ...]:
        """Working mode at ``q`` (computes the Jacobians)."""
        A = ik_jacobian(mech, q)
        return self.mode(A[: self.m], A[self.m :])

    def task_pose(self, q: np.ndarray) -> np.ndarray:
        """Task coordinates at ``q`` [m, rad], shape (n_task,)."""
        pin.framesForwardKinematics(self.model, self.data, q)
        return np.asarray(self.task.pose_from_data(self.data))

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


BATCH = 1024
"""Points whose Jacobians are buffered before their metrics are computed together."""

Metrics = Callable[[np.ndarray, np.ndarray], dict[str, np.ndarray]]
"""Batch metrics: ``(J_phi (b, m, nv), J_x (b, k, nv)) -> {name: (b,) array}``."""


@dataclass
class GridState:
    """Solutions and metrics over a flattened grid of shape ``shape`` (row-major).

    Attributes:
        shape: grid shape (one or two axes).
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
    _J_phi: np.ndarray | None = field(default=None, repr=False)
    _J_x: np.ndarray | None = field(default=None, repr=False)

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

    def accept(self, ev: IKEvaluator, index: int, q: np.ndarray, target_mode: tuple[int, ...] | None) -> bool:
        """Record the solution at ``index`` (the data of ``ev`` is at ``q``) if its mode fits."""
        J_phi, J_x = ev.jacobians()
        mode = ev.mode(J_phi, J_x)
        if target_mode is not None and not compatible(mode, target_mode):
            return False
        self.q[index] = q
        self.mode[index] = mode
        self.reached[index] = True
        if self._J_phi is None:
            self._J_phi = np.empty((BATCH, *J_phi.shape))
            self._J_x = np.empty((BATCH, *J_x.shape))
        assert self._J_x is not None
        k = len(self._pending)
        self._J_phi[k] = J_phi
        self._J_x[k] = J_x
        self._pending.append(index)
        return True

    def flush(self, metrics: Metrics) -> None:
        """Compute the metrics of the buffered points."""
        if not self._pending:
            return
        assert self._J_phi is not None and self._J_x is not None
        b = len(self._pending)
        values = metrics(self._J_phi[:b], self._J_x[:b])
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
            q = ev.solve(state.poses[n], ev.extrapolate(previous), tol)
            if q is None or not state.accept(ev, n, q, target_mode):
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


def _auto_workers(n_points: int, shape: tuple[int, ...], workers: int | None) -> int:
    if workers is None:
        workers = (os.cpu_count() or 1) if n_points >= PARALLEL_MIN_POINTS else 1
    if workers < 1:
        raise InvalidInput(f"workers must be at least 1, got {workers}")
    if len(shape) < 2:
        return 1
    return max(1, min(workers, shape[0] // 4))


_WORKER: dict[str, Any] = {}


def _init_worker(
    ev: IKEvaluator, poses: np.ndarray, shape: tuple[int, ...], target: tuple[int, ...], tol: float
) -> None:
    _WORKER.update(ev=ev, poses=poses, shape=shape, target=target, tol=tol)


def _metrics_for(ev: IKEvaluator) -> Metrics:
    def metrics(J_phi: np.ndarray, J_x: np.ndarray) -> dict[str, np.ndarray]:
        return batch_metrics(J_phi, J_x, ev.actuated_v, ev.mobility)

    return metrics


def _band(rows: tuple[int, int], spine: list[tuple[int, np.ndarray]]) -> tuple[slice, dict[str, Any]]:
    """Flood one band of rows from its spine points (in a worker); return the band's results."""
    ev: IKEvaluator = _WORKER["ev"]
    shape: tuple[int, ...] = _WORKER["shape"]
    state = GridState.empty(ev, shape, _WORKER["poses"])
    metrics = _metrics_for(ev)
    start = []
    for index, q in spine:
        sol = ev.solve(state.poses[index], np.asarray(q), _WORKER["tol"])
        if sol is not None and state.accept(ev, index, sol, None):
            start.append(index)
    state.flush(metrics)
    active = np.zeros(state.reached.size, dtype=bool)
    band = slice(rows[0] * shape[1], rows[1] * shape[1])
    active[band] = True
    flood(ev, state, metrics, _WORKER["target"], start, _WORKER["tol"], active)
    return band, state.part(band)


def _solve_grid(
    ev: IKEvaluator, state: GridState, seed: int, target: tuple[int, ...], tol: float, workers: int
) -> None:
    metrics = _metrics_for(ev)
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
        initargs=(ev, state.poses, state.shape, target, tol),
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


def _seed(
    mech: Mechanism, poses: np.ndarray, x_guess: np.ndarray, scale: np.ndarray, guess: Any, mode: Any
) -> tuple[int, np.ndarray] | None:
    """The grid point nearest to the guess's pose that the inverse kinematics reaches."""
    flat = poses.reshape(-1, poses.shape[-1])
    varied = scale > 0.0  # distance over the varied coordinates only, in units of their span
    order = np.argsort(np.sum(((flat - x_guess)[:, varied] / scale[varied]) ** 2, axis=1), kind="stable")
    for index in order[:SEED_CANDIDATES]:
        try:
            sol = inverse_kinematics(mech, flat[index], guess, mode=mode)
        except PoseUnreachable:
            continue
        return int(index), sol.q
    return None


def solve_poses(
    mech: Mechanism,
    poses: np.ndarray,
    guess: np.ndarray,
    *,
    mode: tuple[int, ...] | None,
    tol: float,
    workers: int | None,
) -> tuple[GridState, tuple[int, ...] | None]:
    """Solve a grid of task poses by continuation from the point nearest to the guess's pose.

    Args:
        mech: the mechanism.
        poses: task poses [m, rad], shape ``shape + (n_task,)`` (one or two grid axes).
        guess: configuration the seed is solved from, shape (nq,).
        mode: working mode to keep (default: the seed's, from ``guess``).
        tol: residual tolerance [m, rad].
        workers: processes (None: all CPUs for large 2-D grids).

    Returns:
        The solved grid, and the working mode kept (None when no point could be seeded).
    """
    shape = poses.shape[:-1]
    k = poses.shape[-1]
    ev = IKEvaluator.from_mechanism(mech)
    flat = np.ascontiguousarray(poses.reshape(-1, k))
    state = GridState.empty(ev, shape, flat)
    scale = np.ptp(flat, axis=0)
    x_guess = ev.task_pose(guess)
    seeded = _seed(mech, flat, x_guess, scale, guess, mode)
    if seeded is None:
        return state, None
    index, q = seeded
    sol = ev.solve(flat[index], q, tol)
    if sol is None or not state.accept(ev, index, sol, None):
        return state, None
    target = tuple(int(s) for s in state.mode[index])
    _solve_grid(ev, state, index, target, tol, _auto_workers(flat.shape[0], shape, workers))
    return state, target
