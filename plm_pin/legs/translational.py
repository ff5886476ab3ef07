r"""Tsai's 3-UPU translational platform (task x, y, z).

Leg ``i`` joins the base point :math:`a_i` to the platform point :math:`C_i = p + b_i` (the
platform keeps its orientation) by a universal joint, a driven cylinder of length
:math:`\rho_i = |p + b_i - a_i|` (prismatic ``extend<i>``) and a second universal joint. Tsai's
conditions make the platform translate only: the first axis of the base joint and the last
axis of the platform joint are parallel (:math:`s_i`, ``axes``; default the horizontal tangent
of :math:`a_i` about the base centroid), and the two middle axes are parallel to each other
(normal to :math:`s_i` and to the leg). Each leg then forbids the rotation about the normal of
its plane; three legs with independent :math:`s_i` forbid every rotation.

Spanning tree: the platform hangs from the base on a ``floating`` joint; each leg is
``u<i>a`` (about :math:`s_i`) -> ``u<i>b`` -> ``extend<i>`` -> ``u<i>c`` (parallel to ``u<i>b``),
closed on the platform frame ``platform_p<i>`` by a ``revolute`` closure about :math:`s_i`
(the platform joint's last axis). nv = 6 + 3 x 4 = 18, 15 closure rows: mobility 3.
"""

from __future__ import annotations

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
from .hexapod import default_axes

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")

TRANSLATIONAL_LEGS = ("UPU",)
"""The leg types of the translational platform."""


def build_translational(
    *,
    leg: str,
    base: Sequence[Sequence[float]],
    platform: Sequence[Sequence[float]],
    pose: Sequence[float],
    axes: Sequence[Sequence[float]] | None = None,
    stroke: tuple[float, float] | None = None,
    density: float = 1.0,
    platform_mass: float = 1.0,
    effort: tuple[float, float] | None = None,
    gravity: Sequence[float] = (0.0, 0.0, -9.81),
    name: str = "translational",
    source: str = "",
) -> parts.Built:
    """Build Tsai's 3-UPU translational platform (module docstring) as a URDF tree plus sidecar.

    Args:
        leg: ``"UPU"``.
        base: the base joint centres :math:`a_i`, three (x, y, z) [m].
        platform: the platform joint centres :math:`b_i`, three (x, y, z) in the platform frame [m].
        pose: the platform position ``(x, y, z)`` [m] of the reference configuration.
        axes: the axes :math:`s_i` of the base joints' first and the platform joints' last
            revolute, three (x, y, z) (normalised; default: the horizontal tangents of the
            base points about their centroid).
        stroke: the leg-length limits ``(lower, upper)`` [m], 0 < lower; default around the reference.
        density: mass per length of the cylinders and pistons [kg/m].
        platform_mass: platform mass [kg], at the platform centre.
        effort: actuator force limits ``(lower, upper)`` [N], or None (unbounded).
        gravity: gravity in the world frame [m/s^2].
        name: robot name.
        source: provenance written into the sidecar.

    Returns:
        The URDF tree and its sidecar.

    Raises:
        InvalidInput: another leg type, points or axes of the wrong count, a zero axis, a leg
            along its axis :math:`s_i`, or a reference pose out of the stroke.
    """
    leg = parts.leg_type(leg, TRANSLATIONAL_LEGS, "translational")
    a = parts.points(base, "base", 3, 3)
    b = parts.points(platform, "platform", 3, 3)
    p = finite_array(pose, "pose", (3,), "x, y, z [m]")
    density, platform_mass, _ = parts.masses(density, platform_mass, 0.0)
    g = parts.gravity_vector(gravity)
    S = parts.directions(axes, "axes", 3, 3) if axes is not None else default_axes(a)
    D = p + b - a
    rho = np.linalg.norm(D, axis=1)
    where = f"translational UPU: at the reference pose {tuple(p.tolist())}"
    lo, hi = parts.interval(
        stroke if stroke is not None else (0.5 * rho.min(), 1.5 * rho.max()), "stroke", "m", positive=True
    )
    size = max(
        float(np.max(np.linalg.norm(a - a.mean(axis=0), axis=1))),
        float(np.max(np.linalg.norm(b, axis=1))),
        0.0,
    )
    size = size if size > 0 else 1.0
    radius = 0.02 * size
    links: list[yourdfpy.Link] = []
    joints: list[yourdfpy.Joint] = []
    reference: parts.Reference = {}
    closures: list[ClosureSpec] = []
    frames: dict[str, tuple[float, float, float]] = {}
    base_visuals = [
        u.cylinder_visual(1.2 * size, 0.02 * size, "base", (0.0, 0.0, float(a[:, 2].min()) - 0.03 * size))
    ]
    for i in range(3):
        n = i + 1
        if not lo <= rho[i] <= hi:
            raise InvalidInput(f"{where}, leg {n}'s length {rho[i]:.6g} m is outside stroke {(lo, hi)}")
        w = D[i] / rho[i]
        normal = w - float(w @ S[i]) * S[i]
        if not float(np.linalg.norm(normal)) > 0.0:
            raise InvalidInput(
                f"{where}, leg {n} lies along its axis s_{n} = {tuple(S[i].tolist())} (a locked joint)"
            )
        rpy = u.frame_rpy(S[i], normal)  # x along s_i, the leg in the frame's x-z plane
        alpha, beta = u.universal_angles(w, rpy)
        ai = tuple(float(c) for c in a[i])
        base_visuals.append(u.sphere_visual(1.5 * radius, "joint", ai))
        links += [
            u.link(f"cross{n}"),
            parts.rod_along_z(f"cylinder{n}", 0.0, lo, density, 1.6 * radius, "slider"),
            parts.rod_along_z(f"piston{n}", -lo, 0.0, density, radius),
            u.link(f"end{n}", visuals=[u.sphere_visual(1.5 * radius, "joint")]),
        ]
        joints += [
            u.joint(f"u{n}a", "revolute", "base", f"cross{n}", xyz=ai, rpy=rpy, axis=(1, 0, 0)),
            u.joint(f"u{n}b", "revolute", f"cross{n}", f"cylinder{n}", axis=(0, 1, 0)),
            u.joint(f"extend{n}", "prismatic", f"cylinder{n}", f"piston{n}", axis=(0, 0, 1), limits=(lo, hi)),
            u.joint(f"u{n}c", "revolute", f"piston{n}", f"end{n}", axis=(0, 1, 0)),
        ]
        reference.update(
            {f"u{n}a": (alpha,), f"u{n}b": (beta,), f"extend{n}": (float(rho[i]),), f"u{n}c": (-beta,)}
        )
        frames[f"platform_p{n}"] = (*rpy,)  # type: ignore[assignment]
        closures.append(
            ClosureSpec(f"leg{n}_platform", (f"end{n}", f"platform_p{n}"), "revolute", (1.0, 0.0, 0.0))
        )
    links.insert(0, u.link("base", visuals=base_visuals))
    points = {f"platform_p{i + 1}": b[i] for i in range(3)}
    parts.floating_platform(
        links, joints, reference, points, (*p, 0.0, 0.0, 0.0), platform_mass, radius, frames
    )
    sidecar = Sidecar(
        closures=tuple(closures),
        actuation=parts.actuators([f"extend{i}" for i in (1, 2, 3)], effort),
        task=TaskSpec("platform_center", ("x", "y", "z")),
        gravity=g,
        reference=reference,
        name=name,
        source=source or "plm_pin.legs.translational: Tsai's 3-UPU",
    )
    return yourdfpy.Robot(name=name, links=links, joints=joints), sidecar


def translational(
    leg: str,
    base: Sequence[Sequence[float]],
    platform: Sequence[Sequence[float]],
    *,
    folder: str | Path,
    name: str = "translational",
    source: str = "",
    **options: Any,
) -> Path:
    """Write Tsai's 3-UPU translational platform (task x, y, z) as ``<name>.urdf`` + ``<name>.plm.yaml``.

    Args:
        leg: the leg type, as :func:`build_translational`.
        base: the base points [m], as :func:`build_translational`.
        platform: the platform points [m], as :func:`build_translational`.
        folder: where the two files go (created if needed).
        name: the file stem and robot name.
        source: provenance written into the sidecar.
        options: the other keyword arguments of :func:`build_translational`.

    Returns:
        The URDF's path, for :func:`plm_pin.load`.

    Raises:
        InvalidInput: as :func:`build_translational`, an unknown option, or a ``name`` not a file stem.
    """
    return parts.write(
        build_translational, folder, name, source, leg=leg, base=base, platform=platform, **options
    )
