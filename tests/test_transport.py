"""Convolutional Wasserstein distance: debiased, symmetric, near geodesic distances, barycentres."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import read_shared_mesh

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl.applications import sinkhorn, wasserstein_barycenter, wasserstein_distance
from spectral_igl.applications.geodesics import mean_edge_length
from spectral_igl.applications.heat_steps import PositiveHeat, metzler_stiffness
from spectral_igl.applications.transport import density_support

def flat_patch(n=694, seed=0):
    """Random Delaunay triangulation of the unit square: boundary, obtuse triangles."""
    from scipy.spatial import Delaunay

    P = np.random.default_rng(seed).random((n, 2))
    F = Delaunay(P).simplices.astype(np.int64)
    return np.c_[P, np.zeros(n)], F


def unit_area(V, F):
    import igl

    return V / np.sqrt(igl.doublearea(V, F).sum() / 2.0)


def bump(V, F, c, width):
    import igl

    d = igl.exact_geodesic(V, F, np.array([c]), VT=np.arange(len(V)))
    return np.exp(-0.5 * (d / width) ** 2), d


@pytest.fixture(scope="module")
def sphere():
    V, F = icosphere(4)
    return V, sig.laplacian(V, F, mass="lumped")


def test_positive_heat_is_positive_and_stochastic():
    V, F = flat_patch()
    lap = sig.laplacian(V, F)
    assert np.any(lap.L[lap.L.nonzero()] > 0)  # the cotangent stiffness is not Metzler here
    H = PositiveHeat(lap, 1e-3, steps=8)
    off = H.L - __import__("scipy").sparse.diags(H.L.diagonal())
    assert off.max() <= 0 and abs(H.L.sum(axis=1)).max() < 1e-9
    col = H.column(0)
    assert col.min() > 0
    # P 1 = 1 and the kernel is symmetric in the mass inner product
    assert np.allclose(H.apply(np.ones(lap.n)), 1.0, atol=1e-12)
    c5 = H.column(5)
    assert abs(col[5] - c5[0]) < 1e-10 * col[5]
    # metzler_stiffness keeps non-positive off-diagonals and zero row sums
    M = metzler_stiffness(lap.L)
    assert abs(M.sum(axis=1)).max() < 1e-9 and (M - __import__("scipy").sparse.diags(M.diagonal())).max() <= 0


def test_flat_patch_converges_symmetric_debiased():
    """The shape of the issue: 694 vertices, flat with boundary, unit area, gamma = 1e-2."""
    V, F = flat_patch()
    V = unit_area(V, F)
    lap = sig.laplacian(V, F)
    h = mean_edge_length(V, F)
    a, d = bump(V, F, int(np.argmin(np.linalg.norm(V - V.mean(0), axis=1))), 1.5 * h)
    q = int(np.argmin(np.abs(d - 6 * h)))
    b = bump(V, F, q, 1.5 * h)[0]
    with pytest.warns(RuntimeWarning, match="10 h"):  # 1e-2 < 10 h^2 = 0.022 here
        w01, info = wasserstein_distance(lap, a, b, 1e-2, kernel="heat", return_info=True)
        w10 = wasserstein_distance(lap, b, a, 1e-2, kernel="heat")
    assert info["converged"] and info["marginal_error"].max() < 1e-9
    assert abs(w01 - w10) < 1e-3 * w01
    g = 10 * h * h
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        w = wasserstein_distance(lap, a, b, g)
        assert abs(w - d[q]) < 0.1 * d[q]
        # equal inputs: exactly zero without a special case; nearly equal: nearly zero
        assert wasserstein_distance(lap, a, a, g) == 0.0
        rng = np.random.default_rng(1)
        assert wasserstein_distance(lap, a, a * (1 + 1e-3 * rng.random(lap.n)), g) < 1e-3 * d[q]


@pytest.mark.parametrize("name", ["cow.obj", "spot.obj"])
def test_bumps_near_geodesic_on_real_shapes(name):
    V, F = read_shared_mesh(name)
    V = unit_area(V, F)
    lap = sig.laplacian(V, F)
    h = mean_edge_length(V, F)
    p = int(np.argmin(np.linalg.norm(V - V.mean(0), axis=1)))
    a, d = bump(V, F, p, h)
    # the default (geodesic) kernel at every distance and gamma; the heat kernel out to 8h
    for r, kernel, ratio in ((4.0, "auto", 10), (8.0, "auto", 10), (20.0, "auto", 10), (30.0, "auto", 40),
                             (6.0, "heat", 10), (8.0, "heat", 10)):
        q = int(np.argmin(np.abs(d - r * h)))
        b = bump(V, F, q, h)[0]
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            w = wasserstein_distance(lap, a, b, ratio * h * h, kernel=kernel)
        assert abs(w - d[q]) < 0.1 * d[q], (r, kernel, w, d[q])
        assert abs(w - wasserstein_distance(lap, b, a, ratio * h * h, kernel=kernel)) < 1e-3 * w


def test_dirac_limit_is_geodesic(sphere):
    V, lap = sphere
    p = 0
    q = int(np.argmin(np.abs(np.arccos(np.clip(V @ V[p], -1, 1)) - 0.5)))
    d = float(np.arccos(V[p] @ V[q]))
    mu0, mu1 = np.zeros(lap.n), np.zeros(lap.n)
    mu0[p], mu1[q] = 1.0, 1.0
    w_small = wasserstein_distance(lap, mu0, mu1, 0.1)
    w_large = wasserstein_distance(lap, mu0, mu1, 1.0)
    # debiased: accurate at a small and at a large gamma (the entropic blur cancels)
    assert abs(w_small - d) < 0.03 * d and abs(w_large - d) < 0.03 * d


def test_sinkhorn_marginals(sphere):
    V, lap = sphere
    mu0 = np.exp(-8 * np.linalg.norm(V - V[0], axis=1) ** 2)
    mu1 = np.exp(-8 * np.linalg.norm(V - V[100], axis=1) ** 2)
    H = PositiveHeat(lap, 0.05 / 4, steps=16)
    val, info = sinkhorn(lap, mu0, mu1, 0.05, heat=H)
    assert info["converged"] and np.isfinite(val)
    v, w = np.exp(info["logv"]), np.exp(info["logw"])
    m0 = mu0 / (H.mass @ mu0)
    m1 = mu1 / (H.mass @ mu1)
    assert H.mass @ np.abs(v * H.apply(w) - m0) < 1e-8
    assert H.mass @ np.abs(w * H.apply(v) - m1) < 1e-12
    with pytest.raises(ValueError, match="gamma / 4"):
        sinkhorn(lap, mu0, mu1, 0.1, heat=H)


def test_barycenter_of_two_bumps_is_the_midpoint_bump():
    V, F = flat_patch(1500, seed=2)
    V = unit_area(V, F)
    lap = sig.laplacian(V, F)
    h = mean_edge_length(V, F)
    c = V.mean(0)
    i0 = int(np.argmin(np.linalg.norm(V - (c - [0.25, 0, 0]), axis=1)))
    i1 = int(np.argmin(np.linalg.norm(V - (c + [0.25, 0, 0]), axis=1)))
    a, b = bump(V, F, i0, h)[0], bump(V, F, i1, h)[0]
    # the inputs are 18 h apart: gamma ~ d h keeps the kernel's cost quadratic out there
    gamma = 40 * h * h
    for wts, x in (((0.5, 0.5), 0.5), ((0.75, 0.25), 0.25)):
        mu, info = wasserstein_barycenter(lap, np.c_[a, b], gamma, weights=wts, return_info=True)
        assert info["converged"]
        m = mu * lap.mass
        centre = m @ V / m.sum()
        target = (1 - x) * V[i0] + x * V[i1]
        # the barycentre moves the bump (it does not average the two densities)
        assert np.linalg.norm(centre - target) < 0.1 * np.linalg.norm(V[i1] - V[i0])
        # its peak is at the interpolated position (a linear average peaks at the inputs,
        # at least 3.9 h away)
        assert np.linalg.norm(V[np.argmax(mu)] - target) < 2 * h


def test_validation(sphere):
    V, lap = sphere
    mu = np.ones(lap.n)
    with pytest.raises(ValueError, match="non-negative"):
        wasserstein_distance(lap, -mu, mu, 0.1)
    with pytest.raises(ValueError, match="zero mass"):
        wasserstein_distance(lap, 0 * mu, mu, 0.1)
    with pytest.raises(ValueError, match="gamma"):
        wasserstein_distance(lap, mu, mu, 0.0)
    with pytest.raises(ValueError, match="steps"):
        wasserstein_distance(lap, mu, mu, 0.1, steps=0)
    with pytest.raises(ValueError, match="weights"):
        wasserstein_barycenter(lap, np.c_[mu, mu], 0.1, weights=[1, -1])
    h = mean_edge_length(V, lap.data["F"])
    with pytest.warns(RuntimeWarning, match="10 h"):
        wasserstein_distance(lap, mu, mu, 5 * h * h, kernel="heat")
    with pytest.warns(RuntimeWarning, match="mean edge length"):
        wasserstein_distance(lap, np.eye(lap.n)[0], np.eye(lap.n)[1], 0.5 * h * h, kernel="geodesic")
    with pytest.raises(ValueError, match="kernel"):
        wasserstein_distance(lap, mu, mu, 0.1, kernel="gauss")
    edges = np.unique(np.sort(lap.data["F"][:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    graph = sig.graph_laplacian(lap.n, edges)
    with pytest.raises(ValueError, match="kernel='heat'"):
        wasserstein_distance(graph, mu, mu, 0.1, kernel="geodesic")
    with pytest.raises(ValueError, match="gamma is required"):
        wasserstein_distance(graph, mu, mu)


def test_point_cloud_uses_the_geodesic_kernel(sphere):
    """Point clouds have heat-method geodesics: the default kernel there is geodesic too."""
    V, lap = sphere
    pts = sig.point_cloud_laplacian(V)
    p, q = 0, int(np.argmin(np.abs(np.arccos(np.clip(V @ V[0], -1, 1)) - 0.5)))
    mu0, mu1 = np.zeros(len(V)), np.zeros(len(V))
    mu0[p], mu1[q] = 1.0, 1.0
    w, info = wasserstein_distance(pts, mu0, mu1, 0.05, return_info=True)
    d = float(np.arccos(V[p] @ V[q]))
    assert info["kernel"] == "geodesic" and info["support"] == 2 and info["converged"]
    assert abs(w - d) < 0.05 * d


def test_density_support_keeps_all_but_the_tail():
    mass = np.array([1.0, 2.0, 1.0, 1.0, 0.5])
    mu = np.array([1e-20, 1.0, 0.0, 3e-15, 4.0])
    idx, dropped = density_support(mass, mu)
    # masses 1e-20, 2, 0, 3e-15, 2: the two smallest non-zero ones sum to 3e-15 / 4 < 1e-14
    assert idx.tolist() == [1, 4] and 0 < dropped < 1e-14
    idx, dropped = density_support(mass, mu, tail=0.0)
    assert idx.tolist() == [0, 1, 3, 4] and dropped == 0.0
    # the union over columns
    idx, _ = density_support(mass, np.c_[mu, np.eye(5)[2]])
    assert idx.tolist() == [1, 2, 4]


def test_geodesic_kernel_at_every_size():
    """No change of kernel with the size: above the old dense limit (5,000 vertices) the default
    is still the geodesic Gaussian, on the densities' support only (no n^2 memory)."""
    V, F = icosphere(6)          # 40,962 vertices
    lap = sig.laplacian(V, F, mass="lumped")
    p = 0
    ang = np.arccos(np.clip(V @ V[p], -1, 1))
    q = int(np.argmin(np.abs(ang - 0.3)))
    mu0, mu1 = np.zeros(lap.n), np.zeros(lap.n)
    mu0[p], mu1[q] = 1.0, 1.0
    # a memory budget far below n^2 doubles (13 GB): the kernel fits in it
    sig.set_memory_budget(10 ** 6)
    try:
        w, info = wasserstein_distance(lap, mu0, mu1, return_info=True)
    finally:
        sig.set_memory_budget(None)
    h = mean_edge_length(V, F)
    assert info["kernel"] == "geodesic" and info["support"] == 2 and info["converged"]
    assert abs(info["gamma"] - 10 * h * h) < 1e-12 * h * h
    assert abs(w - ang[q]) < 0.02 * ang[q]


def test_full_support_converges_over_relaxed():
    """Densities spread over the whole shape at a small gamma: plain Sinkhorn takes hundreds of
    iterations; the over-relaxed one reaches the same fixed point (checked against a plain loop
    on the same kernel) in a fraction of them."""
    from spectral_igl.applications.transport import GeodesicKernel

    V, F = flat_patch()
    lap = sig.laplacian(V, F, mass="lumped")
    m, g = lap.mass, 2.0 * mean_edge_length(V, F) ** 2
    a, b = 1.0 + V[:, 0], np.ones(lap.n)
    a, b = a / (m @ a), b / (m @ b)
    s, info = sinkhorn(lap, a, b, g)
    K = GeodesicKernel(lap, g)
    logv, logw = np.zeros(lap.n), np.zeros(lap.n)
    for plain in range(1, 100000):
        kw = K.log_apply(logw[:, None])[:, 0]
        if m @ np.abs(np.exp(logv + kw) - a) < 1e-9:
            break
        logv = np.log(a) - kw
        logw = np.log(b) - K.log_apply(logv[:, None])[:, 0]
    ref = g * (m @ (a * logv) + m @ (b * logw))
    # measured: 721 plain iterations, 97 over-relaxed
    assert info["converged"] and plain > 500 and info["iterations"] < plain / 4, (plain, info["iterations"])
    assert abs(s - ref) < 1e-9 * abs(ref)
    # both marginals: the first within tol, the second exact after the last (plain) update
    v, w = np.exp(info["logv"]), np.exp(info["logw"])
    assert m @ np.abs(v * np.exp(K.log_apply(info["logw"][:, None])[:, 0]) - a) < 1e-9
    assert m @ np.abs(w * np.exp(K.log_apply(info["logv"][:, None])[:, 0]) - b) < 1e-12
