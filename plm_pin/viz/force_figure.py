"""A planar drawing of a static solution: links, and the forces as arrows (Harada 2011, Fig. 8).

The mechanism is drawn as its skeleton projected on a world plane (segments from each joint
to its child joints and closure frames); the forces of a :class:`~plm_pin.statics.StaticForces`
are drawn where they act, with one length scale [m/N]:

- ``f_c``: actuator force along each prismatic actuator's axis, at its joint;
- ``f_n``: the guide's normal force on each slider, at its joint;
- ``f_l``: the axial force of each hinged link, drawn at its proximal joint along the
  link: towards the distal end for tension (the link pulls), away for compression;
- the external wrench's force at its frame.

An optional second solution is overlaid with broken lines: in the paper's Fig. 8 (b), the
internal force alone (no load, plate preload :math:`f_i`) over the total. matplotlib is
imported only when drawing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._arguments import positive
from .._text import short
from ..core.mechanism import Mechanism
from ..exceptions import InvalidInput
from ..statics import Load, StaticForces, static_forces
from .figures import _axes
from .panels import panel_grid, shared_legend
from .skeleton import plane_axes, skeleton_segments

if TYPE_CHECKING:
    from matplotlib.axes import Axes

COLOURS = {"f_c": "tab:red", "f_n": "tab:green", "f_l": "tab:blue", "load": "black"}


@dataclass(frozen=True)
class ForceArrow:
    """One force drawn as an arrow, world coordinates.

    Attributes:
        kind: ``"f_c"``, ``"f_n"``, ``"f_l"`` or ``"load"``.
        name: the actuator, joint, link or frame it belongs to.
        point: where it acts [m], shape (3,).
        force: the force [N], shape (3,).
    """

    kind: str
    name: str
    point: np.ndarray
    force: np.ndarray


def actuator_arrows(mech: Mechanism, q: ArrayLike, f_c: ArrayLike) -> list[ForceArrow]:
    """Arrows of the actuator forces ``f_c`` [N, N m] at ``q``: one per prismatic actuator, along its axis.

    A revolute actuator's torque has no arrow.

    Raises:
        InvalidInput: a malformed ``q`` or ``f_c`` not of one value per actuator.
    """
    qa = mech.check_q(q)
    forces = np.asarray(f_c, dtype=float)
    if forces.shape != (mech.n_actuators,):
        raise InvalidInput(
            f"f_c must hold one force per actuator ({mech.n_actuators}), got shape {forces.shape}"
        )
    data = mech.model.createData()
    pin.forwardKinematics(mech.model, data, qa)
    return _actuator_arrows(mech, data, forces)


def _actuator_arrows(mech: Mechanism, data: pin.Data, f_c: np.ndarray) -> list[ForceArrow]:
    """The actuator arrows with the joints placed in ``data``."""
    out = []
    for act, f in zip(mech.actuators, f_c, strict=True):
        if act.kind != "prismatic":
            continue
        S = np.asarray(data.joints[act.joint_id].S).reshape(6, -1)
        axis = data.oMi[act.joint_id].rotation @ S[:3, 0]
        out.append(ForceArrow("f_c", act.joint, data.oMi[act.joint_id].translation.copy(), float(f) * axis))
    return out


def force_arrows(sol: StaticForces) -> list[ForceArrow]:
    """The arrows of a static solution (actuator, slider normal, link axial and load forces)."""
    mech = sol.mechanism
    model, data = mech.model, mech.data
    pin.framesForwardKinematics(model, data, sol.balance.q)
    out = _actuator_arrows(mech, data, sol.f_c)
    for joint, normal in sol.slider_normal_forces().items():
        jid = model.getJointId(joint)
        out.append(ForceArrow("f_n", joint, data.oMi[jid].translation.copy(), normal.copy()))
    for link, lf in sol.link_forces().items():
        jid = model.getJointId(lf.joint)
        out.append(ForceArrow("f_l", link, data.oMi[jid].translation.copy(), lf.axial * lf.axis))
    load = sol.balance.load
    if isinstance(load, Load):  # a joint load (pairs of moments on its joints) has no arrow
        point = data.oMf[load.frame_id].translation.copy()
        out.append(ForceArrow("load", load.frame, point, load.wrench[:3].copy()))
    return out


def plot_static_forces(
    sol: StaticForces,
    overlay: StaticForces | None = None,
    *,
    plane: str = "xy",
    scale: float | None = None,
    ax: Axes | None = None,
    title: str | None = None,
    legend: bool = True,
) -> Axes:
    """Draw the mechanism in a plane with its static forces as arrows (Harada 2011, Fig. 8).

    Args:
        sol: the static solution to draw (solid arrows).
        overlay: a second solution at the same configuration, drawn with broken lines
            (Fig. 8 (b): the internal force alone).
        plane: world plane, one of ``"xy"``, ``"xz"``, ``"yz"``.
        scale: arrow length per force [m/N]; default: the largest force is drawn as long as
            a quarter of the mechanism's extent.
        ax: axes to draw into; a new figure when None.
        title: axes title.
        legend: draw the legend of the force kinds in the axes (False: the caller shares one,
            e.g. :func:`~plm_pin.viz.shared_legend`).

    Returns:
        The axes.
    """
    i, j = plane_axes(plane)
    if overlay is not None and not isinstance(overlay, StaticForces):
        raise InvalidInput(f"overlay must be a StaticForces result or None, got {short(overlay)}")
    if scale is not None:
        scale = positive(scale, "scale", "m/N")
    if overlay is not None and not np.allclose(overlay.balance.q, sol.balance.q):
        raise InvalidInput("overlay must be a solution at the same configuration")
    arrows = force_arrows(sol)
    extra = force_arrows(overlay) if overlay is not None else []
    segments = skeleton_segments(sol.mechanism, sol.mechanism.data)
    points = np.array([p for seg in segments for p in seg] or [np.zeros(3)])
    extent = float(np.max(np.ptp(points[:, [i, j]], axis=0))) or 1.0
    if scale is None:
        biggest = max((float(np.linalg.norm(a.force)) for a in arrows + extra), default=0.0)
        scale = 0.25 * extent / biggest if biggest > 0 else 1.0
    _, axes = _axes(ax, (6.0, 5.0))
    for a, b in segments:
        axes.plot([a[i], b[i]], [a[j], b[j]], color="0.3", lw=2, solid_capstyle="round")
    for style, group in (("-", arrows), ("--", extra)):
        for arrow in group:
            d = scale * arrow.force
            axes.annotate(
                "",
                xy=(arrow.point[i] + d[i], arrow.point[j] + d[j]),
                xytext=(arrow.point[i], arrow.point[j]),
                arrowprops={"arrowstyle": "-|>", "color": COLOURS[arrow.kind], "ls": style, "lw": 1.5},
            )
    for kind, colour in COLOURS.items():
        axes.plot([], [], color=colour, label=kind)
    if legend:  # right of the drawing: arrows reach every corner of it
        axes.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    axes.set_aspect("equal")
    axes.set_xlabel(f"{'xyz'[i]} [m]")
    axes.set_ylabel(f"{'xyz'[j]} [m]")
    axes.set_title(title or f"static forces ({scale:.3g} m/N)")
    axes.update_datalim(np.array([[p[i], p[j]] for p in points]))
    axes.autoscale_view()
    return axes


def fig8(mech: Mechanism, q: ArrayLike, f_e: ArrayLike, f_i: float = 1.0) -> tuple[Axes, Axes]:
    """Harada 2011 Fig. 8 on a 3D4M-like mechanism: (a) a load, no preload; (b) with plate preload ``f_i``.

    Args:
        mech: a 2-PRRRP mechanism with a hinged ``plate`` link (the Harada presets).
        q: configuration.
        f_e: force the actuators exert on the end plate (the paper's :math:`f_e`); the load
            applied is its opposite, gravity excluded as in the paper.
        f_i: compression of the end plate by the internal force [N] (eq. (21)).

    Returns:
        The two axes (a) and (b).
    """
    load = -np.asarray(f_e, dtype=float)
    preload = {"plate": -float(f_i)}
    a = static_forces(mech, q, load, gravity=False)
    b = static_forces(mech, q, load, gravity=False, internal=preload)
    internal_only = static_forces(mech, q, gravity=False, internal=preload)
    fig, (ax_a, ax_b) = panel_grid(2, width=5.0, height=2.6)
    plot_static_forces(a, ax=ax_a, title="(a) external force, no internal force", legend=False)
    plot_static_forces(
        b, internal_only, ax=ax_b, title=f"(b) with internal force f_i = {f_i:g} N (broken)", legend=False
    )
    shared_legend(fig, (ax_a, ax_b), below=True)
    return ax_a, ax_b
