"""Every result a user reads carries a bound of every entry (spectral_igl.accuracy), and the
bound holds against the dense generalized eigendecomposition of small meshes."""
from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import scipy.linalg as sl
from _needs import CLUSTER
from data_generators import icosphere

import spectral_igl as sig
from spectral_igl import filters as F
from spectral_igl.accuracy import BOUND_KINDS, weakest
from spectral_igl.applications import diffusion_smooth
from spectral_igl.cli import main
from spectral_igl.collection import Job, Shape, load, process_shape
from spectral_igl.descriptors import _wks_filter
from spectral_igl.linalg.threads import blas_threads
from spectral_igl.quantity import evaluate

pytestmark = pytest.mark.filterwarnings("ignore::spectral_igl.accuracy.AccuracyWarning")


def jittered_grid(k=12, seed=0):
    """A flat (k x k)-vertex grid of the unit square with jittered interior vertices: a
    boundary, obtuse angles, uneven masses."""
    x, y = np.meshgrid(np.linspace(0, 1, k), np.linspace(0, 1, k), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), np.zeros(k * k)]
    inner = (V[:, 0] > 0) & (V[:, 0] < 1) & (V[:, 1] > 0) & (V[:, 1] < 1)
    V[inner, :2] += np.random.default_rng(seed).uniform(-0.3, 0.3, (inner.sum(), 2)) / (k - 1)
    idx = np.arange(k * k).reshape(k, k)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel()
    return V, np.vstack([np.c_[a, b, d], np.c_[a, d, c]])


MESHES = {"sphere": lambda: sig.laplacian(*icosphere(2)),
          "sphere_full": lambda: sig.laplacian(*icosphere(2), mass="full"),
          "grid": lambda: sig.laplacian(*jittered_grid()),
          "grid_full": lambda: sig.laplacian(*jittered_grid(), mass="full")}


@functools.lru_cache(maxsize=None)
def mesh(name):
    return MESHES[name]()


@functools.lru_cache(maxsize=None)
def pairs(name):
    """The dense generalized eigenpairs of ``scipy.linalg.eigh(L, B)``."""
    lap = mesh(name)
    lam, X = sl.eigh(lap.L.toarray(), lap.B.toarray())
    lam[:lap.n_components] = 0.0
    return np.maximum(lam, 0.0), X


def phi(name, filt):
    """phi at the dense eigenvalues, 0 on ker L for a singular filter."""
    lam, _ = pairs(name)
    with np.errstate(all="ignore"):
        ph = np.asarray(filt(lam), dtype=complex)
    if filt.singular:
        ph[:mesh(name).n_components] = 0.0
    return ph


def true_diagonal(name, filt, delta="mass"):
    _, X = pairs(name)
    W = X if delta == "mass" else mesh(name).B @ X
    return np.real((W ** 2) @ phi(name, filt))


def true_distances(name, filt, source, delta="mass"):
    """d(source, .) for the filter phi (the distance uses |phi|^2)."""
    _, X = pairs(name)
    W = X if delta == "mass" else mesh(name).B @ X
    return np.sqrt(np.maximum(((W - W[source]) ** 2) @ np.abs(phi(name, filt)) ** 2, 0.0))


def check(values, info, truth):
    """The convention's fields, and every entry's true error within its bound."""
    assert info["bound_kind"] in BOUND_KINDS + (None,)
    assert isinstance(info["method"], str)
    err = np.abs(np.asarray(values) - truth)
    bound = np.asarray(info["abs_error"], dtype=float)
    assert bound.shape == np.shape(values)
    if info["bound_kind"] is None:
        assert np.isnan(bound).any()
        return
    assert np.all(bound >= 0)
    bad = ~(err <= bound)
    assert not bad.any(), (info["method"], info["bound_kind"], err[bad].max(), bound[bad].min())


FILTERS = [F.heat(0.05), F.commute_time(), F.mexican_hat(0.1), F.polyharmonic(3)]


# ---- distances --------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(MESHES))
@pytest.mark.parametrize("diagonal", ["auto", "exact", "dense", "probing"])
def test_one_to_all_distance_bounds_every_entry(name, diagonal):
    lap = mesh(name)
    for filt in FILTERS + ([F.biharmonic()] if diagonal != "auto" else []):
        for delta in ("mass", "seed"):
            d, info = sig.spectral_distance(lap, filt, 5, diagonal=diagonal, delta=delta, return_info=True)
            check(d, info, true_distances(name, filt, 5, delta))
            assert info["abs_error"][5] == 0.0 and d[5] == 0.0
            # the squared-distance bound of the entries not recomputed is still there
            assert info["d2_error_bound"] >= 0
            if diagonal == "probing":
                assert info["bound_kind"] == "estimate"


def test_biharmonic_selinv_distance_bound():
    """The selected-inverse biharmonic diagonal once reported a zero bound (its rounding unbounded)."""
    d, info = sig.biharmonic_distance(mesh("sphere"), 5, return_info=True)
    assert info["method"] == "selinv"
    check(d, info, true_distances("sphere", F.biharmonic(), 5))


@pytest.mark.parametrize("name", ["sphere", "grid_full"])
def test_target_distances_are_norms_within_the_engine_bound(name):
    lap = mesh(name)
    for filt in FILTERS:
        truth = true_distances(name, filt, 3)
        t = np.array([0, 3, 17, 60])
        d, info = sig.spectral_distance(lap, filt, 3, targets=t, return_info=True)
        check(d, info, truth[t])
        assert info["bound_kind"] == "proof" and info["abs_error"][1] == 0.0
        d, info = sig.spectral_distance(lap, filt, 3, targets=17, return_info=True)
        assert isinstance(d, float) and isinstance(info["abs_error"], float)
        assert abs(d - truth[17]) <= info["abs_error"]
        # many targets through one-to-all keep their own entries' bounds
        d, info = sig.spectral_distance(lap, filt, 3, targets=t, diagonal="eigen", return_info=True)
        assert info["bound_kind"] is None and np.isnan(info["abs_error"]).all()


def test_named_distances_and_one_to_all_object_pass_return_info():
    name = "grid"
    lap = mesh(name)
    cases = [(sig.diffusion_distance, (0.1,), F.heat(0.05)),
             (sig.commute_time_distance, (), F.commute_time()),
             (sig.polyharmonic_distance, (3,), F.polyharmonic(3)),
             (sig.mexican_hat_distance, (0.1,), F.mexican_hat(0.1)),
             (sig.wave_distance, (0.1,), F.wave(0.1))]
    for fn, args, filt in cases:
        d, info = fn(lap, *args, 7, return_info=True)
        check(d, info, true_distances(name, filt, 7))
        assert info["bound_kind"] in ("proof", "estimate")
    solver = sig.OneToAll(lap, F.mexican_hat(0.1), diagonal="exact")
    d, info = solver.distance(7, return_info=True)
    check(d, info, true_distances(name, F.mexican_hat(0.1), 7))


@pytest.mark.parametrize("name", list(MESHES))
def test_pairwise_distances_bound_every_pair(name):
    lap = mesh(name)
    S = [0, 9, 40, 77, 100]
    for filt in FILTERS + [F.biharmonic()]:
        D, info = sig.pairwise_spectral_distance(lap, filt, S, return_info=True)
        truth = np.array([true_distances(name, filt, s)[S] for s in S])
        check(D, info, truth)
        assert info["bound_kind"] == "proof" and np.all(np.diag(info["abs_error"]) == 0)
        assert info["bnorm_error"].shape == (len(S),)
    D, info = sig.pairwise_diffusion_distance(lap, 0.1, S, return_info=True)
    check(D, info, np.array([true_distances(name, F.heat(0.05), s)[S] for s in S]))


def test_pairwise_heat_block_path_bounds(monkeypatch):
    """Many heat sources above the dense limit share one factorization per pole (here the limit
    is lowered so that a small mesh takes that path)."""
    if not sig.linalg.ldlt.available():
        pytest.skip("needs the compiled LDLT extension")
    import spectral_igl.diagonal as diagonal

    monkeypatch.setattr(diagonal, "EXACT_MAX", 10)
    name = "grid"
    S = list(range(0, 144, 16))
    assert sig.kernels.block_sources(mesh(name), "auto", "mass", len(S))
    D, info = sig.pairwise_diffusion_distance(mesh(name), 0.1, S, return_info=True)
    assert info["method"] == "rational"
    check(D, info, np.array([true_distances(name, F.heat(0.05), s)[S] for s in S]))


# ---- diagonals and descriptors -----------------------------------------------------------
@pytest.mark.parametrize("name", list(MESHES))
def test_kernel_diagonal_bounds_every_vertex(name):
    lap = mesh(name)
    expected = {"selinv": "proof", "exact": "proof", "dense": "estimate", "probing": "estimate",
                "eigen": None}
    for method, kind in expected.items():
        for filt in [F.heat(0.05), F.mexican_hat(0.1)] if method == "selinv" else FILTERS:
            d, info = sig.kernel_diagonal(lap, filt, method=method, return_info=True)
            check(d, info, true_diagonal(name, filt))
            if filt.kind == "heat":
                assert info["bound_kind"] == kind, (method, info)
            assert info["method"] == method
            if kind != "proof":
                assert info["note"]
    if lap.lumped:      # the seed-delta diagonal of B phi(L~)
        for method in ("exact", "selinv"):
            d, info = sig.kernel_diagonal(lap, F.heat(0.05), method=method, delta="seed", return_info=True)
            check(d, info, true_diagonal(name, F.heat(0.05), "seed"))
            assert info["bound_kind"] == "proof"
    # the heat at a time where e^{-t lambda_2} underflows: the projection onto the constants,
    # exactly 1/area (a sum of the masses in exact arithmetic: more accurate than eigh)
    t = 2e6 / sig.lambda_max(lap)
    d, info = sig.kernel_diagonal(lap, F.heat(t), method="selinv", return_info=True)
    assert info["method"] == "projection" and info["bound_kind"] == "proof"
    check(d, info, np.full(lap.n, 1.0 / math.fsum(lap.mass)))


@pytest.mark.parametrize("name", list(MESHES))
def test_hks_adf_eccentricity_bounds(name):
    lap = mesh(name)
    lam, X = pairs(name)
    times = np.array([0.01, 0.1, 1.0])
    truth = (X ** 2) @ np.exp(-np.outer(lam, times))
    for method in ("auto", "exact", "dense"):
        H, info = sig.hks(lap, times, method=method, return_info=True)
        check(H, info, truth)
    h, info = sig.hks(lap, 0.1, return_info=True)
    check(h, info, truth[:, 1])
    many = np.geomspace(0.01, 1.0, 8)                   # common poles for all times
    H, info = sig.hks(lap, many, return_info=True)
    check(H, info, (X ** 2) @ np.exp(-np.outer(lam, many)))
    assert info["bound_kind"] == "proof" and info["eps"].shape == (8,)
    d, info = sig.spectral_descriptor(lap, F.heat(0.1), return_info=True)
    check(d, info, truth[:, 1])

    c = lap.n_components
    A, info = sig.auto_diffusion_function(lap, [0.1, 1.0], return_info=True)
    check(A, info, (X ** 2) @ np.exp(-np.outer(lam, [0.1, 1.0]) / lam[c]) * lap.area())
    assert info["bound_kind"] == "estimate" and "lambda_2" in info["note"]

    m, area = lap.mass, lap.mass.sum()
    for filt in (F.heat(0.05), F.commute_time()):
        for method in ("auto", "exact"):
            e, info = sig.eccentricity(lap, filt, method=method, return_info=True)
            g = true_diagonal(name, filt.square)
            truth_e = np.sqrt(np.maximum(g + m @ g / area - 2 * abs(filt.at_zero()) ** 2 / area, 0))
            check(e, info, truth_e)


@pytest.mark.parametrize("name", list(MESHES))
def test_wks_bound_propagates_the_normaliser(name):
    lap = mesh(name)
    lam, X = pairs(name)
    c = lap.n_components
    E = np.linspace(np.log(lam[c]), np.log(lam[-1]), 5)
    sigma = 7.0 * (E[1] - E[0])
    with np.errstate(divide="ignore"):
        ls = np.log(np.where(lam > 0, lam, 1.0))
    Psi = np.where(lam[:, None] > 0, np.exp(-((E[None, :] - ls[:, None]) ** 2) / (2 * sigma ** 2)), 0.0)
    truth = (X ** 2) @ Psi / Psi.sum(axis=0)
    for method in ("exact", "dense", "auto"):
        W, info = sig.wks(lap, E, method=method, return_info=True)
        check(W, info, truth)
        # the normaliser is proved with either mass: the result is as strong as its diagonals
        diagonals = [sig.kernel_diagonal(lap, _wks_filter(float(e), sigma), method=method, return_info=True)[1]
                     for e in E]
        assert info["bound_kind"] == weakest(*(d["bound_kind"] for d in diagonals)), (method, info.get("note"))
        assert "normaliser" not in info.get("note", "")
        if lap.lumped and method == "exact":
            assert info["bound_kind"] == "proof"
    w, info = sig.wks(lap, E[2], sigma=sigma, method="exact", return_info=True)
    check(w, info, truth[:, 2])
    W, info = sig.wks(lap, E, k=20, return_info=True)          # Aubry et al.'s truncated definition
    assert info["bound_kind"] is None and np.isnan(info["abs_error"]).all() and info["note"]


def test_embedding_says_why_it_has_no_bound():
    E, info = sig.spectral_embedding(mesh("sphere"), F.heat(0.1), 5, return_info=True)
    assert E.shape == info["abs_error"].shape == (162, 5)
    assert info["bound_kind"] is None and np.isnan(info["abs_error"]).all()
    assert "sign" in info["note"] and info["method"] == "lanczos"


def test_diffusion_smoothing_bound():
    name = "grid_full"
    lap = mesh(name)
    lam, X = pairs(name)
    f = np.c_[np.sin(3 * lap.data["V"][:, 0]), lap.data["V"][:, 1] ** 2]
    u, info = diffusion_smooth(lap, f, 0.01, return_info=True)
    check(u, info, X @ (np.exp(-0.01 * lam)[:, None] * (X.T @ (lap.B @ f))))
    assert info["bound_kind"] == "proof"


# ---- validation ---------------------------------------------------------------------------
def test_return_info_accepts_only_booleans():
    lap = mesh("sphere")
    calls = [lambda r: sig.spectral_distance(lap, F.heat(0.1), 0, return_info=r),
             lambda r: sig.spectral_distance(lap, F.heat(0.1), 0, targets=[1, 2], return_info=r),
             lambda r: sig.biharmonic_distance(lap, 0, return_info=r),
             lambda r: sig.OneToAll(lap, F.heat(0.1)).distance(0, return_info=r),
             lambda r: sig.pairwise_spectral_distance(lap, F.heat(0.1), [0, 1], return_info=r),
             lambda r: sig.pairwise_biharmonic_distance(lap, [0, 1], return_info=r),
             lambda r: sig.kernel_diagonal(lap, F.heat(0.1), return_info=r),
             lambda r: sig.spectral_descriptor(lap, F.heat(0.1), return_info=r),
             lambda r: sig.hks(lap, [0.1, 1.0], return_info=r),
             lambda r: sig.wks(lap, [1.0, 2.0], return_info=r),
             lambda r: sig.auto_diffusion_function(lap, 0.1, return_info=r),
             lambda r: sig.eccentricity(lap, F.heat(0.1), return_info=r),
             lambda r: sig.spectral_embedding(lap, F.heat(0.1), 3, return_info=r),
             lambda r: diffusion_smooth(lap, lap.mass, 0.1, return_info=r)]
    for call in calls:
        for bad in (1, "yes", None):
            with pytest.raises(TypeError, match="return_info must be True or False"):
                call(bad)
        assert isinstance(call(np.bool_(True)), tuple)


# ---- evaluate, the command line and the store --------------------------------------------
def test_evaluate_reads_per_entry_bounds():
    name = "grid_full"
    lap = mesh(name)
    ev = evaluate(lap, "distance", 4, "biharmonic", diagonal="exact")
    check(ev.values, {"abs_error": ev.abs_error, "bound_kind": ev.bound_kind, "method": ev.method},
          true_distances(name, F.biharmonic(), 4))
    assert ev.error_bound == ev.abs_error.max() and ev.bound_kind == "proof"
    ev = evaluate(lap, "kernel", 4, "heat", 0.05)
    _, X = pairs(name)
    check(ev.values, {"abs_error": ev.abs_error, "bound_kind": ev.bound_kind, "method": ev.method},
          np.real((X * phi(name, F.heat(0.05))) @ X[4]))
    ev = evaluate(lap, "geodesic", 4)
    assert ev.error_bound is None and ev.bound_kind is None


@pytest.mark.parametrize("argv, expected", [
    (["distance", "--filter", "biharmonic", "--diagonal", "exact"], "(proof, largest over the entries)"),
    (["kernel", "--filter", "heat", "-t", "0.1"], "(proof, largest over the entries)"),
    (["hks", "--times", "0.1", "1.0", "--diagonal", "probing", "--no-normalize"],
     "(estimate, largest over the entries)"),
    (["smooth", "-t", "0.01"], "(proof, largest over the entries)"),
    (["geodesic"], "error bound: none (")])
def test_cli_prints_the_bound(argv, expected, capsys):
    assert main(argv + ["--shape", "sphere", "--level", "2", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert expected in out
    if "none" not in expected:
        value = float(out.split("error bound ")[1].split(" ")[0])
        assert 0 < value < 1


def test_cli_distance_bound_is_the_largest_entry_bound(capsys):
    assert main(["distance", "--shape", "sphere", "--level", "2", "--source", "5", "--diagonal", "exact",
                 "--no-progress"]) == 0
    printed = float(capsys.readouterr().out.split("error bound ")[1].split(" ")[0])
    _, info = sig.biharmonic_distance(sig.laplacian(*icosphere(2)), 5, diagonal="exact", return_info=True)
    assert printed == pytest.approx(info["abs_error"].max(), rel=1e-2)


@CLUSTER
def test_store_round_trips_the_bound(tmp_path):
    V, Fc = icosphere(2)
    lap = sig.laplacian(V, Fc)      # fresh, as the task's: no factor cached by earlier tests
    lam, X = pairs("sphere")
    out = str(tmp_path / "b.zarr")
    jobs = {"hks": Job.hks([0.1, 1.0]), "diagonal": Job.kernel_diagonal("heat", t=0.1, method="probing"),
            "distances": Job.distances([0, 5], "commute_time"), "eigenvalues": Job.eigenvalues(4)}
    truths = {"hks": (X ** 2) @ np.exp(-np.outer(lam, [0.1, 1.0])),
              "diagonal": true_diagonal("sphere", F.heat(0.1)),
              "distances": np.stack([true_distances("sphere", F.commute_time(), s) for s in (0, 5)]),
              "eigenvalues": lam[:4]}
    for key, job in jobs.items():
        with blas_threads(1):          # as a collection task computes it: the same rounding
            arrays, bounds = job("s", lap)
        lap.cache.clear()
        assert process_shape(Shape(key, None, V, Fc), job, out, {})["status"] == "done"
        res = load(out).results[key]
        kind = {"hks": "proof", "diagonal": "estimate", "distances": "proof", "eigenvalues": "proof"}[key]
        assert res.bound_kind == bounds["bound_kind"] == kind
        assert res.meta["bounds"]["of"] == key
        np.testing.assert_array_equal(res.abs_error(key), arrays[key + "_abs_error"])
        if kind is None:
            assert np.isnan(res.abs_error(key)).all() and res.meta["bounds"]["abs_error"] is None
            continue
        assert res.meta["bounds"]["abs_error"] == res.abs_error(key).max()
        check(res[key], {"abs_error": res.abs_error(key), "bound_kind": res.bound_kind,
                         "method": res.meta["bounds"]["method"]}, truths[key])
        # metadata only: the largest bound
        assert load(out, arrays=False).results[key].abs_error(key) == res.meta["bounds"]["abs_error"]
