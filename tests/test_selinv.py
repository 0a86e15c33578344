"""Supernodal LDLᵀ, selected inversion, and the ``"selinv"`` kernel diagonal against dense truth."""
import numpy as np
import pytest
import scipy.sparse as sp
from _spectral_truth import dense_kernel, dense_sq_distances, torus

import spectral_igl as sig
from data_generators import box_tets, icosphere
from spectral_igl.linalg.ldlt import LDLT, Pattern, available

F = pytest.importorskip("spectral_igl.filters")
pytestmark = pytest.mark.skipif(not available(), reason="compiled LDLT missing")


@pytest.fixture(scope="module")
def lap_torus():
    return sig.laplacian(*torus(20, 10, jitter=0.3, seed=3), mass="full")


@pytest.fixture(scope="module")
def lap_two():
    """Two spheres of different size: two components, two zero eigenvalues."""
    V1, F1 = icosphere(2)
    V2, F2 = icosphere(1)
    V = np.vstack([V1, 0.5 * V2 + 3.0])
    return sig.laplacian(V, np.vstack([F1, F2 + len(V1)]))


@pytest.mark.parametrize("shift", [0.3, -2.0 + 5.0j, 7.0j])
def test_ldlt_solve_and_inverse_diagonal_match_dense(lap_torus, shift):
    """Real SPD and complex symmetric (definite real or imaginary part) matrices."""
    lap = lap_torus
    A = (lap.L - shift * lap.B) if np.iscomplexobj(shift) else (lap.L + shift * lap.B)
    Ad = A.toarray()
    fac = LDLT(A)
    Zi = np.linalg.inv(Ad)
    rng = np.random.default_rng(0)
    b = rng.standard_normal((lap.n, 3))
    x = fac.solve(b)
    assert np.abs(Ad @ x - b).max() <= 1e-10 * np.abs(b).max()
    d = fac.inverse_diagonal()
    assert np.abs(d - np.diag(Zi)).max() <= 1e-12 * np.abs(np.diag(Zi)).max()


def test_ldlt_pattern_shared_by_shifts_and_tets():
    """One analysis serves every matrix on the pattern; tetrahedral meshes work too."""
    lap = sig.laplacian(*box_tets((5, 4, 3)))
    pat = Pattern(abs(lap.L) + abs(lap.B))
    for z in (-1.0, -3.0 + 40.0j):
        A = lap.L - z * lap.B
        d = LDLT(A, pat).inverse_diagonal()
        ref = np.diag(np.linalg.inv(A.toarray()))
        assert np.abs(d - ref).max() <= 1e-12 * np.abs(ref).max()


def test_ldlt_rejects_bad_input():
    with pytest.raises(ValueError, match="square"):
        LDLT(sp.csr_matrix(np.ones((2, 3))))
    with pytest.raises(ValueError, match="pivot"):          # needs pivoting: refused, no crash
        LDLT(sp.csr_matrix(np.array([[0.0, 1.0], [1.0, 0.0]])))
    A = sp.csr_matrix(np.diag([1.0, 2.0, 3.0]))
    pat = Pattern(A)
    with pytest.raises(ValueError, match="outside"):
        LDLT(sp.csr_matrix(np.array([[1.0, 1.0, 0], [1.0, 2.0, 0], [0, 0, 3.0]])), pat)
    with pytest.raises(ValueError, match="non-finite"):
        LDLT(sp.csr_matrix(np.diag([1.0, np.nan, 3.0])), pat)


CASES = [
    ("commute", F.commute_time().square, lambda s: np.where(s > 0, 1.0 / s, 0.0), True),
    ("biharmonic", F.biharmonic().square, lambda s: np.where(s > 0, s ** -2.0, 0.0), True),
    ("heat small t", F.heat(2e-3), lambda s: np.exp(-2e-3 * s), False),
    ("heat", F.heat(0.2), lambda s: np.exp(-0.2 * s), False),
    ("mexican hat", F.mexican_hat(0.05).square, lambda s: (0.05 * s * np.exp(-0.05 * s)) ** 2, False),
]


@pytest.mark.parametrize("mass", ["full", "lumped"])
@pytest.mark.parametrize("name,filt,fn,singular", CASES, ids=[c[0] for c in CASES])
def test_selinv_diagonal_matches_dense_within_its_bound(lap_torus, lap_two, mass, name, filt, fn, singular):
    for lap0 in (lap_torus, lap_two):
        lap = lap0 if mass == "full" else sig.make_laplacian(lap0.L, sp.diags(lap0.mass))
        ref = np.diag(dense_kernel(lap, fn, singular))
        d, info = sig.kernel_diagonal(lap, filt, method="selinv", return_info=True)
        err = np.abs(d - ref)
        # certified approximation bound plus rounding; exact filters have bound 0
        assert err.max() <= info["abs_error_bound"] + 1e-9 * np.abs(ref).max()
        assert err.max() <= 1e-7 * np.abs(ref).max()
        assert info["sample_rel_error"] < 1e-8          # selected inversion == solves


def test_selinv_is_what_auto_uses_and_falls_back(lap_torus):
    lap = lap_torus
    _, info = sig.kernel_diagonal(lap, F.heat(0.1), return_info=True)
    assert info["method"] == "selinv"
    # s^-3 (the poly-harmonic k = 3 distance): the circle rule on the resolvent, exact up to
    # a proved relative aliasing error
    poly3 = F.polyharmonic(3).square
    d, info = sig.kernel_diagonal(lap, poly3, return_info=True)
    assert info["method"] == "selinv" and info["bound_kind"] == "proof"
    ref = np.diag(dense_kernel(lap, lambda s: np.where(s > 0, s ** -3.0, 0.0), True))
    assert np.abs(d - ref).max() <= info["abs_error_bound"] + 1e-13 * ref.max()
    # the bound is the proved aliasing (3.5e-12 relative) plus the a-priori rounding allowance
    # 64 eps p (1 + 3 lambda_max / lambda_min+) per unit of the terms' magnitudes (a few 1e-9 here)
    assert info["abs_error_bound"] <= 1e-8 * ref.max()
    # s^-2.5 has no rational fit with poles away from 0: auto falls back, selinv refuses
    poly5 = F.polyharmonic(5)
    d, info = sig.kernel_diagonal(lap, poly5, return_info=True)
    assert info["method"] == "dense"
    ref = np.diag(dense_kernel(lap, lambda s: np.where(s > 0, s ** -2.5, 0.0), True))
    assert np.abs(d - ref).max() <= 1e-8 * ref.max()
    with pytest.raises(ValueError, match="selinv"):
        sig.kernel_diagonal(lap, poly5, method="selinv")
    with pytest.raises(ValueError, match="seed"):   # B G B needs a diagonal B
        sig.kernel_diagonal(lap, F.heat(0.1), method="selinv", delta="seed")


@pytest.mark.parametrize("delta", ["mass", "seed"])
def test_selinv_one_to_all_distances_match_dense(lap_torus, delta):
    lap = lap_torus if delta == "mass" else sig.make_laplacian(lap_torus.L, sp.diags(lap_torus.mass))
    for filt, fn, singular in [(F.biharmonic(), lambda s: np.where(s > 0, 1.0 / s, 0.0), True),
                               (F.heat(0.01), lambda s: np.exp(-0.01 * s), False)]:
        for src in (0, 77):
            d, info = sig.spectral_distance(lap, filt, src, diagonal="selinv", delta=delta, return_info=True)
            ref = np.sqrt(np.maximum(dense_sq_distances(lap, fn, src, singular, delta=delta), 0.0))
            assert info["method"] == "selinv"
            assert np.all(d >= 0) and d[src] == 0.0
            assert np.abs(d - ref).max() <= 1e-7 * ref.max()
            assert info["d2_error_bound"] <= 1e-6 * ref.max() ** 2


@pytest.mark.parametrize("t", [1e-5, 1e-3, 1e-1])
def test_selinv_one_to_all_at_10k_matches_exact_norms(t):
    """Above the dense range auto uses selinv: every d >= 0 and d equals the exact B-norm."""
    lap = sig.laplacian(*icosphere(5))                    # n = 10,242, unit sphere
    src = 17
    d, info = sig.diffusion_distance(lap, t, src, return_info=True)
    assert info["method"] == "selinv" and lap.n > 3000
    assert np.all(np.isfinite(d)) and np.all(d >= 0) and d[src] == 0.0
    rng = np.random.default_rng(1)
    targets = np.r_[rng.choice(lap.n, 6, replace=False), np.flatnonzero(lap.L[[src]].toarray()[0])[:2]]
    exact = sig.diffusion_distance(lap, t, src, targets=targets)   # norms of filtered differences
    assert np.abs(d[targets] - exact).max() <= 1e-7 * d.max()


def test_shifted_factor_ldlt_accepts_definite_and_refuses_indefinite(lap_torus):
    """theta B + beta L needs no pivoting when a part of it is definite, also negative
    definite (a real pole above the spectrum); an indefinite real shift is refused."""
    from spectral_igl.laplacian import lambda_max

    lap = lap_torus
    b = lambda_max(lap)
    rhs = np.random.default_rng(2).standard_normal(lap.n)
    for beta, theta in [(1.0, -1.5 * b), (1.0, 2.0), (0.5, -3.0 + 1.0j)]:
        fac = sig.linalg.shifted_factor(lap, beta, theta, backend="ldlt")
        A = (theta * lap.B + beta * lap.L).toarray()
        assert np.abs(fac.solve(rhs) - np.linalg.solve(A, rhs)).max() <= 1e-10 * np.abs(np.linalg.solve(A, rhs)).max()
    with pytest.raises(ValueError, match="definite"):
        sig.linalg.shifted_factor(lap, 1.0, -0.5 * b, backend="ldlt")
