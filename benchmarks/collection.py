"""Shapes per minute: ``collection.run`` on 1 and 2 local workers against a plain Python loop.

The job is the heat kernel signature at t = 1e-3 and 1e-2 times each shape's area (a user
function, so that every shape gets the same relative scales), on the shared meshes.

What each row includes (the imports of a fresh process are left out of every row, and
printed apart):

- "plain loop": in this process, after its imports: read, build the Laplacian, compute,
  keep nothing. Its first shape pays the first calls (libigl, the compiled LDLᵀ extension).
- "plain loop as a script": the same loop in a fresh process (the honest twin of a run,
  which is also a fresh process).
- "run, w workers": ``collection.run`` in a fresh process, as a user's script calls it:
  the cluster's start (workers forked from a server that imports the package), dispatch,
  hashing the inputs, computing, writing one Zarr group per shape (synced), the stop.
- "run, 2 workers, on a kept cluster": the same, on a cluster the script started before
  (``collection.local_cluster``, as a session of several runs keeps one), so without the
  cluster's start and stop.

The machine may be shared, so every row also gives CPU time: the loop's, the sum inside the
tasks (``time.process_time`` of the worker around each shape; the task thread's own
``thread_time`` is printed below the table) and the client's (which, on a local cluster,
also runs the scheduler). "in-task / loop" compares the CPU of the same work in a worker and
in the loop; "predicted on a quiet machine" is the wall time the CPU accounting implies on
``os.cpu_count()`` idle cores: the busiest worker's task CPU, or all CPU spent divided by the
cores, whichever is larger; "with start and stop" adds the run's own wall before its first
task and after its last (read from the tasks' start times: these are wall times, inflated
by a busy machine). The timeline lines say where each run's wall went, per worker.

The row "2 plain loops in parallel" is the machine's ceiling for that split: the shapes
each worker of the 2-worker run computed, each set in a plain loop in its own fresh
process, both at once; their CPU is compared with each set's run alone in a fresh process
just before (two busy processes share the caches, memory bandwidth and clock). The
"ceiling" line bounds the speed-up from the largest shape's share and the start and stop.

The scheduling overhead per shape is measured with a trivial job (the number of vertices) on
many small shapes: (wall − before the first task − after the last − time inside the tasks
/ workers) / shapes.

    OPENBLAS_NUM_THREADS=1 python benchmarks/collection.py --small 100           # the table
    OPENBLAS_NUM_THREADS=1 python benchmarks/collection.py --count 1000 --only-count   # 1,000 shapes
    OPENBLAS_NUM_THREADS=1 python benchmarks/collection.py --loopback --only-loopback  # dask CLI
    OPENBLAS_NUM_THREADS=1 python benchmarks/collection.py --memory   # estimate vs peak RSS
"""
from __future__ import annotations

import argparse
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
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


def load_avg() -> str:
    return " ".join(open("/proc/loadavg").read().split()[:3]) if os.path.exists("/proc/loadavg") \
        else f"{os.getloadavg()[0]:.2f}"


def client_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def plain_loop(paths, fn):
    """(wall, CPU, CPU of the job alone, {name: (CPU of read + Laplacian + job, of the job)})
    over ``paths``."""
    import spectral_igl as sig
    from spectral_igl.io import read_mesh

    t, c, job_cpu, per_shape = time.perf_counter(), time.process_time(), 0.0, {}
    for p in paths:
        c0 = time.process_time()
        V, C = read_mesh(p)
        lap = sig.laplacian(V, C)
        c1 = time.process_time()
        fn(Path(p).stem, lap)
        c2 = time.process_time()
        job_cpu += c2 - c1
        per_shape[Path(p).stem] = (c2 - c0, c2 - c1)
    return time.perf_counter() - t, time.process_time() - c, job_cpu, per_shape


# a plain loop in a fresh process: imports, says "ready", waits for "go", runs, prints JSON
_LOOP = """
import json, sys, time
c0 = time.process_time()
sys.path.insert(0, sys.argv[1])
from collection import hks_relative, plain_loop
import spectral_igl
from spectral_igl.io import read_mesh
paths = json.loads(sys.stdin.readline())
print(json.dumps({"import_cpu": time.process_time() - c0}), flush=True)
sys.stdin.readline()
wall, cpu, job_cpu, per_shape = plain_loop(paths, hks_relative)
print(json.dumps(dict(wall=wall, cpu=cpu, job_cpu=job_cpu)), flush=True)
"""


def parallel_loops(halves):
    """Plain loops over each list of ``halves`` at once, one fresh process each (started and
    imported first, then released together): what the machine gives two busy processes."""
    import json

    procs = [subprocess.Popen([sys.executable, "-c", _LOOP, str(Path(__file__).parent)],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True) for _ in halves]
    for proc, half in zip(procs, halves):
        proc.stdin.write(json.dumps(half) + "\n")
        proc.stdin.flush()
    ready = [json.loads(proc.stdout.readline()) for proc in procs]
    t = time.perf_counter()
    for proc in procs:
        proc.stdin.write("go\n")
        proc.stdin.flush()
    results = [dict(json.loads(proc.stdout.readline()), **r) for proc, r in zip(procs, ready)]
    wall = time.perf_counter() - t
    for proc in procs:
        proc.wait()
    return wall, results


# ``collection.run`` as a script: a fresh process imports, runs once, prints JSON
_RUN_ONE = """
import json, resource, sys, time
t0 = time.perf_counter()
sys.path.insert(0, sys.argv[1])
from collection import hks_relative, n_vertices, small_shapes
from spectral_igl import collection
from spectral_igl.collection import Job
if __name__ == "__main__":
    spec = json.loads(sys.stdin.readline())
    inputs = small_shapes(spec["small"]) if spec["small"] else spec["paths"]
    job = Job.function(hks_relative if spec["job"] == "hks" else n_vertices)
    imports = time.perf_counter() - t0
    client = None
    if spec.get("kept"):            # a cluster started beforehand and kept (collection.local_cluster)
        from distributed import Client
        cluster = collection.local_cluster(spec["workers"])
        client = Client(cluster)
        client.wait_for_workers(spec["workers"])
    r0 = resource.getrusage(resource.RUSAGE_SELF)
    e0, t = time.time(), time.perf_counter()
    s = collection.run(inputs, job, spec["out"], workers=spec["workers"], scheduler=client, progress=False)
    wall, e1 = time.perf_counter() - t, time.time()
    r1 = resource.getrusage(resource.RUSAGE_SELF)
    cpu = r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime
    print(json.dumps(dict(ok=s.ok, wall=wall, epoch=[e0, e1], client_cpu=cpu, client_imports=imports)))
"""


def small_shapes(count):
    """``count`` copies of a 42-vertex sphere, each scaled a little (distinct inputs)."""
    from data_generators import icosphere

    V, F = icosphere(1)
    return [(f"s{i:04d}", V * (1 + i * 1e-3), F) for i in range(count)]


def run_as_script(out, workers, job="hks", paths=(), small=0, kept=False):
    """``collection.run`` in a fresh process, as a user's script runs it (the client's
    imports apart): wall, epoch of start and end, the client's CPU during the run (it also
    runs the scheduler and starts the cluster)."""
    import json

    spec = dict(out=str(out), workers=workers, job=job, paths=list(paths), small=small, kept=kept)
    proc = subprocess.run([sys.executable, "-c", _RUN_ONE, str(Path(__file__).parent)], input=json.dumps(spec),
                          capture_output=True, text=True, check=True)
    res = json.loads(proc.stdout.strip().splitlines()[-1])
    assert res["ok"], proc.stderr[-2000:]
    return res


def task_times(out):
    """Per-shape timings of a store: sums of wall and CPU inside the tasks (the task's
    process and its own thread), CPU per worker, the shapes each worker computed, and each
    worker's first task start, last task end and busy wall (seconds since the epoch)."""
    from spectral_igl import collection

    res = collection.load(out, arrays=False).results
    sums = {k: sum(r.meta["timings"].get(k, 0.0) for r in res.values())
            for k in ("total", "cpu", "thread_cpu", "compute_cpu", "compute_thread_cpu", "compute")}
    per_worker, split, span = {}, {}, {}
    for name, r in res.items():
        key, t = (r.meta["host"], r.meta["pid"]), r.meta["timings"]
        per_worker[key] = per_worker.get(key, 0.0) + t["cpu"]
        split.setdefault(key, []).append(name)
        first, last, busy = span.get(key, (np.inf, -np.inf, 0.0))
        span[key] = (min(first, t["started"]), max(last, t["started"] + t["total"]), busy + t["total"])
    return dict(inside=sums["total"], cpu=sums["cpu"], thread_cpu=sums["thread_cpu"],
                job_cpu=sums["compute_cpu"], job_thread_cpu=sums["compute_thread_cpu"],
                compute=sums["compute"], per_worker=per_worker, split=list(split.values()),
                span=list(span.values()), n=len(res))


def timed_run(out, workers, job="hks", paths=(), small=0, kept=False):
    """A run as a script (:func:`run_as_script`), its store's task timings, and a rerun in
    this process that skips everything."""
    from spectral_igl import collection
    from spectral_igl.collection import Job

    shutil.rmtree(out, ignore_errors=True)
    r = run_as_script(out, workers, job, paths, small, kept)
    tt = task_times(out)
    inputs = small_shapes(small) if small else list(paths)
    t = time.perf_counter()
    s2 = collection.run(inputs, Job.function(hks_relative if job == "hks" else n_vertices), out,
                        workers=workers, progress=False)
    rerun = time.perf_counter() - t
    assert len(s2.skipped) == tt["n"]
    e0, e1 = r["epoch"]
    end = max(last for _, last, _ in tt["span"])
    start = min(first for first, _, _ in tt["span"]) - e0
    return dict(r, rerun=rerun, start=start, stop=e1 - end, **tt)


def timeline(r) -> str:
    """Where a run's wall went: until each worker's first task (cluster start, the worker's
    imports, dispatch), inside tasks, between tasks, idle at the end, after the last task."""
    e0, e1 = r["epoch"]
    span = sorted(r["span"])
    end = max(last for _, last, _ in span)
    firsts = " / ".join(f"{first - e0:.2f}" for first, _, _ in span)
    busy = " / ".join(f"{b:.2f}" for _, _, b in span)
    gaps = " / ".join(f"{last - first - b:.2f}" for first, last, b in span)
    idle = " / ".join(f"{end - last:.2f}" for _, last, _ in span)
    return (f"first task at {firsts} s (cluster start, a worker's imports, dispatch), inside tasks {busy} s, "
            f"between tasks {gaps} s, idle at the end {idle} s (per worker); after the last task "
            f"{e1 - end:.2f} s (stop); wall {e1 - e0:.2f} s")


def speed_table(paths, tmp):
    cores = os.cpu_count() or 1
    print(f"load average before: {load_avg()}")
    lw, lc, ljob, per_shape = plain_loop(paths, hks_relative)
    fresh = parallel_loops([paths])[1][0]        # the same loop as a script: a fresh process
    n = len(paths)
    print("\n| | wall (s) | shapes per minute | CPU (s): tasks / busiest worker / client | job CPU in-task / loop "
          f"| predicted on {cores} quiet cores, without / with start and stop (s) "
          "| predicted speed-up over the loop, without / with | rerun, all skipped (s) |")
    print("|---|---|---|---|---|---|---|---|")
    print(f"| plain loop | {lw:.1f} | {60 * n / lw:.0f} | {lc:.1f} | 1 | {lc:.1f} | 1 | |")
    print(f"| plain loop as a script | {fresh['wall']:.1f} | {60 * n / fresh['wall']:.0f} | {fresh['cpu']:.1f} | "
          f"{fresh['job_cpu'] / ljob:.2f} | {fresh['cpu']:.1f} | {lc / fresh['cpu']:.2f} | |")
    lines = []
    for w, kept in ((1, False), (2, False), (2, True)):
        r = timed_run(tmp / f"w{w}{'k' if kept else ''}.zarr", w, paths=paths, kept=kept)
        busiest = max(r["per_worker"].values())
        # the client's CPU includes the cluster's start and stop (and, locally, the scheduler)
        pred = max(busiest, (r["cpu"] + r["client_cpu"]) / cores)
        full = pred + r["start"] + r["stop"]
        label = f"run, {w} worker{'s' if w > 1 else ''}" + (", on a kept cluster (local_cluster)" if kept else "")
        print(f"| {label} | {r['wall']:.1f} | {60 * n / r['wall']:.0f} | "
              f"{r['cpu']:.1f} / {busiest:.1f} / {r['client_cpu']:.1f} | {r['job_cpu'] / ljob:.2f} | "
              f"{pred:.1f} / {full:.1f} | {lc / pred:.2f} / {lc / full:.2f} | {r['rerun']:.2f} |")
        if w == 2 and not kept:
            started = r                 # the ceiling counts a run's own start and stop
        lines.append(f"{label}: {timeline(r)}")
        lines.append(f"{label}: job CPU {r['job_cpu']:.2f} s in the tasks' processes, "
                     f"{r['job_thread_cpu']:.2f} s in the task threads (the loop: {ljob:.2f} s); all tasks "
                     f"{r['cpu']:.2f} s, {r['thread_cpu']:.2f} s in the task threads")
    print(f"\nimports before the first shape, a fresh process: the loop's {fresh['import_cpu']:.2f} s CPU, "
          f"the run's client {r['client_imports']:.2f} s wall (both left out of the rows)")
    for line in lines:
        print(line)
    ceiling(paths, started["split"], per_shape, lc, cores, started["start"] + started["stop"])
    print(f"\nloop: job CPU {ljob:.1f} s of {lc:.1f} s CPU; load average after: {load_avg()}")


def ceiling(paths, split, per_shape, loop_cpu, cores, startstop):
    """The row "two plain loops in parallel": the shapes of each worker of the last run, each
    in a plain loop in its own process, both at once, against each set alone in a fresh
    process just before (the same conditions); and the bound the largest shape, the
    cluster's start and stop and the workers' imports set."""
    by_name = {Path(p).stem: p for p in paths}
    halves = [[by_name[k] for k in names] for names in split]
    alone = [parallel_loops([half])[1][0] for half in halves]
    wall, res = parallel_loops(halves)
    solo = [r["cpu"] for r in alone]
    solo_job = sum(r["job_cpu"] for r in alone)
    busiest = max(r["cpu"] for r in res)
    cpu = sum(r["cpu"] for r in res)
    print(f"\n| {len(res)} plain loops in parallel (each on one worker's shapes) | {wall:.1f} | "
          f"{60 * len(paths) / wall:.0f} | {cpu:.1f} / {busiest:.1f} / | "
          f"{sum(r['job_cpu'] for r in res) / solo_job:.2f} | {busiest:.1f} / | "
          f"{loop_cpu / busiest:.2f} / | |")
    print("\nparallel loops: CPU of each half " + ", ".join(
        f"{r['cpu']:.2f} s against {s:.2f} s alone ({r['cpu'] / s:.2f}x)" for r, s in zip(res, solo))
        + "; a fresh process's imports before the first shape "
        f"{np.mean([r['import_cpu'] for r in res]):.2f} s CPU (the loop rows exclude them; a local run's workers are forked from a server that has imported them)")
    name, (big, _) = max(per_shape.items(), key=lambda kv: kv[1][0])
    bound = max(big, loop_cpu / cores)
    full = bound + startstop
    print(f"ceiling: largest shape {name}, {big:.2f} s of the loop's {loop_cpu:.1f} s CPU "
          f"({100 * big / loop_cpu:.0f} %): on {cores} workers at best {bound:.2f} s, a speed-up of at most "
          f"{loop_cpu / bound:.2f}; with the last run's wall before its first task and after its last "
          f"({startstop:.2f} s: cluster start, a worker's imports, stop) at best {full:.2f} s, a speed-up of "
          f"at most {loop_cpu / full:.2f}")


def overhead(n_small, tmp):
    for w in (1, 2):
        r = timed_run(tmp / f"o{w}.zarr", w, job="n", small=n_small)
        over = (r["wall"] - r["start"] - r["stop"] - r["compute"] / w) / n_small
        print(f"overhead, {n_small} shapes of 42 vertices, {w} worker(s): wall {r['wall']:.2f} s, of which "
              f"{r['start']:.2f} s before the first task and {r['stop']:.2f} s after the last, job inside the "
              f"tasks {r['compute']:.3f} s, task CPU {1e3 * r['cpu'] / n_small:.1f} ms/shape, client CPU "
              f"{1e3 * r['client_cpu'] / n_small:.1f} ms/shape (with the cluster's start): "
              f"{1e3 * over:.1f} ms per shape; load {load_avg()}")


# ---- a thousand shapes ----------------------------------------------------------------------
def make_dataset(folder: Path, count: int, meshes: Path, seed: int = 0):
    """``count`` mesh files: mostly small (decimated and resampled public models, spheres,
    tori; 100-3,000 vertices), 2.5 % mid-sized (about 10k vertices), and three large ones
    (95k-141k vertices). Returns the paths."""
    import igl

    from data_generators import icosphere, torus
    from data_generators.perturb import mean_edge_length, midpoint_subdivide, normal_noise, resample
    from spectral_igl.io import read_mesh, write_mesh

    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    models = {}
    for name in ("spot.obj", "cow.obj", "homer.obj", "cheburashka.obj", "fertility.off", "rocker-arm.obj",
                 "armadillo.obj", "stanford-bunny.obj"):
        V, F = read_mesh(meshes / name)
        models[Path(name).stem] = (np.asarray(V, float), np.asarray(F, np.int64))

    def decimated(V, F, faces):
        if len(F) <= faces:
            return V, F
        out = igl.decimate(V, F, faces)
        U, G = (out[1], out[2]) if isinstance(out[0], (bool, np.bool_)) else (out[0], out[1])
        return np.asarray(U, float), np.asarray(G, np.int64)

    bases = [decimated(V, F, f) for V, F in models.values() for f in (400, 1000, 2500)]
    mids = [decimated(V, F, 16000) for V, F in models.values()]
    bases += [icosphere(2), icosphere(3), torus(1.0, 0.4, 32, 12), torus(1.0, 0.3, 48, 16)]
    large = [resample(*models["armadillo"], 1.0, seed=1),                  # 129k vertices
             midpoint_subdivide(*models["stanford-bunny"]),                 # 141k vertices
             resample(*models["armadillo"], 0.6, seed=2)]                   # 95k vertices
    n_mid = max(1, count // 40)
    paths = []
    for i in range(count):
        if i < len(large):
            V, F = large[i]
        elif i < len(large) + n_mid:
            V, F = resample(*mids[i % len(mids)], 0.5, seed=i)          # about 10k vertices
        else:
            V, F = bases[rng.integers(len(bases))]
            V, F = resample(V, F, float(rng.uniform(0.1, 0.6)), seed=i)
            V = normal_noise(V, F, 0.05 * mean_edge_length(V, F), seed=i)
        p = folder / f"shape{i:05d}{'.off' if i % 2 else '.obj'}"
        write_mesh(p, V, F)
        paths.append(str(p))
    return paths


_RUN = """
import sys
sys.path.insert(0, {bench!r})
from collection import hks_relative
from spectral_igl import collection
from spectral_igl.collection import Job
if __name__ == "__main__":
    collection.run({folder!r}, Job.function(hks_relative), {out!r}, workers=2, progress=False)
"""


def thousand(count, meshes, tmp, keep=None):
    from spectral_igl import collection
    from spectral_igl.collection import Job

    folder = Path(keep) if keep else tmp / "dataset"
    t = time.perf_counter()
    paths = sorted(str(p) for p in folder.glob("shape*")) if folder.is_dir() else []
    if len(paths) != count:
        shutil.rmtree(folder, ignore_errors=True)
        paths = make_dataset(folder, count, meshes)
    from spectral_igl.io import read_mesh

    sizes = sorted(len(read_mesh(p)[0]) for p in paths[:3] + paths[3:][::50])
    print(f"{count} shapes in {folder} ({time.perf_counter() - t:.0f} s to make or find); sampled sizes "
          f"{sizes[0]}..{sizes[-1]} vertices, median {sizes[len(sizes) // 2]}; load {load_avg()}")
    out = tmp / "thousand.zarr"
    shutil.rmtree(out, ignore_errors=True)
    # 1. killed part-way (the whole process group), then resumed
    script = tmp / "run.py"
    script.write_text(_RUN.format(bench=str(Path(__file__).parent), folder=str(folder), out=str(out)))
    proc = subprocess.Popen([sys.executable, str(script)], start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        while proc.poll() is None and sum(1 for _ in out.glob("shape*")) < count // 3:
            time.sleep(0.2)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    first = sum(1 for _ in out.glob("shape*"))
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    c0, t = client_cpu(), time.perf_counter()
    s = collection.run(str(folder), Job.function(hks_relative), out, workers=2, progress=True)
    wall, ccpu = time.perf_counter() - t, client_cpu() - c0
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    assert s.ok, str(s)
    tt = task_times(out)
    print(f"killed after {first} groups; resumed: {len(s.skipped)} skipped, {len(s.done)} done in {wall:.1f} s "
          f"({60 * len(s.done) / wall:.0f} shapes/min); task CPU {tt['cpu']:.0f} s in all, client CPU "
          f"{ccpu:.1f} s; client peak RSS {rss0 / 1024:.0f} MB before the run, {rss1 / 1024:.0f} MB after; "
          f"load {load_avg()}")
    t = time.perf_counter()
    s2 = collection.run(str(folder), Job.function(hks_relative), out, workers=2, progress=False)
    print(f"restart with every shape done: {len(s2.skipped)} skipped in {time.perf_counter() - t:.2f} s")
    res = collection.load(out, arrays=False).results
    small = [r.meta for r in res.values() if r.meta["n"] <= 5000]
    print(f"small shapes (n <= 5000): {len(small)}, mean n {np.mean([m['n'] for m in small]):.0f}, "
          f"mean in-task wall {1e3 * np.mean([m['timings']['total'] for m in small]):.0f} ms, of which the "
          f"job {1e3 * np.mean([m['timings']['compute'] for m in small]):.0f} ms; largest n "
          f"{max(r.meta['n'] for r in res.values())}")


# ---- a scheduler and workers started as separate processes -------------------------------------
def loopback(paths, tmp, workers=3):
    """``dask scheduler`` and ``workers`` ``dask worker`` processes on 127.0.0.1; one worker
    killed at a third of the shapes and one added; the results against a 1-worker run."""
    from spectral_igl import collection
    from spectral_igl.collection import Job

    out, ref = tmp / "loopback.zarr", tmp / "single.zarr"
    job = Job.function(hks_relative)
    with collection.LoopbackCluster(workers, folder=tmp / "cluster", memory_limit="4GB", timeout=60) as cluster, \
            cluster.client() as client:
        box = {}
        t = time.perf_counter()
        th = threading.Thread(target=lambda: box.update(s=collection.run(
            paths, job, out, scheduler=client, progress=False)))
        th.start()
        while th.is_alive() and sum(1 for p in out.glob("*") if not p.name.startswith(".")
                                    and (p / "zarr.json").is_file()) < len(paths) // 3:
            time.sleep(0.05)
        cluster.kill_worker(0)
        killed_at = time.perf_counter() - t
        cluster.add_worker()
        th.join()
        wall = time.perf_counter() - t
    s = box["s"]
    collection.run(paths, job, ref, workers=1, progress=False)
    a, b = collection.load(out).results, collection.load(ref).results
    same = all(np.array_equal(a[k]["result"], b[k]["result"]) for k in b)
    pids = {r.meta["pid"] for r in a.values()}
    print(f"loopback: {len(s.done)} done, {len(s.failed)} failed in {wall:.1f} s on {workers} workers, one "
          f"killed at {killed_at:.1f} s and one added; results from {len(pids)} worker processes; "
          f"bitwise equal to a 1-worker LocalCluster run: {same}; load {load_avg()}")


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
    ap.add_argument("--count", type=int, default=0, help="also a run over this many generated shapes")
    ap.add_argument("--dataset", default=None, help="folder to keep the generated shapes in (reused)")
    ap.add_argument("--only-count", action="store_true", help="only the --count run")
    ap.add_argument("--loopback", action="store_true",
                    help="also dask scheduler + dask worker processes on 127.0.0.1, one killed, one added")
    ap.add_argument("--only-loopback", action="store_true", help="only the loopback run")
    ap.add_argument("--memory", action="store_true", help="also the memory estimate against peak RSS")
    ap.add_argument("--only-memory", action="store_true", help="only the memory table")
    args = ap.parse_args()
    folder = Path(args.meshes)
    paths = sorted(str(p) for p in folder.iterdir() if p.suffix in (".obj", ".off", ".mesh"))
    if not paths:
        sys.exit(f"no meshes in {folder}")
    print(f"{len(paths)} meshes in {folder}; {os.cpu_count()} cores; "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")
    if args.only_memory:
        memory_table(paths)
        return
    tmp = Path(tempfile.mkdtemp(prefix="collection-bench-"))
    try:
        if args.only_count:
            thousand(args.count or 1000, folder, tmp, args.dataset)
            return
        if args.only_loopback:
            loopback(paths, tmp)
            return
        speed_table(paths, tmp)
        overhead(args.small, tmp)
        if args.count:
            thousand(args.count, folder, tmp, args.dataset)
        if args.loopback:
            loopback(paths, tmp)
        if args.memory:
            memory_table(paths)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
