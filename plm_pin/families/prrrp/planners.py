r"""Planning and tracking the mode changes of a 2-PRRRP (Harada 2015, Figs. 5-7).

The generic machinery it builds on is in :mod:`plm_pin.kinematics.paths` (continuation along
task and actuator paths, redundancy margin) and :mod:`plm_pin.kinematics.mode_graph`
(mode-transition graphs and routes); the modes are those of :mod:`plm_pin.families.prrrp.modes`.

- :func:`assembly_mode_graph` derives the transition graph of Fig. 5 by computation:
  representatives of the 9 modes reached by inverse-kinematics continuation, the rank of
  :math:`C` at each (3 except at ``[0 0]``), and an edge between two modes when a straight
  walk in pair-height space from one representative to the other, assembled at every
  sample, visits no third mode.
- :func:`plan_assembly_mode_change` plans the singularity-free change ``[+ +] -> [- -]``
  along a route of the graph that avoids the singular modes (the paper's
  ``[+ +] -> [+ 0] -> [+ -] -> [0 -] -> [- -]`` by default) and returns the sampled actuator
  path with the configuration tracked along it.
- :func:`plan_working_mode_change` flips one leg through its actuator singularity, e.g.
  ``(- + - +) -> (- + 0 +) -> (- + + +)`` (Fig. 7), at a constant plate pose at both ends.

Units: lengths [m], angles [rad], margins are normalised singular-value ratios [-].
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..._arguments import check_tolerance, count, finite_number
from ...core.mechanism import Mechanism, require_task
from ...core.rank import numerical_rank
from ...exceptions import InvalidInput, PoseUnreachable, SingularConfiguration
from ...kinematics.forward import frame_distance
from ...kinematics.jacobians import closed_chain_jacobians
from ...kinematics.mode_graph import Mode, ModeEdge, ModeGraph, ModeNode, compress_modes
from ...kinematics.paths import TrackedPath, follow_targets, redundancy_margin, track_actuator_path
from ...kinematics.singularity import report_from_jacobians
from ...results import Result, unit
from ...tolerances import (
    KNOT_TOL,
    MODE_CHANGE_DEVIATION_TOL,
    MODE_CHANGE_RESIDUAL_TOL,
    MODE_CHANGE_TOL,
    PRRRP_MODE_TOL,
    SINGULARITY_TOL,
)
from .builder import TASK_FRAME
from .layout import PrrrpLayout, PrrrpLeg, PrrrpSubMechanism, prrrp_layout, resolve_layout
from .modes import ASSEMBLY_MODES, PrrrpState, mode_label, prrrp_state

PAPER_ASSEMBLY_ROUTE: tuple[Mode, ...] = ((1, 1), (1, 0), (1, -1), (0, -1), (-1, -1))
"""Harada 2015, section V: ``[+ +] -> [+ 0] -> [+ -] -> [0 -] -> [- -]``."""

PAPER_WORKING_ROUTE: tuple[Mode, ...] = ((-1, 1, -1, 1), (-1, 1, 0, 1), (-1, 1, 1, 1))
"""Harada 2015, section V: ``(- + - +) -> (- + 0 +) -> (- + + +)`` (leg 3 flips)."""


def _pose_from_heights(
    lay: PrrrpLayout, x: float, h_left: float, h_right: float, cos_sign: float
) -> np.ndarray:
    """Plate pose ``(x, y, theta)`` with the pairs at the given heights; ``cos_sign`` picks the branch."""
    sin_t = (h_right - h_left) / (2.0 * lay.half_plate)
    if abs(sin_t) >= 1.0 - 1e-9:
        raise InvalidInput(
            f"pair heights {h_left:.4g} m and {h_right:.4g} m differ by more than the plate length "
            f"{2 * lay.half_plate:.4g} m"
        )
    theta = math.asin(sin_t) if cos_sign >= 0.0 else math.pi - math.asin(sin_t)
    theta = math.atan2(math.sin(theta), math.cos(theta))
    return np.array([x, 0.5 * (h_left + h_right), theta])


def _check_heights(lay: PrrrpLayout, h: np.ndarray, what: str) -> None:
    for sub, hj in zip(lay.subs, h, strict=True):
        reach = min(lay.leg(i).length for i in sub.legs)
        if abs(hj) >= reach * (1.0 - 1e-6):
            raise InvalidInput(
                f"{what}: the {sub.name} pair at height {hj:.4g} m is out of reach of its rods "
                f"(shortest {reach:.4g} m)"
            )


def _walk(
    mech: Mechanism,
    lay: PrrrpLayout,
    q_from: np.ndarray,
    waypoints: np.ndarray,
    samples: int,
    x0: float,
    cos_sign: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[tuple[int, int]]]:
    """Inverse-kinematics continuation along straight segments in pair-height space.

    Samples are uniform in arc length, plus one sample exactly where a pair height changes
    sign (set to zero there). Returns the path parameter, the heights, the configurations
    and ``(sample index, sub index)`` of each crossing.
    """
    seg = np.linalg.norm(np.diff(waypoints, axis=0), axis=1)
    knots = np.concatenate([[0.0], np.cumsum(seg)])
    total = knots[-1]
    knots = knots / total if total > 0.0 else np.linspace(0.0, 1.0, len(waypoints))
    s_list = list(np.linspace(0.0, 1.0, samples))
    zero_at: list[tuple[float, int]] = []
    for k in range(len(waypoints) - 1):
        a, b = waypoints[k], waypoints[k + 1]
        for j in range(2):
            if a[j] * b[j] < 0.0 or (b[j] == 0.0 and a[j] != 0.0):
                t = a[j] / (a[j] - b[j])
                zero_at.append((knots[k] + t * (knots[k + 1] - knots[k]), j))
    for sz, _ in zero_at:
        s_list = [v for v in s_list if abs(v - sz) > KNOT_TOL]
    s = np.array(sorted(set(s_list) | {sz for sz, _ in zero_at}))
    h = np.column_stack([np.interp(s, knots, waypoints[:, j]) for j in range(2)])
    crossings = []
    for sz, j in zero_at:
        idx = int(np.argmin(np.abs(s - sz)))
        h[idx, j] = 0.0
        crossings.append((idx, j))
    _check_heights(lay, np.max(np.abs(h), axis=0), "path")
    poses = np.array([_pose_from_heights(lay, x0, hl, hr, cos_sign) for hl, hr in h])
    qs = follow_targets(mech, q_from, task_dofs=("x", "y", "rz"), task_values=poses, s=s)
    return s, h, qs, sorted(crossings)


def _start(
    mech: Mechanism, lay: PrrrpLayout, guess: ArrayLike | None
) -> tuple[np.ndarray, PrrrpState, float, float]:
    q0 = mech.q_ref if guess is None else mech.check_q(guess, "guess")
    state = prrrp_state(mech, q0, lay)
    pin.framesForwardKinematics(mech.model, mech.data, q0)
    M = mech.data.oMf[mech.model.getFrameId(TASK_FRAME)]
    x0 = float(M.translation @ lay.direction)
    cos_sign = 1.0 if float(M.rotation[:, 0] @ lay.direction) >= 0.0 else -1.0
    return q0, state, x0, cos_sign


def assembly_mode_graph(
    mech: Mechanism,
    guess: ArrayLike | None = None,
    *,
    height: float | None = None,
    walk_samples: int = 7,
    tol: float = SINGULARITY_TOL,
    layout: PrrrpLayout | None = None,
) -> ModeGraph:
    """Compute the state-transition graph of the 2-PRRRP assembly modes (Harada 2015, Fig. 5).

    Each of the 9 modes gets a representative configuration: pair heights
    ``(sign_left * height, sign_right * height)`` at the plate x of ``guess``, reached
    from ``guess`` by inverse-kinematics continuation (so the legs keep their working
    modes). Its rank of :math:`C` decides whether the mode is singular. Two modes are
    adjacent when the straight walk in pair-height space from one representative to the
    other, assembled at every sample (with a sample exactly where a height changes sign)
    and labelled by :func:`assembly_mode`, visits no third mode.

    Args:
        mech: a 2-PRRRP of the :func:`plm_pin.families.prrrp.build_2prrrp` family (the 3D3M too).
        guess: configuration whose working modes and plate x are kept (default reference).
        height: magnitude of the representatives' pair heights [m] (default half the
            plate half-length, so that ``[+ -]`` tilts the plate by 30 deg).
        walk_samples: uniform samples per walk (plus the sign-change samples).
        tol: singularity tolerance for the reported margins.
        layout: the layout (read from the model when omitted).

    Returns:
        The graph; for the 2-PRRRP with two complete sub-mechanisms only ``[0 0]`` is singular.
    """
    lay = resolve_layout(mech, layout)
    walk_samples, tol = count(walk_samples, "walk_samples", minimum=1), check_tolerance(tol, "tol")
    q0, state, x0, cos_sign = _start(mech, lay, guess)
    m = 0.5 * lay.half_plate if height is None else finite_number(height, "height", "m")
    if not (0.0 < m < lay.half_plate):
        raise InvalidInput(f"height must lie in (0, {lay.half_plate:.4g}) m, got {m!r}")
    mobility = mech.mobility
    nodes = []
    for mode in ASSEMBLY_MODES:
        target = np.array(mode, dtype=float) * m
        _, _, qs, _ = _walk(mech, lay, q0, np.array([state.heights, target]), walk_samples, x0, cos_sign)
        q = qs[-1]
        found = prrrp_state(mech, q, lay).assembly_mode
        if found != mode:
            raise PoseUnreachable(
                f"{mech.name}: the representative of {mode_label(mode)} assembled as {mode_label(found)}; "
                "choose another height or start configuration"
            )
        jac = closed_chain_jacobians(mech, q)
        rep = report_from_jacobians(mech, jac, tol)
        nodes.append(
            ModeNode(
                mode,
                mode_label(mode),
                q.copy(),
                numerical_rank(jac.C),
                mobility,
                rep.direct_margin,
                redundancy_margin(mech, q, jac),
            )
        )
    edges = []
    for i, a in enumerate(nodes):
        for b in nodes[i + 1 :]:
            wp = np.array([a.mode, b.mode], dtype=float) * m
            _, _, qs, _ = _walk(mech, lay, a.q, wp, walk_samples, x0, cos_sign)
            labels = [prrrp_state(mech, q, lay).assembly_mode for q in qs]
            if compress_modes(labels) == (a.mode, b.mode):
                margin = min(
                    report_from_jacobians(mech, closed_chain_jacobians(mech, q), tol).direct_margin
                    for q in qs
                )
                edges.append(ModeEdge(a.mode, b.mode, margin, len(qs)))
    return ModeGraph(tuple(nodes), tuple(edges), mode_label)


def _change_ok(
    route: tuple[Mode, ...], visited: tuple[Mode, ...], path: TrackedPath, deviation: float
) -> bool:
    """Whether a tracked mode change followed its route cleanly (the planners' ``ok``)."""
    return bool(
        visited == route
        and path.nonsingular
        and path.max_residual <= MODE_CHANGE_RESIDUAL_TOL
        and deviation <= MODE_CHANGE_DEVIATION_TOL
    )


@dataclass(frozen=True)
class ModeCrossing(Result):
    """A sample where one sub-mechanism sits at ``[0]`` (circles touching).

    Attributes:
        index: sample index in the path.
        s: path parameter there [-].
        sub: ``left`` or ``right``.
        mode: the combined assembly mode there, e.g. ``(1, 0)``.
        x: plate pose ``(x [m], y [m], theta [rad])``, shape (3,).
        actuators: actuator positions there [m], shape (n_act,).
        direct_margin: the whole mechanism's direct margin there [-] (stays above tolerance).
        sub_direct_margin: that sub-mechanism's own direct margin there [-] (zero: it is singular).
        redundancy_margin: :func:`redundancy_margin` there [-] (zero: redundancy lost).
    """

    index: int
    s: float = field(metadata=unit("-"))
    sub: str
    mode: Mode
    x: np.ndarray = field(metadata=unit("m, m, rad"))
    actuators: np.ndarray = field(metadata=unit("m"))
    direct_margin: float = field(metadata=unit("-"))
    sub_direct_margin: float = field(metadata=unit("-"))
    redundancy_margin: float = field(metadata=unit("-"))
    _DERIVED = ("label",)
    _NONFINITE_AS_TEXT = ("sub_direct_margin",)

    @property
    def label(self) -> str:
        """The combined assembly mode as the paper writes it, e.g. ``[+ 0]``."""
        return mode_label(self.mode)


@dataclass(frozen=True)
class AssemblyModeChange(Result):
    """A planned and tracked assembly-mode change of a 2-PRRRP.

    Attributes:
        route: the planned route of assembly modes.
        visited: the assembly modes the tracked path visits, in order.
        path: the sampled actuator path with the configuration tracked along it.
        assembly_modes: assembly mode per sample, shape (N, 2).
        working_modes: the paper's working mode per sample, shape (N, n_legs).
        heights: pair heights per sample [m], shape (N, 2).
        sub_direct_margin: each sub-mechanism's own direct margin per sample [-], shape (N, 2).
        crossings: the samples where a sub-mechanism is at ``[0]``.
        max_deviation: largest distance between a frame of the planned (inverse
            continuation) and the tracked (forward continuation) configurations [m].
        graph: the transition graph the route was taken from.
    """

    route: tuple[Mode, ...]
    visited: tuple[Mode, ...]
    path: TrackedPath
    assembly_modes: np.ndarray
    working_modes: np.ndarray
    heights: np.ndarray = field(metadata=unit("m"))
    sub_direct_margin: np.ndarray = field(metadata=unit("-"))
    crossings: tuple[ModeCrossing, ...]
    max_deviation: float = field(metadata=unit("m"))
    graph: ModeGraph
    _DERIVED = ("ok",)
    _NONFINITE_AS_TEXT = ("sub_direct_margin",)

    @property
    def ok(self) -> bool:
        """Route followed, never direct- or constraint-singular, loops closed to 1e-10, no branch jump."""
        return _change_ok(self.route, self.visited, self.path, self.max_deviation)


def _max_deviation(mech: Mechanism, qa: np.ndarray, qb: np.ndarray) -> float:
    """Largest frame distance between planned and tracked configurations, sample by sample [m]."""
    return max([0.0, *(frame_distance(mech, q1, q2) for q1, q2 in zip(qa, qb, strict=True))])


def plan_assembly_mode_change(
    mech: Mechanism,
    guess: ArrayLike | None = None,
    *,
    goal: Sequence[int] | None = None,
    route: Sequence[Sequence[int]] | None = None,
    tilt: float = math.radians(60.0),
    samples: int = 201,
    tol: float = MODE_CHANGE_TOL,
    graph: ModeGraph | None = None,
) -> AssemblyModeChange:
    """Plan a singularity-free assembly-mode change of a 2-PRRRP (Harada 2015, Fig. 6).

    1. The transition graph (:func:`assembly_mode_graph`) gives the shortest routes from
       the start mode to ``goal`` that avoid every mode where :math:`C` loses rank; by
       default the paper's route ``[+ +] -> [+ 0] -> [+ -] -> [0 -] -> [- -]`` when it is one
       of them, else the first.
    2. Each mode of the route with both pairs off the stator gets a waypoint in pair-height
       space: the start's heights, the goal's (default: the start mirrored in the stator,
       which has the same actuator positions: the other solution of the direct kinematics),
       and in between ``sign * r_t sin(tilt)`` (the plate tilted by ``tilt``). Straight
       segments join them; crossing a ``[0]`` mode is sampled exactly.
    3. Inverse-kinematics continuation (:func:`follow_targets`) along the plate poses gives
       the actuator path; forward-kinematics continuation (:func:`track_actuator_path`) from
       the start configuration along it gives the realised configurations, which are
       labelled and checked against the plan.

    Args:
        mech: a 2-PRRRP of the :func:`plm_pin.families.prrrp.build_2prrrp` family.
        guess: start configuration, both pairs off the stator (default: the reference).
        goal: goal assembly mode (default: the start's signs reversed).
        route: modes to follow, start to goal (default: see step 1); checked against the graph.
        tilt: plate angle at the intermediate waypoints [rad], in (0, pi/2).
        samples: uniform samples along the path (the ``[0]`` samples are added).
        tol: margin the direct and constraint margins must stay above (default
            :data:`MODE_CHANGE_TOL`).
        graph: a graph already computed from ``guess`` (optional).

    Returns:
        The plan with its tracked path; check :attr:`AssemblyModeChange.ok`.

    Raises:
        SingularConfiguration: when no route avoids the singular modes (e.g. the
            non-redundant 3D3M, whose left pair cannot cross the stator without a
            direct singularity); the message lists the singular modes.
        InvalidInput: malformed arguments, a route that is not a path of the graph, or a
            start with a pair on the stator.
    """
    lay = prrrp_layout(mech)
    q0, state, x0, cos_sign = _start(mech, lay, guess)
    start = state.assembly_mode
    if 0 in start:
        raise InvalidInput(
            f"the start configuration is in {mode_label(start)}: start with both pairs off the stator"
        )
    goal_mode = tuple(-v for v in start) if goal is None else tuple(int(v) for v in goal)
    if goal_mode not in ASSEMBLY_MODES or 0 in goal_mode:
        raise InvalidInput(f"goal must be one of [+ +], [+ -], [- +], [- -]; got {goal_mode}")
    tilt = finite_number(tilt, "tilt", "rad")
    if not (0.0 < tilt < math.pi / 2):
        raise InvalidInput(f"tilt must lie in (0, pi/2) rad, got {tilt!r}")
    samples, tol = count(samples, "samples", minimum=3), check_tolerance(tol, "tol")
    g = assembly_mode_graph(mech, q0, tol=tol, layout=lay) if graph is None else graph
    if route is None:
        candidates = g.routes(start, goal_mode)
        if not candidates:
            raise SingularConfiguration(
                f"{mech.name}: no route from {mode_label(start)} to {mode_label(goal_mode)} avoids the "
                f"singular modes {[mode_label(m) for m in g.singular_modes]} (rank C < {mech.mobility})"
            )
        chosen = PAPER_ASSEMBLY_ROUTE if PAPER_ASSEMBLY_ROUTE in candidates else candidates[0]
    else:
        chosen = tuple(tuple(int(v) for v in m) for m in route)
        if chosen[0] != start or chosen[-1] != goal_mode:
            raise InvalidInput(
                f"route must run from {mode_label(start)} to {mode_label(goal_mode)}, got "
                f"{[mode_label(m) for m in chosen]}"
            )
        for a, b in itertools.pairwise(chosen):
            if not g.adjacent(a, b):
                raise InvalidInput(
                    f"route step {mode_label(a)} -> {mode_label(b)} is not an edge of the graph"
                )
        bad = [mode_label(m) for m in chosen if g.node(m).singular]
        if bad:
            raise InvalidInput(f"route passes the singular modes {bad}")
    opened = [m for m in chosen if 0 not in m]
    for a, b in itertools.pairwise(chosen):
        if (0 in a) == (0 in b):
            raise InvalidInput(
                f"route step {mode_label(a)} -> {mode_label(b)}: steps must alternate between modes "
                "off and on the stator"
            )
    mag = lay.half_plate * math.sin(tilt)
    waypoints = [state.heights.copy()]
    for m in opened[1:-1]:
        waypoints.append(np.array(m, dtype=float) * mag)
    if goal_mode == tuple(-v for v in start):
        waypoints.append(-state.heights)
    else:
        waypoints.append(np.array(goal_mode, dtype=float) * mag)
    wp = np.array(waypoints)
    s, _, q_plan, _ = _walk(mech, lay, q0, wp, samples, x0, cos_sign)
    c = np.array([mech.actuator_positions(q) for q in q_plan])
    path = track_actuator_path(mech, c, q0, s=s, tol=tol)
    states = [prrrp_state(mech, q, lay) for q in path.q]
    modes = np.array([st.assembly_mode for st in states])
    crossings = []
    for k, st in enumerate(states):
        for j, sub in enumerate(lay.subs):
            if st.assembly_mode[j] == 0:
                crossings.append(
                    ModeCrossing(
                        k,
                        float(s[k]),
                        sub.name,
                        st.assembly_mode,
                        path.x[k].copy(),
                        path.actuators[k].copy(),
                        float(path.direct_margin[k]),
                        float(st.sub_direct_margin[j]),
                        float(path.redundancy_margin[k]),
                    )
                )
    return AssemblyModeChange(
        chosen,
        compress_modes([st.assembly_mode for st in states]),
        path,
        modes,
        np.array([st.working_mode for st in states]),
        np.array([st.heights for st in states]),
        np.array([st.sub_direct_margin for st in states]),
        tuple(crossings),
        _max_deviation(mech, q_plan, path.q),
        g,
    )


@dataclass(frozen=True)
class WorkingModeChange(Result):
    """A planned and tracked working-mode change of one 2-PRRRP leg (Harada 2015, Fig. 7).

    Attributes:
        leg: the leg that flips.
        route: the expected working modes: start, the leg at 0, the leg reversed.
        visited: the working modes the tracked path visits (paper's signs), in order.
        path: the sampled actuator path with the configuration tracked along it.
        working_modes: the paper's working mode per sample, shape (N, n_legs).
        assembly_modes: assembly mode per sample, shape (N, 2).
        fold_index: sample where the flipping rod is perpendicular to the stator (``(0)``).
        slider_gap: distance between the two sliders of the flipping leg's sub-mechanism
            per sample [m], shape (N,); never below :math:`|l_{j1} - l_{j2}|`.
        max_deviation: largest frame distance between planned and tracked configurations [m].
    """

    leg: int
    route: tuple[Mode, ...]
    visited: tuple[Mode, ...]
    path: TrackedPath
    working_modes: np.ndarray
    assembly_modes: np.ndarray
    fold_index: int
    slider_gap: np.ndarray = field(metadata=unit("m"))
    max_deviation: float = field(metadata=unit("m"))
    _DERIVED = ("ok",)

    @property
    def ok(self) -> bool:
        """Route followed, never direct- or constraint-singular, loops closed to 1e-10, no branch jump."""
        return _change_ok(self.route, self.visited, self.path, self.max_deviation)


def fold_plan(
    mech: Mechanism, lay: PrrrpLayout, leg: int, q0: np.ndarray, tilt: float
) -> tuple[PrrrpLeg, PrrrpSubMechanism, int, float, float, np.ndarray, float]:
    """Common set-up of a leg flip: leg, sub, pair index, pair x and side, start pose, tilt sign.

    Also the set-up of :func:`plm_pin.families.prrrp.complex_singularity_check`.
    """
    tilt = finite_number(tilt, "tilt", "rad")
    g = lay.leg(leg)
    sub = lay.sub_of(leg)
    j = lay.subs.index(sub)
    state = prrrp_state(mech, q0, lay)
    if state.assembly_mode[j] == 0:
        raise InvalidInput(f"the {sub.name} pair is on the stator at the start; it cannot fold leg {leg}")
    side = float(state.assembly_mode[j])
    pin.framesForwardKinematics(mech.model, mech.data, q0)
    x_pair = float((state.pairs[j] - lay.origin) @ lay.direction)
    task = require_task(mech)
    pose = task.pose_from_data(mech.data)
    order = [task.dofs.index(d) for d in ("x", "y", "rz")]
    pose = pose[order]
    # raise the flipping pair above the other one: theta > 0 for the right pair, < 0 for the left
    tilt_sign = side * (1.0 if sub.name == "right" else -1.0)
    if not (0.0 <= tilt < math.pi / 2):
        raise InvalidInput(f"tilt must lie in [0, pi/2) rad, got {tilt!r}")
    return g, sub, j, x_pair, side, pose, tilt_sign


def plan_working_mode_change(
    mech: Mechanism,
    leg: int = 3,
    guess: ArrayLike | None = None,
    *,
    tilt: float = math.radians(30.0),
    samples: int = 101,
    tol: float = MODE_CHANGE_TOL,
) -> WorkingModeChange:
    r"""Flip one leg's working mode through its actuator singularity (Harada 2015, Fig. 7).

    The flipping slider moves at constant speed from its start position :math:`c_i` to
    its mirror image :math:`2 p_j - c_i` across its pair (so the plate pose at the end is
    the start pose), while the plate angle rises by ``tilt`` and comes back
    (:math:`\theta_0 + \text{tilt}\,\sin \pi s`, raising the flipping pair above the other)
    and the plate moves along the stator so that the pair stays above its start. Halfway,
    the rod is perpendicular to the stator (working mode 0) and the pair at the rod's
    height :math:`l_i`. The other legs keep their working modes. The configuration is
    solved by continuation with the slider and the plate's ``x`` and angle prescribed
    (regular through the fold), then tracked by forward continuation with all actuators.

    The partner leg of the same pair must be *longer* (it has to reach the height
    :math:`l_i`); equal rods fold together, the sliders meet and the complex singularity
    is hit (:func:`complex_singularity_check`).

    Args:
        mech: a 2-PRRRP of the :func:`plm_pin.families.prrrp.build_2prrrp` family.
        leg: the leg to flip (3 in the paper).
        guess: start configuration (default: the reference).
        tilt: plate angle added halfway [rad], in [0, pi/2).
        samples: samples along the path (made odd so that the fold is a sample).
        tol: margin the direct and constraint margins must stay above (default
            :data:`MODE_CHANGE_TOL`).

    Returns:
        The plan with its tracked path; check :attr:`WorkingModeChange.ok`.

    Raises:
        PoseUnreachable: when the partner leg is shorter than the flipping one, or a
            sample cannot be reached.
        InvalidInput: malformed arguments.
    """
    lay = prrrp_layout(mech)
    q0 = mech.q_ref if guess is None else mech.check_q(guess, "guess")
    g, sub, _, x_pair, _, pose, tilt_sign = fold_plan(mech, lay, leg, q0, tilt)
    for other in sub.legs:
        if other != leg and lay.leg(other).length < g.length - 1e-12:
            raise PoseUnreachable(
                f"{mech.name}: leg {other} (l = {lay.leg(other).length:.4g} m) cannot reach the height "
                f"{g.length:.4g} m where leg {leg} is perpendicular to the stator; only the shorter rod "
                "of a pair can fold while its partner holds the pair"
            )
    samples = count(samples, "samples", minimum=5)
    n = samples + (1 - samples % 2)
    s = np.linspace(0.0, 1.0, n)
    s[n // 2] = 0.5
    c0 = float(mech.actuator_positions(q0)[g.actuator])
    if abs(c0 - x_pair) <= PRRRP_MODE_TOL:
        raise InvalidInput(
            f"leg {leg} is already perpendicular to the stator at the start; start off the fold"
        )
    c_leg = x_pair + (c0 - x_pair) * (1.0 - 2.0 * s)
    theta = pose[2] + tilt_sign * tilt * np.sin(np.pi * s)
    arm = -lay.half_plate if sub.name == "right" else lay.half_plate
    x_plate = x_pair + arm * np.cos(theta)
    q_plan = follow_targets(
        mech,
        q0,
        task_dofs=("x", "rz"),
        task_values=np.column_stack([x_plate, theta]),
        fixed={g.slider: c_leg},
        s=s,
    )
    c = np.array([mech.actuator_positions(q) for q in q_plan])
    path = track_actuator_path(mech, c, q0, s=s, tol=tol)
    states = [prrrp_state(mech, q, lay) for q in path.q]
    pair_legs = [lay.leg(i).actuator for i in sub.legs]
    gap = np.abs(c[:, pair_legs[0]] - c[:, pair_legs[1]]) if len(pair_legs) == 2 else np.full(n, np.nan)
    start = prrrp_state(mech, q0, lay).working_mode
    k_leg = [lg.index for lg in lay.legs].index(leg)
    fold = tuple(0 if k == k_leg else v for k, v in enumerate(start))
    flipped = tuple(-v if k == k_leg else v for k, v in enumerate(start))
    return WorkingModeChange(
        leg,
        (start, fold, flipped),
        compress_modes([st.working_mode for st in states]),
        path,
        np.array([st.working_mode for st in states]),
        np.array([st.assembly_mode for st in states]),
        n // 2,
        gap,
        _max_deviation(mech, q_plan, path.q),
    )
