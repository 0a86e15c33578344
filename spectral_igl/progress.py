"""Progress bars for long calls.

Every public call that can run for more than a few seconds takes ``progress=False``.
With ``progress=True`` it draws a `tqdm <https://tqdm.github.io>`_ bar on stderr whose
steps mean something: one per factorization or pole, per colour block, per source
block, per time, per candidate time, per shape. With ``progress=False`` (the default)
nothing is written. The default, ``progress=None``, means off unless the call runs
inside :func:`enabled` (the command line does this, so its bars reach every stage).
"""
from __future__ import annotations

import contextlib
import contextvars

import numpy as np

__all__ = ["progress_bar", "enabled", "NoProgress"]

_DEFAULT = contextvars.ContextVar("spectral_igl_progress", default=False)


@contextlib.contextmanager
def enabled(on: bool = True):
    r"""Within this context, calls given ``progress=None`` draw their bars (or not).

    Parameters
    ----------
    on : bool
        Whether ``progress=None`` means on inside the context.

    Yields
    ------
    None
        A context; the previous default comes back on leaving it.

    Examples
    --------
    >>> from spectral_igl import progress
    >>> with progress.enabled(False):
    ...     progress.progress_bar(3, "work").update()
    """
    if not isinstance(on, (bool, np.bool_)):
        raise TypeError(f"on must be True or False, got {type(on).__name__} {on!r}")
    token = _DEFAULT.set(bool(on))
    try:
        yield
    finally:
        _DEFAULT.reset(token)


class NoProgress:
    r"""A silent stand-in for a tqdm bar: every method does nothing.

    What :func:`progress_bar` returns when bars are off, so that callers update a bar without
    asking whether there is one.

    Examples
    --------
    >>> from spectral_igl import progress
    >>> bar = progress.progress_bar(10, "work", enable=False)
    >>> isinstance(bar, progress.NoProgress)
    True
    >>> with bar:
    ...     bar.update(3)
    >>> bar.n
    0
    """

    total = 0
    n = 0

    def update(self, n=1):
        """Do nothing (a tqdm bar would advance by ``n``)."""

    def set_postfix_str(self, s="", refresh=True):
        """Do nothing (a tqdm bar would show ``s`` after the counter)."""

    def set_description(self, desc=None, refresh=True):
        """Do nothing (a tqdm bar would change its label)."""

    def close(self):
        """Do nothing."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def __iter__(self):
        return iter(())


def progress_bar(total, desc: str = "", enable: bool | None = None, unit: str = "step", leave=None):
    """A tqdm progress bar on stderr, or a silent :class:`NoProgress` when not enabled.

    Parameters
    ----------
    total : int or None
        Number of steps (``None``: unknown, the bar counts without a percentage).
    desc : str
        Label shown before the bar.
    enable : bool or None
        ``False`` returns a :class:`NoProgress` that writes nothing; ``None`` follows
        :func:`enabled` (off by default).
    unit : str
        Name of one step (``"pole"``, ``"block"``, ``"time"``, ...).
    leave : bool, optional
        Keep the finished bar on screen. Default: keep it unless it is nested inside
        another open bar.

    Returns
    -------
    tqdm.tqdm or NoProgress
        Use as a context manager and call ``update()`` once per step.

    Raises
    ------
    TypeError
        ``enable`` is neither a bool nor None.

    Examples
    --------
    >>> from spectral_igl.progress import progress_bar
    >>> with progress_bar(3, "work", enable=False) as bar:
    ...     for _ in range(3):
    ...         bar.update()
    """
    if enable is None:
        enable = _DEFAULT.get()
    if not isinstance(enable, (bool, np.bool_)):
        raise TypeError(f"progress must be True, False or None, got {type(enable).__name__} {enable!r}")
    if not enable:
        return NoProgress()
    import sys

    from tqdm import tqdm

    if leave is None:
        leave = not any(not getattr(b, "disable", True) for b in list(getattr(tqdm, "_instances", ())))
    return tqdm(total=None if total is None else int(total), desc=desc, unit=unit, leave=leave,
                file=sys.stderr, dynamic_ncols=True, mininterval=0.2)

