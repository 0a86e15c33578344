"""spectral_igl.viz: level-set pictures off screen, colour conventions, the viewer's callbacks."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

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


pytestmark = pytest.mark.usefixtures("one_blas_thread")


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
    with pytest.raises(ImportError, match=r'pip install "spectral_igl\[viz\]"'):
        _backend.pyvista()


def test_levelset_values_uniform_inside_range():
    v = levelset_values(-1.0, 3.0, 7)
    assert v.shape == (7,)
    assert np.allclose(np.diff(v), 0.5) and v[0] == pytest.approx(-0.5) and v[-1] == pytest.approx(2.5)
    assert levelset_values(1.0, 1.0, 5).size == 0


def test_colour_conventions():
    dist = colormap("distance")
    assert np.allclose(dist(0.0)[:3], (0, 0, 1)) and np.allclose(dist(1.0)[:3], (1, 0, 0))
    cyc = colormap("cyclic")
    # red -> yellow -> green -> cyan -> blue -> magenta -> red at sixths of the range
    expected = [(1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1), (1, 0, 1), (1, 0, 0)]
    for k, rgb in enumerate(expected):
        assert np.allclose(cyc(k / 6)[:3], rgb, atol=0.02), (k, cyc(k / 6))
    with pytest.raises(ValueError, match="unknown colormap"):
        colormap("no-such-map")


def test_distance_picture_blue_at_source_red_far(tmp_path, sphere):
    V, F = sphere
    d = np.arccos(np.clip(V @ V[0], -1, 1))
    path = tmp_path / "d.png"
    p = plot_levelsets((V, F), d, sources=[0], filename=path, window_size=(300, 300))
    img = assert_not_blank(path)
    assert img.shape[:2] == (300, 300)
    # camera faces the source: plenty of (shaded) blue near the centre of the picture
    centre = img[110:190, 110:190]
    assert colour_fraction(centre, (0, 0, 200), tol=90) > 0.05
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
    # distances use the blue-to-red map
    lut = viewer.surface_actor.mapper.lookup_table
    assert np.allclose(np.asarray(lut.GetTableValue(0))[:3], (0, 0, 1), atol=0.02)
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
