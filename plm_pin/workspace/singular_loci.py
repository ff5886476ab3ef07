r"""Singular configurations located along paths and over slices of the workspace, by root finding.

Along a path :math:`x(t)` of task poses, the inverse kinematics is solved at samples by
continuation (the working mode of the first solved sample is kept, as in
:mod:`plm_pin.workspace.maps`), then each singularity is refined to ``xtol`` in
:math:`t`:

- **non-redundant** mechanisms (as many actuators as DOF): sign changes of

  .. math:: g = \det T \, \det C, \qquad T = J_x N, \quad C = S_a N,

  which vanishes at inverse (type 1) and direct (type 2) singularities, and does not
  depend on the null-space basis :math:`N` (a change of basis :math:`N Q`,
  :math:`Q` orthogonal, multiplies it by :math:`\det(Q)^2 = 1`); :math:`g` has the sign of
  :math:`\det J_{ce}`. Roots are refined by :func:`scipy.optimize.brentq`. A double root
  (tangency without a sign change) is not detected.
- **redundant** mechanisms: :math:`C` is tall, its rank drop is not a sign change, so
  the local minima of the direct, inverse and constraint margins below ``near`` are
  refined by bounded minimisation (:func:`scipy.optimize.minimize_scalar`); each result
  says whether its margin reaches zero (at most ``tol``).
- **boundaries**: where the samples leave the reachable set of the working mode, the
  boundary is located by bisection; a leg folds there (its two branches meet), which is
  an inverse singularity of that leg (Harada 2011 eq. (9), :math:`z_i^T a = 0`).

A 2-D slice is handled line by line (:func:`singular_loci`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import check_tolerance, flag, positive, real_numbers
from .._lazy import lazy_module
from ..core.mechanism import Mechanism, require_task
from ..exceptions import InvalidInput, PoseUnreachable
from ..kinematics.inverse import check_mode, inverse_kinematics
from ..kinematics.jacobians import check_square_task, closed_chain_jacobians, feasible_motions
from ..kinematics.singularity import SingularityReport, classify
from ..results import Result, unit
from ..tolerances import LOCUS_REFINE_MARGIN, LOCUS_XTOL, SINGULARITY_TOL
from ._continuation import IKEvaluator, base_pose, compatible, solve_poses
from .manipulability import MARGIN_METRICS

optimize = lazy_module("scipy.optimize")  # brentq, minimize_scalar: 0.1 s to import

METHODS: tuple[str, ...] = ("sign_change", "minimum", "boundary")


@dataclass(frozen=True)
class SingularPoint(Result):
    """A singular (or nearly singular) configuration found on a path.

    Attributes:
        parameter: path parameter of the point [unit of t: m or rad along a task coordinate].
        x: task pose [m, rad], shape (n_task,).
        q: configuration, shape (nq,).
        kind: ``"inverse"``, ``"direct"`` or ``"constraint"``: the kind whose margin is
            smallest at the point.
        method: ``"sign_change"`` (root of det T det C), ``"minimum"`` (minimised margin) or
            ``"boundary"`` (end of the reachable set of the working mode).
        reaches_zero: whether the margin of ``kind`` is at most ``report.tol`` (always
            True for sign changes).
        report: the singularity margins at ``q``.
        bracket: final bracket ``(t_lo, t_hi)`` holding the point [unit of t].
    """

    parameter: float = field(metadata=unit("m, rad"))
    x: np.ndarray = field(metadata=unit("m, rad"))
    q: np.ndarray = field(metadata=unit("m, rad"))
    kind: str
    method: str
    reaches_zero: bool
    report: SingularityReport
    bracket: tuple[float, float] = field(metadata=unit("m, rad"))

    @property
    def margin(self) -> float:
        """Margin of ``kind`` at the point [-]."""
        return float(getattr(self.report, f"{self.kind}_margin"))


def signed_singularity_function(mech: Mechanism, q: ArrayLike) -> float:
    r""":math:`\det(J_x N) \det(S_a N)`: zero at inverse and direct singularities, basis-independent.

    Needs as many actuators and task coordinates as DOF.

    Raises:
        InvalidInput: for a redundant mechanism or a task of another size.
    """
    jac = closed_chain_jacobians(mech, q)
    return float(_det_T_det_C(mech, jac.T, jac.C))


def _signed_functions(mech: Mechanism, A: np.ndarray) -> np.ndarray:
    """:func:`signed_singularity_function` from stacked ``[J_phi; J_x]`` (B, m + k, nv) at solutions."""
    m = mech.n_closure_rows
    _, _, T, C = feasible_motions(A[:, :m], A[:, m:], mech.actuated_v_indices, mech.mobility)
    return _det_T_det_C(mech, T, C)


def _det_T_det_C(mech: Mechanism, T: np.ndarray, C: np.ndarray) -> np.ndarray:
    """``det(T) det(C)`` (batched over leading axes), refused unless both are square."""
    if T.shape[-2] != T.shape[-1] or C.shape[-2] != C.shape[-1]:
        raise InvalidInput(
            f"{mech.name}: det(T) det(C) needs as many task coordinates and actuators as DOF "
            f"({mech.mobility}); T is {T.shape[-2:]}, C is {C.shape[-2:]}"
        )
    return np.asarray(np.linalg.det(T) * np.linalg.det(C))


class _PathSolver:
    """Inverse kinematics on a path, from the solved samples around the asked parameter."""

    def __init__(
        self,
        mech: Mechanism,
        path: Callable[[float], np.ndarray],
        target_mode: tuple[int, ...],
        tol: float,
    ) -> None:
        self.mech = mech
        self.ev = IKEvaluator.from_mechanism(mech)
        self.path = path
        self.target = target_mode
        self.tol = tol

    def solve(
        self,
        t: float,
        t_a: float,
        q_a: np.ndarray,
        t_b: float,
        q_b: np.ndarray | None,
        fallback: bool = True,
    ) -> np.ndarray | None:
        """Configuration at ``path(t)`` in the working mode, started between two solved samples.

        Newton from the interpolated configuration, then (``fallback``) the general solver.
        """
        model = self.mech.model
        x = self.path(t)
        if q_b is None or t_b == t_a:
            start = q_a
        else:
            s = (t - t_a) / (t_b - t_a)
            start = pin.integrate(model, q_a, s * pin.difference(model, q_a, q_b))
        found = self.ev.solve_point(x, start, self.tol)
        if found is None and fallback:
            try:
                general = inverse_kinematics(self.mech, x, start, tol=self.tol).q
            except PoseUnreachable:
                return None
            found = self.ev.solve_point(x, np.asarray(general), self.tol)
        if found is None or not compatible(found[2], self.target):
            return None
        return np.asarray(found[0])


def _point(
    mech: Mechanism,
    path: Callable[[float], np.ndarray],
    t: float,
    q: np.ndarray,
    method: str,
    bracket: tuple[float, float],
    tol: float,
    kind: str | None = None,
) -> SingularPoint:
    report = classify(mech, q, tol)
    margins = {
        "constraint": report.constraint_margin,
        "inverse": report.inverse_margin,
        "direct": report.direct_margin,
    }
    if kind is None:
        kind = min(margins, key=lambda k: margins[k])
    reaches = True if method == "sign_change" else margins[kind] <= tol
    return SingularPoint(
        float(t), np.asarray(path(t), dtype=float), np.asarray(q), kind, method, reaches, report, bracket
    )


def singular_points(
    mech: Mechanism,
    path: Callable[[float], ArrayLike],
    t: ArrayLike,
    *,
    guess: ArrayLike | None = None,
    mode: tuple[int, ...] | None = None,
    xtol: float = LOCUS_XTOL,
    tol: float = SINGULARITY_TOL,
    near: float = LOCUS_REFINE_MARGIN,
    boundaries: bool = True,
    ik_tol: float | None = None,
) -> list[SingularPoint]:
    """Singularities on the path ``x = path(t)``, located between the samples ``t``.

    Args:
        mech: the mechanism (its task must have as many coordinates as it has DOF).
        path: task pose [m, rad] as a function of the parameter.
        t: increasing samples of the parameter, shape (n,); a singularity between two
            samples is found, two in one interval may be missed.
        guess: configuration the first sample is solved from (default: reference).
        mode: working mode to keep (default: the first solved sample's).
        xtol: tolerance on the located parameter [unit of t].
        tol: margin at or below which a point counts as singular (``reaches_zero``).
        near: redundant mechanisms: local minima of a margin below ``near`` are refined.
        boundaries: also locate where the path leaves the reachable set of the working mode.
        ik_tol: inverse-kinematics residual tolerance [m, rad] (default: the mechanism's ``closure_tol``).

    Returns:
        The points, sorted by parameter.

    Raises:
        InvalidInput: malformed samples or a task whose size differs from the DOF.
    """
    task = require_task(mech)
    check_square_task(task.size, mech.mobility, "singularity location needs", mech.name)
    xtol, tol, near = positive(xtol, "xtol"), check_tolerance(tol, "tol"), check_tolerance(near, "near")
    flag(boundaries, "boundaries")
    mode = check_mode(mech, mode)
    ts = np.asarray(real_numbers(t, "t"), dtype=float)
    if ts.ndim != 1 or ts.size < 2 or not np.all(np.isfinite(ts)) or np.any(np.diff(ts) <= 0.0):
        raise InvalidInput(f"t must be an increasing 1-D array of at least 2 finite samples, got {t!r}")

    def pose(s: float) -> np.ndarray:
        x = np.asarray(path(s), dtype=float)
        if x.shape != (task.size,):
            raise InvalidInput(f"path({s}) must return {task.size} task coordinates, got shape {x.shape}")
        return x

    poses = np.stack([pose(float(s)) for s in ts])
    ik_tol = mech.closure_tol if ik_tol is None else positive(ik_tol, "ik_tol", "m, rad")
    state, target = solve_poses(mech, poses, guess, mode=mode, tol=ik_tol, workers=1, names=MARGIN_METRICS)
    if target is None:
        return []
    return locate_on_solved(
        mech, pose, ts, state.q, state.reached, state.metrics, target, xtol, tol, near, boundaries, ik_tol
    )


def locate_on_solved(
    mech: Mechanism,
    pose: Callable[[float], np.ndarray],
    ts: np.ndarray,
    Q: np.ndarray,
    reached: np.ndarray,
    metrics: Mapping[str, np.ndarray],
    target: tuple[int, ...],
    xtol: float,
    tol: float,
    near: float,
    boundaries: bool,
    ik_tol: float,
) -> list[SingularPoint]:
    """:func:`singular_points` on a path already solved at its samples (``Q``, ``reached``, margins).

    ``metrics`` holds the samples' ``direct_margin``, ``inverse_margin`` and
    ``constraint_margin`` (read for redundant mechanisms); ``target`` is the working mode kept.
    """
    solver = _PathSolver(mech, pose, target, ik_tol)
    out: list[SingularPoint] = []
    redundant = mech.n_actuators != mech.mobility
    if not redundant:
        g = np.full(ts.size, np.nan)
        solved = np.flatnonzero(reached)
        if solved.size:  # from the samples' Jacobians at once
            X = np.stack([pose(float(t)) for t in ts[solved]])
            g[solved] = _signed_functions(mech, solver.ev.ik_jacobians(Q[solved], X))
        for i in range(ts.size - 1):
            if not (reached[i] and reached[i + 1]):
                continue
            if g[i] == 0.0:
                out.append(_point(mech, pose, ts[i], Q[i], "sign_change", (ts[i], ts[i]), tol))
                continue
            if np.sign(g[i]) * np.sign(g[i + 1]) >= 0.0:
                continue
            point = _refine_root(mech, solver, pose, ts[i], Q[i], ts[i + 1], Q[i + 1], xtol, tol)
            if point is not None:
                out.append(point)
        if reached[-1] and g[-1] == 0.0:
            out.append(_point(mech, pose, ts[-1], Q[-1], "sign_change", (ts[-1], ts[-1]), tol))
    else:
        margins = {
            "direct": metrics["direct_margin"],
            "inverse": metrics["inverse_margin"],
            "constraint": metrics["constraint_margin"],
        }
        for kind, values in margins.items():
            for i in range(1, ts.size - 1):
                if not (reached[i - 1] and reached[i] and reached[i + 1]):
                    continue
                if not (values[i] <= values[i - 1] and values[i] <= values[i + 1] and values[i] < near):
                    continue
                point = _refine_minimum(mech, solver, pose, kind, ts, Q, i, xtol, tol)
                if point is not None:
                    out.append(point)
    if boundaries:
        for i in range(ts.size - 1):
            if reached[i] != reached[i + 1]:
                inside = i if reached[i] else i + 1
                outside = i + 1 if reached[i] else i
                point = _refine_boundary(mech, solver, pose, ts[inside], Q[inside], ts[outside], xtol, tol)
                if point is not None:
                    out.append(point)
    out.sort(key=lambda p: p.parameter)
    return out


def _refine_root(
    mech: Mechanism,
    solver: _PathSolver,
    pose: Callable[[float], np.ndarray],
    t_a: float,
    q_a: np.ndarray,
    t_b: float,
    q_b: np.ndarray,
    xtol: float,
    tol: float,
) -> SingularPoint | None:
    """Root of det T det C between two solved samples of opposite signs, by Brent's method.

    The ends are solved again first. When a sample lies on the singularity, its function is
    round-off, whose sign the new solve may turn: the ends then share a sign, and the end
    nearer to zero is the root.
    """
    cache: dict[float, np.ndarray] = {}

    def g(s: float) -> float:
        q = solver.solve(s, t_a, q_a, t_b, q_b)
        if q is None:
            raise _Unreached(s)
        cache[s] = q
        return signed_singularity_function(mech, q)

    try:
        g_a, g_b = g(t_a), g(t_b)
        if g_a * g_b >= 0.0:
            end = t_a if abs(g_a) <= abs(g_b) else t_b
            return _point(mech, pose, end, cache[end], "sign_change", (end, end), tol)
        root, result = optimize.brentq(g, t_a, t_b, xtol=xtol, full_output=True, disp=False)
    except _Unreached:
        return None
    if not result.converged:
        return None
    q = cache.get(root)
    if q is None:
        q = solver.solve(root, t_a, q_a, t_b, q_b)
        if q is None:
            return None
    return _point(mech, pose, root, q, "sign_change", (t_a, t_b), tol)


class _Unreached(Exception):
    """The inverse kinematics failed inside a bracket."""


def _margin_of(mech: Mechanism, q: np.ndarray, kind: str) -> float:
    report = classify(mech, q)
    return float(getattr(report, f"{kind}_margin"))


def _refine_minimum(
    mech: Mechanism,
    solver: _PathSolver,
    pose: Callable[[float], np.ndarray],
    kind: str,
    ts: np.ndarray,
    Q: np.ndarray,
    i: int,
    xtol: float,
    tol: float,
) -> SingularPoint | None:
    """Minimum of one margin between the samples around sample ``i``, by bounded Brent minimisation."""
    cache: dict[float, np.ndarray] = {}

    def f(s: float) -> float:
        j = i - 1 if s < ts[i] else i
        q = solver.solve(s, ts[j], Q[j], ts[j + 1], Q[j + 1])
        if q is None:
            return np.inf
        cache[s] = q
        return _margin_of(mech, q, kind)

    result = optimize.minimize_scalar(
        f, bounds=(ts[i - 1], ts[i + 1]), method="bounded", options={"xatol": xtol, "maxiter": 500}
    )
    s = float(result.x)
    q = cache.get(s)
    if q is None or not np.isfinite(result.fun):
        return None
    return _point(mech, pose, s, q, "minimum", (float(ts[i - 1]), float(ts[i + 1])), tol, kind)


def _refine_boundary(
    mech: Mechanism,
    solver: _PathSolver,
    pose: Callable[[float], np.ndarray],
    t_in: float,
    q_in: np.ndarray,
    t_out: float,
    xtol: float,
    tol: float,
) -> SingularPoint | None:
    """Last reachable parameter between a reachable and an unreachable sample, by bisection."""
    lo, hi = t_in, t_out
    q_lo = q_in
    while abs(hi - lo) > xtol:
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        q = solver.solve(mid, lo, q_lo, lo, None, fallback=False)
        if q is None:
            hi = mid
        else:
            lo, q_lo = mid, q
    bracket = (min(lo, hi), max(lo, hi))
    return _point(mech, pose, lo, q_lo, "boundary", bracket, tol)


def singular_points_along(
    mech: Mechanism,
    axis: str,
    values: ArrayLike,
    pose: ArrayLike | None = None,
    **options: Any,
) -> list[SingularPoint]:
    """Singularities along one task coordinate, the others fixed (a 1-D slice).

    Args:
        mech: the mechanism.
        axis: the varied task coordinate, e.g. ``"rz"``.
        values: increasing samples of it [m or rad].
        pose: task pose giving the fixed coordinates (default: the guess's or reference pose).
        **options: passed to :func:`singular_points` (``guess``, ``mode``, ``xtol``, ``tol``, ...).

    Returns:
        The points; ``parameter`` is the value of ``axis`` [m or rad].
    """
    return singular_points(mech, line_path(mech, axis, pose, options.get("guess")), values, **options)


def line_path(
    mech: Mechanism, axis: str, pose: ArrayLike | None, guess: ArrayLike | None
) -> Callable[[float], np.ndarray]:
    """The path ``s -> pose with axis = s`` of a 1-D slice (``pose`` default: the guess's).

    Raises:
        InvalidInput: an unknown axis or a malformed pose.
    """
    task = require_task(mech)
    if axis not in task.dofs:
        raise InvalidInput(f"unknown task coordinate {axis!r}; the task's coordinates are {list(task.dofs)}")
    base = base_pose(mech, pose, guess)
    k = task.dofs.index(axis)

    def path(s: float) -> np.ndarray:
        x = base.copy()
        x[k] = s
        return x

    return path


def singular_loci(
    mech: Mechanism,
    axis: str,
    values: ArrayLike,
    across: str,
    across_values: Sequence[float],
    pose: ArrayLike | None = None,
    **options: Any,
) -> list[SingularPoint]:
    r"""Singular curves over a 2-D slice, found line by line along ``axis``.

    For each value of the task coordinate ``across``, the singularities along ``axis``
    (:func:`singular_points_along`); together they sample the singular curves, e.g. the
    loci :math:`\theta(y)` of Harada 2011 eq. (11) with ``axis="rz"``, ``across="y"``.

    Args:
        mech: the mechanism.
        axis: the coordinate searched along [m or rad].
        values: increasing samples of ``axis``.
        across: the coordinate stepped between lines.
        across_values: its values [m or rad].
        pose: task pose giving the other coordinates (default: the reference pose).
        **options: passed to :func:`singular_points`.

    Returns:
        Every point found, ordered by line then parameter; ``x`` holds both coordinates.
    """
    task = require_task(mech)
    if across not in task.dofs or across == axis:
        raise InvalidInput(
            f"across must be another task coordinate than {axis!r} among {list(task.dofs)}, got {across!r}"
        )
    base = base_pose(mech, pose, options.get("guess"))
    k = task.dofs.index(across)
    out: list[SingularPoint] = []
    for v in across_values:
        line = np.array(base, dtype=float)
        line[k] = float(v)
        out.extend(singular_points_along(mech, axis, values, line, **options))
    return out
