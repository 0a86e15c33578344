r"""Point descriptors from the diagonal of a spectral kernel: HKS, WKS, ADF, eccentricity."""
from __future__ import annotations

import numpy as np

from ._validate import as_array, as_int, as_positive, as_real_in, describe
from .diagonal import kernel_diagonal
from .diagonal.multiscale import family_diagonals, heat_diagonals
from .filters import Filter, check_filter, heat
from .laplacian import as_laplacian
from .linalg import cached_eigs, dense_eigs
from .progress import progress_bar

__all__ = ["spectral_descriptor", "hks", "wks", "auto_diffusion_function", "eccentricity"]


#: most times or energies per call (each is one kernel diagonal)
MAX_SCALES = 1000


def _values(x, name):
    a = as_array(x, name)
    if a.dtype.kind not in "biuf":
        raise TypeError(f"{name} must be real numbers, got {describe(x)}")
    a = a.astype(float)
    if a.ndim > 1 or a.size == 0 or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be a finite scalar or 1-D array, got {describe(x)}")
    if a.size > MAX_SCALES:
        raise ValueError(f"{name} has {a.size} values, more than {MAX_SCALES} (one kernel diagonal each)")
    return a


def spectral_descriptor(lap, filt, method: str = "auto", **kwargs):
    r"""The diagonal of the spectral kernel :math:`K = \varphi(\tilde L)B^{-1}`.

    .. math:: SD(i) = K(i, i) = \sum_l \varphi(\lambda_l)\, x_l(i)^2

    Parameters
    ----------
    lap : Laplacian
    filt : Filter
    method : str
        Diagonal method, see :func:`spectral_igl.kernel_diagonal` (``"auto"``: selected
        inversion of a rational approximation, with a certified error bound).
    **kwargs
        Passed to :func:`spectral_igl.kernel_diagonal` (``k``, ``distance``,
        ``return_info``, ...).

    Returns
    -------
    (n,) float
    """
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    return kernel_diagonal(lap, filt, method=method, **kwargs)


def hks(lap, times, method: str = "auto", progress=None, **kwargs):
    r"""Heat kernel signature (Sun et al. 2009) at one or several times.

    .. math:: HKS(i, t) = K_t(i, i) = \sum_l e^{-t\lambda_l}\, x_l(i)^2

    Parameters
    ----------
    lap : Laplacian
    times : float or (T,) float
        Diffusion times.
    method : str
        Diagonal method, see :func:`spectral_igl.kernel_diagonal`.
    progress : bool, optional
        A progress bar on stderr, one step per time, with the diagonal's own bar (per
        pole) under it (see :mod:`spectral_igl.progress`; default off).
    **kwargs
        Passed to :func:`spectral_igl.kernel_diagonal`.

    Several times with ``method="selinv"``, or ``"auto"`` above 3000 vertices or for 8 times
    or more, share one set of poles
    (:func:`spectral_igl.diagonal.multiscale.heat_diagonals`): about as many factorizations
    as one time, each time with its own certified bound (``kernel_diagonal`` options other
    than ``tol`` select the one-time-at-a-time path).

    Returns
    -------
    (n,) float for a scalar time, (n, len(times)) float for an array of times.
    """
    lap = as_laplacian(lap)
    T = _values(times, "times")
    Tv = T.reshape(-1)
    for t in Tv:
        as_positive(t, "time")
    if _family(lap, method, Tv.size, kwargs):
        with progress_bar(T.size, "hks", progress, unit="time") as bar:
            out = heat_diagonals(lap, Tv, tol=kwargs.get("tol", 1e-8)).values.copy()
            bar.update(T.size)
        return out
    cols = []
    with progress_bar(T.size, "hks", progress, unit="time") as bar:
        for t in Tv:
            cols.append(kernel_diagonal(lap, heat(float(t)), method=method, progress=progress, **kwargs))
            bar.set_postfix_str(f"t={t:.3g}")
            bar.update()
    return cols[0] if T.ndim == 0 else np.stack(cols, axis=1)


def _family(lap, method, count, kwargs) -> bool:
    """Whether several filters go through the common-pole diagonals: ``"selinv"``, or
    ``"auto"`` above the dense limit or for :data:`FAMILY_MIN` filters or more (below both,
    a few filters one at a time cost less than fitting common poles)."""
    from .diagonal import EXACT_MAX, selinv_supported

    if count < 2 or method not in ("auto", "selinv") or set(kwargs) - {"tol"}:
        return False
    if method == "auto" and lap.n <= EXACT_MAX and count < FAMILY_MIN:
        return False
    return selinv_supported(lap, heat(1.0))


#: smallest number of scales for which ``method="auto"`` fits common poles on small shapes
#: (WKS at 100 energies on a 2.9k-vertex mesh: 4.1 s, against 18.8 s one energy at a time)
FAMILY_MIN = 8


def _wks_filter(e, sigma):
    def psi(s, e=e, sigma=sigma):
        s = np.asarray(s, dtype=float)
        with np.errstate(divide="ignore"):
            ls = np.log(np.where(s > 0, s, np.finfo(float).tiny))
        return np.where(s > 0, np.exp(-((e - ls) ** 2) / (2.0 * sigma ** 2)), 0.0)

    # singular: a log-normal band, 0 on ker L by definition (the engine's convention for
    # singular filters) and analytic only away from s = 0, so it is fitted on [lambda_2, b]
    return Filter(psi, name=f"wks({e:g},{sigma:g})", singular=True, kind="wks",
                  params={"e": e, "sigma": sigma}, key=("wks", e, sigma))


#: Rademacher probes of the trace estimate of the WKS normaliser (full mass, large n)
WKS_TRACE_PROBES = 64
#: largest n whose WKS normaliser (full mass) comes from the dense spectrum
WKS_DENSE_MAX = 3000


def _wks_trace(lap, f, diag):
    r""":math:`\operatorname{tr}\psi(\tilde L) = \operatorname{tr}(KB)`, K the kernel whose diagonal is ``diag``.

    Lumped mass: :math:`\sum_i m_i K_{ii}`, exact. Full mass: :math:`\operatorname{tr}(KB)`
    also needs :math:`K_{ij}` on the edges, so the spectrum is used below the dense limit
    (exact) and Hutchinson's estimate :math:`\mathbb E[z^\top\psi(\tilde L)z]` above it.
    """
    if lap.lumped:
        return float(lap.mass @ diag)
    if lap.n <= WKS_DENSE_MAX:
        lam = np.asarray(dense_eigs(lap)[0])
        return float(np.sum(f(np.maximum(lam, 0.0))))
    from .approx import apply_filter

    Z = np.random.default_rng(0).choice([-1.0, 1.0], size=(lap.n, WKS_TRACE_PROBES))
    Y = np.real(apply_filter(lap, f, Z))
    return float(np.mean(np.einsum("ij,ij->j", Z, Y)))


def wks(lap, energies, sigma: float | None = None, k: int = 100, method: str = "eigen",
        progress=None, **kwargs):
    r"""Wave kernel signature (Aubry et al. 2011) at log-energies ``energies``.

    .. math:: WKS(i, e) = \frac{\sum_l \psi_e(\lambda_l)\, x_l(i)^2}{\sum_l \psi_e(\lambda_l)},
              \qquad \psi_e(s) = \exp\Big(-\frac{(e - \log s)^2}{2\sigma^2}\Big), \ \psi_e(0) = 0

    Parameters
    ----------
    energies : float or (E,) float
        Log-energies :math:`e` (Aubry et al. spread them over
        :math:`[\log\lambda_2, \log\lambda_k]`).
    sigma : float, optional
        Band width; default :math:`7\,\delta` with :math:`\delta` the spacing of
        ``energies`` (Aubry's choice), required for a single energy.
    k : int
        Non-zero eigenpairs for ``method="eigen"`` (the definition of Aubry et al.).
    method : {"eigen", "auto", "selinv", "exact", "probing", "dense"}
        ``"eigen"``: the original truncated definition. Otherwise the diagonal of
        :math:`K = \psi_e(\tilde L)B^{-1}` spectrum-free; the normaliser
        :math:`\operatorname{tr}\psi_e(\tilde L) = \operatorname{tr}(KB)` is then
        :math:`\sum_i m_i K(i,i)` for a lumped mass matrix (exact); for a full mass matrix
        :math:`\operatorname{tr}(KB) \ne \sum_i m_i K(i,i)` (the off-diagonal
        :math:`K_{ij}B_{ij}` differ, by a factor of about 2 at high energies), so it is
        :math:`\sum_l \psi_e(\lambda_l)` from the dense spectrum for
        :math:`n \le` ``WKS_DENSE_MAX`` = 3000 (exact) and a Hutchinson estimate with ``WKS_TRACE_PROBES``
        Rademacher vectors above (relative error about :math:`(2/64)^{1/2}` times
        :math:`\|\psi_e(\tilde L)\|_F/\operatorname{tr}\psi_e(\tilde L)`).
    progress : bool, optional
        Spectrum-free methods: a progress bar on stderr, one step per energy (see
        :mod:`spectral_igl.progress`; default off).
    **kwargs
        Passed to :func:`spectral_igl.kernel_diagonal`.

    Returns
    -------
    (n,) float for a scalar energy, (n, E) float for an array.
    """
    lap = as_laplacian(lap)
    E = _values(energies, "energies")
    Ev = E.reshape(-1)
    if sigma is None:
        if Ev.size < 2:
            raise ValueError("sigma is required for a single energy")
        sigma = 7.0 * (Ev.max() - Ev.min()) / (Ev.size - 1)
    sigma = as_real_in(sigma, "sigma", 1e-8, 1e3)
    if np.abs(Ev).max() > 1e3:
        raise ValueError(f"energies are log-eigenvalues, within [-1000, 1000] (double precision spans "
                         f"about [-745, 710]), got {float(Ev[np.argmax(np.abs(Ev))]):g}")
    if method == "eigen":
        k = as_int(k, "k", lo=1, hi=lap.n)
        if kwargs:
            raise TypeError(f"method='eigen' takes no diagonal options, got {sorted(kwargs)}")
        c = lap.n_components
        if c >= lap.n:
            raise ValueError("the shape has no non-zero eigenvalue (every vertex is its own component)")
        kk = c + k
        lam, X = cached_eigs(lap, kk if kk < lap.n else None)
        lam, X = lam[c:], X[:, c:]
        with np.errstate(divide="ignore"):
            z = -(((Ev[None, :] - np.log(lam)[:, None]) / sigma) ** 2) / 2.0
        # normalised by its largest weight per energy: the ratio is unchanged, nothing underflows
        Psi = np.exp(z - z.max(axis=0))
        out = (X ** 2) @ Psi / Psi.sum(axis=0)
    else:
        filts = [_wks_filter(float(e), sigma) for e in Ev]
        D = None
        if _family(lap, method, Ev.size, kwargs):
            # common poles for all energies (set-valued AAA), each energy certified
            tol = kwargs.get("tol", 1e-8)
            D = family_diagonals(lap, filts, max(tol * 1e-1, 1e-12), scales=np.exp(Ev)).values
        cols = []
        bar = progress_bar(Ev.size, "wks", progress, unit="energy")
        for k, f in enumerate(filts):
            d = D[:, k] if D is not None else np.real(kernel_diagonal(lap, f, method=method,
                                                                       progress=progress, **kwargs))
            tr = _wks_trace(lap, f, d)
            if not tr > 0:
                raise ValueError(f"the WKS band at energy {float(Ev[k]):g} (sigma {sigma:g}) holds no "
                                 "eigenvalue of the shape to double precision; choose energies within "
                                 "[log lambda_2, log lambda_max] or use method='eigen'")
            cols.append(d / tr)
            bar.update()
        bar.close()
        out = np.stack(cols, axis=1)
    return out[:, 0] if E.ndim == 0 else out


def auto_diffusion_function(lap, t, method: str = "auto", **kwargs):
    r"""Auto-diffusion function (Gebal et al. 2009), scale invariant.

    .. math:: ADF_t(i) = A\, K_{t/\lambda_2}(i, i) = A \sum_l e^{-t\lambda_l/\lambda_2}\, x_l(i)^2

    Time is measured in units of :math:`1/\lambda_2` (the first non-zero eigenvalue,
    Gebal et al.'s normalisation) and the value is multiplied by the area :math:`A`, so
    ADF is invariant under a uniform scaling of the shape and equals 1 at large t on a
    connected shape. Returns (n,) float, or (n, len(t)) for an array of times.
    """
    lap = as_laplacian(lap)
    T = _values(t, "t")
    for ti in T.reshape(-1):
        as_positive(ti, "t")
    c = lap.n_components
    if c >= lap.n:
        raise ValueError("the shape has no non-zero eigenvalue (every vertex is its own component)")
    lam2 = float(cached_eigs(lap, c + 1)[0][c])
    out = hks(lap, T / lam2, method=method, **kwargs) * lap.area()
    return out


def eccentricity(lap, filt, method: str = "auto", **kwargs):
    r"""Spectral eccentricity: the root-mean-square spectral distance to the shape.

    .. math:: ecc(i)^2 = \frac{1}{A_c}\sum_{j \in c} m_j\, d^2(i, j)
              = G_{ii} + \frac{1}{A_c}\sum_{j\in c} m_j G_{jj} - \frac{2|\varphi(0)|^2}{A_c}

    with :math:`G = |\varphi|^2(\tilde L)B^{-1}`, :math:`m = B\mathbf 1`, :math:`c` the
    connected component of i and :math:`A_c` its area. The identity uses
    :math:`G B \mathbf 1 = |\varphi(0)|^2 \mathbf 1`, so the eccentricity costs one
    diagonal (no n² distances). For the diffusion filter it is the survey's
    :math:`ecc_t` (§5.1) up to the square root.

    Returns
    -------
    (n,) float
    """
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    G2 = filt.square
    diag = np.real(kernel_diagonal(lap, G2, method=method, **kwargs))
    m = lap.mass
    lab = lap.components
    Ac = np.bincount(lab, weights=m)
    Tc = np.bincount(lab, weights=m * diag)
    phi0 = abs(filt.at_zero()) ** 2
    e2 = diag + Tc[lab] / Ac[lab] - 2.0 * phi0 / Ac[lab]
    return np.sqrt(np.maximum(e2, 0.0))
