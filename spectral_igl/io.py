"""Reading shapes from files: triangle meshes (obj, off, ply, stl, wrl) and tet meshes (.mesh)."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ._validate import as_cells, as_points

__all__ = ["read_mesh", "write_mesh"]

_TRI = (".obj", ".off", ".ply", ".stl", ".wrl")


def read_mesh(path):
    """Read a mesh file.

    Parameters
    ----------
    path : str or os.PathLike
        ``.obj``, ``.off``, ``.ply``, ``.stl``, ``.wrl`` (polygons are triangulated), or
        MEDIT ``.mesh`` (tetrahedra).

    Returns
    -------
    V : (n, 3) float
    F : (m, 3) int for surfaces, or T : (m, 4) int for ``.mesh`` files.

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ValueError
        The extension is not supported, or the file holds no valid mesh.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such mesh file: {path}")
    ext = path.suffix.lower()
    import igl

    if ext == ".mesh":
        try:
            V, T, _ = igl.readMESH(str(path))
        except RuntimeError as err:
            raise ValueError(f"could not read tetrahedral mesh {path}: {err}") from err
        if T.size == 0:
            raise ValueError(f"{path} holds no tetrahedra")
        V = as_points(V, f"vertices of {path.name}", dims=(3,))
        return V, as_cells(T, len(V), f"tetrahedra of {path.name}", sizes=(4,))
    if ext not in _TRI:
        raise ValueError(f"unsupported mesh format {ext!r} for {path}; expected one of "
                         f"{', '.join(_TRI + ('.mesh',))}")
    try:
        V, F = igl.read_triangle_mesh(str(path))
    except RuntimeError as err:
        raise ValueError(f"could not read mesh {path}: not a valid {ext[1:].upper()} file") from err
    if V.size == 0 or F.size == 0:
        raise ValueError(f"{path} holds no triangles")
    V = as_points(V, f"vertices of {path.name}", dims=(3,))
    return V, as_cells(F, len(V), f"faces of {path.name}", sizes=(3,))


def write_mesh(path, V, F) -> None:
    """Write a triangle mesh (obj/off/ply/stl) or a tet mesh (``.mesh``)."""
    import igl

    path = Path(path)
    V = as_points(V, "V", dims=(3,))
    F = as_cells(F, len(V), "F", sizes=(3, 4))
    if F.shape[1] == 4:
        if path.suffix.lower() != ".mesh":
            raise ValueError(f"tetrahedra can only be written to .mesh, got {path.suffix!r}")
        igl.writeMESH(str(path), V, F, np.zeros((0, 3), dtype=np.int64))
        return
    if path.suffix.lower() not in _TRI[:4]:
        raise ValueError(f"unsupported mesh format {path.suffix!r}; expected .obj, .off, .ply or .stl")
    igl.write_triangle_mesh(str(path), V, F)
