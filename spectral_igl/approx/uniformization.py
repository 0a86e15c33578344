r"""Heat on a Metzler operator without cancellation: every entry to a proved relative accuracy.

When B is diagonal (lumped) and every off-diagonal entry of L is non-positive,
:math:`A = B^{-1}L` has :math:`-A` Metzler and :math:`A\mathbf 1 = 0`. With
:math:`\alpha \ge \max_j A_{jj}` the matrix :math:`P = I - A/\alpha` is entrywise non-negative
with unit row sums, and

.. math:: e^{-tA} = e^{-t\alpha} e^{t\alpha P} = \sum_{k \ge 0} \pi_k(t\alpha)\, P^k,
          \qquad \pi_k(\Lambda) = e^{-\Lambda}\Lambda^k / k!

(uniformization). Applied to a non-negative G every term is non-negative, so no sum cancels:
the rounding of each entry is relative to that entry, however small it is against the peak.
Here :math:`\alpha = \tfrac{17}{16}\max_j A_{jj}` (so :math:`P_{jj} \ge 1/17` and the
diagonal's rounding is relative too) and t is split into s steps of
:math:`\Lambda = t\alpha/s \le` :data:`STEP` each. The rounding of :math:`\Lambda` moves the
time by at most 4u relative, which moves every entry by a factor within
:math:`e^{\pm 4u\,t\alpha}` (for a Metzler generator,
:math:`e^{-\delta\alpha}K_t \le K_{t+\delta} \le e^{\delta\alpha}K_t` entrywise).

**Bound of every entry.** Truncating a step after K terms leaves the non-negative remainder
:math:`\sum_{k>K}\pi_k P^k v \le \Pr[\mathrm{Poisson}(\Lambda) > K]\,\|v\|_\infty` (P is
stochastic).
The exact step operator is non-negative and stochastic, so over s steps the truncation adds at
most :math:`s\,\tau\,\|G\|_\infty` per entry (the tail :math:`\tau` bounded by
:math:`\pi_{K+1}/(1 - \Lambda/(K+2))`), and componentwise relative rounding errors (the
entries of P within :math:`33u`, each product within :math:`\gamma_r` for rows of r entries,
the coefficients within :math:`\gamma_{2k} + 4u`, the sum within :math:`\gamma_{K+1}`, u the
unit round-off) stay componentwise relative: :math:`|\tilde U - U| \le \rho\,\tilde U/(1-\rho)
+ s\tau\|G\|_\infty` with :math:`\rho = (1+\delta)^s - 1` and :math:`\delta` one step's relative
rounding. ``exp`` is taken to be within 4 units in the last place (glibc's is within 1).

The cost is about :math:`1.1\text{--}1.6\,t\alpha` sparse products per block of columns: cheap at
small t, expensive where one poorly shaped element makes :math:`\alpha` large.
"""
from __future__ import annotations

import math
import sys

import numpy as np
import scipy.sparse as sp

from ..accuracy import UNIT_ROUNDOFF as U, rounding_gamma as _gamma

__all__ = ["metzler_heat", "uniformize", "rate", "rate_matrix", "products_needed", "terms", "STEP", "TAIL"]

#: largest Poisson mean per step (e^-STEP stays far above the underflow threshold)
STEP = 512.0
#: default bound of the truncated Poisson tails (all steps), relative to each column's maximum
TAIL = 1e-32
#: t * alpha beyond which the step count is not even formed
MAX_RATE_TIME = 1e12



def rate(lap):
    """(alpha, P) with alpha = 17/16 max_j A_jj and P = I - A/alpha >= 0 (P_jj >= 1/17),
    cached on ``lap`` (alpha = 0 and P = None when L is 0)."""
    def build():
        return rate_matrix(lap.L, lap.mass)

    return lap.cache.fetch("bound", "uniformization", build)


def rate_matrix(L, mass):
    """(alpha, P) of the stiffness L and lumped mass ``mass``: alpha = 17/16 max_j L_jj / mass_j
    and P = I - diag(mass)^-1 L / alpha, rounded as the module notes assume; (0, None) when
    every L_jj is 0. For a principal submatrix L_RR this is the Dirichlet operator of R."""
    L = sp.csr_matrix(L, dtype=float)
    d = L.diagonal() / mass
    top = float(np.max(d)) if d.size else 0.0
    if not top > 0:
        return 0.0, None
    alpha = 1.0625 * top
    P = sp.csr_matrix(sp.diags(-1.0 / (mass * alpha)) @ L)
    P.setdiag(1.0 - d / alpha)
    P.eliminate_zeros()
    return alpha, P


def _terms(lam, tail):
    r"""Smallest K with P[Poisson(lam) > K] <= tail, and that tail's bound.

    :math:`\Pr[X > K] \le \pi_{K+1}/(1 - \lambda/(K+2))` for :math:`K + 2 > \lambda` (the
    ratios :math:`\pi_{k+1}/\pi_k = \lambda/(k+1)` decrease), with :math:`\pi_{K+1}` from
    ``lgamma`` (taken within 1e-12 relative in the exponent's scale).
    """
    log_tail = math.log(tail)
    K = max(int(math.ceil(lam)), 1)
    while True:
        lp = -lam + (K + 1) * math.log(lam) - math.lgamma(K + 2)
        lt = lp - math.log1p(-lam / (K + 2)) + 1e-12 * (lam + K + 2) * (1.0 + abs(math.log(lam)))
        if lt <= log_tail:
            return K, math.exp(lt)
        K += max(1, K // 256)


def terms(t: float, alpha: float, tail: float = TAIL) -> int:
    """Sparse products that :func:`uniformize` takes at time t and rate alpha."""
    if alpha == 0:
        return 0
    if not t * alpha <= MAX_RATE_TIME:          # inf included: far beyond any budget
        return sys.maxsize
    s, lam = _steps(t, alpha)
    return s * _terms(lam, tail / s)[0]


def _steps(t, alpha):
    total = t * alpha
    s = max(1, int(math.ceil(total / STEP)))
    return s, total / s


def products_needed(lap, t: float, tail: float = TAIL) -> int:
    """Sparse products (per block of columns) that :func:`metzler_heat` takes at time t."""
    return terms(t, rate(lap)[0], tail)


def metzler_heat(lap, t: float, G: np.ndarray, tail: float = TAIL):
    r""":math:`e^{-t\tilde L}G` for non-negative G on a Metzler Laplacian, with a bound of each entry.

    Parameters
    ----------
    lap : Laplacian
        Lumped mass and non-positive off-diagonal stiffness (:attr:`~spectral_igl.Laplacian.is_metzler`).
    t : float
    G : (n,) or (n, m) float, non-negative
        E.g. the discrete deltas :math:`B^{-1}e_i`.
    tail : float
        Allowed truncation, in total over the steps, relative to each column's maximum.

    Returns
    -------
    U : same shape as G
    abs_error : same shape as G
        :math:`|U - e^{-t\tilde L}G| \le` ``abs_error`` entry by entry: a proof (module notes).
    """
    if not lap.is_metzler:
        raise ValueError("metzler_heat needs a lumped mass and non-positive off-diagonal stiffness")
    alpha, P = rate(lap)
    return uniformize(P, alpha, t, G, tail)


def uniformize(P, alpha: float, t: float, G: np.ndarray, tail: float = TAIL):
    r""":math:`e^{-t\alpha(I - P)}G` for a non-negative, sub-stochastic P, with a bound of each entry.

    The engine of :func:`metzler_heat`, for a P built as there (:func:`rate`) or a principal
    submatrix of one: :math:`P_{RR}` is the uniformized Dirichlet operator
    :math:`I - B_{RR}^{-1}L_{RR}/\alpha` of a vertex set R (zero values outside R). Its rows sum
    to at most 1, which is all the module notes use (:math:`\|P^k v\|_\infty \le \|v\|_\infty`,
    the step operator non-negative with norm at most 1), so the bound is the same proof.

    Parameters
    ----------
    P : (n, n) scipy.sparse.csr_matrix
        Non-negative, rows summing to at most 1, diagonal at least 1/17.
    alpha : float
        The rate P was built with.
    t : float
    G : (n,) or (n, m) float, non-negative
    tail : float
        Allowed truncation, in total over the steps, relative to each column's maximum.

    Returns
    -------
    U : same shape as G
    abs_error : same shape as G
        :math:`|U - e^{-t\alpha(I - P)}G| \le` ``abs_error`` entry by entry: a proof.
    """
    G = np.asarray(G, dtype=float)
    if np.any(G < 0) or not np.all(np.isfinite(G)):
        raise ValueError("G must be finite and non-negative")
    one = G.ndim == 1
    V = G.reshape(G.shape[0], -1).copy()
    gmax = np.max(V, axis=0) if V.size else np.zeros(V.shape[1])
    if alpha == 0 or t == 0:
        err = np.zeros_like(V)
        return (V[:, 0], err[:, 0]) if one else (V, err)
    if not t * alpha <= MAX_RATE_TIME:
        raise ValueError(f"t * alpha = {t * alpha:.3g}: uniformization would take more than "
                         f"{MAX_RATE_TIME:.0e} sparse products")
    s, lam = _steps(t, alpha)
    K, step_tail = _terms(lam, tail / s)
    r = max(int(np.max(np.diff(P.indptr), initial=0)), 1)
    # entries of P within 33u: off-diagonal three roundings; diagonal 1 - x with x within 2u
    # relative, x / (1 - x) <= 16, and the subtraction's own rounding
    eps1 = 33.0 * U + _gamma(r) * (1.0 + 33.0 * U)
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
    # the steps apply the exact semigroup at t' = s lam / alpha, |t' - t| <= 4u t; for a Metzler
    # generator K(t') / K(t) lies in [e^{-|t'-t| alpha}, e^{|t'-t| alpha}] entrywise
    rho = math.expm1(s * math.log1p(delta) + 4.0 * U * t * alpha * (1.0 + 1e-6))
    # plus what underflow can lose: each of the s * (K + 1) products and sums of r + 1 terms
    # rounds an entry by at most one subnormal unit per term
    tiny = s * (K + 1) * (r + 2) * float(np.finfo(float).smallest_subnormal)
    err = rho * V / (1.0 - rho) + s * step_tail * gmax[None, :] * (1.0 + 1e-6) + tiny
    return (V[:, 0], err[:, 0]) if one else (V, err)
