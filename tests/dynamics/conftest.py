"""Shared cases of the dynamics tests."""

from __future__ import annotations

import math

import numpy as np

from plm_pin.core.mechanism import Mechanism
from plm_pin.dynamics import JointTrajectory, task_trajectory
from tests.conftest import preset


def direct_crossing() -> tuple[Mechanism, np.ndarray, JointTrajectory, int]:
    """The 3D3M at x = 0, y = 0.08 m turning theta 0 -> -50 deg in 1 s (101 samples): a direct singularity.

    Returns:
        The mechanism, the times [s], the task trajectory (the task map is regular there) and
        the first sample past the singular angle of Harada 2011's eq. (11.4),
        ``cos theta = sqrt(((l + r_t)^2 - y^2) / (l + r_t)^2)`` with ``l + r_t = 0.140 + 0.05 m`` (Table 1).
    """
    mech = preset("harada2011_3d3m")
    y, rate = 0.08, -math.radians(50.0)

    def profile(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return np.array([0.0, y, rate * t]), np.array([0.0, 0.0, rate]), np.zeros(3)

    times = np.linspace(0.0, 1.0, 101)
    reach = 0.140 + 0.05
    theta_4 = -math.acos(math.sqrt((reach**2 - y**2) / reach**2))
    first_past = int(np.flatnonzero(rate * times < theta_4)[0])
    return mech, times, task_trajectory(mech, profile, times), first_past
