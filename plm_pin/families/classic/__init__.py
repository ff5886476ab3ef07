"""Classic planar linkages: the crank-rocker four-bar and the RRRRR five-bar."""

from .builder import build_fivebar, build_fourbar

__all__ = ["build_fivebar", "build_fourbar"]
