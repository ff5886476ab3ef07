r"""The 2-PRRRP structure of a mechanism: legs, plate pairs (sub-mechanisms) and stator line.

For the family of :func:`plm_pin.families.prrrp.build_2prrrp`: legs are found by their joint
names, the pairs by the frames :data:`~plm_pin.families.prrrp.builder.LEFT_PAIR` and
:data:`~plm_pin.families.prrrp.builder.RIGHT_PAIR`, the stator line and rod lengths are measured
on the assembled reference configuration (Harada 2015, Fig. 1(b)).

Units: lengths [m].
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..._text import short
from ...core.mechanism import Mechanism
from ...exceptions import InvalidInput
from ...results import Result, unit
from ...tolerances import LAYOUT_TOL
from .builder import LEFT_LEGS, LEFT_PAIR, RIGHT_LEGS, RIGHT_PAIR, TASK_FRAME

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

_PAIRS = {i: LEFT_PAIR for i in LEFT_LEGS} | {i: RIGHT_PAIR for i in RIGHT_LEGS}


@dataclass(frozen=True)
class PrrrpLeg(Result):
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
    length: float = field(metadata=unit("m"))
    actuator: int


@dataclass(frozen=True)
class PrrrpSubMechanism(Result):
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
class PrrrpLayout(Result):
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
    direction: np.ndarray = field(metadata=unit("-"))
    normal: np.ndarray = field(metadata=unit("-"))
    origin: np.ndarray = field(metadata=unit("m"))
    half_plate: float = field(metadata=unit("m"))

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


def prrrp_layout(mech: Mechanism) -> PrrrpLayout:
    """Read the 2-PRRRP structure of a mechanism built by :func:`plm_pin.families.prrrp.build_2prrrp`.

    Legs are found by their joint names (``slider<i>`` actuated, ``rod<i>_pivot``); rod
    lengths, the stator line and the plate are measured on the assembled reference
    configuration. The task must be ``plate_center`` with ``x y rz``, midway between the pairs.

    Raises:
        InvalidInput: when the mechanism is not of this family; the message says what is missing.
    """
    model, data = mech.model, mech.model.createData()
    actuated = {a.joint: k for k, a in enumerate(mech.actuators)}
    missing = [f for f in (LEFT_PAIR, RIGHT_PAIR, TASK_FRAME) if not model.existFrame(f)]
    if missing:
        raise InvalidInput(
            f"{mech.name} is not a 2-PRRRP of plm_pin.families.prrrp.build_2prrrp: "
            f"frames {missing} are missing"
        )
    task = mech.task
    if task is None or task.frame != TASK_FRAME or tuple(task.dofs) != ("x", "y", "rz"):
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
    if (
        len(legs) < 3
        or not any(g.index in LEFT_LEGS for g in legs)
        or not any(g.index in RIGHT_LEGS for g in legs)
    ):
        raise InvalidInput(
            f"{mech.name} is not a 2-PRRRP of plm_pin.families.prrrp.build_2prrrp: legs found "
            f"{[g.index for g in legs]}; need joints slider<i> and rod<i>_pivot on both pairs"
        )
    a, w, origin = axes[0]
    for a2, w2, o2 in axes[1:]:
        off = o2 - origin
        if (
            np.linalg.norm(a2 - a) > LAYOUT_TOL
            or np.linalg.norm(w2 - w) > LAYOUT_TOL
            or np.linalg.norm(off - (off @ a) * a) > LAYOUT_TOL
        ):
            raise InvalidInput(f"{mech.name}: the sliders do not share one stator line and one plane")
    if np.linalg.norm(a - np.array([1.0, 0.0, 0.0])) > LAYOUT_TOL or np.linalg.norm(origin) > LAYOUT_TOL:
        raise InvalidInput(f"{mech.name}: the stator must be the world x axis (the builder's convention)")
    normal = np.cross(w, a)
    p_left = data.oMf[model.getFrameId(LEFT_PAIR)].translation
    p_right = data.oMf[model.getFrameId(RIGHT_PAIR)].translation
    centre = data.oMf[model.getFrameId(TASK_FRAME)].translation
    if np.linalg.norm(centre - 0.5 * (p_left + p_right)) > LAYOUT_TOL:
        raise InvalidInput(f"{mech.name}: plate_center must lie midway between the pairs")
    subs = (
        PrrrpSubMechanism("left", LEFT_PAIR, tuple(g.index for g in legs if g.index in LEFT_LEGS)),
        PrrrpSubMechanism("right", RIGHT_PAIR, tuple(g.index for g in legs if g.index in RIGHT_LEGS)),
    )
    return PrrrpLayout(
        tuple(legs), subs, a.copy(), normal, origin.copy(), float(0.5 * np.linalg.norm(p_right - p_left))
    )


def resolve_layout(mech: Mechanism, layout: PrrrpLayout | None) -> PrrrpLayout:
    """The given layout, or the one read from the model by :func:`prrrp_layout` when None."""
    if layout is not None and not isinstance(layout, PrrrpLayout):
        raise InvalidInput(f"layout must be a PrrrpLayout (prrrp_layout(mech)) or None, got {short(layout)}")
    return prrrp_layout(mech) if layout is None else layout
