"""Compiled intrinsic Delaunay flips against libigl, and the geodesic precompute that uses them."""
import numpy as np
import pytest
import scipy.sparse as sp
from _spectral_truth import torus

from spectral_igl.applications.geodesics import HeatGeodesics
from spectral_igl.laplacian.intrinsic import intrinsic_delaunay
from spectral_igl.laplacian.intrinsic_fem import triangle_gradients

igl = pytest.importorskip("igl")


def _stiffness(l, F, n):
    G, A = triangle_gradients(l, F, n)
    return (G.T @ sp.diags(np.r_[A, A]) @ G).tocsr()


def _check(V, F):
    l = igl.edge_lengths(V, F)
    l1, F1 = intrinsic_delaunay(l, F)
    l2, F2 = igl.intrinsic_delaunay_triangulation(np.ascontiguousarray(l), F)[:2]
    L1, L2 = _stiffness(l1, F1, len(V)), _stiffness(l2, F2, len(V))
    # the intrinsic Delaunay cotangent Laplacian is unique (whatever the order of flips)
    assert abs(L1 - L2).max() <= 1e-12 * abs(L2).max()
    # and all its off-diagonal weights are non-negative (L is the PSD stiffness)
    off = sp.triu(L1, 1).data
    assert off.max(initial=0.0) <= 1e-12 * abs(L1).max()
    return l1, F1


def test_flips_match_libigl_on_a_jittered_torus():
    V, F = torus(24, 12, jitter=0.45, seed=3)
    l0 = igl.edge_lengths(V, F)
    l1, F1 = _check(V, F)
    assert not np.array_equal(F1, F)          # some edges were flipped
    # flips keep the faces' count and the total intrinsic area
    def area(l):
        s = l.sum(axis=1) / 2
        return np.sqrt(np.maximum(s * (s - l[:, 0]) * (s - l[:, 1]) * (s - l[:, 2]), 0)).sum()
    assert abs(area(l1) - area(l0)) <= 1e-12 * area(l0)


def test_flips_match_libigl_on_a_real_mesh():
    from conftest import read_shared_mesh

    V, F = read_shared_mesh("homer.obj")
    _check(V, F)


def test_flips_do_not_depend_on_the_faces_orientation():
    """A mesh need not be oriented: reversing random faces changes neither the triangulation's
    Laplacian nor its Delaunay property (the flips once read a reversed neighbour's edge
    lengths in the wrong order)."""
    from spectral_igl.laplacian.intrinsic import intrinsic_cotan_stiffness

    V, F = torus(24, 12, jitter=0.45, seed=3)
    rng = np.random.default_rng(0)
    G = F.copy()
    rev = rng.random(len(F)) < 0.5
    G[rev] = G[rev][:, ::-1]
    S, R = intrinsic_cotan_stiffness(V, F), intrinsic_cotan_stiffness(V, G)
    assert abs(S - R).max() <= 1e-12 * abs(S).max()
    assert sp.triu(R, 1).data.max(initial=0.0) <= 1e-12 * abs(R).max()
    # and the same Laplacian as libigl's on the oriented mesh
    assert abs(S + igl.intrinsic_delaunay_cotmatrix(V, F)[0]).max() <= 1e-12 * abs(S).max()


def test_heat_geodesics_on_the_sphere_stay_accurate():
    from data_generators import icosphere

    V, F = icosphere(4)
    d = HeatGeodesics((V, F)).compute(0)
    exact = np.arccos(np.clip(V @ V[0], -1, 1))
    assert np.abs(d - exact).max() < 0.05
    assert np.mean(np.abs(d - exact)[1:] / exact[1:]) < 0.012    # measured 0.0112


def test_element_sum_matches_scipy_and_stores_the_diagonal():
    from spectral_igl.laplacian.intrinsic import element_sum

    rng = np.random.default_rng(5)
    F = rng.integers(0, 40, (200, 3))
    W = rng.standard_normal((200, 3, 3))
    W = W + W.transpose(0, 2, 1)
    S = element_sum(W, F, 45)
    ref = sp.coo_matrix((W.ravel(), (np.repeat(F, 3, axis=1).ravel(), np.tile(F, (1, 3)).ravel())),
                        shape=(45, 45)).toarray()
    assert np.abs(S.toarray() - ref).max() <= 1e-13 * np.abs(ref).max()
    assert S.has_canonical_format
    assert (S != S.T).nnz == 0                                  # summed in face order: exactly symmetric
    d = S.indptr[:-1] + np.array([np.searchsorted(S.indices[S.indptr[i]:S.indptr[i + 1]], i) for i in range(45)])
    assert np.array_equal(S.indices[d], np.arange(45))           # every diagonal stored
    assert np.all(S.data[d[40:]] == 0) and np.setdiff1d(np.arange(40, 45), F).size == 5
    with pytest.raises(ValueError, match="F must index"):
        element_sum(W, F, 30)
    with pytest.raises(ValueError, match="shape"):
        element_sum(W[:, :2], F, 45)
