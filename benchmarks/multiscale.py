"""Many scales and many sources at once: HKS/WKS at T scales, heat columns at many sources,
pairwise distances, one-to-all peak memory.

Each task runs in its own process (so that its peak resident memory is its own) and is timed
as a ratio to one Cholesky factorization of B + tL (cholespy) measured in that process just
before it. Errors are against exact values at random check vertices (kernel columns at
engine tolerance 1e-12).

    OPENBLAS_NUM_THREADS=1 python benchmarks/multiscale.py --mesh ../shared/data/meshes/armadillo.obj
    OPENBLAS_NUM_THREADS=1 python benchmarks/multiscale.py --torus 40000 --tasks hks,wks
    OPENBLAS_NUM_THREADS=1 python benchmarks/multiscale.py --box 200000 --tasks columns,onetoall --m 1

With ``--json-dir DIR`` the table is also written to ``DIR/<--table>.json`` (docs/results).
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np
from _results import Table  # beside this script

TASKS = ("hks", "hks_loop3", "wks", "eigsh", "columns", "columns_times", "pairwise", "onetoall")


def shape(args):
    import spectral_igl as sig
    from data_generators import torus

    if args.torus:
        nv = int(round(np.sqrt(args.torus / 2.5)))
        V, F = torus(1.0, 0.4, n_major=int(round(args.torus / nv)), n_minor=nv)
    elif args.box:      # a tetrahedral box of about this many vertices, unit volume
        from data_generators import box_tets

        k = int(round(args.box ** (1 / 3)))
        V, T = box_tets((k, k, k))
        lap0 = sig.laplacian(V, T)
        return sig.laplacian(V / lap0.area() ** (1 / 3), T)
    else:
        from spectral_igl.io import read_mesh

        V, F = read_mesh(args.mesh)
        if args.upsample:
            import igl

            V, F = igl.upsample(V, F, args.upsample)
    lap0 = sig.laplacian(V, F)
    return sig.laplacian(V / np.sqrt(lap0.area()), F)


def exact_diag(lap, filt_t, idx):
    """Exact heat diagonal entries at idx: columns at engine tolerance 1e-12."""
    import spectral_igl as sig

    K = sig.heat_kernel(lap, filt_t, idx, method="rational", tol=1e-12)
    return K[idx, np.arange(idx.size)]


def run_task(args):
    import spectral_igl as sig
    from spectral_igl.linalg import factorize

    lap = shape(args)
    if args.factor_budget is not None:
        lap.cache.factor_budget = int(args.factor_budget * 2 ** 30)
    n = lap.n
    t0 = time.perf_counter()
    factorize(lap.B + 1e-3 * lap.L)
    chol = time.perf_counter() - t0
    rng = np.random.default_rng(7)
    checks = np.sort(rng.choice(n, args.checks, replace=False))
    times = np.geomspace(args.t1, args.t2, args.T)
    out = {"task": args.task, "n": n, "chol": chol}
    t0 = time.perf_counter()
    if args.task == "hks":
        from spectral_igl.families import heat_diagonals

        md = heat_diagonals(lap, times)
        out["time"] = time.perf_counter() - t0
        out["factorizations"] = md.n_factorizations
        out["bound_rel"] = float(np.max(md.abs_bound / md.values))
        H = md.values
        errs = []
        for k in (0, args.T // 2, args.T - 1) if args.checks else ():
            ex = exact_diag(lap, float(times[k]), checks)
            errs.append(float(np.max(np.abs(H[checks, k] - ex) / ex)))
        out["err"] = max(errs, default=None)
    elif args.task == "hks_loop3":
        from spectral_igl.filters import heat

        H = [sig.kernel_diagonal(lap, heat(float(t))) for t in times[[0, args.T // 2, -1]]]
        out["time"] = time.perf_counter() - t0
    elif args.task == "wks":
        lam = sig.eigs(lap, 301)[0]                 # only to place the energies as Aubry et al.
        E = np.linspace(np.log(lam[1]), np.log(lam[300]), args.T)
        t0 = time.perf_counter()
        from spectral_igl.descriptors import _wks_filter   # noqa: the filter WKS uses
        from spectral_igl.families import family_diagonals

        sigma = 7.0 * (E[1] - E[0])
        filts = [_wks_filter(float(e), sigma) for e in E]
        md = family_diagonals(lap, filts, 1e-9, scales=np.exp(E))
        out["time"] = time.perf_counter() - t0
        out["factorizations"] = md.n_factorizations
        out["bound_rel"] = float(np.max(md.abs_bound[checks] / np.abs(md.values[checks]).max(axis=0)))
        errs = []
        for k in (0, args.T // 2, args.T - 1):
            op = sig.spectral_operator(lap, filts[k], "chebyshev", 1e-12)
            Ec = np.zeros((n, checks.size))
            Ec[checks, np.arange(checks.size)] = 1.0
            ex = op.apply_inverse_mass(Ec)[checks, np.arange(checks.size)]
            errs.append(float(np.max(np.abs(md.values[checks, k] - ex)) / np.abs(md.values[:, k]).max()))
        out["err"] = max(errs)
    elif args.task == "eigsh":
        lam, X = sig.eigs(lap, args.k)
        out["time"] = time.perf_counter() - t0
        errs = []
        for k in (0, args.T // 2, args.T - 1):
            tr = (X[checks] ** 2) @ np.exp(-lam * times[k])
            ex = exact_diag(lap, float(times[k]), checks)
            errs.append(float(np.max(np.abs(tr - ex) / ex)))
        out["err"] = max(errs)
    elif args.task == "columns":
        src = rng.choice(n, args.m, replace=False)
        K = sig.heat_kernel(lap, args.t, src)
        out["time"] = time.perf_counter() - t0
    elif args.task == "columns_times":
        src = rng.choice(n, args.m, replace=False)
        K, eps = sig.kernels.heat_kernels(lap, times, src, return_bound=True)
        out["time"] = time.perf_counter() - t0
        out["eps"] = float(eps.max())
    elif args.task == "pairwise":
        from spectral_igl.filters import heat

        src = rng.choice(n, args.m, replace=False)
        D = sig.pairwise_spectral_distance(lap, heat(args.t / 2), src)
        out["time"] = time.perf_counter() - t0
    elif args.task == "onetoall":
        d = sig.diffusion_distance(lap, args.t, 0) if args.filter == "diffusion" else sig.biharmonic_distance(lap, 0)
        out["time"] = time.perf_counter() - t0
        out["filter"] = args.filter
        out["budget_gb"] = lap.cache.factor_budget / 2 ** 30
    out["ratio"] = out["time"] / chol
    out["peak_gb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20
    out["cache_gb"] = lap.cache.nbytes / 2 ** 30
    print("RESULT " + json.dumps(out), flush=True)


COLUMNS = ["task", "n", "Cholesky (s)", "time ÷ Cholesky", "factorizations", "max rel. error at the checks",
           "certified bound (relative)", "peak (GB)", "factor cache (GB)"]


def cells(r):
    """One table row from a task's result."""
    def sci(key):
        return "—" if r.get(key) is None else f"{r[key]:.1e}"

    task = r["task"] + (f" {r['filter']}" if "filter" in r else "")
    bound = sci("eps") if "eps" in r else sci("bound_rel")
    return [task, f"{r['n']:,}", f"{r['chol']:.2f}", f"{r['ratio']:.1f}", str(r.get("factorizations", "—")),
            sci("err"), bound, f"{r['peak_gb']:.2f}", f"{r['cache_gb']:.2f}"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh")
    ap.add_argument("--box", type=int, default=0, help="a tetrahedral box of about this many vertices")
    ap.add_argument("--torus", type=int)
    ap.add_argument("--upsample", type=int, default=0)
    ap.add_argument("--tasks", default=",".join(TASKS))
    ap.add_argument("--task", help=argparse.SUPPRESS)
    ap.add_argument("--T", type=int, default=100, help="scales (times or energies)")
    ap.add_argument("--t1", type=float, default=1e-3)
    ap.add_argument("--t2", type=float, default=1e-1)
    ap.add_argument("--t", type=float, default=1e-2, help="time of the column/pairwise/one-to-all tasks")
    ap.add_argument("--m", type=int, default=100, help="sources (columns) or seeds (pairwise)")
    ap.add_argument("--k", type=int, default=100, help="eigsh pairs")
    ap.add_argument("--checks", type=int, default=8,
                    help="random check vertices (0: no reference, for shapes where it costs more than the task)")
    ap.add_argument("--filter", default="diffusion")
    ap.add_argument("--factor-budget", type=float, default=None,
                    help="byte budget (GiB) of the cached factorizations (default: 25%% of available memory)")
    ap.add_argument("--json-dir", help="also write the table as JSON in this folder (docs/results)")
    ap.add_argument("--table", default="multiscale", help="the table's name (its JSON file's stem)")
    args = ap.parse_args()
    if args.task:
        return run_task(args)
    base, skip = [], False
    for a in sys.argv[1:]:
        if skip or a.startswith(("--tasks", "--json-dir", "--table")):
            skip = a in ("--tasks", "--json-dir", "--table")
            continue
        base.append(a)
    table = Table(args.table, COLUMNS, args.json_dir)
    for task in args.tasks.split(","):
        variants = [["--filter", "diffusion"], ["--filter", "biharmonic"]] if task == "onetoall" else [[]]
        for extra in variants:
            cmd = [sys.executable, __file__, *base, "--task", task, *extra]
            res = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ))
            line = [x for x in res.stdout.splitlines() if x.startswith("RESULT ")]
            if not line:
                print(f"{task}: failed\n{res.stderr[-2000:]}", flush=True)
                continue
            table.add(*cells(json.loads(line[0][7:])))
    table.close()


if __name__ == "__main__":
    main()
