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
    "as_flag",
    "as_nonnegative",
    "describe",
    "as_mesh_arrays",
    "is_mesh_object",
    "as_array",
    "as_delta",
    "DELTAS",
    "MAX_MAGNITUDE",
    "check_magnitude",
    "as_int",
    "as_tol",
    "as_real_in",
    "as_choice",
    "check_finite_result",
    "check_spectral_function",
    "memory_budget",
    "set_memory_budget",
    "check_dense_size",
    "check_tets_have_volume",
]

#: the discrete deltas of a kernel column: B^-1 e_i (converges) or e_i (the survey's Eq. (5))
DELTAS = ("mass", "seed")


def describe(x) -> str:
    """A short, one-line description of ``x`` for error messages.

    Numbers, strings and other builtins are shown with their value; arrays by shape and
    dtype; any other object by its type only (a foreign object's repr can span many lines).
    """
    if isinstance(x, np.ndarray):
        return f"array of shape {x.shape} and dtype {x.dtype}"
    if hasattr(x, "shape") and hasattr(x, "dtype"):
        return f"{type(x).__name__} of shape {x.shape} and dtype {x.dtype}"
    if isinstance(x, (list, tuple, dict, set, frozenset)):
        return f"{type(x).__name__} of length {len(x)}"
    if x is None or isinstance(x, (bool, int, float, complex, str, bytes, np.generic)):
        text = f"{type(x).__name__} {x!r}"
        return text if len(text) <= 120 else text[:117] + "..."
    kind = type(x)
    return f"a {kind.__module__.split('.')[0]}.{kind.__qualname__} object"


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
    return check_magnitude(a, name, hint="rescale the coordinates (lengths, areas and eigenvalues "
                                         "scale with them)")


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


def as_signal(f, n: int, name: str = "f", allow_complex: bool = True,
              max_magnitude: float | None = None) -> np.ndarray:
    """Validate a signal of shape ``(n,)`` or ``(n, k)``, k >= 1; return float64 or complex128.

    Entries beyond ``max_magnitude`` (default :data:`MAX_MAGNITUDE`) are refused; ``inf``
    accepts any finite value (for solvers that also serve intermediate vectors)."""
    a = as_array(f, name)
    if a.dtype.kind == "c" and not allow_complex:
        raise TypeError(f"{name} must be real, got {describe(a)}")
    if a.dtype.kind not in "biufc":
        raise TypeError(f"{name} must be numeric, got {describe(a)}")
    if a.ndim not in (1, 2) or a.shape[0] != n:
        raise ValueError(f"{name} must have shape ({n},) or ({n}, k), got {describe(a)}")
    if a.ndim == 2 and a.shape[1] == 0:
        raise ValueError(f"{name} has no columns: got {describe(a)}; pass (n,) or (n, k) with k >= 1")
    target = np.dtype(np.complex128 if a.dtype.kind == "c" else np.float64)
    if a.dtype != target:
        check_dense_size(float(target.itemsize) * a.size, f"{name} of shape {a.shape} as {target}",
                         "pass fewer columns at a time")
    a = a.astype(np.complex128 if a.dtype.kind == "c" else np.float64, copy=False)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or inf")
    return check_magnitude(a, name, MAX_MAGNITUDE if max_magnitude is None else max_magnitude)


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


def as_flag(x, name: str) -> bool:
    """Validate a yes/no option: ``True`` or ``False`` only (never read by truthiness)."""
    if not isinstance(x, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {describe(x)}")
    return bool(x)


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


# ---- mesh objects of other packages ------------------------------------------------------
# VTK cell type ids (pyvista's ``cells_dict`` keys) and meshio's cell names
_VTK_TRIANGLE, _VTK_TETRA = 5, 10


def is_mesh_object(obj) -> bool:
    """Whether ``obj`` looks like a pyvista, trimesh or meshio mesh (duck-typed).

    Recognised: objects with ``points`` and ``faces`` (pyvista ``PolyData``), ``points``
    and ``cells_dict`` (pyvista ``UnstructuredGrid``, ``meshio.Mesh``), or ``vertices``
    (``trimesh.Trimesh``, ``trimesh.PointCloud``). Plain arrays, lists and tuples are not.
    """
    if isinstance(obj, (np.ndarray, list, tuple, str, bytes, dict)) or obj is None:
        return False
    return (hasattr(obj, "points") and (hasattr(obj, "faces") or hasattr(obj, "cells_dict"))) \
        or hasattr(obj, "vertices")


def _polydata_faces(faces, name: str) -> np.ndarray:
    """Triangles from VTK's flat ``[k, i_1 .. i_k, k, ...]`` face list (fans for k > 3)."""
    faces = np.asarray(faces, dtype=np.int64).ravel()
    if faces.size == 0:
        return np.zeros((0, 3), dtype=np.int64)
    if faces.size % 4 == 0 and np.all(faces[::4] == 3):
        return faces.reshape(-1, 4)[:, 1:].copy()
    tris, i = [], 0
    while i < faces.size:
        k = int(faces[i])
        if k < 3 or i + 1 + k > faces.size:
            raise ValueError(f"{name}: malformed face list (a face with {k} vertices at offset {i})")
        poly = faces[i + 1:i + 1 + k]
        tris.extend((poly[0], poly[j], poly[j + 1]) for j in range(1, k - 1))
        i += 1 + k
    return np.asarray(tris, dtype=np.int64).reshape(-1, 3)


def _cells_from_dict(cells: dict, name: str) -> np.ndarray | None:
    """Tetrahedra if there are any, else triangles, from a pyvista/meshio ``cells_dict``."""
    def get(*keys):
        for key, val in cells.items():
            if key in keys or (isinstance(key, (int, np.integer)) and int(key) in keys):
                return np.asarray(val)
        return None

    tets = get(_VTK_TETRA, "tetra")
    if tets is not None and len(tets):
        return tets
    tris = get(_VTK_TRIANGLE, "triangle")
    if tris is not None and len(tris):
        return tris
    if cells:
        raise ValueError(f"{name} holds neither tetrahedra nor triangles (cell types "
                         f"{sorted(str(k) for k in cells)}); triangulate it first")
    return None


def as_mesh_arrays(V, F=None, name: str = "V", need_cells: bool = True):
    """``(V, F)`` arrays from a mesh object, or the arrays themselves.

    Every public function that takes ``(V, F)`` passes its arguments through here, so it
    also accepts a pyvista ``PolyData`` (polygons are fan-triangulated) or
    ``UnstructuredGrid`` (its tetrahedra, else its triangles), a ``trimesh.Trimesh``,
    a ``trimesh.PointCloud`` or a ``meshio.Mesh`` in place of ``V`` (with ``F`` omitted).
    Neither package is imported: the objects are recognised by their attributes.

    Parameters
    ----------
    V : (n, 3) float or mesh object
        Vertex positions, or a mesh object.
    F : (m, 3) or (m, 4) int, optional
        Elements; must be omitted when ``V`` is a mesh object.
    name : str
        Name of ``V`` in error messages.
    need_cells : bool
        Raise when no elements result (``False`` for point clouds).

    Returns
    -------
    V : (n, 3) array_like
        The points (not yet validated: pass them to :func:`as_points`).
    F : (m, 3) or (m, 4) array_like, or None
        Triangles or tetrahedra; ``None`` when the object has no cells (a point cloud),
        and ``F`` unchanged when ``V`` is not a mesh object.

    Raises
    ------
    TypeError
        ``V`` is a mesh object and ``F`` is given as well, or ``need_cells`` and there
        are no elements.
    ValueError
        The object holds cells that are neither triangles, polygons nor tetrahedra.

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl._validate import as_mesh_arrays
    >>> class Tri:  # anything with .vertices and .faces, like trimesh.Trimesh
    ...     vertices = np.eye(3); faces = np.array([[0, 1, 2]])
    >>> V, F = as_mesh_arrays(Tri())
    >>> V.shape, F.tolist()
    ((3, 3), [[0, 1, 2]])
    """
    kind = type(V).__name__ if is_mesh_object(V) else None
    V, F = _mesh_arrays(V, F, name)
    if kind is not None and F is not None:
        _warn_coincident(V, kind)
    if need_cells and F is None:
        raise TypeError(f"F is missing: pass (V, F) arrays, or a mesh object with triangles or "
                        f"tetrahedra as {name}; got {name} = {describe(V)}")
    return V, F


def _warn_coincident(points, kind: str) -> None:
    """Warn when points of a mesh object coincide: the object is cut along them.

    File readers that split vertices at texture seams or normal creases (pyvista's and
    trimesh's OBJ readers do) give such objects; every cut becomes a boundary.
    """
    import warnings

    P = np.asarray(points)
    if P.ndim != 2 or len(P) < 2:
        return
    dup = len(P) - len(np.unique(P, axis=0))
    if dup:
        warnings.warn(f"{dup} of the {len(P)} points of the {kind} coincide with another point, "
                      f"so the shape is cut along them (a reader that splits vertices at texture "
                      f"seams does this). Merge them first (pyvista: mesh.clean(); trimesh: "
                      f"mesh.merge_vertices(merge_tex=True, merge_norm=True)) or read the file "
                      f"with spectral_igl.io.read_mesh", RuntimeWarning, stacklevel=4)


def _mesh_arrays(V, F, name):
    if not is_mesh_object(V):
        return V, F
    what = f"{name} ({type(V).__module__.split('.')[0]}.{type(V).__name__})"
    if F is not None:
        raise TypeError(f"{name} is a mesh object ({type(V).__name__}): do not pass F as well, "
                        f"got F = {describe(F)}")
    if hasattr(V, "vertices") and not hasattr(V, "points"):          # trimesh
        pts = np.asarray(V.vertices)
        faces = getattr(V, "faces", None)
        cells = None if faces is None or len(faces) == 0 else np.asarray(faces)
        return pts, cells
    pts = np.asarray(V.points)
    if hasattr(V, "cells_dict") and not hasattr(V, "faces"):         # UnstructuredGrid, meshio
        return pts, _cells_from_dict(dict(V.cells_dict), what)
    tris = _polydata_faces(V.faces, what)                             # PolyData
    return pts, (tris if len(tris) else None)
def as_delta(delta) -> str:
    """Validate the ``delta`` argument of kernels and distances (one of :data:`DELTAS`)."""
    if not isinstance(delta, str) or delta not in DELTAS:
        raise ValueError(f"delta must be 'mass' (B^-1 e_i, converges) or 'seed' (e_i), got {describe(delta)}")
    return delta


# --- magnitudes, integers, tolerances, choices -------------------------------------------

#: largest magnitude accepted in coordinates and signals: squares and B-norms of larger
#: values overflow double precision (every operator here is linear, so rescale instead)
MAX_MAGNITUDE = 1e100


def check_magnitude(a: np.ndarray, name: str, limit: float = MAX_MAGNITUDE,
                    hint: str = "rescale it (every operator here is linear in the signal)") -> np.ndarray:
    """Refuse a finite array whose largest entry exceeds ``limit`` in magnitude.

    Sums of squares of such values overflow to inf; the message says the size found.
    """
    if a.size:
        top = float(np.max(np.abs(a)))
        if top > limit:
            raise ValueError(f"{name} has entries of magnitude up to {top:.3g}, beyond {limit:.0e}: "
                             f"squares and norms of such values overflow; {hint}")
    return a


def as_int(x, name: str, lo: int | None = None, hi: int | None = None) -> int:
    """Validate an integer (Python or numpy; not bool, float or str) in ``[lo, hi]``."""
    if isinstance(x, np.ndarray) and x.ndim == 0 and x.dtype.kind in "iu":
        x = x.item()
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (numbers.Integral, np.integer)):
        raise TypeError(f"{name} must be an integer, got {describe(x)}")
    x = int(x)
    if (lo is not None and x < lo) or (hi is not None and x > hi):
        lo_s = "-inf" if lo is None else str(lo)
        hi_s = "inf" if hi is None else str(hi)
        raise ValueError(f"{name} must be an integer in [{lo_s}, {hi_s}], got {x}")
    return x


def as_tol(x, name: str = "tol", allow_zero: bool = False) -> float:
    """Validate a relative tolerance: finite, in (0, 1) (``[0, 1)`` with ``allow_zero``)."""
    x = _as_real(x, name)
    if not ((0.0 <= x if allow_zero else 0.0 < x) and x < 1.0):
        rng = "[0, 1)" if allow_zero else "(0, 1)"
        raise ValueError(f"{name} must be a relative tolerance in {rng}, got {x}")
    return x


def as_real_in(x, name: str, lo: float | None = None, hi: float | None = None) -> float:
    """Validate a finite real number in ``[lo, hi]``."""
    x = _as_real(x, name)
    if (lo is not None and x < lo) or (hi is not None and x > hi):
        raise ValueError(f"{name} must be in [{lo if lo is not None else '-inf'}, "
                         f"{hi if hi is not None else 'inf'}], got {x}")
    return x


def as_choice(x, name: str, choices) -> str:
    """Validate a string option against its admissible values."""
    choices = tuple(choices)
    if not isinstance(x, str) or x not in choices:
        raise ValueError(f"{name} must be one of {choices}, got {describe(x)}")
    return x


def check_finite_result(x, what: str, hint: str = "") -> np.ndarray:
    """Raise instead of returning NaN or inf: ``what`` names the result, ``hint`` the way out."""
    a = np.asarray(x)
    if a.dtype.kind in "fc" and not np.all(np.isfinite(a)):
        bad = int(np.count_nonzero(~np.isfinite(a)))
        raise ValueError(f"{what} is not finite at {bad} of {a.size} entries" + (f": {hint}" if hint else ""))
    return x


def check_spectral_function(fn, lo: float, hi: float, name: str = "filter", singular: bool = False,
                            samples: int = 64) -> None:
    """Evaluate a user function of the spectrum once on a sample of ``[lo, hi]``.

    Refuses a function that raises, returns the wrong shape, or returns NaN/inf there
    (a singular filter is not evaluated at 0, where it is defined as 0).
    """
    s = np.linspace(lo, hi, samples)
    if singular:
        s = s[s > 0]
    try:
        with np.errstate(all="ignore"):
            y = np.asarray(fn(s))
    except (ArithmeticError, ValueError, TypeError) as err:
        raise ValueError(f"{name} failed on an array of {s.size} eigenvalues in [{lo:.3g}, {hi:.3g}]: "
                         f"{err}") from err
    if y.shape != s.shape:
        raise ValueError(f"{name} must map an array of eigenvalues of shape {s.shape} to the same shape "
                         f"(it is applied elementwise), got {describe(y)}")
    if y.dtype.kind not in "biufc":
        raise ValueError(f"{name} must return numbers, got {describe(y)}")
    finite = np.isfinite(y)
    if not finite.all():
        where = float(s[~finite][0])
        hint = ("a filter singular at 0 such as 1/s must be declared with filters.Filter(fn, singular=True)"
                if where == 0.0 and finite[1:].all() else
                "check its parameters (e.g. a time so large that t * lambda overflows)")
        raise ValueError(f"{name} is not finite on the spectrum [{lo:.3g}, {hi:.3g}] (e.g. at "
                         f"{where:.3g}): {hint}")


# --- the size guard --------------------------------------------------------------------------

_BUDGET = [None]          # bytes set by set_memory_budget, None: automatic
#: fraction of MemAvailable a single dense array may take by default
BUDGET_FRACTION = 0.25
#: fallback when /proc/meminfo cannot be read
BUDGET_FALLBACK = 2 * 1024 ** 3


def _available_memory() -> int | None:
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def memory_budget() -> int:
    r"""Bytes that one dense allocation or dense eigenproblem may take.

    In order: :func:`set_memory_budget`, the environment variable
    ``SPECTRAL_IGL_MEMORY_BUDGET`` (bytes), a quarter of ``MemAvailable`` in
    ``/proc/meminfo``, or 2 GiB.

    Returns
    -------
    int
        Bytes.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> sig.set_memory_budget(2**30)
    >>> sig.memory_budget()
    1073741824
    >>> sig.set_memory_budget(None); sig.memory_budget() > 0
    True
    """
    import os

    if _BUDGET[0] is not None:
        return _BUDGET[0]
    env = os.environ.get("SPECTRAL_IGL_MEMORY_BUDGET")
    if env:
        try:
            value = int(float(env))
        except ValueError as err:
            raise ValueError(f"SPECTRAL_IGL_MEMORY_BUDGET must be a number of bytes, got {env!r}") from err
        if value <= 0:
            raise ValueError(f"SPECTRAL_IGL_MEMORY_BUDGET must be positive, got {env!r}")
        return value
    avail = _available_memory()
    return int(BUDGET_FRACTION * avail) if avail else BUDGET_FALLBACK


def set_memory_budget(nbytes) -> None:
    r"""Set the bytes one dense allocation may take (``None``: back to the automatic budget).

    A dense computation (dense eigenpairs, pairwise distance matrices, ...) that would need
    more is refused with a ValueError naming the size and a spectrum-free alternative.

    Parameters
    ----------
    nbytes : int or None
        Positive number of bytes, or ``None`` for the automatic budget
        (:func:`memory_budget`).

    Returns
    -------
    None

    Examples
    --------
    >>> import spectral_igl as sig
    >>> sig.set_memory_budget(10**9); sig.memory_budget()
    1000000000
    >>> sig.set_memory_budget(None)
    """
    if nbytes is None:
        _BUDGET[0] = None
        return
    _BUDGET[0] = as_int(nbytes, "nbytes", lo=1)


def _size(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{n:.1f} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024.0
    return f"{n:.1f} PiB"  # pragma: no cover


def check_dense_size(nbytes, what: str, alternative: str = "") -> None:
    """Refuse up front a dense allocation of ``nbytes`` beyond :func:`memory_budget`.

    ``what`` describes the array (e.g. "a (100000, 100000) distance matrix"),
    ``alternative`` the sparse or streaming way to get what is wanted.
    """
    nbytes = float(nbytes)
    budget = memory_budget()
    if not nbytes <= budget:
        raise ValueError(f"{what} would take {_size(nbytes)}, beyond the memory budget of {_size(budget)}"
                         + (f"; {alternative}" if alternative else "")
                         + " (raise the budget with spectral_igl.set_memory_budget(bytes) or "
                           "SPECTRAL_IGL_MEMORY_BUDGET)")


# --- element checks ----------------------------------------------------------------------

def check_tets_have_volume(V: np.ndarray, T: np.ndarray, rel_tol: float = 1e-12) -> None:
    """Refuse (m, 4) index arrays whose "tetrahedra" mostly have zero volume.

    Quads (four coplanar corners per row) have the shape of tetrahedra; read as tets they
    would give a meaningless Laplacian. ``V`` (n, 3) float and ``T`` (m, 4) int, validated.
    """
    if T.ndim != 2 or T.shape[1] != 4 or V.shape[1] != 3 or T.shape[0] == 0:
        return
    e1, e2, e3 = (V[T[:, k]] - V[T[:, 0]] for k in (1, 2, 3))
    with np.errstate(over="ignore", invalid="ignore"):
        vol = np.abs(np.einsum("ij,ij->i", np.cross(e1, e2), e3))
        scale = np.max(np.linalg.norm(np.concatenate([e1, e2, e3]), axis=1)) ** 3
    flat = ~(vol > rel_tol * scale) if scale > 0 else np.ones(len(T), bool)
    if 2 * np.count_nonzero(flat) > len(T):
        raise ValueError(f"T of shape {T.shape} is degenerate: zero volume in {np.count_nonzero(flat)} of its "
                         "rows (the four corners are coplanar); these look like quads, not tetrahedra: use "
                         "laplacian(V, F, elements='polygon') or split each quad into two triangles")
