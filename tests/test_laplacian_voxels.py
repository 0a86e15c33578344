"""Voxel FD Laplacian: exact discrete Neumann spectrum, O(h²) convergence, masks."""
import numpy as np
import pytest

import spectral_igl as sig
from data_generators import box_eigenvalues, box_voxel_eigenvalues, box_voxels

SIZE = (1.0, 0.75, 0.5)


def test_box_spectrum_is_the_exact_discrete_one():
    shape = (10, 8, 6)
    mask, h = box_voxels(shape, SIZE)
    lap = sig.voxel_laplacian(mask, h)
    ev, _ = sig.eigs(lap, 20)
    exact = box_voxel_eigenvalues(20, shape, SIZE)
    assert np.allclose(ev, exact, rtol=1e-9, atol=1e-9)
    assert lap.area() == pytest.approx(np.prod(SIZE), rel=1e-14)


def test_box_converges_to_continuous_neumann_at_second_order():
    exact = box_eigenvalues(10, SIZE)
    errs = []
    for m in (1, 2, 4):
        mask, h = box_voxels((8 * m, 6 * m, 4 * m), SIZE)
        ev, _ = sig.eigs(sig.voxel_laplacian(mask, h), 10)
        errs.append(np.max(np.abs(ev - exact) / np.maximum(exact, 1)))
    rates = np.log2(np.array(errs[:-1]) / errs[1:])
    assert np.all(rates > 1.9), (errs, rates)


def test_dense_matches_discrete_formula_on_every_mode():
    shape, size = (4, 3, 2), (2.0, 1.5, 1.0)
    mask, h = box_voxels(shape, size)
    ev, X = sig.dense_eigs(sig.voxel_laplacian(mask, h))
    assert np.allclose(ev, box_voxel_eigenvalues(24, shape, size), atol=1e-12)


def test_mask_shapes_and_components():
    m = np.zeros((6, 6, 6), bool)
    m[:3, :3, :3] = True
    m[4:, 4:, 4:] = True  # touches the first block only at a corner
    m[0, 5, 5] = True
    lap = sig.voxel_laplacian(m, 0.5)
    assert lap.n == 27 + 8 + 1 and lap.n_components == 3
    assert np.abs(lap.L @ np.ones(lap.n)).max() == 0
    assert np.allclose(lap.data["V"][0], [0.25, 0.25, 0.25])
    # an L-shaped region: symmetric, PSD, one component
    m = np.zeros((8, 8, 2), bool)
    m[:, :3] = True
    m[:3, :] = True
    lap = sig.voxel_laplacian(m, (0.1, 0.2, 0.3))
    assert lap.n_components == 1 and abs(lap.L - lap.L.T).max() == 0
    ev, _ = sig.eigs(lap, 4)
    assert ev[0] == 0 and ev[1] > 0
    assert lap.B.diagonal()[0] == pytest.approx(0.1 * 0.2 * 0.3)


@pytest.mark.parametrize("bad, err", [
    (np.zeros((3, 3, 3), bool), ValueError), (np.ones((2, 2, 2, 2), bool), ValueError),
    (np.full((2, 2, 2), 0.5), TypeError), ("mask", TypeError), (None, TypeError)])
def test_bad_masks(bad, err):
    with pytest.raises(err, match="mask"):
        sig.voxel_laplacian(bad)


@pytest.mark.parametrize("spacing", [0.0, -1.0, np.nan, (1.0, 2.0), "x", (1, 1, -1)])
def test_bad_spacing(spacing):
    with pytest.raises((ValueError, TypeError), match="spacing"):
        sig.voxel_laplacian(np.ones((2, 2, 2), bool), spacing)
