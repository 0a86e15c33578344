"""What the jobs read: the shape (a mesh file or a generated one), the source vertex, the
Laplacian, a time given on the command line and a signal file."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .._validate import as_signal
from ..io import read_mesh
from ..laplacian import laplacian
from ..laplacian.units import shape_time, time_label
from .errors import EXIT_INPUT, EXIT_USAGE, CLIError

__all__ = ["load_shape", "check_source", "build_laplacian", "given_time", "read_signal"]


def load_shape(args):
    """(V, C, name) from the MESH argument or --shape."""
    if args.mesh is not None and getattr(args, "shape", None):
        raise CLIError("give either MESH or --shape, not both", EXIT_USAGE)
    if args.mesh is None and not getattr(args, "shape", None):
        raise CLIError("no input: give a MESH file or --shape sphere", EXIT_USAGE)
    if args.mesh is not None:

        try:
            V, C = read_mesh(args.mesh)
        except (FileNotFoundError, IsADirectoryError, PermissionError) as err:
            raise CLIError(str(err), EXIT_INPUT) from err
        except (ValueError, TypeError, RuntimeError, OSError, MemoryError) as err:
            raise CLIError(f"cannot read {args.mesh}: {err}", EXIT_INPUT) from err
        return V, C, Path(args.mesh).stem
    import spectral_igl.data_generators as dg

    level = int(args.level)
    if not 1 <= level <= 7:
        raise CLIError(f"--level must be between 1 and 7, got {level}", EXIT_USAGE)
    if args.shape == "sphere":
        V, F = dg.icosphere(level)
    elif args.shape == "box":
        k = 2 + 2 * level
        V, F = dg.box_tets((k, max(2, (3 * k) // 4), max(2, k // 2)))
    elif args.shape == "torus":
        V, F = dg.torus(1.0, 0.4, n_major=8 * 2 ** (level - 1) * 3 // 2, n_minor=3 * 2 ** (level - 1))
    else:  # cylinder
        V, F = dg.cylinder(1.0, 2.0, n_theta=8 * 2 ** (level - 1) * 3 // 2, n_z=3 * 2 ** (level - 1))
    return V, F, args.shape


def check_source(source, V, C):
    """Refuse, before any work, a source outside the mesh or one that no element references
    (an isolated vertex reaches nothing: there is nothing to compute or draw)."""
    if source >= len(V):
        raise CLIError(f"--source {source} is out of range: the mesh has {len(V)} vertices", EXIT_USAGE)
    if C is not None and not np.any(np.asarray(C) == source):
        lone = len(V) - np.unique(np.asarray(C)).size
        raise CLIError(f"--source {source} is a vertex that no element references ({lone} of the "
                       f"{len(V)} vertices are): nothing is reached from it; choose a vertex of the mesh",
                       EXIT_USAGE)


def build_laplacian(V, C, args):
    """The Laplacian of ``--weights`` and ``--mass``; a bad input file exits with EXIT_INPUT."""
    try:
        return laplacian(V, C, weights=args.weights, mass=args.mass)
    except ValueError as err:
        raise CLIError(f"cannot build the Laplacian: {err}", EXIT_INPUT) from err


def given_time(lap, t, unit, default=None, what="-t"):
    """``(absolute t, label)`` of a time given on the command line (``default``: a time in the
    shape's units used when ``-t`` is omitted, or None to leave the choice to the job)."""
    if t is None:
        if unit is not None:
            raise CLIError(f"--time-unit {unit} applies to {what}, which was not given", EXIT_USAGE)
        if default is None:
            return None, "t=default"
        t, unit = default, "shape"
    unit = unit or "absolute"
    try:
        value = shape_time(lap, t, unit)
    except ValueError as err:
        raise CLIError(str(err), EXIT_USAGE) from err
    return value, time_label(t, value, unit) if np.ndim(value) == 0 else f"{unit} units"


def read_signal(path, n):
    """The signal of ``--signal`` (.npy, or .csv with or without a header) on ``n`` vertices."""
    p = Path(path)
    if not p.is_file():
        raise CLIError(f"no such signal file: {path}", EXIT_INPUT)
    try:
        f = np.load(p) if p.suffix.lower() == ".npy" else np.loadtxt(p, delimiter=",", ndmin=1)
    except (ValueError, OSError) as err:
        try:
            f = np.loadtxt(p, delimiter=",", skiprows=1, ndmin=1)
        except (ValueError, OSError):
            raise CLIError(f"cannot read signal {path}: {err}", EXIT_INPUT) from err
    try:
        f = as_signal(f, n, f"signal {path}", allow_complex=False)
    except (ValueError, TypeError) as err:
        raise CLIError(f"signal {path} must hold {n} finite values (one per vertex) or an (n, d) "
                       f"array: {err}", EXIT_INPUT) from err
    return f
