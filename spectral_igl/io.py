"""Shapes and fields in files: triangle meshes (obj, off, ply, stl, wrl), tet meshes (.mesh),
and meshes with per-vertex fields (vtu, vtk, ply)."""
from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from ._extras import require
from ._validate import as_cells, as_mesh_arrays, as_points, as_signal, describe

__all__ = ["read_mesh", "write_mesh", "check_mesh_file"]

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
    IsADirectoryError
        ``path`` is a directory.
    ValueError
        The extension is not supported, or the file holds no valid mesh; a malformed file
        (see :func:`check_mesh_file`) is refused with its name and line.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a directory, not a mesh file")
    if not path.is_file():
        raise FileNotFoundError(f"no such mesh file: {path}")
    ext = path.suffix.lower()
    check_mesh_file(path)
    import igl

    if ext == ".mesh":
        try:
            V, T, _ = igl.readMESH(str(path))
        except (RuntimeError, MemoryError) as err:
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
    except (RuntimeError, MemoryError) as err:
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
    >>> from spectral_igl.data_generators import icosphere
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
        meshio = require("meshio", "io", f"writing {ext} files")

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
    # libigl's ASCII PLY keeps 6 significant digits (a shape at 1e5 moves by 1e-6 of its size);
    # binary PLY keeps every bit
    binary = igl.FileEncoding.Binary if ext == ".ply" else igl.FileEncoding.Ascii
    igl.write_triangle_mesh(str(path), V, F, encoding=binary)


# ---- structure checks before libigl's readers ---------------------------------------------
#: smallest bytes per vertex and per element in a text file ("0 0 0\n", "3 0 1 2\n")
_MIN_TEXT_BYTES = 6


def _fail(path, line_no, msg):
    where = f"{path}, line {line_no}" if line_no else str(path)
    ext = Path(path).suffix.lower()
    kind = "MEDIT .mesh" if ext == ".mesh" else ext[1:].upper()
    raise ValueError(f"{where}: not a valid {kind} file: {msg}")


def _text_lines(path):
    with open(path, "rb") as fh:
        for no, raw in enumerate(fh, 1):
            yield no, raw.decode("utf-8", errors="replace").strip()


def _check_obj(path):
    nv = 0
    for no, line in _text_lines(path):
        if line.startswith("v "):
            parts = line.split()
            if len(parts) < 4:
                _fail(path, no, f"vertex with {len(parts) - 1} coordinate(s), need 3: {line[:80]!r}")
            try:
                [float(x) for x in parts[1:4]]
            except ValueError:
                _fail(path, no, f"vertex coordinates are not numbers: {line[:80]!r}")
            nv += 1
        elif line.startswith("f "):
            refs = line.split()[1:]
            if len(refs) < 3:
                _fail(path, no, f"face with {len(refs)} vertex/vertices, need at least 3 "
                                f"(truncated line?): {line[:80]!r}")
            for r in refs:
                head = r.split("/", 1)[0]
                try:
                    i = int(head)
                except ValueError:
                    _fail(path, no, f"face vertex {r!r} is not an integer index: {line[:80]!r}")
                if i == 0 or i > nv or i < -nv:
                    _fail(path, no, f"face vertex index {i} is outside the {nv} vertices defined before "
                                    f"it (OBJ indices start at 1): {line[:80]!r}")


def _check_off(path):
    size = path.stat().st_size
    lines = ((no, line) for no, line in _text_lines(path) if line and not line.startswith("#"))
    no, head = next(lines, (1, ""))
    kw = head.split()[0] if head.split() else ""
    if not kw.endswith("OFF"):
        _fail(path, no, f"an OFF file starts with 'OFF', got {head[:80]!r}")
    rest = head.split()[1:]
    if not rest:
        no, counts_line = next(lines, (no + 1, ""))
        rest = counts_line.split()
    try:
        nv, nf = int(rest[0]), int(rest[1])
    except (ValueError, IndexError):
        _fail(path, no, f"the counts line must give the numbers of vertices and faces, got {' '.join(rest)[:80]!r}")
    if nv < 0 or nf < 0:
        _fail(path, no, f"negative vertex or face count ({nv}, {nf})")
    if (nv + nf) * _MIN_TEXT_BYTES > size:
        _fail(path, no, f"the header claims {nv} vertices and {nf} faces, more than a file of "
                        f"{size} bytes can hold")
    for _ in range(nv):
        item = next(lines, None)
        if item is None:
            _fail(path, 0, f"the file ends before its {nv} vertices")
        vno, line = item
        parts = line.split()
        try:
            [float(x) for x in parts[:3]]
        except ValueError:
            _fail(path, vno, f"vertex coordinates are not numbers: {line[:80]!r}")
        if len(parts) < 3:
            _fail(path, vno, f"vertex with {len(parts)} coordinate(s), need 3: {line[:80]!r}")
    for _ in range(nf):
        item = next(lines, None)
        if item is None:
            _fail(path, 0, f"the file ends before its {nf} faces")
        fno, line = item
        parts = line.split()
        try:
            k = int(parts[0])
            idx = [int(x) for x in parts[1:1 + k]]
        except (ValueError, IndexError):
            _fail(path, fno, f"a face line is 'k i1 ... ik' with integers, got {line[:80]!r}")
        if k < 3 or len(idx) < k:
            _fail(path, fno, f"face with {min(k, len(idx))} vertex/vertices, need at least 3 "
                             f"(truncated line?): {line[:80]!r}")
        if min(idx) < 0 or max(idx) >= nv:
            _fail(path, fno, f"face vertex index outside [0, {nv}): {line[:80]!r}")


def _check_ply(path):
    size = path.stat().st_size
    with open(path, "rb") as fh:
        head = fh.read(65536)
    if not head.startswith(b"ply"):
        _fail(path, 1, "a PLY file starts with 'ply'")
    for no, raw in enumerate(head.split(b"\n"), 1):
        parts = raw.decode("latin-1").split()
        if parts[:1] == ["element"] and len(parts) >= 3:
            try:
                count = int(parts[2])
            except ValueError:
                _fail(path, no, f"element count is not an integer: {' '.join(parts)!r}")
            if count < 0 or count > size:
                _fail(path, no, f"the header claims {count} {parts[1]} element(s), more than a file of "
                                f"{size} bytes can hold")
        if parts[:1] == ["end_header"]:
            return
    _fail(path, 0, "no end_header in the first 64 KiB")


def _check_stl(path):
    size = path.stat().st_size
    with open(path, "rb") as fh:
        head = fh.read(84)
    if head[:5].lower() == b"solid" and b"\0" not in head[:80]:
        return       # ASCII STL: libigl parses it line by line
    if size < 84:
        _fail(path, 0, f"a binary STL has an 84-byte header, the file has {size} bytes")
    count = int.from_bytes(head[80:84], "little")
    if 84 + 50 * count > size:
        _fail(path, 0, f"the header claims {count} triangles, more than a file of {size} bytes can hold")


def _check_medit(path):
    size = path.stat().st_size
    lines = ((no, line) for no, line in _text_lines(path) if line and not line.startswith("#"))
    for no, line in lines:
        if line.split()[0] in ("Vertices", "Tetrahedra", "Triangles"):
            key = line.split()[0]
            rest = line.split()[1:]
            if not rest:
                no, nxt = next(lines, (no + 1, ""))
                rest = nxt.split()
            try:
                count = int(rest[0])
            except (ValueError, IndexError):
                _fail(path, no, f"{key} must be followed by a count, got {' '.join(rest)[:80]!r}")
            if count < 0 or count * _MIN_TEXT_BYTES > size:
                _fail(path, no, f"{key} claims {count} entries, more than a file of {size} bytes can hold")


_CHECKS = {".obj": _check_obj, ".off": _check_off, ".ply": _check_ply, ".stl": _check_stl,
           ".mesh": _check_medit}


def check_mesh_file(path) -> None:
    """Check the structure of a mesh file before a C++ reader sees it.

    Headers that claim more elements than the file can hold, truncated or out-of-range
    face lines (OBJ, OFF) raise a ``ValueError`` naming the file and the line, instead of
    a silent drop or an allocation failure inside the reader.
    """
    path = Path(path)
    check = _CHECKS.get(path.suffix.lower())
    if check is not None:
        try:
            check(path)
        except OSError as err:
            raise ValueError(f"cannot read {path}: {err}") from err
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
