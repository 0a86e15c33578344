"""Shapes and fields in files: triangle meshes (obj, off, ply, stl, wrl), tet meshes (.mesh),
and meshes with per-vertex fields (vtu, vtk, ply)."""
from __future__ import annotations

import contextlib
import os
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

from ._extras import require
from ._validate import as_cells, as_mesh_arrays, as_points, as_signal, describe

__all__ = ["read_mesh", "write_mesh", "check_mesh_file"]

_TRI = (".obj", ".off", ".ply", ".stl", ".wrl")


def read_mesh(path, polygons: bool = False):
    r"""Read a mesh file.

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

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.io import read_mesh, write_mesh
    >>> V, F = icosphere(1)
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "sphere.obj"
    >>> write_mesh(path, V, F)
    >>> V2, F2 = read_mesh(path)
    >>> V2.shape, F2.shape, bool(np.allclose(V2, V))
    ((42, 3), (80, 3), True)
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a directory, not a mesh file")
    if not path.is_file():
        raise FileNotFoundError(f"no such mesh file: {path}")
    ext = path.suffix.lower()
    if ext != ".off":             # an OFF file is checked as it is parsed, below
        check_mesh_file(path)
    import igl

    if ext == ".mesh":
        try:
            with _captured_stderr() as said:
                V, T, _ = igl.readMESH(str(path))
        except (RuntimeError, MemoryError) as err:
            raise ValueError(f"could not read tetrahedral mesh {path}: {err}{_said(said)}") from err
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
        V, faces = (_read_obj_polygons if ext == ".obj" else _parse_off)(path)
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
    if ext == ".off":        # libigl misreads comments inside an OFF file: parsed here
        V, faces = _parse_off(path)
        if len(V) == 0 or len(faces) == 0:
            raise ValueError(f"{path} holds no triangles")
        V = as_points(V, f"vertices of {path.name}", dims=(3,))
        return V, as_cells(_fan(faces), len(V), f"faces of {path.name}", sizes=(3,))
    try:
        with _captured_stderr() as said:
            V, F = igl.read_triangle_mesh(str(path))
    except (RuntimeError, MemoryError) as err:
        raise ValueError(f"could not read mesh {path}: not a valid {ext[1:].upper()} file"
                         f"{_said(said)}") from err
    if V.size == 0 or F.size == 0:
        raise ValueError(f"{path} holds no triangles")
    V = as_points(V, f"vertices of {path.name}", dims=(3,))
    return V, as_cells(F, len(V), f"faces of {path.name}", sizes=(3,))


@contextlib.contextmanager
def _captured_stderr():
    """Collect what C++ code writes to the process's stderr (file descriptor 2) meanwhile.

    libigl's readers print each line they do not understand (for a file of garbage, the
    garbage); the text is kept for the error message instead. Yields a list that holds the
    text once the block ends.
    """
    said = []
    try:
        saved = os.dup(2)
    except OSError:          # no stderr to redirect
        yield said
        return
    with tempfile.TemporaryFile() as tmp:
        sys.stderr.flush()
        os.dup2(tmp.fileno(), 2)
        try:
            yield said
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            said.append(tmp.read(4096).decode("utf-8", errors="replace"))


def _said(said) -> str:
    text = " ".join("".join(said).split())
    return f" (the reader said: {text[:300]!r})" if text else ""


_FIELD_FORMATS = (".vtu", ".vtk", ".ply")


def write_mesh(path, V, F=None, fields=None) -> None:
    r"""Write a mesh, with per-vertex fields as point data.

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

    Returns
    -------
    None

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


def _claimed_counts(path, no, tokens, size, bytes_each, not_counts, claims, negative=None):
    """The counts a header claims on line ``no`` (``tokens``, each an integer), refused when
    they are not integers (message ``not_counts``), below 0 (``negative(counts)``, default the
    same as the next), or more items than a file of ``size`` bytes can hold at ``bytes_each``
    bytes each (``claims(*counts)``, then "more than a file of ... bytes can hold")."""
    try:
        counts = [int(t) for t in tokens]
    except (ValueError, TypeError):
        _fail(path, no, not_counts)
    if negative is not None and min(counts) < 0:
        _fail(path, no, negative(counts))
    if min(counts) < 0 or sum(counts) * bytes_each > size:
        _fail(path, no, f"{claims(*counts)}, more than a file of {size} bytes can hold")
    return counts


def _text_lines(path):
    with open(path, "rb") as fh:
        for no, raw in enumerate(fh, 1):
            yield no, raw.decode("utf-8", errors="replace").strip()


def _check_text(path, kind: str) -> None:
    """Refuse binary data in a text format (a NUL byte or mostly undecodable bytes in the first
    64 KiB) before a reader echoes it."""
    with open(path, "rb") as fh:
        head = fh.read(65536)
    if b"\0" in head or head.decode("utf-8", errors="replace").count("\ufffd") > len(head) // 10:
        _fail(path, 0, f"it holds binary data, not {kind} text")


def _check_obj(path):
    _check_text(path, "OBJ")
    nv = nf = 0
    for no, line in _text_lines(path):
        toks = line.split()
        key = toks[0] if toks else ""
        if key == "v":
            if len(toks) < 4:
                _fail(path, no, f"vertex with {len(toks) - 1} coordinate(s), need 3: {line[:80]!r}")
            try:
                [float(x) for x in toks[1:4]]
            except ValueError:
                _fail(path, no, f"vertex coordinates are not numbers: {line[:80]!r}")
            nv += 1
        elif key == "f":
            refs = toks[1:]
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
            nf += 1
    if nv == 0 or nf == 0:
        _fail(path, 0, f"it has {nv} vertex ('v') and {nf} face ('f') lines")


def _off_lines(path):
    """``(line number, tokens)`` of the non-empty lines of an OFF file, comments (``#`` to the
    end of the line) removed."""
    for no, line in _text_lines(path):
        toks = line.split("#", 1)[0].split()
        if toks:
            yield no, toks


class _Tokens:
    """The tokens of an OFF file line by line, where an item may continue on the next lines
    (a face line wrapped over several lines; libigl reads these too)."""

    def __init__(self, path):
        self.path = path
        self.lines = _off_lines(path)
        self.no = 0

    def line(self, what):
        item = next(self.lines, None)
        if item is None:
            _fail(self.path, 0, f"the file ends before {what}")
        self.no = item[0]
        return list(item[1])

    def item(self, need, what):
        """At least ``need(tokens)`` tokens, starting on a new line; returns them and the
        number of the item's first line."""
        toks = self.line(what)
        first = self.no
        while len(toks) < need(toks):
            toks += self.line(what)
        return toks, first


def _parse_off(path):
    """Vertices (n, 3) and faces (lists of 0-based indices) of an ASCII OFF file, read by
    tokens: comments anywhere, the counts on the header line or after it, vertex and face
    lines wrapped over several lines, and trailing values (normals, colours, texture
    coordinates) after the ones needed. A malformed file is refused with its line."""
    _check_text(path, "OFF")
    size = path.stat().st_size
    tokens = _Tokens(path)
    head = tokens.line("its header")
    kw = head[0]
    if not kw.upper().endswith("OFF"):
        _fail(path, tokens.no, f"an OFF file starts with 'OFF', got {' '.join(head)[:80]!r}")
    prefix = kw[:-3]            # [ST][C][N][4][n]OFF: 4 and n change the vertices' dimension
    if "4" in prefix or prefix.endswith("n"):
        _fail(path, tokens.no, f"{kw!r} (4-D or n-D vertices) is not supported: vertices must have 3 coordinates")
    rest = head[1:]
    if rest[:1] == ["BINARY"]:
        _fail(path, tokens.no, "binary OFF is not supported; write it as ASCII OFF or PLY")
    no = tokens.no
    while len(rest) < 2:
        rest += tokens.line("its vertex and face counts")
        no = tokens.no
    nv, nf = _claimed_counts(
        path, no, rest[:2], size, _MIN_TEXT_BYTES,
        f"the counts line must give the numbers of vertices and faces, got {' '.join(rest)[:80]!r}",
        lambda nv, nf: f"the header claims {nv} vertices and {nf} faces",
        negative=lambda counts: f"negative vertex or face count ({counts[0]}, {counts[1]})")
    V = np.empty((nv, 3))
    for i in range(nv):
        toks, vno = tokens.item(lambda t: 3, f"its {nv} vertices")
        try:
            V[i] = [float(x) for x in toks[:3]]
        except ValueError:
            _fail(path, vno, f"vertex coordinates are not numbers: {' '.join(toks)[:80]!r}")
    faces = []
    for _ in range(nf):
        toks, fno = tokens.item(lambda t: 1 + max(_face_size(t[0]), 0), f"its {nf} faces")
        k = _face_size(toks[0])
        if k < 0:
            _fail(path, fno, f"a face is 'k i1 ... ik' with integers, got {' '.join(toks)[:80]!r}")
        if k < 3:
            _fail(path, fno, f"face with {k} vertex/vertices, need at least 3: {' '.join(toks)[:80]!r}")
        try:
            idx = [int(x) for x in toks[1:1 + k]]
        except ValueError:
            _fail(path, fno, f"a face is 'k i1 ... ik' with integers, got {' '.join(toks)[:80]!r}")
        if min(idx) < 0 or max(idx) >= nv:
            _fail(path, fno, f"face vertex index outside [0, {nv}): {' '.join(toks)[:80]!r}")
        faces.append(idx)
    return V, faces


def _face_size(tok) -> int:
    """The vertex count that starts a face, -1 when it is not an integer."""
    try:
        return int(tok)
    except ValueError:
        return -1


def _fan(faces) -> np.ndarray:
    """Triangles of polygons (lists of indices) by fans from each polygon's first vertex, as
    libigl triangulates them."""
    tris = [(f[0], f[j], f[j + 1]) for f in faces for j in range(1, len(f) - 1)]
    return np.asarray(tris, dtype=np.int64).reshape(-1, 3)


def _check_off(path):
    _parse_off(path)


def _check_ply(path):
    size = path.stat().st_size
    with open(path, "rb") as fh:
        head = fh.read(65536)
    if not head.startswith(b"ply"):
        _fail(path, 1, "a PLY file starts with 'ply'")
    for no, raw in enumerate(head.split(b"\n"), 1):
        parts = raw.decode("latin-1").split()
        if parts[:1] == ["element"] and len(parts) >= 3:
            _claimed_counts(path, no, parts[2:3], size, 1,
                            f"element count is not an integer: {' '.join(parts)!r}",
                            lambda count: f"the header claims {count} {parts[1]} element(s)")
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
    _check_text(path, "MEDIT")
    size = path.stat().st_size
    lines = ((no, line) for no, line in _text_lines(path) if line and not line.startswith("#"))
    for no, line in lines:
        if line.split()[0] in ("Vertices", "Tetrahedra", "Triangles"):
            key = line.split()[0]
            rest = line.split()[1:]
            if not rest:
                no, nxt = next(lines, (no + 1, ""))
                rest = nxt.split()
            _claimed_counts(path, no, rest[:1] or [None], size, _MIN_TEXT_BYTES,
                            f"{key} must be followed by a count, got {' '.join(rest)[:80]!r}",
                            lambda count: f"{key} claims {count} entries")


_CHECKS = {".obj": _check_obj, ".off": _check_off, ".ply": _check_ply, ".stl": _check_stl,
           ".mesh": _check_medit}


def check_mesh_file(path) -> None:
    r"""Check the structure of a mesh file before a C++ reader sees it.

    Headers that claim more elements than the file can hold, truncated or out-of-range
    face lines (OBJ, OFF), binary data in a text format, and an OBJ file without vertex or
    face lines raise a ``ValueError`` naming the file and the line, instead of a silent
    drop, an echo of the bytes or an allocation failure inside the reader; so do a
    directory, a missing file and an unsupported extension.

    Parameters
    ----------
    path : str or os.PathLike
        A file with one of the extensions :func:`read_mesh` reads.

    Returns
    -------
    None
        The file passed the checks.

    Raises
    ------
    ValueError
        A malformed file (naming it and the line), a directory or an unsupported extension.
    FileNotFoundError
        The file does not exist.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from spectral_igl.io import check_mesh_file
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "bad.off"
    >>> _ = path.write_text("OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n")
    >>> check_mesh_file(path)
    Traceback (most recent call last):
    ...
    ValueError: ...
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{path} is a directory, not a mesh file")
    if not path.is_file():
        raise ValueError(f"no such mesh file: {path}")
    check = _CHECKS.get(path.suffix.lower())
    if check is None and path.suffix.lower() not in _TRI:
        raise ValueError(f"unsupported mesh format {path.suffix.lower()!r} for {path}; expected one of "
                         f"{', '.join(_TRI + ('.mesh',))}")
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
