r"""Heat on a Metzler operator without cancellation: every entry to a proved relative accuracy.

When B is diagonal (lumped) and every off-diagonal entry of L is non-positive,
:math:`A = B^{-1}L` has :math:`-A` Metzler and :math:`A\mathbf 1 = 0`. With
:math:`\alpha \ge \max_j A_{jj}` the matrix :math:`P = I - A/\alpha` is entrywise non-negative
with unit row sums, and

.. math:: e^{-tA} = e^{-t\alpha} e^{t\alpha P} = \sum_{k \ge 0} \pi_k(t\alpha)\, P^k,
          \qquad \pi_k(\Lambda) = e^{-\Lambda}\Lambda^k / k!

(uniformization). Applied to a non-negative G every term is non-negative, so no sum cancels:
the rounding of each entry is relative to that entry, however small it is against the peak.
Here :math:`\alpha` is a power of two (at least :math:`\tfrac98\max_j A_{jj}`, so
:math:`P_{jj} \ge 1/9`) and t is split into :math:`s` (a power of two) steps of
:math:`\Lambda = t\alpha/s \le` :data:`STEP` each, so that :math:`\Lambda` and
:math:`P`'s off-diagonal entries carry no rounding from the scaling.

**Bound of every entry.** Truncating a step after K terms leaves the non-negative remainder
:math:`\sum_{k>K}\pi_k P^k v \le \Pr[\mathrm{Poisson}(\Lambda) > K]\,\|v\|_\infty` (P is
stochastic), with the Chernoff bound :math:`\Pr[X \ge K+1] \le e^{-\Lambda}(e\Lambda/(K+1))^{K+1}`.
The exact step operator is non-negative and stochastic, so over s steps the truncation adds at
most :math:`s\,\tau\,\|G\|_\infty` per entry, and componentwise relative rounding errors (the
entries of P within :math:`9u`, each product within :math:`\gamma_r` for rows of r entries,
the coefficients within :math:`\gamma_{2k} + 4u`, the sum within :math:`\gamma_{K+1}`, u the
unit round-off) stay componentwise relative: :math:`|\tilde U - U| \le \rho\,\tilde U/(1-\rho)
+ s\tau\|G\|_\infty` with :math:`\rho = (1+\delta)^s - 1` and :math:`\delta` one step's relative
rounding. ``exp`` is taken to be within 4 units in the last place (glibc's is within 1).

The cost is about :math:`1.6\,t\alpha` sparse products per block of columns: cheap at small t,
expensive where one poorly shaped element makes :math:`\alpha` large.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..laplacian import metzler

__all__ = ["metzler_heat", "products_needed", "STEP", "TAIL"]

#: largest Poisson mean per step (e^-STEP stays far above the underflow threshold)
STEP = 256.0
#: Chernoff bound of each step's truncated Poisson tail, relative to max |input|
TAIL = 1e-32
U = 2.0 ** -53


def _gamma(k):
    return k * U / (1.0 - k * U)


def _rate(lap):
    """(alpha, P) with alpha a power of two >= 9/8 max_j A_jj and P = I - A/alpha >= 0."""
    L = sp.csr_matrix(lap.L, dtype=float)
    d = L.diagonal() / lap.mass
    top = float(np.max(d)) if d.size else 0.0
    if not top > 0:
        return 0.0, None
    alpha = 2.0 ** math.ceil(math.log2(1.125 * top))
    minv = 1.0 / lap.mass
    P = sp.csr_matrix(-(sp.diags(minv) @ L) / alpha)
    P.setdiag(1.0 - d / alpha)
    P.eliminate_zeros()
    return alpha, P


def _terms(lam):
    """Smallest K with the Chernoff bound of P[Poisson(lam) > K] <= TAIL, and that bound."""
    log_tail = math.log(TAIL)
    K = max(int(math.ceil(lam)), 1)
    while True:
        j = K + 1
        lt = -lam + j * (1.0 + math.log(lam) - math.log(j))
        if lt <= log_tail:
            return K, math.exp(lt)
        K += max(1, K // 64)


def _steps(t, alpha):
    total = t * alpha
    s = 1 if total <= STEP else 2 ** math.ceil(math.log2(total / STEP))
    return s, total / s          # t * alpha / s is exact: alpha and s are powers of two


def products_needed(lap, t: float) -> int:
    """Sparse products (per block of columns) that :func:`metzler_heat` takes at time t."""
    alpha, _ = _rate(lap)
    if alpha == 0:
        return 0
    s, lam = _steps(t, alpha)
    return s * _terms(lam)[0]


def metzler_heat(lap, t: float, G: np.ndarray):
    r""":math:`e^{-t\tilde L}G` for non-negative G on a Metzler Laplacian, with a bound of each entry.

    Parameters
    ----------
    lap : Laplacian
        Lumped mass and non-positive off-diagonal stiffness (:func:`spectral_igl.laplacian.metzler`).
    t : float
    G : (n,) or (n, m) float, non-negative
        E.g. the discrete deltas :math:`B^{-1}e_i`.

    Returns
    -------
    U : same shape as G
    abs_error : same shape as G
        :math:`|U - e^{-t\tilde L}G| \le` ``abs_error`` entry by entry: a proof (module notes).
    """
    if not metzler(lap):
        raise ValueError("metzler_heat needs a lumped mass and non-positive off-diagonal stiffness")
    G = np.asarray(G, dtype=float)
    if np.any(G < 0) or not np.all(np.isfinite(G)):
        raise ValueError("G must be finite and non-negative")
    one = G.ndim == 1
    V = G.reshape(G.shape[0], -1).copy()
    gmax = np.max(V, axis=0) if V.size else np.zeros(V.shape[1])
    alpha, P = _rate(lap)
    if alpha == 0 or t == 0:
        err = np.zeros_like(V)
        return (V[:, 0], err[:, 0]) if one else (V, err)
    s, lam = _steps(t, alpha)
    K, tail = _terms(lam)
    r = int(np.max(np.diff(P.indptr)))
    eps1 = 9.0 * U + _gamma(r) * (1.0 + 9.0 * U)
    # one step, relative and componentwise: term k has k products and a coefficient within
    # gamma_2k + 4u, times (1 + u) for the product, and the sum of K+1 terms adds gamma_{K+1}
    delta = math.expm1(K * math.log1p(eps1) + math.log1p(_gamma(2 * K) + 4 * U) + math.log1p(U)) \
        + _gamma(K + 1)
    delta *= 1.0 + 1e-6
    for _ in range(s):
        c = math.exp(-lam)
        W = c * V
        p = V
        for k in range(1, K + 1):
            p = P @ p
            c *= lam / k
            W += c * p
        V = W
    rho = math.expm1(s * math.log1p(delta))
    # plus what underflow can lose: each of the s * (K + 1) products and sums of r + 1 terms
    # rounds an entry by at most one subnormal unit per term
    tiny = s * (K + 1) * (r + 2) * float(np.finfo(float).smallest_subnormal)
    err = rho * V / (1.0 - rho) + s * tail * gmax[None, :] * (1.0 + 1e-6) + tiny
    return (V[:, 0], err[:, 0]) if one else (V, err)
