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
from contextlib import contextmanager

from threadpoolctl import ThreadpoolController

__all__ = ["MAX_BLAS_THREADS", "blas_threads", "serial_blas"]

#: threads the BLAS may use inside the package's dense sections; ``None``: no limit (the
#: BLAS's own setting, e.g. OPENBLAS_NUM_THREADS)
MAX_BLAS_THREADS = 1

_controller = []


def _get_controller():
    """A threadpoolctl controller of the BLAS libraries loaded (built once), or None."""
    if not _controller:
        try:
            _controller.append(ThreadpoolController())
        except Exception:          # pragma: no cover - unable to inspect the loaded libraries
            _controller.append(None)
    return _controller[0]


@contextmanager
def blas_threads(limit: int | None = None):
    """Context in which the BLAS uses at most ``limit`` threads (default
    :data:`MAX_BLAS_THREADS`; ``None`` there: no change).

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
    ctl = _get_controller() if limit is not None else None
    if ctl is None:
        yield
        return
    with ctl.limit(limits=int(limit), user_api="blas"):
        yield


def serial_blas(fn):
    """Decorator: run ``fn`` inside :func:`blas_threads` (the default limit)."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with blas_threads():
            return fn(*args, **kwargs)
    return wrapper
