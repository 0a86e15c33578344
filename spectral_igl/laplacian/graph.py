"""Combinatorial graph Laplacian."""
from __future__ import annotations

import numbers

import numpy as np
import scipy.sparse as sp

from .._validate import as_cells, check_dense_size, describe
from ._operator import Laplacian, make_laplacian

__all__ = ["graph_laplacian"]


def graph_laplacian(n, edges, weights=None) -> Laplacian:
    r"""Laplacian of an undirected graph: :math:`L = D - W`, :math:`B = D`.

    The spectral-graph-theory convention: :math:`B^{-1}L = I - D^{-1}W` is the random-walk
    Laplacian, whose spectrum lies in :math:`[0, 2]`.

    Parameters
    ----------
    n : int
        Number of vertices.
    edges : (m, 2) int
        Vertex pairs. Order does not matter; repeated edges add up (a multigraph) and
        self-loops are ignored.
    weights : (m,) float or None
        Positive edge weights; ``None`` means 1 (unit weights, mass = valence).

    Returns
    -------
    Laplacian
        ``domain="graph"``, ``B`` diagonal. An isolated vertex (valence 0) becomes its own
        component with mass 1, so ``B`` stays positive definite.

    Examples
    --------
    >>> import spectral_igl as sig
    >>> lap = sig.graph_laplacian(3, [[0, 1], [1, 2]])
    >>> lap.L.toarray().tolist(), lap.mass.tolist()
    ([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]], [1.0, 2.0, 1.0])
    """
    if isinstance(n, bool) or not isinstance(n, (numbers.Integral, np.integer)):
        raise TypeError(f"n must be an integer number of vertices, got {describe(n)}")
    n = int(n)
    if n < 1:
        raise ValueError(f"n must be at least 1, got {n}")
    check_dense_size(64.0 * n, f"the per-vertex arrays of a graph of n = {n} vertices",
                     "n is the number of vertices, not of edges; a graph this large does not fit")
    E = as_cells(edges, n, "edges", sizes=(2,))
    if weights is None:
        w = np.ones(E.shape[0])
    else:
        w = np.asarray(weights)
        if w.dtype.kind not in "biuf":
            raise TypeError(f"weights must be real numbers, got {describe(weights)}")
        if w.shape != (E.shape[0],):
            raise ValueError(f"weights must have shape ({E.shape[0]},), got {describe(w)}")
        w = w.astype(np.float64)
        if not np.all(np.isfinite(w)) or np.any(w <= 0):
            raise ValueError("weights must be finite and positive")
    loop = E[:, 0] == E[:, 1]
    E, w = E[~loop], w[~loop]
    i = np.concatenate([E[:, 0], E[:, 1]])
    j = np.concatenate([E[:, 1], E[:, 0]])
    W = sp.csr_matrix((np.concatenate([w, w]), (i, j)), shape=(n, n))
    deg = np.asarray(W.sum(axis=1)).ravel()
    L = sp.diags(deg) - W
    B = sp.diags(np.where(deg > 0, deg, 1.0))
    return make_laplacian(L, B, domain="graph", data={"edges": E, "weights": w},
                          adjacency=W)
