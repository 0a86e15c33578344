"""The task pages of the documentation run: every ```python block, in order, one namespace per page.

Each page is a walk-through a user copies from, so each block must run as it stands, from an
empty folder, and its asserts (checks against exact answers) must hold.
"""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest
from _needs import VIZ

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGES = {"heat_kernels.md": [VIZ], "descriptors.md": [], "bounds.md": [], "own_mesh.md": []}


def python_blocks(page: Path) -> list[str]:
    """The ```python blocks of a markdown page, in order."""
    return re.findall(r"^```python\n(.*?)^```", page.read_text(encoding="utf-8"), flags=re.M | re.S)


@pytest.mark.usefixtures("one_blas_thread")
@pytest.mark.parametrize("name", [pytest.param(n, marks=m) for n, m in PAGES.items()])
def test_every_code_block_of_the_page_runs(name, tmp_path, monkeypatch):
    blocks = python_blocks(DOCS / name)
    assert blocks, f"{name} has no python block"
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": f"docs_{Path(name).stem}"}
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)      # a page must not teach a deprecated call
        for i, code in enumerate(blocks):
            try:
                exec(compile(code, f"{name}, block {i + 1}", "exec"), namespace)
            except Exception as exc:
                raise AssertionError(f"{name}, block {i + 1} failed:\n{code}") from exc


def test_the_index_lists_every_task_page():
    index = (DOCS / "index.rst").read_text(encoding="utf-8")
    for entry in ("heat_kernels", "descriptors", "correspondence", "bounds", "notebooks/first_steps",
                  "examples/index"):
        assert re.search(rf"^   {re.escape(entry)}\*?$", index, flags=re.M), entry
