"""Polygon-mesh Laplacian: virtual vertices, refinement and prolongation (Bunge et al. 2020)."""
from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp

from .._validate import as_points, describe
from ._operator import Laplacian, drop_negative_weights, make_laplacian
from .elements import cotan_stiffness, full_mass

__all__ = ["polygon_laplacian", "as_polygons", "virtual_vertices"]

_MASSES = ("full", "lumped")


def as_polygons(faces, n: int, name: str = "faces") -> list[np.ndarray]:
    """Polygon faces grouped by degree: a list of ``(m_k, k)`` int arrays.

    ``faces`` is an ``(m, k)`` integer array or a sequence of index sequences (each of
    at least 3 vertices, indices in ``[0, n)``). Faces of the same degree keep their
    relative order within their group.
    """
    if isinstance(faces, np.ndarray) and faces.ndim == 2:
        rows = [faces]
    elif isinstance(faces, (list, tuple)) or (isinstance(faces, np.ndarray) and faces.dtype == object):
        if len(faces) == 0:
            raise ValueError(f"{name} is empty")
        try:
            rows = [np.asarray(f) for f in faces]
        except Exception as err:  # pragma: no cover - defensive
            raise TypeError(f"{name} must be index sequences, got {describe(faces)}") from err
    else:
        raise TypeError(f"{name} must be an (m, k) integer array or a list of index lists, "
                        f"got {describe(faces)}")
    groups: dict[int, list] = {}
    for r in rows:
        if r.ndim == 1:
            r = r[None, :]
        if r.ndim != 2 or r.size == 0:
            raise ValueError(f"{name}: every face must be a 1-D index sequence, got shape {r.shape}")
        if not (np.issubdtype(r.dtype, np.integer) or (np.issubdtype(r.dtype, np.floating)
                                                       and np.all(r == np.round(r)))):
            raise TypeError(f"{name} must hold integer vertex indices, got dtype {r.dtype}")
        k = r.shape[1]
        if k < 3:
            raise ValueError(f"{name}: a polygon needs at least 3 vertices, got a face with {k}")
        groups.setdefault(k, []).append(r.astype(np.int64))
    out = []
    for k in sorted(groups):
        G = np.concatenate(groups[k], axis=0)
        if G.min() < 0 or G.max() >= n:
            raise ValueError(f"{name} index out of range [0, {n}): min {G.min()}, max {G.max()}")
        out.append(G)
    return out


def virtual_vertices(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Area-minimising virtual vertex of each polygon (Bunge et al. 2020).

    For a polygon :math:`x_1, \dots, x_k` the point :math:`c` minimising the sum of the
    squared areas of the fan triangles :math:`(x_i, x_{i+1}, c)`,

    .. math:: c = \arg\min_c \sum_i \|(x_i - c)\times(x_{i+1} - c)\|^2,

    written as the affine combination :math:`c = \sum_i w_i x_i`, :math:`\sum_i w_i = 1`,
    of least norm :math:`\|w\|`. On a triangle, :math:`w = (1/3, 1/3, 1/3)`.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, k) int
        Polygons of one degree ``k``.

    Returns
    -------
    C : (m, 3) float
        The virtual vertices.
    W : (m, k) float
        Their weights; every row sums to 1.
    """
    X = V[F]                                         # (m, k, 3)
    m, k, _ = X.shape
    ctr = X.mean(axis=1)
    Xc = X - ctr[:, None, :]
    Xn = np.roll(Xc, -1, axis=1)
    b = np.cross(Xc, Xn)                             # x_i × x_{i+1}
    dvec = Xc - Xn                                   # a_i = b_i + c × d_i = b_i - [d_i]× c
    # normal equations  (Σ [d]×ᵀ[d]×) c = Σ [d]×ᵀ b,   [d]×ᵀ[d]× = |d|² I - d dᵀ,  [d]×ᵀ b = b × d
    dd = np.einsum("mki,mki->m", dvec, dvec)
    M = dd[:, None, None] * np.eye(3) - np.einsum("mki,mkj->mij", dvec, dvec)
    r = np.cross(b, dvec).sum(axis=1)
    c = np.einsum("mij,mj->mi", np.linalg.pinv(M, rcond=1e-10, hermitian=True), r)
    # least-norm affine weights:  [Xcᵀ; 1ᵀ] w = [c; 1]
    A = np.concatenate([np.transpose(Xc, (0, 2, 1)), np.ones((m, 1, k))], axis=1)  # (m, 4, k)
    rhs = np.concatenate([c, np.ones((m, 1))], axis=1)
    W = np.einsum("mkj,mj->mk", np.linalg.pinv(A, rcond=1e-10), rhs)
    W /= W.sum(axis=1, keepdims=True)
    return np.einsum("mk,mki->mi", W, X), W


def polygon_laplacian(V, faces, mass: str = "full", positive: bool = False) -> Laplacian:
    r"""Laplacian of a polygon mesh ("Polygon Laplacian Made Simple", Bunge et al. 2020).

    Each polygon gets a virtual vertex :math:`c_f = \sum_i w_{fi} x_i` (the minimiser of
    the squared fan areas, :func:`virtual_vertices`) and is refined into the triangle fan
    :math:`(x_i, x_{i+1}, c_f)`. With :math:`S, M` the cotangent stiffness and linear-FEM
    mass of the refined triangle mesh and :math:`P` the prolongation that keeps every
    vertex and puts :math:`c_f` at :math:`\sum_i w_{fi} f_i`,

    .. math:: L = P^\top S P, \qquad B = P^\top M P.

    Since :math:`P\mathbf 1 = \mathbf 1`, :math:`L\mathbf 1 = 0`; :math:`L` is PSD and
    :math:`B` SPD because :math:`S` is PSD, :math:`M` SPD and :math:`P` has full column
    rank. On a triangle the virtual vertex is the centroid, a linear function stays
    linear on the fan, and :math:`L, B` equal the cotangent stiffness and linear-FEM mass.

    Parameters
    ----------
    V : (n, 3) float
        Vertex positions.
    faces : (m, k) int or sequence of index sequences
        Polygons (any mix of degrees >= 3), each listed around its boundary.
    mass : {"full", "lumped"}
        ``"full"``: :math:`P^\top M P`. ``"lumped"``: its row sums on the diagonal (each
        vertex's share of the refined areas), as in Bunge et al.
    positive : bool
        Set the positive off-diagonal entries of :math:`L` (negative edge weights, from
        obtuse angles of the refined fans) to 0, the diagonal following so that rows sum
        to 0: with ``mass="lumped"``, :math:`-B^{-1}L` is then Metzler and heat kernels
        are non-negative (:func:`spectral_igl.laplacian.mesh.laplacian`'s default).

    Returns
    -------
    Laplacian
        ``domain="polygon"``; ``data`` holds ``V``, ``faces`` (the list of per-degree
        arrays), the virtual vertices ``C``, the prolongation ``P``, ``positive``,
        ``clamped`` (the number of edge weights set to 0) and ``positivity``
        (:attr:`~spectral_igl.laplacian.Laplacian.is_metzler`).

    Notes
    -----
    Degenerate polygons (a repeated vertex, or a fan triangle of zero area) are dropped
    with a warning, as :func:`spectral_igl.laplacian.mesh.laplacian` drops degenerate
    triangles; unreferenced vertices are kept as isolated components with the mean vertex
    mass.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    >>> lap = sig.polygon_laplacian(V, [[0, 1, 2, 3]])
    >>> round(lap.area(), 12), bool(np.allclose(lap.L @ np.ones(4), 0))
    (1.0, True)
    """
    V = as_points(V, "V", dims=(3,))
    n = V.shape[0]
    if mass not in _MASSES:
        raise ValueError(f"mass must be one of {_MASSES}, got {mass!r}")
    if not isinstance(positive, (bool, np.bool_)):
        raise TypeError(f"positive must be a bool, got {type(positive).__name__}")
    groups = as_polygons(faces, n, "faces")
    Cs, tris, prow, pcol, pval, kept = [], [], [], [], [], []
    dropped = 0
    nv = n
    for F in groups:
        s = np.sort(F, axis=1)
        bad = np.any(s[:, 1:] == s[:, :-1], axis=1)
        C, W = virtual_vertices(V, F)
        X = V[F]
        fan = np.linalg.norm(np.cross(X - C[:, None], np.roll(X, -1, axis=1) - C[:, None]), axis=2)
        scale = np.max(np.linalg.norm(X - C[:, None], axis=2), axis=1) ** 2
        with np.errstate(invalid="ignore"):
            bad |= ~np.all(fan > 1e-12 * scale[:, None], axis=1) | ~np.all(np.isfinite(W), axis=1)
        dropped += int(bad.sum())
        F, C, W = F[~bad], C[~bad], W[~bad]
        m, k = F.shape
        if m == 0:
            continue
        idx = nv + np.arange(m)
        tris.append(np.stack([F, np.roll(F, -1, axis=1), np.repeat(idx[:, None], k, axis=1)],
                             axis=2).reshape(-1, 3))
        prow.append(np.repeat(idx, k)), pcol.append(F.ravel()), pval.append(W.ravel())
        Cs.append(C)
        kept.append(F)
        nv += m
    if not tris:
        raise ValueError("all polygons of faces are degenerate (repeated vertices or zero area)")
    if dropped:
        warnings.warn(f"dropped {dropped} degenerate polygon(s) (repeated vertex or zero-area fan "
                      "triangle)", RuntimeWarning, stacklevel=2)
    Vr = np.vstack([V] + Cs)
    T = np.concatenate(tris)
    P = sp.vstack([sp.identity(n, format="csr"),
                   sp.csr_matrix((np.concatenate(pval), (np.concatenate(prow) - n, np.concatenate(pcol))),
                                 shape=(nv - n, n))]).tocsr()
    S = cotan_stiffness(Vr, T)
    M = full_mass(Vr, T)
    L = (P.T @ S @ P).tocsr()
    clamped = 0
    if positive:
        L, clamped = drop_negative_weights(L)
    B = (P.T @ M @ P).tocsr()
    if mass == "lumped":
        B = sp.diags(np.asarray(B.sum(axis=1)).ravel()).tocsr()
    referenced = np.zeros(n, dtype=bool)
    for F in kept:
        referenced[F.ravel()] = True
    n_unref = int(n - referenced.sum())
    if n_unref:
        warnings.warn(f"{n_unref} vertex/vertices referenced by no polygon: each is kept as an "
                      "isolated component with the mean vertex mass", RuntimeWarning, stacklevel=2)
        mean_mass = float(np.asarray(B.sum(axis=1)).ravel()[referenced].mean())
        B = (B + sp.diags(np.where(referenced, 0.0, mean_mass))).tocsr()
    adj = sp.csr_matrix((np.ones(sum(F.size for F in kept)),
                         (np.concatenate([np.repeat(F[:, 0], F.shape[1]) for F in kept]),
                          np.concatenate([F.ravel() for F in kept]))), shape=(n, n))
    data = {"V": V, "faces": kept, "C": np.vstack(Cs), "P": P, "mass": mass,
            "referenced": referenced, "positive": bool(positive), "clamped": (clamped + 1) // 2}
    lap = make_laplacian(L, B, domain="polygon", data=data, adjacency=adj)
    lap.data["positivity"] = lap.is_metzler
    return lap
