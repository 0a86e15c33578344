"""The ``spectral-igl`` parser and its entry point: one sub-command per job, each job's
errors mapped to its exit code."""
from __future__ import annotations

import argparse
import sys

from .._version import __version__
from ..progress import enabled as progress_enabled
from .batch import add_batch, run_batch
from .errors import EXIT_ERROR, EXIT_MISSING, EXIT_USAGE, CLIError
from .figures import add_figures, run_figures
from .hks import add_hks, run_hks
from .single import add_distance, add_geodesic, add_kernel, add_view, run_geodesic, run_kernel_distance, run_view
from .smooth import add_smooth, run_smooth

__all__ = ["JOBS", "build_parser", "main"]

#: job -> (adds its sub-command, runs it), in the order ``--help`` lists them
JOBS = {"kernel": (add_kernel, run_kernel_distance), "distance": (add_distance, run_kernel_distance),
        "hks": (add_hks, run_hks), "smooth": (add_smooth, run_smooth),
        "geodesic": (add_geodesic, run_geodesic), "view": (add_view, run_view),
        "figures": (add_figures, run_figures), "batch": (add_batch, run_batch)}


def build_parser():
    r"""The ``argparse`` parser of ``spectral-igl``: one sub-command per job.

    Returns
    -------
    argparse.ArgumentParser

    Examples
    --------
    >>> from spectral_igl.cli import build_parser
    >>> args = build_parser().parse_args(["kernel", "--shape", "sphere", "--source", "3"])
    >>> args.job, args.shape, args.source
    ('kernel', 'sphere', 3)
    """
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
    for add, _ in JOBS.values():
        add(sub)
    return parser


def main(argv=None) -> int:
    r"""Run ``spectral-igl`` with ``argv`` (default ``sys.argv[1:]``); return the exit code.

    Parameters
    ----------
    argv : list of str, optional
        The command line after the program name.

    Returns
    -------
    int
        0 ok, 1 computation failed, 2 bad arguments, 3 bad input file, 4 missing optional
        dependency (messages go to stderr, never a traceback).

    Examples
    --------
    A heat kernel column on a generated sphere, written as ``.npy``:

    >>> import numpy as np
    >>> from spectral_igl.cli import main
    >>> main(["kernel", "--shape", "sphere", "--level", "2", "--source", "0", "--filter", "heat",
    ...       "-t", "0.1", "--out", "k.npy", "--quiet"])
    0
    >>> np.load("k.npy").shape
    (162,)
    >>> main(["kernel", "--source", "0", "--quiet"])     # no mesh given: bad arguments
    2
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors
        return int(exc.code) if isinstance(exc.code, int) else EXIT_USAGE
    try:
        with progress_enabled(bool(getattr(args, "progress", False)) and not getattr(args, "quiet", False)):
            return JOBS[args.job][1](args)
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
