"""The one cache of a :class:`~spectral_igl.Laplacian`: everything derived from (L, B).

Later stages (factorizations, spectral bounds, eigenpairs, selected-inverse kernels,
spectral operators) store what they compute here, in named slots, so that repeated calls
on one shape never recompute it. ``clear()`` drops everything; ``nbytes`` reports the
memory held. L and B are never modified after construction, so nothing here goes stale.
"""
from __future__ import annotations

import logging
from collections import OrderedDict

import numpy as np
import scipy.sparse as sp

__all__ = ["Cache", "SLOTS", "nbytes_of"]

log = logging.getLogger(__name__)

#: slot name -> (what it holds, most entries kept; None = unbounded). Least recently used
#: entries are evicted first.
SLOTS = {
    "bound": ("spectral bounds: lambda_max, lambda_min_positive, mass_ratio", None),
    "basis": ("B-orthonormal basis of ker L (one indicator per component)", None),
    "factor": ("factorizations of theta B + beta L and of the grounded stiffness", 24),
    "pattern": ("ordering and symbolic LDLT analysis of the pattern of L + B", None),
    "eigen": ("eigenpairs (k -> (evals, evecs)); 'dense' for all of them", 4),
    "diagonal": ("kernel diagonals and diag(B^-1)", 16),
    "kernel": ("selected-inverse kernels, keyed by (filter, tol)", 16),
    "operator": ("spectral operators, keyed by (filter, method, tol, backend)", 32),
}


def nbytes_of(obj) -> int:
    """Bytes held by ``obj``: arrays, sparse matrices, objects with ``nbytes``, containers."""
    if obj is None:
        return 0
    if isinstance(obj, np.ndarray):
        return int(obj.nbytes)
    if sp.issparse(obj):
        return int(sum(getattr(obj, a).nbytes for a in ("data", "indices", "indptr", "row", "col", "offsets")
                       if hasattr(obj, a)))
    nb = getattr(obj, "nbytes", None)
    if isinstance(nb, (int, np.integer)):
        return int(nb)
    if isinstance(obj, (list, tuple)):
        return sum(nbytes_of(x) for x in obj)
    if isinstance(obj, dict):
        return sum(nbytes_of(x) for x in obj.values())
    return 0


class Cache:
    """Named slots of derived quantities of one Laplacian, each an LRU mapping.

    Examples
    --------
    >>> c = Cache()
    >>> c.fetch("bound", "lambda_max", lambda: 8.0)
    8.0
    >>> c.get("bound", "lambda_max")
    8.0
    >>> c.clear(); len(c)
    0
    """

    def __init__(self):
        self._slots = {name: OrderedDict() for name in SLOTS}
        self.hits = 0
        self.misses = 0

    def _slot(self, slot: str) -> OrderedDict:
        try:
            return self._slots[slot]
        except KeyError:
            raise KeyError(f"unknown cache slot {slot!r}; slots are {tuple(SLOTS)}") from None

    def get(self, slot: str, key, default=None):
        """The entry ``key`` of ``slot`` (marked recently used), or ``default``."""
        d = self._slot(slot)
        if key in d:
            d.move_to_end(key)
            return d[key]
        return default

    def put(self, slot: str, key, value):
        """Store ``value``; evicts the least recently used entries beyond the slot's limit."""
        d = self._slot(slot)
        d[key] = value
        d.move_to_end(key)
        limit = SLOTS[slot][1]
        while limit is not None and len(d) > limit:
            old, _ = d.popitem(last=False)
            log.debug("cache: evicted %s %r", slot, old)
        return value

    def fetch(self, slot: str, key, build):
        """The entry ``key`` of ``slot``, computed by ``build()`` and stored when missing."""
        d = self._slot(slot)
        if key in d:
            d.move_to_end(key)
            self.hits += 1
            log.debug("cache hit: %s %r", slot, key)
            return d[key]
        self.misses += 1
        return self.put(slot, key, build())

    def __contains__(self, item) -> bool:
        slot, key = item
        return key in self._slot(slot)

    def keys(self, slot: str):
        """The keys held in ``slot``, least recently used first."""
        return list(self._slot(slot))

    def discard(self, slot: str, key=None) -> None:
        """Drop one entry of ``slot``, or the whole slot when ``key`` is None."""
        d = self._slot(slot)
        if key is None:
            d.clear()
        else:
            d.pop(key, None)

    def clear(self) -> None:
        """Drop every cached factorization and derived quantity."""
        for d in self._slots.values():
            d.clear()

    def __len__(self) -> int:
        return sum(len(d) for d in self._slots.values())

    @property
    def nbytes(self) -> int:
        """Bytes held by the cached arrays, matrices and factorizations."""
        return sum(nbytes_of(v) for d in self._slots.values() for v in d.values())

    def __repr__(self) -> str:
        used = ", ".join(f"{k}={len(d)}" for k, d in self._slots.items() if d)
        return f"Cache({used or 'empty'}; {self.nbytes / 2**20:.1f} MiB)"
