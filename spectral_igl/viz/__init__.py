"""Pictures of spectral kernels and distances (optional extra ``viz``).

Install with ``pip install "spectral_igl[viz]"`` (pyvista and matplotlib). Both are
imported only when a function here is called. Rendering works off screen (scripts,
CI, machines without a display) and on screen.
"""
from ._backend import colormap, headless, save_png, to_pyvista
from ._levelsets import levelset_values, plot_levelsets
from ._viewer import Viewer

__all__ = ["plot_levelsets", "levelset_values", "colormap", "to_pyvista", "save_png", "headless", "Viewer"]
