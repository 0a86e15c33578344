"""Anisotropic Laplacian: exact cotan limit, curvature frames, and spectra with known scaling."""
import numpy as np
import pytest

import spectral_igl as sig
from data_generators import cylinder, icosphere, sphere_eigenvalues, torus
from spectral_igl.laplacian.anisotropic import face_curvature


@pytest.mark.parametrize("shape", ["sphere", "torus", "cylinder"])
def test_alpha_zero_is_cotan_exactly(shape):
    V, F = {"sphere": lambda: icosphere(3), "torus": torus, "cylinder": cylinder}[shape]()
    a = sig.anisotropic_laplacian(V, F, alpha=0.0)
    c = sig.laplacian(V, F, weights="cotan", mass="full")   # what alpha = 0 reduces to
    assert abs(a.L - c.L).max() <= 1e-12 * abs(c.L).max()
    assert abs(a.B - c.B).max() == 0


def test_cylinder_principal_frame():
    V, F = cylinder(radius=0.5, height=2.0, n_theta=64, n_z=32)
    kappa, dirs = face_curvature(V, F)
    # away from the rims (where one-sided vertex normals tilt): |κ| = 0 along the axis and
    # 1/r around it (sign follows the orientation)
    z = V[F, 2]
    inner = (z.min(axis=1) > 0.1) & (z.max(axis=1) < 1.9)
    kappa, dirs, F = kappa[inner], dirs[inner], F[inner]
    k = np.sort(np.abs(kappa), axis=1)
    assert np.allclose(k[:, 0], 0.0, atol=1e-8)
    assert np.median(k[:, 1]) == pytest.approx(2.0, rel=0.01)
    flat = np.argmin(np.abs(kappa), axis=1)
    axis_dir = dirs[np.arange(len(F)), flat]
    assert np.allclose(np.abs(axis_dir[:, 2]), 1.0, atol=1e-8)


def test_sphere_spectrum_scales_by_phi():
    # on the unit sphere κ_m = κ_M = 1, so D = I / (1 + α) and λ_l = l(l+1) / (1 + α)
    V, F = icosphere(4)
    alpha = 3.0
    ev, _ = sig.eigs(sig.anisotropic_laplacian(V, F, alpha), 16)
    evc, _ = sig.eigs(sig.laplacian(V, F, weights="cotan", mass="full"), 16)
    assert np.allclose(ev[1:], evc[1:] / (1 + alpha), rtol=0.01)
    assert np.allclose(ev[1:], sphere_eigenvalues(16)[1:] / (1 + alpha), rtol=0.02)


def test_cylinder_slows_only_the_curved_direction():
    # κ = 0 along z: the axial modes (πl/h)² keep their eigenvalue; angular modes (m/r)²
    # are divided by 1 + α/r
    r, h, alpha = 1.0, 2.0, 1.0
    V, F = cylinder(r, h, n_theta=96, n_z=48)
    lap = sig.anisotropic_laplacian(V, F, alpha)
    ev, X = sig.eigs(lap, 6)
    theta = np.arctan2(V[:, 1], V[:, 0])
    axial = np.cos(np.pi * V[:, 2] / h)
    ang = np.cos(theta)
    rq = lambda f: float(f @ (lap.L @ f) / (f @ (lap.B @ f)))  # noqa: E731
    assert rq(axial) == pytest.approx((np.pi / h) ** 2, rel=0.01)
    assert rq(ang) == pytest.approx(1 / r ** 2 / (1 + alpha / r), rel=0.01)
    assert ev[1] == pytest.approx(0.5, rel=0.01)  # the angular pair now comes first


def test_properties_on_a_creased_shape(rng):
    V, F = icosphere(3)
    V = V * np.array([1.0, 1.0, 0.3])  # flattened: strong curvature at the rim
    lap = sig.anisotropic_laplacian(V, F, alpha=20.0, mass="lumped")
    L = lap.L
    assert abs(L - L.T).max() <= 1e-14 * abs(L).max()
    assert np.abs(L @ np.ones(lap.n)).max() <= 1e-12 * abs(L).max()
    f = rng.standard_normal((lap.n, 20))
    assert np.all(np.einsum("ij,ij->j", f, L @ f) > 0)
    ev, _ = sig.eigs(lap, 6)
    assert ev[0] == 0 and ev[1] > 0


def test_rejects_negative_alpha():
    V, F = icosphere(1)
    with pytest.raises(ValueError, match="alpha"):
        sig.anisotropic_laplacian(V, F, -1.0)
    with pytest.raises(TypeError, match="alpha"):
        sig.anisotropic_laplacian(V, F, "big")
