r"""Planar three-legged platforms from their leg type: 3-RPR, 3-PRR, 3-RRR and 3-PRP (task x, y, rz).

Everything lies in the world x-y plane, every revolute axis along z. Leg ``i`` joins the base
point :math:`A_i` to the platform point :math:`C_i = p + R(\phi) P_i`, with :math:`P_i` given in
the platform frame (origin at the platform centre, the task frame ``platform_center``). The
first letter is the joint at the base, the actuated joint is underlined in the usual names:

- **RPR**: a hinge at :math:`A_i` (passive), a cylinder whose length :math:`\rho_i = |C_i - A_i|`
  is driven (prismatic ``extend<i>``), a hinge at :math:`C_i`.
- **PRR**: a carriage driven along the rail through :math:`A_i` with direction :math:`u_i`
  (``slider<i>``, position :math:`s_i` from :math:`A_i`), a hinge, a rod of length :math:`l_i`, a
  hinge at :math:`C_i`: :math:`s_i = u_i \cdot d_i + \sigma_i \sqrt{l_i^2 - |d_i|^2 + (u_i \cdot d_i)^2}`,
  :math:`d_i = C_i - A_i`, :math:`\sigma_i` the leg's branch (``modes``).
- **RRR**: a crank (link ``arm<i>``) driven at :math:`A_i` (joint ``crank<i>``, length
  :math:`l_{1i}`), a hinge, a rod (:math:`l_{2i}`), a hinge at :math:`C_i`; the elbow on the
  side :math:`\sigma_i` of :math:`A_i \to C_i` (+1: to the left).
- **PRP**: a carriage driven along the rail (``slider<i>``), a hinge, and a slot of the
  platform along its direction :math:`v_i` (``slots``, platform frame) sliding on the hinge's
  arm (passive prismatic ``slot<i>``): the pivot :math:`B_i = A_i + s_i u_i` lies on the line
  through :math:`C_i` along :math:`w_i = R v_i`, :math:`s_i = ((C_i - A_i) \times w_i) / (u_i \times w_i)`.

Spanning tree: leg 1 carries the platform (its last hinge, ``wrist1``, is a tree joint; for
PRP the platform is fixed to leg 1's slot block); legs 2 and 3 are cut at the platform by a
``point`` closure (a hinge in a planar chain) or, for PRP, a ``weld`` (the slot keeps the
relative angle). Each link frame starts at its joint and runs along its own x. No link is named
like a joint, so that every name is one frame of the Pinocchio model.
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

PLANAR_LEGS = ("RPR", "PRR", "RRR", "PRP")
"""The planar leg types, base joint first."""

ACTUATED = {"RPR": "extend", "PRR": "slider", "RRR": "crank", "PRP": "slider"}
"""The actuated joint of each planar leg type, named ``<name><i>``."""


def _angle(v: np.ndarray) -> float:
    return math.atan2(float(v[1]), float(v[0]))


def _wrap(angle: float) -> float:
    return math.remainder(angle, 2 * math.pi) + 0.0


def _cross(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def build_planar(
    *,
    leg: str,
    base: Sequence[Sequence[float]],
    platform: Sequence[Sequence[float]],
    pose: Sequence[float] = (0.0, 0.0, 0.0),
    lengths: float | Sequence[float] | Sequence[Sequence[float]] | None = None,
    directions: Sequence[Sequence[float]] | None = None,
    slots: Sequence[Sequence[float]] | None = None,
    stroke: tuple[float, float] | None = None,
    modes: Sequence[int] | None = None,
    density: float = 1.0,
    platform_mass: float = 1.0,
    slider_mass: float = 0.5,
    effort: tuple[float, float] | None = None,
    gravity: Sequence[float] = (0.0, 0.0, -9.81),
    name: str = "planar",
    source: str = "",
) -> parts.Built:
    """Build a planar three-legged platform (module docstring) as a URDF tree plus sidecar.

    Args:
        leg: ``"RPR"``, ``"PRR"``, ``"RRR"`` or ``"PRP"``.
        base: the base points :math:`A_i`, three (x, y) [m]: hinges (RPR, RRR) or rail origins
            (PRR, PRP).
        platform: the platform points :math:`P_i`, three (x, y) in the platform frame [m].
        pose: the platform pose ``(x [m], y [m], rz [rad])`` of the reference configuration.
        lengths: PRR: the rod length(s) [m] (one for every leg or three); RRR: crank and rod
            ``(l1, l2)`` [m] for every leg, or three pairs. None for RPR and PRP.
        directions: PRR, PRP: the rail directions :math:`u_i`, three (x, y) (normalised).
        slots: PRP: the slot directions :math:`v_i`, three (x, y) in the platform frame.
        stroke: the actuator limits written into the URDF: leg lengths (RPR, 0 < lower) or
            slider positions (PRR, PRP) [m]; default around the reference. None for RRR.
        modes: PRR, RRR: the branch of each leg, +1 or -1 (default all +1; module docstring).
        density: mass per length of the rods, cranks and cylinders [kg/m].
        platform_mass: platform mass [kg], at the platform centre.
        slider_mass: mass of each carriage [kg] (PRR, PRP).
        effort: actuator effort limits ``(lower, upper)`` [N] or [N m], or None (unbounded).
        gravity: gravity in the world frame [m/s^2] (default along -z, normal to the plane).
        name: robot name.
        source: provenance written into the sidecar.

    Returns:
        The URDF tree and its sidecar.

    Raises:
        InvalidInput: an unknown leg type, points or directions of the wrong count, a length
            not > 0, an argument the leg type does not take or lacks, or a reference pose some
            leg cannot reach (the message names the leg).
    """
    leg = parts.leg_type(leg, PLANAR_LEGS, "planar")
    A = parts.points(base, "base", 3, 2)
    P = parts.points(platform, "platform", 3, 2)
    x, y, rz = finite_array(pose, "pose", (3,), "x, y [m], rz [rad]").tolist()
    density, platform_mass, slider_mass = parts.masses(density, platform_mass, slider_mass)
    g = parts.gravity_vector(gravity)
    rails = leg in ("PRR", "PRP")
    if leg in ("PRR", "RRR"):
        parts.needed("planar", leg, lengths=lengths)
    else:
        parts.unused("planar", leg, lengths=lengths, modes=modes)
    if rails:
        parts.needed("planar", leg, directions=directions)
    else:
        parts.unused("planar", leg, directions=directions)
    if leg == "PRP":
        parts.needed("planar", leg, slots=slots)
    else:
        parts.unused("planar", leg, slots=slots)
    if leg == "RRR":
        parts.unused("planar", leg, stroke=stroke)
    U = parts.directions(directions, "directions", 3, 2) if rails else None
    V = parts.directions(slots, "slots", 3, 2) if leg == "PRP" else None
    L = None
    if leg == "PRR":
        L = parts.per_leg(lengths, "lengths", 3, 1, "rod lengths > 0 [m]")
    elif leg == "RRR":
        L = parts.per_leg(lengths, "lengths", 3, 2, "(crank, rod) lengths > 0 [m]")
    sig = parts.signs(modes if modes is not None else (1, 1, 1), "modes", 3)
    rot = np.array([[math.cos(rz), -math.sin(rz)], [math.sin(rz), math.cos(rz)]])
    C = np.array([x, y]) + P @ rot.T
    size = max(
        float(np.max(np.linalg.norm(A - A.mean(axis=0), axis=1))), float(np.max(np.linalg.norm(P, axis=1)))
    )
    size = size if size > 0 else 1.0
    radius = 0.03 * size
    where = f"planar {leg}: at the reference pose {(x, y, rz)}"

    # the joint coordinates of every leg at the reference pose
    coords: list[dict[str, float]] = []
    for i in range(3):
        d = C[i] - A[i]
        if leg == "RPR":
            rho = float(np.linalg.norm(d))
            if not rho > 0:
                raise InvalidInput(f"{where}, leg {i + 1}'s platform point lies on its base hinge")
            coords.append({"q": rho, "psi": _angle(d)})
        elif leg == "PRR":
            assert U is not None and L is not None
            s = float(U[i] @ d)
            disc = L[i, 0] ** 2 - float(d @ d) + s * s
            if disc < 0.0:
                raise InvalidInput(
                    f"{where}, leg {i + 1}'s rod ({L[i, 0]:.6g} m) cannot reach its rail: the platform "
                    f"point is {math.sqrt(float(d @ d) - s * s):.6g} m from it"
                )
            q = s + sig[i] * math.sqrt(disc)
            coords.append({"q": q, "psi": _angle(d - q * U[i])})
        elif leg == "RRR":
            assert L is not None
            l1, l2 = L[i]
            r = float(np.linalg.norm(d))
            if not abs(l1 - l2) <= r <= l1 + l2:
                raise InvalidInput(
                    f"{where}, leg {i + 1}'s crank and rod ({l1:.6g} m, {l2:.6g} m) cannot span the "
                    f"{r:.6g} m from its base point to its platform point"
                )
            half = math.acos(max(-1.0, min(1.0, (l1 * l1 + r * r - l2 * l2) / (2 * l1 * r))))
            theta = _angle(d) + sig[i] * half
            elbow = A[i] + l1 * np.array([math.cos(theta), math.sin(theta)])
            coords.append({"q": theta, "psi": _angle(C[i] - elbow)})
        else:
            assert U is not None and V is not None
            w = rot @ V[i]
            across = _cross(U[i], w)
            if across == 0.0:
                raise InvalidInput(f"{where}, leg {i + 1}'s slot is parallel to its rail (no pivot point)")
            s = _cross(d, w) / across
            coords.append({"q": s, "psi": _angle(w), "t": float((C[i] - A[i] - s * U[i]) @ w)})
    if stroke is None and leg == "RPR":
        reach = [c["q"] for c in coords]
        stroke = (0.5 * min(reach), 1.5 * max(reach))
    elif stroke is None and rails:
        reach = [c["q"] for c in coords]
        stroke = (min(reach) - size, max(reach) + size)
    limits = None if leg == "RRR" else parts.interval(stroke, "stroke", "m", positive=leg == "RPR")
    if limits is not None:
        for i, c in enumerate(coords):
            if not limits[0] <= c["q"] <= limits[1]:
                raise InvalidInput(
                    f"{where}, leg {i + 1}'s actuator is at {c['q']:.6g} m, outside stroke {limits}"
                )

    base_visuals = [u.cylinder_visual(1.2 * size, 0.02 * size, "base", (0.0, 0.0, -0.05 * size))]
    links: list[yourdfpy.Link] = []
    joints: list[yourdfpy.Joint] = []
    reference: parts.Reference = {}
    ends: list[str] = []
    for i, c in enumerate(coords):
        n = i + 1
        Ai = (float(A[i, 0]), float(A[i, 1]), 0.0)
        if leg == "RPR":
            assert limits is not None
            lo = limits[0]
            base_visuals.append(u.sphere_visual(1.5 * radius, "joint", Ai))
            links += [
                parts.rod_along_x(f"cylinder{n}", 0.0, lo, density, 1.6 * radius, "slider"),
                parts.rod_along_x(f"piston{n}", -lo, 0.0, density, radius),
            ]
            joints += [
                u.joint(f"pivot{n}", "revolute", "base", f"cylinder{n}", xyz=Ai),
                u.joint(
                    f"extend{n}", "prismatic", f"cylinder{n}", f"piston{n}", axis=(1, 0, 0), limits=limits
                ),
            ]
            reference[f"pivot{n}"] = (_wrap(c["psi"]),)
            reference[f"extend{n}"] = (c["q"],)
            ends.append(f"piston{n}")
            continue
        if rails:
            assert U is not None and limits is not None
            yaw = _angle(U[i])
            lo, hi = limits
            mid = tuple(float(v) for v in (A[i] + 0.5 * (lo + hi) * U[i]))
            base_visuals.append(
                u.box_visual((hi - lo, radius, radius), "base", (*mid, -radius), (0.0, 0.0, yaw))
            )
            box = (4 * radius, 3 * radius, 2 * radius)
            links.append(
                u.link(
                    f"carriage{n}",
                    slider_mass,
                    u.box_inertia(slider_mass, box),
                    visuals=[u.box_visual(box, "slider")],
                )
            )
            joints.append(
                u.joint(
                    f"slider{n}",
                    "prismatic",
                    "base",
                    f"carriage{n}",
                    xyz=Ai,
                    rpy=(0.0, 0.0, yaw),
                    axis=(1, 0, 0),
                    limits=limits,
                )
            )
            reference[f"slider{n}"] = (c["q"],)
            if leg == "PRR":
                assert L is not None
                l = float(L[i, 0])
                links += [parts.rod_along_x(f"rod{n}", 0.0, l, density, radius), u.link(f"rod{n}_tip")]
                joints += [
                    u.joint(f"pivot{n}", "revolute", f"carriage{n}", f"rod{n}"),
                    u.joint(f"rod{n}_tip_fixed", "fixed", f"rod{n}", f"rod{n}_tip", xyz=(l, 0.0, 0.0)),
                ]
                reference[f"pivot{n}"] = (_wrap(c["psi"] - yaw),)
                ends.append(f"rod{n}_tip")
            else:
                t = c["t"]
                span = (min(0.0, t) - 0.3 * size, max(0.0, t) + 0.3 * size)
                block = (3 * radius, 2.5 * radius, 2.5 * radius)
                links += [
                    parts.rod_along_x(f"arm{n}", span[0], span[1], density, 0.6 * radius),
                    u.link(f"block{n}", visuals=[u.box_visual(block, "joint")]),
                ]
                joints += [
                    u.joint(f"pivot{n}", "revolute", f"carriage{n}", f"arm{n}"),
                    u.joint(
                        f"slot{n}",
                        "prismatic",
                        f"arm{n}",
                        f"block{n}",
                        axis=(1, 0, 0),
                        limits=(-4 * size, 4 * size),
                    ),
                ]
                reference[f"pivot{n}"] = (_wrap(c["psi"] - yaw),)
                reference[f"slot{n}"] = (t,)
                ends.append(f"block{n}")
            continue
        assert L is not None
        l1, l2 = (float(v) for v in L[i])
        base_visuals.append(u.sphere_visual(1.5 * radius, "joint", Ai))
        links += [
            parts.rod_along_x(f"arm{n}", 0.0, l1, density, 1.3 * radius, "slider"),
            parts.rod_along_x(f"rod{n}", 0.0, l2, density, radius),
            u.link(f"rod{n}_tip"),
        ]
        joints += [
            u.joint(f"crank{n}", "revolute", "base", f"arm{n}", xyz=Ai),
            u.joint(f"elbow{n}", "revolute", f"arm{n}", f"rod{n}", xyz=(l1, 0.0, 0.0)),
            u.joint(f"rod{n}_tip_fixed", "fixed", f"rod{n}", f"rod{n}_tip", xyz=(l2, 0.0, 0.0)),
        ]
        reference[f"crank{n}"] = (_wrap(c["q"]),)
        reference[f"elbow{n}"] = (_wrap(c["psi"] - c["q"]),)
        ends.append(f"rod{n}_tip")

    # the platform: its frame at leg 1's platform point, turned by rz
    offset = -P[0]
    joint_marks = [
        u.cylinder_visual(1.2 * radius, 3 * radius, "joint", (*(P[j] - P[0]), 0.0)) for j in range(3)
    ]
    links.append(
        parts.disc(
            "platform",
            platform_mass,
            float(np.max(np.linalg.norm(P, axis=1))) or size,
            (*offset, 0.0),
            joint_marks,
        )
    )
    if leg == "PRP":
        assert V is not None
        joints.append(u.joint("platform_fixed", "fixed", ends[0], "platform", rpy=(0.0, 0.0, -_angle(V[0]))))
    else:
        joints.append(u.joint("wrist1", "revolute", ends[0], "platform"))
        reference["wrist1"] = (_wrap(rz - coords[0]["psi"]),)
    links.append(u.link("platform_center"))
    joints.append(
        u.joint("platform_center_fixed", "fixed", "platform", "platform_center", xyz=(*offset, 0.0))
    )
    closures = []
    for j in (1, 2):
        yaw = _angle(V[j]) if V is not None else 0.0
        links.append(u.link(f"platform_p{j + 1}"))
        joints.append(
            u.joint(
                f"platform_p{j + 1}_fixed",
                "fixed",
                "platform",
                f"platform_p{j + 1}",
                xyz=(*(P[j] - P[0]), 0.0),
                rpy=(0.0, 0.0, yaw),
            )
        )
        closures.append(
            ClosureSpec(
                f"leg{j + 1}_platform", (ends[j], f"platform_p{j + 1}"), "weld" if leg == "PRP" else "point"
            )
        )
    links.insert(0, u.link("base", visuals=base_visuals))
    sidecar = Sidecar(
        closures=tuple(closures),
        actuation=parts.actuators([f"{ACTUATED[leg]}{i}" for i in (1, 2, 3)], effort),
        task=TaskSpec("platform_center", ("x", "y", "rz")),
        gravity=g,
        reference=reference,
        name=name,
        source=source or f"plm_pin.legs.planar: a planar 3-{leg}",
    )
    return yourdfpy.Robot(name=name, links=links, joints=joints), sidecar


def planar(
    leg: str,
    base: Sequence[Sequence[float]],
    platform: Sequence[Sequence[float]],
    *,
    folder: str | Path,
    name: str = "planar",
    source: str = "",
    **options: Any,
) -> Path:
    """Write a planar 3-RPR, 3-PRR, 3-RRR or 3-PRP (task x, y, rz) as ``<name>.urdf`` + ``<name>.plm.yaml``.

    Args:
        leg: the leg type, as :func:`build_planar`.
        base: the base points [m], as :func:`build_planar`.
        platform: the platform points [m], as :func:`build_planar`.
        folder: where the two files go (created if needed).
        name: the file stem and robot name.
        source: provenance written into the sidecar.
        options: the other keyword arguments of :func:`build_planar`.

    Returns:
        The URDF's path, for :func:`plm_pin.load`.

    Raises:
        InvalidInput: as :func:`build_planar`, an unknown option, or a ``name`` that is not a file stem.
    """
    return parts.write(build_planar, folder, name, source, leg=leg, base=base, platform=platform, **options)
