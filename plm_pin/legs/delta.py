r"""Clavel's Delta with parallelograms (task x, y, z).

Arm ``i`` turns about the horizontal tangent :math:`k_i` of its pivot :math:`a_i` about the
base centroid (``crank<i>``, driven), its angle :math:`\theta_i` measured from the outward
radial direction :math:`e_i`, positive downwards (the crank frame has z along :math:`k_i`,
x along :math:`e_i`, so y points down). Its elbow is
:math:`E_i = a_i + l_a (\cos\theta_i\, e_i - \sin\theta_i\, \hat z)`. A parallelogram joins the
elbow to the platform point :math:`C_i = p + b_i`: two rods of length :math:`l_b`, ball-ended,
``width`` apart along :math:`k_i` (at :math:`E_i \pm \tfrac{w}{2} k_i` and
:math:`C_i \pm \tfrac{w}{2} k_i`), which keep the platform level. Both rods give the same
condition :math:`|C_i - E_i| = l_b`, Clavel's closed form: in the crank frame, with
:math:`d = C_i - a_i`, :math:`\theta_i = \operatorname{atan2}(d_y, d_x) + \sigma_i
\arccos(K / \sqrt{d_x^2 + d_y^2})`, :math:`K = (|d|^2 + l_a^2 - l_b^2) / (2 l_a)`; by
default the branch whose arm points most outward (the larger :math:`\cos\theta_i`, elbows out).

Spanning tree: the platform hangs from the base on a ``floating`` joint; each of the six
rods hangs from its arm on a universal joint (its idle spin dropped,
:mod:`plm_pin.legs.parts`) and is closed on the platform by a ``point`` closure (the lower
ball): nv = 6 + 3 + 6 x 2 = 21, 18 closure rows, mobility 3.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._arguments import finite_array, length
from .._lazy import lazy_module
from ..description import urdf_parts as u
from ..description.sidecar import ClosureSpec, Sidecar, TaskSpec
from ..exceptions import InvalidInput
from . import parts
from .hexapod import crank_angle, crank_frame, default_axes

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")


def build_delta(
    *,
    base: Sequence[Sequence[float]],
    platform: Sequence[Sequence[float]],
    arm: float,
    forearm: float,
    pose: Sequence[float],
    width: float | None = None,
    modes: Sequence[int] | None = None,
    density: float = 1.0,
    platform_mass: float = 1.0,
    effort: tuple[float, float] | None = None,
    gravity: Sequence[float] = (0.0, 0.0, -9.81),
    name: str = "delta",
    source: str = "",
) -> parts.Built:
    """Build a Clavel Delta with parallelograms (module docstring) as a URDF tree plus sidecar.

    Args:
        base: the arm pivots :math:`a_i`, three (x, y, z) [m], not at their centroid.
        platform: the parallelograms' lower midpoints :math:`b_i`, three (x, y, z) in the
            platform frame [m].
        arm: arm (upper link) length :math:`l_a` [m].
        forearm: rod length :math:`l_b` of the parallelograms [m].
        pose: the platform position ``(x, y, z)`` [m] of the reference configuration.
        width: distance between a parallelogram's two rods [m] (default ``forearm / 4``).
        modes: the elbow branch of each arm, +1 or -1 (default: each arm pointing most outward).
        density: mass per length of the arms and rods [kg/m].
        platform_mass: platform mass [kg], at the platform centre.
        effort: motor torque limits ``(lower, upper)`` [N m], or None (unbounded).
        gravity: gravity in the world frame [m/s^2].
        name: robot name.
        source: provenance written into the sidecar.

    Returns:
        The URDF tree and its sidecar.

    Raises:
        InvalidInput: points of the wrong count, a length not > 0, a pivot at the base
            centroid, or a reference pose an arm cannot reach (the message names the arm).
    """
    a = parts.points(base, "base", 3, 3)
    b = parts.points(platform, "platform", 3, 3)
    la = length(arm, "arm")
    lb = length(forearm, "forearm")
    w = length(width, "width") if width is not None else lb / 4
    p = finite_array(pose, "pose", (3,), "x, y, z [m]")
    sig: Sequence[int | None] = parts.signs(modes, "modes", 3) if modes is not None else (None,) * 3
    density, platform_mass, _ = parts.masses(density, platform_mass, 0.0)
    g = parts.gravity_vector(gravity)
    centroid = a.mean(axis=0)
    radial = a - centroid
    radial[:, 2] = 0.0
    if not np.all(np.linalg.norm(radial, axis=1) > 0):
        raise InvalidInput(
            "base: the arm pivots must lie around their centroid (none on the vertical through it), "
            f"got {a.tolist()}"
        )
    K = default_axes(a)
    C = p + b
    size = max(float(np.max(np.linalg.norm(radial, axis=1))), la)
    radius = 0.02 * size
    where = f"delta: at the reference pose {tuple(p.tolist())}"
    links: list[yourdfpy.Link] = []
    joints: list[yourdfpy.Joint] = []
    reference: parts.Reference = {}
    closures: list[ClosureSpec] = []
    points: dict[str, np.ndarray] = {}
    base_visuals = [
        u.cylinder_visual(
            1.3 * size, 0.02 * size, "base", (*centroid[:2], float(a[:, 2].max()) + 0.03 * size)
        )
    ]
    for i in range(3):
        n = i + 1
        rpy = crank_frame(K[i], radial[i])
        Rc = u.transform(rpy=rpy)[:3, :3]
        d = Rc.T @ (C[i] - a[i])
        theta = crank_angle(d, la, lb, sig[i])
        if theta is None:
            raise InvalidInput(
                f"{where}, arm {n} ({la:.6g} m) and its rods ({lb:.6g} m) cannot reach the platform"
            )
        elbow = la * np.array([math.cos(theta), math.sin(theta), 0.0])
        rot = u.transform(rpy=(0.0, 0.0, theta))[:3, :3]
        direction = rot.T @ (d - elbow) / lb
        ai = tuple(float(c) for c in a[i])
        base_visuals.append(u.cylinder_visual(1.5 * radius, 8 * radius, "joint", ai, rpy))
        elbow_bar = u.cylinder_visual(radius, w, "slider", (la, 0.0, 0.0))
        arm_link = parts.rod_along_x(f"arm{n}", 0.0, la, density, 1.5 * radius, "slider")
        arm_link.visuals.append(elbow_bar)
        links.append(arm_link)
        joints.append(u.joint(f"crank{n}", "revolute", "base", f"arm{n}", xyz=ai, rpy=rpy))
        reference[f"crank{n}"] = (math.remainder(theta, 2 * math.pi) + 0.0,)
        for side, sign in (("a", 1.0), ("b", -1.0)):
            label = f"{n}{side}"
            end = parts.universal_rod(
                links, joints, f"arm{n}", (la, 0.0, sign * w / 2), direction, lb, label, density, radius
            )
            reference.update({f"u{label}a": (0.0,), f"u{label}b": (0.0,)})
            points[f"platform_p{label}"] = b[i] + sign * w / 2 * K[i]
            closures.append(ClosureSpec(f"rod{label}_platform", (end, f"platform_p{label}"), "point"))
    links.insert(0, u.link("base", visuals=base_visuals))
    parts.floating_platform(links, joints, reference, points, (*p, 0.0, 0.0, 0.0), platform_mass, radius)
    sidecar = Sidecar(
        closures=tuple(closures),
        actuation=parts.actuators([f"crank{i}" for i in (1, 2, 3)], effort),
        task=TaskSpec("platform_center", ("x", "y", "z")),
        gravity=g,
        reference=reference,
        name=name,
        source=source or "plm_pin.legs.delta: Clavel's Delta with parallelograms",
    )
    return yourdfpy.Robot(name=name, links=links, joints=joints), sidecar


def delta(
    base: Sequence[Sequence[float]],
    platform: Sequence[Sequence[float]],
    *,
    folder: str | Path,
    name: str = "delta",
    source: str = "",
    **options: Any,
) -> Path:
    """Write a Clavel Delta with parallelograms (task x, y, z) as ``<name>.urdf`` + ``<name>.plm.yaml``.

    Args:
        base: the base points [m], as :func:`build_delta`.
        platform: the platform points [m], as :func:`build_delta`.
        folder: where the two files go (created if needed).
        name: the file stem and robot name.
        source: provenance written into the sidecar.
        options: the other keyword arguments of :func:`build_delta`.

    Returns:
        The URDF's path, for :func:`plm_pin.load`.

    Raises:
        InvalidInput: as :func:`build_delta`, an unknown option, or a ``name`` that is not a file stem.
    """
    return parts.write(build_delta, folder, name, source, base=base, platform=platform, **options)
