"""Running a :class:`~spectral_igl.collection.jobs.Job` over many shapes on dask.distributed."""
from __future__ import annotations

import glob
import hashlib
import json
import logging
import math
import os
import resource
import shutil
import socket
import time
import sys
import traceback
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._extras import require
from .._validate import as_flag, as_int, describe
from .._version import __version__
from .jobs import Job
from .store import (check_name, check_record, clean_partial, lock_store, open_root, publish, read_record,
                    stage_record, write_record)

__all__ = ["run", "local_cluster", "RunSummary", "Shape", "collect_inputs", "estimate_memory", "process_shape",
           "process_batch", "inspect_shape", "input_hash", "estimate_nnz", "file_stat"]

#: file types read by :func:`spectral_igl.io.read_mesh` (a directory input means these)
MESH_TYPES = (".obj", ".off", ".ply", ".stl", ".wrl", ".mesh")
#: fixed cost of one task in a worker (interpreter, libraries, mesh arrays), bytes
BASE_BYTES = 64 * 2 ** 20
#: shapes whose input is at most this many bytes are sent to the workers in batches
SMALL_BYTES = 256 * 2 ** 10
#: a batch holds at most this many shapes and this many input bytes
BATCH_SHAPES, BATCH_BYTES = 64, 2 * 2 ** 20


@dataclass
class Shape:
    """One input: a file path, or named arrays (``C`` None for a point set)."""

    name: str
    path: str | None = None
    V: np.ndarray | None = None
    C: np.ndarray | None = None

    @property
    def source(self) -> str:
        return self.path if self.path is not None else "<arrays>"


@dataclass
class RunSummary:
    """What a :func:`run` did: names of the shapes done, skipped and failed.

    Parameters
    ----------
    out : str
        The store written.
    done, skipped : list of str
        Shapes computed by this run; shapes whose stored result was current (same input
        hash, job key and package version) and left as it was.
    failed : dict of str -> str
        Shapes that raised, with the error text (the run goes on without them).
    damaged : dict of str -> str
        Stored results found damaged (a checksum or a file that no longer matches) and
        recomputed, with what was wrong.
    seconds : float
        Wall time of the run.
    workers : int
        dask workers used.

    Attributes
    ----------
    ok : bool
        No shape failed.

    Examples
    --------
    >>> from spectral_igl.collection import RunSummary
    >>> s = RunSummary("hks.zarr", done=["cow"], skipped=["spot"], seconds=1.25, workers=2)
    >>> s.ok
    True
    >>> print(s)
    1 done, 1 skipped, 0 failed in 1.2 s on 2 worker(s); store hks.zarr
    """

    out: str
    done: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    failed: dict = field(default_factory=dict)     # name -> error text
    damaged: dict = field(default_factory=dict)    # name -> what was damaged (recomputed)
    seconds: float = 0.0
    workers: int = 0

    @property
    def ok(self) -> bool:
        return not self.failed

    def __str__(self) -> str:
        text = (f"{len(self.done)} done, {len(self.skipped)} skipped, {len(self.failed)} failed "
                f"in {self.seconds:.1f} s on {self.workers} worker(s); store {self.out}")
        for name, err in sorted(self.damaged.items()):
            text += f"\n  damaged (recomputed): {name}: {err}"
        for name, err in sorted(self.failed.items()):
            text += f"\n  failed: {name}: {err}"
        return text


# ---- inputs -------------------------------------------------------------------------------
def _has_magic(s: str) -> bool:
    return any(c in s for c in "*?[")


def _paths(item) -> list:
    s = os.fspath(item)
    if _has_magic(s):
        return sorted(p for p in glob.glob(s, recursive=True) if os.path.isfile(p))
    if os.path.isdir(s):
        return sorted(str(p) for p in Path(s).iterdir()
                      if p.is_file() and p.suffix.lower() in MESH_TYPES)
    return [s]


def _array_shape(name, value) -> Shape:
    name = check_name(str(name))
    if isinstance(value, np.ndarray) or (isinstance(value, (list, tuple)) and len(value) == 0):
        V, C = value, None
    elif isinstance(value, (tuple, list)) and len(value) == 2:
        V, C = value
    else:
        raise TypeError(f"the input {name!r} must be (V, F), (V, T), (P, None) or an (n, 3) point "
                        f"array, got {describe(value)}")
    V = np.asarray(V, dtype=float)
    C = None if C is None else np.asarray(C)
    return Shape(name, None, V, C)


def collect_inputs(inputs) -> list:
    """The shapes named by ``inputs``.

    Parameters
    ----------
    inputs : path, glob, directory, dict, or a list of these and of ``(name, V, F)``
        A path (``.obj .off .ply .stl .wrl`` triangles, MEDIT ``.mesh`` tetrahedra); a glob
        (``"scans/*.ply"``, ``**`` allowed); a directory (its mesh files); a dict
        ``{name: (V, F)}`` (``(V, T)`` for tets, ``(P, None)`` or ``P`` for a point set); a
        list mixing paths and ``(name, V, F)`` tuples.

    Returns
    -------
    list of Shape
        With unique names (a file's name is its stem); files are named, not read.

    Examples
    --------
    >>> from spectral_igl.collection import collect_inputs
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(1)
    >>> shapes = collect_inputs({"ball": (V, F), "cloud": V})
    >>> [(s.name, s.C is None) for s in shapes]
    [('ball', False), ('cloud', True)]
    """
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    if isinstance(inputs, dict):
        inputs = [(k, v) for k, v in inputs.items()]
    if not isinstance(inputs, (list, tuple)):
        raise TypeError(f"inputs must be paths, globs, a dict of arrays or a list of these, got "
                        f"{describe(inputs)}")
    shapes = []
    for item in inputs:
        if isinstance(item, (str, os.PathLike)):
            found = _paths(item)
            if not found:
                raise ValueError(f"inputs: the pattern {os.fspath(item)!r} matches no file")
            missing = [p for p in found if not os.path.isfile(p)]
            if missing:
                raise ValueError(f"inputs: no such file {missing[0]!r}")
            shapes += [Shape(check_name(Path(p).stem), p) for p in found]
        elif isinstance(item, (tuple, list)) and len(item) == 3:
            shapes.append(_array_shape(item[0], (item[1], item[2])))
        elif isinstance(item, (tuple, list)) and len(item) == 2 and isinstance(item[0], str):
            shapes.append(_array_shape(item[0], item[1]))
        else:
            raise TypeError(f"inputs: each item must be a path, a glob or (name, V, F), got "
                            f"{describe(item)}")
    seen = {}
    for s in shapes:
        if s.name in seen:
            raise ValueError(f"inputs: two shapes are named {s.name!r} ({seen[s.name]} and "
                             f"{s.source}); shape names (file stems) must be unique")
        seen[s.name] = s.source
    if not shapes:
        raise ValueError("inputs: no shape given")
    return shapes


# ---- per-shape work (runs on the workers) ---------------------------------------------------
def _read(shape: Shape):
    if shape.path is None:
        return shape.V, shape.C
    from ..io import read_mesh

    V, C = read_mesh(shape.path)
    return V, (None if C is None or np.asarray(C).size == 0 else C)


def _digest(*arrays) -> str:
    h = hashlib.sha256()
    for a in arrays:
        if a is None:
            h.update(b"none")
            continue
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _file_digest(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def estimate_nnz(n, C) -> int:
    """nnz of L: n plus twice the number of edges (k-NN graph estimate for point sets)."""
    if C is None:
        return 41 * n          # symmetrised k-nearest-neighbour graph, k about 20
    C = np.asarray(C, dtype=np.int64)
    k = C.shape[1]
    pairs = [(a, b) for a in range(k) for b in range(a + 1, k)]
    E = np.concatenate([C[:, [a, b]] for a, b in pairs])
    E.sort(axis=1)
    edges = np.unique(E[:, 0] * np.int64(n) + E[:, 1]).size
    return int(n + 2 * edges)


def _nnz_bound(n, C) -> int:
    """An upper bound of :func:`estimate_nnz` without counting edges: every cell's vertex
    pairs taken as distinct edges."""
    if C is None:
        return estimate_nnz(n, C)
    k = np.asarray(C).shape[1]
    return int(n + k * (k - 1) * len(C))


def estimate_memory(n: int, nnz: int, domain: str = "triangle", job: Job | None = None) -> int:
    r"""Estimated peak memory of one shape's job, in bytes.

    A model of the sparse factorizations, fitted to peak resident memory measured on the
    shared meshes (HKS at two times; an estimate, not a bound): with selected inversion
    (HKS, kernel diagonals, distances, user functions)

    .. math:: \text{bytes} \approx 64\,\text{MiB} + c\cdot\operatorname{nnz}(L)\cdot f(n),

    :math:`f = \log_2 n`, c = 130 for surfaces and point sets (nested-dissection fill
    :math:`O(n\log n)`), :math:`f = n^{1/3}`, c = 200 for tetrahedra (fill
    :math:`O(n^{4/3})`); eigenvalue jobs and truncated WKS need one real factor and the
    Lanczos basis, :math:`20\operatorname{nnz}\log_2 n + 32 n k`.

    Parameters
    ----------
    n : int
        Vertices (points) of the shape.
    nnz : int
        Stored entries of its Laplacian L.
    domain : str
        ``"tet"`` for tetrahedral meshes (wider fill), anything else for surfaces, polygon
        meshes and point sets.
    job : Job or None
        The job to run; eigenvalue jobs and truncated WKS use the smaller model.

    Returns
    -------
    int
        Estimated peak bytes; :func:`run` runs a shape alone (not beside others on its
        worker) when the estimate exceeds the worker's share of memory.

    Examples
    --------
    >>> from spectral_igl.collection import estimate_memory
    >>> mib = estimate_memory(10_000, 70_000) / 2**20
    >>> 64 < mib < 64 + 130 * 70_000 * 14 / 2**20
    True
    >>> estimate_memory(10_000, 70_000, domain="tet") > estimate_memory(10_000, 70_000)
    True
    """
    n, nnz = max(int(n), 2), max(int(nnz), 1)
    if job is not None and not job.uses_selected_inverse() and job.kind != "function":
        k = int(job.params.get("k", 100)) + 20
        return int(BASE_BYTES + 20 * nnz * math.log2(n) + 32 * n * k)
    if domain == "tet":
        return int(BASE_BYTES + 200 * nnz * n ** (1.0 / 3.0))
    return int(BASE_BYTES + 130 * nnz * math.log2(n))


def _transient(err) -> bool:
    """Failures worth retrying on a rerun (memory, I/O) rather than a property of the input."""
    return isinstance(err, (MemoryError, OSError))


def input_hash(shape: Shape) -> str:
    """SHA-256 of the input file's bytes (of the arrays for array inputs)."""
    return _file_digest(shape.path) if shape.path is not None else _digest(shape.V, shape.C)


def inspect_shape(shape: Shape) -> dict:
    """Size of one input before any work: ``n``, ``nnz`` (of L), ``domain``.

    An unreadable input gives ``error`` (its text) instead of the sizes.
    """
    info = {"name": shape.name}
    try:
        V, C = _read(shape)
        n = len(V)
        domain = "points" if C is None else ("tet" if np.asarray(C).shape[1] == 4 else "triangle")
        info.update(n=n, nnz=estimate_nnz(n, C), domain=domain)
    except Exception as err:  # noqa: BLE001 - reported as this shape's failure
        info["error"] = f"{type(err).__name__}: {err}"
        info["transient"] = _transient(err)
    return info


def _peak_rss() -> int:
    """Peak resident memory of this worker process so far, in bytes."""
    try:  # Linux: the high-water mark of this address space
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


def _laplacian(V, C, options):
    if C is None:
        from ..laplacian import point_cloud_laplacian

        return point_cloud_laplacian(V)
    from ..laplacian import laplacian

    return laplacian(V, C, weights=options.get("weights", "auto"), mass=options.get("mass", "lumped"))


def file_stat(path) -> list:
    """``[size, mtime_ns]`` of a file: a rerun trusts a recorded hash while these are unchanged."""
    st = os.stat(path)
    return [int(st.st_size), int(st.st_mtime_ns)]


_MALLOC_TUNED = []


def _tune_malloc() -> None:
    """Undo dask's ``MALLOC_TRIM_THRESHOLD_`` in this worker process (glibc only; once).

    dask's nanny starts workers with ``MALLOC_TRIM_THRESHOLD_=65536``, which also freezes
    glibc's mmap threshold at 128 KiB: every large array of a factorization is then mapped
    and unmapped afresh, and its pages faulted in again. Measured on stanford-bunny (HKS at
    two times): 3.2 s of CPU in the task thread against 2.2 s in a plain process. The
    thresholds set here are the largest glibc's own dynamic rule would reach (32 MiB mmap,
    twice that for trimming), which restores the plain-process time.
    """
    if _MALLOC_TUNED:
        return
    _MALLOC_TUNED.append(True)
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(-3, 32 * 2 ** 20)     # M_MMAP_THRESHOLD
        libc.mallopt(-1, 64 * 2 ** 20)     # M_TRIM_THRESHOLD
    except (OSError, AttributeError):       # not glibc
        pass


def _compute(shape: Shape, job: Job, meta: dict, limit):
    """``(record, arrays)`` of one shape; record status ``"too_large"`` when its memory
    estimate exceeds ``limit`` (nothing computed)."""
    t0, c0, h0 = time.perf_counter(), time.process_time(), time.thread_time()
    timings = {"started": time.time()}      # seconds since the epoch: a run's timeline across workers
    record = dict(meta, name=shape.name, source=shape.source, version=__version__,
                  host=socket.gethostname(), pid=os.getpid())
    lap, arrays = None, {}
    try:
        if shape.path is not None:    # the bytes actually read here
            record["input_stat"] = file_stat(shape.path)
        record["input_hash"] = input_hash(shape)
        V, C = _read(shape)
        record["mesh_hash"] = _digest(np.asarray(V, dtype=float),
                                      None if C is None else np.asarray(C, dtype=np.int64))
        domain = "points" if C is None else ("tet" if np.asarray(C).shape[1] == 4 else "triangle")
        # the estimate grows with nnz: count the edges only when the cheap bound is above the limit
        est = estimate_memory(len(V), _nnz_bound(len(V), C), domain, job)
        if limit is not None and est > limit:
            est = estimate_memory(len(V), estimate_nnz(len(V), C), domain, job)
        record["memory_estimate_bytes"] = est
        timings["read"] = time.perf_counter() - t0
        if limit is not None and est > limit:
            record["status"] = "too_large"
            return record, arrays
        t = time.perf_counter()
        lap = _laplacian(V, C, meta.get("laplacian", {}))
        timings["laplacian"] = time.perf_counter() - t
        record.update(n=lap.n, nnz=int(lap.L.nnz), domain=lap.domain,
                      n_components=int(lap.n_components),
                      memory_estimate_bytes=estimate_memory(lap.n, int(lap.L.nnz), domain, job))
        t, c, h = time.perf_counter(), time.process_time(), time.thread_time()
        arrays, bounds = job(shape.name, lap)
        timings["compute"] = time.perf_counter() - t
        timings["compute_cpu"] = time.process_time() - c
        timings["compute_thread_cpu"] = time.thread_time() - h
        record.update(status="done", bounds=bounds)
    except Exception as err:  # noqa: BLE001 - the shape's failure is recorded, others go on
        arrays = {}
        record.update(status="failed", error=f"{type(err).__name__}: {err}",
                      transient=_transient(err), traceback=traceback.format_exc(limit=8))
    finally:
        if lap is not None:      # the factorizations of this shape are not kept
            lap.cache.clear()
        del lap
    timings["total"] = time.perf_counter() - t0
    timings["cpu"] = time.process_time() - c0
    timings["thread_cpu"] = time.thread_time() - h0     # the task's own thread, without the event loop
    record["timings"] = timings
    record["worker_peak_rss_bytes"] = _peak_rss()
    record["finished"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    return record, arrays


def _summary(record: dict) -> dict:
    """What a task returns to the client for one shape (a few numbers, never the arrays)."""
    t = record.get("timings", {})
    return {"name": record["name"], "status": record["status"], "error": record.get("error"),
            "seconds": t.get("total", 0.0), "compute": t.get("compute", 0.0),
            "cpu": t.get("cpu", 0.0), "estimate": record.get("memory_estimate_bytes")}


def _written_by(out, name, run_id) -> bool:
    """True when this run already wrote ``name``'s result (a task retried after its worker died)."""
    prev = read_record(out, name) if run_id else None
    return prev is not None and prev.get("run_id") == run_id and prev.get("status") == "done"


def process_batch(shapes, job: Job, out: str, metas, limit=None) -> list:
    """Process several shapes in one task (runs on a worker); one summary dict per shape.

    Each shape is computed with the BLAS limited to one thread (parallelism comes from
    the worker processes) and staged under ``out/.partial``; the staged groups are then
    made durable with one file-system sync and renamed into place together. A shape whose
    memory estimate exceeds ``limit`` is not computed: its summary has status
    ``"too_large"`` and the client runs it alone afterwards. A shape already written by
    this run (``meta["run_id"]``; the task was retried after its worker died) is not
    computed again.
    """
    from ..linalg.threads import blas_threads

    _tune_malloc()
    staged, results = [], []
    try:
        for shape, meta in zip(shapes, metas):
            if _written_by(out, shape.name, meta.get("run_id")):
                results.append({"name": shape.name, "status": "done", "error": None, "seconds": 0.0,
                                "compute": 0.0, "cpu": 0.0, "estimate": None})
                continue
            with blas_threads(1):
                record, arrays = _compute(shape, job, meta, limit)
            if record["status"] != "too_large":
                staged.append((shape.name, stage_record(out, shape.name, record, arrays)))
            results.append(_summary(record))
            del arrays
        publish(out, staged)
    except BaseException:
        for _, tmp in staged:      # never published: removed, not left for the next run
            shutil.rmtree(tmp, ignore_errors=True)
        raise
    return results


def process_shape(shape: Shape, job: Job, out: str, meta: dict) -> dict:
    """Read, build the Laplacian, run ``job`` and write the result (runs on a worker).

    A failure of the shape is written as a ``"failed"`` record with its error text and
    returned, never raised; only a failure to write the store raises (the scheduler then
    retries the task).
    """
    return process_batch([shape], job, out, [meta])[0]


# ---- the driver ---------------------------------------------------------------------------
def _as_job(job) -> Job:
    if isinstance(job, Job):
        return job
    if callable(job):
        return Job.function(job)
    raise TypeError(f"job must be a Job (Job.hks(...), Job.distances(...), ...) or a function "
                    f"fn(name, lap), got {describe(job)}")


#: dask settings of the workers of a local cluster (and of :class:`LoopbackCluster`'s
#: programs). No sampling profiler: it interrupts the task thread every 10 ms (about 10 % of
#: the CPU of an HKS task, measured). The event loop's periodic checks wake less often: the
#: tick monitor (20 ms by default), the system monitor (500 ms) and the memory monitor
#: (100 ms) each take the GIL from the task thread; with dask's intervals the other threads
#: of a worker spent 3-5 % of the task thread's CPU during the jobs, and the task thread
#: itself 1-4 % more, measured (with these: under 1 % and the loop's CPU). The memory
#: monitor then checks the worker's limit every 0.5 s (each task also checks its shape's
#: estimate against it before computing).
WORKER_CONFIG = {"distributed.worker.profile.enabled": False,
                 "distributed.admin.tick.interval": "1s",
                 "distributed.admin.system-monitor.interval": "5s",
                 "distributed.worker.memory.monitor-interval": "500ms"}


#: modules the fork server of a local cluster's workers imports (once, for every worker)
WORKER_PRELOAD = ["distributed", "spectral_igl.collection.preload"]
#: environment the fork server starts with: the thread counts dask's nanny gives a worker it
#: spawns (``distributed.nanny.pre-spawn-environ``), which libraries read when they load
#: (without them, forked workers ran an HKS with 18x the CPU: OpenBLAS on every core)
WORKER_ENV = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


def _fork_server() -> dict:
    """dask's setting that forks a local cluster's workers from a server that has imported
    :data:`WORKER_PRELOAD`, where the platform has one (else none: dask spawns them).

    A spawned worker imports distributed and this package itself, each worker again
    (0.4–0.6 s of CPU measured), and pays the first call of the compiled extensions in its
    first task; forked from the server, it starts with them. The server lives as long as
    this process, so the workers of a later run fork from it too. (A worker that its nanny
    restarts after it died is spawned: the nanny reads dask's setting at that time.) dask
    sets a preload list of its own when it first makes the context; the server reads the
    list once, when it starts, and this starts it first.
    """
    import multiprocessing

    if "forkserver" not in multiprocessing.get_all_start_methods():
        return {}
    from multiprocessing import forkserver

    multiprocessing.get_context("forkserver").set_forkserver_preload(WORKER_PRELOAD)
    saved = {k: os.environ.get(k) for k in WORKER_ENV}
    os.environ.update(WORKER_ENV)       # inherited by the server when it starts, then restored
    try:
        # returns at once: the server imports while this process imports dask and starts the scheduler
        forkserver.ensure_running()
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return {"distributed.worker.multiprocessing-method": "forkserver"}


def _local_cluster(n, memory_limit, silence):
    """A LocalCluster of ``n`` single-threaded worker processes, with :data:`WORKER_CONFIG`
    (a nanny hands its configuration to the worker it starts or restarts), forked from a
    server that has imported :data:`WORKER_PRELOAD` (:func:`_fork_server`)."""
    import dask
    from distributed import LocalCluster

    with dask.config.set(dict(WORKER_CONFIG, **_fork_server())):
        return LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                            memory_limit=memory_limit, dashboard_address=None, silence_logs=silence)


def local_cluster(workers: int | None = None, memory_limit="auto", progress: bool = False):
    r"""The local cluster :func:`run` starts for itself, to keep across several runs.

    :func:`run` without ``scheduler`` starts a cluster and stops it when it ends: about a
    second on a 2-core machine (the workers' fork server importing the package, the
    workers registering), which a long run does not notice and a short one does. A session
    of several runs (a notebook, a script computing several jobs) starts this cluster once
    and passes ``scheduler=client`` to each run.

    Parameters
    ----------
    workers : int, optional
        Single-threaded worker processes (default: one per core).
    memory_limit : str, int or float
        Per-worker limit (dask's syntax, as in :func:`run`).
    progress : bool
        Let dask's warnings through (as :func:`run` does with ``progress=True``).

    Returns
    -------
    distributed.LocalCluster
        Its workers are forked from a server that has imported the package, with
        :data:`WORKER_CONFIG`, exactly as :func:`run`'s own. Close it (or use it as a
        context manager) when done.

    Examples
    --------
    Two runs on one cluster (``tests/test_collection.py`` runs this):

    >>> from distributed import Client
    >>> from spectral_igl.collection import Job, local_cluster, run
    >>> from spectral_igl.data_generators import icosphere
    >>> with local_cluster(2) as cluster, Client(cluster) as client:  # doctest: +SKIP
    ...     run({"ball": icosphere(2)}, Job.hks([0.01, 0.1]), "hks.zarr", scheduler=client)
    ...     run({"ball": icosphere(2)}, Job.eigenvalues(10), "eigs.zarr", scheduler=client)

    Its arguments are checked before anything starts:

    >>> local_cluster(0)
    Traceback (most recent call last):
    ...
    ValueError: workers must be an integer in [1, inf], got 0
    """
    require("distributed", "cluster", "spectral_igl.collection")
    silence = logging.WARNING if as_flag(progress, "progress") else logging.ERROR
    return _local_cluster(_worker_count(workers), memory_limit, silence)


def _worker_count(workers) -> int:
    """``workers``, or one per core when None (validated)."""
    return (os.cpu_count() or 1) if workers is None else as_int(workers, "workers", lo=1)


def _connect(scheduler, workers, memory_limit, silence):
    """(client, cluster or None, owned)."""
    from distributed import Client

    if scheduler is None:
        cluster = _local_cluster(_worker_count(workers), memory_limit, silence)
        return Client(cluster), cluster, True
    if isinstance(scheduler, Client):
        return scheduler, None, False
    if isinstance(scheduler, str):
        return Client(scheduler), None, True
    raise TypeError(f"scheduler must be None, an address such as 'tcp://host:8786' or a "
                    f"distributed.Client, got {describe(scheduler)}")


def _worker_limits(client):
    """``(workers, memory limit of one task or None, threads per worker)`` of the cluster."""
    info = client.scheduler_info()["workers"]
    limits = [w.get("memory_limit") or 0 for w in info.values()]
    threads = max((w.get("nthreads") or 1 for w in info.values()), default=1)
    limit = min(limits) // threads if limits and all(limits) else None
    return len(info), limit, threads


def run(inputs, job, out, *, workers: int | None = None, scheduler=None, progress: bool = True,
        retries: int = 2, memory_limit="auto", weights: str | None = None, mass: str | None = None,
        force: bool = False, retry_failed: bool = False) -> RunSummary:
    r"""Run ``job`` on every shape of ``inputs`` on dask.distributed; results in a Zarr store.

    Parameters
    ----------
    inputs : paths, globs, directories, ``{name: (V, F)}`` or ``[(name, V, F), ...]``
        See :func:`collect_inputs`. Files are read on the workers by
        :func:`spectral_igl.io.read_mesh`; ``F`` with 4 columns means tetrahedra, ``None``
        a point set (:func:`spectral_igl.point_cloud_laplacian`).
    job : Job or callable
        ``Job.hks(times)``, ``Job.wks(energies)``, ``Job.kernel_diagonal(filter, t)``,
        ``Job.distances(sources, filter)``, ``Job.eigenvalues(k)``, or any function
        ``fn(name, lap)`` returning an array or a dict of arrays.
    out : str or os.PathLike
        Directory of the Zarr store (created). One group per shape; on a cluster it must be
        on a file system every worker and the client can reach.
    workers : int, optional
        Worker processes of the local cluster (default: one per core). Ignored when
        ``scheduler`` is given.
    scheduler : None, str or distributed.Client
        ``None``: a ``LocalCluster`` with ``workers`` single-threaded processes, each with
        ``memory_limit``; an address (``"tcp://host:8786"``) or a ``Client``: that cluster.
    progress : bool
        A progress line on stdout (shapes finished of all, rate, failures, time left).
    retries : int
        Times a task that raised is resubmitted (the shape's own errors are recorded, not
        raised: this covers a store that could not be written). A task whose worker died
        is resubmitted by the scheduler, up to ``distributed.scheduler.allowed-failures``
        times (dask's default 3), then recorded as failed with ``KilledWorker``.
    memory_limit : str, int or float
        Per-worker limit of the local cluster (dask's syntax: ``"auto"`` shares the
        machine's memory, ``"4GB"``, bytes).
    weights, mass : str, optional
        Laplacian options of :func:`spectral_igl.laplacian` (meshes); by default the job's
        (:meth:`Job.laplacian_options`: ``"auto"`` and ``"lumped"``, finite elements for
        :meth:`Job.shape_dna`).
    force : bool
        Recompute shapes whose stored result is current.
    retry_failed : bool
        Rerun shapes whose recorded failure came from the input itself (a corrupt file, an
        invalid mesh, an exception of the job) although input and job are unchanged.
        Failures from memory, I/O or a dying worker are always retried.

    Returns
    -------
    RunSummary
        Names done, skipped (result already in the store for the same input hash and
        job), and failed (with the error text, also stored; a failure recorded by an
        earlier run for the same input and job is reported again, not recomputed).

    Notes
    -----
    Each shape's group is written atomically; a rerun recomputes only the shapes without
    a current result. The client reads no input: tasks are dispatched at once, largest
    input first, with a bounded number in flight; small inputs travel in batches of
    several shapes per task (one scheduler round trip and one file-system sync per
    batch). Each worker reads and hashes its inputs, estimates the peak memory
    (:func:`estimate_memory`) and runs the job with the BLAS on one thread. A shape whose
    estimate exceeds a worker's limit is handed back and runs afterwards one at a time
    (on a local cluster: in a single worker given the memory of all). On a rerun a file
    is hashed by the client only if its size or modification time differs from the
    recorded ones. The Laplacian's caches are cleared after every shape.

    A stored result is skipped only when its group matches its completion record (every
    array's shape, dtype and SHA-256, see :func:`~spectral_igl.collection.store.check_record`);
    a damaged group (a deleted chunk, truncated metadata) is listed in
    ``RunSummary.damaged`` and recomputed.

    One run per store at a time: a run holds the store's lock
    (:class:`~spectral_igl.collection.store.lock_store`), and a second run on the same
    store raises ``StoreInUse`` naming the holder before any work; the lock of a run
    that was killed is detected (its process is gone) and taken over. A run then removes
    leftovers of interrupted writes.

    Examples
    --------
    Certified eigenvalues of two generated shapes on one local worker; a second run finds
    them current and computes nothing:

    >>> from spectral_igl.collection import Job, load, run
    >>> from spectral_igl.data_generators import icosphere, torus
    >>> shapes = {"ball": icosphere(2), "torus": torus(n_major=20, n_minor=10)}
    >>> summary = run(shapes, Job.eigenvalues(4), "ev.zarr", workers=1, progress=False)
    >>> sorted(summary.done), summary.ok
    (['ball', 'torus'], True)
    >>> run(shapes, Job.eigenvalues(4), "ev.zarr", workers=1, progress=False).skipped
    ['ball', 'torus']
    >>> results, failures = load("ev.zarr")
    >>> results["ball"].bound_kind, failures
    ('proof', [])
    """
    t_start = time.perf_counter()
    shapes = collect_inputs(inputs)
    job = _as_job(job)
    out = os.fspath(out)
    if not isinstance(retries, (int, np.integer)) or isinstance(retries, bool) or retries < 0:
        raise ValueError(f"retries must be an integer >= 0, got {retries!r}")
    options = job.laplacian_options(weights, mass)
    ident = {"job": job.kind, "params": job.params, "laplacian": options}
    key = hashlib.sha256(json.dumps(ident, sort_keys=True).encode()).hexdigest()
    for flag, value in (("progress", progress), ("force", force), ("retry_failed", retry_failed)):
        as_flag(value, flag)
    open_root(out)
    with lock_store(out):
        return _run_locked(shapes, job, out, key, options, workers, scheduler, progress, retries,
                           memory_limit, force, retry_failed, t_start)


def _size_hint(shape: Shape) -> int:
    """Bytes of the input (file size, or the arrays' size): the order and batching key."""
    if shape.path is not None:
        try:
            return os.path.getsize(shape.path)
        except OSError:
            return 0
    return sum(np.asarray(x).nbytes for x in (shape.V, shape.C) if x is not None)


def _pending(shapes, out, key, base, force, retry_failed, summary) -> list:
    """``[(shape, meta)]`` of the shapes without a current result; skipped and earlier input
    failures go to ``summary``.

    A file is hashed here only when its record is for the same job but its size or
    modification time changed since (else the recorded hash stands, or the worker hashes
    it while reading): the client reads no input on a first run, and one stat per file on
    a rerun.
    """
    pending = []
    for s in shapes:
        meta = dict(base)
        prev = None if force else read_record(out, s.name)
        if prev is not None and prev.get("job_key") == key:
            if s.path is not None and prev.get("input_stat") == file_stat(s.path):
                h = prev.get("input_hash")
            else:
                h = input_hash(s)
            current = prev.get("input_hash") == h
        else:
            current = False
        if (current and prev["status"] == "done") or (prev is None and (Path(out) / s.name).is_dir()):
            problem = check_record(out, s.name)[2]
            if problem is not None:
                summary.damaged[s.name] = problem
                current = False
        if current and prev["status"] == "done":
            summary.skipped.append(s.name)
        elif current and not retry_failed and not prev.get("transient", True):
            summary.failed[s.name] = prev.get("error", "failed") + " (recorded earlier; not retried)"
        else:
            pending.append((s, meta))
    return pending


def _batches(pending, slots: int) -> list:
    """Group ``pending`` (largest input first) into tasks: large shapes alone, small ones
    together, at most :data:`BATCH_SHAPES` shapes and :data:`BATCH_BYTES` input bytes per
    task and at least four tasks per worker slot, so that the load still balances."""
    items = sorted(((_size_hint(s), s, m) for s, m in pending), key=lambda x: -x[0])
    per_task = max(1, min(BATCH_SHAPES, len(items) // (4 * max(slots, 1))))
    tasks, current, size = [], [], 0
    for nbytes, s, m in items:
        if nbytes > SMALL_BYTES:
            tasks.append([(s, m)])
            continue
        if current and (len(current) >= per_task or size + nbytes > BATCH_BYTES):
            tasks.append(current)
            current, size = [], 0
        current.append((s, m))
        size += nbytes
    if current:
        tasks.append(current)
    return tasks


class _Progress:
    """A one-line progress bar on stdout: shapes finished of all, rate, failures, time left."""

    def __init__(self, total: int, show: bool, every: float = 0.5):
        self.total, self.show, self.every = total, show, every
        self.done = self.failed = 0
        self.t0 = self.last = time.perf_counter()

    def update(self, done: int = 0, failed: int = 0, force: bool = False):
        self.done += done
        self.failed += failed
        now = time.perf_counter()
        if not self.show or (not force and now - self.last < self.every):
            return
        self.last = now
        n = self.done + self.failed
        rate = n / max(now - self.t0, 1e-9)
        left = (self.total - n) / rate if rate > 0 else float("inf")
        width = 30
        fill = int(width * n / max(self.total, 1))
        eta = f"{left:.0f} s left" if math.isfinite(left) else ""
        sys.stdout.write(f"\r[{'#' * fill}{' ' * (width - fill)}] {n}/{self.total} shapes, "
                         f"{rate:.1f}/s, {self.failed} failed {eta}   ")
        sys.stdout.flush()

    def close(self):
        if self.show:
            self.update(force=True)
            sys.stdout.write("\n")
            sys.stdout.flush()


def _record_lost(out, s, meta, err, summary):
    """A task that never returned (workers died, store unwritable): recorded as a transient failure."""
    summary.failed[s.name] = err
    try:
        write_record(out, s.name, dict(meta, name=s.name, source=s.source, status="failed", error=err,
                                       transient=True, version=__version__))
    except OSError:
        pass


def _dispatch(client, tasks, job, out, limit, retries, slots, summary, bar, too_large):
    """Run ``tasks`` with at most ``slots`` in flight, as results arrive.

    One task per worker thread: dask assigns a submitted task to a worker at once (each
    task is its own task group, so the scheduler does not queue it), and a task waiting
    on a busy worker cannot move to one that has become idle. With more in flight the
    first large shapes were dealt out in turn and one worker could be left with two of
    them while the other ran out of work; with one each, a worker gets its next task when
    it finishes one, largest first, which balances to within the last (smallest) task.
    The cost is one scheduler round trip per task, amortised by the batches.

    A task that failed (its worker died ``allowed-failures`` times, or the store could not
    be written) is split into single shapes and resubmitted once; a single shape that
    fails is recorded as failed.
    """
    from distributed import as_completed

    queue = list(reversed(tasks))       # pop() takes the largest first
    window = max(slots, 1)
    running = {}
    ac = as_completed()

    def submit():
        while queue and len(running) < window:
            task = queue.pop()
            first = task[0][0].name
            f = client.submit(process_batch, [s for s, _ in task], job, out, [m for _, m in task],
                              limit, pure=False, retries=retries,
                              key=f"shapes-{first}-{len(task)}-{uuid.uuid4().hex[:8]}")
            running[f.key] = task
            ac.add(f)

    submit()
    for f in ac:
        task = running.pop(f.key)
        if f.status == "finished":
            meta = {s.name: (s, m) for s, m in task}
            for r in f.result():
                if r["status"] == "done":
                    summary.done.append(r["name"])
                    bar.update(done=1)
                elif r["status"] == "too_large":
                    too_large.append(meta[r["name"]] + (r["estimate"],))
                else:
                    summary.failed[r["name"]] = r["error"]
                    bar.update(failed=1)
        elif len(task) > 1:       # find the shape that kills its workers: one per task
            queue.extend([x] for x in task)
        else:
            exc = f.exception()
            _record_lost(out, task[0][0], task[0][1], f"{type(exc).__name__}: {exc}", summary)
            bar.update(failed=1)
        f.release()
        submit()


def _run_locked(shapes, job, out, key, options, workers, scheduler, progress, retries, memory_limit,
                force, retry_failed, t_start) -> RunSummary:
    """The body of :func:`run`, with the store's lock held."""
    clean_partial(out)
    summary = RunSummary(out=out)
    silence = logging.ERROR if not progress else logging.WARNING
    base = {"job": job.kind, "params": job.params, "laplacian": options, "job_key": key,
            "run_id": uuid.uuid4().hex}
    pending = _pending(shapes, out, key, base, force, retry_failed, summary)
    if not pending:
        summary.seconds = time.perf_counter() - t_start
        return summary

    if scheduler is None:
        _fork_server()       # its imports overlap the client's import of dask and the scheduler's start
    require("distributed", "cluster", "spectral_igl.collection")
    client, cluster, owned = _connect(scheduler, workers, memory_limit, silence)
    bar = _Progress(len(pending), progress)
    try:
        summary.workers, limit, nthreads = _worker_limits(client)
        slots = max(summary.workers * nthreads, 1)
        too_large = []
        _dispatch(client, _batches(pending, slots), job, out, limit, retries, slots, summary, bar,
                  too_large)
        # shapes larger than a worker's limit: one at a time, largest first
        if too_large:
            if owned and cluster is not None:
                from distributed import Client

                client.close()
                cluster.close()
                cluster = _local_cluster(1, limit * summary.workers, silence)
                client = Client(cluster)
            for s, meta, est in sorted(too_large, key=lambda x: -x[2]):
                meta["run_alone"] = True
                _dispatch(client, [[(s, meta)]], job, out, None, retries, 1, summary, bar, [])
    finally:
        bar.close()
        if owned:
            client.close()
            if cluster is not None:
                cluster.close()
    summary.seconds = time.perf_counter() - t_start
    return summary
