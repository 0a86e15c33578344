"""The core works without any extra; a missing extra ends in one line naming its install."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import spectral_igl as sig
from data_generators import icosphere
from spectral_igl._extras import EXTRAS, install_hint, require

ROOT = Path(__file__).resolve().parents[1]
OPTIONAL = sorted({m for mods in EXTRAS.values() for m in mods} | {"vtk", "vtkmodules", "numcodecs"})


def _hides(monkeypatch, *modules):
    """Make ``import m`` raise ImportError for each of ``modules`` (and their submodules)."""
    for name in list(sys.modules):
        if name.split(".")[0] in modules:
            monkeypatch.delitem(sys.modules, name)
    for name in modules:
        monkeypatch.setitem(sys.modules, name, None)


def _one_line(err, extra):
    msg = str(err.value)
    assert "\n" not in msg and msg.endswith(f'pip install "spectral-igl[{extra}]"'), msg
    return msg


def test_require_names_the_extra_and_rejects_an_unknown_one(monkeypatch):
    _hides(monkeypatch, "meshio")
    with pytest.raises(ImportError) as err:
        require("meshio", "io", "reading a .vtu file")
    assert _one_line(err, "io") == 'reading a .vtu file needs meshio: pip install "spectral-igl[io]"'
    with pytest.raises(ValueError, match="extra must be one of"):
        install_hint("plots")
    assert install_hint("all") == 'pip install "spectral-igl[all]"'


def test_every_extra_is_declared_in_pyproject():
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    for extra in (*EXTRAS, "all"):
        assert f"\n{extra} = [" in text, extra


def test_the_core_imports_every_module_and_computes_a_heat_kernel_without_any_extra():
    # a fresh interpreter in which every optional package is unimportable
    code = f"""
import importlib, pkgutil, sys
sys.modules.update(dict.fromkeys({OPTIONAL!r}))
import numpy as np
import spectral_igl as sig
from spectral_igl.data_generators import icosphere
for info in pkgutil.walk_packages(sig.__path__, prefix="spectral_igl."):
    if not info.name.endswith(("_ldlt", "_assembly")):
        importlib.import_module(info.name)
lap = sig.laplacian(*icosphere(2))
k, info = sig.heat_kernel(lap, 0.05, 7, return_info=True)
d = sig.biharmonic_distance(lap, 0)
h = sig.hks(lap, [0.01, 0.1])
assert info["bound_kind"] == "proof" and np.isfinite(d).all() and h.shape == (lap.n, 2)
print("ok")
"""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                          cwd=ROOT, env={"PATH": "/usr/bin:/bin", "PYTHONPATH": str(ROOT),
                                         "OPENBLAS_NUM_THREADS": "1"})
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr[-3000:]


def test_file_formats_beyond_libigl_name_the_io_extra(monkeypatch, tmp_path):
    from spectral_igl.io import write_mesh

    _hides(monkeypatch, "meshio")
    V, F = icosphere(1)
    with pytest.raises(ImportError) as err:
        write_mesh(tmp_path / "s.vtu", V, F)
    _one_line(err, "io")
    write_mesh(tmp_path / "s.obj", V, F)                 # libigl's formats need no extra
    assert (tmp_path / "s.obj").stat().st_size > 0


def test_tetrahedralize_names_the_tet_extra(monkeypatch):
    _hides(monkeypatch, "pytetwild")
    with pytest.raises(ImportError) as err:
        sig.tetrahedralize(*icosphere(1))
    assert _one_line(err, "tet").startswith("tetrahedralize needs pytetwild")


def test_pictures_name_the_viz_extra(monkeypatch):
    from spectral_igl import viz

    _hides(monkeypatch, "pyvista", "matplotlib")
    V, F = icosphere(1)
    with pytest.raises(ImportError) as err:
        viz.plot_levelsets((V, F), V[:, 2], off_screen=True)
    _one_line(err, "viz")


def test_pypardiso_backend_names_the_fast_extra(monkeypatch):
    from spectral_igl.linalg import factorize

    _hides(monkeypatch, "pypardiso")
    lap = sig.laplacian(*icosphere(1))
    with pytest.raises(ImportError) as err:
        factorize((lap.L + lap.B).tocsc(), backend="pypardiso")
    _one_line(err, "fast")


def test_collections_name_the_cluster_extra(monkeypatch, tmp_path):
    from spectral_igl.collection import Job, run

    _hides(monkeypatch, "zarr", "distributed", "dask")
    with pytest.raises(ImportError) as err:
        run({"s": icosphere(1)}, Job.hks([0.1]), str(tmp_path / "out.zarr"), workers=1, progress=False)
    _one_line(err, "cluster")
    assert np.isfinite(sig.hks(sig.laplacian(*icosphere(1)), [0.1])).all()
