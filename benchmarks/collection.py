"""Shapes per minute: ``collection.run`` on 1 and 2 local workers against a plain Python loop.

The job is the heat kernel signature at t = 1e-3 and 1e-2 times each shape's area (a user
function, so that every shape gets the same relative scales), on the shared meshes. The
plain loop reads, builds the Laplacian and computes, and keeps nothing; ``run`` also hashes
the inputs, estimates memory, schedules, and writes one Zarr group per shape.

The scheduling overhead per shape is measured with a trivial job (the number of vertices) on
many small shapes: (wall time of the run − cluster start − time spent inside the tasks) / shapes.

    OPENBLAS_NUM_THREADS=1 python benchmarks/collection.py
    OPENBLAS_NUM_THREADS=1 python benchmarks/collection.py --memory   # estimate vs peak RSS
"""
from __future__ import annotations

import argparse
import logging
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

MESHES = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "meshes"


def hks_relative(name, lap):
    """HKS at t = 1e-3 and 1e-2 times the area (module level: shipped to workers by value)."""
    import spectral_igl as sig

    scale = float(lap.area()) if lap.domain == "triangle" else float(lap.mass.sum()) ** (2.0 / 3.0)
    return sig.hks(lap, np.array([1e-3, 1e-2]) * scale)


def n_vertices(name, lap):
    return np.array([lap.n])


def plain_loop(paths, fn):
    import spectral_igl as sig
    from spectral_igl.io import read_mesh

    t = time.perf_counter()
    for p in paths:
        V, C = read_mesh(p)
        fn(Path(p).stem, sig.laplacian(V, C))
    return time.perf_counter() - t


def cluster_start(workers):
    from distributed import Client, LocalCluster

    t = time.perf_counter()
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=logging.ERROR)
    client = Client(cluster)
    up = time.perf_counter() - t
    client.close()
    cluster.close()
    return up, time.perf_counter() - t


def timed_run(inputs, job, out, workers):
    from spectral_igl import collection

    shutil.rmtree(out, ignore_errors=True)
    t = time.perf_counter()
    s = collection.run(inputs, job, out, workers=workers, progress=False)
    wall = time.perf_counter() - t
    assert s.ok, str(s)
    res = collection.load(out, arrays=False).results
    inside = sum(r.meta["timings"]["total"] for r in res.values())
    t = time.perf_counter()
    s2 = collection.run(inputs, job, out, workers=workers, progress=False)
    rerun = time.perf_counter() - t
    assert len(s2.skipped) == len(res)
    return wall, inside, rerun


def memory_table(paths):
    """Peak resident memory of one shape's job in a fresh process against the estimate."""
    code = (
        "import sys, numpy as np\n"
        "def hwm():  # peak RSS of this address space (ru_maxrss would include the parent's)\n"
        "    line = [x for x in open('/proc/self/status') if x.startswith('VmHWM')][0]\n"
        "    return int(line.split()[1])\n"
        "sys.path.insert(0, sys.argv[2])\n"
        "from collection import hks_relative\n"
        "import spectral_igl as sig\n"
        "from spectral_igl.io import read_mesh\n"
        "from spectral_igl.collection import Job, estimate_memory\n"
        "from spectral_igl.collection.engine import estimate_nnz\n"
        "V, C = read_mesh(sys.argv[1])\n"
        "est = estimate_memory(len(V), estimate_nnz(len(V), C), 'tet' if C.shape[1] == 4 else 'triangle', "
        "Job.hks([1.0]))\n"
        "r0 = hwm()\n"
        "lap = sig.laplacian(V, C)\n"
        "hks_relative('x', lap)\n"
        "r1 = hwm()\n"
        "print(len(V), lap.L.nnz, (r1 - r0) / 1024, est / 2**20)\n")
    print("\n| mesh | n | nnz(L) | measured peak increase (MB) | estimate (MB) |")
    print("|---|---|---|---|---|")
    for p in paths:
        out = subprocess.run([sys.executable, "-c", code, str(p), str(Path(__file__).parent)],
                             capture_output=True, text=True, check=True).stdout.split()
        n, nnz, meas, est = int(out[0]), int(out[1]), float(out[2]), float(out[3])
        print(f"| {Path(p).stem} | {n:,} | {nnz:,} | {meas:.0f} | {est:.0f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default=str(MESHES), help="folder of meshes (default: the shared meshes)")
    ap.add_argument("--small", type=int, default=200, help="small shapes of the overhead run")
    ap.add_argument("--memory", action="store_true", help="also the memory estimate against peak RSS")
    ap.add_argument("--only-memory", action="store_true", help="only the memory table")
    args = ap.parse_args()
    from spectral_igl.collection import Job

    folder = Path(args.meshes)
    paths = sorted(str(p) for p in folder.iterdir() if p.suffix in (".obj", ".off", ".mesh"))
    if not paths:
        sys.exit(f"no meshes in {folder}")
    print(f"{len(paths)} meshes in {folder}; {os.cpu_count()} cores; "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")
    if args.only_memory:
        memory_table(paths)
        return
    job = Job.function(hks_relative)
    tmp = Path(tempfile.mkdtemp(prefix="collection-bench-"))
    try:
        loop = plain_loop(paths, hks_relative)
        rows = [("plain loop", loop, None, loop, None)]
        for w in (1, 2):
            up, updown = cluster_start(w)
            wall, inside, rerun = timed_run(paths, job, tmp / f"w{w}.zarr", w)
            rows.append((f"run, {w} worker{'s' if w > 1 else ''}", wall, updown, inside, rerun))
        n = len(paths)
        print("\n| | wall (s) | shapes per minute | cluster start + stop (s) | time inside the tasks, summed (s) | rerun, all skipped (s) |")
        print("|---|---|---|---|---|---|")
        for label, wall, updown, inside, rerun in rows:
            extra = "" if updown is None else f"{updown:.1f}"
            rr = "" if rerun is None else f"{rerun:.2f}"
            print(f"| {label} | {wall:.1f} | {60 * n / wall:.0f} | {extra} | {inside:.1f} | {rr} |")
        print(f"load average after the runs: {os.getloadavg()[0]:.1f}")

        from data_generators import icosphere

        V, F = icosphere(1)
        small = [(f"s{i:04d}", V * (1 + i * 1e-3), F) for i in range(args.small)]
        for w in (1, 2):
            up, updown = cluster_start(w)
            wall, inside, _ = timed_run(small, Job.function(n_vertices), tmp / f"o{w}.zarr", w)
            over = (wall - updown - inside / w) / len(small)
            print(f"\noverhead, {len(small)} shapes of {len(V)} vertices, {w} worker(s): wall {wall:.1f} s, "
                  f"cluster start + stop {updown:.1f} s, inside the tasks {inside:.2f} s in all: "
                  f"{1e3 * over:.1f} ms per shape")
        if args.memory:
            memory_table(paths)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
