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

from .._validate import as_indices, as_positive, describe
from ..filters import FILTERS, by_name

__all__ = ["Job"]

def _floats(x, name):
    a = np.asarray(x, dtype=float) if not isinstance(x, (str, bytes)) else None
    if a is None or a.ndim > 1 or a.size == 0 or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be a finite scalar or 1-D array, got {describe(x)}")
    return [float(v) for v in a.reshape(-1)]


def _filter_params(filter, t, order):
    if filter not in FILTERS:
        raise ValueError(f"filter must be one of {tuple(FILTERS)}, got {filter!r}")
    params = {"filter": filter}
    if FILTERS[filter][1]:
        if t is None:
            raise ValueError(f"filter {filter!r} needs a time t, got None")
        params["t"] = as_positive(t, "t")
    elif t is not None:
        raise ValueError(f"filter {filter!r} takes no time t, got t={t!r}")
    if filter == "polyharmonic":
        if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 1:
            raise ValueError(f"order of the polyharmonic filter must be an integer >= 1, got {order!r}")
        params["order"] = int(order)
    return params


def _make_filter(params):
    return by_name(params["filter"], params.get("t"), params.get("order", 3))


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
    :meth:`distances`, :meth:`eigenvalues` or :meth:`function`. Calling the job on
    ``(name, lap)`` returns ``(arrays, bounds)``: a dict of named arrays (``(n, ...)`` per
    vertex) and a dict of error bounds (JSON values; ``None`` where no bound exists, with
    a ``note`` saying why).

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
    >>> from data_generators import icosphere
    >>> job = Job.hks([0.1, 1.0])
    >>> arrays, bounds = job("sphere", sig.laplacian(*icosphere(2)))
    >>> arrays["hks"].shape, len(bounds["abs_error_bound"])
    ((162, 2), 2)
    >>> Job.hks([0.1, 1.0]).key() == job.key() != Job.hks([0.1]).key()
    True
    """

    kind: str
    params: dict = field(default_factory=dict)
    fn: object = None

    # ---- constructors -------------------------------------------------------------------
    @classmethod
    def hks(cls, times, method: str = "auto", tol: float = 1e-8):
        r"""Heat kernel signature at ``times`` (:func:`spectral_igl.hks`).

        .. math:: HKS(i, t) = K_t(i, i)

        Stores ``"hks"``: (n, len(times)) float, and the certified ``abs_error_bound`` of
        each time (for ``method="selinv"``/``"auto"``).
        """
        return cls("hks", {"times": _floats(times, "times"), "method": str(method),
                           "tol": as_positive(tol, "tol")})

    @classmethod
    def wks(cls, energies, sigma: float | None = None, k: int = 100, method: str = "eigen"):
        r"""Wave kernel signature at log-energies ``energies`` (:func:`spectral_igl.wks`).

        Stores ``"wks"``: (n, len(energies)) float.
        """
        E = _floats(energies, "energies")
        if sigma is None and len(E) < 2:
            raise ValueError("sigma is required for a single energy")
        return cls("wks", {"energies": E, "sigma": None if sigma is None else as_positive(sigma, "sigma"),
                           "k": int(k), "method": str(method)})

    @classmethod
    def kernel_diagonal(cls, filter: str = "heat", t: float | None = None, order: int | None = None,
                        method: str = "auto", tol: float = 1e-8):
        r"""Kernel diagonal :math:`G_{ii}` of ``filter`` (:func:`spectral_igl.kernel_diagonal`).

        .. math:: G = \varphi(\tilde L) B^{-1}

        ``filter`` is a name of :data:`spectral_igl.filters.FILTERS` (as in
        :func:`spectral_igl.filters.by_name`: ``"diffusion"`` at t is ``heat(t / 2)``); ``t``
        for the filters with a time, ``order`` for ``"polyharmonic"``. Stores
        ``"diagonal"``: (n,).
        """
        params = _filter_params(filter, t, order)
        params.update(method=str(method), tol=as_positive(tol, "tol"))
        return cls("kernel_diagonal", params)

    @classmethod
    def distances(cls, sources, filter: str = "biharmonic", t: float | None = None,
                  order: int | None = None, method: str = "auto", tol: float = 1e-8):
        r"""One-to-all spectral distances from each of ``sources``.

        .. math:: d(s, j) = \|\varphi(\tilde L) B^{-1}(e_s - e_j)\|_B

        Uses :func:`spectral_igl.diffusion_distance` (``filter="diffusion"``: time ``t`` of
        :math:`|\varphi|^2 = e^{-ts}`), :func:`~spectral_igl.biharmonic_distance`,
        :func:`~spectral_igl.commute_time_distance`,
        :func:`~spectral_igl.polyharmonic_distance` or
        :func:`~spectral_igl.spectral_distance`. Stores ``"distances"``: (len(sources), n)
        and ``"sources"``; the bound is each row's ``d2_error_bound``.
        """
        src = as_indices(sources, 2 ** 62, "sources")
        params = _filter_params(filter, t, order)
        params.update(sources=[int(s) for s in src.reshape(-1)], method=str(method),
                      tol=as_positive(tol, "tol"))
        return cls("distances", params)

    @classmethod
    def eigenvalues(cls, k: int):
        r"""The ``k`` smallest eigenvalues of :math:`Lx = \lambda Bx` (:func:`spectral_igl.eigs`).

        Stores ``"eigenvalues"``: (k,) float.
        """
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise ValueError(f"k must be an integer >= 1, got {k!r}")
        return cls("eigenvalues", {"k": int(k)})

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

    # ---- identity -----------------------------------------------------------------------
    def key(self) -> str:
        """A digest of ``kind`` and ``params``: equal jobs give equal keys."""
        text = json.dumps({"kind": self.kind, "params": self.params}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    def uses_selected_inverse(self) -> bool:
        """True when the job factorizes shifted complex matrices (memory estimate)."""
        if self.kind in ("hks", "kernel_diagonal", "distances"):
            return True
        return self.kind == "wks" and self.params.get("method") != "eigen"

    # ---- evaluation ---------------------------------------------------------------------
    def __call__(self, name, lap):
        """Evaluate on one shape: ``(arrays, bounds)``."""
        from ..descriptors import spectral_descriptor as kernel_diagonal  # diagonal of phi(L~)B^-1
        from ..descriptors import wks

        p = self.params
        if self.kind == "hks":
            from ..filters import heat

            cols, bounds = [], []
            for t in p["times"]:
                d, info = kernel_diagonal(lap, heat(t), method=p["method"], tol=p["tol"],
                                          return_info=True)
                cols.append(np.asarray(d, dtype=float).reshape(lap.n))
                bounds.append(info.get("abs_error_bound"))
            return {"hks": np.stack(cols, axis=1)}, {"abs_error_bound": bounds,
                                                     "method": info.get("method")}
        if self.kind == "wks":
            W = wks(lap, p["energies"], sigma=p["sigma"], k=p["k"], method=p["method"])
            note = ("truncated eigen-expansion: no error bound" if p["method"] == "eigen"
                    else "normalised diagonals: no bound is propagated")
            return {"wks": np.asarray(W).reshape(lap.n, -1)}, {"abs_error_bound": None, "note": note}
        if self.kind == "kernel_diagonal":
            d, info = kernel_diagonal(lap, _make_filter(p), method=p["method"], tol=p["tol"],
                                      return_info=True)
            b = {"abs_error_bound": info.get("abs_error_bound"), "method": info.get("method")}
            if "sample_rel_error" in info:
                b["sample_rel_error"] = info["sample_rel_error"]
            if info.get("method") in ("probing", "eigen", "dense"):
                b["note"] = {"probing": "estimate: error measured at sample vertices",
                             "eigen": "truncated eigen-expansion: no error bound",
                             "dense": "dense eigen-decomposition: rounding only"}[info["method"]]
            return {"diagonal": np.asarray(d)}, b
        if self.kind == "distances":
            rows, bounds = [], []
            for s in p["sources"]:
                d, info = _distance(lap, p, s)
                rows.append(np.asarray(d, dtype=float))
                bounds.append(info.get("d2_error_bound"))
            return ({"distances": np.stack(rows), "sources": np.asarray(p["sources"], dtype=np.int64)},
                    {"d2_error_bound": bounds, "method": info.get("method")})
        if self.kind == "eigenvalues":
            from ..linalg import dense_eigs, eigs

            k = p["k"]
            if k > lap.n:
                raise ValueError(f"k = {k} eigenvalues asked of a shape with {lap.n} vertices")
            lam = eigs(lap, k)[0] if k < lap.n else dense_eigs(lap)[0]
            return {"eigenvalues": np.asarray(lam, dtype=float)}, {
                "abs_error_bound": None, "note": "ARPACK shift-invert Lanczos: not certified"}
        out = self.fn(name, lap)
        if isinstance(out, dict):
            arrays = {str(k): np.asarray(v) for k, v in out.items()}
        else:
            arrays = {"result": np.asarray(out)}
        for k, v in arrays.items():
            if v.dtype == object:
                raise TypeError(f"the job returned {k!r} as an object array; return numeric arrays")
        return arrays, {"abs_error_bound": None, "note": "user function"}


def _distance(lap, p, s):
    from ..distances import (biharmonic_distance, commute_time_distance, diffusion_distance,
                             polyharmonic_distance, spectral_distance)

    kw = dict(method=p["method"], tol=p["tol"], return_info=True)
    name = p["filter"]
    if name == "diffusion":
        return diffusion_distance(lap, p["t"], s, **kw)
    if name == "biharmonic":
        return biharmonic_distance(lap, s, **kw)
    if name == "commute_time":
        return commute_time_distance(lap, s, **kw)
    if name == "polyharmonic":
        return polyharmonic_distance(lap, p["order"], s, **kw)
    return spectral_distance(lap, _make_filter(p), s, **kw)
