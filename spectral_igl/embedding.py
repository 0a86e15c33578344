r"""Spectral embedding: points mapped to filtered eigenfunction coordinates."""
from __future__ import annotations

import numbers

from ._validate import check_finite_result
from .diagonal import phi_values
from .filters import check_filter
from .laplacian import as_laplacian
from .linalg import dense_eigs, eigs

__all__ = ["spectral_embedding"]


def spectral_embedding(lap, filt, k: int):
    r"""The spectral embedding :math:`x \mapsto (\varphi(\lambda_l)\, x_l(x))_{l}` with ``k``
    eigenpairs.

    .. math:: \mathcal E(i) = \big(\varphi(\lambda_l)\, x_l(i)\big)_{l = c+1}^{c+k}

    Euclidean distances between rows approximate the spectral distance,
    :math:`\|\mathcal E(i) - \mathcal E(j)\| \to d(i, j)` as ``k`` grows (the omitted
    tail is the truncation error; :func:`spectral_igl.spectral_distance` has none).
    The kernel directions (one constant per connected component) are left out: they
    do not change distances within a component. This function is eigen-based by
    definition.

    Parameters
    ----------
    lap : Laplacian
    filt : Filter
    k : int
        Number of non-zero eigenpairs, ``1 <= k <= n - c``.

    Returns
    -------
    (n, k) float (complex for a complex filter)
    """
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    if isinstance(k, bool) or not isinstance(k, numbers.Integral):
        raise TypeError(f"k must be an integer, got {type(k).__name__}")
    c, n = lap.n_components, lap.n
    if not 1 <= k <= n - c:
        raise ValueError(f"k must be in [1, {n - c}], got {k}")
    lam, X = eigs(lap, c + k) if c + k < n else dense_eigs(lap)
    ph = phi_values(filt, lam, c)
    check_finite_result(ph[c:c + k], f"{filt!r} at the {k} eigenvalues", "check the filter's parameters")
    return (X * ph[None, :])[:, c:c + k]
