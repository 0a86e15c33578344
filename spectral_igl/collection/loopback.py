"""A dask scheduler and workers started as separate programs on 127.0.0.1 (one machine)."""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .._validate import describe
from .engine import WORKER_CONFIG, WORKER_ENV

__all__ = ["LoopbackCluster", "worker_environment"]


def worker_environment(extra_paths=(), env=None) -> dict:
    """The environment for ``dask scheduler`` and ``dask worker`` programs started from here.

    Parameters
    ----------
    extra_paths : sequence of str or os.PathLike
        Folders put on ``PYTHONPATH`` after the one this ``spectral_igl`` is imported from
        (modules whose functions the workers must import).
    env : dict, optional
        The environment to start from (default ``os.environ``).

    Returns
    -------
    dict
        ``env`` with the folder of this ``spectral_igl`` and ``extra_paths`` first on
        ``PYTHONPATH`` (the workers import the same package as the client),
        the thread counts of ``engine.WORKER_ENV`` unless set, and
        :data:`~spectral_igl.collection.engine.WORKER_CONFIG`
        as ``DASK_*`` variables (what a local cluster's workers get).

    Examples
    --------
    >>> from spectral_igl.collection.loopback import worker_environment
    >>> env = worker_environment(env={"PATH": "/usr/bin"})
    >>> env["DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED"], env["OPENBLAS_NUM_THREADS"]
    ('False', '1')
    """
    env = dict(os.environ if env is None else env)
    root = str(Path(__file__).resolve().parents[2])
    paths = [root, *(os.fspath(p) for p in extra_paths)]
    if env.get("PYTHONPATH"):
        paths.append(env["PYTHONPATH"])
    env["PYTHONPATH"] = os.pathsep.join(paths)
    for key, value in WORKER_ENV.items():     # the thread counts a local cluster's workers get
        env.setdefault(key, value)
    for key, value in WORKER_CONFIG.items():
        env["DASK_" + key.upper().replace(".", "__").replace("-", "_")] = str(value)
    return env


class LoopbackCluster:
    """A ``dask scheduler`` and ``workers`` ``dask worker`` programs on 127.0.0.1.

    Each is its own process (its own session, so that killing one kills its children),
    started as on a cluster of many machines: the scheduler writes its address to a
    scheduler file, the workers and the client read it. A test of the multi-machine set-up
    on one machine: workers can be killed and added while a run goes on. Use it as a
    context manager; leaving it kills every process it started.

    Parameters
    ----------
    workers : int
        ``dask worker`` processes started with the scheduler (one thread each).
    folder : str or os.PathLike, optional
        Where the scheduler file and the processes' log go (default: a new temporary folder).
    memory_limit : str
        Each worker's ``--memory-limit``.
    extra_paths : sequence of str or os.PathLike
        Folders the workers also import from (see :func:`worker_environment`).
    timeout : float
        Seconds to wait for the scheduler file and for the workers to connect.

    Attributes
    ----------
    scheduler_file : pathlib.Path
        The scheduler's address file (``Client(scheduler_file=...)``).
    processes : list of subprocess.Popen
        The scheduler first, then the workers in the order they were started.

    Examples
    --------
    >>> from spectral_igl.collection import Job, run
    >>> from spectral_igl.collection.loopback import LoopbackCluster
    >>> from spectral_igl.data_generators import icosphere
    >>> with LoopbackCluster(workers=1) as cluster, cluster.client() as client:
    ...     summary = run({"ball": icosphere(1)}, Job.eigenvalues(3), "ev.zarr",
    ...                   scheduler=client, progress=False)
    >>> summary.done
    ['ball']
    """

    def __init__(self, workers: int = 2, folder=None, memory_limit: str = "2GB", extra_paths=(),
                 timeout: float = 30.0):
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
            raise ValueError(f"workers must be an integer >= 0, got {describe(workers)}")
        self._own = folder is None
        self.folder = Path(tempfile.mkdtemp(prefix="loopback-") if folder is None else folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.scheduler_file = self.folder / "scheduler.json"
        self.scheduler_file.unlink(missing_ok=True)
        self.memory_limit, self.timeout = memory_limit, float(timeout)
        self._env = worker_environment(extra_paths)
        self._log = open(self.folder / "cluster.log", "a")
        self.processes, self._initial = [], workers
        try:
            self._start("dask_scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                        "--scheduler-file", str(self.scheduler_file))
            deadline = time.monotonic() + self.timeout
            while not self.scheduler_file.is_file():
                if time.monotonic() > deadline or self.processes[0].poll() is not None:
                    raise RuntimeError(f"dask scheduler did not start; see {self.folder / 'cluster.log'}")
                time.sleep(0.05)
            for _ in range(workers):
                self.add_worker()
        except BaseException:
            self.close()
            raise

    def _start(self, program, *args):
        proc = subprocess.Popen([sys.executable, "-m", "distributed.cli." + program, *args], env=self._env,
                                start_new_session=True, stdout=self._log, stderr=subprocess.STDOUT)
        self.processes.append(proc)
        return proc

    def add_worker(self) -> subprocess.Popen:
        """Start one more ``dask worker`` (one thread, no dashboard) on 127.0.0.1.

        Returns
        -------
        subprocess.Popen
            The worker's process (also appended to ``processes``).
        """
        return self._start("dask_worker", "--scheduler-file", str(self.scheduler_file), "--nthreads", "1",
                           "--no-dashboard", "--host", "127.0.0.1", "--memory-limit", str(self.memory_limit))

    def kill_worker(self, index: int = 0) -> None:
        """Kill worker ``index`` (0: the first started) and its children with SIGKILL."""
        workers = self.processes[1:]
        if isinstance(index, bool) or not isinstance(index, int) or not -len(workers) <= index < len(workers):
            raise ValueError(f"index must be one of the {len(workers)} workers started, got {describe(index)}")
        self._kill(workers[index])

    @staticmethod
    def _kill(proc):
        if proc.poll() is None:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        proc.wait()

    def client(self, wait: int | None = None, **kwargs):
        """A ``distributed.Client`` of this cluster.

        Parameters
        ----------
        wait : int, optional
            Wait until this many workers are connected (default: the workers started with
            the cluster).
        **kwargs
            Passed to ``distributed.Client``.

        Returns
        -------
        distributed.Client
            Connected to the scheduler (close it, or use it as a context manager).
        """
        from distributed import Client

        kwargs.setdefault("timeout", self.timeout)
        client = Client(scheduler_file=str(self.scheduler_file), **kwargs)
        n = self._initial if wait is None else wait
        if n:
            try:
                client.wait_for_workers(n, timeout=self.timeout)
            except BaseException:
                client.close()
                raise
        return client

    def close(self) -> None:
        """Kill every process started (workers first), close the log, remove an own folder."""
        for proc in reversed(self.processes):
            self._kill(proc)
        if not self._log.closed:
            self._log.close()
        if self._own:
            shutil.rmtree(self.folder, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
