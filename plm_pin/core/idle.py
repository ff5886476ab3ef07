r"""Idle mobilities: feasible motions that move nothing else, and the gauge that fixes them.

A strut between two spherical joints can spin about its own axis, and the half-revolute +
weld pairs of the example-parallel-robots models can turn together, without moving any
other part of the mechanism: such a motion satisfies the closures, yet moves no actuator,
no end-effector frame and no joint. It counts in :math:`n_v - \operatorname{rank} J_\phi`
but no analysis can use it. A feasible motion :math:`v` (:math:`J_\phi v = 0`) is *idle*
when it also leaves at rest

- every actuated joint (:math:`S_a v = 0`),
- the end-effector frame (its whole twist),
- the origin of every joint and of every closure frame, and the centre of mass of every
  body with mass (their linear velocities).

So only bodies spinning about an axis through all their attachment points and their centre
of mass move (a pendulum hanging on a ball joint is a real mobility, not an idle one). The idle
motions span the null space of :math:`O N`, :math:`O` stacking these rows and :math:`N` a
basis of the feasible motions.

Their *gauge* is fixed by holding one one-DOF joint per idle mobility at its reference
value, chosen by a column-pivoted QR (Gram-Schmidt) of the idle basis so that the held joints block every
idle motion. Each held joint becomes a weld closure ``idle:<joint>`` between two frames
added to the model (``idle_gauge_<joint>_parent`` on the parent body at the joint's
reference placement, ``idle_gauge_<joint>_child`` at the joint): its one non-zero rotation
row is the joint's offset from its reference angle (or its translation for a prismatic
joint). Every analysis then runs on the *effective* mobility.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..description.sidecar import ClosureSpec
from ..exceptions import ClosureNotSatisfied
from ..tolerances import CLOSURE_TOL, GAUGE_MIN_PIVOT, GAUGE_TIE_RTOL, IDLE_RTOL
from . import closures as _closures
from .assembly import assemble
from .rank import rank_by_gap

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

GAUGE_PREFIX = "idle:"
"""Name prefix of the gauge closures."""


@dataclass(frozen=True)
class IdleGauge:
    """The gauge of one idle mobility: a joint held at its reference value.

    Attributes:
        joint: the held one-DOF joint.
        value: its reference position [rad] or [m].
        closure: the weld closure holding it, between two frames added to the model.
    """

    joint: str
    value: float
    closure: ClosureSpec


def observed_rows(
    model: pin.Model,
    data: pin.Data,
    closures: Sequence[_closures.Closure],
    actuated_v: Sequence[int] | np.ndarray,
    task_frame: int | None,
) -> np.ndarray:
    """Rows that an idle motion leaves at zero, from joint Jacobians already in ``data``, shape (k, nv).

    Actuated velocities, the task frame's twist, and the linear velocities of the joint
    origins, of the centres of mass of the bodies with mass and of the closure frames (all
    world-aligned). ``data`` must also hold the joint placements.
    """
    rows = [np.eye(model.nv)[list(actuated_v)]]
    if task_frame is not None:
        rows.append(pin.getFrameJacobian(model, data, task_frame, _LWA))
    for j in range(1, model.njoints):
        J = pin.getJointJacobian(model, data, j, _LWA)  # (6, nv) at the joint origin
        rows.append(J[:3])
        if model.inertias[j].mass > 0.0:  # centre of mass: v_o + w x (c - o)
            lever = data.oMi[j].rotation @ model.inertias[j].lever
            rows.append(J[:3] - pin.skew(lever) @ J[3:])
    for c in closures:
        rows += [pin.getFrameJacobian(model, data, f, _LWA)[:3] for f in c.frame_ids]
    return np.vstack(rows)


def idle_motions(
    model: pin.Model,
    data: pin.Data,
    closures: Sequence[_closures.Closure],
    q: np.ndarray,
    actuated_v: Sequence[int] | np.ndarray,
    task_frame: int | None,
    tol: float = CLOSURE_TOL,
) -> np.ndarray:
    """Orthonormal basis of the idle motions at an assembled ``q``, shape (nv, n_idle).

    The feasible motions are the null space of the closure Jacobian, its rank cut at the
    largest gap above the closure tolerance ``tol`` [m, rad]
    (:func:`~plm_pin.core.rank.rank_by_gap`); a motion is idle when the observed rows move by
    at most ``max(IDLE_RTOL, tol)`` of their scale (the loops of a rounded description close
    only to ``tol``, and its idle motions move the observed points by as little).
    """
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    nv = model.nv
    if closures:
        J_phi = _closures.jacobian_from_data(model, data, closures)
        rank = rank_by_gap(J_phi, tol).rank
        N = np.linalg.svd(J_phi)[2][rank:].T  # (nv, mobility)
    else:
        N = np.eye(nv)
    if N.shape[1] == 0:
        return N
    ON = observed_rows(model, data, closures, actuated_v, task_frame) @ N
    _, s, Vt = np.linalg.svd(ON)
    scale = max(float(s[0]) if s.size else 0.0, 1.0)
    moving = int(np.sum(s > max(IDLE_RTOL, tol) * scale))
    return np.asarray(N @ Vt[moving:].T)


def gauge_joints(model: pin.Model, K: np.ndarray) -> list[int]:
    """Joint ids of one-DOF joints whose velocities block the idle motions ``K`` (nv, n_idle).

    Column-pivoted Gram-Schmidt (the pivoting of a QR) on the one-DOF rows of ``K``: the
    joint carrying the largest share of the idle motions first, then the one carrying most
    of what is left. Shares equal to :data:`GAUGE_TIE_RTOL` (symmetric legs) go to the first
    joint by name, and the joints come back in the order of their names, so that the
    gauges depend on rounding no more than on the tree order (a model exported and read
    back holds the same joints in the same order). Fewer joints than idle motions come back
    when no more one-DOF joint takes a share above :data:`GAUGE_MIN_PIVOT`.
    """
    candidates = sorted(
        (j for j in range(1, model.njoints) if model.joints[j].nv == 1), key=lambda j: str(model.names[j])
    )
    if not candidates or K.shape[1] == 0:
        return []
    rows = K[[model.joints[j].idx_v for j in candidates]]  # (n_cand, n_idle)
    chosen = []
    for _ in range(min(K.shape[1], len(candidates))):
        share = np.linalg.norm(rows, axis=1)
        best = float(share.max())
        if best < GAUGE_MIN_PIVOT:
            break
        k = int(np.flatnonzero(share >= best * (1.0 - GAUGE_TIE_RTOL))[0])
        chosen.append(candidates[k])
        u = rows[k] / share[k]
        rows = rows - np.outer(rows @ u, u)  # what the chosen joint leaves of each share
    return sorted(chosen, key=lambda j: str(model.names[j]))


def add_gauges(model: pin.Model, q: np.ndarray, joints: Sequence[int]) -> tuple[IdleGauge, ...]:
    """Add the frames holding ``joints`` at their values in ``q`` and return their gauges.

    The model gains two frames per joint: create the data afterwards.
    """
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    out = []
    for j in joints:
        name = str(model.names[j])
        parent = int(model.parents[j])
        joint = model.joints[j]
        parent_frame = f"idle_gauge_{name}_parent"
        child_frame = f"idle_gauge_{name}_child"
        model.addFrame(pin.Frame(parent_frame, parent, pin.SE3(data.liMi[j]), pin.FrameType.OP_FRAME))
        model.addFrame(pin.Frame(child_frame, j, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
        if joint.nq == 2:  # unbounded revolute stored as (cos, sin)
            value = float(np.arctan2(q[joint.idx_q + 1], q[joint.idx_q]))
        else:
            value = float(q[joint.idx_q])
        spec = ClosureSpec(name=f"{GAUGE_PREFIX}{name}", frames=(parent_frame, child_frame), type="weld")
        out.append(IdleGauge(name, value, spec))
    return tuple(out)


def find_gauges(
    model: pin.Model,
    closures: Sequence[_closures.Closure],
    guess: np.ndarray,
    actuated_v: Sequence[int] | np.ndarray,
    task_frame: int | None,
    *,
    tol: float = CLOSURE_TOL,
) -> tuple[tuple[IdleGauge, ...], np.ndarray | None]:
    """Detect the idle mobilities near ``guess`` and hold one joint each (frames added to ``model``).

    The loops are closed from ``guess``; the idle motions are counted there and at an
    assembled random perturbation of it, the smaller count being the generic one (a special
    configuration can only add idle motions). No gauge comes back when the loops cannot be
    closed (the caller reports that) or when no one-DOF joint can hold an idle motion.

    Returns:
        The gauges, and the configuration assembled from ``guess`` (None when the loops
        cannot be closed), at which the held joints take their values.
    """
    if not closures:
        return (), None
    data = model.createData()
    free = np.arange(model.nv)
    try:
        q0 = assemble(model, data, closures, guess, free, tol=tol).q
    except ClosureNotSatisfied:
        return (), None
    configs = [q0]
    step = np.random.default_rng(20111009).normal(scale=0.02, size=model.nv)
    try:
        configs.append(assemble(model, data, closures, pin.integrate(model, q0, step), free, tol=tol).q)
    except ClosureNotSatisfied:
        pass
    bases = [idle_motions(model, data, closures, q, actuated_v, task_frame, tol) for q in configs]
    k = min(range(len(bases)), key=lambda i: bases[i].shape[1])
    if bases[k].shape[1] == 0:
        return (), q0
    return add_gauges(model, q0, gauge_joints(model, bases[k])), q0
