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


# ---- round three: accepted nonsense ------------------------------------------------------------
LUMPED = sig.laplacian(V, F, mass="lumped")
FULL = sig.laplacian(V, F, mass="full")
BUMP0 = np.r_[np.ones(5), np.zeros(N - 5)]
BUMP1 = np.r_[np.zeros(N - 5), np.ones(5)]


@pytest.mark.parametrize("value", ["no", None, 1, 0.0])
@pytest.mark.parametrize("call", [
    lambda x: sig.mean_curvature_flow(V, F, steps=1, history=x),
    lambda x: sig.mean_curvature_flow(V, F, steps=1, conformal=x),
    lambda x: sig.mean_curvature_flow(V, F, steps=1, normalize=x),
    lambda x: sig.wasserstein_distance(LAP, BUMP0, BUMP1, 0.05, return_info=x),
    lambda x: sig.wasserstein_barycenter(LAP, np.c_[BUMP0, BUMP1], 0.05, return_info=x),
    lambda x: sig.varadhan_distance(LAP, 0, normalize=x),
    lambda x: sig.linalg.shifted_factor(LAP, 0.1, keep=x),
    lambda x: sig.linalg.factorize(LAP.L + LAP.B, spd=x),
    lambda x: sig.filters.Filter(np.exp, singular=x),
    lambda x: sig.tetrahedralize(V, F, optimize=x),
])
def test_flags_are_true_or_false_never_truthiness(call, value):
    refused(TypeError, "must be True or False|must be True, False", call, value)


def test_filter_of_the_wrong_shape_is_refused_not_broadcast():
    refused(ValueError, "same shape", sig.apply_filter, LAP, sig.filters.Filter(lambda s: s[:1]), np.ones(N))
    # a constant is a filter: a scalar is broadcast
    const = sig.apply_filter(LAP, sig.filters.Filter(lambda s: 2.0), np.ones(N))
    assert np.allclose(const, 2.0, rtol=1e-12)


@pytest.mark.parametrize("call, match", [
    (lambda: sig.kernel_diagonal(LAP, sig.filters.heat(1e-2), method="selinv", k=0),
     "option k=0 is not used by diagonal method 'selinv'"),
    (lambda: sig.kernel_diagonal(LAP, sig.filters.heat(1e-2), method="exact", samples=0),
     "option samples=0 is not used by diagonal method 'exact'"),
    (lambda: sig.kernel_diagonal(LAP, sig.filters.heat(1e-2), method="dense", distance=2),
     "option distance=2 is not used"),
    (lambda: sig.kernel_diagonal(LAP, sig.filters.heat(1e-2), method="eigen", k=0),
     r"k must be an integer in \[1, n\] for method 'eigen'"),
    (lambda: sig.wks(LAP, [1.0, 2.0], k=0, method="probing"), "option k=0 is used only by method='eigen'"),
    (lambda: sig.feature_points(LAP, persistence=2.0), r"persistence must be in \[0.0, 1.0\], got 2.0"),
    (lambda: sig.feature_points(LAP, t=-1.0), "t must be positive, got -1.0"),
    (lambda: sig.feature_points(LAP, t=0.5), "option t=0.5 is not used with source='eigenfunctions'"),
    (lambda: sig.point_cloud_laplacian(V, k=10 ** 6), r"k must be an integer in \[3, 161\], got 1000000"),
    (lambda: sig.point_cloud_laplacian(V, k=10, radius=0.3, method="belkin"), "give k or radius, not both"),
    (lambda: sig.eigs(LUMPED, 1, backend=None), "backend must be one of .* got NoneType None"),
    (lambda: sig.schrodinger(LAP, np.ones(N), 0.0, method=""), "method must be one of"),
    (lambda: sig.schrodinger(LAP, np.ones(N), 0.0, tol=np.nan), "tol must be finite"),
    (lambda: sig.point_cloud_laplacian(V, boundary="yes"), "boundary must be True, False or 'auto', got str 'yes'"),
    (lambda: sig.point_cloud_laplacian(V, boundary=1), "boundary must be True, False or 'auto', got int 1"),
    (lambda: sig.point_cloud_laplacian(V, method="belkin", boundary=True), "boundary=True is an option of"),
    (lambda: sig.point_cloud_laplacian(V, method="liu", boundary="auto"), "boundary='auto' is an option of"),
    (lambda: sig.heat_kernels(LAP, np.linspace(0.01, 1.0, 1001), [0]), "times has 1001 values, more than 1000"),
])
def test_options_checked_whatever_the_path(call, match):
    with pytest.raises((ValueError, TypeError), match=match):
        call()


def test_make_laplacian_refuses_asymmetric_mass_and_complex_matrices():
    import scipy.sparse as sp

    B = FULL.B + 1e-3 * sp.triu(FULL.B, 1)
    refused(ValueError, r"B must be symmetric, but \|B - B\^T\| reaches 7.4", sig.make_laplacian, FULL.L, B)
    refused(TypeError, "L must be real, got .* complex128", sig.make_laplacian, FULL.L * (1 + 1j), FULL.B)
    refused(TypeError, "B must be real", sig.make_laplacian, FULL.L, FULL.B.astype(complex))
    # symmetric up to rounding is taken, and gives the same Laplacian
    again = sig.make_laplacian(FULL.L, FULL.B + 1e-14 * sp.triu(FULL.B, 1))
    assert abs(again.B - FULL.B).max() < 1e-15


def test_missing_backend_names_its_install_command(monkeypatch):
    from spectral_igl.linalg import factor

    monkeypatch.setattr(factor, "available_backends", lambda: ["ldlt", "superlu"])
    for call in (lambda: sig.linalg.pseudo_solve(LAP, np.ones(N) - 1.0 / N, backend="pypardiso"),
                 lambda: sig.linalg.factorize(LAP.L + LAP.B, backend="pypardiso"),
                 lambda: sig.eigs(LAP, 3, backend="cholespy")):
        with pytest.raises(ImportError, match=r"not installed here \(available: .*\): pip install (\"spectral-igl\[fast\]\"|cholespy)"):
            call()


# ---- round three: silent NaN and inf -------------------------------------------------------------
def test_harmonic_values_that_overflow_are_refused():
    refused(ValueError, r"values has entries of magnitude up to 1e\+308", sig.harmonic, LAP, [0, N - 1],
            [1e308, -1e308], k=2)
    u = sig.harmonic(LAP, [0, N - 1], [1e90, -1e90], k=2)     # linear: the scaled solution
    assert np.abs(u / 1e90 - sig.harmonic(LAP, [0, N - 1], [1.0, -1.0], k=2)).max() < 1e-12   # values O(1)


def test_transport_between_components_is_refused():
    V2, F2 = np.r_[V, V + 3.0], np.r_[F, F + N]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lap2 = sig.laplacian(V2, F2)
        across = np.r_[np.zeros(2 * N - 5), np.ones(5)]
        for gamma in (1e-300, 0.05):
            refused(ValueError, "different fractions of their mass on connected component 0 .1 and 0",
                    sig.wasserstein_distance, lap2, np.r_[BUMP0, np.zeros(N)], across, gamma, max_iter=20)
        refused(ValueError, "mus.:, 0. and mus.:, 1. put different", sig.wasserstein_barycenter, lap2,
                np.c_[np.r_[BUMP0, np.zeros(N)], across], 0.05, max_iter=20)
        # equal mass on every component: the distance is the sum over the two copies
        mu0, mu1 = np.r_[BUMP0, BUMP0], np.r_[BUMP1, BUMP1]
        w = sig.wasserstein_distance(lap2, mu0, mu1, 0.05, max_iter=500)
        w1 = sig.wasserstein_distance(LAP, BUMP0, BUMP1, 0.05, max_iter=500)
    assert np.isfinite(w) and abs(w - w1) < 1e-6 * w1


def test_heat_kernels_at_a_huge_time_are_the_projection_with_a_finite_bound():
    K, eps = sig.heat_kernels(LAP, [1e-2, 1e300], [0, 7], return_bound=True)
    assert np.all(np.isfinite(eps)) and eps[1] < 1e-12
    exact = 1.0 / LAP.B.sum()                  # e^{-tL} B^-1 e_i -> 1 / area
    assert np.abs(K[:, :, 1] - exact).max() <= eps[1] * np.sqrt(1.0 / LAP.mass.min()) + 1e-15
    lam, X = sig.dense_eigs(LAP)
    small = X @ (np.exp(-1e-2 * lam)[:, None] * X[[0, 7]].T)
    assert np.abs(K[:, :, 0] - small).max() < 1e-6


# ---- round three: the size guard -------------------------------------------------------------------
@pytest.fixture
def budget():
    sig.set_memory_budget(10 ** 6)
    yield
    sig.set_memory_budget(None)


@pytest.mark.parametrize("call, match", [
    (lambda: sig.heat_kernels(LAP, np.geomspace(1e-3, 1, 5), np.arange(N)), "162 heat-kernel columns .* 5 time"),
    (lambda: sig.apply_filter(LAP, sig.filters.heat(0.1), np.ones((N, 2000), np.int8)),
     r"f of shape \(162, 2000\) as float64 would take 2.5 MiB"),
    (lambda: sig.apply_filter(LAP, sig.filters.heat(0.1), np.ones((N, 100))), "work arrays of the engine"),
    (lambda: sig.set_memory_budget(5 * 10 ** 5) or sig.wasserstein_distance(LAP, np.ones(N), BUMP1, 0.3,
                                                                           kernel="geodesic"),
     r"dense \(162, 162\) geodesic kernel .* use kernel='heat'"),
    (lambda: sig.voxel_laplacian(np.broadcast_to(True, (3000, 3000, 3000))),
     r"grid of shape \(3000, 3000, 3000\) would take 251.5 GiB.*crop the mask"),
    (lambda: sig.point_cloud_laplacian(np.random.default_rng(0).standard_normal((2000, 3))),
     "20-nearest-neighbour Laplacian of 2000 points .* subsample"),
])
def test_size_guard_before_the_allocation(budget, call, match):
    refused(ValueError, match, call)


# ---- round three: valid calls that would run for minutes ------------------------------------------
def test_exact_diagonal_refused_up_front_with_its_cost(monkeypatch):
    from spectral_igl.diagonal import core

    exact = sig.kernel_diagonal(LAP, sig.filters.heat(0.05), method="exact")
    monkeypatch.setattr(core, "EXACT_TIME_LIMIT", 1e-9)
    refused(ValueError, r"method='exact' would take about .* s here \(162 engine columns.*'selinv'",
            sig.kernel_diagonal, LAP, sig.filters.heat(0.051), method="exact")
    monkeypatch.setattr(core, "EXACT_TIME_LIMIT", 60.0)
    assert np.allclose(sig.kernel_diagonal(LAP, sig.filters.heat(0.05), method="selinv"), exact, rtol=1e-6)


# ---- round three: files --------------------------------------------------------------------------------
OFF_WRAPPED = "OFF # a comment on the header\n4 2 0\n0 0 0\n1 0 0 # v1\n1 1 0\n0 1 0\n4 0\n 1 2 # wrapped\n3\n3 0 2 3\n"


def test_off_read_by_tokens(tmp_path):
    from spectral_igl.io import read_mesh

    p = tmp_path / "w.off"
    p.write_text(OFF_WRAPPED)
    Vr, Fr = read_mesh(p)
    assert Vr.shape == (4, 3) and Fr.tolist() == [[0, 1, 2], [0, 2, 3], [0, 2, 3]]
    Vp, Fp = read_mesh(p, polygons=True)
    assert [list(map(int, f)) for f in Fp] == [[0, 1, 2, 3], [0, 2, 3]]
    # the same as libigl on a file it reads correctly (no inline comments): wrapped faces, colours
    import igl

    q = tmp_path / "c.off"
    q.write_text("COFF\n4 2 0\n0 0 0 1 0 0 1\n1 0 0 1 0 0 1\n1 1 0 1 0 0 1\n0 1 0 1 0 0 1\n4\n0 1 2 3 255 0 0\n"
                 "3 0 2 3\n")
    Vi, Fi = igl.read_triangle_mesh(str(q))
    Vq, Fq = read_mesh(q)
    assert np.array_equal(Vq, Vi) and np.array_equal(Fq, Fi)
    refused(ValueError, r"t.off: not a valid OFF file: the file ends before its 2 faces", read_mesh,
            _write(tmp_path / "t.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n3 0\n"))


def _write(p, text):
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    return p


def test_check_mesh_file_refuses_directories_and_random_bytes(tmp_path):
    from spectral_igl.io import check_mesh_file

    junk = np.random.default_rng(0).bytes(4096)
    refused(ValueError, "is a directory, not a mesh file", check_mesh_file, tmp_path)
    refused(ValueError, "holds binary data", check_mesh_file, _write(tmp_path / "j.obj", junk))
    refused(ValueError, "holds binary data", check_mesh_file, _write(tmp_path / "j.off", junk))
    refused(ValueError, "unsupported mesh format '.bin'", check_mesh_file, _write(tmp_path / "j.bin", junk))
    refused(ValueError, "0 vertex .* and 0 face", check_mesh_file, _write(tmp_path / "g.obj", "hello\nworld\n" * 9))


def test_libigl_does_not_echo_the_file(tmp_path, capfd):
    from spectral_igl.io import read_mesh

    p = _write(tmp_path / "k.obj", "o thing\nv 0 0 0\nv 1 0 0\nv 0 1 0\nGARBAGE LINE\nf 1 2 3\n")
    Vr, Fr = read_mesh(p)
    assert Fr.tolist() == [[0, 1, 2]]
    assert "GARBAGE" not in capfd.readouterr().err


def test_cli_unreferenced_source_and_existing_store_file(tmp_path):
    V2 = np.r_[np.zeros((5, 3)), V]
    p = _write(tmp_path / "u.obj", "".join(f"v {a} {b} {c}\n" for a, b, c in V2)
               + "".join(f"f {a + 6} {b + 6} {c + 6}\n" for a, b, c in F))
    r = _cli("distance", p, "--source", 0, "--out", tmp_path / "d.png", "--quiet")
    assert r.returncode == 2 and "no element references (5 of the 167" in r.stderr, r.stderr
    assert not (tmp_path / "d.png").exists()
    taken = _write(tmp_path / "store", "a file")
    r = _cli("batch", "--job", "hks", "--times", "0.1", "-o", taken, p)
    assert r.returncode == 2 and "it is a file, not a directory" in r.stderr, r.stderr


# ---- round three: the collection store ----------------------------------------------------------
@pytest.fixture(scope="module")
def threads():
    pytest.importorskip("distributed")
    pytest.importorskip("zarr", minversion="3")
    import logging

    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=1, processes=False, threads_per_worker=1, dashboard_address=None,
                      silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
        yield client


def _store(tmp_path, client):
    from spectral_igl import collection

    shapes = {"a": (V, F), "b": (V * 2.0, F)}
    out = tmp_path / "s.zarr"
    s = collection.run(shapes, collection.Job.hks([0.1]), out, scheduler=client, progress=False)
    assert sorted(s.done) == ["a", "b"]
    return shapes, out, collection


def test_store_damage_is_reported_and_recomputed_never_read_as_zeros(tmp_path, threads):
    shapes, out, collection = _store(tmp_path, threads)
    good = collection.load(out).results["a"]["hks"].copy()
    for chunk in (out / "a" / "hks").rglob("*"):
        if chunk.is_file() and chunk.name != "zarr.json":
            chunk.unlink()                                   # deleted chunk: zarr reads zeros
    meta = out / "b" / "zarr.json"
    meta.write_text(meta.read_text()[:40])                   # truncated metadata
    results, failures = collection.load(out)
    assert results == {}
    assert {f["name"]: f["error"] for f in failures} == {
        "a": "damaged record: array 'hks' has no data chunks (deleted)",
        "b": failures[1]["error"]}
    assert failures[1]["error"].startswith("damaged record: zarr.json is unreadable or truncated")
    s = collection.run(shapes, collection.Job.hks([0.1]), out, scheduler=threads, progress=False)
    assert sorted(s.done) == ["a", "b"] and sorted(s.damaged) == ["a", "b"] and s.skipped == []
    results, failures = collection.load(out)
    assert failures == [] and np.array_equal(results["a"]["hks"], good)
    # a chunk whose bytes changed (same size): the checksum catches it
    chunk = next(c for c in (out / "a" / "hks").rglob("*") if c.is_file() and c.name != "zarr.json")
    chunk.write_bytes(bytes(len(chunk.read_bytes())))
    assert "damaged" in collection.load(out).failures[0]["error"]


def test_store_lock_refuses_a_second_run_and_takes_over_a_dead_one(tmp_path, threads):
    import json
    import os
    import socket

    from spectral_igl.collection.store import LOCK, lock_store

    shapes, out, collection = _store(tmp_path, threads)
    with lock_store(out):                                     # another run holds it
        with pytest.raises(collection.StoreInUse, match=f"in use by another run .*pid {os.getpid()}"):
            collection.run(shapes, collection.Job.hks([0.2]), out, scheduler=threads, progress=False)
    assert not (out / LOCK).exists()
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()                                               # a killed run left its lock behind
    (out / LOCK).write_text(json.dumps({"host": socket.gethostname(), "pid": dead.pid, "start": 1}))
    s = collection.run(shapes, collection.Job.hks([0.2]), out, scheduler=threads, progress=False)
    assert sorted(s.done) == ["a", "b"] and not (out / LOCK).exists()
    (out / LOCK).write_text(json.dumps({"host": "elsewhere", "pid": 1}))
    with pytest.raises(collection.StoreInUse, match="on another host: if that run is dead, remove"):
        collection.run(shapes, collection.Job.hks([0.2]), out, scheduler=threads, progress=False)
