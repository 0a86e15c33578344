"""Imported by the server that a local cluster's workers are forked from.

Everything a worker would otherwise import or set up in its first task is done here once,
in the fork server, and every worker forked from it starts with it: ``distributed``, this
package, libigl and the compiled LDLᵀ extension (loaded at the first factorization), and
threadpoolctl's scan of the BLAS libraries (:mod:`spectral_igl.linalg.threads`). Measured in
a fresh process: 0.4–0.6 s of CPU of imports, then 60–70 ms more on the first shape than on
the next ones.
"""
from __future__ import annotations

__all__ = ["warm"]


def warm() -> bool:
    """Import what a task needs and run one tiny heat kernel signature.

    Returns
    -------
    bool
        True when everything ran; False if something failed (a worker then pays the
        cost in its first task instead: nothing else changes).

    Examples
    --------
    >>> from spectral_igl.collection.preload import warm
    >>> warm()
    True
    """
    try:
        from ..data_generators import icosphere
        from ..descriptors import hks
        from ..laplacian import laplacian
        from ..linalg.threads import blas_threads

        with blas_threads(1):
            hks(laplacian(*icosphere(1)), [0.1])
        return True
    except Exception:  # noqa: BLE001 - never fail the fork server's start
        return False


warm()
