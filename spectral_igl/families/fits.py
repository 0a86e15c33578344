r"""Families of filters sharing poles: the poles and each member's certified residues.

A family of real filters :math:`\varphi_1, \dots, \varphi_T` (the heat filters
:math:`e^{-t s}` at T times, the WKS band filters at T energies) is approximated with
**common poles** :math:`z_j` and per-member residues,

.. math:: r_k(s) = \alpha_{0,k} + \sum_j \frac{c_{jk}}{s - z_j},

so each pole costs one sparse LDLᵀ factorization *for the whole family*, whatever is then
taken from it (:mod:`.diagonals`: a selected inversion; :mod:`.columns`: a block solve).

Poles. For the heat family :math:`t \in [t_1, t_2]` the poles are the nodes of a hyperbolic
contour :math:`z(\theta) = \mu(1 + \sin(i\theta - \alpha))` (Weideman & Trefethen 2007),
whose parameters were optimised once for ranges :math:`t_2/t_1 \le \Lambda` and are scaled
by :math:`1/t_2` (:data:`HYPERBOLA`); one node is real (a real Cholesky-like LDLᵀ), the
others come in conjugate pairs (one complex LDLᵀ per pair). Wider ranges are split. For
other families (WKS) the poles come from a set-valued AAA fit (Lietaert et al. 2022) of
representative members on a log-spaced sample of :math:`[0, \lambda_{\max}]`.

Residues and certification. For each member the residues are a Lawson (reweighted least
squares, QR without truncation) minimax fit with the poles fixed, and
:math:`\varepsilon_k = \max_{[0,\lambda_{\max}]}|\varphi_k - r_k|` plus the rounding term of
the solves are certified per member exactly as for one filter
(:func:`spectral_igl.approx.rational.certify`, :func:`~spectral_igl.approx.rational.rounding`).
Then :math:`|G^{(k)}_{ii} - R^{(k)}_{ii}| \le \varepsilon_k (B^{-1})_{ii}` at every vertex,
and a kernel column :math:`\|G^{(k)}e_i - R^{(k)}e_i\|_B \le \varepsilon_k\|B^{-1}e_i\|_B`.
The pole count is raised until every member meets its target; a member that still does not
is refused (never returned with a larger error than asked).
"""
from __future__ import annotations

import logging

import numpy as np
import scipy.linalg as sla

from .._validate import describe
from ..approx.rational import PartialFractions, cf_exp, certify, rounding
from ..filters import Filter, heat
from ..laplacian import as_laplacian, lambda_max
from ..linalg import inverse_mass_diagonal, ldlt_factor
from ..linalg.threads import serial_blas

__all__ = ["HYPERBOLA", "heat_poles", "fit_family", "family_poles", "plan_poles", "pole_factorizations",
           "coefficients", "as_times", "SCALAR_FLOOR", "heat_targets", "heat_plan", "as_filters"]

log = logging.getLogger(__name__)

#: Hyperbolic-contour nodes for :math:`e^{-ts}`, :math:`t \in [t_2/\Lambda, t_2]`:
#: ``Lambda -> [(K, (log(mu t_2), alpha, h), max error)]`` with K complex conjugate pairs
#: plus one real node; the error is the measured max over 13 times of the Lawson fit on
#: :math:`[0, 10^4/t_1]`. Only a guide for the choice of K: every use is certified anew.
HYPERBOLA = {
    10: [
        (6, (1.780693, 0.431044, 0.529870), 3.3e-06),
        (8, (2.059148, 0.409802, 0.420076), 9.3e-08),
        (10, (2.124504, 0.463930, 0.349165), 3.6e-09),
        (12, (2.467675, 0.548102, 0.274816), 1.2e-10),
        (14, (2.405413, 0.512796, 0.252680), 1.1e-11),
        (16, (1.997309, 0.465741, 0.249069), 2.7e-12),
        (18, (1.816388, 0.504194, 0.230623), 1.0e-12),
        (20, (1.593707, 0.527334, 0.219382), 5.0e-13),
        (22, (1.190602, 0.492974, 0.219816), 2.2e-13),
        (24, (1.058030, 0.543826, 0.205605), 1.3e-13),
        (26, (0.616690, 0.507466, 0.207996), 6.4e-14),
    ],
    100: [
        (6, (1.534630, 0.251474, 0.889143), 1.3e-04),
        (8, (1.882438, 0.254300, 0.659245), 1.6e-05),
        (10, (1.670028, 0.258769, 0.593264), 1.3e-06),
        (12, (1.931896, 0.275903, 0.490035), 1.2e-07),
        (14, (2.190940, 0.287704, 0.405726), 1.7e-08),
        (16, (2.083811, 0.309484, 0.378282), 1.6e-09),
        (18, (2.276417, 0.311377, 0.329579), 1.9e-10),
        (20, (2.189539, 0.331245, 0.310228), 2.4e-11),
        (22, (1.949224, 0.335625, 0.298218), 7.3e-12),
        (24, (1.724612, 0.340134, 0.281525), 2.3e-12),
        (26, (1.392400, 0.296500, 0.278369), 8.4e-13),
        (28, (0.970202, 0.234187, 0.286110), 3.7e-13),
        (30, (0.685849, 0.242864, 0.275235), 1.5e-13),
    ],
}


def _hyperbola(K: int, params, t2: float):
    """(upper complex poles, real poles) in the variable s for e^{-ts}, t <= t2."""
    lmu, alpha, h = params
    th = h * np.arange(K + 1)
    z = np.exp(lmu) / t2 * (1.0 + np.sin(1j * th - alpha))
    return -z[1:], np.array([-z[0].real])


def heat_poles(t1: float, t2: float, K: int | None = None):
    """Candidate common pole sets for :math:`e^{-ts}`, :math:`t \\in [t_1, t_2]`, fewest first.

    Yields ``(upper, real)``: complex poles with positive imaginary part (their conjugates
    are implied) and real poles, in the variable s. A single time gets the
    Carathéodory--Fejér poles of degree 8 to 16.
    """
    lam = t2 / t1
    if lam <= 1.0 + 1e-12:
        for r in range(8, 17, 2):
            _, _, P, _ = cf_exp(r)
            yield P[P.imag > 1e-10] / t2, P[np.abs(P.imag) <= 1e-10].real / t2
        return
    grid = [g for g in sorted(HYPERBOLA) if g >= lam * (1 - 1e-9)]
    if not grid:
        raise ValueError(f"time range t2/t1 = {lam:.3g} is wider than {max(HYPERBOLA):g}; split it")
    for Kk, params, _ in HYPERBOLA[grid[0]]:
        if K is None or Kk == K:
            yield _hyperbola(Kk, params, t2)


# ----------------------------------------------------------------------------- fits
def _sample(a: float, b: float, scales=()) -> np.ndarray:
    lo = a if a > 0 else b * 1e-14
    parts = [[a, b], np.linspace(a, b, 400), np.geomspace(lo, b, 1200)]
    for s in scales:   # dense where the member varies
        parts.append(np.clip(np.geomspace(s * 1e-4, s * 1e2, 400), a, b))
    x = np.unique(np.concatenate(parts))
    return x[(x >= a) & (x <= b)]


def _design(x, upper, real):
    cols = [np.ones_like(x)]
    for z in upper:
        d = 1.0 / (x - z)
        cols += [2.0 * d.real, -2.0 * d.imag]
    for z in real:
        cols.append(1.0 / (x - z))
    return np.array(cols).T


def _lawson(A, y, iterations=6):
    """Minimax-leaning least squares by QR (no singular-value truncation), Lawson weights."""
    scale = np.max(np.abs(A), axis=0)
    scale[scale == 0] = 1.0
    As = A / scale
    w = np.full(y.size, 1.0 / y.size)
    best = None
    for _ in range(iterations):
        sw = np.sqrt(w)
        Q, R = np.linalg.qr(As * sw[:, None])
        with np.errstate(all="ignore"):
            sol = sla.solve_triangular(R, Q.T @ (y * sw), check_finite=False)
        if not np.all(np.isfinite(sol)):
            break
        e = np.abs(As @ sol - y)
        if best is None or e.max() < best[1]:
            best = (sol / scale, float(e.max()))
        w = w * e
        tot = w.sum()
        if not tot > 0:
            break
        w /= tot
    return best


@serial_blas
def fit_family(filters, upper, real, a: float, b: float, sigma: float, scales=None, targets=None,
               stop: bool = False):
    """Per-member partial fractions with the poles fixed, and each member's certified error.

    Returns a list of ``(PartialFractions, eps)`` with eps = certified sup error plus the
    rounding term of the solves. With ``targets``, a member whose error on the fitting sample
    already exceeds its target is not certified (its eps is that sample error, a lower
    bound); with ``stop`` the remaining members are then skipped (eps = inf).
    """
    upper = np.asarray(upper, dtype=complex)
    real = np.asarray(real, dtype=float)
    out = []
    for k, filt in enumerate(filters):
        x = _sample(a, b, () if scales is None else (scales[k],))
        if stop and out and not out[-1][1] <= targets[k - 1]:
            out.append((None, np.inf))
            continue
        sol = _lawson(_design(x, upper, real), np.asarray(filt(x), dtype=float))
        if sol is None:
            out.append((None, np.inf))
            continue
        c, sample_err = sol
        m = upper.size
        cu = c[1:1 + 2 * m:2] + 1j * c[2:2 + 2 * m:2]
        cr = c[1 + 2 * m:]
        # r(s) = a0 + sum c/(s - z) = a0 + sum (c sigma)/(sigma s - sigma z)
        pf = PartialFractions(c[0], np.concatenate([cu, np.conj(cu), cr]) * sigma,
                              np.concatenate([upper, np.conj(upper), real]) * sigma, sigma=sigma)
        rnd = rounding(pf, 0.0, b, b)      # over [0, b]: the solves also see ker L
        if targets is not None and sample_err + rnd > targets[k]:
            pf.scalar_error = sample_err
        else:
            pf.scalar_error = certify(pf, filt, a, b)
        out.append((pf, pf.scalar_error + rnd))
    return out


@serial_blas
def family_poles(filters, a: float, b: float, rtol: float = 1e-12, max_poles: int = 80,
                 representatives: int = 12, scales=None):
    """Common poles of a family of real filters by set-valued AAA on [a, b].

    Runs AAA on the stacked samples of up to ``representatives`` members (each normalised
    by its maximum), takes the poles of the common denominator, drops those on [a, b] and
    symmetrises them. Returns ``(upper, real)`` as in :func:`heat_poles`.
    """
    idx = np.unique(np.linspace(0, len(filters) - 1, min(representatives, len(filters))).round().astype(int))
    lo = a if a > 0 else b * 1e-14
    x = np.unique(np.concatenate([[a, b], np.linspace(a, b, 300), np.geomspace(lo, b, 1500)]
                                 + ([] if scales is None else
                                    [np.clip(np.geomspace(scales[i] * 1e-2, scales[i] * 1e2, 100), a, b)
                                     for i in idx])))
    F = np.stack([np.asarray(filters[i](x), dtype=float) for i in idx], axis=1)
    F = F / np.maximum(np.max(np.abs(F), axis=0), np.finfo(float).tiny)
    M, T = F.shape
    J = np.ones(M, dtype=bool)
    zs = []
    R = np.tile(F.mean(axis=0), (M, 1))
    w = None
    for m in range(max_poles + 1):
        err = np.max(np.abs(F - R), axis=1)
        err[~J] = 0.0
        if err.max() <= rtol:
            break
        j = int(np.argmax(err))
        zs.append(j)
        J[j] = False
        z = x[zs]
        C = 1.0 / (x[J][:, None] - z[None, :])
        A = np.concatenate([(F[J, k][:, None] - F[zs, k][None, :]) * C for k in range(T)], axis=0)
        _, _, Vh = np.linalg.svd(np.linalg.qr(A, mode="r"))
        w = Vh[-1].conj()
        den = C @ w
        R = F.copy()
        R[J] = (C @ (w[:, None] * F[zs])) / den[:, None]
    if w is None or len(zs) < 2:
        return np.zeros(0, dtype=complex), np.zeros(0)
    z = x[zs]
    mm = len(zs)
    Eg = np.zeros((mm + 1, mm + 1))
    Eg[0, 1:] = w.real
    Eg[1:, 0] = 1.0
    Eg[1:, 1:] = np.diag(z)
    Bg = np.eye(mm + 1)
    Bg[0, 0] = 0.0
    poles = sla.eigvals(Eg, Bg)
    poles = poles[np.isfinite(poles)]
    tol_im = 1e-10 * np.maximum(1.0, np.abs(poles))
    real = poles[np.abs(poles.imag) <= tol_im].real
    real = real[(real < a) | (real > b)]     # a pole on the spectrum would make r useless
    upper = poles[poles.imag > tol_im]
    return upper, real


def plan_poles(filters, targets, a, b, sigma, candidates, scales=None, scalar_targets=None):
    """The first candidate pole set whose fits meet every member's target (the end members,
    the hardest, are tried first), else the last candidate's fits. With ``scalar_targets``
    the certified sup error alone (without the rounding term) must meet them too."""
    def meets(fits, idx):
        ok = all(e <= targets[k] for (_, e), k in zip(fits, idx))
        if ok and scalar_targets is not None:
            ok = all(pf is not None and pf.scalar_error <= scalar_targets[k] for (pf, _), k in zip(fits, idx))
        return ok

    cands = iter(candidates)
    nxt = next(cands, None)
    last = upper = real = None
    ends = sorted({0, len(filters) // 2, len(filters) - 1})
    while nxt is not None:
        (upper, real), nxt = nxt, next(cands, None)
        more = nxt is not None
        if more and len(filters) > 3:
            sc = None if scales is None else [scales[k] for k in ends]
            probe = fit_family([filters[k] for k in ends], upper, real, a, b, sigma, sc, targets[ends],
                               stop=True)
            if not meets(probe, ends):
                continue
        fits = fit_family(filters, upper, real, a, b, sigma, scales, targets, stop=more)
        eps = np.array([e for _, e in fits])
        last = (upper, real, fits, eps)
        if meets(fits, range(len(fits))):
            return last
        log.debug("common poles: %d pairs + %d real miss the target by %.2g", upper.size, real.size,
                  float(np.max(eps / targets)))
    if last is None and upper is not None:
        fits = fit_family(filters, upper, real, a, b, sigma, scales, targets)
        last = (upper, real, fits, np.array([e for _, e in fits]))
    return last


def pole_factorizations(lap, upper, real):
    """Yield (pole, factor) one at a time; the caller drops each before the next is built."""
    for z in upper:
        yield complex(z), ldlt_factor(lap, (lap.L.astype(complex) - z * lap.B.astype(complex)).tocsr())
    for z in real:
        yield float(z), ldlt_factor(lap, (lap.L - float(z) * lap.B).tocsr())


def coefficients(fits, upper, real):
    """(T,) alpha0 and (T, P) residues in s-units, for the poles upper then real."""
    al = np.array([pf.alpha0.real for pf, _ in fits])
    P = upper.size + real.size
    C = np.zeros((len(fits), P), dtype=complex)
    for k, (pf, _) in enumerate(fits):
        cs = pf.coef / pf.sigma
        C[k, :upper.size] = cs[:upper.size]
        C[k, upper.size:] = cs[2 * upper.size:]
    return al, C


# ----------------------------------------------------------------------------- heat
#: most times in one call (each costs a weighted sum of the solves; 1000 take about 30 s on
#: 642 vertices)
MAX_TIMES = 1000


def as_times(times):
    T = np.asarray(times, dtype=float) if not isinstance(times, (str, bytes)) else None
    if T is None or T.ndim > 1 or T.size == 0 or not np.all(np.isfinite(T)) or np.any(T <= 0):
        raise ValueError(f"times must be positive finite numbers (scalar or 1-D), got {describe(times)}")
    if T.size > MAX_TIMES:
        raise ValueError(f"times has {T.size} values, more than {MAX_TIMES}: split them over several calls")
    return T.reshape(-1)


def _groups(T, max_ratio):
    """Split sorted unique times into runs with t_max / t_min <= max_ratio."""
    out, start = [], 0
    for i in range(1, T.size + 1):
        if i == T.size or T[i] / T[start] > max_ratio:
            out.append(np.arange(start, i))
            start = i
    return out


#: floor of the certified sup error (rounding term excluded) of common-pole heat fits, where
#: ``tol`` asks for less than that: the actual errors then stay below
#: ``tol`` = 1e-8 on the unit-area meshes measured (the one-time Carathéodory--Fejér
#: approximant of degree 16 is at 1e-15)
SCALAR_FLOOR = 2e-12


def heat_targets(lap, times, tol: float, scalar: bool = False):
    r"""Per-time target of the certified sup error for heat diagonals and columns.

    The single-time path's target: :math:`\varepsilon \le tol \cdot \min_i 1/(V_c (B^{-1})_{ii})`
    (then :math:`|G_{ii} - R_{ii}| \le tol\,G_{ii}`, since :math:`G_{ii} \ge 1/V_c`), or where
    that is out of reach, what the best Carathéodory--Fejér approximant at that time certifies
    (the single-time result). With ``scalar`` also returns the target of the sup error
    alone: ``max(tol_adj, SCALAR_FLOOR)``, at most the total target.
    """
    lap = as_laplacian(lap)
    b = lambda_max(lap)
    minv = inverse_mass_diagonal(lap)
    tol_adj = max(float(tol) * float(np.min(1.0 / (lap.component_volume() * minv))), 1e-15)
    out = np.empty(len(times))
    for k, t in enumerate(times):
        # what the Carathéodory--Fejér approximants certify at this time (about twice their
        # sampled error plus the rounding term), the best of degrees 8 to 16
        best = min(2.0 * cf_exp(r)[3] + rounding(PartialFractions(*cf_exp(r)[:3], sigma=t), 0.0, b, b)
                   for r in range(8, 17, 2))
        out[k] = tol_adj if best <= tol_adj else best
    if scalar:
        return out, np.minimum(out, max(tol_adj, SCALAR_FLOOR))
    return out


def heat_plan(lap, times, tol, targets=None):
    """[(indices into times, upper, real, fits, eps)] covering the sorted unique times.

    A range whose common poles miss a member's target is split in two (a narrower range
    needs fewer poles for the same accuracy); a single time gets the Carathéodory--Fejér
    poles, so every member meets its target.
    """
    b = lambda_max(lap)
    if targets is None:
        targets, scalar_targets = heat_targets(lap, times, tol, scalar=True)
    else:
        targets, scalar_targets = np.broadcast_to(targets, times.shape), None
    plans = []
    todo = _groups(times, max(HYPERBOLA))
    while todo:
        g = todo.pop(0)
        tg = times[g]
        filters = [heat(float(t)) for t in tg]
        if g.size == 1:
            plans.append((g,) + _cf_single(filters[0], float(tg[0]), targets[g][0], b))
            continue
        st = None if scalar_targets is None else scalar_targets[g]
        upper, real, fits, eps = plan_poles(filters, targets[g], 0.0, b, float(tg[0]),
                                       heat_poles(float(tg[0]), float(tg[-1])), scalar_targets=st)
        if np.all(eps <= targets[g]) and (st is None or all(pf.scalar_error <= x for (pf, _), x in zip(fits, st))):
            plans.append((g, upper, real, fits, eps))
        else:
            cut = int(np.searchsorted(tg, np.sqrt(tg[0] * tg[-1]), side="right"))
            cut = min(max(cut, 1), g.size - 1)
            todo[:0] = [g[:cut], g[cut:]]
            log.info("heat family: splitting [%.3g, %.3g]", tg[0], tg[-1])
    return plans


def _cf_single(filt, t, target, b):
    """One time alone: the Carathéodory--Fejér partial fractions, as the one-time path uses
    them (the lowest degree meeting the target, else degree 16)."""
    for r in range(8, 17, 2):
        a0, c, p, _ = cf_exp(r)
        pf = PartialFractions(a0, c, p, sigma=t)
        eps = certify(pf, filt, 0.0, b) + rounding(pf, 0.0, b, b)
        if eps <= target:
            break
    up = p[p.imag > 1e-10]
    return up / t, p[np.abs(p.imag) <= 1e-10].real / t, [(pf, eps)], np.array([eps])


def as_filters(filters):
    """Validate a sequence of real Filters."""
    out = list(filters)
    if not out or not all(isinstance(f, Filter) and not f.is_complex for f in out):
        raise TypeError(f"filters must be a non-empty sequence of real Filters, got {describe(filters)}")
    return out
