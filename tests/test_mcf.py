"""Mean-curvature flow: rounder, area kept, no pinching for the conformalized flow."""
import numpy as np
import pytest

import spectral_igl as sig
from conftest import read_shared_mesh
from data_generators import gaussian_noise, icosphere
from spectral_igl.laplacian.mesh import element_measures


def roundness(X, F):
    a = element_measures(X, F)
    c = (a[:, None] * X[F].mean(axis=1)).sum(0) / a.sum()
    r = np.linalg.norm(X - c, axis=1)
    return r.std() / r.mean()


def flipped(X, F):
    """Number of triangles whose normal points toward the centroid (inverted)."""
    n = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])
    return int(np.sum(np.einsum("ij,ij->i", n, X[F].mean(1) - X.mean(0)) < 0))


@pytest.mark.parametrize("conformal", [True, False])
def test_noisy_sphere_becomes_round_with_its_area(conformal):
    V, F = icosphere(3)
    Vn = gaussian_noise(V, 0.03, seed=0)
    H = sig.mean_curvature_flow(Vn, F, steps=6, conformal=conformal, history=True)
    a0 = element_measures(Vn, F).sum()
    rs = [roundness(X, F) for X in H]
    assert rs[-1] < 0.25 * rs[0] and np.all(np.diff(rs) < 0), rs
    for X in H:
        assert element_measures(X, F).sum() == pytest.approx(a0, rel=1e-12)
    w = element_measures(Vn, F)
    c0 = (w[:, None] * Vn[F].mean(1)).sum(0) / w.sum()
    w = element_measures(H[-1], F)
    assert np.allclose((w[:, None] * H[-1][F].mean(1)).sum(0) / w.sum(), c0, atol=1e-12)
    assert flipped(H[-1], F) == 0


def test_round_sphere_is_a_fixed_point():
    V, F = icosphere(3)
    X = sig.mean_curvature_flow(V, F, dt=1e-2, steps=5)
    assert np.abs(np.linalg.norm(X, axis=1) - np.linalg.norm(V, axis=1)).max() < 2e-3


def test_one_step_is_the_backward_euler_system():
    V, F = icosphere(2)
    V = V * [1.3, 1.0, 0.7]
    lap = sig.laplacian(V, F, weights="cotan", mass="barycentric")
    delta = 1e-3 * lap.area()
    import scipy.sparse.linalg as spla

    expect = spla.spsolve((lap.B + delta * lap.L).tocsc(), lap.B @ V)
    X = sig.mean_curvature_flow(V, F, dt=1e-3, steps=1, normalize=False)
    assert np.abs(X - expect).max() < 1e-12


def test_real_shape_conformalized_rounds_without_pinching_classical_pinches():
    V, F = read_shared_mesh("spot.obj")
    X = sig.mean_curvature_flow(V, F, dt=5e-3, steps=30)
    assert roundness(X, F) < 0.15 * roundness(V, F)
    a = element_measures(X, F)
    assert a.min() > 1e-6 * a.mean() and flipped(X, F) == 0
    assert a.sum() == pytest.approx(element_measures(V, F).sum(), rel=1e-12)
    # the classical flow collapses triangles on the same run
    with pytest.raises(FloatingPointError, match="pinched"):
        sig.mean_curvature_flow(V, F, dt=5e-3, steps=30, conformal=False)


def test_bad_input():
    V, F = icosphere(1)
    with pytest.raises(ValueError, match="dt"):
        sig.mean_curvature_flow(V, F, dt=-1)
    with pytest.raises(ValueError, match="steps"):
        sig.mean_curvature_flow(V, F, steps=1.5)
    with pytest.raises(ValueError, match="mass"):
        sig.mean_curvature_flow(V, F, mass="voronoi")
    with pytest.raises(ValueError, match="triangle"):
        sig.mean_curvature_flow(V, np.c_[F, F[:, 0]])
