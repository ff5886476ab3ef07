"""Position limits of the tree joints: whether a configuration respects them.

Joints the description leaves without limits are unlimited (see
:func:`plm_pin.description.loader.open_missing_limits`). A revolute angle respects limits
``[lo, hi]`` when some ``angle + 2 k pi`` lies in them (the same pose of the body);
:func:`wrap_into_limits` moves it there. Limits are a reachability condition of their own:
a pose where the loops close only with a joint outside its range is reported as such
(:func:`limit_violations`), apart from the poses where the loops cannot close at all.
"""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ..core.mechanism import Mechanism
from ..tolerances import LIMIT_TOL

TWO_PI = 2.0 * np.pi


_ONE_DOF: weakref.WeakKeyDictionary[pin.Model, tuple[tuple[str, int, bool], ...]] = (
    weakref.WeakKeyDictionary()
)

"""(name, idx_q, revolute) of a model's one-DOF joints: the joint types never change, limits may."""


def _one_dof_joints(model: pin.Model) -> tuple[tuple[str, int, bool], ...]:
    """(name, idx_q, revolute) of the one-DOF joints, found once per model (a Python call per joint)."""
    try:
        return _ONE_DOF[model]
    except (KeyError, TypeError):
        pass
    out = []
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if joint.nq == 1 and joint.nv == 1:
            revolute = not joint.shortname().startswith("JointModelP")
            out.append((str(model.names[j]), int(joint.idx_q), revolute))
    joints = tuple(out)
    try:
        _ONE_DOF[model] = joints
    except TypeError:  # a model that takes no weak reference: found again next time
        pass
    return joints


class _Limits(NamedTuple):
    """The one-DOF joints with a finite range: names, q indices, revolute flags, bounds (arrays)."""

    names: tuple[str, ...]
    k: np.ndarray
    revolute: np.ndarray
    lower: np.ndarray
    upper: np.ndarray


def _limited_joints(mech: Mechanism) -> _Limits:
    """The one-DOF joints with a finite range, their bounds read from the model at each call."""
    model = mech.model
    joints = _one_dof_joints(model)
    k = np.array([j[1] for j in joints], dtype=int)
    lower, upper = np.asarray(model.lowerPositionLimit)[k], np.asarray(model.upperPositionLimit)[k]
    keep = np.isfinite(lower) & np.isfinite(upper)
    names = tuple(j[0] for j, kept in zip(joints, keep, strict=True) if kept)
    revolute = np.array([j[2] for j in joints], dtype=bool)[keep]
    return _Limits(names, k[keep], revolute, lower[keep], upper[keep])


def _outside(value: np.ndarray, limits: _Limits) -> np.ndarray:
    """Distance of each joint's ``value`` (last axis) outside its range (0 inside).

    For a revolute joint whose range is narrower than a turn, the distance of the angle's
    closest 2 pi shift; a revolute joint with a wider range holds every angle.
    """
    lo, hi = limits.lower, limits.upper
    wrapped = limits.revolute & (hi - lo < TWO_PI)
    with np.errstate(invalid="ignore"):  # NaN or infinite entries give NaN, as the callers expect
        shifted = lo + np.mod(value - lo, TWO_PI)  # in [lo, lo + 2 pi)
        angle = np.minimum(np.maximum(shifted - hi, 0.0), lo + TWO_PI - shifted)
        linear = np.maximum(lo - value, 0.0) + np.maximum(value - hi, 0.0)
    return np.where(wrapped, angle, np.where(limits.revolute, 0.0, linear))


def limit_violations(mech: Mechanism, q: np.ndarray) -> dict[str, float]:
    """By how much each joint is outside its position limits at ``q`` [m or rad]; empty when none is."""
    limits = _limited_joints(mech)
    d = _outside(np.asarray(q, dtype=float)[limits.k], limits)
    return {limits.names[i]: float(d[i]) for i in np.flatnonzero(d > LIMIT_TOL)}


def within_limits(mech: Mechanism, q: np.ndarray) -> np.ndarray:
    """Whether configurations respect every joint's limits, shape ``q.shape[:-1]``; False for NaN rows."""
    arr = np.asarray(q, dtype=float)
    ok = np.all(np.isfinite(arr), axis=-1)
    limits = _limited_joints(mech)
    d = np.nan_to_num(_outside(arr[..., limits.k], limits), nan=np.inf)
    return ok & np.all(d <= LIMIT_TOL, axis=-1)


def wrap_into_limits(mech: Mechanism, q: np.ndarray) -> np.ndarray:
    """``q`` with each limited revolute angle shifted by a multiple of 2 pi into its limits where one fits."""
    out = np.array(q, dtype=float)
    limits = _limited_joints(mech)
    lo, hi, value = limits.lower, limits.upper, out[limits.k]
    with np.errstate(invalid="ignore"):
        shifted = lo + np.mod(value - lo, TWO_PI)
        move = limits.revolute & ~((lo <= value) & (value <= hi)) & (shifted <= hi)
    out[limits.k[move]] = shifted[move]
    return out
