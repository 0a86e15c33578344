"""The gallery's input for sphinx-gallery, written from ``examples/*.py`` at every build.

Every public example script (``examples/*.py`` whose name does not start with ``_``; the tool
``make_gallery.py`` excepted) becomes a gallery page: the first line of its docstring as the
title, the rest as text, the pictures of ``docs/gallery`` it writes, the command that runs it,
and its code. The scripts are not executed when the documentation is built (they need a
renderer and up to minutes): the pages show the pictures stored in ``docs/gallery``, which
``python examples/make_gallery.py`` refreshes. Sphinx-gallery reads copies of the scripts in
``docs/_examples``, whose docstrings are turned into reStructuredText here; the scripts' own
docstrings stay plain text (``--help`` prints them).
"""
from __future__ import annotations

import ast
import re
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
DOCS = ROOT / "docs"
PICTURES = DOCS / "gallery"
SOURCE = DOCS / "_examples"          # generated: what sphinx-gallery reads
TOOLS = {"make_gallery.py"}          # scripts in examples/ that are not examples

INTRO = """Gallery
=======

Every example script in ``examples/``, with its code and the pictures it draws. Each runs as
``python examples/NAME.py`` (``--quick`` for small shapes in seconds, ``--mesh PATH`` for your
own triangle mesh, ``--out DIR`` for the pictures); ``spectral-igl figures --quick --out
figures/`` runs them all. The pictures here are the ones stored in ``docs/gallery``
(``python examples/make_gallery.py`` redraws them): the documentation is built without
running the scripts.
"""


def public_scripts(folder: Path = EXAMPLES) -> list[Path]:
    """The example scripts the gallery shows, by file name."""
    return sorted(p for p in folder.glob("*.py") if not p.name.startswith("_") and p.name not in TOOLS)


def escape(text: str) -> str:
    """``text`` with the characters reStructuredText reads as markup escaped."""
    return re.sub(r"([\\*`|_])", r"\\\1", text)


def rst_paragraphs(body: str) -> list[str]:
    """Plain-text paragraphs as reStructuredText: prose joined and escaped, indented lines literal."""
    out = []
    for para in re.split(r"\n\s*\n", body.strip("\n")):
        lines = para.splitlines()
        if not lines:
            continue
        if any(line.startswith((" ", "\t")) for line in lines):      # a command or a formula
            out += ["::", "", *("    " + line for line in lines), ""]
        else:
            out += [escape(" ".join(line.strip() for line in lines)), ""]
    return out


def png_patterns(code: str) -> list[re.Pattern]:
    """The PNG names a script's code writes, as patterns: ``f"fig03_{k:02d}.png"`` -> ``fig03_.+\\.png``."""
    names = re.findall(r"""["']((?:[^"'\s{]|\{[^}]*\})+\.png)["']""", code)
    return [re.compile(".+".join(map(re.escape, re.split(r"\{[^}]*\}", name))) + "$") for name in names]


def pictures(script: Path, folder: Path = PICTURES) -> list[Path]:
    """The stored pictures of ``script``: those its code writes, or named after it."""
    patterns = png_patterns(script.read_text(encoding="utf-8"))
    return [png for png in sorted(folder.glob("*.png"))
            if png.stem.startswith(script.stem) or any(p.match(png.name) for p in patterns)]


def captions(folder: Path = PICTURES) -> dict[str, str]:
    """``{png name: caption}`` from ``docs/gallery/captions.md``."""
    from readme_tools import readme_captions

    return readme_captions(folder / "captions.md")


def gallery_source(script: Path, caption: dict[str, str] | None = None) -> str:
    """The copy of ``script`` that sphinx-gallery reads: a reStructuredText docstring, then the code."""
    text = script.read_text(encoding="utf-8")
    tree = ast.parse(text)
    doc = ast.get_docstring(tree, clean=True)
    if not doc:
        raise ValueError(f"{script}: an example starts with a docstring (its first line is the title)")
    title, _, body = doc.partition("\n")
    title = escape(title.strip())
    lines = [title, "=" * len(title), "", *rst_paragraphs(body)]
    pngs = pictures(script)
    for png in pngs:
        cap = escape((caption or {}).get(png.name) or png.stem.replace("_", " "))
        lines += [f".. figure:: /gallery/{png.name}", "   :width: 100%", f"   :alt: {cap}", "",
                  f"   {cap}", ""]
    lines += [f"Run it: ``python examples/{script.name} --quick --out figures/`` "
              f"(``--help`` lists its options).", ""]
    end = tree.body[0].end_lineno                      # the docstring's last line
    code = "\n".join(text.splitlines()[end:]).lstrip("\n")
    thumb = f'# sphinx_gallery_thumbnail_path = "gallery/{pngs[0].name}"\n' if pngs else ""
    return 'r"""\n' + "\n".join(lines).rstrip() + '\n"""\n' + thumb + code + ("\n" if not code.endswith("\n") else "")


def write_sources(source: Path = SOURCE) -> list[Path]:
    """Write ``docs/_examples``: the gallery's introduction and a copy of every example."""
    shutil.rmtree(source, ignore_errors=True)
    source.mkdir(parents=True)
    (source / "README.txt").write_text(INTRO, encoding="utf-8")
    caption = captions()
    written = []
    for script in public_scripts():
        (source / script.name).write_text(gallery_source(script, caption), encoding="utf-8")
        written.append(source / script.name)
    return written
