r"""A heat operator that keeps positive inputs positive, to full relative accuracy.

Entropic transport and Varadhan's formula need :math:`\log K_t`, i.e. the heat kernel to a
*relative* accuracy where it is :math:`e^{-d^2/4t}` small. The engine's rational
approximations bound the absolute error, so far from the source their kernel is noise of
either sign. Backward-Euler steps with a Metzler operator do not have that limit:

.. math:: P = (M + sL)^{-1} M, \qquad K_t \approx P^N, \quad s = t/N,

with :math:`M` the lumped mass and :math:`L` a stiffness whose off-diagonal entries are
all :math:`\le 0`. Then :math:`M + sL` is a symmetric M-matrix: its Cholesky factor has
non-positive off-diagonal entries, so both triangular solves of a non-negative right-hand
side only add non-negative terms. No cancellation occurs, every entry of the result is
positive and accurate to a few units of round-off relative to itself, however small
(until it underflows below :math:`10^{-308}`).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .._validate import as_int, as_positive, describe
from ..laplacian import Laplacian
from ..laplacian.intrinsic_fem import intrinsic_operators
from ..linalg import factorize

__all__ = ["PositiveHeat", "metzler_stiffness", "log_apply", "MAX_STEPS"]

#: most backward-Euler steps of one heat application (each is one sparse solve)
MAX_STEPS = 10000


def metzler_stiffness(L) -> sp.csr_matrix:
    r"""The stiffness with its positive off-diagonal entries removed (rows still sum to 0).

    .. math:: \hat L_{ij} = \min(L_{ij}, 0)\ (i \ne j), \qquad \hat L_{ii} = -\sum_{j\ne i}\hat L_{ij}

    Parameters
    ----------
    L : (n, n) sparse, symmetric

    Returns
    -------
    (n, n) sparse csr, symmetric, positive semi-definite, with non-positive off-diagonals.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.applications.heat_steps import metzler_stiffness
    >>> L = metzler_stiffness(sig.laplacian(*icosphere(2), weights="cotan").L)
    >>> off = L - np.diag(L.diagonal())
    >>> bool(off.max() <= 0), bool(np.allclose(L @ np.ones(L.shape[0]), 0.0))
    (True, True)
    """
    C = sp.coo_matrix(L)
    keep = (C.row != C.col) & (C.data < 0)
    n = C.shape[0]
    W = sp.csr_matrix((C.data[keep], (C.row[keep], C.col[keep])), shape=(n, n))
    return (W - sp.diags(np.asarray(W.sum(axis=1)).ravel())).tocsr()


def log_apply(apply, logX: np.ndarray) -> np.ndarray:
    r"""Column-wise :math:`\log K e^{X}` for log-densities X (``-inf`` allowed) and a positive
    operator ``apply`` = K, the largest value of each column factored out first."""
    m = np.max(np.where(np.isfinite(logX), logX, -np.inf), axis=0)
    m = np.where(np.isfinite(m), m, 0.0)
    Y = apply(np.exp(logX - m))
    return np.log(np.maximum(Y, np.finfo(float).tiny)) + m


class PositiveHeat:
    r"""Heat diffusion :math:`u \mapsto P^N u`, :math:`P = (M + \tfrac{t}{N} L)^{-1}M`, positive.

    Parameters
    ----------
    lap : Laplacian
        For a triangle mesh (``V`` and ``F`` in ``lap.data``) the stiffness is built on
        the intrinsic Delaunay triangulation (all interior cotangent weights
        :math:`\ge 0`); any remaining positive off-diagonal entry (a boundary edge opposite
        an obtuse angle, or any entry of another domain's ``lap.L``) is removed by
        :func:`metzler_stiffness`. The mass is lumped (``lap.mass``, or the intrinsic
        barycentric areas).
    t : float
        Diffusion time, > 0.
    steps : int, default 16
        Backward-Euler steps :math:`N`. The kernel of :math:`P^N` is the heat kernel's
        Gaussian :math:`e^{-d^2/4t}` for :math:`d^2/4t \ll N` (the exponent's relative
        error is about :math:`d^2/(8Nt)`) and decays only like :math:`e^{-d\sqrt{N/t}}`
        beyond; each application costs :math:`N` pairs of triangular solves with one
        factorization.

    Attributes
    ----------
    L : (n, n) sparse
        The Metzler stiffness used.
    mass : (n,) float
        The lumped mass used.

    Examples
    --------
    A column of the positive heat operator is a non-negative bump of unit mass:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.applications.heat_steps import PositiveHeat
    >>> P = PositiveHeat(sig.laplacian(*icosphere(2)), 0.05)
    >>> u = P.column(0)
    >>> bool(u.min() >= 0), bool(np.isclose(P.mass @ u, 1.0))
    (True, True)
    """

    def __init__(self, lap: Laplacian, t: float, steps: int = 16):
        if not isinstance(lap, Laplacian):
            raise TypeError(f"lap must be a spectral_igl.Laplacian, got {describe(lap)}")
        as_int(steps, "steps", lo=1, hi=MAX_STEPS)
        self.t = as_positive(t, "t")
        self.steps = int(steps)
        self.n = lap.n
        if lap.domain == "triangle" and "V" in lap.data and "F" in lap.data:
            V = np.asarray(lap.data["V"], dtype=float)
            V = V if V.shape[1] == 3 else np.c_[V, np.zeros(len(V))]
            _, _, L, M, _ = intrinsic_operators(V, np.asarray(lap.data["F"]))
            mass = M.diagonal()
        else:
            L, mass = lap.L, np.asarray(lap.mass, dtype=float)
        self.L = metzler_stiffness(L)
        self.mass = np.asarray(mass, dtype=float)
        s = self.t / self.steps
        self._factor = factorize((sp.diags(self.mass) + s * self.L).tocsr())

    def apply(self, X: np.ndarray) -> np.ndarray:
        """:math:`P^N X` for X of shape (n,) or (n, k); non-negative in, positive out."""
        X = np.asarray(X, dtype=float)
        m = self.mass if X.ndim == 1 else self.mass[:, None]
        for _ in range(self.steps):
            X = self._factor.solve(m * X)
        return X

    def log_apply(self, logX: np.ndarray) -> np.ndarray:
        r"""Column-wise :math:`\log K e^{X}` (see :func:`log_apply`); the kernel is positive,
        so the log of each entry is accurate relative to itself."""
        return log_apply(self.apply, logX)

    def column(self, source: int) -> np.ndarray:
        r"""(n,) kernel column :math:`K_t(\cdot, p) \approx P^N (e_p / m_p)`."""
        e = np.zeros(self.n)
        e[int(source)] = 1.0 / self.mass[int(source)]
        return self.apply(e)
