"""The default path's bounds: which method ``auto`` takes and whether its bound is a proof.

For every built-in filter and t = 1e-6 … 1e3 (unit area), one kernel column at the default
settings (``method="auto"``, ``tol=1e-8``) on each shape; prints, per filter, the share of calls
whose bound is a ``"proof"``, the methods ``auto`` chose, and every call whose bound misses
``tol * ||B^-1 e_i||_B``.

Usage::

    python benchmarks/default_bounds.py --meshes ../shared/data/meshes
    python benchmarks/default_bounds.py --quick          # two generated shapes only
"""
from __future__ import annotations

import argparse
import collections
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import spectral_igl as sig  # noqa: E402
from data_generators import icosphere  # noqa: E402
from spectral_igl import filters  # noqa: E402
from spectral_igl.approx.common import inv_bnorm_upper  # noqa: E402

TIMES = np.logspace(-6, 3, 10)
MESHES = ("armadillo.obj", "camel_b.obj", "beetle.obj", "fertility.off", "bunny.mesh")


def unit_area(lap_fn, *args):
    lap = lap_fn(*args)
    s = np.sqrt(lap.area())
    return lap_fn(args[0] / s, *args[1:])


def shapes(args):
    V, F = icosphere(4)
    yield "icosphere(4)", unit_area(sig.laplacian, V, F)
    if args.quick or not args.meshes:
        return
    from spectral_igl import io

    for name in MESHES:
        path = Path(args.meshes) / name
        if not path.exists():
            continue
        mesh = io.read_mesh(str(path))
        V, E = mesh[0], mesh[1]
        yield name, unit_area(sig.laplacian, V, E)


def cases():
    for t in TIMES:
        yield "heat", filters.heat(t)
        yield "mexican_hat", filters.mexican_hat(t)
        yield "wave", filters.wave(t)
    yield "commute_time", filters.commute_time()
    yield "biharmonic", filters.biharmonic()
    for k in (3, 4):
        yield f"polyharmonic{k}", filters.polyharmonic(k)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", default=None)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    print(f"# {platform.node()} {platform.processor() or platform.machine()}, {time.strftime('%Y-%m-%d')}, "
          f"python benchmarks/default_bounds.py {' '.join(sys.argv[1:])}")
    share = collections.defaultdict(lambda: [0, 0, collections.Counter()])
    misses = []
    for name, lap in shapes(args):
        i = int(np.argmax(lap.mass))
        e = np.zeros(lap.n)
        e[i] = 1.0
        norm = float(inv_bnorm_upper(lap, e))
        for fname, filt in cases():
            t0 = time.perf_counter()
            try:
                K, info = sig.spectral_kernel(lap, filt, i, return_info=True)
            except (ValueError, RuntimeError) as exc:
                misses.append((name, repr(filt), "refused", str(exc)[:80]))
                continue
            row = share[fname]
            row[0] += info["bound_kind"] == "proof"
            row[1] += 1
            row[2][info["method"]] += 1
            b = float(np.max(info["bnorm_error"]))
            if not b <= 1e-8 * norm:
                misses.append((name, repr(filt), info["method"], f"bound {b:.2e} > tol*norm {1e-8 * norm:.2e}"))
            print(f"{name:16s} {filt!r:40s} {info['method']:13s} {info['bound_kind']:9s} "
                  f"{b / norm:9.2e} {time.perf_counter() - t0:7.3f} s", flush=True)
    print("\n| filter | calls | proof | methods |\n|---|---|---|---|")
    for fname, (p, c, m) in share.items():
        print(f"| {fname} | {c} | {p / c:.0%} | {', '.join(f'{k} {v}' for k, v in m.items())} |")
    print(f"\ncalls over tol or refused: {len(misses)}")
    for row in misses:
        print("  ", *row)


if __name__ == "__main__":
    main()
