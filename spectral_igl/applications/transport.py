"""Entropic optimal transport: the heat kernel (convolutional Wasserstein distance) or the
Gaussian of geodesic distances."""
from __future__ import annotations

import warnings

import numpy as np

from .._validate import as_flag, as_int, as_positive, as_signal, as_tol, check_dense_size, describe
from ..laplacian import as_laplacian
from .geodesics import HeatGeodesics
from .heat_steps import PositiveHeat, log_apply

__all__ = ["wasserstein_distance", "sinkhorn", "wasserstein_barycenter", "GeodesicKernel", "KERNELS",
           "GEODESIC_MAX"]

#: ``kernel`` choices of the transport functions
KERNELS = ("auto", "geodesic", "heat")
#: largest vertex count for which ``kernel="auto"`` uses the (dense) geodesic kernel
GEODESIC_MAX = 5000


class GeodesicKernel:
    r"""The Gaussian of geodesic distances, :math:`K_{ij} = e^{-d_{ij}^2/\gamma}\,a_j`, dense.

    :math:`d` is the heat-method geodesic distance (:class:`~.geodesics.HeatGeodesics`,
    every vertex a source, symmetrised), cached on the Laplacian for every ``gamma``;
    :math:`a` the lumped vertex areas. Unlike a mesh heat kernel, it is Gaussian in
    :math:`d` at every distance, so the entropic cost it defines is :math:`d^2` up to
    the heat method's error. Memory and time per application are :math:`O(n^2)`.
    """

    def __init__(self, lap, gamma: float):
        lap = as_laplacian(lap)
        if lap.domain not in ("triangle", "tet") or "V" not in lap.data:
            raise ValueError(f"the geodesic kernel needs a triangle or tetrahedral mesh, got a {lap.domain} "
                             "Laplacian; use kernel='heat'")
        # the distances, their log-kernel, the kernel and a log-sum-exp temporary: (n, n) each
        check_dense_size(4 * 8.0 * lap.n ** 2, f"the dense ({lap.n}, {lap.n}) geodesic kernel",
                         "use kernel='heat' (sparse heat steps, O(n) memory)")
        self.n, self.gamma = lap.n, float(gamma)
        self.mass = np.asarray(lap.B.sum(axis=1)).ravel()
        D = lap.cache.fetch("kernel", ("all_pairs_geodesic",), lambda: _all_pairs(lap))
        with np.errstate(over="ignore"):
            self.logK = -(D * D) / self.gamma
        finite = np.isfinite(self.logK)
        # a dense product is exact enough while no kernel entry underflows
        self.dense = bool(np.all(self.logK[finite] > -700.0))
        self.K = np.exp(self.logK) * self.mass[None, :] if self.dense else None

    def apply(self, X: np.ndarray) -> np.ndarray:
        """:math:`K X`."""
        if self.K is not None:
            return self.K @ X
        return np.exp(self.log_apply(np.log(np.maximum(X, 0.0))))

    def log_apply(self, logX: np.ndarray) -> np.ndarray:
        r"""Column-wise :math:`\log K e^{X}`: a dense product with each column's largest
        value factored out, or log-sum-exp where kernel entries would underflow."""
        if self.K is not None:
            return log_apply(self.K.dot, logX)
        from scipy.special import logsumexp

        la = np.log(self.mass)
        return np.stack([logsumexp(self.logK + (logX[:, j] + la)[None, :], axis=1)
                         for j in range(logX.shape[1])], axis=1)


def _all_pairs(lap):
    D = HeatGeodesics(lap).compute_each(np.arange(lap.n))
    D = np.maximum(0.5 * (D + D.T), 0.0)
    np.fill_diagonal(D, 0.0)
    return D



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


def _kernel(lap, gamma, kernel, steps, heat=None):
    """The transport kernel: a given PositiveHeat, or by ``kernel`` (see :data:`KERNELS`)."""
    if heat is not None:
        if not isinstance(heat, PositiveHeat) or heat.n != lap.n:
            raise TypeError(f"heat must be a PositiveHeat of this Laplacian, got {describe(heat)}")
        if not np.isclose(heat.t, gamma / 4.0, rtol=1e-12):
            raise ValueError(f"heat has t = {heat.t:g}, but gamma / 4 = {gamma / 4.0:g}")
        return heat
    if not isinstance(kernel, str) or kernel not in KERNELS:
        raise ValueError(f"kernel must be one of {KERNELS}, got {describe(kernel)}")
    as_int(steps, "steps", lo=1, hi=10 ** 4)
    meshed = lap.domain in ("triangle", "tet") and "V" in lap.data
    if kernel == "geodesic" or (kernel == "auto" and meshed and lap.n <= GEODESIC_MAX):
        return GeodesicKernel(lap, gamma)
    return PositiveHeat(lap, gamma / 4.0, steps=steps)


def _log(mu):
    with np.errstate(divide="ignore"):
        return np.log(mu)


def _sinkhorn_block(heat, A, B, gamma, max_iter, tol):
    """Log-domain Sinkhorn for the columns of A (first marginals) and B (second)."""
    a = heat.mass
    logA, logB = _log(A), _log(B)
    sA, sB = A > 0, B > 0
    logv = np.where(sA, 0.0, -np.inf)
    logw = np.where(sB, 0.0, -np.inf)
    err = np.full(A.shape[1], np.inf)
    it = 0
    for it in range(1, int(max_iter) + 1):
        kw = heat.log_apply(logw)
        # first-marginal error of the current pair (the second is exact after each update)
        marg = np.where(sA, np.exp(np.where(sA, logv + kw, -np.inf)), 0.0)
        err = a @ np.abs(marg - A)
        if np.all(err < tol):
            break
        logv = np.where(sA, logA - kw, -np.inf)
        logw = np.where(sB, logB - heat.log_apply(logv), -np.inf)
    value = gamma * (a @ (A * np.where(sA, logv, 0.0)) + a @ (B * np.where(sB, logw, 0.0)))
    return value, {"iterations": it, "marginal_error": err, "converged": bool(np.all(err < tol)),
                   "logv": logv, "logw": logw}


def _check_iter(max_iter, tol):
    as_int(max_iter, "max_iter", lo=1, hi=10 ** 7)
    return as_tol(tol, "tol")


def sinkhorn(lap, mu0, mu1, gamma, heat=None, kernel: str = "auto", steps: int = 16, max_iter: int = 5000,
             tol: float = 1e-9):
    r"""Entropic transport between densities ``mu0`` and ``mu1`` (Solomon et al. 2015).

    Sinkhorn iterations on log-potentials with a kernel :math:`K(x, y) \propto
    e^{-d(x, y)^2/\gamma}`:

    .. math:: v \leftarrow \mu_0 / K w, \qquad w \leftarrow \mu_1 / K v

    ``kernel="heat"``: the heat kernel at :math:`t = \gamma/4`, applied by
    :class:`~spectral_igl.applications.heat_steps.PositiveHeat` (``steps`` backward-Euler
    steps with a Metzler stiffness and the lumped mass; positive and relatively accurate
    however small the kernel); Gaussian in d only out to a few :math:`t/h`.
    ``kernel="geodesic"``: :class:`GeodesicKernel`, the Gaussian of heat-method geodesic
    distances, dense. ``"auto"``: geodesic on triangle and tet meshes of at most
    :data:`GEODESIC_MAX` vertices, else heat.

    Parameters
    ----------
    lap : Laplacian
    mu0, mu1 : (n,) float
        Non-negative densities, normalised here to :math:`\int\mu\,dA = 1` (lumped areas).
    gamma : float
        Entropic regularisation, length squared.
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
        ``iterations``, ``marginal_error``, ``converged``, ``logv``, ``logw``.
    """
    lap = as_laplacian(lap)
    gamma = as_positive(gamma, "gamma")
    tol = _check_iter(max_iter, tol)
    _check_components(lap, [("mu0", _density(lap, mu0, "mu0", lap.mass)),
                            ("mu1", _density(lap, mu1, "mu1", lap.mass))])
    heat = _kernel(lap, gamma, kernel, steps, heat)
    mu0 = _density(lap, mu0, "mu0", heat.mass)
    mu1 = _density(lap, mu1, "mu1", heat.mass)
    value, info = _sinkhorn_block(heat, mu0[:, None], mu1[:, None], gamma, max_iter, tol)
    info = {k: (v[:, 0] if k in ("logv", "logw") else v) for k, v in info.items()}
    info["marginal_error"] = float(info["marginal_error"][0])
    return float(value[0]), info


def _mean_edge(lap):
    if lap.domain in ("triangle", "tet") and "V" in lap.data:
        from .geodesics import mean_edge_length

        return mean_edge_length(lap.data["V"], lap.data["F" if lap.domain == "triangle" else "T"])
    return None


def wasserstein_distance(lap, mu0, mu1, gamma, kernel: str = "auto", steps: int = 16, max_iter: int = 5000,
                         tol: float = 1e-9, return_info: bool = False):
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
    gamma : float
        Entropic regularisation, in units of length squared: the kernel is
        :math:`\propto e^{-d^2/\gamma}`.
    kernel : {"auto", "geodesic", "heat"}
        ``"geodesic"``: :class:`GeodesicKernel` (dense, accurate at every distance);
        ``"heat"``: the heat kernel at :math:`t = \gamma/4` (sparse, Solomon et al.'s
        convolutional transport; see the notes for its accuracy); ``"auto"``: geodesic on
        triangle and tet meshes of at most :data:`GEODESIC_MAX` vertices, else heat.
    steps : int, default 16
        Backward-Euler steps of the heat kernel (:class:`~spectral_igl.applications.heat_steps.PositiveHeat`).
    max_iter, tol
        Sinkhorn iterations and tolerance on the :math:`L^1` marginal error.
    return_info : bool
        Also return a dict with ``iterations``, ``marginal_error`` (one per problem),
        ``converged`` and the three costs ``S``.

    Returns
    -------
    float, or (float, dict)

    Warns when the heat kernel is used with ``gamma`` below :math:`10 h^2` (``h`` the mean
    edge length of a triangle or tet mesh), or when the iterations did not converge in
    ``max_iter``.

    Notes
    -----
    *The geodesic kernel* (the default up to :data:`GEODESIC_MAX` vertices) is Gaussian in
    the heat method's distance at every distance, so what remains is that distance's own
    error (a few percent). Measured as below: :math:`W/d - 1` from -4.2% to 0.0% at
    :math:`d` = 4h to 30h on cow and spot, at :math:`\gamma = 10h^2` and :math:`40h^2`
    alike; -3% to -2% at 4h to 12h on the unit square (bumps farther from its centre are
    cut by its boundary). 0.13-0.30 s per call at n = 3k, after the all-pairs distances
    (about 3 s once per shape, cached).

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
    """
    lap = as_laplacian(lap)
    gamma = as_positive(gamma, "gamma")
    tol = _check_iter(max_iter, tol)
    return_info = as_flag(return_info, "return_info")
    _check_components(lap, [("mu0", _density(lap, mu0, "mu0", lap.mass)),
                            ("mu1", _density(lap, mu1, "mu1", lap.mass))])
    heat = _kernel(lap, gamma, kernel, steps)
    h = _mean_edge(lap)
    if isinstance(heat, PositiveHeat) and h is not None and gamma < 10.0 * h * h * (1 - 1e-12):
        warnings.warn(f"gamma = {gamma:.3g} is below 10 h^2 = {10 * h * h:.3g} (h = {h:.3g} the mean "
                      "edge length): the discrete heat kernel is far from its smooth limit at "
                      "t = gamma/4", RuntimeWarning, stacklevel=2)
    elif h is not None and gamma < h * h * (1 - 1e-12):
        warnings.warn(f"gamma = {gamma:.3g} is below h^2 = {h * h:.3g} (h = {h:.3g} the mean edge length): "
                      "the kernel's width is below the mesh's resolution", RuntimeWarning, stacklevel=2)
    mu0 = _density(lap, mu0, "mu0", heat.mass)
    mu1 = _density(lap, mu1, "mu1", heat.mass)
    A = np.c_[mu0, mu0, mu1]
    B = np.c_[mu1, mu0, mu1]
    S, info = _sinkhorn_block(heat, A, B, gamma, max_iter, tol)
    if not info["converged"]:
        warnings.warn(f"Sinkhorn did not converge in {info['iterations']} iterations (marginal "
                      f"errors {np.array2string(info['marginal_error'], precision=2)}); increase "
                      "max_iter or gamma", RuntimeWarning, stacklevel=2)
    w = float(np.sqrt(max(S[0] - 0.5 * (S[1] + S[2]), 0.0)))
    if return_info:
        return w, {"iterations": info["iterations"], "marginal_error": info["marginal_error"],
                   "converged": info["converged"], "S": S}
    return w


def wasserstein_barycenter(lap, mus, gamma, weights=None, kernel: str = "auto", steps: int = 16,
                           max_iter: int = 5000, tol: float = 1e-7, return_info: bool = False):
    r"""Entropic Wasserstein barycentre of densities (Solomon et al. 2015, Algorithm 2).

    .. math:: \mu = \arg\min_\mu \sum_i \alpha_i\, S_\gamma(\mu, \mu_i)

    solved by the iterative Bregman projections of Solomon et al., on log-potentials:
    :math:`w_i \leftarrow \mu_i / K v_i`, :math:`d_i \leftarrow v_i\, K w_i`,
    :math:`\mu \leftarrow \prod_i d_i^{\alpha_i}`, :math:`v_i \leftarrow v_i\,\mu / d_i`,
    with the kernel of :func:`sinkhorn` (``kernel``, ``steps`` as there).

    Parameters
    ----------
    lap : Laplacian
    mus : (n, k) float
        k non-negative densities (columns), each normalised here to unit mass.
    gamma : float
        Entropic regularisation (length squared).
    weights : (k,) float, optional
        Non-negative barycentric weights :math:`\alpha`, normalised to sum 1; default equal.
    kernel, steps
        As in :func:`sinkhorn`.
    max_iter, tol
        Iterations, tolerance on :math:`\max_i \int |d_i - \mu|\,dA`.
    return_info : bool
        Also return ``iterations``, ``error`` and ``converged``.

    Returns
    -------
    (n,) float
        The barycentre density, :math:`\int \mu\, dA = 1`.
    """
    lap = as_laplacian(lap)
    gamma = as_positive(gamma, "gamma")
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
    _check_components(lap, [(f"mus[:, {i}]", _density(lap, mus[:, i], f"mus[:, {i}]", lap.mass))
                            for i in range(k)])
    heat = _kernel(lap, gamma, kernel, steps)
    a = heat.mass
    mus = np.stack([_density(lap, mus[:, i], f"mus[:, {i}]", a) for i in range(k)], axis=1)
    logmus = _log(mus)
    logv = np.zeros_like(mus)
    logmu = np.zeros(lap.n)
    err, it = np.inf, 0
    for it in range(1, int(max_iter) + 1):
        logw = np.where(mus > 0, logmus - heat.log_apply(logv), -np.inf)
        logd = logv + heat.log_apply(logw)
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
        return mu, {"iterations": it, "error": err, "converged": err < tol}
    return mu
