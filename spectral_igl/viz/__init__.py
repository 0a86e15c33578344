"""Pictures of spectral kernels and distances (optional extra ``viz``).

Install with ``pip install "spectral_igl[viz]"`` (pyvista and matplotlib). Both are
imported only when a function here is called. Rendering works off screen (scripts,
CI, machines without a display) and on screen.
"""
from ._backend import color_kind, colormap, display_available, headless, save_png, to_pyvista
from ._camera import auto_view, parse_view, place_camera, principal_axes
from ._levelsets import levelset_values, plot_levelsets, reached_vertices
from ._viewer import Viewer

__all__ = ["plot_levelsets", "levelset_values", "reached_vertices", "colormap", "color_kind",
           "auto_view", "parse_view", "place_camera", "principal_axes", "to_pyvista", "save_png", "headless",
           "display_available", "Viewer"]
