"""Shared fixtures: generated shapes and the optional real meshes beside the checkout."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

MESH_DIR = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "meshes"


def read_shared_mesh(name: str):
    """(V, F) of a mesh in ../shared/data/meshes, or skip the test when it is absent."""
    path = MESH_DIR / name
    if not path.exists():
        pytest.skip(f"{path} not present (real meshes live beside the checkout)")
    from spectral_igl.io import read_mesh

    return read_mesh(path)


@pytest.fixture
def shared_meshes():
    """Directory of the real meshes; skips the test when it is absent."""
    if not MESH_DIR.is_dir():
        pytest.skip(f"{MESH_DIR} not present")
    return MESH_DIR


@pytest.fixture(scope="session")
def sphere3():
    from data_generators import icosphere

    return icosphere(3)


@pytest.fixture(scope="module")
def one_blas_thread():
    """Small dense factorizations run faster on one BLAS thread (and far faster on a busy machine)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # only a matter of speed
        yield
        return
    with threadpool_limits(1):
        yield


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
