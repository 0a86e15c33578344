"""Smoothing of scalar functions: least squares (unconstrained and interpolating) and diffusion."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..accuracy import info as bound_info, weakest
from .._validate import as_flag, as_indices, as_nonnegative, as_positive, as_signal
from ..approx import SpectralOperator
from ..filters import heat
from ..laplacian import as_laplacian, entry_error, lambda_max_kind
from ..linalg import factorize
from .harmonic import constraints, polyharmonic_matrix

__all__ = ["smooth", "smooth_constrained", "diffusion_smooth"]


def smooth(lap, f, eps):
    r"""Least-squares smoothing: the compromise between fidelity and smoothness.

    Minimises

    .. math:: \varepsilon \|\tilde f - f\|_B^2 + \|L \tilde f\|_{M^{-1}}^2,

    whose normal equations are :math:`(L M^{-1} L + \varepsilon B)\tilde f = \varepsilon B f`.

    Parameters
    ----------
    lap : Laplacian
    f : (n,) or (n, k) float
        Noisy function(s).
    eps : float
        Fidelity weight, > 0. Small values smooth more. Its unit is that of
        eigenvalue squared: the filter acts as :math:`\varepsilon/(\lambda^2 + \varepsilon)`.

    Returns
    -------
    (n,) or (n, k) float

    Notes
    -----
    :math:`M` is the lumped mass (row sums of ``lap.B``) so that the system stays sparse;
    the norm :math:`\|L\tilde f\|_{M^{-1}} = \|\tilde L \tilde f\|_M` makes the energy
    independent of the mesh resolution (the survey writes :math:`\|L\tilde f\|_2`, which
    is not). When ``lap.B`` is lumped the result is exactly the spectral filter
    :math:`\tilde f = \sum_i \varepsilon (\lambda_i^2 + \varepsilon)^{-1}
    \langle f, x_i\rangle_B\, x_i`.

    The survey's §7.1 (smoothing).

    Examples
    --------
    Height on a sphere plus white noise of 0.3:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> z = lap.data["V"][:, 2]
    >>> f = z + 0.3 * np.random.default_rng(0).standard_normal(lap.n)
    >>> g = sig.smooth(lap, f, 100.0)
    >>> bool(np.sqrt(np.mean((g - z) ** 2)) < 0.5 * np.sqrt(np.mean((f - z) ** 2)))
    True
    """
    lap = as_laplacian(lap)
    f = as_signal(f, lap.n, "f", allow_complex=False)
    eps = as_positive(eps, "eps")
    A = polyharmonic_matrix(lap, 2) + eps * lap.B
    return factorize(A.tocsr()).solve(eps * (lap.B @ f))


def smooth_constrained(lap, f, fixed, eps: float = 0.0):
    r"""Smoothing with interpolating constraints: :math:`\tilde f = f` on ``fixed``.

    Minimises

    .. math:: \|L \tilde f\|_{M^{-1}}^2 + \varepsilon \|\tilde f - f\|_B^2
              \quad\text{subject to}\quad \tilde f_i = f_i,\ i \in \text{fixed}.

    With ``eps = 0`` (default, the survey's formulation) only the values at ``fixed``
    are used and the result is the biharmonic interpolant of them (``harmonic(...,
    k=2)``); ``eps > 0`` also keeps the result close to ``f`` elsewhere.

    Parameters
    ----------
    lap : Laplacian
    f : (n,) or (n, k) float
    fixed : (c,) int
        Vertices where the value of ``f`` is kept exactly (e.g. its critical points);
        every connected component needs one when ``eps = 0``.
    eps : float, default 0
        Fidelity weight, >= 0.

    Returns
    -------
    (n,) or (n, k) float

    Notes
    -----
    The survey's §7.1 (smoothing).

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> z = lap.data["V"][:, 2]
    >>> f = z + 0.3 * np.random.default_rng(0).standard_normal(lap.n)
    >>> g = sig.smooth_constrained(lap, f, [0, 1])
    >>> bool(np.allclose(g[[0, 1]], f[[0, 1]]))
    True
    """
    lap = as_laplacian(lap)
    f = as_signal(f, lap.n, "f", allow_complex=False)
    eps = as_nonnegative(eps, "eps")
    fixed = as_indices(fixed, lap.n, "fixed")
    fixed, vals = constraints(lap, fixed, f[fixed]) if eps == 0.0 else (fixed, f[fixed])
    if np.unique(fixed).size != fixed.size:
        raise ValueError("fixed has duplicate indices")
    n = lap.n
    free = np.setdiff1d(np.arange(n), fixed)
    out = np.array(f, dtype=np.float64, copy=True)
    out[fixed] = vals
    if free.size == 0:
        return out
    A = polyharmonic_matrix(lap, 2)
    rhs = -(A[free][:, fixed] @ vals)
    if eps > 0.0:
        A = A + eps * lap.B
        Bf = lap.B @ f
        rhs = rhs + eps * Bf[free] - eps * (lap.B[free][:, fixed] @ vals)
    out[free] = factorize(sp.csr_matrix(A[free][:, free])).solve(rhs)
    return out


def diffusion_smooth(lap, f, t, method: str = "auto", tol: float = 1e-8, return_info: bool = False):
    r"""Diffusion smoothing: the heat filter :math:`e^{-t\tilde L} f`, through the engine.

    .. math:: \tilde f = e^{-t \tilde L} f = \sum_i e^{-\lambda_i t}\langle f, x_i\rangle_B\, x_i

    Parameters
    ----------
    lap : Laplacian
    f : (n,) or (n, k) float
    t : float
        Diffusion time, > 0 (physical time; see :func:`optimal_time` to choose it).
    method, tol
        Passed to :func:`spectral_igl.apply_filter`.
    return_info : bool
        Also return ``info`` (:mod:`spectral_igl.accuracy`): ``abs_error`` shaped as the
        result, every entry's bound from the engine's B-norm bound of its column
        (:func:`spectral_igl.laplacian.entry_error`), ``bound_kind``, ``method``, ``tol`` and
        ``bnorm_error``.

    Returns
    -------
    (n,) or (n, k) float
    info : dict, only with ``return_info``

    Notes
    -----
    The survey's §7.1 (smoothing).

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> z = lap.data["V"][:, 2]
    >>> f = z + 0.3 * np.random.default_rng(0).standard_normal(lap.n)
    >>> g, info = sig.diffusion_smooth(lap, f, 0.05, return_info=True)
    >>> bool(np.sqrt(np.mean((g - z) ** 2)) < 0.5 * np.sqrt(np.mean((f - z) ** 2))), info["bound_kind"]
    (True, 'proof')
    """
    lap = as_laplacian(lap)
    f = as_signal(f, lap.n, "f", allow_complex=False)
    t = as_positive(t, "t")
    return_info = as_flag(return_info, "return_info")
    op = SpectralOperator(lap, heat(t), method=method, tol=tol)
    u = np.real(op.apply(f))
    if not return_info:
        return u
    bnorm = np.asarray(np.nan if op.error_bound is None else op.error_bound, dtype=float)
    kind = weakest(op.bound_kind, lambda_max_kind(lap)) if np.all(np.isfinite(bnorm)) else None
    return u, bound_info(entry_error(lap, bnorm), kind, op.method, tol=tol, bnorm_error=bnorm)
