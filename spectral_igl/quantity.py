"""One place that turns (quantity, filter, t, method, source) into values on the vertices.

Used by the command line and the interactive viewer; the names it accepts come from the
registries :data:`spectral_igl.filters.FILTERS`, :data:`spectral_igl.approx.METHODS` and
:data:`spectral_igl.diagonal.METHODS`.
"""
from __future__ import annotations

import time

import numpy as np

from ._validate import as_index, as_int
from .approx import spectral_operator
from .distances import MAX_ORDER, spectral_distance
from .filters import FILTERS, by_name

__all__ = ["QUANTITIES", "FILTERED", "evaluate", "Evaluation", "uses_time", "color_meaning"]

#: what :func:`evaluate` computes
QUANTITIES = ("kernel", "distance", "geodesic")
#: quantities whose value depends on the spectral filter (the geodesic distance does not)
FILTERED = ("kernel", "distance")
#: filters whose kernels are non-negative quantities (their rare small negative values are
#: discretisation artefacts, drawn at the low end of a sequential scale)
POSITIVE_KERNELS = ("heat", "diffusion")


def color_meaning(quantity: str, filter: str) -> str:
    """The colour reading of a picture: ``"sequential"`` or ``"auto"`` (diverging if signed).

    Distances and heat kernels are non-negative quantities; the other kernels (biharmonic,
    commute time, wave, Mexican hat) take both signs.

    Examples
    --------
    >>> color_meaning("distance", "biharmonic"), color_meaning("kernel", "biharmonic")
    ('sequential', 'auto')
    """
    if quantity != "kernel" or filter in POSITIVE_KERNELS:
        return "sequential"
    return "auto"


def uses_time(quantity: str, filter: str) -> bool:
    """Whether the picture of ``quantity`` with ``filter`` depends on a time/scale t.

    Examples
    --------
    >>> uses_time("kernel", "heat"), uses_time("kernel", "biharmonic"), uses_time("geodesic", "heat")
    (True, False, False)
    """
    return quantity in FILTERED and filter in FILTERS and bool(FILTERS[filter][1])


class Evaluation:
    """Values on the vertices with the certified error bound and the wall time."""

    def __init__(self, values, error_bound, seconds, label, bound_kind=None):
        self.values = values
        self.error_bound = error_bound
        self.bound_kind = bound_kind
        self.seconds = seconds
        self.label = label

    def __repr__(self):
        return (f"Evaluation({self.label}, n={self.values.shape[0]}, "
                f"error_bound={self.error_bound}, seconds={self.seconds:.3g})")


def _bound(x):
    if x is None:
        return None
    x = np.asarray(x, dtype=float)
    return float(np.max(x)) if x.size else None


def evaluate(lap, quantity: str, source: int, filter: str = "heat", t: float | None = None,
             method: str = "auto", tol: float = 1e-8, order: int = 3,
             diagonal: str = "auto") -> Evaluation:
    r"""Kernel column or distance from one vertex.

    Parameters
    ----------
    lap : Laplacian
    quantity : {"kernel", "distance", "geodesic"}
        ``"kernel"``: :math:`K(\cdot, i) = \varphi(\tilde L) B^{-1} e_i`;
        ``"distance"``: :math:`d(i, \cdot)`, the spectral distance of :math:`\varphi`;
        ``"geodesic"``: the geodesic distance by the heat method (``filter`` and ``t`` are
        not used).
    source : int
        Vertex ``i``.
    filter : str
        A name in :data:`spectral_igl.filters.FILTERS`.
    t : float, optional
        Time/scale of the filters that take one.
    method, tol
        Passed to the spectrum-free engine.
    diagonal : str
        One of :data:`spectral_igl.diagonal.METHODS`.
        How a one-to-all distance obtains the kernel diagonal
        (:func:`spectral_igl.spectral_distance`).

    Returns
    -------
    Evaluation
        ``values`` (n,) float (the real part for the complex wave filter), ``error_bound``
        (absolute: in the B-norm for a kernel column, the largest bound on
        :math:`|d_j - \tilde d_j|` for distances; ``None`` when the method gives none),
        ``seconds``, ``bound_kind`` (``"proof"``, ``"estimate"``, or ``None`` without a bound).
    """
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {QUANTITIES}, got {quantity!r}")
    source = as_index(source, lap.n, "source")
    order = as_int(order, "order", lo=1, hi=MAX_ORDER)
    if quantity == "geodesic":
        from .applications.geodesics import geodesic_distance

        start = time.perf_counter()
        values = np.asarray(geodesic_distance(lap, source), dtype=float).ravel()
        return Evaluation(values, None, time.perf_counter() - start, "geodesic distance (heat method)")
    filt = by_name(filter, t, order)
    label = f"{filter} {quantity}" + (f", t={t:g}" if FILTERS[filter][1] else "")
    start = time.perf_counter()
    if quantity == "kernel":
        op = spectral_operator(lap, filt, method=method, tol=tol)
        e = np.zeros(lap.n)
        e[source] = 1.0
        values = op.apply_inverse_mass(e)
        bound = _bound(op.error_bound)
        kind = op.bound_kind if bound is not None else None
        values = np.real(values) if np.iscomplexobj(values) else values
    else:
        values, bound, kind = _distance(lap, filt, source, method, tol, diagonal)
    seconds = time.perf_counter() - start
    return Evaluation(np.asarray(values, dtype=float).ravel(), bound, seconds, label, kind)


def _distance(lap, filt, source, method, tol, diagonal="auto"):
    """Distances from ``source``, a bound on each |d - d~| (``None`` when there is none) and its kind.

    For non-negative d, d~: ``|d - d~| = |d^2 - d~^2| / (d + d~) <= min(sqrt(e), e / d~)``
    with ``e`` the bound on the squared distances.
    """
    out, info = spectral_distance(lap, filt, source, method=method, tol=tol, diagonal=diagonal,
                                  return_info=True)
    out = np.asarray(out)
    e = info.get("d2_error_bound")
    if e is None or not np.isfinite(e):
        return out, None, None
    d = np.delete(np.abs(out), source)
    per = np.minimum(np.sqrt(e), e / np.maximum(d, np.finfo(float).tiny))
    return out, float(per.max(initial=0.0)), info.get("bound_kind", "estimate")
