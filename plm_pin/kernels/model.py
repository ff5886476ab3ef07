"""A mechanism's kernel: the constant arrays the compiled kernels read, built once from the Pinocchio model.

:func:`kernel_of` returns the :class:`Kernel` of a mechanism (built at first use and kept
with it), or None when the kernels cannot serve it: a joint type they do not handle (said
once per mechanism by a :class:`~plm_pin.warnings.KernelFallbackWarning`), numba missing
(said once), or the environment variable ``PLM_PIN_KERNELS=0``. The callers then take the
Pinocchio path, which gives the same results.
"""

from __future__ import annotations

import itertools
import os
import warnings
from collections.abc import Iterator, Sequence
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..core.assembly import CHORD_RATIO, NEWTON_MAX_ITERATIONS, STALL_RATIO
from ..core.closures import Closure
from ..core.legs import Leg
from ..core.task import FrameTask, Task, TaskTarget
from ..tolerances import (
    ASSEMBLY_RCOND,
    FACTOR_RCOND,
    GRAM_RTOL,
    INVERSE_RTOL,
    LEG_SINGULAR_RTOL,
    LOG3_SERIES_ANGLE,
    RANK_RTOL,
    ROUND_OFF,
)
from ..warnings import KernelFallbackWarning
from .arrays import Elimination, KernelArrays, build_arrays, kernel_frames, pack, unsupported_joints

if TYPE_CHECKING:
    from ..core.mechanism import Mechanism

SWITCH = "PLM_PIN_KERNELS"
"""Environment variable: ``0`` turns the kernels off (every caller takes the Pinocchio path)."""


class Kernel:
    """A mechanism's compiled kinematics: placements, closure and task rows, Newton.

    Attributes:
        arrays: the constant arrays (:class:`KernelArrays`).
        ints: the integer arrays packed into one (:func:`.arrays.pack`), as the compiled calls take them.
        floats: the float arrays packed into one.
        frame_ids: Pinocchio frame index of each kernel frame (closure frames, then the task frame).
        n_task: number of task rows (0 without a task).
    """

    def __init__(self, arrays: KernelArrays, frame_ids: tuple[int, ...], n_task: int) -> None:
        """Wrap ``arrays`` (see :func:`build_arrays`)."""
        self.arrays = arrays
        self.ints, self.floats = pack(arrays)
        self.frame_ids = frame_ids
        self.n_task = n_task
        self._all = np.arange(arrays.nv)
        # a frame task (kind 1) holding all three angles: its targets come with their rotation
        self._rotation_target = arrays.t_kind == 1 and int(np.count_nonzero(arrays.t_rows >= 3)) == 3
        self._legs: tuple[Sequence[Leg], tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None

    @classmethod
    def build(cls, model: pin.Model, closures: tuple[Closure, ...], task: Task | None) -> Kernel:
        """The kernel of ``model`` with ``closures`` and ``task`` (every joint must be supported)."""
        arrays = build_arrays(model, closures, task)
        return cls(arrays, tuple(kernel_frames(closures, task)), task.size if task is not None else 0)

    @staticmethod
    def _target_arrays(target: TaskTarget | None) -> tuple[np.ndarray, np.ndarray]:
        """The target coordinates and, with all three angles selected, the target rotation."""
        if target is None:
            return _NO_TARGET, _EYE
        return Kernel._pose_arrays(target.task, target.x)

    @staticmethod
    def _pose_arrays(task: Task, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Task coordinates ``x`` and, with all three angles of a frame task selected, their rotation."""
        if isinstance(task, FrameTask) and len(task.angular) == 3:
            angles = np.empty(3)
            angles[list(task.angular)] = x[len(task.linear) :]
            return x, pin.rpy.rpyToMatrix(angles)
        return x, _EYE

    @property
    def elimination(self) -> Elimination:
        """The symbolic LU of the closure and task rows' Jacobian (:func:`.arrays.elimination`)."""
        a = self.arrays
        return Elimination(a.lu_order, a.lu_row_ptr, a.lu_rows, a.lu_col_ptr, a.lu_cols)

    def placements(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """World rotations and translations of every joint (nj, 3, 3), (nj, 3) and kernel frame (nf, ...)."""
        nj, nf = self.arrays.parents.size, max(self.arrays.f_joint.size, 1)
        oR, op, fR, fp = np.empty((nj, 3, 3)), np.empty((nj, 3)), np.empty((nf, 3, 3)), np.empty((nf, 3))
        _compiled().placements(self.ints, self.floats, np.asarray(q, dtype=float), oR, op, fR, fp)
        return oR, op, fR, fp

    def rows(self, q: np.ndarray, target: TaskTarget | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Residual ``[phi; task target]`` (m + n,) and its Jacobian (m + n, nv) at ``q``."""
        x, R = self._target_arrays(target)
        n = self.arrays.m + (target.size if target is not None else 0)
        r, A = np.empty(n), np.empty((n, self.arrays.nv))
        _compiled().rows(self.ints, self.floats, np.asarray(q, float), x, R, target is not None, r, A)
        return r, A

    def dynamics(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
        r"""Joint-space dynamics terms at ``(q, v)`` (:mod:`.dynamics`).

        Args:
            q: configuration, shape (nq,).
            v: joint velocities [m/s, rad/s], shape (nv,).

        Returns:
            The mass matrix with the armature on its diagonal (nv, nv), the nonlinear effects
            ``rnea(q, v, 0)`` (nv,) [N, N m], the potential energy [J] and the closure drift
            :math:`\dot J_\phi v` (m,).
        """
        nv, m = self.arrays.nv, self.arrays.m
        M, h, gamma = np.empty((nv, nv)), np.empty(nv), np.empty(m)
        potential = _dynamics().terms(
            self.ints, self.floats, np.asarray(q, float), np.asarray(v, float), LOG3_SERIES_ANGLE, M, h, gamma
        )
        return M, h, float(potential), gamma

    def samples(
        self,
        states: np.ndarray,
        origin: np.ndarray,
        tau: np.ndarray,
        rank: int,
        tol: float,
        velocity_tol: float,
        out: tuple[np.ndarray, ...],
    ) -> int:
        r"""Project and evaluate simulation states in turn (:func:`.dynamics.samples`) up to one it cannot.

        Args:
            states: chart coordinates at ``origin`` (the configuration itself for a vector-space
                model) and velocities of each state, shape (n, 2 nv).
            origin: the chart's configuration, shape (nq,).
            tau: applied generalized forces [N, N m], shape (nv,).
            rank: independent closure rows, :math:`n_v - \text{mobility}`.
            tol: closure distance above which the configuration is projected [m, rad].
            velocity_tol: closure rate above which the velocity is projected [m/s, rad/s].
            out: the buffers receiving row by row the configurations (n, nq), velocities (n, nv),
                accelerations (n, nv), closure forces (n, m), closure distances after and before
                the projection (n,), energies (n,), potential energies (n,) and task poses (n, n_task).

        Returns:
            The number of states done; the next one needs the Python path (a constraint
            singularity, a projection needing more than one step, a non-finite value).
        """
        nv = self.arrays.nv
        done, _ = _dynamics().samples(
            self.ints, self.floats, states, origin, origin.size == nv, tau, rank, tol, velocity_tol,
            RANK_RTOL, LOG3_SERIES_ANGLE, *out,
        )  # fmt: skip
        return int(done)

    def integrate(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Pinocchio's ``integrate``: ``q`` moved by the tangent vector ``v``."""
        out = np.empty(len(q))
        _compiled().integrate_packed(self.ints, self.floats, np.asarray(q, float), np.asarray(v, float), out)
        return out

    def newton(
        self,
        q0: np.ndarray,
        free: np.ndarray | None,
        tol: float,
        target: TaskTarget | None = None,
        polish: bool = True,
        max_iterations: int = NEWTON_MAX_ITERATIONS,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """:func:`plm_pin.core.assembly.newton` on the kernels, or None when it stalls.

        Args:
            q0: starting configuration, shape (nq,).
            free: velocity columns allowed to move (None: all).
            tol: target largest absolute residual [m, rad].
            target: task rows solved with the closures.
            polish: take the polishing step once within ``tol``.
            max_iterations: iterations before it gives up.

        Returns:
            The configuration, its residual ``[phi; task target]`` and its task coordinates
            (:meth:`plm_pin.core.task.Task.pose_from_data`, empty without a task).
        """
        solved = self.solve(q0, free, tol, target, polish, max_iterations=max_iterations)
        return None if solved is None else solved[:3]

    def solve(
        self,
        q0: np.ndarray,
        free: np.ndarray | None,
        tol: float,
        target: TaskTarget | None = None,
        polish: bool = True,
        in_place: bool = False,
        max_iterations: int = NEWTON_MAX_ITERATIONS,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, bool] | None:
        """:meth:`newton`, with the largest absolute residual and whether the solution is within limits.

        Args:
            q0: starting configuration, shape (nq,).
            free: velocity columns allowed to move (None: all).
            tol: target largest absolute residual [m, rad].
            target: task rows solved with the closures.
            polish: take the polishing step once within ``tol``.
            in_place: solve in ``q0`` itself, a writable C-contiguous float array the caller gives
                up (it holds the last iterate when Newton stalls), instead of in a copy.
            max_iterations: iterations before it gives up.

        Returns:
            ``(q, residual, pose, residual_norm, within_limits)``, or None when Newton stalls.
        """
        x, R = self._target_arrays(target)
        q = q0 if in_place else _float_copy(q0)
        task_rows = target.size if target is not None else None
        return self._solve(q, free, tol, x, R, task_rows, polish, max_iterations)

    def assemble(
        self,
        q0: np.ndarray,
        free: np.ndarray | None,
        tol: float,
        target: TaskTarget | None = None,
        max_iterations: int = 100,
    ) -> tuple[np.ndarray, np.ndarray, bool]:
        """:func:`plm_pin.core.assembly.assemble` (Levenberg-Marquardt) on the kernels.

        Args:
            q0: starting configuration, shape (nq,).
            free: velocity columns allowed to move (None: all).
            tol: target largest absolute residual [m, rad].
            target: task rows solved with the closures.
            max_iterations: iteration cap.

        Returns:
            The last iterate, its residual ``[phi; task target]`` and whether ``tol`` was reached.
        """
        x, R = self._target_arrays(target)
        q = _float_copy(q0)
        r = np.empty(self.arrays.m + (target.size if target is not None else 0))
        iterations = _compiled().assemble(
            self.ints, self.floats, self._all if free is None else free, x, R, target is not None, tol,
            ASSEMBLY_RCOND, ROUND_OFF, max_iterations, q, r,
        )  # fmt: skip
        return q, r, iterations >= 0

    def solve_pose(
        self, q0: np.ndarray, tol: float, task: Task, x: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, bool] | None:
        """:meth:`solve` on every column with the task rows of ``TaskTarget(task, x)``, without building it.

        Args:
            q0: starting configuration, shape (nq,).
            tol: target largest absolute residual [m, rad].
            task: the task the kernel was built with.
            x: its target coordinates [m, rad], shape (n_task,).
        """
        x, R = self._pose_arrays(task, x) if self._rotation_target else (x, _EYE)
        return self._solve(_float_copy(q0), None, tol, x, R, self.n_task, True)

    def _solve(
        self,
        q: np.ndarray,
        free: np.ndarray | None,
        tol: float,
        x: np.ndarray,
        R: np.ndarray,
        task_rows: int | None,
        polish: bool,
        max_iterations: int = NEWTON_MAX_ITERATIONS,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, bool] | None:
        """:meth:`solve` from ``q``, overwritten, the target as arrays and its rows (None: no target)."""
        pose, info = np.empty(self.n_task), np.empty(2)
        r = np.empty(self.arrays.m + (task_rows or 0))
        iterations = _compiled().newton(
            self.ints,
            self.floats,
            self._all if free is None else free,
            x,
            R,
            task_rows is not None,
            tol,
            ROUND_OFF,
            max_iterations,
            STALL_RATIO,
            CHORD_RATIO,
            polish,
            q,
            r,
            pose,
            info,
        )
        if iterations < 0:
            return None
        residual_norm, inside = info.tolist()
        return q, r, pose, residual_norm, bool(inside)

    def walk_rows(
        self,
        legs: Sequence[Leg],
        wanted: Sequence[int],
        poses: np.ndarray,
        R_stars: np.ndarray,
        Q: np.ndarray,
        reached: np.ndarray,
        modes: np.ndarray,
        n1: int,
        i0: int,
        lag: int,
        tol: float,
    ) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """Solve the rows on both sides of row ``i0`` of a grid, both sides' next rows a step (a frame task).

        Each step (:func:`.compiled.walk_rows_step`) predicts the next row of each side per column
        from the rows before it on its side, solves it by Gauss-Newton (as :meth:`newton_modes`)
        and writes the points that converge in a working mode compatible with ``wanted`` into
        ``Q``, ``reached`` and ``modes``; the downward side waits ``lag`` steps. A side ends at
        the grid's edge or after a row with no solved point.

        Args:
            legs: the mechanism's legs (the square ones carry the working mode).
            wanted: the working mode to keep, one sign per square leg (0 matches either).
            poses: task targets of the row-major grid, shape (n_points, n_task).
            R_stars: their rotations where the task holds all three angles (n_points, 3, 3), else
                any one rotation (1, 3, 3).
            Q: configurations (in and out), shape (n_points, nq).
            reached: solved points (in and out), shape (n_points,).
            modes: working modes (out where reached), shape (n_points, n_legs).
            n1: columns of the grid.
            i0: the row already solved (the seed's).
            lag: steps the downward side waits.
            tol: residual tolerance [m, rad].

        Yields:
            Per step with points kept, their flat indices (b,) and IK Jacobians ``[J_phi; J_x]``
            (task twist rows) (b, m + n_task, nv): views valid until the next step.
        """
        blocks, turns, generic = self._leg_arrays(legs)
        target = np.asarray(wanted, dtype=np.int8)
        fronts = np.array([i0 + 1, i0 - 1], dtype=np.int64)
        index = np.empty(2 * n1, dtype=np.int64)
        A = np.empty((2 * n1, self.arrays.m + poses.shape[1], self.arrays.nv))
        step = _compiled().walk_rows_step
        for k in itertools.count():
            count = step(
                self.ints, self.floats, blocks, turns, generic, target, LEG_SINGULAR_RTOL, poses, R_stars,
                Q, reached, modes, n1, fronts, np.bool_(k < lag), tol, NEWTON_MAX_ITERATIONS, STALL_RATIO,
                index, A,
            )  # fmt: skip
            if count < 0:
                return
            if count:
                yield index[:count], A[:count]

    def walk_line(
        self,
        legs: Sequence[Leg],
        wanted: Sequence[int],
        poses: np.ndarray,
        R_stars: np.ndarray,
        Q: np.ndarray,
        reached: np.ndarray,
        modes: np.ndarray,
        start: int,
        step: int,
        tol: float,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Walk one side of a line of poses from its solved point ``start`` (:func:`.compiled.walk_line`).

        Args:
            legs: the mechanism's legs (the square ones carry the working mode).
            wanted: the working mode to keep, one sign per square leg (0 matches either).
            poses: task targets of the line's points, in order, shape (n, n_task).
            R_stars: as :meth:`walk_rows` takes them, for these points.
            Q: their configurations (in and out; a view writes through), shape (n, nq).
            reached: solved points (in and out), shape (n,).
            modes: working modes (out where reached), shape (n, n_legs).
            start: the point walked from.
            step: +1 or -1.
            tol: residual tolerance [m, rad].

        Returns:
            The indices of the points kept, in walking order (b,), and their IK Jacobians
            ``[J_phi; J_x]`` (task twist rows) (b, m + n_task, nv); the walk stopped at point
            ``start + step * (b + 1)``.
        """
        blocks, turns, generic = self._leg_arrays(legs)
        n = reached.shape[0]
        index = np.empty(n, dtype=np.int64)
        A = np.empty((n, self.arrays.m + poses.shape[1], self.arrays.nv))
        count = _compiled().walk_line(
            self.ints, self.floats, blocks, turns, generic, np.asarray(wanted, dtype=np.int8),
            LEG_SINGULAR_RTOL, poses, R_stars, Q, reached, modes, start, step, tol,
            NEWTON_MAX_ITERATIONS, STALL_RATIO, index, A,
        )  # fmt: skip
        return index[:count], A[:count]

    def newton_modes(
        self, legs: Sequence[Leg], Q: np.ndarray, X: np.ndarray, R_stars: np.ndarray, tol: float,
        max_iterations: int = NEWTON_MAX_ITERATIONS,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        """Gauss-Newton at each pose of a batch, with the working mode of each that converges (a frame task).

        One compiled call (:func:`.compiled.batch_newton_modes`): each start's quaternions and
        (cos, sin) pairs are put back to unit norm, every iteration takes a fresh Jacobian, and a
        pose fails when its residual does not fall below :data:`STALL_RATIO` times the previous
        one, when the normal matrix is not positive definite, or after ``max_iterations``.

        Args:
            legs: the mechanism's legs (the square ones carry the working mode).
            Q: starting configurations, shape (B, nq) (a solution with ``max_iterations`` 0: only
                its Jacobian and mode are computed).
            X: task targets, shape (B, n_task).
            R_stars: their rotations where the task holds all three angles (else ignored),
                (B, 3, 3), or one for every pose (1, 3, 3).
            tol: residual tolerance [m, rad].
            max_iterations: iteration cap.

        Returns:
            Configurations (B, nq), which converged (B,), the inverse-kinematics Jacobians
            ``[J_phi; J_x]`` (task twist rows) (B, m + n_task, nv) and the working modes (B, n_legs),
            one sign per square leg (0 where its block is singular); the last two meaningful
            where converged.
        """
        a = self.arrays
        B = Q.shape[0]
        q = np.array(Q, dtype=float)
        blocks, turns, generic = self._leg_arrays(legs)
        ok = np.zeros(B, dtype=np.bool_)
        A = np.empty((B, a.m + X.shape[1], a.nv))
        modes = np.zeros((B, blocks.shape[0]), dtype=np.int8)
        _compiled().batch_newton_modes(
            self.ints, self.floats, blocks, turns, generic, LEG_SINGULAR_RTOL, q,
            np.ascontiguousarray(X, dtype=float), np.ascontiguousarray(R_stars, dtype=float), tol,
            max_iterations, STALL_RATIO, ok, A, modes,
        )  # fmt: skip
        return q, ok, A, modes

    def _leg_arrays(self, legs: Sequence[Leg]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:func:`_leg_arrays` of ``legs``, kept for the last legs asked (a mechanism's, asked per point).

        Raises:
            ValueError: a leg's sign rows reach past the IK Jacobian (the compiled modes read only it).
        """
        if self._legs is None or self._legs[0] is not legs:
            packed = _leg_arrays(legs)
            rows = packed[0][:, 1 : 1 + (packed[0].shape[1] - 1) // 2]
            if rows.size and rows.max() >= self.arrays.m + self.n_task:
                raise ValueError("working modes with sign rows past the IK Jacobian are not compiled")
            self._legs = (legs, packed)
        return self._legs[1]

    def map_metrics(
        self, A: np.ndarray, actuated_v: np.ndarray, mobility: int, names: Sequence[str]
    ) -> tuple[np.ndarray, np.ndarray]:
        """Map metrics of stacked Jacobians ``A = [J_phi; J_x]`` (B, m + k, nv), compiled (:mod:`.metrics`).

        Only the metrics in ``names`` (among :data:`.metrics.METRIC_NAMES`) are computed.

        Returns:
            The metrics (B, 5) in the order of :data:`.metrics.METRIC_NAMES` (NaN in the columns
            not asked for), and whether each pose passed the acceptance tests of those it
            computes (B,) (the others' rows are meaningless).
        """
        from . import metrics

        B = A.shape[0]
        out, good = np.full((B, len(metrics.METRIC_NAMES)), np.nan), np.zeros(B, dtype=np.bool_)
        metrics.square_metrics(
            np.ascontiguousarray(A, dtype=float),
            self.arrays.m,
            np.asarray(actuated_v, dtype=np.int64),
            mobility,
            self.elimination,
            np.array([name in names for name in metrics.METRIC_NAMES]),
            FACTOR_RCOND,
            GRAM_RTOL,
            INVERSE_RTOL,
            out,
            good,
        )
        return out, good


def _leg_arrays(legs: Sequence[Leg]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The square legs' sign blocks and passive revolutes packed as the compiled working modes read them.

    Returns:
        Per square leg its block size ``n``, its ``n`` sign rows and ``n`` velocity columns, each
        padded to the largest block (n_legs, 1 + 2 * size); per passive revolute to orient its
        leg, column in the block, joint and the leg's root joint (n_axes, 4); and its generic
        axis in the root joint's frame (n_axes, 3).
    """
    square = [leg for leg in legs if leg.square]
    size = max((len(leg.columns) for leg in square), default=0)
    blocks = np.zeros((len(square), 1 + 2 * size), dtype=np.int64)
    for n, leg in enumerate(square):
        blocks[n, 0] = len(leg.columns)
        blocks[n, 1 : 1 + len(leg.columns)] = leg.sign_rows
        blocks[n, 1 + size : 1 + size + len(leg.columns)] = leg.columns
    axes = [(n, *axis) for n, leg in enumerate(square) for axis in leg.axes]
    turns = np.array([a[:4] for a in axes], dtype=np.int64).reshape(-1, 4)
    generic = np.array([a[4] for a in axes], dtype=float).reshape(-1, 3)
    return blocks, turns, generic


_FLOAT = np.dtype(float)


def _float_copy(q: np.ndarray) -> np.ndarray:
    """``q`` as a new C-contiguous float array (the compiled Newton's start, solved in place)."""
    # a float array's copy() is the same array as np.array(q, dtype=float), for half its cost
    return q.copy() if type(q) is np.ndarray and q.dtype is _FLOAT else np.array(q, dtype=float)


_NO_TARGET = np.zeros(0)
_EYE = np.eye(3)
_COMPILED: list[ModuleType] = []
_DYNAMICS: list[ModuleType] = []


def _dynamics() -> ModuleType:
    """The compiled dynamics module (imports numba; compiled on first call, cached on disk)."""
    if not _DYNAMICS:
        from . import dynamics

        _DYNAMICS.append(dynamics)
    return _DYNAMICS[0]


def _compiled() -> ModuleType:
    """The compiled module (imports numba; its functions compile on first call, cached on disk)."""
    if not _COMPILED:
        from . import compiled

        _COMPILED.append(compiled)
    return _COMPILED[0]


_WARNED: set[str] = set()


def _warn_once(key: str, message: str) -> None:
    if key not in _WARNED:
        _WARNED.add(key)
        warnings.warn(message, KernelFallbackWarning, stacklevel=4)


def kernels_enabled() -> bool:
    """Whether the kernels may be used: ``PLM_PIN_KERNELS`` is not ``0`` and numba imports."""
    if _switched_off():
        return False
    if not _NUMBA:
        try:
            import numba  # noqa: F401
        except ImportError:
            _warn_once(
                "numba",
                "numba is not installed: kinematics runs on the Pinocchio path (same results, slower)",
            )
            return False
        _NUMBA.append(True)
    return True


def _switched_off() -> bool:
    """Whether ``PLM_PIN_KERNELS`` reads ``0`` now (read at each call: tests and callers change it).

    On POSIX ``os.environ`` keeps its entries in a dict of encoded bytes, ``_data``, which its
    setters and deleters update: reading it there skips the key's encoding and the Mapping
    machinery (a twentieth of ``os.environ.get``'s cost), the value decoded as ``os.environ`` does.
    """
    data = getattr(os.environ, "_data", None) if _POSIX else None
    if type(data) is not dict:
        return os.environ.get(SWITCH, "1").strip() == "0"
    raw = data.get(_SWITCH_KEY)
    return raw is not None and os.fsdecode(raw).strip() == "0"


_POSIX = os.name == "posix"
_SWITCH_KEY = os.fsencode(SWITCH)
"""The switch's name as ``os.environ`` encodes it (the file-system encoding)."""

_NUMBA: list[bool] = []
"""Holds True once numba imported."""


def kernel_of(mech: Mechanism) -> Kernel | None:
    """The compiled kernel of ``mech``, or None where the Pinocchio path must run (see the module).

    Built at first use from the model, the closures and the task, then kept with the mechanism.
    """
    if _switched_off() or (not _NUMBA and not kernels_enabled()):
        return None
    closures = mech.closures  # the model is final (idle gauges added) once they are compiled
    hit = vars(mech).get(_CACHE)
    if hit is not None and hit[0] is closures:
        return hit[1]
    missing = unsupported_joints(mech.model)
    kernel = None
    if missing:
        _warn_once(
            f"joints:{mech.name}",
            f"{mech.name}: the compiled kernels do not handle the joints {', '.join(missing)}; "
            "kinematics runs on the Pinocchio path (slower, same results)",
        )
    else:
        kernel = Kernel.build(mech.model, closures, mech.task_compiled)
    vars(mech)[_CACHE] = (closures, kernel)
    return kernel


_CACHE = "_kernel"
"""Attribute of a mechanism holding its closures and their kernel (or None)."""
