"""3-PRP star-triangle planar manipulators (Enferadi & Tavakolian 2017)."""

from .builder import (
    build_star_triangle,
    enferadi2017_circle,
    enferadi2017_line,
    star_triangle_inverse_kinematics,
)

__all__ = [
    "build_star_triangle",
    "enferadi2017_circle",
    "enferadi2017_line",
    "star_triangle_inverse_kinematics",
]
