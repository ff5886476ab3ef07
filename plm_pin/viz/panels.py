"""Multi-panel figures that read at a report's width, with flat panels stated rather than drawn.

A report page is about 1280 px wide: more than :data:`PANELS_PER_ROW` panels side by side
make unreadable ticks. A panel whose values are zero, or constant, to round-off (within
:data:`NOISE` of the quantity's scale) would draw numerical noise as if it were a curve;
it is left out and said in a sentence ("y: constant at 0.08 m to 3e-17 m"). matplotlib is
imported only when drawing.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from .._arguments import check_tolerance, count, positive
from .._text import short
from ..exceptions import InvalidInput
from ..tolerances import NOISE
from .figures import _pyplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

PANELS_PER_ROW = 3
"""Most panels side by side in a figure: more would be unreadable at a report page's width."""


@dataclass(frozen=True)
class Flat:
    """A quantity that is zero, or constant, to round-off: said, not drawn.

    Attributes:
        name: the quantity (a panel's title without its unit).
        level: the constant value [unit]; 0.0 for a quantity that is zero.
        bound: the largest deviation from ``level`` [unit].
        unit: unit of ``level`` and ``bound`` (may be empty).
    """

    name: str
    level: float
    bound: float
    unit: str

    def sentence(self) -> str:
        """E.g. ``x: zero to 2e-17 m``, ``y: constant at 0.08 m to 3e-17 m``, ``tau: zero``."""
        unit = f" {self.unit}" if self.unit else ""
        level = "zero" if self.level == 0.0 else f"constant at {self.level:.6g}{unit}"
        return f"{self.name}: {level}" + (f" to {self.bound:.0e}{unit}" if self.bound > 0.0 else "")


def flat(
    name: str, values: ArrayLike, unit: str = "", *, scale: float | None = None, noise: float = NOISE
) -> Flat | None:
    """The :class:`Flat` statement of ``values`` if they are zero or constant to round-off, else None.

    Zero: every ``|v| <= noise * scale``. Constant: every ``|v - v[0]| <= noise * scale``.

    Args:
        name: the quantity's name, for the sentence.
        values: the samples, any shape (all columns of a panel together) [unit].
        unit: their unit.
        scale: the quantity's scale [unit], e.g. the largest value of that unit in the figure;
            default: the largest ``|v|`` (so only a constant can be flat, a zero curve exactly 0).
        noise: relative threshold [-].

    Raises:
        InvalidInput: empty or non-finite values, a negative scale or noise.
    """
    v = np.asarray(values, dtype=float).ravel()
    if v.size == 0 or not np.all(np.isfinite(v)):
        raise InvalidInput(f"{name!r}: values must be finite and not empty")
    noise = check_tolerance(noise, "noise")
    s = float(np.max(np.abs(v))) if scale is None else check_tolerance(scale, "scale")
    peak = float(np.max(np.abs(v)))
    if peak <= noise * s:
        return Flat(name, 0.0, peak, unit)
    spread = float(np.max(np.abs(v - v[0])))
    if spread <= noise * s:
        return Flat(name, float(v[0]), spread, unit)
    return None


def flat_note(flats: Sequence[Flat]) -> str:
    """The sentence a caption ends with for the panels left out ("" when none)."""
    if not flats:
        return ""
    return " Not drawn, being flat to round-off: " + "; ".join(f.sentence() for f in flats) + "."


def panel_grid(
    n: int, *, width: float = 4.2, height: float = 3.2, **kwargs: Any
) -> tuple[Figure, list[Axes]]:
    """A figure of ``n`` panels, at most :data:`PANELS_PER_ROW` a row; unused cells are hidden.

    Args:
        n: number of panels (at least 1).
        width: width of one panel [in].
        height: height of one panel [in].
        **kwargs: passed to ``plt.subplots`` (``sharex``, ``sharey``).

    Returns:
        The figure and its ``n`` visible axes, row by row.
    """
    n = count(n, "n", minimum=1)
    width, height = positive(width, "width", "in"), positive(height, "height", "in")
    cols = min(PANELS_PER_ROW, n)
    rows = -(-n // cols)
    fig, axes = _pyplot().subplots(
        rows, cols, figsize=(width * cols, height * rows), layout="constrained", squeeze=False, **kwargs
    )
    flat_axes = list(axes.flat)
    for ax in flat_axes[n:]:
        ax.set_visible(False)
    return fig, flat_axes[:n]


def shared_legend(
    fig: Figure, axes: Sequence[Axes], title: str | None = None, *, below: bool = False
) -> None:
    """One legend for the figure from the labelled lines of all axes (each label once).

    Args:
        fig: the figure (made with ``layout="constrained"``, as :func:`panel_grid` does).
        axes: the panels whose lines are listed.
        title: legend title.
        below: under the panels in one row (for short, wide panels such as equal-aspect
            drawings), instead of right of them.
    """
    seen: dict[str, Any] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            seen.setdefault(label, handle)
    if seen:
        handles, labels = list(seen.values()), list(seen)
        if below:
            fig.legend(
                handles, labels, title=title, fontsize="small", loc="outside lower center", ncols=len(labels)
            )
        else:
            fig.legend(handles, labels, title=title, fontsize="small", loc="outside right upper")


def _unit(title: str, default: str = "") -> str:
    """The unit in a title's trailing brackets, ``"y [m]"`` -> ``"m"`` (``default`` without one)."""
    return title.rsplit("[", 1)[1].rstrip("]").strip() if title.endswith("]") and "[" in title else default


def _name(title: str) -> str:
    """A title without its trailing unit, ``"y [m]"`` -> ``"y"``."""
    return title.rsplit("[", 1)[0].strip() if title.endswith("]") and "[" in title else title


def plot_panels(
    x: ArrayLike,
    curves: Mapping[str, ArrayLike],
    *,
    xlabel: str,
    ylabel: str | None = None,
    unit: str = "",
    labels: Sequence[str] = (),
    legend_title: str | None = None,
    noise: float = NOISE,
) -> tuple[Figure | None, str]:
    """Curves against a common abscissa, one panel each, flat ones stated instead of drawn.

    Each panel's title ends with its unit in brackets (``"(b) velocity [m/s]"``,
    ``"theta [deg]"``); a panel is flat (:func:`flat`) relative to the largest ``|value|`` of
    all panels of the same unit. The drawn panels are laid out by :func:`panel_grid` with one
    :func:`shared_legend`.

    Args:
        x: abscissa, shape (n,).
        curves: panel title -> values, shape (n,) or (n, k) (k lines, labelled by ``labels``).
        xlabel: abscissa label, with its unit.
        ylabel: ordinate label of every panel (default: the panel's unit in brackets).
        unit: unit of the panels whose title names none.
        labels: legend text of the k lines of each panel (none: no legend).
        legend_title: title of the shared legend.
        noise: relative threshold of :func:`flat` [-].

    Returns:
        The figure (None when every panel is flat) and the sentence naming the flat panels,
        to append to the caption ("" when none).

    Raises:
        InvalidInput: no curves, or values whose length differs from ``x``.
    """
    t = np.asarray(x, dtype=float)
    if not curves:
        raise InvalidInput("plot_panels needs at least one curve")
    if (
        isinstance(labels, str)
        or not isinstance(labels, Sequence)
        or not all(isinstance(s, str) for s in labels)
    ):
        raise InvalidInput(f"labels must be a sequence of legend texts (strings), got {short(labels)}")
    check_tolerance(noise, "noise")
    values: dict[str, np.ndarray] = {}
    for title, v in curves.items():
        a = np.asarray(v, dtype=float)
        if a.ndim not in (1, 2) or a.shape[0] != t.size:
            raise InvalidInput(f"curve {title!r} has shape {a.shape}; expected ({t.size},) or ({t.size}, k)")
        values[title] = a.reshape(t.size, -1)
    scales: dict[str, float] = {}
    units = {title: _unit(title, unit) for title in values}
    for title, a in values.items():
        scales[units[title]] = max(scales.get(units[title], 0.0), float(np.max(np.abs(a), initial=0.0)))
    flats: list[Flat] = []
    drawn: dict[str, np.ndarray] = {}
    for title, v in values.items():
        stated = flat(_name(title), v, units[title], scale=scales[units[title]], noise=noise)
        if stated is None:
            drawn[title] = v
        else:
            flats.append(stated)
    note = flat_note(flats)
    if not drawn:
        return None, note
    fig, axes = panel_grid(len(drawn))
    for ax, (title, v) in zip(axes, drawn.items(), strict=True):
        for i in range(v.shape[1]):
            ax.plot(t, v[:, i], label=labels[i] if i < len(labels) else None)
        ax.set_title(title)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel if ylabel is not None else (f"[{units[title]}]" if units[title] else ""))
        ax.grid(alpha=0.3)
    shared_legend(fig, axes, legend_title)
    return fig, note
