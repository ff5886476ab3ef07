"""Harada 2011 closed forms written from the paper, independent of plm_pin: eqs. (1)-(4), (9), (11)."""

from __future__ import annotations

import math

import numpy as np

A = np.array([1.0, 0.0])  # stator direction a, eq. (1)
R_THETA = np.array([[0.0, -1.0], [1.0, 0.0]])  # eq. (4)
PAPER_SIGNS = {1: -1, 2: 1, 3: -1, 4: 1}  # sign of the square root of eq. (2) in the code (M.5)


def rotation(theta: float) -> np.ndarray:
    """R of eq. (1)."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def pair_offset(leg: int, rt: float) -> np.ndarray:
    """s_i of eq. (1): legs 1, 2 on the left pair, 3, 4 on the right."""
    return np.array([-rt, 0.0]) if leg in (1, 2) else np.array([rt, 0.0])


def pair_position(pose, leg: int, rt: float) -> np.ndarray:
    """L_i = p + R s_i, eq. (1)."""
    x, y, theta = pose
    return np.array([x, y]) + rotation(theta) @ pair_offset(leg, rt)


def slider_positions(pose, l: float, rt: float, legs, signs=PAPER_SIGNS) -> np.ndarray:
    """c_i of eq. (2) as coded in (M.5): L.a + sign sqrt((L.a)^2 - L.L + l^2)."""
    out = []
    for i in legs:
        L = pair_position(pose, i, rt)
        La = L @ A
        out.append(La + signs[i] * math.sqrt(La * La - L @ L + l * l))
    return np.array(out)


def J_ce(pose, c, l: float, rt: float, legs) -> np.ndarray:
    """J_c^{-1} J_e of eqs. (4), (12): rows z_i^T, z_i^T R_theta R s_i over z_i^T a."""
    theta = pose[2]
    rows, diag = [], []
    for ci, i in zip(c, legs, strict=True):
        z = (pair_position(pose, i, rt) - ci * A) / l  # eq. (3)
        rows.append([z[0], z[1], z @ R_THETA @ rotation(theta) @ pair_offset(i, rt)])
        diag.append(z @ A)
    return np.linalg.solve(np.diag(diag), np.array(rows))


def reachable_sin_interval(y: float, l: float, rt: float) -> tuple[float, float]:
    """Values of sin(theta) for which both pairs are within reach, |L_y| <= l (eqs. (2), (9))."""
    lo = max((y - l) / rt, (-l - y) / rt, -1.0)
    hi = min((y + l) / rt, (l - y) / rt, 1.0)
    return lo, hi
