r"""The live inspector's state: a pose of a mechanism, what moved it last, and everything read there.

:func:`inspect_state` makes the first state and :func:`inspect_update` the next one from a
change (no I/O: the browser panel, the Jupyter panel and the tests call the same function):

- ``{"task": {"x": 0.01, ...}}``: move the task frame (closed-loop inverse kinematics
  from the current configuration, in small steps, keeping the working mode);
- ``{"actuators": {"slider1": 0.2, ...}}``: move actuators (the loops closed with the
  actuators fixed, in small steps from the current configuration, keeping the assembly
  mode); a redundantly actuated mechanism fixes as many actuators as it has DOF (the moved
  ones first, then the others in order) and lets the rest follow;
- ``{"working_mode": [1, -1, ...]}``: the same pose in another working mode;
- ``{"find_modes": True}``: every working mode at the pose
  (:func:`~plm_pin.kinematics.working_modes`) and every assembly mode at the actuator
  positions (:func:`~plm_pin.kinematics.forward_kinematics` with ``all_modes``);
- ``{"assembly_mode": i}``: the ``i``-th assembly mode found;
- ``{"load": [...]}``: the wrench on the task frame, one value per task coordinate [N, N m];
- ``{"limits": [[lower, upper], ...]}``: the actuators' effort limits, one pair per actuator
  [N, N m] (``None`` in a pair: no limit on that side; ``None`` for all: the description's);
- ``{"preload": [...]}``: the internal forces of a redundantly actuated mechanism, in the
  internal basis [N, N m] (``None``: the minimum-norm forces).

The assembly modes found are kept: after a move they are followed to the new actuator
positions (each closed with the actuators fixed, in the steps of the move), so that the
selector still lists them; a mode that cannot be followed is dropped.

A move that would leave the workspace (no assembly, a joint limit), cross a singularity
(a sign change of :math:`\det T` or :math:`\det C` along the move, or of the working mode)
or reach one (a margin at :data:`~plm_pin.tolerances.SINGULARITY_TOL`) stops at its edge,
found by bisection along the move to :data:`~plm_pin.tolerances.INSPECT_EDGE_TOL`, and
:attr:`InspectState.stopped` says why. An actuator move passes inverse singularities (the
working mode then changes); a task move stops at every kind.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import signs
from ..core.mechanism import Mechanism, require_task
from ..exceptions import ClosureNotSatisfied, InvalidInput, PlmError, PoseUnreachable
from ..kinematics.forward import forward_kinematics, same_assembly, task_pose
from ..kinematics.inverse import check_mode, inverse_kinematics, working_modes
from ..kinematics.jacobians import ClosedChainJacobians, check_square_task, closed_chain_jacobians
from ..kinematics.limits import limit_violations
from ..kinematics.singularity import KINDS, report_from_jacobians
from ..kinematics.working_mode import working_mode
from ..results import Result, unit
from ..statics import actuator_limits, internal_force_range, static_forces
from ..stiffness import stiffness
from ..tolerances import INSPECT_EDGE_TOL, SAME_ASSEMBLY_TOL, SINGULARITY_TOL
from ..workspace.manipulability import manipulability_from_jacobians

CHANGES = ("task", "actuators", "working_mode", "find_modes", "assembly_mode", "load", "limits", "preload")
"""The keys a change may hold, applied in this order."""

MOVE_STEP = 0.05
"""Largest step of a move along a translation or a prismatic actuator, in mechanism sizes [-]."""

TURN_STEP = 0.05
"""Largest step of a move along a rotation or a revolute actuator [rad]."""

BISECTIONS = 60
"""Most halvings of a failed step: enough to reach a singularity's margin band in double precision."""

AXES = {"x": 0, "y": 1, "z": 2}
"""World axis of each translational task coordinate (task rows are world-aligned)."""


@dataclass(frozen=True)
class InspectState(Result):
    r"""One pose of the live inspector and its readouts.

    Attributes:
        mech: the mechanism.
        source: how it was loaded (a preset name or a path), for the "copy pose" texts.
        q: assembled configuration, shape (nq,).
        x: task coordinates [m, rad], shape (n_task,).
        actuators: actuator positions [m, rad], shape (n_act,).
        working_mode: one sign per square leg (0: that leg at an inverse singularity).
        working_modes: the working modes found at the last search (:func:`inspect_state` or
            ``find_modes``).
        assembly_modes: configurations of the assembly modes found at the last ``find_modes``,
            followed to the current actuator positions since, shape (k, nq) (empty before).
        assembly_index: which of them is displayed (None: none found, or the configuration
            shown is not among them).
        load: wrench on the task frame, one value per task coordinate [N, N m].
        preload: internal-force coordinates asked for, or None for the minimum-norm forces [N, N m].
        stopped: why the last change was not applied in full ('' when it was).
        closure_residual: largest absolute closure residual [m, rad].
        margins: singularity margin of each kind (``constraint``, ``inverse``, ``direct``) [-].
        singular: the kinds whose margin is at or below :data:`SINGULARITY_TOL`.
        manipulability: Yoshikawa :math:`w` of :math:`J_{ce}` (inf at an inverse singularity).
        condition_number: :math:`\kappa(J_{ce})` [-] (inf at a singularity).
        ellipse_radii: semi-axes of the translational velocity ellipse (ellipsoid): task-frame
            speeds reached with unit actuator speed, the rotation held [m/s per unit actuator
            rate], descending; empty at an inverse singularity or without a translation.
        ellipse_axes: their world directions, one per row, shape (k, 3).
        forces: actuator forces holding gravity and the load [N, N m] (NaN when not held).
        force_limits: each actuator's effort limits (lower, upper), infinite where none, shape
            (n_act, 2): the description's, or those of the last ``limits`` change.
        internal_range: admissible range of each internal force under these limits
            (:func:`~plm_pin.statics.internal_force_range`), shape (k, 2) [N, N m]; empty
            without redundancy or finite limits.
        stiffness: smallest translational eigen-stiffness [N/m] (NaN without a compliance section).
        stiffness_axis: its world direction, shape (3,) (zeros without).
        notes: why a readout is missing (statics not held, no limits, ...).
    """

    mech: Mechanism = field(repr=False, compare=False)
    source: str
    q: np.ndarray = field(metadata=unit("m, rad"))
    x: np.ndarray = field(metadata=unit("m, rad"))
    actuators: np.ndarray = field(metadata=unit("m, rad"))
    working_mode: tuple[int, ...]
    working_modes: tuple[tuple[int, ...], ...]
    assembly_modes: np.ndarray = field(metadata=unit("m, rad"))
    assembly_index: int | None
    load: np.ndarray = field(metadata=unit("N, N m"))
    preload: np.ndarray | None = field(metadata=unit("N, N m"))
    stopped: str
    closure_residual: float = field(metadata=unit("m, rad"))
    margins: Mapping[str, float] = field(metadata=unit("-"))
    singular: tuple[str, ...]
    manipulability: float
    condition_number: float = field(metadata=unit("-"))
    ellipse_radii: np.ndarray
    ellipse_axes: np.ndarray = field(metadata=unit("-"))
    forces: np.ndarray = field(metadata=unit("N, N m"))
    force_limits: np.ndarray = field(metadata=unit("N, N m"))
    internal_range: np.ndarray = field(metadata=unit("N, N m"))
    stiffness: float = field(metadata=unit("N/m"))
    stiffness_axis: np.ndarray = field(metadata=unit("-"))
    notes: tuple[str, ...]
    _SKIPPED = ("mech",)
    _DERIVED = ("dofs", "actuator_names", "python_snippet", "cli_line")
    _NONFINITE_AS_TEXT = ("manipulability", "condition_number", "forces", "force_limits", "stiffness")

    @property
    def dofs(self) -> tuple[str, ...]:
        """The task coordinates' names."""
        return tuple(require_task(self.mech).dofs)

    @property
    def actuator_names(self) -> tuple[str, ...]:
        """The actuated joints' names."""
        return tuple(a.joint for a in self.mech.actuators)

    @property
    def python_snippet(self) -> str:
        """Python that rebuilds this configuration ("copy pose")."""
        x = ", ".join(f"{v:.9g}" for v in self.x)
        mode = "" if 0 in self.working_mode or not self.working_mode else f", mode={tuple(self.working_mode)}"
        q = ", ".join(f"{v:.9g}" for v in self.q)
        return (
            "import numpy as np\nimport plm_pin\nfrom plm_pin.kinematics import inverse_kinematics\n\n"
            f"mech = plm_pin.load({self.source!r})\n"
            f"sol = inverse_kinematics(mech, [{x}]{mode})\n"
            f"q = np.array([{q}])  # the configuration shown\n"
        )

    @property
    def cli_line(self) -> str:
        """The ``plm-pin ik`` command that solves this pose ("copy pose")."""
        words = " ".join(f"{d}={v:.9g}" for d, v in zip(self.dofs, self.x, strict=True))
        mode = ",".join({1: "+", -1: "-"}.get(m, "0") for m in self.working_mode)
        flag = f" --mode={mode}" if mode and "0" not in mode else ""
        return f"plm-pin ik {self.source} {words}{flag}"


def inspect_state(mech: Mechanism, q: ArrayLike | None = None, *, source: str | None = None) -> InspectState:
    """The inspector's first state: ``mech`` at ``q`` (default: its reference configuration).

    Args:
        mech: the mechanism; its task needs as many coordinates as it has DOF.
        q: an assembled configuration, shape (nq,).
        source: the name or path ``mech`` was loaded from (default: its name).

    Raises:
        InvalidInput: no task, a task of another size than the DOF, a malformed ``q``.
        ClosureNotSatisfied: ``q`` is not assembled.
    """
    task = require_task(mech)
    check_square_task(task.size, mech.mobility, "the inspector needs", mech.name)
    qa = np.array(mech.q_ref if q is None else mech.check_q(q))
    x = task_pose(mech, qa)
    source = mech.name if source is None else str(source)
    modes = tuple(s.mode for s in working_modes(mech, x, guess=qa))
    given = _Given(
        source,
        modes,
        np.zeros((0, mech.nq)),
        None,
        np.zeros(task.size),
        actuator_limits(mech, "description"),
        None,
        "",
    )
    return _readouts(mech, qa, given)


def inspect_update(state: InspectState, change: Mapping[str, object]) -> InspectState:
    """The state after ``change`` (see the module docstring for its keys); ``state`` is unchanged.

    Raises:
        InvalidInput: an unknown key, an unknown task coordinate or actuator, malformed values,
            a working mode of the wrong size, an assembly mode not found, malformed limits, a
            preload on a mechanism without internal forces.
    """
    if not isinstance(change, Mapping):
        raise InvalidInput(f"change must be a mapping with keys among {list(CHANGES)}, got {change!r}")
    unknown = [k for k in change if k not in CHANGES]
    if unknown:
        raise InvalidInput(f"change keys {unknown} are unknown; valid keys are {list(CHANGES)}")
    mech = state.mech
    modes, found, index = state.working_modes, state.assembly_modes, state.assembly_index
    load, limits, preload = state.load, state.force_limits, state.preload
    q, stopped = state.q, ""
    if "task" in change:
        q, stopped = _move_task(state, change["task"])
    if "actuators" in change:
        q, stopped = _move_actuators(state, change["actuators"])
    if "working_mode" in change:
        q, stopped = _switch_working_mode(mech, q, change["working_mode"])
    if q is not state.q and len(found):
        found, index = _retrack(mech, found, state.actuators, q)
    if change.get("find_modes"):
        modes = tuple(s.mode for s in working_modes(mech, task_pose(mech, q), guess=q))
        fk = forward_kinematics(mech, mech.actuator_positions(q), q, all_modes=True)
        found = np.array([s.q for s in fk]).reshape(len(fk), mech.nq)
        index = next((i for i, s in enumerate(fk) if same_assembly(mech, s.q, q)), None)
    if "assembly_mode" in change:
        asked = change["assembly_mode"]
        if not isinstance(asked, int) or isinstance(asked, bool) or not 0 <= asked < len(found):
            raise InvalidInput(
                f"assembly_mode must be the index of a mode found (0..{len(found) - 1}; find them first "
                f"with find_modes), got {asked!r}"
            )
        q, index = found[asked], asked
    if "load" in change:
        load = _vector(change["load"], state.load.size, "load", "N, N m")
    if "limits" in change:
        limits = _limits(mech, change["limits"])
    if "preload" in change:
        preload = _preload(mech, change["preload"])
    given = _Given(state.source, modes, found, index, load, limits, preload, stopped)
    return _readouts(mech, np.array(q), given)


# ----------------------------------------------------------------------------- moves
def _vector(value: object, size: int, name: str, units: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.full(0, np.nan)
    if arr.shape != (size,) or not np.all(np.isfinite(arr)):
        raise InvalidInput(f"{name} must be {size} finite numbers [{units}], got {value!r}")
    return arr


def _named_values(value: object, names: tuple[str, ...], what: str) -> dict[str, float]:
    """``{name: value}`` with every name among ``names`` and finite values."""
    if not isinstance(value, Mapping) or not value:
        raise InvalidInput(f"{what} must map names among {list(names)} to numbers, got {value!r}")
    out = {}
    for key, v in value.items():
        if key not in names:
            raise InvalidInput(f"{what}: {key!r} is not one of {list(names)}")
        try:
            out[key] = float(v)
        except (TypeError, ValueError):
            out[key] = math.nan
        if not math.isfinite(out[key]):
            raise InvalidInput(f"{what}[{key!r}] must be a finite number, got {v!r}")
    return out


def _limits(mech: Mechanism, value: object) -> np.ndarray:
    """Effort limits (n_act, 2) from one ``[lower, upper]`` pair per actuator, ``None`` for no limit."""
    if value is None:
        return actuator_limits(mech, "description")
    n = mech.n_actuators
    pairs = value if isinstance(value, list | tuple) else []
    if len(pairs) != n or not all(isinstance(p, list | tuple) and len(p) == 2 for p in pairs):
        raise InvalidInput(
            f"limits must hold one [lower, upper] pair per actuator ({n}) [N, N m], None for no limit "
            f"(or None for the description's), got {value!r}"
        )
    try:
        arr = np.array(
            [[-math.inf if a is None else a, math.inf if b is None else b] for a, b in pairs], float
        )
    except (TypeError, ValueError):
        raise InvalidInput(f"limits must be numbers or None [N, N m], got {value!r}") from None
    return actuator_limits(mech, arr)


def _preload(mech: Mechanism, value: object) -> np.ndarray | None:
    if value is None:
        return None
    if mech.redundancy <= 0:
        raise InvalidInput(f"{mech.name} is not redundantly actuated: it has no internal force to preload")
    return _vector(value, mech.redundancy, "preload", "N, N m")


def _size(mech: Mechanism, q: np.ndarray) -> float:
    """Largest side of the box around the frame origins at ``q`` [m] (the scale of a move's steps)."""
    data = mech.model.createData()
    pin.framesForwardKinematics(mech.model, data, q)
    points = np.array([M.translation for M in data.oMf])
    return max(float(np.max(np.ptp(points, axis=0))), MOVE_STEP)


def _steps(delta: np.ndarray, rotational: np.ndarray, size: float) -> int:
    """Number of equal steps that keep each one within :data:`MOVE_STEP` sizes and :data:`TURN_STEP`."""
    scale = np.where(rotational, TURN_STEP, MOVE_STEP * size)
    return max(1, math.ceil(float(np.max(np.abs(delta) / scale, initial=0.0))))


@dataclass(frozen=True)
class _Probe:
    """A configuration reached along a move, with what the next one is compared to."""

    q: np.ndarray
    jac: ClosedChainJacobians
    mode: tuple[int, ...]


def _probe(mech: Mechanism, q: np.ndarray) -> _Probe:
    return _Probe(q, closed_chain_jacobians(mech, q), working_mode(mech, q))


def _orientation(jac: ClosedChainJacobians, basis: np.ndarray) -> tuple[float, float]:
    r"""Signs of :math:`\det T` and :math:`\det C` with the feasible-motion basis oriented as ``basis``.

    ``N`` is defined up to an orthogonal factor: multiplying by the sign of
    :math:`\det(\text{basis}^T N)` makes the signs comparable along a move (0 when ``C`` is not square).
    """
    turn = float(np.sign(np.linalg.det(basis.T @ jac.N)))
    det_c = float(np.sign(np.linalg.det(jac.C))) if jac.C.shape[0] == jac.C.shape[1] else 0.0
    return turn * float(np.sign(np.linalg.det(jac.T))), turn * det_c


def _track(
    mech: Mechanism,
    start: np.ndarray,
    n: int,
    solve: Callable[[float, np.ndarray], np.ndarray],
    stop_kinds: tuple[str, ...],
    keep_mode: bool,
) -> tuple[np.ndarray, str]:
    """Follow ``solve(s, guess)`` for s from 0 to 1 in ``n`` steps; stop at the first edge found.

    ``solve`` raises :class:`~plm_pin.exceptions.PlmError` (with the reason) where there is
    no configuration. The step that fails is bisected to :data:`INSPECT_EDGE_TOL` of the
    move; a singularity crossed is bisected further, until a configuration on it (its margin
    at :data:`SINGULARITY_TOL`) is found, and the move stops there, so that the scene shows
    it singular. Returns the configuration reached and why it stopped ('' at s = 1).
    """
    good, s_good = _probe(mech, start), 0.0
    for k in range(1, n + 1):
        s = k / n
        probe, why = _attempt(mech, s, good, solve, stop_kinds, keep_mode)
        if not why:
            assert probe is not None
            good, s_good = probe, s
            continue
        lo, hi, on = s_good, s, probe  # on: a configuration at the singularity, once found
        for _ in range(BISECTIONS):
            if hi - lo <= INSPECT_EDGE_TOL and (on is not None or not why.startswith("would cross")):
                break
            mid = 0.5 * (lo + hi)
            middle, middle_why = _attempt(mech, mid, good, solve, stop_kinds, keep_mode)
            if middle_why:
                hi, why = mid, middle_why
                on = middle if middle is not None else on
            else:
                assert middle is not None
                lo, good = mid, middle
        return (on.q, why) if on is not None and why.startswith("reaches") else (good.q, why)
    return good.q, ""


def _attempt(
    mech: Mechanism,
    s: float,
    good: _Probe,
    solve: Callable[[float, np.ndarray], np.ndarray],
    stop_kinds: tuple[str, ...],
    keep_mode: bool,
) -> tuple[_Probe | None, str]:
    """The configuration at ``s`` from ``good``, or why the move may not go there.

    A configuration at a singularity comes with its reason; none comes with the others.
    """
    try:
        q = solve(s, good.q)
    except PlmError as exc:
        return None, f"leaves the workspace: {exc}"
    outside = limit_violations(mech, q)
    if outside:
        return None, "leaves the joint limits: " + ", ".join(f"{k} by {v:.3g}" for k, v in outside.items())
    probe = _probe(mech, q)
    report = report_from_jacobians(mech, probe.jac, SINGULARITY_TOL)
    reached = [k for k in report.kinds if k in stop_kinds]
    if reached:
        return probe, f"reaches a {reached[0]} singularity"
    before, after = _orientation(good.jac, good.jac.N), _orientation(probe.jac, good.jac.N)
    for kind, b, a in zip(("inverse", "direct"), before, after, strict=True):
        if kind in stop_kinds and b * a < 0.0:
            return None, f"would cross a{'n' if kind == 'inverse' else ''} {kind} singularity"
    if keep_mode and probe.mode != good.mode:
        return None, "would cross an inverse singularity (the working mode would change)"
    return probe, ""


def _move_task(state: InspectState, value: object) -> tuple[np.ndarray, str]:
    mech = state.mech
    goal = state.x.copy()
    for dof, v in _named_values(value, state.dofs, "task").items():
        goal[state.dofs.index(dof)] = v
    delta = goal - state.x
    rotational = np.array([d.startswith("r") for d in state.dofs])

    def solve(s: float, guess: np.ndarray) -> np.ndarray:
        x = state.x + s * delta
        try:
            return inverse_kinematics(mech, x, guess, explain=False).q
        except PoseUnreachable:
            where = ", ".join(f"{d} = {v:.6g}" for d, v in zip(state.dofs, x, strict=True))
            raise PoseUnreachable(f"no assembly places the task frame at {where}") from None

    n = _steps(delta, rotational, _size(mech, state.q))
    return _track(mech, state.q, n, solve, KINDS, keep_mode=True)


def _move_actuators(state: InspectState, value: object) -> tuple[np.ndarray, str]:
    mech = state.mech
    names = state.actuator_names
    moved = _named_values(value, names, "actuators")
    if len(moved) > mech.mobility:
        raise InvalidInput(
            f"{mech.name} has {mech.mobility} DOF: move at most {mech.mobility} actuators at once, "
            f"got {list(moved)}"
        )
    held = list(moved) + [n for n in names if n not in moved]
    fixed = held[: mech.mobility]
    start = {n: float(v) for n, v in zip(names, state.actuators, strict=True)}
    goal = {n: moved.get(n, start[n]) for n in fixed}
    delta = np.array([goal[n] - start[n] for n in fixed])
    rotational = np.array([mech.actuators[names.index(n)].kind != "prismatic" for n in fixed])

    def solve(s: float, guess: np.ndarray) -> np.ndarray:
        targets = {n: start[n] + s * (goal[n] - start[n]) for n in fixed}
        try:
            return mech.assemble(guess, fixed=targets).q
        except ClosureNotSatisfied:
            raise PoseUnreachable(
                "the loops do not close with " + ", ".join(f"{n} = {v:.6g}" for n, v in targets.items())
            ) from None

    n = _steps(delta, rotational, _size(mech, state.q))
    return _track(mech, state.q, n, solve, ("constraint", "direct"), keep_mode=False)


def _retrack(
    mech: Mechanism, found: np.ndarray, start: np.ndarray, q: np.ndarray
) -> tuple[np.ndarray, int | None]:
    """The assembly modes ``found`` at actuator positions ``start``, followed to those of ``q``.

    Each mode is closed with the first DOF-many actuators fixed, in the steps a move between
    the two positions takes; a mode whose loops do not close, whose other actuators end
    elsewhere than ``q``'s, or that falls onto another mode is dropped. Returns the modes
    and the index of ``q``'s among them (None when it is not one of them).
    """
    names = tuple(a.joint for a in mech.actuators)
    goal = mech.actuator_positions(q)
    fixed = names[: mech.mobility]
    rotational = np.array([a.kind != "prismatic" for a in mech.actuators])
    n = _steps(goal - start, rotational, _size(mech, q))
    kept: list[np.ndarray] = []
    for mode in found:
        current = mode
        try:
            for k in range(1, n + 1):
                at = start + k / n * (goal - start)
                current = mech.assemble(current, fixed=dict(zip(fixed, at, strict=False))).q
        except ClosureNotSatisfied:
            continue
        elsewhere = np.max(np.abs(mech.actuator_positions(current) - goal)) > SAME_ASSEMBLY_TOL
        if not elsewhere and not any(same_assembly(mech, current, other) for other in kept):
            kept.append(np.array(current))
    index = next((i for i, other in enumerate(kept) if same_assembly(mech, other, q)), None)
    return np.array(kept).reshape(len(kept), mech.nq), index


def _switch_working_mode(mech: Mechanism, q: np.ndarray, value: object) -> tuple[np.ndarray, str]:
    mode = check_mode(mech, signs(value, "working_mode"))
    if mode is None:
        raise InvalidInput("working_mode must hold one sign (+1 or -1) per leg, got None")
    x = task_pose(mech, q)
    try:
        return inverse_kinematics(mech, x, q, mode=mode).q, ""
    except PoseUnreachable as exc:
        return q, f"working mode {mode} not reached: {exc}"


# -------------------------------------------------------------------------- readouts
class _Given(NamedTuple):
    """The fields of a state that are chosen, not computed."""

    source: str
    working_modes: tuple[tuple[int, ...], ...]
    assembly_modes: np.ndarray
    assembly_index: int | None
    load: np.ndarray
    force_limits: np.ndarray
    preload: np.ndarray | None
    stopped: str


def _readouts(mech: Mechanism, q: np.ndarray, given: _Given) -> InspectState:
    """The state at ``q`` with every readout computed."""
    q.setflags(write=False)
    task = require_task(mech)
    jac = closed_chain_jacobians(mech, q)
    report = report_from_jacobians(mech, jac, SINGULARITY_TOL)
    margins = dict(
        zip(KINDS, (report.constraint_margin, report.inverse_margin, report.direct_margin), strict=True)
    )
    manip = manipulability_from_jacobians(jac, SINGULARITY_TOL)
    notes: list[str] = []
    radii, axes = _ellipse(task.dofs, manip.J_ce)
    load, preload, limits = given.load, given.preload, given.force_limits
    forces = np.full(mech.n_actuators, np.nan)
    internal = np.zeros((0, 2))
    try:
        forces = static_forces(mech, q, load, limits=None, internal=preload).f_c
    except PlmError as exc:
        notes.append(f"statics: {exc}")
    if mech.redundancy > 0 and np.all(np.isfinite(forces)):
        if np.isfinite(limits).all():
            try:
                r = internal_force_range(mech, q, load, limits=limits)
                internal = np.column_stack([r.lower, r.upper])
            except PlmError as exc:
                notes.append(f"internal-force range: {exc}")
        else:
            notes.append("internal-force range: give every actuator finite effort limits")
    k_min, k_axis = math.nan, np.zeros(3)
    if mech.sidecar.compliance is not None:
        try:
            eig = stiffness(mech, q, load, internal=preload).translational
            if eig.values.size:
                k_min = float(eig.values[0])
                for dof, c in zip(eig.dofs, eig.directions[:, 0], strict=True):
                    k_axis[AXES[dof]] = c
        except PlmError as exc:
            notes.append(f"stiffness: {exc}")
    errors = mech.closure_errors(q)
    return InspectState(
        mech=mech,
        q=q,
        x=task_pose(mech, q),
        actuators=mech.actuator_positions(q),
        working_mode=working_mode(mech, q),
        closure_residual=max(errors.values(), default=0.0),
        margins=margins,
        singular=report.kinds,
        manipulability=float(manip.w),
        condition_number=float(manip.condition_number),
        ellipse_radii=radii,
        ellipse_axes=axes,
        forces=forces,
        internal_range=internal,
        stiffness=k_min,
        stiffness_axis=k_axis,
        notes=tuple(notes),
        **given._asdict(),
    )


def _ellipse(dofs: tuple[str, ...], J_ce: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    r"""Semi-axes and world directions of :math:`\{\dot x_t : |J_{ce,t} \dot x_t| \le 1\}`.

    :math:`J_{ce,t}` holds the columns of the translational task coordinates: the rotation is
    held still. The semi-axes are :math:`1 / \sigma_i` along the right singular vectors.
    """
    lin = [i for i, d in enumerate(dofs) if d in AXES]
    if J_ce is None or not lin:
        return np.zeros(0), np.zeros((0, 3))
    _, s, vt = np.linalg.svd(J_ce[:, lin], full_matrices=False)
    with np.errstate(divide="ignore"):
        radii = np.where(s > 0.0, 1.0 / np.where(s > 0.0, s, 1.0), np.inf)
    axes = np.zeros((len(lin), 3))
    for row, v in enumerate(vt):
        for i, c in zip(lin, v, strict=True):
            axes[row, AXES[dofs[i]]] = c
    order = np.argsort(-radii)
    return radii[order], axes[order]
