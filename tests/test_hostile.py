"""The causes of crashes, hangs, silent NaN/inf and accepted nonsense, each on its own.

Every case is refused before any work with a ValueError/TypeError that names the argument
and what was received, or handled (unreferenced vertices anywhere in V) with results equal
to those of the clean mesh.
"""
from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

import spectral_igl as sig
from data_generators import icosphere

V, F = icosphere(2)
LAP = sig.laplacian(V, F)
N = LAP.n


def refused(exc, match, fn, *args, **kwargs):
    with pytest.raises(exc, match=match):
        fn(*args, **kwargs)


# ---- signals -----------------------------------------------------------------------------------
@pytest.mark.parametrize("call", [
    lambda f: sig.smooth(LAP, f, 0.1),
    lambda f: sig.diffusion_smooth(LAP, f, 0.1),
    lambda f: sig.linalg.pseudo_solve(LAP, f),
    lambda f: sig.SpectralOperator(LAP, sig.filters.heat(0.1), method="shift_invert").apply(f),
    lambda f: sig.apply_filter(LAP, sig.filters.heat(0.1), f),
])
def test_zero_column_signal_is_refused(call):
    refused(ValueError, r"no columns.*\(162, 0\)", call, np.zeros((N, 0)))


def test_overflowing_signal_is_refused_and_linearity_is_the_way_out():
    f = np.random.default_rng(0).standard_normal(N)
    refused(ValueError, r"magnitude up to 1e\+308", sig.apply_filter, LAP, sig.filters.heat(0.1), f / np.abs(f).max() * 1e308)
    # rescaling is exact for the linear operators: the same answer up to the scale
    a = sig.apply_filter(LAP, sig.filters.heat(0.1), f * 1e90)
    b = sig.apply_filter(LAP, sig.filters.heat(0.1), f)
    assert np.allclose(a / 1e90, b, rtol=1e-12, atol=0)


# ---- parameters that drive work --------------------------------------------------------------
@pytest.mark.parametrize("call, match", [
    (lambda: sig.eigs(LAP, 5, tol=float("nan")), "tol must be finite"),
    (lambda: sig.eigs(LAP, 5, tol=-1), r"tol must be a relative tolerance in \[0, 1\)"),
    (lambda: sig.dense_eigs(LAP, k="5"), "k must be an integer, got str '5'"),
    (lambda: sig.harmonic(LAP, [0, 1], [0.0, 1.0], k=10 ** 6), r"k must be an integer in \[1, 8\]"),
    (lambda: sig.polyharmonic_distance(LAP, 10 ** 6, 0), r"k must be an integer in \[1, 16\]"),
    (lambda: sig.spectral_distance(LAP, sig.filters.heat(0.1), 0, targets=np.arange(N), diagonal="foo"),
     "diagonal method must be one of"),
    (lambda: sig.heat_kernel(LAP, 0.1, 0, method=""), "method must be one of"),
    (lambda: sig.SpectralOperator(LAP, sig.filters.heat(0.1), method="rational", k=5),
     "option k=5 is not used by method 'rational'"),
    (lambda: sig.SpectralOperator(LAP, sig.filters.heat(0.1), method="chebyshev", degree=10 ** 9),
     r"degree must be an integer in \[0, 100000\]"),
    (lambda: sig.apply_filter(LAP, sig.filters.heat(0.1), np.ones(N), tol=1.5), r"tol must be .* \(0, 1\)"),
    (lambda: sig.wasserstein_distance(LAP, np.ones(N), np.r_[1.0, np.zeros(N - 1)], 0.05, max_iter=0),
     r"max_iter must be an integer in \[1, 10000000\]"),
    (lambda: sig.optimal_time(LAP, np.zeros(N)), "constant on every connected component"),
    (lambda: sig.wks(LAP, [1.0, 2.0], k=0), r"k must be an integer in \[1, 162\]"),
    (lambda: sig.wks(LAP, [1e300]), "sigma is required|energies are log-eigenvalues"),
    (lambda: sig.wks(LAP, [1.0], sigma=1e-300), r"sigma must be in \[1e-08"),
    (lambda: sig.kernel_diagonal(LAP, sig.filters.heat(0.1), samples=-1), r"samples must be an integer in \[0"),
    (lambda: sig.hks(LAP, np.linspace(0.01, 1, 5000)), "more than 1000"),
    (lambda: sig.distance_colouring(LAP, 10 ** 6), r"distance must be an integer in \[1, 162\]"),
])
def test_work_parameters_range_checked(call, match):
    with pytest.raises((ValueError, TypeError), match=match):
        call()


def test_extreme_wks_energies_are_finite_with_eigen():
    """An energy far above the spectrum with a narrow band: all the weight goes to the top
    eigenvalue (normalised in log space; the plain weights underflow to 0/0)."""
    lam, X = sig.dense_eigs(LAP)
    w = sig.wks(LAP, [30.0, 31.0], sigma=1e-3, k=N - 1)
    top = lam >= lam[-1] * (1 - 1e-9)
    assert np.all(np.isfinite(w))
    assert np.allclose(w[:, 0], (X[:, top] ** 2).mean(axis=1), rtol=1e-8, atol=1e-12)


@pytest.mark.parametrize("fn, match", [
    (lambda s: s * np.nan, "not finite on the spectrum"),
    (lambda s: 1.0 / s, "singular=True"),
    (lambda s: np.ones(3), "failed on an array|same shape"),
    (lambda s: np.ones((s.size, 2)), "failed on an array|same shape"),
])
def test_user_filters_checked_on_the_spectrum(fn, match):
    refused(ValueError, match, sig.apply_filter, LAP, fn, np.ones(N))


def test_wave_time_that_overflows():
    """|wave|^2 = 1 whatever t: the one-to-all distance needs only that and stays finite;
    a path that evaluates e^{-ist} itself refuses t s overflowing."""
    d = sig.wave_distance(LAP, 1e308, 0)
    assert np.allclose(d, sig.wave_distance(LAP, 0.1, 0), rtol=1e-10, atol=1e-12)
    refused(ValueError, "not finite on the spectrum", sig.wave_distance, LAP, 1e308, 0, targets=[1, 2])


def test_negative_semidefinite_stiffness_is_refused():
    refused(ValueError, "libigl's cotmatrix", sig.make_laplacian, -LAP.L, LAP.B)
    again = sig.make_laplacian(LAP.L, LAP.B)
    assert abs(again.L - LAP.L).max() == 0.0


# ---- the size guard ----------------------------------------------------------------------------
def test_memory_budget_refuses_dense_results_up_front(monkeypatch):
    sig.set_memory_budget(10 ** 6)
    try:
        assert sig.memory_budget() == 10 ** 6
        refused(ValueError, r"would take .* beyond the memory budget of 976.6 KiB; use fewer seeds",
                sig.pairwise_spectral_distance, LAP, sig.filters.heat(0.1), np.arange(N))
        refused(ValueError, "dense .* generalized eigenproblem.*use eigs", sig.dense_eigs, LAP)
        sig.set_memory_budget(10 ** 5)
        refused(ValueError, "150 eigenvectors of length 162.*spectrum-free", sig.eigs, LAP, 150)
        sig.set_memory_budget(10 ** 6)
        sig.set_memory_budget(3 * 10 ** 5)
        refused(ValueError, "162 dense kernel columns", sig.heat_kernel, LAP, 0.1, np.arange(N))
        # within the budget the same calls work (the dense eigenproblem takes 1.2 MiB)
        sig.set_memory_budget(2 * 10 ** 6)
        D = sig.pairwise_spectral_distance(LAP, sig.filters.heat(0.1), [0, 5, 9])
        assert D.shape == (3, 3) and np.all(np.isfinite(D))
    finally:
        sig.set_memory_budget(None)
    monkeypatch.setenv("SPECTRAL_IGL_MEMORY_BUDGET", "12345")
    assert sig.memory_budget() == 12345
    monkeypatch.setenv("SPECTRAL_IGL_MEMORY_BUDGET", "lots")
    refused(ValueError, "SPECTRAL_IGL_MEMORY_BUDGET must be a number of bytes", sig.memory_budget)
    monkeypatch.delenv("SPECTRAL_IGL_MEMORY_BUDGET")
    assert sig.memory_budget() > 0


def test_graph_of_a_trillion_vertices_is_refused():
    refused(ValueError, "n = 1000000000000 vertices would take", sig.graph_laplacian, 10 ** 12, [[0, 1]])


def test_huge_coordinates_refused_before_tetrahedralize():
    refused(ValueError, r"V has entries of magnitude up to .*e\+200", sig.tetrahedralize, V * 1e200, F)


# ---- real-file layouts -----------------------------------------------------------------------------
def _insert(where, k=3):
    """V with k unreferenced vertices at ``where``, F re-indexed, and the map old -> new."""
    n = len(V)
    at = {"start": 0, "middle": n // 2, "end": n}[where]
    V2 = np.vstack([V[:at], np.full((k, 3), 5.0), V[at:]])
    new = np.where(np.arange(n) < at, np.arange(n), np.arange(n) + k)
    return V2, new[F], new


@pytest.mark.parametrize("where", ["start", "middle", "end"])
@pytest.mark.parametrize("weights, mass", [("cotan", "lumped"), ("intrinsic_delaunay", "full"),
                                           ("cotan", "full")])
def test_unreferenced_vertices_anywhere(where, weights, mass):
    clean = sig.laplacian(V, F, weights=weights, mass=mass)
    V2, F2, new = _insert(where)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lap = sig.laplacian(V2, F2, weights=weights, mass=mass)
    assert lap.n == len(V2) and lap.n_components == 1 + 3
    sub = np.ix_(new, new)
    assert abs(lap.L[sub] - clean.L).max() < 1e-12
    assert abs(lap.B[sub] - clean.B).max() < 1e-15


@pytest.mark.parametrize("where", ["start", "middle", "end"])
def test_geodesic_distance_with_unreferenced_vertices(where):
    V2, F2, new = _insert(where)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d2 = sig.geodesic_distance((V2, F2), int(new[0]))
    d = sig.geodesic_distance((V, F), 0)
    assert np.allclose(d2[new], d, rtol=0, atol=1e-10)
    lone = np.setdiff1d(np.arange(len(V2)), new)
    assert np.all(np.isinf(d2[lone]))        # no path reaches them


def test_quads_are_not_taken_as_tetrahedra():
    """(m, 4) rows with four coplanar corners are polygons: the polygon Laplacian, with the
    true area, never a tetrahedral one; a caller of the tet check gets the pointer there."""
    Q = np.array([[0, 1, 2, 3], [1, 4, 5, 2]])
    P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], float)
    lap = sig.laplacian(P, Q)
    assert lap.domain != "tet" and abs(lap.area() - 2.0) < 1e-12
    from spectral_igl._validate import check_tets_have_volume
    refused(ValueError, "look like quads, not tetrahedra", check_tets_have_volume, P, Q)


def test_varadhan_is_finite_on_a_connected_shape():
    Vb, Fb = icosphere(4)
    d = sig.varadhan_distance(sig.laplacian(Vb, Fb), 0)
    exact = np.arccos(np.clip(Vb @ Vb[0], -1, 1))
    assert np.all(np.isfinite(d))
    near = exact < 1.0          # the formula is a short-distance one (measured: 0.06 within 1 rad)
    assert np.abs(d - exact)[near].max() < 0.1


# ---- files and the command line -----------------------------------------------------------------
BAD_FILES = {
    "t.obj": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3\n", "line 5"),
    "h.off": ("OFF\n1000000000 1 0\n0 0 0\n", "line 2"),
    "i.off": ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "line 6"),
    "n.obj": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9\n", "line 4"),
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_malformed_files_name_the_line(tmp_path, name):
    text, line = BAD_FILES[name]
    p = tmp_path / name
    p.write_text(text)
    from spectral_igl.io import read_mesh
    with pytest.raises(ValueError, match=f"{name}, {line}"):
        read_mesh(p)


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "spectral_igl.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def test_cli_bad_inputs_and_outputs(tmp_path):
    p = tmp_path / "t.obj"
    p.write_text(BAD_FILES["t.obj"][0])
    r = _cli("distance", p)
    assert r.returncode == 3 and "t.obj, line 5" in r.stderr, r.stderr
    r = _cli("distance", tmp_path)
    assert r.returncode == 3 and "is a directory" in r.stderr, r.stderr
    r = _cli("distance", "--shape", "sphere", "--out", tmp_path / "missing" / "x.png")
    assert r.returncode == 2 and "does not exist" in r.stderr, r.stderr
    assert not (tmp_path / "missing").exists()
    r = _cli("distance", "--shape", "sphere", "--out", tmp_path)
    assert r.returncode == 2
