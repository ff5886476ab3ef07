"""Classic small closed chains for tests and comparisons: the four-bar and the five-bar.

Both are planar in the world x-y plane with revolute axes along z and gravity along -y;
links are uniform bars of ``density`` [kg/m] with centroidal inertia :math:`m L^2 / 12`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..._arguments import finite_array, finite_number, length, nonnegative
from ..._lazy import lazy_module
from ...description import urdf_parts as u
from ...description.sidecar import ActuatorSpec, ClosureSpec, Sidecar, TaskSpec
from ...exceptions import InvalidInput

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")


def _bar(name: str, length: float, density: float) -> yourdfpy.Link:
    m = density * length
    transverse = m * length**2 / 12.0
    return u.link(
        name,
        m,
        (0.5 * m * 0.005**2, transverse, transverse),
        com=(length / 2, 0.0, 0.0),
        visuals=[u.box_visual((length, 0.012, 0.006), "rod", (length / 2, 0.0, 0.0))],
    )


def _circle_intersection(p0: np.ndarray, r0: float, p1: np.ndarray, r1: float, upper: bool) -> np.ndarray:
    d = float(np.linalg.norm(p1 - p0))
    a = (r0**2 - r1**2 + d**2) / (2 * d)
    h = math.sqrt(r0**2 - a**2)
    mid = p0 + a * (p1 - p0) / d
    normal = np.array([-(p1 - p0)[1], (p1 - p0)[0]]) / d
    return mid + (h if upper else -h) * normal


def _angle(v: np.ndarray) -> float:
    return math.atan2(float(v[1]), float(v[0]))


def _check_triangle(d: float, r0: float, r1: float, bars: str, what: str) -> None:
    """Refuse ``bars`` ``r0``, ``r1`` [m] whose pivots, ``d`` [m] apart, cannot meet (``what`` says where)."""
    if not abs(r0 - r1) <= d <= r0 + r1:
        raise InvalidInput(
            f"{what}: the {bars} ({r0:.6g} m, {r1:.6g} m) cannot meet: their pivots are {d:.6g} m apart, "
            f"outside [{abs(r0 - r1):.6g}, {r0 + r1:.6g}] m"
        )


def _bar_parameters(density: object, gravity: object, **lengths: object) -> None:
    """Check the lengths [m] (> 0), the density [kg/m] and the gravity [m/s^2] (>= 0) of a classic chain."""
    for key, value in lengths.items():
        length(value, key)
    nonnegative(density, "density", "kg/m")
    nonnegative(gravity, "gravity", "m/s^2")


def build_fourbar(
    *,
    name: str = "fourbar",
    crank: float = 0.10,
    coupler: float = 0.25,
    rocker: float = 0.20,
    ground: float = 0.30,
    density: float = 2.0,
    crank_angle: float = math.radians(60.0),
    gravity: float = 9.81,
    source: str = "",
) -> tuple[yourdfpy.Robot, Sidecar]:
    """A crank-rocker four-bar, the crank at the origin and the rocker pivot at ``(ground, 0)``.

    Args:
        name: robot name.
        crank: crank length [m].
        coupler: coupler length [m].
        rocker: rocker length [m].
        ground: distance between the fixed pivots [m].
        density: mass per length of every moving bar [kg/m].
        crank_angle: crank angle of the reference configuration [rad].
        gravity: gravity along -y [m/s^2].
        source: provenance.

    Raises:
        InvalidInput: a length not > 0, a density or gravity not >= 0, a crank angle not finite, or a
            crank angle where coupler and rocker cannot close the loop.
    """
    _bar_parameters(density, gravity, crank=crank, coupler=coupler, rocker=rocker, ground=ground)
    finite_number(crank_angle, "crank_angle", "rad")
    A = crank * np.array([math.cos(crank_angle), math.sin(crank_angle)])
    D = np.array([ground, 0.0])
    _check_triangle(
        float(np.linalg.norm(D - A)),
        coupler,
        rocker,
        "coupler and rocker",
        f"crank_angle = {crank_angle:.6g} rad",
    )
    links = [
        u.link("base", visuals=[u.box_visual((ground, 0.01, 0.004), "base", (ground / 2, -0.02, -0.01))]),
        _bar("crank", crank, density),
        _bar("coupler", coupler, density),
        _bar("rocker", rocker, density),
        u.link("coupler_tip"),
        u.link("rocker_tip"),
    ]
    joints = [
        u.joint("crank_pivot", "revolute", "base", "crank"),
        u.joint("coupler_pivot", "revolute", "crank", "coupler", xyz=(crank, 0.0, 0.0)),
        u.joint("rocker_pivot", "revolute", "base", "rocker", xyz=(ground, 0.0, 0.0)),
        u.joint("coupler_tip_fixed", "fixed", "coupler", "coupler_tip", xyz=(coupler, 0.0, 0.0)),
        u.joint("rocker_tip_fixed", "fixed", "rocker", "rocker_tip", xyz=(rocker, 0.0, 0.0)),
    ]
    B = _circle_intersection(A, coupler, D, rocker, upper=True)
    reference = {
        "crank_pivot": (crank_angle,),
        "coupler_pivot": (_angle(B - A) - crank_angle,),
        "rocker_pivot": (_angle(B - D),),
    }
    sidecar = Sidecar(
        closures=(ClosureSpec("coupler_rocker", ("coupler_tip", "rocker_tip"), "point"),),
        actuation=(ActuatorSpec("crank_pivot"),),
        task=TaskSpec("rocker", ("rz",)),
        gravity=(0.0, -gravity, 0.0),
        reference=reference,
        name=name,
        source=source,
    )
    return yourdfpy.Robot(name=name, links=links, joints=joints), sidecar


def build_fivebar(
    *,
    name: str = "fivebar",
    base: float = 0.20,
    proximal: float = 0.15,
    distal: float = 0.20,
    density: float = 2.0,
    tip: tuple[float, float] = (0.02, 0.25),
    gravity: float = 9.81,
    source: str = "",
) -> tuple[yourdfpy.Robot, Sidecar]:
    """A symmetric RRRRR five-bar with motors at ``(-base/2, 0)`` and ``(base/2, 0)``.

    Args:
        name: robot name.
        base: distance between the motors [m].
        proximal: length of the driven links [m].
        distal: length of the links meeting at the tip [m].
        density: mass per length of every moving bar [kg/m].
        tip: tip position of the reference configuration [m] (elbows outward).
        gravity: gravity along -y [m/s^2].
        source: provenance.

    Raises:
        InvalidInput: a length not > 0, a density or gravity not >= 0, a tip that is not two finite
            numbers or that a side cannot reach.
    """
    _bar_parameters(density, gravity, base=base, proximal=proximal, distal=distal)
    tip_xy = finite_array(tip, "tip", (2,), "coordinates [m]")
    for side, x0 in (("left", -base / 2), ("right", base / 2)):
        reach = float(np.linalg.norm(tip_xy - (x0, 0.0)))
        _check_triangle(
            reach,
            proximal,
            distal,
            "proximal and distal links",
            f"tip {tuple(tip_xy.tolist())} m, {side} side",
        )
    links = [u.link("base", visuals=[u.box_visual((base, 0.01, 0.004), "base", (0.0, -0.02, -0.01))])]
    joints = []
    reference: dict[str, tuple[float, ...]] = {}
    P = np.array(tip, dtype=float)
    for side, x0, outward in (("left", -base / 2, True), ("right", base / 2, False)):
        O = np.array([x0, 0.0])
        # elbow outward: left elbow on the left of the line O->P, right elbow on its right
        E = _circle_intersection(O, proximal, P, distal, upper=outward)
        links += [
            _bar(f"{side}_proximal", proximal, density),
            _bar(f"{side}_distal", distal, density),
            u.link(f"{side}_tip"),
        ]
        joints += [
            u.joint(f"{side}_motor", "revolute", "base", f"{side}_proximal", xyz=(x0, 0.0, 0.0)),
            u.joint(
                f"{side}_elbow", "revolute", f"{side}_proximal", f"{side}_distal", xyz=(proximal, 0.0, 0.0)
            ),
            u.joint(f"{side}_tip_fixed", "fixed", f"{side}_distal", f"{side}_tip", xyz=(distal, 0.0, 0.0)),
        ]
        a1 = _angle(E - O)
        reference[f"{side}_motor"] = (a1,)
        reference[f"{side}_elbow"] = (_angle(P - E) - a1,)
    sidecar = Sidecar(
        closures=(ClosureSpec("tip", ("left_tip", "right_tip"), "point"),),
        actuation=(ActuatorSpec("left_motor"), ActuatorSpec("right_motor")),
        task=TaskSpec("left_tip", ("x", "y")),
        gravity=(0.0, -gravity, 0.0),
        reference=reference,
        name=name,
        source=source,
    )
    return yourdfpy.Robot(name=name, links=links, joints=joints), sidecar
