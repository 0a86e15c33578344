r"""Spectral filters :math:`\varphi : [0, \infty) \to \mathbb{R}` (or :math:`\mathbb{C}`).

A filter defines the spectral operator :math:`\varphi(\tilde L) = X \varphi(\Lambda) X^\top B`
and the kernel :math:`K = \varphi(\tilde L) B^{-1}`. Every :class:`Filter` evaluates
:math:`\varphi` on arrays, knows whether it is singular at 0 (then :math:`\varphi(0) := 0`
on ker L: a pseudo-inverse acting on the B-orthogonal complement of the constants of each
component), knows :math:`|\varphi|^2` (``.square``, what spectral distances need) and
carries its analytic form (``.kind``, ``.params``) so that the approximation methods can
use closed forms (best rational approximations of the exponential, exact pseudo-solves).

Examples
--------
>>> from spectral_igl import filters
>>> h = filters.heat(0.1)
>>> float(h(0.0)), h.square.params["t"]
(1.0, 0.2)
>>> filters.biharmonic().singular
True
"""
from __future__ import annotations

import numbers

import numpy as np

from ._validate import as_flag, as_positive, describe

__all__ = ["Filter", "heat", "wave", "commute_time", "biharmonic", "polyharmonic",
           "mexican_hat", "multiscale", "as_filter", "check_filter", "FILTERS", "by_name"]


class Filter:
    r"""A spectral filter :math:`\varphi`, evaluated elementwise on eigenvalues :math:`s \ge 0`.

    Parameters
    ----------
    fn : callable
        Vectorised function of a float array ``s`` (eigenvalues, ``s >= 0``) returning an
        array of the same shape (real, or complex when ``is_complex``).
    name : str, optional
        Label used in reprs and tables.
    singular : bool
        True when :math:`\varphi` is unbounded at 0. The filter is then applied as a
        pseudo-inverse: :math:`\varphi(0) := 0` on ker L, and ``fn`` is only evaluated
        on the positive part of the spectrum.
    is_complex : bool
        True when :math:`\varphi` takes complex values (e.g. the wave filter).
    square : Filter or callable, optional
        :math:`|\varphi|^2`: a Filter, or a callable of no argument returning one (built
        lazily, so that e.g. the square of a heat filter is again a heat filter). Built
        from ``fn`` when not given.
    kind, params :
        Analytic form, used by the approximation methods (``"heat"``, ``"wave"``,
        ``"power"`` for :math:`s^{-p}`, ...). User filters have ``kind=None``.
    derivative : callable, optional
        :math:`\varphi'(s)`; used to certify error bounds between sample points. When
        absent, the bound uses finite differences on a fine grid (see ``approx``).
    key : hashable, optional
        What makes two filters equal. Filters are values: those built by this module's
        constructors are equal (and hash alike) when their kind and parameters are, so every
        cache keyed by a filter is reused across calls (``heat(0.01) == heat(0.01)``). A user
        filter defaults to the identity of ``fn``.

    Examples
    --------
    >>> import numpy as np
    >>> g = Filter(lambda s: 1.0 / (1.0 + s) ** 2, name="resolvent2")
    >>> float(g(np.array([1.0]))[0])
    0.25
    """

    def __init__(self, fn, name: str | None = None, singular: bool = False, is_complex: bool = False,
                 square=None, kind: str | None = None, params: dict | None = None, derivative=None,
                 key=None):
        if not callable(fn):
            raise TypeError(f"fn must be a callable of an array, got {describe(fn)}")
        self.fn = fn
        self.name = name or getattr(fn, "__name__", "filter")
        self.singular = as_flag(singular, "singular")
        self.is_complex = as_flag(is_complex, "is_complex")
        self.kind = kind
        self.params = dict(params or {})
        self.derivative = derivative
        self._square = square
        if key is None:
            key = (("kind", kind, tuple(sorted(self.params.items()))) if kind is not None
                   else ("fn", fn, self.name))
        self.key = (key, self.singular, self.is_complex)

    def __eq__(self, other) -> bool:
        return isinstance(other, Filter) and self.key == other.key

    def __hash__(self) -> int:
        return hash(self.key)

    def at_zero(self):
        r""":math:`\varphi(0)`, with the convention :math:`\varphi(0) := 0` for singular filters."""
        if self.singular:
            return 0.0
        with np.errstate(all="ignore"):
            return np.asarray(self(np.zeros(1))).ravel()[0]

    def __call__(self, s):
        """φ(s) for an array ``s`` (float); singular filters return 0 at s == 0."""
        s = np.asarray(s, dtype=np.float64)
        if self.singular:
            out = np.zeros(s.shape, dtype=np.complex128 if self.is_complex else np.float64)
            pos = s > 0
            if np.any(pos):
                out[pos] = self._values(s[pos])
            return out if out.ndim else out[()]
        out = self._values(s)
        if not self.is_complex and np.iscomplexobj(out):
            raise ValueError(f"filter {self.name!r} returned complex values; pass is_complex=True")
        return out

    def _values(self, s: np.ndarray) -> np.ndarray:
        """``fn(s)`` with the shape of ``s``: a scalar (a constant filter) is broadcast,
        any other shape refused (broadcasting it would give every eigenvalue the same value)."""
        out = np.asarray(self.fn(s))
        if out.shape != s.shape:
            if out.ndim != 0:
                raise ValueError(f"filter {self.name!r} must map an array of eigenvalues of shape {s.shape} "
                                 f"to the same shape (it is applied elementwise), got {describe(out)}")
            out = np.broadcast_to(out, s.shape).copy()
        return out

    @property
    def square(self) -> "Filter":
        r""":math:`|\varphi|^2` as a Filter (what spectral distances integrate)."""
        sq = self._square
        if isinstance(sq, Filter):
            return sq
        if callable(sq):
            self._square = sq()
            return self._square
        fn = self.fn
        if self.is_complex:
            new = Filter(lambda s: np.abs(fn(s)) ** 2, name=f"|{self.name}|^2", singular=self.singular,
                         key=("square", self.key))
        else:
            new = Filter(lambda s: fn(s) ** 2, name=f"{self.name}^2", singular=self.singular,
                         key=("square", self.key))
        self._square = new
        return new

    def __repr__(self) -> str:
        extra = ", ".join(f"{k}={v!r}" for k, v in self.params.items())
        flags = (", singular" if self.singular else "") + (", complex" if self.is_complex else "")
        return f"Filter({self.name}{', ' + extra if extra else ''}{flags})"


def as_filter(filt) -> Filter:
    r"""Validate a filter argument: a :class:`Filter`, or a plain vectorised callable.

    Parameters
    ----------
    filt : Filter or callable
        A callable ``fn(s)`` of an array of eigenvalues is wrapped as ``Filter(fn)``.

    Returns
    -------
    Filter
        ``filt`` itself when it is a Filter.

    Raises
    ------
    TypeError
        For anything else, naming what was received.

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl import filters
    >>> f = filters.as_filter(lambda s: 1.0 / (1.0 + s))
    >>> float(f(np.array([1.0]))[0]), filters.as_filter(filters.heat(1.0)) == filters.heat(1.0)
    (0.5, True)
    """
    if isinstance(filt, Filter):
        return filt
    if callable(filt):
        return Filter(filt)
    raise TypeError(f"filter must be a spectral_igl.filters.Filter or a callable, got {describe(filt)}")


def check_filter(filt) -> Filter:
    r"""Validate a filter argument that must already be a :class:`Filter` (e.g. ``heat(t)``).

    Parameters
    ----------
    filt : Filter

    Returns
    -------
    Filter
        ``filt`` itself.

    Raises
    ------
    TypeError
        When ``filt`` is not a Filter (a plain callable included), naming what was received.

    Examples
    --------
    >>> from spectral_igl import filters
    >>> filters.check_filter(filters.biharmonic()) == filters.biharmonic()
    True
    >>> filters.check_filter(abs)
    Traceback (most recent call last):
    ...
    TypeError: expected a spectral_igl.filters.Filter (e.g. filters.heat(t)), got ...
    """
    if not isinstance(filt, Filter):
        raise TypeError("expected a spectral_igl.filters.Filter (e.g. filters.heat(t)), got " + describe(filt))
    return filt


def heat(t) -> Filter:
    r"""Heat (diffusion) filter, :math:`\varphi(s) = e^{-ts}`.

    Parameters
    ----------
    t : float
        Time, ``t > 0`` (physical time: no normalisation).

    Returns
    -------
    Filter
        Kind ``"heat"``; its square is ``heat(2 * t)``.

    Notes
    -----
    .. math:: K_t = e^{-t\tilde L} B^{-1}

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl import filters
    >>> f = filters.heat(0.5)
    >>> np.round(f([0.0, 2.0]), 6), f.square == filters.heat(1.0)
    (array([1.      , 0.367879]), True)
    """
    t = as_positive(t, "t")
    return Filter(lambda s: np.exp(-t * s), name="heat", kind="heat", params={"t": t},
                  derivative=lambda s: -t * np.exp(-t * s), square=lambda: heat(2.0 * t))


def wave(t) -> Filter:
    r"""Wave (Schrödinger) filter, :math:`\varphi(s) = e^{-ist}` (complex).

    Parameters
    ----------
    t : float
        Time of the propagator (real; physical time: no normalisation).

    Returns
    -------
    Filter
        Kind ``"wave"``, complex; its square is the constant filter 1.

    Notes
    -----
    .. math:: \varphi(\tilde L) f = \cos(t\tilde L) f - i \sin(t\tilde L) f

    Its modulus is 1, so ``.square`` is the constant filter 1.

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl import filters
    >>> f = filters.wave(np.pi / 2)
    >>> np.round(f([0.0, 1.0]), 6), f.is_complex
    (array([1.+0.j, 0.-1.j]), True)
    """
    t = as_positive(t, "t")
    return Filter(lambda s: np.exp(-1j * t * s), name="wave", is_complex=True, kind="wave",
                  params={"t": t}, derivative=lambda s: -1j * t * np.exp(-1j * t * s),
                  square=lambda: Filter(np.ones_like, name="one", key=("one",)))


def _power(p: float, name: str) -> Filter:
    """s^{-p} on the complement of ker L (p > 0): singular at 0."""
    return Filter(lambda s: s ** (-p), name=name, singular=True, kind="power", params={"p": p},
                  derivative=lambda s: -p * s ** (-p - 1.0),
                  square=lambda: _power(2.0 * p, f"({name})^2"))


def commute_time() -> Filter:
    r"""Commute-time filter, :math:`\varphi(s) = s^{-1/2}` (:math:`\varphi^2 = s^{-1}`), singular at 0.

    Returns
    -------
    Filter
        Kind ``"power"`` with ``p = 1/2``, singular: 0 on ker L.

    Notes
    -----
    .. math:: d^2(i, j) = \sum_{l \ge 2} \lambda_l^{-1} |x_l(i) - x_l(j)|^2

    The filter is applied as a pseudo-inverse on the B-orthogonal complement of ker L
    (:math:`\varphi(0) := 0` on the constants of each component).

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl import filters
    >>> f = filters.commute_time()
    >>> np.round(f([0.0, 4.0]), 6), np.round(f.square([4.0]), 6)
    (array([0. , 0.5]), array([0.25]))
    """
    return _power(0.5, "commute_time")


def biharmonic() -> Filter:
    r"""Biharmonic filter, :math:`\varphi(s) = s^{-1}` (:math:`\varphi^2 = s^{-2}`), singular at 0.

    Returns
    -------
    Filter
        Kind ``"power"`` with ``p = 1``, singular: 0 on ker L.

    Notes
    -----
    .. math:: d^2(i, j) = \sum_{l \ge 2} \lambda_l^{-2} |x_l(i) - x_l(j)|^2

    Lipman et al.'s biharmonic distance (the survey's): the filter is applied as a
    pseudo-inverse on the B-orthogonal complement of ker L.

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl import filters
    >>> f = filters.biharmonic()
    >>> np.round(f([0.0, 4.0]), 6), f.singular
    (array([0.  , 0.25]), True)
    """
    return _power(1.0, "biharmonic")


def polyharmonic(k) -> Filter:
    r"""Poly-harmonic filter, :math:`\varphi(s) = s^{-k/2}`, singular at 0.

    Parameters
    ----------
    k : int
        Positive integer order.

    Returns
    -------
    Filter
        Kind ``"power"`` with ``p = k/2``, singular: 0 on ker L.

    Notes
    -----
    ``k = 1`` is commute-time, ``k = 2`` biharmonic.

    .. math:: \varphi(\tilde L) = (\tilde L^+)^{k/2}

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl import filters
    >>> filters.polyharmonic(2) == filters.biharmonic()
    True
    >>> np.round(filters.polyharmonic(3)([4.0]), 6)
    array([0.125])
    """
    if isinstance(k, (bool, np.bool_)) or not isinstance(k, (numbers.Integral, np.integer)):
        raise TypeError(f"k must be a positive integer, got {describe(k)}")
    if int(k) < 1:
        raise ValueError(f"k must be a positive integer, got {int(k)}")
    return _power(int(k) / 2.0, f"polyharmonic{int(k)}")


def mexican_hat(t, form: str = "tse") -> Filter:
    r"""Mexican-hat filter (band-pass, 0 at s = 0), in one of two forms in use.

    Parameters
    ----------
    t : float
        Scale, ``t > 0``.
    form : {"tse", "survey"}
        Which of the two forms (see Notes).

    Returns
    -------
    Filter
        Zero at :math:`s = 0`.

    Notes
    -----
    ``form="tse"`` (default): :math:`\varphi(s) = t s\, e^{-ts}`, i.e.
    :math:`\varphi(\tilde L) = t \tilde L e^{-t\tilde L}`.
    ``form="survey"``: the survey's (Hou and Qin 2012) :math:`\varphi(s) = s^{1/2}e^{-s^2}`
    at scale ``t``,

    .. math:: \varphi_t(s) = (ts)^{1/2} e^{-(ts)^2}, \qquad |\varphi_t|^2(s) = ts\, e^{-2(ts)^2}

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl import filters
    >>> f = filters.mexican_hat(0.5)
    >>> np.round(f([0.0, 2.0]), 6)
    array([0.      , 0.367879])
    """
    t = as_positive(t, "t")
    if form == "survey":
        def fn(s):
            with np.errstate(divide="ignore", over="ignore"):   # in logs: no inf * 0 at huge ts
                u = np.minimum(t * np.maximum(np.asarray(s, dtype=float), 0.0), 1e300)
                return np.where(u > 0, np.exp(0.5 * np.log(u) - u * u), 0.0)
        return Filter(fn, name="mexican_hat_survey", kind="mexican_hat_survey", params={"t": t},
                      square=lambda: Filter(lambda s: t * np.maximum(s, 0.0) * np.exp(-2.0 * (t * s) ** 2),
                                            name="mexican_hat_survey^2",
                                            key=("square", "mexican_hat_survey", t)))
    if form != "tse":
        raise ValueError(f"form must be 'tse' or 'survey', got {form!r}")
    return Filter(lambda s: t * s * np.exp(-t * s), name="mexican_hat", kind="mexican_hat",
                  params={"t": t}, derivative=lambda s: t * (1.0 - t * s) * np.exp(-t * s),
                  square=lambda: Filter(lambda s: (t * s) ** 2 * np.exp(-2.0 * t * s), name="mexican_hat^2",
                                        derivative=lambda s: 2 * t * t * s * (1.0 - t * s) * np.exp(-2 * t * s),
                                        key=("square", "mexican_hat", t)))


def multiscale(t, k, alpha) -> Filter:
    r"""Multi-scale filter, :math:`\varphi(s) = t^k s^\alpha e^{-t s^\alpha}`.

    Parameters
    ----------
    t : float
        Scale, ``t > 0``.
    k : float
        Power of ``t`` in front, ``k >= 0``.
    alpha : float
        Power of :math:`s`, ``alpha > 0``.

    Returns
    -------
    Filter
        ``multiscale(t, 0, 1)`` is the heat filter's shape.

    Notes
    -----
    .. math:: \varphi(\tilde L) = t^k \tilde L^\alpha e^{-t\tilde L^\alpha}

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl import filters
    >>> f = filters.multiscale(0.5, 1.0, 1.0)
    >>> bool(np.allclose(f([0.0, 1.0, 3.0]), filters.mexican_hat(0.5)([0.0, 1.0, 3.0])))
    True
    """
    t = as_positive(t, "t")
    if isinstance(k, (bool, np.bool_)) or not isinstance(k, (numbers.Real, np.integer, np.floating)):
        raise TypeError(f"k must be a real number, got {describe(k)}")
    k = float(k)
    if not np.isfinite(k) or k < 0:
        raise ValueError(f"k must be finite and >= 0, got {k}")
    a = as_positive(alpha, "alpha")

    def fn(s):
        sa = s ** a
        return t ** k * sa * np.exp(-t * sa)

    def der(s):
        with np.errstate(divide="ignore", invalid="ignore"):
            sa = s ** a
            d = t ** k * a * s ** (a - 1.0) * (1.0 - t * sa) * np.exp(-t * sa)
        return np.where(s > 0, d, np.inf if a < 1 else (t ** k if a == 1 else 0.0))

    return Filter(fn, name="multiscale", kind="multiscale", params={"t": t, "k": k, "alpha": a},
                  derivative=der,
                  square=lambda: Filter(lambda s: fn(s) ** 2, name="multiscale^2",
                                        derivative=lambda s: 2.0 * fn(s) * der(s),
                                        key=("square", "multiscale", t, k, a)))


def _diffusion(t) -> Filter:
    """The heat filter at ``t / 2``, whose square :math:`e^{-ts}` defines the diffusion distance at t."""
    return heat(as_positive(t, "t") / 2.0)


#: The filters by name, read by the command line, the viewer and
#: :func:`spectral_igl.quantity.evaluate`: name -> (constructor, whether it takes a time t).
#: ``"diffusion"`` is the heat filter at t/2 (its square defines the diffusion distance at t).
FILTERS = {
    "heat": (heat, True),
    "diffusion": (_diffusion, True),
    "wave": (wave, True),
    "mexican_hat": (mexican_hat, True),
    "commute_time": (commute_time, False),
    "biharmonic": (biharmonic, False),
    "polyharmonic": (polyharmonic, False),
}


def by_name(name: str, t: float | None = None, order: int = 3) -> Filter:
    r"""The filter called ``name`` in :data:`FILTERS`, at time ``t`` (or of ``order``, poly-harmonic).

    Parameters
    ----------
    name : str
        A key of :data:`FILTERS`: ``"heat"``, ``"diffusion"`` (``heat(t / 2)``, whose square
        defines the diffusion distance at ``t``), ``"wave"``, ``"mexican_hat"``,
        ``"commute_time"``, ``"biharmonic"``, ``"polyharmonic"``.
    t : float, optional
        Time of the timed filters (required for them).
    order : int
        Order of ``"polyharmonic"`` (default 3).

    Returns
    -------
    Filter

    Examples
    --------
    >>> by_name("diffusion", 0.2) == heat(0.1)
    True
    >>> by_name("polyharmonic", order=2) == biharmonic()
    True
    """
    if not isinstance(name, str) or name not in FILTERS:
        raise ValueError(f"unknown filter {name!r}; choose one of {', '.join(FILTERS)}")
    make, timed = FILTERS[name]
    if timed:
        if t is None:
            raise ValueError(f"filter {name!r} needs a time t")
        return make(t)
    if name == "polyharmonic":
        return make(order)
    return make()
