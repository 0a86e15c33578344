"""Level-set pictures of scalar functions on surfaces, volumes and point sets."""
from __future__ import annotations

import numpy as np

from ._backend import CRITICAL_COLORS, colormap, headless, pyvista, save_png, to_pyvista

__all__ = ["plot_levelsets", "levelset_values"]

_KINDS = ("distance", "cyclic")
_VOLUME = ("boundary", "clip", "slices", "isosurfaces")


def levelset_values(vmin: float, vmax: float, n_levels: int) -> np.ndarray:
    """``n_levels`` iso-values uniformly sampled inside ``(vmin, vmax)`` (end points excluded).

    Examples
    --------
    >>> levelset_values(0.0, 1.0, 3)
    array([0.25, 0.5 , 0.75])
    """
    if n_levels < 0:
        raise ValueError(f"n_levels must be >= 0, got {n_levels}")
    if not np.isfinite(vmin) or not np.isfinite(vmax) or vmax <= vmin:
        return np.empty(0)
    return np.linspace(vmin, vmax, n_levels + 2)[1:-1]


def _critical_sets(critical):
    """Normalise critical points to {kind: indices}."""
    if critical is None:
        return {}
    if isinstance(critical, dict):
        items = critical.items()
    else:
        items = [(k, getattr(critical, k)) for k in ("minima", "maxima", "saddles") if hasattr(critical, k)]
        if not items:
            raise TypeError("critical must be a dict {'minimum'|'maximum'|'saddle': indices} or have "
                            "attributes minima/maxima/saddles")
    out = {}
    alias = {"min": "minimum", "minima": "minimum", "m": "minimum", "minimum": "minimum",
             "max": "maximum", "maxima": "maximum", "M": "maximum", "maximum": "maximum",
             "saddle": "saddle", "saddles": "saddle", "s": "saddle"}
    for key, idx in items:
        if key not in alias:
            raise ValueError(f"unknown critical point kind {key!r}; use minimum, maximum or saddle")
        idx = np.asarray(idx, dtype=np.int64)
        if idx.ndim == 2:  # (index, multiplicity) rows, as for saddles
            idx = idx[:, 0]
        out[alias[key]] = idx.ravel()
    return out


def plot_levelsets(shape, f, *, kind="distance", n_levels=12, clim=None, shared_scale=True,
                   sources=None, critical=None, volume="clip", title=None, labels=None,
                   plotter=None, filename=None, off_screen=None, window_size=None,
                   camera_position=None, zoom=None, source_color="black", scalar_bar=True, line_width=2.0,
                   point_size=None, show_edges=False, background="white"):
    r"""Draw a scalar function on a shape with iso-lines at uniformly sampled values.

    Parameters
    ----------
    shape : tuple, array, Laplacian, pyvista.DataSet, or a list of them
        ``(V, F)`` triangle mesh (``V : (n, 3) float``, ``F : (m, 3) int``), ``(V, T)``
        tetrahedral mesh (``T : (m, 4) int``), ``P : (n, 3) float`` point set (drawn as
        spheres), a :class:`~spectral_igl.Laplacian`, or a pyvista dataset. A list draws
        several shapes side by side.
    f : (n,) float, or a list of them (one per shape)
        Values at the vertices/points.
    kind : {"distance", "cyclic"} or a matplotlib colormap name
        ``"distance"``: blue at the minimum to red at the maximum. ``"cyclic"``: the
        survey's hue circle red -> yellow -> green -> cyan -> blue -> magenta -> red, for
        kernels, eigenfunctions and other functions.
    n_levels : int
        Number of iso-values, uniformly sampled in the open colour range.
    clim : (2,) float, optional
        Colour range; default the range of ``f`` (of all ``f`` when ``shared_scale``).
    shared_scale : bool
        With several shapes, use one colour scale and one set of iso-values for all.
    sources : int or sequence of int, optional
        Vertices drawn as dots (source points of distances and kernels).
    critical : dict or object, optional
        Critical points ``{"minimum": idx, "maximum": idx, "saddle": idx}`` (or an object
        with attributes ``minima``, ``maxima``, ``saddles``), marked blue, red and green.
    volume : {"clip", "slices", "boundary", "isosurfaces"}
        How a tetrahedral mesh is shown: boundary cut away by a plane, boundary plus three
        orthogonal slices, boundary only, or iso-surfaces inside a translucent boundary.
        Iso-values of volumes are sampled in the range on the boundary (as in the survey).
    title : str, optional
        Text at the top (of each panel when ``labels`` is given).
    labels : list of str, optional
        One caption per shape.
    plotter : pyvista.Plotter, optional
        Draw into this plotter (single shape) instead of creating one.
    filename : str or path, optional
        Write a PNG there; the plotter is then closed.
    off_screen : bool, optional
        Default: off screen when no display is available or ``filename`` is given.
    window_size : (2,) int, optional
        Pixels; default 600 x 600 per panel.
    camera_position : str or list, optional
        A pyvista camera position (``"iso"``, ``"xy"``, ...). Default: facing the first
        source when ``sources`` is given, else ``"iso"``.
    zoom : float, optional
        Camera zoom after fitting the shape; default 1.2 for surfaces and point sets,
        1.0 for volumes (whose bounding box fills the picture).
    source_color : str
        Colour of the source dots.

    Returns
    -------
    pyvista.Plotter
        The plotter (closed when ``filename`` was given; its last image is in
        ``plotter.last_image``).

    Examples
    --------
    >>> from data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> p = plot_levelsets((V, F), V[:, 2], kind="cyclic", filename="z.png")  # doctest: +SKIP
    """
    pv = pyvista()
    lines_over_surfaces()
    shapes = shape if isinstance(shape, list) else [shape]
    fs = f if isinstance(f, list) else [f]
    if len(shapes) != len(fs):
        raise ValueError(f"got {len(shapes)} shape(s) but {len(fs)} function(s)")
    if labels is not None and len(labels) != len(shapes):
        raise ValueError(f"got {len(labels)} label(s) for {len(shapes)} shape(s)")
    if kind not in _KINDS and not isinstance(kind, str):
        raise TypeError(f"kind must be a string, got {type(kind).__name__}")
    if volume not in _VOLUME:
        raise ValueError(f"volume must be one of {_VOLUME}, got {volume!r}")
    n_levels = int(n_levels)
    cmap = colormap(kind)
    if plotter is not None and len(shapes) > 1:
        raise ValueError("pass plotter only with a single shape")

    meshes, values = [], []
    for s, fi in zip(shapes, fs):
        mesh, mkind = to_pyvista(s)
        fi = np.asarray(fi)
        if np.iscomplexobj(fi):
            raise TypeError("f must be real; draw f.real and f.imag separately")
        fi = fi.astype(float).ravel()
        if fi.shape[0] != mesh.n_points:
            raise ValueError(f"f has {fi.shape[0]} values but the shape has {mesh.n_points} vertices")
        meshes.append((mesh, mkind))
        values.append(fi)

    def _range(mesh, mkind, fi):
        if mkind == "tet":  # range on the boundary, as in the survey's Fig. 8
            surf = outer_surface(mesh)
            ids = surf.point_data.get("vtkOriginalPointIds")
            fi = fi[np.asarray(ids)] if ids is not None else fi
        fin = fi[np.isfinite(fi)]
        return (float(fin.min()), float(fin.max())) if fin.size else (0.0, 1.0)

    ranges = [_range(m, k, fi) for (m, k), fi in zip(meshes, values)]
    if clim is not None:
        clim = (float(clim[0]), float(clim[1]))
        ranges = [clim] * len(meshes)
    elif shared_scale and len(meshes) > 1:
        shared = (min(r[0] for r in ranges), max(r[1] for r in ranges))
        ranges = [shared] * len(meshes)

    if off_screen is None:
        off_screen = bool(filename is not None or headless() or pv.OFF_SCREEN)
    ncol = len(meshes)
    if plotter is None:
        size = tuple(window_size) if window_size is not None else (600 * ncol, 600)
        plotter = pv.Plotter(shape=(1, ncol), off_screen=off_screen, window_size=size,
                             border=False)
    plotter.set_background(background)

    for j, ((mesh, mkind), fi, rng) in enumerate(zip(meshes, values, ranges)):
        if ncol > 1:
            plotter.subplot(0, j)
        lo, hi = rng
        if hi <= lo:
            hi = lo + 1.0
        iso = levelset_values(lo, hi, n_levels)
        mesh = mesh.copy()
        mesh.point_data["f"] = fi
        # pyvista links mappers whose scalar bars share a title: one title per colour scale
        bar_title = " " if (shared_scale or clim is not None) else " " * (j + 1)
        sb = dict(title=bar_title, color="black", n_labels=3, fmt="%.3g", vertical=False,
                  width=0.6, position_x=0.2, position_y=0.03, label_font_size=12)
        show_bar = bool(scalar_bar and (j == ncol - 1 or not (shared_scale or clim is not None)))
        common = dict(scalars="f", cmap=cmap, clim=(lo, hi), show_scalar_bar=show_bar,
                      scalar_bar_args=sb)
        if mkind == "triangle":
            plotter.add_mesh(mesh, smooth_shading=True, show_edges=show_edges, **common)
            _add_isolines(plotter, mesh, iso, line_width)
        elif mkind == "points":
            panel = plotter.window_size[0] / ncol  # pixels across this panel
            ps = point_size or max(3.0, 0.5 * panel / np.sqrt(max(mesh.n_points, 1)))
            plotter.add_mesh(mesh, render_points_as_spheres=True, point_size=ps, **common)
        else:
            _add_volume(plotter, pv, mesh, iso, volume, common, line_width)
        if sources is not None:
            src = np.atleast_1d(np.asarray(sources, dtype=np.int64))
            if src.size and (src.min() < 0 or src.max() >= mesh.n_points):
                raise ValueError(f"source index out of range [0, {mesh.n_points})")
            plotter.add_points(np.asarray(mesh.points)[src], color=source_color,
                               render_points_as_spheres=True, point_size=16)
        for crit_kind, idx in _critical_sets(critical).items():
            if idx.size:
                if idx.min() < 0 or idx.max() >= mesh.n_points:
                    raise ValueError(f"{crit_kind} index out of range [0, {mesh.n_points})")
                plotter.add_points(np.asarray(mesh.points)[idx], color=CRITICAL_COLORS[crit_kind],
                                   render_points_as_spheres=True, point_size=14)
        caption = labels[j] if labels is not None else (title if j == 0 else None)
        if labels is not None and title and j == 0:
            caption = f"{title}\n{caption}"
        if caption:
            panel = plotter.window_size[0] / ncol
            plotter.add_text(caption, position="upper_edge", color="black",
                             font_size=int(np.clip(panel / 50, 7, 11)))
        if camera_position is not None:
            plotter.camera_position = camera_position
        elif sources is not None and np.size(sources):
            look_at(plotter, mesh, int(np.atleast_1d(sources)[0]))
        else:
            plotter.camera_position = "iso"
        plotter.reset_camera()
        z = zoom if zoom is not None else (1.0 if mkind == "tet" else 1.2)
        if z != 1.0:
            plotter.camera.zoom(z)

    if filename is not None:
        image = plotter.screenshot(return_img=True)
        plotter.close()
        save_png(image, filename)
    return plotter


def lines_over_surfaces():
    """Draw iso-lines on top of the surface they lie on (no z-fighting).

    The contour lines are coincident with the triangles; VTK's polygon offset pushes the
    filled polygons slightly back in depth so that the lines always win. (A process-wide
    VTK setting; it only affects coincident geometry.)
    """
    from vtkmodules.vtkRenderingCore import vtkMapper

    vtkMapper.SetResolveCoincidentTopologyToPolygonOffset()


def look_at(plotter, mesh, vertex):
    """Place the camera on the side of ``vertex``, slightly from above."""
    c = np.asarray(mesh.center, dtype=float)
    p = np.asarray(mesh.points[vertex], dtype=float)
    d = p - c
    if np.linalg.norm(d) < 1e-12 * max(mesh.length, 1e-300):
        plotter.camera_position = "iso"
        return
    d /= np.linalg.norm(d)
    up = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    d = d + 0.35 * up + 0.25 * np.cross(up, d)
    d /= np.linalg.norm(d)
    plotter.camera_position = [tuple(c + 3.0 * mesh.length * d), tuple(c), tuple(up)]


def outer_surface(grid):
    """Boundary surface of a volume, keeping ``vtkOriginalPointIds``."""
    import inspect

    if "algorithm" in inspect.signature(grid.extract_surface).parameters:
        return grid.extract_surface(algorithm="dataset_surface")
    return grid.extract_surface()


def _add_isolines(plotter, surface, iso, line_width):
    if iso.size == 0:
        return
    lines = surface.contour(isosurfaces=iso, scalars="f")
    if lines.n_points:
        plotter.add_mesh(lines, color="black", line_width=line_width, show_scalar_bar=False)


def _add_volume(plotter, pv, grid, iso, volume, common, line_width):
    surf = outer_surface(grid)
    center = np.asarray(grid.center)
    if volume == "boundary":
        plotter.add_mesh(surf, smooth_shading=True, **common)
        _add_isolines(plotter, surf, iso, line_width)
        return
    if volume == "clip":
        # cut away the quarter facing the camera (x > cx and y > cy) to show the inside
        P = np.asarray(grid.points)
        grid = grid.copy()
        grid.point_data["_cut"] = np.minimum(P[:, 0] - center[0], P[:, 1] - center[1])
        inside = grid.clip_scalar(scalars="_cut", value=0.0, invert=True)
        inside.set_active_scalars("f")
        shell = outer_surface(inside)
        plotter.add_mesh(shell, **common)
        _add_isolines(plotter, shell, iso, line_width)
        return
    if volume == "slices":
        plotter.add_mesh(surf, opacity=0.15, color="gray", show_scalar_bar=False)
        slices = grid.slice_orthogonal(x=center[0], y=center[1], z=center[2])
        for k, sl in enumerate(slices):
            if sl.n_points:
                plotter.add_mesh(sl, **dict(common, show_scalar_bar=common["show_scalar_bar"] and k == 0))
                _add_isolines(plotter, sl, iso, line_width)
        return
    # isosurfaces
    plotter.add_mesh(surf, opacity=0.12, color="gray", show_scalar_bar=False)
    if iso.size:
        shells = grid.contour(isosurfaces=iso, scalars="f")
        if shells.n_points:
            plotter.add_mesh(shells, opacity=0.6, smooth_shading=True, **common)
