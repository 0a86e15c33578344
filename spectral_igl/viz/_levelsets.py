"""Level-set pictures of scalar functions on surfaces, volumes and point sets."""
from __future__ import annotations

import numpy as np

from ._backend import (CRITICAL_COLORS, KINDS, NEUTRAL_COLOR, color_kind, colormap, headless,
                       notebook_picture, pyvista, save_png, to_pyvista)
from ._camera import fit_view, parse_view, place_camera, view_sees
from ._scale import SCALES, apply_ticks, use_log_scale

__all__ = ["plot_levelsets", "levelset_values", "reached_vertices"]

_VOLUME = ("boundary", "clip", "slices", "isosurfaces")


def levelset_values(vmin: float, vmax: float, n_levels: int, log: bool = False) -> np.ndarray:
    r"""``n_levels`` iso-values uniformly sampled inside ``(vmin, vmax)`` (end points excluded).

    With ``log`` they are uniform in the logarithm (geometric), as on a logarithmic colour
    scale.

    Parameters
    ----------
    vmin, vmax : float
        The range of the values (``vmin > 0`` with ``log``).
    n_levels : int
        Number of iso-values.
    log : bool
        Geometric instead of uniform spacing.

    Returns
    -------
    (n_levels,) float
        :math:`v_k = v_{min} + \frac{k}{n+1}(v_{max} - v_{min})`, :math:`k = 1..n` (with ``log``
        the same in :math:`\log v`).

    Examples
    --------
    >>> from spectral_igl import viz
    >>> viz.levelset_values(0.0, 1.0, 3)
    array([0.25, 0.5 , 0.75])
    >>> viz.levelset_values(1e-3, 1e1, 3, log=True)
    array([0.01, 0.1 , 1.  ])
    """
    if n_levels < 0:
        raise ValueError(f"n_levels must be >= 0, got {n_levels}")
    if not np.isfinite(vmin) or not np.isfinite(vmax) or vmax <= vmin or (log and vmin <= 0):
        return np.empty(0)
    if log:
        return np.logspace(np.log10(vmin), np.log10(vmax), n_levels + 2)[1:-1]
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


def reached_vertices(mesh, sources=None):
    r"""Vertices in the connected components that contain a source.

    Parameters
    ----------
    mesh : pyvista.DataSet
        Triangles, tetrahedra or a point set.
    sources : sequence of int, optional
        Without sources: every vertex that belongs to a cell (a point set: every point).

    Returns
    -------
    (n,) bool

    Examples
    --------
    A shape of two spheres: the sources' component only.

    >>> import numpy as np
    >>> from spectral_igl import viz
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(1)
    >>> mesh, _ = viz.to_pyvista((np.vstack([V, V + 3]), np.vstack([F, F + len(V)])))
    >>> r = viz.reached_vertices(mesh, [0])
    >>> int(r.sum()), bool(r[:42].all()), bool(r[42:].any())
    (42, True, False)
    """
    label = component_labels(mesh)
    src = np.atleast_1d(np.asarray(sources if sources is not None else [], dtype=np.int64))
    if src.size == 0:
        return label >= 0
    return np.isin(label, label[src]) & (label >= 0)


def component_labels(mesh):
    """Connected component of every vertex, numbered by size (0: the largest; equal sizes
    in the order of their first vertex).

    Vertices in no cell get -1; a point set is one component.

    Parameters
    ----------
    mesh : pyvista.DataSet

    Returns
    -------
    (n,) int
    """
    n = mesh.n_points
    cells = _cell_array(mesh)
    if cells is None:
        return np.zeros(n, dtype=np.int64)
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    k = cells.shape[1]
    rows = np.repeat(cells[:, 0], k - 1)
    cols = cells[:, 1:].ravel()
    A = sp.coo_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    _, label = connected_components(A, directed=False)
    used = np.zeros(n, dtype=bool)
    used[cells.ravel()] = True
    sizes = np.bincount(label[used], minlength=label.max() + 1)
    rank = np.empty_like(sizes)
    rank[np.argsort(-sizes, kind="stable")] = np.arange(sizes.size)
    out = rank[label]
    out[~used] = -1
    return out


def _cell_array(mesh):
    """(m, k) int cells of a triangle or tetrahedral dataset, ``None`` for a point set."""
    pv = pyvista()
    if isinstance(mesh, pv.UnstructuredGrid):
        return np.asarray(mesh.cells_dict.get(pv.CellType.TETRA, np.empty((0, 4))), dtype=np.int64)
    if isinstance(mesh, pv.PolyData) and mesh.n_cells and mesh.n_verts != mesh.n_cells:
        tri = mesh if mesh.is_all_triangles else mesh.triangulate()
        return np.asarray(tri.faces).reshape(-1, 4)[:, 1:].astype(np.int64)
    return None


def plot_levelsets(shape, f, *, kind="auto", cmap=None, n_levels=12, clim=None, shared_scale=True,
                   sources=None, critical=None, volume="clip", title=None, labels=None,
                   plotter=None, filename=None, off_screen=None, window_size=None,
                   camera="auto", camera_position=None, zoom=None, source_color="black",
                   scalar_bar=True, line_width=2.0, point_size=None, show_edges=False,
                   background="white", neutral_color=None, scale="auto"):
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
    kind : {"auto", "distance", "sequential", "diverging", "cyclic"} or a colormap name
        What the values mean, which fixes the colour map and the range. ``"distance"``
        and ``"sequential"`` (non-negative quantities): viridis, perceptually uniform, dark
        at the minimum and yellow at the maximum. ``"diverging"`` (signed quantities):
        blue - white - red with the range
        centred at 0, :math:`[-\max|f|, \max|f|]`. ``"cyclic"``: the hue circle, whose
        ends are the same colour -- for periodic data only. ``"auto"`` (default): diverging
        when ``f`` takes both signs, else sequential. A matplotlib name is drawn over the
        range of ``f``.
    cmap : str or matplotlib Colormap, optional
        Use this colour map instead of the one ``kind`` implies (the range still follows
        ``kind``).
    n_levels : int or list of int
        Number of iso-values, uniformly sampled in the open colour range (one per shape
        with a list; 0 draws no iso-lines).
    clim : (2,) float, optional
        Colour range; default from ``kind`` and the values of ``f`` on the reached parts
        (of all ``f`` when ``shared_scale``).
    scale : {"auto", "linear", "log"}
        Colour scale. ``"auto"``: logarithmic for sequential values (not ``kind="distance"``)
        that are all positive and span more than two decades (``max / min > 100``; an HKS,
        a heat kernel at a short time), linear otherwise; the title then says "log colour
        scale" and the iso-values are geometric. ``"log"`` greys the values <= 0.
        Colour-bar ticks are round values, printed with as many digits as they need to
        differ.
    shared_scale : bool
        With several shapes, use one colour scale and one set of iso-values for all.
    sources : int, sequence of int, or a list of them (one per shape), optional
        Source vertices, marked by dots (with several shapes: the same indices in every
        panel, or one entry per panel, ``None`` for none). Connected components containing no source (and
        vertices in no cell, and non-finite values: an infinite distance, a NaN) are drawn
        in a neutral grey and kept out of the colour range; the title says so. On a shape
        with several components the picture frames the source's component and the title
        names it ("component 3 of 44 (source's)", numbered by size, 1 the largest); when the other
        components hide the source from every direction they are drawn see-through.
    critical : dict or object, optional
        Critical points ``{"minimum": idx, "maximum": idx, "saddle": idx}`` (or an object
        with attributes ``minima``, ``maxima``, ``saddles``), marked blue, red and green.
    volume : {"clip", "slices", "boundary", "isosurfaces"}
        How a tetrahedral mesh is shown: boundary with the quarter ``x > x_s, y > y_s`` cut
        away (``s`` the first source, else the centre), boundary plus three
        orthogonal slices (through the first source, else the centre), boundary only, or
        iso-surfaces inside a translucent boundary.
        Iso-values of volumes are sampled in the range on the boundary (as in the survey),
        or over the whole volume when there are sources (the cut shows them).
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
    camera : str, (3,) float or pyvista camera position
        ``"auto"`` (default): face the first source -- or, without sources, the minimum of
        ``f`` (both its minimum and maximum when ``f`` is signed; a ``kind="sequential"``
        descriptor has no point to face and is seen from the broad side of the shape) --
        from outside the shape, along the outward normal there when a ray test
        shows it unobstructed (else the best of a few other directions, among them the
        principal directions of the shape), with the up direction from the area-weighted
        principal axes of the shape, not the file's axes (:func:`spectral_igl.viz.auto_view`).
        A tetrahedral mesh drawn inside (``volume`` other than ``"boundary"``) is seen from
        ``"iso"``, facing the cut (which passes through the first source, as do the slices).
        Or a named view ``"iso"``, ``"+x"``, ``"-z"``, ...; a direction ``(dx, dy, dz)``
        from the shape towards the camera; a pyvista camera position.
    camera_position : optional
        Older name of ``camera``; used when given.
    zoom : float, optional
        Camera zoom after fitting the bounding sphere of the shape. Default: surfaces and
        point sets are fitted to fill the panel between the title and the colour bar;
        volumes keep their bounding box in the picture.
    source_color : str
        Colour of the source dots.
    neutral_color : str, optional
        Colour of the parts outside the scale (default a neutral grey).

    Returns
    -------
    pyvista.Plotter
        The plotter (closed when ``filename`` was given; its last image is in
        ``plotter.last_image``). ``plotter.spectral_igl_views`` lists, per panel, the
        camera ``direction``, ``up`` and the ``visible`` fraction of the target's
        neighbourhood, the colour ``kind``, ``clim``, ``log`` (logarithmic scale),
        ``ticks`` and ``tick_labels`` of the colour bar, and ``notes`` (what the title adds:
        the source's component, the grey parts).

    Examples
    --------
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> p = plot_levelsets((V, F), V[:, 2], filename="z.png")  # doctest: +SKIP
    """
    pv = pyvista()
    lines_over_surfaces()
    shapes = shape if isinstance(shape, list) else [shape]
    fs = f if isinstance(f, list) else [f]
    if len(shapes) != len(fs):
        raise ValueError(f"got {len(shapes)} shape(s) but {len(fs)} function(s)")
    if labels is not None and len(labels) != len(shapes):
        raise ValueError(f"got {len(labels)} label(s) for {len(shapes)} shape(s)")
    if not isinstance(kind, str):
        raise TypeError(f"kind must be a string, got {type(kind).__name__}")
    if volume not in _VOLUME:
        raise ValueError(f"volume must be one of {_VOLUME}, got {volume!r}")
    if scale not in SCALES:
        raise ValueError(f"scale must be one of {SCALES}, got {scale!r}")
    levels = list(n_levels) if isinstance(n_levels, (list, tuple)) else [n_levels] * len(shapes)
    if len(levels) != len(shapes):
        raise ValueError(f"got {len(levels)} n_levels for {len(shapes)} shape(s)")
    levels = [int(k) for k in levels]
    if any(k < 0 for k in levels):
        raise ValueError(f"n_levels must be >= 0, got {n_levels}")
    if camera_position is not None:
        camera = camera_position
    parse_view(camera)  # a bad camera is refused before any drawing
    if plotter is not None and len(shapes) > 1:
        raise ValueError("pass plotter only with a single shape")
    neutral = neutral_color or NEUTRAL_COLOR

    per_sources = _sources_per_panel(sources, len(shapes))
    meshes, values, reached, labels_c = [], [], [], []
    for s, fi, sources in zip(shapes, fs, per_sources):
        mesh, mkind = to_pyvista(s)
        fi = np.asarray(fi)
        if np.iscomplexobj(fi):
            raise TypeError("f must be real; draw f.real and f.imag separately")
        fi = fi.astype(float).ravel()
        if fi.shape[0] != mesh.n_points:
            raise ValueError(f"f has {fi.shape[0]} values but the shape has {mesh.n_points} vertices")
        src = np.atleast_1d(np.asarray(sources if sources is not None else [], dtype=np.int64))
        if src.size and (src.min() < 0 or src.max() >= mesh.n_points):
            raise ValueError(f"source index out of range [0, {mesh.n_points})")
        meshes.append((mesh, mkind))
        values.append(fi)
        comp = component_labels(mesh)
        labels_c.append(comp)
        reach = (comp >= 0) & (np.isin(comp, comp[src]) if src.size else True)
        reached.append(reach & np.isfinite(fi))

    # what the values mean: one reading for all panels of a shared scale
    known = kind in KINDS
    if known:
        pooled = np.concatenate([fi[r] for fi, r in zip(values, reached)])
        meaning = color_kind(pooled, kind)
        per_panel = [color_kind(fi[r], kind) for fi, r in zip(values, reached)]
    else:
        meaning, per_panel = "sequential", ["sequential"] * len(values)
    if shared_scale or clim is not None:
        per_panel = [meaning] * len(values)
    cmaps = [colormap(cmap if cmap is not None else (kind if not known else
                      ("distance" if m == "sequential" else m))) for m in per_panel]
    # logarithmic colours for positive values spanning decades (one decision per scale); a
    # distance is read on a linear scale
    if kind == "distance":
        per_meaning, meaning_all = ["distance"] * len(values), "distance"
    else:
        per_meaning, meaning_all = per_panel, meaning
    if shared_scale or clim is not None:
        logs = [use_log_scale(np.concatenate([fi[r] for fi, r in zip(values, reached)]), scale,
                              meaning_all)] * len(values)
    else:
        logs = [use_log_scale(fi[r], scale, m) for fi, r, m in zip(values, reached, per_meaning)]
    for j, log in enumerate(logs):  # a log scale has no place for values <= 0: grey them
        if log:
            reached[j] = reached[j] & (values[j] > 0)

    def _range(mesh, mkind, fi, ok, src):
        if mkind == "tet" and (src is None or np.size(src) == 0):  # range on the boundary, as in the survey's Fig. 8
            surf = outer_surface(mesh)
            ids = surf.point_data.get("vtkOriginalPointIds")
            if ids is not None:
                ids = np.asarray(ids)
                fi, ok = fi[ids], ok[ids]
        fin = fi[ok]
        return (float(fin.min()), float(fin.max())) if fin.size else (0.0, 1.0)

    ranges = [_range(m, k, fi, r, sp) for (m, k), fi, r, sp in zip(meshes, values, reached, per_sources)]
    if clim is not None:
        clim = (float(clim[0]), float(clim[1]))
        ranges = [clim] * len(meshes)
    else:
        if shared_scale and len(meshes) > 1:
            shared = (min(r[0] for r in ranges), max(r[1] for r in ranges))
            ranges = [shared] * len(meshes)
        ranges = [(-max(abs(lo), abs(hi)), max(abs(lo), abs(hi))) if m == "diverging" else (lo, hi)
                  for (lo, hi), m in zip(ranges, per_panel)]

    if off_screen is None:
        off_screen = bool(filename is not None or headless() or pv.OFF_SCREEN)
    ncol = len(meshes)
    if plotter is None:
        size = tuple(window_size) if window_size is not None else (600 * ncol, 600)
        plotter = pv.Plotter(shape=(1, ncol), off_screen=off_screen, window_size=size,
                             border=False)
    plotter.set_background(background)
    views = []

    for j, ((mesh, mkind), fi, ok, rng) in enumerate(zip(meshes, values, reached, ranges)):
        sources = per_sources[j]
        if ncol > 1:
            plotter.subplot(0, j)
        lo, hi = rng
        if hi <= lo:
            hi = lo + 1.0
        log = logs[j]
        if log and lo <= 0:
            raise ValueError(f"a logarithmic colour scale needs a positive range, got clim ({lo:g}, {hi:g})")
        iso = levelset_values(lo, hi, levels[j], log=log)
        mesh = mesh.copy()
        mesh.point_data["f"] = np.where(ok, fi, np.nan)
        # pyvista links mappers whose scalar bars share a title: one title per colour scale
        bar_title = " " if (shared_scale or clim is not None) else " " * (j + 1)
        sb = dict(title=bar_title, color="black", n_labels=3, fmt="%.3g", vertical=False,
                  width=0.6, position_x=0.2, position_y=0.03, label_font_size=12)
        show_bar = bool(scalar_bar and (j == ncol - 1 or not (shared_scale or clim is not None)))
        common = dict(scalars="f", cmap=cmaps[j], clim=(lo, hi), show_scalar_bar=show_bar,
                      scalar_bar_args=sb, nan_color=neutral, ambient=0.25, diffuse=0.8, log_scale=log)
        main, rest = split_reached(pv, mesh, mkind, ok)
        grey_actor = None
        if rest is not None:  # the parts out of reach: grey, no scale, no lines
            if mkind == "points":
                plotter.add_mesh(rest, color=neutral, render_points_as_spheres=True,
                                 point_size=point_size or 4.0, show_scalar_bar=False)
            else:
                grey = outer_surface(rest) if mkind == "tet" else rest
                grey_actor = plotter.add_mesh(grey, color=neutral, smooth_shading=True,
                                              show_scalar_bar=False)
        if mkind == "triangle":
            plotter.add_mesh(main, smooth_shading=True, show_edges=show_edges, **common)
            _add_isolines(plotter, main, iso, line_width)
        elif mkind == "points":
            panel = plotter.window_size[0] / ncol  # pixels across this panel
            ps = point_size or max(3.0, 0.5 * panel / np.sqrt(max(main.n_points, 1)))
            plotter.add_mesh(main, render_points_as_spheres=True, point_size=ps, **common)
        P = np.asarray(mesh.points)
        src = np.atleast_1d(np.asarray(sources if sources is not None else [], dtype=np.int64))
        if mkind == "tet":  # the cut of "clip" passes through the source, which it shows
            _add_volume(plotter, pv, main, iso, volume, common, line_width,
                        cut_at=P[src[0]] if src.size else None)
        for crit_kind, idx in _critical_sets(critical).items():
            if idx.size:
                if idx.min() < 0 or idx.max() >= mesh.n_points:
                    raise ValueError(f"{crit_kind} index out of range [0, {mesh.n_points})")
                plotter.add_points(P[idx], color=CRITICAL_COLORS[crit_kind],
                                   render_points_as_spheres=True, point_size=14)
        caption = labels[j] if labels is not None else (title if j == 0 else None)
        if labels is not None and title and j == 0:
            caption = f"{title}\n{caption}"
        comp = labels_c[j]
        notes = _grey_notes(comp, src, fi, ok, log)
        if log:
            notes.append("log colour scale")
        n_comp = int(comp.max()) + 1 if comp.size else 0
        part = np.isin(comp, comp[src]) & (comp >= 0) if src.size else None
        # where to look from
        mode, _ = parse_view(camera)
        drawn = outer_surface(mesh) if mkind == "tet" else mesh
        target = None
        if mode == "auto":
            if mkind == "tet" and volume != "boundary":
                camera_j = "iso"  # the cut (and the slices) through the source face the iso view
            else:
                camera_j = camera
                if src.size:
                    target = P[src[0]]
                elif kind not in ("auto", "distance", "diverging") and per_panel[j] == "sequential":
                    target = None  # a descriptor: no point to face, the broad side of the shape
                elif ok.any() and per_panel[j] == "diverging" and mkind != "tet":
                    cand = np.flatnonzero(ok)  # a signed function: both ends of the scale
                    target = P[[cand[np.argmin(fi[cand])], cand[np.argmax(fi[cand])]]]
                elif ok.any():
                    cand = np.flatnonzero(ok)
                    if mkind == "tet":
                        ids = drawn.point_data.get("vtkOriginalPointIds")
                        if ids is not None:
                            cand = np.intersect1d(cand, np.asarray(ids))
                    if cand.size:
                        target = P[cand[np.argmin(fi[cand])]]
                if target is not None and mkind == "tet":  # nearest boundary point
                    Q = np.asarray(drawn.points)
                    target = Q[np.argmin(np.linalg.norm(Q - target, axis=1))]
        else:
            camera_j = camera
        same = j > 0 and mode == "auto" and views and views[0].get("direction") is not None and \
            _same_points(meshes[0][0], mesh)
        if same:  # the same shape in every panel: one view, so that panels compare at a glance
            camera_j = views[0]["direction"]
        focus = None
        if part is not None and n_comp > 1 and mkind != "points" and mode == "auto" and not same:
            focus = P[part]  # frame the source's component
        surface = drawn if mkind != "points" else mesh
        view = place_camera(plotter, surface, camera_j, target, focus=focus)
        if focus is not None and mkind == "triangle" and grey_actor is not None and \
                target is not None and target.ndim == 1 and not view_sees(surface, target, plotter.camera.position):
            # the other components hide the source from every side tried: see through them
            view = place_camera(plotter, surface, camera_j, target, focus=focus, occluder=main)
            grey_actor.prop.opacity = 0.12
            notes[0] = notes[0].replace("others grey", "others see-through")
        if notes:
            caption = "\n".join(([caption] if caption else []) + notes)
        if caption:
            panel = plotter.window_size[0] / ncol
            plotter.add_text(caption, position="upper_edge", color="black",
                             font_size=_font_size(caption, panel))
        view.update(kind=per_panel[j], clim=(lo, hi), log=log, notes=notes)
        if show_bar:
            bar = plotter.scalar_bars[bar_title] if bar_title in plotter.scalar_bars else None
            view.update(zip(("ticks", "tick_labels"), apply_ticks(bar, lo, hi, log)))
        views.append(view)
        if zoom is None:  # fill the panel, leaving room for title and bar
            lines = len(caption.splitlines()) if caption else 0  # room for every line of the title
            fit_view(plotter, view.pop("points", P), height=0.82 - 0.05 * min(lines, 4) - (0.03 if lines else 0),
                     width=0.92, lift=(0.035 if (caption and show_bar) else 0.0) - 0.025 * max(min(lines, 4) - 1, 0))
        else:
            view.pop("points", None)
            z = zoom if zoom is not None else 1.0
            if z != 1.0:
                plotter.camera.zoom(z)
        if src.size:
            add_source_marker(plotter, P[src], source_color)

    _set_attribute(pv, plotter, "spectral_igl_views", views)
    image = None
    if filename is not None:
        image = plotter.screenshot(return_img=True)
        plotter.close()
        save_png(image, filename)
    return notebook_picture(plotter, image)


def _grey_notes(comp, src, f, ok, log):
    """What the grey parts of a panel are, for its title: the source's component, the
    vertices without a value on the scale (infinite, NaN, or <= 0 on a log scale)."""
    notes = []
    n_comp = int(comp.max()) + 1 if comp.size else 0
    mine = comp >= 0
    if src.size and n_comp > 1:
        ids = sorted({int(c) + 1 for c in comp[src] if c >= 0})
        which = "component" if len(ids) == 1 else "components"
        whose = "source's" if len(src) == 1 else "sources'"
        mine = np.isin(comp, comp[src]) & (comp >= 0)
        others = (comp >= 0) & ~mine
        inf = " (infinite)" if others.any() and not np.isfinite(f[others]).any() else ""
        notes.append(f"{which} {', '.join(map(str, ids))} of {n_comp} ({whose}); others grey{inf}")
    bad = mine & ~ok
    if bad.any():
        kinds = [name for name, m in (("infinite", np.isinf(f[bad])), ("NaN", np.isnan(f[bad])),
                                       ("<= 0 on the log scale", np.isfinite(f[bad]) & (f[bad] <= 0)))
                 if np.any(m)]
        notes.append(f"grey: {int(bad.sum())} vertices {' or '.join(kinds)}")
    return notes


def _same_points(a, b):
    """Whether two datasets have the same vertex positions."""
    return a.n_points == b.n_points and np.array_equal(np.asarray(a.points), np.asarray(b.points))


def _sources_per_panel(sources, count):
    """One source list (or None) per panel."""
    if isinstance(sources, (list, tuple)) and count > 1 and len(sources) == count and \
            any(s is None or np.ndim(s) > 0 for s in sources):
        return [None if s is None else np.atleast_1d(np.asarray(s, dtype=np.int64)) for s in sources]
    return [sources] * count


def _set_attribute(pv, obj, name, value):
    """Attach ``value`` to a pyvista object (newer pyvista refuses plain new attributes)."""
    setter = getattr(pv, "set_new_attribute", None)
    if setter is not None:
        setter(obj, name, value)
    else:  # pragma: no cover - older pyvista
        setattr(obj, name, value)


def _font_size(caption, panel):
    """A font size (points) at which the longest line of ``caption`` fits in ``panel`` pixels."""
    longest = max((len(line) for line in str(caption).splitlines()), default=1)
    fit = 0.92 * panel / (1.25 * max(longest, 1))  # VTK's glyphs: ~1.2 pixels wide per point
    return int(np.clip(min(panel / 50, fit), 6, 11))


def add_source_marker(plotter, points, color="black", names=(None, None)):
    """Source dots: a dark sphere on a white one, visible on every colour of every map.

    The dark dot is moved towards the camera by a fraction of the white one's size, so
    that it is drawn in front of it.
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    cam = plotter.camera
    eye = np.asarray(cam.position, dtype=float)
    focal = np.asarray(cam.focal_point, dtype=float)
    dist = float(np.linalg.norm(eye - focal)) or 1.0
    # world size of one pixel at the focal distance
    h = 2.0 * dist * np.tan(np.radians(cam.view_angle) / 2.0) / max(plotter.window_size[1], 1)
    toward = eye - points
    toward /= np.maximum(np.linalg.norm(toward, axis=1, keepdims=True), 1e-300)
    plotter.add_points(points, color="white", render_points_as_spheres=True, point_size=22,
                       pickable=False, reset_camera=False, name=names[0])
    plotter.add_points(points + 12.0 * h * toward, color=color, render_points_as_spheres=True,
                       point_size=14, pickable=False, reset_camera=False, name=names[1])


def split_reached(pv, mesh, mkind, ok):
    """(part with values, part out of reach or None) of ``mesh``; cells need all corners reached."""
    if ok.all():
        return mesh, None
    if mkind == "points":
        idx = np.flatnonzero(ok)
        other = np.flatnonzero(~ok)
        return mesh.extract_points(idx), (mesh.extract_points(other) if other.size else None)
    cells = _cell_array(mesh)
    good = ok[cells].all(axis=1)
    keep = np.flatnonzero(good)
    drop = np.flatnonzero(~good)
    main = mesh.extract_cells(keep)
    rest = mesh.extract_cells(drop) if drop.size else None
    if mkind == "triangle":
        main = outer_surface(main)
        rest = outer_surface(rest) if rest is not None else None
    return main, rest


def lines_over_surfaces():
    """Draw iso-lines on top of the surface they lie on (no z-fighting).

    The contour lines are coincident with the triangles; VTK's polygon offset pushes the
    filled polygons slightly back in depth so that the lines always win. (A process-wide
    VTK setting; it only affects coincident geometry.)
    """
    from vtkmodules.vtkRenderingCore import vtkMapper

    vtkMapper.SetResolveCoincidentTopologyToPolygonOffset()


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


def _add_volume(plotter, pv, grid, iso, volume, common, line_width, cut_at=None):
    surf = outer_surface(grid)
    center = np.asarray(grid.center) if cut_at is None else np.asarray(cut_at, dtype=float)
    if volume == "boundary":
        plotter.add_mesh(surf, smooth_shading=True, **common)
        _add_isolines(plotter, surf, iso, line_width)
        return
    if volume == "clip":
        # cut away the quarter facing the camera (x > cx and y > cy) to show the inside: the
        # part x < cx, and the part x > cx, y < cy, each cut by an exact plane (one cut by
        # min(x - cx, y - cy) would leave pieces of the corner's tetrahedra standing)
        left = grid.clip(normal=(1.0, 0.0, 0.0), origin=center, invert=True)
        right = grid.clip(normal=(1.0, 0.0, 0.0), origin=center, invert=False)
        right = right.clip(normal=(0.0, 1.0, 0.0), origin=center, invert=True) if right.n_cells else right
        for part in (left, right):
            if part.n_cells:
                part.set_active_scalars("f")
                shell = outer_surface(part)
                plotter.add_mesh(shell, **common)
                _add_isolines(plotter, shell, iso, line_width)
                common = dict(common, show_scalar_bar=False)
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
