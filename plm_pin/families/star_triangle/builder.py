r"""Parametric planar 3-PRP star-triangle XY-theta machine tool (Enferadi 2017).

Enferadi & Tavakolian, Period. Polytech. Mech. Eng. 61(2) 107-114, 2017. The figures are
missing from the text; the geometry below is rebuilt from the constraint equations
:math:`\Lambda_1 .. \Lambda_9` (1), :math:`\Gamma_1 .. \Gamma_3` (2) and the inverse
kinematics (3)-(5).

World frame: origin at vertex :math:`V_1` of the equilateral base of side :math:`a`
(:math:`a = a_i = L_f`), x along the side :math:`V_1 V_3`, y into the triangle, z out of
the plane. :math:`\Lambda_1`-:math:`\Lambda_6` pin this down: rail 1 starts at the origin,
rail 3 starts at :math:`(a_3, 0)` and runs toward -x (:math:`a_3 - q_3`), and
:math:`\Lambda_6` (:math:`y = \rho_3 \sin\varphi`) puts side 3 on the x axis. The vertices
are :math:`V_1 = (0, 0)`, :math:`V_2 = (a/2, a\sqrt{3}/2)`, :math:`V_3 = (a, 0)`. The rails
run round the triangle:

========  =========  ====================  ==============================  ==============
rail i    side       origin :math:`P_i`    unit direction :math:`a_i`      angle
========  =========  ====================  ==============================  ==============
1         V1 -> V2   (0, 0)                (1/2, sqrt(3)/2)                +60 deg
2         V2 -> V3   (a/2, a sqrt(3)/2)    (1/2, -sqrt(3)/2)               -60 deg
3         V3 -> V1   (a, 0)                (-1, 0)                         180 deg
========  =========  ====================  ==============================  ==============

The actuated coordinate :math:`q_i` is the distance of slider point :math:`A_i` from
:math:`P_i` along :math:`a_i`, :math:`A_i = P_i + q_i a_i`, stroke :math:`[0, a]`.

Moving star: three lines through its centre :math:`C = (x, y)` (end effector and mass
centre), 120 deg apart. The direction of star line ``i`` from :math:`A_i` toward
:math:`C` is :math:`u_i = (\cos\psi_i, \sin\psi_i)` with :math:`\psi_1 = \varphi -
\alpha_1`, :math:`\psi_2 = \varphi + \alpha_3`, :math:`\psi_3 = \varphi` (:math:`\alpha_i
= 2\pi/3`), so :math:`\varphi` is the absolute angle of star line 3 and :math:`C = A_i +
\rho_i u_i`, :math:`\rho_i \ge 0` the distance from :math:`A_i` to :math:`C`. The paper's
:math:`s_i` in (3) is :math:`-u_i`. At :math:`\varphi = \pi/2` every :math:`u_i` is the
inward normal of side ``i``: :math:`A_i` is the foot of the perpendicular from :math:`C`
and the velocity Jacobian is the identity. :math:`\varphi = 0, \pi` are actuator
singularities (a star line parallel to its rail).

Legs: P-R-P with zero leg length (:math:`r_i = 0`): the actuated prismatic (slider, mass
:math:`m_a`), a revolute about z at :math:`A_i`, and the intermediate link (mass
:math:`m_{il}`, inertia :math:`I_{il}`, mass centre on the revolute axis at :math:`A_i`)
whose guide slides along star line ``i``. It translates with the slider and turns with
the star, as in eq. (20). The star has mass :math:`m_p` and inertia :math:`I_p` about
:math:`C`.

Spanning tree: ``base -> slider1 (prismatic, actuated) -> pivot1 (revolute) -> arm1
(prismatic along star line 1) -> star``; legs 2 and 3 hang from the star, ``star -> arm<i>
-> il<i>``, and their revolutes at :math:`A_i` are cut. Each cut is a ``point`` closure
between the frames ``il<i>`` and ``carriage<i>``, which both sit at :math:`A_i` (3 rows, the
z row identically zero). Joint names: ``slider<i>`` (prismatic along :math:`a_i`, child
``carriage<i>``), ``pivot1`` (value :math:`\varphi - \pi/2`), ``arm<i>`` (value
:math:`\rho_i`). URDF position limits (not in the paper, not enforced by plm_pin): sliders
and arms :math:`[0, a]`, ``pivot1`` :math:`(-\pi/2, \pi/2)`, the range of :math:`\varphi`
free of actuator singularities. The plane is horizontal (section 4: "the potential energy is zero"), so
gravity is along -z and does no work.

Typos of the paper that matter here (evidence in the preset's notes):

* :math:`\Gamma_2` prints :math:`q_1 \cos\theta_1`, :math:`q_1 \sin\theta_1` for
  :math:`a_1 \cos\theta_1`, :math:`a_1 \sin\theta_1` (:math:`\Lambda_3`,
  :math:`\Lambda_4` and :math:`b_{32}` of (30) have :math:`a_1`; the printed form is not
  satisfied by the geometry).
* :math:`\Lambda_4` prints :math:`+q_2 \sin\theta_2`; rail 2 runs from :math:`V_2` down to
  :math:`V_3`, so it is :math:`-q_2 \sin\theta_2` with :math:`\theta_2 = 60^\circ` (or
  :math:`\theta_2 = -60^\circ` as an absolute angle); section 6's
  ":math:`\theta_i = 60^\circ`" is a magnitude.
* (12) writes :math:`+\dot\rho_i s_i`, inconsistent with (3); the term drops out of (14).
* (7) orders the twist :math:`[\varphi, x, y]` while (24)-(34) use :math:`[x, y, \varphi]`;
  plm_pin's task is ``[x, y, rz]`` with ``rz`` = :math:`\varphi`.
* :math:`I_{il} = 37.5` and :math:`I_p = 25` kg m^2 on 3 kg and 2 kg bodies of a 0.5 m
  machine (radius of gyration 3.5 m) are implausible, perhaps kg cm^2; they are kept as
  printed (they do not enter the section 6 paths, where :math:`\dot\varphi = 0`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..._arguments import finite_array, length, nonnegative
from ..._lazy import lazy_module
from ...description import urdf_parts as u
from ...description.sidecar import ActuatorSpec, ClosureSpec, Sidecar, TaskSpec
from ...exceptions import InvalidInput
from ...tolerances import STAR_SINGULAR_SIN

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")

ALPHA = 2.0 * math.pi / 3.0
"""Angle between two lines of the star, :math:`\\alpha_i` [rad]."""

LEGS = (1, 2, 3)

# Angle of star line i (from A_i toward C) relative to the star's angle phi [rad].
_LINE_OFFSET = {1: -ALPHA, 2: ALPHA, 3: 0.0}


def rails(side: float) -> tuple[np.ndarray, np.ndarray]:
    """Rail origins :math:`P_i` [m] and unit directions :math:`a_i`, each shape (3, 2).

    Args:
        side: side length :math:`a` of the equilateral base [m].
    """
    h = side * math.sqrt(3.0) / 2.0
    origins = np.array([[0.0, 0.0], [side / 2.0, h], [side, 0.0]])  # (3, 2)
    angles = (math.pi / 3.0, -math.pi / 3.0, math.pi)
    directions = np.array([[math.cos(t), math.sin(t)] for t in angles])  # (3, 2)
    directions[2] = (-1.0, 0.0)  # exact: cos(pi) has no rounding error but sin(pi) does
    return origins, directions


def star_triangle_inverse_kinematics(pose: Sequence[float], side: float) -> tuple[np.ndarray, np.ndarray]:
    r"""Slider positions :math:`q_i` [m] and arm lengths :math:`\rho_i` [m] of a star pose.

    Eqs. (4)-(5) of Enferadi 2017 with :math:`s_i = -u_i` (the sign cancels):

    .. math::
        q_i = \frac{u_i^T E (c - P_i)}{u_i^T E a_i}, \qquad
        \rho_i = \frac{a_i^T E (c - P_i)}{a_i^T E u_i},

    with :math:`E` the 90 deg rotation; both denominators are :math:`\pm\sin\varphi`.

    Args:
        pose: star pose ``(x [m], y [m], phi [rad])``.
        side: side length :math:`a` of the base [m].

    Returns:
        ``(q, rho)``, each shape (3,).

    Raises:
        ValueError: at an actuator singularity (:math:`\sin\varphi = 0`).
    """
    x, y, phi = (float(v) for v in pose)
    if abs(math.sin(phi)) < STAR_SINGULAR_SIN:
        raise InvalidInput(f"phi = {phi:.6g} rad: star lines parallel to their rails (sin phi = 0)")
    origins, directions = rails(side)
    q = np.empty(3)
    rho = np.empty(3)
    for k, i in enumerate(LEGS):
        psi = phi + _LINE_OFFSET[i]
        u = (math.cos(psi), math.sin(psi))
        a = (float(directions[k][0]), float(directions[k][1]))
        d = (x - float(origins[k][0]), y - float(origins[k][1]))
        # u^T E v = -(u x v): the signs cancel in each ratio. Plain float arithmetic (no BLAS)
        # keeps the written preset identical on every machine.
        q[k] = _cross(u, d) / _cross(u, a)
        rho[k] = _cross(a, d) / _cross(a, u)
    return q, rho


def _cross(u: tuple[float, float], v: tuple[float, float]) -> float:
    """Planar cross product u_x v_y - u_y v_x."""
    return u[0] * v[1] - u[1] * v[0]


def build_star_triangle(
    *,
    name: str,
    side: float,
    slider_mass: float,
    link_mass: float,
    link_inertia: float,
    star_mass: float,
    star_inertia: float,
    reference_pose: Sequence[float] | None = None,
    gravity: float = 9.81,
    source: str = "",
) -> tuple[yourdfpy.Robot, Sidecar]:
    r"""Build the 3-PRP star-triangle machine tool as a URDF tree plus sidecar.

    Args:
        name: robot name.
        side: side length :math:`a` of the equilateral base, also the rail length [m].
        slider_mass: :math:`m_a`, mass of each actuated slider [kg].
        link_mass: :math:`m_{il}`, mass of each intermediate link [kg].
        link_inertia: :math:`I_{il}`, intermediate-link inertia about its mass centre,
            normal to the plane [kg m^2].
        star_mass: :math:`m_p`, mass of the moving star [kg].
        star_inertia: :math:`I_p`, star inertia about its centre, normal to the plane [kg m^2].
        reference_pose: star pose ``(x [m], y [m], phi [rad])`` of the reference
            configuration; default the start of section 6's vertical line,
            :math:`(a/2, a/2 + a/5, \pi/2)`.
        gravity: magnitude of gravity along -z [m/s^2] (normal to the plane, no work).
        source: provenance written into the sidecar.

    Returns:
        The URDF tree and its sidecar.

    Raises:
        InvalidInput: a side not > 0, a mass, inertia or gravity not >= 0, a reference pose that
            is not three finite numbers, puts a slider off its rail or an arm length below zero,
            or is an actuator singularity.
    """
    a = length(side, "side")
    for key, value, unit in (
        ("slider_mass", slider_mass, "kg"),
        ("link_mass", link_mass, "kg"),
        ("link_inertia", link_inertia, "kg m^2"),
        ("star_mass", star_mass, "kg"),
        ("star_inertia", star_inertia, "kg m^2"),
        ("gravity", gravity, "m/s^2"),
    ):
        nonnegative(value, key, unit)
    if reference_pose is None:
        pose = (a / 2.0, 0.7 * a, math.pi / 2.0)
    else:
        pose = tuple(finite_array(reference_pose, "reference_pose", (3,), "x [m], y [m], phi [rad]").tolist())
    q, rho = star_triangle_inverse_kinematics(pose, a)
    for k, i in enumerate(LEGS):
        if not (0.0 <= q[k] <= a and rho[k] >= 0.0):
            raise InvalidInput(
                f"reference pose {pose}: leg {i} has q = {q[k]:.4g} m (stroke [0, {a:.4g}]) and "
                f"rho = {rho[k]:.4g} m (must be >= 0)"
            )
    origins, directions = rails(a)
    height = a * math.sqrt(3.0) / 2.0
    links: list[yourdfpy.Link] = []
    joints: list[yourdfpy.Joint] = []

    # Base: one bar per rail, below the plane of motion.
    rail_visuals = []
    for k in range(3):
        yaw = math.atan2(directions[k][1], directions[k][0])
        mid = origins[k] + 0.5 * a * directions[k]
        rail_visuals.append(u.box_visual((a, 0.012, 0.006), "base", (mid[0], mid[1], -0.012), (0, 0, yaw)))
    links.append(u.link("base", visuals=rail_visuals))

    slider_size = (0.04, 0.03, 0.01)
    # The intermediate link's inertia normal to the plane is the paper's; the in-plane ones
    # (never excited in the plane) are half of it, as for a thin disc, to keep the URDF valid.
    link_inertia_diag = (link_inertia / 2.0, link_inertia / 2.0, link_inertia)
    for k, i in enumerate(LEGS):
        links.append(
            u.link(
                f"carriage{i}",
                slider_mass,
                u.box_inertia(slider_mass, slider_size),
                visuals=[u.box_visual(slider_size, "slider", (0.0, 0.0, -0.004))],
            )
        )
        yaw = math.atan2(directions[k][1], directions[k][0])
        joints.append(
            u.joint(
                f"slider{i}",
                "prismatic",
                "base",
                f"carriage{i}",
                xyz=(origins[k][0], origins[k][1], 0.0),
                rpy=(0.0, 0.0, yaw),
                axis=(1, 0, 0),
                limits=(0.0, a),
            )
        )
        # Intermediate link: frame at A_i, x along star line i toward C, mass centre at A_i.
        links.append(
            u.link(
                f"il{i}",
                link_mass,
                link_inertia_diag,
                visuals=[
                    u.cylinder_visual(0.012, 0.012, "joint", (0.0, 0.0, 0.004)),
                    u.box_visual((0.05, 0.02, 0.008), "rod", (0.0, 0.0, 0.012)),
                ],
            )
        )

    # Leg 1 carries the star: il1 frame angle = pi/3 - pi/2 + pivot1 = psi_1 = phi - 2 pi/3.
    joints.append(
        u.joint(
            "pivot1",
            "revolute",
            "carriage1",
            "il1",
            rpy=(0.0, 0.0, -math.pi / 2.0),
            limits=(-math.pi / 2.0, math.pi / 2.0),
        )
    )
    # arm1 frame turned by +2 pi/3 so the star frame angle is phi; its axis is u_1 in that frame.
    arm_length = height
    star_visuals = [u.cylinder_visual(0.02, 0.01, "plate", (0.0, 0.0, 0.02))]
    for i in LEGS:
        out = math.pi + _LINE_OFFSET[i]  # outward direction -u_i relative to phi
        mid = (0.5 * arm_length * math.cos(out), 0.5 * arm_length * math.sin(out), 0.02)
        star_visuals.append(u.box_visual((arm_length, 0.015, 0.008), "plate", mid, (0.0, 0.0, out)))
    links.append(
        u.link(
            "star",
            star_mass,
            (star_inertia / 2.0, star_inertia / 2.0, star_inertia),
            visuals=star_visuals,
        )
    )
    joints.append(
        u.joint(
            "arm1",
            "prismatic",
            "il1",
            "star",
            rpy=(0.0, 0.0, ALPHA),
            axis=(-0.5, -math.sqrt(3.0) / 2.0, 0.0),  # u_1 = R(-2 pi/3) x
            limits=(0.0, a),
        )
    )
    # Legs 2 and 3 hang from the star: il<i> = C - rho_i u_i, x along u_i.
    closures: list[ClosureSpec] = []
    for i in LEGS[1:]:
        joints.append(
            u.joint(
                f"arm{i}",
                "prismatic",
                "star",
                f"il{i}",
                rpy=(0.0, 0.0, _LINE_OFFSET[i]),
                axis=(-1, 0, 0),
                limits=(0.0, a),
            )
        )
        closures.append(ClosureSpec(f"il{i}_carriage{i}", (f"il{i}", f"carriage{i}"), "point"))

    reference: dict[str, tuple[float, ...]] = {f"slider{i}": (float(q[k]),) for k, i in enumerate(LEGS)}
    reference["pivot1"] = (float(pose[2] - math.pi / 2.0),)
    reference.update({f"arm{i}": (float(rho[k]),) for k, i in enumerate(LEGS)})
    robot = yourdfpy.Robot(name=name, links=links, joints=joints)
    sidecar = Sidecar(
        closures=tuple(closures),
        actuation=tuple(ActuatorSpec(f"slider{i}") for i in LEGS),
        task=TaskSpec("star", ("x", "y", "rz")),
        gravity=(0.0, 0.0, -gravity),
        reference=reference,
        name=name,
        source=source,
    )
    return robot, sidecar
