"""The package's layout: data flows one way through its stages.

Every module of ``spectral_igl`` imports only from its own stage or the stages before it,
never through the package root, never a private name of another module, and the
module-level imports have no cycle. A new module gets a stage in :data:`STAGES`.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "spectral_igl"

#: first dotted component below ``spectral_igl`` -> stage (lower imports nothing higher)
STAGES = {
    "_validate": 0, "_version": 0, "_extras": 0, "io": 0, "progress": 0, "accuracy": 0,
    "laplacian": 1, "data_generators": 1,
    "filters": 2,
    "linalg": 3,
    "approx": 4,
    "diagonal": 5,
    "kernels": 6,
    "distances": 7, "descriptors": 7, "embedding": 7,
    "applications": 8,
    "quantity": 9,
    "collection": 10,
    "viz": 11,
    "cli": 12,
}
#: compiled halves of a module, imported by that module alone
EXTENSIONS = {"laplacian._assembly": {"laplacian.anisotropic", "laplacian.points", "laplacian.intrinsic"},
              "linalg._ldlt": {"linalg.ldlt"}}


def _modules():
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).with_suffix("")
        parts = list(rel.parts)
        is_pkg = parts[-1] == "__init__"
        if is_pkg:
            parts = parts[:-1]
        yield ".".join(parts), path, is_pkg


def _imports(name: str, path: Path, is_pkg: bool):
    """(target module below spectral_igl, imported names, line, top-level?) for each import."""
    tree = ast.parse(path.read_text(), str(path))
    top = set(id(n) for n in tree.body)
    package = name.split(".") if is_pkg else name.split(".")[:-1]
    package = [p for p in package if p]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level == 0:
                if node.module and node.module.startswith("spectral_igl"):
                    target = node.module[len("spectral_igl"):].lstrip(".")
                else:
                    continue
            else:
                base = package[: len(package) - (node.level - 1)] if node.level > 1 else package
                target = ".".join(base + ([node.module] if node.module else []))
            yield target, [a.name for a in node.names], node.lineno, id(node) in top
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("spectral_igl"):
                    yield a.name[len("spectral_igl"):].lstrip("."), [], node.lineno, id(node) in top


def _stage(module: str) -> int:
    head = module.split(".")[0]
    if head not in STAGES:
        pytest.fail(f"module spectral_igl.{module} has no stage: add {head!r} to STAGES in {__file__}")
    return STAGES[head]


MODULES = list(_modules())


@pytest.mark.parametrize("name,path,is_pkg", MODULES, ids=[m[0] or "__init__" for m in MODULES])
def test_imports_flow_one_way(name, path, is_pkg):
    if name == "":
        return        # the package root gathers the public names of every stage
    own = _stage(name)
    for target, names, line, _ in _imports(name, path, is_pkg):
        where = f"{path.relative_to(ROOT.parent)}:{line}"
        assert target != "", f"{where} imports {names} through the package root"
        if target in EXTENSIONS or any(f"{target}.{n}" in EXTENSIONS for n in names):
            ext = target if target in EXTENSIONS else next(f"{target}.{n}" for n in names
                                                           if f"{target}.{n}" in EXTENSIONS)
            assert name in EXTENSIONS[ext], f"{where}: only {EXTENSIONS[ext]} may import {ext}"
            continue
        assert _stage(target) <= own, f"{where}: stage {own} module imports the later stage {target}"
        private = [n for n in names if n.startswith("_") and n != "__version__"]
        assert not private, f"{where} imports the private names {private} of spectral_igl.{target}"
        if target.split(".")[-1].startswith("_") and target.split(".")[0] != name.split(".")[0]:
            assert target in ("_validate", "_version", "_extras"), \
                f"{where} imports the private module spectral_igl.{target} from another room"


def test_no_import_cycle():
    graph = {}
    known = {m[0] for m in MODULES}
    for name, path, is_pkg in MODULES:
        deps = set()
        for target, names, _, top in _imports(name, path, is_pkg):
            if not top:
                continue
            for cand in [f"{target}.{n}" for n in names] + [target]:
                if cand in known and cand != name:
                    deps.add(cand)
                    break
        graph[name] = deps
    # a package's __init__ importing its own submodules is not a cycle with them
    state, stack = {}, []

    def visit(u):
        state[u] = 1
        stack.append(u)
        for v in graph.get(u, ()):
            if u and (v.startswith(u + ".") if u else True):
                continue
            if state.get(v) == 1:
                cyc = stack[stack.index(v):] + [v]
                pytest.fail("import cycle: " + " -> ".join(c or "spectral_igl" for c in cyc))
            if state.get(v) is None:
                visit(v)
        stack.pop()
        state[u] = 2

    for u in graph:
        if u and state.get(u) is None:
            visit(u)
