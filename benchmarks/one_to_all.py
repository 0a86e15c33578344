"""One-to-all spectral distances and HKS at every vertex on a large mesh.

Times are ratios to one Cholesky factorization of B + tL (cholespy), the project's
yardstick. Errors are measured against exact values at random check vertices (computed
independently, as B-norms of filtered differences / kernel columns at engine tolerance
1e-12), relative to the largest value; the truncated-eigenpair baseline (eigsh, k = 100
and 500) is shown beside.

    python benchmarks/one_to_all.py            # icosphere level 7, n = 163,842
    python benchmarks/one_to_all.py --quick    # level 5, n = 10,242
    python benchmarks/one_to_all.py --torus 100000 --ks 100   # a 100k-vertex torus
    python benchmarks/one_to_all.py --mesh ../shared/data/meshes/armadillo.obj --upsample 1 --ks 100
    python benchmarks/one_to_all.py --torus 100000 --ks 100 --json-dir docs/results   # docs/results/one_to_all.json
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from _results import Table  # beside this script

import spectral_igl as sig
from data_generators import icosphere, torus
from spectral_igl import filters
from spectral_igl.linalg import factorize


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--level", type=int, default=7, help="icosphere level (7: 163k vertices)")
    ap.add_argument("--mesh", help="a mesh file instead of the icosphere")
    ap.add_argument("--upsample", type=int, default=0, help="midpoint subdivisions of --mesh (x4 faces each)")
    ap.add_argument("--quick", action="store_true", help="level 5 and k = 100 only")
    ap.add_argument("--checks", type=int, default=24, help="check vertices for the errors")
    ap.add_argument("--ks", default="100,500", help="eigsh baselines (0: none)")
    ap.add_argument("--torus", type=int, help="a torus (R = 1, r = 0.4) with about this many vertices")
    ap.add_argument("--max-colours", type=int, default=None, help="probing colour budget")
    ap.add_argument("--max-recompute", type=int, default=None,
                    help="cap on exact recomputations near the source (default: all)")
    ap.add_argument("--rtol", type=float, default=1e-4, help="accuracy the probing choices aim at")
    ap.add_argument("--diagonal", default="auto", help="kernel_diagonal method (auto = selinv)")
    ap.add_argument("--json-dir", help="also write the table as one_to_all.json in this folder (docs/results)")
    args = ap.parse_args()
    if args.torus:
        nv = int(round(np.sqrt(args.torus / 2.5)))
        V, F = torus(1.0, 0.4, n_major=int(round(args.torus / nv)), n_minor=nv)
    elif args.mesh:
        from spectral_igl.io import read_mesh

        V, F = read_mesh(args.mesh)
        if args.upsample:
            import igl

            V, F = igl.upsample(V, F, args.upsample)
    else:
        V, F = icosphere(5 if args.quick else args.level)
    lap0 = sig.laplacian(V, F)
    V = V / np.sqrt(lap0.area())          # unit area
    lap = sig.laplacian(V, F)
    n = lap.n
    ks = [100] if args.quick else [int(k) for k in args.ks.split(",") if k.strip() and int(k) > 0]
    print(f"mesh: n = {n}, unit area, the default Laplacian (intrinsic Delaunay cotan, lumped mass)", flush=True)

    t0 = time.perf_counter()
    factorize(lap.B + 1e-3 * lap.L)
    chol = time.perf_counter() - t0
    print(f"one Cholesky of B + tL: {chol:.3f} s", flush=True)

    t0 = time.perf_counter()
    sig.linalg.ldlt_pattern(lap)
    print(f"ordering + symbolic analysis of the pattern (once per mesh): {time.perf_counter() - t0:.3f} s", flush=True)

    eig = {}
    for k in ks:
        t0 = time.perf_counter()
        eig[k] = (sig.eigs(lap, k), time.perf_counter() - t0)
        print(f"eigsh k={k}: {eig[k][1]:.1f} s", flush=True)

    rng = np.random.default_rng(7)
    src = int(rng.integers(n))
    checks = rng.choice(n, args.checks, replace=False)
    table = Table("one_to_all", ["quantity (all vertices)", "time / Cholesky", "diagonal", "max rel. error",
                                 "reported (samples)", "recomputed / unverified near source"]
                  + [f"eigsh k={k} error" for k in ks], args.json_dir)
    cases = [("biharmonic distance", filters.biharmonic(), "dist"),
             ("commute-time distance", filters.commute_time(), "dist"),
             ("diffusion distance t=1e-3", filters.heat(0.5e-3), "dist"),
             ("diffusion distance t=1e-2", filters.heat(0.5e-2), "dist"),
             ("HKS t=1e-3", filters.heat(1e-3), "diag"),
             ("HKS t=1e-2", filters.heat(1e-2), "diag")]
    for name, filt, kind in cases:
        # every row pays its own factorizations, diagonals and operators; the mesh's ordering
        # and symbolic analysis (timed once above), spectral bounds and eigenpairs are shared
        for slot in ("factor", "diagonal", "kernel", "operator"):
            lap.cache.discard(slot)
        t0 = time.perf_counter()
        if kind == "dist":
            val, info = sig.spectral_distance(lap, filt, src, diagonal=args.diagonal, max_colours=args.max_colours,
                                              rtol=args.rtol, max_recompute=args.max_recompute,
                                              return_info=True)
        else:
            val, info = sig.kernel_diagonal(lap, filt, method=args.diagonal, max_colours=args.max_colours,
                                            rtol=args.rtol, return_info=True)
        elapsed = time.perf_counter() - t0
        chk = np.setdiff1d(checks, info.get("samples", []))
        if kind == "dist":
            exact = sig.spectral_distance(lap, filt, src, targets=chk, tol=1e-12)
            scale = val.max()
        else:
            from spectral_igl.kernels import kernel_columns

            exact = kernel_columns(lap, filt, chk, tol=1e-12)[chk, np.arange(chk.size)]
            scale = np.abs(exact).max()
        err = np.abs(val[chk] - exact).max() / scale
        if info["method"] == "selinv":
            how = f"selinv, {info['factorizations']} factorizations"
        else:
            how = f"{info['method']}, k={info.get('k')}, D={info.get('distance')}, {info.get('colours')} colours"
        row = [name, f"{elapsed / chol:.1f}x", how, f"{err:.1e}", f"{info.get('sample_rel_error', np.nan):.1e}",
               f"{len(info.get('recomputed', []))} / {len(info.get('unverified', []))}"]
        for k in ks:
            (lam, X), tk = eig[k]
            ph = np.abs(filt(lam)) ** 2 if kind == "dist" else filt(lam)
            if filt.singular:
                ph = np.where(lam > 0, ph, 0.0)
            if kind == "dist":
                tr = np.sqrt(np.maximum(((X[chk] - X[src]) ** 2) @ ph, 0))
            else:
                tr = (X[chk] ** 2) @ ph
            row.append(f"{np.abs(tr - exact).max() / scale:.1e}")
        table.add(*row)
    table.close()
    print(f"\nn = {n}; one Cholesky = {chol:.3f} s; "
          + "; ".join(f"eigsh k={k}: {eig[k][1]:.1f} s = {eig[k][1] / chol:.0f}x" for k in ks))


if __name__ == "__main__":
    main()
