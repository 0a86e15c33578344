"""Argument checks of the generators: counts and lengths, refused before any allocation."""
from __future__ import annotations

import numbers

import numpy as np

#: most vertices (or eigenvalues, points, cells) a generator makes
MAX_COUNT = 10 ** 7


def count(x, name: str, lo: int = 0, hi: int = MAX_COUNT) -> int:
    """An integer in ``[lo, hi]`` (not bool, float or str)."""
    if isinstance(x, np.ndarray) and x.ndim == 0 and x.dtype.kind in "iu":
        x = x.item()
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (numbers.Integral, np.integer)):
        raise TypeError(f"{name} must be an integer, got {type(x).__name__} {x!r}"[:200])
    x = int(x)
    if not lo <= x <= hi:
        raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {x}")
    return x


def real(x, name: str, positive: bool = False, nonnegative: bool = False, limit: float = 1e100) -> float:
    """A finite real number of magnitude at most ``limit`` (optionally > 0 or >= 0)."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{name} must be a real number, got {type(x).__name__} {x!r}"[:200])
    x = float(x)
    if not np.isfinite(x) or abs(x) > limit:
        raise ValueError(f"{name} must be finite and at most {limit:g} in magnitude, got {x}")
    if positive and not x > 0:
        raise ValueError(f"{name} must be positive, got {x}")
    if nonnegative and not x >= 0:
        raise ValueError(f"{name} must be non-negative, got {x}")
    return x


def triple(x, name: str, kind: str):
    """Three grid counts (``kind="count"``) or three positive lengths (``"length"``)."""
    try:
        items = list(x)
    except TypeError:
        raise TypeError(f"{name} must be three numbers, got {type(x).__name__} {x!r}"[:200]) from None
    if len(items) != 3:
        raise ValueError(f"{name} must be three numbers, got {len(items)}")
    if kind == "count":
        out = tuple(count(v, name, lo=1, hi=10 ** 4) for v in items)
        if np.prod([v + 1 for v in out], dtype=float) > MAX_COUNT:
            raise ValueError(f"{name} {out} makes more than {MAX_COUNT} vertices")
        return out
    return tuple(real(v, name, positive=True) for v in items)
