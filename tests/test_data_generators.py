"""Generated shapes: their analytic spectra and measures, perturbations, and the command line."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import spectral_igl as sig
from data_generators import (
    cylinder,
    cylinder_eigenvalues,
    gaussian_noise,
    icosphere,
    make_holes,
    mean_edge_length,
    normal_noise,
    resample,
    sample_points,
    sphere_eigenvalues,
    sphere_points,
    torus,
    uv_sphere,
    vertex_normals,
)


def test_uv_sphere_spectrum_and_orientation():
    V, F = uv_sphere(40, 80)
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    assert np.all(np.einsum("ij,ij->i", N, V[F].mean(axis=1)) > 0)
    ev, _ = sig.eigs(sig.laplacian(V, F), 16)
    assert np.allclose(ev, sphere_eigenvalues(16), rtol=0.01)


def test_cylinder_spectrum_converges_at_second_order():
    exact = cylinder_eigenvalues(12, 1.0, 2.0)
    assert np.allclose(exact[:6], [0, 1, 1, (np.pi / 2) ** 2, 1 + (np.pi / 2) ** 2, 1 + (np.pi / 2) ** 2])
    errs = []
    for m in (1, 2):
        V, F = cylinder(1.0, 2.0, 32 * m, 16 * m)
        ev, _ = sig.eigs(sig.laplacian(V, F), 12)
        errs.append(np.max(np.abs(ev - exact) / np.maximum(exact, 1)))
    assert np.log2(errs[0] / errs[1]) > 1.8, errs


def test_torus_area_and_genus():
    R, r = 1.0, 0.4
    V, F = torus(R, r, 96, 48)
    lap = sig.laplacian(V, F)
    assert lap.area() == pytest.approx(4 * np.pi ** 2 * R * r, rel=2e-3)
    E = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
    assert len(V) - len(E) + len(F) == 0  # Euler characteristic of genus 1


def test_perturbations():
    V, F = icosphere(3)
    h = mean_edge_length(V, F)
    Vg = gaussian_noise(V, 0.1 * h, seed=1)
    assert np.std(Vg - V) == pytest.approx(0.1 * h, rel=0.1)
    Vn = normal_noise(V, F, 0.1 * h, seed=1)
    d = Vn - V
    assert np.allclose(np.linalg.norm(np.cross(d, vertex_normals(V, F)), axis=1), 0, atol=1e-15)
    assert np.all(np.einsum('ij,ij->i', vertex_normals(V, F), V) > 0.999)  # nearly radial
    Vr, Fr = resample(V, F, 0.5, seed=2)
    assert len(Fr) == len(F) + 2 * (len(Vr) - len(V))
    assert sig.laplacian(Vr, Fr).area() == pytest.approx(sig.laplacian(V, F).area(), rel=1e-12)
    Vh, Fh = make_holes(V, F, 3, seed=3)
    E = np.sort(np.concatenate([Fh[:, [0, 1]], Fh[:, [1, 2]], Fh[:, [2, 0]]]), axis=1)
    _, cnt = np.unique(E, axis=0, return_counts=True)
    assert np.sum(cnt == 1) > 0 and np.all(np.unique(Fh) == np.arange(len(Vh)))


def test_point_samplers():
    V, F = icosphere(4)
    P = sample_points(V, F, 5000, seed=0, project=lambda X: X / np.linalg.norm(X, axis=1, keepdims=True))
    assert np.allclose(np.linalg.norm(P, axis=1), 1)
    assert abs(P[:, 2].mean()) < 0.03  # uniform: E[z] = 0, sd 0.58/sqrt(5000)
    Q = sample_points(V, F, 5000, density=2.0, seed=0)
    assert Q[:, 2].mean() == pytest.approx(1 / 6, abs=0.03)  # density 2 + z: E[z] = (1/3) / 2
    S = sphere_points(5000, seed=0, nonuniform=1.0)
    assert S[:, 2].mean() == pytest.approx(1 / 6, abs=0.03)  # E[z] = s/3 / (1 + s)


def test_command_line(tmp_path):
    root = Path(__file__).resolve().parents[1]
    env = {"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin", "OPENBLAS_NUM_THREADS": "1"}
    for args, out in [(["torus", "--normal-noise", "0.1"], "t.off"), (["icosphere", "--points", "500"], "p.npy"),
                      (["box_voxels", "--n", "5"], "v.npy"), (["cylinder", "--holes", "2"], "c.obj")]:
        proc = subprocess.run([sys.executable, "-m", "data_generators", *args, "--out", str(tmp_path / out)],
                              capture_output=True, text=True, env=env, timeout=120)
        assert proc.returncode == 0, proc.stderr
    from spectral_igl.io import read_mesh

    V, F = read_mesh(tmp_path / "t.off")
    assert F.shape[1] == 3 and len(V) > 100
    assert np.load(tmp_path / "p.npy").shape == (500, 3)
    assert np.load(tmp_path / "v.npy").shape == (5, 5, 5)


def test_bend_is_rigid_outside_its_band_and_bends_inside():
    from data_generators import bend

    V, F = cylinder(0.1, 2.0, 16, 40)           # along z, from 0 to 2
    assert np.allclose(bend(V, 0.0), V, rtol=0, atol=1e-15)
    W = bend(V, np.pi / 4, at=0.6, band=0.3)    # joint at z = 1.2, blend over z in [0.9, 1.5]
    below, above = V[:, 2] <= 0.9 - 1e-9, V[:, 2] >= 1.5 + 1e-9
    assert np.allclose(W[below], V[below], atol=1e-12)
    # the part beyond the band turned rigidly by 45 degrees: distances kept, direction turned
    P, Q = V[above], W[above]
    assert np.allclose(np.linalg.norm(P[:, None] - P[None], axis=2),
                       np.linalg.norm(Q[:, None] - Q[None], axis=2), atol=1e-12)
    # a segment along the cylinder's axis (perpendicular to the turning axis) turns by 45 degrees
    i = np.argmax(V[:, 2])
    j = np.flatnonzero(above & np.all(np.isclose(V[:, :2], V[i, :2]), axis=1))
    j = j[np.argmin(V[j, 2])]
    a, b = V[i] - V[j], W[i] - W[j]
    assert np.isclose(a @ b / (a @ a), np.cos(np.pi / 4), rtol=1e-12)
    # inside the band the surface stretches, on the outside of the bend, by theta w' r at most
    E = np.r_[F[:, :2], F[:, 1:], F[:, ::2]]
    l0, l1 = (np.linalg.norm(X[E[:, 0]] - X[E[:, 1]], axis=1) for X in (V, W))
    strain = np.abs(l1 - l0) / l0
    assert 0.01 < strain.max() <= np.pi / 4 * 1.5 / 0.6 * 0.1 * 1.1
