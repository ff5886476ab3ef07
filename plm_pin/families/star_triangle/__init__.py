"""3-PRP star-triangle planar manipulators (Enferadi & Tavakolian 2017)."""

from .builder import build_star_triangle, star_triangle_inverse_kinematics

__all__ = ["build_star_triangle", "star_triangle_inverse_kinematics"]
