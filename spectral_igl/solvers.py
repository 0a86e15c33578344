r"""Cached sparse factorizations of the shifted matrices :math:`\theta B + \beta L`.

Every spectrum-free method reduces to solves with matrices shaped like the mesh:
:math:`B + \beta L` (real shifts, symmetric positive definite: Cholesky), :math:`tL - \theta B`
(complex poles: one complex symmetric LDLᵀ per conjugate pair), :math:`B` itself, and the grounded
stiffness for pseudo-inverses. The factorizations live in ``lap.cache`` so that repeated
calls on one shape -- other right-hand sides, other filters with the same poles -- never
refactor.

Backends: CHOLMOD through cholespy (default for real SPD matrices), MKL PARDISO through
pypardiso (``backend="pypardiso"``), the package's supernodal LDLᵀ (``"ldlt"``, default
for complex symmetric matrices with a definite real or imaginary part, and the one that
gives selected inverses), SuperLU for indefinite matrices and as the fallback.
"""
from __future__ import annotations

import numbers
from collections import OrderedDict

import numpy as np
import scipy.sparse as sp

from . import _selinv
from ._factor import available_backends, factorize
from ._validate import as_signal, describe
from .laplacian import Laplacian

__all__ = ["shifted_factor", "pseudo_solve", "mass_solve", "clear_cache", "max_cached_factors"]

#: At most this many shifted factorizations are kept per Laplacian (least recently used first out).
max_cached_factors = 24


def _check_lap(lap) -> Laplacian:
    if not isinstance(lap, Laplacian):
        raise TypeError(f"expected a spectral_igl.Laplacian, got {describe(lap)}")
    return lap


def _check_backend(backend: str) -> str:
    valid = ("auto",) + tuple(available_backends())
    if backend not in valid:
        raise ValueError(f"backend must be one of {valid}, got {backend!r}")
    return backend


def _ldlt_safe(lap: Laplacian, beta, theta) -> bool:
    """True when theta B + beta L has a definite real or imaginary part, so that LDLᵀ needs
    no pivoting: a part t B + b L is definite when t != 0 and b does not have the opposite
    sign, or when |t/b| lies above the spectrum of B⁻¹L."""
    def definite(t, b):
        if t == 0 or t * b >= 0:
            return t != 0
        from .approx._common import lambda_max

        return abs(t) > abs(b) * lambda_max(lap)

    beta, theta = complex(beta), complex(theta)
    return definite(theta.real, beta.real) or definite(theta.imag, beta.imag)


def ldlt_pattern(lap: Laplacian):
    """The ordering and symbolic LDLᵀ analysis of the pattern of L + B, cached on ``lap``."""
    pat = lap.cache.get("ldlt_pattern")
    if pat is None:
        pat = lap.cache["ldlt_pattern"] = _selinv.Pattern(abs(lap.L) + abs(lap.B))
    return pat


def _scalar(x, name):
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (numbers.Number, np.number)):
        raise TypeError(f"{name} must be a number, got {describe(x)}")
    x = complex(x)
    if not (np.isfinite(x.real) and np.isfinite(x.imag)):
        raise ValueError(f"{name} must be finite, got {x}")
    return x.real if x.imag == 0 else x


def shifted_factor(lap: Laplacian, beta, theta=1.0, backend: str = "auto"):
    r"""Cached factorization of :math:`\theta B + \beta L`.

    Parameters
    ----------
    lap : Laplacian
    beta, theta : float or complex
        Real ``theta > 0, beta >= 0`` gives a symmetric positive definite matrix
        (Cholesky); complex values give a complex symmetric matrix (LDLᵀ when its real or
        imaginary part is definite, else SuperLU).
    backend : {"auto", "cholespy", "pypardiso", "ldlt", "superlu"}

    Returns
    -------
    Factor
        With ``.solve(b)`` for ``b`` of shape (n,) or (n, k), real or complex.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> fac = sig.solvers.shifted_factor(lap, 0.1)
    >>> x = fac.solve(lap.B @ np.ones(lap.n))
    >>> bool(np.allclose(x, 1.0))
    True
    """
    lap = _check_lap(lap)
    beta, theta = _scalar(beta, "beta"), _scalar(theta, "theta")
    backend = _check_backend(backend)
    cplx = isinstance(beta, complex) or isinstance(theta, complex)
    spd = (not cplx) and theta > 0 and beta >= 0
    if cplx and backend == "auto" and _selinv.available() and _ldlt_safe(lap, beta, theta):
        backend = "ldlt"
    key = ("shifted", beta, theta, backend)
    cache = lap.cache.setdefault("factors", OrderedDict())
    fac = cache.get(key)
    if fac is not None:
        cache.move_to_end(key)
        return fac
    if backend == "ldlt":
        if not _ldlt_safe(lap, beta, theta):
            raise ValueError(f"backend 'ldlt' needs a definite real or imaginary part, got "
                             f"beta={beta}, theta={theta}")
        dt = np.complex128 if cplx else np.float64
        fac = _selinv.LDLT((theta * lap.B.astype(dt) + beta * lap.L.astype(dt)).tocsr(), ldlt_pattern(lap))
    elif cplx:
        A = (theta * lap.B.astype(np.complex128) + beta * lap.L.astype(np.complex128)).tocsr()
        fac = factorize(A, backend="superlu", spd=False)
    else:
        A = (theta * lap.B + beta * lap.L).tocsr()
        if spd:
            fac = factorize(A, backend=backend, spd=True)
        else:
            fac = factorize(A, backend="superlu", spd=False)
    cache[key] = fac
    while len(cache) > max_cached_factors:
        cache.popitem(last=False)
    return fac


def mass_solve(lap: Laplacian, g: np.ndarray, backend: str = "auto") -> np.ndarray:
    r""":math:`B^{-1} g` (a division when B is diagonal, a cached Cholesky otherwise)."""
    lap = _check_lap(lap)
    if lap.lumped:
        d = lap.B.diagonal()
        return g / (d if g.ndim == 1 else d[:, None])
    return shifted_factor(lap, 0.0, 1.0, backend=backend).solve(g)


def grounded_vertices(lap: Laplacian) -> np.ndarray:
    """(n,) bool: one vertex per component, the one of largest stiffness diagonal (best pivot),
    whose row and column are removed to make L definite."""
    comp = lap.components
    order = np.lexsort((-lap.L.diagonal(), comp))
    first = np.ones(order.size, dtype=bool)
    first[1:] = comp[order[1:]] != comp[order[:-1]]
    grounded = np.zeros(lap.n, dtype=bool)
    grounded[order[first]] = True
    return grounded


def _grounded(lap: Laplacian, backend: str = "auto"):
    """Factor of L with one vertex per component removed (SPD), and the kept indices."""
    key = ("grounded", backend)
    g = lap.cache.get(key)
    if g is not None:
        return g
    keep = np.flatnonzero(~grounded_vertices(lap))
    fac = None
    if keep.size:
        Lr = lap.L[keep][:, keep].tocsr()
        fac = factorize(Lr, backend=backend, spd=True)
    g = (fac, keep)
    lap.cache[key] = g
    return g


def pseudo_solve(lap: Laplacian, g, backend: str = "auto") -> np.ndarray:
    r"""Solve :math:`L u = g - B Z Z^\top g` with :math:`u` B-orthogonal to ker L.

    ``Z`` is the B-orthonormal basis of ker L (one indicator per component). With
    ``g = B f`` this is :math:`u = \tilde L^{+} f`, the pseudo-inverse of the Laplacian:
    the biharmonic filter :math:`s^{-1}` exactly, with no regularisation. Each component
    is grounded at one vertex (the reduced stiffness is positive definite and factorized
    once, cached), then the solution is B-projected onto the complement of ker L.

    Parameters
    ----------
    lap : Laplacian
    g : (n,) or (n, k) float or complex

    Returns
    -------
    u : same shape as ``g``
    """
    lap = _check_lap(lap)
    g = as_signal(g, lap.n, "g")
    Z = lap.component_basis()
    rhs = g - lap.B @ (Z @ (Z.T @ g))
    fac, keep = _grounded(lap, backend)
    u = np.zeros_like(rhs)
    if fac is not None:
        u[keep] = fac.solve(rhs[keep])
    return lap.project_out_kernel(u)


def clear_cache(lap: Laplacian) -> None:
    """Drop every factorization cached on ``lap`` (e.g. to free memory)."""
    lap = _check_lap(lap)
    for key in list(lap.cache):
        if key == "factors" or (isinstance(key, tuple) and key and key[0] == "grounded"):
            del lap.cache[key]


