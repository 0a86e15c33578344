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
        wasserstein_distance(lap, mu, mu, 0.5 * h * h, kernel="geodesic", max_iter=2)
    with pytest.raises(ValueError, match="kernel"):
        wasserstein_distance(lap, mu, mu, 0.1, kernel="gauss")
    pts = sig.point_cloud_laplacian(V)
    with pytest.raises(ValueError, match="kernel='heat'"):
        wasserstein_distance(pts, mu, mu, 0.1, kernel="geodesic")
