"""Files in and out (fields with their mesh), mesh objects of other packages, progress bars."""
from __future__ import annotations

import numpy as np
import pytest

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl.io import read_mesh, write_mesh

meshio = pytest.importorskip("meshio")


# ---- fields written with their mesh ------------------------------------------------------
@pytest.mark.parametrize("ext", [".vtu", ".vtk"])
def test_vtk_round_trip_of_fields_on_triangles_and_tets(tmp_path, ext):
    V, F = icosphere(2)
    d = sig.geodesic_distance((V, F), 0)
    write_mesh(tmp_path / f"s{ext}", V, F, fields={"geodesic": d, "normal": V})
    m = meshio.read(tmp_path / f"s{ext}")
    assert np.array_equal(m.cells_dict["triangle"], F) and np.allclose(m.points, V)
    assert np.array_equal(m.point_data["geodesic"], d)
    assert m.point_data["normal"].shape == (len(V), 3)
    # the exact great-circle distance is what was written (to the heat method's accuracy)
    exact = np.arccos(np.clip(V @ V[0], -1, 1))
    assert np.abs(m.point_data["geodesic"] - exact).max() < 0.1
    Vt, T = sig.tetrahedralize(V, F, edge_length_fac=0.3)
    h = sig.hks(sig.laplacian(Vt, T), [1e-2, 1e-1])
    write_mesh(tmp_path / f"t{ext}", Vt, T, fields={"t=0.01": h[:, 0], "t=0.1": h[:, 1]})
    m = meshio.read(tmp_path / f"t{ext}")
    assert np.array_equal(m.cells_dict["tetra"], T)
    assert np.array_equal(m.point_data["t=0.1"], h[:, 1]) and m.point_data["t=0.01"].shape == (len(Vt),)


def test_ply_fields_columns_complex_and_reserved_names(tmp_path):
    V, F = icosphere(1)
    z = V[:, 0] + 1j * V[:, 1]
    write_mesh(tmp_path / "a.ply", V, F, fields={"x": V[:, 2], "vec": V, "wave": z})
    m = meshio.read(tmp_path / "a.ply")
    pd = m.point_data
    assert np.allclose(pd["x_"], V[:, 2])                  # x names the coordinates
    assert all(np.allclose(pd[f"vec_{j}"], V[:, j]) for j in range(3))
    assert np.allclose(pd["wave.real"], z.real) and np.allclose(pd["wave.imag"], z.imag)
    V2, F2 = read_mesh(tmp_path / "a.ply")                  # still a readable triangle mesh
    assert np.allclose(V2, V) and np.array_equal(F2, F)


def test_write_mesh_rejects_what_the_format_cannot_hold(tmp_path):
    V, F = icosphere(1)
    with pytest.raises(ValueError, match="cannot hold fields"):
        write_mesh(tmp_path / "a.obj", V, F, fields={"f": V[:, 0]})
    with pytest.raises(ValueError, match=r"field 'f' must have shape \(42,\)"):
        write_mesh(tmp_path / "a.vtu", V, F, fields={"f": V[:-1, 0]})
    with pytest.raises(TypeError, match="fields must be a dict"):
        write_mesh(tmp_path / "a.vtu", V, F, fields=[V[:, 0]])
    Vt, T = sig.tetrahedralize(V, F, edge_length_fac=0.5)
    with pytest.raises(ValueError, match="tetrahedra cannot be written to .ply"):
        write_mesh(tmp_path / "a.ply", Vt, T, fields={"f": Vt[:, 0]})
    with pytest.raises(ValueError, match="unsupported mesh format"):
        write_mesh(tmp_path / "a.xyz", V, F)


# ---- mesh objects ------------------------------------------------------------------------
def _same(a, b):
    return abs(a.L - b.L).max() == 0 and abs(a.B - b.B).max() == 0


def test_pyvista_meshes_are_accepted():
    pv = pytest.importorskip("pyvista")
    V, F = icosphere(2)
    poly = pv.PolyData(V, np.c_[np.full(len(F), 3), F].ravel())
    ref = sig.laplacian(V, F)
    assert _same(sig.laplacian(poly), ref)
    assert _same(sig.laplacian(poly, mass="lumped"), sig.laplacian(V, F, mass="lumped"))
    assert _same(sig.anisotropic_laplacian(poly, alpha=1.0), sig.anisotropic_laplacian(V, F, alpha=1.0))
    assert np.array_equal(sig.geodesic_distance(poly, 5), sig.geodesic_distance((V, F), 5))
    cp = sig.critical_points(poly, V[:, 2])
    assert (cp.n_minima, cp.n_maxima, cp.n_saddles) == (1, 1, 0)
    # a point cloud: its points
    pc = sig.point_cloud_laplacian(pv.PolyData(V), k=12)
    assert _same(pc, sig.point_cloud_laplacian(V, k=12))
    # tetrahedra of an UnstructuredGrid
    Vt, T = sig.tetrahedralize(poly, edge_length_fac=0.3)
    grid = pv.UnstructuredGrid({pv.CellType.TETRA: T}, Vt)
    lt = sig.laplacian(grid)
    assert lt.domain == "tet" and _same(lt, sig.laplacian(Vt, T))


def test_pyvista_polygons_are_fan_triangulated():
    pv = pytest.importorskip("pyvista")
    cube = pv.Cube().clean()                     # 6 quads, 8 vertices
    lap = sig.laplacian(cube)
    assert lap.n == 8 and len(lap.data["F"]) == 12
    # every face of a cube has area side^2: the total area is 6 side^2
    side = np.ptp(np.asarray(cube.points)[:, 0])
    assert np.isclose(lap.area(), 6 * side ** 2)


def test_trimesh_and_meshio_meshes_are_accepted():
    trimesh = pytest.importorskip("trimesh")
    V, F = icosphere(2)
    tm = trimesh.Trimesh(V, F, process=False)
    assert _same(sig.laplacian(tm), sig.laplacian(V, F))
    assert _same(sig.point_cloud_laplacian(trimesh.PointCloud(V), k=12), sig.point_cloud_laplacian(V, k=12))
    Vt, T = sig.tetrahedralize(tm, edge_length_fac=0.3)
    mm = meshio.Mesh(Vt, [("triangle", F[:1]), ("tetra", T)])   # tets win over triangles
    assert _same(sig.laplacian(mm), sig.laplacian(Vt, T))


def test_mesh_objects_bad_input_is_named():
    pv = pytest.importorskip("pyvista")
    V, F = icosphere(1)
    poly = pv.PolyData(V, np.c_[np.full(len(F), 3), F].ravel())
    with pytest.raises(TypeError, match="do not pass F as well"):
        sig.laplacian(poly, F)
    with pytest.raises(TypeError, match="F is missing"):
        sig.laplacian(V)
    with pytest.raises(TypeError, match="F is missing"):
        sig.laplacian(pv.PolyData(V))            # points only
    lines = pv.UnstructuredGrid({pv.CellType.LINE: np.array([[0, 1], [1, 2]])}, V)
    with pytest.raises(ValueError, match="neither tetrahedra nor triangles"):
        sig.laplacian(lines)


# ---- progress ----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def lap():
    return sig.laplacian(*icosphere(4))          # 2,562 vertices


def test_kernel_diagonal_bar_per_pole(lap, capfd):
    d = sig.kernel_diagonal(lap, sig.filters.heat(1e-2), method="selinv", progress=True)
    err = capfd.readouterr().err
    assert "kernel diagonal" in err and "pole" in err and "100%" in err
    d0 = sig.kernel_diagonal(lap, sig.filters.heat(1e-2), method="selinv", progress=False)
    assert capfd.readouterr().err == ""
    assert np.array_equal(d, d0)
    # the bar does not change the numbers: HKS against the dense truth
    evals, X = sig.dense_eigs(lap)
    truth = (X ** 2) @ np.exp(-1e-2 * evals)
    assert np.max(np.abs(d - truth) / truth) < 1e-7


def test_progress_on_long_calls_and_silence_by_default(lap, capfd):
    f = sig.filters.heat(1e-2)
    D = sig.pairwise_spectral_distance(lap, f, np.arange(0, 2562, 20), progress=True, block=32)
    err = capfd.readouterr().err
    assert "pairwise distances" in err and "5/5" in err     # 129 seeds in blocks of 32
    D0 = sig.pairwise_spectral_distance(lap, f, np.arange(0, 2562, 20))
    assert capfd.readouterr().err == ""
    assert np.allclose(D, D0, rtol=1e-12, atol=0)   # blocks give the same distances
    sig.hks(lap, [1e-3, 1e-2, 1e-1], progress=True)
    err = capfd.readouterr().err
    assert "hks" in err and "3/3" in err
    V = lap.data["V"]
    sig.optimal_time(lap, V[:, 0], n_times=12, progress=True)
    assert "optimal time" in capfd.readouterr().err
    sig.geodesic_distance(lap, 0, progress=True)
    assert "heat geodesics" in capfd.readouterr().err
    sig.eigs(lap, 10, progress=True)
    assert "eigs k=10" in capfd.readouterr().err
    sig.kernel_diagonal(lap, f, method="probing", progress=True)
    assert "block" in capfd.readouterr().err
    # silent by default
    sig.hks(lap, [1e-3, 1e-2])
    sig.eigs(lap, 10)
    sig.optimal_time(lap, V[:, 0], n_times=12)
    assert capfd.readouterr().err == ""


def test_progress_context_and_bad_flag(lap, capfd):
    from spectral_igl.progress import NoProgress, enabled, progress_bar

    with enabled():
        sig.hks(lap, [1e-3, 1e-2])
        sig.hks(lap, 1e-3, progress=False)                  # explicit False wins
    err = capfd.readouterr().err
    assert err.count("hks:") >= 1 and "2/2" in err and "1/1" not in err
    assert isinstance(progress_bar(3, "x"), NoProgress)    # off outside the context
    with pytest.raises(TypeError, match="progress must be True, False or None"):
        sig.hks(lap, 1e-3, progress="yes")


def test_mesh_object_cut_at_coincident_points_is_warned():
    """A reader that splits vertices at texture seams cuts the shape: say so."""
    pv = pytest.importorskip("pyvista")
    V, F = icosphere(2)
    cut = V[F].reshape(-1, 3)                  # every triangle with its own three corners
    soup = pv.PolyData(cut, np.c_[np.full(len(F), 3), np.arange(3 * len(F)).reshape(-1, 3)].ravel())
    with pytest.warns(RuntimeWarning, match=r"of the 960 points of the PolyData coincide.*clean\(\)"):
        lap = sig.laplacian(soup)
    assert lap.n_components == len(F)          # what the warning is about
    merged = sig.laplacian(soup.clean())       # the advice works: one closed sphere again
    assert merged.n == len(V) and merged.n_components == 1
    assert np.isclose(merged.area(), sig.laplacian(V, F).area())
