"""Generalized eigenpairs L x = λ B x: the truncated-spectrum baseline and dense ground truth."""
from __future__ import annotations

import numbers

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from .._validate import as_int, as_tol, check_dense_size, describe
from ..laplacian import Laplacian, as_laplacian, lambda_max
from ..progress import progress_bar
from . import ldlt
from .factor import factorize

__all__ = ["eigs", "dense_eigs", "cached_eigs", "lambda_min_positive", "lambda_min_positive_kind",
           "negative_inertia"]


def eigs(lap: Laplacian, k: int, tol: float = 0.0, backend: str = "auto", progress=None):
    r"""The ``k`` smallest generalized eigenpairs :math:`L x = \lambda B x`.

    Shift-invert Lanczos (ARPACK) in the B-inner product, with ker L deflated exactly:
    the first ``lap.n_components`` pairs are :math:`\lambda = 0` with the B-normalised
    indicator of each connected component, and Lanczos runs on the B-orthogonal
    complement, so shapes with many components (or isolated vertices) lose no
    multiplicity.

    Parameters
    ----------
    lap : Laplacian
    k : int
        Number of eigenpairs, ``1 <= k < n``.
    tol : float
        ARPACK relative tolerance (0 = machine precision).
    backend : str
        Sparse factorization of the shift, see :func:`spectral_igl.linalg.shifted_factor`.
    progress : bool, optional
        A progress counter on stderr: the shift's factorization, then one step per
        solve of the Lanczos iteration, whose number is not known in advance (see
        :mod:`spectral_igl.progress`; default off).

    Returns
    -------
    evals : (k,) float, ascending, ``evals[:c] == 0``
    evecs : (n, k) float, :math:`X^\top B X = I`
    """
    lap = as_laplacian(lap)
    n, c = lap.n, lap.n_components
    if isinstance(k, bool) or not isinstance(k, numbers.Integral):
        raise TypeError(f"k must be an integer, got {describe(k)}")
    k = int(k)
    if not 1 <= k < n:
        raise ValueError(f"k must be in [1, {n - 1}] for n = {n}, got {k}")
    tol = as_tol(tol, "tol", allow_zero=True)
    # the (n, k) eigenvectors and ARPACK's (n, ncv) Lanczos basis, ncv about 2k
    check_dense_size(8.0 * n * (3 * k + 32), f"{k} eigenvectors of length {n} (with the Lanczos basis)",
                     "ask for fewer pairs, or use the spectrum-free engine (apply_filter, "
                     "kernel_diagonal) that needs no eigenvectors")
    Z = lap.component_basis()  # sparse (n, c), B-orthonormal basis of ker L
    if k <= c:
        return np.zeros(k), Z[:, :k].toarray()
    m = k - c
    if m >= n - c - 1 or n - c <= 3:  # ARPACK needs ncv < n - c: too few modes left
        return dense_eigs(lap, k=k)
    B = lap.B
    # shift: any s > 0 keeps L + sB positive definite; kernel directions are projected out
    s = 1e-3 * float(lap.L.diagonal().sum() / B.diagonal().sum()) / max(n, 1) ** 0.5
    bar = progress_bar(None, f"eigs k={k}", progress, unit="solve")
    bar.set_postfix_str("factorization")
    fac = factorize(lap.L + s * B, backend=backend)
    bar.set_postfix_str("Lanczos")

    def project(y):
        return y - Z @ (Z.T @ (B @ y))

    def op(x):  # (L + sB)^{-1} x restricted to the complement of ker L; x = B v in mode 3
        x = x - B @ (Z @ (Z.T @ x))
        bar.update()
        return project(fac.solve(x))

    Op = spla.LinearOperator((n, n), matvec=op, dtype=np.float64)
    v0 = project(np.random.default_rng(0).standard_normal(n))
    ncv = min(n - c - 1, max(2 * m + 1, m + 32))
    vals, vecs = spla.eigsh(lap.L, k=m, M=B, sigma=-s, which="LM", OPinv=Op, v0=v0, tol=tol, ncv=ncv)
    bar.close()
    order = np.argsort(vals)
    vals, vecs = np.maximum(vals[order], 0.0), vecs[:, order]
    Zd = Z.toarray()
    return np.concatenate([np.zeros(c), vals]), np.hstack([Zd, vecs])


def dense_eigs(lap: Laplacian, k: int | None = None, max_n: int = 8000):
    r"""All (or the first ``k``) generalized eigenpairs by a dense solver: the ground truth.

    ``scipy.linalg.eigh(L, B)``; the kernel is replaced by the exact B-normalised
    component indicators. Refuses ``n > max_n`` (memory and time grow as n² and n³).

    Returns
    -------
    evals : (k,) float ascending; evecs : (n, k) float with :math:`X^\top B X = I`
    """
    lap = as_laplacian(lap)
    n, c = lap.n, lap.n_components
    max_n = as_int(max_n, "max_n", lo=1)
    if n > max_n:
        raise ValueError(f"dense_eigs is for small meshes: n = {n} > max_n = {max_n}; use eigs(lap, k)")
    k = n if k is None else as_int(k, "k", lo=1, hi=n)
    check_dense_size(6 * 8.0 * n * n, f"a dense ({n}, {n}) generalized eigenproblem",
                     "use eigs(lap, k) for the k smallest pairs")
    Z = lap.component_basis().toarray()
    # eigenproblem on the complement of ker L, then prepend the exact kernel
    Lf, Bf = lap.L.toarray(), lap.B.toarray()
    evals, X = sla.eigh(Lf, Bf, driver="gvd")
    X = X[:, c:]
    X = X - Z @ (Z.T @ (Bf @ X))
    # re-orthonormalise in B after the projection (Cholesky of the Gram matrix)
    G = X.T @ Bf @ X
    R = np.linalg.cholesky((G + G.T) / 2)
    X = np.linalg.solve(R, X.T).T
    vals = np.concatenate([np.zeros(c), np.maximum(evals[c:], 0.0)])
    vecs = np.hstack([Z, X])
    return vals[:k], vecs[:, :k]


def cached_eigs(lap: Laplacian, k: int | None = None):
    """:func:`eigs` (``k`` pairs) or :func:`dense_eigs` (``k=None``: all of them), cached on ``lap``.

    ``k >= n - 1`` is answered densely too (Lanczos cannot give that many).
    """
    lap = as_laplacian(lap)
    if k is None or k >= lap.n - 1:
        return lap.cache.fetch("eigen", "dense" if k is None else k,
                               lambda: dense_eigs(lap, k if k is not None and k <= lap.n else None))
    return lap.cache.fetch("eigen", int(k), lambda: eigs(lap, int(k)))


def negative_inertia(lap: Laplacian, mu: float):
    r"""Number of eigenvalues of :math:`\tilde L` below ``mu``, by Sylvester's law of inertia.

    The number of negative pivots of an :math:`LDL^\top` factorization of :math:`L - \mu B`
    (the package's LDLᵀ where it is built, else SuperLU with diagonal pivots and a
    symmetric ordering). Returns ``None`` when no such factorization succeeds (a zero
    pivot, or off-diagonal pivoting).
    """
    lap = as_laplacian(lap)
    A = (lap.L - mu * lap.B).tocsr()
    if ldlt.available():
        try:
            d = ldlt.LDLT(A).pivots()
        except ValueError:
            return None
    else:
        try:
            lu = spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                           options={"SymmetricMode": True})
        except RuntimeError:
            return None
        if not np.array_equal(lu.perm_r, lu.perm_c):
            return None
        d = lu.U.diagonal()
    if not np.all(np.isfinite(d)) or np.any(d == 0):
        return None
    return int(np.sum(d < 0))


def lambda_min_positive(lap: Laplacian) -> float:
    r"""A lower bound of the smallest positive eigenvalue :math:`\lambda_{c+1}` of :math:`\tilde L`.

    An estimate :math:`\hat\lambda` comes from shift-invert Lanczos with ker L deflated
    (:func:`eigs`; dense for small n). It is then certified by spectrum slicing: for
    :math:`\mu = 0.999\hat\lambda` (lowered until it succeeds), an :math:`LDL^\top`
    factorization of :math:`L - \mu B` with exactly c negative pivots (c = number of
    connected components, the dimension of ker L) shows, by Sylvester's law of inertia,
    that exactly c eigenvalues lie below :math:`\mu`: the c zeros. Then
    :math:`\mu \le \lambda_{c+1}`. When no factorization confirms it, the Lanczos value
    lowered by 5% is returned and :func:`lambda_min_positive_kind` says ``"estimate"``.
    Cached on ``lap``. Needed by the singular filters and by every spectrum-free method,
    which approximate the filter on :math:`[\lambda_{c+1}, \lambda_{\max}]` once ker L is
    split off exactly.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> ev, _ = sig.dense_eigs(lap, k=2)
    >>> lo = sig.lambda_min_positive(lap)
    >>> bool(0.99 * ev[1] < lo <= ev[1]), sig.linalg.lambda_min_positive_kind(lap)
    (True, 'proof')
    """
    return _lambda_min_positive(lap)[0]


def lambda_min_positive_kind(lap: Laplacian) -> str:
    """``"proof"`` when :func:`lambda_min_positive` was certified by inertia, else ``"estimate"``."""
    return _lambda_min_positive(lap)[1]


def _lambda_min_positive(lap):
    lap = as_laplacian(lap)

    def build():
        c = lap.n_components
        if lap.n - c <= 0:
            return lambda_max(lap), "proof"
        if lap.n <= 400:
            ev, _ = dense_eigs(lap, k=min(lap.n, c + 1))
        else:
            ev, _ = eigs(lap, c + 1)
        est = float(ev[c])
        if not est > 0:
            return 1e-300, "estimate"
        mu = 0.999 * est
        for _ in range(6):
            if negative_inertia(lap, mu) == c:
                return mu, "proof"
            mu *= 0.8
        return max(0.95 * est, 1e-300), "estimate"

    return lap.cache.fetch("bound", "lambda_min_positive", build)
