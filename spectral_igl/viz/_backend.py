"""Lazy access to pyvista/matplotlib, off-screen set-up, colour maps and shape conversion.

Nothing here imports pyvista, vtk or matplotlib at module level: ``import spectral_igl``
and ``import spectral_igl.viz`` stay light.
"""
from __future__ import annotations

import functools
import os
import sys

import numpy as np

from .._extras import install_hint
from .._validate import as_cells, as_points, describe

INSTALL_HINT = install_hint("viz")

# Colour maps by meaning. Distances and other non-negative quantities: viridis, a sequential
# map whose lightness grows uniformly from the minimum (dark blue) to the maximum (yellow):
# equal steps of value look like equal steps of colour, and it reads in grey and for
# colour-blind readers (a rainbow puts false edges at cyan and yellow). Signed quantities (eigen-
# functions, biharmonic kernels, differences): a diverging map, blue - white - red, centred
# at 0. The hue circle is kept for periodic data (angles, phases) only: its two ends are the
# same colour, so on anything else the minimum and the maximum look alike.
DIVERGING_COLORS = ["#2040b0", "#5b8fd6", "#c4d8ef", "#f7f7f7", "#f4c6a8", "#d6604d", "#a01020"]
CYCLIC_COLORS = ["#ff0000", "#ffff00", "#00ff00", "#00ffff", "#0000ff", "#ff00ff", "#ff0000"]
#: colour of the parts a source does not reach (other components): outside every scale
NEUTRAL_COLOR = "#a8a8a8"
#: colour kinds: how the values are read, hence the map and the range
KINDS = ("auto", "distance", "sequential", "diverging", "cyclic")
CRITICAL_COLORS = {"minimum": "#1f3cff", "maximum": "#ff2020", "saddle": "#20c020"}


def headless() -> bool:
    """True when no display server is reachable (see :func:`spectral_igl.viz.display_available`)."""
    return not display_available()


def display_available() -> bool:
    r"""Whether an on-screen window can be opened.

    Linux: ``WAYLAND_DISPLAY`` is trusted; ``DISPLAY`` is tried (``XOpenDisplay`` through
    libX11 when the library is present), so that a stale or unreachable ``DISPLAY`` counts
    as no display. Other systems: True.

    Returns
    -------
    bool
        Without a display, pictures are rendered off screen (to files or a notebook).

    Examples
    --------
    >>> from spectral_igl import viz
    >>> isinstance(viz.display_available(), bool)
    True
    """
    if not sys.platform.startswith("linux"):
        return True
    if os.environ.get("WAYLAND_DISPLAY"):
        return True
    return _x_display_opens(os.environ.get("DISPLAY") or "")


@functools.lru_cache(maxsize=8)
def _x_display_opens(name: str) -> bool:
    if not name:
        return False
    import ctypes
    import ctypes.util

    try:
        x11 = ctypes.CDLL(ctypes.util.find_library("X11") or "libX11.so.6")
    except OSError:  # cannot check without libX11: trust the variable
        return True
    x11.XOpenDisplay.restype = ctypes.c_void_p
    x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
    handle = x11.XOpenDisplay(name.encode())
    if not handle:
        return False
    x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
    x11.XCloseDisplay(handle)
    return True


def pyvista():
    """Import pyvista, choosing an off-screen OpenGL context on a headless Linux machine.

    VTK >= 9.4 wheels carry an EGL render window that needs only the system's libEGL
    (Mesa software rendering works; no X server, no GPU). On a machine with no display we
    select it before VTK creates its first window, which also silences VTK's attempt to
    reach an X server. An explicit ``VTK_DEFAULT_OPENGL_WINDOW`` is respected.
    """
    if headless():
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    try:
        import pyvista as pv
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise ImportError(f"spectral_igl.viz needs pyvista for 3-D pictures: {INSTALL_HINT}") from err
    return pv


def pyplot():
    """Import matplotlib.pyplot with a non-interactive backend when there is no display."""
    try:
        import matplotlib
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise ImportError(f"spectral_igl.viz needs matplotlib for plots: {INSTALL_HINT}") from err
    if headless() and "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def colormap(name):
    r"""A matplotlib colormap by meaning or by name.

    ``"distance"`` / ``"sequential"``: viridis, perceptually uniform, dark blue (minimum)
    to yellow (maximum), for non-negative quantities; ``"diverging"``: blue - white - red, for signed quantities (drawn with a
    range centred at 0); ``"cyclic"``: the hue circle, for periodic data only; any other
    string is a matplotlib colormap name; a ``Colormap`` is returned as is.

    Parameters
    ----------
    name : str or matplotlib.colors.Colormap
        ``"distance"``, ``"sequential"``, ``"diverging"``, ``"cyclic"``, a matplotlib name, or
        a Colormap.

    Returns
    -------
    matplotlib.colors.Colormap

    Examples
    --------
    >>> from spectral_igl import viz
    >>> viz.colormap("distance").name, viz.colormap("magma").name
    ('viridis', 'magma')
    """
    pyplot()
    from matplotlib.colors import Colormap, LinearSegmentedColormap

    if isinstance(name, Colormap):
        return name
    if not isinstance(name, str):
        raise TypeError(f"colormap must be a name or a matplotlib Colormap, got {type(name).__name__}")
    import matplotlib

    if name in ("distance", "sequential"):
        return matplotlib.colormaps["viridis"]
    if name == "diverging":
        return LinearSegmentedColormap.from_list("spectral_igl_diverging", DIVERGING_COLORS, N=256)
    if name == "cyclic":
        return LinearSegmentedColormap.from_list("spectral_igl_cyclic", CYCLIC_COLORS, N=256)
    try:
        return matplotlib.colormaps[name]
    except KeyError as err:
        raise ValueError(f"unknown colormap {name!r}; use 'distance', 'sequential', 'diverging', "
                         "'cyclic' or a matplotlib name") from err


def color_kind(values, kind="auto", rtol=1e-6):
    r"""How to read ``values``: ``"sequential"`` or ``"diverging"`` (or ``"cyclic"`` if asked).

    ``"auto"``: diverging when the values take both signs beyond ``rtol`` times their
    largest magnitude (rounding-level negative values of a non-negative kernel do not
    count), sequential otherwise. ``"distance"`` is sequential. A matplotlib name is read
    as sequential.

    Parameters
    ----------
    values : array_like
        The values to draw.
    kind : str
        ``"auto"`` (default), ``"sequential"``, ``"diverging"``, ``"cyclic"``, ``"distance"`` or a
        matplotlib colormap name.
    rtol : float
        Negative values down to ``-rtol`` times the largest magnitude count as zero.

    Returns
    -------
    {"sequential", "diverging", "cyclic"}

    Examples
    --------
    >>> from spectral_igl.viz import color_kind
    >>> color_kind([0.0, 1.0, 2.0]), color_kind([-1.0, 2.0]), color_kind([-1e-12, 1.0])
    ('sequential', 'diverging', 'sequential')
    """
    if kind in ("diverging", "cyclic"):
        return kind
    if kind != "auto":
        return "sequential"
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return "sequential"
    big = float(np.max(np.abs(v)))
    return "diverging" if (v.min() < -rtol * big and v.max() > rtol * big) else "sequential"


def to_pyvista(shape):
    r"""Convert a shape to a pyvista dataset.

    Parameters
    ----------
    shape : tuple, array, Laplacian or pyvista.DataSet
        ``(V, F)`` with ``F : (m, 3) int`` (triangle mesh), ``(V, T)`` with ``T : (m, 4)
        int`` (tetrahedral mesh), ``V : (n, 3) float`` alone (point set), a
        :class:`~spectral_igl.Laplacian` (its ``data``), or a pyvista dataset.

    Returns
    -------
    mesh : pyvista.PolyData or pyvista.UnstructuredGrid
    kind : {"triangle", "tet", "points"}

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl import viz
    >>> from spectral_igl.data_generators import icosphere
    >>> mesh, kind = viz.to_pyvista(icosphere(1))
    >>> mesh.n_points, mesh.n_cells, kind
    (42, 80, 'triangle')
    >>> viz.to_pyvista(sig.laplacian(*icosphere(1)))[1]
    'triangle'
    """
    pv = pyvista()

    if isinstance(shape, pv.DataSet):
        if isinstance(shape, pv.UnstructuredGrid):
            return shape, "tet"
        if isinstance(shape, pv.PolyData) and shape.n_cells and shape.n_verts != shape.n_cells:
            return shape, "triangle"
        return shape, "points"
    data = getattr(shape, "data", None)
    if isinstance(data, dict) and hasattr(shape, "L"):  # a Laplacian
        if "V" in data and ("F" in data or "T" in data):
            shape = (data["V"], data["T"] if "T" in data else data["F"])
        elif "V" in data or "P" in data:
            shape = data.get("V", data.get("P"))
        else:
            raise ValueError(f"this Laplacian (domain {shape.domain!r}) carries no geometry to draw")
    if isinstance(shape, (tuple, list)) and len(shape) == 2 and np.ndim(shape[0]) == 2 and np.ndim(shape[1]) == 2:
        V = as_points(shape[0], "V", dims=(2, 3))
        if V.shape[1] == 2:
            V = np.column_stack([V, np.zeros(len(V))])
        C = as_cells(shape[1], len(V), "cells", sizes=(3, 4))
        cells = np.column_stack([np.full(len(C), C.shape[1]), C]).ravel()
        if C.shape[1] == 3:
            return pv.PolyData(V, cells), "triangle"
        return pv.UnstructuredGrid(cells, np.full(len(C), pv.CellType.TETRA, dtype=np.uint8), V), "tet"
    if isinstance(shape, np.ndarray) or isinstance(shape, (list, tuple)):
        P = as_points(shape, "points", dims=(2, 3))
        if P.shape[1] == 2:
            P = np.column_stack([P, np.zeros(len(P))])
        return pv.PolyData(P), "points"
    raise TypeError(f"cannot draw {describe(shape)}; expected (V, F), (V, T), points, a Laplacian "
                    "or a pyvista dataset")


def save_png(image, path, max_colors: int | None = None, optimize: bool = False):
    r"""Write an RGB image array to ``path`` as a PNG.

    With ``max_colors`` the image is quantised to an adaptive palette (smaller files,
    at the price of some banding in smooth gradients). ``optimize`` spends several times
    longer on the compression for files about 10% smaller.

    Parameters
    ----------
    image : (h, w, 3) uint8
        RGB pixels (a pyvista screenshot).
    path : str or os.PathLike
    max_colors : int, optional
        Size of the adaptive palette (default: full colour).
    optimize : bool
        Slower, smaller compression.

    Returns
    -------
    path
        ``path`` as given.

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> from PIL import Image
    >>> from spectral_igl import viz
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "ramp.png"
    >>> ramp = np.repeat(np.linspace(0, 255, 64, dtype=np.uint8)[None, :, None], 8, axis=0).repeat(3, 2)
    >>> viz.save_png(ramp, path, max_colors=16) == path
    True
    >>> Image.open(path).size, len(Image.open(path).convert("RGB").getcolors())
    ((64, 8), 16)
    """
    from PIL import Image

    img = Image.fromarray(np.asarray(image, dtype=np.uint8))
    if max_colors:
        img = img.convert("RGB").quantize(colors=max_colors, method=Image.Quantize.MEDIANCUT)
    img.save(str(path), optimize=bool(optimize))
    return path


def notebook_picture(plotter, image=None):
    """Make ``plotter`` show as a picture when it ends a notebook cell, and return it.

    IPython shows an object through its ``_ipython_display_``. A plotter still open is shown
    by ``plotter.show()``, through pyvista's Jupyter backend (``pyvista.set_jupyter_backend``:
    ``"static"`` a PNG, ``"trame"`` or ``"html"`` an interactive view; ``"static"`` when none
    is set). A plotter already closed (a picture written with ``filename=``) shows ``image``,
    the picture it rendered, which becomes its ``last_image`` (pyvista's ``_repr_png_``).
    Nothing else about the plotter changes: scripts use it as before.

    Parameters
    ----------
    plotter : pyvista.Plotter
        The plotter to return.
    image : (h, w, 3) uint8 array, optional
        The picture a closed plotter rendered.

    Returns
    -------
    pyvista.Plotter
        ``plotter``.
    """
    if image is not None:
        plotter.last_image = np.asarray(image)

    def _ipython_display_():
        if plotter.render_window is not None:          # open: pyvista's notebook backend
            backend = plotter.theme.jupyter_backend or "static"
            plotter.show(jupyter_backend=backend)
            return
        from IPython.display import Image, display     # closed: the picture it rendered

        png = plotter._repr_png_()
        if png is not None:
            display(Image(data=png, format="png"))
        else:
            display({"text/plain": repr(plotter)}, raw=True)

    plotter._ipython_display_ = _ipython_display_
    return plotter
