"""Input validation shared by every public entry point.

Everything that reaches libigl or a sparse factorization passes through one of
these functions first, so that bad input ends in a ``ValueError``/``TypeError``
that names what was received -- never a segfault inside C++ or a silent NaN.
"""
from __future__ import annotations

import numbers

import numpy as np

__all__ = [
    "as_points",
    "as_cells",
    "as_signal",
    "as_index",
    "as_indices",
    "as_positive",
    "as_nonnegative",
    "describe",
    "as_array",
    "as_delta",
    "DELTAS",
]

#: the discrete deltas of a kernel column: B^-1 e_i (converges) or e_i (the survey's Eq. (5))
DELTAS = ("mass", "seed")


def describe(x) -> str:
    """A short description of ``x`` for error messages."""
    if isinstance(x, np.ndarray):
        return f"array of shape {x.shape} and dtype {x.dtype}"
    if hasattr(x, "shape") and hasattr(x, "dtype"):
        return f"{type(x).__name__} of shape {x.shape} and dtype {x.dtype}"
    if isinstance(x, (list, tuple)):
        return f"{type(x).__name__} of length {len(x)}"
    return f"{type(x).__name__} {x!r}"[:200]


def as_array(x, name: str) -> np.ndarray:
    if x is None:
        raise TypeError(f"{name} must be an array, got None")
    if isinstance(x, (str, bytes, dict, set)):
        raise TypeError(f"{name} must be an array, got {describe(x)}")
    if hasattr(x, "toarray") and not isinstance(x, np.ndarray):
        raise TypeError(f"{name} must be a dense array, got sparse {describe(x)}")
    try:
        a = np.asarray(x)
    except (ValueError, TypeError) as err:  # ragged lists and the like
        raise TypeError(f"{name} must be a rectangular numeric array, got {describe(x)}") from err
    if a.dtype == object:
        raise TypeError(f"{name} must be a rectangular numeric array, got {describe(x)}")
    return a


def as_points(V, name: str = "V", dims=(2, 3), min_rows: int = 1) -> np.ndarray:
    """Validate an ``(n, d)`` array of coordinates; return float64, C-contiguous.

    ``dims`` lists the admissible numbers of columns.
    """
    a = as_array(V, name)
    if a.dtype.kind not in "biuf":
        raise TypeError(f"{name} must hold real numbers, got {describe(a)}")
    if a.ndim != 2 or a.shape[1] not in tuple(dims):
        want = " or ".join(f"(n, {d})" for d in dims)
        raise ValueError(f"{name} must have shape {want}, got {describe(a)}")
    if a.shape[0] < min_rows:
        raise ValueError(f"{name} must have at least {min_rows} row(s), got {describe(a)}")
    a = np.ascontiguousarray(a, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        bad = int(np.count_nonzero(~np.isfinite(a).all(axis=1)))
        raise ValueError(f"{name} contains NaN or inf in {bad} row(s)")
    return a


def as_cells(F, n: int, name: str = "F", sizes=(3, 4)) -> np.ndarray:
    """Validate an ``(m, k)`` integer array of element indices into ``n`` vertices.

    Returns int64, C-contiguous. Rejects floats that are not whole numbers,
    negative and out-of-range indices, and empty arrays.
    """
    a = as_array(F, name)
    if a.ndim != 2 or a.shape[1] not in tuple(sizes):
        want = " or ".join(f"(m, {k})" for k in sizes)
        raise ValueError(f"{name} must have shape {want}, got {describe(a)}")
    if a.shape[0] == 0:
        raise ValueError(f"{name} is empty: got {describe(a)}")
    if a.dtype.kind == "f":
        if not np.all(np.isfinite(a)) or np.any(a != np.round(a)):
            raise TypeError(f"{name} must hold integer indices, got non-integral {describe(a)}")
    elif a.dtype.kind not in "iub":
        raise TypeError(f"{name} must hold integer indices, got {describe(a)}")
    a = np.ascontiguousarray(a, dtype=np.int64)
    lo, hi = int(a.min()), int(a.max())
    if lo < 0:
        raise ValueError(f"{name} has a negative index ({lo})")
    if hi >= n:
        raise ValueError(f"{name} has index {hi} but there are only {n} vertices")
    return a


def as_signal(f, n: int, name: str = "f", allow_complex: bool = True) -> np.ndarray:
    """Validate a signal of shape ``(n,)`` or ``(n, k)``; return float64 or complex128."""
    a = as_array(f, name)
    if a.dtype.kind == "c" and not allow_complex:
        raise TypeError(f"{name} must be real, got {describe(a)}")
    if a.dtype.kind not in "biufc":
        raise TypeError(f"{name} must be numeric, got {describe(a)}")
    if a.ndim not in (1, 2) or a.shape[0] != n:
        raise ValueError(f"{name} must have shape ({n},) or ({n}, k), got {describe(a)}")
    a = a.astype(np.complex128 if a.dtype.kind == "c" else np.float64, copy=False)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or inf")
    return a


def as_index(i, n: int, name: str = "source") -> int:
    """Validate a single vertex index in ``[0, n)``."""
    if isinstance(i, (bool, np.bool_)) or not isinstance(i, (numbers.Integral, np.integer)):
        if isinstance(i, np.ndarray) and i.ndim == 0 and i.dtype.kind in "iu":
            i = int(i)
        else:
            raise TypeError(f"{name} must be an integer vertex index, got {describe(i)}")
    i = int(i)
    if not 0 <= i < n:
        raise ValueError(f"{name} must be a vertex index in [0, {n}), got {i}")
    return i


def as_indices(idx, n: int, name: str = "sources", allow_empty: bool = False) -> np.ndarray:
    """Validate a 1-D array of vertex indices in ``[0, n)``; scalars become length 1."""
    a = as_array(idx, name)
    if a.ndim == 0:
        a = a.reshape(1)
    if a.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array of vertex indices, got {describe(a)}")
    if a.size == 0:
        if allow_empty:
            return a.astype(np.int64)
        raise ValueError(f"{name} is empty")
    if a.dtype.kind == "b":
        raise TypeError(f"{name} must hold integer indices, got booleans")
    if a.dtype.kind == "f" and np.all(np.isfinite(a)) and np.all(a == np.round(a)):
        a = a.astype(np.int64)
    if a.dtype.kind not in "iu":
        raise TypeError(f"{name} must hold integer indices, got {describe(a)}")
    a = a.astype(np.int64)
    if a.min() < 0 or a.max() >= n:
        bad = a[(a < 0) | (a >= n)][0]
        raise ValueError(f"{name} must hold vertex indices in [0, {n}), got {int(bad)}")
    return a


def _as_real(x, name: str) -> float:
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (numbers.Real, np.floating, np.integer)):
        if isinstance(x, np.ndarray) and x.ndim == 0 and x.dtype.kind in "iuf":
            x = x.item()
        else:
            raise TypeError(f"{name} must be a real number, got {describe(x)}")
    x = float(x)
    if not np.isfinite(x):
        raise ValueError(f"{name} must be finite, got {x}")
    return x


def as_positive(x, name: str) -> float:
    """Validate a finite real number > 0."""
    x = _as_real(x, name)
    if x <= 0:
        raise ValueError(f"{name} must be positive, got {x}")
    return x


def as_nonnegative(x, name: str) -> float:
    """Validate a finite real number >= 0."""
    x = _as_real(x, name)
    if x < 0:
        raise ValueError(f"{name} must be non-negative, got {x}")
    return x


def as_delta(delta) -> str:
    """Validate the ``delta`` argument of kernels and distances (one of :data:`DELTAS`)."""
    if not isinstance(delta, str) or delta not in DELTAS:
        raise ValueError(f"delta must be 'mass' (B^-1 e_i, converges) or 'seed' (e_i), got {describe(delta)}")
    return delta
