"""Figures of analysis results (matplotlib, imported only when a figure is drawn)."""

from .figures import plot_map, plot_sweep

__all__ = ["plot_map", "plot_sweep"]
