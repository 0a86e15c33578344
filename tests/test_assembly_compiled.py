"""The compiled per-element kernels equal their NumPy references (skipped without a build)."""
import numpy as np
import pytest

import spectral_igl as sig
from data_generators import cylinder, icosphere, sphere_points, torus
from spectral_igl.laplacian import anisotropic, points

_assembly = pytest.importorskip("spectral_igl.laplacian._assembly")


@pytest.mark.parametrize("shape", ["sphere", "torus", "cylinder", "noisy"])
@pytest.mark.parametrize("alpha", [0.0, 3.0])
def test_anisotropic_faces_match_numpy(shape, alpha):
    V, F = {"sphere": lambda: icosphere(3), "torus": torus, "cylinder": cylinder,
            "noisy": lambda: icosphere(3)}[shape]()
    if shape == "noisy":
        V = V * (1 + 0.05 * np.random.default_rng(0).standard_normal((len(V), 1)))
    kc, dc, Kc = _assembly.anisotropic_faces(V, F, alpha)
    kn, dn, Kn = anisotropic._anisotropic_faces_numpy(V, F, alpha)
    scale = np.abs(kn).max()
    assert np.abs(kc - kn).max() <= 1e-12 * scale
    assert np.abs(Kc - Kn).max() <= 1e-12 * np.abs(Kn).max()
    # directions agree up to sign where the principal curvatures are distinct
    gap = (kn[:, 1] - kn[:, 0]) > 1e-6 * scale
    dots = np.abs(np.einsum("mai,mai->ma", dc, dn))[gap]
    assert np.allclose(dots, 1.0, atol=1e-9)
    assert np.allclose(np.linalg.norm(dc, axis=2), 1.0, atol=1e-14)


def test_anisotropic_laplacian_matches_numpy_path(monkeypatch):
    V, F = torus()
    lap_c = sig.anisotropic_laplacian(V, F, 2.0)
    monkeypatch.setattr(anisotropic, "_faces_compiled", None)
    lap_n = sig.anisotropic_laplacian(V, F, 2.0)
    assert abs(lap_c.L - lap_n.L).max() <= 1e-12 * abs(lap_n.L).max()
    assert abs(lap_c.B - lap_n.B).max() == 0


@pytest.mark.parametrize("seed", [0, 1])
def test_clip_cells_match_numpy(seed):
    rng = np.random.default_rng(seed)
    Q = rng.standard_normal((500, 24, 2))
    Q[:7, 3] = 0.0  # coincident neighbours clip nothing
    half = 1.5 * np.sort(np.linalg.norm(Q, axis=2), axis=1)[:, 7]
    a_c = _assembly.clip_cells(Q, half)
    a_n = points._clip_cells(Q, half)
    assert np.abs(a_c - a_n).max() <= 1e-12 * np.abs(a_n).max()


def test_liu_matches_numpy_path(monkeypatch):
    P = sphere_points(3000, seed=2)
    lap_c = sig.point_cloud_laplacian(P, method="liu")
    monkeypatch.setattr(points, "_clip_compiled", None)
    lap_n = sig.point_cloud_laplacian(P, method="liu")
    assert abs(lap_c.L - lap_n.L).max() <= 1e-12 * abs(lap_n.L).max()
    assert np.abs(lap_c.B.diagonal() - lap_n.B.diagonal()).max() <= 1e-12 * lap_n.B.diagonal().max()
