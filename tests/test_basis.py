"""Diffusion basis and feature points (survey §7.2) against dense eigendecompositions."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

pytest.importorskip("spectral_igl.filters")

import spectral_igl as sig  # noqa: E402
from data_generators import box_tets, icosphere  # noqa: E402
from spectral_igl.applications import (  # noqa: E402
    critical_points,
    diffusion_basis,
    feature_points,
    graph_extrema,
)


def _rotate_to_x(V, i):
    """Rotate V so that vertex i lies on the +x axis."""
    a = V[i] / np.linalg.norm(V[i])
    v, c = np.cross(a, [1.0, 0.0, 0.0]), a[0]
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return V @ (np.eye(3) + K + K @ K / (1.0 + c)).T


@pytest.fixture(scope="module")
def ellipsoid():
    """icosphere(3) stretched along x; vertex 0 and its antipode sit exactly on the tips."""
    V, F = icosphere(3)
    V = _rotate_to_x(V, 0)
    tips = {int(np.argmax(V[:, 0])), int(np.argmin(V[:, 0]))}
    assert 0 in tips and np.isclose(V[list(tips)][:, 0], [1, -1]).all()
    return V * [3.0, 1.2, 1.0], F, tips


@pytest.fixture(scope="module")
def arms():
    """A sphere with four smooth protrusions of different lengths; returns the tip vertices."""
    V, F = icosphere(3)
    dirs = np.array([[1, 0, 0], [-0.3, 1, 0.2], [-0.3, -0.6, 0.8], [0.1, -0.5, -0.9]])
    dirs = dirs / np.linalg.norm(dirs, axis=1)[:, None]
    tips = [int(np.argmax(V @ d)) for d in dirs]
    r = np.ones(len(V))
    for k, a in zip(tips, (1.2, 1.0, 0.9, 0.8)):
        r += a * np.exp(-np.sum((V - V[k]) ** 2, axis=1) / 0.15)
    return V * r[:, None], F, set(tips)


@pytest.mark.parametrize("mesh, mass", [("sphere", "full"), ("sphere", "lumped"), ("tets", "lumped")])
def test_diffusion_basis_is_the_heat_kernel(mesh, mass):
    if mesh == "sphere":
        V, F = icosphere(3)
        V = V + 0.02 * np.random.default_rng(0).standard_normal(V.shape)
        lap = sig.laplacian(V, F, mass=mass)
    else:
        V, T = box_tets((5, 5, 5), (1.0, 1.0, 1.0))
        lap = sig.laplacian(V, T, mass=mass)
    lam, X = sig.dense_eigs(lap)
    t = 2.0 / lam[1]
    centers = np.array([0, 17, lap.n // 2, lap.n - 1])
    Psi = diffusion_basis(lap, t, centers, tol=1e-11)
    assert Psi.shape == (lap.n, centers.size)
    exact = X @ (np.exp(-lam * t)[:, None] * X[centers].T)   # e^{-tL~} B^{-1} e_i
    bnorm = lambda U: np.sqrt(np.einsum("ij,ij->j", U, lap.B @ U))  # noqa: E731
    assert np.all(bnorm(Psi - exact) < 1e-8 * bnorm(exact))
    assert np.all(Psi > 0)
    np.testing.assert_allclose(lap.mass @ Psi, 1.0, rtol=1e-9)          # each integrates to 1
    np.testing.assert_allclose(Psi[centers], Psi[centers].T, rtol=1e-9)  # psi_i(p_j) = psi_j(p_i)


def test_diffusion_basis_partition_of_unity():
    V, F = icosphere(2)
    lap = sig.laplacian(V, F, mass="full")
    lam, X = sig.dense_eigs(lap)
    t = 0.3 / lam[1]
    Psi = diffusion_basis(lap, t, np.arange(lap.n), tol=1e-11)
    np.testing.assert_allclose(Psi @ lap.mass, 1.0, rtol=1e-9)  # sum_i m_i psi_i = 1
    np.testing.assert_allclose(Psi, X @ (np.exp(-lam * t)[:, None] * X.T), atol=1e-9 * Psi.max())


def test_adf_feature_points_are_the_tips(ellipsoid, arms):
    V, F, tips = ellipsoid
    lap = sig.laplacian(V, F)
    # the two ends of the long axis, at both scales; no other vertex
    for t in (0.1, 1.0):
        assert set(feature_points(lap, source="adf", t=t, method="dense")) == tips
    V, F, tips = arms
    lap = sig.laplacian(V, F)
    for t in (0.05, 0.1, 0.3):  # at t = 0.1 the spectrum-free ADF (probing diagonal)
        fp = feature_points(lap, source="adf", t=t, method="probing" if t == 0.1 else "dense")
        assert set(fp) == tips
    # without the persistence filter the discrete ADF has shallow extra maxima: they are
    # real local maxima of the dense ADF, which the filter removes
    lam, X = sig.dense_eigs(lap)
    adf = (X ** 2) @ np.exp(-0.1 * lam / lam[1]) * lap.area()
    raw = set(feature_points(lap, source="adf", t=0.1, persistence=0.0, method="dense"))
    assert raw == set(graph_extrema(lap, adf)[1]) and raw > tips


def test_eigenfunction_feature_points_match_dense_eigenvectors():
    V, F = icosphere(3)
    V = V * [2.0, 1.4, 1.0] + 0.01 * np.random.default_rng(3).standard_normal(V.shape)
    lap = sig.laplacian(V, F)
    lam, X = sig.dense_eigs(lap, 8)
    assert np.min(np.diff(lam[1:8]) / lam[7]) > 1e-3  # simple eigenvalues: x_k defined up to sign
    for k in (3, 6):
        for p in (0.0, 0.25):
            expect = set()
            for j in range(1, k + 1):
                mn, mx = graph_extrema(lap, X[:, j], persistence=p)
                expect |= set(mn) | set(mx)
            got = feature_points(lap, n_eigenfunctions=k, persistence=p)
            assert set(got) == expect and np.all(np.diff(got) > 0)
    # x_2 of the stretched shape is monotone along x: its only extrema are the two ends
    assert set(feature_points(lap, n_eigenfunctions=1)) == {int(np.argmin(V[:, 0])), int(np.argmax(V[:, 0]))}


def test_graph_extrema_equal_the_lower_link_test(arms):
    V, F, _ = arms
    lap = sig.laplacian(V, F, weights="cotan")    # the mesh graph: its links are the edges
    f = np.random.default_rng(1).standard_normal(lap.n)
    f[:10] = f[10:20]  # ties, broken by index in both
    mn, mx = graph_extrema(lap, f)
    cp = critical_points(V, F, f)
    np.testing.assert_array_equal(mn, cp.minima)
    np.testing.assert_array_equal(mx, cp.maxima)


def _brute_persistence(A, f, m):
    """f(m) minus the highest level c at which {f >= c} joins m to a higher-ranked vertex."""
    n = f.size
    rank = np.empty(n, dtype=np.int64)
    rank[np.lexsort((np.arange(n), f))] = np.arange(n)
    for v in np.argsort(-rank):  # lower the level one vertex at a time
        if rank[v] > rank[m]:
            continue
        keep = rank >= rank[v]
        sub = A[keep][:, keep]
        _, lab = connected_components(sub, directed=False)
        idx = np.flatnonzero(keep)
        comp = lab[np.searchsorted(idx, m)]
        if np.any(rank[idx[lab == comp]] > rank[m]):
            return f[m] - f[v]
    return np.inf


def test_graph_extrema_persistence_brute_force():
    V, F = icosphere(2)
    lap = sig.laplacian(V, F)
    f = np.random.default_rng(2).standard_normal(lap.n)
    A = sp.csr_matrix(lap.L != 0)
    rng_f = f.max() - f.min()
    mn0, mx0 = graph_extrema(lap, f)
    pmax = {int(m): _brute_persistence(A, f, m) for m in mx0}
    pmin = {int(m): _brute_persistence(A, -f, m) for m in mn0}
    assert sum(np.isinf(list(pmax.values()))) == 1 and sum(np.isinf(list(pmin.values()))) == 1
    for p in (0.0, 0.05, 0.1, 0.2, 0.4):
        mn, mx = graph_extrema(lap, f, persistence=p)
        assert set(mx) == {m for m, v in pmax.items() if v >= p * rng_f}
        assert set(mn) == {m for m, v in pmin.items() if v >= p * rng_f}
    assert len(graph_extrema(lap, f, persistence=0.4)[1]) < len(mx0)


def test_validation(ellipsoid):
    V, F, _ = ellipsoid
    lap = sig.laplacian(V, F)
    with pytest.raises(ValueError, match="source"):
        feature_points(lap, source="hks")
    with pytest.raises(ValueError, match="n_eigenfunctions"):
        feature_points(lap, n_eigenfunctions=0)
    with pytest.raises(ValueError, match="persistence"):
        graph_extrema(lap, V[:, 0], persistence=-1)
    with pytest.raises(ValueError, match="f"):
        graph_extrema(lap, V[:10, 0])
    with pytest.raises(ValueError, match="t"):
        diffusion_basis(lap, -1.0, [0])
    with pytest.raises(ValueError, match="centers"):
        diffusion_basis(lap, 1.0, [lap.n])
    assert not hasattr(sig, "auto_diffusion")  # one name: sig.auto_diffusion_function
