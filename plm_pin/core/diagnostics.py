"""What ``plm-pin check`` says about a loaded mechanism beyond its files: DOF, task, limits."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import pinocchio as pin

from ..tolerances import LOOSE_END_RTOL
from .mechanism import Mechanism, body_names


@dataclass(frozen=True)
class Finding:
    """One finding about a mechanism.

    Attributes:
        severity: ``"error"`` (analyses would refuse or be wrong: the check fails) or
            ``"note"`` (how the mechanism is read; the check passes).
        message: what was found and what it means, in one sentence or two.
    """

    severity: Literal["error", "note"]
    message: str


def mobility_text(mech: Mechanism) -> str:
    """The mobility, with its idle part apart: ``"2"`` or ``"2, 1 idle"``."""
    return f"{mech.mobility}" + (f", {mech.idle_mobility} idle" if mech.idle_mobility else "")


@dataclass(frozen=True)
class LooseEnd:
    """A frame of a leaf body (no child joint, no closure) lying near a frame of another body.

    Attributes:
        frame: the leaf body's frame.
        body: the leaf body.
        near: the nearest frame of another body.
        near_body: that body (``"universe"`` for the ground).
        distance: their distance at the reference configuration [m].
    """

    frame: str
    body: str
    near: str
    near_body: str
    distance: float


def loose_ends(mech: Mechanism) -> tuple[LooseEnd, ...]:
    """Frames of leaf bodies that lie near another body's frame at the reference: missing closures?

    A frame of a leaf body counts when it is away from the body's joint (a tip, not the
    hinge the body hangs from) and no closure uses it; it is a loose end when a frame of
    another body (not its parent's) lies within :data:`LOOSE_END_RTOL` of the mechanism's
    size. One per pair of frames (the first leaf's), sorted by distance.
    """
    model = mech.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, mech.q_ref)
    origins = np.array([data.oMi[j].translation for j in range(model.njoints)])
    size = float(np.max(np.linalg.norm(origins[:, None] - origins[None], axis=-1), initial=0.0))
    if size == 0.0:
        return ()
    has_child = {int(model.parents[j]) for j in range(1, model.njoints)}
    used = {f for c in mech.sidecar.closures for f in c.frames}
    bodies = ("universe", *body_names(model))
    points = np.array([data.oMf[f].translation for f in range(len(model.frames))])
    owner = np.array([model.frames[f].parentJoint for f in range(len(model.frames))])
    named = np.array([f.type in (pin.FrameType.BODY, pin.FrameType.OP_FRAME) for f in model.frames])
    named &= np.array([f.name not in used for f in model.frames])
    out: list[LooseEnd] = []
    for f, frame in enumerate(model.frames):
        j = frame.parentJoint
        if j == 0 or j in has_child or not named[f]:
            continue
        if np.linalg.norm(points[f] - origins[j]) <= LOOSE_END_RTOL * size:
            continue  # at the hinge the body hangs from
        others = np.flatnonzero(named & (owner != j) & (owner != model.parents[j]))
        if others.size == 0:
            continue
        d = np.linalg.norm(points[others] - points[f], axis=1)
        k = int(np.argmin(d))
        near = int(others[k])
        if d[k] <= LOOSE_END_RTOL * size and not any(e.frame == model.frames[near].name for e in out):
            out.append(
                LooseEnd(frame.name, bodies[j], model.frames[near].name, bodies[owner[near]], float(d[k]))
            )
    return tuple(sorted(out, key=lambda e: e.distance))


def findings(mech: Mechanism) -> tuple[Finding, ...]:
    """Idle mobilities, a task that does not match the DOF, under-actuation.

    Args:
        mech: the mechanism (its mobility is computed here).

    Returns:
        The findings, errors first.
    """
    out: list[Finding] = []
    task = mech.task
    if task is not None and len(task.dofs) != mech.mobility:
        few = len(task.dofs) < mech.mobility
        out.append(
            Finding(
                "error",
                f"the task {list(task.dofs)} has {len(task.dofs)} coordinates but the mechanism has "
                f"{mech.mobility} DOF: "
                + (
                    "a pose does not determine the configuration, so IK, FK, the Jacobians and "
                    "manipulability are undefined; " + _missing_causes(mech)
                    if few
                    else "the task coordinates are not independent, so the Jacobians and "
                    "manipulability are undefined; keep only independent coordinates in end_effector.task"
                ),
            )
        )
    if mech.idle_mobility:
        joints = [g.joint for g in mech.idle_gauges]
        out.append(
            Finding(
                "note",
                f"mobility {mobility_text(mech)}: {mech.idle_mobility} motion(s) move nothing else (a strut "
                "spinning about its own axis, a half-revolute pair turning together); joint(s) "
                f"{joints} are held at their reference values and every analysis runs on the "
                f"{mech.mobility} effective DOF",
            )
        )
    if mech.n_actuators < mech.mobility:
        out.append(
            Finding(
                "note",
                f"{mech.n_actuators} actuators for {mech.mobility} DOF: under-actuated, the actuators do "
                "not determine the configuration (forward kinematics refuses)",
            )
        )
    return tuple(sorted(out, key=lambda f: f.severity != "error"))


def _missing_causes(mech: Mechanism) -> str:
    """Both causes of a task shorter than the mobility; a missing closure first, named by a loose end."""
    ends = loose_ends(mech)
    closure = (
        "either a closure is missing"
        if not ends
        else "either a closure is missing: "
        + "; ".join(
            f"frame {e.frame!r} of leaf body {e.body!r} lies {e.distance:.3g} m from frame {e.near!r} "
            f"of body {e.near_body!r} with no closure between them"
            for e in ends[:3]
        )
        + " (add it under closures)"
    )
    return f"{closure}, or the task lacks coordinates (add the missing coordinates to end_effector.task)"
