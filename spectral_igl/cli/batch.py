"""The ``batch`` job: one job over many shapes on dask.distributed, into a Zarr store."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..filters import FILTERS
from .arguments import (FILTER_NAMES, operator_args, positive, positive_int, quiet_arg, time_args,
                        tol_arg, vertex_index)
from .errors import EXIT_ERROR, EXIT_INPUT, EXIT_OK, EXIT_USAGE, CLIError

__all__ = ["add_batch", "batch_job", "run_batch"]


def add_batch(sub):
    """The ``batch`` job's arguments."""
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
    p.add_argument("--times", type=positive, nargs="+",
                   help="hks: times t (default: --count times from each shape's own spectrum)")
    p.add_argument("--count", type=positive_int, default=100,
                   help="hks: number of times of the default grid (default 100)")
    p.add_argument("--normalize", action=argparse.BooleanOptionalAction, default=True,
                   help="hks: multiply by the area (volume) of each vertex's component, so that "
                        "shapes of different sizes compare (default on)")
    p.add_argument("--energies", type=float, nargs="+",
                   help="wks: log-energies (default: 100 from each shape's own spectrum)")
    p.add_argument("--sigma", type=positive, default=None, help="wks: band width")
    p.add_argument("-f", "--filter", default=None, metavar="FILTER",
                   choices=FILTER_NAMES, help=f"diagonal, distance: {', '.join(FILTER_NAMES)} "
                                              "(default heat for diagonal, biharmonic for distance)")
    time_args(p, "time t of the filter", "-t and --times")
    p.add_argument("--order", type=positive_int, default=3, help="polyharmonic order (default 3)")
    p.add_argument("-s", "--sources", type=vertex_index, nargs="+", help="distance: source vertices")
    p.add_argument("-k", type=positive_int, default=None,
                   help="eigenvalues: how many (default 20); wks: eigenpairs (default 100)")
    p.add_argument("--method", default="auto", help="diagonal method (default auto; wks: eigen)")
    tol_arg(p, kind=positive)
    operator_args(p, described=False)
    p.add_argument("--workers", type=positive_int, default=None,
                   help="local worker processes (default: one per core)")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run on this dask scheduler (tcp://host:8786) instead of a local cluster")
    p.add_argument("--memory-limit", default="auto",
                   help="per-worker memory limit of the local cluster (default auto)")
    p.add_argument("--retries", type=int, default=2, help="retries after a worker died (default 2)")
    p.add_argument("--force", action="store_true", help="recompute shapes with a current result")
    p.add_argument("--retry-failed", action="store_true",
                   help="rerun shapes whose input made them fail before (default: report them again)")
    quiet_arg(p, "no progress bar, summary only")


def batch_job(args):
    """The :class:`spectral_igl.collection.Job` the arguments describe."""
    from ..collection import Job

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


def run_batch(args):
    """Run the job over the inputs and print the summary; exit 1 if any shape failed."""
    try:
        from ..collection import run
    except ImportError as err:
        raise ImportError(f"{err}; batch needs dask[distributed] and zarr") from err
    try:
        job = batch_job(args)
    except ValueError as err:
        raise CLIError(str(err), EXIT_USAGE) from err
    try:
        from ..collection import collect_inputs

        collect_inputs(list(args.inputs))
    except (ValueError, TypeError) as err:
        raise CLIError(str(err), EXIT_INPUT) from err
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise CLIError(f"cannot write the store {args.out!r}: it is a file, not a directory", EXIT_USAGE)
    from ..collection.store import StoreInUse

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
