"""Small mechanisms built inline for the stiffness oracles: a 6-UPS platform, a cantilever, a pendulum."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import yourdfpy

import plm_pin
from plm_pin.core.mechanism import Mechanism
from plm_pin.description import urdf_parts as u
from plm_pin.description import write_description
from plm_pin.description.sidecar import parse_sidecar

BASE_RADIUS, PLATFORM_RADIUS, HEIGHT = 0.5, 0.3, 0.6


def _z_to(d: np.ndarray) -> np.ndarray:
    """Roll-pitch-yaw of a rotation taking z onto the unit vector ``d``."""
    z = d / np.linalg.norm(d)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    return pin.rpy.matrixToRpy(np.column_stack([x, np.cross(z, x), z]))


def _platform_frames(links: list, joints: list, b: np.ndarray) -> None:
    """Append the platform's anchor frames ``platform_b2`` ... (leg 1 carries it at b_1) and its centre."""
    for i in range(1, len(b)):
        links.append(u.link(f"platform_b{i + 1}"))
        joints.append(
            u.joint(
                f"platform_b{i + 1}_fixed", "fixed", "platform", f"platform_b{i + 1}", xyz=tuple(b[i] - b[0])
            )
        )
    links.append(u.link("platform_center"))
    joints.append(u.joint("platform_center_fixed", "fixed", "platform", "platform_center", xyz=tuple(-b[0])))


def stewart_points() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Base anchors a_i (world), platform anchors b_i (platform frame), platform centre (world)."""
    ta = np.deg2rad([0, 100, 120, 220, 240, 340]) + 0.1
    tb = np.deg2rad([40, 70, 160, 190, 280, 310])
    a = np.column_stack([BASE_RADIUS * np.cos(ta), BASE_RADIUS * np.sin(ta), np.zeros(6)])
    b = np.column_stack([PLATFORM_RADIUS * np.cos(tb), PLATFORM_RADIUS * np.sin(tb), np.zeros(6)])
    return a, b, np.array([0.02, -0.01, HEIGHT])


def stewart(tmp_path: Path, platform_mass: float = 0.0, spin: bool = False) -> Mechanism:
    """A 6-UPS Stewart-Gough platform: U at the base, driven prismatic leg, ball (point closure) at the top.

    Leg 1 carries the platform through a ball made of three revolutes; legs 2-6 end in a point
    closure. The platform is world-aligned at the reference. Legs are massless. With ``spin``,
    legs 2-6 also turn about their own axis (6-SPS): five idle motions.
    """
    a, b, p = stewart_points()
    links = [u.link("base")]
    joints = []
    closures = []
    reference: dict[str, Any] = {}
    for i in range(6):
        d = p + b[i] - a[i]
        n = i + 1
        links += [u.link(f"leg{n}_u"), u.link(f"leg{n}_cyl"), u.link(f"leg{n}_rod")]
        joints += [
            u.joint(
                f"leg{n}_ux",
                "revolute",
                "base",
                f"leg{n}_u",
                xyz=tuple(a[i]),
                rpy=tuple(_z_to(d)),
                axis=(1, 0, 0),
            ),
            u.joint(f"leg{n}_uy", "revolute", f"leg{n}_u", f"leg{n}_cyl", axis=(0, 1, 0)),
        ]
        cyl = f"leg{n}_cyl"
        if spin and n > 1:
            links.append(u.link(f"leg{n}_spun"))
            joints.append(u.joint(f"leg{n}_spin", "revolute", cyl, f"leg{n}_spun"))
            reference[f"leg{n}_spin"] = 0.0
            cyl = f"leg{n}_spun"
        joints.append(
            u.joint(f"leg{n}_slide", "prismatic", cyl, f"leg{n}_rod", axis=(0, 0, 1), limits=(0.0, 2.0))
        )
        reference.update({f"leg{n}_ux": 0.0, f"leg{n}_uy": 0.0, f"leg{n}_slide": float(np.linalg.norm(d))})
        if n > 1:
            links.append(u.link(f"leg{n}_tip"))
            joints.append(u.joint(f"leg{n}_tip_fixed", "fixed", f"leg{n}_rod", f"leg{n}_tip"))
            closures.append({"name": f"leg{n}", "frames": [f"leg{n}_tip", f"platform_b{n}"], "type": "point"})
    R1 = pin.rpy.rpyToMatrix(_z_to(p + b[0] - a[0]))
    links += [u.link("ball1"), u.link("ball2")]
    joints += [
        u.joint("ball_x", "revolute", "leg1_rod", "ball1", axis=(1, 0, 0)),
        u.joint("ball_y", "revolute", "ball1", "ball2", axis=(0, 1, 0)),
    ]
    inertia = (0.02, 0.03, 0.04) if platform_mass else None
    links.append(u.link("platform", platform_mass, inertia, com=tuple(-b[0])))
    joints.append(u.joint("ball_z", "revolute", "ball2", "platform", rpy=tuple(pin.rpy.matrixToRpy(R1.T))))
    reference.update({"ball_x": 0.0, "ball_y": 0.0, "ball_z": 0.0})
    _platform_frames(links, joints, b)
    sidecar = parse_sidecar(
        {
            "format": "plm-pin/1",
            "gravity": [0.0, 0.0, -9.81],
            "closures": closures,
            "actuation": [{"joint": f"leg{n}_slide"} for n in range(1, 7)],
            "end_effector": {"frame": "platform_center", "task": ["x", "y", "z", "rx", "ry", "rz"]},
            "reference": reference,
        }
    )
    write_description(yourdfpy.Robot(name="sg", links=links, joints=joints), sidecar, tmp_path, "sg")
    return plm_pin.load(tmp_path / "sg.urdf")


def cantilever(
    tmp_path: Path, length: float, tip_mass: float = 0.0, compliance: dict | None = None
) -> Mechanism:
    """A link on a driven (rigid) hinge about z, along x, with a tip frame (and a point mass there)."""
    links = [
        u.link("base"),
        u.link("beam", 0.0),
        u.link("beam_tip", tip_mass, (1e-9, 1e-9, 1e-9) if tip_mass else None),
    ]
    joints = [
        u.joint("hinge", "revolute", "base", "beam", xyz=(0.0, 0.0, 0.3)),
        u.joint("tip_fixed", "fixed", "beam", "beam_tip", xyz=(length, 0.0, 0.0)),
    ]
    data: dict[str, Any] = {
        "format": "plm-pin/1",
        "gravity": [0.0, 0.0, 0.0],
        "actuation": [{"joint": "hinge"}],
        "end_effector": {"frame": "beam_tip", "task": ["x", "y", "z", "rx", "ry", "rz"]},
    }
    if compliance is not None:
        data["compliance"] = compliance
    write_description(
        yourdfpy.Robot(name="cantilever", links=links, joints=joints),
        parse_sidecar(data),
        tmp_path,
        "cantilever",
    )
    return plm_pin.load(tmp_path / "cantilever.urdf")


def pendulum(
    tmp_path: Path, mass: float, length: float, inertia: float, k: float, g: float, flap: bool = False
) -> Mechanism:
    """A bar on a driven hinge about z with a torsional drive spring k, hanging along -y under gravity g.

    With ``flap``, a second bar of the same mass hangs on a passive hinge (no spring) at its end.
    """
    links = [u.link("base"), u.link("bar", mass, (inertia, inertia, inertia), com=(0.0, -length, 0.0))]
    joints = [u.joint("hinge", "revolute", "base", "bar")]
    if flap:
        links.append(u.link("flap", mass, (inertia, inertia, inertia), com=(0.0, -length, 0.0)))
        joints.append(u.joint("flap_hinge", "revolute", "bar", "flap", xyz=(0.0, -2.0 * length, 0.0)))
    data = {
        "format": "plm-pin/1",
        "gravity": [0.0, -g, 0.0],
        "actuation": [{"joint": "hinge"}],
        "end_effector": {"frame": "bar", "task": ["rz"]},
        "compliance": {"actuators": {"hinge": k}},
    }
    write_description(
        yourdfpy.Robot(name="pendulum", links=links, joints=joints), parse_sidecar(data), tmp_path, "pendulum"
    )
    return plm_pin.load(tmp_path / "pendulum.urdf")


RPR_ROD = 0.3
"""Length of each leg's rod, the flexible part beyond the slider [m]."""


def rpr_points() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Base pivots a_i, platform anchors b_i (platform frame), platform centre (world) of the 3-RPR."""
    ta = np.deg2rad([90.0, 210.0, 330.0])
    tb = np.deg2rad([60.0, 200.0, 310.0])
    a = np.column_stack([0.8 * np.cos(ta), 0.8 * np.sin(ta), np.zeros(3)])
    b = np.column_stack([0.15 * np.cos(tb), 0.15 * np.sin(tb), np.zeros(3)])
    return a, b, np.array([0.05, -0.03, 0.0])


def rpr(tmp_path: Path, compliance: dict) -> Mechanism:
    """A planar 3-RPR: base revolute, driven slider, rod to the platform revolute (leg 1) or point closure."""
    a, b, p = rpr_points()
    links = [u.link("base")]
    joints = []
    reference: dict[str, Any] = {}
    closures = []
    yaw1 = 0.0
    for i in range(3):
        n = i + 1
        d = p + b[i] - a[i]
        yaw = float(np.arctan2(d[1], d[0]))
        yaw1 = yaw if n == 1 else yaw1
        links += [u.link(f"leg{n}_cyl"), u.link(f"leg{n}_rod"), u.link(f"leg{n}_tip")]
        joints += [
            u.joint(f"leg{n}_pivot", "revolute", "base", f"leg{n}_cyl", xyz=tuple(a[i]), rpy=(0.0, 0.0, yaw)),
            u.joint(
                f"leg{n}_slide", "prismatic", f"leg{n}_cyl", f"leg{n}_rod", axis=(1, 0, 0), limits=(-1.0, 1.0)
            ),
            u.joint(f"leg{n}_tip_fixed", "fixed", f"leg{n}_rod", f"leg{n}_tip", xyz=(RPR_ROD, 0.0, 0.0)),
        ]
        reference.update({f"leg{n}_pivot": 0.0, f"leg{n}_slide": float(np.linalg.norm(d)) - RPR_ROD})
        if n > 1:
            closures.append({"name": f"leg{n}", "frames": [f"leg{n}_tip", f"platform_b{n}"], "type": "point"})
    links.append(u.link("platform"))
    joints.append(
        u.joint(
            "platform_pivot",
            "revolute",
            "leg1_rod",
            "platform",
            xyz=(RPR_ROD, 0.0, 0.0),
            rpy=(0.0, 0.0, -yaw1),
        )
    )
    reference["platform_pivot"] = 0.0
    _platform_frames(links, joints, b)
    sidecar = parse_sidecar(
        {
            "format": "plm-pin/1",
            "gravity": [0.0, 0.0, 0.0],
            "closures": closures,
            "actuation": [{"joint": f"leg{n}_slide"} for n in (1, 2, 3)],
            "end_effector": {"frame": "platform_center", "task": ["x", "y", "rz"]},
            "reference": reference,
            "compliance": compliance,
        }
    )
    write_description(yourdfpy.Robot(name="rpr", links=links, joints=joints), sidecar, tmp_path, "rpr")
    return plm_pin.load(tmp_path / "rpr.urdf")
