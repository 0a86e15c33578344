"""Time one heat-kernel column K_t δ_i = e^{-tL̃}B⁻¹e_i, as a ratio to one Cholesky of B + tL.

Side by side, in one process, on the same unit-area shapes: spectral_igl's ``auto`` method at
tol 1e-8, eigsh truncation with k = 100 and k = 500 (eigenpairs computed once per shape, timed
once), and scipy's expm_multiply. Errors are relative B-norm errors against a reference
computed by shift-and-invert Lanczos at tol 1e-13 with another pole (B + tL instead of the
auto choice).

Usage::

    python benchmarks/heat_column.py                      # spheres 10k, 40k, 160k + armadillo
    python benchmarks/heat_column.py --quick              # sphere 10k only, three times
    python benchmarks/heat_column.py --sizes 10k 40k 160k 650k --mesh ../shared/data/meshes/armadillo.obj
    python benchmarks/heat_column.py --quick --json-dir docs/results   # also docs/results/heat_column.json
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from _results import Table  # beside this script

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import spectral_igl as sig  # noqa: E402
from spectral_igl import filters, linalg as solvers  # noqa: E402
from spectral_igl.linalg import factorize  # noqa: E402

SPHERE_LEVEL = {"10k": 5, "40k": 6, "160k": 7, "650k": 8}


def unit_area(V, F):
    lap = sig.laplacian(V, F)
    return sig.laplacian(V / np.sqrt(lap.area()), F)


def bnorm(lap, x):
    return float(np.sqrt(x @ (lap.B @ x)))


def timed(fn, repeat=1):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def run_shape(name, lap, times, args, table):
    rows = []
    n = lap.n
    i = int(np.argmax(lap.data["V"][:, 2])) if "V" in lap.data else 0
    g = np.zeros(n)
    g[i] = 1.0
    eig = {}
    if not args.no_eigsh:
        for k in args.eigsh_k:
            if k >= n:
                continue
            t_e, (ev, X) = timed(lambda k=k: sig.eigs(lap, k))
            eig[k] = (t_e, ev, X)
    for t in times:
        A = (lap.B + t * lap.L).tocsr()
        t_chol, _ = timed(lambda: factorize(A), repeat=args.repeat)
        # reference: shift-invert Lanczos at tol 1e-13 with a different pole (gamma = t)
        ref = sig.SpectralOperator(lap, filters.heat(t), method="shift_invert", tol=1e-13,
                                   shift=t).apply_inverse_mass(g)
        nref = bnorm(lap, ref)

        def ours():
            solvers.clear_cache(lap)
            op = sig.SpectralOperator(lap, filters.heat(t), method=args.method, tol=1e-8)
            return op, op.apply_inverse_mass(g)

        t_ours, (op, u) = timed(ours, repeat=args.repeat)
        err = bnorm(lap, u - ref) / nref
        row = dict(shape=name, n=n, t=t, chol=t_chol, ours=t_ours, method=op.method,
                   solves=op.n_solves, err=err, bound=op.error_bound / nref)
        for k, (t_e, ev, X) in eig.items():
            uk = X @ (np.exp(-t * ev) * X[i])
            row[f"eig{k}"] = (t_e, bnorm(lap, uk - ref) / nref)
        if args.expm and n <= args.expm_max_n and any(np.isclose(t, args.expm_times)):
            import scipy.sparse.linalg as spla

            def expm():
                Bf = factorize(lap.B)
                A = spla.LinearOperator((n, n), matvec=lambda v: -t * Bf.solve(lap.L @ v),
                                        rmatvec=lambda v: -t * (lap.L @ Bf.solve(v)), dtype=float)
                x0 = Bf.solve(g)
                return spla.expm_multiply(A, x0, traceA=-t * float(lap.L.diagonal() @ (1.0 / lap.mass)))

            try:
                t_x, ux = timed(expm)
                row["expm"] = (t_x, bnorm(lap, ux - ref) / nref)
            except Exception as exc:  # pragma: no cover - reported, not fatal
                row["expm"] = (np.nan, f"{type(exc).__name__}: {exc}"[:60])
        rows.append(row)
        table.add(*cells(row, eig_ks(args)))
    return rows


def eig_ks(args):
    """The eigsh truncations the table has a column for."""
    return [] if args.no_eigsh else list(args.eigsh_k)


def columns(ks):
    """The table's header, with a column per eigsh truncation in ``ks``."""
    return (["shape", "n", "t", "Cholesky (s)", "auto (s)", "auto / Cholesky", "method", "solves",
             "auto rel. error", "certified bound"]
            + [f"eigsh k={k}: time / error" for k in ks] + ["expm_multiply: time / error"])


def cells(r, ks):
    """One row of the table: a shape at one time."""
    out = [r["shape"], f"{r['n']}", f"{r['t']:.0e}", f"{r['chol']:.3f}", f"{r['ours']:.3f}",
           f"{r['ours'] / r['chol']:.2f}", r["method"], f"{r['solves']}", f"{r['err']:.1e}", f"{r['bound']:.1e}"]
    for k in ks:
        te, ee = r.get(f"eig{k}", (np.nan, np.nan))
        out.append(f"{te:.1f} s / {ee:.1e}" if k < r["n"] else "-")
    if "expm" in r:
        te, ee = r["expm"]
        out.append(f"{te:.1f} s / {ee:.1e}" if not isinstance(ee, str) else ee)
    else:
        out.append("-")
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sizes", nargs="*", default=["10k", "40k", "160k"], choices=list(SPHERE_LEVEL))
    p.add_argument("--mesh", nargs="*", default=None, help="extra meshes (default: the armadillo if present)")
    p.add_argument("--times", nargs="*", type=float, default=[1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0])
    p.add_argument("--method", default="auto")
    p.add_argument("--eigsh-k", nargs="*", type=int, default=[100, 500])
    p.add_argument("--no-eigsh", action="store_true")
    p.add_argument("--expm", action="store_true", help="also time scipy's expm_multiply (slow)")
    p.add_argument("--expm-max-n", type=int, default=50000)
    p.add_argument("--expm-times", nargs="*", type=float, default=[1e-2])
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("--quick", action="store_true")
    p.add_argument("--json-dir", help="also write the table as heat_column.json in this folder (docs/results)")
    args = p.parse_args(argv)
    from data_generators import icosphere

    shapes = []
    if args.quick:
        args.sizes, args.times, args.eigsh_k = ["10k"], [1e-4, 1e-2, 1.0], [100]
        args.mesh = []
    for s in args.sizes:
        shapes.append((f"sphere {s}", lambda s=s: unit_area(*icosphere(SPHERE_LEVEL[s]))))
    meshes = args.mesh
    if meshes is None:
        default = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "meshes" / "armadillo.obj"
        meshes = [str(default)] if default.exists() else []
    for m in meshes:
        def load(m=m):
            from spectral_igl.io import read_mesh

            V, F = read_mesh(m)
            return unit_area(V, F)

        shapes.append((Path(m).stem, load))
    print(f"backend: {solvers.available_backends()[0]}; tol 1e-8; time = wall clock (best of "
          f"{args.repeat}), errors relative in the B-norm\n", flush=True)
    table = Table("heat_column", columns(eig_ks(args)), args.json_dir)
    for name, make in shapes:
        run_shape(name, make(), args.times, args, table)
    table.close()


if __name__ == "__main__":
    main()
