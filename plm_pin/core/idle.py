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

Their *gauge* is fixed by holding, per idle mobility, one one-DOF joint at its reference
value or one ball (spherical) joint about one axis, chosen by a column-pivoted QR
(Gram-Schmidt) of the idle basis so that the held joints block every idle motion. Each hold
becomes a closure ``idle:<joint>`` between two frames added to the model
(``idle_gauge_<joint>_parent`` on the parent body at the joint's reference placement,
``idle_gauge_<joint>_child`` at the joint): a weld for a one-DOF joint, whose one non-zero
rotation row is the joint's offset from its reference angle (or its translation for a
prismatic joint); a one-row ``twist`` for a ball joint (the spin of a rod on a ball joint
closed by a point at its other end), which holds the rotation about the idle axis alone and
leaves the two others to the mechanism. Every analysis then runs on the *effective* mobility.
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
from .rank import rank_of_singular_values

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

GAUGE_PREFIX = "idle:"
"""Name prefix of the gauge closures."""


@dataclass(frozen=True)
class IdleGauge:
    """The gauge of one idle mobility: a joint held at its reference value.

    Attributes:
        joint: the held joint.
        value: its reference position [rad] or [m] (one-DOF joint), 0 for a ball joint held about
            ``closure.axis`` (the rotation from its reference orientation about that axis).
        closure: the closure holding it (weld, or twist for a ball joint), between two frames
            added to the model.
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
        _, s, Vt = np.linalg.svd(J_phi)
        N = Vt[rank_of_singular_values(s, tol).rank :].T  # (nv, mobility)
    else:
        N = np.eye(nv)
    if N.shape[1] == 0:
        return N
    ON = observed_rows(model, data, closures, actuated_v, task_frame) @ N
    _, s, Vt = np.linalg.svd(ON)
    scale = max(float(s[0]) if s.size else 0.0, 1.0)
    moving = int(np.sum(s > max(IDLE_RTOL, tol) * scale))
    return np.asarray(N @ Vt[moving:].T)


_BALL_JOINTS = {"JointModelSpherical": 0, "JointModelFreeFlyer": 3}
"""Joints held about one axis, with the index of their local angular velocity in their velocity."""


def gauge_joints(model: pin.Model, K: np.ndarray) -> list[tuple[int, np.ndarray | None]]:
    """Joints whose velocities block the idle motions ``K`` (nv, n_idle), with the axis each is held about.

    Column-pivoted Gram-Schmidt (the pivoting of a QR) on the joints' shares of ``K``: the
    joint carrying the largest share of the idle motions first, then the one carrying most
    of what is left. A one-DOF joint's share is its row of ``K`` (held whole: axis None); a
    ball joint's (spherical, or a free flyer's rotation) is the largest singular value of its
    angular-velocity rows, held about the matching axis (in the joint's frame), a free flyer
    only when the idle motions do not translate it. Shares equal to :data:`GAUGE_TIE_RTOL`
    (symmetric legs) go to the first joint by name, and the joints come back in the order of
    their names, so that the gauges depend on rounding no more than on the tree order (a
    model exported and read back holds the same joints in the same order). Fewer joints than
    idle motions come back when no more joint takes a share above :data:`GAUGE_MIN_PIVOT`.
    """
    candidates: list[tuple[int, np.ndarray]] = []  # (joint, its rows of K)
    for j in sorted(range(1, model.njoints), key=lambda j: str(model.names[j])):
        joint = model.joints[j]
        start = _BALL_JOINTS.get(joint.shortname())
        if joint.nv == 1:
            candidates.append((j, K[joint.idx_v : joint.idx_v + 1]))
        elif (
            start is not None
            and not np.abs(K[joint.idx_v : joint.idx_v + start]).max(initial=0.0) > GAUGE_MIN_PIVOT
        ):
            candidates.append((j, K[joint.idx_v + start : joint.idx_v + start + 3]))
    if not candidates or K.shape[1] == 0:
        return []
    chosen: list[tuple[int, np.ndarray | None]] = []
    for _ in range(K.shape[1]):
        shares = [
            float(np.linalg.norm(rows, 2)) if rows.shape[0] > 1 else float(np.linalg.norm(rows))
            for _, rows in candidates
        ]
        best = max(shares)
        if best < GAUGE_MIN_PIVOT:
            break
        k = next(i for i, share in enumerate(shares) if share >= best * (1.0 - GAUGE_TIE_RTOL))
        j, rows = candidates[k]
        U, _, Vt = np.linalg.svd(rows)
        chosen.append((j, None if rows.shape[0] == 1 else U[:, 0]))
        u = Vt[0]  # the idle motion the hold blocks, in the idle basis
        candidates = [(i, r - np.outer(r @ u, u)) for i, r in candidates]  # what is left of each share
    return sorted(chosen, key=lambda c: str(model.names[c[0]]))


def add_gauges(
    model: pin.Model, q: np.ndarray, joints: Sequence[tuple[int, np.ndarray | None]]
) -> tuple[IdleGauge, ...]:
    """Add the frames holding ``joints`` (each with the axis of a ball joint's hold, or None) at ``q``.

    The model gains two frames per held joint: create the data afterwards.
    """
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    out = []
    held: dict[str, int] = {}
    for j, axis in joints:
        name = str(model.names[j])
        parent_frame = f"idle_gauge_{name}_parent"
        child_frame = f"idle_gauge_{name}_child"
        held[name] = held.get(name, 0) + 1
        if held[name] == 1:
            parent = int(model.parents[j])
            model.addFrame(pin.Frame(parent_frame, parent, pin.SE3(data.liMi[j]), pin.FrameType.OP_FRAME))
            model.addFrame(pin.Frame(child_frame, j, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
        closure = f"{GAUGE_PREFIX}{name}" + (f":{held[name]}" if held[name] > 1 else "")
        joint = model.joints[j]
        if axis is not None:  # a ball joint held about one axis
            unit = tuple(float(a) for a in axis / np.linalg.norm(axis))
            spec = ClosureSpec(closure, (parent_frame, child_frame), "twist", unit)  # type: ignore[arg-type]
            out.append(IdleGauge(name, 0.0, spec))
            continue
        if joint.nq == 2:  # unbounded revolute stored as (cos, sin)
            value = float(np.arctan2(q[joint.idx_q + 1], q[joint.idx_q]))
        else:
            value = float(q[joint.idx_q])
        spec = ClosureSpec(name=closure, frames=(parent_frame, child_frame), type="weld")
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
    closed (the caller reports that) or when no joint can hold an idle motion.

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
