"""The ``smooth`` job: diffusion smoothing of a signal or of the shape itself."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..applications import diffusion_smooth, optimal_shape_time, optimal_time
from ..io import write_mesh
from .arguments import input_args, method_arg, nonnegative, time_args, tol_arg, vertex_index
from .errors import EXIT_OK, EXIT_USAGE, CLIError
from .inputs import build_laplacian, given_time, load_shape, read_signal
from .outputs import FIELD_MESHES, OUTPUTS, bound_text, check_outputs, say, write_values, wrote

__all__ = ["add_smooth", "run_smooth"]

#: mesh files that carry no point data: only the smoothed shape itself is written to them
_PLAIN_MESHES = (".obj", ".off", ".stl")


def add_smooth(sub):
    """The ``smooth`` job's arguments."""
    p = sub.add_parser("smooth", help="diffusion smoothing of a signal or of the shape itself",
                       description="Diffusion smoothing f_t = exp(-t L~) f. The signal comes from "
                                   "--signal (.npy/.csv with one value per vertex, or n x d); "
                                   "without it the vertex coordinates are smoothed and the "
                                   "result may be written as a mesh (.obj .off .ply .stl).")
    input_args(p, outputs=OUTPUTS + (".obj", ".off", ".ply", ".stl"))
    p.add_argument("--signal", metavar="FILE", help="signal to smooth (.npy or .csv)")
    p.add_argument("--noise", type=nonnegative, default=0.0,
                   help="first add Gaussian noise of this standard deviation (relative to the "
                        "signal's range) -- for demonstrations")
    p.add_argument("--seed", type=vertex_index, default=0, help="seed of --noise")
    time_args(p, "diffusion time (default: for --signal, the minimum of the estimated "
                 "risk, optimal_time; for the shape itself, the same risk rule with the "
                 "noise measured along the normals, optimal_shape_time)")
    method_arg(p)
    tol_arg(p)


def _default_time(lap, f, C, geometry, args):
    """The diffusion time when ``-t`` is omitted: the minimum of the estimated risk."""
    if geometry and C.shape[1] == 3:
        # the risk rule with the shape's normal noise (the noisy operator hides it)
        return optimal_shape_time(lap)[0]
    if geometry:
        # tetrahedra: no normal noise to measure; the risk rule per coordinate (median)
        return float(np.median([optimal_time(lap, c)[0] for c in f.T]))
    cols = f.reshape(lap.n, -1).T     # per column (their median)
    return float(np.median([optimal_time(lap, c, method=args.method, tol=args.tol)[0] for c in cols]))


def _write_shape(outs, g, V, C, args, t):
    """The smoothed shape: as a mesh (with its displacement where fields fit), its
    coordinates as values, and pictures coloured by displacement."""
    mesh_types = _PLAIN_MESHES + FIELD_MESHES
    mesh_outs = [o for o in outs if Path(o).suffix.lower() in mesh_types]
    for o in mesh_outs:
        fields = {"displacement": np.linalg.norm(g - V, axis=1)} \
            if Path(o).suffix.lower() in FIELD_MESHES else None
        write_mesh(o, g, C, fields=fields)
    other = [o for o in outs if o not in mesh_outs]
    pics = [o for o in other if o.lower().endswith(".png")]
    write_values([o for o in other if o not in pics], g, V, C, args, names=["x", "y", "z"][:g.shape[1]])
    for o in pics:
        write_values([o], np.linalg.norm(g - V, axis=1), g, C, args, kind="distance",
                     title=f"smoothed, t={t:.3g} (colour: displacement)")


def run_smooth(args):
    """Smooth ``--signal`` (or the vertex coordinates) at ``-t`` or the risk rule's time."""
    check_outputs(args.out, OUTPUTS + _PLAIN_MESHES)
    geometry = args.signal is None
    if not geometry and any(Path(o).suffix.lower() in _PLAIN_MESHES for o in args.out):
        raise CLIError("a mesh can only be written to .obj, .off or .stl when smoothing the shape "
                       "itself (no --signal); write the smoothed signal with its mesh to .vtu, "
                       ".vtk or .ply", EXIT_USAGE)
    V, C, name = load_shape(args)
    f = read_signal(args.signal, len(V)) if not geometry else V.copy()
    if args.noise:
        rng = np.random.default_rng(args.seed)
        span = float(np.ptp(f)) or 1.0
        f = f + args.noise * span * rng.standard_normal(f.shape)
    if geometry:  # smoothing the shape itself: the operator is that of the (noisy) shape
        V = f.copy()
    lap = build_laplacian(V, C, args)
    t, _ = given_time(lap, args.time, args.time_unit)
    if t is None:
        t = _default_time(lap, f, C, geometry, args)
    start = time.perf_counter()
    g, info = diffusion_smooth(lap, f, t, method=args.method, tol=args.tol, return_info=True)
    g = np.asarray(g)
    seconds = time.perf_counter() - start
    if geometry:
        _write_shape(args.out, g, V, C, args, t)
    else:
        write_values(args.out, g, V, C, args, kind="auto", title=f"smoothed, t={t:.3g}",
                     names=["smoothed"] if g.ndim == 1 else [f"smoothed{j}" for j in range(g.shape[1])])
    bound = bound_text(info["abs_error"], info["bound_kind"], f"method {info['method']}")
    say(args, f"diffusion smoothing on {name} ({lap.n} vertices) at t={t:.4g}; {bound}; "
              f"{seconds:.3g} s" + wrote(args.out))
    return EXIT_OK
