"""spectral_igl.viz: level-set pictures off screen, colour conventions, the viewer's callbacks."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from _needs import VIZ

from spectral_igl.viz import colormap, levelset_values, plot_levelsets  # noqa: E402



def image_stats(path_or_img):
    """(pixel standard deviation, number of distinct colours) of an image."""
    from PIL import Image

    img = np.asarray(Image.open(path_or_img).convert("RGB")) if not isinstance(path_or_img, np.ndarray) \
        else np.asarray(path_or_img)[..., :3]
    flat = img.reshape(-1, 3)
    return float(img.std()), len(np.unique(flat, axis=0)), img


def assert_not_blank(path, min_std=10.0, min_colors=50):
    std, ncol, img = image_stats(path)
    assert std > min_std, f"{path}: looks blank (pixel std {std:.2f})"
    assert ncol > min_colors, f"{path}: only {ncol} distinct colours"
    return img


def colour_fraction(img, rgb, tol=60):
    d = np.abs(img.astype(int) - np.array(rgb)[None, None, :]).max(axis=2)
    return float(np.mean(d < tol))


pytestmark = [VIZ, pytest.mark.usefixtures("one_blas_thread")]


@pytest.fixture(scope="module")
def sphere():
    from data_generators import icosphere

    return icosphere(3)


def test_import_is_light():
    code = ("import sys, spectral_igl, spectral_igl.viz; "
            "bad = [m for m in ('pyvista', 'vtk', 'matplotlib') if m in sys.modules]; "
            "print(','.join(bad))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_missing_extra_names_the_install(monkeypatch):
    import builtins

    from spectral_igl.viz import _backend

    real_import = builtins.__import__

    def fake(name, *a, **k):
        if name == "pyvista" or name.startswith("pyvista."):
            raise ImportError("No module named 'pyvista'")
        return real_import(name, *a, **k)

    monkeypatch.setattr(builtins, "__import__", fake)
    with pytest.raises(ImportError, match=r'pip install "spectral-igl\[viz\]"'):
        _backend.pyvista()


def test_levelset_values_uniform_inside_range():
    v = levelset_values(-1.0, 3.0, 7)
    assert v.shape == (7,)
    assert np.allclose(np.diff(v), 0.5) and v[0] == pytest.approx(-0.5) and v[-1] == pytest.approx(2.5)
    assert levelset_values(1.0, 1.0, 5).size == 0


def _lightness(rgb):
    """CIE L* of sRGB colours (n, 3) in [0, 1]."""
    c = np.asarray(rgb, dtype=float)
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    y = lin @ np.array([0.2126, 0.7152, 0.0722])
    return np.where(y > (6 / 29) ** 3, 116 * np.cbrt(y) - 16, y * (29 / 3) ** 3)


def test_colour_conventions():
    dist = colormap("distance")
    # perceptually uniform: the lightness climbs steadily from a dark minimum to a light
    # maximum (a rainbow's lightness goes up and down: blue and red both dark)
    L = _lightness(dist(np.linspace(0, 1, 65))[:, :3])
    steps = np.diff(L)
    assert steps.min() > 0 and L[-1] - L[0] > 60
    assert steps.max() < 2.0 * steps.mean()
    assert np.allclose(dist(0.0)[:3], (0.267, 0.005, 0.329), atol=0.01)  # viridis
    cyc = colormap("cyclic")
    # red -> yellow -> green -> cyan -> blue -> magenta -> red at sixths of the range
    expected = [(1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1), (1, 0, 1), (1, 0, 0)]
    for k, rgb in enumerate(expected):
        assert np.allclose(cyc(k / 6)[:3], rgb, atol=0.02), (k, cyc(k / 6))
    with pytest.raises(ValueError, match="unknown colormap"):
        colormap("no-such-map")


def test_distance_picture_dark_at_source(tmp_path, sphere):
    V, F = sphere
    d = np.arccos(np.clip(V @ V[0], -1, 1))
    path = tmp_path / "d.png"
    p = plot_levelsets((V, F), d, sources=[0], filename=path, window_size=(300, 300))
    img = assert_not_blank(path)
    assert img.shape[:2] == (300, 300)
    # camera faces the source: the centre of the picture (around the source) is darker than
    # the rest of the surface (viridis: dark at the minimum)
    L = _lightness(img[..., :3] / 255.0)
    surface = (img.min(axis=2) < 200) & (L > 12)  # not the white background, not the lines
    surface[250:] = False  # nor the colour bar
    centre = np.zeros_like(surface)
    centre[110:190, 110:190] = True
    assert L[centre & surface].mean() < L[~centre & surface].mean() - 5
    # iso-lines: black pixels on the surface
    assert colour_fraction(img, (0, 0, 0), tol=40) > 0.002
    assert p._closed if hasattr(p, "_closed") else True


def test_cyclic_and_isolines_count(sphere):
    V, F = sphere
    mesh_f = V[:, 2]
    p = plot_levelsets((V, F), mesh_f, kind="cyclic", n_levels=9, off_screen=True,
                       window_size=(200, 200))
    lines = [a for a in p.renderer.actors.values()
             if hasattr(a, "mapper") and a.mapper is not None and a.mapper.dataset is not None
             and a.mapper.dataset.n_lines > 0]
    assert len(lines) == 1
    z = np.asarray(lines[0].mapper.dataset.points)[:, 2]
    # the contour points lie on the 9 planes z = -1 + 0.2 k, k = 1..9
    levels = levelset_values(mesh_f.min(), mesh_f.max(), 9)
    assert np.allclose(np.min(np.abs(z[:, None] - levels[None, :]), axis=1), 0, atol=1e-9)
    assert len(np.unique(np.round(z, 6))) == 9
    p.close()


def test_shared_scale_and_critical_points(tmp_path, sphere):
    V, F = sphere
    f1, f2 = V[:, 0], 3 * V[:, 1]
    crit = {"minimum": [int(np.argmin(f1))], "maximum": [int(np.argmax(f1))],
            "saddle": np.array([[5, 1]])}
    p = plot_levelsets([(V, F), (V, F)], [f1, f2], kind="cyclic", shared_scale=True,
                       critical=crit, labels=["x", "3y"], off_screen=True, window_size=(400, 200))
    ranges = []
    for r in p.renderers:
        for a in r.actors.values():
            m = getattr(a, "mapper", None)
            if m is not None and m.dataset is not None and "f" in m.dataset.point_data \
                    and m.dataset.n_cells == len(F):
                ranges.append(tuple(m.scalar_range))
    assert len(ranges) == 2 and ranges[0] == ranges[1]
    assert ranges[0] == pytest.approx((min(f1.min(), f2.min()), max(f1.max(), f2.max())))
    img = p.screenshot(return_img=True)
    p.close()
    std, ncol, _ = image_stats(img)
    assert std > 10 and ncol > 50


def test_tet_volume_and_point_set(tmp_path):
    from data_generators import box_tets

    V, T = box_tets((8, 6, 4))
    f = np.linalg.norm(V - V.mean(0), axis=1)
    for volume in ("clip", "slices", "boundary", "isosurfaces"):
        path = tmp_path / f"vol_{volume}.png"
        plot_levelsets((V, T), f, volume=volume, filename=path, window_size=(250, 250))
        assert_not_blank(path)
    path = tmp_path / "points.png"
    plot_levelsets(V, f, filename=path, window_size=(250, 250))
    assert_not_blank(path)


def test_laplacian_input(tmp_path, sphere):
    import spectral_igl as sig

    lap = sig.laplacian(*sphere)
    path = tmp_path / "lap.png"
    plot_levelsets(lap, sphere[0][:, 1], kind="cyclic", filename=path, window_size=(200, 200))
    assert_not_blank(path)


def test_bad_input_is_rejected(sphere):
    V, F = sphere
    with pytest.raises(ValueError, match="vertices"):
        plot_levelsets((V, F), np.zeros(len(V) - 1), off_screen=True)
    with pytest.raises(ValueError, match="out of range"):
        plot_levelsets((V, F), V[:, 0], sources=[len(V)], off_screen=True)
    with pytest.raises(ValueError, match="2 shape"):
        plot_levelsets([(V, F), (V, F)], [V[:, 0]], off_screen=True)
    with pytest.raises(TypeError, match="real"):
        plot_levelsets((V, F), V[:, 0] + 1j, off_screen=True)
    with pytest.raises(ValueError, match="volume"):
        plot_levelsets((V, F), V[:, 0], volume="xray", off_screen=True)
    with pytest.raises(TypeError, match="cannot draw"):
        plot_levelsets("mesh.obj", V[:, 0], off_screen=True)
    with pytest.raises(ValueError):
        plot_levelsets((V, F + len(V)), V[:, 0], off_screen=True)


# ---- the interactive viewer, driven off screen ---------------------------------------------
@pytest.fixture
def viewer():
    import spectral_igl as sig
    from data_generators import icosphere
    from spectral_igl.viz import Viewer

    lap = sig.laplacian(*icosphere(2))
    v = Viewer(lap, quantity="kernel", filter="heat", t=0.1, source=3, off_screen=True,
               window_size=(300, 300))
    yield v
    v.close()


def test_viewer_callbacks_match_dense_ground_truth(viewer):
    import spectral_igl as sig

    lap = viewer.lap
    evals, X = sig.dense_eigs(lap)

    def kernel(t, i):
        return X @ (np.exp(-t * evals) * X[i])

    # initial state: heat kernel from vertex 3 at t = 0.1
    assert np.allclose(viewer.last.values, kernel(0.1, 3), atol=1e-6)
    # pick a vertex: everything follows
    viewer.on_pick(40)
    assert viewer.source == 40
    assert np.allclose(viewer.last.values, kernel(0.1, 40), atol=1e-6)
    assert np.allclose(viewer.mesh.point_data["f"], viewer.last.values)
    # pick by a 3-D point (what the mouse gives): the nearest vertex is chosen
    viewer.on_pick_point(lap.data["V"][77] * 1.02)
    assert viewer.source == 77
    # the slider works in log10 t
    viewer._on_slider(np.log10(0.02))
    assert viewer.t == pytest.approx(0.02)
    assert np.allclose(viewer.last.values, kernel(0.02, 77), atol=1e-6)
    assert viewer.slider.GetRepresentation().GetValue() == pytest.approx(np.log10(0.02))
    viewer.on_time(0.3)
    assert viewer.slider.GetRepresentation().GetValue() == pytest.approx(np.log10(0.3))
    # the text overlay reports the bound and the time of the last evaluation
    text = viewer.status()
    assert "error bound" in text and "ms" in text and "vertex 77" in text
    img = viewer.screenshot()
    std, ncol, _ = image_stats(img)
    assert std > 10 and ncol > 50


def test_viewer_filter_method_quantity(viewer):
    import spectral_igl as sig

    lap = viewer.lap
    evals, X = sig.dense_eigs(lap)
    viewer.on_pick(5)
    viewer.set_quantity("distance")
    viewer.set_filter("biharmonic")
    phi2 = np.zeros_like(evals)
    phi2[1:] = evals[1:] ** -2.0
    truth = np.sqrt(np.maximum(((X - X[5]) ** 2) @ phi2, 0))
    assert np.allclose(viewer.last.values, truth, atol=1e-6 * truth.max())
    assert viewer.last.values[5] == pytest.approx(0.0, abs=1e-6 * truth.max())
    # distances use the sequential map (viridis)
    lut = viewer.surface_actor.mapper.lookup_table
    assert np.allclose(np.asarray(lut.GetTableValue(0))[:3], colormap("distance")(0.0)[:3], atol=0.02)
    count = viewer.evaluations
    viewer.set_method("dense")
    assert viewer.method == "dense" and viewer.evaluations == count + 1
    assert np.allclose(viewer.last.values, truth, atol=1e-8 * truth.max())
    with pytest.raises(ValueError):
        viewer.set_filter("gaussian-blur")
    with pytest.raises(ValueError):
        viewer.on_time(-1.0)
    with pytest.raises(ValueError):
        viewer.on_pick(lap.n)
    assert viewer.filter == "biharmonic" and viewer.source == 5


def test_separate_scales_stay_separate(sphere):
    V, F = sphere
    f1, f2 = V[:, 0], 100 * V[:, 1]
    p = plot_levelsets([(V, F), (V, F)], [f1, f2], shared_scale=False, off_screen=True,
                       window_size=(300, 150))
    ranges = []
    for r in p.renderers:
        for a in r.actors.values():
            m = getattr(a, "mapper", None)
            if m is not None and m.dataset is not None and m.dataset.n_cells == len(F):
                ranges.append(tuple(m.scalar_range))
    p.close()
    assert ranges[0] == pytest.approx((f1.min(), f1.max()))
    assert ranges[1] == pytest.approx((f2.min(), f2.max()))


# ---- colour maps by meaning ----------------------------------------------------------------
def test_colour_kind_by_meaning():
    from spectral_igl.viz import color_kind

    assert color_kind([0.0, 0.5, 2.0]) == "sequential"
    assert color_kind([-1.0, 0.5, 2.0]) == "diverging"
    assert color_kind([-1e-13, 0.5, 2.0]) == "sequential"  # rounding below zero is not a sign
    assert color_kind([-3.0, -1.0]) == "sequential"
    assert color_kind([-1.0, 1.0], "distance") == "sequential"
    div = colormap("diverging")
    lo, mid, hi = (np.asarray(div(x)[:3]) for x in (0.0, 0.5, 1.0))
    # blue end, near-white centre, red end: the two ends are far apart
    assert lo[2] > lo[0] and hi[0] > hi[2] and np.all(mid > 0.9)
    assert np.linalg.norm(lo - hi) > 0.6  # (the hue circle: 0)


def _mapper_of_f(plotter, n_cells=None):
    out = []
    for r in plotter.renderers:
        for a in r.actors.values():
            m = getattr(a, "mapper", None)
            if m is not None and m.dataset is not None and "f" in m.dataset.point_data and \
                    m.scalar_visibility and m.dataset.n_cells and m.dataset.n_lines == 0 and \
                    (n_cells is None or m.dataset.n_cells == n_cells):
                out.append(m)
    return out


def test_signed_kernel_is_diverging_and_centred(sphere):
    """A biharmonic kernel column takes both signs: its scale is [-a, a] and its ends differ."""
    import spectral_igl as sig

    V, F = sphere
    lap = sig.laplacian(V, F)
    evals, X = sig.dense_eigs(lap)
    phi = np.zeros_like(evals)
    phi[1:] = 1.0 / evals[1:]
    k = X @ (phi * X[0])  # biharmonic kernel column (pseudo-inverse of L~)
    assert k.min() < 0 < k.max()
    p = plot_levelsets((V, F), k, sources=[0], off_screen=True, window_size=(200, 200))
    (m,) = _mapper_of_f(p, len(F))
    a = max(abs(k.min()), abs(k.max()))
    assert tuple(m.scalar_range) == pytest.approx((-a, a))
    lut = m.lookup_table
    first, last = np.asarray(lut.GetTableValue(0))[:3], np.asarray(lut.GetTableValue(lut.GetNumberOfTableValues() - 1))[:3]
    assert np.linalg.norm(first - last) > 0.6
    assert p.spectral_igl_views[0]["kind"] == "diverging"
    p.close()


def test_unreached_components_grey_and_out_of_scale():
    """Two spheres and isolated vertices: the scale is that of the source's sphere."""
    from data_generators import icosphere

    from spectral_igl.viz import reached_vertices, to_pyvista

    V1, F1 = icosphere(2)
    V = np.vstack([V1, V1 + [3.0, 0.0, 0.0], [[0.0, 5.0, 0.0], [0.0, -5.0, 0.0]]])
    F = np.vstack([F1, F1 + len(V1)])
    n1 = len(V1)
    f = np.concatenate([np.linalg.norm(V1 - V1[0], axis=1),
                        np.full(n1, 50.0), [781.0, 900.0]])  # far values off the source's part
    mesh, _ = to_pyvista((V, F))
    reach = reached_vertices(mesh, [0])
    assert reach.sum() == n1 and reach[:n1].all()
    assert reached_vertices(mesh).sum() == 2 * n1  # without sources: every vertex of a cell
    p = plot_levelsets((V, F), f, sources=[0], off_screen=True, window_size=(300, 300), camera="+z")
    coloured = _mapper_of_f(p)
    assert len(coloured) == 1 and coloured[0].dataset.n_cells == len(F1)
    assert tuple(coloured[0].scalar_range) == pytest.approx((0.0, f[:n1].max()))
    grey = [a for a in p.renderer.actors.values() if getattr(a, "mapper", None) is not None
            and a.mapper.dataset is not None and a.mapper.dataset.n_cells == len(F1)
            and not a.mapper.scalar_visibility]
    assert len(grey) == 1
    img = p.screenshot(return_img=True)
    p.close()
    assert colour_fraction(img, (150, 150, 150), tol=45) > 0.01  # the grey sphere is drawn


def test_per_panel_sources_and_markers(sphere):
    V, F = sphere
    p = plot_levelsets([(V, F), (V, F)], [V[:, 0] + 2, V[:, 1] + 2], sources=[[0], [5]],
                       off_screen=True, window_size=(400, 200))
    marks = []
    for r in p.renderers:
        pts = [np.asarray(a.mapper.dataset.points) for a in r.actors.values()
               if getattr(a, "mapper", None) is not None and a.mapper.dataset is not None
               and a.mapper.dataset.n_points == 1]
        marks.append(pts)
    p.close()
    # each panel: a white rim exactly at its source, a dark dot just in front of it
    assert np.allclose(marks[0][0], V[0]) and np.allclose(marks[1][0], V[5])
    assert all(len(m) == 2 for m in marks)


# ---- the camera -----------------------------------------------------------------------------
def _depth_check(plotter, point):
    """Whether ``point`` is the nearest surface at its pixel (z-buffer of the last render)."""
    from vtkmodules.vtkRenderingCore import vtkCoordinate

    for a in plotter.renderer.actors.values():  # the source markers stand in front: hide them
        m = getattr(a, "mapper", None)
        if m is not None and m.dataset is not None and m.dataset.n_points == 1:
            a.visibility = False
    plotter.screenshot(return_img=True)
    zbuf = plotter.get_image_depth(fill_value=-np.inf, reset_camera_clipping_range=False)
    c = vtkCoordinate()
    c.SetCoordinateSystemToWorld()
    c.SetValue(*map(float, point))
    x, y = c.GetComputedDoubleDisplayValue(plotter.renderer)
    h = zbuf.shape[0]
    row, col = int(round(h - 1 - y)), int(round(x))
    if not (0 <= row < h and 0 <= col < zbuf.shape[1]):
        return False
    eye = np.asarray(plotter.camera.position)
    fwd = np.asarray(plotter.camera.focal_point) - eye
    fwd /= np.linalg.norm(fwd)
    depth = -float((np.asarray(point) - eye) @ fwd)  # pyvista's depth: minus the distance along the view
    window = zbuf[max(row - 1, 0):row + 2, max(col - 1, 0):col + 2]
    scale = float(np.linalg.norm(np.ptp(np.asarray(plotter.bounds).reshape(3, 2), axis=1)))
    # visible: the nearest surface at that pixel is the point's own (not something in front)
    window = window[np.isfinite(window)]
    return bool(window.size and np.min(window) <= depth + 1e-2 * scale)


def test_auto_camera_sees_a_source_hidden_from_the_centre():
    """A point on the inner equator of a torus is hidden from the centre direction and
    from its normal (the tube opposite is in the way); the camera must find a view."""
    from data_generators import torus

    from spectral_igl.viz import auto_view, to_pyvista

    V, F = torus(1.0, 0.4, n_major=48, n_minor=24)
    src = int(np.argmin(np.linalg.norm(V - [0.6, 0.0, 0.0], axis=1)))
    surface, _ = to_pyvista((V, F))
    d, visible = auto_view(surface, V[src])
    assert visible == 1.0
    assert abs(d[2]) > 0.3  # seen from above or below, through the hole
    f = np.linalg.norm(V - V[src], axis=1)
    p = plot_levelsets((V, F), f, sources=[src], off_screen=True, window_size=(400, 400))
    assert _depth_check(p, V[src])
    # a fixed view from +x sees the outer side only: the z-buffer says the source is hidden
    p2 = plot_levelsets((V, F), f, sources=[src], off_screen=True, window_size=(400, 400), camera="+x")
    assert not _depth_check(p2, V[src])
    assert p2.spectral_igl_views[0]["direction"] == pytest.approx([1.0, 0.0, 0.0])
    p.close()
    p2.close()


def test_named_and_explicit_views(sphere):
    from spectral_igl.viz import parse_view

    assert parse_view("auto") == ("auto", None)
    mode, d = parse_view("-z")
    assert mode == "direction" and np.allclose(d, [0, 0, -1])
    assert np.allclose(parse_view("1,1,0")[1], np.array([1, 1, 0]) / np.sqrt(2))
    assert np.allclose(parse_view([0, 2, 0])[1], [0, 1, 0])
    with pytest.raises(ValueError, match="camera/view"):
        parse_view("sideways")
    with pytest.raises(ValueError, match="non-zero"):
        parse_view([0, 0, 0])
    V, F = sphere
    p = plot_levelsets((V, F), V[:, 0], camera="-y", off_screen=True, window_size=(200, 200))
    eye, focal = np.asarray(p.camera.position), np.asarray(p.camera.focal_point)
    assert (eye - focal) / np.linalg.norm(eye - focal) == pytest.approx([0, -1, 0], abs=0.05)
    p.close()


def _real_mesh_pictures(mesh_dir, tmp_path):
    """Source visible (z-buffer) and scale from the source's component, on real meshes."""
    import spectral_igl as sig
    from spectral_igl.io import read_mesh

    from spectral_igl.viz import reached_vertices, to_pyvista

    for name, source in (("spot.obj", 100), ("cow.obj", 0), ("homer.obj", 0), ("fertility.off", 0),
                         ("beetle.obj", 0), ("suzanne.obj", 10), ("stanford-bunny.obj", 100)):
        V, F = read_mesh(mesh_dir / name)
        lap = sig.laplacian(V, F)
        d = np.asarray(sig.diffusion_distance(lap, 1e-2 * float(lap.area()), source))
        p = plot_levelsets((V, F), d, sources=[source], off_screen=True, window_size=(400, 400))
        assert p.spectral_igl_views[0]["visible"] >= 0.75, name  # the source, most neighbours
        assert _depth_check(p, V[source]), name
        reach = reached_vertices(to_pyvista((V, F))[0], [source])
        (m,) = _mapper_of_f(p)
        assert tuple(m.scalar_range) == pytest.approx((d[reach].min(), d[reach].max())), name
        p.close()


@pytest.mark.filterwarnings("ignore:.*referenced by no element")
def test_real_meshes_source_visible_and_scale(shared_meshes, tmp_path):
    _real_mesh_pictures(shared_meshes, tmp_path)


# ---- the viewer: picking by clicks, controls, geodesic mode, no display -------------------
def _display_xy(plotter, point):
    from vtkmodules.vtkRenderingCore import vtkCoordinate

    c = vtkCoordinate()
    c.SetCoordinateSystemToWorld()
    c.SetValue(*map(float, point))
    return c.GetComputedDisplayValue(plotter.renderer)


def _click(plotter, x, y, release_at=None):
    """A left press and release through the interactor, as a mouse gives them."""
    inter = plotter.iren.interactor
    inter.SetEventInformation(int(x), int(y), 0, 0, "\0", 0)
    inter.InvokeEvent("LeftButtonPressEvent")
    rx, ry = release_at if release_at is not None else (x, y)
    inter.SetEventInformation(int(rx), int(ry), 0, 0, "\0", 0)
    inter.InvokeEvent("LeftButtonReleaseEvent")


def test_viewer_click_picks_the_vertex_under_the_mouse(viewer):
    """Simulated clicks at the pixels of front-facing vertices make each the source."""
    import spectral_igl as sig

    lap = viewer.lap
    V = lap.data["V"]
    evals, X = sig.dense_eigs(lap)
    viewer.screenshot()
    eye = np.asarray(viewer.plotter.camera.position)
    facing = np.flatnonzero(np.einsum("ij,ij->i", V, (eye - V)) / np.linalg.norm(eye - V, axis=1) > 0.6)
    facing = [int(v) for v in facing if v != viewer.source][:5]
    assert len(facing) >= 3
    for v in facing:
        x, y = _display_xy(viewer.plotter, V[v])
        _click(viewer.plotter, x, y)
        assert viewer.source == v
        assert np.allclose(viewer.last.values, X @ (np.exp(-viewer.t * evals) * X[v]), atol=1e-6)
    picks = viewer.picks
    # a drag rotates: it does not pick
    x, y = _display_xy(viewer.plotter, V[facing[0]])
    _click(viewer.plotter, x, y, release_at=(x + 40, y))
    assert viewer.picks == picks and viewer.source == facing[-1]
    # a click on the background picks nothing
    assert viewer.pick_at(2, 2) is None and viewer.source == facing[-1]


def test_viewer_controls_only_where_they_apply(viewer):
    from data_generators import icosphere

    from spectral_igl.applications.geodesics import geodesic_distance

    assert viewer.slider is not None  # heat: a time
    viewer.set_filter("biharmonic")
    assert viewer.slider is None
    viewer.set_filter("wave")
    assert viewer.slider is not None
    viewer.set_quantity("geodesic")
    assert viewer.slider is None and "filter" not in viewer.status()
    viewer.on_pick(7)
    assert np.array_equal(viewer.last.values, geodesic_distance(viewer.lap, 7))
    V = icosphere(2)[0]
    great_circle = np.arccos(np.clip(V @ V[7], -1.0, 1.0))
    assert np.max(np.abs(viewer.last.values - great_circle)) < 0.1 * np.pi
    assert viewer.surface_actor.mapper.scalar_range[0] == pytest.approx(0.0, abs=1e-12)


def test_viewer_refuses_a_window_without_display_before_any_work(monkeypatch):
    from data_generators import icosphere

    import spectral_igl.viz._viewer as viewer_module
    from spectral_igl.viz import Viewer

    monkeypatch.setattr(viewer_module, "display_available", lambda: False)
    calls = []
    monkeypatch.setattr(viewer_module, "evaluate", lambda *a, **k: calls.append(1))
    with pytest.raises(RuntimeError, match="no display"):
        Viewer(icosphere(1), off_screen=False)
    assert calls == []


def test_cli_view_without_display_says_so_at_once(tmp_path):
    import os
    import time

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "spectral_igl.cli", "view", "--shape", "sphere",
                          "--level", "5"], capture_output=True, text=True, env=env, timeout=120)
    seconds = time.perf_counter() - start
    assert out.returncode == 2
    assert "no display" in out.stderr and "--screenshot" in out.stderr
    assert "leak" not in out.stderr.lower()
    assert len(out.stderr.strip().splitlines()) == 1
    # no Laplacian was built: far less than building one at level 5 (10k vertices) and drawing
    assert seconds < 20


def test_cli_view_and_cmap_options(tmp_path):
    from spectral_igl.cli import main

    path = tmp_path / "d.png"
    assert main(["distance", "--shape", "sphere", "--level", "2", "--view", "+x", "--cmap", "viridis",
                 "-o", str(path), "-q"]) == 0
    assert_not_blank(path)
    assert main(["distance", "--shape", "sphere", "--level", "2", "--view", "sideways",
                 "-o", str(path), "-q"]) == 2


# ---- a real window under a virtual X server, clicked by xdotool (skipped without them) ---
_XVFB_CLICKS = r'''
import os
import subprocess
import sys
import time
import numpy as np
from data_generators import icosphere
import spectral_igl as sig
from spectral_igl.viz import Viewer
from vtkmodules.vtkRenderingCore import vtkCoordinate

lap = sig.laplacian(*icosphere(2))
v = Viewer(lap, quantity="kernel", filter="heat", t=0.1, source=3, off_screen=False, window_size=(400, 400))
v.plotter.show(interactive_update=True, auto_close=False)
for _ in range(20):
    v.plotter.update(); time.sleep(0.05)
V = lap.data["V"]
eye = np.asarray(v.plotter.camera.position)
facing = [int(i) for i in np.flatnonzero(np.einsum("ij,ij->i", V, eye - V) / np.linalg.norm(eye - V, axis=1) > 0.6) if i != 3][:3]
wid = []
for _ in range(100):  # the window maps asynchronously
    wid = subprocess.run(["xdotool", "search", "--onlyvisible", "--pid", str(os.getpid())],
                         capture_output=True, text=True).stdout.split()
    wid = wid or subprocess.run(["xdotool", "search", "--onlyvisible", "--name", "."],
                                capture_output=True, text=True).stdout.split()
    if wid:
        break
    v.plotter.update(); time.sleep(0.05)
print("windows", wid, file=sys.stderr)
w = wid[-1]
got = []
for k in facing:
    c = vtkCoordinate(); c.SetCoordinateSystemToWorld(); c.SetValue(*map(float, V[k]))
    x, y = c.GetComputedDisplayValue(v.plotter.renderer)
    h = v.plotter.window_size[1]
    subprocess.run(["xdotool", "mousemove", "--window", w, str(x), str(h - 1 - y)], check=True)
    for _ in range(5):
        v.plotter.update(); time.sleep(0.05)
    subprocess.run(["xdotool", "click", "--window", w, "1"], check=True)
    for _ in range(20):
        v.plotter.update(); time.sleep(0.05)
    got.append((k, v.source))
print("RESULT", got)
v.close()
'''


def test_viewer_real_clicks_under_xvfb(tmp_path):
    """An on-screen viewer under Xvfb: xdotool moves the mouse over a vertex and clicks."""
    import os
    import shutil

    if not (shutil.which("xvfb-run") and shutil.which("xdotool")):
        pytest.skip("xvfb-run and xdotool are not installed")
    script = tmp_path / "clicks.py"
    script.write_text(_XVFB_CLICKS)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    env.pop("VTK_DEFAULT_OPENGL_WINDOW", None)  # set for off-screen rendering in this process
    out = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", sys.executable, str(script)],
                         capture_output=True, text=True, timeout=300, env=env)
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("RESULT")]
    assert out.returncode == 0 and lines, out.stderr[-2000:]
    picks = eval(lines[0][len("RESULT"):])  # [(vertex clicked, source after the click)]
    assert len(picks) == 3 and all(k == s for k, s in picks), picks
    assert "leak" not in out.stderr.lower()


def test_volume_cut_passes_through_an_interior_source():
    """A tetrahedral box, source inside: the cut shows it, and the scale starts at its value."""
    from data_generators import box_tets

    V, T = box_tets((10, 8, 6))
    lo, hi = V.min(0), V.max(0)
    s = int(np.argmin(np.linalg.norm(V - (lo + 0.4 * (hi - lo)), axis=1)))
    assert np.all(V[s] > lo) and np.all(V[s] < hi)  # interior
    f = np.linalg.norm(V - V[s], axis=1)
    p = plot_levelsets((V, T), f, sources=[s], off_screen=True, window_size=(400, 400))
    assert p.spectral_igl_views[0]["clim"] == pytest.approx((0.0, f.max()))
    assert _depth_check(p, V[s])
    p.close()
