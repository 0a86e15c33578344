"""Shifted factorizations and pseudo-inverse solves against dense linear algebra."""
import numpy as np
import pytest

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl import linalg as solvers


def two_spheres():
    V, F = icosphere(2)
    V2 = V * 0.5 + np.array([3.0, 0, 0])
    return sig.laplacian(np.vstack([V, V2]), np.vstack([F, F + len(V)]))


@pytest.fixture(scope="module")
def lap():
    return sig.laplacian(*icosphere(2))


def test_shifted_factor_real_and_complex(lap, rng):
    b = rng.standard_normal((lap.n, 3))
    for beta, theta in [(0.1, 1.0), (2.0, 0.5), (1.0, 3.0 - 2.0j)]:
        A = (theta * lap.B + beta * lap.L).toarray()
        x = solvers.shifted_factor(lap, beta, theta).solve(b)
        assert np.allclose(A @ x, b, atol=1e-10 * np.abs(b).max())


def test_shifted_factor_is_cached(lap):
    f1 = solvers.shifted_factor(lap, 0.37, 1.0)
    f2 = solvers.shifted_factor(lap, 0.37, 1.0)
    assert f1 is f2


def test_pseudo_solve_matches_dense_pseudoinverse(rng):
    lap = two_spheres()
    assert lap.n_components == 2
    ev, X = sig.dense_eigs(lap)
    c = lap.n_components
    f = rng.standard_normal(lap.n)
    u = solvers.pseudo_solve(lap, lap.B @ f)
    ref = X[:, c:] @ ((X[:, c:].T @ (lap.B @ f)) / ev[c:])
    assert np.allclose(u, ref, atol=1e-10 * np.abs(ref).max())
    # B-orthogonal to the constants of each component
    Z = lap.component_basis()
    assert np.allclose(Z.T @ (lap.B @ u), 0, atol=1e-12)


def test_mass_solve(lap, rng):
    g = rng.standard_normal(lap.n)
    assert np.allclose(lap.B @ solvers.mass_solve(lap, g), g)


def test_validation(lap):
    with pytest.raises(TypeError):
        solvers.shifted_factor(np.eye(3), 1.0)
    with pytest.raises(ValueError):
        solvers.shifted_factor(lap, np.nan)
    with pytest.raises(ValueError):
        solvers.shifted_factor(lap, 1.0, backend="nope")
    with pytest.raises(ValueError):
        solvers.pseudo_solve(lap, np.ones(3))
