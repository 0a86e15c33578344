"""Dense ground truth for kernels and distances: K = X phi(Lambda) X^T from dense_eigs."""
from __future__ import annotations

import numpy as np
from scipy.special import eval_legendre

import spectral_igl as sig


def dense_phi(lap, fn, singular=False):
    """(lam, X, phi(lam)) with phi := 0 on ker L for singular filters."""
    lam, X = sig.dense_eigs(lap)
    with np.errstate(all="ignore"):
        ph = np.asarray(fn(lam), dtype=complex)
    if singular:
        ph[: lap.n_components] = 0.0
    if np.all(ph.imag == 0):
        ph = ph.real
    return lam, X, ph


def dense_kernel(lap, fn, singular=False):
    """(n, n) K = phi(L~) B^-1 = X phi(Lambda) X^T."""
    lam, X, ph = dense_phi(lap, fn, singular)
    return (X * ph) @ X.T


def dense_sq_distances(lap, fn, source, singular=False, delta="mass"):
    """(n,) d^2(source, j) = sum |phi|^2 |x_l(s) - x_l(j)|^2 (mass) or the seed variant."""
    lam, X, ph = dense_phi(lap, fn, singular)
    W = X if delta == "mass" else np.asarray(lap.B @ X)
    return ((W - W[source]) ** 2) @ (np.abs(ph) ** 2)


def sphere_heat_kernel(t, cos_theta, tol=1e-17):
    """Analytic heat kernel of the unit sphere, summed until the terms are below ``tol``."""
    cos_theta = np.clip(np.asarray(cos_theta, dtype=float), -1.0, 1.0)
    out = np.zeros_like(cos_theta)
    l = 0
    while True:
        w = (2 * l + 1) / (4 * np.pi) * np.exp(-l * (l + 1) * t)
        out += w * eval_legendre(l, cos_theta)
        if w < tol and l > 5:
            return out
        l += 1


def torus(nu=24, nv=12, R=1.0, r=0.4, jitter=0.0, seed=0):
    """A triangulated torus (closed, genus 1), optionally with jittered vertices."""
    u, v = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv, indexing="ij")
    u, v = u.ravel(), v.ravel()
    if jitter:
        rng = np.random.default_rng(seed)
        u = u + jitter * 2 * np.pi / nu * rng.uniform(-1, 1, u.size)
        v = v + jitter * 2 * np.pi / nv * rng.uniform(-1, 1, v.size)
    V = np.c_[(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u), r * np.sin(v)]
    idx = np.arange(nu * nv).reshape(nu, nv)
    a, b = idx, np.roll(idx, -1, axis=0)
    c, d = np.roll(idx, -1, axis=1), np.roll(np.roll(idx, -1, axis=0), -1, axis=1)
    F = np.vstack([np.c_[a.ravel(), b.ravel(), d.ravel()], np.c_[a.ravel(), d.ravel(), c.ravel()]])
    return V, F


def strip(nx=40, ny=10, length=np.pi, width=1.0, rolled=False):
    """A flat strip [0, length] x [0, width], or the same connectivity rolled into a
    half-cylinder of radius length / pi (an isometry of the smooth surface)."""
    x, y = np.meshgrid(np.linspace(0, length, nx + 1), np.linspace(0, width, ny + 1), indexing="ij")
    x, y = x.ravel(), y.ravel()
    if rolled:
        r = length / np.pi
        V = np.c_[r * np.cos(x / r), r * np.sin(x / r), y]
    else:
        V = np.c_[x, np.zeros_like(x), y]
    idx = np.arange((nx + 1) * (ny + 1)).reshape(nx + 1, ny + 1)
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[:-1, 1:], idx[1:, 1:]
    F = np.vstack([np.c_[a.ravel(), b.ravel(), d.ravel()], np.c_[a.ravel(), d.ravel(), c.ravel()]])
    return V, F
