"""Wave, singular and user filters, kernel columns, identities, lambda_max and validation."""
import numpy as np
import pytest
from engine_cases import HEAT_TIMES, SHAPES, bnorm, check, shape, truth  # noqa: F401

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl import filters

FILTERS = [filters.wave(0.01), filters.biharmonic(), filters.commute_time(),
           filters.polyharmonic(3), filters.polyharmonic(4), filters.mexican_hat(0.01),
           filters.Filter(lambda s: 1.0 / (1.0 + 0.1 * s) ** 2, name="user")]


@pytest.mark.parametrize("name", ["sphere", "box_tets", "two_spheres"])
@pytest.mark.parametrize("filt", FILTERS, ids=lambda f: f.name)
def test_filters_auto_exact(name, filt, rng):
    lap, ev, X = shape(name)
    f = rng.standard_normal(lap.n)
    op, err, slack = check(lap, ev, X, filt, "auto", f)
    assert op.method != "dense" or lap.n <= 300
    assert err <= op.error_bound + slack
    assert err <= 1e-8 * bnorm(lap, f) + slack


@pytest.mark.parametrize("filt", FILTERS[:4], ids=lambda f: f.name)
@pytest.mark.parametrize("method", ["rational", "chebyshev", "shift_invert", "krylov"])
def test_filters_each_method(filt, method, rng):
    if method == "rational" and filt.kind == "wave":
        pytest.skip("wave: an AAA fit of an oscillation; Chebyshev and Lanczos cover it")
    lap, ev, X = shape("sphere")
    f = rng.standard_normal(lap.n)
    op, err, slack = check(lap, ev, X, filt, method, f)
    assert err <= op.error_bound + slack
    assert op.error_bound <= 1e-8 * bnorm(lap, f) * 1.0001 + 10 * slack


@pytest.mark.parametrize("method", ["rational", "shift_invert", "chebyshev", "euler", "contour", "dense"])
@pytest.mark.parametrize("filt", [filters.heat(1e-3), filters.biharmonic(), filters.commute_time()],
                         ids=lambda f: f.name)
def test_inverse_mass_columns(method, filt, rng):
    lap, ev, X = shape("two_spheres")
    if method in ("euler", "contour") and filt.kind != "heat":
        pytest.skip("heat-only method")
    idx = [0, 17, lap.n - 1]
    G = np.zeros((lap.n, 3))
    G[idx, range(3)] = 1.0
    op = sig.SpectralOperator(lap, filt, method=method)
    U = op.apply_inverse_mass(G)
    ref = truth(lap, ev, X, filt, G, rhs=True)
    err = bnorm(lap, U - ref)
    assert np.all(err <= op.error_bound + 1e-12 * bnorm(lap, ref))
    # the kernel matrix is symmetric: K[i, j] == K[j, i]
    K = U[idx]
    assert np.allclose(K, K.T, atol=1e-6 * np.abs(K).max() if method == "euler" else 1e-9 * np.abs(K).max())


def test_eigen_has_no_bound(rng):
    lap, ev, X = shape("sphere")
    op = sig.SpectralOperator(lap, filters.heat(0.1), method="eigen", k=50)
    u = op.apply(rng.standard_normal(lap.n))
    assert op.error_bound is None and u.shape == (lap.n,)


def test_singular_filters_kill_constants():
    lap, ev, X = shape("two_spheres")
    const = np.where(lap.components == 0, 2.0, -5.0)
    for filt in (filters.biharmonic(), filters.commute_time(), filters.polyharmonic(3)):
        u = sig.apply_filter(lap, filt, const, method="rational")
        assert np.abs(u).max() <= 1e-10


def test_semigroup_and_scale_covariance(rng):
    V, F = icosphere(3)
    lap = sig.laplacian(V, F)
    f = rng.standard_normal(lap.n)
    s, t = 0.003, 0.02
    a = sig.apply_filter(lap, filters.heat(s), sig.apply_filter(lap, filters.heat(t), f, tol=1e-12), tol=1e-12)
    b = sig.apply_filter(lap, filters.heat(s + t), f, tol=1e-12)
    assert bnorm(lap, a - b) <= 1e-8 * bnorm(lap, b)
    # scaling V by alpha scales L̃ by alpha^-2: e^{-t L̃(alpha V)} = e^{-(t/alpha^2) L̃(V)}
    alpha = 2.5
    lap2 = sig.laplacian(alpha * V, F)
    u2 = sig.apply_filter(lap2, filters.heat(t), f, tol=1e-12)
    u1 = sig.apply_filter(lap, filters.heat(t / alpha ** 2), f, tol=1e-12)
    assert np.linalg.norm(u2 - u1) <= 1e-8 * np.linalg.norm(u1)


def test_lambda_max_is_an_upper_bound():
    for name in SHAPES:
        lap, ev, X = shape(name)
        lm = sig.lambda_max(lap)
        assert ev[-1] <= lm <= 20 * ev[-1]


def test_validation():
    lap, ev, X = shape("sphere")
    with pytest.raises(ValueError, match="method must be one of"):
        sig.SpectralOperator(lap, filters.heat(1.0), method="magic")
    with pytest.raises(ValueError, match="heat filter only"):
        sig.SpectralOperator(lap, filters.biharmonic(), method="euler")
    with pytest.raises(ValueError):
        sig.apply_filter(lap, filters.heat(1.0), np.ones(3))
    with pytest.raises(ValueError):
        sig.apply_filter(lap, filters.heat(1.0), np.full(lap.n, np.nan))
    with pytest.raises(ValueError):
        sig.SpectralOperator(lap, filters.heat(1.0), tol=0.0)
    with pytest.raises(TypeError):
        sig.SpectralOperator(np.eye(3), filters.heat(1.0))
    with pytest.raises(TypeError):
        sig.SpectralOperator(lap, 3.0)
