"""Analyses over the workspace: manipulability, workspace maps, accuracy maps and singular loci."""

from .accuracy import AccuracyMap, accuracy_map, accuracy_over
from .manipulability import (
    POSE_METRICS,
    Manipulability,
    manipulability,
    manipulability_at,
    manipulability_unit,
)
from .maps import WorkspaceSlice, workspace_grid, workspace_map, workspace_sweep
from .orientation import OrientationRange, orientation_range
from .singular_loci import SingularPoint, singular_loci, singular_points, singular_points_along

__all__ = [
    "POSE_METRICS",
    "AccuracyMap",
    "Manipulability",
    "OrientationRange",
    "SingularPoint",
    "WorkspaceSlice",
    "accuracy_map",
    "accuracy_over",
    "manipulability",
    "manipulability_at",
    "manipulability_unit",
    "orientation_range",
    "singular_loci",
    "singular_points",
    "singular_points_along",
    "workspace_grid",
    "workspace_map",
    "workspace_sweep",
]
