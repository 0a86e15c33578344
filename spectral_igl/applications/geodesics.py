"""Geodesic distances from heat: the heat method (Crane et al. 2013) and Varadhan's formula."""
from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp

from .._validate import as_flag, as_indices, as_mesh_arrays, as_nonnegative, as_positive, describe
from ..approx import SpectralOperator
from ..filters import heat
from ..laplacian import Laplacian, as_laplacian, laplacian
from ..laplacian.elements import element_measures, pattern_components
from ..laplacian.inputs import as_laplacian_or_triangles
from ..laplacian import units
from ..laplacian.units import optional_time
from ..laplacian.intrinsic import edge_lengths, normalized_gradient_divergence
from ..laplacian.intrinsic_fem import (frame_gradients, gradient_matrix, hat_stiffness, intrinsic_operators,
                                       intrinsic_parts)
from ..laplacian.points import JOIN_K, fan_votes, local_triangles, neighbour_pieces, tufted_delaunay
from ..linalg import factorize, ldlt
from ..progress import progress_bar
from .heat_steps import PositiveHeat

__all__ = ["HeatGeodesics", "geodesic_distance", "varadhan_distance", "mean_edge_length", "intrinsic_operators"]

_STEPS = ("euler", "intrinsic_delaunay", "engine", "tufted_cover")

#: where one of the heat method's distances is more than this share and :data:`FLOOR_EDGES`
#: mean edge lengths below the straight line to its source (a lower bound of the geodesic
#: distance), all that are below it are raised to it, with a warning. The method's own error
#: next to the source is of the order of an edge (101 of an icosphere(3)'s vertices a little
#: below the chord; 34% below it one ring from a source on homer): those results are left as
#: they are. Far below: 60% on beetle's non-manifold panels (79% before the heat step was
#: made Metzler, :func:`_metzler_values`), 66% on truck
FLOOR_WARN = 0.3
FLOOR_EDGES = 2.0


def _nearest(ends, X):
    """Distance from each row of X to the nearest row of ``ends``."""
    from scipy.spatial import cKDTree

    return cKDTree(ends).query(X)[0]


def mean_edge_length(V, C=None) -> float:
    """Mean length of the (unique) edges of a triangle or tetrahedral mesh.

    ``(V, C)`` are arrays, or ``V`` is a pyvista/trimesh/meshio mesh and ``C`` is omitted.
    """
    import igl

    V, C = as_mesh_arrays(V, C)
    V = np.asarray(V, dtype=float)

    E = igl.edges(np.ascontiguousarray(C))
    return float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())


def _metzler_values(data, on_diagonal, col, diag):
    """The values ``data`` of a symmetric stiffness in CSC (``col`` each entry's column,
    ``diag`` the positions of the diagonal, one per column) with its positive off-diagonal
    entries (negative edge weights) set to 0 and the diagonal raised to keep zero sums, on
    the same pattern: the heat step's operator is then Metzler and its heat positive and
    monotone along edges. An intrinsic Delaunay triangulation has none on a closed manifold;
    the edges that no flip reaches (non-manifold and boundary edges) may: on beetle.obj's
    non-manifold panels 110 of them made the heat oscillate, and 1,096 distances from four
    sources fell below 0.9 of the straight line to their source (130 with this, potpourri3d
    76). The Poisson step keeps the full stiffness, which its divergence is consistent with."""
    bad = (data > 0) & ~on_diagonal
    if not bad.any():
        return data
    out = data.copy()
    out[bad] = 0.0
    out[diag] += np.bincount(col[bad], weights=data[bad], minlength=len(diag))
    return out


def _with_diagonal(L) -> sp.csr_matrix:
    """``L`` in canonical CSR with every diagonal entry stored (explicit zeros added)."""
    L = sp.csr_matrix(L)
    n = L.shape[0]
    if L.has_canonical_format:
        rows = np.repeat(np.arange(n), np.diff(L.indptr))
        if np.count_nonzero(L.indices == rows) == n:
            return L
    C = L.tocoo()
    ar = np.arange(n)
    out = sp.csr_matrix((np.r_[C.data, np.zeros(n)], (np.r_[C.row, ar], np.r_[C.col, ar])), shape=L.shape)
    out.sum_duplicates()
    return out


def _as_laplacian(lap_or_mesh, domains=("triangle", "tet")) -> Laplacian:
    lap = as_laplacian(lap_or_mesh, "lap_or_mesh")
    if lap.domain not in domains or ("V" not in lap.data and "P" not in lap.data):
        kinds = {"triangle": "triangle", "tet": "tet", "polygon": "polygon", "points": "point cloud"}
        raise ValueError(f"this needs a {' or '.join(kinds[d] for d in domains)} Laplacian (with its "
                         f"vertices in lap.data), got domain {lap.domain!r}")
    return lap


def _polygon_fans(lap: Laplacian):
    """(Vr, T): a polygon Laplacian's refinement, every polygon a fan of triangles around its
    virtual vertex (the vertices first, then one virtual vertex per polygon, as in
    :func:`spectral_igl.laplacian.polygon.polygon_laplacian`)."""
    V, n = lap.data["V"], lap.n
    tris, start = [], n
    for F in lap.data["faces"]:
        m, k = F.shape
        c = np.repeat(start + np.arange(m)[:, None], k, axis=1)
        tris.append(np.stack([F, np.roll(F, -1, axis=1), c], axis=2).reshape(-1, 3))
        start += m
    return np.vstack([V, lap.data["C"]]), np.concatenate(tris)


#: ``step="tufted_cover"``: a star's triangles tilted by more than this (degrees) from its
#: tangent plane are left out: bridges to a sheet closer than the spacing (homer's limbs)
#: stand at 60° to 90°, the triangles across a 90° crease (fandisk) at 45°. Measured in
#: ``benchmarks/geodesic_domains.py``: 40° loses fandisk's creases (4.8% to 6.3% against
#: 1.5% to 1.9%), homer's error grows from 40° (2.5% to 3.6%) to 60° (3.1% to 4.3%); with
#: the normals of :data:`_POINT_NORMAL_K` and the votes, 55° puts cow behind potpourri3d
#: in two of seven draws, 60° in none
_POINT_MAX_TILT = 60.0
#: ``step="tufted_cover"``: neighbours of the fans' first (PCA) normal. 12 (the cloud
#: Laplacian's) sees the body through cow's legs and tail; 8 gives them their own plane
#: (cow 5.08% -> 4.74% mean over seven draws with the votes); 6 and 10 do worse on cow
_POINT_NORMAL_K = 8
#: ``step="tufted_cover"``: the default time in mean squared edge lengths of the cover.
#: The mean square, not the squared mean, so that an unevenly spaced cloud diffuses
#: further (mean(l²)/mean(l)² is 1.36 on cow, 1.18 on spot, 1.05 on fandisk): 0.75 puts
#: cow behind potpourri3d in one draw of seven, 0.85 spot in two, 0.8 neither
_POINT_TIME = 0.8


def _pieces(n, T, L=None):
    """Connected pieces of the n points under the edges of the rows of T (2 or 3 columns),
    and those of the matrix L if given."""
    from scipy.sparse.csgraph import connected_components

    T = np.asarray(T, dtype=np.int64)
    i, j = T.ravel(), np.roll(T, 1, axis=1).ravel()
    A = sp.coo_matrix((np.ones(i.size), (i, j)), shape=(n, n)).tocsr()
    if L is not None:
        A = A + abs(sp.csr_matrix(L))
    return int(connected_components(A, directed=False)[0])


def _point_parts(lap: Laplacian, cover: bool, mollify: float):
    r"""(gx, gy, A, T, L, mass, h) of a point cloud's heat method.

    ``cover=False``: its local Delaunay triangles ``T`` (each point's star,
    :func:`~spectral_igl.laplacian.points.local_triangles`), their hat gradients in their
    own frames, a third of their areas (a triangle is in up to three stars), the stiffness
    :math:`G^\top \mathrm{diag}(A)\, G` of that soup, the cloud's own mass, and ``h`` the
    soup's mean edge length. ``cover=True``: the same of the intrinsic Delaunay
    triangulation of the tufted cover of those triangles
    (:func:`~spectral_igl.laplacian.points.tufted_delaunay`; the fans' first normals from
    :data:`_POINT_NORMAL_K` neighbours, triangles tilted more than
    :data:`_POINT_MAX_TILT` from their star's plane left out), each face's area halved
    (the cover has every face twice) and weighted by the share of its three points' fans
    that list it (a face made by a flip: the mean share of the fans' triangles), its lumped mass (the cloud's at a point in no
    triangle), and ``h`` the root mean square edge length. Either stiffness has a 1e-3
    share of the cloud's own, so that a point in no triangle stays attached."""
    P, n = lap.data["P"], lap.n
    k = lap.data.get("k") if lap.data.get("method") == "delaunay" else 20
    boundary = lap.data.get("boundary") is True  # "auto" stars keep their clipped cells here
    if not cover:
        T = local_triangles(P, k=k, boundary=boundary)
        l = edge_lengths(P, T)
        gx, gy, A = frame_gradients(l)
        L = (hat_stiffness(gx, gy, A / 3.0, T, n) + 1e-3 * _with_diagonal(lap.L)).tocsr()
        return gx, gy, A / 3.0, T, L, lap.mass, float(l.mean())
    fans = local_triangles(P, k=k, boundary=boundary, max_tilt=_POINT_MAX_TILT, normal_k=_POINT_NORMAL_K)
    if k < JOIN_K and _pieces(n, fans, lap.L) > neighbour_pieces(P, JOIN_K):
        # the stars leave apart what a wider neighbourhood joins (a cloud Laplacian built with
        # a k of the user's): the cover's stars take JOIN_K neighbours, as potpourri3d's do
        # (camel_b's vertices: distances to its legs were inf; now 18.1% against 18.2%)
        fans = local_triangles(P, k=JOIN_K, boundary=boundary, max_tilt=_POINT_MAX_TILT,
                               normal_k=_POINT_NORMAL_K)
    l, T = tufted_delaunay(P, fans, mollify)
    share = fan_votes(fans, T) / 3.0
    gx, gy, A = frame_gradients(l)
    # a face listed by all three fans around it is surer than one a single fan holds (cow:
    # 44% of its fans' triangles are in one fan only, where the fans disagree about the
    # surface); the 1e-3 share of the cloud's stiffness is against these weights
    mean_share = len(fans) / (3.0 * len(np.unique(np.sort(fans, axis=1), axis=0))) if len(fans) else 1.0
    A = 0.5 * A * np.where(share > 0, share, mean_share)
    L = (hat_stiffness(gx, gy, A, T, n) + 1e-3 * _with_diagonal(lap.L)).tocsr()
    mass = np.bincount(T.ravel(), weights=np.repeat(A / 3.0, 3), minlength=n)
    mass = np.where(mass > 0, mass, lap.mass)
    return gx, gy, A, T, L, mass, float(np.sqrt(np.mean(l ** 2)))


def _libigl_order(mesh, source, method):
    """``(mesh, source, method)`` with libigl's and potpourri3d's positional habit
    ``f(V, F, source)`` read as ``f((V, F), source)``."""
    def integer_cells(x):
        return isinstance(x, np.ndarray) and x.ndim == 2 and x.dtype.kind in "iu" and x.shape[1] in (3, 4)

    if not (isinstance(mesh, np.ndarray) and mesh.ndim == 2 and integer_cells(source)):
        return mesh, source, method
    if isinstance(method, str):
        raise TypeError("geodesic_distance(V, F) needs a source vertex: call "
                        "geodesic_distance(V, F, source) or geodesic_distance((V, F), source, method=...)")
    return (mesh, source), method, "heat"


def _cells(lap: Laplacian) -> np.ndarray:
    return lap.data["F"] if lap.domain == "triangle" else lap.data["T"]


class HeatGeodesics:
    r"""Reusable heat-method geodesic distance solver (Crane, Weischedel, Wardetzky 2013).

    Three steps, each a sparse solve with a matrix factorized once here:

    .. math::
        u = (B + tL)^{-1}\delta_\gamma, \qquad X = -\nabla u / |\nabla u|, \qquad
        L \phi = \nabla^{\!\top} (A\, X),

    then :math:`\phi` is shifted to vanish at the sources (``A`` the element areas or
    volumes, so :math:`\nabla^\top A \nabla = L` for the cotangent stiffness).

    On a polygon mesh (:func:`~spectral_igl.laplacian.polygon.polygon_laplacian`) the three
    steps run on the Laplacian's own refinement, every polygon a fan of triangles around
    its virtual vertex, and the distance is read on the polygon vertices. On a point cloud
    (:func:`~spectral_igl.laplacian.points.point_cloud_laplacian`) all three steps run by
    default on the intrinsic Delaunay triangulation of the tufted cover of the triangles of
    every point's local Delaunay fan (:func:`~spectral_igl.laplacian.points.local_triangles`;
    Sharp and Crane 2020, potpourri3d's construction, on our fans:
    :func:`~spectral_igl.laplacian.points.tufted_delaunay`), the fans' first normals from 8
    neighbours (thin parts, legs and tails, get their own plane), without the triangles that
    stand more than 60° on their fan's plane (bridges to a sheet closer than the spacing),
    each face weighted by the share of its points' fans that list it, at
    :math:`t = 0.8h^2`, :math:`h^2` the mean squared edge length of the cover. With
    ``step="euler"`` the heat step is the cloud's own
    :math:`(B + tL)^{-1}` and the gradient, divergence and Poisson step use the fans'
    triangles, each with a third of its area (a triangle is in up to three fans). Mean relative error against ``igl.exact_geodesic`` at the
    default t, beside potpourri3d on the same input (``benchmarks/geodesic_domains.py``: 12
    random sources, unit area; then ``--seed 1``): horse_quad (quads, exact on its
    triangulation) 1.8% (``PolygonMeshHeatSolver`` 33%, its
    ``MeshHeatMethodDistanceSolver`` on the triangulated quads 2.4%); point clouds, in %,
    ``step="euler"`` / the default (the cover) / ``PointCloudHeatSolver``:

    =========================== ================== ==================
    points                      draw 1             draw 2
    =========================== ================== ==================
    unit sphere, 4,000 random   2.23 / 1.78 / 1.95 2.29 / 1.88 / 2.10
    spot's vertices             1.87 / 1.87 / 2.01 1.98 / 1.90 / 1.94
    cow                         6.25 / 6.32 / 6.48 5.70 / 5.70 / 5.72
    homer                       4.16 / 3.86 / 4.07 3.85 / 3.44 / 3.67
    rocker-arm                  2.40 / 1.81 / 2.36 2.30 / 1.85 / 2.10
    fandisk                     2.52 / 1.91 / 3.88 2.60 / 1.78 / 3.32
    cheburashka                 2.66 / 2.31 / 3.25 2.94 / 2.68 / 3.31
    =========================== ================== ==================

    ``"euler"`` is behind potpourri3d on three or four clouds of a draw, by up to 14%; the
    default is at or below it on all seven clouds in all seven draws ``--seed 0`` to ``6``
    (mean over the draws 4.74% against 4.97% on cow, the coarsest and most unevenly spaced
    sampling, where it is closest: 5.70% against 5.72% in draw 2), and with Gaussian noise
    of 0.1 and 0.2 of the median spacing (``--noise``, ``--seed 0`` and ``1``) in all 28
    cases. On cow the fans disagree (44% of their triangles are listed by one fan only, 3%
    to 28% on the other clouds), and its tail lies closer to the body than the spacing:
    the two sources on it drawn (vertices 180 and 211) keep errors of 19.8% and 24.7%
    (potpourri3d 18.7% and 25.0%), the fans there bridging to the body.

    Parameters
    ----------
    lap_or_mesh : Laplacian, (V, F) or (V, T), or a pyvista/trimesh/meshio mesh
        A triangle or tetrahedral mesh, polygon mesh or point-cloud Laplacian (its ``L``
        and ``B`` are used), or the arrays, in which case the cotangent Laplacian with
        lumped mass is built (a ``trimesh.PointCloud`` or other object without cells gives
        :func:`~spectral_igl.laplacian.points.point_cloud_laplacian`).
    t : float, optional
        Diffusion time; default :math:`h^2`, ``h`` the mean edge length (Crane's m = 1);
        :math:`0.8h^2` on a point cloud's cover, ``h²`` the mean squared edge length of the
        cover.
    step : {"euler", "intrinsic_delaunay", "engine", "tufted_cover"}, default "intrinsic_delaunay"
        How the heat is diffused. ``"euler"``: one backward-Euler step
        :math:`(B + tL)^{-1}` with ``lap``. ``"intrinsic_delaunay"``: the same step with
        the intrinsic-Delaunay stiffness (tets fall back to ``"euler"``; on a point cloud it
        is ``"tufted_cover"``).
        ``"engine"``: the exact heat kernel :math:`e^{-t\tilde L}B^{-1}\delta` through
        :class:`spectral_igl.SpectralOperator` (not on point clouds). ``"tufted_cover"``:
        point clouds only, all three steps on the tufted cover of the local triangles
        (above; the default there). The default is the most accurate against
        exact geodesics on the meshes measured in ``benchmarks/geodesics.py``. The exact
        kernel is the least accurate there (9% to 18% mean relative error at
        :math:`t = h^2`, once its distances far below the straight line to the source are
        raised to that line, with a warning; 54% to 83% before): it decays like
        :math:`e^{-d^2/4t}`, so about 9 rings from the
        source (:math:`e^{-d^2/4h^2} < 10^{-8}`) it is below the engine's certified
        absolute accuracy and its normalised gradient is noise, while the backward-Euler
        kernel decays only exponentially and keeps a usable direction everywhere.
    mollify : float
        Intrinsic mollification of ``step="intrinsic_delaunay"``, relative to the mean
        edge length.
    progress : bool, optional
        A progress bar on stderr over the precomputation: operators, heat
        factorization, Poisson factorization (see :mod:`spectral_igl.progress`; default
        off).

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(4)
    >>> d = HeatGeodesics((V, F)).compute(0)
    >>> exact = np.arccos(np.clip(V @ V[0], -1, 1))
    >>> bool(np.abs(d - exact).max() < 0.05)
    True
    """

    def __init__(self, lap_or_mesh, t: float | None = None, step: str = "intrinsic_delaunay",
                 mollify: float = 1e-6, progress=None):
        if not isinstance(step, str) or step not in _STEPS:
            raise ValueError(f"step must be one of {_STEPS}, got {describe(step)}")
        mollify = as_nonnegative(mollify, "mollify")
        self.mollify, self._fans = float(mollify), None
        # a triangle mesh's arrays need no Laplacian: the intrinsic-Delaunay step builds its
        # own operators, and the Laplacian is built only if asked for (self.lap)
        lap = (as_laplacian_or_triangles(lap_or_mesh, "lap_or_mesh") if step == "intrinsic_delaunay"
               else _as_laplacian(lap_or_mesh, ("points",)) if step == "tufted_cover" else lap_or_mesh)
        if isinstance(lap, tuple) and step == "intrinsic_delaunay":
            self._lap, self._mesh = None, lap
            self.n, self._components = lap[0].shape[0], None   # components: from the operators
            self._init_steps(step, t, progress)
            return
        lap = _as_laplacian(lap, ("triangle", "tet", "polygon", "points"))
        self._lap, self._mesh = lap, None
        self.n, self._components = lap.n, lap.components
        if lap.domain == "polygon":
            # the heat method on the polygon Laplacian's own refinement (every polygon a fan
            # around its virtual vertex), read back on the polygon vertices
            self._fans = HeatGeodesics(_polygon_fans(lap), t=t, step=step, mollify=mollify,
                                       progress=progress)
            self.step, self.t, self.h = step, self._fans.t, self._fans.h
            return
        if lap.domain == "points" and step == "engine":
            raise ValueError("step='engine' needs a triangle or tet mesh; a point cloud's heat "
                             "method takes step='intrinsic_delaunay' (the default), 'euler' or 'tufted_cover'")
        if lap.domain == "tet" and step == "intrinsic_delaunay":
            step = "euler"
        if lap.domain == "points" and step == "intrinsic_delaunay":
            step = "tufted_cover"     # a cloud's intrinsic Delaunay triangulation is its cover's
        self._init_steps(step, t, progress)

    @property
    def lap(self) -> Laplacian:
        """The Laplacian of the input: the one given, or, for a triangle mesh given as arrays
        or a mesh object, :func:`spectral_igl.laplacian` of it with its defaults, built at the
        first access (the default step does not need it)."""
        if self._lap is None:
            with warnings.catch_warnings():   # the mesh's warnings were given at construction
                warnings.filterwarnings("ignore", r"\d+ vertex/vertices referenced by no element", RuntimeWarning)
                self._lap = laplacian(*self._mesh)
        return self._lap

    def _init_steps(self, step, t, progress):
        """The operators and factorizations of the three steps."""
        import igl

        lap = self._lap
        self.step = step
        bar = progress_bar(3, "heat geodesics", progress, unit="step")
        bar.set_postfix_str("operators")
        if lap is not None and lap.domain == "points":
            cover = step == "tufted_cover"
            gx, gy, self.A, Fi, Lp, mass, self.h = _point_parts(lap, cover, self.mollify)
            if cover:   # the cover's stars may join what the cloud's Laplacian leaves apart
                self._components = pattern_components(Lp)[0]
            self.G = gradient_matrix(gx, gy, Fi, self.n)
            self._hats = (gx, gy, Fi)
            self._dim = 2
            Lh, M = (Lp if cover else lap.L), sp.diags(mass).tocsr()
        elif step == "intrinsic_delaunay":
            V, C = self._mesh if lap is None else (lap.data["V"], _cells(lap))
            gx, gy, self.A, Fi, Lp, M, self.h = intrinsic_parts(V, C, self.mollify)
            if self._components is None:   # flips keep the components: the mesh's are Lp's
                self._components = pattern_components(Lp)[0]
            self.G = gradient_matrix(gx, gy, Fi, self.n)
            self._hats = (gx, gy, Fi)
            self._dim = 2
            Lh = Lp
        else:
            V, C = lap.data["V"], _cells(lap)
            Vg = V if V.shape[1] == 3 else np.c_[V, np.zeros(len(V))]
            self.G = igl.grad(np.ascontiguousarray(Vg), C).tocsr()
            self._dim = self.G.shape[0] // C.shape[0]
            self._hats = None
            self.A = element_measures(V, C)
            Lp = Lh = lap.L
            M = sp.diags(lap.mass).tocsr()
            self.h = units.mean_edge_length(lap)      # cached on lap
        if t is None:
            self.t = (_POINT_TIME if step == "tufted_cover" else 1.0) * self.h ** 2
        else:
            self.t = as_positive(t, "t")
        self._GT = self.G.T
        bar.update()
        bar.set_postfix_str("heat factorization")
        # Poisson solve: ground one vertex per component (the rhs is consistent)
        ground = np.unique(self._components, return_index=True)[1]
        keep = np.ones(self.n, dtype=bool)
        keep[ground] = False
        self._fixed, self._free = ground, np.flatnonzero(keep)
        if step != "engine" and (lap is None or lap.domain != "points") and ldlt.available():
            # M + tL and the grounded L (its grounded rows and columns replaced by the
            # identity's) are stored on the pattern of L with its whole diagonal: one
            # ordering and symbolic analysis, two numeric LDLᵀ factorizations. The ordering
            # is minimum degree (compiled): nested dissection costs more than both numeric
            # factorizations together here, for a factor of about the same size
            S = _with_diagonal(Lh)
            # intrinsic_operators' L is exactly symmetric: its CSR arrays are its CSC arrays
            S = (sp.csc_matrix((S.data, S.indices, S.indptr), shape=S.shape)
                 if step == "intrinsic_delaunay" else S.tocsc())
            col = np.repeat(np.arange(self.n), np.diff(S.indptr))
            diag = np.flatnonzero(S.indices == col)   # one per column, in column order
            pattern = ldlt.Pattern(S, ordering="minimum_degree")
            heat_data = _metzler_values(S.data, S.indices == col, col, diag) if step == "intrinsic_delaunay" \
                else S.data
            vals = self.t * heat_data
            vals[diag] += M.diagonal()
            self._heat = ldlt.LDLT(sp.csc_matrix((vals, S.indices, S.indptr), shape=S.shape), pattern)
            bar.update()
            bar.set_postfix_str("Poisson factorization")
            vals = np.where(keep[S.indices] & keep[col], S.data, 0.0)
            vals[diag[ground]] = 1.0
            Lg = sp.csc_matrix((vals, S.indices, S.indptr), shape=S.shape)
            self._poisson, self._grounded = ldlt.LDLT(Lg, pattern), True
            bar.update()
            bar.close()
            return
        if step == "engine":
            self._op = SpectralOperator(lap, heat(self.t))
        else:
            if step == "intrinsic_delaunay":
                S = _with_diagonal(Lh).tocsc()
                col = np.repeat(np.arange(self.n), np.diff(S.indptr))
                on = S.indices == col
                Lh = sp.csc_matrix((_metzler_values(S.data, on, col, np.flatnonzero(on)), S.indices, S.indptr),
                                   shape=S.shape)
            self._heat = factorize((M + self.t * Lh).tocsr())
        bar.update()
        bar.set_postfix_str("Poisson factorization")
        self._poisson, self._grounded = factorize(sp.csr_matrix(Lp[self._free][:, self._free])), False
        bar.update()
        bar.close()

    def _positions(self):
        """(n, 3) vertex positions, or None (a Laplacian given as matrices)."""
        if self._mesh is not None:
            return self._mesh[0]
        data = self._lap.data or {}
        return data.get("V", data.get("P"))

    def _floor(self, d: np.ndarray, src: np.ndarray) -> np.ndarray:
        """``d`` (n,) or (n, k) as it is (but for negative values, raised to the line) where no
        distance falls below the straight line to the nearest source of the same component
        (column k: ``src[k]`` alone), a lower bound of any geodesic distance, by more than
        :data:`FLOOR_WARN` of it and :data:`FLOOR_EDGES` mean edge lengths; else raised to
        that line wherever below it, with a warning: the heat method has failed there."""
        P = self._positions()
        if P is None or P.shape[0] != self.n:
            return d
        comps = self._components
        if d.ndim == 1:
            line = np.full(self.n, np.inf)
            for c in np.unique(comps[src]):
                at = comps == c
                ends = P[src[comps[src] == c]]
                line[at] = np.min(np.linalg.norm(P[at][:, None, :] - ends[None, :, :], axis=2), axis=1) \
                    if len(ends) <= 64 else _nearest(ends, P[at])
        else:
            line = np.linalg.norm(P[:, None, :] - P[src][None, :, :], axis=2)
            line[comps[:, None] != comps[src][None, :]] = np.inf
        finite = np.isfinite(d) & np.isfinite(line)
        short = np.where(finite, line - np.where(finite, d, 0.0), 0.0)
        if not np.any((short > FLOOR_WARN * line) & (short > FLOOR_EDGES * self.h)):
            return np.where(d < 0, line, d)                 # a negative distance is never right
        low = finite & (d < line)
        worst = float(np.max(1.0 - d[low] / line[low]))
        warnings.warn(f"the heat method put {int(low.sum())} of {int(finite.sum())} distances below the "
                      f"straight line to their source, the worst by {100 * worst:.0f}%: they were raised to "
                      "it, a lower bound of the geodesic distance. Its field is not a distance's gradient "
                      "here (a boundary, non-manifold edges, coincident vertices?); compare another step "
                      "or igl.exact_geodesic", RuntimeWarning, stacklevel=3)
        return np.where(low, line, d)

    def _diffuse(self, delta: np.ndarray) -> np.ndarray:
        if self.step == "engine":
            return np.real(self._op.apply_inverse_mass(delta))
        return self._heat.solve(delta)

    def compute(self, sources) -> np.ndarray:
        """(n,) geodesic distance to the nearest of ``sources`` (int or (s,) int).

        Vertices in a connected component without a source get ``inf``.
        """
        src = as_indices(sources, self.n, "sources")
        if self._fans is not None:
            return self._fans.compute(src)[:self.n]
        delta = np.zeros(self.n)
        delta[src] = 1.0
        u = self._diffuse(delta)
        if self._hats is not None:
            gx, gy, Fi = self._hats
            return self._floor(self._integrate(normalized_gradient_divergence(u, gx, gy, self.A, Fi), src),
                               np.atleast_1d(src))
        g = (self.G @ u).reshape(self._dim, -1)           # (dim, m): x row, y row (, z row)
        norm = np.sqrt(np.einsum("ij,ij->j", g, g))
        # X = -∇u / |∇u| (zero where ∇u vanishes), integrated against the element measures
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.where(norm > 0, -self.A / norm, 0.0)
        g *= w
        return self._floor(self._integrate(self._GT @ g.ravel(), src), np.atleast_1d(src))

    def _integrate(self, div: np.ndarray, src: np.ndarray) -> np.ndarray:
        phi = np.zeros(self.n)
        if self._grounded:
            div[self._fixed] = 0.0
            phi = self._poisson.solve(div)
            phi[self._fixed] = 0.0
        else:
            phi[self._free] = self._poisson.solve(div[self._free])
        if len(self._fixed) == 1:                       # one connected component
            phi -= phi[src].mean()
            return phi
        comps = self._components
        out = np.full(self.n, np.inf)
        for c in np.unique(comps[src]):
            mask = comps == c
            s = src[comps[src] == c]
            out[mask] = phi[mask] - phi[s].mean()
        return out


    def compute_each(self, sources, block: int = 256) -> np.ndarray:
        """(n, s) geodesic distances, column k from ``sources[k]`` alone: the solves of a
        block of sources together (``inf`` outside each source's component)."""
        src = as_indices(sources, self.n, "sources").reshape(-1)
        if self._fans is not None:
            return self._fans.compute_each(src, block)[:self.n]
        out = np.empty((self.n, src.size))
        comps = self._components
        for a in range(0, src.size, block):
            s = src[a:a + block]
            k = s.size
            delta = np.zeros((self.n, k))
            delta[s, np.arange(k)] = 1.0
            u = self._diffuse(delta)
            g = (self.G @ u).reshape(self._dim, -1, k)
            norm = np.sqrt(np.sum(g * g, axis=0))
            with np.errstate(invalid="ignore", divide="ignore"):
                X = np.where(norm > 0, -g / norm, 0.0) * self.A[None, :, None]
            div = self.G.T @ X.reshape(-1, k)
            if self._grounded:
                div[self._fixed] = 0.0
                phi = self._poisson.solve(div)
                phi[self._fixed] = 0.0
            else:
                phi = np.zeros((self.n, k))
                phi[self._free] = self._poisson.solve(div[self._free])
            same = comps[:, None] == comps[s][None, :]
            out[:, a:a + k] = self._floor(np.where(same, phi - phi[s, np.arange(k)][None, :], np.inf), s)
        return out


def geodesic_distance(lap_or_mesh, source, method: str = "heat", t: float | None = None,
                      step: str = "intrinsic_delaunay", progress=None, time_unit: str = "absolute"):
    r"""Geodesic distance from ``source`` by the heat method or Varadhan's formula.

    Parameters
    ----------
    lap_or_mesh : Laplacian, (V, F) or (V, T), or a pyvista/trimesh/meshio mesh
        Triangle or tetrahedral mesh (see :mod:`spectral_igl.laplacian.inputs`), or, for the
        heat method, a polygon-mesh or point-cloud Laplacian or a point cloud. libigl's and
        potpourri3d's order ``geodesic_distance(V, F, source)`` is read as
        ``geodesic_distance((V, F), source)``.
    source : int or (s,) int
        Source vertex (or vertices: distance to the nearest).
    method : {"heat", "varadhan"}
        ``"heat"``: :class:`HeatGeodesics` (recommended). ``"varadhan"``:
        :func:`varadhan_distance`, :math:`d = \sqrt{-4t \log K_t(p, q)}` (see there for
        where it is and is not accurate).
    t : float, optional
        Diffusion time; default :math:`h^2` for the heat method, ``h`` the mean edge
        length, and :math:`4h^2` for Varadhan.
    step : str
        Heat step of the heat method, see :class:`HeatGeodesics`.
    progress : bool, optional
        Heat method: a progress bar over the precomputation (see
        :mod:`spectral_igl.progress`; default off).
    time_unit : str
        Unit of ``t`` (:mod:`spectral_igl.laplacian.units`): ``"absolute"`` (default),
        ``"shape"``, ``"area"``, ``"volume"`` or ``"h2"`` (``t=1, time_unit="h2"`` is the
        heat method's default).

    Returns
    -------
    (n,) float
        ``inf`` exactly on the vertices of connected components that hold no source (e.g.
        vertices no face references): no path reaches them.

    Notes
    -----
    The survey's §6.2.3 (geodesics from the heat kernel).

    Examples
    --------
    Against great-circle distances on the unit sphere (642 vertices):

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(3))
    >>> V = lap.data["V"] / np.linalg.norm(lap.data["V"], axis=1, keepdims=True)
    >>> exact = np.arccos(np.clip(V @ V[0], -1.0, 1.0))
    >>> d = sig.geodesic_distance(lap, 0)
    >>> float(d[0]), bool(np.mean(np.abs(d - exact)) < 0.03 * np.mean(exact))
    (0.0, True)
    """
    lap_or_mesh, source, method = _libigl_order(lap_or_mesh, source, method)
    if not isinstance(method, str) or method not in ("heat", "varadhan"):
        raise ValueError(f"method must be 'heat' or 'varadhan', got {describe(method)}")
    if method == "varadhan" and step != "intrinsic_delaunay":
        raise ValueError(f"step applies to method='heat' only, got step={step!r} with method='varadhan'")
    if time_unit != "absolute":
        lap_or_mesh = _as_laplacian(lap_or_mesh, ("triangle", "tet") if method == "varadhan"
                                    else ("triangle", "tet", "polygon", "points"))
        t = optional_time(lap_or_mesh, t, time_unit)
    if method == "heat":
        return HeatGeodesics(lap_or_mesh, t=t, step=step, progress=progress).compute(source)
    if method == "varadhan":
        return varadhan_distance(lap_or_mesh, source, t=t)
    raise ValueError(f"method must be 'heat' or 'varadhan', got {method!r}")


#: Varadhan's formula is used where d^2 / 4t is near this ratio (measured best of 1 to 32)
_VARADHAN_RATIO = 8.0
#: the smallest time of the ladder, in squared mean edge lengths (below it the mesh's kernel is
#: not the surface's)
_VARADHAN_T0 = 4.0


def varadhan_distance(lap_or_mesh, source, t: float | None = None, normalize: bool = True,
                      steps: int = 64):
    r"""Geodesic distance from the heat kernel by Varadhan's formula, finite everywhere.

    .. math:: d(p, q)^2 = \lim_{t\to 0} -4t \log K_t(p, q)

    At a fixed time the formula holds only in a band of distances: where :math:`d^2/4t` is
    small the kernel is the mesh's rather than the surface's, and far out the discrete
    kernel decays like the mesh graph's, more slowly than the Gaussian, and the distance
    comes out low. By default the kernel is therefore computed on a ladder of times
    :math:`t_k = 4h^2\, 2^k` (``h`` the mean edge length), up to the first at which every
    vertex of the source's component has :math:`d^2/4t \le 8\sqrt2`, and each vertex takes
    the estimate of the first time at which its own :math:`d^2/4t \le 8\sqrt2` (the ladder's
    time nearest to 8).

    Parameters
    ----------
    lap_or_mesh : Laplacian, (V, F) or (V, T), or a pyvista/trimesh/meshio mesh
    source : int
        Source vertex.
    t : float, optional
        One time for every vertex instead of the ladder: the classical formula at ``t``.
        Only the vertices with :math:`4 \le d^2/4t \le 16` are in the band measured below
        (with :math:`t \ge 4h^2`); a ``RuntimeWarning`` gives the share of the component
        outside it (and says when :math:`t < 4h^2`).
    normalize : bool, default True
        Divide out the leading term of the short-time expansion,
        :math:`K_t \approx (4\pi t)^{-D/2} e^{-d^2/4t}` (``D`` = 2 for surfaces, 3 for
        volumes), i.e. use :math:`d^2 = -4t \log((4\pi t)^{D/2} K_t)`; without it the
        estimate is off by :math:`2Dt\log(4\pi t)` in :math:`d^2` even at the source.
    steps : int, default 64
        Backward-Euler steps of each kernel (see below). With ``t`` given, halved
        automatically until no value underflows.

    Returns
    -------
    (n,) float
        Finite on the source's connected component, ``inf`` on the others.

    Notes
    -----
    :math:`\log K_t` is needed where :math:`K_t` is :math:`e^{-d^2/4t}` small, i.e. to a
    relative accuracy the engine's (absolute) bounds do not give. Each kernel is
    therefore :math:`P^N e_p/m_p` with :math:`P = (M + \tfrac tN L)^{-1}M`, a Metzler
    stiffness and the lumped mass
    (:class:`~spectral_igl.applications.heat_steps.PositiveHeat`): positive everywhere
    on the component and accurate relative to itself. On the ladder a vertex whose
    kernel underflows at one time takes its estimate from a larger one.

    Accuracy band, measured against ``igl.exact_geodesic`` at unit area with the defaults
    (two random sources per mesh), mean relative error over all vertices: spot 3.0%, cow
    4.2%, homer 3.4%, fertility 4.8%, rocker-arm 2.9%, camel_b (with boundary) 4.6% (the
    single :math:`t = 4h^2` of earlier versions: 13%, 17%, 17%, 10%, 24%, 18%; the heat
    method, :class:`HeatGeodesics`, 1.8% to 3.1% on the same sources at a tenth of the
    cost). By distance from the source, mean over a band: within :math:`2h` 13% to 100%
    (no time resolves the first rings: there :math:`d^2/4t < 1/4` already at
    :math:`t = 4h^2`), :math:`[2h, 5h)` 3% to 44%, :math:`[5h, 10h)` 2% to 9%, beyond
    :math:`10h` 1% to 8%.

    The survey's §6.2.3 (geodesics from the heat kernel).

    Examples
    --------
    Against great-circle distances on the unit sphere (642 vertices): finite everywhere, a
    few percent off on average:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(3))
    >>> V = lap.data["V"] / np.linalg.norm(lap.data["V"], axis=1, keepdims=True)
    >>> exact = np.arccos(np.clip(V @ V[0], -1.0, 1.0))
    >>> d = sig.varadhan_distance(lap, 0)
    >>> float(d[0]), bool(np.all(np.isfinite(d))), bool(np.mean(np.abs(d - exact)) < 0.1 * np.mean(exact))
    (0.0, True, True)
    """
    lap = _as_laplacian(lap_or_mesh)
    src = as_indices(source, lap.n, "source")
    normalize = as_flag(normalize, "normalize")
    if src.size != 1:
        raise ValueError(f"source must be a single vertex for Varadhan's formula, got {src.size}")
    V, C = lap.data["V"], _cells(lap)
    h = units.mean_edge_length(lap)
    comp = lap.components == lap.components[src[0]]
    D = 2.0 if lap.domain == "triangle" else 3.0

    def estimate(heat):
        K = heat.column(src[0])[comp]
        with np.errstate(divide="ignore"):
            logk = np.log(K)
        if normalize:
            logk = logk + 0.5 * D * np.log(4.0 * np.pi * heat.t)
        return np.sqrt(np.maximum(-4.0 * heat.t * logk, 0.0))

    out = np.full(lap.n, np.inf)
    if t is not None:
        out[comp] = _varadhan_one_time(lap, src[0], comp, as_positive(t, "t"), steps, estimate, h)
        return out
    est = np.full(int(comp.sum()), np.inf)
    open_ = np.ones(est.size, dtype=bool)       # vertices still waiting for their time
    tk = _VARADHAN_T0 * h * h
    for _ in range(64):
        d = estimate(PositiveHeat(lap, tk, steps=steps))
        fin = np.isfinite(d)
        est[open_ & fin] = d[open_ & fin]          # the latest finite estimate, until ...
        # ... the first time at which d^2/4t is at most sqrt(2) r*: the ladder's point nearest r*
        open_ &= ~(fin & (d * d <= 4.0 * tk * np.sqrt(2.0) * _VARADHAN_RATIO))
        if not open_.any():
            break
        tk *= 2.0
    out[comp] = est
    return out


def _varadhan_one_time(lap, s, comp, t, steps, estimate, h):
    """Varadhan's formula at the one time ``t`` on the component ``comp`` of ``s``, with the
    step count halved until nothing underflows, and a warning for the share of the vertices
    outside the measured band."""
    heat = PositiveHeat(lap, t, steps=steps)
    while True:
        d = estimate(heat)
        if np.all(np.isfinite(d)) or heat.steps == 1:
            break
        heat = PositiveHeat(lap, t, steps=max(1, heat.steps // 2))
    if not np.all(np.isfinite(d)):
        raise ValueError(f"the heat kernel at t={t:.3g} underflows at {int(np.sum(~np.isfinite(d)))} of "
                         f"the {d.size} vertices connected to the source, so Varadhan's formula has "
                         "no value there; use a larger t, t=None, or geodesic_distance(..., method='heat')")
    r = d * d / (4.0 * t)
    outside = float(np.mean((r < 0.5 * _VARADHAN_RATIO) | (r > 2.0 * _VARADHAN_RATIO)))
    if outside > 0 or t < _VARADHAN_T0 * h * h:
        low = f"; t = {t / h ** 2:.3g} h^2 is below {_VARADHAN_T0:g} h^2" if t < _VARADHAN_T0 * h * h else ""
        warnings.warn(f"varadhan_distance at one time t={t:.3g}: {100 * outside:.0f}% of the vertices "
                      f"connected to the source have d^2/4t outside [{0.5 * _VARADHAN_RATIO:g}, "
                      f"{2 * _VARADHAN_RATIO:g}], the band where the formula was measured within "
                      f"about 9% of exact geodesics{low}; t=None uses a ladder of times that keeps "
                      "every vertex in it", RuntimeWarning, stacklevel=3)
    return d
