"""Pictures that read on any mesh: the source in view, log scales, distinct ticks, grey parts
said in the title, the source's component framed, the camera along the shape's own axes."""
from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pyvista")
pytest.importorskip("matplotlib")

from spectral_igl.viz import plot_levelsets  # noqa: E402
from spectral_igl.viz._scale import colour_ticks, use_log_scale  # noqa: E402

pytestmark = pytest.mark.usefixtures("one_blas_thread")


def _surface_actor(p):
    """The actor that draws the scalar ``f`` (its mapper shows scalars)."""
    (a,) = [a for a in p.renderer.actors.values() if getattr(a, "mapper", None) is not None
            and a.mapper.dataset is not None and a.mapper.scalar_visibility
            and "f" in a.mapper.dataset.point_data and a.mapper.dataset.n_cells > 0
            and a.mapper.dataset.n_points > 1 and a.mapper.dataset.n_cells != a.mapper.dataset.n_points]
    return a


def _pixel(plotter, point):
    from vtkmodules.vtkRenderingCore import vtkCoordinate

    c = vtkCoordinate()
    c.SetCoordinateSystemToWorld()
    c.SetValue(*map(float, point))
    x, y = c.GetComputedDoubleDisplayValue(plotter.renderer)
    return int(round(plotter.window_size[1] - 1 - y)), int(round(x))


def _marker_shows(plotter, point):
    """Whether the source marker (dark dot on a white rim) is what the pixels at ``point`` show."""
    img = plotter.screenshot(return_img=True)[..., :3].astype(int)
    row, col = _pixel(plotter, point)
    h, w = img.shape[:2]
    if not (3 <= row < h - 3 and 3 <= col < w - 3):
        return False
    patch = img[row - 3:row + 4, col - 3:col + 4]
    return bool(patch.max(axis=2).min() < 90)  # the dark dot covers the 7 x 7 pixels


def _depth_visible(plotter, point):
    """Whether ``point`` is the nearest surface at its pixel (z-buffer, markers hidden)."""
    for a in plotter.renderer.actors.values():
        m = getattr(a, "mapper", None)
        if m is not None and m.dataset is not None and m.dataset.n_points == 1:
            a.visibility = False
    plotter.screenshot(return_img=True)
    zbuf = plotter.get_image_depth(fill_value=-np.inf, reset_camera_clipping_range=False)
    row, col = _pixel(plotter, point)
    if not (0 <= row < zbuf.shape[0] and 0 <= col < zbuf.shape[1]):
        return False
    eye = np.asarray(plotter.camera.position)
    fwd = np.asarray(plotter.camera.focal_point) - eye
    fwd /= np.linalg.norm(fwd)
    depth = -float((np.asarray(point) - eye) @ fwd)
    window = zbuf[max(row - 1, 0):row + 2, max(col - 1, 0):col + 2]
    window = window[np.isfinite(window)]
    scale = float(np.linalg.norm(np.ptp(np.asarray(plotter.bounds).reshape(3, 2), axis=1)))
    return bool(window.size and np.min(window) <= depth + 1e-2 * scale)


# ---- colour-bar ticks and the log scale ------------------------------------------------------
def test_ticks_differ_on_the_issue_range_and_on_any_range():
    """42.5 / 42.6 / 42.6 was the old bar of a nearly constant HKS."""
    ticks, fmt = colour_ticks(42.5, 42.62)
    assert [fmt % t for t in ticks] == ["42.5", "42.55", "42.6"]
    rng = np.random.default_rng(3)
    for _ in range(400):
        centre = 10.0 ** rng.uniform(-12, 12) * rng.choice([-1.0, 1.0])
        width = abs(centre) * 10.0 ** rng.uniform(-11, 3)
        lo, hi = centre, centre + width
        for log in ((False, True) if lo > 0 else (False,)):
            ticks, fmt = colour_ticks(lo, hi, log=log)
            labels = [fmt % t for t in ticks]
            assert 2 <= len(ticks) <= 5, (lo, hi, log, labels)
            assert len(set(labels)) == len(labels), (lo, hi, log, labels)
            assert np.all(np.diff(ticks) > 0)
            assert ticks[0] >= lo - 1e-9 * width and ticks[-1] <= hi + 1e-9 * width
            # a label reads back as its tick
            tol = max(1e-6 * np.min(np.diff(ticks)), 8 * np.finfo(float).eps * np.abs(ticks).max())
            assert all(abs(float(s) - t) <= tol for s, t in zip(labels, ticks)), labels


def _graded_strip(nx=16, ny=12):
    """A wavy strip whose columns are geometrically spaced, 3e-3 to 1: vertex areas span
    more than two decades (a scan sampled densely in one place)."""
    x = np.concatenate([[0.0], np.geomspace(3e-3, 1.0, nx)])
    y = np.linspace(0.0, 0.6, ny)
    X, Y = np.meshgrid(x, y, indexing="ij")
    V = np.column_stack([X.ravel(), Y.ravel(), 0.1 * np.sin(3.0 * Y.ravel())])
    idx = np.arange(len(V)).reshape(len(x), len(y))
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return V, np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])


def test_log_scale_chosen_on_a_two_decade_hks():
    """HKS at a short time on a graded strip: about 1/(vertex area), more than two decades;
    drawn on a log scale with geometric iso-values and ticks at powers of ten."""
    import spectral_igl as sig

    V, F = _graded_strip()
    lap = sig.laplacian(V, F)
    H = np.asarray(sig.hks(lap, [1e-6])).ravel()
    ratio = H.max() / H.min()
    assert ratio > 100  # the data: two decades and more
    assert np.all(H > 0)
    p = plot_levelsets((V, F), H, kind="sequential", off_screen=True, window_size=(300, 300))
    view = p.spectral_igl_views[0]
    assert view["log"] and "log colour scale" in view["notes"]
    assert view["clim"] == pytest.approx((H.min(), H.max()))
    lut = _surface_actor(p).mapper.lookup_table
    assert lut.log_scale
    # the geometric mean of the range takes the middle colour of the map
    from spectral_igl.viz import colormap

    mid = np.asarray(lut.map_value(float(np.sqrt(H.min() * H.max())), opacity=False), dtype=float)[:3]
    assert np.allclose(mid, colormap("sequential")(0.5)[:3], atol=0.02)
    labels = view["tick_labels"]
    assert len(set(labels)) == len(labels) >= 2
    assert all(np.log10(t) == pytest.approx(round(np.log10(t))) for t in view["ticks"])
    p.close()
    # a linear scale on request; and a distance (0 at the source) stays linear
    p = plot_levelsets((V, F), H, kind="sequential", scale="linear", off_screen=True, window_size=(200, 200))
    assert not p.spectral_igl_views[0]["log"] and not _surface_actor(p).mapper.lookup_table.log_scale
    p.close()
    assert not use_log_scale(np.linalg.norm(V - V[0], axis=1))
    assert not use_log_scale(np.linspace(-1.0, 300.0, 10), kind="diverging")
    with pytest.raises(ValueError, match="scale must be one of"):
        plot_levelsets((V, F), H, scale="logarithmic", off_screen=True)


def test_bar_of_a_nearly_constant_picture_has_distinct_labels(sphere3):
    V, F = sphere3
    f = 42.5 + 0.12 * (V[:, 2] + 1.0) / 2.0  # 42.50 ... 42.62, the issue's HKS
    p = plot_levelsets((V, F), f, kind="sequential", off_screen=True, window_size=(300, 300))
    (bar,) = [b for b in p.scalar_bars.values()]
    assert bar.GetUseCustomLabels()
    arr = bar.GetCustomLabels()
    values = [arr.GetValue(k) for k in range(arr.GetNumberOfTuples())]
    labels = [bar.GetLabelFormat() % v for v in values]
    assert labels == ["42.5", "42.55", "42.6"]
    assert not p.spectral_igl_views[0]["log"]  # ratio 1.003: linear
    p.close()


# ---- infinite values and components --------------------------------------------------------
def test_infinite_values_leave_the_colour_range_and_are_said(sphere3):
    V, F = sphere3
    d = np.linalg.norm(V - V[0], axis=1)
    d[V[:, 2] < -0.5] = np.inf  # a region the distance does not reach
    d[1] = np.nan
    p = plot_levelsets((V, F), d, sources=[0], kind="distance", off_screen=True, window_size=(300, 300))
    fin = np.isfinite(d)
    view = p.spectral_igl_views[0]
    assert view["clim"] == pytest.approx((0.0, d[fin].max()))
    assert np.all(np.isfinite(_surface_actor(p).mapper.scalar_range))
    bad = int((~fin).sum())
    assert view["notes"] == [f"grey: {bad} vertices infinite or NaN"]
    assert all(np.isfinite(t) for t in view["ticks"])
    p.close()


def _many_components():
    """A large sphere with a small sphere inside it (hidden from every side) and 20 small
    spheres around it: 22 components."""
    from data_generators import icosphere

    V1, F1 = icosphere(3)
    v, f = icosphere(1)
    Vs, Fs = [3.0 * V1], [F1]
    n = len(V1)
    centres = [np.zeros(3)] + [4.5 * np.array([np.cos(a), np.sin(a), 0.3 * np.cos(3 * a)])
                               for a in np.linspace(0, 2 * np.pi, 20, endpoint=False)]
    starts = []
    for c in centres:
        starts.append(n)
        Vs.append(0.3 * v + c)
        Fs.append(f + n)
        n += len(v)
    return np.vstack(Vs), np.vstack(Fs), starts, len(v)


def test_many_components_frame_the_source_component_and_name_it():
    import spectral_igl as sig

    V, F, starts, k = _many_components()
    lap = sig.laplacian(V, F)
    # a source on an outer small sphere: its component is framed and named
    s = starts[5]
    d = np.asarray(sig.geodesic_distance(lap, s))
    mine = np.zeros(len(V), dtype=bool)
    mine[s:s + k] = True
    assert np.all(np.isfinite(d[mine])) and np.all(np.isinf(d[~mine]))  # the real geodesic
    p = plot_levelsets((V, F), d, sources=[s], kind="distance", off_screen=True, window_size=(400, 400))
    view = p.spectral_igl_views[0]
    # numbered by size, equal sizes in file order: the big sphere, the inner one, then 5 more
    assert view["notes"] == ["component 7 of 22 (source's); others grey (infinite)"]
    assert view["clim"] == pytest.approx((0.0, d[mine].max()))
    assert _depth_visible(p, V[s])
    # framed: the component spans much of the picture
    rows, cols = zip(*[_pixel(p, q) for q in V[mine]])
    assert max(np.ptp(rows), np.ptp(cols)) > 0.5 * 400
    p.close()
    # a source on the sphere inside the big one: seen through it
    s = starts[0]
    d = np.asarray(sig.geodesic_distance(lap, s))
    p = plot_levelsets((V, F), d, sources=[s], kind="distance", off_screen=True, window_size=(400, 400))
    assert p.spectral_igl_views[0]["notes"] == ["component 2 of 22 (source's); others see-through (infinite)"]
    assert _marker_shows(p, V[s])
    p.close()


def test_a_hidden_component_is_shown_only_when_hidden(sphere3):
    """A single component, or a source in plain view: no see-through, no component note."""
    V, F = sphere3
    p = plot_levelsets((V, F), V[:, 0] + 2.0, sources=[3], off_screen=True, window_size=(200, 200))
    assert p.spectral_igl_views[0]["notes"] == []
    assert all(a.prop.opacity == 1.0 for a in p.renderer.actors.values() if hasattr(a, "prop")
               and hasattr(a.prop, "opacity"))
    p.close()


# ---- the camera: along the shape's own axes; the source seen on real meshes -------------------
def _rotation(axis, degrees):
    a = np.radians(degrees)
    x, y, z = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K


def test_principal_axes_are_those_of_the_surface_not_of_the_sampling():
    """A 3 x 1 rectangle sampled densely along one short side: the vertices' spread is
    dominated by that side, the surface's is exactly 3/sqrt(12) by 1/sqrt(12)."""
    from scipy.spatial import Delaunay

    from spectral_igl.viz import principal_axes

    gx, gy = np.meshgrid(np.linspace(0, 3, 7), np.linspace(0, 1, 3))
    dense = np.column_stack([np.full(2000, 0.01), np.linspace(0, 1, 2000)])
    P2 = np.vstack([np.column_stack([gx.ravel(), gy.ravel()]), dense])
    F = Delaunay(P2).simplices
    R = _rotation([1.0, 2.0, 0.5], 45.0)
    P = np.column_stack([P2, np.zeros(len(P2))]) @ R.T
    centre, axes, spread = principal_axes(P, F)
    assert spread[:2] == pytest.approx([3.0 / np.sqrt(12.0), 1.0 / np.sqrt(12.0)], rel=1e-12)
    assert abs(axes[0] @ R[:, 0]) == pytest.approx(1.0, abs=1e-12)
    assert centre == pytest.approx(R @ [1.5, 0.5, 0.0], abs=1e-12)
    _, axes_v, _ = principal_axes(P)  # the vertices alone: the dense side wins
    assert abs(axes_v[0] @ R[:, 1]) > 0.9


def test_tilted_shape_is_drawn_upright_along_its_axes():
    """An ellipsoid long along y, tilted 45 degrees about z: the picture's up is its long
    axis (the file's y is 45 degrees off); untilted, the file's y stays up."""
    from data_generators import icosphere

    V0, F = icosphere(3)
    V0 = V0 * [0.8, 2.5, 0.5]
    R = _rotation([0.0, 0.0, 1.0], 45.0)
    long_axis = R @ [0.0, 1.0, 0.0]
    for V, axis in ((V0 @ R.T, long_axis), (V0, np.array([0.0, 1.0, 0.0]))):
        side = R @ [0.0, 0.0, 1.0] if axis is long_axis else np.array([0.0, 0.0, 1.0])
        for sources in (None, [int(np.argmax(V @ side))]):  # seen from the side
            p = plot_levelsets((V, F), np.linalg.norm(V - V[5], axis=1), sources=sources,
                               kind="sequential", off_screen=True, window_size=(200, 200))
            up = p.spectral_igl_views[0]["up"]
            d = p.spectral_igl_views[0]["direction"]
            want = axis - (axis @ d) * d
            assert abs(up @ want / np.linalg.norm(want)) > 0.99, (axis, sources, up)
            p.close()


def test_source_seen_in_a_mouth_on_a_small_component_and_inside_a_model(shared_meshes):
    """suzanne: a vertex inside the mouth and one on an eye (a 33-vertex component); truck
    (50 components): a part inside the body."""
    import spectral_igl as sig
    from spectral_igl.io import read_mesh

    cases = (("suzanne.obj", 307, "component 1 of 3"), ("suzanne.obj", 0, "component 2 of 3"),
             ("truck.obj", 1500, "see-through"), ("truck.obj", 743, "of 50 (source's)"))
    for name, source, note in cases:
        V, F = read_mesh(shared_meshes / name)
        d = np.asarray(sig.geodesic_distance(sig.laplacian(V, F), source))
        p = plot_levelsets((V, F), d, sources=[source], kind="distance", off_screen=True,
                           window_size=(300, 300))
        assert note in p.spectral_igl_views[0]["notes"][0], (name, source)
        assert _marker_shows(p, V[source]), (name, source)
        if "see-through" not in note:
            assert _depth_visible(p, V[source]), (name, source)
        p.close()
