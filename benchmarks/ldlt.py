"""The package's supernodal LDLᵀ against CHOLMOD (cholespy) and SuperLU, and its selected inverse.

Matrices of a unit-area torus with n vertices: the real SPD B + 1e-3 L and the complex
symmetric 1e-3 L - zB of a heat pole (z = -2 + 3i). Times in seconds and as ratios to
cholespy's factorization (which includes its own ordering and analysis; ours is timed
apart, once per pattern). Accuracy: the relative residual of a solve, and the selected
inverse against solves with unit vectors at 8 vertices.

    OPENBLAS_NUM_THREADS=1 python benchmarks/ldlt.py --n 10000 100000
    OPENBLAS_NUM_THREADS=1 python benchmarks/ldlt.py --n --tets 35      # a 35^3-cell tet box (3D fill)
    OPENBLAS_NUM_THREADS=1 python benchmarks/ldlt.py --n 10000 100000 --tets 35 --superlu-ordering COLAMD \
        --json-dir docs/results
"""
from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse.linalg as spla
from _results import Table  # beside this script

import spectral_igl as sig
from data_generators import box_tets, torus
from spectral_igl.linalg import factorize
from spectral_igl.linalg.ldlt import LDLT, Pattern


def unit_torus(n):
    nv = int(round(np.sqrt(n / 2.5)))
    V, F = torus(1.0, 0.4, n_major=int(round(n / nv)), n_minor=nv)
    return V / np.sqrt(sig.laplacian(V, F).area()), F


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="*", default=[10000, 100000], help="torus sizes")
    ap.add_argument("--tets", type=int, nargs="*", default=[], help="tet boxes with S^3 cells")
    ap.add_argument("--superlu-ordering", default="MMD_AT_PLUS_A",
                    choices=["MMD_AT_PLUS_A", "MMD_ATA", "COLAMD", "NATURAL"],
                    help="SuperLU's column ordering (its time is part of SuperLU's)")
    ap.add_argument("--json-dir", help="also write the table as ldlt.json in this folder (docs/results)")
    args = ap.parse_args()
    table = Table("ldlt", ["n", "stored L entries", "cholespy factor [s]", "ordering + analysis [s]",
                           "LDLᵀ real [s] (÷ cholespy)", "selected inverse real [s]", "LDLᵀ complex [s]",
                           "selected inverse complex [s]", f"SuperLU complex, {args.superlu_ordering} [s]",
                           "complex residual", "selinv vs solves"], args.json_dir)
    shapes = [("torus", n) for n in args.n] + [("tets", s) for s in args.tets]
    for kind, size in shapes:
        lap = sig.laplacian(*(unit_torus(size) if kind == "torus" else box_tets((size, size, size))))
        n = lap.n
        A = (lap.B + 1e-3 * lap.L).tocsr()
        Z = (1e-3 * lap.L - (-2 + 3j) * lap.B).tocsc()
        chol, t_chol = timed(lambda: factorize(A, backend="cholespy"))
        pat, t_pat = timed(lambda: Pattern(abs(lap.L) + abs(lap.B)))
        f, t_f = timed(lambda: LDLT(A, pat))
        d, t_d = timed(f.inverse_diagonal)
        fz, t_fz = timed(lambda: LDLT(Z, pat))
        dz, t_dz = timed(fz.inverse_diagonal)
        lu, t_lu = timed(lambda: spla.splu(Z, permc_spec=args.superlu_ordering))
        rng = np.random.default_rng(0)
        b = rng.standard_normal(n)
        res = np.linalg.norm(Z @ fz.solve(b) - b) / np.linalg.norm(b)
        idx = rng.choice(n, 8, replace=False)
        E = np.zeros((n, 8))
        E[idx, np.arange(8)] = 1.0
        sel = np.abs(dz[idx] - fz.solve(E)[idx, np.arange(8)]).max() / np.abs(dz[idx]).max()
        table.add(f"{n:,}" + (" (tets)" if kind == "tets" else ""), f"{pat.nnz_L:,}", f"{t_chol:.2f}",
                  f"{t_pat:.2f}", f"{t_f:.2f} ({t_f / t_chol:.2f}x)", f"{t_d:.2f}", f"{t_fz:.2f}", f"{t_dz:.2f}",
                  f"{t_lu:.2f} ({t_lu / t_fz:.0f}x ours)", f"{res:.1e}", f"{sel:.1e}")
    table.close()


if __name__ == "__main__":
    main()
