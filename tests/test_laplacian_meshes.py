"""Every constructor on every real mesh: L symmetric PSD with L·1 = 0, B SPD, no NaN."""
import warnings

import numpy as np
import pytest
from conftest import MESH_DIR, read_shared_mesh

import spectral_igl as sig
from spectral_igl.linalg import factorize

MESHES = sorted(p.name for p in MESH_DIR.glob("*")) if MESH_DIR.is_dir() else ["absent"]
# components as the data README lists them (stanford-bunny: 1 surface + 1,113 unreferenced)
COMPONENTS = {"teapot.obj": 4, "suzanne.obj": 3, "beetle.obj": 2, "stanford-bunny.obj": 1 + 1113}


def _check(lap, expect_components=None):
    L, B = lap.L, lap.B
    n = lap.n
    assert np.all(np.isfinite(L.data)) and np.all(np.isfinite(B.data))
    scale = abs(L).max()
    assert abs(L - L.T).max() <= 1e-12 * scale
    assert np.abs(L @ np.ones(n)).max() <= 1e-10 * scale
    factorize(B)  # Cholesky succeeds: B is SPD
    # PSD: L + εB is positive definite for a tiny ε (a Cholesky factorization succeeds) ...
    eps = 1e-10 * scale / B.diagonal().max()
    factorize((L + eps * B).tocsc())
    # ... and the smallest nonzero eigenvalues are positive
    c = lap.n_components
    if c < 50:
        ev, _ = sig.eigs(lap, c + 2)
        assert np.all(ev[c:] > 0)
    if expect_components is not None:
        assert lap.n_components == expect_components


@pytest.mark.parametrize("name", MESHES)
def test_constructors_on_real_mesh(name):
    V, C = read_shared_mesh(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        if C.shape[1] == 4:
            _check(sig.laplacian(V, C))
            return
        big = len(V) > 20000
        _check(sig.laplacian(V, C), COMPONENTS.get(name))
        _check(sig.anisotropic_laplacian(V, C, alpha=0.5 * np.ptp(V, axis=0).max()),
               COMPONENTS.get(name))
        if not big:
            _check(sig.laplacian(V, C, weights="intrinsic_delaunay", mass="lumped"),
                   COMPONENTS.get(name))
            ref = np.zeros(len(V), bool)
            ref[C.ravel()] = True
            _check(sig.point_cloud_laplacian(V[ref], k=16))
            _check(sig.point_cloud_laplacian(V[ref], k=24, method="liu"))
