"""Harmonic and poly-harmonic interpolation against exact solutions and the maximum principle."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import read_shared_mesh

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl.applications import harmonic


def grid(k=16, size=1.0):
    """Uniform right-triangle grid of [0, size]^2 with (k+1)^2 vertices."""
    x, y = np.meshgrid(np.linspace(0, size, k + 1), np.linspace(0, size, k + 1), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    idx = np.arange((k + 1) ** 2).reshape(k + 1, k + 1)
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[:-1, 1:], idx[1:, 1:]
    F = np.r_[np.c_[a.ravel(), b.ravel(), d.ravel()], np.c_[a.ravel(), d.ravel(), c.ravel()]]
    return V, F, idx


def ring(idx, depth):
    """Vertices within ``depth`` layers of the boundary of the grid."""
    m = np.zeros(idx.shape, dtype=bool)
    m[:depth], m[-depth:], m[:, :depth], m[:, -depth:] = True, True, True, True
    return idx[m]


def test_quadratic_harmonic_reproduced_exactly():
    # on this grid the cotan Laplacian is the 5-point stencil, exact on quadratics
    V, F, idx = grid(12)
    lap = sig.laplacian(V, F)
    u = V[:, 0] ** 2 - V[:, 1] ** 2 + 0.3 * V[:, 0] * V[:, 1]
    b = ring(idx, 1)
    h = harmonic(lap, b, u[b])
    assert np.abs(h - u).max() < 1e-12
    # a non-harmonic quadratic is not reproduced
    w = V[:, 0] ** 2 + V[:, 1] ** 2
    assert np.abs(harmonic(lap, b, w[b]) - w).max() > 1e-3


def test_biharmonic_reproduces_biharmonic_quadratic():
    # x^2 + y^2 is biharmonic (not harmonic); two fixed layers determine it exactly
    V, F, idx = grid(12)
    lap = sig.laplacian(V, F, mass="lumped")
    w = V[:, 0] ** 2 + V[:, 1] ** 2
    b = ring(idx, 2)
    assert np.abs(harmonic(lap, b, w[b], k=2) - w).max() < 1e-12


def test_convergence_rate_second_order():
    errs = []
    for k in (8, 16, 32):
        V, F, idx = grid(k)
        lap = sig.laplacian(V, F)
        u = np.exp(V[:, 0]) * np.cos(V[:, 1])
        b = ring(idx, 1)
        errs.append(np.abs(harmonic(lap, b, u[b]) - u).max())
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(rates > 1.8), rates


def test_maximum_principle_and_columns():
    V, F = read_shared_mesh("spot.obj")
    lap = sig.laplacian(V, F, weights="intrinsic_delaunay")  # non-negative weights: M-matrix
    rng = np.random.default_rng(0)
    fixed = rng.choice(len(V), 6, replace=False)
    vals = rng.random((6, 2))
    H = harmonic(lap, fixed, vals)
    assert H.shape == (len(V), 2)
    assert np.array_equal(H[fixed], vals)
    assert H.min() >= vals.min() - 1e-12 and H.max() <= vals.max() + 1e-12
    np.testing.assert_allclose(H[:, 1], harmonic(lap, fixed, vals[:, 1]), atol=1e-12)
    # the solution satisfies the equation at the free vertices
    free = np.setdiff1d(np.arange(len(V)), fixed)
    r = (lap.L @ H)[free]
    assert np.abs(r).max() < 1e-9 * np.abs(lap.L.data).max()


def test_validation():
    V, F = icosphere(1)
    lap = sig.laplacian(V, F)
    with pytest.raises(ValueError, match="duplicate"):
        harmonic(lap, [0, 0], [1.0, 2.0])
    with pytest.raises(ValueError, match="vertex indices"):
        harmonic(lap, [0, 99], [1.0, 2.0])
    with pytest.raises(ValueError, match="values must have shape"):
        harmonic(lap, [0, 1], [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="k must be"):
        harmonic(lap, [0, 1], [1.0, 2.0], k=0)
    with pytest.raises(ValueError, match="NaN"):
        harmonic(lap, [0, 1], [1.0, np.nan])
    with pytest.raises(TypeError):
        harmonic(V, [0, 1], [1.0, 2.0])
    # two components, constraints on one only
    V2 = np.r_[V, V + 3.0]
    F2 = np.r_[F, F + len(V)]
    lap2 = sig.laplacian(V2, F2)
    with pytest.raises(ValueError, match="component"):
        harmonic(lap2, [0, 1], [0.0, 1.0])
    h = harmonic(lap2, [0, len(V)], [0.0, 1.0])
    np.testing.assert_allclose(h, np.r_[np.zeros(len(V)), np.ones(len(V))], atol=1e-12)
