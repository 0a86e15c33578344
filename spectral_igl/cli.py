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
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from ._version import __version__
from ._validate import as_signal
from .applications import diffusion_smooth, geodesic_distance, optimal_shape_time, optimal_time
from .approx import METHODS
from .descriptors import hks, hks_times
from .distances import MAX_ORDER
from .diagonal import METHODS as DIAGONAL_METHODS
from .filters import FILTERS
from .io import read_mesh, write_mesh
from .laplacian import laplacian
from .laplacian.units import TIME_UNITS, shape_time, time_label
from .progress import enabled as progress_enabled
from .progress import progress_bar
from .quantity import QUANTITIES, color_meaning, evaluate

__all__ = ["main", "check_writable", "bound_text", "EXIT_OK", "EXIT_ERROR", "EXIT_USAGE", "EXIT_INPUT", "EXIT_MISSING"]

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_INPUT, EXIT_MISSING = 0, 1, 2, 3, 4

_FILTERS = tuple(FILTERS)
_METHODS = METHODS
_OUTPUTS = (".npy", ".csv", ".png", ".vtu", ".vtk", ".ply")
_FIELD_MESHES = (".vtu", ".vtk", ".ply")
_SHAPES = ("sphere", "box", "torus", "cylinder")


class CLIError(Exception):
    """An error with the exit code it maps to."""

    def __init__(self, message, code=EXIT_ERROR):
        super().__init__(message)
        self.code = code


# ---- argument parsing -------------------------------------------------------------------
def _positive(text):
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not np.isfinite(x) or x <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return x


def _order(text):
    x = _positive_int(text)
    if x > MAX_ORDER:
        raise argparse.ArgumentTypeError(f"expected an order from 1 to {MAX_ORDER}, got {text!r}")
    return x


def _tolerance(text):
    x = _positive(text)
    if x >= 1:
        raise argparse.ArgumentTypeError(f"expected a relative tolerance in (0, 1), got {text!r}")
    return x


def _nonnegative(text):
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}") from None
    if not np.isfinite(x) or x < 0:
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return x


def _nonnegative_int(text):
    try:
        x = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a vertex index (integer >= 0), got {text!r}") from None
    if x < 0:
        raise argparse.ArgumentTypeError(f"expected a vertex index (integer >= 0), got {text!r}")
    return x


def _positive_int(text):
    try:
        x = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if x <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return x


def _input_args(p, outputs=_OUTPUTS):
    p.add_argument("mesh", nargs="?", metavar="MESH",
                   help="mesh file: .obj .off .ply .stl .wrl (triangles) or .mesh (tetrahedra)")
    p.add_argument("--shape", choices=_SHAPES,
                   help="use a generated shape instead of a file: sphere (unit icosphere), "
                        "torus (R = 1, r = 0.4), cylinder (open, radius 1, height 2), "
                        "box (tetrahedral box 1 x 0.75 x 0.5)")
    p.add_argument("--level", type=int, default=3,
                   help="resolution of the generated shape, 1 to 7 (sphere: icosphere "
                        "subdivisions, 642 vertices at 3; default 3)")
    p.add_argument("--weights", default="auto", choices=("auto", "cotan", "intrinsic_delaunay", "uniform"),
                   help="Laplacian weights (default auto: intrinsic Delaunay for triangles, cotan "
                        "for tets)")
    p.add_argument("--mass", default="lumped", choices=("lumped", "full", "barycentric"),
                   help="mass matrix (default lumped: with auto weights the heat stays non-negative)")
    p.add_argument("-o", "--out", action="append", default=[], metavar="FILE",
                   help=f"write the result; type by extension ({', '.join(outputs)}); repeatable")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="print nothing on success (and draw no progress bar)")
    _progress_arg(p)
    _picture_args(p)


def _progress_arg(p):
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=True,
                   help="progress bars on stderr, one step per factorization, pole, time or "
                        "figure (default: on)")


def _view(text):
    from .viz import parse_view

    try:
        parse_view(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    return text


def _picture_args(p):
    p.add_argument("--view", default="auto", type=_view, metavar="VIEW",
                   help="camera of pictures: auto (face the source from outside the shape), "
                        "iso, +x, -x, +y, -y, +z, -z, or a direction dx,dy,dz (default auto)")
    p.add_argument("--cmap", default=None, metavar="NAME",
                   help="colour map of pictures (a matplotlib name); default by meaning: "
                        "sequential for distances and non-negative values, diverging centred "
                        "at 0 for signed ones")


def _time_unit_arg(p, what="-t"):
    p.add_argument("--time-unit", default=None, choices=TIME_UNITS,
                   help=f"unit of {what}: absolute (as given; the default), shape (x the area of a "
                        "surface, x volume^(2/3) of a solid: the same meaning on a mesh of any size "
                        "or unit), area, volume, h2 (x the squared mean edge length)")


def _given_time(lap, t, unit, default=None, what="-t"):
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


def _engine_args(p, filter_default, t_help="time/scale t of the filter (default: 1e-2 x area of "
                                              "a surface, x volume^(2/3) of a solid)"):
    p.add_argument("-s", "--source", type=_nonnegative_int, default=0,
                   help="source vertex index (default 0)")
    p.add_argument("-f", "--filter", default=filter_default, choices=_FILTERS, metavar="FILTER",
                   help=f"spectral filter: {', '.join(_FILTERS)} (default {filter_default})")
    p.add_argument("-t", "--time", type=_positive, default=None, help=t_help)
    _time_unit_arg(p)
    p.add_argument("--order", type=_order, default=3,
                   help=f"order k of the polyharmonic filter, 1 to {MAX_ORDER} (default 3)")
    p.add_argument("--method", default="auto", choices=_METHODS, metavar="METHOD",
                   help=f"approximation method: {', '.join(_METHODS)} (default auto)")
    p.add_argument("--tol", type=_tolerance, default=1e-8, help="target accuracy, in (0, 1) (default 1e-8)")
    p.add_argument("--diagonal", default="auto", choices=DIAGONAL_METHODS,
                   help="distances: how the kernel diagonal is obtained (selinv: selected "
                        "inversion, certified; exact: one application per vertex; probing: "
                        "colouring estimator; default auto: selinv where it applies)")


def build_parser():
    """The ``argparse`` parser of ``spectral-igl``."""
    parser = argparse.ArgumentParser(
        prog="spectral-igl",
        description="Laplacian spectral kernels and distances on 3-D shapes, spectrum-free "
                    "with a certified error bound.",
        epilog="examples:\n"
               "  spectral-igl distance --shape sphere --source 0 --filter biharmonic --out d.png\n"
               "  spectral-igl kernel bunny.obj --source 10 --filter heat -t 1e-3 --out k.npy\n"
               "  spectral-igl hks spot.obj --out hks.csv\n"
               "  spectral-igl figures --quick --out figures/\n"
               "exit codes: 0 ok, 1 computation failed, 2 bad arguments, 3 bad input file, "
               "4 missing optional dependency",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="job", metavar="JOB")
    sub.required = True

    p = sub.add_parser("kernel", help="kernel column K(:, source) = phi(L) B^-1 e_source",
                       description="Kernel column K(:, i) = phi(B^-1 L) B^-1 e_i of a spectral "
                                   "filter phi, evaluated spectrum-free.")
    _input_args(p)
    _engine_args(p, "heat")

    p = sub.add_parser("distance", help="spectral distance d(source, :) of a filter",
                       description="Spectral distance from a source vertex: "
                                   "d(i,j)^2 = ||phi(L~) B^-1 (e_i - e_j)||_B^2. biharmonic: "
                                   "phi^2 = s^-2; commute_time: phi^2 = s^-1; diffusion: "
                                   "phi^2 = exp(-t s).")
    _input_args(p)
    _engine_args(p, "biharmonic")

    p = sub.add_parser("hks", help="heat kernel signature at several times",
                       description="Heat kernel signature HKS_t(i) = K_t(i, i) at several times t. "
                                   "Output (n, number of times); the picture shows the middle time.")
    _input_args(p)
    p.add_argument("--times", type=_positive, nargs="+", default=None,
                   help="times t (default: --count times from the shape's spectrum, spanning its "
                        "first 200 eigenvalues as Sun et al. 2009: the same grid relative to any "
                        "shape)")
    _time_unit_arg(p, "--times")
    p.add_argument("--count", type=_positive_int, default=5,
                   help="number of times of the default grid (default 5)")
    p.add_argument("--normalize", action=argparse.BooleanOptionalAction, default=True,
                   help="multiply by the area (volume) of the vertex's component: dimensionless, "
                        "comparable across shapes of any size (default on; --no-normalize gives "
                        "K_t(i, i) as is)")
    p.add_argument("--method", default="auto", choices=_METHODS, metavar="METHOD",
                   help=f"approximation method: {', '.join(_METHODS)} (default auto)")
    p.add_argument("--diagonal", default="auto", choices=DIAGONAL_METHODS,
                   help="how the diagonal K_t(i, i) is obtained: selinv (selected inversion, "
                        "certified), exact (one application per vertex), probing (colouring "
                        "estimator), dense; default auto (selinv)")
    p.add_argument("--tol", type=_tolerance, default=1e-8)

    p = sub.add_parser("smooth", help="diffusion smoothing of a signal or of the shape itself",
                       description="Diffusion smoothing f_t = exp(-t L~) f. The signal comes from "
                                   "--signal (.npy/.csv with one value per vertex, or n x d); "
                                   "without it the vertex coordinates are smoothed and the "
                                   "result may be written as a mesh (.obj .off .ply .stl).")
    _input_args(p, outputs=_OUTPUTS + (".obj", ".off", ".ply", ".stl"))
    p.add_argument("--signal", metavar="FILE", help="signal to smooth (.npy or .csv)")
    p.add_argument("--noise", type=_nonnegative, default=0.0,
                   help="first add Gaussian noise of this standard deviation (relative to the "
                        "signal's range) -- for demonstrations")
    p.add_argument("--seed", type=_nonnegative_int, default=0, help="seed of --noise")
    p.add_argument("-t", "--time", type=_positive, default=None,
                   help="diffusion time (default: for --signal, the minimum of the estimated "
                        "risk, optimal_time; for the shape itself, the same risk rule with the "
                        "noise measured along the normals, optimal_shape_time)")
    _time_unit_arg(p)
    p.add_argument("--method", default="auto", choices=_METHODS, metavar="METHOD",
                   help=f"approximation method: {', '.join(_METHODS)} (default auto)")
    p.add_argument("--tol", type=_tolerance, default=1e-8)

    p = sub.add_parser("geodesic", help="geodesic distance from a source (heat method or Varadhan)",
                       description="Approximate geodesic distance from a source vertex.")
    _input_args(p)
    p.add_argument("-s", "--source", type=_nonnegative_int, default=0, help="source vertex (default 0)")
    p.add_argument("--method", default="heat", choices=("heat", "varadhan"),
                   help="heat method (Crane et al.) or Varadhan's formula (default heat)")
    p.add_argument("-t", "--time", type=_positive, default=None,
                   help="diffusion time (default: squared mean edge length)")
    _time_unit_arg(p)

    p = sub.add_parser("view", help="interactive viewer: click a vertex to see level sets",
                       description="Interactive viewer: press p over the surface to pick a vertex; "
                                   "slider for log10 t; keys f / m / k cycle filter, method, "
                                   "kernel/distance. With --screenshot it renders once off screen.")
    _input_args(p, outputs=())
    _engine_args(p, "biharmonic")
    p.add_argument("--quantity", default="distance", choices=QUANTITIES)
    p.add_argument("--screenshot", metavar="PNG", help="render off screen to this file and exit")

    p = sub.add_parser("figures", help="run the example scripts that draw the survey's figures",
                       description="Run the scripts in examples/ (a source checkout) and write "
                                   "their PNGs to --out.")
    p.add_argument("-o", "--out", default="figures", help="output directory (default figures/)")
    p.add_argument("--quick", action="store_true", help="small shapes, fast (seconds per figure)")
    p.add_argument("--only", nargs="+", metavar="NAME", help="only these scripts (e.g. fig02 fig09)")
    p.add_argument("--list", action="store_true", help="list the scripts and exit")
    p.add_argument("--mesh", help="run the scripts on this mesh instead of generated shapes")
    p.add_argument("-q", "--quiet", action="store_true")
    _progress_arg(p)
    _batch_arguments(sub)
    return parser


# ---- inputs -----------------------------------------------------------------------------
def _load_shape(args):
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


def _check_outputs(outs, allowed):
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


def _check_source(source, V, C):
    """Refuse, before any work, a source outside the mesh or one that no element references
    (an isolated vertex reaches nothing: there is nothing to compute or draw)."""
    if source >= len(V):
        raise CLIError(f"--source {source} is out of range: the mesh has {len(V)} vertices", EXIT_USAGE)
    if C is not None and not np.any(np.asarray(C) == source):
        lone = len(V) - np.unique(np.asarray(C)).size
        raise CLIError(f"--source {source} is a vertex that no element references ({lone} of the "
                       f"{len(V)} vertices are): nothing is reached from it; choose a vertex of the mesh",
                       EXIT_USAGE)


def _laplacian(V, C, args):
    try:
        return laplacian(V, C, weights=args.weights, mass=args.mass)
    except ValueError as err:
        raise CLIError(f"cannot build the Laplacian: {err}", EXIT_INPUT) from err


def _range_text(values):
    """``"min a, max b"`` over the finite values, and how many are not (unreachable components)."""
    v = np.asarray(values, dtype=float)
    ok = np.isfinite(v)
    if not ok.any():
        return "no finite value"
    text = f"min {v[ok].min():.6g}, max {v[ok].max():.6g}"
    if not ok.all():
        text += f" ({int((~ok).sum())} vertices infinite: no path from the source's component)"
    return text


def _column_names(values, names=None):
    """Names of the columns of ``values`` (CSV header, fields of a mesh file)."""
    k = 1 if values.ndim == 1 else values.shape[1]
    if names is None:
        names = ["value"] if k == 1 else [f"value{j}" for j in range(k)]
    if len(names) != k:
        raise ValueError(f"{len(names)} column names for {k} column(s)")
    return list(names)


def _write(outs, values, V, C, args, sources=None, kind="auto", title="", names=None):
    """Write ``values`` (one row per vertex) to each output, by extension.

    ``names`` name the columns: the CSV header, and the point-data arrays of a
    ``.vtu``/``.vtk``/``.ply`` mesh (one array per column).
    """
    names = _column_names(values, names)
    for out in outs:
        path = Path(out)
        ext = path.suffix.lower()
        if ext == ".npy":
            np.save(path, values)
        elif ext == ".csv":
            header = ",".join(names)
            np.savetxt(path, values, delimiter=",", header=header, comments="", fmt="%.10g")
        elif ext == ".png":
            from .viz import plot_levelsets

            f = values if values.ndim == 1 else values[:, values.shape[1] // 2]
            plot_levelsets((V, C), f, kind=kind, sources=sources, title=title, filename=path,
                           camera=getattr(args, "view", "auto"), cmap=getattr(args, "cmap", None))
        elif ext in _FIELD_MESHES:
            cols = [values] if values.ndim == 1 else [values[:, j] for j in range(values.shape[1])]
            write_mesh(path, V, C, fields=dict(zip(names, cols)))
        else:

            write_mesh(path, values, C)


def _say(args, text):
    if not args.quiet:
        print(text)


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


# ---- jobs ---------------------------------------------------------------------------------
def _job_kernel_distance(args):
    _check_outputs(args.out, _OUTPUTS)
    prog = progress_bar(4, args.job, unit="step")
    prog.set_postfix_str("reading")
    V, C, name = _load_shape(args)
    prog.update()
    prog.set_postfix_str("Laplacian")
    _check_source(args.source, V, C)
    lap = _laplacian(V, C, args)
    prog.update()
    prog.set_postfix_str(args.job)
    t, _ = _given_time(lap, args.time, args.time_unit, 1e-2 if FILTERS[args.filter][1] else None)
    ev = evaluate(lap, args.job, args.source, args.filter, t, method=args.method, tol=args.tol,
                  order=args.order, diagonal=args.diagonal)
    prog.update()
    prog.set_postfix_str("writing")
    kind = color_meaning(args.job, args.filter)
    _write(args.out, ev.values, V, C, args, sources=[args.source], kind=kind,
           title=f"{ev.label} ({name})", names=[f"{args.filter}_{args.job}"])
    prog.update()
    prog.close()
    _say(args, f"{ev.label} from vertex {args.source} on {name} ({lap.n} vertices): "
               f"{_range_text(ev.values)}; "
               f"{bound_text(ev.abs_error, ev.bound_kind, f'method {ev.method}')}; "
               f"{ev.seconds:.3g} s" + "".join(f"\nwrote {o}" for o in args.out))
    return EXIT_OK


def _job_hks(args):
    _check_outputs(args.out, _OUTPUTS)
    V, C, name = _load_shape(args)
    lap = _laplacian(V, C, args)
    times, _ = _given_time(lap, args.times, args.time_unit, what="--times")
    if times is None:
        times = hks_times(lap, args.count)
    times = [float(t) for t in times]
    start = time.perf_counter()     # one bar step per time (progress=None: the CLI's setting)
    H, info = hks(lap, np.asarray(times, dtype=float), method=args.diagonal, engine_method=args.method,
                  tol=args.tol, return_info=True, normalize=args.normalize)
    H = np.asarray(H, dtype=float).reshape(lap.n, len(times))
    seconds = time.perf_counter() - start
    title = ("HKS x area" if args.normalize else "HKS") + f" t={times[len(times) // 2]:.3g} ({name})"
    _write(args.out, H, V, C, args, kind="sequential", title=title,
           names=[f"t={t:.4g}" for t in times])
    why = info.get("note", f"method {info['method']}")
    _say(args, f"hks at {len(times)} times on {name} ({lap.n} vertices); "
               f"{bound_text(info['abs_error'], info['bound_kind'], why)}; {seconds:.3g} s"
               + "".join(f"\nwrote {o}" for o in args.out))
    return EXIT_OK


def _read_signal(path, n):
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


def _job_smooth(args):
    plain_meshes = (".obj", ".off", ".stl")
    mesh_types = plain_meshes + _FIELD_MESHES
    _check_outputs(args.out, _OUTPUTS + plain_meshes)
    geometry = args.signal is None
    if not geometry and any(Path(o).suffix.lower() in plain_meshes for o in args.out):
        raise CLIError("a mesh can only be written to .obj, .off or .stl when smoothing the shape "
                       "itself (no --signal); write the smoothed signal with its mesh to .vtu, "
                       ".vtk or .ply", EXIT_USAGE)
    V, C, name = _load_shape(args)
    f = _read_signal(args.signal, len(V)) if not geometry else V.copy()
    if args.noise:
        rng = np.random.default_rng(args.seed)
        span = float(np.ptp(f)) or 1.0
        f = f + args.noise * span * rng.standard_normal(f.shape)
    if geometry:  # smoothing the shape itself: the operator is that of the (noisy) shape
        V = f.copy()
    lap = _laplacian(V, C, args)
    t, _ = _given_time(lap, args.time, args.time_unit)
    if t is None and geometry and C.shape[1] == 3:
        # the risk rule with the shape's normal noise (the noisy operator hides it)
        t = optimal_shape_time(lap)[0]
    elif t is None and geometry:
        # tetrahedra: no normal noise to measure; the risk rule per coordinate (median)
        t = float(np.median([optimal_time(lap, c)[0] for c in f.T]))
    elif t is None:  # the minimum of the estimated risk, per column (their median)
        cols = f.reshape(lap.n, -1).T
        t = float(np.median([optimal_time(lap, c, method=args.method, tol=args.tol)[0] for c in cols]))
    start = time.perf_counter()
    g, info = diffusion_smooth(lap, f, t, method=args.method, tol=args.tol, return_info=True)
    g = np.asarray(g)
    seconds = time.perf_counter() - start
    if geometry:
        mesh_outs = [o for o in args.out if Path(o).suffix.lower() in mesh_types]
        for o in mesh_outs:    # the smoothed shape (with its displacement where fields fit)
            fields = {"displacement": np.linalg.norm(g - V, axis=1)} \
                if Path(o).suffix.lower() in _FIELD_MESHES else None
            write_mesh(o, g, C, fields=fields)
        other = [o for o in args.out if o not in mesh_outs]
        pics = [o for o in other if o.lower().endswith(".png")]
        _write([o for o in other if o not in pics], g, V, C, args, names=["x", "y", "z"][:g.shape[1]])
        for o in pics:  # the smoothed shape, coloured by displacement
            _write([o], np.linalg.norm(g - V, axis=1), g, C, args, kind="distance",
                   title=f"smoothed, t={t:.3g} (colour: displacement)")
    else:
        _write(args.out, g, V, C, args, kind="auto", title=f"smoothed, t={t:.3g}",
               names=["smoothed"] if g.ndim == 1 else [f"smoothed{j}" for j in range(g.shape[1])])
    bound = bound_text(info["abs_error"], info["bound_kind"], f"method {info['method']}")
    _say(args, f"diffusion smoothing on {name} ({lap.n} vertices) at t={t:.4g}; {bound}; "
               f"{seconds:.3g} s" + "".join(f"\nwrote {o}" for o in args.out))
    return EXIT_OK


def _job_geodesic(args):
    _check_outputs(args.out, _OUTPUTS)
    V, C, name = _load_shape(args)
    _check_source(args.source, V, C)
    lap = _laplacian(V, C, args)
    start = time.perf_counter()
    t, _ = _given_time(lap, args.time, args.time_unit)
    d = np.asarray(geodesic_distance(lap, args.source, method=args.method, t=t))
    seconds = time.perf_counter() - start
    _write(args.out, d, V, C, args, sources=[args.source], kind="distance",
           title=f"geodesic distance ({args.method}) ({name})", names=["geodesic_distance"])
    _say(args, f"geodesic distance ({args.method}) from vertex {args.source} on {name} "
               f"({lap.n} vertices): {_range_text(d)}; "
               f"{bound_text(np.nan, None, 'an approximation of the smooth geodesic distance, not certified')}; "
               f"{seconds:.3g} s"
               + "".join(f"\nwrote {o}" for o in args.out))
    return EXIT_OK


def _job_view(args):
    from .viz import Viewer
    from .viz import display_available

    if args.screenshot is None and not display_available():  # before any work
        raise CLIError("no display available for the interactive viewer: use "
                       "--screenshot FILE.png to render off screen", EXIT_USAGE)
    if args.screenshot is not None:
        if Path(args.screenshot).suffix.lower() != ".png":
            raise CLIError(f"--screenshot must be a .png file, got {args.screenshot!r}", EXIT_USAGE)
        check_writable(args.screenshot)
    V, C, name = _load_shape(args)
    _check_source(args.source, V, C)
    lap = _laplacian(V, C, args)
    t, _ = _given_time(lap, args.time, args.time_unit, 1e-2)
    off = args.screenshot is not None
    viewer = Viewer(lap, quantity=args.quantity, filter=args.filter, t=t, method=args.method,
                    source=args.source, tol=args.tol, off_screen=True if off else None,
                    diagonal=args.diagonal, camera=args.view, cmap=args.cmap)
    if off:
        viewer.screenshot(args.screenshot)
        viewer.close()
        _say(args, viewer.status().splitlines()[0] + f"\nwrote {args.screenshot}")
        return EXIT_OK
    viewer.show()
    return EXIT_OK


def examples_dir():
    """The ``examples/`` directory of a source checkout, or None."""
    here = Path(__file__).resolve().parents[1] / "examples"
    env = os.environ.get("SPECTRAL_IGL_EXAMPLES")
    for d in ([Path(env)] if env else []) + [here, Path.cwd() / "examples"]:
        if (d / "_common.py").is_file():
            return d
    return None


def _job_figures(args):
    import importlib.util

    d = examples_dir()
    if d is None:
        raise CLIError("the example scripts were not found: run from a source checkout "
                       "(or set SPECTRAL_IGL_EXAMPLES to its examples/ directory)", EXIT_ERROR)
    scripts = sorted(p for p in d.glob("fig*.py"))
    names = [p.stem for p in scripts]
    if args.list:
        print("\n".join(names))
        return EXIT_OK
    if args.only:
        unknown = [n for n in args.only if not any(m == n or m.startswith(n + "_") for m in names)]
        if unknown:
            raise CLIError(f"unknown figure script(s) {', '.join(unknown)}; available: "
                           f"{', '.join(names)}", EXIT_USAGE)
        scripts = [p for p in scripts if any(p.stem == n or p.stem.startswith(n + "_") for n in args.only)]
    sys.path.insert(0, str(d))
    prog = progress_bar(len(scripts), "figures", unit="figure")
    failed = []
    for p in scripts:
        spec = importlib.util.spec_from_file_location(p.stem, p)
        mod = importlib.util.module_from_spec(spec)
        argv = ["--out", str(args.out)] + (["--quick"] if args.quick else [])
        argv += ["--mesh", args.mesh] if args.mesh else []
        try:
            spec.loader.exec_module(mod)
            mod.main(argv)  # prints its own summary
        except Exception as err:  # report and go on with the other figures
            failed.append(p.stem)
            print(f"{p.stem}: failed: {type(err).__name__}: {err}", file=sys.stderr)
        prog.set_postfix_str(p.stem)
        prog.update()
    prog.close()
    if failed:
        print(f"{len(failed)} of {len(scripts)} figure script(s) failed: {', '.join(failed)}",
              file=sys.stderr)
        return EXIT_ERROR
    _say(args, f"wrote the figures of {len(scripts)} script(s) to {args.out}")
    return EXIT_OK


_JOBS = {"kernel": _job_kernel_distance, "distance": _job_kernel_distance, "hks": _job_hks,
         "smooth": _job_smooth, "geodesic": _job_geodesic, "view": _job_view,
         "figures": _job_figures}


# ---- batch: many shapes on dask.distributed ---------------------------------------------
def _batch_arguments(sub):
    p = sub.add_parser("batch", help="run one job over many shapes (dask.distributed, Zarr store)",
                       description="Run one job over many shapes on dask.distributed and write "
                                   "one Zarr group per shape to STORE. A rerun skips shapes whose "
                                   "result is current; a failing shape is recorded and the others "
                                   "go on. Exit 1 if any shape failed.")
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="mesh files, globs (quote them: 'scans/*.ply') or directories")
    p.add_argument("--job", dest="batch_job", required=True,
                   choices=("hks", "wks", "diagonal", "distance", "eigenvalues"),
                   help="hks (--times), wks (--energies), kernel diagonal (--filter, -t), "
                        "one-to-all distance (--sources, --filter, -t), eigenvalues (-k)")
    p.add_argument("-o", "--out", required=True, metavar="STORE", help="Zarr store (a directory)")
    p.add_argument("--times", type=_positive, nargs="+",
                   help="hks: times t (default: --count times from each shape's own spectrum)")
    p.add_argument("--count", type=_positive_int, default=100,
                   help="hks: number of times of the default grid (default 100)")
    p.add_argument("--normalize", action=argparse.BooleanOptionalAction, default=True,
                   help="hks: multiply by the area (volume) of each vertex's component, so that "
                        "shapes of different sizes compare (default on)")
    p.add_argument("--energies", type=float, nargs="+",
                   help="wks: log-energies (default: 100 from each shape's own spectrum)")
    p.add_argument("--sigma", type=_positive, default=None, help="wks: band width")
    p.add_argument("-f", "--filter", default=None, metavar="FILTER",
                   choices=_FILTERS, help=f"diagonal, distance: {', '.join(_FILTERS)} "
                                          "(default heat for diagonal, biharmonic for distance)")
    p.add_argument("-t", "--time", type=_positive, default=None, help="time t of the filter")
    _time_unit_arg(p, "-t and --times")
    p.add_argument("--order", type=_positive_int, default=3, help="polyharmonic order (default 3)")
    p.add_argument("-s", "--sources", type=_nonnegative_int, nargs="+", help="distance: source vertices")
    p.add_argument("-k", type=_positive_int, default=None,
                   help="eigenvalues: how many (default 20); wks: eigenpairs (default 100)")
    p.add_argument("--method", default="auto", help="diagonal method (default auto; wks: eigen)")
    p.add_argument("--tol", type=_positive, default=1e-8)
    p.add_argument("--weights", default="auto", choices=("auto", "cotan", "intrinsic_delaunay", "uniform"))
    p.add_argument("--mass", default="lumped", choices=("lumped", "full", "barycentric"))
    p.add_argument("--workers", type=_positive_int, default=None,
                   help="local worker processes (default: one per core)")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run on this dask scheduler (tcp://host:8786) instead of a local cluster")
    p.add_argument("--memory-limit", default="auto",
                   help="per-worker memory limit of the local cluster (default auto)")
    p.add_argument("--retries", type=int, default=2, help="retries after a worker died (default 2)")
    p.add_argument("--force", action="store_true", help="recompute shapes with a current result")
    p.add_argument("--retry-failed", action="store_true",
                   help="rerun shapes whose input made them fail before (default: report them again)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar, summary only")


def _batch_job(args):
    from .collection import Job

    kind = args.batch_job
    unit = args.time_unit or "absolute"
    if kind == "hks":
        if not args.times and args.time_unit:
            raise CLIError(f"--time-unit {unit} applies to --times, which were not given", EXIT_USAGE)
        return Job.hks(args.times or None, method=args.method, tol=args.tol, time_unit=unit,
                       normalize=args.normalize, count=args.count)
    if kind in ("wks", "eigenvalues") and args.time_unit:
        raise CLIError(f"--time-unit applies to times; --job {kind} has none", EXIT_USAGE)
    if kind == "wks":
        return Job.wks(args.energies or None, sigma=args.sigma, k=args.k or 100,
                       method="eigen" if args.method == "auto" else args.method)
    if kind == "eigenvalues":
        return Job.eigenvalues(args.k or 20)
    filt = args.filter or ("heat" if kind == "diagonal" else "biharmonic")
    order = args.order if filt == "polyharmonic" else None
    timed = FILTERS[filt][1]
    t = args.time if timed else None
    if timed and t is None:
        raise CLIError(f"filter {filt} needs a time: give -t", EXIT_USAGE)
    if kind == "diagonal":
        return Job.kernel_diagonal(filt, t=t, order=order, method=args.method, tol=args.tol, time_unit=unit)
    if not args.sources:
        raise CLIError("--job distance needs --sources", EXIT_USAGE)
    return Job.distances(args.sources, filt, t=t, order=order, method=args.method, tol=args.tol,
                         time_unit=unit)


def _job_batch(args):
    try:
        from .collection import run
    except ImportError as err:
        raise ImportError(f"{err}; batch needs dask[distributed] and zarr") from err
    try:
        job = _batch_job(args)
    except ValueError as err:
        raise CLIError(str(err), EXIT_USAGE) from err
    try:
        from .collection import collect_inputs

        collect_inputs(list(args.inputs))
    except (ValueError, TypeError) as err:
        raise CLIError(str(err), EXIT_INPUT) from err
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise CLIError(f"cannot write the store {args.out!r}: it is a file, not a directory", EXIT_USAGE)
    from .collection.store import StoreInUse

    try:
        summary = run(list(args.inputs), job, args.out, workers=args.workers, scheduler=args.scheduler,
                      progress=not args.quiet, retries=args.retries, memory_limit=args.memory_limit,
                      weights=args.weights, mass=args.mass, force=args.force,
                      retry_failed=args.retry_failed)
    except StoreInUse as err:
        raise CLIError(str(err), EXIT_ERROR) from err
    print(f"done {len(summary.done)}, skipped {len(summary.skipped)}, failed {len(summary.failed)} "
          f"({summary.seconds:.1f} s, {summary.workers} workers); store {summary.out}")
    for name, err in sorted(summary.damaged.items()):
        print(f"damaged, recomputed: {name}: {err}", file=sys.stderr)
    for name, err in sorted(summary.failed.items()):
        print(f"failed: {name}: {err}", file=sys.stderr)
    return EXIT_OK if summary.ok else EXIT_ERROR


_JOBS["batch"] = _job_batch


def main(argv=None) -> int:
    """Run ``spectral-igl`` with ``argv`` (default ``sys.argv[1:]``); return the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors
        return int(exc.code) if isinstance(exc.code, int) else EXIT_USAGE
    try:
        with progress_enabled(bool(getattr(args, "progress", False)) and not getattr(args, "quiet", False)):
            return _JOBS[args.job](args)
    except CLIError as err:
        print(f"spectral-igl {args.job}: error: {err}", file=sys.stderr)
        return err.code
    except ImportError as err:
        print(f"spectral-igl {args.job}: error: {err}", file=sys.stderr)
        return EXIT_MISSING
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except Exception as err:  # the computation failed: say what, not a traceback
        print(f"spectral-igl {args.job}: failed: {type(err).__name__}: {err}", file=sys.stderr)
        return EXIT_ERROR


if __name__ == "__main__":
    sys.exit(main())
