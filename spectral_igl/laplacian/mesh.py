"""Linear-FEM Laplacians of triangle and tetrahedral meshes (libigl assembles)."""
from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp

from .._validate import as_cells, as_mesh_arrays, as_points, check_tets_have_volume
from ._operator import Laplacian, drop_negative_weights, make_laplacian
from .elements import (cotan_stiffness, element_measures, full_mass, mean_value_weights, mesh_components,
                       row_cross, star_adjacency)
from .polygon import polygon_laplacian

__all__ = ["laplacian", "clean_mesh", "clean_mesh_with_measures", "MASSES", "square", "mass_matrix", "full_mass",
           "star_adjacency", "element_measures", "mesh_components", "cotan_stiffness",
           "mean_value_weights", "triangle_arrays"]

_WEIGHTS = ("auto", "cotan", "intrinsic_delaunay", "uniform", "mean_value")
_ELEMENTS = ("auto", "triangle", "tet", "polygon")
MASSES = ("full", "lumped", "voronoi", "barycentric")


def clean_mesh(V, C=None, rel_tol: float = 1e-12):
    r"""Validate ``(V, C)`` and drop degenerate elements.

    An element is degenerate when it repeats a vertex or its measure is at most
    ``rel_tol`` times the largest element measure: its cotangent weights would be
    infinite or NaN.

    Parameters
    ----------
    V : (n, 3) float, or a pyvista/trimesh/meshio mesh with ``C`` omitted
    C : (m, 3) or (m, 4) int, optional
        Triangles or tetrahedra.
    rel_tol : float
        Relative measure below which an element is dropped (default 1e-12).

    Returns
    -------
    V : (n, 3) float
        The vertices, unchanged (unreferenced ones are kept).
    C_clean : (k, 3) or (k, 4) int
        The elements kept.
    dropped : int
        How many elements were removed.

    Raises
    ------
    ValueError
        When the arrays are malformed (naming which and how), or nothing is left.

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl.laplacian.mesh import clean_mesh
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]])
    >>> _, F, dropped = clean_mesh(V, np.array([[0, 1, 2], [0, 1, 3], [1, 1, 2]]))
    >>> F.tolist(), dropped
    ([[0, 1, 2]], 2)
    """
    V, C, dropped, _ = clean_mesh_with_measures(V, C, rel_tol)
    return V, C, dropped


def clean_mesh_with_measures(V, C, rel_tol: float = 1e-12):
    """:func:`clean_mesh`, also returning the measures of the kept elements."""
    V, C = as_mesh_arrays(V, C)
    V = as_points(V, "V", dims=(2, 3))
    shape = np.shape(C) if isinstance(C, np.ndarray) else ()
    C = as_cells(C, V.shape[0], "T" if len(shape) == 2 and shape[1] == 4 else "F")
    if C.shape[1] == 4 and V.shape[1] != 3:
        raise ValueError(f"tetrahedra need 3-D vertices; V has shape {V.shape}")
    check_tets_have_volume(V, C)
    s = np.sort(C, axis=1)
    repeated = np.any(s[:, 1:] == s[:, :-1], axis=1)
    with np.errstate(over="ignore", invalid="ignore"):   # overflowing measures are dropped below
        meas = element_measures(V, C)
    finite = np.isfinite(meas)
    top = meas[finite].max() if finite.any() else 0.0
    bad = repeated | (meas <= rel_tol * top) | ~finite
    if bad.all():
        raise ValueError(f"all {C.shape[0]} elements are degenerate (zero area/volume or repeated vertices)")
    return V, C[~bad], int(bad.sum()), meas[~bad]


def square(A: sp.spmatrix, n: int) -> sp.csr_matrix:
    """``A`` padded with zero rows and columns to (n, n).

    libigl sizes some matrices by the largest referenced index, so vertices that no
    element references at the end of ``V`` would otherwise be missing.
    """
    A = sp.csr_matrix(A)
    if A.shape != (n, n):
        A = A.copy()
        A.resize((n, n))
    return A


def voronoi_areas(V: np.ndarray, F: np.ndarray, meas: np.ndarray | None = None) -> np.ndarray:
    """(n,) mixed Voronoi areas of a triangle mesh's vertices (Meyer et al. 2003).

    In a triangle without an obtuse angle, corner i gets (|e_ij|² cot θ_k + |e_ik|² cot θ_j) / 8;
    in an obtuse one, the obtuse corner gets half the area and the others a quarter. The
    cotangents divide by the area from the cross product (``meas``), which stays accurate
    on needles whose edge lengths no longer resolve the area.
    """
    from .intrinsic import corner_cotangents, edge_lengths

    A = element_measures(V, F) if meas is None else np.asarray(meas, dtype=float)
    l = edge_lengths(V, F)
    sq = l * l                                                      # opposite each corner
    cot = corner_cotangents(l, A)
    area = (np.roll(sq, -1, axis=1) * np.roll(cot, -1, axis=1) + np.roll(sq, -2, axis=1) * np.roll(cot, -2, axis=1)) / 8.0
    obtuse = cot < 0
    some = obtuse.any(axis=1)
    area[some] = np.where(obtuse[some], 0.5, 0.25) * A[some, None]
    return np.bincount(F.ravel(), weights=area.ravel(), minlength=V.shape[0])


def mass_matrix(V: np.ndarray, C: np.ndarray, mass: str, meas: np.ndarray | None = None) -> sp.csr_matrix:
    if mass == "full":
        return full_mass(V, C, meas)
    if mass in ("lumped", "voronoi") and C.shape[1] == 3:
        return sp.diags(voronoi_areas(V, C, meas)).tocsr()
    # barycentric: row sums of the consistent mass (the lumped mass of tets as well)
    return sp.diags(np.asarray(full_mass(V, C, meas).sum(axis=1)).ravel()).tocsr()


def _element_kind(V, F, elements: str):
    """``("polygon", faces)`` or ``("cells", F)``: what ``laplacian`` should build from ``F``."""
    if elements == "polygon":
        return ("polygon", F)
    if not isinstance(F, np.ndarray):
        try:
            A = np.asarray(F)
        except ValueError:          # ragged: faces of different sizes
            A = None
        if A is None or A.dtype == object:
            if elements != "auto":
                raise ValueError(f"elements={elements!r} needs an (m, k) array; faces of "
                                 "different sizes are polygons (elements='polygon')")
            return ("polygon", F)
        F = A
    if F.ndim != 2 or elements != "auto":
        return ("cells", F)
    k = F.shape[1]
    if k >= 5:
        return ("polygon", F)
    if k != 4:
        return ("cells", F)
    Vp = np.asarray(V, dtype=np.float64)
    if Vp.ndim != 2 or Vp.shape[1] != 3 or F.size == 0 or not np.issubdtype(F.dtype, np.integer) \
            or F.min() < 0 or F.max() >= len(Vp):
        if Vp.ndim == 2 and Vp.shape[1] == 2:
            return ("polygon", F)   # four planar points are a quad, never a tetrahedron
        return ("cells", F)         # let the validation report the problem
    X = Vp[F]
    with np.errstate(over="ignore", invalid="ignore"):
        vol = np.abs(np.einsum("ij,ij->i", row_cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]),
                               X[:, 3] - X[:, 0])) / 6.0
        ell = np.mean([np.linalg.norm(X[:, a] - X[:, b], axis=1)
                       for a in range(4) for b in range(a + 1, 4)], axis=0)
        thin = float(np.median(vol / ell ** 3)) < 0.02 if np.all(np.isfinite(ell)) else False
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 3]], F[:, [3, 0]]]), axis=1)
    _, count = np.unique(e, axis=0, return_counts=True)
    if thin and count.max() <= 2:
        return ("polygon", F)
    return ("cells", F)


def _cleaned_cells(V, C, stacklevel: int):
    """:func:`clean_mesh_with_measures` of the cells ``C`` and the (n,) bool of the vertices
    they reference, with :func:`laplacian`'s warnings for dropped elements and unreferenced
    vertices (``stacklevel`` as :func:`warnings.warn` counts from the caller of this function)."""
    V, C, dropped, meas = clean_mesh_with_measures(V, C)
    n = V.shape[0]
    if dropped:
        warnings.warn(f"dropped {dropped} degenerate element(s) (zero measure or repeated vertex)",
                      RuntimeWarning, stacklevel=stacklevel + 1)
    referenced = np.zeros(n, dtype=bool)
    referenced[C.ravel()] = True
    n_unref = int(n - np.count_nonzero(referenced))
    if n_unref:
        warnings.warn(f"{n_unref} vertex/vertices referenced by no element: each is kept as an "
                      "isolated component with the mean vertex mass", RuntimeWarning, stacklevel=stacklevel + 1)
    return V, C, meas, referenced


def triangle_arrays(V, F, stacklevel: int = 2):
    """``(V, F)`` validated and cleaned as :func:`laplacian` with its defaults reads them, when
    it reads them as a triangle mesh; ``None`` for tetrahedra and polygons.

    For callers that build their own operators on a triangle mesh and need no
    :class:`Laplacian`: the same checks, the same dropped degenerate triangles and the
    same warnings (dropped triangles, unreferenced vertices) as :func:`laplacian`.

    Parameters
    ----------
    V : (n, 3) or (n, 2) float
    F : (m, 3) int, or any cells :func:`laplacian` takes
    stacklevel : int
        Where the warnings point, counted as :func:`warnings.warn` does from the caller.

    Returns
    -------
    V : (n, 3) or (n, 2) float
    F : (k, 3) int64
        The triangles kept. ``None`` in place of the pair for tetrahedra and polygons.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> _, F = triangle_arrays(V, [[0, 1, 2], [1, 3, 2]])
    >>> F.tolist(), triangle_arrays(V, np.array([[0, 1, 3, 2]])) is None
    ([[0, 1, 2], [1, 3, 2]], True)
    """
    kind, C = _element_kind(V, F, "auto")
    if kind == "polygon" or np.ndim(C) != 2 or np.shape(C)[1] != 3:
        return None
    V, C, _, _ = _cleaned_cells(V, C, stacklevel + 1)
    return V, C


def laplacian(V, F=None, weights: str = "auto", mass: str = "lumped", elements: str = "auto",
              positive: bool | None = None) -> Laplacian:
    r"""Laplacian of a triangle mesh ``(V, F)``, tetrahedral mesh ``(V, T)`` or polygon mesh.

    Parameters
    ----------
    V : (n, 3) float, or a mesh object
        Vertex positions (``(n, 2)`` allowed for planar triangle meshes); or a pyvista
        ``PolyData``/``UnstructuredGrid``, ``trimesh.Trimesh`` or ``meshio.Mesh``, with
        ``F`` omitted (its tetrahedra if it has any, else its triangles).
    F : (m, 3), (m, 4) or (m, k) int, or a list of index lists, optional
        Triangles, tetrahedra, or polygons; see ``elements``.
    elements : {"auto", "triangle", "tet", "polygon"}
        How to read ``F``. ``"auto"``: 3 columns are triangles; 5 or more columns, or a
        list of faces of different sizes, are polygons; 4 columns are decided by
        shape: ``F`` is a quad mesh when its boundary cycles (0, 1), (1, 2), (2, 3),
        (3, 0) form an edge-manifold surface (every such edge shared by at most two
        cells; in a tetrahedral mesh interior edges are shared by 3 or more) *and* the
        cells are thin (median volume below :math:`0.02\,\bar\ell^3`, :math:`\bar\ell`
        the cell's mean edge length; a regular tetrahedron has :math:`0.118\,\bar\ell^3`),
        and goes to the polygon Laplacian; otherwise ``F`` holds tetrahedra. Points in
        the plane (``V`` of shape ``(n, 2)``) make quads. ``"polygon"``
        always takes the faces as polygons (:func:`~spectral_igl.laplacian.polygon.polygon_laplacian`,
        Bunge et al. 2020; ``mass="full"`` is its :math:`P^\top M P`, the other masses its
        lumped row sums; ``weights`` must be ``"cotan"`` or ``"auto"``). On triangles it equals the
        cotan Laplacian.
    weights : {"auto", "cotan", "intrinsic_delaunay", "uniform", "mean_value"}
        ``"auto"`` (default): ``"intrinsic_delaunay"`` with ``positive=True`` for triangles,
        ``"cotan"`` for tets and polygons (see ``positive``).
        ``"cotan"``: linear FEM stiffness (libigl ``cotmatrix``), triangles and tets.
        ``"intrinsic_delaunay"``: cotan weights of the intrinsic Delaunay triangulation
        (Bobenko--Springborn); triangles only. Its weights are non-negative on interior
        edges; an edge with a single triangle (boundary) or more than two (non-manifold)
        cannot be flipped and keeps its cotan weight, negative where its opposite angles
        sum to more than :math:`\pi`. ``"uniform"``: graph Laplacian, unit edge weights.
        ``"mean_value"``: Floater's mean-value weights (triangles only,
        :func:`mean_value_weights`), positive for every triangle shape. They are not
        symmetric (:math:`w_{ij}` uses the angles at :math:`x_i`); the survey lists them as
        "always positive" and asks of every Laplacian a symmetric PSD stiffness with null
        row sums, so the stiffness uses :math:`(W + W^\top)/2`:
        :math:`L = \operatorname{diag}(\bar W\mathbf 1) - \bar W`,
        :math:`\bar W = (W + W^\top)/2`. Unlike cotan they are not the FEM stiffness and do
        not converge to the Laplace--Beltrami operator on general meshes.
    mass : {"lumped", "full", "barycentric"}
        ``"lumped"`` (default; alias ``"voronoi"``): the mixed Voronoi cell area (Meyer et
        al. 2003) for triangles, the barycentric mass for tets. ``"full"``: consistent
        linear-FEM mass. ``"barycentric"``: a third (a quarter) of each incident element's
        measure, the row sums of the full mass.
    positive : bool or None
        Make every edge weight non-negative (every off-diagonal entry of L <= 0): with a
        diagonal ``mass``, :math:`-B^{-1}L` is then Metzler and heat kernels are
        non-negative. With ``"intrinsic_delaunay"`` the boundary edges, which no flip of
        the mesh reaches, are first flipped in the mesh's mirror double (the Neumann
        reflection; ``mirror`` of
        :func:`~spectral_igl.laplacian.intrinsic.intrinsic_cotan_stiffness`), which keeps
        the accuracy of intrinsic Delaunay; then, for any ``weights``, the weights still
        negative are set to 0 (the diagonal follows, so rows still sum to 0).
        ``lap.data["clamped"]`` counts them. ``None`` (default): ``True`` for
        ``weights="auto"`` on triangles, ``False`` otherwise. Measured
        (``benchmarks/positivity.py``, jittered Neumann unit square with obtuse angles on
        the boundary, first 12 eigenvalues): 1.97e-3 -> 5.36e-4 from 4,225 to 16,641
        vertices against 1.96e-3 -> 5.34e-4 without ``positive``, where setting the
        boundary weights to 0 without the mirror flips gives first-order 5.5e-3 -> 2.7e-3.
        On tets and polygons no flips apply and the negative weights are interior: setting
        them to 0 makes the operator inconsistent (jittered unit cube: eigenvalues 40% off
        and not converging; jittered quads 2.2% against 0.23% at 4,225 vertices), so there
        ``positive=True`` trades accuracy for non-negative heat and is not the default.

    Returns
    -------
    Laplacian
        :math:`L` positive semi-definite with zero row sums, :math:`B` positive definite,
        and :math:`\tilde L = B^{-1}L`.

    Notes
    -----
    The defaults preserve positivity on triangle meshes, with or without boundary,
    manifold or not: intrinsic-Delaunay cotan weights (see ``positive``) are non-negative
    and the lumped mass is diagonal, so :math:`-B^{-1}L` is a Metzler matrix and
    :math:`e^{-t\tilde L}` maps non-negative data to non-negative data (the heat kernel,
    diffusion distances and HKS are non-negative). On the unit sphere the heat kernel at
    t = 0.05 converges in the max norm at rate 2.0 with these defaults against 1.6 with
    ``mass="full"`` (errors 5.1e-3 and 4.3e-3 at 10242 vertices), and the first 25
    eigenvalues are closer (0.13 against 0.16 at 2562 vertices); cotan with the full mass
    gives heat kernels whose minimum is -0.1% to -3% of the peak on real meshes at t = 1e-3
    (unit area), -5% to -13% on icospheres at t = 1e-4 (``benchmarks/positivity.py``).
    Cotan weights of tetrahedra and polygon Laplacians can be positive off the diagonal
    (obtuse dihedral and fan angles), so positivity is not guaranteed there by default
    (see ``positive``).
    ``lap.data["positivity"]`` and ``lap.is_metzler`` say whether this Laplacian has it
    (L's off-diagonal entries all <= 0 and B diagonal); where it has not, heat kernels
    warn once (:meth:`~spectral_igl.laplacian.Laplacian.warn_if_not_metzler`).

    Real data is handled rather than rejected. Several components, boundaries (natural
    Neumann conditions) and non-manifold edges need nothing special. Degenerate
    elements (repeated vertices, zero area or volume) are dropped with a warning, since
    their cotangent weights are infinite. Vertices that no remaining element references
    keep their index so outputs match ``V`` row for row; each becomes an isolated
    component with a zero row in ``L`` and the mean vertex mass in ``B`` (so ``B`` stays
    positive definite), and a warning says how many there are.

    Examples
    --------
    >>> import numpy as np, spectral_igl as sig
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0]]); F = np.array([[0, 1, 2]])
    >>> lap = sig.laplacian(V, F)
    >>> np.allclose(lap.L @ np.ones(3), 0), round(lap.area(), 6)
    (True, 0.5)
    """
    if weights not in _WEIGHTS:
        raise ValueError(f"weights must be one of {_WEIGHTS}, got {weights!r}")
    if mass not in MASSES:
        raise ValueError(f"mass must be one of {MASSES[:2] + MASSES[3:]}, got {mass!r}")
    if elements not in _ELEMENTS:
        raise ValueError(f"elements must be one of {_ELEMENTS}, got {elements!r}")
    if positive is not None and not isinstance(positive, (bool, np.bool_)):
        raise TypeError(f"positive must be a bool or None, got {type(positive).__name__}")
    if F is None:
        V, F = as_mesh_arrays(V, F)
    F = _element_kind(V, F, elements)
    if F[0] == "polygon":
        if weights not in ("cotan", "auto"):
            raise ValueError(f"polygon meshes take weights='cotan' only, got {weights!r}")
        Vp = as_points(V, "V", dims=(2, 3))
        if Vp.shape[1] == 2:
            Vp = np.c_[Vp, np.zeros(len(Vp))]
        return polygon_laplacian(Vp, F[1], mass="full" if mass == "full" else "lumped",
                                 positive=bool(positive))
    if elements == "tet" and np.shape(F[1])[1:] != (4,):
        raise ValueError(f"elements='tet' needs an (m, 4) array, got shape {np.shape(F[1])}")
    if elements == "triangle" and np.shape(F[1])[1:] != (3,):
        raise ValueError(f"elements='triangle' needs an (m, 3) array, got shape {np.shape(F[1])}")
    V, C, meas, referenced = _cleaned_cells(V, F[1], stacklevel=2)
    n = V.shape[0]
    if positive is None:
        positive = weights == "auto" and C.shape[1] == 3
    if weights == "auto":
        weights = "cotan" if C.shape[1] == 4 else "intrinsic_delaunay"
    L = square(cotan_stiffness(V, C, weights, mirror=bool(positive)), n)
    clamped = 0
    if positive:
        L, clamped = drop_negative_weights(L)
    B = square(mass_matrix(V, C, mass, meas), n)
    if not referenced.all():
        mean_mass = float(np.asarray(B.sum(axis=1)).ravel()[referenced].mean())
        B = (B + sp.diags(np.where(referenced, 0.0, mean_mass))).tocsr()
    domain = "triangle" if C.shape[1] == 3 else "tet"
    key = "F" if domain == "triangle" else "T"
    data = {"V": V, key: C, "weights": weights, "mass": mass, "referenced": referenced,
            "positive": bool(positive), "clamped": (clamped + 1) // 2}
    lap = make_laplacian(L, B, domain=domain, data=data, adjacency=star_adjacency(n, C))
    lap.data["positivity"] = lap.is_metzler
    return lap
