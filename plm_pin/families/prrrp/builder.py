r"""Parametric 2-PRRRP planar tables on one linear stator (Harada 2011, 2015).

Geometry (Harada 2011, eq. (1) and Fig. 5): every slider ``i`` moves along the world x
axis (the stator, :math:`a = [1, 0]^T`) at :math:`c_i`; rod ``i`` of length :math:`l_i`
joins slider ``i`` to a pair of the end plate, :math:`p + R(\theta) s_i = c_i a + l_i z_i`,
with :math:`s_1 = s_2 = [-r_t, 0]^T` (left pair) and :math:`s_3 = s_4 = [r_t, 0]^T` (right
pair). The plane is the world x-y plane, every revolute axis is z, gravity acts along -y.

Spanning tree: ``base -> slider1 -> rod1_pivot -> plate_pivot`` carries the plate; the
other legs end at ``rod<i>_tip`` frames closed on ``plate_left`` / ``plate_right`` by
``point`` closures (3 rows each, one of them redundant in the plane).

Working modes: the sign :math:`\sigma_i` in front of the square root of eq. (2). The
paper's text gives (+, -, +, -) for links 1-4, but its code (M.5) and its skeleton plots
(M.42) use (-, +, -, +): slider 1 left of the left pair, slider 2 right of it, and so on.
We follow the code, which produced the paper's figures.

Self-collision: the drawing puts every shape in the plane z = 0, but a real table stacks them
(as the 2-PRRRP presets' notes state): only the carriages share a layer, on the stator, and
can touch; the sidecar's ``self_collision.ignore`` lists every other pair of shapes on non-adjacent bodies.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

from ..._arguments import (
    finite_array,
    leg_numbers,
    length,
    nonnegative,
    numbers_of,
    optional_positive,
    signs,
)
from ..._lazy import lazy_module
from ...description import urdf_parts as u
from ...description.compliance import assumed_drive_stiffness
from ...description.sidecar import ActuatorSpec, ClosureSpec, Sidecar, TaskSpec
from ...exceptions import InvalidInput
from ...models.registry import HARADA2011_ROD, rod_scaled

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")

LEFT_LEGS = (1, 2)
"""Legs reaching the left plate pair."""

RIGHT_LEGS = (3, 4)
"""Legs reaching the right plate pair."""

LEFT_PAIR = "plate_left"
"""Frame of the left plate pair (the rod tips of legs 1-2)."""

RIGHT_PAIR = "plate_right"
"""Frame of the right plate pair (the rod tips of legs 3-4)."""

TASK_FRAME = "plate_center"
"""Task frame, midway between the pairs (x, y, rz)."""

CARRIAGE_SIZE = (0.03, 0.02, 0.01)
"""Box of each carriage (moving part of a linear motor): length along the stator, height, depth [m]."""


def leg_inverse_kinematics(
    pose: Sequence[float],
    rod_lengths: Sequence[float],
    half_plate: float,
    modes: Sequence[int],
    legs: Sequence[int],
) -> dict[int, tuple[float, float]]:
    r"""Slider position :math:`c_i` [m] and rod angle :math:`\varphi_i` [rad] of each leg.

    Closed form of Harada 2011 eqs. (2)-(3) with sign :math:`\sigma_i` = ``modes[i-1]``.

    Raises:
        ValueError: when a leg cannot reach its plate pair.
    """
    x, y, theta = pose
    out = {}
    for i in legs:
        s = -half_plate if i in LEFT_LEGS else half_plate
        Lx = x + s * math.cos(theta)
        Ly = y + s * math.sin(theta)
        l = rod_lengths[i - 1]
        disc = l * l - Ly * Ly
        if disc < 0.0:
            raise InvalidInput(f"leg {i} cannot reach its pair: |L_y| = {abs(Ly):.4g} m > l = {l:.4g} m")
        c = Lx + modes[i - 1] * math.sqrt(disc)
        out[i] = (c, math.atan2(Ly / l, (Lx - c) / l))
    return out


def build_2prrrp(
    *,
    name: str,
    rod_lengths: Sequence[float],
    half_plate: float,
    slider_mass: float,
    rod_masses: Sequence[float],
    rod_inertias: Sequence[float],
    plate_mass: float,
    plate_inertia: float,
    legs: Sequence[int] = (1, 2, 3, 4),
    reference_pose: Sequence[float] = (0.0, 0.08, 0.0),
    working_modes: Sequence[int] = (-1, 1, -1, 1),
    gravity: float = 9.81,
    actuator_stiffness: float | None = None,
    source: str = "",
) -> tuple[yourdfpy.Robot, Sidecar]:
    """Build a 2-PRRRP table (or a subset of its legs) as a URDF tree plus sidecar.

    Args:
        name: robot name.
        rod_lengths: :math:`l_1 .. l_4` [m].
        half_plate: :math:`r_t`, half the distance between the plate's pairs [m].
        slider_mass: mass of each moving part of the linear motor [kg].
        rod_masses: rod masses [kg].
        rod_inertias: rod moments of inertia about their centre, normal to the plane [kg m^2].
        plate_mass: end-plate mass [kg].
        plate_inertia: end-plate moment of inertia about its centre, normal to the plane [kg m^2].
        legs: legs present; leg 1 must be present (it carries the plate).
        reference_pose: plate pose ``(x [m], y [m], theta [rad])`` of the reference configuration.
        working_modes: sign of the square root of eq. (2) per leg.
        gravity: magnitude of gravity along -y [m/s^2].
        actuator_stiffness: stiffness of each linear motor along its guide [N/m], written
            into the sidecar's ``compliance`` (marked assumed), or None.
        source: provenance written into the sidecar.

    Returns:
        The URDF tree and its sidecar.

    Raises:
        InvalidInput: a length not > 0, a mass, inertia or gravity not >= 0, a pose that is not three
            finite numbers, working modes other than four signs, legs other than 1, 2 and at least one
            right leg, or a reference pose some leg cannot reach.
    """
    legs = leg_numbers(legs, "legs", 4)
    if 1 not in legs or not any(i in legs for i in RIGHT_LEGS) or 2 not in legs:
        raise InvalidInput(f"legs {legs}: legs 1 and 2 and at least one right leg are needed")
    rod_lengths = tuple(numbers_of(rod_lengths, "rod_lengths", 4, "lengths > 0 [m]", "positive").tolist())
    rt = length(half_plate, "half_plate")
    slider_mass = nonnegative(slider_mass, "slider_mass", "kg")
    rod_masses = tuple(numbers_of(rod_masses, "rod_masses", 4, "masses >= 0 [kg]", "nonnegative").tolist())
    rod_inertias = tuple(
        numbers_of(rod_inertias, "rod_inertias", 4, "inertias >= 0 [kg m^2]", "nonnegative").tolist()
    )
    plate_mass = nonnegative(plate_mass, "plate_mass", "kg")
    plate_inertia = nonnegative(plate_inertia, "plate_inertia", "kg m^2")
    reference_pose = tuple(
        finite_array(reference_pose, "reference_pose", (3,), "x [m], y [m], theta [rad]").tolist()
    )
    modes = signs(working_modes, "working_modes")
    if modes is None or len(modes) != 4 or any(m not in (-1, 1) for m in modes):
        raise InvalidInput(f"working_modes must be four signs (+1 or -1), one per leg, got {working_modes!r}")
    working_modes = modes
    gravity = nonnegative(gravity, "gravity", "m/s^2")
    optional_positive(actuator_stiffness, "actuator_stiffness", "N/m")
    try:
        ik = leg_inverse_kinematics(reference_pose, rod_lengths, rt, working_modes, legs)
    except InvalidInput as exc:
        raise InvalidInput(f"reference_pose {reference_pose} is out of reach: {exc}") from None
    links: list[yourdfpy.Link] = []
    joints: list[yourdfpy.Joint] = []
    stator = 1.0
    links.append(u.link("base", visuals=[u.box_visual((stator, 0.01, 0.004), "base", (0.0, -0.01, -0.01))]))
    slider_size = CARRIAGE_SIZE
    reference: dict[str, tuple[float, ...]] = {}
    closures: list[ClosureSpec] = []
    for i in legs:
        l, m, inertia = rod_lengths[i - 1], rod_masses[i - 1], rod_inertias[i - 1]
        links.append(
            u.link(
                f"carriage{i}",
                slider_mass,
                u.box_inertia(slider_mass, slider_size),
                visuals=[u.box_visual(slider_size, "slider")],
            )
        )
        joints.append(
            u.joint(
                f"slider{i}",
                "prismatic",
                "base",
                f"carriage{i}",
                axis=(1, 0, 0),
                limits=(-stator / 2, stator / 2),
            )
        )
        # rod along its local x; axial inertia of a 5 mm radius bar, transverse ones as given
        axial = 0.5 * m * 0.005**2
        links.append(
            u.link(
                f"rod{i}",
                m,
                (axial, inertia, inertia),
                com=(l / 2, 0.0, 0.0),
                visuals=[u.box_visual((l, 0.008, 0.004), "rod", (l / 2, 0.0, 0.0))],
            )
        )
        joints.append(u.joint(f"rod{i}_pivot", "revolute", f"carriage{i}", f"rod{i}"))
        c, phi = ik[i]
        reference[f"slider{i}"] = (c,)
        reference[f"rod{i}_pivot"] = (phi,)
        if i != 1:
            links.append(u.link(f"rod{i}_tip"))
            joints.append(u.joint(f"rod{i}_tip_fixed", "fixed", f"rod{i}", f"rod{i}_tip", xyz=(l, 0.0, 0.0)))
            pair = LEFT_PAIR if i in LEFT_LEGS else RIGHT_PAIR
            closures.append(ClosureSpec(f"rod{i}_{pair}", (f"rod{i}_tip", pair), "point"))
    axial = plate_mass * 0.01**2 / 6.0
    links.append(
        u.link(
            "plate",
            plate_mass,
            (axial, plate_inertia, plate_inertia),
            com=(rt, 0.0, 0.0),
            visuals=[u.box_visual((2 * rt + 0.02, 0.012, 0.006), "plate", (rt, 0.0, 0.0))],
        )
    )
    joints.append(u.joint("plate_pivot", "revolute", "rod1", "plate", xyz=(rod_lengths[0], 0.0, 0.0)))
    for frame, x in ((LEFT_PAIR, 0.0), (TASK_FRAME, rt), (RIGHT_PAIR, 2 * rt)):
        links.append(u.link(frame))
        joints.append(u.joint(f"{frame}_fixed", "fixed", "plate", frame, xyz=(x, 0.0, 0.0)))
    reference["plate_pivot"] = (reference_pose[2] - ik[1][1],)
    robot = yourdfpy.Robot(name=name, links=links, joints=joints)
    sidecar = Sidecar(
        closures=tuple(closures),
        actuation=tuple(ActuatorSpec(f"slider{i}") for i in legs),
        task=TaskSpec(TASK_FRAME, ("x", "y", "rz")),
        gravity=(0.0, -gravity, 0.0),
        reference={k: tuple(float(x) for x in v) for k, v in reference.items()},
        name=name,
        source=source,
        compliance=assumed_drive_stiffness([f"slider{i}" for i in legs], actuator_stiffness),
        collision_ignore=_other_layers(legs),
    )
    return robot, sidecar


def _other_layers(legs: Sequence[int]) -> tuple[tuple[str, str], ...]:
    """The body pairs in different layers of the real table (see the module docstring), not yet adjacent.

    Adjacent pairs (a rod and its carriage, a rod and the plate) are left out by the checker.
    """
    pairs = [(f"rod{i}", f"rod{j}") for i in legs for j in legs if i < j]
    pairs += [(f"rod{i}", f"carriage{j}") for i in legs for j in legs if i != j]
    pairs += [("plate", f"carriage{i}") for i in legs]
    return tuple(pairs)


def symmetric_rods(rod_length: float) -> dict[str, tuple[float, ...]]:
    """Builder parameters of four equal rods ``rod_length`` [m] long, for :func:`build_2prrrp`.

    Masses and inertias scale from the Harada 2011 rod (140 mm, 0.026 kg, 9.84e-5 kg m^2,
    Table 1) by :func:`~plm_pin.models.registry.rod_scaled`, as in the 2015 preset. Give them to
    :func:`plm_pin.build_mechanism` with a 2-PRRRP preset to rebuild it with equal rods.

    Raises:
        InvalidInput: a rod length that is not a positive finite number.
    """
    if not (isinstance(rod_length, (int, float)) and math.isfinite(rod_length) and rod_length > 0.0):
        raise InvalidInput(f"rod_length must be a positive length [m], got {rod_length!r}")
    mass, inertia = rod_scaled(float(rod_length), *HARADA2011_ROD)
    return {"rod_lengths": (rod_length,) * 4, "rod_masses": (mass,) * 4, "rod_inertias": (inertia,) * 4}
