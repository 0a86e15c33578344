"""Entropic optimal transport: the Gaussian of geodesic distances on the densities' support, or
the heat kernel (convolutional Wasserstein distance)."""
from __future__ import annotations

import warnings

import numpy as np

from .._validate import (as_flag, as_indices, as_int, as_positive, as_signal, as_tol, check_dense_size,
                         describe)
from ..laplacian import as_laplacian
from ..laplacian.units import mean_edge_length
from .geodesics import HeatGeodesics
from .heat_steps import PositiveHeat, log_apply

__all__ = ["wasserstein_distance", "sinkhorn", "wasserstein_barycenter", "GeodesicKernel", "KERNELS",
           "SUPPORT_TAIL", "GAMMA_H2", "GEODESIC_DOMAINS", "density_support", "relaxation_factor"]

#: ``kernel`` choices of the transport functions
KERNELS = ("auto", "geodesic", "heat")
#: domains whose ``kernel="auto"`` is the geodesic kernel (those of the heat method)
GEODESIC_DOMAINS = ("triangle", "tet", "polygon", "points")
#: fraction of each density's mass left out of its support (its smallest values)
SUPPORT_TAIL = 1e-14
#: default ``gamma`` in units of the squared mean edge length
GAMMA_H2 = 10.0


def density_support(mass, mus, tail: float = SUPPORT_TAIL):
    r"""The vertices that carry all but a fraction ``tail`` of each density's mass.

    For each column :math:`\mu` the smallest entries of :math:`m_i\mu_i` are dropped while
    their sum stays :math:`\le` ``tail`` :math:`\sum_i m_i\mu_i`; the support is the union
    over the columns of the vertices kept.

    Parameters
    ----------
    mass : (n,) float
        Lumped vertex areas :math:`m`.
    mus : (n,) or (n, k) float
        Non-negative densities.
    tail : float
        Fraction of each density's mass that may be left out, in [0, 1).

    Returns
    -------
    index : (s,) int
        Sorted vertex indices of the support.
    dropped : float
        Largest fraction of a density's mass outside the support.

    Notes
    -----
    A Gaussian bump :math:`e^{-d^2/2w^2}` keeps all but :math:`10^{-14}` of its mass
    within :math:`d \approx 8w`: entropic transport between narrow bumps runs on a few
    hundred vertices whatever the size of the mesh. Leaving out a fraction
    :math:`\delta` of the mass changes the transport cost by at most about
    :math:`\delta\,\mathrm{diam}^2`.

    Examples
    --------
    >>> import numpy as np
    >>> idx, dropped = density_support(np.ones(4), np.array([1.0, 1e-20, 0.0, 2.0]))
    >>> idx.tolist(), dropped < 1e-14
    ([0, 3], True)
    """
    mus = np.asarray(mus, dtype=float).reshape(len(mass), -1)
    keep = np.zeros(len(mass), dtype=bool)
    dropped = 0.0
    for mu in mus.T:
        m = mass * mu
        order = np.argsort(m, kind="stable")
        tails = np.cumsum(m[order])
        cut = int(np.searchsorted(tails, tail * tails[-1], side="right"))
        keep[order[cut:]] = True
        dropped = max(dropped, float(tails[cut - 1] / tails[-1]) if cut else 0.0)
    return np.flatnonzero(keep), dropped


class GeodesicKernel:
    r"""The Gaussian of geodesic distances :math:`K_{ij} = e^{-d_{ij}^2/\gamma}\,m_j` between
    vertex sets: rows ``rows``, columns ``cols``.

    :math:`d` is the heat-method geodesic distance (:class:`~.geodesics.HeatGeodesics`,
    the solver cached on the Laplacian), one heat-method solve per column's vertex;
    where the row and column sets are equal, it is symmetrised, :math:`(d_{ij} + d_{ji})/2`.
    :math:`m` are the lumped vertex areas. Unlike a mesh heat kernel it is Gaussian in
    :math:`d` at every distance, so the entropic cost it defines is :math:`d^2` up to the
    heat method's error, on a mesh of any size: its cost is that of ``len(cols)``
    heat-method solves and its memory ``len(rows) * len(cols)`` numbers, never :math:`n^2`
    unless the sets are the whole shape.

    Parameters
    ----------
    lap : Laplacian
        A triangle, tetrahedral, polygon mesh or point-cloud Laplacian.
    gamma : float
        Width :math:`\gamma` (length squared).
    rows, cols : (s,) int, optional
        Vertex indices; default every vertex.

    Notes
    -----
    .. math:: (K x)_i = \sum_{j \in \text{cols}} e^{-d_{ij}^2/\gamma}\, m_j\, x_j,
              \qquad (K^* y)_j = \sum_{i \in \text{rows}} e^{-d_{ij}^2/\gamma}\, m_i\, y_i

    Both are computed in the log domain (:meth:`log_apply`, :meth:`log_apply_adjoint`), so
    that no kernel entry underflows however small.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(3)
    >>> K = GeodesicKernel(sig.laplacian(V, F), 0.1, rows=[0, 1, 2], cols=[0, 5])
    >>> K.logE.shape
    (3, 2)
    """

    def __init__(self, lap, gamma: float, rows=None, cols=None):
        lap = as_laplacian(lap)
        if lap.domain not in GEODESIC_DOMAINS:
            raise ValueError(f"the geodesic kernel needs a mesh or point cloud, got a {lap.domain} "
                             "Laplacian; use kernel='heat'")
        self.gamma = as_positive(gamma, "gamma")
        everyone = np.arange(lap.n)
        self.rows = everyone if rows is None else as_indices(rows, lap.n, "rows").reshape(-1)
        self.cols = everyone if cols is None else as_indices(cols, lap.n, "cols").reshape(-1)
        # the distances, their log-kernel and a log-sum-exp temporary
        check_dense_size(3 * 8.0 * self.rows.size * self.cols.size,
                         f"the dense ({self.rows.size}, {self.cols.size}) geodesic kernel",
                         "narrow the densities' supports, or use kernel='heat' (sparse heat steps, "
                         "O(n) memory)")
        self.n = lap.n
        self.mass_rows, self.mass_cols = lap.mass[self.rows], lap.mass[self.cols]
        self.logE = -(_cached_distances(lap, self.rows, self.cols) ** 2) / self.gamma
        finite = self.logE[np.isfinite(self.logE)]
        # a dense product is exact enough while no kernel entry underflows
        self._E = np.exp(self.logE) if finite.size and finite.min() > -700.0 else None

    @property
    def mass(self) -> np.ndarray:
        """Lumped areas of the row vertices."""
        return self.mass_rows

    def log_apply(self, logX: np.ndarray) -> np.ndarray:
        r"""Column-wise :math:`\log K e^{X}`, X on the columns' vertices: (len(cols), k) ->
        (len(rows), k)."""
        if self._E is not None:
            return log_apply(lambda X: self._E @ (self.mass_cols[:, None] * X), logX)
        return _logsumexp_product(self.logE, np.log(self.mass_cols), logX)

    def log_apply_adjoint(self, logY: np.ndarray) -> np.ndarray:
        r"""Column-wise :math:`\log K^{*} e^{Y}`, Y on the rows' vertices: (len(rows), k) ->
        (len(cols), k)."""
        if self._E is not None:
            return log_apply(lambda Y: self._E.T @ (self.mass_rows[:, None] * Y), logY)
        return _logsumexp_product(self.logE.T, np.log(self.mass_rows), logY)


def _logsumexp_product(logE, logm, logX):
    """Column-wise log sum_j exp(logE[i, j] + logm[j] + logX[j, c])."""
    from scipy.special import logsumexp

    with np.errstate(divide="ignore"):
        return np.stack([logsumexp(logE + (logX[:, c] + logm)[None, :], axis=1)
                         for c in range(logX.shape[1])], axis=1)


#: largest distance block (entries) kept in the Laplacian's cache
CACHED_DISTANCES_MAX = 25_000_000


def _cached_distances(lap, rows, cols):
    if rows.size * cols.size > CACHED_DISTANCES_MAX:
        return _distances(lap, rows, cols)
    return lap.cache.fetch("kernel", ("geodesic_distances", _key(rows), _key(cols)),
                           lambda: _distances(lap, rows, cols))


def _key(index):
    import hashlib

    return (index.size, hashlib.sha1(np.ascontiguousarray(index, dtype=np.int64).tobytes()).hexdigest())


def _distances(lap, rows, cols):
    """Heat-method distances from each of ``cols`` to ``rows``, (len(rows), len(cols)); symmetrised
    when the two sets are equal."""
    solver = lap.cache.fetch("factor", ("heat_geodesics",), lambda: HeatGeodesics(lap))
    D = np.empty((rows.size, cols.size))
    with warnings.catch_warnings():
        # distances far below the straight line come back raised to it: the kernel takes them so
        warnings.filterwarnings("ignore", "the heat method put", RuntimeWarning)
        for a in range(0, cols.size, 128):
            D[:, a:a + 128] = solver.compute_each(cols[a:a + 128])[rows]
    if rows.size == cols.size and np.array_equal(rows, cols):
        D = 0.5 * (D + D.T)
        np.fill_diagonal(D, 0.0)
    return np.maximum(D, 0.0)


def _log_apply_adjoint(kern, logY):
    r""":math:`\log K^* e^Y`: the heat kernel is self-adjoint in the mass inner product."""
    return kern.log_apply_adjoint(logY) if isinstance(kern, GeodesicKernel) else kern.log_apply(logY)


def _density(lap, mu, name, mass):
    mu = as_signal(mu, lap.n, name, allow_complex=False)
    if mu.ndim != 1:
        raise ValueError(f"{name} must have shape ({lap.n},), got shape {mu.shape}")
    if np.any(mu < 0):
        raise ValueError(f"{name} must be non-negative")
    total = float(mass @ mu)
    if total <= 0:
        raise ValueError(f"{name} has zero mass")
    return mu / total


#: relative difference of a component's mass between two densities taken as rounding
COMPONENT_MASS_RTOL = 1e-9


def _check_components(lap, named) -> None:
    """Refuse densities that put different fractions of their mass on a connected component.

    No mass crosses between components (the kernel is exactly 0 there), so no transport
    plan exists and Sinkhorn's scalings diverge (NaN) whatever gamma. ``named``: a list of
    ``(name, density)`` normalised to unit mass.
    """
    if lap.n_components == 1 or len(named) < 2:
        return
    a = lap.mass
    shares = [(name, np.bincount(lap.components, weights=a * mu, minlength=lap.n_components))
              for name, mu in named]
    (n0, s0), rest = shares[0], shares[1:]
    for name, s in rest:
        gap = np.abs(s - s0)
        if gap.max() > COMPONENT_MASS_RTOL:
            c = int(np.argmax(gap))
            raise ValueError(f"{n0} and {name} put different fractions of their mass on connected component "
                             f"{c} ({s0[c]:.6g} and {s[c]:.6g}; the shape has {lap.n_components} components): "
                             "no mass moves between components, so no transport plan exists; compare the "
                             "densities on each component separately, or give them equal mass on each")


def _kernel(lap, gamma, kernel, steps, heat=None, rows=None, cols=None):
    """The transport kernel: a given PositiveHeat, or by ``kernel`` (see :data:`KERNELS`); a
    geodesic kernel between ``rows`` and ``cols`` (default every vertex)."""
    if heat is not None:
        if not isinstance(heat, PositiveHeat) or heat.n != lap.n:
            raise TypeError(f"heat must be a PositiveHeat of this Laplacian, got {describe(heat)}")
        if not np.isclose(heat.t, gamma / 4.0, rtol=1e-12):
            raise ValueError(f"heat has t = {heat.t:g}, but gamma / 4 = {gamma / 4.0:g}")
        return heat
    if not isinstance(kernel, str) or kernel not in KERNELS:
        raise ValueError(f"kernel must be one of {KERNELS}, got {describe(kernel)}")
    as_int(steps, "steps", lo=1, hi=10 ** 4)
    if kernel == "geodesic" or (kernel == "auto" and lap.domain in GEODESIC_DOMAINS):
        return GeodesicKernel(lap, gamma, rows, cols)
    return PositiveHeat(lap, gamma / 4.0, steps=steps)


def _restriction(kern, n, index):
    """The vertices a kernel acts on: ``index`` for a geodesic kernel, every vertex for heat."""
    return index if isinstance(kern, GeodesicKernel) else np.arange(n)


def _log(mu):
    with np.errstate(divide="ignore"):
        return np.log(mu)


#: plain Sinkhorn iterations over which the rate is measured (after as many more), to set the
#: over-relaxation factor
RELAX_WINDOW = 10
#: largest over-relaxation factor
RELAX_MAX = 1.9


def relaxation_factor(rate: float) -> float:
    r"""Over-relaxation factor of Sinkhorn's iteration from its plain convergence rate.

    .. math:: \omega = \frac{2}{1 + \sqrt{1 - \rho}}

    Young's optimal SOR factor for a Gauss-Seidel iteration of rate :math:`\rho`, the
    rule of Thibault et al. (2017) for Sinkhorn, capped at :data:`RELAX_MAX`.

    Parameters
    ----------
    rate : float
        Observed linear rate :math:`\rho` of the plain iteration's marginal error.

    Returns
    -------
    float
        :math:`\omega \in [1,` :data:`RELAX_MAX` :math:`]`; 1 (no relaxation) unless
        :math:`0 < \rho < 1`.

    Examples
    --------
    >>> round(relaxation_factor(0.977), 3), relaxation_factor(1.5)
    (1.737, 1.0)
    """
    if not 0.0 < rate < 1.0:
        return 1.0
    return float(min(RELAX_MAX, 2.0 / (1.0 + np.sqrt(1.0 - rate))))


def _sinkhorn_block(heat, A, B, gamma, max_iter, tol):
    """Log-domain Sinkhorn for the columns of A (first marginals) and B (second), over-relaxed.

    :data:`RELAX_WINDOW` plain iterations after as many more (the first ones drop
    faster) measure the rate, then both updates are
    over-relaxed by :func:`relaxation_factor`, and plain again to the end if the error grows
    a thousandfold or its rate over a window is no better than the plain one (a mode that
    relaxation slows, e.g. the oscillation of a symmetric problem). The
    result always ends on a plain update of ``w``, so that the second marginal is exact
    and the first is the reported ``marginal_error``.
    """
    a = heat.mass
    logA, logB = _log(A), _log(B)
    sA, sB = A > 0, B > 0
    logv = np.where(sA, 0.0, -np.inf)
    logw = np.where(sB, 0.0, -np.inf)
    err = np.full(A.shape[1], np.inf)
    history, omega, plain, relax, plain_rate, it = [], 1.0, True, True, 1.0, 0

    def first_marginal_error(logv, kw):
        marg = np.where(sA, np.exp(np.where(sA, logv + kw, -np.inf)), 0.0)
        return a @ np.abs(marg - A)

    def relaxed(old, new, w):
        return np.where(np.isfinite(new), (1.0 - w) * np.where(np.isfinite(old), old, 0.0) + w * new, -np.inf)

    for it in range(1, int(max_iter) + 1):
        kw = heat.log_apply(logw)
        err = first_marginal_error(logv, kw)
        if np.all(err < tol) and plain:
            break
        if np.all(err < tol):
            # a relaxed w: one plain update of w makes the second marginal exact, then recheck
            logw = np.where(sB, logB - heat.log_apply(logv), -np.inf)
            plain = True
            continue
        e = float(err.max())
        history.append(e)
        rate = (e / history[-1 - RELAX_WINDOW]) ** (1.0 / RELAX_WINDOW) if len(history) > 2 * RELAX_WINDOW else None
        if omega > 1.0 and (e > 1e3 * min(history) or (rate is not None and not rate < plain_rate)):
            omega, relax = 1.0, False              # relaxed slower than plain here: plain to the end
        elif omega == 1.0 and relax and rate is not None:
            omega, plain_rate, history = relaxation_factor(rate), rate, [e]
        logv = relaxed(logv, np.where(sA, logA - kw, -np.inf), omega)
        logw = relaxed(logw, np.where(sB, logB - heat.log_apply(logv), -np.inf), omega)
        plain = omega == 1.0
    value = gamma * (a @ (A * np.where(sA, logv, 0.0)) + a @ (B * np.where(sB, logw, 0.0)))
    return value, {"iterations": it, "marginal_error": err, "converged": bool(np.all(err < tol) and plain),
                   "logv": logv, "logw": logw}


def _check_iter(max_iter, tol):
    as_int(max_iter, "max_iter", lo=1, hi=10 ** 7)
    return as_tol(tol, "tol")


def _gamma(lap, gamma):
    """``gamma``, or its default :data:`GAMMA_H2` h^2 (h the mean edge length)."""
    if gamma is not None:
        return as_positive(gamma, "gamma")
    try:
        h = mean_edge_length(lap)
    except ValueError:
        raise ValueError(f"gamma is required on a {lap.domain!r} Laplacian without vertex positions "
                         "(its default is 10 h^2, h the mean edge length)") from None
    return GAMMA_H2 * h * h


def _prepare(lap, named, gamma, kernel, steps, heat=None, whole_rows=False):
    """Densities normalised to unit mass, their kernel and the vertices it acts on.

    ``named``: ``(name, density)`` pairs. Returns ``(kern, index, densities, dropped)``:
    ``densities`` (len(cols), k) restricted to the kernel's columns and normalised there,
    ``index`` the kernel's column vertices (its rows too unless ``whole_rows``).
    """
    dens = [_density(lap, mu, name, lap.mass) for name, mu in named]
    _check_components(lap, list(zip([name for name, _ in named], dens)))
    cols, dropped = density_support(lap.mass, np.stack(dens, axis=1))
    kern = _kernel(lap, gamma, kernel, steps, heat, None if whole_rows else cols, cols)
    index = _restriction(kern, lap.n, cols)
    dropped = dropped if index.size < lap.n else 0.0
    mass = kern.mass_cols if isinstance(kern, GeodesicKernel) else kern.mass
    dens = np.stack([mu[index] / (mass @ mu[index]) for mu in dens], axis=1)
    return kern, index, dens, dropped


def _kernel_name(kern):
    return "geodesic" if isinstance(kern, GeodesicKernel) else "heat"


def sinkhorn(lap, mu0, mu1, gamma=None, heat=None, kernel: str = "auto", steps: int = 16,
             max_iter: int = 5000, tol: float = 1e-9):
    r"""Entropic transport between densities ``mu0`` and ``mu1`` (Solomon et al. 2015).

    Sinkhorn iterations on log-potentials with a kernel :math:`K(x, y) \propto
    e^{-d(x, y)^2/\gamma}`:

    .. math:: v \leftarrow \mu_0 / K w, \qquad w \leftarrow \mu_1 / K v

    ``kernel="geodesic"``: :class:`GeodesicKernel`, the Gaussian of heat-method geodesic
    distances on the vertices that carry the densities' mass (:func:`density_support`).
    ``kernel="heat"``: the heat kernel at :math:`t = \gamma/4`, applied by
    :class:`~spectral_igl.applications.heat_steps.PositiveHeat` (``steps`` backward-Euler
    steps with a Metzler stiffness and the lumped mass; positive and relatively accurate
    however small the kernel); Gaussian in d only out to a few :math:`t/h`. ``"auto"``:
    geodesic on meshes and point clouds of every size (:data:`GEODESIC_DOMAINS`), heat on
    other domains.

    Parameters
    ----------
    lap : Laplacian
    mu0, mu1 : (n,) float
        Non-negative densities, normalised here to :math:`\int\mu\,dA = 1` (lumped areas).
    gamma : float, optional
        Entropic regularisation, length squared; default :data:`GAMMA_H2` :math:`h^2`
        (h the mean edge length).
    heat : PositiveHeat, optional
        A heat kernel at :math:`t = \gamma/4`, to reuse across calls (``kernel`` is then ignored).
    kernel : {"auto", "geodesic", "heat"}
        See above.
    steps : int
        Backward-Euler steps of the heat kernel.
    max_iter, tol
        Iterations and tolerance on the :math:`L^1` marginal error.

    Returns
    -------
    value : float
        :math:`\gamma \int (\mu_0 \log v + \mu_1 \log w)\,dA`, the entropic transport
        cost up to a constant that does not depend on the inputs.
    info : dict
        ``iterations``, ``marginal_error``, ``converged``, ``logv``, ``logw`` ((n,), ``-inf``
        outside the support), ``kernel``, ``gamma``, ``support`` (vertices the kernel acts
        on), ``dropped_mass`` (largest fraction of a density's mass left out of it).

    Notes
    -----
    The densities are restricted to :func:`density_support` (all but a fraction
    :data:`SUPPORT_TAIL` of each one's mass) for the geodesic kernel; the heat kernel acts on
    every vertex.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(3)
    >>> lap = sig.laplacian(V, F)
    >>> mu0 = np.exp(-20 * np.sum((V - V[0]) ** 2, axis=1))
    >>> value, info = sinkhorn(lap, mu0, mu0[::-1].copy(), 0.1)
    >>> info["converged"], info["kernel"]
    (True, 'geodesic')
    """
    lap = as_laplacian(lap)
    gamma = _gamma(lap, gamma)
    tol = _check_iter(max_iter, tol)
    kern, index, dens, dropped = _prepare(lap, [("mu0", mu0), ("mu1", mu1)], gamma, kernel, steps, heat)
    value, info = _sinkhorn_block(kern, dens[:, :1], dens[:, 1:], gamma, max_iter, tol)
    for k in ("logv", "logw"):
        full = np.full(lap.n, -np.inf)
        full[index] = info[k][:, 0]
        info[k] = full
    info.update(marginal_error=float(info["marginal_error"][0]), kernel=_kernel_name(kern), gamma=gamma,
                support=index.size, dropped_mass=dropped)
    return float(value[0]), info


def wasserstein_distance(lap, mu0, mu1, gamma=None, kernel: str = "auto", steps: int = 16,
                         max_iter: int = 5000, tol: float = 1e-9, return_info: bool = False):
    r"""Debiased entropic 2-Wasserstein distance (Sinkhorn divergence).

    .. math::
        W_\gamma(\mu_0, \mu_1) = \Big(S_\gamma(\mu_0, \mu_1)
        - \tfrac12 S_\gamma(\mu_0, \mu_0) - \tfrac12 S_\gamma(\mu_1, \mu_1)\Big)^{1/2}

    with :math:`S_\gamma` the entropic transport cost of :func:`sinkhorn` (Solomon et al.
    2015, convolutional Wasserstein). The three problems are solved together, by the
    same iteration on one block of three columns, so equal inputs give exactly 0 and
    nearly equal inputs nearly 0 (no special case); the kernel's normalisation cancels
    and the entropic blur is removed to first order: between a density and its
    translate in the plane the divergence is the squared translation for every
    :math:`\gamma`.

    Parameters
    ----------
    lap : Laplacian
    mu0, mu1 : (n,) float
        Non-negative densities per unit area (normalised here so that
        :math:`\int \mu\, dA = 1` with the lumped areas).
    gamma : float, optional
        Entropic regularisation, in units of length squared: the kernel is
        :math:`\propto e^{-d^2/\gamma}`. Default :data:`GAMMA_H2` :math:`h^2 = 10h^2`, h the
        mean edge length.
    kernel : {"auto", "geodesic", "heat"}
        ``"geodesic"``: :class:`GeodesicKernel` on the densities' support (accurate at every
        distance, on a mesh of any size); ``"heat"``: the heat kernel at :math:`t = \gamma/4`
        (sparse, Solomon et al.'s convolutional transport; see the notes for its accuracy);
        ``"auto"``: geodesic on meshes and point clouds (:data:`GEODESIC_DOMAINS`) whatever
        their size, heat on other domains. ``info["kernel"]`` says which one ran.
    steps : int, default 16
        Backward-Euler steps of the heat kernel (:class:`~spectral_igl.applications.heat_steps.PositiveHeat`).
    max_iter, tol
        Sinkhorn iterations and tolerance on the :math:`L^1` marginal error of each problem.
    return_info : bool
        Also return a dict with ``iterations``, ``marginal_error`` (one per problem),
        ``converged``, the three costs ``S``, ``kernel``, ``gamma``, ``support`` (vertices
        the kernel acts on) and ``dropped_mass`` (see :func:`density_support`).

    Returns
    -------
    float, or (float, dict)

    Warns when the heat kernel is used with ``gamma`` below :math:`10 h^2`, when ``gamma``
    is below :math:`h^2`, or when the iterations did not converge in ``max_iter``
    (``info["converged"]`` is then False).

    Notes
    -----
    *The geodesic kernel* (the default) is Gaussian in the heat method's distance at every
    distance, so what remains is that distance's own error (a few percent). It acts on the
    vertices that carry all but :data:`SUPPORT_TAIL` of each density's mass
    (:func:`density_support`): one heat-method solve per such vertex and their number
    squared in memory, whatever the size of the mesh; a density spread over the whole
    shape costs n solves and :math:`n^2` memory (refused beyond the memory budget, with
    ``kernel="heat"`` as the alternative). Measured (``benchmarks/transport.py --cpu``, bumps
    of width h, unit area, against ``igl.exact_geodesic``, process time of a first call on a
    fresh Laplacian): :math:`W/d - 1` from -3.0% to -0.2% at d = 4h to 30h on cow and
    -4.2% to 0.0% on spot (n = 2.9k, :math:`\gamma = 10h^2` and :math:`40h^2` alike;
    0.07-0.26 s per call, 5-21 iterations, the kernel on 131-667 vertices); on armadillo
    (n = 43k, :math:`\gamma = 10h^2`) from -2.2% to +0.3% (4h: +0.3%, 8h: -1.3%, 12h:
    -2.2%, 20h: -1.0%, 30h: -0.2%), 3.3-7.0 s per call, nearly all of it the 273-426
    heat-method solves, 9 iterations.
    With the default ``gamma`` on cow: Diracs 0.03 s, bumps of width h 0.2 s, of width 5h
    (the kernel on 2,535 of 2,903 vertices) 2.1 s, a density spread over the whole shape
    against the uniform one 4.7 s (123 over-relaxed iterations; 868 plain ones).

    *Where the heat kernel is accurate.* For narrow bumps the divergence is Varadhan's estimate
    :math:`-\gamma\log\big(K(p,q)/\sqrt{K(p,p)K(q,q)}\big)`, which needs the discrete heat
    kernel to be Gaussian out to the bumps' distance :math:`d`. On a mesh it is Gaussian
    only up to :math:`d \approx` a few :math:`t/h`: beyond, every sparse operator's
    kernel decays like the graph's, more slowly than :math:`e^{-d^2/4t}`, and the distance
    comes out low. Measured between bumps of width :math:`h` (``benchmarks/transport.py``:
    cow, spot and a random Delaunay unit square with boundary, n = 2.9k to 3k, unit area,
    ``steps=16``, against ``igl.exact_geodesic``), :math:`W/d - 1` at
    :math:`\gamma = 10h^2`: +2% to +13% at :math:`d = 4h`, -2% to -1% at 6h, -7% to -6%
    at 8h, -15% to -14% at 12h, -26% to -25% at 20h; at :math:`40h^2`: +4% to +26% at 4h, +2% to +6% at 8h,
    -2% to +2% at 12h, -9% to -2% at 20h. The error depends on :math:`d h/\gamma`: for
    bumps :math:`d` apart take :math:`\gamma \approx 2\text{--}3\, d h`. Symmetric to
    round-off (below 1e-14 relative); one call costs 0.05-0.09 s there. Below
    :math:`10h^2` the kernel is far from its smooth limit and the result drifts.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(4)
    >>> lap = sig.laplacian(V, F)
    >>> p, q = 0, int(np.argmin(np.abs(V @ V[0] - np.cos(0.5))))
    >>> mu0, mu1 = np.zeros(lap.n), np.zeros(lap.n)
    >>> mu0[p], mu1[q] = 1.0, 1.0
    >>> w, info = wasserstein_distance(lap, mu0, mu1, 0.1, return_info=True)
    >>> d = float(np.arccos(V[p] @ V[q]))
    >>> bool(abs(w - d) < 0.03 * d), info["converged"], info["support"]
    (True, True, 2)
    """
    lap = as_laplacian(lap)
    gamma = _gamma(lap, gamma)
    tol = _check_iter(max_iter, tol)
    return_info = as_flag(return_info, "return_info")
    kern, index, dens, dropped = _prepare(lap, [("mu0", mu0), ("mu1", mu1)], gamma, kernel, steps)
    _warn_gamma(lap, gamma, kern)
    mu0, mu1 = dens[:, 0], dens[:, 1]
    S, info = _sinkhorn_block(kern, np.c_[mu0, mu0, mu1], np.c_[mu1, mu0, mu1], gamma, max_iter, tol)
    if not info["converged"]:
        warnings.warn(f"Sinkhorn did not converge in {info['iterations']} iterations (marginal "
                      f"errors {np.array2string(info['marginal_error'], precision=2)}); increase "
                      "max_iter or gamma", RuntimeWarning, stacklevel=2)
    w = float(np.sqrt(max(S[0] - 0.5 * (S[1] + S[2]), 0.0)))
    if return_info:
        return w, {"iterations": info["iterations"], "marginal_error": info["marginal_error"],
                   "converged": info["converged"], "S": S, "kernel": _kernel_name(kern), "gamma": gamma,
                   "support": index.size, "dropped_mass": dropped}
    return w


def _warn_gamma(lap, gamma, kern):
    """Warn when ``gamma`` is below what the kernel resolves on this mesh."""
    try:
        h = mean_edge_length(lap)
    except ValueError:
        return
    if isinstance(kern, PositiveHeat) and gamma < 10.0 * h * h * (1 - 1e-12):
        warnings.warn(f"gamma = {gamma:.3g} is below 10 h^2 = {10 * h * h:.3g} (h = {h:.3g} the mean "
                      "edge length): the discrete heat kernel is far from its smooth limit at "
                      "t = gamma/4", RuntimeWarning, stacklevel=3)
    elif gamma < h * h * (1 - 1e-12):
        warnings.warn(f"gamma = {gamma:.3g} is below h^2 = {h * h:.3g} (h = {h:.3g} the mean edge length): "
                      "the kernel's width is below the mesh's resolution", RuntimeWarning, stacklevel=3)


def wasserstein_barycenter(lap, mus, gamma=None, weights=None, kernel: str = "auto", steps: int = 16,
                           max_iter: int = 5000, tol: float = 1e-7, return_info: bool = False):
    r"""Entropic Wasserstein barycentre of densities (Solomon et al. 2015, Algorithm 2).

    .. math:: \mu = \arg\min_\mu \sum_i \alpha_i\, S_\gamma(\mu, \mu_i)

    solved by the iterative Bregman projections of Solomon et al., on log-potentials:
    :math:`w_i \leftarrow \mu_i / K^* v_i`, :math:`d_i \leftarrow v_i\, K w_i`,
    :math:`\mu \leftarrow \prod_i d_i^{\alpha_i}`, :math:`v_i \leftarrow v_i\,\mu / d_i`,
    with the kernel of :func:`sinkhorn` (``kernel``, ``steps`` as there). The geodesic
    kernel runs from the inputs' support (:func:`density_support`) to every vertex (where
    the barycentre lives): one heat-method solve per support vertex, ``n`` times their
    number in memory.

    Parameters
    ----------
    lap : Laplacian
    mus : (n, k) float
        k non-negative densities (columns), each normalised here to unit mass.
    gamma : float, optional
        Entropic regularisation (length squared); default :data:`GAMMA_H2` :math:`h^2`.
    weights : (k,) float, optional
        Non-negative barycentric weights :math:`\alpha`, normalised to sum 1; default equal.
    kernel, steps
        As in :func:`sinkhorn`.
    max_iter, tol
        Iterations, tolerance on :math:`\max_i \int |d_i - \mu|\,dA`.
    return_info : bool
        Also return ``iterations``, ``error``, ``converged``, ``kernel``, ``gamma``,
        ``support`` and ``dropped_mass``.

    Returns
    -------
    (n,) float
        The barycentre density, :math:`\int \mu\, dA = 1`.
    info : dict, only with ``return_info``

    Notes
    -----
    Warns when the iterations did not converge (``info["converged"]`` False). Measured on
    cow at the default ``gamma``: two bumps of width h at the ends of the shape, 11
    iterations, the kernel from 474 vertices to all 2,903, 0.2 s of process time.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(3)
    >>> lap = sig.laplacian(V, F)
    >>> mus = np.stack([np.exp(-40 * np.sum((V - V[i]) ** 2, axis=1)) for i in (0, 1)], axis=1)
    >>> mu, info = wasserstein_barycenter(lap, mus, 0.05, return_info=True)
    >>> info["converged"], bool(abs(lap.mass @ mu - 1) < 1e-12)
    (True, True)
    """
    lap = as_laplacian(lap)
    gamma = _gamma(lap, gamma)
    tol = _check_iter(max_iter, tol)
    return_info = as_flag(return_info, "return_info")
    mus = as_signal(mus, lap.n, "mus", allow_complex=False)
    if mus.ndim != 2 or mus.shape[1] < 1:
        raise ValueError(f"mus must have shape ({lap.n}, k), got shape {mus.shape}")
    k = mus.shape[1]
    if weights is None:
        alpha = np.full(k, 1.0 / k)
    else:
        alpha = np.asarray(weights, dtype=float)
        if alpha.shape != (k,) or not np.all(np.isfinite(alpha)) or np.any(alpha < 0) or alpha.sum() <= 0:
            raise ValueError(f"weights must be {k} non-negative numbers with a positive sum, got {describe(weights)}")
        alpha = alpha / alpha.sum()
    kern, index, mus, dropped = _prepare(lap, [(f"mus[:, {i}]", mus[:, i]) for i in range(k)], gamma, kernel,
                                         steps, whole_rows=True)
    a = kern.mass
    logmus = _log(mus)
    logv = np.zeros((lap.n, k))
    logmu = np.zeros(lap.n)
    err, it = np.inf, 0
    for it in range(1, int(max_iter) + 1):
        logw = np.where(mus > 0, logmus - _log_apply_adjoint(kern, logv), -np.inf)
        logd = logv + kern.log_apply(logw)
        logmu = logd @ alpha
        err = float(np.max(a @ np.abs(np.exp(logd) - np.exp(logmu)[:, None])))
        logv = logv + logmu[:, None] - logd
        if err < tol:
            break
    mu = np.exp(logmu - logmu.max())
    mu = mu / float(a @ mu)
    if err >= tol:
        warnings.warn(f"barycentre iterations did not converge in {it} iterations (error {err:.2g})",
                      RuntimeWarning, stacklevel=2)
    if return_info:
        return mu, {"iterations": it, "error": err, "converged": err < tol, "kernel": _kernel_name(kern),
                    "gamma": gamma, "support": index.size, "dropped_mass": dropped}
    return mu
