"""Point-cloud Laplacians: heat-kernel weights on a neighbourhood graph (Belkin--Niyogi, Liu et al.)."""
from __future__ import annotations

import numbers

import numpy as np
import scipy.sparse as sp

from .._validate import as_mesh_arrays, as_points, as_positive, describe
from ._operator import Laplacian, make_laplacian

__all__ = ["point_cloud_laplacian", "tangent_voronoi_areas"]

_METHODS = ("belkin", "liu")

try:  # compiled clipping loop; _clip_cells below is its NumPy reference (tested equal)
    from ._assembly import clip_cells as _clip_compiled
except ImportError:  # pragma: no cover - source checkout without a build
    _clip_compiled = None


def _neighbours(P: np.ndarray, k: int | None, radius: float | None):
    """Directed neighbour pairs (i, j), i != j, and the local area per point h² (n,)."""
    from scipy.spatial import cKDTree

    n = P.shape[0]
    tree = cKDTree(P)
    if radius is None:
        d, J = tree.query(P, k + 1, workers=-1)
        if not np.all(np.isfinite(d)):
            raise ValueError("neighbour distances overflow to inf: the point coordinates are too "
                             f"large (max |P| = {np.abs(P).max():.3g}); rescale P")
        # drop each point itself (column 0 unless duplicates reorder the ties)
        own = J == np.arange(n)[:, None]
        keep = ~own
        keep[~own.any(axis=1), -1] = False  # a point hidden behind k+1 duplicates: drop the farthest
        d = d[keep].reshape(n, k)
        J = J[keep].reshape(n, k)
        I = np.repeat(np.arange(n), k)
        rk = d[:, -1]
        h2 = np.pi * rk ** 2 / k
        return I, J.ravel(), d, J, h2
    D = tree.sparse_distance_matrix(tree, radius, output_type="coo_matrix")
    off = D.row != D.col
    I, J = D.row[off].astype(np.int64), D.col[off].astype(np.int64)
    count = np.bincount(I, minlength=n)
    if np.any(count == 0):
        raise ValueError(f"radius={radius} leaves {int(np.sum(count == 0))} point(s) without a "
                         "neighbour; increase radius or use k")
    h2 = np.pi * radius ** 2 / count
    return I, J, None, None, h2


def _clip_cells(Q: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Area of the Voronoi cell of the origin among the 2-D points ``Q`` (n, k, 2).

    Sutherland--Hodgman clipping of the square ``[-half, half]²`` by the bisector
    half-planes ``x·q <= |q|²/2``, vectorised over the n points.
    """
    n, k, _ = Q.shape
    s = half[:, None]
    poly = np.stack([np.c_[-s, -s], np.c_[s, -s], np.c_[s, s], np.c_[-s, s]], axis=1)
    cnt = np.full(n, 4)
    for j in range(k):
        q = Q[:, j]
        c = 0.5 * np.einsum("ij,ij->i", q, q)
        f = np.einsum("imj,ij->im", poly, q) - c[:, None]
        nxt = np.roll(poly, -1, axis=1)
        fn = np.roll(f, -1, axis=1)
        inside = f <= 0
        cross = inside != (fn <= 0)
        tt = f / np.where(cross, f - fn, 1.0)
        X = poly + tt[..., None] * (nxt - poly)
        m = poly.shape[1]
        out = np.stack([poly, X], axis=2).reshape(n, 2 * m, 2)
        keep = np.stack([inside, cross], axis=2).reshape(n, 2 * m)
        cnt = keep.sum(axis=1)
        order = np.argsort(~keep, axis=1, kind="stable")
        width = max(int(cnt.max()), 3)
        out = np.take_along_axis(out, order[:, :width, None], axis=1)
        # pad every polygon with its last vertex (zero-length edges change nothing)
        idx = np.minimum(np.arange(width)[None, :], np.maximum(cnt - 1, 0)[:, None])
        poly = np.take_along_axis(out, idx[..., None], axis=1)
    x, y = poly[..., 0], poly[..., 1]
    area = 0.5 * np.abs(np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1))
    return np.where(cnt >= 3, area, 0.0)


def tangent_voronoi_areas(P, k: int = 24) -> np.ndarray:
    r"""Area of each point's Voronoi cell on its estimated tangent plane (Liu et al. 2012).

    The tangent plane of :math:`p_i` is spanned by the two leading principal directions of
    its ``k`` nearest neighbours; the neighbours are projected onto it and the Voronoi cell
    of :math:`p_i` among them is clipped to a square of half-side 1.5 times the distance to
    the 8th neighbour (this bounds the cells of points on an open boundary).

    Parameters
    ----------
    P : (n, 3) float, or a pyvista/trimesh/meshio object (its points)
    k : int
        Neighbours used for the plane and the cell.

    Returns
    -------
    A : (n,) float, positive. Coincident points each get the full cell.
    """
    from scipy.spatial import cKDTree

    P = as_points(as_mesh_arrays(P, name="P", need_cells=False)[0], "P", dims=(3,), min_rows=4)
    k = min(int(k), P.shape[0] - 1)
    d, J = cKDTree(P).query(P, k + 1, workers=-1)
    return _voronoi_from_knn(P, d[:, 1:], J[:, 1:])


def _voronoi_from_knn(P, d, J):
    nb = P[J] - P[:, None, :]
    C = np.einsum("nki,nkj->nij", nb, nb)
    _, U = np.linalg.eigh(C)
    Q = np.einsum("nki,nij->nkj", nb, U[:, :, 1:])
    half = 1.5 * d[:, min(7, d.shape[1] - 1)]
    if _clip_compiled is not None:
        A = _clip_compiled(np.ascontiguousarray(Q, dtype=np.float64), np.ascontiguousarray(half, dtype=np.float64))
    else:
        A = _clip_cells(Q, half)
    good = np.isfinite(A) & (A > 0)
    if not good.all():
        fill = float(np.mean(A[good])) if good.any() else 1.0
        A = np.where(good, A, fill)
    return A


_DEFAULTS = {"belkin": (64, 0.9), "liu": (128, 1.1)}


def point_cloud_laplacian(P, k: int | None = None, method: str = "belkin", t=None,
                          radius: float | None = None, bandwidth: float | None = None) -> Laplacian:
    r"""Laplacian of a point cloud sampled from a surface, from heat-kernel weights.

    Both methods weigh a pair of neighbours by the Euclidean heat kernel
    :math:`g_{ij} = e^{-\|p_i-p_j\|^2/(4t_{ij})}` and discretise

    .. math:: \Delta f(p_i) \approx \frac{1}{4\pi t^2}\int e^{-\|p_i-y\|^2/(4t)}\,(f(y)-f(p_i))\,dy

    (Belkin, Sun & Wang 2009) with a quadrature weight :math:`a_j` per point:

    * ``"belkin"``: Belkin--Niyogi heat weights on the (symmetrised) k-nearest-neighbour
      graph, with the weights estimated from the sampling itself: the kernel density
      :math:`q_i = \sum_j g_{ij}/(4\pi t_{ij})` (points per unit area) gives
      :math:`a_i = 1/q_i`, and the mass is the degree (as in Laplacian eigenmaps),

      .. math:: L_{ij} = -\frac{a_i a_j g_{ij}}{4\pi t_{ij}^2}, \qquad
                B_{ii} = \sum_j \frac{a_i a_j g_{ij}}{4\pi t_{ij}},

      so that for a constant bandwidth :math:`B^{-1}L = (I - D^{-1}W)/t` is the random-walk
      Laplacian of the density-normalised graph (Coifman--Lafon, α = 1): it converges to
      the Laplace--Beltrami operator for uniform *and* non-uniform sampling.
    * ``"liu"``: Liu, Prabhakaran & Guo 2012 ("Point-based manifold harmonics"):
      :math:`a_i` is the area of the Voronoi cell of :math:`p_i` on its PCA tangent plane
      (:func:`tangent_voronoi_areas`), :math:`B = \operatorname{diag}(a)` and
      :math:`L_{ij} = -a_i a_j g_{ij}/(4\pi t_{ij}^2)`.

    Parameters
    ----------
    P : (n, 3) float, or a mesh object
        Points; at least 4. A pyvista, trimesh or meshio object gives its points (its
        cells are ignored).
    k : int or None
        Number of nearest neighbours (scipy's KD-tree). Ignored when ``radius`` is given.
        ``None``: 64 for ``"belkin"``, 128 for ``"liu"`` (whose Voronoi quadrature wants a
        wider kernel, hence more neighbours for the same truncation).
    method : {"belkin", "liu"}
    t : float or None
        Heat-kernel bandwidth (area units). ``None``: follow the local sampling density,
        :math:`t_i = (\text{bandwidth}\cdot h_i)^2` with :math:`h_i^2 = \pi r_i^2/k` the area
        per point, :math:`r_i` the distance to the k-th neighbour (or, with ``radius``,
        :math:`h_i^2 = \pi\,\text{radius}^2/\#\text{neighbours}`). Pairs use
        :math:`t_{ij} = (t_i + t_j)/2`, so L stays symmetric.
    radius : float or None
        Use all neighbours within this distance instead of the k nearest.
    bandwidth : float or None
        The factor in the adaptive bandwidth above (ignored when ``t`` is given).
        ``None``: 0.9 for ``"belkin"``, 1.1 for ``"liu"``.

    Returns
    -------
    Laplacian
        ``domain="points"``; ``B`` diagonal and positive, ``L`` symmetric PSD with zero row
        sums; ``data`` holds ``P``, ``method``, ``t`` (the per-point bandwidths) and ``k``.

    Notes
    -----
    The intrinsic dimension is taken to be 2 (points on a surface). Measured on 10,000
    uniformly random points of the unit sphere with the defaults, the first 16 nonzero
    eigenvalues are within about 4% (belkin) and 3% (liu) of :math:`l(l+1)`; both
    underestimate slightly (kernel truncation and the O(t) bias of the heat kernel). Coincident points are allowed: they are neighbours at distance
    0. Points whose neighbourhoods do not connect form separate components.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> P = np.random.default_rng(0).standard_normal((2000, 3))
    >>> P /= np.linalg.norm(P, axis=1, keepdims=True)
    >>> lap = sig.point_cloud_laplacian(P, k=30)
    >>> lap.domain, lap.n
    ('points', 2000)
    """
    P = as_points(as_mesh_arrays(P, name="P", need_cells=False)[0], "P", dims=(3,), min_rows=4)
    n = P.shape[0]
    if method not in _METHODS:
        raise ValueError(f"method must be one of {_METHODS}, got {method!r}")
    k_default, bw_default = _DEFAULTS[method]
    k = k_default if k is None else k
    bandwidth = as_positive(bw_default if bandwidth is None else bandwidth, "bandwidth")
    if radius is not None:
        radius = as_positive(radius, "radius")
    else:
        if isinstance(k, bool) or not isinstance(k, (numbers.Integral, np.integer)):
            raise TypeError(f"k must be an integer number of neighbours, got {describe(k)}")
        k = int(k)
        if k < 3:
            raise ValueError(f"k must be at least 3, got {k}")
        k = min(k, n - 1)
    I, J, d, Jk, h2 = _neighbours(P, k, radius)
    if t is None:
        if not np.any(h2 > 0):
            raise ValueError("all points coincide: the sampling density is undefined")
        # duplicates can make a local spacing 0: floor it at a small fraction of the typical one
        h2 = np.maximum(h2, 1e-6 * np.median(h2[h2 > 0]))
        ti = bandwidth ** 2 * h2
    else:
        ti = np.full(n, as_positive(t, "t"))
    # symmetric pattern: union of the directed neighbour relations, without the diagonal
    if Jk is not None and radius is None:
        pat = sp.csr_matrix((np.ones(I.size), J, np.arange(0, I.size + 1, k)), shape=(n, n))
    else:
        pat = sp.csr_matrix((np.ones(I.size), (I, J)), shape=(n, n))
    pat = (pat + pat.T).tocsr()
    pat.setdiag(0)
    pat.eliminate_zeros()
    pat.sort_indices()
    c = pat.indices.astype(np.int64)
    r = np.repeat(np.arange(n, dtype=np.int64), np.diff(pat.indptr))
    tij = 0.5 * (ti[r] + ti[c])
    diff = P[r] - P[c]
    g = np.exp(-np.einsum("ij,ij->i", diff, diff) / (4.0 * tij))
    if method == "belkin":
        q = np.bincount(r, weights=g / (4.0 * np.pi * tij), minlength=n)
        if np.any(q <= 0):
            raise ValueError("some points have no neighbour within reach of the kernel")
        a = 1.0 / q
        w = a[r] * a[c] * g / (4.0 * np.pi * tij ** 2)
        mass = np.bincount(r, weights=w * tij, minlength=n)
    else:
        if Jk is None:
            from scipy.spatial import cKDTree

            kk = min(24, n - 1)
            d, Jk = cKDTree(P).query(P, kk + 1, workers=-1)
            d, Jk = d[:, 1:], Jk[:, 1:]
        kv = min(32, Jk.shape[1])
        a = _voronoi_from_knn(P, d[:, :kv], Jk[:, :kv])
        w = a[r] * a[c] * g / (4.0 * np.pi * tij ** 2)
        mass = a
    # L = D - W; W is symmetric entry for entry (every factor of w is symmetric in (r, c))
    # and make_laplacian puts the row sums of W on the diagonal
    L = sp.csr_matrix((-w, pat.indices, pat.indptr), shape=(n, n))
    B = sp.diags(mass).tocsr()
    data = {"P": P, "method": method, "t": ti, "k": k, "radius": radius}
    return make_laplacian(L, B, domain="points", data=data, _symmetric=True)
