"""Every example script in quick mode: its images exist and are not blank, its key number holds.

The scripts are imported and their ``main(argv)`` called, so they cannot rot.
"""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pyvista")
pytest.importorskip("matplotlib")

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

# what each script needs from the package (skipped with the reason while a piece is missing)
NEEDS = {
    "fig02_harmonic": ["harmonic", "critical_points"],
    "fig03_eigenfunctions": ["critical_points"],
    "fig04_anisotropic_heat": ["anisotropic_laplacian", "heat_kernel"],
    "fig05_lcurve": ["diffusion_smooth", "optimal_time"],
    "fig06_conditioning": ["SpectralOperator"],
    "fig07_17_timing": ["heat_kernel", "diffusion_distance"],
    "fig08_volumetric_heat": ["heat_kernel"],
    "fig09_distances": ["spectral_distance", "filters"],
    "fig10_filters": ["filters"],
    "fig11_12_biharmonic_stability": ["biharmonic_distance"],
    "fig13_14_accuracy": ["diffusion_distance"],
    "fig15_gibbs": ["SpectralOperator", "filters"],
    "fig16_tradeoff": ["apply_filter", "filters"],
    "fig18_23_robustness": ["heat_kernel", "diffusion_distance", "point_cloud_laplacian"],
    "fig24_26_smoothing": ["diffusion_smooth", "critical_points"],
}


def scripts():
    return sorted(p.stem for p in EXAMPLES.glob("fig*.py"))


def load(name):
    if str(EXAMPLES) not in sys.path:
        sys.path.insert(0, str(EXAMPLES))
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def image_ok(path, min_std=8.0, min_colors=40):
    from PIL import Image

    img = np.asarray(Image.open(path).convert("RGB"))
    colours = len(np.unique(img.reshape(-1, 3), axis=0))
    return float(img.std()) > min_std and colours > min_colors, (float(img.std()), colours)


def run(name, tmp_path):
    import spectral_igl as sig

    missing = [n for n in NEEDS.get(name, []) if not hasattr(sig, n)]
    if missing:
        pytest.skip(f"{name} needs spectral_igl.{', spectral_igl.'.join(missing)}, not available yet")
    result = load(name).main(["--quick", "--out", str(tmp_path)])
    assert isinstance(result, dict) and result.get("images"), f"{name} returned no images"
    for path in result["images"]:
        assert Path(path).is_file(), path
        ok, stats = image_ok(path)
        assert ok, f"{path} looks blank (pixel std, colours) = {stats}"
        assert Path(path).stat().st_size < 400_000, f"{path} is too large"
    return result


def test_every_script_is_listed():
    assert set(scripts()) <= set(NEEDS), set(scripts()) - set(NEEDS)


def test_fig02_harmonic(tmp_path):
    r = run("fig02_harmonic", tmp_path)
    assert r["euler_characteristic"] == [2, 2, 2]
    assert r["extrema_only_at_constraints"]
    assert [m + M for m, M, s in r["critical_counts"]] == [2, 4, 6]


def test_fig03_eigenfunctions(tmp_path):
    r = run("fig03_eigenfunctions", tmp_path)
    assert all(e == 2 for e in r["euler_characteristic"])
    # higher eigenfunctions oscillate more: more critical points
    totals = [sum(c) for c in r["critical_counts"]]
    assert totals[-1] > totals[0]


def test_fig04_anisotropic_heat(tmp_path):
    r = run("fig04_anisotropic_heat", tmp_path)
    assert r["elongation_anisotropic"] > 1.5 * r["elongation_isotropic"]


def test_fig05_lcurve(tmp_path):
    r = run("fig05_lcurve", tmp_path)
    assert r["error_smoothed"] < 0.5 * r["error_noisy"]


def test_fig06_conditioning(tmp_path):
    r = run("fig06_conditioning", tmp_path)
    assert r["bound_holds"]
    assert np.isfinite(r["max_condition"])


def test_fig07_17_timing(tmp_path):
    r = run("fig07_17_timing", tmp_path)
    assert r["speedup_at_largest_n"] > 1.0


def test_fig08_volumetric_heat(tmp_path):
    r = run("fig08_volumetric_heat", tmp_path)
    assert r["conservation_error"] < 1e-6
    assert r["symmetry_error"] < 1e-6


def test_fig09_distances(tmp_path):
    r = run("fig09_distances", tmp_path)
    assert r["min_elsewhere"] > 0
    assert r["relative_error_vs_dense"] < 1e-6


def test_fig10_filters(tmp_path):
    r = run("fig10_filters", tmp_path)
    assert r["heat_filter_error"] < 1e-14 and r["biharmonic_filter_error"] < 1e-12
    assert r["lambda_2"] == pytest.approx(2.0, rel=0.02)  # unit sphere: l(l+1) at l = 1


def test_fig11_12_biharmonic_stability(tmp_path):
    r = run("fig11_12_biharmonic_stability", tmp_path)
    errs = r["sphere_relative_error"]
    assert errs[-1] < errs[0] and errs[-1] < 0.05


def test_fig13_14_accuracy(tmp_path):
    r = run("fig13_14_accuracy", tmp_path)
    assert r["spectrum_free_max_error"] < 1e-6


def test_fig15_gibbs(tmp_path):
    r = run("fig15_gibbs", tmp_path)
    assert r["truncated_min"] < 0
    assert r["spectrum_free_min_plus_bound"] >= 0


def test_fig16_tradeoff(tmp_path):
    r = run("fig16_tradeoff", tmp_path)
    assert r["best_spectrum_free_error"] < r["best_truncated_error"]


def test_fig18_23_robustness(tmp_path):
    r = run("fig18_23_robustness", tmp_path)
    assert r["sampling_difference"] < 0.1
    assert r["noise_difference"] < 0.2


def test_fig24_26_smoothing(tmp_path):
    r = run("fig24_26_smoothing", tmp_path)
    assert r["critical_after"] < 0.5 * r["critical_before"]
    assert r["error_smoothed"] < r["error_noisy"]
