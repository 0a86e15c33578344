"""Krylov--Schur and multi-resolution prolongation as inner solvers of ``eigs``: certified like the
Lanczos path, checked against dense eigendecompositions and analytic multiplicities."""
import numpy as np
import pytest

import spectral_igl as sig
from spectral_igl.data_generators import flat_torus_eigenvalues, flat_torus_laplacian, icosphere


def clusters(ev, gap):
    """Sizes of the groups of sorted values closer than ``gap`` to their neighbour."""
    cuts = np.flatnonzero(np.diff(ev) > gap) + 1
    return np.diff(np.r_[0, cuts, ev.size]).tolist()


@pytest.fixture(scope="module")
def sphere():
    lap = sig.laplacian(*icosphere(3))
    return lap, sig.dense_eigs(lap, k=30)[0]


@pytest.mark.parametrize("method", ["krylov_schur", "multires"])
def test_sphere_spectrum_certified_with_its_multiplicities(sphere, method):
    lap, dense = sphere
    ev, X, info = sig.eigs(lap, 25, method=method, return_info=True)
    assert info["bound_kind"] == "proof" and info["method"] == method
    assert info["first_search"] == method          # 1,280 faces: multires coarsens
    assert np.all(np.abs(ev - dense[:25]) <= info["abs_error"] + 1e-12 * dense[24])
    assert np.abs(X.T @ (lap.B @ X) - np.eye(25)).max() < 1e-10
    # unit sphere: l(l+1) with multiplicity 2l+1 (this mesh is within 3% of it)
    assert clusters(ev, 0.5) == [1, 3, 5, 7, 9]
    assert np.allclose(ev[[1, 4, 9, 16]], [2, 6, 12, 20], rtol=0.03)


def test_flat_torus_fourfold_eigenvalues_by_krylov_schur():
    lap = flat_torus_laplacian(nu=24, nv=24)
    dense = sig.dense_eigs(lap, k=21)[0]
    ev, _, info = sig.eigs(lap, 21, method="krylov_schur", return_info=True)
    # the count agrees; the kind is "estimate" on every path here, since lambda_max of this
    # intrinsic-length operator (which scales the residual bounds) is not proved
    assert info["count_certified"] and info["count"] >= 21
    assert np.all(np.abs(ev - dense) <= info["abs_error"] + 1e-12 * dense[-1])
    # 4 pi^2 (i^2 + j^2), each fourfold (the diagonals of the triangulation split (1, 1) in 2 + 2)
    assert clusters(ev, 0.5) == [1, 4, 2, 2, 4, 4, 4]
    assert np.allclose(ev[1:13], flat_torus_eigenvalues(13)[1:13], rtol=0.03)


def test_multires_falls_back_where_there_is_no_mesh_to_coarsen():
    lap = flat_torus_laplacian(nu=16, nv=16)           # intrinsic lengths only, no vertices
    ev, _, info = sig.eigs(lap, 9, method="multires", return_info=True)
    assert info["first_search"] == "lanczos" and info["count_certified"]
    assert np.all(np.abs(ev - sig.dense_eigs(lap, k=9)[0]) <= info["abs_error"] + 1e-10)


def test_methods_agree_within_their_proved_enclosures():
    lap = sig.laplacian(*icosphere(4))                 # 2,562 vertices, no dense truth needed
    out = {m: sig.eigs(lap, 40, method=m, return_info=True) for m in sig.linalg.EIG_METHODS}
    ref, _, ref_info = out["lanczos"]
    for m, (ev, _, info) in out.items():
        assert info["bound_kind"] == "proof"
        assert np.all(np.abs(ev - ref) <= info["abs_error"] + ref_info["abs_error"])


def test_unknown_method_is_refused(sphere):
    with pytest.raises(ValueError, match="method must be one of"):
        sig.eigs(sphere[0], 5, method="arnoldi")
