"""Figures (matplotlib) and meshcat scenes of mechanisms; both packages are imported only when used."""

from .figures import plot_map, plot_sweep
from .force_figure import ForceArrow, fig8, force_arrows, plot_static_forces
from .inspect_server import Inspector, inspect
from .inspect_state import InspectState, inspect_state, inspect_update
from .inspect_widget import InspectorPanel
from .meshcat_server import MeshcatServer
from .meshcat_view import MeshcatViewer, SceneStatus, scene_html, show
from .panels import Flat, flat, flat_note, panel_grid, plot_panels, shared_legend
from .skeleton import plot_skeletons
from .stiffness_figures import plot_stiffness_map
from .sweep_figures import plot_sweep_heatmap, plot_sweep_lines

__all__ = [
    "Flat",
    "ForceArrow",
    "InspectState",
    "Inspector",
    "InspectorPanel",
    "MeshcatServer",
    "MeshcatViewer",
    "SceneStatus",
    "fig8",
    "flat",
    "flat_note",
    "force_arrows",
    "inspect",
    "inspect_state",
    "inspect_update",
    "panel_grid",
    "plot_map",
    "plot_panels",
    "plot_skeletons",
    "plot_static_forces",
    "plot_stiffness_map",
    "plot_sweep",
    "plot_sweep_heatmap",
    "plot_sweep_lines",
    "scene_html",
    "shared_legend",
    "show",
]
