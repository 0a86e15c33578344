"""Shape collections on dask.distributed: results equal the single-process functions, failures
are recorded without stopping the others, reruns skip, interrupted runs resume, and a worker
that dies during a task is replaced and the task retried."""
from __future__ import annotations

import json
import logging
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")
pytest.importorskip("zarr", minversion="3")

import cloudpickle  # noqa: E402  (a dependency of distributed)

import spectral_igl as sig  # noqa: E402
from data_generators import box_tets, icosphere, torus  # noqa: E402
from spectral_igl import collection  # noqa: E402
from spectral_igl.collection import Job  # noqa: E402
from spectral_igl.io import read_mesh, write_mesh  # noqa: E402

from conftest import MESH_DIR  # noqa: E402

# user functions of this module travel to the workers by value (workers cannot import tests/)
cloudpickle.register_pickle_by_value(sys.modules[__name__])

REL = 1e-12


@pytest.fixture(scope="module")
def client():
    """A LocalCluster of two single-threaded worker processes; a dying worker is retried once."""
    import dask
    from distributed import Client, LocalCluster

    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR)
        c = Client(cluster)
        try:
            yield c
        finally:
            c.close()
            cluster.close()


def _close(a, b):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    scale = max(np.max(np.abs(b)), np.finfo(float).tiny)
    return np.max(np.abs(a - b)) <= REL * scale


def _shapes():
    V, F = icosphere(2)                       # 162 vertices, unit sphere
    Vt, Ft = torus(1.0, 0.4, 24, 12)
    Vb, T = box_tets((5, 4, 3))               # tetrahedra
    P = icosphere(3)[0]                       # a point set (642 points)
    return {"sphere": (V, F), "torus": (Vt, Ft), "box": (Vb, T), "points": (P, None)}


def _lap(V, C):
    return sig.point_cloud_laplacian(V) if C is None else sig.laplacian(V, C)


def test_results_equal_single_process(client, tmp_path):
    shapes = _shapes()
    times = [1e-2, 1e-1]
    out = tmp_path / "hks.zarr"
    s = collection.run(shapes, Job.hks(times), out, scheduler=client, progress=False)
    assert sorted(s.done) == sorted(shapes) and not s.failed and not s.skipped
    results, failures = collection.load(out)
    assert failures == [] and sorted(results) == sorted(shapes)
    for name, (V, C) in shapes.items():
        lap = _lap(V, C)
        H = results[name]["hks"]
        assert H.shape == (lap.n, 2)
        assert _close(H, sig.hks(lap, times)), name
        meta = results[name].meta
        assert meta["n"] == lap.n and meta["version"] == sig.__version__
        assert meta["params"]["times"] == times and meta["timings"]["compute"] > 0
        assert len(meta["mesh_hash"]) == 64 and len(meta["input_hash"]) == 64
    # the stored bounds are honest against the dense ground truth of the small sphere
    lap = _lap(*shapes["sphere"])
    lam, X = sig.dense_eigs(lap)
    bounds = results["sphere"].meta["bounds"]["abs_error_bound"]
    for j, t in enumerate(times):
        exact = (X ** 2) @ np.exp(-t * lam)
        err = np.max(np.abs(results["sphere"]["hks"][:, j] - exact))
        assert 0 < bounds[j] and err <= bounds[j]

    # one-to-all distances from two sources, eigenvalues, a kernel diagonal, a user function
    V, F = shapes["torus"]
    lap = _lap(V, F)
    two = {"torus": (V, F), "sphere": shapes["sphere"]}
    out2 = tmp_path / "dist.zarr"
    collection.run(two, Job.distances([0, 7], "biharmonic"), out2, scheduler=client, progress=False)
    D = collection.load(out2).results["torus"]
    assert D["distances"].shape == (2, lap.n) and list(D["sources"]) == [0, 7]
    for row, src in zip(D["distances"], [0, 7]):
        assert _close(row, sig.biharmonic_distance(lap, src))
    out3 = tmp_path / "eig.zarr"
    collection.run(two, Job.eigenvalues(9), out3, scheduler=client, progress=False)
    lam = collection.load(out3).results["sphere"]["eigenvalues"]
    assert _close(lam, sig.eigs(_lap(*shapes["sphere"]), 9)[0])
    # and they are the sphere's: 0, then l(l+1) = 2 three times, 6 five times, to O(h^2)
    assert abs(lam[0]) < 1e-8 and np.allclose(lam[1:4], 2, rtol=0.03) and np.allclose(lam[4:9], 6, rtol=0.05)
    out4 = tmp_path / "diag.zarr"
    collection.run(two, Job.kernel_diagonal("heat", t=0.05), out4, scheduler=client, progress=False)
    assert _close(collection.load(out4).results["torus"]["diagonal"],
                  sig.kernel_diagonal(lap, sig.filters.heat(0.05)))
    out5 = tmp_path / "user.zarr"
    collection.run(two, Job.function(_mass_and_degree, params={"v": 1}), out5, scheduler=client,
                   progress=False)
    R = collection.load(out5).results["torus"]
    assert np.array_equal(R["mass"], lap.mass) and np.array_equal(R["degree"], np.diff(lap.L.indptr))


def _mass_and_degree(name, lap):
    return {"mass": lap.mass, "degree": np.diff(lap.L.indptr)}


def test_corrupt_file_among_good_ones(client, tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    V, F = icosphere(2)
    write_mesh(folder / "good.obj", V, F)
    write_mesh(folder / "box.mesh", *box_tets((4, 3, 3)))
    (folder / "garbage.obj").write_text("v 1 2\nf 1 2 9\n")
    bad = F.copy()
    bad[0, 0] = 10_000
    (folder / "badindex.off").write_text(
        "OFF\n%d %d 0\n" % (len(V), len(F))
        + "".join("%.17g %.17g %.17g\n" % tuple(v) for v in V) + "".join("3 %d %d %d\n" % tuple(f) for f in bad))
    out = tmp_path / "store"
    s = collection.run(str(folder / "*"), Job.hks([0.05]), out, scheduler=client, progress=False)
    assert sorted(s.done) == ["box", "good"] and sorted(s.failed) == ["badindex", "garbage"]
    results, failures = collection.load(out)
    assert sorted(results) == ["box", "good"]
    errors = {f["name"]: f["error"] for f in failures}
    assert "not a valid OBJ" in errors["garbage"] and "ValueError" in errors["garbage"]
    assert "10000" in errors["badindex"]
    assert all(f["source"].endswith(("garbage.obj", "badindex.off")) for f in failures)
    assert _close(results["good"]["hks"][:, 0], sig.hks(sig.laplacian(V, F), 0.05))
    # a rerun recomputes nothing: the good shapes are skipped, the corrupt ones reported again
    s2 = collection.run(str(folder / "*"), Job.hks([0.05]), out, scheduler=client, progress=False)
    assert s2.done == [] and sorted(s2.skipped) == ["box", "good"] and sorted(s2.failed) == ["badindex", "garbage"]
    # repairing a file recomputes that file only
    write_mesh(folder / "badindex.off", V, F)
    s3 = collection.run(str(folder / "*"), Job.hks([0.05]), out, scheduler=client, progress=False)
    assert s3.done == ["badindex"] and sorted(s3.skipped) == ["box", "good"]


def test_rerun_skips_and_new_parameters_recompute(client, tmp_path):
    shapes = _shapes()
    out = tmp_path / "s.zarr"
    collection.run(shapes, Job.hks([0.1]), out, scheduler=client, progress=False)
    stamps = {n: (out / n / "zarr.json").stat().st_mtime_ns for n in shapes}
    s = collection.run(shapes, Job.hks([0.1]), out, scheduler=client, progress=False)
    assert s.done == [] and sorted(s.skipped) == sorted(shapes) and s.ok
    assert stamps == {n: (out / n / "zarr.json").stat().st_mtime_ns for n in shapes}
    # other parameters, other mass matrix, or a changed input: recomputed
    s = collection.run(shapes, Job.hks([0.2]), out, scheduler=client, progress=False)
    assert sorted(s.done) == sorted(shapes)
    s = collection.run(shapes, Job.hks([0.2]), out, scheduler=client, progress=False, mass="full")
    assert sorted(s.done) == sorted(shapes)
    moved = dict(shapes, sphere=(shapes["sphere"][0] * 2.0, shapes["sphere"][1]))
    s = collection.run(moved, Job.hks([0.2]), out, scheduler=client, progress=False, mass="full")
    assert s.done == ["sphere"]
    H = collection.load(out).results["sphere"]["hks"][:, 0]
    assert _close(H, sig.hks(sig.laplacian(*moved["sphere"], mass="full"), 0.2))


_INTERRUPTED = """
import sys
import numpy as np
from data_generators import icosphere
from spectral_igl import collection
from spectral_igl.collection import Job

if __name__ == "__main__":
    V, F = icosphere(3)
    shapes = {f"s{i:02d}": (V * (1.0 + 0.1 * i), F) for i in range(24)}
    collection.run(shapes, Job.hks([0.01, 0.1]), sys.argv[1], workers=2, progress=False)
"""


def test_interrupted_run_resumes(client, tmp_path):
    out = tmp_path / "int.zarr"
    script = tmp_path / "batch.py"
    script.write_text(textwrap.dedent(_INTERRUPTED))
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    # the whole process group (client, scheduler and worker processes) is killed part-way
    proc = subprocess.Popen([sys.executable, str(script), str(out)], env=env,
                            start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 60
        while time.time() < deadline and proc.poll() is None:
            if out.is_dir() and sum((p / "zarr.json").is_file() for p in out.iterdir()
                                    if not p.name.startswith(".")) >= 3:
                break
            time.sleep(0.05)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    first = sorted(collection.load(out, arrays=False).results)
    assert 3 <= len(first) < 24, first
    # a write cut short leaves nothing that reads back as a result
    (out / ".partial" / "s99.x").mkdir(parents=True, exist_ok=True)
    (out / ".partial" / "s99.x" / "zarr.json").write_text(json.dumps(
        {"zarr_format": 3, "node_type": "group", "attributes": {"status": "done"}}))
    (out / "ghost").mkdir()
    (out / "ghost" / "zarr.json").write_text(json.dumps(
        {"zarr_format": 3, "node_type": "group", "attributes": {"status": "done", "arrays": ["hks"]}}))
    assert sorted(collection.load(out).results) == first
    V, F = icosphere(3)
    shapes = {f"s{i:02d}": (V * (1.0 + 0.1 * i), F) for i in range(24)}
    s = collection.run(shapes, Job.hks([0.01, 0.1]), out, scheduler=client, progress=False)
    assert sorted(s.skipped) == first and sorted(s.done) == sorted(set(shapes) - set(first))
    assert not (out / ".partial" / "s99.x").exists()
    results = collection.load(out).results
    assert sorted(results) == sorted(shapes)
    for name in ("s00", "s23"):
        assert _close(results[name]["hks"], sig.hks(sig.laplacian(*shapes[name]), [0.01, 0.1]))


def _dies_once(folder):
    def job(name, lap):
        marker = Path(folder) / f"{name}.died"
        if name == "sphere" and not marker.exists():
            marker.write_text("x")
            os._exit(1)                      # the worker process dies during the task
        return sig.eigs(lap, 4)[0]
    return job


def _always_dies(name, lap):
    os._exit(1)


def test_worker_killed_during_task_is_retried(client, tmp_path):
    shapes = {"sphere": icosphere(2), "torus": torus(1.0, 0.4, 24, 12)}
    out = tmp_path / "k.zarr"
    s = collection.run(shapes, Job.function(_dies_once(str(tmp_path))), out, scheduler=client, progress=False)
    assert (tmp_path / "sphere.died").exists()
    assert sorted(s.done) == ["sphere", "torus"] and s.ok
    res = collection.load(out).results
    assert _close(res["sphere"]["result"], sig.eigs(sig.laplacian(*shapes["sphere"]), 4)[0])
    # a task that kills every worker it meets is given up and recorded, the others finish
    client.wait_for_workers(2, timeout=30)
    s = collection.run({"sphere": shapes["sphere"]}, Job.function(_always_dies), tmp_path / "k2.zarr",
                       scheduler=client, progress=False, retries=0)
    assert sorted(s.failed) == ["sphere"] and "KilledWorker" in s.failed["sphere"]
    failures = collection.load(tmp_path / "k2.zarr").failures
    assert [f["name"] for f in failures] == ["sphere"] and failures[0]["transient"] is True
    client.wait_for_workers(2, timeout=30)


def test_cli_batch(client, tmp_path, capsys):
    from spectral_igl.cli import main

    V, F = icosphere(2)
    write_mesh(tmp_path / "a.obj", V, F)
    write_mesh(tmp_path / "b.off", V * 2.0, F)
    out = tmp_path / "cli.zarr"
    args = ["batch", str(tmp_path / "*.o*"), "--job", "distance", "--sources", "0", "5",
            "--out", str(out), "--scheduler", client.scheduler_info()["address"], "-q"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "done 2, skipped 0, failed 0" in text
    d = collection.load(out).results["b"]["distances"]
    from spectral_igl.io import read_mesh

    # against the mesh as stored (the file rounds V at ~5e-15)
    assert _close(d[1], sig.biharmonic_distance(sig.laplacian(*read_mesh(tmp_path / "b.off")), 5))
    assert main(args) == 0 and "done 0, skipped 2, failed 0" in capsys.readouterr().out
    (tmp_path / "c.obj").write_text("not a mesh\n")
    assert main(args) == 1
    captured = capsys.readouterr()
    assert "skipped 2, failed 1" in captured.out and "failed: c:" in captured.err
    # a time unit with no time to apply it to is a usage error (--job hks alone is valid: its grid)
    assert main(["batch", str(tmp_path / "a.obj"), "--job", "hks", "--time-unit", "shape",
                 "--out", str(out)]) == 2
    assert main(["batch", str(tmp_path / "nothing*.obj"), "--job", "hks", "--times", "1",
                 "--out", str(out)]) == 3


@pytest.mark.skipif(not MESH_DIR.is_dir(), reason="real meshes live beside the checkout")
def test_real_meshes_triangles_and_tets(client, tmp_path):
    paths = [str(MESH_DIR / "spot.obj"), str(MESH_DIR / "bunny.mesh")]
    out = tmp_path / "real.zarr"
    s = collection.run(paths, Job.kernel_diagonal("biharmonic"), out, scheduler=client, progress=False)
    assert sorted(s.done) == ["bunny", "spot"]
    res = collection.load(out).results
    for p in paths:
        V, C = read_mesh(p)
        expect = sig.kernel_diagonal(sig.laplacian(V, C), sig.filters.biharmonic())
        assert _close(res[Path(p).stem]["diagonal"], expect)
    assert res["bunny"].meta["domain"] == "tet"


def test_bad_arguments(tmp_path):
    V, F = icosphere(1)
    with pytest.raises(ValueError, match="two shapes are named 'x'"):
        collection.collect_inputs([("x", V, F), ("x", V, F)])
    with pytest.raises(ValueError, match="matches no file"):
        collection.collect_inputs(str(tmp_path / "*.obj"))
    with pytest.raises(ValueError, match="no such file"):
        collection.collect_inputs(str(tmp_path / "missing.obj"))
    with pytest.raises(ValueError, match="shape name"):
        collection.collect_inputs([(".hidden", V, F)])
    with pytest.raises(TypeError, match="job must be a Job"):
        collection.run({"x": (V, F)}, "hks", tmp_path / "o")
    with pytest.raises(ValueError, match="needs a time"):
        Job.kernel_diagonal("heat")
    with pytest.raises(ValueError, match="filter must be one of"):
        Job.distances([0], "gaussian")
    with pytest.raises(ValueError, match="times"):
        Job.hks([])
    with pytest.raises(ValueError, match="k must be"):
        Job.eigenvalues(0)
    # the memory model grows with size, and faster for tetrahedra (3-D fill)
    a = collection.estimate_memory(10_000, 70_000, "triangle")
    b = collection.estimate_memory(100_000, 700_000, "triangle")
    c = collection.estimate_memory(10_000, 150_000, "tet")
    assert a < b and 10 * (a - collection.engine.BASE_BYTES) < b - collection.engine.BASE_BYTES and c > a


def test_shapes_above_the_worker_limit_run_alone(tmp_path, monkeypatch):
    from distributed import Client, LocalCluster

    from spectral_igl.collection import engine

    shapes = _shapes()
    big = shapes["torus"][0].shape[0]
    real = engine.estimate_memory
    monkeypatch.setattr(engine, "estimate_memory",
                        lambda n, nnz, domain="triangle", job=None: 10 ** 15 if n == big else real(n, nnz, domain, job))
    # the memory is estimated in the task: a worker thread in this process sees the patch
    with LocalCluster(n_workers=1, processes=False, threads_per_worker=1, memory_limit="4GB",
                      dashboard_address=None, silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
        s = collection.run(shapes, Job.hks([0.1]), tmp_path / "big.zarr", scheduler=client, progress=False)
    assert sorted(s.done) == sorted(shapes)
    res = collection.load(tmp_path / "big.zarr").results
    assert res["torus"].meta.get("run_alone") is True and "run_alone" not in res["sphere"].meta
    assert res["torus"].meta["memory_estimate_bytes"] == 10 ** 15
    assert _close(res["torus"]["hks"][:, 0], sig.hks(sig.laplacian(*shapes["torus"]), 0.1))


def _monitor_periods(dask_worker=None):
    """(sampling profiler on, tick and memory monitor periods in ms) of a worker, or as
    WORKER_CONFIG asks for them when called without one."""
    if dask_worker is None:
        from dask.utils import parse_timedelta

        from spectral_igl.collection.engine import WORKER_CONFIG

        return (False, 1000 * parse_timedelta(WORKER_CONFIG["distributed.admin.tick.interval"]),
                1000 * parse_timedelta(WORKER_CONFIG["distributed.worker.memory.monitor-interval"]))
    pc = dask_worker.periodic_callbacks
    return ("profile" in pc, pc["tick"].callback_time, pc["memory_monitor"].callback_time)


def _worker_state(name, lap):
    """Tasks the worker running this shape holds unfinished, whether it was forked from the
    server that preloads the package, whether it samples stacks, and the periods (ms) of its
    tick and memory monitors."""
    from distributed import get_worker

    w = get_worker()
    held = sum(ts.state in ("waiting", "ready", "constrained", "executing") for ts in w.state.tasks.values())
    forked = "spectral_igl.collection.preload" in sys.modules      # imported by the server only
    return np.array([held, forked, *_monitor_periods(w)], dtype=float)


def test_local_workers_hold_one_task_and_no_profiler(tmp_path):
    """A worker gets its next task only when it has finished one (a task queued on a busy
    worker cannot move to an idle one); a local cluster's workers are forked from a server
    that has imported the package, run no sampling profiler and wake their event loop's
    monitors as WORKER_CONFIG says."""
    import multiprocessing

    V, F = icosphere(0)
    shapes = {f"s{i:02d}": (V * (1 + 0.01 * i), F) for i in range(12)}     # 4 batches of 3
    s = collection.run(shapes, Job.function(_worker_state), tmp_path / "w.zarr", workers=1, progress=False)
    assert s.ok and sorted(s.done) == sorted(shapes)
    states = np.array([r["result"] for r in collection.load(tmp_path / "w.zarr").results.values()])
    assert states.shape == (12, 5)
    assert np.all(states[:, 0] == 1), states[:, 0]
    assert np.all(states[:, 1] == ("forkserver" in multiprocessing.get_all_start_methods())), states[:, 1]
    assert np.all(states[:, 2:] == _monitor_periods()), states[:, 2:]



def test_a_kept_local_cluster_has_the_workers_of_a_run(tmp_path):
    """collection.local_cluster, kept across runs, gives workers set up as a run's own
    (forked from the preloading server, WORKER_CONFIG's monitors), and two runs on it
    reuse the same worker process; its arguments are checked before anything starts."""
    import multiprocessing

    from distributed import Client

    for bad, err in ((0, ValueError), (True, TypeError), (1.5, TypeError)):
        with pytest.raises(err, match="workers"):
            collection.local_cluster(bad)
    V, F = icosphere(0)
    shapes = {f"s{i:02d}": (V * (1 + 0.01 * i), F) for i in range(4)}
    with collection.local_cluster(1) as cluster, Client(cluster) as client:
        pids = []
        for out in ("a.zarr", "b.zarr"):
            s = collection.run(shapes, Job.function(_worker_state), tmp_path / out, scheduler=client,
                               progress=False)
            assert s.ok and sorted(s.done) == sorted(shapes)
            loaded = collection.load(tmp_path / out).results
            states = np.array([r["result"] for r in loaded.values()])
            assert np.all(states[:, 1] == ("forkserver" in multiprocessing.get_all_start_methods()))
            assert np.all(states[:, 2:] == _monitor_periods()), states[:, 2:]
            pids += [r.meta["pid"] for r in loaded.values()]
    assert len(set(pids)) == 1

_THREADS = """
import os, sys
import numpy as np
from spectral_igl import collection
from spectral_igl.collection import Job
from spectral_igl.data_generators import icosphere

KEYS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")


def thread_settings(name, lap):
    from threadpoolctl import threadpool_info

    return np.array([os.environ.get(k) == "1" for k in KEYS]
                    + [max((i["num_threads"] for i in threadpool_info()), default=1) == 1])


if __name__ == "__main__":
    s = collection.run({"ball": icosphere(1)}, Job.function(thread_settings), sys.argv[1], workers=1,
                       progress=False)
    print(s.ok, collection.load(sys.argv[1]).results["ball"]["result"].tolist())
"""


def test_forked_workers_get_one_thread_per_library(tmp_path):
    """Workers forked from the server start with the thread counts a spawned worker gets,
    whatever the client's environment: the BLAS libraries read them when they load, in the
    server (without them a forked worker's OpenBLAS ran on every core inside its tasks)."""
    script = tmp_path / "threads.py"
    script.write_text(_THREADS)
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_NUM_THREADS", "MKL_NUM_THREADS",
                                                            "OPENBLAS_NUM_THREADS")}
    env["PYTHONPATH"] = str(Path(__file__).resolve().parents[1]) + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, str(script), str(tmp_path / "t.zarr")], env=env, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "True [True, True, True, True]", out.stdout


def _hks_slowly(name, lap):
    """HKS at two times, a little slower than it needs to be, so that a run lasts a few seconds."""
    time.sleep(0.15)
    return sig.hks(lap, [0.01, 0.1])


def test_scheduler_and_workers_on_loopback(tmp_path):
    """A separate scheduler and worker processes on 127.0.0.1, a worker killed and one added
    mid-run: every shape is done once, bitwise equal to the single-process result."""
    import threading

    from spectral_igl.linalg.threads import blas_threads

    V, F = icosphere(3)
    shapes = {f"s{i:02d}": (V * (1.0 + 0.05 * i), F) for i in range(30)}
    out = tmp_path / "loop.zarr"
    # the scheduler unpickles the task graph: it imports what this module's functions refer to
    tests = Path(__file__).resolve().parent
    with collection.LoopbackCluster(workers=2, folder=tmp_path, extra_paths=[tests], timeout=30) as cluster, \
            cluster.client() as client:
        result = {}
        run = threading.Thread(target=lambda: result.update(s=collection.run(
            shapes, Job.function(_hks_slowly), out, scheduler=client, progress=False)))
        run.start()
        while run.is_alive() and sum(1 for p in out.glob("s*") if (p / "zarr.json").is_file()) < 6:
            time.sleep(0.02)
        cluster.kill_worker(0)             # a worker dies mid-run
        cluster.add_worker()               # and another one joins
        run.join(timeout=60)
        assert not run.is_alive()
        workers_seen = {r.meta["pid"] for r in collection.load(out, arrays=False).results.values()}
        periods = client.run(_monitor_periods)
    # the worker programs get a local cluster's settings (no profiler, slow monitors)
    assert len(periods) >= 2 and set(periods.values()) == {_monitor_periods()}, periods
    s = result["s"]
    assert sorted(s.done) == sorted(shapes) and s.ok, str(s)
    assert len(workers_seen) >= 2
    res = collection.load(out).results
    for name, (Vi, Fi) in shapes.items():
        with blas_threads(1):
            expect = sig.hks(sig.laplacian(Vi, Fi), [0.01, 0.1])
        assert np.array_equal(res[name]["result"], expect), name


def test_loopback_cluster_arguments_and_clean_up(tmp_path):
    """Bad arguments are refused by name, and leaving the context kills every process."""
    with pytest.raises(ValueError, match="workers"):
        collection.LoopbackCluster(workers=-1)
    with collection.LoopbackCluster(workers=0, folder=tmp_path) as cluster:
        assert cluster.scheduler_file.is_file()
        with pytest.raises(ValueError, match="index"):
            cluster.kill_worker(0)
    assert all(p.poll() is not None for p in cluster.processes)
    assert tmp_path.is_dir()             # a folder given is kept (its log is there)


def test_store_writes_arrays_zarr_reads(tmp_path):
    """Numeric arrays are written as Zarr v3 files directly: zarr reads them back exactly,
    and a truncated chunk is damage, never a result."""
    import zarr

    from spectral_igl.collection.store import check_record, write_record

    arrays = {"f": np.arange(6.0).reshape(3, 2) / 7, "i": np.arange(-2, 3, dtype=np.int32),
              "u": np.arange(3, dtype=np.uint8), "b": np.array([True, False, True]),
              "c": np.array([1 + 2j, -0.5j]), "be": np.arange(4, dtype=">f8"), "e": np.zeros((0, 3)),
              "t": np.arange(24.0).reshape(2, 3, 4)}
    out = tmp_path / "s.zarr"
    write_record(out, "x", {"status": "done"}, arrays)
    g = zarr.open_group(str(out / "x"), mode="r")
    assert g.attrs["status"] == "done"
    attrs, back, problem = check_record(out, "x")
    assert problem is None
    for key, a in arrays.items():
        z = np.asarray(g[key][...])
        assert z.shape == a.shape and np.array_equal(z, a) and z.dtype == a.dtype.newbyteorder("="), key
        assert np.array_equal(back[key], a) and back[key].dtype == z.dtype, key
    chunk = out / "x" / "f" / "c" / "0" / "0"
    chunk.write_bytes(chunk.read_bytes()[:-8])
    assert "'f' cannot be read" in check_record(out, "x")[2]
    assert collection.load(out).failures[0]["damaged"] is True
