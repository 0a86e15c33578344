"""Heat-method and Varadhan geodesics against exact geodesics, beside libigl and potpourri3d.

Usage::

    python benchmarks/geodesics.py [--meshes DIR] [--sources 5] [--quick] [--json-dir docs/results]

For each mesh (scaled to unit area): mean relative error |d - d*| / d* over all vertices
(sources excluded) against ``igl.exact_geodesic`` (great-circle distance on the
icosphere), averaged over random sources, at the default t (m = 1, t = m h^2) and at the
best m of a grid (tuned t); and the precompute time of each solver. Then Varadhan's
formula at several t, and the heat method on a tetrahedral ball against straight-line
distance. With ``--json-dir`` the heat-method table (``geodesics.json``: mean error at the
default t / at the tuned t, per mesh and solver) and Varadhan's (``varadhan.json``) are written
for docs/results.md.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import igl  # noqa: E402

import spectral_igl as sig  # noqa: E402
from _results import Table  # noqa: E402
from data_generators import icosphere  # noqa: E402
from spectral_igl.applications.geodesics import HeatGeodesics, mean_edge_length  # noqa: E402

M_GRID = (0.25, 0.5, 1.0, 2.0, 4.0)
#: the solvers of the heat-method table, in its column order, and their column titles
COLUMNS = {"spectral_igl intrinsic_delaunay": "intrinsic Delaunay step (default)",
           "spectral_igl euler": "backward Euler", "spectral_igl engine": 'exact heat (`step="engine"`)',
           "libigl heat_geodesics": "libigl heat", "potpourri3d": "potpourri3d"}


def rel_error(d, exact):
    m = exact > 1e-9 * exact.max()
    return float(np.mean(np.abs(d[m] - exact[m]) / exact[m]))


def load(name, mesh_dir):
    if name.startswith("icosphere"):
        V, F = icosphere(int(name[-1]))
    else:
        from spectral_igl.io import read_mesh

        V, F = read_mesh(mesh_dir / name)
    V = V / np.sqrt(igl.doublearea(V, F).sum() / 2.0)
    return V, F


def exact_distances(name, V, F, sources):
    if name.startswith("icosphere"):
        r = np.linalg.norm(V[0])
        return [r * np.arccos(np.clip(V @ V[s] / r ** 2, -1, 1)) for s in sources]
    return [igl.exact_geodesic(V, F, np.array([s]), VT=np.arange(len(V))) for s in sources]


def solvers(V, F, lap, t_coef):
    """name -> (precompute seconds, distance function)."""
    import potpourri3d as pp3d

    h = mean_edge_length(V, F)
    out = {}
    for step in ("euler", "intrinsic_delaunay", "engine"):
        t0 = time.perf_counter()
        try:
            hg = HeatGeodesics(lap, t=None if t_coef == 1.0 else None, step=step)
            if t_coef != 1.0:
                hg = HeatGeodesics(lap, t=t_coef * hg.h ** 2, step=step)
        except ImportError:
            continue
        out[f"spectral_igl {step}"] = (time.perf_counter() - t0, hg.compute)
    t0 = time.perf_counter()
    data = igl.HeatGeodesicsData()
    igl.heat_geodesics_precompute(V, F, t_coef * h * h, data)
    out["libigl heat_geodesics"] = (time.perf_counter() - t0,
                                    lambda s: igl.heat_geodesics_solve(data, np.array([s])))
    t0 = time.perf_counter()
    solver = pp3d.MeshHeatMethodDistanceSolver(V, F, t_coef=t_coef)
    out["potpourri3d"] = (time.perf_counter() - t0, solver.compute_distance)
    return out


def heat_table(names, mesh_dir, n_sources, grid):
    rows = []
    for name in names:
        try:
            V, F = load(name, mesh_dir)
        except (FileNotFoundError, ValueError) as err:
            print(f"skip {name}: {err}")
            continue
        lap = sig.laplacian(V, F, mass="lumped")
        rng = np.random.default_rng(0)
        sources = rng.choice(len(V), n_sources, replace=False)
        exact = exact_distances(name, V, F, sources)
        errs, times = {}, {}
        for m in grid:
            for key, (tp, fn) in solvers(V, F, lap, m).items():
                e = np.mean([rel_error(fn(s), ex) for s, ex in zip(sources, exact)])
                errs.setdefault(key, {})[m] = e
                if m == 1.0:
                    times[key] = tp
        for key in errs:
            best = min(errs[key], key=errs[key].get)
            rows.append((name, len(V), key, errs[key][1.0], errs[key][best], best, times[key]))
            print(f"{name:18s} n={len(V):6d} {key:34s} default {100 * errs[key][1.0]:6.2f}%  "
                  f"tuned {100 * errs[key][best]:6.2f}% (m={best:g})  precompute {times[key]:.3f} s",
                  flush=True)
    return rows


def write_heat_table(rows, json_dir):
    """The heat-method rows as one table: mesh (n), then "default / tuned" error per solver."""
    table = Table("geodesics", ["mesh (n)"] + list(COLUMNS.values()), json_dir)
    cells = {}
    for name, n, key, default, tuned, _, _ in rows:
        cells.setdefault((name, n), {})[key] = f"{100 * default:.2f} / {100 * tuned:.2f}%"
    for (name, n), by_key in cells.items():
        table.add(f"{name.rsplit('.', 1)[0]} ({n:,})", *(by_key.get(k, "") for k in COLUMNS))
    table.close()


def varadhan_table(n_sources=3, json_dir=None):
    """Varadhan's formula on the unit sphere against great-circle distance."""
    from spectral_igl.applications.geodesics import varadhan_distance

    V, F = icosphere(4)
    lap = sig.laplacian(V, F)
    h = mean_edge_length(V, F)
    rng = np.random.default_rng(0)
    sources = rng.choice(len(V), n_sources, replace=False)
    print("\nVaradhan on the unit icosphere(4), n=%d, h=%.4f: mean relative error by distance band" % (len(V), h))
    bands = [(0.0, 0.25), (0.25, 0.5), (0.5, 1.0), (1.0, 2.0), (2.0, np.pi + 0.1)]
    table = Table("varadhan", ["t / h²"] + [f"d in [{a:.2f}, {b:.2f})" for a, b in bands]
                  + ["vertices infinite"], json_dir)
    for m in (0.5, 1.0, 4.0, 16.0, 64.0, None):        # None: the default ladder of times
        t = None if m is None else m * h * h
        acc = np.zeros(len(bands))
        bad = 0
        for s in sources:
            exact = np.arccos(np.clip(V @ V[s], -1, 1))
            d = varadhan_distance(lap, s, t=t)
            bad += int(np.sum(~np.isfinite(d)))
            for k, (a, b) in enumerate(bands):
                sel = (exact >= max(a, 1e-9)) & (exact < b) & np.isfinite(d)
                acc[k] += np.mean(np.abs(d[sel] - exact[sel]) / exact[sel]) if sel.any() else np.nan
        table.add("ladder (`t=None`, the default)" if m is None else f"{m:g}",
                  *(f"{100 * a / n_sources:.2f}%" for a in acc), bad // n_sources)
    table.close()


def tet_table():
    """Heat method on a tetrahedral ball (convex: geodesic = straight line)."""
    V, T = tet_ball()
    lap = sig.laplacian(V, T, mass="lumped")
    src = int(np.argmin(np.linalg.norm(V, axis=1)))
    exact = np.linalg.norm(V - V[src], axis=1)
    print(f"\nTetrahedral ball, n={len(V)}, tets={len(T)}: mean relative error vs straight-line distance")
    for step in ("euler", "engine"):
        for m in (0.5, 1.0, 2.0, 4.0):
            try:
                hg = HeatGeodesics(lap, step=step)
                hg = HeatGeodesics(lap, t=m * hg.h ** 2, step=step)
            except ImportError:
                continue
            print(f"  {step:8s} m={m:4g}: {100 * rel_error(hg.compute(src), exact):.2f}%")


def tet_ball():
    try:
        from spectral_igl import tetrahedralize

        V, F = icosphere(3)
        return tetrahedralize(V, F)[:2]
    except ImportError:
        from data_generators import box_tets

        V, T = box_tets((12, 12, 12), (2.0, 2.0, 2.0))
        V = V - 1.0
        # map the cube to the ball (radial squash); convex, straight lines stay geodesics
        r = np.linalg.norm(V, axis=1)
        inf = np.abs(V).max(axis=1)
        scale = np.where(r > 0, inf / np.where(r > 0, r, 1), 1.0)
        return V * scale[:, None], T


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", type=Path, default=ROOT.parent / "shared" / "data" / "meshes")
    ap.add_argument("--sources", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="fewer meshes and t values")
    ap.add_argument("--json-dir", help="also write the two tables as JSON in this folder (docs/results)")
    args = ap.parse_args(argv)
    names = ["icosphere5", "spot.obj", "cow.obj", "homer.obj", "fertility.off", "cheburashka.obj",
             "rocker-arm.obj", "fandisk.obj"]
    grid = M_GRID
    if args.quick:
        names, grid = names[:3], (0.5, 1.0, 2.0)
    rows = heat_table(names, args.meshes, args.sources, grid)
    print()
    write_heat_table(rows, args.json_dir)
    try:
        varadhan_table(json_dir=args.json_dir)
    except ImportError as err:
        print(f"\nVaradhan skipped: {err}")
    tet_table()


if __name__ == "__main__":
    main()
