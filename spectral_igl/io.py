"""Shapes and fields in files: triangle meshes (obj, off, ply, stl, wrl), tet meshes (.mesh),
and meshes with per-vertex fields (vtu, vtk, ply)."""
from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from ._validate import as_cells, as_mesh_arrays, as_points, as_signal, describe

__all__ = ["read_mesh", "write_mesh"]

_TRI = (".obj", ".off", ".ply", ".stl", ".wrl")


def read_mesh(path, polygons: bool = False):
    """Read a mesh file.

    Parameters
    ----------
    path : str or os.PathLike
        ``.obj``, ``.off``, ``.ply``, ``.stl``, ``.wrl`` (polygons are triangulated), or
        MEDIT ``.mesh`` (tetrahedra).
    polygons : bool
        ``.obj`` and ``.off`` only: keep the faces as they are in the file instead of
        triangulating them. Other formats are read as without it.

    Returns
    -------
    V : (n, 3) float
    F : (m, 3) int for surfaces, or T : (m, 4) int for ``.mesh`` files. With
        ``polygons=True``: an (m, k) int array when every face has k vertices, else a
        list of m int arrays (one per face, in file order); either goes to
        :func:`spectral_igl.laplacian.laplacian` (or ``polygon_laplacian``) as it is.

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
    if not isinstance(polygons, (bool, np.bool_)):
        raise TypeError(f"polygons must be a bool, got {type(polygons).__name__}")
    if polygons and ext in (".obj", ".off"):
        V, faces = (_read_obj_polygons if ext == ".obj" else _read_off_polygons)(path)
        if len(V) == 0 or len(faces) == 0:
            raise ValueError(f"{path} holds no faces")
        V = as_points(V, f"vertices of {path.name}", dims=(3,))
        sizes = {len(f) for f in faces}
        if min(sizes) < 3:
            raise ValueError(f"{path} has a face with fewer than 3 vertices")
        F = [np.asarray(f, dtype=np.int64) for f in faces]
        top = max(int(f.max()) for f in F)
        if min(int(f.min()) for f in F) < 0 or top >= len(V):
            raise ValueError(f"faces of {path.name} index vertices outside [0, {len(V)})")
        return V, (np.vstack(F) if len(sizes) == 1 else F)
    try:
        V, F = igl.read_triangle_mesh(str(path))
    except RuntimeError as err:
        raise ValueError(f"could not read mesh {path}: not a valid {ext[1:].upper()} file") from err
    if V.size == 0 or F.size == 0:
        raise ValueError(f"{path} holds no triangles")
    V = as_points(V, f"vertices of {path.name}", dims=(3,))
    return V, as_cells(F, len(V), f"faces of {path.name}", sizes=(3,))


_FIELD_FORMATS = (".vtu", ".vtk", ".ply")


def write_mesh(path, V, F=None, fields=None) -> None:
    """Write a mesh, with per-vertex fields as point data.

    Parameters
    ----------
    path : str or os.PathLike
        Format by extension. ``.vtu`` and ``.vtk`` (VTK, through meshio) hold triangles or
        tetrahedra and any number of fields; ``.ply`` holds triangles and fields (one
        vertex property per column); ``.obj``, ``.off``, ``.stl`` hold triangles only and
        ``.mesh`` (MEDIT) tetrahedra only, without fields.
    V : (n, 3) float, or a mesh object
        Vertex positions, or a pyvista/trimesh/meshio mesh with ``F`` omitted.
    F : (m, 3) or (m, 4) int, optional
        Triangles or tetrahedra.
    fields : dict of str to array_like, optional
        Per-vertex values, each ``(n,)`` or ``(n, k)``, real or complex (complex fields are
        written as ``name.real`` and ``name.imag``). In ``.ply`` the columns of an
        ``(n, k)`` field become ``name_0`` ... ``name_{k-1}``, and characters other than
        letters, digits, ``_``, ``.``, ``-``, ``+`` and ``=`` become ``_``; a field called
        ``x``, ``y`` or ``z`` is written as ``x_`` (and so on), since those name the
        coordinates.

    Raises
    ------
    ValueError
        An unsupported extension, tetrahedra for a surface format, fields for a format
        that cannot hold them, or a field whose length is not ``n``.
    TypeError
        ``fields`` is not a mapping of names to arrays.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np, meshio
    >>> from data_generators import icosphere
    >>> from spectral_igl.io import write_mesh
    >>> V, F = icosphere(1)
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "z.vtu"
    >>> write_mesh(path, V, F, fields={"height": V[:, 2]})
    >>> meshio.read(path).point_data["height"].shape
    (42,)
    """
    V, F = as_mesh_arrays(V, F)
    path = Path(path)
    V = as_points(V, "V", dims=(3,))
    F = as_cells(F, len(V), "F", sizes=(3, 4))
    ext = path.suffix.lower()
    point_data = _point_data(fields, len(V), ply=ext == ".ply")
    if ext in (".vtu", ".vtk") or (ext == ".ply" and point_data):
        if ext == ".ply" and F.shape[1] == 4:
            raise ValueError(f"tetrahedra cannot be written to .ply; use .vtu or .vtk for {path.name}")
        import meshio

        cell = "tetra" if F.shape[1] == 4 else "triangle"
        cells = F.astype(np.int32) if ext == ".ply" else F    # PLY indices are 32-bit
        mesh = meshio.Mesh(V, [(cell, cells)], point_data=point_data)
        meshio.write(str(path), mesh, binary=True) if ext == ".ply" else meshio.write(str(path), mesh)
        return
    if point_data:
        raise ValueError(f"{ext or 'a file without extension'} cannot hold fields; write them to "
                         f"{', '.join(_FIELD_FORMATS)}")
    import igl

    if F.shape[1] == 4:
        if ext != ".mesh":
            raise ValueError(f"tetrahedra can only be written to .mesh, .vtu or .vtk, got {path.suffix!r}")
        igl.writeMESH(str(path), V, F, np.zeros((0, 3), dtype=np.int64))
        return
    if ext not in _TRI[:4]:
        raise ValueError(f"unsupported mesh format {path.suffix!r}; expected .obj, .off, .ply, .stl, "
                         f".vtu or .vtk")
    igl.write_triangle_mesh(str(path), V, F)


def _read_obj_polygons(path: Path):
    """Vertices and faces (lists of 0-based indices) of an OBJ file, faces untouched."""
    V, faces = [], []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if line.startswith("v "):
                V.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                idx = [int(tok.split("/")[0]) for tok in line.split()[1:]]
                nv = len(V)  # negative indices count back from the vertices read so far
                faces.append([i - 1 if i > 0 else nv + i for i in idx])
    return np.asarray(V, dtype=np.float64).reshape(-1, 3), faces


def _read_off_polygons(path: Path):
    """Vertices and faces of an OFF file, faces untouched."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        toks = [ln.split("#")[0].split() for ln in fh]
    toks = [t for t in toks if t]
    try:
        head = toks[0]
        if head[0].upper().endswith("OFF"):
            head = head[1:] or toks[1]
            body = toks[2:] if not toks[0][1:] else toks[1:]
        else:
            body = toks[1:]
        nv, nf = int(head[0]), int(head[1])
        V = np.array([[float(x) for x in t[:3]] for t in body[:nv]], dtype=np.float64)
        faces = [[int(x) for x in t[1:1 + int(t[0])]] for t in body[nv:nv + nf]]
    except (IndexError, ValueError) as err:
        raise ValueError(f"could not read mesh {path}: not a valid OFF file") from err
    return V.reshape(-1, 3), faces


def _point_data(fields, n: int, ply: bool) -> dict:
    """Validated ``{name: (n,) or (n, k) float}`` for meshio."""
    if fields is None:
        return {}
    if not hasattr(fields, "items"):
        raise TypeError(f"fields must be a dict of name -> (n,) array, got {describe(fields)}")
    out = {}
    for name, value in fields.items():
        if not isinstance(name, str) or not name:
            raise TypeError(f"field names must be non-empty strings, got {name!r}")
        a = as_signal(value, n, f"field {name!r}")
        parts = [(name + ".real", a.real), (name + ".imag", a.imag)] if a.dtype.kind == "c" else [(name, a)]
        for nm, arr in parts:
            if ply:
                nm = re.sub(r"[^A-Za-z0-9_.+=-]", "_", nm)
                nm = nm + "_" if nm in ("x", "y", "z") else nm   # the coordinates' names
                cols = [arr] if arr.ndim == 1 else [arr[:, j] for j in range(arr.shape[1])]
                names = [nm] if arr.ndim == 1 else [f"{nm}_{j}" for j in range(arr.shape[1])]
                out.update({k: np.ascontiguousarray(c, dtype=np.float64) for k, c in zip(names, cols)})
            else:
                out[nm] = np.ascontiguousarray(arr, dtype=np.float64)
    return out
