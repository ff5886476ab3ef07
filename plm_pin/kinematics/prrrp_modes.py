r"""Assembly and working modes of the 2-PRRRP, and the planning of their changes.

For the 2-PRRRP family of :func:`plm_pin.models.build_2prrrp` (the presets
``harada2015_asymmetric``, ``harada2011_3d4m``, ``harada2011_3d3m`` and variants), after
Harada 2015, "Mode changes of a planar 3 DOF redundantly actuated parallel robot". The
generic machinery it builds on is in :mod:`plm_pin.kinematics.paths` (continuation along
task and actuator paths, redundancy margin) and :mod:`plm_pin.kinematics.mode_graph`
(mode-transition graphs and routes).

- A *sub-mechanism* is a plate pair with the legs (slider + rod) that reach it: legs 1-2
  on ``plate_left``, legs 3-4 on ``plate_right``. With its two sliders at :math:`c_{j1},
  c_{j2}` the pair :math:`p_j = [p_j, q_j]^T` lies on two circles centred on the stator
  (eq. (4)): :math:`(c_{ji} - p_j)^2 + q_j^2 = l_{ji}^2`. Its **assembly mode** is the side
  of the stator the pair is on: ``[+]`` for :math:`q_j > 0`, ``[-]`` for :math:`q_j < 0`,
  ``[0]`` for :math:`q_j = 0`, where the circles touch (the sub-mechanism's own direct
  singularity: both rods along the stator). The 2-PRRRP has the 9 combined modes
  :data:`ASSEMBLY_MODES`.
- The **working mode** of leg :math:`i` is the sign before the square root of eq. (6),
  :math:`c_i = L_i^T a \pm \sqrt{\cdot}`: ``(+)`` with the slider beyond the pair along the
  stator direction :math:`a`, ``(-)`` before it, ``(0)`` with the rod perpendicular to the
  stator (actuator singularity). It is **minus** the sign of :math:`z_i^T a` (:math:`z_i`
  the unit rod vector from slider to pair), which is the leg-block sign returned by
  :func:`plm_pin.kinematics.legs.working_mode` (0 when :math:`z_i^T a = 0`).
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
- :func:`complex_singularity_check` shows that equal rods in a sub-mechanism admit the
  complex (constraint) singularity: when one rod is perpendicular to the stator the other
  must be too, the two sliders share a position, the two circles of eq. (4) coincide, and
  the closure Jacobian loses rank; with unequal rods (``harada2015_asymmetric``) it cannot
  happen, since :math:`|c_{j1} - c_{j2}| \ge |l_{j1} - l_{j2}| > 0`.

Units: lengths [m], angles [rad], margins are normalised singular-value ratios [-].
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from ..exceptions import ClosureNotSatisfied, InvalidInput, PoseUnreachable, SingularConfiguration
from .forward import frame_distance
from .jacobians import closed_chain_jacobians, require_task
from .mode_graph import Mode, ModeEdge, ModeGraph, ModeNode, compress_modes
from .paths import TrackedPath, follow_targets, redundancy_margin, track_actuator_path
from .singularity import (
    SINGULARITY_TOL,
    SingularityReport,
    normalised_margin,
    numerical_rank,
    report_from_jacobians,
)

if TYPE_CHECKING:
    from ..mechanism import Mechanism

MODE_TOL = 1e-9
"""Pair heights [m] and rod cosines :math:`|z_i^T a|` [-] at or below which a mode sign is 0."""

MODE_CHANGE_TOL = 1e-3
"""Direct and constraint margin the mode-change planners require at every sample [-].

A thousandth of the largest singular value: far above round-off, so that the rank of
:math:`C` (Harada 2015: rank :math:`J_x = 3`) is not in doubt anywhere on the path.
"""

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


ASSEMBLY_MODES: tuple[Mode, ...] = (
    (1, 1),
    (1, -1),
    (1, 0),
    (-1, 1),
    (-1, -1),
    (-1, 0),
    (0, 1),
    (0, -1),
    (0, 0),
)
"""The 9 combined assembly modes of the 2-PRRRP (left pair, right pair), in the paper's order."""

PAPER_ASSEMBLY_ROUTE: tuple[Mode, ...] = ((1, 1), (1, 0), (1, -1), (0, -1), (-1, -1))
"""Harada 2015, section V: ``[+ +] -> [+ 0] -> [+ -] -> [0 -] -> [- -]``."""

PAPER_WORKING_ROUTE: tuple[Mode, ...] = ((-1, 1, -1, 1), (-1, 1, 0, 1), (-1, 1, 1, 1))
"""Harada 2015, section V: ``(- + - +) -> (- + 0 +) -> (- + + +)`` (leg 3 flips)."""

_PAIRS = {1: "plate_left", 2: "plate_left", 3: "plate_right", 4: "plate_right"}


def _sym(v: int) -> str:
    return "+" if v > 0 else ("-" if v < 0 else "0")


def mode_label(mode: Sequence[int]) -> str:
    """An assembly mode as the paper writes it, e.g. ``[+ 0]``."""
    return "[" + " ".join(_sym(v) for v in mode) + "]"


def working_mode_label(mode: Sequence[int]) -> str:
    """A working mode as the paper writes it, e.g. ``(- + 0 +)``."""
    return "(" + " ".join(_sym(v) for v in mode) + ")"


@dataclass(frozen=True)
class PrrrpLeg:
    """One leg (slider + rod) of a 2-PRRRP.

    Attributes:
        index: leg number ``i`` (1..4), as in the joint names ``slider<i>``, ``rod<i>_pivot``.
        slider: actuated prismatic joint.
        rod: passive revolute joint at the slider.
        pair: plate frame the rod reaches (``plate_left`` or ``plate_right``).
        length: rod length :math:`l_i` [m], measured on the assembled reference.
        actuator: index of the slider among the mechanism's actuators.
    """

    index: int
    slider: str
    rod: str
    pair: str
    length: float
    actuator: int


@dataclass(frozen=True)
class PrrrpSubMechanism:
    """A plate pair with the legs that reach it (Harada 2015, Fig. 1(b)).

    Attributes:
        name: ``left`` or ``right``.
        pair: plate frame of the pair.
        legs: leg numbers reaching it.
    """

    name: str
    pair: str
    legs: tuple[int, ...]

    @property
    def complete(self) -> bool:
        """Whether the pair is held by two legs (a PRRRP sub-mechanism with eq. (4))."""
        return len(self.legs) == 2


@dataclass(frozen=True)
class PrrrpLayout:
    r"""The 2-PRRRP structure of a mechanism, read from its model.

    Attributes:
        legs: the legs present, by leg number.
        subs: the left and right sub-mechanisms.
        direction: stator direction :math:`a` (unit, world), shape (3,).
        normal: in-plane unit normal of the stator, :math:`n = w \times a` with :math:`w`
            the revolute axis, shape (3,); pair heights are measured along it [m].
        origin: a point of the stator line (the sliders' zero) [m], shape (3,).
        half_plate: :math:`r_t`, half the distance between the pairs [m].
    """

    legs: tuple[PrrrpLeg, ...]
    subs: tuple[PrrrpSubMechanism, PrrrpSubMechanism]
    direction: np.ndarray
    normal: np.ndarray
    origin: np.ndarray
    half_plate: float

    def __post_init__(self) -> None:
        for arr in (self.direction, self.normal, self.origin):
            arr.setflags(write=False)

    def leg(self, index: int) -> PrrrpLeg:
        """The leg numbered ``index``.

        Raises:
            InvalidInput: when there is no such leg.
        """
        for leg in self.legs:
            if leg.index == index:
                return leg
        raise InvalidInput(f"no leg {index}; legs are {[leg.index for leg in self.legs]}")

    def sub_of(self, index: int) -> PrrrpSubMechanism:
        """The sub-mechanism leg ``index`` belongs to."""
        for sub in self.subs:
            if index in sub.legs:
                return sub
        raise InvalidInput(f"no leg {index}; legs are {[leg.index for leg in self.legs]}")

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "legs": [
                {"index": g.index, "slider": g.slider, "rod": g.rod, "pair": g.pair, "length": g.length}
                for g in self.legs
            ],
            "subs": [{"name": s.name, "pair": s.pair, "legs": list(s.legs)} for s in self.subs],
            "direction": self.direction.tolist(),
            "normal": self.normal.tolist(),
            "origin": self.origin.tolist(),
            "half_plate": self.half_plate,
        }


def prrrp_layout(mech: Mechanism) -> PrrrpLayout:
    """Read the 2-PRRRP structure of a mechanism built by :func:`plm_pin.models.build_2prrrp`.

    Legs are found by their joint names (``slider<i>`` actuated, ``rod<i>_pivot``); rod
    lengths, the stator line and the plate are measured on the assembled reference
    configuration. The task must be ``plate_center`` with ``x y rz``, midway between the pairs.

    Raises:
        InvalidInput: when the mechanism is not of this family; the message says what is missing.
    """
    model, data = mech.model, mech.model.createData()
    actuated = {a.joint: k for k, a in enumerate(mech.actuators)}
    missing = [f for f in ("plate_left", "plate_right", "plate_center") if not model.existFrame(f)]
    if missing:
        raise InvalidInput(
            f"{mech.name} is not a 2-PRRRP of plm_pin.models.build_2prrrp: frames {missing} are missing"
        )
    task = mech.task
    if task is None or task.frame != "plate_center" or tuple(task.dofs) != ("x", "y", "rz"):
        raise InvalidInput(f"{mech.name}: a 2-PRRRP needs the task plate_center with x y rz, got {task}")
    q = mech.q_ref
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    legs = []
    axes = []
    for i in (1, 2, 3, 4):
        slider, rod = f"slider{i}", f"rod{i}_pivot"
        if not (model.existJointName(slider) and model.existJointName(rod)):
            continue
        if slider not in actuated:
            raise InvalidInput(
                f"{mech.name}: joint {slider!r} is not actuated; actuators are {list(actuated)}"
            )
        jr = model.getJointId(rod)
        pair = data.oMf[model.getFrameId(_PAIRS[i])].translation
        length = float(np.linalg.norm(pair - data.oMi[jr].translation))
        js = model.getJointId(slider)
        a = pin.getJointJacobian(model, data, js, _LWA)[:3, model.joints[js].idx_v]
        w = pin.getJointJacobian(model, data, jr, _LWA)[3:, model.joints[jr].idx_v]
        origin = data.oMi[js].translation - q[model.joints[js].idx_q] * a
        axes.append((a, w, origin))
        legs.append(PrrrpLeg(i, slider, rod, _PAIRS[i], length, actuated[slider]))
    if len(legs) < 3 or not any(g.index in (1, 2) for g in legs) or not any(g.index in (3, 4) for g in legs):
        raise InvalidInput(
            f"{mech.name} is not a 2-PRRRP of plm_pin.models.build_2prrrp: legs found "
            f"{[g.index for g in legs]}; need joints slider<i> and rod<i>_pivot on both pairs"
        )
    a, w, origin = axes[0]
    for a2, w2, o2 in axes[1:]:
        off = o2 - origin
        if (
            np.linalg.norm(a2 - a) > 1e-9
            or np.linalg.norm(w2 - w) > 1e-9
            or np.linalg.norm(off - (off @ a) * a) > 1e-9
        ):
            raise InvalidInput(f"{mech.name}: the sliders do not share one stator line and one plane")
    if np.linalg.norm(a - np.array([1.0, 0.0, 0.0])) > 1e-9 or np.linalg.norm(origin) > 1e-9:
        raise InvalidInput(f"{mech.name}: the stator must be the world x axis (the builder's convention)")
    normal = np.cross(w, a)
    p_left = data.oMf[model.getFrameId("plate_left")].translation
    p_right = data.oMf[model.getFrameId("plate_right")].translation
    centre = data.oMf[model.getFrameId("plate_center")].translation
    if np.linalg.norm(centre - 0.5 * (p_left + p_right)) > 1e-9:
        raise InvalidInput(f"{mech.name}: plate_center must lie midway between the pairs")
    subs = (
        PrrrpSubMechanism("left", "plate_left", tuple(g.index for g in legs if g.index in (1, 2))),
        PrrrpSubMechanism("right", "plate_right", tuple(g.index for g in legs if g.index in (3, 4))),
    )
    return PrrrpLayout(
        tuple(legs), subs, a.copy(), normal, origin.copy(), float(0.5 * np.linalg.norm(p_right - p_left))
    )


def _layout(mech: Mechanism, layout: PrrrpLayout | None) -> PrrrpLayout:
    return prrrp_layout(mech) if layout is None else layout


@dataclass(frozen=True)
class PrrrpState:
    r"""Geometry of a 2-PRRRP configuration: pairs, rods, modes, sub-mechanism margins.

    Attributes:
        heights: signed height :math:`q_j` of each pair above the stator (left, right) [m], shape (2,).
        pairs: pair positions (left, right) in the world [m], shape (2, 3).
        rods: unit rod vectors :math:`z_i` from slider to pair, one per leg present, shape (n_legs, 3).
        cosines: :math:`z_i^T a` per leg [-], shape (n_legs,).
        assembly_mode: sign of each pair height, 0 within :data:`MODE_TOL` (``[+ 0]`` etc.).
        working_mode: the paper's eq. (6) sign per leg, :math:`-\mathrm{sign}(z_i^T a)`, 0 within
            :data:`MODE_TOL` (``(- + 0 +)`` etc.).
        sub_direct_margin: per sub-mechanism, :math:`\sigma_{min}/\sigma_{max}` of its own
            direct Jacobian (rows :math:`z_{j1}^T, z_{j2}^T` in the plane, eq. (4)
            differentiated); zero at ``[0]`` and when its circles coincide; NaN for a pair
            held by one leg [-], shape (2,).
    """

    heights: np.ndarray
    pairs: np.ndarray
    rods: np.ndarray
    cosines: np.ndarray
    assembly_mode: Mode
    working_mode: Mode
    sub_direct_margin: np.ndarray

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON (NaN margins as None)."""
        return {
            "heights": self.heights.tolist(),
            "pairs": self.pairs.tolist(),
            "rods": self.rods.tolist(),
            "cosines": self.cosines.tolist(),
            "assembly_mode": list(self.assembly_mode),
            "assembly_mode_label": mode_label(self.assembly_mode),
            "working_mode": list(self.working_mode),
            "working_mode_label": working_mode_label(self.working_mode),
            "sub_direct_margin": [None if math.isnan(m) else float(m) for m in self.sub_direct_margin],
        }


def _sign(value: float, tol: float) -> int:
    return 0 if abs(value) <= tol else (1 if value > 0 else -1)


def prrrp_state(
    mech: Mechanism, q: Any, layout: PrrrpLayout | None = None, tol: float = MODE_TOL
) -> PrrrpState:
    """Pair heights, rod directions, assembly and working modes of a 2-PRRRP configuration.

    Args:
        mech: a 2-PRRRP of the :func:`plm_pin.models.build_2prrrp` family.
        q: assembled configuration, shape (nq,).
        layout: its layout (read from the model when omitted).
        tol: heights [m] and cosines [-] at or below which a sign counts as 0.
    """
    lay = _layout(mech, layout)
    qa = mech.check_q(q)
    model, data = mech.model, mech.data
    pin.framesForwardKinematics(model, data, qa)
    pairs = np.array([data.oMf[model.getFrameId(sub.pair)].translation for sub in lay.subs])
    heights = (pairs - lay.origin) @ lay.normal
    rods = []
    for leg in lay.legs:
        base = data.oMi[model.getJointId(leg.rod)].translation
        v = data.oMf[model.getFrameId(leg.pair)].translation - base
        rods.append(v / np.linalg.norm(v))
    rod_arr = np.array(rods)
    cos = rod_arr @ lay.direction
    margins = []
    for sub in lay.subs:
        if not sub.complete:
            margins.append(math.nan)
            continue
        rows = np.array([rod_arr[[g.index for g in lay.legs].index(i)] for i in sub.legs])
        plane = np.column_stack([lay.direction, lay.normal])
        margins.append(normalised_margin(rows @ plane))
    return PrrrpState(
        heights,
        pairs,
        rod_arr,
        cos,
        tuple(_sign(float(h), tol) for h in heights),
        tuple(-_sign(float(c), tol) for c in cos),
        np.array(margins),
    )


def assembly_mode(mech: Mechanism, q: Any, layout: PrrrpLayout | None = None, tol: float = MODE_TOL) -> Mode:
    """Assembly mode ``(left, right)`` of a 2-PRRRP configuration: the side of the stator of each pair."""
    return prrrp_state(mech, q, layout, tol).assembly_mode


def paper_working_modes(
    mech: Mechanism, q: Any, layout: PrrrpLayout | None = None, tol: float = MODE_TOL
) -> Mode:
    r"""Working mode of each leg (Harada 2015, eq. (6)): :math:`-\mathrm{sign}(z_i^T a)`, 0 at 90 deg."""
    return prrrp_state(mech, q, layout, tol).working_mode


@dataclass(frozen=True)
class PairSolutions:
    """Direct kinematics of one PRRRP sub-mechanism, eq. (4): the intersections of two circles.

    Attributes:
        kind: ``two`` (assembly modes [+] and [-]), ``touching`` ([0], direct singularity),
            ``none`` (no assembly) or ``coincident`` (indefinite: complex singularity).
        points: pair positions along and normal to the stator ``(p, q)`` [m], [+] first,
            shape (k, 2) with k = 2, 1 or 0 (0 also when coincident: a whole circle).
    """

    kind: str
    points: np.ndarray

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {"kind": self.kind, "points": self.points.tolist()}


def pair_solutions(c1: float, c2: float, l1: float, l2: float, tol: float = 1e-12) -> PairSolutions:
    """Closed-form direct kinematics of a PRRRP sub-mechanism (Harada 2015, eq. (4)).

    The pair lies on the circles of radii ``l1``, ``l2`` [m] centred on the stator at the
    slider positions ``c1``, ``c2`` [m]; ``tol`` [m] decides touching and coincident circles.
    A cross-check of the generic forward kinematics, not used by the planners.
    """
    d = c2 - c1
    if abs(d) <= tol:
        kind = "coincident" if abs(l1 - l2) <= tol else "none"
        return PairSolutions(kind, np.zeros((0, 2)))
    p = 0.5 * (c1 + c2) - (l1 * l1 - l2 * l2) / (2.0 * (c1 - c2))
    h2 = l1 * l1 - (c1 - p) ** 2
    touch = min(abs(abs(d) - (l1 + l2)), abs(abs(d) - abs(l1 - l2)))
    if touch <= tol or abs(h2) <= tol * tol:
        return PairSolutions("touching", np.array([[p, 0.0]]))
    if h2 < 0.0:
        return PairSolutions("none", np.zeros((0, 2)))
    h = math.sqrt(h2)
    return PairSolutions("two", np.array([[p, h], [p, -h]]))


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
        s_list = [v for v in s_list if abs(v - sz) > 1e-9]
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


def _start(mech: Mechanism, lay: PrrrpLayout, q_start: Any) -> tuple[np.ndarray, PrrrpState, float, float]:
    q0 = mech.q_ref if q_start is None else mech.check_q(q_start, "q_start")
    state = prrrp_state(mech, q0, lay)
    pin.framesForwardKinematics(mech.model, mech.data, q0)
    M = mech.data.oMf[mech.model.getFrameId("plate_center")]
    x0 = float(M.translation @ lay.direction)
    cos_sign = 1.0 if float(M.rotation[:, 0] @ lay.direction) >= 0.0 else -1.0
    return q0, state, x0, cos_sign


def assembly_mode_graph(
    mech: Mechanism,
    q_start: Any = None,
    *,
    height: float | None = None,
    walk_samples: int = 7,
    tol: float = SINGULARITY_TOL,
    layout: PrrrpLayout | None = None,
) -> ModeGraph:
    """Compute the state-transition graph of the 2-PRRRP assembly modes (Harada 2015, Fig. 5).

    Each of the 9 modes gets a representative configuration: pair heights
    ``(sign_left * height, sign_right * height)`` at the plate x of ``q_start``, reached
    from ``q_start`` by inverse-kinematics continuation (so the legs keep their working
    modes). Its rank of :math:`C` decides whether the mode is singular. Two modes are
    adjacent when the straight walk in pair-height space from one representative to the
    other, assembled at every sample (with a sample exactly where a height changes sign)
    and labelled by :func:`assembly_mode`, visits no third mode.

    Args:
        mech: a 2-PRRRP of the :func:`plm_pin.models.build_2prrrp` family (the 3D3M too).
        q_start: configuration whose working modes and plate x are kept (default reference).
        height: magnitude of the representatives' pair heights [m] (default half the
            plate half-length, so that ``[+ -]`` tilts the plate by 30 deg).
        walk_samples: uniform samples per walk (plus the sign-change samples).
        tol: singularity tolerance for the reported margins.
        layout: the layout (read from the model when omitted).

    Returns:
        The graph; for the 2-PRRRP with two complete sub-mechanisms only ``[0 0]`` is singular.
    """
    lay = _layout(mech, layout)
    q0, state, x0, cos_sign = _start(mech, lay, q_start)
    m = 0.5 * lay.half_plate if height is None else float(height)
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
    return bool(visited == route and path.nonsingular and path.max_residual <= 1e-10 and deviation <= 1e-7)


@dataclass(frozen=True)
class ModeCrossing:
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
    s: float
    sub: str
    mode: Mode
    x: np.ndarray
    actuators: np.ndarray
    direct_margin: float
    sub_direct_margin: float
    redundancy_margin: float

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "index": self.index,
            "s": self.s,
            "sub": self.sub,
            "mode": list(self.mode),
            "label": mode_label(self.mode),
            "x": self.x.tolist(),
            "actuators": self.actuators.tolist(),
            "direct_margin": self.direct_margin,
            "sub_direct_margin": self.sub_direct_margin,
            "redundancy_margin": self.redundancy_margin,
        }


@dataclass(frozen=True)
class AssemblyModeChange:
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
    heights: np.ndarray
    sub_direct_margin: np.ndarray
    crossings: tuple[ModeCrossing, ...]
    max_deviation: float
    graph: ModeGraph

    @property
    def ok(self) -> bool:
        """Route followed, never direct- or constraint-singular, loops closed to 1e-10, no branch jump."""
        return _change_ok(self.route, self.visited, self.path, self.max_deviation)

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "route": [mode_label(m) for m in self.route],
            "visited": [mode_label(m) for m in self.visited],
            "path": self.path.to_dict(),
            "assembly_modes": self.assembly_modes.tolist(),
            "working_modes": self.working_modes.tolist(),
            "heights": self.heights.tolist(),
            "sub_direct_margin": [
                [None if math.isnan(v) else float(v) for v in row] for row in self.sub_direct_margin
            ],
            "crossings": [c.to_dict() for c in self.crossings],
            "max_deviation": self.max_deviation,
            "graph": self.graph.to_dict(),
            "ok": self.ok,
        }


def _max_deviation(mech: Mechanism, qa: np.ndarray, qb: np.ndarray) -> float:
    """Largest frame distance between planned and tracked configurations, sample by sample [m]."""
    return max([0.0, *(frame_distance(mech, q1, q2) for q1, q2 in zip(qa, qb, strict=True))])


def plan_assembly_mode_change(
    mech: Mechanism,
    q_start: Any = None,
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
        mech: a 2-PRRRP of the :func:`plm_pin.models.build_2prrrp` family.
        q_start: start configuration, both pairs off the stator (default: the reference).
        goal: goal assembly mode (default: the start's signs reversed).
        route: modes to follow, start to goal (default: see step 1); checked against the graph.
        tilt: plate angle at the intermediate waypoints [rad], in (0, pi/2).
        samples: uniform samples along the path (the ``[0]`` samples are added).
        tol: margin the direct and constraint margins must stay above (default
            :data:`MODE_CHANGE_TOL`).
        graph: a graph already computed from ``q_start`` (optional).

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
    q0, state, x0, cos_sign = _start(mech, lay, q_start)
    start = state.assembly_mode
    if 0 in start:
        raise InvalidInput(
            f"the start configuration is in {mode_label(start)}: start with both pairs off the stator"
        )
    goal_mode = tuple(-v for v in start) if goal is None else tuple(int(v) for v in goal)
    if goal_mode not in ASSEMBLY_MODES or 0 in goal_mode:
        raise InvalidInput(f"goal must be one of [+ +], [+ -], [- +], [- -]; got {goal_mode}")
    if not (0.0 < tilt < math.pi / 2):
        raise InvalidInput(f"tilt must lie in (0, pi/2) rad, got {tilt!r}")
    if samples < 3:
        raise InvalidInput(f"samples must be at least 3, got {samples}")
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
class WorkingModeChange:
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
    slider_gap: np.ndarray
    max_deviation: float

    @property
    def ok(self) -> bool:
        """Route followed, never direct- or constraint-singular, loops closed to 1e-10, no branch jump."""
        return _change_ok(self.route, self.visited, self.path, self.max_deviation)

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "leg": self.leg,
            "route": [working_mode_label(m) for m in self.route],
            "visited": [working_mode_label(m) for m in self.visited],
            "path": self.path.to_dict(),
            "working_modes": self.working_modes.tolist(),
            "assembly_modes": self.assembly_modes.tolist(),
            "fold_index": self.fold_index,
            "slider_gap": self.slider_gap.tolist(),
            "max_deviation": self.max_deviation,
            "ok": self.ok,
        }


def _fold_plan(
    mech: Mechanism, lay: PrrrpLayout, leg: int, q0: np.ndarray, tilt: float
) -> tuple[PrrrpLeg, PrrrpSubMechanism, int, float, float, np.ndarray, float]:
    """Common set-up of a leg flip: leg, sub, pair index, pair x and side, start pose, tilt sign."""
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
    q_start: Any = None,
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
        mech: a 2-PRRRP of the :func:`plm_pin.models.build_2prrrp` family.
        leg: the leg to flip (3 in the paper).
        q_start: start configuration (default: the reference).
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
    q0 = mech.q_ref if q_start is None else mech.check_q(q_start, "q_start")
    g, sub, _, x_pair, _, pose, tilt_sign = _fold_plan(mech, lay, leg, q0, tilt)
    for other in sub.legs:
        if other != leg and lay.leg(other).length < g.length - 1e-12:
            raise PoseUnreachable(
                f"{mech.name}: leg {other} (l = {lay.leg(other).length:.4g} m) cannot reach the height "
                f"{g.length:.4g} m where leg {leg} is perpendicular to the stator; only the shorter rod "
                "of a pair can fold while its partner holds the pair"
            )
    n = samples + (1 - samples % 2)
    if n < 5:
        raise InvalidInput(f"samples must be at least 5, got {samples}")
    s = np.linspace(0.0, 1.0, n)
    s[n // 2] = 0.5
    c0 = float(mech.actuator_positions(q0)[g.actuator])
    if abs(c0 - x_pair) <= MODE_TOL:
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


def prrrp_configuration(
    mech: Mechanism,
    pose: Sequence[float],
    working_modes: Sequence[int],
    layout: PrrrpLayout | None = None,
) -> np.ndarray:
    r"""Assembled 2-PRRRP configuration at a plate pose, from the closed form (eq. (6)).

    Each slider at :math:`c_i = L_{ix} + \sigma_i \sqrt{l_i^2 - L_{iy}^2}` with the paper's
    sign :math:`\sigma_i` (0 or either sign when the root vanishes), each rod at its world
    angle, the plate pivot at :math:`\theta - \varphi_1`; then :meth:`Mechanism.assemble`
    checks the closures (and polishes them). Exact also at singular configurations, where
    Newton from afar converges only linearly.

    Args:
        mech: a 2-PRRRP of the :func:`plm_pin.models.build_2prrrp` family.
        pose: plate pose ``(x [m], y [m], theta [rad])``.
        working_modes: the paper's sign per leg present, in leg order.
        layout: its layout (read from the model when omitted).

    Raises:
        PoseUnreachable: when a leg cannot reach its pair; the message names it and the miss.
    """
    lay = _layout(mech, layout)
    x, y, theta = (float(v) for v in pose)
    if len(working_modes) != len(lay.legs):
        raise InvalidInput(f"give {len(lay.legs)} working modes, one per leg, got {list(working_modes)}")
    q = mech.neutral()
    rt = lay.half_plate
    phi1 = 0.0
    for leg, sigma in zip(lay.legs, working_modes, strict=True):
        arm = -rt if leg.pair == "plate_left" else rt
        Lx, Ly = x + arm * math.cos(theta), y + arm * math.sin(theta)
        disc = leg.length**2 - Ly**2
        if disc < -1e-15 * leg.length**2:
            raise PoseUnreachable(
                f"{mech.name}: leg {leg.index} cannot reach its pair: |L_y| = {abs(Ly):.6g} m > "
                f"l = {leg.length:.6g} m"
            )
        c = Lx + float(np.sign(sigma)) * math.sqrt(max(disc, 0.0))
        phi = math.atan2(Ly, Lx - c)
        mech.set_joint(q, leg.slider, c)
        mech.set_joint(q, leg.rod, phi)
        if leg.index == 1:
            phi1 = phi
    mech.set_joint(q, "plate_pivot", theta - phi1)
    return np.array(mech.assemble(q).q)


@dataclass(frozen=True)
class CoincidentCircleSample:
    """A configuration with the two sliders of a sub-mechanism at one position.

    Attributes:
        rod_angle: common rod angle from the stator [rad].
        slider_gap: distance between the two sliders [m] (zero).
        sub_rank: rank of the sub-mechanism's two actuator rows of :math:`C` (1: locking
            both sliders leaves the pair free on the circle; 2 at the fold, where each
            slider moves with the plate still).
        sub_direct_margin: the sub-mechanism's own direct margin [-] (zero).
        report: the whole mechanism's singularity report.
    """

    rod_angle: float
    slider_gap: float
    sub_rank: int
    sub_direct_margin: float
    report: SingularityReport

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "rod_angle": self.rod_angle,
            "slider_gap": self.slider_gap,
            "sub_rank": self.sub_rank,
            "sub_direct_margin": self.sub_direct_margin,
            "report": self.report.to_dict(),
        }


@dataclass(frozen=True)
class ComplexSingularityCase:
    """One mechanism checked for the complex (constraint) singularity of a sub-mechanism.

    Attributes:
        name: mechanism name.
        leg: the leg brought perpendicular to the stator.
        rod_lengths: rod lengths of that leg's sub-mechanism, flipping leg first [m].
        q_fold: configuration with leg ``leg`` perpendicular to the stator, shape (nq,).
        report: singularity report there (``constraint`` in its kinds when the partner rod
            is perpendicular too).
        slider_gap: distance between the sub-mechanism's sliders there [m].
        circles: :func:`pair_solutions` kind of the sub-mechanism's circles there.
        closure_rank: rank of the closure Jacobian there.
        generic_closure_rank: the generic rank ``nv - mobility``.
        min_slider_gap: smallest slider gap the sub-mechanism can have, :math:`|l_1 - l_2|` [m].
        coincident: configurations with the two sliders at one position (rod angles
            50, 70 deg and perpendicular); empty when unequal rods make it impossible.
    """

    name: str
    leg: int
    rod_lengths: tuple[float, float]
    q_fold: np.ndarray
    report: SingularityReport
    slider_gap: float
    circles: str
    closure_rank: int
    generic_closure_rank: int
    min_slider_gap: float
    coincident: tuple[CoincidentCircleSample, ...]

    @property
    def admits_complex_singularity(self) -> bool:
        """Whether the closure Jacobian loses rank at the fold (``constraint`` kind)."""
        return "constraint" in self.report.kinds

    def to_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return {
            "name": self.name,
            "leg": self.leg,
            "rod_lengths": list(self.rod_lengths),
            "q_fold": self.q_fold.tolist(),
            "report": self.report.to_dict(),
            "slider_gap": self.slider_gap,
            "circles": self.circles,
            "closure_rank": self.closure_rank,
            "generic_closure_rank": self.generic_closure_rank,
            "min_slider_gap": self.min_slider_gap,
            "coincident": [c.to_dict() for c in self.coincident],
            "admits_complex_singularity": self.admits_complex_singularity,
        }


def complex_singularity_check(
    mech: Mechanism,
    leg: int = 3,
    q_start: Any = None,
    *,
    tilt: float = math.radians(30.0),
    tol: float = SINGULARITY_TOL,
) -> ComplexSingularityCase:
    """Bring one leg perpendicular to the stator and classify the configuration (Harada 2015, Fig. 7).

    The pose is the halfway pose of :func:`plan_working_mode_change`: the pair of leg
    ``leg`` above its start at the height :math:`l_i`, the plate tilted by ``tilt``. With
    equal rods the partner rod is perpendicular too, the sliders coincide, the circles of
    eq. (4) coincide and the closure Jacobian loses rank: :func:`plm_pin.kinematics.classify`
    reports ``constraint``. With a longer partner the partner rod is oblique, the sliders
    are apart and only the leg's own actuator (``inverse``) singularity remains.

    When the rods are equal, configurations with the two sliders at one position, the rods
    at 50 deg, 70 deg and perpendicular and the plate as at the fold are added: off the
    fold the sub-mechanism's two actuator rows of :math:`C` have rank 1 (with both sliders
    locked the pair still moves on the circle) while the whole mechanism keeps its direct
    margin; at the fold the closure Jacobian loses rank instead.

    Raises:
        PoseUnreachable: when the partner leg is shorter than ``leg``.
    """
    lay = prrrp_layout(mech)
    q0 = mech.q_ref if q_start is None else mech.check_q(q_start, "q_start")
    g, sub, j, x_pair, side, pose, tilt_sign = _fold_plan(mech, lay, leg, q0, tilt)
    if not sub.complete:
        raise InvalidInput(f"leg {leg} is alone on its pair: there is no sub-mechanism to check")
    partner = lay.leg(next(i for i in sub.legs if i != leg))
    if partner.length < g.length - 1e-12:
        raise PoseUnreachable(
            f"{mech.name}: leg {partner.index} (l = {partner.length:.4g} m) cannot reach the height "
            f"{g.length:.4g} m where leg {leg} is perpendicular to the stator"
        )
    modes0 = list(prrrp_state(mech, q0, lay).working_mode)
    theta = pose[2] + tilt_sign * tilt
    arm = -lay.half_plate if sub.name == "right" else lay.half_plate
    y = side * g.length + arm * math.sin(theta)
    x = x_pair + arm * math.cos(theta)
    modes = list(modes0)
    modes[[lg.index for lg in lay.legs].index(leg)] = 0
    if abs(partner.length - g.length) <= 1e-12:  # equal rods: the partner is perpendicular too
        modes[[lg.index for lg in lay.legs].index(partner.index)] = 0
    q_fold = prrrp_configuration(mech, (x, y, theta), modes, lay)
    jac = closed_chain_jacobians(mech, q_fold)
    report = report_from_jacobians(mech, jac, tol)
    c = mech.actuator_positions(q_fold)
    circles = pair_solutions(c[g.actuator], c[partner.actuator], g.length, partner.length, tol=1e-9).kind
    coincident: list[CoincidentCircleSample] = []
    if abs(partner.length - g.length) <= 1e-12:
        k_leg = [lg.index for lg in lay.legs].index(leg)
        k_partner = [lg.index for lg in lay.legs].index(partner.index)
        for angle in (math.radians(50.0), math.radians(70.0), math.pi / 2):
            # both rods at the same angle from the stator: the pair at (c + l cos, l sin)
            h = side * g.length * math.sin(angle)
            yy = h + arm * math.sin(theta)
            m2 = list(modes0)
            sigma = 0 if abs(angle - math.pi / 2) < 1e-15 else modes0[k_leg]
            m2[k_leg] = sigma
            m2[k_partner] = sigma
            try:
                qc = prrrp_configuration(mech, (x, yy, theta), m2, lay)
            except (PoseUnreachable, ClosureNotSatisfied):
                continue
            jc = closed_chain_jacobians(mech, qc)
            cc = mech.actuator_positions(qc)
            st = prrrp_state(mech, qc, lay)
            coincident.append(
                CoincidentCircleSample(
                    angle,
                    float(abs(cc[g.actuator] - cc[partner.actuator])),
                    numerical_rank(jc.C[[g.actuator, partner.actuator]]),
                    float(st.sub_direct_margin[j]),
                    report_from_jacobians(mech, jc, tol),
                )
            )
    return ComplexSingularityCase(
        mech.name,
        leg,
        (g.length, partner.length),
        q_fold,
        report,
        float(abs(c[g.actuator] - c[partner.actuator])),
        circles,
        numerical_rank(jac.J_phi),
        mech.nv - mech.mobility,
        abs(g.length - partner.length),
        tuple(coincident),
    )


def symmetric_variant(
    rod_length: float = 0.240, *, base: str = "harada2015_asymmetric", name: str | None = None
) -> Mechanism:
    """A 2-PRRRP like the preset ``base`` but with every rod ``rod_length`` [m] long.

    Rod masses and inertias scale from the 2011 rod (Table 1) as in the 2015 preset; the
    other parameters are the preset's. Built in memory, not registered.
    """
    # imported here: these modules import plm_pin.mechanism, which imports this package
    from ..description.loader import description_from_text
    from ..description.writer import urdf_text
    from ..loading import mechanism_from_description
    from ..models.prrrp import rod_scaled
    from ..models.registry import PRESETS

    if base not in PRESETS or PRESETS[base].builder.__name__ != "build_2prrrp":
        raise InvalidInput(f"base must be a 2-PRRRP preset, got {base!r}")
    if not (math.isfinite(rod_length) and rod_length > 0.0):
        raise InvalidInput(f"rod_length must be a positive length [m], got {rod_length!r}")
    preset = PRESETS[base]
    params = dict(preset.parameters)
    scaled = rod_scaled(rod_length, 0.140, 0.026, 9.84e-5)
    params.update(
        rod_lengths=(rod_length,) * 4,
        rod_masses=(scaled[0],) * 4,
        rod_inertias=(scaled[1],) * 4,
    )
    label = name or f"{base}_symmetric_{round(rod_length * 1000)}mm"
    robot, sidecar = preset.builder(name=label, source=f"{preset.source}; all rods {rod_length} m", **params)
    description = description_from_text(urdf_text(robot), sidecar.to_yaml())
    return mechanism_from_description(description, label)
