"""Harmonic and poly-harmonic interpolation with Dirichlet constraints."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .._validate import as_indices, as_int, check_magnitude, describe
from ..laplacian import Laplacian, as_laplacian
from ..linalg import factorize

__all__ = ["harmonic", "constraints", "polyharmonic_matrix", "MAX_ORDER"]

#: largest poly-harmonic order: beyond it the system is numerically singular on any mesh
MAX_ORDER = 8


def constraints(lap: Laplacian, fixed, values):
    n = lap.n
    fixed = as_indices(fixed, n, "fixed")
    if np.unique(fixed).size != fixed.size:
        u, c = np.unique(fixed, return_counts=True)
        raise ValueError(f"fixed has duplicate indices, e.g. {int(u[c > 1][0])}")
    vals = np.asarray(values)
    if vals.dtype == object or vals.dtype.kind not in "biuf":
        raise TypeError(f"values must be real numbers, got {describe(values)}")
    if vals.ndim == 0:
        vals = np.full(fixed.size, float(vals))
    if vals.ndim not in (1, 2) or vals.shape[0] != fixed.size:
        raise ValueError(f"values must have shape ({fixed.size},) or ({fixed.size}, k) "
                         f"to match fixed, got {describe(vals)}")
    vals = vals.astype(np.float64)
    if not np.all(np.isfinite(vals)):
        raise ValueError("values contains NaN or inf")
    check_magnitude(vals, "values", hint="rescale them (the solution is linear in the values)")
    missing = np.setdiff1d(np.arange(lap.n_components), lap.components[fixed])
    if missing.size:
        raise ValueError(f"{missing.size} connected component(s) have no fixed vertex (e.g. the one "
                         f"containing vertex {int(np.flatnonzero(lap.components == missing[0])[0])}); "
                         "the solution is not determined there")
    return fixed, vals


def polyharmonic_matrix(lap: Laplacian, k: int) -> sp.csr_matrix:
    r"""The sparse operator :math:`L (M^{-1} L)^{k-1}`, ``M`` the lumped mass (row sums of B)."""
    Q = lap.L
    if k > 1:
        Minv = sp.diags(1.0 / lap.mass)
        for _ in range(k - 1):
            Q = Q @ (Minv @ lap.L)
    return sp.csr_matrix(Q)


def harmonic(lap, fixed, values, k: int = 1):
    r"""Harmonic (``k = 1``) or poly-harmonic (:math:`\Delta^k h = 0`) interpolation.

    Parameters
    ----------
    lap : Laplacian
    fixed : (c,) int
        Constrained vertices, distinct; every connected component needs at least one.
    values : (c,) or (c, m) float
        Dirichlet values at ``fixed`` (a scalar sets all of them).
    k : int, default 1
        Order: 1 harmonic, 2 biharmonic, ..., at most :data:`MAX_ORDER` (the condition
        number of the system grows like :math:`(\lambda_{max}/\lambda_{min})^k` and its
        fill like :math:`k^2` neighbours per vertex).

    Returns
    -------
    h : (n,) or (n, m) float
        Equal to ``values`` on ``fixed``; shape follows ``values``.

    Notes
    -----
    Solves, on the free vertices :math:`f` with the constrained ones :math:`c`,

    .. math:: Q_{ff} h_f = -Q_{fc}\, h_c, \qquad Q = L (M^{-1} L)^{k-1},

    with a sparse Cholesky factorization. :math:`Q` is the stiffness of the
    energy :math:`\int |\Delta^{k/2} h|^2` with the operator :math:`\tilde L = M^{-1}L`
    built on the lumped mass :math:`M` (row sums of ``lap.B``, exactly ``B`` when it
    is lumped), which keeps :math:`Q` sparse; for ``k = 1`` the mass plays no role.
    For :math:`k \ge 2` the boundary behaves as with natural (Neumann-type) conditions.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2); lap = sig.laplacian(V, F)
    >>> h = harmonic(lap, [0, 5], [0.0, 1.0])
    >>> float(h[0]), float(h[5]), bool(h.min() >= 0 and h.max() <= 1)
    (0.0, 1.0, True)
    """
    lap = as_laplacian(lap)
    k = as_int(k, "k", lo=1, hi=MAX_ORDER)
    fixed, vals = constraints(lap, fixed, values)
    n = lap.n
    free = np.setdiff1d(np.arange(n), fixed)
    out = np.empty((n,) + vals.shape[1:])
    out[fixed] = vals
    if free.size == 0:
        return out
    Q = polyharmonic_matrix(lap, int(k))
    Qff = Q[free][:, free]
    rhs = -(Q[free][:, fixed] @ vals)
    out[free] = factorize(Qff).solve(rhs)
    return out
