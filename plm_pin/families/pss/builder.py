r"""Parametric n-PSS spatial parallel manipulators; the Zhao 2011 8-PSS and its 6-PSS counterpart.

Geometry (Zhao 2011, Fig. 2 and eq. (6a)): slider ``i`` runs on a fixed guide through
:math:`B_i` (Table 1) along the unit direction :math:`e_i`; its ball-joint centre is
:math:`C_i = B_i + q_i e_i`, the slider coordinate :math:`q_i` [m] being measured from
:math:`B_i`. A strut of length :math:`l_i` (Table 3) joins :math:`C_i` to the platform
ball joint :math:`A_i = p + R a_i`, with :math:`a_i` given in the platform frame
:math:`O'\text{-}uvw` at the platform's centre of mass (Table 2). The platform pose is
:math:`X = [x, y, z, \phi_x, \phi_y, \phi_z]`, the angles being rotations about the fixed
x, y and z axes: :math:`R = R_z(\phi_z) R_y(\phi_y) R_x(\phi_x)` (``pin.rpy.rpyToMatrix``).
Inverse kinematics is the strut-length equation :math:`|A_i - B_i - q_i e_i| = l_i`:

.. math:: q_i = e_i^T d_i - \sqrt{l_i^2 - |d_i|^2 + (e_i^T d_i)^2}, \qquad d_i = A_i - B_i,

the root that keeps the slider on the guide-origin side of its platform joint (the
struts rise from the sliders to the platform, :math:`w_i^T e_i > 0`).

Which slider moves along which axis (Zhao 2011, section "Description"): "The lead screws
of B1, B2, B3 and B4 are vertical to the ground. The lead screws of B5, B6 and the lead
screws of B7, B8 are parallel with the ground. They are orthogonal to each other." The
horizontal axes follow from Tables 1-2: :math:`B_{5,6}` lie at y = -2.0 m with the same x
(+-0.4 m) as :math:`a_{5,6}`, whose platform points sit near y = -0.68 m, 1.32 m away in y;
a guide along x would leave :math:`|y_A - y_B| > l = 1` m (no assembly), so
:math:`e_{5,6} = +y`. Likewise :math:`B_{7,8}` at x = -2.0 m share y with
:math:`a_{7,8}`, so :math:`e_{7,8} = +x`. Sliders 1-4 sit on z = 0 below their platform
points (same x, y), so :math:`e_{1..4} = +z`, z pointing up. Each sign makes :math:`q_i`
grow towards the platform; :math:`w_i^T e_i \ge 0.909` along the paper's trajectory (no
actuator singularity).

Spanning tree (URDF has no ball joint): the platform hangs from the base on a
``floating`` joint (a Pinocchio free-flyer, q = xyz then quaternion x y z w); each leg is
``slider<i>`` (prismatic, actuated) -> ``u<i>a``, ``u<i>b`` (a universal joint, two
revolutes through a massless cross) -> ``strut<i>`` (local z along the strut, centre of
mass at mid-length) -> frame ``strut<i>_tip``, closed on the platform frame
``platform_p<i>`` by a ``point`` closure (3 rows). The universal joint replaces the
slider-side ball: the third rotation, the strut's spin about its own axis, is an idle
freedom (a ball there would add 8 DOF, mobility 14). The paper drops it: an S-S strut
transmits no axial torque, so an axisymmetric strut's spin rate stays constant (Euler:
:math:`I_a \dot\omega_3 = (I_t - I_t) \omega_1 \omega_2 = 0`), zero, and its angular velocity
is :math:`\omega_i = w_i \times \dot w_i`, normal to the strut (eqs. (6b), (9)). The
universal joint instead slaves the spin to the swing (:math:`\omega \cdot w = \dot\alpha
\sin\beta`, up to 0.1 rad/s on the eq. (35) trajectory), and would make the motors drive the
axial inertia. So the tree's strut carries the transverse moments only, its axial moment
set to zero: the component of :math:`\omega` normal to the strut is :math:`w \times \dot w`
in both models, hence the strut's kinetic energy
:math:`\tfrac12 m |v_G|^2 + \tfrac12 I_t |w \times \dot w|^2` and every dynamic result are
exactly the paper's S-S ones (the builder refuses unequal transverse moments, for which
that does not hold). The axial moment still sizes the drawn strut. The universal joint's
frame is turned so that its z axis is the guide direction :math:`e_i`; its first axis is
then normal to the guide and it locks only when the strut lies along that axis, at 90 deg
from the guide, far outside the workspace (the angles stay below 0.43 rad on the paper's
trajectory). An 8-PSS tree has nv = 6 + 8 x 3 = 30 and 24 closure rows: mobility 6,
redundancy 2.

Drive (eqs. (5), (18)-(19)): each slider is driven through a ball screw of lead
:math:`p_i` [m/rev] by a base-mounted DC motor without reducer; the lead-screw inertia
:math:`I_{Li}` and the coupler-plus-rotor inertia :math:`I_{Ci} + I_{Mi}` are reflected on
the slider as the armature :math:`(2\pi / p_i)^2 (I_{Li} + I_{Ci} + I_{Mi})`
(= 408.2068 kg here).

Typos of Zhao 2011 that matter here:

- eq. (19) prints the lead as "p_i = 0.05 m^-1"; a lead is 0.05 m/rev (2 pi / p in rad/m).
- after eq. (5), "A is the actuating torques": A = diag(2 pi / p_i) of eq. (19).
- eq. (5) gives :math:`J^+ = J^T (J J^T)^{-1}` "when J is m x n", but J is 8 x 6 (eq. (6a))
  and the projection used is :math:`(J^T)^+ = J (J^T J)^{-1}`.
- eq. (1) sets :math:`\omega = [\dot\phi_x, \dot\phi_y, \dot\phi_z]^T`; for fixed-axis
  angles this is exact only to first order.
- Table 1 is titled "base platform" but lists the guide points :math:`B_i` (q = 0).
- the strut's transverse inertia 1.279 kg m^2 is not that of a uniform 20 kg, 1 m rod
  (1.667); it is kept as printed.
- "d_i = 0.244 m" (section "Simulation") enters no equation or table; unused. It equals the
  height of the trajectory midpoint above the horizontal guides, 1.744 - 1.5 m.
- Table 5 (work per motor) is not reproduced by the paper's own printed model (a literal
  re-implementation gives a sum near 8479 J, not 15242.219 J); it is quoted here as
  ``ZHAO2011_TABLE5_WORK`` of the Zhao 2011 study (``analyses/_zhao2011_paper.py``),
  not used as a reference.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..._arguments import finite_array, leg_numbers, nonnegative, numbers_of, optional_positive, positive
from ..._lazy import lazy_module
from ...description import urdf_parts as u
from ...description.compliance import assumed_drive_stiffness
from ...description.sidecar import ActuatorSpec, ClosureSpec, Sidecar, TaskSpec
from ...exceptions import InvalidInput
from ...tolerances import UNIT_VECTOR_TOL

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")

Vec3 = tuple[float, float, float]


# ---------------------------------------------------------------- kinematics
def pose_rotation(pose: Sequence[float]) -> np.ndarray:
    r"""Platform rotation :math:`R = R_z(\phi_z) R_y(\phi_y) R_x(\phi_x)` of a pose, shape (3, 3)."""
    return u.transform(rpy=(pose[3], pose[4], pose[5]))[:3, :3]


def pose_quaternion(pose: Sequence[float]) -> tuple[float, float, float, float]:
    r"""Unit quaternion ``(x, y, z, w)`` (Pinocchio order) of :math:`R_z(\phi_z) R_y(\phi_y) R_x(\phi_x)`."""
    x, y, z, w = (float(c) for c in pin.Quaternion(pose_rotation(pose)).coeffs())
    return (x, y, z, w)


def pss_inverse_kinematics(
    pose: Sequence[float],
    guide_points: Sequence[Sequence[float]],
    guide_directions: Sequence[Sequence[float]],
    platform_points: Sequence[Sequence[float]],
    strut_lengths: Sequence[float],
    legs: Sequence[int],
) -> dict[int, tuple[float, np.ndarray]]:
    r"""Slider position :math:`q_i` [m] and strut unit vector :math:`w_i` of each leg.

    Closed form of the strut-length equation :math:`|p + R a_i - B_i - q_i e_i| = l_i`, the
    root with the slider on the guide-origin side of its platform joint (module docstring).

    Args:
        pose: platform pose ``(x, y, z [m], phi_x, phi_y, phi_z [rad])``.
        guide_points: :math:`B_i` per leg number ``i`` (index ``i - 1``) [m].
        guide_directions: unit :math:`e_i` per leg.
        platform_points: :math:`a_i` in the platform frame per leg [m].
        strut_lengths: :math:`l_i` per leg [m].
        legs: leg numbers (1-based).

    Returns:
        ``{i: (q_i, w_i)}`` with ``w_i`` (3,) pointing from the slider to the platform.

    Raises:
        ValueError: when a strut cannot reach its platform joint from its guide.
    """
    p = np.asarray(pose[:3], dtype=float)
    R = pose_rotation(pose)
    out = {}
    for i in legs:
        B = np.asarray(guide_points[i - 1], dtype=float)
        e = np.asarray(guide_directions[i - 1], dtype=float)
        l = float(strut_lengths[i - 1])
        d = p + R @ np.asarray(platform_points[i - 1], dtype=float) - B
        s = float(e @ d)
        disc = l * l - float(d @ d) + s * s
        if disc < 0.0:
            raise InvalidInput(
                f"leg {i}: the strut (l = {l:.4g} m) cannot reach its platform joint; "
                f"distance to the guide {math.sqrt(float(d @ d) - s * s):.4g} m"
            )
        q = s - math.sqrt(disc)
        out[i] = (q, (d - q * e) / l)
    return out


# ---------------------------------------------------------------- builder
def build_pss(
    *,
    name: str,
    legs: Sequence[int],
    guide_points: Sequence[Sequence[float]],
    guide_directions: Sequence[Sequence[float]],
    platform_points: Sequence[Sequence[float]],
    strut_lengths: Sequence[float],
    strut_mass: float,
    strut_inertia: Sequence[float],
    platform_mass: float,
    platform_inertia: Sequence[float],
    slider_mass: float,
    lead: float,
    screw_inertia: float,
    rotor_inertia: float,
    home_pose: Sequence[float],
    gravity: Sequence[float],
    stroke: tuple[float, float] = (0.0, 1.5),
    actuator_stiffness: float | None = None,
    source: str = "",
) -> tuple[yourdfpy.Robot, Sidecar]:
    """Build an n-PSS manipulator (a subset of its legs) as a URDF tree plus sidecar.

    Args:
        name: robot name.
        legs: leg numbers kept (1-based); per-leg data are indexed by ``leg - 1``.
        guide_points: guide point :math:`B_i` of each slider, world frame [m].
        guide_directions: unit guide direction :math:`e_i` of each slider.
        platform_points: platform ball joint :math:`a_i`, platform frame [m].
        strut_lengths: strut length :math:`l_i` [m].
        strut_mass: mass of each strut [kg], centre of mass at mid-length.
        strut_inertia: strut inertia about its centre, diagonal (transverse, transverse,
            axial) in the strut frame [kg m^2]; the transverse moments must be equal. The
            tree's strut gets an axial moment of zero (the S-S strut's spin is idle, see
            the module docstring); the axial value sizes the drawing.
        platform_mass: platform mass [kg], centre of mass at the platform frame's origin.
        platform_inertia: platform inertia about its centre of mass, diagonal in the
            platform frame [kg m^2].
        slider_mass: mass of each slider [kg].
        lead: ball-screw lead [m/rev].
        screw_inertia: lead-screw inertia [kg m^2].
        rotor_inertia: motor rotor plus coupler inertia [kg m^2].
        home_pose: platform pose ``(x, y, z [m], phi_x, phi_y, phi_z [rad])`` of the
            reference configuration.
        gravity: gravity vector in the world frame [m/s^2].
        stroke: slider position limits [m] written into the URDF.
        actuator_stiffness: axial stiffness of each ball-screw drive along its guide [N/m],
            written into the sidecar's ``compliance`` (marked assumed), or None.
        source: provenance written into the sidecar.

    Returns:
        The URDF tree and its sidecar.

    Raises:
        InvalidInput: an invalid leg list, point or direction, a length or lead not > 0, a mass or
            inertia not >= 0, unequal transverse strut moments, an empty stroke, or an
            unreachable home pose.
    """
    n = len(guide_points) if isinstance(guide_points, Sequence | np.ndarray) else 0
    if n == 0:
        raise InvalidInput(
            f"guide_points must be a non-empty sequence of (x, y, z) points [m], got {guide_points!r}"
        )
    legs = leg_numbers(legs, "legs", n)
    guide_points = finite_array(guide_points, "guide_points", (n, 3), "points [m]").tolist()
    guide_directions = finite_array(guide_directions, "guide_directions", (n, 3), "unit vectors").tolist()
    platform_points = finite_array(platform_points, "platform_points", (n, 3), "points [m]").tolist()
    strut_lengths = numbers_of(strut_lengths, "strut_lengths", n, "lengths > 0 [m]", "positive").tolist()
    strut_mass = nonnegative(strut_mass, "strut_mass", "kg")
    strut_inertia = tuple(
        numbers_of(strut_inertia, "strut_inertia", 3, "inertias >= 0 [kg m^2]", "nonnegative").tolist()
    )
    platform_mass = nonnegative(platform_mass, "platform_mass", "kg")
    platform_inertia = numbers_of(
        platform_inertia, "platform_inertia", 3, "inertias >= 0 [kg m^2]", "nonnegative"
    ).tolist()
    slider_mass = nonnegative(slider_mass, "slider_mass", "kg")
    lead = positive(lead, "lead", "m/rev")
    screw_inertia = nonnegative(screw_inertia, "screw_inertia", "kg m^2")
    rotor_inertia = nonnegative(rotor_inertia, "rotor_inertia", "kg m^2")
    home_pose = finite_array(home_pose, "home_pose", (6,), "x, y, z [m], phi_x, phi_y, phi_z [rad]").tolist()
    gravity = finite_array(gravity, "gravity", (3,), "components [m/s^2]").tolist()
    low, high = finite_array(stroke, "stroke", (2,), "slider limits [m]")
    if not low < high:
        raise InvalidInput(
            f"stroke must be (lower, upper) slider limits [m] with lower < upper, got {stroke!r}"
        )
    optional_positive(actuator_stiffness, "actuator_stiffness", "N/m")
    for i in legs:
        norm = float(np.linalg.norm(guide_directions[i - 1]))
        if abs(norm - 1.0) > UNIT_VECTOR_TOL:
            raise InvalidInput(f"guide direction of leg {i} must be a unit vector, |e| = {norm}")
    if strut_inertia[0] != strut_inertia[1]:
        raise InvalidInput(
            f"strut_inertia {strut_inertia}: the transverse moments must be equal (an "
            "axisymmetric strut, whose idle spin the universal joint may drop)"
        )
    ik = pss_inverse_kinematics(
        home_pose, guide_points, guide_directions, platform_points, strut_lengths, legs
    )
    strut_radius = math.sqrt(2.0 * strut_inertia[2] / strut_mass) if strut_mass > 0 else 0.02
    slider_size = (0.12, 0.12, 0.08)
    base_visuals = [u.box_visual((1.2, 1.2, 0.02), "base", (0.0, 0.0, -0.05))]
    links: list[yourdfpy.Link] = []
    joints: list[yourdfpy.Joint] = []
    reference: dict[str, tuple[float, ...]] = {}
    closures: list[ClosureSpec] = []
    for i in legs:
        B = tuple(float(c) for c in guide_points[i - 1])
        e = tuple(float(c) for c in guide_directions[i - 1])
        l = float(strut_lengths[i - 1])
        rho = u.universal_frame_rpy(e)
        rail_mid = tuple(b + 0.5 * (stroke[0] + stroke[1]) * c for b, c in zip(B, e, strict=True))
        base_visuals.append(u.cylinder_visual(0.015, stroke[1] - stroke[0], "base", rail_mid, rho))
        links.append(
            u.link(
                f"carriage{i}",
                slider_mass,
                u.box_inertia(slider_mass, slider_size),
                visuals=[u.box_visual(slider_size, "slider", rpy=rho), u.sphere_visual(0.04, "joint")],
            )
        )
        joints.append(
            u.joint(f"slider{i}", "prismatic", "base", f"carriage{i}", xyz=B, axis=e, limits=stroke)
        )
        links.append(u.link(f"cross{i}"))
        joints.append(u.joint(f"u{i}a", "revolute", f"carriage{i}", f"cross{i}", rpy=rho, axis=(1, 0, 0)))
        links.append(
            u.link(
                f"strut{i}",
                strut_mass,
                (float(strut_inertia[0]), float(strut_inertia[1]), 0.0),  # axial moment: the idle spin
                com=(0.0, 0.0, l / 2),
                visuals=[u.cylinder_visual(strut_radius, l, "rod", (0.0, 0.0, l / 2))],
            )
        )
        joints.append(u.joint(f"u{i}b", "revolute", f"cross{i}", f"strut{i}", axis=(0, 1, 0)))
        links.append(u.link(f"strut{i}_tip"))
        joints.append(
            u.joint(f"strut{i}_tip_fixed", "fixed", f"strut{i}", f"strut{i}_tip", xyz=(0.0, 0.0, l))
        )
        closures.append(ClosureSpec(f"strut{i}_platform", (f"strut{i}_tip", f"platform_p{i}"), "point"))
        q, w = ik[i]
        alpha, beta = u.universal_angles(w, rho)
        reference[f"slider{i}"] = (q,)
        reference[f"u{i}a"] = (alpha,)
        reference[f"u{i}b"] = (beta,)
    links.insert(0, u.link("base", visuals=base_visuals))
    # a box with the platform's inertia: 1.0 x 1.0 x 0.2 m for Zhao 2011's 200 kg
    mx, my, mz = (float(c) for c in platform_inertia)
    scale = 6.0 / platform_mass if platform_mass > 0 else 0.0
    box = tuple(math.sqrt(max(scale * v, 1e-6)) for v in (my + mz - mx, mx + mz - my, mx + my - mz))
    links.append(
        u.link(
            "platform",
            platform_mass,
            (mx, my, mz),
            visuals=[u.box_visual(box, "plate")],
        )
    )
    joints.append(u.joint("platform_floating", "floating", "base", "platform"))
    for i in legs:
        a = tuple(float(c) for c in platform_points[i - 1])
        links.append(u.link(f"platform_p{i}", visuals=[u.sphere_visual(0.04, "joint")]))
        joints.append(u.joint(f"platform_p{i}_fixed", "fixed", "platform", f"platform_p{i}", xyz=a))
    links.append(u.link("platform_center"))
    joints.append(u.joint("platform_center_fixed", "fixed", "platform", "platform_center"))
    reference["platform_floating"] = (*(float(c) for c in home_pose[:3]), *pose_quaternion(home_pose))
    robot = yourdfpy.Robot(name=name, links=links, joints=joints)
    sidecar = Sidecar(
        closures=tuple(closures),
        actuation=tuple(
            ActuatorSpec(f"slider{i}", lead=lead, rotor_inertia=rotor_inertia, screw_inertia=screw_inertia)
            for i in legs
        ),
        task=TaskSpec("platform_center", ("x", "y", "z", "rx", "ry", "rz")),
        gravity=(float(gravity[0]), float(gravity[1]), float(gravity[2])),
        reference={k: tuple(float(x) for x in v) for k, v in reference.items()},
        name=name,
        source=source,
        compliance=assumed_drive_stiffness([f"slider{i}" for i in legs], actuator_stiffness),
    )
    return robot, sidecar
