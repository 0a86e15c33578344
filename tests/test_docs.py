"""The documentation site builds with warnings as errors and covers the public API."""
from __future__ import annotations

import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

for _mod in ("sphinx", "numpydoc", "myst_parser"):
    pytest.importorskip(_mod)

sys.path.insert(0, str(DOCS / "_ext"))
from readme_tools import import_object  # noqa: E402  (the docs' own importer of dotted names)


def _api_entries():
    """Names listed in the autosummary tables of docs/api.rst, as importable dotted names."""
    text = (DOCS / "api.rst").read_text(encoding="utf-8")
    names = []
    for block in re.findall(r"\.\. autosummary::\n((?:   .*\n|\n)+)", text):
        for line in block.splitlines():
            line = line.strip()
            if line and not line.startswith(":"):
                names.append("spectral_igl." + line.lstrip("~").removeprefix("spectral_igl."))
    return names


def test_every_public_name_is_in_the_api_reference():
    import spectral_igl

    documented = {id(import_object(n)) for n in _api_entries()}
    public = {}
    for modname in ("spectral_igl", "spectral_igl.filters", "spectral_igl.io", "spectral_igl.progress",
                    "spectral_igl.applications", "spectral_igl.laplacian"):
        mod = importlib.import_module(modname)
        for name in mod.__all__:
            obj = getattr(mod, name)
            if callable(obj) and not isinstance(obj, type(spectral_igl)):
                public[f"{modname}.{name}"] = obj
    missing = sorted(k for k, v in public.items() if id(v) not in documented)
    assert not missing, f"not in docs/api.rst: {missing}"


def test_sphinx_build_without_warnings(tmp_path):
    out = tmp_path / "html"
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                           str(DOCS), str(out)], capture_output=True, text=True, timeout=600,
                          cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-5000:]
    assert "WARNING" not in proc.stderr, proc.stderr[-5000:]
    # API pages rendered from the docstrings, with their math
    page = (out / "generated" / "spectral_igl.kernel_diagonal.html").read_text(encoding="utf-8")
    assert "G_{ii} = \\sum_l" in page and "Parameters" in page and "mathjax" in page.lower()
    # MathJax is served with the pages (they read offline), not loaded from a CDN
    assert '_static/mathjax/tex-chtml-full.js' in page and "cdn." not in page, page[:3000]
    assert (out / "_static" / "mathjax" / "output" / "chtml" / "fonts" / "woff-v2").is_dir()
    # the gallery: a page per public example script with its code and its stored pictures,
    # and every stored picture on some page
    from example_gallery import pictures, public_scripts

    index = (out / "examples" / "index.html").read_text(encoding="utf-8")
    shown = set()
    for script in public_scripts():
        html = (out / "examples" / f"{script.stem}.html").read_text(encoding="utf-8")
        assert f"{script.stem}.html" in index and "main" in html and "highlight" in html, script.name
        assert f"examples/{script.name}" in html, script.name
        for png in pictures(script):
            assert png.name in html, (script.name, png.name)
            shown.add(png.name)
    assert shown == {p.name for p in (DOCS / "gallery").glob("*.png")}
    # the task pages and the notebook, with its stored pictures
    for page in ("heat_kernels", "descriptors", "bounds"):
        assert 'class="highlight-python' in (out / f"{page}.html").read_text(encoding="utf-8"), page
    notebook = (out / "notebooks" / "first_steps.html").read_text(encoding="utf-8")
    assert notebook.count("<img") >= 2 and "heat_kernel" in notebook
    results = (out / "results.html").read_text(encoding="utf-8")
    assert results.count("<table") >= 5 and "One-to-all distances" in results
    assert "write_mesh" in (out / "getting_started.html").read_text(encoding="utf-8")


def test_a_new_example_script_enters_the_gallery_as_clean_restructuredtext(tmp_path):
    """Any public examples/*.py is picked up; its plain-text docstring becomes warning-free rst."""
    import io

    import docutils.core

    from example_gallery import gallery_source, public_scripts

    script = tmp_path / "matching.py"
    script.write_text('"""Point matching: phi^2 = s^-2 *and* `x`, a_b_ and |x|.\n\n'
                      "Descriptors on both shapes, then nearest neighbours\nin descriptor space.\n\n"
                      "    python examples/matching.py --quick\n\n- a list?\n"
                      '"""\nimport numpy as np\n\n\ndef main(argv=None):\n    return {}\n', encoding="utf-8")
    (tmp_path / "_private.py").write_text('"""Not an example."""\n', encoding="utf-8")
    assert [p.name for p in public_scripts(tmp_path)] == ["matching.py"]
    source = gallery_source(script)
    code = compile(source, "matching.py", "exec")                   # still the same program
    doc = source.split('"""')[1]
    title = doc.strip().splitlines()[0]
    assert title.startswith("Point matching") and doc.strip().splitlines()[1] == "=" * len(title)
    assert "import numpy as np" in source and code.co_filename == "matching.py"
    stream = io.StringIO()
    docutils.core.publish_doctree(doc, settings_overrides={"report_level": 2, "halt_level": 5,
                                                           "warning_stream": stream})
    assert not stream.getvalue(), stream.getvalue()             # no warning, no error
