"""The :class:`Laplacian` pair (L, B) that every later stage takes."""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .._validate import describe
from .cache import Cache
from .elements import pattern_components

__all__ = ["Laplacian", "make_laplacian", "check_laplacian", "drop_negative_weights"]


@dataclass(eq=False)
class Laplacian:
    r"""A discrete Laplacian as a stiffness/mass pair.

    The Laplace--Beltrami operator is :math:`\tilde L = B^{-1} L`, self-adjoint in
    the inner product :math:`\langle f, g\rangle_B = f^\top B g`.

    Attributes
    ----------
    L : (n, n) scipy.sparse.csr_matrix, float64
        Stiffness matrix: symmetric positive *semi*-definite, every row sums to 0.
    B : (n, n) scipy.sparse.csr_matrix, float64
        Mass matrix: symmetric positive definite.
    domain : str
        ``"triangle"``, ``"tet"``, ``"points"``, ``"voxels"`` or ``"graph"``.
    data : dict
        What the domain was built from (``V``, ``F``/``T``, ``P``, ``mask``...), so that
        later stages (gradients, pictures) can get at the geometry.
    components : (n,) int
        Connected component label of each vertex (graph of the nonzeros of L).
    n_components : int
    cache : Cache
        Factorizations, spectral bounds and other derived quantities computed by later
        stages, reused across calls (``lap.cache.clear()`` frees them, ``lap.cache.nbytes``
        reports their memory). Never stale: L and B are not to be modified after
        construction.

    Examples
    --------
    Built by the domain constructors (:func:`spectral_igl.laplacian`, ...); rows of L sum to 0
    and the mass sums to the area:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> lap.n, lap.n_components, lap.domain
    (162, 1, 'triangle')
    >>> bool(np.allclose(lap.L @ np.ones(lap.n), 0)), bool(np.isclose(lap.mass.sum(), lap.area()))
    (True, True)
    """

    L: sp.csr_matrix
    B: sp.csr_matrix
    domain: str = "matrix"
    data: dict = field(default_factory=dict)
    components: np.ndarray = None
    n_components: int = 0
    cache: Cache = field(default_factory=Cache, repr=False)
    _metzler: bool = field(default=None, init=False, repr=False)
    _warned: bool = field(default=False, init=False, repr=False)

    @property
    def n(self) -> int:
        """Number of vertices (rows of L and B)."""
        return self.L.shape[0]

    @property
    def lumped(self) -> bool:
        """True when B is diagonal."""
        return self.B.nnz == self.n and np.all(self.B.indices == np.arange(self.n))

    @property
    def mass(self) -> np.ndarray:
        """(n,) row sums of B: the lumped mass of each vertex."""
        return np.asarray(self.B.sum(axis=1)).ravel()

    @property
    def is_metzler(self) -> bool:
        r"""True when :math:`-B^{-1}L` is a Metzler matrix: B diagonal and positive, and
        every off-diagonal entry of L :math:`\le 0` (every edge weight non-negative).

        Exactly then is :math:`e^{-tB^{-1}L}` entrywise non-negative for every
        :math:`t \ge 0`, so that heat kernels, diffusion distances and heat kernel
        signatures are non-negative (for an exactly computed kernel).
        """
        if self._metzler is None:
            L = self.L
            row = np.repeat(np.arange(self.n), np.diff(L.indptr))
            off_ok = not np.any((L.data > 0) & (L.indices != row))
            self._metzler = bool(off_ok and self.lumped and np.all(self.B.diagonal() > 0))
        return self._metzler

    def warn_if_not_metzler(self, what: str = "heat kernel", stacklevel: int = 3) -> None:
        """Warn, once per Laplacian, that its ``what`` can be negative (see :attr:`is_metzler`).

        Called where heat kernels and other kernels that are non-negative in the continuum
        are evaluated; silent when :attr:`is_metzler` holds.
        """
        if self._warned or self.is_metzler:
            return
        self._warned = True
        if not self.lumped:
            why = "its mass matrix B is not diagonal"
        else:
            row = np.repeat(np.arange(self.n), np.diff(self.L.indptr))
            k = int(np.count_nonzero((self.L.data > 0) & (self.L.indices != row))) // 2
            why = f"{k} of its edge weights are negative (positive off-diagonal entries of L)"
        warnings.warn(f"this Laplacian is not Metzler ({why}), so its {what} can take negative "
                      "values; the defaults of sig.laplacian (weights='auto', mass='lumped') are "
                      "Metzler on triangle and polygon meshes, and positive=True makes any lumped "
                      "Laplacian Metzler", RuntimeWarning, stacklevel=stacklevel)

    def component_basis(self) -> sp.csr_matrix:
        r"""(n, c) sparse basis of ker L: one B-normalised indicator per component.

        Columns :math:`z_c = 1_c / \sqrt{1_c^\top B 1_c}`, so :math:`Z^\top B Z = I`.
        """
        def build():
            n, c = self.n, self.n_components
            Z = sp.csr_matrix((np.ones(n), (np.arange(n), self.components)), shape=(n, c))
            area = np.asarray((Z.T @ (self.B @ Z)).diagonal()).ravel()
            return (Z @ sp.diags(1.0 / np.sqrt(area))).tocsr()

        return self.cache.fetch("basis", "components", build)

    def component_sum(self, f: np.ndarray) -> np.ndarray:
        r""":math:`\sum_c 1_c 1_c^\top f`: each entry of ``f`` ((n,) or (n, k)) replaced by the
        sum over its connected component."""
        comp = self.components
        S = sp.csr_matrix((np.ones(self.n), (np.arange(self.n), comp)), shape=(self.n, self.n_components))
        return S @ (S.T @ f)

    def component_volume(self) -> np.ndarray:
        r"""(n,) the measure :math:`1_c^\top B 1_c` of each vertex's component."""
        return np.bincount(self.components, weights=self.mass, minlength=self.n_components)[self.components]

    def project_out_kernel(self, f: np.ndarray) -> np.ndarray:
        r"""Remove from ``f`` its B-orthogonal projection onto ker L (constants per component).

        Returns :math:`f - Z Z^\top B f`. Used by singular filters (pseudo-inverses).
        """
        Z = self.component_basis()
        return f - Z @ (Z.T @ (self.B @ f))

    def area(self) -> float:
        """Total measure (area, volume, or mass) ``1ᵀ B 1``."""
        return float(self.B.sum())

    def __repr__(self) -> str:
        return (
            f"Laplacian(domain={self.domain!r}, n={self.n}, nnz(L)={self.L.nnz}, "
            f"components={self.n_components}, lumped={self.lumped}, metzler={self.is_metzler})"
        )


def check_laplacian(lap, name: str = "lap") -> Laplacian:
    """Validate a Laplacian argument (strict: the package's own stages; public entry points
    take any input through :func:`spectral_igl.laplacian.inputs.as_laplacian`)."""
    if not isinstance(lap, Laplacian):
        raise TypeError(f"{name} must be a spectral_igl.Laplacian (from sig.laplacian(V, F) or "
                        f"another constructor), got {describe(lap)}")
    return lap


def drop_negative_weights(L: sp.spmatrix) -> tuple[sp.csr_matrix, int]:
    """``L`` with its positive off-diagonal entries (negative edge weights) set to 0.

    Returns ``(L, k)``, ``k`` the number of entries changed. The diagonal is left as it is:
    :func:`make_laplacian` resets it so that every row sums to 0, which keeps the result
    positive semi-definite (it is a sum of non-negative edge terms).
    """
    L = sp.csr_matrix(L, dtype=np.float64, copy=True)
    row = np.repeat(np.arange(L.shape[0]), np.diff(L.indptr))
    bad = (L.data > 0) & (L.indices != row)
    L.data[bad] = 0.0
    L.eliminate_zeros()
    return L, int(np.count_nonzero(bad))


#: relative asymmetry of a mass matrix taken as rounding (beyond it B is refused, not symmetrised)
MASS_ASYMMETRY = 1e-10


def _real_matrix(A, name: str) -> sp.csr_matrix:
    """``A`` as a real CSR matrix; complex or non-numeric entries are refused (a cast would drop
    the imaginary part)."""
    try:
        M = sp.csr_matrix(A)
    except (TypeError, ValueError) as err:
        raise TypeError(f"{name} must be a real sparse or dense matrix, got {type(A).__name__}") from err
    if M.dtype.kind not in "biuf":
        raise TypeError(f"{name} must be real, got a {M.shape} matrix of dtype {M.dtype}")
    return M


def _check_symmetric(B: sp.csr_matrix, name: str) -> None:
    """Refuse a matrix that differs from its transpose beyond rounding."""
    B = sp.csr_matrix(B, dtype=np.float64)
    if B.shape[0] != B.shape[1] or B.nnz == 0:
        return
    asym = abs(B - B.T).max()
    top = abs(B).max()
    if asym > MASS_ASYMMETRY * top:
        raise ValueError(f"{name} must be symmetric, but |{name} - {name}^T| reaches {asym:.3g} "
                         f"(largest entry {top:.3g})")


def _symmetrize(A: sp.spmatrix) -> sp.csr_matrix:
    A = sp.csr_matrix(A, dtype=np.float64)
    A = ((A + A.T) * 0.5).tocsr()
    A.sum_duplicates()
    A.eliminate_zeros()
    A.sort_indices()
    return A


def _canonical(A: sp.spmatrix) -> sp.csr_matrix:
    """``A`` as canonical CSR (sorted, summed, no explicit zeros), for an exactly symmetric ``A``."""
    A = sp.csr_matrix(A, dtype=np.float64, copy=True)
    A.sum_duplicates()
    A.eliminate_zeros()
    A.sort_indices()
    return A


def _zero_row_sums(L: sp.csr_matrix) -> sp.csr_matrix:
    """Replace the diagonal of a canonical CSR ``L`` by minus its off-diagonal row sums.

    Equal, entry for entry and in the stored pattern, to
    ``off - diags(off.sum(1))`` with ``off = L - diags(L.diagonal())`` (zeros dropped):
    the row sums are accumulated in the same order (``np.add.reduceat``). Done on the CSR arrays directly when
    every row has a nonzero result on the diagonal, the common case; when all of them
    also lack a stored diagonal entry, the entries are inserted in one pass.
    """
    n = L.shape[0]
    counts = np.diff(L.indptr)
    row = np.repeat(np.arange(n, dtype=L.indices.dtype), counts)
    isdiag = L.indices == row
    off = np.where(isdiag, 0.0, L.data)
    # scipy's row sum is np.add.reduceat over the stored off-diagonal entries: do the same
    keep = ~isdiag
    ptr = np.concatenate([[0], np.cumsum(np.bincount(row[keep], minlength=n))])
    vals = L.data[keep]
    rs = np.zeros(n)
    nonempty = ptr[1:] > ptr[:-1]
    if vals.size:
        rs[nonempty] = np.add.reduceat(vals, ptr[:-1][nonempty])
    if np.all(rs != 0):
        nd = int(np.count_nonzero(isdiag))
        if nd == n:
            off[isdiag] = -rs
            return sp.csr_matrix((off, L.indices.copy(), L.indptr.copy()), shape=L.shape)
        if nd == 0:
            below = np.bincount(row[L.indices < row], minlength=n)
            pos = np.arange(L.nnz) + row + (L.indices > row)
            dpos = L.indptr[:-1] + np.arange(n) + below
            data = np.empty(L.nnz + n)
            idx = np.empty(L.nnz + n, dtype=L.indices.dtype)
            data[pos], idx[pos] = off, L.indices
            data[dpos], idx[dpos] = -rs, np.arange(n)
            indptr = L.indptr + np.arange(n + 1, dtype=L.indptr.dtype)
            return sp.csr_matrix((data, idx, indptr), shape=L.shape)
    offm = L - sp.diags(L.diagonal())
    L = (offm - sp.diags(np.asarray(offm.sum(axis=1)).ravel())).tocsr()
    L.sort_indices()
    return L


def make_laplacian(L, B, domain: str = "matrix", data: dict | None = None,
                   adjacency: sp.spmatrix | None = None, *, _symmetric: bool = False) -> Laplacian:
    r"""Build a :class:`Laplacian` from a stiffness ``L`` (PSD) and a mass ``B`` (SPD).

    ``L`` is symmetrised and its diagonal reset so that every row sums to exactly 0; ``B``
    must be symmetric up to rounding (:data:`MASS_ASYMMETRY`), and both must be real.
    This is the one place where every constructor's matrices are normalised.

    Parameters
    ----------
    L : (n, n) sparse or dense float
        Stiffness, symmetric positive semi-definite up to rounding.
    B : (n, n) sparse or dense float
        Mass, symmetric positive definite.
    domain : str
        Label of the domain (default ``"matrix"``: no geometry).
    data : dict, optional
        What the domain was built from (``V``, ``F``, ...), kept as :attr:`Laplacian.data`.
    adjacency : (n, n) sparse, optional
        Connectivity giving the components (default: the nonzero pattern of ``L``).

    Returns
    -------
    Laplacian

    Notes
    -----
    Components come from ``adjacency`` (e.g. the mesh's elements) when given, else from
    the nonzero pattern of ``L``; a cotangent weight that happens to be exactly zero
    must not split a connected mesh. A constructor that knows ``L``
    equals ``L.T`` entry for entry says so with the keyword-only ``_symmetric=True``, so that
    :math:`(L + L^T)/2 = L` needs no transpose.

    .. math:: L \leftarrow \tfrac12 (L + L^\top), \qquad L_{ii} \leftarrow -\sum_{j \ne i} L_{ij}

    Examples
    --------
    The path graph on three vertices with a lumped mass:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> L = np.array([[1.0, -1, 0], [-1, 2, -1], [0, -1, 1]])
    >>> lap = sig.make_laplacian(L, np.eye(3))
    >>> lap.n, lap.n_components, np.round(sig.dense_eigs(lap)[0], 6)
    (3, 1, array([0., 1., 3.]))
    """
    L, B = _real_matrix(L, "L"), _real_matrix(B, "B")
    L = _canonical(L) if _symmetric else _symmetrize(L)
    n = L.shape[0]
    if L.shape != (n, n):
        raise ValueError(f"L must be square, got shape {L.shape}")
    L = _zero_row_sums(L)
    _check_symmetric(B, "B")
    B = _symmetrize(B)
    if B.shape != (n, n):
        raise ValueError(f"B must have shape {(n, n)}, got {B.shape}")
    if not (np.all(np.isfinite(L.data)) and np.all(np.isfinite(B.data))):
        raise ValueError("L or B contains NaN or inf")
    d = L.diagonal()
    if d.size and d.min() < -1e-12 * max(float(np.abs(d).max()), np.finfo(float).tiny):
        neg = int(np.count_nonzero(d < 0))
        raise ValueError(f"L must be positive semi-definite (stiffness), but {neg} of its {n} diagonal "
                         f"entries are negative (min {d.min():.3g}) once its rows sum to 0: this is the "
                         "sign of libigl's cotmatrix (negative semi-definite); pass -L")
    if np.any(B.diagonal() <= 0):
        raise ValueError(f"B must be positive definite; {int(np.sum(B.diagonal() <= 0))} diagonal entries are <= 0")
    labels, nc = pattern_components(L if adjacency is None else adjacency)
    return Laplacian(L=L, B=B, domain=domain, data=dict(data or {}), components=labels, n_components=nc)
