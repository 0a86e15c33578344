"""How many threads the BLAS gets inside the package's own dense work.

The package's BLAS calls are small or medium: the dense fronts of the LDLᵀ factorization and
its selected inversion, the least-squares and SVD problems of the rational fits, the Lanczos
vectors. With OpenBLAS's default (one thread per core), such calls spin on every core, and
when another process keeps one core busy they wait for it: a heat column on a 43k-vertex
mesh took 21.9 s instead of 2.0 s with one core busy on a 2-core machine (one thread: the
same 2.0 s on a quiet machine). Those sections therefore run with at most
:data:`MAX_BLAS_THREADS` threads (through threadpoolctl); the limit is
lifted on leaving them, so the caller's own BLAS work keeps the caller's setting.

A section that knows its largest BLAS calls beforehand (``calls``: the sparse LDLᵀ reads
them from its symbolic analysis) is entered only when the BLAS could run one of them on more
than one thread. The rule is OpenBLAS's, the BLAS scipy's wheels bring: a gemm runs on the
calling thread alone while m·n·k ≤ 65536 · GEMM_MULTITHREAD_THRESHOLD (:data:`SERIAL_GEMM`,
the threshold's default 4; OpenBLAS's ``interface/gemm.c``; an OpenBLAS built with a smaller
threshold would thread calls the rule leaves alone). Every trsm and trmm counts as threaded:
OpenBLAS 0.3.30 (scipy 1.17's) threads a left trsm of 600 rows and one to seven columns,
which its source's thresholds (both sides from 8) say it runs alone; with two threads and
another process on one of two cores it took 0.33–11 ms instead of 0.07–0.14 ms (measured).
Under another BLAS behind scipy (per its build configuration) every section is entered.

A factorization, which calls only gemm, and solves whose blocks all stay below the
compiled code's BLAS cut-off thus change no thread count and never pay threadpoolctl's search
of the loaded libraries (5 ms, once per process: it resolves the path of every shared object,
a third of a cold heat-geodesic precompute on cow). Measured: the heat-geodesic factorizations
of cow, spot and homer (up to 6,000 vertices) make gemms of at most 0.07–0.15 M
multiply-adds and enter no section; fandisk's (6,475 vertices, 1.1 M) and larger ones enter one.
"""
from __future__ import annotations

import functools
import threading
from contextlib import contextmanager

from threadpoolctl import ThreadpoolController

__all__ = ["MAX_BLAS_THREADS", "SERIAL_GEMM", "blas_threads", "may_thread", "serial_blas"]

#: threads the BLAS may use inside the package's dense sections; ``None``: no limit (the
#: BLAS's own setting, e.g. OPENBLAS_NUM_THREADS)
MAX_BLAS_THREADS = 1

#: OpenBLAS runs a gemm of at most this many multiply-adds (m·n·k) on the calling thread
SERIAL_GEMM = 65536 * 4

_controller = []
_openblas = []
_state = threading.local()      # depth of nested sections in this thread


def _blas_libraries():
    """threadpoolctl's controllers of the BLAS libraries loaded (found once), possibly empty."""
    if not _controller:
        try:
            libs = [lib for lib in ThreadpoolController().lib_controllers if lib.user_api == "blas"]
        except Exception:          # pragma: no cover - unable to inspect the loaded libraries
            libs = []
        _controller.append(libs)
    return _controller[0]


def _scipy_uses_openblas() -> bool:
    """True when scipy was built against OpenBLAS (its build configuration says so)."""
    if not _openblas:
        try:
            import scipy

            name = scipy.show_config(mode="dicts")["Build Dependencies"]["blas"]["name"]
            _openblas.append("openblas" in str(name).lower())
        except Exception:          # pragma: no cover - no configuration to read: assume any BLAS
            _openblas.append(False)
    return _openblas[0]


def may_thread(gemm: float = 0.0, trxm: int = 0) -> bool:
    """Whether the BLAS behind scipy may run a call as large as these on several threads.

    Parameters
    ----------
    gemm : float
        The largest m·n·k of the gemm calls (0: none).
    trxm : int
        The largest smaller side min(m, n) of the trsm and trmm calls (0: none).

    Returns
    -------
    bool
        False only under OpenBLAS with ``gemm <= SERIAL_GEMM`` and no trsm or trmm.

    Examples
    --------
    >>> from spectral_igl.linalg.threads import may_thread
    >>> may_thread(gemm=1e9)
    True
    """
    return not (_scipy_uses_openblas() and gemm <= SERIAL_GEMM and trxm == 0)


@contextmanager
def blas_threads(limit: int | None = None, calls: tuple[float, int] | None = None):
    """Context in which the BLAS uses at most ``limit`` threads (default
    :data:`MAX_BLAS_THREADS`; ``None`` there: no change).

    Cheap enough to wrap every solve: a nested section changes nothing, and an outer one only
    reads each library's thread count (a few microseconds) and sets those above the limit,
    restoring them on leaving. With ``calls``, the (gemm, trxm) sizes of the largest BLAS
    calls the section makes through scipy's BLAS (see :func:`may_thread`), a section whose
    calls all run on one thread anyway changes nothing either.

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl.linalg.threads import blas_threads
    >>> with blas_threads(1):
    ...     x = np.linalg.lstsq(np.eye(3), np.ones(3), rcond=None)[0]
    >>> x.tolist()
    [1.0, 1.0, 1.0]
    """
    limit = MAX_BLAS_THREADS if limit is None else limit
    depth = getattr(_state, "depth", 0)
    if limit is None or depth or (calls is not None and not may_thread(*calls)):
        yield
        return
    limit = int(limit)
    changed = []
    for lib in _blas_libraries():
        old = lib.num_threads
        if old > limit:
            lib.set_num_threads(limit)
            changed.append((lib, old))
    _state.depth = 1
    try:
        yield
    finally:
        _state.depth = 0
        for lib, old in changed:
            lib.set_num_threads(old)


def serial_blas(fn):
    """Decorator: run ``fn`` inside :func:`blas_threads` (the default limit)."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with blas_threads():
            return fn(*args, **kwargs)
    return wrapper
