"""The whole heat kernel matrix as a certified sparse matrix: cost, memory and bounds.

For each t: :func:`spectral_igl.sparse_heat_kernel` on a shape (unit area), cold (the
Laplacian's cache cleared), its time as a ratio to one cholespy Cholesky factorization of
B + tL in the same process (wall and CPU time: the machine may be shared), the stored entries per column, the process's peak
resident size (and with ``--traced`` the peak of traced memory, ``tracemalloc``: numpy and scipy
arrays, in a second call, since tracing slows the call's threads), the sparse
products spent; then checks against global reference columns (``heat_kernel``,
``"rational"``, tol 1e-12, with its own bound) at a few sources: stored entries outside
their bound, dropped entries above ``dropped_max``, dropped mass above ``dropped_mass`` (all
must be 0), and the largest bounds relative to the column's peak; and the heat kernel
signature of every vertex (K's diagonal) against the reference's diagonal entries. With
``--distances``, also :func:`spectral_igl.sparse_diffusion_distance` (every stored pair),
timed the same way and checked at the same sources against ``diffusion_distance``
(``"rational"``, tol 1e-12; the reference's bound on d^2 carried to d).

Usage::

    python benchmarks/sparse_heat.py --mesh ../shared/data/meshes/stanford-bunny.obj --subdivide 1 --distances
"""
from __future__ import annotations

import argparse
import datetime
import os
import platform
import resource
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import spectral_igl as sig  # noqa: E402
from local_heat import cholesky_seconds, load  # noqa: E402


def check(lap, t, K, info, sources):
    """(stored entries outside their bound, dropped entries above dropped_max, columns whose
    dropped mass exceeds its bound, HKS entries outside their bound) against references."""
    bad = [0, 0, 0, 0]
    for s in sources:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sig.accuracy.AccuracyWarning)
            ref, rinfo = sig.heat_kernel(lap, t, s, method="rational", tol=1e-12, return_info=True)
        col = K[:, [s]].toarray()[:, 0]
        err = info["abs_error"][:, [s]].toarray()[:, 0]
        stored = col > 0
        gap = np.abs(col - ref) - rinfo["abs_error"]
        bad[0] += int(np.count_nonzero(gap[stored] > err[stored]))
        bad[1] += int(np.count_nonzero(ref[~stored] - rinfo["abs_error"][~stored] > info["dropped_max"][s]))
        low = np.maximum(ref - rinfo["abs_error"], 0.0)[~stored]
        bad[2] += int(lap.mass[~stored] @ low > info["dropped_mass"][s])
        bad[3] += int(abs(K[s, s] - ref[s]) - rinfo["abs_error"][s] > info["abs_error"][s, s])
    return bad


def check_distances(lap, t, D, info, sources):
    """Stored distances outside their bound at the sources (against the reference's interval)."""
    bad = 0
    for s in sources:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sig.accuracy.AccuracyWarning)
            ref, rinfo = sig.diffusion_distance(lap, t, s, method="rational", tol=1e-12, return_info=True)
        row = D[s]
        got, err = row.data, info["abs_error"][s].data
        exact, slack = ref[row.indices], rinfo["abs_error"][row.indices]
        bad += int(np.count_nonzero(np.abs(got - exact) > err + slack))
    return bad


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--subdivide", type=int, default=0)
    ap.add_argument("--times", type=float, nargs="+", default=[1e-5])
    ap.add_argument("--threshold", type=float, default=1e-8)
    ap.add_argument("--block", type=int, default=32)
    ap.add_argument("--sources", type=int, default=3)
    ap.add_argument("--no-check", action="store_true", help="skip the reference columns (large n)")
    ap.add_argument("--traced", action="store_true",
                    help="also the peak of numpy's traced memory, in a second call (max RSS is of both)")
    ap.add_argument("--distances", action="store_true", help="also time and check sparse_diffusion_distance")
    args = ap.parse_args(argv)
    name, lap = load(args.mesh, args.subdivide)
    sources = np.random.default_rng(0).choice(lap.n, args.sources, replace=False)
    print(f"# {platform.processor() or platform.machine()}, {datetime.date.today()}, "
          f"python {' '.join(sys.argv)}, load average {os.getloadavg()[0]:.1f}")
    print(f"# {name}: n = {lap.n}, unit area, tol = 1e-8, threshold = {args.threshold:g}, block = {args.block}")
    print("| t | time / Cholesky | CPU time / Cholesky's | Cholesky (s) | entries per column | traced peak (GB) | max RSS (GB) | "
          "products | max bound / peak | max dropped / peak | max dropped mass | outside bounds (stored, "
          "dropped, mass, HKS) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for t in args.times:
        c0 = time.process_time()
        chol = cholesky_seconds(lap, t)
        chol_cpu = (time.process_time() - c0) / 3
        lap.cache.clear()
        t0, c0 = time.perf_counter(), time.process_time()
        K, info = sig.sparse_heat_kernel(lap, t, threshold=args.threshold, block=args.block, return_info=True)
        sec, cpu = time.perf_counter() - t0, time.process_time() - c0
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20
        peak = float("nan")
        if args.traced:                          # apart: tracing slows the batches' threads
            del K, info
            lap.cache.clear()
            tracemalloc.start()
            K, info = sig.sparse_heat_kernel(lap, t, threshold=args.threshold, block=args.block, return_info=True)
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
        d = K.diagonal()
        rel = info["abs_error"].max(axis=0).toarray()[0] / K.max(axis=0).toarray()[0]
        bad = "not checked" if args.no_check else ", ".join(map(str, check(lap, t, K, info, sources)))
        print(f"| {t:g} | {sec / chol:.2f} | {cpu / chol_cpu:.2f} | {chol:.2f} | {K.nnz / lap.n:.0f} | {peak / 2 ** 30:.2f} | "
              f"{rss:.2f} | {info['products']:.0f} | {rel.max():.1e} | "
              f"{np.max(info['dropped_max'] / d):.1e} | {info['dropped_mass'].max():.1e} | {bad} |", flush=True)
        print(f"# load average after t = {t:g}: {os.getloadavg()[0]:.1f}", flush=True)
        del K, info
        if args.distances:
            lap.cache.clear()
            t0, c0 = time.perf_counter(), time.process_time()
            D, dinfo = sig.sparse_diffusion_distance(lap, t, threshold=args.threshold, block=args.block,
                                                     return_info=True)
            sec, cpu = time.perf_counter() - t0, time.process_time() - c0
            rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20
            bad = "not checked" if args.no_check else check_distances(lap, t, D, dinfo, sources)
            off = D.data > 0
            print(f"# diffusion distances at t = {t:g}: {sec / chol:.2f} Cholesky ({cpu / chol_cpu:.2f} in CPU "
                  f"time), {D.nnz / lap.n:.0f} pairs per vertex, max RSS so far {rss:.2f} GB, median "
                  f"bound / distance {np.median(dinfo['abs_error'].data[off] / D.data[off]):.1e}, HKS bound / "
                  f"HKS max {np.max(dinfo['hks_error'] / dinfo['hks']):.1e}, outside bounds: {bad}", flush=True)
            del D, dinfo


if __name__ == "__main__":
    main()
