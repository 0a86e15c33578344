"""Diffusion distances to a few targets from local heat columns, against dense generalized
eigendecompositions."""
import numpy as np
import pytest
import scipy.linalg as sl

import spectral_igl as sig
from spectral_igl.data_generators import icosphere

#: rounding of the dense reference, relative to the largest distance (eigh of n <= 700)
REFERENCE = 1e-12


def _two_components():
    V1, F1 = icosphere(3)
    V2, F2 = icosphere(1, radius=0.3)
    return np.r_[V1, V2 + [3.0, 0.0, 0.0]], np.r_[F1, F2 + len(V1)]


MESHES = {"icosphere": lambda: icosphere(3), "two": _two_components}
_CACHE = {}


def _exact(name):
    if name not in _CACHE:
        V, F = MESHES[name]()
        lap = sig.laplacian(V, F)
        lap = sig.laplacian(V / np.sqrt(lap.area()), F)     # unit area
        assert lap.is_metzler
        _CACHE[name] = (lap,) + tuple(sl.eigh(lap.L.toarray(), lap.B.toarray()))
    return _CACHE[name]


@pytest.mark.parametrize("name, source, targets", [("icosphere", 7, [7, 8, 100, 641]),
                                                    ("two", 5, [5, 6, 300, 650, 680]),
                                                    ("two", 650, 651)])
@pytest.mark.parametrize("t", [2e-5, 1e-4, 2e-4])
def test_local_diffusion_distance_within_its_proved_bound(monkeypatch, name, source, targets, t):
    monkeypatch.setattr(sig.distances, "LOCAL_MIN_VERTICES", 0)
    lap, w, X = _exact(name)
    idx = np.atleast_1d(targets)
    exact = np.sqrt(np.exp(-t * w) @ (X[source] - X[idx]).T ** 2)
    d, info = sig.diffusion_distance(lap, t, source, targets, return_info=True)
    assert info["method"] == "local" and info["bound_kind"] == "proof"
    assert np.shape(d) == np.shape(targets)
    d, err = np.atleast_1d(d), np.atleast_1d(info["abs_error"])
    # every distance within its bound, and the bound within the global path's promise
    assert np.all(np.abs(d - exact) <= err + REFERENCE * exact.max())
    promise = 1e-8 * np.sqrt(1.0 / lap.mass[source] + 1.0 / lap.mass[idx])
    assert np.all(err <= promise)
    assert np.all(d[idx == source] == 0.0)


def test_local_diffusion_distance_same_as_global_path(monkeypatch):
    monkeypatch.setattr(sig.distances, "LOCAL_MIN_VERTICES", 0)
    lap, w, X = _exact("icosphere")
    d, info = sig.diffusion_distance(lap, 1e-4, 3, [4, 50, 300], return_info=True)
    g, ginfo = sig.diffusion_distance(lap, 1e-4, 3, [4, 50, 300], method="rational", return_info=True)
    assert info["method"] == "local" and ginfo["method"] != "local"
    assert np.all(np.abs(d - g) <= info["abs_error"] + ginfo["abs_error"])


def test_large_t_distance_takes_the_global_path(monkeypatch):
    monkeypatch.setattr(sig.distances, "LOCAL_MIN_VERTICES", 0)
    lap, w, X = _exact("icosphere")
    t = 0.1
    d, info = sig.diffusion_distance(lap, t, 3, [4, 300], return_info=True)
    exact = np.sqrt(np.exp(-t * w) @ (X[3] - X[[4, 300]]).T ** 2)
    assert info["method"] != "local"
    assert np.all(np.abs(d - exact) <= info["abs_error"] + REFERENCE * exact.max())
