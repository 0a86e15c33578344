"""Command line: ``spectral-igl <job> MESH [options]``.

Jobs: ``kernel``, ``distance``, ``hks``, ``smooth``, ``geodesic``, ``view``, ``figures``.
Meshes: ``.obj``, ``.off``, ``.ply``, ``.stl``, ``.wrl`` (triangles) and MEDIT ``.mesh``
(tetrahedra); or a generated shape with ``--shape``. Outputs by extension: ``.npy``,
``.csv`` (a header naming each column), ``.png``, and ``.vtu``/``.vtk``/``.ply``: the mesh
with the result as point data, one array per column (``--out`` may be repeated). A
progress bar is drawn on stderr unless ``--no-progress`` or ``--quiet`` is given.

Exit codes
----------
0 success; 1 the computation failed (including an invalid value met inside it); 2 bad
command line (unknown option, out-of-range vertex, unsupported output type); 3 the input
file is missing or unreadable, or no Laplacian can be built on it;
4 an optional dependency is missing (e.g. pictures need ``pip install "spectral_igl[viz]"``).

The package: ``command`` holds the parser and the entry point, ``arguments`` the argument
blocks the jobs share, ``inputs`` and ``outputs`` what the jobs read and write, and one
module per job family: ``single`` (kernel, distance, geodesic, view), ``hks``, ``smooth``,
``figures`` and ``batch``.
"""
from __future__ import annotations

from .command import build_parser, main
from .errors import EXIT_ERROR, EXIT_INPUT, EXIT_MISSING, EXIT_OK, EXIT_USAGE, CLIError
from .figures import examples_dir
from .outputs import bound_text, check_writable

__all__ = ["main", "build_parser", "check_writable", "bound_text", "examples_dir", "CLIError",
           "EXIT_OK", "EXIT_ERROR", "EXIT_USAGE", "EXIT_INPUT", "EXIT_MISSING"]
