r"""Shared pieces of the approximation methods: spectral intervals, norms, certified sup-errors.

Two kinds of scalar error bounds are proved here:

- :func:`certified_sup`: :math:`\max_{[a,b]}|e|` for :math:`e = \varphi - r` from samples
  and a rigorous bound of :math:`|e''|` between them (linear interpolation error
  :math:`h^2\max|e''|/8`), plus an allowance for the rounding of each sample. The bound of
  :math:`|e''|` is :func:`interpolated_d2` when :math:`e''` can be evaluated: sampled at
  Chebyshev points of each interval, so it sees the cancellation between φ and r that a
  bound of :math:`|\varphi''| + |r''|` cannot;
- :func:`ellipse_tails`: the tail :math:`\sum_{k>m}|c_k|` of the Chebyshev series of an
  analytic function on [a, b], from its maximum on a Bernstein ellipse
  (:math:`|c_k| \le 2M\rho^{-k}`).

Both need a bound of the filter that only the built-in filters provide
(:func:`filter_d2`, :func:`filter_logmax`); for a user filter the sampled
:func:`sup_error` is used and the result says ``"estimate"``.
"""
from __future__ import annotations

import numpy as np
import scipy.fft

from ..laplacian import Laplacian, make_laplacian, mass_ratio
from ..linalg import lambda_min_positive, lambda_min_positive_kind

EPS = np.finfo(float).eps


# ----------------------------------------------------------------------------- norms
def bnorm(lap: Laplacian, f: np.ndarray) -> np.ndarray:
    """B-norm of each column; (n,) -> scalar array, (n, k) -> (k,)."""
    Bf = lap.B @ f
    return np.sqrt(np.maximum(np.real(np.sum(np.conj(f) * Bf, axis=0)), 0.0))


def inv_bnorm_upper(lap: Laplacian, g: np.ndarray) -> np.ndarray:
    r"""Upper bound of :math:`\|B^{-1}g\|_B = (g^* B^{-1} g)^{1/2}` without a solve.

    :math:`g^*B^{-1}g \le g^*D^{-1}g / c` with c from :func:`mass_ratio`.
    """
    d = lap.mass if g.ndim == 1 else lap.mass[:, None]
    return np.sqrt(np.real(np.sum(np.abs(g) ** 2 / d, axis=0)) / mass_ratio(lap))


def abs_bnorm(lap: Laplacian, e: np.ndarray) -> np.ndarray:
    r""":math:`\sqrt{|e|^\top|B|\,|e|} \ge \|x\|_B` for every x with :math:`|x| \le e`
    entrywise (the B-norm of a vector known only through a bound of each entry)."""
    e = np.abs(e)
    absB = lap.cache.fetch("basis", "abs_mass", lambda: abs(lap.B).tocsr())
    return np.sqrt(np.sum(e * (absB @ e), axis=0)) * (1.0 + 4 * EPS)


# ----------------------------------------------------------------------------- rounding of P0
def gamma(k) -> np.ndarray:
    r""":math:`\gamma_k = ku/(1 - ku)`, u = ε/2: the relative rounding of k chained flops
    (Higham, *Accuracy and Stability of Numerical Algorithms*, §3.1)."""
    ku = np.asarray(k, dtype=float) * (0.5 * EPS)
    return ku / (1.0 - ku)


def _projection_constants(lap: Laplacian):
    r"""Per vertex: :math:`\hat V` of its component, the relative error of
    :math:`\hat z^2 = 1/\hat V` (each factor of ``component_basis``), the component's size and
    the longest row of B."""
    def build():
        absB = abs(lap.B).tocsr()
        k = int(np.max(np.diff(absB.indptr))) if lap.n else 1
        comp = lap.components
        size = np.bincount(comp, minlength=lap.n_components)[comp]
        Z = lap.component_basis()
        vhat = 1.0 / np.asarray(Z.multiply(Z).sum(axis=1)).ravel()          # 1 / z_c^2
        absvol = np.bincount(comp, weights=np.asarray(absB.sum(axis=1)).ravel(),
                             minlength=lap.n_components)[comp]
        # V^ = 1^T (B 1) (row sums of k terms, then a sum of n_c terms), z = 1/sqrt(V^)
        # with two more roundings, and z^2 = 1/V^ itself rounded once more in vhat
        theta = gamma(k + size + 8) * absvol / vhat
        theta = np.minimum(theta, 0.5)
        alpha = theta / (2.0 * (1.0 - theta)) + gamma(3)
        return vhat * (1.0 - theta), alpha, size, k
    return lap.cache.fetch("basis", "projection_rounding", build)


def mass_sum_rounding(lap: Laplacian):
    r"""``(row, vol)``: per vertex, bounds of the relative rounding of ``lap.mass`` (the row
    sums of B, k terms each: :math:`\gamma_k (|B|1)_i / m_i`) and of
    :meth:`~spectral_igl.laplacian.Laplacian.component_volume` (those row sums summed over the
    :math:`n_c` vertices of the component: :math:`\gamma_{k + n_c}\,1_c^\top|B|1 / \hat V_c`)."""
    absB = abs(lap.B).tocsr()
    k = int(np.max(np.diff(absB.indptr))) if lap.n else 1
    comp = lap.components
    size = np.bincount(comp, minlength=lap.n_components)[comp]
    rowabs = np.asarray(absB.sum(axis=1)).ravel()
    absvol = np.bincount(comp, weights=rowabs, minlength=lap.n_components)[comp]
    return gamma(k) * rowabs / lap.mass, gamma(k + size) * absvol / lap.component_volume()


def projection_rounding(lap: Laplacian, y_abs: np.ndarray, with_mass: bool) -> np.ndarray:
    r"""Entrywise bound of :math:`|Z\,\mathrm{fl}(Z^\top y) - P_0f|` as computed by
    :meth:`~spectral_igl.laplacian.Laplacian.component_basis` (the projection onto the
    constants of each component).

    ``with_mass``: y = fl(Bf) and ``y_abs`` = :math:`|B||f|`; else y = g and ``y_abs`` = |g|.
    With :math:`\hat z = z(1 + \alpha)` the computed basis, the products and the sum of the
    :math:`n_c` terms of a component (Higham §3.1), and the k-term rows of Bf,

    .. math:: |u_i - (P_0f)_i| \le \bigl((1 + \alpha)^2(1 + \gamma_1)(1 + \gamma_{n_c})
              (1 + \gamma_k) - 1\bigr)\, \frac{1_c^\top|B||f|}{V_c}:

    the allowance is scaled to the sum of the magnitudes of what cancels, not to the result.
    """
    vlow, alpha, size, k = _projection_constants(lap)
    rel = (1.0 + alpha) ** 2 * (1.0 + gamma(1)) * (1.0 + gamma(size)) * (1.0 + gamma(k if with_mass else 0)) - 1.0
    S = lap.component_sum(np.abs(y_abs))
    if S.ndim == 2:
        return (rel / vlow)[:, None] * S * (1.0 + 4 * EPS)
    return rel / vlow * S * (1.0 + 4 * EPS)


def abs_mass_apply(lap: Laplacian, f: np.ndarray) -> np.ndarray:
    """:math:`|B||f|` (the magnitudes summed in each entry of Bf)."""
    absB = lap.cache.fetch("basis", "abs_mass", lambda: abs(lap.B).tocsr())
    return absB @ np.abs(f)


def mass_rounding(lap: Laplacian, f: np.ndarray) -> np.ndarray:
    r"""Entrywise bound of :math:`|\mathrm{fl}(Bf) - Bf| \le \gamma_k|B||f|` (k: the longest row)."""
    return gamma(_projection_constants(lap)[3]) * abs_mass_apply(lap, f)


def filter_sup(filt, a: float, b: float, target: float = 0.0):
    r"""``(M, proved)``: a bound of :math:`\max_{[a, b]}|\varphi|`, proved
    (:func:`certified_sup`, refined down to ``target``/1000) for the built-in filters,
    sampled (:func:`sup_error`) otherwise."""
    d2 = filter_d2(filt)
    with np.errstate(all="ignore"):
        if d2 is not None:
            return certified_sup(lambda s: (filt(s), np.abs(filt(s))), d2, a, b, target, n=200), True
        return sup_error(filt, a, b, n=500), False


def inv_bnorm_lower(lap: Laplacian, g: np.ndarray) -> np.ndarray:
    r"""Lower bound of :math:`\|B^{-1}g\|_B` without a solve, or None.

    For B entrywise non-negative with row sums D, :math:`D^{-1}B` is stochastic, so
    :math:`B \le D` in the Loewner order (spectral radius 1) and
    :math:`g^*B^{-1}g \ge g^*D^{-1}g`. None for a B with negative entries.
    """
    if not nonnegative_mass(lap):
        return None
    d = lap.mass if g.ndim == 1 else lap.mass[:, None]
    return np.sqrt(np.real(np.sum(np.abs(g) ** 2 / d, axis=0)))


def nonnegative_mass(lap: Laplacian) -> bool:
    """Whether B is entrywise non-negative (every lumped and linear-FEM mass), cached."""
    return lap.cache.fetch("bound", "nonnegative_mass", lambda: bool(lap.lumped or (lap.B.data >= 0).all()))


# ----------------------------------------------------------------------------- certified sup
def sample_grid(a: float, b: float, n: int = 6000) -> np.ndarray:
    """Sorted sample points of [a, b]: linear, geometric from a (or from 1e-14 b) and Chebyshev."""
    lin = np.linspace(a, b, n)
    lo = a if a > 0 else b * 1e-14
    geo = np.geomspace(lo, b, n) if b > lo else np.array([b])
    ch = a + (b - a) * 0.5 * (1 - np.cos(np.linspace(0, np.pi, n)))
    x = np.unique(np.concatenate([[a, b], lin, geo, ch]))
    return x[(x >= a) & (x <= b)]


def sup_error(err, a: float, b: float, n: int = 6000, rounds: int = 8, safety: float = 2.0,
              scale: float | None = None, max_points: int = 200_000) -> float:
    r"""Upper bound of :math:`\max_{x \in [a, b]} |e(x)|` from a refined sample.

    ``err(x)`` evaluates the error on an array. The sample (linear, geometric and
    Chebyshev points, about 3n) is bisected wherever the error changes by more than 5% of
    its maximum between neighbours (variations below the rounding level
    :math:`10^3 \varepsilon \cdot` ``scale`` are ignored), until it is resolved; then
    :math:`\max_i (\max(|e_i|, |e_{i+1}|) + |e_{i+1} - e_i|)` plus the rounding level is
    multiplied by ``safety``. The error functions met here (differences of analytic
    functions and rational or polynomial approximants) are smooth on the scale of a resolved
    grid, so the factor 2 covers what lies between samples; the tests check the result
    against dense ground truth on many shapes and filters.
    """
    x = sample_grid(a, b, n)
    floor = 0.0
    for it in range(rounds + 1):
        with np.errstate(all="ignore"):
            e = np.abs(err(x))
        if not np.all(np.isfinite(e)):
            return np.inf
        if it == 0:
            floor = 1e3 * EPS * (scale if scale is not None else 1.0)
        de = np.abs(np.diff(e))
        bound = np.maximum(e[:-1], e[1:]) + de
        top = float(np.max(e))
        bad = de > max(0.05 * top, floor)
        if not np.any(bad) or it == rounds or x.size > max_points:
            break
        x0, x1 = x[:-1][bad], x[1:][bad]
        x = np.unique(np.concatenate([x, x0 + 0.25 * (x1 - x0), x0 + 0.5 * (x1 - x0), x0 + 0.75 * (x1 - x0)]))
    return safety * (float(np.max(bound)) + floor)


def certified_sup(err, d2, a: float, b: float, target: float = 0.0, n: int = 2000, rounds: int = 14,
                  max_points: int = 400_000) -> float:
    r"""Proved upper bound of :math:`\max_{x \in [a, b]} |e(x)|`.

    ``err(x)`` returns ``(e, mag)`` on an array: the error and the sum of the magnitudes of
    the terms it is computed from (its rounding is at most :math:`64\varepsilon\,`mag);
    ``d2(lo, hi)`` bounds :math:`|e''|` on each interval ``[lo_i, hi_i]``. On an interval
    between two samples, :math:`|e| \le \max(|e_i|, |e_{i+1}|) + h^2 \max|e''| / 8`
    (the error of linear interpolation). Intervals where the curvature term exceeds a tenth
    of the sampled maximum (or of ``target``/1000) are bisected, up to ``rounds`` times.
    """
    a, b = float(a), float(b)
    if not b > a:
        e, mag = err(np.array([a]))
        return float(np.abs(e[0]) + 64 * EPS * mag[0])
    x = sample_grid(a, b, n)
    bound = np.inf
    for _ in range(rounds + 1):
        with np.errstate(all="ignore"):
            e, mag = err(x)
            E = np.abs(e) + 64 * EPS * np.abs(mag)
            lo, hi = x[:-1], x[1:]
            curv = np.asarray(d2(lo, hi), dtype=float) * (hi - lo) ** 2 / 8.0
        E = np.where(np.isfinite(E), E, np.inf)
        curv = np.where(np.isnan(curv), np.inf, curv)
        seg = np.maximum(E[:-1], E[1:]) + curv
        bound = float(np.max(seg))
        top = float(np.max(E))
        if not np.isfinite(top):
            return np.inf
        bad = curv > max(0.1 * top, 1e-3 * target)
        if not np.any(bad) or x.size > max_points:
            break
        x = np.unique(np.concatenate([x, 0.5 * (lo[bad] + hi[bad])]))
    return bound


def sampled_error(fn, approx, a: float, b: float) -> float:
    """:func:`sup_error` of ``fn - approx`` on [a, b] (an estimate), scaled by the sampled
    maximum of ``fn``: what an unproved plan reports at least, so that a filter the
    approximation never saw (a bump between its interpolation points) is not called exact."""
    lo = a if a > 0 else b * 1e-14
    xs = np.unique(np.concatenate([np.geomspace(lo, b, 400), np.linspace(a, b, 400)]))
    with np.errstate(all="ignore"):
        scale = float(np.max(np.abs(fn(xs))))
        return sup_error(lambda s: fn(s) - approx(s), a, b, scale=scale if np.isfinite(scale) else None)


def interpolated_d2(e2, ellipse2, m: int = 8, loose=None, chunk: int = 20_000):
    r"""``d2(lo, hi)`` for :func:`certified_sup` from :math:`e''` itself.

    On each interval, :math:`e''` is sampled at the m + 1 Chebyshev points; its interpolant
    p satisfies :math:`|p| \le \Lambda_m \max_k|e''(x_k)|` with the Lebesgue constant
    :math:`\Lambda_m \le 1 + \tfrac{2}{\pi}\log(m + 1)` (Trefethen, ATAP Thm 15.2), and
    :math:`|e'' - p| \le 4M\rho^{-m}/(\rho - 1)` where M bounds :math:`|e''|` on the
    Bernstein ellipse :math:`E_\rho` of the interval (ATAP Thm 8.2). So

    .. math:: \max_{[lo, hi]}|e''| \le \Lambda_m \max_k \bigl(|e''(x_k)| + 64\varepsilon\,
              \mathrm{mag}_k\bigr) + \min_\rho 4M(\rho)\rho^{-m}/(\rho - 1).

    ``e2(x)`` returns ``(e''(x), mag)`` (mag: the sum of the magnitudes of the terms, as in
    :func:`certified_sup`); ``ellipse2(lo, hi, rho)`` bounds :math:`|e''|` on
    :math:`E_\rho` of each interval (``inf`` where a singularity may lie inside). ``loose``
    (optional, same signature as the result) is another valid bound; the smaller is kept.
    """
    nodes = np.cos(np.pi * np.arange(m + 1) / m)
    lebesgue = 1.0 + 2.0 / np.pi * np.log(m + 1.0)
    rhos = (1.5, 3.0, 8.0, 32.0, 128.0)

    def d2(lo, hi):
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        out = np.empty(lo.shape)
        for s in range(0, lo.size, chunk):
            l, h = lo.ravel()[s:s + chunk], hi.ravel()[s:s + chunk]
            c, d = 0.5 * (l + h), 0.5 * (h - l)
            x = c[:, None] + d[:, None] * nodes[None, :]
            with np.errstate(all="ignore"):
                v, mag = e2(x.ravel())
                top = np.max(np.abs(v).reshape(x.shape) + 64 * EPS * np.abs(mag).reshape(x.shape), axis=1)
                rem = np.full(l.shape, np.inf)
                for rho in rhos:
                    M = np.asarray(ellipse2(l, h, rho), dtype=float)
                    rem = np.minimum(rem, 4.0 * M * rho ** (-m) / (rho - 1.0))
                b = lebesgue * top + rem
                b = np.where(np.isnan(b), np.inf, b)
                if loose is not None:
                    b = np.minimum(b, np.asarray(loose(l, h), dtype=float))
            out.ravel()[s:s + chunk] = b
        return out
    return d2


def ellipse_box(lo, hi, rho):
    r"""Half-axes of the Bernstein ellipse :math:`E_\rho` of each [lo, hi]: it lies in the box
    :math:`[c - A, c + A] \times [-B, B]`, returned as ``(c, A, B)``."""
    c, d = 0.5 * (lo + hi), 0.5 * (hi - lo)
    return c, d * 0.5 * (rho + 1.0 / rho), d * 0.5 * (rho - 1.0 / rho)


def filter_second(filt):
    r"""``phi2(x)``: :math:`\varphi''` on real x > 0 for the built-in filters, or None."""
    kind, p = filt.kind, filt.params
    if kind == "heat":
        t = p["t"]
        return lambda x: t * t * np.exp(-t * x)
    if kind == "wave":
        t = p["t"]
        return lambda x: -t * t * np.exp(-1j * t * x)
    if kind == "power":
        q = p["p"]
        return lambda x: q * (q + 1) * x ** (-(q + 2))
    if kind == "mexican_hat":
        t = p["t"]
        return lambda x: t * t * (t * x - 2.0) * np.exp(-t * x)
    if kind == "wks":
        e, sg = p["e"], p["sigma"]

        def w2(x):
            w = np.log(x) - e
            return np.exp(-w * w / (2 * sg * sg)) * (w * w / sg ** 4 + (w - 1.0) / sg ** 2) / (x * x)
        return w2
    if filt.key[0] == ("one",):
        return lambda x: np.zeros(np.shape(x))
    return None


def filter_d2_ellipse(filt):
    r"""``bound(lo, hi, rho)``: a bound of :math:`|\varphi''|` on the Bernstein ellipse
    :math:`E_\rho` of each [lo, hi] (through the box of :func:`ellipse_box`), or None."""
    kind, p = filt.kind, filt.params
    if kind == "heat":
        t = p["t"]
        return lambda lo, hi, rho: _heat_box(t, *ellipse_box(lo, hi, rho)) * t * t
    if kind == "wave":
        t = p["t"]
        return lambda lo, hi, rho: t * t * np.exp(t * ellipse_box(lo, hi, rho)[2])
    if kind == "power":
        q = p["p"]

        def pw(lo, hi, rho):
            c, A, _ = ellipse_box(lo, hi, rho)
            left = c - A
            with np.errstate(all="ignore"):
                return np.where(left > 0, q * (q + 1) * np.abs(left) ** (-(q + 2)), np.inf)
        return pw
    if kind == "mexican_hat":
        t = p["t"]

        def mh(lo, hi, rho):
            c, A, _ = ellipse_box(lo, hi, rho)
            return t * t * (t * (np.abs(c) + A) + 2.0) * _heat_box(t, c, A, None)
        return mh
    if kind == "wks":
        e, sg = p["e"], p["sigma"]

        def we(lo, hi, rho):
            c, A, B = ellipse_box(lo, hi, rho)
            left = c - A
            with np.errstate(all="ignore"):
                theta = np.arctan(B / left)
                w1, w2 = np.log(left) - e, np.log(np.hypot(c + A, B)) - e
                return np.where(left > 0, _wks_second_bound(w1, w2, theta, sg) / left ** 2, np.inf)
        return we
    if filt.key[0] == ("one",):
        return lambda lo, hi, rho: np.zeros(np.shape(lo))
    return None


def _heat_box(t, c, A, B):
    """max of |e^{-tz}| over the box: e^{-t (c - A)} (inf on overflow)."""
    with np.errstate(over="ignore"):
        return np.exp(-t * (c - A))


def _logt(t):
    return np.log(t)


def filter_d2(filt):
    r"""``d2(lo, hi)``: a bound of :math:`|\varphi''|` on ``[lo, hi]`` (0 <= lo), or None
    for a filter without a known one."""
    kind, p = filt.kind, filt.params
    if kind == "heat":
        t = p["t"]
        return lambda lo, hi: np.exp(2 * _logt(t) - t * lo)
    if kind == "wave":
        t = p["t"]
        return lambda lo, hi: np.full(np.shape(lo), t * t)
    if kind == "power":
        q = p["p"]
        return lambda lo, hi: q * (q + 1) * np.exp(-(q + 2) * np.log(lo))
    if kind == "mexican_hat":
        t = p["t"]   # phi'' = t^2 (ts - 2) e^{-ts}
        return lambda lo, hi: np.exp(2 * _logt(t) - t * lo) * (t * hi + 2.0)
    if kind == "wks":
        e, sg = p["e"], p["sigma"]

        def wk(lo, hi):     # |phi''| <= max g * max |P| / lo^2 over w = log s - e in the interval
            with np.errstate(all="ignore"):
                w1, w2 = np.log(lo) - e, np.log(hi) - e
                return np.where(lo > 0, _wks_second_bound(w1, w2, 0.0, sg) / lo ** 2, np.inf)
        return wk
    if filt.key[0] == ("one",):
        return lambda lo, hi: np.zeros(np.shape(lo))
    return None


def _wks_second_bound(w1, w2, theta, sg):
    r"""Bound of :math:`|g(w)P(w)|` for :math:`w = x + iy`, x in [w1, w2], :math:`|y| \le \theta`,
    where :math:`g = e^{-w^2/2\sigma^2}`, :math:`P = w^2/\sigma^4 + w/\sigma^2 - 1/\sigma^2`:
    the WKS filter's :math:`\varphi''(s) = g(\log s - e) P(\log s - e)/s^2`."""
    dmin = np.where((w1 <= 0) & (w2 >= 0), 0.0, np.minimum(np.abs(w1), np.abs(w2)))
    W = np.maximum(np.abs(w1), np.abs(w2)) + theta
    return np.exp(-(dmin * dmin - theta * theta) / (2 * sg * sg)) * (W * W / sg ** 4 + (W + 1.0) / sg ** 2)


def filter_logmax(filt, a: float, b: float):
    r"""``logmax(rho)``: log of a bound of :math:`|\varphi|` on the Bernstein ellipse
    :math:`E_\rho` of [a, b] (``inf`` where φ is not analytic inside), or None."""
    kind, p = filt.kind, filt.params
    c, d = 0.5 * (a + b), 0.5 * (b - a)

    def semi(rho):
        return d * 0.5 * (rho + 1.0 / rho), d * 0.5 * (rho - 1.0 / rho)

    if kind == "heat":
        t = p["t"]

        def heat_log(rho):
            return -t * (c - semi(rho)[0])
        heat_log.elementwise = True     # arithmetic only: an array of radii gives each one's value
        return heat_log
    if kind == "wave":
        t = p["t"]
        return lambda rho: t * semi(rho)[1]
    if kind == "power":
        q = p["p"]

        def lm(rho):
            left = c - semi(rho)[0]
            return -q * np.log(left) if left > 0 else np.inf
        return lm
    if kind == "mexican_hat":
        t = p["t"]

        def lm(rho):
            A = semi(rho)[0]
            return np.log(t) + np.log(c + A) - t * (c - A)
        return lm
    if kind == "wks":
        e, sg = p["e"], p["sigma"]

        def lw(rho):       # |g(log z - e)| <= exp(-(dmin^2 - theta^2) / 2 sigma^2) on the box
            A, B = semi(rho)
            left = c - A
            if not left > 0:
                return np.inf
            theta = np.arctan(B / left)
            w1, w2 = np.log(left) - e, np.log(np.hypot(c + A, B)) - e
            dmin = 0.0 if w1 <= 0 <= w2 else min(abs(w1), abs(w2))
            return -(dmin * dmin - theta * theta) / (2 * sg * sg)
        return lw
    if filt.key[0] == ("one",):
        return lambda rho: 0.0
    return None


def ellipse_tails(logmax, m) -> np.ndarray:
    r"""Proved bounds of :math:`\sum_{k > m}|c_k|` for each m (array), from ``logmax``.

    :math:`|c_k| \le 2M(\rho)\rho^{-k}` for every :math:`\rho > 1` with φ analytic inside
    :math:`E_\rho` (Trefethen, ATAP Thm 8.1), so the tail is at most
    :math:`2M(\rho)\rho^{-m}/(\rho - 1)`; minimised over a grid of ρ.
    """
    m = np.asarray(m, dtype=float)
    rhos = 1.0 + np.geomspace(1e-9, 1e3, 300)
    with np.errstate(all="ignore"):
        if getattr(logmax, "elementwise", False):
            L = np.asarray(logmax(rhos), dtype=float)
        else:
            L = np.array([float(logmax(rho)) for rho in rhos])
    use = np.isfinite(L)
    if not use.any():
        return np.full(m.shape, np.inf)
    # every rho's bound at every m at once: the same operations on the same numbers, so the
    # same minimum as one rho at a time
    L, lr, lr1 = L[use][:, None], np.log(rhos[use])[:, None], np.log(rhos[use] - 1.0)[:, None]
    with np.errstate(all="ignore"):
        best = np.min(np.log(2.0) + L - m.reshape(1, -1) * lr - lr1, axis=0).reshape(m.shape)
    with np.errstate(over="ignore"):
        return np.exp(best)


# ----------------------------------------------------------------------------- Chebyshev
def cheb_coeffs(fn, a: float, b: float, degree: int) -> np.ndarray:
    """Chebyshev coefficients of the interpolant of ``fn`` on [a, b] at degree+1 extreme points."""
    m = int(degree)
    k = np.arange(m + 1)
    x = np.cos(np.pi * k / m)
    s = 0.5 * (a + b) + 0.5 * (b - a) * x
    v = np.asarray(fn(s))
    if np.iscomplexobj(v):
        return cheb_coeffs(lambda s_: np.real(fn(s_)), a, b, m) + 1j * cheb_coeffs(
            lambda s_: np.imag(fn(s_)), a, b, m)
    c = scipy.fft.dct(v, type=1) / m
    c[0] *= 0.5
    c[-1] *= 0.5
    return c


def cheb_adaptive(fn, a: float, b: float, max_degree: int = 2 ** 16, floor: float = 0.0):
    """Chebyshev coefficients resolving ``fn`` on [a, b] to about machine precision.

    Doubles the degree until the last eighth of the coefficients is below
    ``max(8 eps max|c|, floor)`` or ``max_degree`` is reached. Returns ``(c, resolved)``.
    """
    m = 64
    while True:
        c = cheb_coeffs(fn, a, b, m)
        scale = np.max(np.abs(c))
        tail = np.max(np.abs(c[-(m // 8):]))
        if tail <= max(8 * EPS * scale, floor) or m >= max_degree:
            return c, tail <= max(8 * EPS * scale, floor)
        m *= 2


def tail_sums(c: np.ndarray) -> np.ndarray:
    """t[m] = sum_{k >= m} |c_k| (error of the degree m-1 truncation), length len(c)+1."""
    a = np.abs(c)[::-1]
    return np.concatenate([np.cumsum(a)[::-1], [0.0]])


def reciprocal_rounding(lap) -> np.ndarray:
    r"""Per vertex, a bound of :math:`|\mathrm{fl}(1/\hat V_c) - 1/V_c|\,\hat V_c` (the heat's
    limit 1/V_c at a large t, :math:`V_c = 1_c^\top B 1_c` exactly)."""
    theta = np.minimum(mass_sum_rounding(lap)[1], 0.5)
    return (theta / (1.0 - theta) + gamma(1)) * (1.0 + gamma(1))


#: largest component (vertices) whose lambda_2 :func:`mixed_heat` certifies on its own, and
#: most components it certifies in one call (the others keep the partial fractions)
COMPONENT_GAP_MAX = 2000
COMPONENT_GAP_COUNT = 2000


def mixed_heat(lap, t: float, eps: float):
    r"""Vertices of the components on which the heat at time ``t`` has mixed to within ``eps``.

    On a component c, :math:`K_t(i, j) = 1/V_c + \sum_{l \ge 2} e^{-t\lambda_l}x_l(i)x_l(j)`,
    so :math:`|K_t(i, j) - 1/V_c| \le e^{-t\lambda_{2,c}}\sqrt{(B^{-1})_{ii}(B^{-1})_{jj}}`
    (Cauchy--Schwarz over the B-orthonormal :math:`x_l`). Where
    :math:`e^{-t\lambda_{2,c}} \le` ``eps``, the projection :math:`1/V_c` is as accurate as
    the partial fractions are allowed to be, with no solve. The partial fractions themselves
    are, on such a component, a sum of terms :math:`(\sigma L - zB)^{-1}` whose constant mode
    sits under a stiffness :math:`\sigma\lambda_{\max}` times larger, and their rounding there
    outgrows the a-priori allowance (a 7-vertex part of truck.obj at t equal to the mesh's
    area: 3.3e-7 off 2550.85, 4.2 times the allowance).

    :math:`\lambda_{2,c}` is bounded below by :func:`~spectral_igl.linalg.lambda_min_positive`
    of the component's own L and B (proved by an inertia count), once per component and
    cached on ``lap``, for the components of at most :data:`COMPONENT_GAP_MAX` vertices that
    Weyl's law (:math:`8\pi/V_c`) puts above a quarter of :math:`\log(1/\varepsilon)/t`; a
    single vertex is its own projection. Lumped mass only (else nothing is replaced).

    Returns
    -------
    mask : (n,) bool
        Vertices on mixed components.
    decay : (n,) float
        :math:`e^{-t\mu_c}` on them (:math:`\mu_c \le \lambda_{2,c}` proved), 0 elsewhere.
    """
    n = lap.n
    mask, decay = np.zeros(n, bool), np.zeros(n)
    if not lap.lumped or not 0.0 < eps < 1.0 or not 0.0 < t < np.inf:
        return mask, decay
    comp = lap.components
    size = np.bincount(comp, minlength=lap.n_components)
    volume = np.bincount(comp, weights=lap.mass, minlength=lap.n_components)
    gaps = lap.cache.fetch("bound", "component_gaps", dict)
    candidates = np.flatnonzero((size <= COMPONENT_GAP_MAX) & (8.0 * np.pi / volume * t > 0.25 * np.log(1.0 / eps)))
    for c in candidates[size[candidates] == 1]:
        gaps[c] = np.inf
    todo = sorted((c for c in candidates[size[candidates] > 1] if c not in gaps), key=lambda c: size[c])
    for c in todo[:COMPONENT_GAP_COUNT]:      # a factorization each: the smallest components first
        gaps[c] = _component_gap(lap, np.flatnonzero(comp == c))
    if not gaps:
        return mask, decay
    known = np.zeros(lap.n_components)
    known[list(gaps)] = list(gaps.values())
    decay = np.exp(-t * known[comp])
    mask = decay <= eps
    return mask, np.where(mask, decay, 0.0)


def _component_gap(lap, idx) -> float:
    """A proved lower bound of lambda_2 of the component on the vertices ``idx``, or 0."""
    part = make_laplacian(lap.L[idx][:, idx], lap.B[idx][:, idx])
    if part.n_components != 1:
        return 0.0
    lo = lambda_min_positive(part)
    return float(lo) if lambda_min_positive_kind(part) == "proof" else 0.0
