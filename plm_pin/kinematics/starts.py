"""Random starting configurations for multi-start solvers (forward and inverse kinematics)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pinocchio as pin

from ..core.mechanism import Mechanism


def random_starts(
    mech: Mechanism, rng: np.random.Generator, q: np.ndarray, columns: Iterable[int], n: int
) -> list[np.ndarray]:
    """``n`` configurations that redraw the one-DOF joints of ``columns`` within their limits.

    Revolute joints without limits (continuous, or read without ``lower``/``upper``: see
    :mod:`plm_pin.kinematics.limits`) draw an angle in [-pi, pi); prismatic joints with
    infinite or huge limits, and multi-DOF joints, get a unit normal step instead.
    """
    model = mech.model
    cols = set(int(c) for c in columns)
    out = []
    for _ in range(n):
        qs = q.copy()
        step = np.zeros(mech.nv)
        for jid in range(1, model.njoints):
            j = model.joints[jid]
            if j.idx_v not in cols:
                continue
            lo, hi = model.lowerPositionLimit[j.idx_q], model.upperPositionLimit[j.idx_q]
            if j.nq == 1 and j.nv == 1 and np.isfinite(lo) and np.isfinite(hi) and hi - lo < 1e3:
                qs[j.idx_q] = rng.uniform(lo, hi)
            elif j.nq == 1 and j.nv == 1 and not j.shortname().startswith("JointModelP"):
                qs[j.idx_q] = rng.uniform(-np.pi, np.pi)
            else:
                step[j.idx_v : j.idx_v + j.nv] = rng.normal(size=j.nv)
        out.append(pin.integrate(model, qs, step))
    return out
