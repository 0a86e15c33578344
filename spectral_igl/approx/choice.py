"""Which method evaluates a filter: the registry of plans, ``"auto"``'s choice, and the
settings each method reads."""
from __future__ import annotations

import logging

import numpy as np

from .._validate import as_int, as_positive
from ..filters import Filter
from ..laplacian import Laplacian, lambda_max
from ..linalg import lambda_min_positive
from .contour import ContourPlan, GaussLegendrePlan
from .krylov import KrylovPlan, ShiftInvertPlan
from .polynomial import ChebyshevPlan, EulerPlan, PowerPlan, Taylor1Plan, TaylorPlan
from .rational import RationalPlan, certifiable
from .spectral import DensePlan, EigenPlan

__all__ = ["PLANS", "METHODS", "HEAT_ONLY", "LARGE_T", "PROOF_PREMIUM", "choose_method", "OPTIONS",
           "check_engine_options"]

log = logging.getLogger(__name__)

#: method name -> the plan class that builds its scalar approximation
PLANS = {
    "dense": DensePlan,
    "eigen": EigenPlan,
    "euler": EulerPlan,
    "taylor1": Taylor1Plan,
    "power": PowerPlan,
    "krylov": KrylovPlan,
    "shift_invert": ShiftInvertPlan,
    "taylor": TaylorPlan,
    "chebyshev": ChebyshevPlan,
    "rational": RationalPlan,
    "contour": ContourPlan,
    "gauss_legendre": GaussLegendrePlan,
}
#: The engine's method names, read by every entry point, the command line and the viewer.
METHODS = ("auto",) + tuple(PLANS)
#: Methods that approximate the heat filter only.
HEAT_ONLY = ("euler", "taylor1", "power", "contour")
#: above this t * lambda_max, decaying filters (heat, Mexican hat) are approximated on
#: [lambda_min_positive, lambda_max] (one more factorization, cached), and dropped where
#: they are below tol/2 there; below it, on [0, lambda_max]
LARGE_T = 1e6


#: how much more ``auto`` pays for a method that proves its bound over one that estimates it
PROOF_PREMIUM = 4.0


def choose_method(lap: Laplacian, filt: Filter, tol: float = 1e-8) -> str:
    """The method ``"auto"`` uses for this Laplacian, filter and tolerance.

    - heat: ``"rational"`` (Carathéodory--Fejér poles with a proved bound at every t; on the
      43k-vertex armadillo at tol 1e-8 a first column costs 1.6--3.7 Cholesky and a second one
      0.24--0.35, against 1.7--4.3 and 0.54--0.85 for ``"shift_invert"``, whose Lanczos bound is
      only an estimate from t = 1e-5 on there);
    - a user filter (whose error no method can prove) on a tiny problem (n <= 300): ``"dense"``;
    - :math:`s^{-k/2}` (biharmonic, commute-time, poly-harmonic): ``"rational"`` (exact
      pseudo-solves, plus a real-pole rational fit of :math:`s^{-1/2}` for odd k);
    - wave: ``"chebyshev"``, or ``"rational"`` (an AAA fit, proved) where the Chebyshev series
      would need more than 20,000 steps and the fit reaches ``tol``;
    - any other filter: of ``"chebyshev"`` and ``"shift_invert"``, those that reach ``tol`` (both
      if neither does), the cheaper by a cost model in units of one solve (a factorization counts
      as 25 solves, a lumped-mass Chebyshev step as 0.2), unless only the other one proves its
      bound and costs at most :data:`PROOF_PREMIUM` times as much.
    """
    if filt.kind == "heat":
        return "rational"
    if lap.n <= 300 and not certifiable(filt):
        return "dense"
    if filt.kind == "power":
        return "rational"
    if filt.kind == "wave":
        return _wave_method(lap, filt, tol)
    a = lambda_min_positive(lap) if filt.singular else 0.0
    b = lambda_max(lap)
    try:
        si = ShiftInvertPlan(lap, filt, a, b, tol)
        cost_si, proved_si = 25.0 + si.m, si.proved and si.scalar_error <= tol
    except (ValueError, RuntimeError, ArithmeticError) as exc:  # pragma: no cover - defensive
        log.debug("shift_invert not usable for %r: %s", filt, exc)
        cost_si, proved_si = np.inf, False
    ch = ChebyshevPlan(lap, filt, a, b, tol, max_degree=20000)
    cost_ch = (0.0 if lap.lumped else 25.0) + ch.m * (0.2 if lap.lumped else 1.0)
    proved_ch = getattr(ch, "proved", False) and ch.scalar_error <= tol
    # only methods that reach tol (if any does); among them the cheapest, or one that proves its
    # bound for at most PROOF_PREMIUM times the cost
    cands = [(cost_ch, proved_ch, ch.scalar_error <= tol, "chebyshev"),
             (cost_si, proved_si, np.isfinite(cost_si) and si.scalar_error <= tol, "shift_invert")]
    cands = sorted(c for c in cands if c[2]) or sorted(cands)
    cheap = cands[0]
    proving = [c for c in cands if c[1] and c[0] <= PROOF_PREMIUM * cheap[0]]
    return (proving[0] if proving and not cheap[1] else cheap)[3]


def _wave_method(lap, filt, tol):
    """``"chebyshev"`` when its series reaches tol within 20,000 steps (t * lambda_max up to about
    1e4), else the rational (AAA) fit where that reaches tol, else ``"chebyshev"`` (which then
    reports the bound it reaches)."""
    b = lambda_max(lap)
    if ChebyshevPlan(lap, filt, 0.0, b, tol, max_degree=20000).scalar_error <= tol:
        return "chebyshev"
    try:
        rat = RationalPlan(lap, filt, 0.0, b, tol)
    except (ValueError, RuntimeError, ArithmeticError) as exc:
        log.debug("rational not usable for %r: %s", filt, exc)
        return "chebyshev"
    return "rational" if rat.scalar_error + rat.rounding <= tol else "chebyshev"


#: the method settings :class:`SpectralOperator` takes: name -> (methods that read it, range)
OPTIONS = {
    "k": (("eigen",), (1, None)),
    "max_n": (("dense",), (1, None)),
    "steps": (("euler", "krylov", "shift_invert"), (1, 100000)),
    "max_steps": (("krylov", "shift_invert"), (1, 100000)),
    "degree": (("taylor", "chebyshev", "rational", "power"), (0, 100000)),
    "max_degree": (("taylor", "chebyshev"), (1, 1000000)),
    "squarings": (("power",), (0, 60)),
    "max_solves": (("power",), (1, 10000000)),
    "nodes": (("contour", "gauss_legendre"), (1, 4096)),
    "shift": (("shift_invert",), None),
}


def check_engine_options(method: str, options: dict, n: int) -> dict:
    """Validate method settings before any work: known names, read by ``method``, in range.

    ``method="auto"`` accepts none (the method it picks is not known in advance).
    """
    out = {}
    for name, value in options.items():
        if name not in OPTIONS:
            raise TypeError(f"unknown engine option {name!r}; the options are {sorted(OPTIONS)}")
        methods, rng = OPTIONS[name]
        if method not in methods:
            raise ValueError(f"option {name}={value!r} is not used by method {method!r} (it applies to "
                             f"{', '.join(methods)}); remove it or choose one of those methods")
        if value is None:
            out[name] = None
        elif rng is None:
            out[name] = as_positive(value, name)
        else:
            hi = rng[1] if name != "k" else n
            out[name] = as_int(value, name, lo=rng[0], hi=hi)
    return out
