"""Shapes with dense ground truth shared by the engine tests."""
import numpy as np

import spectral_igl as sig
from data_generators import box_tets, icosphere

HEAT_TIMES = [1e-5, 1e-3, 1e-1, 10.0]


def two_spheres():
    V, F = icosphere(2)
    V2 = V * 0.5 + np.array([3.0, 0, 0])
    return sig.laplacian(np.vstack([V, V2]), np.vstack([F, F + len(V)]), mass="full")


def unit_area(lap_fn, V, F, **kw):
    lap = lap_fn(V, F, **kw)
    d = 2 if F.shape[1] == 3 else 3
    return lap_fn(V / lap.area() ** (1 / d), F, **kw)


SHAPES = {
    "sphere": lambda: unit_area(sig.laplacian, *icosphere(3), mass="full"),
    "sphere_lumped": lambda: unit_area(sig.laplacian, *icosphere(3), mass="lumped"),
    "box_tets": lambda: sig.laplacian(*box_tets((7, 5, 4)), mass="full"),
    "two_spheres": two_spheres,
}
_cache = {}


def shape(name):
    if name not in _cache:
        lap = SHAPES[name]()
        _cache[name] = (lap, *sig.dense_eigs(lap))
    return _cache[name]


def truth(lap, ev, X, filt, f, rhs=False):
    c = X.T @ (f if rhs else lap.B @ f)
    phi = filt(ev)
    return X @ (phi[:, None] * c if f.ndim == 2 else phi * c)


def bnorm(lap, x):
    return np.sqrt(np.maximum(np.real(np.sum(np.conj(x) * (lap.B @ x), axis=0)), 0))


def check(lap, ev, X, filt, method, f, tol=1e-8, rhs=False, **opt):
    op = sig.SpectralOperator(lap, filt, method=method, tol=tol, **opt)
    u = op.apply_inverse_mass(f) if rhs else op.apply(f)
    assert u.shape == f.shape
    ref = truth(lap, ev, X, filt, f, rhs)
    err = bnorm(lap, u - ref)
    # the dense ground truth carries its own rounding (~1e-13 relative)
    slack = 1e-12 * bnorm(lap, ref) + 1e-13 * (bnorm(lap, f) if not rhs else np.linalg.norm(X.T @ f, axis=0))
    return op, err, slack


