r"""Cached sparse factorizations of the shifted matrices :math:`\theta B + \beta L`.

Every spectrum-free method reduces to solves with matrices shaped like the mesh:
:math:`B + \beta L` (real shifts, symmetric positive definite: Cholesky), :math:`tL - \theta B`
(complex poles: one complex symmetric LDLᵀ per conjugate pair), :math:`B` itself, and the grounded
stiffness for pseudo-inverses. The factorizations live in ``lap.cache`` (slot ``"factor"``) so that repeated
calls on one shape -- other right-hand sides, other filters with the same poles -- never
refactor.

Backends: CHOLMOD through cholespy (default for real SPD matrices), MKL PARDISO through
pypardiso (``backend="pypardiso"``), the package's supernodal LDLᵀ (``"ldlt"``, default
for complex symmetric matrices with a definite real or imaginary part, and the one that
gives selected inverses), SuperLU for indefinite matrices and as the fallback.
"""
from __future__ import annotations

import logging
import numbers
import time

import numpy as np
import scipy.sparse as sp

from .._validate import as_flag, as_signal, check_finite_result, describe
from ..accuracy import rounding_gamma
from ..laplacian import Laplacian, as_laplacian, lambda_max
from . import ldlt
from .factor import check_backend, factorize

log = logging.getLogger(__name__)

__all__ = ["shifted_factor", "pseudo_solve", "mass_solve", "inverse_mass_diagonal", "MassTraces", "grounded_vertices", "grounded_factor",
           "ldlt_pattern", "ldlt_factor", "check_backend", "clear_cache"]


def _ldlt_safe(lap: Laplacian, beta, theta) -> bool:
    """True when theta B + beta L has a definite real or imaginary part, so that LDLᵀ needs
    no pivoting: a part t B + b L is definite when t != 0 and b does not have the opposite
    sign, or when |t/b| lies above the spectrum of B⁻¹L."""
    def definite(t, b):
        if t == 0 or t * b >= 0:
            return t != 0
        return abs(t) > abs(b) * lambda_max(lap)

    beta, theta = complex(beta), complex(theta)
    return definite(theta.real, beta.real) or definite(theta.imag, beta.imag)


def ldlt_pattern(lap: Laplacian) -> ldlt.Pattern:
    """The ordering and symbolic LDLᵀ analysis of the pattern of L + B, cached on ``lap``."""
    lap = as_laplacian(lap)
    return lap.cache.fetch("pattern", "L+B", lambda: ldlt.Pattern(abs(lap.L) + abs(lap.B)))


def ldlt_factor(lap: Laplacian, A) -> ldlt.LDLT:
    """LDLᵀ of a matrix with the sparsity pattern of L + B (or a part of it), on the cached analysis."""
    pattern = ldlt_pattern(lap)
    start = time.perf_counter()
    fac = ldlt.LDLT(A, pattern)
    log.info("factorized n=%d nnz=%d with ldlt (%s) in %.3f s", A.shape[0], A.nnz, A.dtype,
             time.perf_counter() - start)
    return fac


def _scalar(x, name):
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (numbers.Number, np.number)):
        raise TypeError(f"{name} must be a number, got {describe(x)}")
    x = complex(x)
    if not (np.isfinite(x.real) and np.isfinite(x.imag)):
        raise ValueError(f"{name} must be finite, got {x}")
    return x.real if x.imag == 0 else x


def shifted_factor(lap: Laplacian, beta, theta=1.0, backend: str = "auto", keep: bool = True):
    r"""Cached factorization of :math:`\theta B + \beta L`.

    Parameters
    ----------
    lap : Laplacian
    beta, theta : float or complex
        Real ``theta > 0, beta >= 0`` gives a symmetric positive definite matrix
        (Cholesky); complex values give a complex symmetric matrix (LDLᵀ when its real or
        imaginary part is definite, else SuperLU).
    backend : {"auto", "cholespy", "pypardiso", "ldlt", "superlu"}
    keep : bool
        Store a new factorization in ``lap.cache`` (default). ``False`` returns a cached
        one if there is one, else a fresh one that is not stored (for a single pass that
        should hold one factor at a time).

    Returns
    -------
    Factor
        With ``.solve(b)`` for ``b`` of shape (n,) or (n, k), real or complex.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> fac = sig.linalg.shifted_factor(lap, 0.1)
    >>> x = fac.solve(lap.B @ np.ones(lap.n))
    >>> bool(np.allclose(x, 1.0))
    True
    """
    lap = as_laplacian(lap)
    beta, theta = _scalar(beta, "beta"), _scalar(theta, "theta")
    backend = check_backend(backend)
    keep = as_flag(keep, "keep")
    if theta == 0:
        raise ValueError(f"theta must be nonzero: theta B + beta L is singular for theta = 0 (constants "
                         f"are in the kernel of L), got theta={theta}; use pseudo_solve for L")
    cplx = isinstance(beta, complex) or isinstance(theta, complex)
    spd = (not cplx) and theta > 0 and beta >= 0
    if cplx and backend == "auto" and ldlt.available() and _ldlt_safe(lap, beta, theta):
        backend = "ldlt"

    def build():
        if backend == "ldlt":
            if not _ldlt_safe(lap, beta, theta):
                raise ValueError(f"backend 'ldlt' needs a definite real or imaginary part, got "
                                 f"beta={beta}, theta={theta}")
            dt = np.complex128 if cplx else np.float64
            return ldlt_factor(lap, (theta * lap.B.astype(dt) + beta * lap.L.astype(dt)).tocsr())
        if cplx:
            A = (theta * lap.B.astype(np.complex128) + beta * lap.L.astype(np.complex128)).tocsr()
            return factorize(A, backend="superlu", spd=False)
        A = (theta * lap.B + beta * lap.L).tocsr()
        return factorize(A, backend=backend, spd=True) if spd else factorize(A, backend="superlu", spd=False)

    key = ("shifted", beta, theta, backend)
    try:
        if not keep:
            hit = lap.cache.get("factor", key)
            return hit if hit is not None else build()
        return lap.cache.fetch("factor", key, build)
    except RuntimeError as err:   # the sparse backends' word for a numerically singular matrix
        raise ValueError(f"theta B + beta L cannot be factorized for beta={beta}, theta={theta} (singular "
                         f"or denormal: -theta/beta is an eigenvalue, or one of them dwarfs the other): "
                         f"{err}") from err


def mass_solve(lap: Laplacian, g: np.ndarray, backend: str = "auto") -> np.ndarray:
    r""":math:`B^{-1} g` (a division when B is diagonal, a cached Cholesky otherwise).

    Parameters
    ----------
    lap : Laplacian or mesh
    g : (n,) or (n, k) float or complex
    backend : str
        Sparse solver for a non-diagonal B (see :func:`factorize`; default ``"auto"``).

    Returns
    -------
    (n,) or (n, k)
        :math:`B^{-1} g`, shaped as ``g``.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl import linalg
    >>> lap = sig.laplacian(*icosphere(1), mass="full")
    >>> g = np.arange(lap.n, dtype=float)
    >>> bool(np.allclose(lap.B @ linalg.mass_solve(lap, g), g))
    True
    """
    lap = as_laplacian(lap)
    g = as_signal(g, lap.n, "g", max_magnitude=np.inf)   # also the engine's intermediate vectors
    backend = check_backend(backend)
    if lap.lumped:
        d = lap.B.diagonal()
        with np.errstate(over="ignore"):
            u = g / (d if g.ndim == 1 else d[:, None])
    else:
        u = shifted_factor(lap, 0.0, 1.0, backend=backend).solve(g)
    return check_finite_result(u, "B^-1 g", "g is too large for the masses (rescale it)")


def inverse_mass_diagonal(lap) -> np.ndarray:
    """diag(B^-1): 1/m for a lumped mass, else by selected inversion (cached)."""
    if lap.lumped:
        return 1.0 / lap.mass
    return lap.cache.fetch("diagonal", "inverse_mass",
                           lambda: shifted_factor(lap, 0.0, 1.0, backend="ldlt").inverse_diagonal())


class MassTraces:
    r"""Traces :math:`\operatorname{tr} r_k(\tilde L)` of partial fractions sharing poles, for a
    full mass matrix, accumulated pole by pole from the selected inversions of their factors.

    For :math:`r_k(s) = \alpha_{0,k} + \sum_j w_{jk}/(\sigma s - z_j)` (a conjugate pair folded
    into one pole, :math:`2\,\mathrm{Re}`),
    :math:`\operatorname{tr} r_k(\tilde L) = n\alpha_{0,k} + \sum_j \mathrm{Re}\,w_{jk}
    \operatorname{tr}\big((\sigma L - z_jB)^{-1}B\big)`, and
    :math:`\operatorname{tr}(A^{-1}B) = \sum_{ij}(A^{-1})_{ij}B_{ij}` needs :math:`A^{-1}` only on
    the pattern of B, which the selected inversion gives with the diagonal
    (:meth:`~spectral_igl.linalg.LDLT.selected_inverse`).

    Parameters
    ----------
    lap : Laplacian
    alpha0 : float or (T,) float
        The constant terms :math:`\alpha_{0,k}`.
    """

    def __init__(self, lap, alpha0):
        self._bvals = ldlt_pattern(lap).values(lap.B)
        al = np.atleast_1d(np.asarray(alpha0, dtype=float))
        #: (T,) the traces so far
        self.values = lap.n * al
        #: (T,) the sums of the magnitudes of every term added
        self.magnitude = lap.n * np.abs(al)
        self._terms = 1

    def inverse_diagonal(self, fac, weights) -> np.ndarray:
        """diag(A⁻¹) of the LDLᵀ factor ``fac`` of A = σL - zB, adding
        Re(``weights`` tr(A⁻¹B)) to the traces (``weights``: (T,) complex, or a scalar)."""
        Z = fac.selected_inverse()
        prod = Z.data * self._bvals
        w = np.atleast_1d(weights)
        self.values = self.values + (w * prod.sum()).real
        self.magnitude = self.magnitude + np.abs(w) * float(np.abs(prod).sum())
        self._terms += 1
        return Z.diagonal()

    def subtract(self, value) -> None:
        """Take ``value`` (T,) off the traces (what a fit puts on ker L, computed exactly)."""
        value = np.asarray(value, dtype=float)
        self.values = self.values - value
        self.magnitude = self.magnitude + np.abs(value)
        self._terms += 1

    def rounding(self) -> np.ndarray:
        r"""(T,) bound of the rounding of the sums (not of the selected inverse's entries):
        every trace is a sum of at most nnz + P + 2 products of complex numbers (P poles), so
        :math:`2\gamma_{\mathrm{nnz}+P+4}` times the sum of their magnitudes bounds it (Higham,
        §3.1 and §3.6: a complex product rounds within :math:`\sqrt2\gamma_2`)."""
        return 2.0 * rounding_gamma(self._bvals.size + self._terms + 4) * self.magnitude


def grounded_vertices(lap: Laplacian) -> np.ndarray:
    """(n,) bool: one vertex per component, the one of largest stiffness diagonal (best pivot),
    whose row and column are removed to make L definite."""
    lap = as_laplacian(lap)
    comp = lap.components
    order = np.lexsort((-lap.L.diagonal(), comp))
    first = np.ones(order.size, dtype=bool)
    first[1:] = comp[order[1:]] != comp[order[:-1]]
    grounded = np.zeros(lap.n, dtype=bool)
    grounded[order[first]] = True
    return grounded


def grounded_factor(lap: Laplacian, backend: str = "auto"):
    """The one grounded stiffness of ``lap``, factorized once: ``(factor, L_g, grounded)``.

    ``L_g`` is L with the row and column of each :func:`grounded_vertices` vertex replaced by
    those of the identity: symmetric positive definite, and its inverse with zeros at the
    grounded vertices is the grounded pseudo-inverse X of L. ``backend="auto"`` uses the
    package's LDLᵀ (which also gives diag(X) by selected inversion) where it is built.
    """
    lap = as_laplacian(lap)
    backend = check_backend(backend)
    if backend == "auto":
        backend = "ldlt" if ldlt.available() else "auto"

    def build():
        grounded = grounded_vertices(lap)
        keep = sp.diags((~grounded).astype(float))
        Lg = (keep @ lap.L @ keep + sp.diags(grounded.astype(float))).tocsr()
        fac = ldlt_factor(lap, Lg) if backend == "ldlt" else factorize(Lg, backend=backend, spd=True)
        return fac, Lg, grounded

    return lap.cache.fetch("factor", ("grounded", backend), build)


def pseudo_solve(lap: Laplacian, g, backend: str = "auto") -> np.ndarray:
    r"""Solve :math:`L u = g - B Z Z^\top g` with :math:`u` B-orthogonal to ker L.

    ``Z`` is the B-orthonormal basis of ker L (one indicator per component). With
    ``g = B f`` this is :math:`u = \tilde L^{+} f`, the pseudo-inverse of the Laplacian:
    the biharmonic filter :math:`s^{-1}` exactly, with no regularisation. Each component
    is grounded at one vertex (:func:`grounded_factor`, factorized once and cached), then
    the solution is B-projected onto the complement of ker L.

    Parameters
    ----------
    lap : Laplacian
    g : (n,) or (n, k) float or complex

    Returns
    -------
    u : same shape as ``g``

    Examples
    --------
    :math:`u = \tilde L^+ f` solves :math:`\tilde L u = f` for an ``f`` of mean zero, and has
    mean zero:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl import linalg
    >>> lap = sig.laplacian(*icosphere(2))
    >>> f = lap.data["V"][:, 2]            # z: B-orthogonal to the constants on the sphere
    >>> u = linalg.pseudo_solve(lap, lap.B @ f)
    >>> bool(np.allclose(lap.L @ u, lap.B @ f)), bool(abs(lap.mass @ u) < 1e-10)
    (True, True)
    """
    lap = as_laplacian(lap)
    g = as_signal(g, lap.n, "g")
    Z = lap.component_basis()
    rhs = g - lap.B @ (Z @ (Z.T @ g))
    fac, _, grounded = grounded_factor(lap, backend)
    rhs[grounded] = 0.0
    u = fac.solve(rhs)
    u[grounded] = 0.0
    return lap.project_out_kernel(u)


def clear_cache(lap: Laplacian) -> None:
    r"""Drop everything cached on ``lap`` (the same as ``lap.cache.clear()``).

    Factorizations, spectral bounds and eigenpairs are cached on the Laplacian and reused
    by every later call on it; this frees their memory.

    Parameters
    ----------
    lap : Laplacian

    Returns
    -------
    None

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl import linalg
    >>> lap = sig.laplacian(*icosphere(1))
    >>> _ = sig.lambda_max(lap)
    >>> len(lap.cache) > 0
    True
    >>> linalg.clear_cache(lap); len(lap.cache)
    0
    """
    as_laplacian(lap).cache.clear()
