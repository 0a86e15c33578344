r"""The diagonal of a spectral kernel :math:`G = \varphi(\tilde L)B^{-1}` at every vertex.

One-to-all spectral distances and the descriptors (HKS, WKS, ADF, eccentricity) need
:math:`G_{ii}` at all n vertices. The kernel is dense, so its diagonal is not a by-product
of any single solve. Methods:

``"exact"``
    n applications of the engine (in blocks): exact up to the engine's certified bound.
    Its cost is n engine columns, minutes for a filter the engine applies slowly (a
    multiscale filter on 642 vertices: 158 s); the cost is measured on a few columns first
    and a call estimated above :data:`EXACT_TIME_LIMIT` seconds is refused with the
    estimate, before the rest of the work.
    For small and moderate n.
``"dense"``
    Dense generalized eigen-decomposition (n <= 8000): the ground truth. The
    decomposition is cached on the Laplacian, so further filters and times cost one
    matrix product each. ``"auto"`` uses it for n <= 3000 when ``"selinv"`` does not
    apply (n = 2562: 18 s once, against 37 s per filter for ``"exact"``).
``"eigen"``
    Truncated eigen-expansion with the ``k`` lowest eigenpairs: the classical baseline.
    No error bound; wrong by the whole omitted tail of the spectrum.
``"selinv"``
    Spectrum-free and exact up to a certified rational error: a partial-fraction
    approximation :math:`r(s) = \alpha_0 + \sum_j c_j/(\sigma s - z_j)` of the filter turns
    the diagonal into :math:`\alpha_0\,\mathrm{diag}(B^{-1}) + \sum_j c_j\,
    \mathrm{diag}((\sigma L - z_j B)^{-1})`, and the diagonal of each inverse comes from its
    sparse LDLᵀ factor by selected inversion (no column of the inverse is formed). The heat
    filter uses the Carathéodory--Fejér approximant, other filters an AAA fit. The
    commute-time kernel (:math:`s^{-1}`) is exact: :math:`G = QXQ^\top` with X the inverse of
    the grounded stiffness and :math:`Q = I - 1w^\top` the B-orthogonal projector off ker L;
    the biharmonic kernel (:math:`s^{-2}`) is exact too, :math:`G_c B G_c`, with
    :math:`\mathrm{diag}(XBX)` the complex-step derivative of
    :math:`\mathrm{diag}((L_g - zB)^{-1})` at z = 0 (one complex factorization). Error: :math:`|G_{ii} - \tilde G_{ii}| \le \varepsilon\,(B^{-1})_{ii}` with
    :math:`\varepsilon = \max|\varphi - r|` on the spectrum (reported as
    ``abs_error_bound``), and the error is also measured at ``samples`` vertices. The exact
    paths (and the circle rule of :math:`s^{-p}`, p >= 3) report an a-priori rounding
    allowance instead, which grows with :math:`\lambda_{\max}/\lambda_{\min}^+`
    (64 ε p (1 + κ) times the magnitudes of the terms summed, κ the spectrum's ratio).
``"probing"``
    Spectrum-free estimator: probing vectors built from a distance-``D`` colouring of
    the mesh graph (two vertices of one colour are more than ``D`` edges apart), so that
    :math:`(G z_c)_i = G_{ii} + \sum_{j \in c, j \ne i} G_{ij}` and the far entries
    :math:`G_{ij}` are the error; the slowly-decaying low-frequency part of the kernel is
    optionally removed exactly with ``k`` low eigenpairs (deflation). Its accuracy is
    *measured* and reported: the exact diagonal is computed at ``samples`` random
    vertices and compared (those entries are then exact in the output).
"""
from __future__ import annotations

import logging
import time

import numpy as np

from ..accuracy import info as bound_info, weakest
from .._validate import as_choice, as_delta, as_flag, as_int, as_tol, check_dense_size, check_spectral_function
from ..approx import LARGE_T, spectral_operator
from ..approx import METHODS as ENGINE_METHODS
from ..approx.common import gamma, mass_sum_rounding, reciprocal_rounding
from ..filters import check_filter
from ..laplacian import as_laplacian, entry_error, lambda_max, lambda_max_kind
from ..linalg import inverse_mass_diagonal, lambda_min_positive, lambda_min_positive_kind
from ..progress import progress_bar
from .probing import probing_diagonal
from .selinv import NoSelinv, selinv_kernel, selinv_supported
from .spectral import eigen_diagonal, low_rank, phi_values

__all__ = ["kernel_diagonal", "check_diagonal_options", "column_entry_error", "METHODS", "EXACT_MAX"]

log = logging.getLogger(__name__)

#: The diagonal methods, read by the distances, the command line and the viewer.
METHODS = ("auto", "exact", "dense", "eigen", "selinv", "probing")
#: ``auto`` uses the (cached) dense eigendecomposition up to this many vertices where
#: ``"selinv"`` does not apply
EXACT_MAX = 3000
#: columns per engine call in ``"exact"`` and ``"probing"``
BLOCK = 64
#: seconds above which method="exact" is refused up front (its estimated cost is measured on
#: a few columns); raise it to run longer exact diagonals
EXACT_TIME_LIMIT = 60.0
#: default of ``samples`` (an explicit other value with a method that takes none is refused)
DEFAULT_SAMPLES = 16
#: the methods that read each option of :func:`kernel_diagonal` (``"auto"`` may pick any)
OPTION_METHODS = {"k": ("eigen", "probing"), "distance": ("probing",), "max_colours": ("probing",),
                  "samples": ("probing", "selinv")}
#: the probing estimate of every entry: this many times the largest error measured at the samples
PROBING_SAFETY = 10.0
#: the rounding model of the dense eigendecomposition, in units of ``n * eps * max|phi(lambda)|``
#: (as for the engine's ``"dense"`` method)
DENSE_ROUNDING = 1e2


def column_entry_error(lap, bnorm_error, delta: str = "mass") -> np.ndarray:
    r"""Per-entry bound of a kernel column from the B-norm bound of its error.

    ``delta="mass"``: the column is :math:`Y = \varphi(\tilde L)B^{-1}e_i` and
    :math:`|\delta Y_j| \le \|\delta Y\|_B / \sqrt{c\,D_{jj}}`
    (:func:`spectral_igl.laplacian.entry_error`). ``delta="seed"``: the column is
    :math:`BY` with :math:`Y = \varphi(\tilde L)e_i`, and
    :math:`|e_j^\top B\,\delta Y| = |\langle e_j, \delta Y\rangle_B| \le \sqrt{B_{jj}}\,\|\delta Y\|_B`.

    Parameters
    ----------
    lap : Laplacian
    bnorm_error : float or (m,) float
        Bounds of :math:`\|\delta Y\|_B`, one per column.
    delta : {"mass", "seed"}

    Returns
    -------
    (n,) float for a scalar bound, (n, m) float for m bounds.
    """
    if delta == "mass":
        return entry_error(lap, bnorm_error)
    b = np.asarray(bnorm_error, dtype=float)
    w = np.sqrt(lap.B.diagonal()) * (1.0 + 4.0 * np.finfo(float).eps)
    return w * b if b.ndim == 0 else w[:, None] * b[None, :]


def _gram_apply(lap, op, delta):
    """Z -> G Z for G = phi(L~) B^-1 (mass) or B phi(L~) (seed)."""
    if delta == "mass":
        return op.apply_inverse_mass
    return lambda Z: lap.B @ op.apply(Z)


def check_diagonal_options(n: int, method="auto", k=None, distance=None, samples=16, rtol=1e-4,
                           max_colours=None, tol=1e-8, engine_method="auto", seed=0):
    """Validate the options of :func:`kernel_diagonal` for a Laplacian of ``n`` vertices.

    Everything is checked before any work; returns ``(k, distance, samples, rtol,
    max_colours, tol, seed)`` as plain numbers. ``method="dense"`` is refused up front
    when the dense eigenproblem does not fit the memory budget.
    """
    as_choice(method, "diagonal method", METHODS)
    as_choice(engine_method, "method", ENGINE_METHODS)
    k = None if k is None else as_int(k, "k", lo=0, hi=n)
    distance = None if distance is None else as_int(distance, "distance", lo=1, hi=max(n, 1))
    samples = as_int(samples, "samples", lo=0)
    rtol = as_tol(rtol, "rtol")
    max_colours = None if max_colours is None else as_int(max_colours, "max_colours", lo=1, hi=n)
    tol = as_tol(tol, "tol")
    seed = as_int(seed, "seed", lo=0)
    given = {"k": k, "distance": distance, "max_colours": max_colours,
             "samples": None if samples == DEFAULT_SAMPLES else samples}
    for name, value in given.items():
        if value is not None and method != "auto" and method not in OPTION_METHODS[name]:
            raise ValueError(f"option {name}={value!r} is not used by diagonal method {method!r} (it applies "
                             f"to {' and '.join(repr(m) for m in OPTION_METHODS[name])})")
    if method == "eigen" and k == 0:
        raise ValueError("k must be an integer in [1, n] for method 'eigen' (the number of eigenpairs of "
                         "the truncated expansion), got 0")
    if method == "dense":
        check_dense_size(6 * 8.0 * n * n, f"the dense ({n}, {n}) eigenproblem of method='dense'",
                         "use method='selinv' or 'probing'")
    return k, distance, samples, rtol, max_colours, tol, seed


def kernel_diagonal(lap, filt, method: str = "auto", delta: str = "mass", k: int | None = None,
                    distance: int | None = None, samples: int = 16, rtol: float = 1e-4,
                    max_colours: int | None = None, tol: float = 1e-8,
                    engine_method: str = "auto", seed: int = 0, return_info: bool = False,
                    progress=None):
    r"""Diagonal of the spectral kernel :math:`G = \varphi(\tilde L)B^{-1}` at every vertex.

    .. math:: G_{ii} = \sum_l \varphi(\lambda_l)\, x_l(i)^2

    Parameters
    ----------
    lap : Laplacian
    filt : Filter
        The filter whose kernel diagonal is wanted (for spectral distances pass
        :math:`|\varphi|^2`, ``filt.square``).
    method : {"auto", "exact", "dense", "selinv", "probing", "eigen"}
        See the module notes. ``"auto"``: ``"selinv"``; where it does not apply (a complex
        filter, ``delta="seed"`` with a full mass matrix, a fit with poles near 0 such as
        :math:`s^{-3}`), ``"dense"`` (cached) for ``n <= 3000``, else ``"probing"``.
    delta : {"mass", "seed"}
        ``"seed"`` gives the diagonal of :math:`B\varphi(\tilde L)` (the seed-delta Gram
        matrix).
    k : int, optional
        Eigenpairs: the truncation of ``"eigen"`` (default 100), the deflation rank of
        ``"probing"`` (0: no deflation). ``"probing"`` chooses it when not given: 0 if
        the kernel decays fast enough for ``rtol``, else the better of 0 and 100.
    distance : int, optional
        Colouring distance of ``"probing"`` (graph rings). Chosen when not given: the
        smallest distance whose error, predicted from the decay of the exact sample
        columns with graph distance, is below ``rtol`` within ``max_colours`` colours
        (else the most accurate one within the budget).
    samples : int
        ``"probing"``: vertices at which the exact kernel column is computed; they set
        the choices above and measure the error (reported in ``info``), and are exact
        in the output. At least 1 unless both ``k`` and ``distance`` are given.
        ``"selinv"``: vertices where the selected inversion is checked against solves
        with the same factors (0 to skip); the approximation error itself is certified
        (``abs_error_bound``).
    rtol : float
        ``"probing"``: relative accuracy aimed at when choosing ``k`` and ``distance``
        (the reported error is measured, not this target).
    max_colours : int, optional
        ``"probing"``: colour budget (engine applications), default
        ``min(256, n // 4)``.
    tol, engine_method : passed to the engine.
    seed : int
        Random seed of the sample vertices.
    return_info : bool
        Also return a dict (:mod:`spectral_igl.accuracy`): ``abs_error`` (n,), a bound of
        :math:`|G_{ii} - \tilde G_{ii}|` at every vertex (``nan`` where there is none),
        ``bound_kind`` (``"proof"`` for ``"selinv"``, ``"exact"`` and the large-time
        projection with certified ingredients; ``"estimate"`` for ``"probing"``, whose error
        is measured at the samples and scaled by :data:`PROBING_SAFETY`, and ``"dense"``, whose
        rounding is a model; ``None`` for ``"eigen"``), ``method``, ``note`` (why a bound is
        an estimate or missing), ``abs_error_bound`` (the largest ``abs_error``),
        ``applications`` (engine columns), ``k``, ``distance``, ``colours``, and for
        ``"probing"`` the measured ``sample_abs_error`` and ``sample_rel_error`` (max over
        the samples), the ``samples`` and, when chosen, the ``predicted_rel_error``.
    progress : bool, optional
        Draw a progress bar on stderr, one step per pole (``"selinv"``) or block of 64
        columns or colours; see :mod:`spectral_igl.progress` (default: off).

    Returns
    -------
    diag : (n,) float (complex for a complex filter)
    info : dict, only with ``return_info``

    Examples
    --------
    The diagonal :math:`K(i,i) = \sum_l \varphi(\lambda_l) x_l(i)^2` against dense eigenpairs,
    within its certified bound:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> diag, info = sig.kernel_diagonal(lap, sig.filters.biharmonic(), return_info=True)
    >>> lam, X = sig.dense_eigs(lap)
    >>> exact = X[:, 1:] ** 2 @ (1 / lam[1:])
    >>> bool(np.all(np.abs(diag - exact) <= info["abs_error"])), info["bound_kind"]
    (True, 'proof')
    """
    lap = as_laplacian(lap)
    filt = check_filter(filt)
    delta = as_delta(delta)
    return_info = as_flag(return_info, "return_info")
    k, distance, samples, rtol, max_colours, tol, seed = check_diagonal_options(
        lap.n, method, k, distance, samples, rtol, max_colours, tol, engine_method, seed)
    check_spectral_function(filt, 0.0, lambda_max(lap), repr(filt), singular=filt.singular)
    args = (method, delta, k, distance, samples, rtol, max_colours, float(tol), engine_method, seed)
    diag, info = lap.cache.fetch("diagonal", (filt,) + args, lambda: _diagonal(lap, filt, *args, progress=progress))
    diag = diag.copy()    # the cached arrays stay as computed whatever the caller does
    if not return_info:
        return diag
    return diag, {key: (v.copy() if isinstance(v, np.ndarray) else v) for key, v in info.items()}


def _bounded(info, abs_error, kind, note=None):
    """``info`` with the per-vertex ``abs_error``, its ``bound_kind``, the largest entry as
    ``abs_error_bound`` and, when given, the ``note`` saying why the bound is weak or absent."""
    abs_error = np.asarray(abs_error, dtype=float)
    info.update(bound_info(abs_error, kind, info["method"]))
    info["abs_error_bound"] = float(np.max(abs_error, initial=0.0)) if np.all(np.isfinite(abs_error)) \
        else float("nan")
    if note is not None:
        info["note"] = note
    return info


def _dense_rounding(lap, filt, delta):
    r"""The rounding model of the dense diagonal: :math:`\rho\,(B^{-1})_{ii}` (``"seed"``:
    :math:`\rho B_{ii}`), :math:`\rho` = :data:`DENSE_ROUNDING` n eps max|phi(lambda)|, the
    B-norm error model of the engine's ``"dense"`` method applied to :math:`B^{-1}e_i`."""
    lam, _ = low_rank(lap, None, delta)
    top = float(np.max(np.abs(phi_values(filt, lam, lap.n_components)), initial=0.0))
    rho = DENSE_ROUNDING * lap.n * np.finfo(float).eps * top
    return rho * column_entry_error(lap, 1.0, delta) ** 2


def heat_projection_applies(lap, filt) -> bool:
    """Whether the heat diagonal is taken as the projection onto the constants (a large t)."""
    return filt.kind == "heat" and filt.params["t"] * lambda_max(lap) > LARGE_T


def _exact_cost(G, n: int, dtype) -> float:
    """Estimated seconds of the n engine columns of method="exact", measured on a few.

    One column first; when n times its cost is not clearly below the limit, a block of 8
    (per-column cost falls in blocks, so this is the estimate used).
    """
    def seconds(k):
        E = np.zeros((n, k), dtype=dtype)
        E[np.arange(k), np.arange(k)] = 1.0
        t0 = time.perf_counter()
        G(E)
        return time.perf_counter() - t0

    est = n * seconds(1)
    if est > EXACT_TIME_LIMIT / 4 and n > 8:
        est = n / 8 * seconds(8)
    return est


def _check_exact_cost(G, n: int, dtype) -> None:
    est = _exact_cost(G, n, dtype)
    if est > EXACT_TIME_LIMIT:
        raise ValueError(f"method='exact' would take about {est:.0f} s here ({n} engine columns, cost measured "
                         f"on the first few), beyond EXACT_TIME_LIMIT = {EXACT_TIME_LIMIT:g} s: use "
                         f"method='selinv' (certified, a few factorizations) or 'probing' (measured error), or "
                         f"raise spectral_igl.diagonal.core.EXACT_TIME_LIMIT")


def _diagonal(lap, filt, method, delta, k, distance, samples, rtol, max_colours, tol, engine_method, seed,
              progress=None):
    n = lap.n
    auto = method == "auto"
    if auto:
        method = "selinv" if selinv_supported(lap, filt, delta) else ("dense" if n <= EXACT_MAX else "probing")
        log.info("kernel_diagonal: auto chose %r for %r (n=%d)", method, filt, n)
    info = {"method": method, "applications": 0, "k": 0, "distance": None, "colours": None,
            "bound_kind": None}
    dtype = np.complex128 if filt.is_complex else np.float64

    if method == "dense":
        info["k"] = n
        diag = eigen_diagonal(lap, filt, None, delta)
        return diag, _bounded(info, _dense_rounding(lap, filt, delta), "estimate",
                              "dense eigendecomposition: exact up to the eigensolver's rounding, "
                              "bounded by a model (not a proof)")

    if method == "eigen":
        k = max(1, min(100 if k is None else int(k), n))
        info["k"] = k
        return eigen_diagonal(lap, filt, k, delta), _bounded(
            info, np.full(n, np.nan), None, f"truncated eigen-expansion ({k} pairs): no error bound")

    if method in ("auto", "selinv") and heat_projection_applies(lap, filt):
        # heat at a large time is the projection onto the constants of each component:
        # |G_ii - 1/V_c| = sum_{l > c} e^{-t lambda_l} x_l(i)^2 <= e^{-t lambda_2} (B^-1)_ii
        decay = float(np.exp(-filt.params["t"] * lambda_min_positive(lap)))
        minv = inverse_mass_diagonal(lap)
        vol = lap.component_volume()
        if decay * float(np.max(minv * vol)) <= tol:
            diag, bound = 1.0 / vol, decay * minv + reciprocal_rounding(lap) / vol
            if delta == "seed":
                # m^2 / V: the row sums m_i of B rounded too, and two products
                row = mass_sum_rounding(lap)[0]
                grow = (1.0 + row) ** 2 * (1.0 + gamma(2)) - 1.0
                diag, bound = diag * lap.mass ** 2, (bound * (1.0 + grow) + grow * diag) * lap.mass ** 2
            info["method"] = "projection"
            return diag, _bounded(info, bound, lambda_min_positive_kind(lap))

    if method == "selinv":
        if not selinv_supported(lap, filt, delta):
            raise ValueError("method='selinv' needs the compiled extension, a real filter, "
                             "and a lumped mass for delta='seed'")
        samples = int(min(max(samples, 0), n))
        rng = np.random.default_rng(seed)
        idx = np.sort(rng.choice(n, samples, replace=False))
        E = np.zeros((n, samples))
        E[idx, np.arange(samples)] = 1.0
        if delta == "seed":
            E *= lap.mass[:, None]
        try:
            kern = selinv_kernel(lap, filt, tol)
            if samples:
                kern.prime(E)          # checked with the same factors, in the same pass
            diag, bound = kern.diagonal(progress)
        except NoSelinv as exc:
            if not auto:
                raise ValueError(f"method='selinv' cannot handle {filt.name!r}: {exc}; use 'probing'") from None
            fallback = "dense" if n <= EXACT_MAX else "probing"
            log.info("kernel_diagonal: selinv cannot handle %r (%s); using %r", filt, exc, fallback)
            return _diagonal(lap, filt, fallback, delta, k, distance, samples, rtol, max_colours, tol,
                             engine_method, seed, progress)
        if delta == "seed":       # diag(B G B) = m^2 G_ii for a lumped mass
            diag, bound = diag * lap.mass ** 2, bound * lap.mass ** 2
        info["factorizations"] = kern.n_factorizations
        _bounded(info, bound, kern.bound_kind)
        if samples:     # the selected inversion against solves with the same factors
            exact = kern.columns(E)[idx, np.arange(samples)]
            if delta == "seed":
                exact *= lap.mass[idx]
            err = np.abs(diag[idx] - exact)
            info.update(samples=idx, sample_abs_error=float(err.max()),
                        sample_rel_error=float(np.max(err / np.maximum(np.abs(exact), np.finfo(float).tiny))))
        return diag, info

    op = spectral_operator(lap, filt, engine_method, tol)
    G = _gram_apply(lap, op, delta)
    if method == "exact":
        _check_exact_cost(G, n, dtype)
        diag = np.empty(n, dtype=dtype)
        bound = np.zeros(n)
        w = column_entry_error(lap, 1.0, delta)     # entry i of column i per unit B-norm error
        bar = progress_bar(-(-n // BLOCK), "kernel diagonal", progress, unit="block")
        for a in range(0, n, BLOCK):
            idx = np.arange(a, min(a + BLOCK, n))
            E = np.zeros((n, idx.size))
            E[idx, np.arange(idx.size)] = 1.0
            Y = G(E)
            diag[idx] = Y[idx, np.arange(idx.size)]
            eb = np.asarray(op.error_bound if op.error_bound is not None else np.nan, dtype=float).reshape(-1)
            bound[idx] = w[idx] * eb
            bar.update()
        bar.close()
        info["applications"] = n
        kind = weakest(op.bound_kind, lambda_max_kind(lap)) if np.all(np.isfinite(bound)) else None
        return diag, _bounded(info, bound, kind)

    diag, pinfo = probing_diagonal(lap, filt, G, delta, k, distance, samples, rtol, max_colours, seed,
                                   dtype, block=BLOCK, progress=progress)
    info.update(pinfo)
    if "sample_abs_error" not in info:
        return diag, _bounded(info, np.full(n, np.nan), None,
                              "probing without sample vertices: the error is not measured")
    # measured at the samples, not bounded: the largest absolute or relative sample error,
    # whichever is larger at a vertex, times a safety factor
    est = PROBING_SAFETY * np.maximum(info["sample_abs_error"], info["sample_rel_error"] * np.abs(diag))
    return diag, _bounded(info, est, "estimate",
                          f"probing: the error is measured at {info['samples'].size} sample vertices "
                          f"and scaled by {PROBING_SAFETY:g}, not bounded")
