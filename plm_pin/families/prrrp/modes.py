r"""Assembly and working modes of a 2-PRRRP configuration (Harada 2015), and its closed form.

- A *sub-mechanism* is a plate pair with the legs (slider + rod) that reach it: legs 1-2
  on ``plate_left``, legs 3-4 on ``plate_right``. With its two sliders at :math:`c_{j1},
  c_{j2}` the pair :math:`p_j = [p_j, q_j]^T` lies on two circles centred on the stator
  (eq. (4)): :math:`(c_{ji} - p_j)^2 + q_j^2 = l_{ji}^2` (:func:`pair_solutions`). Its
  **assembly mode** is the side of the stator the pair is on: ``[+]`` for :math:`q_j > 0`,
  ``[-]`` for :math:`q_j < 0`, ``[0]`` for :math:`q_j = 0`, where the circles touch (the
  sub-mechanism's own direct singularity: both rods along the stator). The 2-PRRRP has the
  9 combined modes :data:`ASSEMBLY_MODES`.
- The **working mode** of leg :math:`i` is the sign before the square root of eq. (6),
  :math:`c_i = L_i^T a \pm \sqrt{\cdot}`: ``(+)`` with the slider beyond the pair along the
  stator direction :math:`a`, ``(-)`` before it, ``(0)`` with the rod perpendicular to the
  stator (actuator singularity). It is **minus** the sign of :math:`z_i^T a` (:math:`z_i`
  the unit rod vector from slider to pair), which is the leg-block sign returned by
  :func:`plm_pin.kinematics.working_mode.working_mode` (0 when :math:`z_i^T a = 0`).

Units: lengths [m], angles [rad], margins are normalised singular-value ratios [-].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..._arguments import check_tolerance, finite_number, length
from ...core.mechanism import Mechanism
from ...exceptions import InvalidInput, PoseUnreachable
from ...kinematics.mode_graph import Mode
from ...kinematics.singularity import normalised_margin
from ...results import Result, unit
from ...tolerances import PAIR_DISCRIMINANT_RTOL, PAIR_TOL, PRRRP_MODE_TOL
from .builder import LEFT_PAIR
from .layout import PrrrpLayout, resolve_layout

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


def _sym(v: int) -> str:
    return "+" if v > 0 else ("-" if v < 0 else "0")


def mode_label(mode: Sequence[int]) -> str:
    """An assembly mode as the paper writes it, e.g. ``[+ 0]``."""
    return "[" + " ".join(_sym(v) for v in mode) + "]"


def working_mode_label(mode: Sequence[int]) -> str:
    """A working mode as the paper writes it, e.g. ``(- + 0 +)``."""
    return "(" + " ".join(_sym(v) for v in mode) + ")"


@dataclass(frozen=True)
class PrrrpState(Result):
    r"""Geometry of a 2-PRRRP configuration: pairs, rods, modes, sub-mechanism margins.

    Attributes:
        heights: signed height :math:`q_j` of each pair above the stator (left, right) [m], shape (2,).
        pairs: pair positions (left, right) in the world [m], shape (2, 3).
        rods: unit rod vectors :math:`z_i` from slider to pair, one per leg present, shape (n_legs, 3).
        cosines: :math:`z_i^T a` per leg [-], shape (n_legs,).
        assembly_mode: sign of each pair height, 0 within :data:`PRRRP_MODE_TOL` (``[+ 0]`` etc.).
        working_mode: the paper's eq. (6) sign per leg, :math:`-\mathrm{sign}(z_i^T a)`, 0 within
            :data:`PRRRP_MODE_TOL` (``(- + 0 +)`` etc.).
        sub_direct_margin: per sub-mechanism, :math:`\sigma_{min}/\sigma_{max}` of its own
            direct Jacobian (rows :math:`z_{j1}^T, z_{j2}^T` in the plane, eq. (4)
            differentiated); zero at ``[0]`` and when its circles coincide; NaN for a pair
            held by one leg [-], shape (2,).
    """

    heights: np.ndarray = field(metadata=unit("m"))
    pairs: np.ndarray = field(metadata=unit("m"))
    rods: np.ndarray = field(metadata=unit("-"))
    cosines: np.ndarray = field(metadata=unit("-"))
    assembly_mode: Mode
    working_mode: Mode
    sub_direct_margin: np.ndarray = field(metadata=unit("-"))
    _DERIVED = ("assembly_mode_label", "working_mode_label")
    _NONFINITE_AS_TEXT = ("sub_direct_margin",)

    @property
    def assembly_mode_label(self) -> str:
        """The assembly mode as the paper writes it, e.g. ``[+ 0]``."""
        return mode_label(self.assembly_mode)

    @property
    def working_mode_label(self) -> str:
        """The working mode as the paper writes it, e.g. ``(- + 0 +)``."""
        return working_mode_label(self.working_mode)


def _sign(value: float, tol: float) -> int:
    return 0 if abs(value) <= tol else (1 if value > 0 else -1)


def prrrp_state(
    mech: Mechanism, q: ArrayLike, layout: PrrrpLayout | None = None, tol: float = PRRRP_MODE_TOL
) -> PrrrpState:
    """Pair heights, rod directions, assembly and working modes of a 2-PRRRP configuration.

    Args:
        mech: a 2-PRRRP of the :func:`plm_pin.families.prrrp.build_2prrrp` family.
        q: assembled configuration, shape (nq,).
        layout: its layout (read from the model when omitted).
        tol: heights [m] and cosines [-] at or below which a sign counts as 0.
    """
    lay = resolve_layout(mech, layout)
    tol = check_tolerance(tol, "tol")
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


def assembly_mode(
    mech: Mechanism, q: ArrayLike, layout: PrrrpLayout | None = None, tol: float = PRRRP_MODE_TOL
) -> Mode:
    """Assembly mode ``(left, right)`` of a 2-PRRRP configuration: the side of the stator of each pair."""
    return prrrp_state(mech, q, layout, tol).assembly_mode


def paper_working_modes(
    mech: Mechanism, q: ArrayLike, layout: PrrrpLayout | None = None, tol: float = PRRRP_MODE_TOL
) -> Mode:
    r"""Working mode of each leg (Harada 2015, eq. (6)): :math:`-\mathrm{sign}(z_i^T a)`, 0 at 90 deg."""
    return prrrp_state(mech, q, layout, tol).working_mode


@dataclass(frozen=True)
class PairSolutions(Result):
    """Direct kinematics of one PRRRP sub-mechanism, eq. (4): the intersections of two circles.

    Attributes:
        kind: ``two`` (assembly modes [+] and [-]), ``touching`` ([0], direct singularity),
            ``none`` (no assembly) or ``coincident`` (indefinite: complex singularity).
        points: pair positions along and normal to the stator ``(p, q)`` [m], [+] first,
            shape (k, 2) with k = 2, 1 or 0 (0 also when coincident: a whole circle).
    """

    kind: str
    points: np.ndarray = field(metadata=unit("m"))


def pair_solutions(c1: float, c2: float, l1: float, l2: float, tol: float = PAIR_TOL) -> PairSolutions:
    """Closed-form direct kinematics of a PRRRP sub-mechanism (Harada 2015, eq. (4)).

    The pair lies on the circles of radii ``l1``, ``l2`` [m] centred on the stator at the
    slider positions ``c1``, ``c2`` [m]; ``tol`` [m] decides touching and coincident circles.
    A cross-check of the generic forward kinematics, not used by the planners.

    Raises:
        InvalidInput: slider positions that are not finite numbers, rod lengths not > 0, or a
            ``tol`` that is not a finite number >= 0.
    """
    c1, c2 = finite_number(c1, "c1", "m"), finite_number(c2, "c2", "m")
    l1, l2, tol = length(l1, "l1"), length(l2, "l2"), check_tolerance(tol, "tol")
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
        mech: a 2-PRRRP of the :func:`plm_pin.families.prrrp.build_2prrrp` family.
        pose: plate pose ``(x [m], y [m], theta [rad])``.
        working_modes: the paper's sign per leg present, in leg order.
        layout: its layout (read from the model when omitted).

    Raises:
        PoseUnreachable: when a leg cannot reach its pair; the message names it and the miss.
    """
    lay = resolve_layout(mech, layout)
    x, y, theta = (float(v) for v in pose)
    if len(working_modes) != len(lay.legs):
        raise InvalidInput(f"give {len(lay.legs)} working modes, one per leg, got {list(working_modes)}")
    q = mech.neutral()
    rt = lay.half_plate
    phi1 = 0.0
    for leg, sigma in zip(lay.legs, working_modes, strict=True):
        arm = -rt if leg.pair == LEFT_PAIR else rt
        Lx, Ly = x + arm * math.cos(theta), y + arm * math.sin(theta)
        disc = leg.length**2 - Ly**2
        if disc < -PAIR_DISCRIMINANT_RTOL * leg.length**2:
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
