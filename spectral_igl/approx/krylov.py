r"""Lanczos in the B-inner product: polynomial Krylov (the survey's Table 2) and shift-and-invert.

For an operator A that is self-adjoint in :math:`\langle\cdot,\cdot\rangle_B`, m Lanczos steps
from f give :math:`Q_m` (B-orthonormal) and the tridiagonal :math:`T_m`, and
:math:`g(A)f \approx \|f\|_B Q_m g(T_m) e_1`. A classical bound (e.g. Saad 1992; the Ritz
values stay in the interval [α, β] containing the spectrum) gives

.. math:: \|g(A)f - \|f\|_B Q_m g(T_m)e_1\|_B \le 2 \min_{p \in \mathcal P_{m-1}}
          \max_{y \in [\alpha, \beta]} |g(y) - p(y)| \; \|f\|_B,

which we bound by the tail of the Chebyshev series of g on [α, β]: an a-priori bound, so m
is chosen before any solve. Full B-reorthogonalisation keeps the recurrence faithful.

- ``"krylov"``: :math:`A = \tilde L`, g = φ, [α, β] = [a, λ_max] (one B-solve per step).
- ``"shift_invert"``: :math:`A = (I + \gamma\tilde L)^{-1}`, :math:`g(y) = \varphi((1/y - 1)/\gamma)`
  on :math:`[1/(1 + \gamma\lambda_{\max}), 1/(1 + \gamma a)]`: one real Cholesky of
  :math:`B + \gamma L`, then one solve per step. For the heat filter with
  :math:`\gamma \approx t/2` the function g does not depend on t or on the mesh, so the
  number of steps for a given tolerance is the same at every t. A kernel column
  :math:`\varphi(\tilde L)B^{-1}g` starts from :math:`Af = (B + \gamma L)^{-1}g` with
  :math:`g(y)/y`: no solve with B at all.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..linalg import mass_solve, shifted_factor
from .common import EPS, cheb_coeffs, ellipse_tails, filter_logmax, sample_grid, tail_sums


def _cheb_fit(g, lo, hi, max_degree):
    r"""Chebyshev coefficients of g on [lo, hi] and ``miss``, the largest deviation of their
    series from g on :func:`.common.sample_grid` (linear, geometric and Chebyshev points)
    and on points geometrically graded towards hi.

    The degree doubles from 64 until the last eighth of the coefficients is at the rounding
    level *and* the series matches g on the sample, or ``max_degree`` is reached. The
    coefficients alone cannot see a feature narrower than the spacing of the Chebyshev
    points (a bump near 0 of a wide spectrum: every sample ~0, a zero series, a zero
    "tail"); the geometric points near both ends can.
    """
    xs = sample_grid(lo, hi, 400)
    if hi > lo:     # geometric towards hi too (shift-invert maps s near 0 to y near hi)
        xs = np.unique(np.concatenate([xs, hi - np.geomspace(1e-14 * (hi - lo), hi - lo, 400)]))
        xs = xs[(xs >= lo) & (xs <= hi)]
    with np.errstate(all="ignore"):
        gx = np.asarray(g(xs))
    top = float(np.max(np.abs(gx))) if np.all(np.isfinite(gx)) else np.inf
    X = (2.0 * xs - (lo + hi)) / (hi - lo) if hi > lo else np.zeros_like(xs)
    m = 64
    while True:
        c = cheb_coeffs(g, lo, hi, m)
        scale = max(float(np.max(np.abs(c))), top)
        tail = float(np.max(np.abs(c[-(m // 8):])))
        miss = float(np.max(np.abs(np.polynomial.chebyshev.chebval(X, c) - gx)))
        if not np.isfinite(miss):
            miss = np.inf
        if (tail <= 8 * EPS * scale and miss <= 64 * EPS * scale) or m >= max_degree:
            return c, miss
        m *= 2


def _cheb_steps(g, lo, hi, tol, max_steps, logmax=None, steps=None):
    """Smallest m with 2 * (Chebyshev tail of g beyond degree m-1) <= tol (or the given ``steps``).

    With ``logmax`` (log of a bound of |g| on the Bernstein ellipses of [lo, hi]) the tails
    are proved (:func:`.common.ellipse_tails`); when the proved tail does not reach ``tol``
    within ``max_steps``, or without ``logmax``, the sampled tail plus an aliasing allowance
    and the sampled misfit of the series (:func:`_cheb_fit`) is used (an estimate). Returns
    ``(m, bound, scale, proved)``.
    """
    c, miss = _cheb_fit(g, lo, hi, max(128, 2 * (max_steps if steps is None else max(int(steps), 2))))
    M = c.size - 1
    scale = float(np.max(np.abs(c)))
    if logmax is not None:
        bound = 2.0 * ellipse_tails(logmax, np.arange(1, M + 2) - 1.0)
        if steps is not None and int(steps) <= M + 1 and np.isfinite(bound[int(steps) - 1]):
            return int(steps), float(bound[int(steps) - 1]), scale, True
        ok = np.flatnonzero(bound[:max_steps] <= tol)
        if steps is None and ok.size:
            m = int(ok[0]) + 1
            return m, float(bound[m - 1]), scale, True
    alias = 2.0 * float(np.sum(np.abs(c[-(M // 8):])))
    tails = tail_sums(c)  # tails[m] = error of degree m-1 truncation
    bound = 2.0 * (tails[1:] + alias + miss)  # index m-1 -> m steps
    if steps is not None:
        m = int(steps)
        return m, 2.0 * (float(tails[min(m, M + 1)]) + alias + miss), scale, False
    ok = np.flatnonzero(bound <= tol)
    m = int(ok[0]) + 1 if ok.size else min(M, max_steps)
    m = min(m, max_steps)
    return m, float(bound[m - 1]), scale, False


def lanczos(op, f, Bf, m, lap):
    """Batched B-Lanczos with full reorthogonalisation, columns of f independent.

    ``f``, ``Bf``: (n, k). ``op`` maps (n,) or (n, k) arrays. Returns
    (alpha (m, k), beta (m, k), Q (k, m, n), beta0 (k,), m_eff (k,)).
    """
    n, k = f.shape
    dt = np.result_type(f, Bf, float)
    beta0 = np.sqrt(np.maximum(np.real(np.sum(np.conj(f) * Bf, axis=0)), 0.0))
    safe = np.where(beta0 > 0, beta0, 1.0)
    Q = np.zeros((k, m, n), dtype=dt)
    BQ = np.zeros((k, m, n), dtype=dt)
    Q[:, 0] = (f / safe).T
    BQ[:, 0] = (Bf / safe).T
    alpha = np.zeros((m, k))
    beta = np.zeros((m, k))
    m_eff = np.where(beta0 > 0, m, 0)
    alive = beta0 > 0
    for j in range(m):
        q = Q[:, j]
        w = op(q[0]) if k == 1 else op(np.ascontiguousarray(q.T))
        w = np.atleast_2d(np.asarray(w).T).astype(dt, copy=False) if k == 1 else np.ascontiguousarray(w.T)
        w = w.reshape(k, n)
        a = np.real(np.sum(np.conj(BQ[:, j]) * w, axis=1))
        alpha[j] = np.where(alive, a, 0.0)
        for _ in range(2):  # full reorthogonalisation in the B-inner product, twice
            h = np.matmul(np.conj(BQ[:, : j + 1]), w[:, :, None])  # (k, j+1, 1)
            w = w - np.matmul(Q[:, : j + 1].transpose(0, 2, 1), h)[:, :, 0]
        Bw = (lap.B @ w.T).T
        b = np.sqrt(np.maximum(np.real(np.sum(np.conj(w) * Bw, axis=1)), 0.0))
        dead = alive & (b <= 1e-13 * np.maximum(np.abs(alpha[: j + 1]).max(axis=0), 1e-300))
        m_eff = np.where(dead, j + 1, m_eff)
        alive = alive & ~dead
        beta[j] = np.where(alive, b, 0.0)
        if j + 1 == m or not alive.any():
            break
        sb = np.where(alive, b, 1.0)[:, None]
        Q[:, j + 1] = np.where(alive[:, None], w / sb, 0.0)
        BQ[:, j + 1] = np.where(alive[:, None], Bw / sb, 0.0)
    return alpha, beta, Q, beta0, m_eff


def lanczos_eval(g, alpha, beta, Q, beta0, m_eff, lo, hi, is_complex):
    k = alpha.shape[1]
    n = Q.shape[2]
    out = np.zeros((n, k), dtype=complex if is_complex else float)
    for c in range(k):
        mc = int(m_eff[c])
        if mc == 0:
            continue
        d, e = alpha[:mc, c], beta[: mc - 1, c]
        if mc == 1:
            th, S = d.copy(), np.ones((1, 1))
        else:
            th, S = sla.eigh_tridiagonal(d, e)
        y = S @ (g(np.clip(th, lo, hi)) * S[0, :])
        out[:, c] = beta0[c] * (Q[c, :mc].T @ y)
    return out


class KrylovPlan:
    """Polynomial Lanczos on L̃ = B⁻¹L (the survey's Table 2 Krylov projection)."""

    def __init__(self, lap, filt, a, b, tol, steps=None, max_steps=3000, backend="auto"):
        self.lap, self.filt, self.a, self.b, self.backend = lap, filt, a, b, backend
        logmax = filter_logmax(filt, a, b)
        m, err, scale, self.proved = _cheb_steps(filt, a, b, tol, max_steps, logmax, steps)
        self.m = m
        self.scalar_error = err
        self.rounding = 64 * EPS * m * scale
        self.n_solves = m

    def apply(self, f, rhs):
        lap = self.lap
        if rhs:
            f = mass_solve(lap, f, backend=self.backend)
        F = f.reshape(f.shape[0], -1)

        def op(v):   # on the complement of ker L (kept there against rounding)
            return lap.project_out_kernel(mass_solve(lap, lap.L @ v, backend=self.backend))

        al, be, Q, b0, me = lanczos(op, F, lap.B @ F, self.m, lap)
        out = lanczos_eval(self.filt, al, be, Q, b0, me, self.a, self.b,
                           self.filt.is_complex or np.iscomplexobj(F))
        return (out.reshape(f.shape) if f.ndim == 1 else out), f, self.scalar_error + self.rounding


#: narrowest spectrum interval [1/(1 + gamma b), 1/(1 + gamma a)] of (I + gamma L~)^-1 that
#: shift-and-invert Lanczos is used on. Below it (small gamma b: short times) A is the identity
#: up to the width, and a few steps lost what their bound assumes: on a tet box and on two
#: spheres at t = 1e-7 (widths 7.5e-5 and 4.5e-5, 4 steps) errors reached 1300 and 76 times
#: the bound for some right-hand sides, with AVX2 and pre-AVX BLAS kernels alike; at widths
#: from 4.5e-4 up, over 50 right-hand sides on five shapes, at most 0.74 of it
SHIFT_INVERT_MIN_WIDTH = 1e-3


class ShiftInvertPlan:
    """Shift-and-invert Lanczos with one real factorization of B + γL."""

    def __init__(self, lap, filt, a, b, tol, shift=None, steps=None, max_steps=400, backend="auto"):
        self.lap, self.filt, self.a, self.b, self.backend = lap, filt, a, b, backend
        if shift is None:
            cands = self._candidates(filt, a, b)
        else:
            cands = [float(shift)]
        best = None
        for gam in cands:
            lo, hi = 1.0 / (1.0 + gam * b), 1.0 / (1.0 + gam * a)
            if hi - lo < SHIFT_INVERT_MIN_WIDTH:
                continue
            g = self._g(gam)
            m, err, scale, proved = _cheb_steps(g, lo, hi, tol, max_steps, self._logmax(gam, lo, hi), steps)
            if best is None or (not proved, m, err) < (not best[4], best[0], best[1]):
                best = (m, err, scale, gam, proved)
        if best is None:
            raise ValueError(
                f"method='shift_invert' cannot bound {filt!r} here: every shift gamma it would use "
                f"({', '.join(f'{g:.3g}' for g in cands)}) maps the spectrum [{a:.3g}, {b:.3g}] into an "
                f"interval narrower than {SHIFT_INVERT_MIN_WIDTH:g}, where its Lanczos recurrence "
                "loses the information its bound assumes; use method='rational' or 'chebyshev'")
        self.m, self.scalar_error, scale, self.gamma, self.proved = best
        self.rounding = 64 * EPS * self.m * scale
        self.lo, self.hi = 1.0 / (1.0 + self.gamma * b), 1.0 / (1.0 + self.gamma * a)
        self.n_solves = self.m
        self.tol = tol
        self._rhs_plan = None

    @staticmethod
    def _candidates(filt, a, b):
        t = filt.params.get("t")
        if filt.kind == "heat":
            return [t * c for c in (0.25, 0.5, 0.75, 1.0, 1.5)]
        lo = max(a, b * 1e-10)
        base = list(np.geomspace(1.0 / b, 1.0 / lo, 13))
        if t is not None:
            base += [t * c for c in (0.25, 0.5, 1.0, 2.0)]
        return base

    def _logmax(self, gam, lo, hi, divide=False):
        r"""For the heat and Mexican-hat (``t s e^{-ts}``) filters, log of a bound of :math:`|g|`
        (or :math:`|g(y)/y|`) on the Bernstein ellipse :math:`E_\rho` of [lo, hi]; None for
        other filters. For the Mexican hat, :math:`g(y) = q(1/y - 1)e^{-q(1/y - 1)}` adds
        :math:`\log q + \log(1 + 1/\min|y|)` to the heat's bound.

        :math:`|g(y)| = e^{q(1 - \mathrm{Re}(1/y))}` with :math:`q = t/\gamma`. On
        :math:`y = c + A u + iB\sqrt{1-u^2}`, :math:`\mathrm{Re}(1/y) = (c + Au)/Q(u)` with the
        quadratic :math:`Q(u) = |y|^2 = d^2u^2 + 2cAu + c^2 + B^2`, so its minimum over
        :math:`u \in [-1, 1]` is attained at ±1 or at a root of the quadratic
        :math:`Ad^2u^2 + 2cd^2u + A(c^2 - B^2)` (the zero of the derivative): exact, no sampling.
        Only ellipses with y = 0 outside (c - A > 0) are used.
        """
        if self.filt.kind not in ("heat", "mexican_hat"):
            return None
        mexican = self.filt.kind == "mexican_hat"
        q = self.filt.params["t"] / gam
        c, d = 0.5 * (lo + hi), 0.5 * (hi - lo)

        def lm(rho):
            A, Bm = d * 0.5 * (rho + 1.0 / rho), d * 0.5 * (rho - 1.0 / rho)
            if not c - A > 0:      # y = 0 (the essential singularity) must lie outside E_rho
                return np.inf
            d2 = d * d
            us = [-1.0, 1.0]
            qa, qb, qc = A * d2, 2.0 * c * d2, A * (c * c - Bm * Bm)
            disc = qb * qb - 4.0 * qa * qc
            if qa > 0 and disc >= 0:
                us += [(-qb + sg * np.sqrt(disc)) / (2.0 * qa) for sg in (-1.0, 1.0)]
            us = np.array([u for u in us if -1.0 <= u <= 1.0])

            def Q(u):
                return d2 * u * u + 2.0 * c * A * u + c * c + Bm * Bm

            uq = np.clip(-c * A / d2, -1.0, 1.0) if d2 > 0 else -1.0
            qmin = min(Q(uq), Q(-1.0), Q(1.0))
            if not qmin > 1e-300:
                return np.inf
            fmin = float(np.min((c + A * us) / Q(us)))
            val = q * (1.0 - fmin)
            if mexican:    # |q (1/y - 1)| <= q (1 / |y| + 1) times the heat's factor
                val += np.log(q) + np.log1p(1.0 / np.sqrt(qmin))
            if divide:
                val -= 0.5 * np.log(qmin)
            return val * (1.0 + 1e-12) + 1e-12 * (1.0 + q)
        return lm

    def _g(self, gam, divide=False):
        filt = self.filt

        def g(y):
            s = (1.0 / y - 1.0) / gam
            v = filt(np.maximum(s, 0.0))
            return v / y if divide else v

        return g

    def apply(self, f, rhs):
        lap = self.lap
        fac = shifted_factor(lap, self.gamma, 1.0, backend=self.backend)
        F = f.reshape(f.shape[0], -1)

        def op(v):   # on the complement of ker L (kept there against rounding)
            return lap.project_out_kernel(fac.solve(lap.B @ v))

        if rhs:
            # φ(L̃)B⁻¹g = h(A) (A B⁻¹ g), h(y) = g(y)/y, A B⁻¹ g = (B + γL)⁻¹ g
            if self._rhs_plan is None:
                h = self._g(self.gamma, divide=True)
                m, err, scale, proved = _cheb_steps(h, self.lo, self.hi, self.tol, 400,
                                                    self._logmax(self.gamma, self.lo, self.hi, divide=True))
                self.proved = self.proved and proved
                self._rhs_plan = (h, m, err, 64 * EPS * m * scale)
            h, m, err, rnd = self._rhs_plan
            F0 = fac.solve(F)
            al, be, Q, b0, me = lanczos(op, F0, lap.B @ F0, m, lap)
            out = lanczos_eval(h, al, be, Q, b0, me, self.lo, self.hi,
                               self.filt.is_complex or np.iscomplexobj(F))
            return ((out.reshape(f.shape) if f.ndim == 1 else out),
                    (F0.reshape(f.shape) if f.ndim == 1 else F0), err + rnd)
        al, be, Q, b0, me = lanczos(op, F, lap.B @ F, self.m, lap)
        out = lanczos_eval(self._g(self.gamma), al, be, Q, b0, me, self.lo, self.hi,
                           self.filt.is_complex or np.iscomplexobj(F))
        return (out.reshape(f.shape) if f.ndim == 1 else out), f, self.scalar_error + self.rounding
