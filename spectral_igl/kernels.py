r"""Spectral kernels :math:`K = \varphi(\tilde L) B^{-1}`, evaluated column by column.

The discrete kernel of a filter :math:`\varphi` is the symmetric matrix

.. math:: K = \varphi(\tilde L)\, B^{-1} = X \varphi(\Lambda) X^\top,

whose column ``i`` is :math:`\varphi(\tilde L)` applied to the discrete delta
:math:`B^{-1} e_i`; it converges to the smooth kernel :math:`K(p_i, \cdot)` under
refinement. Nothing here computes eigenpairs: every column is one application of the
spectral engine (:class:`spectral_igl.SpectralOperator`), with its certified error bound.
"""
from __future__ import annotations

import numbers

import numpy as np

from ._validate import as_delta, as_index, as_indices, as_positive, check_dense_size
from .approx import spectral_operator
from .diagonal.multiscale import heat_columns
from .filters import check_filter, heat
from .laplacian import Laplacian, as_laplacian

__all__ = ["spectral_kernel", "heat_kernel", "heat_kernels", "kernel_columns", "source_indices", "BLOCK",
           "block_sources", "MANY_SOURCES"]

#: columns per engine call; bounds the (n, block) work arrays
BLOCK = 64



def _unit_columns(n: int, idx: np.ndarray, weights=None) -> np.ndarray:
    E = np.zeros((n, idx.size))
    E[idx, np.arange(idx.size)] = 1.0 if weights is None else weights
    return E


def kernel_columns(lap, filt, idx, delta: str = "mass", method: str = "auto", tol: float = 1e-8,
                   op=None, return_bound: bool = False):
    r"""(n, m) columns ``idx`` of the kernel: :math:`\varphi(\tilde L)B^{-1}e_i` (``delta="mass"``)
    or :math:`\varphi(\tilde L)e_i` (``delta="seed"``), in blocks of :data:`BLOCK`.

    With ``return_bound`` also returns the (m,) certified B-norm error bound of each column.
    """
    n = lap.n
    idx = np.asarray(idx, dtype=np.int64).reshape(-1)
    check_dense_size(16.0 * n * idx.size, f"{idx.size} dense kernel columns of length {n}",
                     "ask for fewer sources at a time, or for distances/diagonals, which need no columns")
    op = spectral_operator(lap, filt, method, tol) if op is None else op
    dtype = np.complex128 if getattr(filt, "is_complex", False) else np.float64
    out = np.empty((n, idx.size), dtype=dtype)
    bound = np.zeros(idx.size)
    for a in range(0, idx.size, BLOCK):
        sl = slice(a, min(a + BLOCK, idx.size))
        E = _unit_columns(n, idx[sl])
        Y = op.apply_inverse_mass(E) if delta == "mass" else op.apply(E)
        out[:, sl] = Y
        bound[sl] = _as_bound(getattr(op, "error_bound", np.nan), sl.stop - sl.start)
    return (out, bound) if return_bound else out


def _as_bound(b, m: int) -> np.ndarray:
    b = np.asarray(b if b is not None else np.nan, dtype=float).reshape(-1)
    return np.broadcast_to(b, (m,)).copy() if b.size in (1, m) else np.full(m, np.nan)


def source_indices(sources, n: int):
    """(indices, scalar?) for a vertex index or a 1-D array of them."""
    if isinstance(sources, (numbers.Integral, np.integer)) and not isinstance(sources, (bool, np.bool_)):
        return np.array([as_index(sources, n, "source")]), True
    if isinstance(sources, np.ndarray) and sources.ndim == 0:
        return np.array([as_index(sources, n, "source")]), True
    return as_indices(sources, n, "sources"), False


# ---------------------------------------------------------------------------------------
# public API
# ---------------------------------------------------------------------------------------
def spectral_kernel(lap: Laplacian, filt, sources, delta: str = "mass", method: str = "auto",
                    tol: float = 1e-8):
    r"""Columns :math:`K(:, i)` of the spectral kernel :math:`K = \varphi(\tilde L)B^{-1}`.

    .. math:: K(:, i) = \varphi(\tilde L) B^{-1} e_i = \sum_l \varphi(\lambda_l)\, x_l(i)\, x_l

    computed spectrum-free (one application of the engine per column), never from
    truncated eigenpairs.

    Parameters
    ----------
    lap : Laplacian
    filt : spectral_igl.filters.Filter
        The filter :math:`\varphi` (``filters.heat(t)``, ``filters.biharmonic()``, ...).
        Singular filters act on the B-orthogonal complement of ker L.
    sources : int or (m,) int
        Vertex index, or indices, of the kernel's source points.
    delta : {"mass", "seed"}
        ``"mass"`` (default) uses the discrete delta :math:`B^{-1}e_i`, so that
        ``K[j, i]`` converges to :math:`K(p_j, p_i)` under refinement and ``K`` is
        symmetric. ``"seed"`` applies the filter to :math:`e_i` itself (the survey's
        Eq. (5) as printed): mesh dependent, offered for comparison only.
    method : str
        Approximation method of the engine (``"auto"``, ``"rational"``, ``"dense"``, ...).
    tol : float
        Target accuracy of the engine (B-norm, relative to the input).

    Returns
    -------
    K : (n,) float for a single source, (n, m) float for m sources (complex for a
        complex filter such as the wave kernel).

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> k = sig.spectral_kernel(lap, sig.filters.heat(0.1), 0)
    >>> k.shape
    (162,)
    """
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    delta = as_delta(delta)
    idx, scalar = source_indices(sources, lap.n)
    K = kernel_columns(lap, filt, idx, delta=delta, method=method, tol=tol)
    return K[:, 0] if scalar else K


def heat_kernel(lap: Laplacian, t: float, sources, delta: str = "mass", method: str = "auto",
                tol: float = 1e-8):
    r"""Columns of the heat kernel :math:`K_t = e^{-t\tilde L}B^{-1}`.

    .. math:: K_t(:, i) = e^{-t \tilde L} B^{-1} e_i = \sum_l e^{-t\lambda_l} x_l(i)\, x_l

    ``t`` is physical time (no normalisation). See :func:`spectral_kernel` for the
    parameters; returns (n,) for one source, (n, m) for m sources.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> K = sig.heat_kernel(lap, 0.05, [0, 1])
    >>> bool(np.allclose(K.T @ lap.B @ np.ones(lap.n), 1.0))  # heat is conserved
    True
    """
    t = as_positive(t, "t")
    lap = as_laplacian(lap)
    idx, scalar = source_indices(sources, lap.n)
    if block_sources(lap, method, as_delta(delta), idx.size):
        return heat_kernels(lap, [t], idx, tol=tol)[:, :, 0]
    return spectral_kernel(lap, heat(t), sources, delta=delta, method=method, tol=tol)


#: from this many sources on, ``method="auto"`` heat columns use the common-pole block solves
MANY_SOURCES = 8


def block_sources(lap, method, delta, m) -> bool:
    """Whether m heat columns go through one factorization per pole with all sources as one
    block: from :data:`MANY_SOURCES` sources on, above the dense limit (where factorizations,
    not solves, dominate the cost of the Krylov path)."""
    from .diagonal import EXACT_MAX
    from .linalg import ldlt

    return (method == "auto" and delta == "mass" and m >= MANY_SOURCES and lap.n > EXACT_MAX
            and ldlt.available())


def heat_kernels(lap: Laplacian, times, sources, tol: float = 1e-8, return_bound: bool = False):
    r"""Heat-kernel columns at many times and sources, sharing one set of poles.

    .. math:: K_t(:, i) = e^{-t\tilde L}B^{-1}e_i, \qquad
              \|K_t(:,i) - \tilde K_t(:,i)\|_B \le \varepsilon_t \|B^{-1}e_i\|_B

    One sparse factorization per common pole of the whole family of times
    (:func:`spectral_igl.diagonal.multiscale.heat_columns`), each solved with every source
    as one block right-hand side; adding a time costs a weighted sum.

    Parameters
    ----------
    lap : Laplacian
    times : (T,) float
        Positive times.
    sources : int or (m,) int
    tol : float
        Certified B-norm error of each column relative to :math:`\|B^{-1}e_i\|_B`.
    return_bound : bool
        Also return the (T,) certified :math:`\varepsilon_t`.

    Returns
    -------
    K : (n, T) float for one source, (n, m, T) float for m sources.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> K = sig.kernels.heat_kernels(lap, [0.01, 0.1], [0, 3])
    >>> K.shape, bool(np.allclose(K[:, 1, 1], sig.heat_kernel(lap, 0.1, 3)))
    ((162, 2, 2), True)
    """
    lap = as_laplacian(lap)
    idx, scalar = source_indices(sources, lap.n)
    K, eps = heat_columns(lap, times, idx, tol=tol)
    if scalar:
        K = K[:, 0, :]
    return (K, eps) if return_bound else K
