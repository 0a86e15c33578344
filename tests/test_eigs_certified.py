"""eigs returns the k smallest eigenvalues with their multiplicities, certified by an inertia count.

Lanczos may skip one copy of a multiple eigenvalue, and which runs skip depends on the CPU's
rounding. Every test here compares with a dense or analytic spectrum, multiplicities
included, and the skip itself is forced (by a solver that drops a pair) so that detection and
recovery are exercised on every CPU, not only on those whose rounding happens to skip.
"""
import os

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import spectral_igl as sig
from data_generators import flat_torus_laplacian, icosphere
from spectral_igl.linalg import eigen, ldlt

U = np.finfo(np.float64).eps / 2


def dense_spectrum(lap):
    return sla.eigh(lap.L.toarray(), lap.B.toarray(), eigvals_only=True)


def multiplicities(ev, rtol=1e-6):
    """Sizes of the runs of equal values (consecutive gaps below rtol relative) of sorted ev."""
    breaks = np.flatnonzero(np.diff(ev) > rtol * np.maximum(np.abs(ev[1:]), 1.0)) + 1
    return np.diff(np.concatenate([[0], breaks, [len(ev)]])).tolist()


def assert_certified(info, k, count):
    assert info["bound_kind"] == "proof" and info["count_certified"]
    assert info["count"] == count
    assert info["residuals"].shape == info["abs_error"].shape == (k,)
    assert np.all(info["residuals"] <= info["abs_error"])


def test_icosphere_k30_every_copy_of_the_multiple_eigenvalues():
    # the l = 5 band of the discrete sphere splits as 5 + 3 + 3 (icosahedral symmetry): on some
    # CPUs Lanczos returned four copies of 28.6666 and 28.8919 in place of the fifth
    lap = sig.laplacian(*icosphere(3))
    ev, X, info = sig.eigs(lap, 30, return_info=True)
    evd = dense_spectrum(lap)
    assert multiplicities(ev) == multiplicities(evd[:30]) == [1, 3, 5, 3, 4, 5, 4, 5]
    assert evd[30] - evd[29] > 0.2          # 30 ends a cluster: the shift lies in that gap
    assert np.allclose(ev, evd[:30], rtol=0, atol=1e-11)
    assert_certified(info, 30, 30)
    assert evd[29] < info["shift"] < evd[30]
    assert np.all(info["abs_error"] < 1e-10)
    assert np.allclose(X.T @ lap.B @ X, np.eye(30), atol=1e-12)
    res = lap.L @ X - lap.B @ X * ev
    assert np.all(np.sqrt(np.sum(res ** 2 / lap.mass[:, None], axis=0)) <= info["residuals"])


def lumped_square_torus(m):
    """The m x m square flat torus with lumped mass: the 5-point stencil over h², whose spectrum
    (4/h²)(sin²(πi/m) + sin²(πj/m)) has multiplicities 4 and 8."""
    lap = flat_torus_laplacian(1.0, 1.0, m, m)
    i, j = np.meshgrid(np.arange(m), np.arange(m))
    exact = np.sort((4 * m ** 2 * (np.sin(np.pi * i / m) ** 2 + np.sin(np.pi * j / m) ** 2)).ravel())
    return sig.make_laplacian(lap.L, sp.diags(lap.mass)), exact


def test_square_torus_eightfold_eigenvalues_against_the_analytic_spectrum():
    lap, exact = lumped_square_torus(24)
    assert multiplicities(exact[:45]) == [1, 4, 4, 4, 8, 4, 4, 8, 8]
    # k = 41 stops inside the last eightfold cluster: the count is taken after all of it
    ev, X, info = sig.eigs(lap, 41, return_info=True)
    assert_certified(info, 41, 45)
    assert exact[44] < info["shift"] < exact[45]
    # the enclosure is a proof: it holds against the exact discrete spectrum (whose own
    # evaluation rounds by a few units of |λ|)
    assert np.all(np.abs(ev - exact[:41]) <= info["abs_error"] + 8 * U * exact[:41])
    assert np.all(info["abs_error"] < 1e-9)


def test_components_give_the_kernel_multiplicity_and_repeated_spectra():
    V, F = icosphere(2)
    V3 = np.vstack([V, V + 3.0, 0.5 * V - 4.0])
    F3 = np.vstack([F, F + len(V), F + 2 * len(V)])
    lap = sig.laplacian(V3, F3)
    assert lap.n_components == 3
    ev, X, info = sig.eigs(lap, 20, return_info=True)
    evd = dense_spectrum(lap)
    # zero three times, l = 1 of the two unit spheres (6), l = 2 of both (10), then the
    # l = 1 of the half sphere (3, four times the unit sphere's): k = 20 splits it
    assert multiplicities(evd[:22]) == [3, 6, 10, 3]
    assert multiplicities(ev) == [3, 6, 10, 1]
    assert np.all(ev[:3] == 0) and np.allclose(ev, evd[:20], rtol=0, atol=1e-11)
    assert_certified(info, 20, 22)
    Z = lap.component_basis().toarray()
    assert np.array_equal(X[:, :3], Z)


def test_kernel_only_request_is_certified_too():
    V, F = icosphere(1)
    lap = sig.laplacian(np.vstack([V, V + 3.0]), np.vstack([F, F + len(V)]))
    ev, X = sig.eigs(lap, 2)
    ev_i, X_i, info = sig.eigs(lap, 2, return_info=True)
    assert np.all(ev == 0) and np.all(ev_i == 0) and np.array_equal(X, X_i)
    assert_certified(info, 2, 2)
    assert 0 < info["shift"] < dense_spectrum(lap)[2]


def test_consistent_mass_bounds_use_the_proved_mass_ratio():
    lap = sig.laplacian(*icosphere(2), mass="full")
    assert not lap.lumped
    ev, _, info = sig.eigs(lap, 16, return_info=True)
    evd = dense_spectrum(lap)
    assert multiplicities(ev) == multiplicities(evd[:16]) == [1, 3, 5, 3, 4]
    assert np.allclose(ev, evd[:16], rtol=0, atol=1e-11)
    assert_certified(info, 16, 16)


def skipping_eigsh(monkeypatch, value, times=1):
    """Make scipy's eigsh drop the returned pair nearest ``value`` in its first ``times`` calls."""
    real, calls = spla.eigsh, []

    def eigsh(*args, **kwargs):
        vals, vecs = real(*args, **kwargs)
        calls.append(len(vals))
        if len(calls) <= times:
            keep = np.arange(len(vals)) != np.argmin(np.abs(vals - value))
            vals, vecs = vals[keep], vecs[:, keep]
        return vals, vecs

    monkeypatch.setattr(spla, "eigsh", eigsh)
    return calls


def test_a_skipped_copy_is_detected_and_recovered(monkeypatch):
    lap = sig.laplacian(*icosphere(3))
    evd = dense_spectrum(lap)
    calls = skipping_eigsh(monkeypatch, 28.6666)
    ev, X, info = sig.eigs(lap, 30, return_info=True)
    assert len(calls) == 2 and info["searches"] == 2   # the count saw the gap, a second search
    assert multiplicities(ev) == [1, 3, 5, 3, 4, 5, 4, 5]
    assert np.allclose(ev, evd[:30], rtol=0, atol=1e-11)
    assert_certified(info, 30, 30)
    assert np.allclose(X.T @ lap.B @ X, np.eye(30), atol=1e-12)


def test_a_skip_at_every_search_warns_and_says_estimate(monkeypatch):
    lap = sig.laplacian(*icosphere(2))
    real = ldlt.LDLT.pivots

    def one_more_negative(self):   # every count claims one eigenvalue more than was found
        d = np.abs(real(self))
        d[: np.count_nonzero(real(self) < 0) + 1] *= -1
        return d

    monkeypatch.setattr(ldlt.LDLT, "pivots", one_more_negative)
    with pytest.warns(RuntimeWarning, match="could not be certified"):
        ev, _, info = sig.eigs(lap, 9, return_info=True)
    assert info["bound_kind"] == "estimate" and not info["count_certified"]
    assert info["searches"] == eigen.MAX_SEARCHES


def test_return_info_is_checked():
    lap = sig.laplacian(*icosphere(1))
    with pytest.raises(TypeError, match="return_info must be True or False"):
        sig.eigs(lap, 3, return_info="yes")


@pytest.mark.skipif(not ldlt.available(), reason="compiled LDLT not built")
def test_baseline_kernels_can_be_forced_by_the_environment():
    # the second CI pass relies on it: GCC's target_clones resolver cannot be steered so
    import subprocess
    import sys

    code = "from spectral_igl.linalg import ldlt; print(ldlt.kernel_isa())"
    run = [sys.executable, "-c", code]
    forced = subprocess.run(run, env={**os.environ, "SPECTRAL_IGL_BASELINE": "1"}, capture_output=True,
                            text=True, check=True)
    assert forced.stdout.strip() == "baseline"
    assert ldlt.kernel_isa() in ("avx2", "baseline")
