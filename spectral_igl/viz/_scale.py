"""Colour scales: linear or logarithmic, and colour-bar ticks that read.

Only numpy at import time; matplotlib's tick locators are imported when ticks are chosen.
"""
from __future__ import annotations

import numpy as np

__all__ = ["LOG_RATIO", "SCALES", "use_log_scale", "colour_ticks", "distinct_format", "apply_ticks"]

#: positive data whose largest value exceeds the smallest by more than this factor (two
#: decades) is drawn on a logarithmic colour scale by default
LOG_RATIO = 100.0
#: colour scales of :func:`spectral_igl.viz.plot_levelsets`
SCALES = ("auto", "linear", "log")


def use_log_scale(values, scale="auto", kind="sequential") -> bool:
    """Whether ``values`` are drawn on a logarithmic colour scale.

    ``scale="auto"``: when the colours are sequential and every finite value is positive
    with ``max / min > LOG_RATIO`` (a descriptor or kernel spanning decades; on a linear
    scale all but its largest values would share one colour). Distances (zero at the
    source) and signed values stay linear. ``"log"`` asks for it (refused unless some value is
    positive); ``"linear"`` never.

    Examples
    --------
    >>> use_log_scale([1e-3, 1e-2, 1.0]), use_log_scale([0.0, 1.0, 5e3]), use_log_scale([42.5, 42.6])
    (True, False, False)
    """
    if scale not in SCALES:
        raise ValueError(f"scale must be one of {SCALES}, got {scale!r}")
    if scale == "linear":
        return False
    v = np.asarray(values, dtype=float).ravel()
    v = v[np.isfinite(v)]
    if scale == "log":
        if not np.any(v > 0):
            raise ValueError("scale='log' needs positive values; none of the drawn values is")
        return True
    if kind != "sequential" or v.size == 0 or v.min() <= 0:
        return False
    return bool(v.max() > LOG_RATIO * v.min())


def colour_ticks(lo: float, hi: float, log: bool = False, max_ticks: int = 5):
    """Tick values inside ``[lo, hi]`` and a printf format under which their labels differ.

    Linear: round values (steps 1, 2, 2.5 or 5 times a power of ten), as many significant
    digits as the step needs -- a range 42.50 to 42.62 is labelled 42.5, 42.55, 42.6, not
    42.5, 42.6, 42.6. Logarithmic: the powers of ten inside the range (with their 2 and 5
    multiples when the range spans less than two decades). The ends of the range are added
    when fewer than two round values fall inside it.

    Parameters
    ----------
    lo, hi : float
        The colour range (``0 < lo`` for ``log``).
    log : bool
    max_ticks : int

    Returns
    -------
    ticks : (k,) float
    fmt : str
        A ``%``-format (``"%.3g"``, ...) under which every two ticks print differently.

    Examples
    --------
    >>> t, fmt = colour_ticks(42.5, 42.62)
    >>> [fmt % x for x in t]
    ['42.5', '42.55', '42.6']
    >>> t, fmt = colour_ticks(1e-4, 3e-2, log=True)
    >>> [fmt % x for x in t]
    ['0.0001', '0.001', '0.01']
    """
    from matplotlib import ticker

    lo, hi = float(lo), float(hi)
    if not (np.isfinite(lo) and np.isfinite(hi)) or hi <= lo:
        return np.array([lo]), "%.4g"
    if log:
        if lo <= 0:
            raise ValueError(f"a logarithmic scale needs a positive range, got [{lo:g}, {hi:g}]")
        decades = np.log10(hi / lo)
        subs = (1.0,) if decades >= 2 else ((1.0, 2.0, 5.0) if decades >= 0.7 else (1.0, 1.5, 2, 3, 5, 7))
        ticks = ticker.LogLocator(base=10.0, subs=subs, numticks=max_ticks + 2).tick_values(lo, hi)
    else:
        ticks = ticker.MaxNLocator(nbins=max_ticks - 1, steps=[1, 2, 2.5, 5, 10]).tick_values(lo, hi)
    eps = 1e-9 * (hi - lo)
    ticks = np.asarray([x for x in ticks if lo - eps <= x <= hi + eps], dtype=float)
    if ticks.size > max_ticks:  # thin out evenly, keeping the first
        ticks = ticks[::int(np.ceil(ticks.size / max_ticks))]
    if ticks.size < 2:
        ticks = np.unique(np.concatenate([[lo], ticks, [hi]]))
    fmt = distinct_format(ticks)
    if int(fmt[2:-1]) > 6 and ticks.size > 2:  # long labels (a nearly constant value): two of them
        ticks = ticks[[0, -1]]
        fmt = distinct_format(ticks)
    return ticks, fmt


def distinct_format(values, least: int = 1, most: int = 15) -> str:
    """The shortest ``"%.{p}g"`` (``least <= p <= most``) under which ``values`` print
    differently and each label reads back as its value (to a millionth of the smallest gap).

    Examples
    --------
    >>> distinct_format([42.5, 42.55, 42.6]), distinct_format([0.0, 0.25, 0.5])
    ('%.4g', '%.2g')
    """
    values = np.unique(np.asarray(values, dtype=float))
    big = float(np.max(np.abs(values))) if values.size else 0.0
    if 1.0 <= big < 1e5:  # whole numbers in full (10, 20, 30), not 1e+01, 2e+01, 3e+01
        least = max(least, int(np.floor(np.log10(big))) + 1)
    gap = float(np.min(np.diff(values))) if values.size > 1 else abs(float(values[0])) if values.size else 1.0
    tol = max(1e-6 * (gap or 1.0), 8.0 * np.finfo(float).eps * big)  # no finer than the floats
    for p in range(least, most + 1):
        fmt = f"%.{p}g"
        labels = [fmt % x for x in values]
        if len(set(labels)) == len(labels) and all(abs(float(t) - x) <= tol for t, x in zip(labels, values)):
            return fmt
    return f"%.{most}g"


def apply_ticks(bar, lo, hi, log=False):
    """Put the ticks of :func:`colour_ticks` on a VTK scalar bar actor; return (values, labels)."""
    ticks, fmt = colour_ticks(lo, hi, log=log)
    if bar is not None:
        from vtkmodules.vtkCommonCore import vtkDoubleArray

        arr = vtkDoubleArray()
        for t in ticks:
            arr.InsertNextValue(float(t))
        bar.SetUseCustomLabels(True)
        bar.SetCustomLabels(arr)
        bar.SetLabelFormat(fmt)
    return ticks, [fmt % t for t in ticks]
