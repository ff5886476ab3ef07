"""A mechanism's skeleton: links between joints, rails of prismatic joints, the platform's polygon.

The geometry (:func:`skeleton_segments`, :func:`prismatic_rails`, :func:`platform_polygon`)
is shared by the planar figures here and the meshcat scenes of
:mod:`plm_pin.viz.meshcat_view`. :func:`plot_skeletons` draws snapshots of a motion
(Harada 2011, Figs. 11 and 13: the table every 0.2 s) and the mechanism under the force
arrows of :func:`~plm_pin.viz.plot_static_forces`. matplotlib is imported only when drawing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..core.mechanism import Mechanism, joint_type
from ..exceptions import InvalidInput
from ..tolerances import VIEW_MIN_LENGTH
from .figures import _axes

if TYPE_CHECKING:
    from matplotlib.axes import Axes

PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}
"""World planes a skeleton is projected on, with the indices of their axes."""


def plane_axes(plane: str) -> tuple[int, int]:
    """Indices of the world axes of ``plane``.

    Raises:
        InvalidInput: ``plane`` is not one of :data:`PLANES`.
    """
    if not isinstance(plane, str) or plane not in PLANES:
        raise InvalidInput(f"plane {plane!r} is not one of {list(PLANES)}")
    return PLANES[plane]


def skeleton_segments(mech: Mechanism, data: pin.Data) -> list[tuple[np.ndarray, np.ndarray]]:
    """Segments [m] from each joint to its child joints and closure frames, world coordinates.

    Args:
        mech: the mechanism.
        data: Pinocchio data with joint and frame placements at the configuration drawn.
    """
    model = mech.model
    segments = []
    for j in range(1, model.njoints):
        parent = model.parents[j]
        if parent > 0:
            segments.append((data.oMi[parent].translation.copy(), data.oMi[j].translation.copy()))
    for c in mech.closures:
        for fid in c.frame_ids:
            joint = model.frames[fid].parentJoint
            if joint > 0:
                segments.append((data.oMi[joint].translation.copy(), data.oMf[fid].translation.copy()))
    return segments


@dataclass(frozen=True)
class Rail:
    """The stroke of a prismatic joint: the segment its joint frame's origin runs along between its limits.

    Attributes:
        joint: the prismatic joint's name.
        parent: the id of its parent joint (0: the base), whose frame the ends are given in.
        start: the origin's position at the lower limit, in the parent joint's frame [m], shape (3,).
        end: the origin's position at the upper limit, in the parent joint's frame [m], shape (3,).
    """

    joint: str
    parent: int
    start: np.ndarray
    end: np.ndarray

    @property
    def length(self) -> float:
        """The stroke [m]: upper minus lower limit."""
        return float(np.linalg.norm(self.end - self.start))


def prismatic_rails(model: pin.Model) -> list[Rail]:
    """The rail of every one-axis prismatic joint with a finite stroke, in joint order.

    The joint frame moves by ``q * a`` along its axis ``a`` (the linear part of its motion
    subspace), from its placement in the parent joint's frame.
    """
    out = []
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if joint_type(model, j) != "prismatic" or joint.nq != 1:
            continue
        lower = float(model.lowerPositionLimit[joint.idx_q])
        upper = float(model.upperPositionLimit[joint.idx_q])
        if not (np.isfinite(upper - lower) and upper > lower):  # Pinocchio's default: +-max, no rail
            continue
        data = joint.createData()
        joint.calc(data, pin.neutral(model))
        axis = np.asarray(data.S).reshape(6, -1)[:3, 0]  # in the joint frame
        placement = model.jointPlacements[j]
        along = placement.rotation @ axis
        start = placement.translation + lower * along
        end = placement.translation + upper * along
        out.append(Rail(model.names[j], int(model.parents[j]), start, end))
    return out


@dataclass(frozen=True)
class Platform:
    """The polygon through a platform's attachment points, in the platform joint's frame.

    Attributes:
        joint: the id of the joint carrying the platform (the task frame's joint).
        points: the attachment points [m], shape (k, 3), k >= 3, in order around their centroid;
            the polygon closes from the last back to the first.
    """

    joint: int
    points: np.ndarray


def platform_polygon(mech: Mechanism) -> Platform | None:
    """The platform of ``mech`` as a closed polygon, None when it has fewer than 3 attachment points.

    The platform is the body of the task frame; its attachment points are where the legs
    hold it: its closure frames, the origins of the joints it carries, and its own joint's
    origin when that joint hangs on a leg (not on the base). The points are ordered by
    angle in their best-fitting plane; points in one line make no polygon.
    """
    fid = mech.task_frame_id
    if fid is None:
        return None
    model = mech.model
    joint = int(model.frames[fid].parentJoint)
    if joint == 0:
        return None
    frames = [f for c in mech.closures for f in c.frame_ids if model.frames[f].parentJoint == joint]
    points = [model.frames[f].placement.translation for f in frames]
    children = [k for k in range(1, model.njoints) if model.parents[k] == joint]
    points += [model.jointPlacements[k].translation for k in children]
    if model.parents[joint] != 0:
        points.append(np.zeros(3))
    unique: list[np.ndarray] = []
    for p in points:
        if all(np.linalg.norm(p - u) > VIEW_MIN_LENGTH for u in unique):
            unique.append(np.array(p, dtype=float))
    if len(unique) < 3:
        return None
    arr = np.array(unique)
    centred = arr - arr.mean(axis=0)
    _, sv, vt = np.linalg.svd(centred)
    if sv[1] <= VIEW_MIN_LENGTH * max(sv[0], 1.0):
        return None
    angles = np.arctan2(centred @ vt[1], centred @ vt[0])
    return Platform(joint, arr[np.argsort(angles)])


def plot_skeletons(
    mech: Mechanism,
    qs: ArrayLike,
    *,
    plane: str = "xy",
    ax: Axes | None = None,
    title: str | None = None,
) -> Axes:
    """Draw the mechanism's skeleton at each configuration of ``qs``, later ones darker.

    Links are segments between joints (and closure frames); joints on the base, such as
    sliders on their stator, are squares; rails (:func:`prismatic_rails`) are wide light
    bands (``lw=5``) and the platform (:func:`platform_polygon`) a closed outline.

    Args:
        mech: the mechanism.
        qs: configurations, shape (n, nq) (one configuration of shape (nq,) is accepted).
        plane: world plane, one of ``"xy"``, ``"xz"``, ``"yz"``.
        ax: axes to draw into; a new figure when None.
        title: axes title.

    Returns:
        The axes.

    Raises:
        InvalidInput: a configuration of the wrong size or not finite, an empty ``qs``, or
            an unknown plane.
    """
    i, j = plane_axes(plane)
    try:
        rows = np.atleast_2d(np.asarray(qs, dtype=float))
    except (TypeError, ValueError) as exc:
        raise InvalidInput(f"qs must be configurations of {mech.nq} numbers: {exc}") from None
    if rows.size == 0:
        raise InvalidInput("qs is empty: give at least one configuration")
    configs = [mech.check_q(q, f"qs[{k}]") for k, q in enumerate(rows)]
    _, axes = _axes(ax, (6.0, 4.0))
    data = mech.model.createData()
    shades = np.linspace(0.75, 0.0, len(configs)) if len(configs) > 1 else [0.0]
    grounded = [j for j in range(1, mech.model.njoints) if mech.model.parents[j] == 0]
    rails = prismatic_rails(mech.model)
    platform = platform_polygon(mech)
    for k, (q, shade) in enumerate(zip(configs, shades, strict=True)):
        pin.framesForwardKinematics(mech.model, data, q)
        for rail in (r for r in rails if k == 0 or r.parent > 0):  # rails on the base drawn once
            a, b = (data.oMi[rail.parent].act(p) for p in (rail.start, rail.end))
            axes.plot([a[i], b[i]], [a[j], b[j]], color="0.85", lw=5, solid_capstyle="butt", zorder=0)
        if platform is not None:
            ring = np.array([data.oMi[platform.joint].act(p) for p in platform.points])
            ring = np.vstack([ring, ring[:1]])
            axes.plot(ring[:, i], ring[:, j], color=str(shade), lw=0.8)
        for a, b in skeleton_segments(mech, data):
            axes.plot([a[i], b[i]], [a[j], b[j]], color=str(shade), lw=1.2, solid_capstyle="round")
        # joints on the base (sliders on their stator, cranks' pivots) as squares
        base = np.array([data.oMi[k].translation for k in grounded]).reshape(-1, 3)
        axes.plot(base[:, i], base[:, j], "s", color=str(shade), ms=5, ls="none")
    axes.set_aspect("equal")
    axes.set_xlabel(f"{'xyz'[i]} [m]")
    axes.set_ylabel(f"{'xyz'[j]} [m]")
    if title:
        axes.set_title(title)
    return axes
