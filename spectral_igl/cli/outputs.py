"""What the jobs write and print: output checks, values by file type, the summary line."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io import write_mesh
from .errors import EXIT_USAGE, CLIError

__all__ = ["OUTPUTS", "FIELD_MESHES", "check_outputs", "check_writable", "range_text",
           "column_names", "write_values", "say", "bound_text", "wrote"]

#: output types of a job's values, by extension
OUTPUTS = (".npy", ".csv", ".png", ".vtu", ".vtk", ".ply")
#: mesh files that carry the values as point data
FIELD_MESHES = (".vtu", ".vtk", ".ply")


def check_outputs(outs, allowed):
    """Refuse, before any work, an output of a type not in ``allowed`` or a path that cannot
    be written."""
    for out in outs:
        ext = Path(out).suffix.lower()
        if ext not in allowed:
            raise CLIError(f"cannot write {out!r}: output type must be one of {', '.join(allowed)}",
                           EXIT_USAGE)
        check_writable(out)


def check_writable(out):
    """Refuse an output path before any computation: its directory must exist and be
    writable (none is created), and the path must not be a directory."""
    path = Path(out)
    parent = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise CLIError(f"cannot write {out!r}: it is a directory", EXIT_USAGE)
    if not parent.exists():
        raise CLIError(f"cannot write {out!r}: the directory {str(parent)!r} does not exist "
                       "(create it first)", EXIT_USAGE)
    if not parent.is_dir():
        raise CLIError(f"cannot write {out!r}: {str(parent)!r} is not a directory", EXIT_USAGE)
    existed = path.exists()
    try:   # the one reliable test (permissions, read-only or pseudo file systems): open it
        with open(path, "ab" if existed else "xb"):
            pass
    except OSError as err:
        raise CLIError(f"cannot write {out!r}: {err.strerror or err}", EXIT_USAGE) from None
    if not existed:
        path.unlink()


def range_text(values):
    """``"min a, max b"`` over the finite values, and how many are not (unreachable components)."""
    v = np.asarray(values, dtype=float)
    ok = np.isfinite(v)
    if not ok.any():
        return "no finite value"
    text = f"min {v[ok].min():.6g}, max {v[ok].max():.6g}"
    if not ok.all():
        text += f" ({int((~ok).sum())} vertices infinite: no path from the source's component)"
    return text


def column_names(values, names=None):
    """Names of the columns of ``values`` (CSV header, fields of a mesh file)."""
    k = 1 if values.ndim == 1 else values.shape[1]
    if names is None:
        names = ["value"] if k == 1 else [f"value{j}" for j in range(k)]
    if len(names) != k:
        raise ValueError(f"{len(names)} column names for {k} column(s)")
    return list(names)


def write_values(outs, values, V, C, args, sources=None, kind="auto", title="", names=None):
    """Write ``values`` (one row per vertex) to each output, by extension.

    ``names`` name the columns: the CSV header, and the point-data arrays of a
    ``.vtu``/``.vtk``/``.ply`` mesh (one array per column).
    """
    names = column_names(values, names)
    for out in outs:
        path = Path(out)
        ext = path.suffix.lower()
        if ext == ".npy":
            np.save(path, values)
        elif ext == ".csv":
            header = ",".join(names)
            np.savetxt(path, values, delimiter=",", header=header, comments="", fmt="%.10g")
        elif ext == ".png":
            from ..viz import plot_levelsets

            f = values if values.ndim == 1 else values[:, values.shape[1] // 2]
            plot_levelsets((V, C), f, kind=kind, sources=sources, title=title, filename=path,
                           camera=getattr(args, "view", "auto"), cmap=getattr(args, "cmap", None))
        elif ext in FIELD_MESHES:
            cols = [values] if values.ndim == 1 else [values[:, j] for j in range(values.shape[1])]
            write_mesh(path, V, C, fields=dict(zip(names, cols)))
        else:

            write_mesh(path, values, C)


def say(args, text):
    """Print ``text`` unless ``--quiet``."""
    if not args.quiet:
        print(text)


def wrote(outs):
    """The ``wrote FILE`` lines that end a job's summary."""
    return "".join(f"\nwrote {o}" for o in outs)


def bound_text(abs_error, kind, why: str = "the method gives none") -> str:
    """How the command line reports a result's accuracy: the largest per-entry bound of
    ``abs_error`` and its kind (:mod:`spectral_igl.accuracy`), or that there is none and why.

    Examples
    --------
    >>> bound_text([1e-9, 3e-9], "proof")
    'error bound 3e-09 (proof, largest over the entries)'
    >>> bound_text([float("nan")], None, "the heat method is not certified")
    'error bound: none (the heat method is not certified)'
    """
    e = np.asarray(abs_error, dtype=float)
    if kind is None or e.size == 0 or not np.all(np.isfinite(e)):
        return f"error bound: none ({why})"
    return f"error bound {float(np.max(e)):.3g} ({kind}, largest over the entries)"
