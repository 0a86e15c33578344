"""Fast assembly paths give exactly what the straightforward sparse formulas give."""
import numpy as np
import pytest
import scipy.sparse as sp

from data_generators import icosphere
from spectral_igl.laplacian._operator import _symmetrize, _zero_row_sums
from spectral_igl.laplacian.mesh import (
    element_measures,
    full_mass,
    mesh_components,
    star_adjacency,
)


def _reference_zero_row_sums(L):
    off = L - sp.diags(L.diagonal())
    out = (off - sp.diags(np.asarray(off.sum(axis=1)).ravel())).tocsr()
    out.sort_indices()
    return out


def _same(A, B):
    return (A.shape == B.shape and np.array_equal(A.indptr, B.indptr)
            and np.array_equal(A.indices, B.indices) and np.array_equal(A.data, B.data))


@pytest.mark.parametrize("diag", ["all", "none", "some", "zero_row"])
def test_zero_row_sums_matches_sparse_formula(diag):
    rng = np.random.default_rng(3)
    n = 60
    A = sp.random(n, n, density=0.1, random_state=rng, format="csr")
    A = A + A.T
    A.setdiag(0)
    A.eliminate_zeros()
    if diag == "all":
        A = A + sp.diags(rng.uniform(1, 2, n))
    elif diag == "some":
        A = A + sp.diags(np.where(np.arange(n) % 2 == 0, 1.0, 0.0))
    elif diag == "zero_row":
        A = A.tolil()
        A[5, :] = 0
        A[:, 5] = 0
        A = A.tocsr()
    A = _symmetrize(A)
    assert _same(_zero_row_sums(A), _reference_zero_row_sums(A))


def test_full_mass_and_star_components():
    V, F = icosphere(2)
    n = len(V)
    B = full_mass(V, F)
    ref = sp.csr_matrix((n, n))
    meas = element_measures(V, F)
    for a in range(3):
        for b in range(3):
            ref = ref + sp.csr_matrix((meas * (2.0 if a == b else 1.0) / 12.0, (F[:, a], F[:, b])), shape=(n, n))
    assert abs(B - ref).max() <= 1e-15 * abs(ref).max()
    assert B.sum() == pytest.approx(meas.sum(), rel=1e-14)
    from scipy.sparse.csgraph import connected_components
    F2 = np.vstack([F, F[:5] + n])  # a second component sharing no vertex
    V2 = np.vstack([V, V])
    c1 = connected_components(mesh_components(2 * n, F2), directed=False)
    c2 = connected_components(star_adjacency(2 * n, F2), directed=False)
    assert c1[0] == c2[0] and np.array_equal(c1[1], c2[1])
    assert V2.shape[0] == 2 * n
