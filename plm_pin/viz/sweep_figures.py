"""Matplotlib figures of design sweeps: heat maps and line plots of one result variable.

They take one variable of a sweep's Dataset (:mod:`plm_pin.sweep.result`), an
``xarray.DataArray`` with the other dimensions already selected, e.g.
``ds.orientation_halfwidth.sel(legs="(1, 2, 4)")``. Values and coordinates whose ``units``
are ``rad`` are shown in degrees (and labelled so); text coordinates (tuple-valued
parameters) become categorical ticks. matplotlib and xarray are imported by the caller's
objects only.
"""

from __future__ import annotations

import textwrap
from typing import TYPE_CHECKING

import numpy as np

from ..exceptions import InvalidInput
from .figures import _axes, _pyplot

if TYPE_CHECKING:
    import xarray as xr
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def _values(data: xr.DataArray) -> tuple[np.ndarray, str]:
    """Display values of a DataArray and their unit text (degrees for radians)."""
    units = str(data.attrs.get("units", ""))
    values = np.asarray(data.values)
    if units == "rad":
        return np.degrees(values.astype(float)), "deg"
    return values, units


def _coordinate(data: xr.DataArray, dim: str) -> tuple[np.ndarray, str, list[str] | None]:
    """Positions along ``dim``, its axis label, and tick labels for text coordinates."""
    if dim not in data.dims:
        raise InvalidInput(f"{data.name!r} has no dimension {dim!r}; its dimensions are {list(data.dims)}")
    coord = data[dim]
    values, units = _values(coord)
    label = f"{dim} [{units}]" if units else dim
    if values.dtype.kind in "US":
        return np.arange(values.size, dtype=float), label, [str(v) for v in values]
    return values.astype(float), label, None


LABEL_WIDTH = 40
"""Characters per line of an axis label; longer labels (long units) are wrapped."""


def _label(data: xr.DataArray) -> str:
    _, units = _values(data)
    label = f"{data.name} [{units}]" if units else str(data.name)
    return textwrap.fill(label, LABEL_WIDTH)


def plot_sweep_heatmap(
    data: xr.DataArray,
    x: str,
    y: str,
    *,
    ax: Axes | None = None,
    title: str | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    cmap: str = "viridis",
    colorbar: bool = True,
) -> Figure:
    """Colour map of a sweep variable over two dimensions; NaN (unreached, failed) left blank.

    Args:
        data: a 2-D ``xarray.DataArray`` of a sweep's result with dimensions ``x`` and ``y``.
        x: the dimension along the horizontal axis.
        y: the dimension along the vertical axis.
        ax: axes to draw in (default: a new figure).
        title: axes title (default: the variable's description).
        vmin: lower end of the colour scale, in display units (degrees for radians).
        vmax: upper end of the colour scale.
        cmap: matplotlib colour map.
        colorbar: add a colour bar labelled with the variable and its unit (False: panels
            sharing ``vmin`` and ``vmax`` share one, added by the caller).

    Returns:
        The figure.

    Raises:
        InvalidInput: ``data`` is not 2-D over ``x`` and ``y``.
    """
    if data.ndim != 2 or set(data.dims) != {x, y}:
        raise InvalidInput(
            f"a heat map needs a 2-D variable over {[x, y]}; {data.name!r} has dimensions {list(data.dims)} "
            "(select the others first)"
        )
    _pyplot()
    fig, ax_ = _axes(ax, (6.0, 4.5))
    u, ulabel, uticks = _coordinate(data, x)
    v, vlabel, vticks = _coordinate(data, y)
    z, _ = _values(data.transpose(y, x))
    mesh = ax_.pcolormesh(
        u, v, np.ma.masked_invalid(z.astype(float)), shading="nearest", vmin=vmin, vmax=vmax, cmap=cmap
    )
    if colorbar:
        fig.colorbar(mesh, ax=ax_, label=_label(data))
    if uticks is not None:
        ax_.set_xticks(u, uticks, rotation=30, ha="right")
    if vticks is not None:
        ax_.set_yticks(v, vticks)
    ax_.set_xlabel(ulabel)
    ax_.set_ylabel(vlabel)
    ax_.set_title(title if title is not None else str(data.attrs.get("description", data.name)))
    return fig


def plot_sweep_lines(
    data: xr.DataArray,
    x: str,
    hue: str | None = None,
    *,
    ax: Axes | None = None,
    title: str | None = None,
    label: str = "{hue} = {value}",
    linestyle: str = "-",
    marker: str | None = None,
) -> Figure:
    """A sweep variable against one dimension, one line per value of ``hue``; NaN leaves gaps.

    Call again with the same ``ax`` (and another ``linestyle``) to overlay mechanisms.

    Args:
        data: an ``xarray.DataArray`` over ``x`` (and ``hue``).
        x: the dimension along the horizontal axis.
        hue: the dimension whose values give the lines (None: ``data`` is 1-D).
        ax: axes to draw in (default: a new figure).
        title: axes title.
        label: legend text, formatted with ``hue`` and ``value``.
        linestyle: matplotlib line style.
        marker: matplotlib marker.

    Returns:
        The figure.

    Raises:
        InvalidInput: ``data`` has other dimensions than ``x`` and ``hue``.
    """
    dims = {x} if hue is None else {x, hue}
    if set(data.dims) != dims:
        raise InvalidInput(
            f"a line plot needs a variable over {sorted(dims)}; {data.name!r} has dimensions "
            f"{list(data.dims)} (select the others first)"
        )
    _pyplot()
    fig, ax_ = _axes(ax, (6.0, 4.0))
    t, tlabel, tticks = _coordinate(data, x)
    if hue is None:
        values, _ = _values(data)
        ax_.plot(t, values.astype(float), linestyle=linestyle, marker=marker)
    else:
        shown, _ = _values(data[hue])
        for k, value in enumerate(data[hue].values):
            line, _ = _values(data.isel({hue: k}).transpose(x))
            text = f"{shown[k]:.4g}" if np.asarray(shown).dtype.kind == "f" else str(value)
            ax_.plot(
                t,
                line.astype(float),
                linestyle=linestyle,
                marker=marker,
                label=label.format(hue=hue, value=text),
            )
        ax_.legend(loc="best", fontsize="small")
    if tticks is not None:
        ax_.set_xticks(t, tticks, rotation=30, ha="right")
    ax_.set_xlabel(tlabel)
    ax_.set_ylabel(_label(data))
    if title is not None:
        ax_.set_title(title)
    ax_.grid(alpha=0.3)
    return fig
