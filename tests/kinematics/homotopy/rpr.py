"""A planar 3-RPR as URDF + sidecar, and its forward kinematics by a univariate search (the oracle)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

LINK = (
    '<link name="{name}"><inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="1.0"/>'
    '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
)


def rpr_files(folder: Path, base: np.ndarray, plate: np.ndarray, name: str = "rpr3") -> Path:
    """Write a 3-RPR into ``folder``; returns the URDF path.

    Base pivots ``base`` (3, 2) [m], platform points ``plate`` (3, 2) [m] in the platform frame
    (origin at point 1); leg i: revolute at A_i, then a prismatic joint (actuated) along the leg.
    """
    links = ["base"] + [f"leg{i}" for i in (1, 2, 3)] + [f"rod{i}" for i in (1, 2, 3)] + ["plate"]
    joints = []
    for i in range(3):
        ax, ay = (float(v) for v in base[i])
        joints.append(
            f'<joint name="pivot{i + 1}" type="continuous"><parent link="base"/><child link="leg{i + 1}"/>'
            f'<origin xyz="{ax!r} {ay!r} 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>'
        )
        joints.append(
            f'<joint name="slider{i + 1}" type="prismatic"><parent link="leg{i + 1}"/>'
            f'<child link="rod{i + 1}"/>'
            '<origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="1 0 0"/>'
            '<limit lower="-100" upper="100" effort="100" velocity="1"/></joint>'
        )
    joints.append(
        '<joint name="plate_pivot" type="continuous"><parent link="rod1"/><child link="plate"/>'
        '<origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>'
    )
    frames = []
    for i in (2, 3):
        bx, by = (float(v) for v in plate[i - 1])
        frames.append(
            f'<joint name="plate_b{i}_fix" type="fixed"><parent link="plate"/><child link="plate_b{i}"/>'
            f'<origin xyz="{bx!r} {by!r} 0" rpy="0 0 0"/></joint><link name="plate_b{i}"/>'
        )
    urdf = (
        f'<?xml version="1.0"?><robot name="{name}">'
        + "".join(LINK.format(name=n) for n in links)
        + "".join(joints)
        + "".join(frames)
        + "</robot>"
    )
    sidecar = f"""format: plm-pin/1
name: {name}
closures:
- {{name: leg2_plate, frames: [rod2, plate_b2], type: point}}
- {{name: leg3_plate, frames: [rod3, plate_b3], type: point}}
actuation:
- {{joint: slider1}}
- {{joint: slider2}}
- {{joint: slider3}}
end_effector:
  frame: plate
  task: [x, y, rz]
"""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{name}.urdf").write_text(urdf, encoding="utf-8")
    (folder / f"{name}.plm.yaml").write_text(sidecar, encoding="utf-8")
    return folder / f"{name}.urdf"


def rpr_poses(
    base: np.ndarray, plate: np.ndarray, rho: np.ndarray, n_grid: int = 200_000
) -> list[np.ndarray]:
    """Every platform pose (x, y, phi) with |B_i - A_i| = rho_i, by a univariate search in phi.

    For each phi, point 1 lies on the circle of radius rho_1 about A_1 and, shifted by
    R(phi) b_2, on the circle of radius rho_2 about A_2: two candidates; the third leg's
    squared-length error is then a function of phi alone, whose sign changes on a fine grid
    are refined by Brent's method.
    """

    def branches(phi: float) -> list[np.ndarray | None]:
        R = np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])
        c2 = base[1] - R @ plate[1]  # B1 must be at rho_2 from c2
        d = c2 - base[0]
        dist = math.hypot(*d)
        a = (rho[0] ** 2 - rho[1] ** 2 + dist**2) / (2 * dist)
        h2 = rho[0] ** 2 - a**2
        if h2 < 0:
            return [None, None]
        mid = base[0] + a * d / dist
        n = np.array([-d[1], d[0]]) / dist
        return [mid + s * math.sqrt(h2) * n for s in (1.0, -1.0)]

    def g(phi: float, k: int) -> float:
        R = np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])
        p = branches(phi)[k]
        return np.nan if p is None else float(np.sum((p + R @ plate[2] - base[2]) ** 2) - rho[2] ** 2)

    grid = np.linspace(-math.pi, math.pi, n_grid + 1)
    out = []
    for k in (0, 1):
        vals = np.array([g(phi, k) for phi in grid])
        for i in range(n_grid):
            if np.isfinite(vals[i]) and np.isfinite(vals[i + 1]) and vals[i] * vals[i + 1] < 0:
                phi = brentq(g, grid[i], grid[i + 1], args=(k,), xtol=1e-15, rtol=1e-15)
                p = branches(phi)[k]
                out.append(np.array([p[0], p[1], phi]))
    return out


def rpr_complex_poses(base: np.ndarray, plate: np.ndarray, rho: np.ndarray) -> list[np.ndarray]:
    """Every finite complex pose (x, y, phi) with |p + R(phi) b_i - A_i| = rho_i, by elimination.

    Subtracting leg 1's equation from legs 2 and 3 leaves two equations linear in the platform
    origin p, solved by Cramer's rule, p = N / D (N, D quadratic in cos phi, sin phi); leg 1's
    equation times D^2 is then a quartic in (cos phi, sin phi), a degree-8 polynomial in
    t = tan(phi / 2) once multiplied by (1 + t^2)^4, interpolated at 9 points. Of its roots,
    t = +-i are the factor (1 + t^2) and those with D = 0 have p at infinity (the linear system
    degenerates; for similar triangles these are the two roots at infinity); the others are
    the finite poses. ``rho`` may be complex.
    """
    rho2 = np.asarray(rho, dtype=complex) ** 2

    def parts(t: complex) -> tuple[complex, complex, complex, complex]:
        c, s = (1 - t * t) / (1 + t * t), 2 * t / (1 + t * t)
        e = np.array([[c * b[0] - s * b[1], s * b[0] + c * b[1]] for b in plate]) - base
        q = (e**2).sum(axis=1) - rho2
        M, rhs = 2 * (e[1:] - e[0]), q[0] - q[1:]
        D = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
        Nx, Ny = rhs[0] * M[1, 1] - M[0, 1] * rhs[1], M[0, 0] * rhs[1] - rhs[0] * M[1, 0]
        g = (Nx * Nx + Ny * Ny + 2 * D * (Nx * e[0, 0] + Ny * e[0, 1]) + D * D * q[0]) * (1 + t * t) ** 4
        return g, Nx, Ny, D * (1 + t * t) ** 2

    nodes = 1.3 * np.exp(2j * np.pi * np.arange(9) / 9)
    coef = np.linalg.solve(np.vander(nodes, 9), [parts(t)[0] for t in nodes])
    d_size = max(abs(parts(t)[3]) for t in nodes)
    out = []
    for t in np.roots(coef):
        _, Nx, Ny, D = parts(t)
        if abs(1 + t * t) < 1e-6 or abs(D) < 1e-6 * d_size:
            continue
        out.append(np.array([Nx / D * (1 + t * t) ** 2, Ny / D * (1 + t * t) ** 2, 2 * np.arctan(t)]))
    return out
