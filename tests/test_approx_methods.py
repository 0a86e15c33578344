"""Every method against the dense ground truth φ(L̃)f; the certified bound is never below the error."""
import numpy as np
import pytest

import spectral_igl as sig
from data_generators import box_tets, icosphere
from spectral_igl import filters

HEAT_TIMES = [1e-5, 1e-3, 1e-1, 10.0]


def two_spheres():
    V, F = icosphere(2)
    V2 = V * 0.5 + np.array([3.0, 0, 0])
    return sig.laplacian(np.vstack([V, V2]), np.vstack([F, F + len(V)]))


def unit_area(lap_fn, V, F, **kw):
    lap = lap_fn(V, F, **kw)
    d = 2 if F.shape[1] == 3 else 3
    return lap_fn(V / lap.area() ** (1 / d), F, **kw)


SHAPES = {
    "sphere": lambda: unit_area(sig.laplacian, *icosphere(3)),
    "sphere_lumped": lambda: unit_area(sig.laplacian, *icosphere(3), mass="lumped"),
    "box_tets": lambda: sig.laplacian(*box_tets((7, 5, 4))),
    "two_spheres": two_spheres,
}
_cache = {}


def shape(name):
    if name not in _cache:
        lap = SHAPES[name]()
        _cache[name] = (lap, *sig.dense_eigs(lap))
    return _cache[name]


def truth(lap, ev, X, filt, f, rhs=False):
    c = X.T @ (f if rhs else lap.B @ f)
    phi = filt(ev)
    return X @ (phi[:, None] * c if f.ndim == 2 else phi * c)


def bnorm(lap, x):
    return np.sqrt(np.maximum(np.real(np.sum(np.conj(x) * (lap.B @ x), axis=0)), 0))


def check(lap, ev, X, filt, method, f, tol=1e-8, rhs=False, **opt):
    op = sig.SpectralOperator(lap, filt, method=method, tol=tol, **opt)
    u = op.apply_inverse_mass(f) if rhs else op.apply(f)
    assert u.shape == f.shape
    ref = truth(lap, ev, X, filt, f, rhs)
    err = bnorm(lap, u - ref)
    # the dense ground truth carries its own rounding (~1e-13 relative)
    slack = 1e-12 * bnorm(lap, ref) + 1e-13 * (bnorm(lap, f) if not rhs else np.linalg.norm(X.T @ f, axis=0))
    return op, err, slack


@pytest.mark.parametrize("name", list(SHAPES))
@pytest.mark.parametrize("method", ["rational", "contour", "shift_invert", "chebyshev", "krylov"])
def test_heat_accurate_and_bounded(name, method, rng):
    lap, ev, X = shape(name)
    f = rng.standard_normal((lap.n, 2))
    for t in HEAT_TIMES:
        if method == "krylov" and t * sig.lambda_max(lap) > 1e4:
            continue  # polynomial Krylov needs ~sqrt(t lambda_max) steps: covered at small t
        op, err, slack = check(lap, ev, X, filters.heat(t), method, f)
        assert np.all(err <= op.error_bound + slack), (t, err, op.error_bound)
        assert np.all(op.error_bound <= 1e-8 * bnorm(lap, f) + slack * 10), (t, op.error_bound)


@pytest.mark.parametrize("method, opts", [("euler", {"steps": 1}), ("euler", {"steps": 8}),
                                          ("taylor1", {}), ("power", {}), ("taylor", {}),
                                          ("rational", {"degree": 4}), ("contour", {"nodes": 6}),
                                          ("chebyshev", {"degree": 5}), ("krylov", {"steps": 4}),
                                          ("shift_invert", {"steps": 4})])
def test_heat_low_order_bound_holds(method, opts, rng):
    """Crude settings: the error is large, and the bound must still cover it."""
    lap, ev, X = shape("sphere")
    f = rng.standard_normal(lap.n)
    for t in HEAT_TIMES:
        if method == "power" and t * sig.lambda_max(lap) > 2 ** 14:
            with pytest.raises(ValueError, match="squarings"):
                sig.SpectralOperator(lap, filters.heat(t), method="power")
            continue
        op, err, slack = check(lap, ev, X, filters.heat(t), method, f, **opts)
        assert err <= op.error_bound + slack, (t, err, op.error_bound)


FILTERS = [filters.wave(0.01), filters.wave(0.001), filters.biharmonic(), filters.commute_time(),
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


@pytest.mark.parametrize("filt", FILTERS[:5], ids=lambda f: f.name)
@pytest.mark.parametrize("method", ["rational", "chebyshev", "shift_invert", "krylov"])
def test_filters_each_method(filt, method, rng):
    lap, ev, X = shape("sphere")
    f = rng.standard_normal(lap.n)
    op, err, slack = check(lap, ev, X, filt, method, f)
    assert err <= op.error_bound + slack
    if not (method == "rational" and filt.kind == "wave"):  # an AAA fit of an oscillation
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
