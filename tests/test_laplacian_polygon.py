"""Polygon meshes: the polygon Laplacian, reading polygon files, quads never taken for tets."""
import warnings

import numpy as np
import pytest

import spectral_igl as sig
from conftest import read_shared_mesh
from data_generators import box_tets, icosphere, quad_sphere, sphere_eigenvalues
from spectral_igl.io import read_mesh
from spectral_igl.laplacian.polygon import virtual_vertices

EXACT16 = sphere_eigenvalues(17)[1:]


def _first16(lap):
    ev, _ = sig.eigs(lap, 17)    # certified: every copy of the multiple eigenvalues
    return np.max(np.abs(ev[1:] - EXACT16) / EXACT16)


def _mixed_mesh():
    """A bumpy grid of non-planar quads, triangles and one hexagon (n = 7 x 6 vertices)."""
    nx, ny = 7, 6
    x, y = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float), indexing="ij")
    z = 0.3 * np.sin(x) * np.cos(1.3 * y)
    V = np.c_[x.ravel(), y.ravel(), z.ravel()]
    idx = np.arange(nx * ny).reshape(nx, ny)
    faces = []
    for i in range(nx - 1):
        for j in range(ny - 1):
            if i == nx - 2 and j in (1, 2):
                continue                      # these two cells make the hexagon below
            a, b, c, d = idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]
            if (i + j) % 3 == 0:
                faces += [[a, b, c], [a, c, d]]
            else:
                faces.append([a, b, c, d])
    faces.append([idx[nx - 2, 1], idx[nx - 1, 1], idx[nx - 1, 2], idx[nx - 1, 3], idx[nx - 2, 3],
                  idx[nx - 2, 2]])
    return V, faces


def test_equal_to_cotan_on_triangles():
    V, F = icosphere(2)
    V = V * [1.0, 0.8, 1.3]
    a, b = sig.laplacian(V, F, weights="cotan", mass="full"), sig.polygon_laplacian(V, F)
    assert abs(a.L - b.L).max() < 1e-12 * abs(a.L).max()
    assert abs(a.B - b.B).max() < 1e-12 * abs(a.B).max()
    lumped = sig.polygon_laplacian(V, [list(f) for f in F], mass="lumped")
    bary = sig.laplacian(V, F, mass="barycentric")
    assert abs(lumped.B - bary.B).max() < 1e-14 and abs(lumped.L - a.L).max() < 1e-12
    _, W = virtual_vertices(V, F)
    assert np.allclose(W, 1.0 / 3.0)


@pytest.mark.parametrize("mass", ["full", "lumped"])
def test_guarantees_on_a_mixed_non_planar_polygon_mesh(mass):
    V, faces = _mixed_mesh()
    lap = sig.polygon_laplacian(V, faces, mass=mass)
    L, B = lap.L.toarray(), lap.B.toarray()
    assert lap.domain == "polygon" and lap.n_components == 1
    assert np.array_equal(L, L.T) and np.abs(L.sum(axis=1)).max() < 1e-13 * np.abs(L).max()
    ev = np.linalg.eigvalsh(L)
    assert ev.min() > -1e-12 * ev.max() and np.sum(ev < 1e-10 * ev.max()) == 1
    assert np.linalg.eigvalsh(B).min() > 0 and np.allclose(B, B.T)
    # the measure is the area of the refined fans: sum of the triangle areas around c_f
    area = 0.0
    for f in faces:
        X = V[f]
        c, _ = virtual_vertices(V, np.array([f]))
        area += 0.5 * np.linalg.norm(np.cross(X - c, np.roll(X, -1, axis=0) - c), axis=1).sum()
    assert lap.area() == pytest.approx(area, rel=1e-12)
    # linear precision on a planar polygon mesh: L x = 0 at interior vertices
    Vp = V.copy()
    Vp[:, 2] = 0.0
    lp = sig.polygon_laplacian(Vp, faces, mass=mass)
    interior = np.flatnonzero((Vp[:, 0] > 0) & (Vp[:, 0] < 6) & (Vp[:, 1] > 0) & (Vp[:, 1] < 5))
    assert np.abs(lp.L @ Vp[:, :2])[interior].max() < 1e-12


def test_virtual_vertex_of_a_planar_regular_polygon_is_its_centre():
    t = np.linspace(0, 2 * np.pi, 7)[:-1]
    V = np.c_[np.cos(t) + 2, np.sin(t) - 1, np.zeros(6)]
    C, W = virtual_vertices(V, np.arange(6)[None])
    assert np.allclose(C, [[2.0, -1.0, 0.0]]) and np.allclose(W, 1 / 6)


def test_quad_sphere_converges_to_the_sphere_spectrum():
    errs = []
    for n in (8, 16, 32):
        V, Q = quad_sphere(n)
        lap = sig.laplacian(V, Q)          # (m, 4) quads: routed to the polygon Laplacian
        assert lap.domain == "polygon"
        errs.append(_first16(lap))
    # second order: the error falls about 4x per halving of the quad size
    assert errs[1] < 0.3 * errs[0] and errs[2] < 0.3 * errs[1], errs
    assert errs[2] < 0.004, errs


def test_neumann_rectangle_with_quads():
    # flat [0, 2] x [0, 1] grid of (slightly perturbed) quads: π²(i²/4 + j²)
    nx, ny = 41, 21
    x, y = np.meshgrid(np.linspace(0, 2, nx), np.linspace(0, 1, ny), indexing="ij")
    rng = np.random.default_rng(2)
    jit = 0.15 * (2.0 / (nx - 1)) * rng.standard_normal((nx, ny, 2))
    jit[[0, -1], :, 0] = 0
    jit[:, [0, -1], 1] = 0
    V = np.c_[(x + jit[..., 0]).ravel(), (y + jit[..., 1]).ravel(), np.zeros(nx * ny)]
    idx = np.arange(nx * ny).reshape(nx, ny)
    Q = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], -1).reshape(-1, 4)
    lap = sig.laplacian(V, Q)
    assert lap.domain == "polygon" and lap.area() == pytest.approx(2.0, rel=1e-12)
    ev, _ = sig.eigs(lap, 8)
    i, j = np.meshgrid(np.arange(6), np.arange(4), indexing="ij")
    exact = np.sort((np.pi ** 2 * (i ** 2 / 4.0 + j ** 2)).ravel())[:8]
    assert np.max(np.abs(ev[1:] - exact[1:]) / exact[1:]) < 0.01, (ev, exact)


def test_quads_are_never_taken_for_tetrahedra():
    V, Q = quad_sphere(6)
    assert sig.laplacian(V, Q).domain == "polygon"
    assert sig.laplacian(V, Q, elements="polygon").domain == "polygon"
    # a tetrahedral mesh stays one, even a single tetrahedron
    Vt, T = box_tets((4, 3, 3))
    assert sig.laplacian(Vt, T).domain == "tet"
    assert sig.laplacian(np.r_[np.eye(3), [[0.0, 0, 0]]], np.array([[0, 1, 2, 3]])).domain == "tet"
    # forcing a quad to be a tetrahedron: it is flat, hence degenerate
    square = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    with pytest.raises(ValueError, match="degenerate"):
        sig.laplacian(square, np.array([[0, 1, 2, 3]]), elements="tet")
    assert sig.laplacian(square, np.array([[0, 1, 2, 3]])).area() == pytest.approx(1.0)
    # ragged face lists are polygons; elements must be valid
    assert sig.laplacian(*_mixed_mesh()).domain == "polygon"
    with pytest.raises(ValueError, match="elements"):
        sig.laplacian(V, Q, elements="quad")
    with pytest.raises(ValueError, match="cotan"):
        sig.laplacian(V, Q, weights="uniform")


def test_real_quad_mesh(tmp_path):
    V, Q = read_shared_mesh("horse_quad.obj")                  # triangulated by default
    assert Q.shape[1] == 3
    from conftest import MESH_DIR

    Vq, Fq = read_mesh(MESH_DIR / "horse_quad.obj", polygons=True)
    assert isinstance(Fq, np.ndarray) and Fq.shape[1] == 4 and np.array_equal(Vq, V)
    lap = sig.laplacian(Vq, Fq)
    assert lap.domain == "polygon" and lap.n_components == 1
    tri = sig.laplacian(V, Q)
    # the mass is the surface area (of the refined fans), within the non-planarity of the quads
    assert lap.area() == pytest.approx(tri.area(), rel=5e-3)
    assert np.abs(lap.L @ np.ones(lap.n)).max() < 1e-12 * abs(lap.L).max()
    # the low spectrum agrees with the triangulation's
    a, b = sig.eigs(lap, 11)[0][1:], sig.eigs(tri, 11)[0][1:]
    assert np.max(np.abs(a / b - 1)) < 0.03, (a, b)


def test_read_polygon_files(tmp_path):
    obj = tmp_path / "m.obj"
    obj.write_text("# mixed\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nvt 0 0\n"
                   "f 1/1 2/1 3/1 4/1\nf -5 5 6 -4\n")
    V, F = read_mesh(obj, polygons=True)
    assert V.shape == (6, 3) and F.tolist() == [[0, 1, 2, 3], [1, 4, 5, 2]]
    V3, F3 = read_mesh(obj)                                  # default: triangles, as before
    assert F3.shape == (4, 3)
    off = tmp_path / "m.off"
    off.write_text("OFF\n6 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2 1.5 0\n4 0 1 2 3\n3 1 4 5\n")
    V, F = read_mesh(off, polygons=True)
    assert isinstance(F, list) and [f.tolist() for f in F] == [[0, 1, 2, 3], [1, 4, 5]]
    lap = sig.laplacian(V, F)
    assert lap.domain == "polygon" and lap.area() == pytest.approx(1.0 + 0.75, rel=1e-12)
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(ValueError, match="outside"):
        read_mesh(bad, polygons=True)
    with pytest.raises(TypeError, match="polygons"):
        read_mesh(obj, polygons="yes")


def test_bad_polygon_input():
    V, faces = _mixed_mesh()
    with pytest.raises(ValueError, match="at least 3"):
        sig.polygon_laplacian(V, [[0, 1]])
    with pytest.raises(ValueError, match="out of range"):
        sig.polygon_laplacian(V, [[0, 1, 500]])
    with pytest.raises(TypeError, match="faces"):
        sig.polygon_laplacian(V, 3)
    with pytest.raises(ValueError, match="mass"):
        sig.polygon_laplacian(V, faces, mass="voronoi")
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        lap = sig.polygon_laplacian(V, faces + [[0, 0, 1, 2]])
    assert any("degenerate" in str(x.message) for x in w) and lap.n == len(V)


# ---- mean-value weights --------------------------------------------------------------

def test_mean_value_weights():
    from spectral_igl.laplacian.mesh import mean_value_weights

    V, F = icosphere(2)
    rng = np.random.default_rng(1)
    V = V + 0.05 * rng.standard_normal(V.shape)
    W = mean_value_weights(V, F)
    assert W.min() >= 0 and np.all(W.data > 0)          # positive for every triangle
    assert abs(W - W.T).max() > 1e-3 * W.max()           # and not symmetric
    lap = sig.laplacian(V, F, weights="mean_value")
    Wsym = 0.5 * (W + W.T).toarray()
    L = lap.L.toarray()
    off = ~np.eye(len(V), dtype=bool)
    assert np.allclose(L[off], -Wsym[off]) and np.abs(L.sum(axis=1)).max() < 1e-12 * np.abs(L).max()
    assert np.linalg.eigvalsh(L).min() > -1e-10
    # Floater's mean value property: an interior vertex of a planar mesh is the
    # W-weighted mean of its neighbours (linear precision of the unsymmetrised weights)
    x, y = np.meshgrid(np.arange(6.0), np.arange(6.0), indexing="ij")
    Vp = np.c_[x.ravel(), y.ravel()] + 0.2 * rng.standard_normal((36, 2))
    from scipy.spatial import Delaunay

    Fp = Delaunay(Vp).simplices
    Wp = mean_value_weights(Vp, Fp)
    interior = np.flatnonzero((x.ravel() > 0) & (x.ravel() < 5) & (y.ravel() > 0) & (y.ravel() < 5))
    mean = (Wp @ Vp) / np.asarray(Wp.sum(axis=1))
    assert np.abs(mean[interior] - Vp[interior]).max() < 1e-12
    with pytest.raises(ValueError, match="triangle"):
        sig.laplacian(*box_tets((3, 3, 3)), weights="mean_value")
