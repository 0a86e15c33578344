"""What is computed per shape: a :class:`Job` turns ``(name, lap)`` into named arrays.

A job is a small picklable value: its ``kind`` and JSON-able ``params`` identify the result
in the store (a rerun with the same input and the same job skips the shape), and calling it
on a Laplacian returns the arrays and the error bounds of that shape.
"""
from __future__ import annotations

import hashlib
import inspect
import json
from dataclasses import dataclass, field

import numpy as np

from ..accuracy import weakest
from .._validate import as_choice, as_flag, as_indices, as_int, as_positive, describe
from ..filters import FILTERS, by_name
from ..laplacian.units import TIME_UNITS, shape_time, time_scale
from .store import BOUND_SUFFIX

__all__ = ["Job"]


def _largest(abs_error):
    """The largest entry of a bound, or None where any entry has none (nan)."""
    e = np.asarray(abs_error, dtype=float)
    return float(np.max(e)) if e.size and np.all(np.isfinite(e)) else None


def _bounded(arrays, key, abs_error, kind, method, **extra):
    """``(arrays, bounds)`` with the per-entry bound of ``arrays[key]`` stored next to it (as
    ``<key>_abs_error``) and its summary: the largest entry, the kind, the method."""
    e = np.broadcast_to(np.asarray(abs_error, dtype=float), np.shape(arrays[key]))
    arrays = dict(arrays, **{key + BOUND_SUFFIX: np.array(e)})
    top = _largest(e)
    bounds = {"of": key, "abs_error": top, "bound_kind": kind if top is not None else None,
              "method": method}
    bounds.update(extra)
    return arrays, bounds

def _floats(x, name):
    a = np.asarray(x, dtype=float) if not isinstance(x, (str, bytes)) else None
    if a is None or a.ndim > 1 or a.size == 0 or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be a finite scalar or 1-D array, got {describe(x)}")
    return [float(v) for v in a.reshape(-1)]


def _unit(time_unit):
    """``{"time_unit": unit}`` for a unit other than ``"absolute"`` (absolute times keep the keys
    they always had, so existing stores stay current)."""
    unit = as_choice(time_unit, "time_unit", TIME_UNITS)
    return {} if unit == "absolute" else {"time_unit": unit}


def _time_record(lap, p, absolute):
    """What the store records about times: the unit, its scale on this shape, the absolute times."""
    unit = p.get("time_unit", "absolute")
    return {"time_unit": unit, "time_scale": time_scale(lap, unit),
            "absolute_times": [float(x) for x in np.atleast_1d(absolute)]}


def _filter_params(filter, t, order, time_unit="absolute"):
    if filter not in FILTERS:
        raise ValueError(f"filter must be one of {tuple(FILTERS)}, got {filter!r}")
    params = {"filter": filter}
    if FILTERS[filter][1]:
        if t is None:
            raise ValueError(f"filter {filter!r} needs a time t, got None")
        params["t"] = as_positive(t, "t")
        params.update(_unit(time_unit))
    elif t is not None:
        raise ValueError(f"filter {filter!r} takes no time t, got t={t!r}")
    elif time_unit != "absolute":
        raise ValueError(f"filter {filter!r} takes no time t, so time_unit={time_unit!r} has nothing "
                         "to apply to")
    if filter == "polyharmonic":
        if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 1:
            raise ValueError(f"order of the polyharmonic filter must be an integer >= 1, got {order!r}")
        params["order"] = int(order)
    return params


def _time(lap, params):
    """The filter's absolute time on ``lap`` (None for filters without one)."""
    t = params.get("t")
    return None if t is None else shape_time(lap, t, params.get("time_unit", "absolute"))


def _make_filter(params, lap):
    return by_name(params["filter"], _time(lap, params), params.get("order", 3))


def _source_digest(fn):
    """A digest of a user function's code, so that editing it invalidates stored results."""
    try:
        text = inspect.getsource(fn)
    except (OSError, TypeError):
        code = getattr(fn, "__code__", None)
        text = repr(code.co_code) + repr(code.co_consts) if code is not None else repr(fn)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Job:
    """One computation applied to every shape of a collection.

    Build it with a constructor: :meth:`hks`, :meth:`wks`, :meth:`kernel_diagonal`,
    :meth:`distances`, :meth:`eigenvalues`, :meth:`heat_trace`, :meth:`shape_dna` or
    :meth:`function`. Calling the job on
    ``(name, lap)`` returns ``(arrays, bounds)``: a dict of named arrays (``(n, ...)`` per
    vertex) with, next to the result ``<key>``, its per-entry bound ``<key>_abs_error``
    (:mod:`spectral_igl.accuracy`), and a dict of JSON values: ``of`` (the bounded result),
    ``abs_error`` (its largest entry; ``None`` where no bound exists, with a ``note`` saying
    why), ``bound_kind``, ``method`` and the job's own fields.

    Attributes
    ----------
    kind : str
    params : dict
        JSON-able parameters; with ``kind`` they identify the result in the store.
    fn : callable or None
        The user function of :meth:`function`.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> job = Job.hks([0.1, 1.0])
    >>> arrays, bounds = job("sphere", sig.laplacian(*icosphere(2)))
    >>> arrays["hks"].shape, arrays["hks_abs_error"].shape, len(bounds["abs_error_bound"])
    ((162, 2), (162, 2), 2)
    >>> bounds["bound_kind"], bool(bounds["abs_error"] < 1e-8)
    ('proof', True)
    >>> Job.hks([0.1, 1.0]).key() == job.key() != Job.hks([0.1]).key()
    True
    """

    kind: str
    params: dict = field(default_factory=dict)
    fn: object = None

    # ---- constructors -------------------------------------------------------------------
    @classmethod
    def hks(cls, times=None, method: str = "auto", tol: float = 1e-8, time_unit: str = "absolute",
            normalize: bool = False, count: int = 100):
        r"""Heat kernel signature at ``times`` (:func:`spectral_igl.hks`).

        .. math:: HKS(i, t) = K_t(i, i)

        ``times`` in the units ``time_unit`` (:mod:`spectral_igl.laplacian.units`); without
        them, ``count`` times from each shape's own spectrum (:func:`spectral_igl.hks_times`),
        so that a shape and its scaled copy get the same relative grid. ``normalize``
        multiplies by the area (volume) of each vertex's component: with the two, HKS of shapes of
        different sizes compare. Stores ``"hks"``: (n, len(times)) float, its per-entry
        bound ``"hks_abs_error"`` and the largest bound of each time, ``abs_error_bound``,
        and records ``time_unit``, ``time_scale`` (the factor it stood for on that shape)
        and ``absolute_times``.
        """
        params = {"times": None if times is None else _floats(times, "times"), "method": str(method),
                  "tol": as_positive(tol, "tol")}
        if times is None:
            if time_unit != "absolute":
                raise ValueError(f"time_unit={time_unit!r} applies to times, which were not given "
                                 "(the default grid follows each shape's spectrum)")
            params["count"] = as_int(count, "count", lo=1, hi=1000)
        params.update(_unit(time_unit))
        if as_flag(normalize, "normalize"):
            params["normalize"] = True
        return cls("hks", params)

    @classmethod
    def wks(cls, energies=None, sigma: float | None = None, k: int = 100, method: str = "eigen"):
        r"""Wave kernel signature at log-energies ``energies`` (:func:`spectral_igl.wks`).

        Without ``energies``, each shape's own grid over its first ``k`` non-zero eigenvalues
        (:func:`spectral_igl.wks_energies`). Stores ``"wks"``: (n, len(energies)) float, and
        the ``energies`` and ``sigma`` used.
        """
        E = None if energies is None else _floats(energies, "energies")
        if sigma is None and E is not None and len(E) < 2:
            raise ValueError("sigma is required for a single energy")
        return cls("wks", {"energies": E, "sigma": None if sigma is None else as_positive(sigma, "sigma"),
                           "k": int(k), "method": str(method)})

    @classmethod
    def kernel_diagonal(cls, filter: str = "heat", t: float | None = None, order: int | None = None,
                        method: str = "auto", tol: float = 1e-8, time_unit: str = "absolute"):
        r"""Kernel diagonal :math:`G_{ii}` of ``filter`` (:func:`spectral_igl.kernel_diagonal`).

        .. math:: G = \varphi(\tilde L) B^{-1}

        ``filter`` is a name of :data:`spectral_igl.filters.FILTERS` (as in
        :func:`spectral_igl.filters.by_name`: ``"diffusion"`` at t is ``heat(t / 2)``); ``t``
        for the filters with a time (in the units ``time_unit``), ``order`` for
        ``"polyharmonic"``. Stores ``"diagonal"``: (n,).
        """
        params = _filter_params(filter, t, order, time_unit)
        params.update(method=str(method), tol=as_positive(tol, "tol"))
        return cls("kernel_diagonal", params)

    @classmethod
    def distances(cls, sources, filter: str = "biharmonic", t: float | None = None,
                  order: int | None = None, method: str = "auto", tol: float = 1e-8,
                  time_unit: str = "absolute"):
        r"""One-to-all spectral distances from each of ``sources``.

        .. math:: d(s, j) = \|\varphi(\tilde L) B^{-1}(e_s - e_j)\|_B

        Uses :func:`spectral_igl.diffusion_distance` (``filter="diffusion"``: time ``t`` of
        :math:`|\varphi|^2 = e^{-ts}`), :func:`~spectral_igl.biharmonic_distance`,
        :func:`~spectral_igl.commute_time_distance`,
        :func:`~spectral_igl.polyharmonic_distance` or
        :func:`~spectral_igl.spectral_distance`. Stores ``"distances"``: (len(sources), n)
        and ``"sources"``, with ``"distances_abs_error"``, a bound of every distance (the row's
        ``abs_error``), and each row's ``d2_error_bound``.
        """
        src = as_indices(sources, 2 ** 62, "sources")
        params = _filter_params(filter, t, order, time_unit)
        params.update(sources=[int(s) for s in src.reshape(-1)], method=str(method),
                      tol=as_positive(tol, "tol"))
        return cls("distances", params)

    @classmethod
    def eigenvalues(cls, k: int):
        r"""The ``k`` smallest eigenvalues of :math:`Lx = \lambda Bx` (:func:`spectral_igl.eigs`).

        Stores ``"eigenvalues"``: (k,) float, certified: ``"eigenvalues_abs_error"`` bounds
        each entry (residual bounds and an inertia count, ``bound_kind == "proof"``); with
        ``k`` equal to the number of vertices, the dense solver's values, without a bound.
        """
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise ValueError(f"k must be an integer >= 1, got {k!r}")
        return cls("eigenvalues", {"k": int(k)})

    @classmethod
    def heat_trace(cls, times=None, time_unit: str = "shape", tol: float = 1e-8):
        r"""The heat trace :math:`Z(t) = \sum_l e^{-t\lambda_l}` (:func:`spectral_igl.heat_trace`).

        ``times`` in the units ``time_unit``; without them the common grid
        :data:`spectral_igl.applications.compare.TRACE_TIMES` in the shape's units, so that
        the stored traces compare (:func:`spectral_igl.shape_distance_matrix`). Stores
        ``"heat_trace"``: (T,) float, its bound ``"heat_trace_abs_error"`` and ``"times"``
        (absolute).
        """
        params = {"times": None if times is None else _floats(times, "times"), "tol": as_positive(tol, "tol")}
        params["time_unit"] = as_choice(time_unit, "time_unit", TIME_UNITS)
        return cls("heat_trace", params)

    @classmethod
    def shape_dna(cls, k: int = 50, normalize: str | None = "shape"):
        """ShapeDNA: the first ``k`` certified eigenvalues times the shape's measure
        (:func:`spectral_igl.shape_dna`), of the finite-element Laplacian (cotan weights,
        consistent mass) unless the run asks for other ``weights`` or ``mass``
        (:meth:`laplacian_options`). Stores ``"shape_dna"``: (k,) float and its bound
        ``"shape_dna_abs_error"``.
        """
        if normalize is not None:
            normalize = as_choice(normalize, "normalize", tuple(u for u in TIME_UNITS if u != "absolute"))
        return cls("shape_dna", {"k": as_int(k, "k", lo=1), "normalize": normalize})

    @classmethod
    def function(cls, fn, params: dict | None = None, name: str | None = None):
        """Any function ``fn(name, lap)`` returning an array or a dict of arrays.

        ``params`` (JSON-able) and a digest of ``fn``'s source code identify the result,
        so editing the function or its parameters recomputes every shape. On a cluster
        ``fn`` is shipped to the workers by cloudpickle: define it in an importable module
        or in ``__main__``.
        """
        if not callable(fn):
            raise TypeError(f"fn must be callable as fn(name, lap), got {describe(fn)}")
        params = {} if params is None else dict(params)
        try:
            json.dumps(params)
        except TypeError as err:
            raise TypeError(f"params must be JSON-serialisable, got {params!r}: {err}") from None
        label = name or getattr(fn, "__qualname__", type(fn).__name__)
        return cls("function", {"function": label, "code": _source_digest(fn), "params": params}, fn)

    def laplacian_options(self, weights: str | None = None, mass: str | None = None) -> dict:
        """The options of :func:`spectral_igl.laplacian` this job's meshes are given:
        ``weights`` and ``mass`` where set, else the job's own defaults, those of
        :func:`spectral_igl.laplacian` (``"auto"``, ``"lumped"``) except for
        :meth:`shape_dna`, computed with the finite elements ShapeDNA is defined with
        (:data:`spectral_igl.applications.compare.SHAPE_DNA_LAPLACIAN`, as
        :func:`spectral_igl.shape_dna` does from a mesh).

        Examples
        --------
        >>> from spectral_igl.collection import Job
        >>> Job.shape_dna(10).laplacian_options()
        {'weights': 'cotan', 'mass': 'full'}
        >>> Job.eigenvalues(4).laplacian_options(mass="full")
        {'weights': 'auto', 'mass': 'full'}
        """
        from ..applications.compare import SHAPE_DNA_LAPLACIAN

        own = SHAPE_DNA_LAPLACIAN if self.kind == "shape_dna" else {"weights": "auto", "mass": "lumped"}
        return {"weights": str(own["weights"] if weights is None else weights),
                "mass": str(own["mass"] if mass is None else mass)}

    # ---- identity -----------------------------------------------------------------------
    def key(self) -> str:
        """A digest of ``kind`` and ``params``: equal jobs give equal keys."""
        text = json.dumps({"kind": self.kind, "params": self.params}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    def uses_selected_inverse(self) -> bool:
        """True when the job factorizes shifted complex matrices (memory estimate)."""
        if self.kind in ("hks", "kernel_diagonal", "distances", "heat_trace"):
            return True
        return self.kind == "wks" and self.params.get("method") != "eigen"

    # ---- evaluation ---------------------------------------------------------------------
    def __call__(self, name, lap):
        """Evaluate on one shape: ``(arrays, bounds)``."""
        from ..descriptors import hks, hks_times, wks
        from ..descriptors import spectral_descriptor as kernel_diagonal  # diagonal of phi(L~)B^-1

        p = self.params
        if self.kind == "hks":
            times = hks_times(lap, p["count"]) if p["times"] is None else np.asarray(p["times"])
            H, info = hks(lap, times, method=p["method"], tol=p["tol"], return_info=True,
                          time_unit=p.get("time_unit", "absolute"), normalize=p.get("normalize", False))
            H = np.asarray(H, dtype=float).reshape(lap.n, -1)
            err = np.asarray(info["abs_error"], dtype=float).reshape(lap.n, -1)
            return _bounded({"hks": H, "times": np.asarray(info["times"])}, "hks", err,
                            info["bound_kind"], info["method"],
                            abs_error_bound=[_largest(err[:, j]) for j in range(err.shape[1])],
                            normalized_by=info.get("normalized_by"),
                            **_time_record(lap, p, info["times"]), **_note(info))
        if self.kind == "wks":
            W, info = wks(lap, p["energies"], sigma=p["sigma"], k=p["k"], method=p["method"], return_info=True)
            return _bounded({"wks": np.asarray(W).reshape(lap.n, -1), "energies": info["energies"]}, "wks",
                            np.asarray(info["abs_error"]).reshape(lap.n, -1), info["bound_kind"],
                            info["method"], sigma=info["sigma"], **_note(info))
        if self.kind == "kernel_diagonal":
            d, info = kernel_diagonal(lap, _make_filter(p, lap), method=p["method"], tol=p["tol"],
                                      return_info=True)
            extra = {"abs_error_bound": info.get("abs_error_bound"), **_note(info)}
            if "t" in p:
                extra.update(_time_record(lap, p, _time(lap, p)))
            if "sample_rel_error" in info:
                extra["sample_rel_error"] = info["sample_rel_error"]
            return _bounded({"diagonal": np.asarray(d)}, "diagonal", info["abs_error"], info["bound_kind"],
                            info["method"], **extra)
        if self.kind == "distances":
            rows, errs, kinds, d2 = [], [], [], []
            for s in p["sources"]:
                d, info = _distance(lap, p, s)
                rows.append(np.asarray(d, dtype=float))
                errs.append(np.asarray(info["abs_error"], dtype=float))
                kinds.append(info["bound_kind"])
                d2.append(info.get("d2_error_bound"))
            extra = _time_record(lap, p, _time(lap, p)) if "t" in p else {}
            return _bounded({"distances": np.stack(rows), "sources": np.asarray(p["sources"], dtype=np.int64)},
                            "distances", np.stack(errs), weakest(*kinds), info["method"],
                            d2_error_bound=d2, **extra)
        if self.kind in ("heat_trace", "shape_dna"):
            return _signature(self.kind, lap, p)
        if self.kind == "eigenvalues":
            from ..linalg import dense_eigs, eigs

            k = p["k"]
            if k > lap.n:
                raise ValueError(f"k = {k} eigenvalues asked of a shape with {lap.n} vertices")
            if k >= lap.n:      # every eigenvalue: the dense solver, whose rounding is not bounded here
                return _bounded({"eigenvalues": np.asarray(dense_eigs(lap)[0], dtype=float)}, "eigenvalues",
                                np.nan, None, "dense", note="all eigenvalues by a dense solver: no bound")
            lam, _, info = eigs(lap, k, return_info=True)
            return _bounded({"eigenvalues": np.asarray(lam, dtype=float)}, "eigenvalues", info["abs_error"],
                            info["bound_kind"], info["method"])
        out = self.fn(name, lap)
        if isinstance(out, dict):
            arrays = {str(k): np.asarray(v) for k, v in out.items()}
        else:
            arrays = {"result": np.asarray(out)}
        for k, v in arrays.items():
            if v.dtype == object:
                raise TypeError(f"the job returned {k!r} as an object array; return numeric arrays")
        return arrays, {"abs_error": None, "bound_kind": None, "abs_error_bound": None,
                        "note": "user function: no bound"}


def _note(info):
    """The ``note`` of an ``info`` dict, if it has one, as keyword arguments."""
    return {"note": info["note"]} if info.get("note") else {}


def _signature(kind, lap, p):
    """``(arrays, bounds)`` of :meth:`Job.heat_trace` or :meth:`Job.shape_dna`."""
    from ..applications.compare import heat_trace, shape_dna

    if kind == "shape_dna":
        v, info = shape_dna(lap, p["k"], normalize=p["normalize"], return_info=True)
        return _bounded({"shape_dna": v}, "shape_dna", info["abs_error"], info["bound_kind"],
                        info["method"], scale=info["scale"], normalize=info["normalize"])
    v, info = heat_trace(lap, p["times"], time_unit=p["time_unit"], tol=p["tol"], return_info=True)
    return _bounded({"heat_trace": np.atleast_1d(v), "times": info["times"]}, "heat_trace",
                    np.atleast_1d(info["abs_error"]), info["bound_kind"], info["method"],
                    **_time_record(lap, p, info["times"]), **_note(info))


def _distance(lap, p, s):
    from ..distances import (biharmonic_distance, commute_time_distance, diffusion_distance,
                             polyharmonic_distance, spectral_distance)

    kw = dict(method=p["method"], tol=p["tol"], return_info=True)
    name = p["filter"]
    if name == "diffusion":
        return diffusion_distance(lap, _time(lap, p), s, **kw)
    if name == "biharmonic":
        return biharmonic_distance(lap, s, **kw)
    if name == "commute_time":
        return commute_time_distance(lap, s, **kw)
    if name == "polyharmonic":
        return polyharmonic_distance(lap, p["order"], s, **kw)
    return spectral_distance(lap, _make_filter(p, lap), s, **kw)
