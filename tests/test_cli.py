"""The ``spectral-igl`` command line: jobs, outputs, messages and exit codes."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from _needs import IO, VIZ

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


def test_progress_bar_on_stderr_by_default_and_off_when_asked(tmp_path, capfd):
    """The command line draws tqdm bars on stderr unless --no-progress or --quiet."""
    out = tmp_path / "h.npy"
    args = ["hks", "--shape", "sphere", "--level", "2", "--times", "0.01", "0.1", "--out", str(out)]
    assert main(args) == EXIT_OK
    err = capfd.readouterr().err
    assert "hks: 100%" in err and "2/2" in err
    assert main(args + ["--no-progress"]) == EXIT_OK
    assert capfd.readouterr().err == ""
    assert main(args + ["-q"]) == EXIT_OK
    captured = capfd.readouterr()
    assert captured.err == "" and captured.out == ""


# ---- jobs ------------------------------------------------------------
def _dense_distance(lap, i, phi2):
    import spectral_igl as sig

    evals, X = sig.dense_eigs(lap)
    return np.sqrt(np.maximum(((X - X[i]) ** 2) @ phi2(evals), 0))


@VIZ
def test_distance_writes_npy_csv_png(tmp_path, capsys):
    from test_viz import assert_not_blank

    import spectral_igl as sig
    from data_generators import icosphere

    npy, csv, png = tmp_path / "d.npy", tmp_path / "d.csv", tmp_path / "sub" / "d.png"
    # an output directory is never created: a missing one is refused before any work
    code = main(["distance", "--shape", "sphere", "--level", "2", "--out", str(png)])
    assert code == EXIT_USAGE and "does not exist" in capsys.readouterr().err
    assert not png.parent.exists()
    png.parent.mkdir()
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


@VIZ
def test_view_screenshot(tmp_path):
    from test_viz import assert_not_blank

    png = tmp_path / "view.png"
    assert main(["view", "--shape", "sphere", "--level", "2", "--source", "4",
                 "--screenshot", str(png), "-q"]) == EXIT_OK
    assert_not_blank(png)


pytestmark = pytest.mark.usefixtures("one_blas_thread")


def _dense(lap):
    import spectral_igl as sig

    return sig.dense_eigs(lap)


def test_generated_shapes_torus_cylinder(tmp_path):
    import data_generators as dg
    import spectral_igl as sig

    for shape, (V, F) in (("torus", dg.torus(1.0, 0.4, n_major=24, n_minor=6)),
                          ("cylinder", dg.cylinder(1.0, 2.0, n_theta=24, n_z=6))):
        out = tmp_path / f"{shape}.npy"
        assert main(["distance", "--shape", shape, "--level", "2", "--source", "3",
                     "--out", str(out), "-q"]) == EXIT_OK
        d = np.load(out)
        lap = sig.laplacian(V, F)  # --level 2 is this resolution
        phi2 = lambda s: np.where(s > 1e-9, 1.0 / np.maximum(s, 1e-9) ** 2, 0.0)  # noqa: E731
        truth = _dense_distance(lap, 3, phi2)
        assert d.shape == (lap.n,) and d[3] == 0.0
        assert np.max(np.abs(d - truth)) < 1e-6 * truth.max(), shape


@VIZ
def test_hks_against_dense(tmp_path, capsys):
    import spectral_igl as sig
    from data_generators import icosphere

    out, png = tmp_path / "h.npy", tmp_path / "h.png"
    assert main(["hks", "--shape", "sphere", "--level", "2", "--times", "0.01", "0.1", "--no-normalize",
                 "--out", str(out), "--out", str(png)]) == EXIT_OK
    H = np.load(out)
    evals, X = _dense(sig.laplacian(*icosphere(2)))
    truth = (X ** 2) @ np.exp(-np.outer(evals, [0.01, 0.1]))
    assert H.shape == truth.shape == (162, 2)
    assert np.max(np.abs(H - truth)) < 1e-7 * truth.max()
    from test_viz import assert_not_blank

    assert_not_blank(png)
    assert "hks at 2 times" in capsys.readouterr().out


@VIZ
def test_smooth_signal_and_shape(tmp_path, capsys):
    import spectral_igl as sig
    from data_generators import icosphere
    from spectral_igl.io import read_mesh

    V, F = icosphere(2)
    rng = np.random.default_rng(0)
    f = V[:, 2] + 0.1 * rng.standard_normal(len(V))
    sig_path, out = tmp_path / "f.csv", tmp_path / "g.npy"
    np.savetxt(sig_path, f, delimiter=",")
    assert main(["smooth", "--shape", "sphere", "--level", "2", "--signal", str(sig_path),
                 "-t", "0.05", "--out", str(out), "-q"]) == EXIT_OK
    lap = sig.laplacian(V, F)
    evals, X = _dense(lap)
    truth = X @ (np.exp(-0.05 * evals) * (X.T @ (lap.B @ f)))
    assert np.max(np.abs(np.load(out) - truth)) < 1e-7
    # a mesh output needs the shape itself as the signal
    assert main(["smooth", "--shape", "sphere", "--signal", str(sig_path), "--out",
                 str(tmp_path / "s.obj")]) == EXIT_USAGE
    assert "mesh can only be written" in capsys.readouterr().err
    # the noisy shape, smoothed at the default time (optimal_shape_time): rounder
    obj, png = tmp_path / "smooth.obj", tmp_path / "smooth.png"
    assert main(["smooth", "--shape", "sphere", "--level", "3", "--noise", "0.01",
                 "--out", str(obj), "--out", str(png)]) == EXIT_OK
    printed = capsys.readouterr().out
    assert "diffusion smoothing on sphere (642 vertices) at t=" in printed
    W, G = read_mesh(obj)
    V3, F3 = icosphere(3)
    noisy = V3 + 0.01 * 2.0 * np.random.default_rng(0).standard_normal(V3.shape)
    assert np.array_equal(G, F3)
    spread = lambda P: float(np.std(np.linalg.norm(P - P.mean(0), axis=1)))  # noqa: E731
    assert spread(W) < 0.6 * spread(noisy)  # rounder than the noisy input
    # closer to the clean sphere than the noisy input, and than the former default t = h^2
    lapn = sig.laplacian(noisy, F3)
    h = float(np.mean(np.linalg.norm(noisy[F3[:, 0]] - noisy[F3[:, 1]], axis=1)))
    err = lambda P: float(np.sqrt(np.sum((P - V3) * (lapn.B @ (P - V3)))))  # noqa: E731
    assert err(W) < err(noisy) and err(W) < err(np.asarray(sig.diffusion_smooth(lapn, noisy, h * h)))


@VIZ
def test_geodesic_on_the_sphere(tmp_path, capsys):
    from data_generators import icosphere

    out, png = tmp_path / "g.npy", tmp_path / "g.png"
    assert main(["geodesic", "--shape", "sphere", "--level", "3", "--source", "0",
                 "--out", str(out), "--out", str(png)]) == EXIT_OK
    V, _ = icosphere(3)
    arc = np.arccos(np.clip(V @ V[0], -1, 1))
    assert np.max(np.abs(np.load(out) - arc)) < 0.03 * np.pi  # heat method, 642 vertices
    from test_viz import assert_not_blank

    assert_not_blank(png)
    assert "geodesic distance (heat)" in capsys.readouterr().out


def test_computation_errors_exit_1(capsys):
    from spectral_igl.cli import EXIT_ERROR

    # backward Euler approximates the heat filter only: the engine refuses the wave filter
    assert main(["kernel", "--shape", "sphere", "--level", "1", "--filter", "wave", "-t", "0.1",
                 "--method", "euler"]) == EXIT_ERROR
    err = capsys.readouterr().err
    assert "failed" in err and "heat filter only" in err and "Traceback" not in err


@VIZ
def test_real_meshes(shared_meshes, tmp_path):
    """Triangle meshes with one and several components, and a tetrahedral mesh."""
    from test_viz import assert_not_blank

    from spectral_igl.io import read_mesh

    # several components: distances stay finite, zero at the source only
    out, png = tmp_path / "suzanne.npy", tmp_path / "suzanne.png"
    assert main(["distance", str(shared_meshes / "suzanne.obj"), "--source", "10",
                 "--out", str(out), "--out", str(png), "-q"]) == EXIT_OK
    d = np.load(out)
    assert d.shape == (len(read_mesh(shared_meshes / "suzanne.obj")[0]),)
    assert np.all(np.isfinite(d)) and d[10] == 0.0 and np.delete(d, 10).min() > 0
    assert_not_blank(png)
    # tetrahedral mesh: heat is conserved
    out = tmp_path / "bunny.npy"
    assert main(["kernel", str(shared_meshes / "bunny.mesh"), "--source", "0", "--out", str(out),
                 "-q"]) == EXIT_OK
    import spectral_igl as sig

    lap = sig.laplacian(*read_mesh(shared_meshes / "bunny.mesh"))
    assert np.load(out) @ (lap.B @ np.ones(lap.n)) == pytest.approx(1.0, abs=1e-7)


# ---- fields written with their mesh ------------------------------------------------------
@IO
@pytest.mark.parametrize("ext", [".vtu", ".vtk", ".ply"])
def test_distance_written_with_its_mesh(tmp_path, ext):
    """--out x.vtu/.vtk/.ply: the mesh and the distance as point data, equal to the .npy."""
    import meshio

    from data_generators import icosphere

    out, npy = tmp_path / f"d{ext}", tmp_path / "d.npy"
    assert main(["distance", "--shape", "sphere", "--level", "2", "--source", "3", "--filter",
                 "biharmonic", "--out", str(out), "--out", str(npy), "-q"]) == EXIT_OK
    m = meshio.read(out)
    V, F = icosphere(2)
    assert np.allclose(m.points, V) and np.array_equal(m.cells_dict["triangle"], F)
    d = m.point_data["biharmonic_distance"]
    assert d.shape == (len(V),) and np.array_equal(d, np.load(npy))
    assert d[3] == 0.0 and d.max() > 0


@IO
def test_hks_names_its_times(tmp_path):
    """HKS: the CSV header names the times; a .vtu holds one array per time; by default the
    values are multiplied by the area (dimensionless)."""
    import meshio

    import spectral_igl as sig
    from data_generators import icosphere

    csv, vtu = tmp_path / "h.csv", tmp_path / "h.vtu"
    assert main(["hks", "--shape", "sphere", "--level", "2", "--times", "0.001", "0.01", "0.1",
                 "--out", str(csv), "--out", str(vtu), "-q"]) == EXIT_OK
    header = csv.read_text().splitlines()[0]
    assert header == "t=0.001,t=0.01,t=0.1"
    H = np.loadtxt(csv, delimiter=",", skiprows=1)
    lap = sig.laplacian(*icosphere(2))
    evals, X = sig.dense_eigs(lap)
    m = meshio.read(vtu)
    for j, t in enumerate((0.001, 0.01, 0.1)):
        truth = (X ** 2) @ np.exp(-t * evals) * lap.area()
        assert np.max(np.abs(H[:, j] - truth) / truth) < 1e-6
        assert np.allclose(m.point_data[f"t={t:g}"], H[:, j], rtol=1e-9)


@IO
def test_smooth_signal_written_with_its_mesh(tmp_path, capsys):
    """A smoothed signal goes to .vtu with its mesh; .obj (no fields) is refused for it."""
    import meshio

    from data_generators import icosphere

    V, F = icosphere(2)
    f = V[:, 0] + 0.1 * np.random.default_rng(1).standard_normal(len(V))
    src, vtu, npy = tmp_path / "f.npy", tmp_path / "g.vtu", tmp_path / "g.npy"
    np.save(src, f)
    assert main(["smooth", "--shape", "sphere", "--level", "2", "--signal", str(src), "-t", "0.05",
                 "--out", str(vtu), "--out", str(npy), "-q"]) == EXIT_OK
    assert np.array_equal(meshio.read(vtu).point_data["smoothed"], np.load(npy))
    # the shape itself to .vtu: smoothed positions, displacement as a field
    shape = tmp_path / "s.vtu"
    assert main(["smooth", "--shape", "sphere", "--level", "2", "--out", str(shape), "-q"]) == EXIT_OK
    m = meshio.read(shape)
    disp = np.linalg.norm(m.points - V, axis=1)
    assert np.allclose(m.point_data["displacement"], disp) and disp.max() > 0
