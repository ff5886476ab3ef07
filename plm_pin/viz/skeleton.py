"""A mechanism drawn as its planar skeleton: segments from each joint to its children and closure frames.

Used for snapshots of a motion (Harada 2011, Figs. 11 and 13: the table every 0.2 s) and
under the force arrows of :func:`~plm_pin.viz.plot_static_forces`. matplotlib is imported
only when drawing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput
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
    sliders on their stator, are squares.

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
    for q, shade in zip(configs, shades, strict=True):
        pin.framesForwardKinematics(mech.model, data, q)
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
