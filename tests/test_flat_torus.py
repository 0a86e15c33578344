"""Flat torus: intrinsic periodic mesh, analytic spectrum 4π²(i²/a² + j²/b²), O(h²) convergence."""
import numpy as np
import pytest

import spectral_igl as sig
from data_generators import flat_torus, flat_torus_eigenvalues, flat_torus_laplacian


def test_analytic_spectrum_by_enumeration():
    a, b = 1.0, 0.7
    ev = flat_torus_eigenvalues(30, a, b)
    i, j = np.meshgrid(np.arange(-20, 21), np.arange(-20, 21), indexing="ij")
    brute = np.sort((4 * np.pi ** 2 * (i ** 2 / a ** 2 + j ** 2 / b ** 2)).ravel())[:30]
    assert np.allclose(ev, brute, rtol=1e-15, atol=0)
    assert ev[0] == 0 and ev[1] == pytest.approx(4 * np.pi ** 2) and ev[2] == ev[1]


def test_mesh_is_closed_flat_and_periodic():
    F, l = flat_torus(2.0, 1.0, 8, 6)
    assert F.shape == (96, 3) and l.shape == (96, 3)
    assert np.bincount(F.ravel()).tolist() == [6] * 48  # valence 6 everywhere: no boundary
    h_u, h_v = 2.0 / 8, 1.0 / 6
    assert np.allclose(np.sort(l, axis=1), [h_v, h_u, np.hypot(h_u, h_v)])
    lap = flat_torus_laplacian(2.0, 1.0, 8, 6)
    assert lap.n_components == 1 and lap.area() == pytest.approx(2.0, rel=1e-14)
    assert np.allclose(lap.L @ np.ones(48), 0, atol=1e-12)


def test_fem_eigenvalues_converge_at_second_order():
    a, b, k = 1.0, 0.7, 13
    exact = flat_torus_eigenvalues(k, a, b)
    errs = []
    for m in (16, 32):
        ev, _ = sig.eigs(flat_torus_laplacian(a, b, m, m), k)
        errs.append(np.max(np.abs(ev - exact) / np.maximum(exact, 1)))
    # measured: 0.0663 at 16x16, 0.0162 at 32x32 (ratio 4.1)
    assert errs[1] < 0.02
    assert errs[0] / errs[1] > 3.5
