r"""How a result says how right it is: one convention across the package.

Every public function that returns numbers a user reads takes ``return_info=False``; with
``return_info=True`` it returns ``(values, info)`` where ``info`` is a dict with at least

``"abs_error"``
    A bound on :math:`|\text{exact} - \text{returned}|` for **each entry** (an array of the
    values' shape, or a float for a scalar result). ``nan`` where the method gives no bound
    (truncated eigenpairs, say).
``"bound_kind"``
    ``"proof"`` when every ingredient of ``abs_error`` is proved (a certified enclosure of the
    spectrum, a certified scalar error, a rounding allowance), ``"estimate"`` when one of them
    is measured or modelled, ``None`` when there is no bound.
``"method"``
    The method that produced the values (``"auto"`` resolved).

and, where they apply, ``"tol"`` (the tolerance asked for), ``"bnorm_error"`` (the B-norm
bound of each column, from which ``abs_error`` is derived), ``"rel_error"`` (a per-entry
relative bound, :math:`\infty` where the entry is not bounded away from 0) and ``"floor"``.

"Exact" means the exact value for the discrete operator (L, B) as stored in floating point:
the discretisation error of the mesh is not part of any bound.

A result whose bound misses the tolerance asked for says so every time with an
:class:`AccuracyWarning` that names the achieved bound (turn it into an error with
``warnings.simplefilter("error", spectral_igl.accuracy.AccuracyWarning)``).
"""
from __future__ import annotations

import warnings

import numpy as np

__all__ = ["AccuracyWarning", "BOUND_KINDS", "UNIT_ROUNDOFF", "rounding_gamma", "weakest", "warn_missed",
           "relative_error", "info"]

#: the kinds of a bound, strongest first
BOUND_KINDS = ("proof", "estimate")

#: u, the unit roundoff of float64 (round to nearest)
UNIT_ROUNDOFF = 2.0 ** -53


def rounding_gamma(m):
    r"""Higham's :math:`\gamma_m = m u / (1 - m u)`, u = :data:`UNIT_ROUNDOFF`: the relative
    rounding of a sum, or a product, of m floating-point terms (valid while :math:`m u < 1`).

    Parameters
    ----------
    m : int or float
        Number of terms (operations).

    Returns
    -------
    float

    Examples
    --------
    >>> from spectral_igl.accuracy import rounding_gamma, UNIT_ROUNDOFF
    >>> rounding_gamma(1) > UNIT_ROUNDOFF, rounding_gamma(10) < 11 * UNIT_ROUNDOFF
    (True, True)
    """
    return m * UNIT_ROUNDOFF / (1.0 - m * UNIT_ROUNDOFF)


class AccuracyWarning(RuntimeWarning):
    r"""A result's error bound exceeds the tolerance that was asked for (or is only an estimate
    where a proof was asked for).

    A :class:`RuntimeWarning`: the result is returned with its bound in ``info``; turn the
    warning into an error to refuse such results.

    Examples
    --------
    >>> import warnings
    >>> from spectral_igl.accuracy import AccuracyWarning
    >>> issubclass(AccuracyWarning, RuntimeWarning)
    True
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("error", AccuracyWarning)   # a missed tolerance raises
    ...     warnings.warn("bound 1e-6 > tol 1e-8", AccuracyWarning)
    Traceback (most recent call last):
    ...
    spectral_igl.accuracy.AccuracyWarning: bound 1e-6 > tol 1e-8
    """


# every miss is reported, not only the first one at a given line
warnings.filterwarnings("always", category=AccuracyWarning)


def weakest(*kinds):
    r"""The kind of a bound built from parts of these kinds: ``None`` if any part has no bound,
    ``"estimate"`` if any part is an estimate, else ``"proof"``.

    Parameters
    ----------
    *kinds : {"proof", "estimate", None}
        The kinds of the parts' bounds.

    Returns
    -------
    {"proof", "estimate", None}

    Examples
    --------
    >>> weakest("proof", "proof"), weakest("proof", "estimate"), weakest("proof", None)
    ('proof', 'estimate', None)
    """
    if any(k is None for k in kinds):
        return None
    return "proof" if all(k == "proof" for k in kinds) else "estimate"


def warn_missed(what: str, bound, target, stacklevel: int = 3) -> bool:
    """Warn (:class:`AccuracyWarning`) when ``bound > target`` anywhere; True if it did.

    ``bound`` and ``target`` are broadcast; nan bounds count as missed.
    """
    b = np.asarray(bound, dtype=float)
    t = np.broadcast_to(np.asarray(target, dtype=float), b.shape)
    bad = ~(b <= t)
    if not np.any(bad):
        return False
    worst = float(np.nanmax(np.where(bad, b / np.where(t > 0, t, np.nan), np.nan), initial=np.nan))
    warnings.warn(f"{what}: the error bound {float(np.nanmax(b, initial=np.nan)):.3g} exceeds the "
                  f"tolerance asked for ({float(np.max(t)):.3g}) in {int(np.count_nonzero(bad))} of {b.size} "
                  f"results (worst {worst:.3g} times the tolerance); the values are returned with "
                  "their bounds (return_info=True)", AccuracyWarning, stacklevel=stacklevel)
    return True


def relative_error(values, abs_error):
    r"""Per-entry bound of :math:`|x - \tilde x| / |x|` from :math:`|x - \tilde x| \le e`:
    :math:`e / (|\tilde x| - e)` where :math:`|\tilde x| > e`, :math:`\infty` elsewhere.

    Parameters
    ----------
    values : array_like
        The computed :math:`\tilde x`.
    abs_error : array_like
        Bounds :math:`e` of :math:`|x - \tilde x|`, broadcast against ``values``.

    Returns
    -------
    ndarray of float
        The relative bounds, shaped as the broadcast of the two.

    Examples
    --------
    >>> relative_error([2.0, 1.0, 0.5], [1.0, 1.0, 0.0])
    array([ 1., inf,  0.])
    """
    v = np.abs(np.asarray(values))
    e = np.asarray(abs_error, dtype=float)
    gap = v - e
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(gap > 0, e / np.where(gap > 0, gap, 1.0), np.inf)


def info(abs_error, bound_kind, method, **extra) -> dict:
    """The ``info`` dict of the convention above (``abs_error`` as a float array)."""
    if bound_kind not in BOUND_KINDS + (None,):
        raise ValueError(f"bound_kind must be one of {BOUND_KINDS} or None, got {bound_kind!r}")
    out = {"abs_error": np.asarray(abs_error, dtype=float) if np.ndim(abs_error) else float(abs_error),
           "bound_kind": bound_kind, "method": method}
    out.update(extra)
    return out
