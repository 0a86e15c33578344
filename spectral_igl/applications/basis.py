"""Diffusion basis functions and feature points (survey §7.2)."""
from __future__ import annotations

import numpy as np

from .._validate import as_choice, as_indices, as_int, as_positive, as_real_in, as_signal
from ..approx import SpectralOperator
from ..descriptors import auto_diffusion_function
from ..filters import heat
from ..laplacian import as_laplacian
from ..linalg import eigs

__all__ = ["diffusion_basis", "feature_points", "graph_extrema", "merge_pairs"]


def diffusion_basis(lap, t, centers, method: str = "auto", tol: float = 1e-8):
    r"""Heat-kernel basis functions centred at ``centers``: columns :math:`K_t(\cdot, p_i)`.

    .. math:: \psi_i = K_t e_i = e^{-t\tilde L} B^{-1} e_i

    Parameters
    ----------
    lap : Laplacian
    t : float
        Diffusion time, > 0: the support radius grows like :math:`\sqrt{t}`.
    centers : (k,) int
        Vertex indices.
    method, tol
        Passed to :class:`spectral_igl.SpectralOperator`.

    Returns
    -------
    (n, k) float
        Smooth, positive, intrinsic bumps. Each column integrates to 1
        (:math:`\mathbf 1^\top B \psi_i = 1`), the matrix is symmetric
        (:math:`\psi_i(p_j) = \psi_j(p_i)`), and over all vertices the basis is a
        partition of unity weighted by the areas: :math:`\sum_i m_i \psi_i = \mathbf 1`
        with :math:`m = B\mathbf 1` (on each connected component).

    Notes
    -----
    The diffusion basis of the survey's §7.2.

    Examples
    --------
    Each column integrates to 1, and all n of them weighted by the masses sum to 1:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> P = sig.diffusion_basis(lap, 0.1, [0, 5, 9])
    >>> P.shape, bool(np.allclose(lap.mass @ P, 1.0))
    ((162, 3), True)
    >>> bool(np.allclose(sig.diffusion_basis(lap, 0.1, np.arange(lap.n)) @ lap.mass, 1.0))
    True
    """
    lap = as_laplacian(lap)
    t = as_positive(t, "t")
    centers = as_indices(centers, lap.n, "centers")
    E = np.zeros((lap.n, centers.size))
    E[centers, np.arange(centers.size)] = 1.0
    op = SpectralOperator(lap, heat(t), method=method, tol=tol)
    return np.real(op.apply_inverse_mass(E))


def _rank(f):
    """Rank of each value, ties broken by the vertex index (the order of every extremum test)."""
    n = f.size
    rank = np.empty(n, dtype=np.int64)
    rank[np.lexsort((np.arange(n), f))] = np.arange(n)
    return rank


def merge_pairs(order, indptr, indices):
    """0-dimensional persistence of the sweep that adds the vertices in ``order``.

    A vertex without an earlier neighbour (in the CSR graph ``indptr, indices``; self-loops
    ignored) starts a component. When components meet at a vertex, every one but the
    oldest (its first vertex earliest in ``order``: the elder rule) dies there.

    Returns
    -------
    pairs : list of (int, int)
        ``(first vertex of the component that died, vertex where it died)``.
    survivors : list of int
        The first vertex of each component left at the end (one per connected component).
    """
    n = len(order)
    parent = -np.ones(n, dtype=np.int64)     # -1: not yet added; a root is its own first vertex
    pos = np.empty(n, dtype=np.int64)
    pos[order] = np.arange(n)

    def find(x):
        root = x
        while parent[root] != root:
            root = parent[root]
        while parent[x] != root:
            parent[x], x = root, parent[x]
        return root

    pairs = []
    for v in order:
        roots = {find(u) for u in indices[indptr[v]:indptr[v + 1]] if parent[u] >= 0}
        if not roots:
            parent[v] = v
            continue
        keep = min(roots, key=lambda r: pos[r])
        for r in sorted(roots - {keep}, key=lambda r: pos[r]):
            pairs.append((int(r), int(v)))
            parent[r] = keep
        parent[v] = keep
    return pairs, [int(r) for r in np.unique([find(x) for x in range(n)])]


def _maxima_persistence(A, f):
    """Persistence of every local maximum of ``f`` in the superlevel-set filtration of graph A.

    Vertices enter in decreasing rank (:func:`merge_pairs`); a component dying at ``v``
    has persistence its maximum minus ``f[v]``. The highest maximum of each connected
    component never dies (``inf``).
    """
    pairs, survivors = merge_pairs(np.argsort(-_rank(f)), A.indptr, A.indices)
    pers = {top: float(f[top] - f[v]) for top, v in pairs}
    pers.update((top, np.inf) for top in survivors)
    return pers


def graph_extrema(lap, f, persistence: float = 0.0):
    r"""Local minima and maxima of ``f`` over the neighbourhoods of the graph of ``lap.L``.

    Ties are broken by the vertex index, as in :func:`critical_points`; for a triangle
    mesh the result equals the minima and maxima of the lower-link test.

    Parameters
    ----------
    lap : Laplacian
    f : (n,) float
    persistence : float, default 0
        Keep only extrema whose topological persistence (0-dimensional, of the
        sub/superlevel-set filtration of the graph) is at least ``persistence`` times
        the range :math:`\max f - \min f`. Discretisation and noise make shallow
        extrema (small persistence); 0 keeps every local extremum. The global minimum
        and maximum of each connected component are always kept.

    Returns
    -------
    minima, maxima : (p,) int, (q,) int
        Sorted vertex indices.

    Examples
    --------
    The height on a sphere has one minimum (the south pole) and one maximum:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.applications import graph_extrema
    >>> lap = sig.laplacian(*icosphere(2))
    >>> lo, hi = graph_extrema(lap, lap.data["V"][:, 2])
    >>> lap.data["V"][lo, 2].round(6).tolist(), lap.data["V"][hi, 2].round(6).tolist()
    ([-1.0], [1.0])
    """
    lap = as_laplacian(lap)
    f = as_signal(f, lap.n, "f", allow_complex=False)
    if f.ndim != 1:
        raise ValueError(f"f must have shape ({lap.n},), got shape {f.shape}")
    # no extremum but the global ones persists over more than the range of f
    persistence = as_real_in(persistence, "persistence", 0.0, 1.0)
    n = lap.n
    rank = _rank(f)
    A = lap.L.tocoo()
    off = A.row != A.col
    i, j = A.row[off], A.col[off]
    lower = rank[j] < rank[i]
    n_lower = np.bincount(i, weights=lower, minlength=n)
    n_nb = np.bincount(i, minlength=n)
    has = n_nb > 0
    mins, maxs = np.flatnonzero(has & (n_lower == 0)), np.flatnonzero(has & (n_lower == n_nb))
    if persistence > 0:
        G = lap.L.tocsr()
        cut = persistence * float(f.max() - f.min())
        pmax = _maxima_persistence(G, f)
        pmin = _maxima_persistence(G, -f)
        maxs = np.array([v for v in maxs if pmax[int(v)] >= cut], dtype=np.int64)
        mins = np.array([v for v in mins if pmin[int(v)] >= cut], dtype=np.int64)
    return mins, maxs


def feature_points(lap, n_eigenfunctions: int = 6, t: float = 0.1, source: str = "eigenfunctions",
                   persistence: float = 0.25, method: str = "auto"):
    r"""Feature points: extrema of the first eigenfunctions or of the auto-diffusion function.

    Parameters
    ----------
    lap : Laplacian
    n_eigenfunctions : int, default 6
        With ``source="eigenfunctions"``: how many non-constant eigenfunctions
        :math:`x_2, x_3, \ldots` (Ruggeri et al. 2010) to take extrema of.
    t : float, default 0.1
        With ``source="adf"``: the time of :func:`spectral_igl.auto_diffusion_function`,
        in units of :math:`1/\lambda_2` (scale invariant); at 0.1 the protrusions of the
        shape stand out.
    source : {"eigenfunctions", "adf"}
    persistence : float, default 0.25
        Minimum persistence of an extremum, relative to the range of the function (see
        :func:`graph_extrema`; 0 keeps every local extremum). On a discretised shape the
        ADF and the eigenfunctions have shallow local extrema in nearly flat regions;
        on a sphere with four smooth protrusions (642 vertices, ADF at t = 0.05 to 0.3)
        these have persistence at most 0.13 of the range, the tips at least 0.75.
    method : str
        With ``source="adf"``: the diagonal method of
        :func:`spectral_igl.auto_diffusion_function` (spectrum-free).

    Returns
    -------
    (p,) int
        Sorted, distinct vertex indices: the minima and maxima (over the neighbourhoods
        of :func:`graph_extrema`) of each eigenfunction (``"eigenfunctions"``) or the
        maxima of the auto-diffusion function (``"adf"``, tips of protrusions).

    Notes
    -----
    The feature points of the survey's §7.2 (Ruggeri et al. 2010; Gebal et al. 2009).

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> p = sig.feature_points(lap, n_eigenfunctions=3)
    >>> bool(np.all(np.diff(p) > 0)), bool(len(p) >= 6)
    (True, True)
    """

    lap = as_laplacian(lap)
    as_choice(source, "source", ("eigenfunctions", "adf"))
    t = as_positive(t, "t")
    n_eigenfunctions = as_int(n_eigenfunctions, "n_eigenfunctions", lo=1, hi=max(lap.n - lap.n_components, 1))
    persistence = as_real_in(persistence, "persistence", 0.0, 1.0)
    unused = {"eigenfunctions": {"t": (t, 0.1), "method": (method, "auto")},
              "adf": {"n_eigenfunctions": (n_eigenfunctions, 6)}}[source]
    for name, (value, default) in unused.items():
        if value != default:
            raise ValueError(f"option {name}={value!r} is not used with source={source!r}")
    if source == "adf":
        return graph_extrema(lap, auto_diffusion_function(lap, t, method=method), persistence)[1]
    c = lap.n_components
    lam, X = eigs(lap, c + int(n_eigenfunctions))
    pts = []
    for j in range(c, X.shape[1]):
        mn, mx = graph_extrema(lap, X[:, j], persistence)
        pts += [mn, mx]
    return np.unique(np.concatenate(pts))
