r"""Six-legged spatial platforms from their leg type: 6-UPS (Gough-Stewart), 6-RUS and 6-PSS (task 6-D).

Leg ``i`` joins the base point :math:`a_i` to the platform point :math:`C_i = p + R b_i`, with
:math:`b_i` given in the platform frame (origin ``platform_center``) and
:math:`R = R_z(r_z) R_y(r_y) R_x(r_x)` from the pose ``(x, y, z, rx, ry, rz)``:

- **UPS**: a universal joint at :math:`a_i`, a cylinder whose length
  :math:`\rho_i = |p + R b_i - a_i|` is driven (prismatic ``extend<i>``), a ball at :math:`C_i`.
- **RUS**: a crank driven about the axis :math:`k_i` through :math:`a_i` (``crank<i>``, length
  :math:`l_{1i}`, angle from the outward direction: base centroid to :math:`a_i`, made normal
  to :math:`k_i`), a rod of length :math:`l_{2i}` from a universal joint at the crank's tip to a
  ball at :math:`C_i`. In the crank frame (z along :math:`k_i`, x outward),
  :math:`d = C_i - a_i` has :math:`\theta_i = \operatorname{atan2}(d_y, d_x) + \sigma_i
  \arccos(K / \sqrt{d_x^2 + d_y^2})`, :math:`K = (|d|^2 + l_1^2 - l_2^2) / (2 l_1)`, by default
  the branch whose crank points most outward (the larger :math:`\cos\theta_i`).
- **PSS**: a carriage driven along the guide through :math:`a_i` with direction :math:`e_i`
  (``slider<i>``), a rod of length :math:`l_i` from a universal joint on the carriage to a
  ball at :math:`C_i`: :math:`q_i = e_i \cdot d + \sigma_i \sqrt{l_i^2 - |d|^2 + (e_i \cdot d)^2}`.

A UPU leg has five freedoms: six of them leave the platform no motion, which is why
:func:`build_hexapod` refuses it; three UPU legs with Tsai's axes make the translational
platform of :mod:`plm_pin.legs.translational`.

Spanning tree: the platform hangs from the base on a ``floating`` joint; each leg ends at a
``point`` closure on the platform frame ``platform_p<i>`` (the ball). The first ball of an
S-S rod is a universal joint whose frame points along the rod in the reference (both angles
0 there), the rod's idle spin dropped (:mod:`plm_pin.legs.parts`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._arguments import finite_array
from .._lazy import lazy_module
from ..description import urdf_parts as u
from ..description.sidecar import ClosureSpec, Sidecar, TaskSpec
from ..exceptions import InvalidInput
from . import parts

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")

HEXAPOD_LEGS = ("UPS", "RUS", "PSS")
"""The six-legged platforms' leg types, base joint first."""

ACTUATED = {"UPS": "extend", "RUS": "crank", "PSS": "slider"}
"""The actuated joint of each hexapod leg type, named ``<name><i>``."""

_UPU_HINT = (
    " (a UPU leg has 5 freedoms: six of them lock the platform; three make Tsai's translational "
    "platform, plm_pin.legs.translational('UPU', ...))"
)


def crank_frame(axis: np.ndarray, outward: np.ndarray) -> tuple[float, float, float]:
    """Roll-pitch-yaw [rad] of a crank's frame: z along ``axis``, x along ``outward`` made normal to it.

    When ``outward`` lies along ``axis`` (a base point at the centroid), the world x (or y) is used.
    """
    for x in (outward, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])):
        if float(np.linalg.norm(np.cross(axis, x))) > 0.0:
            roll, pitch, yaw = u.frame_rpy(x, axis)
            return (roll, pitch, yaw)
    raise AssertionError("unreachable: two orthogonal vectors cannot both lie along one axis")


def crank_angle(d: np.ndarray, crank: float, rod: float, sign: int | None) -> float | None:
    """The crank angle [rad] putting the rod's end ``rod`` [m] away from ``d`` (crank frame), or None.

    The crank of length ``crank`` [m] turns about z from x; ``sign`` picks the branch, None the
    one whose crank points most outward (the larger cosine).
    """
    k = (float(d @ d) + crank * crank - rod * rod) / (2 * crank)
    r = math.hypot(float(d[0]), float(d[1]))
    if not abs(k) <= r:
        return None
    roots = [
        math.atan2(float(d[1]), float(d[0])) + s * math.acos(max(-1.0, min(1.0, k / r))) for s in (1, -1)
    ]
    return roots[0 if sign == 1 else 1] if sign is not None else max(roots, key=math.cos)


def default_axes(base: np.ndarray) -> np.ndarray:
    """Horizontal tangents of the base points about their centroid, shape (n, 3) (x at the centroid)."""
    radial = base - base.mean(axis=0)
    out = []
    for r in radial:
        t = np.array([-r[1], r[0], 0.0])
        n = float(np.linalg.norm(t))
        out.append(t / n if n > 0 else np.array([1.0, 0.0, 0.0]))
    return np.array(out)


def build_hexapod(
    *,
    leg: str,
    base: Sequence[Sequence[float]],
    platform: Sequence[Sequence[float]],
    pose: Sequence[float],
    lengths: float | Sequence[float] | Sequence[Sequence[float]] | None = None,
    directions: Sequence[Sequence[float]] | None = None,
    axes: Sequence[Sequence[float]] | None = None,
    stroke: tuple[float, float] | None = None,
    modes: Sequence[int] | None = None,
    density: float = 1.0,
    platform_mass: float = 1.0,
    slider_mass: float = 0.5,
    effort: tuple[float, float] | None = None,
    gravity: Sequence[float] = (0.0, 0.0, -9.81),
    name: str = "hexapod",
    source: str = "",
) -> parts.Built:
    """Build a six-legged 6-UPS, 6-RUS or 6-PSS platform (module docstring) as a URDF tree plus sidecar.

    Args:
        leg: ``"UPS"``, ``"RUS"`` or ``"PSS"`` (``"UPU"`` is refused, module docstring).
        base: the base points :math:`a_i`, six (x, y, z) [m]: universal joints (UPS), crank
            pivots (RUS) or guide origins (PSS).
        platform: the platform ball centres :math:`b_i`, six (x, y, z) in the platform frame [m].
        pose: the platform pose ``(x, y, z [m], rx, ry, rz [rad])`` of the reference configuration.
        lengths: PSS: rod length(s) [m] (one or six); RUS: ``(crank, rod)`` [m] for every leg or
            six pairs. None for UPS.
        directions: PSS: the guide directions :math:`e_i`, six (x, y, z) (normalised).
        axes: RUS: the crank axes :math:`k_i` (normalised; default: the horizontal tangents of
            the base points about their centroid).
        stroke: the actuator limits written into the URDF: leg lengths (UPS, 0 < lower) or
            slider positions (PSS) [m]; default around the reference. None for RUS.
        modes: RUS, PSS: the branch of each leg, +1 or -1 (module docstring); default: PSS -1,
            RUS the crank pointing most outward.
        density: mass per length of the rods, cranks and cylinders [kg/m].
        platform_mass: platform mass [kg], at the platform centre.
        slider_mass: mass of each carriage [kg] (PSS).
        effort: actuator effort limits ``(lower, upper)`` [N] or [N m], or None (unbounded).
        gravity: gravity in the world frame [m/s^2].
        name: robot name.
        source: provenance written into the sidecar.

    Returns:
        The URDF tree and its sidecar.

    Raises:
        InvalidInput: an unknown leg type (UPU among them, with the reason), points or
            directions of the wrong count, a length not > 0, an argument the leg type does not
            take or lacks, or a reference pose some leg cannot reach (the message names the leg).
    """
    leg = parts.leg_type(leg, HEXAPOD_LEGS, "hexapod", _UPU_HINT if str(leg).upper() == "UPU" else "")
    a = parts.points(base, "base", 6, 3)
    b = parts.points(platform, "platform", 6, 3)
    X = finite_array(pose, "pose", (6,), "x, y, z [m], rx, ry, rz [rad]")
    density, platform_mass, slider_mass = parts.masses(density, platform_mass, slider_mass)
    g = parts.gravity_vector(gravity)
    if leg == "UPS":
        parts.unused("hexapod", leg, lengths=lengths, modes=modes)
    else:
        parts.needed("hexapod", leg, lengths=lengths)
    if leg == "PSS":
        parts.needed("hexapod", leg, directions=directions)
    else:
        parts.unused("hexapod", leg, directions=directions)
    if leg != "RUS":
        parts.unused("hexapod", leg, axes=axes)
    else:
        parts.unused("hexapod", leg, stroke=stroke)
    sig: Sequence[int | None] = parts.signs(modes, "modes", 6) if modes is not None else (None,) * 6
    C = X[:3] + b @ parts.pose_rotation(X[3:]).T
    size = max(
        float(np.max(np.linalg.norm(a - a.mean(axis=0), axis=1))), float(np.max(np.linalg.norm(b, axis=1)))
    )
    size = size if size > 0 else 1.0
    radius = 0.02 * size
    where = f"hexapod {leg}: at the reference pose {tuple(X.tolist())}"
    links: list[yourdfpy.Link] = []
    joints: list[yourdfpy.Joint] = []
    reference: parts.Reference = {}
    closures: list[ClosureSpec] = []
    base_visuals = [
        u.cylinder_visual(1.2 * size, 0.02 * size, "base", (0.0, 0.0, float(a[:, 2].min()) - 0.03 * size))
    ]
    if leg == "UPS":
        rho = np.linalg.norm(C - a, axis=1)
        if not np.all(rho > 0):
            raise InvalidInput(
                f"{where}, a platform point lies on its base joint (legs {np.flatnonzero(~(rho > 0)) + 1})"
            )
        lo, hi = parts.interval(
            stroke if stroke is not None else (0.5 * rho.min(), 1.5 * rho.max()), "stroke", "m", positive=True
        )
        for i in range(6):
            n = i + 1
            if not lo <= rho[i] <= hi:
                raise InvalidInput(f"{where}, leg {n}'s length {rho[i]:.6g} m is outside stroke {(lo, hi)}")
            w = (C[i] - a[i]) / rho[i]
            ai = tuple(float(c) for c in a[i])
            base_visuals.append(u.sphere_visual(1.5 * radius, "joint", ai))
            links += [
                u.link(f"cross{n}"),
                parts.rod_along_z(f"cylinder{n}", 0.0, lo, density, 1.6 * radius, "slider"),
                parts.rod_along_z(f"piston{n}", -lo, 0.0, density, radius),
            ]
            joints += [
                u.joint(
                    f"u{n}a",
                    "revolute",
                    "base",
                    f"cross{n}",
                    xyz=ai,
                    rpy=u.universal_frame_rpy(w),
                    axis=(1, 0, 0),
                ),
                u.joint(f"u{n}b", "revolute", f"cross{n}", f"cylinder{n}", axis=(0, 1, 0)),
                u.joint(
                    f"extend{n}", "prismatic", f"cylinder{n}", f"piston{n}", axis=(0, 0, 1), limits=(lo, hi)
                ),
            ]
            reference.update({f"u{n}a": (0.0,), f"u{n}b": (0.0,), f"extend{n}": (float(rho[i]),)})
            closures.append(ClosureSpec(f"leg{n}_platform", (f"piston{n}", f"platform_p{n}"), "point"))
    elif leg == "RUS":
        L = parts.per_leg(lengths, "lengths", 6, 2, "(crank, rod) lengths > 0 [m]")
        K = parts.directions(axes, "axes", 6, 3) if axes is not None else default_axes(a)
        for i in range(6):
            n = i + 1
            l1, l2 = (float(v) for v in L[i])
            rpy = crank_frame(K[i], a[i] - a.mean(axis=0))
            Rc = u.transform(rpy=rpy)[:3, :3]
            d = Rc.T @ (C[i] - a[i])
            theta = crank_angle(d, l1, l2, sig[i])
            if theta is None:
                raise InvalidInput(
                    f"{where}, leg {n}'s crank and rod ({l1:.6g} m, {l2:.6g} m) cannot reach its platform "
                    "point"
                )
            tip = l1 * np.array([math.cos(theta), math.sin(theta), 0.0])
            rot = u.transform(rpy=(0.0, 0.0, theta))[:3, :3]
            ai = tuple(float(c) for c in a[i])
            base_visuals.append(u.cylinder_visual(1.5 * radius, 6 * radius, "joint", ai, rpy))
            links.append(parts.rod_along_x(f"arm{n}", 0.0, l1, density, 1.3 * radius, "slider"))
            joints.append(u.joint(f"crank{n}", "revolute", "base", f"arm{n}", xyz=ai, rpy=rpy))
            end = parts.universal_rod(
                links, joints, f"arm{n}", (l1, 0.0, 0.0), rot.T @ (d - tip) / l2, l2, str(n), density, radius
            )
            reference.update(
                {f"crank{n}": (math.remainder(theta, 2 * math.pi) + 0.0,), f"u{n}a": (0.0,), f"u{n}b": (0.0,)}
            )
            closures.append(ClosureSpec(f"leg{n}_platform", (end, f"platform_p{n}"), "point"))
    else:
        L = parts.per_leg(lengths, "lengths", 6, 1, "rod lengths > 0 [m]")
        E = parts.directions(directions, "directions", 6, 3)
        q = []
        for i in range(6):
            d = C[i] - a[i]
            s = float(E[i] @ d)
            disc = float(L[i, 0]) ** 2 - float(d @ d) + s * s
            if disc < 0.0:
                raise InvalidInput(
                    f"{where}, leg {i + 1}'s rod ({L[i, 0]:.6g} m) cannot reach its guide: the platform "
                    f"point is {math.sqrt(float(d @ d) - s * s):.6g} m from it"
                )
            q.append(s + (sig[i] or -1) * math.sqrt(disc))
        lo, hi = parts.interval(
            stroke if stroke is not None else (min(q) - size, max(q) + size), "stroke", "m"
        )
        box = (3 * radius, 3 * radius, 2 * radius)
        for i in range(6):
            n = i + 1
            if not lo <= q[i] <= hi:
                raise InvalidInput(f"{where}, leg {n}'s slider is at {q[i]:.6g} m, outside stroke {(lo, hi)}")
            ai = tuple(float(c) for c in a[i])
            rail = u.universal_frame_rpy(E[i])
            mid = tuple(float(c) for c in a[i] + 0.5 * (lo + hi) * E[i])
            base_visuals.append(u.cylinder_visual(0.7 * radius, hi - lo, "base", mid, rail))
            links.append(
                u.link(
                    f"carriage{n}",
                    slider_mass,
                    u.box_inertia(slider_mass, box),
                    visuals=[u.box_visual(box, "slider", rpy=rail)],
                )
            )
            joints.append(
                u.joint(
                    f"slider{n}",
                    "prismatic",
                    "base",
                    f"carriage{n}",
                    xyz=ai,
                    axis=tuple(E[i]),
                    limits=(lo, hi),
                )
            )
            w = (C[i] - a[i] - q[i] * E[i]) / float(L[i, 0])
            end = parts.universal_rod(
                links, joints, f"carriage{n}", (0.0, 0.0, 0.0), w, float(L[i, 0]), str(n), density, radius
            )
            reference.update({f"slider{n}": (q[i],), f"u{n}a": (0.0,), f"u{n}b": (0.0,)})
            closures.append(ClosureSpec(f"leg{n}_platform", (end, f"platform_p{n}"), "point"))
    links.insert(0, u.link("base", visuals=base_visuals))
    parts.floating_platform(
        links, joints, reference, {f"platform_p{i + 1}": b[i] for i in range(6)}, X, platform_mass, radius
    )
    sidecar = Sidecar(
        closures=tuple(closures),
        actuation=parts.actuators([f"{ACTUATED[leg]}{i}" for i in range(1, 7)], effort),
        task=TaskSpec("platform_center", ("x", "y", "z", "rx", "ry", "rz")),
        gravity=g,
        reference=reference,
        name=name,
        source=source or f"plm_pin.legs.hexapod: a 6-{leg} platform",
    )
    return yourdfpy.Robot(name=name, links=links, joints=joints), sidecar


def hexapod(
    leg: str,
    base: Sequence[Sequence[float]],
    platform: Sequence[Sequence[float]],
    *,
    folder: str | Path,
    name: str = "hexapod",
    source: str = "",
    **options: Any,
) -> Path:
    """Write a 6-UPS, 6-RUS or 6-PSS platform (task 6-D) as ``<name>.urdf`` + ``<name>.plm.yaml``.

    Args:
        leg: the leg type, as :func:`build_hexapod`.
        base: the base points [m], as :func:`build_hexapod`.
        platform: the platform points [m], as :func:`build_hexapod`.
        folder: where the two files go (created if needed).
        name: the file stem and robot name.
        source: provenance written into the sidecar.
        options: the other keyword arguments of :func:`build_hexapod`.

    Returns:
        The URDF's path, for :func:`plm_pin.load`.

    Raises:
        InvalidInput: as :func:`build_hexapod`, an unknown option, or a ``name`` that is not a file stem.
    """
    return parts.write(build_hexapod, folder, name, source, leg=leg, base=base, platform=platform, **options)
