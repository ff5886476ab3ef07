"""Matplotlib figures of workspace maps, sweeps and singular loci.

matplotlib is optional (``pip install 'plm-pin[viz]'``) and imported inside the functions
only. Results stay in SI units and radians; angles (``rx``, ``ry``, ``rz``) are converted
to degrees for display, and the labels say so.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .._text import short
from ..exceptions import InvalidInput
from ..workspace.manipulability import POSE_METRICS
from ..workspace.maps import WorkspaceSlice
from ..workspace.singular_loci import SingularPoint

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

ANGLES = ("rx", "ry", "rz")

LABELS = {
    "manipulability": "manipulability w",  # unit: product of J_ce's column units, mechanism-dependent
    "condition_number": "condition number of J_ce [-]",
    "constraint_margin": "constraint margin [-]",
    "inverse_margin": "inverse (type 1) margin [-]",
    "direct_margin": "direct (type 2) margin [-]",
}

KIND_MARKERS = {"inverse": "v", "direct": "o", "constraint": "s"}


def _pyplot() -> Any:
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise ImportError(
            "plm_pin.viz needs matplotlib, which is not installed: pip install 'plm-pin[viz]' "
            "(or pip install matplotlib)"
        ) from exc
    return plt


def _display(axis: str, values: np.ndarray) -> tuple[np.ndarray, str]:
    """Values in display units (degrees for angles) and the axis label with its unit."""
    if axis in ANGLES:
        return np.degrees(values), f"{axis} [deg]"
    return np.asarray(values), f"{axis} [m]"


def _check_metric(metric: str) -> None:
    if not isinstance(metric, str) or metric not in POSE_METRICS:
        raise InvalidInput(f"unknown metric {short(metric)}; metrics are {list(POSE_METRICS)}")


def _check_points(points: object, name: str) -> Sequence[SingularPoint]:
    """``points`` if it is a sequence of :class:`SingularPoint` (e.g. from ``singular_loci``)."""
    if not isinstance(points, Sequence) or not all(isinstance(p, SingularPoint) for p in points):
        raise InvalidInput(
            f"{name} must be a sequence of SingularPoint (plm_pin.workspace.singular_loci), got "
            f"{short(points)}"
        )
    return points


def _axes(ax: Axes | None, figsize: tuple[float, float]) -> tuple[Figure, Axes]:
    if ax is not None:
        from matplotlib.axes import Axes as AxesType

        if not isinstance(ax, AxesType):
            raise InvalidInput(f"ax must be matplotlib Axes or None, got {short(ax)}")
        return ax.figure, ax  # type: ignore[return-value]
    plt = _pyplot()
    fig, new_ax = plt.subplots(figsize=figsize)
    return fig, new_ax


def plot_map(
    result: WorkspaceSlice,
    metric: str = "manipulability",
    *,
    loci: Sequence[SingularPoint] = (),
    ax: Axes | None = None,
    log: bool = False,
    title: str | None = None,
) -> Figure:
    """Colour map of one metric over a 2-D workspace slice, unreachable points left blank.

    Args:
        result: a map from :func:`plm_pin.workspace.workspace_map`.
        metric: one of :data:`plm_pin.workspace.POSE_METRICS`.
        loci: singular points to mark (e.g. from :func:`plm_pin.workspace.singular_loci`),
            one marker shape per kind.
        ax: axes to draw in (default: a new figure).
        log: logarithmic colour scale.
        title: axes title (default: the mechanism-independent metric name).

    Returns:
        The figure (with a colour bar).
    """
    _check_metric(metric)
    loci = _check_points(loci, "loci")
    if len(result.axes) != 2:
        raise InvalidInput(f"plot_map needs a 2-D map, got a slice along {list(result.axes)}; use plot_sweep")
    _pyplot()  # a clear message when matplotlib is missing
    from matplotlib.colors import LogNorm

    fig, ax_ = _axes(ax, (6.0, 4.5))
    u, ulabel = _display(result.axes[0], result.values[0])
    v, vlabel = _display(result.axes[1], result.values[1])
    z = np.array(result.metric(metric), dtype=float)
    z[~np.isfinite(z) | ~result.reachable] = np.nan
    norm = None
    if log:
        positive = z[np.isfinite(z) & (z > 0.0)]
        if positive.size:
            norm = LogNorm(vmin=float(positive.min()), vmax=float(positive.max()))
        z[z <= 0.0] = np.nan
    mesh = ax_.pcolormesh(u, v, np.ma.masked_invalid(z).T, shading="nearest", norm=norm)
    fig.colorbar(mesh, ax=ax_, label=LABELS[metric])
    _mark_loci(ax_, result, loci)
    ax_.set_xlabel(ulabel)
    ax_.set_ylabel(vlabel)
    ax_.set_title(title if title is not None else LABELS[metric])
    return fig


def _mark_loci(ax: Axes, result: WorkspaceSlice, loci: Sequence[SingularPoint]) -> None:
    if not loci:
        return
    i, j = (result.dofs.index(a) for a in result.axes)
    for kind, marker in KIND_MARKERS.items():
        pts = [p for p in loci if p.kind == kind]
        if not pts:
            continue
        xs, _ = _display(result.axes[0], np.array([p.x[i] for p in pts]))
        ys, _ = _display(result.axes[1], np.array([p.x[j] for p in pts]))
        ax.scatter(xs, ys, marker=marker, s=14, facecolors="none", edgecolors="red", label=f"{kind} singular")
    ax.legend(loc="best", fontsize="small")


def plot_sweep(
    result: WorkspaceSlice,
    metric: str = "manipulability",
    *,
    singular: Sequence[SingularPoint] = (),
    ax: Axes | None = None,
    label: str | None = None,
    log: bool = False,
    title: str | None = None,
) -> Figure:
    """One metric along a 1-D sweep (e.g. w against the plate angle, Harada 2011 Fig. 6).

    Unreachable samples leave gaps. Call again with the same ``ax`` to overlay mechanisms.

    Args:
        result: a sweep from :func:`plm_pin.workspace.workspace_sweep`.
        metric: one of :data:`plm_pin.workspace.POSE_METRICS`.
        singular: singular points on the sweep (from
            :func:`plm_pin.workspace.singular_points_along`), drawn as dashed vertical lines.
        ax: axes to draw in (default: a new figure).
        label: legend label of the curve.
        log: logarithmic vertical axis.
        title: axes title.

    Returns:
        The figure.
    """
    _check_metric(metric)
    singular = _check_points(singular, "singular")
    if label is not None and not isinstance(label, str):
        raise InvalidInput(f"label must be a string or None, got {short(label)}")
    if len(result.axes) != 1:
        raise InvalidInput(f"plot_sweep needs a 1-D sweep, got a map over {list(result.axes)}; use plot_map")
    _pyplot()
    fig, ax_ = _axes(ax, (6.0, 4.0))
    axis = result.axes[0]
    t, tlabel = _display(axis, result.values[0])
    y = np.array(result.metric(metric), dtype=float)
    y[~result.reachable] = np.nan
    ax_.plot(t, y, label=label)
    for p in singular:
        at = float(_display(axis, np.array([p.parameter]))[0][0])
        ax_.axvline(at, linestyle="--", linewidth=0.8, color="red")
        unit = "deg" if axis in ANGLES else "m"
        ax_.annotate(
            f"{p.kind} {at:.2f} {unit}",
            xy=(at, 1.0),
            xycoords=("data", "axes fraction"),
            rotation=90,
            va="top",
            ha="right",
            fontsize="small",
        )
    if log:
        ax_.set_yscale("log")
    ax_.set_xlabel(tlabel)
    ax_.set_ylabel(LABELS[metric])
    if title is not None:
        ax_.set_title(title)
    if label is not None:
        ax_.legend(loc="best")
    return fig
