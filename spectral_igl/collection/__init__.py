"""Many shapes on dask.distributed, results in one Zarr store.

Usage::

    from spectral_igl import collection
    summary = collection.run("scans/*.ply", collection.Job.hks([1e-3, 1e-2]), "hks.zarr")
    results, failures = collection.load("hks.zarr")
    results["scan01"].arrays["hks"]        # (n, 2) float

dask and zarr are imported only when a collection is run or loaded.
"""
from .engine import (RunSummary, Shape, collect_inputs, estimate_memory, inspect_shape, local_cluster,
                     process_shape, run)
from .jobs import Job
from .loopback import LoopbackCluster
from .store import Loaded, ShapeResult, StoreInUse, load

__all__ = ["run", "local_cluster", "load", "Job", "RunSummary", "Loaded", "ShapeResult", "Shape",
           "collect_inputs", "estimate_memory", "inspect_shape", "process_shape", "StoreInUse",
           "LoopbackCluster"]
