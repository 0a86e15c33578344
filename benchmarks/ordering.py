"""Fill-reducing orderings on real meshes: minimum degree (compiled) against METIS nested
dissection, for the pattern of B + tL that heat geodesics factorize.

    OPENBLAS_NUM_THREADS=1 python benchmarks/ordering.py [--meshes DIR] [--repeat 7]

Per mesh: the ordering's time alone (median of ``--repeat``), the entries of the LDLᵀ
factor L under each ordering, and one numeric factorization's time under each.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from _results import Table  # beside this script
from _timing import median_time

import spectral_igl as sig
from spectral_igl.io import read_mesh
from spectral_igl.linalg import ldlt

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", type=Path, default=ROOT.parent / "shared" / "data" / "meshes")
    ap.add_argument("--names", default="cow.obj,spot.obj,homer.obj,fandisk.obj,rocker-arm.obj,armadillo.obj")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--json-dir", help="also write the table as JSON in this folder (docs/results)")
    args = ap.parse_args()
    table = Table("ordering", ["mesh", "n", "minimum degree (ms)", "METIS (ms)", "nnz L: min. degree",
                               "nnz L: METIS", "ratio", "factor: min. degree (ms)", "factor: METIS (ms)"],
                  args.json_dir)
    for name in args.names.split(","):
        V, F = read_mesh(args.meshes / name)
        lap = sig.laplacian(V, F, mass="lumped")
        A = (lap.B + 1e-3 * lap.L).tocsc()
        md = ldlt.Pattern(A, ordering="minimum_degree")
        t_md, perm = median_time(lambda: ldlt.minimum_degree(A), args.repeat)
        assert np.array_equal(np.sort(perm), np.arange(lap.n))
        t_nd, _ = median_time(lambda: ldlt.nested_dissection(A), args.repeat)
        nd = ldlt.Pattern(A, ordering="nested_dissection")
        f_md, _ = median_time(lambda: ldlt.LDLT(A, md), args.repeat)
        f_nd, _ = median_time(lambda: ldlt.LDLT(A, nd), args.repeat)
        table.add(name, f"{lap.n:,}", f"{1e3 * t_md:.1f}", f"{1e3 * t_nd:.1f}", f"{md.nnz_L:,}",
                  f"{nd.nnz_L:,}", f"{md.nnz_L / nd.nnz_L:.2f}", f"{1e3 * f_md:.1f}", f"{1e3 * f_nd:.1f}")
    table.close()


if __name__ == "__main__":
    main()
