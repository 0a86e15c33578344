"""Schrödinger propagator through the engine: unitarity and the dense solution."""
from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("spectral_igl.filters")

import spectral_igl as sig  # noqa: E402
from data_generators import icosphere  # noqa: E402
from spectral_igl.applications import schrodinger  # noqa: E402


def test_unitary_and_dense():
    V, F = icosphere(2)
    lap = sig.laplacian(V, F)
    lam, X = sig.dense_eigs(lap)
    h = np.exp(-4 * np.linalg.norm(V - V[0], axis=1) ** 2)
    nh = np.sqrt(h @ (lap.B @ h))
    for t in (0.05, 0.4, -0.2):
        H = schrodinger(lap, h, t)
        assert np.iscomplexobj(H) and H.shape == h.shape
        nH = np.sqrt(np.real(np.conj(H) @ (lap.B @ H)))
        assert abs(nH - nh) < 1e-8 * nh
        expected = X @ (np.exp(-1j * lam * t) * (X.T @ (lap.B @ h)))
        d = H - expected
        assert np.sqrt(np.real(np.conj(d) @ (lap.B @ d))) < 1e-7 * nh
    np.testing.assert_array_equal(schrodinger(lap, h, 0.0), h)
    with pytest.raises(TypeError):
        schrodinger(lap, h, "1")
