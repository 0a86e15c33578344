"""Every ``>>>`` example in the package's docstrings runs and prints what it shows."""
from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import spectral_igl

OPTIONAL = {"spectral_igl.viz": "pyvista"}   # modules whose examples need an optional package


def _modules():
    names = [spectral_igl.__name__]
    for info in pkgutil.walk_packages(spectral_igl.__path__, prefix="spectral_igl."):
        names.append(info.name)
    return sorted(n for n in names if not n.rsplit(".", 1)[-1].startswith("__"))


def _examples():
    finder = doctest.DocTestFinder(exclude_empty=True)
    cases = []
    for name in _modules():
        try:
            mod = importlib.import_module(name)
        except ImportError:
            continue
        for test in finder.find(mod, name):
            if test.examples and test.name.startswith(name) and \
                    getattr(test, "filename", None) == getattr(mod, "__file__", None):
                cases.append(pytest.param(test, id=test.name))
    return cases


CASES = _examples()


def test_there_are_examples():
    assert len(CASES) >= 15


@pytest.mark.parametrize("test", CASES)
def test_docstring_example(test):
    for prefix, package in OPTIONAL.items():
        if test.name.startswith(prefix):
            pytest.importorskip(package)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    out = []
    result = runner.run(test, out=out.append)
    assert result.failed == 0, "".join(out)
