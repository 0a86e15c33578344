r"""Rational approximation in partial fractions: :math:`r(s) = \alpha_0 + \sum_j c_j/(\sigma s - z_j)`.

Applied to :math:`\tilde L = B^{-1}L` this is

.. math:: r(\tilde L) f = \alpha_0 f + \sum_j c_j (\sigma L - z_j B)^{-1} B f,

one sparse solve per pole (one complex solve per conjugate pair), and for a kernel column
:math:`r(\tilde L)B^{-1}g` needs no solve with B at all. The poles come from

- the heat filter: the best uniform rational approximation of :math:`e^{-x}` on
  :math:`[0, \infty)` (Carathéodory--Fejér, Trefethen--Weideman--Schmelzer 2006), error
  about :math:`9.28^{-r}`;
- power filters :math:`s^{-p}` (biharmonic, commute-time, poly-harmonic): exact
  pseudo-solves for the integer part of p, and for a half-integer part an AAA fit of
  :math:`s^{-1/2}` on :math:`[\lambda_{\min}^+, \lambda_{\max}]` (real negative poles:
  Cholesky solves);
- any other filter: an AAA rational fit (``scipy.interpolate.AAA``) of φ on
  :math:`[a, \lambda_{\max}]`, turned into partial fractions.

The error bound is :math:`\max_{s \in [a, \lambda_{\max}]} |\varphi(s) - r(s)|\,\|f\|_B`,
certified by :func:`.common.sup_error` with the exact derivative bound of the partial
fractions, plus a rounding term for the solves.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.linalg as sla

from ..filters import commute_time
from ..linalg import mass_solve, pseudo_solve, shifted_factor
from ..linalg.threads import serial_blas
from .common import (EPS, bnorm, certified_sup, ellipse_box, filter_d2_ellipse, filter_second,
                     interpolated_d2, inv_bnorm_upper, sup_error)


# ----------------------------------------------------------------------------- CF for exp
@serial_blas
def lawson_lstsq(A, y, iterations: int):
    """Least squares of ``A c ≈ y`` reweighted towards the minimax solution (Lawson).

    Each pass multiplies the weights by the absolute residual; the iterate with the
    smallest maximum residual is returned as ``(c, max_residual)``. One pass is plain
    least squares.
    """
    wts = np.full(len(y), 1.0 / len(y))
    best = None
    for _ in range(int(iterations)):
        sw = np.sqrt(wts)
        sol = np.linalg.lstsq(A * sw[:, None], y * sw, rcond=None)[0]
        e = np.abs(A @ sol - y)
        if best is None or e.max() < best[1]:
            best = (sol, float(e.max()))
        wts = wts * e
        wts /= wts.sum()
    return best


@lru_cache(maxsize=None)
@serial_blas
def cf_exp(r: int):
    r"""Near-best rational approximation of :math:`e^{-x}` on :math:`[0, \infty)`, type (r, r).

    Poles by the Carathéodory--Fejér method (SVD of a Hankel matrix of the Chebyshev
    coefficients of :math:`e^{-x}` transplanted to [-1, 1] by :math:`x = 9(1-t)/(1+t)`),
    then residues and :math:`\alpha_0` by a Lawson (iteratively reweighted least squares)
    minimax fit with the poles fixed.

    Returns
    -------
    alpha0 : float
    coef : (r,) complex
    poles : (r,) complex
    err : float
        max |e^{-x} - r(x)| on a 2000-point sample of [0, inf] (the certified bound is
        recomputed on each interval of use).
    """
    r = int(r)
    if not 1 <= r <= 16:
        raise ValueError(f"degree must be in [1, 16] for the heat filter, got {r}")
    K, nf, scl = 75, 1024, 9.0
    w = np.exp(2j * np.pi * np.arange(nf) / nf)
    t = w.real
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        F = np.exp(scl * (t - 1) / (t + 1 + 1e-16))
    c = np.real(np.fft.fft(F)) / nf
    _, _, Vh = np.linalg.svd(sla.hankel(c[1:K + 1]))
    zr = np.roots(Vh[r].conj())
    q = zr[np.abs(zr) > 1]
    poles = -scl * (q - 1) ** 2 / (q + 1) ** 2
    up = poles[poles.imag > 1e-10]
    real = poles[np.abs(poles.imag) <= 1e-10].real
    # minimax residues with fixed poles (Lawson), on Chebyshev points of t <-> x
    th = np.linspace(0, np.pi, 2000)
    tt = np.cos(th)
    fin = tt > -1
    x = np.where(fin, scl * (1 - tt) / (1 + np.where(fin, tt, 0)), 0.0)
    cols = [np.ones_like(x)]
    for z in up:
        d = np.where(fin, 1.0 / (x - z), 0.0)
        cols += [2 * d.real, -2 * d.imag]
    for z in real:
        cols.append(np.where(fin, 1.0 / (x - z), 0.0).real)
    A = np.array(cols).T
    y = np.where(fin, np.exp(-x), 0.0)
    sol, err = lawson_lstsq(A, y, 25)
    alpha0 = float(sol[0])
    m = up.size
    cu = sol[1:1 + 2 * m:2] + 1j * sol[2:2 + 2 * m:2]
    cr = sol[1 + 2 * m:]
    coef = np.concatenate([cu, np.conj(cu), cr.astype(complex)])
    pol = np.concatenate([up, np.conj(up), real.astype(complex)])
    return alpha0, coef, pol, float(err)


# ----------------------------------------------------------------------------- partial fractions
class PartialFractions:
    r""":math:`r(s) = \alpha_0 + \sum_j c_j / (\sigma s - z_j)` with conjugate pairs grouped.

    ``real_symmetric`` is True when the poles/residues come in conjugate pairs and
    :math:`\alpha_0` is real (r is real on the real axis): then each pair costs one
    complex solve, 2 Re(...).
    """

    def __init__(self, alpha0, coef, poles, sigma=1.0):
        self.alpha0 = complex(alpha0)
        self.coef = np.asarray(coef, dtype=complex)
        self.poles = np.asarray(poles, dtype=complex)
        self.sigma = float(sigma)
        self._group()

    def _group(self):
        c, z = self.coef, self.poles
        used = np.zeros(z.size, dtype=bool)
        terms = []  # (coef, pole, factor) with factor 2 for a grouped pair (take 2 Re)
        sym = abs(self.alpha0.imag) <= 1e-14 * max(1.0, abs(self.alpha0))
        for i in range(z.size):
            if used[i]:
                continue
            used[i] = True
            if abs(z[i].imag) <= 1e-12 * max(1.0, abs(z[i])):
                if abs(c[i].imag) > 1e-12 * max(1.0, abs(c[i])):
                    sym = False
                terms.append((c[i], complex(z[i].real, 0.0), 1))
                continue
            j = np.flatnonzero(~used & (np.abs(z - np.conj(z[i])) <= 1e-10 * abs(z[i]))
                               & (np.abs(c - np.conj(c[i])) <= 1e-10 * max(abs(c[i]), 1e-300)))
            if j.size:
                used[j[0]] = True
                terms.append((c[i], z[i], 2))
            else:
                sym = False
                terms.append((c[i], z[i], 1))
        self.real_symmetric = sym
        self.terms = terms
        # the grouped form, term by term: what apply() computes, so what is evaluated and
        # certified (a nearly conjugate pair is an exact pair, a nearly real pole real)
        gc, gz = [], []
        for c_, z_, k_ in terms:
            gc.append(c_)
            gz.append(z_)
            if k_ == 2:
                gc.append(np.conj(c_))
                gz.append(np.conj(z_))
        self._gcoef, self._gpoles = np.array(gc, dtype=complex), np.array(gz, dtype=complex)

    def __call__(self, s):
        s = np.asarray(s, dtype=float)
        out = np.full(s.shape, self.alpha0, dtype=complex)
        for c, z in zip(self._gcoef, self._gpoles):
            out = out + c / (self.sigma * s - z)
        return out.real if self.real_symmetric else out

    @property
    def n_solves(self) -> int:
        return len(self.terms)

    def magnitude(self, s):
        r""":math:`|\alpha_0| + \sum_j |c_j| / |\sigma s - z_j|`: the scale of the rounding of r(s)."""
        s = np.asarray(s, dtype=float)
        out = np.full(s.shape, abs(self.alpha0))
        for c, z in zip(self._gcoef, self._gpoles):
            out = out + abs(c) / np.abs(self.sigma * s - z)
        return out

    def _halved(self):
        """Poles, residues and multiplicities with each conjugate pair as one term (when
        r is real on the axis a pair contributes twice the real part of one member)."""
        if self.real_symmetric:
            c = np.array([t[0] for t in self.terms], dtype=complex)
            z = np.array([t[1] for t in self.terms], dtype=complex)
            k = np.array([t[2] for t in self.terms], dtype=float)
            return c, z, k
        return self._gcoef, self._gpoles, np.ones(self._gpoles.size)

    def second(self, s):
        r""":math:`r''(s) = \sum_j 2c_j\sigma^2/(\sigma s - z_j)^3` and the sum of the
        magnitudes of its terms (the scale of its rounding)."""
        s = np.asarray(s, dtype=float)
        flat = s.ravel()
        c, z, k = self._halved()
        out = np.empty(flat.size, dtype=float if self.real_symmetric else complex)
        mag = np.empty(flat.size)
        wk = 2.0 * np.float64(self.sigma) ** 2 * c * k
        for j in range(0, flat.size, 4096):
            with np.errstate(all="ignore"):
                d = 1.0 / (self.sigma * flat[j:j + 4096, None] - z[None, :])
                w = (d * d * d) * wk[None, :]
            out[j:j + 4096] = w.real.sum(axis=1) if self.real_symmetric else w.sum(axis=1)
            mag[j:j + 4096] = np.abs(w).sum(axis=1)
        return out.reshape(s.shape), mag.reshape(s.shape)

    def d2_ellipse(self, lo, hi, rho):
        r"""Bound of :math:`|r''|` on the Bernstein ellipse :math:`E_\rho` of each [lo, hi]:
        :math:`\sum_j 2|c_j|\sigma^2/\operatorname{dist}(z_j, \sigma E_\rho)^3`, with the
        distance to the ellipse's box as a lower bound (``inf`` if a pole is in the box)."""
        c, A, B = ellipse_box(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float), rho)
        sg = abs(self.sigma)
        coef, z, k = self._halved()      # the box is symmetric: z and its conjugate are as far
        flat_c, flat_a, flat_b = c.ravel(), A.ravel(), B.ravel()
        out = np.empty(flat_c.size)
        w = 2.0 * np.abs(coef) * k * np.float64(sg) ** 2
        for j in range(0, flat_c.size, 4096):
            sl = slice(j, j + 4096)
            with np.errstate(all="ignore"):
                dx = np.maximum(np.abs(z.real[None, :] - self.sigma * flat_c[sl, None]) - sg * flat_a[sl, None], 0.0)
                dy = np.maximum(np.abs(z.imag)[None, :] - sg * flat_b[sl, None], 0.0)
                d2 = dx * dx + dy * dy
                out[sl] = np.where(d2 > 0, w[None, :] / (d2 * np.sqrt(d2)), np.inf).sum(axis=1)
        return out.reshape(c.shape)

    def amplification(self, a: float, b: float) -> float:
        r""":math:`|\alpha_0| + \sum_j |c_j| / \operatorname{dist}(z_j, \sigma[a, b])`: bounds the B-norm of each term."""
        tot = abs(self.alpha0)
        lo, hi = sorted((self.sigma * a, self.sigma * b))
        for c, z in zip(self._gcoef, self._gpoles):
            dr = lo - z.real if z.real < lo else (z.real - hi if z.real > hi else 0.0)
            tot += abs(c) / max(np.hypot(dr, z.imag), 1e-300)
        return tot

    def apply(self, lap, f, rhs: bool, backend="auto", with_alpha0: bool = True):
        r"""r(L̃) f, or r(L̃) B⁻¹ f when ``rhs`` (f is then a right-hand side g)."""
        real_out = self.real_symmetric and np.isrealobj(f)
        g = f if rhs else lap.B @ f
        out = np.zeros(f.shape, dtype=float if real_out else complex)
        for c, z, k in self.terms:
            theta = -z.real if z.imag == 0 else -z
            x = shifted_factor(lap, self.sigma, theta, backend=backend).solve(g)
            if k == 2 and real_out:
                out += 2.0 * (c * x).real
            elif k == 2 and np.isrealobj(g):
                # (σL - z̄B)⁻¹ g = conj((σL - zB)⁻¹ g) for real g
                out += c * x + np.conj(c) * np.conj(x)
            elif k == 2:
                x2 = shifted_factor(lap, self.sigma, -np.conj(z), backend=backend).solve(g)
                out += c * x + np.conj(c) * x2
            else:
                out += (c * x).real if real_out else c * x
        if with_alpha0 and self.alpha0 != 0:
            base = mass_solve(lap, f, backend=backend) if rhs else f
            out += self.alpha0.real * base if real_out else self.alpha0 * base
        return out


def certifiable(filt) -> bool:
    """Whether :func:`certify` proves its bound for ``filt`` (a built-in filter whose φ'' and
    its bound on Bernstein ellipses are known), rather than estimating it."""
    return filter_second(filt) is not None and filter_d2_ellipse(filt) is not None


def certify(pf: PartialFractions, filt, a: float, b: float, target: float = 0.0) -> float:
    """Upper bound of max |φ - r| on [a, b]: proved (:func:`.common.certified_sup`) when
    :func:`certifiable`, else a refined-sample estimate."""
    if certifiable(filt):
        phi2, ell = filter_second(filt), filter_d2_ellipse(filt)
        def err2(s):
            v = filt(s)
            return v - pf(s), np.abs(v) + pf.magnitude(s)

        def e2(s):
            v2 = phi2(s)
            r2, m2 = pf.second(s)
            return v2 - r2, np.abs(v2) + m2

        tight = interpolated_d2(e2, lambda lo, hi, rho: ell(lo, hi, rho) + pf.d2_ellipse(lo, hi, rho))
        return certified_sup(err2, tight, a, b, target, n=600)

    def err(s):
        return filt(s) - pf(s)

    xs = np.geomspace(max(a, b * 1e-14), b, 200)
    scale = float(np.max(np.abs(filt(np.r_[a if a > 0 else 0.0, xs])))) if not filt.singular else float(
        np.max(np.abs(filt(xs))))
    return sup_error(err, a, b, scale=scale)


def heat_rational(t: float, degree: int, b: float):
    """Partial fractions of the CF approximant of e^{-ts} (sigma = t) and its error on [0, b]."""
    alpha0, coef, poles, _ = cf_exp(degree)
    pf = PartialFractions(alpha0, coef, poles, sigma=t)
    return pf


def fit_residues(x, y, poles, real: bool, lawson: int = 0):
    """Residues and constant for fixed poles: (weighted) least squares on samples (x, y)."""
    up = poles[poles.imag > 1e-12 * np.maximum(1.0, np.abs(poles))] if real else poles
    rp = poles[np.abs(poles.imag) <= 1e-12 * np.maximum(1.0, np.abs(poles))].real if real else np.array([])
    cols = [np.ones_like(x, dtype=float if real else complex)]
    for z in up:
        d = 1.0 / (x - z)
        cols += [2 * d.real, -2 * d.imag] if real else [d]
    for z in rp:
        cols.append(1.0 / (x - z))
    A = np.array(cols).T
    scale = np.max(np.abs(A), axis=0)
    A = A / scale
    sol = lawson_lstsq(A, y, max(1, lawson))[0] / scale
    if real:
        m = up.size
        cu = sol[1:1 + 2 * m:2] + 1j * sol[2:2 + 2 * m:2]
        cr = sol[1 + 2 * m:]
        return float(sol[0]), np.concatenate([cu, np.conj(cu), cr.astype(complex)]), \
            np.concatenate([up, np.conj(up), rp.astype(complex)])
    return complex(sol[0]), sol[1:], up


@serial_blas
def aaa_fit(fn, a: float, b: float, rtol: float = 1e-13, max_terms: int = 100, is_complex=False):
    """AAA rational fit of ``fn`` on [a, b], in partial fractions (None when unusable).

    The AAA poles are kept (minus spurious ones with negligible residues, or any on
    [a, b]); residues and the constant are refitted by least squares with the poles fixed
    (conjugate-symmetric for a real function).
    """
    import warnings

    from scipy.interpolate import AAA

    lo = a if a > 0 else b * 1e-12
    x = np.unique(np.concatenate([np.linspace(a, b, 1000), np.geomspace(lo, b, 1500), [a, b]]))
    y = fn(x)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = AAA(x, y, rtol=rtol, max_terms=max_terms)
        poles = r.poles()
        res = r.residues()
    except Exception:  # pragma: no cover - scipy raising on degenerate data
        return None
    scale = np.max(np.abs(y))
    keep = np.abs(res) > 1e-15 * scale * max(1.0, b - a)
    poles = poles[keep]
    on = (np.abs(poles.imag) < 1e-9 * (b - a + 1)) & (poles.real >= a) & (poles.real <= b)
    if np.any(on):
        return None
    real = not is_complex
    xf = np.unique(np.concatenate([x, np.linspace(a, b, 4000), np.geomspace(lo, b, 4000)]))
    yf = fn(xf)
    best = None
    for pol in (poles, spread_clusters(poles, a, b, rtol)):
        if pol is None:
            continue
        if real:  # symmetrise: keep upper poles and real ones
            tol_im = 1e-10 * np.maximum(1.0, np.abs(pol))
            pol = np.concatenate([pol[pol.imag > tol_im], pol[np.abs(pol.imag) <= tol_im].real + 0j])
        pf = PartialFractions(*fit_residues(xf, yf, pol, real), sigma=1.0)
        err = float(np.max(np.abs(pf(xf) - yf)))
        if best is None or err < best[0]:
            best = (err, pf)
        if err <= 10.0 * rtol * max(scale, 1e-300):
            break
    return best[1]


#: poles of an AAA fit closer to each other than this fraction of their distance to the
#: interval form a cluster (the fit's picture of a multiple pole)
CLUSTER_GAP = 0.05


def spread_clusters(poles, a: float, b: float, rtol: float):
    r"""The poles with each cluster replaced by a ring of well-separated ones, or None when
    there is no cluster.

    A pole of order k of the function is fitted by k simple poles a distance
    :math:`\sim \varepsilon^{1/k}` apart, whose residues are :math:`\varepsilon^{-(k-1)/k}` times the
    function: their partial fractions lose that much to rounding (a fit of
    :math:`(1+s)^{-4}` then stalls at 1e-7). m poles evenly spaced on a circle of radius R
    around the cluster's centre c represent every singularity inside the circle within
    :math:`(R/|s-c|)^m + (\rho/R)^m` (the trapezoid rule on the circle; ρ the cluster's
    radius), with residues of the function's size: R is a third of the distance to
    [a, b], m the even number making :math:`3^{-m}` below ``rtol``.
    """
    poles = np.asarray(poles, dtype=complex)
    if poles.size < 2:
        return None
    dist = np.abs(poles - np.clip(poles.real, a, b))
    gap = np.abs(poles[:, None] - poles[None, :]) < CLUSTER_GAP * np.minimum(dist[:, None], dist[None, :])
    label = np.arange(poles.size)
    for _ in range(poles.size):                     # single linkage: connected components
        new = np.min(np.where(gap, label[None, :], poles.size), axis=1)
        if np.array_equal(new, label):
            break
        label = new
    out, spread = [], False
    m = int(2 * np.ceil(np.log(max(rtol, 1e-16)) / np.log(1.0 / 3.0) / 2.0))
    for lab in np.unique(label):
        group = poles[label == lab]
        c = group.mean()
        radius = np.max(np.abs(group - c))
        R = abs(c - np.clip(c.real, a, b)) / 3.0
        if group.size < 2 or not 3.0 * radius < R:
            out.append(group)
            continue
        spread = True
        out.append(c + R * np.exp(1j * np.pi * (2 * np.arange(m) + 1) / m))
    return np.concatenate(out) if spread else None


def rounding(pf: PartialFractions, a: float, b: float, lam_max: float) -> float:
    """Relative rounding term of the solves: 64 eps x amplification x log-conditioning."""
    return 64 * EPS * pf.amplification(a, b) * (1.0 + np.log1p(lam_max * abs(pf.sigma)))


class RationalPlan:
    """The ``"rational"`` method: CF for heat, exact pseudo-solves for power filters, else AAA."""

    def __init__(self, lap, filt, a, b, tol, degree=None, backend="auto"):
        self.lap, self.filt, self.a, self.b, self.backend = lap, filt, a, b, backend
        self.proved = certifiable(filt)
        self.pseudo = 0
        self.pf = None
        if filt.kind == "heat":
            t = filt.params["t"]
            degrees = [int(degree)] if degree is not None else range(2, 17, 2)
            for r in degrees:
                pf = PartialFractions(*cf_exp(r)[:3], sigma=t)
                err = certify(pf, filt, a, b, tol)
                rnd = rounding(pf, a, b, b)
                if err + rnd <= tol or r == degrees[-1]:
                    break
            self.pf, self.scalar_error, self.rounding = pf, err, rnd
        elif filt.kind == "power":
            p = filt.params["p"]
            self.pseudo = int(np.floor(p + 1e-12))
            half = p - self.pseudo
            self.scalar_error, self.rounding = 0.0, 0.0
            if half > 1e-12:
                if abs(half - 0.5) > 1e-12:
                    raise ValueError(f"power filters need p = k/2, got p = {p}")
                root = commute_time()
                pf = aaa_fit(root, a, b, rtol=1e-13)
                if pf is None:
                    raise RuntimeError("rational fit of s^(-1/2) failed")
                self.pf = pf
                self.scalar_error = certify(pf, root, a, b)
                self.rounding = rounding(pf, a, b, b)
                self._half_filter = root
        else:
            pf = aaa_fit(filt, a, b, rtol=max(tol * 1e-3, 1e-13), is_complex=filt.is_complex)
            if pf is None:
                raise ValueError(f"no usable rational fit of {filt.name!r} on [{a:.3g}, {b:.3g}] "
                                 "(a pole on the spectrum); use method='chebyshev' or 'shift_invert'")
            self.pf = pf
            self.scalar_error = certify(pf, filt, a, b)
            self.rounding = rounding(pf, a, b, b)
        self.n_solves = (self.pf.n_solves if self.pf is not None else 0) + self.pseudo

    def _solve_bound(self, u, g):
        r"""Bound of :math:`\|u - \tilde L^+ B^{-1}g\|_B` for a computed pseudo-solve u.

        :math:`\|r\|_{B^{-1}} / \lambda_{\min}^+` with the residual :math:`r = Lu - Pg`, plus
        the rounding of computing r itself (:math:`\varepsilon(\lambda_{\max}\|u\|_B + \|g\|_{B^{-1}})`).
        """
        lap = self.lap
        Z = lap.component_basis()
        r = lap.L @ u - (g - lap.B @ (Z @ (Z.T @ g)))
        rnd = 64 * EPS * (self.b * bnorm(lap, u) + inv_bnorm_upper(lap, g))
        return (inv_bnorm_upper(lap, r) + rnd) / self.a

    def apply(self, f, rhs):
        """Returns (u, src, scalar): bound = scalar * ||src||_B + (exact-solve residual part)."""
        lap = self.lap
        src = None if rhs else f
        scal = self.scalar_error + self.rounding
        if self.pf is None:
            # integer power: u = (L̃⁺)^m f, m pseudo-solves (no solve with B for a kernel column)
            u = f
            res_bound = np.zeros(f.shape[1:]) if f.ndim == 2 else np.zeros(())
            for k in range(self.pseudo):
                rhs_k = u if (rhs and k == 0) else lap.B @ u
                u = pseudo_solve(lap, rhs_k, backend=self.backend)
                res_bound = res_bound / self.a + self._solve_bound(u, rhs_k)
            self.residual_bound = res_bound
            return u, src, 0.0
        # a kernel column with a non-diagonal B: rather than a solve with B for alpha0 B^-1 g,
        # drop alpha0 (tiny for the heat filter) and account for it in the bound
        keep0 = not (rhs and not lap.lumped and abs(self.pf.alpha0) <= 10 * scal)
        if not keep0:
            scal = scal + abs(self.pf.alpha0)
        if self.pseudo == 0:
            u = self.pf.apply(lap, f, rhs, backend=self.backend, with_alpha0=keep0)
            self.residual_bound = 0.0
            return u, src, scal
        # half-integer power: rational s^(-1/2), then integer pseudo-solves
        v = self.pf.apply(lap, f, rhs, backend=self.backend, with_alpha0=keep0)
        v = lap.project_out_kernel(v)
        u = v
        res_bound = 0.0
        for _ in range(self.pseudo):
            g = lap.B @ u
            u = pseudo_solve(lap, g, backend=self.backend)
            res_bound = res_bound / self.a + self._solve_bound(u, g)
        self.residual_bound = res_bound
        # the rational error is amplified by ||(L̃⁺)^m|| <= a^-m
        return u, src, scal / self.a ** self.pseudo
