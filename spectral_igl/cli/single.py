"""Jobs on one shape from one source: ``kernel``, ``distance``, ``geodesic`` and ``view``."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..applications import geodesic_distance
from ..filters import FILTERS
from ..progress import progress_bar
from ..quantity import QUANTITIES, color_meaning, evaluate
from .arguments import engine_args, input_args, source_arg, time_args
from .errors import EXIT_OK, EXIT_USAGE, CLIError
from .inputs import build_laplacian, check_source, given_time, load_shape
from .outputs import OUTPUTS, bound_text, check_outputs, check_writable, range_text, say, write_values, wrote

__all__ = ["add_kernel", "add_distance", "add_geodesic", "add_view", "run_kernel_distance",
           "run_geodesic", "run_view"]


def add_kernel(sub):
    """The ``kernel`` job's arguments."""
    p = sub.add_parser("kernel", help="kernel column K(:, source) = phi(L) B^-1 e_source",
                       description="Kernel column K(:, i) = phi(B^-1 L) B^-1 e_i of a spectral "
                                   "filter phi, evaluated spectrum-free.")
    input_args(p)
    engine_args(p, "heat")


def add_distance(sub):
    """The ``distance`` job's arguments."""
    p = sub.add_parser("distance", help="spectral distance d(source, :) of a filter",
                       description="Spectral distance from a source vertex: "
                                   "d(i,j)^2 = ||phi(L~) B^-1 (e_i - e_j)||_B^2. biharmonic: "
                                   "phi^2 = s^-2; commute_time: phi^2 = s^-1; diffusion: "
                                   "phi^2 = exp(-t s).")
    input_args(p)
    engine_args(p, "biharmonic")


def add_geodesic(sub):
    """The ``geodesic`` job's arguments."""
    p = sub.add_parser("geodesic", help="geodesic distance from a source (heat method or Varadhan)",
                       description="Approximate geodesic distance from a source vertex.")
    input_args(p)
    source_arg(p, "source vertex (default 0)")
    p.add_argument("--method", default="heat", choices=("heat", "varadhan"),
                   help="heat method (Crane et al.) or Varadhan's formula (default heat)")
    time_args(p, "diffusion time (default: squared mean edge length)")


def add_view(sub):
    """The ``view`` job's arguments."""
    p = sub.add_parser("view", help="interactive viewer: click a vertex to see level sets",
                       description="Interactive viewer: press p over the surface to pick a vertex; "
                                   "slider for log10 t; keys f / m / k cycle filter, method, "
                                   "kernel/distance. With --screenshot it renders once off screen.")
    input_args(p, outputs=())
    engine_args(p, "biharmonic")
    p.add_argument("--quantity", default="distance", choices=QUANTITIES)
    p.add_argument("--screenshot", metavar="PNG", help="render off screen to this file and exit")


def run_kernel_distance(args):
    """A kernel column or one-to-all distance, with its bound."""
    check_outputs(args.out, OUTPUTS)
    prog = progress_bar(4, args.job, unit="step")
    prog.set_postfix_str("reading")
    V, C, name = load_shape(args)
    prog.update()
    prog.set_postfix_str("Laplacian")
    check_source(args.source, V, C)
    lap = build_laplacian(V, C, args)
    prog.update()
    prog.set_postfix_str(args.job)
    t, _ = given_time(lap, args.time, args.time_unit, 1e-2 if FILTERS[args.filter][1] else None)
    ev = evaluate(lap, args.job, args.source, args.filter, t, method=args.method, tol=args.tol,
                  order=args.order, diagonal=args.diagonal)
    prog.update()
    prog.set_postfix_str("writing")
    kind = color_meaning(args.job, args.filter)
    write_values(args.out, ev.values, V, C, args, sources=[args.source], kind=kind,
                 title=f"{ev.label} ({name})", names=[f"{args.filter}_{args.job}"])
    prog.update()
    prog.close()
    say(args, f"{ev.label} from vertex {args.source} on {name} ({lap.n} vertices): "
              f"{range_text(ev.values)}; "
              f"{bound_text(ev.abs_error, ev.bound_kind, f'method {ev.method}')}; "
              f"{ev.seconds:.3g} s" + wrote(args.out))
    return EXIT_OK


def run_geodesic(args):
    """A geodesic distance by the heat method or Varadhan's formula (not certified)."""
    check_outputs(args.out, OUTPUTS)
    V, C, name = load_shape(args)
    check_source(args.source, V, C)
    lap = build_laplacian(V, C, args)
    start = time.perf_counter()
    t, _ = given_time(lap, args.time, args.time_unit)
    d = np.asarray(geodesic_distance(lap, args.source, method=args.method, t=t))
    seconds = time.perf_counter() - start
    write_values(args.out, d, V, C, args, sources=[args.source], kind="distance",
                 title=f"geodesic distance ({args.method}) ({name})", names=["geodesic_distance"])
    say(args, f"geodesic distance ({args.method}) from vertex {args.source} on {name} "
              f"({lap.n} vertices): {range_text(d)}; "
              f"{bound_text(np.nan, None, 'an approximation of the smooth geodesic distance, not certified')}; "
              f"{seconds:.3g} s" + wrote(args.out))
    return EXIT_OK


def run_view(args):
    """The interactive viewer, or one off-screen picture with ``--screenshot``."""
    from ..viz import Viewer
    from ..viz import display_available

    if args.screenshot is None and not display_available():  # before any work
        raise CLIError("no display available for the interactive viewer: use "
                       "--screenshot FILE.png to render off screen", EXIT_USAGE)
    if args.screenshot is not None:
        if Path(args.screenshot).suffix.lower() != ".png":
            raise CLIError(f"--screenshot must be a .png file, got {args.screenshot!r}", EXIT_USAGE)
        check_writable(args.screenshot)
    V, C, name = load_shape(args)
    check_source(args.source, V, C)
    lap = build_laplacian(V, C, args)
    t, _ = given_time(lap, args.time, args.time_unit, 1e-2)
    off = args.screenshot is not None
    viewer = Viewer(lap, quantity=args.quantity, filter=args.filter, t=t, method=args.method,
                    source=args.source, tol=args.tol, off_screen=True if off else None,
                    diagonal=args.diagonal, camera=args.view, cmap=args.cmap)
    if off:
        viewer.screenshot(args.screenshot)
        viewer.close()
        say(args, viewer.status().splitlines()[0] + f"\nwrote {args.screenshot}")
        return EXIT_OK
    viewer.show()
    return EXIT_OK
