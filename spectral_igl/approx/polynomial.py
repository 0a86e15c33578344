r"""Polynomial approximations of φ(L̃)f: Chebyshev, Taylor (the survey's Algorithm 2, case I),
and the heat solvers of the survey's Table 2: backward Euler, first-order Taylor, and the
truncated power series with scaling and squaring.

Each power of :math:`\tilde L = B^{-1}L` costs one product with L and one solve with B
(a division for a lumped mass, a cached Cholesky otherwise).
"""
from __future__ import annotations

import math

import numpy as np

from ..linalg import mass_solve, shifted_factor
from .common import (EPS, cheb_adaptive, certified_sup, ellipse_tails, filter_logmax, sampled_error, sup_error,
                     tail_sums)


def _ltilde(lap, v, backend):
    r""":math:`\tilde L v`, B-projected off ker L: the engine applies the approximations to
    the complement of ker L only, and the rounding must not bring the kernel back (where
    a Chebyshev recurrence mapped to :math:`[\lambda_{\min}^+, \lambda_{\max}]` would grow
    exponentially)."""
    return lap.project_out_kernel(mass_solve(lap, lap.L @ v, backend=backend))


class ChebyshevPlan:
    r"""Chebyshev expansion :math:`p_m(s) = \sum_{k \le m} c_k T_k(\frac{2s - a - b}{b - a})`.

    The coefficients are those of the Chebyshev interpolant of degree M (resolved to about
    machine precision). For the built-in filters the bound of
    :math:`\max_{[a,b]} |\varphi - p_m|` is proved: the coefficient tail beyond m plus twice the
    tail beyond M (the aliasing of the interpolant), both bounded from the maximum of φ on a
    Bernstein ellipse (:func:`.common.ellipse_tails`); m is the smallest degree meeting
    ``tol``. For a user filter the sampled tail plus an aliasing allowance is used (an
    estimate). Evaluation by the three-term recurrence (numerically stable, unlike the
    monomial form).
    """

    def __init__(self, lap, filt, a, b, tol, degree=None, max_degree=20000, backend="auto"):
        self.lap, self.a, self.b, self.backend = lap, a, b, backend
        fn = filt
        c, resolved = cheb_adaptive(fn, a, b, max_degree=2 ** int(np.ceil(np.log2(max(64, max_degree)))))
        M = c.size - 1
        alias = 2.0 * float(np.sum(np.abs(c[-(M // 8):])))
        tails = tail_sums(c)
        logmax = filter_logmax(fn, a, b)
        self.proved = logmax is not None
        if self.proved:   # proved tails beyond each degree, and the aliasing beyond M
            tails = ellipse_tails(logmax, np.arange(M + 2) - 1.0)
            alias = 2.0 * float(ellipse_tails(logmax, [M])[0])
            tails = np.minimum(tails, tails[0])   # tails[j]: beyond degree j - 1
        if degree is None:
            ok = np.flatnonzero(tails[1:] + alias + 4 * EPS * np.arange(1, M + 2) * np.abs(c).sum() <= tol)
            m = int(ok[0]) if ok.size else M
            m = min(m, max_degree)
        else:
            m = min(int(degree), M)
        self.m = m
        self.c = c[: m + 1]
        self.scalar_error = float(tails[m + 1] + alias)
        if not self.proved:   # the coefficients see φ only at Chebyshev points: check between them
            self.scalar_error = max(self.scalar_error, sampled_error(
                fn, lambda s: np.polynomial.chebyshev.chebval((2.0 * s - a - b) / (b - a), self.c), a, b))
        self.rounding = 4 * EPS * (m + 1) * float(np.abs(self.c).sum())
        self.n_solves = m

    def apply(self, f, rhs):
        lap, a, b = self.lap, self.a, self.b
        if rhs:
            f = mass_solve(lap, f, backend=self.backend)
        al, be = 2.0 / (b - a), -(a + b) / (b - a)

        def X(v):
            # the whole step B-projected off ker L, where T_k would grow like (1.0 + 2a/(b - a))^k
            return lap.project_out_kernel(al * mass_solve(lap, lap.L @ v, backend=self.backend) + be * v)

        c = self.c
        t0 = f
        out = c[0] * t0
        if self.m >= 1:
            t1 = X(f)
            out = out + c[1] * t1
            for k in range(2, self.m + 1):
                t0, t1 = t1, 2.0 * X(t1) - t0
                out = out + c[k] * t1
        return out, f, self.scalar_error + self.rounding


def _taylor_coeffs(filt, a, b, degree):
    """Monomial coefficients of φ: exact Taylor series at 0 for heat/wave, else from Chebyshev."""
    kind, t = filt.kind, filt.params.get("t")
    k = np.arange(degree + 1)
    if kind == "heat":
        return np.array([(-t) ** j / math.factorial(j) for j in k], dtype=float)
    if kind == "wave":
        return np.array([(-1j * t) ** j / math.factorial(j) for j in k], dtype=complex)
    from numpy.polynomial import Polynomial
    from numpy.polynomial import chebyshev as C

    c, _ = cheb_adaptive(filt, a, b, max_degree=4096)
    c = c[: degree + 1]
    p = Polynomial(C.cheb2poly(c.real)) if not np.iscomplexobj(c) else None
    x = Polynomial([-(a + b) / (b - a), 2.0 / (b - a)])
    if p is None:
        pr = Polynomial(C.cheb2poly(c.real))(x)
        pi = Polynomial(C.cheb2poly(c.imag))(x)
        out = _pad(pr.coef, degree) + 1j * _pad(pi.coef, degree)
    else:
        out = _pad(p(x).coef, degree)
    return out


def _pad(coef, degree):
    """``degree + 1`` coefficients: a short Chebyshev series (φ resolved by few terms) padded with 0."""
    out = np.zeros(degree + 1, dtype=coef.dtype)
    out[: min(coef.size, degree + 1)] = coef[: degree + 1]
    return out


class TaylorPlan:
    r"""The survey's Algorithm 2, case I: :math:`p_r(s) = \sum_{k \le r} \alpha_k s^k`,
    :math:`g_{k} = \tilde L g_{k-1}` (one B-solve each).

    For the heat and wave filters the :math:`\alpha_k` are the Taylor coefficients at 0
    and the Lagrange remainder :math:`(tb)^{r+1}/(r+1)!` bounds the error on [0, b]; for
    other filters they are the monomial coefficients of the truncated Chebyshev expansion
    on [a, b], whose tail bounds the error. The monomial form is numerically unstable when
    :math:`t\lambda_{\max}` is large; the bound includes the rounding term
    :math:`r\,\varepsilon \sum_k |\alpha_k| b^k`, so it says so.
    """

    def __init__(self, lap, filt, a, b, tol, degree=None, max_degree=60, backend="auto"):
        self.lap, self.backend = lap, backend
        best = None
        degrees = [int(degree)] if degree is not None else range(1, max_degree + 1)
        self.proved = True
        if filt.kind in ("heat", "wave"):
            x = filt.params["t"] * b
            remainder = lambda m: np.exp((m + 1) * np.log(x) - math.lgamma(m + 2)) if x > 0 else 0.0  # noqa: E731
        else:
            c, _ = cheb_adaptive(filt, a, b, max_degree=4096)
            tails = tail_sums(c)
            M = c.size - 1
            alias = 2.0 * float(np.sum(np.abs(c[-(M // 8):])))
            logmax = filter_logmax(filt, a, b)
            self.proved = logmax is not None
            if self.proved:
                tails = ellipse_tails(logmax, np.arange(M + 2) - 1.0)
                alias = 2.0 * float(ellipse_tails(logmax, [M])[0])
            remainder = lambda m: tails[min(m + 1, M + 1)] + alias  # noqa: E731
        for m in degrees:
            coef = _taylor_coeffs(filt, a, b, m)
            with np.errstate(over="ignore", invalid="ignore"):
                err = float(remainder(m))
                rnd = (m + 1) * 4 * EPS * float(np.sum(np.abs(coef) * b ** np.arange(m + 1)))
            tot = err + rnd
            if not np.isfinite(tot):
                tot = np.inf
            if best is None or tot < best[0]:
                best = (tot, m, coef, err, rnd)
            if tot <= tol:
                break
        _, self.m, self.coef, self.scalar_error, self.rounding = best
        if not self.proved:   # the tails see φ only at Chebyshev points: check between them
            self.scalar_error = max(self.scalar_error, sampled_error(
                filt, lambda s: np.polynomial.polynomial.polyval(s, self.coef), a, b))
        self.n_solves = self.m

    def apply(self, f, rhs):
        if rhs:
            f = mass_solve(self.lap, f, backend=self.backend)
        g = f
        out = self.coef[0] * f
        for k in range(1, self.m + 1):
            g = _ltilde(self.lap, g, self.backend)
            out = out + self.coef[k] * g
        return out, f, self.scalar_error + self.rounding


class EulerPlan:
    r"""Backward Euler, m steps: :math:`(I + \tfrac{t}{m}\tilde L)^{-m} f`, i.e.
    :math:`r(s) = (1 + ts/m)^{-m}`; each step is a solve with :math:`B + \tfrac{t}{m}L`
    (one cached Cholesky), and a kernel column needs no solve with B."""

    def __init__(self, lap, filt, a, b, tol, steps=1, backend="auto"):
        t = filt.params["t"]
        tol = float(tol)
        self.lap, self.t, self.m, self.backend = lap, t, int(steps), backend
        if self.m < 1:
            raise ValueError(f"steps must be a positive integer, got {steps}")
        m = self.m

        def err(s):
            r = (1.0 + t * s / m) ** (-m)
            return np.exp(-t * s) - r, 2.0 + m

        def d2(lo, hi):   # |phi''| + |r''|, both decreasing in s
            return t * t * (np.exp(-t * lo) + (m + 1.0) / m * (1.0 + t * lo / m) ** (-m - 2.0))

        self.proved = True
        self.scalar_error = certified_sup(err, d2, a, b, tol)
        self.rounding = 16 * EPS * m
        self.n_solves = m

    def apply(self, f, rhs):
        fac = shifted_factor(self.lap, self.t / self.m, 1.0, backend=self.backend)
        g = f
        for k in range(self.m):
            g = fac.solve(g if (rhs and k == 0) else self.lap.B @ g)
        # in rhs mode the caller bounds ||B^-1 g||_B without a solve
        return g, (None if rhs else f), self.scalar_error + self.rounding


class Taylor1Plan:
    r"""First-order Taylor: :math:`B F = (B - tL) f`, i.e. :math:`r(s) = 1 - ts`."""

    def __init__(self, lap, filt, a, b, tol, backend="auto"):
        t = filt.params["t"]
        self.lap, self.t, self.backend = lap, t, backend
        self.proved = True
        self.scalar_error = certified_sup(lambda s: (np.exp(-t * s) - (1.0 - t * s), 2.0 + t * s),
                                          lambda lo, hi: t * t * np.exp(-t * lo), a, b, tol)
        self.rounding = 8 * EPS * (1 + t * b)
        self.n_solves = 1

    def apply(self, f, rhs):
        if rhs:
            f = mass_solve(self.lap, f, backend=self.backend)
        return f - self.t * _ltilde(self.lap, f, self.backend), f, self.scalar_error + self.rounding


class PowerPlan:
    r"""Truncated exponential power series with scaling and squaring:
    :math:`r(s) = T_q(-ts/2^j)^{2^j}` with :math:`T_q(x) = \sum_{k \le q} x^k/k!`, i.e. the
    degree-q Taylor polynomial of :math:`e^{-t\tilde L/2^j}` applied :math:`2^j` times
    (:math:`q 2^j` B-solves). ``j`` makes :math:`t\lambda_{\max}/2^j \le 1/2`, and q is
    the smallest degree meeting ``tol``; the cost grows like :math:`t\lambda_{\max}`, and a
    ``ValueError`` is raised beyond ``max_solves``.
    """

    def __init__(self, lap, filt, a, b, tol, degree=None, squarings=None, max_solves=20000,
                 backend="auto"):
        t = filt.params["t"]
        self.lap, self.t, self.backend = lap, t, backend
        if squarings is None:
            j = max(0, int(np.ceil(np.log2(max(t * b / 0.5, 1.0)))))
        else:
            j = int(squarings)
        if 2 ** j > max_solves:
            raise ValueError(f"method 'power' needs 2^{j} squarings for t * lambda_max = {t * b:.3g} "
                             f"(more than max_solves = {max_solves} solves); use 'rational' or 'shift_invert'")
        self.j = j
        self.proved = False    # the sampled sup of |exp - r|: an estimate
        best = None
        qs = [int(degree)] if degree is not None else range(1, 31)
        for q in qs:
            coef = np.array([1.0 / math.factorial(k) for k in range(q + 1)])

            def r(s, coef=coef):
                with np.errstate(over="ignore", invalid="ignore"):
                    return np.polynomial.polynomial.polyval(-t * s / 2 ** j, coef) ** (2 ** j)

            with np.errstate(over="ignore", invalid="ignore"):
                err = sup_error(lambda s: np.exp(-t * s) - r(s), a, b, n=1500, scale=1.0)
            if not np.isfinite(err):
                err = np.inf
            if best is None or err < best[0]:
                best = (err, q)
            if err <= tol:
                break
        self.scalar_error, self.q = best
        self.rounding = 8 * EPS * self.q * 2 ** j * (1 + t * b / 2 ** j)
        self.n_solves = self.q * 2 ** j

    def apply(self, f, rhs):
        if rhs:
            f = mass_solve(self.lap, f, backend=self.backend)
        h = -self.t / 2 ** self.j
        u = f
        for _ in range(2 ** self.j):
            term, acc = u, u
            for k in range(1, self.q + 1):
                term = (h / k) * _ltilde(self.lap, term, self.backend)
                acc = acc + term
            u = acc
        return u, f, self.scalar_error + self.rounding
