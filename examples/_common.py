"""Shared pieces of the example scripts: arguments, shapes, truncated spectral references, saving.

Every script ``figNN_*.py`` has ``main(argv=None) -> dict``: it parses ``--mesh``, ``--out``
and ``--quick``, writes PNGs into ``--out`` and returns its key numbers (and the list of
``images``) so that the test suite can import it and check them.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a plain script from a source checkout
    sys.path.insert(0, str(ROOT))


def parser(doc: str) -> argparse.ArgumentParser:
    """Argument parser with ``--mesh``, ``--out``, ``--quick``."""
    p = argparse.ArgumentParser(description=(doc or "").strip().splitlines()[0] if doc else None)
    p.add_argument("--mesh", help="a triangle mesh file to use instead of the generated shape")
    p.add_argument("--out", default="figures", help="output directory for the PNGs (default figures/)")
    p.add_argument("--quick", action="store_true", help="small shapes and few samples (seconds)")
    return p


#: picture size factor: quick runs render at half the resolution (4x fewer pixels)
PIXELS = {"scale": 1.0}


def out_dir(args) -> Path:
    """The output directory (created); also sets the picture size for ``--quick``."""
    PIXELS["scale"] = 0.5 if args.quick else 1.0
    d = Path(args.out)
    d.mkdir(parents=True, exist_ok=True)
    return d


def blob(level: int = 4):
    """A smooth genus-0 shape with bumps (a deformed icosphere), so that level sets bend.

    Returns ``V : (n, 3) float``, ``F : (m, 3) int``.
    """
    from data_generators import icosphere

    V, F = icosphere(level)
    x, y, z = V.T
    r = 1.0 + 0.22 * np.sin(3.0 * x + 0.5) * np.cos(2.0 * y) + 0.18 * z ** 2 - 0.12 * x * y
    V = V * r[:, None] * np.array([1.4, 1.0, 0.8])
    return V, F


def normalize_area(V, F):
    """Scale ``V`` so that the surface has unit area."""
    import igl

    area = float(np.sum(igl.doublearea(V, F))) / 2.0
    return V / np.sqrt(area)


def surface(args, level_quick: int = 3, level_full: int = 4, unit_area: bool = True):
    """``(V, F, name)``: the ``--mesh`` file, or the generated blob."""
    if args.mesh:
        from spectral_igl.io import read_mesh

        V, F = read_mesh(args.mesh)
        if F.shape[1] == 4:  # a tetrahedral mesh: its boundary surface
            V, F = boundary_surface(V, F)
        name = Path(args.mesh).stem
    else:
        V, F = blob(level_quick if args.quick else level_full)
        name = "blob"
    if unit_area:
        V = normalize_area(V, F)
    return V, F, name


def boundary_surface(V, T):
    """The boundary triangles of a tetrahedral mesh ``(V, T)`` and the vertices they use.

    Returns ``V2 : (k, 3) float``, ``F : (m, 3) int``.
    """
    faces = np.vstack([T[:, [1, 2, 3]], T[:, [0, 3, 2]], T[:, [0, 1, 3]], T[:, [0, 2, 1]]])
    key = np.sort(faces, axis=1)
    _, first, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    F = faces[first[count == 1]]  # faces of one tetrahedron only, as it orients them
    used, F = np.unique(F, return_inverse=True)
    return V[used], F.reshape(-1, 3)


def far_vertex(V, i: int = 0) -> int:
    """The vertex farthest (in space) from vertex ``i``."""
    return int(np.argmax(np.linalg.norm(V - V[i], axis=1)))


def extreme_vertex(V, axis: int = 0) -> int:
    """Vertex with the largest coordinate along ``axis`` (a tip of the shape)."""
    return int(np.argmax(V[:, axis]))


# ---- truncated spectral references (what the survey compares against) -----------------
def kernel_from_eigs(evals, X, phi, i):
    r"""Truncated :math:`\sum_l \varphi(\lambda_l) x_l(i) x_l` (all columns when ``X`` is complete)."""
    return X @ (phi(evals) * X[i])


def distance_from_eigs(evals, X, phi2, i):
    r"""Truncated :math:`d(i,\cdot) = (\sum_l \varphi^2(\lambda_l) |x_l(i) - x_l|^2)^{1/2}`."""
    D = X - X[i]
    return np.sqrt(np.maximum(D ** 2 @ phi2(evals), 0.0))


def singular(fn):
    """``fn`` with the value 0 on the (numerically) zero eigenvalues: the pseudo-inverse rule."""

    def g(s):
        s = np.asarray(s, dtype=float)
        out = np.zeros_like(s)
        pos = s > 1e-10 * max(1.0, float(np.max(np.abs(s))) if s.size else 1.0)
        out[pos] = fn(s[pos])
        return out

    return g


# ---- timing and files ----------------------------------------------------------------
class Timer:
    def __enter__(self):
        self.start = time.perf_counter()
        return self

    def __exit__(self, *exc):
        self.seconds = time.perf_counter() - self.start


def pyplot():
    from spectral_igl.viz._backend import pyplot as _p

    return _p()


def savefig(fig, path, dpi: int = 90):
    """Save a matplotlib figure as PNG and close it (at 2/3 of ``dpi`` for ``--quick``)."""
    plt = pyplot()
    fig.savefig(path, dpi=int(dpi * (1.0 if PIXELS["scale"] == 1.0 else 0.67)), bbox_inches="tight")
    plt.close(fig)
    return str(path)


def render(path, shape, f, **kwargs):
    """:func:`spectral_igl.viz.plot_levelsets` to a PNG, returning the path."""
    from spectral_igl.viz import plot_levelsets

    n = len(shape) if isinstance(shape, list) else 1
    w, h = kwargs.pop("window_size", None) or (600 * n, 600)
    scale = PIXELS["scale"]
    plot_levelsets(shape, f, filename=path, window_size=(int(w * scale), int(h * scale)), **kwargs)
    return str(path)


def summary(name: str, result: dict) -> dict:
    """Print a one-line summary of the key numbers; return ``result``."""
    items = [f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}" for k, v in result.items()
             if k != "images" and not isinstance(v, (list, dict, np.ndarray))]
    print(f"{name}: " + ", ".join(items))
    for img in result.get("images", []):
        print(f"  wrote {img}")
    return result


# ---- the package's distances (one place to call them) ---------------------------------
# The kernel diagonal of one-to-all distances is the package's default, "auto": the
# selected inversion, whose error bound is a proof as is that of the exact diagonal, at the
# cost of a few factorizations instead of one engine application per vertex (over ten
# minutes on an 8k-vertex mesh); where it does not apply, the dense diagonal on small
# meshes, else a probing estimate (the distance's info then says "estimate").
DIAGONAL = "auto"


def spectral_distance(lap, filt, i, method="auto", tol=1e-8):
    """Spectrum-free spectral distance ``d(i, :)`` of the filter ``filt``; (n,) float."""
    import spectral_igl as sig

    return np.asarray(sig.spectral_distance(lap, filt, i, method=method, tol=tol,
                                            diagonal=DIAGONAL), dtype=float)


def diffusion_distance(lap, t, i, method="auto", tol=1e-8):
    """Spectrum-free diffusion distance at time ``t`` (filter squared e^(-ts)); (n,) float."""
    import spectral_igl as sig

    return np.asarray(sig.diffusion_distance(lap, t, i, method=method, tol=tol,
                                             diagonal=DIAGONAL), dtype=float)


def biharmonic_distance(lap, i, method="auto", tol=1e-8):
    """Spectrum-free biharmonic distance (filter squared s^-2); (n,) float."""
    import spectral_igl as sig

    return np.asarray(sig.biharmonic_distance(lap, i, method=method, tol=tol,
                                              diagonal=DIAGONAL), dtype=float)


# ---- perturbations for the robustness figures ------------------------------------------
def vertex_normals(V, F):
    import igl

    return igl.per_vertex_normals(V, F)


def add_noise(V, F, amount, seed=0):
    """Move each vertex along its normal by Gaussian noise of ``amount`` x mean edge length."""
    rng = np.random.default_rng(seed)
    h = float(np.mean(np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1)))
    return V + amount * h * rng.standard_normal(len(V))[:, None] * vertex_normals(V, F)


def cut_holes(V, F, centers, radius):
    """Remove the faces within ``radius`` of the vertices ``centers``; drop unused vertices.

    Returns ``V2, F2, index`` with ``index[i]`` the new index of old vertex ``i`` (-1 if removed).
    """
    bary = V[F].mean(axis=1)
    keep = np.ones(len(F), dtype=bool)
    for c in np.atleast_1d(centers):
        keep &= np.linalg.norm(bary - V[c], axis=1) > radius
    F2 = F[keep]
    used = np.unique(F2)
    index = -np.ones(len(V), dtype=np.int64)
    index[used] = np.arange(used.size)
    return V[used], index[F2], index


def sphere_biharmonic_distance(theta, lmax=3000):
    r"""Biharmonic distance on the unit sphere at angle ``theta`` (analytic series).

    .. math:: d^2(\theta) = \sum_{l \ge 1} \frac{2l+1}{4\pi} \frac{2(1 - P_l(\cos\theta))}{(l(l+1))^2}
    """
    x = np.cos(np.asarray(theta, dtype=float))
    d2 = np.zeros_like(x)
    p_prev, p = np.ones_like(x), x.copy()  # P_0, P_1; Bonnet's recurrence for the rest
    for l in range(1, lmax + 1):
        d2 += (2 * l + 1) / (4 * np.pi) * 2 * (1 - p) / (l * (l + 1.0)) ** 2
        p_prev, p = p, ((2 * l + 1) * x * p - l * p_prev) / (l + 1)
    return np.sqrt(np.maximum(d2, 0))


# ---- critical points that matter: cancelling pairs of low persistence ---------------------
def persistent_critical_points(V, F, f, fraction=0.02):
    r"""Critical points of ``f`` after cancelling extremum-saddle pairs of low persistence.

    The piecewise-linear critical points of a smooth function sampled on a mesh come with
    spurious nearby pairs (a minimum next to a saddle where ``f`` is nearly flat). The
    sub- and super-level set sweeps pair each minimum (maximum) with the saddle where its
    component merges into an older one; pairs whose values differ by less than
    ``fraction`` of the range of ``f`` are removed together, which keeps
    :math:`m - s + M` unchanged.

    Returns
    -------
    dict
        ``{"minimum": idx, "maximum": idx, "saddle": (s, 2) rows (index, multiplicity)}``
        and the counts ``n_minima``, ``n_maxima``, ``n_saddles``, ``raw`` (the counts before).
    """
    import scipy.sparse as sp

    from spectral_igl import critical_points
    from spectral_igl.applications.basis import merge_pairs

    f = np.asarray(f, dtype=float)
    n = len(f)
    cp = critical_points(V, F, f)
    E = np.vstack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    A = sp.coo_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(n, n)).tocsr()
    A = ((A + A.T) > 0).tocsr()
    order = np.lexsort((np.arange(n), f))  # the (value, index) order of critical_points
    thr = fraction * float(np.ptp(f))
    mins = set(np.asarray(cp.minima).tolist())
    maxs = set(np.asarray(cp.maxima).tolist())
    sad = {int(i): int(k) for i, k in np.asarray(cp.saddles).reshape(-1, 2)}
    for sweep, extrema in ((order, mins), (order[::-1], maxs)):
        for ext, saddle in merge_pairs(sweep, A.indptr, A.indices)[0]:
            if abs(float(f[saddle] - f[ext])) < thr and ext in extrema and sad.get(saddle, 0) > 0:
                extrema.discard(ext)
                sad[saddle] -= 1
    saddles = np.array([[i, k] for i, k in sorted(sad.items()) if k > 0], dtype=np.int64).reshape(-1, 2)
    return {"minimum": np.array(sorted(mins), dtype=np.int64),
            "maximum": np.array(sorted(maxs), dtype=np.int64), "saddle": saddles,
            "n_minima": len(mins), "n_maxima": len(maxs), "n_saddles": int(saddles[:, 1].sum()),
            "raw": (cp.n_minima, cp.n_maxima, cp.n_saddles)}
