"""Heat-geodesic precompute and per-source solve time against libigl and potpourri3d, and one
Cholesky of B + tL.

``from (V, F)`` is the precompute as a user runs it, from the arrays
(``HeatGeodesics((V, F))``); ``prebuilt`` starts from a Laplacian built beforehand. libigl
and potpourri3d start from the arrays too. ``cold`` is the first call in a fresh process
(after the imports and reading the mesh; ours and libigl's each the first of its kind, in
alternating order): the median over ``--cold`` processes per order.

    OPENBLAS_NUM_THREADS=1 python benchmarks/geodesic_precompute.py [--meshes DIR] [--repeat 5] [--cold 5] [--cpu] [--json-dir DIR]

Each mesh is scaled to unit area. Each time is the median of ``--repeat`` runs in this
process, the contenders taking turns within each repetition (the machine's load drifts; a
ratio compares runs made seconds apart). ``solve`` is one single-source distance (ours:
``HeatGeodesics.compute``; libigl: ``heat_geodesics_solve``): the mean over ``--sources``
sources in a row, median over the repetitions.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from _results import Table  # beside this script

import spectral_igl as sig
from spectral_igl.applications.geodesics import HeatGeodesics
from spectral_igl.io import read_mesh
from spectral_igl.linalg import factorize

ROOT = Path(__file__).resolve().parents[1]


CLOCK = [time.perf_counter]


def timed(fn):
    t0 = CLOCK[0]()
    out = fn()
    return CLOCK[0]() - t0, out


def first_calls(path: Path, order: str) -> dict:
    """CPU or wall seconds of the first ``HeatGeodesics((V, F))`` ("o") and the first libigl
    precompute ("i") in this process, in ``order``; the mesh scaled to unit area by libigl
    (building nothing of ours before the call)."""
    import igl

    V, F = read_mesh(path)
    V = V / np.sqrt(igl.doublearea(V, F).sum() / 2)
    h = float(igl.avg_edge_length(V, F))

    def libigl():
        igl.heat_geodesics_precompute(V, F, h * h, igl.HeatGeodesicsData())

    calls = {"o": lambda: HeatGeodesics((V, F)), "i": libigl}
    return {k: timed(calls[k])[0] for k in order}


def cold(path: Path, runs: int, cpu: bool) -> tuple[float, float]:
    """Medians of the first calls (ours, libigl's) over ``runs`` fresh processes per order."""
    out = []
    for r in range(2 * runs):
        cmd = [sys.executable, __file__, "--first-call", str(path), "oi" if r % 2 == 0 else "io"]
        cmd += ["--cpu"] if cpu else []
        out.append(json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout))
    return float(np.median([o["o"] for o in out])), float(np.median([o["i"] for o in out]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", type=Path, default=ROOT.parent / "shared" / "data" / "meshes")
    ap.add_argument("--names", default="cow.obj,spot.obj,homer.obj,fandisk.obj,rocker-arm.obj,armadillo.obj")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--sources", type=int, default=40)
    ap.add_argument("--json-dir", help="also write the table as JSON in this folder (docs/results)")
    ap.add_argument("--cpu", action="store_true",
                    help="process CPU time instead of wall time (steadier on a loaded machine)")
    ap.add_argument("--cold", type=int, default=5, help="fresh processes per order for the cold columns")
    ap.add_argument("--first-call", nargs=2, metavar=("MESH", "ORDER"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.cpu:
        CLOCK[0] = time.process_time
    if args.first_call:
        print(json.dumps(first_calls(Path(args.first_call[0]), args.first_call[1])))
        return
    import igl

    try:
        import potpourri3d as pp3d
    except ImportError:
        pp3d = None
    table = Table("geodesic_precompute",
                  ["mesh", "n", "ours from (V, F) (s)", "ours prebuilt (s)", "libigl (s)", "potpourri3d (s)",
                   "(V, F) ÷ libigl", "prebuilt ÷ libigl", "cold: ours (s)", "cold: libigl (s)", "cold ÷ libigl", "prebuilt ÷ Cholesky", "solve: ours (ms)",
                   "solve: libigl (ms)", "solve ratio"], args.json_dir)
    for name in args.names.split(","):
        V, F = read_mesh(args.meshes / name)
        lap0 = sig.laplacian(V, F, mass="lumped")
        V = V / np.sqrt(lap0.area())
        lap = sig.laplacian(V, F, mass="lumped")
        h = float(igl.avg_edge_length(V, F))

        def libigl():
            data = igl.HeatGeodesicsData()
            igl.heat_geodesics_precompute(V, F, h * h, data)
            return data

        T = {k: [] for k in ("arrays", "ours", "libigl", "pp3d", "chol", "s_ours", "s_libigl")}
        sources = np.random.default_rng(0).choice(lap.n, args.sources, replace=False)
        for r in range(args.repeat):
            T["arrays"].append(timed(lambda: HeatGeodesics((V, F)))[0])
            dt, hg = timed(lambda: HeatGeodesics(lap))
            T["ours"].append(dt)
            dt, data = timed(libigl)
            T["libigl"].append(dt)
            if pp3d is not None:
                T["pp3d"].append(timed(lambda: pp3d.MeshHeatMethodDistanceSolver(V, F))[0])
            T["chol"].append(timed(lambda: factorize(lap.B + h * h * lap.L))[0])
            T["s_ours"].append(timed(lambda: [hg.compute(int(s)) for s in sources])[0] / len(sources))
            T["s_libigl"].append(timed(lambda: [igl.heat_geodesics_solve(data, np.array([s]))
                                                for s in sources])[0] / len(sources))
        m = {k: float(np.median(v)) if v else float("nan") for k, v in T.items()}
        c_ours, c_libigl = cold(args.meshes / name, args.cold, args.cpu)
        table.add(name, f"{lap.n:,}", f"{m['arrays']:.3f}", f"{m['ours']:.3f}", f"{m['libigl']:.3f}",
                  f"{m['pp3d']:.3f}", f"{m['arrays'] / m['libigl']:.2f}", f"{m['ours'] / m['libigl']:.2f}",
                  f"{c_ours:.3f}", f"{c_libigl:.3f}", f"{c_ours / c_libigl:.2f}",
                  f"{m['ours'] / m['chol']:.2f}", f"{1e3 * m['s_ours']:.2f}", f"{1e3 * m['s_libigl']:.2f}",
                  f"{m['s_ours'] / m['s_libigl']:.2f}")
    table.close()


if __name__ == "__main__":
    main()
