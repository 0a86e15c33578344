"""Cost of a second source through the one-call distance functions, against the first.

Each mesh is scaled to unit area. Times are wall seconds and multiples of one Cholesky
factorization of B + tL (cholespy) of the same mesh.

    OPENBLAS_NUM_THREADS=1 python benchmarks/second_source.py ../shared/data/meshes/armadillo.obj
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import spectral_igl as sig
from spectral_igl.io import read_mesh
from spectral_igl.linalg import factorize


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("-t", type=float, default=1e-3, help="diffusion time (unit area)")
    args = ap.parse_args()
    print("| mesh | n | distance | one Cholesky (s) | first source | second source | second / first |")
    print("|---|---|---|---|---|---|---|")
    for path in args.meshes:
        V, F = read_mesh(path)[:2]
        lap = sig.laplacian(V, F)
        lap = sig.laplacian(V / np.sqrt(lap.area()), F)
        start = time.perf_counter()
        factorize(lap.B + args.t * lap.L)
        chol = time.perf_counter() - start
        runs = [(f"diffusion t={args.t:g}", lambda s: sig.diffusion_distance(lap, args.t, s)),
                ("biharmonic", lambda s: sig.biharmonic_distance(lap, s))]
        for label, fn in runs:
            t0 = time.perf_counter()
            fn(0)
            t1 = time.perf_counter()
            fn(17)
            t2 = time.perf_counter()
            a, b = t1 - t0, t2 - t1
            print(f"| {path.rsplit('/', 1)[-1]} | {lap.n} | {label} | {chol:.3f} | {a:.3f} s ({a / chol:.1f}×) "
                  f"| {b:.3f} s ({b / chol:.2f}×) | {b / a:.3f} |", flush=True)


if __name__ == "__main__":
    main()
