"""Shifted factorizations and pseudo-inverse solves against dense linear algebra."""
import numpy as np
import pytest

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl import linalg as solvers


def two_spheres():
    V, F = icosphere(2)
    V2 = V * 0.5 + np.array([3.0, 0, 0])
    return sig.laplacian(np.vstack([V, V2]), np.vstack([F, F + len(V)]))


@pytest.fixture(scope="module")
def lap():
    return sig.laplacian(*icosphere(2))


def test_shifted_factor_real_and_complex(lap, rng):
    b = rng.standard_normal((lap.n, 3))
    for beta, theta in [(0.1, 1.0), (2.0, 0.5), (1.0, 3.0 - 2.0j)]:
        A = (theta * lap.B + beta * lap.L).toarray()
        x = solvers.shifted_factor(lap, beta, theta).solve(b)
        assert np.allclose(A @ x, b, atol=1e-10 * np.abs(b).max())


def test_shifted_factor_is_cached(lap):
    f1 = solvers.shifted_factor(lap, 0.37, 1.0)
    f2 = solvers.shifted_factor(lap, 0.37, 1.0)
    assert f1 is f2


def test_pseudo_solve_matches_dense_pseudoinverse(rng):
    lap = two_spheres()
    assert lap.n_components == 2
    ev, X = sig.dense_eigs(lap)
    c = lap.n_components
    f = rng.standard_normal(lap.n)
    u = solvers.pseudo_solve(lap, lap.B @ f)
    ref = X[:, c:] @ ((X[:, c:].T @ (lap.B @ f)) / ev[c:])
    assert np.allclose(u, ref, atol=1e-10 * np.abs(ref).max())
    # B-orthogonal to the constants of each component
    Z = lap.component_basis()
    assert np.allclose(Z.T @ (lap.B @ u), 0, atol=1e-12)


def test_mass_solve(lap, rng):
    g = rng.standard_normal(lap.n)
    assert np.allclose(lap.B @ solvers.mass_solve(lap, g), g)


def test_validation(lap):
    with pytest.raises(TypeError):
        solvers.shifted_factor(np.eye(3), 1.0)
    with pytest.raises(ValueError):
        solvers.shifted_factor(lap, np.nan)
    with pytest.raises(ValueError):
        solvers.shifted_factor(lap, 1.0, backend="nope")
    with pytest.raises(ValueError):
        solvers.pseudo_solve(lap, np.ones(3))


def test_minimum_degree_ordering_factor_matches_dense(rng):
    import scipy.sparse as sp

    from spectral_igl.linalg import ldlt

    if not ldlt.available():
        pytest.skip("compiled LDLT not built")
    pytest.importorskip("pymetis")
    lap = sig.laplacian(*icosphere(4))
    A = (lap.B + 0.01 * lap.L).tocsc()
    perm = ldlt.minimum_degree(A)
    assert np.array_equal(np.sort(perm), np.arange(lap.n))
    md = ldlt.Pattern(A, ordering="minimum_degree")
    nd = ldlt.Pattern(A, ordering="nested_dissection")
    assert md.ordering == "minimum_degree" and nd.ordering == "nested_dissection"
    # a fill-reducing ordering: far below the dense triangle, within 1.5x of METIS's
    assert md.nnz_L < 0.05 * lap.n * (lap.n + 1) / 2
    assert md.nnz_L < 1.5 * nd.nnz_L
    b = rng.standard_normal((lap.n, 2))
    x = ldlt.LDLT(A, md).solve(b)
    assert np.allclose(x, np.linalg.solve(A.toarray(), b), rtol=1e-10, atol=1e-12)
    # a matrix stored exactly on the pattern and one that is not give the same values
    S = sp.csc_matrix((np.arange(md.indices.size, dtype=float), md.indices, md.indptr), shape=A.shape)
    S = S + S.T
    assert np.array_equal(md.values(S), md.values(sp.coo_matrix(S)))
    with pytest.raises(ValueError, match="ordering"):
        ldlt.Pattern(A, ordering="rcm")


def test_auto_ordering_keeps_minimum_degree_on_a_small_surface_and_nested_dissection_on_a_volume():
    from data_generators import box_tets
    from spectral_igl.linalg import ldlt

    if not ldlt.available():
        pytest.skip("compiled LDLT not built")
    pytest.importorskip("pymetis")
    for lap, want in ((sig.laplacian(*icosphere(4)), "minimum_degree"), (sig.laplacian(*box_tets((14, 14, 14))), "nested_dissection")):
        A = (lap.B + lap.L).tocsc()
        auto = ldlt.Pattern(A)
        md = ldlt.Pattern(A, ordering="minimum_degree")
        nd = ldlt.Pattern(A, ordering="nested_dissection")
        assert auto.ordering == want
        chosen = md if want == "minimum_degree" else nd
        assert auto.symbolic.flops == chosen.symbolic.flops and auto.nnz_L == chosen.nnz_L
        if want == "minimum_degree":        # narrow updates: nested dissection not needed
            assert md.symbolic.flops <= ldlt.AUTO_WIDTH * md.nnz_L
        else:                               # a volume: minimum degree's fronts are wide and costlier
            assert md.symbolic.flops > ldlt.AUTO_WIDTH * md.nnz_L and nd.symbolic.flops < md.symbolic.flops


def test_without_metis_auto_keeps_minimum_degree_and_nested_dissection_names_the_extra(monkeypatch):
    import sys

    from data_generators import box_tets
    from spectral_igl.linalg import ldlt

    if not ldlt.available():
        pytest.skip("compiled LDLT not built")
    monkeypatch.setattr(ldlt, "has_metis", lambda: False)
    monkeypatch.setitem(sys.modules, "pymetis", None)        # import pymetis raises ImportError
    lap = sig.laplacian(*box_tets((14, 14, 14)))        # a volume: auto would try nested dissection
    A = (lap.B + lap.L).tocsc()
    auto = ldlt.Pattern(A)
    assert auto.ordering == "minimum_degree"
    assert auto.symbolic.flops > ldlt.AUTO_WIDTH * auto.nnz_L
    b = np.ones(lap.n)
    x = ldlt.LDLT(A, auto).solve(b)
    assert np.linalg.norm(A @ x - b) < 1e-10 * np.linalg.norm(b)
    with pytest.raises(ImportError, match=r'^the nested-dissection ordering needs pymetis: pip install "spectral-igl\[metis\]"$'):
        ldlt.Pattern(A, ordering="nested_dissection")


@pytest.mark.parametrize("dtype", [float, complex])
def test_unit_right_hand_sides_take_the_sparse_forward_substitution_and_match_the_dense_solve(rng, dtype):
    from spectral_igl.linalg import ldlt

    if not ldlt.available():
        pytest.skip("compiled LDLT not built")
    lap = sig.laplacian(*icosphere(3))
    A = (lap.L.astype(dtype) - (0.7 + (2.0j if dtype is complex else 0.0)) * lap.B.astype(dtype) + 5 * lap.B).tocsc()
    f = ldlt.LDLT(A)
    dense = np.linalg.inv(A.toarray())
    idx = np.r_[rng.choice(lap.n, 12, replace=False), 7, 7, 0, lap.n - 1]   # repeats and both ends
    X = f.inverse_columns(idx)
    assert X.shape == (lap.n, idx.size) and X.dtype == np.dtype(dtype)
    assert np.allclose(X, dense[:, idx], rtol=1e-11, atol=1e-13 * np.abs(dense).max())
    # solve() finds one nonzero per column itself, scaled columns included; a column with
    # two nonzeros takes the dense path
    E = np.zeros((lap.n, idx.size))
    E[idx, np.arange(idx.size)] = np.linspace(-2.0, 3.0, idx.size)
    assert np.allclose(f.solve(E), dense @ E, rtol=1e-11, atol=1e-13 * np.abs(dense).max())
    assert np.allclose(f.solve(E[:, 3]), dense @ E[:, 3], rtol=1e-11, atol=1e-13 * np.abs(dense).max())
    E[0, 0] += 1.0
    assert np.allclose(f.solve(E), dense @ E, rtol=1e-11, atol=1e-13 * np.abs(dense).max())
    with pytest.raises(ValueError, match="column indices"):
        f.inverse_columns([0, lap.n])


@pytest.mark.parametrize("min_work", [0.0, 1e30])
@pytest.mark.parametrize("dtype", [float, complex])
def test_blas_and_loop_kernels_agree_with_the_dense_inverse(rng, dtype, min_work):
    """Every dense block through BLAS (min_work 0) or through the loops (1e30): the factor's
    solves, unit columns and selected inverse against the dense inverse, on a tetrahedral box
    (fronts of a few hundred) and a sphere (small fronts)."""
    from data_generators import box_tets
    from spectral_igl.linalg import ldlt

    if not ldlt.available():
        pytest.skip("compiled LDLT not built")
    ext = ldlt._ext()
    old = ext.set_blas_min_work(min_work)
    try:
        for lap in (sig.laplacian(*box_tets((9, 9, 9))), sig.laplacian(*icosphere(3))):
            z = (0.7 + 2.0j) if dtype is complex else -0.7
            A = (lap.L.astype(dtype) - z * lap.B.astype(dtype)).tocsc()
            f = ldlt.LDLT(A)
            dense = np.linalg.inv(A.toarray())
            scale = np.abs(dense).max()
            assert np.allclose(f.inverse_diagonal(), np.diag(dense), rtol=1e-10, atol=1e-12 * scale)
            b = rng.standard_normal((lap.n, 3))
            assert np.allclose(f.solve(b), dense @ b, rtol=1e-10, atol=1e-12 * scale * np.abs(b).sum(0).max())
            idx = rng.choice(lap.n, 9, replace=False)
            assert np.allclose(f.inverse_columns(idx), dense[:, idx], rtol=1e-10, atol=1e-12 * scale)
    finally:
        ext.set_blas_min_work(old)


def _exact_fill(A, perm):
    """Entries of the exact Cholesky factor of A[perm][:, perm] (dense; structural zeros stay 0.0)."""
    L = np.linalg.cholesky(A[perm][:, perm].toarray())
    return int(np.count_nonzero(L))


def test_minimum_degree_on_disconnected_graph_with_isolated_vertices_and_a_dense_row(rng):
    import scipy.sparse as sp

    from spectral_igl.linalg import ldlt

    if not ldlt.available():
        pytest.skip("compiled LDLT not built")
    pytest.importorskip("pymetis")
    # a 30 x 30 grid (0..899), a path (900..959), 40 isolated vertices (960..999) and a hub
    # (1000) joined to every grid vertex: 900 entries > 10 sqrt(n), a dense row
    g = np.arange(900).reshape(30, 30)
    edges = [np.c_[g[:, :-1].ravel(), g[:, 1:].ravel()], np.c_[g[:-1].ravel(), g[1:].ravel()],
             np.c_[np.arange(900, 959), np.arange(901, 960)], np.c_[np.full(900, 1000), np.arange(900)]]
    e = np.vstack(edges)
    n = 1001
    W = sp.coo_matrix((rng.uniform(0.5, 1.0, len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    W = (W + W.T).tocsc()
    A = (sp.diags(np.asarray(W.sum(axis=1)).ravel() + 1.0) - W).tocsc()   # SPD, diagonally dominant
    perm = ldlt.minimum_degree(A)
    assert perm.dtype == np.int32 and np.array_equal(np.sort(perm), np.arange(n))
    assert perm[-1] == 1000                      # the dense row is ordered last
    # the path and the isolated vertices are eliminated without fill; the grid's fill is
    # within 1.5x of nested dissection's (exact counts from dense Cholesky)
    sub = perm[(perm >= 900) & (perm < 1000)] - 900          # the ordering restricted to them
    assert _exact_fill(A[900:1000][:, 900:1000], sub) == 100 + 59
    md, nd = _exact_fill(A, perm), _exact_fill(A, ldlt.nested_dissection(A))
    assert md < 1.5 * nd
    # only the upper triangle given: the pattern is symmetrized, same ordering
    assert np.array_equal(ldlt.minimum_degree(sp.triu(A).tocsc()), perm)
    b = rng.standard_normal(n)
    x = ldlt.LDLT(A, ldlt.Pattern(A, ordering="minimum_degree")).solve(b)
    assert np.allclose(x, np.linalg.solve(A.toarray(), b), rtol=1e-10, atol=1e-12)
    # a tree has a no-fill ordering and minimum degree finds it: a star whose centre is a
    # dense row, beside a path
    m = 400
    t = np.r_[np.c_[np.zeros(m - 1, int), np.arange(1, m)], np.c_[np.arange(m, 2 * m - 1), np.arange(m + 1, 2 * m)]]
    T = sp.coo_matrix((np.ones(len(t)), (t[:, 0], t[:, 1])), shape=(2 * m, 2 * m))
    T = (T + T.T + 2 * m * sp.eye(2 * m)).tocsc()
    pt = ldlt.minimum_degree(T)
    assert np.array_equal(np.sort(pt), np.arange(2 * m)) and pt[-1] == 0
    assert _exact_fill(T, pt) == 2 * m + len(t)
    # empty and 1 x 1 patterns
    assert ldlt.minimum_degree(sp.csc_matrix((0, 0))).shape == (0,)
    assert np.array_equal(ldlt.minimum_degree(sp.csc_matrix(np.ones((1, 1)))), [0])
