"""Per-entry accuracy of heat-kernel columns: what the default promises, and what ``rtol`` costs.

For each shape (unit area) and t: one Cholesky of B + tL (cholespy, the yardstick); the
default column (tol 1e-8) and the share of its entries above ``floor`` x peak that its
per-entry bound proves within ``rtol``; the ``rtol`` column (method, sparse products, time as a
ratio to the Cholesky, the largest proved relative error above the floor); and a consistency
check of the two proved results where both bound an entry (their difference must be within the
sum of their bounds).

Usage::

    python benchmarks/entrywise.py --mesh ../shared/data/meshes/armadillo.obj
    python benchmarks/entrywise.py --mesh ../shared/data/meshes/armadillo.obj --upsample 1
    python benchmarks/entrywise.py --sphere 6                      # icosphere(6), 41k vertices
"""
from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import spectral_igl as sig  # noqa: E402
from spectral_igl.approx.uniformization import metzler_heat, products_needed  # noqa: E402


def load(args):
    if args.sphere is not None:
        from data_generators import icosphere

        V, F = icosphere(args.sphere)
        name = f"icosphere({args.sphere})"
    else:
        import igl

        V, F = igl.read_triangle_mesh(args.mesh)[:2]
        name = Path(args.mesh).name
        for _ in range(args.upsample):
            V, F = igl.upsample(V, F)
        if args.upsample:
            name += f" upsampled x{4 ** args.upsample}"
    lap = sig.laplacian(V, F)
    return name, sig.laplacian(V / np.sqrt(lap.area()), F)


def cholesky_seconds(lap, t):
    from cholespy import CholeskySolverD, MatrixType

    M = (lap.B + t * lap.L).tocoo()
    t0 = time.perf_counter()
    CholeskySolverD(lap.n, M.row, M.col, M.data, MatrixType.COO)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh")
    ap.add_argument("--sphere", type=int)
    ap.add_argument("--upsample", type=int, default=0)
    ap.add_argument("--times", type=float, nargs="+", default=[1e-5, 1e-4, 1e-3])
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--floor", type=float, default=1e-10)
    args = ap.parse_args()
    name, lap = load(args)
    print(f"# {platform.node()}, {time.strftime('%Y-%m-%d')}, python benchmarks/entrywise.py "
          f"{' '.join(sys.argv[1:])}")
    print(f"# {name}: n = {lap.n}, Metzler = {lap.is_metzler}, lambda_max = {sig.lambda_max(lap):.3g}")
    i = int(np.argmax(lap.mass))
    print("| t | Cholesky s | default: share of entries >= floor proved within rtol | rtol: method | "
          "products | time / Cholesky | max proved rel. error | consistent |")
    print("|---|---|---|---|---|---|---|---|")
    for t in args.times:
        chol = min(cholesky_seconds(lap, t) for _ in range(2))
        k, info = sig.heat_kernel(lap, t, i, return_info=True)
        above = k >= args.floor * k.max()
        share = float(np.mean(info["abs_error"][above] <= args.rtol / (1 + args.rtol) * k[above]))
        lap.cache.clear()
        t0 = time.perf_counter()
        try:
            ke, ie = sig.heat_kernel(lap, t, i, rtol=args.rtol, floor=args.floor, return_info=True)
        except ValueError as exc:
            print(f"| {t:g} | {chol:.3f} | {share:.1%} | refused: {str(exc)[:120]} | | | | |")
            continue
        sec = time.perf_counter() - t0
        ab = ke >= args.floor * ke.max()
        worst = float(np.max(ie["rel_error"][ab]))
        both = np.abs(ke - k) <= ie["abs_error"] + info["abs_error"]
        print(f"| {t:g} | {chol:.3f} | {share:.1%} | {ie['method']} | {ie.get('products', '')} | "
              f"{sec / chol:.1f} | {worst:.1e} | {bool(both.all())} |", flush=True)


if __name__ == "__main__":
    main()
