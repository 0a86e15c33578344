"""Sparse direct factorizations: the one primitive every solve in the package uses.

``factorize(A)`` returns an object with ``.solve(b)`` for ``b`` of shape (n,) or (n, k).
Real symmetric positive definite matrices go to CHOLMOD (through cholespy) by
default, to MKL PARDISO (pypardiso) when asked, and to SuperLU as the fallback;
complex matrices to SuperLU. ``"ldlt"`` is the package's own supernodal LDLᵀ without
pivoting (:mod:`spectral_igl.linalg.ldlt`), for definite real or complex symmetric matrices;
it also gives the diagonal of the inverse.
"""
from __future__ import annotations

import importlib.util
import logging
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .._extras import install_hint, require
from .._validate import as_flag, describe
from . import ldlt

__all__ = ["factorize", "available_backends", "check_backend", "Factor", "BACKENDS"]

log = logging.getLogger(__name__)

#: every backend name, best first (``available_backends()`` lists those importable here)
BACKENDS = ("cholespy", "pypardiso", "ldlt", "superlu")


def available_backends() -> list[str]:
    """Backends importable here, best first."""
    out = []
    if importlib.util.find_spec("cholespy") is not None:
        out.append("cholespy")
    if importlib.util.find_spec("pypardiso") is not None:
        out.append("pypardiso")
    if ldlt.available():
        out.append("ldlt")
    out.append("superlu")
    return out


#: how to install the backends that are optional dependencies
INSTALL = {"cholespy": "pip install cholespy", "pypardiso": install_hint("fast")}


def check_backend(backend) -> str:
    """Validate a sparse-solver backend name against those importable here.

    A known backend that is not installed is refused, before any work, with an ImportError of
    one line naming the command that installs it (a missing dependency, as for every extra).
    """
    valid = ("auto",) + tuple(available_backends())
    if isinstance(backend, str) and backend in BACKENDS and backend not in valid:
        raise ImportError(f"backend {backend!r} is not installed here (available: {', '.join(valid)}): "
                          f"{INSTALL.get(backend, '')}")
    if not isinstance(backend, str) or backend not in valid:
        raise ValueError(f"backend must be one of {valid}, got {describe(backend)}")
    return backend


class Factor:
    r"""A factorized sparse matrix. ``solve(b)`` solves ``A x = b``.

    Parameters
    ----------
    A : (n, n) sparse matrix
        Real or complex; symmetric positive definite unless ``spd=False``.
    backend : {"auto", "cholespy", "pypardiso", "ldlt", "superlu"}
        ``"auto"``: CHOLMOD (cholespy) for a real SPD matrix, SuperLU otherwise (and for
        complex matrices). A backend that is not installed is refused with an ImportError naming
        its ``pip install``.
    spd : bool
        Whether ``A`` is symmetric positive definite (default True).

    Attributes
    ----------
    n : int
    backend : str
        The backend used.
    nbytes : int
        Memory held by the factors (exact for ``ldlt`` and SuperLU, an estimate for CHOLMOD).

    Examples
    --------
    A complex shifted system, as the rational approximations solve, :math:`(L + zB)x = b`:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.linalg import Factor
    >>> lap = sig.laplacian(*icosphere(1))
    >>> A = (lap.L + (1 + 2j) * lap.B).tocsr()
    >>> fac = Factor(A, spd=False)
    >>> b = np.ones(lap.n)
    >>> fac.backend, bool(np.allclose(A @ fac.solve(b), b))
    ('superlu', True)
    """

    def __init__(self, A: sp.spmatrix, backend: str = "auto", spd: bool = True):
        A = sp.csr_matrix(A)
        n = A.shape[0]
        spd = as_flag(spd, "spd")
        if A.shape != (n, n):
            raise ValueError(f"matrix to factorize must be square, got shape {A.shape}")
        self.n = n
        self.dtype = np.complex128 if np.iscomplexobj(A.data) else np.float64
        backend = check_backend(backend)
        if backend == "auto":
            backend = "cholespy" if (spd and self.dtype == np.float64
                                     and "cholespy" in available_backends()) else "superlu"
        if backend not in ("superlu", "ldlt") and self.dtype != np.float64:
            backend = "superlu"
        self.backend = backend
        start = time.perf_counter()
        self.nbytes = 0
        if backend == "cholespy":
            from cholespy import CholeskySolverD, MatrixType

            A = A.tocsr()
            A.sort_indices()
            self._chol = CholeskySolverD(n, A.indptr.astype(np.int32), A.indices.astype(np.int32),
                                         A.data.astype(np.float64), MatrixType.CSR)
            # CHOLMOD does not report its factor's size: the lower triangle of A times the
            # fill of a nested-dissection factor on a surface mesh (about 10) is an estimate
            self.nbytes = int(12 * 10 * (A.nnz + n) // 2)
        elif backend == "ldlt":
            self._ldlt = ldlt.LDLT(A)
            self.nbytes = self._ldlt.nbytes
        elif backend == "pypardiso":
            pypardiso = require("pypardiso", "fast", "backend='pypardiso'")
            self._pardiso = pypardiso.PyPardisoSolver(mtype=11)
            self._A = A.tocsr()
            self._pardiso.factorize(self._A)
        else:
            self._lu = spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A" if spd else "COLAMD")
            self.nbytes = int((self._lu.L.nnz + self._lu.U.nnz) * (np.dtype(self.dtype).itemsize + 4))
        log.info("factorized n=%d nnz=%d with %s in %.3f s", n, A.nnz, backend, time.perf_counter() - start)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve ``A x = b`` for b of shape (n,) or (n, k)."""
        b = np.asarray(b)
        if b.shape[0] != self.n:
            raise ValueError(f"right-hand side must have {self.n} rows, got shape {b.shape}")
        if np.iscomplexobj(b) and self.dtype == np.float64:
            return self.solve(b.real) + 1j * self.solve(b.imag)
        if self.backend == "cholespy":
            b = np.ascontiguousarray(b, dtype=np.float64)
            x = np.empty_like(b)
            self._chol.solve(b, x)
            return x
        if self.backend == "ldlt":
            return self._ldlt.solve(b)
        if self.backend == "pypardiso":
            x = self._pardiso.solve(self._A, np.ascontiguousarray(b, dtype=np.float64))
            return x.reshape(b.shape)
        return self._lu.solve(np.asarray(b, dtype=np.result_type(b, self.dtype)))

    __call__ = solve


def factorize(A: sp.spmatrix, backend: str = "auto", spd: bool = True) -> Factor:
    r"""Factorize a sparse square matrix; see :class:`Factor`.

    Parameters
    ----------
    A : (n, n) sparse matrix
        Real or complex; symmetric positive definite unless ``spd=False``.
    backend : {"auto", "cholespy", "pypardiso", "ldlt", "superlu"}
        ``"auto"``: CHOLMOD (cholespy) for a real SPD matrix, SuperLU otherwise.
    spd : bool
        Whether ``A`` is symmetric positive definite (default True).

    Returns
    -------
    Factor
        ``solve(b)`` solves :math:`A x = b` for (n,) or (n, k) ``b``.

    Examples
    --------
    >>> import numpy as np
    >>> import scipy.sparse as sp
    >>> from spectral_igl import linalg
    >>> A = sp.csr_matrix(np.array([[4.0, 1.0], [1.0, 3.0]]))
    >>> x = linalg.factorize(A).solve(np.array([1.0, 2.0]))
    >>> bool(np.allclose(A @ x, [1.0, 2.0]))
    True
    """
    return Factor(A, backend=backend, spd=spd)
