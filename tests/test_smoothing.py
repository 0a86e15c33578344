"""Least-squares and diffusion smoothing against the dense spectral filter; fewer critical points."""
from __future__ import annotations

import numpy as np
import pytest

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl.applications import (
    critical_points,
    harmonic,
    smooth,
    smooth_constrained,
)


@pytest.fixture(scope="module")
def sphere_lumped():
    V, F = icosphere(3)
    return V, F, sig.laplacian(V, F, mass="lumped")


def noisy(V, seed=0, sigma=0.1):
    clean = V[:, 0] + 0.5 * V[:, 1] * V[:, 2]
    rng = np.random.default_rng(seed)
    return clean, clean + sigma * rng.standard_normal(len(V))


def test_smooth_is_the_spectral_filter():
    V, F = icosphere(2)
    lap = sig.laplacian(V, F, mass="lumped")
    _, f = noisy(V)
    lam, X = sig.dense_eigs(lap)
    eps = 30.0
    expected = X @ (eps / (lam ** 2 + eps) * (X.T @ (lap.B @ f)))
    np.testing.assert_allclose(smooth(lap, f, eps), expected, atol=1e-10)
    # columns independent, shape follows input
    G = smooth(lap, np.c_[f, 2 * f], eps)
    assert G.shape == (lap.n, 2)
    np.testing.assert_allclose(G[:, 1], 2 * expected, atol=1e-9)


def test_smooth_removes_noise_and_critical_points(sphere_lumped):
    V, F, lap = sphere_lumped
    clean, f = noisy(V)
    g = smooth(lap, f, 1000.0)  # keeps l <= 2 (lambda <= 6) at > 96%
    err = lambda u: np.sqrt((u - clean) @ (lap.B @ (u - clean)))  # noqa: E731
    assert err(g) < 0.5 * err(f)
    before, after = critical_points(V, F, f), critical_points(V, F, g)
    assert after.n_minima + after.n_maxima < 0.2 * (before.n_minima + before.n_maxima)
    assert after.n_minima - after.n_saddles + after.n_maxima == 2


def test_smooth_constrained_interpolates(sphere_lumped):
    V, F, lap = sphere_lumped
    clean, f = noisy(V)
    cp = critical_points(V, F, clean)
    fixed = np.r_[cp.minima, cp.maxima, np.arange(0, lap.n, 17)]
    fixed = np.unique(fixed)
    g = smooth_constrained(lap, f, fixed)
    np.testing.assert_array_equal(g[fixed], f[fixed])
    np.testing.assert_allclose(g, harmonic(lap, fixed, f[fixed], k=2), atol=1e-12)
    # with a fidelity term: still interpolating, closer to f elsewhere, and eps -> inf gives f
    g1 = smooth_constrained(lap, f, fixed, eps=10.0)
    np.testing.assert_array_equal(g1[fixed], f[fixed])
    ginf = smooth_constrained(lap, f, fixed, eps=1e9)
    assert np.abs(ginf - f).max() < 1e-3
    # optimality: the constrained energy at g1 is below that of perturbations keeping the constraints
    M_inv = 1.0 / lap.mass

    def energy(u):
        Lu = lap.L @ u
        return Lu @ (M_inv * Lu) + 10.0 * (u - f) @ (lap.B @ (u - f))

    rng = np.random.default_rng(1)
    for _ in range(3):
        p = rng.standard_normal(lap.n) * 1e-3
        p[fixed] = 0
        assert energy(g1 + p) > energy(g1)


def test_validation(sphere_lumped):
    V, F, lap = sphere_lumped
    f = V[:, 0]
    with pytest.raises(ValueError, match="eps"):
        smooth(lap, f, 0.0)
    with pytest.raises(ValueError, match="eps"):
        smooth_constrained(lap, f, [0, 1], eps=-1.0)
    with pytest.raises(ValueError, match="f must have shape"):
        smooth(lap, f[:-1], 1.0)
    with pytest.raises(ValueError, match="duplicate"):
        smooth_constrained(lap, f, [1, 1])


def test_diffusion_smooth_matches_dense():
    pytest.importorskip("spectral_igl.filters")
    from spectral_igl.applications import diffusion_smooth

    V, F = icosphere(2)
    lap = sig.laplacian(V, F)  # full mass
    _, f = noisy(V)
    lam, X = sig.dense_eigs(lap)
    for t in (1e-3, 0.05):
        expected = X @ (np.exp(-lam * t) * (X.T @ (lap.B @ f)))
        g = diffusion_smooth(lap, f, t)
        assert np.sqrt((g - expected) @ (lap.B @ (g - expected))) < 1e-6 * np.sqrt(f @ (lap.B @ f))


def _sphere_signal(V, degree):
    x, y, z = V.T
    return {1: x, 2: x + 0.5 * y * z, 3: 5 * x * y * z + z, 5: 3 * np.real((x + 1j * y) ** 5) + x}[degree]


def _box_signal(V, k):
    x, y, z = V.T
    return np.cos(k * np.pi * x) * np.cos(np.pi * z) + np.cos(np.pi * y)


def _decade_check(lap, clean, noise, seed, **kw):
    """The chosen t beats t/10 and 10 t on the error to the clean signal (exact heat)."""
    from spectral_igl.applications import diffusion_smooth, optimal_time

    rms = np.sqrt(clean @ (lap.B @ clean) / lap.area())
    f = clean + noise * rms * np.random.default_rng(seed).standard_normal(lap.n)
    t, curve = optimal_time(lap, f, **kw)
    err = lambda u: np.sqrt((u - clean) @ (lap.B @ (u - clean)))  # noqa: E731
    e = [err(diffusion_smooth(lap, f, s)) for s in (t / 10, t, 10 * t)]
    assert e[1] < e[0] and e[1] < e[2], (t, e)
    assert e[1] < err(f)
    return t, curve, f


@pytest.mark.parametrize("degree, noise", [(1, 0.1), (1, 0.3), (1, 1.0), (3, 0.1), (3, 0.3),
                                           (3, 1.0), (5, 0.3), (5, 1.0)])
def test_optimal_time_beats_a_decade_either_side_sphere(degree, noise):
    pytest.importorskip("spectral_igl.filters")
    V, F = icosphere(3)
    lap = sig.laplacian(V, F, mass="lumped")
    t, curve, f = _decade_check(lap, _sphere_signal(V, degree), noise, seed=degree)
    # the fitted noise level is the one added (per-vertex standard deviation)
    rms = np.sqrt(_sphere_signal(V, degree) @ (lap.B @ _sphere_signal(V, degree)) / lap.area())
    assert curve["noise"] == pytest.approx(noise * rms, rel=0.1)


@pytest.mark.parametrize("k, noise", [(1, 0.1), (1, 0.3), (1, 1.0), (3, 0.1), (3, 0.3), (3, 1.0)])
def test_optimal_time_beats_a_decade_either_side_tets(k, noise):
    pytest.importorskip("spectral_igl.filters")
    from data_generators import box_tets

    V, T = box_tets((9, 9, 9), (1.0, 1.0, 1.0))
    lap = sig.laplacian(V, T, mass="lumped")
    _decade_check(lap, _box_signal(V, k), noise, seed=k)


def test_optimal_time_full_mass_and_curve():
    pytest.importorskip("spectral_igl.filters")
    V, F = icosphere(3)
    lap = sig.laplacian(V, F)
    t, curve, _ = _decade_check(lap, _sphere_signal(V, 2), 0.3, seed=0)
    assert set(curve) == {"t", "residual", "energy", "curvature", "risk", "noise"}
    assert np.all(np.diff(curve["residual"]) > 0) and np.all(np.diff(curve["energy"]) < 0)
    assert curve["t"][np.nanargmin(curve["risk"])] == t
    t_l, curve_l = sig.optimal_time(lap, _sphere_signal(V, 2), rule="lcurve")
    assert np.all(np.isnan(curve_l["risk"]))
    with pytest.raises(ValueError, match="rule"):
        sig.optimal_time(lap, _sphere_signal(V, 2), rule="gcv")


def test_heat_family_against_dense_over_all_times():
    from spectral_igl.applications import HeatFamily

    V, F = icosphere(3)
    for mass in ("full", "lumped"):
        lap = sig.laplacian(V, F, mass=mass)
        lam, X = sig.dense_eigs(lap)
        rng = np.random.default_rng(0)
        Y = np.c_[V[:, 0] + 0.1 * rng.standard_normal(lap.n), rng.choice([-1.0, 1.0], (lap.n, 3))]
        fam = HeatFamily(lap, Y)
        assert fam.lambda_max == pytest.approx(lam[-1], rel=0.02)
        assert fam.lambda_2 == pytest.approx(lam[1], rel=0.02)
        C = X.T @ (lap.B @ Y)
        for t in np.logspace(np.log10(0.01 / lam[-1]), np.log10(1 / lam[1]), 9):
            exact = X @ (np.exp(-t * lam)[:, None] * C)
            got = np.stack([fam.apply_column(j, [t])[:, 0] for j in range(Y.shape[1])], axis=1)
            err = np.sqrt(np.einsum("ij,ij->j", got - exact, lap.B @ (got - exact)))
            assert np.all(err <= 1e-6 * np.sqrt(np.einsum("ij,ij->j", Y, lap.B @ Y))), (mass, t)


@pytest.mark.parametrize("name", ["spot.obj", "fandisk.obj"])
@pytest.mark.parametrize("kind", ["iid", "normal"])
def test_optimal_shape_time_on_noisy_real_shapes(name, kind):
    from conftest import read_shared_mesh

    from data_generators.perturb import normal_noise
    from spectral_igl.applications import diffusion_smooth, optimal_shape_time

    V, F = read_shared_mesh(name)
    V = V / np.sqrt(np.sum(sig.laplacian(V, F).mass))
    h = float(np.mean(np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1)))
    rng = np.random.default_rng(1)
    Vn = V + 0.3 * h * rng.standard_normal(V.shape) if kind == "iid" else normal_noise(V, F, 0.3 * h, seed=1)
    lap = sig.laplacian(Vn, F)
    t, sigma = optimal_shape_time(lap)
    assert sigma == pytest.approx(0.3 * h, rel=0.15)  # the normal noise added
    err = lambda u: float(np.sqrt(np.sum((u - V) * (lap.B @ (u - V)))))  # noqa: E731
    e = [err(diffusion_smooth(lap, Vn, s)) for s in (t / 10, t, 10 * t, h * h)]
    assert e[1] < e[0] and e[1] < e[2] and e[1] < err(Vn)
    assert e[1] < e[3]  # better than the former default t = h^2


@pytest.mark.parametrize("name", ["cow.obj", "fandisk.obj"])
def test_optimal_time_on_noisy_functions_on_real_shapes(name):
    from conftest import read_shared_mesh

    V, F = read_shared_mesh(name)
    V = V / np.sqrt(np.sum(sig.laplacian(V, F).mass))
    lap = sig.laplacian(V, F)
    c = V - V.mean(0)
    for clean in (np.sin(4 * c[:, 0]) + 3 * np.cos(3 * c[:, 1]) * c[:, 2], c[:, 0] + 0.5 * c[:, 1] * c[:, 2]):
        for noise in (0.1, 1.0):
            _decade_check(lap, clean, noise, seed=2)


def test_optimal_shape_time_on_a_flat_mesh(tmp_path):
    """A flat mesh has no normal noise to measure: the time comes from the risk rule of the
    in-plane coordinates (the constant one left out), and ``spectral-igl smooth`` runs."""
    import igl
    from scipy.spatial import Delaunay

    from spectral_igl.applications.scale import optimal_shape_time, optimal_time
    from spectral_igl.cli import main

    g = np.stack(np.meshgrid(np.linspace(0, 1, 20), np.linspace(0, 1, 20)), -1).reshape(-1, 2)
    g += 0.01 * np.random.default_rng(0).standard_normal(g.shape)
    F = Delaunay(g).simplices.astype(np.int64)
    V = np.c_[g, np.zeros(len(g))]
    lap = sig.laplacian(V, F)
    t, sigma = optimal_shape_time(lap)
    assert sigma == 0.0
    expect = np.median([optimal_time(lap, V[:, j])[0] for j in range(2)])
    assert t == expect and np.isfinite(t) and t > 0
    path = tmp_path / "flat.obj"
    igl.write_triangle_mesh(str(path), V, F)
    out = tmp_path / "smoothed.obj"
    assert main(["smooth", str(path), "--out", str(out)]) == 0
    Vs, _ = igl.read_triangle_mesh(str(out))
    assert np.abs(Vs[:, 2]).max() == 0.0 and 0 < np.abs(Vs - V).max() < 0.1
