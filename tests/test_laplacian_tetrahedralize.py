"""tetrahedralize: a closed surface becomes a volume whose Laplacian has the right measure."""
import numpy as np
import pytest
from _needs import TET

import spectral_igl as sig

pytestmark = TET
from data_generators import icosphere, volume_from_surface


def _enclosed_volume(V, F):
    return float(np.einsum("ij,ij->i", V[F[:, 0]], np.cross(V[F[:, 1]], V[F[:, 2]])).sum() / 6)


def test_ball_volume_and_neumann_spectrum():
    V, F = icosphere(3)
    Vt, T = sig.tetrahedralize(V, F, edge_length_fac=0.1, optimize=False)
    lap = sig.laplacian(Vt, T)
    assert lap.domain == "tet" and lap.n_components == 1
    # fTetWild's envelope is 1e-3 of the bounding-box diagonal
    assert lap.area() == pytest.approx(_enclosed_volume(V, F), rel=5e-3)
    assert lap.area() == pytest.approx(4 * np.pi / 3, rel=0.015)
    assert np.all(np.unique(T) == np.arange(len(Vt)))
    # first nonzero Neumann eigenvalue of the unit ball, (first root of j1')² = 2.0815759…²;
    # about 2-3% high on this coarse mesh (n ≈ 900, FEM errors are positive)
    ev, _ = sig.eigs(lap, 4)
    assert np.allclose(ev[1:], 2.0815759778671 ** 2, rtol=0.04)


def test_generator_and_validation():
    V, F = icosphere(2)
    Vt, T = volume_from_surface(V, F, edge_length_fac=0.2, optimize=False)
    assert T.shape[1] == 4 and Vt.shape[1] == 3
    with pytest.raises(ValueError, match="F"):
        sig.tetrahedralize(V, F + len(V))
    with pytest.raises(ValueError, match="edge_length_fac"):
        sig.tetrahedralize(V, F, edge_length_fac=2.0)
    with pytest.raises(ValueError, match="V"):
        sig.tetrahedralize(V * np.nan, F)


def test_a_surface_ftetwild_cannot_finish_is_refused_after_the_timeout(tmp_path, monkeypatch):
    """fTetWild runs without end on some self-intersecting surfaces (faces of a sphere
    pointing at shifted vertices); it runs in a child process, so that ends in a ValueError
    and leaves the caller's working directory alone."""
    import time

    from data_generators import icosphere

    V, F = icosphere(2)
    bad = np.r_[np.ones((3, 3)), V]          # F now points at the wrong vertices
    monkeypatch.chdir(tmp_path)
    start = time.perf_counter()
    with pytest.raises(ValueError, match="did not finish in 3 s"):
        sig.tetrahedralize(bad, F, edge_length_fac=0.2, timeout=3)
    assert time.perf_counter() - start < 30
    assert list(tmp_path.iterdir()) == []    # no scratch file left in the working directory
    Vt, T = sig.tetrahedralize(V, F, edge_length_fac=0.2, timeout=120)
    assert T.shape[1] == 4 and np.all(np.isfinite(Vt))
