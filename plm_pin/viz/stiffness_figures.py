"""Figures of stiffness maps (matplotlib, imported when used)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..exceptions import InvalidInput
from ..stiffness import StiffnessMap
from ..stiffness.maps import VARIABLES
from .figures import _axes, _display, _pyplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def plot_stiffness_map(
    smap: StiffnessMap,
    variable: str = "min_translational_stiffness",
    *,
    ax: Axes | None = None,
    log: bool = True,
) -> Figure:
    """Colour map of one stiffness variable over a 2-D slice, unreached or singular points blank.

    Args:
        smap: from :func:`plm_pin.stiffness.stiffness_map`.
        variable: one of :data:`plm_pin.stiffness.maps.VARIABLES`.
        ax: axes to draw in (default: a new figure).
        log: logarithmic colour scale.

    Raises:
        InvalidInput: an unknown variable or a slice that is not 2-D.
    """
    z = np.array(smap.variable(variable), dtype=float)
    if len(smap.axes) != 2:
        raise InvalidInput(f"plot_stiffness_map needs a 2-D map, got a slice along {list(smap.axes)}")
    _pyplot()
    from matplotlib.colors import LogNorm

    fig, ax_ = _axes(ax, (6.0, 4.5))
    u, ulabel = _display(smap.axes[0], smap.values[0])
    v, vlabel = _display(smap.axes[1], smap.values[1])
    z[~np.isfinite(z) | ~smap.reachable] = np.nan
    norm = None
    positive = z[np.isfinite(z) & (z > 0.0)]
    if log and positive.size:
        norm = LogNorm(vmin=float(positive.min()), vmax=float(positive.max()))
        z[z <= 0.0] = np.nan
    mesh = ax_.pcolormesh(u, v, np.ma.masked_invalid(z).T, shading="nearest", norm=norm)
    unit, meaning = VARIABLES[variable]
    fig.colorbar(mesh, ax=ax_, label=f"{variable} [{unit}]")
    ax_.set_xlabel(ulabel)
    ax_.set_ylabel(vlabel)
    ax_.set_title(meaning, fontsize=9)
    return fig
