"""The ``spectral-igl`` command line: jobs, outputs, messages and exit codes."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from spectral_igl.cli import EXIT_INPUT, EXIT_OK, EXIT_USAGE, main

ROOT = Path(__file__).resolve().parents[1]


def run_module(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    return subprocess.run([sys.executable, "-m", "spectral_igl.cli", *args], capture_output=True,
                          text=True, env=env, cwd=ROOT)


def test_help_lists_jobs_and_exit_codes():
    out = run_module("--help")
    assert out.returncode == 0
    for job in ("kernel", "distance", "hks", "smooth", "geodesic", "view", "figures"):
        assert job in out.stdout
    assert "exit codes" in out.stdout
    out = run_module("distance", "--help")
    assert out.returncode == 0 and "--source" in out.stdout and "biharmonic" in out.stdout


def test_version(capsys):
    from spectral_igl import __version__

    assert main(["--version"]) == EXIT_OK
    assert __version__ in capsys.readouterr().out


@pytest.mark.parametrize("argv, code, message", [
    ([], EXIT_USAGE, "JOB"),
    (["frobnicate"], EXIT_USAGE, "invalid choice"),
    (["distance"], EXIT_USAGE, "no input"),
    (["distance", "--shape", "sphere", "--source", "-3"], EXIT_USAGE, "vertex index"),
    (["distance", "--shape", "sphere", "--source", "100000"], EXIT_USAGE, "out of range"),
    (["distance", "--shape", "sphere", "-t", "-1"], EXIT_USAGE, "positive"),
    (["distance", "--shape", "sphere", "--filter", "gauss"], EXIT_USAGE, "invalid choice"),
    (["distance", "--shape", "sphere", "--out", "d.txt"], EXIT_USAGE, "output type"),
    (["kernel", "no/such/file.obj"], EXIT_INPUT, "no such mesh file"),
    (["kernel", "model.xyz"], EXIT_INPUT, "no such mesh file"),
])
def test_usage_errors(argv, code, message, capsys):
    assert main(argv) == code
    err = capsys.readouterr().err
    assert message in err
    assert "Traceback" not in err


def test_bad_files(tmp_path, capsys):
    bad = tmp_path / "bad.off"
    bad.write_text("this is not an OFF file\n")
    assert main(["distance", str(bad)]) == EXIT_INPUT
    assert "bad.off" in capsys.readouterr().err
    ext = tmp_path / "shape.xyz"
    ext.write_text("0 0 0\n")
    assert main(["distance", str(ext)]) == EXIT_INPUT
    assert "unsupported mesh format" in capsys.readouterr().err
    both = tmp_path / "s.obj"
    both.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    assert main(["distance", str(both), "--shape", "sphere"]) == EXIT_USAGE
    assert "not both" in capsys.readouterr().err
    # exit codes survive the process boundary
    out = run_module("kernel", str(bad))
    assert out.returncode == EXIT_INPUT and "error" in out.stderr


def test_figures_list():
    out = run_module("figures", "--list")
    assert out.returncode == 0
    names = out.stdout.split()
    assert "fig15_gibbs" in names and "fig09_distances" in names
    out = run_module("figures", "--only", "fig99")
    assert out.returncode == EXIT_USAGE and "unknown figure" in out.stderr


def test_progress_bar_renders():
    import io

    from spectral_igl.cli import Progress

    buf = io.StringIO()
    p = Progress(4, "work", enabled=True, stream=buf)
    for k in range(4):
        p.step(f"step {k}")
    text = buf.getvalue()
    assert "100%" in text and "#" * 28 in text and text.endswith("\n")


# ---- jobs ------------------------------------------------------------
def _dense_distance(lap, i, phi2):
    import spectral_igl as sig

    evals, X = sig.dense_eigs(lap)
    return np.sqrt(np.maximum(((X - X[i]) ** 2) @ phi2(evals), 0))


def test_distance_writes_npy_csv_png(tmp_path, capsys):
    import spectral_igl as sig
    from data_generators import icosphere

    from test_viz import assert_not_blank

    npy, csv, png = tmp_path / "d.npy", tmp_path / "d.csv", tmp_path / "sub" / "d.png"
    code = main(["distance", "--shape", "sphere", "--level", "2", "--source", "7", "--filter",
                 "biharmonic", "--out", str(npy), "--out", str(csv), "--out", str(png)])
    assert code == EXIT_OK, capsys.readouterr().err
    d = np.load(npy)
    lap = sig.laplacian(*icosphere(2))
    phi2 = lambda s: np.where(s > 1e-9, 1.0 / np.maximum(s, 1e-9) ** 2, 0.0)  # noqa: E731
    truth = _dense_distance(lap, 7, phi2)
    assert d.shape == (lap.n,)
    assert np.max(np.abs(d - truth)) < 1e-6 * truth.max()
    assert np.allclose(np.loadtxt(csv, delimiter=",", skiprows=1), d, rtol=1e-9, atol=1e-12)
    assert_not_blank(png)
    out = capsys.readouterr().out
    assert "error bound" in out and str(png) in out


def test_kernel_on_mesh_files(tmp_path):
    import spectral_igl as sig
    from data_generators import box_tets, icosphere

    from spectral_igl.io import write_mesh

    V, F = icosphere(2)
    for ext in (".obj", ".off", ".ply", ".stl"):
        path = tmp_path / f"s{ext}"
        write_mesh(path, V, F)
        out = tmp_path / f"k{ext}.npy"
        assert main(["kernel", str(path), "--source", "3", "-t", "0.1", "--out", str(out), "-q"]) == 0
        k = np.load(out)
        if ext != ".stl":  # stl does not keep the vertex order
            lap = sig.laplacian(V, F)
            evals, X = sig.dense_eigs(lap)
            assert np.allclose(k, X @ (np.exp(-0.1 * evals) * X[3]), atol=1e-6)
    Vt, T = box_tets((4, 3, 2))
    path = tmp_path / "box.mesh"
    write_mesh(path, Vt, T)
    out = tmp_path / "kt.npy"
    assert main(["kernel", str(path), "--source", "0", "-t", "0.01", "--out", str(out), "-q"]) == 0
    lap = sig.laplacian(Vt, T)
    assert np.load(out) @ (lap.B @ np.ones(lap.n)) == pytest.approx(1.0, abs=1e-7)  # heat conserved


def test_view_screenshot(tmp_path):
    from test_viz import assert_not_blank

    png = tmp_path / "view.png"
    assert main(["view", "--shape", "sphere", "--level", "2", "--source", "4",
                 "--screenshot", str(png), "-q"]) == EXIT_OK
    assert_not_blank(png)
