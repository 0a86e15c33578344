"""Diffusion basis functions and feature points (survey §7.2)."""
from __future__ import annotations

import numbers

import numpy as np

from .._validate import as_indices, as_positive, describe
from .harmonic import _check_lap

__all__ = ["diffusion_basis", "feature_points", "auto_diffusion", "graph_extrema"]


def diffusion_basis(lap, t, centers, method: str = "auto", tol: float = 1e-8):
    r"""Heat-kernel basis functions centred at ``centers``: columns :math:`K_t(\cdot, p_i)`.

    .. math:: \psi_i = K_t e_i = e^{-t\tilde L} B^{-1} e_i

    Parameters
    ----------
    lap : Laplacian
    t : float
        Diffusion time, > 0: the support radius grows like :math:`\sqrt{t}`.
    centers : (k,) int
        Vertex indices.
    method, tol
        Passed to :class:`spectral_igl.SpectralOperator`.

    Returns
    -------
    (n, k) float
        Smooth, intrinsic bumps; each column integrates to 1 (:math:`1^\top B \psi_i = 1`).
    """
    from .. import SpectralOperator, filters

    lap = _check_lap(lap)
    t = as_positive(t, "t")
    centers = as_indices(centers, lap.n, "centers")
    E = np.zeros((lap.n, centers.size))
    E[centers, np.arange(centers.size)] = 1.0
    op = SpectralOperator(lap, filters.heat(t), method=method, tol=tol)
    return np.real(op.apply_inverse_mass(E))


def graph_extrema(lap, f):
    """Local minima and maxima of ``f`` over the neighbourhoods of the graph of ``lap.L``.

    Ties are broken by the vertex index, as in :func:`critical_points`; for a triangle
    mesh the result equals the minima and maxima of the lower-link test. Returns
    ``(minima, maxima)`` index arrays.
    """
    lap = _check_lap(lap)
    f = np.asarray(f, dtype=float)
    n = lap.n
    rank = np.empty(n, dtype=np.int64)
    rank[np.lexsort((np.arange(n), f))] = np.arange(n)
    A = lap.L.tocoo()
    off = A.row != A.col
    i, j = A.row[off], A.col[off]
    lower = rank[j] < rank[i]
    n_lower = np.bincount(i, weights=lower, minlength=n)
    n_nb = np.bincount(i, minlength=n)
    has = n_nb > 0
    return np.flatnonzero(has & (n_lower == 0)), np.flatnonzero(has & (n_lower == n_nb))


def auto_diffusion(lap, t, k: int = 200):
    r"""Auto-diffusion function :math:`K_t(x, x)` (Gębal et al. 2009) from ``k`` eigenpairs.

    .. math:: \mathrm{ADF}_t(x) = \sum_i e^{-\lambda_i t} x_i(x)^2

    The truncation error is at most :math:`e^{-\lambda_{k} t}` times the remaining
    diagonal, small once :math:`\lambda_k t \gg 1`.
    """
    from ..laplacian import eigs

    lap = _check_lap(lap)
    t = as_positive(t, "t")
    k = int(min(k, lap.n - 1))
    lam, X = eigs(lap, k)
    return (X ** 2) @ np.exp(-np.asarray(lam) * t)


def feature_points(lap, n_eigenfunctions: int = 6, t=None, source: str = "eigenfunctions"):
    r"""Feature points: extrema of the first eigenfunctions or of the auto-diffusion function.

    Parameters
    ----------
    lap : Laplacian
    n_eigenfunctions : int, default 6
        With ``source="eigenfunctions"``: how many non-constant eigenfunctions
        :math:`x_2, x_3, \ldots` (Ruggeri et al. 2010) to take extrema of.
    t : float, optional
        With ``source="adf"``: the diffusion time; default :math:`0.1/\lambda_2`
        (a scale at which the protrusions of the shape stand out).
    source : {"eigenfunctions", "adf"}

    Returns
    -------
    (p,) int
        Sorted, distinct vertex indices: the minima and maxima of each eigenfunction
        (``"eigenfunctions"``) or the maxima of the auto-diffusion function (``"adf"``,
        tips of protrusions).
    """
    from ..laplacian import eigs

    lap = _check_lap(lap)
    if source not in ("eigenfunctions", "adf"):
        raise ValueError(f"source must be 'eigenfunctions' or 'adf', got {source!r}")
    if isinstance(n_eigenfunctions, bool) or not isinstance(n_eigenfunctions, numbers.Integral) \
            or n_eigenfunctions < 1:
        raise ValueError(f"n_eigenfunctions must be a positive integer, got {describe(n_eigenfunctions)}")
    c = lap.n_components
    if source == "eigenfunctions":
        lam, X = eigs(lap, c + int(n_eigenfunctions))
        pts = []
        for j in range(c, X.shape[1]):
            mn, mx = graph_extrema(lap, X[:, j])
            pts += [mn, mx]
        return np.unique(np.concatenate(pts))
    if t is None:
        lam = eigs(lap, c + 1)[0]
        t = 0.1 / float(lam[c])
    adf = auto_diffusion(lap, t)
    return graph_extrema(lap, adf)[1]
