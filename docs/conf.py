"""Sphinx configuration of the spectral_igl documentation.

Build: ``python -m sphinx -W -b html docs docs/_build/html`` (``tests/test_docs.py`` does
this with warnings as errors).
"""
from __future__ import annotations

import shutil
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS / "_ext"))
if str(ROOT) not in sys.path:       # data_generators, used by the docstring examples
    sys.path.insert(0, str(ROOT))

import spectral_igl  # noqa: E402

# the API stubs are generated afresh at every build (a stale stub of a removed name would
# be an orphan page)
shutil.rmtree(DOCS / "generated", ignore_errors=True)

project = "spectral_igl"
author = "the spectral_igl authors"
copyright = "the spectral_igl authors, MPL-2.0"
release = spectral_igl.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "readme_tools",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "_static", "api/generated/*.md", "gallery/*.md"]   # gallery/captions.md: data
templates_path = ["_templates"]
root_doc = "index"

# --- API reference ---------------------------------------------------------------------
autosummary_generate = True
autosummary_generate_overwrite = True
autosummary_imported_members = True
autodoc_typehints = "none"          # the numpydoc sections carry the types and shapes
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_attributes_as_param_list = False
add_module_names = False
nitpicky = True                     # every cross-reference must resolve (see _ext/readme_tools.py)

# --- MyST (the README sections) -------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]   # README sections start at ### under a page title

# --- HTML --------------------------------------------------------------------------------
html_theme = "alabaster"
html_title = f"spectral_igl {release}"
html_static_path = ["_static"]
html_theme_options = {
    "description": "Laplacian spectral kernels and distances on 3D shapes, spectrum-free and certified",
    "page_width": "1100px",
    "sidebar_width": "240px",
}
# MathJax is served with the pages (docs/_static/mathjax), so they read offline: no CDN
mathjax_path = "mathjax/tex-chtml-full.js"
mathjax3_config = {"tex": {"macros": {"R": r"\mathbb{R}"}}}
