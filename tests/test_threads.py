"""The package's dense sections run with a limited BLAS thread count and restore the caller's."""
import numpy as np
import pytest

threadpoolctl = pytest.importorskip("threadpoolctl")

from spectral_igl.linalg import threads  # noqa: E402
from spectral_igl.linalg.ldlt import LDLT, available  # noqa: E402


def _blas_threads():
    return {d["filepath"]: d["num_threads"] for d in threadpoolctl.threadpool_info() if d["user_api"] == "blas"}


def test_limit_inside_and_restored_outside():
    seen = {}

    @threads.serial_blas
    def probe():
        seen.update(_blas_threads())
        return 7

    with threadpoolctl.threadpool_limits(2, user_api="blas"):      # the caller's setting
        before = _blas_threads()
        if not before:
            pytest.skip("no BLAS that threadpoolctl can see")
        assert set(before.values()) == {2}
        assert probe() == 7
        assert set(seen.values()) == {threads.MAX_BLAS_THREADS} == {1}
        assert _blas_threads() == before


@pytest.mark.skipif(not available(), reason="LDLT extension not built")
def test_ldlt_runs_serial(monkeypatch):
    """The factorization's dense fronts call the BLAS: they run inside the limit."""
    import scipy.sparse as sp
    calls = []
    orig = threads.blas_threads

    def spy(limit=None):
        calls.append(limit)
        return orig(limit)

    monkeypatch.setattr(threads, "blas_threads", spy)
    A = sp.diags([-1.0, 4.0, -1.0], [-1, 0, 1], shape=(50, 50)).tocsr()
    fac = LDLT(A)
    x = fac.solve(np.ones(50))
    assert np.allclose(A @ x, 1.0)
    assert len(calls) >= 2
