"""Panel figures: at most three a row, one legend, flat (zero or constant to round-off) panels stated."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from plm_pin.exceptions import InvalidInput
from plm_pin.viz import Flat, flat, flat_note, panel_grid, plot_panels

T = np.linspace(0.0, 1.0, 51)


def test_zero_to_round_off_is_flat_with_its_bound():
    """Values within 1e-9 of the scale are zero, bound = their largest magnitude, said with the unit."""
    noise = np.zeros(T.size)
    noise[7], noise[20] = 3e-15, -4e-15  # largest |v| is 4e-15 by construction
    stated = flat("x", noise, "m", scale=0.08)
    assert stated == Flat("x", 0.0, 4e-15, "m")
    assert stated.sentence() == "x: zero to 4e-15 m"
    assert flat("tau", np.zeros(5), "N m", scale=1.0).sentence() == "tau: zero"


def test_constant_to_round_off_is_flat_at_its_level():
    """A curve one double (1.4e-17) off 0.08 m at one sample is constant at 0.08 m to that step."""
    values = np.full(T.size, 0.08)
    values[3] = np.nextafter(0.08, 1.0)
    step = float(values[3] - values[0])
    assert 0.0 < step < 2e-17
    stated = flat("y", values, "m")
    assert stated is not None
    assert stated.level == 0.08 and stated.bound == step
    assert stated.sentence() == f"y: constant at 0.08 m to {step:.0e} m"


def test_a_real_curve_is_not_flat():
    """sin(2 pi t) varies by 1 on a scale of 1: drawn; so is a 1e-6 ripple on the same scale."""
    assert flat("s", np.sin(2 * np.pi * T)) is None
    assert flat("r", 1e-6 * np.sin(2 * np.pi * T), scale=1.0) is None


def test_flat_refuses_bad_input():
    """Empty or non-finite values and a negative scale are refused by name."""
    with pytest.raises(InvalidInput, match="'x': values must be finite"):
        flat("x", [])
    with pytest.raises(InvalidInput, match="'x': values must be finite"):
        flat("x", [0.0, np.nan])
    with pytest.raises(InvalidInput, match=r"^scale must be a finite number >= 0, got -1.0$"):
        flat("x", [1.0], scale=-1.0)


def test_flat_note_lists_the_panels():
    """One sentence for all flat panels, nothing when there are none."""
    assert flat_note([]) == ""
    note = flat_note([Flat("x", 0.0, 1e-17, "m"), Flat("theta", -20.0, 0.0, "deg")])
    assert note == " Not drawn, being flat to round-off: x: zero to 1e-17 m; theta: constant at -20 deg."


def test_panel_grid_has_at_most_three_a_row():
    """Five panels: two rows of three, the sixth cell hidden; two panels: one row of two."""
    fig, axes = panel_grid(5)
    assert len(axes) == 5
    shape = axes[0].get_gridspec().get_geometry()
    assert shape == (2, 3)
    assert sum(ax.get_visible() for ax in fig.axes) == 5
    plt.close(fig)
    fig, axes = panel_grid(2)
    assert axes[0].get_gridspec().get_geometry() == (1, 2)
    plt.close(fig)
    with pytest.raises(InvalidInput, match=r"^n must be a whole number >= 1, got 0$"):
        panel_grid(0)


def test_plot_panels_states_flat_panels_and_shares_one_legend():
    """Flat x (1e-17 on y's scale) and theta are stated; y and a two-line panel drawn, one legend."""
    x = 1e-17 * np.cos(T)  # largest |x| = 1e-17 at t = 0
    y = 0.08 + 0.01 * T**2
    curves = {
        "x [m]": x,
        "y [m]": y,
        "theta [deg]": np.full(T.size, -20.0),
        "pair [N]": np.column_stack([np.sin(T), np.cos(T)]),
    }
    fig, note = plot_panels(T, curves, xlabel="t [s]", labels=["one", "two"])
    assert note == (" Not drawn, being flat to round-off: x: zero to 1e-17 m; theta: constant at -20 deg.")
    assert fig is not None
    drawn = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in drawn] == ["y [m]", "pair [N]"]
    assert [ax.get_ylabel() for ax in drawn] == ["[m]", "[N]"]
    assert len(fig.legends) == 1 and not any(ax.get_legend() for ax in drawn)
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["one", "two"]
    plt.close(fig)


def test_plot_panels_with_every_panel_flat_draws_nothing():
    """All panels flat: no figure, only the sentence."""
    fig, note = plot_panels(T, {"a [W]": np.zeros(T.size)}, xlabel="t [s]")
    assert fig is None and note == " Not drawn, being flat to round-off: a: zero."


def test_plot_panels_refuses_mismatched_samples():
    """A curve with another number of samples than the abscissa is refused by name."""
    with pytest.raises(InvalidInput, match="curve 'a' has shape"):
        plot_panels(T, {"a": np.zeros(3)}, xlabel="t [s]")
    with pytest.raises(InvalidInput, match="at least one curve"):
        plot_panels(T, {}, xlabel="t [s]")
