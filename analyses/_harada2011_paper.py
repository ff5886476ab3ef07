"""Harada 2011 closed forms from the paper, independent of plm_pin: eqs. (1)-(4), (9), (11), (15)-(22).

The oracles of the tests (tests/analysis, tests/statics, tests/viz) and the "paper" column
of the Harada 2011 study's statics: plain numpy on the paper's planar vectors, nothing from
plm_pin. Conventions of section 4: ``f_e = J_ce^T f_c`` is the force the actuators exert
on the end plate (no gravity); ``f_l`` is the tensile force of a rod; ``f_n`` the
constraint force along ``n = (0, 1)`` on a slider (eq. (16): ``f_c a + f_n n + f_l z = 0``).

Eq. (22) as printed, ``J_ce43^T J_i^-1 f_i``, is a (3 x 4)(4,) product: a 3-vector where f_c
has 4 entries. With eqs. (18) and (21) the internal part is ``-J_c4 J_i^-1 f_i``: the rods'
axial forces ``f_l = J_i^-1 f_i`` that put the plate ends under ``f_i``, turned into actuator
forces by eq. (18). That corrected form is what :func:`statics` uses.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

A = np.array([1.0, 0.0])  # stator direction a, eq. (1)
N_DIR = np.array([0.0, 1.0])  # guide normal n of eq. (16)
R_THETA = np.array([[0.0, -1.0], [1.0, 0.0]])  # eq. (4)
PAPER_SIGNS = {1: -1, 2: 1, 3: -1, 4: 1}  # sign of the square root of eq. (2) in the code (M.5)

Pose = Sequence[float] | np.ndarray
"""A plate pose ``(x [m], y [m], theta [rad])``."""


def rotation(theta: float) -> np.ndarray:
    """R of eq. (1)."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def pair_offset(leg: int, rt: float) -> np.ndarray:
    """s_i of eq. (1): legs 1, 2 on the left pair, 3, 4 on the right."""
    return np.array([-rt, 0.0]) if leg in (1, 2) else np.array([rt, 0.0])


def pair_position(pose: Pose, leg: int, rt: float) -> np.ndarray:
    """L_i = p + R s_i, eq. (1)."""
    x, y, theta = pose
    return np.array([x, y]) + rotation(theta) @ pair_offset(leg, rt)


def slider_positions(
    pose: Pose, l: float, rt: float, legs: Sequence[int], signs: Mapping[int, int] = PAPER_SIGNS
) -> np.ndarray:
    """c_i of eq. (2) as coded in (M.5): L.a + sign sqrt((L.a)^2 - L.L + l^2)."""
    out = []
    for i in legs:
        L = pair_position(pose, i, rt)
        La = L @ A
        out.append(La + signs[i] * math.sqrt(La * La - L @ L + l * l))
    return np.array(out)


def J_ce(pose: Pose, c: Sequence[float] | np.ndarray, l: float, rt: float, legs: Sequence[int]) -> np.ndarray:
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


def leg_matrices(
    pose: Pose, l: float, rt: float, legs: Sequence[int]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """z_i (eq. (3)), J_cm = diag(z_i^T a), J_nm = diag(z_i^T n), J_ce (eq. (12)) at ``pose``."""
    c = slider_positions(pose, l, rt, legs)
    z = np.array([(pair_position(pose, i, rt) - ci * A) / l for ci, i in zip(c, legs, strict=True)])
    return z, np.diag(z @ A), np.diag(z @ N_DIR), J_ce(pose, c, l, rt, legs)


def internal_part(pose: Pose, z: np.ndarray, J_cm: np.ndarray, f_i: float) -> np.ndarray:
    """-J_c4 J_i^-1 f_i with J_i and f_i of eq. (21): the actuator forces of a plate compression f_i [N]."""
    theta = pose[2]
    J_i = -np.block(
        [[z[0][:, None], z[1][:, None], np.zeros((2, 2))], [np.zeros((2, 2)), z[2][:, None], z[3][:, None]]]
    )
    f_vec = f_i * np.array([math.cos(theta), math.sin(theta), -math.cos(theta), -math.sin(theta)])
    return -J_cm @ np.linalg.solve(J_i, f_vec)


def statics(
    pose: Pose, f_e: ArrayLike, l: float, rt: float, legs: Sequence[int], f_i: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Actuator, rod-axial and guide-normal forces ``(f_c, f_l, f_n)`` of eqs. (15)-(22) [N].

    Three legs: f_c = J_ce^-T f_e (15). Four legs: f_c = (J_ce^T)^+ f_e - J_c4 J_i^-1 f_i
    (eqs. (20)-(22), corrected). Then eq. (19) per leg: f_l = -J_cm^-1 f_c, f_n = J_nm J_cm^-1 f_c.
    """
    z, J_cm, J_nm, jce = leg_matrices(pose, l, rt, legs)
    f_e = np.asarray(f_e, dtype=float)
    if len(legs) == 3:
        if f_i:
            raise ValueError("the 3D3M has no internal force")
        f_c = np.linalg.solve(jce.T, f_e)
    else:
        f_c = np.linalg.pinv(jce.T) @ f_e + internal_part(pose, z, J_cm, f_i)
    return f_c, -np.linalg.solve(J_cm, f_c), J_nm @ np.linalg.solve(J_cm, f_c)
