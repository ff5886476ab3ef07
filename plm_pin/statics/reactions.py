r"""Joint reactions, slider normal forces and link axial forces of a static solution.

Once the actuator forces :math:`f_c` and the cut-joint forces :math:`\lambda` are known,
the closure forces are applied as external forces on the two bodies of each cut joint
(force :math:`\lambda` on frame B, its opposite on frame A, moments from the rotation rows),
and Pinocchio's RNEA at rest transmits every load down the spanning tree: the spatial force
each joint passes from its parent to its child is that joint's reaction. Its component along
the joint's motion is the actuator force (zero for a passive joint); the rest is carried by
the joint's structure. Projections give the quantities of Harada 2011 (eqs. (16)-(19)):

- slider normal force: the force a prismatic guide exerts normal to its axis (:math:`f_n n`);
- link axial force: on a link hinged at its parent joint (revolute or spherical, unactuated)
  with one distal attachment (a child joint or a closure frame), the component of the
  proximal reaction along the link's axis, **tension positive** (:math:`f_l`). It is the
  whole reaction (shear zero) on a two-force link: massless or without gravity, no load on it.

Everything is linear in the loads, so internal-force directions (no load, no gravity) are read
by the same code.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..core import closures as _closures
from ..core.mechanism import Mechanism, body_name
from ..results import Result, unit
from ..tolerances import ATTACHMENT_ATOL
from .balance import AnyLoad, Load


@dataclass(frozen=True)
class JointReaction(Result):
    """Force a joint passes from its parent body to its child, world-aligned, about the joint origin.

    Attributes:
        joint: joint name.
        force: force on the child [N], shape (3,).
        moment: moment on the child about the joint origin [N m], shape (3,).
        drive: component along the joint's motion: actuator force [N] or torque [N m]
            (zero for a passive joint), shape (joint nv,).
    """

    joint: str
    force: np.ndarray = field(metadata=unit("N"))
    moment: np.ndarray = field(metadata=unit("N m"))
    drive: np.ndarray = field(metadata=unit("N, N m"))


@dataclass(frozen=True)
class LinkForce(Result):
    """Axial force of a hinged link, read at its proximal joint.

    Attributes:
        link: link (body) name.
        joint: its parent joint.
        axis: unit vector from the proximal joint to the distal attachment, world, shape (3,).
        axial: tension along ``axis`` [N], positive in tension (Harada 2011's :math:`f_l`).
        shear: magnitude of the proximal reaction normal to ``axis`` [N]; zero on a two-force link.
    """

    link: str
    joint: str
    axis: np.ndarray = field(metadata=unit("-"))
    axial: float = field(metadata=unit("N"))
    shear: float = field(metadata=unit("N"))


@dataclass(frozen=True)
class _Hinged:
    link: str
    joint_id: int
    distal: tuple[str, int]  # ("joint", id) or ("frame", id)
    proximal_closures: tuple[tuple[slice, float], ...]  # force rows of closures acting at the hinge, sign


@functools.lru_cache(maxsize=64)
def hinged_links(mech: Mechanism) -> tuple[_Hinged, ...]:
    """Links hinged at an unactuated rotational parent joint with exactly one distal attachment."""
    model = mech.model
    q = mech.q_ref
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    actuated = {a.joint_id for a in mech.actuators}
    closure_frames = {fid for c in mech.closures for fid in c.frame_ids}
    out = []
    for j in range(1, model.njoints):
        if j in actuated or not _is_rotational(model, data, j):
            continue
        origin = data.oMi[j].translation
        points: list[tuple[np.ndarray, tuple[str, int]]] = []
        for k in range(1, model.njoints):
            if model.parents[k] == j:
                points.append((data.oMi[k].translation, ("joint", k)))
        for fid in sorted(closure_frames):
            if model.frames[fid].parentJoint == j:
                points.append((data.oMf[fid].translation, ("frame", fid)))
        at_hinge = tuple(
            (slice(c.rows.start, c.rows.start + 3), 1.0 if side == 1 else -1.0)
            for c in mech.closures
            for side, fid in enumerate(c.frame_ids)
            if c.point_rows
            and model.frames[fid].parentJoint == j
            and np.linalg.norm(data.oMf[fid].translation - origin) <= ATTACHMENT_ATOL
        )
        distinct: list[tuple[np.ndarray, tuple[str, int]]] = []
        for p, ref in points:
            if np.linalg.norm(p - origin) <= ATTACHMENT_ATOL:
                continue
            if all(np.linalg.norm(p - d) > ATTACHMENT_ATOL for d, _ in distinct):
                distinct.append((p, ref))
        if len(distinct) == 1:
            out.append(_Hinged(body_name(model, j), j, distinct[0][1], at_hinge))
    return tuple(out)


def _is_rotational(model: pin.Model, data: pin.Data, j: int) -> bool:
    """Whether joint ``j`` only rotates about its origin (revolute, spherical)."""
    S = np.asarray(data.joints[j].S).reshape(6, -1)
    return S.size > 0 and bool(np.allclose(S[:3], 0.0)) and model.joints[j].nq != 7


def transmitted_forces(
    mech: Mechanism,
    q: np.ndarray,
    lam: np.ndarray,
    load: AnyLoad | None,
    gravity: bool,
    v: np.ndarray | None = None,
    a: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Forces every joint passes from parent to child, world-aligned, about the joint origin.

    Args:
        mech: the mechanism.
        q: configuration, shape (nq,).
        lam: cut-joint forces, shape (m,).
        load: external wrench, or None.
        gravity: include the bodies' weight.
        v: joint velocities (None: at rest); the bodies' inertia forces are then included.
        a: joint accelerations (None: zero).

    Returns:
        forces (njoints, 6) as ``(force, moment)`` rows (row 0, the universe, is zero) and the
        joint drive forces ``S^T f`` (nv,), which equal the actuator forces on actuated joints
        and vanish on passive ones in equilibrium.
    """
    model, data = mech.model, mech.data
    pin.framesForwardKinematics(model, data, q)
    fext = [pin.Force.Zero() for _ in range(model.njoints)]
    for c in mech.closures:
        fa, fb = c.frame_ids
        force = lam[c.rows.start : c.rows.start + c.point_rows] if c.point_rows else np.zeros(3)
        moment = np.zeros(3)
        if c.spec.type != "point":
            moment = _closures.angular_rows(c, data).T @ lam[c.rotation_rows]
        _add_world_wrench(model, data, fext, fb, force, moment)
        _add_world_wrench(model, data, fext, fa, -force, -moment)
    if isinstance(load, Load):
        _add_world_wrench(model, data, fext, load.frame_id, load.wrench[:3], load.wrench[3:])
    elif load is not None:  # on each output joint's child body, and its opposite on the parent body
        for jid, f in zip(load.joints, load.forces, strict=True):
            j = model.getJointId(jid)
            S = np.asarray(data.joints[j].S).reshape(6, -1)[:, 0]  # (v, omega) in the joint's frame
            pair = pin.Force(S[:3] * f, S[3:] * f)
            fext[j] += pair
            fext[model.parents[j]] -= data.liMi[j].act(pair)
    zero = np.zeros(model.nv)
    vel = zero if v is None else v
    acc = zero if a is None else a
    drive = pin.rnea(model, data, q, vel, acc, fext).copy()
    local = [data.f[j].copy() for j in range(model.njoints)]
    if not gravity:  # remove the weight: RNEA is linear in gravity and external forces
        drive -= pin.computeGeneralizedGravity(model, data, q)
        local = [f - data.f[j] for j, f in enumerate(local)]
    pin.framesForwardKinematics(model, data, q)  # placements of q for the world-aligned reading
    out = np.zeros((model.njoints, 6))
    for j in range(1, model.njoints):
        fw = data.oMi[j].act(local[j])  # world frame, about the world origin
        p = data.oMi[j].translation
        out[j, :3] = fw.linear
        out[j, 3:] = fw.angular - np.cross(p, fw.linear)
    return out, drive


def _add_world_wrench(
    model: pin.Model,
    data: pin.Data,
    fext: list[pin.Force],
    frame_id: int,
    force: np.ndarray,
    moment: np.ndarray,
) -> None:
    """Add a world-aligned wrench acting at a frame origin to the external forces of its joint."""
    joint = model.frames[frame_id].parentJoint
    p = data.oMf[frame_id].translation
    world = pin.Force(force, moment + np.cross(p, force))
    fext[joint] += data.oMi[joint].actInv(world)


def joint_reactions(mech: Mechanism, forces: np.ndarray, drive: np.ndarray) -> dict[str, JointReaction]:
    """Per-joint reactions from :func:`transmitted_forces` output."""
    model = mech.model
    out = {}
    for j in range(1, model.njoints):
        name = model.names[j]
        idx, nvj = model.joints[j].idx_v, model.joints[j].nv
        out[name] = JointReaction(
            name, forces[j, :3].copy(), forces[j, 3:].copy(), drive[idx : idx + nvj].copy()
        )
    return out


def slider_normal_forces(mech: Mechanism, forces: np.ndarray) -> dict[str, np.ndarray]:
    """Force each prismatic guide exerts normal to its axis [N], world, keyed by joint name.

    Harada 2011's :math:`f_n n` (eq. (16)): the reaction force minus its axial (driving) part.
    """
    model, data = mech.model, mech.data
    out = {}
    for j in range(1, model.njoints):
        S = np.asarray(data.joints[j].S).reshape(6, -1)
        if S.shape[1] != 1 or not np.allclose(S[3:], 0.0):
            continue
        axis = data.oMi[j].rotation @ S[:3, 0]
        f = forces[j, :3]
        out[model.names[j]] = f - (axis @ f) * axis
    return out


def link_forces(mech: Mechanism, forces: np.ndarray, lam: np.ndarray) -> dict[str, LinkForce]:
    """Axial force (tension positive) and shear of every hinged link, keyed by link name.

    The force at the hinge is the parent joint's reaction plus the forces of closures cut at
    the hinge point on this link (a plate hinged on one rod and closed on another at the
    same point receives both).
    """
    model, data = mech.model, mech.data
    out = {}
    for h in hinged_links(mech):
        kind, idx = h.distal
        distal = data.oMi[idx].translation if kind == "joint" else data.oMf[idx].translation
        u = distal - data.oMi[h.joint_id].translation
        u = u / np.linalg.norm(u)
        f = forces[h.joint_id, :3].copy()  # force of the parent on the link
        for rows, sign in h.proximal_closures:
            f += sign * lam[rows]
        axial = float(-(u @ f))
        shear = float(np.linalg.norm(f - (u @ f) * u))
        out[h.link] = LinkForce(h.link, model.names[h.joint_id], u, axial, shear)
    return out
