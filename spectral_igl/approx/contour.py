r"""Contour-integral approximations: Talbot quadrature of the heat filter (Pusa 2011), and
Gauss--Legendre quadrature of Cauchy's integral for any analytic filter (the survey's
Algorithm 2, case II; :class:`GaussLegendrePlan`).

Talbot:

.. math:: e^{-x} = \frac{1}{2\pi i}\int_\Gamma \frac{e^{z}}{z + x}\,dz
          \approx \sum_{k=1}^{N} \frac{w_k}{z_k + x},

with the trapezoidal rule on Weideman's optimised Talbot contour
:math:`z(\theta) = N(0.5017\,\theta\cot(0.6407\,\theta) - 0.6122 + 0.2645\,i\theta)`,
:math:`\theta \in (-\pi, \pi)`. The nodes come in conjugate pairs, so :math:`N/2` complex
solves with :math:`z_k B + tL` give :math:`e^{-t\tilde L}f`; the error decays like
:math:`e^{-1.36 N}` uniformly on :math:`[0, \infty)`.
"""
from __future__ import annotations

import numpy as np

from .common import sample_grid
from .rational import PartialFractions, certifiable, certify, rounding


def talbot(N: int):
    """Nodes z_k and weights w_k of the N-point Talbot rule for e^{-x} = sum w_k/(z_k + x)."""
    N = int(N)
    th = -np.pi + (np.arange(1, N + 1) - 0.5) * 2 * np.pi / N
    a, b, c, d = 0.5017, 0.6407, 0.6122, 0.2645
    z = N * (a * th / np.tan(b * th) - c + 1j * d * th)
    dz = N * (a / np.tan(b * th) - a * b * th / np.sin(b * th) ** 2 + 1j * d)
    w = np.exp(z) * dz / (1j * N)
    return z, w


class ContourPlan:
    def __init__(self, lap, filt, a, b, tol, nodes=None, backend="auto"):
        t = filt.params["t"]
        self.lap, self.backend = lap, backend
        self.proved = True
        Ns = [int(nodes)] if nodes is not None else range(4, 41, 2)
        for N in Ns:
            z, w = talbot(N)
            pf = PartialFractions(0.0, w, -z, sigma=t)
            err = certify(pf, filt, a, b, tol)
            rnd = rounding(pf, a, b, b)
            if err + rnd <= tol:
                break
        self.pf, self.scalar_error, self.rounding, self.N = pf, err, rnd, N
        self.n_solves = pf.n_solves

    def apply(self, f, rhs):
        u = self.pf.apply(self.lap, f, rhs, backend=self.backend)
        return u, (None if rhs else f), self.scalar_error + self.rounding


# ----------------------------------------------------------------------------- Gauss-Legendre
#: node counts :class:`GaussLegendrePlan` tries, per half of the contour (one complex solve each)
GL_NODES = (2, 4, 6, 8, 10, 12, 16, 20, 24, 32, 40, 48, 64, 96, 128)

#: log ρ of the Bernstein ellipses :class:`GaussLegendrePlan` tries for each node count
GL_LOG_RHO = np.geomspace(0.01, 4.0, 40)


def ellipse_contour(a: float, b: float, rho: float, N: int, half: bool):
    r"""Nodes and weights of the Gauss--Legendre discretization of Cauchy's integral on the
    Bernstein ellipse :math:`E_\rho` of [a, b].

    With :math:`z(\theta) = c + h(\rho e^{i\theta} + \rho^{-1}e^{-i\theta})/2`, c and h the
    centre and half-width of [a, b], :math:`\varphi(s) = \frac{1}{2\pi i}\oint
    \frac{\varphi(z)}{z - s}\,dz` for s inside the ellipse; the N-point Gauss--Legendre rule
    is applied to :math:`\theta \in [0, \pi]` (``half``, the upper arc: for φ real on the real
    axis the lower arc gives the complex conjugate) or to each of :math:`[0, \pi]` and
    :math:`[\pi, 2\pi]`. Returns ``(z, q)`` with
    :math:`\varphi(s) \approx \sum_k q_k\varphi(z_k)/(z_k - s)` (times 2, real part, for ``half``).
    """
    x, w = np.polynomial.legendre.leggauss(int(N))
    theta, wt = 0.5 * np.pi * (x + 1.0), 0.5 * np.pi * w
    if not half:
        theta, wt = np.concatenate([theta, theta + np.pi]), np.concatenate([wt, wt])
    c, h = 0.5 * (a + b), 0.5 * (b - a)
    e = np.exp(1j * theta)
    z = c + 0.5 * h * (rho * e + 1.0 / (rho * e))
    dz = 0.5j * h * (rho * e - 1.0 / (rho * e))
    return z, wt * dz / (2j * np.pi)


def contour_values(filt, z):
    """φ at the complex nodes ``z`` (the analytic continuation of the filter's formula), or
    ValueError naming the filter when its function cannot be evaluated there."""
    try:
        with np.errstate(all="ignore"):
            v = np.asarray(filt.fn(np.asarray(z, dtype=complex)), dtype=complex)
    except (TypeError, ValueError, ArithmeticError) as err:
        raise ValueError(f"method 'gauss_legendre' evaluates the filter at complex points, and "
                         f"{filt.name!r} fails there ({err}); use 'rational' or 'chebyshev'") from err
    if v.shape != np.shape(z):
        v = np.broadcast_to(v, np.shape(z)).astype(complex)
    return v


def gauss_legendre_fractions(filt, a: float, b: float, rho: float, N: int) -> PartialFractions:
    r"""The partial fractions :math:`r(s) = \sum_k c_k/(s - z_k)` of N Gauss--Legendre nodes
    per arc of the ellipse :math:`E_\rho` of [a, b] (see :func:`ellipse_contour`); for a real
    filter the poles come in conjugate pairs (N complex solves)."""
    half = not filt.is_complex
    z, q = ellipse_contour(a, b, rho, N, half)
    with np.errstate(all="ignore"):
        w = q * contour_values(filt, z)
    if half:   # 2 Re[w/(z - s)] = w/(z - s) + conj(w)/(conj(z) - s)
        z, w = np.concatenate([z, np.conj(z)]), np.concatenate([w, np.conj(w)])
    return PartialFractions(0.0, -w, z, sigma=1.0)


def _largest_rho(filt, a: float, b: float) -> float:
    """The widest ellipse :class:`GaussLegendrePlan` may use: for a filter singular at 0, one
    whose leftmost point stays at a/2 or more."""
    if not filt.singular:
        return np.inf
    c, h = 0.5 * (a + b), 0.5 * (b - a)
    m = (c - 0.5 * a) / h                     # (ρ + 1/ρ)/2 at most m
    return m + np.sqrt(m * m - 1.0) if m > 1.0 else 1.0


def _best_ellipse(filt, a, b, N, rhos, xs, ref):
    """``(sampled error + rounding, fractions, rho, N)`` for the ellipse of ``rhos`` with the
    smallest sampled error at N nodes, or None when no ellipse gives finite values."""
    best = None
    for rho in rhos:
        with np.errstate(all="ignore"):
            pf = gauss_legendre_fractions(filt, a, b, rho, N)
            est = float(np.max(np.abs(pf(xs) - ref))) + rounding(pf, a, b, b)
        if np.isfinite(est) and (best is None or est < best[0]):
            best = (est, pf, rho, N)
    return best


class GaussLegendrePlan:
    r"""The ``"gauss_legendre"`` method: the survey's Algorithm 2, case II, for any filter
    analytic around the spectrum.

    Parameters
    ----------
    lap : Laplacian
    filt : Filter
        Its function must accept complex arrays (the analytic continuation of φ).
    a, b : float
        The spectral interval :math:`[a, \lambda_{\max}]` (certified by the operator).
    tol : float
        Target bound of :math:`\max_{[a, b]}|\varphi - r|` (relative to the signal's B-norm).
    nodes : int, optional
        Gauss--Legendre nodes per arc; default: the smallest of :data:`GL_NODES` that reaches
        ``tol``.
    backend : str
        Sparse solver of the shifted systems.

    Attributes
    ----------
    pf : PartialFractions
        :math:`r(s) = \sum_k c_k/(s - z_k)`.
    N, rho : int, float
        Nodes per arc and the ellipse.
    scalar_error, rounding : float
        The bound of :math:`\max_{[a, b]}|\varphi - r|` and the rounding allowance of the solves.
    proved : bool
        Whether ``scalar_error`` is a proof (built-in filters) or an estimate (a user's).

    Notes
    -----
    For s in [a, b] and φ analytic inside and on the Bernstein ellipse :math:`E_\rho` of [a, b],

    .. math:: \varphi(s) = \frac{1}{2\pi i}\oint_{E_\rho}\frac{\varphi(z)}{z - s}\,dz
              \approx \sum_{k=1}^{N} \frac{q_k\varphi(z_k)}{z_k - s} + \text{conj.}
              = \sum_k \frac{\alpha_k}{1 + \beta_k s},
              \quad \alpha_k = -\frac{q_k\varphi(z_k)}{z_k},\ \beta_k = -\frac{1}{z_k},

    with the N-point Gauss--Legendre rule on the upper arc :math:`\theta \in [0, \pi]` (the
    lower arc is its complex conjugate for a real filter; a complex filter takes both arcs, 2N
    solves). This is the partial-fraction form of the survey (its Eq. (7): each term is one
    solve with :math:`B + \beta_k L`, here :math:`L - z_kB`). The node count N and the ellipse
    ρ are the smallest N (and among 40 ellipses the best ρ) whose sampled error, rounding
    included, is below ``tol``/2; the error is then bounded on the whole interval by
    :func:`.rational.certify` (derivative bounds between samples: a proof for the built-in
    filters, a refined-sample estimate for a user's), which goes into the operator's
    bound :math:`\max_{[a,b]}|\varphi - r|\,\|f\|_B`. One ellipse around a wide interval
    converges slowly for a filter with a singularity near it (:math:`s^{-p}` at 0, a pole at
    :math:`-1/\tau`): the bound then says how far from ``tol`` the result is, and
    ``"rational"`` is the better method.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> op = sig.SpectralOperator(lap, sig.filters.heat(1e-3), method="gauss_legendre")
    >>> u = op.apply(np.ones(lap.n))
    >>> bool(np.allclose(u, 1.0)), op.bound_kind, op.n_solves == op.plan.N
    (True, 'proof', True)
    """

    def __init__(self, lap, filt, a, b, tol, nodes=None, backend="auto"):
        self.lap, self.backend = lap, backend
        self.proved = certifiable(filt)
        xs = sample_grid(a, b, 400)
        ref = filt(xs)
        rho_max = _largest_rho(filt, a, b)
        rhos = np.exp(GL_LOG_RHO)
        rhos = rhos[rhos < rho_max] if np.any(rhos < rho_max) else np.array([0.5 * (1.0 + rho_max)])
        best, chosen = None, None
        for N in ([int(nodes)] if nodes is not None else GL_NODES):
            here = _best_ellipse(filt, a, b, N, rhos, xs, ref)
            if here is None:
                continue
            if best is None or here[0] < best[0]:
                best = here
            if here[0] <= 0.5 * tol:
                err = certify(here[1], filt, a, b, tol)
                if err + rounding(here[1], a, b, b) <= tol:
                    chosen = here + (err,)
                    break
        if best is None:
            raise ValueError(f"method 'gauss_legendre' found no usable contour for {filt!r} on "
                             f"[{a:.3g}, {b:.3g}] (non-finite filter values on every ellipse)")
        if chosen is None:
            chosen = best + (certify(best[1], filt, a, b, tol),)
        _, self.pf, self.rho, self.N, self.scalar_error = chosen
        self.rounding = rounding(self.pf, a, b, b)
        self.n_solves = self.pf.n_solves

    def apply(self, f, rhs):
        u = self.pf.apply(self.lap, f, rhs, backend=self.backend)
        return u, (None if rhs else f), self.scalar_error + self.rounding
