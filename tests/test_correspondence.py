"""Shape correspondence: exact recovery of a permutation, small error on a remeshed pair, the
functional map as the minimiser of its energy, descriptors against dense eigendecompositions."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from scipy.spatial import cKDTree

import spectral_igl as sig
from spectral_igl.data_generators import icosphere, resample


def lumpy(level=3):
    """A sphere stretched and bent so that no symmetry is left (matching it is well posed)."""
    V, F = icosphere(level)
    return V * [1.0, 0.8, 0.6] + 0.3 * V[:, :1] ** 2 + 0.15 * V[:, 1:2] * V[:, 2:3], F


def permuted(V, F, seed=0):
    perm = np.random.default_rng(seed).permutation(len(V))
    return V[perm], np.argsort(perm)[F], perm


def dense_pairs(lap):
    evals, X = scipy.linalg.eigh(lap.L.toarray(), lap.B.toarray())
    return np.maximum(evals, 0.0), X


def test_permuted_copy_is_recovered_exactly():
    V, F = lumpy(2)
    W, G, perm = permuted(V, F)
    res = sig.match_shapes((V, F), (W, G), k=10, k_final=30, n_descriptors=10, method="dense")
    assert np.array_equal(res.p2p, perm)           # target vertex y is source vertex perm[y]
    assert sig.map_error(V, F, res.p2p, perm, samples=None) == 0.0
    assert set(res.seconds) == {"eigs", "descriptors", "fit", "zoomout"}


@pytest.mark.parametrize("scale", [1.5, 1e-3, 1e3])
def test_a_scaled_copy_is_matched_as_the_copy(scale):
    # B-orthonormal eigenvectors scale as 1/size: without unit measure a copy 1.5 times
    # larger matched only 15% of its vertices
    V, F = lumpy(2)
    W, G, perm = permuted(V, F)
    res = sig.match_shapes((V, F), (scale * W, G), k=10, k_final=30, n_descriptors=10, method="dense")
    assert np.array_equal(res.p2p, perm)


def test_remeshed_pair_has_a_small_error():
    V, F = lumpy(2)
    W, G = resample(V, F, 0.5, seed=1)            # different connectivity and size
    W, G, perm = permuted(W, G, seed=2)
    truth = cKDTree(V).query(W)[1]                 # the source vertex at (or nearest) each point
    res = sig.match_shapes((V, F), (W, G), k=10, k_final=30, n_descriptors=10, method="dense")
    err = sig.map_error(V, F, res.p2p, truth, samples=None)
    rand = sig.map_error(V, F, np.random.default_rng(0).integers(0, len(V), len(W)), truth, samples=None)
    assert rand > 0.3 and err < 0.02               # measured 0.005 and 0.46


def test_landmark_descriptors_against_dense_heat_kernel():
    V, F = lumpy(2)
    lap = sig.laplacian(V, F)
    evals, X = dense_pairs(lap)
    lm, times = np.array([3, 50, 100]), np.array([1e-3, 1e-2, 1e-1])
    K = np.einsum("nl,ml,lt->nmt", X, X[lm], np.exp(-np.outer(evals, times))).reshape(lap.n, -1)
    K /= np.sqrt(np.einsum("ij,ij->j", K, lap.B @ K) / lap.area())
    D = sig.landmark_descriptors(lap, lm, times=times)
    assert np.abs(D - K).max() < 1e-6 * np.abs(K).max()


def test_pair_descriptors_against_dense_wks():
    V, F = lumpy(2)
    lap = sig.laplacian(V, F)
    D1, D2 = sig.pair_descriptors(lap, lap, n=6, k=40)
    evals, X = dense_pairs(lap)
    e, sigma = sig.wks_energies(lap, 6, 40)
    pos = evals > 1e-9
    w = np.exp(-(e[None, :] - np.log(evals[pos])[:, None]) ** 2 / (2 * sigma ** 2))
    W = (X[:, pos] ** 2 @ w) / w.sum(axis=0)
    W /= np.sqrt(np.einsum("ij,ij->j", W, lap.B @ W) / lap.area())
    assert np.abs(D1 - W).max() < 1e-6 and np.array_equal(D1, D2)


def test_own_grid_is_scale_invariant_and_common_grid_is_not():
    V, F = lumpy(2)
    own = sig.pair_descriptors((V, F), (3 * V, F), kind="hks", n=6, k=30)
    common = sig.pair_descriptors((V, F), (3 * V, F), kind="hks", n=6, k=30, grid="common")
    assert np.abs(own[0] - own[1]).max() < 1e-6
    assert np.abs(common[0] - common[1]).max() > 0.1    # measured 0.24


def commutator(C, P1, P2):
    return sum(np.sum((C @ a - b @ C) ** 2) for a, b in zip(P1, P2))


def energy(C, A, Bh, M, P1, P2, O1, O2, w_d, w_l, w_p, w_o):
    E = np.sum((C @ A - Bh) ** 2) * w_d + w_l * np.sum(M * C ** 2)
    return E + w_p * commutator(C, P1, P2) + w_o * commutator(C, O1, O2)


def resolvent_mask(x, y, gamma=0.5):
    """|R(x_j) - R(y_i)|^2, R(l) = 1 / ((l / max)^gamma - i) in real and imaginary parts."""
    top = max(x.max(), y.max())
    a, b = (x / top) ** gamma, (y / top) ** gamma
    re = a[None, :] / (a[None, :] ** 2 + 1) - b[:, None] / (b[:, None] ** 2 + 1)
    im = 1 / (a[None, :] ** 2 + 1) - 1 / (b[:, None] ** 2 + 1)
    return re ** 2 + im ** 2


@pytest.mark.parametrize("mask", ["squared", "resolvent"])
@pytest.mark.parametrize("mu_d, mu_o", [(0.0, 0.0), (0.5, 0.0), (0.0, 0.7), (0.5, 0.7)])
def test_functional_map_minimises_its_energy(mu_d, mu_o, mask):
    """The gradient of the documented energy vanishes at C, and C beats every perturbation."""
    from spectral_igl.applications.correspondence import orientation_operators

    V, F = lumpy(2)
    W, G = resample(V, F, 0.5, seed=3)
    l1, l2 = sig.laplacian(V, F), sig.laplacian(W, G)
    b1, b2 = sig.eigs(l1, 6), sig.eigs(l2, 5)
    rng = np.random.default_rng(0)
    D1, D2 = rng.random((l1.n, 4)), rng.random((l2.n, 4))
    C = sig.functional_map(l1, l2, D1, D2, b1, b2, laplacian_weight=0.3, commutativity_weight=mu_d,
                           laplacian_mask=mask, orientation_weight=mu_o)
    assert C.shape == (5, 6)
    A, Bh = b1[1].T @ l1.B @ D1, b2[1].T @ l2.B @ D2
    x, y = l1.area() * np.abs(b1[0]), l2.area() * np.abs(b2[0])
    M = (x[None, :] - y[:, None]) ** 2 if mask == "squared" else resolvent_mask(x, y)
    P1 = np.einsum("ni,np,nj->pij", l1.B @ b1[1], D1, b1[1])
    P2 = np.einsum("ni,np,nj->pij", l2.B @ b2[1], D2, b2[1])
    O1, O2 = orientation_operators(l1, b1[1], D1), orientation_operators(l2, b2[1], D2)
    assert np.abs(O1 - O1.transpose(0, 2, 1)).max() > 0.1 * np.abs(O1).max()   # not symmetric
    w = (1 / (4 * np.mean(Bh ** 2)), 0.3 / np.mean(M),
         mu_d / (4 * np.mean(np.concatenate([P1.ravel(), P2.ravel()]) ** 2)),
         mu_o / (4 * np.mean(np.concatenate([O1.ravel(), O2.ravel()]) ** 2)))
    e0 = energy(C, A, Bh, M, P1, P2, O1, O2, *w)
    for _ in range(20):
        dC = 1e-4 * rng.normal(size=C.shape)
        assert energy(C + dC, A, Bh, M, P1, P2, O1, O2, *w) > e0


def test_point_map_and_zoomout():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(40, 5))
    perm = rng.permutation(40)
    R = np.linalg.qr(rng.normal(size=(5, 5)))[0]
    # shape 2's embedding is shape 1's, permuted and rotated by C: Phi2 = Pi Phi1 C^T
    assert np.array_equal(sig.point_map(R, X, X[perm] @ R.T), perm)
    V, F = lumpy(2)
    W, G, perm = permuted(V, F)
    l1, l2 = sig.laplacian(V, F), sig.laplacian(W, G)
    b1, b2 = sig.eigs(l1, 20), sig.eigs(l2, 20)
    p2p, C = sig.zoomout(l2, perm, b1, b2)
    assert np.array_equal(p2p, perm)
    # the pull-back of the true map is orthogonal up to the signs of the eigenvectors
    assert np.allclose(np.abs(C), np.eye(20), atol=1e-6)


def test_map_error_on_the_sphere():
    V, F = icosphere(3)
    truth = np.arange(len(V))
    anti = cKDTree(V).query(-V)[1]
    assert sig.map_error(V, F, anti, truth, samples=10) == pytest.approx(np.pi / np.sqrt(4 * np.pi), rel=0.01)
    heat = sig.map_error(V, F, anti, truth, samples=10, method="heat")
    assert heat == pytest.approx(np.pi / np.sqrt(4 * np.pi), rel=0.05)


def test_bad_input():
    V, F = icosphere(1)
    lap = sig.laplacian(V, F)
    basis = sig.eigs(lap, 4)
    D = np.ones((lap.n, 2))
    with pytest.raises(ValueError, match="kind"):
        sig.pair_descriptors(lap, lap, kind="sihks")
    with pytest.raises(ValueError, match="grid"):
        sig.pair_descriptors(lap, lap, grid="mine")
    with pytest.raises(ValueError, match="landmarks"):
        sig.landmark_descriptors(lap, [lap.n])
    with pytest.raises(ValueError, match="same number of columns"):
        sig.functional_map(lap, lap, D, D[:, :1], basis, basis)
    with pytest.raises(ValueError, match="desc1"):
        sig.functional_map(lap, lap, D[:5], D, basis, basis)
    with pytest.raises(ValueError, match="desc2"):
        sig.functional_map(lap, lap, D, np.full_like(D, np.nan), basis, basis)
    with pytest.raises(TypeError, match="basis1"):
        sig.functional_map(lap, lap, D, D, basis[1], basis)
    with pytest.raises(ValueError, match="basis2"):
        sig.functional_map(lap, lap, D, D, basis, (basis[0], basis[1][:5]))
    with pytest.raises(ValueError, match="laplacian_weight"):
        sig.functional_map(lap, lap, D, D, basis, basis, laplacian_weight=-1.0)
    with pytest.raises(ValueError, match="laplacian_mask"):
        sig.functional_map(lap, lap, D, D, basis, basis, laplacian_mask="cube")
    with pytest.raises(ValueError, match="p2p"):
        sig.zoomout(lap, np.arange(lap.n - 1), basis, basis)
    with pytest.raises(TypeError, match="p2p"):
        sig.map_error(V, F, np.zeros(lap.n), np.arange(lap.n))
    with pytest.raises(ValueError, match="truth"):
        sig.map_error(V, F, np.arange(lap.n), np.arange(lap.n) + 1)
    with pytest.raises(ValueError, match="method"):
        sig.map_error(V, F, np.arange(lap.n), np.arange(lap.n), method="fast")
    with pytest.raises(ValueError, match="k_final"):
        sig.match_shapes(lap, lap, k=10, k_final=5)
    with pytest.raises(ValueError, match="landmarks"):
        sig.match_shapes(lap, lap, k=3, k_final=5, n_descriptors=4, landmarks=[1, 2])
    with pytest.raises(ValueError, match="C must be"):
        sig.point_map(np.ones(3), basis[1], basis[1])


def test_a_part_is_matched_into_the_whole():
    # the target is the source without a cap (ground truth: the kept vertices), measured by
    # the heat method: 0.264 with the former default (squared eigenvalue differences as the
    # Laplacian mask, weight 0.01), 0.187 with the resolvent mask at weight 0.1; a random
    # map: 0.43. Other caps of this small shape are matched no better than at random by
    # either (10 eigenfunctions do not tell a part of it from its mirror image). Orientation
    # preservation is off here: at its default weight it gave 0.49 on this near-sphere, whose
    # true map in 10 eigenfunctions commutes no better with the orientation operators than its
    # mirror (the term then pulls C towards zero); on the benchmark's limbs it is what helps
    V, F = lumpy(3)
    keep = V[:, 1] < V[:, 1].max() - 0.25 * np.ptp(V[:, 1])
    G = F[np.all(keep[F], axis=1)]
    kept = np.unique(G)
    W, G = V[kept], np.searchsorted(kept, G)
    W, G, perm = permuted(W, G, seed=2)
    truth = kept[perm]
    res = sig.match_shapes((V, F), (W, G), k=10, k_final=30, n_descriptors=10, method="dense",
                           orientation_weight=0.0)
    assert sig.map_error(V, F, res.p2p, truth, samples=None, method="heat") < 0.22


def test_orientation_operator_on_a_flat_patch():
    """On a plane, <grad f x grad g, n> is the 2-D cross product f_x g_y - f_y g_x: for linear f
    and g a constant c, integrated against each hat function: c times its barycentric area."""
    from scipy.spatial import Delaunay

    from spectral_igl.applications.correspondence import orientation_operators

    P = np.random.default_rng(0).uniform(size=(12, 2))
    F = Delaunay(P).simplices
    V = np.c_[P, np.zeros(len(P))]
    e1, e2 = P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]
    area = (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]) / 2
    assert area.min() > 0                                       # counter-clockwise: n = +z
    hat = np.bincount(F.ravel(), np.repeat(area / 3, 3), len(V))
    f, g = 2 * P[:, 0] + P[:, 1], -P[:, 0] + 3 * P[:, 1]        # grad f = (2, 1), grad g = (-1, 3)
    O = orientation_operators(sig.laplacian(V, F), np.eye(len(V)), np.c_[f, g])
    assert O.shape == (2, 12, 12)
    assert np.abs(O[0] @ g - 7.0 * hat).max() < 1e-14            # 2 * 3 - 1 * (-1) = 7
    assert np.abs(O[1] @ f + 7.0 * hat).max() < 1e-14            # antisymmetric in f and g
    assert np.abs(O[0] @ f).max() < 1e-14
    flipped = orientation_operators(sig.laplacian(V, F[:, ::-1]), np.eye(len(V)), f[:, None])
    assert np.abs(flipped[0] + O[0]).max() < 1e-14              # the other orientation: -O


def test_a_mirror_image_is_not_matched_as_the_identity_with_orientation():
    # the mirrored copy (faces reversed: normals still outward) is isometric to the shape, so
    # its intrinsic descriptors are the same and without the orientation term the map is the
    # vertex-to-vertex identity, which reverses orientation
    V, F = lumpy(2)
    W, G, perm = permuted(V * [-1.0, 1.0, 1.0], F[:, ::-1])
    kw = dict(k=10, k_final=30, n_descriptors=10, method="dense")
    plain = sig.match_shapes((V, F), (W, G), orientation_weight=0.0, **kw)
    oriented = sig.match_shapes((V, F), (W, G), **kw)            # on by default for meshes
    assert np.mean(plain.p2p == perm) > 0.9
    assert np.mean(oriented.p2p == perm) < 0.1
    # and it does not disturb an orientation-preserving copy
    W, G, perm = permuted(V, F)
    assert np.array_equal(sig.match_shapes((V, F), (W, G), **kw).p2p, perm)
