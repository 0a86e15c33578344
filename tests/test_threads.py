"""The package's dense sections run with a limited BLAS thread count and restore the caller's."""
import numpy as np
import pytest

threadpoolctl = pytest.importorskip("threadpoolctl")

from spectral_igl.linalg import threads  # noqa: E402
from spectral_igl.linalg.ldlt import LDLT, available  # noqa: E402


def _blas_threads():
    return {d["filepath"]: d["num_threads"] for d in threadpoolctl.threadpool_info() if d["user_api"] == "blas"}


def test_limit_inside_and_restored_outside():
    seen = {}

    @threads.serial_blas
    def probe():
        seen.update(_blas_threads())
        return 7

    with threadpoolctl.threadpool_limits(2, user_api="blas"):      # the caller's setting
        before = _blas_threads()
        if not before:
            pytest.skip("no BLAS that threadpoolctl can see")
        assert set(before.values()) == {2}
        assert probe() == 7
        assert set(seen.values()) == {threads.MAX_BLAS_THREADS} == {1}
        assert _blas_threads() == before


@pytest.mark.skipif(not available(), reason="LDLT extension not built")
def test_ldlt_runs_serial(monkeypatch):
    """The factorization's dense fronts call the BLAS: they run inside the limit."""
    import scipy.sparse as sp
    calls = []
    orig = threads.blas_threads

    def spy(limit=None):
        calls.append(limit)
        return orig(limit)

    monkeypatch.setattr(threads, "blas_threads", spy)
    A = sp.diags([-1.0, 4.0, -1.0], [-1, 0, 1], shape=(50, 50)).tocsr()
    fac = LDLT(A)
    x = fac.solve(np.ones(50))
    assert np.allclose(A @ x, 1.0)
    assert len(calls) >= 2


#: dense LAPACK entry points the package calls (numpy.linalg, scipy.linalg)
_LAPACK = {"numpy.linalg": ["qr", "svd", "lstsq", "eigh", "eigvalsh", "eig", "eigvals", "solve", "inv", "pinv",
                            "cholesky"],
           "scipy.linalg": ["qr", "svd", "lstsq", "eigh", "eigvalsh", "eig", "solve", "inv", "pinv", "cholesky",
                            "eigh_tridiagonal", "eigvalsh_tridiagonal", "lu_factor", "cho_factor",
                            "solve_triangular", "schur", "null_space", "orth"]}


def test_dense_work_of_the_main_paths_runs_in_a_section(monkeypatch):
    """Every LAPACK call on a matrix of 16 or more rows and columns made by the descriptors,
    kernels, distances and eigensolvers runs inside a thread section: outside one, OpenBLAS's
    default threads spin on a busy machine (the common-pole fits' QRs took an HKS at 16
    times on a 6k-vertex mesh from 1.5 s to 12 s of CPU with one core busy)."""
    import importlib
    import traceback
    import warnings
    from pathlib import Path

    import spectral_igl as sig
    from spectral_igl.data_generators import icosphere

    outside = []
    for modname, names in _LAPACK.items():
        mod = importlib.import_module(modname)
        for name in names:
            fn = getattr(mod, name)

            def guarded(*args, _fn=fn, _name=f"{modname}.{name}", **kwargs):
                big = any(isinstance(a, np.ndarray) and a.ndim == 2 and min(a.shape) >= 16 for a in args)
                if big and not getattr(threads._state, "depth", 0):
                    caller = traceback.extract_stack(limit=2)[0]
                    outside.append(f"{_name} from {Path(caller.filename).name}:{caller.lineno}")
                return _fn(*args, **kwargs)

            monkeypatch.setattr(mod, name, guarded)
    V, F = icosphere(3)
    lap, full = sig.laplacian(V, F), sig.laplacian(V, F, mass="full")
    area = float(lap.area())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sig.hks(lap, np.geomspace(1e-4, 1e-1, 8) * area)      # common poles (the fits)
        sig.wks(full, np.linspace(1.0, 4.0, 6), method="auto")
        sig.heat_kernel(lap, 1e-2 * area, [0, 7])
        sig.eigs(lap, 30)
        sig.eigs(full, 30)
        sig.biharmonic_distance(lap, 0)
        sig.diffusion_distance(lap, 1e-3 * area, 0)
        sig.kernel_diagonal(lap, sig.filters.heat(1e-2 * area))
    assert not outside, sorted(set(outside))
