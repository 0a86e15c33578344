"""Critical points by the lower-link test: Euler relation, known functions, ties, boundaries."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import read_shared_mesh

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl.applications import critical_points, harmonic


def torus(nu=40, nv=20, R=1.0, r=0.4):
    """Closed torus grid (genus 1, chi = 0)."""
    u, v = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv, indexing="ij")
    V = np.c_[((R + r * np.cos(v)) * np.cos(u)).ravel(), ((R + r * np.cos(v)) * np.sin(u)).ravel(),
              (r * np.sin(v)).ravel()]
    idx = np.arange(nu * nv).reshape(nu, nv)
    a, b = idx, np.roll(idx, -1, axis=0)
    c, d = np.roll(idx, -1, axis=1), np.roll(np.roll(idx, -1, axis=0), -1, axis=1)
    F = np.r_[np.c_[a.ravel(), b.ravel(), d.ravel()], np.c_[a.ravel(), d.ravel(), c.ravel()]]
    return V, F


def polar_disk(n_rings=8, n_sectors=24):
    """Planar disk: centre vertex 0, rings of n_sectors vertices (chi = 1)."""
    V = [[0.0, 0.0, 0.0]]
    for k in range(1, n_rings + 1):
        ang = np.arange(n_sectors) * 2 * np.pi / n_sectors + 0.1 * k
        V += [[k * np.cos(a) / n_rings, k * np.sin(a) / n_rings, 0.0] for a in ang]
    V = np.array(V)
    F = [[0, 1 + s, 1 + (s + 1) % n_sectors] for s in range(n_sectors)]
    for k in range(1, n_rings):
        o0, o1 = 1 + (k - 1) * n_sectors, 1 + k * n_sectors
        for s in range(n_sectors):
            s1 = (s + 1) % n_sectors
            F += [[o0 + s, o1 + s, o1 + s1], [o0 + s, o1 + s1, o0 + s1]]
    return V, np.array(F)


def test_height_function_on_sphere():
    V, F = icosphere(3)
    cp = critical_points(V, F, V[:, 2])
    assert cp.minima.tolist() == [int(np.argmin(V[:, 2]))]
    assert cp.maxima.tolist() == [int(np.argmax(V[:, 2]))]
    assert cp.saddles.shape == (0, 2)
    assert cp["minima"] is cp.minima


@pytest.mark.parametrize("seed", range(5))
def test_euler_relation_random_functions(seed):
    rng = np.random.default_rng(seed)
    for (V, F), chi in ((icosphere(3), 2), (torus(), 0)):
        f = rng.standard_normal(len(V))
        cp = critical_points(V, F, f)
        assert cp.n_minima - cp.n_saddles + cp.n_maxima == chi
        # reversing the function swaps minima and maxima and keeps the saddles
        cq = critical_points(V, F, -f)
        assert np.array_equal(cq.minima, cp.maxima) and np.array_equal(cq.maxima, cp.minima)
        assert np.array_equal(cq.saddles, cp.saddles)


def test_ties_are_broken_by_index():
    V, F = icosphere(2)
    n = len(V)
    cp = critical_points(V, F, np.zeros(n))
    # a constant function is the function "vertex index": 0 is the lowest, n-1 the highest
    assert 0 in cp.minima and n - 1 in cp.maxima
    assert cp.n_minima - cp.n_saddles + cp.n_maxima == 2
    rng = np.random.default_rng(3)
    f = np.round(rng.random(n) * 2)  # three values, many ties
    cp = critical_points(V, F, f)
    assert cp.n_minima - cp.n_saddles + cp.n_maxima == 2
    # equal result for the same ordering given without ties
    order = np.lexsort((np.arange(n), f))
    g = np.empty(n)
    g[order] = np.arange(n)
    cg = critical_points(V, F, g)
    assert np.array_equal(cg.minima, cp.minima) and np.array_equal(cg.saddles, cp.saddles)


def test_monkey_saddle_multiplicity():
    V, F = polar_disk()
    z = V[:, 0] + 1j * V[:, 1]
    cp = critical_points(V, F, (z ** 3).real)
    row = cp.saddles[cp.saddles[:, 0] == 0]
    assert row.tolist() == [[0, 2]]  # three lower sectors: multiplicity 2
    cp2 = critical_points(V, F, (z ** 2).real)
    assert cp2.saddles[cp2.saddles[:, 0] == 0].tolist() == [[0, 1]]


@pytest.mark.parametrize("seed", range(3))
def test_boundary_euler_relation(seed):
    rng = np.random.default_rng(seed)
    V, F = polar_disk()
    cp = critical_points(V, F, rng.standard_normal(len(V)))
    assert cp.euler_characteristic() == pytest.approx(1.0)
    assert np.all(np.isin(cp.boundary, np.arange(len(V) - 24, len(V))))
    # annulus: drop the centre fan
    Fa = F[24:]
    cp = critical_points(V, Fa, rng.standard_normal(len(V)))
    assert cp.euler_characteristic() == pytest.approx(0.0)
    # linear function on the disk: one boundary minimum, one boundary maximum
    cp = critical_points(V, F, V[:, 0])
    assert cp.n_minima == 1 and cp.n_maxima == 1 and cp.n_saddles == 0
    assert cp.euler_characteristic() == pytest.approx(1.0)


def test_harmonic_saddles_genus_torus():
    V, F = torus()
    lap = sig.laplacian(V, F)
    i, j = int(np.argmin(V[:, 0])), int(np.argmax(V[:, 0]))
    h = harmonic(lap, [i, j], [0.0, 1.0])
    cp = critical_points(V, F, h)
    assert cp.minima.tolist() == [i] and cp.maxima.tolist() == [j]
    assert cp.n_saddles == 2  # 2g


@pytest.mark.parametrize("name,genus", [("fertility.off", 4), ("rocker-arm.obj", 1)])
def test_harmonic_saddles_real_meshes(name, genus):
    V, F = read_shared_mesh(name)
    lap = sig.laplacian(V, F)
    i, j = int(np.argmin(V[:, 1])), int(np.argmax(V[:, 1]))
    cp = critical_points(V, F, harmonic(lap, [i, j], [0.0, 1.0]))
    assert cp.n_minima == 1 and cp.n_maxima == 1
    assert cp.n_saddles == 2 * genus
    rng = np.random.default_rng(0)
    cr = critical_points(V, F, rng.random(len(V)))
    assert cr.n_minima - cr.n_saddles + cr.n_maxima == 2 - 2 * genus


def test_validation():
    V, F = icosphere(1)
    with pytest.raises(ValueError, match="f must have shape"):
        critical_points(V, F, np.zeros(len(V) + 1))
    with pytest.raises(ValueError, match="index"):
        critical_points(V, np.r_[F, [[0, 1, len(V)]]], np.zeros(len(V)))
    with pytest.raises(ValueError, match="NaN"):
        critical_points(V, F, np.full(len(V), np.nan))
    with pytest.raises(ValueError):
        critical_points(V, F, np.zeros((len(V), 2)))
