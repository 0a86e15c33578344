"""The Schrödinger (wave) equation through the engine."""
from __future__ import annotations

from .._validate import as_choice, as_real_in, as_signal, as_tol, describe
from ..approx import METHODS, apply_filter
from ..filters import wave
from ..laplacian import as_laplacian

__all__ = ["schrodinger"]


def schrodinger(lap, h, t, method: str = "auto", tol: float = 1e-8):
    r"""Solution of the Schrödinger equation :math:`(i\Delta + \partial_t)H = 0`, :math:`H(0) = h`.

    .. math:: H(\cdot, t) = e^{-it\tilde L} h = \sum_i e^{-i\lambda_i t}\langle h, x_i\rangle_B\, x_i

    evaluated by the engine's wave filter (real and imaginary parts), no eigenpairs.

    Parameters
    ----------
    lap : Laplacian
    h : (n,) or (n, k) float or complex
        Initial condition.
    t : float
        Time (any real number; negative times run backwards).
    method, tol
        Passed to :func:`spectral_igl.apply_filter`.

    Returns
    -------
    (n,) or (n, k) complex
        The propagator is unitary in the B-inner product:
        :math:`\|H(t)\|_B = \|h\|_B` for every ``t``.

    Notes
    -----
    The survey's §5.2 (wave equation).

    Examples
    --------
    The propagator keeps the B-norm:

    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> lap = sig.laplacian(*icosphere(2))
    >>> h = lap.data["V"][:, 2]
    >>> H = sig.schrodinger(lap, h, 0.7)
    >>> bool(np.isclose(np.sqrt(np.real(np.conj(H) @ (lap.B @ H))), np.sqrt(h @ lap.B @ h)))
    True
    """
    import numbers

    import numpy as np
    lap = as_laplacian(lap)
    h = as_signal(h, lap.n, "h")
    if isinstance(t, bool) or not isinstance(t, numbers.Real):
        raise TypeError(f"t must be a real number, got {describe(t)}")
    t = as_real_in(t, "t")
    as_choice(method, "method", METHODS)     # checked here too: t = 0 returns before the engine
    as_tol(tol, "tol")
    if t == 0.0:
        return h.astype(complex)
    if t < 0:  # e^{+i|t|L} h is the conjugate of e^{-i|t|L} conj(h): L is real
        return np.conj(apply_filter(lap, wave(-t), np.conj(h), method=method, tol=tol))
    return apply_filter(lap, wave(t), h, method=method, tol=tol)
