"""Progress bars for long calls.

Every public call that can run for more than a few seconds takes ``progress=False``.
With ``progress=True`` it draws a `tqdm <https://tqdm.github.io>`_ bar on stderr whose
steps mean something: one per factorization or pole, per colour block, per source
block, per time, per candidate time, per shape. With ``progress=False`` (the default)
nothing is written.
"""
from __future__ import annotations

__all__ = ["progress_bar", "NoProgress"]


class NoProgress:
    """A silent stand-in for a tqdm bar: every method does nothing."""

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


def progress_bar(total, desc: str = "", enable: bool = False, unit: str = "step", leave=None):
    """A tqdm progress bar on stderr, or a silent :class:`NoProgress` when not enabled.

    Parameters
    ----------
    total : int or None
        Number of steps (``None``: unknown, the bar counts without a percentage).
    desc : str
        Label shown before the bar.
    enable : bool
        ``False`` returns a :class:`NoProgress` that writes nothing.
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
        ``enable`` is not a bool.

    Examples
    --------
    >>> from spectral_igl.progress import progress_bar
    >>> with progress_bar(3, "work", enable=False) as bar:
    ...     for _ in range(3):
    ...         bar.update()
    """
    if not isinstance(enable, bool):
        raise TypeError(f"progress must be True or False, got {type(enable).__name__} {enable!r}")
    if not enable:
        return NoProgress()
    import sys

    from tqdm import tqdm

    if leave is None:
        leave = not any(not getattr(b, "disable", True) for b in list(getattr(tqdm, "_instances", ())))
    return tqdm(total=None if total is None else int(total), desc=desc, unit=unit, leave=leave,
                file=sys.stderr, dynamic_ncols=True, mininterval=0.2)
