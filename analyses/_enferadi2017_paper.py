"""Enferadi & Tavakolian 2017, section 6: the two star-centre paths the study follows.

Profiles ``t -> (pose, rate, acceleration)`` for :func:`plm_pin.dynamics.task_trajectory` on
the preset ``enferadi2017_star_triangle`` (task order ``[x, y, rz]``).
"""

from __future__ import annotations

import math

import numpy as np


def enferadi2017_line(t: float, side: float = 0.5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Section 6, first path of Enferadi 2017: the star centre on a vertical line, :math:`t \in [0, 8]` s.

    .. math::
        x = a/2, \qquad y = a/2 + (a/5) \cos(\pi t / 4), \qquad \varphi = \pi/2,

    one period: :math:`y` from :math:`0.7 a` down to :math:`0.3 a` at :math:`t = 4` s and back.

    Args:
        t: time [s].
        side: side length :math:`a` of the base [m] (0.5 in the paper).

    Returns:
        Pose ``(x, y, phi)`` [m, m, rad], its rate and its acceleration, each shape (3,), in
        the task order ``[x, y, rz]``.
    """
    w = math.pi / 4.0
    c, s = math.cos(w * t), math.sin(w * t)
    r = side / 5.0
    return (
        np.array([side / 2.0, side / 2.0 + r * c, math.pi / 2.0]),
        np.array([0.0, -r * w * s, 0.0]),
        np.array([0.0, -r * w * w * c, 0.0]),
    )


def enferadi2017_circle(t: float, side: float = 0.5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Section 6, second path of Enferadi 2017: the star centre on a circle, :math:`t \in [0, 2]` s.

    .. math::
        x = a/2 + (a/8) \cos \pi t, \qquad y = a/2 + (a/8) \sin \pi t, \qquad \varphi = \pi/2,

    one counter-clockwise turn from :math:`(5a/8, a/2)`.

    Args:
        t: time [s].
        side: side length :math:`a` of the base [m] (0.5 in the paper).

    Returns:
        Pose ``(x, y, phi)`` [m, m, rad], its rate and its acceleration, each shape (3,), in
        the task order ``[x, y, rz]``.
    """
    w = math.pi
    c, s = math.cos(w * t), math.sin(w * t)
    r = side / 8.0
    return (
        np.array([side / 2.0 + r * c, side / 2.0 + r * s, math.pi / 2.0]),
        np.array([-r * w * s, r * w * c, 0.0]),
        np.array([-r * w * w * c, -r * w * w * s, 0.0]),
    )
