"""A researcher's own mesh at its own scale: time units, descriptor grids, one way in."""
import numpy as np
import pytest

import spectral_igl as sig
from data_generators import box_tets, icosphere, torus
from spectral_igl.collection import Job
from spectral_igl.linalg import eigenvalue_bracket

SCALES = (1e-3, 1.0, 1e3)


@pytest.fixture(scope="module")
def sphere():
    return icosphere(3)


# ---- time units ----------------------------------------------------------------------------
def test_time_units_are_the_shape_measure_and_the_edge_length(sphere):
    V, F = sphere
    for s in SCALES:
        lap = sig.laplacian(s * V, F)
        assert sig.time_scale(lap, "shape") == pytest.approx(lap.B.sum(), rel=1e-14)
        assert sig.time_scale(lap, "area") == sig.time_scale(lap, "shape")
        E = np.unique(np.sort(np.vstack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
        h = np.linalg.norm(s * V[E[:, 0]] - s * V[E[:, 1]], axis=1).mean()
        assert sig.time_scale(lap, "h2") == pytest.approx(h * h, rel=1e-12)
        assert sig.time_scale(lap, "absolute") == 1.0
    with pytest.raises(ValueError, match="time_unit='volume' is for solids"):
        sig.time_scale(sig.laplacian(V, F), "volume")
    with pytest.raises(ValueError, match="time_unit must be one of"):
        sig.time_scale(sig.laplacian(V, F), "meters")


def test_time_units_on_a_solid():
    V = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 0, 2], [2, 2, 2]], float)
    T = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
    lap = sig.laplacian(V, T)
    vol = lap.B.sum()
    assert sig.time_scale(lap, "volume") == pytest.approx(vol ** (2 / 3), rel=1e-14)
    assert sig.time_scale(lap, "shape") == sig.time_scale(lap, "volume")
    with pytest.raises(ValueError, match="'area' is for surfaces"):
        sig.time_scale(lap, "area")
    g = sig.graph_laplacian(3, np.array([[0, 1], [1, 2]]))
    with pytest.raises(ValueError, match="without one"):
        sig.shape_time(g, 1e-3, "shape")


def test_heat_kernel_in_shape_units_is_the_same_on_every_scale(sphere):
    """K_t on the shape scaled by s equals s^-2 K_{t/s^2}: with t in the shape's units the
    scaled kernels (and their bounds) agree entry by entry."""
    V, F = sphere
    ref = None
    for s in SCALES:
        k, info = sig.heat_kernel((s * V, F), 1e-3, 7, time_unit="shape", return_info=True)
        area = float(sig.laplacian(s * V, F).B.sum())
        assert info["time"] == pytest.approx(1e-3 * area, rel=1e-14)
        if ref is None:
            ref, ref_err = k * area, info["abs_error"] * area
            continue
        assert np.max(np.abs(k * area - ref)) <= 1e-9 * ref.max()
        assert np.allclose(info["abs_error"] * area, ref_err, rtol=1e-6)
    # absolute time keeps its meaning: 1e-3 absolute on the unit-area copy is 1e-3 x shape
    W = V / np.sqrt(sig.laplacian(V, F).area())
    assert np.allclose(sig.heat_kernel((W, F), 1e-3, 7), sig.heat_kernel((W, F), 1e-3, 7, time_unit="shape"),
                       rtol=1e-12, atol=0)


def test_every_timed_function_takes_the_unit(sphere):
    V, F = sphere
    lap, big = sig.laplacian(V, F), sig.laplacian(100 * V, F)
    for fn in (sig.diffusion_distance, sig.mexican_hat_distance):
        d, D = fn(lap, 1e-2, 3, time_unit="shape"), fn(big, 1e-2, 3, time_unit="shape")
        assert np.allclose(d, 100 * D, rtol=1e-7, atol=1e-9 * d.max())   # B-normalised: x_l scales as 1/s
    P, Q = (sig.pairwise_diffusion_distance(x, 1e-2, [0, 5, 9], time_unit="shape") for x in (lap, big))
    assert np.allclose(P, 100 * Q, rtol=1e-7)
    K, info = sig.heat_kernels(lap, [1e-3, 1e-2], [0, 1], time_unit="h2", return_info=True)
    assert np.allclose(info["times"], np.array([1e-3, 1e-2]) * sig.time_scale(lap, "h2"), rtol=1e-14)
    g = sig.geodesic_distance(lap, 0, t=1.0, time_unit="h2")
    assert np.array_equal(g, sig.geodesic_distance(lap, 0))          # t = h^2 is its default
    with pytest.raises(ValueError, match="time_unit='shape' applies to t"):
        sig.geodesic_distance(lap, 0, time_unit="shape")


# ---- descriptor grids ----------------------------------------------------------------------
@pytest.mark.parametrize("case", ["sphere", "two_components", "torus", "tets"])
def test_eigenvalue_bracket_holds_the_dense_eigenvalue(case):
    if case == "sphere":
        lap = sig.laplacian(*icosphere(3))
    elif case == "two_components":
        V, F = icosphere(2)
        lap = sig.laplacian(np.vstack([V, 3 * V + 10]), np.vstack([F, F + len(V)]))
    elif case == "torus":
        lap = sig.laplacian(*torus(30, 12))
    else:
        lap = sig.laplacian(*box_tets((6, 5, 4)))
    ev = sig.dense_eigs(lap)[0]
    for k in (1, lap.n_components + 1, 7, 50, 120, lap.n - 1, lap.n):
        lo, hi, kind = eigenvalue_bracket(lap, k)
        assert lo <= ev[k - 1] * (1 + 1e-12) and ev[k - 1] <= hi * (1 + 1e-12), (k, lo, ev[k - 1], hi)
        if lap.n_components < k < lap.n:
            assert hi <= 1.05 * lo and kind == "proof"


def _pyfm_hks_times(ev, n):          # pyFM's auto_HKS on the first k eigenvalues
    return np.geomspace(4 * np.log(10) / ev[-1], 4 * np.log(10) / ev[1], n)


def _pyfm_wks(ev, n):                # pyFM's auto_WKS
    e_min, e_max = np.log(ev[1]), np.log(ev[-1])
    sigma = 7 * (e_max - e_min) / n
    return np.linspace(e_min + 2 * sigma, e_max - 2 * sigma, n), sigma


def test_descriptor_grids_match_the_eigenvalue_recipes(sphere):
    """HKS times and WKS energies from two certified ends of the spectrum equal the recipes of
    Sun et al. / Aubry et al. (as pyFM implements them) on the dense first k eigenvalues, to the
    bracket's width (5%: 2.5% in time, log 1.025 in energy)."""
    lap = sig.laplacian(*sphere)
    ev = sig.dense_eigs(lap, k=200)[0]
    t = sig.hks_times(lap, n=100, k=200)
    assert np.allclose(t, _pyfm_hks_times(ev, 100), rtol=0.026)
    assert t[-1] == pytest.approx(4 * np.log(10) / ev[1], rel=1.1e-3)
    E, sigma = sig.wks_energies(lap, n=100, k=200)
    E0, s0 = _pyfm_wks(ev, 100)
    assert np.max(np.abs(E - E0)) < np.log(1.026) and sigma == pytest.approx(s0, rel=0.02)
    W, info = sig.wks(lap, return_info=True)          # default: the grid of the first 1 + 100
    assert W.shape == (lap.n, 100) and np.array_equal(info["energies"], sig.wks_energies(lap, 100, 101)[0])


def test_hks_default_grid_and_normalisation_do_not_depend_on_scale(sphere):
    V, F = sphere
    out = []
    for s in (1e-3, 1e3):
        H, info = sig.hks((s * V, F), normalize=True, return_info=True)
        out.append((H, info["times"] / s ** 2, info["abs_error"]))
    (H0, t0, e0), (H1, t1, e1) = out
    assert H0.shape == (len(V), 100) and np.allclose(t0, t1, rtol=1e-9)
    assert np.max(np.abs(H0 - H1)) <= 1e-7 * H0.max()
    assert np.all(np.abs(H0 - H1) <= e0 + e1)
    # normalised HKS tends to 1 at large time on every component, an isolated vertex included
    W = np.vstack([V, 5 * V + 9, [[40.0, 0, 0]]])
    G = np.vstack([F, F + len(V)])
    assert np.allclose(sig.hks((W, G), [1e4], normalize=True), 1.0, rtol=1e-8)


def test_batch_hks_of_a_shape_and_its_scaled_copy_agree(sphere):
    V, F = sphere
    job = Job.hks(normalize=True, count=6)
    (a, ba), (b, bb) = job("a", sig.laplacian(V, F)), job("b", sig.laplacian(1e5 * V, F))
    assert np.max(np.abs(a["hks"] - b["hks"])) <= 1e-7 * a["hks"].max()
    assert np.allclose(b["times"], 1e10 * a["times"], rtol=1e-9)
    assert ba["time_unit"] == "absolute" and bb["normalized_by"] == "component measure"
    rel = Job.hks([1e-3, 1e-2], time_unit="shape")
    (a, ba), (b, bb) = rel("a", sig.laplacian(V, F)), rel("b", sig.laplacian(1e5 * V, F))
    assert np.allclose(b["hks"] * 1e10, a["hks"], rtol=1e-7)
    assert bb["time_scale"] == pytest.approx(1e10 * ba["time_scale"]) and bb["time_unit"] == "shape"
    assert Job.hks([1e-3]).key() != Job.hks([1e-3], time_unit="shape").key()
    assert Job.hks([1e-3]).key() == Job("hks", {"times": [1e-3], "method": "auto", "tol": 1e-8}).key()


def test_cli_relative_time_gives_the_same_picture_values_at_any_scale(tmp_path, sphere):
    from spectral_igl.cli import main
    from spectral_igl.io import write_mesh

    V, F = sphere
    vals = []
    for s in (1.0, 1e5):
        write_mesh(tmp_path / f"m{s:g}.obj", s * V, F)
        out = tmp_path / f"k{s:g}.npy"
        assert main(["kernel", str(tmp_path / f"m{s:g}.obj"), "-t", "1e-3", "--time-unit", "shape",
                     "-s", "4", "--out", str(out), "-q"]) == 0
        vals.append(np.load(out) * s * s)
        h = tmp_path / f"h{s:g}.npy"
        assert main(["hks", str(tmp_path / f"m{s:g}.obj"), "--out", str(h), "-q"]) == 0
        vals.append(np.load(h))
    assert np.allclose(vals[0], vals[2], rtol=1e-6, atol=1e-9 * vals[0].max())
    assert np.allclose(vals[1], vals[3], rtol=1e-6)
    assert main(["kernel", "--shape", "sphere", "--time-unit", "h2", "-q"]) == 2


# ---- one way in ----------------------------------------------------------------------------
class _Tri:                           # anything with .vertices and .faces, like trimesh.Trimesh
    def __init__(self, V, F):
        self.vertices, self.faces = V, F

    def __repr__(self):
        return "<a mesh\nwhose repr\nspans lines>"


def test_one_call_functions_take_what_a_user_has():
    V, F = icosphere(2)
    lap = sig.laplacian(V, F)
    inputs = [(V, F), [V, F], _Tri(V, F)]
    try:
        import pyvista as pv

        inputs.append(pv.PolyData(V, np.hstack([np.full((len(F), 1), 3), F]).ravel()))
    except ImportError:
        pass
    calls = {
        "heat_kernel": lambda x: sig.heat_kernel(x, 1e-2, 0),
        "hks": lambda x: sig.hks(x, [1e-2, 1e-1]),
        "diffusion_distance": lambda x: sig.diffusion_distance(x, 1e-2, 0),
        "biharmonic_distance": lambda x: sig.biharmonic_distance(x, 0),
        "kernel_diagonal": lambda x: sig.kernel_diagonal(x, sig.filters.heat(1e-2)),
        "lambda_max": lambda x: np.array(sig.lambda_max(x)),
        "geodesic_distance": lambda x: sig.geodesic_distance(x, 0),
        "harmonic": lambda x: sig.harmonic(x, [0, 5], [0.0, 1.0]),
    }
    for name, fn in calls.items():
        ref = fn(lap)
        for x in inputs:
            assert np.allclose(fn(x), ref, rtol=1e-12, atol=0), (name, type(x))


def test_libigl_order_and_messages_without_foreign_reprs():
    V, F = icosphere(2)
    assert np.array_equal(sig.geodesic_distance(V, F, 3), sig.geodesic_distance((V, F), 3))
    with pytest.raises(TypeError, match=r"geodesic_distance\(V, F, source\)"):
        sig.geodesic_distance(V, F)
    with pytest.raises(TypeError, match=r"pass \(V, F\) as one tuple"):
        sig.heat_kernel(V, 1e-2, 0)
    with pytest.raises(TypeError) as err:
        sig.hks(object.__new__(type("Weird", (), {"__repr__": lambda self: "a\nb\nc"})), [1e-2])
    assert "\n" not in str(err.value) and "Weird" in str(err.value)


@pytest.mark.parametrize("ext", [".ply", ".off", ".obj"])
def test_written_meshes_keep_every_digit(tmp_path, ext, sphere):
    """A scaled copy written and read back is the same shape: libigl's ASCII PLY kept 6 digits,
    so a shape at 1e5 came back moved by 1e-6 of its size and its kernels by 1e-5."""
    from spectral_igl.io import read_mesh, write_mesh

    V, F = sphere
    V = np.pi * 1e5 * V
    write_mesh(tmp_path / f"m{ext}", V, F)
    W, G = read_mesh(tmp_path / f"m{ext}")
    assert np.array_equal(G, F)
    if ext == ".ply":                  # binary: every bit
        assert np.array_equal(W, V)
    else:                              # libigl's text formats: 15 significant digits
        assert np.max(np.abs(W - V)) <= 1e-14 * np.abs(V).max()
