"""Element matrices of a clean triangle or tetrahedral mesh: measures, stiffness, consistent mass.

The pieces both the simplicial Laplacian (:mod:`.mesh`) and the polygon Laplacian
(:mod:`.polygon`, on its refined triangles) assemble from.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.csgraph as csgraph

from .._validate import as_mesh_arrays

__all__ = ["row_cross", "element_measures", "mesh_components", "star_adjacency", "mean_value_weights",
           "cotan_stiffness", "full_mass", "pattern_components"]


def row_cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (m, 3) arrays (np.cross without its overhead)."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=1)


def element_measures(V, C=None) -> np.ndarray:
    r"""(m,) area of each triangle or volume of each tetrahedron (unsigned).

    Parameters
    ----------
    V : (n, 3) float, or a pyvista/trimesh/meshio mesh with ``C`` omitted
        Vertex positions (2-D positions are allowed for triangles).
    C : (m, 3) or (m, 4) int, optional
        Triangles or tetrahedra.

    Returns
    -------
    (m,) float
        :math:`\tfrac12 \|(v_1 - v_0) \times (v_2 - v_0)\|` per triangle,
        :math:`\tfrac16 |\det(v_1 - v_0, v_2 - v_0, v_3 - v_0)|` per tetrahedron.

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl.laplacian.mesh import element_measures
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> element_measures(V, np.array([[0, 1, 2]])), element_measures(V, np.array([[0, 1, 2, 3]]))
    (array([0.5]), array([0.16666667]))
    """
    V, C = as_mesh_arrays(V, C)
    V, C = np.asarray(V, dtype=float), np.asarray(C)
    if C.shape[1] == 3:
        e1 = V[C[:, 1]] - V[C[:, 0]]
        e2 = V[C[:, 2]] - V[C[:, 0]]
        if V.shape[1] == 2:
            return 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        return 0.5 * np.linalg.norm(row_cross(e1, e2), axis=1)
    e1, e2, e3 = (V[C[:, k]] - V[C[:, 0]] for k in (1, 2, 3))
    return np.abs(np.einsum("ij,ij->i", row_cross(e1, e2), e3)) / 6.0


def mesh_components(n: int, C: np.ndarray) -> sp.csr_matrix:
    """(n, n) vertex adjacency of the elements ``C`` (pattern only)."""
    k = C.shape[1]
    i = np.concatenate([C[:, a] for a in range(k) for b in range(k) if a != b])
    j = np.concatenate([C[:, b] for a in range(k) for b in range(k) if a != b])
    return sp.csr_matrix((np.ones(i.size), (i, j)), shape=(n, n))


def star_adjacency(n: int, C: np.ndarray) -> sp.csr_matrix:
    """(n, n) pattern linking each element's first vertex to its others, one direction.

    Its connected components (as an undirected graph) are those of
    :func:`mesh_components`, from ``k - 1`` entries per element instead of ``k(k - 1)``.
    """
    k = C.shape[1]
    i = np.repeat(C[:, 0], k - 1)
    j = C[:, 1:].ravel()
    return sp.csr_matrix((np.ones(i.size), (i, j)), shape=(n, n))


def pattern_components(A) -> tuple[np.ndarray, int]:
    """(labels (n,) int64, count): the connected components of the graph of the stored
    entries of the square sparse ``A`` (explicit zeros included, directions ignored),
    numbered in the order of their smallest vertex, as
    :attr:`~spectral_igl.laplacian.Laplacian.components`."""
    A = sp.csr_matrix(A)
    pattern = sp.csr_matrix((np.ones(A.nnz), A.indices, A.indptr), shape=A.shape)
    nc, labels = csgraph.connected_components(pattern, directed=False)
    return labels.astype(np.int64), int(nc)


def mean_value_weights(V: np.ndarray, F: np.ndarray) -> sp.csr_matrix:
    r"""(n, n) mean-value weights of a triangle mesh (Floater 2003), not symmetric.

    .. math:: w_{ij} = \frac{\tan(\delta_{ij}/2) + \tan(\gamma_{ij}/2)}{\|x_j - x_i\|},

    with :math:`\delta_{ij}, \gamma_{ij}` the angles *at* :math:`x_i` between the edge
    :math:`ij` and the other edges of the two triangles on it (one on a boundary edge).
    The weights are positive for every triangle shape, but :math:`w_{ij} \ne w_{ji}`
    in general: the angles are measured at the row's vertex.
    """
    n = V.shape[0]
    rows, cols, vals = [], [], []
    for a in range(3):
        i, j, k = F[:, a], F[:, (a + 1) % 3], F[:, (a + 2) % 3]
        e1, e2 = V[j] - V[i], V[k] - V[i]
        l1, l2 = np.linalg.norm(e1, axis=1), np.linalg.norm(e2, axis=1)
        dot = np.einsum("ij,ij->i", e1, e2)
        cr = np.linalg.norm(row_cross(e1, e2), axis=1) if V.shape[1] == 3 else \
            np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        half_tan = (l1 * l2 - dot) / cr          # tan(θ/2) = (1 - cos θ) / sin θ
        rows += [i, i]
        cols += [j, k]
        vals += [half_tan / l1, half_tan / l2]
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n, n))


def cotan_stiffness(V: np.ndarray, C: np.ndarray, weights: str = "cotan", mirror: bool = False) -> sp.csr_matrix:
    """Positive semi-definite stiffness of a clean mesh: the one place libigl's sign flips.

    libigl's ``cotmatrix`` is negative semi-definite; this returns ``-cotmatrix``.
    ``mirror``: intrinsic Delaunay weights only, flip boundary edges in the mesh's double
    (see :func:`~spectral_igl.laplacian.intrinsic.intrinsic_cotan_stiffness`).
    """
    import igl

    if weights == "cotan":
        return -igl.cotmatrix(V, C).tocsr()
    if weights == "intrinsic_delaunay":
        if C.shape[1] != 3:
            raise ValueError("weights='intrinsic_delaunay' is defined for triangle meshes only")
        from .intrinsic import intrinsic_cotan_stiffness

        return intrinsic_cotan_stiffness(V, C, mirror=mirror)
    if weights == "mean_value":
        if C.shape[1] != 3:
            raise ValueError("weights='mean_value' is defined for triangle meshes only")
        W = mean_value_weights(V, C)
        W = ((W + W.T) * 0.5).tocsr()
        return (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()
    A = mesh_components(V.shape[0], C)
    A.data[:] = 1.0
    return (sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A).tocsr()


def full_mass(V: np.ndarray, C: np.ndarray, meas: np.ndarray | None = None) -> sp.csr_matrix:
    """Consistent linear-FEM mass: |e| (1 + δ_ij) / ((k)(k+1)) per element of k vertices."""
    k = C.shape[1]
    if meas is None:
        meas = element_measures(V, C)
    denom = 12.0 if k == 3 else 20.0
    # (a, b)-major order, as the duplicates are summed
    rows = np.repeat(C.T, k, axis=0).ravel()
    cols = np.tile(C.T, (k, 1)).ravel()
    vals = np.concatenate([meas * ((2.0 if a == b else 1.0) / denom) for a in range(k) for b in range(k)])
    n = V.shape[0]
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
