"""Textbook parallel robots built from scratch, with their closed-form kinematics.

Each builder writes ``<name>.urdf`` + ``<name>.plm.yaml`` into a folder and loads it; the
closed forms below are derived here from the geometry alone, never from plm_pin:

- planar 3-RRR (Gosselin): base joints A_i on a circle, proximal l1, distal l2, platform
  vertices C_i = p + R(phi) c_i; leg i closes when |A_i + l1 (cos t_i, sin t_i) - C_i| = l2,
  two elbow branches each, t_i = atan2(C_i - A_i) +- acos((l1^2 + d^2 - l2^2) / (2 l1 d)).
- Delta (Clavel): arms of length La turning about the tangent of a base circle of radius R,
  rods of length Lb to the platform point P (single rods meeting at P) or to Q_i = P + r e_i
  (parallelograms of half-width h, platform kept level); in leg i's frame the elbow is
  (R + La cos t, 0, -La sin t) and a cos t + b sin t = c, a = -2 La (x - R'),
  b = 2 La z, c = Lb^2 - La^2 - (x - R')^2 - y^2 - z^2 with R' = R - r.
- Stewart platform 6-UPS (Gough): leg lengths L_k = |p + R P_k - B_k|, velocities
  L'_k = e_k . (v + w x R P_k).
- Four-bar gripper finger (output joint as task): Freudenstein's equation, the velocity ratio
  a sin(t3 - t2) / (c sin(t3 - t4)), the transmission angle by the law of cosines.
- Planar 3-PRR (a sidecar written as a user would, reference optional): slider positions
  s_i = (C_i - A_i) . u_i +- sqrt(l^2 - ((C_i - A_i) . n_i)^2).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import yaml
import yourdfpy

import plm_pin
from plm_pin.core.mechanism import Mechanism
from plm_pin.description import urdf_parts as u
from plm_pin.description import write_description
from plm_pin.description.sidecar import parse_sidecar

# --------------------------------------------------------------------------- 3-RRR
RRR = {"Rb": 0.5, "rp": 0.12, "l1": 0.3, "l2": 0.35}
RRR_POSE = (0.02, -0.01, 0.1)


def rrr_angles() -> np.ndarray:
    """Directions of the base joints and of the platform vertices [rad], shape (3,)."""
    return np.pi / 2 + 2 * np.pi * np.arange(3) / 3


def rrr_points(pose: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Base joints A_i and platform vertices C_i at ``pose`` = (x, y, phi), shapes (3, 2)."""
    a = rrr_angles()
    A = RRR["Rb"] * np.column_stack([np.cos(a), np.sin(a)])
    x, y, phi = pose
    c = RRR["rp"] * np.column_stack([np.cos(a + phi), np.sin(a + phi)])
    return A, np.array([x, y]) + c


def rrr_ik(pose: tuple[float, float, float], signs: tuple[int, ...]) -> np.ndarray:
    """Closed-form motor angles of the 3-RRR in elbow branches ``signs`` [rad], shape (3,)."""
    A, C = rrr_points(pose)
    l1, l2 = RRR["l1"], RRR["l2"]
    out = []
    for i, s in enumerate(signs):
        d = C[i] - A[i]
        r = float(np.hypot(*d))
        out.append(math.atan2(d[1], d[0]) + s * math.acos((l1 * l1 + r * r - l2 * l2) / (2 * l1 * r)))
    return np.array(out)


def rrr_jce(pose: tuple[float, float, float], theta: np.ndarray) -> np.ndarray:
    """Closed-form actuator Jacobian dtheta/d(x, y, phi) of the 3-RRR, shape (3, 3).

    Differentiating |C_i - B_i|^2 = l2^2 with B_i = A_i + l1 a_i gives
    e_i . v + phi' (R c_i x e_i) = theta_i' (l1 a_i x e_i), e_i = C_i - B_i.
    """
    A, C = rrr_points(pose)
    x, y, _ = pose
    rows = []
    for i in range(3):
        a = RRR["l1"] * np.array([math.cos(theta[i]), math.sin(theta[i])])
        e = C[i] - A[i] - a
        rc = C[i] - np.array([x, y])
        cross = lambda p, q: p[0] * q[1] - p[1] * q[0]  # noqa: E731
        rows.append(np.array([e[0], e[1], cross(rc, e)]) / cross(a, e))
    return np.array(rows)


def rrr_elbows(pose: tuple[float, float, float], theta: np.ndarray) -> np.ndarray:
    """Closed-form elbow joint angles (distal direction minus motor angle) [rad], shape (3,)."""
    A, C = rrr_points(pose)
    out = []
    for i in range(3):
        B = A[i] + RRR["l1"] * np.array([math.cos(theta[i]), math.sin(theta[i])])
        out.append(math.atan2(C[i][1] - B[1], C[i][0] - B[0]) - theta[i])
    return np.array(out)


def three_rrr(
    folder: Path,
    task: tuple[str, ...] = ("x", "y", "rz"),
    name: str = "rrr3",
    elbow_limits: tuple[float, float] = (-7.0, 7.0),
    elbow_spheres: float = 0.0,
) -> Mechanism:
    """A symmetric planar 3-RRR; the platform hangs on leg 0, legs 1 and 2 close on it (point closures).

    ``elbow_limits`` are the position limits of leg 1's elbow ``e1`` [rad]; with
    ``elbow_spheres`` > 0, each proximal link carries a sphere of that radius [m] at its elbow
    (its only visual), so that two legs collide when their elbows come closer than twice it.
    """
    l1, l2 = RRR["l1"], RRR["l2"]
    a = rrr_angles()
    A, C = rrr_points(RRR_POSE)
    theta = rrr_ik(RRR_POSE, (1, 1, 1))
    links = [u.link("base")]
    joints = []
    reference: dict[str, float] = {}
    phi = RRR_POSE[2]
    for i in range(3):
        spheres = [u.sphere_visual(elbow_spheres, "joint", xyz=(l1, 0, 0))] if elbow_spheres > 0 else []
        links += [u.link(f"prox{i}", 0.5, (1e-4, 4e-3, 4e-3), com=(l1 / 2, 0, 0), visuals=spheres)]
        links += [u.link(f"dist{i}", 0.4, (1e-4, 4e-3, 4e-3), com=(l2 / 2, 0, 0)), u.link(f"tip{i}")]
        joints += [
            u.joint(f"m{i}", "revolute", "base", f"prox{i}", xyz=(*A[i], 0.0), limits=(-7.0, 7.0)),
            u.joint(
                f"e{i}",
                "revolute",
                f"prox{i}",
                f"dist{i}",
                xyz=(l1, 0, 0),
                limits=elbow_limits if i == 1 else (-7.0, 7.0),
            ),
            u.joint(f"tip{i}_fixed", "fixed", f"dist{i}", f"tip{i}", xyz=(l2, 0, 0)),
        ]
        B = A[i] + l1 * np.array([math.cos(theta[i]), math.sin(theta[i])])
        delta = math.atan2(*(C[i] - B)[::-1])
        reference[f"m{i}"] = float(theta[i])
        reference[f"e{i}"] = float(delta - theta[i])
        if i == 0:
            reference["p0"] = float(phi - delta)
    # the platform frame sits at vertex 0, turned by phi; its vertices are c_i - c_0 there
    c = RRR["rp"] * np.column_stack([np.cos(a), np.sin(a)])
    links += [u.link("platform", 1.0, (1e-3, 1e-3, 2e-3), com=(*(-c[0]), 0.0)), u.link("centre")]
    joints += [
        u.joint("p0", "revolute", "dist0", "platform", xyz=(l2, 0, 0), limits=(-7.0, 7.0)),
        u.joint("centre_fixed", "fixed", "platform", "centre", xyz=(*(-c[0]), 0.0)),
    ]
    for i in (1, 2):
        links.append(u.link(f"vertex{i}"))
        joints.append(
            u.joint(f"vertex{i}_fixed", "fixed", "platform", f"vertex{i}", xyz=(*(c[i] - c[0]), 0.0))
        )
    sidecar = parse_sidecar(
        {
            "format": "plm-pin/1",
            "closures": [
                {"name": f"leg{i}", "frames": [f"vertex{i}", f"tip{i}"], "type": "point"} for i in (1, 2)
            ],
            "actuation": [{"joint": f"m{i}"} for i in range(3)],
            "end_effector": {"frame": "centre", "task": list(task)},
            "reference": reference,
        }
    )
    write_description(yourdfpy.Robot(name=name, links=links, joints=joints), sidecar, folder, name)
    return plm_pin.load(folder / f"{name}.urdf")


# --------------------------------------------------------------------------- Delta
DELTA = {"R": 0.2, "La": 0.3, "Lb": 0.6, "r": 0.05, "h": 0.04}
DELTA_POINT = (0.01, -0.02, -0.55)


def delta_ik(point: tuple[float, float, float], signs: tuple[int, ...], r: float) -> np.ndarray:
    """Closed-form motor angles of a Delta with platform radius ``r`` [rad], shape (3,)."""
    R, La, Lb = DELTA["R"] - r, DELTA["La"], DELTA["Lb"]
    out = []
    for i, s in enumerate(signs):
        ph = 2 * np.pi * i / 3
        x = math.cos(ph) * point[0] + math.sin(ph) * point[1]
        y = -math.sin(ph) * point[0] + math.cos(ph) * point[1]
        z = point[2]
        a, b = -2 * La * (x - R), 2 * La * z
        c = Lb * Lb - La * La - (x - R) ** 2 - y * y - z * z
        out.append(math.atan2(b, a) + s * math.acos(c / math.hypot(a, b)))
    return np.array(out)


def _rot_z(ph: float) -> np.ndarray:
    return np.array([[math.cos(ph), -math.sin(ph), 0], [math.sin(ph), math.cos(ph), 0], [0, 0, 1]])


def _rot_y(t: float) -> np.ndarray:
    return np.array([[math.cos(t), 0, math.sin(t)], [0, 1, 0], [-math.sin(t), 0, math.cos(t)]])


def _universal_angles(d: np.ndarray) -> tuple[float, float]:
    """Angles (alpha about z, beta about y) with Rz(alpha) Ry(beta) x along ``d``."""
    return math.atan2(d[1], d[0]), math.atan2(-d[2], math.hypot(d[0], d[1]))


def delta(folder: Path, parallelogram: bool, floating: bool = True, name: str = "delta") -> Mechanism:
    """A Delta robot: single rods meeting at the task point, or parallelograms on a level platform.

    With ``parallelogram``, each leg carries two rods 2 h apart on universal joints, closed on
    the platform by point closures; the platform floats (``floating``) or hangs on leg 0's
    first rod by a ball joint (three revolutes). Single rods all end at one point: rod 0's tip
    carries the task, rods 1 and 2 close on it.
    """
    R, La, Lb = DELTA["R"], DELTA["La"], DELTA["Lb"]
    r, h = (DELTA["r"], DELTA["h"]) if parallelogram else (0.0, 0.0)
    P = np.array(DELTA_POINT)
    theta = delta_ik(DELTA_POINT, (1, 1, 1), r)
    links = [u.link("base")]
    joints = []
    reference: dict[str, object] = {}
    closures = []
    rods = ("p", "m") if parallelogram else ("",)
    for i in range(3):
        ph = 2 * np.pi * i / 3
        links.append(u.link(f"arm{i}", 0.3, (1e-4, 2e-3, 2e-3), com=(La / 2, 0, 0)))
        joints.append(
            u.joint(
                f"m{i}",
                "revolute",
                "base",
                f"arm{i}",
                xyz=(R * math.cos(ph), R * math.sin(ph), 0),
                rpy=(0, 0, ph),
                axis=(0, 1, 0),
                limits=(-7.0, 7.0),
            )
        )
        reference[f"m{i}"] = float(theta[i])
        R_arm = _rot_z(ph) @ _rot_y(theta[i])
        elbow = np.array([R * math.cos(ph), R * math.sin(ph), 0]) + R_arm @ np.array([La, 0, 0])
        alpha, beta = _universal_angles(R_arm.T @ (P + r * np.array([math.cos(ph), math.sin(ph), 0]) - elbow))
        for side, sign in zip(rods, (1, -1), strict=False):
            rod = f"rod{i}{side}"
            links += [
                u.link(f"cross{i}{side}", 1e-3, (1e-7, 1e-7, 1e-7)),
                u.link(rod, 0.1, (1e-5, 3e-3, 3e-3), com=(Lb / 2, 0, 0)),
                u.link(f"{rod}_tip"),
            ]
            joints += [
                u.joint(
                    f"u{i}{side}a",
                    "revolute",
                    f"arm{i}",
                    f"cross{i}{side}",
                    xyz=(La, sign * h, 0),
                    limits=(-7.0, 7.0),
                ),
                u.joint(
                    f"u{i}{side}b", "revolute", f"cross{i}{side}", rod, axis=(0, 1, 0), limits=(-7.0, 7.0)
                ),
                u.joint(f"{rod}_tip_fixed", "fixed", rod, f"{rod}_tip", xyz=(Lb, 0, 0)),
            ]
            reference[f"u{i}{side}a"] = alpha
            reference[f"u{i}{side}b"] = beta
    if parallelogram:
        links.append(u.link("platform", 0.2, (1e-4, 1e-4, 2e-4)))
        if floating:
            joints.append(u.joint("platform_free", "floating", "base", "platform"))
            reference["platform_free"] = [*P, 0.0, 0.0, 0.0, 1.0]
        else:  # ball joint at rod 0p's tip, platform frame at P: offset r e_0 + h y_0 from the tip
            links += [u.link("ball0", 1e-3, (1e-7, 1e-7, 1e-7)), u.link("ball1", 1e-3, (1e-7, 1e-7, 1e-7))]
            joints += [
                u.joint("s0", "revolute", "rod0p_tip", "ball0", axis=(1, 0, 0), limits=(-7.0, 7.0)),
                u.joint("s1", "revolute", "ball0", "ball1", axis=(0, 1, 0), limits=(-7.0, 7.0)),
            ]
            R_rod = _rot_y(theta[0]) @ _rot_z(float(reference["u0pa"])) @ _rot_y(float(reference["u0pb"]))  # type: ignore[arg-type]
            rpy = pin.rpy.matrixToRpy(R_rod.T)  # platform level: its rotation in the rod frame is R_rod^T
            reference["s0"], reference["s1"] = 0.0, 0.0
            joints.append(
                u.joint("s2", "revolute", "ball1", "platform_link", axis=(0, 0, 1), limits=(-7.0, 7.0))
            )
            links.append(u.link("platform_link", 1e-3, (1e-7, 1e-7, 1e-7)))
            reference["s2"] = 0.0
            joints.append(
                u.joint(
                    "platform_fixed",
                    "fixed",
                    "platform_link",
                    "platform",
                    xyz=tuple(R_rod.T @ np.array([-r, -h, 0.0])),
                    rpy=tuple(rpy),
                )
            )
        for i in range(3):
            ph = 2 * np.pi * i / 3
            e, t = np.array([math.cos(ph), math.sin(ph), 0]), np.array([-math.sin(ph), math.cos(ph), 0])
            for side, sign in zip(rods, (1, -1), strict=True):
                if not floating and (i, side) == (0, "p"):
                    continue
                links.append(u.link(f"pt{i}{side}"))
                joints.append(
                    u.joint(
                        f"pt{i}{side}_fixed",
                        "fixed",
                        "platform",
                        f"pt{i}{side}",
                        xyz=tuple(r * e + sign * h * t),
                    )
                )
                closures.append(
                    {
                        "name": f"rod{i}{side}",
                        "frames": [f"pt{i}{side}", f"rod{i}{side}_tip"],
                        "type": "point",
                    }
                )
        frame = "platform"
    else:
        closures = [
            {"name": f"rod{i}", "frames": ["rod0_tip", f"rod{i}_tip"], "type": "point"} for i in (1, 2)
        ]
        frame = "rod0_tip"
    sidecar = parse_sidecar(
        {
            "format": "plm-pin/1",
            "closures": closures,
            "actuation": [{"joint": f"m{i}"} for i in range(3)],
            "end_effector": {"frame": frame, "task": ["x", "y", "z"]},
            "reference": reference,
        }
    )
    write_description(yourdfpy.Robot(name=name, links=links, joints=joints), sidecar, folder, name)
    return plm_pin.load(folder / f"{name}.urdf")


# --------------------------------------------------------------------------- Stewart
STEWART = {"rb": 0.5, "rp": 0.3, "height": 0.8}
STEWART_POSE = (0.01, -0.02, 0.8, 0.03, -0.02, 0.05)


def stewart_points() -> tuple[np.ndarray, np.ndarray]:
    """Base joints B_k and platform joints P_k (platform frame) of the 6-UPS [m], shapes (6, 3)."""
    base = np.radians([-10, 10, 110, 130, 230, 250])
    plat = np.radians([-50, 50, 70, 170, 190, 290])
    B = STEWART["rb"] * np.column_stack([np.cos(base), np.sin(base), np.zeros(6)])
    P = STEWART["rp"] * np.column_stack([np.cos(plat), np.sin(plat), np.zeros(6)])
    return B, P


def stewart_legs(pose: tuple[float, ...], B: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form leg lengths L_k [m] (6,) and actuator Jacobian dL/d(v, w) (6, 6) at ``pose``.

    ``B`` replaces the base joints of :func:`stewart_points`.
    """
    B0, P = stewart_points()
    B = B0 if B is None else B
    p, R = np.array(pose[:3]), pin.rpy.rpyToMatrix(np.array(pose[3:]))
    d = p + P @ R.T - B
    L = np.linalg.norm(d, axis=1)
    e = d / L[:, None]
    return L, np.hstack([e, np.cross(P @ R.T, e)])


def stewart(folder: Path, spherical_base: bool = False, name: str = "stewart") -> Mechanism:
    """A 6-UPS Stewart platform (floating platform, point closures at the platform joints).

    With ``spherical_base`` the base universal joints become ball joints (a third revolute
    about the strut): each strut can then spin about its own axis, an idle mobility.
    """
    B, P = stewart_points()
    L, _ = stewart_legs(STEWART_POSE)
    p, R = np.array(STEWART_POSE[:3]), pin.rpy.rpyToMatrix(np.array(STEWART_POSE[3:]))
    links = [u.link("base"), u.link("platform", 2.0, (0.05, 0.05, 0.09))]
    joints = [u.joint("platform_free", "floating", "base", "platform")]
    quat = pin.Quaternion(R).coeffs()
    reference: dict[str, object] = {"platform_free": [*p, *quat]}
    closures = []
    for k in range(6):
        alpha, beta = _universal_angles(p + R @ P[k] - B[k])
        links += [
            u.link(f"cross{k}", 1e-3, (1e-7, 1e-7, 1e-7)),
            u.link(f"cyl{k}", 1.0, (1e-3, 2e-2, 2e-2), com=(0.2, 0, 0)),
            u.link(f"piston{k}", 0.5, (1e-4, 1e-2, 1e-2), com=(-0.2, 0, 0)),
            u.link(f"pj{k}"),
        ]
        child = f"cyl{k}"
        if spherical_base:
            links.append(u.link(f"cross{k}b", 1e-3, (1e-7, 1e-7, 1e-7)))
            child = f"cross{k}b"
        joints += [
            u.joint(f"u{k}a", "revolute", "base", f"cross{k}", xyz=tuple(B[k]), limits=(-7.0, 7.0)),
            u.joint(f"u{k}b", "revolute", f"cross{k}", child, axis=(0, 1, 0), limits=(-7.0, 7.0)),
            u.joint(f"leg{k}", "prismatic", f"cyl{k}", f"piston{k}", axis=(1, 0, 0), limits=(0.3, 1.6)),
            u.joint(f"pj{k}_fixed", "fixed", "platform", f"pj{k}", xyz=tuple(P[k])),
        ]
        if spherical_base:
            joints.append(
                u.joint(f"u{k}c", "revolute", f"cross{k}b", f"cyl{k}", axis=(1, 0, 0), limits=(-7.0, 7.0))
            )
            reference[f"u{k}c"] = 0.0
        reference[f"u{k}a"], reference[f"u{k}b"], reference[f"leg{k}"] = alpha, beta, float(L[k])
        closures.append({"name": f"leg{k}", "frames": [f"pj{k}", f"piston{k}"], "type": "point"})
    sidecar = parse_sidecar(
        {
            "format": "plm-pin/1",
            "closures": closures,
            "actuation": [{"joint": f"leg{k}"} for k in range(6)],
            "end_effector": {"frame": "platform", "task": ["x", "y", "z", "rx", "ry", "rz"]},
            "reference": reference,
        }
    )
    write_description(yourdfpy.Robot(name=name, links=links, joints=joints), sidecar, folder, name)
    return plm_pin.load(folder / f"{name}.urdf")


# --------------------------------------------------------------------------- four-bar finger
FINGER = {"a": 0.02, "b": 0.045, "c": 0.035, "d": 0.04}
"""Gripper finger four-bar [m]: crank a (input, pivot A at the origin), coupler b, finger c
(output, pivot D = (d, 0)); all joints turn about z, gravity along -y."""

FINGER_BODIES = {  # mass [kg], centre of mass in the body frame [m], izz about it [kg m^2]
    "crank": (0.010, (0.010, 0.000), 4e-7),
    "coupler": (0.015, (0.0225, 0.002), 3e-6),
    "finger": (0.030, (0.030, 0.006), 9e-6),
}


def finger_freudenstein(theta2: float, branch: int = -1) -> tuple[float, float]:
    """Output and coupler angles (theta4, theta3) [rad] of the finger at crank angle theta2.

    Freudenstein's equation K1 cos t4 - K2 cos t2 + K3 = cos(t2 - t4), K1 = d/a, K2 = d/c,
    K3 = (a^2 - b^2 + c^2 + d^2) / (2 a c), solved by the half-angle substitution
    t = tan(t4 / 2): A t^2 + B t + C = 0; ``branch`` picks the root's sign (-1: the finger
    above the palm, the reference's assembly).
    """
    a, b, c, d = (FINGER[k] for k in "abcd")
    K1, K2, K3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    A = math.cos(theta2) - K1 - K2 * math.cos(theta2) + K3
    B = -2 * math.sin(theta2)
    C = K1 - (K2 + 1) * math.cos(theta2) + K3
    t4 = 2 * math.atan((-B + branch * math.sqrt(B * B - 4 * A * C)) / (2 * A))
    Bx, By = a * math.cos(theta2), a * math.sin(theta2)
    Cx, Cy = d + c * math.cos(t4), c * math.sin(t4)
    return t4, math.atan2(Cy - By, Cx - Bx)


def finger_velocity_ratio(theta2: float, branch: int = -1) -> float:
    """D theta4 / d theta2 = a sin(t3 - t2) / (c sin(t3 - t4)) (the four-bar's angular velocity ratio)."""
    t4, t3 = finger_freudenstein(theta2, branch)
    return FINGER["a"] * math.sin(t3 - theta2) / (FINGER["c"] * math.sin(t3 - t4))


def finger_transmission_angle(theta2: float) -> float:
    """Transmission angle mu between coupler and finger [rad], by the law of cosines.

    cos mu = (b^2 + c^2 - BD^2) / (2 b c), BD^2 = a^2 + d^2 - 2 a d cos t2.
    """
    a, b, c, d = (FINGER[k] for k in "abcd")
    bd2 = a * a + d * d - 2 * a * d * math.cos(theta2)
    return math.acos((b * b + c * c - bd2) / (2 * b * c))


def finger_from_output(theta4: float, branch: int = -1) -> tuple[float, float]:
    """Crank and coupler angles (theta2, theta3) [rad] at output angle theta4 (circle intersection).

    B is where the circle of radius a about A meets the circle of radius b about C; ``branch``
    picks the side of the line A C (-1: B to its left, the reference's assembly).
    """
    a, b, c, d = (FINGER[k] for k in "abcd")
    C = np.array([d + c * math.cos(theta4), c * math.sin(theta4)])
    L = float(np.linalg.norm(C))
    along = (a * a - b * b + L * L) / (2 * L)
    h = math.sqrt(a * a - along * along)
    e = C / L
    n = np.array([e[1], -e[0]])  # e turned by -90 degrees
    B = along * e + branch * h * n
    return math.atan2(B[1], B[0]), math.atan2(C[1] - B[1], C[0] - B[0])


def finger_points(theta4: float, branch: int = -1) -> dict[str, tuple[np.ndarray, float]]:
    """Each body's centre of mass [m] and angle [rad] at output angle ``theta4`` (closed form)."""
    a, d = FINGER["a"], FINGER["d"]
    t2, t3 = finger_from_output(theta4, branch)
    origins = {
        "crank": (np.zeros(2), t2),
        "coupler": (a * np.array([math.cos(t2), math.sin(t2)]), t3),
        "finger": (np.array([d, 0.0]), theta4),
    }
    out = {}
    for name, (o, ang) in origins.items():
        com = np.array(FINGER_BODIES[name][1])
        R = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]])
        out[name] = (o + R @ com, ang)
    return out


FINGER_URDF = """<?xml version="1.0"?>
<robot name="{name}">
  <link name="palm"/>
  <link name="crank">
    <inertial><origin xyz="{crank_com}"/><mass value="{crank_m}"/>
      <inertia ixx="{crank_i}" iyy="{crank_i}" izz="{crank_i}" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="coupler">
    <inertial><origin xyz="{coupler_com}"/><mass value="{coupler_m}"/>
      <inertia ixx="{coupler_i}" iyy="{coupler_i}" izz="{coupler_i}" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="coupler_tip"/>
  <link name="finger">
    <inertial><origin xyz="{finger_com}"/><mass value="{finger_m}"/>
      <inertia ixx="{finger_i}" iyy="{finger_i}" izz="{finger_i}" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="finger_knuckle"/>
  <joint name="drive" type="revolute">
    <parent link="palm"/><child link="crank"/><axis xyz="0 0 1"/>
    <limit lower="-7" upper="7" effort="10" velocity="10"/>
  </joint>
  <joint name="coupler_pivot" type="revolute">
    <parent link="crank"/><child link="coupler"/><origin xyz="{a} 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-7" upper="7" effort="10" velocity="10"/>
  </joint>
  <joint name="coupler_tip_fixed" type="fixed">
    <parent link="coupler"/><child link="coupler_tip"/><origin xyz="{b} 0 0"/>
  </joint>
  <joint name="finger_pivot" type="revolute">
    <parent link="palm"/><child link="finger"/><origin xyz="{d} 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-7" upper="7" effort="10" velocity="10"/>
  </joint>
  <joint name="finger_knuckle_fixed" type="fixed">
    <parent link="finger"/><child link="finger_knuckle"/><origin xyz="{c} 0 0"/>
  </joint>
</robot>
"""

FINGER_SIDECAR = """format: plm-pin/1
name: {name}
gravity: [0.0, -9.81, 0.0]
closures:
  - name: knuckle
    frames: [coupler_tip, finger_knuckle]
    type: point
actuation:
  - joint: drive
    limits: [-2.0, 2.0]
end_effector:
  joints: [finger_pivot]
reference: {{drive: {t2}, coupler_pivot: {t32}, finger_pivot: {t4}}}
"""

FINGER_THETA2 = 1.2
"""Crank angle of the finger's reference [rad]."""


def finger(folder: Path, name: str = "finger") -> Mechanism:
    """Write the four-bar gripper finger (URDF + sidecar, output joint as the task) and load it."""
    t4, t3 = finger_freudenstein(FINGER_THETA2)
    fields: dict[str, object] = {k: v for k, v in FINGER.items()}
    for body, (m, com, izz) in FINGER_BODIES.items():
        fields[f"{body}_m"], fields[f"{body}_com"], fields[f"{body}_i"] = m, f"{com[0]} {com[1]} 0", izz
    (folder / f"{name}.urdf").write_text(FINGER_URDF.format(name=name, **fields))
    (folder / f"{name}.plm.yaml").write_text(
        FINGER_SIDECAR.format(name=name, t2=FINGER_THETA2, t32=t3 - FINGER_THETA2, t4=t4)
    )
    return plm_pin.load(folder / f"{name}.urdf")


# --------------------------------------------------------------------------- 3-PRR
PRR = {"Rb": 0.25, "rp": 0.1, "l": 0.3}
"""Planar 3-PRR [m]: slider i runs through A_i = Rb (cos a_i, sin a_i) along the tangent
u_i = (-sin a_i, cos a_i), a_i = 90 deg + 120 deg i; a rod of length l joins the slider's pivot
B_i = A_i + s_i u_i to the platform vertex C_i = p + R(phi) rp (cos a_i, sin a_i)."""


def prr_ik(pose: tuple[float, float, float], signs: tuple[int, ...], l: float | None = None) -> np.ndarray:
    """Closed-form slider positions s_i [m] in branches ``signs``: |C_i - A_i - s_i u_i| = l.

    s_i = (C_i - A_i) . u_i + sign_i sqrt(l^2 - ((C_i - A_i) . n_i)^2), n_i = (cos a_i, sin a_i).
    """
    rod = PRR["l"] if l is None else l
    a = rrr_angles()
    x, y, phi = pose
    out = []
    for i, s in enumerate(signs):
        A = PRR["Rb"] * np.array([math.cos(a[i]), math.sin(a[i])])
        C = np.array([x, y]) + PRR["rp"] * np.array([math.cos(a[i] + phi), math.sin(a[i] + phi)])
        u = np.array([-math.sin(a[i]), math.cos(a[i])])
        n = np.array([math.cos(a[i]), math.sin(a[i])])
        d = C - A
        out.append(float(d @ u + s * math.sqrt(rod * rod - float(d @ n) ** 2)))
    return np.array(out)


def prr_inverse_margins(pose: tuple[float, float, float], l: float | None = None) -> np.ndarray:
    """|cos| of each rod's angle to the normal of its slider: 0 at leg i's inverse (type 1) singularity."""
    rod = PRR["l"] if l is None else l
    a = rrr_angles()
    x, y, phi = pose
    out = []
    for i in range(3):
        A = PRR["Rb"] * np.array([math.cos(a[i]), math.sin(a[i])])
        C = np.array([x, y]) + PRR["rp"] * np.array([math.cos(a[i] + phi), math.sin(a[i] + phi)])
        n = np.array([math.cos(a[i]), math.sin(a[i])])
        out.append(math.sqrt(max(0.0, 1.0 - (float((C - A) @ n) / rod) ** 2)))
    return np.array(out)


def three_prr(
    folder: Path, name: str = "prr3", rod: float | None = None, reference: dict | None = None
) -> Mechanism:
    """Write a planar 3-PRR as a user would from the docs (no ``reference`` unless given) and load it.

    ``rod`` overrides the length of rod 2 only (a typo in one rod); the platform hangs on
    leg 0, legs 1 and 2 close on its vertices with point closures.
    """
    a = rrr_angles()
    rp = PRR["rp"]
    c = rp * np.column_stack([np.cos(a), np.sin(a)])
    links = [u.link("base")]
    joints = []
    for i in range(3):
        A = PRR["Rb"] * np.array([math.cos(a[i]), math.sin(a[i])])
        length = rod if (rod is not None and i == 2) else PRR["l"]
        links += [
            u.link(f"carriage{i}", 0.3, (1e-4, 1e-4, 1e-4)),
            u.link(f"rod{i}", 0.2, (1e-5, 1.5e-3, 1.5e-3), com=(length / 2, 0, 0)),
            u.link(f"tip{i}"),
        ]
        joints += [
            u.joint(
                f"slider{i}",
                "prismatic",
                "base",
                f"carriage{i}",
                xyz=(*A, 0.0),
                rpy=(0.0, 0.0, float(a[i] + math.pi / 2)),
                axis=(1, 0, 0),
                limits=(-1.0, 1.0),
            ),
            u.joint(f"pivot{i}", "revolute", f"carriage{i}", f"rod{i}", limits=(-7.0, 7.0)),
            u.joint(f"tip{i}_fixed", "fixed", f"rod{i}", f"tip{i}", xyz=(length, 0, 0)),
        ]
    links += [u.link("platform", 1.0, (1e-3, 1e-3, 2e-3), com=(*(-c[0]), 0.0)), u.link("centre")]
    joints += [
        u.joint("p0", "revolute", "rod0", "platform", xyz=(PRR["l"], 0, 0), limits=(-7.0, 7.0)),
        u.joint("centre_fixed", "fixed", "platform", "centre", xyz=(*(-c[0]), 0.0)),
    ]
    for i in (1, 2):
        links.append(u.link(f"vertex{i}"))
        joints.append(
            u.joint(f"vertex{i}_fixed", "fixed", "platform", f"vertex{i}", xyz=(*(c[i] - c[0]), 0.0))
        )
    data = {
        "format": "plm-pin/1",
        "closures": [
            {"name": f"leg{i}", "frames": [f"vertex{i}", f"tip{i}"], "type": "point"} for i in (1, 2)
        ],
        "actuation": [{"joint": f"slider{i}"} for i in range(3)],
        "end_effector": {"frame": "centre", "task": ["x", "y", "rz"]},
    }
    if reference is not None:
        data["reference"] = reference
    write_description(
        yourdfpy.Robot(name=name, links=links, joints=joints), parse_sidecar(data), folder, name
    )
    return plm_pin.load(folder / f"{name}.urdf")


PRR_POSE = (0.01, -0.02, 0.1)
"""A pose well inside the 3-PRR's workspace [m, m, rad]."""


def prr_reference(pose: tuple[float, float, float]) -> dict[str, float]:
    """Joint values of the 3-PRR at ``pose`` in branches (+, +, +), from the closed-form IK."""
    s = prr_ik(pose, (1, 1, 1))
    a = rrr_angles()
    out = {}
    for i in range(3):
        A = PRR["Rb"] * np.array([math.cos(a[i]), math.sin(a[i])])
        B = A + s[i] * np.array([-math.sin(a[i]), math.cos(a[i])])
        C = np.array(pose[:2]) + PRR["rp"] * np.array([math.cos(a[i] + pose[2]), math.sin(a[i] + pose[2])])
        rod = math.atan2(C[1] - B[1], C[0] - B[0]) - (a[i] + math.pi / 2)  # in the slider's frame
        out[f"slider{i}"], out[f"pivot{i}"] = float(s[i]), float(rod)
        if i == 0:
            out["p0"] = float(pose[2] - (a[0] + math.pi / 2) - rod)
    return out


# ----------------------------------------------------------------- slider-crank
SLIDER_CRANK = {"r": 0.05, "l": 0.2}
"""Crank and rod lengths [m] of the slider-crank below (the slider moves along x through the crank pivot)."""


def slider_crank_position(t: float) -> float:
    """Slider position [m] at crank angle ``t`` [rad]: x = r cos t + sqrt(l^2 - r^2 sin^2 t)."""
    r, length = SLIDER_CRANK["r"], SLIDER_CRANK["l"]
    return float(r * np.cos(t) + np.sqrt(length**2 - (r * np.sin(t)) ** 2))


def slider_crank_ratio(t: float) -> float:
    """dx/dt [m/rad] of :func:`slider_crank_position`: -r sin t (1 + r cos t / sqrt(l^2 - r^2 sin^2 t))."""
    r, length = SLIDER_CRANK["r"], SLIDER_CRANK["l"]
    return float(-r * np.sin(t) - r**2 * np.sin(t) * np.cos(t) / np.sqrt(length**2 - (r * np.sin(t)) ** 2))


SLIDER_CRANK_URDF = """<?xml version="1.0"?>
<robot name="slider_crank">
  <link name="base"/>
  <link name="crank"><inertial><mass value="0.1"/>
    <inertia ixx="1e-5" iyy="1e-5" izz="2e-5" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="rod"><inertial><origin xyz="0.1 0 0"/><mass value="0.2"/>
    <inertia ixx="1e-5" iyy="7e-4" izz="7e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="rod_tip"/>
  <link name="slider"><inertial><mass value="0.3"/>
    <inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="crank_joint" type="continuous"><parent link="base"/><child link="crank"/>
    <axis xyz="0 0 1"/></joint>
  <joint name="rod_joint" type="continuous"><parent link="crank"/><child link="rod"/>
    <origin xyz="0.05 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="rod_tip_fixed" type="fixed"><parent link="rod"/><child link="rod_tip"/>
    <origin xyz="0.2 0 0"/></joint>
  <joint name="slider_joint" type="prismatic"><parent link="base"/><child link="slider"/><axis xyz="1 0 0"/>
    <limit lower="0.0" upper="0.4" effort="100" velocity="1"/></joint>
</robot>
"""
SLIDER_CRANK_SIDECAR = {
    "format": "plm-pin/1",
    "closures": [{"name": "wrist_pin", "frames": ["rod_tip", "slider"], "type": "point"}],
    "actuation": [{"joint": "crank_joint", "limits": [-5.0, 5.0]}],
    "end_effector": {"joints": ["slider_joint"]},
}


def slider_crank(folder: Path) -> Path:
    """Write the slider-crank (crank input, the slider's joint as task, no reference) into ``folder``."""
    (folder / "slider_crank.urdf").write_text(SLIDER_CRANK_URDF)
    (folder / "slider_crank.plm.yaml").write_text(yaml.safe_dump(SLIDER_CRANK_SIDECAR))
    return folder / "slider_crank.urdf"
