"""Running a :class:`~spectral_igl.collection.jobs.Job` over many shapes on dask.distributed."""
from __future__ import annotations

import glob
import hashlib
import json
import logging
import math
import os
import resource
import socket
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._extras import require
from .._validate import as_flag, describe
from .._version import __version__
from .jobs import Job
from .store import check_name, check_record, clean_partial, lock_store, open_root, read_record, write_record

__all__ = ["run", "RunSummary", "Shape", "collect_inputs", "estimate_memory", "process_shape",
           "inspect_shape", "input_hash", "estimate_nnz"]

#: file types read by :func:`spectral_igl.io.read_mesh` (a directory input means these)
MESH_TYPES = (".obj", ".off", ".ply", ".stl", ".wrl", ".mesh")
#: fixed cost of one task in a worker (interpreter, libraries, mesh arrays), bytes
BASE_BYTES = 64 * 2 ** 20


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
    """What a :func:`run` did: names of the shapes done, skipped and failed."""

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
    list of Shape, with unique names (a file's name is its stem).
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


def process_shape(shape: Shape, job: Job, out: str, meta: dict) -> dict:
    """Read, build the Laplacian, run ``job`` and write the result (runs on a worker).

    A failure of the shape is written as a ``"failed"`` record with its error text and
    returned, never raised; only a failure to write the store raises (the scheduler then
    retries the task).
    """
    t0 = time.perf_counter()
    timings = {}
    record = dict(meta, name=shape.name, source=shape.source, version=__version__,
                  host=socket.gethostname(), pid=os.getpid())
    lap = None
    try:
        if shape.path is not None:    # the bytes actually read here
            record["input_hash"] = input_hash(shape)
        V, C = _read(shape)
        record["mesh_hash"] = _digest(np.asarray(V, dtype=float),
                                      None if C is None else np.asarray(C, dtype=np.int64))
        timings["read"] = time.perf_counter() - t0
        t = time.perf_counter()
        lap = _laplacian(V, C, meta.get("laplacian", {}))
        timings["laplacian"] = time.perf_counter() - t
        record.update(n=lap.n, nnz=int(lap.L.nnz), domain=lap.domain,
                      n_components=int(lap.n_components))
        t = time.perf_counter()
        arrays, bounds = job(shape.name, lap)
        timings["compute"] = time.perf_counter() - t
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
    record["timings"] = timings
    record["worker_peak_rss_bytes"] = _peak_rss()
    record["finished"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    write_record(out, shape.name, record, arrays)
    return {"name": shape.name, "status": record["status"], "error": record.get("error"),
            "seconds": timings["total"]}


# ---- the driver ---------------------------------------------------------------------------
def _as_job(job) -> Job:
    if isinstance(job, Job):
        return job
    if callable(job):
        return Job.function(job)
    raise TypeError(f"job must be a Job (Job.hks(...), Job.distances(...), ...) or a function "
                    f"fn(name, lap), got {describe(job)}")


def _connect(scheduler, workers, memory_limit, silence):
    """(client, cluster or None, owned)."""
    from distributed import Client, LocalCluster

    if scheduler is None:
        n = int(workers) if workers is not None else (os.cpu_count() or 1)
        if n < 1:
            raise ValueError(f"workers must be >= 1, got {workers!r}")
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               memory_limit=memory_limit, dashboard_address=None,
                               silence_logs=silence)
        return Client(cluster), cluster, True
    if isinstance(scheduler, Client):
        return scheduler, None, False
    if isinstance(scheduler, str):
        return Client(scheduler), None, True
    raise TypeError(f"scheduler must be None, an address such as 'tcp://host:8786' or a "
                    f"distributed.Client, got {describe(scheduler)}")


def _worker_limits(client):
    info = client.scheduler_info()["workers"]
    limits = [w.get("memory_limit") or 0 for w in info.values()]
    threads = [w.get("nthreads") or 1 for w in info.values()]
    mem_res = [w.get("resources", {}).get("MEMORY") for w in info.values()]
    limit = min(limits) if limits and all(limits) else None
    res = min(mem_res) if mem_res and all(r is not None for r in mem_res) else None
    return len(info), limit, max(threads, default=1), res


def run(inputs, job, out, *, workers: int | None = None, scheduler=None, progress: bool = True,
        retries: int = 2, memory_limit="auto", weights: str = "auto", mass: str = "lumped",
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
        dask's text progress bar on stdout.
    retries : int
        Times a task that raised is resubmitted (the shape's own errors are recorded, not
        raised: this covers a store that could not be written). A task whose worker died
        is resubmitted by the scheduler, up to ``distributed.scheduler.allowed-failures``
        times (dask's default 3), then recorded as failed with ``KilledWorker``.
    memory_limit : str, int or float
        Per-worker limit of the local cluster (dask's syntax: ``"auto"`` shares the
        machine's memory, ``"4GB"``, bytes).
    weights, mass : Laplacian options of :func:`spectral_igl.laplacian` (meshes).
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
    a current result. Before any work, each input is hashed and its size read (in
    parallel on the workers); its memory is estimated (:func:`estimate_memory`). Shapes
    that fit a worker's limit run in parallel, largest first; the others run afterwards
    one at a time (on a local cluster: in a single worker given the memory of all). The
    Laplacian's caches are cleared after every shape.

    A stored result is skipped only when its group matches its completion record (every
    array's shape, dtype and SHA-256, see :func:`~spectral_igl.collection.store.check_record`);
    a damaged group (a deleted chunk, truncated metadata) is listed in
    ``RunSummary.damaged`` and recomputed.

    One run per store at a time: a run holds the store's lock
    (:class:`~spectral_igl.collection.store.lock_store`), and a second run on the same
    store raises ``StoreInUse`` naming the holder before any work; the lock of a run
    that was killed is detected (its process is gone) and taken over. A run then removes
    leftovers of interrupted writes.
    """
    t_start = time.perf_counter()
    shapes = collect_inputs(inputs)
    job = _as_job(job)
    out = os.fspath(out)
    if not isinstance(retries, (int, np.integer)) or isinstance(retries, bool) or retries < 0:
        raise ValueError(f"retries must be an integer >= 0, got {retries!r}")
    options = {"weights": str(weights), "mass": str(mass)}
    ident = {"job": job.kind, "params": job.params, "laplacian": options}
    key = hashlib.sha256(json.dumps(ident, sort_keys=True).encode()).hexdigest()
    for flag, value in (("progress", progress), ("force", force), ("retry_failed", retry_failed)):
        as_flag(value, flag)
    open_root(out)
    with lock_store(out):
        return _run_locked(shapes, job, out, key, options, workers, scheduler, progress, retries,
                           memory_limit, force, retry_failed, t_start)


def _run_locked(shapes, job, out, key, options, workers, scheduler, progress, retries, memory_limit,
                force, retry_failed, t_start) -> RunSummary:
    """The body of :func:`run`, with the store's lock held."""
    clean_partial(out)
    summary = RunSummary(out=out)
    silence = logging.ERROR if not progress else logging.WARNING

    # 1. skip current results (hashes computed here: the inputs must be readable by the client)
    pending = []
    for s in shapes:
        h = input_hash(s)
        meta = {"job": job.kind, "params": job.params, "laplacian": options, "job_key": key,
                "input_hash": h}
        prev = read_record(out, s.name)
        current = (not force and prev is not None and prev.get("input_hash") == h
                   and prev.get("job_key") == key)
        problem = None
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
    if not pending:
        summary.seconds = time.perf_counter() - t_start
        return summary

    require("distributed", "cluster", "spectral_igl.collection")
    from distributed import progress as dask_progress
    from distributed import wait

    client, cluster, owned = _connect(scheduler, workers, memory_limit, silence)
    try:
        summary.workers, limit, nthreads, mem_res = _worker_limits(client)
        # 2. size every remaining input (files on the workers, arrays here); record unreadable ones
        files = [s for s, _ in pending if s.path is not None]
        futs = client.map(inspect_shape, files, pure=False, retries=retries,
                          key=[f"inspect-{s.name}-{os.urandom(4).hex()}" for s in files])
        infos = {s.name: i for s, i in zip(files, client.gather(futs))}
        todo = []
        for s, meta in pending:
            info = infos[s.name] if s.path is not None else inspect_shape(s)
            if "error" in info:
                write_record(out, s.name, dict(meta, name=s.name, source=s.source, status="failed",
                                               error=info["error"], transient=info["transient"],
                                               version=__version__))
                summary.failed[s.name] = info["error"]
                continue
            est = estimate_memory(info["n"], info["nnz"], info["domain"], job)
            meta["memory_estimate_bytes"] = est
            todo.append((est, s, meta))
        todo.sort(key=lambda x: -x[0])
        small = [x for x in todo if limit is None or x[0] <= limit]
        large = [x for x in todo if not (limit is None or x[0] <= limit)]

        # 3. shapes that fit a worker: in parallel, largest first
        def submit(items, c):
            futures = []
            for est, s, meta in items:
                kw = {}
                if mem_res is not None and nthreads > 1:   # pack by estimated memory
                    kw["resources"] = {"MEMORY": min(est, mem_res)}
                futures.append(c.submit(process_shape, s, job, out, meta, pure=False,
                                        retries=retries, priority=int(est // 2 ** 20),
                                        key=f"shape-{s.name}-{os.urandom(4).hex()}", **kw))
            return futures

        def collect(items, futures, show):
            if show and futures:
                dask_progress(futures)
            wait(futures)
            for (est, s, meta), f in zip(items, futures):
                if f.status == "finished":
                    r = f.result()
                    if r["status"] == "done":
                        summary.done.append(s.name)
                    else:
                        summary.failed[s.name] = r["error"]
                else:   # the worker died more often than allowed, or the store was not writable
                    exc = f.exception()
                    err = f"{type(exc).__name__}: {exc}"
                    summary.failed[s.name] = err
                    try:
                        write_record(out, s.name, dict(meta, name=s.name, source=s.source,
                                                       status="failed", error=err, transient=True,
                                                       version=__version__))
                    except OSError:
                        pass

        collect(small, submit(small, client), progress)

        # 4. shapes larger than a worker's limit: one at a time
        if large:
            if owned and cluster is not None:
                from distributed import Client, LocalCluster

                client.close()
                cluster.close()
                total = limit * summary.workers
                cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                       memory_limit=total, dashboard_address=None,
                                       silence_logs=silence)
                client = Client(cluster)
            for item in large:
                item[2]["run_alone"] = True
                collect([item], submit([item], client), progress)
    finally:
        if owned:
            client.close()
            if cluster is not None:
                cluster.close()
    summary.seconds = time.perf_counter() - t_start
    return summary
