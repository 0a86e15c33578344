"""Timing helper shared by the benchmark scripts (run as ``python benchmarks/<script>.py``,
which puts this folder on the import path)."""
from __future__ import annotations

import time

import numpy as np


def median_time(fn, repeat: int):
    """(median wall time of ``repeat`` calls of fn, the last call's result)."""
    ts, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts)), out
