"""Sparse symmetric LDLᵀ with selected inversion (the compiled ``_ldlt`` extension).

``LDLT(A)`` factorizes a sparse symmetric matrix, real or complex symmetric (``A = Aᵀ``,
not Hermitian), without pivoting: for symmetric positive definite matrices and for
``σL - zB`` with z off the real spectrum (a definite real or imaginary part), whose
leading minors never vanish. It gives ``solve(b)`` and ``inverse_diagonal()``, the
diagonal of ``A⁻¹`` by selected inversion (``selected_inverse()``: its entries on the pattern
of A) (Takahashi's equations on the supernodes of the
factor), at about the cost of a second factorization instead of n solves.

The fill-reducing ordering is approximate minimum degree (compiled; four to ten times
cheaper to compute, with a factor of about the same size on surface meshes of up to 10⁵
vertices) or METIS nested dissection (pymetis, the ``[metis]`` extra), whichever ``Pattern``
finds cheaper to factorize (see ``Pattern``); it holds the ordering and the symbolic analysis,
shared by every matrix with the same sparsity pattern (the shifted matrices of one
Laplacian).

The extension also holds the loops of the local heat kernels' region series
(:func:`chebyshev_series`, :func:`poisson_series`) and region growth (:func:`region_keys`),
each rounded exactly as its numpy form in :mod:`spectral_igl.approx`, which stays the path
where the extension is missing.
"""
from __future__ import annotations

import importlib.util

import numpy as np
import scipy.sparse as sp

from .._extras import require
from .threads import blas_threads

__all__ = ["Pattern", "LDLT", "available", "has_metis", "kernel_isa", "nested_dissection", "minimum_degree", "ORDERINGS",
           "chebyshev_series", "poisson_series", "region_keys"]

ORDERINGS = ("auto", "nested_dissection", "minimum_degree")

#: ``ordering="auto"`` keeps minimum degree while its factorization's flops per stored entry
#: (the mean width of the updates, small on small surface meshes) stay below this, and
#: otherwise also tries nested dissection and keeps the one with fewer flops
AUTO_WIDTH = 100.0


_BLAS = ("dgemm", "zgemm", "dtrsm", "ztrsm", "dtrmm", "ztrmm")


def _ext():
    from . import (
        _ldlt as ext,  # the compiled half of this module, built with the package
    )

    if not ext.blas_ready():
        ext.set_blas(*_blas_addresses())
    return ext


def _blas_addresses():
    """Addresses of the BLAS routines scipy exports to compiled code (its cython_blas
    capsules), for the dense blocks of the factorization, the solves and the inversion."""
    import ctypes

    from scipy.linalg import cython_blas

    get_name, get_pointer = ctypes.pythonapi.PyCapsule_GetName, ctypes.pythonapi.PyCapsule_GetPointer
    get_name.restype, get_name.argtypes = ctypes.c_char_p, [ctypes.py_object]
    get_pointer.restype, get_pointer.argtypes = ctypes.c_void_p, [ctypes.py_object, ctypes.c_char_p]
    out = []
    for name in _BLAS:
        cap = cython_blas.__pyx_capi__[name]
        out.append(int(get_pointer(cap, get_name(cap))))
    return out


def available() -> bool:
    """True when the compiled extension is importable."""
    try:
        _ext()
    except ImportError:
        return False
    return True


def _csr(M):
    """(indptr, indices, data) of a csr matrix for the compiled loops: one index type for both
    (int32 while both fit), contiguous float data."""
    M = sp.csr_matrix(M)
    index = np.int32 if M.indices.dtype == np.int32 and M.indptr.dtype == np.int32 else np.int64
    return (M.indptr.astype(index, copy=False), M.indices.astype(index, copy=False),
            np.ascontiguousarray(M.data, dtype=float))


def chebyshev_series(P: sp.csr_matrix, offsets, C, rows, t1, t0, W) -> bool:
    """Terms 2..K of a Chebyshev recurrence on a block-diagonal P, in the compiled loop: at
    term k, on the leading ``rows[k]`` rows, ``t_k = P t_{k-1} - t_{k-2}`` and
    ``W += C[b, k] t_k`` (b the row's block, ``offsets`` the blocks' rows), rounded exactly as
    the numpy form ``q = P @ t1; q - t0; W += c * t`` rounds it (no fused multiply-add), one pass
    over each row instead of four; ``rows[k]`` are block boundaries that never grow. ``W`` is
    updated in place; ``t1`` and ``t0`` are scratch. Each block runs all its terms at once, while
    its rows are in cache, without the GIL. Returns False, having done nothing, when the extension is not available."""
    try:
        ext = _ext()
    except ImportError:
        return False
    ext.chebyshev_series(*_csr(P), np.asarray(offsets, dtype=np.int64), np.ascontiguousarray(C, dtype=float),
                         np.asarray(rows, dtype=np.int64), t1, t0, W)
    return True


def poisson_series(P: sp.csr_matrix, offsets, lam, rows, W) -> bool:
    """Terms 1..K of a Poisson series on a block-diagonal P, in the compiled loop, from W's
    blocks q_0: at term k, on the blocks within the leading ``rows[k]`` rows,
    ``q_k = (P q_{k-1}) * (lam[b] / k)`` and ``W += q_k``, rounded exactly as the numpy form
    ``q = P @ q; q *= lam / k; W += q`` rounds it, one pass over each row, each block's terms at
    once (as :func:`chebyshev_series`). Returns False, having done nothing, when the extension is
    not available."""
    try:
        ext = _ext()
    except ImportError:
        return False
    ext.poisson_series(*_csr(P), np.asarray(offsets, dtype=np.int64), np.ascontiguousarray(lam, dtype=float),
                       np.asarray(rows, dtype=np.int64), np.empty_like(W), np.empty_like(W), W)
    return True


def region_keys(L: sp.csr_matrix, h2, sources, offsets, radii, limits, labels):
    """(keys, region offsets) of :func:`spectral_igl.approx.region.grow_regions` in the compiled
    loop, group by group, each distance rounded as the numpy form rounds it (the same regions);
    None when the extension is not available."""
    try:
        ext = _ext()
    except ImportError:
        return None
    f64, i64 = (lambda a: np.ascontiguousarray(a, dtype=float)), (lambda a: np.ascontiguousarray(a, dtype=np.int64))
    indptr, indices, _ = _csr(L)
    return ext.grow_regions(indptr, indices, f64(h2), i64(sources), i64(offsets), f64(radii), i64(limits),
                            i64(labels))



def has_metis() -> bool:
    """True when pymetis (the ``[metis]`` extra), and so nested dissection, is installed."""
    return importlib.util.find_spec("pymetis") is not None


def kernel_isa() -> str:
    """Instruction set of the compiled kernels in use: ``"avx2"``, or ``"baseline"``.

    The factorization, solves and selected inversion are compiled for AVX2 and for the
    x86-64 baseline and chosen at run time by the CPU; ``SPECTRAL_IGL_BASELINE=1`` in the
    environment (read once, at the first call) forces the baseline, to test on one
    machine what machines without AVX2 compute.
    """
    return _ext().kernel_isa()


def _symmetric_csc(A) -> sp.csc_matrix:
    A = sp.csc_matrix(A)
    n = A.shape[0]
    if A.shape != (n, n):
        raise ValueError(f"LDLT needs a square matrix, got shape {A.shape}")
    A.sum_duplicates()
    A.sort_indices()
    return A


def nested_dissection(A) -> np.ndarray:
    """METIS nested-dissection ordering of the graph of ``A + Aᵀ`` (perm[q] = old index).

    Needs pymetis, the ``[metis]`` extra.
    """
    pymetis = require("pymetis", "metis", "the nested-dissection ordering")

    n = A.shape[0]
    G = sp.csr_matrix((np.ones(A.nnz, dtype=np.int8), A.indices, A.indptr), shape=(n, n))
    G = (G + G.T).tocsr()
    G.setdiag(0)
    G.eliminate_zeros()
    G.sort_indices()
    if G.nnz == 0:
        return np.arange(n, dtype=np.int32)
    perm, _ = pymetis.nested_dissection(pymetis.CSRAdjacency(G.indptr.astype(np.int64), G.indices.astype(np.int64)))
    return np.asarray(perm, dtype=np.int32)


def minimum_degree(A) -> np.ndarray:
    """Minimum-degree ordering of the graph of ``A + Aᵀ`` (perm[q] = old index).

    Compiled (``src/minimum_degree.hpp``): the elimination graph is kept as a quotient
    graph of eliminated cliques, indistinguishable vertices are eliminated together, and
    degrees are the approximate-minimum-degree upper bounds (Amestoy, Davis & Duff 1996).
    Rows with more than max(16, 10√n) entries are ordered last.

    Parameters
    ----------
    A : (n, n) sparse
        Its pattern is symmetrized; values, the diagonal and duplicates are ignored.

    Returns
    -------
    perm : (n,) int32
        A permutation of ``0..n-1``: ``perm[q]`` is eliminated ``q``-th.
    """
    A = _symmetric_csc(A)   # the compiled ordering symmetrizes the pattern itself
    return _ext().minimum_degree(A.indptr.astype(np.int32), A.indices.astype(np.int32))


class Pattern:
    """Ordering and symbolic factorization of one symmetric sparsity pattern.

    ``ordering`` is ``"nested_dissection"`` (METIS), ``"minimum_degree"`` (compiled, see
    :func:`minimum_degree`: four to ten times cheaper to compute, a factor of about the same
    size on surface meshes below about 10⁵ vertices, far larger on volumes and large
    surfaces) or ``"auto"`` (the default): minimum degree, unless its factorization costs
    more than :data:`AUTO_WIDTH` flops per stored entry, in which case nested dissection is
    computed too (when pymetis, the ``[metis]`` extra, is installed) and the ordering with
    fewer flops kept (``self.ordering`` says which).
    """

    def __init__(self, A, ordering: str = "auto"):
        if not isinstance(ordering, str) or ordering not in ORDERINGS:
            raise ValueError(f"ordering must be one of {ORDERINGS}, got {ordering!r}")
        A = _symmetric_csc(A)
        self.n = A.shape[0]
        pat = sp.csc_matrix((np.ones(A.nnz), A.indices, A.indptr), shape=A.shape)
        pat = (pat + pat.T).tocsc()
        pat.sort_indices()
        self.indptr = pat.indptr.astype(np.int32)
        self.indices = pat.indices.astype(np.int32)
        # sorted keys col * n + row of the pattern's entries, in CSC order
        self._keys = np.repeat(np.arange(self.n, dtype=np.int64), np.diff(pat.indptr)) * self.n + pat.indices
        ext = _ext()
        if ordering == "nested_dissection":
            sym = ext.Symbolic(self.indptr, self.indices, nested_dissection(pat))
        else:
            sym = ext.Symbolic(self.indptr, self.indices, ext.minimum_degree(self.indptr, self.indices))
            if ordering == "auto":
                ordering = "minimum_degree"
                if sym.flops > AUTO_WIDTH * sym.nnz_L and has_metis():
                    nd = ext.Symbolic(self.indptr, self.indices, nested_dissection(pat))
                    if nd.flops < sym.flops:
                        sym, ordering = nd, "nested_dissection"
        self.ordering = ordering
        self.symbolic = sym

    @property
    def nnz_L(self) -> int:
        """Entries stored in the factor L (supernodal, lower triangle)."""
        return int(self.symbolic.nnz_L)

    @property
    def nbytes(self) -> int:
        """Bytes of the ordering and the pattern's index arrays."""
        return int(self.indptr.nbytes + self.indices.nbytes + self._keys.nbytes)

    def values(self, A) -> np.ndarray:
        """The entries of ``A`` in this pattern's order (entries outside it are refused)."""
        A = _symmetric_csc(A)
        if A.shape[0] != self.n:
            raise ValueError(f"matrix has {A.shape[0]} rows, the pattern {self.n}")
        if (A.nnz == self._keys.size and np.array_equal(A.indptr, self.indptr)
                and np.array_equal(A.indices, self.indices)):
            # stored exactly on the pattern: its entries are already in order
            return np.array(A.data, dtype=np.result_type(A.data.dtype, np.float64))
        A = A.tocoo()
        key = A.col.astype(np.int64) * self.n + A.row
        pos = np.minimum(np.searchsorted(self._keys, key), self._keys.size - 1)
        inside = self._keys[pos] == key
        if not np.all(inside | (A.data == 0)):
            raise ValueError("matrix has entries outside the analysed sparsity pattern")
        pos, data = pos[inside], A.data[inside]
        m = self._keys.size
        out = np.bincount(pos, weights=data.real, minlength=m)
        if np.iscomplexobj(data):
            out = out + 1j * np.bincount(pos, weights=data.imag, minlength=m)
        return out


def _one_nonzero_per_column(B):
    """(rows, values) if every column of the dense B holds exactly one nonzero, else None."""
    if B.size == 0:
        return None
    nz = B != 0
    if not np.all(np.count_nonzero(nz, axis=0) == 1):
        return None
    rows = np.argmax(nz, axis=0)
    return rows, B[rows, np.arange(B.shape[1])]


class LDLT:
    """``A = P L D Lᵀ Pᵀ`` of a sparse symmetric matrix (real or complex symmetric).

    Its dense work runs in a thread section of :mod:`spectral_igl.linalg.threads` when its
    largest BLAS call (from the symbolic analysis) could use several threads.
    """

    def __init__(self, A, pattern: Pattern | None = None):
        A = _symmetric_csc(A)
        self.pattern = pattern if pattern is not None else Pattern(A)
        vals = self.pattern.values(A)
        cplx = np.iscomplexobj(vals)
        self.dtype = np.complex128 if cplx else np.float64
        if not np.all(np.isfinite(vals)):
            raise ValueError("matrix to factorize has non-finite entries")
        ext = _ext()
        cls = ext.FactorZ if cplx else ext.FactorD
        try:
            with self._section("factor"):
                self._f = cls(self.pattern.symbolic, np.ascontiguousarray(vals, dtype=self.dtype))
        except RuntimeError as exc:   # a zero pivot: the matrix is singular or needs pivoting
            raise ValueError(f"LDLT failed: {exc}") from None
        self.n = A.shape[0]
        self.nbytes = int(self.pattern.nnz_L * np.dtype(self.dtype).itemsize)

    def _section(self, op: str, k: int = 1):
        """The thread section of ``op`` ("factor", "solve" of ``k`` columns, "inverse")."""
        return blas_threads(calls=self.pattern.symbolic.largest_blas(op, k))

    def solve(self, b) -> np.ndarray:
        b = np.asarray(b)
        if b.shape[0] != self.n:
            raise ValueError(f"right-hand side must have {self.n} rows, got shape {b.shape}")
        if np.iscomplexobj(b) and self.dtype == np.float64:
            return self.solve(b.real) + 1j * self.solve(b.imag)
        B = b.reshape(self.n, -1)
        unit = _one_nonzero_per_column(B)
        if unit is not None:          # scaled columns of A^-1: a sparse forward substitution
            rows, w = unit
            X = self.inverse_columns(rows)
            if not np.all(w == 1):
                X *= w
            return X.reshape(b.shape)
        B = np.ascontiguousarray(B, dtype=self.dtype)
        with self._section("solve", B.shape[1]):
            return self._f.solve(B).reshape(b.shape)

    def inverse_columns(self, idx) -> np.ndarray:
        """(n, k) the columns ``idx`` of A⁻¹.

        The forward substitution of a unit vector is nonzero only on the path from its row to
        the root of the elimination tree, so it runs on each supernode for just the columns
        whose rows lie below it (one contiguous range, the columns sorted by elimination order);
        the backward substitution is dense.
        """
        idx = np.ascontiguousarray(np.asarray(idx).reshape(-1), dtype=np.int64)
        if idx.size and (idx.min() < 0 or idx.max() >= self.n):
            raise ValueError(f"column indices must lie in [0, {self.n}), got range [{idx.min()}, {idx.max()}]")
        with self._section("solve", idx.size):
            return self._f.inverse_columns(idx)

    def inverse_diagonal(self) -> np.ndarray:
        """diag(A⁻¹) by selected inversion."""
        with self._section("inverse"):
            return self._f.inverse_diagonal()

    def selected_inverse(self) -> sp.csc_matrix:
        r"""(n, n) sparse: the entries of A⁻¹ on the sparsity pattern of ``self.pattern``.

        The selected inversion behind :meth:`inverse_diagonal` forms, supernode by supernode,
        the dense blocks of A⁻¹ on the rows of the factor, which hold every entry of the
        pattern of A; this keeps them, at no extra factorization. With it,
        :math:`\operatorname{tr}(A^{-1}M) = \sum_{ij} (A^{-1})_{ij} M_{ji}` for any symmetric M
        whose pattern lies in A's (``np.dot(Z.data, self.pattern.values(M))``, the entries
        in the same order).
        """
        p = self.pattern
        with self._section("inverse"):
            vals = self._f.selected_inverse()
        return sp.csc_matrix((vals, p.indices, p.indptr), shape=(self.n, self.n))

    def pivots(self) -> np.ndarray:
        """(n,) the diagonal D of the factorization, in the original ordering (its signs are
        the inertia of A, by Sylvester's law)."""
        return self._f.pivots()
