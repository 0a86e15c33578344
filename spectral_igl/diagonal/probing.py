"""Probing estimator of a kernel diagonal: colourings of the mesh graph and deflation."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, shortest_path

from .._validate import as_choice, as_int, check_dense_size
from ..laplacian import as_laplacian
from ..progress import progress_bar
from .spectral import low_rank, phi_values

__all__ = ["distance_colouring", "probing_diagonal", "MAX_COLOURS", "KDEFL"]

#: default colour budget of ``"probing"`` (engine applications)
MAX_COLOURS = 256
#: deflation rank tried by ``"probing"`` when the kernel does not decay fast enough
KDEFL = 100


def distance_colouring(lap, distance: int = 2, order: str = "bfs") -> np.ndarray:
    r"""(n,) greedy colouring in which two vertices of one colour are more than ``distance``
    edges apart in the graph of the nonzeros of L (a distance-``distance`` colouring).

    The number of colours is about the number of vertices in a ball of ``distance`` rings.
    Probing (:func:`spectral_igl.kernel_diagonal` with ``method="probing"``) applies the
    kernel to one indicator per colour, :math:`K(i,i) \approx (K \sum_{j \in c(i)} e_j)_i`,
    exact up to the kernel's entries more than ``distance`` rings away.

    Parameters
    ----------
    lap : Laplacian or mesh
    distance : int
        Rings of separation (default 2), at least 1.
    order : {"bfs", "natural"}
        Order in which the greedy colouring visits the vertices.

    Returns
    -------
    colours : (n,) int
        Colour of every vertex, from 0.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> import scipy.sparse as sp
    >>> lap = sig.laplacian(*icosphere(2))
    >>> c = sig.distance_colouring(lap, distance=1)
    >>> A = sp.coo_matrix(lap.L)
    >>> off = A.row != A.col
    >>> bool(np.all(c[A.row[off]] != c[A.col[off]])), int(c.max()) + 1 < 20
    (True, True)
    """
    lap = as_laplacian(lap)
    n = lap.n
    distance = as_int(distance, "distance", lo=1, hi=max(n, 1))
    as_choice(order, "order", ("bfs", "natural"))
    deg = lap.L.nnz / max(n, 1)
    check_dense_size(13.0 * n * min(n, deg ** min(distance, 64)),
                     f"the distance-{distance} neighbourhoods of {n} vertices",
                     "use a smaller colouring distance")
    A = sp.csr_matrix((np.ones(lap.L.nnz, dtype=np.int8), lap.L.indices, lap.L.indptr), shape=(n, n))
    A = (A + sp.identity(n, dtype=np.int8, format="csr")).astype(bool).astype(np.int8)
    P = A.copy()
    for _ in range(distance - 1):
        P = (P @ A).astype(bool).astype(np.int8)
    P = P.tocsr()
    P.sort_indices()
    if order == "bfs":
        seen = np.zeros(n, bool)
        perm = []
        for s in range(n):
            if not seen[s]:
                o = breadth_first_order(A, s, directed=False, return_predecessors=False)
                seen[o] = True
                perm.append(o)
        perm = np.concatenate(perm)
    else:
        perm = np.arange(n)
    colours = np.full(n, -1, dtype=np.int64)
    mark = np.full(n + 1, -1, dtype=np.int64)
    indptr, indices = P.indptr, P.indices
    for v in perm:
        used = colours[indices[indptr[v]:indptr[v + 1]]]
        used = used[used >= 0]
        mark[used] = v
        free = np.flatnonzero(mark[: used.size + 1] != v)
        colours[v] = free[0]
    return colours


def _colour_budget(n: int, max_colours) -> int:
    if max_colours is None:
        return int(max(8, min(MAX_COLOURS, n // 4)))
    return int(max(1, max_colours))


def _adjacency(lap):
    n = lap.n
    return sp.csr_matrix((np.ones(lap.L.nnz, dtype=np.int8), lap.L.indices, lap.L.indptr), shape=(n, n))


def _probing_prediction(R, dist, exact, Ds):
    """Predicted relative probing error for each colouring distance in ``Ds``.

    For sample column i, the error of probing is the sum of G_ij over the j that share
    i's colour; every vertex further than D rings away does so with probability about
    1/ncol(D), and ncol(D) is about 0.55 times the number of vertices within D rings
    (greedy distance-D colouring of a surface mesh); the few nearest allowed vertices
    (D+1 and D+2 rings away) are counted at their full weight. Returns (pred, ncol).
    """
    s = R.shape[1]
    dmax = int(dist.max()) + 1
    pred = np.zeros(len(Ds))
    balls = np.zeros((s, len(Ds)))
    Ds = np.asarray(Ds)
    for i in range(s):
        a = np.abs(R[:, i])
        w = np.bincount(dist[i], weights=a, minlength=dmax + 3)
        cnt = np.bincount(dist[i], minlength=dmax + 3)
        peak = np.zeros(dmax + 3)
        np.maximum.at(peak, dist[i], a)
        tail = w.sum() - np.cumsum(w)
        ball = np.cumsum(cnt)
        D = np.minimum(Ds, dmax)
        balls[i] = ball[D]
        # far vertices share i's colour with probability ~1/ncol; a few of the nearest
        # allowed ones (D+1, D+2 rings) do so for sure: greedy colouring packs colours
        near = 3.0 * np.maximum(peak[D + 1], peak[D + 2])
        pred = np.maximum(pred, (tail[D] / (0.55 * ball[D]) + near) / max(abs(exact[i]), np.finfo(float).tiny))
    return pred, np.maximum(1.0, 0.55 * np.median(balls, axis=0))


def _choose_probing(lap, filt, delta, C, idx, exact, k, distance, rtol, budget):
    """(k, distance) for probing from the exact columns C at the sample vertices idx.

    The off-diagonal decay of the kernel, or of its remainder after deflation with k
    eigenpairs, is read off the sample columns against graph distance; the cheapest
    colouring distance whose predicted error meets ``rtol`` within the colour budget is
    taken, else the most accurate one. Deflation is tried only when the kernel itself
    does not decay fast enough: a truncated low-mode expansion is not local (its
    off-diagonal entries oscillate over the whole shape), so deflating a local kernel
    makes the remainder non-local and probing worse.
    """
    n, c = lap.n, lap.n_components
    dist = shortest_path(_adjacency(lap), unweighted=True, indices=idx)
    far = dist[np.isfinite(dist)].max() + 1 if np.isfinite(dist).any() else 1
    dist = np.where(np.isfinite(dist), dist, far).astype(np.int64)   # other components: G_ij = 0
    Dall = np.arange(1, int(far) + 1) if distance is None else np.array([int(distance)])

    def best(kk):
        if kk:
            lam, W = low_rank(lap, kk, delta)
            ph = phi_values(filt, lam, c)
            R = C - (W * ph) @ W[idx].T
        else:
            R = C
        pred, ncol = _probing_prediction(np.real(R) if not np.iscomplexobj(R) else R, dist, exact, Dall)
        ok = ncol <= budget
        if not ok.any():
            ok[0] = True
        good = np.flatnonzero(ok & (pred <= rtol))
        j = good[0] if good.size else np.flatnonzero(ok)[np.argmin(pred[ok])]
        return {"k": kk, "distance": int(Dall[j]), "predicted": float(pred[j])}

    if k is not None:
        return best(max(0, min(int(k), n - 1)))
    plain = best(0)
    if plain["predicted"] <= rtol:
        return plain
    kd = int(min(KDEFL, max(0, n // 20)))
    if kd == 0:
        return plain
    defl = best(kd)
    return defl if defl["predicted"] < plain["predicted"] else plain



def probing_diagonal(lap, filt, G, delta: str, k, distance, samples: int, rtol: float, max_colours,
                     seed: int, dtype, block: int = 64, progress=None):
    """Probing estimate of diag(G), ``G(Z)`` applying the kernel to the columns of Z.

    Returns ``(diag, info)``; the error is measured at ``samples`` vertices (exact there)."""
    n = lap.n
    info = {"applications": 0}
    samples = int(min(max(samples, 0), n))
    if samples == 0 and (k is None or distance is None):
        raise ValueError("method='probing' chooses k and distance from exact columns at sample "
                         "vertices: pass samples >= 1, or both k and distance")
    idx = np.empty(0, dtype=np.int64)
    if samples:
        rng = np.random.default_rng(seed)
        idx = np.sort(rng.choice(n, samples, replace=False))
        E = np.zeros((n, samples))
        E[idx, np.arange(samples)] = 1.0
        C = G(E)                                   # exact columns at the samples
        exact = C[idx, np.arange(samples)]
        info["applications"] += samples
    budget = _colour_budget(n, max_colours)
    if k is None or distance is None:
        choice = _choose_probing(lap, filt, delta, C, idx, exact, k, distance, rtol, budget)
        k, distance = choice["k"], choice["distance"]
        info["predicted_rel_error"] = choice["predicted"]
    k = max(0, min(int(k), n - 1))
    distance = int(distance)
    colours = distance_colouring(lap, distance)
    ncol = int(colours.max()) + 1
    info.update(distance=distance, colours=ncol, k=k)
    diag = np.zeros(n, dtype=dtype)
    rows = np.arange(n)
    bar = progress_bar(-(-ncol // block), "kernel diagonal", progress, unit="block")
    for a in range(0, ncol, block):
        cols = np.arange(a, min(a + block, ncol))
        sel = (colours >= cols[0]) & (colours <= cols[-1])
        Z = np.zeros((n, cols.size))
        Z[rows[sel], colours[sel] - a] = 1.0
        Y = G(Z)
        diag[sel] = Y[rows[sel], colours[sel] - a]
        bar.update()
    bar.close()
    info["applications"] += ncol
    if k > 0:
        lam, W = low_rank(lap, k, delta)
        ph = phi_values(filt, lam, lap.n_components)
        low_diag = (W ** 2) @ ph
        # (G_low Z)_{i, c(i)} = sum over i's colour class of G_low(i, j)
        S = np.zeros((ncol, W.shape[1]), dtype=W.dtype)
        np.add.at(S, colours, W)                     # Z^T W
        low_probe = np.einsum("ij,ij->i", W * ph, S[colours])
        diag += low_diag - low_probe
    # measured accuracy at the sample vertices (made exact there)
    if samples:
        err = np.abs(diag[idx] - exact)
        info["sample_abs_error"] = float(err.max())
        info["sample_rel_error"] = float(np.max(err / np.maximum(np.abs(exact), np.finfo(float).tiny)))
        info["samples"] = idx
        diag[idx] = exact
    return diag, info
