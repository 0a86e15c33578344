"""Interactive viewer: click a vertex, see the level sets of a kernel or distance from it."""
from __future__ import annotations

import numpy as np

from .._validate import as_index
from ..approx import METHODS
from ..filters import FILTERS
from ..laplacian import Laplacian, laplacian
from ..quantity import QUANTITIES, evaluate
from ._backend import colormap, headless, pyvista, save_png, to_pyvista
from ._levelsets import levelset_values, lines_over_surfaces, look_at, outer_surface

__all__ = ["Viewer"]


class Viewer:
    r"""Interactive level sets of kernels and distances from a picked vertex.

    Click a vertex (key ``p`` over the surface, or a left click with the picking
    enabled) to evaluate the chosen kernel column :math:`\varphi(\tilde L)B^{-1}e_i` or
    spectral distance :math:`d(i,\cdot)` from it; a slider sets :math:`\log_{10} t`; keys
    ``f``, ``m`` and ``k`` cycle the filter, the method and kernel/distance. The
    certified error bound and the time of the last evaluation are shown on screen.

    Every interaction is a plain method (:meth:`on_pick`, :meth:`on_time`,
    :meth:`set_filter`, :meth:`set_method`, :meth:`set_quantity`), so the viewer can be
    driven from a script or a test with an off-screen plotter.

    Parameters
    ----------
    shape : tuple, Laplacian
        ``(V, F)`` triangle mesh, ``(V, T)`` tetrahedral mesh (its boundary is shown),
        or a :class:`~spectral_igl.Laplacian` built from one.
    quantity : {"kernel", "distance"}
    filter : str
        One of :data:`spectral_igl.filters.FILTERS` (``"heat"``, ``"diffusion"``,
        ``"biharmonic"``, ...).
    t : float, optional
        Initial time; default :math:`10^{-2}` times the squared bounding-box diagonal.
    method : str
        Engine method, one of :data:`spectral_igl.approx.METHODS`.
    source : int
        Initial vertex.
    n_levels : int
        Number of iso-lines.
    off_screen : bool, optional
        Default: off screen when there is no display.
    diagonal : {"auto", "selinv", "exact", "probing", "dense"}
        How distances obtain the kernel diagonal (see :func:`spectral_igl.spectral_distance`).

    Examples
    --------
    >>> from data_generators import icosphere
    >>> viewer = Viewer(icosphere(3), filter="heat", quantity="kernel", off_screen=True)  # doctest: +SKIP
    >>> viewer.on_pick(10); viewer.on_time(0.05); viewer.screenshot("v.png")  # doctest: +SKIP
    """

    def __init__(self, shape, quantity="distance", filter="biharmonic", t=None, method="auto",
                 source=0, n_levels=12, tol=1e-8, off_screen=None, window_size=(900, 800),
                 weights="cotan", diagonal="auto"):
        pv = pyvista()
        lines_over_surfaces()

        if quantity not in QUANTITIES:
            raise ValueError(f"quantity must be one of {QUANTITIES}, got {quantity!r}")
        if filter not in FILTERS:
            raise ValueError(f"unknown filter {filter!r}; choose one of {', '.join(FILTERS)}")
        if isinstance(shape, Laplacian):
            self.lap = shape
        else:
            if not (isinstance(shape, (tuple, list)) and len(shape) == 2):
                raise TypeError("shape must be (V, F), (V, T) or a Laplacian")
            self.lap = laplacian(shape[0], shape[1], weights=weights)
        grid, kind = to_pyvista(self.lap)
        if kind == "points":
            raise ValueError("the viewer draws triangle and tetrahedral meshes")
        if kind == "tet":

            surface = outer_surface(grid)
            self._ids = np.asarray(surface.point_data["vtkOriginalPointIds"], dtype=np.int64)
        else:
            surface = grid
            self._ids = np.arange(grid.n_points)
        self.mesh = surface.copy()
        self.points = np.asarray(grid.points)
        self.quantity = quantity
        self.filter = filter
        self.method = method
        self.tol = float(tol)
        self.diagonal = diagonal
        self.n_levels = int(n_levels)
        diag2 = float(np.sum((self.points.max(0) - self.points.min(0)) ** 2))
        self.t = float(t) if t is not None else 1e-2 * diag2
        self._t_range = (np.log10(self.t) - 3, np.log10(self.t) + 2)
        self.source = int(source)
        self.last = None
        self.evaluations = 0
        if off_screen is None:
            off_screen = headless() or bool(pv.OFF_SCREEN)
        self.plotter = pv.Plotter(off_screen=off_screen, window_size=window_size)
        self.plotter.set_background("white")
        self.mesh.point_data["f"] = np.zeros(self.mesh.n_points)
        self.surface_actor = self.plotter.add_mesh(
            self.mesh, scalars="f", cmap=colormap(self._kind()), smooth_shading=True,
            scalar_bar_args=dict(title=" ", color="black", vertical=False, fmt="%.3g",
                                 position_x=0.25, position_y=0.02, width=0.5), pickable=True)
        self._kdtree = None
        self._add_widgets()
        self.update()

        look_at(self.plotter, grid, self.source)
        self.plotter.reset_camera()

    # ---- interactions -------------------------------------------------------------
    def on_pick(self, vertex):
        """Evaluate from ``vertex`` (an index into the mesh vertices) and redraw."""

        self.source = as_index(vertex, self.lap.n, "vertex")
        return self.update()

    def on_pick_point(self, point):
        """Picking callback: the vertex nearest to the 3-D ``point`` becomes the source."""
        if point is None:
            return None
        if self._kdtree is None:
            from scipy.spatial import cKDTree

            self._kdtree = cKDTree(self.points[self._ids])
        _, j = self._kdtree.query(np.asarray(point, dtype=float).ravel()[:3])
        return self.on_pick(int(self._ids[j]))

    def on_time(self, t):
        """Set the time/scale ``t`` (> 0) and redraw."""
        t = float(t)
        if not np.isfinite(t) or t <= 0:
            raise ValueError(f"t must be a positive number, got {t!r}")
        self.t = t
        if self.slider is None:
            return self.update()
        rep = self.slider.GetRepresentation()
        lo, hi = rep.GetMinimumValue(), rep.GetMaximumValue()
        logt = float(np.log10(t))
        if not lo <= logt <= hi:  # widen the slider to show the value
            rep.SetMinimumValue(min(lo, logt))
            rep.SetMaximumValue(max(hi, logt))
        rep.SetValue(logt)
        return self.update()

    def _on_slider(self, value):
        if self.slider is not None and abs(10.0 ** value - self.t) > 1e-12 * self.t:
            self.on_time(10.0 ** value)

    def set_filter(self, name):
        """Choose the filter by name (see :data:`FILTERS`) and redraw."""
        if name not in FILTERS:
            raise ValueError(f"unknown filter {name!r}; choose one of {', '.join(FILTERS)}")
        self.filter = name
        return self.update()

    def set_method(self, name):
        """Choose the engine method (``"auto"``, ``"rational"``, ...) and redraw."""
        if not isinstance(name, str):
            raise TypeError(f"method must be a string, got {type(name).__name__}")
        previous, self.method = self.method, name
        try:
            return self.update()
        except Exception:
            self.method = previous
            raise

    def set_quantity(self, name):
        """``"kernel"`` or ``"distance"``; redraw."""
        if name not in QUANTITIES:
            raise ValueError(f"quantity must be one of {QUANTITIES}, got {name!r}")
        self.quantity = name
        return self.update()

    # ---- drawing --------------------------------------------------------------------
    def _kind(self):
        return "distance" if self.quantity == "distance" else "cyclic"

    def update(self):
        """Recompute the scalar for the current settings and refresh actors and text."""
        ev = evaluate(self.lap, self.quantity, self.source, self.filter, self.t,
                      method=self.method, tol=self.tol, diagonal=self.diagonal)
        self.last = ev
        self.evaluations += 1
        f = ev.values[self._ids]
        self.mesh.point_data["f"] = f
        fin = f[np.isfinite(f)]
        lo, hi = (float(fin.min()), float(fin.max())) if fin.size else (0.0, 1.0)
        if hi <= lo:
            hi = lo + 1.0
        self.clim = (lo, hi)
        mapper = self.surface_actor.mapper
        mapper.lookup_table.cmap = colormap(self._kind())
        mapper.scalar_range = self.clim
        self.isovalues = levelset_values(lo, hi, self.n_levels)
        self.plotter.remove_actor("isolines")
        lines = self.mesh.contour(isosurfaces=self.isovalues, scalars="f") if self.isovalues.size else None
        if lines is not None and lines.n_points:
            self.plotter.add_mesh(lines, color="black", line_width=2, name="isolines",
                                  show_scalar_bar=False, pickable=False, reset_camera=False)
        self.plotter.add_points(self.points[self.source][None, :], color="black", point_size=16,
                                render_points_as_spheres=True, name="source", pickable=False,
                                reset_camera=False)
        self.plotter.add_text(self.status(), position="upper_left", font_size=10, color="black",
                              name="status")
        self.plotter.render()
        return ev

    def status(self) -> str:
        """The text overlay: what is shown, the certified error bound, the time taken."""
        ev = self.last
        bound = "n/a" if ev.error_bound is None else f"{ev.error_bound:.2e}"
        return (f"{ev.label} from vertex {self.source}\nmethod: {self.method}   "
                f"error bound: {bound}   time: {1e3 * ev.seconds:.1f} ms\n"
                "p: pick   f: filter   m: method   k: kernel/distance")

    def _add_widgets(self):
        p = self.plotter
        try:
            p.enable_point_picking(callback=self.on_pick_point, show_message=False,
                                   show_point=False, use_picker=False, left_clicking=False)
        except TypeError:  # older pyvista
            p.enable_point_picking(callback=self.on_pick_point, show_message=False)
        self.slider = None
        self.slider = p.add_slider_widget(self._on_slider, rng=self._t_range,
                            value=float(np.log10(self.t)), title="log10 t", fmt="%.2f",
                            pointa=(0.6, 0.92), pointb=(0.95, 0.92), color="black")
        p.add_key_event("f", lambda: self.set_filter(_next(list(FILTERS), self.filter)))
        p.add_key_event("m", lambda: self.set_method(_next(list(METHODS), self.method)))
        p.add_key_event("k", lambda: self.set_quantity(_next(list(QUANTITIES), self.quantity)))

    def show(self, **kwargs):
        """Open the window (on screen) and run its event loop."""
        return self.plotter.show(**kwargs)

    def screenshot(self, filename=None):
        """Render and return the image (H, W, 3); write a PNG when ``filename`` is given."""
        image = self.plotter.screenshot(return_img=True)
        if filename is not None:
            save_png(image, filename)
        return image

    def close(self):
        self.plotter.close()


def _next(items, current):
    i = items.index(current) if current in items else -1
    return items[(i + 1) % len(items)]
