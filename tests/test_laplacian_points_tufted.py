"""The tufted cover of a triangle soup and its intrinsic Delaunay triangulation."""
import igl
import numpy as np
import pytest
from scipy.spatial import Delaunay

from data_generators import icosphere, sphere_points
from spectral_igl.laplacian.intrinsic import cotan_elements, intrinsic_cotan_stiffness
from spectral_igl.laplacian.points import fan_votes, local_triangles, tufted_cover, tufted_delaunay


def cover_operators(P, T):
    """Half the cotangent stiffness and half the lumped mass of the flipped cover."""
    l, F = tufted_delaunay(P, T)
    s = 0.5 * l.sum(axis=1)
    area = np.sqrt(np.maximum(s * (s - l[:, 0]) * (s - l[:, 1]) * (s - l[:, 2]), 0.0))
    mass = np.bincount(F.ravel(), weights=np.repeat(area / 3.0, 3), minlength=len(P))
    return 0.5 * cotan_elements(l, F, len(P)).toarray(), 0.5 * mass


def test_every_edge_of_the_cover_of_a_cloud_has_exactly_two_faces():
    P = sphere_points(400, seed=3)
    T = local_triangles(P, k=20)
    F, l, twin = tufted_cover(P, T)
    u = len(np.unique(np.sort(T, axis=1), axis=0))
    assert F.shape == (2 * u, 3) and u < len(T)               # the stars share triangles
    np.testing.assert_array_equal(F[u:], F[:u, ::-1])
    h = np.arange(3 * len(F))
    np.testing.assert_array_equal(twin[twin], h)
    assert np.all(twin != h)
    tail, head = F.ravel()[3 * (h // 3) + (h + 1) % 3], F.ravel()[3 * (h // 3) + (h + 2) % 3]
    # glued halfedges run the other way between the same points: the cover is oriented
    np.testing.assert_array_equal(tail[twin], head)
    np.testing.assert_array_equal(head[twin], tail)
    np.testing.assert_allclose(l.ravel()[twin], l.ravel(), rtol=0, atol=0)
    # the soup of a cloud is not edge-manifold: some edges hold three or more triangles
    e = np.sort(np.c_[F[:u, [1, 2]], F[:u, [2, 0]], F[:u, [0, 1]]].reshape(-1, 2), axis=1)
    assert np.unique(e, axis=0, return_counts=True)[1].max() >= 3


def test_pages_of_a_book_are_glued_to_their_angular_neighbours():
    # four pages about the spine (0, 1), at 0, 180, 90 and 270 degrees in that order
    ang = np.radians([0.0, 180.0, 90.0, 270.0])
    P = np.r_[[[0.0, 0, 0], [0.0, 0, 1]], np.c_[np.cos(ang), np.sin(ang), np.full(4, 0.5)]]
    T = np.c_[np.zeros(4, int), np.ones(4, int), 2 + np.arange(4)]
    F, _, twin = tufted_cover(P, T)
    spine = [3 * f + i for f in range(8) for i in range(3) if {F[f, (i + 1) % 3], F[f, (i + 2) % 3]} == {0, 1}]
    pairs = {frozenset((h // 3 % 4, twin[h] // 3 % 4)) for h in spine}
    assert pairs == {frozenset(p) for p in [(0, 2), (2, 1), (1, 3), (3, 0)]}   # never 0-180 or 90-270


def test_planar_equilateral_patch_gives_the_planar_cotan_laplacian():
    i, j = np.meshgrid(np.arange(6), np.arange(5), indexing="ij")
    P = np.c_[(i + 0.5 * j).ravel(), (j * np.sqrt(3) / 2).ravel(), np.zeros(30)]
    idx = (i * 5 + j)
    F = np.r_[np.c_[idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[:-1, 1:].ravel()],
              np.c_[idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]]
    L, mass = cover_operators(P, F)
    np.testing.assert_allclose(L, -igl.cotmatrix(P, F).toarray(), rtol=0, atol=1e-13)
    np.testing.assert_allclose(mass, igl.massmatrix(P, F, igl.MASSMATRIX_TYPE_BARYCENTRIC).diagonal(),
                               rtol=1e-14)


def test_closed_mesh_cover_is_its_intrinsic_delaunay_laplacian():
    V, F = icosphere(2)
    V = V * np.array([3.0, 1.0, 0.4])                         # obtuse triangles: flips needed
    L, _ = cover_operators(V, F)
    ref = intrinsic_cotan_stiffness(V, F).toarray()
    assert np.abs(ref - (-igl.cotmatrix(V, F).toarray())).max() > 0.1
    np.testing.assert_allclose(L, ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_open_mesh_cover_is_its_mirrored_double():
    rng = np.random.default_rng(5)
    Q = rng.random((60, 2))
    F = Delaunay(Q).simplices
    P = np.c_[Q, np.zeros(60)]
    L, _ = cover_operators(P, F)
    ref = intrinsic_cotan_stiffness(P, F, mirror=True).toarray()
    assert np.abs(ref - (-igl.cotmatrix(P, F).toarray())).max() > 0.1   # boundary edges flip
    np.testing.assert_allclose(L, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    assert np.all(L[~np.eye(60, dtype=bool)] <= 1e-12)


def test_tufted_cover_refuses_bad_triangles():
    P = np.eye(3)
    with pytest.raises(ValueError, match="T must be"):
        tufted_cover(P, np.array([[0, 1, 3]]))
    with pytest.raises(ValueError, match="T must be"):
        tufted_cover(P, np.array([0, 1, 2]))


def test_max_tilt_leaves_out_the_triangles_standing_on_a_star():
    i, j = np.meshgrid(np.arange(12.0), np.arange(12.0))
    P = np.c_[(i + 0.5 * j).ravel(), (j * np.sqrt(3) / 2).ravel(), np.zeros(144)]
    flat = local_triangles(P, k=20)
    area = np.linalg.norm(np.cross(P[flat[:, 1]] - P[flat[:, 0]], P[flat[:, 2]] - P[flat[:, 0]]), axis=1)
    # every triangle of a flat cloud lies in its stars' plane: none is left out but the
    # collinear ones of the boundary stars, whose plane is undefined
    kept = {tuple(t) for t in local_triangles(P, k=20, max_tilt=1.0)}
    assert {tuple(t) for t in flat[area > 1e-9]} <= kept <= {tuple(t) for t in flat}
    # lift one point two spacings: its triangles stand at atan(2 / (sqrt(3)/2)) = 66.6° or
    # more on the planes of its neighbours' stars (and its neighbours' on its own)
    spike = 6 * 12 + 5
    P[spike, 2] = 2.0
    T = local_triangles(P, k=20)
    assert np.sum(np.any(T == spike, axis=1)) >= 6
    for tilt, left in ((60.0, False), (70.0, True)):
        Tk = local_triangles(P, k=20, max_tilt=tilt)
        assert np.any(Tk == spike) == left
    # the rest of the lattice keeps its triangles
    Tk = local_triangles(P, k=20, max_tilt=60.0)
    assert set(np.unique(Tk)) == set(range(144)) - {spike}
    with pytest.raises(ValueError, match="max_tilt"):
        local_triangles(P, max_tilt=120.0)


def lattice(m):
    i, j = np.meshgrid(np.arange(float(m)), np.arange(float(m)))
    return np.c_[(i + 0.5 * j).ravel(), (j * np.sqrt(3) / 2).ravel(), np.zeros(m * m)]


def test_fan_votes_count_the_fans_that_hold_each_face():
    m = 9
    P = lattice(m)
    T = local_triangles(P, k=12)
    U = np.unique(np.sort(T, axis=1), axis=0)
    votes = fan_votes(T, U[:, ::-1])                    # orientation does not matter
    assert votes.sum() == len(T) and votes.min() >= 1 and votes.max() == 3
    # on a triangular lattice every fan is the ring of 6 triangles: a triangle whose three
    # corners are interior points is in all three fans
    inner = np.zeros(m * m, dtype=bool)
    inner.reshape(m, m)[1:-1, 1:-1] = True
    assert np.all(votes[inner[U].all(axis=1)] == 3)
    # a face no fan holds (as made by a flip) gets 0, an empty soup nothing
    np.testing.assert_array_equal(fan_votes(T, [[0, 1, m * m - 1], [2, 1, 0]]), [0, 0])
    np.testing.assert_array_equal(fan_votes(np.zeros((0, 3), dtype=int), U[:2]), [0, 0])


def test_normal_k_sets_the_first_normal_only():
    P = lattice(8)
    # any normal_k finds a flat cloud's plane: the same fans
    base = local_triangles(P, k=12)
    for normal_k in (3, 8, 12):
        np.testing.assert_array_equal(local_triangles(P, k=12, normal_k=normal_k), base)
    for bad in (2, True, 8.0):
        with pytest.raises(ValueError, match="normal_k"):
            local_triangles(P, normal_k=bad)
