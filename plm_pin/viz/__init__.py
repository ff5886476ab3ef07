"""Figures (matplotlib) and meshcat scenes of mechanisms; both packages are imported only when used."""

from .figures import plot_map, plot_sweep
from .meshcat_server import MeshcatServer, ViewerError
from .meshcat_view import MeshcatViewer, SceneStatus, scene_html, show

__all__ = [
    "MeshcatServer",
    "MeshcatViewer",
    "SceneStatus",
    "ViewerError",
    "plot_map",
    "plot_sweep",
    "scene_html",
    "show",
]
