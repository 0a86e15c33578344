r"""Kernel diagonals by selected inversion of the partial fractions of the filter."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

EPS = np.finfo(float).eps

from ..approx.common import mixed_heat, reciprocal_rounding
from ..approx.rational import RationalPlan, aaa_fit, certifiable, certify, rounding
from ..laplacian import lambda_max, lambda_max_kind
from ..laplacian.cache import SLOTS
from ..linalg import (
    MassTraces,
    grounded_factor,
    inverse_mass_diagonal,
    lambda_min_positive,
    lambda_min_positive_kind,
    ldlt,
    ldlt_factor,
    ldlt_pattern,
    mass_solve,
    pseudo_solve,
    shifted_factor,
)
from ..progress import progress_bar

#: constant of the a-priori rounding allowance of the exact paths (see
#: :meth:`SelinvKernel._rounding`), as in :func:`~spectral_igl.approx.rational.rounding`
ROUNDING_C = 64.0

#: nodes of the circle rule for the integer powers s^-p, p >= 3, and the radius as a
#: fraction of lambda_min_positive: aliasing error (1/3)^24 = 3.5e-12 relative
CIRCLE_NODES = 24
CIRCLE_RADIUS = 1.0 / 3.0

__all__ = ["SelinvKernel", "NoSelinv", "selinv_kernel", "selinv_supported"]


class NoSelinv(Exception):
    """The filter or the mass matrix is outside what ``"selinv"`` handles."""


def selinv_supported(lap, filt, delta: str = "mass") -> bool:
    """Whether :func:`~spectral_igl.kernel_diagonal` can use ``method="selinv"`` for this input."""
    if not ldlt.available() or (delta == "seed" and not lap.lumped):
        return False
    return not filt.is_complex


class SelinvKernel:
    r"""One approximation R of :math:`G = \varphi(\tilde L)B^{-1}` giving its diagonal (by
    selected inversion), its columns and the per-vertex bound :math:`|G_{ii} - R_{ii}|`.

    Distances built from the diagonal and a column of the same R are the exact distances
    of R: :math:`|d^2 - d_R^2| \le \varepsilon \|B^{-1}(e_i - e_j)\|_B^2`, with no error
    from mixing two approximations.
    """

    def __init__(self, lap, filt, tol):
        self.lap, self.filt = lap, filt
        p = filt.params.get("p") if filt.kind == "power" else None
        integer = p is not None and abs(p - round(p)) < 1e-12 and round(p) >= 1
        self.power = int(round(p)) if integer and round(p) in (1, 2) else 0
        self.circle = int(round(p)) if integer and round(p) >= 3 else 0
        self._diag = self._trace = None
        self._pending, self._done = [], []   # blocks E whose R E the diagonal's pass computes
        #: keep the diagonal's factorizations in ``lap.cache`` (for later columns) instead of
        #: dropping each after use
        self.keep_factors = False
        self.bound_kind = "proof"
        if self.circle:
            self._circle_setup()
        elif self.power:
            self.vol = lap.component_volume()
            self.w = np.asarray(lap.B.sum(axis=1)).ravel() / self.vol   # Q = I - 1 w^T per component
            self.fac, self.Lg, self.grounded = grounded_factor(lap)
            self.eps, self.n_factorizations = 0.0, 2
        else:
            self._rational(tol)
        # components where the heat has mixed: their projection, not the partial fractions
        self.mixed = None
        if filt.kind == "heat" and not self.circle and not self.power:
            mask, decay = mixed_heat(lap, filt.params["t"], self.eps)
            if mask.any():
                self.mixed = mask, decay, lap.component_volume()

    # ----------------------------------------------------------------- rational filters
    def _rational(self, tol):
        lap, filt = self.lap, self.filt
        b = lambda_max(lap)
        a = lambda_min_positive(lap) if filt.singular else 0.0
        self.minv = inverse_mass_diagonal(lap)
        if filt.kind == "power":
            pf = aaa_fit(filt, a, b, rtol=max(tol * 1e-3, 1e-13))
            if pf is None:
                raise NoSelinv("no usable rational fit")
            eps = certify(pf, filt, a, b) + rounding(pf, a, b, b)
            if not certifiable(filt):
                self.bound_kind = "estimate"
        else:
            g0 = abs(filt.at_zero())
            if g0 > 0:
                # |error_i| <= eps (B^-1)_ii and G_ii >= phi(0)/V_c (the constant mode; every
                # term of G_ii is >= 0 for phi = |psi|^2): this eps, relative to max |phi| as
                # the fits take it, makes the error at most tol G_ii at every vertex
                top = float(np.max(np.abs(filt(np.geomspace(max(b, 1e-300) * 1e-12, b, 200)))))
                rel = g0 / max(top, g0)
                tol = max(tol * rel * float(np.min(1.0 / (lap.component_volume() * self.minv))), 1e-15)
            try:
                plan = RationalPlan(lap, filt, a, b, tol)
            except (ValueError, RuntimeError) as exc:
                raise NoSelinv(str(exc)) from None
            pf, eps = plan.pf, plan.scalar_error + plan.rounding
            if not getattr(plan, "proved", False):
                self.bound_kind = "estimate"
        if filt.singular and lambda_min_positive_kind(lap) != "proof":
            self.bound_kind = "estimate"
        if lambda_max_kind(lap) != "proof":
            self.bound_kind = "estimate"
        for c, z, k in pf.terms:
            # a real pole inside the spectrum's hull makes sigma L - z B indefinite
            if abs(z.imag) <= 1e-12 * max(1.0, abs(z)) and 0.0 <= z.real / pf.sigma <= b:
                raise NoSelinv(f"real pole {z.real / pf.sigma:.3g} inside the spectrum")
            if filt.singular and abs(z / pf.sigma) < 0.5 * a:   # ker L would dominate that term
                raise NoSelinv(f"pole {z / pf.sigma:.3g} too close to the singularity at 0")
        self.pf, self.eps, self.n_factorizations = pf, eps, len(pf.terms)

    # ----------------------------------------------------------------- integer powers p >= 3
    def _circle_setup(self):
        r"""The kernel of :math:`s^{-p}`, p >= 3, by the circle rule on the resolvent.

        :math:`R(z) = (L - zB)^{-1} = -\frac{1}{z}ZZ^\top + \sum_{\lambda > 0} \frac{x x^\top}{\lambda - z}`,
        so :math:`G = \sum_{\lambda>0}\lambda^{-p}xx^\top` is the coefficient of :math:`z^{p-1}`
        of :math:`R(z) + ZZ^\top/z`, analytic in :math:`|z| < \lambda_{\min}^+`. The
        trapezoidal rule on the circle :math:`|z| = \rho` with N nodes gives it up to the
        aliased coefficients :math:`\sum_{m \ge 1} \rho^{mN} \sum_\lambda \lambda^{-p-mN}xx^\top`,
        whose diagonal is at most :math:`G_{ii}\,q/(1-q)`, :math:`q = (\rho/a)^N`, with a the
        certified :func:`~spectral_igl.linalg.lambda_min_positive`: a proved relative bound.
        The nodes come in conjugate pairs (N/2 complex LDLᵀ factorizations, each with a
        definite imaginary part, and their selected inverses).
        """
        lap = self.lap
        self.a = lambda_min_positive(lap)
        if lambda_min_positive_kind(lap) != "proof":
            self.bound_kind = "estimate"
        N = CIRCLE_NODES
        rho = CIRCLE_RADIUS * self.a
        th = 2.0 * np.pi * (np.arange(N // 2) + 0.5) / N           # upper half; conjugates implied
        self.nodes = rho * np.exp(1j * th)
        self.q = CIRCLE_RADIUS ** N
        self.n_factorizations = N // 2
        self.eps = 0.0

    def _circle_factors(self):
        for z in self.nodes:
            # theta B + beta L with theta = -z: imaginary part -Im(z) B, definite
            yield z, shifted_factor(self.lap, 1.0, -z, backend="ldlt")

    def _circle_diagonal(self):
        lap, p, N = self.lap, self.circle, CIRCLE_NODES
        zz = np.asarray(lap.component_basis().multiply(lap.component_basis()).sum(axis=1)).ravel()
        acc = np.zeros(lap.n)
        mag = np.zeros(lap.n)
        for z, fac in self._circle_factors():
            inv = fac.inverse_diagonal()
            scale = np.abs(z) ** (-(p - 1))
            term = (inv + zz / z) * z ** (-(p - 1))
            acc += 2.0 * term.real / N       # the node and its conjugate
            mag += 2.0 * (np.abs(inv) + np.abs(zz / z)) * scale / N
        diag = acc
        # the resolvent's eigenvalue 0 is at distance rho = a / 3 from the nodes (the
        # others at least 2a / 3), so its relative rounding carries 3 lambda_max / a
        bound = (self.q / (1.0 - self.q) * np.abs(diag) / (1.0 - 2.0 * self.q)
                 + self._rounding(mag, p, 1.0 / CIRCLE_RADIUS))
        return diag, bound

    def _factors(self, keep: bool = True):
        for c, z, k in self.pf.terms:
            theta = -z.real if z.imag == 0 else -z
            yield c, k, shifted_factor(self.lap, self.pf.sigma, theta, backend="ldlt", keep=keep)

    def _kernel_part(self):
        """r(0) / V_c: what r puts on ker L, where a singular filter is 0."""
        return float(np.real(self.pf(np.zeros(1))[0])) / self.lap.component_volume()

    # ----------------------------------------------------------------- exact powers
    def _X(self, b):
        """The grounded pseudo-inverse X (zero rows at the grounded vertices)."""
        x = self.fac.solve(b)
        x[self.grounded] = 0.0
        return x

    def _commute(self, V):
        r""":math:`Q X Q^\top V` for V of shape (n, k): the kernel of :math:`s^{-1}`."""
        w = self.w[:, None]
        Y = self._X(V - w * self.lap.component_sum(V))
        return Y - self.lap.component_sum(w * Y)

    def _rounding(self, mag, order: int, spread: float = 1.0) -> np.ndarray:
        r"""A-priori rounding allowance of an exact path (no approximation error to hide it).

        A symmetric factorization without growth is the exact factorization of a matrix
        within :math:`c\,\varepsilon` of the one factorized, relative to its norm (Higham,
        *Accuracy and Stability*, ch. 10): it moves every eigenvalue λ of the pencil
        :math:`(L, B)` by at most about :math:`c\,\varepsilon\,\lambda_{\max}`, so each term
        :math:`\lambda^{-p}x(i)^2` of the kernel by the relative amount
        :math:`p\,c\,\varepsilon\,\lambda_{\max}/d`, d the distance of the factorized shift to
        the spectrum (:math:`d \ge \lambda_{\min}^+/`\ ``spread``). The diagonal is a signed
        sum of such terms whose magnitudes add up to ``mag`` (per vertex), hence

        .. math:: c\,\varepsilon\, p\,(1 + \texttt{spread}\;\lambda_{\max}/\lambda_{\min}^+)\,
                  \mathrm{mag}_i, \qquad c = 64.

        Zero would claim exact arithmetic: on a 2000-vertex mesh with
        :math:`\lambda_{\max}/\lambda_{\min}^+ = 5\cdot 10^6` the biharmonic distance's diagonal is
        off by :math:`10^{-11}` relative.
        """
        kappa = lambda_max(self.lap) / lambda_min_positive(self.lap)
        return ROUNDING_C * EPS * order * (1.0 + spread * kappa) * np.abs(mag)

    # ----------------------------------------------------------------- public
    def prime(self, E) -> None:
        """Have the diagonal's pass (if still to come) also compute R E: each pole's factor
        serves its selected inversion and its solves (a one-to-all distance needs the
        diagonal and a column, the diagonal's check a few columns). The factors are kept in
        ``lap.cache`` for the columns of later calls (a second source) when all of them fit in
        the cache's factor budget (:meth:`factors_fit`), else each is dropped
        after use, so the pass holds one factorization at a time."""
        if self._diag is None and not (self.circle or self.power):
            self._pending.append(np.array(E, dtype=float, copy=True))
            self.keep_factors = self.keep_factors or self.factors_fit()

    def factors_fit(self) -> bool:
        """Whether the factorizations of every pole fit in the factor budget of ``lap.cache``
        (and its entry limit), by the size of the symbolic analysis; older factorizations
        make room, least recently used first."""
        if self.circle or self.power:
            return True
        terms = self.pf.terms
        per_pole = ldlt_pattern(self.lap).nnz_L * np.dtype(np.complex128).itemsize
        return len(terms) * per_pole <= self.lap.cache.factor_budget and len(terms) <= SLOTS["factor"][1]

    def columns(self, E):
        """R E for E of shape (n, k)."""
        lap = self.lap
        for j, (Ej, Rj) in enumerate(self._done):
            if Ej.shape == np.shape(E) and np.array_equal(Ej, E):
                del self._done[j]
                return Rj
        if self.circle:                     # (L~+)^p B^-1 E: p exact pseudo-solves
            u = pseudo_solve(lap, E)
            for _ in range(self.circle - 1):
                u = pseudo_solve(lap, lap.B @ u)
            return u
        if self.power == 1:
            return self._commute(E)
        if self.power == 2:                 # G = G_c B G_c
            return self._commute(lap.B @ self._commute(E))
        out = np.zeros(E.shape)
        for c, k, fac in self._factors():
            out += k * (c * fac.solve(E)).real       # a conjugate pair (k = 2): 2 Re(c x)
        out += self.pf.alpha0.real * mass_solve(lap, E, backend="ldlt")
        if self.filt.singular:
            out -= self._kernel_part()[:, None] * self.lap.component_sum(E)
        return self._mix(E, out)

    def _mix(self, E, out):
        """``out`` = R E with the rows of mixed components (:func:`mixed_heat`) replaced by the
        projection :math:`1_c 1_c^\top E / V_c` (R is block diagonal over components)."""
        if self.mixed is not None:
            mask, _, vol = self.mixed
            out[mask] = (self.lap.component_sum(E) / (vol[:, None] if E.ndim == 2 else vol))[mask]
        return out

    def diagonal(self, progress=None):
        """(diag R, per-vertex bound of |G_ii - R_ii|), computed once."""
        if self._diag is None:
            if self.circle:
                self._diag = self._circle_diagonal()
            else:
                self._diag = self._power_diagonal() if self.power else self._rational_diagonal(progress)
        return self._diag

    def trace(self, progress=None):
        r"""``(tr r(L~), bound)`` for a full mass matrix: the trace of R B, computed in the
        diagonal's pass (one selected inversion per pole serves both, see
        :class:`~spectral_igl.linalg.MassTraces`), and a bound of
        :math:`|\operatorname{tr}\varphi(\tilde L) - \operatorname{tr}(RB)|`.

        :math:`\operatorname{tr}\varphi(\tilde L) - \operatorname{tr} r(\tilde L) =
        \sum_l (\varphi - r)(\lambda_l)` over the n eigenvalues (r put to 0 on ker L for a
        singular filter, as :math:`\varphi`), each term within :math:`\varepsilon` (the
        certified sup error on the spectrum's enclosure plus the solves' rounding, as for the
        diagonal): the bound is :math:`n\varepsilon` plus the rounding of the sums.
        """
        if self.lap.lumped or self.circle or self.power:
            raise NoSelinv("the kernel's trace is computed for partial fractions and a full mass matrix "
                           "(with a lumped mass it is the mass-weighted diagonal)")
        self.diagonal(progress)
        return self._trace

    def _rational_diagonal(self, progress=None):
        lap = self.lap
        diag = np.zeros(lap.n)
        blocks, self._pending = self._pending, []
        E = np.hstack(blocks) if blocks else None
        out = None if E is None else np.zeros(E.shape)
        traces = None if lap.lumped else MassTraces(lap, self.pf.alpha0.real)
        with progress_bar(len(self.pf.terms), "kernel diagonal", progress, unit="pole") as bar:
            for c, k, fac in self._factors(keep=self.keep_factors):
                d = fac.inverse_diagonal() if traces is None else traces.inverse_diagonal(fac, k * c)
                diag += k * (c * d).real
                if E is not None:
                    out += k * (c * fac.solve(E)).real
                del fac
                bar.update()
        diag += self.pf.alpha0.real * self.minv
        if self.filt.singular:
            diag -= self._kernel_part()
            if traces is not None:    # r(0)/V_c on each component: r(0) per component in the trace
                traces.subtract(lap.n_components * float(np.real(self.pf(np.zeros(1))[0])))
        if traces is not None:
            self._trace = (float(traces.values[0]),
                           float(lap.n * self.eps * (1.0 + 4.0 * EPS) + traces.rounding()[0]))
        if E is not None:
            out += self.pf.alpha0.real * mass_solve(self.lap, E, backend="ldlt")
            if self.filt.singular:
                out -= self._kernel_part()[:, None] * self.lap.component_sum(E)
            out = self._mix(E, out)
            cuts = np.cumsum([b.shape[1] for b in blocks])[:-1]
            self._done = list(zip(blocks, np.split(out, cuts, axis=1)))
        bound = self.eps * self.minv
        if self.mixed is not None:
            # |G_ii - 1/V_c| <= e^{-t mu_c} (B^-1)_ii, and fl(1/V_c) to its rounding
            mask, decay, vol = self.mixed
            diag[mask] = 1.0 / vol[mask]
            bound[mask] = (decay * self.minv + reciprocal_rounding(self.lap) / vol)[mask]
        return diag, bound

    def _power_diagonal(self):
        lap, w, vol = self.lap, self.w, self.vol
        u = self._X(w)
        if self.power == 1:
            xd = self.fac.inverse_diagonal()
            xd[self.grounded] = 0.0
            mdiag, Mw = xd, u
            mag_d, mag_w = np.abs(xd), np.abs(u)
        else:
            # G = Q (X B X - V u u^T) Q^T, since Q^T B Q = B - V w w^T per component.
            # diag(X B X) is the derivative at z = 0 of diag((L_g - z B_g)^-1) (B_g: B
            # without the grounded rows), taken by a complex step: Im diag((L_g - ihB_g)^-1)/h
            # is sum_l x_l(i)^2 / (mu_l^2 + h^2), exact to rounding for h = 1e-20 lambda_max,
            # and nothing cancels.
            h = 1e-20 * lambda_max(lap)
            keep = sp.diags((~self.grounded).astype(float))
            step = ldlt_factor(lap, (self.Lg - 1j * h * (keep @ lap.B @ keep)).tocsr())
            xbx = step.inverse_diagonal().imag / h
            xbx[self.grounded] = 0.0
            mdiag = xbx - vol * u * u
            xbu = self._X(lap.B @ u)
            Mw = xbu - vol * u * self.lap.component_sum(u * w)
            mag_d = np.abs(xbx) + vol * u * u
            mag_w = np.abs(xbu) + vol * np.abs(u) * self.lap.component_sum(np.abs(u * w))
        # diag(Q M Q^T) = M_ii - 2 (M w)_i + (w^T M w)_c(i)
        diag = mdiag - 2.0 * Mw + self.lap.component_sum(w * Mw)
        mag = mag_d + 2.0 * mag_w + self.lap.component_sum(np.abs(w) * mag_w)
        return diag, self._rounding(mag, self.power)


def selinv_kernel(lap, filt, tol: float) -> SelinvKernel:
    """The :class:`SelinvKernel` of ``(filt, tol)``, cached on ``lap`` (filters are values, so an
    equal filter built anew finds it)."""
    return lap.cache.fetch("kernel", (filt, float(tol)), lambda: SelinvKernel(lap, filt, tol))
