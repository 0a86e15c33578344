"""Finite-difference Laplacian on a voxel mask (Neumann on the mask's boundary)."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .._validate import as_array, as_positive, check_dense_size, describe
from ._operator import Laplacian, make_laplacian

__all__ = ["voxel_laplacian"]


def _as_spacing(spacing) -> np.ndarray:
    if np.ndim(spacing) == 0:
        h = as_positive(spacing, "spacing")
        return np.full(3, h)
    s = as_array(spacing, "spacing")
    if s.shape != (3,) or s.dtype.kind not in "iuf":
        raise ValueError(f"spacing must be a positive number or 3 positive numbers, got {describe(s)}")
    return np.array([as_positive(x, f"spacing[{a}]") for a, x in enumerate(s.tolist())])


def _check_grid(nbytes: float, shape) -> None:
    check_dense_size(nbytes, f"the voxel Laplacian of a grid of shape {shape}",
                     "crop the mask to the shape's bounding box or coarsen the grid")


def voxel_laplacian(mask, spacing=1.0) -> Laplacian:
    r"""7-point finite-difference Laplacian on the True voxels of a 3-D mask.

    One unknown per True voxel (C order of ``np.flatnonzero(mask)``). Face neighbours
    along axis :math:`a` are coupled with weight :math:`V/h_a^2`, :math:`V = h_x h_y h_z`
    the voxel volume; a missing neighbour is simply omitted, which is the homogeneous
    Neumann condition on the mask's boundary (the flux through that face is zero).

    .. math:: (B^{-1}L f)_i = \sum_{a}\sum_{j \sim_a i} \frac{f_i - f_j}{h_a^2}, \qquad B = V\,I

    On a full box of :math:`N_a` voxels per axis the eigenvalues are exactly
    :math:`\sum_a (4/h_a^2)\sin^2(\pi i_a/(2N_a))`, converging at O(h²) to the continuous
    Neumann spectrum :math:`\pi^2\sum_a i_a^2/\ell_a^2`.

    Parameters
    ----------
    mask : (nx, ny, nz) bool
        Voxel occupancy (0/1 integers are accepted). A 2-D mask is read as one layer.
    spacing : float or (3,) float
        Voxel size ``h`` or ``(hx, hy, hz)``.

    Returns
    -------
    Laplacian
        ``domain="voxels"``, ``B`` diagonal; ``data`` has ``mask``, ``spacing``, ``index``
        (the voxel index of each unknown, ``(n, 3)`` int) and ``V`` (voxel centres, ``(n, 3)``).
        Voxels touching only by an edge or corner are separate components.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> lap = sig.voxel_laplacian(np.ones((4, 3, 2), bool), spacing=0.5)
    >>> lap.n, round(lap.area(), 6)
    (24, 3.0)
    """
    m = as_array(mask, "mask")
    # an int64 voxel number per grid cell and boolean temporaries (then, per True voxel,
    # its six face couplings and coordinates: checked below)
    _check_grid(10.0 * m.size, m.shape)
    if m.dtype.kind == "b":
        pass
    elif m.dtype.kind in "iu" and np.all((m == 0) | (m == 1)):
        m = m.astype(bool)
    else:
        raise TypeError(f"mask must be a boolean array, got {describe(m)}")
    if m.ndim == 2:
        m = m[:, :, None]
    if m.ndim != 3:
        raise ValueError(f"mask must have shape (nx, ny, nz), got {describe(m)}")
    h = _as_spacing(spacing)
    n = int(m.sum())
    if n == 0:
        raise ValueError(f"mask has no True voxel ({describe(m)})")
    _check_grid(10.0 * m.size + 200.0 * n, m.shape)
    number = np.full(m.shape, -1, dtype=np.int64)
    number[m] = np.arange(n)
    vol = float(np.prod(h))
    rows, cols, vals = [], [], []
    for a in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[a] = slice(0, -1)
        hi[a] = slice(1, None)
        u, v = number[tuple(lo)], number[tuple(hi)]
        both = (u >= 0) & (v >= 0)
        u, v = u[both], v[both]
        rows += [u, v]
        cols += [v, u]
        vals.append(np.full(2 * u.size, -vol / h[a] ** 2))
    if rows:
        r, c, w = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
    else:
        r = c = np.zeros(0, np.int64)
        w = np.zeros(0)
    W = sp.csr_matrix((w, (r, c)), shape=(n, n))
    L = W - sp.diags(np.asarray(W.sum(axis=1)).ravel())
    idx = np.argwhere(m)
    data = {"mask": m, "spacing": h, "index": idx, "V": (idx + 0.5) * h}
    return make_laplacian(L, vol * sp.eye(n, format="csr"), domain="voxels", data=data,
                          adjacency=sp.csr_matrix((np.ones(r.size), (r, c)), shape=(n, n)))
