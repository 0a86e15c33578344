"""Spectral distances: dense ground truth, positivity, isometry, scale covariance, sphere."""
import numpy as np
import pytest
from _spectral_truth import dense_sq_distances, sphere_heat_kernel, strip, torus

import spectral_igl as sig
from data_generators import icosphere

F = pytest.importorskip("spectral_igl.filters")


@pytest.fixture(scope="module")
def lap_torus():
    return sig.laplacian(*torus(18, 9, jitter=0.3, seed=11))


NAMED = [
    ("diffusion", lambda lap, s, **k: sig.diffusion_distance(lap, 0.03, s, **k),
     lambda x: np.exp(-0.015 * x), False),
    ("commute_time", lambda lap, s, **k: sig.commute_time_distance(lap, s, **k),
     lambda x: np.where(x > 0, x ** -0.5, 0), True),
    ("biharmonic", lambda lap, s, **k: sig.biharmonic_distance(lap, s, **k),
     lambda x: np.where(x > 0, 1.0 / x, 0), True),
    ("polyharmonic3", lambda lap, s, **k: sig.polyharmonic_distance(lap, 3, s, **k),
     lambda x: np.where(x > 0, x ** -1.5, 0), True),
    ("mexican_hat", lambda lap, s, **k: sig.mexican_hat_distance(lap, 0.05, s, **k),
     lambda x: 0.05 * x * np.exp(-0.05 * x), False),
    ("wave", lambda lap, s, **k: sig.wave_distance(lap, 0.7, s, **k),
     lambda x: np.exp(-0.7j * x), False),
]


@pytest.mark.parametrize("name,dist,fn,singular", NAMED, ids=[d[0] for d in NAMED])
def test_named_distances_match_dense(lap_torus, name, dist, fn, singular):
    lap = lap_torus
    s = 13
    ref = np.sqrt(np.maximum(dense_sq_distances(lap, fn, s, singular), 0))
    d_all = dist(lap, s)                       # one-to-all, exact diagonal (small n)
    assert d_all.shape == (lap.n,) and d_all[s] == 0.0
    assert np.abs(d_all - ref).max() <= 1e-7 * ref.max()
    t = np.array([0, 13, 40, 77])
    d_some = dist(lap, s, targets=t)           # one-to-many: norms
    assert np.abs(d_some - ref[t]).max() <= 1e-7 * ref.max()
    d_one = dist(lap, s, targets=40)           # one-to-one
    assert isinstance(d_one, float) and abs(d_one - ref[40]) <= 1e-7 * ref.max()


def test_seed_delta_matches_eq5(lap_torus):
    lap = lap_torus
    fn = lambda x: np.where(x > 0, 1.0 / x, 0)  # noqa: E731
    ref = np.sqrt(np.maximum(dense_sq_distances(lap, fn, 5, True, delta="seed"), 0))
    d = sig.biharmonic_distance(lap, 5, delta="seed")
    assert np.abs(d - ref).max() <= 1e-7 * ref.max()


def test_pairwise(lap_torus):
    lap = lap_torus
    seeds = [1, 30, 60, 99, 150]
    D = sig.pairwise_spectral_distance(lap, F.biharmonic(), seeds)
    fn = lambda x: np.where(x > 0, 1.0 / x, 0)  # noqa: E731
    for a, s in enumerate(seeds):
        ref = np.sqrt(np.maximum(dense_sq_distances(lap, fn, s, True), 0))
        assert np.abs(D[a] - ref[seeds]).max() <= 1e-7 * ref.max()
    assert np.all(D == D.T) and np.all(np.diag(D) == 0)


NAMED_PAIRWISE = [
    ("diffusion", lambda lap, S: sig.pairwise_diffusion_distance(lap, 0.01, S),
     lambda lap, s: sig.diffusion_distance(lap, 0.01, s)),
    ("commute_time", lambda lap, S: sig.pairwise_commute_time_distance(lap, S),
     lambda lap, s: sig.commute_time_distance(lap, s)),
    ("biharmonic", lambda lap, S: sig.pairwise_biharmonic_distance(lap, S),
     lambda lap, s: sig.biharmonic_distance(lap, s)),
    ("polyharmonic", lambda lap, S: sig.pairwise_polyharmonic_distance(lap, 3, S),
     lambda lap, s: sig.polyharmonic_distance(lap, 3, s)),
    ("wave", lambda lap, S: sig.pairwise_wave_distance(lap, 0.3, S),
     lambda lap, s: sig.wave_distance(lap, 0.3, s)),
    ("mexican_hat", lambda lap, S: sig.pairwise_mexican_hat_distance(lap, 0.05, S),
     lambda lap, s: sig.mexican_hat_distance(lap, 0.05, s)),
]


@pytest.mark.parametrize("name,pair,one", NAMED_PAIRWISE, ids=[c[0] for c in NAMED_PAIRWISE])
def test_named_pairwise_equals_one_to_all(lap_torus, name, pair, one):
    lap = lap_torus
    seeds = [1, 30, 60, 99, 150]
    D = pair(lap, seeds)
    for a, s in enumerate(seeds):
        row = one(lap, s)[seeds]
        assert np.abs(D[a] - row).max() <= 1e-6 * row.max(), name
    assert np.all(D == D.T) and np.all(np.diag(D) == 0)


def test_pairwise_heat_filter_is_diffusion_at_twice_the_time(lap_torus):
    """The documented factor 2: the filter heat(t) gives |phi|^2 = e^{-2ts}."""
    lap = lap_torus
    seeds = [1, 30, 60]
    D = sig.pairwise_spectral_distance(lap, F.heat(0.01), seeds)
    assert np.allclose(D, sig.pairwise_diffusion_distance(lap, 0.02, seeds), rtol=1e-8, atol=0)
    assert not np.allclose(D, sig.pairwise_diffusion_distance(lap, 0.01, seeds), rtol=1e-3)


def test_eigen_baseline_converges_to_exact(lap_torus):
    lap = lap_torus
    exact = sig.biharmonic_distance(lap, 3)
    full = sig.biharmonic_distance(lap, 3, diagonal="eigen", k=lap.n)
    assert np.abs(full - exact).max() <= 1e-7 * exact.max()
    trunc = sig.biharmonic_distance(lap, 3, diagonal="eigen", k=20)
    assert np.abs(trunc - exact).max() > 1e-4 * exact.max()  # truncation error is real


@pytest.mark.parametrize("t", [1e-4, 1e-2, 1.0])
def test_positivity_sweep_with_poor_diagonal(t):
    """A deliberately poor diagonal estimate (distance-1 colouring, no deflation) makes
    G_ii + G_jj - 2 G_ij negative near the source; those targets must be recomputed as
    exact norms, so every returned squared distance equals a norm or exceeds its error."""
    V, Fc = icosphere(3)
    lap = sig.laplacian(V, Fc)
    ref = np.sqrt(np.maximum(dense_sq_distances(lap, lambda x: np.exp(-t * x / 2), 0), 0))
    d, info = sig.diffusion_distance(lap, t, 0, diagonal="probing", distance=1, k=0, samples=4,
                                     return_info=True)
    assert np.all(d >= 0) and d[0] == 0
    redo = info["recomputed"]
    assert np.abs(d[redo] - ref[redo]).max(initial=0) <= 1e-7 * ref.max()
    # the nearest neighbours' distances are never the clipped remains of a bad estimate
    nbrs = lap.L[0].indices[lap.L[0].indices != 0]
    assert np.all(np.isin(nbrs, redo) | (np.abs(d[nbrs] - ref[nbrs]) <= 0.5 * ref[nbrs]))


@pytest.mark.parametrize("level", [2, 3])
def test_positivity_all_filters_exact(level):
    lap = sig.laplacian(*icosphere(level))
    for filt in (F.heat(1e-4), F.heat(1.0), F.biharmonic(), F.commute_time(), F.mexican_hat(0.01)):
        d = sig.spectral_distance(lap, filt, 4)
        assert np.all(np.isfinite(d)) and np.all(d >= 0) and d[4] == 0
        assert np.all(d[np.arange(lap.n) != 4] > 0)  # nullity only at the source


def test_sphere_diffusion_distance_analytic():
    """d_t^2(p,q) = 2 (K_t(p,p) - K_t(p,q)) on the unit sphere; lumped mass, O(h^2)."""
    t, errs = 0.1, []
    for level in (2, 3, 4):
        V, Fc = icosphere(level)
        lap = sig.laplacian(V, Fc, mass="lumped")
        tg = np.arange(0, lap.n, 5)
        d = sig.diffusion_distance(lap, t, 0, targets=tg)
        exact = np.sqrt(2 * (sphere_heat_kernel(t, 1.0) - sphere_heat_kernel(t, V[tg] @ V[0])))
        errs.append(np.abs(d - exact).max() / exact.max())
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert errs[-1] < 1e-2 and np.all(rates > 1.8), (errs, rates)


def test_isometry_strip_vs_half_cylinder():
    """Same intrinsic geometry (a flat strip rolled into a half-cylinder): the distances
    agree up to the discretization of the bending (chords instead of arcs), O(h^2)."""
    gaps = []
    for nx, ny in ((24, 8), (48, 16)):
        lf = sig.laplacian(*strip(nx, ny))
        lr = sig.laplacian(*strip(nx, ny, rolled=True))
        s = (ny + 1) * (nx // 4) + ny // 2
        tg = np.arange(0, lf.n, 3)
        for dist in (lambda l: sig.biharmonic_distance(l, s, targets=tg),
                     lambda l: sig.diffusion_distance(l, 0.05, s, targets=tg)):
            a, b = dist(lf), dist(lr)
            gaps.append(np.abs(a - b).max() / a.max())
    gaps = np.array(gaps).reshape(2, 2)
    assert np.all(gaps[1] < 5e-3), gaps
    assert np.all(gaps[1] < 0.4 * gaps[0]), gaps  # shrinks under refinement


def test_scale_covariance(lap_torus):
    lap = lap_torus
    V, Fc = lap.data["V"], lap.data["F"]
    a = 2.5
    la = sig.laplacian(a * V, Fc)
    tg = np.array([0, 20, 50, 90, 140])
    t = 0.02
    # K_t(aM) = a^-2 K_{t/a^2}(M)  =>  d_t(aM) = d_{t/a^2}(M) / a
    d1 = sig.diffusion_distance(la, t, 7, targets=tg)
    d0 = sig.diffusion_distance(lap, t / a ** 2, 7, targets=tg)
    assert np.allclose(d1, d0 / a, rtol=1e-7)
    # biharmonic scales like length, commute time is scale invariant in 2-D
    assert np.allclose(sig.biharmonic_distance(la, 7, targets=tg),
                       a * sig.biharmonic_distance(lap, 7, targets=tg), rtol=1e-7)
    assert np.allclose(sig.commute_time_distance(la, 7, targets=tg),
                       sig.commute_time_distance(lap, 7, targets=tg), rtol=1e-7)


def test_wave_distance_is_time_independent(lap_torus):
    lap = lap_torus
    tg = [1, 2, 50]
    d1 = sig.wave_distance(lap, 0.3, 0, targets=tg)
    d2 = sig.wave_distance(lap, 2.0, 0, targets=tg)
    assert np.allclose(d1, d2, rtol=1e-7)


def test_bad_input(lap_torus):
    with pytest.raises(ValueError):
        sig.biharmonic_distance(lap_torus, -1)
    with pytest.raises(TypeError):
        sig.biharmonic_distance(lap_torus, 1.5)
    with pytest.raises(ValueError):
        sig.biharmonic_distance(lap_torus, 0, targets=[0, lap_torus.n])
    with pytest.raises(ValueError):
        sig.diffusion_distance(lap_torus, 0.0, 0)


def test_survey_mexican_hat_distance_against_dense(lap_torus):
    lap = lap_torus
    filt = F.mexican_hat(0.05, form="survey")
    fn = lambda x: np.sqrt(0.05 * np.maximum(x, 0)) * np.exp(-(0.05 * x) ** 2)  # noqa: E731
    ref = np.sqrt(np.maximum(dense_sq_distances(lap, fn, 5, False), 0))
    d = sig.spectral_distance(lap, filt, 5)
    assert np.abs(d - ref).max() <= 1e-6 * ref.max()


@pytest.mark.parametrize("name,dist,fn,singular", [d for d in NAMED if d[0] in ("diffusion", "mexican_hat")],
                         ids=["diffusion", "mexican_hat"])
def test_one_to_all_selinv_streams_its_factors(name, dist, fn, singular):
    """Through the selected inverse, the column and the diagonal's check come from the
    diagonal's single pass over the poles: with no room in the factor budget the complex
    factorizations are not kept (with room they are), and a second source (factorizing again,
    or not) agrees with the dense truth just as well."""
    for budget in (0, None):
        lap = sig.laplacian(*torus(18, 9, jitter=0.3, seed=11))
        lap.cache.factor_budget = budget
        for s in (13, 90):
            ref = np.sqrt(np.maximum(dense_sq_distances(lap, fn, s, singular), 0))
            d, info = dist(lap, s, diagonal="selinv", return_info=True)
            assert info["method"] == "selinv"
            assert np.abs(d - ref).max() <= 1e-7 * ref.max()
            if s == 13:
                kept = [k for k in lap.cache.keys("factor") if isinstance(k[2], complex)]
                assert bool(kept) == (budget is None)


@pytest.mark.parametrize("tol", [1e-6, 1e-8, 1e-10])
def test_user_filter_distance_meets_tol_relative_to_the_distance(tol):
    """A user filter phi = 1/(1+s)^2: the rational fit of |phi|^2 = (1+s)^-4 has a pole of order
    4, which simple AAA poles picture as a cluster whose residues lose 1e-7 to rounding; the
    cluster is spread into a ring and the fit's target is set relative to the diagonal, so the
    one-to-all distance is within tol of the largest distance (dense eigh as the truth)."""
    lap = sig.laplacian(*icosphere(3))
    ev, X = sig.dense_eigs(lap)
    phi = lambda s: 1.0 / (1.0 + s) ** 2  # noqa: E731
    d, info = sig.spectral_distance(lap, F.Filter(phi), 0, tol=tol, return_info=True)
    ref = np.sqrt(np.maximum(((phi(ev) ** 2)[None, :] * (X - X[0]) ** 2).sum(axis=1), 0.0))
    err = np.abs(d - ref)
    assert err.max() <= tol * ref.max(), (err.max(), ref.max())
    assert np.all(err <= info["abs_error"] + 1e-15)
    assert info["bound_kind"] == "estimate"          # a user filter's fit cannot be proved
