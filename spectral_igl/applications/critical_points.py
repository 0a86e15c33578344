"""Critical points of a piecewise-linear function on a triangle mesh (lower-link test)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.csgraph as csgraph

from .._validate import as_cells, as_mesh_arrays, as_points, as_signal, is_mesh_object

__all__ = ["CriticalPoints", "critical_points"]


@dataclass(frozen=True)
class CriticalPoints:
    r"""Minima, maxima and saddles of a piecewise-linear function.

    What :func:`critical_points` returns. Items can also be read as keys: ``cp["minima"]``.

    Attributes
    ----------
    minima : (m,) int
        Vertex indices of the minima, ascending.
    maxima : (M,) int
        Vertex indices of the maxima, ascending.
    saddles : (s, 2) int
        One row ``(index, multiplicity)`` per saddle vertex; a monkey saddle has
        multiplicity 2, and so on.
    boundary : (b,) int
        Indices of the boundary vertices among the critical points above (their
        contribution to the Euler relation is halved, see :func:`critical_points`).
    nonmanifold : (k,) int
        Vertices whose link is neither a cycle nor a path.

    Examples
    --------
    The height on a sphere: one minimum, one maximum, no saddle, and the Morse count
    :math:`m - s + M` is the sphere's Euler characteristic 2:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> cp = sig.critical_points(V, F, V[:, 2])
    >>> len(cp.minima), len(cp.maxima), len(cp.saddles), cp.euler_characteristic()
    (1, 1, 0, 2.0)
    >>> bool(np.array_equal(cp["minima"], cp.minima))
    True
    """

    minima: np.ndarray
    maxima: np.ndarray
    saddles: np.ndarray
    boundary: np.ndarray
    nonmanifold: np.ndarray

    def __getitem__(self, key: str):
        if key not in ("minima", "maxima", "saddles", "boundary", "nonmanifold"):
            raise KeyError(key)
        return getattr(self, key)

    @property
    def n_minima(self) -> int:
        return int(self.minima.size)

    @property
    def n_maxima(self) -> int:
        return int(self.maxima.size)

    @property
    def n_saddles(self) -> int:
        """Number of saddles counted with multiplicity."""
        return int(self.saddles[:, 1].sum())

    def euler_characteristic(self) -> float:
        r"""The Morse count :math:`m - s + M`, boundary critical points weighted by 1/2.

        Equals the Euler characteristic :math:`\chi` of a manifold mesh (closed or with
        boundary) for every function, by construction of the classification.
        """
        bset = set(self.boundary.tolist())

        def weight(i) -> float:
            return 0.5 if int(i) in bset else 1.0

        mins = sum(weight(i) for i in self.minima)
        maxs = sum(weight(i) for i in self.maxima)
        sad = sum(weight(i) * int(k) for i, k in self.saddles)
        return mins + maxs - sad

    def __repr__(self) -> str:
        return (f"CriticalPoints(minima={self.n_minima}, maxima={self.n_maxima}, "
                f"saddles={self.n_saddles} (at {len(self.saddles)} vertices))")


def _link_structure(F: np.ndarray, n: int):
    """Per-vertex link graph: nodes are (v, neighbour) pairs, edges come from face corners."""
    # corner c of face f: vertex v = F[f, c], opposite link edge (a, b)
    v = F.ravel()
    a = np.roll(F, -1, axis=1).ravel()
    b = np.roll(F, -2, axis=1).ravel()
    # nodes: unique (v, a) pairs
    keys = np.concatenate([v * n + a, v * n + b])
    uniq, inv = np.unique(keys, return_inverse=True)
    inv = inv.ravel()
    m = v.size
    na, nb = inv[:m], inv[m:]
    node_v = uniq // n
    node_u = uniq % n
    N = uniq.size
    G = sp.csr_matrix((np.ones(m), (na, nb)), shape=(N, N))
    G = G + G.T
    deg = np.asarray((G > 0).sum(axis=1)).ravel()
    mult = np.asarray(G.sum(axis=1)).ravel()  # counts repeated link edges too
    _, comp = csgraph.connected_components(G, directed=False)
    # per vertex: number of link nodes, link edges, link components, degree-1 nodes
    n_nodes = np.bincount(node_v, minlength=n)
    n_edges = np.bincount(v, minlength=n)
    # number of distinct components per vertex
    pair = np.unique(np.c_[node_v, comp], axis=0)
    n_comp = np.bincount(pair[:, 0], minlength=n)
    ends = np.bincount(node_v[deg == 1], minlength=n)
    bad_node = (deg > 2) | (mult > 2) | (deg == 0)
    bad = np.bincount(node_v[bad_node], minlength=n) > 0
    is_cycle = (n_comp == 1) & (ends == 0) & ~bad & (n_edges == n_nodes)
    is_path = (n_comp == 1) & (ends == 2) & ~bad & (n_edges == n_nodes - 1)
    return v, a, b, node_v, node_u, n_nodes, is_cycle, is_path


def critical_points(V, F, f=None) -> CriticalPoints:
    r"""Minima, maxima and saddles of the piecewise-linear function ``f`` on ``(V, F)``.

    Parameters
    ----------
    V : (n, 3) float, or a mesh object
        Vertex positions (only their number is used: the test is combinatorial). A
        pyvista, trimesh or meshio triangle mesh may stand for ``(V, F)``: then call
        ``critical_points(mesh, f)``; so may a pair, ``critical_points((V, F), f)``.
    F : (m, 3) int
        Triangles.
    f : (n,) float
        Function values at the vertices.

    Returns
    -------
    CriticalPoints
        ``minima``, ``maxima`` (vertex indices) and ``saddles`` (rows ``(index, k)``,
        ``k`` the multiplicity), also readable as keys.

    Notes
    -----
    *Lower-link test.* A neighbour ``u`` of ``v`` is lower when
    :math:`(f_u, u) < (f_v, v)` lexicographically: ties between equal values are
    broken by the vertex index, a symbolic perturbation that makes every function
    generic and every classification consistent. Going once around the link of an
    interior vertex, let :math:`2c` be the number of sign changes (lower/upper). The
    vertex is a minimum if no neighbour is lower, a maximum if no neighbour is upper,
    regular if :math:`c = 1`, and a saddle of multiplicity :math:`c - 1` if
    :math:`c \ge 2`. On a closed manifold mesh :math:`m - s + M = \chi` holds, saddles
    counted with multiplicity.

    *Boundary vertices* (link is a path) are classified as their image on the mesh
    doubled across its boundary: with :math:`c'` sign changes along the path, a minimum
    if no neighbour is lower, a maximum if none is upper, else a saddle of multiplicity
    :math:`c' - 1` when :math:`c' \ge 2`. On the double every interior critical point
    appears twice and every boundary one once, so
    :math:`m - s + M = \chi` holds with boundary critical points weighted by 1/2
    (:meth:`CriticalPoints.euler_characteristic`).

    *Non-manifold vertices* (link not a single cycle or path) are classified by the
    lower-link Euler characteristic: a minimum if no neighbour is lower, a maximum if
    none is upper, else a saddle of multiplicity :math:`\chi(\mathrm{Lk}^-) - 1` when
    that is positive. They are listed in ``nonmanifold``; the Euler relation is not
    claimed there. Vertices in no triangle are never critical.

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> cp = critical_points(V, F, V[:, 2])
    >>> cp.n_minima, cp.n_maxima, cp.n_saddles
    (1, 1, 0)
    """
    if isinstance(V, (tuple, list)) and len(V) == 2 and f is None:     # critical_points((V, F), f)
        (V, F), f = V, F
    if is_mesh_object(V) and f is None:
        V, F, f = (*as_mesh_arrays(V), F)
    if f is None:
        raise TypeError("critical_points needs (V, F, f) or (mesh, f); f is missing")
    V = as_points(V, "V", dims=(2, 3))
    n = V.shape[0]
    F = as_cells(F, n, "F", sizes=(3,))
    f = as_signal(f, n, "f", allow_complex=False)
    if f.ndim != 1:
        raise ValueError(f"f must have shape ({n},), got shape {f.shape}")
    # rank of (f, index): lexicographic order as a single integer key
    rank = np.empty(n, dtype=np.int64)
    rank[np.lexsort((np.arange(n), f))] = np.arange(n)
    v, a, b, node_v, node_u, n_nodes, is_cycle, is_path = _link_structure(F, n)
    lower_a = rank[a] < rank[v]
    lower_b = rank[b] < rank[v]
    changes = np.bincount(v, weights=(lower_a != lower_b).astype(float), minlength=n).astype(np.int64)
    lower_nodes = np.bincount(node_v, weights=(rank[node_u] < rank[node_v]).astype(float),
                              minlength=n).astype(np.int64)
    lower_edges = np.bincount(v, weights=(lower_a & lower_b).astype(float), minlength=n).astype(np.int64)
    in_face = n_nodes > 0
    is_min = in_face & (lower_nodes == 0)
    is_max = in_face & (lower_nodes == n_nodes)
    mixed = in_face & ~is_min & ~is_max
    mult = np.zeros(n, dtype=np.int64)
    # interior manifold vertices: 2c changes around the cycle
    sel = mixed & is_cycle
    mult[sel] = changes[sel] // 2 - 1
    sel = mixed & is_path
    mult[sel] = changes[sel] - 1
    nonman = in_face & ~is_cycle & ~is_path
    sel = mixed & nonman
    mult[sel] = np.maximum(lower_nodes[sel] - lower_edges[sel] - 1, 0)
    sad = np.flatnonzero(mult > 0)
    crit = is_min | is_max | (mult > 0)
    return CriticalPoints(
        minima=np.flatnonzero(is_min),
        maxima=np.flatnonzero(is_max),
        saddles=np.c_[sad, mult[sad]].astype(np.int64).reshape(-1, 2),
        boundary=np.flatnonzero(crit & is_path),
        nonmanifold=np.flatnonzero(nonman),
    )
