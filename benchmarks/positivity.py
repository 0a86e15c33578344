"""Positivity of heat kernels, and what the Metzler default costs in accuracy.

Sections (``--section``, default all):

``heat``
    Every mesh in ``--meshes`` (scaled to unit area, tetrahedra to unit volume) and three
    generated ones (a flat jittered grid with obtuse triangles on its boundary, a
    non-manifold "book" of three jittered pages sharing an edge, a jittered tetrahedral
    cube): whether L is Metzler, how many edge weights the default sets to 0, and
    min/max of the heat kernel over 5 sources at t = 1e-5 ... 1e-1, for the default
    Laplacian and for ``positive=False`` (the previous default). The kernel is exact: a
    dense eigendecomposition for n <= 3000, else ``heat_kernels`` at tol = 1e-12.
``accuracy``
    Neumann unit square (jittered grids, N x N cells): largest relative error of the first
    12 nonzero eigenvalues against pi^2 (i^2 + j^2), and max-norm error of heat-kernel
    columns at t = 1e-2 against the analytic kernel, relative to its peak. The book:
    eigenvalues against pi^2 (i^2 + j^2) (once) and pi^2 ((i + 1/2)^2 + j^2) (twice). The
    jittered unit cube: first 10 nonzero eigenvalues against pi^2 (i^2 + j^2 + k^2).
``sphere``
    Unit sphere: heat kernel at t = 0.05 against the analytic series, and the first 25
    eigenvalues, for the defaults against cotan + full mass; real meshes at t = 1e-3.

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/positivity.py [--meshes ../shared/data/meshes]
        [--section heat accuracy sphere]
"""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla
from scipy.special import eval_legendre

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import spectral_igl as sig  # noqa: E402
from data_generators import box_eigenvalues, box_tets, icosphere  # noqa: E402
from spectral_igl import filters  # noqa: E402
from spectral_igl.io import read_mesh  # noqa: E402
from spectral_igl.laplacian import make_laplacian  # noqa: E402

TIMES = (1e-5, 1e-4, 1e-3, 1e-2, 1e-1)
DENSE_MAX = 3000


# ---------------------------------------------------------------- generated domains
def jittered_square(N: int, jitter: float = 0.35, seed: int = 0, first_row: float = 0.4):
    """Unit square, N x N cells cut in two, every vertex moved by up to ``jitter`` cells
    (boundary vertices along the boundary only), the rows next to the boundary at
    ``first_row`` cells from it: many boundary edges face an obtuse angle, which no
    intrinsic flip can change."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 1.0, N + 1)
    X, Y = np.meshgrid(x, x, indexing="ij")
    V = np.c_[X.ravel(), Y.ravel()]
    J = rng.uniform(-jitter, jitter, V.shape) / N
    h = 1.0 / N
    for a in range(2):
        J[(V[:, a] == 0) | (V[:, a] == 1), a] = 0.0
        lo, hi = np.isclose(V[:, a], h), np.isclose(V[:, a], 1 - h)
        J[lo, a] = (first_row - 1) * h
        J[hi, a] = (1 - first_row) * h
    V = V + J
    idx = np.arange((N + 1) ** 2).reshape(N + 1, N + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel()
    return np.c_[V, np.zeros(len(V))], np.r_[np.c_[a, b, d], np.c_[a, d, c]]


def quads(V: np.ndarray, N: int) -> np.ndarray:
    """The N x N quads of a :func:`jittered_square`'s vertices."""
    idx = np.arange((N + 1) ** 2).reshape(N + 1, N + 1)
    return np.c_[idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()]


def book(N: int, pages: int = 3, seed: int = 0):
    """``pages`` jittered unit squares sharing the edge x = 0 (non-manifold there)."""
    V0, F0 = jittered_square(N, seed=seed)
    spine = np.flatnonzero(V0[:, 0] == 0)
    Vs, Fs, n = [], [], 0
    for p in range(pages):
        Vp, Fp = jittered_square(N, seed=seed + p)
        Vp[spine] = V0[spine]                      # one shared spine
        ang = 2 * np.pi * p / pages
        X = np.c_[Vp[:, 0] * np.cos(ang), Vp[:, 1], Vp[:, 0] * np.sin(ang)]
        new = np.full(len(Vp), -1)
        keep = np.ones(len(Vp), bool)
        if p:
            keep[spine] = False
            new[spine] = spine
        new[keep] = n + np.arange(keep.sum())
        Vs.append(X[keep])
        Fs.append(new[Fp])
        n += int(keep.sum())
    return np.vstack(Vs), np.vstack(Fs)


def book_eigenvalues(k: int, pages: int = 3) -> np.ndarray:
    """Neumann spectrum of the book: pi^2 (i^2 + j^2) once, pi^2 ((i + 1/2)^2 + j^2) pages - 1 times."""
    i, j = np.meshgrid(np.arange(12), np.arange(12), indexing="ij")
    a = np.pi ** 2 * (i ** 2 + j ** 2)
    b = np.pi ** 2 * ((i + 0.5) ** 2 + j ** 2)
    return np.sort(np.r_[a.ravel(), np.repeat(b.ravel(), pages - 1)])[:k]


def jittered_cube(N: int, jitter: float = 0.2, seed: int = 0):
    """Unit cube of N^3 Kuhn-subdivided cells, vertices moved by up to ``jitter`` cells."""
    V, T = box_tets((N, N, N), (1.0, 1.0, 1.0))
    J = np.random.default_rng(seed).uniform(-jitter, jitter, V.shape) / N
    for d in range(3):
        J[(V[:, d] < 1e-12) | (V[:, d] > 1 - 1e-12), d] = 0.0
    return V + J, T


def square_heat(t: float, P: np.ndarray, q: np.ndarray, terms: int = 200) -> np.ndarray:
    """Neumann heat kernel of the unit square between the points P (n, 2) and q (2,)."""
    k = np.arange(1, terms)
    w = np.exp(-np.pi ** 2 * k ** 2 * t)

    def one(x, y):
        return 1.0 + 2.0 * (np.cos(np.pi * np.outer(x, k)) * np.cos(np.pi * k * y) * w).sum(axis=1)

    return one(P[:, 0], q[0]) * one(P[:, 1], q[1])


# ---------------------------------------------------------------- helpers
def unit(lap_fn, V, F, **kw):
    """Laplacian of (V, F) scaled to unit area (unit volume for tetrahedra)."""
    lap = lap_fn(V, F, **kw)
    dim = 3 if np.shape(F)[1] == 4 and lap.domain == "tet" else 2
    return lap_fn(V / lap.area() ** (1.0 / dim), F, **kw)


def exact_heat(lap, times, sources):
    """(n, m, T) heat-kernel columns, exact to rounding (dense) or to 1e-12 (large n)."""
    if lap.n <= DENSE_MAX:
        ev, X = sla.eigh(lap.L.toarray(), lap.B.toarray())
        Xs = X[sources]
        return np.stack([(X * np.exp(-t * np.maximum(ev, 0))) @ Xs.T for t in times], axis=2)
    return sig.kernels.heat_kernels(lap, times, sources, tol=1e-12)


def clamp_only(V, F):
    """Intrinsic Delaunay without the mirror flips, its negative weights set to 0."""
    lap = sig.laplacian(V, F, positive=False)
    off = lap.L.minimum(0)                  # negative entries: off-diagonal, weights >= 0 kept
    clamped = (lap.L.nnz - off.nnz - lap.n) // 2
    return make_laplacian(off, lap.B, data={"clamped": clamped})


def eig_error(lap, ref):
    k = len(ref)
    if lap.n <= DENSE_MAX:
        ev = sla.eigh(lap.L.toarray(), lap.B.toarray(), eigvals_only=True, subset_by_index=[1, k])
    else:
        ev = np.sort(spla.eigsh(lap.L.tocsc(), k + 1, lap.B.tocsc(), sigma=-1e-3, which="LM")[0])[1:]
    return float(np.max(np.abs(ev - ref) / ref))


def fmt_ratio(K):
    return f"{K.min() / K.max():.1e}"


# ---------------------------------------------------------------- sections
def domains(meshes: Path):
    out = []
    for path in sorted(meshes.iterdir()):
        if path.suffix.lower() not in (".obj", ".off", ".ply", ".stl", ".mesh"):
            continue
        V, F = read_mesh(path)
        out.append((path.name, np.asarray(V, float), F))
    out.append(("flat jittered grid 64^2", *jittered_square(64)))
    out.append(("non-manifold book 3 x 24^2", *book(24)))
    out.append(("jittered tet cube 12^3", *jittered_cube(12)))
    return out


def section_heat(meshes: Path):
    print("\nHeat kernel min/max over 5 sources, unit area/volume, exact kernel "
          f"(dense eigh for n <= {DENSE_MAX}, else heat_kernels tol = 1e-12); 'sig.heat_kernel': "
          "the default call (tol = 1e-8)\n")
    print("| mesh | n | Laplacian | Metzler | weights set to 0 | "
          + " | ".join(f"t = {t:g}" for t in TIMES) + " |")
    print("|---|---|---|---|---|" + "---|" * len(TIMES))
    settings = (("default", {}), ("positive=False", {"positive": False}), ("positive=True", {"positive": True}))
    for name, V, F in domains(meshes):
        for label, kw in settings:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                lap = unit(sig.laplacian, V, F, **kw)
            if label == "positive=True" and lap.domain != "tet":
                continue                                       # the default already
            src = np.linspace(0, lap.n - 1, 5).astype(int)
            K = exact_heat(lap, TIMES, src)
            row(name, lap, label, [K[:, :, a] for a in range(len(TIMES))])
            if label == "default":                             # as users call it: tol = 1e-8
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    row(name, lap, "default, sig.heat_kernel", [sig.heat_kernel(lap, t, src) for t in TIMES])


def row(name, lap, label, kernels):
    cells = " | ".join(fmt_ratio(K) for K in kernels)
    print(f"| {name} | {lap.n:,} | {label} | {'yes' if lap.is_metzler else 'no'} | "
          f"{lap.data.get('clamped', 0):,} | {cells} |", flush=True)


def section_accuracy():
    print("\nNeumann unit square, jittered grids: eigenvalues 1..12 (largest relative error) and "
          "heat kernel at t = 1e-2 (max-norm error / peak, 5 sources) against the analytic ones\n")
    print("| N | n | Laplacian | weights set to 0 | eigenvalues | heat t = 1e-2 |")
    print("|---|---|---|---|---|---|")
    ref = np.sort([np.pi ** 2 * (i * i + j * j) for i in range(8) for j in range(8)])[1:13]
    settings = (("default", {}), ("positive=False", {"positive": False}), ("clamp only", None),
                ("cotan", {"weights": "cotan"}), ("cotan, positive=True", {"weights": "cotan", "positive": True}))
    for N in (8, 16, 32, 64, 128):
        V, F = jittered_square(N)
        for label, kw in settings:
            lap = clamp_only(V, F) if kw is None else sig.laplacian(V, F, **kw)
            src = np.linspace(0, lap.n - 1, 5).astype(int)
            if lap.n <= DENSE_MAX:
                K = exact_heat(lap, [1e-2], src)[:, :, 0]
            else:
                K = sig.kernels.heat_kernels(lap, [1e-2], src, tol=1e-12)[:, :, 0]
            Kc = np.stack([square_heat(1e-2, V[:, :2], V[s, :2]) for s in src], axis=1)
            herr = float(np.max(np.abs(K - Kc)) / np.max(Kc))
            print(f"| {N} | {lap.n:,} | {label} | {lap.data['clamped']:,} | {eig_error(lap, ref):.2e} | "
                  f"{herr:.2e} |", flush=True)
    print("\nThe same vertices as quads (polygon Laplacian): eigenvalues 1..12\n")
    print("| N | n | Laplacian | weights set to 0 | eigenvalues |")
    print("|---|---|---|---|---|")
    for N in (8, 16, 32, 64):
        V, _ = jittered_square(N)
        for label, kw in (("default", {}), ("positive=True", {"positive": True})):
            lap = sig.laplacian(V, quads(V, N), elements="polygon", **kw)
            print(f"| {N} | {lap.n:,} | {label} | {lap.data['clamped']:,} | {eig_error(lap, ref):.2e} |", flush=True)
    print("\nNon-manifold book of 3 jittered unit squares: eigenvalues 1..12\n")
    print("| N | n | Laplacian | weights set to 0 | eigenvalues |")
    print("|---|---|---|---|---|")
    ref = book_eigenvalues(13)[1:]
    for N in (8, 16, 32, 64):
        V, F = book(N)
        for label, kw in (("default", {}), ("positive=False", {"positive": False}), ("clamp only", None),
                          ("cotan", {"weights": "cotan"})):
            lap = clamp_only(V, F) if kw is None else sig.laplacian(V, F, **kw)
            print(f"| {N} | {lap.n:,} | {label} | {lap.data['clamped']:,} | {eig_error(lap, ref):.2e} |", flush=True)
    print("\nJittered unit cube (tets): eigenvalues 1..10\n")
    print("| N | n | Laplacian | weights set to 0 | eigenvalues |")
    print("|---|---|---|---|---|")
    ref = box_eigenvalues(11, (1.0, 1.0, 1.0))[1:]
    for N in (4, 8, 12, 16):
        V, T = jittered_cube(N)
        for label, kw in (("default (cotan)", {}), ("positive=True", {"positive": True})):
            lap = sig.laplacian(V, T, **kw)
            print(f"| {N} | {lap.n:,} | {label} | {lap.data['clamped']:,} | {eig_error(lap, ref):.2e} |", flush=True)


def sphere_kernel(t, cos):
    return sum((2 * k + 1) / (4 * np.pi) * np.exp(-t * k * (k + 1)) * eval_legendre(k, cos) for k in range(200))


def section_sphere(meshes: Path, names):
    settings = [("defaults", {}), ("cotan + full", {"weights": "cotan", "mass": "full"})]
    t = 0.05
    print("\n| discretization | max-norm error, n = 162 / 642 / 2562 / 10242 | rates | "
          "eigenvalue error n = 642 / 2562 |")
    print("|---|---|---|---|")
    for label, kw in settings:
        errs, specs = [], []
        for lev in (2, 3, 4, 5):
            V, F = icosphere(lev)
            V = V / np.linalg.norm(V, axis=1)[:, None]
            lap = sig.laplacian(V, F, **kw)
            e = np.zeros(lap.n)
            e[0] = 1.0
            u = sig.SpectralOperator(lap, filters.heat(t), method="rational", tol=1e-10).apply_inverse_mass(e)
            errs.append(np.abs(u - sphere_kernel(t, V @ V[0])).max())
            if lev in (3, 4):
                ev, _ = sig.eigs(lap, 25)
                ref = np.concatenate([[l * (l + 1)] * (2 * l + 1) for l in range(5)])[:25]
                specs.append(np.abs(ev - ref).max())
        rates = np.log(np.array(errs[:-1]) / np.array(errs[1:])) / np.log(2)
        print(f"| {label} | {' / '.join(f'{x:.2e}' for x in errs)} | {' / '.join(f'{r:.2f}' for r in rates)} "
              f"| {' / '.join(f'{x:.2f}' for x in specs)} |", flush=True)
    print("\n| mesh | n | " + " | ".join(f"{label}: min/max" for label, _ in settings) + " |")
    print("|---|---|" + "---|" * len(settings))
    for name in names:
        path = meshes / name
        if not path.exists():
            continue
        V, F = read_mesh(path)
        V = np.asarray(V, float)
        cells = []
        for _, kw in settings:
            lap = unit(sig.laplacian, V, F, **kw)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                K = sig.heat_kernel(lap, 1e-3, np.arange(0, lap.n, max(1, lap.n // 20)))
            cells.append(fmt_ratio(K))
        print(f"| {name} | {lap.n} | " + " | ".join(cells) + " |", flush=True)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--meshes", default=str(Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes"))
    p.add_argument("--section", nargs="*", default=["heat", "accuracy", "sphere"],
                   choices=["heat", "accuracy", "sphere"])
    p.add_argument("--names", nargs="*", default=["spot.obj", "cheburashka.obj", "fertility.off", "homer.obj"],
                   help="meshes of the sphere section's real-mesh table")
    args = p.parse_args(argv)
    meshes = Path(args.meshes)
    if "heat" in args.section:
        section_heat(meshes)
    if "accuracy" in args.section:
        section_accuracy()
    if "sphere" in args.section:
        section_sphere(meshes, args.names)


if __name__ == "__main__":
    main()
