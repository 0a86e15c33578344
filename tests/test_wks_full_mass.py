"""The selected inverse on the factor's pattern, and the WKS normaliser with a full mass matrix
it proves, against dense inverses and dense generalized eigendecompositions."""
import numpy as np
import pytest
from _spectral_truth import strip

import spectral_igl as sig
from data_generators import box_tets, icosphere
from spectral_igl.linalg import ldlt

pytestmark = pytest.mark.skipif(not ldlt.available(), reason="compiled LDLT not built")


def _meshes():
    """A closed surface (small fronts), a surface with boundary, a tetrahedral box (fronts of
    a few hundred), all with the full (consistent) mass matrix."""
    return {"sphere642": sig.laplacian(*icosphere(3), mass="full"),
            "strip_boundary": sig.laplacian(*strip(30, 10), mass="full"),
            "box_tets": sig.laplacian(*box_tets((7, 7, 7)), mass="full")}


@pytest.fixture(scope="module")
def meshes():
    return _meshes()


@pytest.mark.parametrize("min_work", [0.0, 1e30])
@pytest.mark.parametrize("shift", [-0.7, 0.7 + 2.0j])
def test_selected_inverse_is_the_dense_inverse_on_the_pattern(meshes, shift, min_work):
    """Every entry of A^-1 on the pattern of A (both triangles), through the BLAS blocks
    (min_work 0) and the loops (1e30), real and complex symmetric; its diagonal is the
    selected inversion's bit for bit, and tr(A^-1 B) the dense one."""
    ext = ldlt._ext()
    old = ext.set_blas_min_work(min_work)
    try:
        for name, lap in meshes.items():
            dtype = complex if isinstance(shift, complex) else float
            A = (lap.L.astype(dtype) - shift * lap.B.astype(dtype)).tocsc()
            f = ldlt.LDLT(A)
            Z = f.selected_inverse()
            dense = np.linalg.inv(A.toarray())
            scale = np.abs(dense).max()
            C = Z.tocoo()
            assert Z.nnz == f.pattern.indices.size, name
            err = np.abs(C.data - dense[C.row, C.col]).max()
            assert err <= 1e-12 * scale, (name, err / scale)
            assert np.array_equal(Z.diagonal(), f.inverse_diagonal()), name
            tr = np.dot(Z.data, f.pattern.values(lap.B))
            ref = np.trace(dense @ lap.B.toarray())
            assert abs(tr - ref) <= 1e-12 * abs(ref), (name, abs(tr - ref) / abs(ref))
    finally:
        ext.set_blas_min_work(old)


def _dense_psi(lap, E, sigma):
    lam, X = sig.dense_eigs(lap)
    c = lap.n_components
    ls = np.log(np.maximum(lam[c:], 1e-300))
    psi = np.exp(-((np.asarray(E)[None] - ls[:, None]) ** 2) / (2 * sigma ** 2))
    return psi, X[:, c:]


@pytest.mark.parametrize("name", ["sphere642", "strip_boundary", "box_tets"])
def test_wks_full_mass_normaliser_is_proved_against_the_dense_spectrum(meshes, name):
    """tr psi(L~) = sum_l psi(lambda_l) from the selected inverses, within its bound; the
    signature entry by entry within its bound, one energy at a time ("auto") and with common
    poles ("selinv"); every bound a proof."""
    from spectral_igl.descriptors import _wks_filter, _wks_trace

    lap = meshes[name]
    lam = sig.dense_eigs(lap)[0]
    sigma = 0.4
    E = np.log(lam[[len(lam) // 8, len(lam) // 4, len(lam) // 2]])
    psi, X = _dense_psi(lap, E, sigma)
    ref_tr = psi.sum(axis=0)
    ref = (X ** 2) @ psi / ref_tr
    for j, e in enumerate(E):
        f = _wks_filter(float(e), sigma)
        tr, bound, kind, note = _wks_trace(lap, f, None, None, None, 1e-8)
        assert kind == "proof" and note is None
        assert abs(tr - ref_tr[j]) <= bound, (name, j, abs(tr - ref_tr[j]), bound)
        assert bound <= 1e-5 * ref_tr[j]          # a useful bound, not a vacuous one
    for method in ("auto", "selinv"):              # one energy at a time; common poles
        W, info = sig.wks(lap, E, sigma=sigma, method=method, return_info=True)
        # "auto" takes the dense diagonal (an estimate) where the one-filter fit has a real pole
        # between 0 and lambda_2 (sphere642 at the second energy); the normaliser is proved
        assert "normaliser" not in info.get("note", ""), (name, method, info["note"])
        if method == "selinv":
            assert info["bound_kind"] == "proof" and "note" not in info, (name, info.get("note"))
        err = np.abs(W - ref)
        assert np.all(err <= info["abs_error"]), (name, method, float(np.max(err - info["abs_error"])))
        assert info["abs_error"].max() <= 1e-5 * ref.max()


def test_wks_full_mass_family_traces_match_the_single_energy_ones(meshes):
    """The common-pole pass gives each energy's trace within its bound of the dense sum."""
    from spectral_igl.descriptors import _wks_filter
    from spectral_igl.families import family_diagonals

    lap = meshes["sphere642"]
    lam = sig.dense_eigs(lap)[0]
    E = np.linspace(np.log(lam[3]), np.log(lam[-30]), 6)
    sigma = 0.3
    psi, _ = _dense_psi(lap, E, sigma)
    md = family_diagonals(lap, [_wks_filter(float(e), sigma) for e in E], 1e-9, scales=np.exp(E))
    assert md.trace is not None and md.bound_kind == "proof"
    err = np.abs(md.trace - psi.sum(axis=0))
    assert np.all(err <= md.trace_bound), err / md.trace_bound
    assert lap.n * md.eps.max() < 1e-5


def test_the_trace_is_refused_with_a_lumped_mass():
    from spectral_igl.diagonal import NoSelinv, selinv_kernel
    from spectral_igl.descriptors import _wks_filter

    lap = sig.laplacian(*icosphere(2))
    with pytest.raises(NoSelinv, match="lumped"):
        selinv_kernel(lap, _wks_filter(3.0, 0.5), 1e-8).trace()
