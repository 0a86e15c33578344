"""The inner eigensolvers of ``sig.eigs`` side by side: ARPACK's Lanczos (default), Krylov--Schur
(the survey's Table 2) and multi-resolution prolongation (Vaxman et al. 2010), each certified
by the same residual bounds and inertia count.

For each mesh (unit area, default Laplacian) and k: wall time of each method (a fresh
Laplacian per call, so every call pays its own factorizations), its ratio to Lanczos, the
largest difference of its eigenvalues from Lanczos's, the largest proved enclosure radius,
the bound's kind and the number of searches.

Usage::

    python benchmarks/eigensolvers.py --meshes ../shared/data/meshes/spot.obj \\
        ../shared/data/meshes/armadillo.obj --k 50 200 [--json-dir docs/results]
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from _results import Table  # beside this script

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import spectral_igl as sig  # noqa: E402
from data_generators import icosphere  # noqa: E402
from spectral_igl.io import read_mesh  # noqa: E402


def unit_area(V, F):
    return sig.laplacian(V / np.sqrt(sig.laplacian(V, F).area()), F)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--meshes", nargs="*", default=[], help="mesh files (default: icosphere(6) only)")
    p.add_argument("--k", nargs="*", type=int, default=[50, 200])
    p.add_argument("--sphere-level", type=int, default=6)
    p.add_argument("--json-dir", help="also write the table as eigensolvers.json in this folder")
    args = p.parse_args(argv)
    shapes = [(f"icosphere({args.sphere_level})", icosphere(args.sphere_level))]
    shapes += [(Path(m).stem, read_mesh(m)[:2]) for m in args.meshes]
    table = Table("eigensolvers", ["shape", "n", "k", "method", "time (s)", "÷ lanczos", "max \\|Δλ\\| vs lanczos",
                                   "max proved radius", "kind", "searches"], args.json_dir)
    for name, (V, F) in shapes:
        for k in args.k:
            ref, t_ref = None, None
            for method in sig.linalg.EIG_METHODS:
                lap = unit_area(V, F)
                t0 = time.perf_counter()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    ev, _, info = sig.eigs(lap, k, method=method, return_info=True)
                dt = time.perf_counter() - t0
                if ref is None:
                    ref, t_ref = ev, dt
                first = "" if info["first_search"] == method else f" ({info['first_search']})"
                table.add(name, f"{lap.n:,}", k, f"{method}{first}", f"{dt:.2f}", f"{dt / t_ref:.2f}",
                          f"{np.abs(ev - ref).max():.1e}", f"{info['abs_error'].max():.1e}", info["bound_kind"],
                          info["searches"])
    table.close()


if __name__ == "__main__":
    main()
