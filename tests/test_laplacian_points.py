"""Point-cloud Laplacians against the sphere's analytic spectrum, beside robust_laplacian."""
import numpy as np
import pytest
import scipy.sparse.linalg as spla

import spectral_igl as sig
from data_generators import icosphere, sample_points, sphere_eigenvalues, sphere_points

EXACT16 = sphere_eigenvalues(17)[1:]  # 2 (x3), 6 (x5), 12 (x7), 20


def _rel_err(ev):
    return np.max(np.abs(ev[1:17] - EXACT16) / EXACT16)


def _robust_err(P):
    robust_laplacian = pytest.importorskip("robust_laplacian")
    L, M = robust_laplacian.point_cloud_laplacian(P)
    ev = np.sort(spla.eigsh(L, 17, M, sigma=-1e-6)[0])
    return _rel_err(ev)


@pytest.fixture(scope="module")
def clouds():
    # 10,000 points: uniform by area, and with density varying by a factor 3 pole to pole
    return {"uniform": sphere_points(10000, seed=3), "nonuniform": sphere_points(10000, seed=4, nonuniform=1.0)}


@pytest.mark.parametrize("method", ["belkin", "liu"])
@pytest.mark.parametrize("sampling", ["uniform", "nonuniform"])
def test_sphere_first_16_eigenvalues_within_5_percent(clouds, method, sampling):
    P = clouds[sampling]
    lap = sig.point_cloud_laplacian(P, method=method)
    ev, _ = sig.eigs(lap, 17)
    err = _rel_err(ev)
    ref = _robust_err(P) if sampling == "uniform" else float("nan")
    print(f"\n{method:>7} {sampling:>10}: max rel. error {err:.4f}  (robust_laplacian {ref:.4f})")
    assert err < 0.05, (method, sampling, err, ref)
    assert lap.n_components == 1
    # the measure estimates the sphere's area (4π) to a few percent
    assert lap.area() == pytest.approx(4 * np.pi, rel=0.05)


@pytest.mark.parametrize("method", ["belkin", "liu"])
def test_matrix_properties(method):
    P = sample_points(*icosphere(3), 1500, seed=1)
    lap = sig.point_cloud_laplacian(P, k=20, method=method)
    L, B = lap.L, lap.B
    assert abs(L - L.T).max() == 0
    assert np.abs(L @ np.ones(lap.n)).max() < 1e-10 * abs(L).max()
    assert lap.lumped and np.all(B.diagonal() > 0)
    assert np.all(L.data[L.indices != np.repeat(np.arange(lap.n), np.diff(L.indptr))] <= 0)
    ev, _ = sig.eigs(lap, 5)
    assert ev[0] == 0 and np.all(ev[1:] > 0)


def test_liu_masses_are_tangent_voronoi_areas_on_a_grid():
    # a regular planar grid: every interior Voronoi cell is the h × h square
    h = 0.1
    x, y = np.meshgrid(np.arange(20) * h, np.arange(20) * h, indexing="ij")
    P = np.c_[x.ravel(), y.ravel(), np.zeros(400)]
    from spectral_igl.laplacian.points import tangent_voronoi_areas

    A = tangent_voronoi_areas(P, k=12).reshape(20, 20)
    assert np.allclose(A[2:-2, 2:-2], h * h, rtol=1e-10)


def test_fixed_bandwidth_and_radius_neighbourhoods():
    P = sphere_points(3000, seed=2)
    lap_t = sig.point_cloud_laplacian(P, k=60, t=0.004)
    assert np.all(lap_t.data["t"] == 0.004)
    lap_r = sig.point_cloud_laplacian(P, radius=0.3, method="belkin")
    ev, _ = sig.eigs(lap_r, 4)
    assert np.allclose(ev[1:4], 2.0, rtol=0.08)  # coarse (3,000 points), the l=1 triple
    with pytest.raises(ValueError, match="radius"):
        sig.point_cloud_laplacian(P, radius=1e-4)


def test_separated_clusters_are_components():
    P = sphere_points(600, seed=5)
    lap = sig.point_cloud_laplacian(np.vstack([P, P + 10.0]), k=15)
    assert lap.n_components == 2
