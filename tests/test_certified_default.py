"""The default path is the certified path: every kernel entry a user reads carries a bound that
holds, ``auto`` proves, a missed tol is said every time, and per-entry relative accuracy is
proved against exact arithmetic or refused.

Ground truth: dense generalized eigendecompositions of the discrete operator (absolute errors),
and the matrix exponential in 50-digit arithmetic of the exact stored (L, B) (relative errors of
entries down to 1e-17 of the peak, where no double-precision reference is right).
"""
from __future__ import annotations

import warnings

import mpmath
import numpy as np
import pytest
import scipy.linalg as sla

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl import filters, kernels
from spectral_igl.accuracy import AccuracyWarning
from spectral_igl.approx import choose_method
from spectral_igl.approx.uniformization import metzler_heat


def _flat_boundary(n=9, seed=0):
    """A jittered planar grid, unit area, with boundary."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    V = np.c_[x.ravel(), y.ravel(), np.zeros(n * n)]
    V[:, :2] += rng.uniform(-0.25, 0.25, (n * n, 2)) / (n - 1)
    F = []
    for i in range(n - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, i * n + j + 1, (i + 1) * n + j, (i + 1) * n + j + 1
            F += [[a, b, d], [a, d, c]]
    return V, np.array(F)


def _dense_kernel(lap, filt, i):
    """Column i of X phi(Lambda) X^T; phi(0) := 0 on ker L for singular filters."""
    ev, X = sla.eigh(lap.L.toarray(), lap.B.toarray())
    zero = np.arange(ev.size) < lap.n_components
    vals = np.zeros(ev.size, dtype=complex if filt.is_complex else float)
    vals[~zero] = filt(ev[~zero])
    if not filt.singular:
        vals[zero] = filt(np.zeros(zero.sum()))
    return X @ (vals * X[i])


SHAPES = {
    "sphere": lambda: sig.laplacian(*icosphere(2)),
    "flat": lambda: sig.laplacian(*_flat_boundary()),
    "flat_full_mass": lambda: sig.laplacian(*_flat_boundary(), mass="full"),
}


@pytest.mark.parametrize("shape", sorted(SHAPES))
@pytest.mark.parametrize("t", [1e-4, 1e-2, 1.0])
def test_default_heat_column_bounds_every_entry(shape, t):
    lap = SHAPES[shape]()
    i = 7
    k, info = sig.heat_kernel(lap, t, i, return_info=True)
    ref = _dense_kernel(lap, filters.heat(t), i)
    assert info["bound_kind"] == "proof" and info["method"] == "rational"
    assert info["abs_error"].shape == k.shape
    err = np.abs(k - ref)
    assert np.all(err <= info["abs_error"]), float(np.max(err / info["abs_error"]))
    # and the bound is not vacuous: within tol * ||B^-1 e_i||_B / sqrt(c m_j) of the truth
    assert np.max(info["abs_error"]) < 1e-6 * np.max(np.abs(ref))


@pytest.mark.parametrize("name", ["biharmonic", "commute_time", "mexican_hat", "wave"])
def test_default_kernel_bounds_every_entry_other_filters(name):
    lap = SHAPES["flat"]()
    filt = filters.by_name(name, t=0.01)
    k, info = sig.spectral_kernel(lap, filt, 3, return_info=True)
    ref = _dense_kernel(lap, filt, 3)
    err = np.abs(k - ref)
    assert info["bound_kind"] in ("proof", "estimate")
    assert np.all(err <= info["abs_error"])


def test_auto_proves_heat_where_shift_invert_estimates():
    """On a 2562-vertex sphere auto took shift-and-invert at t = 0.1 and 1, whose Lanczos bound
    is an estimate there; a proving method of comparable cost exists."""
    lap = sig.laplacian(*icosphere(4))
    for t in (1e-6, 1e-3, 0.1, 1.0, 10.0):
        assert choose_method(lap, filters.heat(t)) == "rational"
        _, info = sig.heat_kernel(lap, t, 0, return_info=True)
        assert info["bound_kind"] == "proof"


def test_missed_tol_warns_every_time_with_the_achieved_bound():
    lap = sig.laplacian(*icosphere(2))
    for _ in range(2):
        with pytest.warns(AccuracyWarning, match="error bound") as rec:
            _, info = sig.spectral_kernel(lap, filters.heat(0.01), 0, method="rational", tol=1e-16,
                                          return_info=True)
        assert len(rec) == 1
    achieved = float(info["bnorm_error"])
    assert f"{achieved:.3g}" in str(rec[0].message)


def test_met_tol_is_silent():
    lap = sig.laplacian(*icosphere(2))
    with warnings.catch_warnings():
        warnings.simplefilter("error", AccuracyWarning)
        sig.heat_kernel(lap, 0.01, 0)
        sig.spectral_kernel(lap, filters.biharmonic(), 0)


def test_heat_on_a_metzler_operator_is_never_negative():
    lap = sig.laplacian(*icosphere(3))
    assert lap.is_metzler
    K = sig.heat_kernel(lap, 1e-4, np.arange(10))
    assert K.min() >= 0.0


# ----------------------------------------------------------------------- exact arithmetic
def _exact_heat(lap, t, i, dps=50):
    """e^{-tA} B^-1 e_i in dps-digit arithmetic from the stored float64 L and lumped mass."""
    mpmath.mp.dps = dps
    L = lap.L.toarray()
    m = lap.mass
    n = lap.n
    A = mpmath.matrix(n, n)
    for j in range(n):
        for k in range(n):
            if L[j, k] != 0:
                A[j, k] = -mpmath.mpf(t) * mpmath.mpf(L[j, k]) / mpmath.mpf(m[j])
    E = mpmath.expm(A)
    return [E[j, i] / mpmath.mpf(m[i]) for j in range(n)]


@pytest.mark.parametrize("t", [1e-3, 3e-2, 0.5])
def test_metzler_heat_bound_holds_entrywise_in_exact_arithmetic(t):
    lap = sig.laplacian(*icosphere(1))
    i = 5
    G = np.zeros(lap.n)
    G[i] = 1.0 / lap.mass[i]
    U, err = metzler_heat(lap, t, G)
    exact = _exact_heat(lap, t, i)
    true = np.array([float(abs(mpmath.mpf(U[j]) - exact[j])) for j in range(lap.n)])
    ex = np.array([float(x) for x in exact])
    assert np.all(true <= err)
    # every entry, down to the smallest, to about 1e-13 relative
    assert np.max(err / ex) < 1e-12
    if t == 1e-3:                                   # the smallest entries are 1e-17 of the peak
        assert ex.min() / ex.max() < 1e-15


def test_heat_rtol_proves_entries_far_below_the_peak():
    """tol-based evaluation cannot bound entries at 1e-10 of the peak; rtol gets each within 1e-6,
    checked against exact arithmetic."""
    lap = sig.laplacian(*icosphere(1))
    t, i = 2e-3, 5
    k, info = sig.heat_kernel(lap, t, i, rtol=1e-6, floor=1e-12, return_info=True)
    exact = _exact_heat(lap, t, i)
    ex = np.array([float(x) for x in exact])
    rel = np.array([float(abs(mpmath.mpf(k[j]) - exact[j]) / exact[j]) for j in range(lap.n)])
    above = ex >= 1e-12 * ex.max()
    assert (ex < 1e-8 * ex.max()).sum() > 0            # the test reaches small entries
    assert np.all(rel[above] <= 1e-6)
    assert np.all(rel <= info["rel_error"])
    assert info["bound_kind"] == "proof"
    # the default (no rtol) cannot promise these entries
    _, plain = sig.heat_kernel(lap, t, i, return_info=True)
    assert np.any(plain["abs_error"][above] > 1e-6 * ex[above])


def test_rtol_tightens_tol_when_that_suffices():
    lap = SHAPES["flat_full_mass"]()       # not Metzler: no cancellation-free path to take
    filt = filters.heat(0.01)
    with pytest.warns(RuntimeWarning, match="not Metzler"):
        k, info = sig.spectral_kernel(lap, filt, 3, rtol=1e-6, floor=3e-3, return_info=True)
    ref = _dense_kernel(lap, filt, 3)
    above = np.abs(ref) >= 3e-3 * np.abs(ref).max()
    assert np.all(np.abs(k - ref)[above] <= 1e-6 * np.abs(ref)[above] * 1.0000001)
    assert info["tol"] < 1e-8 and info["method"] == "rational"


def test_rtol_refuses_with_a_reason():
    full = SHAPES["flat_full_mass"]()
    with pytest.raises(ValueError, match="not Metzler"):
        sig.heat_kernel(full, 1e-3, 3, rtol=1e-6)
    lap = sig.laplacian(*icosphere(2))
    with pytest.raises(ValueError, match="method='rational' was asked for"):
        sig.heat_kernel(lap, 1e-3, 3, rtol=1e-6, method="rational")


def test_rtol_refuses_beyond_the_work_limit(monkeypatch):
    monkeypatch.setattr(kernels, "MAX_PRODUCTS", 5)
    monkeypatch.setattr(kernels, "DIRECT_PRODUCTS", 0)
    lap = sig.laplacian(*icosphere(2))
    with pytest.raises(ValueError, match="sparse products"):
        sig.heat_kernel(lap, 1e-2, 3, rtol=1e-6)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, 1.5, "1e-6"])
def test_rtol_validated(bad):
    lap = sig.laplacian(*icosphere(1))
    with pytest.raises((ValueError, TypeError), match="rtol"):
        sig.heat_kernel(lap, 1e-2, 0, rtol=bad)


def test_return_info_is_a_flag():
    lap = sig.laplacian(*icosphere(1))
    with pytest.raises(TypeError, match="return_info"):
        sig.heat_kernel(lap, 1e-2, 0, return_info="yes")


def test_many_sources_carry_entry_bounds():
    lap = sig.laplacian(*icosphere(2))
    src = np.arange(0, 40, 4)
    K, info = kernels.heat_kernels(lap, [1e-3, 1e-1], src, return_info=True)
    ev, X = sla.eigh(lap.L.toarray(), lap.B.toarray())
    for a, t in enumerate((1e-3, 1e-1)):
        ref = X @ (np.exp(-t * ev)[:, None] * X[src].T)
        assert np.all(np.abs(K[:, :, a] - ref) <= info["abs_error"][:, :, a])
    assert info["bound_kind"] == "proof"


@pytest.mark.parametrize("tol", [1e-8, 1e-11])
def test_full_mass_column_warns_whenever_its_bound_exceeds_tol_times_the_true_norm(tol):
    """The check once compared with an upper bound of ||B^-1 e_i||_B (twice the true norm for a
    full triangle mass), so a column 1.3 times over tol passed silently."""
    import scipy.sparse.linalg as spla

    lap = sig.laplacian(*icosphere(3), mass="full")
    e = np.zeros(lap.n)
    e[11] = 1.0
    x = spla.spsolve(lap.B.tocsc(), e)
    true_norm = float(np.sqrt(x @ (lap.B @ x)))
    for s in (0.1, 1.0, 10.0):
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            _, info = sig.heat_kernel(lap, s * lap.area(), 11, tol=tol, return_info=True)
        warned = any(issubclass(w.category, AccuracyWarning) for w in rec)
        if info["bnorm_error"] > tol * true_norm:
            assert warned, (s, info["bnorm_error"], tol * true_norm)
    # at the default tol the plan targets tol sqrt(c), so the bound meets tol and nothing warns
    if tol == 1e-8:
        assert info["bnorm_error"] <= tol * true_norm and not warned
