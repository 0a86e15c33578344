"""Graph Laplacian: the known spectra of paths and cycles (random-walk normalisation)."""
import numpy as np
import pytest

import spectral_igl as sig


def test_cycle_spectrum():
    n = 40
    E = np.c_[np.arange(n), (np.arange(n) + 1) % n]
    ev, _ = sig.dense_eigs(sig.graph_laplacian(n, E))
    exact = np.sort(1 - np.cos(2 * np.pi * np.arange(n) / n))
    assert np.allclose(ev, exact, atol=1e-12)


def test_path_spectrum_and_mass_is_valence():
    n = 25
    E = np.c_[np.arange(n - 1), np.arange(1, n)]
    lap = sig.graph_laplacian(n, E)
    assert np.array_equal(lap.mass, np.r_[1, np.full(n - 2, 2), 1])
    ev, _ = sig.dense_eigs(lap)
    assert np.allclose(ev, 1 - np.cos(np.pi * np.arange(n) / (n - 1)), atol=1e-12)


def test_isolated_vertices_loops_and_weights():
    lap = sig.graph_laplacian(5, [[0, 1], [1, 2], [2, 2], [0, 1]], weights=[1.0, 2.0, 5.0, 0.5])
    assert lap.n_components == 3  # {0,1,2}, {3}, {4}
    assert lap.L[0, 1] == -1.5 and lap.L[2, 2] == 2.0  # duplicate edges add, loops ignored
    assert np.all(lap.B.diagonal() > 0)
    ev, _ = sig.eigs(lap, 4)
    assert np.all(ev[:3] == 0) and ev[3] > 0


@pytest.mark.parametrize("n, edges, err", [
    (3, [[0, 3]], ValueError), (3, [[0, -1]], ValueError), (0, [[0, 1]], ValueError),
    (3.5, [[0, 1]], TypeError), (3, [[0, 1, 2]], ValueError), (3, [[0.5, 1]], TypeError),
    (3, np.zeros((0, 2), int), ValueError), (3, "01", TypeError)])
def test_bad_graphs(n, edges, err):
    with pytest.raises(err):
        sig.graph_laplacian(n, edges)


def test_bad_weights():
    with pytest.raises(ValueError, match="weights"):
        sig.graph_laplacian(3, [[0, 1]], weights=[-1.0])
    with pytest.raises(ValueError, match="weights"):
        sig.graph_laplacian(3, [[0, 1]], weights=[1.0, 2.0])
