"""Point-cloud Laplacians: heat-kernel weights on a neighbourhood graph (Belkin--Niyogi, Liu et al.)."""
from __future__ import annotations

import numbers

import numpy as np
import scipy.sparse as sp

from .._validate import as_int, as_mesh_arrays, as_points, as_positive, check_dense_size, describe
from ._operator import Laplacian, make_laplacian
from .intrinsic import edge_lengths, intrinsic_delaunay, mollify as mollify_lengths

__all__ = ["point_cloud_laplacian", "tangent_voronoi_areas", "local_triangles", "tufted_cover",
           "tufted_delaunay", "fan_votes", "neighbour_pieces", "JOIN_K"]

_METHODS = ("delaunay", "belkin", "liu")

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
    """Area of the Voronoi cell of the origin among the 2-D points ``Q`` (n, k, 2), clipped
    by the square ``[-half, half]²``: the NumPy reference of the compiled clipping."""
    return _clip_cells_dual(Q, half, cut_open=False)[0]


def _clip_cells_dual(Q: np.ndarray, half: np.ndarray, cut_open: bool = True):
    """Voronoi cell of the origin among the 2-D points ``Q`` (n, k, 2), with its edges.

    Sutherland--Hodgman clipping of the square ``[-half, half]²`` by the bisector
    half-planes ``x·q <= |q|²/2``, vectorised over the n points, each polygon edge
    carrying the index of the bisector it lies on (-1 for the bounding square).
    Returns ``(area (n,), dual (n, k), open (n,) bool)`` with ``dual[i, j]`` the length
    of the cell's edge on the bisector of ``Q[i, j]`` (0 when that neighbour is not a
    Voronoi neighbour) and ``open`` true where the cell reaches the square. With
    ``cut_open``, open cells are those of the local Delaunay star with its hull edges:
    their bisector edges that reach the square are cut at the primal edge's midpoint;
    without it they are clipped by the square.
    """
    n, k, _ = Q.shape
    s = half[:, None]
    poly = np.stack([np.c_[-s, -s], np.c_[s, -s], np.c_[s, s], np.c_[-s, s]], axis=1)
    lab = np.full((n, 4), -1, dtype=np.int64)
    cnt = np.full(n, 4)
    for j in range(k):
        q = Q[:, j]
        c = 0.5 * np.einsum("ij,ij->i", q, q)
        # only the cnt real vertices of each row count: the slots past them are padding
        # (its width is the batch's longest polygon) and the polygon closes at cnt - 1 -> 0
        m = poly.shape[1]
        slot = np.arange(m)[None, :]
        real = slot < cnt[:, None]
        after = np.where(slot + 1 < cnt[:, None], slot + 1, 0)
        f = np.einsum("imj,ij->im", poly, q) - c[:, None]
        nxt = np.take_along_axis(poly, after[..., None], axis=1)
        fn = np.take_along_axis(f, after, axis=1)
        inside = f <= 0
        cross = (inside != (fn <= 0)) & real
        if not cross.any():
            continue
        tt = f / np.where(cross, f - fn, 1.0)
        X = poly + tt[..., None] * (nxt - poly)
        out = np.stack([poly, X], axis=2).reshape(n, 2 * m, 2)
        # the edge leaving a crossing point runs along the bisector j when the polygon
        # leaves the half-plane there, along the old edge when it comes back in
        olab = np.stack([lab, np.where(inside, j, lab)], axis=2).reshape(n, 2 * m)
        keep = np.stack([inside & real, cross], axis=2).reshape(n, 2 * m)
        cnt = keep.sum(axis=1)
        order = np.argsort(~keep, axis=1, kind="stable")
        width = max(int(cnt.max()), 3)
        out = np.take_along_axis(out, order[:, :width, None], axis=1)
        olab = np.take_along_axis(olab, order[:, :width], axis=1)
        idx = np.minimum(np.arange(width)[None, :], np.maximum(cnt - 1, 0)[:, None])
        poly = np.take_along_axis(out, idx[..., None], axis=1)
        lab = np.take_along_axis(olab, idx, axis=1)
    # Walk the cnt real vertices of each cell. An edge on bisector j whose neighbour edge
    # lies on the bounding square is a ray of an open (boundary) cell: it is cut at the
    # midpoint q_j / 2 of the primal edge, so that the dual length and the area are those
    # of the circumcentric dual of the local Delaunay star (1/2 cot of the one angle).
    width = poly.shape[1]
    m = np.arange(width)[None, :]
    valid = m < cnt[:, None]
    nxt = np.where(m + 1 < cnt[:, None], m + 1, 0)
    prv = np.where(m >= 1, m - 1, np.maximum(cnt - 1, 0)[:, None])
    A = poly
    Bn = np.take_along_axis(poly, nxt[..., None], axis=1)
    lab_prev = np.take_along_axis(lab, prv, axis=1)
    lab_next = np.take_along_axis(lab, nxt, axis=1)
    bis = valid & (lab >= 0) & (cnt >= 3)[:, None]
    rows = np.broadcast_to(np.arange(n)[:, None], lab.shape)
    mid = 0.5 * Q[rows, np.maximum(lab, 0)]
    start = np.where((lab_prev < 0)[..., None] & cut_open, mid, A)
    end = np.where((lab_next < 0)[..., None] & cut_open, mid, Bn)
    edge = Bn - A
    elen = np.linalg.norm(edge, axis=2)
    signed = np.einsum("nmi,nmi->nm", end - start, edge) / np.where(elen > 0, elen, 1.0)
    use = bis & (signed > 0)
    tri = 0.5 * (start[..., 0] * end[..., 1] - start[..., 1] * end[..., 0])
    # the square's edges count toward the area of an uncut cell
    area = np.where(use | (valid & (lab < 0) & (not cut_open)), tri, 0.0).sum(axis=1)
    dual = np.zeros((n, k))
    np.add.at(dual, (rows[use], lab[use]), signed[use])
    is_open = np.any(valid & (lab < 0), axis=1)
    return np.where(cnt >= 3, np.maximum(area, 0.0), 0.0), dual, is_open


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

    Examples
    --------
    On points spread evenly over the unit sphere the cells add up to about its area
    :math:`4\pi`:

    >>> import numpy as np
    >>> from spectral_igl.data_generators import sphere_points
    >>> from spectral_igl.laplacian.points import tangent_voronoi_areas
    >>> A = tangent_voronoi_areas(sphere_points(500))
    >>> A.shape, bool(abs(A.sum() / (4 * np.pi) - 1) < 0.05)
    ((500,), True)
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


_DEFAULTS = {"delaunay": (20, 1.0), "belkin": (64, 0.9), "liu": (128, 1.1)}
#: peak bytes per point and neighbour of the k-nearest-neighbour constructions (measured at
#: n = 200k on a sphere: 260 for "delaunay" at k = 20, 170 for "belkin" at k = 64)
BYTES_PER_NEIGHBOUR = 300


def _check_k(k, default: int, n: int) -> int:
    """The number of neighbours: the default (at most n - 1), or a given k in [3, n - 1]."""
    if k is None:
        return min(default, n - 1)
    if isinstance(k, bool) or not isinstance(k, (numbers.Integral, np.integer)):
        raise TypeError(f"k must be an integer number of neighbours, got {describe(k)}")
    return as_int(k, "k", lo=3, hi=n - 1)


def _check_size(n: int, k: int) -> None:
    check_dense_size(BYTES_PER_NEIGHBOUR * float(n) * (k + 1),
                     f"the {k}-nearest-neighbour Laplacian of {n} points",
                     "subsample the points (e.g. voxel-grid or Poisson-disk) or take fewer neighbours k")


def point_cloud_laplacian(P, k: int | None = None, method: str = "delaunay", t=None,
                          radius: float | None = None, bandwidth: float | None = None,
                          boundary: bool | str | None = None) -> Laplacian:
    r"""Laplacian of a point cloud sampled from a surface.

    * ``"delaunay"`` (default): cotangent weights of the local Delaunay triangulation in
      the tangent plane. The tangent plane of :math:`p_i` is first that of the centred
      PCA of its 12 nearest neighbours; its ``k`` nearest neighbours are projected onto
      it and the Voronoi cell :math:`\Omega_i` of :math:`p_i` among them is clipped (to a
      square of half-side 1.5 times the distance to the 8th neighbour, which bounds cells
      on an open boundary). The neighbours whose bisectors carry an edge of the cell are
      the local Delaunay fan; the plane is then replaced by the one normal to the fan's
      3-D normal (the sum of the cross products of consecutive fan edges) and the cell is
      clipped again. A Delaunay neighbour :math:`j`, whose bisector carries an edge of
      :math:`\Omega_i` of length :math:`\ell_{ij}`, gets the dual length over the 3-D
      primal length (for a planar star, :math:`\ell_{ij}/\|q_j - q_i\|` is the Delaunay
      cotangent weight, the same identity as for meshes):

      .. math:: w_{ij} = \frac{\ell_{ij}}{\|p_j - p_i\|}, \qquad
                L_{ij} = -\tfrac12(w_{ij} + w_{ji}), \qquad
                B_{ii} = \tfrac14 \sum_j (-L_{ij}) \|p_j - p_i\|^2.

      The mass is the one L is exact with on :math:`f = \|x - p_i\|^2`, whose surface
      Laplacian at :math:`p_i` is 4 on any surface; for a planar Delaunay star it is the
      area :math:`|\Omega_i|` of the cell. The off-diagonal weights are non-negative,
      about 6 per row, and no bandwidth is involved: it converges on uniform, random and
      non-uniform samplings. The 3-D lengths keep weights and masses bounded where a
      plane fits the neighbours badly (creases, coarse or one-sided samplings), which
      with projected lengths and cell areas put cow's total area 7.5% and beetle's 59% too
      high and weights up to 1e5 at fandisk's creases.
    * ``"belkin"``: heat-kernel weights :math:`g_{ij} = e^{-\|p_i-p_j\|^2/(4t_{ij})}` on
      the (symmetrised) k-nearest-neighbour graph, normalised by a kernel density
      estimate (Coifman--Lafon, α = 1): :math:`q_i = \sum_{j\ne i} g_{ij}/(4\pi t_{ij})`,
      :math:`a_i = 1/q_i`,

      .. math:: L_{ij} = -\frac{a_i a_j g_{ij}}{4\pi t_{ij}^2}, \qquad
                B_{ii} = \sum_j \frac{a_i a_j g_{ij}}{4\pi t_{ij}}.

      Its error does not vanish on quasi-uniform samplings: with the bandwidth tied to
      the spacing (:math:`t = c^2 h^2`), the kernel sum over the *other* points depends on
      how they are arranged within a spacing of :math:`p_i`. For Poisson samples it is
      unbiased; on a lattice-like (Fibonacci) sampling the hole around :math:`p_i` is
      one point's worth, :math:`h^2/(4\pi t) = 1/(4\pi c^2) \approx 9.8\%` at
      :math:`c = 0.9`, and the eigenvalues come out about 9--10% high at every
      resolution. Counting the self term :math:`g_{ii}` removes that bias on Fibonacci
      samplings (-1.8% at 4k, -1.2% at 16k) but then biases random ones by -11%: no
      normalisation by a kernel sum at :math:`t \propto h^2` fits every sampling,
      which is why the default takes its weights from the tangent Voronoi cells.
    * ``"liu"``: Liu, Prabhakaran & Guo 2012 ("Point-based manifold harmonics"): the
      heat weights with :math:`a_i` the area of the tangent Voronoi cell of :math:`p_i`
      (:func:`tangent_voronoi_areas`), :math:`B = \operatorname{diag}(a)` and
      :math:`L_{ij} = -a_i a_j g_{ij}/(4\pi t_{ij}^2)`, discretising

      .. math:: \Delta f(p_i) \approx \frac{1}{4\pi t^2}\int e^{-\|p_i-y\|^2/(4t)}\,(f(y)-f(p_i))\,dy.

    Parameters
    ----------
    P : (n, 3) float, or a mesh object
        Points; at least 4. A pyvista, trimesh or meshio object gives its points (its
        cells are ignored).
    k : int or None
        Number of nearest neighbours (scipy's KD-tree). Ignored by the heat methods when
        ``radius`` is given. ``None``: 20 for ``"delaunay"``, 64 for ``"belkin"``, 128 for
        ``"liu"``.
    method : {"delaunay", "belkin", "liu"}
    t : float or None
        Heat methods only: the bandwidth (area units). ``None``: follow the local
        sampling density, :math:`t_i = (\text{bandwidth}\cdot h_i)^2` with
        :math:`h_i^2 = \pi r_i^2/k` the area per point, :math:`r_i` the distance to the
        k-th neighbour (or, with ``radius``, :math:`h_i^2 = \pi\,\text{radius}^2/\#\text{neighbours}`).
        Pairs use :math:`t_{ij} = (t_i + t_j)/2`, so L stays symmetric.
    radius : float or None
        Heat methods only: all neighbours within this distance instead of the k nearest.
    bandwidth : float or None
        Heat methods only: the factor in the adaptive bandwidth above. ``None``: 0.9 for
        ``"belkin"``, 1.1 for ``"liu"``.
    boundary : {"auto", True, False} or None
        ``"delaunay"`` only: how a cell that its ``k`` neighbours leave open is read.

        * a **rim** (a surface *with boundary*, free/Neumann): the cell is the circumcentric
          dual of the local Delaunay star, whose hull edges keep :math:`\tfrac12\cot` of
          their one angle (the bisector cut at the edge's midpoint);
        * a **one-sided point of a closed surface** (sharp tips, folds, anisotropic
          sampling): the cell is clipped by a square of half-side 1.5 times the distance to
          its 8th neighbour.

        ``"auto"`` (``None``, the default): a rim where the cell is still open among
        ``RIM_FACTOR`` (3) times as many neighbours and the star is a graph over its plane
        (at most ``RIM_OVERLAP``, 25%, of its neighbours have another neighbour that projects
        closer than half their 3-D distance: where a fold lays two sheets over each other);
        otherwise one-sided. ``True``: every open cell is a rim. ``False``: none is. The
        points taken for rims are ``data["rim"]``.

        Measured (``benchmarks/point_clouds.py``, median / largest relative error of the
        first 20 nonzero eigenvalues against each surface's spectrum): on circle.obj, a flat
        disk, ``"auto"`` finds the 160 rim points and no other, and the operator is the mesh's
        own cotan Laplacian and Voronoi mass (0.169% / 0.367%; ``False`` 5.25% / 9.17%);
        stanford-bunny, whose scan has holes, 1.75% -> 1.26% (``True`` 0.76%); beetle 6.13%
        -> 5.66%; on the closed shapes it takes cow's folds (ears, hooves, horns: 40-95%
        overlapping neighbours) for one-sided and leaves spot, fertility, fandisk,
        armadillo, cow, homer and suzanne bit for bit as with ``False`` (rocker-arm 2.82% ->
        2.88%, 7 rims; cheburashka 1.91% -> 1.90%, 1 rim); no point of the four sphere
        samplings is a rim. Random points of a flat 2 x 1 rectangle, largest error of the
        first 8 Neumann eigenvalues at 4,000 -> 16,000 points (``benchmarks/domains.py``):
        ``"auto"`` 1.09% -> 0.41%, ``True`` 0.95% -> 0.61%, ``False`` 8.57% -> 4.20%
        (robust_laplacian 4.00% -> 4.72%).

    Returns
    -------
    Laplacian
        ``domain="points"``; ``B`` diagonal and positive, ``L`` symmetric PSD with zero row
        sums and non-positive off-diagonal entries; ``data`` holds ``P``, ``method``,
        ``k`` (and ``t``, the per-point bandwidths, for the heat methods; ``boundary`` and
        ``rim``, the boolean mask of the points read as rims, for ``"delaunay"``).

    Notes
    -----
    The intrinsic dimension is taken to be 2 (points on a surface). Measured on the unit
    sphere (first 16 nonzero eigenvalues against :math:`l(l+1)`, largest relative error,
    4,000 -> 16,000 points; ``benchmarks/point_clouds.py``): ``"delaunay"`` 0.41% ->
    0.11% on a Fibonacci sampling, 1.6% -> 0.62% uniformly random, 1.8% -> 0.53% with
    density ratio 3, with 7 nonzeros per row of L (robust_laplacian: 0.67% -> 0.16%,
    6.4% -> 7.6%, 6.5% -> 11%, 7 per row); ``"belkin"`` 10.1% -> 10.2%, 7.2% -> 2.4%,
    8.7% -> 2.5% with 65--69 per row. On the vertices of 15 real shapes, against the
    spectrum of each mesh's surface (median / largest error of 20 eigenvalues),
    ``"delaunay"`` is at or below robust_laplacian in both on 7 (0.17% / 1.5% against
    4.2% / 11% on armadillo, 1.5% / 4.3% against 10% / 19% on fandisk). Where it is not,
    the error sits in surface the points do not show (``docs/results.md``): meshes cut
    along seams whose two sides are coincident or within half an edge (camel_b, teapot,
    truck, suzanne, beetle: the same points sample the surface without the cut), parts
    that touch (homer's largest error 90% -> 4.1% and cheburashka's 36% -> 8.2% with each
    star kept to its own sheet, an oracle; cow's tail, 92% -> 74%, robust_laplacian 52%),
    and circle, a flat disk, where the operator is its mesh's own (cotan, Voronoi mass:
    0.169% against 0.155%; with full mass that mesh gives 0.144%). Coincident points are allowed
    (neighbours at distance 0; ``"delaunay"`` gives a coincident pair no weight between
    them). Points whose neighbourhoods do not connect form separate components.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> P = np.random.default_rng(0).standard_normal((2000, 3))
    >>> P /= np.linalg.norm(P, axis=1, keepdims=True)
    >>> lap = sig.point_cloud_laplacian(P)
    >>> lap.domain, lap.n
    ('points', 2000)
    """
    P = as_points(as_mesh_arrays(P, name="P", need_cells=False)[0], "P", dims=(3,), min_rows=4)
    n = P.shape[0]
    if method not in _METHODS:
        raise ValueError(f"method must be one of {_METHODS}, got {method!r}")
    k_default, bw_default = _DEFAULTS[method]
    if boundary is None:
        boundary = "auto" if method == "delaunay" else False
    if isinstance(boundary, (bool, np.bool_)):
        boundary = bool(boundary)
    elif not (isinstance(boundary, str) and boundary == "auto"):
        raise TypeError(f"boundary must be True, False or 'auto', got {describe(boundary)}")
    if boundary is not False and method != "delaunay":
        raise ValueError(f"boundary={boundary!r} is an option of method='delaunay', not of "
                         f"method={method!r}")
    if method == "delaunay":
        given = [name for name, v in (("t", t), ("radius", radius), ("bandwidth", bandwidth))
                 if v is not None]
        if given:
            raise ValueError(f"{', '.join(given)} set the heat kernel of method='belkin' or "
                             "'liu'; method='delaunay' has no bandwidth")
        chosen = k is None
        k = _check_k(k, k_default, n)
        _check_size(n, k)
        lap = _delaunay_laplacian(P, k, boundary)
        if chosen and k < JOIN_K < n and lap.components.max() > 0 \
                and lap.components.max() + 1 > neighbour_pieces(P, JOIN_K):
            # the stars leave apart what a wider neighbourhood joins (a band sampled more
            # coarsely than its sides): the default takes the wider stars
            lap = _delaunay_laplacian(P, JOIN_K, boundary)
        return lap
    bandwidth = as_positive(bw_default if bandwidth is None else bandwidth, "bandwidth")
    if radius is not None:
        radius = as_positive(radius, "radius")
        if k is not None:
            raise ValueError(f"give k or radius, not both: got k={k!r} and radius={radius}")
    else:
        k = _check_k(k, k_default, n)
        _check_size(n, k)
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


_NORMAL_K = 12  # neighbours of the first (PCA) normal estimate

#: neighbours that ``"delaunay"``'s default stars take where those of the default k split the
#: cloud into more pieces than the graph of this many nearest neighbours does (potpourri3d's
#: and robust_laplacian's default): camel_b's vertices, whose legs hang from the body by mesh
#: edges four spacings long, are 3 pieces with 20 and one with 30 (median error of the first
#: 20 eigenvalues 115.7% -> 70.8%, robust_laplacian 80.1%); clouds that the default joins are
#: unchanged
JOIN_K = 30


def neighbour_pieces(P, k: int) -> int:
    """Connected pieces of the graph of each point's ``k`` nearest neighbours."""
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    n = len(P)
    k = min(int(k), n - 1)
    if k < 1:
        return n
    j = cKDTree(P).query(P, k + 1)[1][:, 1:]
    A = sp.csr_matrix((np.ones(n * k), j.ravel(), np.arange(0, n * k + 1, k)), shape=(n, n))
    return int(connected_components(A, directed=False)[0])


def _tangent_frames(nb: np.ndarray, N: np.ndarray) -> np.ndarray:
    """(n, 3, 2): orthonormal basis of the plane normal to each unit row of ``N``, along the
    principal directions of the neighbour offsets ``nb`` (n, k, 3) projected onto it (the
    clipping square then lies along the star's extent)."""
    a = np.where(np.abs(N[:, [0]]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    e1 = np.cross(N, a)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    E = np.stack([e1, np.cross(N, e1)], axis=2)
    Q = np.einsum("nki,nij->nkj", nb, E)
    _, R = np.linalg.eigh(np.einsum("nki,nkj->nij", Q, Q))
    return np.einsum("nij,njk->nik", E, R)


def _fan_normals(nb: np.ndarray, Q: np.ndarray, dual: np.ndarray, N: np.ndarray) -> np.ndarray:
    """Unit normal of each point's local Delaunay fan: the sum of the 3-D cross products of
    angularly consecutive Delaunay neighbours (triangles of the star, not across a gap of π
    or more); ``N`` where the star has no triangle."""
    n, k = dual.shape
    ang = np.where(dual > 0, np.arctan2(Q[..., 1], Q[..., 0]), np.inf)
    order = np.argsort(ang, axis=1)
    cnt = (dual > 0).sum(axis=1)
    nbs = np.take_along_axis(nb, order[..., None], axis=1)
    # past a row's cnt Delaunay neighbours the angles are padding: 0, not inf (a star
    # without any, cnt = 0, would otherwise subtract inf from inf)
    angs = np.where(np.arange(k)[None, :] < cnt[:, None], np.take_along_axis(ang, order, axis=1), 0.0)
    rows = np.arange(n)
    S = np.zeros((n, 3))
    for m in range(k):
        b = np.where(m + 1 < cnt, m + 1, 0)
        gap = np.where(b == 0, angs[rows, b] + 2.0 * np.pi - angs[:, m], angs[rows, b] - angs[:, m])
        ok = (m < cnt) & (cnt >= 2) & (gap > 0) & (gap < np.pi)
        S += np.where(ok[:, None], np.cross(nbs[:, m], nbs[rows, b]), 0.0)
    norm = np.linalg.norm(S, axis=1)
    good = norm > 0
    return np.where(good[:, None], S / np.where(good, norm, 1.0)[:, None], N)


def _star_plane(P: np.ndarray, rows: np.ndarray, d: np.ndarray, J: np.ndarray, cut_open: bool,
                normal_k: int = _NORMAL_K):
    """(nb, Q, area, dual, open) of the points ``rows`` among their neighbours ``J`` (r, k):
    the 3-D offsets ``nb`` (r, k, 3), their coordinates ``Q`` (r, k, 2) in the plane of the
    local Delaunay fan (first normal from the PCA of the ``normal_k`` nearest), and
    :func:`_clip_cells_dual`'s results there (see :func:`_star`)."""
    nb = P[J] - P[rows][:, None, :]
    kn = min(normal_k, J.shape[1])
    c = nb[:, :kn] - nb[:, :kn].mean(axis=1, keepdims=True)
    _, U = np.linalg.eigh(np.einsum("nki,nkj->nij", c, c))
    half = 1.5 * d[:, min(7, d.shape[1] - 1)]
    Q = np.einsum("nki,nij->nkj", nb, _tangent_frames(nb, U[:, :, 0]))
    _, dual, _ = _clip_cells_dual(Q, half, cut_open)
    N = _fan_normals(nb, Q, dual, U[:, :, 0])
    Q = np.einsum("nki,nij->nkj", nb, _tangent_frames(nb, N))
    area, dual, is_open = _clip_cells_dual(Q, half, cut_open)
    return nb, Q, area, dual, is_open


def _star(P: np.ndarray, rows: np.ndarray, d: np.ndarray, J: np.ndarray, cut_open: bool):
    """Cell areas, Delaunay weights and openness of the points ``rows`` among ``J`` (r, k).

    The tangent plane is that of the local Delaunay fan: a first normal from the centred
    PCA of the nearest ``_NORMAL_K`` neighbours, the fan of the Voronoi cell in that plane,
    then the plane normal to the fan's own (3-D) normal, where the cell is clipped again.
    The weight of a Delaunay neighbour is the cell edge over the 3-D distance.
    """
    nb, Q, area, dual, is_open = _star_plane(P, rows, d, J, cut_open)
    dist = np.linalg.norm(nb, axis=2)
    w = np.where((dual > 0) & (dist > 0), dual / np.where(dist > 0, dist, 1.0), 0.0)
    return area, w, is_open


def _knn(tree, P, rows, k):
    """(d, J) of the k nearest other points of ``P[rows]``."""
    d, J = tree.query(P[rows], k + 1, workers=-1)
    if not np.all(np.isfinite(d)):
        raise ValueError("neighbour distances overflow to inf: the point coordinates are too "
                         f"large (max |P| = {np.abs(P).max():.3g}); rescale P")
    own = J == rows[:, None]
    keep = ~own
    keep[~own.any(axis=1), -1] = False
    m = len(rows)
    return d[keep].reshape(m, k), J[keep].reshape(m, k)


def _delaunay_laplacian(P: np.ndarray, k, boundary=False) -> Laplacian:
    from scipy.spatial import cKDTree

    tree = cKDTree(P)
    d, J = _knn(tree, P, np.arange(P.shape[0]), k)
    if not np.any(d > 0):
        raise ValueError("all points coincide: there is no tangent plane")
    return delaunay_from_neighbours(P, d, J, boundary, tree=tree)


#: ``boundary="auto"`` takes a cell for a rim where it is still open among this many times
#: its star's ``k`` neighbours (a one-sided point of a closed surface is closed by points
#: a little farther away; nothing closes a rim's cell) ...
RIM_FACTOR = 3
#: ... and its star is a graph over the tangent plane: at most this share of its neighbours
#: has another neighbour that projects closer than half their 3-D distance. A fold (the rim
#: of a thin ear, a hoof's edge, a horn's tip, seen from points too sparse for it) lays two
#: sheets over each other there: cow's 43 cells that stay open all have 40-95% such
#: neighbours, circle's 160 rims none, 41 of the 42 stanford-bunny cells that stay open
#: less than 25% (one has 45%)
RIM_OVERLAP = 0.25


def _overlap(nb: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """(r,): the share of each star's neighbours (offsets ``nb`` (r, k, 3), plane coordinates
    ``Q`` (r, k, 2)) that have another neighbour closer than half their 3-D distance in the
    plane: where the projection folds the surface over itself."""
    k = nb.shape[1]
    D3 = np.linalg.norm(nb[:, :, None] - nb[:, None], axis=3)
    D2 = np.linalg.norm(Q[:, :, None] - Q[:, None], axis=3)
    steep = D2 < 0.5 * D3
    steep[:, np.arange(k), np.arange(k)] = False
    return steep.any(axis=2).mean(axis=1)


def _rims(P: np.ndarray, tree, d: np.ndarray, J: np.ndarray, is_open: np.ndarray,
          block: int = 4096) -> np.ndarray:
    """Boolean (n,): the points whose tangent cell among their ``k`` neighbours ``J`` is open,
    stays open among their ``RIM_FACTOR * k`` nearest (clipped by the same square), and
    whose ``k``-star is a graph over its plane (:data:`RIM_OVERLAP`); ``block`` open points
    at a time (a cloud whose cells are all open stays within a few times the stars' memory)."""
    k = J.shape[1]
    rim = np.zeros(len(P), bool)
    kk = min(RIM_FACTOR * k, len(P) - 1)
    if kk <= k:
        return rim
    open_rows = np.flatnonzero(is_open)
    for start in range(0, open_rows.size, block):
        rows = open_rows[start:start + block]
        nb, Q, _, _, _ = _star_plane(P, rows, d[rows], J[rows], False)
        rows = rows[_overlap(nb, Q) <= RIM_OVERLAP]
        if rows.size:
            d2, J2 = _knn(tree, P, rows, kk)
            d2[:, :k] = d[rows]   # the same clipping square (1.5 times the 8th distance)
            rim[rows] = _star_plane(P, rows, d2, J2, False)[4]
    return rim


def delaunay_from_neighbours(P: np.ndarray, d: np.ndarray, J: np.ndarray, boundary=False,
                             tree=None) -> Laplacian:
    """``"delaunay"``'s operator with each point's star among the given neighbours: ``J``
    (n, k) their indices, ``d`` (n, k) their distances, nearest first (what a benchmark's
    oracle that knows the surface passes in place of the k nearest). ``boundary``: True,
    False or ``"auto"`` (:func:`point_cloud_laplacian`); ``tree``: a KD-tree of ``P``, for
    ``"auto"``."""
    n, k = J.shape
    rows = np.arange(n)
    if boundary == "auto":
        area, w, is_open = _star(P, rows, d, J, False)
        if tree is None:
            from scipy.spatial import cKDTree

            tree = cKDTree(P)
        rim = _rims(P, tree, d, J, is_open)
        if rim.any():
            area[rim], w[rim], _ = _star(P, rows[rim], d[rim], J[rim], True)
    else:
        area, w, is_open = _star(P, rows, d, J, bool(boundary))
        rim = is_open if boundary else np.zeros(n, bool)
    r = np.repeat(rows, k)
    nz = w.ravel() > 0
    W = sp.csr_matrix((w.ravel()[nz], (r[nz], J.ravel()[nz])), shape=(n, n))
    W = ((W + W.T) * 0.5).tocsr()
    # the mass that L is consistent with: f = |x - p_i|² has surface Laplacian 4 at p_i on
    # any surface, and (L f)_i = sum_j W_ij |p_j - p_i|², so m_i = sum_j W_ij |p_j - p_i|² / 4
    # (the Voronoi area for a planar Delaunay star)
    C = W.tocoo()
    mass = 0.25 * np.bincount(C.row, weights=C.data * np.sum((P[C.row] - P[C.col]) ** 2, axis=1),
                              minlength=n)
    good = np.isfinite(area) & (area > 0)
    if not good.all():
        area = np.where(good, area, float(np.mean(area[good])) if good.any() else 1.0)
    mass = np.where(np.isfinite(mass) & (mass > 0), mass, area)   # a point without a neighbour
    data = {"P": P, "method": "delaunay", "k": k, "radius": None, "boundary": boundary,
            "rim": rim}
    return make_laplacian(-W, sp.diags(mass).tocsr(), domain="points", data=data)


def local_triangles(P, k: int = 20, boundary: bool = False, max_tilt: float | None = None,
                    normal_k: int = _NORMAL_K) -> np.ndarray:
    r"""The triangles of every point's local Delaunay fan (the stars behind ``"delaunay"``).

    For each point :math:`p_i`, its Delaunay neighbours in the tangent plane of
    :func:`point_cloud_laplacian` (``method="delaunay"``, same ``k`` and ``boundary``),
    taken in angular order, give the triangles :math:`(i, j_m, j_{m+1})` between
    consecutive neighbours less than π apart. A triangle is listed once per point whose
    star holds it (up to three times: a triangle soup, not a manifold mesh; summing
    the cotangent stiffness of the soup with weight 1/3 gives a Laplacian of the cloud).

    Parameters
    ----------
    P : (n, 3) float, or a mesh object (its points)
    k : int
        Neighbours of each star.
    boundary : bool
        As in :func:`point_cloud_laplacian`.
    max_tilt : float, optional
        Leave out a star's triangles whose 3-D plane is tilted from the star's tangent
        plane by more than this angle (degrees): the ratio of the projected to the 3-D
        area is the cosine of the tilt. Where two sheets of a surface pass closer than
        the sampling's spacing, the star of a point on one takes neighbours on the other,
        and the triangles to them stand steeply on its plane; a triangle that one star
        leaves out is still listed by the stars that hold it flat. Default: keep all.
    normal_k : int
        Neighbours of the first (PCA) normal estimate, before the fan's own normal (at
        least 3; 12, that of :func:`point_cloud_laplacian`, by default). Fewer see less
        of a nearby sheet across a thin part of the surface (a leg or tail a few
        spacings wide) and more of the local noise.

    Returns
    -------
    (m, 3) int
        Rows ``(i, a, b)``, the first entry the point whose star it is.

    Examples
    --------
    >>> import numpy as np
    >>> i, j = np.meshgrid(np.arange(7.0), np.arange(7.0))     # a triangular lattice
    >>> P = np.c_[(i + 0.5 * j).ravel(), (j * np.sqrt(3) / 2).ravel(), np.zeros(49)]
    >>> local_triangles(P, k=12)[local_triangles(P, k=12)[:, 0] == 24].tolist()
    [[24, 18, 25], [24, 25, 31], [24, 31, 30], [24, 30, 23], [24, 23, 17], [24, 17, 18]]
    """
    from scipy.spatial import cKDTree

    P = as_points(as_mesh_arrays(P, name="P", need_cells=False)[0], "P", dims=(3,), min_rows=4)
    if isinstance(k, bool) or not isinstance(k, (numbers.Integral, np.integer)) or k < 3:
        raise ValueError(f"k must be an integer number of neighbours >= 3, got {describe(k)}")
    if max_tilt is not None:
        max_tilt = as_positive(max_tilt, "max_tilt")
        if max_tilt > 90:
            raise ValueError(f"max_tilt must be an angle in (0, 90] degrees, got {max_tilt}")
    if isinstance(normal_k, bool) or not isinstance(normal_k, (numbers.Integral, np.integer)) or normal_k < 3:
        raise ValueError(f"normal_k must be an integer number of neighbours >= 3, got {describe(normal_k)}")
    n = P.shape[0]
    k = min(int(k), n - 1)
    rows = np.arange(n)
    d, J = _knn(cKDTree(P), P, rows, k)
    nb, Q, _, dual, _ = _star_plane(P, rows, d, J, bool(boundary), int(normal_k))
    ang = np.where(dual > 0, np.arctan2(Q[..., 1], Q[..., 0]), np.inf)
    order = np.argsort(ang, axis=1)
    cnt = (dual > 0).sum(axis=1)
    Js = np.take_along_axis(J, order, axis=1)
    angs = np.take_along_axis(ang, order, axis=1)
    Qs = np.take_along_axis(Q, order[..., None], axis=1)
    nbs = np.take_along_axis(nb, order[..., None], axis=1)
    out = []
    for m in range(k):
        b = np.where(m + 1 < cnt, m + 1, 0)
        gap = np.where(b == 0, angs[rows, b] + 2.0 * np.pi - angs[:, m], angs[rows, b] - angs[:, m])
        ok = (m < cnt) & (cnt >= 2) & (gap > 0) & (gap < np.pi)
        if max_tilt is not None:
            qa, qb = Qs[:, m], Qs[rows, b]
            flat = np.abs(qa[:, 0] * qb[:, 1] - qa[:, 1] * qb[:, 0])
            full = np.linalg.norm(np.cross(nbs[:, m], nbs[rows, b]), axis=1)
            ok &= flat >= np.cos(np.radians(max_tilt)) * full
        out.append(np.c_[rows[ok], Js[ok, m], Js[rows, b][ok]])
    return np.concatenate(out).astype(np.int64)


def fan_votes(T, F) -> np.ndarray:
    """How many times the triangle soup ``T`` lists each face of ``F``, as a set of three points.

    With ``T`` from :func:`local_triangles`, the number of points' fans (0 to 3) that hold
    each face of a triangulation ``F`` built from them, e.g. of :func:`tufted_delaunay`
    (where a face made by an intrinsic flip is in no fan).

    Parameters
    ----------
    T : (m, 3) int
        Triangles, repeated as often as they are listed.
    F : (M, 3) int
        Faces on the same points, in any orientation.

    Returns
    -------
    (M,) int64

    Examples
    --------
    >>> import numpy as np
    >>> fan_votes(np.array([[0, 1, 2], [1, 2, 0], [2, 1, 3]]), np.array([[2, 1, 0], [1, 2, 3], [0, 1, 3]])).tolist()
    [2, 1, 0]
    """
    T = np.sort(np.asarray(T, dtype=np.int64).reshape(-1, 3), axis=1)
    F = np.sort(np.asarray(F, dtype=np.int64).reshape(-1, 3), axis=1)
    keys, votes = np.unique(T, axis=0, return_counts=True)
    if not len(keys):
        return np.zeros(len(F), dtype=np.int64)
    # rows of the sorted unique keys, compared lexicographically through a structured view
    row = np.dtype([("a", np.int64), ("b", np.int64), ("c", np.int64)])
    kv, fv = np.ascontiguousarray(keys).view(row).ravel(), np.ascontiguousarray(F).view(row).ravel()
    pos = np.minimum(np.searchsorted(kv, fv), len(kv) - 1)
    return np.where(kv[pos] == fv, votes[pos], 0).astype(np.int64)


def tufted_cover(P, T):
    r"""The tufted cover of a triangle soup (Sharp and Crane 2020): a manifold with two faces at every edge.

    The soup's triangles are first made unique (a triangle listed by several stars of
    :func:`local_triangles` is one face). Every face is then doubled, a front copy with
    the face's orientation and a back copy with the opposite one, and around every edge
    the faces that hold it are taken in their cyclic order about the edge (the angle of
    the opposite vertex in the plane normal to the edge); each face's copy that faces
    the next face in that order is glued to that face's copy facing back. An edge with
    one face (a boundary of the soup) glues the face's two copies, a manifold edge gives
    two sheets, a non-manifold edge with ``K`` faces gives ``K`` glued pairs. The result
    is oriented, every edge has exactly two faces, and its geometry is the soup's (each
    copy keeps its face's edge lengths), possibly covering the soup's surface twice.

    Parameters
    ----------
    P : (n, 3) float
        Points.
    T : (m, 3) int
        Triangles on ``P``, e.g. :func:`local_triangles`.

    Returns
    -------
    F : (2u, 3) int64
        Faces of the cover on the original point indices: the ``u`` unique triangles
        (front), then the same reversed (back, ``F[u + f] = F[f, ::-1]``).
    l : (2u, 3) float
        ``l[f, i]``: length of the edge of face ``f`` opposite its corner ``i``.
    twin : (6u,) int64
        Halfedge ``3 f + i`` (the edge of face f opposite corner i, run in the face's
        orientation) is glued to ``twin[3 f + i]``, which runs the other way between the
        same two points; ``twin[twin] = arange``, and no halfedge is its own twin.

    Examples
    --------
    One triangle: its two copies glued along all three edges (a doubly covered disc)

    >>> import numpy as np
    >>> P = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> F, l, twin = tufted_cover(P, np.array([[0, 1, 2], [1, 2, 0]]))
    >>> F.tolist(), twin.tolist()
    ([[0, 1, 2], [2, 1, 0]], [5, 4, 3, 2, 1, 0])
    """
    P = np.asarray(P, dtype=np.float64)
    T = np.asarray(T, dtype=np.int64)
    if T.ndim != 2 or T.shape[1] != 3 or (T.size and (T.min() < 0 or T.max() >= len(P))):
        raise ValueError(f"T must be (m, 3) indices into the {len(P)} points P, got {describe(T)}")
    _, first = np.unique(np.sort(T, axis=1), axis=0, return_index=True)
    T = T[np.sort(first)]
    m, n = len(T), len(P)
    l = edge_lengths(P, T)
    f = np.repeat(np.arange(m), 3)
    i = np.tile(np.arange(3), m)
    a, b, w = T[f, (i + 1) % 3], T[f, (i + 2) % 3], T[f, i]
    u, v = np.minimum(a, b), np.maximum(a, b)
    # the front halfedge 3f + i runs a -> b, its back copy (corner 2 - i of the reversed
    # face) b -> a; "plus" runs u -> v, "minus" v -> u
    front, back = 3 * f + i, 3 * (m + f) + 2 - i
    plus, minus = np.where(a == u, front, back), np.where(a == u, back, front)
    e = P[v] - P[u]
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    ref = np.where(np.abs(e[:, [0]]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    b1 = np.cross(e, ref)
    b1 /= np.linalg.norm(b1, axis=1, keepdims=True)
    off = P[w] - P[u]
    angle = np.arctan2(np.einsum("ij,ij->i", off, np.cross(e, b1)), np.einsum("ij,ij->i", off, b1))
    key = u * n + v
    order = np.lexsort((angle, key))               # by edge, then about it
    ks = key[order]
    start = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]])
    group = np.repeat(np.arange(start.size), np.diff(np.r_[start, ks.size]))
    size = np.diff(np.r_[start, ks.size])[group]
    pos = np.arange(ks.size) - start[group]
    after = order[start[group] + (pos + 1) % size]   # the next face about the edge
    twin = np.empty(6 * m, dtype=np.int64)
    twin[minus[order]] = plus[after]
    twin[plus[after]] = minus[order]
    return np.r_[T, T[:, ::-1]], np.r_[l, l[:, ::-1]], twin


def _cover_vertices(F, twin):
    """(labels (M, 3), point (k,)): the vertices of a cover whose halfedges are glued by
    ``twin``: corners that the gluing identifies share a label, ``point[label]`` is their
    point."""
    from scipy.sparse.csgraph import connected_components

    M = len(F)
    h = np.arange(3 * M)
    f, i, f2, j = h // 3, h % 3, twin // 3, twin % 3
    # halfedge h runs corner (f, i+1) -> (f, i+2), its twin (f2, j+1) -> (f2, j+2) back
    rows = np.r_[3 * f + (i + 1) % 3, 3 * f + (i + 2) % 3]
    cols = np.r_[3 * f2 + (j + 2) % 3, 3 * f2 + (j + 1) % 3]
    k, label = connected_components(sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(3 * M, 3 * M)),
                                    directed=False)
    point = np.empty(k, dtype=np.int64)
    point[label] = F.ravel()
    return label.reshape(M, 3), point


def tufted_delaunay(P, T, mollify: float = 1e-5):
    r"""Intrinsic Delaunay triangulation of the tufted cover of a triangle soup (Sharp and Crane 2020).

    The cover (:func:`tufted_cover`) is a manifold, so its edges can be flipped like a
    mesh's: its edge lengths are mollified (:func:`~spectral_igl.laplacian.intrinsic.mollify`,
    ``mollify`` times the mean length) and flipped to the intrinsic Delaunay
    triangulation (:func:`~spectral_igl.laplacian.intrinsic.intrinsic_delaunay`), whose
    cotangent weights are non-negative. Half the cotangent stiffness and half the lumped
    mass of the result (the cover has every face twice) are the Laplacian of the soup
    that robust_laplacian builds for point clouds. The flips find twins by their end
    points, so the cover is handed over on its own vertices (the corners the gluing
    identifies); where two edges of the cover join the same two cover vertices, which
    happens at some non-manifold edges of a soup (0.4% to 3% of the edges of the stars
    of the real point clouds measured), those edges are left unflipped.

    Parameters
    ----------
    P : (n, 3) float
    T : (m, 3) int
        Triangles on ``P``, e.g. :func:`local_triangles`.
    mollify : float
        Relative mollification of the edge lengths (robust_laplacian's 1e-5).

    Returns
    -------
    l : (M, 3) float
        Intrinsic edge lengths, ``l[f, i]`` opposite corner ``i``.
    F : (M, 3) int64
        Faces on the original point indices (``M`` twice the number of unique triangles).

    Examples
    --------
    On a closed Delaunay mesh the cover is two copies of it and nothing flips:

    >>> import numpy as np
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(1)
    >>> l, Fc = tufted_delaunay(V, F)
    >>> Fc.shape == (2 * len(F), 3), bool(np.allclose(np.sort(l, axis=1)[:len(F)], np.sort(l, axis=1)[len(F):]))
    (True, True)
    """
    F, l, twin = tufted_cover(P, T)
    l, _ = mollify_lengths(l, as_positive(mollify, "mollify") if mollify else 0.0)
    label, point = _cover_vertices(F, twin)
    l, Fl = intrinsic_delaunay(l, label)
    return l, point[Fl]
