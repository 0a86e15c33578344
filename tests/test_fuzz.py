"""Hostile input at every public entry point: never a crash, a hang or a silent NaN.

Each case runs in a worker subprocess (``tests/fuzz_cases.py``), so a segfault is a failed
case and not the end of the run, and a case that does not answer within the timeout is a
hang. A case passes when the call returns a finite result or refuses the input with a
ValueError/TypeError; any other exception type, NaN/inf in the result, a dead worker or a
silent one fails it. Hypothesis chooses, per function, which parameters get a hostile value
and which one (from the pools in ``fuzz_cases.POOLS`` and from arbitrary floats and integers).

The CI run takes a couple of minutes. ``SPECTRAL_IGL_FUZZ=long`` runs many more random examples
per function with a longer timeout; ``SPECTRAL_IGL_FUZZ_LOG=file`` appends each failure to
``file`` as it happens.
"""
from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import time
from pathlib import Path

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, Phase, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _needs import TET  # noqa: E402
from fuzz_cases import FUNCTIONS, MUST_REFUSE, POOLS  # noqa: E402

LONG = os.environ.get("SPECTRAL_IGL_FUZZ", "") == "long"
EXAMPLES = 300 if LONG else 100
TIMEOUT = 120.0 if LONG else 45.0
RUNNER = Path(__file__).resolve().parent / "fuzz_cases.py"
#: failures are also appended to this file as they happen (long runs)
LOG = os.environ.get("SPECTRAL_IGL_FUZZ_LOG")


class Worker:
    """A subprocess running :func:`fuzz_cases.serve`, restarted after a crash or a hang."""

    def __init__(self):
        self.proc = None

    def start(self):
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
        self.proc = subprocess.Popen([sys.executable, str(RUNNER)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                                     env=env, cwd=str(RUNNER.parents[1]))
        hello = self._read(120.0)
        assert hello is not None and json.loads(hello).get("ready"), "the fuzz worker did not start"

    def _read(self, timeout):
        end = time.monotonic() + timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                return None
            ready, _, _ = select.select([self.proc.stdout], [], [], left)
            if ready:
                return self.proc.stdout.readline()

    def stop(self):
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        self.proc = None

    def run(self, case, timeout=TIMEOUT) -> dict:
        if self.proc is None or self.proc.poll() is not None:
            self.start()
        self.proc.stdin.write(json.dumps(case) + "\n")
        self.proc.stdin.flush()
        line = self._read(timeout)
        if line is None:
            self.stop()
            return {"outcome": "hang", "detail": f"no answer within {timeout:g} s"}
        if not line:
            code = self.proc.wait()
            self.proc = None
            return {"outcome": "crash", "detail": f"worker died with exit code {code}"}
        return json.loads(line)


@pytest.fixture(scope="module")
def worker():
    w = Worker()
    yield w
    w.stop()


def _valid(name):
    return {p: spec for p, _, spec in FUNCTIONS[name] if spec is not None}


def _hostile(kind):
    pool = st.sampled_from(POOLS[kind])
    if kind in ("int", "index"):
        return st.one_of(pool, st.integers(min_value=-2 ** 70, max_value=2 ** 70))
    if kind in ("pos", "tol"):
        return st.one_of(pool, st.floats(allow_nan=True, allow_infinity=True))
    return pool


@st.composite
def _cases(draw, name):
    params = FUNCTIONS[name]
    kwargs = _valid(name)
    picked = draw(st.lists(st.integers(0, len(params) - 1), min_size=1, max_size=2, unique=True))
    refuse = False
    for i in picked:
        p, kind, _ = params[i]
        kwargs[p] = draw(_hostile(kind))
        refuse = refuse or kind in MUST_REFUSE
    return {"name": name, "kwargs": kwargs, "refuse": refuse}


def _fail(case, res):
    return f"{res['outcome']}: {case['name']}({json.dumps(case['kwargs'])[:300]}) -> {res['detail']}"


#: every template; tetrahedralize only where its extra (pytetwild) is installed
NAMES = [pytest.param(n, marks=TET) if n == "tetrahedralize" else n for n in sorted(FUNCTIONS)]


@pytest.mark.parametrize("name", NAMES)
def test_valid_call_is_finite(worker, name):
    """The valid arguments of each template work: a finite result, no refusal."""
    case = {"name": name, "kwargs": _valid(name)}
    res = worker.run(case)
    assert res["outcome"] == "ok", _fail(case, res)


@pytest.mark.parametrize("name", NAMES)
def test_hostile_input(worker, name):
    """Hostile values in one or two parameters: a finite result or a ValueError/TypeError."""
    # no shrinking: the cases are small already, and shrinking a hang would repeat it
    @settings(max_examples=EXAMPLES, deadline=None, database=None, derandomize=not LONG,
              suppress_health_check=list(HealthCheck), phases=[Phase.explicit, Phase.generate])
    @given(case=_cases(name))
    def check(case):
        res = worker.run(case)
        if res["outcome"] not in ("ok", "refused") and LOG:
            with open(LOG, "a") as fh:
                fh.write(_fail(case, res) + "\n")
        assert res["outcome"] in ("ok", "refused"), _fail(case, res)
        # a value that is never valid (a flag other than True/False) must not be taken
        assert not case["refuse"] or res["outcome"] == "refused", _fail(case, dict(res, outcome="accepted"))

    check()


@pytest.mark.parametrize("kind, expect", [("trunc_obj", "line 5"), ("huge_off", "line 2"),
                                          ("bad_off", "line 6"), ("dir", "directory")])
def test_cli_bad_files_exit_3(worker, kind, expect, tmp_path):
    """A bad mesh file exits 3 and the message names the file and the line."""
    case = {"name": "io.read_mesh", "kwargs": {"path": {"path": kind}}}
    res = worker.run(case)
    assert res["outcome"] == "refused" or kind == "dir", _fail(case, res)
    from spectral_igl.cli import EXIT_INPUT, main
    sys.path.insert(0, str(RUNNER.parent))
    from fuzz_cases import _Build
    path = _Build.__new__(_Build)
    path.tmp = str(tmp_path)
    p = _Build._file(path, kind)
    err = subprocess.run([sys.executable, "-m", "spectral_igl.cli", "distance", p, "--quiet"],
                         capture_output=True, text=True, timeout=120)
    assert err.returncode == EXIT_INPUT, err.stderr
    assert expect in err.stderr and Path(p).name in err.stderr, err.stderr
    assert main  # the in-process entry point is the same function


def test_cli_output_checked_before_computing(tmp_path):
    """A missing output directory is refused (exit 2) before any work, and not created."""
    missing = tmp_path / "no" / "such"
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "spectral_igl.cli", "distance", "--shape", "sphere",
                        "--level", "5", "--out", str(missing / "d.npy")], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and "does not exist" in r.stderr, r.stderr
    assert not (tmp_path / "no").exists()
    # refused before the 10242-vertex computation: well under the time of the computation
    assert time.perf_counter() - t0 < 30
