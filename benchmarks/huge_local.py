"""Local heat columns and HKS entries of a shape of millions of vertices, column by column.

A scan (default the 43k armadillo) midpoint-subdivided k times (x16: 0.69M vertices, x64: 2.8M,
x256: 11M; the subdivided mesh is cached as .npy under ``--cache``), scaled to unit area. The
default Laplacian is built once (seconds, peak resident memory); then, at each t, local heat
columns (:func:`spectral_igl.approx.region.region_heat_column`, the engine of
:func:`spectral_igl.local_heat_kernel`, without a budget: the global path, a factorization of the
whole shape, is not what is measured here) at random sources, one at a time, each keeping only
its HKS entry :math:`K_t(s, s)` with its proved bound, its region and its B-norm bound; a column
whose region would pass a quarter of the vertices is counted as declined. After 10, 100
and 1000 columns: the mean seconds per column, the resident memory now and its peak over the
columns so far (the kernel's peak counter is reset after the build, so the build's own peak does
not hide it), the largest region, the largest HKS bound relative to the entry, and the largest
B-norm bound relative to the target tol ||B^-1 e_s||_B (at most 1: every column met tol).

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/huge_local.py --subdivide 2 3 4
"""
from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import spectral_igl as sig  # noqa: E402
from spectral_igl.approx.region import region_heat_column  # noqa: E402
from spectral_igl.data_generators import midpoint_subdivide  # noqa: E402
from _results import Table  # noqa: E402

GB = 2.0 ** 30


def resident() -> tuple[float, float]:
    """(resident memory now, its peak since the last :func:`reset_peak`), in GB."""
    fields = dict(line.split(":", 1) for line in Path("/proc/self/status").read_text().splitlines()
                  if ":" in line)
    kb = lambda key: float(fields[key].split()[0]) * 1024.0 / GB  # noqa: E731
    return kb("VmRSS"), kb("VmHWM")


def reset_peak() -> None:
    """Reset the kernel's peak resident counter (VmHWM) of this process (Linux)."""
    Path("/proc/self/clear_refs").write_text("5")


def mesh(path, k, cache):
    """(V, F) of ``path`` midpoint-subdivided ``k`` times, from ``cache`` when it was made before."""
    import igl

    stem = Path(cache) / f"{Path(path).stem}_x{4 ** k}"
    if Path(f"{stem}_V.npy").exists():
        return np.load(f"{stem}_V.npy"), np.load(f"{stem}_F.npy")
    V, F = igl.read_triangle_mesh(str(path))[:2]
    for _ in range(k):                     # one level at a time: the previous level is freed
        V, F = midpoint_subdivide(V, F, 1)
    F = F.astype(np.int32)
    Path(cache).mkdir(parents=True, exist_ok=True)
    np.save(f"{stem}_V.npy", V)
    np.save(f"{stem}_F.npy", F)
    return V, F


def unit_area(V, F, chunk=1 << 20):
    """V scaled to unit area (the area summed by chunks of faces, in bounded memory)."""
    area = 0.0
    for a in range(0, len(F), chunk):
        f = F[a:a + chunk]
        area += 0.5 * float(np.sum(np.linalg.norm(np.cross(V[f[:, 1]] - V[f[:, 0]], V[f[:, 2]] - V[f[:, 0]]),
                                                  axis=1)))
    V /= np.sqrt(area)
    return V


def columns(lap, t, sources, checkpoints, table, label):
    """Local columns at ``sources`` one at a time; a row of ``table`` at each checkpoint."""
    reset_peak()
    spent, regions, hks_rel, bnorm_rel, declined = 0.0, [0], [0.0], [0.0], 0
    for c, s in enumerate(sources, start=1):
        t0 = time.perf_counter()
        k, info = region_heat_column(lap, t, int(s), 1e-8, budget=np.inf)
        spent += time.perf_counter() - t0
        if k is None:
            declined += 1
        else:
            regions.append(info["region"])
            hks_rel.append(float(info["abs_error"][s]) / float(k[s]))
            bnorm_rel.append(float(info["bnorm_error"]) * np.sqrt(lap.mass[s]) / 1e-8)
        del k, info
        if c in checkpoints:
            now, peak = resident()
            table.add(label, f"{t:g}", c, declined, f"{spent / c:.3f}", f"{now:.2f}", f"{peak:.2f}",
                      f"{max(regions):,}", f"{max(hks_rel):.1e}", f"{max(bnorm_rel):.2f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default=str(Path(__file__).resolve().parents[2] / "shared/data/meshes/armadillo.obj"))
    ap.add_argument("--subdivide", type=int, nargs="+", default=[2])
    ap.add_argument("--times", type=float, nargs="+", default=[1e-5, 1e-4])
    ap.add_argument("--columns", type=int, nargs="+", default=[10, 100, 1000])
    ap.add_argument("--cache", default="/tmp/spectral_igl_huge", help="folder of the subdivided meshes")
    ap.add_argument("--json-dir", help="also write the table as huge_local.json in this folder (docs/results)")
    args = ap.parse_args(argv)
    print(f"# {Path(args.mesh).name} midpoint-subdivided, unit area, tol = 1e-8; seconds per column "
          "(cold region, the Laplacian built once); memory: resident GB now / peak over the columns; "
          "build: seconds / peak GB of the whole run so far")
    table = Table("huge_local", ["shape (build s, peak GB)", "t", "columns", "declined", "s per column",
                                 "resident GB", "peak GB (columns)", "largest region",
                                 "max HKS bound / HKS", "max B-norm bound / target"], args.json_dir)
    for k in args.subdivide:
        V, F = mesh(args.mesh, k, args.cache)
        V = unit_area(V, F)
        t0 = time.perf_counter()
        lap = sig.laplacian(V, F)
        build = time.perf_counter() - t0
        del V, F
        build_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0 / GB
        label = f"{Path(args.mesh).stem} x{4 ** k}: {lap.n:,} ({build:.0f} s, {build_peak:.1f} GB)"
        sources = np.random.default_rng(0).choice(lap.n, max(args.columns), replace=False)
        for t in args.times:
            columns(lap, t, sources, set(args.columns), table, label)
        del lap
    table.close()


if __name__ == "__main__":
    main()
