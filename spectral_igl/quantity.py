"""One place that turns (quantity, filter, t, method, source) into values on the vertices.

Used by the command line and the interactive viewer; the names it accepts come from the
registries :data:`spectral_igl.filters.FILTERS`, :data:`spectral_igl.approx.METHODS` and
:data:`spectral_igl.diagonal.METHODS`.
"""
from __future__ import annotations

import time

import numpy as np

from ._validate import as_index, as_int
from .distances import MAX_ORDER, spectral_distance
from .filters import FILTERS, by_name
from .kernels import spectral_kernel
from .laplacian import as_laplacian
from .laplacian.units import optional_time, time_label

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
    """Values on the vertices with their error bounds (:mod:`spectral_igl.accuracy`) and the
    wall time.

    Attributes
    ----------
    values : (n,) float
    abs_error : (n,) float
        A bound of :math:`|\text{exact} - \text{returned}|` at every vertex (``nan`` where
        there is none).
    error_bound : float or None
        The largest ``abs_error``; ``None`` without a bound.
    bound_kind : {"proof", "estimate"} or None
    method : str or None
        The method that produced the values.
    seconds : float
    label : str
    """

    def __init__(self, values, abs_error, seconds, label, bound_kind=None, method=None):
        self.values = values
        self.abs_error = np.broadcast_to(np.asarray(abs_error, dtype=float), values.shape)
        finite = self.abs_error.size and np.all(np.isfinite(self.abs_error))
        self.error_bound = float(np.max(self.abs_error)) if finite else None
        self.bound_kind = bound_kind if finite else None
        self.method = method
        self.seconds = seconds
        self.label = label

    def __repr__(self):
        return (f"Evaluation({self.label}, n={self.values.shape[0]}, "
                f"error_bound={self.error_bound}, seconds={self.seconds:.3g})")


def evaluate(lap, quantity: str, source: int, filter: str = "heat", t: float | None = None,
             method: str = "auto", tol: float = 1e-8, order: int = 3,
             diagonal: str = "auto", time_unit: str = "absolute") -> Evaluation:
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
        Time/scale of the filters that take one, in the units ``time_unit``.
    time_unit : str
        ``"absolute"`` (default), ``"shape"``, ``"area"``, ``"volume"`` or ``"h2"``
        (:mod:`spectral_igl.laplacian.units`); the label shows both the relative and the
        absolute time.
    method, tol
        Passed to the spectrum-free engine.
    diagonal : str
        One of :data:`spectral_igl.diagonal.METHODS`.
        How a one-to-all distance obtains the kernel diagonal
        (:func:`spectral_igl.spectral_distance`).

    Returns
    -------
    Evaluation
        ``values`` (n,) float (the real part for the complex wave filter), ``abs_error`` (a
        bound of every entry's error, from the kernel's or the distance's ``info``),
        ``error_bound`` (its largest entry; ``None`` when the method gives no bound),
        ``bound_kind`` (``"proof"``, ``"estimate"``, or ``None`` without a bound), ``method``,
        ``seconds``.
    """
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {QUANTITIES}, got {quantity!r}")
    lap = as_laplacian(lap)
    given = t
    t = optional_time(lap, t, time_unit)
    source = as_index(source, lap.n, "source")
    order = as_int(order, "order", lo=1, hi=MAX_ORDER)
    if quantity == "geodesic":
        from .applications.geodesics import geodesic_distance

        start = time.perf_counter()
        values = np.asarray(geodesic_distance(lap, source), dtype=float).ravel()
        return Evaluation(values, np.nan, time.perf_counter() - start, "geodesic distance (heat method)",
                          method="heat method")
    filt = by_name(filter, t, order)
    label = f"{filter} {quantity}" + (f", {time_label(given, t, time_unit)}" if FILTERS[filter][1] else "")
    start = time.perf_counter()
    if quantity == "kernel":
        values, info = spectral_kernel(lap, filt, source, method=method, tol=tol, return_info=True)
        values = np.real(values)     # |Re e| <= |e|: the bound of the complex entry holds
    else:
        values, info = spectral_distance(lap, filt, source, method=method, tol=tol, diagonal=diagonal,
                                         return_info=True)
    seconds = time.perf_counter() - start
    return Evaluation(np.asarray(values, dtype=float).ravel(), info["abs_error"], seconds, label,
                      info["bound_kind"], info["method"])
