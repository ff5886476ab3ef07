r"""Path continuation on the closure manifold: sampled task and actuator paths, tracked.

Generic: any mechanism with a task (:class:`plm_pin.Mechanism`).

- :func:`follow_targets`: continuation along a sampled path of prescribed task coordinates
  and fixed joints (warm-started Newton with a secant predictor); with every task
  coordinate prescribed it is inverse-kinematics continuation.
- :func:`track_actuator_path`: forward-kinematics continuation along a sampled actuator
  path (:meth:`Mechanism.assemble` with the actuators fixed, warm-started), with the
  singularity margins of :func:`plm_pin.kinematics.classify` and the
  :func:`redundancy_margin` at every sample, returned as a :class:`TrackedPath`.
- :func:`redundancy_margin`: the smallest direct margin left when any one actuator is
  removed; zero where a redundantly actuated chain *loses its redundancy* while staying
  non-singular.

Units: lengths [m], angles [rad], margins are normalised singular-value ratios [-].
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import check_tolerance, mapping, positive, real_numbers
from .._text import short
from ..core.assembly import assemble
from ..core.mechanism import Mechanism, require_task
from ..core.task import FrameTask, Task, TaskTarget, compile_joint_task, compile_task
from ..exceptions import ClosureNotSatisfied, InvalidInput, PoseUnreachable
from ..results import Result, unit
from ..tolerances import SINGULARITY_TOL, TRACK_TOL
from .jacobians import ClosedChainJacobians, closed_chain_jacobians
from .singularity import SingularityReport, direct_margins, report_from_jacobians


def redundancy_margin(mech: Mechanism, q: ArrayLike, jac: ClosedChainJacobians | None = None) -> float:
    r"""Smallest direct margin left when any one actuator is removed [-].

    For each actuator :math:`k`, the direct margin (:mod:`plm_pin.kinematics.singularity`) of
    :math:`C` without row :math:`k`, the smallest singular value; the minimum over
    :math:`k`. It is zero where some single actuator has become indispensable: a
    redundantly actuated chain that *loses its redundancy* (Harada 2015: a sub-mechanism
    at ``[0]``) while :math:`C` keeps full rank. Zero for a non-redundant chain.

    Args:
        mech: the mechanism.
        q: assembled configuration, shape (nq,).
        jac: Jacobians already computed at ``q`` (optional).
    """
    j = closed_chain_jacobians(mech, q) if jac is None else jac
    C = j.C  # (n_act, mobility)
    if C.shape[0] <= C.shape[1]:
        return 0.0
    return min(float(direct_margins(np.delete(C, k, axis=0))) for k in range(C.shape[0]))


def _predict(mech: Mechanism, qs: Sequence[np.ndarray], s: np.ndarray, k: int) -> np.ndarray:
    """Secant predictor for sample ``k`` from the two previous solutions."""
    if k < 2:
        return np.array(qs[-1])
    ds_prev = s[k - 1] - s[k - 2]
    if ds_prev == 0.0:
        return np.array(qs[-1])
    dq = pin.difference(mech.model, qs[-2], qs[-1]) * ((s[k] - s[k - 1]) / ds_prev)
    return np.asarray(pin.integrate(mech.model, qs[-1], dq))


def _check_path_parameter(s: ArrayLike | None, n: int) -> np.ndarray:
    arr = (
        np.arange(n, dtype=float) / max(n - 1, 1)
        if s is None
        else np.asarray(real_numbers(s, "s"), dtype=float)
    )
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise InvalidInput(f"s must be {n} finite numbers, got shape {arr.shape}")
    if n > 1 and np.any(np.diff(arr) < 0.0):
        raise InvalidInput("s must be non-decreasing")
    return arr


def follow_targets(
    mech: Mechanism,
    guess: ArrayLike,
    *,
    task_dofs: Sequence[str] = (),
    task_values: ArrayLike | None = None,
    fixed: Mapping[str, ArrayLike] | None = None,
    s: ArrayLike | None = None,
    tol: float | None = None,
) -> np.ndarray:
    r"""Configurations along a sampled path of prescribed task coordinates and joint values.

    At each sample, Newton (Levenberg-Marquardt) solves the closures together with the
    prescribed task coordinates of the mechanism's task frame, the ``fixed`` joints held
    at their values, from a secant prediction of the two previous solutions; so the
    branch of ``guess`` is followed as long as the sampled system stays regular and the
    samples are dense. With every task coordinate prescribed this is inverse-kinematics
    continuation; with the actuators fixed, forward-kinematics continuation.

    Args:
        mech: the mechanism.
        guess: configuration near the first sample, shape (nq,).
        task_dofs: prescribed task coordinates among the task's (e.g. ``("x", "rz")``).
        task_values: their values [m, rad], shape (N, len(task_dofs)).
        fixed: one-DOF joint name -> values along the path [m, rad], shape (N,).
        s: path parameter of the samples, shape (N,), non-decreasing (for the predictor);
            default uniform.
        tol: closure and target tolerance [m, rad] (default: :data:`~plm_pin.tolerances.TRACK_TOL`, or
            the mechanism's ``closure_tol`` when larger).

    Returns:
        The configurations, shape (N, nq).

    Raises:
        PoseUnreachable: when a sample cannot be solved; the message names the sample.
        InvalidInput: malformed inputs.
    """
    tol = max(TRACK_TOL, mech.closure_tol) if tol is None else positive(tol, "tol", "m, rad")
    task = require_task(mech)
    if (
        isinstance(task_dofs, str)
        or not isinstance(task_dofs, Sequence)
        or not all(isinstance(d, str) for d in task_dofs)
    ):
        raise InvalidInput(f"task_dofs must be a sequence of task coordinate names, got {short(task_dofs)}")
    dofs = tuple(task_dofs)
    unknown = [d for d in dofs if d not in task.dofs]
    if unknown:
        raise InvalidInput(f"task coordinates {unknown} are not in the task {list(task.dofs)}")
    fixed = dict(mapping(fixed or {}, "fixed", "one-DOF joint names to values along the path [m, rad]"))
    sizes = []
    values = None
    if dofs:
        values = np.asarray(real_numbers(task_values, "task_values"), dtype=float)
        if values.ndim != 2 or values.shape[1] != len(dofs) or not np.all(np.isfinite(values)):
            raise InvalidInput(f"task_values must be finite with shape (N, {len(dofs)}), got {values.shape}")
        sizes.append(values.shape[0])
    fixed_values = {}
    for joint, vals in fixed.items():
        arr = np.asarray(real_numbers(vals, f"fixed[{joint!r}]"), dtype=float)
        if arr.ndim != 1 or not np.all(np.isfinite(arr)):
            raise InvalidInput(f"fixed[{joint!r}] must be a finite 1-D array, got shape {arr.shape}")
        fixed_values[joint] = arr
        sizes.append(arr.shape[0])
    if not sizes or len(set(sizes)) != 1:
        raise InvalidInput(f"prescribe at least one quantity, all with the same sample count; got {sizes}")
    n = sizes[0]
    sp = _check_path_parameter(s, n)
    sub_task: Task | None = None
    if dofs and isinstance(task, FrameTask):
        sub_task = compile_task(mech.model, mech.model.frames[task.frame_id].name, dofs)
    elif dofs:
        sub_task = compile_joint_task(mech.model, dofs)
    free = mech.free_columns(fixed_values)
    qs: list[np.ndarray] = [mech.check_q(guess, "guess")]
    for joint in fixed_values:
        nv = mech.model.joints[mech.model.getJointId(joint)].nv
        if nv != 1:
            raise InvalidInput(f"joint {joint!r} has {nv} DOF; only one-DOF joints can be prescribed")
    out: list[np.ndarray] = []
    for k in range(n):
        near = _predict(mech, qs, sp, k) if out else np.array(qs[0])
        for joint, arr in fixed_values.items():
            mech.set_joint(near, joint, float(arr[k]))
        target = TaskTarget(sub_task, values[k]) if sub_task is not None and values is not None else None
        try:
            q = assemble(
                mech.model, mech.data, mech.closures, near, free, tol=tol, max_iterations=60, extra=target
            ).q
        except ClosureNotSatisfied as exc:
            raise PoseUnreachable(
                f"{mech.name}: path sample {k} of {n} (s = {sp[k]:.6g}) cannot be reached from the "
                f"previous one: residual {exc.residual_norm:.3g} above {tol:.3g}; refine the sampling "
                "or check that the path stays in the workspace"
            ) from None
        qs = [qs[-1], q] if out else [q]
        out.append(q)
    return np.array(out)


_TRACKED_ARRAYS = (
    "s",
    "actuators",
    "q",
    "x",
    "residual",
    "constraint_margin",
    "inverse_margin",
    "direct_margin",
    "redundancy_margin",
)


@dataclass(frozen=True)
class TrackedPath(Result):
    """A sampled actuator path with the configuration followed along it (forward continuation).

    Attributes:
        s: path parameter of the samples [-], shape (N,).
        actuators: actuator positions [m] or [rad], shape (N, n_act).
        q: tracked configurations, shape (N, nq).
        x: task coordinates of the end-effector frame [m, rad], shape (N, n_task).
        residual: largest absolute closure residual per sample [m, rad], shape (N,).
        constraint_margin: constraint-singularity margin per sample [-], shape (N,).
        inverse_margin: inverse (type 1, actuator) singularity margin per sample [-], shape (N,).
        direct_margin: direct (type 2) singularity margin per sample [-], shape (N,); the
            normalised smallest singular value of :math:`C`, zero when its rank drops
            (Harada 2015: rank :math:`J_x` < 3).
        redundancy_margin: :func:`redundancy_margin` per sample [-], shape (N,).
        tol: the singularity tolerance the margins are judged against [-].
    """

    s: np.ndarray = field(metadata=unit("-"))
    actuators: np.ndarray = field(metadata=unit("m, rad"))
    q: np.ndarray = field(metadata=unit("m, rad"))
    x: np.ndarray = field(metadata=unit("m, rad"))
    residual: np.ndarray = field(metadata=unit("m, rad"))
    constraint_margin: np.ndarray = field(metadata=unit("-"))
    inverse_margin: np.ndarray = field(metadata=unit("-"))
    direct_margin: np.ndarray = field(metadata=unit("-"))
    redundancy_margin: np.ndarray = field(metadata=unit("-"))
    tol: float = field(metadata=unit("-"))
    _DERIVED = ("n_samples", "max_residual", "min_direct_margin", "nonsingular")

    def __post_init__(self) -> None:
        n = self.s.shape[0]
        for name in _TRACKED_ARRAYS:
            arr = getattr(self, name)
            if arr.shape[0] != n:
                raise InvalidInput(f"{name} has {arr.shape[0]} samples, s has {n}")
            arr.setflags(write=False)

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.s.shape[0])

    @property
    def max_residual(self) -> float:
        """Largest closure residual over the path [m, rad]."""
        return float(np.max(self.residual)) if self.residual.size else 0.0

    @property
    def min_direct_margin(self) -> float:
        """Smallest direct margin over the path [-]."""
        return float(np.min(self.direct_margin))

    @property
    def min_constraint_margin(self) -> float:
        """Smallest constraint margin over the path [-]."""
        return float(np.min(self.constraint_margin))

    @property
    def nonsingular(self) -> bool:
        """Whether the direct and constraint margins stay above ``tol`` at every sample.

        Inverse (actuator) singularities are allowed: a leg may fold while the mechanism
        keeps control of its end effector.
        """
        return bool(self.min_direct_margin > self.tol and self.min_constraint_margin > self.tol)

    def report(self, k: int) -> SingularityReport:
        """The singularity report of sample ``k``."""
        return SingularityReport(
            float(self.constraint_margin[k]),
            float(self.inverse_margin[k]),
            float(self.direct_margin[k]),
            self.tol,
        )


def track_actuator_path(
    mech: Mechanism,
    actuators: ArrayLike,
    guess: ArrayLike,
    *,
    s: ArrayLike | None = None,
    tol: float = SINGULARITY_TOL,
    closure_tol: float | None = None,
) -> TrackedPath:
    """Follow the configuration along a sampled actuator path (forward-kinematics continuation).

    At each sample :meth:`Mechanism.assemble` closes the loops with every actuator fixed
    at its sampled value, warm-started from a secant prediction of the two previous
    configurations, so the assembly mode of ``guess`` is followed; then the singularity
    margins and the redundancy margin are evaluated. For a redundantly actuated chain the
    actuator values must be consistent (e.g. from :func:`follow_targets`).

    Args:
        mech: the mechanism.
        actuators: actuator positions [m, rad], shape (N, n_act).
        guess: configuration near the first sample (it picks the assembly mode), shape (nq,).
        s: path parameter, shape (N,), non-decreasing (default uniform).
        tol: singularity tolerance the margins are judged against.
        closure_tol: closure tolerance of each assembly [m, rad] (default:
            :data:`~plm_pin.tolerances.TRACK_TOL`, or the mechanism's ``closure_tol`` when larger).

    Returns:
        The tracked path.

    Raises:
        ClosureNotSatisfied: when a sample cannot be assembled; the message names it.
        InvalidInput: malformed inputs.
    """
    tol = check_tolerance(tol, "tol")
    closure_tol = (
        max(TRACK_TOL, mech.closure_tol)
        if closure_tol is None
        else positive(closure_tol, "closure_tol", "m, rad")
    )
    c = np.asarray(real_numbers(actuators, "actuators"), dtype=float)
    if c.ndim != 2 or c.shape[1] != mech.n_actuators or not np.all(np.isfinite(c)):
        raise InvalidInput(
            f"actuators must be finite with shape (N, {mech.n_actuators}), got {np.shape(actuators)}"
        )
    n = c.shape[0]
    sp = _check_path_parameter(s, n)
    task = require_task(mech)
    names = [a.joint for a in mech.actuators]
    qs: list[np.ndarray] = [mech.check_q(guess, "guess")]
    out_q: list[np.ndarray] = []
    out_x: list[np.ndarray] = []
    res: list[float] = []
    cm: list[float] = []
    im: list[float] = []
    dm: list[float] = []
    rm: list[float] = []
    for k in range(n):
        near = _predict(mech, qs, sp, k) if out_q else np.array(qs[0])
        try:
            asm = mech.assemble(
                near, fixed=dict(zip(names, c[k].tolist(), strict=True)), tol=closure_tol, max_iterations=60
            )
        except ClosureNotSatisfied as exc:
            raise ClosureNotSatisfied(
                f"{mech.name}: actuator path sample {k} of {n} (s = {sp[k]:.6g}) cannot be assembled "
                f"from the previous configuration: {exc}",
                exc.residual_norm,
                exc.tolerance,
                exc.q,
                exc.worst_closure,
            ) from None
        q = asm.q
        qs = [qs[-1], q] if out_q else [q]
        out_q.append(q)
        jac = closed_chain_jacobians(mech, q)
        rep = report_from_jacobians(mech, jac, tol)
        pin.framesForwardKinematics(mech.model, mech.data, q)
        out_x.append(task.pose_from_data(mech.data))
        res.append(asm.residual_norm)
        cm.append(rep.constraint_margin)
        im.append(rep.inverse_margin)
        dm.append(rep.direct_margin)
        rm.append(redundancy_margin(mech, q, jac))
    return TrackedPath(
        sp.copy(),
        c.copy(),
        np.array(out_q),
        np.array(out_x),
        np.array(res),
        np.array(cm),
        np.array(im),
        np.array(dm),
        np.array(rm),
        tol,
    )
