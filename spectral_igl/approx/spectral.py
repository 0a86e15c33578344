r"""Eigen-decomposition methods: ``"dense"`` (all eigenpairs; exact, small n) and ``"eigen"``
(the truncated spectral approximation with k eigenpairs, the usual baseline).

.. math:: \varphi(\tilde L) f \approx X_k \varphi(\Lambda_k) X_k^\top B f

The truncated method cannot certify its error: the discarded part
:math:`\sum_{l > k} \varphi(\lambda_l) \langle f, x_l\rangle_B x_l` is unknown without the
rest of the spectrum. Its ``error_bound`` is therefore ``None``.
"""
from __future__ import annotations

import numpy as np

from ..linalg import cached_eigs as _pairs
from .common import EPS


class DensePlan:
    def __init__(self, lap, filt, a, b, tol, max_n=6000):
        if lap.n > max_n:
            raise ValueError(f"method 'dense' is for small meshes: n = {lap.n} > {max_n}")
        self.lap, self.filt = lap, filt
        self.evals, self.X = _pairs(lap, None)
        self.phi = filt(self.evals)
        self.rounding = 1e2 * lap.n * EPS * float(np.max(np.abs(self.phi)))
        self.n_solves = 0

    def apply(self, f, rhs):
        c = self.X.T @ (f if rhs else self.lap.B @ f)
        phi = self.phi if f.ndim == 1 else self.phi[:, None]
        u = self.X @ (phi * c)
        # ||B^-1 g||_B = ||X^T g|| exactly
        src = None if rhs else f
        self.coef_norm = np.linalg.norm(c, axis=0)
        return u, src, self.rounding


class EigenPlan:
    def __init__(self, lap, filt, a, b, tol, k=100):
        k = int(k)
        if not 1 <= k < lap.n:
            raise ValueError(f"k must be in [1, {lap.n - 1}], got {k}")
        self.lap, self.filt, self.k = lap, filt, k
        self.evals, self.X = _pairs(lap, k)
        self.phi = filt(self.evals)
        self.n_solves = 0

    def apply(self, f, rhs):
        c = self.X.T @ (f if rhs else self.lap.B @ f)
        phi = self.phi if f.ndim == 1 else self.phi[:, None]
        return self.X @ (phi * c), None, None
