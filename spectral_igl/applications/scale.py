"""Selection of the diffusion time scale (survey §5.4): risk minimum and L-curve corner."""
from __future__ import annotations

import numpy as np

from .._validate import as_array, as_choice, as_int, as_signal, as_tol, describe
from ..approx import METHODS
from ..approx import apply_filter
from ..filters import heat
from ..laplacian import as_laplacian, lambda_max
from ..linalg import eigs

__all__ = ["optimal_time", "MAX_TIMES"]

#: most times :func:`optimal_time` tries (each costs one heat evaluation of 1 + probes columns)
MAX_TIMES = 1000


def _curvature(x, y, s):
    dx, dy = np.gradient(x, s), np.gradient(y, s)
    ddx, ddy = np.gradient(dx, s), np.gradient(dy, s)
    return (dx * ddy - dy * ddx) / np.maximum(dx ** 2 + dy ** 2, 1e-300) ** 1.5


def _corner(k):
    """First local curvature maximum (> 0, >= a quarter of the largest), ends excluded."""
    inner = k[2:-2]
    top = inner.max()
    peak = (inner[1:-1] > inner[:-2]) & (inner[1:-1] >= inner[2:]) & (inner[1:-1] > 0.25 * top)
    loc = np.flatnonzero(peak & (inner[1:-1] > 0)) + 3
    if loc.size:
        return int(loc[0]), True
    return int(np.argmax(inner)) + 2, False


def _noise_variance(ts, res2, T, t_max):
    r"""Per-vertex noise variance from the smallest times.

    Fits :math:`\rho^2(t) \approx \sigma^2 T(t) + \beta t^2` (non-negative, relative least
    squares) for :math:`t \le` ``t_max``: white noise fills the whole spectrum, so its
    residual :math:`T(t) = E\|(I - S_t)n\|_M^2 / \sigma^2` saturates at
    :math:`t \approx 1/\lambda_{\max}`, while a smooth signal's residual still grows like
    :math:`t^2\|\tilde L f\|^2`. The two shapes separate the two parts.
    """
    from scipy.optimize import nnls

    sel = ts <= t_max
    if sel.sum() < 3:
        sel = np.zeros(ts.size, dtype=bool)
        sel[:3] = True
    w = 1.0 / np.maximum(res2[sel], np.finfo(float).tiny)
    A = np.c_[T[sel] * w, ts[sel] ** 2 * w]
    return float(nnls(A, np.ones(sel.sum()))[0][0])


def optimal_time(lap, f, ts=None, n_times: int = 48, rule: str = "risk", probes: int = 16,
                 seed: int = 0, method: str = "auto", tol: float = 1e-8):
    r"""Diffusion time that best separates a smooth signal from white noise.

    For :math:`F(t) = S_t f = e^{-t\tilde L} f` the residual
    :math:`\rho(t) = \|F(t) - f\|` grows with ``t`` while the energy
    :math:`\eta(t) = \sqrt{F^\top L F}` falls; the survey (§5.4) takes the corner of the
    L-curve :math:`(\log\rho, \log\eta)`.

    ``rule="risk"`` (default) minimises Stein's unbiased estimate of the error to the
    clean signal for per-vertex white noise of variance :math:`\sigma^2`
    (:math:`M = \mathrm{diag}(m)`, :math:`m = B\mathbf 1`):

    .. math:: \hat R(t) = \|(I - S_t) f\|_M^2 - \sigma^2 \operatorname{tr} M
              + 2\sigma^2 \operatorname{tr}(M S_t)

    with :math:`\operatorname{tr}(M S_t)` estimated by Hutchinson's method (``probes``
    Rademacher vectors diffused with ``f``) and :math:`\sigma^2` fitted from the
    residual at the smallest times, where the noise has been removed but a smooth
    signal has not. Neither needs a spectrum.

    Parameters
    ----------
    lap : Laplacian
    f : (n,) float
        Noisy function.
    ts : (k,) float, optional
        Times to try, increasing. Default: ``n_times`` log-spaced values in
        :math:`[0.01/\lambda_{\max}, 1/\lambda_2]` for ``"risk"`` (which needs the
        smallest times to measure the noise), :math:`[1/\lambda_{\max}, 1/\lambda_2]` for
        ``"lcurve"``; above :math:`1/\lambda_2` the smoothest non-constant mode is gone.
    rule : {"risk", "lcurve"}
        ``"risk"``: the minimum of :math:`\hat R`. ``"lcurve"``: the first marked
        curvature peak of the Dirichlet L-curve (else of the norm L-curve,
        :math:`\eta = \|F - \bar f\|_B`).
    probes : int
        Hutchinson vectors for ``"risk"``.
    seed : int
        Seed of the probes.
    method, tol
        Passed to :func:`spectral_igl.apply_filter` for each time; ``"auto"`` is
        ``"chebyshev"`` here, the cheapest for a block of ``1 + probes`` columns.

    Returns
    -------
    t : float
        The chosen time.
    curve : dict
        ``"t"``, ``"residual"`` (:math:`\rho`, B-norm), ``"energy"`` (:math:`\eta`),
        ``"curvature"`` (of the L-curve), ``"risk"`` (:math:`\hat R`, nan for
        ``"lcurve"``) and ``"noise"`` (the fitted :math:`\sigma`), one entry per time.

    Notes
    -----
    Why not the L-curve corner by default: white noise fills the whole spectrum, so the
    L-curve of heat smoothing has no sharp corner where the noise is gone; its sharpest
    corner is where the signal's own modes are lost, past the best time for any signal
    with content above the lowest modes (and for a degree-1 signal with little noise the
    corner sits at :math:`1/\lambda_2`). Measured with the criterion "smaller error to
    the clean signal than at t/10 and at 10 t" (``benchmarks/optimal_time.py --quick``:
    icosphere(3) and a 9x9x9 tet box, full and lumped mass, signals of degree 1 to 8 and
    a bump, noise 3% to 100%), ``"risk"`` meets it in 59 of 72 cases, ``"lcurve"`` in 29.
    All 13 misses of ``"risk"`` are signals of degree >= 5 with 3% or 10% noise, whose
    best time is below :math:`1/\lambda_{\max}`: there the signal is about as rough as
    the mesh, hardly separable from the noise, and the gain of any smoothing is small.
    Cost: one heat evaluation of ``1 + probes`` columns per time.
        """

    lap = as_laplacian(lap)
    f = as_signal(f, lap.n, "f", allow_complex=False)
    if f.ndim != 1:
        raise ValueError(f"f must have shape ({lap.n},), got shape {f.shape}")
    if rule not in ("risk", "lcurve"):
        raise ValueError(f"rule must be 'risk' or 'lcurve', got {rule!r}")
    probes = as_int(probes, "probes", lo=1, hi=4096)
    n_times = as_int(n_times, "n_times", lo=7, hi=MAX_TIMES)
    seed = as_int(seed, "seed", lo=0)
    as_choice(method, "method", METHODS)
    tol = as_tol(tol, "tol")
    Z = lap.component_basis()
    g = f - Z @ (Z.T @ (lap.B @ f))
    if not np.sqrt(max(g @ (lap.B @ g), 0.0)) > 1e-12 * np.sqrt(max(f @ (lap.B @ f), 0.0)):
        raise ValueError("f is constant on every connected component (e.g. zero): diffusion does not "
                         "change it, so there is no time to choose")
    lmax = float(lambda_max(lap))
    if ts is None:
        lam = np.asarray(eigs(lap, lap.n_components + 1)[0])
        lo = (0.01 if rule == "risk" else 1.0) / lmax
        hi = 1.0 / float(lam[lap.n_components])
        ts = np.logspace(np.log10(lo), np.log10(max(hi, 1000 * lo)), int(n_times))
    ts = as_array(ts, "ts")
    if ts.dtype.kind not in "biuf":
        raise TypeError(f"ts must be real times, got {describe(ts)}")
    ts = ts.astype(float)
    if ts.ndim != 1 or ts.size < 7 or not np.all(np.isfinite(ts)) or np.any(ts <= 0) \
            or np.any(np.diff(ts) <= 0):
        raise ValueError(f"ts must be at least 7 increasing positive times, got {ts.size} values")
    if ts.size > MAX_TIMES:
        raise ValueError(f"ts has {ts.size} times, more than {MAX_TIMES} (one heat evaluation each)")
    m = lap.mass
    Z = lap.component_basis()
    mean = Z @ (Z.T @ (lap.B @ f))
    k = int(probes) if rule == "risk" else 0
    P = np.random.default_rng(seed).choice([-1.0, 1.0], size=(lap.n, k))
    X = np.c_[f, P]
    n_t = ts.size
    if method == "auto":
        method = "chebyshev"
    R, ED, EN, RM2, TMS, TRES = (np.empty(n_t) for _ in range(6))
    for i, t in enumerate(ts):
        Y = np.real(apply_filter(lap, heat(t), X, method=method, tol=tol))
        F = Y[:, 0]
        d = F - f
        R[i] = np.sqrt(max(d @ (lap.B @ d), 0.0))
        ED[i] = np.sqrt(max(F @ (lap.L @ F), 0.0))
        g = F - mean
        EN[i] = np.sqrt(max(g @ (lap.B @ g), 0.0))
        RM2[i] = float(m @ d ** 2)
        if k:
            S = Y[:, 1:]
            TMS[i] = float(np.mean(np.einsum("ij,ij->j", P, m[:, None] * S)))
            TRES[i] = float(np.mean(m @ (P - S) ** 2))
    tiny = np.finfo(float).tiny
    x, s = np.log(np.maximum(R, tiny)), np.log(ts)
    # the Dirichlet curve turns counter-clockwise at its corner, the norm curve clockwise
    kd = _curvature(x, np.log(np.maximum(ED, tiny)), s)
    kn = -_curvature(x, np.log(np.maximum(EN, tiny)), s)
    i_d, found = _corner(kd)
    curv = kd if found else kn
    risk = np.full(n_t, np.nan)
    sigma2 = np.nan
    if rule == "risk":
        sigma2 = _noise_variance(ts, RM2, TRES, 2.0 / lmax)
        risk = RM2 - sigma2 * m.sum() + 2.0 * sigma2 * TMS
        i = int(np.argmin(risk))
    else:
        i = i_d if found else _corner(kn)[0]
    curve = {"t": ts, "residual": R, "energy": ED if found else EN, "curvature": curv,
             "risk": risk, "noise": np.sqrt(sigma2)}
    return float(ts[i]), curve
