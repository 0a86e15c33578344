"""Every docstring example of the package runs and prints what it shows."""
from __future__ import annotations

import ast
import doctest
import importlib
import importlib.util
import pkgutil

import pytest

import spectral_igl


def _modules():
    names = [spectral_igl.__name__]
    for info in pkgutil.walk_packages(spectral_igl.__path__, prefix="spectral_igl."):
        if info.name.rsplit(".", 1)[-1].startswith("_") and info.name.endswith(("_ldlt", "_assembly")):
            continue
        names.append(info.name)
    return names


def _examples():
    finder = doctest.DocTestFinder(exclude_empty=True)
    out = []
    for name in _modules():
        module = importlib.import_module(name)
        for test in finder.find(module, name):
            if test.examples and test.name.startswith(name):
                out.append(test)
    return out


EXAMPLES = _examples()

#: modules whose examples call an extra without importing it
EXTRA_OF_MODULE = {"spectral_igl.laplacian.tetrahedralize": ("pytetwild",),
                   "spectral_igl.viz": ("pyvista", "matplotlib"),
                   "spectral_igl.collection": ("zarr", "distributed"),
                   "spectral_igl.retrieval": ("zarr", "distributed")}


def _missing_extras(test) -> list[str]:
    """Optional packages an example needs (imports, or its module's extra) that are not installed."""
    needed = {m for prefix, mods in EXTRA_OF_MODULE.items() if test.name.startswith(prefix) for m in mods}
    for ex in test.examples:
        try:
            tree = ast.parse(ex.source)
        except SyntaxError:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                needed.update(a.name.split(".")[0] for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                needed.add(node.module.split(".")[0])
    return sorted(m for m in needed if importlib.util.find_spec(m) is None)


def test_there_are_examples():
    # the public functions carry runnable examples; a collapse of this count means the
    # finder (or the docstrings) broke
    assert sum(len(t.examples) for t in EXAMPLES) >= 70


@pytest.mark.parametrize("test", EXAMPLES, ids=[t.name for t in EXAMPLES])
def test_docstring_example(test, tmp_path, monkeypatch):
    missing = _missing_extras(test)
    if missing:
        pytest.skip(f"needs {', '.join(missing)} (an extra of spectral-igl)")
    monkeypatch.chdir(tmp_path)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    result = runner.run(test, out=lambda s: print(s, end=""))
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {test.name}"
