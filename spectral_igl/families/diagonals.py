r"""Kernel diagonals of a family of filters sharing poles: one selected inversion per pole.

.. math:: \operatorname{diag} r_k(\tilde L)B^{-1} = \alpha_{0,k}\operatorname{diag}(B^{-1})
          + \sum_j c_{jk} \operatorname{diag}\big((L - z_jB)^{-1}\big),

so another member costs a weighted sum of the selected-inverse diagonals already computed
(the poles and residues: :mod:`.fits`). Each factor is dropped as soon as its diagonal is
taken, so at most one factor is held at a time. Then
:math:`|G^{(k)}_{ii} - R^{(k)}_{ii}| \le \varepsilon_k (B^{-1})_{ii}` at every vertex. With a
full mass matrix the same selected inversions also give each member's trace
:math:`\operatorname{tr} r_k(\tilde L)` (:class:`~spectral_igl.linalg.MassTraces`), within
:math:`n\varepsilon_k` of :math:`\operatorname{tr}\varphi_k(\tilde L)`.
"""
from __future__ import annotations

import logging

import numpy as np

from ..approx.rational import certifiable
from ..approx.common import mixed_heat, reciprocal_rounding
from ..laplacian import as_laplacian, lambda_max, lambda_max_kind
from ..linalg import MassTraces, inverse_mass_diagonal, lambda_min_positive, lambda_min_positive_kind, ldlt
from .fits import as_times, coefficients, family_poles, heat_plan, plan_poles, pole_factorizations

__all__ = ["MultiDiagonal", "family_diagonals", "diagonals_from_fits", "heat_diagonals"]

log = logging.getLogger(__name__)

EPS = np.finfo(float).eps


class MultiDiagonal:
    r"""Kernel diagonals of a family of filters from common poles.

    Attributes
    ----------
    values : (n, T) float
        :math:`R^{(k)}_{ii}`.
    eps : (T,) float
        Certified :math:`\max|\varphi_k - r_k|` on the spectrum's enclosure plus rounding.
    minv : (n,) float
        :math:`(B^{-1})_{ii}`.
    n_factorizations : int
        Sparse factorizations for the whole family (complex pairs and real poles).
    bound_kind : {"proof", "estimate"}
        ``"proof"`` when every member's sup error is proved (built-in filters, WKS
        included) and the spectrum's enclosure is certified.
    trace : (T,) float or None
        Full mass matrix (:func:`family_diagonals`): :math:`\operatorname{tr} r_k(\tilde L)`,
        from the same selected inversions; None with a lumped mass (there it is
        :math:`\sum_i m_i R^{(k)}_{ii}`).
    trace_bound : (T,) float or None
        Bound of :math:`|\operatorname{tr}\varphi_k(\tilde L) - \operatorname{tr} r_k(\tilde L)|`:
        :math:`n\varepsilon_k` plus the rounding of the sums.
    """

    def __init__(self, values, eps, minv, n_factorizations, poles, bound_kind="proof", trace=None,
                 trace_bound=None, replaced=None):
        self.values, self.eps, self.minv = values, np.asarray(eps, dtype=float), minv
        self.n_factorizations, self.poles = int(n_factorizations), poles
        self.bound_kind = bound_kind
        self.trace, self.trace_bound = trace, trace_bound
        #: None, or (mask (n, T), bound (n, T)): entries replaced by another value with its own
        #: bound (the projection of a component where the heat has mixed, :func:`heat_diagonals`)
        self.replaced = replaced

    @property
    def abs_bound(self) -> np.ndarray:
        r"""(n, T) certified :math:`|G^{(k)}_{ii} - R^{(k)}_{ii}| \le \varepsilon_k (B^{-1})_{ii}`
        (where an entry was replaced, its own bound)."""
        bound = self.minv[:, None] * self.eps[None, :]
        if self.replaced is not None:
            mask, own = self.replaced
            bound = np.where(mask, own, bound)
        return bound

    @property
    def nbytes(self) -> int:
        return int(self.values.nbytes + self.minv.nbytes)


def family_diagonals(lap, filters, targets, poles=None, a: float = 0.0, scales=None):
    """Diagonals of :math:`\\varphi_k(\\tilde L)B^{-1}` for a family of real filters with common poles.

    Parameters
    ----------
    lap : Laplacian
    filters : sequence of Filter, length T
    targets : (T,) float
        Largest certified sup error accepted for each member.
    poles : iterable of (upper, real), optional
        Candidate pole sets, fewest first (default: set-valued AAA at decreasing rtol).
    scales : (T,) float, optional
        Where each member varies (sample refinement).

    Returns
    -------
    MultiDiagonal
    """
    lap = as_laplacian(lap)
    if not ldlt.available():
        raise ValueError("common-pole diagonals need the compiled LDLT extension")
    b = lambda_max(lap)
    targets = np.broadcast_to(np.asarray(targets, dtype=float), (len(filters),))
    filters = list(filters)
    singular = any(f.singular for f in filters)
    if singular:    # fitted on [lambda_2, b]; what the fits put on ker L is taken out
        a = max(a, lambda_min_positive(lap))
    poles_given = poles is not None
    if poles is None:
        rt = max(float(np.min(targets)) * 1e-2, 1e-13)
        poles = (family_poles(filters, a, b, rtol=r, scales=scales) for r in (rt * 20, rt))
    sigma = 1.0 / np.sqrt(b * max(a, b * 1e-10)) if scales is None else 1.0 / float(np.median(scales))
    plan = plan_poles(filters, targets, a, b, sigma, poles, scales)
    if plan is None:
        raise ValueError("no common poles found for this family")
    upper, real, fits, eps = plan
    if not np.all(eps <= targets):
        bad = np.flatnonzero(eps > targets)
        if len(filters) == 1 or poles_given:
            raise ValueError(f"common poles reach only {eps[bad].max():.3g} for {bad.size} member(s) "
                             f"(target {targets[bad].min():.3g}); use fewer or closer scales")
        # a narrower family needs fewer poles for the same accuracy: halve it
        h = len(filters) // 2
        log.info("common poles: splitting a family of %d", len(filters))
        parts = [family_diagonals(lap, filters[sl], targets[sl], None, a,
                                  None if scales is None else scales[sl])
                 for sl in (slice(0, h), slice(h, None))]
        traced = parts[0].trace is not None
        return MultiDiagonal(np.concatenate([p.values for p in parts], axis=1),
                             np.concatenate([p.eps for p in parts]), parts[0].minv,
                             sum(p.n_factorizations for p in parts), [p.poles for p in parts],
                             "proof" if all(p.bound_kind == "proof" for p in parts) else "estimate",
                             np.concatenate([p.trace for p in parts]) if traced else None,
                             np.concatenate([p.trace_bound for p in parts]) if traced else None)
    traces = None if lap.lumped else MassTraces(lap, coefficients(fits, upper, real)[0])
    out = diagonals_from_fits(lap, upper, real, fits, eps, traces)
    if singular:
        r0 = np.array([float(np.real(pf(np.zeros(1))[0])) for pf, _ in fits])
        out.values -= np.outer(1.0 / lap.component_volume(), r0)
        if traces is not None:     # r(0)/V_c on each component: r(0) per component in the trace
            traces.subtract(lap.n_components * r0)
    if traces is not None:
        out.trace = traces.values
        out.trace_bound = lap.n * out.eps * (1.0 + 4.0 * EPS) + traces.rounding()
    proved = (all(certifiable(f) for f in filters) and lambda_max_kind(lap) == "proof"
              and (not singular or lambda_min_positive_kind(lap) == "proof"))
    out.bound_kind = "proof" if proved else "estimate"
    return out


def diagonals_from_fits(lap, upper, real, fits, eps, traces=None) -> MultiDiagonal:
    r"""The diagonals of fitted partial fractions with common poles: one factorization and one
    selected inversion per pole (a conjugate pair counts once), each factor dropped after use.
    Each member's r puts r(0)/V_c on ker L (the caller takes it out for singular filters).
    ``traces`` (a :class:`~spectral_igl.linalg.MassTraces` started with the members'
    :math:`\alpha_0`), when given, gathers the members' traces in the same pass."""
    minv = inverse_mass_diagonal(lap)
    al, C = coefficients(fits, upper, real)
    D = np.outer(minv, al)
    for j, (z, fac) in enumerate(pole_factorizations(lap, upper, real)):
        if traces is None:
            d = fac.inverse_diagonal()
        else:
            d = traces.inverse_diagonal(fac, (2.0 if j < upper.size else 1.0) * C[:, j])
        del fac
        if j < upper.size:    # a conjugate pair: 2 Re(c d)
            D += 2.0 * (np.outer(d.real, C[:, j].real) - np.outer(d.imag, C[:, j].imag))
        else:
            D += np.outer(d.real, C[:, j].real)
    log.info("family of %d diagonals: %d complex pairs + %d real poles", len(fits), upper.size, real.size)
    return MultiDiagonal(D, eps, minv, upper.size + real.size, (upper, real))


def heat_diagonals(lap, times, tol: float = 1e-8) -> MultiDiagonal:
    r"""Heat-kernel diagonals :math:`K_t(i, i)` at many times, sharing their factorizations.

    .. math:: K_t(i,i) = \big(e^{-t\tilde L}B^{-1}\big)_{ii} = \sum_l e^{-t\lambda_l} x_l(i)^2

    The times are grouped into ranges :math:`t_2/t_1 \le \max\Lambda` of :data:`HYPERBOLA`;
    each range gets one set of common poles (about 10--25 factorizations, whatever the
    number of times in it), and each time its own certified residues.

    Parameters
    ----------
    lap : Laplacian
    times : (T,) float
        Positive times (any order; repeats allowed).
    tol : float
        Relative accuracy: the certified bound is at most ``tol`` times :math:`K_t(i,i)`
        wherever the single-time path achieves that (see :func:`heat_targets`).

    Returns
    -------
    MultiDiagonal
        ``values`` (n, T) in the order of ``times``, ``eps`` (T,), ``abs_bound`` (n, T).

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> from spectral_igl.families import heat_diagonals
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> md = heat_diagonals(lap, [0.01, 0.03, 0.1])
    >>> md.values.shape, bool(np.all(md.abs_bound < 1e-6 * md.values))
    ((162, 3), True)
    """
    lap = as_laplacian(lap)
    T = as_times(times)
    key = ("heat_family", tuple(T.tolist()), float(tol))

    def build():
        u, inv = np.unique(T, return_inverse=True)
        plans = heat_plan(lap, u, tol)
        vals = np.empty((lap.n, u.size))
        eps = np.empty(u.size)
        nf = 0
        pls = []
        for g, upper, real, fits, e in plans:
            md = diagonals_from_fits(lap, upper, real, fits, e)
            vals[:, g], eps[g] = md.values, md.eps
            nf += md.n_factorizations
            pls.append(md.poles)
        minv = inverse_mass_diagonal(lap)
        # components where the heat has mixed to within a time's eps: the projection 1/V_c
        mask, own = np.zeros(vals.shape, bool), np.zeros(vals.shape)
        vol = lap.component_volume()
        for k, t in enumerate(u):
            mixed, decay = mixed_heat(lap, float(t), float(eps[k]))
            vals[mixed, k] = 1.0 / vol[mixed]
            mask[:, k], own[:, k] = mixed, np.where(mixed, decay * minv + reciprocal_rounding(lap) / vol, 0.0)
        replaced = (mask[:, inv], own[:, inv]) if mask.any() else None
        return MultiDiagonal(vals[:, inv], eps[inv], minv, nf, pls, replaced=replaced)

    return lap.cache.fetch("diagonal", key, build)
