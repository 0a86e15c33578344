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

__all__ = ["Cache", "SLOTS", "nbytes_of", "available_memory", "BUDGET_FRACTION"]

log = logging.getLogger(__name__)

#: slot name -> (what it holds, most entries kept; None = unbounded). Least recently used
#: entries are evicted first.
SLOTS = {
    "bound": ("spectral bounds: lambda_max, lambda_min_positive, mass_ratio, the uniformization "
              "rate and its stochastic matrix", None),
    "basis": ("B-orthonormal basis of ker L (one indicator per component)", None),
    "factor": ("factorizations of theta B + beta L and of the grounded stiffness", 24),
    "pattern": ("ordering and symbolic LDLT analysis of the pattern of L + B", None),
    "eigen": ("eigenpairs (k -> (evals, evecs)); 'dense' for all of them", 4),
    "diagonal": ("kernel diagonals and diag(B^-1)", 16),
    "kernel": ("selected-inverse kernels, keyed by (filter, tol)", 16),
    "operator": ("spectral operators, keyed by (filter, method, tol, backend)", 32),
}


#: default byte budget of the ``"factor"`` slot, as a fraction of the available memory
BUDGET_FRACTION = 0.25


def available_memory() -> int:
    """Bytes of memory available to new allocations (``MemAvailable`` of /proc/meminfo; 8 GiB
    where that file is absent)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 8 * 2 ** 30


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
    r"""Named slots of derived quantities of one Laplacian, each an LRU mapping.

    The ``"factor"`` slot also has a byte budget (``factor_budget``, default
    :data:`BUDGET_FRACTION` of :func:`available_memory` when the cache is made): when the
    factorizations it holds exceed it, the least recently used are evicted until they fit
    (the newest entry is always kept). ``nbytes`` of each entry is exact for the package's
    LDLᵀ and SuperLU factors and an estimate for CHOLMOD's.

    Parameters
    ----------
    factor_budget : int, optional
        Bytes the ``"factor"`` slot may hold (default: :data:`BUDGET_FRACTION` of the
        available memory).

    Examples
    --------
    >>> c = Cache()
    >>> c.fetch("bound", "lambda_max", lambda: 8.0)
    8.0
    >>> c.get("bound", "lambda_max")
    8.0
    >>> c.clear(); len(c)
    0
    >>> c = Cache(factor_budget=100)
    >>> _ = c.put("factor", "a", np.zeros(10)); _ = c.put("factor", "b", np.zeros(10))
    >>> c.keys("factor")          # 160 bytes > 100: the older one is evicted
    ['b']
    """

    def __init__(self, factor_budget: int | None = None):
        self._slots = {name: OrderedDict() for name in SLOTS}
        self._bytes = {name: {} for name in SLOTS}
        self.hits = 0
        self.misses = 0
        self.evictions = 0
        self.factor_budget = factor_budget

    @property
    def factor_budget(self) -> int:
        """Byte budget of the ``"factor"`` slot (settable; None restores the default)."""
        return self._budget

    @factor_budget.setter
    def factor_budget(self, value) -> None:
        if value is None:
            value = int(BUDGET_FRACTION * available_memory())
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
                or not value >= 0:
            raise ValueError(f"factor_budget must be a non-negative number of bytes, got {value!r}")
        self._budget = int(value)
        self._evict("factor")

    def slot_nbytes(self, slot: str) -> int:
        """Bytes held by one slot."""
        self._slot(slot)
        return int(sum(self._bytes[slot].values()))

    def _evict(self, slot: str) -> None:
        d = self._slot(slot)
        limit = SLOTS[slot][1]
        while limit is not None and len(d) > limit:
            self._drop(slot, next(iter(d)))
        if slot == "factor":
            while len(d) > 1 and self.slot_nbytes(slot) > self._budget:
                self._drop(slot, next(iter(d)))

    def _drop(self, slot, key):
        self._slots[slot].pop(key, None)
        self._bytes[slot].pop(key, None)
        self.evictions += 1
        log.debug("cache: evicted %s %r", slot, key)

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
        self._bytes[slot][key] = nbytes_of(value)
        self._evict(slot)
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
            self._bytes[slot].clear()
        else:
            d.pop(key, None)
            self._bytes[slot].pop(key, None)

    def clear(self) -> None:
        """Drop every cached factorization and derived quantity."""
        for d in self._slots.values():
            d.clear()
        for b in self._bytes.values():
            b.clear()

    def __len__(self) -> int:
        return sum(len(d) for d in self._slots.values())

    @property
    def nbytes(self) -> int:
        """Bytes held by the cached arrays, matrices and factorizations."""
        return sum(nbytes_of(v) for d in self._slots.values() for v in d.values())

    def __repr__(self) -> str:
        used = ", ".join(f"{k}={len(d)}" for k, d in self._slots.items() if d)
        return f"Cache({used or 'empty'}; {self.nbytes / 2**20:.1f} MiB)"
