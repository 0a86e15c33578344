"""Kernel diagonals from eigenpairs: the dense ground truth and the truncated baseline."""
from __future__ import annotations

import numpy as np

from ..linalg import cached_eigs

__all__ = ["phi_values", "low_rank", "eigen_diagonal"]


def low_rank(lap, k: int | None, delta: str = "mass"):
    r"""(evals, W) with the rank-k kernel :math:`G_k = W \varphi(\Lambda_k) W^\top`: W = X
    (``delta="mass"``) or B X (``"seed"``), from eigenpairs cached on ``lap`` (all of them
    for ``k=None``)."""
    lam, X = cached_eigs(lap, k)
    W = X if delta == "mass" else np.asarray(lap.B @ X)
    return lam, W


def phi_values(filt, lam, c: int) -> np.ndarray:
    r""":math:`\varphi` at the eigenvalues ``lam``, with :math:`\varphi := 0` on the ``c`` kernel
    modes of a singular filter."""
    with np.errstate(all="ignore"):
        ph = np.array(filt(lam), dtype=np.complex128 if getattr(filt, "is_complex", False) else float)
    if filt.singular:
        ph[:c] = 0.0
    if not np.all(np.isfinite(ph)):
        bad = lam[~np.isfinite(ph)]
        raise ValueError(f"{filt!r} is not finite at {bad.size} eigenvalue(s) (e.g. {float(np.real(bad[0])):.3g}): "
                         "check its parameters (e.g. a time so large that t * lambda overflows)")
    return ph



def eigen_diagonal(lap, filt, k: int | None, delta: str = "mass") -> np.ndarray:
    """diag of the kernel from ``k`` eigenpairs (all of them for ``k=None``: the ground truth)."""
    lam, W = low_rank(lap, k, delta)
    return (W ** 2) @ phi_values(filt, lam, lap.n_components)
