"""Many scales from common poles (heat, WKS), many sources per solve, and the factor budget."""
import numpy as np
import pytest

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl.families import family_diagonals, heat_columns, heat_diagonals, heat_targets
from spectral_igl.filters import heat
from spectral_igl.laplacian.cache import BUDGET_FRACTION, Cache, available_memory


@pytest.fixture(scope="module")
def sphere():
    lap = sig.laplacian(*icosphere(3))          # n = 642
    lam, X = sig.dense_eigs(lap)
    return lap, lam, X


def test_heat_diagonals_match_dense_truth_within_their_bounds(sphere):
    lap, lam, X = sphere
    times = np.geomspace(1e-2, 1.0, 12)[::-1]       # any order
    md = heat_diagonals(lap, times)
    truth = (X ** 2) @ np.exp(-np.outer(lam, times))
    err = np.abs(md.values - truth)
    assert md.values.shape == (lap.n, times.size)
    assert np.all(err <= md.abs_bound)                           # certified, entry by entry
    # every member certifies the one-time path's target, at fewer factorizations than 12
    # separate times (the entry bounds differ by the rounding allowance of more poles)
    targets = heat_targets(lap, times, 1e-8)
    assert np.all(md.eps <= targets)
    total = 0
    for k in (0, 5, 11):
        _, info = sig.kernel_diagonal(lap, heat(times[k]), return_info=True)
        total += info["factorizations"]
    assert md.n_factorizations < 4 * total


def test_hks_many_times_agrees_with_single_times(sphere):
    lap, lam, X = sphere
    times = [0.02, 0.05, 0.3]
    H = sig.hks(lap, times, method="selinv")
    for j, t in enumerate(times):
        single, info = sig.kernel_diagonal(lap, heat(t), return_info=True)
        truth = (X ** 2) @ np.exp(-lam * t)
        assert np.abs(H[:, j] - truth).max() <= 1e-8 * truth.min()
        assert np.abs(H[:, j] - single).max() <= 2e-8 * truth.min()


def test_heat_columns_many_times_and_sources(sphere):
    lap, lam, X = sphere
    times = np.array([0.01, 0.03, 0.1])
    src = np.array([0, 17, 300])
    K, eps = heat_columns(lap, times, src)
    assert K.shape == (lap.n, 3, 3)
    minv_norm = np.sqrt(sig.diagonal.inverse_mass_diagonal(lap)[src])   # ||B^-1 e_i||_B
    for k, t in enumerate(times):
        truth = X @ (np.exp(-lam * t)[:, None] * X[src].T)
        E = K[:, :, k] - truth
        errB = np.sqrt(np.einsum("ij,ij->j", E, lap.B @ E))
        assert np.all(errB <= eps[k] * minv_norm)
        assert np.all(eps[k] <= 1e-8)               # the engine's tol: relative to ||B^-1 e_i||_B
    # the public multi-time kernel gives the same columns, clipped at 0 on this Metzler operator
    # (the exact heat kernel is non-negative, so clipping only moves an entry towards it)
    assert lap.is_metzler and K.min() < 0
    K2 = sig.kernels.heat_kernels(lap, times, src)
    np.testing.assert_allclose(K2, np.maximum(K, 0.0), rtol=0, atol=1e-14)
    assert sig.kernels.heat_kernels(lap, times, 5).shape == (lap.n, 3)


def test_wks_family_matches_dense(sphere):
    lap, lam, X = sphere
    E = np.linspace(np.log(lam[1]), np.log(lam[200]), 16)
    W = sig.wks(lap, E, method="selinv")
    ref = sig.wks(lap, E, method="dense")
    assert np.abs(W - ref).max() <= 1e-8 * np.abs(ref).max()


def test_family_diagonals_certify_every_member(sphere):
    lap, lam, X = sphere
    filts = [heat(t) for t in (0.05, 0.07, 0.1)]
    md = family_diagonals(lap, filts, 1e-10)
    assert np.all(md.eps <= 1e-10)
    truth = (X ** 2) @ np.exp(-np.outer(lam, [0.05, 0.07, 0.1]))
    assert np.all(np.abs(md.values - truth) <= md.abs_bound)


def test_bad_times_are_refused(sphere):
    lap = sphere[0]
    with pytest.raises(ValueError, match="times"):
        heat_diagonals(lap, [0.1, -1.0])
    with pytest.raises(ValueError, match="times"):
        heat_diagonals(lap, [])


# ------------------------------------------------------------------------------- budget
def test_factor_slot_evicts_least_recently_used_by_bytes():
    c = Cache(factor_budget=2500)
    for key in "abc":
        c.put("factor", key, np.zeros(100))      # 800 bytes each
    c.get("factor", "a")                          # a is now the most recently used
    c.put("factor", "d", np.zeros(100))          # 3200 > 2500: evict b (least recent)
    assert c.keys("factor") == ["c", "a", "d"]
    assert c.slot_nbytes("factor") == 2400
    c.factor_budget = 1000                        # shrinking the budget evicts at once
    assert c.keys("factor") == ["d"]
    c.put("factor", "big", np.zeros(1000))       # a lone entry over the budget is kept
    assert c.keys("factor") == ["big"]
    with pytest.raises(ValueError, match="factor_budget"):
        c.factor_budget = -1


def test_default_budget_is_a_fraction_of_available_memory():
    c = Cache()
    assert 0 < c.factor_budget <= BUDGET_FRACTION * available_memory() * 1.2
    c.factor_budget = None
    assert c.factor_budget > 0


def test_budget_bounds_the_cached_factorizations(sphere):
    lap = sig.laplacian(*icosphere(3))
    one = sig.linalg.shifted_factor(lap, 0.1)
    lap.cache.factor_budget = int(1.5 * one.nbytes)
    for beta in (0.2, 0.3, 0.4):
        sig.linalg.shifted_factor(lap, beta)
    assert lap.cache.slot_nbytes("factor") <= 1.5 * one.nbytes
    assert len(lap.cache.keys("factor")) == 1


def test_many_sources_take_the_block_path_above_the_dense_limit():
    from _spectral_truth import torus

    lap = sig.laplacian(*torus(80, 50))            # 4,000 vertices > EXACT_MAX
    src = np.arange(0, 4000, 400)                   # 10 sources
    assert sig.kernels.block_sources(lap, "auto", "mass", src.size)
    K = sig.heat_kernel(lap, 1e-2, src)             # one factorization per pole, one block
    k0 = sig.heat_kernel(lap, 1e-2, int(src[3]))    # one source: the Krylov path
    e = K[:, 3] - k0
    minv_norm = np.sqrt(sig.diagonal.inverse_mass_diagonal(lap)[src[3]])
    assert np.sqrt(e @ (lap.B @ e)) <= 2e-8 * minv_norm       # both within tol of the truth
    D = sig.pairwise_spectral_distance(lap, heat(5e-3), src)
    d = sig.diffusion_distance(lap, 1e-2, int(src[0]), src)
    np.testing.assert_allclose(D[0], d, rtol=1e-6, atol=1e-8 * d.max())
