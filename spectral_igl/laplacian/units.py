r"""Times in the shape's own units: the one rule for every argument that is a diffusion time.

A diffusion time has the units of a squared length: on a surface scaled by :math:`s` the
eigenvalues of :math:`B^{-1}L` scale by :math:`s^{-2}`, so :math:`K_t` on the scaled shape
equals :math:`s^{-2} K_{t/s^2}` on the original. A time that means the same thing on every
mesh is therefore a number times a squared length of the shape:

=============  =====================================================================
``time_unit``  a time ``t`` means :math:`t \times`
=============  =====================================================================
``"absolute"`` 1 (the default everywhere: ``t`` as given)
``"shape"``    the shape's measure to the power :math:`2/d`: its area on a surface
               (:math:`d = 2`: triangle, polygon meshes and point clouds), its
               volume\ :sup:`2/3` on a solid (:math:`d = 3`: tetrahedra, voxels)
``"area"``     the total area :math:`1^\top B 1` (surfaces only)
``"volume"``   the total volume to the power 2/3 (solids only)
``"h2"``       the squared mean edge length :math:`h^2` (resolution, not size: the
               same number of rings around a source on every mesh)
=============  =====================================================================

Every public function that takes a time accepts ``time_unit`` with these values and converts
with :func:`shape_time`; what it reports (``info["time"]``, stored results) is the absolute
time it used.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .._validate import as_choice, as_positive, describe
from ._operator import Laplacian

__all__ = ["TIME_UNITS", "dimension", "mean_edge_length", "time_scale", "shape_time", "optional_time", "time_label"]

TIME_UNITS = ("absolute", "shape", "area", "volume", "h2")

#: intrinsic dimension of each domain (``None``: a graph or a bare matrix has no geometry)
_DIMENSION = {"triangle": 2, "polygon": 2, "points": 2, "tet": 3, "voxels": 3}


def dimension(lap: Laplacian) -> int | None:
    r"""Intrinsic dimension d of the domain: 2 for surfaces, 3 for solids, None without geometry.

    Parameters
    ----------
    lap : Laplacian

    Returns
    -------
    int or None
        2 for triangle and polygon meshes and point clouds, 3 for tetrahedra, the mask's
        dimension for voxels, ``None`` for a graph or a bare matrix.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.data_generators import box_tets
    >>> from spectral_igl.laplacian.units import dimension
    >>> dimension(sig.laplacian(*icosphere(1))), dimension(sig.laplacian(*box_tets((2, 2, 2))))
    (2, 3)
    """
    if lap.domain == "voxels":
        return int(np.asarray(lap.data["mask"]).ndim)
    return _DIMENSION.get(lap.domain)


def _positions(lap):
    for key in ("V", "P"):
        if key in lap.data:
            return np.asarray(lap.data[key], dtype=float)
    return None


def _edges(lap) -> np.ndarray:
    """The unique edges of the elements when there are some, else of the pattern of L."""
    C = lap.data.get("F", lap.data.get("T"))
    if C is not None and lap.domain in ("triangle", "tet"):
        C = np.asarray(C)
        pairs = np.vstack([C[:, [a, b]] for a in range(C.shape[1]) for b in range(a + 1, C.shape[1])])
    elif lap.domain == "polygon":
        pairs = np.vstack([np.column_stack([f.ravel(), np.roll(f, -1, axis=1).ravel()])
                           for f in lap.data["faces"] if len(f)])
    else:
        U = sp.triu(lap.L, k=1).tocoo()
        pairs = np.column_stack([U.row, U.col])
    pairs = np.sort(pairs, axis=1)
    return np.unique(pairs[pairs[:, 0] != pairs[:, 1]], axis=0)


def mean_edge_length(lap: Laplacian) -> float:
    r"""Mean length :math:`h` of the unique edges of the elements (or of the neighbour graph), cached.

    Parameters
    ----------
    lap : Laplacian
        A Laplacian with vertex positions (meshes, point clouds).

    Returns
    -------
    h : float
        The unit of ``time_unit="h2"`` is :math:`h^2`.

    Raises
    ------
    ValueError
        When ``lap`` has no positions or no edge.

    Examples
    --------
    The icosahedron's edge on the unit sphere is :math:`4/\sqrt{10 + 2\sqrt 5}`:

    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> import numpy as np
    >>> from spectral_igl.laplacian import mean_edge_length
    >>> h = mean_edge_length(sig.laplacian(*icosphere(0)))
    >>> bool(np.isclose(h, 4 / np.sqrt(10 + 2 * np.sqrt(5))))
    True
    """
    def build():
        P = _positions(lap)
        if P is None:
            raise ValueError(f"time_unit='h2' needs vertex positions; this {lap.domain!r} Laplacian "
                             "has none: give an absolute time")
        E = _edges(lap)
        if not len(E):
            raise ValueError("time_unit='h2' needs at least one edge; this Laplacian has none")
        return float(np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1).mean())

    return lap.cache.fetch("bound", "mean_edge_length", build)


def time_scale(lap: Laplacian, unit: str = "shape") -> float:
    r"""The absolute time that one unit of ``unit`` stands for on ``lap`` (see the module's table).

    Parameters
    ----------
    lap : Laplacian
    unit : {"shape", "absolute", "area", "volume", "h2"}
        Default ``"shape"``.

    Returns
    -------
    float
        1 for ``"absolute"``, the area :math:`A = 1^\top B 1` (surfaces) or the volume
        :math:`V^{2/3}` (solids) for ``"shape"``, :math:`h^2` for ``"h2"``.

    Notes
    -----
    A time has the units of a squared length: on a shape scaled by :math:`s` the eigenvalues
    of :math:`B^{-1}L` scale by :math:`s^{-2}`, so :math:`t\,A^{2/d}` means the same on every
    size.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> bool(sig.time_scale(lap) == lap.area()), sig.time_scale(lap, "absolute")
    (True, 1.0)
    """
    unit = as_choice(unit, "time_unit", TIME_UNITS)
    if unit == "absolute":
        return 1.0
    if unit == "h2":
        return mean_edge_length(lap) ** 2
    d = dimension(lap)
    if d is None:
        raise ValueError(f"time_unit={unit!r} needs a surface or a solid; this is a {lap.domain!r} "
                         "Laplacian without one: give an absolute time")
    if unit == "area" and d != 2:
        raise ValueError(f"time_unit='area' is for surfaces; this {lap.domain!r} Laplacian is "
                         f"{d}-dimensional: use 'volume' or 'shape'")
    if unit == "volume" and d != 3:
        raise ValueError(f"time_unit='volume' is for solids; this {lap.domain!r} Laplacian is "
                         f"{d}-dimensional: use 'area' or 'shape'")
    return lap.area() ** (2.0 / d)


def shape_time(lap: Laplacian, t, unit: str = "shape", name: str = "t"):
    r"""The absolute time(s) for ``t`` given in ``unit``: ``t * time_scale(lap, unit)``.

    Parameters
    ----------
    lap : Laplacian
    t : float or array of float
        Positive time(s) in the unit ``unit``.
    unit : {"shape", "absolute", "area", "volume", "h2"}
        Default ``"shape"`` (see :mod:`spectral_igl.laplacian.units`).
    name : str
        The argument's name in error messages.

    Returns
    -------
    float or array of float
        The absolute time(s) :math:`t \cdot` ``time_scale(lap, unit)``, shaped as ``t``.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> lap, big = sig.laplacian(V, F), sig.laplacian(1e3 * V, F)
    >>> t, T = sig.shape_time(lap, 1e-3), sig.shape_time(big, 1e-3)
    >>> round(T / t)        # the same relative time on a shape 1000 times larger
    1000000
    """
    scale = time_scale(lap, unit)
    if isinstance(t, (str, bytes)) or (np.ndim(t) and np.asarray(t).dtype.kind not in "iuf"):
        raise TypeError(f"{name} must be a positive number or an array of them, got {describe(t)}")
    arr = np.asarray(t, dtype=float)
    for x in arr.ravel():
        as_positive(x, name)
    out = arr * scale
    if not np.all(np.isfinite(out) & (out > 0)):
        raise ValueError(f"{name} = {t!r} in time_unit={unit!r} (x {scale:.6g}) is not a positive "
                         "finite time")
    return float(out) if out.ndim == 0 else out


def optional_time(lap: Laplacian, t, unit: str, name: str = "t"):
    r""":func:`shape_time` for a time that may be omitted (``None``: the function's default).

    A ``unit`` other than ``"absolute"`` with no time is refused rather than ignored.

    Parameters
    ----------
    lap : Laplacian
    t : None, float or array of float
        The time(s) in ``unit``, or ``None``.
    unit : {"absolute", "shape", "area", "volume", "h2"}
    name : str
        The argument's name in error messages.

    Returns
    -------
    None, float or array of float
        ``None`` for ``t=None``, else :func:`shape_time`.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.laplacian.units import optional_time
    >>> lap = sig.laplacian(*icosphere(1))
    >>> optional_time(lap, None, "absolute") is None, optional_time(lap, 0.5, "absolute")
    (True, 0.5)
    >>> optional_time(lap, None, "shape")
    Traceback (most recent call last):
    ...
    ValueError: ...
    """
    unit = as_choice(unit, "time_unit", TIME_UNITS)
    if t is None:
        if unit != "absolute":
            raise ValueError(f"time_unit={unit!r} applies to {name}, but {name} was not given "
                             f"(the default {name} is chosen in the shape's units already)")
        return None
    return shape_time(lap, t, unit, name)


def time_label(given, t, unit: str) -> str:
    """``"t=0.001"``, or ``"t=0.001 x shape (0.0123)"`` for a time given in the shape's units."""
    if t is None:
        return "t=default"
    if unit == "absolute":
        return f"t={t:.4g}"
    return f"t={float(given):.4g} x {unit} ({t:.4g})"
