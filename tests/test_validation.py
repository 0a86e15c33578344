"""Malformed input to every public constructor ends in ValueError/TypeError, never a crash."""
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import spectral_igl as sig
from data_generators import icosphere

V0, F0 = icosphere(1)
T0 = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
VT0 = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]])

BAD_V = [None, "V", [[0.0, 1.0]], np.zeros((0, 3)), np.zeros((5,)), np.zeros((5, 4)),
         np.full((42, 3), np.nan), np.array([[1 + 1j, 0, 0]] * 42), np.array([["a", "b", "c"]] * 42),
         np.array([[0, 0, 0], [1, 1]], dtype=object), np.where(np.arange(42)[:, None] == 3, np.inf, V0)]
BAD_F = [None, F0 + 100, F0 - 50, F0.astype(float) + 0.5, F0[:, :2], np.zeros((0, 3), int),
         F0.astype(object), F0.ravel(), [[0, 1]], "F", np.full((3, 3), np.nan)]


def constructors():
    return {
        "laplacian": lambda V, F: sig.laplacian(V, F),
        "laplacian_tet": lambda V, F: sig.laplacian(VT0 if V is V0 else V, T0 if F is F0 else F),
        "anisotropic": lambda V, F: sig.anisotropic_laplacian(V, F, 1.0),
        "points_delaunay": lambda V, F: sig.point_cloud_laplacian(V, k=8),
        "points_belkin": lambda V, F: sig.point_cloud_laplacian(V, k=8, method="belkin"),
        "points_liu": lambda V, F: sig.point_cloud_laplacian(V, k=8, method="liu"),
        "tetrahedralize": lambda V, F: sig.tetrahedralize(V, F),
        "graph": lambda V, F: sig.graph_laplacian(42, F),
        "voxels": lambda V, F: sig.voxel_laplacian(V),
    }


@pytest.mark.parametrize("name", list(constructors()))
@pytest.mark.parametrize("i", range(len(BAD_V)))
def test_bad_vertices(name, i):
    fn = constructors()[name]
    if name == "graph":
        pytest.skip("no vertex array")
    with pytest.raises((ValueError, TypeError)) as info:
        fn(BAD_V[i], F0)
    assert len(str(info.value)) > 10


@pytest.mark.parametrize("name", ["laplacian", "laplacian_tet", "anisotropic", "tetrahedralize", "graph"])
@pytest.mark.parametrize("i", range(len(BAD_F)))
def test_bad_faces(name, i):
    fn = constructors()[name]
    if name == "graph" and BAD_F[i] is not None and np.shape(BAD_F[i])[-1:] == (2,):
        pytest.skip("(m, 2) pairs are valid edges")
    with pytest.raises((ValueError, TypeError)) as info:
        fn(V0, BAD_F[i])
    assert len(str(info.value)) > 10


def test_messages_name_what_was_received():
    with pytest.raises(ValueError, match=r"index 141 but there are only 42"):
        sig.laplacian(V0, F0 + 100)
    with pytest.raises(ValueError, match=r"negative index"):
        sig.anisotropic_laplacian(V0, F0 - 50)
    with pytest.raises(ValueError, match=r"shape \(n, 3\).*\(5, 4\)"):
        sig.point_cloud_laplacian(np.zeros((5, 4)))
    with pytest.raises(TypeError, match="method|k"):
        sig.point_cloud_laplacian(V0, k=2.5)
    with pytest.raises(ValueError, match="method"):
        sig.point_cloud_laplacian(V0, method="cotan")


def test_degenerate_but_valid_input_is_handled():
    # zero-area faces, duplicate points and unreferenced vertices: warnings, finite output
    V = np.vstack([V0, [[5.0, 5, 5]]])
    F = np.vstack([F0, [[0, 0, 1]], [[0, 1, 1]]])
    with pytest.warns(RuntimeWarning):
        lap = sig.anisotropic_laplacian(V, F, 2.0)
    assert lap.n == len(V) and lap.n_components == 2 and np.all(np.isfinite(lap.L.data))
    P = np.vstack([V0, V0[:5]])  # coincident points
    for m in ("delaunay", "belkin", "liu"):
        lap = sig.point_cloud_laplacian(P, k=8, method=m)
        assert np.all(np.isfinite(lap.L.data)) and np.all(lap.B.diagonal() > 0)
    with pytest.raises(ValueError, match="coincide"):
        sig.point_cloud_laplacian(np.zeros((10, 3)), k=4)


_finite = st.floats(allow_nan=True, allow_infinity=True, width=64)
_ints = st.integers(min_value=-10**6, max_value=10**6)


@st.composite
def malformed(draw):
    n = draw(st.integers(0, 12))
    cols = draw(st.sampled_from([3, 3, 3, 2, 4]))
    V = np.array(draw(st.lists(st.lists(_finite, min_size=cols, max_size=cols), min_size=n, max_size=n)),
                 dtype=float).reshape(n, cols)
    m = draw(st.integers(0, 6))
    fc = draw(st.sampled_from([3, 3, 4, 2]))
    F = np.array(draw(st.lists(st.lists(_ints, min_size=fc, max_size=fc), min_size=m, max_size=m)),
                 dtype=np.int64).reshape(m, fc)
    if draw(st.booleans()):
        F = F % max(n, 1) if n else F
    return V, F


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(malformed(), st.sampled_from(["laplacian", "laplacian_tet", "anisotropic", "points_belkin",
                                      "points_liu", "graph"]))
def test_hypothesis_inputs_raise_cleanly_or_give_valid_laplacians(data, name):
    V, F = data
    try:
        lap = constructors()[name](V, F)
    except (ValueError, TypeError):
        return
    except np.linalg.LinAlgError:
        pytest.fail("LinAlgError escaped")
    if isinstance(lap, sig.Laplacian):
        assert np.all(np.isfinite(lap.L.data)) and np.all(lap.B.diagonal() > 0)


SCRIPT = textwrap.dedent("""
    import sys, warnings, numpy as np
    import spectral_igl as sig
    warnings.simplefilter("ignore")
    rng = np.random.default_rng(int(sys.argv[1]))
    V = rng.standard_normal((30, 3))
    F = rng.integers(0, 30, (40, 3))
    case = sys.argv[2]
    if case == "face_out_of_range":
        F[7, 1] = 10**9; sig.laplacian(V, F)
    elif case == "negative_tet":
        sig.laplacian(V, np.c_[F, -F[:, 0] - 1])
    elif case == "nan_anisotropic":
        V[3, 2] = np.nan; sig.anisotropic_laplacian(V, F, 1.0)
    elif case == "points_inf":
        V[0] = np.inf; sig.point_cloud_laplacian(V, k=5)
    elif case == "points_empty":
        sig.point_cloud_laplacian(np.zeros((0, 3)), k=5, method="liu")
    elif case == "tetwild_bad_index":
        F[0, 0] = 30; sig.tetrahedralize(V, F)
    elif case == "graph_bad":
        sig.graph_laplacian(30, F[:, :2] - 31)
    elif case == "voxel_object":
        sig.voxel_laplacian(np.array([[1, None]], dtype=object))
    elif case == "int32_overflow_faces":
        sig.laplacian(V, (F.astype(np.int64) + 2**32))
""")
CASES = ["face_out_of_range", "negative_tet", "nan_anisotropic", "points_inf", "points_empty",
         "tetwild_bad_index", "graph_bad", "voxel_object", "int32_overflow_faces"]


DEGENERATE_FLIPS = textwrap.dedent("""
    import numpy as np
    import spectral_igl as sig
    from scipy.spatial import ConvexHull
    # closed surfaces on which libigl's intrinsic Delaunay flips never stop: two triangles on
    # the same three vertices, a tetrahedron of needles, convex hulls squashed onto a line
    cases = [(np.array([[0.0, 0, 0], [10, 0, 0], [5, 0.1, 0]]), np.array([[0, 1, 2], [0, 2, 1]])),
             (np.array([[0.0, 0, 0], [10, 0, 0], [5, 1e-9, 0], [5, 0, 1e-9]]),
              np.array([[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]]))]
    for k, seed in ((8, 2), (50, 1), (200, 3)):
        P = np.random.default_rng(seed).standard_normal((k, 3))
        F = ConvexHull(P).simplices
        P[:, 1:] *= 1e-9
        cases.append((P, F))
    for V, F in cases:
        lap = sig.laplacian(V, F, weights="intrinsic_delaunay")
        L = lap.L.toarray()
        assert np.all(np.isfinite(L)) and np.allclose(L, L.T, rtol=0, atol=1e-12 * abs(L).max())
        assert abs(L.sum(axis=1)).max() <= 1e-12 * abs(L).max()
        off = L - np.diag(np.diag(L))
        assert off.max() <= 1e-9 * abs(L).max()          # Delaunay: no negative weight
        assert np.linalg.eigvalsh(L).min() >= -1e-9 * abs(L).max()
    print("ok")
""")


def test_intrinsic_delaunay_weights_stop_on_needles_and_two_triangle_spheres(tmp_path):
    script = tmp_path / "flips.py"
    script.write_text(DEGENERATE_FLIPS)
    root = Path(__file__).resolve().parents[1]
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120,
                          env={"PYTHONPATH": str(root), "OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr[-2000:]


def test_intrinsic_delaunay_weights_equal_libigls_on_a_real_mesh():
    import igl

    from spectral_igl.laplacian.intrinsic import intrinsic_cotan_stiffness

    V, F = icosphere(3)
    V = V * np.random.default_rng(3).uniform(0.6, 1.4, (len(V), 1))   # bumpy: many flips
    S = intrinsic_cotan_stiffness(V, F)
    R = -igl.intrinsic_delaunay_cotmatrix(V, F)[0]
    assert abs(S - R).max() <= 1e-12 * abs(R).max()
    assert abs(S - sig.laplacian(V, F).L).max() <= 1e-13 * abs(S).max()     # the default weights


@pytest.mark.parametrize("case", CASES)
def test_subprocess_ends_in_a_python_exception(case, tmp_path):
    script = tmp_path / "bad.py"
    script.write_text(SCRIPT)
    root = Path(__file__).resolve().parents[1]
    proc = subprocess.run([sys.executable, str(script), "0", case], capture_output=True, text=True,
                          timeout=120, env={"PYTHONPATH": str(root), "OPENBLAS_NUM_THREADS": "1",
                                            "PATH": "/usr/bin:/bin"})
    assert proc.returncode == 1, (proc.returncode, proc.stderr[-2000:])  # a signal gives < 0
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith(("ValueError", "TypeError")), last


@pytest.mark.parametrize("source", [5.0, np.float64(5.0), np.array(5.0), True])
def test_a_scalar_source_must_be_an_integer(source):
    """A float scalar was read as the array [5] (a column of shape (n, 1) instead of (n,));
    a vertex index is an integer, as the error says."""
    lap = sig.laplacian(*icosphere(2))
    with pytest.raises(TypeError, match="source must be an integer vertex index"):
        sig.heat_kernel(lap, 1e-2, source)
    assert sig.heat_kernel(lap, 1e-2, np.array([5.0])).shape == (lap.n, 1)   # an array of indices
