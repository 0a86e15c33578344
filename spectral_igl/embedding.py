r"""Spectral embedding: points mapped to filtered eigenfunction coordinates."""
from __future__ import annotations

import numbers

import numpy as np

from .accuracy import info as bound_info
from ._validate import as_flag, check_finite_result
from .diagonal import phi_values
from .filters import check_filter
from .laplacian import as_laplacian
from .linalg import dense_eigs, eigs

__all__ = ["spectral_embedding"]


def spectral_embedding(lap, filt, k: int, return_info: bool = False):
    r"""The spectral embedding :math:`x \mapsto (\varphi(\lambda_l)\, x_l(x))_{l}` with ``k``
    eigenpairs.

    Parameters
    ----------
    lap : Laplacian or mesh
    filt : Filter
        :math:`\varphi`.
    k : int
        Number of non-zero eigenpairs, ``1 <= k <= n - c``.
    return_info : bool
        Also return ``info`` (:mod:`spectral_igl.accuracy`): ``abs_error`` is ``nan`` and
        ``bound_kind`` ``None``. No per-entry bound is derivable: an eigenvector is defined only
        up to its sign, and within a repeated eigenvalue (the sphere's, any symmetric shape's)
        up to a rotation of the eigenspace, so the entries themselves are not determined by
        (L, B); the eigenpairs come from Lanczos or a dense solver without a certificate
        (``note``). ``method`` is ``"lanczos"`` or ``"dense"``.

    Returns
    -------
    E : (n, k) float
        One row per vertex (complex for a complex filter).
    info : dict
        Only with ``return_info=True``.

    Notes
    -----
    .. math:: \mathcal E(i) = \big(\varphi(\lambda_l)\, x_l(i)\big)_{l = c+1}^{c+k}

    Euclidean distances between rows approximate the spectral distance,
    :math:`\|\mathcal E(i) - \mathcal E(j)\| \to d(i, j)` as ``k`` grows (the omitted
    tail is the truncation error; :func:`spectral_igl.spectral_distance` has none).
    The kernel directions (one constant per connected component) are left out: they
    do not change distances within a component. This function is eigen-based by
    definition.

    Examples
    --------
    With every non-zero eigenpair the rows are exactly as far apart as the spectral distance:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(1))
    >>> E = sig.spectral_embedding(lap, sig.filters.biharmonic(), k=lap.n - 1)
    >>> d = sig.biharmonic_distance(lap, 0, 5)
    >>> bool(abs(np.linalg.norm(E[0] - E[5]) - d) < 1e-8 * d)
    True
    """
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    return_info = as_flag(return_info, "return_info")
    if isinstance(k, bool) or not isinstance(k, numbers.Integral):
        raise TypeError(f"k must be an integer, got {type(k).__name__}")
    c, n = lap.n_components, lap.n
    if not 1 <= k <= n - c:
        raise ValueError(f"k must be in [1, {n - c}], got {k}")
    dense = c + k >= n
    lam, X = dense_eigs(lap) if dense else eigs(lap, c + k)
    ph = phi_values(filt, lam, c)
    check_finite_result(ph[c:c + k], f"{filt!r} at the {k} eigenvalues", "check the filter's parameters")
    out = (X * ph[None, :])[:, c:c + k]
    if not return_info:
        return out
    return out, bound_info(np.full(out.shape, np.nan), None, "dense" if dense else "lanczos",
                              note="eigenvectors are defined up to sign (and a rotation within a "
                                   "repeated eigenvalue) and are not certified: no per-entry bound")
