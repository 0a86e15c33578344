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
small t, expensive where one poorly shaped element makes :math:`\alpha` large. There
:func:`chebyshev_blocks` takes the Chebyshev series of the same operator (about
:math:`\sqrt{t\alpha\log(1/\varepsilon)}` products), its bound proved in the B-norm instead
of entry by entry relative.
"""
from __future__ import annotations

import math
import sys

import numpy as np
import scipy.sparse as sp
from scipy.special import gammaln

from ..accuracy import UNIT_ROUNDOFF as U, rounding_gamma as _gamma
from ..filters import heat
from ..linalg.ldlt import chebyshev_series, poisson_series
from .polynomial import ChebyshevPlan

__all__ = ["metzler_heat", "uniformize", "uniformize_blocks", "rate", "rate_matrix", "spectral_top", "abs_radius", "products_needed", "terms", "STEP", "TAIL",
           "chebyshev_rate", "chebyshev_terms", "chebyshev_blocks", "poisson_terms"]

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


def rate_matrix(L, mass, offsets=None, alpha=None, nonnegative=True, top=None):
    """(alpha, P) of the stiffness L and lumped mass ``mass``: alpha = 17/16 max_j L_jj / mass_j
    and P = I - diag(mass)^-1 L / alpha, rounded as the module notes assume; (0, None) when
    every L_jj is 0. For a principal submatrix L_RR this is the Dirichlet operator of R.

    With ``offsets`` (increasing, from 0 to n, blocks of at least one row) L is block diagonal
    and each block b (rows ``offsets[b]:offsets[b+1]``) gets its own rate: alpha is then an
    array (0 for a block whose diagonal is 0, whose rows of P are the identity's) for
    :func:`uniformize_blocks`; a given ``alpha`` (one rate per block, each at least the
    17/16 max_j L_jj / mass_j of its block) is used instead. With ``nonnegative=False`` a given
    ``alpha`` need only be at least half of each block's :func:`spectral_top` (P may then have
    negative diagonal entries, its spectrum in [-1, 1 + drift / alpha]: :func:`chebyshev_blocks`,
    e.g. with rates from :func:`chebyshev_rate`); ``top``, each block's :func:`spectral_top` when
    the caller holds it already (the same check, without forming it again)."""
    L = sp.csr_matrix(L, dtype=float)
    d = L.diagonal() / mass
    if offsets is not None:
        offsets = np.asarray(offsets, dtype=np.int64)
        if alpha is None:
            alpha = 1.0625 * np.maximum.reduceat(d, offsets[:-1])
        elif nonnegative and not np.all(np.asarray(alpha) >= 1.0625 * np.maximum.reduceat(d, offsets[:-1])):
            raise ValueError("alpha must be at least 17/16 of each block's largest L_jj / mass_j")
        elif not nonnegative and not np.all(np.asarray(alpha) >= 0.5 * (spectral_top(L, mass, offsets)
                                                                    if top is None else np.asarray(top))):
            raise ValueError("alpha must be at least half of each block's spectral_top")
        alpha = np.asarray(alpha, dtype=float)
        scale = np.repeat(np.where(alpha > 0, alpha, 1.0), np.diff(offsets))
    else:
        top = float(np.max(d)) if d.size else 0.0
        if not top > 0:
            return 0.0, None
        alpha = scale = 1.0625 * top
    P = _row_scaled(L, -1.0 / (mass * scale))
    P.setdiag(1.0 - d / scale)
    P.eliminate_zeros()
    return alpha, P


def _row_scaled(L, a):
    """``diags(a) @ L`` of a csr L with no two entries at one place, as scipy's product forms
    it (each row's entries in the reverse of L's order, exact zeros left out, every entry
    a_i L_ij rounded once): the same arrays, so the same series' sums, without the general
    sparse product's pass."""
    n = L.shape[0]
    counts = np.diff(L.indptr)
    rows = np.repeat(np.arange(n), counts)
    rev = (L.indptr[:-1] + L.indptr[1:] - 1).astype(np.int64)[rows] - np.arange(L.nnz)
    data = L.data[rev] * a[rows]
    keep = data != 0
    if keep.all():
        indices, indptr = L.indices[rev], L.indptr.copy()
    else:
        data, indices = data[keep], L.indices[rev[keep]]
        indptr = np.zeros(n + 1, dtype=L.indptr.dtype)
        np.cumsum(np.bincount(rows[keep], minlength=n), out=indptr[1:])
    return sp.csr_matrix((data, indices, indptr), shape=L.shape)


def spectral_top(L, mass, offsets=None, sums=None) -> np.ndarray:
    r"""Per block of the block-diagonal, symmetric L (``offsets`` as in :func:`rate_matrix`; one
    block when omitted): a proved upper bound of the spectral radius of
    :math:`B^{-1}|L|` (B = diag(``mass``)), so of the largest eigenvalue of :math:`B^{-1}L`.

    The smaller of two Gershgorin bounds, :math:`\max_i \sum_j |L_{ij}|/B_{ii}` (the rows of
    :math:`B^{-1}|L|`) and :math:`\max_i \sum_j |L_{ij}|/\sqrt{B_{ii}B_{jj}}` (the rows of the
    similar, symmetric :math:`B^{-1/2}|L|B^{-1/2}`), which is well below the first (and
    below twice the largest :math:`L_{ii}/B_{ii}`) where the masses vary. Each term is
    formed with at most 4 roundings and each row summed over at most r terms, so the computed
    maxima times :math:`(1 + \gamma_{r+8})(1 + 4u)` are proofs. ``sums``: :func:`row_sums` of
    the same arguments, when the caller holds them (:func:`abs_radius` reads the same).
    """
    offsets, d, off_row, off_sym, grow = row_sums(L, mass, offsets) if sums is None else sums
    start = offsets[:-1]
    top = np.minimum(np.maximum.reduceat(d + off_row, start), np.maximum.reduceat(d + off_sym, start))
    return top * grow


def row_sums(L, mass, offsets):
    """(offsets, L_jj / B_jj, sum_k!=j |L_jk| / B_jj, sum_k!=j |L_jk| / sqrt(B_jj B_kk), the factor
    (1 + gamma_{r+8})(1 + 4u) that makes a maximum of sums of these terms a proof)."""
    L = sp.csr_matrix(L, dtype=float)
    n = L.shape[0]
    offsets = np.asarray([0, n] if offsets is None else offsets, dtype=np.int64)
    rows = np.repeat(np.arange(n), np.diff(L.indptr))
    a = np.where(rows == L.indices, 0.0, np.abs(L.data))
    d = np.abs(L.diagonal()) / mass
    off_row = np.bincount(rows, a, minlength=n) / mass
    off_sym = np.bincount(rows, a / np.sqrt(mass[rows] * mass[L.indices]), minlength=n)
    r = int(np.max(np.diff(L.indptr), initial=0))
    return offsets, d, off_row, off_sym, (1.0 + _gamma(r + 8)) * (1.0 + 4.0 * U)


def abs_radius(L, mass, offsets, alpha, sums=None) -> np.ndarray:
    r"""Per block (as in :func:`spectral_top`): a proved upper bound of
    :math:`\|\,|P|\,\|_B = \rho(|P|)` for :math:`P = I - B^{-1}L/\alpha_b` (``alpha`` one rate
    per block, at least half its :func:`spectral_top`): :math:`|P|` is self-adjoint in the B
    inner product and non-negative, so its norm is its spectral radius, at most the smaller of
    the largest row sums of :math:`|P|` and of :math:`B^{1/2}|P|B^{-1/2}`. About 1 where
    neighbours' masses are alike (:func:`chebyshev_blocks`' rounding grows with it).

    With :math:`x_j = L_{jj}/(B_{jj}\alpha) \le 2`, :math:`|1 - x_j|` is formed within
    :math:`4u(1 + x_j)`, added to each row; the rest as in :func:`spectral_top` (``sums`` too)."""
    offsets, d, off_row, off_sym, grow = row_sums(L, mass, offsets) if sums is None else sums
    alpha = np.repeat(np.asarray(alpha, dtype=float), np.diff(offsets))
    x = d / alpha
    diag = np.abs(1.0 - x) + 4.0 * U * (1.0 + x)
    start = offsets[:-1]
    return np.minimum(np.maximum.reduceat(diag + off_row / alpha, start),
                      np.maximum.reduceat(diag + off_sym / alpha, start)) * grow


def _terms(lam, tail):
    """:func:`_terms_many` of one Poisson mean: (K, its tail's bound)."""
    K, tau = _terms_many([lam], tail)
    return int(K[0]), float(tau[0])


def _terms_many(lams, tail):
    r"""Smallest K with P[Poisson(lam) > K] <= tail for every (positive) lam, and those tails'
    bounds, as arrays.

    :math:`\Pr[X > K] \le \pi_{K+1}/(1 - \lambda/(K+2))` for :math:`K + 2 > \lambda` (the
    ratios :math:`\pi_{k+1}/\pi_k = \lambda/(k+1)` decrease), with :math:`\pi_{K+1}` from
    ``gammaln`` (taken within 1e-12 relative in the exponent's scale).
    """
    lams = np.asarray(lams, dtype=float)
    log_tail = np.broadcast_to(np.log(np.asarray(tail, dtype=float)), lams.shape)
    K = np.maximum(np.ceil(lams), 1.0)
    out_k, out_tau = np.zeros(lams.size, dtype=np.int64), np.zeros(lams.size)
    todo = np.arange(lams.size)
    # K runs through k, k + max(1, floor(k / 256)), ...: the next _TERMS_AHEAD of them are
    # tried at once (the first that meets the tail is the one a try at a time finds)
    while todo.size:
        k = np.empty((todo.size, _TERMS_AHEAD))
        k[:, 0] = K[todo]
        for i in range(1, _TERMS_AHEAD):
            k[:, i] = k[:, i - 1] + np.maximum(1.0, np.floor(k[:, i - 1] / 256))
        lam = lams[todo]
        log_lam = np.log(lam)[:, None]
        lam = lam[:, None]
        lp = -lam + (k + 1) * log_lam - gammaln(k + 2)
        lt = lp - np.log1p(-lam / (k + 2)) + 1e-12 * (lam + k + 2) * (1.0 + np.abs(log_lam))
        ok = lt <= log_tail[todo][:, None]
        hit = ok.any(axis=1)
        first = np.argmax(ok, axis=1)[hit]
        out_k[todo[hit]] = k[hit, first]
        out_tau[todo[hit]] = np.exp(lt[hit, first])
        last = k[:, -1]
        K[todo] = last + np.maximum(1.0, np.floor(last / 256))
        todo = todo[~hit]
    return out_k, out_tau


#: candidate numbers of terms :func:`_terms_many` tries at once
_TERMS_AHEAD = 32


def terms(t: float, alpha: float, tail: float = TAIL) -> int:
    """Sparse products that :func:`uniformize` takes at time t and rate alpha."""
    if alpha == 0:
        return 0
    if not t * alpha <= MAX_RATE_TIME:          # inf included: far beyond any budget
        return sys.maxsize
    s, lam = _steps(t, alpha)
    return s * _terms(lam, tail / s)[0]


def poisson_terms(t: float, alpha, tail=TAIL) -> np.ndarray:
    """:func:`terms` of many rates (and tails, one or one per rate) at once (array; 0 where a
    rate is 0)."""
    alpha = np.asarray(alpha, dtype=float)
    tail = np.broadcast_to(np.asarray(tail, dtype=float), alpha.shape)
    lam = t * alpha
    s = np.maximum(1.0, np.ceil(lam / STEP))
    out = np.zeros(alpha.size, dtype=np.int64)
    pos = lam > 0
    if pos.any():
        out[pos] = s[pos].astype(np.int64) * _terms_many(lam[pos] / s[pos], tail[pos] / s[pos])[0]
    return out


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
    V = G.reshape(G.shape[0], -1)
    if alpha == 0 or t == 0:
        V = V.copy()
        err = np.zeros_like(V)
        return (V[:, 0], err[:, 0]) if one else (V, err)
    V, rel, add, _ = uniformize_blocks(P, [alpha], [0, V.shape[0]], t, V, tail)
    err = rel[0] * V + add
    return (V[:, 0], err[:, 0]) if one else (V, err)


def _leading(P, offsets, need, K, first):
    """(rows of terms first..K, head): the rows of the blocks still summing at each term, a
    leading part of the block-diagonal P when the blocks come in decreasing order of their
    terms ``need`` (its columns are those rows too), all of P otherwise; head(rows) is the
    leading rows x rows of P, formed only when asked (the compiled series reads rows alone)."""
    leading = bool(np.all(np.diff(need) <= 0))
    n = P.shape[0]
    rows = [int(offsets[np.count_nonzero(need >= k)]) if leading else n for k in range(first, K + 1)]
    heads = {}

    def head(r):
        if r not in heads:
            end = int(P.indptr[r])
            heads[r] = P if r == n else sp.csr_matrix((P.data[:end], P.indices[:end], P.indptr[:r + 1]), shape=(r, r))
        return heads[r]

    return rows, head


def uniformize_blocks(P, alpha, offsets, t: float, G: np.ndarray, tail: float = TAIL):
    r""":func:`uniformize` on a block-diagonal P whose blocks have their own rates, at once.

    Block b holds rows ``offsets[b]:offsets[b+1]`` of P and G; P has no entry coupling two
    blocks, and block b was built with the rate ``alpha[b]`` (:func:`rate_matrix` with
    ``offsets``), so each block's series is its own operator's
    :math:`e^{-t\alpha_b(I - P_b)}` and its bound the proof of the module notes with that
    block's Poisson tail. All blocks take the same number of steps and terms (the largest any
    needs; more terms only shrink a tail). One sparse product per term serves every block: the
    independent regions of many sources in one call.

    Parameters
    ----------
    P : (n, n) scipy.sparse.csr_matrix
        Non-negative, rows summing to at most 1, diagonal at least 1/17, block diagonal.
    alpha : (nb,) float
        The rate of each block (0 for a block whose operator is 0: P's rows are then those of
        the identity).
    offsets : (nb + 1,) int
        Increasing, from 0 to n: every block holds at least one row.
    t : float
    G : (n, m) float, non-negative
    tail : float
        Allowed truncation, in total over the steps, relative to each block's column maximum.

    Returns
    -------
    V : (n, m) float
    rel : (nb,) float
    add : (n, m) float
        :math:`|V - e^{-t\alpha_b(I - P_b)}G_b| \le` ``rel[b] * V + add`` on the rows of block
        b, entry by entry: a proof (``add`` is each block column's truncation, the same down the
        block, plus the underflow allowance).
    work : int
        Stored entries of P multiplied in all (a block stops at its own number of terms when the
        blocks come in decreasing order of rate).
    """
    G = np.asarray(G, dtype=float)
    alpha = np.asarray(alpha, dtype=float)
    offsets = np.asarray(offsets, dtype=np.int64)
    if not np.all(np.isfinite(alpha * t)) or np.any(alpha * t > MAX_RATE_TIME):
        raise ValueError(f"t * alpha up to {np.max(alpha) * t:.3g}: uniformization would take more than "
                         f"{MAX_RATE_TIME:.0e} sparse products")
    counts = np.diff(offsets)
    gmax = np.maximum.reduceat(G, offsets[:-1], axis=0)
    s = max([_steps(t, a)[0] if a > 0 else 1 for a in alpha.tolist()] or [1])
    lams = [t * a / s for a in alpha.tolist()]       # as _steps rounds it
    positive = np.array(lams) > 0
    need, taus = np.zeros(len(lams), dtype=np.int64), np.zeros(len(lams))
    if positive.any():
        need[positive], taus[positive] = _terms_many(np.array(lams)[positive], tail / s)
    K = int(need.max(initial=0))
    r = max(int(np.max(np.diff(P.indptr), initial=0)), 1)
    lam = np.array(lams)
    single = alpha.size == 1
    lam_rows = float(lam[0]) if single else np.repeat(lam, counts)[:, None]
    heads, head = _leading(P, offsets, need, K, 1)

    V = G.copy()
    work = s * sum(int(P.indptr[rows]) for rows in heads)
    for _ in range(s):
        # term k, c_k P^k V with c_k = e^-lam lam^k / k!, as (lam / k) P (term k - 1): the same
        # roundings as the coefficient and the products formed apart (module notes)
        q = V * (float(math.exp(-lams[0])) if single else
                 np.repeat([math.exp(-x) for x in lams], counts)[:, None])
        W = np.ascontiguousarray(q)
        if not (K >= 1 and poisson_series(P, offsets, lam, [0] + heads, W)):
            W = q.copy()
            for k, rows in enumerate(heads, start=1):
                q = head(rows) @ q[:rows]
                q *= lam_rows / k if single else lam_rows[:rows] / k
                W[:rows] += q
        V = W
    # each step's relative rounding (module notes), with K terms for every block
    eps1 = 33.0 * U + _gamma(r) * (1.0 + 33.0 * U)
    delta = math.expm1(K * math.log1p(eps1) + math.log1p(_gamma(2 * K) + 4 * U) + math.log1p(U)) \
        + _gamma(K + 1)
    delta *= 1.0 + 1e-6
    # the steps apply the exact semigroup at t' = s lam / alpha, |t' - t| <= 4u t; for a Metzler
    # generator K(t') / K(t) lies in [e^{-|t'-t| alpha}, e^{|t'-t| alpha}] entrywise
    rho = np.expm1(s * math.log1p(delta) + 4.0 * U * t * alpha * (1.0 + 1e-6))
    rel = rho / (1.0 - rho)
    # plus what underflow can lose: each of the s * (K + 1) products and sums of r + 1 terms
    # rounds an entry by at most one subnormal unit per term
    tiny = s * (K + 1) * (r + 3) * float(np.finfo(float).smallest_subnormal)
    trunc = s * taus[:, None] * gmax * (1.0 + 1e-6) + tiny
    add = np.repeat(trunc, counts, axis=0)
    return V, rel, add, work


# ----------------------------------------------------------------------------- Chebyshev
#: a Chebyshev rate (:func:`chebyshev_rate`) is an integer below 2^RATE_BITS times a power of 2
RATE_BITS = 6
#: largest k of the spectral margin 2^-k of :func:`chebyshev_blocks` (so the interval's ends stay exact)
MARGIN_BITS = 40
_PLANS: dict = {}


def chebyshev_rate(least):
    """The smallest rates at least ``least`` (array, positive) of the form m 2^e with m an
    integer below 2^:data:`RATE_BITS` (at most 1/32 above): the ends of the interval of
    :func:`chebyshev_blocks` are then exact, and the series of nearby regions are shared."""
    least = np.asarray(least, dtype=float)
    e = np.floor(np.log2(least)) - (RATE_BITS - 1)
    return np.ldexp(np.ceil(np.ldexp(least, -e.astype(int))), e.astype(int))


def _margin(alpha, drift):
    """k with 2^-k >= drift / alpha (the spectral margin of P), or 0 when none up to 1/2."""
    if drift <= 0:
        return MARGIN_BITS
    k = int(math.floor(math.log2(alpha / drift)))
    return min(k, MARGIN_BITS) if k >= 1 and math.ldexp(1.0, -min(k, MARGIN_BITS)) * alpha >= drift else 0


def _plan(t, alpha, k, tol):
    """Chebyshev coefficients of e^{-ts} on [-alpha 2^-k, alpha (2 + 2^-k)] (exact ends) with
    their proved bound (:class:`~.polynomial.ChebyshevPlan`), cached."""
    key = (t, alpha, k, tol)
    if key not in _PLANS:
        if len(_PLANS) > 4096:
            _PLANS.clear()
        a = -math.ldexp(alpha, -k)
        plan = ChebyshevPlan(None, heat(t), a, 2.0 * alpha - a, tol)
        _PLANS[key] = (plan.c, plan.scalar_error + plan.rounding)
    return _PLANS[key]


def _recurrence_rounding(c, delta):
    """(A1, A2) of :func:`chebyshev_blocks`' notes for the coefficients c and the local
    rounding delta: the computed sum is within A1 ||g||_B + A2 zeta of p(X) g."""
    k = np.arange(c.size, dtype=float)
    h = 0.5 * k * (k + 1.0)
    if not delta * h[-1] < 0.5:
        return np.inf, np.inf
    grow = h / (1.0 - delta * h)
    a = np.abs(c)
    g = _gamma(c.size + 1)
    A1 = (1.0 + g) * delta * float(a @ grow) + g * float(a.sum())
    A2 = (1.0 + g) * float(a @ grow)
    return A1 * (1.0 + 1e-6), A2 * (1.0 + 1e-6)


def _local_rounding(P, omega=1.0):
    r"""(delta of :func:`chebyshev_blocks`' notes for :math:`\rho(|P|) \le` ``omega`` (array or
    float), r) for P's widest row (one more than the given matrix's, so that L's pattern serves
    for its P, whose diagonal is always stored)."""
    r = int(np.max(np.diff(P.indptr), initial=0)) + 1
    eta = math.expm1(math.log1p(33.0 * U + _gamma(r) * (1.0 + 33.0 * U)) + 2.0 * math.log1p(U))
    diag = 4.2 * U * (1.0 + U) ** 2 * (1.0 + _gamma(r))
    omega = np.asarray(omega, dtype=float)
    return (2.0 * (eta * omega + diag) + 2.0 * U * ((1.0 + eta) * omega + diag) + U) * (1.0 + 1e-6), r


def chebyshev_terms(P, alpha, t: float, eps, drift: float, omega):
    r"""Per block: (degree, the proved relative bound of :func:`chebyshev_blocks`' series) for a
    B-norm error ``eps`` relative to the column's, or degree -1 where it cannot be met (the
    rounding floor, or no spectral margin).

    Parameters
    ----------
    P : csr_matrix
        From :func:`rate_matrix` with the rates ``alpha`` (or L: only its widest row is used).
    alpha : (nb,) float
        From :func:`chebyshev_rate`, at least half of each block's :func:`spectral_top`.
    t : float
    eps : (nb,) float
    drift : float
        A bound of :math:`\max_j |(L\mathbf 1)_j| / B_{jj}` (P's spectrum is at most
        :math:`1 + \text{drift}/\alpha`).
    omega : (nb,) float
        Each block's :func:`abs_radius` at its rate.
    """
    delta = np.broadcast_to(_local_rounding(P, omega)[0], (len(alpha),))
    out = np.full(len(alpha), -1, dtype=np.int64)
    bounds = [None] * len(alpha)
    for b, (a, e) in enumerate(zip(np.asarray(alpha, float).tolist(), np.asarray(eps, float).tolist())):
        k = _margin(a, drift) if a > 0 else 0
        if not k or not e > 0:
            continue
        tol = 10.0 ** (math.floor(2.0 * math.log10(e)) / 2.0)     # shared by nearby eps
        c, err = _plan(t, a, k, 0.5 * tol)
        A1, A2 = _recurrence_rounding(c, float(delta[b]))
        if err + A1 <= e:
            out[b] = c.size - 1
            bounds[b] = (c, k, err + A1, A2)
    return out, bounds


def chebyshev_blocks(P, alpha, offsets, t: float, G: np.ndarray, mass, plans, volume):
    r""":math:`e^{-t\alpha_b(I - P_b)}G_b` on a block-diagonal P by Chebyshev series, each block
    with its own rate and degree, with a proved bound in the B-norm and per entry.

    For a block with rate :math:`\alpha` and exact
    :math:`P = I - B^{-1}L/\alpha` (B the block's ``mass``, L symmetric with non-positive
    off-diagonal entries), P is self-adjoint in the B inner product. Write
    :math:`L = L_0 + \mathrm{diag}(L\mathbf 1)` with :math:`L_0` a principal submatrix of a
    matrix with zero row sums and non-positive off-diagonal entries, so positive semi-definite:
    the spectrum of :math:`A = B^{-1}L` is at least :math:`-\max_j|(L\mathbf 1)_j|/B_{jj}
    \ge -\text{drift}` and at most :func:`spectral_top` :math:`\le 2\alpha`
    (:func:`rate_matrix` checks it), so P's lies in :math:`[-1, 1 + \text{drift}/\alpha]
    \subset [-\sigma, \sigma]`, :math:`\sigma = 1 + 2^{-k}`, and A's in
    :math:`[a, b] = [-\alpha 2^{-k}, \alpha(2 + 2^{-k})]` (exact floats: α from
    :func:`chebyshev_rate`). With :math:`X = -P/\sigma = (2A - a - b)/(b - a)` and p the
    Chebyshev expansion of :math:`e^{-ts}` on [a, b] (:class:`~.polynomial.ChebyshevPlan`:
    its proved :math:`\max_{[a,b]}|e^{-ts} - p|` plus its coefficients' rounding, ε₀),
    :math:`\|e^{-tA}g - p(A)g\|_B \le \varepsilon_0\|g\|_B`.

    **Rounding.** The recurrence :math:`\hat t_{k+1} = \mathrm{fl}(\mathrm{fl}(\mathrm{fl}(
    \mathrm{fl}(-2/\sigma)\hat P)\hat t_k) - \hat t_{k-1})` (the factor taken into P's
    entries, each rounded once) with :math:`|\hat P - P| \le 33u|P| + 4.2u I` (the diagonal
    :math:`1 - x_j`, :math:`x_j = L_{jj}/(B_{jj}\alpha) \le 2`, may cancel) and
    rows of at most r entries has local errors :math:`|f_k| \le \tfrac{2}{\sigma}(\eta|P| +
    \eta' I)|\hat t_k| + u(\tfrac2\sigma((1+\eta)|P| + \eta' I)|\hat t_k| + |\hat t_{k-1}|)
    + \zeta_0`, :math:`1 + \eta = (1 + 33u + \gamma_r(1+33u))(1+u)^2`,
    :math:`\eta' = 4.2u(1+u)^2(1+\gamma_r)`, :math:`\zeta_0` the underflow of
    r + 4 operations per entry; :math:`|P|` is non-negative and self-adjoint in the B inner
    product, so :math:`\|\,|P||v|\,\|_B \le \omega\|v\|_B` (:func:`abs_radius`), and
    :math:`\|f_k\|_B \le \delta\max(\|\hat t_k\|_B, \|\hat t_{k-1}\|_B) + \zeta`,
    :math:`\delta = 2(\eta\omega + \eta') + 2u((1+\eta)\omega + \eta') + u` (σ ≥ 1),
    :math:`\zeta = \zeta_0\sqrt{\sum B}`. The errors
    :math:`e_k = \hat t_k - T_k(X)g` obey the same recurrence driven by :math:`f_k`, so
    :math:`e_k = \sum_{j<k}U_{k-1-j}(X)f_j` with :math:`\|U_m(X)\|_B \le m + 1`, and with
    :math:`h_k = k(k+1)/2`, :math:`\|e_k\|_B \le E_k = h_k(\delta\|g\|_B + \zeta)/(1 - \delta
    h_k)` (:math:`\|T_k(X)\|_B \le 1`). The sum :math:`\sum c_k\hat t_k` adds
    :math:`\gamma_{m+1}\sum|c_k|(\|g\|_B + E_k)`. So the computed V is within
    :math:`(\varepsilon_0 + A_1)\|g\|_B + A_2\zeta` of :math:`e^{-tA}g` in the B-norm
    (:func:`chebyshev_terms`), and so is :math:`V^+` (the exact heat is non-negative), and
    entry j within that over :math:`\sqrt{B_{jj}}`.

    Parameters
    ----------
    P : (n, n) csr_matrix
        Block diagonal, from :func:`rate_matrix` with the rates ``alpha``, ``offsets`` and
        ``nonnegative=False``.
    alpha : (nb,) float
    offsets : (nb + 1,) int
    t : float
    G : (n, w) float, non-negative
    mass : (n,) float
        The rows' lumped masses (P's B).
    plans : list
        Per block, from :func:`chebyshev_terms` (none ``None``).
    volume : (nb,) float
        An upper bound of each block's :math:`\sum B_{jj}`.

    Returns
    -------
    V : (n, w) float
        Non-negative.
    add : (n, w) float
        Proved bound of each entry's error.
    bnorm : (nb, w) float
        Proved bound of each block column's error in the B-norm.
    work : int
        Stored entries of P multiplied.
    """
    offsets = np.asarray(offsets, dtype=np.int64)
    counts = np.diff(offsets)
    degree = np.array([p[0].size - 1 for p in plans])
    K = int(degree.max(initial=0))
    C = np.zeros((len(plans), K + 1))
    for b, p in enumerate(plans):
        C[b, :p[0].size] = p[0]
    # X = -P / sigma, the factor -2 / sigma (rounded once) taken into P's entries (rounded once)
    scale = np.repeat([-2.0 / (1.0 + math.ldexp(1.0, -p[1])) for p in plans], counts)
    P = sp.csr_matrix((P.data * np.repeat(scale, np.diff(P.indptr)), P.indices, P.indptr), shape=P.shape)
    heads, head = _leading(P, offsets, degree, K, 2)

    t0 = np.array(G, dtype=float)
    W = np.repeat(C[:, 0], counts)[:, None] * t0
    work = 0
    if K >= 1:
        t1 = P @ t0
        t1 *= 0.5
        W += np.repeat(C[:, 1], counts)[:, None] * t1
        work += P.nnz
    work += sum(int(P.indptr[rows]) for rows in heads)
    if not (K >= 2 and chebyshev_series(P, offsets, C, [0, 0] + heads, t1, t0, W)):
        for k, rows in enumerate(heads, start=2):
            q = head(rows) @ t1[:rows]
            new = t0[:rows]
            np.subtract(q, new, out=new)          # t_k = 2X t_{k-1} - t_{k-2}, in t_{k-2}'s place
            t0, t1 = t1, t0
            np.multiply(new, np.repeat(C[:, k], counts)[:rows, None], out=q)
            W[:rows] += q
    del heads
    np.maximum(W, 0.0, out=W)
    _, r = _local_rounding(P)
    zeta = (r + 4) * float(np.finfo(float).smallest_subnormal) * np.sqrt(np.asarray(volume, float))
    norm = np.sqrt(np.add.reduceat(mass[:, None] * G * G, offsets[:-1], axis=0)) \
        * (1.0 + _gamma(np.max(counts, initial=1) + 4))
    rel = np.array([p[2] for p in plans])[:, None]
    absolute = (np.array([p[3] for p in plans]) * zeta)[:, None]
    bnorm = (rel * norm + absolute) * (1.0 + 4.0 * U)
    add = np.repeat(bnorm, counts, axis=0) / np.sqrt(mass)[:, None] * (1.0 + 4.0 * U)
    return W, add, bnorm, work
