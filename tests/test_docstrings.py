"""Every docstring example of the package runs and prints what it shows."""
from __future__ import annotations

import ast
import doctest
import importlib
import importlib.util
import inspect
import pkgutil
import re
import sys
import warnings
from pathlib import Path

import pytest

import spectral_igl

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "_ext"))
from readme_tools import import_object  # noqa: E402  (the docs' own importer of dotted names)


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
    # every public name carries a runnable example (786 statements in 146 docstrings when
    # this was last raised); a collapse of this count means the finder (or the docstrings) broke
    assert sum(len(t.examples) for t in EXAMPLES) >= 750


@pytest.mark.parametrize("test", EXAMPLES, ids=[t.name for t in EXAMPLES])
def test_docstring_example(test, tmp_path, monkeypatch):
    missing = _missing_extras(test)
    if missing:
        pytest.skip(f"needs {', '.join(missing)} (an extra of spectral-igl)")
    monkeypatch.chdir(tmp_path)
    # verbose=False: doctest reads "-v" from sys.argv otherwise (pytest -v), and reports differently
    runner = doctest.DocTestRunner(verbose=False, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    result = runner.run(test, out=lambda s: print(s, end=""))
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {test.name}"


API_RST = Path(__file__).resolve().parents[1] / "docs" / "api.rst"



def _api_rst_names() -> list[str]:
    """Dotted names (relative to ``spectral_igl``) in the autosummary tables of docs/api.rst."""
    text = API_RST.read_text(encoding="utf-8")
    names = []
    for block in re.findall(r"\.\. autosummary::\n((?:   .*\n|\n)+)", text):
        names += [s.strip().lstrip("~").removeprefix("spectral_igl.") for s in block.splitlines()
                  if s.strip() and not s.strip().startswith(":")]
    return names


def _resolve(dotted: str):
    """The object ``spectral_igl.<dotted>``, as autosummary resolves it."""
    return import_object("spectral_igl." + dotted)


def _public():
    """``{name: object}`` for ``spectral_igl.__all__`` and every docs/api.rst entry that is a
    function or a class (modules and constants have no sections to check)."""
    out = {name: getattr(spectral_igl, name) for name in spectral_igl.__all__}
    for name in _api_rst_names():
        try:
            out.setdefault(name, _resolve(name))
        except ImportError:       # a module of an extra that is not installed
            continue
    return {k: v for k, v in out.items() if inspect.isclass(v) or inspect.isroutine(v)}


PUBLIC = _public()


def _has_section(doc: str, *titles: str) -> bool:
    return any(re.search(rf"^{t}\n-{{3,}}\s*$", doc, re.M) for t in titles)


def _parameters(obj) -> list[str]:
    if inspect.isclass(obj) and not any("__init__" in vars(c) for c in obj.__mro__
                                        if c.__module__ != "builtins"):
        return []     # an exception or a plain class: built-in arguments only
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return []
    return [p for p in sig.parameters if p not in ("self", "cls")]


def _missing_sections(obj) -> list[str]:
    doc = inspect.getdoc(obj) or ""
    missing = []
    if _parameters(obj) and not _has_section(doc, "Parameters", "Attributes"):
        missing.append("Parameters")
    if not inspect.isclass(obj) and not _has_section(doc, "Returns", "Yields"):
        missing.append("Returns")
    if not _has_section(doc, "Examples"):
        missing.append("Examples")
    return missing


#: modules whose public names compute mathematics, which their docstrings state
MATH_MODULES = ("spectral_igl.kernels", "spectral_igl.distances", "spectral_igl.descriptors",
                "spectral_igl.embedding", "spectral_igl.diagonal", "spectral_igl.approx",
                "spectral_igl.applications", "spectral_igl.linalg.eigen", "spectral_igl.laplacian.bounds")


def test_public_names_are_found():
    # __all__ (77 names) plus the api.rst tables: a collapse means the parser broke
    assert len(PUBLIC) > 130 and "hks" in PUBLIC and "filters.heat" in PUBLIC


@pytest.mark.parametrize("name", sorted(k for k, v in PUBLIC.items()
                                         if v.__module__.startswith(MATH_MODULES)))
def test_public_docstring_states_the_maths(name):
    doc = inspect.getdoc(PUBLIC[name]) or ""
    assert ":math:" in doc or ".. math::" in doc, f"spectral_igl.{name}: no formula in the docstring"


@pytest.mark.parametrize("name", sorted(PUBLIC))
def test_public_docstring_has_sections(name):
    missing = _missing_sections(PUBLIC[name])
    assert not missing, f"spectral_igl.{name}: the docstring has no {', '.join(missing)} section"


def _documented_objects():
    """``{qualified name: object}`` for every module, class, function and method of the package."""
    out = {}
    for modname in _modules():
        module = importlib.import_module(modname)
        out[modname] = module
        for name, obj in vars(module).items():
            if getattr(obj, "__module__", None) != modname:
                continue
            if inspect.isclass(obj):
                out[f"{modname}.{name}"] = obj
                for attr, member in vars(obj).items():
                    member = getattr(member, "fget", getattr(member, "__func__", member))
                    if inspect.isroutine(member) and member.__doc__:
                        out[f"{modname}.{name}.{attr}"] = member
            elif inspect.isroutine(obj):
                out[f"{modname}.{name}"] = obj
    return out


DOCUMENTED = _documented_objects()


def test_no_docstring_has_control_characters():
    # a backslash in a docstring that is not raw (\v of \varphi, \f of \frac) becomes a
    # control character and the maths renders as garbage
    bad = {name: sorted({repr(c) for c in obj.__doc__ if ord(c) < 32 and c not in "\n\t"})
           for name, obj in DOCUMENTED.items() if obj.__doc__}
    bad = {k: v for k, v in bad.items() if v}
    assert not bad, f"control characters (make these docstrings raw): {bad}"


def test_section_headers_follow_a_blank_line():
    # a header glued to the paragraph above it is read as that paragraph's text
    header = re.compile(r"[^\n]\n(Parameters|Returns|Yields|Raises|Attributes|Notes|Examples|See Also)\n-{3,}")
    bad = sorted(name for name, obj in DOCUMENTED.items() if header.search(inspect.getdoc(obj) or ""))
    assert not bad, f"section headers without a blank line before them: {bad}"


#: what numpydoc may take as the name of a parameter, return value or attribute
ENTRY_NAME = re.compile(r"^\*{0,2}\w+(, \*{0,2}\w+)*$|^$")


def test_docstring_entries_are_names():
    # a paragraph indented as an entry (after a parameter's description, or a note placed in
    # Returns) renders as a bold fake parameter with its markup shown raw
    docscrape = pytest.importorskip("numpydoc.docscrape")
    bad = {}
    for name, obj in DOCUMENTED.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)     # sections numpydoc does not know
            doc = docscrape.NumpyDocString(inspect.getdoc(obj) or "")
        entries = [p.name for section in ("Parameters", "Returns", "Yields", "Attributes", "Other Parameters")
                   for p in doc[section] if not ENTRY_NAME.match(p.name)]
        if entries:
            bad[name] = entries
    assert not bad, f"entries that are not names: {bad}"
