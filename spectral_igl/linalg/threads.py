"""How many threads the BLAS gets inside the package's own dense work.

The package's BLAS calls are small or medium: the dense fronts of the LDLᵀ factorization and
its selected inversion, the least-squares and SVD problems of the rational fits, the Lanczos
vectors. With OpenBLAS's default (one thread per core), such calls spin on every core, and
when another process keeps one core busy they wait for it: a heat column on a 43k-vertex
mesh took 21.9 s instead of 2.0 s with one core busy on a 2-core machine (one thread: the
same 2.0 s on a quiet machine). Those sections therefore run with at most
:data:`MAX_BLAS_THREADS` threads (through threadpoolctl); the limit is
lifted on leaving them, so the caller's own BLAS work keeps the caller's setting.
"""
from __future__ import annotations

import functools
import threading
from contextlib import contextmanager

from threadpoolctl import ThreadpoolController

__all__ = ["MAX_BLAS_THREADS", "blas_threads", "serial_blas"]

#: threads the BLAS may use inside the package's dense sections; ``None``: no limit (the
#: BLAS's own setting, e.g. OPENBLAS_NUM_THREADS)
MAX_BLAS_THREADS = 1

_controller = []
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


@contextmanager
def blas_threads(limit: int | None = None):
    """Context in which the BLAS uses at most ``limit`` threads (default
    :data:`MAX_BLAS_THREADS`; ``None`` there: no change).

    Cheap enough to wrap every solve: a nested section changes nothing, and an outer one only
    reads each library's thread count (a few microseconds) and sets those above the limit,
    restoring them on leaving.

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
    if limit is None or depth:
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
