"""Non-negative heat kernels: the default Laplacian is Metzler where it can be, says so truthfully
everywhere, and warns where a caller's choice gives up positivity.

Ground truth: the exact discrete heat kernel e^{-t B^-1 L} B^-1 (scipy.linalg.expm, dense) and
the analytic Neumann spectrum of the unit square, pi^2 (i^2 + j^2).
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.linalg as sla
from conftest import MESH_DIR

import spectral_igl as sig
from data_generators import box_tets, icosphere

TIMES = (1e-5, 1e-4, 1e-3, 1e-2, 1e-1)


def squeezed_square(N: int, seed: int = 0):
    """Unit square of N x N cells cut in two, vertices jittered by up to 0.35 cell, the rows
    next to the boundary at 0.4 cell from it: boundary edges facing obtuse angles."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 1.0, N + 1)
    X, Y = np.meshgrid(x, x, indexing="ij")
    V = np.c_[X.ravel(), Y.ravel()]
    J = rng.uniform(-0.35, 0.35, V.shape) / N
    for a in range(2):
        J[(V[:, a] == 0) | (V[:, a] == 1), a] = 0.0
        J[np.isclose(V[:, a], 1.0 / N), a] = -0.6 / N
        J[np.isclose(V[:, a], 1.0 - 1.0 / N), a] = 0.6 / N
    idx = np.arange((N + 1) ** 2).reshape(N + 1, N + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel()
    return np.c_[V + J, np.zeros(len(V))], np.r_[np.c_[a, b, d], np.c_[a, d, c]]


def book(N: int):
    """Three squeezed squares sharing the edge x = 0: non-manifold there."""
    V0, F = squeezed_square(N)
    spine = np.flatnonzero(V0[:, 0] == 0)
    rest = np.flatnonzero(V0[:, 0] != 0)
    Vs, Fs = [V0], [F]
    for p in (1, 2):
        Vp, _ = squeezed_square(N, seed=p)
        ang = 2 * np.pi * p / 3
        new = np.empty(len(Vp), dtype=np.int64)
        new[spine] = spine
        new[rest] = sum(len(v) for v in Vs) + np.arange(rest.size)
        Vs.append(np.c_[Vp[rest, 0] * np.cos(ang), Vp[rest, 1], Vp[rest, 0] * np.sin(ang)])
        Fs.append(new[F])
    return np.vstack(Vs), np.vstack(Fs)


def unit_area(V, F, **kw):
    lap = sig.laplacian(V, F, **kw)
    dim = 3 if lap.domain == "tet" else 2
    return sig.laplacian(V / lap.area() ** (1.0 / dim), F, **kw)


def exact_heat_min_over_max(lap):
    """min/max of the dense e^{-t B^-1 L} B^-1 over the TIMES."""
    Binv = np.diag(1.0 / lap.B.diagonal())
    A = -Binv @ lap.L.toarray()
    out = []
    for t in TIMES:
        K = sla.expm(t * A) @ Binv
        out.append(K.min() / K.max())
    return np.array(out)


def test_obtuse_boundary_default_is_metzler_and_its_heat_is_non_negative():
    V, F = squeezed_square(10)
    old = unit_area(V, F, positive=False)       # intrinsic Delaunay alone: boundary edges stay
    assert not old.is_metzler and not old.data["positivity"]
    assert exact_heat_min_over_max(old).min() < -1e-4     # what the default used to give
    lap = unit_area(V, F)
    assert lap.is_metzler and lap.data["positivity"] and "metzler=True" in repr(lap)
    assert exact_heat_min_over_max(lap).min() >= -1e-12


def test_non_manifold_default_is_metzler_and_its_heat_is_non_negative():
    V, F = book(5)
    e = np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1)
    assert np.unique(e, axis=0, return_counts=True)[1].max() == 3
    cotan = unit_area(V, F, weights="cotan")
    assert not cotan.is_metzler
    assert exact_heat_min_over_max(cotan).min() < -1e-4
    lap = unit_area(V, F)
    assert lap.is_metzler and lap.data["weights"] == "intrinsic_delaunay"
    assert exact_heat_min_over_max(lap).min() >= -1e-12


def test_tets_keep_cotan_by_default_and_positive_true_makes_them_metzler():
    V, T = box_tets((3, 3, 3), (1.0, 1.0, 1.0))
    rng = np.random.default_rng(1)
    inner = np.all((V > 1e-9) & (V < 1 - 1e-9), axis=1)
    V[inner] += rng.uniform(-0.08, 0.08, (inner.sum(), 3))
    lap = unit_area(V, T)
    assert lap.data["weights"] == "cotan" and not lap.data["positive"]
    assert not lap.is_metzler and lap.data["positivity"] is False
    assert exact_heat_min_over_max(lap).min() < -1e-4
    pos = unit_area(V, T, positive=True)
    assert pos.is_metzler and pos.data["clamped"] > 0
    assert exact_heat_min_over_max(pos).min() >= -1e-12


def test_default_eigenvalues_converge_at_second_order_on_the_neumann_square():
    """The boundary edges are flipped in the mesh's mirror double, not merely dropped: the
    error keeps the rate (and the size) of the intrinsic Delaunay Laplacian."""
    ref = np.sort([np.pi ** 2 * (i * i + j * j) for i in range(5) for j in range(5)])[1:7]
    err, old = [], []
    for N in (8, 16, 32):
        V, F = squeezed_square(N)
        for out, kw in ((err, {}), (old, {"positive": False})):
            lap = sig.laplacian(V, F, **kw)
            ev = sla.eigh(lap.L.toarray(), lap.B.toarray(), eigvals_only=True, subset_by_index=[1, 6])
            out.append(np.max(np.abs(ev - ref) / ref))
        assert sig.laplacian(V, F).is_metzler
    rates = np.log2(np.array(err[:-1]) / np.array(err[1:]))
    assert np.all(rates > 1.8), (err, rates)
    assert err[-1] <= 1.05 * old[-1], (err, old)


def test_the_warning_fires_once_for_a_non_metzler_choice():
    V, F = icosphere(2)
    full = sig.laplacian(V, F, mass="full")
    assert not full.is_metzler and not full.data["positivity"]
    with pytest.warns(RuntimeWarning, match="not diagonal"):
        full.warn_if_not_metzler()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        full.warn_if_not_metzler()                 # once per Laplacian
        sig.laplacian(V, F).warn_if_not_metzler()  # the default: silent
    V, F = squeezed_square(6)
    cot = sig.laplacian(V, F, weights="cotan")
    k = int(np.sum(np.triu(cot.L.toarray(), 1) > 0))
    assert k > 0
    with pytest.warns(RuntimeWarning, match=f"{k} of its edge weights are negative"):
        cot.warn_if_not_metzler("heat kernel")


def test_is_metzler_is_the_definition_on_every_domain():
    rng = np.random.default_rng(0)
    P = rng.standard_normal((300, 3))
    P /= np.linalg.norm(P, axis=1, keepdims=True)
    laps = [sig.point_cloud_laplacian(P), sig.voxel_laplacian(np.ones((4, 3, 2), bool)),
            sig.laplacian(*icosphere(1), mass="full"), sig.laplacian(*squeezed_square(5), weights="cotan"),
            sig.laplacian(*box_tets((2, 2, 2))), sig.graph_laplacian(4, [[0, 1], [1, 2], [2, 3]])]
    for lap in laps:
        L, B = lap.L.toarray(), lap.B.toarray()
        off = L - np.diag(np.diag(L))
        truth = bool(np.all(off <= 0) and np.all(B == np.diag(np.diag(B))) and np.all(np.diag(B) > 0))
        assert lap.is_metzler == truth, lap
    assert [lap.is_metzler for lap in laps] == [True, True, False, False, laps[4].is_metzler, True]


def test_positive_clamps_only_what_is_negative_and_keeps_rows_summing_to_zero():
    V, F = squeezed_square(6)
    cot = sig.laplacian(V, F, weights="cotan")
    pos = sig.laplacian(V, F, weights="cotan", positive=True)
    Lc, Lp = cot.L.toarray(), pos.L.toarray()
    off = ~np.eye(len(Lc), dtype=bool)
    assert np.array_equal(Lp[off], np.minimum(Lc[off], 0.0))
    assert np.abs(Lp.sum(axis=1)).max() <= 1e-12 * np.abs(Lp).max()
    assert pos.data["clamped"] == int(np.sum(np.triu(Lc, 1) > 0))


def test_positive_must_be_a_bool():
    with pytest.raises(TypeError, match="positive"):
        sig.laplacian(*icosphere(0), positive="yes")
    with pytest.raises(TypeError, match="positive"):
        sig.polygon_laplacian(*icosphere(0), positive=1)


@pytest.mark.skipif(not MESH_DIR.is_dir(), reason="the shared meshes are not beside the checkout")
def test_default_heat_kernel_is_non_negative_on_every_shared_triangle_mesh():
    """The default path on real meshes (boundaries, several components, non-manifold edges,
    quads triangulated by the reader): a Metzler operator and heat columns >= 0 at every t."""
    from spectral_igl.io import read_mesh

    seen = 0
    for path in sorted(MESH_DIR.iterdir()):
        if path.suffix not in (".obj", ".off"):
            continue
        V, F = read_mesh(path)[:2]
        if F.shape[1] != 3:
            continue
        lap = sig.laplacian(V, F)
        lap = sig.laplacian(V / np.sqrt(lap.area()), F)
        assert lap.is_metzler, path.name
        src = np.linspace(0, lap.n - 1, 4).astype(int)
        for t in (1e-5, 1e-3, 1e-1):
            K, info = sig.heat_kernel(lap, t, src, return_info=True)
            assert K.min() >= 0.0, (path.name, t)
            # what clipping removed was within each entry's bound of 0: nothing real was cut
            E = np.zeros((lap.n, src.size))
            E[src, np.arange(src.size)] = 1.0
            raw = sig.spectral_operator(lap, sig.filters.heat(t)).apply_inverse_mass(E)
            assert np.all(raw >= -info["abs_error"]), (path.name, t)
        seen += 1
    assert seen >= 10
