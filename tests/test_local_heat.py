"""Local heat kernel columns against dense generalized eigendecompositions."""
import numpy as np
import pytest
import scipy.linalg as sl

import spectral_igl as sig
from spectral_igl.data_generators import icosphere
from spectral_igl.data_generators.surfaces import grid_faces

#: rounding of the dense reference, relative to the column's peak (eigh of n <= 700)
REFERENCE = 1e-12


def _grid(N=24, seed=0):
    """Jittered unit square with its boundary (N x N cells)."""
    x = np.linspace(0.0, 1.0, N + 1)
    X, Y = np.meshgrid(x, x, indexing="ij")
    rng = np.random.default_rng(seed)
    inner = (X > 0) & (X < 1) & (Y > 0) & (Y < 1)
    J = rng.uniform(-0.3, 0.3, (2,) + X.shape) / N
    X, Y = X + J[0] * inner, Y + J[1] * inner
    V = np.c_[X.ravel(), Y.ravel(), np.zeros(X.size)]
    return V, grid_faces(N + 1, N + 1, False, False)


def _two_components():
    V1, F1 = icosphere(3)
    V2, F2 = icosphere(1, radius=0.3)
    return np.r_[V1, V2 + [3.0, 0.0, 0.0]], np.r_[F1, F2 + len(V1)]


MESHES = {"icosphere": lambda: icosphere(3), "grid": _grid, "two": _two_components}
_CACHE = {}


def _exact(name):
    if name not in _CACHE:
        V, F = MESHES[name]()
        lap = sig.laplacian(V, F)
        V = V / np.sqrt(lap.area())          # unit area
        lap = sig.laplacian(V, F)
        assert lap.is_metzler
        w, X = sl.eigh(lap.L.toarray(), lap.B.toarray())
        _CACHE[name] = lap, w, X
    return _CACHE[name]


@pytest.mark.parametrize("name, source",
                         [("icosphere", 7), ("grid", 0), ("grid", 300), ("two", 5), ("two", 650)])
@pytest.mark.parametrize("t", [1e-5, 5e-5, 2e-4])
def test_local_column_within_its_proved_bound(name, source, t):
    lap, w, X = _exact(name)
    exact = X @ (np.exp(-t * w) * X[source])
    k, info = sig.local_heat_kernel(lap, t, source, return_info=True)
    assert info["bound_kind"] == "proof" and info["method"] == "local"
    peak = exact.max()
    # every entry within its bound
    assert np.all(np.abs(k - exact) <= info["abs_error"] + REFERENCE * peak)
    # below the truth up to the region solver's own bound (the Dirichlet kernel is a lower bound)
    assert np.all(k - info["solver_error"] <= exact + REFERENCE * peak)
    # the bound keeps the promise of the global path: tol / sqrt(B_ss B_jj) per entry
    mass = lap.mass
    target = 1e-8 / np.sqrt(mass[source])
    assert info["bnorm_error"] <= target
    assert np.all(info["abs_error"] <= target / np.sqrt(mass))
    # and it is not loose: within 200x of the column's B-norm error, or far below the target
    diff = k - exact
    assert np.sqrt(diff @ (mass * diff)) * 200 >= info["bnorm_error"] or info["bnorm_error"] < 1e-2 * target
    # other components get exactly nothing
    other = lap.components != lap.components[source]
    assert np.all(k[other] == 0) and np.all(info["abs_error"][other] == 0)


def test_region_grows_with_t():
    lap, _, _ = _exact("grid")
    sizes = [sig.local_heat_kernel(lap, t, 300, return_info=True)[1]["region"] for t in (1e-5, 5e-5, 2e-4)]
    assert sizes[0] < sizes[1] < sizes[2] < lap.n // 4


def test_small_component_is_solved_whole():
    lap, w, X = _exact("two")
    source = 650                               # on the small sphere (42 vertices)
    small = int(np.count_nonzero(lap.components == lap.components[source]))
    k, info = sig.local_heat_kernel(lap, 1.0, source, return_info=True)
    exact = X @ (np.exp(-1.0 * w) * X[source])
    # nothing leaves the component: the lost heat is only what the solver's own bound allows
    assert info["region"] == small and info["method"] == "local"
    assert info["m_lost"] <= 2.5 * np.sum(lap.mass * info["solver_error"]) + 1e-14
    assert np.all(np.abs(k - exact) <= info["abs_error"] + REFERENCE * exact.max())


def test_large_t_falls_back_to_the_global_path():
    lap, w, X = _exact("icosphere")
    k, info = sig.local_heat_kernel(lap, 0.05, 3, return_info=True)
    exact = X @ (np.exp(-0.05 * w) * X[3])
    assert info["method"].startswith("global") and "region" in info["note"]
    assert np.all(np.abs(k - exact) <= info["abs_error"] + REFERENCE * exact.max())


def test_refuses_non_metzler():
    V, F = icosphere(2)
    lap = sig.laplacian(V, F, mass="full")
    with pytest.raises(ValueError, match="positive=True"):
        sig.local_heat_kernel(lap, 1e-3, 0)


def test_bad_source():
    lap, _, _ = _exact("icosphere")
    with pytest.raises(ValueError, match="source"):
        sig.local_heat_kernel(lap, 1e-3, lap.n)


@pytest.mark.parametrize("name, sources, t", [("grid", 300, 1e-5), ("two", [5, 650], 2e-4),
                                              ("icosphere", [7, 100], 5e-5)])
def test_auto_heat_kernel_takes_the_local_path(monkeypatch, name, sources, t):
    monkeypatch.setattr(sig.kernels, "LOCAL_MIN_VERTICES", 0)
    lap, w, X = _exact(name)
    k, info = sig.heat_kernel(lap, t, sources, return_info=True)
    exact = (X * np.exp(-t * w)) @ X[sources].T
    assert info["method"] == "local" and info["bound_kind"] == "proof" and k.shape == exact.shape
    assert np.all(np.abs(k - exact) <= info["abs_error"] + REFERENCE * exact.max())
    target = 1e-8 / np.sqrt(lap.mass[sources])
    assert np.all(info["bnorm_error"] <= target)
    # the same column as the explicit call
    first = np.atleast_1d(sources)[0]
    k0 = k if k.ndim == 1 else k[:, 0]
    assert np.array_equal(k0, sig.local_heat_kernel(lap, t, first))


def test_auto_heat_kernel_declines_large_regions(monkeypatch):
    monkeypatch.setattr(sig.kernels, "LOCAL_MIN_VERTICES", 0)
    lap, w, X = _exact("icosphere")
    k, info = sig.heat_kernel(lap, 0.05, 3, return_info=True)
    exact = X @ (np.exp(-0.05 * w) * X[3])
    assert info["method"] == "rational" and info["note"].startswith("local column declined")
    assert np.all(np.abs(k - exact) <= info["abs_error"] + REFERENCE * exact.max())


def test_auto_local_above_the_threshold():
    """Above LOCAL_MIN_VERTICES without any patch, against the global path's own proof."""
    V, F = icosphere(5)
    lap = sig.laplacian(V, F)
    lap = sig.laplacian(V / np.sqrt(lap.area()), F)
    assert lap.n > sig.kernels.LOCAL_MIN_VERTICES
    k, info = sig.heat_kernel(lap, 1e-5, 11, return_info=True)
    ref, rinfo = sig.heat_kernel(lap, 1e-5, 11, method="rational", tol=1e-10, return_info=True)
    assert info["method"] == "local" and info["region"] < lap.n // 20
    assert np.all(np.abs(k - ref) <= info["abs_error"] + rinfo["abs_error"])
    assert info["bnorm_error"] <= 1e-8 / np.sqrt(lap.mass[11])


@pytest.mark.parametrize("name, source", [("grid", 0), ("grid", 300), ("two", 5), ("icosphere", 7)])
@pytest.mark.parametrize("t", [1e-5, 1e-4])
def test_local_mexican_hat_within_its_proved_bound(name, source, t):
    lap, w, X = _exact(name)
    exact = X @ (t * w * np.exp(-t * w) * X[source])
    h, info = sig.local_mexican_hat(lap, t, source, return_info=True)
    assert info["method"] == "local" and info["bound_kind"] == "proof"
    scale = np.abs(exact).max()
    assert np.all(np.abs(h - exact) <= info["abs_error"] + REFERENCE * scale * max(1.0, t * w.max()))
    assert info["bnorm_error"] <= 1e-8 / np.sqrt(lap.mass[source])
    # sparse: zero beyond one ring of the heat column's region
    assert np.count_nonzero(h) < lap.n // 2
    # the bound is not vacuous: the column's B-norm error is within 1e4 of it or far below tol
    diff = h - exact
    assert np.sqrt(diff @ (lap.mass * diff)) * 1e4 >= info["bnorm_error"] or \
        info["bnorm_error"] < 1e-2 * 1e-8 / np.sqrt(lap.mass[source])


def test_local_mexican_hat_falls_back_at_large_t():
    lap, w, X = _exact("icosphere")
    h, info = sig.local_mexican_hat(lap, 0.05, 3, return_info=True)
    exact = X @ (0.05 * w * np.exp(-0.05 * w) * X[3])
    assert info["method"].startswith("global") and "region" in info["note"]
    assert np.all(np.abs(h - exact) <= info["abs_error"] + REFERENCE * np.abs(exact).max())


@pytest.mark.parametrize("name", ["grid", "two", "icosphere"])
@pytest.mark.parametrize("t, threshold, block", [(1e-5, 1e-8, 64), (1e-4, 1e-6, 16), (2e-4, 1e-10, 7)])
def test_sparse_heat_kernel_every_entry_and_dropped_mass(name, t, threshold, block):
    lap, w, X = _exact(name)
    exact = (X * np.exp(-t * w)) @ X.T          # k_t(x_i, x_j), symmetric for the lumped mass
    K, info = sig.sparse_heat_kernel(lap, t, threshold=threshold, block=block, return_info=True)
    assert info["bound_kind"] == "proof" and info["method"] == "local"
    assert abs(K - K.T).max() == 0 and K.min() >= 0
    Kd, E = K.toarray(), info["abs_error"].toarray()
    stored = Kd > 0
    assert np.array_equal(stored, E > 0)
    peak = exact.max(axis=0)
    slack = REFERENCE * peak[None, :]
    # every stored entry within its bound, every dropped one within dropped_max of its column
    assert np.all((np.abs(Kd - exact) <= E + slack)[stored])
    assert np.all((exact <= info["dropped_max"][None, :] + slack)[~stored])
    # each column's dropped mass within its bound
    assert np.all(lap.mass @ np.where(stored, 0.0, exact) <= info["dropped_mass"] + REFERENCE)
    # everything at or above the threshold of its column's peak is stored (up to the bounds)
    assert np.all(stored[exact > threshold * peak[None, :] * (1 + 1e-6) + 2 * E.max(axis=0)[None, :]])
    # the matrix is sparse, and its columns keep the B-norm promise of the global path
    assert K.nnz < lap.n ** 2 // 4
    assert np.all(info["bnorm_error"] <= 1e-8 / np.sqrt(lap.mass))
    # the bounds are not vacuous: the dropped mass bound within 1e3 of the truth, or below 1e-9
    true_dropped = lap.mass @ np.where(stored, 0.0, exact)
    assert np.all((info["dropped_mass"] <= 1e3 * true_dropped) | (info["dropped_mass"] < 1e-9))


def test_sparse_heat_kernel_diagonal_is_the_hks():
    lap, w, X = _exact("grid")
    t = 1e-4
    K, info = sig.sparse_heat_kernel(lap, t, return_info=True)
    hks = (X * X) @ np.exp(-t * w)
    assert np.all(np.abs(K.diagonal() - hks) <= info["abs_error"].diagonal() + REFERENCE * hks)


def test_sparse_heat_kernel_refuses_dense_and_bad_arguments():
    lap, _, _ = _exact("icosphere")
    with pytest.raises(ValueError, match="not sparse"):
        sig.sparse_heat_kernel(lap, 0.05)
    with pytest.raises(ValueError, match="threshold"):
        sig.sparse_heat_kernel(lap, 1e-5, threshold=1.5)
    with pytest.raises(ValueError, match="block"):
        sig.sparse_heat_kernel(lap, 1e-5, block=0)
    V, F = icosphere(2)
    with pytest.raises(ValueError, match="positive=True"):
        sig.sparse_heat_kernel(sig.laplacian(V, F, mass="full"), 1e-3)


@pytest.mark.parametrize("name, t", [("grid", 1e-4), ("two", 2e-4), ("icosphere", 5e-5)])
def test_sparse_diffusion_distance_every_stored_pair(name, t):
    lap, w, X = _exact(name)
    exact_K = (X * np.exp(-t * w)) @ X.T
    diag = np.diag(exact_K)
    exact = np.sqrt(np.maximum(diag[:, None] + diag[None, :] - 2.0 * exact_K, 0.0))
    D, info = sig.sparse_diffusion_distance(lap, t, return_info=True)
    assert info["bound_kind"] == "proof" and abs(D - D.T).max() == 0
    K = sig.sparse_heat_kernel(lap, t)
    assert np.array_equal(D.indices, K.indices) and np.array_equal(D.indptr, K.indptr)
    rows = np.repeat(np.arange(lap.n), np.diff(D.indptr))
    got, err = D.data, info["abs_error"].data.astype(float)
    # the reference's rounding of d^2 (1e-12 of the peak) is up to its square root in d
    slack = np.sqrt(REFERENCE * diag.max())
    assert np.all(np.abs(got - exact[rows, D.indices]) <= err + slack)
    assert np.all(np.abs(info["hks"] - diag) <= info["hks_error"] + REFERENCE * diag)
    # not vacuous: off the diagonal the bound is a small share of the distance
    off = rows != D.indices
    assert np.median(err[off] / got[off]) < 1e-3
    # an unstored pair is as far as the kernel's dropped entries say
    stored = K.toarray() > 0
    low = diag[:, None] + diag[None, :] - 2.0 * np.minimum.outer(info["dropped_max"], info["dropped_max"])
    assert np.all((exact ** 2 >= low - info["hks_error"][:, None] - info["hks_error"][None, :]
                   - REFERENCE * diag.max())[~stored])


def test_stacked_regions_each_within_their_own_bound():
    """Three Dirichlet regions of different rates in one block-diagonal series: each block's
    columns within the proved bound of its own exact exponential (dense expm)."""
    import scipy.sparse as sp
    from spectral_igl.approx.region import dirichlet_heat_blocks, grow_regions, vertex_spacing

    lap, _, _ = _exact("grid")
    t = 2e-4
    h2 = vertex_spacing(lap)
    sources = np.array([0, 1, 300, 301, 302, 620])
    offsets = np.array([0, 2, 5, 6])
    keys, roff = grow_regions(sp.csr_matrix(lap.L), h2, sources, offsets, np.array([0.05, 0.12, 0.08]),
                              np.full(3, lap.n), lap.components)
    u, rel, add, lost, _ = dirichlet_heat_blocks(lap, t, keys, roff, sources, offsets, 1e-14)
    L, m = lap.L.toarray(), lap.mass
    for b in range(3):
        R = keys[roff[b]:roff[b + 1]] % lap.n
        assert np.all(np.isin(sources[offsets[b]:offsets[b + 1]], R))
        A = L[np.ix_(R, R)] / m[R][:, None]
        cols = sources[offsets[b]:offsets[b + 1]]
        G = np.zeros((R.size, cols.size))
        G[np.searchsorted(R, cols), np.arange(cols.size)] = 1.0 / m[cols]
        exact = sl.expm(-t * A) @ G
        got = u[roff[b]:roff[b + 1], :cols.size]
        bound = rel[b] * got + add[roff[b]:roff[b + 1], :cols.size]
        assert np.all(np.abs(got - exact) <= bound + REFERENCE * exact.max())
        # the Dirichlet kernel is below the true one, and the heat lost bounds what is missing
        full = sl.expm(-t * L / m[:, None]) @ (np.eye(lap.n)[:, cols] / m[cols])
        assert np.all(exact <= full[R] + REFERENCE * full.max())
        missing = m @ full - m[R] @ exact
        assert np.all(missing <= lost[b, :cols.size] + REFERENCE)
    # a group's columns past its size are 0
    assert np.all(u[roff[2]:roff[3], 1:] == 0)


def _sliver_grid():
    """The jittered grid with one vertex next to its neighbour (1e-3 of a cell away): the
    pair's elements make one rate 600 times the median."""
    V, F = _grid()
    i = 12 * 25 + 12
    V[i] = V[i + 1] + np.array([-1e-3, 0.3e-3, 0.0]) / 24
    return V, F


MESHES["sliver"] = _sliver_grid


def _graded_grid(N=24):
    """Unit square whose cells' widths grow geometrically 1000-fold along x (right triangles,
    so Metzler): lumped masses vary 1000-fold, and across neighbours."""
    s = np.linspace(0.0, 1.0, N + 1)
    X, Y = np.meshgrid((1000.0 ** s - 1.0) / 999.0, s, indexing="ij")
    return np.c_[X.ravel(), Y.ravel(), np.zeros(X.size)], grid_faces(N + 1, N + 1, False, False)


MESHES["graded"] = _graded_grid


@pytest.mark.parametrize("name", ["grid", "sliver", "graded", "two"])
def test_spectral_top_bounds_the_dense_spectrum(name):
    """spectral_top of stacked principal submatrices (regions) bounds the largest eigenvalue of
    each region's B^-1 L and the spectral radius of B^-1 |L| (dense), and is well below twice
    the largest L_jj / B_jj (the row-sum bound's size) where neighbours' masses differ."""
    import scipy.sparse as sp
    from spectral_igl.approx.uniformization import abs_radius, rate_matrix, spectral_top

    lap, _, _ = _exact(name)
    L, m = sp.csr_matrix(lap.L), lap.mass
    rng = np.random.default_rng(1)
    regions = [np.arange(lap.n), np.sort(rng.choice(lap.n, lap.n // 3, replace=False)), np.array([7])]
    rows = np.concatenate(regions)
    offsets = np.r_[0, np.cumsum([R.size for R in regions])]
    stacked = sp.block_diag([L[R][:, R] for R in regions], format="csr")
    top = spectral_top(stacked, m[rows], offsets)
    for b, R in enumerate(regions):
        LR = L[R][:, R].toarray()
        assert sl.eigvalsh(LR, np.diag(m[R]))[-1] <= top[b]
        assert np.max(np.abs(np.linalg.eigvals(np.abs(LR) / m[R][:, None]))) <= top[b] * (1 + 1e-12)
    assert np.isclose(top[2], L[7, 7] / m[7], rtol=1e-13)
    if name == "graded":
        assert top[0] < 1.75 * np.max(L.diagonal() / m)
    # a Chebyshev rate needs half of it, no less
    with pytest.raises(ValueError, match="spectral_top"):
        rate_matrix(stacked, m[rows], offsets, alpha=0.499 * top, nonnegative=False)
    _, P = rate_matrix(stacked, m[rows], offsets, alpha=0.5 * top, nonnegative=False)
    w = sl.eigvals(P[:offsets[1], :offsets[1]].toarray()).real
    assert w.min() >= -1 - 1e-12
    # the B-norm of |P| (the recurrence's rounding): its spectral radius, near 1 for these meshes
    omega = abs_radius(stacked, m[rows], offsets, 0.5 * top)
    for b, R in enumerate(regions):
        absP = np.abs(np.eye(R.size) - L[R][:, R].toarray() / (m[R][:, None] * 0.5 * top[b]))
        radius = np.max(np.abs(np.linalg.eigvals(absP)))
        assert radius <= omega[b] < 1.5


def test_chebyshev_regions_against_dense_expm():
    """Regions around a badly shaped element take the Chebyshev series: each column within
    its proved bound of the region's own exact exponential (dense expm), entry by entry and in
    the B-norm, and the heat it proves kept bounds what the region misses."""
    import scipy.sparse as sp
    from spectral_igl.approx import region
    from spectral_igl.approx.region import dirichlet_heat_blocks, grow_regions, vertex_spacing

    lap, _, _ = _exact("sliver")
    t = 2e-4
    i = 12 * 25 + 12
    sources = np.array([0, 1, i, i + 3, i - 25, 620])
    offsets = np.array([0, 2, 5, 6])
    keys, roff = grow_regions(sp.csr_matrix(lap.L), vertex_spacing(lap), sources, offsets,
                              np.array([0.05, 0.12, 0.08]), np.full(3, lap.n), lap.components)
    calls = []
    chebyshev = region.chebyshev_blocks

    def spy(P, alpha, *args):
        calls.append(np.asarray(alpha) * t)
        return chebyshev(P, alpha, *args)

    region.chebyshev_blocks = spy
    try:
        u, rel, add, lost, work = dirichlet_heat_blocks(lap, t, keys, roff, sources, offsets, 1e-14,
                                                        allowance=np.full(3, 1e-10))
    finally:
        region.chebyshev_blocks = chebyshev
    assert len(calls) == 1 and calls[0].size == 1 and calls[0][0] > 100     # the sliver's region only
    L, m = lap.L.toarray(), lap.mass
    for b in range(3):
        R = keys[roff[b]:roff[b + 1]] % lap.n
        cols = sources[offsets[b]:offsets[b + 1]]
        G = np.zeros((R.size, cols.size))
        G[np.searchsorted(R, cols), np.arange(cols.size)] = 1.0 / m[cols]
        exact = sl.expm(-t * L[np.ix_(R, R)] / m[R][:, None]) @ G
        got = u[roff[b]:roff[b + 1], :cols.size]
        bound = rel[b] * got + add[roff[b]:roff[b + 1], :cols.size]
        assert np.all(got >= 0) and np.all(np.abs(got - exact) <= bound + REFERENCE * exact.max())
        full = sl.expm(-t * L / m[:, None]) @ (np.eye(lap.n)[:, cols] / m[cols])
        assert np.all(m @ full - m[R] @ exact <= lost[b, :cols.size] + REFERENCE)
    # the Chebyshev block's bound is not vacuous (B-norm allowance 1e-10 over the region's mass)
    assert np.max(add[roff[1]:roff[2], :3]) < 1e-8 * np.max(u[roff[1]:roff[2], :3])
    # and cheaper than uniformizing it
    plain = dirichlet_heat_blocks(lap, t, keys, roff, sources, offsets, 1e-14)
    assert work < 0.5 * plain[4]


def test_chebyshev_share_costs_a_column_at_most_twice_its_share():
    """sparse_heat_kernel's allowance (CHEBYSHEV_SHARE of the B-norm target, over the square root
    of the smallest mass) costs a Chebyshev region's column at most the share of its target
    through the heat it proves kept, and at most as much again through its entries' bounds:
    with the lost heat's goal of half the target, the first attempts keep their target."""
    import scipy.sparse as sp
    from spectral_igl import local
    from spectral_igl.approx import region
    from spectral_igl.approx.region import dirichlet_heat_blocks, grow_regions, vertex_spacing

    assert 0.5 + 2.0 * local.CHEBYSHEV_SHARE < 1.0
    lap, _, _ = _exact("sliver")
    t, tol = 2e-4, 1e-8
    i = 12 * 25 + 12
    sources = np.array([i, i + 3, i - 25])
    offsets = np.array([0, 3])
    keys, roff = grow_regions(sp.csr_matrix(lap.L), vertex_spacing(lap), sources, offsets, np.array([0.12]),
                              np.full(1, lap.n), lap.components)
    calls = []
    chebyshev = region.chebyshev_blocks

    def spy(*args):
        calls.append(1)
        return chebyshev(*args)

    region.chebyshev_blocks = spy
    try:
        allowance = np.array([local.CHEBYSHEV_SHARE * tol * np.sqrt(lap.mass.min())])
        u, rel, add, lost, work = dirichlet_heat_blocks(lap, t, keys, roff, sources, offsets, 1e-14,
                                                        allowance=allowance)
    finally:
        region.chebyshev_blocks = chebyshev
    assert calls
    L, m = lap.L.toarray(), lap.mass
    R = keys % lap.n
    target = tol / np.sqrt(m[sources])
    G = np.zeros((R.size, sources.size))
    G[np.searchsorted(R, sources), np.arange(sources.size)] = 1.0 / m[sources]
    exact = sl.expm(-t * L[np.ix_(R, R)] / m[R][:, None]) @ G
    full = sl.expm(-t * L / m[:, None]) @ (np.eye(lap.n)[:, sources] / m[sources])
    outside = m @ full - m[R] @ exact                    # the heat truly outside R
    # through the kept heat: lost exceeds the heat outside by at most share * target * sqrt(min B)
    assert np.all(lost[0] - outside <= local.CHEBYSHEV_SHARE * target * np.sqrt(m.min()) + REFERENCE)
    # through the entries: their bounds' B-norm at most share * target
    err = rel[0] * u + add
    assert np.all(np.sqrt(m[R] @ (err * err)) <= local.CHEBYSHEV_SHARE * target * (1.0 + 1e-6))


@pytest.mark.parametrize("name, t", [("sliver", 1e-5), ("sliver", 2e-4), ("graded", 2e-6), ("graded", 1e-5)])
def test_sparse_heat_kernel_with_a_sliver_every_entry(name, t):
    lap, w, X = _exact(name)
    exact = (X * np.exp(-t * w)) @ X.T
    K, info = sig.sparse_heat_kernel(lap, t, threshold=1e-8, block=16, return_info=True)
    Kd, E = K.toarray(), info["abs_error"].toarray()
    stored = Kd > 0
    slack = REFERENCE * exact.max(axis=0)[None, :]
    assert np.all((np.abs(Kd - exact) <= E + slack)[stored])
    assert np.all((exact <= info["dropped_max"][None, :] + slack)[~stored])
    assert np.all(lap.mass @ np.where(stored, 0.0, exact) <= info["dropped_mass"] + REFERENCE)
    assert np.all(info["bnorm_error"] <= 1e-8 / np.sqrt(lap.mass))


def _numpy_series(P, offsets, C, rows, t1, t0, W):
    """The numpy form of the Chebyshev terms 2..K that the compiled loop replaces."""
    counts = np.diff(offsets)
    for k in range(2, C.shape[1]):
        r = rows[k]
        q = P[:r, :r] @ t1[:r]
        new = t0[:r]
        np.subtract(q, new, out=new)
        t0, t1 = t1, t0
        W[:r] += np.repeat(C[:, k], counts)[:r, None] * new
    return W


@pytest.mark.parametrize("width", [32, 16, 8, 5, 4, 1])
def test_compiled_chebyshev_series_rounds_as_numpy(width):
    """The compiled recurrence agrees bit for bit with the numpy form whose rounding the
    series' bound is proved for, on blocks that stop at their own terms (leading rows)."""
    import scipy.sparse as sp

    from spectral_igl.linalg import ldlt

    if not ldlt.available():
        pytest.skip("no compiled extension")
    rng = np.random.default_rng(width)
    sizes = [40, 25, 31]
    blocks = [sp.random(s, s, density=0.2, random_state=rng) for s in sizes]
    P = sp.csr_matrix(sp.block_diag([b + b.T - sp.diags(rng.uniform(0, 1, s)) for b, s in zip(blocks, sizes)]))
    offsets = np.r_[0, np.cumsum(sizes)]
    n, K = P.shape[0], 9
    C = rng.standard_normal((len(sizes), K + 1))
    rows = [0, 0] + [int(offsets[3 if k < 5 else 2 if k < 8 else 1]) for k in range(2, K + 1)]
    t0, t1 = rng.standard_normal((n, width)), rng.standard_normal((n, width))
    W = rng.standard_normal((n, width))
    want = _numpy_series(P, offsets, C, rows, t1.copy(), t0.copy(), W.copy())
    got = W.copy()
    assert ldlt.chebyshev_series(P, offsets, C, rows, t1.copy(), t0.copy(), got)
    assert np.array_equal(got, want)
    with pytest.raises(ValueError, match="block diagonal"):
        coupled = P.tolil()
        coupled[0, offsets[1]] = 1.0
        ldlt.chebyshev_series(coupled.tocsr(), offsets, C, rows, t1, t0, W)
    with pytest.raises(ValueError, match="block boundaries"):
        ldlt.chebyshev_series(P, offsets, C, rows[:-1] + [offsets[1] + 1], t1, t0, W)
    with pytest.raises(ValueError, match="indices out of range"):
        bad = P.copy()
        bad.indices[3] = n
        ldlt.chebyshev_series(bad, offsets, C, rows, t1, t0, W)
    with pytest.raises(ValueError, match="one shape"):
        ldlt.chebyshev_series(P, offsets, C, rows, t1, t0[:-1], W)


@pytest.mark.parametrize("width", [32, 16, 8, 4, 3])
def test_compiled_poisson_series_rounds_as_numpy(width):
    """The compiled uniformization terms agree bit for bit with their numpy form, on blocks that
    stop at their own terms."""
    import scipy.sparse as sp

    from spectral_igl.linalg import ldlt

    if not ldlt.available():
        pytest.skip("no compiled extension")
    rng = np.random.default_rng(10 + width)
    sizes = [30, 45, 20, 12]
    P = sp.csr_matrix(sp.block_diag([sp.random(s, s, density=0.25, random_state=rng) + sp.eye(s) for s in sizes]))
    offsets = np.r_[0, np.cumsum(sizes)]
    lam = rng.uniform(0.5, 3.0, len(sizes))
    K = 12
    rows = [0] + [int(offsets[4 if k < 6 else 2 if k < 10 else 1]) for k in range(1, K + 1)]
    W0 = rng.uniform(0, 1, (P.shape[0], width))
    want, q = W0.copy(), W0.copy()
    lam_rows = np.repeat(lam, sizes)[:, None]
    for k in range(1, K + 1):
        q = P[:rows[k], :rows[k]] @ q[:rows[k]]
        q *= lam_rows[:rows[k]] / k
        want[:rows[k]] += q
    got = W0.copy()
    assert ldlt.poisson_series(P, offsets, lam, rows, got)
    assert np.array_equal(got, want)
    with pytest.raises(ValueError, match="one entry per block"):
        ldlt.poisson_series(P, offsets, lam[:-1], rows, W0.copy())


def test_sparse_heat_kernel_same_with_the_compiled_series(monkeypatch):
    """sparse_heat_kernel gives the same matrix and bounds, bit for bit, with the compiled
    series and with their numpy forms (the path taken where the extension is missing)."""
    from spectral_igl.approx import uniformization

    lap = _exact("sliver")[0]
    calls = []
    for name in ("chebyshev_series", "poisson_series"):
        compiled = getattr(uniformization, name)
        monkeypatch.setattr(uniformization, name, lambda *a, f=compiled, name=name: calls.append(name) or f(*a))
    K, info = sig.sparse_heat_kernel(lap, 2e-4, block=16, return_info=True)
    # the sliver's regions took the Chebyshev series, the others uniformization
    assert set(calls) == {"chebyshev_series", "poisson_series"}
    monkeypatch.setattr(uniformization, "chebyshev_series", lambda *a: False)
    monkeypatch.setattr(uniformization, "poisson_series", lambda *a: False)
    K2, info2 = sig.sparse_heat_kernel(lap, 2e-4, block=16, return_info=True)
    assert (K != K2).nnz == 0 and (info["abs_error"] != info2["abs_error"]).nnz == 0


def test_first_radii_are_first_radius_per_source():
    """The radii of many sources at once are those of one source at a time, in the hop regime
    (t short against the spacing), the Gaussian one, and for isolated vertices (spacing inf)."""
    from spectral_igl.approx.region import first_radii, first_radius

    rng = np.random.default_rng(3)
    h2 = rng.uniform(1e-6, 1e-4, 400)
    h2[::9] = np.inf
    goal = 10.0 ** rng.uniform(-16, 0, 400)
    for t in (1e-7, 6e-7, 1e-5):
        want = [first_radius(t, float(a), float(g)) for a, g in zip(h2, goal)]
        assert np.array_equal(first_radii(t, h2, goal), want)


@pytest.mark.parametrize("name", ["grid", "two", "sliver"])
def test_compiled_regions_are_the_numpy_regions(name, monkeypatch):
    """grow_regions gives the same keys in the compiled loop as in its numpy form, with groups
    that stop at their radius and groups that pass their limit (whole component)."""
    import scipy.sparse as sp

    from spectral_igl.approx import region
    from spectral_igl.linalg import ldlt

    if not ldlt.available():
        pytest.skip("no compiled extension")
    lap = _exact(name)[0]
    L, h2, labels = sp.csr_matrix(lap.L), region.vertex_spacing(lap), lap.components
    rng = np.random.default_rng(5)
    sizes = [3, 1, 6, 10, 1, 19]
    # each group's sources in one component (that of its first)
    groups = []
    for size in sizes:
        first = rng.integers(lap.n)
        same = np.flatnonzero(labels == labels[first])
        groups.append(np.r_[first, rng.choice(same, size - 1)])
    sources, offsets = np.concatenate(groups), np.r_[0, np.cumsum(sizes)]
    radii = rng.uniform(0.01, 0.3, len(sizes))
    limits = np.array([lap.n, 10, lap.n, 5, lap.n, lap.n])
    got = region.grow_regions(L, h2, sources, offsets, radii, limits, labels)
    monkeypatch.setattr(region, "region_keys", lambda *a: None)
    want = region.grow_regions(L, h2, sources, offsets, radii, limits, labels)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
    whole = np.bincount(labels)[labels[sources[offsets[:-1]]]]
    assert np.any(np.diff(got[1]) == whole) and np.any(np.diff(got[1]) < whole)


def test_sparse_heat_kernel_reports_its_absolute_time():
    """info["time"] is the absolute time the kernel was computed at, whatever unit t was given
    in (a mesh of area 0.02: t = 1e-4 of the shape's area is 2e-6)."""
    V, F = icosphere(3)
    lap = sig.laplacian(V, F)
    lap = sig.laplacian(V * np.sqrt(0.02 / lap.area()), F)
    K, info = sig.sparse_heat_kernel(lap, 1e-4, time_unit="shape", return_info=True)
    assert np.isclose(info["time"], sig.shape_time(lap, 1e-4), rtol=0) and np.isclose(info["time"], 2e-6, rtol=1e-12)
    K2 = sig.sparse_heat_kernel(lap, info["time"])
    assert (K != K2).nnz == 0


def test_sparse_heat_kernel_does_not_depend_on_the_batches_timing(monkeypatch):
    """Batches in flight at once give the same matrix and bounds whatever their threads' timing
    (batches finishing in another order, delayed at random), and each batch's calibration is
    read from the batches collected before it."""
    import random
    import time

    from spectral_igl import local

    lap = _exact("sliver")[0]
    monkeypatch.setattr(local, "BATCH", 48)              # several batches on a small mesh
    monkeypatch.setattr(local, "FIRST_BATCH", 16)
    runs = []
    for seed in (0, 1):
        rng = random.Random(seed)
        solve = local._solve_batch

        def slow(*args, solve=solve, rng=rng):
            time.sleep(rng.uniform(0.0, 0.02))
            return solve(*args)

        monkeypatch.setattr(local, "_solve_batch", slow)
        runs.append(sig.sparse_heat_kernel(lap, 1e-4, block=8, return_info=True))
        monkeypatch.setattr(local, "_solve_batch", solve)
    (K, info), (K2, info2) = runs
    assert (K != K2).nnz == 0 and (info["abs_error"] != info2["abs_error"]).nnz == 0
    assert np.array_equal(info["dropped_mass"], info2["dropped_mass"])


def test_column_blocks_are_the_column_slices():
    """sparse_heat_kernel's symmetric assembly reads A's columns block by block with a cursor
    per row: each block is A[:, a:b] transposed, arrays and all."""
    import scipy.sparse as sp
    from spectral_igl.local import _column_block

    rng = np.random.default_rng(1)
    for _ in range(30):
        n = int(rng.integers(1, 200))
        A = sp.random(n, n, density=float(rng.uniform(0.0, 0.3)), format="csr", random_state=int(rng.integers(1e9)))
        A.sort_indices()
        step = int(rng.integers(1, n + 1))
        cursor = A.indptr[:-1].astype(np.int64)
        for a in range(0, n, step):
            b = min(a + step, n)
            got, want = _column_block(A, a, b, cursor), sp.csr_matrix(A[:, a:b].T)
            assert got.shape == want.shape and got.has_canonical_format
            for x, y in ((got.indptr, want.indptr), (got.indices, want.indices), (got.data, want.data)):
                assert np.array_equal(x, y)
        assert np.array_equal(cursor, A.indptr[1:])


def test_row_scaled_is_scipys_diagonal_product():
    """rate_matrix scales L's rows without scipy's general product, to the same arrays (entry
    order, dropped zeros, roundings), so the series sum in the same order."""
    import scipy.sparse as sp
    from spectral_igl.approx.uniformization import _row_scaled

    rng = np.random.default_rng(0)
    mats = [sp.csr_matrix(_exact("icosphere")[0].L)]
    mats += [sp.random(n, n, density=0.2, format="csr", random_state=n) for n in (1, 7, 60)]
    for L in mats:
        a = rng.normal(size=L.shape[0])
        a[rng.random(L.shape[0]) < 0.2] = 0.0
        want, got = sp.csr_matrix(sp.diags(a) @ L), _row_scaled(L, a)
        for x, y in ((got.indptr, want.indptr), (got.indices, want.indices), (got.data, want.data)):
            assert np.array_equal(x, y)
