"""Building blocks of the parametric builders: yourdfpy links and joints with inertias and simple visuals."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from .._lazy import lazy_module

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")

from .._text import short
from ..exceptions import DescriptionError

Vec3 = Sequence[float]

COLORS: dict[str, tuple[float, float, float, float]] = {
    "base": (0.55, 0.57, 0.60, 1.0),
    "slider": (0.20, 0.45, 0.80, 1.0),
    "rod": (0.80, 0.82, 0.86, 1.0),  # light steel: no yellow, orange or red, the scene's singularity colours
    "plate": (0.30, 0.70, 0.35, 1.0),
    "joint": (0.35, 0.35, 0.35, 1.0),
}
"""RGBA of the builders' visuals by part; none near the scene's singularity colours (a test checks)."""


def transform(xyz: Vec3 = (0.0, 0.0, 0.0), rpy: Vec3 = (0.0, 0.0, 0.0)) -> np.ndarray:
    """Homogeneous transform from a translation [m] and roll-pitch-yaw angles [rad], shape (4, 4)."""
    roll, pitch, yaw = rpy
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    T = np.eye(4)
    T[:3, :3] = np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )
    T[:3, 3] = xyz
    return T


def universal_frame_rpy(direction: Vec3 | np.ndarray) -> Vec3:
    r"""Roll-pitch-yaw [rad] of a frame whose z axis is ``direction`` (unit), yaw 0.

    :math:`R_y(\beta) R_x(\alpha) \hat z = (s_\beta c_\alpha, -s_\alpha, c_\beta c_\alpha)`.
    """
    ex, ey, ez = (float(c) for c in direction)
    return (math.atan2(-ey, math.hypot(ex, ez)) + 0.0, math.atan2(ex, ez) + 0.0, 0.0)


def universal_angles(strut: np.ndarray, frame_rpy: Sequence[float]) -> tuple[float, float]:
    r"""Universal-joint angles :math:`(\alpha, \beta)` [rad] that point the strut along ``strut``.

    The strut's z axis is :math:`R_\rho R_x(\alpha) R_y(\beta) \hat z` with :math:`R_\rho`
    the universal joint's frame; with :math:`d = R_\rho^T w = (s_\beta, -s_\alpha c_\beta,
    c_\alpha c_\beta)`: :math:`\beta = \arcsin d_x`, :math:`\alpha = \operatorname{atan2}(-d_y, d_z)`.
    """
    d = transform(rpy=frame_rpy)[:3, :3].T @ np.asarray(strut, dtype=float)
    return math.atan2(-d[1], d[2]) + 0.0, math.asin(max(-1.0, min(1.0, float(d[0])))) + 0.0


def frame_rpy(x_axis: Vec3 | np.ndarray, z_axis: Vec3 | np.ndarray) -> Vec3:
    """Roll-pitch-yaw [rad] of the frame whose z axis is ``z_axis`` and whose x axis is ``x_axis``.

    ``z_axis`` is normalised; ``x_axis`` is made normal to it (its component along ``z_axis`` removed).

    Raises:
        DescriptionError: a zero ``z_axis``, or an ``x_axis`` along it.
    """
    z = np.asarray(z_axis, dtype=float)
    x = np.asarray(x_axis, dtype=float)
    nz = float(np.linalg.norm(z))
    if not nz > 0.0:
        raise DescriptionError(f"frame_rpy: the z axis must be a non-zero vector, got {tuple(z_axis)}")
    z = z / nz
    x = x - float(x @ z) * z
    nx = float(np.linalg.norm(x))
    if not nx > 0.0:
        raise DescriptionError(f"frame_rpy: the x axis {tuple(x_axis)} lies along the z axis {tuple(z_axis)}")
    x = x / nx
    R = np.column_stack([x, np.cross(z, x), z])
    pitch = math.asin(max(-1.0, min(1.0, -float(R[2, 0]))))
    roll = math.atan2(float(R[2, 1]), float(R[2, 2]))
    return (roll + 0.0, pitch + 0.0, math.atan2(float(R[1, 0]), float(R[0, 0])) + 0.0)


def material(kind: str) -> yourdfpy.Material:
    """A named colour material (one of :data:`COLORS`)."""
    return yourdfpy.Material(name=kind, color=yourdfpy.Color(rgba=np.array(COLORS[kind])))


def box_inertia(mass: float, size: Vec3) -> np.ndarray:
    """Inertia tensor of a solid box about its centre [kg m^2], shape (3, 3)."""
    a, b, c = size
    return mass / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def link(
    name: str,
    mass: float = 0.0,
    inertia: np.ndarray | Sequence[float] | None = None,
    com: Vec3 = (0.0, 0.0, 0.0),
    visuals: Sequence[yourdfpy.Visual] = (),
) -> yourdfpy.Link:
    """A link with an inertial (omitted when ``mass`` and ``inertia`` are 0) and visuals.

    Args:
        name: link name.
        mass: mass [kg].
        inertia: inertia tensor about the centre of mass [kg m^2], (3, 3) or diagonal (3,).
        com: centre of mass in the link frame [m].
        visuals: visual elements.

    Raises:
        DescriptionError: a negative or non-finite mass (the URDF reader checks the inertia).
    """
    if not (math.isfinite(mass) and mass >= 0.0):
        raise DescriptionError(f"link {short(name)}: the mass must be finite and >= 0 [kg], got {mass!r}")
    I = np.zeros((3, 3)) if inertia is None else np.asarray(inertia, dtype=float)
    if I.shape == (3,):
        I = np.diag(I)
    inertial = None
    if mass > 0.0 or np.any(I != 0.0):
        inertial = yourdfpy.Inertial(origin=transform(com), mass=float(mass), inertia=I)
    return yourdfpy.Link(name=name, inertial=inertial, visuals=list(visuals))


def box_visual(
    size: Vec3, kind: str, xyz: Vec3 = (0.0, 0.0, 0.0), rpy: Vec3 = (0.0, 0.0, 0.0)
) -> yourdfpy.Visual:
    """A box visual [m]."""
    return yourdfpy.Visual(
        origin=transform(xyz, rpy),
        geometry=yourdfpy.Geometry(box=yourdfpy.Box(size=np.asarray(size, dtype=float))),
        material=material(kind),
    )


def cylinder_visual(
    radius: float, length: float, kind: str, xyz: Vec3 = (0.0, 0.0, 0.0), rpy: Vec3 = (0.0, 0.0, 0.0)
) -> yourdfpy.Visual:
    """A cylinder visual (axis along the visual frame's z) [m]."""
    return yourdfpy.Visual(
        origin=transform(xyz, rpy),
        geometry=yourdfpy.Geometry(cylinder=yourdfpy.Cylinder(radius=radius, length=length)),
        material=material(kind),
    )


def sphere_visual(radius: float, kind: str, xyz: Vec3 = (0.0, 0.0, 0.0)) -> yourdfpy.Visual:
    """A sphere visual [m]."""
    return yourdfpy.Visual(
        origin=transform(xyz),
        geometry=yourdfpy.Geometry(sphere=yourdfpy.Sphere(radius=radius)),
        material=material(kind),
    )


def joint(
    name: str,
    kind: str,
    parent: str,
    child: str,
    xyz: Vec3 = (0.0, 0.0, 0.0),
    rpy: Vec3 = (0.0, 0.0, 0.0),
    axis: Vec3 = (0.0, 0.0, 1.0),
    limits: tuple[float, float] | None = None,
    effort: float = 1000.0,
    velocity: float = 100.0,
) -> yourdfpy.Joint:
    """A joint: ``kind`` is revolute, continuous, prismatic, fixed or floating.

    Args:
        name: joint name.
        kind: URDF joint type.
        parent: parent link name.
        child: child link name.
        xyz: joint origin in the parent link frame [m].
        rpy: joint origin roll-pitch-yaw [rad].
        axis: joint axis in the joint frame.
        limits: position limits [m] or [rad] (revolute and prismatic).
        effort: URDF effort limit [N] or [N m] (informative; actuator limits live in the sidecar).
        velocity: URDF velocity limit [m/s] or [rad/s].
    """
    limit = None
    if kind in ("revolute", "prismatic"):
        lo, hi = limits if limits is not None else (-2 * np.pi, 2 * np.pi)
        limit = yourdfpy.Limit(effort=effort, velocity=velocity, lower=lo, upper=hi)
    elif kind == "continuous":
        limit = yourdfpy.Limit(effort=effort, velocity=velocity)
    return yourdfpy.Joint(
        name=name,
        type=kind,
        parent=parent,
        child=child,
        origin=transform(xyz, rpy),
        axis=None if kind in ("fixed", "floating") else np.asarray(axis, dtype=float),
        limit=limit,
    )
