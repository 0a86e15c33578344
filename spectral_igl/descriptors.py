r"""Point descriptors from the diagonal of a spectral kernel: HKS, WKS, ADF, eccentricity."""
from __future__ import annotations

import numpy as np

from .accuracy import info as bound_info, weakest
from ._validate import as_array, as_flag, as_int, as_positive, as_real_in, describe
from .diagonal import NoSelinv, kernel_diagonal, selinv_kernel
from .distances import root_error
from .families import family_diagonals, heat_diagonals
from .filters import Filter, check_filter, heat
from .laplacian import as_laplacian, lambda_max, lambda_max_kind, shape_time
from .linalg import cached_eigs, dense_eigs, eigenvalue_bracket, lambda_min_positive
from .linalg.eigen import lambda_min_positive_kind
from .progress import progress_bar

__all__ = ["spectral_descriptor", "hks", "wks", "auto_diffusion_function", "eccentricity",
           "spectral_band", "hks_times", "wks_energies"]


#: most times or energies per call (each is one kernel diagonal)
MAX_SCALES = 1000

#: descriptor grids span the first ``BAND`` eigenvalues (the number of eigenpairs common practice
#: computes for descriptors, e.g. pyFM's default) with ``GRID_SIZE`` scales
BAND, GRID_SIZE = 200, 100

#: the HKS grid runs from the time that damps lambda_hi to 1e-4, e^{-t lambda} = 1e-4, to the one
#: that damps lambda_lo so (Sun et al. 2009)
_DAMP = 4.0 * np.log(10.0)


def spectral_band(lap, k: int = BAND):
    r"""The ends :math:`(\lambda_{lo}, \lambda_{hi})` of the band of the first ``k`` eigenvalues
    that descriptor grids span, spectrum-free, and whether they are proved.

    :math:`\lambda_{lo}` is a proved lower bound of the smallest positive eigenvalue
    :math:`\lambda_{c+1}` (:func:`spectral_igl.lambda_min_positive`, within 0.1% of it);
    :math:`\lambda_{hi}` is :math:`\lambda_k` (counted with the zeros of ker L, as an
    eigen-solver returns them), the geometric middle of a proved bracket 5% wide
    (:func:`spectral_igl.linalg.eigenvalue_bracket`: a few inertia counts, no eigenvector);
    for ``k >= n`` the proved :func:`spectral_igl.lambda_max`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    k : int
        Number of eigenvalues in the band (default 200), counted with the zeros of ker L.

    Returns
    -------
    lam_lo, lam_hi : float
        The ends of the band.
    kind : str
        ``"proof"`` or ``"estimate"`` (of the brackets behind the two ends).

    Examples
    --------
    The unit sphere's eigenvalues are :math:`l(l+1)` with multiplicity :math:`2l+1`:
    :math:`\lambda_1 = 0`, :math:`\lambda_2 = \dots = \lambda_4 = 2`,
    :math:`\lambda_5 = \dots = \lambda_9 = 6`; a 642-vertex sphere is close:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lo, hi, kind = sig.spectral_band(sig.laplacian(*icosphere(3)), 9)
    >>> bool(1.9 < lo <= 2.0), bool(5.8 < hi < 6.3), kind
    (True, True, 'proof')
    """
    lap = as_laplacian(lap)
    k = as_int(k, "k", lo=1)
    c = lap.n_components
    if c >= lap.n:
        raise ValueError("the shape has no non-zero eigenvalue (every vertex is its own component)")
    lam_lo, kind_lo = lambda_min_positive(lap), lambda_min_positive_kind(lap)
    if k >= lap.n:
        return lam_lo, lambda_max(lap), weakest(kind_lo, lambda_max_kind(lap))
    lo, hi, kind = eigenvalue_bracket(lap, max(k, c + 2) if c + 2 <= lap.n else lap.n)
    return lam_lo, max(float(np.sqrt(lo * hi)), lam_lo), weakest(kind_lo, kind)


def hks_times(lap, n: int = GRID_SIZE, k: int = BAND):
    r"""HKS times from the spectrum (Sun et al. 2009): ``n`` times log-spaced over
    :math:`[4\ln 10/\lambda_{hi},\ 4\ln 10/\lambda_{lo}]`.

    The band :math:`[\lambda_{lo}, \lambda_{hi}]` of the first ``k`` eigenvalues comes from
    :func:`spectral_band`, spectrum-free. At the first time the k-th eigenfunction's weight is
    :math:`e^{-t\lambda_{hi}} = 10^{-4}`: finer scales are below what k eigenpairs resolve;
    at the last, the first non-constant one's is. The same as pyFM's ``auto_HKS`` on the same
    ``k`` eigenvalues (to the bracket's 2.5%), and covariant with scale: on a shape scaled by
    s every time is multiplied by :math:`s^2`.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    n : int
        Number of times (default 100).
    k : int
        The band spans the first ``k`` eigenvalues (default 200; :func:`spectral_band`).

    Returns
    -------
    times : (n,) float
        Increasing, log-spaced.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(3)
    >>> t = sig.hks_times(sig.laplacian(V, F), n=5, k=50)
    >>> T = sig.hks_times(sig.laplacian(10 * V, F), n=5, k=50)
    >>> bool(abs(T[0] / t[0] - 100) < 1e-6 * 100)
    True
    """
    lap = as_laplacian(lap)
    n = as_int(n, "n", lo=1, hi=MAX_SCALES)
    lam_lo, lam_hi, _ = spectral_band(lap, k)
    return np.geomspace(_DAMP / lam_hi, _DAMP / lam_lo, n)


def wks_energies(lap, n: int = GRID_SIZE, k: int = BAND):
    r"""WKS log-energies and band width from the spectrum (Aubry et al. 2011).

    With :math:`[e_{lo}, e_{hi}] = [\log\lambda_{lo}, \log\lambda_{hi}]` the band of the first
    ``k`` eigenvalues (:func:`spectral_band`) and :math:`r = e_{hi} - e_{lo}`:
    :math:`\sigma = 7 r / \max(n, 100)` and ``n`` energies evenly spaced over
    :math:`[e_{lo} + 2\sigma, e_{hi} - 2\sigma]`. For ``n >= 100`` this is Aubry et al.'s
    choice as pyFM's ``auto_WKS`` implements it; fewer energies keep the band width of 100
    (a wider one would blur every energy into its neighbours').

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    n : int
        Number of energies (default 100).
    k : int
        The band spans the first ``k`` eigenvalues (default 200; :func:`spectral_band`).

    Returns
    -------
    energies : (n,) float
        Log-energies, evenly spaced.
    sigma : float
        The band width :math:`\sigma`.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> e, sigma = sig.wks_energies(lap, n=5, k=50)
    >>> lo, hi, _ = sig.spectral_band(lap, 50)
    >>> bool(np.isclose(e[0] - 2 * sigma, np.log(lo))), bool(np.isclose(sigma, 7 * np.log(hi / lo) / 100))
    (True, True)
    """
    lap = as_laplacian(lap)
    n = as_int(n, "n", lo=1, hi=MAX_SCALES)
    lam_lo, lam_hi, _ = spectral_band(lap, k)
    e_lo, e_hi = np.log(lam_lo), np.log(lam_hi)
    sigma = 7.0 * (e_hi - e_lo) / max(n, GRID_SIZE)
    if not sigma > 0:
        raise ValueError(f"the band of the first {k} eigenvalues is a single point; use a larger k")
    return np.linspace(e_lo + 2 * sigma, e_hi - 2 * sigma, n), float(sigma)


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


EPS = np.finfo(float).eps


def _joined(methods):
    """One method name, or the distinct names joined by ``+``."""
    names = list(dict.fromkeys(methods))
    return names[0] if len(names) == 1 else "+".join(names)


def _stacked(infos, scalar, **extra):
    """The ``info`` of diagonals computed one scale at a time: per-entry bounds side by side."""
    err = np.stack([np.asarray(i["abs_error"], dtype=float) for i in infos], axis=1)
    out = bound_info(err[:, 0] if scalar else err, weakest(*[i["bound_kind"] for i in infos]),
                        _joined(i["method"] for i in infos), **extra)
    notes = [i["note"] for i in infos if i.get("note")]
    if notes:
        out["note"] = "; ".join(dict.fromkeys(notes))
    return out


def spectral_descriptor(lap, filt, method: str = "auto", return_info: bool = False, **kwargs):
    r"""The diagonal of the spectral kernel :math:`K = \varphi(\tilde L)B^{-1}`.

    .. math:: SD(i) = K(i, i) = \sum_l \varphi(\lambda_l)\, x_l(i)^2

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    filt : Filter
        :math:`\varphi` (:mod:`spectral_igl.filters`).
    method : str
        Diagonal method, see :func:`spectral_igl.kernel_diagonal` (``"auto"``: selected
        inversion of a rational approximation, with a certified error bound).
    return_info : bool
        Also return the diagonal's ``info`` (:func:`spectral_igl.kernel_diagonal`): the
        per-vertex ``abs_error``, ``bound_kind``, ``method``, ...
    **kwargs
        Passed to :func:`spectral_igl.kernel_diagonal` (``k``, ``distance``, ...).

    Returns
    -------
    SD : (n,) float
        :math:`K(i, i)` at every vertex.
    info : dict
        Only with ``return_info=True``.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> sd = sig.spectral_descriptor(lap, sig.filters.mexican_hat(0.2))
    >>> lam, X = sig.dense_eigs(lap)
    >>> exact = X ** 2 @ (0.2 * lam * np.exp(-0.2 * lam))
    >>> bool(np.max(np.abs(sd - exact)) < 1e-6)
    True
    """
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    return kernel_diagonal(lap, filt, method=method, return_info=return_info, **kwargs)


def hks(lap, times=None, method: str = "auto", progress=None, return_info: bool = False,
        time_unit: str = "absolute", normalize: bool = False, **kwargs):
    r"""Heat kernel signature (Sun et al. 2009) at one or several times.

    .. math:: HKS(i, t) = K_t(i, i) = \sum_l e^{-t\lambda_l}\, x_l(i)^2

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    times : float or (T,) float, optional
        Diffusion times, in the units ``time_unit``. Default: :func:`hks_times` (100 times
        spread over the band of the first 200 eigenvalues, from the spectrum, spectrum-free).
    method : str
        Diagonal method, see :func:`spectral_igl.kernel_diagonal`.
    progress : bool, optional
        A progress bar on stderr, one step per time, with the diagonal's own bar (per
        pole) under it (see :mod:`spectral_igl.progress`; default off).
    return_info : bool
        Also return ``info`` (:mod:`spectral_igl.accuracy`): ``abs_error`` shaped as the
        result, the kernel diagonal's bound at every vertex and time
        (:func:`spectral_igl.kernel_diagonal`), ``bound_kind`` (the weakest over the times),
        ``method``.
    time_unit : str
        Unit of ``times`` (:mod:`spectral_igl.laplacian.units`): ``"absolute"`` (default),
        ``"shape"`` (x area on surfaces, x volume\ :sup:`2/3` on solids), ``"area"``,
        ``"volume"``, ``"h2"``. ``info["times"]`` holds the absolute times used.
    normalize : bool
        Multiply by the measure (area or volume) of the vertex's connected component, the
        shape's measure on a connected shape: a dimensionless HKS that tends to 1 at large t on
        every component (an unreferenced vertex is its own component: 1 at every t) and, at
        times in the shape's units (or on the default grid), does not change when the shape is
        scaled, so that shapes of different sizes compare.
    **kwargs
        Passed to :func:`spectral_igl.kernel_diagonal`.

    Returns
    -------
    H : (n,) or (n, T) float
        :math:`K_t(i, i)`: (n,) for a scalar time, (n, T) for an array of T times.
    info : dict
        Only with ``return_info=True``; see ``return_info``.

    Notes
    -----
    Several times with ``method="selinv"``, or ``"auto"`` above 3000 vertices or for 8 times
    or more, share one set of poles
    (:func:`spectral_igl.families.heat_diagonals`): about as many factorizations
    as one time, each time with its own certified bound (``kernel_diagonal`` options other
    than ``tol`` select the one-time-at-a-time path).

    The signature of the survey's §6.2.1; spectrum-free as in §6.4.2.

    Examples
    --------
    The signature is the heat kernel's diagonal. On the unit sphere every point sees the
    same spectrum, :math:`\lambda = l(l+1)` with multiplicity :math:`2l+1`, so
    :math:`K_t(i,i) = \sum_l \frac{2l+1}{4\pi} e^{-l(l+1)t}`; a 642-vertex sphere is within 1%
    of it at :math:`t = 1`:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(3))
    >>> H, info = sig.hks(lap, [0.1, 1.0], return_info=True)
    >>> H.shape, info["bound_kind"], bool(np.all(info["abs_error"] < 1e-8))
    ((642, 2), 'proof', True)
    >>> l = np.arange(60)
    >>> exact = np.sum((2 * l + 1) / (4 * np.pi) * np.exp(-l * (l + 1) * 1.0))
    >>> bool(np.all(np.abs(H[:, 1] - exact) < 0.01 * exact))
    True
    """
    lap = as_laplacian(lap)
    return_info = as_flag(return_info, "return_info")
    normalize = as_flag(normalize, "normalize")
    if times is None:
        if time_unit != "absolute":
            raise ValueError(f"time_unit={time_unit!r} applies to times, which were not given (the "
                             "default grid hks_times(lap) follows the shape's spectrum already)")
        times = hks_times(lap)
    T = _values(shape_time(lap, _values(times, "times"), time_unit, "times"), "times")
    Tv = T.reshape(-1)
    out, info = _hks(lap, T, Tv, method, progress, kwargs)
    info["times"] = Tv.copy()
    if normalize:        # the measure of each vertex's component: 1 at large t on every component
        scale = lap.component_volume() if out.ndim == 1 else lap.component_volume()[:, None]
        out = out * scale
        info["abs_error"] = info["abs_error"] * scale * (1.0 + 2.0 * EPS) + EPS * np.abs(out)
        info["normalized_by"] = "component measure"
    return (out, info) if return_info else out


def _hks(lap, T, Tv, method, progress, kwargs):
    """``(values, info)`` of :func:`hks` at validated absolute times ``T``."""
    if _family(lap, method, Tv.size, kwargs):
        with progress_bar(T.size, "hks", progress, unit="time") as bar:
            md = heat_diagonals(lap, Tv, tol=kwargs.get("tol", 1e-8))
            out = md.values.copy()
            bar.update(T.size)
        info = bound_info(md.abs_bound, weakest(md.bound_kind, lambda_max_kind(lap)), "selinv",
                          eps=md.eps.copy(), factorizations=md.n_factorizations)
        return out, info
    cols, infos = [], []
    with progress_bar(T.size, "hks", progress, unit="time") as bar:
        for t in Tv:
            d, i = kernel_diagonal(lap, heat(float(t)), method=method, progress=progress, return_info=True,
                                   **kwargs)
            cols.append(d)
            infos.append(i)
            bar.set_postfix_str(f"t={t:.3g}")
            bar.update()
    out = cols[0] if T.ndim == 0 else np.stack(cols, axis=1)
    return out, _stacked(infos, T.ndim == 0)


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


def _family_target(tol):
    """The certified sup error asked of each WKS band filter's common-pole fit for ``tol``."""
    return max(tol * 1e-1, 1e-12)


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


#: Rademacher probes of the trace estimate of the WKS normaliser (full mass), where the
#: selected inversion cannot take the filter and n exceeds :data:`WKS_DENSE_MAX`
WKS_TRACE_PROBES = 64
#: largest n whose WKS normaliser (full mass) comes from the dense spectrum where the selected
#: inversion cannot take the filter
WKS_DENSE_MAX = 3000


def _wks_trace(lap, f, diag, diag_error, diag_kind, tol, family=None):
    r""":math:`\operatorname{tr}\psi(\tilde L) = \operatorname{tr}(KB)`, K the kernel whose diagonal is
    ``diag``, with a bound of its error and the bound's kind: ``(trace, bound, kind, note)``.

    Lumped mass: :math:`\sum_i m_i K_{ii}`, exact, within :math:`\sum_i m_i` ``diag_error``
    (plus the rounding of the sums). Full mass: :math:`\operatorname{tr}(KB)` also needs
    :math:`K_{ij}` on the edges; it is :math:`\operatorname{tr} r(\tilde L)` of the rational
    approximation r, from the entries of each pole's inverse on the pattern of B (selected
    inversion), within :math:`n\varepsilon` (``family``: ``(trace, bound, kind)`` from the
    common-pole pass; else the selected-inverse kernel of ``(f, tol)``, which the diagonal's
    pass has computed it with when that took the ``"selinv"`` path; where that kernel refuses
    the filter, a common-pole fit of it alone). Where neither applies: the dense spectrum for :math:`n \le` ``WKS_DENSE_MAX``
    (its rounding a model), Hutchinson's estimate :math:`\mathbb E[z^\top\psi(\tilde L)z]`
    above (three standard errors of the probes' mean): estimates both.
    """
    if lap.lumped:
        tr = float(lap.mass @ diag)
        bound = float(lap.mass @ diag_error) + (lap.n + 2) * EPS * float(lap.mass @ np.abs(diag))
        return tr, bound, diag_kind, None
    if family is not None:
        return family + (None,)
    try:
        kern = selinv_kernel(lap, f, tol)
        tr, bound = kern.trace()
        return tr, bound, kern.bound_kind, None
    except NoSelinv:    # e.g. a real pole of the one-filter fit between 0 and lambda_2
        pass
    try:
        md = family_diagonals(lap, [f], _family_target(tol))
        return float(md.trace[0]), float(md.trace_bound[0]), weakest(md.bound_kind, lambda_max_kind(lap)), None
    except ValueError:
        pass
    if lap.n <= WKS_DENSE_MAX:
        lam = np.asarray(dense_eigs(lap)[0])
        vals = f(np.maximum(lam, 0.0))
        return (float(np.sum(vals)), 1e2 * lap.n * EPS * float(np.sum(np.abs(vals))), "estimate",
                "the normaliser (full mass) is the sum of the filter over the dense spectrum: its "
                "rounding is a model")
    from .approx import apply_filter

    Z = np.random.default_rng(0).choice([-1.0, 1.0], size=(lap.n, WKS_TRACE_PROBES))
    Y = np.real(apply_filter(lap, f, Z))
    q = np.einsum("ij,ij->j", Z, Y)
    return (float(np.mean(q)), 3.0 * float(np.std(q, ddof=1)) / np.sqrt(q.size), "estimate",
            f"the normaliser (full mass) is a Hutchinson estimate with {q.size} probes: its bound is "
            "three standard errors of their mean")


def _ratio_error(w, d_error, tr, tr_error):
    r"""Bound of :math:`|d/\tau - \tilde d/\tilde\tau|` from :math:`|d - \tilde d| \le \delta_d`,
    :math:`|\tau - \tilde\tau| \le \delta_\tau`, :math:`\tilde w = \tilde d/\tilde\tau`:
    :math:`(\delta_d + |\tilde w|\delta_\tau)/(\tilde\tau - \delta_\tau)` (:math:`\infty` unless
    :math:`\tilde\tau > \delta_\tau`), plus the rounding of the division."""
    low = tr - tr_error
    if not low > 0:
        return np.full(np.shape(w), np.inf)
    return (d_error + np.abs(w) * tr_error) / low * (1.0 + 4.0 * EPS) + 2.0 * EPS * np.abs(w)


def wks(lap, energies=None, sigma: float | None = None, k: int = 100, method: str = "eigen",
        progress=None, return_info: bool = False, **kwargs):
    r"""Wave kernel signature (Aubry et al. 2011) at log-energies ``energies``.

    .. math:: WKS(i, e) = \frac{\sum_l \psi_e(\lambda_l)\, x_l(i)^2}{\sum_l \psi_e(\lambda_l)},
              \qquad \psi_e(s) = \exp\Big(-\frac{(e - \log s)^2}{2\sigma^2}\Big), \ \psi_e(0) = 0

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    energies : float or (E,) float, optional
        Log-energies :math:`e`. Default: :func:`wks_energies` over the band of the first
        ``k`` non-zero eigenvalues (100 energies, Aubry et al.'s spacing and ``sigma``), from
        the spectrum, spectrum-free; ``info["energies"]`` and ``info["sigma"]`` hold the grid.
    sigma : float, optional
        Band width; default with ``energies`` given: :math:`7\,\delta` with :math:`\delta` the
        spacing of ``energies`` (Aubry's choice), required for a single energy.
    k : int
        Non-zero eigenpairs for ``method="eigen"`` (the definition of Aubry et al.).
    method : {"eigen", "auto", "selinv", "exact", "probing", "dense"}
        ``"eigen"``: the original truncated definition. Otherwise the diagonal of
        :math:`K = \psi_e(\tilde L)B^{-1}` spectrum-free; the normaliser
        :math:`\operatorname{tr}\psi_e(\tilde L) = \operatorname{tr}(KB)` is then
        :math:`\sum_i m_i K(i,i)` for a lumped mass matrix; for a full mass matrix
        :math:`\operatorname{tr}(KB) \ne \sum_i m_i K(i,i)` (the off-diagonal
        :math:`K_{ij}B_{ij}` differ, by a factor of about 2 at high energies), so it is
        :math:`\operatorname{tr} r(\tilde L) = n\alpha_0 + \sum_j \mathrm{Re}\,c_j
        \operatorname{tr}((\sigma L - z_jB)^{-1}B)` of the rational approximation r of the
        diagonal, each :math:`\operatorname{tr}(A^{-1}B) = \sum_{ij}(A^{-1})_{ij}B_{ij}` from
        the entries of :math:`A^{-1}` on the pattern of B that the same selected inversion
        gives (:meth:`spectral_igl.linalg.LDLT.selected_inverse`): within
        :math:`n\varepsilon` of the exact trace (:math:`\varepsilon` the diagonal's
        certified sup error, every one of the n eigenvalues contributing at most that), at
        the cost of the lumped case (measured 1.0--2.0 times it, 3k to 43k vertices). Only
        where no rational fit is taken does it fall back to the dense spectrum
        (:math:`n \le` ``WKS_DENSE_MAX``) or a Hutchinson estimate with ``WKS_TRACE_PROBES``
        probes, both labelled estimates.
    progress : bool, optional
        Spectrum-free methods: a progress bar on stderr, one step per energy (see
        :mod:`spectral_igl.progress`; default off).
    return_info : bool
        Also return ``info`` (:mod:`spectral_igl.accuracy`): ``abs_error`` shaped as the
        result. Spectrum-free: the diagonal's bound :math:`\delta_d` and the normaliser's
        :math:`\delta_\tau` propagated through the ratio,
        :math:`(\delta_d + |\widetilde{WKS}|\,\delta_\tau)/(\tilde\tau - \delta_\tau)`;
        ``bound_kind`` the weakest of the parts (a proof for either mass matrix where the
        diagonal is one; a normaliser that is an estimate says so in ``note``). ``"eigen"``: ``nan`` and ``None`` (a truncated expansion by definition;
        its eigenpairs are not certified).
    **kwargs
        Passed to :func:`spectral_igl.kernel_diagonal`.

    Returns
    -------
    W : (n,) or (n, E) float
        (n,) for a scalar energy, (n, E) for E energies.
    info : dict
        Only with ``return_info=True``.

    Notes
    -----
    The wave kernel signature of the survey's §6.1 and §6.2.1, in Aubry et al.'s band-pass form.

    Examples
    --------
    With a lumped mass matrix the normaliser is :math:`\sum_i m_i K(i,i)`, so the
    mass-weighted sum of the signature is 1 at every energy:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> W = sig.wks(lap, [1.0, 2.0, 3.0], sigma=0.5, method="auto")
    >>> W.shape, np.round(lap.mass @ W, 6)
    ((162, 3), array([1., 1., 1.]))
    """
    lap = as_laplacian(lap)
    return_info = as_flag(return_info, "return_info")
    if energies is None:
        k = as_int(k, "k", lo=1, hi=lap.n)
        energies, grid_sigma = wks_energies(lap, GRID_SIZE, lap.n_components + k)
        sigma = grid_sigma if sigma is None else sigma
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
        info = bound_info(np.full(out.shape, np.nan), None, "eigen", k=k,
                             note="truncated eigen-expansion (Aubry et al.'s definition) from eigenpairs "
                                  "that are not certified: no error bound")
    else:
        if k != 100:
            raise ValueError(f"option k={k!r} is used only by method='eigen' (the truncation), not by "
                             f"method {method!r}")
        filts = [_wks_filter(float(e), sigma) for e in Ev]
        md = None
        if _family(lap, method, Ev.size, kwargs):
            # common poles for all energies (set-valued AAA), each energy certified
            tol = kwargs.get("tol", 1e-8)
            md = family_diagonals(lap, filts, _family_target(tol), scales=np.exp(Ev))
        cols, errs, kinds, methods, notes = [], [], [], [], []
        bar = progress_bar(Ev.size, "wks", progress, unit="energy")
        for k, f in enumerate(filts):
            family = None
            if md is not None:
                d, derr = md.values[:, k], md.abs_bound[:, k]
                kinds.append(weakest(md.bound_kind, lambda_max_kind(lap)))
                methods.append("selinv")
                if md.trace is not None:
                    family = (float(md.trace[k]), float(md.trace_bound[k]), kinds[-1])
            else:
                d, dinfo = kernel_diagonal(lap, f, method=method, progress=progress, return_info=True, **kwargs)
                d, derr = np.real(d), dinfo["abs_error"]
                kinds.append(dinfo["bound_kind"])
                methods.append(dinfo["method"])
                notes.append(dinfo.get("note"))
            tr, tr_err, tr_kind, note = _wks_trace(lap, f, d, derr, kinds[-1], kwargs.get("tol", 1e-8), family)
            if not tr > 0:
                raise ValueError(f"the WKS band at energy {float(Ev[k]):g} (sigma {sigma:g}) holds no "
                                 "eigenvalue of the shape to double precision; choose energies within "
                                 "[log lambda_2, log lambda_max] or use method='eigen'")
            cols.append(d / tr)
            errs.append(_ratio_error(cols[-1], derr, tr, tr_err))
            kinds.append(tr_kind)
            notes.append(note)
            bar.update()
        bar.close()
        out = np.stack(cols, axis=1)
        info = bound_info(np.stack(errs, axis=1), weakest(*kinds), _joined(methods))
        if any(notes):
            info["note"] = "; ".join(dict.fromkeys(x for x in notes if x))
    if E.ndim == 0:
        out, info["abs_error"] = out[:, 0], info["abs_error"][:, 0]
    info.update(energies=Ev.copy(), sigma=float(sigma))
    return (out, info) if return_info else out


def auto_diffusion_function(lap, t, method: str = "auto", return_info: bool = False, **kwargs):
    r"""Auto-diffusion function (Gebal et al. 2009), scale invariant.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    t : float or (T,) float
        Times in units of :math:`1/\lambda_2`.
    method : str
        Diagonal method, see :func:`spectral_igl.kernel_diagonal`.
    return_info : bool
        With ``return_info`` also ``info`` (:mod:`spectral_igl.accuracy`): ``abs_error``, the
        area times the heat diagonal's bound at the time :math:`t/\tilde\lambda_2`; its
        ``bound_kind`` is at best ``"estimate"``: :math:`\tilde\lambda_2` is a Lanczos eigenvalue
        (not certified) and its error moves the time itself (``note``). ``lambda2`` is that value.
    **kwargs
        Passed to :func:`spectral_igl.kernel_diagonal`.

    Returns
    -------
    ADF : (n,) or (n, T) float
        (n,) for a scalar time, (n, T) for T times.
    info : dict
        Only with ``return_info=True``.

    Notes
    -----
    .. math:: ADF_t(i) = A\, K_{t/\lambda_2}(i, i) = A \sum_l e^{-t\lambda_l/\lambda_2}\, x_l(i)^2

    Time is measured in units of :math:`1/\lambda_2` (the first non-zero eigenvalue,
    Gebal et al.'s normalisation) and the value is multiplied by the area :math:`A`, so
    ADF is invariant under a uniform scaling of the shape and equals 1 at large t on a
    connected shape.

    Examples
    --------
    The same values on a shape ten times larger, and 1 at large times:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> a = sig.auto_diffusion_function(sig.laplacian(V, F), [0.5, 50.0])
    >>> b = sig.auto_diffusion_function(sig.laplacian(10 * V, F), [0.5, 50.0])
    >>> bool(np.max(np.abs(a - b)) < 1e-6), bool(np.max(np.abs(a[:, 1] - 1)) < 1e-6)
    (True, True)
    """
    lap = as_laplacian(lap)
    return_info = as_flag(return_info, "return_info")
    T = _values(t, "t")
    for ti in T.reshape(-1):
        as_positive(ti, "t")
    c = lap.n_components
    if c >= lap.n:
        raise ValueError("the shape has no non-zero eigenvalue (every vertex is its own component)")
    lam2 = float(cached_eigs(lap, c + 1)[0][c])
    H, info = hks(lap, T / lam2, method=method, return_info=True, **kwargs)
    area = float(lap.area())
    out = H * area
    if not return_info:
        return out
    info["abs_error"] = info["abs_error"] * area * (1.0 + 2.0 * EPS) + EPS * np.abs(out)
    info.update(bound_kind=weakest(info["bound_kind"], "estimate"), lambda2=lam2,
                note="the time unit 1/lambda_2 comes from a Lanczos eigenvalue (not certified); the "
                     "bound is that of the heat diagonal at the computed time, times the area")
    return out, info


def eccentricity(lap, filt, method: str = "auto", return_info: bool = False, **kwargs):
    r"""Spectral eccentricity: the root-mean-square spectral distance to the shape.

    Parameters
    ----------
    lap : Laplacian or mesh
        The shape (anything :func:`~spectral_igl.laplacian.as_laplacian` takes).
    filt : Filter
        :math:`\varphi`; the distance uses :math:`|\varphi|^2` (:func:`spectral_igl.spectral_distance`).
    method : str
        Diagonal method, see :func:`spectral_igl.kernel_diagonal`.
    return_info : bool
        With ``return_info`` also ``info`` (:mod:`spectral_igl.accuracy`): ``abs_error`` (n,)
        from the diagonal's bound :math:`\delta`, :math:`|ecc^2 - \widetilde{ecc}^2| \le \delta_i +
        \frac{1}{A_c}\sum_{j \in c} m_j\delta_j` plus the rounding of the sums, turned into a bound
        of :math:`|ecc - \widetilde{ecc}|` by :func:`spectral_igl.distances.root_error`;
        ``bound_kind`` and ``method`` of the diagonal.
    **kwargs
        Passed to :func:`spectral_igl.kernel_diagonal`.

    Returns
    -------
    ecc : (n,) float
        The eccentricity of every vertex.
    info : dict
        Only with ``return_info=True``.

    Notes
    -----
    .. math:: ecc(i)^2 = \frac{1}{A_c}\sum_{j \in c} m_j\, d^2(i, j)
              = G_{ii} + \frac{1}{A_c}\sum_{j\in c} m_j G_{jj} - \frac{2|\varphi(0)|^2}{A_c}

    with :math:`G = |\varphi|^2(\tilde L)B^{-1}`, :math:`m = B\mathbf 1`, :math:`c` the
    connected component of i and :math:`A_c` its area. The identity uses
    :math:`G B \mathbf 1 = |\varphi(0)|^2 \mathbf 1`, so the eccentricity costs one
    diagonal (no n² distances). For the diffusion filter it is the survey's
    :math:`ecc_t` (§5.1) up to the square root.

    Examples
    --------
    The mean of the squared distances, computed from one diagonal instead of n distances:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> ecc = sig.eccentricity(lap, sig.filters.biharmonic())
    >>> d = sig.biharmonic_distance(lap, 7)
    >>> bool(abs(ecc[7] - np.sqrt(lap.mass @ d ** 2 / lap.mass.sum())) < 1e-6 * ecc[7])
    True
    """
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    return_info = as_flag(return_info, "return_info")
    G2 = filt.square
    diag, dinfo = kernel_diagonal(lap, G2, method=method, return_info=True, **kwargs)
    diag = np.real(diag)
    m = lap.mass
    lab = lap.components
    Ac = np.bincount(lab, weights=m)
    Tc = np.bincount(lab, weights=m * diag)
    phi0 = abs(filt.at_zero()) ** 2
    e2 = diag + Tc[lab] / Ac[lab] - 2.0 * phi0 / Ac[lab]
    ecc = np.sqrt(np.maximum(e2, 0.0))
    if not return_info:
        return ecc
    derr = np.asarray(dinfo["abs_error"], dtype=float)
    size = np.bincount(lab)
    mag = np.abs(diag) + (np.bincount(lab, weights=m * np.abs(diag)) / Ac)[lab] + 2.0 * phi0 / Ac[lab]
    e2_error = derr + (np.bincount(lab, weights=m * derr) / Ac)[lab] + (size[lab] + 8) * EPS * mag
    info = dict(dinfo, abs_error=root_error(ecc, e2_error))
    info.pop("abs_error_bound", None)      # the diagonal's, not the eccentricity's
    return ecc, info
