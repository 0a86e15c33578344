"""Smoke test of an installed wheel: a heat kernel column against the dense spectrum.

Run from outside the source tree, in a venv holding only the wheel and its core
dependencies, so that the package, its compiled extensions and its generated shapes come
from the wheel. Exits non-zero on any failure.
"""
import sys
from pathlib import Path

import numpy as np
import scipy.linalg

import spectral_igl as sig
from spectral_igl.data_generators import icosphere
from spectral_igl.linalg import ldlt

root = Path(__file__).resolve().parents[1]
where = Path(sig.__file__).resolve()
assert root not in where.parents, f"spectral_igl imported from the source tree: {where}"
assert ldlt.available(), "the compiled LDLT extension is missing from the wheel"

lap = sig.laplacian(*icosphere(2))                       # 162 vertices
t, i = 0.05, 7
k, info = sig.heat_kernel(lap, t, i, return_info=True)
lam, X = scipy.linalg.eigh(lap.L.toarray(), lap.B.toarray())
exact = X @ (np.exp(-t * lam) * X[i])                    # K_t(:, i) = sum_l e^{-t lam_l} x_l(i) x_l
err = np.abs(k - exact)
assert info["bound_kind"] == "proof", info["bound_kind"]
assert np.all(err <= info["abs_error"]), float((err - info["abs_error"]).max())
assert err.max() < 1e-6, float(err.max())
for name in ("data_generators",):                        # the wheel ships no generic top-level name
    try:
        __import__(name)
    except ImportError:
        pass
    else:
        sys.exit(f"the environment has a top-level {name!r} package")
print(f"spectral_igl {sig.__version__} from {where.parent}: heat kernel column of {lap.n} entries, "
      f"max error {err.max():.2e} <= bound, LDLT kernels {ldlt.kernel_isa()}")
