"""Many shapes on dask.distributed, results in one Zarr store.

>>> from spectral_igl import collection                               # doctest: +SKIP
>>> s = collection.run("scans/*.ply", collection.Job.hks([1e-3, 1e-2]), "hks.zarr")
>>> results, failures = collection.load("hks.zarr")
>>> results["scan01"].arrays["hks"].shape                              # (n, 2)

dask and zarr are imported only when a collection is run or loaded.
"""
from .engine import RunSummary, Shape, collect_inputs, estimate_memory, inspect_shape, process_shape, run
from .jobs import FILTERS, Job
from .store import Loaded, ShapeResult, load

__all__ = ["run", "load", "Job", "FILTERS", "RunSummary", "Loaded", "ShapeResult", "Shape",
           "collect_inputs", "estimate_memory", "inspect_shape", "process_shape"]
