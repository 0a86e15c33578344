"""Intrinsic Delaunay triangulation of a triangle mesh's edge lengths, by compiled edge flips."""
from __future__ import annotations

import numpy as np

from .._validate import describe

__all__ = ["intrinsic_delaunay"]


def intrinsic_delaunay(l, F):
    r"""Flip the edges of a triangulation with edge lengths ``l`` until it is intrinsically Delaunay.

    Every interior manifold edge whose two opposite angles sum to more than :math:`\pi`
    (:math:`\cot\alpha + \cot\beta < 0`) is flipped, the new diagonal's length coming from
    the unfolded quad, until none is left (Fisher et al. 2007). The cotangent weights of the
    result are non-negative and its cotangent Laplacian is unique. Compiled in the package's
    extension; libigl's ``intrinsic_delaunay_triangulation`` where that is not built.

    Parameters
    ----------
    l : (m, 3) float
        ``l[f, i]``: length of the edge of face f opposite its corner i (satisfying the
        triangle inequalities).
    F : (m, 3) int

    Returns
    -------
    l : (m, 3) float
    F : (m, 3) int64
        The flipped triangulation (same vertices, same number of faces).

    Examples
    --------
    >>> import numpy as np
    >>> l = np.array([[1.0, 1.0, 1.9], [1.0, 1.0, 1.9]])   # two obtuse triangles on edge 2
    >>> F = np.array([[0, 1, 2], [1, 0, 3]])
    >>> l2, F2 = intrinsic_delaunay(l, F)
    >>> sorted(map(int, F2[0])), round(float(l2[0, 1]), 6)
    ([0, 2, 3], 0.6245)
    """
    l = np.ascontiguousarray(l, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if l.ndim != 2 or l.shape[1] != 3 or F.shape != l.shape:
        raise ValueError(f"l and F must both have shape (m, 3), got {describe(l)} and {describe(F)}")
    try:
        from ._assembly import intrinsic_flips
    except ImportError:   # pragma: no cover - the extension is built with the package
        import igl

        out = igl.intrinsic_delaunay_triangulation(l, F)
        return np.asarray(out[0]), np.asarray(out[1], dtype=np.int64)
    lo, Fo, _ = intrinsic_flips(l, F)
    return lo, Fo
