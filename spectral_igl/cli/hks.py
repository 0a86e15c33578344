"""The ``hks`` job: heat kernel signatures at several times."""
from __future__ import annotations

import argparse
import time

import numpy as np

from ..descriptors import hks, hks_times
from .arguments import diagonal_arg, input_args, method_arg, positive, positive_int, time_unit_arg, tol_arg
from .errors import EXIT_OK
from .inputs import build_laplacian, given_time, load_shape
from .outputs import OUTPUTS, bound_text, check_outputs, say, write_values, wrote

__all__ = ["add_hks", "run_hks"]


def add_hks(sub):
    """The ``hks`` job's arguments."""
    p = sub.add_parser("hks", help="heat kernel signature at several times",
                       description="Heat kernel signature HKS_t(i) = K_t(i, i) at several times t. "
                                   "Output (n, number of times); the picture shows the middle time.")
    input_args(p)
    p.add_argument("--times", type=positive, nargs="+", default=None,
                   help="times t (default: --count times from the shape's spectrum, spanning its "
                        "first 200 eigenvalues as Sun et al. 2009: the same grid relative to any "
                        "shape)")
    time_unit_arg(p, "--times")
    p.add_argument("--count", type=positive_int, default=5,
                   help="number of times of the default grid (default 5)")
    p.add_argument("--normalize", action=argparse.BooleanOptionalAction, default=True,
                   help="multiply by the area (volume) of the vertex's component: dimensionless, "
                        "comparable across shapes of any size (default on; --no-normalize gives "
                        "K_t(i, i) as is)")
    method_arg(p)
    diagonal_arg(p, "how the diagonal K_t(i, i) is obtained: selinv (selected inversion, "
                    "certified), exact (one application per vertex), probing (colouring "
                    "estimator), dense; default auto (selinv)")
    tol_arg(p)


def run_hks(args):
    """The signature at ``--times`` (default: ``--count`` times from the spectrum)."""
    check_outputs(args.out, OUTPUTS)
    V, C, name = load_shape(args)
    lap = build_laplacian(V, C, args)
    times, _ = given_time(lap, args.times, args.time_unit, what="--times")
    if times is None:
        times = hks_times(lap, args.count)
    times = [float(t) for t in times]
    start = time.perf_counter()     # one bar step per time (progress=None: the CLI's setting)
    H, info = hks(lap, np.asarray(times, dtype=float), method=args.diagonal, engine_method=args.method,
                  tol=args.tol, return_info=True, normalize=args.normalize)
    H = np.asarray(H, dtype=float).reshape(lap.n, len(times))
    seconds = time.perf_counter() - start
    title = ("HKS x area" if args.normalize else "HKS") + f" t={times[len(times) // 2]:.3g} ({name})"
    write_values(args.out, H, V, C, args, kind="sequential", title=title,
                 names=[f"t={t:.4g}" for t in times])
    why = info.get("note", f"method {info['method']}")
    say(args, f"hks at {len(times)} times on {name} ({lap.n} vertices); "
              f"{bound_text(info['abs_error'], info['bound_kind'], why)}; {seconds:.3g} s"
              + wrote(args.out))
    return EXIT_OK
