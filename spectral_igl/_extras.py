"""Optional dependencies: which extra installs each, and the one error a missing one gives.

The core (numpy, scipy, libigl, cholespy, tqdm) computes every kernel, distance and
descriptor. Clusters, tetrahedralization, file formats beyond libigl's, pictures, METIS
orderings and MKL PARDISO are extras, imported only by the function that needs them:

========  =====================================  ==========================================
extra     packages                               used by
========  =====================================  ==========================================
cluster   dask[distributed], zarr 3              :mod:`spectral_igl.collection`
tet       pytetwild                              :func:`spectral_igl.tetrahedralize`
io        meshio                                 ``.vtu``/``.vtk`` and PLY with fields
viz       pyvista, matplotlib                    :mod:`spectral_igl.viz`, pictures of the CLI
metis     pymetis                                nested-dissection orderings of the LDLᵀ
fast      pypardiso                              ``backend="pypardiso"``
all       every extra above
========  =====================================  ==========================================
"""
from __future__ import annotations

import importlib

__all__ = ["EXTRAS", "install_hint", "require"]

#: extra -> the importable modules it provides
EXTRAS = {
    "cluster": ("distributed", "dask", "zarr"),
    "tet": ("pytetwild",),
    "io": ("meshio",),
    "viz": ("pyvista", "matplotlib", "PIL"),
    "metis": ("pymetis",),
    "fast": ("pypardiso",),
}


def install_hint(extra: str) -> str:
    """The command that installs ``extra``: ``pip install "spectral-igl[extra]"``.

    Examples
    --------
    >>> install_hint("viz")
    'pip install "spectral-igl[viz]"'
    """
    if extra not in EXTRAS and extra != "all":
        raise ValueError(f"extra must be one of {sorted(EXTRAS)} or 'all', got {extra!r}")
    return f'pip install "spectral-igl[{extra}]"'


def require(module: str, extra: str, purpose: str):
    """Import ``module``, or raise an ImportError of one line naming the extra to install.

    Parameters
    ----------
    module : str
        Dotted name of the optional module.
    extra : str
        The extra of ``pyproject.toml`` that installs it (a key of :data:`EXTRAS`).
    purpose : str
        What needs it, the subject of the message (``"tetrahedralize"``).

    Returns
    -------
    module
        The imported module.

    Raises
    ------
    ImportError
        ``module`` is not installed: ``<purpose> needs <module>: pip install "spectral-igl[<extra>]"``.

    Examples
    --------
    >>> require("math", "io", "nothing").sqrt(4.0)
    2.0
    """
    hint = install_hint(extra)
    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise ImportError(f"{purpose} needs {module.split('.')[0]}: {hint}") from err
