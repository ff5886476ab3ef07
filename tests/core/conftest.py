"""Shared helpers of the tests of plm_pin.core."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from plm_pin.core.mechanism import Mechanism


def random_q(mech: Mechanism, rng: np.random.Generator, scale: float = 0.3) -> np.ndarray:
    """A configuration near the reference, off the closure manifold: ``q_ref`` moved by normal velocities."""
    return pin.integrate(mech.model, mech.q_ref, rng.normal(scale=scale, size=mech.nv))
