"""Sphinx helpers of the spectral_igl documentation.

:func:`readme_captions` reads the captions of the stored gallery pictures from the table of
``docs/gallery/captions.md`` (the gallery itself: ``example_gallery.py``).
Short Python references in docstrings (``:func:`graph_extrema```) are resolved to the one
documented object of that name; see :func:`resolve_short_names`.
"""
from __future__ import annotations

import re
from pathlib import Path


def readme_captions(readme: Path) -> dict[str, str]:
    """``{png file name: caption}`` from the ``![](docs/gallery/X.png) caption`` cells of ``readme``."""
    if not readme.is_file():
        return {}
    text = readme.read_text(encoding="utf-8")
    out = {}
    for m in re.finditer(r"!\[[^\]]*\]\(docs/gallery/([^)]+\.png)\)\s*([^|\n]*)", text):
        out[m.group(1)] = m.group(2).strip()
    return out


# ---- cross-references ----------------------------------------------------------------------
def import_object(name: str):
    """The Python object called ``name`` (dotted), or raise ImportError/AttributeError."""
    import importlib

    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            obj = getattr(obj, attr)
        return obj
    raise ImportError(name)


def resolve_short_names(app, env, node, contnode):
    """Resolve a Python reference that Sphinx could not.

    1. A name whose last components match exactly one documented object links to it
       (``graph_extrema`` -> ``spectral_igl.applications.graph_extrema``).
    2. A name of an existing object links to where that object is documented under
       another name (``spectral_igl.laplacian`` -> ``spectral_igl.laplacian.laplacian``);
       if it is not documented (a module constant, a private helper) it is shown as code,
       without a link.
    Anything else stays unresolved, and the nitpicky build reports it: a stale or misspelt
    name in a docstring fails the documentation build.
    """
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"].lstrip("~.")
    domain = env.get_domain("py")
    matches = [(name, obj) for name, obj in domain.objects.items()
               if (name == target or name.endswith("." + target)) and not obj.aliased]
    if len(matches) == 1:
        from sphinx.util.nodes import make_refnode

        name, obj = matches[0]
        return make_refnode(app.builder, node["refdoc"], obj.docname, obj.node_id, contnode, name)
    context = [node.get("py:module"), node.get("py:class"), "spectral_igl", None]
    m = re.search(r"docstring of ([\w.]+)", node.source or "")
    if m:    # the modules around the docstring's own object, innermost first
        parts = m.group(1).split(".")
        context += [".".join(parts[:i]) for i in range(len(parts) - 1, 0, -1)]
    for prefix in context:
        full = f"{prefix}.{target}" if prefix else target
        try:
            obj = import_object(full)
        except (ImportError, AttributeError):
            continue
        for name, entry in domain.objects.items():    # documented under another name?
            try:
                same = not entry.aliased and import_object(name) is obj
            except (ImportError, AttributeError):
                same = False
            if same:
                from sphinx.util.nodes import make_refnode

                return make_refnode(app.builder, node["refdoc"], entry.docname, entry.node_id,
                                    contnode, name)
        return contnode
    return None


def setup(app):
    app.connect("missing-reference", resolve_short_names)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
