"""One-call costs under the BLAS's default threads beside one thread, on a quiet machine and
with one core kept busy by another process.

Every other benchmark here runs with ``OPENBLAS_NUM_THREADS=1``; users run with the
default (one thread per core). Each configuration runs in a fresh process: a heat column
(t = 1e-3) and a biharmonic distance from (V, F) scaled to unit area, first and second
source, then the HKS at 16 times (the common-pole fits) and the default WKS, as wall
seconds and multiples of one Cholesky factorization of B + tL (cholespy) in the same
process. ``--busy`` adds the rows with a spinning process on one core (it is
stopped at the end).

    python benchmarks/threads.py ../shared/data/meshes/armadillo.obj --busy
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

CALLS = ("heat column, 1st", "heat column, 2nd", "biharmonic, 1st", "biharmonic, 2nd",
         "HKS at 16 times (common poles)", "WKS, default grid")


def child(path, t):
    import spectral_igl as sig
    from spectral_igl.io import read_mesh
    from spectral_igl.linalg import factorize

    V, F = read_mesh(path)[:2]
    lap = sig.laplacian(V, F)
    lap = sig.laplacian(V / np.sqrt(lap.area()), F)
    start = time.perf_counter()
    factorize(lap.B + t * lap.L)
    chol = time.perf_counter() - start
    runs = [lambda: sig.heat_kernel(lap, t, 0), lambda: sig.heat_kernel(lap, t, 17),
            lambda: sig.biharmonic_distance(lap, 0), lambda: sig.biharmonic_distance(lap, 17),
            lambda: sig.hks(lap, np.geomspace(1e-4, 1e-1, 16)), lambda: sig.wks(lap, method="auto")]
    out = []
    for fn in runs:
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    print(json.dumps({"n": lap.n, "chol": chol, "times": out}))


def run(path, t, threads):
    env = dict(os.environ)
    env.pop("OPENBLAS_NUM_THREADS", None)
    if threads is not None:
        env["OPENBLAS_NUM_THREADS"] = str(threads)
    res = subprocess.run([sys.executable, __file__, path, "-t", str(t), "--child"], env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("-t", type=float, default=1e-3, help="heat time (unit area)")
    ap.add_argument("--busy", action="store_true", help="also with one core kept busy")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return child(args.meshes[0], args.t)
    loads = [False, True] if args.busy else [False]
    print("| mesh | n | machine | call | default threads | OPENBLAS_NUM_THREADS=1 |")
    print("|---|---|---|---|---|---|")
    for path in args.meshes:
        for busy in loads:
            spin = subprocess.Popen([sys.executable, "-c", "while True: pass"]) if busy else None
            try:
                res = {k: run(path, args.t, k) for k in (None, 1)}
            finally:
                if spin is not None:
                    spin.kill()
                    spin.wait()
            for i, call in enumerate(CALLS):
                cells = [f"{r['times'][i]:.2f} s ({r['times'][i] / r['chol']:.2f}×)" for r in res.values()]
                print(f"| {os.path.basename(path)} | {res[1]['n']} | {'one core busy' if busy else 'quiet'} "
                      f"| {call} | {cells[0]} | {cells[1]} |", flush=True)


if __name__ == "__main__":
    main()
