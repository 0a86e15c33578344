"""Tests of optional features (the package's extras) skip, naming what is missing."""
from __future__ import annotations

import importlib.util

import pytest


def needs(*modules: str):
    """A mark skipping the test unless every one of ``modules`` is installed."""
    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    return pytest.mark.skipif(bool(missing), reason=f"needs {', '.join(missing)} (an extra of spectral-igl)")


VIZ = needs("pyvista", "matplotlib")
IO = needs("meshio")
TET = needs("pytetwild")
CLUSTER = needs("zarr", "distributed")
