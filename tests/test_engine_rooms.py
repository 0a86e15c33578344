"""The engine's rooms: the typed cache, filters as values, one registry of names, the
operator as a scipy LinearOperator, logging, and reuse of precomputed work across calls."""
from __future__ import annotations

import logging

import numpy as np
import pytest
import scipy.sparse.linalg as spla

import spectral_igl as sig
from data_generators import icosphere, torus
from spectral_igl import filters
from spectral_igl.cli import build_parser, main


@pytest.fixture(scope="module")
def lap():
    return sig.laplacian(*icosphere(3))


# ------------------------------------------------------------------------------- cache
def test_clear_leaves_nothing_cached():
    lap = sig.laplacian(*icosphere(2))
    sig.biharmonic_distance(lap, 0)                    # grounded factor, selinv, diagonal
    sig.heat_kernel(lap, 0.05, 3, method="rational")   # complex shifted LDLT factors
    sig.heat_kernel(lap, 0.05, 3, method="shift_invert")
    sig.commute_time_distance(lap, 1, [2, 3])
    sig.hks(lap, [0.01, 0.1])
    assert len(lap.cache) > 5 and lap.cache.nbytes > 8 * lap.n
    assert set(lap.cache.keys("factor")) and set(lap.cache.keys("bound"))
    lap.cache.clear()
    assert len(lap.cache) == 0 and lap.cache.nbytes == 0
    # and everything still works, recomputed from scratch
    d = sig.biharmonic_distance(lap, 0)
    assert d.shape == (lap.n,) and d[0] == 0.0


def test_linalg_clear_cache_is_the_cache_clear(lap):
    sig.linalg.shifted_factor(lap, 0.3)
    sig.linalg.clear_cache(lap)
    assert len(lap.cache) == 0


def test_cache_slots_are_typed():
    lap = sig.laplacian(*icosphere(1))
    with pytest.raises(KeyError, match="unknown cache slot"):
        lap.cache.get("factors", 1)


def test_factor_slot_is_bounded_least_recently_used():
    lap = sig.laplacian(*icosphere(1))
    first = sig.linalg.shifted_factor(lap, 1.0)
    for beta in np.linspace(2.0, 3.0, 30):
        sig.linalg.shifted_factor(lap, float(beta))
    assert len(lap.cache.keys("factor")) == 24
    assert sig.linalg.shifted_factor(lap, 1.0) is not first       # evicted, rebuilt


# ------------------------------------------------------------------------------- filters
def test_filters_are_values():
    assert filters.heat(0.01) == filters.heat(0.01)
    assert hash(filters.heat(0.01)) == hash(filters.heat(0.01))
    assert filters.heat(0.01) != filters.heat(0.02)
    assert filters.heat(0.01).square == filters.heat(0.02)
    assert filters.biharmonic() == filters.polyharmonic(2)
    assert filters.commute_time() != filters.biharmonic()
    assert filters.mexican_hat(0.1).square == filters.mexican_hat(0.1).square
    assert filters.wave(1.0).square == filters.wave(2.0).square          # |e^{-ist}|^2 = 1
    assert filters.by_name("diffusion", 0.2) == filters.heat(0.1)
    # user filters are equal when they wrap the same function
    fn = np.cos
    assert filters.Filter(fn) == filters.Filter(fn) and filters.Filter(fn) != filters.Filter(np.sin)
    assert len({filters.heat(1.0), filters.heat(1.0), filters.biharmonic()}) == 2


def test_second_source_reuses_the_precomputation(monkeypatch):
    """Above the dense limit a one-call distance keeps its poles' factorizations when they fit
    in the cache's factor budget: a second source factorizes nothing and reuses the diagonal.
    With no room it holds one factorization at a time (none is kept), and a second source
    factorizes the poles again but reuses the diagonal. ``OneToAll`` keeps the factorizations,
    so its second source needs no new one."""
    from spectral_igl.linalg import ldlt

    made = []
    init = ldlt.LDLT.__init__

    def counted(self, *args, **kwargs):
        made.append(1)
        init(self, *args, **kwargs)

    monkeypatch.setattr(ldlt.LDLT, "__init__", counted)
    d0 = None
    for budget in (None, 0):
        lap = sig.laplacian(*torus(n_major=80, n_minor=50))   # 4,000 vertices > EXACT_MAX
        assert lap.n > sig.diagonal.EXACT_MAX
        lap.cache.factor_budget = budget
        first = sig.diffusion_distance(lap, 1e-2, 0)
        d0 = first if d0 is None else d0
        poles = [k for k in lap.cache.keys("factor") if isinstance(k[2], complex)]
        assert bool(poles) == (budget is None)
        diagonals = lap.cache.keys("diagonal")
        del made[:]
        d7 = sig.diffusion_distance(lap, 1e-2, 7)
        assert lap.cache.keys("diagonal") == diagonals        # no new selected inversion
        # kept: no factorization at all; dropped: one per pole (each conjugate pair is one)
        kern = sig.diagonal.selinv_kernel(lap, filters.heat(1e-2).square, 1e-8)
        assert len(made) == (0 if budget is None else len(kern.pf.terms)), (budget, len(made))
        assert abs(first[7] - d7[0]) <= 1e-7 * first[7]
        assert abs(first[7] - d0[7]) <= 1e-12 * d0[7]
    lap2 = sig.laplacian(*torus(n_major=80, n_minor=50))
    solver = sig.OneToAll(lap2, filters.heat(5e-3))
    factors = set(lap2.cache.keys("factor"))
    assert [k for k in factors if isinstance(k[2], complex)]
    hits = lap2.cache.hits
    e0, e7 = solver.distance(0), solver.distance(7)
    assert set(lap2.cache.keys("factor")) == factors and lap2.cache.hits > hits
    assert abs(e0[7] - e7[0]) <= 1e-7 * e0[7] and abs(e0[7] - d0[7]) <= 1e-7 * d0[7]


def test_one_to_all_object_matches_the_one_call_function(lap):
    solver = sig.OneToAll(lap, filters.biharmonic())
    assert solver.info["method"] == "selinv"
    for s in (0, 11):
        np.testing.assert_allclose(solver.distance(s), sig.biharmonic_distance(lap, s), rtol=1e-12,
                                   atol=1e-14)
    np.testing.assert_allclose(solver.distance(0, [5, 6]), sig.biharmonic_distance(lap, 0)[[5, 6]],
                               rtol=1e-8)


# ------------------------------------------------------------------------------- registry
def test_every_engine_method_is_accepted_by_the_cli(tmp_path):
    parser = build_parser()
    for method in sig.METHODS:
        args = parser.parse_args(["kernel", "--shape", "sphere", "--method", method])
        assert args.method == method
    for d in sig.diagonal.METHODS:
        assert parser.parse_args(["distance", "--shape", "sphere", "--diagonal", d]).diagonal == d
    for f in filters.FILTERS:
        assert parser.parse_args(["kernel", "--shape", "sphere", "-f", f]).filter == f
    out = tmp_path / "k.npy"
    assert main(["kernel", "--shape", "sphere", "--method", "shift_invert", "-t", "0.01",
                 "--out", str(out), "--quiet"]) == 0
    k = np.load(out)
    lap = sig.laplacian(*icosphere(3))
    np.testing.assert_allclose(k, sig.heat_kernel(lap, 0.01, 0, method="dense"), atol=1e-6 * k.max())


def test_viewer_offers_every_method_and_filter():
    from spectral_igl.viz import _viewer

    assert _viewer.METHODS is sig.METHODS and _viewer.FILTERS is filters.FILTERS


# ------------------------------------------------------------------------------- operator
def test_spectral_operator_is_a_linear_operator(lap):
    op = sig.SpectralOperator(lap, filters.heat(0.05), method="dense")
    assert isinstance(op, spla.LinearOperator) and op.shape == (lap.n, lap.n)
    rng = np.random.default_rng(1)
    x, y = rng.standard_normal(lap.n), rng.standard_normal(lap.n)
    X = rng.standard_normal((lap.n, 3))
    np.testing.assert_allclose(op @ x, op.apply(x), rtol=1e-14)
    np.testing.assert_allclose(op.matmat(X), op.apply(X), rtol=1e-14)
    # the Euclidean adjoint: <A x, y> = <x, A^H y>
    assert abs((op @ x) @ y - x @ (op.H @ y)) <= 1e-10 * np.linalg.norm(x) * np.linalg.norm(y)
    # scipy's eigensolver on it finds eigenvalues e^{-t lambda}, the largest 1 (which copies of
    # the threefold e^{-2t} it finds depends on the rounding: no multiplicity is compared)
    ev = np.sort(spla.eigs(op, k=4, which="LM", return_eigenvectors=False).real)[::-1]
    exact = np.exp(-0.05 * sig.dense_eigs(lap, 20)[0])
    assert ev[0] == pytest.approx(1.0, rel=1e-8)
    assert np.all(np.min(np.abs(ev[:, None] - exact[None, :]), axis=1) <= 1e-8 * ev), (ev, exact)


def test_complex_operator_adjoint(lap):
    op = sig.SpectralOperator(lap, filters.wave(0.3), method="dense")
    rng = np.random.default_rng(2)
    x = rng.standard_normal(lap.n) + 1j * rng.standard_normal(lap.n)
    y = rng.standard_normal(lap.n) + 1j * rng.standard_normal(lap.n)
    assert op.dtype == np.complex128
    lhs = np.vdot(y, op @ x)
    rhs = np.vdot(op.H @ y, x)
    assert abs(lhs - rhs) <= 1e-10 * np.linalg.norm(x) * np.linalg.norm(y)


def test_spectral_operator_cached_by_filter_value(lap):
    a = sig.spectral_operator(lap, filters.heat(0.02), tol=1e-8)
    assert a is sig.spectral_operator(lap, filters.heat(0.02), tol=1e-8)
    assert a is not sig.spectral_operator(lap, filters.heat(0.02), tol=1e-6)


# ------------------------------------------------------------------------------- logging
def test_engine_logs_its_choices(caplog):
    lap = sig.laplacian(*icosphere(3))
    with caplog.at_level(logging.DEBUG, logger="spectral_igl"):
        sig.heat_kernel(lap, 0.01, 0)
        sig.biharmonic_distance(lap, 0)
        sig.biharmonic_distance(lap, 1)
    text = caplog.text
    assert "auto chose method 'rational'" in text       # heat: the proved CF poles
    assert "factorized n=" in text
    assert "cache hit" in text


def test_engine_is_silent_by_default(capfd):
    lap = sig.laplacian(*icosphere(2))
    sig.heat_kernel(lap, 0.01, 0)
    out = capfd.readouterr()
    assert out.out == "" and out.err == ""
