r"""The complex (constraint) singularity of a 2-PRRRP sub-mechanism (Harada 2015, Fig. 7).

:func:`complex_singularity_check` shows that equal rods in a sub-mechanism admit the
complex (constraint) singularity: when one rod is perpendicular to the stator the other
must be too, the two sliders share a position, the two circles of eq. (4) coincide, and
the closure Jacobian loses rank; with unequal rods (``harada2015_asymmetric``) it cannot
happen, since :math:`|c_{j1} - c_{j2}| \ge |l_{j1} - l_{j2}| > 0`.

Units: lengths [m], angles [rad], margins are normalised singular-value ratios [-].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...core.mechanism import Mechanism
from ...core.rank import numerical_rank
from ...exceptions import ClosureNotSatisfied, InvalidInput, PoseUnreachable
from ...kinematics.jacobians import closed_chain_jacobians
from ...kinematics.singularity import SingularityReport, report_from_jacobians
from ...results import Result, unit
from ...tolerances import EQUAL_RODS_TOL, FOLD_PAIR_TOL, RIGHT_ANGLE_TOL, SINGULARITY_TOL
from .layout import prrrp_layout
from .modes import pair_solutions, prrrp_configuration, prrrp_state
from .planners import fold_plan


@dataclass(frozen=True)
class CoincidentCircleSample(Result):
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

    rod_angle: float = field(metadata=unit("rad"))
    slider_gap: float = field(metadata=unit("m"))
    sub_rank: int
    sub_direct_margin: float = field(metadata=unit("-"))
    report: SingularityReport


@dataclass(frozen=True)
class ComplexSingularityCase(Result):
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
    rod_lengths: tuple[float, float] = field(metadata=unit("m"))
    q_fold: np.ndarray = field(metadata=unit("m, rad"))
    report: SingularityReport
    slider_gap: float = field(metadata=unit("m"))
    circles: str
    closure_rank: int
    generic_closure_rank: int
    min_slider_gap: float = field(metadata=unit("m"))
    coincident: tuple[CoincidentCircleSample, ...]
    _DERIVED = ("admits_complex_singularity",)

    @property
    def admits_complex_singularity(self) -> bool:
        """Whether the closure Jacobian loses rank at the fold (``constraint`` kind)."""
        return "constraint" in self.report.kinds


def complex_singularity_check(
    mech: Mechanism,
    leg: int = 3,
    guess: ArrayLike | None = None,
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
    q0 = mech.q_ref if guess is None else mech.check_q(guess, "guess")
    g, sub, j, x_pair, side, pose, tilt_sign = fold_plan(mech, lay, leg, q0, tilt)
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
    if abs(partner.length - g.length) <= EQUAL_RODS_TOL:  # equal rods: the partner is perpendicular too
        modes[[lg.index for lg in lay.legs].index(partner.index)] = 0
    q_fold = prrrp_configuration(mech, (x, y, theta), modes, lay)
    jac = closed_chain_jacobians(mech, q_fold)
    report = report_from_jacobians(mech, jac, tol)
    c = mech.actuator_positions(q_fold)
    circles = pair_solutions(
        c[g.actuator], c[partner.actuator], g.length, partner.length, tol=FOLD_PAIR_TOL
    ).kind
    coincident: list[CoincidentCircleSample] = []
    if abs(partner.length - g.length) <= EQUAL_RODS_TOL:
        k_leg = [lg.index for lg in lay.legs].index(leg)
        k_partner = [lg.index for lg in lay.legs].index(partner.index)
        for angle in (math.radians(50.0), math.radians(70.0), math.pi / 2):
            # both rods at the same angle from the stator: the pair at (c + l cos, l sin)
            h = side * g.length * math.sin(angle)
            yy = h + arm * math.sin(theta)
            m2 = list(modes0)
            sigma = 0 if abs(angle - math.pi / 2) < RIGHT_ANGLE_TOL else modes0[k_leg]
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
