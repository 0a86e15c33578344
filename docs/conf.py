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
# the gallery's input: every public examples/*.py with a reStructuredText docstring
import example_gallery  # noqa: E402

example_gallery.write_sources()

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
    "myst_nb",
    "sphinx_gallery.gen_gallery",
    "readme_tools",
]

exclude_patterns = ["_build", "_static", "_examples", "examples/*.ipynb", "api/generated/*.md",
                    "gallery/*.md", "results/*"]   # gallery/captions.md, results/: data
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

# --- gallery: the example scripts, not executed (the stored pictures are shown) ----------
sphinx_gallery_conf = {
    "examples_dirs": "_examples",          # written by _ext/example_gallery.py
    "gallery_dirs": "examples",
    "plot_gallery": "False",
    "remove_config_comments": True,
    "write_computation_times": False,
    "download_all_examples": False,
    "line_numbers": False,
    "backreferences_dir": None,
    "doc_module": (),
    # a downloaded notebook runs its example in quick mode (from examples/, beside _common.py)
    "first_notebook_cell": ("# Run from the repository's examples/ folder (the scripts share _common.py).\n"
                            "import sys\n\nsys.argv = [\"example\", \"--quick\"]"),
}

# --- notebooks: rendered with their stored outputs, never executed by the build ----------
nb_execution_mode = "off"
nb_output_stderr = "remove"          # import-time notices of the kernel

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


# --- task pages --------------------------------------------------------------------------
#: pages the index lists that may not be written yet: left out of the toctree until they are
PENDING_PAGES = ("correspondence",)


def drop_pending_pages(app, docname, source):
    """Leave an unwritten page of :data:`PENDING_PAGES` out of the index's toctree."""
    if docname == "index":
        for name in PENDING_PAGES:
            if not (DOCS / f"{name}.md").is_file() and not (DOCS / f"{name}.rst").is_file():
                source[0] = source[0].replace(f"\n   {name}\n", "\n")


def setup(app):
    app.connect("source-read", drop_pending_pages)
