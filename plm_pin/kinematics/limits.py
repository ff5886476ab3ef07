"""Position limits of the tree joints: missing ones, and whether a configuration respects them.

URDF revolute and prismatic joints without ``lower``/``upper`` are read by Pinocchio as the
zero-width box [0, 0]; :func:`open_missing_limits` makes them unlimited (with one warning
per description), which is how solvers then sample their starting configurations.

A revolute angle respects limits ``[lo, hi]`` when some ``angle + 2 k pi`` lies in them
(the same pose of the body); :func:`wrap_into_limits` moves it there. Limits are a
reachability condition of their own: a pose where the loops close only with a joint outside
its range is reported as such (:func:`limit_violations`), apart from the poses where the
loops cannot close at all.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..warnings import MissingLimitsWarning

if TYPE_CHECKING:
    from ..mechanism import Mechanism

LIMIT_TOL = 1e-9
"""A joint within this distance of its range [m or rad] respects it."""

TWO_PI = 2.0 * np.pi


def open_missing_limits(model: pin.Model, label: str = "") -> list[str]:
    """Make every one-DOF joint with a zero-width position range unlimited, warning once.

    Args:
        model: the model, changed in place.
        label: where the joints come from (a file), to start the warning with.

    Returns:
        The names of the joints changed, in model order.
    """
    changed = []
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if joint.nq != 1:
            continue
        k = joint.idx_q
        if model.lowerPositionLimit[k] == model.upperPositionLimit[k]:
            model.lowerPositionLimit[k] = -np.inf
            model.upperPositionLimit[k] = np.inf
            changed.append(str(model.names[j]))
    if changed:
        prefix = f"{label}: " if label else ""
        warnings.warn(
            f"{prefix}{len(changed)} joint(s) have no position limits (lower = upper = 0 in the URDF) "
            f"and are treated as unlimited (continuous): {changed}",
            MissingLimitsWarning,
            stacklevel=2,
        )
    return changed


def _limited_joints(mech: Mechanism) -> list[tuple[str, int, bool, float, float]]:
    """(name, idx_q, revolute, lower, upper) of the one-DOF joints with a finite range."""
    model = mech.model
    out = []
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if joint.nq != 1 or joint.nv != 1:
            continue
        k = joint.idx_q
        lo, hi = float(model.lowerPositionLimit[k]), float(model.upperPositionLimit[k])
        if np.isfinite(lo) and np.isfinite(hi):
            revolute = not joint.shortname().startswith("JointModelP")
            out.append((str(model.names[j]), k, revolute, lo, hi))
    return out


def _outside(value: np.ndarray, revolute: bool, lo: float, hi: float) -> np.ndarray:
    """Distance of ``value`` outside [lo, hi] (0 inside); for an angle, of its closest 2 pi shift."""
    if revolute and hi - lo < TWO_PI:
        shifted = lo + np.mod(value - lo, TWO_PI)  # in [lo, lo + 2 pi)
        return np.minimum(np.maximum(shifted - hi, 0.0), lo + TWO_PI - shifted)
    if revolute:
        return np.zeros_like(value)
    return np.maximum(lo - value, 0.0) + np.maximum(value - hi, 0.0)


def limit_violations(mech: Mechanism, q: np.ndarray) -> dict[str, float]:
    """By how much each joint is outside its position limits at ``q`` [m or rad]; empty when none is."""
    out = {}
    for name, k, revolute, lo, hi in _limited_joints(mech):
        d = float(_outside(np.asarray(q[k]), revolute, lo, hi))
        if d > LIMIT_TOL:
            out[name] = d
    return out


def within_limits(mech: Mechanism, q: np.ndarray) -> np.ndarray:
    """Whether configurations respect every joint's limits, shape ``q.shape[:-1]``; False for NaN rows."""
    arr = np.asarray(q, dtype=float)
    ok = np.all(np.isfinite(arr), axis=-1)
    for _, k, revolute, lo, hi in _limited_joints(mech):
        with np.errstate(invalid="ignore"):
            ok &= np.nan_to_num(_outside(arr[..., k], revolute, lo, hi), nan=np.inf) <= LIMIT_TOL
    return ok


def wrap_into_limits(mech: Mechanism, q: np.ndarray) -> np.ndarray:
    """``q`` with each limited revolute angle shifted by a multiple of 2 pi into its limits where one fits."""
    out = np.array(q, dtype=float)
    for _, k, revolute, lo, hi in _limited_joints(mech):
        if revolute and not lo <= out[k] <= hi:
            shifted = lo + float(np.mod(out[k] - lo, TWO_PI))
            if shifted <= hi:
                out[k] = shifted
    return out
