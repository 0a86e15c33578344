"""Shape comparison: ShapeDNA and the heat trace against dense eigenvalues, invariances, distances."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

import spectral_igl as sig
from data_generators import icosphere
from data_generators.perturb import normal_noise, resample
from spectral_igl.collection import Job

U = np.finfo(float).eps


@pytest.fixture(scope="module")
def blob():
    """An irregular closed surface without symmetry: a noisy, randomly resampled icosphere."""
    V, F = icosphere(2)
    V = normal_noise(V * [1.0, 0.8, 0.6], F, 0.03, seed=3)
    return resample(V, F, 0.5, seed=4)


@pytest.fixture(scope="module")
def dense(blob):
    """Eigenvalues of (L, B) by a dense generalized solver, their rounding allowance, and the area."""
    lap = sig.laplacian(*blob)
    lam = np.maximum(sla.eigh(lap.L.toarray(), lap.B.toarray(), eigvals_only=True), 0.0)
    # a backward-stable dense solver moves each eigenvalue by a few n u lambda_max
    delta = 16 * lap.n * U * lam[-1]
    return lap, lam, delta, lap.B.sum()


def test_shape_dna_is_the_dense_spectrum_times_the_area(dense):
    lap, lam, delta, area = dense
    k = 30
    v, info = sig.shape_dna(lap, k, return_info=True)
    assert info["bound_kind"] == "proof" and info["method"] == "eigs" and info["normalize"] == "shape"
    assert info["abs_error"].shape == (k,) and info["scale"] == pytest.approx(area, rel=1e-14)
    assert np.all(np.abs(v - lam[:k] * area) <= info["abs_error"] + delta * area)
    assert np.all(info["abs_error"] < 1e-8 * v.max())
    # no normalisation: the eigenvalues themselves
    assert np.allclose(sig.shape_dna(lap, k, normalize=None), v / area, rtol=1e-12, atol=1e-12)


def test_shape_dna_of_a_mesh_is_the_finite_element_spectrum(blob):
    """From the arrays, ShapeDNA's own Laplacian (Reuter et al., LaPy): libigl's cotan matrix
    and consistent mass, solved densely, within the certified bound per entry."""
    import igl

    V, F = blob
    L = -igl.cotmatrix(V, F).toarray()
    M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_FULL).toarray()
    lam = np.maximum(sla.eigh(L, M, eigvals_only=True), 0.0)
    k = 30
    v, info = sig.shape_dna((V, F), k, return_info=True)
    area = M.sum()
    assert info["scale"] == pytest.approx(area, rel=1e-12)
    delta = 16 * len(V) * U * lam[-1] * area
    assert np.all(np.abs(v - lam[:k] * area) <= info["abs_error"] + delta)
    # the default (lumped) Laplacian's spectrum differs from it by far more than the bounds
    lumped = sig.shape_dna(sig.laplacian(V, F), k)
    assert np.max(np.abs(lumped - v)[1:] / v[1:]) > 1e3 * np.max(info["abs_error"][1:] / v[1:])


def test_heat_trace_is_the_sum_of_exponentials_per_entry(dense):
    lap, lam, delta, area = dense
    tau = np.array([1e-3, 1e-2, 0.1, 1.0])
    z, info = sig.heat_trace(lap, tau, return_info=True)
    t = tau * area
    assert np.allclose(info["times"], t, rtol=1e-15) and info["time_unit"] == "shape"
    exact = np.exp(-np.outer(t, lam)).sum(axis=1)
    # the truth's own error: |d/dλ e^{-tλ}| <= t, over n eigenvalues each off by delta
    allowance = lap.n * t * delta + 4 * lap.n * U * exact
    assert info["bound_kind"] == "proof" and info["abs_error"].shape == (4,)
    assert np.all(np.abs(z - exact) <= info["abs_error"] + allowance)
    assert np.all(info["abs_error"] < 1e-6 * exact)
    # at large times only the constants remain: one component
    assert z[-1] == pytest.approx(1.0, abs=1e-6)
    # a scalar time gives a float and a float bound
    z1, i1 = sig.heat_trace(lap, 0.1, return_info=True)
    assert isinstance(z1, float) and isinstance(i1["abs_error"], float)
    assert abs(z1 - exact[2]) <= i1["abs_error"] + allowance[2]


def _permuted(V, F, seed):
    p = np.random.default_rng(seed).permutation(len(V))
    inv = np.empty_like(p)
    inv[p] = np.arange(len(p))
    return V[p], inv[F]


@pytest.mark.parametrize("signature", ["shape_dna", "heat_trace"])
def test_signatures_are_invariant_to_scale_and_vertex_order(blob, signature):
    V, F = blob
    fn = sig.shape_dna if signature == "shape_dna" else sig.heat_trace
    kw = {"k": 20} if signature == "shape_dna" else {"times": [3e-3, 3e-2, 0.3]}
    ref, info = fn(sig.laplacian(V, F), return_info=True, **kw)
    for other in [(1e-3 * V, F), (1e3 * V, F), _permuted(V, F, 5)]:
        got, ginfo = fn(sig.laplacian(*other), return_info=True, **kw)
        # the two results are each within their bound of the same exact (scale-free) value
        assert np.all(np.abs(got - ref) <= info["abs_error"] + ginfo["abs_error"])
        assert np.all(info["abs_error"] < 1e-6 * np.abs(ref).max())


@pytest.mark.parametrize("signature", ["shape_dna", "heat_trace"])
def test_distance_zero_for_one_shape_symmetric_and_bounded(blob, signature):
    V, F = blob
    kw = {"k": 20} if signature == "shape_dna" else {"times": [3e-3, 3e-2, 0.3]}
    a, b = sig.laplacian(V, F), sig.laplacian(*icosphere(2))
    assert sig.shape_distance(a, a, signature, **kw) == 0.0
    # the same shape at another scale: zero up to the bounds of the two signatures
    d_scaled, info_s = sig.shape_distance(a, (1e2 * V, F), signature, return_info=True, **kw)
    assert d_scaled <= info_s["abs_error"]
    d_ab, info = sig.shape_distance(a, b, signature, return_info=True, **kw)
    assert d_ab == sig.shape_distance(b, a, signature, **kw)
    assert info["bound_kind"] == "proof" and info["abs_error"] < 1e-3 * d_ab
    # the matrix over precomputed signatures agrees with the pairwise distances
    fn = sig.shape_dna if signature == "shape_dna" else sig.heat_trace
    S = [fn(x, **kw) for x in (a, b, a)]
    D = sig.shape_distance_matrix(S, signature)
    assert np.array_equal(D, D.T) and np.all(np.diag(D) == 0) and D[0, 2] == 0
    assert D[0, 1] == pytest.approx(d_ab, rel=1e-13)


def test_shape_dna_distance_is_lapy_s_reweighted_euclidean(dense):
    lap, lam, delta, area = dense
    b = sig.laplacian(*icosphere(2))
    lb = sla.eigh(b.L.toarray(), b.B.toarray(), eigvals_only=True)[:10] * b.B.sum()
    la = lam[:10] * area
    i = np.arange(1, 10)
    expected = np.linalg.norm(la[1:] / i - lb[1:] / i)
    d, info = sig.shape_distance(lap, b, "shape_dna", k=10, return_info=True)
    # the dense truth is itself off by up to delta per eigenvalue (and b's by its own)
    delta_b = 16 * b.n * U * sla.eigh(b.L.toarray(), b.B.toarray(), eigvals_only=True)[-1]
    allowance = np.linalg.norm((delta * area + delta_b * b.B.sum()) / i)
    assert abs(d - expected) <= info["abs_error"] + allowance
    assert info["abs_error"] < 1e-8 * d


def test_jobs_store_the_signatures_with_their_bounds(blob):
    lap = sig.laplacian(*blob)
    arrays, bounds = Job.heat_trace([1e-2, 0.1])("blob", lap)
    z, info = sig.heat_trace(lap, [1e-2, 0.1], return_info=True)
    assert np.array_equal(arrays["heat_trace"], z)
    assert np.array_equal(arrays["heat_trace_abs_error"], info["abs_error"])
    assert bounds["bound_kind"] == "proof" and bounds["time_unit"] == "shape"
    assert np.allclose(bounds["absolute_times"], info["times"])
    arrays, bounds = Job.shape_dna(8)("blob", lap)
    assert np.array_equal(arrays["shape_dna"], sig.shape_dna(lap, 8))
    assert arrays["shape_dna_abs_error"].shape == (8,) and bounds["bound_kind"] == "proof"
    assert Job.shape_dna(8).key() != Job.shape_dna(9).key()
    assert Job.heat_trace().params["times"] is None
    # a collection gives ShapeDNA the Laplacian sig.shape_dna builds from a mesh, others the default
    fem = sig.laplacian(*blob, **Job.shape_dna(8).laplacian_options())
    assert np.array_equal(Job.shape_dna(8)("blob", fem)[0]["shape_dna"], sig.shape_dna(blob, 8))
    assert Job.heat_trace().laplacian_options() == {"weights": "auto", "mass": "lumped"}
    assert Job.shape_dna(8).laplacian_options(mass="lumped") == {"weights": "cotan", "mass": "lumped"}


def test_bad_input_is_refused_with_a_message(blob):
    V, F = blob
    lap = sig.laplacian(V, F)
    with pytest.raises(ValueError, match="lumped"):
        sig.heat_trace(sig.laplacian(V, F, mass="full"), [0.1])
    with pytest.raises(ValueError, match="signature"):
        sig.shape_distance(lap, lap, "eigenvalues")
    with pytest.raises(ValueError, match="k must be below"):
        sig.shape_dna(lap, lap.n)
    with pytest.raises(ValueError, match="normalize"):
        sig.shape_dna(lap, 5, normalize="metres")
    with pytest.raises(ValueError, match="time_unit"):
        sig.heat_trace(lap, time_unit="absolute")
    with pytest.raises(ValueError, match="signatures"):
        sig.shape_distance_matrix([1.0, 2.0])
    with pytest.raises(ValueError, match="positive"):
        sig.shape_distance_matrix([[1.0, -2.0], [1.0, 2.0]])
    with pytest.raises(ValueError, match="normalize"):
        Job.shape_dna(5, normalize="metres")


def test_heat_trace_distance_without_the_zero_modes(blob):
    """With the number of components, the features are log(Z - beta_0) and log(beta_0): checked
    against traces summed from every dense eigenvalue but the zero ones."""
    V, F = blob
    W, G = icosphere(1)
    shapes = [(V, F), (np.r_[V, W + 3.0], np.r_[F, G + len(V)]), (1.5 * V, F)]   # 1, 2, 1 components
    tau = np.array([1e-2, 3e-2, 0.1])
    laps = [sig.laplacian(*s) for s in shapes]
    Z, E, exact, top = [], [], [], []
    for lap in laps:
        z, info = sig.heat_trace(lap, tau, return_info=True)
        Z.append(z)
        E.append(info["abs_error"])
        lam = np.sort(sla.eigh(lap.L.toarray(), lap.B.toarray(), eigvals_only=True))
        top.append(lam[-1])
        rest = lam[lap.n_components:]
        exact.append(np.exp(-np.outer(tau * lap.B.sum(), rest)).sum(axis=1))
    b = np.array([lap.n_components for lap in laps])
    assert list(b) == [1, 2, 1]
    D, info = sig.shape_distance_matrix(Z, abs_error=E, return_info=True, components=b)
    X = np.c_[np.log(np.array(exact)), np.log(b)] / np.sqrt(tau.size)
    truth = np.linalg.norm(X[:, None] - X[None], axis=2)
    # the dense truth is itself off by delta = 16 n u lambda_max per eigenvalue, so each of its
    # terms e^{-t lambda} by t delta relative, and log(Z - beta_0) by t delta
    slack = np.array([tau[-1] * lap.B.sum() * 16 * lap.n * U * lam_max for lap, lam_max in zip(laps, top)])
    allowance = slack[:, None] + slack[None, :]
    assert np.all(np.abs(D - truth) <= info["abs_error"] + allowance)
    assert D[0, 2] <= info["abs_error"][0, 2] and D[0, 1] > 1e3 * info["abs_error"][0, 1]
    assert info["bound_kind"] == "proof"
    with pytest.raises(ValueError, match="only the zero eigenvalues remain"):
        sig.shape_distance_matrix(Z, components=[1, 3, 1])
    with pytest.raises(ValueError, match="components must be"):
        sig.shape_distance_matrix(Z, components=[1, 2])
    with pytest.raises(ValueError, match="components applies to heat traces"):
        sig.shape_distance_matrix(Z, "shape_dna", components=b)
