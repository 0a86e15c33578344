"""The compiled LDLᵀ's three kernels on a real mesh, beside one cholespy Cholesky in the same run.

    OPENBLAS_NUM_THREADS=1 python benchmarks/ldlt_kernels.py [--mesh PATH] [--repeat 5] [--k 100]

On the unit-area mesh: the complex symmetric matrix (1 + 2i) B + 0.01 L (what a heat pole
factorizes), its numeric LDLᵀ factorization, its selected inversion (the diagonal of the
inverse), one block solve with ``--k`` unit right-hand sides (columns of the inverse: the
forward substitution runs only on each column's path to the root) and one with ``--k`` dense
ones; the real LDLᵀ of B + 0.01 L; and
one cholespy Cholesky of B + 0.01 L as the yardstick (that one includes its ordering and
symbolic analysis; the LDLᵀ rows are numeric work on a pattern analysed once, as every pole
of a family shares it). Medians of ``--repeat``. The kernels are compiled for AVX2 and for
the baseline and chosen at run time by the CPU; dense blocks above 32k multiply-adds go to
the BLAS scipy links.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from _timing import median_time  # beside this script

import spectral_igl as sig
from spectral_igl.io import read_mesh
from spectral_igl.linalg import factorize, ldlt

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", type=Path, default=ROOT.parent / "shared" / "data" / "meshes" / "armadillo.obj")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--k", type=int, default=100)
    args = ap.parse_args()
    V, F = read_mesh(args.mesh)
    lap0 = sig.laplacian(V, F)
    lap = sig.laplacian(V / np.sqrt(lap0.area()), F)
    real = (lap.B + 0.01 * lap.L).tocsc()
    cplx = ((1 + 2j) * lap.B + 0.01 * lap.L).tocsc()
    pat = ldlt.Pattern(real)
    t_chol, _ = median_time(lambda: factorize(real.tocsr(), backend="cholespy", spd=True), args.repeat)
    t_real, _ = median_time(lambda: ldlt.LDLT(real, pat), args.repeat)
    t_fac, fac = median_time(lambda: ldlt.LDLT(cplx, pat), args.repeat)
    t_sel, _ = median_time(fac.inverse_diagonal, args.repeat)
    E = np.zeros((lap.n, args.k))
    E[np.linspace(0, lap.n - 1, args.k).astype(int), np.arange(args.k)] = 1.0
    t_sol, _ = median_time(lambda: fac.solve(E), args.repeat)
    R = np.random.default_rng(0).standard_normal((lap.n, args.k))
    t_dense, _ = median_time(lambda: fac.solve(R), args.repeat)
    print(f"{args.mesh.name}: n = {lap.n}, one cholespy Cholesky {t_chol:.3f} s")
    print("| kernel | time (s) | ÷ Cholesky |")
    print("|---|---|---|")
    for name, t in (("real LDLᵀ factorization", t_real), ("complex LDLᵀ factorization", t_fac),
                    ("complex selected inversion", t_sel), (f"complex solve, {args.k} unit right-hand sides", t_sol),
                    (f"complex solve, {args.k} dense right-hand sides", t_dense)):
        print(f"| {name} | {t:.3f} | {t / t_chol:.2f} |")


if __name__ == "__main__":
    main()
