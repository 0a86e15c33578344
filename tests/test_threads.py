"""The package's dense sections run with a limited BLAS thread count and restore the caller's."""
import functools
from contextlib import contextmanager
from pathlib import Path

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


def _grid(k, dim=2):
    """(k^dim, k^dim) sparse: the grid Laplacian of a k x ... x k grid plus the identity."""
    import scipy.sparse as sp
    T = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(k, k))
    A = sp.csc_matrix((1, 1))
    for _ in range(dim):
        A = sp.kron(A, sp.eye(k)) + sp.kron(sp.eye(A.shape[0]), T) if A.shape[0] > 1 else T
    return (A + sp.eye(k ** dim)).tocsc()


class _RecordingBLAS:
    """The BLAS routines the LDLᵀ extension calls, wrapped to record each call's sizes:
    gemm's m·n·k, trsm's and trmm's min(m, n) (real routines; the complex ones untouched)."""

    def __init__(self):
        import ctypes
        from spectral_igl.linalg import ldlt
        self.ext, self.real = ldlt._ext(), ldlt._blas_addresses()
        i, d, c, v = ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_double), ctypes.c_char_p, ctypes.c_void_p
        gemm_t = ctypes.CFUNCTYPE(None, c, c, i, i, i, d, v, i, v, i, d, v, i)
        trxm_t = ctypes.CFUNCTYPE(None, c, c, c, c, i, i, d, v, i, v, i)
        self.gemm, self.trxm = [], []
        real = dict(zip(("dgemm", "zgemm", "dtrsm", "ztrsm", "dtrmm", "ztrmm"), self.real))

        def gemm(*a, _f=gemm_t(real["dgemm"])):
            self.gemm.append(float(a[2][0]) * a[3][0] * a[4][0])
            _f(*a)

        def trxm(*a, _f=None):
            self.trxm.append(min(a[4][0], a[5][0]))
            _f(*a)

        self._keep = [gemm_t(gemm), trxm_t(functools.partial(trxm, _f=trxm_t(real["dtrsm"]))),
                      trxm_t(functools.partial(trxm, _f=trxm_t(real["dtrmm"])))]
        addr = [ctypes.cast(f, ctypes.c_void_p).value for f in self._keep]
        self.ext.set_blas(addr[0], real["zgemm"], addr[1], real["ztrsm"], addr[2], real["ztrmm"])

    def largest(self):
        out = (max(self.gemm, default=0.0), max(self.trxm, default=0))
        self.gemm.clear()
        self.trxm.clear()
        return out

    def restore(self):
        self.ext.set_blas(*self.real)


def _other_threads_cpu():
    """CPU clock ticks spent so far by this process's threads other than the calling one."""
    import os
    import threading
    me = threading.get_native_id()
    total = 0
    for tid in os.listdir("/proc/self/task"):
        if int(tid) != me:
            try:
                with open(f"/proc/self/task/{tid}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:         # the thread ended meanwhile
                continue
            total += int(fields[11]) + int(fields[12])     # utime, stime
    return total


@pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="needs Linux's /proc")
def test_gemms_the_rule_calls_serial_wake_no_blas_thread():
    """Against the BLAS itself: with two BLAS threads allowed, gemms of SERIAL_GEMM
    multiply-adds, square and thin, leave the BLAS's worker thread idle, while a gemm of 64
    times as much work wakes it (so the measure sees threads)."""
    if threads.may_thread():
        pytest.skip("scipy's BLAS is not OpenBLAS: the rule enters every section")
    import time

    from scipy.linalg import blas
    rng = np.random.default_rng(0)
    shapes = [(64, 64, 64), (1, 512, 512), (512, 512, 1), (8, 256, 128), (1, 4096, 64), (2, 128, 1024)]
    pairs = [(np.asfortranarray(rng.standard_normal((m, k))), np.asfortranarray(rng.standard_normal((k, n))))
             for m, n, k in shapes]
    assert {m * n * k for m, n, k in shapes} == {threads.SERIAL_GEMM}
    big = np.asfortranarray(rng.standard_normal((256, 256)))

    def ticks(fn, reps):
        before = _other_threads_cpu()
        for _ in range(reps):
            fn()
        return _other_threads_cpu() - before

    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        if not _blas_threads() or set(_blas_threads().values()) != {2}:
            pytest.skip("the BLAS's threads cannot be set to 2")
        time.sleep(0.2)                   # the worker threads' start-up is not a call's
        quiet = sum(ticks(lambda a=a, b=b: blas.dgemm(1.0, a, b), 300) for a, b in pairs)
        busy = ticks(lambda: blas.dgemm(1.0, big, big), 40)
    assert quiet == 0
    assert busy > 0


@pytest.mark.skipif(not available(), reason="LDLT extension not built")
@pytest.mark.parametrize("min_work", [None, 1000.0])
def test_largest_blas_is_the_largest_call_made(min_work):
    """The sizes the thread rule is decided on are those of the BLAS calls the factorization,
    the solves and the selected inversion then make, on fronts below and above the BLAS's
    thread thresholds (every front to the BLAS with a small ``min_work``)."""
    from spectral_igl.linalg import ldlt
    A = _grid(45)                            # 2,025 unknowns, separators of 45 and more
    rec = _RecordingBLAS()
    old = rec.ext.set_blas_min_work(0.0)
    rec.ext.set_blas_min_work(old if min_work is None else min_work)
    try:
        fac = LDLT(A, ldlt.Pattern(A, ordering="minimum_degree"))
        sym = fac.pattern.symbolic
        assert rec.largest() == sym.largest_blas("factor") != (0.0, 0)
        rng = np.random.default_rng(0)
        for k in (1, 3, 8, 40):
            x = fac.solve(rng.standard_normal((A.shape[0], k)))
            assert rec.largest() == sym.largest_blas("solve", k)
            assert np.abs(A @ x).max() < 1e3      # a solve, not only a call
        cols = fac.inverse_columns(rng.choice(A.shape[0], 9, replace=False))
        gemm, trxm = rec.largest()
        assert cols.shape == (A.shape[0], 9)
        assert gemm <= sym.largest_blas("solve", 9)[0] and trxm <= sym.largest_blas("solve", 9)[1]
        fac.inverse_diagonal()
        assert rec.largest() == sym.largest_blas("inverse")
    finally:
        rec.ext.set_blas_min_work(old)
        rec.restore()
    with pytest.raises(ValueError, match="op must be"):
        sym.largest_blas("solves")


@pytest.mark.skipif(not available(), reason="LDLT extension not built")
def test_small_factorization_changes_no_threads(monkeypatch):
    """Under OpenBLAS a factorization and solves whose BLAS calls all run on one thread enter
    no section: no thread count is read or set, and the loaded libraries are never searched."""
    if threads.may_thread():
        pytest.skip("scipy's BLAS is not OpenBLAS: every section is entered")
    searched = []
    monkeypatch.setattr(threads, "_controller", [])
    monkeypatch.setattr(threads, "ThreadpoolController", lambda: searched.append(1))
    A = _grid(30)                                 # 900 unknowns: fronts of a few dozen
    fac = LDLT(A)
    assert not threads.may_thread(*fac.pattern.symbolic.largest_blas("factor"))
    x = fac.solve(np.ones(A.shape[0]))
    fac.solve(np.ones((A.shape[0], 4)))
    assert np.allclose(A @ x, 1.0)
    assert searched == []


@pytest.mark.skipif(not available(), reason="LDLT extension not built")
def test_large_factorization_runs_serial(monkeypatch):
    """A factorization with a gemm the BLAS would thread runs inside the limit, and the
    caller's thread count is back afterwards."""
    from spectral_igl.linalg import ldlt
    A = _grid(14, dim=3)                          # 2,744 unknowns: separators of 200 or so
    pattern = ldlt.Pattern(A, ordering="minimum_degree")
    assert threads.may_thread(*pattern.symbolic.largest_blas("factor"))
    seen = []
    orig = ldlt.blas_threads

    @contextmanager
    def watch(*args, **kwargs):
        with orig(*args, **kwargs):
            seen.append(_blas_threads())
            yield

    monkeypatch.setattr(ldlt, "blas_threads", watch)
    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        before = _blas_threads()
        if not before:
            pytest.skip("no BLAS that threadpoolctl can see")
        fac = LDLT(A, pattern)
        assert _blas_threads() == before
    assert seen and set(seen[0].values()) == {threads.MAX_BLAS_THREADS} == {1}
    assert np.allclose(A @ fac.solve(np.ones(A.shape[0])), 1.0)


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
