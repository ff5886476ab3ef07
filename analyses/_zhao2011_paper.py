"""Zhao 2011's numbers that only the study reads: the eq. (35) trajectory and Table 5.

The 8-PSS geometry, masses and drive (Tables 1-4, section "Simulation", eq. (19)) are the
parameters of the presets ``zhao2011_8pss`` and ``zhao2011_6pss`` (``plm_pin.models.PRESETS``).
"""

from __future__ import annotations

import math

import numpy as np

ZHAO2011_TRAJECTORY_START: tuple[float, ...] = (-0.1, -0.1, 1.644, -0.1, -0.1, -0.1)
"""Eq. (35): pose at t = 0, :math:`[x, y, z]` [m] and :math:`[\\phi_x, \\phi_y, \\phi_z]` [rad]."""


ZHAO2011_TRAJECTORY_STROKE = 0.2
"""Eq. (35): travel S of every pose coordinate [m] or [rad]."""


ZHAO2011_TRAJECTORY_A_MAX = 9.8
"""Eq. (35): peak acceleration :math:`a_{max}` [m/s^2] or [rad/s^2]."""


ZHAO2011_TRAJECTORY_DURATION = math.sqrt(
    2.0 * math.pi * ZHAO2011_TRAJECTORY_STROKE / ZHAO2011_TRAJECTORY_A_MAX
)
"""Eq. (35): duration :math:`T = \\sqrt{2 \\pi S / a_{max}}` [s] (0.358090 s)."""


ZHAO2011_TABLE5_WORK: tuple[float, ...] = (
    99.697,
    1544.119,
    2819.088,
    401.408,
    166.805,
    753.256,
    6495.371,
    2962.475,
)
"""Table 5: output work of motors 1-8 on the eq. (35) trajectory [J] (sum 15242.219 J).
Quoted only: the paper's printed model does not reproduce it (see the docstring of
plm_pin.families.pss.builder)."""


def zhao2011_trajectory(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Pose, pose rate and pose acceleration of Zhao 2011, eq. (35), at time ``t`` [s].

    Every coordinate :math:`c` of :math:`X = [x, y, z, \phi_x, \phi_y, \phi_z]` follows
    :math:`c(t) = c_0 + S (u - \sin(2 \pi u) / 2 \pi)`, :math:`u = t / T`, rest to rest.
    The rate of the angles is :math:`\dot\phi`, not the angular velocity.

    Returns:
        ``X`` [m, rad], ``dX/dt`` [m/s, rad/s], ``d2X/dt2`` [m/s^2, rad/s^2], each shape (6,).
    """
    S, T, a_max = ZHAO2011_TRAJECTORY_STROKE, ZHAO2011_TRAJECTORY_DURATION, ZHAO2011_TRAJECTORY_A_MAX
    s = t / T
    ones = np.ones(6)
    pose = np.asarray(ZHAO2011_TRAJECTORY_START, dtype=float) + S * (
        s - math.sin(2 * math.pi * s) / (2 * math.pi)
    )
    rate = (S / T) * (1.0 - math.cos(2 * math.pi * s)) * ones
    acceleration = a_max * math.sin(2 * math.pi * s) * ones
    return pose, rate, acceleration
