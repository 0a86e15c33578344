"""Interactive viewer: click a vertex, see the level sets of a kernel or distance from it."""
from __future__ import annotations

import numpy as np

from .._validate import as_index, describe
from ..approx import METHODS
from ..filters import FILTERS
from ..laplacian import Laplacian, laplacian, shape_time
from ..quantity import FILTERED, QUANTITIES, color_meaning, evaluate, uses_time
from ._backend import NEUTRAL_COLOR, color_kind, colormap, display_available, pyvista, save_png, to_pyvista
from ._levelsets import add_source_marker, levelset_values, lines_over_surfaces, outer_surface, reached_vertices
from ._scale import apply_ticks, use_log_scale

__all__ = ["Viewer"]

#: a press and release closer than this (pixels) is a click (a pick), farther a drag (a rotation)
CLICK_PIXELS = 4


class Viewer:
    r"""Interactive level sets of kernels and distances from a picked vertex.

    Click a vertex (a left click without dragging, or key ``p`` under the mouse) to
    evaluate the chosen kernel column :math:`\varphi(\tilde L)B^{-1}e_i`, spectral
    distance :math:`d(i,\cdot)` or geodesic distance from it; a slider sets
    :math:`\log_{10} t` (shown only for filters that have a time); keys ``f``, ``m`` and
    ``k`` cycle the filter, the method and kernel / distance / geodesic (``f`` and ``m``
    only where they apply: the geodesic distance has neither); ``c`` turns the camera to
    the source. The certified error bound and the time of the last evaluation are shown.

    Every interaction is a plain method (:meth:`on_pick`, :meth:`pick_at`,
    :meth:`on_time`, :meth:`set_filter`, :meth:`set_method`, :meth:`set_quantity`), so the
    viewer can be driven from a script or a test with an off-screen plotter.

    Parameters
    ----------
    shape : tuple, Laplacian
        ``(V, F)`` triangle mesh, ``(V, T)`` tetrahedral mesh (its boundary is shown),
        or a :class:`~spectral_igl.Laplacian` built from one.
    quantity : {"kernel", "distance", "geodesic"}
    filter : str
        One of :data:`spectral_igl.filters.FILTERS` (``"heat"``, ``"diffusion"``,
        ``"biharmonic"``, ...).
    t : float, optional
        Initial time, in the units ``time_unit``; default :math:`10^{-2}` times the shape's
        area (volume\ :sup:`2/3` of a solid), the same on a mesh of any size.
    time_unit : str
        Unit of ``t`` (:mod:`spectral_igl.laplacian.units`): ``"absolute"`` (default),
        ``"shape"``, ``"area"``, ``"volume"`` or ``"h2"``. The slider and ``self.t`` are absolute.
    method : str
        Engine method, one of :data:`spectral_igl.approx.METHODS`.
    source : int
        Initial vertex.
    n_levels : int
        Number of iso-lines.
    off_screen : bool, optional
        Default: off screen when there is no display. ``False`` without a display raises
        ``RuntimeError`` at once, before any computation.
    camera : str or (3,) float
        Initial view (see :func:`spectral_igl.viz.plot_levelsets`); ``"auto"`` faces the
        source from outside the shape.
    cmap : str, optional
        Colour map instead of the one the values call for (sequential for distances and
        non-negative kernels, diverging for signed kernels).
    diagonal : {"auto", "selinv", "exact", "probing", "dense"}
        How distances obtain the kernel diagonal (see :func:`spectral_igl.spectral_distance`).

    Examples
    --------
    >>> from spectral_igl.data_generators import icosphere
    >>> viewer = Viewer(icosphere(3), filter="heat", quantity="kernel", off_screen=True)  # doctest: +SKIP
    >>> viewer.on_pick(10); viewer.on_time(0.05); viewer.screenshot("v.png")  # doctest: +SKIP
    """

    def __init__(self, shape, quantity="distance", filter="biharmonic", t=None, method="auto",
                 source=0, n_levels=12, tol=1e-8, off_screen=None, window_size=(900, 800),
                 weights="auto", diagonal="auto", camera="auto", cmap=None, time_unit="absolute"):
        if quantity not in QUANTITIES:
            raise ValueError(f"quantity must be one of {QUANTITIES}, got {quantity!r}")
        if filter not in FILTERS:
            raise ValueError(f"unknown filter {filter!r}; choose one of {', '.join(FILTERS)}")
        if off_screen is False and not display_available():
            raise RuntimeError("no display available for an interactive window: pass "
                               "off_screen=True and use screenshot()")
        pv = pyvista()
        from ._camera import parse_view

        lines_over_surfaces()
        parse_view(camera)
        if isinstance(shape, Laplacian):
            self.lap = shape
        else:
            if not (isinstance(shape, (tuple, list)) and len(shape) == 2):
                raise TypeError(f"shape must be (V, F), (V, T) or a Laplacian, got {describe(shape)}")
            self.lap = laplacian(shape[0], shape[1], weights=weights)
        grid, kind = to_pyvista(self.lap)
        if kind == "points":
            raise ValueError("the viewer draws triangle and tetrahedral meshes")
        self._grid = grid
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
        self.cmap = cmap
        self.n_levels = int(n_levels)
        self.t = shape_time(self.lap, 1e-2, "shape") if t is None else shape_time(self.lap, t, time_unit)
        self._t_range = (np.log10(self.t) - 3, np.log10(self.t) + 2)
        self.source = as_index(source, self.lap.n, "source")
        self.last = None
        self.evaluations = 0
        self.picks = 0
        if off_screen is None:
            off_screen = (not display_available()) or bool(pv.OFF_SCREEN)
        self.plotter = pv.Plotter(off_screen=off_screen, window_size=window_size)
        self.plotter.set_background("white")
        self.mesh.point_data["f"] = np.zeros(self.mesh.n_points)
        self.surface_actor = self.plotter.add_mesh(
            self.mesh, scalars="f", cmap=colormap("distance"), smooth_shading=True,
            nan_color=NEUTRAL_COLOR,
            scalar_bar_args=dict(title=" ", color="black", vertical=False, fmt="%.3g",
                                 position_x=0.25, position_y=0.02, width=0.5), pickable=True)
        self._kdtree = None
        self._press = None
        self.slider = None
        self._add_widgets()
        self.camera = camera
        self.update(refresh_marker=False)
        self.look_at_source(camera)

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

    def pick_at(self, x, y):
        """Pick the surface under the display pixel ``(x, y)`` (origin at the bottom left).

        What a click does: a ray from the camera through the pixel hits the surface (VTK's
        cell picker, restricted to the surface); the vertex nearest to the hit becomes the
        source. Returns the new ``Evaluation``, or ``None`` when the pixel shows no
        surface.
        """
        from vtkmodules.vtkRenderingCore import vtkCellPicker

        picker = vtkCellPicker()
        picker.SetTolerance(1e-4)
        picker.PickFromListOn()
        picker.AddPickList(self.surface_actor)
        if not picker.Pick(float(x), float(y), 0.0, self.plotter.renderer):
            return None
        if picker.GetCellId() < 0:
            return None
        self.picks += 1
        return self.on_pick_point(picker.GetPickPosition())

    def _event_position(self):
        # the observers sit on the interactor style; the position is the interactor's
        return tuple(self.plotter.iren.interactor.GetEventPosition())

    def _on_press(self, obj=None, event=None):
        self._press = self._event_position()

    def _on_release(self, obj=None, event=None):
        press, self._press = self._press, None
        pos = self._event_position()
        if press is not None and max(abs(pos[0] - press[0]), abs(pos[1] - press[1])) <= CLICK_PIXELS:
            self.pick_at(*pos)

    def _on_key_pick(self):
        x, y = self.plotter.iren.interactor.GetEventPosition()
        self.pick_at(x, y)

    def look_at_source(self, camera=None):
        """Turn the camera to the source (``camera="auto"``) or to the view ``camera``."""
        from ._camera import fit_view, place_camera

        target = self.points[self.source]
        if self._ids.size != self.points.shape[0]:  # a volume: the nearest boundary point
            Q = self.points[self._ids]
            target = Q[np.argmin(np.linalg.norm(Q - target, axis=1))]
        view = place_camera(self.plotter, self.mesh, self.camera if camera is None else camera, target)
        if view.get("points") is not None:
            fit_view(self.plotter, view["points"], height=0.7, width=0.9, lift=0.03)
        self._draw_marker()
        self.plotter.render()
        return view

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
        self._sync_slider()
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
        """``"kernel"``, ``"distance"`` or ``"geodesic"``; redraw."""
        if name not in QUANTITIES:
            raise ValueError(f"quantity must be one of {QUANTITIES}, got {name!r}")
        self.quantity = name
        self._sync_slider()
        return self.update()

    # ---- drawing --------------------------------------------------------------------
    def update(self, refresh_marker=True):
        """Recompute the scalar for the current settings and refresh actors and text.

        Parts of the shape the source does not reach (other connected components) are drawn
        in a neutral grey and kept out of the colour scale; sequential colours (viridis) for
        distances and non-negative kernels, on a logarithmic scale when the values are
        positive and span more than two decades (:func:`spectral_igl.viz.plot_levelsets`),
        diverging colours centred at 0 for signed kernels.
        """
        ev = evaluate(self.lap, self.quantity, self.source, self.filter, self.t,
                      method=self.method, tol=self.tol, diagonal=self.diagonal)
        self.last = ev
        self.evaluations += 1
        reach = reached_vertices(self._grid, [self.source]) & np.isfinite(ev.values)
        ok = reach[self._ids]
        f = np.where(ok, ev.values[self._ids], np.nan)
        self.mesh.point_data["f"] = f
        fin = f[ok]
        self.color_kind = color_kind(fin, color_meaning(self.quantity, self.filter))
        self.log = use_log_scale(fin, "auto", self.color_kind)  # a kernel spanning decades
        lo, hi = (float(fin.min()), float(fin.max())) if fin.size else (0.0, 1.0)
        if self.color_kind == "diverging":
            lo, hi = -max(abs(lo), abs(hi)), max(abs(lo), abs(hi))
        if hi <= lo:
            hi = lo + 1.0
        self.clim = (lo, hi)
        mapper = self.surface_actor.mapper
        mapper.lookup_table.cmap = colormap(self.cmap or ("distance" if self.color_kind == "sequential"
                                                          else self.color_kind))
        mapper.lookup_table.nan_color = NEUTRAL_COLOR
        mapper.lookup_table.log_scale = self.log
        mapper.scalar_range = self.clim
        bar = self.plotter.scalar_bars[" "] if " " in self.plotter.scalar_bars else None
        self.ticks = apply_ticks(bar, lo, hi, self.log)[1]
        self.isovalues = levelset_values(lo, hi, self.n_levels, log=self.log)
        self.plotter.remove_actor("isolines")
        lines = None
        if self.isovalues.size:
            part = self.mesh if ok.all() else self.mesh.extract_points(np.flatnonzero(ok),
                                                                        adjacent_cells=False)
            if part.n_points:
                lines = part.contour(isosurfaces=self.isovalues, scalars="f")
        if lines is not None and lines.n_points:
            self.plotter.add_mesh(lines, color="black", line_width=2, name="isolines",
                                  show_scalar_bar=False, pickable=False, reset_camera=False)
        if refresh_marker:
            self._draw_marker()
        self.plotter.add_text(self.status(), position="upper_left", font_size=10, color="black",
                              name="status")
        self.plotter.render()
        return ev

    def _draw_marker(self):
        for name in ("source_rim", "source"):
            self.plotter.remove_actor(name)
        add_source_marker(self.plotter, self.points[self.source][None, :], "black",
                          names=("source_rim", "source"))

    def status(self) -> str:
        """The text overlay: what is shown, the certified error bound, the time taken."""
        ev = self.last
        bound = "n/a" if ev.error_bound is None else f"{ev.error_bound:.2e}"
        keys = "click / p: pick   k: kernel/distance/geodesic   c: camera to source"
        if self.quantity in FILTERED:
            keys += "\nf: filter   m: method"
        method = f"method: {self.method}   " if self.quantity in FILTERED else ""
        scale = "   log colour scale" if getattr(self, "log", False) else ""
        return (f"{ev.label} from vertex {self.source}{scale}\n{method}"
                f"error bound: {bound}   time: {1e3 * ev.seconds:.1f} ms\n{keys}")

    def _sync_slider(self):
        """Show the t slider exactly when the quantity and filter have a time."""
        want = uses_time(self.quantity, self.filter)
        if want and self.slider is None:
            self.slider = self.plotter.add_slider_widget(
                self._on_slider, rng=self._t_range, value=float(np.log10(self.t)), title="log10 t",
                fmt="%.2f", pointa=(0.6, 0.92), pointb=(0.95, 0.92), color="black")
        elif not want and self.slider is not None:
            self.plotter.clear_slider_widgets()  # the t slider is the only one
            self.slider = None

    def _add_widgets(self):
        p = self.plotter
        iren = p.iren
        if iren is not None:
            iren.add_observer("LeftButtonPressEvent", self._on_press)
            iren.add_observer("LeftButtonReleaseEvent", self._on_release)
        self._sync_slider()
        p.add_key_event("p", self._on_key_pick)
        p.add_key_event("c", lambda: self.look_at_source())
        p.add_key_event("f", lambda: self.set_filter(_next(list(FILTERS), self.filter))
                        if self.quantity in FILTERED else None)
        p.add_key_event("m", lambda: self.set_method(_next(list(METHODS), self.method))
                        if self.quantity in FILTERED else None)
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
