r"""What every leg builder shares: argument checks, rods and platforms drawn simply, writing to a folder.

Rods are uniform bars of ``density`` [kg/m]: mass :math:`m = \rho L`, centroidal transverse
inertia :math:`m L^2 / 12`. A rod hung on a universal joint and closed by a point (a ball) at
its other end gets an axial moment of zero: its spin about its own axis is idle (an S-S rod
transmits no axial torque), and the universal joint that replaces the first ball would
otherwise make the actuators drive it (see :mod:`plm_pin.families.pss`). Platforms are discs
of the platform points' largest radius.
"""

from __future__ import annotations

import inspect
import math
import numbers
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from .._arguments import finite_array, nonnegative
from .._lazy import lazy_module
from .._text import short
from ..description import urdf_parts as u
from ..description.sidecar import ActuatorSpec, Sidecar
from ..description.writer import write_description
from ..exceptions import InvalidInput

if TYPE_CHECKING:
    import yourdfpy
else:
    yourdfpy = lazy_module("yourdfpy")

Built = tuple["yourdfpy.Robot", Sidecar]
"""What a builder returns: the URDF spanning tree and its sidecar."""

Reference = dict[str, tuple[float, ...]]
"""Joint name -> its value(s) in the reference configuration [m, rad]."""


def leg_type(leg: object, valid: Sequence[str], builder: str, hint: str = "") -> str:
    """``leg`` if it is one of ``valid`` (upper-cased), else one error listing them.

    Raises:
        InvalidInput: naming ``leg``, the value, the valid choices and ``hint``.
    """
    text = leg.upper() if isinstance(leg, str) else leg
    if text not in valid:
        raise InvalidInput(f"{builder}: leg must be one of {list(valid)}, got {short(leg)}{hint}")
    return str(text)


def points(value: object, name: str, n: int, dim: int) -> np.ndarray:
    """``value`` as ``n`` points of ``dim`` coordinates [m], shape (n, dim).

    The coordinates may also come flat, ``n * dim`` numbers point after point (the form a
    sweep varies: a tuple of numbers).

    Raises:
        InvalidInput: another count of points, of coordinates, or a non-finite one.
    """
    arr = np.asarray(value, dtype=object)
    if arr.shape == (n * dim,):
        arr = arr.reshape(n, dim)
        value = arr.tolist()
    if arr.ndim != 2 or arr.shape[0] != n:
        got = f"{arr.shape[0]} entries" if arr.ndim >= 1 else short(value)
        raise InvalidInput(f"{name} must be {n} points of {dim} coordinates [m], got {got}")
    return finite_array(value, name, (n, dim), "coordinates [m]")


def directions(value: object, name: str, n: int, dim: int) -> np.ndarray:
    """``value`` as ``n`` non-zero vectors of ``dim`` coordinates, each normalised, shape (n, dim).

    Raises:
        InvalidInput: a wrong shape, a non-finite entry or a zero vector.
    """
    arr = np.asarray(value, dtype=object)
    if arr.ndim != 2 or arr.shape[0] != n:
        raise InvalidInput(f"{name} must be {n} direction vectors of {dim} coordinates, got {short(value)}")
    arr = finite_array(value, name, (n, dim), "direction vectors")
    norms = np.linalg.norm(arr, axis=1)
    zero = np.flatnonzero(~(norms > 0.0))
    if zero.size:
        raise InvalidInput(f"{name}: direction(s) {zero.tolist()} are zero vectors; give non-zero directions")
    return np.asarray(arr / norms[:, None])


def per_leg(value: object, name: str, n: int, width: int, what: str) -> np.ndarray:
    """Positive numbers [m] per leg: ``width`` of them given once for every leg, or per leg, shape (n, width).

    A scalar is accepted when ``width`` is 1.

    Raises:
        InvalidInput: a wrong shape, or a value not finite and > 0.
    """
    shape_one = () if width == 1 else (width,)
    arr = np.asarray(value, dtype=object)
    if arr.shape in (shape_one, (width,)):
        arr = np.broadcast_to(arr.reshape(1, width), (n, width))
    elif width == 1 and arr.shape == (n,):
        arr = arr.reshape(n, 1)
    if arr.shape != (n, width):
        raise InvalidInput(
            f"{name} must be {what}, once for every leg or per leg ({n} of them), got {short(value)}"
        )
    good = [
        isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) and float(v) > 0
        for v in arr.flat
    ]
    if not all(good):
        raise InvalidInput(f"{name} must be {what}, each a finite number > 0 [m], got {short(value)}")
    return np.asarray(arr, dtype=float)


def signs(value: object, name: str, n: int) -> tuple[int, ...]:
    """``value`` as ``n`` branch signs, each +1 or -1.

    Raises:
        InvalidInput: another count, or an entry that is not +1 or -1.
    """
    if (
        not isinstance(value, Sequence | np.ndarray)
        or isinstance(value, str)
        or len(value) != n
        or any(isinstance(s, bool) or s not in (1, -1) for s in value)
    ):
        raise InvalidInput(f"{name} must be {n} branch signs, each +1 or -1, got {short(value)}")
    return tuple(int(s) for s in value)


def interval(value: object, name: str, unit: str, positive: bool = False) -> tuple[float, float]:
    """``value`` as ``(lower, upper)`` with lower < upper (and lower > 0 when ``positive``).

    Raises:
        InvalidInput: naming ``name``, the unit and the valid range.
    """
    lo, hi = finite_array(value, name, (2,), f"(lower, upper) [{unit}]").tolist()
    if not lo < hi or (positive and not lo > 0.0):
        need = "0 < lower < upper" if positive else "lower < upper"
        raise InvalidInput(f"{name} must be (lower, upper) [{unit}] with {need}, got {short(value)}")
    return float(lo), float(hi)


def unused(builder: str, leg: str, **given: object) -> None:
    """Refuse the arguments of ``given`` that are not None: ``leg`` legs take none of them.

    Raises:
        InvalidInput: naming the first such argument and the leg type.
    """
    for key, value in given.items():
        if value is not None:
            raise InvalidInput(f"{builder}: {leg} legs take no {key} (got {short(value)}); leave it None")


def needed(builder: str, leg: str, **given: object) -> None:
    """Refuse the arguments of ``given`` that are None: ``leg`` legs need them.

    Raises:
        InvalidInput: naming the first missing argument and the leg type.
    """
    for key, value in given.items():
        if value is None:
            raise InvalidInput(f"{builder}: {leg} legs need {key}")


def masses(density: object, platform_mass: object, slider_mass: object) -> tuple[float, float, float]:
    """The three mass parameters of a builder, checked (finite, >= 0).

    Raises:
        InvalidInput: naming the argument.
    """
    return (
        nonnegative(density, "density", "kg/m"),
        nonnegative(platform_mass, "platform_mass", "kg"),
        nonnegative(slider_mass, "slider_mass", "kg"),
    )


def actuators(joints: Sequence[str], effort: object) -> tuple[ActuatorSpec, ...]:
    """The driven joints, each with the effort limits ``effort`` ([N] or [N m], or None).

    Raises:
        InvalidInput: ``effort`` not None nor (lower, upper) with lower < upper.
    """
    limits = None if effort is None else interval(effort, "effort", "N or N m")
    return tuple(ActuatorSpec(j, limits) for j in joints)


def gravity_vector(value: object) -> tuple[float, float, float]:
    """``value`` as a gravity vector [m/s^2].

    Raises:
        InvalidInput: not three finite numbers.
    """
    g = finite_array(value, "gravity", (3,), "components [m/s^2]").tolist()
    return (float(g[0]), float(g[1]), float(g[2]))


ROD_X_RPY = (0.0, math.pi / 2, 0.0)
"""Roll-pitch-yaw turning a cylinder visual's z axis onto x."""


def rod_along_x(
    name: str, start: float, stop: float, density: float, radius: float, kind: str = "rod"
) -> yourdfpy.Link:
    """A bar along the link's x axis from ``start`` to ``stop`` [m], of ``density`` [kg/m]."""
    length = abs(stop - start)
    m = density * length
    mid = 0.5 * (start + stop)
    visuals = [u.cylinder_visual(radius, length, kind, (mid, 0.0, 0.0), ROD_X_RPY)] if length > 0 else []
    axial = 0.5 * m * radius**2
    return u.link(
        name,
        m,
        (axial, m * length**2 / 12 + axial / 2, m * length**2 / 12 + axial / 2),
        (mid, 0.0, 0.0),
        visuals,
    )


def rod_along_z(
    name: str, start: float, stop: float, density: float, radius: float, kind: str = "rod"
) -> yourdfpy.Link:
    """A bar along the link's z axis from ``start`` to ``stop`` [m], its axial moment 0 (module docstring)."""
    length = abs(stop - start)
    m = density * length
    transverse = m * length**2 / 12
    mid = (0.0, 0.0, 0.5 * (start + stop))
    return u.link(name, m, (transverse, transverse, 0.0), mid, [u.cylinder_visual(radius, length, kind, mid)])


def pose_rotation(rpy: Sequence[float] | np.ndarray) -> np.ndarray:
    r"""The rotation :math:`R = R_z(r_z) R_y(r_y) R_x(r_x)` of roll-pitch-yaw angles [rad], shape (3, 3)."""
    return u.transform(rpy=tuple(rpy))[:3, :3]


def universal_rod(
    links: list[yourdfpy.Link],
    joints: list[yourdfpy.Joint],
    parent: str,
    xyz: Sequence[float],
    direction: np.ndarray,
    length: float,
    label: str,
    density: float,
    radius: float,
) -> str:
    """Hang a rod of ``length`` [m] on a universal joint at ``xyz`` of ``parent``, along ``direction``.

    ``direction`` (unit, in ``parent``'s frame) is the rod's direction in the reference
    configuration: the joint's frame has its z axis there, so both angles (``u<label>a`` about
    x, then ``u<label>b`` about y) are 0 in the reference, 90 deg away from the joint's lock.

    Returns:
        The name of the frame at the rod's free end, ``rod<label>_tip``.
    """
    rpy = u.universal_frame_rpy(direction)
    links += [
        u.link(f"cross{label}"),
        rod_along_z(f"rod{label}", 0.0, length, density, radius),
        u.link(f"rod{label}_tip"),
    ]
    joints += [
        u.joint(f"u{label}a", "revolute", parent, f"cross{label}", xyz=tuple(xyz), rpy=rpy, axis=(1, 0, 0)),
        u.joint(f"u{label}b", "revolute", f"cross{label}", f"rod{label}", axis=(0, 1, 0)),
        u.joint(f"rod{label}_tip_fixed", "fixed", f"rod{label}", f"rod{label}_tip", xyz=(0.0, 0.0, length)),
    ]
    return f"rod{label}_tip"


def floating_platform(
    links: list[yourdfpy.Link],
    joints: list[yourdfpy.Joint],
    reference: Reference,
    platform_points: dict[str, np.ndarray],
    pose: Sequence[float] | np.ndarray,
    mass: float,
    radius: float,
    frame_rpy: Mapping[str, Sequence[float]] | None = None,
) -> None:
    """Add the platform on a floating joint at ``pose`` (x, y, z [m], rx, ry, rz [rad]) with its frames.

    ``platform_points`` maps each frame name to its position in the platform frame [m]
    (``frame_rpy`` optionally to its orientation); ``platform_center`` is the platform frame.
    """
    size = max((float(np.linalg.norm(b)) for b in platform_points.values()), default=0.0) or radius * 10
    marks = [
        u.sphere_visual(1.5 * radius, "joint", tuple(float(c) for c in b)) for b in platform_points.values()
    ]
    links.append(disc("platform", mass, size, (0.0, 0.0, 0.0), marks))
    joints.append(u.joint("platform_floating", "floating", "base", "platform"))
    for frame, b in platform_points.items():
        rpy = (frame_rpy or {}).get(frame, (0.0, 0.0, 0.0))
        links.append(u.link(frame))
        joints.append(
            u.joint(f"{frame}_fixed", "fixed", "platform", frame, xyz=tuple(float(c) for c in b), rpy=rpy)
        )
    links.append(u.link("platform_center"))
    joints.append(u.joint("platform_center_fixed", "fixed", "platform", "platform_center"))
    quaternion = pin.Quaternion(pose_rotation(pose[3:6])).coeffs()
    reference["platform_floating"] = (*(float(c) for c in pose[:3]), *(float(c) for c in quaternion))


def disc(
    name: str, mass: float, radius: float, centre: Sequence[float], extra: Sequence[Any] = ()
) -> yourdfpy.Link:
    """A platform: a thin disc of ``radius`` [m] and ``mass`` [kg] centred at ``centre`` (link frame)."""
    inertia = (mass * radius**2 / 4, mass * radius**2 / 4, mass * radius**2 / 2)
    thickness = 0.1 * radius
    visuals = [u.cylinder_visual(radius, thickness, "plate", tuple(centre)), *extra]
    return u.link(name, mass, inertia, tuple(float(c) for c in centre), visuals)


def write(build: Callable[..., Built], folder: str | Path, name: str, source: str, **parameters: Any) -> Path:
    """Build with ``parameters`` and write ``<name>.urdf`` and ``<name>.plm.yaml`` into ``folder``.

    Returns:
        The URDF's path (give it to :func:`plm_pin.load`).
    """
    valid = inspect.signature(build).parameters
    unknown = sorted(set(parameters) - set(valid))
    if unknown:
        options = sorted(set(valid) - {"name", "source"} - set(parameters))
        raise InvalidInput(
            f"unknown option(s) {unknown} of {build.__name__}; its other options are {options}"
        )
    robot, sidecar = build(name=name, source=source, **parameters)
    urdf, _ = write_description(robot, sidecar, folder, name)
    return urdf
