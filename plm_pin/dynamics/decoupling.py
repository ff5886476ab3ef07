r"""Decoupling checks: which task-space terms vanish or stay constant over a workspace sample.

Harada 2011 (eq. (23), (26), (M.29)-(M.30)) designs its 2-PRRRP table so that the x motion
is *decoupled with constant inertia*: :math:`m_{xx}` constant, :math:`m_{xy} = m_{x\theta} = 0`,
no velocity or gravity term along x. :func:`decoupling_check` tests such claims numerically
for any mechanism: it evaluates :func:`plm_pin.dynamics.task_space.task_space_dynamics` at
every pose of a sample (and at a stated set of task velocities for :math:`h_x`) and classifies

- each entry of :math:`M_x` and each row of :math:`g_x` as ``zero`` (vanishes at every
  pose), ``constant`` (one value at every pose) or ``varies`` (with its range);
- each row of :math:`h_x` as ``zero`` or ``nonzero`` (with its range over the poses and
  velocities).

Velocities. At a pose :math:`h_x` is a quadratic form in the task velocity,
:math:`h_{x,i} = \dot x^T \Gamma_i \dot x`, so its values at the :math:`n (n + 1) / 2`
velocities :math:`v e_i` and :math:`v (e_i + e_j)`, :math:`i < j` (:func:`task_velocities`, each
rate :math:`v` = ``velocity_scale`` in m/s or rad/s), determine it: a row that vanishes at
all of them vanishes at every velocity. The range reported is over those velocities.

Tolerances. Each entry is compared with the largest value it could take, its
Cauchy-Schwarz bound in the kinetic-energy metric of the tree (:math:`s_i = S e_i` the
motion of task coordinate :math:`i`, :math:`\|s_i\|_M^2 = M_{x,ii}`):

.. math::
    |M_{x,ij}| \le \sqrt{M_{x,ii} M_{x,jj}}, \qquad
    |g_{x,i}| \le \sqrt{M_{x,ii}}\, \sqrt{g^T M^{-1} g}, \qquad
    |h_{x,i}| \le \sqrt{M_{x,ii}}\, \sqrt{h^T M^{-1} h},

(:math:`M, g, h` the joint-space terms; for :math:`h_x` the largest bound over the velocities
at that pose). An entry is ``zero`` when at every pose (and
velocity) its magnitude is at most :math:`\text{atol} + \text{rtol}\, B` with :math:`B`
its bound there, and ``constant`` when its range (max - min) over the sample is at most
:math:`\text{tol} = \text{atol} + \text{rtol} \max B`; tolerances are in the entry's own
unit (:func:`plm_pin.dynamics.task_space.task_units`). An entry that
vanishes by design is a cancellation (of the legs' contributions in Harada's table), exact
up to rounding, about 1e-16 of the bound; the default ``rtol``, :data:`DECOUPLING_RTOL`, is
far above rounding and far below any physical coupling. Raise it (say 1e-3) to ask whether
a term is negligible rather than absent.

Sample. Either task poses, each solved by inverse kinematics
(:func:`plm_pin.kinematics.inverse_kinematics`) in one working mode (default: the
reference configuration's), or a :class:`plm_pin.workspace.WorkspaceSlice` whose reachable
points are used as solved. Poses that cannot be reached in that working mode, and poses at
or near an inverse-kinematics (type 1) or constraint singularity (margin at most
``singular_tol``, :func:`plm_pin.kinematics.classify`), where :math:`M_x` is undefined or
unbounded, are *skipped* and reported (counts and poses), not raised: a box of poses usually overlaps the
workspace boundary. Malformed input (an empty sample, a wrong shape, a non-finite pose)
raises, and so does a sample of which no pose can be evaluated.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import check_tolerance, positive
from ..core.mechanism import Mechanism, require_task
from ..exceptions import InvalidInput, PoseUnreachable
from ..kinematics.inverse import check_mode, inverse_kinematics
from ..kinematics.jacobians import check_square_task
from ..kinematics.singularity import classify
from ..kinematics.working_mode import working_mode
from ..results import Result, unit
from ..tolerances import DECOUPLING_RTOL, SINGULARITY_TOL
from ..workspace.maps import WorkspaceSlice
from .task_space import TaskSpaceDynamics, task_space_dynamics, task_units


@dataclass(frozen=True)
class EntryBehaviour(Result):
    """How one task-space entry behaves over the sample.

    Attributes:
        kind: ``zero`` (vanishes at every pose), ``constant`` (one value at every pose) or
            ``varies``; a velocity-term row is ``zero`` or ``nonzero``.
        minimum: smallest value over the sample [unit].
        maximum: largest value over the sample [unit].
        tolerance: ``atol + rtol *`` the entry's largest bound over the sample: the threshold
            of ``constant`` and the largest threshold of ``zero`` (module docstring) [unit].
        ratio: largest ratio of the entry's magnitude to its Cauchy-Schwarz bound over the
            sample [-]: how strongly an off-diagonal inertia couples two coordinates (0 to 1),
            or what fraction of the joint-space term reaches the row; 1 on the diagonal.
        unit: SI unit of the entry (``kg``, ``kg m``, ``kg m^2``, ``N``, ``N m``).
    """

    kind: str
    minimum: float
    maximum: float
    tolerance: float
    ratio: float = field(metadata=unit("-"))
    unit: str
    _NONFINITE_AS_TEXT = ("ratio",)

    @property
    def value(self) -> float:
        """Mid-range value [unit]: the constant for a ``constant`` entry."""
        return 0.5 * (self.minimum + self.maximum)

    @property
    def spread(self) -> float:
        """Range ``maximum - minimum`` over the sample [unit]."""
        return self.maximum - self.minimum

    @property
    def largest(self) -> float:
        """Largest magnitude over the sample [unit]."""
        return max(abs(self.minimum), abs(self.maximum))

    def describe(self) -> str:
        """Short text: ``0``, the constant value, or the range with as many digits as tell its ends apart."""
        if self.kind == "zero":
            return "0"
        if self.kind == "constant":
            return f"{self.value:.6g} {self.unit}"
        digits = next((p for p in range(4, 18) if f"{self.minimum:.{p}g}" != f"{self.maximum:.{p}g}"), 4)
        return f"{self.minimum:.{digits}g} .. {self.maximum:.{digits}g} {self.unit}"


def _behaviour(
    zero: bool, minimum: float, maximum: float, tol: float, ratio: float, unit: str, *, constant: bool = True
) -> EntryBehaviour:
    """Classify an entry; ``constant=False`` for velocity terms: ``zero`` or ``nonzero`` (0 at rest)."""
    if not constant:
        kind = "zero" if zero else "nonzero"
    else:
        kind = "zero" if zero else "constant" if maximum - minimum <= tol else "varies"
    return EntryBehaviour(kind, float(minimum), float(maximum), float(tol), float(ratio), unit)


@dataclass(frozen=True)
class DecouplingReport(Result):
    r"""Behaviour of :math:`M_x`, :math:`g_x` and :math:`h_x` over a sample of task poses.

    Arrays are read-only. Per-entry behaviours come from :meth:`inertia`, :meth:`gravity`
    and :meth:`velocity`; the tolerance rule is in the module docstring.

    Attributes:
        mechanism: the mechanism's name.
        dofs: task coordinates (rows and columns of the terms).
        poses: poses evaluated [m, rad], shape (k, n_task).
        configurations: their configurations, shape (k, nq).
        unreachable: poses skipped as unreachable in the working mode [m, rad], shape (u, n_task).
        singular: poses skipped at an inverse-kinematics singularity [m, rad], shape (s, n_task).
        M_min: smallest value of each entry of :math:`M_x` [kg, kg m, kg m^2], shape (n_task, n_task).
        M_max: largest value of each entry of :math:`M_x`, shape (n_task, n_task).
        M_tol: tolerance of each entry of :math:`M_x`, ``atol + rtol B``, shape (n_task, n_task).
        M_zero: whether each entry of :math:`M_x` vanishes at every pose, shape (n_task, n_task).
        M_ratio: largest ratio of each entry to its bound [-], shape (n_task, n_task).
        g_min: smallest value of each row of :math:`g_x` [N, N m], shape (n_task,).
        g_max: largest value of each row of :math:`g_x`, shape (n_task,).
        g_tol: tolerance of each row of :math:`g_x`, shape (n_task,).
        g_zero: whether each row of :math:`g_x` vanishes at every pose, shape (n_task,).
        g_ratio: largest ratio of each row of :math:`g_x` to its bound [-], shape (n_task,).
        h_min: smallest value of each row of :math:`h_x` at the velocities ``velocities`` [N, N m],
            shape (n_task,).
        h_max: largest value of each row of :math:`h_x`, shape (n_task,).
        h_tol: tolerance of each row of :math:`h_x`, shape (n_task,).
        h_zero: whether each row of :math:`h_x` vanishes at every pose and velocity, shape (n_task,).
        h_ratio: largest ratio of each row of :math:`h_x` to its bound [-], shape (n_task,).
        rtol: cancellation ratio used [-].
        atol: absolute tolerance used, in each entry's unit.
        velocities: the task velocities :math:`h_x` is evaluated at, at every pose
            (:func:`task_velocities`) [m/s, rad/s], shape (n_task (n_task + 1) / 2, n_task).
    """

    mechanism: str
    dofs: tuple[str, ...]
    poses: np.ndarray = field(metadata=unit("m, rad"))
    configurations: np.ndarray = field(metadata=unit("m, rad"))
    unreachable: np.ndarray = field(metadata=unit("m, rad"))
    singular: np.ndarray = field(metadata=unit("m, rad"))
    M_min: np.ndarray = field(metadata=unit("kg, kg m, kg m^2"))
    M_max: np.ndarray = field(metadata=unit("kg, kg m, kg m^2"))
    M_tol: np.ndarray = field(metadata=unit("kg, kg m, kg m^2"))
    M_zero: np.ndarray
    M_ratio: np.ndarray = field(metadata=unit("-"))
    g_min: np.ndarray = field(metadata=unit("N, N m"))
    g_max: np.ndarray = field(metadata=unit("N, N m"))
    g_tol: np.ndarray = field(metadata=unit("N, N m"))
    g_zero: np.ndarray
    g_ratio: np.ndarray = field(metadata=unit("-"))
    h_min: np.ndarray = field(metadata=unit("N, N m"))
    h_max: np.ndarray = field(metadata=unit("N, N m"))
    h_tol: np.ndarray = field(metadata=unit("N, N m"))
    h_zero: np.ndarray
    h_ratio: np.ndarray = field(metadata=unit("-"))
    rtol: float = field(metadata=unit("-"))
    atol: float
    velocities: np.ndarray = field(metadata=unit("m/s, rad/s"))
    _SKIPPED = (
        "configurations",
        *(f"{t}_{s}" for t in "Mgh" for s in ("min", "max", "tol", "zero", "ratio")),
    )
    _DERIVED = ("n_poses",)

    def __post_init__(self) -> None:
        n = len(self.dofs)
        shapes: dict[str, tuple[int, ...]] = {
            **{f"M_{s}": (n, n) for s in ("min", "max", "tol", "zero", "ratio")},
            **{f"{t}_{s}": (n,) for t in "gh" for s in ("min", "max", "tol", "zero", "ratio")},
        }
        for name in ("poses", "unreachable", "singular"):
            shapes[name] = (getattr(self, name).shape[0], n)
        shapes["velocities"] = (n * (n + 1) // 2, n)
        shapes["configurations"] = (self.poses.shape[0], self.configurations.shape[-1])
        for name, shape in shapes.items():
            arr = getattr(self, name)
            if arr.shape != shape:
                raise InvalidInput(f"{name} has shape {arr.shape}, expected {shape}")
            arr.setflags(write=False)

    @property
    def n_poses(self) -> int:
        """Number of poses evaluated."""
        return int(self.poses.shape[0])

    def _index(self, dof: str) -> int:
        if dof not in self.dofs:
            raise InvalidInput(
                f"unknown task coordinate {dof!r}; the task's coordinates are {list(self.dofs)}"
            )
        return self.dofs.index(dof)

    def inertia(self, row: str, column: str) -> EntryBehaviour:
        """Behaviour of the entry of :math:`M_x` at task coordinates ``row``, ``column`` (e.g. x, y)."""
        i, j = self._index(row), self._index(column)
        unit = task_units(self.dofs)[0][i * len(self.dofs) + j]
        return _behaviour(
            bool(self.M_zero[i, j]),
            self.M_min[i, j],
            self.M_max[i, j],
            self.M_tol[i, j],
            self.M_ratio[i, j],
            unit,
        )

    def gravity(self, row: str) -> EntryBehaviour:
        """Behaviour of the row ``row`` of :math:`g_x`."""
        i = self._index(row)
        unit = task_units(self.dofs)[1][i]
        return _behaviour(
            bool(self.g_zero[i]), self.g_min[i], self.g_max[i], self.g_tol[i], self.g_ratio[i], unit
        )

    def velocity(self, row: str) -> EntryBehaviour:
        """Behaviour of the row ``row`` of :math:`h_x` at :attr:`velocities` (``zero`` or ``nonzero``)."""
        i = self._index(row)
        unit = task_units(self.dofs)[1][i]
        return _behaviour(
            bool(self.h_zero[i]),
            self.h_min[i],
            self.h_max[i],
            self.h_tol[i],
            self.h_ratio[i],
            unit,
            constant=False,
        )

    def decoupled(self) -> tuple[str, ...]:
        r"""Task coordinates decoupled with constant inertia (Harada 2011's x).

        Those whose off-diagonal inertias vanish, diagonal inertia and gravity term are
        constant (or zero) and velocity term vanishes, so that :math:`m_{ii} \ddot x_i + g_i = f_i`.
        """
        out = []
        for d in self.dofs:
            couplings = [self.inertia(d, e).kind == "zero" for e in self.dofs if e != d]
            if (
                all(couplings)
                and self.inertia(d, d).kind != "varies"
                and self.gravity(d).kind != "varies"
                and self.velocity(d).kind == "zero"
            ):
                out.append(d)
        return tuple(out)

    def entries(self) -> list[tuple[str, EntryBehaviour]]:
        """Every entry by name: the upper triangle of M_x (``M_xy``), then the g_x and h_x rows."""
        out = [(f"M_{a}{b}", self.inertia(a, b)) for i, a in enumerate(self.dofs) for b in self.dofs[i:]]
        out += [(f"g_{a}", self.gravity(a)) for a in self.dofs]
        out += [(f"h_{a}", self.velocity(a)) for a in self.dofs]
        return out

    def to_table(self) -> str:
        """Readable text table: ``0``, a constant value, or a range per entry, with the tolerances."""
        header = [
            f"Decoupling of {self.mechanism} over {self.n_poses} poses ({len(self.unreachable)} unreachable "
            f"and {len(self.singular)} singular skipped), h_x at the {len(self.velocities)} task velocities "
            f"{self.velocity_text()} per pose, which determine it (zero there: zero at every velocity)",
            f"zero: |value| <= atol + rtol x its Cauchy-Schwarz bound at every pose; constant: max - min <= "
            f"tol = atol + rtol x largest bound (atol = {self.atol:g}, rtol = {self.rtol:g}); (n%): largest "
            f"|value| / bound",
        ]
        rows: list[list[str]] = [["", *self.dofs]]
        for d in self.dofs:
            rows.append([f"M_x {d}", *(self._cell(self.inertia(d, e), d != e) for e in self.dofs)])
        rows.append(["g_x", *(self._cell(self.gravity(d), True) for d in self.dofs)])
        rows.append(["h_x", *(self._cell(self.velocity(d), True) for d in self.dofs)])
        widths = [max(len(r[c]) for r in rows) for c in range(len(rows[0]))]
        lines = ["  ".join(cell.ljust(w) for cell, w in zip(r, widths, strict=True)).rstrip() for r in rows]
        decoupled = self.decoupled()
        footer = f"decoupled with constant inertia: {', '.join(decoupled) if decoupled else 'none'}"
        return "\n".join([*header, "", *lines, "", footer])

    def velocity_text(self) -> str:
        """The velocities :math:`h_x` is evaluated at, in words, with their rate ``v`` stated."""
        v = float(np.abs(self.velocities).max())
        return f"v e_i and v (e_i + e_j), i < j, with v = {v:g} m/s or rad/s along each task coordinate"

    @staticmethod
    def _cell(entry: EntryBehaviour, with_ratio: bool) -> str:
        if entry.kind not in ("varies", "nonzero"):
            return entry.describe()
        return f"{entry.kind} {entry.describe()}" + (f" ({entry.ratio:.0%})" if with_ratio else "")

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON: per-entry behaviours, tolerances and the skipped poses."""
        return {
            **super().to_dict(),
            "M_x": [[self.inertia(d, e).to_dict() for e in self.dofs] for d in self.dofs],
            "g_x": [self.gravity(d).to_dict() for d in self.dofs],
            "h_x": [self.velocity(d).to_dict() for d in self.dofs],
            "decoupled": list(self.decoupled()),
        }


def _sample(
    mech: Mechanism, sample: WorkspaceSlice | ArrayLike, mode: tuple[int, ...] | None, n_task: int
) -> tuple[np.ndarray, list[np.ndarray | None]]:
    """Poses (k, n_task) and their configurations (None: unreachable in the working mode)."""
    if isinstance(sample, WorkspaceSlice):
        if sample.dofs != tuple(require_task(mech).dofs) or sample.q.shape[-1] != mech.nq:
            raise InvalidInput(
                f"the workspace slice (task {list(sample.dofs)}, nq = {sample.q.shape[-1]}) does not belong "
                f"to {mech.name}"
            )
        poses = sample.poses().reshape(-1, n_task)
        qs = sample.q.reshape(-1, mech.nq)
        return poses, [q if ok else None for q, ok in zip(qs, sample.reachable.ravel(), strict=True)]
    try:
        poses = np.asarray(sample, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidInput(f"poses must be numbers, shape (k, {n_task}): {exc}") from None
    if poses.ndim == 1 and poses.size == n_task:
        poses = poses[None, :]
    if poses.ndim != 2 or poses.shape[1] != n_task:
        raise InvalidInput(f"poses must have shape (k, {n_task}), got {poses.shape}")
    if poses.shape[0] == 0:
        raise InvalidInput("the sample is empty: give at least one pose")
    bad = np.flatnonzero(~np.all(np.isfinite(poses), axis=1))
    if bad.size:
        raise InvalidInput(f"poses hold non-finite entries in rows {bad.tolist()}")
    target = working_mode(mech, mech.q_ref) if mode is None else tuple(mode)
    return poses, [_solve(mech, x, target) for x in poses]


def _solve(mech: Mechanism, x: np.ndarray, mode: tuple[int, ...]) -> np.ndarray | None:
    """Configuration at ``x`` in working mode ``mode``, or None when it cannot be reached there.

    Newton from the reference configuration first (its basin is normally the reference
    working mode); all working modes are enumerated only when it lands elsewhere. A leg at
    an actuator singularity (mode sign 0) is on the border of every branch and is accepted.
    """
    try:
        sol = inverse_kinematics(mech, x)
        if any(s != t for s, t in zip(sol.mode, mode, strict=True) if s != 0):
            sol = inverse_kinematics(mech, x, mode=mode)
    except PoseUnreachable:
        return None
    return sol.q


def decoupling_check(
    mech: Mechanism,
    sample: WorkspaceSlice | ArrayLike,
    *,
    mode: tuple[int, ...] | None = None,
    rtol: float = DECOUPLING_RTOL,
    atol: float = 0.0,
    velocity_scale: float = 1.0,
    singular_tol: float = SINGULARITY_TOL,
) -> DecouplingReport:
    """Classify the entries of :math:`M_x`, :math:`g_x` and :math:`h_x` over a workspace sample.

    Args:
        mech: the mechanism (its task must have as many coordinates as it has DOF).
        sample: task poses [m, rad], shape (k, n_task) (or one pose), or a
            :class:`plm_pin.workspace.WorkspaceSlice` of this mechanism (its reachable points).
        mode: working mode the poses are solved in (default: the reference configuration's);
            a workspace slice keeps its own.
        rtol: cancellation ratio for ``zero`` and ``constant`` [-].
        atol: absolute tolerance added, in each entry's unit.
        velocity_scale: the rate :math:`v` of the task velocities :math:`h_x` is evaluated at
            (:func:`task_velocities`) [m/s or rad/s per task coordinate].
        singular_tol: inverse or constraint margin (:func:`plm_pin.kinematics.classify`) at or
            below which a pose is skipped as singular [-]; direct (type 2) singularities are
            kept, :math:`M_x` being defined there.

    Returns:
        The report; unreachable and singular poses are skipped and listed.

    Raises:
        InvalidInput: no task, a task size different from the DOF, an empty or malformed
            sample, a non-finite pose, or bad tolerances or velocity settings.
        PoseUnreachable: when no pose of the sample can be evaluated.
    """
    task = require_task(mech)
    n = task.size
    check_square_task(n, mech.mobility, "decoupling checks need", mech.name)
    rtol, atol = check_tolerance(rtol, "rtol"), check_tolerance(atol, "atol")
    velocity_scale = positive(velocity_scale, "velocity_scale", "m/s, rad/s")
    singular_tol = check_tolerance(singular_tol, "singular_tol")
    mode = check_mode(mech, mode)
    poses, configurations = _sample(mech, sample, mode, n)
    velocities = task_velocities(n, velocity_scale)
    kept: list[int] = []
    kept_q: list[np.ndarray] = []
    singular: list[int] = []
    terms: dict[str, list[np.ndarray]] = {k: [] for k in ("M", "M_bound", "g", "g_bound", "h", "h_bound")}
    for k, q in enumerate(configurations):
        if q is None:
            continue
        if {"inverse", "constraint"}.intersection(classify(mech, q, singular_tol).kinds):
            singular.append(k)
            continue
        dyn = [task_space_dynamics(mech, q, xdot=xdot, singularity_tol=singular_tol) for xdot in velocities]
        kept.append(k)
        kept_q.append(q)
        _collect(terms, dyn)
    unreachable = [k for k, q in enumerate(configurations) if q is None]
    if not kept:
        raise PoseUnreachable(
            f"{mech.name}: none of the {len(poses)} poses could be evaluated ({len(unreachable)} unreachable "
            f"in the working mode, {len(singular)} singular)"
        )
    stacked = {key: np.stack(values) for key, values in terms.items()}
    fields: dict[str, np.ndarray] = {}
    for key in ("M", "g", "h"):
        values, bounds = stacked[key], stacked[f"{key}_bound"]
        fields[f"{key}_min"] = values.min(axis=0)
        fields[f"{key}_max"] = values.max(axis=0)
        fields[f"{key}_tol"] = atol + rtol * bounds.max(axis=0)
        fields[f"{key}_zero"] = np.all(np.abs(values) <= atol + rtol * bounds, axis=0)
        ratio = np.divide(
            np.abs(values), bounds, out=np.where(values == 0.0, 0.0, np.inf), where=bounds > 0.0
        )
        fields[f"{key}_ratio"] = ratio.max(axis=0)
    return DecouplingReport(
        mechanism=mech.name,
        dofs=tuple(task.dofs),
        poses=poses[kept],
        configurations=np.stack(kept_q),
        unreachable=poses[unreachable].reshape(-1, n),
        singular=poses[singular].reshape(-1, n),
        **fields,
        rtol=float(rtol),
        atol=float(atol),
        velocities=velocities,
    )


def task_velocities(n: int, rate: float = 1.0) -> np.ndarray:
    """Task velocities that determine a quadratic form in n rates: ``rate e_i``, ``rate (e_i + e_j)``, i < j.

    Args:
        n: number of task coordinates.
        rate: the rate along each coordinate involved [m/s or rad/s].

    Returns:
        The velocities [m/s, rad/s], shape (n (n + 1) / 2, n).
    """
    eye = np.eye(n)
    pairs = [eye[i] + eye[j] for i in range(n) for j in range(i + 1, n)]
    return rate * np.vstack([eye, *pairs]) if pairs else rate * eye


def _collect(terms: dict[str, list[np.ndarray]], dyn: list[TaskSpaceDynamics]) -> None:
    """Append the task-space terms of one pose and their Cauchy-Schwarz bounds (module docstring)."""
    first = dyn[0]
    M_inv = np.linalg.pinv(first.M, hermitian=True)
    d = np.sqrt(np.diag(first.M_x))  # kinetic-energy norm of each task direction
    terms["M"].append(first.M_x)
    terms["M_bound"].append(np.outer(d, d))
    terms["g"].append(first.g_x)
    terms["g_bound"].append(d * np.sqrt(first.g @ M_inv @ first.g))
    # h's bound at each velocity, raised to the pose's largest: at a velocity that moves little
    # (e.g. a decoupled coordinate's own rate) the bound itself is round-off, and so is h_x there
    bounds = [d * np.sqrt(t.h @ M_inv @ t.h) for t in dyn]
    scale = np.max(bounds, axis=0)
    for t in dyn:
        terms["h"].append(t.h_x)
        terms["h_bound"].append(scale)
